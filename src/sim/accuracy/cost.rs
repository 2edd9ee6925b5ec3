//! What a sweep will cost, scaled from a pilot run of each integrator:
//! for the note a long sweep prints before it starts, and the budget of
//! its reference's refinement.

use super::run::{run_steps, step_size};
use super::settings::SweepSettings;
use crate::physics::model::Model;
use crate::physics::params::Integrator;
use crate::physics::state::State;

/// Steps of each integrator [`estimated_cost`] times at least.
pub const PILOT_STEPS: u64 = 256;
/// Wall time [`estimated_cost`] times each integrator for at least (unless
/// that would run past the finest point's own steps), s: 256 steps of a
/// 7-particle leaf take a quarter of a millisecond, where a cold start
/// alone doubled the estimate.
pub const PILOT_MIN_S: f64 = 0.02;

/// Bisection runs `locate_limit` (sweep.rs) takes to 1 %
/// (log₂ 100 ≈ 7), counted at twice the first point's steps.
const BISECTION_RUNS: f64 = 7.0;

/// What a sweep will cost, from a pilot run of each integrator at its
/// finest step ([`PILOT_STEPS`] and [`PILOT_MIN_S`] at least) (stable, and where the implicit scheme's
/// conjugate gradients converge fastest, so that cost is a floor there).
#[derive(Clone, Debug, PartialEq)]
pub struct SweepCost {
    /// Seconds of one core per integrator, in the sweep's order.
    pub per_integrator: Vec<(Integrator, f64)>,
    /// The reference's seconds, RK4 at h_ref and h_ref/2 (more if it must
    /// be refined).
    pub reference_s: f64,
}

impl SweepCost {
    /// The whole sweep, s of one core.
    pub fn total_s(&self) -> f64 {
        self.per_integrator.iter().map(|(_, s)| s).sum::<f64>() + self.reference_s
    }
}

/// Times a pilot run of each integrator of `settings` on `model` and
/// scales it to the sweep: every point's timed and untimed runs, the
/// bisection of each limit and the reference. A guide for the note a long
/// sweep prints before it starts, not a promise (the implicit scheme takes
/// more iterations at larger steps).
pub fn estimated_cost(model: &Model, initial: &State, settings: &SweepSettings) -> SweepCost {
    let seconds = settings.seconds;
    // Doubled until it takes PILOT_MIN_S, or as many steps as `j` gives.
    let per_step = |integrator: Integrator, j: u32| {
        let dt = step_size(seconds, j);
        let mut steps = PILOT_STEPS.min(1 << j);
        loop {
            let run = run_steps(model, initial, integrator, dt, steps);
            if run.wall_s >= PILOT_MIN_S || steps >= 1 << j {
                return run.wall_s / steps as f64;
            }
            steps *= 2;
        }
    };
    let per_integrator = settings
        .ranges
        .iter()
        .map(|r| {
            let cost = per_step(r.integrator, r.j_max);
            let steps: f64 = (r.j_min..=r.j_max).map(|j| 2f64.powi(j as i32)).sum();
            let bisection = if settings.locate_limits {
                BISECTION_RUNS * 2f64.powi(r.j_min as i32 + 1)
            } else {
                0.0
            };
            let runs = (settings.runs + 1) as f64;
            (r.integrator, cost * (runs * steps + bisection))
        })
        .collect();
    let j = settings.reference_j;
    let rk4 = per_step(Integrator::Rk4, j + 1);
    SweepCost {
        per_integrator,
        reference_s: rk4 * 3.0 * 2f64.powi(j as i32),
    }
}
