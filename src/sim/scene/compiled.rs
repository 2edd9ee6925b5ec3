//! The compiled scene: [`Scene`], one model holding every object with its
//! initial state and run settings, and its objects, whose kind, particles
//! and pose reference decide what a run records and writes for each.

use crate::physics::model::Model;
use crate::physics::params::Integrator;
use crate::physics::params::TimeStep;
use crate::physics::state::State;
use crate::physics::terms::{Decision, Terms};
use nalgebra::UnitQuaternion;

/// The default limit of the memory a scene run records (every recorded
/// particle and pose at every frame, and their CSV text), bytes; `scene
/// --max-memory` raises it. The shipped scenes record at most 7 MB.
pub const MAX_MEMORY: f64 = 2e9;

/// What an object is, which decides what is written for it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ObjectKind {
    /// A leaf (pose, plus particles unless rigid).
    Leaf,
    /// A rigid shape (pose).
    Rigid,
    /// A flexible sheet (particles).
    Sheet,
    /// A rope (particles, ends included).
    Rope,
    /// A fixed particle (nothing).
    Fixed,
}

impl ObjectKind {
    /// The name used in summaries.
    pub fn name(self) -> &'static str {
        match self {
            ObjectKind::Leaf => "leaf",
            ObjectKind::Rigid => "rigid",
            ObjectKind::Sheet => "sheet",
            ObjectKind::Rope => "rope",
            ObjectKind::Fixed => "fixed",
        }
    }
}

/// The object's own rest shape, for pose extraction (body frame = the
/// object's local frame).
#[derive(Clone, Debug)]
pub struct PoseFrame {
    /// The object alone, in its local frame.
    pub model: Model,
    /// Its initial rotation (local → world).
    pub initial: UnitQuaternion<f64>,
}

/// One object of a compiled scene.
#[derive(Clone, Debug)]
pub struct SceneObject {
    /// Unique name (copies of a leaf object are `name-000`, ...).
    pub name: String,
    /// What it is.
    pub kind: ObjectKind,
    /// Its particles in the scene model (a rope's list includes its ends).
    pub particles: Vec<usize>,
    /// Pose reference for leaves and rigid objects.
    pub pose: Option<PoseFrame>,
    /// Index of its rigid body in the model, if rigid.
    pub rigid_body: Option<usize>,
    /// Its surface triangles for display and export, as indices into
    /// `particles`. Kept apart from the model's triangles because the
    /// compiler drops surfaces that feel no wind (a rigid bin with zero
    /// aerodynamic coefficients still has to be drawn).
    pub surface: Vec<[usize; 3]>,
}

impl SceneObject {
    /// Whether per-frame particle positions are written for it.
    pub fn writes_particles(&self) -> bool {
        match self.kind {
            ObjectKind::Leaf => self.rigid_body.is_none(),
            ObjectKind::Sheet | ObjectKind::Rope => true,
            ObjectKind::Rigid | ObjectKind::Fixed => false,
        }
    }
}

/// A compiled scene: one model holding every object, the initial state and
/// the run settings.
#[derive(Clone, Debug)]
pub struct Scene {
    /// Scene name.
    pub name: String,
    /// Free text from the file.
    pub description: String,
    /// The file it came from.
    pub source: String,
    /// All objects' particles, springs, triangles, hinges, rigid bodies,
    /// ground and wind: only what the scene uses.
    pub model: Model,
    /// Positions and velocities at t = 0.
    pub initial: State,
    /// The objects, in file order.
    pub objects: Vec<SceneObject>,
    /// Time integrator.
    pub integrator: Integrator,
    /// Time step setting.
    pub dt: TimeStep,
    /// Simulated duration, s.
    pub duration: f64,
    /// Output frames per simulated second.
    pub frame_rate: f64,
    /// Items the compiler left out of the model, with the reason.
    pub pruned: Vec<String>,
    /// A run is refused past this many particle-steps
    /// ([`crate::physics::run::MAX_WORK`] unless raised).
    pub max_work: f64,
    /// A recorded run is refused past this many bytes of frames
    /// ([`MAX_MEMORY`] unless raised).
    pub max_memory: f64,
}

impl Scene {
    /// The terms and passes the compiled model needs.
    pub fn terms(&self) -> Terms {
        Terms::needed(&self.model)
    }

    /// What was kept and what was left out, and why.
    pub fn explain(&self) -> Vec<Decision> {
        self.terms().explain(&self.model, self.integrator)
    }

    /// The object called `name`.
    pub fn object(&self, name: &str) -> Option<&SceneObject> {
        self.objects.iter().find(|o| o.name == name)
    }
}
