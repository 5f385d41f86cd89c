//! The gap rule: missing samples, gaps and rate changes in a series of time stamps, in
//! integer nanoseconds — the one place the workspace finds them (`bag2mat info` and both
//! analysers, through [`crate::record_check`], which also judges the clock and the values).
//!
//! * The **median period** is the median of the positive intervals (of a quarter million
//!   of them, evenly spread, in a longer record; a 1 h gap in a 60 s recording, or 2 % of
//!   duplicated stamps, leave it at the sensor's period).
//! * Each interval is a whole number of periods `k = round(d / median)` (integer arithmetic:
//!   an interval of exactly 2.5 periods is 3 the same way in every tool); `k − 1` samples are
//!   missing behind it — unless the samples around it give the time back: a receive time
//!   that jitters (a late sample then an early one, or a burst after a stall) puts a long
//!   interval beside short ones, and no sample is missing. So each long interval is checked
//!   against the [`JITTER_WINDOW`] samples on either side ([`confirmed_missing`]: the samples
//!   after it must stay late by whole periods against the samples before it), and only what
//!   stays missing counts. A **gap** is an interval with at least one sample missing; the
//!   missing count is exact (2 % single-sample dropouts of 360,000 samples are 7,200 missing
//!   in 7,200 gaps), and receive-time jitter of up to half a period is no gap.
//! * The **nominal period** is the span over the number of periods it holds: the intervals
//!   between the samples that arrived and the samples confirmed missing. It is the sensor's
//!   sampling period, which lost samples do not change (the mean interval does), nor
//!   receive-time jitter (rounding each jittered interval to whole periods does: a 400 Hz
//!   queue read 401.1 Hz that way). Equal stamps are samples here; samples stored twice are
//!   dropped before the gap rule ([`crate::record_check`]).
//! * A **rate change** is a block of [`RATE_BLOCK`] intervals whose median differs from the
//!   series' by more than [`RATE_CHANGE_REL`]; the change is placed at the exact interval
//!   where the period changes (not at the block boundary).
//! * The series is **one continuous record** unless the rate changes or the gaps longer than
//!   [`GAP_FACTOR`] periods ("long gaps") add up to more than [`MAX_GAP_FRACTION`] of the
//!   span; otherwise it is cut at every rate change and long gap into [`Segment`]s, each at
//!   one rate. Shorter gaps (one or two samples lost in a row, as USB IMUs lose them) are
//!   bridged: the samples around them are analysed as consecutive at the nominal period.

/// A gap longer than this many nominal periods (more than two samples lost in a row) is a
/// "long gap": it may break the record (see [`MAX_GAP_FRACTION`]).
pub const GAP_FACTOR: u64 = 3;
/// Samples on either side of a long interval that may give its time back (receive-time
/// jitter, a burst after a stall of up to this many samples) before it counts as a gap.
pub const JITTER_WINDOW: usize = 32;
/// Intervals per block when looking for a rate change.
pub const RATE_BLOCK: usize = 256;
/// A block whose median period differs from the series' by more than this (relative) is at
/// another rate (IMU clocks drift by ppm, not percent).
pub const RATE_CHANGE_REL: f64 = 0.05;
/// Long gaps adding up to more than this fraction of the span make an Allan variance over
/// the whole series meaningless: the τ grid assumes samples at one rate with none missing.
pub const MAX_GAP_FRACTION: f64 = 0.01;

const NS: f64 = 1e-9;

/// One gap: an interval with at least one sample missing.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Gap {
    /// Index of the sample before the gap.
    pub after: usize,
    /// Its time from the first sample, s.
    pub at: f64,
    /// Length of the interval, s.
    pub length: f64,
    /// Samples missing in it (periods in the interval − 1).
    pub missing: u64,
}

/// A stretch of samples at one rate: indices `start..end`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Segment {
    /// First index.
    pub start: usize,
    /// One past the last index.
    pub end: usize,
    /// Its nominal period (span / periods in it), s.
    pub period: f64,
}

impl Segment {
    /// Number of samples.
    pub fn len(&self) -> usize {
        self.end - self.start
    }

    /// True when empty.
    pub fn is_empty(&self) -> bool {
        self.end == self.start
    }
}

/// What [`analyse`] found.
#[derive(Debug, Clone, PartialEq)]
pub struct Timing {
    /// Samples.
    pub n: usize,
    /// Median positive interval, ns (`None` without one).
    pub median_period_ns: Option<i64>,
    /// Nominal period of the whole series (span / its periods: intervals and samples
    /// confirmed missing), s; `None` without a period.
    pub nominal_period: Option<f64>,
    /// Last minus first time, s.
    pub span: f64,
    /// Every gap, in order.
    pub gaps: Vec<Gap>,
    /// Samples missing in all the gaps.
    pub missing: u64,
    /// Intervals of zero or negative length (equal or reversed stamps).
    pub not_increasing: u64,
    /// Indices where the rate changes (the first sample at the other rate).
    pub rate_changes: Vec<usize>,
    /// The stretches to analyse apart, in order: the whole series when it is one continuous
    /// record, else cut at every rate change and long gap.
    pub segments: Vec<Segment>,
}

impl Timing {
    /// Total time in long gaps (beyond one period each), s.
    pub fn long_gap_time(&self) -> f64 {
        let p = self.nominal_period.unwrap_or(0.0);
        self.gaps
            .iter()
            .filter(|g| g.missing >= GAP_FACTOR)
            .map(|g| g.length - p)
            .sum()
    }

    /// Missing samples as a fraction of the samples the span should hold.
    pub fn missing_fraction(&self) -> f64 {
        let expected = self.n as f64 + self.missing as f64;
        if expected > 0.0 {
            self.missing as f64 / expected
        } else {
            0.0
        }
    }

    /// True when an Allan variance over the whole series is meaningful: no rate change and
    /// long gaps adding up to at most `MAX_GAP_FRACTION` of the span.
    pub fn is_continuous(&self) -> bool {
        self.rate_changes.is_empty()
            && (self.span <= 0.0 || self.long_gap_time() <= MAX_GAP_FRACTION * self.span)
    }

    /// The longest segment.
    pub fn longest(&self) -> Option<Segment> {
        self.segments.iter().copied().max_by_key(|s| s.len())
    }

    /// The longest gap (the first of equals).
    pub fn longest_gap(&self) -> Option<Gap> {
        self.gaps
            .iter()
            .copied()
            .reduce(|a, b| if b.length > a.length { b } else { a })
    }

    /// Nominal rate of the whole series, Hz.
    pub fn nominal_rate(&self) -> Option<f64> {
        self.nominal_period.filter(|p| *p > 0.0).map(|p| 1.0 / p)
    }
}

/// The element at `len / 2` of `v` in sorted order (selection in linear time).
fn median(v: &mut [i64]) -> i64 {
    let k = v.len() / 2;
    *v.select_nth_unstable(k).1
}

/// Intervals a median period is taken over at most, evenly spread (it rounds each interval to
/// whole periods; the median of a quarter million intervals is the median of millions to
/// within their jitter, and costs no copy of a 4 h record).
const MEDIAN_INTERVALS: usize = 1 << 18;

/// Median of the positive values of `d` (of at most [`MEDIAN_INTERVALS`] of them, evenly
/// spread), `None` without one.
fn median_positive(d: &[i64]) -> Option<i64> {
    let stride = d.len().div_ceil(MEDIAN_INTERVALS).max(1);
    let mut pos: Vec<i64> = d
        .iter()
        .step_by(stride)
        .copied()
        .filter(|&x| x > 0)
        .collect();
    if pos.is_empty() && stride > 1 {
        pos = d.iter().copied().filter(|&x| x > 0).collect();
    }
    (!pos.is_empty()).then(|| median(&mut pos))
}

/// Whole periods in an interval of `d` ns at median period `p` ns: `round(d / p)` with halves
/// up, in integers; 0 for an interval that is not positive.
pub fn periods(d: i64, p: i64) -> u64 {
    if d <= 0 || p <= 0 {
        return 0;
    }
    if d < i64::MAX / 4 && p < i64::MAX / 4 {
        return ((2 * d + p) / (2 * p)) as u64;
    }
    let (d, p) = (d as i128, p as i128);
    ((2 * d + p) / (2 * p)) as u64
}

/// The sample where the rate changes near the boundary `b` between two blocks of medians
/// `pa` (before) and `pb` (after): the `c` that minimises Σ_{i<c} |d_i − pa| + Σ_{i≥c}
/// |d_i − pb| over the two blocks around `b` (exact on a clean change).
fn refine_change(d: &[i64], b: usize, pa: i64, pb: i64) -> usize {
    let lo = b.saturating_sub(RATE_BLOCK);
    let hi = (b + RATE_BLOCK).min(d.len());
    let cost_b: i128 = d[lo..hi]
        .iter()
        .map(|&x| (x as i128 - pb as i128).abs())
        .sum();
    let (mut best, mut best_c) = (cost_b, lo);
    let mut cost = cost_b;
    for (i, &x) in d.iter().enumerate().take(hi).skip(lo) {
        cost += (x as i128 - pa as i128).abs() - (x as i128 - pb as i128).abs();
        if cost < best {
            best = cost;
            best_c = i + 1;
        }
    }
    best_c
}

/// Finds the gaps, rate changes and segments of `t` (ns, in the order analysed).
pub fn analyse(t: &[i64]) -> Timing {
    let n = t.len();
    let mut out = Timing {
        n,
        median_period_ns: None,
        nominal_period: None,
        span: if n > 1 {
            (t[n - 1] - t[0]) as f64 * NS
        } else {
            0.0
        },
        gaps: Vec::new(),
        missing: 0,
        not_increasing: 0,
        rate_changes: Vec::new(),
        segments: Vec::new(),
    };
    let d: Vec<i64> = t.windows(2).map(|w| w[1] - w[0]).collect();
    out.not_increasing = d.iter().filter(|&&x| x <= 0).count() as u64;
    let Some(p) = median_positive(&d) else {
        if n > 0 {
            out.segments.push(Segment {
                start: 0,
                end: n,
                period: 0.0,
            });
        }
        return out;
    };
    out.median_period_ns = Some(p);
    out.rate_changes = rate_changes(&d, p, n);
    let long_cuts = out.count_gaps(t, &d, p);
    let mut cuts: Vec<usize> = if out.is_continuous() {
        Vec::new()
    } else {
        out.rate_changes.iter().copied().chain(long_cuts).collect()
    };
    cuts.sort_unstable();
    cuts.dedup();
    if cuts.is_empty() {
        out.segments.push(Segment {
            start: 0,
            end: n,
            period: out.nominal_period.unwrap_or(0.0),
        });
        return out;
    }
    let mut start = 0;
    for c in cuts.into_iter().chain([n]) {
        if c > start {
            out.segments.push(Segment {
                start,
                end: c,
                period: segment_period(t, start, c, &out.gaps),
            });
            start = c;
        }
    }
    out
}

/// Where the rate changes in a series of `n` stamps with intervals `d` and median
/// interval `p`: blocks of [`RATE_BLOCK`] intervals at another rate, each change placed
/// exactly ([`refine_change`]).
fn rate_changes(d: &[i64], p: i64, n: usize) -> Vec<usize> {
    let mut changes: Vec<usize> = Vec::new();
    let mut prev: Option<(bool, i64)> = None;
    let mut buf: Vec<i64> = Vec::with_capacity(RATE_BLOCK);
    for (b, block) in d.chunks(RATE_BLOCK).enumerate() {
        if block.len() < RATE_BLOCK / 4 {
            continue;
        }
        buf.clear();
        buf.extend(block.iter().copied().filter(|&x| x > 0));
        if buf.is_empty() {
            continue;
        }
        let m = median(&mut buf);
        let other = ((m - p) as f64 / p as f64).abs() > RATE_CHANGE_REL;
        match prev {
            Some((was, pm)) if was != other => {
                changes.push(refine_change(d, b * RATE_BLOCK, pm, m));
            }
            None if other => changes.push(0),
            _ => {}
        }
        prev = Some((other, m));
    }
    changes.retain(|&c| c > 0 && c < n);
    changes.dedup();
    changes
}

impl Timing {
    /// Within each rate segment (cut at `self.rate_changes`), the intervals `d` of `t` in
    /// whole periods of the segment's own median (`p` with one rate throughout): the gaps,
    /// the samples missing and the nominal period. Returns where gaps longer than
    /// [`GAP_FACTOR`] periods cut the series.
    fn count_gaps(&mut self, t: &[i64], d: &[i64], p: i64) -> Vec<usize> {
        let one_rate = self.rate_changes.is_empty();
        let bounds: Vec<usize> = std::iter::once(0)
            .chain(self.rate_changes.iter().copied())
            .chain([self.n])
            .collect();
        let mut long_cuts: Vec<usize> = Vec::new();
        let mut total_periods = 0u64;
        for w in bounds.windows(2) {
            let (a, b) = (w[0], w[1]);
            // the intervals inside [a, b): a .. b-1
            let inner = &d[a..b.saturating_sub(1).max(a)];
            // one rate throughout: the series' median (no second selection)
            let ps = if one_rate {
                p
            } else {
                median_positive(inner).unwrap_or(p)
            };
            // most intervals are one period: no division for them
            let k_of = |x: i64| {
                if x <= 0 {
                    0 // equal or reversed stamps hold no period
                } else if x.saturating_sub(ps).saturating_abs().saturating_mul(2) < ps {
                    1
                } else {
                    periods(x, ps)
                }
            };
            // the grid the missing samples are confirmed on: the stretch's span over its
            // whole periods (the median of a jittery or lossy record is off by more than
            // the lateness of a few dozen samples can bear)
            let whole: u64 = inner.iter().map(|&x| k_of(x)).sum();
            // the stretch's periods: each sample that arrived, and each confirmed missing
            // (added below); Σ k over jittered intervals counts some twice and others not
            total_periods += inner.len() as u64;
            let grid = if whole > 0 && b > a + 1 {
                (t[b - 1] - t[a]) as f64 / whole as f64
            } else {
                ps as f64
            };
            let mut from = a;
            for (j, &x) in inner.iter().enumerate() {
                let k = k_of(x);
                if k < 2 {
                    continue;
                }
                let i = a + j;
                let missing = confirmed_missing(&t[..b], from, i, grid).min(k - 1);
                if missing >= 1 {
                    self.gaps.push(Gap {
                        after: i,
                        at: (t[i] - t[0]) as f64 * NS,
                        length: x as f64 * NS,
                        missing,
                    });
                    self.missing += missing;
                    total_periods += missing;
                    if missing + 1 > GAP_FACTOR {
                        long_cuts.push(i + 1);
                    }
                    from = i + 1;
                }
            }
        }
        if total_periods > 0 {
            self.nominal_period = Some(self.span / total_periods as f64);
        }
        long_cuts
    }
}

/// The samples missing behind interval `i` (between `t[i]` and `t[i + 1]`) of stamps `t`
/// (ns) at period `p` ns, as the samples around it confirm them. Each stamp's lateness
/// against the period grid, `t_j − j·p`: a sample lost leaves every later stamp a period
/// late, while a receive delay makes single stamps late and is gone a few samples on. So
/// the earliest of the [`JITTER_WINDOW`] samples after the interval is compared with the
/// earliest of those before it (from `from` on: not across an earlier gap), in whole
/// periods — the lower envelope of the stamps, which a delay, a late sample followed by
/// on-time ones or a burst after a stall leave in place. Half a period less a thousandth
/// counts as one, so that exactly half is one from every clock's rounding.
pub(crate) fn confirmed_missing(t: &[i64], from: usize, i: usize, p: f64) -> u64 {
    let late = |j: usize| (t[j] - t[i]) as f64 - (j as f64 - i as f64) * p;
    let before = (from.max(i.saturating_sub(JITTER_WINDOW))..=i)
        .map(late)
        .fold(f64::INFINITY, f64::min);
    let after = (i + 1..(i + 2 + JITTER_WINDOW).min(t.len()))
        .map(late)
        .fold(f64::INFINITY, f64::min);
    let x = (after - before) / p - 0.5 + 1e-3;
    if x > 0.0 { x.ceil() as u64 } else { 0 }
}

/// The nominal rate of `t` (ns, in order), Hz: [`analyse`]'s (the cross-check of a second
/// clock, a text log's time unit).
pub fn nominal_rate(t: &[i64]) -> Option<f64> {
    analyse(t).nominal_rate()
}

/// The nominal period of the segment `start..end` of `t`, s: its span over its periods, the
/// intervals between its samples and the samples confirmed missing in them (`gaps`); 0 for
/// fewer than two samples.
fn segment_period(t: &[i64], start: usize, end: usize, gaps: &[Gap]) -> f64 {
    if end < start + 2 {
        return 0.0;
    }
    let missing: u64 = gaps
        .iter()
        .filter(|g| g.after >= start && g.after + 1 < end)
        .map(|g| g.missing)
        .sum();
    let periods = (end - start - 1) as u64 + missing;
    (t[end - 1] - t[start]) as f64 * NS / periods as f64
}

/// Nanoseconds of each time (ROS time, exact).
pub fn ns_of_times(t: &[crate::RosTime]) -> Vec<i64> {
    t.iter().map(|x| x.as_nanos() as i64).collect()
}

/// Nanoseconds of each time given in seconds (a `.mat`'s column): the first rounded, the
/// others from their difference to it, so the intervals keep the resolution the seconds
/// have (a product with 1e9 of absolute times near 1.7e9 s would round each to 256 ns).
pub fn ns_of_seconds(t: &[f64]) -> Vec<i64> {
    // within ±(2^62 − 1) ns (146 years): any two differ by less than an i64 holds
    const LIMIT: i64 = (1 << 62) - 1;
    let ns = |x: f64| ((x * 1e9).round() as i64).clamp(-LIMIT, LIMIT);
    let t0 = t.first().copied().unwrap_or(0.0);
    let t0_ns = ns(t0);
    t.iter()
        .map(|&x| t0_ns.saturating_add(ns(x - t0)).clamp(-LIMIT, LIMIT))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    const P: i64 = 5_000_000; // 200 Hz
    const T0: i64 = 1_700_000_000_000_000_000;

    fn grid(n: usize) -> Vec<i64> {
        (0..n as i64).map(|i| T0 + i * P).collect()
    }

    #[test]
    fn median_by_selection_is_the_middle_of_the_sorted_values() {
        for n in [1usize, 2, 3, 10, 1001, 4096] {
            let v: Vec<i64> = (0..n as u64)
                .map(|i| ((i.wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 40) % 97) as i64)
                .collect();
            let mut sorted = v.clone();
            sorted.sort();
            assert_eq!(median(&mut v.clone()), sorted[n / 2], "n = {n}");
        }
    }

    #[test]
    fn periods_round_half_up_in_integers() {
        assert_eq!(periods(P, P), 1);
        assert_eq!(periods(3 * P, P), 3);
        assert_eq!(periods(3 * P / 2, P), 2);
        assert_eq!(periods(3 * P / 2 - 1, P), 1);
        assert_eq!(periods(0, P), 0);
        assert_eq!(periods(-P, P), 0);
    }

    #[test]
    fn a_one_hour_gap_in_a_minute_is_found_and_the_rate_is_the_median() {
        let mut t = grid(12_000);
        t.extend((0..12_000).map(|i| T0 + 3_660_000_000_000 + i * P));
        let tm = analyse(&t);
        assert_eq!(tm.median_period_ns, Some(P));
        assert_eq!(tm.gaps.len(), 1);
        assert_eq!(tm.gaps[0].after, 11_999);
        assert!(!tm.is_continuous());
        assert_eq!(tm.segments.len(), 2);
        assert_eq!(tm.longest().unwrap().len(), 12_000);
        assert!((tm.segments[0].period - 0.005).abs() < 1e-15);
    }

    #[test]
    fn a_rate_change_is_cut_at_the_exact_sample() {
        // 200 Hz for 5000 samples (not a multiple of the block), then 100 Hz
        for first in [5000usize, 5120, 5133] {
            let mut t = grid(first);
            let t0 = t[first - 1];
            t.extend((1..5000).map(|i| t0 + i * 2 * P));
            let tm = analyse(&t);
            assert_eq!(tm.rate_changes, vec![first - 1], "first {first}");
            assert!(!tm.is_continuous());
            assert_eq!(tm.segments.len(), 2);
            assert_eq!(tm.segments[1].start, first - 1);
            assert!((tm.segments[1].period - 0.01).abs() < 1e-15);
            // the other-rate stretch is not a string of gaps
            assert!(tm.gaps.is_empty(), "{:?}", &tm.gaps[..3.min(tm.gaps.len())]);
        }
    }

    #[test]
    fn every_clock_counts_the_same_gaps() {
        // intervals of exactly 2.5 and 3 periods at absolute times: the same gaps from the
        // stamps (ns) and from the seconds a .mat holds (before: 3 periods was a gap in one
        // tool and not in the other, float seconds against integer nanoseconds)
        let mut t = grid(20_000);
        for (at, by) in [(5000usize, P / 2), (9000, P), (15_000, 2 * P)] {
            for x in &mut t[at..] {
                *x += by;
            }
        }
        let secs: Vec<f64> = t
            .iter()
            .map(|&x| crate::RosTime::from_nanos(x as u64).to_sec())
            .collect();
        let a = analyse(&t);
        let b = analyse(&ns_of_seconds(&secs));
        let missing = |tm: &Timing| tm.gaps.iter().map(|g| g.missing).collect::<Vec<_>>();
        // 1.5 periods round to 2 (one missing), 2 to 2, 3 to 3
        assert_eq!(missing(&a), vec![1, 1, 2]);
        assert_eq!(missing(&b), missing(&a));
        assert_eq!(a.missing, 4);
        assert_eq!(b.missing, a.missing);
    }

    #[test]
    fn a_steady_series_with_a_dropped_message_is_continuous() {
        let mut t = grid(10_000);
        t.remove(5000);
        let tm = analyse(&t);
        assert_eq!(tm.missing, 1);
        assert_eq!(tm.gaps.len(), 1);
        assert!(tm.rate_changes.is_empty());
        assert!(tm.is_continuous());
        assert_eq!(tm.segments.len(), 1);
        assert!((tm.nominal_period.unwrap() - 0.005).abs() < 1e-15);
    }

    #[test]
    fn lost_samples_leave_the_nominal_rate_alone() {
        let mut t = grid(300_000);
        for i in (1000..299_000).rev().step_by(97) {
            t.remove(i);
        }
        assert!((nominal_rate(&t).unwrap() - 200.0).abs() < 1e-9);
    }

    #[test]
    fn absurd_seconds_stay_comparable() {
        let t = ns_of_seconds(&[1e300, -1e300, f64::NAN, 0.0, f64::INFINITY]);
        let tm = analyse(&t);
        assert_eq!(tm.n, 5);
    }

    /// Receive times that jitter by up to half a period (a late sample then on-time ones,
    /// an exponential delay held in order as a queue delivers) lose no sample; real losses
    /// among the jitter are still counted exactly.
    #[test]
    fn receive_time_jitter_is_no_gap_and_real_losses_beside_it_still_count() {
        // SplitMix64, seeded: uniform delays in [0, P/2) and, for a queue, exponential ones
        let mut st = 0x41_7177_u64;
        let mut unit = || {
            st = st.wrapping_add(0x9E37_79B9_7F4A_7C15);
            let mut z = st;
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
        };
        const P400: i64 = 2_500_000; // 400 Hz
        let n = 40_000usize;
        let uniform: Vec<i64> = (0..n as i64)
            .map(|i| T0 + i * P400 + (unit() * P400 as f64 * 0.49) as i64)
            .collect();
        let mut queue: Vec<i64> = Vec::with_capacity(n);
        for i in 0..n as i64 {
            let d = (-unit().max(1e-12).ln() * 0.3e-3 * 1e9) as i64; // mean 0.3 ms
            let t = T0 + i * P400 + d;
            queue.push(queue.last().map_or(t, |&l: &i64| l.max(t)));
        }
        for (name, t) in [("uniform", &uniform), ("queue", &queue)] {
            let tm = analyse(t);
            assert_eq!((tm.missing, tm.gaps.len()), (0, 0), "{name}");
            assert!(tm.is_continuous(), "{name}");
            // a queue's equal receive times hold no period: its nominal rate is off by
            // less than a thousandth (the analysers snap a rate within 0.5 % of a whole Hz)
            const RATE_REL_TOL: f64 = 1e-3;
            let rate = tm.nominal_rate().unwrap();
            assert!(
                (rate / 400.0 - 1.0).abs() < RATE_REL_TOL,
                "{name}: {rate} Hz"
            );
            // 1 % of the samples lost, one at a time, among the same jitter
            let lossy: Vec<i64> = t
                .iter()
                .enumerate()
                .filter(|(i, _)| i % 100 != 37)
                .map(|(_, &x)| x)
                .collect();
            let tm = analyse(&lossy);
            assert_eq!(tm.missing, 400, "{name}");
            assert_eq!(tm.gaps.len(), 400, "{name}");
        }
    }

    /// A 400 Hz sensor read through a queue (an exponential receive delay of a quarter
    /// period on average, held in order: bursts of equal receive times after a stall) keeps
    /// its rate: the samples that arrived, and the ones confirmed missing, are its periods.
    /// Rounding each jittered interval to whole periods counted some twice and others not
    /// at all (401.1 Hz for a bag at 400 Hz; the analysers wrote `update_rate: 401.0`).
    #[test]
    fn a_queues_receive_times_keep_the_sensors_rate() {
        let mut st = 0x5157_0041_u64;
        let mut unit = || {
            st = st.wrapping_add(0x9E37_79B9_7F4A_7C15);
            let mut z = st;
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
        };
        const P400: i64 = 2_500_000;
        // the span's two ends are late by a receive delay each (a few ms at most) over 60 s
        const RATE_REL_TOL: f64 = 1e-4;
        for mean_ms in [0.3, 0.6, 1.0] {
            let mut t: Vec<i64> = Vec::with_capacity(24_000);
            for i in 0..24_000 {
                let d = (-unit().max(1e-12).ln() * mean_ms * 1e6) as i64;
                let x = T0 + i * P400 + d;
                t.push(t.last().map_or(x, |&l: &i64| l.max(x)));
            }
            let tm = analyse(&t);
            let rate = tm.nominal_rate().unwrap();
            assert!(
                (rate / 400.0 - 1.0).abs() < RATE_REL_TOL,
                "{mean_ms} ms: {rate} Hz"
            );
            // and with 1 % of the samples lost among the jitter
            let lossy: Vec<i64> = t
                .iter()
                .enumerate()
                .filter(|(i, _)| i % 100 != 37)
                .map(|(_, &x)| x)
                .collect();
            let rate = analyse(&lossy).nominal_rate().unwrap();
            assert!(
                (rate / 400.0 - 1.0).abs() < RATE_REL_TOL,
                "{mean_ms} ms, lossy: {rate} Hz"
            );
        }
    }

    #[test]
    fn equal_stamps_leave_the_median_alone_and_are_samples() {
        let mut t = grid(10_000);
        for i in (0..10_000).step_by(50).rev() {
            t.insert(i, t[i]);
        }
        let tm = analyse(&t);
        assert_eq!(tm.not_increasing, 200);
        assert_eq!(tm.missing, 0);
        assert_eq!(tm.median_period_ns, Some(P));
        // every stamp is a sample here (a coarse clock's, a queue's burst); samples stored
        // twice are dropped before the gap rule (record_check::clock::duplicates)
        let span = 9999.0 * 0.005;
        assert!((tm.nominal_period.unwrap() - span / 10_199.0).abs() < 1e-15);
    }
}
