//! The classifier from the orientation on reference falls: the
//! Andersen–Pesavento–Wang quasi-steady plate model's, and the MuJoCo
//! falls kept in tests/data/mujoco-falls.

use super::*;
use std::path::{Path, PathBuf};

// ------------------------------------------------------------ APW ODE

/// Falls of the Andersen–Pesavento–Wang 2D quasi-steady plate model
/// (nondimensional form of docs/design/falling-plates.md, "APW quasi-steady
/// model": C_T = 1.2, C_R = π, A = 1.4, B = 1, μ1 = μ2 = 0.2), released
/// from rest at 45°, RK4 with h = 0.005, embedded in 3D (motion in the x–z
/// plane, span along y). Lengths in half-chords a = 1 cm, time unit
/// a/U = 10 ms, sampled every 0.4 units (250 Hz) up to t = 600 units.
fn apw_fall(i_star: f64) -> Trajectory {
    const A: f64 = 0.01;
    const T_UNIT: f64 = 0.01;
    let (ct, cr, ca, cb, mu1, mu2) = (1.2, PI, 1.4, 1.0, 0.2, 0.2);
    let deriv = |s: &[f64; 6]| -> [f64; 6] {
        let [u, v, w, th, _, _] = *s;
        let speed = (u * u + v * v).sqrt();
        let gamma = (2.0 / PI)
            * (if speed > 1e-12 {
                -ct * u * v / speed
            } else {
                0.0
            } + cr * w);
        let drag = if speed > 1e-12 {
            (1.0 / PI) * (ca - cb * (u * u - v * v) / (speed * speed)) * speed
        } else {
            0.0
        };
        let tau = (mu1 + mu2 * w.abs()) * w;
        let du = ((i_star + 1.0) * w * v - gamma * v - th.sin() - drag * u) / i_star;
        let dv = (-i_star * w * u + gamma * u - th.cos() - drag * v) / (i_star + 1.0);
        let dw = (-u * v - tau) / (0.25 * (i_star + 0.5));
        let (c, sn) = (th.cos(), th.sin());
        [du, dv, dw, w, u * c - v * sn, u * sn + v * c]
    };
    let h = 0.005;
    let per_sample = 80;
    let samples = 1501;
    let mut s = [0.0, 0.0, 0.0, 45f64.to_radians(), 0.0, 0.0];
    let mut tr = Trajectory::with_capacity(samples);
    for k in 0..samples {
        if k > 0 {
            for _ in 0..per_sample {
                let add = |a: &[f64; 6], b: &[f64; 6], f: f64| {
                    std::array::from_fn::<f64, 6, _>(|i| a[i] + f * b[i])
                };
                let k1 = deriv(&s);
                let k2 = deriv(&add(&s, &k1, h / 2.0));
                let k3 = deriv(&add(&s, &k2, h / 2.0));
                let k4 = deriv(&add(&s, &k3, h));
                s = std::array::from_fn(|i| {
                    s[i] + h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i])
                });
            }
        }
        let t = (k * per_sample) as f64 * h * T_UNIT;
        // Body x (chord) = (cos θ, 0, sin θ): a rotation by −θ about y.
        tr.push(t, Vector3::new(s[4] * A, 0.0, s[5] * A), ry(-s[3]));
    }
    tr
}

/// The APW model classified as the table in docs/design/falling-plates.md, "APW
/// quasi-steady model", says it falls.
#[test]
fn apw_model_falls_flutter_and_tumble_where_the_notes_say() {
    use MotionClass as C;
    // That table (our integration of the same equations): flutter at
    // I* ≤ 1.2 (±42° … ±96°), tumble at 1.3–1.4, irregular flutter/flip
    // mixture at 1.5–2.5, flutter again at 3.
    for (i_star, want) in [
        (0.5, C::Floater),
        (1.0, C::Floater),
        (1.2, C::Floater),
        (1.3, C::Spinner),
        (1.4, C::Spinner),
        (1.5, C::Lilter),
        (2.0, C::Lilter),
        (2.5, C::Lilter),
        (3.0, C::Floater),
    ] {
        let tr = apw_fall(i_star);
        let c = classify(&tr, 0.02);
        let f = &c.features;
        println!(
            "APW I* = {i_star}: {} / {} margin {:.2}; turns {:.2} cons {:.2} rev {} amp {:.0}° flips {} drift {:.2} tilt {:.0} p10 {:.0} — {}",
            c.class,
            c.regime,
            f.margin,
            f.net_turns,
            f.rotation_consistency,
            f.reversals,
            f.rocking_amplitude_deg,
            f.normal_flips,
            f.drift_ratio,
            f.tilt_mean_deg,
            f.tilt_p10_deg,
            c.reason.as_deref().unwrap_or("")
        );
        assert_eq!(c.class, want, "I* = {i_star}: {c:#?}");
        let c60 = classify(&tr.resampled(60.0), 0.02);
        assert_eq!(c60.class, want, "I* = {i_star} at 60 Hz");
    }
}

// ------------------------------------------------------------ MuJoCo falls

/// The MuJoCo falls kept in the repository (tests/data/mujoco-falls).
fn mujoco_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/mujoco-falls")
}

const MUJOCO: [(&str, MotionClass); 6] = [
    ("steady_fall", MotionClass::Floater),
    ("glide_ballast", MotionClass::Floater),
    ("wobble_card", MotionClass::Floater),
    ("flutter_strip", MotionClass::Floater),
    ("tumble_thick", MotionClass::Spinner),
    ("tumble_cardscoef", MotionClass::Spinner),
];
const MUJOCO_CHORD: f64 = 0.04;

#[test]
fn mujoco_falls_get_the_readme_class_from_240_down_to_24_hz() {
    let dir = mujoco_dir();
    for (name, class) in MUJOCO {
        let tr = Trajectory::read_csv(&dir.join(format!("{name}.csv"))).unwrap();
        let c = classify(&tr, MUJOCO_CHORD);
        let f = &c.features;
        println!(
            "{name}: {} / {} margin {:.2} (regime {:.2}); turns {:.2} cons {:.2} rev {} amp {:.1}° period {:?} flips {} yaw {:.2} tilt {:.1}±{:.1} p10 {:.1} drift {:.3} v {:.2} m/s chords {:.0} — {}",
            c.class,
            c.regime,
            f.margin,
            f.regime_margin,
            f.net_turns,
            f.rotation_consistency,
            f.reversals,
            f.rocking_amplitude_deg,
            f.oscillation_period_s,
            f.normal_flips,
            f.yaw_turns,
            f.tilt_mean_deg,
            f.tilt_std_deg,
            f.tilt_p10_deg,
            f.drift_ratio,
            f.mean_descent_speed_m_s,
            f.descent_chords,
            c.reason.as_deref().unwrap_or("")
        );
        assert_eq!(c.class, class, "{name}: {c:#?}");
        for (how, rate, low) in [
            ("decimated", 60.0, tr.every(4)),
            ("slerp", 60.0, tr.resampled(60.0)),
            ("slerp", 75.0, tr.resampled(75.0)),
            ("slerp", 100.0, tr.resampled(100.0)),
            // Video and animation frame rates: 30, 25 and film's 24 (every
            // tenth sample).
            ("slerp", 30.0, tr.resampled(30.0)),
            ("slerp", 25.0, tr.resampled(25.0)),
            ("decimated", 24.0, tr.every(10)),
        ] {
            let cl = classify(&low, MUJOCO_CHORD);
            assert!((cl.features.sample_rate_hz - rate).abs() < 0.1);
            assert_eq!(cl.inputs, Inputs::Orientation, "{name} {how} {rate} Hz");
            assert_eq!(cl.class, class, "{name} {how} {rate} Hz: {cl:#?}");
            assert_eq!(cl.regime, c.regime, "{name} {how} {rate} Hz");
        }
    }
}
