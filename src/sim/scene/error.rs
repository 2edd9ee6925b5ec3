//! A scene file's errors: [`SceneError`] names the file, the line and the
//! field, and the checks of the compiler's numbers and names raise it with
//! the line found from the field's path.

use crate::util::bad_input::BadInput;
use std::collections::HashMap;
use std::path::Path;

/// A scene file that could not be read, parsed or compiled: the file, the
/// line, the field and the reason, as every input's error
/// ([`BadInput`]).
pub type SceneError = BadInput;

/// Where errors are reported.
pub(super) struct Ctx<'a> {
    pub(super) text: &'a str,
    pub(super) file: &'a str,
    pub(super) base: &'a Path,
    /// The law every leaf falls under, over its file's (`scene --law`).
    pub(super) law: Option<crate::leaf::AeroLawName>,
}

impl Ctx<'_> {
    /// A leaf under the scene's `--law`, if one is given.
    pub(super) fn under_law(&self, spec: crate::leaf::LeafSpec) -> crate::leaf::LeafSpec {
        match self.law {
            Some(law) => spec.under_law(law),
            None => spec,
        }
    }

    pub(super) fn err(&self, field: impl Into<String>, message: impl Into<String>) -> SceneError {
        BadInput::in_toml(self.file, self.text, field, message)
    }

    pub(super) fn finite(&self, field: &str, v: f64) -> Result<(), SceneError> {
        if v.is_finite() {
            Ok(())
        } else {
            Err(self.err(field, format!("must be a finite number, got {v}")))
        }
    }

    pub(super) fn positive(&self, field: &str, v: f64) -> Result<(), SceneError> {
        if v.is_finite() && v > 0.0 {
            Ok(())
        } else {
            Err(self.err(field, format!("must be a finite number > 0, got {v}")))
        }
    }

    pub(super) fn non_negative(&self, field: &str, v: f64) -> Result<(), SceneError> {
        if v.is_finite() && v >= 0.0 {
            Ok(())
        } else {
            Err(self.err(field, format!("must be a finite number ≥ 0, got {v}")))
        }
    }

    pub(super) fn vector(&self, field: &str, v: &[f64]) -> Result<(), SceneError> {
        match v.iter().find(|c| !c.is_finite()) {
            Some(c) => Err(self.err(field, format!("must be finite, got {c}"))),
            None => Ok(()),
        }
    }
}

pub(super) fn check_name(
    ctx: &Ctx<'_>,
    field: &str,
    name: &str,
    seen: &mut HashMap<String, String>,
) -> Result<(), SceneError> {
    if name.is_empty() || name.contains(['/', '\\', ':']) || name.starts_with('.') {
        return Err(ctx.err(
            field,
            format!("'{name}' is not a usable name (empty, or contains '/', '\\\\', ':' or starts with '.')"),
        ));
    }
    if let Some(other) = seen.insert(name.to_string(), field.to_string()) {
        return Err(ctx.err(field, format!("name '{name}' is already used by {other}")));
    }
    Ok(())
}
