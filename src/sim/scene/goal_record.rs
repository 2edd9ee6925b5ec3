//! What a run of a scene says of its `[[goal]]` tables: each goal's shape
//! (as checked by `crate::direct`) and each of its leaves' verdict, written
//! as `goals.json` beside `summary.toml` by `leafmagic scene` and read back
//! by `preview`, which draws the goals and colours the leaves. It lives
//! here, below both, so that the writer (`direct`, which judges) and the
//! reader (`output`) share one format.

use super::goal_spec::GoalKind;
use serde::{Deserialize, Serialize};

/// The file's name in a scene's output directory.
pub const GOALS_FILE: &str = "goals.json";

/// Every goal of a scene, judged on one run.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GoalsRecord {
    /// The goals, in file order.
    pub goals: Vec<GoalRecord>,
}

/// One goal: where it is, when it looks, and how its leaves did.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GoalRecord {
    /// Its name.
    pub name: String,
    /// What it asks.
    pub kind: GoalKind,
    /// `land`: the polygon on the ground, `[x, y]`, m.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub polygon: Option<Vec<[f64; 2]>>,
    /// `land`, `pass`, `stay`: a box's lower corner, m.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub min: Option<[f64; 3]>,
    /// A box's upper corner, m.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max: Option<[f64; 3]>,
    /// `pass`: the point, m.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub point: Option<[f64; 3]>,
    /// `pass`: the distance from the point that counts as through it, m.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tolerance: Option<f64>,
    /// `land`: the ground's height, m.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ground: Option<f64>,
    /// `enter`: the rigid object's name (drawn as itself).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub object: Option<String>,
    /// The window's start, s (the time itself for `pass` and `enter`).
    pub from: f64,
    /// The window's end, s.
    pub to: f64,
    /// The fraction of its leaves that met it.
    pub met_fraction: f64,
    /// Their mean distance to it, m.
    pub mean_distance: f64,
    /// Per leaf, in the goal's order.
    pub leaves: Vec<LeafRecord>,
}

/// One leaf against one goal.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LeafRecord {
    /// The leaf's object name (`east-001`).
    pub name: String,
    /// Whether it met the goal.
    pub met: bool,
    /// How far it was from meeting it, m (0 when met).
    pub distance: f64,
}
