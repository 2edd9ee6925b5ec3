//! Keyframed strength: the paper's time-varying fields (section 2.2, "the
//! strengths may vary with time"), as a multiplier k(t) of one primitive.

use serde::{Deserialize, Serialize};

use super::error::FieldError;

/// How [`Keyframes`] are interpolated between keys.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Interpolation {
    /// Straight line between neighbouring keys (the default).
    #[default]
    Linear,
    /// Hold each key's value until the next key.
    Step,
}

/// Time-varying strength multiplier: keys (time s, multiplier), times
/// strictly increasing. Before the first key the first value holds, after the
/// last key the last value holds.
///
/// In TOML: `keys = [[t, k], ...]` and optional `interpolation` on the
/// primitive's table.
#[derive(Clone, Debug, PartialEq)]
pub struct Keyframes {
    /// (time, multiplier) pairs, strictly increasing in time.
    pub keys: Vec<(f64, f64)>,
    /// Interpolation between keys.
    pub interpolation: Interpolation,
}

impl Keyframes {
    /// Multiplier at time `t`. An empty key list (rejected by validation) gives 1.
    #[inline]
    pub fn value(&self, t: f64) -> f64 {
        let keys = &self.keys;
        let (Some(&(t_first, v_first)), Some(&(t_last, v_last))) = (keys.first(), keys.last())
        else {
            return 1.0;
        };
        // NaN (a clock gone wrong) takes the first key rather than an index
        // off the end.
        if t.is_nan() || t <= t_first {
            return v_first;
        }
        if t >= t_last {
            return v_last;
        }
        // First key strictly after t; 1 ≤ i < len because t_first < t < t_last.
        let i = keys.partition_point(|&(tk, _)| tk <= t);
        let (t0, v0) = keys[i - 1];
        let (t1, v1) = keys[i];
        match self.interpolation {
            Interpolation::Step => v0,
            Interpolation::Linear => v0 + (v1 - v0) * ((t - t0) / (t1 - t0)),
        }
    }

    /// Largest |multiplier| over all time (both interpolations stay within the keys).
    pub fn max_abs(&self) -> f64 {
        self.keys.iter().fold(0.0, |m, &(_, v)| m.max(v.abs()))
    }

    /// Checks the keys; items are named `keys` (the list) or `keys[i]`.
    pub(super) fn validate(&self) -> Result<(), FieldError> {
        if self.keys.is_empty() {
            return Err(FieldError::new(
                "keys",
                "empty keyframe list (omit `keys` for constant strength)",
            ));
        }
        for (i, &(t, v)) in self.keys.iter().enumerate() {
            let item = format!("keys[{i}]");
            if !t.is_finite() || !v.is_finite() {
                return Err(FieldError::new(item, format!("non-finite key ({t}, {v})")));
            }
            if i > 0 {
                let prev = self.keys[i - 1].0;
                if t <= prev {
                    return Err(FieldError::new(
                        item,
                        format!("time {t} is not after the previous key's time {prev}"),
                    ));
                }
            }
        }
        Ok(())
    }
}
