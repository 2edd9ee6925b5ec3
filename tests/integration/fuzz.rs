//! A seeded fuzz harness: leaf, scene and fall files of the repository
//! (falls as CSV records and as glTF, USD and Alembic animations, handed
//! to `classify` and to `preview`, which classifies every object)
//! (and a plate as `leafmagic plate` writes it), mutated (bytes flipped,
//! lines cut, duplicated or swapped, numbers replaced by extremes, text that
//! is not UTF-8, truncation), are handed to the
//! binary; every case must end within a few seconds, without a panic, either
//! successfully or with an error that names the file. The cases of issue 22
//! live in tests/data/hardening and each is checked for its own outcome.
//! Run directories too: one file of a finished run mutated, `breed --resume`
//! must end byte-identical to the run or refuse naming the file.
//!
//! `LEAFMAGIC_FUZZ_CASES=N` sets the mutated cases per kind (default 40, a
//! few seconds in all); the mutations depend only on the seed, so a failure
//! names a case that can be rerun.

use super::breeding::leafmagic;
use rand::rngs::Xoshiro256PlusPlus;
use rand::{RngExt, SeedableRng};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// Longest a single case may run: no command of a fuzzed file should hang.
const TIMEOUT: Duration = Duration::from_secs(10);

fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn scratch(name: &str) -> PathBuf {
    super::common::scratch("fuzz", name)
}

/// What a case ended with.
pub(super) struct Ended {
    pub(super) code: Option<i32>,
    pub(super) stdout: String,
    pub(super) stderr: String,
    pub(super) took: Duration,
}

/// Runs `cmd`, killing it past [`TIMEOUT`].
fn run(cmd: Command) -> Ended {
    run_within(cmd, TIMEOUT)
}

/// Runs `cmd`, its output read on threads (a full pipe cannot stall it),
/// killing it past `limit`: a case that hangs ends with no exit code.
pub(super) fn run_within(mut cmd: Command, limit: Duration) -> Ended {
    let start = Instant::now();
    let mut child = cmd
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let drain = |pipe: Option<Box<dyn std::io::Read + Send>>| {
        std::thread::spawn(move || {
            let mut bytes = Vec::new();
            if let Some(mut pipe) = pipe {
                let _ = pipe.read_to_end(&mut bytes);
            }
            String::from_utf8_lossy(&bytes).into_owned()
        })
    };
    let stdout = drain(child.stdout.take().map(|p| Box::new(p) as _));
    let stderr = drain(child.stderr.take().map(|p| Box::new(p) as _));
    let code = loop {
        if let Some(status) = child.try_wait().unwrap() {
            break status.code();
        }
        if start.elapsed() > limit {
            let _ = child.kill();
            let _ = child.wait();
            break None;
        }
        std::thread::sleep(Duration::from_millis(2));
    };
    Ended {
        code,
        stdout: stdout.join().unwrap(),
        stderr: stderr.join().unwrap(),
        took: start.elapsed(),
    }
}

/// Numbers a hostile or unlucky file might hold.
const EXTREMES: [&str; 14] = [
    "0",
    "-1",
    "1e308",
    "-1e308",
    "1e-300",
    "5e-324",
    "nan",
    "inf",
    "1e8",
    "1e9",
    "100000000",
    "18446744073709551615",
    "-0.0",
    "\"x\"",
];

/// One seeded mutation of `text`.
pub(super) fn mutate(text: &[u8], rng: &mut Xoshiro256PlusPlus) -> Vec<u8> {
    let mut out = text.to_vec();
    let lines =
        |b: &[u8]| -> Vec<Vec<u8>> { b.split(|&c| c == b'\n').map(<[u8]>::to_vec).collect() };
    for _ in 0..rng.random_range(1..4) {
        match rng.random_range(0..7) {
            0 if !out.is_empty() => {
                // Flip a byte (may make invalid UTF-8).
                let k = rng.random_range(0..out.len());
                out[k] ^= 1 << rng.random_range(0..8);
            }
            1 if !out.is_empty() => {
                let k = rng.random_range(0..out.len());
                out.truncate(k);
            }
            2 => {
                // Replace a number with an extreme.
                let text = String::from_utf8_lossy(&out).into_owned();
                let spans: Vec<(usize, usize)> = number_spans(&text);
                if !spans.is_empty() {
                    let (a, b) = spans[rng.random_range(0..spans.len())];
                    let v = EXTREMES[rng.random_range(0..EXTREMES.len())];
                    out = format!("{}{v}{}", &text[..a], &text[b..]).into_bytes();
                }
            }
            3 => {
                let mut ls = lines(&out);
                if !ls.is_empty() {
                    let k = rng.random_range(0..ls.len());
                    ls.remove(k);
                }
                out = ls.join(&b'\n');
            }
            4 => {
                let mut ls = lines(&out);
                if !ls.is_empty() {
                    let k = rng.random_range(0..ls.len());
                    let dup = ls[k].clone();
                    ls.insert(k, dup);
                }
                out = ls.join(&b'\n');
            }
            5 => {
                let mut ls = lines(&out);
                if ls.len() > 1 {
                    let (a, b) = (rng.random_range(0..ls.len()), rng.random_range(0..ls.len()));
                    ls.swap(a, b);
                }
                out = ls.join(&b'\n');
            }
            _ => {
                let k = rng.random_range(0..=out.len());
                let junk: &[u8] =
                    [&b"\xff\xfe"[..], b",,,", b"[[", b"= =", b"\0"][rng.random_range(0..5)];
                let _none: Vec<u8> = out.splice(k..k, junk.iter().copied()).collect();
            }
        }
    }
    out
}

/// Byte spans of the numbers in `text`.
fn number_spans(text: &str) -> Vec<(usize, usize)> {
    let b = text.as_bytes();
    let mut spans = Vec::new();
    let mut k = 0;
    while k < b.len() {
        let start_ok = k == 0 || !(b[k - 1].is_ascii_alphanumeric() || b[k - 1] == b'_');
        if start_ok
            && (b[k].is_ascii_digit()
                || (b[k] == b'-' && b.get(k + 1).is_some_and(u8::is_ascii_digit)))
        {
            let s = k;
            k += 1;
            while k < b.len() && (b[k].is_ascii_digit() || b".eE-+".contains(&b[k])) {
                k += 1;
            }
            spans.push((s, k));
        } else {
            k += 1;
        }
    }
    spans
}

/// The cases per kind.
fn cases() -> usize {
    std::env::var("LEAFMAGIC_FUZZ_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(40)
}

/// Checks one ended case: no hang, no panic, success or an error naming
/// the file.
fn judge(what: &str, file: &Path, e: &Ended) {
    let name = file.file_name().unwrap().to_string_lossy();
    assert!(
        e.code.is_some(),
        "{what}: {name} hung (killed after {TIMEOUT:?}) or died by a signal"
    );
    assert!(
        !e.stderr.contains("panicked") && e.code != Some(101),
        "{what}: {name} panicked:\n{}",
        e.stderr
    );
    assert!(
        matches!(e.code, Some(0 | 1)),
        "{what}: {name} exited {:?}:\n{}",
        e.code,
        e.stderr
    );
    if e.code == Some(1) {
        assert!(
            e.stderr.contains(&*name),
            "{what}: the error does not name the file {name}:\n{}",
            e.stderr
        );
    }
}

fn seeds(dir: &str, ext: &str) -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(repo().join(dir))
        .unwrap()
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == ext))
        .collect();
    v.sort();
    v
}

#[test]
fn mutated_leaf_scene_and_fall_files_end_cleanly_and_name_the_file() {
    let dir = scratch("cases");
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(22);
    // A rigid plate as `leafmagic plate` writes it, under the unsteady law.
    let plate = dir.join("plate-seed.toml");
    let made = leafmagic()
        .args(["plate", "--shape", "square", "--size", "0.05", "--out"])
        .arg(&plate)
        .output()
        .unwrap();
    assert!(made.status.success(), "{made:?}");
    // A mutated .gltf still finds the buffer it names.
    std::fs::copy(
        repo().join("tests/data/blender/tumble_thick_separate.bin"),
        dir.join("tumble_thick_separate.bin"),
    )
    .unwrap();
    // A mutated composed shot still finds the layers it names.
    for layer in ["anim.usda", "card_asset.usdc", "card_mesh.usda"] {
        std::fs::copy(
            repo().join("tests/data/usd/composed").join(layer),
            dir.join(layer),
        )
        .unwrap();
    }
    let kinds: [(&str, Vec<PathBuf>); 4] = [
        (
            "leaf",
            [
                seeds("prototypes", "toml"),
                vec![
                    repo().join("tests/data/hardening/unsteady-leaf.toml"),
                    plate,
                ],
            ]
            .concat(),
        ),
        ("scene", seeds("scenes", "toml")),
        (
            "fall",
            vec![
                repo().join("tests/data/mujoco-falls/steady_fall.csv"),
                repo().join("tests/data/mujoco-falls/tumble_thick.csv"),
            ],
        ),
        (
            // Falls in animation files: glTF (JSON and binary, skinned,
            // quantised), USD text (nested, UsdSkel, blend shapes, a PointInstancer), USD crate files, a
            // USDZ package, a composed shot and Alembic archives.
            "animation",
            [
                "blender/tumble_thick_separate.gltf",
                "blender/tumble_thick_rigged.glb",
                "gltfpack/tumble_thick_rigged.glb",
                "blender/tumble_thick_rigged.usda",
                "blender/tumble_thick_parented.usda",
                "usd/skinned_leaf.usda",
                "blender/tumble_thick_curled.usda",
                "usd/instanced/leaves.usda",
                "usd/composed/tumble_thick_rigged.usdc",
                "usd/composed/skinned_leaf.usdc",
                "usd/composed/tumble_thick.usdz",
                "usd/composed/shot.usda",
                "blender/tumble_thick_parented.abc",
                "blender/tumble_thick_curled.abc",
                "particles/dying.abc",
            ]
            .iter()
            .map(|f| repo().join("tests/data").join(f))
            .collect(),
        ),
    ];
    let mut slowest = (Duration::ZERO, String::new());
    let mut failed_cleanly = 0;
    for (kind, sources) in &kinds {
        for case in 0..cases() {
            let source = &sources[case % sources.len()];
            let text = std::fs::read(source).unwrap();
            let ext = source.extension().unwrap().to_string_lossy();
            let file = dir.join(format!("{kind}-{case:04}.{ext}"));
            std::fs::write(&file, mutate(&text, &mut rng)).unwrap();
            let mut commands: Vec<(&str, Command)> = Vec::new();
            match *kind {
                "leaf" => {
                    let mut check = leafmagic();
                    check.arg("check").arg(&file);
                    let mut drop = leafmagic();
                    drop.arg("drop")
                        .arg(&file)
                        .args(["--seconds", "0.5", "--max-work", "3e6"]);
                    commands.push(("check", check));
                    commands.push(("drop", drop));
                }
                "scene" => {
                    let mut scene = leafmagic();
                    // Scene leaf paths are relative to the scene file.
                    scene
                        .current_dir(&dir)
                        .arg("scene")
                        .arg(&file)
                        .args([
                            "--seconds",
                            "0.1",
                            "--max-work",
                            "3e6",
                            "--max-memory",
                            "1e8",
                        ])
                        .arg("--out")
                        .arg(dir.join(format!("out-{case}")));
                    commands.push(("scene", scene));
                }
                _ => {
                    let mut classify = leafmagic();
                    classify.arg("classify").arg(&file);
                    commands.push(("classify", classify));
                    // The page classifies every object of the file, not
                    // only the one classify picks, and resamples them.
                    let mut preview = leafmagic();
                    preview
                        .arg("preview")
                        .arg(&file)
                        .arg("--out")
                        .arg(dir.join(format!("page-{case}.html")));
                    commands.push(("preview", preview));
                }
            }
            for (what, cmd) in commands {
                let ended = run(cmd);
                judge(what, &file, &ended);
                failed_cleanly += usize::from(ended.code == Some(1));
                if ended.took > slowest.0 {
                    slowest = (ended.took, format!("{what} {}", file.display()));
                }
            }
            let _ = std::fs::remove_dir_all(dir.join(format!("out-{case}")));
            let _ = std::fs::remove_file(dir.join(format!("page-{case}.html")));
        }
    }
    // The mutations do reach the checks (most cases are refused).
    assert!(failed_cleanly > cases(), "only {failed_cleanly} refusals");
    eprintln!(
        "fuzz: {} cases per kind; slowest {:?} ({})",
        cases(),
        slowest.0,
        slowest.1
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// `(command, file, extra arguments, success expected, words the output must
/// hold)`.
type Expect = (
    &'static str,
    &'static str,
    &'static [&'static str],
    bool,
    &'static [&'static str],
);

/// Each case of issue 22 ends as it now should.
#[test]
fn the_cases_of_issue_22_end_as_they_should() {
    let data = repo().join("tests/data/hardening");
    let out = scratch("regressions");
    let lost_mass: &[&str] = &[
        "no time step can be chosen",
        "particle[0]'s added mass is 3.064e24 kg",
        "[aero] added_mass",
    ];
    let overflowed: &[&str] = &[
        "no time step can be chosen",
        "the drag rate = inf",
        "gravity",
    ];
    let cases: [Expect; 19] = [
        (
            "check",
            "overflowing-spring.toml",
            &[],
            false,
            &["no time step can be chosen", "spring[0]"],
        ),
        ("check", "huge-added-mass.toml", &[], false, lost_mass),
        ("check", "rigid-huge-gravity.toml", &[], false, overflowed),
        ("drop", "rigid-huge-gravity.toml", &[], false, overflowed),
        ("drop", "huge-added-mass.toml", &[], false, lost_mass),
        (
            "drop",
            "huge-added-mass.toml",
            &["--dt", "1e-4"],
            false,
            lost_mass,
        ),
        (
            "drop",
            "overflowing-spring.toml",
            &[],
            false,
            &["no time step can be chosen", "spring[0]"],
        ),
        ("drop", "heavy-particle.toml", &[], true, &[]),
        (
            "drop",
            "stiff-springs.toml",
            &["--max-work", "1e7"],
            false,
            &[
                "particle-steps",
                "stiffest spring is spring 0",
                "--integrator implicit",
                "--max-work",
            ],
        ),
        (
            "drop",
            "light-masses.toml",
            &["--max-work", "1e7"],
            false,
            &[
                "lightest particle",
                "--integrator implicit",
                "set by the damping's fastest rate",
                "lower the springs' and hinges' damping",
            ],
        ),
        (
            "drop",
            "stiff-springs.toml",
            &["--integrator", "implicit"],
            true,
            &[],
        ),
        (
            "breed",
            "stiff-springs.toml",
            &[],
            false,
            &[
                "--prototype",
                "stiff-springs.toml",
                "particle-steps",
                "--max-work",
            ],
        ),
        (
            "scene",
            "big-cylinder.toml",
            &["--explain"],
            false,
            &["big-cylinder.toml:", "rigid[0].segments", "1000000"],
        ),
        (
            "scene",
            "big-rope.toml",
            &["--explain"],
            false,
            &["rope[0].segments"],
        ),
        (
            "scene",
            "many-leaves.toml",
            &["--explain"],
            false,
            &["leaf[0].count"],
        ),
        (
            "scene",
            "big-sheet.toml",
            &["--explain"],
            false,
            &["sheet[0].cells", "1.00e10 particles"],
        ),
        (
            "scene",
            "stiff-tear.toml",
            &[],
            false,
            &["integrator = \"implicit\"", "stiffest spring", "--max-work"],
        ),
        (
            "scene",
            "integrator-number.toml",
            &[],
            false,
            &["integrator", "\"rk4\""],
        ),
        (
            "scene",
            "tiny-vortex-core.toml",
            &[],
            false,
            &["the wind field is not finite", "core_radius"],
        ),
    ];
    for (command, file, extra, ok, words) in cases {
        let path = data.join(file);
        let mut cmd = leafmagic();
        cmd.arg(command);
        match command {
            "breed" => {
                cmd.arg("--prototype")
                    .arg(&path)
                    .arg("--out")
                    .arg(out.join("breed"));
            }
            "scene" => {
                cmd.arg(&path).arg("--out").arg(out.join(file));
            }
            "drop" => {
                cmd.arg(&path).args(["--seconds", "1"]);
            }
            _ => {
                cmd.arg(&path);
            }
        }
        cmd.args(extra);
        let ended = run(cmd);
        judge(command, &path, &ended);
        assert_eq!(
            ended.code == Some(0),
            ok,
            "{command} {file}: {}",
            ended.stderr
        );
        for w in words {
            assert!(
                ended.stderr.contains(w),
                "{command} {file}: no {w:?} in:\n{}",
                ended.stderr
            );
        }
        // A refused breed leaves no run directory behind.
        if command == "breed" {
            assert!(!out.join("breed").exists());
        }
    }
    for (file, words) in [
        ("bad-utf8.csv", &["line 3", "field 4 is not UTF-8"][..]),
        (
            "extra-field.csv",
            &["line 3", "9 fields", "remove the extra fields"][..],
        ),
    ] {
        let path = data.join(file);
        let mut cmd = leafmagic();
        cmd.arg("classify").arg(&path);
        let ended = run(cmd);
        judge("classify", &path, &ended);
        assert_eq!(ended.code, Some(1));
        assert!(!ended.stderr.contains("Utf8 {"), "{}", ended.stderr);
        for w in words {
            assert!(
                ended.stderr.contains(w),
                "{file}: no {w:?} in:\n{}",
                ended.stderr
            );
        }
    }
}

/// The bounds refuse none of today's valid work: every shipped scene is far
/// below the work and memory limits, and the default breed of either
/// prototype (its 800 leaves, each from every release) well below the
/// breed's limit of about ten minutes of one core.
#[test]
fn the_bounds_refuse_no_shipped_scene_and_not_the_default_breed() {
    use leafmagic::physics::run::{MAX_BREED_WORK, MAX_WORK};
    use leafmagic::sim::drop::{DropParams, drop_work};
    use leafmagic::sim::scene::{MAX_MEMORY, Scene};
    for file in seeds("scenes", "toml") {
        let scene = Scene::load(&file).unwrap();
        let work = scene.work(None).unwrap();
        assert!(
            work.particle_steps() < MAX_WORK / 100.0,
            "{}: {}",
            file.display(),
            work.describe()
        );
        assert!(
            scene.recorded_bytes(None) < MAX_MEMORY / 100.0,
            "{}",
            file.display()
        );
    }
    for p in ["a", "b"] {
        let model = leafmagic::leaf::LeafSpec::load(p).unwrap().model().unwrap();
        let one = drop_work(&model, &DropParams::default()).unwrap();
        // 100 leaves × 8 generations, each dropped from the default releases.
        let releases = leafmagic::breed::settings::DEFAULT_RELEASES as f64;
        let breed = one.particle_steps() * 800.0 * releases;
        assert!(breed < MAX_BREED_WORK / 20.0, "{p}: {breed:.2e}");
        assert!(!one.is_long(), "{p}: {}", one.describe());
    }
}

/// Copies a directory tree.
fn copy_tree(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap() {
        let e = e.unwrap();
        if e.path().is_dir() {
            copy_tree(&e.path(), &to.join(e.file_name()));
        } else {
            std::fs::copy(e.path(), to.join(e.file_name())).unwrap();
        }
    }
}

/// A run directory with one file mutated (bytes flipped, cut, lines
/// dropped, duplicated or swapped, numbers made extreme, junk inserted) is
/// resumed by `breed --resume`: it ends without a hang or a panic, either
/// with every file byte-identical to the uninterrupted run's (the damage
/// was recomputed, or the mutation changed nothing) or refused with an
/// error naming the mutated file (a changed run.toml cannot be recomputed).
#[test]
fn mutated_run_directories_resume_to_the_same_bytes_or_are_refused_naming_the_file() {
    use super::breeding::{breed, contents};
    let dir = scratch("runs");
    let whole = dir.join("whole");
    let small = ["--population", "12", "--generations", "3", "--seconds", "2"];
    let made = breed(&small, &whole);
    assert!(
        made.status.success(),
        "{}",
        String::from_utf8_lossy(&made.stderr)
    );
    let reference = contents(&whole);
    let targets = [
        "checkpoint.json",
        "run.toml",
        "gen-000.csv",
        "gen-001.csv",
        "gen-002.csv",
        "generations.csv",
        "best/index.csv",
    ];
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(2022);
    let (mut repaired, mut refused) = (0, 0);
    for case in 0..(cases() / 2).max(targets.len()) {
        let target = targets[case % targets.len()];
        let case_dir = dir.join(format!("case-{case:03}"));
        copy_tree(&whole, &case_dir);
        let path = case_dir.join(target);
        let text = std::fs::read(&path).unwrap();
        std::fs::write(&path, mutate(&text, &mut rng)).unwrap();
        let mut cmd = leafmagic();
        cmd.arg("breed").arg("--resume").arg(&case_dir);
        let ended = run(cmd);
        judge("breed --resume", &path, &ended);
        if ended.code == Some(0) {
            assert!(
                contents(&case_dir) == reference,
                "case {case} ({target}): resumed but not byte-identical:\n{}",
                ended.stderr
            );
            repaired += 1;
        } else {
            refused += 1;
        }
        let _ = std::fs::remove_dir_all(&case_dir);
    }
    eprintln!("fuzz: run directories: {repaired} resumed byte-identical, {refused} refused");
    // Both outcomes are reached: damage is repaired, and run.toml refused.
    assert!(
        repaired > 0 && refused > 0,
        "{repaired} repaired, {refused} refused"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// Every command given a file or run directory that is not there fails
/// naming it once, with what the system said once (an error chain printed
/// the I/O error twice when the message also held it) and in its own
/// words (a missing run directory read as "no run to resume there" for
/// export, merge and --start-from).
#[test]
fn a_missing_input_is_named_once_in_the_commands_own_words() {
    let dir = scratch("missing");
    let gone = |name: &str| dir.join(name).to_string_lossy().into_owned();
    let (csv, toml, run) = (gone("fall.csv"), gone("leaf.toml"), gone("run"));
    let out = gone("out");
    let cases: Vec<Vec<&str>> = vec![
        vec!["classify", &csv],
        vec!["describe", &csv],
        vec!["compare", &csv, &csv],
        vec!["drop", &toml, "--seconds", "0.1"],
        vec!["check", &toml],
        vec!["scene", &toml],
        vec!["export", &run, "--top", "1", "--out", &out],
        vec!["merge", &run, "--generation", "0", "--count", "1"],
        vec!["breed", "--start-from", &run, "--out", &out],
        vec!["breed", "--resume", &run],
    ];
    for args in cases {
        let ended = run_args(&args);
        let what = args.join(" ");
        assert!(!ended.success, "{what}: succeeded");
        let named = args
            .iter()
            .find(|a| a.starts_with(dir.to_str().unwrap()))
            .unwrap();
        assert!(ended.stderr.contains(*named), "{what}: {}", ended.stderr);
        assert!(
            ended.stderr.matches("No such file or directory").count() <= 1,
            "{what}: said twice: {}",
            ended.stderr
        );
        assert!(
            !ended.stderr.contains(": file:"),
            "{what}: {}",
            ended.stderr
        );
        if !args.contains(&"--resume") {
            assert!(!ended.stderr.contains("resume"), "{what}: {}", ended.stderr);
        }
    }
}

/// What a command ended with.
struct CliEnd {
    success: bool,
    stderr: String,
}

fn run_args(args: &[&str]) -> CliEnd {
    let out = leafmagic().args(args).output().unwrap();
    CliEnd {
        success: out.status.success(),
        stderr: String::from_utf8_lossy(&out.stderr).into_owned(),
    }
}
