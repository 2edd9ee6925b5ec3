//! What a work-precision sweep runs: each integrator's steps and the
//! reference's, and the default sweep for a model, set by its predicted
//! stable steps and by what each curve can show at what cost
//! (docs/design/numerics.md, "Error against work").

use super::error::AccuracyError;
use crate::physics::model::Model;
use crate::physics::params::Integrator;
use crate::physics::stability;
use serde::Serialize;

/// Timed runs per point (the median is reported); at least 5
/// (docs/design/numerics.md, "Error against work", step 1).
pub const DEFAULT_RUNS: usize = 5;
/// The most steps any single run of a default sweep may take, so that a
/// stiff model cannot make the sweep run for hours.
pub const MAX_STEPS_LOG2: u32 = 22;
/// The implicit scheme's default sweep stops at this step, s (2⁻¹⁹ s: on
/// prototype A the error is then ≈ 5e-7 chords after 1 s).
pub const IMPLICIT_MIN_STEP: f64 = 1.0 / 524_288.0;

/// Which steps one integrator is swept over: h = T/2^j for j in
/// `j_min..=j_max`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct SweepRange {
    /// The integrator.
    pub integrator: Integrator,
    /// Smallest j (largest h).
    pub j_min: u32,
    /// Largest j (smallest h).
    pub j_max: u32,
}

/// Settings of a work-precision sweep.
#[derive(Clone, Debug, PartialEq)]
pub struct SweepSettings {
    /// Simulated duration T, s.
    pub seconds: f64,
    /// Timed runs per point; the median wall time is reported.
    pub runs: usize,
    /// Steps per integrator.
    pub ranges: Vec<SweepRange>,
    /// The reference is RK4 at T/2^`reference_j`, checked against T/2^(j+1).
    pub reference_j: u32,
    /// Halve the reference's step until it validates against the errors
    /// plotted (or reaches round-off, or 2^[`MAX_STEPS_LOG2`] steps); off
    /// keeps exactly `reference_j`.
    pub refine_reference: bool,
    /// Seconds the refinement may spend in all: a halving that would take
    /// it past this is not started (each costs twice the last).
    pub refine_budget_s: f64,
    /// Bisect the step count between the largest stable and the smallest
    /// diverged step of each scheme.
    pub locate_limits: bool,
}

/// How many halvings each integrator gets below its first point in the
/// default sweep. The first point is about 4 × the scheme's predicted limit
/// (so the curve starts with its diverged points). The counts are set by
/// cost and by what the curve can show, measured on prototype A over 1 s:
/// euler and symplectic stop near 2^20 steps (≈ 0.3 s a run; they reach
/// only 1e-5 … 1e-6, the table extrapolates the rest), verlet at 2^18
/// (error ≈ 1e-9), RK4 at 2^11 (error ≈ 1e-10: one more halving would fall
/// to within 20 × the reference's round-off floor of ≈ 3e-13), implicit at
/// 2^19 (error ≈ 5e-7, ≈ 1 s a run). The whole default sweep then takes
/// about 15 s on the 2-core machine.
pub fn default_halvings(integrator: Integrator) -> u32 {
    match integrator {
        Integrator::Euler => 10,
        Integrator::Symplectic => 11,
        Integrator::Verlet => 10,
        Integrator::Rk4 => 4,
        Integrator::Implicit => 15,
    }
}

impl SweepSettings {
    /// The default sweep for `model` over `seconds`: each explicit scheme
    /// starts at the first h = T/2^j ≤ 4 × its predicted stable step (so two
    /// points lie beyond the limit) and halves h [`default_halvings`] times;
    /// the implicit scheme, stable at any step, starts at T/16 and stops at
    /// [`IMPLICIT_MIN_STEP`]. No run takes
    /// more than 2^[`MAX_STEPS_LOG2`] steps. The reference is RK4 three
    /// halvings below RK4's smallest step: its truncation error is then
    /// 8⁴ ≈ 4000 times below any RK4 point's, and finer references only add
    /// round-off (on prototype A the self-difference is 3.4e-13 chords at
    /// 2^13 steps, 3.3e-13 at 2^14, 6.8e-13 at 2^15).
    pub fn for_model(model: &Model, seconds: f64) -> SweepSettings {
        let est = stability::estimate(model);
        let ranges: Vec<SweepRange> = Integrator::ALL
            .iter()
            .map(|&integrator| {
                // Forward Euler on an undamped mode has no stable step at all;
                // start it where symplectic Euler would.
                let limit = match est.dt_max(integrator) {
                    Some(m) if m > 0.0 => Some(m),
                    Some(_) => est.dt_max(Integrator::Symplectic).filter(|&m| m > 0.0),
                    None => None,
                };
                let j_min = match limit {
                    Some(m) => (seconds / (4.0 * m)).log2().ceil().max(1.0) as u32,
                    None => 4,
                };
                let j_min = j_min.min(MAX_STEPS_LOG2);
                let mut j_max = (j_min + default_halvings(integrator)).min(MAX_STEPS_LOG2);
                if limit.is_none() {
                    // Counted from T/16, the implicit curve would cost the
                    // same 2^19 steps for any T; stop it at an absolute
                    // step instead, so a short sweep stays short.
                    let floor = (seconds / IMPLICIT_MIN_STEP).log2().floor().max(0.0) as u32;
                    j_max = j_max.min(floor).max(j_min);
                }
                SweepRange {
                    integrator,
                    j_min,
                    j_max,
                }
            })
            .collect();
        let rk4_max = ranges
            .iter()
            .find(|r| r.integrator == Integrator::Rk4)
            .map_or(12, |r| r.j_max);
        SweepSettings {
            seconds,
            runs: DEFAULT_RUNS,
            ranges,
            reference_j: (rk4_max + 3).min(MAX_STEPS_LOG2),
            refine_reference: true,
            refine_budget_s: f64::INFINITY,
            locate_limits: true,
        }
    }

    pub(super) fn validate(&self) -> Result<(), AccuracyError> {
        if !(self.seconds > 0.0 && self.seconds.is_finite()) {
            return Err(AccuracyError::Settings(format!(
                "seconds: must be a positive number, got {}",
                self.seconds
            )));
        }
        if self.runs == 0 {
            return Err(AccuracyError::Settings(
                "runs: at least one timed run per point is needed".into(),
            ));
        }
        for r in &self.ranges {
            if r.j_min > r.j_max || r.j_max > 30 {
                return Err(AccuracyError::Settings(format!(
                    "ranges[{}]: need j_min ≤ j_max ≤ 30, got {}..={}",
                    r.integrator, r.j_min, r.j_max
                )));
            }
        }
        if self.reference_j > 30 {
            return Err(AccuracyError::Settings(format!(
                "reference_j: at most 30, got {}",
                self.reference_j
            )));
        }
        Ok(())
    }
}
