//! What a newcomer met on a fresh clone (issue 59): a target that cannot
//! be bred listed and then refused, a scene folder given to `export`, a
//! leaf and a scene file swapped, `accuracy` writing into the current
//! folder. Each now says what to do, or does the expected thing.

use super::breeding::{leafmagic, scratch};
use std::path::PathBuf;

fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Runs the binary in the repository; (success, stderr).
fn run(args: &[&str]) -> (bool, String) {
    let out = leafmagic().current_dir(repo()).args(args).output().unwrap();
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn undetermined_is_no_target() {
    for command in [["breed", "--target"], ["studio", "--target"]] {
        let (ok, err) = run(&[command[0], command[1], "undetermined"]);
        assert!(!ok, "{command:?}");
        assert!(err.contains("expected floater, spinner or lilter"), "{err}");
    }
}

#[test]
fn export_of_a_scene_folder_says_how_scenes_export() {
    let dir = scratch("newcomer-scene-out");
    std::fs::write(dir.join("summary.toml"), "scene = \"x\"\n").unwrap();
    let (ok, err) = run(&[
        "export",
        dir.to_str().unwrap(),
        "--top",
        "1",
        "--out",
        "/nonexistent/x",
    ]);
    assert!(!ok);
    assert!(
        err.contains("a scene's output") && err.contains("leafmagic scene SCENE.toml --export"),
        "{err}"
    );
    assert!(!err.contains("start it again"), "{err}");
}

#[test]
fn a_leaf_and_a_scene_file_swapped_are_named() {
    let (ok, err) = run(&["scene", "prototypes/leaf-a.toml", "--out", "/nonexistent/x"]);
    assert!(!ok);
    assert!(
        err.contains("is a leaf file") && err.contains("leafmagic drop prototypes/leaf-a.toml"),
        "{err}"
    );
    let (ok, err) = run(&["drop", "scenes/inhale.toml"]);
    assert!(!ok);
    assert!(
        err.contains("is a scene file") && err.contains("leafmagic scene scenes/inhale.toml"),
        "{err}"
    );
    // A leaf file that is only wrong is not called a scene.
    let dir = scratch("newcomer-bad-leaf");
    let bad = dir.join("bad-leaf.toml");
    let leaf = std::fs::read_to_string(repo().join("prototypes/leaf-a.toml")).unwrap();
    std::fs::write(&bad, leaf.replacen("alpha_n = 0.47", "alpha_n = \"x\"", 1)).unwrap();
    let (ok, err) = run(&["drop", bad.to_str().unwrap()]);
    assert!(!ok);
    assert!(err.contains("alpha_n") && !err.contains("hint:"), "{err}");
}

#[test]
fn accuracy_writes_under_runs_not_into_the_current_folder() {
    let dir = scratch("newcomer-accuracy");
    let out = leafmagic()
        .current_dir(&dir)
        .args([
            "accuracy",
            "a",
            "--seconds",
            "0.05",
            "--runs",
            "1",
            "--integrators",
            "rk4",
        ])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(dir.join("runs/accuracy/accuracy.csv").is_file());
    assert!(!dir.join("accuracy.csv").exists());
}

/// `studio` run again in the same folder reopens its session where it was
/// (the default folder is named by prototype and seed), and refuses, naming
/// both ways on, when asked for other settings.
#[test]
fn studio_run_again_reopens_its_session() {
    use std::io::{BufRead, BufReader};
    use std::process::Stdio;
    let dir = scratch("newcomer-studio-again");
    // Starts `studio ARGS` in `dir`; (its stderr, whether it printed its
    // address), stopped once it has.
    let start = |extra: &[&str]| -> (String, bool) {
        let mut child = leafmagic()
            .current_dir(&dir)
            .args(["studio", "--port", "0", "--grid", "4", "--seconds", "2"])
            .args(extra)
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        let stdout = BufReader::new(child.stdout.take().unwrap());
        let served = stdout
            .lines()
            .map_while(Result::ok)
            .any(|l| l.starts_with("studio: http://127.0.0.1:"));
        let _ = child.kill();
        let out = child.wait_with_output().unwrap();
        (String::from_utf8_lossy(&out.stderr).into_owned(), served)
    };
    let (err, served) = start(&[]);
    assert!(served, "{err}");
    assert!(err.contains("breeding generation 0"), "{err}");
    let (err, served) = start(&[]);
    assert!(served, "{err}");
    assert!(
        err.contains("reopening runs/studio-a-s1991 where it was"),
        "{err}"
    );
    let (err, served) = start(&["--target", "spinner"]);
    assert!(!served);
    assert!(
        err.contains("holds a session with other settings")
            && err.contains("--resume runs/studio-a-s1991")
            && err.contains("--out DIR"),
        "{err}"
    );
}
