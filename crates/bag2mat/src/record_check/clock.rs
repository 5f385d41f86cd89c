//! The clock side of the record: rows the container did not promise, samples stored twice,
//! a clock that steps back, the gap rule's findings ([`crate::timing`]) and the header clock
//! against the record clock.

use super::{Finding, Keep, Kind, Level, Record, secs, stamp_text};
use crate::series::TimeColumn;
use crate::timing::{self, GAP_FACTOR, Segment, Timing};

/// The header and record clocks may disagree by this much (relative) before it is said:
/// both tick at the sensor's rate, whatever their offset and latency.
pub const CLOCK_MISMATCH_REL: f64 = 0.01;

/// A row is compared with at most this many rows of its stamp before it (a copy follows its
/// original once the rows are sorted; a clock stuck at one value must not cost n²).
const DUPLICATE_LOOKBACK: usize = 8;

/// Gaps and steps listed at most (the counts are always given).
pub const MAX_LISTED: usize = 3;

fn clock_name(t: TimeColumn) -> &'static str {
    match t {
        TimeColumn::Record => "the record time",
        TimeColumn::Header => "header.stamp",
    }
}

fn other_column(t: TimeColumn) -> TimeColumn {
    match t {
        TimeColumn::Record => TimeColumn::Header,
        TimeColumn::Header => TimeColumn::Record,
    }
}

/// More rows delivered than the container promises (a chunk or a storage file read twice).
pub fn extra_rows(r: &Record<'_>) -> Option<Finding> {
    let (promised, delivered) = r.promised?;
    (delivered > promised).then(|| {
        Finding::new(
            Level::Warning,
            Kind::ExtraRows,
            format!(
                "the container promises {promised} messages on this topic and {delivered} rows were read: {} more than it holds (a chunk or storage file stored or listed twice?); samples stored twice are dropped from the analysis",
                delivered - promised
            ),
        )
        .counted((delivered - promised) as f64, "rows")
    })
}

/// Rows equal to an earlier row of the same stamp (stamps, other clock and every value):
/// dropped from `keep` (which holds every row on entry).
pub fn duplicates(r: &Record<'_>, keep: &mut Keep) -> Option<Finding> {
    let n = r.t.len();
    let same = |i: usize, j: usize| {
        r.other.is_none_or(|o| o[i] == o[j])
            && r.values.iter().all(|v| v[i].to_bits() == v[j].to_bits())
    };
    let mut dup: Vec<usize> = Vec::new();
    let mut group = 0; // first row of the current run of equal stamps
    for i in 1..n {
        if r.t[i] != r.t[i - 1] {
            group = i;
        } else if (group.max(i.saturating_sub(DUPLICATE_LOOKBACK))..i).any(|j| same(i, j)) {
            dup.push(i);
        }
    }
    let t0 = r.t.first().copied().unwrap_or(0);
    let &first = dup.first()?;
    let drop: std::collections::HashSet<usize> = dup.iter().copied().collect();
    keep.retain(n, |i| !drop.contains(&i));
    Some(
            Finding::new(
                Level::Warning,
                Kind::Duplicates,
                format!(
                    "{} samples are stored twice (same stamps and values; the first at t = {:.3} s, sample {first}): dropped from the analysis ({:.2} % of {n} rows; left in, they would raise the rate and every N)",
                    dup.len(),
                    secs(r.t[first] - t0),
                    100.0 * dup.len() as f64 / n as f64
                ),
            )
            .at(secs(r.t[first] - t0), first)
            .counted(dup.len() as f64, "samples"),
    )
}

/// Consecutive samples differ by more than this many times what every second sample does
/// (medians of |x_i − x_{i−1}| and |x_i − x_{i−2}|), on [`INTERLEAVED_AXES`] axes or more:
/// the rows alternate between two sensors. One sensor's white noise gives 1, a low-pass
/// filtered one less; two IMUs whose biases differ by a few σ of their noise give the bias
/// difference over the noise.
pub const INTERLEAVED_RATIO: f64 = 3.0;
/// Axes that must alternate ([`INTERLEAVED_RATIO`]) for two sensors (one axis alone may be a
/// vibration at half the rate).
pub const INTERLEAVED_AXES: usize = 3;
/// Differences the alternation is measured on at most (evenly spread).
const INTERLEAVED_SAMPLES: usize = 1 << 16;

/// Rows that alternate between two sensors (two IMUs interleaved in one record, as a CSV
/// with a sensor column holds them): the axes on which consecutive samples differ by more
/// than [`INTERLEAVED_RATIO`] times what every second sample does. The corrected analysis
/// is refused: the two sensors' samples read as one at twice the rate make every term
/// meaningless.
pub fn interleaved(r: &Record<'_>, keep: &Keep) -> Option<Finding> {
    let n = keep.len(r.t.len());
    if n < 16 {
        return None;
    }
    let stride = (n / INTERLEAVED_SAMPLES).max(1);
    let median = |mut v: Vec<f64>| {
        let k = v.len() / 2;
        *v.select_nth_unstable_by(k, f64::total_cmp).1
    };
    let mut axes: Vec<(usize, f64)> = Vec::new();
    for (a, v) in r.values.iter().enumerate() {
        let x = |i: usize| v[keep.row(i)];
        let idx: Vec<usize> = (2..n).step_by(stride).collect();
        let d1: Vec<f64> = idx.iter().map(|&i| (x(i) - x(i - 1)).abs()).collect();
        let d2: Vec<f64> = idx.iter().map(|&i| (x(i) - x(i - 2)).abs()).collect();
        let (m1, m2) = (median(d1), median(d2));
        if !(m1.is_finite() && m2.is_finite()) || m1 == 0.0 {
            continue;
        }
        let ratio = if m2 > 0.0 { m1 / m2 } else { f64::INFINITY };
        if ratio > INTERLEAVED_RATIO {
            axes.push((a, ratio));
        }
    }
    if axes.len() < INTERLEAVED_AXES {
        return None;
    }
    let list: Vec<String> = axes
        .iter()
        .map(|&(a, q)| format!("{} {q:.0}×", super::Axis::ALL[a].label()))
        .collect();
    Some(
        Finding::new(
            Level::Refusal,
            Kind::Interleaved,
            format!(
                "the rows alternate between two sensors: consecutive samples differ by far more than every second sample does ({}) — two IMUs, each with its own bias, interleaved in one record (a log of several sensors, one row each in turn); analysed as one they are neither, at twice the rate: analyse one sensor's rows (a text log's sensor column: --sensor-id)",
                list.join(", ")
            ),
        )
        .counted(axes.len() as f64, "axes"),
    )
}

/// Kept rows (in row order) that carry the stamp of the kept row before them with other
/// values: kept, and said (checked after a clock step is cut, whose stretches may share
/// stamps). `two_sensors`: the rows alternate between two sensors ([`interleaved`]), which
/// is why, not the clock.
pub fn equal_stamps(r: &Record<'_>, keep: &Keep, two_sensors: bool) -> Option<Finding> {
    let n = keep.len(r.t.len());
    let equal: Vec<usize> = (1..n)
        .filter(|&i| r.t[keep.row(i)] == r.t[keep.row(i - 1)])
        .collect();
    let &first = equal.first()?;
    let t0 = r.t[keep.row(0)];
    Some(
            Finding::new(
                Level::Warning,
                Kind::EqualStamps,
                format!(
                    "{} samples carry the stamp of the sample before them with other values (the first at t = {:.3} s, sample {first}): kept; {}",
                    equal.len(),
                    secs(r.t[keep.row(first)] - t0),
                    if two_sensors {
                        "two sensors stamped alike (see 'two sensors')"
                    } else {
                        "the clock's resolution or the driver's stamping is coarser than the samples, so the rate from the stamps may be off"
                    }
                ),
            )
            .at(secs(r.t[keep.row(first)] - t0), first)
            .counted(equal.len() as f64, "samples"),
    )
}

/// A clock that steps back by more than [`GAP_FACTOR`] periods in the order the samples
/// arrived (their storage order, whichever clock is analysed): the samples are cut to the
/// longest consistent stretch instead of sorted (sorting would interleave the stretches and
/// double the apparent rate where they overlap).
pub fn steps(r: &Record<'_>, keep: &mut Keep) -> Option<Finding> {
    let n = r.t.len();
    if r.storage_order.is_none() && r.t.windows(2).all(|w| w[0] <= w[1]) {
        return None; // stored in time order: no step back
    }
    let mut order = keep.rows(n);
    if let Some(so) = r.storage_order {
        order.sort_by_key(|&i| so[i]);
    }
    if order.len() < 3 {
        return None;
    }
    let d: Vec<i64> = order.windows(2).map(|w| r.t[w[1]] - r.t[w[0]]).collect();
    let mut pos: Vec<i64> = d.iter().copied().filter(|&x| x > 0).collect();
    if pos.is_empty() {
        return None;
    }
    let k = pos.len() / 2;
    let p = *pos.select_nth_unstable(k).1;
    let limit = (GAP_FACTOR as i64).saturating_mul(p).saturating_neg();
    let steps: Vec<usize> = (0..d.len()).filter(|&j| d[j] < limit).collect();
    if steps.is_empty() {
        return None;
    }
    // stretches between the steps: [0, s0+1), [s0+1, s1+1), …
    let bounds: Vec<usize> = std::iter::once(0)
        .chain(steps.iter().map(|&j| j + 1))
        .chain([order.len()])
        .collect();
    let (a, b) = bounds
        .windows(2)
        .map(|w| (w[0], w[1]))
        .max_by_key(|(a, b)| b - a)
        .expect("two bounds");
    let largest = steps.iter().copied().min_by_key(|&j| d[j]).expect("a step");
    let list: Vec<String> = steps
        .iter()
        .take(MAX_LISTED)
        .map(|&j| {
            format!(
                "{:.3} s back after stored sample {j} (stamp {})",
                secs(-d[j]),
                stamp_text(r.t[order[j]])
            )
        })
        .collect();
    let mut rows: Vec<usize> = order[a..b].to_vec();
    rows.sort_unstable();
    let (lo, hi) = (
        rows.iter().map(|&i| r.t[i]).min().unwrap_or(0),
        rows.iter().map(|&i| r.t[i]).max().unwrap_or(0),
    );
    let kept = rows.len();
    let total = order.len();
    *keep = if kept == n {
        Keep::All
    } else {
        Keep::Rows(rows)
    };
    Some(
        Finding::new(
            Level::Warning,
            Kind::ClockStep,
            format!(
                "{} steps back {} time(s) in the order the samples were stored ({}{}): sorting would interleave the stretches, so only the longest consistent stretch is analysed: stored samples {a}..{b} ({kept} of {total}, stamps {} – {})",
                clock_name(r.time),
                steps.len(),
                list.join(", "),
                if steps.len() > MAX_LISTED { ", …" } else { "" },
                stamp_text(lo),
                stamp_text(hi)
            ),
        )
        .at(secs(r.t[order[largest + 1]] - lo), largest + 1)
        .sized(secs(-d[largest]), "s"),
    )
}

/// The gap rule's findings on stamps `t` (ns) with their analysis `tm`; `cut` is the
/// stretch analysed when the record is not continuous.
pub fn gaps(tm: &Timing, t: &[i64], cut: Option<Segment>) -> Vec<Finding> {
    let mut out = Vec::new();
    let rate = tm.nominal_rate().unwrap_or(f64::NAN);
    let cut_text = cut.map(|s| {
        format!(
            "not one continuous record: an Allan variance across it would be meaningless, so only its longest continuous stretch is analysed: samples {}..{} ({} of {}, t = {:.3} – {:.3} s)",
            s.start,
            s.end,
            s.len(),
            tm.n,
            secs(t[s.start] - t[0]),
            secs(t[s.end - 1] - t[0])
        )
    });
    if tm.missing > 0 {
        out.push(missing_samples(tm, t, cut_text.as_deref(), rate));
    }
    if let Some(&first) = tm.rate_changes.first() {
        out.push(rate_changes(tm, t, first, cut_text.as_deref()));
    }
    out
}

/// The finding on samples missing from the record: how many, the longest gap, the long
/// ones, and whether the record is bridged or cut.
fn missing_samples(tm: &Timing, t: &[i64], cut_text: Option<&str>, rate: f64) -> Finding {
    let longest = tm.longest_gap().expect("a gap");
    let long: Vec<_> = tm.gaps.iter().filter(|g| g.missing >= GAP_FACTOR).collect();
    let long_text = if long.is_empty() {
        String::new()
    } else {
        format!(
            "; {} long gap(s) of {GAP_FACTOR} or more samples in a row, totalling {:.3} s ({:.2} % of the span)",
            long.len(),
            tm.long_gap_time(),
            100.0 * tm.long_gap_time() / tm.span.max(f64::MIN_POSITIVE)
        )
    };
    let what = match (cut_text, tm.rate_changes.is_empty()) {
        (Some(c), true) => c.to_string(),
        (Some(_), false) => "cut with the rate change below".to_string(),
        (None, _) => bridged_text(tm, rate),
    };
    Finding::new(
        Level::Warning,
        Kind::Gaps,
        format!(
            "{} samples missing ({:.2} % of the {} the span holds at the nominal {rate:.4} Hz) in {} gap(s); the longest {:.4} s ({} missing) at t = {:.3} s, after sample {} (stamp {}){long_text}; {what}",
            tm.missing,
            100.0 * tm.missing_fraction(),
            tm.n as u64 + tm.missing,
            tm.gaps.len(),
            longest.length,
            longest.missing,
            longest.at,
            longest.after,
            stamp_text(t[longest.after])
        ),
    )
    .at(longest.at, longest.after)
    .counted(tm.missing as f64, "samples missing")
}

/// Bridged gaps (none longer than [`GAP_FACTOR`] samples, and the long ones within
/// [`timing::MAX_GAP_FRACTION`]): the samples that arrived are analysed as consecutive, so
/// the analysis' time axis is the samples' count over the rate, not the record's span. Said
/// with both lengths; past [`timing::MAX_GAP_FRACTION`] of the samples, with what it does
/// to the terms (white noise N is unchanged; a drift term sees τ shortened by the share
/// lost, so K reads up to √(span / analysed) high).
fn bridged_text(tm: &Timing, rate: f64) -> String {
    let analysed = tm.n.saturating_sub(1) as f64 / rate;
    let f = tm.missing_fraction();
    let base = format!(
        "bridged: the {} samples that arrived are analysed as one record at the nominal {rate:.4} Hz (lost samples do not change the rate of those that arrived)",
        tm.n
    );
    if f <= timing::MAX_GAP_FRACTION || !analysed.is_finite() || analysed <= 0.0 {
        return base;
    }
    format!(
        "{base}, so the analysis' time axis is {analysed:.1} s of samples for a {:.1} s record: {:.0} % of the time is gone from it; N is unchanged, but every τ beyond one sample is shorter than the time it spanned, so a random walk K or ramp R reads up to ×{:.2} high",
        tm.span,
        100.0 * f,
        (tm.span / analysed).sqrt()
    )
}

/// The finding on the sampling rate changing (the first ones listed), at the first change.
fn rate_changes(tm: &Timing, t: &[i64], first: usize, cut_text: Option<&str>) -> Finding {
    let list: Vec<String> = tm
        .rate_changes
        .iter()
        .take(MAX_LISTED)
        .map(|&i| format!("sample {i} (t = {:.3} s)", secs(t[i] - t[0])))
        .collect();
    Finding::new(
        Level::Warning,
        Kind::RateChange,
        format!(
            "the sampling rate changes {} time(s) (off the median {:.4} Hz by more than {:.0} %, at {}{}); {}",
            tm.rate_changes.len(),
            1e9 / tm.median_period_ns.unwrap_or(1) as f64,
            100.0 * timing::RATE_CHANGE_REL,
            list.join(", "),
            if tm.rate_changes.len() > MAX_LISTED {
                ", …"
            } else {
                ""
            },
            cut_text.unwrap_or_default()
        ),
    )
    .at(secs(t[first] - t[0]), first)
}

/// The other clock over the same samples: both must tick at the sensor's rate.
pub fn cross_check(time: TimeColumn, rate: f64, other: &[i64]) -> Option<Finding> {
    let r2 = timing::nominal_rate(other)?;
    let ratio = r2 / rate;
    ((ratio - 1.0).abs() > CLOCK_MISMATCH_REL).then(|| {
        let (this, that) = (clock_name(time), clock_name(other_column(time)));
        Finding::new(
            Level::Warning,
            Kind::ClockMismatch,
            format!(
                "{that} advances at {r2:.4} Hz and {this} (analysed) at {rate:.4} Hz over the same samples ({ratio:.3}×): one of the two clocks is wrong; if {that} is right, every N here is off by ×{:.3} and every K by ×{:.3} (--time {} analyses it)",
                ratio.sqrt(),
                ratio.sqrt().recip(),
                other_column(time).name()
            ),
        )
        .sized(r2, "Hz")
    })
}
