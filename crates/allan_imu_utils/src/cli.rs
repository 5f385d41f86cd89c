//! The command line (what the user typed, [`Args`]) and the resolved settings ([`Config`]):
//! explicit flags, then the `--launch` file's parameters, then upstream-like defaults.

use std::path::PathBuf;

use clap::Parser;

use crate::error::Error;
use crate::launch::{self, LaunchParams, LaunchValue};

/// Default topic, name, limit and cluster count (imu_utils' shipped launch files).
pub const DEFAULT_TOPIC: &str = "imu";
/// Default IMU name.
pub const DEFAULT_NAME: &str = "imu";
/// Default `max_time_min` of the shipped launch files.
pub const DEFAULT_MAX_TIME_MIN: u32 = 120;
/// Default `max_cluster` of the shipped launch files.
pub const DEFAULT_MAX_CLUSTER: usize = 100;

/// imu_utils' Allan variance and noise fit, read straight from a bag — ROS 1, a ROS 2 bag
/// directory, an .mcap or a .db3 (no roscore, no replay). Prints upstream's report and writes
/// `<name>_imu_param.yaml`, a continuous-time `<name>_imu_param_continuous.yaml`, the 16
/// `data_<name>_*.txt` curves and plots. Then the IEEE 952 section (unless --compat-only):
/// terms with 95 % intervals, the fitted range and fit quality per axis, recording-length
/// advice, warm-up and gap checks, and its files prefixed `<name>_`. With --curves it works on
/// Allan curves another tool wrote.
#[derive(Debug, Clone, Parser)]
#[command(name = "allan_imu_utils", version, allow_negative_numbers = true)]
pub struct Args {
    /// The bag: ROS 1 (uncompressed, bz2 or lz4 chunks), a ROS 2 bag directory, .mcap or .db3;
    /// or an IMU log (EuRoC/ASL dataset, CSV/TSV text, PX4 .ulg, ArduPilot .bin, NumPy .npy).
    #[arg(required_unless_present = "curves")]
    pub bag: Option<PathBuf>,
    /// Analyse existing Allan curves instead of a bag: an imu_utils data directory (then
    /// imu_utils' own fit is re-run and its yaml files written), allan_variance_ros'
    /// allan_variance.csv, an allan_curves.csv, an ieee952_curves.csv, or a plain CSV
    /// `tau,x,y,z` (one sensor; give --units). A plain CSV per sensor may be given twice.
    #[arg(long, value_name = "PATH", conflicts_with = "bag")]
    pub curves: Vec<PathBuf>,
    /// Unit of each plain CSV of --curves, in order: rad/s, deg/s, deg/h, imu_utils, m/s^2,
    /// g, mg (the values are Allan deviations).
    #[arg(long, value_name = "UNIT")]
    pub units: Vec<String>,
    /// Length of the record behind --curves, in seconds (for the confidence intervals).
    #[arg(long, value_name = "SECONDS", conflicts_with = "samples", value_parser = bag2mat::shared::cli::positive_f64)]
    pub duration: Option<f64>,
    /// Number of samples behind --curves (for the confidence intervals).
    #[arg(long, value_name = "N")]
    pub samples: Option<u64>,
    /// IMU rate of plain --curves CSVs whose τ do not start at one sample, or of a text log
    /// without a time column, Hz.
    #[arg(long, value_name = "HZ")]
    pub rate: Option<f64>,
    /// Drop the first SECONDS of header time (a warm-up) before the stop rule and analysis.
    #[arg(long, value_name = "SECONDS", value_parser = bag2mat::shared::cli::positive_f64)]
    pub skip_start: Option<f64>,
    /// Drop the samples the record check finds to be spikes (a sample far off its
    /// neighbours, reported with its time) before the analysis.
    #[arg(long)]
    pub drop_outliers: bool,
    /// sensor_msgs/Imu topic (`imu` and `/imu` are the same); repeatable, each topic then
    /// gets its own folder under the output directory [default: imu]
    #[arg(long = "topic", value_name = "TOPIC")]
    pub topics: Vec<String>,
    /// Every topic of the bag that carries sensor_msgs/Imu, each into its own folder
    #[arg(long)]
    pub all_imu_topics: bool,
    /// The time the Allan variance and the stop rule use: header.stamp (imu_utils) or the
    /// record (receive) time
    #[arg(long, value_enum, default_value_t = TimeArg::Header)]
    pub time: TimeArg,
    /// IMU name used in output file names and the yaml [default: imu]
    #[arg(long)]
    pub name: Option<String>,
    /// Output directory (created if missing) [default: .]
    #[arg(long)]
    pub data_save_path: Option<PathBuf>,
    /// Stop after this many minutes of header time; the message crossing it is kept [default: 120]
    #[arg(long, value_parser = positive_int::<u32>)]
    pub max_time_min: Option<u32>,
    /// Number of log-spaced cluster sizes requested (at most half the samples) [default: 100]
    #[arg(long, value_parser = positive_int::<usize>)]
    pub max_cluster: Option<usize>,
    /// Take the settings from an imu_utils roslaunch file; explicit flags override it
    #[arg(long, value_name = "FILE.launch")]
    pub launch: Option<PathBuf>,
    /// Only errors and warnings on stderr: no progress bar (the report still goes to stdout)
    #[arg(long, short)]
    pub quiet: bool,
    /// Do not draw allan_gyr/allan_acc plots
    #[arg(long)]
    pub no_plots: bool,
    /// Print the time of each phase on stderr (for benchmarks)
    #[arg(long)]
    pub timings: bool,
    /// Only what imu_utils produces: skip the IEEE 952 section and its files
    #[arg(long)]
    pub compat_only: bool,
    #[command(flatten)]
    pub input_args: bag2mat::formats::InputArgs,
}

/// The time column.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum TimeArg {
    /// header.stamp: what imu_utils' node reads.
    Header,
    /// Record (receive) time.
    Record,
}

/// `--curves`: the inputs and what the user said about them.
#[derive(Debug, Clone, PartialEq)]
pub struct CurvesInput {
    /// A directory or files.
    pub paths: Vec<PathBuf>,
    /// Record length, sample count, rate, units, name.
    pub options: allan_kalibr::ieee952::curves_in::Options,
}

/// What a run uses.
#[derive(Debug, Clone, PartialEq)]
pub struct Config {
    /// Input bag (empty with --curves).
    pub bag: PathBuf,
    /// Curves to analyse instead of a bag.
    pub curves: Option<CurvesInput>,
    /// Seconds dropped at the start.
    pub skip_start: Option<f64>,
    /// Drop the spikes the record check finds.
    pub drop_outliers: bool,
    /// Topics (one unless several were asked for).
    pub topics: Vec<String>,
    /// Also every other Imu topic of the bag.
    pub all_imu: bool,
    /// The time column.
    pub time: bag2mat::TimeColumn,
    /// IMU name.
    pub name: String,
    /// Output directory.
    pub out_dir: PathBuf,
    /// Stop rule, minutes.
    pub max_time_min: u32,
    /// Cluster count M.
    pub max_cluster: usize,
    /// No progress bar.
    pub quiet: bool,
    /// Draw plots.
    pub plots: bool,
    /// Report phase times.
    pub timings: bool,
    /// Also run the IEEE 952 analysis (allan_kalibr::ieee952) beside the compat outputs.
    pub ieee952: bool,
    /// What the user said about a log whose content does not say it all (a text log's
    /// columns and units).
    pub input_options: bag2mat::formats::InputOptions,
}

/// A positive whole number: "must be positive" for 0 and negatives (clap would otherwise
/// call "-1" an unexpected argument).
fn positive_int<T: std::str::FromStr + TryFrom<u64>>(s: &str) -> Result<T, String> {
    let t = s.trim();
    if t.starts_with('-') || t.parse::<f64>().is_ok_and(|v| v <= 0.0) {
        return Err(format!("{s} must be positive"));
    }
    let v: u64 = t
        .parse()
        .map_err(|_| format!("'{s}' is not a whole number"))?;
    T::try_from(v).map_err(|_| format!("{s} is too large"))
}

fn from_launch(lp: Option<&LaunchParams>, param: &str) -> Result<Option<String>, Error> {
    match lp.and_then(|l| l.get(param)) {
        None => Ok(None),
        Some(LaunchValue::Value(v)) => Ok(Some(v.clone())),
        Some(LaunchValue::Unresolved(v)) => Err(Error::Config(format!(
            "launch parameter {param} = \"{v}\" needs ROS to resolve the $(…) substitution; give {} instead",
            launch::flag_for(param)
        ))),
    }
}

fn parse_launch_int<T: std::str::FromStr>(
    v: Option<String>,
    param: &str,
) -> Result<Option<T>, Error> {
    v.map(|s| {
        s.parse::<T>().map_err(|_| {
            Error::Config(format!(
                "launch parameter {param} = \"{s}\" is not a non-negative integer"
            ))
        })
    })
    .transpose()
}

impl Args {
    /// [`allan_kalibr::cli::curve_flags_need_curves`], --rate included (it only sets the
    /// rate of plain CSV curves here).
    pub fn curve_flags_need_curves(&self) -> Result<(), String> {
        allan_kalibr::cli::curve_flags_need_curves(
            &self.curves,
            &self.units,
            self.duration,
            self.samples,
            &[("--rate", self.rate.is_some())],
        )
    }
}

impl TryFrom<Args> for Config {
    type Error = Error;

    fn try_from(a: Args) -> Result<Config, Error> {
        a.curve_flags_need_curves().map_err(Error::Config)?;
        let lp = a.launch.as_deref().map(launch::read).transpose()?;
        let lp = lp.as_ref();
        let topics = if !a.topics.is_empty() {
            a.topics
        } else if a.all_imu_topics {
            Vec::new()
        } else {
            vec![from_launch(lp, "imu_topic")?.unwrap_or_else(|| DEFAULT_TOPIC.into())]
        };
        let name_given = a.name.is_some();
        let name = match a.name {
            Some(n) => n,
            None => from_launch(lp, "imu_name")?.unwrap_or_else(|| DEFAULT_NAME.into()),
        };
        let out_dir = match a.data_save_path {
            Some(p) => p,
            None => from_launch(lp, "data_save_path")?
                .map(PathBuf::from)
                .unwrap_or_else(|| PathBuf::from(".")),
        };
        let max_time_min = match a.max_time_min {
            Some(v) => v,
            None => parse_launch_int(from_launch(lp, "max_time_min")?, "max_time_min")?
                .unwrap_or(DEFAULT_MAX_TIME_MIN),
        };
        let max_cluster = match a.max_cluster {
            Some(v) => v,
            None => parse_launch_int(from_launch(lp, "max_cluster")?, "max_cluster")?
                .unwrap_or(DEFAULT_MAX_CLUSTER),
        };
        if max_cluster < 2 {
            return Err(Error::Config(format!(
                "max_cluster must be at least 2 (got {max_cluster})"
            )));
        }
        if topics.iter().any(|t| t.trim().is_empty()) {
            return Err(Error::Config("the topic is empty".into()));
        }
        if name.is_empty() || name.contains('/') {
            return Err(Error::Config(format!(
                "the IMU name '{name}' must be non-empty and contain no '/'"
            )));
        }
        let curves = (!a.curves.is_empty()).then(|| CurvesInput {
            paths: a.curves.clone(),
            options: allan_kalibr::ieee952::curves_in::Options {
                duration: a.duration,
                samples: a.samples,
                rate: a.rate,
                units: a.units.clone(),
                // an imu_utils directory may hold several IMUs: --name picks one
                name: name_given.then(|| name.clone()),
            },
        });
        Ok(Config {
            bag: a.bag.unwrap_or_default(),
            curves,
            skip_start: a.skip_start,
            drop_outliers: a.drop_outliers,
            topics,
            all_imu: a.all_imu_topics,
            time: match a.time {
                TimeArg::Header => bag2mat::TimeColumn::Header,
                TimeArg::Record => bag2mat::TimeColumn::Record,
            },
            name,
            out_dir,
            max_time_min,
            max_cluster,
            quiet: a.quiet,
            plots: !a.no_plots,
            timings: a.timings,
            ieee952: !a.compat_only,
            // a text log without a time column is sampled at --rate
            input_options: a
                .input_args
                .options(if a.curves.is_empty() { a.rate } else { None }),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn args(extra: &[&str]) -> Args {
        let mut v = vec!["allan_imu_utils", "x.bag"];
        v.extend_from_slice(extra);
        Args::parse_from(v)
    }

    #[test]
    fn defaults() {
        let c = Config::try_from(args(&[])).unwrap();
        assert_eq!(
            (
                c.topics[0].as_str(),
                c.name.as_str(),
                c.max_time_min,
                c.max_cluster
            ),
            ("imu", "imu", 120, 100)
        );
        assert_eq!(c.out_dir, PathBuf::from("."));
    }

    #[test]
    fn launch_file_then_flags_override() {
        let dir = tempfile::tempdir().unwrap();
        let f = dir.path().join("a.launch");
        std::fs::write(
            &f,
            r#"<launch><node pkg="imu_utils" type="imu_an" name="imu_an">
            <param name="imu_topic" type="string" value="/imu/data"/>
            <param name="imu_name" type="string" value="xsens"/>
            <param name="data_save_path" type="string" value="$(find imu_utils)/data/"/>
            <param name="max_time_min" type="int" value="200"/>
            <param name="max_cluster" type="int" value="50"/></node></launch>"#,
        )
        .unwrap();
        let fs = f.to_str().unwrap();
        let e = Config::try_from(args(&["--launch", fs]))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("--data-save-path") && e.contains("$(find imu_utils)"),
            "{e}"
        );
        let c = Config::try_from(args(&[
            "--launch",
            fs,
            "--data-save-path",
            "/tmp/o",
            "--max-cluster",
            "100",
        ]))
        .unwrap();
        assert_eq!(c.topics, vec!["/imu/data".to_string()]);
        assert_eq!(c.time, bag2mat::TimeColumn::Header);
        assert_eq!(c.name, "xsens");
        assert_eq!(c.max_time_min, 200);
        assert_eq!(c.max_cluster, 100);
        assert_eq!(c.out_dir, PathBuf::from("/tmp/o"));
    }

    #[test]
    fn bad_values() {
        assert!(Config::try_from(args(&["--max-cluster", "1"])).is_err());
        assert!(Config::try_from(args(&["--name", "a/b"])).is_err());
    }
}
