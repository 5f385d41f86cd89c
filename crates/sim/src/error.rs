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

/// The spline's errors keep the kinds `sim` always said them as: a setting out of range is
/// an invalid argument, poses that make no spline a spline error.
impl From<allan_kalibr::spline::SplineError> for SimError {
    fn from(e: allan_kalibr::spline::SplineError) -> Self {
        match e {
            allan_kalibr::spline::SplineError::Invalid(m) => SimError::InvalidArgument(m),
            allan_kalibr::spline::SplineError::Fit(m) => SimError::Spline(m),
        }
    }
}

/// What is wrong inside a `--noise-spec` (or truth) file; [`SimError::Spec`] adds the path.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum SpecError {
    /// The YAML does not deserialise (the parser's message: key, line, column).
    #[error("{0}")]
    Yaml(String),
    /// A truth file (format tag `sim-truth-1`) without its `model:` section.
    #[error("truth file without a model section")]
    TruthWithoutModel,
    /// `warmup:` with neither form complete.
    #[error("warmup needs either amplitude, or temperature_rise_k and bias_per_k (with tau_s)")]
    Warmup,
    /// `filter: {kind: butterworth2}` without its cutoff.
    #[error("filter butterworth2 needs cutoff_hz")]
    CutoffMissing,
    /// A cutoff on a filter kind that has none.
    #[error("filter {0} takes no cutoff_hz")]
    CutoffUnused(String),
    /// An unknown filter kind.
    #[error("unknown filter kind '{0}' (expected none, butterworth2 or average)")]
    FilterKind(String),
    /// A per-axis override is wrong.
    #[error("axis {axis}: {error}")]
    Axis {
        /// `x`, `y` or `z`.
        axis: &'static str,
        /// What is wrong with it.
        error: Box<SpecError>,
    },
}

/// `--seed` is not a whole number from 0 to 2^64 − 1 (clap prints it after the flag).
#[derive(Debug, thiserror::Error)]
#[error("'{0}' is not a seed: a whole number from 0 to {max}", max = u64::MAX)]
pub struct SeedError(pub String);

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
