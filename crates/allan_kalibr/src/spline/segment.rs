//! One spline segment: four control points and the local parameter u ∈ [0, 1]
//! (sophus-rs `spline_segment.rs` layering: basis → segment → spline).
//!
//! R³ part (cumulative form, identical to the standard blend in a vector space):
//! ```text
//! p(u) = c₀ + Σ_{j=1..3} B̃_j(u)·(c_j − c_{j−1})
//! ṗ = Σ dB̃_j/du·(c_j − c_{j−1}) / Δt,     p̈ = Σ d²B̃_j/du²·(c_j − c_{j−1}) / Δt²
//! ```
//! SO(3) part (Lovegrove et al. 2013, eq. 4, on rotation matrices):
//! ```text
//! R(u) = R₀ · Π_{j=1..3} A_j,   A_j = exp(B̃_j(u) Ω_j),   Ω_j = log(R_{j−1}ᵀ R_j)
//! body rate (basalt So3Spline::velocityBody):  ω = 0;  for j = 1..3:
//!     ω = A_jᵀ ω + (dB̃_j/du / Δt) Ω_j          ⇒ ω = vee(Rᵀ Ṙ)
//! product rule (Lovegrove eq. 5–6, kept as the test oracle):
//!     Ȧ_j = A_j Ω̂_j dB̃_j,  Ä_j = Ȧ_j Ω̂_j dB̃_j + A_j Ω̂_j d²B̃_j
//!     Ṙ = R₀(Ȧ₁A₂A₃ + A₁Ȧ₂A₃ + A₁A₂Ȧ₃)
//!     R̈ = R₀(Ä₁A₂A₃ + A₁Ä₂A₃ + A₁A₂Ä₃ + 2(Ȧ₁Ȧ₂A₃ + Ȧ₁A₂Ȧ₃ + A₁Ȧ₂Ȧ₃))
//! ```

use super::{basis, so3};
use nalgebra::{Matrix3, Vector3};

/// Position, velocity and acceleration of an R³ segment at u (Δt = knot spacing, s).
pub fn r3_eval(
    c: &[Vector3<f64>; 4],
    u: f64,
    dt: f64,
) -> (Vector3<f64>, Vector3<f64>, Vector3<f64>) {
    let (b, db, d2b) = (basis::b(u), basis::du_b(u), basis::du2_b(u));
    let mut p = c[0];
    let mut v = Vector3::zeros();
    let mut a = Vector3::zeros();
    for j in 1..4 {
        let d = c[j] - c[j - 1];
        p += d * b[j];
        v += d * db[j];
        a += d * d2b[j];
    }
    (p, v / dt, a / (dt * dt))
}

/// Rotation and body angular velocity (rad/s) of an SO(3) segment at u.
pub fn so3_eval(c: &[Matrix3<f64>; 4], u: f64, dt: f64) -> (Matrix3<f64>, Vector3<f64>) {
    let (b, db) = (basis::b(u), basis::du_b(u));
    let mut r = c[0];
    let mut w = Vector3::zeros();
    for j in 1..4 {
        let omega = so3::log(&(c[j - 1].transpose() * c[j]));
        let a = so3::exp(&(omega * b[j]));
        r *= a;
        w = a.transpose() * w + omega * (db[j] / dt);
    }
    (r, w)
}

/// Rotation only (cheaper; used by the fit).
pub fn so3_value(c: &[Matrix3<f64>; 4], u: f64) -> Matrix3<f64> {
    let b = basis::b(u);
    let mut r = c[0];
    for j in 1..4 {
        let omega = so3::log(&(c[j - 1].transpose() * c[j]));
        r *= so3::exp(&(omega * b[j]));
    }
    r
}

/// R, Ṙ, R̈ by Lovegrove's product rule (module doc) — the slow, obviously-correct oracle.
#[cfg(test)]
pub fn so3_product_rule(
    c: &[Matrix3<f64>; 4],
    u: f64,
    dt: f64,
) -> (Matrix3<f64>, Matrix3<f64>, Matrix3<f64>) {
    let (b, db, d2b) = (basis::b(u), basis::du_b(u), basis::du2_b(u));
    let mut a = [Matrix3::identity(); 3];
    let mut ad = [Matrix3::zeros(); 3];
    let mut add = [Matrix3::zeros(); 3];
    for j in 1..4 {
        let omega = so3::log(&(c[j - 1].transpose() * c[j]));
        let oh = so3::hat(&omega);
        let (d1, d2) = (db[j] / dt, d2b[j] / (dt * dt));
        a[j - 1] = so3::exp(&(omega * b[j]));
        ad[j - 1] = a[j - 1] * oh * d1;
        add[j - 1] = ad[j - 1] * oh * d1 + a[j - 1] * oh * d2;
    }
    let r = c[0] * a[0] * a[1] * a[2];
    let rd = c[0] * (ad[0] * a[1] * a[2] + a[0] * ad[1] * a[2] + a[0] * a[1] * ad[2]);
    let rdd = c[0]
        * (add[0] * a[1] * a[2]
            + a[0] * add[1] * a[2]
            + a[0] * a[1] * add[2]
            + (ad[0] * ad[1] * a[2] + ad[0] * a[1] * ad[2] + a[0] * ad[1] * ad[2]) * 2.0);
    (r, rd, rdd)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand::rngs::StdRng;
    use rand_distr::{Distribution, StandardNormal};

    const SEED: u64 = 11;
    /// Recursion vs product rule: the same quantity by two routes, rounding only.
    const SAME_QUANTITY_TOL: f64 = 1e-12;
    /// Central difference with h = 1e-6 (in u): O(h²) truncation + ε/h rounding.
    const FD_TOL: f64 = 1e-7;

    fn random_controls(rng: &mut StdRng) -> [Matrix3<f64>; 4] {
        let mut n = || -> f64 { StandardNormal.sample(rng) };
        let mut r = so3::exp(&Vector3::new(n(), n(), n()));
        let mut out = [r; 4];
        for o in out.iter_mut().skip(1) {
            r *= so3::exp(&(Vector3::new(n(), n(), n()) * 0.3));
            *o = r;
        }
        out
    }

    #[test]
    fn body_rate_recursion_equals_product_rule_and_finite_differences() {
        let mut rng = StdRng::seed_from_u64(SEED);
        let dt = 0.1;
        for case in 0..20 {
            let c = random_controls(&mut rng);
            for k in 1..10 {
                let u = k as f64 / 10.0;
                let (r, w) = so3_eval(&c, u, dt);
                let (r2, rd, _) = so3_product_rule(&c, u, dt);
                assert!(
                    (r - r2).abs().max() < SAME_QUANTITY_TOL,
                    "case {case} u {u}: R differs"
                );
                let w2 = so3::vee(&(r.transpose() * rd));
                let err = (w - w2).norm();
                assert!(
                    err < SAME_QUANTITY_TOL,
                    "case {case} u {u}: ω {w:?} vs product rule {w2:?}, err {err}"
                );
                let h = 1e-6;
                let fd = (so3_value(&c, u + h) - so3_value(&c, u - h)) / (2.0 * h * dt);
                let err = (fd - rd).abs().max();
                assert!(err < FD_TOL / dt, "case {case} u {u}: Ṙ fd err {err}");
            }
        }
    }

    #[test]
    fn second_derivative_matches_finite_differences() {
        let mut rng = StdRng::seed_from_u64(SEED + 1);
        let dt = 1.0;
        for case in 0..10 {
            let c = random_controls(&mut rng);
            for k in 1..10 {
                let u = k as f64 / 10.0;
                let h = 1e-5;
                let (_, rdp, _) = so3_product_rule(&c, u + h, dt);
                let (_, rdm, _) = so3_product_rule(&c, u - h, dt);
                let (_, _, rdd) = so3_product_rule(&c, u, dt);
                let err = ((rdp - rdm) / (2.0 * h) - rdd).abs().max();
                assert!(err < 1e-6, "case {case} u {u}: R̈ fd err {err}, tol 1e-6");
            }
        }
    }

    #[test]
    fn r3_is_the_standard_blend() {
        let c = [
            Vector3::new(1.0, 2.0, 3.0),
            Vector3::new(-1.0, 0.5, 2.0),
            Vector3::new(4.0, -2.0, 0.0),
            Vector3::new(0.0, 1.0, 1.0),
        ];
        let u: f64 = 0.37;
        let v = 1.0 - u;
        let w = [
            v * v * v / 6.0,
            (3.0 * u * u * u - 6.0 * u * u + 4.0) / 6.0,
            (-3.0 * u * u * u + 3.0 * u * u + 3.0 * u + 1.0) / 6.0,
            u * u * u / 6.0,
        ];
        let expected = c[0] * w[0] + c[1] * w[1] + c[2] * w[2] + c[3] * w[3];
        let (p, _, _) = r3_eval(&c, u, 1.0);
        assert!(
            (p - expected).norm() < 1e-14,
            "expected {expected:?}, actual {p:?}"
        );
    }
}
