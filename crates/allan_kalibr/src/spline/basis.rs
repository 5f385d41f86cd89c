//! The cumulative cubic B-spline basis (Lovegrove et al. 2013, eq. 4; sophus-rs
//! `CubicBasisFunction`): B̃(u) = C·[1, u, u², u³]ᵀ with
//! ```text
//!           [ 6 0  0  0 ]
//! C = 1/6 · [ 5 3 −3  1 ]      row j gives B̃_j; B̃_0 ≡ 1
//!           [ 1 3  3 −2 ]
//!           [ 0 0  0  1 ]
//! ```
//! Derivatives with respect to u: dB̃/du = C·[0, 1, 2u, 3u²]ᵀ, d²B̃/du² = C·[0, 0, 2, 6u]ᵀ
//! (divide by Δt and Δt² for time derivatives).

/// The cumulative blending matrix C (row-major, rows j = 0..3).
pub const C: [[f64; 4]; 4] = [
    [1.0, 0.0, 0.0, 0.0],
    [5.0 / 6.0, 3.0 / 6.0, -3.0 / 6.0, 1.0 / 6.0],
    [1.0 / 6.0, 3.0 / 6.0, 3.0 / 6.0, -2.0 / 6.0],
    [0.0, 0.0, 0.0, 1.0 / 6.0],
];

fn mul(m: &[f64; 4]) -> [f64; 4] {
    let mut out = [0.0; 4];
    for (j, row) in C.iter().enumerate() {
        out[j] = row[0] * m[0] + row[1] * m[1] + row[2] * m[2] + row[3] * m[3];
    }
    out
}

/// Cumulative basis values B̃_0..3 at u ∈ [0, 1].
pub fn b(u: f64) -> [f64; 4] {
    mul(&[1.0, u, u * u, u * u * u])
}

/// dB̃/du at u.
pub fn du_b(u: f64) -> [f64; 4] {
    mul(&[0.0, 1.0, 2.0 * u, 3.0 * u * u])
}

/// d²B̃/du² at u.
pub fn du2_b(u: f64) -> [f64; 4] {
    mul(&[0.0, 0.0, 2.0, 6.0 * u])
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Central differences with h = 1e-6 on cubics: error O(h²)·|b'''| ≈ 1e-12, plus
    /// rounding ε/h ≈ 1e-10.
    const FD_TOL: f64 = 1e-8;

    /// Naive oracle: the textbook uniform cubic B-spline weights.
    fn standard_weights(u: f64) -> [f64; 4] {
        let v = 1.0 - u;
        [
            v * v * v / 6.0,
            (3.0 * u * u * u - 6.0 * u * u + 4.0) / 6.0,
            (-3.0 * u * u * u + 3.0 * u * u + 3.0 * u + 1.0) / 6.0,
            u * u * u / 6.0,
        ]
    }

    #[test]
    fn cumulative_is_the_tail_sum_of_the_standard_weights() {
        for k in 0..=100 {
            let u = k as f64 / 100.0;
            let w = standard_weights(u);
            let bt = b(u);
            for j in 0..4 {
                let tail: f64 = w[j..].iter().sum();
                assert!(
                    (bt[j] - tail).abs() < 1e-15,
                    "u {u} j {j}: expected {tail}, actual {}",
                    bt[j]
                );
            }
        }
        assert_eq!(b(0.0), [1.0, 5.0 / 6.0, 1.0 / 6.0, 0.0]);
    }

    #[test]
    fn derivatives_match_finite_differences() {
        let h = 1e-6;
        for k in 1..100 {
            let u = k as f64 / 100.0;
            let (bp, bm) = (b(u + h), b(u - h));
            let (dp, dm) = (du_b(u + h), du_b(u - h));
            let (d1, d2) = (du_b(u), du2_b(u));
            for j in 0..4 {
                let fd1 = (bp[j] - bm[j]) / (2.0 * h);
                let fd2 = (dp[j] - dm[j]) / (2.0 * h);
                assert!(
                    (fd1 - d1[j]).abs() < FD_TOL,
                    "du_b u {u} j {j}: fd {fd1}, analytic {}",
                    d1[j]
                );
                assert!(
                    (fd2 - d2[j]).abs() < FD_TOL,
                    "du2_b u {u} j {j}: fd {fd2}, analytic {}",
                    d2[j]
                );
            }
        }
    }
}
