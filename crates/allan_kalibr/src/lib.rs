//! # allan_kalibr
//!
//! Reproduces the MATLAB half of rpng/kalibr_allan (`9d38ea9`: `SCRIPT_allan_matparallel.m`,
//! `allan.m`, `SCRIPT_process_results.m`, `gen_chart.m`) in seconds instead of hours, and adds
//! what users ask for: Kalibr's `imu.yaml`, the curves as CSV, readable plots, and an IEEE
//! Std 952 analysis with intervals and verdicts ([`ieee952`]).
//! The behaviour contract is `shared/specs/kalibr_allan.md`.
//!
//! ## Brief overview
//! The crate holds two analyses in two module trees, [`kalibr`] and [`ieee952`], no module
//! name shared between them:
//! * [`kalibr`]: the kalibr_allan reproduction: [`kalibr::grid`], the 2000-point τ grid
//!   exactly as upstream builds it; [`kalibr::estimator`], the non-overlapping `sig2` per
//!   axis (prefix-sum fast path, bit-exact replay of upstream's recursion, slow oracle);
//!   [`kalibr::chart_fit`], gen_chart's fixed-slope fits and read-offs; [`kalibr::report`],
//!   the exact printed text; [`kalibr::curves`], the CSV; [`kalibr::chart`], the two charts.
//! * [`yaml`]: Kalibr imu.yaml and the YAML spelling both halves write.
//! * [`input`]: `.mat`/`.bag` loading and the update-rate check; [`run`](mod@run): the whole
//!   job.
//! * [`ieee952`]: the IEEE Std 952 analysis both analysers (this one and `allan_imu_utils`)
//!   run after their upstream-compatible output, unless `--compat-only`: overlapping Allan
//!   deviation with Greenhall-EDF intervals ([`ieee952::oadev`], [`ieee952::edf`],
//!   [`ieee952::ci`], [`ieee952::noise_id`]); the 5-term model (plus a Gauss–Markov bump and
//!   a flicker floor's corner) fitted by GLS under the points' covariance
//!   ([`ieee952::avar_cov`]) with a model-discrepancy component, on the τ range the model
//!   can describe ([`ieee952::fit`]); per-axis verdicts and per-term 95 % intervals, the IEEE
//!   952 region readings as cross-check and fallback ([`ieee952::region`]); record-length
//!   advice ([`ieee952::advisor`]); the record check's findings named in the verdicts
//!   (`bag2mat::record_check`: clocks, gaps, outliers, warm-up, motion);
//!   other tools' Allan curves (`--curves`, [`ieee952::curves_in`]); the section's text
//!   ([`ieee952::imu`]), its files (terms and curves CSV, Kalibr/VINS/ORB-SLAM3 yaml, with
//!   named columns `sim compare` reads: [`ieee952::files`]) and chart ([`ieee952::plot`]).
//!
//! ## Units and conventions
//! Accelerometer in m/s², gyroscope in rad/s, as in the bag. The four numbers are
//! continuous-time Kalibr values: noise densities in m/s²/√Hz and rad/s/√Hz (the −½ line at
//! τ = 1 s), random walks in m/s³/√Hz and rad/s²/√Hz (the +½ line at τ = 3 s).
//!
//! ## Quirks reproduced on purpose (compat)
//! * The τ grid starts at δ² (issue #25), keeps its m = 0 points (NaN), duplicates, and the
//!   knife-edge last point (`kalibr::grid`, `quirk_25_grid_starts_at_delta_squared`,
//!   `quirk_knife_edge_last_point`).
//! * `sig2` is the non-overlapping deviation; the overlapping one upstream also computes is
//!   never used (`kalibr::estimator`).
//! * With exactly two clusters Octave squares with `pow(d, 2)` (`kalibr::estimator`,
//!   `quirk_two_clusters_square_with_pow`).
//! * Deviations (not variances) are averaged over axes (issue #27); fit windows are grid
//!   indices `1:minid-50` and `minid+50:end`; empty windows give NaN (issues #12/#13,
//!   `quirk_12_13_*` in `kalibr::chart_fit`).
//! * The update rate drives the grid; timestamps are only counted (they are checked here
//!   and a warning printed, which upstream never does).

pub mod cli;
pub mod error;
pub mod front;
pub mod ieee952;
pub mod input;
pub mod kalibr;
pub mod run;
pub mod yaml;

pub use error::Error;
pub use front::{Common, CurvesInput, Input};
pub use kalibr::estimator::Estimator;
pub use run::{Analysis, Config, CurvesOutput, RunOutput, analyse, run, run_curves, run_on};
