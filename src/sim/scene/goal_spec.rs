//! The directing tables of a scene file as written: `[[goal]]` (where the
//! leaves should go) and `[[free]]` (which numbers a search may change,
//! within bounds). `leafmagic scene` reads and ignores them; `crate::direct`
//! (a layer above this one) checks and uses them. Every field is documented
//! in `scenes/README.md`.

use serde::de::Deserializer;
use serde::{Deserialize, Serialize};

fn goal_kind<'de, D: Deserializer<'de>>(d: D) -> Result<GoalKind, D::Error> {
    crate::util::named::by_name(d, &["land", "pass", "stay", "enter"])
}

/// What a goal asks of its leaves.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum GoalKind {
    /// First touch the ground inside a region (`polygon` on the ground, or
    /// the box `min`..`max`) between `after` and `before`.
    Land,
    /// Be within `tolerance` of `point`, or inside the box, at time `at`.
    Pass,
    /// Stay inside the box from `after` until `until`.
    Stay,
    /// Be inside the rigid `object` (a cylinder: the bin) at time `by`.
    Enter,
}

impl GoalKind {
    /// The name used in the file.
    pub fn name(self) -> &'static str {
        match self {
            GoalKind::Land => "land",
            GoalKind::Pass => "pass",
            GoalKind::Stay => "stay",
            GoalKind::Enter => "enter",
        }
    }
}

/// One leaf-group name or a list of them.
#[derive(Clone, Debug, Deserialize)]
#[serde(untagged)]
pub enum LeafNames {
    /// One name.
    One(String),
    /// Several.
    Many(Vec<String>),
}

impl LeafNames {
    /// The names as a list.
    pub fn names(&self) -> Vec<String> {
        match self {
            LeafNames::One(n) => vec![n.clone()],
            LeafNames::Many(v) => v.clone(),
        }
    }
}

/// A `[[goal]]` table: which leaves, and what they should do. Which of the
/// optional fields apply depends on `kind`; the directing layer checks them.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GoalSpec {
    /// Name, in reports.
    pub name: String,
    /// `[[leaf]]` group names (or copy names, `east-001`).
    #[serde(default)]
    pub leaves: Option<LeafNames>,
    /// What is asked.
    #[serde(deserialize_with = "goal_kind")]
    pub kind: GoalKind,
    /// `land`: a polygon on the ground, `[[x, y], ...]`, m.
    #[serde(default)]
    pub polygon: Option<Vec<[f64; 2]>>,
    /// A box's lower corner, m.
    #[serde(default)]
    pub min: Option<[f64; 3]>,
    /// A box's upper corner, m.
    #[serde(default)]
    pub max: Option<[f64; 3]>,
    /// `pass`: the point, m.
    #[serde(default)]
    pub point: Option<[f64; 3]>,
    /// `pass`: how near the point counts as through it, m.
    #[serde(default)]
    pub tolerance: Option<f64>,
    /// `enter`: the rigid object's name.
    #[serde(default)]
    pub object: Option<String>,
    /// `land`, `stay`: start of the window, s (default 0).
    #[serde(default)]
    pub after: Option<f64>,
    /// `land`: end of the window, s (default: the scene's duration).
    #[serde(default)]
    pub before: Option<f64>,
    /// `pass`: the time, s.
    #[serde(default)]
    pub at: Option<f64>,
    /// `stay`: end of the window, s.
    #[serde(default)]
    pub until: Option<f64>,
    /// `enter`: the time, s.
    #[serde(default)]
    pub by: Option<f64>,
}

/// A `[[free]]` table: a number of the file that a search may change,
/// within `min`..`max`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FreeSpec {
    /// The field, as a path in the file: `wind[1].circulation`,
    /// `wind[0].velocity[2]`, `leaf[east].position[0]`.
    pub parameter: String,
    /// Lower bound.
    #[serde(default)]
    pub min: Option<f64>,
    /// Upper bound.
    #[serde(default)]
    pub max: Option<f64>,
}
