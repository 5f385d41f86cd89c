//! Gaps and rate changes in a series of timestamps — the one place the workspace finds
//! them: `bag2mat info` prints them, and both analysers check their samples with
//! [`analyse`] before an Allan variance that assumes one constant rate.
//!
//! The period is the **median** interval (a 1 h gap in a 60 s recording leaves it at the
//! sensor's period, where span/N would be 60× too long). A gap is an interval longer than
//! [`GAP_FACTOR`] median periods. A rate change is a block of [`RATE_BLOCK`] intervals whose
//! median period differs from the series' by more than [`RATE_CHANGE_REL`]. The series is
//! cut at every gap and rate change into [`Segment`]s of one constant rate.

/// An interval longer than this many median periods is a gap (a dropped message or two is
/// not: 3 periods is two messages lost in a row).
pub const GAP_FACTOR: f64 = 3.0;
/// Intervals per block when looking for a rate change.
pub const RATE_BLOCK: usize = 256;
/// A block whose median period differs from the series' by more than this (relative) is at
/// another rate (IMU clocks drift by ppm, not percent).
pub const RATE_CHANGE_REL: f64 = 0.05;
/// Gaps adding up to more than this fraction of the span make an Allan variance over the
/// whole series meaningless: the τ grid assumes samples at one rate with none missing.
pub const MAX_GAP_FRACTION: f64 = 0.01;

/// One gap.
#[derive(Debug, Clone, PartialEq)]
pub struct Gap {
    /// Index of the sample before the gap.
    pub after: usize,
    /// Time of that sample (as given).
    pub at: f64,
    /// Length of the interval, s.
    pub length: f64,
}

/// A stretch of samples at one rate with no gap: indices `start..end`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Segment {
    /// First index.
    pub start: usize,
    /// One past the last index.
    pub end: usize,
    /// Its median period, s.
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
    /// Median interval, s (`None` with fewer than two samples).
    pub median_period: Option<f64>,
    /// Last minus first time, s.
    pub span: f64,
    /// Every gap, in order.
    pub gaps: Vec<Gap>,
    /// Indices where the rate changes (start of a block at another rate).
    pub rate_changes: Vec<usize>,
    /// The constant-rate, gap-free stretches, in order.
    pub segments: Vec<Segment>,
}

impl Timing {
    /// Total time in gaps beyond one period each, s.
    pub fn gap_time(&self) -> f64 {
        let p = self.median_period.unwrap_or(0.0);
        self.gaps.iter().map(|g| g.length - p).sum()
    }

    /// True when an Allan variance over the whole series is meaningful: no rate change and
    /// gaps adding up to at most [`MAX_GAP_FRACTION`] of the span.
    pub fn is_continuous(&self) -> bool {
        self.rate_changes.is_empty()
            && (self.span <= 0.0 || self.gap_time() <= MAX_GAP_FRACTION * self.span)
    }

    /// The longest segment.
    pub fn longest(&self) -> Option<Segment> {
        self.segments.iter().copied().max_by_key(|s| s.len())
    }

    /// One line per finding (at most a few gaps listed), for warnings.
    pub fn describe(&self) -> String {
        let mut s = String::new();
        if let Some(p) = self.median_period {
            s.push_str(&format!(
                "median period {p:.6} s ({:.4} Hz)",
                if p > 0.0 { 1.0 / p } else { f64::NAN }
            ));
        }
        if !self.gaps.is_empty() {
            let longest = self.gaps.iter().map(|g| g.length).fold(0.0, f64::max);
            s.push_str(&format!(
                "; {} gap(s) totalling {:.3} s over a {:.3} s span (longest {:.3} s",
                self.gaps.len(),
                self.gap_time(),
                self.span,
                longest
            ));
            for g in self.gaps.iter().take(3) {
                s.push_str(&format!(", {:.3} s after sample {}", g.length, g.after));
            }
            s.push(')');
        }
        if !self.rate_changes.is_empty() {
            s.push_str(&format!(
                "; the rate changes near sample(s) {:?}",
                &self.rate_changes[..self.rate_changes.len().min(5)]
            ));
        }
        s
    }
}

/// The element at `len / 2` of `v` in sorted order (selection in linear time: the 4 h bag's
/// 2.9 M intervals would otherwise be sorted three times per call).
fn median(v: &mut [f64]) -> f64 {
    let k = v.len() / 2;
    *v.select_nth_unstable_by(k, f64::total_cmp).1
}

/// Finds the gaps, rate changes and constant-rate segments of `t` (seconds, in order).
pub fn analyse(t: &[f64]) -> Timing {
    let n = t.len();
    let mut out = Timing {
        n,
        median_period: None,
        span: if n > 1 { t[n - 1] - t[0] } else { 0.0 },
        gaps: Vec::new(),
        rate_changes: Vec::new(),
        segments: Vec::new(),
    };
    if n < 2 {
        if n == 1 {
            out.segments.push(Segment {
                start: 0,
                end: 1,
                period: 0.0,
            });
        }
        return out;
    }
    let d: Vec<f64> = t.windows(2).map(|w| w[1] - w[0]).collect();
    let period = median(&mut d.clone());
    out.median_period = Some(period);
    // Cuts: after a gap, and at the start of a block at another rate.
    let mut cuts: Vec<usize> = Vec::new();
    if period > 0.0 {
        for (i, &x) in d.iter().enumerate() {
            if x > GAP_FACTOR * period {
                out.gaps.push(Gap {
                    after: i,
                    at: t[i],
                    length: x,
                });
                cuts.push(i + 1);
            }
        }
        let mut prev_other = false;
        for (b, block) in d.chunks(RATE_BLOCK).enumerate() {
            if block.len() < RATE_BLOCK / 4 {
                continue;
            }
            let m = median(&mut block.to_vec());
            let other = ((m - period) / period).abs() > RATE_CHANGE_REL;
            if other != prev_other {
                out.rate_changes.push(b * RATE_BLOCK);
                cuts.push(b * RATE_BLOCK);
            }
            prev_other = other;
        }
    }
    cuts.sort_unstable();
    cuts.dedup();
    let mut start = 0;
    if cuts.is_empty() {
        out.segments.push(Segment {
            start: 0,
            end: n,
            period,
        });
        return out;
    }
    for c in cuts.into_iter().chain([n]) {
        if c > start {
            let mut seg: Vec<f64> = d[start..c.saturating_sub(1).max(start)].to_vec();
            out.segments.push(Segment {
                start,
                end: c,
                period: if seg.is_empty() {
                    period
                } else {
                    median(&mut seg)
                },
            });
            start = c;
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn median_by_selection_is_the_middle_of_the_sorted_values() {
        // A deterministic scramble (multiplicative hash) of values with ties, odd and even
        // lengths, checked against the obvious sort.
        for n in [1usize, 2, 3, 10, 1001, 4096] {
            let v: Vec<f64> = (0..n as u64)
                .map(|i| ((i.wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 40) % 97) as f64 * 0.25)
                .collect();
            let mut sorted = v.clone();
            sorted.sort_by(f64::total_cmp);
            assert_eq!(median(&mut v.clone()), sorted[n / 2], "n = {n}");
        }
    }

    #[test]
    fn a_one_hour_gap_in_a_minute_is_found_and_the_rate_is_the_median() {
        // 60 s at 200 Hz, then a 1 h gap, then 60 s more.
        let mut t: Vec<f64> = (0..12_000).map(|i| i as f64 * 0.005).collect();
        t.extend((0..12_000).map(|i| 3660.0 + i as f64 * 0.005));
        let tm = analyse(&t);
        assert!((tm.median_period.unwrap() - 0.005).abs() < 1e-12);
        assert_eq!(tm.gaps.len(), 1);
        assert_eq!(tm.gaps[0].after, 11_999);
        assert!(!tm.is_continuous());
        assert_eq!(tm.segments.len(), 2);
        assert_eq!(tm.longest().unwrap().len(), 12_000);
    }

    #[test]
    fn a_rate_change_splits_the_series() {
        let mut t: Vec<f64> = (0..5000).map(|i| i as f64 * 0.005).collect();
        let t0 = t[4999];
        t.extend((1..5000).map(|i| t0 + i as f64 * 0.01));
        let tm = analyse(&t);
        assert!(!tm.rate_changes.is_empty());
        assert!(!tm.is_continuous());
        assert!(tm.segments.len() >= 2);
    }

    #[test]
    fn a_steady_series_with_a_dropped_message_is_continuous() {
        let mut t: Vec<f64> = (0..10_000).map(|i| i as f64 * 0.01).collect();
        t.remove(5000);
        let tm = analyse(&t);
        assert!(tm.gaps.is_empty() && tm.rate_changes.is_empty());
        assert!(tm.is_continuous());
        assert_eq!(tm.segments.len(), 1);
    }
}
