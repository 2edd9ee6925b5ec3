//! A directing problem read from a scene file: the scene as written, its
//! checked goals and free parameters, and the evaluation of one choice of
//! the free values (substituted, compiled, run as far as the last goal
//! looks, and judged).

use super::error::Where;
use super::free::{self, Free};
use super::goals::{self, Goal, GoalResult, Tracks};
use crate::sim::scene::{Scene, SceneSpec};
use crate::util::bad_input::BadInput;
use std::path::{Path, PathBuf};

/// A leaf of a run that failed (diverged) counts this far from every goal,
/// m: far worse than any leaf that ran.
pub const FAILED_DISTANCE: f64 = 100.0;

/// A scene file with goals and free parameters.
#[derive(Clone, Debug)]
pub struct Problem {
    /// The file as named.
    pub file: String,
    /// Its directory (leaf paths are relative to it).
    pub base: PathBuf,
    /// The file parsed as a plain document, where free values go.
    pub document: toml::Table,
    /// The file parsed as a scene.
    pub spec: SceneSpec,
    /// The scene at the file's own values.
    pub scene: Scene,
    /// The goals.
    pub goals: Vec<Goal>,
    /// The free parameters.
    pub free: Vec<Free>,
    /// How far a run goes: the last time a goal looks at, on a frame, s.
    pub seconds: f64,
}

/// One choice of the free values, judged.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Evaluation {
    /// Per goal.
    pub goals: Vec<GoalResult>,
    /// The search's objective (lower is better): per goal, the mean
    /// distance of its leaves (m) plus the fraction that missed, averaged
    /// over the goals. The distance makes it smooth where the fraction is
    /// flat; the fraction rewards finishing the job.
    pub objective: f64,
    /// Why the run failed, if it did (every leaf then counts as
    /// [`FAILED_DISTANCE`] away).
    pub failed: Option<String>,
}

impl Evaluation {
    /// The mean over goals of the fraction of leaves that met them.
    pub fn met_fraction(&self) -> f64 {
        self.goals.iter().map(|g| g.met_fraction).sum::<f64>() / self.goals.len().max(1) as f64
    }
}

/// The objective of judged goals ([`Evaluation::objective`]).
pub fn objective(goals: &[GoalResult]) -> f64 {
    goals
        .iter()
        .map(|g| g.mean_distance + (1.0 - g.met_fraction))
        .sum::<f64>()
        / goals.len().max(1) as f64
}

impl Problem {
    /// Reads a scene file with goals and free parameters.
    ///
    /// # Errors
    /// The file cannot be read, is not a scene, has no goal or no free
    /// parameter, or a goal or free parameter is bad.
    pub fn load(path: &Path) -> Result<Problem, BadInput> {
        let file = path.display().to_string();
        let text = std::fs::read_to_string(path)
            .map_err(|e| BadInput::file(file.clone(), format!("cannot read: {e}")))?;
        let base = path.parent().map(Path::to_path_buf).unwrap_or_default();
        Problem::from_toml(&text, &file, &base)
    }

    /// [`Problem::load`] from text; `file` names it in errors and leaf
    /// paths are relative to `base`.
    ///
    /// # Errors
    /// As [`Problem::load`].
    pub fn from_toml(text: &str, file: &str, base: &Path) -> Result<Problem, BadInput> {
        let scene = Scene::from_toml(text, file, base)?;
        let spec: SceneSpec =
            toml::from_str(text).map_err(|e| BadInput::toml_parse(file, text, &e))?;
        let document: toml::Table =
            toml::from_str(text).map_err(|e| BadInput::toml_parse(file, text, &e))?;
        let at = Where { file, text };
        if spec.goals.is_empty() {
            return Err(at.err(
                "goal",
                "the scene states no [[goal]]: directing needs at least one",
            ));
        }
        if spec.free.is_empty() {
            return Err(at.err(
                "free",
                "the scene has no [[free]] parameter: there is nothing to search",
            ));
        }
        let goals = goals::check(&spec, &scene, &at)?;
        let free = free::check(&spec, &document, &at)?;
        let last = goals.iter().map(Goal::end).fold(0.0, f64::max);
        // On a frame, at least one frame in.
        let seconds =
            ((last * scene.frame_rate).ceil().max(1.0) / scene.frame_rate).min(spec.duration);
        let problem = Problem {
            file: file.to_string(),
            base: base.to_path_buf(),
            document,
            spec,
            scene,
            goals,
            free,
            seconds,
        };
        // Bounds the scene refuses are refused here, not mid-search: the
        // scene compiled with each parameter at each bound, the others as
        // written.
        for (i, f) in problem.free.iter().enumerate() {
            for (bound, v) in [("min", f.min), ("max", f.max)] {
                let mut values: Vec<f64> = problem.free.iter().map(|g| g.written).collect();
                values[i] = v;
                if let Err(e) = problem.scene_at(&values) {
                    return Err(at.err(
                        format!("free[{i}].{bound}"),
                        format!(
                            "the scene refuses {} = {v}: {}: {}",
                            f.parameter, e.field, e.reason
                        ),
                    ));
                }
            }
        }
        Ok(problem)
    }

    /// The document with `values` (one per free parameter) in place.
    pub fn document_at(&self, values: &[f64]) -> toml::Table {
        let mut doc = self.document.clone();
        for (f, &v) in self.free.iter().zip(values) {
            free::set(&mut doc, &f.path, v);
        }
        doc
    }

    /// The scene compiled with `values`.
    ///
    /// # Errors
    /// The scene refuses the values (a core radius of 0, say).
    pub fn scene_at(&self, values: &[f64]) -> Result<Scene, BadInput> {
        let spec: SceneSpec = toml::Value::Table(self.document_at(values))
            .try_into()
            .map_err(|e: toml::de::Error| BadInput::file(self.file.clone(), e.to_string()))?;
        Scene::from_spec(&spec, &self.file, &self.base)
    }

    /// The values of unit coordinates `u` (each in [0, 1] of its bounds).
    pub fn values(&self, u: &[f64]) -> Vec<f64> {
        self.free.iter().zip(u).map(|(f, &x)| f.value(x)).collect()
    }

    /// Runs the scene with `values` as far as the goals look and judges it.
    pub fn evaluate(&self, values: &[f64]) -> Evaluation {
        let run = self
            .scene_at(values)
            .map_err(|e| e.to_string())
            .and_then(|scene| {
                let mut tracks = Tracks::new(&scene);
                scene
                    .run_with(Some(self.seconds), |_, s| {
                        tracks.record(&scene, &self.goals, &s.position)
                    })
                    .map(|_| tracks)
                    .map_err(|e| e.to_string())
            });
        match run {
            Ok(tracks) => {
                let goals: Vec<GoalResult> = self
                    .goals
                    .iter()
                    .map(|g| goals::judge(g, &tracks))
                    .collect();
                Evaluation {
                    objective: objective(&goals),
                    goals,
                    failed: None,
                }
            }
            Err(why) => {
                let goals: Vec<GoalResult> = self
                    .goals
                    .iter()
                    .map(|g| GoalResult {
                        met_fraction: 0.0,
                        mean_distance: FAILED_DISTANCE,
                        leaves: vec![
                            goals::LeafVerdict {
                                met: false,
                                distance: FAILED_DISTANCE
                            };
                            g.leaves.len()
                        ],
                    })
                    .collect();
                Evaluation {
                    objective: objective(&goals),
                    goals,
                    failed: Some(why),
                }
            }
        }
    }

    /// The solved scene: the file's document with `values` in place and
    /// its `[[free]]` tables removed (the goals stay, which `scene`
    /// ignores), after `header` as comment lines.
    pub fn solved_toml(&self, values: &[f64], header: &[String]) -> String {
        let mut doc = self.document_at(values);
        doc.remove("free");
        let mut out = String::new();
        for line in header {
            out.push_str(&format!("# {line}\n"));
        }
        out.push('\n');
        out.push_str(&toml::to_string(&doc).expect("a parsed document serialises"));
        out
    }
}
