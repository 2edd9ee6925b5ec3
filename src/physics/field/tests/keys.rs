//! Keyframed strength.

use super::super::{Interpolation, Keyframes, Primitive};
use super::{V3, v};

#[test]
fn keyframe_interpolation() {
    let keys = vec![(0.0, 0.0), (1.0, 1.0), (3.0, 0.2)];
    let lin = Keyframes {
        keys: keys.clone(),
        interpolation: Interpolation::Linear,
    };
    let step = Keyframes {
        keys,
        interpolation: Interpolation::Step,
    };
    let cases = [
        (-5.0, 0.0, 0.0),
        (0.0, 0.0, 0.0),
        (0.25, 0.25, 0.0),
        (1.0, 1.0, 1.0),
        (2.0, 0.6, 1.0),
        (2.999, 1.0 - 0.8 * 0.9995, 1.0),
        (3.0, 0.2, 0.2),
        (50.0, 0.2, 0.2),
    ];
    for (t, l, s) in cases {
        assert!(
            (lin.value(t) - l).abs() < 1e-12,
            "linear t={t}: {}",
            lin.value(t)
        );
        assert_eq!(step.value(t), s, "step t={t}");
    }
    let single = Keyframes {
        keys: vec![(2.0, 0.7)],
        interpolation: Interpolation::Linear,
    };
    assert_eq!(single.value(-1.0), 0.7);
    assert_eq!(single.value(9.0), 0.7);
    assert_eq!(lin.max_abs(), 1.0);
    // Applied to a primitive, and to its speed bound.
    let u = v(1.0, 2.0, 0.0);
    let p = Primitive::uniform(u).with_keys(lin);
    assert!((p.velocity(&V3::zeros(), 2.0) - 0.6 * u).norm() < 1e-12);
    assert_eq!(p.velocity(&V3::zeros(), -1.0), V3::zeros());
    assert!((p.speed_bound() - u.norm()).abs() < 1e-15);
}
