//! Command-line arguments (what the user typed, clap derive) and their resolution into the
//! library's configurations (`TryFrom`), kept out of `main.rs` so they can be unit-tested.
//! The shared noise flags are in `noise_args`, the real-sensor model flags of `sim bag` in
//! `model_args` (built on them); both are re-exported here, the one path to them.

// The argument docs are clap's help texts, which write units as `[Hz]`, `[s]` and defaults
// as `<stem>`: rustdoc would read those as links and HTML tags, and escaping them would
// show the escapes in `--help`.
#![allow(rustdoc::broken_intra_doc_links)]

use crate::bag_sim::{BagConfig, now_ns, parse_start_time};
use crate::error::{Result, SimError};
use crate::grid::Grid;
use crate::integrate::{InitState, IntegrateConfig, IntegrateInput, Method};
use crate::motion::{Mode, Motion};
use crate::noise::Preset;
use crate::spline::Fit;
use crate::spline_sim::{PoseSource, SplineConfig};
use crate::traj::TrajConfig;
use bag2mat::Compression;
use clap::{Args, Parser, Subcommand, ValueEnum};
use std::path::PathBuf;

mod model_args;
mod noise_args;

pub use model_args::{ModelArgs, SPEC_EXAMPLE, SensorArg, SensorsArgs};
pub use noise_args::{NoiseArgs, PresetArg};

/// IMU data simulator (after HeYijia/vio_data_simulation) and Spline-Fusion IMU synthesis.
#[derive(Debug, Parser)]
#[command(name = "sim", version, about)]
pub struct Cli {
    /// What to do.
    #[command(subcommand)]
    pub command: Command,
}

/// Subcommands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Write a simulated IMU bag (default: vio_data_simulation ros_version's 4 h static bag).
    Bag(Box<BagArgs>),
    /// Write the upstream text files of the 20 s ellipse trajectory.
    Traj(TrajArgs),
    /// Integrate IMU samples (Euler vs midpoint) and report the errors.
    Integrate(IntegrateArgs),
    /// Fit a cubic B-spline to poses and emit IMU data from its derivatives.
    Spline(SplineArgs),
    /// Tabulate the analysers' figures (written by scripts/compare.sh) against the truth.
    Compare(CompareArgs),
    /// List the sensor profiles of `sim bag --sensor` with their figures and sources.
    Sensors(SensorsArgs),
}

/// `sim compare` arguments.
#[derive(Debug, Args)]
pub struct CompareArgs {
    /// Folder with `<preset>/imu_utils/<preset>_imu_param.yaml`, `<preset>/kalibr/imu.yaml`
    /// and `<preset>/kalibr/ieee952_terms.csv`.
    #[arg(long)]
    pub root: PathBuf,
    /// Presets to compare, comma-separated.
    #[arg(long, value_delimiter = ',', default_values = ["low", "medium", "high"])]
    pub presets: Vec<PresetArg>,
    /// Sample rate of the simulated bags [Hz].
    #[arg(long, default_value_t = 200.0)]
    pub rate: f64,
    /// Duration of the simulated bags [s].
    #[arg(long, default_value_t = 14400.0)]
    pub duration: f64,
    /// Write the Markdown tables here as well [default: ROOT/compare.md].
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// Fail (exit 1) when a figure is outside the tolerances stated for this data length.
    #[arg(long)]
    pub check: bool,
}

impl TryFrom<CompareArgs> for crate::compare::CompareConfig {
    type Error = SimError;
    fn try_from(a: CompareArgs) -> Result<Self> {
        if !(a.rate > 0.0 && a.duration > 0.0) {
            return Err(SimError::InvalidArgument(
                "--rate and --duration must be positive".into(),
            ));
        }
        let presets = a
            .presets
            .iter()
            .map(|p| match p {
                PresetArg::Low => Ok(Preset::Low),
                PresetArg::Medium => Ok(Preset::Medium),
                PresetArg::High => Ok(Preset::High),
                PresetArg::Master => Err(SimError::InvalidArgument(
                    "compare takes low, medium or high".into(),
                )),
            })
            .collect::<Result<Vec<_>>>()?;
        let output = a.output.unwrap_or_else(|| a.root.join("compare.md"));
        Ok(crate::compare::CompareConfig {
            root: a.root,
            presets,
            rate: a.rate,
            duration: a.duration,
            output,
            check: a.check,
        })
    }
}

/// Motion models.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum MotionArg {
    /// Level IMU at rest (ros_version).
    Static,
    /// The 20 s ellipse (master), repeated.
    Ellipse,
}

/// Bag chunk compression.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum CompressionArg {
    /// Uncompressed (upstream default).
    None,
    /// bzip2.
    Bz2,
    /// LZ4 frames.
    Lz4,
    /// zstd (MCAP chunks only).
    Zstd,
}

impl From<CompressionArg> for Compression {
    fn from(c: CompressionArg) -> Self {
        match c {
            CompressionArg::None | CompressionArg::Zstd => Compression::None,
            CompressionArg::Bz2 => Compression::Bz2,
            CompressionArg::Lz4 => Compression::Lz4,
        }
    }
}

/// `sim bag --format`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum BagFormatArg {
    /// ROS 1 bag (format 2.0), as upstream.
    Ros1,
    /// ROS 2 bag directory with an MCAP file (Imu as CDR).
    Mcap,
    /// ROS 2 bag directory with a sqlite3 .db3 file (Imu as CDR).
    Sqlite3,
}

/// The container and compression of `sim bag`, checked together.
fn bag_format(f: BagFormatArg, c: CompressionArg) -> Result<crate::bag_sim::BagFormat> {
    use crate::bag_sim::BagFormat;
    use bag2mat::ChunkCompression;
    Ok(match (f, c) {
        (BagFormatArg::Ros1, CompressionArg::Zstd) => {
            return Err(SimError::InvalidArgument(
                "--compression zstd is for --format mcap (ROS 1 bags take none, bz2 or lz4)".into(),
            ));
        }
        (BagFormatArg::Ros1, _) => BagFormat::Ros1,
        (BagFormatArg::Mcap, CompressionArg::None) => BagFormat::Mcap(ChunkCompression::None),
        (BagFormatArg::Mcap, CompressionArg::Zstd) => BagFormat::Mcap(ChunkCompression::Zstd),
        (BagFormatArg::Mcap, CompressionArg::Lz4) => BagFormat::Mcap(ChunkCompression::Lz4),
        (BagFormatArg::Sqlite3, CompressionArg::None) => BagFormat::Sqlite3,
        (f, c) => {
            return Err(SimError::InvalidArgument(format!(
                "--compression {c:?} does not apply to --format {f:?} (mcap: none, zstd, lz4; sqlite3: none)"
            )));
        }
    })
}

/// Time grids.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum GridArg {
    /// Upstream master's float-accumulated times (4001 samples, t₄₀₀₀ = 19.99965).
    Upstream,
    /// t = i/rate, end point included.
    Exact,
}

impl From<GridArg> for Grid {
    fn from(g: GridArg) -> Self {
        match g {
            GridArg::Upstream => Grid::AccumulatedF32,
            GridArg::Exact => Grid::Exact,
        }
    }
}

/// `sim bag`.
#[derive(Debug, Clone, Args)]
pub struct BagArgs {
    /// Output bag (a directory for ROS 2 formats) [default: imu.bag, or imu for ROS 2].
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// Container: ROS 1 bag, or a ROS 2 bag directory holding an MCAP or sqlite3 file.
    #[arg(long, value_enum, default_value_t = BagFormatArg::Ros1)]
    pub format: BagFormatArg,
    #[command(flatten)]
    #[allow(missing_docs)]
    pub noise: NoiseArgs,
    /// Sample rate [Hz].
    #[arg(allow_negative_numbers = true, long, default_value_t = 200.0)]
    pub rate: f64,
    /// Duration [s]; samples at t = 0, 1/rate, … while t < duration, accumulated in double as
    /// upstream (14400 s at 200 Hz → 2 880 001 messages).
    #[arg(allow_negative_numbers = true, long, default_value_t = 14400.0)]
    pub duration: f64,
    /// Time of the first message [UNIX seconds, decimal]; default now.
    #[arg(allow_negative_numbers = true, long, value_name = "UNIX_SECONDS")]
    pub start_time: Option<String>,
    /// Topic name.
    #[arg(long, default_value = "imu")]
    pub topic: String,
    /// header.frame_id.
    #[arg(long, default_value = "base_link")]
    pub frame_id: String,
    /// Motion model. A moving IMU's motion goes through the sensor's low-pass filter and
    /// decimation like its noise (a profile or spec with a filter delays and attenuates it).
    #[arg(long, value_enum, default_value_t = MotionArg::Static)]
    pub motion: MotionArg,
    /// Chunk compression (ROS 1: none, bz2, lz4; MCAP: none, zstd, lz4).
    #[arg(long, value_enum, default_value_t = CompressionArg::None)]
    pub compression: CompressionArg,
    /// No progress bar and no parameter report (errors are still printed)
    #[arg(short, long)]
    pub quiet: bool,
    #[command(flatten)]
    #[allow(missing_docs)]
    pub model: ModelArgs,
}

impl TryFrom<BagArgs> for BagConfig {
    type Error = SimError;
    fn try_from(a: BagArgs) -> Result<Self> {
        let start_ns = match &a.start_time {
            Some(s) => parse_start_time(s)?,
            None => now_ns(),
        };
        crate::bag_sim::validate_rate(a.rate)?;
        let format = bag_format(a.format, a.compression)?;
        let out = a.output.unwrap_or_else(|| {
            PathBuf::from(if format == crate::bag_sim::BagFormat::Ros1 {
                "imu.bag"
            } else {
                "imu"
            })
        });
        let cfg = BagConfig {
            out,
            model: a.model.resolve(&a.noise, a.rate)?,
            rate: a.rate,
            duration: a.duration,
            seed: a.noise.seed,
            start_ns,
            topic: a.topic,
            frame_id: a.frame_id,
            motion: match a.motion {
                MotionArg::Static => Motion::Static,
                MotionArg::Ellipse => Motion::Ellipse,
            },
            compression: if format == crate::bag_sim::BagFormat::Ros1 {
                a.compression.into()
            } else {
                Compression::None
            },
            format,
            quiet: a.quiet,
        };
        crate::bag_sim::validate(&cfg)?;
        Ok(cfg)
    }
}

/// `sim traj`.
#[derive(Debug, Clone, Args)]
pub struct TrajArgs {
    /// Output directory.
    #[arg(short, long, default_value = ".")]
    pub output: PathBuf,
    /// Duration [s].
    #[arg(allow_negative_numbers = true, long, default_value_t = 20.0)]
    pub duration: f64,
    /// IMU rate [Hz].
    #[arg(allow_negative_numbers = true, long, default_value_t = 200.0)]
    pub rate: f64,
    /// Camera rate [Hz].
    #[arg(allow_negative_numbers = true, long, default_value_t = 30.0)]
    pub cam_rate: f64,
    /// Time grid.
    #[arg(long, value_enum, default_value_t = GridArg::Upstream)]
    pub grid: GridArg,
    /// Upstream's float model constants on the upstream grid: the clean outputs then match
    /// vio_data_simulation master digit for digit.
    #[arg(long, conflicts_with = "grid")]
    pub compat: bool,
    #[command(flatten)]
    #[allow(missing_docs)]
    pub noise: NoiseArgs,
}

fn positive(name: &str, v: f64) -> Result<f64> {
    if v.is_finite() && v > 0.0 {
        Ok(v)
    } else {
        Err(SimError::InvalidArgument(format!(
            "{name} must be a positive number, got {v}"
        )))
    }
}

impl TryFrom<TrajArgs> for TrajConfig {
    type Error = SimError;
    fn try_from(a: TrajArgs) -> Result<Self> {
        Ok(TrajConfig {
            out_dir: a.output,
            duration: positive("--duration", a.duration)?,
            rate: positive("--rate", a.rate)?,
            cam_rate: positive("--cam-rate", a.cam_rate)?,
            noise: a.noise.resolve(PresetArg::Master)?,
            seed: a.noise.seed,
            grid: if a.compat {
                Grid::AccumulatedF32
            } else {
                a.grid.into()
            },
            mode: if a.compat {
                Mode::CompatF32
            } else {
                Mode::Double
            },
        })
    }
}

/// Integration methods to run.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum MethodArg {
    /// Upstream Euler.
    Euler,
    /// Midpoint.
    Midpoint,
    /// Both.
    Both,
}

/// Initial-state source.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum InitArg {
    /// The analytic ellipse model at the first timestamp (as upstream).
    Model,
    /// The first row's pose, velocity from the first three positions.
    File,
}

/// `sim integrate`.
#[derive(Debug, Clone, Args)]
pub struct IntegrateArgs {
    /// Integration scheme.
    #[arg(long, value_enum, default_value_t = MethodArg::Both)]
    pub method: MethodArg,
    /// 14-column IMU pose file (imu_pose.txt); default: simulate the model in memory.
    #[arg(long, value_name = "FILE")]
    pub input: Option<PathBuf>,
    /// Noisy file; default: imu_pose_noise.txt next to --input, if present.
    #[arg(long, value_name = "FILE")]
    pub noisy: Option<PathBuf>,
    /// Output directory (imu_int_pose*.txt, integrate_*.png/svg).
    #[arg(short, long, default_value = ".")]
    pub output: PathBuf,
    /// Initial state.
    #[arg(long, value_enum, default_value_t = InitArg::Model)]
    pub init: InitArg,
    /// Sample rate [Hz] (the integration step is 1/rate, as upstream's imu_timestep).
    #[arg(allow_negative_numbers = true, long, default_value_t = 200.0)]
    pub rate: f64,
    /// Duration [s] when simulating in memory.
    #[arg(allow_negative_numbers = true, long, default_value_t = 20.0)]
    pub duration: f64,
    /// Time grid when simulating in memory.
    #[arg(long, value_enum, default_value_t = GridArg::Upstream)]
    pub grid: GridArg,
    /// Upstream's float model constants on the upstream grid: the clean outputs then match
    /// vio_data_simulation master digit for digit.
    #[arg(long, conflicts_with = "grid")]
    pub compat: bool,
    /// Skip the plots.
    #[arg(long)]
    pub no_plot: bool,
    #[command(flatten)]
    #[allow(missing_docs)]
    pub noise: NoiseArgs,
}

impl TryFrom<IntegrateArgs> for IntegrateConfig {
    type Error = SimError;
    fn try_from(a: IntegrateArgs) -> Result<Self> {
        let rate = positive("--rate", a.rate)?;
        let mode = if a.compat {
            Mode::CompatF32
        } else {
            Mode::Double
        };
        let input = match a.input {
            Some(clean) => {
                let noisy = a.noisy.or_else(|| {
                    let n = clean.with_file_name("imu_pose_noise.txt");
                    (n.exists() && n != clean).then_some(n)
                });
                IntegrateInput::Files { clean, noisy }
            }
            None => {
                if a.noisy.is_some() {
                    return Err(SimError::InvalidArgument("--noisy needs --input".into()));
                }
                IntegrateInput::Model {
                    grid: if a.compat {
                        Grid::AccumulatedF32
                    } else {
                        a.grid.into()
                    },
                    mode,
                    duration: positive("--duration", a.duration)?,
                    rate,
                    noise: a.noise.resolve(PresetArg::Master)?,
                    seed: a.noise.seed,
                }
            }
        };
        Ok(IntegrateConfig {
            input,
            methods: match a.method {
                MethodArg::Euler => vec![Method::Euler],
                MethodArg::Midpoint => vec![Method::Midpoint],
                MethodArg::Both => vec![Method::Euler, Method::Midpoint],
            },
            mode,
            init: match a.init {
                InitArg::Model => InitState::Model,
                InitArg::File => InitState::File,
            },
            dt: 1.0 / rate,
            out_dir: a.output,
            plots: !a.no_plot,
        })
    }
}

/// Spline fit kinds.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum FitArg {
    /// The spline passes through the poses.
    Interp,
    /// Poses are the control points (smoothing).
    Approx,
}

/// `sim spline`.
#[derive(Debug, Clone, Args)]
pub struct SplineArgs {
    /// TUM pose file `t tx ty tz qx qy qz qw`.
    #[arg(long, value_name = "POSES.tum", required_unless_present_any = ["from_model", "self_check"], conflicts_with = "from_model")]
    pub poses: Option<PathBuf>,
    /// Use the analytic ellipse model's poses (at --pose-rate over --duration) as input.
    #[arg(long)]
    pub from_model: bool,
    /// Only run the self-check (model poses → spline → IMU vs analytic IMU) and exit non-zero
    /// if it fails.
    #[arg(long)]
    pub self_check: bool,
    /// Pose rate for --from-model / --self-check [Hz].
    #[arg(allow_negative_numbers = true, long, default_value_t = 200.0)]
    pub pose_rate: f64,
    /// Duration for --from-model [s].
    #[arg(allow_negative_numbers = true, long, default_value_t = 20.0)]
    pub duration: f64,
    /// Knot spacing [s]; default the median pose spacing.
    #[arg(allow_negative_numbers = true, long, value_name = "S")]
    pub knot_dt: Option<f64>,
    /// Fit kind.
    #[arg(long, value_enum, default_value_t = FitArg::Interp)]
    pub fit: FitArg,
    /// IMU rate [Hz].
    #[arg(allow_negative_numbers = true, long, default_value_t = 200.0)]
    pub rate: f64,
    /// Write the noisy file and bag without noise.
    #[arg(long)]
    pub no_noise: bool,
    #[command(flatten)]
    #[allow(missing_docs)]
    pub noise: NoiseArgs,
    /// Output directory, or a path ending in .bag (text files then go beside it).
    #[arg(short, long, default_value = ".")]
    pub output: PathBuf,
    /// First emitted time [s, same clock as the poses]; default the spline start.
    #[arg(allow_negative_numbers = true, long, value_name = "S")]
    pub t_start: Option<String>,
    /// Last emitted time [s]; default the spline end.
    #[arg(allow_negative_numbers = true, long, value_name = "S")]
    pub t_end: Option<String>,
    /// Bag time of the first sample [UNIX seconds]; default the pose times if absolute, else now.
    #[arg(allow_negative_numbers = true, long, value_name = "UNIX_SECONDS")]
    pub start_time: Option<String>,
    /// Bag topic.
    #[arg(long, default_value = "imu")]
    pub topic: String,
    /// Bag header.frame_id.
    #[arg(long, default_value = "base_link")]
    pub frame_id: String,
    /// Bag chunk compression.
    #[arg(long, value_enum, default_value_t = CompressionArg::None)]
    pub compression: CompressionArg,
    /// Gravity magnitude [m/s²], world z up: a level IMU at rest reads +g on z.
    #[arg(long, allow_negative_numbers = true, default_value_t = crate::spline::GRAVITY)]
    pub gravity: f64,
    /// No progress bar.
    #[arg(short, long)]
    pub quiet: bool,
}

fn time_arg(name: &str, s: &Option<String>) -> Result<Option<i64>> {
    s.as_ref()
        .map(|s| {
            crate::textio::parse_time_ns(s).ok_or_else(|| {
                SimError::InvalidArgument(format!("{name} {s:?} is not a number of seconds"))
            })
        })
        .transpose()
}

impl TryFrom<SplineArgs> for SplineConfig {
    type Error = SimError;
    fn try_from(a: SplineArgs) -> Result<Self> {
        let source = match (a.poses, a.from_model) {
            (Some(p), false) => PoseSource::Tum(p),
            (None, true) => PoseSource::Model {
                duration: positive("--duration", a.duration)?,
                rate: positive("--pose-rate", a.pose_rate)?,
            },
            _ => {
                return Err(SimError::InvalidArgument(
                    "give exactly one of --poses FILE and --from-model".into(),
                ));
            }
        };
        let knot_dt_ns = match a.knot_dt {
            Some(k) => Some((positive("--knot-dt", k)? * 1e9).round() as i64),
            None => None,
        };
        Ok(SplineConfig {
            source,
            knot_dt_ns,
            fit: match a.fit {
                FitArg::Interp => Fit::Interp,
                FitArg::Approx => Fit::Approx,
            },
            rate: positive("--rate", a.rate)?,
            noise: if a.no_noise {
                None
            } else {
                Some(a.noise.resolve(PresetArg::Master)?)
            },
            seed: a.noise.seed,
            out: a.output,
            topic: a.topic,
            frame_id: a.frame_id,
            start_ns: a.start_time.as_deref().map(parse_start_time).transpose()?,
            compression: a.compression.into(),
            t_start_ns: time_arg("--t-start", &a.t_start)?,
            t_end_ns: time_arg("--t-end", &a.t_end)?,
            gravity: a.gravity,
            quiet: a.quiet,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(args: &[&str]) -> std::result::Result<Cli, clap::Error> {
        Cli::try_parse_from(std::iter::once("sim").chain(args.iter().copied()))
    }

    #[test]
    fn quirk_03_topic_imu_without_slash_and_seed_defaults() {
        let Command::Bag(a) = parse(&["bag", "--start-time", "1700000000"])
            .unwrap()
            .command
        else {
            panic!("not bag")
        };
        let c = BagConfig::try_from(*a).unwrap();
        assert_eq!(
            (c.rate, c.duration, c.topic.as_str(), c.frame_id.as_str()),
            (200.0, 14400.0, "imu", "base_link")
        );
        assert_eq!(c.model.legacy(200.0), Some(Preset::Medium.params()));
        assert_eq!(c.motion, Motion::Static);
        assert_eq!(c.compression, Compression::None);
        assert_eq!(c.start_ns, 1_700_000_000_000_000_000);
        assert_eq!(c.out, PathBuf::from("imu.bag"));
    }

    #[test]
    fn explicit_flags_override_the_preset() {
        let Command::Bag(a) = parse(&["bag", "--preset", "high", "--acc-noise", "0.5"])
            .unwrap()
            .command
        else {
            panic!()
        };
        let c = BagConfig::try_from(*a).unwrap();
        let n = c.model.legacy(200.0).unwrap();
        assert_eq!(n.acc_noise, 0.5);
        assert_eq!(n.gyro_noise, 0.03);
    }

    #[test]
    fn bad_values_are_rejected() {
        for args in [
            &["bag", "--rate", "0"][..],
            &["bag", "--duration", "-1"],
            &["bag", "--gyro-noise", "-0.1"],
            &["bag", "--start-time", "yesterday"],
            &["bag", "--topic", ""],
        ] {
            let Command::Bag(a) = parse(args).unwrap().command else {
                panic!()
            };
            assert!(
                BagConfig::try_from(*a).is_err(),
                "{args:?} should be rejected"
            );
        }
        assert!(parse(&["bag", "--compression", "zip"]).is_err());
        assert!(parse(&["bag", "--motion", "circle"]).is_err());
        assert!(
            parse(&["spline"]).is_err(),
            "spline needs --poses or --from-model"
        );
    }

    #[test]
    fn spline_sources() {
        let Command::Spline(a) = parse(&["spline", "--from-model", "--knot-dt", "0.01"])
            .unwrap()
            .command
        else {
            panic!()
        };
        let c = SplineConfig::try_from(a).unwrap();
        assert!(matches!(c.source, PoseSource::Model { .. }));
        assert_eq!(c.knot_dt_ns, Some(10_000_000));
        assert!(parse(&["spline", "--from-model", "--poses", "x.tum"]).is_err());
    }
}
