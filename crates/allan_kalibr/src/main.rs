//! `allan_kalibr INPUT [--rate HZ] [--topic T] [-o DIR]`: kalibr_allan without MATLAB;
//! `allan_kalibr --curves PATH…` analyses Allan curves another tool wrote.

use std::process::ExitCode;

use allan_kalibr::{Args, Config, TOOL, finish_job, parse_args, sections};

/// Out of memory is reported as an error, not an abort.
#[global_allocator]
static ALLOC: bag2mat::shared::alloc::ExitOnOom = bag2mat::shared::alloc::ExitOnOom::new(TOOL);

fn main() -> ExitCode {
    bag2mat::shared::alloc::start_threads(TOOL);
    let config = match parse_args::<Args, Config, _>(TOOL, Config::try_from) {
        Ok(c) => c,
        Err(code) => return code,
    };
    finish_job(TOOL, &config.common, |outputs| sections(&config, outputs))
}
