//! The library's error type.

use std::path::PathBuf;

/// Everything `sim` can fail with; the binary reports it once and exits non-zero.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum SimError {
    /// A value given on the command line is out of range or inconsistent.
    #[error("invalid argument: {0}")]
    InvalidArgument(String),
    /// An input text file could not be parsed.
    #[error("{path}: line {line}: {msg}")]
    Parse {
        /// The file.
        path: PathBuf,
        /// 1-based line number.
        line: usize,
        /// What is wrong.
        msg: String,
    },
    /// Reading or writing a file failed.
    // The cause is part of the message, not a `source`: it is printed once.
    #[error("{}: {}", .path.display(), bag2mat::shared::output::describe(.cause))]
    Io {
        /// The file.
        path: PathBuf,
        /// The cause.
        cause: std::io::Error,
    },
    /// The spline cannot be built from the given poses.
    #[error("spline: {0}")]
    Spline(String),
    /// Drawing a plot failed.
    #[error("plot {path}: {msg}")]
    Plot {
        /// The output file.
        path: PathBuf,
        /// The backend's message.
        msg: String,
    },
    /// A tool output read by `sim compare` is missing or malformed.
    #[error("comparison input: {0}")]
    Input(String),
    /// A `--noise-spec` file is malformed.
    #[error("noise spec {path}: {msg}")]
    Spec {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        msg: String,
    },
    /// Writing the bag failed (bag2mat's error).
    #[error(transparent)]
    Bag(#[from] bag2mat::Error),
}

/// Shorthand.
pub type Result<T> = std::result::Result<T, SimError>;

impl SimError {
    /// An I/O error with its path.
    pub(crate) fn io(path: impl Into<PathBuf>, cause: std::io::Error) -> Self {
        SimError::Io {
            path: path.into(),
            cause,
        }
    }
}
