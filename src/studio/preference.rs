//! A model of what the person prefers, fitted to their picks, that orders
//! the grid (Llorà et al. 2005 report 3–7× fewer judgements when a
//! surrogate of the user's taste orders what is shown; Sequential Gallery,
//! Koyama et al. 2020, fits one to each choice made).
//!
//! Every generation the person bred from is a set of judgements: the
//! candidates they picked are liked, the others on the same grid not. A
//! logistic model over each fall's numbers (descent, drift, rotation rate,
//! tilt, scaled by their spread across prototype A's variants, and the
//! class) is fitted to them by Newton's method with a Gaussian prior on
//! the weights (ridge): with a handful of judgements the prior keeps it
//! from reading a rule into one click. Its taste of a candidate is the
//! model's probability that the person would pick it. The machine's own
//! picks (Auto N, More like this) are not the person's and are left out.

use crate::breed::population::{Evaluation, Fall};
use crate::motion::classify::MotionClass;
use crate::motion::describe::SCALES;
use nalgebra::{DMatrix, DVector};

/// The numbers a fall is judged by: descent, drift, rotation rate and
/// tilt in units of [`SCALES`], then one indicator per class.
pub const FEATURES: usize = 7;

/// Precision of the Gaussian prior on each weight (in units of the
/// scaled features): one judgement moves a weight little, a consistent
/// dozen a lot.
const PRIOR_PRECISION: f64 = 1.0;

/// Newton steps: the log-likelihood is concave, so a few dozen reach
/// machine precision on a grid's worth of judgements; a fixed count keeps
/// the fit the same bytes on every machine.
const NEWTON_STEPS: usize = 30;

/// A fall's features, or none for a drop that diverged (it is never
/// shown as a leaf to like).
pub fn features(e: &Evaluation) -> Option<[f64; FEATURES]> {
    e.fall().map(of_fall)
}

fn of_fall(f: &Fall) -> [f64; FEATURES] {
    let class = |c: MotionClass| if f.class == c { 1.0 } else { 0.0 };
    [
        f.descent_m_s / SCALES[0],
        f.drift_ratio / SCALES[5],
        f.spin_rad_s / SCALES[1],
        f.tilt_deg / SCALES[8],
        class(MotionClass::Floater),
        class(MotionClass::Spinner),
        class(MotionClass::Lilter),
    ]
}

/// The fitted model.
#[derive(Clone, Debug, PartialEq)]
pub struct Preference {
    /// Weights of [`FEATURES`], then the bias.
    weights: [f64; FEATURES + 1],
    /// How many candidates were judged (picked or passed over).
    pub judgements: usize,
}

impl Preference {
    /// The model of `judgements` (a fall's features, and whether it was
    /// picked); none unless at least one was picked and one was not, as
    /// there is nothing to tell apart before.
    pub fn fit(judgements: &[([f64; FEATURES], bool)]) -> Option<Preference> {
        let liked = judgements.iter().filter(|(_, picked)| *picked).count();
        if liked == 0 || liked == judgements.len() {
            return None;
        }
        let n = FEATURES + 1;
        let x = DMatrix::from_fn(judgements.len(), n, |i, j| {
            if j < FEATURES {
                judgements[i].0[j]
            } else {
                1.0
            }
        });
        let y = DVector::from_iterator(
            judgements.len(),
            judgements.iter().map(|(_, p)| if *p { 1.0 } else { 0.0 }),
        );
        let mut w = DVector::<f64>::zeros(n);
        // The bias is not pulled toward 0: the prior is on the weights.
        let prior = DMatrix::from_fn(n, n, |i, j| {
            if i == j && i < FEATURES {
                PRIOR_PRECISION
            } else {
                0.0
            }
        });
        for _ in 0..NEWTON_STEPS {
            let p = (&x * &w).map(sigmoid);
            let gradient = x.transpose() * (&y - &p) - &prior * &w;
            let curvature =
                DMatrix::from_fn(judgements.len(), n, |i, j| x[(i, j)] * p[i] * (1.0 - p[i]));
            let hessian = x.transpose() * curvature + &prior;
            // Positive definite (the prior's diagonal plus a Gram matrix,
            // with the bias's column kept apart by at least one 0 and one
            // 1 label), so Cholesky holds; if it does not, stop where it is.
            match hessian.cholesky() {
                Some(c) => w += c.solve(&gradient),
                None => break,
            }
        }
        let mut weights = [0.0; FEATURES + 1];
        weights.copy_from_slice(w.as_slice());
        weights.iter().all(|v| v.is_finite()).then_some(Preference {
            weights,
            judgements: judgements.len(),
        })
    }

    /// The probability that the person picks a fall with these features.
    pub fn taste_of(&self, x: &[f64; FEATURES]) -> f64 {
        let z: f64 = x.iter().zip(&self.weights).map(|(a, b)| a * b).sum();
        sigmoid(z + self.weights[FEATURES])
    }

    /// [`Preference::taste_of`] a candidate's fall; none for a diverged one.
    pub fn taste(&self, e: &Evaluation) -> Option<f64> {
        features(e).map(|x| self.taste_of(&x))
    }
}

fn sigmoid(z: f64) -> f64 {
    1.0 / (1.0 + (-z).exp())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn leaf(descent: f64, drift: f64, class: usize) -> [f64; FEATURES] {
        let mut x = [
            descent / SCALES[0],
            drift / SCALES[5],
            1.0,
            0.5,
            0.0,
            0.0,
            0.0,
        ];
        x[4 + class] = 1.0;
        x
    }

    /// Nothing to tell apart: no model.
    #[test]
    fn no_model_without_both_a_pick_and_a_pass() {
        let all = [(leaf(1.0, 0.1, 0), true), (leaf(1.2, 0.2, 1), true)];
        assert!(Preference::fit(&all).is_none());
        let none = [(leaf(1.0, 0.1, 0), false)];
        assert!(Preference::fit(&none).is_none());
        assert!(Preference::fit(&[]).is_none());
    }

    /// A person who picks the slow fallers of three grids: the model's
    /// taste falls with descent speed whatever the drift and class, and
    /// ranks every slow leaf of a fresh grid above every fast one.
    #[test]
    fn picks_of_slow_leaves_teach_a_taste_for_slow_leaves() {
        let mut judgements = Vec::new();
        for g in 0..3 {
            for k in 0..12 {
                let descent = 0.4 + 0.1 * ((k * 7 + g * 5) % 12) as f64;
                let drift = 0.05 * ((k * 5 + g) % 7) as f64;
                judgements.push((leaf(descent, drift, k % 3), descent < 0.75));
            }
        }
        let model = Preference::fit(&judgements).unwrap();
        assert_eq!(model.judgements, 36);
        for class in 0..3 {
            for drift in [0.0, 0.15, 0.3] {
                let tastes: Vec<f64> = (0..10)
                    .map(|k| model.taste_of(&leaf(0.3 + 0.12 * k as f64, drift, class)))
                    .collect();
                assert!(
                    tastes.windows(2).all(|w| w[0] > w[1]),
                    "class {class}, drift {drift}: {tastes:?}"
                );
            }
        }
        let slow = (0..6).map(|k| leaf(0.45 + 0.05 * k as f64, 0.1, k % 3));
        let fast = (0..6).map(|k| leaf(0.85 + 0.1 * k as f64, 0.1, k % 3));
        let worst_slow = slow.map(|x| model.taste_of(&x)).fold(1.0, f64::min);
        let best_fast = fast.map(|x| model.taste_of(&x)).fold(0.0, f64::max);
        assert!(worst_slow > best_fast, "{worst_slow} vs {best_fast}");
    }

    /// One pick among twelve is a weak hint: the prior keeps every taste
    /// well inside (0, 1) rather than certain.
    #[test]
    fn one_judgement_is_not_a_certainty() {
        let judgements: Vec<_> = (0..12)
            .map(|k| (leaf(0.5 + 0.1 * k as f64, 0.1, k % 3), k == 0))
            .collect();
        let model = Preference::fit(&judgements).unwrap();
        for (k, (x, _)) in judgements.iter().enumerate() {
            let t = model.taste_of(x);
            assert!((0.01..0.9).contains(&t), "leaf {k}: {t}");
        }
    }
}
