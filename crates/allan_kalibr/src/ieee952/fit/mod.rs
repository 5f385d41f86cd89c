//! Fit of the IEEE Std 952-1997 (Annex C) noise model to an Allan variance curve.
//!
//! ```text
//! AVAR(τ) = 3Q²/τ² + N²/τ + (2 ln2/π)·B² + K²τ/3 + R²τ²/2
//! ```
//!
//! linear in the coefficients c = (Q², N², B², K², R²), fitted to the curve points on a
//! 2-per-octave sub-grid ([`FitConfig::per_octave`]).
//!
//! The terms' basis functions and shapes are in [`super::model`], the small dense linear algebra
//! (whitening, active-set NNLS, normal equations, SPD solve) in `linalg`, one GLS solve with
//! the discrepancy in `gls`; this module is the fit itself: the τ range, term selection and
//! the intervals.
//! How far a range may go on past the first point the model misses is `range_end`'s joint
//! test of the extension.
//!
//! # Weighting: generalised least squares with a model-discrepancy component
//! The statistical covariance Σ(c) of the overlapping AVAR points under the model
//! ([`super::avar_cov`]) is exact when the model is right. Real sensors are not exactly the
//! model (a low-pass filter, a flicker floor with corners, a Gauss–Markov bump), and the
//! short-τ points of a long record carry error bars of 0.1 %: weighted by Σ alone they steer
//! the whole fit, and a few-percent shape error there turns into a white noise dropped and a
//! random walk invented (issue 10). So the covariance is
//!
//! ```text
//! V = Σ(c) + δ²·diag(A_model²)
//! ```
//!
//! with δ, the relative model discrepancy, estimated from the data as the value that makes
//! the generalised χ²/dof equal 1 (δ = 0 when the model already fits within the statistics:
//! then this is the plain GLS). A point can then never claim more precision than the model
//! has; high-precision points are capped at δ, noisy ones keep their statistical weight.
//! The alternatives, measured on the real-IMU curves of `testdata/real_curves`: Σ alone
//! (χ²/dof 10³–10⁵, terms dropped and invented), and Σ scaled by χ²/dof (same weights, same
//! wrong terms, only wider intervals) — see `tests/studies/real.rs`.
//!
//! # Which τ the model may describe ([`choose_start`])
//! The model's log-AVAR is convex in log τ (a sum of power laws). A band-limited sensor's
//! curve is not: below a few filter time constants it lies under the white-noise line, or
//! rises (a heavily filtered accelerometer). Those points are excluded: first the stretch
//! before the curve starts to fall like white noise, then, one at a time, each shortest point
//! whose inclusion raises the χ² by more than [`TRIM_CHI2`] times the χ² per degree of
//! freedom of the points after it (a deletion F-test, with the scale taken from the data so
//! that real-curve misfit elsewhere does not decide it). The
//! asymptotic effect of a low-pass filter on the white-noise region is a negative 1/τ²
//! correction (AVAR = N²/τ − c/τ², c = (N²/4π²)∫(1 − |H|²)/f² df); with
//! [`FitConfig::band_limit`] the 1/τ² coefficient may be negative so that this region is
//! described rather than cut, and the white-noise region keeps τ = 1 s.
//!
//! # Terms
//! Forward selection of the nuisance terms Q, B, R ([`fit`]): N and K are always fitted,
//! the others enter when they lower χ² (under the full model's discrepancy) by more than
//! [`SELECT_CHI2`]; fitting terms the data do not have costs the others precision (B and R
//! trade off against K at long τ). A Q that entered but whose line never comes within 20 %
//! of the model ([`super::RESOLVED_SHARE`]) is taken out again and the model refitted: a
//! τ⁻² excess that small is the white-noise region's bend (a filter, aliasing) more often
//! than a quantization, and kept it lowers N below the −½ line (real imu_utils curves of a
//! MicroStrain GX4 gyro: N 10 % under the IEEE 952 reading with it, 0.2 % without).
//! Non-negativity: every subset of terms is solved unconstrained and the cheapest feasible
//! one kept — with six unknowns this enumeration of active sets is the exact NNLS optimum.
//! Intervals by test inversion ([`inverted_interval`]).
//!
//! Two shapes that are not power laws, so that they are not read as one (issue 10: "handle
//! flicker floors, Gauss–Markov bumps and quantization without inventing terms"):
//! * a Gauss–Markov (exponentially correlated) bias, IEEE 952 Annex C ([`gm_basis`]):
//!   its bump would otherwise be fitted as bias instability or random walk. It enters only
//!   where the data locate its correlation time (an interior best time, at least
//!   [`GM_MIN_T`]) and lower χ² by [`SELECT_CHI2_GM`]; a B or K that a bump explains as
//!   well is not "resolved" ([`FitResult::ambiguous`]).
//! * a lower corner of the flicker floor ([`flicker_band`]): a 1/f spectrum that stops at a
//!   shortest correlation time rolls off slowly below it, and a flat floor trades the missing
//!   flicker for white noise. The corner enters like a term; where the data cannot tell
//!   (the usual case) every plausible corner widens the intervals
//!   ([`FitResult::alternatives`]).
//!
//! And the vibration lines the PSD finds (IEEE 952's sinusoidal noise, [`LineShape`]): their
//! shapes are known, their A² fitted; in the enumeration of active sets they are in every
//! set (2⁶ sets whatever the lines), and they take any sign.
//!
//! Their covariance: the shaped terms' AVAR is given, point by point, to the power law of
//! its local slope (`effective_coef`); a line's to white noise (plus, for a resonance, the
//! variance of a narrow-band estimate), and a ramp's — deterministic, but its estimate
//! carries the noise's cross term — to random walk, so that an R read off the longest
//! points is as uncertain as those points are (issue 18.5).
//!
//! [`flicker_band`]: super::model::flicker_band

// Small dense matrix code (Cholesky, normal equations) reads best with explicit indices.
#![allow(clippy::needless_range_loop)]

use super::avar_cov::CovBasis;

mod gls;
mod linalg;
mod profile;
mod range_end;
use super::model::effective_coef;
pub(in crate::ieee952) use super::model::is_positive;
#[cfg(test)]
pub(in crate::ieee952) use super::model::{FLICKER_AVAR, flicker_band};
pub use super::model::{
    LINE_SLOTS, LineShape, LineSlots, Shapes, TERM_COUNT, basis, basis_at, gm_basis, term_basis_at,
};
pub use super::term::NoiseTerm;
use super::term::NoiseTerm::{
    BiasInstability, GaussMarkov, Quantization, Ramp, RandomWalk, WhiteNoise,
};
use gls::{Delta, FixedLs, Problem, Solve, fixed_ls, gls};
pub(in crate::ieee952) use linalg::solve_spd;
use linalg::{covariance, whiten};
pub(in crate::ieee952) use profile::{ONE_SIDED_95, Profile, TWO_SIDED_95};
pub(in crate::ieee952) use range_end::extension_agrees;

/// Fit settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FitConfig {
    /// Which of Q, N, B, K, R are in the model.
    pub terms: [bool; TERM_COUNT],
    /// The fit uses the curve points nearest to m = 2^(k/p), k = 0, 1, … for this p (2 is
    /// enough: the accuracy study gives the same estimates with 4).
    pub per_octave: u32,
    /// Iteration cap of the re-weighting.
    pub max_iter: usize,
    /// Forward selection of the nuisance terms Q, B, R (see `fit`).
    pub select: bool,
    /// Model-discrepancy variance component (see the module docs). Off: plain GLS with the
    /// statistical covariance, standard errors scaled by √max(1, χ²/dof).
    pub discrepancy: bool,
    /// Choose the start of the fitted range (`choose_start`); off: fit every point.
    pub trim: bool,
    /// Allow a negative 1/τ² coefficient (the low-pass correction; module docs).
    pub band_limit: bool,
    /// Allow the flicker floor a lower corner (`flicker_band`).
    pub flicker_corner: bool,
}

impl Default for FitConfig {
    fn default() -> Self {
        FitConfig {
            terms: [true; TERM_COUNT],
            per_octave: 2,
            max_iter: 50,
            select: true,
            discrepancy: true,
            trim: true,
            band_limit: true,
            flicker_corner: true,
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
}

/// The points of one curve on the fit grid, with their statistical covariance model.
#[derive(Clone, Debug)]
pub struct FitData<'a> {
    /// Points, ascending τ, AVAR > 0.
    pub points: Vec<FitPoint>,
    /// Statistical covariance (None when the sample count is unknown: then only relative
    /// weights, no intervals).
    pub basis: Option<&'a CovBasis>,
    /// Index of each point into the basis.
    pub basis_index: Vec<usize>,
    /// The lines the model holds (from the PSD of the samples; none for a curve alone).
    pub lines: LineSlots,
}

impl FitData<'_> {
    /// The power laws and this curve's lines: the shapes every fit starts from.
    pub(crate) fn base_shapes(&self) -> Shapes {
        Shapes::with_lines(self.lines)
    }
}

/// Indices of the points nearest (in log m) to each 2^(k/p), k = 0, 1, …, without repeats.
/// When the curve's grid is a refinement of the p-per-octave grid these are exactly its
/// points; otherwise the nearest ones.
pub(crate) fn thin_to_grid(ms: &[usize], p: u32) -> Vec<usize> {
    let p = p.max(1) as f64;
    let Some(&max_m) = ms.iter().max() else {
        return Vec::new();
    };
    let mut out: Vec<usize> = Vec::new();
    let mut k = 0.0;
    while 2f64.powf(k / p) <= max_m as f64 * 2f64.powf(0.5 / p) {
        let target = k / p;
        let best = (0..ms.len()).filter(|&i| ms[i] > 0).min_by(|&a, &b| {
            let da = ((ms[a] as f64).log2() - target).abs();
            let db = ((ms[b] as f64).log2() - target).abs();
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

/// Result of a fit over a range of the fit grid.
#[derive(Clone, Debug, PartialEq)]
pub struct FitResult {
    /// Fitted coefficients (0 for a term at its bound or not in the model; the 1/τ²
    /// coefficient may be negative with [`FitConfig::band_limit`]).
    pub coef: [f64; TERM_COUNT],
    /// Covariance of the coefficients (zero rows for terms not in the model).
    pub cov: [[f64; TERM_COUNT]; TERM_COUNT],
    /// Terms in the final model (nonzero coefficient).
    pub free: [bool; TERM_COUNT],
    /// Terms left out by [`FitConfig::select`] (coefficient 0; their variance is the full model's).
    pub left_out: [bool; TERM_COUNT],
    /// For a term left out: its coefficient (≥ 0) in the fit that had it, the full model's or,
    /// for a quantization taken out again, the selected one's; its upper bound starts there.
    pub left_out_coef: [f64; TERM_COUNT],
    /// Positions (into [`FitData::points`]) of the points used: a contiguous range.
    pub used: Vec<usize>,
    /// Re-weighting iterations of the final fit.
    pub iterations: usize,
    /// Whether the re-weighting converged.
    pub converged: bool,
    /// Statistical χ² per degree of freedom over the used range (Σ only; NaN without a
    /// sample count). ≈ 1 when the model describes the points within their statistics.
    pub chi2_per_dof: f64,
    /// Relative model discrepancy δ (0: the model fits within the statistics).
    pub delta: f64,
    /// Degrees of freedom (points − free terms).
    pub dof: usize,
    /// Shapes of the Gauss–Markov term and of the flicker floor.
    pub shapes: Shapes,
    /// Other flicker-floor corners the data do not reject (χ² within [`PROFILE_CHI2_95`] of
    /// the best, the terms unchanged): how the coefficients move with the floor's unresolved
    /// shape. A term's interval spans theirs — a profile-likelihood interval over the corner
    /// (a long record of a white + flicker sensor cannot tell a flat floor from one with a
    /// corner where the two meet, and N follows the choice by about a percent).
    pub alternatives: Vec<ShapeAlternative>,
    /// Terms in the model that a Gauss–Markov bias explains as well (see [`fit`]): B or K
    /// whose floor or rise is a bump's shoulder or tail; not "resolved".
    pub ambiguous: [bool; TERM_COUNT],
    /// Where the model has a flicker floor and no Gauss–Markov bias: the best correlation
    /// time of a bump in the floor's place (NaN: none searched). B's interval spans the
    /// model with that bump beside the floor ([`Profile`]): a bump's shoulder read as a
    /// floor gave a B 2.4× the truth with an interval excluding it.
    pub bump_for_floor: f64,
    /// Largest share of the model's Allan variance each term's own line has at a used point:
    /// ≈ 1 where it alone makes the curve, ≥ 0.64 where its line comes within 20 % of it.
    pub max_share: [f64; TERM_COUNT],
}

/// The fit with other shape parameters (see [`FitResult::alternatives`]).
#[derive(Clone, Debug, PartialEq)]
pub struct ShapeAlternative {
    /// The shapes.
    pub shapes: Shapes,
    /// Coefficients with them.
    pub coef: [f64; TERM_COUNT],
    /// Their standard errors.
    pub std_err: [f64; TERM_COUNT],
}

/// χ²(1) quantile at 0.95: a shape is plausible while its χ² is within this of the best.
pub const PROFILE_CHI2_95: f64 = 3.841_458_820_694_124;

impl FitResult {
    /// Model AVAR at τ.
    pub(crate) fn predict(&self, tau: f64) -> f64 {
        predict(&self.coef, &self.shapes, tau)
    }
}

/// Model AVAR at τ for coefficients `coef` and shapes `shapes`.
pub(crate) fn predict(coef: &[f64; TERM_COUNT], shapes: &Shapes, tau: f64) -> f64 {
    (0..TERM_COUNT)
        .filter(|&j| coef[j] != 0.0)
        .map(|j| coef[j] * basis_at(j, tau, shapes))
        .sum()
}

/// A short-τ point is dropped when it raises χ² by more than this many times the χ² per
/// degree of freedom of the points after it: the χ²(1) quantile at 1 − 1e-4 (one point in
/// 10⁴ wrongly dropped on data the model describes; a band-limited point raises χ² by
/// 10²–10⁶).
pub const TRIM_CHI2: f64 = 15.136_705_226_623_606;
/// Nuisance terms [`FitConfig::select`] adds only when the data ask for them: Q, B, R (and
/// the Gauss–Markov bias, with its own threshold [`SELECT_CHI2_GM`]).
const NUISANCE: [NoiseTerm; 3] = [Quantization, BiasInstability, Ramp];
/// χ²(1) quantile at 0.99: a nuisance term enters when it lowers the fit's χ² by more than
/// this (a 1 % chance of adding a term the data do not have).
pub const SELECT_CHI2: f64 = 6.634_896_601_021_214;
/// Median of χ²(1): a robust scale is median(e²)/this.
const CHI2_1_MEDIAN: f64 = 0.454_936_423_119_572_8;

/// Robust χ² per degree of freedom of a fit: the median squared whitened residual over the
/// median of χ²(1), so a few band-limited points do not set the scale they are judged by.
fn robust_scale(resid_w: &[f64]) -> f64 {
    let mut e: Vec<f64> = resid_w.iter().map(|x| x * x).collect();
    if e.is_empty() {
        return f64::NAN;
    }
    e.sort_by(f64::total_cmp);
    let k = e.len();
    let med = if k % 2 == 1 {
        e[k / 2]
    } else {
        0.5 * (e[k / 2 - 1] + e[k / 2])
    };
    med / CHI2_1_MEDIAN
}

fn signed_terms(cfg: &FitConfig) -> [bool; TERM_COUNT] {
    let mut s = [false; TERM_COUNT];
    s[Quantization] = cfg.band_limit;
    // the lines' shapes come from the PSD; their coefficients take any sign
    for l in NoiseTerm::LINES {
        s[l] = true;
    }
    s
}

/// The IEEE 952 terms of `cfg` (the Gauss–Markov one off).
fn ieee_only(terms: [bool; TERM_COUNT]) -> [bool; TERM_COUNT] {
    let mut t = terms;
    t[GaussMarkov] = false;
    t
}

/// First position of the fitted range on `data` (see the module docs): 0 unless
/// [`FitConfig::trim`].
///
/// 1. Shape: the points before the first one from which the curve falls with a log-log
///    slope of at most [`RISE_SLOPE`] are band-limited — no IEEE 952 term makes the Allan
///    deviation flat or rising at the shortest τ and falling after (a heavily filtered
///    sensor; white noise always dominates there otherwise).
/// 2. Statistics: from there, the first point is dropped while it fails the deletion test
///    against the fit of the points after it: including it raises χ² by more than
///    [`TRIM_CHI2`] times the robust χ² per degree of freedom of that fit (the median squared
///    whitened residual over the median of χ²(1): the scale comes from the data, so a model
///    that misses the curve elsewhere does not decide it, and neither do the band-limited
///    points still in).
pub(crate) fn choose_start(data: &FitData, cfg: &FitConfig) -> usize {
    let n = data.points.len();
    if !cfg.trim || n < MIN_FIT_POINTS + 1 {
        return 0;
    }
    // the shape rule on the curve without its lines (as the PSD measured them): a line's
    // bump at short τ is the model's, not a band limit
    let base = data.base_shapes();
    let dev: Vec<f64> = data
        .points
        .iter()
        .map(|p| {
            let lines: f64 = data
                .lines
                .iter()
                .flatten()
                .map(|l| l.psd_amp2 * l.avar(p.tau))
                .sum();
            (p.avar - lines).max(LINE_CLEAN_FLOOR * p.avar).sqrt()
        })
        .collect();
    let fwd_slope =
        |i: usize| (dev[i + 1] / dev[i]).ln() / (data.points[i + 1].tau / data.points[i].tau).ln();
    let mut s = (0..n - 1)
        .find(|&i| fwd_slope(i) <= RISE_SLOPE)
        .unwrap_or(0);
    let signed = signed_terms(cfg);
    let mode = if data.basis.is_some() {
        Delta::Zero
    } else {
        Delta::Fixed(1.0)
    };
    let delta = match mode {
        Delta::Fixed(d) => d,
        _ => 0.0,
    };
    while n - s > MIN_FIT_POINTS {
        let rest: Vec<usize> = (s + 1..n).collect();
        let all: Vec<usize> = (s..n).collect();
        let terms = ieee_only(cfg.terms);
        let Some(fit0) = gls(data, &rest, terms, signed, mode, cfg.max_iter, base) else {
            break;
        };
        // both fits under the covariance of the fit without the point
        let (Some((_, chi_without, rw, _)), Some((_, chi_with, _, _))) = (
            fixed_ls(data, &rest, terms, signed, &fit0.coef, delta, base),
            fixed_ls(data, &all, terms, signed, &fit0.coef, delta, base),
        ) else {
            break;
        };
        let scale = if data.basis.is_some() {
            robust_scale(&rw).max(1.0)
        } else {
            robust_scale(&rw)
        };
        if chi_with - chi_without <= TRIM_CHI2 * scale {
            break;
        }
        s += 1;
    }
    s
}

/// Log-log slope at or below which the curve is falling like white noise (−½) or faster:
/// halfway between flat and −½.
pub const RISE_SLOPE: f64 = -0.25;
/// The start rule's curve without its lines keeps at least this share of the measured
/// Allan variance (a PSD amplitude a few percent high must not make it vanish).
const LINE_CLEAN_FLOOR: f64 = 0.05;
/// Fewest points a fitted range keeps (five terms and two degrees of freedom).
pub const MIN_FIT_POINTS: usize = TERM_COUNT + 2;

/// Fits the model on the contiguous positions `used` of `data`. With
/// [`FitConfig::select`], forward selection: start from the enabled ones of N and K, then
/// repeatedly make the enabled step that lowers χ² most (with the full model's discrepancy
/// δ held fixed), while it lowers it by more than its threshold: add a nuisance term (Q, B,
/// R: [`SELECT_CHI2`]), add a Gauss–Markov bias at its best correlation time
/// ([`SELECT_CHI2_GM`]), or, once B is in, give the flicker floor a lower corner at its best
/// place ([`SELECT_CHI2`]: one parameter; [`flicker_band`]). The chosen model is then
/// refitted with its own δ. Terms left out are reported at 0 with the upper bound of the
/// all-terms fit (ĉ + z·se); a quantization taken out again (below) with that of the
/// selected fit that had it.
///
/// [`flicker_band`]: super::model::flicker_band
pub(crate) fn fit(data: &FitData, used: &[usize], cfg: &FitConfig) -> Option<FitResult> {
    let f = fit_terms(data, used, cfg)?;
    // A quantization term whose line never comes near the curve is not one the curve shows:
    // it is the model's τ⁻² shape bending the white-noise region (a filter, aliasing), and
    // kept it takes its share of the short-τ variance from N. Refit without it and report
    // it as left out, with the bound of the fit that had it (part of the term selection:
    // a fit of every term, `select` off, keeps it).
    let q = Quantization;
    if cfg.select && cfg.terms[q] && f.coef[q] > 0.0 && f.max_share[q] < super::RESOLVED_SHARE {
        let without = FitConfig {
            terms: {
                let mut t = cfg.terms;
                t[q] = false;
                t
            },
            ..*cfg
        };
        if let Some(mut g) = fit_terms(data, used, &without) {
            g.left_out[q] = true;
            g.left_out_coef[q] = f.coef[q];
            g.coef[q] = 0.0;
            g.cov[q][q] = f.cov[q][q];
            g.free[q] = false;
            return Some(g);
        }
    }
    Some(f)
}

/// [`fit`] with the terms of `cfg`.
fn fit_terms(data: &FitData, used: &[usize], cfg: &FitConfig) -> Option<FitResult> {
    let signed = signed_terms(cfg);
    let est = if cfg.discrepancy {
        Delta::Estimate
    } else {
        Delta::Zero
    };
    let ieee = ieee_only(cfg.terms);
    let base = data.base_shapes();
    let full = gls(data, used, ieee, signed, est, cfg.max_iter, base);
    let (terms, mut shapes) = select_terms(data, used, cfg, full.as_ref(), est)?;
    let mut s = if terms == ieee && shapes == base {
        full.clone()?
    } else {
        gls(data, used, terms, signed, est, cfg.max_iter, shapes)?
    };
    if !cfg.discrepancy && data.basis.is_some() {
        scale_by_misfit(&mut s);
    }
    let mut coef = s.coef;
    let mut cov = s.cov;
    let (left_out, left_out_coef) = leave_out(cfg, terms, base, full.as_ref(), &mut coef, &mut cov);
    // the fixed lines' coefficients are the PSD's
    for (j, v) in shapes.fixed_coef().iter().enumerate() {
        if *v != 0.0 {
            coef[j] = *v;
        }
    }
    if coef[GaussMarkov] == 0.0 {
        shapes.gm_t = f64::NAN;
    }
    if coef[BiasInstability] == 0.0 {
        shapes.b_lo = 0.0;
    }
    let model = FinalModel {
        data,
        used,
        cfg,
        s: &s,
        terms,
        shapes,
        coef: &coef,
    };
    let ((ambiguous, bump_for_floor), alternatives) =
        (model.ambiguous_terms(), model.floor_alternatives());
    let max_share = max_shares(data, used, &coef, &shapes);
    Some(FitResult {
        coef,
        cov,
        free: std::array::from_fn(|j| coef[j] != 0.0),
        left_out,
        left_out_coef,
        used: used.to_vec(),
        iterations: s.iterations,
        converged: s.converged,
        chi2_per_dof: s.chi2_stat / s.dof.max(1) as f64,
        delta: if data.basis.is_some() || cfg.discrepancy {
            s.delta
        } else {
            f64::NAN
        },
        dof: s.dof,
        shapes,
        alternatives,
        ambiguous,
        bump_for_floor,
        max_share,
    })
}

/// Plain GLS (no discrepancy): the standard errors of `s` scaled against misfit (by its
/// χ²/dof, when above 1).
fn scale_by_misfit(s: &mut Solve) {
    // plain GLS: standard errors scaled against misfit
    let scale = (s.chi2 / s.dof.max(1) as f64).max(1.0);
    for row in s.cov.iter_mut() {
        for v in row.iter_mut() {
            *v *= scale;
        }
    }
}

/// The terms of `cfg` the selection left out of `terms` (with a shape in `base`): their
/// coefficients in `coef` set to 0, their variances in `cov` taken from the fit of every
/// IEEE term `full`; returns which were left out and their coefficients in `full`.
fn leave_out(
    cfg: &FitConfig,
    terms: [bool; TERM_COUNT],
    base: Shapes,
    full: Option<&Solve>,
    coef: &mut [f64; TERM_COUNT],
    cov: &mut [[f64; TERM_COUNT]; TERM_COUNT],
) -> ([bool; TERM_COUNT], [f64; TERM_COUNT]) {
    let mut left_out = [false; TERM_COUNT];
    let mut left_out_coef = [0.0; TERM_COUNT];
    for j in 0..TERM_COUNT {
        if cfg.terms[j] && !terms[j] && base.has(j) {
            left_out[j] = true;
            coef[j] = 0.0;
            cov[j][j] = full.map_or(f64::NAN, |f| f.cov[j][j]);
            left_out_coef[j] = full.map_or(0.0, |f| f.coef[j].max(0.0));
        }
    }
    (left_out, left_out_coef)
}

/// The forward selection of the nuisance terms, the Gauss–Markov bump and the flicker
/// floor's corner (with `cfg.select`): each step adds the candidate whose χ² drop beyond its
/// threshold is largest, while one is positive. Returns the terms and shapes chosen (the
/// IEEE terms and the base shapes without a selection).
fn select_terms(
    data: &FitData,
    used: &[usize],
    cfg: &FitConfig,
    full: Option<&Solve>,
    est: Delta,
) -> Option<([bool; TERM_COUNT], Shapes)> {
    let base = data.base_shapes();
    if cfg.select {
        let mut t = [false; TERM_COUNT];
        t[WhiteNoise] = cfg.terms[WhiteNoise];
        t[RandomWalk] = cfg.terms[RandomWalk];
        for l in NoiseTerm::LINES {
            t[l] = cfg.terms[l] && base.has(l.index());
        }
        if t.iter().any(|x| *x) {
            return select_forward(data, used, cfg, full, est, t);
        }
    }
    Some((ieee_only(cfg.terms), base))
}

/// [`select_terms`]' steps from the terms `t` always fitted (N, K, the lines), from the
/// base shapes: each adds the best candidate of [`best_candidate`] while its χ² drop beyond
/// its threshold is positive.
fn select_forward(
    data: &FitData,
    used: &[usize],
    cfg: &FitConfig,
    full: Option<&Solve>,
    est: Delta,
    mut t: [bool; TERM_COUNT],
) -> Option<([bool; TERM_COUNT], Shapes)> {
    let signed = signed_terms(cfg);
    let mut shapes = data.base_shapes();
    // each step tests the candidates under the covariance of the current model (the
    // null hypothesis), with the full model's discrepancy (see [`fixed_ls`])
    let d = match (full, est) {
        (Some(f), Delta::Estimate) if data.basis.is_some() => f.delta,
        _ if data.basis.is_none() => 1.0,
        _ => 0.0,
    };
    let dmode = Delta::Fixed(d);
    let grid = shape_grid(data, used, GM_GRID);
    let corners = if cfg.flicker_corner {
        shape_grid(data, used, CORNER_GRID)
    } else {
        Vec::new()
    };
    loop {
        let base = gls(data, used, t, signed, dmode, cfg.max_iter, shapes)?;
        let chi = |tt: [bool; TERM_COUNT], sh: Shapes| {
            fixed_ls(data, used, tt, signed, &base.coef, d, sh).map(|x| x.1)
        };
        let cur = chi(t, shapes)?;
        match best_candidate(cfg, t, shapes, cur, (&grid, &corners), &chi) {
            Some((j, excess, sh)) if excess > 0.0 => {
                if let Some(j) = j {
                    t[j] = true;
                }
                shapes = sh;
            }
            _ => break,
        }
    }
    Some((t, shapes))
}

/// A candidate step of the selection: the term added (none for a corner of the flicker
/// floor), its χ² drop beyond its threshold, and the shapes with it.
type Candidate = (Option<NoiseTerm>, f64, Shapes);

/// The best candidate step from the terms `t` and `shapes` (χ² `cur`, `chi` the χ² of a
/// candidate under the current model's covariance): each nuisance term not in yet, the
/// Gauss–Markov bump at its best correlation time on `grids.0` (only an interior one), and
/// each corner of the flicker floor on `grids.1`.
fn best_candidate(
    cfg: &FitConfig,
    t: [bool; TERM_COUNT],
    shapes: Shapes,
    cur: f64,
    (grid, corners): (&[f64], &[f64]),
    chi: &dyn Fn([bool; TERM_COUNT], Shapes) -> Option<f64>,
) -> Option<Candidate> {
    // (term added or none, χ² drop beyond its threshold, shapes)
    let mut best: Option<Candidate> = None;
    let mut consider = |j: Option<NoiseTerm>, excess: f64, sh: Shapes| {
        if best.is_none_or(|b| excess > b.1) {
            best = Some((j, excess, sh));
        }
    };
    for j in NUISANCE {
        if cfg.terms[j] && !t[j] {
            let mut tt = t;
            tt[j] = true;
            if let Some(c) = chi(tt, shapes) {
                consider(Some(j), cur - c - SELECT_CHI2, shapes);
            }
        }
    }
    if cfg.terms[GaussMarkov] && !t[GaussMarkov] {
        let mut tt = t;
        tt[GaussMarkov] = true;
        // the best correlation time; a bump only where the data locate it (a
        // best time at either end of the search is a trend the power laws
        // miss, not a bump)
        let best_t = grid
            .iter()
            .enumerate()
            .filter_map(|(i, &tg)| {
                let sh = Shapes { gm_t: tg, ..shapes };
                chi(tt, sh).map(|c| (i, c, sh))
            })
            .min_by(|a, b| a.1.total_cmp(&b.1));
        if let Some((i, c, sh)) = best_t
            && i > 0
            && i + 1 < grid.len()
        {
            // the time between the grid's neighbours (the grid's half octave is a 19 %
            // step: a bump at 50 s fitted at 45 s left its tail to a random walk 5× the
            // truth)
            let at = |lt: f64| {
                let s2 = Shapes {
                    gm_t: lt.exp(),
                    ..shapes
                };
                chi(tt, s2).unwrap_or(f64::INFINITY)
            };
            let l0 = sh.gm_t.ln();
            let half = 0.5 * std::f64::consts::LN_2 / GM_GRID.per_octave;
            let lt = super::golden::golden_min(at, l0 - 2.0 * half, l0 + 2.0 * half, GM_T_REL_TOL);
            let refined = Shapes {
                gm_t: lt.exp(),
                ..shapes
            };
            match chi(tt, refined) {
                Some(cr) if cr < c => {
                    consider(Some(GaussMarkov), cur - cr - SELECT_CHI2_GM, refined)
                }
                _ => consider(Some(GaussMarkov), cur - c - SELECT_CHI2_GM, sh),
            }
        }
    }
    if t[BiasInstability] && shapes.b_lo == 0.0 {
        for &lo in corners {
            let sh = Shapes { b_lo: lo, ..shapes };
            if let Some(c) = chi(t, sh) {
                consider(None, cur - c - SELECT_CHI2, sh);
            }
        }
    }
    best
}

/// The final model of a fit, for the checks made under its covariance (`s`): the terms it
/// holds, its shapes and its coefficients (left-out terms at 0, fixed lines at the PSD's).
#[derive(Clone, Copy)]
struct FinalModel<'a> {
    data: &'a FitData<'a>,
    used: &'a [usize],
    cfg: &'a FitConfig,
    s: &'a Solve,
    terms: [bool; TERM_COUNT],
    shapes: Shapes,
    coef: &'a [f64; TERM_COUNT],
}

impl FinalModel<'_> {
    /// B or K only where no Gauss–Markov bias explains the data as well: the model with the
    /// term swapped for a bump (its best correlation time) must fit worse, under the final
    /// model's covariance (`s`), by Akaike's measure (the bump has one more parameter).
    /// Also returns the best correlation time of a bump in place of the flicker floor (NaN
    /// without one), [`FitResult::bump_for_floor`].
    fn ambiguous_terms(&self) -> ([bool; TERM_COUNT], f64) {
        let FinalModel {
            data,
            used,
            cfg,
            s,
            terms,
            shapes,
            coef,
        } = *self;
        let signed = signed_terms(cfg);
        let mut ambiguous = [false; TERM_COUNT];
        let mut bump_for_floor = f64::NAN;
        if cfg.select && cfg.terms[GaussMarkov] {
            let d = if data.basis.is_none() { 1.0 } else { s.delta };
            let grid = shape_grid(data, used, GM_GRID);
            let chi = |tt: [bool; TERM_COUNT], sh: Shapes| {
                fixed_ls(data, used, tt, signed, &s.coef, d, sh).map(|x| x.1)
            };
            if let Some(cur) = chi(terms, shapes) {
                for j in [BiasInstability, RandomWalk] {
                    if !terms[j] || coef[j] == 0.0 {
                        continue;
                    }
                    let mut tt = terms;
                    tt[j] = false;
                    tt[GaussMarkov] = true;
                    let times: Vec<f64> = if terms[GaussMarkov] {
                        vec![shapes.gm_t]
                    } else {
                        grid.clone()
                    };
                    let (alt, at) = times
                        .iter()
                        .filter_map(|&tg| chi(tt, Shapes { gm_t: tg, ..shapes }).map(|c| (c, tg)))
                        .fold(
                            (f64::INFINITY, f64::NAN),
                            |a, b| if b.0 < a.0 { b } else { a },
                        );
                    ambiguous[j] = alt + SWAP_PENALTY <= cur;
                    if j == BiasInstability && !terms[GaussMarkov] {
                        bump_for_floor = at;
                    }
                }
            }
        }
        (ambiguous, bump_for_floor)
    }

    /// The flicker floor's shape as the data leave it: every corner (and the flat floor) whose
    /// fit is within the 95 % profile-likelihood bound of the best one, under the final model's
    /// covariance (`s`) — the terms' intervals span theirs (see [`FitResult`]).
    fn floor_alternatives(&self) -> Vec<ShapeAlternative> {
        let FinalModel {
            data,
            used,
            cfg,
            s,
            terms,
            shapes,
            coef,
        } = *self;
        let signed = signed_terms(cfg);
        let mut alternatives = Vec::new();
        let b = BiasInstability;
        if terms[b] && coef[b] > 0.0 && cfg.flicker_corner && data.basis.is_some() {
            let cands: Vec<f64> = std::iter::once(0.0)
                .chain(shape_grid(data, used, CORNER_GRID))
                .collect();
            let fits: Vec<(f64, FixedLs)> = cands
                .iter()
                .filter_map(|&lo| {
                    let sh = Shapes { b_lo: lo, ..shapes };
                    fixed_ls(data, used, terms, signed, &s.coef, s.delta, sh).map(|f| (lo, f))
                })
                .collect();
            let best = fits.iter().map(|f| f.1.1).fold(f64::INFINITY, f64::min);
            for (lo, (c, chi, _, cv)) in fits {
                if lo != shapes.b_lo && chi - best <= PROFILE_CHI2_95 {
                    alternatives.push(ShapeAlternative {
                        shapes: Shapes { b_lo: lo, ..shapes },
                        coef: c,
                        std_err: std::array::from_fn(|j| cv[j][j].max(0.0).sqrt()),
                    });
                }
            }
        }
        alternatives
    }
}

/// Each term's largest share of the model's Allan variance at a used point (the model
/// rather than the measured points: their scatter at long τ would make a term dominant, or
/// not, by chance). A noise term's share is of the noise: a resonance's tail adds
/// white-like variance at long τ, and must not make the white noise "never dominant".
fn max_shares(
    data: &FitData,
    used: &[usize],
    coef: &[f64; TERM_COUNT],
    shapes: &Shapes,
) -> [f64; TERM_COUNT] {
    let mut noise_coef = *coef;
    for l in NoiseTerm::LINES {
        noise_coef[l] = 0.0;
    }
    std::array::from_fn(|j| {
        used.iter()
            .map(|&i| {
                let tau = data.points[i].tau;
                let noise = !NoiseTerm::at(j).is_line();
                let total = predict(if noise { &noise_coef } else { coef }, shapes, tau);
                if total > 0.0 {
                    (coef[j] * basis_at(j, tau, shapes) / total).max(0.0)
                } else {
                    0.0
                }
            })
            .fold(0.0, f64::max)
    })
}

/// Akaike's penalty for the swapped model's extra parameter (the bump's correlation time):
/// a random walk is a bump whose turn-over lies in the last, noisiest octaves, and with its
/// time free the bump fits such data about as well by chance.
const SWAP_PENALTY: f64 = 2.0;

/// The Gauss–Markov correlation time is refined between its grid neighbours to this share
/// of their span (about 1 % in T).
const GM_T_REL_TOL: f64 = 0.01;

/// χ²(2) quantile at 0.999: the Gauss–Markov bias enters with two parameters, its σ and a
/// correlation time searched over `GM_GRID`, so it must lower χ² by more than this.
pub const SELECT_CHI2_GM: f64 = 13.815_510_557_964_274;
/// Where a shape parameter is searched on a fitted range, relative to its first and last τ,
/// and how finely.
#[derive(Clone, Copy, Debug)]
pub(super) struct ShapeGrid {
    /// Lowest candidate over the range's first τ.
    from_first: f64,
    /// Lowest candidate at all, s.
    floor: f64,
    /// Highest candidate over the range's last τ.
    to_last: f64,
    /// Candidates per octave.
    per_octave: f64,
}

/// Shortest Gauss–Markov correlation time, s. IEEE 952 reads the white noise N on the −½
/// line at τ = 1 s; a Gauss–Markov bias of T ≪ 1 s is white noise there (its Allan variance
/// 2σ²T/τ for τ ≫ T: low-passed white noise), so a bump below 1 s would split N into two
/// and report only the part above 1/(2πT) Hz. Measured on the heavily filtered real
/// accelerometers of `testdata/real_curves`: bumps at 0.2–1 s took up to 20 % of N.
pub const GM_MIN_T: f64 = 1.0;

/// Gauss–Markov correlation times: from 4× the first τ (and [`GM_MIN_T`]) (the rise must be seen) to 1/8 of
/// the last (and the turn-down after the bump; a longer T is a random walk over the
/// record), two per octave.
pub(super) const GM_GRID: ShapeGrid = ShapeGrid {
    from_first: 4.0,
    floor: GM_MIN_T,
    to_last: 1.0 / 8.0,
    per_octave: 2.0,
};
/// Flicker-floor corners: from 1/16 of the first τ (the floor there is still 9 % short,
/// ψ(16) = 0.91) to 1/4 of the last (ψ(4) = 0.67: a floor hardly reached within the range),
/// two per octave.
const CORNER_GRID: ShapeGrid = ShapeGrid {
    from_first: 1.0 / 16.0,
    floor: 0.0,
    to_last: 1.0 / 4.0,
    per_octave: 2.0,
};

/// Candidate values of a shape parameter on the range `used` (empty for short ranges).
fn shape_grid(data: &FitData, used: &[usize], g: ShapeGrid) -> Vec<f64> {
    let (Some(&a), Some(&b)) = (used.first(), used.last()) else {
        return Vec::new();
    };
    let (lo, hi) = (
        (g.from_first * data.points[a].tau).max(g.floor),
        g.to_last * data.points[b].tau,
    );
    let mut out = Vec::new();
    let mut t = lo;
    while t <= hi {
        out.push(t);
        t *= 2f64.powf(1.0 / g.per_octave);
    }
    out
}

/// The model term contributing most AVAR at τ.
pub(crate) fn dominant_term(coef: &[f64; TERM_COUNT], shapes: &Shapes, tau: f64) -> usize {
    (0..TERM_COUNT)
        .max_by(|&x, &y| {
            (coef[x] * basis_at(x, tau, shapes)).total_cmp(&(coef[y] * basis_at(y, tau, shapes)))
        })
        .unwrap_or(1)
}

/// Interval for coefficient j by inverting the test |ĉ − c| ≤ z·se(c), with se(c) the GLS
/// standard error when the truth has c_j = c (the other coefficients at their estimates,
/// the discrepancy δ at its estimate).
///
/// The plain interval ĉ ± z·se(ĉ) is too short above a low estimate: the AVAR variance grows
/// with the term, so an estimate that came out low also reports a small error. Found with a
/// fixed-point iteration (≤ [`INVERSION_MAX_ITER`] covariance evaluations per end). Without a
/// basis, or if the covariance cannot be evaluated, the plain interval is returned.
/// Returns (lo, hi) of the coefficient (a squared term), lo ≥ 0; hi = ∞ when the data bound
/// the term from above at no value (se(c) grows as fast as c/z).
pub(crate) fn inverted_interval(
    data: &FitData,
    res: &FitResult,
    cfg: &FitConfig,
    j: usize,
    z: f64,
) -> (f64, f64) {
    let c_hat = res.coef[j];
    let se_hat = res.cov[j][j].max(0.0).sqrt();
    let plain = ((c_hat - z * se_hat).max(0.0), c_hat + z * se_hat);
    if data.basis.is_none() || res.left_out[j] {
        return plain;
    }
    let free: Vec<usize> = (0..TERM_COUNT).filter(|&t| res.free[t] || t == j).collect();
    let p = Problem::new(data, &res.used, res.shapes);
    let misfit = if cfg.discrepancy {
        1.0
    } else {
        res.chi2_per_dof.max(1.0).sqrt()
    };
    let delta = if cfg.discrepancy { res.delta } else { 0.0 };
    let se_at = |c: f64| -> Option<f64> {
        let mut coef = res.coef;
        coef[j] = c.max(0.0);
        let pred = p.pred(&coef);
        if pred.iter().any(|v| !is_positive(*v)) {
            return None;
        }
        let sigma = p.sigma(&coef);
        let v = p.v(&sigma, delta);
        let (gw, _) = whiten(&v, &p.g, &p.a)?;
        let ones = vec![1.0; gw.len()];
        Some(covariance(&gw, &ones, &free)?[j][j].max(0.0).sqrt() * misfit)
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

#[cfg(test)]
mod tests {
    use super::super::oadev::Overlap;
    use super::linalg::nnls_subsets;
    use super::*;

    /// Noise-free data: the fit must return the generating coefficients to rounding.
    const EXACT_REL_TOL: f64 = 1e-7;

    fn data_for<'a>(
        truth: [f64; 5],
        ms: &[usize],
        tau0: f64,
        cov_basis: Option<&'a CovBasis>,
    ) -> FitData<'a> {
        let points: Vec<FitPoint> = ms
            .iter()
            .map(|&m| {
                let tau = m as f64 * tau0;
                FitPoint {
                    m,
                    tau,
                    avar: NoiseTerm::POWER_LAWS
                        .iter()
                        .map(|&t| truth[t.index()] * basis(t, tau))
                        .sum(),
                }
            })
            .collect();
        let n = points.len();
        FitData {
            points,
            basis: cov_basis,
            basis_index: (0..n).collect(),
            lines: [None; 3],
        }
    }

    #[test]
    fn recovers_exact_model_without_basis() {
        let truth = [1e-8, 2.25e-4, 1e-7, 2.5e-9, 1e-14];
        let ms: Vec<usize> = (0..40).map(|k| 1.4f64.powi(k).round() as usize).collect();
        let mut ms = ms;
        ms.dedup();
        let d = data_for(truth, &ms, 0.005, None);
        let used: Vec<usize> = (0..d.points.len()).collect();
        let r = fit(
            &d,
            &used,
            &FitConfig {
                select: false,
                band_limit: false,
                ..FitConfig::default()
            },
        )
        .unwrap();
        for t in NoiseTerm::POWER_LAWS {
            let j = t.index();
            assert!(
                ((r.coef[t] - truth[j]) / truth[j]).abs() < EXACT_REL_TOL,
                "term {}: expected {:e}, got {:e}",
                t.symbol(),
                truth[j],
                r.coef[t]
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
        let got: Vec<usize> = thin_to_grid(&fine, 2).iter().map(|&i| fine[i]).collect();
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
        let got = thin_to_grid(&odd, 2);
        assert!(
            got.len() + 3 >= coarse.len() && got.len() <= coarse.len() + 1,
            "{} vs {}",
            got.len(),
            coarse.len()
        );
    }

    #[test]
    fn gls_recovers_exact_model_and_keeps_the_whole_range() {
        // noise-free AVAR of a white + random-walk model: GLS, the range choice and the
        // selection must return it
        let truth = [0.0, 2.25e-4, 0.0, 2.5e-9, 0.0];
        let ms: Vec<usize> = (0..20).map(|k| 1usize << k).collect();
        let b = CovBasis::new(&ms, 4_000_000, 0.005, Overlap::Overlapping);
        let d = data_for(truth, &ms, 0.005, Some(&b));
        assert_eq!(choose_start(&d, &FitConfig::default()), 0);
        let used: Vec<usize> = (0..ms.len()).collect();
        let r = fit(&d, &used, &FitConfig::default()).unwrap();
        for t in [WhiteNoise, RandomWalk] {
            let j = t.index();
            assert!(
                ((r.coef[t] - truth[j]) / truth[j]).abs() < EXACT_REL_TOL,
                "term {}: expected {:e}, got {:e}",
                t.symbol(),
                truth[j],
                r.coef[t]
            );
        }
        assert!(
            r.left_out[Quantization] && r.left_out[BiasInstability] && r.left_out[Ramp],
            "nuisance terms must stay out: {:?}",
            r.left_out
        );
        assert_eq!(r.delta, 0.0, "an exact model needs no discrepancy");
        assert!(r.converged);
    }

    #[test]
    fn band_limited_start_is_excluded() {
        // white noise through a first-order low-pass of time constant T (exact AVAR,
        // AVAR = N²/τ·[1 − T/(2τ)(3 − 4e^{−τ/T} + e^{−2τ/T})]) plus a random walk: the
        // points within a few T are not the model's and must be left out, the rest kept
        let (n2, k2, t) = (2.25e-4, 2.5e-9, 0.05);
        let ms: Vec<usize> = (0..20).map(|k| 1usize << k).collect();
        let tau0 = 0.005;
        let b = CovBasis::new(&ms, 4_000_000, tau0, Overlap::Overlapping);
        let mut d = data_for([0.0; 5], &ms, tau0, Some(&b));
        for p in d.points.iter_mut() {
            let x = p.tau / t;
            let filt = 1.0 - (3.0 - 4.0 * (-x).exp() + (-2.0 * x).exp()) / (2.0 * x);
            p.avar = n2 / p.tau * filt + k2 * p.tau / 3.0;
        }
        let s = choose_start(&d, &FitConfig::default());
        let tau_start = d.points[s].tau;
        assert!(
            tau_start > 2.0 * t && tau_start < 40.0 * t,
            "start {tau_start} s for a {t} s filter"
        );
        let used: Vec<usize> = (s..ms.len()).collect();
        let r = fit(&d, &used, &FitConfig::default()).unwrap();
        // the filter's exponential remainder just above the start bends the fitted terms a
        // little (measured: N −0.8 %, K −8 % on these noise-free points)
        const N_FILTER_REL_TOL: f64 = 0.02;
        const K_FILTER_REL_TOL: f64 = 0.10;
        assert!(
            (r.coef[WhiteNoise].sqrt() / n2.sqrt() - 1.0).abs() < N_FILTER_REL_TOL,
            "N² {:e} vs {n2:e}",
            r.coef[WhiteNoise]
        );
        assert!(
            (r.coef[RandomWalk].sqrt() / k2.sqrt() - 1.0).abs() < K_FILTER_REL_TOL,
            "K² {:e} vs {k2:e}",
            r.coef[RandomWalk]
        );
    }

    #[test]
    fn flicker_band_matches_a_sum_of_gauss_markov_biases() {
        // the slow version: the construction itself, a sum of unit Gauss–Markov AVARs with
        // correlation times 64 per octave from T_lo to 10⁸·T_lo, each weighted by its share
        // of ln T, over the integral of all of them (2 ln2)
        const STEPS_PER_OCTAVE: f64 = 64.0;
        // the sum's own quadrature error (midpoint rule in ln T, cut at 10⁸·T_lo: 1e-8)
        const SUM_REL_TOL: f64 = 1e-4;
        let slow = |x: f64| {
            let h = std::f64::consts::LN_2 / STEPS_PER_OCTAVE;
            let steps = (1e8f64.ln() / h) as usize;
            let s: f64 = (0..steps)
                .map(|i| gm_basis(x, ((i as f64 + 0.5) * h).exp()) * h)
                .sum();
            s / (2.0 * std::f64::consts::LN_2)
        };
        for x in [1e-3, 0.01, 0.05, 0.3, 1.0, 3.0, 9.9, 10.0, 40.0, 1e3] {
            let (a, b) = (flicker_band(x), slow(x));
            assert!((a / b - 1.0).abs() < SUM_REL_TOL, "x {x}: {a} vs {b}");
        }
        assert_eq!(flicker_band(0.0), 0.0);
    }

    #[test]
    fn finds_the_flicker_floor_corner() {
        // noise-free white + flicker with a lower corner at 5 s + random walk (white meets
        // the floor at 57 s, the floor meets the random walk at 5000 s): the corner must be
        // found (on the 2-per-octave grid: within a factor √2) and N, B not traded
        let (n2, b2, k2, lo) = (1e-6, 4e-8, 1e-11, 5.0);
        let ms: Vec<usize> = (0..22).map(|k| 1usize << k).collect();
        let tau0 = 0.005;
        let b = CovBasis::new(&ms, 16_000_000, tau0, Overlap::Overlapping);
        let mut d = data_for([0.0; 5], &ms, tau0, Some(&b));
        let shapes = Shapes {
            b_lo: lo,
            ..Shapes::FLAT
        };
        for p in d.points.iter_mut() {
            let mut c = [0.0; TERM_COUNT];
            (c[WhiteNoise], c[BiasInstability], c[RandomWalk]) = (n2, b2, k2);
            p.avar = predict(&c, &shapes, p.tau);
        }
        let used: Vec<usize> = (0..ms.len()).collect();
        let r = fit(&d, &used, &FitConfig::default()).unwrap();
        assert!(
            r.shapes.b_lo > lo / 2f64.sqrt() && r.shapes.b_lo < lo * 2f64.sqrt(),
            "corner {} s for {lo} s",
            r.shapes.b_lo
        );
        // the grid step leaves a little shape error: measured N 0.1 %, B 1 %
        const N_GRID_REL_TOL: f64 = 0.01;
        const B_GRID_REL_TOL: f64 = 0.05;
        assert!(
            (r.coef[WhiteNoise] / n2).sqrt() - 1.0 < N_GRID_REL_TOL,
            "{:e}",
            r.coef[WhiteNoise]
        );
        assert!(
            ((r.coef[BiasInstability] / b2).sqrt() - 1.0).abs() < B_GRID_REL_TOL,
            "{:e}",
            r.coef[BiasInstability]
        );
        // the flat-floor model misses it: N low
        let flat = fit(
            &d,
            &used,
            &FitConfig {
                flicker_corner: false,
                ..FitConfig::default()
            },
        )
        .unwrap();
        assert!(
            flat.coef[WhiteNoise] < r.coef[WhiteNoise],
            "{:e} vs {:e}",
            flat.coef[WhiteNoise],
            r.coef[WhiteNoise]
        );
    }

    #[test]
    fn nnls_subsets_matches_brute_force_grid() {
        // a 2-term case where the unconstrained solution is negative: y = 1/τ data with a dip
        let g: Vec<[f64; TERM_COUNT]> = (1..20)
            .map(|k| std::array::from_fn(|j| basis(NoiseTerm::at(j), k as f64)))
            .collect();
        let a: Vec<f64> = (1..20)
            .map(|k| 1.0 / k as f64 - 0.01 * k as f64 / 3.0)
            .collect();
        let w = vec![1.0; g.len()];
        let (n, k) = (WhiteNoise, RandomWalk);
        let c = nnls_subsets(
            &g,
            &a,
            &w,
            &[n.index(), k.index()],
            &[false; TERM_COUNT],
            &|_| true,
        )
        .unwrap();
        assert_eq!(c[k], 0.0, "K must be clamped at 0");
        // with K = 0, N² is the 1-D LS solution
        let num: f64 = g.iter().zip(&a).map(|(gi, ai)| gi[n] * ai).sum();
        let den: f64 = g.iter().map(|gi| gi[n] * gi[n]).sum();
        assert!((c[n] - num / den).abs() < 1e-12);
    }
}
