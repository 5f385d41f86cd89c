//! Loading the samples (a `.mat` with `data_imu`, or a `.bag` read through bag2mat exactly
//! as bagconvert does) and choosing the update rate that drives the τ grid.
//!
//! Upstream never looks at the timestamps except to count them (kalibr_allan.md §2): the
//! user types the rate into the script. Here the rate is estimated from the timestamps when
//! not given, and a given rate that disagrees with them by more than 1 % gets a warning.

use std::path::Path;

use crate::error::Error;

/// A relative disagreement between the given and the measured rate above which we warn.
pub const RATE_WARN_REL: f64 = 0.01;
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
    pub notes: Vec<String>,
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
    pub fn from_series(s: bag2mat::ImuSeries, time: bag2mat::TimeColumn) -> Self {
        let topic = s.topic.clone();
        let notes = s.notes.clone();
        let [t, ax, ay, az, wx, wy, wz] = bag2mat::convert::into_data_imu(s, time).columns;
        ImuData {
            t,
            axes: [ax, ay, az, wx, wy, wz],
            topic: Some(topic),
            notes,
        }
    }

    /// Samples `range` only.
    pub fn slice(&self, range: std::ops::Range<usize>) -> ImuData {
        ImuData {
            t: self.t[range.clone()].to_vec(),
            axes: std::array::from_fn(|a| self.axes[a][range.clone()].to_vec()),
            topic: self.topic.clone(),
            notes: self.notes.clone(),
        }
    }

    /// Checks that every sample is finite (a NaN would silently turn whole curves into NaN).
    pub fn check_finite(&self) -> Result<(), Error> {
        self.scan_checked().map(|_| ())
    }

    /// One pass over each column (the six in parallel): fails like [`ImuData::check_finite`]
    /// on the first non-finite sample (axes in order), else returns what [`value_problem`]
    /// needs, so the run reads the columns once for both checks.
    pub fn scan_checked(&self) -> Result<[ColumnScan; 6], Error> {
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
    let opts = bag2mat::formats::InputOptions::default();
    Ok(load_all(path, &sel, bag2mat::TimeColumn::Record, quiet, &opts)?.remove(0))
}

/// Reads the selected topics of a bag or log in one pass, or the one `data_imu` of a `.mat`.
pub fn load_all(
    path: &Path,
    sel: &bag2mat::TopicSelector,
    time: bag2mat::TimeColumn,
    quiet: bool,
    opts: &bag2mat::formats::InputOptions,
) -> Result<Vec<ImuData>, Error> {
    if is_mat(path) {
        return Ok(vec![load_mat(path)?]);
    }
    match bag2mat::series::read_imu_topics_with(path, sel, &bag2mat::ReadOptions { quiet }, opts) {
        Ok(r) => {
            for s in &r.series {
                s.require_both_sensors()?;
            }
            Ok(r.series
                .into_iter()
                .map(|s| ImuData::from_series(s, time))
                .collect())
        }
        Err(bag2mat::Error::NotABag { .. }) => Err(Error::UnknownInput {
            path: path.to_path_buf(),
        }),
        Err(e) => Err(e.into()),
    }
}

fn load_mat(path: &Path) -> Result<ImuData, Error> {
    let d = bag2mat::mat::read_data_imu(path)?;
    let [t, ax, ay, az, wx, wy, wz] = d.columns;
    Ok(ImuData {
        t,
        axes: [ax, ay, az, wx, wy, wz],
        topic: None,
        notes: Vec::new(),
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
    pub fn of(col: &[f64]) -> ColumnScan {
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
    pub fn problem(&self, axis: &str) -> Option<(bool, String)> {
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
    /// Hz, drives the τ grid.
    pub used: f64,
    /// `(N-1)/(t_N - t_1)` of the analysed stretch, when the timestamps allow it.
    pub measured: Option<f64>,
    /// An info line (estimated) or a warning (disagreement), for stderr.
    pub message: Option<String>,
}

/// Mean rate of the timestamps, `(N-1)/(t_N - t_1)`; None without a positive span. The run
/// first cuts a record with gaps or rate changes to its longest continuous stretch
/// (bag2mat::timing, median period), so a gap never lowers this; on continuous data the
/// mean is exact where a median of intervals of large absolute times is quantised.
pub fn measured_rate(t: &[f64]) -> Option<f64> {
    let (first, last) = (t.first()?, t.last()?);
    let span = last - first;
    (t.len() >= 2 && span.is_finite() && span > 0.0).then(|| (t.len() - 1) as f64 / span)
}

/// Chooses the update rate: the given one (warning if the timestamps disagree by more than
/// [`RATE_WARN_REL`]) or the measured one, snapped to an integer within [`RATE_SNAP_REL`].
pub fn choose_rate(given: Option<f64>, t: &[f64]) -> Result<RateChoice, Error> {
    let measured = measured_rate(t);
    match given {
        Some(rate) => {
            if !(rate.is_finite() && rate > 0.0) {
                return Err(Error::BadRate(rate));
            }
            let message = measured
                .filter(|m| ((m - rate) / rate).abs() > RATE_WARN_REL)
                .map(|m| {
                    format!(
                        "warning: --update-rate {rate} Hz but the timestamps give {m:.4} Hz \
                     ({:+.2} %); the grid uses {rate} Hz as upstream would",
                        (m - rate) / rate * 100.0
                    )
                });
            Ok(RateChoice {
                used: rate,
                measured,
                message,
            })
        }
        None => {
            let m = measured.ok_or_else(|| Error::NoRate {
                what: format!("{} samples, no positive time span", t.len()),
            })?;
            let r = m.round();
            let used = if r >= 1.0 && ((m - r) / r).abs() <= RATE_SNAP_REL {
                r
            } else {
                m
            };
            let message = Some(format!(
                "update rate: {used} Hz (estimated from the timestamps: {m:.4} Hz; pass --update-rate to override)"
            ));
            Ok(RateChoice {
                used,
                measured,
                message,
            })
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn times(n: usize, rate: f64) -> Vec<f64> {
        (0..n).map(|i| 1.6e9 + i as f64 / rate).collect()
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
        let c = choose_rate(None, &times(1000, 200.0)).unwrap();
        assert_eq!(c.used, 200.0);
        assert!(c.message.unwrap().contains("estimated"));
        let c = choose_rate(None, &times(1000, 12.34)).unwrap();
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
        assert!(choose_rate(Some(200.0), &t).unwrap().message.is_none());
        assert!(choose_rate(Some(201.0), &t).unwrap().message.is_none());
        let c = choose_rate(Some(100.0), &t).unwrap();
        assert_eq!(c.used, 100.0);
        assert!(c.message.unwrap().starts_with("warning"));
    }

    #[test]
    fn no_rate_without_span() {
        assert!(matches!(
            choose_rate(None, &[1.0]),
            Err(Error::NoRate { .. })
        ));
        assert!(matches!(
            choose_rate(None, &[1.0, 1.0]),
            Err(Error::NoRate { .. })
        ));
        assert!(matches!(
            choose_rate(Some(-1.0), &[]),
            Err(Error::BadRate(_))
        ));
        assert_eq!(choose_rate(Some(50.0), &[]).unwrap().used, 50.0);
    }
}
