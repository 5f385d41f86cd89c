//! The start point of imu_utils' fit and its printed `C …` line (docs/upstream/imu_utils.md §4.2):
//! linear least squares of the Allan *deviation* on the basis τ^(j−2)/2, j = 0..4, solved
//! through the normal equations with an explicit inverse (Eigen `MatrixXd::inverse()`, i.e.
//! a partial-pivoting LU), exactly the ill-conditioned route upstream takes. The fit starts
//! at |C|.

/// Unblocked LU with partial pivoting (Eigen's `partial_lu_impl::unblocked_lu`), then the
/// inverse as `solve(I)`: permute, unit-lower then upper triangular solves, column-oriented
/// and multiplying by the reciprocal of each pivot as Eigen's triangular solver does.
pub fn inverse5(a: &[[f64; 5]; 5]) -> [[f64; 5]; 5] {
    const N: usize = 5;
    let mut lu = *a;
    let mut perm: [usize; N] = [0, 1, 2, 3, 4];
    for k in 0..N {
        // maxCoeff returns the first index of the largest |value|.
        let mut p = k;
        let mut big = lu[k][k].abs();
        for (i, row) in lu.iter().enumerate().skip(k + 1) {
            if row[k].abs() > big {
                big = row[k].abs();
                p = i;
            }
        }
        if big != 0.0 {
            if p != k {
                lu.swap(k, p);
                perm.swap(k, p);
            }
            let piv = lu[k][k];
            for row in lu.iter_mut().skip(k + 1) {
                row[k] /= piv;
            }
        }
        for i in k + 1..N {
            let l = lu[i][k];
            for j in k + 1..N {
                lu[i][j] -= l * lu[k][j];
            }
        }
    }
    // X = P·I, column by column.
    let mut x = [[0.0; N]; N];
    for (i, &pi) in perm.iter().enumerate() {
        x[i][pi] = 1.0;
    }
    for col in 0..N {
        for i in 0..N {
            let xi = x[i][col];
            for r in i + 1..N {
                x[r][col] -= xi * lu[r][i];
            }
        }
        for i in (0..N).rev() {
            let xi = x[i][col] * (1.0 / lu[i][i]);
            x[i][col] = xi;
            for r in 0..i {
                x[r][col] -= xi * lu[r][i];
            }
        }
    }
    x
}

/// The signed coefficients C (the printed line); the fit starts at their absolute values.
pub fn start_coefficients(sigma2: &[f64], taus: &[f64]) -> [f64; 5] {
    let rows: Vec<[f64; 5]> = taus
        .iter()
        .map(|&t| {
            let s = t.sqrt();
            // pow(double, double) as upstream's pow(sqrt(tau), kk); not powi.
            [
                s.powf(-2.0),
                s.powf(-1.0),
                s.powf(0.0),
                s.powf(1.0),
                s.powf(2.0),
            ]
        })
        .collect();
    let y: Vec<f64> = sigma2.iter().map(|v| v.sqrt()).collect();
    let mut a = [[0.0; 5]; 5];
    let mut b = [0.0; 5];
    for i in 0..5 {
        for j in 0..5 {
            let mut s = 0.0;
            for r in &rows {
                s += r[i] * r[j];
            }
            a[i][j] = s;
        }
        let mut s = 0.0;
        for (r, yv) in rows.iter().zip(&y) {
            s += r[i] * yv;
        }
        b[i] = s;
    }
    let inv = inverse5(&a);
    let mut c = [0.0; 5];
    for (i, ci) in c.iter_mut().enumerate() {
        let mut s = 0.0;
        for j in 0..5 {
            s += inv[i][j] * b[j];
        }
        *ci = s;
    }
    c
}

/// Eigen's default print of a 1×5 row after `C `: each entry `%g`-6, right-aligned to the
/// widest entry, one space between (docs/upstream/imu_utils.md §4.2).
pub fn c_line(c: &[f64; 5]) -> String {
    let items: Vec<String> = c.iter().map(|&v| bag2mat::shared::cfmt::g6(v)).collect();
    let width = items.iter().map(|s| s.len()).max().unwrap_or(0);
    let cells: Vec<String> = items.iter().map(|s| format!("{s:>width$}")).collect();
    format!("C {}", cells.join(" "))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A well-conditioned matrix: LU inverse error is a few ulps.
    const INVERSE_TOL: f64 = 1e-12;

    #[test]
    fn inverse_times_matrix_is_identity() {
        let a = [
            [4.0, 1.0, 0.5, 0.0, 2.0],
            [1.0, 5.0, 0.0, 1.0, 0.0],
            [0.5, 0.0, 6.0, 0.3, 0.1],
            [0.0, 1.0, 0.3, 7.0, 0.0],
            [9.0, 0.0, 0.1, 0.0, 3.0],
        ];
        let inv = inverse5(&a);
        for i in 0..5 {
            for j in 0..5 {
                let s: f64 = (0..5).map(|k| a[i][k] * inv[k][j]).sum();
                let want = if i == j { 1.0 } else { 0.0 };
                assert!((s - want).abs() < INVERSE_TOL, "({i},{j}): {s}");
            }
        }
    }

    #[test]
    fn c_line_uses_common_width() {
        let c = [-1.15909, 18.9571, -3.72175, 3.77855, -0.0240066];
        assert_eq!(
            c_line(&c),
            "C   -1.15909    18.9571   -3.72175    3.77855 -0.0240066"
        );
        let nan = [-f64::NAN; 5];
        assert_eq!(c_line(&nan), "C -nan -nan -nan -nan -nan");
    }
}
