//! Whether a line the PSD finds near its lowest bins is a sinusoid the record holds.
//!
//! The PSD's local floor is a running median over a window of at least
//! [`psd::FLOOR_MIN_BINS`] bins either side ([`psd::floor`]); within
//! [`LOW_LINE_BINS`] of zero that window is cut by the spectrum's start, and on the steep
//! low end of a random walk or a Gauss–Markov bias (1/f², a Lorentzian) the median lies
//! below the spectrum there: the first bins stand out as "lines". On real static records
//! they were reported at 0.022–0.030 Hz with amplitudes of 2.8–6.1e-3 m/s² where a
//! least-squares sinusoid over the whole record holds at most 4.9e-4, and in the model
//! such a line (its coefficient free in sign) traded with the random walk.
//!
//! So a line below [`LOW_LINE_BINS`] bins is kept only where a sinusoid fitted over the
//! whole record confirms its amplitude: the record is demodulated at the line's frequency,
//! averaged in blocks (a band of ±[`SCAN_BINS`] PSD bins passes them), and the amplitude of
//! the best sinusoid within that band — frequencies 1/([`SCAN_STEP`]·T) apart, T the record
//! — must reach [`CONFIRM_SHARE`] of the PSD's. A sinusoid keeps its whole amplitude over
//! the record; a noise bump's coherent amplitude over T is √(S/T)-small, and a resonance
//! (a random narrow-band process) far less than its own. A resonance down there is not
//! confirmed: its bandwidth would be a few bins of a floor that is not one.

use std::f64::consts::PI;

use super::psd;
#[cfg(doc)]
use super::psd::{FLOOR_MIN_BINS, floor};

/// Lines below this many PSD bins need the whole-record confirmation (the floor window of
/// ±[`psd::FLOOR_MIN_BINS`] is cut by the spectrum's start below half of it, and leans
/// on the steep low end up to twice it).
pub const LOW_LINE_BINS: f64 = 2.0 * psd::FLOOR_MIN_BINS as f64;
/// The best whole-record sinusoid is searched within this many PSD bins of the line (its
/// frequency is known to a fraction of a bin; the PSD's peak is the window's ±1.5 bins).
pub const SCAN_BINS: f64 = 1.5;
/// Frequencies of the search are 1/(this·T) apart (a quarter of the record's resolution:
/// a sinusoid between two of them loses at most 1 % of its amplitude).
pub const SCAN_STEP: f64 = 4.0;
/// A line is confirmed where the whole-record sinusoid holds this share of the PSD's
/// amplitude at least (a sinusoid holds all of it up to the PSD's few-percent error).
pub const CONFIRM_SHARE: f64 = 0.5;

/// The amplitude of the best sinusoid over the whole record `y` (sample rate `rate`)
/// within ±`band` Hz of `f0` (module docs).
pub(crate) fn whole_record_amplitude(y: &[f64], rate: f64, f0: f64, band: f64) -> f64 {
    let n = y.len();
    if n < 2 {
        return 0.0;
    }
    let mean = y.iter().sum::<f64>() / n as f64;
    // blocks short enough that ±band passes (sinc(π·band·block) ≥ 0.99)
    let block = ((0.05 * rate / band.max(1e-12)) as usize).clamp(1, n);
    let w = 2.0 * PI * f0 / rate;
    let (mut re, mut im) = (Vec::new(), Vec::new());
    let (mut sr, mut si, mut count) = (0.0, 0.0, 0usize);
    // demodulated by e^(−iωk), the phase advanced by a rotation (re-anchored every block)
    for (b, chunk) in y.chunks(block).enumerate() {
        let k0 = b * block;
        let (mut c, mut s) = ((w * k0 as f64).cos(), -(w * k0 as f64).sin());
        let (cw, sw) = (w.cos(), -w.sin());
        for &v in chunk {
            let x = v - mean;
            sr += x * c;
            si += x * s;
            count += 1;
            (c, s) = (c * cw - s * sw, c * sw + s * cw);
        }
        re.push(sr / count as f64);
        im.push(si / count as f64);
        (sr, si, count) = (0.0, 0.0, 0);
    }
    let t = n as f64 / rate;
    let step = 1.0 / (SCAN_STEP * t);
    let steps = (band / step).ceil() as i64;
    let tb = block as f64 / rate;
    let mut best = 0.0f64;
    for q in -steps..=steps {
        let d = q as f64 * step;
        let wd = 2.0 * PI * d * tb;
        let (mut ar, mut ai) = (0.0, 0.0);
        let (cw, sw) = (wd.cos(), -wd.sin());
        // the block centres' phase: block b at (b + ½)·tb
        let (mut c, mut s) = ((0.5 * wd).cos(), -(0.5 * wd).sin());
        for (r, i) in re.iter().zip(&im) {
            ar += r * c - i * s;
            ai += r * s + i * c;
            (c, s) = (c * cw - s * sw, c * sw + s * cw);
        }
        let amp = 2.0 * ar.hypot(ai) / re.len() as f64;
        best = best.max(amp);
    }
    best
}

/// The lines of `lines` (found in the PSD `p` of `y`) that stand: each at or above
/// [`LOW_LINE_BINS`] bins, and below it each sinusoid the whole record confirms.
pub(crate) fn confirmed(y: &[f64], p: &psd::Psd, lines: Vec<psd::Line>) -> Vec<psd::Line> {
    let df = p.resolution();
    lines
        .into_iter()
        .filter(|l| {
            l.frequency >= LOW_LINE_BINS * df
                || (l.bandwidth == 0.0
                    && whole_record_amplitude(y, p.rate, l.frequency, SCAN_BINS * df)
                        >= CONFIRM_SHARE * l.amplitude)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand::rngs::StdRng;
    use rand_distr::{Distribution, StandardNormal};

    /// The scan's grid and the blocks' averaging lose at most this share of a sinusoid.
    const AMPLITUDE_REL_TOL: f64 = 0.03;

    /// A sinusoid between PSD bins keeps its amplitude; white noise alone holds a coherent
    /// amplitude of order √(S/T), far below a line's.
    #[test]
    fn a_sinusoid_keeps_its_whole_record_amplitude_and_noise_does_not() {
        let (rate, n) = (100.0, 400_000usize);
        let mut rng = StdRng::seed_from_u64(0x11E5);
        let (amp, f0) = (0.3, 0.0237);
        let y: Vec<f64> = (0..n)
            .map(|k| {
                let e: f64 = StandardNormal.sample(&mut rng);
                amp * (2.0 * PI * f0 * k as f64 / rate + 0.7).sin() + e
            })
            .collect();
        let band = 1.5 * rate / 16_384.0;
        // searched from a frequency half a PSD bin off
        let got = whole_record_amplitude(&y, rate, f0 + 0.5 * rate / 16_384.0, band);
        assert!((got / amp - 1.0).abs() < AMPLITUDE_REL_TOL, "{got}");
        let noise: Vec<f64> = (0..n).map(|_| StandardNormal.sample(&mut rng)).collect();
        let got = whole_record_amplitude(&noise, rate, f0, band);
        // white of unit variance: S = 2/rate per Hz one-sided, coherent amplitude
        // 2·√(1/n) per frequency, the best of a few hundred a few times that
        assert!(got < 0.05, "{got}");
    }
}
