//! Loading the samples (a `.mat` with `data_imu`, or a `.bag` read through bag2mat exactly
//! as bagconvert does) and choosing the update rate that drives the τ grid.
//!
//! Upstream never looks at the timestamps except to count them (docs/upstream/kalibr_allan.md §2): the
//! user types the rate into the script. Here the rate is the stamps' nominal rate
//! (`bag2mat::analyse_timing`: lost samples do not change it) when not given; a given rate the stamps
//! contradict (`bag2mat::rate_argument`) still drives the upstream-compatible
//! grid, as upstream, and the IEEE 952 section uses the measured one.

use std::path::Path;

use bag2mat::shared::note::Note;

use crate::error::Error;

/// An estimated rate within this relative distance of an integer is rounded to it
/// (timestamps of a 200 Hz IMU give 199.99…, and the grid wants the nominal rate).
pub const RATE_SNAP_REL: f64 = 0.005;

/// The samples as bagconvert's `data_imu` columns.
#[derive(Debug, Clone, PartialEq)]
pub struct ImuData {
    /// Column 1: time in seconds (bag record time, `sec + 1e-9*nsec`, for bags).
    pub t: Vec<f64>,
    /// Columns 2–7: ax ay az (m/s²), wx wy wz (rad/s).
    pub axes: [Vec<f64>; 6],
    /// The topic the samples came from (the bag's own spelling), if known.
    pub topic: Option<String>,
    /// Messages for the user (bag2mat's notes).
    pub notes: Vec<Note>,
    /// The stamps in nanoseconds and what the record check needs besides the samples.
    pub clock: Clock,
    /// A sensor the topic does not carry (PX4 `sensor_gyro`, a gyro-only DataFlash
    /// instance): its columns hold zeros as a stand-in (`bag2mat::StandIn::Zeros`),
    /// never analysed nor written.
    pub absent: Option<bag2mat::Sensor>,
    /// For a topic of integrated deltas, its rows' integration intervals (whether they are
    /// samples: [`bag2mat::check_integration`]).
    pub integration: Option<bag2mat::Integration>,
}

/// The clock side of [`ImuData`], for `bag2mat::check_record`: the time column in exact
/// nanoseconds (a bag's stamps; a `.mat`'s seconds as they are), the other clock of a bag,
/// the storage order when the reader sorted, and the container's promised count.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Clock {
    /// Which clock `t` is.
    pub time: bag2mat::TimeColumn,
    /// `t` in ns.
    pub t_ns: Vec<i64>,
    /// The other clock (header.stamp beside the record time, or the other way), ns.
    pub other_ns: Option<Vec<i64>>,
    /// Storage position of each sample, when the reader sorted them by record time.
    pub storage_order: Option<Vec<u32>>,
    /// Messages promised and rows delivered on the topic.
    pub promised: Option<(u64, u64)>,
}

impl ImuData {
    /// Number of samples N.
    pub fn len(&self) -> usize {
        self.t.len()
    }

    /// True when there are no samples.
    pub fn is_empty(&self) -> bool {
        self.t.is_empty()
    }

    /// Builds the columns from a bag2mat series with the chosen time column (bagconvert's
    /// record time by default), through bag2mat's one series-to-matrix conversion.
    pub(crate) fn from_series(mut s: bag2mat::ImuSeries, time: bag2mat::TimeColumn) -> Self {
        let absent = s.stand_in_absent(bag2mat::StandIn::Zeros);
        let integration = s.integration;
        let topic = s.topic.clone();
        let notes = s.notes.clone();
        let (used, other) = match time {
            bag2mat::TimeColumn::Record => (&s.record_time, &s.stamp),
            bag2mat::TimeColumn::Header => (&s.stamp, &s.record_time),
        };
        let clock = Clock {
            time,
            t_ns: bag2mat::ns_of_times(used),
            other_ns: Some(bag2mat::ns_of_times(other)),
            storage_order: s.storage_order.take(),
            promised: s.report.promised.map(|p| (p, s.report.delivered)),
        };
        let [t, ax, ay, az, wx, wy, wz] = bag2mat::into_data_imu(s, time).columns;
        ImuData {
            t,
            axes: [ax, ay, az, wx, wy, wz],
            topic: Some(topic),
            notes,
            clock,
            absent,
            integration,
        }
    }

    /// The samples `keep` names (all of them: unchanged).
    pub(crate) fn select(self, keep: &bag2mat::KeepRows) -> ImuData {
        if keep.is_all() {
            return self;
        }
        let c = &self.clock;
        ImuData {
            t: keep.apply(&self.t).into_owned(),
            axes: std::array::from_fn(|a| keep.apply(&self.axes[a]).into_owned()),
            topic: self.topic.clone(),
            notes: self.notes.clone(),
            clock: Clock {
                time: c.time,
                t_ns: keep.apply(&c.t_ns).into_owned(),
                other_ns: c.other_ns.as_ref().map(|o| keep.apply(o).into_owned()),
                storage_order: None,
                promised: c.promised,
            },
            absent: self.absent,
            integration: self.integration,
        }
    }

    /// Drops the first `k` samples.
    pub(crate) fn drop_first(&mut self, k: usize) {
        self.t.drain(..k);
        for c in self.axes.iter_mut() {
            c.drain(..k);
        }
        let c = &mut self.clock;
        c.t_ns.drain(..k.min(c.t_ns.len()));
        if let Some(o) = c.other_ns.as_mut() {
            o.drain(..k.min(o.len()));
        }
        if let Some(o) = c.storage_order.as_mut() {
            o.drain(..k.min(o.len()));
        }
    }

    /// The record the check reads: gyro x y z, then acc x y z, with the clock.
    pub(crate) fn record(&self) -> bag2mat::CheckInput<'_> {
        let a = &self.axes;
        bag2mat::CheckInput {
            time: self.clock.time,
            t: &self.clock.t_ns,
            other: self.clock.other_ns.as_deref(),
            storage_order: self.clock.storage_order.as_deref(),
            values: [&a[3], &a[4], &a[5], &a[0], &a[1], &a[2]],
            promised: self.clock.promised,
        }
    }

    /// Checks that every sample is finite (a NaN would silently turn whole curves into NaN).
    pub fn check_finite(&self) -> Result<(), Error> {
        self.scan_checked().map(|_| ())
    }

    /// One pass over each column (the six in parallel): fails like [`ImuData::check_finite`]
    /// on the first non-finite sample (axes in order), else returns what [`value_problem`]
    /// needs, so the run reads the columns once for both checks.
    pub(crate) fn scan_checked(&self) -> Result<[ColumnScan; 6], Error> {
        use rayon::prelude::*;
        let scans: Vec<ColumnScan> = self.axes.par_iter().map(|c| ColumnScan::of(c)).collect();
        for (a, (scan, col)) in scans.iter().zip(&self.axes).enumerate() {
            if let Some(i) = scan.first_non_finite {
                return Err(Error::BadData {
                    what: format!(
                        "sample {} of {} is {} (every sample must be finite)",
                        i + 1,
                        AXIS_NAMES[a],
                        col[i]
                    ),
                });
            }
        }
        Ok(std::array::from_fn(|a| scans[a]))
    }
}

/// The six sample columns' names, in `data_imu` order.
pub const AXIS_NAMES: [&str; 6] = ["ax", "ay", "az", "wx", "wy", "wz"];

/// True for a `.mat` path (by extension, as upstream's scripts name them).
fn is_mat(path: &Path) -> bool {
    path.extension()
        .is_some_and(|e| e.to_string_lossy().eq_ignore_ascii_case("mat"))
}

/// Reads one topic of a bag (any format bag2mat reads) or a `.mat` (variable `data_imu`).
pub fn load(path: &Path, topic: &str, quiet: bool) -> Result<ImuData, Error> {
    let sel = bag2mat::TopicSelector::one(topic);
    let opts = bag2mat::InputOptions::default();
    Ok(load_all(path, &sel, bag2mat::TimeColumn::Record, quiet, &opts)?.remove(0))
}

/// Reads the selected topics of a bag or log in one pass, or the one `data_imu` of a `.mat`.
pub(crate) fn load_all(
    path: &Path,
    sel: &bag2mat::TopicSelector,
    time: bag2mat::TimeColumn,
    quiet: bool,
    opts: &bag2mat::InputOptions,
) -> Result<Vec<ImuData>, Error> {
    if is_mat(path) {
        return Ok(vec![load_mat(path)?]);
    }
    match bag2mat::read_imu_topics_with(path, sel, &bag2mat::ReadOptions { quiet }, opts) {
        Ok(r) => Ok(r
            .series
            .into_iter()
            .map(|s| ImuData::from_series(s, time))
            .collect()),
        Err(bag2mat::Error::NotABag { .. }) => Err(Error::UnknownInput {
            path: path.to_path_buf(),
        }),
        Err(e) => Err(e.into()),
    }
}

fn load_mat(path: &Path) -> Result<ImuData, Error> {
    let d = bag2mat::read_data_imu(path)?;
    let [t, ax, ay, az, wx, wy, wz] = d.columns;
    let clock = Clock {
        time: bag2mat::TimeColumn::Record,
        t_ns: bag2mat::ns_of_seconds(&t),
        ..Clock::default()
    };
    Ok(ImuData {
        t,
        axes: [ax, ay, az, wx, wy, wz],
        topic: None,
        notes: Vec::new(),
        clock,
        absent: None,
        integration: None,
    })
}

/// Largest sample magnitude accepted: the Allan variance sums squared differences, and
/// (1e150)² = 1e300 stays finite in f64 where 1e300 would overflow to infinity.
pub const MAX_ABS_VALUE: f64 = 1e150;

/// What one pass over a column finds: its first non-finite sample, its largest magnitude and
/// whether it is constant. The finiteness check and [`value_problem`] share it, so a run reads
/// each column once for both.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ColumnScan {
    /// Index of the first NaN or ±∞.
    pub first_non_finite: Option<usize>,
    /// Largest |value| (NaN ignored, 0 for an empty column).
    pub max_abs: f64,
    /// The first sample (None for an empty column).
    pub first: Option<f64>,
    /// Every sample equals the first (false for a NaN first sample, as `==` says).
    pub constant: bool,
}

impl ColumnScan {
    /// Scans `col` once (8 independent lanes, so the compiler vectorises it).
    pub(crate) fn of(col: &[f64]) -> ColumnScan {
        const L: usize = 8;
        let first = col.first().copied();
        let f = first.unwrap_or(0.0);
        let (mut mx, mut bad, mut differ) = ([0.0f64; L], [false; L], [false; L]);
        let (chunks, rest) = col.as_chunks::<L>();
        for c in chunks {
            for l in 0..L {
                mx[l] = mx[l].max(c[l].abs());
                bad[l] |= !c[l].is_finite();
                differ[l] |= c[l] != f;
            }
        }
        let mut max_abs = mx.iter().fold(0.0f64, |m, &v| m.max(v));
        let (mut any_bad, mut any_differ) = (bad.contains(&true), differ.contains(&true));
        for &v in rest {
            max_abs = max_abs.max(v.abs());
            any_bad |= !v.is_finite();
            any_differ |= v != f;
        }
        ColumnScan {
            // rare: found again by a plain search
            first_non_finite: if any_bad {
                col.iter().position(|v| !v.is_finite())
            } else {
                None
            },
            max_abs,
            first,
            constant: first.is_some() && !any_differ,
        }
    }

    /// [`value_problem`] of the scanned column, named `axis`.
    pub(crate) fn problem(&self, axis: &str) -> Option<(bool, String)> {
        let max = self.max_abs;
        if max > MAX_ABS_VALUE {
            return Some((
                true,
                format!(
                    "{axis} holds values up to {max:e}: beyond {MAX_ABS_VALUE:e} the squared differences of the Allan variance overflow"
                ),
            ));
        }
        let first = self.first?;
        if self.constant {
            return Some((
                false,
                format!(
                    "{axis} is constant ({first} in every sample): its Allan deviation is 0, so its noise fits are undefined (NaN); a sensor that reports no noise is saturated, quantized too coarsely or not streaming"
                ),
            ));
        }
        None
    }
}

/// What makes one axis unusable or its results meaningless, said in words: values too large
/// for the sums of squares (an error), or a constant axis (its Allan deviation is 0 and the
/// fits take logarithms of it: NaN). `None` for ordinary data.
pub fn value_problem(axis: &str, col: &[f64]) -> Option<(bool, String)> {
    ColumnScan::of(col).problem(axis)
}

/// The former one-column [`value_problem`], kept as the obviously correct reference.
#[cfg(test)]
fn value_problem_slow(axis: &str, col: &[f64]) -> Option<(bool, String)> {
    let max = col.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    if max > MAX_ABS_VALUE {
        return Some((
            true,
            format!(
                "{axis} holds values up to {max:e}: beyond {MAX_ABS_VALUE:e} the squared differences of the Allan variance overflow"
            ),
        ));
    }
    let first = *col.first()?;
    if col.iter().all(|&v| v == first) {
        return Some((
            false,
            format!(
                "{axis} is constant ({first} in every sample): its Allan deviation is 0, so its noise fits are undefined (NaN); a sensor that reports no noise is saturated, quantized too coarsely or not streaming"
            ),
        ));
    }
    None
}

/// The rate used for the grid and what to tell the user about it.
#[derive(Debug, Clone, PartialEq)]
pub struct RateChoice {
    /// Hz, drives the τ grid of the upstream-compatible part.
    pub used: f64,
    /// The nominal rate of the analysed stamps (`bag2mat::analyse_timing`), when they allow one.
    pub measured: Option<f64>,
    /// The rate the IEEE 952 section uses: the stamps' (snapped as [`snap_rate`]), unless
    /// the given rate agrees with them (`bag2mat::RATE_ARGUMENT_REL`) or they
    /// give none.
    pub section: f64,
    /// An info line (estimated), for stderr.
    pub message: Option<String>,
    /// A given rate the stamps contradict.
    pub finding: Option<bag2mat::Finding>,
}

/// A measured rate within this fraction of a rate with at most [`RATE_ROUND_DECIMALS`]
/// decimals is that rate: 1 ppm, far inside a MEMS clock's own tolerance (10–50 ppm), so the
/// yaml files say `62.5`, not the float noise of a mean period (`62.49998612009537`).
pub const RATE_ROUND_REL: f64 = 1e-6;
/// Decimals of the round rates [`snap_rate`] snaps to within [`RATE_ROUND_REL`].
pub const RATE_ROUND_DECIMALS: i32 = 3;

/// A rate from the stamps within `RATE_SNAP_REL` of an integer is that integer; else one
/// within `RATE_ROUND_REL` of a rate with few decimals is that rate.
pub fn snap_rate(m: f64) -> f64 {
    let r = m.round();
    if r >= 1.0 && ((m - r) / r).abs() <= RATE_SNAP_REL {
        return r;
    }
    for d in 1..=RATE_ROUND_DECIMALS {
        let scale = 10f64.powi(d);
        let r = (m * scale).round() / scale;
        if r > 0.0 && ((m - r) / r).abs() <= RATE_ROUND_REL {
            return r;
        }
    }
    m
}

/// Mean rate of the timestamps, `(N-1)/(t_N - t_1)`; None without a positive span (the
/// obviously correct reference of the nominal rate on a record without gaps).
pub(crate) fn measured_rate(t: &[f64]) -> Option<f64> {
    let (first, last) = (t.first()?, t.last()?);
    let span = last - first;
    (t.len() >= 2 && span.is_finite() && span > 0.0).then(|| (t.len() - 1) as f64 / span)
}

/// Chooses the update rate from the given one and the stamps' nominal rate `measured`
/// (`bag2mat::analyse_timing`: lost samples do not change it): the given one for the
/// upstream-compatible grid (as upstream), the measured one, snapped to an integer within
/// [`RATE_SNAP_REL`], otherwise and for the IEEE 952 section.
pub(crate) fn choose_rate(
    given: Option<f64>,
    measured: Option<f64>,
    n: usize,
) -> Result<RateChoice, Error> {
    match given {
        Some(rate) => {
            if !(rate.is_finite() && rate > 0.0) {
                return Err(Error::BadRate(rate));
            }
            let finding = measured.and_then(|m| bag2mat::rate_argument(rate, m));
            let section = match (measured, &finding) {
                (Some(m), Some(_)) => snap_rate(m),
                _ => rate,
            };
            Ok(RateChoice {
                used: rate,
                measured,
                section,
                message: None,
                finding,
            })
        }
        None => {
            let m = measured.ok_or_else(|| Error::NoRate {
                what: format!("{n} samples, no positive time span"),
            })?;
            let used = snap_rate(m);
            let message = Some(format!(
                "update rate: {used} Hz (estimated from the timestamps: {m:.4} Hz; pass --rate to override)"
            ));
            Ok(RateChoice {
                used,
                measured,
                section: used,
                message,
                finding: None,
            })
        }
    }
}

/// The finiteness and value checks of each column present (`absent`: the sensor the record
/// lacks): a column that cannot be analysed is an error, a doubtful one a warning in `notes`.
pub(crate) fn check_scans(
    scans: &[ColumnScan; 6],
    absent: Option<bag2mat::Sensor>,
    notes: &mut Vec<Note>,
) -> Result<(), Error> {
    for (a, (name, scan)) in AXIS_NAMES.iter().zip(scans).enumerate() {
        if Some(data_imu_sensor(a)) == absent {
            continue;
        }
        match scan.problem(name) {
            Some((true, what)) => return Err(Error::BadData { what }),
            Some((false, what)) => notes.push(Note::warning(what)),
            None => {}
        }
    }
    Ok(())
}

/// `--skip-start`: drops the samples of the first `seconds` of the record, said in `notes`
/// (a warning when that is most of it).
pub(crate) fn skip_start(
    data: &mut ImuData,
    seconds: f64,
    notes: &mut Vec<Note>,
) -> Result<(), Error> {
    let (k, warning) = bag2mat::checked_skip(&data.t, seconds)?;
    data.drop_first(k);
    notes.extend(warning.map(Note::warning));
    notes.push(Note::info(format!(
        "--skip-start {seconds}: dropped the first {k} samples ({} left)",
        data.len()
    )));
    Ok(())
}

/// The sensor of column `a` of the six `data_imu` sample columns (ax ay az wx wy wz).
fn data_imu_sensor(a: usize) -> bag2mat::Sensor {
    if a < 3 {
        bag2mat::Sensor::Acc
    } else {
        bag2mat::Sensor::Gyro
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_measured_rate_is_said_without_float_noise() {
        assert_eq!(snap_rate(62.49998612009537), 62.5);
        assert_eq!(snap_rate(199.3), 199.0);
        assert_eq!(snap_rate(33.333333), 33.333333);
        assert_eq!(snap_rate(12.3456), 12.3456);
        assert_eq!(snap_rate(0.0125000004), 0.0125000004);
    }

    fn times(n: usize, rate: f64) -> Vec<f64> {
        (0..n).map(|i| 1.6e9 + i as f64 / rate).collect()
    }

    /// The nominal rate of `t`, as the run measures it.
    fn nominal(t: &[f64]) -> Option<f64> {
        bag2mat::analyse_timing(&bag2mat::ns_of_seconds(t)).nominal_rate()
    }

    #[test]
    fn column_scan_matches_the_plain_checks() {
        let mut cols: Vec<Vec<f64>> = vec![
            vec![],
            vec![1.0],
            vec![2.5; 21],
            (0..37).map(|i| (i as f64 * 0.3).sin()).collect(),
            vec![-3e151, 1.0, 2.0],
        ];
        for (len, at, v) in [
            (21, 0, f64::NAN),
            (21, 20, f64::NAN),
            (40, 17, f64::INFINITY),
            (9, 8, f64::NEG_INFINITY),
            (16, 3, 2e150),
        ] {
            let mut c: Vec<f64> = (0..len).map(|i| i as f64).collect();
            c[at] = v;
            cols.push(c);
        }
        let mut nan_first = vec![1.0; 12];
        nan_first[0] = f64::NAN;
        cols.push(nan_first);
        for c in &cols {
            let scan = ColumnScan::of(c);
            assert_eq!(scan.problem("ax"), value_problem_slow("ax", c), "{c:?}");
            assert_eq!(
                scan.first_non_finite,
                c.iter().position(|v| !v.is_finite()),
                "{c:?}"
            );
        }
    }

    #[test]
    fn estimated_rate_snaps_to_integer() {
        let t = times(1000, 200.0);
        let c = choose_rate(None, nominal(&t), t.len()).unwrap();
        assert_eq!(c.used, 200.0);
        assert!(c.message.unwrap().contains("estimated"));
        let t = times(1000, 12.34);
        let c = choose_rate(None, nominal(&t), t.len()).unwrap();
        // Absolute times near 1.6e9 s carry ~2.4e-7 s of rounding each.
        const ABS_TIME_REL_TOL: f64 = 1e-7;
        assert!(
            ((c.used - 12.34) / 12.34).abs() < ABS_TIME_REL_TOL,
            "{}",
            c.used
        );
    }

    #[test]
    fn given_rate_warns_only_beyond_one_percent() {
        let t = times(1000, 200.0);
        let m = nominal(&t);
        assert!(choose_rate(Some(200.0), m, 1000).unwrap().finding.is_none());
        let c = choose_rate(Some(201.0), m, 1000).unwrap();
        assert!(c.finding.is_none());
        assert_eq!(c.section, 201.0);
        let c = choose_rate(Some(100.0), m, 1000).unwrap();
        assert_eq!(c.used, 100.0);
        assert_eq!(c.section, 200.0);
        assert!(c.finding.is_some());
    }

    #[test]
    fn no_rate_without_span() {
        assert!(matches!(
            choose_rate(None, nominal(&[1.0]), 1),
            Err(Error::NoRate { .. })
        ));
        assert!(matches!(
            choose_rate(None, nominal(&[1.0, 1.0]), 2),
            Err(Error::NoRate { .. })
        ));
        assert!(matches!(
            choose_rate(Some(-1.0), None, 0),
            Err(Error::BadRate(_))
        ));
        assert_eq!(choose_rate(Some(50.0), None, 0).unwrap().used, 50.0);
    }
}
