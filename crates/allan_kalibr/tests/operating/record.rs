//! The tests' own writer of moving IMU records with a reference trajectory — independent of
//! the code under test (no spline, no sim): a hand-held-like motion in closed form
//! (positions and ZYX Euler angles as sums of sinusoids, so body rate and specific force
//! are exact), an IMU rotated and offset from the reference body, with scale and
//! misalignment, g-sensitivity, biases that drift (random walk), white noise and vibration
//! lines of known size, stamped on its own clock; and the reference's poses at their own
//! rate and clock, optionally noisy. The IMU goes to an EuRoC/ASL-layout CSV, the poses to a
//! TUM file.

use std::f64::consts::PI;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use nalgebra::{Matrix3, Vector3};
use rand::SeedableRng;
use rand::rngs::StdRng;
use rand_distr::{Distribution, StandardNormal};

/// Gravity, m/s² (world z up; the analysis' magnitude).
pub const G: f64 = 9.81;
/// The records' epoch, ns (stamps far from 0, as a real clock's).
pub const T0_NS: i64 = 1_700_000_000_000_000_000;

/// What to write.
#[derive(Debug, Clone)]
pub struct Spec {
    /// IMU rate, Hz.
    pub rate: f64,
    /// Duration, s.
    pub seconds: f64,
    /// Noise seed.
    pub seed: u64,
    /// Reference rate, Hz.
    pub ref_rate: f64,
    /// The reference's clock runs this far ahead of the IMU's, s.
    pub ref_offset: f64,
    /// Reference noise: position (m) and orientation (rad) per coordinate.
    pub ref_noise: (f64, f64),
    /// Hand-held motion (false: at rest, tilted).
    pub motion: bool,
    /// White noise densities, gyro and acc (rad/s/√Hz, m/s²/√Hz).
    pub n: [f64; 2],
    /// Random walks, gyro and acc (rad/s²/√Hz, m/s³/√Hz).
    pub k: [f64; 2],
    /// Vibration lines: section axis (0–2 gyro x y z, 3–5 acc x y z), frequency (Hz),
    /// amplitude.
    pub lines: Vec<(usize, f64, f64)>,
    /// Scale error on the diagonal (relative).
    pub scale: f64,
    /// Misalignment (symmetric off-diagonal, rad).
    pub misalign: f64,
    /// IMU-to-reference rotation, roll pitch yaw (rad).
    pub rotation: [f64; 3],
    /// Lever arm: the IMU's origin in the reference body frame, m.
    pub lever: [f64; 3],
    /// g-sensitivity on the gyro's diagonal, rad/s per m/s².
    pub g_sens: f64,
}

impl Spec {
    /// A hand-held record: `rate` Hz IMU, `ref_rate` Hz reference 4 ms ahead, 0.5 % scale
    /// and 3 mrad misalignment, a rotated IMU with a lever arm, MEMS-like noise and a
    /// vibration line on acc x/y and gyro z.
    pub fn handheld(rate: f64, ref_rate: f64, seconds: f64, seed: u64) -> Spec {
        Spec {
            rate,
            seconds,
            seed,
            ref_rate,
            ref_offset: 0.004,
            ref_noise: (0.0, 0.0),
            motion: true,
            n: [2e-3, 2e-2],
            k: [2e-5, 4e-4],
            lines: vec![(3, 37.0, 0.06), (4, 37.0, 0.04), (2, 23.0, 6e-3)],
            scale: 0.005,
            misalign: 0.003,
            rotation: [0.05, -0.03, PI / 2.0],
            lever: [0.04, -0.02, 0.03],
            g_sens: 2e-4,
        }
    }

    /// The operating density the analysis should find on each section axis: the white
    /// noise plus each line's A²/(2 f_s) (the calibration removes the rest exactly: scale,
    /// misalignment, rotation, lever arm, offset, g-sensitivity and biases are in its model;
    /// the random walk below the band is the bias model's).
    pub fn expected(&self) -> [f64; 6] {
        std::array::from_fn(|a| {
            let n = self.n[a / 3];
            let lines: f64 = self
                .lines
                .iter()
                .filter(|l| l.0 == a)
                .map(|l| l.2 * l.2 / (2.0 * self.rate))
                .sum();
            (n * n + lines).sqrt()
        })
    }
}

fn rx(a: f64) -> Matrix3<f64> {
    let (s, c) = a.sin_cos();
    Matrix3::new(1.0, 0.0, 0.0, 0.0, c, -s, 0.0, s, c)
}
fn ry(a: f64) -> Matrix3<f64> {
    let (s, c) = a.sin_cos();
    Matrix3::new(c, 0.0, s, 0.0, 1.0, 0.0, -s, 0.0, c)
}
fn rz(a: f64) -> Matrix3<f64> {
    let (s, c) = a.sin_cos();
    Matrix3::new(c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0)
}
fn hat(w: Vector3<f64>) -> Matrix3<f64> {
    Matrix3::new(0.0, -w.z, w.y, w.z, 0.0, -w.x, -w.y, w.x, 0.0)
}

/// Σ a·sin(2πf t + φ) and its first two derivatives.
fn sines(t: f64, terms: &[(f64, f64, f64)]) -> (f64, f64, f64) {
    let (mut x, mut v, mut a) = (0.0, 0.0, 0.0);
    for &(amp, f, ph) in terms {
        let w = 2.0 * PI * f;
        let (s, c) = (w * t + ph).sin_cos();
        x += amp * s;
        v += amp * w * c;
        a -= amp * w * w * s;
    }
    (x, v, a)
}

const PX: [(f64, f64, f64); 2] = [(0.08, 0.7, 0.0), (0.015, 1.3, 1.0)];
const PY: [(f64, f64, f64); 2] = [(0.10, 0.45, 0.3), (0.01, 1.6, 0.0)];
const PZ: [(f64, f64, f64); 1] = [(0.04, 0.9, 2.0)];
const ROLL: [(f64, f64, f64); 2] = [(0.25, 0.6, 0.0), (0.1, 1.4, 0.5)];
const PITCH: [(f64, f64, f64); 2] = [(0.2, 0.5, 1.0), (0.08, 1.9, 0.0)];
const YAW: [(f64, f64, f64); 2] = [(0.4, 0.35, 0.2), (0.1, 1.1, 1.2)];

/// The reference body at true time t: position, rotation body → world, body rate,
/// specific force (all exact).
pub fn body(t: f64, moving: bool) -> (Vector3<f64>, Matrix3<f64>, Vector3<f64>, Vector3<f64>) {
    let gw = Vector3::new(0.0, 0.0, -G);
    if !moving {
        let r = rz(0.3) * ry(0.02) * rx(-0.03);
        return (
            Vector3::new(1.0, 2.0, 0.5),
            r,
            Vector3::zeros(),
            r.transpose() * -gw,
        );
    }
    let (x, _, ax) = sines(t, &PX);
    let (y, _, ay) = sines(t, &PY);
    let (z, _, az) = sines(t, &PZ);
    let (ph, dph, _) = sines(t, &ROLL);
    let (th, dth, _) = sines(t, &PITCH);
    let (ps, dps, _) = sines(t, &YAW);
    let r = rz(ps) * ry(th) * rx(ph);
    let (sp, cp) = ph.sin_cos();
    let (st, ct) = th.sin_cos();
    // body rates of ZYX Euler angles
    let w = Vector3::new(
        dph - st * dps,
        cp * dth + sp * ct * dps,
        -sp * dth + cp * ct * dps,
    );
    let acc = Vector3::new(ax, ay, az);
    (Vector3::new(x, y, z), r, w, r.transpose() * (acc - gw))
}

/// The body rate's time derivative (a fourth-order central difference of the exact rate:
/// its error, ~h⁴·ω⁽⁵⁾ ≈ 1e-14 rad/s², is far below any noise).
fn body_rate_dot(t: f64, moving: bool) -> Vector3<f64> {
    let h = 1e-3;
    let w = |s: f64| body(t + s, moving).2;
    (w(-2.0 * h) - w(-h) * 8.0 + w(h) * 8.0 - w(2.0 * h)) / (12.0 * h)
}

/// Quaternion [x, y, z, w] of a rotation matrix (Shepperd's method).
fn quat(m: &Matrix3<f64>) -> [f64; 4] {
    let tr = m.trace();
    let (x, y, z, w);
    if tr > 0.0 {
        let s = (tr + 1.0).sqrt() * 2.0;
        w = 0.25 * s;
        x = (m[(2, 1)] - m[(1, 2)]) / s;
        y = (m[(0, 2)] - m[(2, 0)]) / s;
        z = (m[(1, 0)] - m[(0, 1)]) / s;
    } else if m[(0, 0)] > m[(1, 1)] && m[(0, 0)] > m[(2, 2)] {
        let s = (1.0 + m[(0, 0)] - m[(1, 1)] - m[(2, 2)]).sqrt() * 2.0;
        w = (m[(2, 1)] - m[(1, 2)]) / s;
        x = 0.25 * s;
        y = (m[(0, 1)] + m[(1, 0)]) / s;
        z = (m[(0, 2)] + m[(2, 0)]) / s;
    } else if m[(1, 1)] > m[(2, 2)] {
        let s = (1.0 + m[(1, 1)] - m[(0, 0)] - m[(2, 2)]).sqrt() * 2.0;
        w = (m[(0, 2)] - m[(2, 0)]) / s;
        x = (m[(0, 1)] + m[(1, 0)]) / s;
        y = 0.25 * s;
        z = (m[(1, 2)] + m[(2, 1)]) / s;
    } else {
        let s = (1.0 + m[(2, 2)] - m[(0, 0)] - m[(1, 1)]).sqrt() * 2.0;
        w = (m[(1, 0)] - m[(0, 1)]) / s;
        x = (m[(0, 2)] + m[(2, 0)]) / s;
        y = (m[(1, 2)] + m[(2, 1)]) / s;
        z = 0.25 * s;
    }
    [x, y, z, w]
}

fn stamp(ns: i64) -> String {
    format!(
        "{}.{:09}",
        ns.div_euclid(1_000_000_000),
        ns.rem_euclid(1_000_000_000)
    )
}

/// The files written.
pub struct Written {
    /// The IMU log (EuRoC/ASL CSV layout).
    pub imu: PathBuf,
    /// The reference (TUM).
    pub reference: PathBuf,
    /// The injected noise per section axis (white noise and lines, the bias left out), at
    /// each IMU sample.
    pub noise: [Vec<f64>; 6],
}

/// Writes `spec`'s IMU log and reference into `dir`.
pub fn write(dir: &Path, spec: &Spec) -> Written {
    let mut rng = StdRng::seed_from_u64(spec.seed);
    let mut n = || -> f64 { StandardNormal.sample(&mut rng) };
    let r_ri = rz(spec.rotation[2]) * ry(spec.rotation[1]) * rx(spec.rotation[0]);
    let lever = Vector3::from(spec.lever);
    let sym = |s: f64, m: f64| {
        Matrix3::new(
            1.0 + s,
            m,
            -0.5 * m,
            m,
            1.0 - 0.5 * s,
            0.7 * m,
            -0.5 * m,
            0.7 * m,
            1.0 + 0.7 * s,
        )
    };
    let (mg, ma) = (
        sym(spec.scale, spec.misalign),
        sym(-0.8 * spec.scale, 1.3 * spec.misalign),
    );
    let gsens = Matrix3::from_diagonal_element(spec.g_sens);
    let mut bias = [0.01, -0.005, 0.02, 0.05, -0.1, 0.08];
    let count = (spec.seconds * spec.rate).round() as usize;
    let white: [f64; 6] = std::array::from_fn(|a| spec.n[a / 3] * spec.rate.sqrt());
    let walk: [f64; 6] = std::array::from_fn(|a| spec.k[a / 3] / spec.rate.sqrt());
    let phases: Vec<f64> = spec.lines.iter().map(|l| 0.37 * l.1).collect();
    let mut csv = String::from(
        "#timestamp [ns],w_RS_S_x [rad s^-1],w_RS_S_y [rad s^-1],w_RS_S_z [rad s^-1],a_RS_S_x [m s^-2],a_RS_S_y [m s^-2],a_RS_S_z [m s^-2]\n",
    );
    let mut noise: [Vec<f64>; 6] = Default::default();
    for k in 0..count {
        let t = k as f64 / spec.rate;
        let (_, _, w, f) = body(t, spec.motion);
        let wd = body_rate_dot(t, spec.motion);
        let w_i = r_ri.transpose() * w;
        let f_i = r_ri.transpose() * (f + (hat(wd) + hat(w) * hat(w)) * lever);
        let gyro = mg * w_i + gsens * f_i;
        let acc = ma * f_i;
        let mut v = [gyro.x, gyro.y, gyro.z, acc.x, acc.y, acc.z];
        let mut e = [0.0; 6];
        for a in 0..6 {
            bias[a] += walk[a] * n();
            e[a] = white[a] * n();
        }
        for (l, ph) in spec.lines.iter().zip(&phases) {
            e[l.0] += l.2 * (2.0 * PI * l.1 * t + ph).sin();
        }
        for a in 0..6 {
            v[a] += bias[a] + e[a];
            noise[a].push(e[a]);
        }
        let ns = T0_NS + (t * 1e9).round() as i64;
        let _ = writeln!(
            csv,
            "{ns},{:e},{:e},{:e},{:e},{:e},{:e}",
            v[0], v[1], v[2], v[3], v[4], v[5]
        );
    }
    let imu = dir.join("imu.csv");
    std::fs::write(&imu, csv).unwrap();
    // the reference: from 1 s before the IMU to 1 s after, on its own clock
    let mut tum = String::from("# t tx ty tz qx qy qz qw (reference body -> world)\n");
    let first = -(spec.ref_rate as i64);
    let last = ((spec.seconds + 1.0) * spec.ref_rate) as i64;
    for j in first..=last {
        let t = j as f64 / spec.ref_rate;
        let (p, r, _, _) = body(t, spec.motion);
        let p = p + Vector3::new(n(), n(), n()) * spec.ref_noise.0;
        let r = r * nalgebra::Rotation3::new(Vector3::new(n(), n(), n()) * spec.ref_noise.1)
            .into_inner();
        let q = quat(&r);
        let ns = T0_NS + ((t + spec.ref_offset) * 1e9).round() as i64;
        let _ = writeln!(
            tum,
            "{} {:e} {:e} {:e} {:e} {:e} {:e} {:e}",
            stamp(ns),
            p.x,
            p.y,
            p.z,
            q[0],
            q[1],
            q[2],
            q[3]
        );
    }
    let reference = dir.join("reference.tum");
    std::fs::write(&reference, tum).unwrap();
    Written {
        imu,
        reference,
        noise,
    }
}

#[test]
fn the_writers_motion_is_hand_held_and_its_rates_are_exact() {
    // body rates up to 2 rad/s, accelerations up to 3 m/s² (the hand-held motion)
    let (mut wmax, mut amax) = (0.0f64, 0.0f64);
    for k in 0..20_000 {
        let t = k as f64 * 0.01;
        let (_, r, w, f) = body(t, true);
        wmax = wmax.max(w.norm());
        amax = amax.max((r * f + Vector3::new(0.0, 0.0, -G)).norm());
        // the body rate against the rotation's own central difference
        let h = 1e-6;
        let (a, b) = (body(t - h, true).1, body(t + h, true).1);
        let d = (a.transpose() * b - b.transpose() * a) / (4.0 * h);
        let num = Vector3::new(d[(2, 1)], d[(0, 2)], d[(1, 0)]);
        assert!((num - w).norm() < 1e-6, "t {t}: {num} vs {w}");
    }
    assert!(wmax > 1.5 && wmax < 2.5, "{wmax}");
    assert!(amax > 2.0 && amax < 3.5, "{amax}");
}
