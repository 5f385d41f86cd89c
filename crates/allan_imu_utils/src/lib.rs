//! Reproduces gaowenliang/imu_utils (`2cdda91`) without ROS: reads `sensor_msgs/Imu` from a
//! ROS 1 bag, computes the overlapping Allan variance on imu_utils' cluster grid, fits its
//! 5-term model the way Ceres 2.1's dogleg does, and writes the same stdout, curve files and
//! OpenCV yaml — plus a yaml with the fit read correctly and plots.
//!
//! Specification: `docs/upstream/imu_utils.md`. Modules, in pipeline order:
//! `collect` (stop rule), `factors` (cluster grid), `estimator` (Allan variance),
//! `fit` (start point, dogleg, derived values), `report` (stdout and curve files),
//! `opencv_yaml` (both yaml files), `plot`; `launch` and `cli` turn the user's
//! flags or roslaunch file into a [`Config`]; `run` ties them together.
//!
//! # Quirks reproduced on purpose (docs/upstream/imu_utils.md §6)
//! 1. `*_n` is the fitted ADEV at 1 s times √freq (discrete), not a density.
//! 2. `*_w` is the minimum of the fitted ADEV curve, not a random walk.
//! 3. `findMinNum` starts at 1000.0 (gyro floor clamp).
//! 4. 57.3 instead of 180/π.
//! 5. The first gyro "White Noise" line is in rad/h and uses N only.
//! 6. Acc-only point filter (`checkData`).
//! 7. 50 Ceres iterations (attempts).
//! 8. Mean-period frequency; uniform sampling assumed.
//! 9. All taus up to maxStride fitted with equal weight.
//! 10. Stop at the first stamp past `max_time_min` (kept); end of bag handled (upstream hangs).
//! 11. All txt files use the x-axis taus.
//! 12. Quoted unit strings with a leading space in the yaml.
//! 13. NaN variance → fit aborts at iteration 0, start point used.
//! 14. Short data only warns.
//!
//! The corrected reading is written beside the compat one, never instead of it
//! (`opencv_yaml::YamlMode`).

// Index loops over the fixed 5-vectors of the fit mirror upstream's (Eigen/Ceres) operation
// order term by term, which iterator chains would obscure.
#![allow(clippy::needless_range_loop)]

mod analysis;
mod cli;
mod collect;
mod error;
mod estimator;
mod factors;
mod fit;
mod launch;
mod opencv_yaml;
mod plot;
mod report;
mod run;

// What the binary, the tests and the benchmark use; everything else is the crate's own.
pub use analysis::{Analysis, AxisAllan};
pub use cli::{Args, Config, TOOL};
pub use error::{Error, LaunchSyntax};
pub use estimator::{allan_variance, mean_period, thetas};
pub use factors::factors;
pub use fit::AxisFit;
pub use fit::dogleg::{Summary as DoglegSummary, Termination as DoglegTermination};
pub use run::{CurvesOutcome, Outcome, TopicRun, run, run_curves, run_topics, sections};
