//! `classify --expect` and `--junit`: checking classifications in a
//! pipeline's tests. A scene of prototype drops exported as an Alembic
//! cache (as a Blender pipeline receives it) is checked against a set of
//! classes that holds and one that does not; the oracle is `classify --all
//! --json`'s own classes, and the JUnit report is read back by Python's
//! XML parser, an independent reader.

use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

const CLASSES: [&str; 4] = ["floater", "spinner", "lilter", "undetermined"];

/// Two leaves of each prototype dropped in still air, tilted: the two
/// prototypes fall differently, so the file holds more than one class.
const SCENE: &str = r#"
name = "drops"
description = "Prototype leaves dropped in still air"
duration = 3.0
frame_rate = 60
integrator = "verlet"
dt = "auto"
seed = 3

[[leaf]]
name = "a"
leaf = "a"
count = 2
position = [0.0, 0.0, 3.0]
spread = [1.0, 1.0, 0.0]
tilt_deg = 20.0
random_yaw = true

[[leaf]]
name = "b"
leaf = "b"
count = 2
position = [3.0, 0.0, 3.0]
spread = [1.0, 1.0, 0.0]
tilt_deg = 20.0
random_yaw = true
"#;

fn leafmagic() -> Command {
    Command::new(env!("CARGO_BIN_EXE_leafmagic"))
}

fn scratch(name: &str) -> PathBuf {
    super::common::scratch("expect", name)
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

/// The scene run and exported as `drops.abc` into `dir`.
fn exported_cache(dir: &Path) -> PathBuf {
    let scene = dir.join("drops.toml");
    std::fs::write(&scene, SCENE).unwrap();
    let out = dir.join("run");
    let o = leafmagic()
        .arg("scene")
        .arg(&scene)
        .args(["--export", "abc", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", text(&o.stderr));
    out.join("drops.abc")
}

/// `classify FILE --all --expect CLASSES [--junit XML]`.
fn check_all(file: &Path, classes: &[&str], junit: Option<&Path>) -> Output {
    let mut cmd = leafmagic();
    cmd.arg("classify")
        .arg(file)
        .args(["--all", "--expect", &classes.join(",")]);
    if let Some(xml) = junit {
        cmd.arg("--junit").arg(xml);
    }
    cmd.output().unwrap()
}

/// The testcases of a JUnit report as Python's ElementTree reads them:
/// (name, failure message or None) each, and the suites' declared counts.
fn junit_cases(xml: &Path) -> Option<Value> {
    let script = r#"
import json, sys
import xml.etree.ElementTree as ET
root = ET.parse(sys.argv[1]).getroot()
cases = []
for case in root.iter("testcase"):
    failure = case.find("failure")
    cases.append({"name": case.get("name"),
                  "failure": None if failure is None else failure.get("message")})
print(json.dumps({"tests": int(root.get("tests")), "failures": int(root.get("failures")),
                  "cases": cases}))
"#;
    let o = match Command::new("python3")
        .arg("-c")
        .arg(script)
        .arg(xml)
        .output()
    {
        Ok(o) => o,
        Err(e) => {
            crate::common::missing_tool(
                "a_cache_s_falls_are_checked_against_the_expected_classes",
                &format!("python3 (to read the JUnit report back) is not available: {e}"),
            );
            return None;
        }
    };
    assert!(o.status.success(), "{}", text(&o.stderr));
    Some(serde_json::from_slice(&o.stdout).unwrap())
}

/// A cache whose falls all have an expected class passes (exit 0, every
/// fall a passing testcase); expecting every class but the first fall's
/// fails (exit non-zero), naming each fall of that class with its class
/// and the expected set on stderr and in the report, and no other fall.
#[test]
fn a_cache_s_falls_are_checked_against_the_expected_classes() {
    let dir = scratch("cache");
    let cache = exported_cache(&dir);
    // The oracle: each fall's class as `classify --all --json` gives it.
    let o = leafmagic()
        .arg("classify")
        .arg(&cache)
        .args(["--all", "--json"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", text(&o.stderr));
    let v: Value = serde_json::from_slice(&o.stdout).unwrap();
    let falls: Vec<(String, String)> = v["objects"]
        .as_array()
        .unwrap()
        .iter()
        .map(|o| {
            (
                o["object"].as_str().unwrap().to_string(),
                o["class"].as_str().unwrap().to_string(),
            )
        })
        .collect();
    assert_eq!(falls.len(), 4, "{v}");
    let mut seen: Vec<&str> = falls.iter().map(|(_, c)| c.as_str()).collect();
    seen.sort_unstable();
    seen.dedup();
    assert!(seen.len() > 1, "the scene's falls are all {seen:?}");

    // Every class that occurs, expected: a pass.
    let xml = dir.join("right.xml");
    let o = check_all(&cache, &seen, Some(&xml));
    assert!(o.status.success(), "{}", text(&o.stderr));
    let out = text(&o.stdout);
    assert!(
        out.contains(&format!("as expected     {0} of {0} falls", falls.len())),
        "{out}"
    );
    assert!(!out.contains("not expected"), "{out}");
    if let Some(report) = junit_cases(&xml) {
        assert_eq!(report["tests"], falls.len(), "{report}");
        assert_eq!(report["failures"], 0, "{report}");
        let cases = report["cases"].as_array().unwrap();
        let names: Vec<&str> = cases.iter().map(|c| c["name"].as_str().unwrap()).collect();
        let want: Vec<&str> = falls.iter().map(|(n, _)| n.as_str()).collect();
        assert_eq!(names, want);
        assert!(cases.iter().all(|c| c["failure"].is_null()), "{report}");
    }

    // Every class but the first fall's: each fall of that class fails.
    let odd = falls[0].1.as_str();
    let expected: Vec<&str> = CLASSES.into_iter().filter(|&c| c != odd).collect();
    let wrong: Vec<&(String, String)> = falls.iter().filter(|(_, c)| c == odd).collect();
    let xml = dir.join("wrong.xml");
    let o = check_all(&cache, &expected, Some(&xml));
    assert!(!o.status.success(), "{}", text(&o.stdout));
    let (out, err) = (text(&o.stdout), text(&o.stderr));
    assert!(
        err.contains(&format!("{} of {} falls", wrong.len(), falls.len())),
        "{err}"
    );
    for (name, class) in &falls {
        let named_in_err = err.contains(&format!("`{name}` {class}"));
        let named_in_out = out.contains(&format!("not expected    {name}: {class}"));
        let is_wrong = class == odd;
        assert_eq!(named_in_err, is_wrong, "{name} ({class}): {err}");
        assert_eq!(named_in_out, is_wrong, "{name} ({class}): {out}");
    }
    // The expected set, in words, on stderr.
    let either = format!(
        "{} or {}",
        expected[..expected.len() - 1].join(", "),
        expected[expected.len() - 1]
    );
    assert!(err.contains(&either), "{err}");
    if let Some(report) = junit_cases(&xml) {
        assert_eq!(report["tests"], falls.len(), "{report}");
        assert_eq!(report["failures"], wrong.len(), "{report}");
        for (case, (name, class)) in report["cases"].as_array().unwrap().iter().zip(&falls) {
            assert_eq!(case["name"], name.as_str());
            match case["failure"].as_str() {
                Some(m) => {
                    assert_eq!(class, odd, "{m}");
                    assert!(
                        m.contains(name) && m.contains(class) && m.contains(&either),
                        "{m}"
                    );
                }
                None => assert_ne!(class, odd, "{name} passed"),
            }
        }
    }

    // One fall, by its object: the same verdict as in the file's table.
    let (name, class) = &falls[0];
    for (classes, passes) in [(vec![class.as_str()], true), (expected.clone(), false)] {
        let o = leafmagic()
            .arg("classify")
            .arg(&cache)
            .args(["--object", name, "--expect", &classes.join(","), "--json"])
            .output()
            .unwrap();
        assert_eq!(o.status.success(), passes, "{}", text(&o.stderr));
        let v: Value = serde_json::from_slice(&o.stdout).unwrap();
        assert_eq!(v["as_expected"], passes, "{v}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// A class the classifier does not name is refused, listing the names it
/// does; `--junit` needs `--expect`; a report that cannot be written is an
/// error naming the flag and the file; nothing is written on a refusal.
#[test]
fn bad_expectations_are_refused_clearly() {
    let dir = scratch("bad");
    let csv =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/real-falls/squares/square_003.csv");
    let xml = dir.join("report.xml");
    let xml_s = xml.to_str().unwrap();
    let missing = dir.join("no/such/dir/report.xml");
    for (more, want) in [
        (
            vec!["--expect", "tumbler"],
            vec!["tumbler", "floater, spinner, lilter, undetermined"],
        ),
        (
            vec!["--expect", "floater,"],
            vec!["floater, spinner, lilter, undetermined"],
        ),
        (vec!["--junit", xml_s], vec!["--expect"]),
        (
            vec!["--expect", "lilter", "--junit", missing.to_str().unwrap()],
            vec!["--junit", "no/such/dir"],
        ),
    ] {
        let o = leafmagic()
            .arg("classify")
            .arg(&csv)
            .args(&more)
            .output()
            .unwrap();
        let err = text(&o.stderr);
        assert!(!o.status.success(), "{more:?}: {err}");
        for w in want {
            assert!(err.contains(w), "{more:?}: {err}");
        }
        assert!(!xml.exists(), "{more:?} wrote a report");
    }
    let _ = std::fs::remove_dir_all(&dir);
}
