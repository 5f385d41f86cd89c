//! Ceres 2.1's trust-region minimizer with the traditional dogleg strategy, as imu_utils runs
//! it (all defaults except `DOGLEG`): Jacobi scaling, 50 step attempts, default tolerances.
//! Many of upstream's fits stop at the attempt cap while still moving, so the yaml values
//! depend on following Ceres' iterate path; every rule of docs/upstream/imu_utils.md §4.4 (items 1–10) is
//! implemented here, in Ceres' order (`trust_region_minimizer.cc`, `dogleg_strategy.cc`).
//!
//! The problem is tiny (≤ ~100 residuals, 5 parameters), so the normal equations are formed
//! densely and solved by Cholesky, as Ceres' SPARSE_NORMAL_CHOLESKY does in exact arithmetic.

use super::model::{self, Params};

/// Ceres `Solver::Options` defaults that matter here (docs/upstream/imu_utils.md §4.4).
#[derive(Debug, Clone, Copy)]
pub struct Options {
    /// `max_num_iterations` (counts step attempts, item 10).
    pub max_num_iterations: usize,
    /// `function_tolerance`.
    pub function_tolerance: f64,
    /// `gradient_tolerance`.
    pub gradient_tolerance: f64,
    /// `parameter_tolerance`.
    pub parameter_tolerance: f64,
    /// `initial_trust_region_radius`.
    pub initial_radius: f64,
    /// `max_trust_region_radius`.
    pub max_radius: f64,
    /// `min_trust_region_radius`.
    pub min_radius: f64,
    /// `min_relative_decrease`.
    pub min_relative_decrease: f64,
    /// `min_lm_diagonal`.
    pub min_diagonal: f64,
    /// `max_lm_diagonal`.
    pub max_diagonal: f64,
    /// `max_num_consecutive_invalid_steps`.
    pub max_consecutive_invalid_steps: usize,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            max_num_iterations: 50,
            function_tolerance: 1e-6,
            gradient_tolerance: 1e-10,
            parameter_tolerance: 1e-8,
            initial_radius: 1e4,
            max_radius: 1e16,
            min_radius: 1e-32,
            min_relative_decrease: 1e-3,
            min_diagonal: 1e-6,
            max_diagonal: 1e32,
            max_consecutive_invalid_steps: 5,
        }
    }
}

/// Dogleg constants of `DoglegStrategy` (`kMinMu`, `kMaxMu`, increase factor, radius rules).
const MIN_MU: f64 = 1e-8;
const MAX_MU: f64 = 1.0;
const MU_INCREASE_FACTOR: f64 = 10.0;
const DECREASE_THRESHOLD: f64 = 0.25;
const INCREASE_THRESHOLD: f64 = 0.75;

/// Why the minimizer stopped (Ceres' `TerminationType`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Termination {
    /// A tolerance was met.
    Convergence,
    /// The attempt cap was reached.
    NoConvergence,
    /// Evaluation failed at the start point or too many invalid steps.
    Failure,
}

/// What happened during a solve.
#[derive(Debug, Clone)]
pub struct Summary {
    /// Stop reason.
    pub termination: Termination,
    /// Step attempts made (iteration 0 not counted).
    pub attempts: usize,
    /// Accepted steps.
    pub accepted: usize,
    /// Cost ½Σr² at the start point (NaN if it could not be evaluated).
    pub initial_cost: f64,
    /// Cost at the returned point.
    pub final_cost: f64,
}

/// The data points of the fit.
pub struct Problem<'a> {
    /// Cluster times (s).
    pub taus: &'a [f64],
    /// Allan variances.
    pub sigma2: &'a [f64],
}

/// Residuals, Jacobian (row per point), cost, unscaled gradient Jᵀr.
struct Evaluation {
    r: Vec<f64>,
    j: Vec<[f64; 5]>,
    cost: f64,
    gradient: [f64; 5],
}

impl Problem<'_> {
    /// Ceres' Jacobian evaluation; `None` if any residual or derivative is not finite
    /// (`IsEvaluationValid`).
    fn evaluate_full(&self, x: &Params) -> Option<Evaluation> {
        let n = self.taus.len();
        let mut ev = Evaluation {
            r: Vec::with_capacity(n),
            j: Vec::with_capacity(n),
            cost: 0.0,
            gradient: [0.0; 5],
        };
        for (&tau, &s2) in self.taus.iter().zip(self.sigma2) {
            let (r, g) = model::residual_and_gradient(x, tau, s2);
            if !r.is_finite() || g.iter().any(|v| !v.is_finite()) {
                return None;
            }
            ev.cost += 0.5 * (r * r);
            for k in 0..5 {
                ev.gradient[k] += g[k] * r;
            }
            ev.r.push(r);
            ev.j.push(g);
        }
        Some(ev)
    }

    /// Ceres' cost-only evaluation; `f64::MAX` when it fails (as `ComputeCandidatePointAndEvaluateCost`).
    fn evaluate_cost(&self, x: &Params) -> f64 {
        let mut cost = 0.0;
        for (&tau, &s2) in self.taus.iter().zip(self.sigma2) {
            let r = model::residual(x, tau, s2);
            if !r.is_finite() {
                return f64::MAX;
            }
            cost += 0.5 * (r * r);
        }
        cost
    }
}

fn norm(v: &[f64; 5]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

fn dot(a: &[f64; 5], b: &[f64; 5]) -> f64 {
    let mut s = 0.0;
    for i in 0..5 {
        s += a[i] * b[i];
    }
    s
}

/// `J·v` for a row-per-point Jacobian.
fn right_multiply(j: &[[f64; 5]], v: &[f64; 5]) -> Vec<f64> {
    j.iter().map(|row| dot(row, v)).collect()
}

/// `Jᵀ·r`.
fn left_multiply(j: &[[f64; 5]], r: &[f64]) -> [f64; 5] {
    let mut out = [0.0; 5];
    for (row, &ri) in j.iter().zip(r) {
        for k in 0..5 {
            out[k] += row[k] * ri;
        }
    }
    out
}

fn squared_column_norm(j: &[[f64; 5]]) -> [f64; 5] {
    let mut out = [0.0; 5];
    for row in j {
        for k in 0..5 {
            out[k] += row[k] * row[k];
        }
    }
    out
}

/// Solves (JᵀJ + diag(d²)) y = Jᵀr by Cholesky; `None` if not positive definite.
fn solve_regularized_normal(j: &[[f64; 5]], r: &[f64], d: &[f64; 5]) -> Option<[f64; 5]> {
    let rhs = left_multiply(j, r);
    let mut a = [[0.0; 5]; 5];
    for row in j {
        for p in 0..5 {
            for q in 0..5 {
                a[p][q] += row[p] * row[q];
            }
        }
    }
    // The regulariser is appended as extra rows, so it is added last.
    for p in 0..5 {
        a[p][p] += d[p] * d[p];
    }
    // Cholesky a = L Lᵀ.
    let mut l = [[0.0; 5]; 5];
    for i in 0..5 {
        for k in 0..=i {
            let mut s = a[i][k];
            for m in 0..k {
                s -= l[i][m] * l[k][m];
            }
            if i == k {
                if s.is_nan() || s <= 0.0 {
                    return None;
                }
                l[i][i] = s.sqrt();
            } else {
                l[i][k] = s / l[k][k];
            }
        }
    }
    let mut y = rhs;
    for i in 0..5 {
        for m in 0..i {
            y[i] -= l[i][m] * y[m];
        }
        y[i] /= l[i][i];
    }
    for i in (0..5).rev() {
        for m in i + 1..5 {
            y[i] -= l[m][i] * y[m];
        }
        y[i] /= l[i][i];
    }
    Some(y)
}

/// `DoglegStrategy` state (TRADITIONAL_DOGLEG).
struct Dogleg {
    radius: f64,
    max_radius: f64,
    min_diagonal: f64,
    max_diagonal: f64,
    mu: f64,
    reuse: bool,
    diagonal: [f64; 5],
    gradient: [f64; 5],
    alpha: f64,
    gauss_newton: [f64; 5],
    dogleg_step_norm: f64,
}

impl Dogleg {
    /// `ComputeStep`: a step in the Jacobi-scaled parameter space, `None` on linear-solver failure.
    fn compute_step(&mut self, js: &[[f64; 5]], r: &[f64]) -> Option<[f64; 5]> {
        if self.reuse {
            return Some(self.traditional_step());
        }
        self.reuse = true;
        let cn = squared_column_norm(js);
        for k in 0..5 {
            self.diagonal[k] = cn[k].max(self.min_diagonal).min(self.max_diagonal).sqrt();
        }
        // ComputeGradient: g = Jᵀr / D.
        let g = left_multiply(js, r);
        for k in 0..5 {
            self.gradient[k] = g[k] / self.diagonal[k];
        }
        // ComputeCauchyPoint: α = |g|² / |J D⁻¹ (D⁻¹ g)|².
        let mut scaled = [0.0; 5];
        for k in 0..5 {
            scaled[k] = self.gradient[k] / self.diagonal[k];
        }
        let jg = right_multiply(js, &scaled);
        let jg2: f64 = jg.iter().map(|v| v * v).sum();
        self.alpha = dot(&self.gradient, &self.gradient) / jg2;
        // ComputeGaussNewtonStep: μ grows ×10 on failure while μ < 1.
        let mut solved = None;
        while self.mu < MAX_MU {
            let sq = self.mu.sqrt();
            let mut lm = [0.0; 5];
            for k in 0..5 {
                lm[k] = self.diagonal[k] * sq;
            }
            match solve_regularized_normal(js, r, &lm) {
                Some(y) if y.iter().all(|v| v.is_finite()) => {
                    solved = Some(y);
                    break;
                }
                _ => self.mu *= MU_INCREASE_FACTOR,
            }
        }
        let y = solved?;
        for k in 0..5 {
            self.gauss_newton[k] = y[k] * -self.diagonal[k];
        }
        Some(self.traditional_step())
    }

    /// `ComputeTraditionalDoglegStep` (docs/upstream/imu_utils.md §4.4 item 5), result divided by D.
    fn traditional_step(&mut self) -> [f64; 5] {
        let gradient_norm = norm(&self.gradient);
        let gauss_newton_norm = norm(&self.gauss_newton);
        let mut step = [0.0; 5];
        if gauss_newton_norm <= self.radius {
            step = self.gauss_newton;
            self.dogleg_step_norm = gauss_newton_norm;
        } else if gradient_norm * self.alpha >= self.radius {
            for k in 0..5 {
                step[k] = -(self.radius / gradient_norm) * self.gradient[k];
            }
            self.dogleg_step_norm = self.radius;
        } else {
            let b_dot_a = -self.alpha * dot(&self.gradient, &self.gauss_newton);
            let a_squared_norm = (self.alpha * gradient_norm).powf(2.0);
            let b_minus_a_squared_norm =
                a_squared_norm - 2.0 * b_dot_a + gauss_newton_norm.powf(2.0);
            let c = b_dot_a - a_squared_norm;
            let d =
                (c * c + b_minus_a_squared_norm * (self.radius.powf(2.0) - a_squared_norm)).sqrt();
            let beta = if c <= 0.0 {
                (d - c) / b_minus_a_squared_norm
            } else {
                (self.radius * self.radius - a_squared_norm) / (d + c)
            };
            for k in 0..5 {
                step[k] =
                    (-self.alpha * (1.0 - beta)) * self.gradient[k] + beta * self.gauss_newton[k];
            }
            self.dogleg_step_norm = norm(&step);
        }
        for k in 0..5 {
            step[k] /= self.diagonal[k];
        }
        step
    }

    fn step_accepted(&mut self, step_quality: f64) {
        if step_quality < DECREASE_THRESHOLD {
            self.radius *= 0.5;
        }
        if step_quality > INCREASE_THRESHOLD {
            self.radius = self
                .radius
                .max(3.0 * self.dogleg_step_norm)
                .min(self.max_radius);
        }
        self.mu = MIN_MU.max(2.0 * self.mu / MU_INCREASE_FACTOR);
        self.reuse = false;
    }

    fn step_rejected(&mut self) {
        self.radius *= 0.5;
        self.reuse = true;
    }

    fn step_is_invalid(&mut self) {
        self.mu *= MU_INCREASE_FACTOR;
        self.reuse = false;
    }
}

fn scale_columns(j: &[[f64; 5]], s: &[f64; 5]) -> Vec<[f64; 5]> {
    j.iter()
        .map(|row| {
            let mut out = *row;
            for k in 0..5 {
                out[k] *= s[k];
            }
            out
        })
        .collect()
}

/// `(x − (x + (−g)))`'s max-norm: Ceres' gradient_max_norm through the (Euclidean) Plus.
fn gradient_max_norm(x: &Params, g: &[f64; 5]) -> f64 {
    (0..5)
        .map(|k| (x[k] - (x[k] + -g[k])).abs())
        .fold(0.0, f64::max)
}

/// Item 1: the Jacobi scale 1/(1 + ‖column‖) of each parameter, computed once, at the start
/// point.
fn jacobi_scale(j: &[[f64; 5]]) -> [f64; 5] {
    let cn = squared_column_norm(j);
    let mut scale = [0.0; 5];
    for k in 0..5 {
        scale[k] = 1.0 / (1.0 + cn[k].sqrt());
    }
    scale
}

/// `FinalizeIterationAndCheckIfMinimizerCanContinue`: the termination before attempt
/// `iteration + 1`, if any (the attempt cap, the gradient after a successful step, the
/// trust region's collapse).
fn stop_before_attempt(
    opts: &Options,
    iteration: usize,
    successful: bool,
    grad_max: f64,
    radius: f64,
) -> Option<Termination> {
    if iteration >= opts.max_num_iterations {
        return Some(Termination::NoConvergence);
    }
    if successful && grad_max <= opts.gradient_tolerance {
        return Some(Termination::Convergence);
    }
    if radius <= opts.min_radius {
        return Some(Termination::Convergence);
    }
    None
}

/// The cost decrease the linear model predicts for `step` (scaled space): −Σ m(r + m/2)
/// with m = J_s·step; the step is valid when it is positive.
fn predicted_decrease(js: &[[f64; 5]], r: &[f64], step: &[f64; 5]) -> f64 {
    let mr = right_multiply(js, step);
    let mut s = 0.0;
    for (m, r) in mr.iter().zip(r) {
        s += m * (r + m / 2.0);
    }
    -s
}

/// `ParameterToleranceReached`, then `FunctionToleranceReached`: the step from `x` (norm
/// `x_norm`, cost `cost`) to `candidate` is too small to go on.
fn tolerance_reached(
    opts: &Options,
    x: &Params,
    x_norm: f64,
    cost: f64,
    candidate: &Params,
    candidate_cost: f64,
) -> bool {
    let mut d2 = 0.0;
    for k in 0..5 {
        let d = x[k] - candidate[k];
        d2 += d * d;
    }
    if d2.sqrt() <= opts.parameter_tolerance * (x_norm + opts.parameter_tolerance) {
        return true;
    }
    (cost - candidate_cost).abs() <= opts.function_tolerance * cost
}

/// The point `x + step·scale`: the Jacobi-scaled step back in parameter space.
fn candidate_point(x: &Params, step: &[f64; 5], scale: &[f64; 5]) -> Params {
    let mut candidate = *x;
    for k in 0..5 {
        candidate[k] = x[k] + step[k] * scale[k];
    }
    candidate
}

/// ρ, the actual over the predicted cost decrease; `f64::MIN` when the candidate's cost
/// could not be evaluated.
fn relative_decrease(cost: f64, candidate_cost: f64, model_cost_change: f64) -> f64 {
    if candidate_cost >= f64::MAX {
        f64::MIN
    } else {
        (cost - candidate_cost) / model_cost_change
    }
}

impl Summary {
    /// Nothing done yet: a failure, costs unknown.
    fn not_started() -> Self {
        Summary {
            termination: Termination::Failure,
            attempts: 0,
            accepted: 0,
            initial_cost: f64::NAN,
            final_cost: f64::NAN,
        }
    }
}

impl Dogleg {
    /// The strategy's start state for `opts`.
    fn new(opts: &Options) -> Self {
        Dogleg {
            radius: opts.initial_radius,
            max_radius: opts.max_radius,
            min_diagonal: opts.min_diagonal,
            max_diagonal: opts.max_diagonal,
            mu: MIN_MU,
            reuse: false,
            diagonal: [0.0; 5],
            gradient: [0.0; 5],
            alpha: 0.0,
            gauss_newton: [0.0; 5],
            dogleg_step_norm: 0.0,
        }
    }
}

/// Minimises ½Σr² from `x0`; returns the final parameters whatever the termination
/// (upstream never checks the summary; on failure at the start point `x0` comes back).
pub fn solve(problem: &Problem<'_>, x0: Params, opts: &Options) -> (Params, Summary) {
    let mut summary = Summary::not_started();
    let mut x = x0;
    // Iteration 0.
    let Some(mut ev) = problem.evaluate_full(&x) else {
        return (x0, summary);
    };
    summary.initial_cost = ev.cost;
    let mut x_norm = norm(&x);
    let scale = jacobi_scale(&ev.j);
    let mut js = scale_columns(&ev.j, &scale);
    let mut grad_max = gradient_max_norm(&x, &ev.gradient);
    let mut strategy = Dogleg::new(opts);
    let mut iteration = 0usize;
    let mut successful = true;
    let mut invalid_in_a_row = 0usize;
    loop {
        if let Some(t) = stop_before_attempt(opts, iteration, successful, grad_max, strategy.radius)
        {
            summary.termination = t;
            break;
        }
        iteration += 1;
        summary.attempts = iteration;
        // ComputeTrustRegionStep.
        let step = strategy
            .compute_step(&js, &ev.r)
            .map(|step| (step, predicted_decrease(&js, &ev.r, &step)));
        let (step, model_cost_change) = match step {
            Some((s, change)) if change > 0.0 => (s, change),
            _ => {
                // HandleInvalidStep.
                invalid_in_a_row += 1;
                if invalid_in_a_row >= opts.max_consecutive_invalid_steps {
                    summary.termination = Termination::Failure;
                    break;
                }
                strategy.step_is_invalid();
                successful = false;
                continue;
            }
        };
        invalid_in_a_row = 0;
        let candidate = candidate_point(&x, &step, &scale);
        let candidate_cost = problem.evaluate_cost(&candidate);
        // The candidate is not applied when a tolerance is reached.
        if tolerance_reached(opts, &x, x_norm, ev.cost, &candidate, candidate_cost) {
            summary.termination = Termination::Convergence;
            break;
        }
        let rho = relative_decrease(ev.cost, candidate_cost, model_cost_change);
        if rho > opts.min_relative_decrease {
            // HandleSuccessfulStep: re-evaluate with the Jacobian at the new point.
            x = candidate;
            x_norm = norm(&x);
            match problem.evaluate_full(&x) {
                Some(e) => ev = e,
                None => {
                    summary.termination = Termination::Failure;
                    break;
                }
            }
            js = scale_columns(&ev.j, &scale);
            grad_max = gradient_max_norm(&x, &ev.gradient);
            strategy.step_accepted(rho);
            summary.accepted += 1;
            successful = true;
        } else {
            strategy.step_rejected();
            successful = false;
        }
    }
    summary.final_cost = problem.evaluate_cost(&x);
    (x, summary)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Exact data from known parameters: a converged fit recovers them to this relative error.
    const RECOVER_REL_TOL: f64 = 1e-4;

    #[test]
    fn recovers_parameters_of_noise_free_data() {
        let truth = [0.5, 30.0, 2.0, 0.3, 0.01];
        let taus: Vec<f64> = crate::factors::factors(400_000, 100)
            .iter()
            .map(|&m| m as f64 * 0.005)
            .collect();
        let sigma2: Vec<f64> = taus.iter().map(|&t| model::variance(&truth, t)).collect();
        let start = [0.6, 25.0, 1.5, 0.35, 0.012];
        let opts = Options {
            max_num_iterations: 1000,
            ..Options::default()
        };
        let (x, s) = solve(
            &Problem {
                taus: &taus,
                sigma2: &sigma2,
            },
            start,
            &opts,
        );
        assert_eq!(s.termination, Termination::Convergence, "{s:?}");
        for k in 0..5 {
            let rel = (x[k].abs() - truth[k]).abs() / truth[k];
            assert!(
                rel < RECOVER_REL_TOL,
                "param {k}: expected {}, actual {}, tol {RECOVER_REL_TOL}",
                truth[k],
                x[k]
            );
        }
    }

    /// docs/upstream/imu_utils.md §4.4 item 10: the cap counts attempts, so at most 50 are made.
    #[test]
    fn quirk_07_fifty_attempt_cap() {
        let truth = [0.5, 30.0, 2.0, 0.3, 0.01];
        let taus: Vec<f64> = crate::factors::factors(400_000, 100)
            .iter()
            .map(|&m| m as f64 * 0.005)
            .collect();
        let sigma2: Vec<f64> = taus
            .iter()
            .map(|&t| model::variance(&truth, t) * (1.0 + 0.3 * (t * 7.0).sin()))
            .collect();
        let (_, s) = solve(
            &Problem {
                taus: &taus,
                sigma2: &sigma2,
            },
            [100.0, 1.0, 100.0, 10.0, 1.0],
            &Options::default(),
        );
        assert!(s.attempts <= 50, "{s:?}");
    }

    /// docs/upstream/imu_utils.md §3.7 / quirk 13: a NaN variance fails evaluation at iteration 0 and the
    /// start point comes back unchanged.
    #[test]
    fn quirk_13_nan_point_returns_start() {
        let taus = [0.01, 0.02];
        let sigma2 = [1.0, f64::NAN];
        let x0 = [1.0, 2.0, 3.0, 4.0, 5.0];
        let (x, s) = solve(
            &Problem {
                taus: &taus,
                sigma2: &sigma2,
            },
            x0,
            &Options::default(),
        );
        assert_eq!(x, x0);
        assert_eq!(s.termination, Termination::Failure);
    }
}
