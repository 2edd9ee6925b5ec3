//! Scene files: errors name the file, the line and the field; the compiler
//! keeps exactly the terms a scene uses and leaving the others out changes
//! nothing; the command writes the same bytes for the same input.

use crate::common::V3;
use crate::scenes::{load, scene_path};
use leafmagic::physics::integrate::{SimError, Simulator};
use leafmagic::physics::state::State;
use leafmagic::physics::terms::Terms;
use leafmagic::sim::scene::{RunError, Scene, SceneError};
use std::path::Path;
use std::process::Command;

const MINIMAL: &str = r#"name = "t"
duration = 1.0

[[leaf]]
name = "l"
leaf = "a"
position = [0.0, 0.0, 1.0]
"#;

fn compile(text: &str) -> Result<Scene, SceneError> {
    Scene::from_toml(text, "test.toml", Path::new(env!("CARGO_MANIFEST_DIR")))
}

fn error(text: &str) -> SceneError {
    compile(text).expect_err("the scene should be rejected")
}

/// 1-based line of the first line of `text` containing `needle`.
fn line_of(text: &str, needle: &str) -> usize {
    text.lines().position(|l| l.contains(needle)).unwrap() + 1
}

#[test]
fn errors_name_the_file_the_line_and_the_field() {
    assert!(compile(MINIMAL).is_ok());
    // (scene text, text on the expected line, expected field)
    let cases: Vec<(String, &str, &str)> = vec![
        // Unknown key (deny_unknown_fields).
        (
            format!("{MINIMAL}colour = \"red\"\n"),
            "colour",
            "leaf[0].colour",
        ),
        // Wrong type.
        (
            MINIMAL.replace("duration = 1.0", "duration = \"long\""),
            "duration",
            "duration",
        ),
        // Out of range, found by the compiler.
        (format!("{MINIMAL}count = 0\n"), "count", "leaf[0].count"),
        (
            format!("{MINIMAL}\n[ground]\nstatic_friction = 0.2\nkinetic_friction = 0.5\n"),
            "static_friction",
            "ground.static_friction",
        ),
        (
            format!(
                "{MINIMAL}\n[[wind]]\nkind = \"line_vortex\"\npoint = [0.0, 0.0, 0.0]\naxis = [0.0, 0.0, 1.0]\ncirculation = 1.0\ncore_radius = -0.1\n"
            ),
            "core_radius",
            "wind[0].core_radius",
        ),
        (
            format!(
                "{MINIMAL}\n[[rigid]]\nname = \"b\"\nshape = \"box\"\nsize = [1.0, 1.0, 1.0]\nmass = -2.0\n"
            ),
            "mass = -2.0",
            "rigid[0].mass",
        ),
        (
            format!(
                "{MINIMAL}\n[[rigid]]\nname = \"b\"\nshape = \"box\"\nsize = [1.0, 1.0, 1.0]\nradius = 2.0\nmass = 2.0\n"
            ),
            "radius",
            "rigid[0].radius",
        ),
        (
            format!(
                "{MINIMAL}\n[[fixed]]\nname = \"p\"\nposition = [0.0, 0.0, 2.0]\n\n[[rope]]\nname = \"r\"\nfrom = \"p\"\nto = \"nowhere:1\"\nsegments = 4\nmass = 0.1\nstiffness = 10.0\n"
            ),
            "nowhere",
            "rope[0].to",
        ),
        (
            MINIMAL.replace("leaf = \"a\"", "leaf = \"no/such/leaf.toml\""),
            "no/such",
            "leaf[0].leaf",
        ),
        // A duplicate name, on the second leaf's name line.
        (
            format!("{MINIMAL}\n[[leaf]]\nname = \"l\" # again\nleaf = \"b\"\n"),
            "# again",
            "leaf[1].name",
        ),
        (
            MINIMAL.replace("name = \"l\"", "name = \"a/b\""),
            "a/b",
            "leaf[0].name",
        ),
        // A key of another kind of wind primitive: on the key's own line.
        (
            format!(
                "{MINIMAL}\n[[wind]]\nkind = \"uniform\"\nflux = 2.0\nvelocity = [1.0, 0.0, 0.0]\n"
            ),
            "flux",
            "wind[0].flux",
        ),
    ];
    for (text, needle, field) in cases {
        let e = error(&text);
        let line = line_of(&text, needle);
        assert_eq!(e.file, "test.toml");
        assert_eq!(e.field, field, "{e}");
        assert_eq!(e.line, Some(line), "{e}");
        let shown = e.to_string();
        assert!(
            shown.starts_with(&format!("test.toml:{line}: {field}: ")),
            "{shown}"
        );
    }
    // A missing required key: named, on its table's line.
    let text = MINIMAL.replace("leaf = \"a\"\n", "");
    let e = error(&text);
    assert!(e.reason.contains("leaf"), "{e}");
    assert_eq!(e.line, Some(line_of(&text, "[[leaf]]")), "{e}");
}

/// A name given as a number (a rigid shape, a wind kind, a bound's shape,
/// a pin, a vortex core) says that a string was wanted and which, naming
/// the file, the line and the field.
#[test]
fn a_number_where_a_name_belongs_says_the_names() {
    let wind = "\n[[wind]]\nkind = \"line_vortex\"\npoint = [0.0, 0.0, 0.0]\naxis = [0.0, 0.0, 1.0]\ncirculation = 1.0\ncore_radius = 0.1\n";
    let cases: Vec<(String, &str, &str, &str)> = vec![
        (
            format!(
                "{MINIMAL}\n[[rigid]]\nname = \"b\"\nshape = 3\nsize = [1.0, 1.0, 1.0]\nmass = 2.0\n"
            ),
            "shape = 3",
            "rigid[0].shape",
            "expected a string: one of box, cylinder",
        ),
        (
            format!(
                "{MINIMAL}{}",
                wind.replace("kind = \"line_vortex\"", "kind = 3")
            ),
            "kind = 3",
            "wind[0].kind",
            "expected a string: one of uniform, point_source,",
        ),
        (
            format!("{MINIMAL}{wind}core = 2\n"),
            "core = 2",
            "wind[0].core",
            "expected a string: one of lamb_oseen, rankine",
        ),
        (
            format!(
                "{MINIMAL}{wind}bounds = {{ shape = 3, center = [0.0, 0.0, 0.0], radius = 1.0, falloff = 0.1 }}\n"
            ),
            "bounds = ",
            "wind[0].bounds.shape",
            "expected a string: one of sphere, box, cylinder",
        ),
        (
            format!(
                "{MINIMAL}\n[[sheet]]\nname = \"s\"\nsize = [1.0, 1.0]\ncells = [2, 2]\nmass = 0.1\nstiffness = 10.0\npin = 1\n"
            ),
            "pin = 1",
            "sheet[0].pin",
            "expected a string: one of none, top_edge, top_corners, corners, border",
        ),
    ];
    for (text, needle, field, words) in cases {
        let e = error(&text);
        let shown = e.to_string();
        let line = line_of(&text, needle);
        assert_eq!(e.field, field, "{shown}");
        assert_eq!(e.line, Some(line), "{shown}");
        assert!(
            shown.starts_with(&format!("test.toml:{line}: {field}: ")),
            "{shown}"
        );
        assert!(shown.contains(words), "{words:?} not in: {shown}");
        assert!(!shown.contains("wanted string or table"), "{shown}");
    }
}

/// A scene far past the limits (65,536 leaves) is refused from the parsed
/// file, before its objects are built (which took 11 s and 0.6 GB), with
/// the estimate, the limit and the flag that raises it; with the memory
/// raised, the work is refused in the same way.
#[test]
fn a_scene_past_its_limits_is_refused_from_the_file_within_a_second() {
    let dir = std::env::temp_dir().join(format!("leafmagic-scene-bounds-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("many.toml");
    std::fs::write(
        &file,
        "name = \"many\"\nduration = 10.0\n\n[[leaf]]\nname = \"l\"\nleaf = \"a\"\ncount = 65536\nposition = [0.0, 0.0, 5.0]\nspread = [50.0, 50.0, 2.0]\n",
    )
    .unwrap();
    let cases: [(&[&str], &[&str]); 2] = [
        (
            &[],
            &[
                "many.toml:7: leaf[0].count: the scene would record about",
                "65536 poses",
                "more than the limit of 2.0e9 bytes",
                "before anything was built",
                "--max-memory",
            ],
        ),
        (
            &["--max-memory", "1e12"],
            &[
                "many.toml:7: leaf[0].count: the scene needs at least",
                "458752 particles",
                "of one core",
                "past the limit of 1.0e9 particle-steps",
                "--max-work",
            ],
        ),
    ];
    for (flags, words) in cases {
        let start = std::time::Instant::now();
        let out = leafmagic()
            .arg("scene")
            .arg(&file)
            .args(flags)
            .arg("--out")
            .arg(dir.join("out"))
            .output()
            .unwrap();
        let took = start.elapsed().as_secs_f64();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{stderr}");
        for w in words {
            assert!(stderr.contains(w), "{w:?} not in: {stderr}");
        }
        assert!(took < 2.0, "refused only after {took:.1} s: {stderr}");
        assert!(!dir.join("out").exists());
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Staging folders of a scene run killed mid-write (`.NAME.partial-PID`,
/// the process gone) are removed by the next run into the same place; one
/// whose process still runs is kept; the output is replaced whole.
#[test]
fn the_next_run_removes_staging_folders_of_killed_runs_only() {
    let work = std::env::temp_dir().join(format!("leafmagic-scene-stale-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&work);
    std::fs::create_dir_all(&work).unwrap();
    let out = work.join("x");
    let mut ended = Command::new("true").spawn().unwrap();
    let dead = ended.id();
    ended.wait().unwrap();
    let mut live = Command::new("sleep").arg("60").spawn().unwrap();
    let stale = work.join(format!(".x.partial-{dead}"));
    let kept = work.join(format!(".x.partial-{}", live.id()));
    for d in [&stale, &kept] {
        std::fs::create_dir_all(d).unwrap();
        std::fs::write(d.join("half.csv"), "t\n").unwrap();
    }
    for _ in 0..2 {
        let r = leafmagic()
            .arg("scene")
            .arg(scene_path("swings"))
            .args(["--seconds", "0.1", "--out"])
            .arg(&out)
            .output()
            .unwrap();
        assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
        assert!(!stale.exists(), "a dead run's staging folder is left");
        assert!(kept.is_dir(), "a live run's staging folder was removed");
        assert!(out.join("summary.toml").is_file());
        // The previous run's folder is replaced whole: nothing of it stays.
        assert!(!out.join("old.csv").exists());
        std::fs::write(out.join("old.csv"), "t\n").unwrap();
    }
    let _ = live.kill();
    let _ = live.wait();
    let mut left: Vec<String> = std::fs::read_dir(&work)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    left.sort();
    assert_eq!(
        left,
        [
            kept.file_name().unwrap().to_string_lossy().into_owned(),
            "x".to_string()
        ]
    );
    let _ = std::fs::remove_dir_all(&work);
}

#[test]
fn the_compiler_keeps_what_each_scene_uses() {
    let kept = |scene: &Scene, term: &str| {
        scene
            .explain()
            .iter()
            .find(|d| d.name == term)
            .unwrap_or_else(|| panic!("no decision on {term}"))
            .kept
    };
    let hover = load("hover");
    assert!(kept(&hover, "wind evaluation"));
    assert!(!kept(&hover, "ground contact") && !kept(&hover, "rigid bodies"));
    assert!(!kept(&hover, "spring breaking") && !kept(&hover, "particle drag"));
    let bin = load("rocking-bin");
    assert!(kept(&bin, "rigid bodies") && kept(&bin, "ground contact"));
    assert!(!kept(&bin, "wind evaluation") && !kept(&bin, "triangle aerodynamics"));
    assert!(!kept(&bin, "springs") && !kept(&bin, "spring breaking"));
    assert!(bin.pruned.iter().any(|p| p.contains("surface triangles")));
    let tear = load("tear");
    assert!(kept(&tear, "spring breaking") && !kept(&tear, "ground contact"));
    let swings = load("swings");
    assert!(kept(&swings, "rigid bodies") && kept(&swings, "particle drag"));
    // A rigid leaf has no internal springs or hinges left, and zero-strength
    // wind is dropped: in still air nothing samples the wind.
    let text = format!(
        "{}rigid = true\n\n[[wind]]\nkind = \"uniform\"\nvelocity = [0.0, 0.0, 0.0]\n",
        MINIMAL
    );
    let s = compile(&text).unwrap();
    assert!(s.model.springs.is_empty() && s.model.hinges.is_empty());
    assert!(s.model.wind.is_still() && !kept(&s, "wind evaluation"));
    assert_eq!(s.pruned.len(), 2, "{:?}", s.pruned);
}

/// Every term switched on, on a scene that gives the extra ones nothing to
/// do, yields bit-identical states: what the compiler leaves out never
/// contributed.
#[test]
fn leaving_terms_out_changes_nothing() {
    for name in ["hover", "rocking-bin", "swings"] {
        let scene = load(name);
        let dt = leafmagic::physics::run::resolve_dt(
            &scene.model,
            scene.integrator,
            scene.dt,
            1.0 / scene.frame_rate,
        )
        .unwrap();
        let mut states: Vec<State> = Vec::new();
        for terms in [Terms::needed(&scene.model), Terms::all()] {
            let mut s = scene.initial.clone();
            let mut sim = Simulator::with_terms(&scene.model, scene.integrator, terms);
            for _ in 0..600 {
                sim.step(&scene.model, &mut s, dt).unwrap();
            }
            states.push(s);
        }
        assert_eq!(states[0], states[1], "{name}: the all-terms run differs");
        assert_ne!(states[0].position, scene.initial.position);
    }
}

/// A run that diverges stops with the simulator's diagnosis.
#[test]
fn a_diverging_scene_stops_with_the_simulators_error() {
    // Forward Euler is unstable on the leaf's lightly damped springs.
    let text = MINIMAL.replace(
        "duration = 1.0",
        "duration = 1.0\ndt = 0.004\nintegrator = \"euler\"",
    );
    let scene = compile(&text).unwrap();
    match scene.run(None) {
        Err(RunError::Sim(SimError::Diverged(d))) => assert!(d.step > 0),
        other => panic!("expected a divergence, got {other:?}"),
    }
}

/// Extreme numbers that pass a "finite and positive" check (found by
/// mutating the shipped scenes' numbers) are refused before any stepping,
/// with the reason, instead of panicking, hanging in the stability
/// estimate, or stepping for ever.
#[test]
fn extreme_numbers_are_refused_before_stepping() {
    let tear = std::fs::read_to_string(scene_path("tear")).unwrap();
    let set = |key: &str, value: &str| {
        let line = tear
            .lines()
            .find(|l| l.starts_with(&format!("{key} =")))
            .unwrap();
        tear.replacen(line, &format!("{key} = {value}"), 1)
    };
    // (scene text, words the error must contain)
    let cases = [
        // Keyframes at time NaN (0 × ∞) once indexed off the end.
        (
            set("frame_rate", "1e-320"),
            ":11: frame_rate: 4 s at 1.000e-320 frames per second is no frame at all",
        ),
        // 1.4e10 frames.
        (
            set("frame_rate", "3.5e9"),
            ":11: frame_rate: 4 s at 3.500e9 frames per second is 1.40e10 frames",
        ),
        // 1e-320 s steps: 4e320 of them.
        (set("dt", "1e-320"), ":13: dt: 4 s at dt = 1.000e-320 s"),
        // A subnormal mass: 1/m overflows; the Schur solver never returned.
        (set("mass", "1e-320"), "1/m must be finite"),
        // k/m overflows.
        (set("stiffness", "1e308"), "k/m, c/m or α/m overflows"),
        // Placed where the simulator would call it run away at step 0.
        (
            set("position", "[0.0, 1e12, 1.5]"),
            "sheet[0].position: starts a particle 1.000e12 m from the origin",
        ),
        // So stiff that dt = auto needs billions of steps.
        (
            set("stiffness", "1e21"),
            ":16: sheet[0]: dt = auto: 4 s at dt =",
        ),
    ];
    for (text, words) in &cases {
        let start = std::time::Instant::now();
        let message = match compile(text) {
            Err(e) => e.to_string(),
            Ok(scene) => match scene.run(None) {
                Err(e) => e.to_string(),
                Ok(_) => panic!("accepted: {text}"),
            },
        };
        assert!(message.contains(words), "{words:?} not in: {message}");
        assert!(
            start.elapsed().as_secs_f64() < 10.0,
            "refused only after {:?}: {message}",
            start.elapsed()
        );
    }
}

fn leafmagic() -> Command {
    Command::new(env!("CARGO_BIN_EXE_leafmagic"))
}

#[test]
fn the_scene_command_writes_the_same_bytes_for_the_same_input() {
    let root = std::env::temp_dir().join(format!("leafmagic-scene-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&root);
    let mut listings = Vec::new();
    for run in ["one", "two"] {
        let out = root.join(run);
        let status = leafmagic()
            .args([
                "scene",
                scene_path("swings").to_str().unwrap(),
                "--seconds",
                "0.5",
                "--out",
            ])
            .arg(&out)
            .output()
            .unwrap();
        assert!(
            status.status.success(),
            "{}",
            String::from_utf8_lossy(&status.stderr)
        );
        let mut files: Vec<_> = std::fs::read_dir(&out)
            .unwrap()
            .map(|e| e.unwrap().path())
            .collect();
        files.sort();
        listings.push(files);
    }
    let names = |files: &Vec<std::path::PathBuf>| -> Vec<String> {
        files
            .iter()
            .map(|f| f.file_name().unwrap().to_string_lossy().into_owned())
            .collect()
    };
    assert_eq!(names(&listings[0]), names(&listings[1]));
    for (a, b) in listings[0].iter().zip(&listings[1]) {
        assert_eq!(
            std::fs::read(a).unwrap(),
            std::fs::read(b).unwrap(),
            "{a:?} differs"
        );
    }
    let names = names(&listings[0]);
    for expected in ["summary.toml", "seat-1.csv", "rope-1lf-particles.csv"] {
        assert!(
            names.contains(&expected.to_string()),
            "{expected} missing: {names:?}"
        );
    }
    assert!(
        !names.iter().any(|n| n.starts_with("beam")),
        "fixed points need no file"
    );
    let dir = root.join("one");
    let pose = std::fs::read_to_string(dir.join("seat-1.csv")).unwrap();
    assert!(pose.starts_with("t,x,y,z,qw,qx,qy,qz\n"));
    assert_eq!(pose.lines().count(), 1 + 31, "0.5 s at 60 fps is 31 frames");
    let traj =
        leafmagic::motion::trajectory::Trajectory::read_csv(&dir.join("seat-1.csv")).unwrap();
    assert_eq!(traj.len(), 31);
    let rope = std::fs::read_to_string(dir.join("rope-1lf-particles.csv")).unwrap();
    assert!(rope.starts_with("t,x0,y0,z0,"), "{}", &rope[..40]);
    let summary: toml::Table =
        toml::from_str(&std::fs::read_to_string(dir.join("summary.toml")).unwrap()).unwrap();
    assert_eq!(summary["scene"].as_str(), Some("swings"));
    assert_eq!(summary["frames"].as_integer(), Some(31));
    let _ = std::fs::remove_dir_all(&root);
}

#[test]
fn the_scene_command_reports_bad_files_and_fails() {
    let dir = std::env::temp_dir().join(format!("leafmagic-bad-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("bad.toml");
    std::fs::write(&file, format!("{MINIMAL}speed = 3\n")).unwrap();
    let out = leafmagic()
        .args(["scene", file.to_str().unwrap(), "--explain"])
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    let line = line_of(&format!("{MINIMAL}speed = 3\n"), "speed");
    assert!(
        err.contains(&format!(
            "bad.toml:{line}: leaf[0].speed: unknown field `speed`"
        )),
        "{err}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// Copies are placed by the seed: the same seed gives the same layout, another
/// seed another one, and every copy stays within its spread.
#[test]
fn seeded_copies_are_reproducible_and_within_their_spread() {
    let text = MINIMAL.replace(
        "position = [0.0, 0.0, 1.0]",
        "position = [0.0, 0.0, 1.0]\ncount = 5\nspread = [0.5, 0.2, 0.1]\ntilt_deg = 20.0\nrandom_yaw = true",
    );
    let a = compile(&text).unwrap();
    let b = compile(&text).unwrap();
    let c = compile(&text.replace("duration = 1.0", "duration = 1.0\nseed = 9")).unwrap();
    assert_eq!(a.initial, b.initial);
    assert_ne!(a.initial.position, c.initial.position);
    assert_eq!(a.objects.len(), 5);
    assert_eq!(a.objects[3].name, "l-003");
    for o in &a.objects {
        let n = o.particles.len() as f64;
        let centre: V3 = o
            .particles
            .iter()
            .map(|&i| a.model.rest_position[i])
            .sum::<V3>()
            / n;
        // The mass centre sits within the spread; the plain centroid is close to it.
        assert!(
            centre.x.abs() < 0.5 + 0.02 && centre.y.abs() < 0.2 + 0.02,
            "{centre:?}"
        );
        assert!((centre.z - 1.0).abs() < 0.1 + 0.02, "{centre:?}");
    }
}

/// Every file of a directory by name.
fn files_of(dir: &Path) -> std::collections::BTreeMap<String, Vec<u8>> {
    std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap())
        .map(|e| {
            (
                e.file_name().to_string_lossy().into_owned(),
                std::fs::read(e.path()).unwrap(),
            )
        })
        .collect()
}

/// Runs `scene FILE --out DIR ARGS` under a file size limit of `blocks`
/// (ulimit -f, SIGXFSZ ignored so a write past it fails with EFBIG, as on a
/// full disk).
fn scene_with_file_limit(
    file: &Path,
    dir: &Path,
    args: &[&str],
    blocks: u32,
) -> std::process::Output {
    Command::new("sh")
        .arg("-c")
        .arg(format!(
            "trap '' XFSZ; ulimit -f {blocks}; bin=\"$0\" file=\"$1\" out=\"$2\"; shift 2; \
             exec \"$bin\" scene \"$file\" --out \"$out\" \"$@\""
        ))
        .arg(env!("CARGO_BIN_EXE_leafmagic"))
        .arg(file)
        .arg(dir)
        .args(args)
        .output()
        .unwrap()
}

/// A scene's output directory is written as a whole: a write that fails (a
/// full disk, simulated by a file size limit) names the file and leaves the
/// previous output exactly as it was, or no directory at all on a first
/// run; a re-run replaces the old files instead of writing beside them; a
/// file or a foreign directory as --out is refused and left alone.
#[test]
fn scene_output_directories_are_replaced_whole_or_left_as_they_were() {
    let work = std::env::temp_dir().join(format!("leafmagic-scene-out-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&work);
    std::fs::create_dir_all(&work).unwrap();
    let file = scene_path("swings");
    let out = work.join("swings");
    let first = leafmagic()
        .arg("scene")
        .arg(&file)
        .args(["--seconds", "0.5", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    assert!(
        first.status.success(),
        "{}",
        String::from_utf8_lossy(&first.stderr)
    );
    let before = files_of(&out);
    assert!(before.contains_key("summary.toml"), "{:?}", before.keys());
    // A stale file of an older run goes when the directory is replaced.
    std::fs::write(out.join("stale.csv"), "t\n").unwrap();
    let before = files_of(&out);

    // "Full disk": the particle CSVs of 2 s (about 58 kB each) pass 40 blocks.
    let failed = scene_with_file_limit(&file, &out, &["--seconds", "2"], 40);
    let stderr = String::from_utf8_lossy(&failed.stderr);
    assert!(!failed.status.success());
    assert!(
        stderr.contains(&format!("{}/", out.display()))
            && stderr.contains(".csv")
            && stderr.contains("nothing was changed"),
        "the error does not name the file: {stderr}"
    );
    assert_eq!(
        files_of(&out),
        before,
        "a failed run changed the previous output"
    );
    let siblings: Vec<_> = std::fs::read_dir(&work)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(
        siblings,
        vec!["swings".to_string()],
        "temporaries left: {siblings:?}"
    );

    // A first run that fails leaves nothing (no lone CSV).
    let fresh = work.join("fresh");
    let failed = scene_with_file_limit(&file, &fresh, &["--seconds", "2"], 40);
    assert!(!failed.status.success());
    assert!(!fresh.exists());

    // A re-run that succeeds replaces the directory: the stale file is gone.
    let again = leafmagic()
        .arg("scene")
        .arg(&file)
        .args(["--seconds", "0.5", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    assert!(again.status.success());
    let after = files_of(&out);
    assert!(!after.contains_key("stale.csv"), "{:?}", after.keys());

    // --out naming a file, or a directory that is not a scene's output.
    let plain = work.join("plain");
    std::fs::write(&plain, "keep").unwrap();
    let foreign = work.join("foreign");
    std::fs::create_dir_all(&foreign).unwrap();
    std::fs::write(foreign.join("notes.txt"), "keep").unwrap();
    for (target, says) in [(&plain, "is a file"), (&foreign, "not a scene's output")] {
        let r = leafmagic()
            .arg("scene")
            .arg(&file)
            .args(["--seconds", "0.1", "--out"])
            .arg(target)
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&r.stderr);
        assert!(!r.status.success() && stderr.contains(says), "{stderr}");
    }
    assert_eq!(std::fs::read_to_string(&plain).unwrap(), "keep");
    assert_eq!(
        std::fs::read_to_string(foreign.join("notes.txt")).unwrap(),
        "keep"
    );
    let _ = std::fs::remove_dir_all(&work);
}

/// `scene --explain` says what sets the step: the leaves' stiffest mode for
/// the shockwave as shipped (linear law), and for the same scene with
/// unsteady-law leaves the air's rate at the wind's speed bound, whose
/// value it prints (the step is then shorter than the springs' limit).
#[test]
fn scene_explain_names_what_sets_the_step() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let shipped = root.join("scenes/shockwave.toml");
    let explain = |file: &Path, json: bool| {
        let mut cmd = leafmagic();
        cmd.args(["scene", file.to_str().unwrap(), "--explain"]);
        if json {
            cmd.arg("--json");
        }
        let out = cmd.output().unwrap();
        crate::common::assert_succeeded(&out);
        String::from_utf8(out.stdout).unwrap()
    };
    let step_line = |text: &str| {
        text.lines()
            .find(|l| l.starts_with("step "))
            .unwrap_or_else(|| panic!("no step line in\n{text}"))
            .to_string()
    };
    let linear = step_line(&explain(&shipped, false));
    assert!(linear.contains("set by the stiffest mode"), "{linear}");
    assert!(!linear.contains("wind's bound"), "{linear}");

    let dir = std::env::temp_dir().join(format!("leafmagic-explain-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let leaf = crate::common::with_aero(
        &std::fs::read_to_string(root.join("prototypes/leaf-a.toml")).unwrap(),
        "law = \"unsteady\"",
    );
    std::fs::write(dir.join("a-unsteady.toml"), leaf).unwrap();
    let text = std::fs::read_to_string(&shipped)
        .unwrap()
        .replace("leaf = \"a\"", "leaf = \"a-unsteady.toml\"");
    let scene = dir.join("shockwave-unsteady.toml");
    std::fs::write(&scene, text).unwrap();
    let unsteady = step_line(&explain(&scene, false));
    assert!(unsteady.contains("set by the drag rate"), "{unsteady}");
    let wind = Scene::load(&scene).unwrap().model.wind.speed_bound();
    assert!(
        unsteady.contains(&format!("the wind's bound, {wind:.2} m/s")),
        "{unsteady}"
    );
    let json: serde_json::Value = serde_json::from_str(&explain(&scene, true)).unwrap();
    assert_eq!(
        json["dt_reason"].as_str(),
        Some(unsteady.trim_start_matches("step").trim())
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// A leaf launched past the runaway speed is refused at its `velocity`,
/// with its line, not stopped as diverging at step 0.
#[test]
fn a_launch_past_the_runaway_speed_is_refused_by_its_field() {
    let text = MINIMAL.replace(
        "position = [0.0, 0.0, 1.0]",
        "position = [0.0, 0.0, 1.0]\nvelocity = [2e4, 0.0, 0.0]",
    );
    let e = error(&text);
    assert_eq!(e.line, Some(line_of(&text, "velocity")), "{e}");
    let text = e.to_string();
    assert!(
        text.contains("leaf[0].velocity: starts a particle 2.000e4 m/s fast"),
        "{text}"
    );
}

/// A leaf file that is one rigid body, as every plate `leafmagic plate`
/// writes (no springs), stays one in a scene: its `[[leaf]]` copies were
/// once compiled as loose particles, and the first breath of wind tore
/// them apart (3 disks in the shockwave diverged at 0.14 s). Each copy is
/// a rigid body, its particles keep their distances through a second of
/// fall, and the scene's own `rigid = false` still overrides the file.
#[test]
fn a_rigid_leaf_file_stays_rigid_in_a_scene() {
    use leafmagic::leaf::plates::{PlateShape, plate};
    use leafmagic::leaf::spec::{AeroLawName, AeroSpec};
    let dir = std::env::temp_dir().join(format!("leafmagic-rigid-leaf-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let disk = plate(
        PlateShape::Circle,
        0.05,
        1.0,
        0.07,
        AeroSpec::named(AeroLawName::Unsteady),
    )
    .unwrap();
    assert!(disk.rigid && disk.springs.is_empty());
    std::fs::write(dir.join("disk.toml"), disk.to_toml()).unwrap();
    let text = MINIMAL.replace(
        "leaf = \"a\"",
        "leaf = \"disk.toml\"\ncount = 3\nspread = [0.5, 0.5, 0.0]\ntilt_deg = 30.0",
    ) + "\n[[wind]]\nkind = \"uniform\"\nvelocity = [0.3, 0.0, 0.6]\n";
    let compile_in = |text: &str| Scene::from_toml(text, "test.toml", &dir).unwrap();
    let scene = compile_in(&text);
    assert_eq!(scene.model.rigid.len(), 3);
    assert!(scene.objects.iter().all(|o| o.rigid_body.is_some()));
    let run = scene.run(None).unwrap();
    let x0 = &scene.model.rest_position;
    let x1 = &run.final_state.position;
    for o in &scene.objects {
        let (a, b) = (o.particles[0], o.particles[o.particles.len() / 2]);
        let (rest, now) = ((x0[a] - x0[b]).norm(), (x1[a] - x1[b]).norm());
        assert!(
            (now - rest).abs() < 1e-9 * rest,
            "{}: {rest} → {now}",
            o.name
        );
        assert!(x1[a].z < x0[a].z, "{} did not fall", o.name);
    }
    let loose = compile_in(&text.replace("count = 3", "count = 3\nrigid = false"));
    assert!(loose.model.rigid.is_empty());
    let _ = std::fs::remove_dir_all(&dir);
}
