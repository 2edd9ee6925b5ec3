//! `drop`, the paper's test of a leaf (section 4.1): released from rest in
//! still air, its pose recorded at every frame.

use crate::motion::trajectory::Trajectory;
use crate::physics::batch::Batch;
use crate::physics::integrate::SimError;
use crate::physics::model::Model;
use crate::physics::params::{Integrator, TimeStep};
use crate::physics::pose::PoseTracker;
use crate::physics::run::{
    MAX_WORK, PoseFault, RunKind, RunStats, StepError, Work, check_budget, hermite, resolve_step,
    run_sampled_until, within,
};
use crate::physics::state::State;
use nalgebra::{UnitQuaternion, Vector3};
use std::time::Instant;

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
    progress: Option<&mut dyn FnMut(u64, u64)>,
) -> Result<DropResult, DropError> {
    let work = drop_work(model, params)?;
    drop_leaf_with_work(model, params, &work, max_work, progress)
}

/// [`drop_leaf_within`] with its [`Work`] already found by [`drop_work`]
/// for the same model and parameters: a caller that shows the work first
/// (`drop`) chooses the step once. Under the unsteady law choosing it
/// measures the air's rates by many force evaluations
/// ([`crate::physics::aero::unsteady::drag_rate`]).
///
/// # Errors
/// As [`drop_leaf_within`].
pub fn drop_leaf_with_work(
    model: &Model,
    params: &DropParams,
    work: &Work,
    max_work: f64,
    mut progress: Option<&mut dyn FnMut(u64, u64)>,
) -> Result<DropResult, DropError> {
    let frame_dt = 1.0 / FRAME_RATE;
    work.check(model, frame_dt, max_work, RunKind::Drop)?;
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

/// [`drop_leaf`] of `L` leaves at once: where they share a topology and
/// need only what a lockstep [`Batch`] steps (the default integrator in
/// still air, as a breed's leaves do), in its lanes, each leaf on its own
/// step and sampled at its own frames; else one after another. Each result
/// is the one [`drop_leaf`] gives, to the bit: a lane's arithmetic is a lone
/// drop's (tests/integration/batch.rs), and a lane that diverges or whose
/// pose is not finite is dropped again alone for its diagnosis. Only the
/// wall time of the stepping loop (`stats.wall_s`, shared by the lanes)
/// differs.
///
/// Each leaf has its own [`DropParams`]; they may differ in the release
/// tilt and the step, and must agree on the rest (else the drops run one
/// after another).
pub fn drop_leaves<const L: usize>(
    models: [&Model; L],
    params: [&DropParams; L],
) -> [Result<DropResult, DropError>; L] {
    match drop_lockstep(models, params) {
        Some(results) => results,
        None => std::array::from_fn(|k| drop_leaf(models[k], params[k])),
    }
}

/// One lane of [`drop_lockstep`]: its pose, its frames, and the step ends
/// it samples between.
struct Lane {
    tracker: PoseTracker,
    trajectory: Trajectory,
    /// The next frame to sample.
    frame: u64,
    x0: Vec<Vector3<f64>>,
    v0: Vec<Vector3<f64>>,
    x1: Vec<Vector3<f64>>,
    v1: Vec<Vector3<f64>>,
    sample: Vec<Vector3<f64>>,
    /// Diverged, or a pose not finite: dropped again alone.
    failed: bool,
}

/// The lockstep drops of [`drop_leaves`], with [`run_sampled_until`]'s
/// frame sampling per lane; `None` if the leaves cannot share a batch or a
/// drop would be refused (the lone drops then say why).
fn drop_lockstep<const L: usize>(
    models: [&Model; L],
    params: [&DropParams; L],
) -> Option<[Result<DropResult, DropError>; L]> {
    let first = params[0];
    let shared = |p: &DropParams| {
        p.integrator == Integrator::Verlet && !p.record_particles && p.seconds == first.seconds
    };
    if !params.iter().all(|p| shared(p)) {
        return None;
    }
    let frame_dt = 1.0 / FRAME_RATE;
    let mut dt = [0.0; L];
    for k in 0..L {
        let work = drop_work(models[k], params[k]).ok()?;
        work.check(models[k], frame_dt, MAX_WORK, RunKind::Drop)
            .ok()?;
        dt[k] = work.dt;
    }
    let frames = (first.seconds * FRAME_RATE).round() as u64;
    let release: [_; L] = std::array::from_fn(|k| release_rotation(params[k].tilt_deg));
    let states: [State; L] =
        std::array::from_fn(|k| State::released(models[k], release[k], Vector3::zeros()));
    let mut batch = Batch::new(models, std::array::from_fn(|k| &states[k]), dt).ok()?;
    let mut lanes: [Lane; L] = std::array::from_fn(|k| {
        let n = models[k].len();
        let mut tracker = PoseTracker::new(models[k], release[k]);
        let mut trajectory = Trajectory::with_capacity(frames as usize + 1);
        let (c, q) = tracker.pose(models[k], &states[k].position);
        let failed = !finite_pose(&c, &q);
        trajectory.push(0.0, c, q);
        Lane {
            tracker,
            trajectory,
            frame: 1,
            x0: states[k].position.clone(),
            v0: states[k].velocity.clone(),
            x1: vec![Vector3::zeros(); n],
            v1: vec![Vector3::zeros(); n],
            sample: vec![Vector3::zeros(); n],
            failed,
        }
    });
    let start = Instant::now();
    loop {
        let active: [bool; L] =
            std::array::from_fn(|k| !lanes[k].failed && lanes[k].frame <= frames);
        if !active.contains(&true) {
            break;
        }
        let steps = batch.steps();
        for (k, lane) in lanes.iter_mut().enumerate() {
            // The start of the step, if a frame falls inside it.
            let begin = steps[k] as f64 * dt[k];
            if active[k] && within(lane.frame as f64 * frame_dt, begin, dt[k]) < 1.0 - 1e-12 {
                batch.lane_into(k, &mut lane.x0, &mut lane.v0);
            }
        }
        let live = batch.step(active);
        for (k, lane) in lanes.iter_mut().enumerate() {
            if !active[k] {
                continue;
            }
            if !live[k] {
                lane.failed = true;
                continue;
            }
            let (begin, end) = (steps[k] as f64 * dt[k], (steps[k] + 1) as f64 * dt[k]);
            let due =
                |frame: u64| frame <= frames && frame as f64 * frame_dt <= end * (1.0 + 1e-12);
            if due(lane.frame) {
                batch.lane_into(k, &mut lane.x1, &mut lane.v1);
            }
            while due(lane.frame) {
                let s = within(lane.frame as f64 * frame_dt, begin, dt[k]);
                let x = if s >= 1.0 - 1e-12 {
                    &lane.x1
                } else {
                    hermite(
                        &lane.x0,
                        &lane.v0,
                        &lane.x1,
                        &lane.v1,
                        dt[k],
                        s,
                        &mut lane.sample,
                    );
                    &lane.sample
                };
                let (c, q) = lane.tracker.pose(models[k], x);
                if !finite_pose(&c, &q) {
                    lane.failed = true;
                    break;
                }
                lane.trajectory.push(lane.frame as f64 * frame_dt, c, q);
                lane.frame += 1;
            }
        }
    }
    let wall_s = start.elapsed().as_secs_f64();
    let steps = batch.steps();
    let mut lanes = lanes.into_iter();
    Some(std::array::from_fn(|k| {
        let lane = lanes.next().expect("one lane per model");
        if lane.failed {
            return drop_leaf(models[k], params[k]);
        }
        Ok(DropResult {
            trajectory: lane.trajectory,
            particles: None,
            stats: RunStats {
                integrator: Integrator::Verlet,
                dt: dt[k],
                steps: steps[k],
                simulated_s: frames as f64 * frame_dt,
                wall_s,
                // Verlet: the first step's acceleration, then one per step.
                force_evals: steps[k] + 1,
                broken_springs: 0,
                contacts_resolved: 0,
                // Lockstep batches sample no wind: nothing to skip.
                skips: Default::default(),
            },
        })
    }))
}

/// Whether a pose fit is finite (what `drop_leaf_within` requires of every
/// frame).
fn finite_pose(c: &Vector3<f64>, q: &UnitQuaternion<f64>) -> bool {
    c.iter().all(|v| v.is_finite()) && q.coords.iter().all(|v| v.is_finite())
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
