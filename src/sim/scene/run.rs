//! Running a compiled scene frame by frame, recording each object, and
//! writing the per-object trajectories and the summary.

use super::compiled::{ObjectKind, Scene};
use crate::motion::trajectory::Trajectory;
use crate::physics::integrate::SimError;
use crate::physics::params::Integrator;
use crate::physics::params::TimeStep;
use crate::physics::pose::PoseTracker;
use crate::physics::run::{PoseFault, RunKind, StepError, Work, check_budget, resolve_dt};
use crate::physics::skip::SkipCounts;
use crate::physics::state::State;
use crate::util::io::particle_csv;
use crate::util::setting::Setting;
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
    /// The recording would not fit the memory limit.
    #[error(
        "recording this scene would take about {:.2e} bytes (every recorded particle and pose \
         at every frame), more than the limit of {limit:.1e}: lower `frame_rate` or the duration \
         (or {}), record fewer deforming objects, or raise the limit with `{}`",
        .bytes,
        Setting::Duration,
        Setting::MaxMemory.set(format_args!("{:.1e}", .bytes * 1.01))
    )]
    Memory {
        /// The estimate, bytes.
        bytes: f64,
        /// The limit, bytes.
        limit: f64,
    },
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
    /// What exact skipping left out (not in the summary file, which stays
    /// as it was without it).
    #[serde(skip)]
    pub skips: SkipCounts,
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
        mut on_frame: impl FnMut(u64, &State),
    ) -> Result<(RunStats, State), RunError> {
        self.run_until(seconds, |k, s| {
            on_frame(k, s);
            Ok(())
        })
    }

    /// [`Scene::run_with`] with an `on_frame` that may stop the run with a
    /// [`PoseFault`] (the simulator's diagnosis of that step).
    pub fn run_until(
        &self,
        seconds: Option<f64>,
        on_frame: impl FnMut(u64, &State) -> Result<(), PoseFault>,
    ) -> Result<(RunStats, State), RunError> {
        let seconds = seconds.unwrap_or(self.duration);
        if !(seconds > 0.0 && seconds.is_finite()) {
            return Err(StepError::Duration(seconds).into());
        }
        let work = self.work(Some(seconds))?;
        work.check(
            &self.model,
            1.0 / self.frame_rate,
            self.max_work,
            RunKind::Scene,
        )?;
        let (frame_dt, dt) = (1.0 / self.frame_rate, work.dt);
        let frames = (seconds * self.frame_rate).round().max(1.0) as u64;
        let mut state = self.initial.clone();
        let run = crate::physics::run::run_frames_until(
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
            skips: run.skips,
            wall_s: run.wall_s,
        };
        Ok((stats, state))
    }

    /// What a run of `seconds` (default: the duration) will cost, before it
    /// starts: particles × steps, the step and why ([`Work`]).
    ///
    /// # Errors
    /// Bad settings: the duration, the step, the step and frame counts.
    pub fn work(&self, seconds: Option<f64>) -> Result<Work, StepError> {
        let seconds = seconds.unwrap_or(self.duration);
        if !(seconds > 0.0 && seconds.is_finite()) {
            return Err(StepError::Duration(seconds));
        }
        let frame_dt = 1.0 / self.frame_rate;
        let dt = resolve_dt(&self.model, self.integrator, self.dt, frame_dt)?;
        check_budget(seconds, dt, self.frame_rate, self.integrator)?;
        Ok(Work::of(
            &self.model,
            self.integrator,
            dt,
            self.dt == TimeStep::Auto,
            seconds,
            frame_dt,
        ))
    }

    /// Bytes a recorded run of `seconds` holds before it is written: every
    /// recorded particle (24 bytes, and up to 75 of CSV text) and pose (64,
    /// and up to 200) at every frame.
    pub fn recorded_bytes(&self, seconds: Option<f64>) -> f64 {
        let frames = (seconds.unwrap_or(self.duration) * self.frame_rate).round() + 1.0;
        let particles: usize = self
            .objects
            .iter()
            .filter(|o| o.writes_particles())
            .map(|o| o.particles.len())
            .sum();
        let poses = self.objects.iter().filter(|o| o.pose.is_some()).count();
        frames * (particles as f64 * 99.0 + poses as f64 * 264.0)
    }

    /// Runs the scene and records every object: poses of leaves and rigid
    /// objects, particle positions of deforming ones.
    pub fn run(&self, seconds: Option<f64>) -> Result<SceneRun, RunError> {
        self.run_observed(seconds, |_, _| {})
    }

    /// [`Scene::run`], calling `progress(frame, frames)` after every frame.
    /// Refused before anything is allocated if the recording would pass
    /// [`Scene::max_memory`].
    pub fn run_observed(
        &self,
        seconds: Option<f64>,
        mut progress: impl FnMut(u64, u64),
    ) -> Result<SceneRun, RunError> {
        self.run_watched(seconds, |k, total, _| progress(k, total))
    }

    /// [`Scene::run_observed`], also showing `watch` each frame's state
    /// (what a judge of the run's goals records).
    pub fn run_watched(
        &self,
        seconds: Option<f64>,
        mut watch: impl FnMut(u64, u64, &State),
    ) -> Result<SceneRun, RunError> {
        let bytes = self.recorded_bytes(seconds);
        if bytes > self.max_memory {
            return Err(RunError::Memory {
                bytes,
                limit: self.max_memory,
            });
        }
        let total = (seconds.unwrap_or(self.duration) * self.frame_rate)
            .round()
            .max(1.0) as u64;
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
        let (stats, final_state) = self.run_until(seconds, |k, s| {
            watch(k, total, s);
            time.push(s.time);
            for (o, obj) in self.objects.iter().enumerate() {
                scratch.clear();
                scratch.extend(obj.particles.iter().map(|&i| s.position[i]));
                if let (Some(tracker), Some(traj), Some(frame)) =
                    (&mut trackers[o], &mut poses[o], &obj.pose)
                {
                    let (c, q) = tracker.pose(&frame.model, &scratch);
                    if !(c.iter().all(|v| v.is_finite()) && q.coords.iter().all(|v| v.is_finite()))
                    {
                        return Err(PoseFault::of(&self.model, &scratch, &c, &obj.particles));
                    }
                    traj.push(s.time, c, q);
                }
                if let Some(rec) = &mut particles[o] {
                    rec.push(scratch.clone());
                }
            }
            Ok(())
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
    /// The leaves' aerodynamic law (`scene --law` or their files').
    aero_law: &'static str,
    #[serde(flatten)]
    stats: &'a RunStats,
    kept: Vec<String>,
    left_out: Vec<String>,
    pruned: &'a [String],
    #[serde(rename = "object")]
    objects: Vec<ObjectSummary>,
}

/// The default output directory of a scene: `runs/scene-<name>`.
pub fn default_out_dir(scene: &Scene) -> PathBuf {
    PathBuf::from("runs").join(format!("scene-{}", scene.name))
}

/// A file of a scene's output that could not be written, named as it
/// would have been in the output directory (which is left as it was).
#[derive(Debug, thiserror::Error)]
#[error("{}: {message}", .path.display())]
pub struct OutputError {
    /// The file (or the directory, when it is the directory that is wrong).
    pub path: PathBuf,
    /// Why, and what was left.
    pub message: String,
}

/// An output directory written as a whole: files go into a temporary
/// sibling (`.<name>.partial-<pid>`), which [`Staged::commit`] renames into
/// place once everything is written. A failure, or a drop without commit,
/// removes the sibling and leaves the directory as it was: the previous
/// run's files, or nothing. A directory is replaced only if it is empty or
/// a scene's output (it holds `summary.toml`), so no other folder is ever
/// swept away.
#[derive(Debug)]
pub struct Staged {
    dir: PathBuf,
    tmp: PathBuf,
    committed: bool,
}

impl Staged {
    /// Starts writing `dir`.
    ///
    /// # Errors
    /// `dir` is a file, or a directory that is not a scene's output, or the
    /// sibling cannot be made.
    pub fn new(dir: &Path) -> Result<Staged, OutputError> {
        let refuse = |message: String| OutputError {
            path: dir.to_path_buf(),
            message,
        };
        if dir.exists() && !dir.is_dir() {
            return Err(refuse(format!(
                "is a file, not a directory; a scene writes a folder of files: name another \
                 {} or remove the file",
                Setting::Out
            )));
        }
        if dir.is_dir() && !dir.join("summary.toml").exists() {
            let empty = std::fs::read_dir(dir)
                .map_err(|e| refuse(format!("cannot be read: {e}")))?
                .next()
                .is_none();
            if !empty {
                return Err(refuse(format!(
                    "exists and is not a scene's output (no summary.toml); a scene's output \
                     replaces its directory as a whole, so it will not replace this one: name \
                     another {}",
                    Setting::Out
                )));
            }
        }
        // Staging folders of killed runs go; a live one's stays.
        let tmp = crate::util::io::staging_dir(dir).map_err(|e| OutputError {
            path: dir.to_path_buf(),
            message: format!("cannot create a staging folder beside it: {e}"),
        })?;
        Ok(Staged {
            dir: dir.to_path_buf(),
            tmp,
            committed: false,
        })
    }

    /// Where files are written until the commit.
    pub fn path(&self) -> &Path {
        &self.tmp
    }

    /// The final path of a file written into [`Staged::path`].
    pub fn final_path(&self, written: &Path) -> PathBuf {
        written
            .strip_prefix(&self.tmp)
            .map_or_else(|_| written.to_path_buf(), |rel| self.dir.join(rel))
    }

    /// Writes `bytes` as `name`, or names the file and says nothing changed.
    pub fn write(&self, name: &str, bytes: &[u8]) -> Result<PathBuf, OutputError> {
        let path = self.tmp.join(name);
        std::fs::write(&path, bytes).map_err(|e| self.failed(name, &e))?;
        Ok(path)
    }

    /// The error of a file that could not be written.
    pub fn failed(&self, name: &str, e: &dyn std::fmt::Display) -> OutputError {
        OutputError {
            path: self.dir.join(name),
            message: format!(
                "cannot be written: {e}; nothing was changed in {}",
                self.dir.display()
            ),
        }
    }

    /// Puts the written directory in place of the previous one, if any, in
    /// one exchange where the file system allows
    /// ([`crate::util::io::swap_dir`]), and removes the previous one.
    ///
    /// # Errors
    /// A rename failed; the previous directory is put back if it can be.
    pub fn commit(mut self) -> Result<(), OutputError> {
        let fail = |e: std::io::Error| OutputError {
            path: self.dir.clone(),
            message: format!("cannot be replaced: {e}"),
        };
        crate::util::io::swap_dir(&self.tmp, &self.dir).map_err(fail)?;
        self.committed = true;
        Ok(())
    }
}

impl Drop for Staged {
    fn drop(&mut self) {
        if !self.committed {
            let _ = std::fs::remove_dir_all(&self.tmp);
        }
    }
}

impl SceneRun {
    /// Writes `DIR/<object>.csv` (pose `t,x,y,z,qw,qx,qy,qz`) for leaves and
    /// rigid objects, `DIR/<object>-particles.csv` for deforming objects, and
    /// `DIR/summary.toml`, as a whole ([`Staged`]): a failure leaves `DIR`
    /// as it was and names the file. Returns the paths written.
    pub fn write(&self, scene: &Scene, dir: &Path) -> Result<Vec<PathBuf>, OutputError> {
        let staged = Staged::new(dir)?;
        let written = self.write_staged(scene, &staged)?;
        staged.commit()?;
        Ok(written)
    }

    /// [`SceneRun::write`] into a [`Staged`] directory that the caller
    /// commits (after adding files of its own, such as an export). Returns
    /// the final paths.
    pub fn write_staged(
        &self,
        scene: &Scene,
        staged: &Staged,
    ) -> Result<Vec<PathBuf>, OutputError> {
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
                let bytes = traj
                    .try_to_csv_bytes()
                    .map_err(|e| staged.failed(&name, &e))?;
                written.push(staged.final_path(&staged.write(&name, &bytes)?));
                summary.pose = Some(name);
            }
            if let Some(frames) = &self.particles[o] {
                let name = format!("{}-particles.csv", obj.name);
                let path = staged.write(&name, &particle_csv(&self.time, frames))?;
                written.push(staged.final_path(&path));
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
            aero_law: scene.model.aero.name(),
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
        let text = toml::to_string(&summary).map_err(|e| staged.failed("summary.toml", &e))?;
        let path = staged.write("summary.toml", text.as_bytes())?;
        written.push(staged.final_path(&path));
        Ok(written)
    }
}
