//! `allan_kalibr INPUT [--rate HZ] [--topic T] [-o DIR]`: kalibr_allan without MATLAB;
//! `allan_kalibr --curves PATH…` analyses Allan curves another tool wrote;
//! `allan_kalibr check CONFIG…` and `allan_kalibr plan …` (the library's `cli`).

use std::process::ExitCode;

use allan_kalibr::TOOL;

/// Out of memory is reported as an error, not an abort.
#[global_allocator]
static ALLOC: bag2mat::shared::alloc::ExitOnOom = bag2mat::shared::alloc::ExitOnOom::new(TOOL);

fn main() -> ExitCode {
    allan_kalibr::command_main()
}
