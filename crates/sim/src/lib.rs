//! `sim`: an IMU data simulator after HeYijia/vio_data_simulation
//! (`docs/upstream/vio_data_simulation.md`), plus Spline-Fusion IMU synthesis from poses.
//!
//! * `noise`: continuous ↔ discrete noise parameters (THE place for these conversions in
//!   the workspace), the seeded `addIMUnoise` generator, and the real-sensor model (every
//!   IEEE 952 term, the DLPF chain, profiles, spec files) with its exact truth curves.
//! * `motion`: the analytic models (static level IMU, 20 s ellipse);
//!   `sensor_chain`: a moving IMU's motion through the sensor's low-pass and decimation.
//! * `grid`: upstream's accumulated time grids.
//! * `bag_sim`: `sim bag` — the `ros_version` static (or ellipse) IMU bag via bag2mat.
//! * `traj`: `sim traj` — the `master` text files (IMU poses, camera poses, landmarks,
//!   observations).
//! * `integrate`: `sim integrate` — upstream Euler vs midpoint dead reckoning, error table,
//!   plots.
//! * `compare`: `sim compare` — the tools' figures against the simulated truth.
//! * `spline`: uniform cumulative cubic B-spline on ℝ³ × SO(3) and its IMU;
//!   `spline_sim`: the `sim spline` command around it.
//!
//! Units: s, m, rad; gravity g_w = (0, 0, −9.81) (ENU, z up), so a level IMU at rest reads
//! acc = (0, 0, +9.81).
//!
//! # Quirks reproduced on purpose
//! * `quirk_01_ros_version_double_accumulation_counts_2880001` (`grid::Grid::AccumulatedF64`):
//!   `for (double t = 0; t < 14400; t += 1.0/200)` gives 2 880 001 samples (docs/upstream/vio_data_simulation.md §4).
//! * `quirk_02_master_float_grid` (`grid::Grid::AccumulatedF32`): the `master` loops
//!   accumulate in `float`: 4001 IMU samples, 600 camera frames (docs/upstream/vio_data_simulation.md §8 item 1).
//! * `quirk_03_topic_imu_without_slash`, seq 0, zero covariances, frame `base_link`
//!   (`bag_sim`, docs/upstream/vio_data_simulation.md §4).
//! * `quirk_04_euler_uses_right_sample` (`integrate`): upstream `testImu` integrates
//!   interval i with sample i (docs/upstream/vio_data_simulation.md §6).
//! * `quirk_05_eigen_quaternion_sign` (`rotation::quat_from_matrix`): w may be negative.
//! * `quirk_06_motion_model_float_locals` (`motion::Mode::CompatF32`, `--compat`): the
//!   `float` constants of `MotionModel` (docs/upstream/vio_data_simulation.md §8 item 2). Off by default (exact f64); with it,
//!   `sim traj --compat` and `sim integrate --compat` reproduced upstream master's clean files
//!   byte for byte when checked once against the real program's output (those outputs are
//!   not committed: nothing built from fetched code is).
//!
//! Not reproduced: upstream noise (a fresh `std::random_device` per sample; docs/upstream/vio_data_simulation.md §8 item 6);
//! the uninitialised gyro/acc columns of `cam_pose.txt` (written as 0).

#![deny(missing_docs)]

mod bag_sim;
mod cli;
mod command;
mod compare;
mod compare_plot;
mod error;
mod grid;
mod integrate;
mod motion;
mod noise;
mod plot;
mod report;
mod rotation;
mod sensor_chain;
mod spline;
mod spline_sim;
mod textio;
mod traj;

// What the binary, the tests and the other crates' tests use; everything else is the
// crate's own.
pub use bag_sim::{BagConfig, message_count, run as run_bag};
pub use bag_sim::{BagFormat, BagSummary};
pub use cli::{
    BagArgs, BagFormatArg, CompareArgs, CompressionArg, FitArg, GridArg, InitArg, IntegrateArgs,
    MethodArg, ModelArgs, MotionArg, NoiseArgs, PresetArg, SensorArg, SensorsArgs, SplineArgs,
    TrajArgs,
};
pub use cli::{Cli, Command};
pub use command::run;
pub use error::{Result, SimError};
pub use motion::MotionSample;
pub use motion::{Motion, ellipse};
pub use noise::DiscreteNoise;
pub use noise::generate::axis_series;
pub use noise::model::{AxisModel, Chain, Filter, ImuModel, Line, SensorModel};
pub use noise::model::{BiasInstability, GaussMarkov, ResolvedChain, Warmup};
pub use noise::profiles::Profile;
pub use noise::truth::AxisTruth;
pub use noise::truth::{FilteredWhite, TermAvar};
pub use noise::truth_file::read_model;
pub use noise::{ContinuousNoise, NoiseGenerator, Preset, white_rw_axis};
pub use rotation::quat_from_matrix;
