//! Motion design from an example (`breed --like`, `--target-features`,
//! `compare`): a round trip toward a fall that prototype A's copies do not
//! make, falls from another engine as targets, and bad input refused before
//! anything is bred.

use crate::breeding::{
    breed, breed_on_one_and_two_threads, kill_then_resume, leafmagic, same_files, scratch,
};
use std::path::{Path, PathBuf};

fn fixture(name: &str) -> String {
    format!("{}/tests/fixtures/{name}", env!("CARGO_MANIFEST_DIR"))
}

fn mujoco(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("tests/data/mujoco-falls/{name}"))
}

/// (generation, best class counts row, best_distance) from generations.csv.
fn best_distances(run: &Path) -> Vec<Option<f64>> {
    let text = std::fs::read_to_string(run.join("generations.csv")).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let k = header.iter().position(|h| *h == "best_distance").unwrap();
    lines
        .map(|l| l.split(',').nth(k).unwrap().parse().ok())
        .collect()
}

/// The class of the best member of the last generation (gen-NNN.csv).
fn best_class(run: &Path) -> (String, f64) {
    let text = std::fs::read_to_string(run.join("best/index.csv")).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let row: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |name: &str| row[header.iter().position(|h| *h == name).unwrap()];
    (col("class").to_string(), col("score").parse().unwrap())
}

fn drop_to(leaf: &str, csv: &Path) {
    let out = leafmagic()
        .args(["drop", leaf, "--out"])
        .arg(csv)
        .output()
        .unwrap();
    crate::common::assert_succeeded(&out);
}

/// The round trip of the issue: the tumbling variant of A (a fixture whose
/// fall none of generation 0's 60 copies of A matches: their best is 1.34
/// reference spreads away) is recorded, and breeding from A toward that
/// recording brings the best distance down by at least half, in the
/// example's class.
#[test]
fn breeding_like_a_tumbler_halves_the_distance_and_keeps_its_class() {
    let dir = scratch("like-tumbler");
    let example = dir.join("tumbler.csv");
    drop_to(&fixture("a-tumbler.toml"), &example);
    let run = dir.join("run");
    let args = [
        "--like",
        example.to_str().unwrap(),
        "--population",
        "60",
        "--generations",
        "12",
        // One drop per leaf from prototype A, the default strategy: what
        // the search reaches on the fall it was selected on (robust fitness,
        // the default 4 releases, is a harder aim: docs/design/breeding.md).
        "--prototype",
        "a",
        "--releases",
        "1",
    ];
    let out = breed(&args, &run);
    crate::common::assert_succeeded(&out);
    let d = best_distances(&run);
    let (first, last) = (d[0].expect("gen 0 has spinners"), d[d.len() - 1].unwrap());
    assert!(
        last <= 0.5 * first,
        "best distance {first:.4} in generation 0, {last:.4} in generation {}: not halved",
        d.len() - 1
    );
    let (class, _) = best_class(&run);
    assert_eq!(class, "spinner", "the example tumbles: a spinner");
    // What it aimed at is recorded; the overlay plot and the example are there.
    let toml = std::fs::read_to_string(run.join("run.toml")).unwrap();
    assert!(
        toml.contains("[settings.like]") && toml.contains("tumble"),
        "{toml}"
    );
    for f in ["like.svg", "example.csv"] {
        assert!(run.join(f).exists(), "{f} missing");
    }
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        stdout.contains("best dist.") && stdout.contains("example"),
        "{stdout}"
    );
}

/// Falls from another engine as targets: breeding from A reaches the
/// example's class (a floater and a tumbling card), and reports how far the
/// best still is.
#[test]
fn falls_from_another_engine_are_reached_in_class() {
    let dir = scratch("like-mujoco");
    for (file, class) in [
        ("steady_fall.csv", "floater"),
        ("tumble_thick.csv", "spinner"),
    ] {
        let run = dir.join(file);
        let path = mujoco(file);
        let args = [
            "--like",
            path.to_str().unwrap(),
            "--size",
            "0.04",
            "--population",
            "30",
            "--generations",
            "4",
            "--seconds",
            "6",
        ];
        let out = breed(&args, &run);
        crate::common::assert_succeeded(&out);
        let (best, score) = best_class(&run);
        assert_eq!(best, class, "{file}");
        assert!(
            score > 1.0,
            "{file}: the best passes the class gate (score {score})"
        );
        let d = best_distances(&run);
        assert!(
            d.last().unwrap().is_some_and(f64::is_finite),
            "{file}: {d:?}"
        );
    }
}

/// `--target-features` in SI units: the gate is --target, the distance
/// counts only what is set, and the same seed gives the same bytes with 1
/// and 2 threads.
#[test]
fn target_features_are_reproducible() {
    let dir = scratch("features");
    let args = [
        "--target",
        "spinner",
        "--target-features",
        "descent=2.0,spin=25",
        "--population",
        "12",
        "--generations",
        "2",
        "--seconds",
        "4",
    ];
    let ca = breed_on_one_and_two_threads(&args, &dir);
    let toml = String::from_utf8_lossy(&ca["run.toml"]).into_owned();
    assert!(
        toml.contains("source = \"features\"") && toml.contains("spin = 25"),
        "{toml}"
    );
}

/// Bad input: a fall too short to describe stops with the classifier's
/// reason, and unknown descriptor names are listed, before any run
/// directory is made.
#[test]
fn bad_targets_stop_before_breeding() {
    let dir = scratch("like-bad");
    let full = dir.join("full.csv");
    drop_to("a", &full);
    // The first 0.5 s only: all start-up transient.
    let text = std::fs::read_to_string(&full).unwrap();
    let short: String = text.lines().take(121).map(|l| format!("{l}\n")).collect();
    let short_path = dir.join("short.csv");
    std::fs::write(&short_path, short).unwrap();
    // A refused breed: its stderr, once it has checked that it failed and
    // wrote nothing.
    let refused = |args: &[&str], name: &str| -> String {
        let run = dir.join(name);
        let out = breed(args, &run);
        assert!(!out.status.success(), "{args:?} must be refused");
        assert!(!run.exists(), "{args:?}: nothing may be written");
        String::from_utf8_lossy(&out.stderr).into_owned()
    };
    let err = refused(&["--like", short_path.to_str().unwrap()], "run-short");
    assert!(
        err.contains("short.csv") && err.contains("undetermined"),
        "{err}"
    );
    let err = refused(
        &["--target-features", "descent=1,speed=2,wobble=3"],
        "run-names",
    );
    assert!(err.contains("speed") && err.contains("wobble"), "{err}");
}

/// `compare`: a fall is at distance 0 from itself, and falls of different
/// classes are never close (null distance in JSON).
#[test]
fn compare_prints_both_vectors_and_gates_by_class() {
    let dir = scratch("compare");
    let (a, b) = (dir.join("a.csv"), dir.join("spinner.csv"));
    drop_to("a", &a);
    drop_to(&fixture("a-spinner.toml"), &b);
    let json = |x: &Path, y: &Path| -> serde_json::Value {
        let out = leafmagic()
            .arg("compare")
            .args([x, y])
            .arg("--json")
            .output()
            .unwrap();
        crate::common::assert_succeeded(&out);
        serde_json::from_slice(&out.stdout).unwrap()
    };
    let same = json(&a, &a);
    assert_eq!(same["distance"], 0.0);
    assert_eq!(same["a"]["descriptors"], same["b"]["descriptors"]);
    let diff = json(&a, &b);
    assert_eq!(diff["same_class"], false);
    assert!(diff["distance"].is_null());
    assert_eq!(diff["b"]["descriptors"]["class"], "spinner");
    assert!(diff["b"]["descriptors"]["spin"].as_f64().unwrap() > 5.0);
}

/// `describe`: one fall's descriptors are exactly what `compare` puts in
/// its column, and the record decides which are measured: all ten from a
/// pose record, descent, drift and (from the projected areas) tumble from
/// a real square filmed without orientation, descent and drift from its
/// positions alone. An undetermined record is an answer, not an error; a
/// file without `t` is an error that names it.
#[test]
fn describe_says_what_the_record_measures_as_compare_uses_it() {
    let dir = scratch("describe");
    let square =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/real-falls/squares/square_000.csv");
    // The same fall without its area columns.
    let text = std::fs::read_to_string(&square).unwrap();
    let positions = dir.join("positions.csv");
    let cut: Vec<String> = text
        .lines()
        .map(|l| l.split(',').take(4).collect::<Vec<_>>().join(","))
        .collect();
    std::fs::write(&positions, cut.join("\n") + "\n").unwrap();
    let short = dir.join("short.csv");
    std::fs::write(&short, cut[..4].join("\n") + "\n").unwrap();
    let run = |args: &[&std::ffi::OsStr]| -> (bool, serde_json::Value, String) {
        let out = leafmagic().args(args).output().unwrap();
        let json = serde_json::from_slice(&out.stdout).unwrap_or(serde_json::Value::Null);
        (
            out.status.success(),
            json,
            String::from_utf8_lossy(&out.stderr).into_owned(),
        )
    };
    let describe = |file: &Path| {
        let (ok, v, err) = run(&[
            "describe".as_ref(),
            file.as_os_str(),
            "--size".as_ref(),
            "0.042".as_ref(),
            "--json".as_ref(),
        ]);
        assert!(ok, "{}: {err}", file.display());
        v
    };
    let measured = |v: &serde_json::Value| -> Vec<String> {
        let mut names: Vec<String> = v["descriptors"]
            .as_object()
            .unwrap()
            .keys()
            .filter(|k| *k != "class" && *k != "regime")
            .cloned()
            .collect();
        names.sort();
        names
    };
    let tumble_thick = mujoco("tumble_thick.csv");
    for (file, inputs, names) in [
        (
            square.as_path(),
            "areas",
            vec!["descent", "drift", "tumble"],
        ),
        (positions.as_path(), "path", vec!["descent", "drift"]),
        (
            tumble_thick.as_path(),
            "orientation",
            vec![
                "descent",
                "descent_cv",
                "drift",
                "flips",
                "period",
                "reversals",
                "spin",
                "tilt",
                "tilt_std",
                "tumble",
            ],
        ),
    ] {
        let v = describe(file);
        assert_eq!(v["inputs"], inputs, "{}", file.display());
        assert_eq!(measured(&v), names, "{}", file.display());
        assert_eq!(
            v["not_measured"].as_array().unwrap().len(),
            10 - names.len()
        );
        // Exactly compare's column for the same file.
        let (ok, c, err) = run(&[
            "compare".as_ref(),
            file.as_os_str(),
            file.as_os_str(),
            "--size".as_ref(),
            "0.042".as_ref(),
            "--json".as_ref(),
        ]);
        assert!(ok, "{err}");
        assert_eq!(v["descriptors"], c["a"]["descriptors"]);
    }
    // Without areas, the turn rate is missing for want of areas or attitude.
    let v = describe(&positions);
    let tumble = v["not_measured"]
        .as_array()
        .unwrap()
        .iter()
        .find(|m| m["name"] == "tumble")
        .unwrap();
    assert!(tumble["reason"].as_str().unwrap().contains("areas"));
    // Too short: undetermined with its reason, no descriptors, exit 0.
    let v = describe(&short);
    assert_eq!(v["class"], "undetermined");
    assert!(v["descriptors"].is_null());
    assert!(v["reason"].as_str().unwrap().contains("too short"));
    // A file that is not a fall.
    let labels = square.with_file_name("labels.csv");
    let (ok, _, err) = run(&["describe".as_ref(), labels.as_os_str()]);
    assert!(!ok);
    assert!(
        err.contains("labels.csv") && err.contains("no column `t`"),
        "{err}"
    );
}

/// The hybrid's Levenberg–Marquardt steps (breed::least_squares) on a real
/// population: after three generations toward the spinner fixture's fall,
/// the steps fitted to the evaluated members, each dropped from the best
/// member's own release attitude, come closer to the example than that
/// best member.
#[test]
fn model_steps_from_a_real_population_come_closer_than_its_best() {
    use leafmagic::breed::{Checkpoint, evaluate, least_squares, strategy};
    use leafmagic::leaf::LeafSpec;
    use leafmagic::leaf::genome::Genome;
    let dir = scratch("like-steps");
    let example = dir.join("spinner.csv");
    drop_to(&fixture("a-spinner.toml"), &example);
    let run = dir.join("run");
    let args = [
        "--like",
        example.to_str().unwrap(),
        "--population",
        "24",
        "--generations",
        "3",
        "--releases",
        "1",
    ];
    let out = breed(&args, &run);
    crate::common::assert_succeeded(&out);
    let cp: Checkpoint =
        serde_json::from_str(&std::fs::read_to_string(run.join("checkpoint.json")).unwrap())
            .unwrap();
    let proto = LeafSpec::load("a").unwrap();
    let bounds = strategy::search_bounds(&cp.settings, &proto);
    let (best, children) =
        least_squares::steps(&cp.population, &bounds, &Genome::of_prototype(&proto));
    let best = best.expect("members inside the gate");
    assert_eq!(children.len(), least_squares::STEPS);
    let before = best.eval.distance.unwrap();
    let after: Vec<f64> = children
        .iter()
        .map(|g| {
            evaluate(&proto, best.id, g, &cp.settings)
                .distance
                .unwrap_or(f64::INFINITY)
        })
        .collect();
    let closest = after.iter().copied().fold(f64::INFINITY, f64::min);
    assert!(
        closest < before,
        "best member {before:.5}; its steps {after:?}"
    );
}

/// A run toward an example, where the hybrid breeds Levenberg–Marquardt
/// steps from the stored residuals, is the same bytes with 1 and 2 threads
/// and after SIGKILL and --resume.
#[test]
fn a_like_run_with_model_steps_is_reproducible() {
    let dir = scratch("like-steps-bytes");
    let example = dir.join("floater.csv");
    drop_to(&fixture("a-floater.toml"), &example);
    let args = [
        "--like",
        example.to_str().unwrap(),
        "--population",
        "16",
        "--generations",
        "6",
        "--seconds",
        "6",
        "--releases",
        "1",
    ];
    let a = breed_on_one_and_two_threads(&args, &dir);
    // The run is one the steps take part in: residuals are stored, and the
    // generation after its last would breed them.
    let cp: leafmagic::breed::Checkpoint = serde_json::from_slice(&a["checkpoint.json"]).unwrap();
    assert!(cp.population.iter().any(|i| !i.eval.residuals.is_empty()));
    let proto = leafmagic::leaf::LeafSpec::load("a").unwrap();
    let plan = leafmagic::breed::selection::plan(&cp.settings, &proto, Some(&cp));
    assert_eq!(plan.model_children, leafmagic::breed::least_squares::STEPS);

    let killed = dir.join("killed");
    kill_then_resume(
        &[&args[..], &["--threads", "2"]].concat(),
        &killed,
        "gen-002.csv",
        5,
    );
    same_files(&dir.join("one"), &killed, "after kill and resume");
}
