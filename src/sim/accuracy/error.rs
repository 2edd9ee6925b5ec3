//! Why an accuracy computation could not be done: the one error of the
//! sweep, the error estimate and the long comparison.

use crate::physics::integrate::SimError;

/// Why an accuracy computation could not be done.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum AccuracyError {
    /// Bad settings: the field and what is wrong.
    #[error("{0}")]
    Settings(String),
    /// The step or the run's length is refused.
    #[error(transparent)]
    Step(#[from] crate::physics::run::StepError),
    /// The reference run itself failed.
    #[error("the reference run failed: {0}")]
    Reference(SimError),
    /// The run whose error was asked for failed (see [`super::estimate`]).
    #[error("the run failed: {0}")]
    Run(SimError),
}
