//! Helpers every binary of the workspace shares, kept in the I/O crate so that no crate
//! writes them twice: atomic output files committed all or none, the error/exit convention
//! (out of memory included), progress bars, the embedded plot font and C `printf` number
//! layouts for upstream-compatible text.

pub mod alloc;
pub mod cfmt;
pub mod cli;
mod live;
pub mod note;
pub mod output;
pub mod plot;
pub mod progress;
pub mod staging;
