//! Robust fitness: every individual is dropped from several release
//! attitudes, drawn from its own seed, and judged by the lower median of
//! their scores. A leaf selected on one drop is often a lucky leaf, not one
//! of its class: a lilter's likeness re-dropped from other tilts is mostly
//! noise (issue 19), so selection must see more than one release.

use super::population::Evaluation;
use super::selection::stream_seed;
use rand::RngExt;
use rand::SeedableRng;
use rand::rngs::Xoshiro256PlusPlus;

/// The generation slot of the release stream in [`stream_seed`]: release
/// attitudes depend on the run's seed and the individual's id only, so an
/// elite carried into a later generation keeps the drops it was judged on.
const RELEASE_STREAM: u64 = u64::MAX - 1;

/// Range of the release tilt from level, degrees: from the few degrees any
/// real release has to a steep 30° (the experiment's cards are dropped at
/// 2–60°, [`crate::leaf::plates::RELEASE_ATTITUDES`]; past 30° most leaves
/// start in a dive whose transient the classifier's window may not shed).
pub const RELEASE_TILT_DEG: [f64; 2] = [2.0, 30.0];

/// The `k` release attitudes of individual `id` (tilt about the body x and y
/// axes, degrees, as [`crate::sim::drop::DropParams::tilt_deg`]): tilt
/// uniform in [`RELEASE_TILT_DEG`] about an axis of uniform direction in
/// the leaf's plane. Deterministic in (seed, id).
pub fn release_attitudes(seed: u64, id: u64, k: usize) -> Vec<[f64; 2]> {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(stream_seed(seed, RELEASE_STREAM, id));
    (0..k)
        .map(|_| {
            let tilt = rng.random_range(RELEASE_TILT_DEG[0]..RELEASE_TILT_DEG[1]);
            let azimuth = rng.random_range(0.0..std::f64::consts::TAU);
            [tilt * azimuth.cos(), tilt * azimuth.sin()]
        })
        .collect()
}

/// The index of the representative drop among `scores`: the lower median,
/// the ⌊(K − 1)/2⌋-th lowest (ties by index), so that at least ⌈(K + 1)/2⌉
/// of the K drops score at least as well (3 of 4, 3 of 5). Lower rather
/// than midpoint: one lucky drop of four cannot lift a leaf, and the score
/// stays that of one real drop, whose fall can be shown and re-dropped.
pub fn lower_median(scores: &[f64]) -> usize {
    assert!(!scores.is_empty(), "at least one release");
    let mut order: Vec<usize> = (0..scores.len()).collect();
    order.sort_by(|&a, &b| scores[a].total_cmp(&scores[b]).then(a.cmp(&b)));
    order[(scores.len() - 1) / 2]
}

/// One individual's drops (one per release) as one evaluation: the lower
/// median's drop, with the number of releases, how many of them kept
/// the target class (`kept[k]` for drop k) and how far apart the drops
/// that fell came out ([`spread`]).
pub fn combine(mut drops: Vec<Evaluation>, kept: &[bool]) -> Evaluation {
    let scores: Vec<f64> = drops.iter().map(|e| e.score).collect();
    let k = lower_median(&scores);
    let releases = drops.len();
    let spread = spread(&drops);
    let mut chosen = drops.swap_remove(k);
    chosen.releases = releases;
    chosen.kept = kept.iter().filter(|&&b| b).count();
    chosen.spread = spread;
    chosen
}

/// The release-to-release spread of `drops` ([`Evaluation::spread`]):
/// max − min of descent speed, drift ratio and rotation rate over the
/// drops that fell; 0 where fewer than two fell. What "apart" is measured
/// against: a leaf whose releases scatter widely must move further to
/// fall visibly otherwise.
pub fn spread(drops: &[Evaluation]) -> [f64; 3] {
    let falls: Vec<[f64; 3]> = drops
        .iter()
        .filter_map(Evaluation::fall)
        .map(|f| [f.descent_m_s, f.drift_ratio, f.spin_rad_s])
        .collect();
    std::array::from_fn(|q| {
        let lo = falls.iter().map(|v| v[q]).fold(f64::INFINITY, f64::min);
        let hi = falls.iter().map(|v| v[q]).fold(f64::NEG_INFINITY, f64::max);
        if falls.len() < 2 { 0.0 } else { hi - lo }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn attitudes_are_per_individual_reproducible_and_within_range() {
        let a = release_attitudes(7, 3, 4);
        assert_eq!(a, release_attitudes(7, 3, 4));
        assert_ne!(a, release_attitudes(7, 4, 4));
        assert_ne!(a, release_attitudes(8, 3, 4));
        // The first k of a longer list are the same draws.
        assert_eq!(a[..], release_attitudes(7, 3, 6)[..4]);
        for id in 0..500 {
            for t in release_attitudes(1, id, 4) {
                let tilt = t[0].hypot(t[1]);
                assert!(
                    (RELEASE_TILT_DEG[0]..RELEASE_TILT_DEG[1] + 1e-12).contains(&tilt),
                    "{t:?}"
                );
            }
        }
    }

    #[test]
    fn the_lower_median_ignores_one_lucky_drop() {
        assert_eq!(lower_median(&[0.5]), 0);
        // Sorted 0.1, 0.2, 0.3, 1.9: the second lowest, 0.2 (index 0).
        assert_eq!(lower_median(&[0.2, 1.9, 0.1, 0.3]), 0);
        // Odd K: the median itself.
        assert_eq!(lower_median(&[3.0, 1.0, 2.0]), 2);
        // Ties: by index.
        assert_eq!(lower_median(&[1.0, 1.0, 1.0, 1.0]), 1);
        // Whatever the order, the chosen score has ≥ ⌈(K+1)/2⌉ at or above it.
        let s = [0.9, -1.0, 0.4, 1.5, 0.4, 2.0];
        let m = s[lower_median(&s)];
        assert!(s.iter().filter(|&&x| x >= m).count() >= (s.len() + 2) / 2);
    }
}
