//! The operating noise density of one axis from its residual's PSD, in the estimator's
//! band, with its 95 % interval and its parts.
//!
//! **What is measured.** An estimator (Kalibr, VINS, OpenVINS, ORB-SLAM3, Basalt) takes
//! each IMU sample's noise as white with the per-sample variance N²·f_s (its
//! discretisation σ_d = N·√f_s). The white-noise density with the variance the residual
//! actually has per sample is N_op² = σ²_op / f_s = (1 / (2 f_N)) ∫₀^{f_N} S(f) df, S the
//! one-sided PSD and f_N = f_s/2: white noise of density N gives N_op = N, a line of
//! amplitude A adds A²/(2 f_s), whatever its frequency below f_N. Below the band's lower
//! edge f_lo the residual is not noise (the bias states absorb its drift, the motion and the
//! spline's own error live there), so S is taken as the broadband floor F̄ there:
//!
//! ```text
//! N_op² = F̄/2 + Σ_lines in band ∫ (S − F̄) df / (2 f_N)      (floor part + line part)
//! F̄ = mean of S − S_spline over the band's bins outside lines
//! ```
//!
//! **The spline's own error** (its PSD S_spline, estimated by [`super::reference`]) is taken
//! out of S before anything else; the band starts where it is below [`SPLINE_SHARE`] of the
//! floor, so what is taken out is a small correction, and its whole size counts in the
//! interval ([`SPLINE_ERROR_REL_SD`]).
//!
//! **The 95 % interval.** A Welch bin of K segments has variance S²/K, and a sum over
//! neighbouring Hann bins correlates as [`HANN_BIN_VARIANCE`] (1 + 2·(4/9 + 1/36)); the
//! floor's mean over M bins therefore has variance 1.944·ΣS²/(K·M²). A line is a
//! deterministic sinusoid: its estimated power varies only through the noise under it,
//! 2·L·F̄ + F̄² per bin. The sum of these variances V gives the estimate Satterthwaite's
//! equivalent degrees of freedom ν = 2·N_op⁴/V, and N_op ~ √(χ²_ν/ν) gives the interval
//! ([`crate::chi2_interval`]): a 95 % statement whose coverage the seeded studies count.

use crate::ieee952::ci::chi2_interval;
use crate::ieee952::psd::{self, Line, Psd};

/// The band starts where the estimated spline error's PSD is below this share of the
/// residual's floor at every frequency above (there it moves N_op by at most a few %).
pub const SPLINE_SHARE: f64 = 0.1;
/// Relative standard deviation counted for the spline error taken out of the band (its
/// estimate is a Richardson extrapolation and one noise realisation: good to a factor of
/// about two, so half of it is one standard deviation).
pub const SPLINE_ERROR_REL_SD: f64 = 0.5;
/// Variance factor of a sum over neighbouring Hann-windowed Welch bins (1 + 2·(4/9 + 1/36)).
pub const HANN_BIN_VARIANCE: f64 = 1.944;
/// Fewest bins in the band.
pub const MIN_BAND_BINS: usize = 32;
/// Bins either side averaged when comparing the spline error with the floor (one bin's
/// scatter is χ² with 2K degrees of freedom).
const SMOOTH_BINS: usize = 3;
/// Confidence of the interval.
pub const CONFIDENCE: f64 = 0.95;

/// A line of the residual's PSD and what it adds to N_op.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BandLine {
    /// The line (frequency, amplitude, bandwidth, peak over the floor).
    pub line: Line,
    /// Inside the band (counted in N_op).
    pub in_band: bool,
    /// Its share of N_op as a density: √(power / (2 f_N)).
    pub density: f64,
}

/// One axis' operating noise density in its band.
#[derive(Debug, Clone, PartialEq)]
pub struct AxisBand {
    /// The residual's Welch PSD (its floor and lines found as the IEEE 952 section finds
    /// them).
    pub psd: Psd,
    /// The estimated spline error's PSD at the same bins (zero without a reference).
    pub spline_psd: Vec<f64>,
    /// The lines, strongest first.
    pub lines: Vec<BandLine>,
    /// The band, Hz.
    pub band: (f64, f64),
    /// N_op, unit/√Hz.
    pub n: f64,
    /// Its 95 % interval.
    pub lo: f64,
    /// Upper end.
    pub hi: f64,
    /// Satterthwaite's degrees of freedom of N_op².
    pub dof: f64,
    /// The broadband floor as a density, √(F̄/2).
    pub floor_n: f64,
    /// The lines' share as a density (N_op² = floor² + lines²).
    pub lines_n: f64,
    /// The spline error taken out of the band, as a density.
    pub spline_n: f64,
}

/// What [`analyse`] needs of an axis.
pub struct BandInput<'a> {
    /// The residual (the motion and the bias taken out), one value per sample.
    pub y: &'a [f64],
    /// Sample rate, Hz.
    pub rate: f64,
    /// The spline's estimated error at the same samples (with a reference).
    pub spline_err: Option<&'a [f64]>,
    /// A band the user gave, Hz.
    pub band: Option<(f64, f64)>,
    /// The lowest lower edge: the bias band's or the motion's.
    pub lo_min: f64,
}

/// Why an axis has no operating density.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum BandError {
    /// Too few samples for a Welch PSD.
    #[error("{n} samples are too few for a PSD ({} at least)", psd::MIN_SEGMENT * psd::MIN_SEGMENTS)]
    TooShort {
        /// Samples.
        n: usize,
    },
    /// The spline's estimated error is above the residual in a band the user gave.
    #[error(
        "in the band {lo:.3} – {hi:.3} Hz the reference spline's estimated error is above the residual: raise the band's lower edge (or leave --band out)"
    )]
    SplineDominates {
        /// Lower edge, Hz.
        lo: f64,
        /// Upper edge, Hz.
        hi: f64,
    },
    /// The band holds too few bins.
    #[error(
        "the band {lo:.3} – {hi:.3} Hz holds {bins} PSD bins ({MIN_BAND_BINS} at least): the motion or the spline's error reach too close to the Nyquist frequency"
    )]
    Narrow {
        /// Lower edge, Hz.
        lo: f64,
        /// Upper edge, Hz.
        hi: f64,
        /// Bins.
        bins: usize,
    },
}

/// The running mean of `v` over ±[`SMOOTH_BINS`].
fn smooth(v: &[f64]) -> Vec<f64> {
    (0..v.len())
        .map(|i| {
            let a = i.saturating_sub(SMOOTH_BINS);
            let b = (i + SMOOTH_BINS).min(v.len() - 1);
            v[a..=b].iter().sum::<f64>() / (b - a + 1) as f64
        })
        .collect()
}

/// The lowest frequency above which the (smoothed) spline error stays below
/// [`SPLINE_SHARE`] of the floor.
fn spline_edge(p: &Psd, spline: &[f64]) -> f64 {
    let s = smooth(spline);
    let mut edge = 0.0;
    for k in (0..p.freq.len()).rev() {
        if s[k] > SPLINE_SHARE * p.floor[k] {
            edge = p.freq[k];
            break;
        }
    }
    edge
}

/// N_op, its interval and parts for one axis (module docs).
pub fn analyse(inp: &BandInput) -> Result<AxisBand, BandError> {
    let p = psd::welch(inp.y, inp.rate).ok_or(BandError::TooShort { n: inp.y.len() })?;
    let spline_psd = match inp.spline_err {
        Some(e) => psd::welch(e, inp.rate)
            .map(|s| s.density)
            .unwrap_or_else(|| vec![0.0; p.freq.len()]),
        None => vec![0.0; p.freq.len()],
    };
    let f_n = inp.rate / 2.0;
    let (lo, hi) = match inp.band {
        Some((lo, hi)) => (lo, hi.min(f_n)),
        None => (inp.lo_min.max(spline_edge(&p, &spline_psd)), f_n),
    };
    let bins: Vec<usize> = (0..p.freq.len())
        .filter(|&k| p.freq[k] >= lo && p.freq[k] <= hi)
        .collect();
    if bins.len() < MIN_BAND_BINS {
        return Err(BandError::Narrow {
            lo,
            hi,
            bins: bins.len(),
        });
    }
    let marks = p.line_marks();
    let df = p.freq[1] - p.freq[0];
    let k_seg = p.segments.max(1) as f64;
    let clean = |k: usize| p.density[k] - spline_psd[k];
    let free: Vec<usize> = bins.iter().copied().filter(|&k| !marks[k]).collect();
    let free = if free.len() < MIN_BAND_BINS / 2 {
        bins.clone()
    } else {
        free
    };
    let m = free.len() as f64;
    let floor = free.iter().map(|&k| clean(k)).sum::<f64>() / m;
    if floor <= 0.0 {
        return Err(BandError::SplineDominates { lo, hi });
    }
    // variance of the floor's mean: Ŝ² overstates S² by (1 + 1/K)
    let var_floor = HANN_BIN_VARIANCE * free.iter().map(|&k| p.density[k].powi(2)).sum::<f64>()
        / (1.0 + 1.0 / k_seg)
        / (k_seg * m * m);
    let line_bins: Vec<usize> = bins.iter().copied().filter(|&k| marks[k]).collect();
    let line_power: f64 = line_bins
        .iter()
        .map(|&k| (clean(k) - floor) * df)
        .sum::<f64>()
        .max(0.0);
    let var_lines: f64 = line_bins
        .iter()
        .map(|&k| {
            let l = (clean(k) - floor).max(0.0);
            (2.0 * l * floor + floor * floor) * HANN_BIN_VARIANCE / k_seg * df * df
        })
        .sum();
    let spline_power: f64 = bins.iter().map(|&k| spline_psd[k] * df).sum();
    let n2 = (floor / 2.0 + line_power / (2.0 * f_n)).max(f64::MIN_POSITIVE);
    let var = var_floor / 4.0
        + var_lines / (2.0 * f_n).powi(2)
        + (SPLINE_ERROR_REL_SD * spline_power / (2.0 * f_n)).powi(2);
    let dof = if var > 0.0 {
        2.0 * n2 * n2 / var
    } else {
        f64::INFINITY
    };
    let n = n2.sqrt();
    let (ci_lo, ci_hi) = if dof.is_finite() {
        chi2_interval(n, dof, CONFIDENCE).unwrap_or((f64::NAN, f64::NAN))
    } else {
        (n, n)
    };
    let lines = psd::find_lines(&p)
        .into_iter()
        .map(|l| {
            let in_band = l.frequency >= lo && l.frequency <= hi;
            BandLine {
                line: l,
                in_band,
                density: (l.amplitude * l.amplitude / 2.0 / (2.0 * f_n)).sqrt(),
            }
        })
        .collect();
    Ok(AxisBand {
        psd: p,
        spline_psd,
        lines,
        band: (lo, hi),
        n,
        lo: ci_lo,
        hi: ci_hi,
        dof,
        floor_n: (floor.max(0.0) / 2.0).sqrt(),
        lines_n: if line_power > 0.0 {
            (line_power / (2.0 * f_n)).sqrt()
        } else {
            0.0
        },
        spline_n: (spline_power / (2.0 * f_n)).sqrt(),
    })
}

/// The power of `y` in `band` as a density √(∫_band S df / (2 f_N)): the share of an error
/// series (a motion-correlated one, the timing's) the analysis reports beside N_op.
pub fn band_density(y: &[f64], rate: f64, band: (f64, f64)) -> Option<f64> {
    let p = psd::welch(y, rate)?;
    let df = p.freq[1] - p.freq[0];
    let power: f64 = p
        .freq
        .iter()
        .zip(&p.density)
        .filter(|(f, _)| **f >= band.0 && **f <= band.1)
        .map(|(_, s)| s * df)
        .sum();
    Some((power / rate).sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand::rngs::StdRng;
    use rand_distr::{Distribution, StandardNormal};
    use std::f64::consts::PI;

    /// The slow, obvious version of N_op for white noise plus one sinusoid: the per-sample
    /// variance of the series over f_s (what the estimator's discretisation takes).
    fn per_sample(y: &[f64], rate: f64) -> f64 {
        let m = y.iter().sum::<f64>() / y.len() as f64;
        (y.iter().map(|v| (v - m).powi(2)).sum::<f64>() / y.len() as f64 / rate).sqrt()
    }

    /// Level of agreement of the band estimate with the per-sample variance on 600 k
    /// samples (both estimate the same quantity; their scatter is ~0.3 %).
    const SAME_QUANTITY_REL: f64 = 0.01;

    #[test]
    fn white_noise_and_a_line_give_the_per_sample_density() {
        let mut rng = StdRng::seed_from_u64(42);
        let (rate, n, nd) = (400.0f64, 600_000, 2e-3f64);
        let (f0, amp) = (37.0, 0.02);
        let y: Vec<f64> = (0..n)
            .map(|i| {
                let w: f64 = StandardNormal.sample(&mut rng);
                nd * rate.sqrt() * w + amp * (2.0 * PI * f0 * i as f64 / rate).sin()
            })
            .collect();
        let b = analyse(&BandInput {
            y: &y,
            rate,
            spline_err: None,
            band: None,
            lo_min: 1.0,
        })
        .unwrap();
        let want = (nd * nd + amp * amp / (2.0 * rate)).sqrt();
        assert!(
            (b.n / want - 1.0).abs() < SAME_QUANTITY_REL,
            "{} vs {want}",
            b.n
        );
        let slow = per_sample(&y, rate);
        assert!(
            (b.n / slow - 1.0).abs() < SAME_QUANTITY_REL,
            "{} vs {slow}",
            b.n
        );
        assert!(b.lo < want && want < b.hi, "{b:?}");
        assert!(
            (b.floor_n / nd - 1.0).abs() < SAME_QUANTITY_REL,
            "{}",
            b.floor_n
        );
        let l = b.lines.iter().find(|l| l.in_band).expect("the line");
        assert!((l.line.frequency / f0 - 1.0).abs() < 0.002, "{l:?}");
        assert!(
            ((b.n * b.n - b.floor_n * b.floor_n - b.lines_n * b.lines_n) / (b.n * b.n)).abs()
                < 1e-12
        );
    }
}

#[cfg(test)]
mod coverage {
    use super::*;
    use rand::SeedableRng;
    use rand::rngs::StdRng;
    use rand_distr::{Distribution, StandardNormal};

    /// Series counted.
    const SERIES: usize = 1000;
    /// The binomial 99.9 % interval of a 95 % coverage over 1000 series.
    const COVERAGE_BOUNDS: (f64, f64) = (0.927, 0.970);

    /// The interval's coverage on white noise with a line (the band estimate alone).
    #[test]
    fn the_interval_covers_the_density_95_percent_of_the_time() {
        let (rate, n, nd, amp) = (200.0f64, 18_000, 2e-3f64, 6e-3);
        let want = (nd * nd + amp * amp / (2.0 * rate)).sqrt();
        let mut covered = 0;
        let mut z = Vec::new();
        for s in 0..SERIES {
            let mut rng = StdRng::seed_from_u64(7000 + s as u64);
            let ph = s as f64 * 0.77;
            let y: Vec<f64> = (0..n)
                .map(|i| {
                    let w: f64 = StandardNormal.sample(&mut rng);
                    nd * rate.sqrt() * w
                        + amp * (2.0 * std::f64::consts::PI * 23.0 * i as f64 / rate + ph).sin()
                })
                .collect();
            let b = analyse(&BandInput {
                y: &y,
                rate,
                spline_err: None,
                band: None,
                lo_min: 1.0,
            })
            .unwrap();
            if b.lo <= want && want <= b.hi {
                covered += 1;
            }
            z.push((b.n - want) / ((b.hi - b.lo) / (2.0 * 1.96)));
        }
        let m = z.iter().sum::<f64>() / z.len() as f64;
        let sd = (z.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (z.len() - 1) as f64).sqrt();
        let share = covered as f64 / SERIES as f64;
        eprintln!(
            "band interval: {covered}/{SERIES} covered, errors' mean {m:.3} and sd {sd:.3} in stated standard errors"
        );
        assert!(
            share >= COVERAGE_BOUNDS.0 && share <= COVERAGE_BOUNDS.1,
            "{covered}/{SERIES}"
        );
    }
}
