//! Helpers every binary of the workspace shares, kept in the I/O crate so that no crate
//! writes them twice: atomic output files, the error/exit convention, progress bars, the embedded plot font and C
//! `printf` number layouts for upstream-compatible text.

pub mod cfmt;
pub mod cli;
pub mod output;
pub mod plot;
pub mod progress;
pub mod staging;
