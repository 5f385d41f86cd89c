//! The studies of the IEEE 952 estimator on simulated and real data, through the public API:
//! issue 10's accuracy studies on every `sim` profile (profiles.rs) and on band-limited
//! sensors (bandlimited.rs), issue 17's vibration lines (lines.rs), N and K against the
//! Cramér–Rao bound (accuracy.rs), issue 40's coverage of the intervals, bounds and bands
//! (coverage.rs), the real-IMU curves of `testdata/real_curves` (real.rs), parity with
//! Stable32 and allantools (stable32.rs), and `allan_kalibr plan` against the analysis'
//! advice (plan.rs). The long ones are `#[ignore]`d; scripts/test.sh runs the release
//! studies by name (`studies::profiles::profiles_study`,
//! `studies::bandlimited::bandlimited_study`, `studies::lines::lines_study`,
//! `studies::coverage::coverage_study`, `studies::plan::plan_study`,
//! `studies::operating::operating_interval_coverage_study`).

mod accuracy;
mod bandlimited;
pub(crate) mod coverage;
mod lines;
mod operating;
pub(crate) mod plan;
mod profiles;
mod real;
mod stable32;
