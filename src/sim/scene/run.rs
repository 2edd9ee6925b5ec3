//! Running a compiled scene frame by frame, recording each object, and
//! writing the per-object trajectories and the summary.

use super::{ObjectKind, Scene};
use crate::motion::trajectory::Trajectory;
use crate::physics::integrate::SimError;
use crate::physics::params::Integrator;
use crate::physics::pose::PoseTracker;
use crate::physics::run::{StepError, check_budget, resolve_dt};
use crate::physics::state::State;
use crate::util::io::{particle_csv, write_atomic};
use nalgebra::Vector3;
use serde::Serialize;
use std::path::{Path, PathBuf};

type V3 = Vector3<f64>;

/// Why a scene run did not complete.
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    /// Bad settings (duration, time step).
    #[error(transparent)]
    Settings(#[from] StepError),
    /// The simulation diverged or its solver failed.
    #[error(transparent)]
    Sim(#[from] SimError),
}

/// Numbers of a finished run. Everything but `wall_s` depends only on the
/// input, so it goes into the summary file; wall time is reported apart.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RunStats {
    /// The integrator.
    pub integrator: Integrator,
    /// The time step used, s.
    pub dt: f64,
    /// Output frames per simulated second.
    pub frame_rate: f64,
    /// Frames recorded, t = 0 included.
    pub frames: u64,
    /// Simulated time, s.
    pub simulated_s: f64,
    /// Steps taken.
    pub steps: u64,
    /// Force evaluations.
    pub force_evaluations: u64,
    /// Point contacts with the ground resolved.
    pub contacts_resolved: u64,
    /// Springs broken during the run.
    pub broken_springs: usize,
    /// Wall-clock time of the stepping loop, s (not in the summary file).
    #[serde(skip)]
    pub wall_s: f64,
}

/// Everything recorded by [`Scene::run`].
#[derive(Clone, Debug)]
pub struct SceneRun {
    /// Run numbers.
    pub stats: RunStats,
    /// Frame times, s.
    pub time: Vec<f64>,
    /// Per object (scene order): its pose trajectory, for leaves and rigid objects.
    pub poses: Vec<Option<Trajectory>>,
    /// Per object: its particle positions per frame, for deforming objects.
    pub particles: Vec<Option<Vec<Vec<V3>>>>,
    /// The state after the last frame.
    pub final_state: State,
}

impl Scene {
    /// Steps the scene from its initial state for `seconds` (default: its
    /// duration), calling `on_frame(k, state)` at frame 0 and after every
    /// frame. The simulator's error stops the run.
    pub fn run_with(
        &self,
        seconds: Option<f64>,
        on_frame: impl FnMut(u64, &State),
    ) -> Result<(RunStats, State), RunError> {
        let seconds = seconds.unwrap_or(self.duration);
        if !(seconds > 0.0 && seconds.is_finite()) {
            return Err(StepError::Duration(seconds).into());
        }
        let frame_dt = 1.0 / self.frame_rate;
        let dt = resolve_dt(&self.model, self.integrator, self.dt, frame_dt)?;
        check_budget(seconds, dt, self.frame_rate, self.integrator)?;
        let frames = (seconds * self.frame_rate).round().max(1.0) as u64;
        let mut state = self.initial.clone();
        let run = crate::physics::run::run_frames(
            &self.model,
            &mut state,
            self.integrator,
            dt,
            frame_dt,
            frames,
            on_frame,
        )
        .map_err(RunError::Sim)?;
        let stats = RunStats {
            integrator: run.integrator,
            dt,
            frame_rate: self.frame_rate,
            frames: frames + 1,
            simulated_s: run.simulated_s,
            steps: run.steps,
            force_evaluations: run.force_evals,
            contacts_resolved: run.contacts_resolved,
            broken_springs: state.broken_springs(),
            wall_s: run.wall_s,
        };
        Ok((stats, state))
    }

    /// Runs the scene and records every object: poses of leaves and rigid
    /// objects, particle positions of deforming ones.
    pub fn run(&self, seconds: Option<f64>) -> Result<SceneRun, RunError> {
        let mut trackers: Vec<Option<PoseTracker>> = self
            .objects
            .iter()
            .map(|o| {
                o.pose
                    .as_ref()
                    .map(|p| PoseTracker::new(&p.model, p.initial))
            })
            .collect();
        let mut poses: Vec<Option<Trajectory>> = self
            .objects
            .iter()
            .map(|o| o.pose.as_ref().map(|_| Trajectory::with_capacity(0)))
            .collect();
        let mut particles: Vec<Option<Vec<Vec<V3>>>> = self
            .objects
            .iter()
            .map(|o| o.writes_particles().then(Vec::new))
            .collect();
        let mut time = Vec::new();
        let mut scratch = Vec::new();
        let (stats, final_state) = self.run_with(seconds, |_, s| {
            time.push(s.time);
            for (o, obj) in self.objects.iter().enumerate() {
                scratch.clear();
                scratch.extend(obj.particles.iter().map(|&i| s.position[i]));
                if let (Some(tracker), Some(traj), Some(frame)) =
                    (&mut trackers[o], &mut poses[o], &obj.pose)
                {
                    let (c, q) = tracker.pose(&frame.model, &scratch);
                    traj.push(s.time, c, q);
                }
                if let Some(rec) = &mut particles[o] {
                    rec.push(scratch.clone());
                }
            }
        })?;
        Ok(SceneRun {
            stats,
            time,
            poses,
            particles,
            final_state,
        })
    }
}

#[derive(Serialize)]
struct ObjectSummary {
    name: String,
    kind: &'static str,
    particles: usize,
    #[serde(skip_serializing_if = "Option::is_none")]
    pose: Option<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    positions: Option<String>,
    /// Centre of mass at the first and last frame, m.
    start: [f64; 3],
    end: [f64; 3],
}

#[derive(Serialize)]
struct Summary<'a> {
    scene: &'a str,
    source: &'a str,
    #[serde(flatten)]
    stats: &'a RunStats,
    kept: Vec<String>,
    left_out: Vec<String>,
    pruned: &'a [String],
    #[serde(rename = "object")]
    objects: Vec<ObjectSummary>,
}

impl SceneRun {
    /// Writes `DIR/<object>.csv` (pose `t,x,y,z,qw,qx,qy,qz`) for leaves and
    /// rigid objects, `DIR/<object>-particles.csv` for deforming objects, and
    /// `DIR/summary.toml`; every file atomically. Returns the paths written.
    pub fn write(&self, scene: &Scene, dir: &Path) -> std::io::Result<Vec<PathBuf>> {
        std::fs::create_dir_all(dir)?;
        let mut written = Vec::new();
        let mut objects = Vec::new();
        for (o, obj) in scene.objects.iter().enumerate() {
            let mut summary = ObjectSummary {
                name: obj.name.clone(),
                kind: obj.kind.name(),
                particles: obj.particles.len(),
                pose: None,
                positions: None,
                start: [0.0; 3],
                end: [0.0; 3],
            };
            let centre = |x: &[V3]| -> [f64; 3] {
                let (mut c, mut m) = (V3::zeros(), 0.0);
                for &i in &obj.particles {
                    c += x[i] * scene.model.mass[i];
                    m += scene.model.mass[i];
                }
                (c / m).into()
            };
            summary.start = centre(&scene.initial.position);
            summary.end = centre(&self.final_state.position);
            if let Some(traj) = &self.poses[o] {
                let name = format!("{}.csv", obj.name);
                let path = dir.join(&name);
                traj.write_csv(&path)?;
                written.push(path);
                summary.pose = Some(name);
            }
            if let Some(frames) = &self.particles[o] {
                let name = format!("{}-particles.csv", obj.name);
                let path = dir.join(&name);
                write_atomic(&path, &particle_csv(&self.time, frames))?;
                written.push(path);
                summary.positions = Some(name);
            }
            if obj.kind != ObjectKind::Fixed {
                objects.push(summary);
            }
        }
        let decisions = scene.explain();
        let summary = Summary {
            scene: &scene.name,
            source: &scene.source,
            stats: &self.stats,
            kept: decisions
                .iter()
                .filter(|d| d.kept)
                .map(|d| d.name.to_string())
                .collect(),
            left_out: decisions
                .iter()
                .filter(|d| !d.kept)
                .map(|d| d.name.to_string())
                .collect(),
            pruned: &scene.pruned,
            objects,
        };
        let text = toml::to_string(&summary).map_err(std::io::Error::other)?;
        let path = dir.join("summary.toml");
        write_atomic(&path, text.as_bytes())?;
        written.push(path);
        Ok(written)
    }
}
