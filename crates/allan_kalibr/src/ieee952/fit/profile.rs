//! The terms' 95 % intervals and upper bounds: profiles of a likelihood of the curve under
//! the joint model, the other terms refitted at each value of the term.
//!
//! **Why not the coefficient's standard error.** An Allan variance estimate with ν degrees
//! of freedom is A·χ²(ν)/ν: at long τ ν is a few, the estimate strongly skewed, and its
//! variance grows with the term that dominates there. A Gaussian interval ĉ ± z·se(ĉ) — or
//! one with se evaluated at the end it tests — is too short on the side the skew hides: an
//! unresolved random walk's bound came out below the truth on a fifth of the axes of a
//! flicker + random-walk study. And the minimum over τ of each point's upper 95 % limit is
//! not a 95 % bound at all: the least of dozens of pointwise limits is below the truth far
//! more often than one time in twenty.
//!
//! **The statistic.** At coefficients c every point of the fitted range has the model's
//! Allan variance M(c), its exact variance Σᵢᵢ(c) ([`super::super::avar_cov`], plus the
//! discrepancy δ²Aᵢ² the fit estimated) and so ν = 2M²/Σᵢᵢ. By Wilson and Hilferty
//! (1931), (χ²(ν)/ν)^⅓ is close to normal with mean 1 − 2/(9ν) and variance 2/(9ν) for
//! every ν ≥ 1 (its one-sided 5 % quantile is within 2 % of χ²'s for ν ≥ 3, and on the
//! safe side below), so
//!
//! ```text
//! zᵢ = ((Aᵢ/Mᵢ)^⅓ − (1 − 2/(9νᵢ))) / sᵢ,   sᵢ² = (Vᵢᵢ/Mᵢ²)/9,   D(c) = zᵀ R(c)⁻¹ z
//! ```
//!
//! with R(c) the correlation of the points under the model (neighbouring overlapping
//! estimates share most of their data). For one point this is the exact pivot of its χ²
//! interval (Stable32's), so a term read off the last few points gets the skewed interval
//! those points allow; for many precise points it is the usual GLS χ². The variance is
//! always the one at the c being tested (a model that overshoots the long end cannot lower
//! D by inflating its own variance: sᵢ is relative to Mᵢ).
//!
//! **The profile.** For a term j and a value c_j, P(c_j) is D minimised over the other
//! coefficients — the fit's terms, non-negative where the fit's are, and always a flicker
//! floor B (with the fit's floor shape) whether the selection took it or not: every real
//! sensor has one, and a K conditional on a model without it leans on the selection (a flat
//! flicker floor read as a Gauss–Markov shoulder plus a random walk gave K intervals 3×
//! above the truth). The minimisation alternates: the weights (νᵢ, sᵢ, R) at the current
//! coefficients, then Gauss–Newton steps on z with them held (each step halved until D
//! falls: a descent), [`OUTER_PASSES`] times — so the variance follows the profiled value,
//! its scale exactly (sᵢ is relative to Mᵢ) and its composition (νᵢ: a random walk's
//! estimate has fewer degrees of freedom than white noise's) pass by pass. The interval is
//! where P − min P stays below χ²(1) at 95 % ([`TWO_SIDED_95`]: both ends of a resolved
//! term) and the upper bound of an unresolved term where it reaches the one-sided 95 %
//! level ([`ONE_SIDED_95`]).

// Small dense matrix code reads best with explicit indices.
#![allow(clippy::needless_range_loop)]

use super::NoiseTerm::{self, BiasInstability, GaussMarkov, RandomWalk, WhiteNoise};
use super::gls::Problem;
use super::linalg::nnls_subsets;
use super::{
    FitConfig, FitData, FitResult, GM_GRID, Shapes, TERM_COUNT, is_positive, signed_terms,
};

/// χ²(1) at 0.95: the two ends of a 95 % interval.
pub const TWO_SIDED_95: f64 = 3.841_458_820_694_124;
/// χ²(1) at 0.90 (z = 1.645 squared): a one-sided 95 % upper bound.
pub const ONE_SIDED_95: f64 = 2.705_543_454_095_404;
/// Passes of weights then Gauss–Newton steps per profile point.
pub const OUTER_PASSES: usize = 3;
/// Gauss–Newton steps per pass at most (warm-started: two or three suffice).
const GN_MAX_STEPS: usize = 10;
/// Halvings of a step that does not lower D before giving up.
const GN_HALVINGS: usize = 6;
/// A pass is converged when a step lowers D by less than this (D is a χ²).
const GN_TOL: f64 = 1e-7;
/// Bisection steps of an interval end in log of the term's value (from a factor-2
/// bracket: 2^(−8) relative, 0.3 %).
const END_BISECT: usize = 8;
/// Doublings of the term's value tried while bracketing an upper end (4096×).
const END_EXPAND: usize = 12;

/// The profile of the terms on one fitted range: one [`Variant`] per plausible shape of
/// the model (the Gauss–Markov bias's correlation time, see the module docs), and the least
/// D over all of them.
pub(crate) struct Profile<'d, 'a> {
    variants: Vec<Variant<'d, 'a>>,
    d_min: f64,
}

/// The profile machinery under one set of shapes.
struct Variant<'d, 'a> {
    /// Used for this term's interval only (None: for every term).
    only: Option<usize>,
    p: Problem<'d, 'a>,
    delta: f64,
    /// Terms free in the profile's model.
    free: Vec<usize>,
    /// Terms that can be profiled (held at a value while the free ones are refitted):
    /// those with a shape (the Gauss–Markov bias only with the fit's correlation time).
    can: [bool; TERM_COUNT],
    signed: [bool; TERM_COUNT],
    /// The minimum of D and its coefficients.
    d_min: f64,
    c_min: [f64; TERM_COUNT],
    /// The fit's coefficients (the start of every profile).
    start: [f64; TERM_COUNT],
}

/// The weights of D at one c: each point's W–H mean 1 − 2/(9ν) and scale s, and the
/// Cholesky factor of the points' correlation R.
struct Weights {
    mu: Vec<f64>,
    s: Vec<f64>,
    chol: Vec<Vec<f64>>,
}

impl Weights {
    /// L⁻¹x.
    fn whiten(&self, x: &[f64]) -> Vec<f64> {
        let k = x.len();
        let mut y = vec![0.0; k];
        for i in 0..k {
            let mut v = x[i];
            for p in 0..i {
                v -= self.chol[i][p] * y[p];
            }
            y[i] = v / self.chol[i][i];
        }
        y
    }
}

impl<'d, 'a> Profile<'d, 'a> {
    /// The profile of the fit `res` on its range (None without a statistical covariance
    /// or where the model has no feasible minimum).
    pub(crate) fn new(
        data: &'d FitData<'a>,
        res: &FitResult,
        cfg: &FitConfig,
    ) -> Option<Profile<'d, 'a>> {
        Self::on(data, res, cfg, &res.used)
    }

    /// The profile on the points of the fit's range from τ = `from` on only (None with
    /// fewer than [`BEYOND_MIN_POINTS`] of them): where a Gauss–Markov bias has turned into
    /// white noise, a random walk the long end shows beyond the bump (module docs).
    pub(crate) fn beyond(
        data: &'d FitData<'a>,
        res: &FitResult,
        cfg: &FitConfig,
        from: f64,
    ) -> Option<Profile<'d, 'a>> {
        let used: Vec<usize> = res
            .used
            .iter()
            .copied()
            .filter(|&i| data.points[i].tau >= from * (1.0 - 1e-12))
            .collect();
        (used.len() >= BEYOND_MIN_POINTS).then(|| Self::on(data, res, cfg, &used))?
    }

    /// The profile of the fit `res` on the points `used` of its range.
    fn on(
        data: &'d FitData<'a>,
        res: &FitResult,
        cfg: &FitConfig,
        used: &[usize],
    ) -> Option<Profile<'d, 'a>> {
        data.basis?;
        let mut shapes = vec![res.shapes];
        if res.coef[GaussMarkov] != 0.0 && res.shapes.gm_t.is_finite() {
            // the correlation time is a parameter too: the fit's ± an octave in eighths
            // of an octave, within the times the fit searches
            let (first, last) = (
                data.points[res.used[0]].tau,
                data.points[res.used[res.used.len() - 1]].tau,
            );
            // (the times the fit searched, whatever points this profile uses)
            let (lo, hi) = (
                (GM_GRID.from_first * first).max(GM_GRID.floor),
                GM_GRID.to_last * last,
            );
            for k in (-GM_T_STEPS..=GM_T_STEPS).filter(|&k| k != 0) {
                let t = res.shapes.gm_t * 2f64.powf(k as f64 / GM_T_PER_OCTAVE);
                if t >= lo && t <= hi {
                    shapes.push(Shapes {
                        gm_t: t,
                        ..res.shapes
                    });
                }
            }
        }
        let mut variants: Vec<Variant> = shapes
            .into_iter()
            .filter_map(|sh| Variant::new(data, res, cfg, sh, used))
            .collect();
        // for the flicker floor's interval: the model with a bump beside it, at the time
        // that explains the floor best (B's only: a bump beside the floor is no statement
        // on the other terms)
        if res.bump_for_floor.is_finite() && res.coef[GaussMarkov] == 0.0 && cfg.terms[GaussMarkov]
        {
            let sh = Shapes {
                gm_t: res.bump_for_floor,
                ..res.shapes
            };
            if let Some(mut v) = Variant::new(data, res, cfg, sh, used) {
                v.only = Some(BiasInstability.index());
                variants.push(v);
            }
        }
        let d_min = variants
            .iter()
            .filter(|v| v.only.is_none())
            .map(|v| v.d_min)
            .fold(f64::INFINITY, f64::min);
        (!variants.is_empty()).then_some(Profile { variants, d_min })
    }

    /// The interval of term `j`'s coefficient where the profile over every variant, less
    /// its least D, stays within `level` (a χ²(1) level: [`TWO_SIDED_95`] or
    /// [`ONE_SIDED_95`]): the union of each plausible variant's interval against the
    /// common minimum. The lower end only when `lower`, else 0; `guess` is a coefficient
    /// near the upper end.
    pub(crate) fn interval(&self, j: usize, level: f64, lower: bool, guess: f64) -> (f64, f64) {
        let mut out: Option<(f64, f64)> = None;
        for v in self
            .variants
            .iter()
            .filter(|v| v.d_min - self.d_min <= level)
        {
            let (lo, hi) = v.interval(j, level, lower, guess, self.d_min);
            out = Some(out.map_or((lo, hi), |(a, b)| (a.min(lo), b.max(hi))));
        }
        out.unwrap_or((0.0, f64::INFINITY))
    }

    /// Whether the value `cj` of term `j`'s coefficient is within `level` of the least D
    /// (in some plausible variant).
    pub(crate) fn allows(&self, j: usize, cj: f64, level: f64) -> bool {
        self.variants
            .iter()
            .filter(|v| v.only.is_none_or(|o| o == j) && v.d_min - self.d_min <= level)
            .any(|v| {
                let mut seen = vec![(v.c_min[j], v.c_min)];
                v.at(j, cj, &mut seen)
                    .is_some_and(|d| d - self.d_min <= level)
            })
    }

    /// Whether term `j` can be profiled.
    pub(crate) fn has(&self, j: usize) -> bool {
        self.variants[0].can[j]
    }
}

/// Fewest points of a profile beyond a bump ([`Profile::beyond`]).
pub const BEYOND_MIN_POINTS: usize = 5;

/// Correlation times of the Gauss–Markov bias tried either side of the fit's, in steps of
/// 1/[`GM_T_PER_OCTAVE`] octave (a bump's time is known to a few percent: D rises by 3
/// from 45 s to 50 s on a 4 h record of one at 50 s).
const GM_T_STEPS: i32 = 8;
/// Steps per octave of the correlation times tried.
const GM_T_PER_OCTAVE: f64 = 8.0;

impl<'d, 'a> Variant<'d, 'a> {
    /// The variant of the fit `res` with the shapes `shapes`.
    fn new(
        data: &'d FitData<'a>,
        res: &FitResult,
        cfg: &FitConfig,
        shapes: Shapes,
        used: &[usize],
    ) -> Option<Variant<'d, 'a>> {
        let p = Problem::new(data, used, shapes);
        // the fit's terms, N and K always, a flicker floor, and a bump where these shapes
        // hold one
        let free: Vec<usize> = (0..TERM_COUNT)
            .filter(|&j| cfg.terms[j] && shapes.has(j))
            .filter(|&j| {
                let t = NoiseTerm::at(j);
                res.coef[j] != 0.0
                    || matches!(t, WhiteNoise | BiasInstability | RandomWalk)
                    || (t == GaussMarkov && shapes.gm_t.is_finite())
            })
            .collect();
        let delta = if res.delta.is_finite() {
            res.delta
        } else {
            0.0
        };
        let start = res.coef;
        let can = std::array::from_fn(|j| {
            cfg.terms[j] && shapes.has(j) && (j != GaussMarkov.index() || shapes.gm_t.is_finite())
        });
        let mut pr = Variant {
            only: None,
            p,
            delta,
            free,
            can,
            signed: signed_terms(cfg),
            d_min: f64::INFINITY,
            c_min: start,
            start,
        };
        let (d, c) = pr.minimise(None, &start)?;
        pr.d_min = d;
        pr.c_min = c;
        Some(pr)
    }

    /// The weights of D at `c` (None where the model is not positive at a point or the
    /// covariance cannot be factored).
    fn weights(&self, c: &[f64; TERM_COUNT]) -> Option<Weights> {
        let m = self.p.pred(c);
        if m.iter().any(|v| !is_positive(*v)) {
            return None;
        }
        let sigma = self.p.sigma(c)?;
        let v = self.p.v(&Some(sigma.clone()), self.delta);
        let k = m.len();
        let mut mu = vec![0.0; k];
        let mut s = vec![0.0; k];
        for i in 0..k {
            let nu = 2.0 * m[i] * m[i] / sigma[i][i];
            s[i] = (v[i][i] / (m[i] * m[i]) / 9.0).sqrt();
            if !(is_positive(nu) && is_positive(s[i])) {
                return None;
            }
            mu[i] = 1.0 - 2.0 / (9.0 * nu);
        }
        // Cholesky of the correlation (a tiny ridge, as the fit's whitening)
        let mut l = vec![vec![0.0; k]; k];
        for i in 0..k {
            for j in 0..=i {
                let mut x = v[i][j] / (v[i][i] * v[j][j]).sqrt() + if i == j { 1e-10 } else { 0.0 };
                for q in 0..j {
                    x -= l[i][q] * l[j][q];
                }
                if i == j {
                    if !is_positive(x) {
                        return None;
                    }
                    l[i][i] = x.sqrt();
                } else {
                    l[i][j] = x / l[j][j];
                }
            }
        }
        Some(Weights { mu, s, chol: l })
    }

    /// z at `c` under `w` (None where the model is not positive).
    fn z(&self, w: &Weights, c: &[f64; TERM_COUNT]) -> Option<(Vec<f64>, Vec<f64>)> {
        let m = self.p.pred(c);
        if m.iter().any(|v| !is_positive(*v)) {
            return None;
        }
        let k = m.len();
        let mut z = vec![0.0; k];
        let mut dz_dm = vec![0.0; k];
        for i in 0..k {
            let r = (self.p.a[i] / m[i]).cbrt();
            z[i] = (r - w.mu[i]) / w.s[i];
            dz_dm[i] = -r / (3.0 * m[i] * w.s[i]);
        }
        Some((z, dz_dm))
    }

    /// D = zᵀR⁻¹z at `c` under `w`.
    fn d_under(&self, w: &Weights, c: &[f64; TERM_COUNT]) -> Option<f64> {
        let (z, _) = self.z(w, c)?;
        Some(w.whiten(&z).iter().map(|x| x * x).sum())
    }

    /// min D over the free terms with term `fixed` (index, coefficient) held, from `c0`
    /// (module docs). Returns D (with the weights at the minimum) and the coefficients.
    fn minimise(
        &self,
        fixed: Option<(usize, f64)>,
        c0: &[f64; TERM_COUNT],
    ) -> Option<(f64, [f64; TERM_COUNT])> {
        let mut c = *c0;
        if let Some((j, v)) = fixed {
            c[j] = v;
        }
        let vars: Vec<usize> = self
            .free
            .iter()
            .copied()
            .filter(|&j| fixed.is_none_or(|(f, _)| f != j))
            .collect();
        for _ in 0..OUTER_PASSES {
            let w = self.weights(&c)?;
            if vars.is_empty() {
                break;
            }
            c = self.gauss_newton(&w, &vars, c)?;
        }
        let w = self.weights(&c)?;
        Some((self.d_under(&w, &c)?, c))
    }

    /// Gauss–Newton steps on z under the weights `w` over the terms `vars` from `c`, each
    /// halved until D falls.
    fn gauss_newton(
        &self,
        w: &Weights,
        vars: &[usize],
        mut c: [f64; TERM_COUNT],
    ) -> Option<[f64; TERM_COUNT]> {
        let mut d = self.d_under(w, &c)?;
        let k = self.p.a.len();
        for _ in 0..GN_MAX_STEPS {
            let (z, dz_dm) = self.z(w, &c)?;
            // z(c') ≈ z + J(c' − c): least squares of y − Xc' with X = −J, y = z − Jc
            let mut x = vec![[0.0; TERM_COUNT]; k];
            let mut y = vec![0.0; k];
            for i in 0..k {
                let mut lin = 0.0;
                for &j in vars {
                    x[i][j] = -dz_dm[i] * self.p.g[i][j];
                    lin += x[i][j] * c[j];
                }
                y[i] = z[i] + lin;
            }
            // whitened by R's factor, column by column
            let mut xw = vec![[0.0; TERM_COUNT]; k];
            for &j in vars {
                let col: Vec<f64> = x.iter().map(|r| r[j]).collect();
                for (i, v) in w.whiten(&col).into_iter().enumerate() {
                    xw[i][j] = v;
                }
            }
            let yw = w.whiten(&y);
            let ones = vec![1.0; k];
            let base = c;
            let feasible = |sol: &[f64; TERM_COUNT]| {
                let mut full = base;
                for &j in vars {
                    full[j] = sol[j];
                }
                self.p.pred(&full).iter().all(|v| is_positive(*v))
            };
            let Some(sol) = nnls_subsets(&xw, &yw, &ones, vars, &self.signed, &feasible) else {
                break;
            };
            let mut t = 1.0;
            let mut accepted = None;
            for _ in 0..=GN_HALVINGS {
                let mut trial = c;
                for &j in vars {
                    trial[j] = c[j] + t * (sol[j] - c[j]);
                }
                if let Some(dt) = self.d_under(w, &trial)
                    && dt < d
                {
                    accepted = Some((trial, dt));
                    break;
                }
                t *= 0.5;
            }
            let Some((trial, dt)) = accepted else { break };
            let gain = d - dt;
            c = trial;
            d = dt;
            if gain < GN_TOL {
                break;
            }
        }
        Some(c)
    }

    /// P(c_j): D minimised with term `j` at coefficient `cj`, warm-started from the
    /// nearest solution in `seen` (updated).
    fn at(&self, j: usize, cj: f64, seen: &mut Vec<(f64, [f64; TERM_COUNT])>) -> Option<f64> {
        let warm = seen
            .iter()
            .min_by(|a, b| (a.0 - cj).abs().total_cmp(&(b.0 - cj).abs()))
            .map_or(self.c_min, |s| s.1);
        let (d, c) = self
            .minimise(Some((j, cj)), &warm)
            .or_else(|| self.minimise(Some((j, cj)), &self.start))?;
        seen.push((cj, c));
        Some(d)
    }

    /// The interval of term `j`'s coefficient where P − `d_min` ≤ `level` (a χ²(1) level:
    /// [`TWO_SIDED_95`] or [`ONE_SIDED_95`]; `d_min` the least D of every variant); the
    /// lower end only when `lower`, else 0. `guess` is a coefficient near the upper end
    /// (the Gaussian one). The upper end is ∞ where no value up to 4096² × the guess
    /// reaches the level.
    fn interval(&self, j: usize, level: f64, lower: bool, guess: f64, d_min: f64) -> (f64, f64) {
        let c_hat = self.c_min[j].max(0.0);
        let mut seen: Vec<(f64, [f64; TERM_COUNT])> = vec![(self.c_min[j], self.c_min)];
        // P − min P − level (∞ where the model cannot be evaluated); the minimum found
        // along the way lowers min P
        let d_min = std::cell::Cell::new(d_min.min(self.d_min));
        let excess = |cj: f64, seen: &mut Vec<(f64, [f64; TERM_COUNT])>| {
            let d = self.at(j, cj, seen).unwrap_or(f64::INFINITY);
            if d < d_min.get() {
                d_min.set(d);
            }
            d - d_min.get() - level
        };
        // the upper end, in the term's value t = √c (log bisection)
        let t_hat = c_hat.sqrt();
        let mut t_lo = t_hat;
        let mut t_hi = guess
            .max(c_hat)
            .max(f64::MIN_POSITIVE)
            .sqrt()
            .max(t_hat * 1.01);
        if !is_positive(t_hi) || !t_hi.is_finite() {
            return (0.0, f64::INFINITY);
        }
        let mut found = false;
        for _ in 0..END_EXPAND {
            if excess(t_hi * t_hi, &mut seen) >= 0.0 {
                found = true;
                break;
            }
            t_lo = t_hi;
            t_hi *= 2.0;
        }
        let hi = if found {
            if !is_positive(t_lo) || t_hi / t_lo > 2.0 {
                // narrow the bracket from above to a factor 2
                loop {
                    let next = t_hi / 2.0;
                    if next <= t_lo.max(t_hi * 1e-6) {
                        break;
                    }
                    if excess(next * next, &mut seen) >= 0.0 {
                        t_hi = next;
                    } else {
                        t_lo = next;
                        break;
                    }
                }
                if !is_positive(t_lo) {
                    t_lo = t_hi * 1e-6;
                }
            }
            for _ in 0..END_BISECT {
                let mid = (t_lo * t_hi).sqrt();
                if excess(mid * mid, &mut seen) >= 0.0 {
                    t_hi = mid;
                } else {
                    t_lo = mid;
                }
            }
            t_hi * t_hi
        } else {
            f64::INFINITY
        };
        // the lower end: 0 unless P(0) is beyond the level
        let lo = if lower && c_hat > 0.0 && excess(0.0, &mut seen) > 0.0 {
            // bracket from the top by halvings, then log bisection
            let (mut a, mut b) = (t_hat / 2.0, t_hat); // excess(a) > 0 ≥ excess(b)
            while a > t_hat * 1e-6 && excess(a * a, &mut seen) <= 0.0 {
                b = a;
                a /= 2.0;
            }
            for _ in 0..END_BISECT {
                let mid = (a * b).sqrt();
                if excess(mid * mid, &mut seen) > 0.0 {
                    a = mid;
                } else {
                    b = mid;
                }
            }
            a * a
        } else {
            0.0
        };
        (lo, hi)
    }
}
