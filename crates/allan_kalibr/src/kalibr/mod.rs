//! The kalibr_allan reproduction: the MATLAB half of rpng/kalibr_allan (`9d38ea9`) bit for
//! bit, and the upstream-compatible files written from it (spec `docs/upstream/kalibr_allan.md`).
//!
//! * [`grid`]: the 2000-point τ grid exactly as `SCRIPT_allan_matparallel.m` builds it.
//! * [`estimator`]: the non-overlapping `sig2` per axis of `allan.m` (prefix-sum fast path,
//!   bit-exact replay of upstream's recursion, slow oracle).
//! * [`chart_fit`]: `gen_chart.m`'s fixed-slope fits and read-offs.
//! * [`report`]: the exact text `SCRIPT_process_results.m` prints; [`curves`]: the curves as
//!   CSV; [`chart`]: `gen_chart.m`'s two charts.
//!
//! * [`imu_yaml`]: Kalibr's `imu.yaml` written from these numbers; its YAML spelling is
//!   shared with the IEEE 952 files and the consumers' configs ([`crate::yaml`]).

pub(crate) mod chart;
pub(crate) mod chart_fit;
pub(crate) mod curves;
pub(crate) mod estimator;
pub(crate) mod grid;
pub(crate) mod imu_yaml;
pub(crate) mod report;
