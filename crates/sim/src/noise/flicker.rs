//! Flicker (1/f) bias noise as a sum of first-order Gauss–Markov processes with log-spaced
//! time constants.
//!
//! Method: a superposition of relaxation (Lorentzian) spectra whose time constants are
//! distributed uniformly in log T has a 1/f spectrum between the extreme corners — A. van der
//! Ziel, "On the noise spectra of semi-conductor noise and of flicker effect", Physica 16
//! (1950) 359–372; M. S. Keshner, "1/f noise", Proc. IEEE 70(3) (1982) 212–218, §III. With
//! time constants T_i = T_0·r^i and equal variances σ² each, the two-sided PSD
//! Σ 2σ²T_i/(1 + (2πfT_i)²) ≈ σ²/(2·f·ln r); IEEE 952's bias-instability PSD is
//! S(f) = B²/(2π·f), hence σ² = B²·ln r/π.
//!
//! Why this and not Kasdin's fractional-integration filter (N. J. Kasdin, "Discrete
//! simulation of colored noise and stochastic processes and 1/f^α power law noise
//! generation", Proc. IEEE 83(5) (1995) 802–827): every component is an exact discrete AR(1)
//! process whose Allan variance has a closed form, so the truth curve is exact for what is
//! generated, not an approximation of it; the cost is one normal draw per component per
//! output sample with O(1) state, streamed (Kasdin's filter needs either an FIR as long as
//! the record or the whole record in memory for an FFT); and the corners are explicit.
//!
//! Spacing: [`PER_DECADE`] = 1.5 components per decade leave an Allan-deviation ripple below
//! 0.1 % (1 per decade: ±1 %). The floor is within 1 % of 0.664·B from ≈ 40·T_min to
//! ≈ T_max/13 (the sum rolls off slowly, like T_min/τ, towards short τ; measured on the exact
//! sum), so T_min = τ_lo/[`LO_MARGIN`] and T_max = τ_hi·[`HI_MARGIN`]. A floor of d decades
//! costs 1.5·(d + 2.8) + 1 components (11 for three decades).

use super::model::BiasInstability;

/// Gauss–Markov components per decade of time constant.
pub const PER_DECADE: f64 = 1.5;
/// T_min = τ_lo / LO_MARGIN.
pub const LO_MARGIN: f64 = 40.0;
/// T_max = τ_hi · HI_MARGIN.
pub const HI_MARGIN: f64 = 16.0;
/// √(2 ln 2 / π): the flicker Allan-deviation floor per unit B.
#[cfg(test)]
pub const FLOOR_PER_B: f64 = 0.664_282_470_267_960_1;

/// One Gauss–Markov component: standard deviation and time constant.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Component {
    /// σ, U.
    pub sigma: f64,
    /// T, s.
    pub tau: f64,
}

/// The components that make the flicker term `bi`.
pub fn components(bi: &BiasInstability) -> Vec<Component> {
    if bi.b == 0.0 {
        return Vec::new();
    }
    let t_min = bi.tau_lo / LO_MARGIN;
    let t_max = bi.tau_hi * HI_MARGIN;
    let n = ((t_max / t_min).log10() * PER_DECADE).ceil() as usize;
    let r = 10f64.powf(1.0 / PER_DECADE);
    let sigma = bi.b * (r.ln() / std::f64::consts::PI).sqrt();
    (0..=n)
        .map(|i| Component {
            sigma,
            tau: t_min * r.powi(i as i32),
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn floor_constant_is_sqrt_2ln2_over_pi() {
        let c = (2.0 * std::f64::consts::LN_2 / std::f64::consts::PI).sqrt();
        assert!((c - FLOOR_PER_B).abs() < 1e-16);
    }

    #[test]
    fn components_span_the_margins() {
        let c = components(&BiasInstability {
            b: 1e-5,
            tau_lo: 1.0,
            tau_hi: 1000.0,
        });
        assert_eq!(c.first().unwrap().tau, 1.0 / LO_MARGIN);
        assert!(c.last().unwrap().tau >= 1000.0 * HI_MARGIN);
        // 3 decades of floor + margins (log10(640) = 2.8): 1.5·5.8 → 9 steps, 10 components.
        assert_eq!(c.len(), 10);
        let s2 = 1e-10 * (10f64.powf(1.0 / 1.5).ln() / std::f64::consts::PI);
        assert!((c[0].sigma.powi(2) - s2).abs() < 1e-24);
    }
}
