//! `leafmagic plate`: the leaf file it writes reads back as a uniform rigid
//! plate (moments of inertia within 2 % of the closed forms, the areal
//! density asked for, the unsteady law by default), and bad flags are
//! refused by name, exiting non-zero and writing nothing.

use leafmagic::leaf::LeafSpec;
use leafmagic::leaf::plates::{PlateShape, uniform_plate_moments};
use leafmagic::physics::model::AeroLaw;
use std::process::Command;

fn dir(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("leafmagic-plate-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn plate(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_leafmagic"))
        .arg("plate")
        .args(args)
        .output()
        .unwrap()
}

#[test]
fn plate_writes_a_uniform_rigid_plate() {
    let dir = dir("good");
    for (shape, size, aspect, sigma) in [
        (PlateShape::Square, 0.05, 1.0, None),
        (PlateShape::Circle, 0.08, 1.0, Some(0.12)),
        (PlateShape::Hexagon, 0.04, 1.0, None),
        (PlateShape::Rectangle, 0.02, 5.0, None),
    ] {
        let out = dir.join(format!("{}.toml", shape.as_str()));
        let (size_s, aspect_s) = (size.to_string(), aspect.to_string());
        let mut args = vec![
            "--shape",
            shape.as_str(),
            "--size",
            &size_s,
            "--aspect",
            &aspect_s,
            "--out",
            out.to_str().unwrap(),
        ];
        let sigma_s = sigma.map(|s: f64| s.to_string());
        if let Some(s) = &sigma_s {
            args.extend(["--areal-density", s]);
        }
        let run = plate(&args);
        assert!(
            run.status.success(),
            "{}",
            String::from_utf8_lossy(&run.stderr)
        );
        let spec = LeafSpec::read(&out).unwrap();
        assert!(spec.rigid);
        let model = spec.model().unwrap();
        assert!(matches!(model.aero, AeroLaw::Unsteady(_)));
        let x = &model.rest_position;
        let area = model.surface_area();
        let m = model.total_mass();
        assert!((m / area - sigma.unwrap_or(0.07)).abs() < 1e-12);
        let ix: f64 = x
            .iter()
            .zip(&model.mass)
            .map(|(p, w)| w * p.y * p.y)
            .sum::<f64>()
            / m;
        let iy: f64 = x
            .iter()
            .zip(&model.mass)
            .map(|(p, w)| w * p.x * p.x)
            .sum::<f64>()
            / m;
        let [ex, ey] = uniform_plate_moments(shape, size, aspect);
        println!(
            "{shape:?}: I_x {:.4}, I_y {:.4} of a uniform plate's",
            ix / ex,
            iy / ey
        );
        assert!((ix / ex - 1.0).abs() < 0.02 && (iy / ey - 1.0).abs() < 0.02);
    }
    // --law linear gives a linear-law plate.
    let out = dir.join("linear.toml");
    let run = plate(&[
        "--shape",
        "square",
        "--size",
        "0.03",
        "--law",
        "linear",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(run.status.success());
    assert_eq!(
        LeafSpec::read(&out).unwrap().model().unwrap().aero,
        AeroLaw::Linear
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn bad_plate_flags_are_refused_by_name_and_write_nothing() {
    let dir = dir("bad");
    let out = dir.join("p.toml");
    let out_s = out.to_str().unwrap();
    let bad_stiffness = ["0", "-1e-4", "nan"].map(|d| {
        let args = [
            "--shape",
            "square",
            "--size",
            "0.05",
            "--bending-stiffness",
            d,
        ];
        (args.to_vec(), "--bending-stiffness")
    });
    for (args, flag) in [
        (vec!["--shape", "square", "--size", "-0.05"], "--size"),
        (vec!["--shape", "square", "--size", "nan"], "--size"),
        (
            vec![
                "--shape",
                "square",
                "--size",
                "0.05",
                "--areal-density",
                "0",
            ],
            "--areal-density",
        ),
        (
            vec![
                "--shape",
                "square",
                "--size",
                "0.05",
                "--areal-density",
                "inf",
            ],
            "--areal-density",
        ),
        (
            vec!["--shape", "circle", "--size", "0.05", "--aspect", "2"],
            "--aspect",
        ),
        (vec!["--shape", "triangle", "--size", "0.05"], "--shape"),
        // Finite, but f64 holds no mass for their particles (inf or 0 kg).
        (vec!["--shape", "square", "--size", "1e308"], "--size"),
        (vec!["--shape", "hexagon", "--size", "1e-300"], "--size"),
        // Masses of 1e-306 kg: a moment of inertia among the subnormals,
        // which once read as "the particles lie on one line".
        (
            vec![
                "--shape",
                "square",
                "--size",
                "0.05",
                "--areal-density",
                "1e-300",
            ],
            "moment of inertia",
        ),
        // 6.8e10 particles: refused before anything is allocated (it was
        // an abort on a terabyte's allocation; 1e308, a panic).
        (
            vec!["--shape", "rectangle", "--size", "0.05", "--aspect", "1e9"],
            "--aspect",
        ),
        (
            vec![
                "--shape",
                "rectangle",
                "--size",
                "0.05",
                "--aspect",
                "1e308",
            ],
            "--aspect",
        ),
        (
            vec!["--shape", "square", "--size", "0.05", "--law", "magic"],
            "--law",
        ),
        (
            vec![
                "--shape",
                "rectangle",
                "--size",
                "0.02",
                "--aspect",
                "4",
                "--bending-stiffness",
                "2.5e-4",
            ],
            "--bending-stiffness",
        ),
    ]
    .into_iter()
    .chain(bad_stiffness)
    {
        let mut all = args.clone();
        all.extend(["--out", out_s]);
        let run = plate(&all);
        let err = String::from_utf8_lossy(&run.stderr);
        assert!(!run.status.success(), "{args:?}");
        // The flag and its reason on the first line (not just the usage).
        let first = err.lines().next().unwrap_or("");
        assert!(first.contains(flag), "{args:?}: {err}");
        assert!(!out.exists(), "{args:?} wrote a file");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// The report and the plate's name give its mass and density in numbers,
/// at paper's weight and at a density whose grams overflow f64: a
/// 5 cm square of 1e308 kg/m² weighs 2.5e305 kg, which is finite, but
/// 2.5e308 g is not, and the report used to print "inf g" and name the
/// plate "…-infgsm".
#[test]
fn a_plate_reports_its_mass_and_density_in_numbers() {
    let dir = dir("report");
    for (sigma, name_tag, mass_text) in [
        ("0.07", "-70gsm", "0.175 g"),
        ("1e308", "-1.00e308kgm2", "2.500e305 kg"),
    ] {
        let out = dir.join("p.toml");
        let run = plate(&[
            "--shape",
            "square",
            "--size",
            "0.05",
            "--areal-density",
            sigma,
            "--out",
            out.to_str().unwrap(),
        ]);
        let report = String::from_utf8_lossy(&run.stderr);
        assert!(run.status.success(), "{report}");
        assert!(!report.contains("inf"), "{report}");
        assert!(report.contains(mass_text), "{sigma}: {report}");
        let spec = LeafSpec::read(&out).unwrap();
        assert!(spec.name.ends_with(name_tag), "{sigma}: {}", spec.name);
    }
    let _ = std::fs::remove_dir_all(&dir);
}
