//! Running a model for a while: the two frame loops around
//! [`Simulator::step`] (sampled by interpolation for drops, stepped onto
//! every frame for scenes), the choice of the step, and the budget that
//! refuses a run which would never end.

use crate::physics::integrate::{SimError, Simulator};
use crate::physics::model::Model;
use crate::physics::params::{Integrator, TimeStep};
use crate::physics::stability;
use crate::physics::state::State;
use nalgebra::Vector3;
use serde::Serialize;
use std::time::Instant;

/// What a run did and what it cost.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RunStats {
    /// The integrator used.
    pub integrator: Integrator,
    /// The time step actually used, s.
    pub dt: f64,
    /// Steps taken.
    pub steps: u64,
    /// Simulated time, s.
    pub simulated_s: f64,
    /// Wall-clock time of the stepping loop (set-up and output excluded), s.
    pub wall_s: f64,
    /// Full force evaluations.
    pub force_evals: u64,
    /// Springs broken during the run.
    pub broken_springs: usize,
    /// Point contacts with the ground resolved during the run.
    pub contacts_resolved: u64,
}

impl RunStats {
    /// The statistics of `sim`'s run since `start` (the wall clock of the
    /// stepping loop alone).
    fn of(sim: &Simulator, dt: f64, simulated_s: f64, start: Instant, broken: usize) -> RunStats {
        RunStats {
            integrator: sim.integrator(),
            dt,
            steps: sim.steps(),
            simulated_s,
            wall_s: start.elapsed().as_secs_f64(),
            force_evals: sim.force_evaluations(),
            broken_springs: broken,
            contacts_resolved: sim.contacts_resolved(),
        }
    }
}

/// Resolves a [`TimeStep`] for `model` to a step that divides `frame_dt`.
/// Errors when `Auto` finds no stable step (forward Euler on undamped springs).
pub fn resolve_dt(
    model: &Model,
    integrator: Integrator,
    dt: TimeStep,
    frame_dt: f64,
) -> Result<f64, StepError> {
    resolve(model, integrator, dt, frame_dt, true)
}

/// Resolves a [`TimeStep`] for a run sampled by [`run_sampled`]: a fixed
/// step is used as given, `Auto` is [`stability::StabilityEstimate::auto_step`]
/// (not snapped to the frame grid).
pub fn resolve_step(
    model: &Model,
    integrator: Integrator,
    dt: TimeStep,
    frame_dt: f64,
) -> Result<f64, StepError> {
    resolve(model, integrator, dt, frame_dt, false)
}

fn resolve(
    model: &Model,
    integrator: Integrator,
    dt: TimeStep,
    frame_dt: f64,
    onto_frames: bool,
) -> Result<f64, StepError> {
    match dt {
        TimeStep::Fixed(h) if h > 0.0 && h.is_finite() => Ok(if onto_frames {
            stability::snap_to_frame(h, frame_dt)
        } else {
            h
        }),
        TimeStep::Fixed(h) => Err(StepError::NotPositive(h)),
        TimeStep::Auto => {
            let estimate = stability::estimate(model);
            if !estimate.is_finite() {
                let rates = [
                    ("ω_max", estimate.omega_max, "rad/s"),
                    ("its upper bound", estimate.omega_upper, "rad/s"),
                    (
                        "the top mode's damping rate",
                        estimate.mode_damping_rate,
                        "1/s",
                    ),
                    ("the drag rate", estimate.drag_rate, "1/s"),
                ];
                let bad: Vec<String> = rates
                    .iter()
                    .filter(|r| !r.1.is_finite())
                    .map(|(name, v, unit)| format!("{name} = {v} {unit}"))
                    .collect();
                return Err(StepError::Overflow {
                    rates: bad.join(", "),
                    stiffest_spring: estimate
                        .stiffest_spring
                        .filter(|_| !estimate.omega_lower.is_finite()),
                });
            }
            if onto_frames {
                estimate.auto_dt(integrator, frame_dt)
            } else {
                estimate.auto_step(integrator, frame_dt)
            }
            .ok_or(StepError::NoStableStep(integrator))
        }
    }
}

/// Most steps, or output frames, one run may take. Far beyond any useful
/// run (a scene of a hundred leaves takes hours for 10⁸ steps): a run that
/// needs more has a step far too small (a very stiff or very light model
/// under `dt = auto`, or a tiny fixed step) or a frame rate far too high, and
/// is refused up front instead of running for ever.
pub const MAX_STEPS: f64 = 1e8;

/// A number for a message: plain when moderate, else in scientific notation.
fn quantity(v: f64) -> String {
    if v != 0.0 && !(1e-3..1e6).contains(&v.abs()) {
        format!("{v:.3e}")
    } else {
        format!("{v}")
    }
}

/// Checks that `seconds` of simulation at step `dt`, written at `frame_rate`
/// frames per second, stays within [`MAX_STEPS`] steps and frames, and
/// writes at least one frame ([`check_frames`], [`check_steps`]).
///
/// # Errors
/// The counts and the likely cause.
pub fn check_budget(
    seconds: f64,
    dt: f64,
    frame_rate: f64,
    integrator: Integrator,
) -> Result<(), StepError> {
    check_frames(seconds, frame_rate)?;
    check_steps(seconds, dt, integrator)
}

/// Checks that `seconds` at `frame_rate` is at least one frame and at most
/// [`MAX_STEPS`].
///
/// # Errors
/// The count.
pub fn check_frames(seconds: f64, frame_rate: f64) -> Result<(), StepError> {
    let frames = seconds * frame_rate;
    if frames.is_nan() || frames < 0.5 {
        return Err(StepError::NoFrame {
            seconds,
            frame_rate,
        });
    }
    if frames > MAX_STEPS {
        return Err(StepError::TooManyFrames {
            seconds,
            frame_rate,
        });
    }
    Ok(())
}

/// Checks that `seconds` at step `dt` is at most [`MAX_STEPS`] steps.
///
/// # Errors
/// The count and the likely cause.
pub fn check_steps(seconds: f64, dt: f64, integrator: Integrator) -> Result<(), StepError> {
    let steps = seconds / dt;
    if steps.is_nan() || steps > MAX_STEPS {
        return Err(StepError::TooManySteps {
            seconds,
            dt,
            integrator,
        });
    }
    Ok(())
}

/// Why no step, or no run, can be had: the step chosen or asked for, or the
/// number of steps or frames it would take.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum StepError {
    /// A fixed step that is not a positive number of seconds.
    #[error("time step must be a positive number of seconds, got {0}")]
    NotPositive(f64),
    /// A duration that is not a positive number of seconds.
    #[error("duration must be a positive number of seconds, got {0}")]
    Duration(f64),
    /// A rate of the model overflows f64, so the auto step has nothing to go on.
    #[error(
        "no time step can be chosen: {rates} (a stiffness, damping or drag coefficient \
         too large, or a mass too small, for f64: k/m, c/m or α/m overflows{})",
        .stiffest_spring.map_or(String::new(), |k| format!("; the stiffest is spring[{k}]"))
    )]
    Overflow {
        /// The rates that are not finite, with their values.
        rates: String,
        /// The stiffest spring, when a spring rate overflows.
        stiffest_spring: Option<usize>,
    },
    /// Forward Euler on an undamped spring mode: unstable at any step.
    #[error(
        "no stable time step exists for {0} on this model \
         (its stiffest spring mode is undamped); choose another integrator"
    )]
    NoStableStep(Integrator),
    /// Less than one frame.
    #[error(
        "{} s at {} frames per second is no frame at all; raise the frame rate or the duration",
        quantity(*.seconds),
        quantity(*.frame_rate)
    )]
    NoFrame {
        /// Duration, s.
        seconds: f64,
        /// Frames per second.
        frame_rate: f64,
    },
    /// More frames than [`MAX_STEPS`].
    #[error(
        "{} s at {} frames per second is {:.2e} frames, more than the limit of \
         {MAX_STEPS:.0e}; lower the frame rate or the duration",
        quantity(*.seconds),
        quantity(*.frame_rate),
        .seconds * .frame_rate
    )]
    TooManyFrames {
        /// Duration, s.
        seconds: f64,
        /// Frames per second.
        frame_rate: f64,
    },
    /// More steps than [`MAX_STEPS`].
    #[error(
        "{} s at dt = {dt:.3e} s needs {} steps of {integrator} (the limit is \
         {MAX_STEPS:.0e}): the step is far too small. With dt = auto this means \
         the model is extremely stiff or light for an explicit integrator (see `leafmagic \
         check`); soften it, make it heavier, or use the implicit integrator, whose step \
         stability does not limit",
        quantity(*.seconds),
        step_count(*.seconds / *.dt)
    )]
    TooManySteps {
        /// Duration, s.
        seconds: f64,
        /// The step, s.
        dt: f64,
        /// The integrator.
        integrator: Integrator,
    },
}

/// A step count for a message; "over 1e308" when it overflows.
fn step_count(steps: f64) -> String {
    if steps.is_finite() {
        format!("{steps:.2e}")
    } else {
        "over 1e308".to_string()
    }
}

/// Steps `state` with step `dt`, which need not divide `frame_dt`, until
/// `frames` frames have passed, calling `on_frame(k, positions)` at frame 0
/// and at every frame time k·`frame_dt`. A frame that falls inside a step
/// gets the cubic Hermite interpolant through the positions and velocities
/// at both ends of that step: its error, O(dt⁴) for smooth motion, stays
/// below the integrators' own O(dt²) or better, and it lets the step be as
/// long as stability allows instead of a divisor of the frame.
///
/// On return `state` is at the end of the last step, at or just past the
/// last frame.
pub fn run_sampled(
    model: &Model,
    state: &mut State,
    integrator: Integrator,
    dt: f64,
    frame_dt: f64,
    frames: u64,
    mut on_frame: impl FnMut(u64, &[Vector3<f64>]),
) -> Result<RunStats, SimError> {
    let t0 = state.time;
    let mut sim = Simulator::new(model, integrator);
    on_frame(0, &state.position);
    let start = Instant::now();
    let broken_before = state.broken_springs();
    let n = state.position.len();
    let mut x0 = state.position.clone();
    let mut v0 = state.velocity.clone();
    let mut sample = vec![Vector3::zeros(); n];
    let mut k = 1;
    while k <= frames {
        // Step ends counted from t0, so the clock carries no summed round-off.
        let begin = sim.steps() as f64 * dt;
        let end = (sim.steps() + 1) as f64 * dt;
        // The start of the step is needed only if a frame falls inside it
        // (the same test as below, for the earliest frame not yet sampled).
        if within(k as f64 * frame_dt, begin, dt) < 1.0 - 1e-12 {
            x0.copy_from_slice(&state.position);
            v0.copy_from_slice(&state.velocity);
        }
        sim.step(model, state, dt)?;
        while k <= frames && k as f64 * frame_dt <= end * (1.0 + 1e-12) {
            let s = within(k as f64 * frame_dt, begin, dt);
            if s >= 1.0 - 1e-12 {
                on_frame(k, &state.position);
            } else {
                hermite(
                    &x0,
                    &v0,
                    &state.position,
                    &state.velocity,
                    dt,
                    s,
                    &mut sample,
                );
                on_frame(k, &sample);
            }
            k += 1;
        }
        state.time = t0 + end;
    }
    Ok(RunStats::of(
        &sim,
        dt,
        frames as f64 * frame_dt,
        start,
        state.broken_springs() - broken_before,
    ))
}

/// Where time `t` falls in the step [begin, begin + dt], as s ∈ [0, 1].
#[inline]
fn within(t: f64, begin: f64, dt: f64) -> f64 {
    ((t - begin) / dt).clamp(0.0, 1.0)
}

/// The cubic Hermite interpolant at s ∈ [0, 1] of a step of length `h`
/// from (x0, v0) to (x1, v1).
fn hermite(
    x0: &[Vector3<f64>],
    v0: &[Vector3<f64>],
    x1: &[Vector3<f64>],
    v1: &[Vector3<f64>],
    h: f64,
    s: f64,
    out: &mut [Vector3<f64>],
) {
    let s2 = s * s;
    let s3 = s2 * s;
    let h00 = 2.0 * s3 - 3.0 * s2 + 1.0;
    let h10 = (s3 - 2.0 * s2 + s) * h;
    let h01 = 3.0 * s2 - 2.0 * s3;
    let h11 = (s3 - s2) * h;
    for i in 0..out.len() {
        out[i] = h00 * x0[i] + h10 * v0[i] + h01 * x1[i] + h11 * v1[i];
    }
}

/// The frame loop of scenes: steps `state` through `frames` frames of
/// length `frame_dt` with step `dt`
/// (which must divide `frame_dt`), calling `on_frame(k, state)` at frame 0
/// and after each frame.
pub fn run_frames(
    model: &Model,
    state: &mut State,
    integrator: Integrator,
    dt: f64,
    frame_dt: f64,
    frames: u64,
    mut on_frame: impl FnMut(u64, &State),
) -> Result<RunStats, SimError> {
    let steps_per_frame = (frame_dt / dt).round().max(1.0) as u64;
    let t0 = state.time;
    let mut sim = Simulator::new(model, integrator);
    on_frame(0, state);
    let start = Instant::now();
    let broken_before = state.broken_springs();
    for k in 1..=frames {
        for _ in 0..steps_per_frame {
            sim.step(model, state, dt)?;
        }
        // Pin the clock to the frame grid so output times carry no round-off drift.
        state.time = t0 + k as f64 * frame_dt;
        on_frame(k, state);
    }
    Ok(RunStats::of(
        &sim,
        dt,
        frames as f64 * frame_dt,
        start,
        state.broken_springs() - broken_before,
    ))
}
