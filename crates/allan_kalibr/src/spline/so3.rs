//! SO(3) on rotation matrices: hat/vee, exp (Rodrigues) and log, with the small-angle and
//! near-π cases handled. Tangent vectors are rotation vectors (axis·angle, rad); `exp` maps
//! ℝ³ → SO(3), `log` returns the rotation vector with angle in [0, π].

use nalgebra::{Matrix3, Vector3};

/// Below this angle (rad) the Taylor expansions are used; their truncation error is
/// O(θ⁴) ≈ 1e-24 relative, far below f64 resolution.
const SMALL_ANGLE: f64 = 1e-6;

/// ω̂: the skew-symmetric matrix with ω̂ v = ω × v.
pub fn hat(w: &Vector3<f64>) -> Matrix3<f64> {
    Matrix3::new(0.0, -w.z, w.y, w.z, 0.0, -w.x, -w.y, w.x, 0.0)
}

/// Inverse of [`hat`] (reads the antisymmetric part, so a slightly non-skew input is fine).
pub fn vee(m: &Matrix3<f64>) -> Vector3<f64> {
    Vector3::new(
        m[(2, 1)] - m[(1, 2)],
        m[(0, 2)] - m[(2, 0)],
        m[(1, 0)] - m[(0, 1)],
    ) * 0.5
}

/// exp(ω̂) = I + sinθ/θ ω̂ + (1 − cosθ)/θ² ω̂², θ = ‖ω‖.
pub fn exp(w: &Vector3<f64>) -> Matrix3<f64> {
    let th2 = w.norm_squared();
    let th = th2.sqrt();
    let (a, b) = if th < SMALL_ANGLE {
        (1.0 - th2 / 6.0, 0.5 - th2 / 24.0)
    } else {
        (th.sin() / th, (1.0 - th.cos()) / th2)
    };
    let k = hat(w);
    Matrix3::identity() + k * a + k * k * b
}

/// log(R): the rotation vector of R, angle in [0, π].
pub fn log(r: &Matrix3<f64>) -> Vector3<f64> {
    let cos = ((r.trace() - 1.0) * 0.5).clamp(-1.0, 1.0);
    let v = vee(r); // = sinθ · axis
    let sin = v.norm();
    if cos > 0.0 {
        // θ < π/2: atan2 is accurate; small angles use θ/sinθ ≈ 1 + θ²/6.
        if sin < SMALL_ANGLE {
            return v * (1.0 + sin * sin / 6.0);
        }
        let th = sin.atan2(cos);
        return v * (th / sin);
    }
    // θ ≥ π/2: the axis from the symmetric part (R + Rᵀ)/2 = cosθ I + (1 − cosθ) a aᵀ,
    // which stays accurate near π where sinθ → 0.
    let th = sin.atan2(cos);
    let s = (r + r.transpose()) * 0.5 - Matrix3::identity() * cos;
    let d = 1.0 - cos;
    // Largest diagonal gives the best-conditioned column.
    let (mut i, mut best) = (0, s[(0, 0)]);
    for k in 1..3 {
        if s[(k, k)] > best {
            i = k;
            best = s[(k, k)];
        }
    }
    let mut axis = Vector3::new(s[(0, i)], s[(1, i)], s[(2, i)]) / (best * d).sqrt();
    axis /= axis.norm();
    // Sign from the antisymmetric part (zero exactly at π, where both signs are valid).
    if axis.dot(&v) < 0.0 {
        axis = -axis;
    }
    axis * th
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand::rngs::StdRng;
    use rand_distr::{Distribution, StandardNormal};

    const SEED: u64 = 7;
    /// exp/log round trip: a few ulps amplified by at most 1/sin θ near π (θ ≤ π − 1e-4).
    const ROUND_TRIP_TOL: f64 = 1e-10;

    fn random_vec(rng: &mut StdRng, scale: f64) -> Vector3<f64> {
        let n = |r: &mut StdRng| -> f64 { StandardNormal.sample(r) };
        Vector3::new(n(rng), n(rng), n(rng)) * scale
    }

    #[test]
    fn exp_log_round_trip_including_hard_cases() {
        let mut rng = StdRng::seed_from_u64(SEED);
        let mut cases: Vec<Vector3<f64>> = vec![
            Vector3::zeros(),
            Vector3::new(1e-9, 0.0, 0.0),
            Vector3::new(1e-4, -2e-4, 3e-5),
            Vector3::new(0.0, 0.0, std::f64::consts::PI - 1e-4),
            Vector3::new(1.0, 1.0, 1.0).normalize() * (std::f64::consts::PI - 1e-6),
            Vector3::new(0.0, 2.0, 0.0),
        ];
        for _ in 0..200 {
            let v = random_vec(&mut rng, 1.0);
            if v.norm() < std::f64::consts::PI - 1e-4 {
                cases.push(v);
            }
        }
        for (i, w) in cases.iter().enumerate() {
            let r = exp(w);
            let orth = (r.transpose() * r - Matrix3::identity()).abs().max();
            assert!(orth < 1e-14, "case {i}: exp not orthonormal ({orth})");
            let back = log(&r);
            let err = (back - w).norm();
            let tol = if w.norm() > 3.0 { 1e-6 } else { ROUND_TRIP_TOL };
            assert!(
                err < tol,
                "case {i}: w = {w:?}, log(exp(w)) = {back:?}, err {err}, tol {tol}"
            );
        }
    }

    #[test]
    fn exp_matches_nalgebra() {
        let mut rng = StdRng::seed_from_u64(SEED + 1);
        for i in 0..50 {
            let w = random_vec(&mut rng, 1.0);
            let n = nalgebra::Rotation3::new(w).into_inner();
            let err = (exp(&w) - n).abs().max();
            assert!(err < 1e-14, "case {i}: {err}");
        }
    }
}
