//! The architecture, held: each folder of `src/` is a layer that imports only
//! the layers below it, the model's data imports nothing of the engine, and
//! no file of the library imports a file that imports it back.
//!
//! Read from the source itself: every `crate::…` and `super::…` path outside
//! comments, strings and `#[cfg(test)]` modules, and every path through a
//! child module named by its bare name, is resolved to the file that
//! defines its module. A parent's `mod child;` is not an import, but its uses of the
//! child (`pub use child::…`, `child::f()`) are: so a child that imports
//! its parent's items, re-exported or not, closes a cycle (siblings import
//! each other directly).

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// The layers, lowest first, with what each may import.
const LAYERS: [(&str, &[&str]); 10] = [
    ("util", &[]),
    ("physics", &["util"]),
    ("motion", &["util"]),
    ("formats", &["motion", "physics", "util"]),
    ("leaf", &["physics", "util"]),
    ("sim", &["physics", "motion", "leaf", "util"]),
    ("breed", &["sim", "leaf", "motion", "physics", "util"]),
    (
        "direct",
        &["breed", "sim", "leaf", "motion", "physics", "util"],
    ),
    (
        "output",
        &[
            "breed", "sim", "leaf", "formats", "motion", "physics", "util",
        ],
    ),
    (
        "studio",
        &[
            "output", "breed", "sim", "leaf", "formats", "motion", "physics", "util",
        ],
    ),
];

/// Every `.rs` file under `src/` but the binary's, by module path
/// (`physics::forces::springs`; a folder's `mod.rs` is the folder's module).
fn library_files() -> BTreeMap<String, PathBuf> {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut out = BTreeMap::new();
    let mut stack = vec![src.clone()];
    while let Some(dir) = stack.pop() {
        for entry in std::fs::read_dir(&dir).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                stack.push(path);
                continue;
            }
            if path.extension().and_then(|e| e.to_str()) != Some("rs") {
                continue;
            }
            let rel = path.strip_prefix(&src).unwrap().with_extension("");
            let mut parts: Vec<String> = rel
                .components()
                .map(|c| c.as_os_str().to_string_lossy().into_owned())
                .collect();
            if parts[0] == "cli" || parts == ["main"] {
                continue;
            }
            if parts.last().is_some_and(|p| p == "mod" || p == "lib") {
                parts.pop();
            }
            out.insert(parts.join("::"), path);
        }
    }
    out
}

/// The code of a file without comments, string and char literals, and
/// without its `#[cfg(test)]` modules (tests may use anything).
fn code_of(text: &str) -> String {
    let text = match text.find("#[cfg(test)]\nmod ") {
        Some(k) => &text[..k],
        None => text,
    };
    let b = text.as_bytes();
    let mut out = String::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        if b[i..].starts_with(b"//") {
            while i < b.len() && b[i] != b'\n' {
                i += 1;
            }
        } else if b[i..].starts_with(b"/*") {
            let end = text[i + 2..].find("*/").map_or(b.len(), |k| i + 4 + k);
            i = end;
        } else if b[i] == b'r' && (b[i + 1..].starts_with(b"\"") || b[i + 1..].starts_with(b"#")) {
            // Raw string r"…" or r#"…"#.
            let hashes = b[i + 1..].iter().take_while(|&&c| c == b'#').count();
            let open = i + 1 + hashes;
            if b.get(open) == Some(&b'"') {
                let close = format!("\"{}", "#".repeat(hashes));
                let end = text[open + 1..]
                    .find(&close)
                    .map_or(b.len(), |k| open + 1 + k + close.len());
                out.push_str("\"\"");
                i = end;
            } else {
                out.push('r');
                i += 1;
            }
        } else if b[i] == b'"' {
            i += 1;
            while i < b.len() && b[i] != b'"' {
                i += if b[i] == b'\\' { 2 } else { 1 };
            }
            out.push_str("\"\"");
            i += 1;
        } else if b[i] == b'\'' {
            // A char literal ('x', '\n', '\u{..}'), not a lifetime ('a).
            let rest = &text[i + 1..];
            let close = if rest.starts_with('\\') {
                rest.find('\'').map(|k| k + 1)
            } else {
                rest.chars()
                    .next()
                    .filter(|_| rest[rest.chars().next().unwrap().len_utf8()..].starts_with('\''))
                    .map(|c| c.len_utf8() + 1)
            };
            match close {
                Some(k) => {
                    out.push_str("' '");
                    i += 1 + k;
                }
                None => {
                    out.push('\'');
                    i += 1;
                }
            }
        } else {
            let c = text[i..].chars().next().unwrap();
            out.push(c);
            i += c.len_utf8();
        }
    }
    out
}

fn is_ident(c: char) -> bool {
    c.is_ascii_alphanumeric() || c == '_'
}

/// Paths starting at `at` (just after `crate::` or `super::`): the segments
/// before a `{` group are a prefix of every item inside it.
fn paths_from(code: &str, at: usize, prefix: &[String], out: &mut Vec<Vec<String>>) -> usize {
    let chars: Vec<char> = code[at..].chars().collect();
    let mut segs = prefix.to_vec();
    let mut i = 0;
    loop {
        while i < chars.len() && chars[i].is_whitespace() {
            i += 1;
        }
        if i < chars.len() && chars[i] == '{' {
            i += 1;
            loop {
                while i < chars.len() && (chars[i].is_whitespace() || chars[i] == ',') {
                    i += 1;
                }
                if i >= chars.len() || chars[i] == '}' {
                    let consumed: usize = chars[..(i + 1).min(chars.len())]
                        .iter()
                        .map(|c| c.len_utf8())
                        .sum();
                    return consumed;
                }
                let offset: usize = chars[..i].iter().map(|c| c.len_utf8()).sum();
                let used = paths_from(code, at + offset, &segs, out);
                let used_chars = code[at + offset..at + offset + used].chars().count();
                i += used_chars.max(1);
            }
        }
        let start = i;
        while i < chars.len() && is_ident(chars[i]) {
            i += 1;
        }
        if i == start {
            break;
        }
        segs.push(chars[start..i].iter().collect());
        if chars[i..].starts_with(&[':', ':']) {
            i += 2;
        } else {
            break;
        }
    }
    out.push(segs);
    chars[..i].iter().map(|c| c.len_utf8()).sum()
}

/// The library files each file imports.
fn imports(files: &BTreeMap<String, PathBuf>) -> BTreeMap<String, BTreeSet<String>> {
    let resolve = |segs: &[String]| -> Option<String> {
        (1..=segs.len())
            .rev()
            .map(|k| segs[..k].join("::"))
            .find(|m| files.contains_key(m))
    };
    let mut edges = BTreeMap::new();
    for (module, path) in files {
        let code = code_of(&std::fs::read_to_string(path).unwrap());
        let own: Vec<String> = if module.is_empty() {
            Vec::new()
        } else {
            module.split("::").map(String::from).collect()
        };
        let mut found = Vec::new();
        let mut k = 0;
        while let Some(pos) = code[k..].find("::") {
            let p = k + pos;
            k = p + 2;
            let word_start = code[..p]
                .char_indices()
                .rev()
                .take_while(|(_, c)| is_ident(*c))
                .last()
                .map_or(p, |(i, _)| i);
            let word = &code[word_start..p];
            let before = code[..word_start].chars().next_back();
            if before.is_some_and(|c| is_ident(c) || c == ':') {
                continue;
            }
            let base: Vec<String> = match word {
                "crate" => Vec::new(),
                "super" => {
                    // Each super:: goes up one module from this file's own
                    // (a folder's mod.rs is the folder's module).
                    let mut ups = 1;
                    let mut rest = p + 2;
                    while code[rest..].starts_with("super::") {
                        ups += 1;
                        rest += "super::".len();
                    }
                    k = rest;
                    own[..own.len().saturating_sub(ups)].to_vec()
                }
                // A child module named by its bare name (`mod springs;` then
                // `springs::springs`, or `pub use springs::…` re-exports).
                child
                    if files.contains_key(
                        &[own.as_slice(), &[child.to_string()]].concat().join("::"),
                    ) =>
                {
                    k = word_start;
                    own.clone()
                }
                _ => continue,
            };
            let mut paths = Vec::new();
            // Past the path read, so that no part of it is read again.
            k += paths_from(&code, k, &base, &mut paths).max(1);
            found.extend(paths);
        }
        let targets: BTreeSet<String> = found
            .iter()
            .filter_map(|segs| resolve(segs))
            .filter(|t| t != module)
            .collect();
        edges.insert(module.clone(), targets);
    }
    edges
}

fn layer(module: &str) -> &str {
    module.split("::").next().unwrap_or("")
}

#[test]
fn each_layer_imports_only_the_layers_below_it() {
    let files = library_files();
    assert!(files.len() > 40, "found only {} files", files.len());
    let edges = imports(&files);
    let allowed: BTreeMap<&str, &[&str]> = LAYERS.into_iter().collect();
    let mut wrong = Vec::new();
    for (from, targets) in &edges {
        let Some(may) = allowed.get(layer(from)) else {
            assert!(from.is_empty(), "{from} is in no layer");
            continue;
        };
        for to in targets {
            if layer(to) != layer(from) && !may.contains(&layer(to)) {
                wrong.push(format!("{from} imports {to}"));
            }
        }
    }
    assert!(wrong.is_empty(), "layer violations:\n{}", wrong.join("\n"));
    // The check sees imports at all: known ones are found.
    assert!(edges["breed::run"].contains("sim::drop"));
    assert!(edges["physics::aero::quadratic::forces"].contains("physics::aero::surfaces"));
    assert!(edges["physics::aero::law"].contains("physics::model::error"));
}

/// The files of the aerodynamic law that are the model's data: the law it
/// holds, the keys it is read from and each law's coefficients (the rest of
/// each law, its forces and bounds, is engine).
fn is_law_data(m: &str) -> bool {
    m == "physics::aero::law"
        || m == "physics::aero::keys"
        || (m.starts_with("physics::aero::") && m.ends_with("::coefficients"))
}

/// The model and its parts import nothing of forces, integrators or
/// anything that runs them (as MuJoCo's mjmodel.h includes nothing of the
/// engine): only each other, the wind field they hold, the aerodynamic
/// law's data, and utilities.
#[test]
fn the_model_imports_nothing_of_the_engine() {
    let edges = imports(&library_files());
    assert!(edges["physics::model"].contains("physics::aero::law"));
    for (from, targets) in edges.iter().filter(|(m, _)| {
        m.starts_with("physics::model")
            || *m == "physics::params"
            || *m == "physics::state"
            || is_law_data(m)
    }) {
        for to in targets {
            let ok = to.starts_with("physics::model")
                || to.starts_with("physics::field")
                || to.starts_with("util")
                || is_law_data(to)
                || (from == "physics::state" && to == "physics::model");
            assert!(ok, "{from} imports {to}");
        }
    }
}

#[test]
fn no_file_imports_a_file_that_imports_it_back() {
    // Every file of the library, every layer and folder (the last folders
    // with a cycle, sim/accuracy, sim/scene and output/export, lost theirs
    // in stop 48).
    let edges = imports(&library_files());
    // Depth-first search for a cycle, reporting its path.
    fn visit(
        m: &str,
        edges: &BTreeMap<String, BTreeSet<String>>,
        state: &mut BTreeMap<String, u8>,
        path: &mut Vec<String>,
    ) -> Option<Vec<String>> {
        state.insert(m.to_string(), 1);
        path.push(m.to_string());
        for to in edges.get(m).into_iter().flatten() {
            match state.get(to.as_str()) {
                Some(1) => {
                    let k = path.iter().position(|p| p == to).unwrap();
                    let mut cycle = path[k..].to_vec();
                    cycle.push(to.clone());
                    return Some(cycle);
                }
                Some(_) => {}
                None => {
                    if let Some(c) = visit(to, edges, state, path) {
                        return Some(c);
                    }
                }
            }
        }
        path.pop();
        state.insert(m.to_string(), 2);
        None
    }
    let mut state = BTreeMap::new();
    for m in edges.keys() {
        if !state.contains_key(m.as_str())
            && let Some(cycle) = visit(m, &edges, &mut state, &mut Vec::new())
        {
            panic!("import cycle: {}", cycle.join(" → "));
        }
    }
}

/// The reader of paths itself, on a made-up file.
#[test]
fn paths_are_read_through_groups_comments_and_strings() {
    let code = code_of(
        "use crate::a::{b::C, d, e::{f, g::H}};\n// crate::zz::no\nlet s = \"crate::yy::no\";\nx = crate::k::l(1);\n#[cfg(test)]\nmod tests { use crate::t::u; }\n",
    );
    let mut found = Vec::new();
    let mut k = 0;
    while let Some(p) = code[k..].find("crate::") {
        let at = k + p + "crate::".len();
        paths_from(&code, at, &[], &mut found);
        k = at;
    }
    let joined: Vec<String> = found.iter().map(|s| s.join("::")).collect();
    assert_eq!(joined, ["a::b::C", "a::d", "a::e::f", "a::e::g::H", "k::l"]);
}

/// The string literals of a file, with the line each starts on; comments
/// skipped (a doc may name the flag that sets a thing).
fn string_literals(text: &str) -> Vec<(usize, String)> {
    let b = text.as_bytes();
    let line_at = |i: usize| text[..i].matches('\n').count() + 1;
    let mut out = Vec::new();
    let mut i = 0;
    while i < b.len() {
        if b[i..].starts_with(b"//") {
            while i < b.len() && b[i] != b'\n' {
                i += 1;
            }
        } else if b[i..].starts_with(b"/*") {
            i = text[i + 2..].find("*/").map_or(b.len(), |k| i + 4 + k);
        } else if b[i] == b'r'
            && (i == 0 || !is_ident(text[..i].chars().next_back().unwrap()))
            && b.get(i + 1 + b[i + 1..].iter().take_while(|&&c| c == b'#').count()) == Some(&b'"')
        {
            // A raw string, r"…" or r#"…"#.
            let hashes = b[i + 1..].iter().take_while(|&&c| c == b'#').count();
            let open = i + 1 + hashes;
            let close = format!("\"{}", "#".repeat(hashes));
            let end = text[open + 1..]
                .find(&close)
                .map_or(b.len(), |k| open + 1 + k);
            out.push((line_at(i), text[open + 1..end].to_string()));
            i = end + close.len();
        } else if b[i] == b'"' {
            let start = i + 1;
            i += 1;
            while i < b.len() && b[i] != b'"' {
                i += if b[i] == b'\\' { 2 } else { 1 };
            }
            out.push((line_at(start), text[start..i.min(b.len())].to_string()));
            i += 1;
        } else if b[i] == b'\'' {
            // A char literal ('"' included), not a lifetime.
            let rest = &text[i + 1..];
            let skip = if rest.starts_with('\\') {
                rest.find('\'').map(|k| k + 1)
            } else {
                let c = rest.chars().next().unwrap_or(' ');
                rest[c.len_utf8()..]
                    .starts_with('\'')
                    .then_some(c.len_utf8() + 1)
            };
            i += 1 + skip.unwrap_or(0);
        } else {
            i += text[i..].chars().next().unwrap().len_utf8();
        }
    }
    out
}

/// The command-line flags a literal names: `--` and a letter, not inside
/// a longer run of dashes.
fn flags_in(literal: &str) -> Vec<String> {
    let b = literal.as_bytes();
    let mut out = Vec::new();
    for k in 0..b.len().saturating_sub(2) {
        if &b[k..k + 2] == b"--" && b[k + 2].is_ascii_lowercase() && (k == 0 || b[k - 1] != b'-') {
            let end = literal[k + 2..]
                .find(|c: char| !(c.is_ascii_alphanumeric() || c == '-'))
                .map_or(literal.len(), |e| k + 2 + e);
            out.push(literal[k..end].to_string());
        }
    }
    out
}

/// Library literals that hold `--word` and are not the command line's
/// words to a user, by file: (module path, flags, why).
const NOT_OUR_FLAGS: &[(&str, &[&str], &str)] = &[
    (
        "formats::usd::stage",
        &["--root", "--parent", "--timeout-s"],
        "the arguments of the compose-usd child process the library starts itself",
    ),
    (
        "formats::usd::stage",
        &["--flatten"],
        "Pixar's usdcat, another tool",
    ),
    (
        "formats::usd::layer",
        &["--flatten"],
        "Pixar's usdcat, another tool",
    ),
    (
        "breed::executor",
        &[
            "--generation",
            "--index",
            "--count",
            "--threads",
            "--skip-done",
        ],
        "the arguments of the shard child processes the executor starts itself",
    ),
    (
        "breed::executor",
        &[
            "--ntasks",
            "--kill-on-bad-exit",
            "--quiet",
            "--overcommit",
            "--cpus-per-task",
            "--job-name",
            "--output",
            "--open-mode",
            "--parsable",
            "--array",
            "--wrap",
        ],
        "Slurm's srun and sbatch, another tool",
    ),
];

#[test]
fn the_library_names_no_command_line_flag() {
    // The library names a setting as `Setting` (`util::setting`), which
    // `src/cli/` spells as a flag: a flag written in library code would be
    // wrong for the studio and for anything else that calls it.
    let mut found = Vec::new();
    for (module, path) in library_files() {
        let text = std::fs::read_to_string(&path).unwrap();
        for (line, literal) in string_literals(&text) {
            for flag in flags_in(&literal) {
                let allowed = NOT_OUR_FLAGS
                    .iter()
                    .any(|(m, flags, _)| *m == module && flags.contains(&flag.as_str()));
                if !allowed {
                    found.push(format!("{}:{line}: {flag}", path.display()));
                }
            }
        }
    }
    assert!(
        found.is_empty(),
        "library code names command-line flags (name a `Setting` instead):\n{}",
        found.join("\n")
    );
}

#[test]
fn literals_and_their_flags_are_found() {
    let text = "let a = \"--max-work {x}\"; // \"--not-this\"\nlet b = r#\"x --dt\"#; let c = '\"'; let d = \"---- a --b\";";
    let lits: Vec<String> = string_literals(text).into_iter().map(|l| l.1).collect();
    assert_eq!(lits, ["--max-work {x}", "x --dt", "---- a --b"]);
    let flags: Vec<String> = lits.iter().flat_map(|l| flags_in(l)).collect();
    assert_eq!(flags, ["--max-work", "--dt", "--b"]);
}
