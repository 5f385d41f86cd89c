//! Spline Fusion: a uniform cumulative cubic B-spline on ℝ³ × SO(3) (the *split*
//! representation, as basalt `Se3Spline` and kontiki `SplitTrajectory`), fitted to
//! timestamped poses, and the IMU readings derived from it (docs/upstream/vio_data_simulation.md §7).
//!
//! Layers, as sophus-rs splits them: [`basis`] (the blending matrix C and its derivatives),
//! [`segment`] (four control points at u ∈ [0, 1]), [`so3`] (exp/log), and here the spline
//! (knot times in integer nanoseconds, control points, segment lookup) and the fit.
//!
//! ```text
//! knots τ_j = t₀ + j·Δt (j = 0..m−1), control points c_{−1..m} (one pad at each end)
//! t ∈ [τ_j, τ_{j+1}):  u = (t − τ_j)/Δt,  segment uses c_{j−1}, c_j, c_{j+1}, c_{j+2}
//! p(t) = c_{j−1} + Σ_{k=1..3} B̃_k(u)(c_{j−2+k+1} − c_{j−2+k})         (ℝ³, plain blend)
//! R(t) = R_{j−1} Π_{k=1..3} exp(B̃_k(u) Ω_k),  Ω_k = log(R_{j−2+k}ᵀ R_{j−1+k})
//! B̃(u) = C [1 u u² u³]ᵀ,  C = 1/6 [6 0 0 0; 5 3 −3 1; 1 3 3 −2; 0 0 0 1]
//! Ḃ̃ = C [0 1 2u 3u²]ᵀ / Δt,  B̈̃ = C [0 0 2 6u]ᵀ / Δt²
//! gyro  = vee(Rᵀ Ṙ)      (body rate; recursion in segment::so3_eval)
//! accel = Rᵀ (p̈ − g_w),  g_w = (0, 0, −9.81)  ⇒ a level IMU at rest reads +9.81 on z
//! ```
//! Accel comes from the ℝ³ part, never from the body twist vee(T⁻¹Ṫ) (that would miss
//! the −ω×(Rᵀṗ) term; docs/upstream/vio_data_simulation.md §7.3 item 2).
//!
//! End pads are second-order extrapolations: c₋₁ = 3c₀ − 3c₁ + c₂ and
//! R₋₁ = R₀·exp(2·log(R₁ᵀR₀) − log(R₂ᵀR₁)), mirrored at the end. `Fit::Approx` uses the
//! poses as control points (the spline then smooths by ≈ Δt²/6·p̈); `Fit::Interp` iterates
//! c_j ← c_j·exp(1.5 r_j), r_j = log(R_spl(τ_j)ᵀ R_j), p_j += 1.5 (p_j − p_spl(τ_j)),
//! re-extrapolating the pads, until the largest knot residual is below 1e-12.

pub(crate) mod basis;
pub(crate) mod segment;
pub(crate) mod so3;

use crate::error::{Result, SimError};
use nalgebra::{Matrix3, Vector3};

/// A timestamped pose (body → world).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pose {
    /// Time, ns (any epoch).
    pub t_ns: i64,
    /// Position in world, m.
    pub p: Vector3<f64>,
    /// Rotation body → world.
    pub r: Matrix3<f64>,
}

/// How control points are obtained from the knot poses.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Fit {
    /// The spline passes through the knot poses (iterative prefilter).
    Interp,
    /// Control points = knot poses (smoothing).
    Approx,
}

/// Convergence threshold of the interpolation fit (m and rad): a few hundred ulps of the
/// trajectory's coordinates (tens of metres).
pub const FIT_TOLERANCE: f64 = 1e-12;
/// The fit fails after this many iterations (typically 26–34 are needed; docs/upstream/vio_data_simulation.md §7.4).
pub const FIT_MAX_ITER: usize = 200;
/// Relaxation factor of the fixed-point fit: the knot operator's eigenvalues lie in
/// [1/3, 1], so 1.5 gives a contraction factor ≤ 0.5.
const FIT_RELAXATION: f64 = 1.5;

/// Standard gravity magnitude of the upstream model (m/s²), world z up.
pub const GRAVITY: f64 = 9.81;

/// What the fit did.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FitReport {
    /// Iterations of the interpolation fit (0 for `Approx`).
    pub iterations: usize,
    /// Largest knot position residual after the fit, m.
    pub max_pos_residual: f64,
    /// Largest knot rotation residual after the fit, rad.
    pub max_rot_residual: f64,
}

/// Spline state and its IMU reading at one time.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SplineSample {
    /// Time, ns.
    pub t_ns: i64,
    /// Position, m.
    pub p: Vector3<f64>,
    /// Velocity (world), m/s.
    pub v: Vector3<f64>,
    /// Rotation body → world.
    pub r: Matrix3<f64>,
    /// Body angular velocity, rad/s.
    pub gyro: Vector3<f64>,
    /// Body specific force, m/s².
    pub acc: Vector3<f64>,
}

/// A uniform cumulative cubic B-spline on ℝ³ × SO(3) (split representation).
#[derive(Debug, Clone)]
pub struct SplitSpline {
    t0_ns: i64,
    dt_ns: i64,
    /// c_{−1..m}: index k holds c_{k−1}.
    pos: Vec<Vector3<f64>>,
    rot: Vec<Matrix3<f64>>,
    gravity_w: Vector3<f64>,
}

impl SplitSpline {
    /// Fit a spline to knot poses `knots[j]` at τ_j = t0_ns + j·dt_ns (at least 4 knots).
    pub fn fit(
        t0_ns: i64,
        dt_ns: i64,
        knots: &[(Vector3<f64>, Matrix3<f64>)],
        fit: Fit,
    ) -> Result<(Self, FitReport)> {
        let m = knots.len();
        if m < 4 {
            return Err(SimError::Spline(format!("need at least 4 poses, got {m}")));
        }
        if dt_ns <= 0 {
            return Err(SimError::Spline(format!(
                "knot spacing must be positive, got {dt_ns} ns"
            )));
        }
        // log is unambiguous only if consecutive rotations differ by less than π/2 (§7.3 item 5).
        for j in 1..m {
            let ang = so3::log(&(knots[j - 1].1.transpose() * knots[j].1)).norm();
            if ang >= std::f64::consts::FRAC_PI_2 {
                return Err(SimError::Spline(format!(
                    "poses {} and {j} differ by {:.1}° (≥ 90°): the rotation between knots is ambiguous; use a smaller --knot-dt or denser poses",
                    j - 1,
                    ang.to_degrees()
                )));
            }
        }
        let mut s = SplitSpline {
            t0_ns,
            dt_ns,
            pos: std::iter::once(Vector3::zeros())
                .chain(knots.iter().map(|k| k.0))
                .chain(std::iter::once(Vector3::zeros()))
                .collect(),
            rot: std::iter::once(Matrix3::identity())
                .chain(knots.iter().map(|k| k.1))
                .chain(std::iter::once(Matrix3::identity()))
                .collect(),
            gravity_w: Vector3::new(0.0, 0.0, -GRAVITY),
        };
        s.extrapolate_pads();
        let mut report = FitReport {
            iterations: 0,
            max_pos_residual: 0.0,
            max_rot_residual: 0.0,
        };
        let mut res_p = vec![Vector3::zeros(); m];
        let mut res_r = vec![Vector3::zeros(); m];
        loop {
            let (mp, mr) = s.knot_residuals(knots, &mut res_p, &mut res_r);
            report.max_pos_residual = mp;
            report.max_rot_residual = mr;
            if fit == Fit::Approx || mp.max(mr) < FIT_TOLERANCE {
                break;
            }
            if report.iterations == FIT_MAX_ITER {
                return Err(SimError::Spline(format!(
                    "interpolation fit did not converge in {FIT_MAX_ITER} iterations (residual {mp:.3e} m, {mr:.3e} rad)"
                )));
            }
            report.iterations += 1;
            for j in 0..m {
                s.pos[j + 1] += res_p[j] * FIT_RELAXATION;
                s.rot[j + 1] *= so3::exp(&(res_r[j] * FIT_RELAXATION));
            }
            s.extrapolate_pads();
        }
        Ok((s, report))
    }

    /// Use a gravity vector other than (0, 0, −9.81) (world frame, m/s²).
    pub fn with_gravity(mut self, gravity_w: Vector3<f64>) -> Self {
        self.gravity_w = gravity_w;
        self
    }

    fn extrapolate_pads(&mut self) {
        let n = self.pos.len(); // m + 2
        let (p, r) = (&mut self.pos, &mut self.rot);
        p[0] = p[1] * 3.0 - p[2] * 3.0 + p[3];
        p[n - 1] = p[n - 2] * 3.0 - p[n - 3] * 3.0 + p[n - 4];
        let d = so3::log(&(r[2].transpose() * r[1])) * 2.0 - so3::log(&(r[3].transpose() * r[2]));
        r[0] = r[1] * so3::exp(&d);
        let d = so3::log(&(r[n - 3].transpose() * r[n - 2])) * 2.0
            - so3::log(&(r[n - 4].transpose() * r[n - 3]));
        r[n - 1] = r[n - 2] * so3::exp(&d);
    }

    /// Residuals target − spline at every knot; returns the largest norms (m, rad).
    fn knot_residuals(
        &self,
        knots: &[(Vector3<f64>, Matrix3<f64>)],
        rp: &mut [Vector3<f64>],
        rr: &mut [Vector3<f64>],
    ) -> (f64, f64) {
        let (mut mp, mut mr) = (0.0f64, 0.0f64);
        for (j, k) in knots.iter().enumerate() {
            // At u = 0 the segment starting at knot j needs c_{j−1}, c_j, c_{j+1} only
            // (B̃₃(0) = 0), which exist for every j including the last knot.
            let cp = [
                self.pos[j],
                self.pos[j + 1],
                self.pos[j + 2],
                self.pos[j + 2],
            ];
            let cr = [
                self.rot[j],
                self.rot[j + 1],
                self.rot[j + 2],
                self.rot[j + 2],
            ];
            let (p, _, _) = segment::r3_eval(&cp, 0.0, 1.0);
            let r = segment::so3_value(&cr, 0.0);
            rp[j] = k.0 - p;
            rr[j] = so3::log(&(r.transpose() * k.1));
            mp = mp.max(rp[j].norm());
            mr = mr.max(rr[j].norm());
        }
        (mp, mr)
    }

    /// Number of knots m.
    pub fn knot_count(&self) -> usize {
        self.pos.len() - 2
    }

    /// Knot spacing, ns.
    pub fn dt_ns(&self) -> i64 {
        self.dt_ns
    }

    /// Valid time range [τ₀, τ_{m−1}], ns.
    pub fn range_ns(&self) -> (i64, i64) {
        (
            self.t0_ns,
            self.t0_ns + (self.knot_count() as i64 - 1) * self.dt_ns,
        )
    }

    /// Segment index j and u for time `t_ns`, clamped to the valid range (t = τ_last falls
    /// in the last segment with u = 1; docs/upstream/vio_data_simulation.md §7.3 item 4).
    pub fn index_and_u(&self, t_ns: i64) -> (usize, f64) {
        let (a, b) = self.range_ns();
        let t = t_ns.clamp(a, b) - self.t0_ns;
        let last = self.knot_count() as i64 - 2;
        let j = (t / self.dt_ns).min(last);
        let u = (t - j * self.dt_ns) as f64 / self.dt_ns as f64;
        (j as usize, u)
    }

    /// Pose, velocity and IMU reading at `t_ns` (clamped to the valid range).
    pub fn sample(&self, t_ns: i64) -> SplineSample {
        let (j, u) = self.index_and_u(t_ns);
        let dt = self.dt_ns as f64 * 1e-9;
        let cp: [Vector3<f64>; 4] = [
            self.pos[j],
            self.pos[j + 1],
            self.pos[j + 2],
            self.pos[j + 3],
        ];
        let cr: [Matrix3<f64>; 4] = [
            self.rot[j],
            self.rot[j + 1],
            self.rot[j + 2],
            self.rot[j + 3],
        ];
        let (p, v, a) = segment::r3_eval(&cp, u, dt);
        let (r, gyro) = segment::so3_eval(&cr, u, dt);
        let acc = r.transpose() * (a - self.gravity_w);
        SplineSample {
            t_ns,
            p,
            v,
            r,
            gyro,
            acc,
        }
    }
}

/// Knot times and poses for a spline, from arbitrary timestamped poses.
#[derive(Debug, Clone)]
pub struct Knots {
    /// τ₀, ns.
    pub t0_ns: i64,
    /// Δt, ns.
    pub dt_ns: i64,
    /// Pose at each knot.
    pub poses: Vec<(Vector3<f64>, Matrix3<f64>)>,
    /// True if the input was not uniform (or not at `knot_dt`) and was resampled (linear
    /// position, geodesic rotation); the accuracy is then bounded by the input rate.
    pub resampled: bool,
}

/// Choose the knot spacing (`knot_dt_ns` or the median input spacing) and, when the input is
/// uniform at that spacing within max(1 µs, 1e-3·Δt), use the poses as knots; otherwise
/// resample at τ_j = t₀ + j·Δt (docs/upstream/vio_data_simulation.md §7.4 items 2–3).
pub fn knots_from_poses(poses: &[Pose], knot_dt_ns: Option<i64>) -> Result<Knots> {
    if poses.len() < 4 {
        return Err(SimError::Spline(format!(
            "need at least 4 poses, got {}",
            poses.len()
        )));
    }
    for (i, w) in poses.windows(2).enumerate() {
        if w[1].t_ns <= w[0].t_ns {
            return Err(SimError::Spline(format!(
                "pose times must increase strictly: pose {} at {} ns, pose {} at {} ns",
                i,
                w[0].t_ns,
                i + 1,
                w[1].t_ns
            )));
        }
    }
    let mut gaps: Vec<i64> = poses.windows(2).map(|w| w[1].t_ns - w[0].t_ns).collect();
    gaps.sort_unstable();
    let median = gaps[gaps.len() / 2];
    let h = knot_dt_ns.unwrap_or(median);
    if h <= 0 {
        return Err(SimError::InvalidArgument(format!(
            "knot spacing must be positive, got {h} ns"
        )));
    }
    let tol = (1_000i64).max(h / 1000);
    let uniform = poses
        .windows(2)
        .all(|w| ((w[1].t_ns - w[0].t_ns) - h).abs() <= tol);
    let t0 = poses[0].t_ns;
    if uniform {
        return Ok(Knots {
            t0_ns: t0,
            dt_ns: h,
            poses: poses.iter().map(|p| (p.p, p.r)).collect(),
            resampled: false,
        });
    }
    let t_last = poses[poses.len() - 1].t_ns;
    let mut out = Vec::new();
    let mut i = 0;
    let mut tau = t0;
    while tau <= t_last {
        while poses[i + 1].t_ns < tau {
            i += 1;
        }
        let (a, b) = (&poses[i], &poses[i + 1]);
        let s = (tau - a.t_ns) as f64 / (b.t_ns - a.t_ns) as f64;
        let p = a.p + (b.p - a.p) * s;
        let r = a.r * so3::exp(&(so3::log(&(a.r.transpose() * b.r)) * s));
        out.push((p, r));
        tau += h;
    }
    if out.len() < 4 {
        return Err(SimError::Spline(format!(
            "knot spacing {h} ns leaves only {} knots",
            out.len()
        )));
    }
    Ok(Knots {
        t0_ns: t0,
        dt_ns: h,
        poses: out,
        resampled: true,
    })
}

/// Result of [`self_check`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SelfCheck {
    /// The fit's report.
    pub fit: FitReport,
    /// Max ‖spline gyro − analytic gyro‖ away from the ends, rad/s.
    pub max_gyro_err: f64,
    /// Max ‖spline acc − analytic acc‖ away from the ends, m/s².
    pub max_acc_err: f64,
    /// Max knot pose error (position m, rotation rad), over all knots.
    pub max_knot_err: f64,
    /// Number of comparison instants.
    pub samples: usize,
}

/// Gyro tolerance of the self-check (issue 5): rad/s.
pub const SELF_CHECK_GYRO_TOL: f64 = 1e-5;
/// Accel tolerance of the self-check (issue 5): m/s².
pub const SELF_CHECK_ACC_TOL: f64 = 1e-3;
/// Knot poses must be reproduced this closely by the interpolating fit (docs/upstream/vio_data_simulation.md §7.5).
pub const SELF_CHECK_KNOT_TOL: f64 = 1e-9;

/// Sample the analytic ellipse model's poses at `pose_rate` Hz on [0, 20] s (t_j = j/rate,
/// in memory), fit, evaluate at twice the pose rate (knot and mid-knot times) with
/// `trim_knots` knots trimmed at each end, and compare with the analytic gyro/acc
/// (docs/upstream/vio_data_simulation.md §7.5).
pub fn self_check(pose_rate: f64, fit: Fit, trim_knots: usize) -> Result<SelfCheck> {
    let poses = model_poses(20.0, pose_rate);
    let knots = knots_from_poses(&poses, None)?;
    let (spline, report) = SplitSpline::fit(knots.t0_ns, knots.dt_ns, &knots.poses, fit)?;
    let mut max_knot_err = 0.0f64;
    for p in &poses {
        let s = spline.sample(p.t_ns);
        max_knot_err = max_knot_err
            .max((s.p - p.p).norm())
            .max(so3::log(&(s.r.transpose() * p.r)).norm());
    }
    let (a, b) = spline.range_ns();
    let half = spline.dt_ns() / 2;
    let (mut t, end) = (
        a + trim_knots as i64 * spline.dt_ns(),
        b - trim_knots as i64 * spline.dt_ns(),
    );
    let (mut mg, mut ma, mut n) = (0.0f64, 0.0f64, 0);
    while t <= end {
        let s = spline.sample(t);
        let m = crate::motion::ellipse(t as f64 * 1e-9);
        mg = mg.max((s.gyro - m.gyro).norm());
        ma = ma.max((s.acc - m.acc).norm());
        n += 1;
        t += half;
    }
    Ok(SelfCheck {
        fit: report,
        max_gyro_err: mg,
        max_acc_err: ma,
        max_knot_err,
        samples: n,
    })
}

/// Poses of the analytic ellipse model at t_j = j/rate on [0, duration] (exact grid).
pub fn model_poses(duration: f64, rate: f64) -> Vec<Pose> {
    crate::grid::Grid::Exact
        .times(duration, rate)
        .enumerate()
        .map(|(j, t)| {
            let m = crate::motion::ellipse(t);
            Pose {
                t_ns: (j as f64 * 1e9 / rate).round() as i64,
                p: m.p,
                r: m.r_wb,
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn self_check_interp_200hz_meets_issue_thresholds() {
        // Issue 5 / docs/upstream/vio_data_simulation.md §7.5: gyro ≤ 1e-5 rad/s, acc ≤ 1e-3 m/s², knots < 1e-9
        // (the prototype reached 1.5e-10 and 2.0e-4).
        let c = self_check(200.0, Fit::Interp, 10).expect("fit");
        assert!(
            c.max_gyro_err <= SELF_CHECK_GYRO_TOL,
            "gyro err {:.3e} > {SELF_CHECK_GYRO_TOL:e}",
            c.max_gyro_err
        );
        assert!(
            c.max_acc_err <= SELF_CHECK_ACC_TOL,
            "acc err {:.3e} > {SELF_CHECK_ACC_TOL:e}",
            c.max_acc_err
        );
        assert!(
            c.max_knot_err < SELF_CHECK_KNOT_TOL,
            "knot err {:.3e} ≥ {SELF_CHECK_KNOT_TOL:e}",
            c.max_knot_err
        );
        assert!(c.fit.iterations > 0 && c.fit.iterations < FIT_MAX_ITER);
        assert_eq!(c.samples, 2 * (4001 - 1 - 20) + 1, "comparison instants");
    }

    #[test]
    fn self_check_30hz_informative_tier() {
        // docs/upstream/vio_data_simulation.md §7.5: interp with 30 Hz poses 8.4e-7 / 9.0e-3, tolerance 1e-5 / 2e-2.
        let c = self_check(30.0, Fit::Interp, 10).expect("fit");
        assert!(c.max_gyro_err <= 1e-5, "gyro err {:.3e}", c.max_gyro_err);
        assert!(c.max_acc_err <= 2e-2, "acc err {:.3e}", c.max_acc_err);
    }

    #[test]
    fn approx_smooths_and_is_worse_than_interp() {
        let a = self_check(200.0, Fit::Approx, 10).expect("fit");
        let i = self_check(200.0, Fit::Interp, 10).expect("fit");
        // docs/upstream/vio_data_simulation.md §7.5: approx at 200 Hz 1.2e-6 / 5.1e-4.
        assert!(
            a.max_gyro_err > i.max_gyro_err,
            "approx {:.3e} vs interp {:.3e}",
            a.max_gyro_err,
            i.max_gyro_err
        );
        assert!(
            a.max_knot_err > 1e-6,
            "approx should not reproduce the knots: {:.3e}",
            a.max_knot_err
        );
    }

    #[test]
    fn static_input_reads_gravity_only() {
        // docs/upstream/vio_data_simulation.md §7.3 item 3 / §7.5: all poses equal ⇒ gyro 0, acc = Rᵀ(0, 0, 9.81) to 1e-12.
        let r = so3::exp(&Vector3::new(0.3, -0.2, 1.0));
        let knots = vec![(Vector3::new(1.0, 2.0, 3.0), r); 10];
        let (s, _) = SplitSpline::fit(0, 5_000_000, &knots, Fit::Interp).expect("fit");
        let expected = r.transpose() * Vector3::new(0.0, 0.0, 9.81);
        for k in 0..=90 {
            let x = s.sample(k * 500_000);
            assert!(x.gyro.norm() < 1e-12, "t {k}: gyro {:?}", x.gyro);
            assert!(
                (x.acc - expected).norm() < 1e-12,
                "t {k}: acc {:?}, expected {expected:?}",
                x.acc
            );
        }
    }

    #[test]
    fn knot_shift_is_caught() {
        // docs/upstream/vio_data_simulation.md §7.3 item 4: an off-by-one knot shift gives ≈ Δt·jerk ≈ 0.157 m/s² — the
        // comparison against the truth must see it.
        let poses = model_poses(20.0, 200.0);
        let knots = knots_from_poses(&poses, None).unwrap();
        let (s, _) = SplitSpline::fit(
            knots.t0_ns + knots.dt_ns,
            knots.dt_ns,
            &knots.poses,
            Fit::Interp,
        )
        .unwrap();
        let m = crate::motion::ellipse(10.0);
        let err = (s.sample(10_000_000_000).acc - m.acc).norm();
        assert!(err > 0.05, "shifted spline acc err {err}");
    }

    #[test]
    fn velocity_matches_numeric_derivative_across_knots() {
        // Continuity at ±1 µs around knots, and ṗ against a central difference.
        let poses = model_poses(2.0, 50.0);
        let k = knots_from_poses(&poses, None).unwrap();
        let (s, _) = SplitSpline::fit(k.t0_ns, k.dt_ns, &k.poses, Fit::Interp).unwrap();
        for j in 2..90 {
            let t = j * 20_000_000;
            let (a, b) = (s.sample(t - 1000), s.sample(t + 1000));
            let fd = (b.p - a.p) / 2e-6;
            let v = s.sample(t).v;
            assert!((fd - v).norm() < 1e-5, "knot {j}: fd {fd:?} vs v {v:?}");
            assert!(
                (a.acc - b.acc).norm() < 1e-3,
                "knot {j}: acc jumps {:?} → {:?}",
                a.acc,
                b.acc
            );
        }
    }

    #[test]
    fn resampling_when_not_uniform() {
        let mut poses = model_poses(2.0, 100.0);
        poses[50].t_ns += 3_000_000; // a 3 ms jitter
        let k = knots_from_poses(&poses, None).unwrap();
        assert!(k.resampled);
        assert_eq!(k.poses.len(), 201);
        let k = knots_from_poses(&model_poses(2.0, 100.0), None).unwrap();
        assert!(!k.resampled);
    }
}
