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
    .chain(bad_crosses())
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

/// Crosses refused, each with the flag its message must name first: an
/// arm that is not narrower than the span or not wider than nothing, an
/// arm width on another shape, a cross without one or with an aspect.
fn bad_crosses() -> Vec<(Vec<&'static str>, &'static str)> {
    let cross = |more: &[&'static str]| {
        let mut args = vec!["--shape", "cross", "--size", "0.05"];
        args.extend(more);
        args
    };
    let mut bad: Vec<(Vec<&'static str>, &'static str)> =
        ["0", "-0.01", "0.05", "0.06", "nan", "inf"]
            .into_iter()
            .map(|w| (cross(&["--arm-width", w]), "--arm-width"))
            .collect();
    bad.extend([
        (cross(&[]), "--arm-width"),
        (cross(&["--arm-width", "0.01", "--aspect", "2"]), "--aspect"),
        (
            vec!["--shape", "square", "--size", "0.05", "--arm-width", "0.01"],
            "--arm-width",
        ),
        (
            vec!["--shape", "cross", "--size", "-0.05", "--arm-width", "0.01"],
            "--size",
        ),
    ]);
    bad
}

/// `plate --shape cross`: a plus of span S (tip to tip) and arm width W
/// has the plus's exact area 2 S W − W², the mass σ × area, its centroid
/// at the centre, every particle inside the plus and tips at ±S/2, and the
/// principal moments of inertia of the uniform plus (within the 2 % the
/// other plates' lumped mass holds): σ I, σ I, 2 σ I about the centre, I
/// the second moment of area about an arm's axis, worked out here as the
/// two arms' rectangles (b h³ / 12 each) less the centre square both count.
#[test]
fn a_cross_has_the_plus_s_area_mass_centroid_and_moments() {
    use leafmagic::leaf::plates::principal_moments;
    let dir = dir("cross");
    for (span, arm, sigma) in [
        (0.05, 0.05 / 3.0, 0.07),
        (0.09, 0.012, 0.07),
        (0.04, 0.036, 0.2),
        (0.06, 0.001, 0.07),
    ] {
        let out = dir.join("cross.toml");
        let (span_s, arm_s, sigma_s) = (span.to_string(), arm.to_string(), sigma.to_string());
        let run = plate(&[
            "--shape",
            "cross",
            "--size",
            &span_s,
            "--arm-width",
            &arm_s,
            "--areal-density",
            &sigma_s,
            "--out",
            out.to_str().unwrap(),
        ]);
        assert!(
            run.status.success(),
            "{}",
            String::from_utf8_lossy(&run.stderr)
        );
        let model = LeafSpec::read(&out).unwrap().model().unwrap();
        let rectangle = |b: f64, h: f64| b * h.powi(3) / 12.0;
        let area = span * arm + arm * span - arm * arm;
        let second = rectangle(span, arm) + rectangle(arm, span) - rectangle(arm, arm);
        let close = |got: f64, want: f64, tol: f64| (got / want - 1.0).abs() < tol;
        let what = format!("span {span}, arm {arm}");
        assert!(close(model.surface_area(), area, 1e-12), "{what}");
        assert!(close(model.total_mass(), sigma * area, 1e-12), "{what}");
        let centre = model.centre_of_mass(&model.rest_position);
        assert!(centre.norm() < 1e-12 * span, "{what}: {centre}");
        let reach = model
            .rest_position
            .iter()
            .map(|p| p.x.abs().max(p.y.abs()))
            .fold(0.0, f64::max);
        assert!(close(reach, 0.5 * span, 1e-12), "{what}: {reach}");
        for p in &model.rest_position {
            let inside = p.x.abs().min(p.y.abs()) <= 0.5 * arm * (1.0 + 1e-12);
            assert!(inside && p.z == 0.0, "{what}: {p} is outside the plus");
        }
        let [a, b, c] = principal_moments(&model);
        let want = sigma * second;
        println!(
            "{what}: principal moments {:.4}, {:.4}, {:.4} of the uniform plus's",
            a / want,
            b / want,
            c / (2.0 * want)
        );
        assert!(
            close(a, want, 0.02) && close(b, want, 0.02) && close(c, 2.0 * want, 0.02),
            "{what}"
        );
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
