//! The goals of a plain scene run judged (what `leafmagic scene` records
//! for `preview` in `goals.json`): the scene file's `[[goal]]` tables
//! checked as `direct` checks them, the run's frames recorded as `direct`
//! records them, and each leaf judged by [`goals::judge`], so that one
//! place decides what "met" means.

use super::error::Where;
use super::geometry::Aabb;
use super::goals::{self, Aim, Goal, GoalResult, Region, Target, Tracks};
use crate::sim::scene::{GoalKind, GoalRecord, GoalsRecord, LeafRecord, Scene, SceneSpec};
use crate::util::bad_input::BadInput;

/// The checked goals of the scene file `text` (named `file`), compiled as
/// `scene`; none when it states none. Its `[[free]]` tables are not read:
/// a run uses the values written.
///
/// # Errors
/// A goal is bad ([`goals::check`]).
pub fn goals_of(text: &str, file: &str, scene: &Scene) -> Result<Vec<Goal>, BadInput> {
    let spec: SceneSpec = toml::from_str(text).map_err(|e| BadInput::toml_parse(file, text, &e))?;
    if spec.goals.is_empty() {
        return Ok(Vec::new());
    }
    goals::check(&spec, scene, &Where { file, text })
}

/// A run's goals as they are judged while it runs: feed every frame's
/// positions to [`Judging::record`], then take [`Judging::finish`].
#[derive(Clone, Debug)]
pub struct Judging {
    goals: Vec<Goal>,
    tracks: Tracks,
}

impl Judging {
    /// Starts judging `goals` on a run of `scene`.
    pub fn new(scene: &Scene, goals: Vec<Goal>) -> Judging {
        Judging {
            tracks: Tracks::new(scene),
            goals,
        }
    }

    /// Records one frame.
    pub fn record(&mut self, scene: &Scene, positions: &[nalgebra::Vector3<f64>]) {
        self.tracks.record(scene, &self.goals, positions);
    }

    /// Each goal judged on the frames recorded, with its shape, and its
    /// leaves named as `scene` names them.
    pub fn finish(&self, scene: &Scene) -> GoalsRecord {
        GoalsRecord {
            goals: self
                .goals
                .iter()
                .map(|g| record(g, &goals::judge(g, &self.tracks), scene))
                .collect(),
        }
    }
}

/// One goal and its verdicts as recorded.
pub fn record(goal: &Goal, result: &GoalResult, scene: &Scene) -> GoalRecord {
    let mut r = GoalRecord {
        name: goal.name.clone(),
        kind: GoalKind::Land,
        polygon: None,
        min: None,
        max: None,
        point: None,
        tolerance: None,
        ground: None,
        object: None,
        from: 0.0,
        to: goal.end(),
        met_fraction: result.met_fraction,
        mean_distance: result.mean_distance,
        leaves: goal
            .leaves
            .iter()
            .zip(&result.leaves)
            .map(|(&k, v)| LeafRecord {
                name: scene.objects[k].name.clone(),
                met: v.met,
                distance: v.distance,
            })
            .collect(),
    };
    let set_box = |r: &mut GoalRecord, b: &Aabb| {
        r.min = Some(b.min.into());
        r.max = Some(b.max.into());
    };
    match &goal.aim {
        Aim::Land {
            region,
            after,
            ground,
            ..
        } => {
            r.from = *after;
            r.ground = Some(*ground);
            match region {
                Region::Polygon(p) => r.polygon = Some(p.vertices.clone()),
                Region::Box(b) => set_box(&mut r, b),
            }
        }
        Aim::Pass { target, at } => {
            r.kind = GoalKind::Pass;
            r.from = *at;
            match target {
                Target::Point { point, tolerance } => {
                    r.point = Some((*point).into());
                    r.tolerance = Some(*tolerance);
                }
                Target::Box(b) => set_box(&mut r, b),
            }
        }
        Aim::Stay { region, after, .. } => {
            r.kind = GoalKind::Stay;
            r.from = *after;
            set_box(&mut r, region);
        }
        Aim::Enter { object, by, .. } => {
            r.kind = GoalKind::Enter;
            r.from = *by;
            r.object = Some(scene.objects[*object].name.clone());
        }
    }
    r
}
