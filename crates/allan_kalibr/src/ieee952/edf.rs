//! Equivalent degrees of freedom of an Allan variance estimate (Greenhall & Riley 2004).
//!
//! C. A. Greenhall and W. J. Riley, "Uncertainty of stability variances based on finite
//! differences", 35th PTTI meeting (2003/2004): for a power-law noise S_y ∝ f^α the variance
//! estimate σ̂² is approximated as σ²·χ²(ν)/ν with
//!
//! ```text
//! ν = M · sz(0)² / BasicSum,   BasicSum = sz(0)² + (1 − J/M)·sz(J/S)² + Σ_{j=1}^{J−1} 2(1 − j/M)·sz(j/S)²
//! sz(t) = 6 sx(t) − 4 sx(t−1) − 4 sx(t+1) + sx(t−2) + sx(t+2)          (d = 2, Allan)
//! sx(t) = F² (2 sw(t) − sw(t − 1/F) − sw(t + 1/F))
//! sw(t) = −|t|, t² ln|t|, |t|³, −t⁴ ln|t|, −|t|⁵   for α = 2, 1, 0, −1, −2
//! ```
//!
//! Unmodified variance: F = m. Overlapping: S = m; normal: S = 1. L = m/F + 2m,
//! M = 1 + ⌊S(N − L)/m⌋ (N phase points; M is the number of second differences), J = min(M, 3S).
//! This is the "direct BasicSum" form; the simpler Howe/Allan/Barnes EDF formulas miss
//! Stable32's bounds by more than 1 % for flicker PM, this one reproduces them.
//!
//! Numerics (ours, not in the paper):
//! * sx is a second difference with step 1/F = 1/m: evaluated literally it loses ~2·log10(m)
//!   digits. For |t|·F > [`TAYLOR_SWITCH`] it is evaluated from its Taylor series
//!   −(sw'' + h²sw''''/12 + h⁴sw⁽⁶⁾/360), h = 1/F, truncation (h/t)⁶ < 1e-10.
//! * The sum has J = 3m terms for the overlapping estimator: for J > [`DIRECT_MAX`] it is
//!   evaluated exactly within [`WINDOW`] terms of the singular points j = 0, S, 2S of sz and,
//!   in between, where the summand is smooth, by the Euler–Maclaurin form
//!   Σ_{j=a}^{b} g(j) ≈ ∫_a^b g + (g(a) + g(b))/2 + (g'(b) − g'(a))/12 with the integral by 8-point Gauss–Legendre
//!   on a grid graded geometrically away from the windows. Cost is O(log m) instead of
//!   O(m); the unit test bounds its error against the direct sum.

use super::oadev::Overlap;

/// |t|·F above which sx is taken from its Taylor series.
pub const TAYLOR_SWITCH: f64 = 50.0;
/// Largest J summed term by term.
pub const DIRECT_MAX: usize = 4096;
/// Half-width (in terms) of the exactly summed windows around the singular points.
pub const WINDOW: usize = 64;

/// Entries kept by the memo of [`greenhall_edf`] before it is cleared.
const MEMO_MAX: usize = 1 << 16;

/// Greenhall EDF of the Allan variance at cluster size `m` from `n_phase` phase points
/// (= rate samples + 1) for power-law noise `alpha` ∈ −2..=2. `None` for another α or when
/// there is no second difference. Memoised: the axes of an IMU share their grid and length,
/// and the declared-fit check asks for the same points again.
pub fn greenhall_edf(alpha: i32, m: usize, n_phase: usize, kind: Overlap) -> Option<f64> {
    use std::collections::HashMap;
    use std::sync::{Mutex, OnceLock};
    type Key = (i32, usize, usize, bool);
    static MEMO: OnceLock<Mutex<HashMap<Key, Option<f64>>>> = OnceLock::new();
    let key = (alpha, m, n_phase, kind == Overlap::Normal);
    let memo = MEMO.get_or_init(|| Mutex::new(HashMap::new()));
    if let Some(v) = memo.lock().ok().and_then(|g| g.get(&key).copied()) {
        return v;
    }
    let v = greenhall_edf_uncached(alpha, m, n_phase, kind);
    if let Ok(mut g) = memo.lock() {
        if g.len() >= MEMO_MAX {
            g.clear();
        }
        g.insert(key, v);
    }
    v
}

/// [`greenhall_edf`] without the memo.
fn greenhall_edf_uncached(alpha: i32, m: usize, n_phase: usize, kind: Overlap) -> Option<f64> {
    if !(-2..=2).contains(&alpha) || m == 0 {
        return None;
    }
    let f = m as f64;
    let s = match kind {
        Overlap::Overlapping => m,
        Overlap::Normal => 1,
    };
    let l = 1 + 2 * m; // m/F + m·d with F = m, d = 2
    if n_phase < l {
        return None;
    }
    let big_m = 1 + (s * (n_phase - l)) / m;
    let j = big_m.min(3 * s);
    let sw = Sw::new(alpha);
    let sz0 = sz(0.0, f, &sw);
    let sum = basic_sum(j, big_m, s, f, &sw);
    Some(big_m as f64 * sz0 * sz0 / sum)
}

/// BasicSum(J, M, S, F, α).
fn basic_sum(j: usize, big_m: usize, s: usize, f: f64, sw: &Sw) -> f64 {
    let mf = big_m as f64;
    let sf = s as f64;
    let sz0 = sz(0.0, f, sw);
    let last = sz(j as f64 / sf, f, sw);
    let head = sz0 * sz0 + (1.0 - j as f64 / mf) * last * last;
    let g = |jj: f64| 2.0 * (1.0 - jj / mf) * sz(jj / sf, f, sw).powi(2);
    if j <= DIRECT_MAX {
        return head + (1..j).map(|jj| g(jj as f64)).sum::<f64>();
    }
    // exact windows around j = 0, S, 2S (the singular points of sz), clipped to 1..=J−1
    let mut ranges: Vec<(usize, usize)> = Vec::new();
    for k in 0..3usize {
        let c = k * s;
        let lo = c.saturating_sub(WINDOW).max(1);
        let hi = (c + WINDOW).min(j - 1);
        if lo <= hi {
            ranges.push((lo, hi));
        }
    }
    ranges.sort_unstable();
    let mut merged: Vec<(usize, usize)> = Vec::new();
    for r in ranges {
        match merged.last_mut() {
            Some(last) if r.0 <= last.1 + 1 => last.1 = last.1.max(r.1),
            _ => merged.push(r),
        }
    }
    let mut total = head;
    let mut cursor = 1usize; // first index not yet accounted for
    for &(lo, hi) in &merged {
        if lo > cursor {
            total += smooth_sum(&g, cursor, lo - 1);
        }
        total += (lo..=hi).map(|jj| g(jj as f64)).sum::<f64>();
        cursor = hi + 1;
    }
    if cursor < j {
        total += smooth_sum(&g, cursor, j - 1);
    }
    total
}

/// Σ_{j=a}^{b} g(j) for a g smooth on [a, b] (Euler–Maclaurin, two corrections).
fn smooth_sum(g: &impl Fn(f64) -> f64, a: usize, b: usize) -> f64 {
    if b < a + 16 {
        return (a..=b).map(|jj| g(jj as f64)).sum();
    }
    let (af, bf) = (a as f64, b as f64);
    let half = 0.5 * (bf - af);
    // breakpoints graded geometrically from both ends: a + w·2^i and b − w·2^i
    let mut cuts = vec![af, bf, af + half];
    let mut w = 8.0;
    while w < half {
        cuts.push(af + w);
        cuts.push(bf - w);
        w *= 2.0;
    }
    cuts.sort_by(f64::total_cmp);
    cuts.dedup();
    let integral: f64 = cuts
        .windows(2)
        .map(|c| gauss_legendre8(g, c[0], c[1]))
        .sum();
    let d = |x: f64| g(x + 0.5) - g(x - 0.5); // g'(x), central difference
    integral + 0.5 * (g(af) + g(bf)) + (d(bf) - d(af)) / 12.0
}

/// 8-point Gauss–Legendre on [a, b].
fn gauss_legendre8(g: &impl Fn(f64) -> f64, a: f64, b: f64) -> f64 {
    const X: [f64; 4] = [
        0.183_434_642_495_649_8,
        0.525_532_409_916_329,
        0.796_666_477_413_626_7,
        0.960_289_856_497_536_3,
    ];
    const W: [f64; 4] = [
        0.362_683_783_378_362,
        0.313_706_645_877_887_3,
        0.222_381_034_453_374_5,
        0.101_228_536_290_376_3,
    ];
    let c = 0.5 * (a + b);
    let h = 0.5 * (b - a);
    let mut s = 0.0;
    for i in 0..4 {
        s += W[i] * (g(c - h * X[i]) + g(c + h * X[i]));
    }
    s * h
}

/// The kernel sw(t) of one noise type: sign · |t|^p (odd p) or sign · t^p ln|t| (even p).
struct Sw {
    p: i32,
    log: bool,
    sign: f64,
}

impl Sw {
    fn new(alpha: i32) -> Sw {
        match alpha {
            2 => Sw {
                p: 1,
                log: false,
                sign: -1.0,
            },
            1 => Sw {
                p: 2,
                log: true,
                sign: 1.0,
            },
            0 => Sw {
                p: 3,
                log: false,
                sign: 1.0,
            },
            -1 => Sw {
                p: 4,
                log: true,
                sign: -1.0,
            },
            _ => Sw {
                p: 5,
                log: false,
                sign: -1.0,
            },
        }
    }

    fn value(&self, t: f64) -> f64 {
        if t == 0.0 {
            return 0.0;
        }
        let a = t.abs();
        let v = if self.log {
            a.powi(self.p) * a.ln()
        } else {
            a.powi(self.p)
        };
        self.sign * v
    }

    /// k-th derivative (k even ≥ 2) at t ≠ 0.
    fn deriv(&self, k: i32, t: f64) -> f64 {
        let a = t.abs();
        let p = self.p;
        let falling = |k: i32| (0..k).map(|i| (p - i) as f64).product::<f64>();
        let v = if self.log {
            if k <= p {
                // d^k t^p ln|t| = p!/(p−k)! t^{p−k} (ln|t| + H_p − H_{p−k}); p − k even here
                let h = |n: i32| (1..=n).map(|i| 1.0 / i as f64).sum::<f64>();
                falling(k) * a.powi(p - k) * (a.ln() + h(p) - h(p - k))
            } else {
                // d^k t^p ln|t| = p! (−1)^{k−p−1} (k−p−1)! t^{p−k}; k − p even ⇒ t^{p−k} = |t|^{p−k}
                let pf = falling(p);
                let q = (1..k - p).map(|i| i as f64).product::<f64>();
                let sgn = if (k - p - 1) % 2 == 0 { 1.0 } else { -1.0 };
                pf * sgn * q * a.powi(p - k)
            }
        } else if k <= p {
            falling(k) * a.powi(p - k) // even k: sign(t)^k = 1
        } else {
            0.0
        };
        self.sign * v
    }
}

/// sx(t) = F²(2 sw(t) − sw(t − 1/F) − sw(t + 1/F)).
fn sx(t: f64, f: f64, sw: &Sw) -> f64 {
    if t.abs() * f > TAYLOR_SWITCH {
        let h2 = 1.0 / (f * f);
        -(sw.deriv(2, t) + h2 * sw.deriv(4, t) / 12.0 + h2 * h2 * sw.deriv(6, t) / 360.0)
    } else {
        let h = 1.0 / f;
        f * f * (2.0 * sw.value(t) - sw.value(t - h) - sw.value(t + h))
    }
}

/// sz(t) for d = 2.
fn sz(t: f64, f: f64, sw: &Sw) -> f64 {
    6.0 * sx(t, f, sw) - 4.0 * sx(t - 1.0, f, sw) - 4.0 * sx(t + 1.0, f, sw)
        + sx(t - 2.0, f, sw)
        + sx(t + 2.0, f, sw)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The windowed Gauss–Legendre BasicSum against the term-by-term sum.
    const APPROX_REL_TOL: f64 = 1e-6;
    /// Taylor branch of sx against the literal second difference at moderate F where the latter
    /// still has ~10 good digits.
    const TAYLOR_REL_TOL: f64 = 1e-7;

    fn direct_edf(alpha: i32, m: usize, n_phase: usize) -> f64 {
        let f = m as f64;
        let s = m;
        let big_m = 1 + (s * (n_phase - 1 - 2 * m)) / m;
        let j = big_m.min(3 * s);
        let sw = Sw::new(alpha);
        let sz0 = sz(0.0, f, &sw);
        let mf = big_m as f64;
        let mut sum = sz0 * sz0 + (1.0 - j as f64 / mf) * sz(j as f64 / s as f64, f, &sw).powi(2);
        for jj in 1..j {
            sum += 2.0 * (1.0 - jj as f64 / mf) * sz(jj as f64 / s as f64, f, &sw).powi(2);
        }
        mf * sz0 * sz0 / sum
    }

    #[test]
    fn windowed_sum_matches_direct_sum() {
        // J = 3m > DIRECT_MAX, and J = M < 3m (record barely longer than 2m)
        for &(m, n_phase) in &[
            (2_000usize, 2_880_001usize),
            (20_000, 2_880_001),
            (150_000, 2_880_001),
            (20_000, 50_001),
            (30_000, 100_000),
        ] {
            for alpha in -2..=2 {
                let fast = greenhall_edf(alpha, m, n_phase, Overlap::Overlapping).unwrap();
                let slow = direct_edf(alpha, m, n_phase);
                let rel = (fast / slow - 1.0).abs();
                assert!(
                    rel < APPROX_REL_TOL,
                    "m={m} N={n_phase} alpha={alpha}: expected {slow}, got {fast} (rel {rel:e}, tol {APPROX_REL_TOL:e})"
                );
            }
        }
    }

    #[test]
    fn taylor_branch_matches_literal_difference() {
        for alpha in -2..=2 {
            let sw = Sw::new(alpha);
            let f = 100.0;
            for &t in &[0.6, 1.3, 2.7, -0.9] {
                let h = 1.0 / f;
                let lit = f * f * (2.0 * sw.value(t) - sw.value(t - h) - sw.value(t + h));
                let tay = sx(t, f, &sw);
                let scale = lit.abs().max(1e-300);
                if lit.abs() < 1e-9 && tay.abs() < 1e-9 {
                    continue; // both zero (|t| kernel)
                }
                assert!(
                    ((lit - tay) / scale).abs() < TAYLOR_REL_TOL,
                    "alpha={alpha} t={t}: literal {lit}, Taylor {tay}"
                );
            }
        }
    }

    /// Large-M limit vs the finite sum: the end terms change ν by O(1/M).
    const LARGE_M_REL_TOL: f64 = 1e-3;

    #[test]
    fn white_pm_m1_is_exact() {
        // Greenhall's kernels model continuous-time noise; for white PM (sw = −|t|) the model is
        // exact for sampled data, so at m = 1 ν must equal the discrete result. (For white FM
        // at m = 1 the continuous model gives M/1.28 where sampled white FM has exactly 2M/3 —
        // Stable32 uses the model, and so do we.)
        let n_phase = 10_001;
        // white PM, m = 1: second differences of white x, an MA(2) with correlations −4/6, 1/6:
        // var factor 1 + 2(16/36 + 1/36) = 1 + 34/36, ν = M/(1 + 34/36)
        let nu = greenhall_edf(2, 1, n_phase, Overlap::Overlapping).unwrap();
        let want = (n_phase - 2) as f64 / (1.0 + 34.0 / 36.0);
        assert!(
            (nu / want - 1.0).abs() < LARGE_M_REL_TOL,
            "expected {want}, got {nu}"
        );
    }

    #[test]
    fn rejects_bad_input() {
        assert!(greenhall_edf(3, 4, 1000, Overlap::Overlapping).is_none());
        assert!(greenhall_edf(0, 0, 1000, Overlap::Overlapping).is_none());
        assert!(greenhall_edf(0, 600, 1000, Overlap::Overlapping).is_none());
    }
}
