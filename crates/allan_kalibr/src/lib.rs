//! # allan_kalibr
//!
//! Reproduces the MATLAB half of rpng/kalibr_allan (`9d38ea9`: `SCRIPT_allan_matparallel.m`,
//! `allan.m`, `SCRIPT_process_results.m`, `gen_chart.m`) in seconds instead of hours, and adds
//! what users ask for: Kalibr's `imu.yaml`, the curves as CSV, readable plots, and an IEEE
//! Std 952 analysis with intervals and verdicts (`ieee952`).
//! The behaviour contract is `docs/upstream/kalibr_allan.md`.
//!
//! ## Brief overview
//! The crate holds two analyses in two private module trees, `kalibr` and `ieee952`, no
//! module name shared between them; callers reach both through the flat names below.
//! * `kalibr`: the kalibr_allan reproduction: `kalibr::grid`, the 2000-point τ grid
//!   exactly as upstream builds it ([`TauGrid`]); `kalibr::estimator`, the non-overlapping
//!   `sig2` per axis (prefix-sum fast path, bit-exact replay of upstream's recursion, slow
//!   oracle: [`Estimator`]); `kalibr::chart_fit`, gen_chart's fixed-slope fits and read-offs
//!   ([`gen_chart`], [`ChartFit`]); `kalibr::report`, the exact printed text
//!   ([`chart_lines`], [`final_lines`]); `kalibr::curves`, the CSV; `kalibr::chart`, the two
//!   charts.
//! * [`operating`]: the noise the estimator will see — the operating-condition noise density
//!   of a moving record against a reference trajectory (`--reference`) or from the signal
//!   alone (`--operating`), with its interval, ratio to the static value and breakdown.
//! * [`spline`]: the workspace's one continuous-time B-spline (Spline Fusion), which the
//!   operating analysis predicts the IMU with and `sim spline` synthesises it with.
//! * `yaml`: Kalibr imu.yaml and the YAML spelling both halves write.
//! * [`consumers`]: every estimator users feed the figures into (Kalibr, OpenVINS, VINS,
//!   ORB-SLAM3, Basalt, PX4 EKF2, ArduPilot EKF3, GTSAM), each described once — keys, units,
//!   convention, the source it was read from — and the config files written for them.
//! * [`check`] and [`plan`]: the commands `allan_kalibr check` and `allan_kalibr plan`, above
//!   the analysis they run or advise with and the consumers' conventions they apply.
//! * `input`: `.mat`/`.bag` loading and the update-rate check ([`load_input`],
//!   [`snap_rate`]); `run`: the whole job ([`run()`], [`Config`]).
//! * `ieee952`: the IEEE Std 952 analysis both analysers (this one and `allan_imu_utils`)
//!   run after their upstream-compatible output, unless `--compat-only`
//!   ([`analyse_ieee952`], [`analyse_curve`], [`Ieee952Config`]): overlapping Allan
//!   deviation with Greenhall-EDF intervals (`ieee952::oadev`, `ieee952::edf`,
//!   `ieee952::ci`, `ieee952::noise_id`: [`Phase`], [`greenhall_edf`], [`chi2_interval`],
//!   [`identify`]); the 5-term model (plus a Gauss–Markov bump and a flicker floor's corner)
//!   fitted by GLS under the points' covariance (`ieee952::avar_cov`) with a
//!   model-discrepancy component, on the τ range the model can describe (`ieee952::fit`,
//!   [`FitConfig`]); per-axis verdicts and per-term 95 % intervals ([`AxisVerdict`],
//!   [`Verdict`]), the IEEE 952 region readings as cross-check and fallback
//!   (`ieee952::region`, [`Reading`]); record-length advice (`ieee952::advisor`,
//!   [`advise`]); the record check's findings named in the verdicts
//!   (`bag2mat::check_record`: clocks, gaps, outliers, warm-up, motion);
//!   other tools' Allan curves (`--curves`, `ieee952::curves_in`: [`read_curves`]); the
//!   section's text (`ieee952::imu`: [`ieee952_summary_text`]), its files (terms and curves
//!   CSV, Kalibr/VINS/ORB-SLAM3 yaml, with named columns `sim compare` reads:
//!   `ieee952::files`, [`write_ieee952_files`], [`TERMS_FILE`], [`CURVES_FILE`]) and chart
//!   (`ieee952::plot`: [`write_ieee952_chart`]).
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

pub mod check;
mod cli;
pub mod consumers;
mod error;
mod front;
mod ieee952;
mod input;
mod kalibr;
pub mod operating;
pub mod plan;
mod run;
pub mod spline;
mod yaml;

pub use cli::{Args, Cli, Command, Run, command_main};
pub use consumers::SensorValue;
pub use error::Error;
pub use front::CurvesInput;
pub use front::{
    Common, CommonArgs, Input, Job, MAT_INPUT, Section, TopicOutcome, command_line,
    main as analyser_main, rate_for_text, refusal_text, run_job, topic_failed, topic_sections,
};
pub use ieee952::advisor::advise;
pub use ieee952::advisor::{Advice, TermAdvice};
pub use ieee952::ci::chi2_interval;
pub use ieee952::csv_back::{OutputCsv, field as csv_field};
pub use ieee952::curves_in::{Curves, Format as CurvesFormat, SensorCurves};
pub use ieee952::curves_in::{
    CurvesError, ImuUtilsRaw, Options as CurvesOptions, read as read_curves,
};
pub use ieee952::edf::greenhall_edf;
pub use ieee952::files::{
    COL_AXIS, COL_CHI2_DOF, COL_CI95_HI, COL_CI95_LO, COL_FIT, COL_FIT_TAU_HI, COL_RESOLVED,
    COL_SENSOR, COL_TERM, COL_VALUE, COL_VERDICT, CURVE_ADEV, CURVE_AXIS, CURVE_M, CURVE_TAU,
    CURVES_FILE, TERMS_FILE, file_names as ieee952_file_names,
    write_outputs as write_ieee952_files,
};
pub use ieee952::imu::{
    AxisResult, ImuAnalysis, ImuCurves, analyse_curves as analyse_imu_curves,
    summary_text as ieee952_summary_text,
};
pub use ieee952::lines::{resonance_avar, resonance_poles, sinusoid_avar};
pub use ieee952::noise_id::{NoiseId, identify, identify_on};
pub use ieee952::oadev::AvarPoint;
pub use ieee952::oadev::{second_diff_sum, second_diff_sums};
pub use ieee952::plot::{find_truth, write_chart as write_ieee952_chart};
pub use ieee952::psd::{BUMP_X, find_lines, welch};
pub use ieee952::psd::{Line as PsdLine, Psd};
pub use ieee952::region::Readings;
pub use ieee952::region::{B_FLOOR_FACTOR, Reading, ReadingKind};
pub use ieee952::stated::section_text as ieee952_section_text;
pub use ieee952::term::{
    AvarBasis, FLICKER_AVAR, LINE_SLOTS, NoiseTerm, PsdForm, TERM_COUNT, TERMS, TermFacts,
};
pub use ieee952::{
    AlphaSource, Analysis as Ieee952Analysis, AxisVerdict, Config as Ieee952Config, CovBasis,
    CurveData, CurvePoint, FitConfig, FitSummary, GridSpec, IdMethod, Ieee952Error, LineShape,
    LineTerm, MAX_MISS_SHARE, MISS_RUN_SPAN, Overlap, Phase, Point as CurveFitPoint, Shapes, Term,
    Terms, Verdict, analyse as analyse_ieee952, analyse_curve, short,
};
pub use input::{Clock, RateChoice};
pub use input::{ImuData, load as load_input, snap_rate, value_problem};
pub use kalibr::chart_fit::{ChartFit, gen_chart};
pub use kalibr::estimator::{Estimator, prefix_in_place, sig2_prefix_fused, sig2_tiled};
pub use kalibr::grid::TauGrid;
pub use kalibr::report::{chart_lines, final_lines};
pub use run::{
    Analysis, Config, RunOutput, TOOL, TopicRun, analyse, curves_rate, curves_text, run,
    run_topics, sections,
};
