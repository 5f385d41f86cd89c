//! The 5-term Allan-variance model and the per-point log residual of imu_utils' fit
//! (docs/upstream/imu_utils.md §4.3):
//! `model(τ) = Q²/τ² + N²/τ + B² + K²·τ + R²·τ²`,
//! `r = log10(model(τ)) − log10(σ²)` with `log10(x) = log(x)/log(10)`.
//!
//! Two evaluation paths, because Ceres runs upstream's templated functor in two ways:
//! with `double` when only the cost is needed (candidate points) and with `Jet`s when the
//! Jacobian is needed. Ceres' Jet division by a `Jet` or a scalar multiplies by the
//! reciprocal, so the two paths differ in the last bit; both are reproduced.

/// Fit parameters `[Q, N, B, K, R]` (signs are free; only squares enter).
pub type Params = [f64; 5];

/// `std::log(10)` as upstream's `calcLog10` divides by it.
fn ln10() -> f64 {
    10f64.ln()
}

/// Model Allan variance, evaluated left to right as upstream's `calcSigma2(double…)`.
pub fn variance(p: &Params, tau: f64) -> f64 {
    let [q, n, b, k, r] = *p;
    q * q / (tau * tau) + n * n / tau + b * b + k * k * tau + r * r * tau * tau
}

/// Fitted Allan deviation `sqrt(model(τ))` (`calcSimDeviation`).
pub fn deviation(p: &Params, tau: f64) -> f64 {
    variance(p, tau).sqrt()
}

/// Residual through the `double` instantiation (Ceres' cost-only evaluations).
pub fn residual(p: &Params, tau: f64, sigma2: f64) -> f64 {
    variance(p, tau).ln() / ln10() - sigma2.ln() / ln10()
}

/// Residual and its gradient through the `Jet` instantiation (Ceres' Jacobian evaluations),
/// following ceres/jet.h 2.1 operation by operation.
pub fn residual_and_gradient(p: &Params, tau: f64, sigma2: f64) -> (f64, [f64; 5]) {
    let [q, n, b, k, r] = *p;
    // Jet / Jet: value f·(1/g), derivative (f' − (f/g)·g')·(1/g); τ is a constant Jet (g' = 0).
    let inv_tau2 = 1.0 / (tau * tau);
    let inv_tau = 1.0 / tau;
    let vq = (q * q) * inv_tau2;
    let vn = (n * n) * inv_tau;
    let vb = b * b;
    let vk = (k * k) * tau;
    let vr = ((r * r) * tau) * tau;
    let m = vq + vn + vb + vk + vr;
    let dm = [
        (q + q) * inv_tau2,
        (n + n) * inv_tau,
        b + b,
        (k + k) * tau,
        ((r + r) * tau) * tau,
    ];
    // log(Jet): (log a, v·(1/a)); Jet / double: both parts times 1/s.
    let inv_m = 1.0 / m;
    let inv_ln10 = 1.0 / ln10();
    let value = m.ln() * inv_ln10 - sigma2.ln() / ln10();
    let mut grad = [0.0; 5];
    for j in 0..5 {
        grad[j] = (dm[j] * inv_m) * inv_ln10;
    }
    (value, grad)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Central differences with h = 1e-3·|p|: O(h²) truncation; errors are measured against the
    /// largest gradient component of the point, since tiny components drown in cancellation.
    const FD_REL_TOL: f64 = 1e-5;
    /// The two evaluation paths differ only by reciprocal-vs-division rounding.
    const PATHS_ABS_TOL: f64 = 1e-14;

    #[test]
    fn jet_gradient_matches_finite_differences() {
        let p = [0.3, 5938.5, 3.39, 0.734, 0.832];
        for &tau in &[0.005, 1.0, 292.9, 65537.0 * 0.005] {
            let (r0, g) = residual_and_gradient(&p, tau, 1.0e6);
            assert!((r0 - residual(&p, tau, 1.0e6)).abs() < PATHS_ABS_TOL);
            for j in 0..5 {
                let h = 1e-3 * p[j].abs();
                let (mut pp, mut pm) = (p, p);
                pp[j] += h;
                pm[j] -= h;
                let fd = (residual(&pp, tau, 1.0e6) - residual(&pm, tau, 1.0e6)) / (2.0 * h);
                let scale = g.iter().fold(0.0f64, |a, v| a.max(v.abs()));
                let err = (fd - g[j]).abs() / scale;
                assert!(
                    err < FD_REL_TOL,
                    "tau {tau} param {j}: fd {fd:e} jet {:e}",
                    g[j]
                );
            }
        }
    }
}
