//! The one error of model validation: which item is wrong, and why.

/// A reason a model is invalid, naming the offending item.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{item}: {reason}")]
pub struct ModelError {
    /// The item, as a path a user can find in the file: `particle[3].mass`.
    pub item: String,
    /// What is wrong with it.
    pub reason: String,
}
