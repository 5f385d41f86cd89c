//! The Allan variance as a spectral integral, continuous and discrete, and the closed forms of
//! the pure IEEE 952 terms it is checked against.
//!
//! Continuous time (IEEE Std 952-1997 Annex C; S two-sided, as in S = N² for white noise):
//! ```text
//! AVAR(τ) = 4 ∫_0^∞ S(f) · sin⁴(πfτ)/(πfτ)² df
//! ```
//! Discrete sequence with sample period τ0 and two-sided PSD S_d(ν) (ν in cycles/sample,
//! ∫_{−½}^{½} S_d = variance), cluster size m — the kernel of the overlapping estimator's
//! second difference of m-sample means, |W(ν)|²/(2m²) with |W|² = 4 sin⁴(πmν)/sin²(πν):
//! ```text
//! AVAR(m) = (4/m²) ∫_0^{½} S_d(ν) · sin⁴(πmν)/sin²(πν) dν
//! ```
//! As τ0 → 0 the discrete kernel tends to the continuous one. A PSD aliased by decimation is
//! S_d(ν) = (1/D)·Σ_{l<D} S_i((ν + l)/D) in terms of the internal-rate PSD S_i.
//!
//! The rate ramp has no convergent spectral form: IEEE 952's S(f) = R²/(2πf)³ makes the
//! integrand ∝ 1/f at f → 0 (the integral diverges logarithmically), so its AVAR R²τ²/2 is a
//! time-domain result only, and the truth uses it as such.

use super::quad::gauss_legendre;
use std::f64::consts::PI;

/// Panels (of the integrand's period) integrated before the tail is extrapolated.
pub const CONTINUOUS_PANELS: usize = 2000;

/// 4∫_0^∞ S(f)·sin⁴(πfτ)/(πfτ)² df by panels of `period` in x = πfτ (π for a smooth S; the
/// joint period when S itself oscillates), with the 1/X tail removed by Richardson
/// extrapolation between X and 2X.
pub fn avar_continuous<F: Fn(f64) -> f64>(s: F, tau: f64, period: f64) -> f64 {
    let g = |x: f64| {
        let sx = x.sin();
        s(x / (PI * tau)) * sx * sx * sx * sx / (x * x)
    };
    let mut acc = 0.0;
    let mut i_half = 0.0;
    for k in 0..2 * CONTINUOUS_PANELS {
        let a = k as f64 * period;
        // Sub-panels of length ≤ π keep 16 nodes per oscillation of sin⁴.
        let sub = (period / PI).ceil().max(1.0) as usize * 2;
        let h = period / sub as f64;
        for j in 0..sub {
            let (lo, hi) = (a + j as f64 * h, a + (j + 1) as f64 * h);
            if k == 0 && j == 0 {
                // Graded towards 0: corners of S far below x = 1 (e.g. a Gauss–Markov process
                // with T ≫ τ) are resolved.
                acc += (0..60)
                    .map(|e| gauss_legendre(&g, hi * 0.5f64.powi(e + 1), hi * 0.5f64.powi(e)))
                    .sum::<f64>();
            } else {
                acc += gauss_legendre(&g, lo, hi);
            }
        }
        if k + 1 == CONTINUOUS_PANELS {
            i_half = acc;
        }
    }
    let extrapolated = 2.0 * acc - i_half;
    4.0 / (PI * tau) * extrapolated
}

/// 4∫_0^{f_max} S(f)·sin⁴(πfτ)/(πfτ)² df (a band-limited S; no tail).
pub fn avar_continuous_band<F: Fn(f64) -> f64>(s: F, tau: f64, f_max: f64) -> f64 {
    let g = |x: f64| {
        let sx = x.sin();
        s(x / (PI * tau)) * sx * sx * sx * sx / (x * x)
    };
    let x_max = PI * f_max * tau;
    let panels = ((x_max / PI).ceil() as usize * 2).max(8);
    let h = x_max / panels as f64;
    let i: f64 = (0..panels)
        .map(|k| gauss_legendre(&g, k as f64 * h, (k + 1) as f64 * h))
        .sum();
    4.0 / (PI * tau) * i
}

/// (4/m²)∫_0^{½} S_d(ν)·sin⁴(πmν)/sin²(πν) dν: the discrete Allan variance (module doc).
pub fn avar_discrete<F: Fn(f64) -> f64>(s_d: F, m: usize) -> f64 {
    let mf = m as f64;
    let g = |nu: f64| {
        let a = (PI * mf * nu).sin();
        let b = (PI * nu).sin();
        s_d(nu) * a * a * a * a / (b * b)
    };
    let panels = (8 * m).max(256);
    let h = 0.5 / panels as f64;
    let i: f64 = (0..panels)
        .map(|k| gauss_legendre(&g, k as f64 * h, (k + 1) as f64 * h))
        .sum();
    4.0 / (mf * mf) * i
}

/// White noise N: N²/τ.
pub fn closed_white(n: f64, tau: f64) -> f64 {
    n * n / tau
}

/// Random walk K: K²τ/3.
pub fn closed_random_walk(k: f64, tau: f64) -> f64 {
    k * k * tau / 3.0
}

/// Quantization Q: 3Q²/τ² (exact at τ = m·τ0 for the IEEE 952 PSD (4Q²/τ0)·sin²(πfτ0)).
pub fn closed_quantization(q: f64, tau: f64) -> f64 {
    3.0 * q * q / (tau * tau)
}

/// Ideal flicker (S = B²/(2πf) at every f): (2 ln 2/π)·B² at every τ.
pub fn closed_flicker(b: f64) -> f64 {
    2.0 * std::f64::consts::LN_2 / PI * b * b
}

/// Flicker cut off above f0 (IEEE 952 Annex C):
/// (2B²/π)·[ln 2 − sin³x/(2x²)·(sin x + 4x cos x) + Ci(2x) − Ci(4x)], x = πf0τ.
pub fn closed_flicker_cutoff(b: f64, f0: f64, tau: f64) -> f64 {
    let x = PI * f0 * tau;
    let (s, c) = x.sin_cos();
    2.0 * b * b / PI
        * (std::f64::consts::LN_2 - s * s * s / (2.0 * x * x) * (s + 4.0 * x * c) + ci(2.0 * x)
            - ci(4.0 * x))
}

/// Continuous first-order Gauss–Markov (σ, T), two-sided PSD 2σ²T/(1 + (2πfT)²):
/// (2σ²T/τ)·[1 − (T/(2τ))·(3 − 4e^(−τ/T) + e^(−2τ/T))].
pub fn closed_gauss_markov(sigma: f64, t: f64, tau: f64) -> f64 {
    let x = tau / t;
    let bracket = if x < 1e-2 {
        // 1 − (3 − 4e^{−x} + e^{−2x})/(2x) = x/3 − x²/8 + x³/30 − … (series: no cancellation)
        x / 3.0 - x * x / 8.0 + x * x * x / 30.0 - x.powi(4) / 144.0
    } else {
        1.0 - (3.0 - 4.0 * (-x).exp() + (-2.0 * x).exp()) / (2.0 * x)
    };
    2.0 * sigma * sigma * t / tau * bracket
}

/// Cosine integral Ci(x) = γ + ln x + ∫_0^x (cos t − 1)/t dt, x > 0: power series for x ≤ 4,
/// else the continued fraction of E₁(ix) (modified Lentz).
pub fn ci(x: f64) -> f64 {
    const EULER: f64 = 0.577_215_664_901_532_9;
    if x <= 4.0 {
        let mut sum = 0.0;
        let mut term = 1.0; // (−1)^k x^{2k}/(2k)!
        for k in 1..60 {
            let kf = k as f64;
            term *= -x * x / ((2.0 * kf - 1.0) * (2.0 * kf));
            let add = term / (2.0 * kf);
            sum += add;
            if add.abs() < 1e-18 * sum.abs().max(1e-300) {
                break;
            }
        }
        return EULER + x.ln() + sum;
    }
    // E₁(ix) = e^{−ix}·1/(1 + ix − 1²/(3 + ix − 2²/(5 + ix − …))); Ci(x) = −Re E₁(ix).
    let mut b = (1.0, x);
    let inv = |z: (f64, f64)| {
        let d = z.0 * z.0 + z.1 * z.1;
        (z.0 / d, -z.1 / d)
    };
    let mul = |a: (f64, f64), b: (f64, f64)| (a.0 * b.0 - a.1 * b.1, a.0 * b.1 + a.1 * b.0);
    let mut c = (1e300, 0.0);
    let mut d = inv(b);
    let mut h = d;
    for i in 1..10_000 {
        let a = -((i * i) as f64);
        b = (b.0 + 2.0, b.1);
        d = inv((a * d.0 + b.0, a * d.1 + b.1));
        let ic = inv(c);
        c = (b.0 + a * ic.0, b.1 + a * ic.1);
        let del = mul(c, d);
        h = mul(h, del);
        if (del.0 - 1.0).abs() + del.1.abs() < 1e-16 {
            break;
        }
    }
    let e = mul(h, (x.cos(), -x.sin()));
    -e.0
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The issue's bound for the numerical integral against the pure terms' closed forms.
    const INTEGRAL_REL_TOL: f64 = 1e-6;
    /// Ci against tabulated values (Abramowitz & Stegun Table 5.1, 15 digits).
    const CI_ABS_TOL: f64 = 1e-13;

    fn rel(a: f64, b: f64) -> f64 {
        ((a - b) / b).abs()
    }

    #[test]
    fn cosine_integral_matches_tables() {
        #[allow(clippy::excessive_precision)]
        for (x, v) in [
            (0.5, -0.177_784_078_806_612_3),
            (1.0, 0.337_403_922_900_968_1),
            (2.0, 0.422_980_828_774_865_0),
            (4.0, -0.140_981_697_886_930_4),
            (5.0, -0.190_029_749_656_643_9),
            (10.0, -0.045_456_433_004_455_4),
            (20.0, 0.044_419_820_845_353_3),
        ] {
            assert!((ci(x) - v).abs() < CI_ABS_TOL, "Ci({x}) = {} vs {v}", ci(x));
        }
    }

    #[test]
    fn integral_matches_white_random_walk_flicker_and_gauss_markov() {
        for tau in [0.01, 1.0, 37.0, 1000.0] {
            let n = 0.013;
            let w = avar_continuous(|_| n * n, tau, PI);
            assert!(
                rel(w, closed_white(n, tau)) < INTEGRAL_REL_TOL,
                "white τ {tau}: {w}"
            );
            let k = 4e-5;
            let r = avar_continuous(|f| k * k / (2.0 * PI * f).powi(2), tau, PI);
            assert!(
                rel(r, closed_random_walk(k, tau)) < INTEGRAL_REL_TOL,
                "rw τ {tau}: {r}"
            );
            let b = 2e-4;
            let fl = avar_continuous(|f| b * b / (2.0 * PI * f), tau, PI);
            assert!(
                rel(fl, closed_flicker(b)) < INTEGRAL_REL_TOL,
                "flicker τ {tau}: {fl}"
            );
            for t in [0.1 * tau, tau, 10.0 * tau] {
                let s = 3e-3;
                let gm = avar_continuous(
                    |f| 2.0 * s * s * t / (1.0 + (2.0 * PI * f * t).powi(2)),
                    tau,
                    PI,
                );
                let c = closed_gauss_markov(s, t, tau);
                assert!(
                    rel(gm, c) < INTEGRAL_REL_TOL,
                    "GM T {t} τ {tau}: {gm} vs {c}"
                );
            }
        }
    }

    #[test]
    fn integral_matches_flicker_with_a_cutoff() {
        let b = 1e-3;
        for (f0, tau) in [(10.0, 0.01), (10.0, 0.1), (1.0, 3.0), (0.05, 100.0)] {
            let v = avar_continuous_band(|f| b * b / (2.0 * PI * f), tau, f0);
            let c = closed_flicker_cutoff(b, f0, tau);
            assert!(rel(v, c) < INTEGRAL_REL_TOL, "f0 {f0} τ {tau}: {v} vs {c}");
        }
        // Far above the cutoff's time scale the floor is (2 ln 2/π)·B².
        assert!(rel(closed_flicker_cutoff(b, 100.0, 100.0), closed_flicker(b)) < 1e-4);
    }

    #[test]
    fn integral_matches_quantization_at_whole_samples() {
        // IEEE 952: S(f) = (4Q²/τ0)·sin²(πfτ0); AVAR = 3Q²/τ² at τ = mτ0 (the sum of the
        // aliased sinc² is 1). The integrand's period in x = πfτ is m·π.
        let (q, tau0) = (2e-6, 0.005);
        for m in [1usize, 2, 3, 8] {
            let tau = m as f64 * tau0;
            let v = avar_continuous(
                |f| 4.0 * q * q / tau0 * (PI * f * tau0).sin().powi(2),
                tau,
                m as f64 * PI,
            );
            let c = closed_quantization(q, tau);
            assert!(rel(v, c) < INTEGRAL_REL_TOL, "m {m}: {v} vs {c}");
        }
    }

    #[test]
    fn discrete_integral_of_white_and_random_walk_sequences() {
        // White sequence of variance v: S_d = v → v/m. Random-walk sequence with step s:
        // S_d = s²/(4 sin²πν) → s²(2m² + 1)/(6m).
        let (v, s) = (0.3, 2e-3);
        for m in [1usize, 2, 5, 64, 1000] {
            let w = avar_discrete(|_| v, m);
            assert!(rel(w, v / m as f64) < 1e-10, "white m {m}: {w}");
            let r = avar_discrete(|nu| s * s / (4.0 * (PI * nu).sin().powi(2)), m);
            let mf = m as f64;
            let c = s * s * (2.0 * mf * mf + 1.0) / (6.0 * mf);
            assert!(rel(r, c) < 1e-10, "rw m {m}: {r} vs {c}");
        }
    }
}
