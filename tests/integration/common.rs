//! Small models built in code for the oracles.

use leafmagic::physics::field::WindField;
use leafmagic::physics::model::{AeroLaw, Model, ModelParts, Spring, Triangle};
use nalgebra::Vector3;

pub type V3 = Vector3<f64>;

/// A Python in a venv `name` under the target directory in which
/// `import_check` (a module path) imports, made once with `pip install
/// package`, or why there is none. Pip has a 30 s network timeout: a
/// network that hangs fails the install instead of stalling CI.
pub fn venv_python(
    name: &str,
    import_check: &str,
    package: &str,
) -> Result<std::path::PathBuf, String> {
    use std::process::Command;
    let venv = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(name);
    let python = venv.join("bin/python3");
    let has = |p: &std::path::Path| {
        Command::new(p)
            .args(["-c", &format!("import {import_check}")])
            .output()
            .is_ok_and(|o| o.status.success())
    };
    if has(&python) {
        return Ok(python);
    }
    let o = Command::new("python3")
        .args(["-m", "venv"])
        .arg(&venv)
        .output()
        .map_err(|e| format!("python3 is not available: {e}"))?;
    if !o.status.success() {
        return Err(format!(
            "python3 -m venv failed: {}",
            String::from_utf8_lossy(&o.stderr).trim()
        ));
    }
    let o = Command::new(&python)
        .args([
            "-m",
            "pip",
            "install",
            "--quiet",
            "--disable-pip-version-check",
        ])
        .args(["--timeout", "30", "--retries", "1", package])
        .output()
        .map_err(|e| e.to_string())?;
    if !o.status.success() || !has(&python) {
        return Err(format!(
            "pip install {package} failed: {}",
            String::from_utf8_lossy(&o.stderr).trim()
        ));
    }
    Ok(python)
}

/// A test whose outside tool is missing: skipped with a message on a
/// developer's machine, a failure under `CI=true`, where `.ci/run`
/// installs every tool the tests use, so a skip there would hide a check
/// that never ran.
pub fn missing_tool(test: &str, why: &str) {
    if std::env::var("CI").is_ok_and(|v| v == "true") {
        panic!("{test}: {why} (CI=true, and .ci/run should have installed it)");
    }
    eprintln!("SKIPPED {test}: {why}");
}

/// Parts with `n` free unit-mass particles at the origin, no gravity.
pub fn parts(n: usize) -> ModelParts {
    ModelParts {
        mass: vec![1.0; n],
        fixed: vec![false; n],
        particle_drag: vec![0.0; n],
        rest_position: vec![V3::zeros(); n],
        springs: vec![],
        triangles: vec![],
        hinges: vec![],
        aero: AeroLaw::Linear,
        wind: WindField::still(),
        gravity: V3::zeros(),
        ..Default::default()
    }
}

/// A single free particle of mass `m` under gravity `g` (down z).
pub fn falling_particle(m: f64, g: f64) -> Model {
    let mut p = parts(1);
    p.mass = vec![m];
    p.gravity = V3::new(0.0, 0.0, -g);
    Model::new(p).unwrap()
}

/// A free particle of mass `m` tied by a spring (k, c) of rest length 1 to a
/// fixed particle at the origin, lying on the x axis: motion along x is the
/// linear oscillator x'' = −(k/m) x − (c/m) x' in the stretch x = l − 1.
pub fn oscillator(m: f64, k: f64, c: f64) -> Model {
    let mut p = parts(2);
    p.mass = vec![1.0, m];
    p.fixed = vec![true, false];
    p.rest_position = vec![V3::zeros(), V3::new(1.0, 0.0, 0.0)];
    p.springs = vec![Spring {
        i: 0,
        j: 1,
        rest_length: 1.0,
        stiffness: k,
        damping: c,
        break_strain: None,
    }];
    Model::new(p).unwrap()
}

/// One flat triangle of equal masses in the x-y plane.
pub fn flat_triangle(mass_each: f64, alpha_n: f64, alpha_t: f64) -> Model {
    let mut p = parts(3);
    p.mass = vec![mass_each; 3];
    p.rest_position = vec![
        V3::new(0.0, 0.0, 0.0),
        V3::new(0.1, 0.0, 0.0),
        V3::new(0.0, 0.1, 0.0),
    ];
    p.triangles = vec![Triangle {
        corners: [0, 1, 2],
        alpha_n,
        alpha_t,
    }];
    Model::new(p).unwrap()
}

/// A leaf file's text (`leaf`, e.g. an embedded prototype) with its
/// `[aero]` table replaced by `aero` (TOML lines).
pub fn with_aero(leaf: &str, aero: &str) -> String {
    let start = leaf.find("[aero]").unwrap();
    let end = start + leaf[start..].find("\n[bounds]").unwrap();
    format!("{}[aero]\n{aero}\n{}", &leaf[..start], &leaf[end..])
}

/// Fails the test with the command's standard error unless `out` is that of
/// a run that exited 0.
pub fn assert_succeeded(out: &std::process::Output) {
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// An empty scratch folder for a test, `name` within module `module`'s
/// (so that tests of different modules running at once never share one),
/// made afresh: whatever an earlier run left there is removed.
pub fn scratch(module: &str, name: &str) -> std::path::PathBuf {
    let dir =
        std::env::temp_dir().join(format!("leafmagic-{module}-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Leaf `id` of a breed run seeded 1991 dropped again for 10 s from each of
/// the four release attitudes the run judged it on: each release and how
/// its fall classifies.
pub fn redropped(
    model: &Model,
    id: u64,
) -> Vec<([f64; 2], leafmagic::motion::classify::Classification)> {
    leafmagic::breed::robust::release_attitudes(1991, id, 4)
        .into_iter()
        .map(|tilt| {
            let params = leafmagic::sim::drop::DropParams {
                seconds: 10.0,
                tilt_deg: tilt,
                ..Default::default()
            };
            let fall = leafmagic::sim::drop::drop_leaf(model, &params).unwrap();
            (
                tilt,
                leafmagic::motion::classify::classify(&fall.trajectory, model.chord()),
            )
        })
        .collect()
}
