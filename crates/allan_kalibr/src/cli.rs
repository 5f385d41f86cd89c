//! The command line as the user typed it ([`Cli`]: an analysis, [`Args`], or one of the
//! [`Command`]s `check` and `plan`) and its resolution into what runs ([`Run`]: a [`Config`]
//! for an analysis).

use std::process::ExitCode;

use clap::{Parser, Subcommand};

use crate::front::CommonArgs;
use crate::kalibr::estimator::Estimator;
use crate::run::{Config, TOOL};

/// kalibr_allan's Allan-deviation results (rpng/kalibr_allan 9d38ea9), in seconds, without
/// MATLAB or ROS; `allan_kalibr check` and `allan_kalibr plan` (below).
///
/// Reads IMU samples from a bagconvert .mat or any input bag2mat reads (INPUT lists them),
/// computes the non-overlapping
/// Allan deviation on upstream's 2000-point tau grid, fits the -1/2 and +1/2 lines as
/// gen_chart.m does, prints upstream's lines and writes imu.yaml (upstream's file, as
/// kalibr_allan writes it), allan_curves.csv and allan_{accel,gyro}.{png,svg}.
///
/// Then the IEEE 952 section (unless --compat-only): terms with 95 % intervals, the fitted
/// range and fit quality per axis, recording-length advice, record checks, its CSVs and
/// charts, and kalibr_imu_ieee952.yaml — the file to give Kalibr — with the VINS, ORB-SLAM3,
/// OpenVINS, Basalt, PX4 EKF2, ArduPilot EKF3 and GTSAM files. With --curves it analyses Allan
/// curves another tool wrote.
///
/// `allan_kalibr check CONFIG…` says what each noise value of the config files you have is
/// and what is wrong with it (--against an analysis folder or a log: measured ratios);
/// `allan_kalibr plan --rate HZ …` plans a record from datasheet figures and converts them
/// for every consumer. (An input file named `check` or `plan`: give it as ./check.)
#[derive(Debug, Clone, Parser)]
#[command(
    name = "allan_kalibr",
    version,
    allow_negative_numbers = true,
    args_conflicts_with_subcommands = true,
    subcommand_negates_reqs = true
)]
pub struct Cli {
    /// `check` or `plan`; none: an analysis.
    #[command(subcommand)]
    pub command: Option<Command>,
    /// The analysis' arguments.
    #[command(flatten)]
    pub analyse: Args,
}

/// allan_kalibr's other commands.
#[derive(Debug, Clone, Subcommand, PartialEq)]
pub enum Command {
    /// Say what each IMU noise value of your config files is (Kalibr imu.yaml or imu_chain,
    /// OpenVINS, VINS, ORB-SLAM3, Basalt JSON, PX4 .params, ArduPilot .param, GTSAM,
    /// imu_utils' yaml) and what is wrong with it: one line per key on stdout, exit 0.
    Check(crate::check::CheckArgs),
    /// Plan a static record from an IMU's figures (Kalibr units or datasheet units): the
    /// record for +-25 % / +-10 % on each term, whether B can be resolved, an honest bound
    /// on K where the datasheet has none, and every consumer's parameters (-o DIR: files).
    Plan(crate::plan::PlanArgs),
}

/// What a command line runs.
#[derive(Debug, Clone)]
pub enum Run {
    /// An analysis.
    Analyse(Box<Config>),
    /// `check`.
    Check(crate::check::CheckArgs),
    /// `plan`.
    Plan(crate::plan::PlanArgs),
}

impl TryFrom<Cli> for Run {
    type Error = bag2mat::shared::cli::UsageError;

    fn try_from(c: Cli) -> Result<Run, Self::Error> {
        Ok(match c.command {
            Some(Command::Check(a)) => Run::Check(a),
            Some(Command::Plan(a)) => Run::Plan(a),
            None => Run::Analyse(Box::new(Config::try_from(c.analyse)?)),
        })
    }
}

/// allan_kalibr's `main`: the command line parsed, then the analysis, `check` or `plan`.
pub fn command_main() -> ExitCode {
    match crate::front::command_line::<Cli, Run>(TOOL) {
        Ok(Run::Analyse(config)) => crate::front::run_job(TOOL, config.as_ref()),
        Ok(Run::Check(a)) => crate::check::main(&a),
        Ok(Run::Plan(a)) => crate::plan::main(&a),
        Err(code) => code,
    }
}

/// The analysis' arguments (`allan_kalibr INPUT …`).
#[derive(Debug, Clone, Parser, PartialEq)]
#[command(name = "allan_kalibr", version, allow_negative_numbers = true)]
pub struct Args {
    /// The flags both analysers share.
    #[command(flatten)]
    pub common: CommonArgs,
    /// The time column the rate is estimated from: record (receive) time, as bagconvert
    /// writes it, or header.stamp.
    #[arg(long, value_enum, default_value_t = bag2mat::TimeColumn::Record)]
    pub time: bag2mat::TimeColumn,
    /// Chart title prefix (upstream's titlestr) [default: the input's file stem].
    #[arg(
        long,
        value_name = "TEXT",
        default_value = "",
        hide_default_value = true
    )]
    pub title: String,
    /// Replay upstream's running-mean recursion: curves bit-identical to kalibr_allan (slower).
    #[arg(long)]
    pub bit_exact: bool,
    /// The operating-noise analysis: the noise the estimator will see in a moving record.
    #[command(flatten)]
    pub operating: crate::operating::OperatingArgs,
}

impl TryFrom<Args> for Config {
    type Error = bag2mat::shared::cli::UsageError;

    fn try_from(a: Args) -> Result<Config, Self::Error> {
        a.common.curve_flags_need_curves(&[])?;
        let operating = a.operating.resolve()?;
        if operating.is_some() && a.common.input.is_none() {
            return Err(bag2mat::shared::cli::UsageError(
                "--reference and --operating analyse samples, not --curves".into(),
            ));
        }
        if operating.is_some() && (a.bit_exact || a.common.compat_only) {
            return Err(bag2mat::shared::cli::UsageError(
                "--bit-exact and --compat-only are for the static Allan analysis, not --reference or --operating".into(),
            ));
        }
        // a text log without a time column is sampled at --rate
        let text_rate = crate::front::rate_for_text(a.common.input.as_deref(), a.common.rate);
        Ok(Config {
            common: a.common.resolve(TOOL, a.time, None, None, text_rate),
            title: a.title,
            estimator: if a.bit_exact {
                Estimator::BitExact
            } else {
                Estimator::PrefixSum
            },
            operating,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::PathBuf;

    fn parse(v: &[&str]) -> Config {
        Args::try_parse_from(std::iter::once("allan_kalibr").chain(v.iter().copied()))
            .unwrap()
            .try_into()
            .unwrap()
    }

    #[test]
    fn defaults() {
        let c = parse(&["data/x.bag"]);
        assert_eq!(c.common.out_dir, PathBuf::from("data/x_allan_kalibr"));
        assert_eq!(c.common.topics, crate::front::default_topics());
        assert_eq!(c.common.time, bag2mat::TimeColumn::Record);
        assert_eq!(c.common.rate, None);
        assert_eq!(c.estimator, Estimator::PrefixSum);
        assert_eq!(
            parse(&["x.mat"]).common.out_dir,
            PathBuf::from("x_allan_kalibr")
        );
    }

    #[test]
    fn flags() {
        let c = parse(&[
            "x.bag",
            "--topic",
            "/imu0",
            "--update-rate",
            "200",
            "--bit-exact",
            "-o",
            "out",
            "--title",
            "ADIS",
        ]);
        assert_eq!(c.common.topics.topics, vec!["/imu0".to_string()]);
        assert_eq!(c.common.rate, Some(200.0));
        assert_eq!(c.estimator, Estimator::BitExact);
        assert_eq!(c.common.out_dir, PathBuf::from("out"));
        assert_eq!(c.title, "ADIS");
    }
}
