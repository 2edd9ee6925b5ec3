//! Bad input gets a clear error naming the file, the item and the reason;
//! the command line exits non-zero and writes nothing.

use leafmagic::leaf::{LeafSpec, PROTOTYPE_A};
use std::process::{Command, Stdio};

/// Prototype A with one edit applied to its TOML tree.
fn edited(edit: impl FnOnce(&mut toml::Table)) -> String {
    let mut table: toml::Table = toml::from_str(PROTOTYPE_A).unwrap();
    edit(&mut table);
    toml::to_string(&table).unwrap()
}

fn item<'a>(table: &'a mut toml::Table, key: &str, index: usize) -> &'a mut toml::Table {
    table[key].as_array_mut().unwrap()[index]
        .as_table_mut()
        .unwrap()
}

fn expect_error(text: &str, needles: &[&str]) {
    let err = LeafSpec::from_toml(text, "bad-leaf.toml").expect_err("must be rejected");
    let msg = err.to_string();
    // File, line, field, reason: the line is the field's own (or, for a
    // field left at its default, its table's header).
    let line = err.line.unwrap_or_else(|| panic!("no line in: {msg}"));
    assert!(
        msg.starts_with(&format!("bad-leaf.toml:{line}: {}: ", err.field)),
        "not file:line: field: in: {msg}"
    );
    let key = err.field.rsplit('.').next().unwrap();
    let key = key.split('[').next().unwrap();
    let at = text.lines().nth(line - 1).unwrap_or("");
    assert!(
        at.trim_start().starts_with(key) || at.starts_with('['),
        "line {line} is `{at}`, not {}: {msg}",
        err.field
    );
    for n in needles {
        assert!(msg.contains(n), "'{n}' missing from: {msg}");
    }
}

#[test]
fn non_finite_values_are_rejected() {
    expect_error(
        &edited(|t| {
            item(t, "particle", 2).insert("mass".into(), toml::Value::Float(f64::NAN));
        }),
        &["particle[2].mass", "finite"],
    );
    expect_error(
        &edited(|t| {
            item(t, "spring", 3).insert("stiffness".into(), toml::Value::Float(f64::INFINITY));
        }),
        &["spring[3].stiffness", "finite"],
    );
    expect_error(
        &edited(|t| {
            item(t, "particle", 1).insert(
                "position".into(),
                toml::Value::Array(vec![0.0.into(), f64::NAN.into(), 0.0.into()]),
            );
        }),
        &["particle[1].position[1]", "finite"],
    );
}

#[test]
fn non_positive_mass_is_rejected() {
    for m in [0.0, -1e-5] {
        expect_error(
            &edited(|t| {
                item(t, "particle", 5).insert("mass".into(), m.into());
            }),
            &["particle[5].mass", "> 0"],
        );
    }
}

#[test]
fn negative_stiffness_or_rest_length_is_rejected() {
    expect_error(
        &edited(|t| {
            item(t, "spring", 0).insert("stiffness".into(), (-2.0).into());
        }),
        &["spring[0].stiffness", "≥ 0"],
    );
    expect_error(
        &edited(|t| {
            item(t, "spring", 4).insert("rest_length".into(), (-0.01).into());
        }),
        &["spring[4].rest_length", "≥ 0"],
    );
}

#[test]
fn indices_out_of_range_are_rejected() {
    expect_error(
        &edited(|t| {
            item(t, "spring", 2)
                .insert("ends".into(), toml::Value::Array(vec![0.into(), 7.into()]));
        }),
        &["spring[2].ends", "out of range"],
    );
    expect_error(
        &edited(|t| {
            item(t, "triangle", 1).insert(
                "corners".into(),
                toml::Value::Array(vec![0.into(), 1.into(), 99.into()]),
            );
        }),
        &["triangle[1].corners[2]", "out of range"],
    );
    expect_error(
        &edited(|t| {
            item(t, "fold", 0).insert("moves".into(), toml::Value::Array(vec![42.into()]));
        }),
        &["fold[0].moves", "out of range"],
    );
}

#[test]
fn duplicate_springs_are_rejected_in_either_order() {
    expect_error(
        &edited(|t| {
            item(t, "spring", 1)
                .insert("ends".into(), toml::Value::Array(vec![1.into(), 0.into()]));
        }),
        &[
            "spring[1].ends",
            "duplicate spring between particles 0 and 1",
        ],
    );
}

#[test]
fn zero_area_triangle_at_rest_is_rejected() {
    let text = r#"
name = "collinear"
[aero]
alpha_n = 0.5
alpha_t = 0.05
[[particle]]
position = [0.0, 0.0, 0.0]
mass = 1e-5
[[particle]]
position = [0.01, 0.0, 0.0]
mass = 1e-5
[[particle]]
position = [0.02, 0.0, 0.0]
mass = 1e-5
[[triangle]]
corners = [0, 1, 2]
"#;
    expect_error(text, &["triangle[0].corners", "zero area"]);
}

#[test]
fn unknown_keys_and_syntax_errors_name_the_place() {
    expect_error(
        &edited(|t| {
            item(t, "spring", 0).insert("stifness".into(), 2.0.into());
        }),
        &["stifness"],
    );
    expect_error("name = \"x\"\n[aero\nalpha_n = 1", &[":2: "]);
}

/// A name given as a number says that a string was wanted, and which
/// (serde's own message, "wanted string or table", said neither), at the
/// key's line and field.
#[test]
fn a_number_where_a_name_belongs_says_the_names() {
    let text = edited(|t| {
        t["aero"]
            .as_table_mut()
            .unwrap()
            .insert("law".into(), 3.into());
    });
    expect_error(
        &text,
        &[
            ": aero.law: ",
            "expected a string: one of linear, quadratic, unsteady",
        ],
    );
    let err = LeafSpec::from_toml(&text, "bad-leaf.toml")
        .unwrap_err()
        .to_string();
    assert!(!err.contains("wanted string or table"), "{err}");
}

fn leafmagic() -> Command {
    Command::new(env!("CARGO_BIN_EXE_leafmagic"))
}

fn scratch_dir(name: &str) -> std::path::PathBuf {
    super::common::scratch("validation", name)
}

#[test]
fn cli_rejects_a_bad_leaf_file_with_its_name_and_field() {
    let dir = scratch_dir("bad-leaf");
    let path = dir.join("bad.toml");
    std::fs::write(
        &path,
        edited(|t| {
            item(t, "particle", 3).insert("mass".into(), (-1.0).into());
        }),
    )
    .unwrap();
    for sub in ["drop", "check"] {
        let out = leafmagic().arg(sub).arg(&path).output().unwrap();
        assert!(!out.status.success());
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(
            err.contains("bad.toml") && err.contains("particle[3].mass"),
            "{sub}: {err}"
        );
    }
    let out = leafmagic()
        .args(["drop", "no/such/leaf.toml"])
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("no/such/leaf.toml"));
}

#[test]
fn cli_divergence_exits_non_zero_and_names_the_cause() {
    let out = leafmagic()
        .args([
            "drop",
            "a",
            "--integrator",
            "symplectic",
            "--dt",
            "0.0042",
            "--seconds",
            "1",
        ])
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("diverged at step") && err.contains("dt_max"),
        "{err}"
    );
}

#[test]
fn cli_check_reports_every_integrator() {
    let out = leafmagic().args(["check", "a", "--json"]).output().unwrap();
    assert!(out.status.success());
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    for i in ["euler", "symplectic", "verlet", "rk4", "implicit"] {
        assert!(v["integrators"][i].is_object(), "{i} missing: {v}");
    }
    assert!(v["omega_max"].as_f64().unwrap() > 0.0);
    assert!(v["integrators"]["implicit"]["dt_max"].is_null());
}

/// A negative release tilt is a value, not a flag: `--tilt -4,2` drops the
/// leaf as `--tilt=-4,2` does (clap took `-4,2` for an option), and another
/// tilt gives another fall.
#[test]
fn a_negative_tilt_is_read_as_a_value() {
    let drop = |tilt: &[&str]| {
        let out = leafmagic()
            .args(["drop", "a", "--seconds", "0.5", "--json"])
            .args(tilt)
            .output()
            .unwrap();
        crate::common::assert_succeeded(&out);
        let mut json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        json.as_object_mut().unwrap().remove("wall_s");
        json
    };
    let spaced = drop(&["--tilt", "-4,2"]);
    assert_eq!(spaced, drop(&["--tilt=-4,2"]));
    assert_ne!(spaced, drop(&["--tilt", "4,2"]));
}

/// A reader that stops early (`leafmagic ... | head`) is not an error of
/// ours: the binary exits with the status a shell gives a process ended by
/// SIGPIPE, 141, and prints no panic or backtrace. The pipe's read end is
/// closed before the binary starts, so its first line meets a broken pipe.
#[test]
fn closed_stdout_is_not_a_panic() {
    let (reader, writer) = std::io::pipe().unwrap();
    drop(reader);
    let out = Command::new(env!("CARGO_BIN_EXE_leafmagic"))
        .args(["check", "a"])
        .stdout(writer)
        .stderr(Stdio::piped())
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(141), "{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
}
