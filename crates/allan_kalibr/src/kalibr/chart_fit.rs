//! `gen_chart.m`'s fixed-slope fits (docs/upstream/kalibr_allan.md §3.1, checklist items 9–13).
//!
//! The three axis deviations are averaged per τ, the curve minimum `minid` splits the grid,
//! a −½ line is fitted on grid indices `1 … minid−50` and a +½ line on `minid+50 … 2000`
//! (mean of the per-point log intercepts over every finite point, duplicates included), and
//! the lines are read at the grid τ nearest to 1 s and 3 s. Empty windows give NaN, as
//! MATLAB's `mean([])` does.

use std::hint::black_box;

/// `windowsize` of gen_chart.m: grid indices (not seconds) kept clear of the minimum.
pub const WINDOW_GAP: usize = 50;

/// Everything gen_chart computes for one sensor (indices are 1-based, as printed).
#[derive(Debug, Clone, PartialEq)]
pub struct ChartFit {
    /// `((sx + sy) + sz)/3` per grid point.
    pub sigavg: Vec<f64>,
    /// 1-based index of the NaN-ignoring minimum of `sigavg` (first if tied), if any.
    pub minid: Option<usize>,
    /// 1-based first index of the grid τ nearest to 1 s.
    pub tauid1: usize,
    /// The grid τ nearest to 1 s, s.
    pub tau_at1: f64,
    /// 1-based first index of the grid τ nearest to 3 s.
    pub tauid2: usize,
    /// The grid τ nearest to 3 s, s.
    pub tau_at2: f64,
    /// Intercept (natural log) of the −½ line; NaN when its window has no finite point.
    pub c1: f64,
    /// Intercept (natural log) of the +½ line; NaN when its window has no finite point.
    pub c2: f64,
    /// `tau_at1^(-1/2) * exp(c1)`: the white-noise density.
    pub white: f64,
    /// `tau_at2^(+1/2) * exp(c2)`: the bias random walk.
    pub bias: f64,
}

impl ChartFit {
    /// The −½ line `tau^(-1/2) * exp(c1)` at `tau` (the red line of the plot).
    pub(crate) fn h_fit1(&self, tau: f64) -> f64 {
        pow(tau, -0.5) * self.c1.exp()
    }
    /// The +½ line `tau^(1/2) * exp(c2)` at `tau` (the blue line of the plot).
    pub(crate) fn h_fit2(&self, tau: f64) -> f64 {
        pow(tau, 0.5) * self.c2.exp()
    }
}

/// glibc `pow` as Octave calls it for `tau.^(±0.5)`; `black_box` stops LLVM from turning
/// `pow(x, 0.5)` into `sqrt(x)` (equal almost always, but not guaranteed to the ulp).
fn pow(x: f64, y: f64) -> f64 {
    x.powf(black_box(y))
}

/// gen_chart(tau, sx, sy, sz) for one sensor. `tau` is `tau1` of the grid.
pub fn gen_chart(tau: &[f64], sx: &[f64], sy: &[f64], sz: &[f64]) -> ChartFit {
    let sigavg: Vec<f64> = (0..tau.len())
        .map(|i| ((sx[i] + sy[i]) + sz[i]) / 3.0)
        .collect();
    let minid = nan_min_first_index(&sigavg).map(|i| i + 1);
    let (tauid1, tau_at1) = nearest_first(tau, 1.0);
    let (tauid2, tau_at2) = nearest_first(tau, 3.0);
    let (c1, c2) = match minid {
        Some(minid) => {
            // 1-based `1 : minid-50` → 0-based `0 .. minid-50`.
            let w1 = 0..minid.saturating_sub(WINDOW_GAP);
            // 1-based `minid+50 : length` → 0-based `minid+49 .. length`.
            let w2 = (minid + WINDOW_GAP - 1).min(tau.len())..tau.len();
            (
                log_intercept(tau, &sigavg, w1, -0.5),
                log_intercept(tau, &sigavg, w2, 0.5),
            )
        }
        // min of an all-NaN curve is NaN and `find` is empty: both windows are empty.
        None => (f64::NAN, f64::NAN),
    };
    let white = pow(tau_at1, -0.5) * c1.exp();
    let bias = pow(tau_at2, 0.5) * c2.exp();
    ChartFit {
        sigavg,
        minid,
        tauid1: tauid1 + 1,
        tau_at1,
        tauid2: tauid2 + 1,
        tau_at2,
        c1,
        c2,
        white,
        bias,
    }
}

/// `mean(log(y ./ tau(keep).^slope))` over the finite points of `window`; NaN if none
/// (MATLAB `mean([])` = NaN, docs/upstream/kalibr_allan.md §3.1 "NaN cases", issues #12/#13).
fn log_intercept(tau: &[f64], sigavg: &[f64], window: std::ops::Range<usize>, slope: f64) -> f64 {
    let mut sum = 0.0;
    let mut count = 0usize;
    for i in window {
        if sigavg[i].is_finite() {
            sum += (sigavg[i] / pow(tau[i], slope)).ln();
            count += 1;
        }
    }
    if count == 0 {
        f64::NAN
    } else {
        sum / count as f64
    }
}

/// `find(v == min(v))` with MATLAB's NaN-skipping `min`; the first index (0-based).
fn nan_min_first_index(v: &[f64]) -> Option<usize> {
    let mut best: Option<usize> = None;
    for (i, &x) in v.iter().enumerate() {
        if x.is_nan() {
            continue;
        }
        match best {
            Some(b) if v[b] <= x => {}
            _ => best = Some(i),
        }
    }
    best
}

/// `find(abs(tau-t) == min(abs(tau-t)), 1)` and the τ there (0-based index).
fn nearest_first(tau: &[f64], target: f64) -> (usize, f64) {
    let dist: Vec<f64> = tau.iter().map(|&x| (x - target).abs()).collect();
    let i = nan_min_first_index(&dist).unwrap_or(0);
    (i, tau[i])
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Synthetic curves: log-log V shape, no NaN. Exact formulas → tolerance of a few ulp.
    const SYNTH_REL_TOL: f64 = 1e-12;

    fn v_curve(n: usize) -> (Vec<f64>, Vec<f64>) {
        let tau: Vec<f64> = (1..=n).map(|i| i as f64 * 0.01).collect();
        let s: Vec<f64> = tau
            .iter()
            .map(|&t| 0.02 * t.powf(-0.5) + 0.001 * t.powf(0.5))
            .collect();
        (tau, s)
    }

    #[test]
    fn first_index_ties_and_nan_skipping_min() {
        assert_eq!(
            nan_min_first_index(&[f64::NAN, 3.0, 1.0, 1.0, 2.0]),
            Some(2)
        );
        assert_eq!(nan_min_first_index(&[f64::NAN, f64::NAN]), None);
        assert_eq!(nearest_first(&[0.0, 0.5, 1.5, 2.0], 1.0), (1, 0.5));
    }

    #[test]
    fn pure_power_laws_recover_their_intercepts() {
        let (tau, _) = v_curve(2000);
        // −½ everywhere left, +½ right: a curve exactly a*tau^-1/2 up to the minimum at
        // index 1000 and b*tau^1/2 after it.
        let (a, b) = (0.03_f64, 0.0002_f64);
        let s: Vec<f64> = tau
            .iter()
            .enumerate()
            .map(|(i, &t)| {
                if i < 1000 {
                    a * t.powf(-0.5)
                } else {
                    b * t.powf(0.5)
                }
            })
            .collect();
        let f = gen_chart(&tau, &s, &s, &s);
        let minid = f.minid.unwrap();
        assert!(
            (f.c1.exp() - a).abs() / a < SYNTH_REL_TOL,
            "c1 {} vs ln a {}",
            f.c1,
            a.ln()
        );
        assert!(
            (f.c2.exp() - b).abs() / b < SYNTH_REL_TOL,
            "c2 {} vs ln b {}",
            f.c2,
            b.ln()
        );
        assert_eq!(f.tauid1, 100);
        assert_eq!(f.tauid2, 300);
        assert!(minid > 50 && minid + 50 <= 2000);
    }

    /// Mirrors kalibr_allan `9d38ea9` gen_chart.m, issues #12/#13: a minimum in the last 50
    /// grid points leaves `minid+50:end` empty and MATLAB's `mean([])` makes the random walk
    /// NaN (not Octave's behaviour, not an error).
    #[test]
    fn quirk_12_13_random_walk_nan_when_minimum_at_end() {
        let (tau, s) = v_curve(2000);
        let mut s = s;
        s[1980] = 1e-9; // force the minimum into the last 50 points
        let f = gen_chart(&tau, &s, &s, &s);
        assert_eq!(f.minid, Some(1981));
        assert!(f.c2.is_nan() && f.bias.is_nan());
        assert!(f.white.is_finite());
    }

    /// The white noise is NaN likewise when the minimum is within the first 50 points, or
    /// the left window holds only NaN (m = 0) points.
    #[test]
    fn quirk_12_13_white_noise_nan_when_window_all_nan() {
        let (tau, mut s) = v_curve(2000);
        for v in s.iter_mut().take(200) {
            *v = f64::NAN;
        }
        s[240] = 1e-9;
        let f = gen_chart(&tau, &s, &s, &s);
        assert!(f.c1.is_nan() && f.white.is_nan());
        assert!(f.bias.is_finite());
    }

    #[test]
    fn nan_in_one_axis_makes_average_nan() {
        let (tau, s) = v_curve(10);
        let mut sx = s.clone();
        sx[3] = f64::NAN;
        let f = gen_chart(&tau, &sx, &s, &s);
        assert!(f.sigavg[3].is_nan());
        assert_eq!(f.sigavg[4], ((s[4] + s[4]) + s[4]) / 3.0);
    }
}
