//! How far a fall is from the boundary of a class it is not in: the graded
//! part of the selection score ([`super::evaluate::score`]).
//!
//! The classifier names a fall by ordered rules of conditions
//! `feature ≥ threshold` (or `<`), each with a natural scale
//! ([`crate::motion::classify`], module docs, "Method" and "Margin"). The
//! *slack* of a condition is (feature − threshold) / scale, positive when it
//! holds. For a rule k of the target class C,
//!
//! - its **deficit** is the largest missing slack over its conditions,
//!   max_c max(0, −slack_c): all of them must hold for it to fire;
//! - an earlier rule j of another class that fires would decide first: its
//!   **break cost** is the smallest slack over its conditions,
//!   min_c slack_c (one failing condition stops it).
//!
//! The distance to class C is then
//!
//! D_C = min over rules k of class C of max(deficit_k, max over earlier rules
//! j of another class that fire of break_j),
//!
//! in the classifier's scale units (the same units as its margin): 0 for a
//! fall of class C, and the largest single-condition move, in scale units,
//! that the nearest route into C needs otherwise. Conditions are treated as
//! independent (features are in fact coupled), which is what makes D_C a
//! guide for selection and not an exact distance in feature space.
//!
//! The rule table is mirrored here from the classifier's module docs (rules
//! 1–11, same thresholds and scales, the constants it exports); a test holds
//! the mirror to the classifier on the falls of `tests/data/mujoco-falls/`
//! and on bred leaves: D is 0 for the class the classifier names.

use crate::motion::classify::{
    AUTOROTATION_MIN_TILT_DEG, AUTOROTATION_MIN_VERTICAL_SHARE, AUTOROTATION_MIN_YAW_CONSISTENCY,
    AUTOROTATION_MIN_YAW_TURNS, DIVE_MIN_TILT_DEG, FLIP_HYSTERESIS_DEG, FLUTTER_MIN_AMPLITUDE_DEG,
    Features, GLIDE_MIN_DRIFT_RATIO, LILT_MIN_REVERSALS, MAX_GAP_S, MAX_SAMPLE_TURN_DEG,
    MIN_DESCENT_CHORDS, MIN_OSCILLATION_PERIODS, MotionClass, SPIN_MIN_NET_TURNS, STEEP_TILT_DEG,
    TUMBLE_MIN_CONSISTENCY, window_is_long_enough,
};

/// One condition: its slack in scale units (> 0 when it holds).
#[derive(Clone, Copy, Debug)]
struct Slack(f64);

fn ge(value: f64, threshold: f64, scale: f64) -> Slack {
    Slack((value - threshold) / scale)
}

fn lt(value: f64, threshold: f64, scale: f64) -> Slack {
    Slack((threshold - value) / scale)
}

impl Slack {
    /// `≥` conditions hold at slack 0, `<` conditions only above it; at the
    /// scale of a selection score the difference is immaterial, so a
    /// condition is taken to hold at slack ≥ 0.
    fn holds(self) -> bool {
        self.0 >= 0.0
    }
}

/// The classifier's rules as (class, condition slacks), in its order.
fn rules(f: &Features) -> [(MotionClass, Vec<Slack>); 11] {
    use MotionClass as C;
    let flip_progress = if f.normal_flips > 0 {
        f.normal_flips as f64
    } else {
        (f.max_excursion_deg / (90.0 + FLIP_HYSTERESIS_DEG)).min(0.99)
    };
    let reversals = f.reversals as f64;
    let lilt_rev = LILT_MIN_REVERSALS as f64;
    let rocking = || ge(f.rocking_amplitude_deg, FLUTTER_MIN_AMPLITUDE_DEG, 10.0);
    [
        (
            C::Spinner,
            vec![
                ge(f.net_turns, SPIN_MIN_NET_TURNS, 1.0),
                ge(f.rotation_consistency, TUMBLE_MIN_CONSISTENCY, 0.1),
                lt(f.vertical_spin_share, AUTOROTATION_MIN_VERTICAL_SHARE, 0.3),
            ],
        ),
        (
            C::Spinner,
            vec![
                ge(f.yaw_turns.abs(), AUTOROTATION_MIN_YAW_TURNS, 1.0),
                ge(f.yaw_consistency, AUTOROTATION_MIN_YAW_CONSISTENCY, 0.1),
                ge(f.vertical_spin_share, AUTOROTATION_MIN_VERTICAL_SHARE, 0.3),
                ge(f.tilt_mean_deg, AUTOROTATION_MIN_TILT_DEG, 30.0),
            ],
        ),
        (
            C::Lilter,
            vec![
                ge(flip_progress, 1.0, 1.0),
                ge(reversals, lilt_rev, lilt_rev),
            ],
        ),
        (
            C::Undetermined,
            vec![
                ge(flip_progress, 1.0, 1.0),
                lt(reversals, lilt_rev, lilt_rev),
            ],
        ),
        (
            C::Undetermined,
            vec![ge(f.tilt_p10_deg, DIVE_MIN_TILT_DEG, 30.0)],
        ),
        (
            C::Floater,
            vec![
                rocking(),
                ge(
                    f.oscillation_periods,
                    MIN_OSCILLATION_PERIODS,
                    MIN_OSCILLATION_PERIODS,
                ),
                lt(f.tilt_p10_deg, STEEP_TILT_DEG, 30.0),
            ],
        ),
        (
            C::Undetermined,
            vec![
                rocking(),
                lt(
                    f.oscillation_periods,
                    MIN_OSCILLATION_PERIODS,
                    MIN_OSCILLATION_PERIODS,
                ),
            ],
        ),
        (
            C::Undetermined,
            vec![rocking(), ge(f.tilt_p10_deg, STEEP_TILT_DEG, 30.0)],
        ),
        (
            C::Undetermined,
            vec![
                ge(f.tilt_mean_deg, STEEP_TILT_DEG, 30.0),
                lt(f.rocking_amplitude_deg, FLUTTER_MIN_AMPLITUDE_DEG, 10.0),
            ],
        ),
        // Glide and steady: floaters whatever the drift.
        (
            C::Floater,
            vec![ge(
                f.drift_ratio,
                GLIDE_MIN_DRIFT_RATIO,
                GLIDE_MIN_DRIFT_RATIO,
            )],
        ),
        (C::Floater, vec![]),
    ]
}

/// Whether the classifier's rules ran on these features: a record with too
/// few samples, a gap or too little descent is undetermined before any rule
/// (classifier, "Method", step 2), and has no distance to any class.
pub fn decided(f: &Features) -> bool {
    window_is_long_enough(f)
        && f.max_gap_s <= MAX_GAP_S
        && f.max_sample_turn_deg <= MAX_SAMPLE_TURN_DEG
        && f.descent_chords >= MIN_DESCENT_CHORDS
}

/// D_C of the module docs: the distance, in the classifier's scale units, of
/// a fall with features `f` to the boundary of class `target` (0 inside it);
/// `None` when the rules did not run ([`decided`]) or `target` is
/// undetermined.
pub fn class_distance(f: &Features, target: MotionClass) -> Option<f64> {
    if target == MotionClass::Undetermined || !decided(f) {
        return None;
    }
    let rules = rules(f);
    let mut blocking = 0.0f64;
    let mut best = f64::INFINITY;
    for (class, conds) in &rules {
        if *class == target {
            let deficit = conds.iter().map(|s| (-s.0).max(0.0)).fold(0.0, f64::max);
            best = best.min(deficit.max(blocking));
        } else if conds.iter().all(|s| s.holds()) {
            let cost = conds.iter().map(|s| s.0).fold(f64::INFINITY, f64::min);
            blocking = blocking.max(cost);
        }
    }
    best.is_finite().then_some(best)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn window() -> Features {
        Features {
            samples: 1000,
            max_gap_s: 1.0 / 240.0,
            descent_chords: 100.0,
            ..Features::default()
        }
    }

    #[test]
    fn a_still_flat_fall_is_a_floater_and_one_turn_from_a_spinner() {
        let f = window();
        assert_eq!(class_distance(&f, MotionClass::Floater), Some(0.0));
        // Tumble needs 1 net turn (scale 1) and consistency 0.9 (scale 0.1):
        // 9 scale units of consistency are missing, the largest deficit.
        let d = class_distance(&f, MotionClass::Spinner).unwrap();
        assert!((d - 9.0).abs() < 1e-12, "{d}");
        // Lilter: one flip (progress 0 → 1, scale 1) and 2 reversals (scale 2).
        let d = class_distance(&f, MotionClass::Lilter).unwrap();
        assert!((d - 1.0).abs() < 1e-12, "{d}");
    }

    #[test]
    fn closer_to_the_boundary_is_closer() {
        let mut f = window();
        f.normal_flips = 1;
        f.reversals = 1;
        // One flip, one reversal: rule 4 (undetermined) fires; the lilter
        // rule misses half a scale of reversals.
        let d1 = class_distance(&f, MotionClass::Lilter).unwrap();
        assert!((d1 - 0.5).abs() < 1e-12, "{d1}");
        f.reversals = 2;
        assert_eq!(class_distance(&f, MotionClass::Lilter), Some(0.0));
        // A lilter is a floater only once the lilt rule stops firing: two
        // flips and four reversals are one scale unit past both thresholds.
        f.normal_flips = 2;
        f.reversals = 4;
        let d = class_distance(&f, MotionClass::Floater).unwrap();
        assert!((d - 1.0).abs() < 1e-12, "{d}");
    }

    /// The class of the first rule that fires in the mirror.
    fn mirrored_class(f: &Features) -> MotionClass {
        rules(f)
            .into_iter()
            .find(|(_, conds)| conds.iter().all(|s| s.holds()))
            .map_or(MotionClass::Floater, |(c, _)| c)
    }

    /// The mirror is the classifier: on the MuJoCo falls and on drops of
    /// varied prototypes its first firing rule names the classifier's class,
    /// D is 0 for that class and positive for the others.
    #[test]
    fn the_mirror_names_the_classifiers_class_on_real_and_bred_falls() {
        use crate::leaf::LeafSpec;
        use crate::leaf::genome::{Genome, mutate};
        use crate::motion::classify::classify;
        use crate::motion::trajectory::Trajectory;
        use crate::sim::drop::{DropParams, drop_leaf};
        use rand::SeedableRng;
        let mut falls = Vec::new();
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/mujoco-falls");
        for name in [
            "steady_fall.csv",
            "glide_ballast.csv",
            "wobble_card.csv",
            "flutter_strip.csv",
            "tumble_thick.csv",
            "tumble_cardscoef.csv",
        ] {
            let t = Trajectory::read_csv(&dir.join(name)).unwrap();
            falls.push((name.to_string(), classify(&t, 0.04)));
        }
        for p in ["a", "b"] {
            let proto = LeafSpec::load(p).unwrap();
            let g = Genome::of_prototype(&proto);
            for seed in 0..12 {
                let mut rng = rand::rngs::Xoshiro256PlusPlus::seed_from_u64(seed);
                let v = mutate(&g, &proto.bounds, 1.5, &mut rng);
                let model = v.model(&proto).unwrap();
                let params = DropParams {
                    seconds: 6.0,
                    ..Default::default()
                };
                let Ok(r) = drop_leaf(&model, &params) else {
                    continue;
                };
                falls.push((
                    format!("{p} seed {seed}"),
                    classify(&r.trajectory, model.chord()),
                ));
            }
        }
        let mut seen = std::collections::BTreeSet::new();
        for (name, c) in &falls {
            let f = &c.features;
            if !decided(f) {
                continue;
            }
            seen.insert(c.class.as_str());
            assert_eq!(mirrored_class(f), c.class, "{name}");
            if c.class != MotionClass::Undetermined {
                assert_eq!(class_distance(f, c.class), Some(0.0), "{name}");
            }
            for other in [
                MotionClass::Floater,
                MotionClass::Spinner,
                MotionClass::Lilter,
            ] {
                if other != c.class {
                    let d = class_distance(f, other).unwrap();
                    assert!(d > 0.0, "{name}: {} is {d} from {other}", c.class);
                }
            }
        }
        assert!(seen.len() >= 3, "the falls cover too few classes: {seen:?}");
    }

    #[test]
    fn an_insufficient_record_has_no_distance() {
        let f = Features::default();
        assert_eq!(class_distance(&f, MotionClass::Floater), None);
        assert_eq!(class_distance(&window(), MotionClass::Undetermined), None);
    }
}
