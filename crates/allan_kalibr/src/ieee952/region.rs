//! IEEE Std 952 region readings: the classic graphical rules, each with its own interval.
//! They are printed beside the fit as a cross-check and replace it when the full model does
//! not describe the curve ("no reliable fit").
//!
//! Rules (on the points of the usable range, local slopes from log-log central differences
//! on the 2-per-octave fit grid):
//! * **N** — the −½ line at τ = 1 s. The white-noise points are those whose local slope is
//!   within [`SLOPE_TOL`] of −½, within an octave of the one nearest 1 s
//!   ([`white_near_1s`]); the line of slope −½ fitted to them (least squares in log: the
//!   geometric mean of σ(τ)·√τ) is read at τ = 1 s. Its 95 % interval is that of the
//!   region's most precise point, scaled to the line (neighbouring overlapping points are
//!   strongly correlated, so averaging them narrows it little). Every term adds to the Allan
//!   variance, so this reading is biased high by whatever else contributes there.
//! * **B** — the flat floor / 0.664: the minimum of the curve when its local slope is within
//!   [`SLOPE_TOL`] of 0, B = σ_min/√(2 ln2/π), interval likewise. (The minimum of noisy
//!   points is biased low.)
//! * **K** — the +½ line at τ = 3 s: the long-τ points whose local slope is within
//!   [`SLOPE_TOL_K`] of +½; K = σ(τ)·√(3/τ) at the region's most precise point (shortest τ)
//!   — a reading only where the record shows the rise: a point of the region whose lower
//!   95 % limit lies above the floor's upper one. A slope of +½ among the last, noisiest
//!   points of a short record is as often chance (issue 41.2: 0.29 s of batch samples gave
//!   a "random walk"); then K is bounded instead.
//! * A term whose region is absent (or not shown) gets a 95 % upper bound instead: every
//!   term's Allan deviation is at most the curve's, jointly over the points ([`upper_bound`]:
//!   Bonferroni, not the least of the pointwise limits).

use super::{Point, ci};

/// Half-width of the slope window that defines the white-noise and floor regions.
pub const SLOPE_TOL: f64 = 0.1;
/// Half-width for the +½ region (fewer, noisier points at long τ).
pub const SLOPE_TOL_K: f64 = 0.15;
/// √(2 ln2/π): ADEV floor of bias instability B is this times B.
pub const B_FLOOR_FACTOR: f64 = 0.664_282_471_410_191_1;

/// How a reading was made.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ReadingKind {
    /// From the term's region, with its 95 % interval.
    Line,
    /// No region: a 95 % upper bound (value = lo = 0, hi = the bound).
    UpperBound,
}

/// One region reading.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Reading {
    /// The value (term unit; 0 for an upper bound).
    pub value: f64,
    /// 95 % lower end.
    pub lo: f64,
    /// 95 % upper end.
    pub hi: f64,
    /// τ of the point it was read from (NaN for a bound over all points).
    pub tau: f64,
    /// Line or bound.
    pub kind: ReadingKind,
}

/// The three readings of one curve.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Readings {
    /// White noise N (−½ line at 1 s).
    pub n: Option<Reading>,
    /// Bias instability B (floor / 0.664).
    pub b: Option<Reading>,
    /// Random walk K (+½ line at 3 s).
    pub k: Option<Reading>,
}

/// Local log-log slopes at each point (central differences; one-sided at the ends).
pub(crate) fn local_slopes(tau: &[f64], adev: &[f64]) -> Vec<f64> {
    let n = tau.len();
    (0..n)
        .map(|i| {
            let (a, b) = match (i.checked_sub(1), i + 1 < n) {
                (Some(a), true) => (a, i + 1),
                (None, true) => (i, i + 1),
                (Some(a), false) => (a, i),
                (None, false) => return f64::NAN,
            };
            (adev[b] / adev[a]).ln() / (tau[b] / tau[a]).ln()
        })
        .collect()
}

/// The white-noise points the N reading uses: those whose local slope is within
/// [`SLOPE_TOL`] of −½ (`is_white`) within [`N_WINDOW`] of the one nearest τ = 1 s. Near 1 s,
/// not all of them: a curve can fall like white noise again beyond a Gauss–Markov bump, and
/// a long run that bends slowly (a filtered sensor) would be read at its middle rather than
/// at 1 s.
pub(crate) fn white_near_1s(tau: &[f64], is_white: &[bool]) -> Vec<usize> {
    let Some(centre) = (0..tau.len())
        .filter(|&i| is_white[i])
        .min_by(|&a, &b| tau[a].ln().abs().total_cmp(&tau[b].ln().abs()))
    else {
        return Vec::new();
    };
    (0..tau.len())
        .filter(|&i| is_white[i] && (tau[i] / tau[centre]).ln().abs() <= N_WINDOW.ln() + 1e-9)
        .collect()
}

/// Half-width (a factor of τ) of the window of white-noise points the N reading averages.
pub const N_WINDOW: f64 = 2.0;

/// The largest value of a term the curve allows at 95 %, jointly over `points`: every
/// term's Allan variance is at most the curve's (where no filter acts: callers leave out the
/// band-limited short τ), and the k points all lie below their one-sided upper limits at
/// 1 − 0.05/k together with probability 95 % at least (Bonferroni) — so the term is at most
/// min over them of that limit over `per_unit`(τ), the term's Allan deviation per unit of
/// its value (∞ when no point bounds it). The minimum of each point's own 95 % limit is not
/// a bound: the least of k pointwise limits lies below the truth far more often than one
/// time in twenty (issue 40.2). The region readings' bounds and each term's whole-record
/// bound come from here.
pub(crate) fn upper_bound<'a>(
    points: impl IntoIterator<Item = &'a Point>,
    per_unit: impl Fn(f64) -> f64,
) -> f64 {
    let pts: Vec<&Point> = points
        .into_iter()
        .filter(|p| p.edf.is_finite() && p.edf > 0.0 && p.adev > 0.0)
        .collect();
    if pts.is_empty() {
        return f64::INFINITY;
    }
    let level = 1.0 - BOUND_RISK / pts.len() as f64;
    pts.iter()
        .filter_map(|p| ci::chi2_upper(p.adev, p.edf, level).map(|hi| hi / per_unit(p.tau)))
        .filter(|v| v.is_finite() && *v >= 0.0)
        .fold(f64::INFINITY, f64::min)
}

/// The risk of [`upper_bound`] over all its points together (a 95 % bound).
pub const BOUND_RISK: f64 = 0.05;

/// The N reading from the white-noise points `white` of `pts` (their τ and deviations
/// `tau`, `adev`): the −½ line through them, read at 1 s, with the relative interval of the
/// most precise of them (the narrowest).
fn white_line(pts: &[&Point], tau: &[f64], adev: &[f64], white: &[usize]) -> Reading {
    let line = (white
        .iter()
        .map(|&i| (adev[i] * tau[i].sqrt()).ln())
        .sum::<f64>()
        / white.len() as f64)
        .exp();
    // the most precise point: the narrowest relative interval
    let best = white
        .iter()
        .copied()
        .min_by(|&a, &b| (pts[a].hi95 / pts[a].lo95).total_cmp(&(pts[b].hi95 / pts[b].lo95)))
        .unwrap_or(white[0]);
    Reading {
        value: line,
        lo: line * pts[best].lo95 / adev[best],
        hi: line * pts[best].hi95 / adev[best],
        tau: 1.0,
        kind: ReadingKind::Line,
    }
}

/// Readings from `points` (the usable range of one curve, ascending τ, on the fit grid) with
/// their 95 % bounds `lo95`/`hi95` (NaN when the sample count is unknown: then the readings
/// carry no interval).
pub(crate) fn read(points: &[Point]) -> Readings {
    let pts: Vec<&Point> = points
        .iter()
        .filter(|p| p.adev > 0.0 && p.adev.is_finite())
        .collect();
    if pts.len() < 2 {
        return Readings {
            n: None,
            b: None,
            k: None,
        };
    }
    let tau: Vec<f64> = pts.iter().map(|p| p.tau).collect();
    let adev: Vec<f64> = pts.iter().map(|p| p.adev).collect();
    let slope = local_slopes(&tau, &adev);
    let scaled = |i: usize, f: f64| Reading {
        value: adev[i] * f,
        lo: pts[i].lo95 * f,
        hi: pts[i].hi95 * f,
        tau: tau[i],
        kind: ReadingKind::Line,
    };
    let bound = |per_unit: &dyn Fn(f64) -> f64| -> Option<Reading> {
        let hi = upper_bound(pts.iter().copied(), per_unit);
        hi.is_finite().then_some(Reading {
            value: 0.0,
            lo: 0.0,
            hi,
            tau: f64::NAN,
            kind: ReadingKind::UpperBound,
        })
    };
    let imin = (0..pts.len())
        .min_by(|&a, &b| adev[a].total_cmp(&adev[b]))
        .unwrap_or(0);
    // N: the −½ line through the white points near 1 s, read at 1 s
    let is_white: Vec<bool> = slope.iter().map(|s| (s + 0.5).abs() <= SLOPE_TOL).collect();
    let white = white_near_1s(&tau, &is_white);
    let n = if white.is_empty() {
        bound(&|t: f64| 1.0 / t.sqrt())
    } else {
        Some(white_line(&pts, &tau, &adev, &white))
    };
    // B: the minimum, when flat there
    let b = if slope[imin].abs() <= SLOPE_TOL {
        Some(scaled(imin, 1.0 / B_FLOOR_FACTOR))
    } else {
        bound(&|_| B_FLOOR_FACTOR)
    };
    // K: the +½ region at the long end (contiguous from the last point), its shortest τ
    let mut first_k = None;
    for i in (0..pts.len()).rev() {
        if (slope[i] - 0.5).abs() <= SLOPE_TOL_K {
            first_k = Some(i);
        } else {
            break;
        }
    }
    // …where the rise above the floor is beyond both points' bands somewhere in the region
    let shown = |i: usize| (i..pts.len()).any(|r| pts[r].lo95 > pts[imin].hi95);
    let k = first_k
        .filter(|&i| i > imin && shown(i))
        .map(|i| scaled(i, (3.0 / tau[i]).sqrt()))
        .or_else(|| bound(&|t: f64| (t / 3.0).sqrt()));
    Readings { n, b, k }
}
