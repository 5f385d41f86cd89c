//! `sim` binary: parse the command line, run the library, report errors once.

use clap::Parser;
use sim::Cli;
use std::process::ExitCode;

const TOOL: &str = "sim";

/// Out of memory is reported as an error, not an abort.
#[global_allocator]
static ALLOC: bag2mat::shared::alloc::ExitOnOom = bag2mat::shared::alloc::ExitOnOom::new(TOOL);

fn main() -> ExitCode {
    bag2mat::shared::alloc::start_threads(TOOL);
    let cli = match Cli::try_parse() {
        Ok(c) => c,
        // No subcommand: say so in one line (clap's message would be the whole description).
        Err(e) if e.kind() == clap::error::ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand => {
            return bag2mat::shared::cli::usage(
                TOOL,
                "a command is required: bag, traj, integrate, spline, compare or sensors (`sim --help` says what each does)\n\nUsage: sim <COMMAND>",
            );
        }
        Err(e) if !e.use_stderr() => {
            let _ = e.print();
            return ExitCode::SUCCESS;
        }
        Err(e) => return bag2mat::shared::cli::usage(TOOL, &e.render().to_string()),
    };
    match sim::run(cli) {
        Ok(code) => code,
        // What the user typed cannot be run: a usage error (exit 2).
        Err(e)
            if matches!(
                e.downcast_ref::<sim::SimError>(),
                Some(sim::SimError::InvalidArgument(_))
            ) =>
        {
            bag2mat::shared::cli::usage(TOOL, &format!("{e:#}"))
        }
        Err(e) => bag2mat::shared::cli::fail(TOOL, &format!("{e:#}")),
    }
}
