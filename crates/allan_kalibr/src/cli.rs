//! The command line as the user typed it ([`Args`]) and its resolution into a [`Config`].

use clap::Parser;

use crate::front::CommonArgs;
use crate::kalibr::estimator::Estimator;
use crate::run::Config;

/// kalibr_allan's Allan-deviation results (rpng/kalibr_allan 9d38ea9), in seconds, without
/// MATLAB or ROS.
///
/// Reads IMU samples from any input bag2mat reads (ROS 1 and ROS 2 bags, a bagconvert .mat,
/// EuRoC/ASL, CSV/TSV, PX4 ULog, ArduPilot DataFlash, NumPy), computes the non-overlapping
/// Allan deviation on upstream's 2000-point tau grid, fits the -1/2 and +1/2 lines as
/// gen_chart.m does, prints upstream's lines and writes imu.yaml (upstream's file, as
/// kalibr_allan writes it), allan_curves.csv and allan_{accel,gyro}.{png,svg}.
///
/// Then the IEEE 952 section (unless --compat-only): terms with 95 % intervals, the fitted
/// range and fit quality per axis, recording-length advice, record checks, its CSVs and
/// charts, and kalibr_imu_ieee952.yaml — the file to give Kalibr — with the VINS, ORB-SLAM3,
/// OpenVINS and Basalt files. With --curves it analyses Allan curves another tool wrote.
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
}

/// The tool's name: its default output folder is `<input stem>_allan_kalibr/`.
pub const TOOL: &str = "allan_kalibr";

impl TryFrom<Args> for Config {
    type Error = bag2mat::shared::cli::UsageError;

    fn try_from(a: Args) -> Result<Config, Self::Error> {
        a.common.curve_flags_need_curves(&[])?;
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
