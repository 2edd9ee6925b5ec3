//! Scenes (the paper's section 4): leaves, rigid objects, sheets, fixed
//! particles and ropes in one wind field over an optional ground, read from a
//! TOML file (`scenes/README.md` documents every field) and compiled into one
//! [`Model`].
//!
//! The compiler keeps only what the scene uses. Items that can never act are
//! left out of the model (wind primitives of zero strength, surfaces with zero
//! aerodynamic coefficients, springs and hinges inside a rigid body, whose
//! forces cancel in its net force and torque); then [`Terms::needed`] drops
//! every force term and pass the model gives nothing to do (no wind
//! evaluation in still air, no contact pass without ground, no breaking
//! checks without breakable springs, no rigid-body pass without rigid
//! bodies). [`Scene::explain`] lists both.
//!
//! Errors name the file, the line and the field (`scene.toml:12: leaf[0].count: ...`).
//!
//! Its files, one job each: `spec` (the file as written), `compile` (reading
//! and compiling it), `bounds` (its cost estimated from the file, before
//! anything is built), `objects` (placing each kind of object), `shapes` (the
//! built-in shapes' particles), `builder` (the model's parts as they
//! accumulate, with each item's owner), `goal_spec` (the `[[goal]]` and `[[free]]` tables
//! that `direct` reads and a plain run ignores), `goal_record` (the goals and
//! each leaf's verdict on a run, as `goals.json`), `error` (errors and the checks that
//! raise them, with line numbers from [`crate::util::toml_lines`]), `compiled` (the compiled
//! scene), `run` (running and writing it), `skips` (what exact skipping
//! leaves out, for `--explain`); this file re-exports what they make public.
//!
//! [`Model`]: crate::physics::model::Model
//! [`Terms::needed`]: crate::physics::terms::Terms::needed

mod bounds;
mod builder;
mod compile;
mod compiled;
mod error;
mod goal_record;
mod goal_spec;
mod objects;
mod run;
mod shapes;
mod skips;
mod spec;

pub use bounds::Limits;
pub use builder::{MAX_PARTICLES, MAX_SPRINGS};
pub use compiled::{MAX_MEMORY, ObjectKind, PoseFrame, Scene, SceneObject};
pub use error::SceneError;
pub use goal_record::{GOALS_FILE, GoalRecord, GoalsRecord, LeafRecord};
pub use goal_spec::{FreeSpec, GoalKind, GoalSpec, LeafNames};
pub use run::{OutputError, RunError, RunStats, SceneRun, Staged, default_out_dir};
pub use skips::GroupSkips;
pub use spec::{
    DtSpec, FixedPoint, LeafObject, Pin, RigidObject, RopeObject, SceneSpec, Shape, SheetObject,
};
