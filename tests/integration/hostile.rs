//! A corpus of hostile animation files, made here (the "script" is
//! [`make_corpus`]) so that symbolic links and FIFOs need no committed
//! files: every kind of reference that leaves the file's folder, cycles,
//! counts that claim bytes that do not exist, nesting without end, and
//! names that would break a page. Each is handed to the binary's readers
//! (`classify`, `classify --json`, `describe`, `preview`); each must end
//! within seconds, without a panic, refusing with the file named where it
//! is at fault, and the canary beside the folder must never be read: its
//! files are a complete, valid fall, so a reader that followed a reference
//! out of the folder would succeed, and the test would see it. Without a
//! system-call tracer: the proof is in the outcomes. Controls read the
//! same bytes from inside the folder, and through `--allow-references`,
//! and must succeed, so the refusals are for the place, not the bytes.
//!
//! The same corpus seeds mutations for the fuzz budget of CI: a sixth of
//! `LEAFMAGIC_FUZZ_CASES` per file, rounded up (6 when it is unset).

use super::breeding::leafmagic;
use super::fuzz::{Ended, run_within};
use rand::SeedableRng;
use rand::rngs::Xoshiro256PlusPlus;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Duration;

/// Longest a case may run.
const TIMEOUT: Duration = Duration::from_secs(20);

/// A name no file of the repository holds: the canary's USD prim. Seen
/// in any output, a reference left the folder.
const CANARY: &str = "canary_6d1f";

fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// What a case is expected to do.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Expect {
    /// Refused, with the file named and, if given, these words in the
    /// message.
    Refused(&'static str),
    /// Read (exit 0).
    Read,
    /// Either, as long as it ends cleanly (a refusal naming the file).
    Ends,
}

struct Case {
    file: PathBuf,
    expect: Expect,
    extra: Vec<String>,
}

/// The corpus under `root`: `root/canary/` holds a valid fall in glTF
/// (`secret.bin`, the buffer of tests/data/blender's separate glTF) and
/// USD (`secret.usda`, its prims renamed to [`CANARY`]); `root/shared/`
/// holds the hostile files, which refer to them in every way a file can.
fn make_corpus(root: &Path) -> Vec<Case> {
    let _ = std::fs::remove_dir_all(root);
    let (canary, shared) = (root.join("canary"), root.join("shared"));
    std::fs::create_dir_all(&canary).unwrap();
    std::fs::create_dir_all(&shared).unwrap();
    let blender = repo().join("tests/data/blender");
    let bin = std::fs::read(blender.join("tumble_thick_separate.bin")).unwrap();
    std::fs::write(canary.join("secret.bin"), &bin).unwrap();
    std::fs::write(shared.join("inside.bin"), &bin).unwrap();
    let usda = std::fs::read_to_string(blender.join("tumble_thick.usda"))
        .unwrap()
        .replace("\"card\"", &format!("\"{CANARY}\""));
    std::fs::write(canary.join("secret.usda"), &usda).unwrap();
    std::fs::write(shared.join("inside.usda"), &usda).unwrap();
    let gltf: serde_json::Value =
        serde_json::from_slice(&std::fs::read(blender.join("tumble_thick_separate.gltf")).unwrap())
            .unwrap();
    let cases = std::cell::RefCell::new(Vec::new());
    let add = |name: &str, bytes: Vec<u8>, expect: Expect| {
        let file = shared.join(name);
        std::fs::write(&file, bytes).unwrap();
        cases.borrow_mut().push(Case {
            file,
            expect,
            extra: Vec::new(),
        });
    };
    // glTF buffers that point anywhere.
    let with_uri = |uri: &str, length: u64| {
        let mut g = gltf.clone();
        g["buffers"][0]["uri"] = uri.into();
        g["buffers"][0]["byteLength"] = length.into();
        serde_json::to_vec(&g).unwrap()
    };
    let len = bin.len() as u64;
    let abs = canary.join("secret.bin");
    add(
        "buffer-inside.gltf",
        with_uri("inside.bin", len),
        Expect::Read,
    );
    add(
        "buffer-parent.gltf",
        with_uri("../canary/secret.bin", len),
        Expect::Refused("outside"),
    );
    add(
        "buffer-encoded-parent.gltf",
        with_uri("%2E%2E/canary/secret.bin", len),
        Expect::Refused("outside"),
    );
    add(
        "buffer-absolute.gltf",
        with_uri(abs.to_str().unwrap(), len),
        Expect::Refused("absolute"),
    );
    add(
        "buffer-file-url.gltf",
        with_uri(&format!("file://{}", abs.display()), len),
        Expect::Refused("file://"),
    );
    add(
        "buffer-dev-zero.gltf",
        with_uri("/dev/zero", 2_000_000_000),
        Expect::Refused("absolute"),
    );
    #[cfg(unix)]
    {
        std::os::unix::fs::symlink(&abs, shared.join("link.bin")).unwrap();
        std::os::unix::fs::symlink("/dev/zero", shared.join("zero.bin")).unwrap();
        let made = Command::new("mkfifo")
            .arg(shared.join("pipe.bin"))
            .arg(shared.join("pipe.usda"))
            .status()
            .unwrap();
        assert!(made.success(), "mkfifo");
        add(
            "buffer-symlink-out.gltf",
            with_uri("link.bin", len),
            Expect::Refused("outside"),
        );
        add(
            "buffer-symlink-dev-zero.gltf",
            with_uri("zero.bin", 2_000_000_000),
            Expect::Refused("outside"),
        );
        add(
            "buffer-fifo.gltf",
            with_uri("pipe.bin", len),
            Expect::Refused("FIFO"),
        );
        add(
            "sublayer-fifo.usda",
            usd_arc("subLayers", "pipe.usda"),
            Expect::Refused("FIFO"),
        );
    }
    // USD arcs that point anywhere.
    add(
        "sublayer-inside.usda",
        usd_arc("subLayers", "inside.usda"),
        Expect::Read,
    );
    add(
        "sublayer-parent.usda",
        usd_arc("subLayers", "../canary/secret.usda"),
        Expect::Refused("outside"),
    );
    add(
        "sublayer-absolute.usda",
        usd_arc("subLayers", canary.join("secret.usda").to_str().unwrap()),
        // openusd makes every asset path absolute before the resolver
        // sees it, so an absolute one is refused for where it leads.
        Expect::Refused("outside"),
    );
    add(
        "reference-parent.usda",
        usd_arc("references", "../canary/secret.usda"),
        Expect::Refused("outside"),
    );
    add(
        "payload-parent.usda",
        usd_arc("payload", "../canary/secret.usda"),
        Expect::Refused("outside"),
    );
    // Graphs and depths a file controls.
    let nodes = |nodes: serde_json::Value, roots: serde_json::Value| {
        let mut g = gltf.clone();
        g["buffers"][0]["uri"] = "inside.bin".into();
        let mut all = nodes.as_array().unwrap().clone();
        all.insert(0, g["nodes"][0].clone());
        g["nodes"] = all.into();
        g["scenes"][0]["nodes"] = roots;
        serde_json::to_vec(&g).unwrap()
    };
    add(
        "node-own-child.gltf",
        nodes(
            serde_json::json!([{ "children": [1] }]),
            serde_json::json!([0, 1]),
        ),
        Expect::Refused("node"),
    );
    add(
        "node-two-cycle.gltf",
        nodes(
            serde_json::json!([{ "children": [2] }, { "children": [1] }]),
            serde_json::json!([0, 1]),
        ),
        Expect::Refused("node"),
    );
    let chain: Vec<serde_json::Value> = (0..100_000)
        .map(|k| {
            if k + 1 < 100_000 {
                serde_json::json!({ "children": [k + 2] })
            } else {
                serde_json::json!({})
            }
        })
        .collect();
    add(
        "node-chain-100000.gltf",
        nodes(chain.into(), serde_json::json!([0, 1])),
        Expect::Ends,
    );
    add(
        "scene-one-node-400000-times.gltf",
        nodes(serde_json::json!([]), vec![0; 400_000].into()),
        Expect::Ends,
    );
    let mut sparse = gltf.clone();
    sparse["buffers"][0]["uri"] = "inside.bin".into();
    sparse["accessors"][0]["sparse"] = serde_json::json!({
        "count": 4_294_967_295u64,
        "indices": { "bufferView": 0, "componentType": 5125 },
        "values": { "bufferView": 0 },
    });
    add(
        "sparse-count-4294967295.gltf",
        serde_json::to_vec(&sparse).unwrap(),
        Expect::Refused(""),
    );
    let deep_brackets = format!(
        "#usda 1.0\ndef Mesh \"m\"\n{{\n    custom int[] x = {}{}\n}}\n",
        "[".repeat(25_000),
        "]".repeat(25_000)
    );
    add(
        "brackets-25000.usda",
        deep_brackets.into_bytes(),
        Expect::Refused(""),
    );
    let mut deep_defs = String::from("#usda 1.0\n");
    for k in 0..20_000 {
        deep_defs.push_str(&format!("def Xform \"x{k}\" {{\n"));
    }
    deep_defs.push_str(&"}\n".repeat(20_000));
    add(
        "defs-20000.usda",
        deep_defs.into_bytes(),
        Expect::Refused(""),
    );
    add(
        "inherit-cycle.usda",
        b"#usda 1.0\nclass \"A\" (inherits = </B>) {}\nclass \"B\" (inherits = </A>) {}\n\
          def Mesh \"m\" (inherits = </A>) {}\n"
            .to_vec(),
        Expect::Refused(""),
    );
    add(
        "negative-face-counts.usda",
        b"#usda 1.0\ndef Mesh \"m\"\n{\n    int[] faceVertexCounts = [-3, 6]\n    \
          int[] faceVertexIndices = [0, 1, 2]\n    point3f[] points = [(0,0,0), (1,0,0), (0,1,0)]\n}\n"
            .to_vec(),
        Expect::Refused("faceVertexCounts"),
    );
    // The escape read through the flag that opens the canary's folder.
    for (name, arc) in [
        ("buffer-parent-allowed.gltf", None),
        ("sublayer-parent-allowed.usda", Some("subLayers")),
    ] {
        let bytes = match arc {
            None => with_uri("../canary/secret.bin", len),
            Some(arc) => usd_arc(arc, "../canary/secret.usda"),
        };
        add(name, bytes, Expect::Read);
        cases.borrow_mut().last_mut().unwrap().extra =
            vec!["--allow-references".into(), canary.to_str().unwrap().into()];
    }
    cases.into_inner()
}

/// A USD root layer that brings in `asset` by `arc`: `subLayers` in the
/// layer's metadata, `references` or `payload` on a prim (the canary's
/// root prim).
fn usd_arc(arc: &str, asset: &str) -> Vec<u8> {
    match arc {
        "subLayers" => format!("#usda 1.0\n(\n    subLayers = [@{asset}@]\n)\n"),
        _ => {
            format!("#usda 1.0\n\ndef Xform \"leaf\" (\n    {arc} = @{asset}@</root>\n)\n{{\n}}\n")
        }
    }
    .into_bytes()
}

fn run(cmd: Command) -> Ended {
    run_within(cmd, TIMEOUT)
}

/// Hands `file` to every reader and checks each outcome against `expect`;
/// returns what went wrong, if anything.
fn judge(file: &Path, expect: Expect, extra: &[String]) -> Vec<String> {
    let name = file.file_name().unwrap().to_string_lossy().into_owned();
    let page = file.with_extension("html");
    let _ = std::fs::remove_file(&page);
    let runs: [Vec<String>; 4] = [
        vec!["classify".into()],
        vec!["classify".into(), "--json".into()],
        vec!["describe".into()],
        vec![
            "preview".into(),
            "--out".into(),
            page.to_str().unwrap().into(),
        ],
    ];
    let mut wrong = Vec::new();
    for args in runs {
        let mut cmd = leafmagic();
        cmd.args(&args).arg(file).args(extra);
        let e = run(cmd);
        let what = format!("{name} ({})", args.join(" "));
        let said = format!("{}{}", e.stdout, e.stderr);
        if e.code.is_none() {
            wrong.push(format!(
                "{what}: no exit code after {:?} (killed or signalled)",
                e.took
            ));
            continue;
        }
        for bad in [
            "panicked",
            "overflow",
            "RUST_BACKTRACE",
            "memory allocation of",
        ] {
            if said.contains(bad) {
                wrong.push(format!("{what}: says `{bad}`: {}", e.stderr.trim()));
            }
        }
        if expect != Expect::Read && said.contains(CANARY) {
            wrong.push(format!("{what}: the canary was read: {}", said.trim()));
        }
        let html = std::fs::read_to_string(&page).unwrap_or_default();
        if expect != Expect::Read && html.contains(CANARY) {
            wrong.push(format!("{what}: the canary is in the page"));
        }
        let refused = e.code != Some(0);
        // describe may refuse a readable fall it cannot describe; the
        // others must read it.
        let must_read = expect == Expect::Read && args[0] != "describe";
        match expect {
            _ if must_read && refused => wrong.push(format!(
                "{what}: refused a readable file: {}",
                e.stderr.trim()
            )),
            Expect::Refused(words) if !refused => {
                wrong.push(format!("{what}: exit 0, expected a refusal ({words})"))
            }
            Expect::Refused(words) if !e.stderr.contains(words) => wrong.push(format!(
                "{what}: the refusal does not say `{words}`: {}",
                e.stderr.trim()
            )),
            _ if refused && !e.stderr.contains(&name) => wrong.push(format!(
                "{what}: the refusal does not name the file: {}",
                e.stderr.trim()
            )),
            _ => {}
        }
    }
    let _ = std::fs::remove_file(&page);
    wrong
}

#[test]
fn hostile_files_are_refused_by_name_and_the_canary_is_never_read() {
    let root = std::env::temp_dir().join(format!("leafmagic-hostile-{}", std::process::id()));
    let cases = make_corpus(&root);
    let mut wrong = Vec::new();
    for case in &cases {
        wrong.extend(judge(&case.file, case.expect, &case.extra));
    }
    let _ = std::fs::remove_dir_all(&root);
    assert!(
        wrong.is_empty(),
        "{} of {} cases went wrong:\n{}",
        wrong.len(),
        cases.len(),
        wrong.join("\n")
    );
}

/// Names that would break a page, as a glTF node's: the page keeps its
/// own tags and plays (the page's data parses back to the names; the
/// preview unit tests check that in detail).
#[test]
fn names_cannot_break_the_preview_page() {
    let root = std::env::temp_dir().join(format!("leafmagic-names-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&root);
    std::fs::create_dir_all(&root).unwrap();
    let blender = repo().join("tests/data/blender");
    std::fs::copy(
        blender.join("tumble_thick_separate.bin"),
        root.join("tumble_thick_separate.bin"),
    )
    .unwrap();
    let gltf: serde_json::Value =
        serde_json::from_slice(&std::fs::read(blender.join("tumble_thick_separate.gltf")).unwrap())
            .unwrap();
    let page_of = |node: &str| {
        let mut g = gltf.clone();
        g["nodes"][0]["name"] = node.into();
        let file = root.join("names.gltf");
        std::fs::write(&file, serde_json::to_vec(&g).unwrap()).unwrap();
        let page = root.join("names.html");
        let e = run({
            let mut c = leafmagic();
            c.arg("preview").arg(&file).arg("--out").arg(&page);
            c
        });
        assert_eq!(e.code, Some(0), "{node:?}: {}", e.stderr);
        std::fs::read_to_string(&page).unwrap()
    };
    let plain = page_of("card");
    for name in [
        "<!--<script>",
        "</script><script>alert(1)</script>",
        "q\"u'o`te",
        "sep\u{2028}ar\u{2029}ate",
    ] {
        let page = page_of(name);
        for tag in ["<script", "</script>", "<!--", "-->"] {
            assert_eq!(
                page.matches(tag).count(),
                plain.matches(tag).count(),
                "{name:?}: {tag}"
            );
        }
        assert!(!page.contains('\u{2028}'), "{name:?}");
    }
    let _ = std::fs::remove_dir_all(&root);
}

/// The corpus's text files mutated ([`super::fuzz`]'s mutations), each
/// left beside its references: every case ends cleanly, and none reads
/// the canary (unless its mutation made it a file that names nothing
/// outside, which the canary's name in the output would still show).
#[test]
fn mutated_hostile_files_end_cleanly_and_never_read_the_canary() {
    let per_file: usize = std::env::var("LEAFMAGIC_FUZZ_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .map_or(6, |n: usize| n.div_ceil(6).max(1));
    let root = std::env::temp_dir().join(format!("leafmagic-hostile-fuzz-{}", std::process::id()));
    let cases = make_corpus(&root);
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(58);
    let mut wrong = Vec::new();
    let mut ran = 0;
    for case in cases.iter().filter(|c| c.extra.is_empty()) {
        let bytes = std::fs::read(&case.file).unwrap();
        if bytes.len() > 200_000 {
            continue;
        }
        for k in 0..per_file {
            let mutated = super::fuzz::mutate(&bytes, &mut rng);
            let file = case.file.with_file_name(format!(
                "m{k}-{}",
                case.file.file_name().unwrap().to_string_lossy()
            ));
            std::fs::write(&file, &mutated).unwrap();
            let mut cmd = leafmagic();
            cmd.arg("classify").arg(&file);
            let e = run(cmd);
            ran += 1;
            let said = format!("{}{}", e.stdout, e.stderr);
            let name = file.file_name().unwrap().to_string_lossy().into_owned();
            if e.code.is_none() {
                wrong.push(format!("{name}: no exit code after {:?}", e.took));
            } else if said.contains("panicked") || said.contains("overflow") {
                wrong.push(format!("{name}: {}", e.stderr.trim()));
            } else if e.code != Some(0) && !e.stderr.contains(&name) {
                wrong.push(format!(
                    "{name}: the error does not name it: {}",
                    e.stderr.trim()
                ));
            }
            let outside = case.expect != Expect::Read;
            if outside && said.contains(CANARY) {
                wrong.push(format!("{name}: the canary was read"));
            }
            let _ = std::fs::remove_file(&file);
        }
    }
    let _ = std::fs::remove_dir_all(&root);
    assert!(ran > 0);
    assert!(
        wrong.is_empty(),
        "{} of {ran}:\n{}",
        wrong.len(),
        wrong.join("\n")
    );
}
