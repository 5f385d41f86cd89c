//! The least-squares fit of the split spline to poses at any times (a motion-capture
//! system's, a ground truth's), with knots at a spacing of the caller's choosing: the fit the
//! operating-noise analysis predicts an IMU from. [`super::SplitSpline::fit`] interpolates
//! knot poses instead (`sim spline`).
//!
//! Position: the control points c minimise Σᵢ |pᵢ − Σₖ wₖ(tᵢ) c_{j−1+k}|², wₖ the uniform
//! cubic B-spline weights of tᵢ's segment j — linear, solved in one step. Rotation: the
//! control rotations are corrected in their own (body) frame, Rₖ ← Rₖ·exp(δₖ), by the
//! same least squares on the residuals rᵢ = log(R(tᵢ)ᵀ Rᵢ): to first order in the small
//! rotations between neighbouring control points, the cumulative spline moves by
//! Σₖ wₖ δ_{j−1+k} in its body frame, so that linear problem is solved again until the
//! largest correction is below [`LSQ_TOLERANCE`]. The fixed point is the rotation fit the
//! linearisation describes (its first-order optimality condition).
//!
//! Both problems carry a weak second-difference penalty on the control points themselves
//! ([`SMOOTHING`], relative to the normal matrix' diagonal; for the rotations on the
//! second difference of their logarithms): it decides control points that no pose reaches
//! (a gap in the reference, an end pad whose segment barely holds the last pose) and moves
//! the others by far less than the data's precision.
//! The normal matrices are banded (half-bandwidth 3) and solved by a banded Cholesky.

use nalgebra::{Matrix3, Vector3};

use super::{Result, SplineError, SplitSpline, segment, so3};

/// The rotation fit stops when its largest correction is below this (rad).
pub const LSQ_TOLERANCE: f64 = 1e-12;
/// Most iterations of the rotation fit (it converges in a few when neighbouring control
/// rotations differ by tenths of a radian).
pub const LSQ_MAX_ITER: usize = 60;
/// Weight of the second-difference penalty relative to the mean diagonal of the normal
/// matrix: small enough to move a fitted control point by ~1e-8 of its data's pull.
pub const SMOOTHING: f64 = 1e-8;

/// What the least-squares fit did.
#[derive(Debug, Clone, PartialEq)]
pub struct LsqReport {
    /// Iterations of the rotation fit.
    pub iterations: usize,
    /// RMS position residual at the poses, m.
    pub rms_position: f64,
    /// RMS rotation residual at the poses, rad.
    pub rms_rotation: f64,
    /// Poses in each segment [τ_j, τ_{j+1}) (the last includes τ_last).
    pub support: Vec<u32>,
    /// Degrees of freedom of the fit per coordinate: poses less control points.
    pub dof: f64,
}

/// The standard uniform cubic B-spline weights at u (the cumulative basis' differences).
pub fn weights(u: f64) -> [f64; 4] {
    let v = 1.0 - u;
    [
        v * v * v / 6.0,
        (3.0 * u * u * u - 6.0 * u * u + 4.0) / 6.0,
        (-3.0 * u * u * u + 3.0 * u * u + 3.0 * u + 1.0) / 6.0,
        u * u * u / 6.0,
    ]
}

/// A symmetric positive-definite banded matrix (half-bandwidth [`BAND`]) and its solve.
struct Banded {
    n: usize,
    /// a[i][d] = A[i][i + d], d = 0..=BAND.
    a: Vec<[f64; BAND + 1]>,
}

const BAND: usize = 3;
/// The second difference's coefficients.
const SECOND_DIFF: [f64; 3] = [1.0, -2.0, 1.0];

impl Banded {
    fn new(n: usize) -> Banded {
        Banded {
            n,
            a: vec![[0.0; BAND + 1]; n],
        }
    }

    fn add(&mut self, i: usize, j: usize, v: f64) {
        let (i, j) = if i <= j { (i, j) } else { (j, i) };
        self.a[i][j - i] += v;
    }

    /// The penalty weight μ: [`SMOOTHING`] times the mean diagonal (module docs).
    fn mu(&self) -> f64 {
        let mean = self.a.iter().map(|r| r[0]).sum::<f64>() / self.n.max(1) as f64;
        SMOOTHING * mean.max(f64::MIN_POSITIVE)
    }

    /// Adds the second-difference penalty μ·Σ|x_{k−1} − 2x_k + x_{k+1}|² (module docs).
    fn smooth(&mut self, mu: f64) {
        for k in 1..self.n.saturating_sub(1) {
            let idx = [k - 1, k, k + 1];
            for a in 0..3 {
                for b in a..3 {
                    self.add(idx[a], idx[b], mu * SECOND_DIFF[a] * SECOND_DIFF[b]);
                }
            }
        }
    }

    /// Solves A X = B for three right-hand sides (banded Cholesky, in place); `None` when
    /// A is not positive definite.
    fn solve(mut self, mut b: Vec<Vector3<f64>>) -> Option<Vec<Vector3<f64>>> {
        let n = self.n;
        // A = Lᵀ... stored as U (upper) with A = UᵀU, U[i][d] = U(i, i + d)
        for i in 0..n {
            let mut d0 = self.a[i][0];
            for k in i.saturating_sub(BAND)..i {
                let u = self.a[k][i - k];
                d0 -= u * u;
            }
            if d0.is_nan() || d0 <= 0.0 {
                return None;
            }
            let d0 = d0.sqrt();
            self.a[i][0] = d0;
            for d in 1..=BAND {
                let j = i + d;
                if j >= n {
                    break;
                }
                let mut v = self.a[i][d];
                for k in j.saturating_sub(BAND)..i {
                    v -= self.a[k][i - k] * self.a[k][j - k];
                }
                self.a[i][d] = v / d0;
            }
        }
        // Uᵀ y = b
        for i in 0..n {
            let v = (i.saturating_sub(BAND)..i).fold(b[i], |v, k| v - b[k] * self.a[k][i - k]);
            b[i] = v / self.a[i][0];
        }
        // U x = y
        for i in (0..n).rev() {
            let mut v = b[i];
            for d in 1..=BAND {
                if i + d < n {
                    v -= b[i + d] * self.a[i][d];
                }
            }
            b[i] = v / self.a[i][0];
        }
        Some(b)
    }
}

impl SplitSpline {
    /// The least-squares spline (module docs) through `poses` (times strictly increasing),
    /// knots τ_j = `t0_ns` + j·`dt_ns` up to the last pose, gravity (0, 0, −9.81) until
    /// [`SplitSpline::with_gravity`].
    pub fn fit_least_squares(
        poses: &[super::Pose],
        t0_ns: i64,
        dt_ns: i64,
    ) -> Result<(SplitSpline, LsqReport)> {
        if dt_ns <= 0 {
            return Err(SplineError::Invalid(format!(
                "knot spacing must be positive, got {dt_ns} ns"
            )));
        }
        let Some(last) = poses.last() else {
            return Err(SplineError::Fit("no poses".into()));
        };
        if poses.windows(2).any(|w| w[1].t_ns <= w[0].t_ns) {
            return Err(SplineError::Fit("pose times must increase strictly".into()));
        }
        if poses[0].t_ns < t0_ns {
            return Err(SplineError::Fit("a pose precedes the first knot".into()));
        }
        let m = ((last.t_ns - t0_ns) / dt_ns + 1) as usize
            + usize::from((last.t_ns - t0_ns) % dt_ns != 0);
        if m < 4 || poses.len() < 4 {
            return Err(SplineError::Fit(format!(
                "need at least 4 poses and 4 knots, got {} and {m}",
                poses.len()
            )));
        }
        let n = m + 2;
        let mut s = SplitSpline {
            t0_ns,
            dt_ns,
            pos: vec![Vector3::zeros(); n],
            rot: vec![Matrix3::identity(); n],
            gravity_w: Vector3::new(0.0, 0.0, -super::GRAVITY),
        };
        // each pose's segment and weights
        let at: Vec<(usize, [f64; 4])> = poses
            .iter()
            .map(|p| {
                let (j, u) = s.index_and_u(p.t_ns);
                (j, weights(u))
            })
            .collect();
        let mut support = vec![0u32; m - 1];
        for (j, _) in &at {
            support[*j] += 1;
        }
        let data_normal = {
            let mut a = Banded::new(n);
            for (j, w) in &at {
                for x in 0..4 {
                    for y in x..4 {
                        a.add(j + x, j + y, w[x] * w[y]);
                    }
                }
            }
            a
        };
        let mu = data_normal.mu();
        let normal = || {
            let mut a = Banded {
                n,
                a: data_normal.a.clone(),
            };
            a.smooth(mu);
            a
        };
        // positions: one linear solve
        let mut rhs = vec![Vector3::zeros(); n];
        for (p, (j, w)) in poses.iter().zip(&at) {
            for k in 0..4 {
                rhs[j + k] += p.p * w[k];
            }
        }
        s.pos = normal()
            .solve(rhs)
            .ok_or_else(|| SplineError::Fit("position fit is singular".into()))?;
        // rotations: start from the nearest pose's rotation at each control point's
        // knot, then corrections until they vanish
        for (k, r) in s.rot.iter_mut().enumerate() {
            let t = t0_ns + (k as i64 - 1) * dt_ns;
            let i = poses.partition_point(|p| p.t_ns < t).min(poses.len() - 1);
            let i = if i > 0 && (t - poses[i - 1].t_ns) < (poses[i].t_ns - t) {
                i - 1
            } else {
                i
            };
            *r = poses[i].r;
        }
        let mut iterations = 0;
        loop {
            let mut rhs = vec![Vector3::zeros(); n];
            for (p, (j, w)) in poses.iter().zip(&at) {
                let c: [Matrix3<f64>; 4] = std::array::from_fn(|k| s.rot[j + k]);
                let (_, u) = s.index_and_u(p.t_ns);
                let r = so3::log(&(segment::so3_value(&c, u).transpose() * p.r));
                for k in 0..4 {
                    rhs[j + k] += r * w[k];
                }
            }
            // the penalty acts on the rotations themselves: their second difference
            // D_k = log(R_kᵀR_{k+1}) − log(R_{k−1}ᵀR_k) moves by the corrections' own
            for k in 1..n - 1 {
                let d = so3::log(&(s.rot[k].transpose() * s.rot[k + 1]))
                    - so3::log(&(s.rot[k - 1].transpose() * s.rot[k]));
                for (c, i) in SECOND_DIFF.iter().zip([k - 1, k, k + 1]) {
                    rhs[i] -= d * (mu * c);
                }
            }
            let delta = normal()
                .solve(rhs)
                .ok_or_else(|| SplineError::Fit("rotation fit is singular".into()))?;
            let big = delta.iter().map(|d| d.norm()).fold(0.0, f64::max);
            for (r, d) in s.rot.iter_mut().zip(&delta) {
                *r *= so3::exp(d);
            }
            iterations += 1;
            if big < LSQ_TOLERANCE {
                break;
            }
            if iterations == LSQ_MAX_ITER {
                return Err(SplineError::Fit(format!(
                    "the rotation fit did not converge in {LSQ_MAX_ITER} iterations (last correction {big:.3e} rad): the reference turns too far between knots; use a smaller knot spacing"
                )));
            }
        }
        let (mut sp, mut sr) = (0.0, 0.0);
        for p in poses {
            let x = s.sample(p.t_ns);
            sp += (x.p - p.p).norm_squared();
            sr += so3::log(&(x.r.transpose() * p.r)).norm_squared();
        }
        let k = poses.len() as f64;
        Ok((
            s,
            LsqReport {
                iterations,
                rms_position: (sp / k).sqrt(),
                rms_rotation: (sr / k).sqrt(),
                support,
                dof: k - n as f64,
            },
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::super::Pose;
    use super::*;

    /// A smooth analytic pose (the test's own: a helix turning about a wandering axis).
    fn pose(t: f64) -> Pose {
        let p = Vector3::new((0.9 * t).sin(), (0.7 * t).cos() * 0.5, 0.2 * t);
        let w = Vector3::new(0.4 * (1.1 * t).sin(), 0.3 * (0.8 * t).cos(), 0.5 * t);
        Pose {
            t_ns: (t * 1e9).round() as i64,
            p,
            r: so3::exp(&w),
        }
    }

    /// The weights sum to one and are the cumulative basis' differences.
    #[test]
    fn weights_are_the_differences_of_the_cumulative_basis() {
        for k in 0..=20 {
            let u = k as f64 / 20.0;
            let w = weights(u);
            let b = super::super::basis::b(u);
            for j in 0..4 {
                let tail: f64 = w[j..].iter().sum();
                assert!((tail - b[j]).abs() < 1e-15, "u {u} j {j}");
            }
        }
    }

    /// The banded solve against a dense Gaussian elimination (the slow, obvious oracle).
    #[test]
    fn banded_cholesky_matches_dense_elimination() {
        let n = 12;
        let mut b = Banded::new(n);
        let mut dense = vec![vec![0.0; n]; n];
        for i in 0..n {
            for d in 0..=BAND {
                if i + d < n {
                    let v = if d == 0 {
                        4.0 + i as f64
                    } else {
                        1.0 / (1 + d + i) as f64
                    };
                    b.add(i, i + d, v);
                    dense[i][i + d] += v;
                    if d > 0 {
                        dense[i + d][i] += v;
                    }
                }
            }
        }
        let rhs: Vec<Vector3<f64>> = (0..n)
            .map(|i| Vector3::new(i as f64, 1.0, -(i as f64).sqrt()))
            .collect();
        let x = b.solve(rhs.clone()).unwrap();
        for c in 0..3 {
            // dense elimination
            let mut a = dense.clone();
            let mut y: Vec<f64> = rhs.iter().map(|v| v[c]).collect();
            for p in 0..n {
                for r in p + 1..n {
                    let f = a[r][p] / a[p][p];
                    let pivot = a[p].clone();
                    for (x, v) in a[r].iter_mut().zip(&pivot).skip(p) {
                        *x -= f * v;
                    }
                    y[r] -= f * y[p];
                }
            }
            for p in (0..n).rev() {
                let mut v = y[p];
                for q in p + 1..n {
                    v -= a[p][q] * y[q];
                }
                y[p] = v / a[p][p];
            }
            for i in 0..n {
                assert!((x[i][c] - y[i]).abs() < 1e-12, "{i} {c}");
            }
        }
    }

    /// Poses at 120 Hz, knots every 4th pose: the fit follows a smooth motion, its body
    /// rate and specific force match the analytic ones (away from the ends).
    #[test]
    fn least_squares_fit_follows_a_smooth_motion() {
        let poses: Vec<Pose> = (0..1200).map(|i| pose(i as f64 / 120.0)).collect();
        let dt_ns = 4 * 1_000_000_000 / 120;
        let (s, rep) = SplitSpline::fit_least_squares(&poses, poses[0].t_ns, dt_ns).unwrap();
        assert!(rep.rms_position < 1e-7, "{rep:?}");
        assert!(rep.rms_rotation < 1e-7, "{rep:?}");
        assert!(rep.iterations < LSQ_MAX_ITER);
        // body rate by a central difference of the analytic rotation (h = 1 µs)
        let h = 1e-6;
        for k in 100..1100 {
            let t = k as f64 / 120.0 + 0.003;
            let x = s.sample((t * 1e9).round() as i64);
            let (a, b) = (pose(t - h), pose(t + h));
            let w = so3::log(&(a.r.transpose() * b.r)) / (2.0 * h);
            // the spline's error at 33 ms knots on this motion (jerk ~1 rad/s³): ~1e-5
            assert!((x.gyro - w).norm() < 1e-4, "t {t}: {} vs {w}", x.gyro);
            let acc = Vector3::new(-0.81 * (0.9 * t).sin(), -0.245 * (0.7 * t).cos(), 0.0)
                - Vector3::new(0.0, 0.0, -super::super::GRAVITY);
            let want = pose(t).r.transpose() * acc;
            assert!((x.acc - want).norm() < 1e-3, "t {t}: {} vs {want}", x.acc);
        }
    }
}
