//! `bag2mat BAG TOPIC [-o OUT] [--format mat|csv|npy]`: a ROS bag's Imu topic to the N×7
//! `data_imu` matrix kalibr_allan's `bagconvert` writes, without ROS or MATLAB.

use std::path::PathBuf;
use std::process::ExitCode;

use bag2mat::convert::{Config, Format, run};
use clap::Parser;

/// Convert a ROS 1 bag's sensor_msgs/Imu topic to a MATLAB .mat (kalibr_allan's bagconvert layout:
/// variable data_imu, N×7, columns t ax ay az wx wy wz, t = bag record time in seconds).
#[derive(Parser, Debug)]
#[command(version, about)]
struct Args {
    /// The bag (format 2.0; chunks none, bz2 or lz4).
    bag: PathBuf,
    /// The Imu topic (`imu` and `/imu` are tried in that order if the exact name is missing).
    topic: String,
    /// Output file [default: beside the bag, <stem>.<format>].
    #[arg(short, long)]
    output: Option<PathBuf>,
    /// Output format.
    #[arg(long, value_enum, default_value_t = Format::Mat)]
    format: Format,
    /// No progress bar and no log lines.
    #[arg(short, long)]
    quiet: bool,
}

fn main() -> ExitCode {
    let a = Args::parse();
    let cfg = Config {
        bag: a.bag,
        topic: a.topic,
        output: a.output,
        format: a.format,
        quiet: a.quiet,
    };
    match run(&cfg) {
        Ok(_) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("bag2mat: error: {e}");
            ExitCode::FAILURE
        }
    }
}
