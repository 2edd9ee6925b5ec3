//! Running a model for a while: the frame loop around [`Simulator::step`],
//! and `drop`, the paper's test of a leaf released from rest in still air.

use crate::integrate::{Integrator, SimError, Simulator};
use crate::model::Model;
use crate::pose::PoseTracker;
use crate::stability;
use crate::state::State;
use crate::trajectory::Trajectory;
use nalgebra::{UnitQuaternion, Vector3};
use serde::Serialize;
use std::time::Instant;

/// Output frames per simulated second of trajectory files.
pub const FRAME_RATE: f64 = 240.0;

/// How the time step is chosen.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum TimeStep {
    /// A fixed step, s (snapped down to divide the frame interval).
    Fixed(f64),
    /// From the model's stability estimate (see [`stability::StabilityEstimate::auto_dt`]).
    Auto,
}

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
}

/// Resolves a [`TimeStep`] for `model` to a step that divides `frame_dt`.
/// Errors when `Auto` finds no stable step (forward Euler on undamped springs).
pub fn resolve_dt(
    model: &Model,
    integrator: Integrator,
    dt: TimeStep,
    frame_dt: f64,
) -> Result<f64, String> {
    match dt {
        TimeStep::Fixed(h) if h > 0.0 && h.is_finite() => Ok(stability::snap_to_frame(h, frame_dt)),
        TimeStep::Fixed(h) => Err(format!(
            "time step must be a positive number of seconds, got {h}"
        )),
        TimeStep::Auto => stability::estimate(model)
            .auto_dt(integrator, frame_dt)
            .ok_or_else(|| {
                format!(
                    "no stable time step exists for {integrator} on this model \
                 (its stiffest spring mode is undamped); choose another integrator"
                )
            }),
    }
}

/// Steps `state` through `frames` frames of length `frame_dt` with step `dt`
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
    Ok(RunStats {
        integrator,
        dt,
        steps: sim.steps(),
        simulated_s: frames as f64 * frame_dt,
        wall_s: start.elapsed().as_secs_f64(),
        force_evals: sim.force_evaluations(),
        broken_springs: state.broken_springs() - broken_before,
    })
}

/// Settings of a drop test.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DropParams {
    /// The integrator.
    pub integrator: Integrator,
    /// The time step.
    pub dt: TimeStep,
    /// Simulated duration, s.
    pub seconds: f64,
    /// Release attitude: tilt about the body x and y axes, degrees. A leaf
    /// released exactly level keeps its symmetry for ever; a small tilt is
    /// what a real release has.
    pub tilt_deg: [f64; 2],
    /// Keep every particle position of every frame.
    pub record_particles: bool,
}

impl Default for DropParams {
    fn default() -> Self {
        DropParams {
            integrator: Integrator::Verlet,
            dt: TimeStep::Auto,
            seconds: 10.0,
            tilt_deg: [10.0, 2.0],
            record_particles: false,
        }
    }
}

/// The outcome of a drop test.
#[derive(Clone, Debug)]
pub struct DropResult {
    /// Pose of the leaf at every frame (240 per simulated second, from t = 0).
    pub trajectory: Trajectory,
    /// All particle positions at every frame, if asked for.
    pub particles: Option<Vec<Vec<Vector3<f64>>>>,
    /// Run statistics.
    pub stats: RunStats,
}

/// The release rotation of a drop.
pub fn release_rotation(tilt_deg: [f64; 2]) -> UnitQuaternion<f64> {
    UnitQuaternion::from_axis_angle(&Vector3::x_axis(), tilt_deg[0].to_radians())
        * UnitQuaternion::from_axis_angle(&Vector3::y_axis(), tilt_deg[1].to_radians())
}

/// Drops `model` from rest, centre of mass at the origin, tilted as asked,
/// and records its pose every frame.
pub fn drop_leaf(model: &Model, params: &DropParams) -> Result<DropResult, DropError> {
    let frame_dt = 1.0 / FRAME_RATE;
    let dt =
        resolve_dt(model, params.integrator, params.dt, frame_dt).map_err(DropError::Settings)?;
    if !(params.seconds > 0.0 && params.seconds.is_finite()) {
        return Err(DropError::Settings(format!(
            "duration must be a positive number of seconds, got {}",
            params.seconds
        )));
    }
    let frames = (params.seconds * FRAME_RATE).round() as u64;
    let release = release_rotation(params.tilt_deg);
    let mut state = State::released(model, release, Vector3::zeros());
    let mut tracker = PoseTracker::new(model, release);
    let mut trajectory = Trajectory::with_capacity(frames as usize + 1);
    let mut particles = params
        .record_particles
        .then(|| Vec::with_capacity(frames as usize + 1));
    let stats = run_frames(
        model,
        &mut state,
        params.integrator,
        dt,
        frame_dt,
        frames,
        |k, s| {
            let (c, q) = tracker.pose(model, &s.position);
            trajectory.push(k as f64 * frame_dt, c, q);
            if let Some(p) = particles.as_mut() {
                p.push(s.position.clone());
            }
        },
    )
    .map_err(DropError::Sim)?;
    Ok(DropResult {
        trajectory,
        particles,
        stats,
    })
}

/// Why a drop did not complete.
#[derive(Debug)]
pub enum DropError {
    /// Bad settings (time step, duration).
    Settings(String),
    /// The simulation diverged or its solver failed.
    Sim(SimError),
}

impl std::fmt::Display for DropError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            DropError::Settings(s) => f.write_str(s),
            DropError::Sim(e) => e.fmt(f),
        }
    }
}

impl std::error::Error for DropError {}
