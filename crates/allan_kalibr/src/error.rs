//! The error type of the allan_kalibr library; the binary prints it once with anyhow.

use std::path::PathBuf;

/// Everything that can stop a run. No output file is written when any of these occurs.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// A `--skip-start` that leaves too little of the record, or is not a span.
    #[error(transparent)]
    Skip(#[from] bag2mat::SkipError),
    /// The update rate is not a finite positive number of Hz.
    #[error("update rate must be a finite positive number of Hz, got {0}")]
    BadRate(f64),
    /// Fewer than 3 samples: taumax = floor((N-1)/2) < 1, where upstream takes log10(0)
    /// or the log of a negative number and produces garbage or crashes.
    #[error(
        "too few samples for an Allan deviation: {n} (need at least 3, so that taumax = floor((N-1)/2) >= 1)"
    )]
    TooShort {
        /// Number of samples found.
        n: usize,
    },
    /// The timestamps cannot give a rate (no --update-rate and no positive time span).
    #[error("cannot estimate the update rate from the timestamps ({what}); pass --rate HZ")]
    NoRate {
        /// Why.
        what: String,
    },
    /// The input is neither a `.mat` nor a bag bag2mat reads.
    #[error(
        "{path}: unknown input type (expected a .mat file or a bag: {})",
        bag2mat::accepted()
    )]
    UnknownInput {
        /// The file.
        path: PathBuf,
    },
    /// Data contains NaN or infinite samples (upstream would silently produce NaN curves).
    #[error("{what}")]
    BadData {
        /// What is wrong.
        what: String,
    },
    /// Reading the bag or .mat, or writing an output file, failed.
    #[error(transparent)]
    Io(#[from] bag2mat::Error),
    /// `--curves` input that cannot be read.
    #[error(transparent)]
    Curves(#[from] crate::ieee952::curves_in::CurvesError),
    /// The operating-noise analysis cannot run (`--reference`, `--operating`).
    #[error(transparent)]
    Operating(#[from] OperatingError),
}

/// What the analysis cannot do on this record.
#[derive(Debug, thiserror::Error)]
pub enum OperatingError {
    /// The reference cannot be used.
    #[error("reference {}: {what}", .path.display())]
    Reference {
        /// The reference.
        path: PathBuf,
        /// Why.
        what: String,
    },
    /// The static record cannot be used.
    #[error("--static {}: {what}", .path.display())]
    Static {
        /// The static record.
        path: PathBuf,
        /// Why.
        what: String,
    },
    /// The record cannot be analysed.
    #[error("{0}")]
    Record(String),
}
