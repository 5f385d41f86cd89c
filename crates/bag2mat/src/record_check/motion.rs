//! A record that is not static: the Allan analysis reads the sensor's noise, and motion is
//! not noise (a hand-held record puts its motion into every term; `sim`'s ellipse bag gives
//! an accelerometer "noise density" 100× the truth).
//!
//! Over one-second windows, the mean angular rate and the mean specific force (gravity's
//! direction and magnitude) are compared with their medians over the record, after
//! removing a fitted warm-up ([`super::warmup`]). A window is moving when either departs by
//! more than what the noise allows ([`MOTION_Z`] × the window's own white-noise σ) and more
//! than a static sensor's bias wanders ([`MOTION_RATE`], [`MOTION_ACC`]: about 3 °/s and 1°
//! of tilt). Moving windows in more than [`MOTION_REFUSE_SHARE`] of the record refuse the
//! corrected analysis; fewer are a warning with their time.

use super::{Finding, Kind, Level, warmup};
use crate::Sensor;

/// Window length, s.
pub const MOTION_WINDOW_S: f64 = 1.0;
/// A window's mean angular rate this far (rad/s, ≈ 2.9 °/s) from the record's median is
/// motion, not bias drift (a MEMS gyro's bias wanders by millirad/s over hours).
pub const MOTION_RATE: f64 = 0.05;
/// A window's mean specific force this far (m/s²: 0.9° of tilt, 1.5 % of g) from the
/// record's median is motion, not accelerometer bias drift.
pub const MOTION_ACC: f64 = 0.15;
/// ... and this many of the window's white-noise standard deviations.
pub const MOTION_Z: f64 = 10.0;
/// Moving windows in more than this share of the record refuse the corrected analysis.
pub const MOTION_REFUSE_SHARE: f64 = 0.05;
/// Specific force below this (m/s²) holds no gravity direction to speak of.
const MIN_GRAVITY: f64 = 1.0;

fn median(mut v: Vec<f64>) -> f64 {
    let k = v.len() / 2;
    *v.select_nth_unstable_by(k, f64::total_cmp).1
}

fn norm(v: [f64; 3]) -> f64 {
    (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()
}

/// The motion finding of the six columns (gyro x y z, acc x y z) sampled `tau0` s apart,
/// with each axis' fitted warm-up removed first; `sigma` is each column's per-sample noise
/// ([`super::outliers::noise_scale`]).
pub fn find(
    cols: &[&[f64]; 6],
    tau0: f64,
    sigma: &[f64; 6],
    warm: &[Option<warmup::Fit>],
) -> Option<Finding> {
    let n = cols[0].len();
    let w = ((MOTION_WINDOW_S / tau0).round() as usize).max(1);
    let j = n / w;
    if j < 10 {
        return None;
    }
    let wt = w as f64 * tau0;
    // window means, warm-up removed; per-window white-noise σ
    let means: Vec<Vec<f64>> = (0..6)
        .map(|k| {
            cols[k]
                .chunks_exact(w)
                .enumerate()
                .map(|(i, c)| {
                    let m = c.iter().sum::<f64>() / w as f64;
                    let t = (i as f64 + 0.5) * wt;
                    m - warm.get(k).copied().flatten().map_or(0.0, |f| f.drift(t))
                })
                .collect()
        })
        .collect();
    let sigma: Vec<f64> = sigma.iter().map(|s| s / (w as f64).sqrt()).collect();
    let reference: Vec<f64> = means.iter().map(|m| median(m.clone())).collect();
    let vec_at = |base: usize, i: usize| -> [f64; 3] {
        std::array::from_fn(|c| means[base + c][i] - reference[base + c])
    };
    let thr = |base: usize, floor: f64| {
        let s = (0..3).map(|c| sigma[base + c].powi(2)).sum::<f64>().sqrt();
        floor.max(MOTION_Z * s)
    };
    let (thr_g, thr_a) = (thr(0, MOTION_RATE), thr(3, MOTION_ACC));
    let g_ref = [reference[3], reference[4], reference[5]];
    let g = norm(g_ref);
    let (mut moving, mut first) = (0usize, None);
    let (mut max_g, mut max_a, mut max_tilt) = (0.0f64, 0.0f64, 0.0f64);
    let (mut mag_lo, mut mag_hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for (i, a) in (0..j).map(|i| (i, std::array::from_fn(|c| means[3 + c][i]))) {
        let a: [f64; 3] = a;
        let dg = norm(vec_at(0, i));
        let da = norm(vec_at(3, i));
        max_g = max_g.max(dg);
        max_a = max_a.max(da);
        let mag = norm(a);
        mag_lo = mag_lo.min(mag);
        mag_hi = mag_hi.max(mag);
        if g > MIN_GRAVITY && mag > 0.0 {
            let cos = (a[0] * g_ref[0] + a[1] * g_ref[1] + a[2] * g_ref[2]) / (mag * g);
            max_tilt = max_tilt.max(cos.clamp(-1.0, 1.0).acos());
        }
        if dg > thr_g || da > thr_a {
            moving += 1;
            first.get_or_insert(i);
        }
    }
    let first = first?;
    let share = moving as f64 / j as f64;
    let refuse = share > MOTION_REFUSE_SHARE;
    let gravity = if g > MIN_GRAVITY {
        format!(
            " (gravity tilted by up to {:.2}°, its magnitude between {mag_lo:.3} and {mag_hi:.3} m/s²)",
            max_tilt.to_degrees()
        )
    } else {
        String::new()
    };
    let text = format!(
        "the IMU is not static: in {moving} of {j} windows of {wt:.2} s ({:.1} %, the first at t = {:.1} s) the mean angular rate departs from its median by up to {max_g:.3e} rad/s ({:.2} °/s) or the specific force by up to {max_a:.3e} m/s²{gravity}, beyond what the noise and a bias drift allow ({thr_g:.2e} rad/s, {thr_a:.2e} m/s²); {}",
        100.0 * share,
        first as f64 * wt,
        max_g.to_degrees(),
        if refuse {
            "motion is not noise, so the IEEE 952 section is not computed (its terms would be the motion's); record the IMU at rest, or measure the noise in operation: allan_kalibr LOG --reference POSES (a reference trajectory), or --operating without one. The upstream-compatible part still runs, as upstream would, and carries the motion in every figure"
        } else {
            "the IMU moved briefly: the terms at τ near those times carry it"
        }
    );
    let (size, unit) = if max_a / thr_a >= max_g / thr_g {
        (max_a, Sensor::Acc.unit())
    } else {
        (max_g, Sensor::Gyro.unit())
    };
    let mut f = Finding::new(
        if refuse {
            Level::Refusal
        } else {
            Level::Warning
        },
        Kind::Motion,
        text,
    )
    .sized(size, unit);
    f.time = Some(first as f64 * wt);
    f.sample = Some(first * w);
    Some(f)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn still(n: usize) -> [Vec<f64>; 6] {
        // tiny deterministic jitter around a static pose
        std::array::from_fn(|k| {
            (0..n)
                .map(|i| {
                    let x = ((i * 7919 + k * 104_729) % 1000) as f64 / 1000.0 - 0.5;
                    (if k == 5 { 9.81 } else { 0.0 }) + 1e-3 * x
                })
                .collect()
        })
    }

    fn cols(c: &[Vec<f64>; 6]) -> [&[f64]; 6] {
        std::array::from_fn(|k| &c[k][..])
    }

    /// The motion finding of `c` sampled at `tau0`, as the record check calls it.
    fn motion(c: &[Vec<f64>; 6], tau0: f64) -> Option<Finding> {
        let sigma = std::array::from_fn(|k| super::super::outliers::noise_scale(&c[k]));
        find(&cols(c), tau0, &sigma, &[None; 6])
    }

    #[test]
    fn a_still_record_is_static() {
        let c = still(60_000);
        assert_eq!(motion(&c, 0.01), None);
    }

    #[test]
    fn a_slow_tilt_swing_refuses_and_a_bump_warns() {
        let rate = 100.0;
        let mut c = still(60_000);
        let w = 2.0 * std::f64::consts::PI * 0.05;
        let t = |i: usize| i as f64 / rate;
        let roll = |i: usize| 0.1 * (w * t(i)).sin();
        let add = |v: &mut Vec<f64>, f: &dyn Fn(usize) -> f64| {
            v.iter_mut().enumerate().for_each(|(i, x)| *x += f(i));
        };
        add(&mut c[0], &|i| 0.1 * w * (w * t(i)).cos());
        add(&mut c[4], &|i| 9.81 * roll(i).sin());
        add(&mut c[5], &|i| 9.81 * (roll(i).cos() - 1.0));
        let f = motion(&c, 1.0 / rate).expect("motion");
        assert_eq!(f.level, Level::Refusal, "{f}");
        // a ±5.7° roll: the specific force swings by g·sin(0.1) ≈ 1 m/s² around its median
        assert!(
            f.text.contains("tilted by up to") && f.size > Some(0.9),
            "{f}"
        );
        let mut c = still(60_000);
        for v in &mut c[3][30_000..30_200] {
            *v += 1.0;
        }
        let f = motion(&c, 1.0 / rate).expect("a bump");
        assert_eq!(f.level, Level::Warning, "{f}");
        assert_eq!(f.time, Some(300.0));
    }
}
