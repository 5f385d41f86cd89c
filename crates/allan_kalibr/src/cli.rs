//! The command line as the user typed it ([`Args`]) and its resolution into a [`Config`].

use std::path::PathBuf;

use clap::Parser;

use crate::estimator::Estimator;
use crate::run::Config;

/// kalibr_allan's Allan-deviation results (rpng/kalibr_allan 9d38ea9), in seconds.
///
/// Reads IMU samples from a ROS 1 bag or a bagconvert .mat (variable data_imu), computes the
/// non-overlapping Allan deviation on upstream's 2000-point tau grid, fits the -1/2 and +1/2
/// lines as gen_chart.m does, prints upstream's lines and writes imu.yaml,
/// allan_curves.csv, allan_accel.{png,svg} and allan_gyro.{png,svg}.
///
/// Then the IEEE 952 section (unless --compat-only): terms with 95 % intervals, the fitted
/// range and fit quality per axis, recording-length advice, warm-up and gap checks,
/// ieee952_terms.csv, ieee952_curves.csv, ieee952_psd.csv, ieee952_allan.{png,svg},
/// ieee952_psd.{png,svg} and Kalibr/VINS/ORB-SLAM3/OpenVINS/Basalt files. With --curves it analyses Allan curves another tool wrote instead of samples.
#[derive(Debug, Clone, Parser, PartialEq)]
#[command(name = "allan_kalibr", version, allow_negative_numbers = true)]
pub struct Args {
    /// Input: a bag, a .mat holding data_imu (N x 7: t ax ay az wx wy wz), or an IMU log
    /// (EuRoC/ASL dataset, CSV/TSV text, PX4 .ulg, ArduPilot .bin, NumPy .npy).
    #[arg(required_unless_present = "curves")]
    pub input: Option<PathBuf>,
    /// Analyse existing Allan curves instead (IEEE 952 section only): an imu_utils data
    /// directory, allan_variance_ros' allan_variance.csv, an allan_curves.csv, an
    /// ieee952_curves.csv, or a plain CSV `tau,x,y,z` (one sensor; give --units). A plain CSV
    /// per sensor may be given twice.
    #[arg(long, value_name = "PATH", conflicts_with = "input")]
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
    /// Drop the first SECONDS of the record (a warm-up) before any analysis.
    #[arg(long, value_name = "SECONDS", value_parser = bag2mat::shared::cli::positive_f64)]
    pub skip_start: Option<f64>,
    /// Drop the samples the record check finds to be spikes (a sample far off its
    /// neighbours, reported with its time) before any analysis.
    #[arg(long)]
    pub drop_outliers: bool,
    /// IMU topic in the bag (ignored for .mat except as rostopic in imu.yaml); repeatable,
    /// each topic then gets its own folder under the output directory [default: imu].
    #[arg(long = "topic", value_name = "TOPIC")]
    pub topics: Vec<String>,
    /// Every topic of the bag that carries sensor_msgs/Imu, each into its own folder.
    #[arg(long)]
    pub all_imu_topics: bool,
    /// The time column the rate is estimated from: record (receive) time, as bagconvert
    /// writes it, or header.stamp.
    #[arg(long, value_enum, default_value_t = TimeArg::Record)]
    pub time: TimeArg,
    /// IMU rate in Hz (drives the tau grid, as upstream's update_rate). Default: estimated
    /// from the timestamps. With --curves (also as --rate): the rate of a plain CSV whose τ
    /// do not start at one sample.
    #[arg(long, value_name = "HZ", visible_alias = "rate", value_parser = rate_hz)]
    pub update_rate: Option<f64>,
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
    /// Only what kalibr_allan produces: skip the IEEE 952 section and its files
    /// (ieee952_terms.csv, ieee952_curves.csv, kalibr/vins/orbslam3 *_ieee952.yaml).
    #[arg(long)]
    pub compat_only: bool,
    /// Output directory (default: the input's directory).
    #[arg(short = 'o', long, value_name = "OUTDIR")]
    pub outdir: Option<PathBuf>,
    /// Only errors and warnings on stderr: no progress bars, no "wrote" lines (the results
    /// still go to stdout).
    #[arg(short, long)]
    pub quiet: bool,
    /// Print the wall time of each phase (load, allan+fit, outputs) on stderr.
    #[arg(long)]
    pub timings: bool,
    #[command(flatten)]
    pub input_args: bag2mat::formats::InputArgs,
}

/// The slowest update rate accepted, Hz: below it a τ grid of seconds-to-hours is meaningless
/// and the printed numbers run to hundreds of digits.
pub const MIN_RATE_HZ: f64 = 1e-3;
/// The fastest update rate accepted, Hz (IMUs sample at 1 Hz to a few tens of kHz).
pub const MAX_RATE_HZ: f64 = 1e7;

/// `--update-rate`: a positive number of Hz within [`MIN_RATE_HZ`, `MAX_RATE_HZ`].
fn rate_hz(s: &str) -> Result<f64, String> {
    let v = bag2mat::shared::cli::positive_f64(s)?;
    if !(MIN_RATE_HZ..=MAX_RATE_HZ).contains(&v) {
        return Err(format!(
            "{s} Hz is outside {MIN_RATE_HZ} .. {MAX_RATE_HZ:e} Hz"
        ));
    }
    Ok(v)
}

/// The time column.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum TimeArg {
    /// Record (receive) time: bagconvert's rule.
    Record,
    /// header.stamp.
    Header,
}

/// --units, --duration, --samples (and `more`) describe Allan curves: without --curves
/// they would be ignored in silence. Both analysers check their flags with this.
pub fn curve_flags_need_curves(
    curves: &[PathBuf],
    units: &[String],
    duration: Option<f64>,
    samples: Option<u64>,
    more: &[(&str, bool)],
) -> Result<(), String> {
    let mut flags = vec![
        ("--units", !units.is_empty()),
        ("--duration", duration.is_some()),
        ("--samples", samples.is_some()),
    ];
    flags.extend_from_slice(more);
    bag2mat::shared::cli::only_with("--curves", !curves.is_empty(), &flags)
}

impl Args {
    /// [`curve_flags_need_curves`] for these arguments.
    pub fn curve_flags_need_curves(&self) -> Result<(), String> {
        curve_flags_need_curves(&self.curves, &self.units, self.duration, self.samples, &[])
    }
}

impl From<Args> for Config {
    fn from(a: Args) -> Config {
        let input = a
            .input
            .clone()
            .or_else(|| a.curves.first().cloned())
            .unwrap_or_default();
        // a curves directory holds its own outputs; a file's directory otherwise
        let outdir = a.outdir.unwrap_or_else(|| {
            if input.is_dir() {
                return input.clone();
            }
            match input.parent() {
                Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
                _ => PathBuf::from("."),
            }
        });
        let curves = (!a.curves.is_empty()).then(|| crate::run::CurvesInput {
            paths: a.curves.clone(),
            options: crate::ieee952::curves_in::Options {
                duration: a.duration,
                samples: a.samples,
                rate: a.update_rate,
                units: a.units.clone(),
                name: None,
            },
        });
        Config {
            skip_start: a.skip_start,
            drop_outliers: a.drop_outliers,
            curves,
            input,
            topics: bag2mat::TopicSelector {
                topics: if a.topics.is_empty() && !a.all_imu_topics {
                    vec!["imu".to_string()]
                } else {
                    a.topics
                },
                all_imu: a.all_imu_topics,
            },
            time: match a.time {
                TimeArg::Record => bag2mat::TimeColumn::Record,
                TimeArg::Header => bag2mat::TimeColumn::Header,
            },
            update_rate: a.update_rate,
            title: a.title,
            estimator: if a.bit_exact {
                Estimator::BitExact
            } else {
                Estimator::PrefixSum
            },
            outdir,
            quiet: a.quiet,
            ieee952: !a.compat_only,
            timings: a.timings,
            // a text log without a time column is sampled at --update-rate
            input_options: a.input_args.options(a.update_rate),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(v: &[&str]) -> Config {
        Args::try_parse_from(std::iter::once("allan_kalibr").chain(v.iter().copied()))
            .unwrap()
            .into()
    }

    #[test]
    fn defaults() {
        let c = parse(&["data/x.bag"]);
        assert_eq!(c.outdir, PathBuf::from("data"));
        assert_eq!(c.topics.topics, vec!["imu".to_string()]);
        assert_eq!(c.time, bag2mat::TimeColumn::Record);
        assert_eq!(c.update_rate, None);
        assert_eq!(c.estimator, Estimator::PrefixSum);
        assert_eq!(parse(&["x.mat"]).outdir, PathBuf::from("."));
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
        assert_eq!(c.topics.topics, vec!["/imu0".to_string()]);
        assert_eq!(c.update_rate, Some(200.0));
        assert_eq!(c.estimator, Estimator::BitExact);
        assert_eq!(c.outdir, PathBuf::from("out"));
        assert_eq!(c.title, "ADIS");
    }
}
