//! The analysis without a reference (a flight or drive log): the motion's band from the
//! signal itself, the operating noise above it.
//!
//! The signal's Welch PSD is the motion's plus the noise's. The motion (a vehicle's, a
//! hand's) lives at low frequencies and falls off steeply; the noise is a floor with lines.
//! The motion band's edge is the highest frequency below [`MOTION_CAP_HZ`] where the PSD's
//! mean over a third of an octave (lines included: a motion of a few strong tones is
//! motion) is above [`MOTION_RATIO`] times the floor high above it (the median floor over
//! [`HIGH_BAND`] of the Nyquist frequency); the band of the operating density starts
//! [`MOTION_MARGIN`] above it. Below the edge the noise is taken to be the floor above it;
//! lines above the cap are vibration.
//!
//! What cannot be separated without a reference is said in the report: motion above the
//! edge (structural vibration the vehicle's motion drives, a rotor's lines) counts as noise
//! — it is what the estimator meets; scale, misalignment, g-sensitivity and a time offset
//! cannot be estimated; noise inside the motion band is not seen.

use bag2mat::Sensor;
use rustfft::num_complex::Complex;

use super::{AXES, AxisOperating, Operating, Settings, band, phases};
use crate::input::ImuData;

/// The lowest lower band edge, Hz: below ~1 Hz an estimator's bias states take the error
/// (IEEE 952 reads N at τ = 1 s).
pub const BAND_LO_MIN: f64 = 1.0;
/// With a reference the band also starts this many times above the bias knots' rate
/// (their piecewise-linear bias takes the error below it).
pub const BIAS_BAND_FACTOR: f64 = 4.0;
/// The motion band ends where the floor is down to this many times the high floor.
pub const MOTION_RATIO: f64 = 2.0;
/// Above this frequency a signal is not taken to be motion (a hand's, a vehicle body's
/// motion stays below ~20 Hz; rotors and structures ring above): lines there are
/// vibration, counted as noise.
pub const MOTION_CAP_HZ: f64 = 20.0;
/// … and not above this share of the Nyquist frequency (a slow log).
pub const MOTION_CAP_NYQUIST: f64 = 0.5;
/// Half-width of the PSD's running mean the motion edge reads, octaves.
pub const FRACTION_OCTAVE: f64 = 1.0 / 6.0;
/// The operating band starts this factor above the motion band's edge.
pub const MOTION_MARGIN: f64 = 1.25;
/// The high floor is the PSD's median over this share of the Nyquist frequency.
pub const HIGH_BAND: (f64, f64) = (0.5, 0.95);

/// The median of the PSD over [`HIGH_BAND`] of the Nyquist frequency.
fn high_median(p: &crate::ieee952::psd::Psd, of: &[f64]) -> Option<f64> {
    let f_n = p.rate / 2.0;
    let mut v: Vec<f64> = p
        .freq
        .iter()
        .zip(of)
        .filter(|(f, _)| **f >= HIGH_BAND.0 * f_n && **f <= HIGH_BAND.1 * f_n)
        .map(|(_, s)| *s)
        .collect();
    if v.is_empty() {
        return None;
    }
    let k = v.len() / 2;
    Some(*v.select_nth_unstable_by(k, f64::total_cmp).1)
}

/// The mean over a sensor's axes of their PSDs' high floor (unit²/Hz): the noise level
/// far above any motion.
pub fn high_floor(series: &[&[f64]; 6], sensor: Sensor, rate: f64) -> Option<f64> {
    let mut sum = 0.0;
    for (i, s, _) in AXES {
        if s != sensor {
            continue;
        }
        let p = crate::ieee952::psd::welch(series[i], rate)?;
        sum += high_median(&p, &p.density)?;
    }
    Some(sum / 3.0)
}

/// The motion band's edge of one axis (module docs), Hz.
pub fn motion_edge(y: &[f64], rate: f64) -> Option<f64> {
    let p = crate::ieee952::psd::welch(y, rate)?;
    let hi = high_median(&p, &p.floor)?;
    let cap = MOTION_CAP_HZ.min(MOTION_CAP_NYQUIST * p.rate / 2.0);
    let k_hi = FRACTION_OCTAVE.exp2();
    let mut edge = 0.0;
    for k in 0..p.freq.len() {
        let f = p.freq[k];
        if f > cap {
            break;
        }
        // the PSD's mean over a third of an octave around f, lines included: motion is
        // motion whether it is broadband or a few strong tones
        let (a, b) = (f / k_hi, f * k_hi);
        let (mut sum, mut n) = (0.0, 0usize);
        for (g, d) in p.freq.iter().zip(&p.density) {
            if *g >= a && *g <= b {
                sum += d;
                n += 1;
            }
        }
        if n > 0 && sum / n as f64 > MOTION_RATIO * hi {
            edge = f;
        }
    }
    Some(edge)
}

/// `y` with the content below `lo` Hz removed (an FFT brick wall over the whole record,
/// zero phase): the operating noise series the IEEE 952 cross-check reads.
pub fn high_pass(y: &[f64], rate: f64, lo: f64) -> Vec<f64> {
    let n = y.len();
    if n == 0 {
        return Vec::new();
    }
    let mut planner = rustfft::FftPlanner::new();
    let (fwd, inv) = (planner.plan_fft_forward(n), planner.plan_fft_inverse(n));
    let mut buf: Vec<Complex<f64>> = y.iter().map(|&v| Complex::new(v, 0.0)).collect();
    fwd.process(&mut buf);
    for (k, z) in buf.iter_mut().enumerate() {
        let f = k.min(n - k) as f64 * rate / n as f64;
        if f < lo {
            *z = Complex::new(0.0, 0.0);
        }
    }
    inv.process(&mut buf);
    buf.iter().map(|z| z.re / n as f64).collect()
}

/// The analysis from the signal alone (module docs).
pub fn analyse(data: &ImuData, rate: f64, s: &Settings) -> Result<Operating, String> {
    let series = super::series_of(&data.axes);
    let present = |sensor: Sensor| data.absent != Some(sensor);
    let mut edges = [None, None];
    for (k, sensor) in [Sensor::Gyro, Sensor::Acc].into_iter().enumerate() {
        if !present(sensor) {
            continue;
        }
        let mut e: Option<f64> = None;
        for (i, s2, _) in AXES {
            if s2 == sensor {
                let x = motion_edge(series[i], rate)
                    .ok_or_else(|| format!("{} samples are too few for a PSD", series[i].len()))?;
                e = Some(e.map_or(x, |v| v.max(x)));
            }
        }
        edges[k] = e;
    }
    // one band edge for the record: the larger motion edge of the two sensors (the motion
    // is one), at least BAND_LO_MIN
    let edge = edges.iter().flatten().fold(0.0f64, |a, b| a.max(*b));
    let lo_min = (edge * MOTION_MARGIN).max(BAND_LO_MIN);
    let mut axes = Vec::new();
    let mut noise_series: [Vec<f64>; 6] = Default::default();
    for (i, sensor, axis) in AXES {
        if !present(sensor) {
            continue;
        }
        let b = band::analyse(&band::BandInput {
            y: series[i],
            rate,
            spline_err: None,
            band: s.band,
            lo_min,
        })
        .map_err(|e| format!("{}: {e}", sensor.axis_label(axis)))?;
        noise_series[i] = high_pass(series[i], rate, b.band.0);
        axes.push(AxisOperating {
            sensor,
            axis,
            band: b,
            motion_n: f64::NAN,
            offset_n: f64::NAN,
            jitter_n: f64::NAN,
            static_n: None,
        });
    }
    let split = axes
        .iter()
        .map(|a| a.band.band.0)
        .fold(BAND_LO_MIN, f64::max);
    let (spectrogram, phases) = phases::phases(&series, &series, data.absent, rate, split, s.band);
    let n = data.len();
    Ok(Operating {
        reference: None,
        rate,
        estimator_rate: s.estimator_rate.unwrap_or(rate),
        samples: n,
        t0: data.clock.t_ns.first().map_or(0.0, |t| *t as f64 * 1e-9),
        range: (0, n),
        axes,
        motion_edge: edges,
        phases,
        spectrogram,
        static_source: String::new(),
        static_an: None,
        operating_an: None,
        noise_series,
        notes: Vec::new(),
        cannot_separate: vec![
            format!("motion above {split:.2} Hz (a structure's vibration the motion drives, a rotor's lines) is counted as noise: it is what the estimator meets"),
            format!("noise below {split:.2} Hz is not seen: it is taken to be the floor above"),
            "scale, misalignment, g-sensitivity and a time offset cannot be estimated without a reference: their errors ride on the motion, inside its band".into(),
            "give a reference trajectory (--reference POSES) to separate them".into(),
        ],
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand::rngs::StdRng;
    use rand_distr::{Distribution, StandardNormal};
    use std::f64::consts::PI;

    /// Motion at 0.3–2 Hz far above white noise: its edge is found between 2 and 10 Hz;
    /// the high-passed series keeps the noise above the cut and nothing below.
    #[test]
    fn the_motion_edge_and_the_high_pass() {
        let mut rng = StdRng::seed_from_u64(9);
        let rate = 200.0;
        let y: Vec<f64> = (0..120_000)
            .map(|i| {
                let t = i as f64 / rate;
                let w: f64 = StandardNormal.sample(&mut rng);
                1e-3 * rate.sqrt() * w
                    + 0.5 * (2.0 * PI * 0.3 * t).sin()
                    + 0.3 * (2.0 * PI * 1.1 * t).sin()
                    + 0.2 * (2.0 * PI * 2.0 * t).sin()
            })
            .collect();
        let e = motion_edge(&y, rate).unwrap();
        assert!(e > 1.5 && e < 10.0, "edge {e}");
        let h = high_pass(&y, rate, 5.0);
        let p = crate::ieee952::psd::welch(&h, rate).unwrap();
        let below: f64 = p
            .freq
            .iter()
            .zip(&p.density)
            .filter(|(f, _)| **f < 3.0)
            .map(|(_, d)| *d)
            .fold(0.0, f64::max);
        assert!(below < 1e-4 * 2e-6, "{below}");
        let above = high_median(&p, &p.density).unwrap();
        assert!((above / 2e-6 - 1.0).abs() < 0.05, "{above}");
    }
}
