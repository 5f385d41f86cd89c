//! `allan_imu_utils INPUT [--topic imu] [--name imu] [-o DIR] [--max-time-min 120]
//! [--max-cluster 100] [--launch FILE.launch]`: imu_utils without ROS.

use std::process::ExitCode;

use allan_imu_utils::{Args, Config, TOOL};
use allan_kalibr::{finish_job, parse_args};

/// Out of memory is reported as an error, not an abort.
#[global_allocator]
static ALLOC: bag2mat::shared::alloc::ExitOnOom = bag2mat::shared::alloc::ExitOnOom::new(TOOL);

fn main() -> ExitCode {
    bag2mat::shared::alloc::start_threads(TOOL);
    let config = match parse_args::<Args, Config, _>(TOOL, Config::try_from) {
        Ok(c) => c,
        Err(code) => return code,
    };
    finish_job(TOOL, &config.common, |outputs| {
        allan_imu_utils::sections(&config, outputs)
    })
}
