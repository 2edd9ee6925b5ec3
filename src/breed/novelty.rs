//! Breeding toward a class past the class (issue 60): once leaves hold the
//! target class robustly, the score rewards falling differently from the
//! others that hold it.
//!
//! Why: toward a class the score is 1 + the classifier's margin, and the
//! margin is clipped at 1. It saturates: `breed --target spinner
//! --population 40` had 31 of 40 leaves tied at 2 in generation 1 and 38–39
//! from generation 2 on, so the "best five" were arbitrary (once, unvaried
//! copies of the prototype) and nothing after the class was reached made
//! the leaves better or more varied. What an animator then chooses between
//! is leaves of the class that fall differently. So, as novelty search
//! rewards being different where an objective gives no gradient (Lehman &
//! Stanley, "Abandoning objectives", Evolutionary Computation 19(2), 2011),
//! a leaf that [`holds`] the class gets 2 + n / (1 + n), n its novelty: the
//! mean [`distance`] to its [`NEIGHBOURS`] nearest among the other leaves of
//! the generation that hold it. Below saturation nothing changes: the score
//! still ranks leaves toward the class and by margin within it, and every
//! leaf that holds the class outranks every one that does not. Selection
//! then spreads the class's robust members over descent, drift and spin, as
//! MAP-Elites (Mouret & Clune 2015, [`super::archive`]) spreads an archive
//! over cells, but within the generation and with no grid to choose.
//!
//! Distances are in units of the two leaves' release-to-release spread
//! ([`Evaluation::spread`]): 1 means "as far apart as their releases
//! scatter", so novelty cannot be bought with a leaf whose releases
//! scatter widely, and `best/` takes leaves pairwise [`apart`]
//! ([`distinct`]). Everything is a function of the generation's members in
//! id order, computed where the generation is finished: the same bytes with
//! any thread count, any executor and after a resume.
//!
//! [`Evaluation::spread`]: super::population::Evaluation::spread

use super::population::{Fall, Individual};
use crate::motion::classify::MotionClass;
use crate::motion::describe::SCALES;

/// How many nearest leaves a leaf's novelty averages over (Lehman &
/// Stanley used 15 in populations of 250; a breed's 40–100 leaves hold
/// fewer of the class).
pub const NEIGHBOURS: usize = 3;

/// The least spread a distance divides by, per descriptor of
/// [`Evaluation::spread`](super::population::Evaluation::spread): a
/// hundredth of the descriptor's scale across prototype A's variants
/// ([`SCALES`]: descent, drift, spin), so that two leaves whose releases
/// all fall alike are not infinitely far apart for a hair's difference.
pub const SPREAD_FLOOR: [f64; 3] = [SCALES[0] / 100.0, SCALES[5] / 100.0, SCALES[1] / 100.0];

/// A margin at least this is at its top, 1, as far as selection can tell:
/// within a thousandth of the classifier's scale unit. The margin reaches
/// its clip from below as a feature nears its physical ceiling (a ratio
/// of 1): 0.9999944–0.9999993 for the 24 spinners of `breed --target
/// spinner --population 24 --generations 5 --seconds 4`, seed 1991,
/// generation 4, of which 18–22 per generation tied at the score table's
/// four decimals; a few units in the last place below 1 after 10 s falls.
pub const SATURATED: f64 = 0.999;

/// Whether `leaf` is of `target` robustly: its recorded drop is of the
/// class, and every one of its releases kept it.
pub fn robust(leaf: &Individual, target: MotionClass) -> bool {
    leaf.eval.fall().is_some_and(|f| f.class == target) && leaf.eval.kept == leaf.eval.releases
}

/// Whether `leaf` holds `target`: [`robust`]ly, with the margin at its top
/// ([`SATURATED`]: the score saturated at 2). Only such leaves are
/// rescored, and rescoring lifts them all to 2 or above, where no other leaf can
/// reach.
pub fn holds(leaf: &Individual, target: MotionClass) -> bool {
    robust(leaf, target) && leaf.eval.fall().is_some_and(|f| f.margin >= SATURATED)
}

fn values(f: &Fall) -> [f64; 3] {
    [f.descent_m_s, f.drift_ratio, f.spin_rad_s]
}

/// Per descriptor (descent, drift, spin), how far apart two falls are in
/// units of their spreads: |a − b| / (spread_a + spread_b + floor). Above
/// 1, their ranges over their releases do not overlap. Infinite when one
/// diverged.
pub fn separation(a: &Individual, b: &Individual) -> [f64; 3] {
    match (a.eval.fall(), b.eval.fall()) {
        (Some(fa), Some(fb)) => {
            let (va, vb) = (values(fa), values(fb));
            std::array::from_fn(|q| {
                (va[q] - vb[q]).abs() / (a.eval.spread[q] + b.eval.spread[q] + SPREAD_FLOOR[q])
            })
        }
        _ => [f64::INFINITY; 3],
    }
}

/// Whether two leaves fall visibly apart: in at least one of descent,
/// drift and spin by more than their release-to-release spreads together.
pub fn apart(a: &Individual, b: &Individual) -> bool {
    separation(a, b).iter().any(|&z| z > 1.0)
}

/// The novelty distance of two leaves: the Euclidean norm of their
/// [`separation`].
pub fn distance(a: &Individual, b: &Individual) -> f64 {
    separation(a, b).iter().map(|z| z * z).sum::<f64>().sqrt()
}

/// Rescores the members of a generation that [`holds`] `target`: 2 + n /
/// (1 + n), n the mean distance to the [`NEIGHBOURS`] nearest of the others
/// that hold it (infinite, a score of 3, for the only one). The others keep
/// their scores. Depends on the members alone, so elites carried over are
/// rescored among the new generation, and again the same on resume.
pub fn rescore(population: &mut [Individual], target: MotionClass) {
    let holders: Vec<usize> = (0..population.len())
        .filter(|&k| holds(&population[k], target))
        .collect();
    let scores: Vec<f64> = holders
        .iter()
        .map(|&a| {
            let mut d: Vec<f64> = holders
                .iter()
                .filter(|&&b| b != a)
                .map(|&b| distance(&population[a], &population[b]))
                .collect();
            d.sort_by(f64::total_cmp);
            let near = &d[..d.len().min(NEIGHBOURS)];
            let n = if near.is_empty() {
                f64::INFINITY
            } else {
                near.iter().sum::<f64>() / near.len() as f64
            };
            3.0 - 1.0 / (1.0 + n)
        })
        .collect();
    for (&k, s) in holders.iter().zip(scores) {
        population[k].eval.score = s;
    }
}

/// The leaves, taken in the order given (best first), that are of `target`
/// [`robust`]ly and fall [`apart`] from every one taken before: at most
/// `most`. What `best/` holds, and (counted over a whole generation) the
/// `distinct` column of `generations.csv`. Robust rather than holding: a
/// class whose margin never saturates (floaters from prototype A top out
/// near 0.98) still gets leaves that differ.
pub fn distinct<'a>(
    ranked: &[&'a Individual],
    target: MotionClass,
    most: usize,
) -> Vec<&'a Individual> {
    let mut chosen: Vec<&Individual> = Vec::new();
    for &leaf in ranked {
        if chosen.len() >= most {
            break;
        }
        if robust(leaf, target) && chosen.iter().all(|c| apart(c, leaf)) {
            chosen.push(leaf);
        }
    }
    chosen
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::breed::population::{Evaluation, Outcome};
    use crate::leaf::genome::Genome;
    use crate::motion::classify::Regime;

    fn leaf(id: u64, class: MotionClass, margin: f64, kept: usize, x: [f64; 3]) -> Individual {
        Individual {
            id,
            parent: None,
            elite: false,
            genome: Genome::of_prototype(&crate::leaf::LeafSpec::load("a").unwrap()),
            eval: Evaluation {
                outcome: Outcome::Fell(Fall {
                    class,
                    regime: Regime::Undetermined,
                    margin,
                    descent_m_s: x[0],
                    drift_ratio: x[1],
                    net_turns: 0.0,
                    yaw_turns: 0.0,
                    spin_rad_s: x[2],
                    reversals: 0,
                    flips: 0,
                    tilt_deg: 0.0,
                    dt: 1e-3,
                }),
                score: 1.0 + margin,
                distance: None,
                releases: 4,
                kept,
                release_deg: [0.0; 2],
                residuals: Vec::new(),
                spread: [0.1, 0.01, 0.5],
            },
        }
    }

    const S: MotionClass = MotionClass::Spinner;

    #[test]
    fn only_robust_saturated_members_are_rescored_and_they_stay_on_top() {
        let mut p = vec![
            leaf(0, S, 1.0, 4, [1.0, 0.1, 10.0]),
            leaf(1, S, 1.0, 4, [1.05, 0.1, 10.0]),
            leaf(2, S, 1.0, 4, [2.0, 0.3, 20.0]),
            leaf(3, S, 1.0, 3, [5.0, 0.9, 40.0]),
            leaf(4, S, 0.4, 4, [5.0, 0.9, 40.0]),
            leaf(5, MotionClass::Floater, 1.0, 0, [0.3, 0.0, 0.1]),
        ];
        p[5].eval.score = 0.5;
        let before: Vec<f64> = p.iter().map(|i| i.eval.score).collect();
        rescore(&mut p, S);
        for k in 3..6 {
            assert_eq!(
                p[k].eval.score, before[k],
                "leaf {k} does not hold the class"
            );
        }
        for holder in &p[..3] {
            let s = holder.eval.score;
            assert!((2.0..3.0).contains(&s), "{s}");
        }
        // The one far from the other two ranks first; the near pair,
        // mutual nearest neighbours, below it.
        assert!(p[2].eval.score > p[0].eval.score && p[2].eval.score > p[1].eval.score);
        // Rescoring again (an elite next generation, a resume) changes nothing.
        let once: Vec<f64> = p.iter().map(|i| i.eval.score).collect();
        rescore(&mut p, S);
        assert_eq!(once, p.iter().map(|i| i.eval.score).collect::<Vec<_>>());
        // A lone holder is as novel as can be.
        let mut lone = vec![leaf(0, S, 1.0, 4, [1.0, 0.1, 10.0])];
        rescore(&mut lone, S);
        assert_eq!(lone[0].eval.score, 3.0);
    }

    #[test]
    fn apart_means_beyond_both_spreads_in_one_descriptor() {
        let a = leaf(0, S, 1.0, 4, [1.0, 0.1, 10.0]);
        // Descent 0.2 apart, spreads 0.1 + 0.1 + floor: not apart.
        let b = leaf(1, S, 1.0, 4, [1.2, 0.1, 10.0]);
        assert!(!apart(&a, &b));
        // Spin 1.2 apart, spreads 0.5 + 0.5 + 0.071: apart.
        let c = leaf(2, S, 1.0, 4, [1.0, 0.1, 11.2]);
        assert!(apart(&a, &c) && apart(&c, &a));
        let ranked = [&a, &b, &c];
        let chosen: Vec<u64> = distinct(&ranked, S, 5).iter().map(|i| i.id).collect();
        assert_eq!(chosen, [0, 2]);
        assert_eq!(distinct(&ranked, S, 1).len(), 1);
        // Robust is enough; a release lost is not.
        let mut d = leaf(3, S, 0.5, 4, [1.0, 0.1, 20.0]);
        assert_eq!(distinct(&[&a, &d], S, 5).len(), 2);
        d.eval.kept = 3;
        assert_eq!(distinct(&[&a, &d], S, 5).len(), 1);
        assert!(distinct(&ranked, MotionClass::Floater, 5).is_empty());
    }
}
