//! Fit of the IEEE Std 952-1997 (Annex C) noise model to an Allan variance curve.
//!
//! ```text
//! AVAR(τ) = 3Q²/τ² + N²/τ + (2 ln2/π)·B² + K²τ/3 + R²τ²/2
//! ```
//!
//! linear in the non-negative coefficients c = (Q², N², B², K², R²), fitted to the curve
//! points on a 2-per-octave sub-grid ([`FitConfig::per_octave`]).
//!
//! 1. Diagonal IRLS: var(AVAR_i) ≈ 2·AVAR_i²/ν_i with the *model-predicted* AVAR (weighting
//!    by the measured value would favour points that scattered low and bias every term down)
//!    and ν_i Greenhall's EDF for the α of the term dominating the model at τ_i
//!    (Q → 2, N → 0, B → −1, K and R → −2).
//! 2. GLS (default, [`FitMethod::Gls`]): the full covariance of the overlapping AVAR points
//!    under the current model ([`super::avar_cov`]), re-evaluated until the coefficients
//!    settle. Neighbouring overlapping points are strongly correlated; treating them as
//!    independent (step 1 alone) under-states every standard error 2–4× (measured: 95 %
//!    intervals covering the truth in only ~50 % of simulated cases).
//! 3. Forward selection of the nuisance terms Q, B, R ([`fit`]): fitting terms the data do not
//!    have costs the others precision (B and R trade off against K at long τ).
//!
//! Non-negativity: every subset of terms is solved unconstrained and the cheapest feasible one
//! kept — with five unknowns this enumeration of active sets is the exact NNLS optimum.
//! Standard errors: the (whitened) normal equations of the terms in the final model, scaled by
//! √max(1, χ²/dof) against model misfit; intervals by test inversion ([`inverted_interval`]).

// Small dense matrix code (Cholesky, normal equations) reads best with explicit indices.
#![allow(clippy::needless_range_loop)]

/// The five IEEE 952 terms, in coefficient order.
pub const TERM_COUNT: usize = 5;
/// Term names in coefficient order.
pub const TERM_NAMES: [&str; TERM_COUNT] = ["Q", "N", "B", "K", "R"];
/// Power-law α of the AVAR of each term (R, a deterministic ramp, is given RW FM's).
pub const TERM_ALPHA: [i32; TERM_COUNT] = [2, 0, -1, -2, -2];

/// Basis function g_j(τ) of coefficient j: AVAR = Σ c_j g_j(τ).
pub fn basis(j: usize, tau: f64) -> f64 {
    match j {
        0 => 3.0 / (tau * tau),
        1 => 1.0 / tau,
        2 => 2.0 * std::f64::consts::LN_2 / std::f64::consts::PI,
        3 => tau / 3.0,
        _ => tau * tau / 2.0,
    }
}

/// `v > 0` (false for NaN), spelled out so that NaN handling is visible at the call sites.
pub(super) fn is_positive(v: f64) -> bool {
    v > 0.0
}

/// Index into an EDF table row for α ∈ 2..=−2.
pub fn alpha_index(alpha: i32) -> usize {
    (2 - alpha.clamp(-2, 2)) as usize
}

/// How the points are weighted.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FitMethod {
    /// Independent points, var(AVAR_i) = 2·AVAR_i²/ν_i (Greenhall EDF of the dominant term).
    Diagonal,
    /// Generalised least squares with the full model covariance of the overlapping AVAR points
    /// ([`super::avar_cov`]), iterated from the diagonal solution.
    Gls,
}

/// Fit settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FitConfig {
    /// Which of Q, N, B, K, R are in the model.
    pub terms: [bool; TERM_COUNT],
    /// Weighting.
    pub method: FitMethod,
    /// The fit uses the curve points nearest to m = 2^(k/p), k = 0, 1, … for this p (2 is
    /// enough: the accuracy study gives the same estimates with 4).
    pub per_octave: u32,
    /// Iteration cap of the re-weighting.
    pub max_iter: usize,
    /// Factor on every standard error, for the diagonal method only: neighbouring overlapping
    /// AVAR points are correlated, which independent weights ignore (1 = no inflation).
    pub correlation_inflation: f64,
    /// Forward selection of the nuisance terms Q, B, R (see [`fit`]). Measured in the
    /// accuracy study: on white + random-walk data, fitting B and R that are not there
    /// doubles the spread of K and biases it low (the B–K–R trade-off at long τ).
    pub select: bool,
}

impl Default for FitConfig {
    fn default() -> Self {
        FitConfig {
            terms: [true; TERM_COUNT],
            method: FitMethod::Gls,
            per_octave: 2,
            max_iter: 50,
            correlation_inflation: 1.0,
            select: true,
        }
    }
}

/// One point given to the fit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FitPoint {
    /// Cluster size.
    pub m: usize,
    /// τ in seconds.
    pub tau: f64,
    /// Measured AVAR.
    pub avar: f64,
    /// Greenhall EDF of this point for α = 2, 1, 0, −1, −2 (see [`alpha_index`]).
    pub edf: [f64; 5],
}

/// Fit result in the coefficient space c = (Q², N², B², K², R²).
#[derive(Clone, Debug, PartialEq)]
pub struct FitResult {
    /// Fitted coefficients (0 for a term at its bound or not in the model).
    pub coef: [f64; TERM_COUNT],
    /// Covariance of the coefficients (zero rows for terms not in the model).
    pub cov: [[f64; TERM_COUNT]; TERM_COUNT],
    /// Terms strictly positive in the solution.
    pub free: [bool; TERM_COUNT],
    /// Re-weighting iterations done (diagonal + GLS).
    pub iterations: usize,
    /// Whether the re-weighting converged.
    pub converged: bool,
    /// χ² per degree of freedom of the final fit (whitened residuals for GLS).
    pub chi2_per_dof: f64,
    /// Index of the dominant model term at each input point.
    pub dominant: Vec<usize>,
    /// Indices (into the input points) of the points the fit used.
    pub used: Vec<usize>,
    /// Weighted (GLS: whitened) χ² of the final fit.
    pub chi2: f64,
    /// Terms left out by [`FitConfig::select`] (coefficient 0; their variance is the full model's).
    pub left_out: [bool; TERM_COUNT],
}

impl FitResult {
    /// Model AVAR at τ.
    pub fn predict(&self, tau: f64) -> f64 {
        (0..TERM_COUNT).map(|j| self.coef[j] * basis(j, tau)).sum()
    }
}

/// Indices of the points nearest (in log m) to each 2^(k/p), k = 0, 1, …, without repeats.
/// When the curve's grid is a refinement of the p-per-octave grid these are exactly its
/// points; otherwise the nearest ones.
fn thin_to_grid(points: &[FitPoint], p: u32) -> Vec<usize> {
    let p = p.max(1) as f64;
    let Some(max_m) = points.iter().map(|q| q.m).max() else {
        return Vec::new();
    };
    let mut out: Vec<usize> = Vec::new();
    let mut k = 0.0;
    while 2f64.powf(k / p) <= max_m as f64 * 2f64.powf(0.5 / p) {
        let target = k / p;
        let best = (0..points.len())
            .filter(|&i| points[i].m > 0)
            .min_by(|&a, &b| {
                let da = ((points[a].m as f64).log2() - target).abs();
                let db = ((points[b].m as f64).log2() - target).abs();
                da.total_cmp(&db)
            });
        if let Some(i) = best.filter(|i| !out.contains(i)) {
            out.push(i);
        }
        k += 1.0;
    }
    out.sort_unstable();
    out
}

/// GLS re-evaluations of the covariance at most.
const GLS_MAX_ITER: usize = 10;
/// GLS stops when no coefficient moves by more than this fraction (far below any standard error).
const GLS_REL_TOL: f64 = 1e-5;

/// Nuisance terms [`FitConfig::select`] adds only when the data ask for them: Q, B, R.
const NUISANCE: [usize; 3] = [0, 2, 4];
/// χ²(1) quantile at 0.99: a nuisance term enters when it lowers the fit's χ² by more than
/// this (a 1 % chance of adding a term the data do not have).
pub const SELECT_CHI2: f64 = 6.634_896_601_021_214;

/// Fits the model to `points` (see [`fit_once`]). With [`FitConfig::select`], forward
/// selection: start from the enabled ones of N and K, then repeatedly add the enabled nuisance
/// term (Q, B, R) that lowers χ² most, while it lowers it by more than [`SELECT_CHI2`].
/// Terms left out are reported at 0 with the upper bound of the all-terms fit.
pub fn fit(
    points: &[FitPoint],
    initial_alpha: &[Option<i32>],
    n: usize,
    tau0: f64,
    cfg: &FitConfig,
) -> Option<FitResult> {
    let full = fit_once(points, initial_alpha, n, tau0, cfg);
    if !cfg.select {
        return full;
    }
    let mut terms = [false; TERM_COUNT];
    terms[1] = cfg.terms[1];
    terms[3] = cfg.terms[3];
    if !terms.iter().any(|t| *t) {
        return full;
    }
    let mut cur = fit_once(points, initial_alpha, n, tau0, &FitConfig { terms, ..*cfg })?;
    loop {
        let best = NUISANCE
            .iter()
            .copied()
            .filter(|&j| cfg.terms[j] && !terms[j])
            .filter_map(|j| {
                let mut t = terms;
                t[j] = true;
                let r = fit_once(
                    points,
                    initial_alpha,
                    n,
                    tau0,
                    &FitConfig { terms: t, ..*cfg },
                )?;
                Some((j, cur.chi2 - r.chi2, r))
            })
            .max_by(|x, y| x.1.total_cmp(&y.1));
        match best {
            Some((j, drop, r)) if drop > SELECT_CHI2 => {
                terms[j] = true;
                cur = r;
            }
            _ => break,
        }
    }
    for j in 0..TERM_COUNT {
        if cfg.terms[j] && !terms[j] {
            cur.left_out[j] = true;
            cur.coef[j] = 0.0;
            cur.cov[j][j] = full.as_ref().map_or(f64::NAN, |f| f.cov[j][j]);
        }
    }
    Some(cur)
}

/// Fits the model to `points` (overlapping AVAR of `n` rate samples at period `tau0`);
/// `initial_alpha` (per point, may be empty) picks the EDF of the first weights.
/// `None` with fewer usable points than enabled terms + 1, or no solution.
pub fn fit_once(
    points: &[FitPoint],
    initial_alpha: &[Option<i32>],
    n: usize,
    tau0: f64,
    cfg: &FitConfig,
) -> Option<FitResult> {
    let pts: Vec<(usize, &FitPoint)> = thin_to_grid(points, cfg.per_octave)
        .into_iter()
        .map(|i| (i, &points[i]))
        .filter(|(_, p)| {
            p.avar > 0.0 && p.avar.is_finite() && p.tau > 0.0 && p.edf.iter().all(|e| *e > 0.0)
        })
        .collect();
    let enabled: Vec<usize> = (0..TERM_COUNT).filter(|&j| cfg.terms[j]).collect();
    if enabled.is_empty() || pts.len() < enabled.len() + 1 {
        return None;
    }
    let g: Vec<[f64; TERM_COUNT]> = pts
        .iter()
        .map(|(_, p)| std::array::from_fn(|j| basis(j, p.tau)))
        .collect();
    let a: Vec<f64> = pts.iter().map(|(_, p)| p.avar).collect();
    let dominant_of = |coef: &[f64; TERM_COUNT], gi: &[f64; TERM_COUNT]| {
        (0..TERM_COUNT)
            .max_by(|&x, &y| (coef[x] * gi[x]).total_cmp(&(coef[y] * gi[y])))
            .unwrap_or(1)
    };
    // 1. diagonal IRLS; first weights from the measured AVAR and the identified α
    let mut pred = a.clone();
    let mut edf: Vec<f64> = pts
        .iter()
        .map(|(i, p)| p.edf[alpha_index(initial_alpha.get(*i).copied().flatten().unwrap_or(0))])
        .collect();
    let mut coef = [0.0; TERM_COUNT];
    let mut iterations = 0;
    let mut converged = false;
    while iterations < cfg.max_iter {
        iterations += 1;
        let w: Vec<f64> = pred
            .iter()
            .zip(&edf)
            .map(|(p, e)| e / (2.0 * p * p))
            .collect();
        coef = nnls_subsets(&g, &a, &w, &enabled)?;
        let new_pred: Vec<f64> = g
            .iter()
            .map(|gi| (0..TERM_COUNT).map(|j| coef[j] * gi[j]).sum::<f64>())
            .collect();
        if new_pred.iter().any(|v| !is_positive(*v)) {
            return None;
        }
        let new_edf: Vec<f64> = pts
            .iter()
            .zip(&g)
            .map(|((_, p), gi)| p.edf[alpha_index(TERM_ALPHA[dominant_of(&coef, gi)])])
            .collect();
        let change = pred
            .iter()
            .zip(&new_pred)
            .map(|(o, n)| ((n - o) / n).abs())
            .fold(0.0, f64::max);
        let edf_same = new_edf == edf;
        pred = new_pred;
        edf = new_edf;
        if change < 1e-10 && edf_same {
            converged = true;
            break;
        }
    }
    let (chi2, base_cov, scale_extra) = match cfg.method {
        FitMethod::Diagonal => {
            let w: Vec<f64> = pred
                .iter()
                .zip(&edf)
                .map(|(p, e)| e / (2.0 * p * p))
                .collect();
            let chi2: f64 = a
                .iter()
                .zip(&pred)
                .zip(&w)
                .map(|((ai, pi), wi)| wi * (ai - pi).powi(2))
                .sum();
            (
                chi2,
                covariance(&g, &w, &enabled)?,
                cfg.correlation_inflation.powi(2),
            )
        }
        FitMethod::Gls => {
            // 2. GLS with the model covariance, re-evaluated at each new solution
            let ms: Vec<usize> = pts.iter().map(|(_, p)| p.m).collect();
            converged = false;
            let mut last = None;
            for _ in 0..cfg.max_iter.min(GLS_MAX_ITER) {
                iterations += 1;
                let sigma = super::avar_cov::avar_cov(&ms, n, tau0, &coef);
                let (gw, aw) = whiten(&sigma, &g, &a)?;
                let ones = vec![1.0; gw.len()];
                let new = nnls_subsets(&gw, &aw, &ones, &enabled)?;
                let change = (0..TERM_COUNT)
                    .filter(|&j| new[j] > 0.0 || coef[j] > 0.0)
                    .map(|j| ((new[j] - coef[j]) / new[j].max(coef[j])).abs())
                    .fold(0.0, f64::max);
                coef = new;
                last = Some((gw, aw));
                if change < GLS_REL_TOL {
                    converged = true;
                    break;
                }
            }
            let (gw, aw) = last?;
            let ones = vec![1.0; gw.len()];
            let chi2: f64 = aw
                .iter()
                .zip(&gw)
                .map(|(ai, gi)| {
                    (ai - (0..TERM_COUNT).map(|j| coef[j] * gi[j]).sum::<f64>()).powi(2)
                })
                .sum();
            (chi2, covariance(&gw, &ones, &enabled)?, 1.0)
        }
    };
    let free: [bool; TERM_COUNT] = std::array::from_fn(|j| coef[j] > 0.0);
    let dof = pts
        .len()
        .saturating_sub(free.iter().filter(|f| **f).count())
        .max(1);
    let chi2_per_dof = chi2 / dof as f64;
    let scale = chi2_per_dof.max(1.0) * scale_extra;
    let mut cov = [[0.0; TERM_COUNT]; TERM_COUNT];
    for r in 0..TERM_COUNT {
        for c in 0..TERM_COUNT {
            cov[r][c] = base_cov[r][c] * scale;
        }
    }
    let dominant = points
        .iter()
        .map(|p| dominant_of(&coef, &std::array::from_fn(|j| basis(j, p.tau))))
        .collect();
    Some(FitResult {
        coef,
        cov,
        free,
        iterations,
        converged,
        chi2_per_dof,
        dominant,
        used: pts.iter().map(|(i, _)| *i).collect(),
        chi2,
        left_out: [false; TERM_COUNT],
    })
}

/// Interval for coefficient j by inverting the test |ĉ − c| ≤ z·se(c), with se(c) the GLS
/// standard error when the truth has c_j = c (the other coefficients at their estimates).
///
/// The plain interval ĉ ± z·se(ĉ) is too short above a low estimate: the AVAR variance grows
/// with the term, so an estimate that came out low also reports a small error. Found with a
/// fixed-point iteration (≤ [`INVERSION_MAX_ITER`] covariance evaluations per end). For the
/// diagonal method, or if the covariance cannot be evaluated, the plain interval is returned.
/// Returns (lo, hi) of the coefficient (a squared term), lo ≥ 0; hi = ∞ when the data bound
/// the term from above at no value (se(c) grows as fast as c/z).
pub fn inverted_interval(
    points: &[FitPoint],
    res: &FitResult,
    n: usize,
    tau0: f64,
    cfg: &FitConfig,
    j: usize,
    z: f64,
) -> (f64, f64) {
    let c_hat = res.coef[j];
    let se_hat = res.cov[j][j].max(0.0).sqrt();
    let plain = ((c_hat - z * se_hat).max(0.0), c_hat + z * se_hat);
    if cfg.method != FitMethod::Gls || res.left_out[j] {
        return plain;
    }
    let enabled: Vec<usize> = (0..TERM_COUNT)
        .filter(|&t| cfg.terms[t] && !res.left_out[t])
        .collect();
    let ms: Vec<usize> = res.used.iter().map(|&i| points[i].m).collect();
    let g: Vec<[f64; TERM_COUNT]> = res
        .used
        .iter()
        .map(|&i| std::array::from_fn(|t| basis(t, points[i].tau)))
        .collect();
    let a: Vec<f64> = res.used.iter().map(|&i| points[i].avar).collect();
    let ones = vec![1.0; a.len()];
    let misfit = res.chi2_per_dof.max(1.0).sqrt();
    let se_at = |c: f64| -> Option<f64> {
        let mut coef = res.coef;
        coef[j] = c.max(0.0);
        let sigma = super::avar_cov::avar_cov(&ms, n, tau0, &coef);
        let (gw, _) = whiten(&sigma, &g, &a)?;
        Some(covariance(&gw, &ones, &enabled)?[j][j].max(0.0).sqrt() * misfit)
    };
    let mut hi = plain.1;
    let mut hi_ok = false;
    for _ in 0..INVERSION_MAX_ITER {
        let Some(se) = se_at(hi) else { return plain };
        let next = c_hat + z * se;
        let done = (next - hi).abs() <= INVERSION_REL_TOL * next;
        hi = next;
        if done {
            hi_ok = true;
            break;
        }
    }
    if !hi_ok && z * se_at(hi * 1e3).unwrap_or(0.0) >= hi * 1e3 {
        hi = f64::INFINITY;
    }
    let mut lo = plain.0;
    if lo > 0.0 {
        for _ in 0..INVERSION_MAX_ITER {
            let Some(se) = se_at(lo) else { return plain };
            let next = (c_hat - z * se).max(0.0);
            let done = (next - lo).abs() <= INVERSION_REL_TOL * c_hat;
            lo = next;
            if done || lo == 0.0 {
                break;
            }
        }
    }
    (lo, hi)
}

/// Covariance evaluations per interval end at most.
pub const INVERSION_MAX_ITER: usize = 12;
/// Fixed point reached when an end moves by less than this fraction.
const INVERSION_REL_TOL: f64 = 1e-3;

/// L⁻¹G and L⁻¹A with Σ = LLᵀ (Σ scaled to unit diagonal first, tiny ridge for safety).
fn whiten(
    sigma: &[Vec<f64>],
    g: &[[f64; TERM_COUNT]],
    a: &[f64],
) -> Option<(Vec<[f64; TERM_COUNT]>, Vec<f64>)> {
    let k = a.len();
    let d: Vec<f64> = (0..k).map(|i| sigma[i][i].sqrt()).collect();
    if d.iter().any(|v| !is_positive(*v)) {
        return None;
    }
    let mut l = vec![vec![0.0; k]; k];
    for i in 0..k {
        for j in 0..=i {
            let mut s = sigma[i][j] / (d[i] * d[j]) + if i == j { 1e-10 } else { 0.0 };
            for p in 0..j {
                s -= l[i][p] * l[j][p];
            }
            if i == j {
                if !is_positive(s) {
                    return None;
                }
                l[i][i] = s.sqrt();
            } else {
                l[i][j] = s / l[j][j];
            }
        }
    }
    // forward substitution on the scaled rows (row i divided by d_i)
    let mut gw = vec![[0.0; TERM_COUNT]; k];
    let mut aw = vec![0.0; k];
    for i in 0..k {
        let mut ga: [f64; TERM_COUNT] = std::array::from_fn(|j| g[i][j] / d[i]);
        let mut av = a[i] / d[i];
        for p in 0..i {
            for j in 0..TERM_COUNT {
                ga[j] -= l[i][p] * gw[p][j];
            }
            av -= l[i][p] * aw[p];
        }
        for j in 0..TERM_COUNT {
            gw[i][j] = ga[j] / l[i][i];
        }
        aw[i] = av / l[i][i];
    }
    Some((gw, aw))
}

/// Weighted NNLS over the enabled terms by enumerating the sets of free terms.
fn nnls_subsets(
    g: &[[f64; TERM_COUNT]],
    a: &[f64],
    w: &[f64],
    enabled: &[usize],
) -> Option<[f64; TERM_COUNT]> {
    let k = enabled.len();
    let mut best: Option<(f64, [f64; TERM_COUNT])> = None;
    for mask in 1u32..(1 << k) {
        let set: Vec<usize> = (0..k)
            .filter(|b| mask & (1 << b) != 0)
            .map(|b| enabled[b])
            .collect();
        let Some(sol) = wls(g, a, w, &set) else {
            continue;
        };
        if sol.iter().any(|v| *v < 0.0) {
            continue;
        }
        let mut c = [0.0; TERM_COUNT];
        for (s, &j) in set.iter().enumerate() {
            c[j] = sol[s];
        }
        let cost: f64 = g
            .iter()
            .zip(a)
            .zip(w)
            .map(|((gi, ai), wi)| {
                wi * (ai - (0..TERM_COUNT).map(|j| c[j] * gi[j]).sum::<f64>()).powi(2)
            })
            .sum();
        if best.as_ref().is_none_or(|(bc, _)| cost < *bc) {
            best = Some((cost, c));
        }
    }
    best.map(|(_, c)| c)
}

/// Column norms of the weighted design for the terms in `set` (for conditioning).
fn col_scale(g: &[[f64; TERM_COUNT]], w: &[f64], set: &[usize]) -> Vec<f64> {
    set.iter()
        .map(|&j| {
            g.iter()
                .zip(w)
                .map(|(gi, wi)| wi * gi[j] * gi[j])
                .sum::<f64>()
                .sqrt()
        })
        .collect()
}

/// Scaled normal matrix and right-hand side of the weighted LS on `set`.
fn normal_eq(
    g: &[[f64; TERM_COUNT]],
    a: &[f64],
    w: &[f64],
    set: &[usize],
    s: &[f64],
) -> (Vec<Vec<f64>>, Vec<f64>) {
    let k = set.len();
    let mut n = vec![vec![0.0; k]; k];
    let mut b = vec![0.0; k];
    for ((gi, ai), wi) in g.iter().zip(a).zip(w) {
        for r in 0..k {
            let xr = gi[set[r]] / s[r];
            b[r] += wi * xr * ai;
            for c in 0..k {
                n[r][c] += wi * xr * gi[set[c]] / s[c];
            }
        }
    }
    (n, b)
}

/// Unconstrained weighted LS on the terms of `set`.
fn wls(g: &[[f64; TERM_COUNT]], a: &[f64], w: &[f64], set: &[usize]) -> Option<Vec<f64>> {
    let s = col_scale(g, w, set);
    if s.iter().any(|v| !is_positive(*v)) {
        return None;
    }
    let (n, b) = normal_eq(g, a, w, set, &s);
    let x = solve_spd(&n, &b)?;
    Some(x.iter().zip(&s).map(|(xi, si)| xi / si).collect())
}

/// (GᵀWG)⁻¹ over the enabled terms, embedded in a 5×5 matrix.
fn covariance(
    g: &[[f64; TERM_COUNT]],
    w: &[f64],
    set: &[usize],
) -> Option<[[f64; TERM_COUNT]; TERM_COUNT]> {
    let s = col_scale(g, w, set);
    let zeros = vec![0.0; g.len()];
    let (n, _) = normal_eq(g, &zeros, w, set, &s);
    let k = set.len();
    let mut out = [[0.0; TERM_COUNT]; TERM_COUNT];
    for c in 0..k {
        let mut e = vec![0.0; k];
        e[c] = 1.0;
        let col = solve_spd(&n, &e)?;
        for r in 0..k {
            out[set[r]][set[c]] = col[r] / (s[r] * s[c]);
        }
    }
    Some(out)
}

/// Solves a symmetric positive-definite system by Cholesky; `None` if not positive definite.
pub(super) fn solve_spd(n: &[Vec<f64>], b: &[f64]) -> Option<Vec<f64>> {
    let k = b.len();
    let mut l = vec![vec![0.0; k]; k];
    for i in 0..k {
        for j in 0..=i {
            let mut s = n[i][j];
            for p in 0..j {
                s -= l[i][p] * l[j][p];
            }
            if i == j {
                if !is_positive(s - 1e-13 * n[i][i].abs().max(f64::MIN_POSITIVE)) {
                    return None;
                }
                l[i][i] = s.sqrt();
            } else {
                l[i][j] = s / l[j][j];
            }
        }
    }
    let mut y = vec![0.0; k];
    for i in 0..k {
        let mut s = b[i];
        for p in 0..i {
            s -= l[i][p] * y[p];
        }
        y[i] = s / l[i][i];
    }
    let mut x = vec![0.0; k];
    for i in (0..k).rev() {
        let mut s = y[i];
        for p in i + 1..k {
            s -= l[p][i] * x[p];
        }
        x[i] = s / l[i][i];
    }
    Some(x)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Noise-free data: the fit must return the generating coefficients to rounding.
    const EXACT_REL_TOL: f64 = 1e-8;

    fn pts(coef: [f64; 5]) -> Vec<FitPoint> {
        (0..40)
            .map(|k| {
                let tau = 0.005 * 1.4f64.powi(k);
                let avar = (0..5).map(|j| coef[j] * basis(j, tau)).sum();
                FitPoint {
                    m: k as usize + 1,
                    tau,
                    avar,
                    edf: [100.0; 5],
                }
            })
            .collect()
    }

    #[test]
    fn recovers_exact_model() {
        let truth = [1e-8, 2.25e-4, 1e-7, 2.5e-9, 1e-14];
        let r = fit(
            &pts(truth),
            &[],
            1_000_000,
            0.005,
            &FitConfig {
                method: FitMethod::Diagonal,
                per_octave: 1000,
                select: false,
                ..FitConfig::default()
            },
        )
        .unwrap();
        for j in 0..5 {
            assert!(
                ((r.coef[j] - truth[j]) / truth[j]).abs() < EXACT_REL_TOL,
                "term {}: expected {:e}, got {:e}",
                TERM_NAMES[j],
                truth[j],
                r.coef[j]
            );
        }
        assert!(r.converged);
    }

    #[test]
    fn thinning_picks_the_coarse_grid() {
        use super::super::tau_grid::GridSpec;
        let n = 2_880_000;
        let fine = GridSpec {
            per_octave: 8,
            min_clusters: 4,
        }
        .cluster_sizes(n);
        let coarse = GridSpec {
            per_octave: 2,
            min_clusters: 4,
        }
        .cluster_sizes(n);
        let pts: Vec<FitPoint> = fine
            .iter()
            .map(|&m| FitPoint {
                m,
                tau: m as f64,
                avar: 1.0,
                edf: [1.0; 5],
            })
            .collect();
        let got: Vec<usize> = thin_to_grid(&pts, 2).iter().map(|&i| pts[i].m).collect();
        // the coarse grid, plus the fine grid's last point when it is within half a coarse
        // step of the next coarse target (it carries the longest τ)
        assert_eq!(got[..coarse.len()], coarse[..]);
        assert!(
            got.len() <= coarse.len() + 1 && got.last() == fine.last(),
            "{got:?}"
        );
        // a grid that is not a refinement still gives one point per target, nearest first
        let odd = GridSpec {
            per_octave: 5,
            min_clusters: 4,
        }
        .cluster_sizes(n);
        let pts: Vec<FitPoint> = odd
            .iter()
            .map(|&m| FitPoint {
                m,
                tau: m as f64,
                avar: 1.0,
                edf: [1.0; 5],
            })
            .collect();
        let got = thin_to_grid(&pts, 2);
        assert!(
            got.len() + 3 >= coarse.len() && got.len() <= coarse.len() + 1,
            "{} vs {}",
            got.len(),
            coarse.len()
        );
    }

    #[test]
    fn gls_recovers_exact_model() {
        // noise-free AVAR of a white + random-walk model: GLS and the selection must return it
        let truth = [0.0, 2.25e-4, 0.0, 2.5e-9, 0.0];
        let ms: Vec<usize> = (0..20).map(|k| 1usize << k).collect();
        let pts: Vec<FitPoint> = ms
            .iter()
            .map(|&m| {
                let tau = m as f64 * 0.005;
                FitPoint {
                    m,
                    tau,
                    avar: (0..5).map(|j| truth[j] * basis(j, tau)).sum(),
                    edf: [100.0; 5],
                }
            })
            .collect();
        let r = fit(
            &pts,
            &[],
            4_000_000,
            0.005,
            &FitConfig {
                per_octave: 1,
                ..FitConfig::default()
            },
        )
        .unwrap();
        for j in [1, 3] {
            assert!(
                ((r.coef[j] - truth[j]) / truth[j]).abs() < EXACT_REL_TOL,
                "term {}: expected {:e}, got {:e}",
                TERM_NAMES[j],
                truth[j],
                r.coef[j]
            );
        }
        assert!(
            r.left_out[0] && r.left_out[2] && r.left_out[4],
            "nuisance terms must stay out: {:?}",
            r.left_out
        );
        assert!(r.converged);
    }

    #[test]
    fn absent_terms_stay_at_zero() {
        let truth = [0.0, 2.25e-4, 0.0, 2.5e-9, 0.0];
        let r = fit(
            &pts(truth),
            &[],
            1_000_000,
            0.005,
            &FitConfig {
                method: FitMethod::Diagonal,
                per_octave: 1000,
                select: false,
                ..FitConfig::default()
            },
        )
        .unwrap();
        for j in [1, 3] {
            assert!(
                ((r.coef[j] - truth[j]) / truth[j]).abs() < EXACT_REL_TOL,
                "term {}: {:e}",
                TERM_NAMES[j],
                r.coef[j]
            );
        }
        for j in [0, 2, 4] {
            assert!(
                r.coef[j] >= 0.0 && r.coef[j] * basis(j, 1.0) < 1e-10 * 2.25e-4,
                "term {}: {:e}",
                TERM_NAMES[j],
                r.coef[j]
            );
        }
    }

    #[test]
    fn nnls_subsets_matches_brute_force_grid() {
        // a 2-term case where the unconstrained solution is negative: y = 1/τ data with a dip
        let g: Vec<[f64; 5]> = (1..20)
            .map(|k| std::array::from_fn(|j| basis(j, k as f64)))
            .collect();
        let a: Vec<f64> = (1..20)
            .map(|k| 1.0 / k as f64 - 0.01 * k as f64 / 3.0)
            .collect();
        let w = vec![1.0; g.len()];
        let c = nnls_subsets(&g, &a, &w, &[1, 3]).unwrap();
        assert_eq!(c[3], 0.0, "K must be clamped at 0");
        // with K = 0, N² is the 1-D LS solution
        let num: f64 = g.iter().zip(&a).map(|(gi, ai)| gi[1] * ai).sum();
        let den: f64 = g.iter().map(|gi| gi[1] * gi[1]).sum();
        assert!((c[1] - num / den).abs() < 1e-12);
    }
}
