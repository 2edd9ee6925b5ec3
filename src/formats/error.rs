//! The error of every export, read-back and preview, in a file of its own
//! so that each format's writer and reader can name it without importing the
//! folder module.

use crate::motion::trajectory::TrajectoryError;
use std::path::PathBuf;

/// Why an export, a preview or a read fall could not be made. Every
/// message names the file or directory at fault.
#[derive(Debug, thiserror::Error)]
pub enum ExportError {
    /// Reading or writing a file failed.
    #[error("{path}: {error}")]
    Io {
        /// The file.
        path: PathBuf,
        /// What the system said (in the message, so not also a `source`:
        /// an error chain would print it twice).
        error: std::io::Error,
    },
    /// The input is not what it should be.
    #[error("{path}: {reason}")]
    Input {
        /// The file or directory.
        path: PathBuf,
        /// What is wrong.
        reason: String,
    },
    /// The data cannot be exported (e.g. no frames, a simulation failed).
    #[error("{0}")]
    Data(String),
    /// A CSV record of a fall could not be read ([`crate::formats::fall::read_any_fall`]).
    #[error(transparent)]
    Record(#[from] TrajectoryError),
}

impl ExportError {
    pub(crate) fn io(path: impl Into<PathBuf>, error: std::io::Error) -> ExportError {
        ExportError::Io {
            path: path.into(),
            error,
        }
    }

    pub(crate) fn input(path: impl Into<PathBuf>, reason: impl Into<String>) -> ExportError {
        ExportError::Input {
            path: path.into(),
            reason: reason.into(),
        }
    }
}
