//! Is this record fit for an Allan analysis? The one place every tool asks (`bag2mat info`,
//! `allan_kalibr`, `allan_imu_utils`), because the analysis assumes one static sensor
//! sampled at one rate, and real recordings break that in ways the Allan curve does not show:
//!
//! * **clocks** ([`clock`]): a clock that steps back (an NTP step) is cut to its longest
//!   consistent stretch instead of sorted into interleaved halves; duplicated samples (a
//!   chunk or file stored twice, a message written twice) are dropped and counted, more rows
//!   than the container promises are reported, equal stamps are flagged; the header and
//!   record clocks are cross-checked;
//! * **rate and gaps** ([`crate::timing`], the one gap rule): exact missing-sample counts,
//!   the longest gap's position, rate changes; a broken record is cut to its longest
//!   continuous stretch; the nominal rate (lost samples do not change it);
//! * **outliers** ([`outliers`]): single spikes, found in the time domain (an Allan curve
//!   cannot see them), reported with their time and dropped with `--drop-outliers`;
//! * **warm-up** ([`warmup`]): a drift at the start, fitted as an exponential per axis, with
//!   the `--skip-start` that outlasts it;
//! * **motion** ([`motion`]): a record that is not static (gravity direction or magnitude,
//!   angular rate beyond what the noise allows) refuses the corrected analysis;
//! * **units** ([`units`]): gravity's magnitude, the rate and the gyroscope's noise against
//!   what IMUs have, whatever unit the input claims.
//!
//! Its findings are typed ([`Finding`]: level, kind, axis, time, size), printed on stderr by
//! every tool (also with `--quiet`), and named by the IEEE 952 section and its yaml files.

pub(crate) mod clock;
pub(crate) mod motion;
pub(crate) mod outliers;
pub(crate) mod units;
pub(crate) mod warmup;

use std::borrow::Cow;
use std::fmt;

use rayon::prelude::*;

use crate::Sensor;
use crate::series::TimeColumn;
use crate::timing::{self, Timing};

/// How much a finding matters.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum Level {
    /// What was done (a cut, samples dropped on request): said, nothing to fix.
    Note,
    /// The analysis runs, but this record breaks one of its assumptions: its figures carry
    /// the error said.
    Warning,
    /// The corrected (IEEE 952) analysis would be meaningless on this record and is not run.
    Refusal,
}

impl fmt::Display for Level {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Level::Note => "note",
            Level::Warning | Level::Refusal => "warning",
        })
    }
}

/// What was found.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Kind {
    /// More rows than the container promises.
    ExtraRows,
    /// Samples stored twice (same stamps, same values).
    Duplicates,
    /// Different samples with one stamp.
    EqualStamps,
    /// The clock steps back.
    ClockStep,
    /// Samples missing.
    Gaps,
    /// The sampling rate changes.
    RateChange,
    /// header.stamp and the record time advance at different rates.
    ClockMismatch,
    /// The rate given on the command line is not the stamps'.
    RateArgument,
    /// A spike.
    Outlier,
    /// A drift at the start.
    WarmUp,
    /// The sensor moved.
    Motion,
    /// A unit the physics contradicts (gravity, rate, noise density).
    Units,
    /// Rows that alternate between two sensors.
    Interleaved,
}

impl Kind {
    /// True for the checks that read the values as samples of the sensor at the stamps'
    /// rate (spikes, warm-up, motion, units, two sensors), false for the clock's.
    pub(crate) fn judges_values_as_samples(self) -> bool {
        matches!(
            self,
            Kind::Outlier | Kind::WarmUp | Kind::Motion | Kind::Units | Kind::Interleaved
        )
    }

    /// The name the section and the yaml caveats use.
    pub(crate) fn name(self) -> &'static str {
        match self {
            Kind::ExtraRows => "extra rows",
            Kind::Duplicates => "duplicated samples",
            Kind::EqualStamps => "equal stamps",
            Kind::ClockStep => "clock step",
            Kind::Gaps => "gaps",
            Kind::RateChange => "rate change",
            Kind::ClockMismatch => "clock mismatch",
            Kind::RateArgument => "update rate",
            Kind::Outlier => "outlier",
            Kind::WarmUp => "warm-up",
            Kind::Motion => "motion",
            Kind::Units => "units",
            Kind::Interleaved => "two sensors",
        }
    }
}

/// One axis of the IMU.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct Axis {
    /// Gyro or accelerometer.
    pub sensor: Sensor,
    /// 0, 1, 2 for x, y, z.
    pub index: usize,
}

impl Axis {
    /// The six axes: gyro x y z, then acc x y z (the order of [`Record::values`]).
    pub const ALL: [Axis; 6] = [
        Axis::new(Sensor::Gyro, 0),
        Axis::new(Sensor::Gyro, 1),
        Axis::new(Sensor::Gyro, 2),
        Axis::new(Sensor::Acc, 0),
        Axis::new(Sensor::Acc, 1),
        Axis::new(Sensor::Acc, 2),
    ];

    /// An axis.
    pub const fn new(sensor: Sensor, index: usize) -> Axis {
        Axis { sensor, index }
    }

    /// `gyro x` … `acc z`.
    pub(crate) fn label(self) -> &'static str {
        self.sensor.axis_label(self.index)
    }
}

/// One finding about the record.
#[derive(Debug, Clone, PartialEq)]
pub struct Finding {
    /// How much it matters.
    pub level: Level,
    /// What it is.
    pub kind: Kind,
    /// The axis it concerns (`None`: the record, or its clock).
    pub axis: Option<Axis>,
    /// When, s from the first sample checked (`None`: throughout).
    pub time: Option<f64>,
    /// The sample (index among those checked) at that time.
    pub sample: Option<usize>,
    /// How big, in [`Finding::unit`].
    pub size: Option<f64>,
    /// The size's unit, or what a count counts (`samples`, `rows`).
    pub unit: &'static str,
    /// The size is a count.
    pub count: bool,
    /// For a warm-up: the `--skip-start` that outlasts it, s.
    pub skip_start: Option<f64>,
    /// What was found, what it does to the results and what was done or to do.
    pub text: String,
}

impl Finding {
    fn new(level: Level, kind: Kind, text: String) -> Finding {
        Finding {
            level,
            kind,
            axis: None,
            time: None,
            sample: None,
            size: None,
            unit: "",
            count: false,
            skip_start: None,
            text,
        }
    }

    fn at(mut self, time: f64, sample: usize) -> Finding {
        self.time = Some(time);
        self.sample = Some(sample);
        self
    }

    fn sized(mut self, size: f64, unit: &'static str) -> Finding {
        self.size = Some(size);
        self.unit = unit;
        self
    }

    fn counted(mut self, n: f64, what: &'static str) -> Finding {
        self.size = Some(n);
        self.unit = what;
        self.count = true;
        self
    }

    fn on(mut self, axis: Axis) -> Finding {
        self.axis = Some(axis);
        self
    }

    /// One line for a caveat: kind, axis, size and time (`warm-up on gyro x: 1.98e-2 rad/s`).
    pub fn short(&self) -> String {
        let mut s = self.kind.name().to_string();
        if let Some(a) = self.axis {
            s.push_str(" on ");
            s.push_str(a.label());
        }
        let mut parts: Vec<String> = Vec::new();
        if let Some(v) = self.size {
            parts.push(if self.count {
                format!("{v:.0} {}", self.unit)
            } else {
                format!("{v:.3e} {}", self.unit)
            });
        }
        // a warm-up is at the start: its advice says more than its time
        if let (Some(t), None) = (self.time, self.skip_start) {
            parts.push(format!("at t = {t:.3} s"));
        }
        if let Some(k) = self.skip_start {
            parts.push(format!("--skip-start {k:.0}"));
        }
        if !parts.is_empty() {
            s.push_str(&format!(" ({})", parts.join(", ")));
        }
        s
    }
}

impl Finding {
    /// The stderr line, naming `topic` when a run analyses several.
    pub fn line(&self, topic: Option<&str>) -> String {
        let mut s = format!("{}: {}", self.level, self.kind.name());
        if let Some(a) = self.axis {
            s.push_str(" on ");
            s.push_str(a.label());
        }
        if let Some(t) = topic {
            s.push_str(&format!(" of topic '{}'", crate::printable::escape(t)));
        }
        s.push_str(": ");
        s.push_str(&self.text);
        s
    }
}

impl fmt::Display for Finding {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.line(None))
    }
}

/// The record to check: one Imu topic's samples with their stamps.
#[derive(Debug, Clone, Copy)]
pub struct Record<'a> {
    /// Which clock `t` is.
    pub time: TimeColumn,
    /// The stamps analysed, ns, in row order.
    pub t: &'a [i64],
    /// The other clock's stamps (header.stamp beside the record time, or the other way),
    /// ns, when the input has them.
    pub other: Option<&'a [i64]>,
    /// Where each row was stored, when the reader sorted the rows by record time (`None`:
    /// row order is storage order).
    pub storage_order: Option<&'a [u32]>,
    /// Gyro x y z (rad/s), then acc x y z (m/s²).
    pub values: [&'a [f64]; 6],
    /// Messages the container promised, and rows it delivered (the whole topic).
    pub promised: Option<(u64, u64)>,
}

impl<'a> Record<'a> {
    /// The record of a series (`time` picks the analysed clock; the other is cross-checked),
    /// with its stamps in ns (from [`timing::ns_of_times`]).
    pub fn of_series(
        s: &'a crate::ImuSeries,
        time: TimeColumn,
        t: &'a [i64],
        other: &'a [i64],
    ) -> Record<'a> {
        Record {
            time,
            t,
            other: Some(other),
            storage_order: s.storage_order.as_deref(),
            values: [
                &s.gyro[0], &s.gyro[1], &s.gyro[2], &s.acc[0], &s.acc[1], &s.acc[2],
            ],
            promised: s.report.promised.map(|p| (p, s.report.delivered)),
        }
    }
}

/// What the tools may ask for.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Options {
    /// Drop the samples found to be spikes (`--drop-outliers`).
    pub drop_outliers: bool,
}

/// Which rows to analyse.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Keep {
    /// Every row (a clean record: nothing copied, the outputs as before).
    All,
    /// These rows, in order.
    Rows(Vec<usize>),
}

impl Keep {
    /// Number of rows kept out of `n`.
    pub fn len(&self, n: usize) -> usize {
        match self {
            Keep::All => n,
            Keep::Rows(r) => r.len(),
        }
    }

    /// True when every row is kept.
    pub fn is_all(&self) -> bool {
        matches!(self, Keep::All)
    }

    /// The kept rows of a column (borrowed when every row is kept).
    pub fn apply<'v, T: Copy>(&self, v: &'v [T]) -> Cow<'v, [T]> {
        match self {
            Keep::All => Cow::Borrowed(v),
            Keep::Rows(r) => Cow::Owned(r.iter().map(|&i| v[i]).collect()),
        }
    }

    /// The row of the `i`-th kept one.
    pub fn row(&self, i: usize) -> usize {
        match self {
            Keep::All => i,
            Keep::Rows(r) => r[i],
        }
    }

    /// The kept rows of the first `n` rows of a series (reordered storage is forgotten).
    pub fn select_series(&self, s: &crate::ImuSeries, n: usize) -> crate::ImuSeries {
        let rows = self.rows(n);
        let pick = |v: &[f64]| rows.iter().map(|&i| v[i]).collect::<Vec<f64>>();
        crate::ImuSeries {
            topic: s.topic.clone(),
            msg_type: s.msg_type.clone(),
            record_time: rows.iter().map(|&i| s.record_time[i]).collect(),
            stamp: rows.iter().map(|&i| s.stamp[i]).collect(),
            seq: rows.iter().map(|&i| s.seq[i]).collect(),
            acc: std::array::from_fn(|c| pick(&s.acc[c])),
            gyro: std::array::from_fn(|c| pick(&s.gyro[c])),
            notes: s.notes.clone(),
            report: s.report.clone(),
            storage_order: None,
            integration: s.integration,
        }
    }

    /// The kept rows among `0..n`, as a list.
    fn rows(&self, n: usize) -> Vec<usize> {
        match self {
            Keep::All => (0..n).collect(),
            Keep::Rows(r) => r.clone(),
        }
    }

    /// Keeps the kept rows for which `f(row)` holds.
    fn retain(&mut self, n: usize, f: impl Fn(usize) -> bool) {
        let rows: Vec<usize> = self.rows(n).into_iter().filter(|&i| f(i)).collect();
        *self = if rows.len() == n {
            Keep::All
        } else {
            Keep::Rows(rows)
        };
    }
}

/// What [`check`] found and decided.
#[derive(Debug, Clone)]
pub struct Check {
    /// Everything found, in the order checked.
    pub findings: Vec<Finding>,
    /// The rows to analyse.
    pub keep: Keep,
    /// The gap rule on the kept rows' stamps.
    pub timing: Timing,
    /// The nominal rate of the kept rows, Hz (span over the periods it holds).
    pub rate: Option<f64>,
}

impl Check {
    /// The finding that refuses the corrected analysis, if any.
    pub fn refusal(&self) -> Option<&Finding> {
        self.findings.iter().find(|f| f.level == Level::Refusal)
    }

    /// The largest `--skip-start` a warm-up asks for, s.
    pub fn skip_advice(&self) -> Option<f64> {
        self.findings
            .iter()
            .filter_map(|f| f.skip_start)
            .fold(None, |m, x| Some(m.map_or(x, |m: f64| m.max(x))))
    }
}

/// Seconds of `ns` for messages.
pub fn secs(ns: i64) -> f64 {
    ns as f64 * 1e-9
}

/// A stamp in ns as `sec.nsec`.
pub fn stamp_text(ns: i64) -> String {
    format!(
        "{}.{:09}",
        ns.div_euclid(1_000_000_000),
        ns.rem_euclid(1_000_000_000)
    )
}

/// Checks `r`: cuts and drops what cannot be analysed (duplicates, the far side of a clock
/// step, a broken record's shorter stretches, spikes when asked), and judges the rest.
pub fn check(r: &Record<'_>, opts: &Options) -> Check {
    let n = r.t.len();
    let mut findings = Vec::new();
    let mut keep = Keep::All;
    findings.extend(clock::extra_rows(r));
    findings.extend(clock::duplicates(r, &mut keep));
    findings.extend(clock::steps(r, &mut keep));
    let two_sensors = clock::interleaved(r, &keep);
    findings.extend(clock::equal_stamps(r, &keep, two_sensors.is_some()));
    findings.extend(two_sensors);
    // the gap rule on what is left; a broken record is cut to its longest stretch
    let mut t = keep.apply(r.t);
    let mut tm = timing::analyse(&t);
    if !tm.is_continuous()
        && let Some(seg) = tm.longest()
    {
        findings.extend(clock::gaps(&tm, &t, Some(seg)));
        let rows = keep.rows(n)[seg.start..seg.end].to_vec();
        keep = if rows.len() == n {
            Keep::All
        } else {
            Keep::Rows(rows)
        };
        t = keep.apply(r.t);
        tm = timing::analyse(&t);
    } else {
        findings.extend(clock::gaps(&tm, &t, None));
    }
    let rate = tm.nominal_rate();
    if let (Some(other), Some(rate)) = (r.other, rate) {
        findings.extend(clock::cross_check(r.time, rate, &keep.apply(other)));
    }
    // the values of the kept rows
    let tau0 = rate.map_or(0.0, |f| 1.0 / f);
    let cols: Vec<Cow<[f64]>> = r.values.par_iter().map(|v| keep.apply(v)).collect();
    let (spikes, sigma): (Vec<Vec<outliers::Spike>>, Vec<f64>) =
        cols.par_iter().map(|c| outliers::find(c)).unzip();
    let spike_rows: std::collections::BTreeSet<usize> = spikes
        .iter()
        .flatten()
        .flat_map(|s| s.start..s.start + s.len)
        .collect();
    for (a, sp) in Axis::ALL.iter().zip(&spikes) {
        findings.extend(outliers::findings(*a, sp, &t, opts.drop_outliers));
    }
    {
        let s6: [f64; 6] = std::array::from_fn(|k| sigma[k]);
        let v6: [&[f64]; 6] = std::array::from_fn(|k| &cols[k][..]);
        findings.extend(units::findings(v6, &s6, rate));
    }
    let clean: Vec<Cow<[f64]>> = if spike_rows.is_empty() {
        cols
    } else if opts.drop_outliers {
        let kept: Vec<usize> = (0..t.len()).filter(|i| !spike_rows.contains(i)).collect();
        let rows = keep.rows(n);
        keep = Keep::Rows(kept.iter().map(|&i| rows[i]).collect());
        t = keep.apply(r.t);
        r.values.par_iter().map(|v| keep.apply(v)).collect()
    } else {
        cols.into_iter()
            .zip(&spikes)
            .map(|(c, sp)| Cow::Owned(outliers::patched(&c, sp)))
            .collect()
    };
    if tau0 > 0.0 {
        let fits: Vec<Option<warmup::Fit>> =
            clean.par_iter().map(|c| warmup::find(c, tau0)).collect();
        for (a, f) in Axis::ALL.iter().zip(&fits) {
            if let Some(f) = f {
                findings.push(warmup::finding(*a, f, t.len() as f64 * tau0));
            }
        }
        let cols: [&[f64]; 6] = std::array::from_fn(|k| &clean[k][..]);
        let sigma: [f64; 6] = std::array::from_fn(|k| sigma[k]);
        findings.extend(motion::find(&cols, tau0, &sigma, &fits));
    }
    Check {
        findings,
        keep,
        timing: tm,
        rate,
    }
}

/// The findings on rows stored twice in a series as read (more rows than the container
/// promises, samples with the stamps and values of an earlier one), on clock `time`: what
/// the converter, which keeps every row, says.
pub fn stored_twice(s: &crate::ImuSeries, time: TimeColumn) -> Vec<Finding> {
    let (used, other) = match time {
        TimeColumn::Record => (&s.record_time, &s.stamp),
        TimeColumn::Header => (&s.stamp, &s.record_time),
    };
    let t = timing::ns_of_times(used);
    let o = timing::ns_of_times(other);
    let r = Record::of_series(s, time, &t, &o);
    let mut keep = Keep::All;
    clock::extra_rows(&r)
        .into_iter()
        .chain(clock::duplicates(&r, &mut keep))
        .collect()
}

/// Drops the findings on the axes of a sensor the topic does not carry (its columns were a
/// stand-in, `crate::series::StandIn`).
pub fn drop_absent(findings: &mut Vec<Finding>, absent: Option<Sensor>) {
    if let Some(s) = absent {
        findings.retain(|f| f.axis.is_none_or(|a| a.sensor != s));
    }
}

/// Index of the first sample at or after `t[0] + seconds` (the `--skip-start` cut).
pub fn skip_index(t: &[f64], seconds: f64) -> usize {
    let Some(&t0) = t.first() else { return 0 };
    t.partition_point(|&x| x < t0 + seconds)
}

/// The fewest samples a `--skip-start` may leave: below this no Allan deviation reaches past
/// a few sample periods, and nothing can be fitted.
pub const SKIP_MIN_SAMPLES_LEFT: usize = 1000;
/// The smallest part of the record a `--skip-start` may leave (a skip that takes more is a
/// mistaken number, not a warm-up).
pub const SKIP_MIN_FRACTION_LEFT: f64 = 0.1;

/// A `--skip-start` that cannot be applied.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SkipError {
    /// Negative, NaN or infinite.
    #[error("--skip-start must be a non-negative number of seconds, got {seconds}")]
    NotASpan {
        /// The value given.
        seconds: f64,
    },
    /// Leaves less than `SKIP_MIN_SAMPLES_LEFT` samples or `SKIP_MIN_FRACTION_LEFT` of the
    /// record.
    #[error(
        "--skip-start {seconds} leaves {left} of {total} samples ({:.1} s of a {span:.1} s record): too little for an Allan analysis (at least {SKIP_MIN_SAMPLES_LEFT} samples and {:.0} % of the record)",
        (.span - .seconds).max(0.0),
        100.0 * SKIP_MIN_FRACTION_LEFT
    )]
    TooLittleLeft {
        /// The value given.
        seconds: f64,
        /// Samples left after the cut.
        left: usize,
        /// Samples in the record.
        total: usize,
        /// The record's span in seconds.
        span: f64,
    },
}

/// The `--skip-start` cut of `t` (`skip_index`), checked: an error when it leaves too
/// little of the record to analyse (`SKIP_MIN_SAMPLES_LEFT`, `SKIP_MIN_FRACTION_LEFT`);
/// else the index and, when it drops more than half of the record, a warning to print.
pub fn checked_skip(t: &[f64], seconds: f64) -> Result<(usize, Option<String>), SkipError> {
    if !(seconds >= 0.0 && seconds.is_finite()) {
        return Err(SkipError::NotASpan { seconds });
    }
    let k = skip_index(t, seconds);
    let left = t.len() - k;
    let span = t.last().zip(t.first()).map_or(0.0, |(b, a)| b - a);
    if left < SKIP_MIN_SAMPLES_LEFT || (left as f64) < SKIP_MIN_FRACTION_LEFT * t.len() as f64 {
        return Err(SkipError::TooLittleLeft {
            seconds,
            left,
            total: t.len(),
            span,
        });
    }
    let warning = (2 * k > t.len()).then(|| {
        format!(
            "--skip-start {seconds} drops {k} of {} samples, more than half of the record",
            t.len()
        )
    });
    Ok((k, warning))
}

/// A relative disagreement between the rate given on the command line and the stamps'
/// above which the corrected analysis uses the stamps'.
pub const RATE_ARGUMENT_REL: f64 = 0.01;

/// The finding for a rate given on the command line that the stamps contradict: the
/// upstream-compatible part uses it (as upstream would), the corrected part the stamps'.
pub fn rate_argument(given: f64, measured: f64) -> Option<Finding> {
    let rel = (measured - given) / given;
    (rel.abs() > RATE_ARGUMENT_REL).then(|| {
        Finding::new(
            Level::Warning,
            Kind::RateArgument,
            format!(
                "--update-rate {given} Hz but the stamps give {measured:.4} Hz ({:+.2} %); the upstream-compatible part uses {given} Hz as upstream would (its N and K are off by ×{:.3} and ×{:.3}), the IEEE 952 section uses the measured {measured:.4} Hz",
                100.0 * rel,
                (measured / given).sqrt(),
                (given / measured).sqrt(),
            ),
        )
        .sized(measured, "Hz")
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn skip_index_counts_the_samples_before_the_cut() {
        let t: Vec<f64> = (0..100_000).map(|i| i as f64 * 0.005).collect();
        assert_eq!(skip_index(&t, 50.0), 10_000);
        assert_eq!(skip_index(&t, 0.0), 0);
        assert_eq!(skip_index(&t, 1e9), t.len());
    }

    /// White noise on six axes, gravity on acc z, stamps at 200 Hz from `T0`.
    fn clean(n: usize) -> (Vec<i64>, Vec<Vec<f64>>) {
        use rand::SeedableRng;
        use rand_distr::{Distribution, StandardNormal};
        let mut rng = rand::rngs::StdRng::seed_from_u64(0x18);
        let t = (0..n as i64)
            .map(|i| 1_700_000_000_000_000_000 + i * 5_000_000)
            .collect();
        let v = (0..6)
            .map(|k| {
                (0..n)
                    .map(|_| {
                        let z: f64 = StandardNormal.sample(&mut rng);
                        (if k == 5 { 9.81 } else { 0.0 }) + 0.01 * z
                    })
                    .collect()
            })
            .collect();
        (t, v)
    }

    fn record<'a>(t: &'a [i64], v: &'a [Vec<f64>]) -> Record<'a> {
        Record {
            time: TimeColumn::Record,
            t,
            other: Some(t),
            storage_order: None,
            values: std::array::from_fn(|k| &v[k][..]),
            promised: Some((t.len() as u64, t.len() as u64)),
        }
    }

    #[test]
    fn a_clean_record_keeps_every_row_and_finds_nothing() {
        let (t, v) = clean(100_000);
        let c = check(&record(&t, &v), &Options::default());
        assert_eq!(c.keep, Keep::All);
        assert!(c.findings.is_empty(), "{:?}", c.findings);
        assert_eq!(c.rate, Some(200.0));
    }

    #[test]
    fn a_spike_is_dropped_only_on_request() {
        let (t, mut v) = clean(100_000);
        v[1][40_000] = 50.0;
        let c = check(&record(&t, &v), &Options::default());
        assert_eq!(c.keep, Keep::All);
        let f = &c.findings;
        assert!(
            f.len() == 1 && f[0].kind == Kind::Outlier && f[0].level == Level::Warning,
            "{f:?}"
        );
        assert_eq!(f[0].axis, Some(Axis::new(Sensor::Gyro, 1)));
        assert_eq!((f[0].sample, f[0].time), (Some(40_000), Some(200.0)));
        let c = check(
            &record(&t, &v),
            &Options {
                drop_outliers: true,
            },
        );
        assert_eq!(c.keep.len(t.len()), t.len() - 1);
        assert_eq!(c.findings[0].level, Level::Note);
    }

    #[test]
    fn stamps_print_as_seconds_and_nanoseconds() {
        assert_eq!(
            stamp_text(1_700_000_000_005_000_000),
            "1700000000.005000000"
        );
        assert_eq!(stamp_text(-1), "-1.999999999");
    }
}
