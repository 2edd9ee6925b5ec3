//! What can be wrong with a number of the field, and the checks that say so.
//!
//! Every check names the item it looked at, relative to its owner; owners
//! prefix their own name ([`FieldError::within`]), so the caller sees the
//! full path, e.g. `wind[2].bounds.falloff`.

use nalgebra::Vector3;

/// A validation failure: which item of the field is wrong, and why.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{item}: {reason}")]
pub struct FieldError {
    /// Path of the offending item, e.g. `wind[2].core_radius`.
    pub item: String,
    /// What is wrong with it.
    pub reason: String,
}

impl FieldError {
    pub(super) fn new(item: impl Into<String>, reason: impl Into<String>) -> Self {
        Self {
            item: item.into(),
            reason: reason.into(),
        }
    }

    /// Prefixes the item path, so nested checks can name items relative to their parent.
    pub(super) fn within(mut self, parent: &str) -> Self {
        self.item = format!("{parent}.{}", self.item);
        self
    }
}

pub(super) fn finite(x: f64, item: &str) -> Result<(), FieldError> {
    if x.is_finite() {
        Ok(())
    } else {
        Err(FieldError::new(item, format!("must be finite, got {x}")))
    }
}

pub(super) fn positive(x: f64, item: &str) -> Result<(), FieldError> {
    if x.is_finite() && x > 0.0 {
        Ok(())
    } else {
        Err(FieldError::new(
            item,
            format!("must be finite and > 0, got {x}"),
        ))
    }
}

pub(super) fn non_negative(x: f64, item: &str) -> Result<(), FieldError> {
    if x.is_finite() && x >= 0.0 {
        Ok(())
    } else {
        Err(FieldError::new(
            item,
            format!("must be finite and >= 0, got {x}"),
        ))
    }
}

pub(super) fn finite_vector(v: &Vector3<f64>, item: &str) -> Result<(), FieldError> {
    if v.iter().all(|c| c.is_finite()) {
        Ok(())
    } else {
        Err(FieldError::new(
            item,
            format!("must be finite, got [{}, {}, {}]", v.x, v.y, v.z),
        ))
    }
}

pub(super) fn direction(v: &Vector3<f64>, item: &str) -> Result<(), FieldError> {
    finite_vector(v, item)?;
    let n = v.norm();
    // A norm that under- or overflows cannot be normalised reliably.
    if n > 0.0 && n.is_finite() && (v / n).iter().all(|c| c.is_finite()) {
        Ok(())
    } else {
        Err(FieldError::new(
            item,
            "must be a non-zero direction".to_string(),
        ))
    }
}
