//! The sensor's digital low-pass filter at the internal rate, its impulse response and the
//! per-sample noise it leaves at the output.
//!
//! 2nd-order Butterworth by the bilinear transform with pre-warping (the usual MEMS DLPF
//! design): with K = tan(π f_c / f_s) and n = 1/(1 + √2·K + K²),
//! ```text
//! b0 = K²n, b1 = 2b0, b2 = b0,   a1 = 2(K² − 1)n, a2 = (1 − √2·K + K²)n
//! y[k] = b0 x[k] + b1 x[k−1] + b2 x[k−2] − a1 y[k−1] − a2 y[k−2]      (|H(f_c)|² = ½, H(0) = 1)
//! ```
//!
//! # Per-sample σ of filtered, decimated white noise
//! White noise of density N (U/√Hz, two-sided) sampled at the internal rate f_i has per-sample
//! variance N²·f_i. The filter output is y = Σ_j h_j·x_{k−j}, so its variance is
//! N²·f_i·Σ_j h_j²; decimation by sub-sampling keeps every D-th value and does not change it:
//! ```text
//! σ_d² = N²·f_i·Σ_j h_j² = N²·∫_{−f_i/2}^{f_i/2} |H(f)|² df = 2·N²·B_e
//! ```
//! (Parseval), B_e being the filter's one-sided equivalent noise bandwidth. Only without a
//! filter and without decimation is σ_d = N·√f (the naive relation); a 2nd-order Butterworth
//! has B_e ≈ 1.1107·f_c when f_c ≪ f_i (π/(2√2)·f_c), so σ_d ≈ N·√(2.221·f_c), below
//! N·√f_out when f_c < f_out/2.221. The averaging filter gives exactly N·√f_out.

use super::model::{Filter, ResolvedChain};

/// Relative energy left in the truncated tail of an IIR impulse response.
pub const IMPULSE_TAIL_REL: f64 = 1e-22;

/// Direct-form-II-transposed biquad.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Biquad {
    /// Feed-forward coefficients.
    pub b: [f64; 3],
    /// Feedback coefficients a1, a2 (a0 = 1).
    pub a: [f64; 2],
    s1: f64,
    s2: f64,
}

impl Biquad {
    /// 2nd-order Butterworth low-pass with −3 dB at `cutoff` Hz at sample rate `fs` Hz.
    pub fn butterworth(cutoff: f64, fs: f64) -> Self {
        let k = (std::f64::consts::PI * cutoff / fs).tan();
        let sq2 = std::f64::consts::SQRT_2;
        let n = 1.0 / (1.0 + sq2 * k + k * k);
        let b0 = k * k * n;
        Biquad {
            b: [b0, 2.0 * b0, b0],
            a: [2.0 * (k * k - 1.0) * n, (1.0 - sq2 * k + k * k) * n],
            s1: 0.0,
            s2: 0.0,
        }
    }

    /// One sample through the filter.
    #[inline(always)]
    pub fn step(&mut self, x: f64) -> f64 {
        let y = self.b[0] * x + self.s1;
        self.s1 = self.b[1] * x - self.a[0] * y + self.s2;
        self.s2 = self.b[2] * x - self.a[1] * y;
        y
    }

    /// |H(e^{2πiν})|² at normalised frequency ν (cycles per sample).
    #[cfg(test)]
    pub fn gain2(&self, nu: f64) -> f64 {
        let w = 2.0 * std::f64::consts::PI * nu;
        let (c1, s1, c2, s2) = (w.cos(), w.sin(), (2.0 * w).cos(), (2.0 * w).sin());
        let nr = self.b[0] + self.b[1] * c1 + self.b[2] * c2;
        let ni = -(self.b[1] * s1 + self.b[2] * s2);
        let dr = 1.0 + self.a[0] * c1 + self.a[1] * c2;
        let di = -(self.a[0] * s1 + self.a[1] * s2);
        (nr * nr + ni * ni) / (dr * dr + di * di)
    }
}

/// Impulse response of the chain's filter at the internal rate: exact for FIR filters,
/// truncated where the remaining energy is below [`IMPULSE_TAIL_REL`] for the IIR.
pub fn impulse_response(chain: &ResolvedChain) -> Vec<f64> {
    match chain.filter {
        Filter::None => vec![1.0],
        Filter::Average => vec![1.0 / chain.decimation as f64; chain.decimation],
        Filter::Butterworth2 { cutoff_hz } => {
            let mut f = Biquad::butterworth(cutoff_hz, chain.internal_rate);
            let mut h = vec![f.step(1.0)];
            // The poles are inside the unit circle: the tail decays geometrically; stop when
            // the last 64 samples carry less than IMPULSE_TAIL_REL of the energy so far.
            let mut energy = h[0] * h[0];
            let mut window = [0.0f64; 64];
            loop {
                let v = f.step(0.0);
                let i = h.len();
                energy += v * v;
                window[i % 64] = v * v;
                h.push(v);
                if i > 64 && window.iter().sum::<f64>() < IMPULSE_TAIL_REL * energy {
                    break;
                }
                if h.len() > 50_000_000 {
                    break; // not reachable for a cutoff above 1e-7 of the rate
                }
            }
            h
        }
    }
}

/// Σ_j h_j·h_{j+lag}.
pub fn autocorrelation(h: &[f64], lag: usize) -> f64 {
    if lag >= h.len() {
        return 0.0;
    }
    h.iter().zip(&h[lag..]).map(|(a, b)| a * b).sum()
}

/// One-sided equivalent noise bandwidth of the chain's filter, Hz: Σh²·f_i/2 (Parseval).
pub fn enbw(chain: &ResolvedChain) -> f64 {
    let h = impulse_response(chain);
    autocorrelation(&h, 0) * chain.internal_rate / 2.0
}

/// Per-sample standard deviation at the output of white noise of density `n` through the
/// chain: N·√(f_i·Σh²) (module doc).
#[cfg(test)]
pub fn per_sample_sigma(n: f64, chain: &ResolvedChain) -> f64 {
    let h = impulse_response(chain);
    n * (chain.internal_rate * autocorrelation(&h, 0)).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The coefficients are rounded in f64: the DC gain and the −3 dB point hold to rounding.
    const COEFF_TOL: f64 = 1e-12;
    /// Gauss–Legendre on 4096 panels of a smooth periodic integrand: far below this.
    const PARSEVAL_REL_TOL: f64 = 1e-10;

    fn chain(fc: f64, fi: f64, d: usize) -> ResolvedChain {
        ResolvedChain {
            internal_rate: fi,
            decimation: d,
            filter: Filter::Butterworth2 { cutoff_hz: fc },
        }
    }

    #[test]
    fn butterworth_dc_gain_and_cutoff() {
        for (fc, fs) in [
            (50.0, 1000.0),
            (23.0, 2000.0),
            (400.0, 1000.0),
            (0.5, 100.0),
        ] {
            let f = Biquad::butterworth(fc, fs);
            assert!((f.gain2(0.0) - 1.0).abs() < COEFF_TOL, "DC gain {fc} {fs}");
            assert!(
                (f.gain2(fc / fs) - 0.5).abs() < COEFF_TOL,
                "|H(fc)|² {fc} {fs}: {}",
                f.gain2(fc / fs)
            );
            // Monotone roll-off, −40 dB/decade well above the corner.
            assert!(f.gain2(0.45) < f.gain2(fc / fs));
        }
    }

    #[test]
    fn impulse_energy_is_the_integral_of_the_squared_gain() {
        // Parseval: Σh² = ∫_{-1/2}^{1/2} |H(ν)|² dν, computed by a slow quadrature.
        for (fc, fs) in [(50.0, 1000.0), (23.0, 2000.0), (5.0, 1000.0)] {
            let c = chain(fc, fs, 5);
            let h = impulse_response(&c);
            let sum_h2 = autocorrelation(&h, 0);
            let f = Biquad::butterworth(fc, fs);
            let integral =
                crate::noise::quad::gauss_legendre_panels(|nu| 2.0 * f.gain2(nu), 0.0, 0.5, 4096);
            assert!(
                ((sum_h2 - integral) / integral).abs() < PARSEVAL_REL_TOL,
                "{fc}/{fs}: Σh² {sum_h2} vs ∫|H|² {integral}"
            );
        }
    }

    #[test]
    fn enbw_of_a_low_corner_butterworth_is_pi_over_2_sqrt2_times_fc() {
        // Analog 2nd-order Butterworth: B_e = π/(2√2)·f_c; the bilinear warping at f_c/f_s =
        // 0.002 changes it by < 1e-4.
        let c = chain(2.0, 1000.0, 1);
        let be = enbw(&c);
        let expected = std::f64::consts::PI / (2.0 * std::f64::consts::SQRT_2) * 2.0;
        assert!(
            ((be - expected) / expected).abs() < 1e-4,
            "{be} vs {expected}"
        );
    }

    #[test]
    fn average_filter_gives_the_naive_output_sigma() {
        let c = ResolvedChain {
            internal_rate: 2000.0,
            decimation: 10,
            filter: Filter::Average,
        };
        let s = per_sample_sigma(0.01, &c);
        assert!((s - 0.01 * 200f64.sqrt()).abs() < 1e-15, "{s}");
        let none = ResolvedChain {
            filter: Filter::None,
            ..c
        };
        // Plain sub-sampling keeps the internal-rate σ: N·√f_i.
        assert!((per_sample_sigma(0.01, &none) - 0.01 * 2000f64.sqrt()).abs() < 1e-15);
    }
}
