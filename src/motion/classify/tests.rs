//! The classifier from the orientation on synthetic falls of known
//! kinematics, one of each regime and the boundary cases between them;
//! `reference_falls` holds the falls of a model and of another simulator.

use super::*;
use nalgebra::{UnitQuaternion, Vector3};
use std::f64::consts::{PI, TAU};

mod reference_falls;

const CHORD: f64 = 0.05;

fn ry(a: f64) -> UnitQuaternion<f64> {
    UnitQuaternion::from_axis_angle(&Vector3::y_axis(), a)
}
fn rx(a: f64) -> UnitQuaternion<f64> {
    UnitQuaternion::from_axis_angle(&Vector3::x_axis(), a)
}
fn rz(a: f64) -> UnitQuaternion<f64> {
    UnitQuaternion::from_axis_angle(&Vector3::z_axis(), a)
}

/// Samples `pos` and `rot` at `rate` Hz from t = 0 to `duration`.
fn synth(
    rate: f64,
    duration: f64,
    pos: impl Fn(f64) -> Vector3<f64>,
    rot: impl Fn(f64) -> UnitQuaternion<f64>,
) -> Trajectory {
    let n = (duration * rate).round() as usize + 1;
    let mut tr = Trajectory::with_capacity(n);
    for k in 0..n {
        let t = k as f64 / rate;
        tr.push(t, pos(t), rot(t));
    }
    tr
}

fn steady() -> Trajectory {
    synth(
        240.0,
        10.0,
        |t| Vector3::new(0.0, 0.0, -0.5 * t),
        |_| rx(2f64.to_radians()),
    )
}
fn glide() -> Trajectory {
    synth(
        240.0,
        10.0,
        |t| Vector3::new(0.2 * t, 0.05 * t, -0.6 * t),
        |_| ry(10f64.to_radians()),
    )
}
fn flutter() -> Trajectory {
    let w = TAU / 0.8;
    synth(
        240.0,
        10.0,
        move |t| Vector3::new(0.08 * (w * t).cos(), 0.0, -0.5 * t),
        move |t| ry(30f64.to_radians() * (w * t).sin()),
    )
}
fn tumble() -> Trajectory {
    synth(
        240.0,
        10.0,
        |t| Vector3::new(0.3 * t, 0.0, -0.8 * t),
        |t| ry(8.0 * t),
    )
}
fn autorotation() -> Trajectory {
    synth(
        240.0,
        10.0,
        |t| Vector3::new(0.05 * (15.0 * t).cos(), 0.05 * (15.0 * t).sin(), -1.5 * t),
        |t| rz(15.0 * t) * rx(60f64.to_radians()),
    )
}
/// Rocking that grows between irregularly spaced flips (some forwards,
/// some back), while the leaf also turns slowly about the vertical
/// (3 rad/s, a boundary case of docs/design/falling-plates.md, "Folded leaves
/// under the linear law").
fn chaotic_pitch(t: f64) -> f64 {
    const FLIPS: [(f64, f64); 6] = [
        (2.3, 1.0),
        (4.1, -1.0),
        (7.4, 1.0),
        (8.6, 1.0),
        (10.9, -1.0),
        (99.0, 0.0),
    ];
    let smooth = |x: f64| {
        let x = x.clamp(0.0, 1.0);
        x * x * (3.0 - 2.0 * x)
    };
    let mut base = 0.0;
    let mut last = 0.0;
    let mut next = FLIPS[0].0;
    for (tf, dir) in FLIPS {
        if t >= tf {
            last = tf + 0.4;
            base += dir * PI * smooth((t - tf) / 0.4);
        } else {
            next = tf;
            break;
        }
    }
    let grow = ((t - last) / (next - last)).clamp(0.0, 1.0);
    let amp = (15.0 + 55.0 * grow).to_radians();
    base + amp * (TAU * t / 0.7).sin()
}
fn chaotic() -> Trajectory {
    chaotic_yawing(3.0)
}
fn chaotic_yawing(yaw_rate: f64) -> Trajectory {
    synth(
        240.0,
        12.0,
        |t| Vector3::new(0.05 * t + 0.03 * (3.0 * t).sin(), 0.0, -0.6 * t),
        move |t| rz(yaw_rate * t) * ry(chaotic_pitch(t)),
    )
}
fn dive() -> Trajectory {
    synth(
        240.0,
        10.0,
        |t| Vector3::new(0.02 * t, 0.0, -4.0 * t),
        |t| ry((85.0 + 2.0 * (TAU * t / 0.5).sin()).to_radians()),
    )
}

/// Rigid spin at 20 rad/s about a world axis tilted 20° from vertical,
/// plate at 60°: its horizontal part turns steadily too, yet it is
/// autorotation (the axis is within 45° of vertical), not a tumble.
fn tilted_spin() -> Trajectory {
    let axis = nalgebra::Unit::new_normalize(Vector3::new(
        20f64.to_radians().sin(),
        0.0,
        20f64.to_radians().cos(),
    ));
    synth(
        240.0,
        10.0,
        |t| Vector3::new(0.0, 0.0, -1.2 * t),
        move |t| UnitQuaternion::from_axis_angle(&axis, 20.0 * t) * rx(60f64.to_radians()),
    )
}
/// A leaf spinning about the vertical at 14 rad/s with its plane near
/// vertical and wobbling ±38° once a turn (measured on a prototype-B
/// variant): its normal crosses the horizontal twice a turn and the
/// wobble reverses, yet nothing turns end over end — autorotation.
fn wobbling_spin() -> Trajectory {
    synth(
        240.0,
        10.0,
        |t| Vector3::new(0.02 * (14.0 * t).cos(), 0.02 * (14.0 * t).sin(), -2.3 * t),
        |t| {
            rz(14.0 * t) * rx((90.0 - 38.0 * (14.0 * t + 0.3 * (2.1 * t).sin()).sin()).to_radians())
        },
    )
}
/// End-over-end tumble about the leaf's own span while the leaf turns
/// slowly about the vertical (the span axis precesses by > 180°).
fn precessing_tumble() -> Trajectory {
    synth(
        240.0,
        10.0,
        |t| Vector3::new(0.3 * (0.8 * t).cos(), 0.3 * (0.8 * t).sin(), -0.8 * t),
        |t| rz(0.8 * t) * ry(8.0 * t),
    )
}
/// Rocking ±20° about a 55° tilt: never near flat, never edge-on.
fn steep_rocking() -> Trajectory {
    synth(
        240.0,
        10.0,
        |t| Vector3::new(0.0, 0.0, -t),
        |t| ry((55.0 + 20.0 * (TAU * t / 0.6).sin()).to_radians()),
    )
}
/// Steady at 45°: "neither clearly floater nor diver"
/// (docs/design/falling-plates.md, "Folded leaves under the linear law").
fn steep_steady() -> Trajectory {
    synth(
        240.0,
        10.0,
        |t| Vector3::new(0.1 * t, 0.0, -1.5 * t),
        |_| ry(45f64.to_radians()),
    )
}

fn cases() -> Vec<(&'static str, Trajectory, MotionClass, Regime)> {
    use MotionClass as C;
    vec![
        ("steady", steady(), C::Floater, Regime::Steady),
        ("glide", glide(), C::Floater, Regime::Glide),
        ("flutter", flutter(), C::Floater, Regime::Flutter),
        ("tumble", tumble(), C::Spinner, Regime::Tumble),
        (
            "autorotation",
            autorotation(),
            C::Spinner,
            Regime::Autorotation,
        ),
        ("chaotic", chaotic(), C::Lilter, Regime::Chaotic),
        ("dive", dive(), C::Undetermined, Regime::Dive),
        (
            "tilted_spin",
            tilted_spin(),
            C::Spinner,
            Regime::Autorotation,
        ),
        (
            "wobbling_spin",
            wobbling_spin(),
            C::Spinner,
            Regime::Autorotation,
        ),
        (
            "precessing_tumble",
            precessing_tumble(),
            C::Spinner,
            Regime::Tumble,
        ),
        (
            "steep_rocking",
            steep_rocking(),
            C::Undetermined,
            Regime::Undetermined,
        ),
        (
            "steep_steady",
            steep_steady(),
            C::Undetermined,
            Regime::Undetermined,
        ),
    ]
}

#[test]
fn synthetic_kinematics_get_their_known_class_and_regime() {
    for (name, tr, class, regime) in cases() {
        let c = classify(&tr, CHORD);
        println!(
            "{name}: {} / {} margin {:.2} — {:?}",
            c.class, c.regime, c.features.margin, c.reason
        );
        assert_eq!((c.class, c.regime), (class, regime), "{name}: {c:#?}");
        assert!(c.reason.is_some());
        if class != MotionClass::Undetermined {
            assert!(
                c.features.margin > 0.2,
                "{name}: margin {}",
                c.features.margin
            );
        }
        // Each holds at the minimum rate too.
        let c60 = classify(&tr.resampled(60.0), CHORD);
        assert_eq!(
            (c60.class, c60.regime),
            (class, regime),
            "{name} at 60 Hz: {c60:#?}"
        );
    }
}

#[test]
fn synthetic_features_measure_what_was_built() {
    let f = classify(&tumble(), CHORD).features;
    // 8 rad/s for 6 s.
    assert!((f.net_turns - 48.0 / TAU).abs() < 0.05, "{}", f.net_turns);
    assert!(f.rotation_consistency > 0.999);
    assert!((f.drift_ratio - 0.375).abs() < 1e-9);
    assert!((f.turn_period_s.unwrap() - TAU / 8.0).abs() < 0.01);
    assert_eq!(f.reversals, 0);
    assert!((f.normal_flips as f64 - 2.0 * f.net_turns).abs() <= 1.0);
    let f = classify(&flutter(), CHORD).features;
    assert!(
        (f.rocking_amplitude_deg - 30.0).abs() < 0.5,
        "{}",
        f.rocking_amplitude_deg
    );
    assert!((f.oscillation_period_s.unwrap() - 0.8).abs() < 0.01);
    assert_eq!(f.normal_flips, 0);
    assert!(f.net_turns < 0.1);
    let f = classify(&autorotation(), CHORD).features;
    assert!((f.mean_yaw_rate_rad_s - 15.0).abs() < 1e-6);
    assert!((f.tilt_mean_deg - 60.0).abs() < 1e-6);
    assert!(f.vertical_spin_share > 0.999);
    // The wobbling spinner flips and reverses like a lilter would; only
    // its vertical share tells it apart.
    let f = classify(&wobbling_spin(), CHORD).features;
    assert!(f.normal_flips >= 10 && f.reversals >= 10, "{f:#?}");
    assert!(f.vertical_spin_share > 0.85, "{}", f.vertical_spin_share);
    let f = classify(&steady(), CHORD).features;
    assert!((f.mean_descent_speed_m_s - 0.5).abs() < 1e-9);
    assert!((f.descent_chords - 60.0).abs() < 1e-6);
    assert!((f.t_start_s - 4.0).abs() < 1e-9 && (f.t_end_s - 10.0).abs() < 1e-9);
    assert_eq!(f.samples, 1441);
}

#[test]
fn lilter_that_also_yaws_is_not_a_spinner() {
    // Lilters turn about the vertical at 1–9 rad/s (docs/design/falling-plates.md,
    // "Folded leaves under the linear law").
    for yaw_rate in [1.0, 3.0, 9.0] {
        let c = classify(&chaotic_yawing(yaw_rate), CHORD);
        let f = &c.features;
        assert!(
            f.yaw_turns.abs() >= 0.9,
            "the case must yaw: {}",
            f.yaw_turns
        );
        assert_eq!(c.class, MotionClass::Lilter, "yaw {yaw_rate} rad/s: {c:#?}");
        assert!(f.normal_flips >= 2 && f.reversals >= 4, "{f:#?}");
        assert_eq!(f.axis_frame, AxisFrame::Body);
    }
}

#[test]
fn too_short_slow_or_gappy_records_are_undetermined_with_a_reason() {
    let why = |tr: &Trajectory| {
        let c = classify(tr, CHORD);
        assert_eq!(c.class, MotionClass::Undetermined, "{c:#?}");
        assert_eq!(c.class, MotionClass::Undetermined);
        assert_eq!(c.regime, Regime::Undetermined);
        assert_eq!(c.features.margin, 0.0);
        c.reason.unwrap()
    };
    let short = synth(
        240.0,
        0.5,
        |t| Vector3::new(0.0, 0.0, -0.5 * t),
        |_| rx(0.0),
    );
    assert!(why(&short).contains("chord lengths"));
    // Below both classifiers' floor (film's 24 frames per second).
    let slow = synth(
        20.0,
        10.0,
        |t| Vector3::new(0.0, 0.0, -0.5 * t),
        |_| rx(0.0),
    );
    let reason = why(&slow);
    assert!(reason.contains("below the 24 Hz minimum"), "{reason}");
    assert!(reason.contains("from the path alone"), "{reason}");
    let mut gappy = Trajectory::default();
    for (k, t) in steady().time.iter().enumerate() {
        if !(1800..1830).contains(&k) {
            gappy.push(*t, Vector3::new(0.0, 0.0, -0.5 * t), rx(0.0));
        }
    }
    assert!(why(&gappy).contains("gap"));
    assert!(why(&Trajectory::default()).contains("too few samples"));
    // Too short for the orientation's rules (0.5 s of window at 60 Hz), long
    // enough for the path's: named from the path, which says why.
    let few = synth(60.0, 0.8, |t| Vector3::new(0.0, 0.0, -0.5 * t), |_| rx(0.0));
    let c = classify(&few, CHORD);
    assert_eq!(
        (c.class, c.regime, c.inputs),
        (MotionClass::Floater, Regime::Steady, Inputs::Path),
        "{c:#?}"
    );
    let reason = c.reason.unwrap();
    assert!(
        reason.contains("the orientation is not used, too few samples"),
        "{reason}"
    );
    // One slow rock in the window: too transient to call a flutter.
    let slow_rock = synth(
        240.0,
        10.0,
        |t| Vector3::new(0.0, 0.0, -t),
        |t| ry(30f64.to_radians() * (TAU * t / 5.0).sin()),
    );
    let c = classify(&slow_rock, CHORD);
    assert_eq!(
        (c.class, c.regime),
        (MotionClass::Undetermined, Regime::Undetermined)
    );
    assert!(c.reason.unwrap().contains("too transient"));
    let rising = synth(
        240.0,
        10.0,
        |t| Vector3::new(0.0, 0.0, 0.5 * t),
        |_| rx(0.0),
    );
    assert!(why(&rising).contains("not falling"));
    assert!(classify(&steady(), 0.0).reason.unwrap().contains("size"));
}

/// A tumble as fast as a record can follow is named from its orientation
/// at film's frame rate; one turning more than [`MAX_SAMPLE_TURN_DEG`]
/// between samples, whose direction the record cannot tell, is not.
#[test]
fn a_rotation_near_half_a_turn_per_sample_is_not_read_from_the_orientation() {
    let tumbling = |deg_per_sample: f64| {
        let rate = 24.0;
        let w = deg_per_sample.to_radians() * rate;
        synth(
            rate,
            10.0,
            |t| Vector3::new(0.3 * t, 0.0, -0.8 * t),
            move |t| rx(w * t),
        )
    };
    let c = classify(&tumbling(120.0), CHORD);
    assert_eq!(
        (c.class, c.regime, c.inputs),
        (MotionClass::Spinner, Regime::Tumble, Inputs::Orientation),
        "{c:#?}"
    );
    assert!((c.features.max_sample_turn_deg - 120.0).abs() < 1e-6);
    let c = classify(&tumbling(170.0), CHORD);
    assert_eq!(c.inputs, Inputs::Path, "{c:#?}");
    let reason = c.reason.unwrap();
    assert!(
        reason.contains("turns 170° between two samples") && reason.contains("sample at 51 Hz"),
        "{reason}"
    );
}

#[test]
fn quaternion_sign_flips_do_not_change_anything() {
    for (name, tr, _, _) in cases() {
        let mut flipped = tr.clone();
        for (k, q) in flipped.orientation.iter_mut().enumerate() {
            if k % 2 == 1 || k % 7 == 3 {
                *q = UnitQuaternion::new_unchecked(-q.into_inner());
            }
        }
        let (a, b) = (classify(&tr, CHORD), classify(&flipped, CHORD));
        assert_eq!((a.class, a.regime), (b.class, b.regime), "{name}");
        let (fa, fb) = (a.features, b.features);
        assert!((fa.net_turns - fb.net_turns).abs() < 1e-9, "{name}");
        assert!((fa.yaw_turns - fb.yaw_turns).abs() < 1e-9, "{name}");
        assert_eq!(fa.reversals, fb.reversals, "{name}");
        assert_eq!(fa.normal_flips, fb.normal_flips, "{name}");
        assert!((fa.margin - fb.margin).abs() < 1e-9, "{name}");
    }
}

mod invariance {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(48))]
        /// Turning the world about the vertical and shifting time and
        /// position leave the class and regime unchanged.
        #[test]
        fn class_is_invariant_under_yaw_and_shifts(
            case in 0usize..12,
            yaw in -PI..PI,
            dt in -1000.0f64..1000.0,
            dx in -100.0f64..100.0,
            dy in -100.0f64..100.0,
            dz in -100.0f64..100.0,
        ) {
            let (name, tr, class, regime) = cases().swap_remove(case);
            let turn = rz(yaw);
            let mut moved = Trajectory::with_capacity(tr.len());
            for k in 0..tr.len() {
                moved.push(
                    tr.time[k] + dt,
                    turn * tr.position[k] + Vector3::new(dx, dy, dz),
                    turn * tr.orientation[k],
                );
            }
            let c = classify(&moved, CHORD);
            prop_assert_eq!((c.class, c.regime), (class, regime), "{}", name);
        }
    }
}

#[test]
fn classification_serializes_class_regime_and_features() {
    let json = serde_json::to_value(classify(&tumble(), CHORD)).unwrap();
    assert_eq!(json["class"], "spinner");
    assert_eq!(json["regime"], "tumble");
    assert!(json["features"]["net_turns"].as_f64().unwrap() > 5.0);
}
