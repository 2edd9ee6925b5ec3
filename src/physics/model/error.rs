//! The one error of model validation: which item is wrong, and why.

use std::fmt;

/// A reason a model is invalid, naming the offending item.
#[derive(Clone, Debug, PartialEq)]
pub struct ModelError {
    /// The item, as a path a user can find in the file: `particle[3].mass`.
    pub item: String,
    /// What is wrong with it.
    pub reason: String,
}

impl fmt::Display for ModelError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}: {}", self.item, self.reason)
    }
}

impl std::error::Error for ModelError {}
