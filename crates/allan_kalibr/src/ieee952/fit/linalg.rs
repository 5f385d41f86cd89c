//! The dense linear algebra the fit needs, for its few unknowns and some tens of points:
//! whitening by the Cholesky factor of the points' covariance, the enumeration of active
//! sets (exact NNLS for six terms), weighted normal equations, the coefficients' covariance
//! and an SPD solve. Written out (no linear-algebra crate): the sizes are tiny and the code
//! is read against its formulas.

// Small dense matrix code (Cholesky, normal equations) reads best with explicit indices.
#![allow(clippy::needless_range_loop)]

use super::{NoiseTerm, TERM_COUNT, is_positive};

/// L⁻¹G and L⁻¹A with V = LLᵀ (V scaled to unit diagonal first, tiny ridge for safety).
/// `g` may be empty (then only `a` is whitened).
pub(super) fn whiten(
    v: &[Vec<f64>],
    g: &[[f64; TERM_COUNT]],
    a: &[f64],
) -> Option<(Vec<[f64; TERM_COUNT]>, Vec<f64>)> {
    let k = a.len();
    let d: Vec<f64> = (0..k).map(|i| v[i][i].sqrt()).collect();
    if d.iter().any(|x| !is_positive(*x)) {
        return None;
    }
    let mut l = vec![vec![0.0; k]; k];
    for i in 0..k {
        for j in 0..=i {
            let mut s = v[i][j] / (d[i] * d[j]) + if i == j { 1e-10 } else { 0.0 };
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
    let with_g = !g.is_empty();
    let mut gw = vec![[0.0; TERM_COUNT]; if with_g { k } else { 0 }];
    let mut aw = vec![0.0; k];
    for i in 0..k {
        let mut av = a[i] / d[i];
        for p in 0..i {
            av -= l[i][p] * aw[p];
        }
        aw[i] = av / l[i][i];
        if with_g {
            let mut ga: [f64; TERM_COUNT] = std::array::from_fn(|j| g[i][j] / d[i]);
            for p in 0..i {
                for j in 0..TERM_COUNT {
                    ga[j] -= l[i][p] * gw[p][j];
                }
            }
            for j in 0..TERM_COUNT {
                gw[i][j] = ga[j] / l[i][i];
            }
        }
    }
    Some((gw, aw))
}

/// Weighted least squares over the enabled terms with sign constraints (terms not in
/// `signed` ≥ 0), by enumerating the sets of free terms; `feasible` rejects solutions (e.g.
/// a model that is not positive at every point). The line terms ([`NoiseTerm::Line`]) are in
/// every set and take any sign: their shapes come from the PSD, so the enumeration is over
/// the power laws only (2⁶ sets whatever the lines).
pub(super) fn nnls_subsets(
    g: &[[f64; TERM_COUNT]],
    a: &[f64],
    w: &[f64],
    enabled: &[usize],
    signed: &[bool; TERM_COUNT],
    feasible: &dyn Fn(&[f64; TERM_COUNT]) -> bool,
) -> Option<[f64; TERM_COUNT]> {
    let is_line = |j: usize| NoiseTerm::at(j).is_line();
    let always: Vec<usize> = enabled.iter().copied().filter(|&j| is_line(j)).collect();
    let choose: Vec<usize> = enabled.iter().copied().filter(|&j| !is_line(j)).collect();
    let k = choose.len();
    let mut best: Option<(f64, [f64; TERM_COUNT])> = None;
    let first = if always.is_empty() { 1u32 } else { 0 };
    for mask in first..(1 << k) {
        let set: Vec<usize> = (0..k)
            .filter(|b| mask & (1 << b) != 0)
            .map(|b| choose[b])
            .chain(always.iter().copied())
            .collect();
        let Some(sol) = wls(g, a, w, &set) else {
            continue;
        };
        if set
            .iter()
            .zip(&sol)
            .any(|(&j, v)| *v < 0.0 && !signed[j] && !is_line(j))
        {
            continue;
        }
        let mut c = [0.0; TERM_COUNT];
        for (s, &j) in set.iter().enumerate() {
            c[j] = sol[s];
        }
        if !feasible(&c) {
            continue;
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
pub(super) fn col_scale(g: &[[f64; TERM_COUNT]], w: &[f64], set: &[usize]) -> Vec<f64> {
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
pub(super) fn normal_eq(
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
pub(super) fn wls(
    g: &[[f64; TERM_COUNT]],
    a: &[f64],
    w: &[f64],
    set: &[usize],
) -> Option<Vec<f64>> {
    let s = col_scale(g, w, set);
    if s.iter().any(|v| !is_positive(*v)) {
        return None;
    }
    let (n, b) = normal_eq(g, a, w, set, &s);
    let x = solve_spd(&n, &b)?;
    Some(x.iter().zip(&s).map(|(xi, si)| xi / si).collect())
}

/// (GᵀWG)⁻¹ over the terms of `set`, embedded in a 5×5 matrix.
pub(super) fn covariance(
    g: &[[f64; TERM_COUNT]],
    w: &[f64],
    set: &[usize],
) -> Option<[[f64; TERM_COUNT]; TERM_COUNT]> {
    let s = col_scale(g, w, set);
    if s.iter().any(|v| !is_positive(*v)) {
        return None;
    }
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
pub(in crate::ieee952) fn solve_spd(n: &[Vec<f64>], b: &[f64]) -> Option<Vec<f64>> {
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
