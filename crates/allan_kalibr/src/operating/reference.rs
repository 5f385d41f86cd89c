//! The reference trajectory as a spline, and the spline's own error.
//!
//! **Why the knot spacing is chosen so.** The spline that predicts the IMU from the poses
//! errs two ways. Too fine a spacing h passes the reference's own noise into the prediction
//! (a position noise σ_p reaches the specific force as ~σ_p/h², an orientation noise σ_θ the
//! body rate as ~σ_θ/h and the specific force through gravity as g·σ_θ); too coarse a
//! spacing misses motion (its error grows as h² in the specific force, h³ in the rate). Both
//! errors are estimated for every candidate spacing (multiples of the pose spacing):
//!
//! * the **model error** by Richardson extrapolation: the prediction with knots h against
//!   the one with 2h, (p_h − p_2h)/(2^q − 1), q the order of the spline's error in that
//!   quantity (3 for the body rate, a first derivative of a cubic; 2 for the specific
//!   force, a second derivative);
//! * the **reference-noise error** by propagating the reference's noise through the same
//!   fit: poses of pure noise at the reference's times, at the levels the fit's residuals
//!   show ([`reference_noise`]), fitted with knots h, read as an IMU.
//!
//! The spacing kept is the one whose summed error PSD stays below
//! [`super::band::SPLINE_SHARE`] of the IMU's noise floor from the lowest frequency on (the
//! widest band of trustworthy residual); the same two estimates, at the IMU's samples, are
//! what [`super::band`] takes out of the residual and reports — the spline's error is never
//! left as an unknown in the residual.

use nalgebra::{Matrix3, Quaternion, UnitQuaternion, Vector3};
use rand::SeedableRng;
use rand::rngs::StdRng;
use rand_distr::{Distribution, StandardNormal};
use rayon::prelude::*;

use crate::spline::{LsqReport, Pose, SplitSpline, so3};

/// Multiples of the pose spacing tried as knot spacings.
pub const KNOT_MULTIPLES: [i64; 6] = [1, 2, 3, 4, 6, 8];
/// Shortest knot spacing, ns (below it a spline follows the reference's stamp jitter).
pub const MIN_KNOT_NS: i64 = 1_000_000;
/// Longest knot spacing, ns (hand-held and vehicle motion has content at a few Hz).
pub const MAX_KNOT_NS: i64 = 200_000_000;
/// The reference noise is read from a fit with knots this many pose spacings apart (the
/// residuals of a finer fit hold less of the noise, of a coarser one more of the motion).
pub const NOISE_FIT_MULTIPLE: i64 = 4;
/// Seed of the noise realisation propagated through the fit (every RNG is seeded).
pub const NOISE_SEED: u64 = 0x5EED_0042;
/// Samples of the error series per candidate when choosing (2¹⁷: five minutes at 400 Hz; the
/// PSD comparison needs no more).
pub const CHOICE_SAMPLES: usize = 1 << 17;
/// Richardson orders: body rate (first derivative of a cubic), specific force (second).
pub const ORDER_GYRO: i32 = 3;
/// See [`ORDER_GYRO`].
pub const ORDER_ACC: i32 = 2;

/// The poses of a [`bag2mat::PoseSeries`] as the spline takes them (quaternions
/// normalised).
pub fn poses_of(s: &bag2mat::PoseSeries) -> Vec<Pose> {
    (0..s.len())
        .map(|i| {
            let [x, y, z, w] = s.orientation[i];
            let q = UnitQuaternion::from_quaternion(Quaternion::new(w, x, y, z));
            Pose {
                t_ns: s.t_ns[i],
                p: Vector3::from(s.position[i]),
                r: q.to_rotation_matrix().into_inner(),
            }
        })
        .collect()
}

/// The median spacing of the poses, ns.
pub fn pose_spacing(poses: &[Pose]) -> i64 {
    let mut d: Vec<i64> = poses.windows(2).map(|w| w[1].t_ns - w[0].t_ns).collect();
    if d.is_empty() {
        return 0;
    }
    let k = d.len() / 2;
    *d.select_nth_unstable(k).1
}

/// The spline fit with knots `dt_ns` apart from the first pose on.
pub fn fit(poses: &[Pose], dt_ns: i64) -> Result<(SplitSpline, LsqReport), String> {
    SplitSpline::fit_least_squares(poses, poses[0].t_ns, dt_ns).map_err(|e| e.to_string())
}

/// The reference's white noise, position (m) and orientation (rad) per coordinate, from the
/// residuals of a fit with knots [`NOISE_FIT_MULTIPLE`] pose spacings apart (an upper bound:
/// the residuals also hold motion the spline misses, which is negligible for motion well
/// below the knots' rate).
pub fn reference_noise(poses: &[Pose], pose_dt: i64) -> (f64, f64) {
    let Ok((_, rep)) = fit(poses, (NOISE_FIT_MULTIPLE * pose_dt).max(1)) else {
        return (0.0, 0.0);
    };
    // the RMS is over 3 coordinates and n poses; the fit took `n − dof` of the freedom
    let k = poses.len() as f64;
    let scale = (k / rep.dof.max(1.0)).sqrt() / 3f64.sqrt();
    (rep.rms_position * scale, rep.rms_rotation * scale)
}

/// Poses of pure white noise (σ_p, σ_θ) at the reference's times, around the origin.
fn noise_poses(poses: &[Pose], sp: f64, sr: f64) -> Vec<Pose> {
    let mut rng = StdRng::seed_from_u64(NOISE_SEED);
    let mut n = || -> f64 { StandardNormal.sample(&mut rng) };
    poses
        .iter()
        .map(|p| Pose {
            t_ns: p.t_ns,
            p: Vector3::new(n(), n(), n()) * sp,
            r: so3::exp(&(Vector3::new(n(), n(), n()) * sr)),
        })
        .collect()
}

/// A candidate spacing's three fits: the spline, the one with twice its spacing (for the
/// Richardson estimate) and the noise propagated through it.
#[derive(Debug, Clone)]
pub struct Fits {
    /// Knot spacing, ns.
    pub dt_ns: i64,
    /// The fit.
    pub spline: SplitSpline,
    /// What the fit did.
    pub report: LsqReport,
    /// Knots twice as far apart.
    pub coarse: Option<SplitSpline>,
    /// The reference's noise through the fit (`None` for a noise-free reference).
    pub noise: Option<SplitSpline>,
}

impl Fits {
    /// The three fits at spacing `dt_ns`.
    pub fn new(poses: &[Pose], dt_ns: i64, noise: (f64, f64)) -> Result<Fits, String> {
        let (spline, report) = fit(poses, dt_ns)?;
        let coarse = fit(poses, 2 * dt_ns).ok().map(|f| f.0);
        let noise = (noise.0 > 0.0 || noise.1 > 0.0)
            .then(|| fit(&noise_poses(poses, noise.0, noise.1), dt_ns).ok())
            .flatten()
            .map(|f| f.0);
        Ok(Fits {
            dt_ns,
            spline,
            report,
            coarse,
            noise,
        })
    }

    /// The spline's estimated error at time `t_ns` in the reference's body frame: body
    /// rate (rad/s) and specific force (m/s²), model and noise parts summed.
    pub fn error_at(&self, t_ns: i64) -> (Vector3<f64>, Vector3<f64>) {
        let mut g = Vector3::zeros();
        let mut a = Vector3::zeros();
        if let Some(c) = &self.coarse {
            let (x, y) = (self.spline.sample(t_ns), c.sample(t_ns));
            g += (x.gyro - y.gyro) / (2f64.powi(ORDER_GYRO) - 1.0);
            a += (x.acc - y.acc) / (2f64.powi(ORDER_ACC) - 1.0);
        }
        if let Some(n) = &self.noise {
            let x = n.sample(t_ns);
            g += x.gyro;
            a += x.acc - Vector3::new(0.0, 0.0, crate::spline::GRAVITY);
        }
        (g, a)
    }
}

/// The knot spacing chosen, with what was weighed.
#[derive(Debug, Clone)]
pub struct Choice {
    /// The fits at the spacing kept.
    pub fits: Fits,
    /// The median pose spacing, ns.
    pub pose_dt_ns: i64,
    /// The reference noise (m, rad).
    pub noise: (f64, f64),
    /// Each candidate spacing (ns) and the lowest frequency its error leaves clean (Hz).
    pub candidates: Vec<(i64, f64)>,
    /// Given by the user (`--knot-dt`), not chosen.
    pub given: bool,
}

/// The lowest frequency above which `err`'s PSD (mean over the 3 axes) stays below
/// [`super::band::SPLINE_SHARE`] × `floor`.
fn clean_edge(err: &[[f64; 3]], rate: f64, floor: f64) -> f64 {
    let mut mean: Option<Vec<f64>> = None;
    let mut freq = Vec::new();
    for k in 0..3 {
        let y: Vec<f64> = err.iter().map(|v| v[k]).collect();
        let Some(p) = crate::ieee952::psd::welch(&y, rate) else {
            return f64::INFINITY;
        };
        freq = p.freq.clone();
        match &mut mean {
            Some(m) => m
                .iter_mut()
                .zip(&p.density)
                .for_each(|(m, d)| *m += d / 3.0),
            None => mean = Some(p.density.iter().map(|d| d / 3.0).collect()),
        }
    }
    let Some(m) = mean else { return 0.0 };
    for k in (0..m.len()).rev() {
        let a = k.saturating_sub(3);
        let b = (k + 3).min(m.len() - 1);
        let s = m[a..=b].iter().sum::<f64>() / (b - a + 1) as f64;
        if s > super::band::SPLINE_SHARE * floor {
            return freq[k];
        }
    }
    0.0
}

/// Chooses the knot spacing (module docs): `floor` holds the IMU's noise floor per sensor
/// (gyro, acc; one-sided PSD, unit²/Hz; `None` for an absent sensor), `rate` its rate.
pub fn choose(
    poses: &[Pose],
    given_ns: Option<i64>,
    rate: f64,
    floor: [Option<f64>; 2],
) -> Result<Choice, String> {
    if poses.len() < 8 {
        return Err(format!(
            "the reference holds {} poses; a spline needs at least 8",
            poses.len()
        ));
    }
    let pose_dt = pose_spacing(poses);
    if pose_dt <= 0 {
        return Err("the reference's poses have no time spacing".into());
    }
    let noise = reference_noise(poses, pose_dt);
    let span = poses[poses.len() - 1].t_ns - poses[0].t_ns;
    let candidates: Vec<i64> = match given_ns {
        Some(h) => vec![h],
        None => {
            let mut c: Vec<i64> = KNOT_MULTIPLES
                .iter()
                .map(|k| k * pose_dt)
                .filter(|&h| (MIN_KNOT_NS..=MAX_KNOT_NS).contains(&h) && span / h >= 16)
                .collect();
            if c.is_empty() {
                c.push(pose_dt.max(MIN_KNOT_NS));
            }
            c
        }
    };
    let t0 = poses[0].t_ns;
    let n = (((span as f64) * 1e-9 * rate) as usize).min(CHOICE_SAMPLES);
    let times: Vec<i64> = (0..n)
        .map(|k| t0 + (k as f64 * 1e9 / rate).round() as i64)
        .collect();
    let scored: Vec<Result<(Fits, f64), String>> = candidates
        .par_iter()
        .map(|&h| {
            let f = Fits::new(poses, h, noise)?;
            let errs: Vec<(Vector3<f64>, Vector3<f64>)> =
                times.iter().map(|&t| f.error_at(t)).collect();
            let mut edge: f64 = 0.0;
            for (s, fl) in floor.iter().enumerate() {
                let Some(fl) = fl else { continue };
                let e: Vec<[f64; 3]> = errs
                    .iter()
                    .map(|(g, a)| if s == 0 { (*g).into() } else { (*a).into() })
                    .collect();
                edge = edge.max(clean_edge(&e, rate, *fl));
            }
            Ok((f, edge))
        })
        .collect();
    let mut best: Option<(Fits, f64)> = None;
    let mut table = Vec::new();
    let mut first_err = None;
    for s in scored {
        match s {
            Ok((f, e)) => {
                table.push((f.dt_ns, e));
                if best.as_ref().is_none_or(|b| e < b.1) {
                    best = Some((f, e));
                }
            }
            Err(e) => {
                first_err.get_or_insert(e);
            }
        }
    }
    let Some((fits, _)) = best else {
        return Err(first_err.unwrap_or_else(|| "no knot spacing fits the reference".into()));
    };
    Ok(Choice {
        fits,
        pose_dt_ns: pose_dt,
        noise,
        candidates: table,
        given: given_ns.is_some(),
    })
}

/// The rotation `m` closest to a 3×3 matrix (polar decomposition by SVD, det +1).
pub fn polar(m: &Matrix3<f64>) -> Matrix3<f64> {
    let svd = m.svd(true, true);
    let (Some(u), Some(vt)) = (svd.u, svd.v_t) else {
        return Matrix3::identity();
    };
    let mut r = u * vt;
    if r.determinant() < 0.0 {
        let mut u = u;
        u.column_mut(2).neg_mut();
        r = u * vt;
    }
    r
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pose(t: f64) -> Pose {
        Pose {
            t_ns: (t * 1e9).round() as i64,
            p: Vector3::new((1.3 * t).sin() * 0.3, (0.9 * t).cos() * 0.2, 0.05 * t),
            r: so3::exp(&Vector3::new(
                0.3 * (0.8 * t).sin(),
                0.2 * (1.4 * t).cos(),
                0.4 * t,
            )),
        }
    }

    /// A noise-free reference: the error estimates are far below any IMU's floor and the
    /// finest spacing is kept; a noisy one (0.5 mm, 0.3 mrad at 100 Hz) pushes the spacing
    /// up and its noise estimate is within 20 % of the truth.
    #[test]
    fn the_spacing_follows_the_reference_noise() {
        let clean: Vec<Pose> = (0..3000).map(|i| pose(i as f64 / 100.0)).collect();
        let floor = [Some(2.0 * 1e-3f64.powi(2)), Some(2.0 * 2e-2f64.powi(2))];
        let c = choose(&clean, None, 200.0, floor).unwrap();
        assert!(c.noise.0 < 1e-6 && c.noise.1 < 1e-6, "{:?}", c.noise);
        assert_eq!(c.fits.dt_ns, 10_000_000, "{:?}", c.candidates);
        let mut rng = StdRng::seed_from_u64(3);
        let (sp, sr) = (5e-4, 3e-4);
        let noisy: Vec<Pose> = clean
            .iter()
            .map(|p| {
                let mut n = || -> f64 { StandardNormal.sample(&mut rng) };
                Pose {
                    t_ns: p.t_ns,
                    p: p.p + Vector3::new(n(), n(), n()) * sp,
                    r: p.r * so3::exp(&(Vector3::new(n(), n(), n()) * sr)),
                }
            })
            .collect();
        let c = choose(&noisy, None, 200.0, floor).unwrap();
        assert!((c.noise.0 / sp - 1.0).abs() < 0.2, "{:?}", c.noise);
        assert!((c.noise.1 / sr - 1.0).abs() < 0.2, "{:?}", c.noise);
        assert!(c.fits.dt_ns > 10_000_000, "{:?}", c.candidates);
    }

    #[test]
    fn polar_of_a_scaled_rotation_is_the_rotation() {
        let r = so3::exp(&Vector3::new(0.3, -1.0, 0.5));
        let s = Matrix3::new(1.01, 0.002, 0.0, 0.002, 0.995, -0.001, 0.0, -0.001, 1.003);
        assert!((polar(&(r * s)) - r).abs().max() < 1e-12);
        assert!((polar(&r) - r).abs().max() < 1e-14);
    }
}
