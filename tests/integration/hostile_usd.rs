//! USD files that try to make the reader read what they do not hold
//! (issue 58): layers outside the file's folder by `..`, absolute paths,
//! symbolic links or package paths, a FIFO that blocks for ever, nesting
//! that overflows the stack, composition arcs in a cycle, and face counts
//! that lie. Each is written into a fresh folder beside a canary file that
//! must never be read, and each must be refused at once, naming the file,
//! without a panic, and without the canary's bytes anywhere.

use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// What the canary files hold: found in any output, the reader leaked.
const CANARY: &str = "CANARY-58-do-not-read";

/// A Mesh that moves, so that a stage read in full classifies.
const MESH: &str = r#"def Mesh "leaf" {
    int[] faceVertexCounts = [3]
    int[] faceVertexIndices = [0, 1, 2]
    point3f[] points.timeSamples = {
        0: [(0, 0, 0), (1, 0, 0), (0, 1, 0)],
        24: [(0, -1, 0), (1, -1, 0), (0, 0, 0)],
    }
}
"#;

/// A fresh folder `shared` with, beside it, the canaries `secret.usda`
/// (a layer that would compose) and `secret.txt`.
fn hostile(name: &str) -> (PathBuf, PathBuf) {
    let base = std::env::temp_dir().join(format!(
        "leafmagic-hostile-usd-{}-{name}",
        std::process::id()
    ));
    let _ = std::fs::remove_dir_all(&base);
    let shared = base.join("shared");
    std::fs::create_dir_all(&shared).unwrap();
    std::fs::write(
        base.join("secret.usda"),
        format!("#usda 1.0\ndef \"S\" {{ custom string probe = \"{CANARY}\" }}\n"),
    )
    .unwrap();
    std::fs::write(base.join("secret.txt"), CANARY).unwrap();
    (base, shared)
}

fn leafmagic() -> Command {
    Command::new(env!("CARGO_BIN_EXE_leafmagic"))
}

/// `leafmagic classify FILE ARGS…`: refused, quickly, naming the file,
/// with no panic, no overflow and no canary; its stderr.
fn refused(file: &Path, args: &[&str]) -> String {
    let start = Instant::now();
    let out = leafmagic()
        .arg("classify")
        .arg(file)
        .args(args)
        .env("LEAFMAGIC_USD_TIMEOUT_S", "30")
        .output()
        .unwrap();
    let took = start.elapsed();
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "{}: read\n{stdout}", file.display());
    let name = file.file_name().unwrap().to_str().unwrap();
    assert!(stderr.contains(name), "the file is not named: {stderr}");
    for bad in ["panicked", "overflow", CANARY] {
        assert!(!stderr.contains(bad), "`{bad}` in: {stderr}");
        assert!(!stdout.contains(bad), "`{bad}` in: {stdout}");
    }
    assert!(took < Duration::from_secs(10), "took {took:?}: {stderr}");
    stderr.into_owned()
}

#[test]
fn references_that_leave_the_folder_are_refused() {
    let (base, shared) = hostile("escape");
    let secret = base.join("secret.usda");
    let cases = [
        (
            "dotdot.usda",
            format!(
                "#usda 1.0\ndef Xform \"x\" (\n    references = @../secret.usda@</S>\n) {{}}\n{MESH}"
            ),
        ),
        (
            "absolute.usda",
            format!(
                "#usda 1.0\n(\n    subLayers = [@{}@]\n)\n{MESH}",
                secret.display()
            ),
        ),
        (
            "linked.usda",
            format!("#usda 1.0\ndef Xform \"x\" (\n    payload = @link.usda@</S>\n) {{}}\n{MESH}"),
        ),
    ];
    std::os::unix::fs::symlink(&secret, shared.join("link.usda")).unwrap();
    for (name, text) in &cases {
        let file = shared.join(name);
        std::fs::write(&file, text).unwrap();
        let e = refused(&file, &[]);
        assert!(e.contains("leads outside"), "{name}: {e}");
        assert!(e.contains("is refused"), "{name}: {e}");
        // The reference as written and the layer that wrote it.
        assert!(
            e.contains(&format!("named in {}", file.display())),
            "{name}: {e}"
        );
    }
    // Opened on request, the same reference is read (and the stage then
    // classifies, or fails for what it is, not for where it points).
    let out = leafmagic()
        .arg("classify")
        .arg(shared.join("dotdot.usda"))
        .arg("--allow-references")
        .arg(&base)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!stderr.contains("refused"), "{stderr}");
    let _ = std::fs::remove_dir_all(&base);
}

#[test]
fn a_fifo_layer_is_refused_at_once() {
    let (base, shared) = hostile("fifo");
    let made = Command::new("mkfifo")
        .arg(shared.join("pipe.usda"))
        .status()
        .unwrap();
    assert!(made.success());
    let file = shared.join("fifo.usda");
    std::fs::write(
        &file,
        format!("#usda 1.0\n(\n    subLayers = [@pipe.usda@]\n)\n{MESH}"),
    )
    .unwrap();
    let e = refused(&file, &[]);
    assert!(e.contains("`pipe.usda`") && e.contains("a FIFO"), "{e}");
    // As a reference too.
    std::fs::write(
        &file,
        format!("#usda 1.0\ndef Xform \"x\" (\n    references = @pipe.usda@\n) {{}}\n{MESH}"),
    )
    .unwrap();
    let e = refused(&file, &[]);
    assert!(e.contains("a FIFO"), "{e}");
    let _ = std::fs::remove_dir_all(&base);
}

/// A `.usdz` package at `path` of `layers` (name, text), the first its
/// root layer.
fn package(path: &Path, layers: &[(&str, String)]) {
    let mut writer = openusd::usdz::ArchiveWriter::create(path).unwrap();
    for (name, text) in layers {
        writer.add_layer(name, text.as_bytes()).unwrap();
    }
    writer.finish().unwrap();
}

#[test]
fn a_package_s_paths_stay_inside_it_and_its_folder() {
    let (base, shared) = hostile("usdz");
    let secret = base.join("secret.usda");
    // An absolute path from inside a package leaves the folder.
    let file = shared.join("absolute.usdz");
    package(
        &file,
        &[(
            "root.usda",
            format!(
                "#usda 1.0\ndef Xform \"x\" (\n    references = @{}@</S>\n) {{}}\n{MESH}",
                secret.display()
            ),
        )],
    );
    let e = refused(&file, &[]);
    assert!(e.contains("leads outside"), "{e}");
    // `..` inside a package stays inside it: there is no `secret.usda`
    // in the package, whatever lies beside it.
    std::fs::write(shared.join("secret.usda"), std::fs::read(&secret).unwrap()).unwrap();
    let file = shared.join("climbing.usdz");
    package(
        &file,
        &[(
            "root.usda",
            format!(
                "#usda 1.0\ndef Xform \"x\" (\n    references = @../../secret.usda@</S>\n) {{}}\n{MESH}"
            ),
        )],
    );
    let e = refused(&file, &[]);
    assert!(e.contains("secret.usda"), "{e}");
    std::fs::remove_file(shared.join("secret.usda")).unwrap();
    // A package path written with `..` inside its brackets is refused.
    let inner = shared.join("inner.usdz");
    package(&inner, &[("a.usda", format!("#usda 1.0\n{MESH}"))]);
    let file = shared.join("bracketed.usda");
    std::fs::write(
        &file,
        format!("#usda 1.0\ndef Xform \"x\" (\n    references = @inner.usdz[../secret.usda]@</S>\n) {{}}\n{MESH}"),
    )
    .unwrap();
    let e = refused(&file, &[]);
    assert!(e.contains("climbs out of its package"), "{e}");
    let _ = std::fs::remove_dir_all(&base);
}

#[test]
fn deep_nesting_is_refused_by_line_without_overflowing() {
    let (base, shared) = hostile("nesting");
    let brackets = format!(
        "#usda 1.0\ndef Mesh \"m\" {{\n    custom double[] deep = {}1{}\n}}\n",
        "[".repeat(25_000),
        "]".repeat(25_000)
    );
    let mut defs = String::from("#usda 1.0\n");
    for k in 0..20_000 {
        defs.push_str(&format!("def Xform \"p{k}\" {{\n"));
    }
    defs.push_str(&"}\n".repeat(20_000));
    // The same, with an arc that sends it to the composing reader.
    let composed = defs.replacen(
        "def Xform \"p0\" {",
        "def Xform \"p0\" (\n    inherits = </c>\n) {",
        1,
    );
    for (name, text) in [
        ("brackets.usda", brackets),
        ("defs.usda", defs),
        ("composed.usda", composed),
    ] {
        let file = shared.join(name);
        std::fs::write(&file, text).unwrap();
        let e = refused(&file, &[]);
        assert!(
            e.contains("nesting deeper than 128 levels at line"),
            "{name}: {e}"
        );
    }
    let _ = std::fs::remove_dir_all(&base);
}

#[test]
fn composition_cycles_are_named() {
    let (base, shared) = hostile("cycles");
    let cases = [
        (
            "inherits",
            "class \"A\" (\n    inherits = </B>\n) {}\nclass \"B\" (\n    inherits = </A>\n) {}\n",
            "</A> inherits </B>, which inherits </A>",
        ),
        (
            "specializes",
            "def \"A\" (\n    specializes = </B>\n) {}\ndef \"B\" (\n    specializes = </A>\n) {}\n",
            "</A> specializes </B>, which specializes </A>",
        ),
        (
            "references",
            "def \"A\" (\n    references = </B>\n) {}\ndef \"B\" (\n    references = </A>\n) {}\n",
            "</A> references </B>, which references </A>",
        ),
        // Through an ancestor: /A/c takes /B/c, which inherits /A/c.
        (
            "ancestral",
            "def \"A\" (\n    inherits = </B>\n) { def \"c\" {} }\ndef \"B\" { def \"c\" (\n    inherits = </A/c>\n) {} }\n",
            "</A/c> inherits </B/c>, which inherits </A/c>",
        ),
        (
            "below",
            "def \"A\" (\n    inherits = </A/c>\n) { def \"c\" {} }\n",
            "</A> inherits </A/c>, which lies below it",
        ),
    ];
    for (name, prims, want) in cases {
        let file = shared.join(format!("{name}.usda"));
        std::fs::write(&file, format!("#usda 1.0\n{prims}{MESH}")).unwrap();
        let e = refused(&file, &[]);
        assert!(e.contains("composition arcs form a cycle"), "{name}: {e}");
        assert!(e.contains(want), "{name}: {e}");
    }
    let _ = std::fs::remove_dir_all(&base);
}

#[test]
fn face_counts_that_lie_are_refused_by_prim_and_attribute() {
    let (base, shared) = hostile("counts");
    let cases = [
        ("[-3]", "[0, 1, 2]", "`faceVertexCounts` [0] is -3"),
        ("[2, 1]", "[0, 1, 2]", "`faceVertexCounts` [0] is 2"),
        (
            "[4]",
            "[0, 1, 2]",
            "add up to 4 vertices but `faceVertexIndices` holds 3",
        ),
        (
            "[3]",
            "[0, 1, 7]",
            "`faceVertexIndices` holds 7, past its 3 points",
        ),
        ("[3]", "[0, -1, 2]", "`faceVertexIndices` [1] is -1"),
        ("[1e300]", "[0, 1, 2]", "`faceVertexCounts` [0] is 1e300"),
    ];
    for (k, (counts, indices, want)) in cases.iter().enumerate() {
        let text = MESH.replace("[3]", counts).replace("[0, 1, 2]", indices);
        let file = shared.join(format!("counts{k}.usda"));
        std::fs::write(&file, format!("#usda 1.0\n{text}")).unwrap();
        let e = leafmagic::formats::fall::read_clip(&file, None)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("mesh `leaf`") && e.contains(want),
            "{counts} {indices}: {e}"
        );
        assert!(e.contains(&format!("counts{k}.usda")), "{e}");
    }
    let _ = std::fs::remove_dir_all(&base);
}

/// Whether process `pid` still runs (a zombie has ended).
fn running(pid: u32) -> bool {
    std::fs::read_to_string(format!("/proc/{pid}/stat")).is_ok_and(|s| {
        s.rsplit(')')
            .next()
            .is_some_and(|r| !r.trim_start().starts_with('Z'))
    })
}

/// A composed stage whose flat layer is far larger than a pipe holds:
/// a reader whose stdout nobody reads blocks writing it, for ever.
fn large_stage(shared: &Path) -> PathBuf {
    let points: Vec<String> = (0..20_000).map(|k| format!("({k}, 0, 0)")).collect();
    std::fs::write(
        shared.join("big.usda"),
        format!(
            "#usda 1.0\ndef Mesh \"big\" {{\n    point3f[] points = [{}]\n}}\n",
            points.join(", ")
        ),
    )
    .unwrap();
    let file = shared.join("shot.usda");
    std::fs::write(&file, "#usda 1.0\n(\n    subLayers = [@big.usda@]\n)\n").unwrap();
    file
}

#[test]
fn the_usd_reader_ends_when_its_parent_does() {
    let (base, shared) = hostile("orphan");
    let file = large_stage(&shared);
    // A shell stands for leafmagic: it starts the reader, says its pid,
    // and ends a second later without reading its answer; the reader's
    // stdout stays open (this test holds it) and full.
    let mut shell = Command::new("/bin/sh")
        .arg("-c")
        .arg(r#""$0" compose-usd "$1" --parent $$ & echo $! >&2; sleep 1"#)
        .arg(env!("CARGO_BIN_EXE_leafmagic"))
        .arg(&file)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut said = String::new();
    let mut stderr = shell.stderr.take().unwrap();
    let mut byte = [0u8; 1];
    while stderr.read(&mut byte).unwrap() == 1 && byte[0] != b'\n' {
        said.push(byte[0] as char);
    }
    let pid: u32 = said.trim().parse().unwrap();
    std::thread::sleep(Duration::from_millis(300));
    assert!(running(pid), "the reader ended before its parent");
    shell.wait().unwrap();
    let start = Instant::now();
    while running(pid) && start.elapsed() < Duration::from_secs(10) {
        std::thread::sleep(Duration::from_millis(50));
    }
    assert!(!running(pid), "the reader outlived its parent by 10 s");
    let _ = std::fs::remove_dir_all(&base);
}

#[test]
fn the_usd_reader_ends_past_its_time() {
    let (base, shared) = hostile("timeout");
    let file = large_stage(&shared);
    let mut reader = leafmagic()
        .arg("compose-usd")
        .arg(&file)
        .args([
            "--parent",
            &std::process::id().to_string(),
            "--timeout-s",
            "1",
        ])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let start = Instant::now();
    let status = loop {
        if let Some(status) = reader.try_wait().unwrap() {
            break status;
        }
        assert!(
            start.elapsed() < Duration::from_secs(10),
            "still running after 10 s"
        );
        std::thread::sleep(Duration::from_millis(50));
    };
    assert!(!status.success());
    let mut said = String::new();
    reader
        .stderr
        .take()
        .unwrap()
        .read_to_string(&mut said)
        .unwrap();
    assert!(said.contains("took longer than 1 s"), "{said}");
    let _ = std::fs::remove_dir_all(&base);
}
