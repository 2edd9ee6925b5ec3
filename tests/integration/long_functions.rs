//! No function of `src/` runs past [`MAX_LINES`] lines unless a comment
//! just above it says why it must be one piece.
//!
//! The rule, kept simple: a function is the lines from its `fn` line to
//! the first line after it that holds only its indentation and `}` (what
//! rustfmt writes). One longer than [`MAX_LINES`] passes only if the
//! comment and attribute lines right above it hold [`MARKER`] and a reason.

use std::path::{Path, PathBuf};

/// The longest a function may run without saying why, lines.
const MAX_LINES: usize = 150;

/// What the comment above a longer function holds, then why.
const MARKER: &str = "one piece:";

/// Every `.rs` file under `src/`.
fn sources() -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut stack = vec![Path::new(env!("CARGO_MANIFEST_DIR")).join("src")];
    while let Some(dir) = stack.pop() {
        for entry in std::fs::read_dir(&dir).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                stack.push(path);
            } else if path.extension().is_some_and(|e| e == "rs") {
                out.push(path);
            }
        }
    }
    out.sort();
    out
}

/// The name of the function a line starts (`pub(crate) const fn name`),
/// with the line's indentation.
fn fn_start(line: &str) -> Option<(&str, &str)> {
    let body = line.trim_start();
    let indent = &line[..line.len() - body.len()];
    let mut words = body.split_whitespace();
    let mut word = words.next()?;
    while ["pub", "const", "async", "unsafe", "extern", "\"C\""].contains(&word)
        || word.starts_with("pub(")
    {
        word = words.next()?;
    }
    if word != "fn" {
        return None;
    }
    let name = words.next()?;
    let end = name
        .find(|c: char| !(c.is_alphanumeric() || c == '_'))
        .unwrap_or(name.len());
    Some((indent, &name[..end]))
}

/// Each function of `text` longer than `max` lines: its name, first line
/// (1-based), length, and whether the comments above it hold [`MARKER`].
fn long_functions(text: &str, max: usize) -> Vec<(String, usize, usize, bool)> {
    let lines: Vec<&str> = text.lines().collect();
    let mut out = Vec::new();
    for (i, line) in lines.iter().enumerate() {
        let Some((indent, name)) = fn_start(line) else {
            continue;
        };
        // A declaration without a body (in a trait) ends at its `;`.
        let Some(open) = (i..lines.len()).find(|&k| {
            let l = lines[k].trim_end();
            l.ends_with('{') || l.ends_with(';')
        }) else {
            continue;
        };
        if lines[open].trim_end().ends_with(';') {
            continue;
        }
        let close = format!("{indent}}}");
        let Some(end) = (open + 1..lines.len()).find(|&k| lines[k] == close) else {
            continue;
        };
        let length = end - i + 1;
        if length <= max {
            continue;
        }
        let marked = lines[..i]
            .iter()
            .rev()
            .take_while(|l| {
                let t = l.trim_start();
                t.starts_with("//") || t.starts_with("#[")
            })
            .any(|l| l.contains(MARKER));
        out.push((name.to_string(), i + 1, length, marked));
    }
    out
}

#[test]
fn no_function_runs_past_150_lines_unless_it_says_why() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut found = Vec::new();
    for path in sources() {
        let rel = path
            .strip_prefix(&root)
            .unwrap()
            .to_string_lossy()
            .replace('\\', "/");
        let text = std::fs::read_to_string(&path).unwrap();
        for (name, line, length, marked) in long_functions(&text, MAX_LINES) {
            if !marked {
                found.push(format!("src/{rel}:{line}: {name}, {length} lines"));
            }
        }
    }
    assert!(
        found.is_empty(),
        "functions over {MAX_LINES} lines: split them into steps, or say above each \
         `// {MARKER} why`:\n{}",
        found.join("\n")
    );
}

#[test]
fn long_functions_are_measured_and_marks_read() {
    let body = |n: usize| "    let x = 1;\n".repeat(n);
    let text = format!(
        "/// Doc.\npub(crate) fn short() {{\n{}}}\n\n\
         // one piece: the steps share too much state.\n#[allow(x)]\nfn marked() {{\n{}}}\n\n\
         fn long(\n    a: u8,\n) -> u8 {{\n{}}}\n\ntrait T {{\n    fn f(&self);\n}}\n",
        body(3),
        body(4),
        body(4)
    );
    let found = long_functions(&text, 5);
    assert_eq!(
        found,
        [
            ("marked".to_string(), 10, 6, true),
            ("long".to_string(), 17, 8, false)
        ]
    );
}
