//! The `bag2mat` command line (what the user typed, clap derive) and the run it asks for:
//! a conversion ([`crate::convert`]) or `bag2mat info` ([`crate::info`]).

// The argument docs are clap's help texts, which write units as `[Hz]`, `[s]` and defaults
// as `<stem>`: rustdoc would read those as links and HTML tags, and escaping them would
// show the escapes in `--help`.
#![allow(rustdoc::invalid_html_tags)]

use std::path::PathBuf;

use clap::{Parser, Subcommand, ValueEnum};

use crate::convert::{Config, Format, resolve_format};
use crate::shared::cli;
use crate::{TimeColumn, TopicSelector};

/// Convert sensor_msgs/Imu topics of a bag to a MATLAB .mat (kalibr_allan's bagconvert layout:
/// variable data_imu, N×7, columns t ax ay az wx wy wz, t = record time in seconds).
///
/// Reads ROS bags and IMU logs from outside ROS, recognised from their content (BAG lists
/// them). `bag2mat info BAG` lists what an input holds.
#[derive(Parser, Debug)]
#[command(name = "bag2mat", version, args_conflicts_with_subcommands = true)]
pub struct Args {
    #[allow(missing_docs)] // a subcommand's help is its own
    #[command(subcommand)]
    pub command: Option<Command>,
    /// The input (its help lists every kind read: [`crate::input_help`]).
    #[arg(help = crate::input_help(&[]))]
    pub bag: Option<PathBuf>,
    /// The Imu topic (`imu` and `/imu` are tried in that order if the exact name is missing)
    /// [default: the input's only sensor_msgs/Imu topic].
    pub topic: Option<String>,
    /// Another Imu topic (repeatable); each topic gets its own output folder.
    #[arg(long = "topic", value_name = "TOPIC")]
    pub topics: Vec<String>,
    /// Every topic that carries sensor_msgs/Imu, each into its own folder.
    #[arg(long)]
    pub all_imu_topics: bool,
    /// Output file for one topic ("-": standard output); output directory for several
    /// [default: beside the bag, <stem>.<format>, or <topic>/<stem>.<format> per topic].
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// Output format [default: from the output's extension (.mat, .csv, .npy), else mat].
    #[arg(long, value_enum)]
    pub format: Option<FormatArg>,
    /// The time in column t: the record (receive) time, as bagconvert, or header.stamp.
    #[arg(long, value_enum, default_value_t = TimeColumn::Record)]
    pub time: TimeColumn,
    /// Only errors and warnings: no progress bar, no log lines.
    #[arg(short, long)]
    pub quiet: bool,
    /// Text logs without a time column: the sample rate, Hz.
    #[arg(long, value_name = "HZ", value_parser = cli::positive_f64)]
    pub rate: Option<f64>,
    #[allow(missing_docs)] // the flattened flags carry their own help
    #[command(flatten)]
    pub input: crate::formats::InputArgs,
}

/// `bag2mat info`.
#[derive(Subcommand, Debug)]
pub enum Command {
    /// Every topic of a bag (any format) with its type, message count, mean rate, rate
    /// jitter, time span and gaps; the Imu topics are flagged.
    Info {
        /// The input (its help lists every kind read: [`crate::input_help`]).
        #[arg(help = crate::input_help(&[]))]
        bag: PathBuf,
        /// No progress bar.
        #[arg(short, long)]
        quiet: bool,
        /// Text logs without a time column: the sample rate, Hz.
        #[arg(long, value_name = "HZ", value_parser = cli::positive_f64)]
        rate: Option<f64>,
        #[allow(missing_docs)] // the flattened flags carry their own help
        #[command(flatten)]
        input: crate::formats::InputArgs,
    },
}

/// Output file formats.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum FormatArg {
    /// MATLAB Level-5 .mat with the variable data_imu (what kalibr_allan loads).
    Mat,
    /// Comma-separated text with a header line.
    Csv,
    /// NumPy .npy, float64, shape (N, 7).
    Npy,
}

/// What the command line asked for, done: `Ok(Some(text))` is `bag2mat info`'s report for
/// stdout; a conversion says what it wrote itself. A command line that cannot be run is
/// [`Invocation::Usage`].
pub fn run(a: Args) -> Result<Option<String>, Invocation> {
    match a.command {
        Some(Command::Info {
            bag,
            quiet,
            rate,
            input,
        }) => crate::info::info_with(&bag, quiet, &input.options(rate))
            .map(|r| Some(r.text(&bag)))
            .map_err(Invocation::Failed),
        None => {
            let Some(bag) = a.bag else {
                return Err(Invocation::Usage(
                    "no input given (bag2mat BAG TOPIC, or bag2mat info BAG)".into(),
                ));
            };
            let mut topics: Vec<String> = a.topic.into_iter().collect();
            topics.extend(a.topics);
            let given = a.format.map(|f| match f {
                FormatArg::Mat => Format::Mat,
                FormatArg::Csv => Format::Csv,
                FormatArg::Npy => Format::Npy,
            });
            let format =
                resolve_format(given, a.output.as_deref()).map_err(|e| Invocation::Usage(e.0))?;
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
            crate::convert::run(&cfg, crate::shared::output::Outputs::staged())
                .map(|_| None)
                .map_err(Invocation::Failed)
        }
    }
}

/// Why [`run`] did not run.
#[derive(Debug)]
pub enum Invocation {
    /// The command line cannot be run (exit 2).
    Usage(String),
    /// The run failed (exit 1).
    Failed(crate::Error),
}
