//! One generalised least-squares solve of the fit (see the module docs of [`super`],
//! "Weighting"): the problem on a set of curve points ([`Problem`]: the terms' basis, the
//! data with the fixed lines taken off, the statistical covariance Σ(c) and V = Σ + δ²·D),
//! the re-weighted GLS with the discrepancy δ set to zero, given or estimated ([`gls`]),
//! and the least squares under one covariance held fixed that the nested-model tests
//! compare ([`fixed_ls`]).

// Small dense matrix code (Cholesky, normal equations) reads best with explicit indices.
#![allow(clippy::needless_range_loop)]

use super::NoiseTerm::{self, BiasInstability, GaussMarkov, Quantization, Ramp};
use super::linalg::{covariance, nnls_subsets, whiten};
use super::{FitData, Shapes, TERM_COUNT, basis_at, effective_coef, is_positive};

/// Iterations of the discrepancy root-finding (bisection in log δ over 18 e-folds: 2⁻³⁰ of
/// that is a relative precision of 2e-8 in δ).
const DELTA_BISECT: usize = 30;
/// Bracket of δ: far below any useful precision, and 10× the value itself.
const DELTA_RANGE: (f64, f64) = (1e-7, 10.0);
/// The re-weighting stops when no coefficient moves by more than this fraction.
const GLS_REL_TOL: f64 = 1e-6;

/// How δ is set in one solve.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Delta {
    /// Statistical covariance only.
    Zero,
    /// Given.
    Fixed(f64),
    /// Estimated (χ²/dof = 1).
    Estimate,
}

/// One GLS solve.
#[derive(Clone, Debug)]
pub(super) struct Solve {
    pub(super) coef: [f64; TERM_COUNT],
    pub(super) cov: [[f64; TERM_COUNT]; TERM_COUNT],
    /// χ² with the covariance used (Σ + δ²D).
    pub(super) chi2: f64,
    /// χ² with Σ alone (NaN without a basis).
    pub(super) chi2_stat: f64,
    pub(super) dof: usize,
    pub(super) delta: f64,
    pub(super) iterations: usize,
    pub(super) converged: bool,
}

pub(super) struct Problem<'d, 'a> {
    data: &'d FitData<'a>,
    sel: Vec<usize>,
    pub(super) g: Vec<[f64; TERM_COUNT]>,
    pub(super) a: Vec<f64>,
    shapes: Shapes,
}

impl<'d, 'a> Problem<'d, 'a> {
    /// The problem on the points `sel` and the terms fitted in it (those `enabled` that have
    /// a shape); `None` without a term or with no more points than terms.
    fn with_terms(
        data: &'d FitData<'a>,
        sel: &[usize],
        enabled: [bool; TERM_COUNT],
        shapes: Shapes,
    ) -> Option<(Self, Vec<usize>)> {
        let terms: Vec<usize> = (0..TERM_COUNT)
            .filter(|&j| enabled[j] && shapes.has(j))
            .collect();
        if terms.is_empty() || sel.len() < terms.len() + 1 {
            return None;
        }
        Some((Problem::new(data, sel, shapes), terms))
    }

    /// The points `sel` of `data` under `shapes`; the fixed lines' Allan variance is taken
    /// off the data (their columns are zero: they are not solved for).
    pub(super) fn new(data: &'d FitData<'a>, sel: &[usize], shapes: Shapes) -> Self {
        let fixed = shapes.fixed_coef();
        let g = sel
            .iter()
            .map(|&i| {
                std::array::from_fn(|j| {
                    if fixed[j] != 0.0 {
                        0.0
                    } else {
                        basis_at(j, data.points[i].tau, &shapes)
                    }
                })
            })
            .collect();
        let a = sel
            .iter()
            .map(|&i| {
                let tau = data.points[i].tau;
                data.points[i].avar
                    - (0..TERM_COUNT)
                        .map(|j| fixed[j] * basis_at(j, tau, &shapes))
                        .sum::<f64>()
            })
            .collect();
        Problem {
            data,
            sel: sel.to_vec(),
            g,
            a,
            shapes,
        }
    }

    pub(super) fn pred(&self, c: &[f64; TERM_COUNT]) -> Vec<f64> {
        self.g
            .iter()
            .map(|gi| (0..TERM_COUNT).map(|j| c[j] * gi[j]).sum())
            .collect()
    }

    /// Statistical covariance at c (the 1/τ² component only where it is a positive Q).
    pub(super) fn sigma(&self, c: &[f64; TERM_COUNT]) -> Option<Vec<Vec<f64>>> {
        let v = self.sigma_terms(c)?;
        Some(self.with_line_variance(c, v))
    }

    /// A resonance's own estimate varies like a narrow-band noise's: 2·(its AVAR)²/ν on the
    /// diagonal, ν = [`LineShape::edf`](super::LineShape::edf) (its white-noise stand-in in the covariance has the
    /// EDF of white noise, far more).
    fn with_line_variance(&self, c: &[f64; TERM_COUNT], mut v: Vec<Vec<f64>>) -> Vec<Vec<f64>> {
        let fixed = self.shapes.fixed_coef();
        for (k, &i) in self.sel.iter().enumerate() {
            let tau = self.data.points[i].tau;
            for (s, l) in self.shapes.lines.iter().enumerate() {
                if let Some(l) = l
                    && l.bandwidth > 0.0
                {
                    let coef = if l.fixed() {
                        fixed[NoiseTerm::Line(s)]
                    } else {
                        c[NoiseTerm::Line(s)]
                    };
                    let a = coef.max(0.0) * l.avar(tau);
                    v[k][k] += 2.0 * a * a / l.edf();
                }
            }
        }
        v
    }

    /// The covariance of the power laws (and the lines' white-noise stand-ins) at c.
    fn sigma_terms(&self, c: &[f64; TERM_COUNT]) -> Option<Vec<Vec<f64>>> {
        let b = self.data.basis?;
        let mut cp = *c;
        cp[Quantization] = cp[Quantization].max(0.0);
        let fixed = self.shapes.fixed_coef();
        for l in NoiseTerm::LINES {
            if fixed[l] != 0.0 {
                cp[l] = fixed[l];
            }
        }
        let idx: Vec<usize> = self.sel.iter().map(|&i| self.data.basis_index[i]).collect();
        let shaped = (cp[BiasInstability] != 0.0 && self.shapes.b_lo > 0.0)
            || cp[GaussMarkov] != 0.0
            || cp[Ramp] != 0.0
            || NoiseTerm::LINES.iter().any(|&l| cp[l] != 0.0);
        if !shaped {
            return Some(b.cov(&idx, &cp));
        }
        let per: Vec<[f64; TERM_COUNT]> = self
            .sel
            .iter()
            .map(|&i| effective_coef(&cp, &self.shapes, self.data.points[i].tau))
            .collect();
        Some(b.cov_pointwise(&idx, &per))
    }

    /// V = Σ + δ²·diag(A²) with A the measured AVAR; without a basis, diag(A²) alone (δ
    /// factored out). The discrepancy is a fraction of the curve as measured: scaling it by
    /// the model instead lets a model that overshoots a stretch of the curve weight that
    /// stretch down and run away from it.
    pub(super) fn v(&self, sigma: &Option<Vec<Vec<f64>>>, delta: f64) -> Vec<Vec<f64>> {
        let k = self.a.len();
        match sigma {
            Some(s) => {
                let mut v = s.clone();
                for i in 0..k {
                    v[i][i] += delta * delta * self.a[i] * self.a[i];
                }
                v
            }
            None => {
                let mut v = vec![vec![0.0; k]; k];
                for i in 0..k {
                    v[i][i] = self.a[i] * self.a[i];
                }
                v
            }
        }
    }
}

/// χ² = rᵀV⁻¹r.
fn chi2_of(v: &[Vec<f64>], r: &[f64]) -> Option<f64> {
    let (_, rw) = whiten(v, &[], r)?;
    Some(rw.iter().map(|x| x * x).sum())
}

/// δ ≥ 0 with rᵀ(Σ + δ²·diag(A²))⁻¹r = dof (0 when already ≤ dof).
fn solve_delta(sigma: &[Vec<f64>], a: &[f64], r: &[f64], dof: usize) -> f64 {
    let target = dof.max(1) as f64;
    let at = |d: f64| -> f64 {
        let mut v = sigma.to_vec();
        for i in 0..a.len() {
            v[i][i] += d * d * a[i] * a[i];
        }
        chi2_of(&v, r).unwrap_or(f64::INFINITY)
    };
    if at(0.0) <= target {
        return 0.0;
    }
    let (mut lo, mut hi) = (DELTA_RANGE.0.ln(), DELTA_RANGE.1.ln());
    if at(DELTA_RANGE.1) > target {
        return DELTA_RANGE.1;
    }
    for _ in 0..DELTA_BISECT {
        let mid = 0.5 * (lo + hi);
        if at(mid.exp()) > target {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    hi.exp()
}

/// GLS of the terms `enabled` (those in `signed` may be negative) on the points `sel`.
#[allow(clippy::too_many_arguments)]
pub(super) fn gls(
    data: &FitData,
    sel: &[usize],
    enabled: [bool; TERM_COUNT],
    signed: [bool; TERM_COUNT],
    delta_mode: Delta,
    max_iter: usize,
    shapes: Shapes,
) -> Option<Solve> {
    let (p, terms) = Problem::with_terms(data, sel, enabled, shapes)?;
    let (coef, mut delta, iterations, converged) =
        reweight(&p, &terms, signed, delta_mode, max_iter)?;
    let no_basis = data.basis.is_none();
    let pred = p.pred(&coef);
    let sigma = p.sigma(&coef);
    let nfree = (0..TERM_COUNT).filter(|&j| coef[j] != 0.0).count();
    let dof = sel.len().saturating_sub(nfree);
    let r: Vec<f64> = p.a.iter().zip(&pred).map(|(a, q)| a - q).collect();
    if delta_mode == Delta::Estimate {
        delta = match &sigma {
            Some(s) => solve_delta(s, &p.a, &r, dof),
            // relative least squares: δ² = Σ(r/A)²/dof
            None => (r
                .iter()
                .zip(&p.a)
                .map(|(ri, q)| (ri / q).powi(2))
                .sum::<f64>()
                / dof.max(1) as f64)
                .sqrt(),
        };
    }
    let v = p.v(&sigma, delta);
    let (gw, _) = whiten(&v, &p.g, &p.a)?;
    let ones = vec![1.0; gw.len()];
    let free_terms: Vec<usize> = terms.iter().copied().filter(|&j| coef[j] != 0.0).collect();
    let mut cov = if free_terms.is_empty() {
        [[0.0; TERM_COUNT]; TERM_COUNT]
    } else {
        covariance(&gw, &ones, &free_terms)?
    };
    if no_basis {
        // the weights are relative: scale by δ² (no statistical meaning, kept for the record)
        for row in cov.iter_mut() {
            for v in row.iter_mut() {
                *v *= delta * delta;
            }
        }
    }
    let chi2 = if no_basis {
        if delta > 0.0 {
            chi2_of(&v, &r)? / (delta * delta)
        } else {
            0.0
        }
    } else {
        chi2_of(&v, &r)?
    };
    let chi2_stat = match &sigma {
        Some(s) => chi2_of(s, &r).unwrap_or(f64::NAN),
        None => f64::NAN,
    };
    Some(Solve {
        coef,
        cov,
        chi2,
        chi2_stat,
        dof,
        delta,
        iterations,
        converged,
    })
}

/// The re-weighting of [`gls`] on `p`: from relative weights 1/A², each step solves under
/// the covariance at the coefficients before it (δ re-estimated with
/// [`Delta::Estimate`]) until no coefficient moves by [`GLS_REL_TOL`] or `max_iter` steps.
/// Returns the coefficients, δ, the steps taken and whether they converged.
fn reweight(
    p: &Problem,
    terms: &[usize],
    signed: [bool; TERM_COUNT],
    delta_mode: Delta,
    max_iter: usize,
) -> Option<([f64; TERM_COUNT], f64, usize, bool)> {
    let sel = &p.sel;
    let feasible = |c: &[f64; TERM_COUNT]| p.pred(c).iter().all(|v| is_positive(*v));
    // start: relative weights 1/A²
    let w0: Vec<f64> = p.a.iter().map(|a| 1.0 / (a * a)).collect();
    let mut coef = nnls_subsets(&p.g, &p.a, &w0, terms, &signed, &feasible)?;
    let no_basis = p.data.basis.is_none();
    let mut delta = match delta_mode {
        Delta::Fixed(d) => d,
        _ => 0.0,
    };
    let mut iterations = 0;
    let mut converged = false;
    for _ in 0..max_iter {
        iterations += 1;
        let pred = p.pred(&coef);
        let sigma = p.sigma(&coef);
        if delta_mode == Delta::Estimate && !no_basis {
            let r: Vec<f64> = p.a.iter().zip(&pred).map(|(a, q)| a - q).collect();
            let nfree = (0..TERM_COUNT).filter(|&j| coef[j] != 0.0).count();
            delta = solve_delta(sigma.as_ref()?, &p.a, &r, sel.len().saturating_sub(nfree));
        }
        let v = p.v(&sigma, delta);
        let (gw, aw) = whiten(&v, &p.g, &p.a)?;
        let ones = vec![1.0; gw.len()];
        let new = nnls_subsets(&gw, &aw, &ones, terms, &signed, &feasible)?;
        let change = (0..TERM_COUNT)
            .filter(|&j| new[j] != 0.0 || coef[j] != 0.0)
            .map(|j| ((new[j] - coef[j]) / new[j].abs().max(coef[j].abs())).abs())
            .fold(0.0, f64::max);
        coef = new;
        if change < GLS_REL_TOL {
            converged = true;
            break;
        }
    }
    Some((coef, delta, iterations, converged))
}

/// Weighted least squares of the terms `enabled` on `sel` with the covariance held fixed at
/// the coefficients `at` and discrepancy `delta` (no re-weighting): the χ² of nested models
/// under one covariance, so that their difference is a likelihood-ratio statistic (with the
/// covariance re-evaluated per model, a model could lower its χ² by inflating its own
/// variances). Returns the coefficients, χ², the whitened residuals and the coefficients'
/// covariance.
#[allow(clippy::too_many_arguments)]
pub(super) fn fixed_ls(
    data: &FitData,
    sel: &[usize],
    enabled: [bool; TERM_COUNT],
    signed: [bool; TERM_COUNT],
    at: &[f64; TERM_COUNT],
    delta: f64,
    shapes: Shapes,
) -> Option<FixedLs> {
    let (p, terms) = Problem::with_terms(data, sel, enabled, shapes)?;
    let feasible = |c: &[f64; TERM_COUNT]| p.pred(c).iter().all(|v| is_positive(*v));
    let sigma = p.sigma(at);
    let v = p.v(&sigma, delta);
    let (gw, aw) = whiten(&v, &p.g, &p.a)?;
    let ones = vec![1.0; gw.len()];
    let c = nnls_subsets(&gw, &aw, &ones, &terms, &signed, &feasible)?;
    let r: Vec<f64> = p.a.iter().zip(p.pred(&c)).map(|(a, q)| a - q).collect();
    let (_, rw) = whiten(&v, &[], &r)?;
    let chi2 = rw.iter().map(|x| x * x).sum::<f64>()
        / if data.basis.is_none() {
            delta * delta
        } else {
            1.0
        };
    let free: Vec<usize> = terms.iter().copied().filter(|&j| c[j] != 0.0).collect();
    let cov = if free.is_empty() {
        [[0.0; TERM_COUNT]; TERM_COUNT]
    } else {
        covariance(&gw, &ones, &free)?
    };
    Some((c, chi2, rw, cov))
}

/// What [`fixed_ls`] returns: coefficients, χ², whitened residuals, covariance.
pub(super) type FixedLs = (
    [f64; TERM_COUNT],
    f64,
    Vec<f64>,
    [[f64; TERM_COUNT]; TERM_COUNT],
);
