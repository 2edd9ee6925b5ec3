//! The command line's words for the library's settings: each
//! [`Setting`] is the flag that sets it.

use leafmagic::util::setting::{Setting, Spelling};

/// Settings spelled as flags: `--max-work`, `--max-work 1.2e9`.
pub struct Flags;

impl Spelling for Flags {
    fn name(&self, setting: Setting) -> String {
        flag(setting).to_string()
    }

    fn set(&self, setting: Setting, value: &str) -> String {
        // `--up=-y`: a value that starts with a dash would read as a flag.
        if value.starts_with('-') {
            format!("{}={value}", flag(setting))
        } else {
            format!("{} {value}", flag(setting))
        }
    }
}

/// The flag that sets `setting`.
pub fn flag(setting: Setting) -> &'static str {
    match setting {
        Setting::Duration => "--seconds",
        Setting::MaxWork => "--max-work",
        Setting::MaxMemory => "--max-memory",
        Setting::Integrator => "--integrator",
        Setting::Dt => "--dt",
        Setting::Explicit => "--explicit",
        Setting::Population => "--population",
        Setting::Generations => "--generations",
        Setting::Target => "--target",
        Setting::TargetFeatures => "--target-features",
        Setting::InitialScale => "--initial-scale",
        Setting::Releases => "--releases",
        Setting::StartFrom => "--start-from",
        Setting::Strategy => "--strategy",
        Setting::Prototype => "--prototype",
        Setting::Out => "--out",
        Setting::Resume => "--resume",
        Setting::Size => "--size",
        Setting::Aspect => "--aspect",
        Setting::ArmWidth => "--arm-width",
        Setting::ArealDensity => "--areal-density",
        Setting::BendingStiffness => "--bending-stiffness",
        Setting::Object => "--object",
        Setting::Animation => "--animation",
        Setting::Scale => "--scale",
        Setting::Fps => "--fps",
        Setting::Format => "--format",
        Setting::Up => "--up",
        Setting::Generation => "--generation",
        Setting::Index => "--index",
        Setting::Count => "--count",
        Setting::AllowReferences => "--allow-references",
        Setting::ReferenceJ => "--reference-j",
        Setting::Grid => "--grid",
    }
}
