//! `bag2mat BAG [TOPIC] [--topic T]… [--all-imu-topics] [-o OUT] [--format mat|csv|npy]
//! [--time record|header]`: Imu topics of a ROS 1 or ROS 2 bag (or an IMU log) to the N×7
//! `data_imu` matrix kalibr_allan's `bagconvert` writes; `bag2mat info BAG`: what it holds.

use std::process::ExitCode;

use bag2mat::shared::cli;
use bag2mat::{Args, Invocation, run};
use clap::Parser;

const TOOL: &str = "bag2mat";

/// Out of memory is reported as an error, not an abort.
#[global_allocator]
static ALLOC: bag2mat::shared::alloc::ExitOnOom = bag2mat::shared::alloc::ExitOnOom::new(TOOL);

fn main() -> ExitCode {
    bag2mat::shared::alloc::start_threads(TOOL);
    let a = match Args::try_parse() {
        Ok(a) => a,
        Err(e) if !e.use_stderr() => {
            let _ = e.print();
            return ExitCode::SUCCESS;
        }
        Err(e) => return cli::usage(TOOL, &e.render().to_string()),
    };
    match run(a) {
        Ok(Some(text)) => match cli::print(&text) {
            Ok(_) => ExitCode::SUCCESS,
            Err(e) => cli::fail(TOOL, &e),
        },
        Ok(None) => ExitCode::SUCCESS,
        Err(Invocation::Usage(e)) => cli::usage(TOOL, &e),
        Err(Invocation::Failed(e)) => cli::fail(TOOL, &e),
    }
}
