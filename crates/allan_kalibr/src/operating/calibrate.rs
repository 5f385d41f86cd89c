//! What a calibration would estimate, estimated jointly, so that the residual is the noise
//! the estimator meets and not an error it would calibrate away.
//!
//! **The model.** With τ = t + δt the reference's time of the IMU sample at t, ω_R, f_R the
//! reference body's rate and specific force from the spline (f_R = Rᵀ(p̈ − g_W)):
//!
//! ```text
//! gyro = A_g ω_R(τ) + G f_meas(t) + b_g(t)
//! acc  = A_a [f_R(τ) + (ω̂̇ + ω̂²) p] + b_a(t)
//! ```
//!
//! A_g, A_a are general 3×3 maps: the IMU-to-reference rotation with each sensor's scale
//! and misalignment (their polar decomposition separates them); G is the gyro's
//! g-sensitivity (rad/s per m/s², on the measured specific force), p the lever arm (the
//! IMU's origin in the reference body frame, m), g_W the gravity in the reference's world
//! (its direction estimated, its magnitude [`crate::spline::GRAVITY`]), b_g, b_a the biases
//! and their drift as piecewise-linear functions with knots [`bias_knot_s`] apart. All of
//! them and the time offset δt are estimated **jointly** (Gauss–Newton on the weighted
//! residuals, each sensor weighted by its residual variance): a time offset leaks into a
//! rotation and a scale when they are fitted one at a time, a lever arm into a scale.
//!
//! **Where the motion does not excite a term** (a static record excites no scale; a record
//! without rotation no lever arm) a weak Gaussian prior decides it: scale and misalignment
//! ±[`PRIOR_SCALE`] around the nearest rotation, g-sensitivity ±[`PRIOR_G_SENS`], lever arm
//! ±[`PRIOR_LEVER`]; a term is reported as estimated only where the data dominate its prior
//! ([`Calibration::excited`]). The time offset starts from the peak of the correlation of
//! |ω| measured and predicted within ±`--max-offset` (rotation-free), and is not observable
//! without rotation (then it stays 0 and the report says so).

use nalgebra::{DMatrix, DVector, Matrix3, Vector3};
use rayon::prelude::*;

use super::reference::polar;
use crate::spline::{GRAVITY, SplitSpline, so3};

/// Prior standard deviation of each element of A − R (scale and misalignment), 5 %.
pub const PRIOR_SCALE: f64 = 0.05;
/// Prior standard deviation of each g-sensitivity element, rad/s per m/s² (MEMS gyros:
/// ~1e-4; 10× that).
pub const PRIOR_G_SENS: f64 = 1e-3;
/// Prior standard deviation of each lever-arm coordinate, m.
pub const PRIOR_LEVER: f64 = 1.0;
/// Prior standard deviation of a Gauss–Newton step of the gravity direction, rad (a
/// damping: the direction is free over the iterations).
pub const PRIOR_TILT_STEP: f64 = 0.2;
/// Prior standard deviation of a bias coefficient (unit of the sensor): no information,
/// only numerical safety.
pub const PRIOR_BIAS: f64 = 1e3;
/// A term is estimated (not its prior) when its standard error is below this share of its
/// prior's.
pub const EXCITED_SHARE: f64 = 0.2;
/// Most Gauss–Newton iterations.
pub const MAX_ITER: usize = 20;
/// The iterations stop when the time offset moves by less than this (s) …
pub const DT_TOL: f64 = 1e-9;
/// … and the linear terms by less than this.
pub const LINEAR_TOL: f64 = 1e-10;
/// Half-step of the numerical time derivatives of the prediction, ns.
pub const DERIVATIVE_STEP_NS: i64 = 250_000;
/// Pieces the normal equations are summed in, each on one thread, then added in order: a
/// count that does not depend on the machine, so every run gives the same bytes (a few
/// dozen partial matrices at most: small beside the samples).
const NORMAL_CHUNKS: usize = 32;
/// Grid step of the coarse time-offset search, s.
pub const COARSE_STEP: f64 = 0.005;
/// The reference must turn by this much (standard deviation of |ω|, rad/s) for the time
/// offset to be observable.
pub const MIN_ROTATION_STD: f64 = 0.02;
/// Fewest overlapping samples.
pub const MIN_SAMPLES: usize = 4096;

/// The bias knots' spacing for a record of `span` seconds: an eighth of it, within 5–60 s
/// (a bias drifts over minutes; the knots' band, below ~1/spacing, is left to the bias).
pub fn bias_knot_s(span: f64) -> f64 {
    (span / 8.0).clamp(5.0, 60.0)
}

/// The IMU samples the calibration reads: times, and gyro and acc (x y z) where present.
pub struct ImuSeries<'a> {
    /// Sample times, ns (the IMU's clock).
    pub t_ns: &'a [i64],
    /// Gyro x y z, rad/s.
    pub gyro: Option<[&'a [f64]; 3]>,
    /// Acc x y z, m/s².
    pub acc: Option<[&'a [f64]; 3]>,
    /// Sample rate, Hz.
    pub rate: f64,
}

/// The estimated calibration, with standard errors.
#[derive(Debug, Clone, PartialEq)]
pub struct Calibration {
    /// Time offset: the IMU sample at t is the reference at t + dt, s.
    pub dt: f64,
    /// Its standard error, s.
    pub dt_se: f64,
    /// The reference turned enough for the offset to be estimated.
    pub dt_observable: bool,
    /// Gyro map A_g (rotation reference → IMU with scale and misalignment).
    pub a_g: Matrix3<f64>,
    /// Standard errors of A_g's elements.
    pub a_g_se: Matrix3<f64>,
    /// g-sensitivity G, rad/s per m/s².
    pub g_sens: Matrix3<f64>,
    /// Its standard errors.
    pub g_sens_se: Matrix3<f64>,
    /// Acc map A_a.
    pub a_a: Matrix3<f64>,
    /// Standard errors of A_a's elements.
    pub a_a_se: Matrix3<f64>,
    /// Lever arm p (IMU origin in the reference body frame), m.
    pub lever: Vector3<f64>,
    /// Its standard errors.
    pub lever_se: Vector3<f64>,
    /// Gravity in the reference's world frame, m/s².
    pub gravity_w: Vector3<f64>,
    /// Bias knot spacing, s.
    pub bias_knot: f64,
    /// Gyro bias at each knot, rad/s.
    pub bias_g: Vec<Vector3<f64>>,
    /// Acc bias at each knot, m/s².
    pub bias_a: Vec<Vector3<f64>>,
    /// Residual standard deviation per sample, gyro and acc.
    pub sigma: [f64; 2],
    /// Gauss–Newton iterations.
    pub iterations: usize,
}

impl Calibration {
    /// Whether a term with standard error `se` and prior `prior` is the data's.
    pub fn excited(se: f64, prior: f64) -> bool {
        se < EXCITED_SHARE * prior
    }
}

/// The residuals and the series the report breaks them down with, per used sample
/// (index 0–2 gyro x y z, 3–5 acc x y z; empty for an absent sensor).
#[derive(Debug, Clone, Default)]
pub struct Fitted {
    /// The samples used: the input's indices `range.0..range.1`.
    pub range: (usize, usize),
    /// Measured − predicted.
    pub residual: [Vec<f64>; 6],
    /// The fitted bias.
    pub bias: [Vec<f64>; 6],
    /// What the calibration removed beyond rotation, offset and bias: scale, misalignment
    /// and g-sensitivity times the motion (a lever arm is geometry, not an error).
    pub motion: [Vec<f64>; 6],
    /// The time derivative of the predicted signal (the timing's share).
    pub derivative: [Vec<f64>; 6],
}

/// The spline's kinematics at one time: R, ω, ω̇, Rᵀa and its derivative.
#[derive(Clone, Copy)]
struct Kin {
    r: Matrix3<f64>,
    w: Vector3<f64>,
    wd: Vector3<f64>,
    ab: Vector3<f64>,
    abd: Vector3<f64>,
}

fn kin(s: &SplitSpline, t: i64) -> Kin {
    let h = DERIVATIVE_STEP_NS;
    let (x, p, m) = (s.sample(t), s.sample(t + h), s.sample(t - h));
    let dt = 2.0 * h as f64 * 1e-9;
    Kin {
        r: x.r,
        w: x.gyro,
        wd: (p.gyro - m.gyro) / dt,
        ab: x.r.transpose() * x.a,
        abd: (p.r.transpose() * p.a - m.r.transpose() * m.a) / dt,
    }
}

// Parameter layout.
const DT: usize = 0;
const AG: usize = 1;
const GS: usize = 10;
const AA: usize = 19;
const LEV: usize = 28;
const TILT: usize = 31;
const BIAS: usize = 33;

/// The index range of the samples the spline covers (with the offset's margin) and whose
/// time `covered` accepts, the longest run of them.
fn usable(
    t: &[i64],
    spline: &SplitSpline,
    margin_ns: i64,
    covered: &dyn Fn(i64) -> bool,
) -> (usize, usize) {
    let (a, b) = spline.range_ns();
    let ok = |k: usize| t[k] >= a + margin_ns && t[k] <= b - margin_ns && covered(t[k]);
    let (mut best, mut start) = ((0, 0), None);
    for k in 0..=t.len() {
        match (k < t.len() && ok(k), start) {
            (true, None) => start = Some(k),
            (false, Some(s)) => {
                if k - s > best.1 - best.0 {
                    best = (s, k);
                }
                start = None;
            }
            _ => {}
        }
    }
    best
}

/// The coarse time offset: the lag within ±`max_offset` s of the best correlation of the
/// measured and predicted |ω| on a [`COARSE_STEP`] grid, refined by a parabola; `None`
/// when the reference does not turn enough.
fn coarse_offset(
    t: &[i64],
    gyro: [&[f64]; 3],
    spline: &SplitSpline,
    max_offset: f64,
) -> Option<f64> {
    let step = COARSE_STEP;
    let t0 = t[0];
    let cells = ((t[t.len() - 1] - t0) as f64 * 1e-9 / step) as usize + 1;
    let (mut sum, mut cnt) = (vec![0.0; cells], vec![0u32; cells]);
    for k in 0..t.len() {
        let c = (((t[k] - t0) as f64 * 1e-9) / step).round() as usize;
        if c < cells {
            sum[c] += (gyro[0][k].powi(2) + gyro[1][k].powi(2) + gyro[2][k].powi(2)).sqrt();
            cnt[c] += 1;
        }
    }
    let lmax = (max_offset / step).ceil() as i64;
    let grid: Vec<f64> = (0..cells as i64 + 2 * lmax + 1)
        .into_par_iter()
        .map(|j| {
            let tt = t0 + (((j - lmax) as f64) * step * 1e9).round() as i64;
            spline.sample(tt).gyro.norm()
        })
        .collect();
    let n = grid.len() as f64;
    let gm = grid.iter().sum::<f64>() / n;
    let gs = (grid.iter().map(|v| (v - gm).powi(2)).sum::<f64>() / n).sqrt();
    if gs < MIN_ROTATION_STD {
        return None;
    }
    let m: Vec<(usize, f64)> = (0..cells)
        .filter(|&c| cnt[c] > 0)
        .map(|c| (c, sum[c] / cnt[c] as f64))
        .collect();
    let mm = m.iter().map(|x| x.1).sum::<f64>() / m.len() as f64;
    let corr: Vec<f64> = (-lmax..=lmax)
        .into_par_iter()
        .map(|l| {
            let (mut sxy, mut syy, mut sy) = (0.0, 0.0, 0.0);
            for &(c, v) in &m {
                let y = grid[(c as i64 + lmax + l) as usize];
                sxy += (v - mm) * y;
                sy += y;
                syy += y * y;
            }
            let k = m.len() as f64;
            let vy = (syy - sy * sy / k).max(f64::MIN_POSITIVE);
            sxy / vy.sqrt()
        })
        .collect();
    let (best, _) = corr.iter().enumerate().max_by(|a, b| a.1.total_cmp(b.1))?;
    let frac = if best > 0 && best + 1 < corr.len() {
        let (a, b, c) = (corr[best - 1], corr[best], corr[best + 1]);
        let d = a - 2.0 * b + c;
        if d < 0.0 { 0.5 * (a - c) / d } else { 0.0 }
    } else {
        0.0
    };
    Some((best as f64 - lmax as f64 + frac) * step)
}

/// The parameters and the state the iterations carry.
struct State {
    theta: DVector<f64>,
    g0: Vector3<f64>,
    nb: usize,
}

impl State {
    fn mat(&self, at: usize) -> Matrix3<f64> {
        Matrix3::from_fn(|i, c| self.theta[at + 3 * i + c])
    }

    fn lever(&self) -> Vector3<f64> {
        Vector3::new(self.theta[LEV], self.theta[LEV + 1], self.theta[LEV + 2])
    }

    /// Two unit vectors orthogonal to g0: the directions of a tilt step.
    fn tilt_axes(&self) -> [Vector3<f64>; 2] {
        let g = self.g0.normalize();
        let a = if g.x.abs() < 0.9 {
            Vector3::x()
        } else {
            Vector3::y()
        };
        let e1 = g.cross(&a).normalize();
        [e1, g.cross(&e1)]
    }

    fn gravity(&self) -> Vector3<f64> {
        let [e1, e2] = self.tilt_axes();
        so3::exp(&(e1 * self.theta[TILT] + e2 * self.theta[TILT + 1])) * self.g0
    }

    fn bias(&self, sensor: usize, l: usize) -> Vector3<f64> {
        let at = BIAS + sensor * 3 * self.nb;
        Vector3::new(
            self.theta[at + l],
            self.theta[at + self.nb + l],
            self.theta[at + 2 * self.nb + l],
        )
    }
}

/// Joint estimation (module docs) over the samples of `imu` the spline covers and
/// `covered` accepts; returns the calibration and the residual series.
pub fn calibrate(
    imu: &ImuSeries,
    spline: &SplitSpline,
    knot_ns: i64,
    covered: &dyn Fn(i64) -> bool,
    max_offset: f64,
) -> Result<(Calibration, Fitted), String> {
    let margin = 2 * knot_ns + (max_offset * 1e9).ceil() as i64 + DERIVATIVE_STEP_NS;
    let (k0, k1) = usable(imu.t_ns, spline, margin, covered);
    let n = k1 - k0;
    if n < MIN_SAMPLES {
        let (a, b) = spline.range_ns();
        return Err(format!(
            "the IMU record and the reference overlap in {n} samples ({MIN_SAMPLES} at least): IMU {:.3} .. {:.3} s, reference {:.3} .. {:.3} s (the clocks must agree within --max-offset {max_offset} s, and the reference must have no long gaps)",
            imu.t_ns.first().map_or(0.0, |t| *t as f64 * 1e-9),
            imu.t_ns.last().map_or(0.0, |t| *t as f64 * 1e-9),
            a as f64 * 1e-9,
            b as f64 * 1e-9
        ));
    }
    let t = &imu.t_ns[k0..k1];
    let gyro = imu
        .gyro
        .map(|g| std::array::from_fn::<&[f64], 3, _>(|i| &g[i][k0..k1]));
    let acc = imu
        .acc
        .map(|a| std::array::from_fn::<&[f64], 3, _>(|i| &a[i][k0..k1]));
    let meas = |s: usize, i: usize, k: usize| -> f64 {
        match s {
            0 => gyro.map_or(0.0, |g| g[i][k]),
            _ => acc.map_or(0.0, |a| a[i][k]),
        }
    };
    // the time offset's start
    let coarse = gyro.and_then(|g| coarse_offset(t, g, spline, max_offset));
    let dt_observable = coarse.is_some();
    let dt0 = coarse.unwrap_or(0.0);
    // bias knots
    let span = (t[n - 1] - t[0]) as f64 * 1e-9;
    let bias_knot = bias_knot_s(span);
    let nb = (span / bias_knot).ceil() as usize + 1;
    let hat = |k: usize| -> (usize, f64) {
        let x = (t[k] - t[0]) as f64 * 1e-9 / bias_knot;
        let l = (x.floor() as usize).min(nb - 2);
        (l, x - l as f64)
    };
    let p_count = BIAS + 6 * nb;
    let mut st = State {
        theta: DVector::zeros(p_count),
        g0: Vector3::new(0.0, 0.0, -GRAVITY),
        nb,
    };
    st.theta[DT] = dt0;
    let eval = |dt: f64| -> Vec<Kin> {
        (0..n)
            .into_par_iter()
            .map(|k| kin(spline, t[k] + (dt * 1e9).round() as i64))
            .collect()
    };
    let mut kins = eval(dt0);
    let mut kin_dt = dt0;
    // start: the rotation from the gyro (A and b by least squares, then the nearest
    // rotation), else from gravity; gravity's direction from the specific force
    let r0 = start_rotation(&kins, gyro, acc, n);
    for i in 0..3 {
        for c in 0..3 {
            st.theta[AG + 3 * i + c] = r0[(i, c)];
            st.theta[AA + 3 * i + c] = r0[(i, c)];
        }
    }
    if let Some(a) = acc {
        let mut g = Vector3::zeros();
        for (k, kk) in kins.iter().enumerate() {
            let f = Vector3::new(a[0][k], a[1][k], a[2][k]);
            g -= kk.r * (r0.transpose() * f - kk.ab);
        }
        if g.norm() > 0.0 {
            st.g0 = g.normalize() * GRAVITY;
        }
    }
    // per-sensor variance from first differences (white noise dominates them)
    let mut sigma2 = [1.0f64; 2];
    for (s, sig) in sigma2.iter_mut().enumerate() {
        let present = if s == 0 {
            gyro.is_some()
        } else {
            acc.is_some()
        };
        if present {
            let mut v = 0.0;
            for i in 0..3 {
                for k in 1..n {
                    v += (meas(s, i, k) - meas(s, i, k - 1)).powi(2);
                }
            }
            *sig = (v / (3.0 * (n - 1) as f64) / 2.0).max(f64::MIN_POSITIVE);
        }
    }
    let mean_acc: Vector3<f64> = match acc {
        Some(a) => Vector3::from_fn(|i, _| a[i].iter().sum::<f64>() / n as f64),
        None => Vector3::zeros(),
    };
    let mut iterations = 0;
    let mut cov;
    loop {
        iterations += 1;
        if (st.theta[DT] - kin_dt).abs() > 1e-7 {
            kin_dt = st.theta[DT];
            kins = eval(kin_dt);
        }
        let ag = st.mat(AG);
        let gs = st.mat(GS);
        let aa = st.mat(AA);
        let lev = st.lever();
        let gw = st.gravity();
        let [e1, e2] = st.tilt_axes();
        let w = [1.0 / sigma2[0], 1.0 / sigma2[1]];
        let dshift = st.theta[DT] - kin_dt;
        let st_ref = &st;
        type Normal = (DMatrix<f64>, DVector<f64>, [f64; 2]);
        let zero = || -> Normal {
            (
                DMatrix::<f64>::zeros(p_count, p_count),
                DVector::<f64>::zeros(p_count),
                [0.0f64; 2],
            )
        };
        let normal = |(mut h, mut gv, mut ss): Normal, k: usize| {
            let kk = &kins[k];
            let (l, u) = hat(k);
            let fr = kk.ab - kk.r.transpose() * gw
                + (kk.abd + kk.w.cross(&(kk.r.transpose() * gw))) * dshift;
            let frd = kk.abd + kk.w.cross(&(kk.r.transpose() * gw));
            let w_b = kk.w + kk.wd * dshift;
            let km = so3::hat(&kk.wd) + so3::hat(&w_b) * so3::hat(&w_b);
            let lv = km * lev;
            let mut add = |idx: &[usize], val: &[f64], r: f64, wt: f64| {
                for a in 0..idx.len() {
                    gv[idx[a]] += wt * val[a] * r;
                    for b in 0..idx.len() {
                        h[(idx[a], idx[b])] += wt * val[a] * val[b];
                    }
                }
            };
            if gyro.is_some() {
                let fm = if acc.is_some() {
                    Vector3::new(meas(1, 0, k), meas(1, 1, k), meas(1, 2, k))
                } else {
                    Vector3::zeros()
                };
                let pred =
                    ag * w_b + gs * fm + st_ref.bias(0, l) * (1.0 - u) + st_ref.bias(0, l + 1) * u;
                let d = ag * kk.wd;
                for i in 0..3 {
                    let r = meas(0, i, k) - pred[i];
                    ss[0] += r * r;
                    let bi = BIAS + i * nb + l;
                    let idx = [
                        DT,
                        AG + 3 * i,
                        AG + 3 * i + 1,
                        AG + 3 * i + 2,
                        GS + 3 * i,
                        GS + 3 * i + 1,
                        GS + 3 * i + 2,
                        bi,
                        bi + 1,
                    ];
                    let val = [d[i], w_b.x, w_b.y, w_b.z, fm.x, fm.y, fm.z, 1.0 - u, u];
                    add(&idx, &val, r, w[0]);
                }
            }
            if acc.is_some() {
                let x = fr + lv;
                let pred = aa * x + st_ref.bias(1, l) * (1.0 - u) + st_ref.bias(1, l + 1) * u;
                let d = aa * frd;
                let dl = aa * km;
                let rt = kk.r.transpose();
                let dt1 = aa * (rt * -(e1.cross(&gw)));
                let dt2 = aa * (rt * -(e2.cross(&gw)));
                for i in 0..3 {
                    let r = meas(1, i, k) - pred[i];
                    ss[1] += r * r;
                    let bi = BIAS + 3 * nb + i * nb + l;
                    let idx = [
                        DT,
                        AA + 3 * i,
                        AA + 3 * i + 1,
                        AA + 3 * i + 2,
                        LEV,
                        LEV + 1,
                        LEV + 2,
                        TILT,
                        TILT + 1,
                        bi,
                        bi + 1,
                    ];
                    let val = [
                        d[i],
                        x.x,
                        x.y,
                        x.z,
                        dl[(i, 0)],
                        dl[(i, 1)],
                        dl[(i, 2)],
                        dt1[i],
                        dt2[i],
                        1.0 - u,
                        u,
                    ];
                    add(&idx, &val, r, w[1]);
                }
            }
            (h, gv, ss)
        };
        // a fixed number of chunks, summed in order: the same sums on every run (rayon's
        // fold/reduce splits by work stealing, and f64 addition is not associative: the last
        // digits of the operating densities changed from run to run)
        let chunk = n.div_ceil(NORMAL_CHUNKS).max(1);
        let (h, g, ss) = (0..n.div_ceil(chunk))
            .into_par_iter()
            .map(|c| (c * chunk..n.min((c + 1) * chunk)).fold(zero(), normal))
            .collect::<Vec<Normal>>()
            .into_iter()
            .fold(zero(), |a, b| {
                (a.0 + b.0, a.1 + b.1, [a.2[0] + b.2[0], a.2[1] + b.2[1]])
            });
        let mut h = h;
        let mut g = g;
        // priors (module docs): A − R, G, lever arm, the tilt step, the biases
        let prior = |i: usize, sd: f64, mean: f64, h: &mut DMatrix<f64>, g: &mut DVector<f64>| {
            let wp = 1.0 / (sd * sd);
            h[(i, i)] += wp;
            g[i] += wp * (mean - st_ref.theta[i]);
        };
        let (rg, ra) = (polar(&ag), polar(&aa));
        for i in 0..3 {
            for c in 0..3 {
                prior(AG + 3 * i + c, PRIOR_SCALE, rg[(i, c)], &mut h, &mut g);
                prior(AA + 3 * i + c, PRIOR_SCALE, ra[(i, c)], &mut h, &mut g);
                prior(GS + 3 * i + c, PRIOR_G_SENS, 0.0, &mut h, &mut g);
            }
            prior(LEV + i, PRIOR_LEVER, 0.0, &mut h, &mut g);
        }
        for j in 0..2 {
            prior(TILT + j, PRIOR_TILT_STEP, 0.0, &mut h, &mut g);
        }
        for i in BIAS..p_count {
            prior(i, PRIOR_BIAS, 0.0, &mut h, &mut g);
        }
        prior(DT, max_offset.max(1e-3), dt0, &mut h, &mut g);
        if !dt_observable {
            // no rotation: the offset is the start's, by fiat
            h[(DT, DT)] += 1e30;
        }
        let Some(ch) = h.clone().cholesky() else {
            return Err("the calibration's normal equations are singular".into());
        };
        let step = ch.solve(&g);
        cov = ch.inverse();
        let d_dt = step[DT].abs();
        let d_lin = (AG..TILT).map(|i| step[i].abs()).fold(0.0, f64::max);
        st.theta += &step;
        // fold the tilt into g0
        st.g0 = st.gravity();
        st.theta[TILT] = 0.0;
        st.theta[TILT + 1] = 0.0;
        // the weights from the residuals (before the step: one iteration behind)
        for s in 0..2 {
            let present = if s == 0 {
                gyro.is_some()
            } else {
                acc.is_some()
            };
            if present {
                sigma2[s] = (ss[s] / (3 * n) as f64).max(f64::MIN_POSITIVE);
            }
        }
        if (iterations >= 3 && d_dt < DT_TOL && d_lin < LINEAR_TOL) || iterations == MAX_ITER {
            break;
        }
    }
    if (st.theta[DT] - kin_dt).abs() > 0.0 {
        kin_dt = st.theta[DT];
        kins = eval(kin_dt);
    }
    // the residuals and their parts at the estimate
    let ag = st.mat(AG);
    let gs = st.mat(GS);
    let aa = st.mat(AA);
    let lev = st.lever();
    let gw = st.gravity();
    let (rg, ra) = (polar(&ag), polar(&aa));
    let mut fitted = Fitted {
        range: (k0, k1),
        ..Fitted::default()
    };
    let per: Vec<[[f64; 4]; 6]> = (0..n)
        .into_par_iter()
        .map(|k| {
            let kk = &kins[k];
            let (l, u) = hat(k);
            let mut out = [[0.0; 4]; 6];
            if gyro.is_some() {
                let fm = if acc.is_some() {
                    Vector3::new(meas(1, 0, k), meas(1, 1, k), meas(1, 2, k))
                } else {
                    Vector3::zeros()
                };
                let b = st.bias(0, l) * (1.0 - u) + st.bias(0, l + 1) * u;
                let pred = ag * kk.w + gs * fm + b;
                let mot = (ag - rg) * kk.w + gs * (fm - mean_acc);
                let d = ag * kk.wd;
                for i in 0..3 {
                    out[i] = [meas(0, i, k) - pred[i], b[i], mot[i], d[i]];
                }
            }
            if acc.is_some() {
                let fr = kk.ab - kk.r.transpose() * gw;
                let frd = kk.abd + kk.w.cross(&(kk.r.transpose() * gw));
                let km = so3::hat(&kk.wd) + so3::hat(&kk.w) * so3::hat(&kk.w);
                let x = fr + km * lev;
                let b = st.bias(1, l) * (1.0 - u) + st.bias(1, l + 1) * u;
                let pred = aa * x + b;
                let mot = (aa - ra) * x;
                let d = aa * frd;
                for i in 0..3 {
                    out[3 + i] = [meas(1, i, k) - pred[i], b[i], mot[i], d[i]];
                }
            }
            out
        })
        .collect();
    for a in 0..6 {
        let present = if a < 3 { gyro.is_some() } else { acc.is_some() };
        if !present {
            continue;
        }
        fitted.residual[a] = per.iter().map(|p| p[a][0]).collect();
        fitted.bias[a] = per.iter().map(|p| p[a][1]).collect();
        fitted.motion[a] = per.iter().map(|p| p[a][2]).collect();
        fitted.derivative[a] = per.iter().map(|p| p[a][3]).collect();
    }
    let se = |i: usize| cov[(i, i)].max(0.0).sqrt();
    let se_mat = |at: usize| Matrix3::from_fn(|i, c| se(at + 3 * i + c));
    let cal = Calibration {
        dt: st.theta[DT],
        dt_se: if dt_observable { se(DT) } else { f64::NAN },
        dt_observable,
        a_g: ag,
        a_g_se: se_mat(AG),
        g_sens: gs,
        g_sens_se: se_mat(GS),
        a_a: aa,
        a_a_se: se_mat(AA),
        lever: lev,
        lever_se: Vector3::new(se(LEV), se(LEV + 1), se(LEV + 2)),
        gravity_w: gw,
        bias_knot,
        bias_g: (0..nb).map(|l| st.bias(0, l)).collect(),
        bias_a: (0..nb).map(|l| st.bias(1, l)).collect(),
        sigma: [sigma2[0].sqrt(), sigma2[1].sqrt()],
        iterations,
    };
    Ok((cal, fitted))
}

/// The starting rotation reference → IMU: from the gyro when the reference turns in
/// every direction (A and a bias by least squares, then the nearest rotation), else the
/// smallest rotation taking the predicted mean specific force (gravity, z up) onto the
/// measured one, else the identity.
fn start_rotation(
    kins: &[Kin],
    gyro: Option<[&[f64]; 3]>,
    acc: Option<[&[f64]; 3]>,
    n: usize,
) -> Matrix3<f64> {
    if let Some(g) = gyro {
        // normal equations of [A | b] on rows (ω_R, 1)
        let mut m = nalgebra::Matrix4::<f64>::zeros();
        let mut rhs = nalgebra::Matrix4x3::<f64>::zeros();
        for (k, kk) in kins.iter().enumerate() {
            let x = nalgebra::Vector4::new(kk.w.x, kk.w.y, kk.w.z, 1.0);
            m += x * x.transpose();
            let y = nalgebra::RowVector3::new(g[0][k], g[1][k], g[2][k]);
            rhs += x * y;
        }
        let cov = m.fixed_view::<3, 3>(0, 0) / n as f64 - {
            let mu = m.fixed_view::<3, 1>(0, 3) / n as f64;
            mu * mu.transpose()
        };
        let min_eig = cov.symmetric_eigenvalues().min();
        if min_eig > MIN_ROTATION_STD.powi(2)
            && let Some(sol) = m.cholesky().map(|c| c.solve(&rhs))
        {
            let a = sol.fixed_view::<3, 3>(0, 0).transpose().into_owned();
            return polar(&a);
        }
    }
    if let Some(a) = acc {
        let mut fr = Vector3::zeros();
        let mut fm = Vector3::zeros();
        for (k, kk) in kins.iter().enumerate() {
            fr += kk.ab + kk.r.transpose() * Vector3::new(0.0, 0.0, GRAVITY);
            fm += Vector3::new(a[0][k], a[1][k], a[2][k]);
        }
        if fr.norm() > 0.0 && fm.norm() > 0.0 {
            let (u, v) = (fr.normalize(), fm.normalize());
            let axis = u.cross(&v);
            let s = axis.norm();
            if s > 1e-12 {
                return so3::exp(&(axis / s * s.atan2(u.dot(&v))));
            }
        }
    }
    Matrix3::identity()
}
