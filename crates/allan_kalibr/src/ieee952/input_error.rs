//! Errors of the IEEE 952 analysis (bad input only; the numerics never panic).

/// Why a series cannot be analysed.
#[derive(Debug, thiserror::Error, PartialEq)]
#[non_exhaustive]
pub enum Ieee952Error {
    /// The sample period is not a positive finite number of seconds.
    #[error("sample period must be a positive finite number of seconds, got {0}")]
    BadSamplePeriod(f64),
    /// A sample is NaN or infinite.
    #[error("sample {index} is not finite ({value})")]
    NonFinite {
        /// Index of the first bad sample.
        index: usize,
        /// Its value.
        value: f64,
    },
    /// Too few samples for even one grid point.
    #[error("{n} samples are too few for an Allan variance curve (need at least {min})")]
    TooShort {
        /// Samples given.
        n: usize,
        /// Samples needed.
        min: usize,
    },
    /// A confidence level outside (0, 1).
    #[error("confidence level must be in (0, 1), got {0}")]
    BadConfidence(f64),
}
