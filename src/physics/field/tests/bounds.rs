//! Bounds and moving fronts: the weights they multiply a primitive by.

use super::super::weight::falloff_weight;
use super::super::{
    Bounds, Front, Interpolation, Keyframes, Primitive, Region, VortexCore, WindField,
};
use super::{V3, v, vortex};

#[test]
fn sphere_bounds_weight() {
    let c = v(0.5, 0.0, 1.0);
    let u = v(0.0, 0.0, 2.0);
    let f = WindField::new(vec![Primitive::uniform(u).with_bounds(Bounds {
        region: Region::Sphere {
            center: c,
            radius: 1.0,
        },
        falloff: 0.5,
    })]);
    let dir = v(1.0, 2.0, -2.0) / 3.0;
    let at = |d: f64| f.velocity(&(c + d * dir), 0.0);
    assert_eq!(at(0.0), u);
    assert_eq!(at(0.99), u);
    assert_eq!(at(1.0), u);
    assert!((at(1.25) - 0.5 * u).norm() < 1e-12);
    assert_eq!(at(1.5), V3::zeros());
    assert_eq!(at(1.5 + 1e-12), V3::zeros());
    assert_eq!(at(100.0), V3::zeros());
    // Continuous: steps of 1e-5 never jump more than max slope (15/8)/falloff × step.
    let step = 1e-5;
    let mut prev = at(0.9);
    let mut d = 0.9;
    while d < 1.6 {
        d += step;
        let cur = at(d);
        assert!((cur - prev).norm() <= 2.0 * 1.875 / 0.5 * step * (1.0 + 1e-9));
        prev = cur;
    }
    // Strictly between full and zero inside the band, and decreasing.
    assert!(at(1.1).z < u.z && at(1.1).z > at(1.4).z && at(1.4).z > 0.0);
}

#[test]
fn box_and_cylinder_bounds_weight() {
    let vort = vortex(V3::zeros(), V3::z(), 2.0, 0.01, VortexCore::LambOseen);
    let unbounded = WindField::new(vec![vort.clone()]);
    let boxed = WindField::new(vec![vort.clone().with_bounds(Bounds {
        region: Region::Box {
            min: v(-1.0, -1.0, 0.0),
            max: v(1.0, 1.0, 2.0),
        },
        falloff: 0.2,
    })]);
    // Deep inside: unchanged.
    for x in [v(0.5, 0.0, 1.0), v(-0.9, 0.9, 0.1), v(1.0, 0.3, 2.0)] {
        assert_eq!(boxed.velocity(&x, 0.0), unbounded.velocity(&x, 0.0));
    }
    // Beyond a face, edge or corner by the falloff: exactly 0.
    for x in [
        v(1.2001, 0.0, 1.0),
        v(0.0, 0.0, -0.2001),
        v(1.15, 1.15, 1.0),
        v(1.2, 1.2, 2.2),
    ] {
        assert_eq!(boxed.velocity(&x, 0.0), V3::zeros(), "{x:?}");
    }
    // Halfway through the band beyond a face: w = 1/2; near a corner the distance is Euclidean.
    let x = v(1.1, 0.0, 1.0);
    assert!((boxed.velocity(&x, 0.0) - 0.5 * unbounded.velocity(&x, 0.0)).norm() < 1e-12);
    let s = 0.1 / 2f64.sqrt();
    let x = v(1.0 + s, 1.0 + s, 1.0);
    assert!((boxed.velocity(&x, 0.0) - 0.5 * unbounded.velocity(&x, 0.0)).norm() < 1e-12);

    let tube = WindField::new(vec![Primitive::uniform(v(1.0, 0.0, 0.0)).with_bounds(
        Bounds {
            region: Region::Cylinder {
                point: V3::zeros(),
                axis: v(0.0, 0.0, 3.0),
                radius: 0.5,
            },
            falloff: 0.1,
        },
    )]);
    assert_eq!(tube.velocity(&v(0.3, 0.3, 100.0), 0.0).x, 1.0);
    assert!((tube.velocity(&v(0.0, 0.55, -7.0), 0.0).x - 0.5).abs() < 1e-12);
    assert_eq!(tube.velocity(&v(0.6001, 0.0, 0.0), 0.0).x, 0.0);
    // A hard edge when falloff = 0.
    let hard = WindField::new(vec![Primitive::uniform(v(1.0, 0.0, 0.0)).with_bounds(
        Bounds {
            region: Region::Sphere {
                center: V3::zeros(),
                radius: 1.0,
            },
            falloff: 0.0,
        },
    )]);
    assert_eq!(hard.velocity(&v(1.0, 0.0, 0.0), 0.0).x, 1.0);
    assert_eq!(hard.velocity(&v(1.0 + 1e-9, 0.0, 0.0), 0.0).x, 0.0);
}

#[test]
fn moving_front_sweeps_at_its_speed() {
    // Plane z = −1 + 2t (normal given unnormalised), falloff 0.1 ahead of it.
    let front = Front {
        normal: v(0.0, 0.0, 2.0),
        offset: -1.0,
        speed: 2.0,
        falloff: 0.1,
    };
    assert_eq!(front.offset_at(1.5), 2.0);
    let up = v(0.0, 0.0, 3.0);
    let f = WindField::new(vec![Primitive::uniform(up).with_front(front.clone())]);
    let t = 1.5;
    assert_eq!(f.velocity(&v(4.0, -2.0, 1.0), t), up);
    assert_eq!(f.velocity(&v(0.0, 0.0, 2.0), t), up);
    assert!((f.velocity(&v(0.0, 0.0, 2.05), t) - 0.5 * up).norm() < 1e-12);
    assert_eq!(f.velocity(&v(0.0, 0.0, 2.1), t), V3::zeros());
    // A leaf at z = 1 sees nothing at t = 0, then full wind once the front passes (t ≥ 1).
    let leaf = v(0.2, 0.2, 1.0);
    assert_eq!(f.velocity(&leaf, 0.0), V3::zeros());
    assert_eq!(f.velocity(&leaf, 0.95 - 1e-9), V3::zeros());
    assert!(f.velocity(&leaf, 0.975).z > 0.0 && f.velocity(&leaf, 0.975).z < up.z);
    assert_eq!(f.velocity(&leaf, 1.0), up);
    // Composes with a singular primitive, bounds and keys: all weights multiply.
    let vort = vortex(V3::zeros(), V3::z(), 2.0, 0.01, VortexCore::Rankine);
    let x = v(0.3, 0.0, 2.05);
    let plain = vort.velocity(&x, t);
    let gated = vort
        .clone()
        .with_front(front)
        .with_bounds(Bounds {
            region: Region::Sphere {
                center: V3::zeros(),
                radius: 0.1,
            },
            falloff: 4.0,
        })
        .with_keys(Keyframes {
            keys: vec![(0.0, 3.0)],
            interpolation: Interpolation::Step,
        });
    let d = x.norm() - 0.1;
    let expected = plain * 0.5 * falloff_weight(d, 4.0) * 3.0;
    assert!((gated.velocity(&x, t) - expected).norm() < 1e-12 * plain.norm());
    assert!(falloff_weight(d, 4.0) > 0.0 && falloff_weight(d, 4.0) < 1.0);
}
