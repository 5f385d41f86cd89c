//! The analytic motion models of vio_data_simulation (docs/upstream/vio_data_simulation.md §2): the `master` ellipse
//! trajectory and the `ros_version` static level IMU, with ground-truth pose, velocity,
//! body-frame gyro and specific force.
//!
//! Differences from upstream: upstream's `MotionModel` keeps its constants in `float`
//! (K = f32(π/10), f32 products such as `K1*K`); here every constant is an exact `f64`
//! (docs/upstream/vio_data_simulation.md §8 item 2: with f64 constants 2843 of the 4001 `imu_pose.txt` lines differ in some
//! printed 6-digit value). The model itself (formulas, ZYX Euler convention, gravity sign)
//! is the same.

use nalgebra::{Matrix3, Vector3};

/// World gravity, ENU z up, hard-coded in upstream `MotionModel`/`testImu`: a level IMU at
/// rest therefore reads +9.81 on acc z.
pub const GRAVITY_W: Vector3<f64> = Vector3::new(0.0, 0.0, -9.81);

/// Ellipse semi-axes (m), z amplitude (m), z frequency factor and angular rate K = π/10
/// (one lap in 20 s) of the `master` model.
const ELLIPSE_X: f64 = 15.0;
const ELLIPSE_Y: f64 = 20.0;
const Z_AMP: f64 = 1.0;
const K1: f64 = 10.0;
const K: f64 = std::f64::consts::PI / 10.0;
/// Roll and pitch amplitudes (rad).
const K_ROLL: f64 = 0.1;
const K_PITCH: f64 = 0.2;

/// Which motion to simulate.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Motion {
    /// `ros_version`: `MotionModel(0)` for every sample ⇒ R = I, gyro 0, acc (0, 0, 9.81).
    Static,
    /// `master`: the 20 s ellipse with sinusoidal z, roll and pitch.
    Ellipse,
}

/// Ground truth at one instant (upstream `MotionData`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MotionSample {
    /// Time, s.
    pub t: f64,
    /// Body → world rotation.
    pub r_wb: Matrix3<f64>,
    /// Body origin in world, m.
    pub p: Vector3<f64>,
    /// World velocity, m/s.
    pub v: Vector3<f64>,
    /// World acceleration, m/s².
    pub a: Vector3<f64>,
    /// Body angular velocity, rad/s.
    pub gyro: Vector3<f64>,
    /// Body specific force R_wbᵀ (a − g_w), m/s².
    pub acc: Vector3<f64>,
}

impl Motion {
    /// Sample the model at time `t` (s).
    pub fn sample(self, t: f64) -> MotionSample {
        match self {
            Motion::Static => static_level(t),
            Motion::Ellipse => ellipse(t),
        }
    }
}

/// R_wb = Rz(yaw)·Ry(pitch)·Rx(roll) (upstream `euler2Rotation`, ZYX, body → world);
/// `rpy` = (roll, pitch, yaw).
pub fn euler_to_rotation(rpy: Vector3<f64>) -> Matrix3<f64> {
    let (sr, cr) = rpy.x.sin_cos();
    let (sp, cp) = rpy.y.sin_cos();
    let (sy, cy) = rpy.z.sin_cos();
    Matrix3::new(
        cy * cp,
        cy * sp * sr - sy * cr,
        sy * sr + cy * cr * sp,
        sy * cp,
        cy * cr + sy * sr * sp,
        sp * sy * cr - cy * sr,
        -sp,
        cp * sr,
        cp * cr,
    )
}

/// E(roll, pitch) mapping ZYX Euler-angle rates to body rates (upstream
/// `eulerRates2bodyRates`): [[1, 0, −sθ], [0, cφ, sφcθ], [0, −sφ, cφcθ]].
pub fn euler_rates_to_body_rates(rpy: Vector3<f64>) -> Matrix3<f64> {
    let (sr, cr) = rpy.x.sin_cos();
    let (sp, cp) = rpy.y.sin_cos();
    Matrix3::new(1.0, 0.0, -sp, 0.0, cr, sr * cp, 0.0, -sr, cr * cp)
}

/// How the ellipse model's constants are evaluated — chosen once, here.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Mode {
    /// Exact f64 constants (K = π/10 in double). The default.
    #[default]
    Double,
    /// Upstream's `float` locals: K = f32(π/10) and the f32 products `K1*K`, `K*K`,
    /// `-K*ellipse_x`, `K*ellipse_y`, `-z*K1*K1` (vio_data_simulation `master` 660dc72
    /// `IMU::MotionModel`, docs/upstream/vio_data_simulation.md §8 item 2). With the upstream float time grid this reproduces
    /// upstream's clean text files digit for digit (`quirk_06_motion_model_float_locals`).
    CompatF32,
}

/// The `master` ellipse model at time `t` with exact f64 constants (docs/upstream/vio_data_simulation.md §2.1).
pub fn ellipse(t: f64) -> MotionSample {
    ellipse_with(t, Mode::Double)
}

/// The `master` ellipse model at time `t`, constants evaluated per `mode`.
pub fn ellipse_with(t: f64, mode: Mode) -> MotionSample {
    if mode == Mode::CompatF32 {
        return ellipse_compat_f32(t);
    }
    let (s, c) = (K * t).sin_cos();
    let (sz, cz) = (K1 * K * t).sin_cos();
    let p = Vector3::new(ELLIPSE_X * c + 5.0, ELLIPSE_Y * s + 5.0, Z_AMP * sz + 5.0);
    let v = Vector3::new(-K * ELLIPSE_X * s, K * ELLIPSE_Y * c, Z_AMP * K1 * K * cz);
    let k2 = K * K;
    let a = Vector3::new(
        -k2 * ELLIPSE_X * c,
        -k2 * ELLIPSE_Y * s,
        -Z_AMP * K1 * K1 * k2 * sz,
    );
    with_attitude(t, K, p, v, a)
}

/// Upstream's arithmetic, C++ promotion rules spelled out: float × float products are
/// rounded to f32, float × double promote to double.
fn ellipse_compat_f32(t: f64) -> MotionSample {
    let kf = (std::f64::consts::PI / 10.0) as f32; // float K = M_PI/10
    let k = kf as f64;
    let k1k = (10.0f32 * kf) as f64; // K1*K (float)
    let (s, c) = ((k * t).sin(), (k * t).cos());
    let (sz, cz) = ((k1k * t).sin(), (k1k * t).cos());
    let p = Vector3::new(15.0 * c + 5.0, 20.0 * s + 5.0, 1.0 * sz + 5.0);
    let v = Vector3::new(
        (-kf * 15.0f32) as f64 * s,
        (kf * 20.0f32) as f64 * c,
        (1.0f32 * 10.0f32 * kf) as f64 * cz,
    );
    let k2 = (kf * kf) as f64; // double K2 = K*K (float product)
    let a = Vector3::new(
        -k2 * 15.0 * c,
        -k2 * 20.0 * s,
        (-10.0f32 * 10.0f32) as f64 * k2 * sz, // -z*K1*K1 in float (z = 1)
    );
    with_attitude(t, k, p, v, a)
}

/// The attitude part shared by both arithmetics: Z-Y-X Euler angles (0.1 cos t, 0.2 sin t,
/// K t) and their rates, body rates by the Euler-rate matrix, specific force Rᵀ(a − g).
fn with_attitude(
    t: f64,
    k: f64,
    p: Vector3<f64>,
    v: Vector3<f64>,
    a: Vector3<f64>,
) -> MotionSample {
    let rpy = Vector3::new(K_ROLL * t.cos(), K_PITCH * t.sin(), k * t);
    let rates = Vector3::new(-K_ROLL * t.sin(), K_PITCH * t.cos(), k);
    let r_wb = euler_to_rotation(rpy);
    let gyro = euler_rates_to_body_rates(rpy) * rates;
    let acc = r_wb.transpose() * (a - GRAVITY_W);
    MotionSample {
        t,
        r_wb,
        p,
        v,
        a,
        gyro,
        acc,
    }
}

/// The `ros_version` model as its `main` uses it: `MotionModel(0)` for every sample
/// (docs/upstream/vio_data_simulation.md §2.2) — identity attitude at the origin, gyro 0, acc (0, 0, 9.81). `t` is only
/// stored.
pub fn static_level(t: f64) -> MotionSample {
    let z = Vector3::zeros();
    MotionSample {
        t,
        r_wb: Matrix3::identity(),
        p: z,
        v: z,
        a: z,
        gyro: z,
        acc: -GRAVITY_W,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rotation::quat_from_matrix;

    /// The sanity values of docs/upstream/vio_data_simulation.md §2.1 are printed with 5–6 significant digits.
    const SPEC_DIGITS_TOL: f64 = 1e-5;
    /// Finite-difference step and the resulting O(h²) central-difference error bound.
    const FD_H: f64 = 1e-5;
    const FD_TOL: f64 = 1e-6;

    fn close(case: &str, got: &[f64], exp: &[f64], tol: f64) {
        for (i, (g, e)) in got.iter().zip(exp).enumerate() {
            assert!(
                (g - e).abs() <= tol,
                "{case} [{i}]: expected {e}, actual {g}, tol {tol}"
            );
        }
    }

    #[test]
    fn sanity_values_at_t0() {
        // docs/upstream/vio_data_simulation.md §2.1: p = (20, 5, 5), v = (0, 2π, π), q_wb = (w 0.99875, x 0.04998, 0, 0),
        // gyro = (0, 0.230364, 0.292623), acc = (−1.48044, 0.979366, 9.76099).
        let m = ellipse(0.0);
        close("p", m.p.as_slice(), &[20.0, 5.0, 5.0], 1e-12);
        let pi = std::f64::consts::PI;
        close("v", m.v.as_slice(), &[0.0, 2.0 * pi, pi], 1e-12);
        let q = quat_from_matrix(&m.r_wb);
        close(
            "q (w x y z)",
            &q,
            &[0.99875, 0.04998, 0.0, 0.0],
            SPEC_DIGITS_TOL * 2.0,
        );
        close(
            "gyro",
            m.gyro.as_slice(),
            &[0.0, 0.230364, 0.292623],
            SPEC_DIGITS_TOL,
        );
        close(
            "acc",
            m.acc.as_slice(),
            &[-1.48044, 0.979366, 9.76099],
            SPEC_DIGITS_TOL,
        );
    }

    #[test]
    fn derivatives_match_finite_differences() {
        // Naive oracle: central differences of p, v and R.
        for &t in &[0.0, 1.3, 7.77, 13.365, 19.9] {
            let (m0, m1, m) = (ellipse(t - FD_H), ellipse(t + FD_H), ellipse(t));
            let v_fd = (m1.p - m0.p) / (2.0 * FD_H);
            let a_fd = (m1.v - m0.v) / (2.0 * FD_H);
            close(
                &format!("v t={t}"),
                v_fd.as_slice(),
                m.v.as_slice(),
                FD_TOL * 10.0,
            );
            close(
                &format!("a t={t}"),
                a_fd.as_slice(),
                m.a.as_slice(),
                FD_TOL * 10.0,
            );
            // ω̂ = Rᵀ Ṙ.
            let rdot = (m1.r_wb - m0.r_wb) / (2.0 * FD_H);
            let w = m.r_wb.transpose() * rdot;
            close(
                &format!("gyro t={t}"),
                &[w[(2, 1)], w[(0, 2)], w[(1, 0)]],
                m.gyro.as_slice(),
                FD_TOL,
            );
        }
    }

    #[test]
    fn quirk_06_motion_model_float_locals() {
        // Upstream `MotionModel` keeps K = M_PI/10 in a float: v_y(0) = f32(K·20), not 2π;
        // the exact-f64 model gives 2π. (Byte parity of the text files: tests/upstream.rs.)
        let kf = (std::f64::consts::PI / 10.0) as f32;
        let c = ellipse_with(0.0, Mode::CompatF32);
        assert_eq!(c.v.y, (kf * 20.0f32) as f64);
        assert_eq!(ellipse(0.0).v.y, 2.0 * std::f64::consts::PI);
        assert!((c.v.y - ellipse(0.0).v.y).abs() > 1e-7 && (c.v.y - ellipse(0.0).v.y).abs() < 1e-5);
    }

    #[test]
    fn static_reads_plus_g_on_z() {
        let m = Motion::Static.sample(123.0);
        assert_eq!(m.acc, Vector3::new(0.0, 0.0, 9.81));
        assert_eq!(m.gyro, Vector3::zeros());
        assert_eq!(quat_from_matrix(&m.r_wb), [1.0, 0.0, 0.0, 0.0]);
    }
}

/// The rotation conversions checked along the ellipse: here, above both modules, so that
/// `rotation` (below `motion`) does not use it.
#[cfg(test)]
mod rotation_tests {
    use super::{ellipse, euler_to_rotation};
    use crate::rotation::{matrix_from_quat, quat_from_matrix};
    use nalgebra::{UnitQuaternion, Vector3};

    /// Conversion round trip of an orthonormal matrix: a few ulps per entry.
    const ROUND_TRIP_TOL: f64 = 1e-14;

    #[test]
    fn quirk_05_eigen_quaternion_sign() {
        let mut negative_w = 0;
        for i in 0..4001 {
            let m = ellipse(i as f64 / 200.0).r_wb;
            let q = quat_from_matrix(&m);
            let back = matrix_from_quat(q);
            let err = (back - m).abs().max();
            assert!(
                err < ROUND_TRIP_TOL,
                "sample {i}: |R(q(R)) − R| = {err}, tol {ROUND_TRIP_TOL}"
            );
            if q[0] < 0.0 {
                negative_w += 1;
            }
            // Same rotation as nalgebra's conversion, up to the overall sign.
            let n = UnitQuaternion::from_matrix(&m);
            let d = (n.w * q[0] + n.i * q[1] + n.j * q[2] + n.k * q[3]).abs();
            assert!(
                (d - 1.0).abs() < 1e-12,
                "sample {i}: |<q_eigen, q_nalgebra>| = {d}"
            );
        }
        // docs/upstream/vio_data_simulation.md §5: along the 20 s run w < 0 for samples 2003–2672 (upstream float grid; on
        // the exact grid the run is within a sample of that).
        assert!(
            (668..=672).contains(&negative_w),
            "negative-w samples: {negative_w}, expected ≈ 670"
        );
    }

    #[test]
    fn largest_diagonal_branch() {
        // Rotation by π about x: trace = −1, x is made positive.
        let m = euler_to_rotation(Vector3::new(std::f64::consts::PI, 0.0, 0.0));
        let q = quat_from_matrix(&m);
        assert!(
            (q[1] - 1.0).abs() < 1e-15 && q[0].abs() < 1e-15,
            "q = {q:?}"
        );
    }
}
