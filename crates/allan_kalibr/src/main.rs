//! `allan_kalibr INPUT [--rate HZ] [--topic T] [-o DIR]`: kalibr_allan without MATLAB;
//! `allan_kalibr --curves PATH…` analyses Allan curves another tool wrote.

use std::process::ExitCode;

use allan_kalibr::{Args, Config, TOOL};

/// Out of memory is reported as an error, not an abort.
#[global_allocator]
static ALLOC: bag2mat::shared::alloc::ExitOnOom = bag2mat::shared::alloc::ExitOnOom::new(TOOL);

fn main() -> ExitCode {
    allan_kalibr::analyser_main::<Args, Config>(TOOL)
}
