//! `allan_kalibr INPUT [--rate HZ] [--topic T] [-o DIR]`: kalibr_allan without MATLAB;
//! `allan_kalibr --curves PATH…` analyses Allan curves another tool wrote.

use std::process::ExitCode;

use allan_kalibr::cli::{Args, TOOL};
use allan_kalibr::{Config, front};

/// Out of memory is reported as an error, not an abort.
#[global_allocator]
static ALLOC: bag2mat::shared::alloc::ExitOnOom = bag2mat::shared::alloc::ExitOnOom::new(TOOL);

fn main() -> ExitCode {
    bag2mat::shared::alloc::start_threads(TOOL);
    let config = match front::parse::<Args, Config>(TOOL, Config::try_from) {
        Ok(c) => c,
        Err(code) => return code,
    };
    front::finish(TOOL, &config.common, |outputs| {
        allan_kalibr::run::sections(&config, outputs)
    })
}
