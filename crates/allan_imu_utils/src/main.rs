//! `allan_imu_utils INPUT [--topic imu] [--name imu] [-o DIR] [--max-time-min 120]
//! [--max-cluster 100] [--launch FILE.launch]`: imu_utils without ROS.

use std::process::ExitCode;

use allan_imu_utils::{Args, Config, TOOL};

/// Out of memory is reported as an error, not an abort.
#[global_allocator]
static ALLOC: bag2mat::shared::alloc::ExitOnOom = bag2mat::shared::alloc::ExitOnOom::new(TOOL);

fn main() -> ExitCode {
    allan_kalibr::analyser_main::<Args, Config>(TOOL)
}
