//! The field's speed bound over primitives that can act together
//! (`reach.rs`): exact values where the groups and their vertex sums are
//! known by hand, and a bound that no sampled point of a random field
//! exceeds.

use proptest::prelude::*;

use super::super::{Bounds, Front, Interpolation, Keyframes, Region, VortexCore};
use super::{Primitive, V3, WindField, point_source, v, vortex};

fn boxed(velocity: V3, min: V3, max: V3, falloff: f64) -> Primitive {
    Primitive::uniform(velocity).with_bounds(Bounds {
        region: Region::Box { min, max },
        falloff,
    })
}

fn sum_of_peaks(f: &WindField) -> f64 {
    f.primitives().iter().map(Primitive::speed_bound).sum()
}

/// Two uniform fields in boxes whose falloff bands do not meet never add:
/// the bound is the faster one's speed; let the bands meet and they add.
#[test]
fn fields_that_cannot_meet_do_not_add() {
    let a = v(3.0, 0.0, 4.0);
    let b = v(0.0, -2.0, 0.0);
    let apart = WindField::new(vec![
        boxed(a, v(0.0, 0.0, 0.0), v(1.0, 1.0, 1.0), 0.2),
        boxed(b, v(1.5, 0.0, 0.0), v(2.5, 1.0, 1.0), 0.2),
    ]);
    assert_eq!(apart.speed_bound(), 5.0);
    let touching = WindField::new(vec![
        boxed(a, v(0.0, 0.0, 0.0), v(1.0, 1.0, 1.0), 0.3),
        boxed(b, v(1.5, 0.0, 0.0), v(2.5, 1.0, 1.0), 0.3),
    ]);
    assert_eq!(touching.speed_bound(), (a + b).norm());
}

/// Uniform fields that meet add as vectors: opposite winds give the larger
/// alone (a weight may be 0), not the sum of their speeds.
#[test]
fn opposite_winds_that_meet_bound_by_the_larger() {
    let f = WindField::new(vec![
        Primitive::uniform(v(0.0, 0.0, 2.5)),
        Primitive::uniform(v(0.0, 0.0, -6.0)),
    ]);
    assert_eq!(f.speed_bound(), 6.0);
    assert_eq!(sum_of_peaks(&f), 8.5);
}

/// The shockwave scene's field (scenes/shockwave.toml): the two fronts act
/// everywhere over time, the column and the three pairs of opposite boxes
/// meet the fronts but not their opposites, so the fastest group is the
/// downdraft with the down, an x and a y box: |(0.3, 0.3, −6.3)| m/s, where
/// the sum of the peaks is 10.908 m/s.
#[test]
fn the_shockwave_field_is_bounded_by_its_fastest_group() {
    let front = |offset: f64, speed: f64| Front {
        normal: v(0.0, 0.0, 1.0),
        offset,
        speed,
        falloff: 0.1,
    };
    let cylinder = Bounds {
        region: Region::Cylinder {
            point: v(0.0, 0.0, 0.0),
            axis: v(0.0, 0.0, 1.0),
            radius: 1.0,
        },
        falloff: 0.3,
    };
    let f = WindField::new(vec![
        Primitive::uniform(v(0.0, 0.0, 0.608)).with_bounds(cylinder),
        boxed(
            v(0.0, 0.0, 0.3),
            v(-3.0, -3.0, -10.0),
            v(3.0, 3.0, 1.0),
            0.2,
        ),
        boxed(
            v(0.0, 0.0, -0.3),
            v(-3.0, -3.0, 2.0),
            v(3.0, 3.0, 10.0),
            0.2,
        ),
        boxed(
            v(-0.3, 0.0, 0.0),
            v(0.7, -3.0, -10.0),
            v(3.0, 3.0, 10.0),
            0.2,
        ),
        boxed(
            v(0.3, 0.0, 0.0),
            v(-3.0, -3.0, -10.0),
            v(-0.7, 3.0, 10.0),
            0.2,
        ),
        boxed(
            v(0.0, -0.3, 0.0),
            v(-3.0, 0.7, -10.0),
            v(3.0, 3.0, 10.0),
            0.2,
        ),
        boxed(
            v(0.0, 0.3, 0.0),
            v(-3.0, -3.0, -10.0),
            v(3.0, -0.7, 10.0),
            0.2,
        ),
        Primitive::uniform(v(0.0, 0.0, 2.5)).with_front(front(-0.5, 1.5)),
        Primitive::uniform(v(0.0, 0.0, -6.0)).with_front(front(-4.5, 3.0)),
    ]);
    assert!((sum_of_peaks(&f) - 10.908).abs() < 1e-12);
    assert_eq!(f.speed_bound(), v(0.3, 0.3, -6.3).norm());
}

/// Keyed or non-uniform primitives add their peak speeds: keys may change
/// sign, and a source's direction varies over its region.
#[test]
fn keyed_and_non_uniform_primitives_add_their_peaks() {
    let keys = Keyframes {
        keys: vec![(0.0, -1.0), (1.0, 2.0)],
        interpolation: Interpolation::Linear,
    };
    let keyed = Primitive::uniform(v(0.0, 0.0, 1.0)).with_keys(keys);
    let source = point_source(v(0.0, 0.0, 0.0), 1.0, 0.1);
    let f = WindField::new(vec![
        Primitive::uniform(v(0.0, 0.0, -3.0)),
        keyed.clone(),
        source.clone(),
    ]);
    assert_eq!(
        f.speed_bound(),
        3.0 + keyed.speed_bound() + source.speed_bound()
    );
    assert_eq!(keyed.speed_bound(), 2.0);
}

fn uniform_in(shape: u8, centre: V3, size: f64, falloff: f64, velocity: V3) -> Primitive {
    let region = match shape % 3 {
        0 => Region::Sphere {
            center: centre,
            radius: size,
        },
        1 => Region::Box {
            min: centre - v(size, 0.5 * size, size),
            max: centre + v(size, 0.5 * size, size),
        },
        _ => Region::Cylinder {
            point: centre,
            axis: v(size, 1.0, -0.5 * size),
            radius: 0.5 * size,
        },
    };
    Primitive::uniform(velocity).with_bounds(Bounds { region, falloff })
}

fn triple(r: f64) -> impl Strategy<Value = V3> {
    (-r..r, -r..r, -r..r).prop_map(|(x, y, z)| v(x, y, z))
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    /// For any field of bounded and unbounded uniform winds, fronts, a
    /// bounded source and a vortex, no sampled point and time is faster than
    /// the bound, and the bound is never above the sum of the peaks.
    #[test]
    fn no_point_of_a_field_exceeds_its_speed_bound(
        regions in prop::collection::vec(
            (0u8..3, triple(2.0), 0.2..1.5f64, 0.0..0.5f64, triple(3.0)),
            1..7,
        ),
        free in triple(1.0),
        front_speed in -2.0..2.0f64,
        extras in 0u8..4,
        points in prop::collection::vec((triple(3.5), 0.0..3.0f64), 400),
    ) {
        let mut primitives: Vec<Primitive> = regions
            .iter()
            .map(|&(shape, c, size, f, vel)| uniform_in(shape, c, size, f, vel))
            .collect();
        if extras & 1 != 0 {
            primitives.push(Primitive::uniform(free));
            primitives.push(Primitive::uniform(-free * 2.0).with_front(Front {
                normal: v(0.2, 0.1, 1.0),
                offset: -1.0,
                speed: front_speed,
                falloff: 0.3,
            }));
        }
        if extras & 2 != 0 {
            primitives.push(point_source(v(0.5, -0.5, 0.0), 2.0, 0.2).with_bounds(Bounds {
                region: Region::Sphere { center: v(0.5, -0.5, 0.0), radius: 1.0 },
                falloff: 0.5,
            }));
            primitives.push(vortex(v(0.0, 1.0, 0.0), v(1.0, 0.0, 0.3), 1.5, 0.2, VortexCore::Rankine));
        }
        let f = WindField::new(primitives);
        let bound = f.speed_bound();
        prop_assert!(bound <= sum_of_peaks(&f) * (1.0 + 1e-15));
        for (x, t) in &points {
            let g = f.velocity(x, *t).norm();
            prop_assert!(g <= bound * (1.0 + 1e-12) + 1e-12, "|G({x:?}, {t})| = {g} > {bound}");
        }
        // Where several regions' centres are, they may all act: their
        // centres are sampled too.
        for &(_, c, ..) in &regions {
            let g = f.velocity(&c, 1.0).norm();
            prop_assert!(g <= bound * (1.0 + 1e-12) + 1e-12, "|G({c:?})| = {g} > {bound}");
        }
    }
}
