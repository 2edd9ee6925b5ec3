//! The settings a run takes, named in the library's own words, and how a
//! front end spells them for its user.
//!
//! An error that says what to change names a [`Setting`], never a flag:
//! the library is called by the command line, by the studio's page and by
//! tests, and each names a setting its own way. By default a setting reads
//! as its key (`max_work`, the name run files and scene files use); a front
//! end installs its own [`Spelling`] once, at start ([`spell_with`]): the
//! command line's spells `--max-work`.

use std::fmt;
use std::sync::OnceLock;

/// A setting of a run, a read or an export that a message may ask to
/// change.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Setting {
    /// Simulated seconds of a drop, a scene or a breeding run's drops.
    Duration,
    /// The most particle-steps a run may take.
    MaxWork,
    /// The most memory a run or a read may take, bytes.
    MaxMemory,
    /// The time integrator.
    Integrator,
    /// The time step (a number of seconds, or automatic).
    Dt,
    /// What the stress cases do with a step above the stability estimate.
    Explicit,
    /// Candidates per generation.
    Population,
    /// Generations to breed.
    Generations,
    /// The motion class bred toward.
    Target,
    /// Descriptor values bred toward.
    TargetFeatures,
    /// The spread of the first generation around the prototype.
    InitialScale,
    /// Release attitudes each candidate is dropped from.
    Releases,
    /// A breeding run whose leaves start another.
    StartFrom,
    /// The search strategy.
    Strategy,
    /// The leaf bred from.
    Prototype,
    /// The folder or file a command writes.
    Out,
    /// A run directory to go on with.
    Resume,
    /// A plate's size (its side, or its short side), m.
    Size,
    /// A rectangle's length over its width.
    Aspect,
    /// A cross plate's arm width.
    ArmWidth,
    /// A plate's mass per area, kg/m².
    ArealDensity,
    /// A flexible plate's bending stiffness, N·m.
    BendingStiffness,
    /// The object of an animation file to read.
    Object,
    /// The animation of a glTF file to read.
    Animation,
    /// Metres per unit of a file that carries no unit.
    Scale,
    /// Frames per second of an export or a preview.
    Fps,
    /// The file format of an export.
    Format,
    /// Which axis of a record points up.
    Up,
    /// The generation a shard evaluates.
    Generation,
    /// A shard's index.
    Index,
    /// The number of shards.
    Count,
    /// Folders besides a file's own that its references may reach.
    AllowReferences,
    /// The refinement of an accuracy sweep's reference.
    ReferenceJ,
    /// Candidates shown at once in the studio.
    Grid,
}

impl Setting {
    /// The setting's key, the library's own name for it.
    pub fn key(self) -> &'static str {
        match self {
            Setting::Duration => "duration",
            Setting::MaxWork => "max_work",
            Setting::MaxMemory => "max_memory",
            Setting::Integrator => "integrator",
            Setting::Dt => "dt",
            Setting::Explicit => "explicit",
            Setting::Population => "population",
            Setting::Generations => "generations",
            Setting::Target => "target",
            Setting::TargetFeatures => "target_features",
            Setting::InitialScale => "initial_scale",
            Setting::Releases => "releases",
            Setting::StartFrom => "start_from",
            Setting::Strategy => "strategy",
            Setting::Prototype => "prototype",
            Setting::Out => "out",
            Setting::Resume => "resume",
            Setting::Size => "size",
            Setting::Aspect => "aspect",
            Setting::ArmWidth => "arm_width",
            Setting::ArealDensity => "areal_density",
            Setting::BendingStiffness => "bending_stiffness",
            Setting::Object => "object",
            Setting::Animation => "animation",
            Setting::Scale => "scale",
            Setting::Fps => "fps",
            Setting::Format => "format",
            Setting::Up => "up",
            Setting::Generation => "generation",
            Setting::Index => "index",
            Setting::Count => "count",
            Setting::AllowReferences => "allow_references",
            Setting::ReferenceJ => "reference_j",
            Setting::Grid => "grid",
        }
    }

    /// The setting given `value`, for a message: `max_work = 1e9` by
    /// default, as its front end spells it otherwise.
    pub fn set(self, value: impl fmt::Display) -> Set {
        Set {
            setting: self,
            value: value.to_string(),
        }
    }
}

/// How a front end names settings to its user.
pub trait Spelling: Sync {
    /// The setting's name.
    fn name(&self, setting: Setting) -> String;
    /// The setting given a value.
    fn set(&self, setting: Setting, value: &str) -> String;
}

/// The front end's spelling, once installed.
static SPELLING: OnceLock<&'static dyn Spelling> = OnceLock::new();

/// Installs how settings are named for the rest of the process; the first
/// call wins (a process has one front end).
pub fn spell_with(spelling: &'static dyn Spelling) {
    let _ = SPELLING.set(spelling);
}

impl fmt::Display for Setting {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match SPELLING.get() {
            Some(s) => f.write_str(&s.name(*self)),
            None => f.write_str(self.key()),
        }
    }
}

/// A setting with a value, for a message ([`Setting::set`]).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Set {
    setting: Setting,
    value: String,
}

impl fmt::Display for Set {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match SPELLING.get() {
            Some(s) => f.write_str(&s.set(self.setting, &self.value)),
            None => write!(f, "{} = {}", self.setting.key(), self.value),
        }
    }
}
