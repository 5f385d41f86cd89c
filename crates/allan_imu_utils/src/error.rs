//! The error type of the allan_imu_utils library; the binary reports it once.

use std::path::PathBuf;

/// Everything that stops an analysis.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// Reading the bag failed (includes "no such topic", whose message lists the bag's topics).
    #[error(transparent)]
    Bag(#[from] bag2mat::Error),
    /// A `--skip-start` that leaves too little of the record, or is not a span.
    #[error(transparent)]
    Skip(#[from] bag2mat::SkipError),
    /// Too few samples for a 5-parameter fit.
    #[error(
        "too few samples on topic '{topic}': {n} messages give {valid} Allan points with data, the 5-term fit needs at least {needed} (record longer)"
    )]
    TooFewSamples {
        /// Topic.
        topic: String,
        /// Samples used.
        n: usize,
        /// Factors with N − 2m > 0.
        valid: usize,
        /// Minimum.
        needed: usize,
    },
    /// A NaN or infinite value in the input.
    #[error(
        "non-finite {what} in message {index} (0-based) of topic '{topic}': the Allan variance would be NaN"
    )]
    NonFinite {
        /// Topic.
        topic: String,
        /// Which field.
        what: String,
        /// Message index.
        index: usize,
    },
    /// The header stamps give no positive, finite mean period.
    #[error(
        "the header stamps of topic '{topic}' do not advance (mean period {period} s over {n} messages): no sample rate"
    )]
    BadStamps {
        /// Topic.
        topic: String,
        /// Mean period found.
        period: f64,
        /// Samples.
        n: usize,
    },
    /// `--curves` input that cannot be read.
    #[error(transparent)]
    Curves(#[from] allan_kalibr::CurvesError),
    /// A roslaunch file could not be used.
    #[error("{path}: {what}")]
    Launch {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        what: LaunchSyntax,
    },
    /// A setting is missing or invalid.
    #[error("{0}")]
    Config(String),
    /// Writing outputs failed.
    // The cause is part of the message, not a `source`: it is printed once.
    #[error("{}: {}", .path.display(), bag2mat::shared::output::describe(.cause))]
    Io {
        /// The path.
        path: PathBuf,
        /// The cause.
        cause: std::io::Error,
    },
}

/// What makes a launch file unreadable as one (said after its path).
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{0}")]
pub struct LaunchSyntax(pub String);
