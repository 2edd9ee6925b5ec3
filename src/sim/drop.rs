//! `drop`, the paper's test of a leaf (section 4.1): released from rest in
//! still air, its pose recorded at every frame.

use crate::motion::trajectory::Trajectory;
use crate::physics::integrate::SimError;
use crate::physics::model::Model;
use crate::physics::params::{Integrator, TimeStep};
use crate::physics::pose::PoseTracker;
use crate::physics::run::{
    Command, MAX_WORK, PoseFault, RunStats, StepError, Work, check_budget, resolve_step,
    run_sampled_until,
};
use crate::physics::state::State;
use nalgebra::{UnitQuaternion, Vector3};

/// Output frames per simulated second of trajectory files.
pub const FRAME_RATE: f64 = 240.0;

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
/// and records its pose every frame; refused past [`MAX_WORK`].
pub fn drop_leaf(model: &Model, params: &DropParams) -> Result<DropResult, DropError> {
    drop_leaf_within(model, params, MAX_WORK, None)
}

/// The work of a drop before it runs ([`Work`]): what `drop_leaf_within`
/// checks against its limit, and what a caller shows when it is long.
///
/// # Errors
/// Bad settings: the step ([`resolve_step`]), the duration, the step and
/// frame counts ([`check_budget`]).
pub fn drop_work(model: &Model, params: &DropParams) -> Result<Work, DropError> {
    let frame_dt = 1.0 / FRAME_RATE;
    let dt = resolve_step(model, params.integrator, params.dt, frame_dt)?;
    if !(params.seconds > 0.0 && params.seconds.is_finite()) {
        return Err(StepError::Duration(params.seconds).into());
    }
    check_budget(params.seconds, dt, FRAME_RATE, params.integrator)?;
    Ok(Work::of(
        model,
        params.integrator,
        dt,
        params.dt == TimeStep::Auto,
        params.seconds,
        frame_dt,
    ))
}

/// [`drop_leaf`] refused past `max_work` particle-steps, calling
/// `progress(frame, frames)` after every frame if given.
///
/// # Errors
/// [`DropError`]: bad settings, too much work, divergence, a pose that is
/// not finite.
pub fn drop_leaf_within(
    model: &Model,
    params: &DropParams,
    max_work: f64,
    mut progress: Option<&mut dyn FnMut(u64, u64)>,
) -> Result<DropResult, DropError> {
    let frame_dt = 1.0 / FRAME_RATE;
    let work = drop_work(model, params)?;
    work.check(model, frame_dt, max_work, Command::Drop)?;
    let dt = work.dt;
    let frames = (params.seconds * FRAME_RATE).round() as u64;
    let release = release_rotation(params.tilt_deg);
    let mut state = State::released(model, release, Vector3::zeros());
    let mut tracker = PoseTracker::new(model, release);
    let mut trajectory = Trajectory::with_capacity(frames as usize + 1);
    let mut particles = params
        .record_particles
        .then(|| Vec::with_capacity(frames as usize + 1));
    let all: Vec<usize> = (0..model.len()).collect();
    let stats = run_sampled_until(
        model,
        &mut state,
        params.integrator,
        dt,
        frame_dt,
        frames,
        |k, x| {
            let (c, q) = tracker.pose(model, x);
            // A pose that is not finite while the particles are (the
            // simulator checks those) stops the run with a diagnosis, never
            // a NaN frame in the trajectory.
            if !(c.iter().all(|v| v.is_finite()) && q.coords.iter().all(|v| v.is_finite())) {
                return Err(PoseFault::of(model, x, &c, &all));
            }
            trajectory.push(k as f64 * frame_dt, c, q);
            if let Some(p) = particles.as_mut() {
                p.push(x.to_vec());
            }
            if let Some(report) = progress.as_mut() {
                report(k, frames);
            }
            Ok(())
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
#[derive(Debug, thiserror::Error)]
pub enum DropError {
    /// Bad settings (time step, duration).
    #[error(transparent)]
    Settings(#[from] StepError),
    /// The simulation diverged or its solver failed.
    #[error(transparent)]
    Sim(#[from] SimError),
}
