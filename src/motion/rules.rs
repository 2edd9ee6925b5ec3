//! The rule machinery the classifiers share: conditions `feature ≥
//! threshold` (or `<`) with a natural scale, ordered rules of which the first
//! whose conditions all hold decides, and margins: how far, in scale units,
//! a decision is from the nearest class (or regime) boundary.

use crate::motion::class::{MotionClass, Regime};

/// One `feature ≥ threshold` (or `<`) test with its scale for margins.
pub(crate) struct Cond {
    pub(crate) value: f64,
    pub(crate) threshold: f64,
    pub(crate) scale: f64,
    pub(crate) at_least: bool,
    /// Failing it would change the class (not just the regime).
    pub(crate) class_boundary: bool,
}

impl Cond {
    pub(crate) fn ge(value: f64, threshold: f64, scale: f64) -> Self {
        Self {
            value,
            threshold,
            scale,
            at_least: true,
            class_boundary: true,
        }
    }
    pub(crate) fn lt(value: f64, threshold: f64, scale: f64) -> Self {
        Self {
            at_least: false,
            ..Self::ge(value, threshold, scale)
        }
    }
    pub(crate) fn regime_only(self) -> Self {
        Self {
            class_boundary: false,
            ..self
        }
    }
    pub(crate) fn holds(&self) -> bool {
        if self.at_least {
            self.value >= self.threshold
        } else {
            self.value < self.threshold
        }
    }
    /// Signed distance to the threshold in scale units, > 0 when it holds.
    pub(crate) fn slack(&self) -> f64 {
        let d = (self.value - self.threshold) / self.scale;
        if self.at_least { d } else { -d }
    }
}

/// A rule: when all its conditions hold (and no earlier rule fired), the
/// fall is of its class and regime.
pub(crate) struct Rule<Id> {
    pub(crate) id: Id,
    pub(crate) class: MotionClass,
    pub(crate) regime: Regime,
    pub(crate) conds: Vec<Cond>,
}

impl<Id> Rule<Id> {
    pub(crate) fn fires(&self) -> bool {
        self.conds.iter().all(Cond::holds)
    }
    /// Distance to firing: every condition must be met, so the largest deficit.
    pub(crate) fn deficit(&self) -> f64 {
        self.conds
            .iter()
            .map(|c| (-c.slack()).max(0.0))
            .fold(0.0, f64::max)
    }
}

/// (class margin, regime margin) of rule `k` of `rules` having fired: the
/// smallest of the slacks of its conditions (those on a class boundary for
/// the class margin) and the distances to every earlier rule (of another
/// class for the class margin), clipped to [0, 1].
pub(crate) fn margins<Id>(rules: &[Rule<Id>], k: usize) -> (f64, f64) {
    let chosen = &rules[k];
    let own = |class_only: bool| {
        chosen
            .conds
            .iter()
            .filter(|c| !class_only || c.class_boundary)
            .map(Cond::slack)
            .fold(f64::INFINITY, f64::min)
    };
    let earlier = |class_only: bool| {
        rules[..k]
            .iter()
            .filter(|r| !class_only || r.class != chosen.class)
            .map(Rule::deficit)
            .fold(f64::INFINITY, f64::min)
    };
    (
        own(true).min(earlier(true)).clamp(0.0, 1.0),
        own(false).min(earlier(false)).clamp(0.0, 1.0),
    )
}
