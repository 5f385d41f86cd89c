//! The command line (what the user typed, [`Args`]) and the resolved settings ([`Config`]):
//! explicit flags, then the `--launch` file's parameters, then upstream-like defaults.

use std::path::PathBuf;

use clap::Parser;

use allan_kalibr::{Common, CommonArgs, Input};

use crate::error::Error;
use crate::launch::{self, LaunchParams, LaunchValue};

/// Default IMU name.
pub const DEFAULT_NAME: &str = "imu";
/// Default `max_time_min` of the shipped launch files.
pub const DEFAULT_MAX_TIME_MIN: u32 = 120;
/// Default `max_cluster` of the shipped launch files.
pub const DEFAULT_MAX_CLUSTER: usize = 100;
/// The tool's name: its default output folder is `<input stem>_allan_imu_utils/`.
pub const TOOL: &str = "allan_imu_utils";

/// imu_utils' Allan variance and noise fit, read straight from a bag — ROS 1, a ROS 2 bag
/// directory, an .mcap or a .db3 (no roscore, no replay) — or an IMU log. Prints upstream's
/// report and writes `<name>_imu_param.yaml` (upstream's file, discrete-time as imu_utils
/// writes it), a continuous-time `<name>_imu_param_continuous.yaml`, the 16
/// `data_<name>_*.txt` curves and plots. Then the IEEE 952 section (unless --compat-only):
/// terms with 95 % intervals, the fitted range and fit quality per axis, recording-length
/// advice, record checks, and its files prefixed `<name>_` — `<name>_kalibr_imu_ieee952.yaml`
/// is the file to give Kalibr. With --curves it works on Allan curves another tool wrote.
#[derive(Debug, Clone, Parser)]
#[command(name = "allan_imu_utils", version, allow_negative_numbers = true)]
pub struct Args {
    /// The flags both analysers share.
    #[command(flatten)]
    pub common: CommonArgs,
    /// The time the Allan variance and the stop rule use: header.stamp (imu_utils) or the
    /// record (receive) time
    #[arg(long, value_enum, default_value_t = bag2mat::TimeColumn::Header)]
    pub time: bag2mat::TimeColumn,
    /// IMU name used in output file names and the yaml [default: imu]
    #[arg(long)]
    pub name: Option<String>,
    /// Stop after this many minutes of header time; the message crossing it is kept [default: 120]
    #[arg(long, value_parser = positive_int::<u32>)]
    pub max_time_min: Option<u32>,
    /// Number of log-spaced cluster sizes requested (at most half the samples) [default: 100]
    #[arg(long, value_parser = positive_int::<usize>)]
    pub max_cluster: Option<usize>,
    /// Take the settings from an imu_utils roslaunch file; explicit flags override it
    #[arg(long, value_name = "FILE.launch")]
    pub launch: Option<PathBuf>,
    /// Do not draw allan_gyr/allan_acc plots
    #[arg(long)]
    pub no_plots: bool,
}

/// What a run uses.
#[derive(Debug, Clone, PartialEq)]
pub struct Config {
    /// What both analysers share: input, topics, time column, output folder, …
    pub common: Common,
    /// IMU name.
    pub name: String,
    /// Stop rule, minutes.
    pub max_time_min: u32,
    /// Cluster count M.
    pub max_cluster: usize,
    /// Draw plots.
    pub plots: bool,
}

impl Config {
    /// Settings for `input` with every other choice at imu_utils' defaults.
    pub fn new(input: Input, out_dir: impl Into<PathBuf>) -> Config {
        let mut common = Common::new(input, out_dir);
        common.time = bag2mat::TimeColumn::Header;
        Config {
            common,
            name: DEFAULT_NAME.into(),
            max_time_min: DEFAULT_MAX_TIME_MIN,
            max_cluster: DEFAULT_MAX_CLUSTER,
            plots: true,
        }
    }
}

/// A positive whole number: "must be positive" for 0 and negatives (clap would otherwise
/// call "-1" an unexpected argument).
fn positive_int<T: std::str::FromStr + TryFrom<u64>>(
    s: &str,
) -> Result<T, bag2mat::shared::cli::UsageError> {
    use bag2mat::shared::cli::UsageError;
    let t = s.trim();
    if t.starts_with('-') || t.parse::<f64>().is_ok_and(|v| v <= 0.0) {
        return Err(UsageError(format!("{s} must be positive")));
    }
    let v: u64 = t
        .parse()
        .map_err(|_| UsageError(format!("'{s}' is not a whole number")))?;
    T::try_from(v).map_err(|_| UsageError(format!("{s} is too large")))
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

impl TryFrom<Args> for Config {
    type Error = Error;

    fn try_from(a: Args) -> Result<Config, Error> {
        // --rate sets the rate of plain CSV curves, or of a text log without a time column:
        // for any other input it would do nothing (imu_utils uses the stamps)
        a.common
            .curve_flags_need_curves(&[])
            .map_err(|e| Error::Config(e.0))?;
        let text_rate = allan_kalibr::rate_for_text(a.common.input.as_deref(), a.common.rate);
        if let (Some(input), Some(rate), None) = (&a.common.input, a.common.rate, text_rate) {
            let kind = bag2mat::input_kind(input)
                .map(|k| k.describe())
                .unwrap_or("input");
            return Err(Error::Config(format!(
                "--rate {rate} does nothing for a {kind} (imu_utils' analysis uses its time stamps): it only applies to a text log without a time column, or with --curves"
            )));
        }
        let lp = a.launch.as_deref().map(launch::read).transpose()?;
        let lp = lp.as_ref();
        let mut common = a.common;
        if common.topics.is_empty()
            && !common.all_imu_topics
            && let Some(t) = from_launch(lp, "imu_topic")?
        {
            common.topics = vec![t];
        }
        let name_given = a.name.is_some();
        let name = match a.name {
            Some(n) => n,
            None => from_launch(lp, "imu_name")?.unwrap_or_else(|| DEFAULT_NAME.into()),
        };
        let launch_dir = match common.out_dir {
            Some(_) => None,
            None => from_launch(lp, "data_save_path")?.map(PathBuf::from),
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
        if common.topics.iter().any(|t| t.trim().is_empty()) {
            return Err(Error::Config("the topic is empty".into()));
        }
        if name.is_empty() || name.contains('/') {
            return Err(Error::Config(format!(
                "the IMU name '{name}' must be non-empty and contain no '/'"
            )));
        }
        // an imu_utils directory may hold several IMUs: --name picks one
        let curves_name = name_given.then(|| name.clone());
        Ok(Config {
            common: common.resolve(TOOL, a.time, curves_name, launch_dir, text_rate),
            name,
            max_time_min,
            max_cluster,
            plots: !a.no_plots,
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
                c.common.topics.preferred.as_deref(),
                c.name.as_str(),
                c.max_time_min,
                c.max_cluster
            ),
            (Some("imu"), "imu", 120, 100)
        );
        assert_eq!(c.common.out_dir, PathBuf::from("x_allan_imu_utils"));
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
        assert_eq!(c.common.topics.topics, vec!["/imu/data".to_string()]);
        assert_eq!(c.common.time, bag2mat::TimeColumn::Header);
        assert_eq!(c.name, "xsens");
        assert_eq!(c.max_time_min, 200);
        assert_eq!(c.max_cluster, 100);
        assert_eq!(c.common.out_dir, PathBuf::from("/tmp/o"));
    }

    #[test]
    fn bad_values() {
        assert!(Config::try_from(args(&["--max-cluster", "1"])).is_err());
        assert!(Config::try_from(args(&["--name", "a/b"])).is_err());
    }
}
