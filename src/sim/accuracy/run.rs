//! One run of a model to T, timed, and what is measured at its end: its
//! RMS difference from another run, whether it rings above the stable
//! step, and the RK4 reference every error is measured against (the
//! folder's docs, "Reference" and "Divergence").

use super::error::AccuracyError;
use crate::physics::integrate::{SimError, Simulator};
use crate::physics::model::Model;
use crate::physics::params::Integrator;
use crate::physics::state::State;
use crate::sim::drop;
use crate::util::setting::Setting;
use nalgebra::Vector3;
use serde::Serialize;
use std::time::Instant;

type V3 = Vector3<f64>;

/// The reference's self-difference must be below this fraction of the
/// smallest error plotted (docs/design/numerics.md, "Error against work", step 3).
pub const REFERENCE_FACTOR: f64 = 0.1;
/// A run that reached T is still unstable when its internal acceleration
/// (see [`EndRun::internal_acceleration`]) exceeds this many times the
/// reference's plus [`OSCILLATION_FLOOR`]: above the stable step the
/// stiffest mode grows each step until the springs' and hinges' geometric
/// nonlinearity holds it in a bounded step-to-step oscillation (prototype A
/// under Verlet at 1.11 × dt_max: springs ringing by 1.5 % of their length
/// for 30 s, never stopped as a runaway; docs/design/accuracy.md, "Stable
/// limits"). That oscillation's second difference is some 4 × its amplitude
/// per step, so over h² it stands orders of magnitude above the smooth
/// motion's.
pub const OSCILLATION_FACTOR: f64 = 100.0;
/// Internal acceleration below this, 1/s² (strain or radians per s²), never
/// counts as oscillating: a ringing of 1e-6 strain at h = 1 ms reads 4.
pub const OSCILLATION_FLOOR: f64 = 1.0;

/// A copy of `model` in which no spring can break, and how many springs
/// were breakable. Breaking is an event that limits any scheme to first
/// order unless located, so convergence studies switch it off
/// (docs/design/numerics.md, "Error against work", step 6).
pub fn smooth_model(model: &Model) -> (Model, usize) {
    let mut smooth = model.clone();
    let mut count = 0;
    for s in &mut smooth.springs {
        if s.break_strain.take().is_some() {
            count += 1;
        }
    }
    (smooth, count)
}

/// The state a leaf is dropped from by `leafmagic drop` with default
/// settings: at rest, centre of mass at the origin, tilted by
/// [`drop::DropParams`]'s default release tilt.
pub fn default_release(model: &Model) -> State {
    let tilt = drop::DropParams::default().tilt_deg;
    State::released(model, drop::release_rotation(tilt), V3::zeros())
}

/// The end of one run of `steps` steps of size `dt` from `initial`.
#[derive(Clone, Debug)]
pub struct EndRun {
    /// The state at the end (or where the run stopped).
    pub state: State,
    /// Wall time of the stepping loop, s.
    pub wall_s: f64,
    /// Force evaluations.
    pub force_evals: u64,
    /// Why the run stopped early, if it did.
    pub error: Option<SimError>,
    /// The largest |d²q/dt²| at T over the internal coordinates q (each
    /// spring's strain l/L − 1 and each hinge's fold angle, rad) from their
    /// second difference over the last two steps, 1/s²; `None` when the
    /// run stopped or took fewer than two steps. Smooth motion gives the
    /// coordinates' real acceleration; a step above the stable limit gives
    /// its ringing, about 4 × amplitude / h².
    pub internal_acceleration: Option<f64>,
}

impl EndRun {
    /// Whether the run is unstable against `reference`: it stopped, or it
    /// reached T ringing (its internal acceleration above
    /// [`OSCILLATION_FACTOR`] × the reference's + [`OSCILLATION_FLOOR`]).
    pub fn unstable(&self, reference: &Reference) -> bool {
        self.error.is_some() || self.oscillating(reference)
    }

    /// Whether the run reached T ringing (see [`Self::unstable`]).
    pub fn oscillating(&self, reference: &Reference) -> bool {
        self.internal_acceleration.is_some_and(|a| {
            a > OSCILLATION_FACTOR * reference.internal_acceleration + OSCILLATION_FLOOR
        })
    }
}

/// The internal coordinates of `state`: each spring's strain l/L − 1 (0 for
/// a zero-length spring) and each hinge's fold angle, rad (0 for a
/// degenerate hinge). They do not move with the leaf as a whole, so their
/// second difference over steps sees only deformation.
fn internal_coordinates(model: &Model, state: &State) -> Vec<f64> {
    let x = &state.position;
    let strains = model.springs.iter().map(|s| {
        if s.rest_length > 0.0 {
            (x[s.i] - x[s.j]).norm() / s.rest_length - 1.0
        } else {
            0.0
        }
    });
    let angles = model
        .hinges
        .iter()
        .map(|h| crate::physics::forces::dihedral(x, h).map_or(0.0, |(theta, _)| theta));
    strains.chain(angles).collect()
}

/// max |q₂ − 2q₁ + q₀| / h² over the coordinates; a fold angle's jump
/// through ±π is wrapped back.
fn second_difference(q: &[Vec<f64>; 3], h: f64, springs: usize) -> f64 {
    let wrap = |d: f64| {
        let tau = std::f64::consts::TAU;
        d - tau * (d / tau).round()
    };
    (0..q[0].len())
        .map(|k| {
            let (d1, d0) = (q[2][k] - q[1][k], q[1][k] - q[0][k]);
            let dd = if k < springs {
                d1 - d0
            } else {
                wrap(d1) - wrap(d0)
            };
            dd.abs() / (h * h)
        })
        .fold(0.0, f64::max)
}

/// Runs `model` from `initial` for `steps` steps of `dt` with `integrator`,
/// timing only the stepping loop.
pub fn run_steps(
    model: &Model,
    initial: &State,
    integrator: Integrator,
    dt: f64,
    steps: u64,
) -> EndRun {
    let mut state = initial.clone();
    let t0 = state.time;
    let mut sim = Simulator::new(model, integrator);
    let start = Instant::now();
    let mut error = None;
    // The coordinates before each of the last two steps (the third, after
    // the last step, is taken below, outside the clock).
    let mut last: Vec<Vec<f64>> = Vec::with_capacity(3);
    for k in 0..steps {
        if k + 2 >= steps {
            last.push(internal_coordinates(model, &state));
        }
        if let Err(e) = sim.step(model, &mut state, dt) {
            error = Some(e);
            break;
        }
    }
    let wall_s = start.elapsed().as_secs_f64();
    let internal_acceleration = match (error.is_none(), <[Vec<f64>; 2]>::try_from(last)) {
        (true, Ok([q0, q1])) => {
            let q2 = internal_coordinates(model, &state);
            Some(second_difference(&[q0, q1, q2], dt, model.springs.len()))
        }
        _ => None,
    };
    if error.is_none() {
        // The clock accumulates round-off over many steps; pin it to the end.
        state.time = t0 + steps as f64 * dt;
    }
    EndRun {
        state,
        wall_s,
        force_evals: sim.force_evaluations(),
        error,
        internal_acceleration,
    }
}

/// RMS over particles of |a_i − b_i|, divided by `scale`.
pub fn rms_difference(a: &[V3], b: &[V3], scale: f64) -> f64 {
    let n = a.len().max(1) as f64;
    let sum: f64 = a.iter().zip(b).map(|(x, y)| (x - y).norm_squared()).sum();
    (sum / n).sqrt() / scale
}

/// The step h = T/2^j.
pub fn step_size(seconds: f64, j: u32) -> f64 {
    seconds / f64::from(2u32.pow(j.min(31)))
}

/// The reference solution at T and how far it can be trusted.
#[derive(Clone, Debug, Serialize)]
pub struct Reference {
    /// Always RK4.
    pub integrator: Integrator,
    /// The reference step h_ref/2 actually used for the errors, s.
    pub dt: f64,
    /// RMS difference (in chords) between the runs at h_ref and h_ref/2:
    /// an upper estimate of the reference's own error.
    pub self_difference: f64,
    /// Particle positions at T.
    #[serde(skip)]
    pub positions: Vec<V3>,
    /// The fine run's [`EndRun::internal_acceleration`], 1/s²: how fast
    /// the leaf's springs and hinges really move at T.
    pub internal_acceleration: f64,
    /// Wall time of the fine run, s: what the next halving will cost, by
    /// half.
    #[serde(skip)]
    pub wall_s: f64,
}

/// Computes the RK4 reference at T/2^j and T/2^(j+1).
pub fn reference(
    model: &Model,
    initial: &State,
    seconds: f64,
    j: u32,
) -> Result<Reference, AccuracyError> {
    let coarse_h = step_size(seconds, j);
    // Above RK4's stable limit the reference would be garbage, or diverge
    // with a message about time steps the user never chose.
    if let Some(limit) = crate::physics::stability::estimate(model).dt_max(Integrator::Rk4)
        && coarse_h > limit
    {
        return Err(AccuracyError::Settings(format!(
            "reference_j: the reference, RK4 at T/2^{j} = {coarse_h:.3e} s, is above RK4's \
             stable step {limit:.3e} s; simulate at most {:.3e} s at this j, or raise it \
             ({}, up to 30)",
            limit * 2f64.powi(j as i32),
            Setting::ReferenceJ
        )));
    }
    let coarse = run_steps(model, initial, Integrator::Rk4, coarse_h, 1 << j);
    if let Some(e) = coarse.error {
        return Err(AccuracyError::Reference(e));
    }
    finer_reference(model, initial, seconds, &coarse.state.position, coarse_h)
}

/// RK4 at half of `coarse_h` over `seconds`, checked against the run at
/// `coarse_h` that ended at `coarse`: a reference, or a refined one.
pub(super) fn finer_reference(
    model: &Model,
    initial: &State,
    seconds: f64,
    coarse: &[V3],
    coarse_h: f64,
) -> Result<Reference, AccuracyError> {
    let dt = coarse_h / 2.0;
    let fine = run_steps(
        model,
        initial,
        Integrator::Rk4,
        dt,
        (seconds / dt).round() as u64,
    );
    if let Some(e) = fine.error {
        return Err(AccuracyError::Reference(e));
    }
    Ok(Reference {
        integrator: Integrator::Rk4,
        dt,
        self_difference: rms_difference(coarse, &fine.state.position, model.chord()),
        positions: fine.state.position,
        internal_acceleration: fine.internal_acceleration.unwrap_or(0.0),
        wall_s: fine.wall_s,
    })
}
