//! `bag2mat BAG [TOPIC] [--topic T]… [--all-imu-topics] [-o OUT] [--format mat|csv|npy]
//! [--time record|header]`: Imu topics of a ROS 1 or ROS 2 bag to the N×7 `data_imu`
//! matrix kalibr_allan's `bagconvert` writes; `bag2mat info BAG`: what a bag holds.

use std::path::PathBuf;
use std::process::ExitCode;

use bag2mat::convert::{Config, Format, resolve_format, run};
use bag2mat::shared::cli;
use bag2mat::{TimeColumn, TopicSelector};
use clap::{Parser, Subcommand, ValueEnum};

/// Convert sensor_msgs/Imu topics of a bag to a MATLAB .mat (kalibr_allan's bagconvert layout:
/// variable data_imu, N×7, columns t ax ay az wx wy wz, t = record time in seconds).
///
/// Reads ROS 1 bags, ROS 2 bag directories (sqlite3 or MCAP, split, zstd-compressed), bare
/// .mcap and .db3 files, and IMU logs from outside ROS (EuRoC/ASL datasets, CSV/TSV text,
/// PX4 ULog, ArduPilot DataFlash .bin, NumPy .npy), recognised from their content.
/// `bag2mat info BAG` lists what an input holds.
#[derive(Parser, Debug)]
#[command(version, about, args_conflicts_with_subcommands = true)]
struct Args {
    #[command(subcommand)]
    command: Option<Command>,
    /// The input: a ROS 1 bag, a ROS 2 bag directory, an .mcap or a .db3, or an IMU log
    /// (EuRoC/ASL dataset, CSV/TSV text, PX4 .ulg, ArduPilot .bin, NumPy .npy).
    bag: Option<PathBuf>,
    /// The Imu topic (`imu` and `/imu` are tried in that order if the exact name is missing)
    /// [default: the input's only sensor_msgs/Imu topic].
    topic: Option<String>,
    /// Another Imu topic (repeatable); each topic gets its own output folder.
    #[arg(long = "topic", value_name = "TOPIC")]
    topics: Vec<String>,
    /// Every topic that carries sensor_msgs/Imu, each into its own folder.
    #[arg(long)]
    all_imu_topics: bool,
    /// Output file for one topic ("-": standard output); output directory for several
    /// [default: beside the bag, <stem>.<format>, or <topic>/<stem>.<format> per topic].
    #[arg(short, long)]
    output: Option<PathBuf>,
    /// Output format [default: from the output's extension (.mat, .csv, .npy), else mat].
    #[arg(long, value_enum)]
    format: Option<FormatArg>,
    /// The time in column t: the record (receive) time, as bagconvert, or header.stamp.
    #[arg(long, value_enum, default_value_t = TimeColumn::Record)]
    time: TimeColumn,
    /// Only errors and warnings: no progress bar, no log lines.
    #[arg(short, long)]
    quiet: bool,
    /// Text logs without a time column: the sample rate, Hz.
    #[arg(long, value_name = "HZ", value_parser = cli::positive_f64)]
    rate: Option<f64>,
    #[command(flatten)]
    input: bag2mat::formats::InputArgs,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Every topic of a bag (any format) with its type, message count, mean rate, rate
    /// jitter, time span and gaps; the Imu topics are flagged.
    Info {
        /// The input.
        bag: PathBuf,
        /// No progress bar.
        #[arg(short, long)]
        quiet: bool,
        /// Text logs without a time column: the sample rate, Hz.
        #[arg(long, value_name = "HZ", value_parser = cli::positive_f64)]
        rate: Option<f64>,
        #[command(flatten)]
        input: bag2mat::formats::InputArgs,
    },
}

/// Output file formats.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
enum FormatArg {
    /// MATLAB Level-5 .mat with the variable data_imu (what kalibr_allan loads).
    Mat,
    /// Comma-separated text with a header line.
    Csv,
    /// NumPy .npy, float64, shape (N, 7).
    Npy,
}

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
    let result = match a.command {
        Some(Command::Info {
            bag,
            quiet,
            rate,
            input,
        }) => match bag2mat::info::info_with(&bag, quiet, &input.options(rate)) {
            Ok(r) => {
                if let Err(e) = cli::print(&r.text(&bag)) {
                    return cli::fail(TOOL, &e);
                }
                Ok(())
            }
            Err(e) => Err(e),
        },
        None => {
            let Some(bag) = a.bag else {
                return cli::usage(
                    TOOL,
                    "no input given (bag2mat BAG TOPIC, or bag2mat info BAG)",
                );
            };
            let mut topics: Vec<String> = a.topic.into_iter().collect();
            topics.extend(a.topics);
            let given = a.format.map(|f| match f {
                FormatArg::Mat => Format::Mat,
                FormatArg::Csv => Format::Csv,
                FormatArg::Npy => Format::Npy,
            });
            let format = match resolve_format(given, a.output.as_deref()) {
                Ok(f) => f,
                Err(e) => return cli::usage(TOOL, &e),
            };
            let cfg = Config {
                bag,
                topics: TopicSelector {
                    topics,
                    all_imu: a.all_imu_topics,
                    preferred: None,
                },
                output: a.output,
                format,
                time: a.time,
                quiet: a.quiet,
                input: a.input.options(a.rate),
            };
            run(&cfg).map(|_| ())
        }
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => cli::fail(TOOL, &e),
    }
}
