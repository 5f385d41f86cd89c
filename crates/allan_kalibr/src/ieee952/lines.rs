//! Spectral lines in the Allan variance: IEEE Std 952's sinusoidal noise and a lightly damped
//! 2nd-order resonance driven by white noise (a vibration line with a bandwidth) — the
//! expectation of the fully overlapping estimator on the sampled sequence, at cluster size m.
//!
//! A sinusoid A·sin(2πf₀t + φ) sampled every τ₀ (ν₀ = f₀τ₀ cycles per sample):
//!
//! ```text
//! AVAR(m) = A²·sin⁴(πmν₀) / (m²·sin²(πν₀))     → A²·sin⁴(πf₀τ)/(πf₀τ)² as τ₀ → 0
//! ```
//!
//! (the continuous form is IEEE 952's; at short τ the discrete one differs by
//! (πν₀)²/sin²(πν₀), a factor 2 at ν₀ = 0.45, so the estimator uses the discrete one). A
//! resonance of centre f₀ and −3 dB bandwidth B (damping ζ = B/(2f₀)), sampled: its
//! autocovariance is R(k) = σ²·e^(−a|k|)·(cos bk + (a/b)·sin b|k|), a = ζω₀τ₀,
//! b = ω₀√(1 − ζ²)·τ₀, i.e. R(k) = Re(c·z^|k|) with z = e^(−a + ib), c = σ²(1 − i·a/b), and
//!
//! ```text
//! AVAR(m) = (1/2m²)·Σ_{|k|≤2m} g(k)·R(k) = Re(c·F(z))/m²,
//! F(z) = m + Σ_{k=1}^{2m} g(k)·z^k = m(1 + z)/(1 − z) − z(1 − z^m)(3 − z^m)/(1 − z)²
//! ```
//!
//! with g the autocorrelation of the estimator's ±1 kernel (g(k) = 2m − 3|k| for |k| ≤ m,
//! −(2m − |k|) to 2m) — the Gauss–Markov closed form with a complex pole. Where |m(1 − z)|
//! is small the closed form cancels; there the sum is taken term by term. As the bandwidth
//! goes to 0 it is the sinusoid of amplitude σ√2 (the tests check both routes, the direct
//! sum and the spectral integral).
//!
//! `sim` computes its truth with these; the fit uses them as the shape of a line term.

use std::f64::consts::PI;

/// Allan variance at cluster size `m` (any m ≥ 1; real m for drawing) of a sampled sinusoid
/// of unit amplitude at `nu0` cycles per sample (0 < ν₀ < ½).
pub fn sinusoid_avar(m: f64, nu0: f64) -> f64 {
    let s = (PI * m * nu0).sin();
    let d = (PI * nu0).sin();
    s * s * s * s / (m * m * d * d)
}

/// The continuous-time damping constants of a resonance at `f0` Hz with −3 dB bandwidth
/// `bandwidth` Hz, per sample of `tau0` s: (a, b) of the module docs (a = 0 for a sinusoid).
pub fn resonance_poles(f0: f64, bandwidth: f64, tau0: f64) -> (f64, f64) {
    let w0 = 2.0 * PI * f0;
    let zeta = bandwidth / (2.0 * f0);
    (
        zeta * w0 * tau0,
        w0 * (1.0 - zeta * zeta).max(0.0).sqrt() * tau0,
    )
}

/// Allan variance at cluster size `m` of a sampled resonance of unit variance whose
/// autocovariance per sample is e^(−a|k|)·(cos bk + (a/b) sin b|k|) (module docs;
/// [`resonance_poles`] gives a, b). With a = 0 it is the sinusoid of amplitude √2.
pub fn resonance_avar(m: usize, a: f64, b: f64) -> f64 {
    if m == 0 {
        return f64::NAN;
    }
    let mf = m as f64;
    let c = Cx(1.0, -a / b);
    let z = Cx::exp(-a, b);
    let one_minus_z = Cx(1.0, 0.0).sub(z);
    let f = if mf * one_minus_z.abs() < DIRECT_BELOW {
        // m + Σ g(k) z^k, term by term
        let mut acc = Cx(mf, 0.0);
        let mut zk = Cx(1.0, 0.0);
        for k in 1..=2 * m {
            zk = zk.mul(z);
            let g = if k <= m {
                2.0 * mf - 3.0 * k as f64
            } else {
                -(2.0 * mf - k as f64)
            };
            acc = acc.add(zk.scale(g));
        }
        acc
    } else {
        let zm = Cx::exp(-a * mf, b * mf);
        let one = Cx(1.0, 0.0);
        let t1 = one.add(z).scale(mf).div(one_minus_z);
        let t2 = z
            .mul(one.sub(zm))
            .mul(Cx(3.0, 0.0).sub(zm))
            .div(one_minus_z.mul(one_minus_z));
        t1.sub(t2)
    };
    c.mul(f).0 / (mf * mf)
}

/// |m(1 − z)| below which [`resonance_avar`] sums term by term (the closed form's two terms
/// cancel to about (m|1 − z|)² of their size).
const DIRECT_BELOW: f64 = 4.0;

/// A complex number (re, im): the few operations the closed form needs.
#[derive(Clone, Copy, Debug)]
struct Cx(f64, f64);

impl Cx {
    fn exp(re: f64, im: f64) -> Cx {
        let r = re.exp();
        Cx(r * im.cos(), r * im.sin())
    }
    fn add(self, o: Cx) -> Cx {
        Cx(self.0 + o.0, self.1 + o.1)
    }
    fn sub(self, o: Cx) -> Cx {
        Cx(self.0 - o.0, self.1 - o.1)
    }
    fn mul(self, o: Cx) -> Cx {
        Cx(self.0 * o.0 - self.1 * o.1, self.0 * o.1 + self.1 * o.0)
    }
    fn div(self, o: Cx) -> Cx {
        let d = o.0 * o.0 + o.1 * o.1;
        Cx(
            (self.0 * o.0 + self.1 * o.1) / d,
            (self.1 * o.0 - self.0 * o.1) / d,
        )
    }
    fn scale(self, s: f64) -> Cx {
        Cx(self.0 * s, self.1 * s)
    }
    fn abs(self) -> f64 {
        self.0.hypot(self.1)
    }
}

/// One-sided PSD (U²/Hz) of a resonance of variance σ² = 1 at `f` Hz: the continuous 2nd-order
/// system driven by white noise, |H(f)|² normalised so that its integral over f > 0 is 1.
pub(crate) fn resonance_psd(f: f64, f0: f64, bandwidth: f64) -> f64 {
    let zeta = bandwidth / (2.0 * f0);
    let (w, w0) = (2.0 * PI * f, 2.0 * PI * f0);
    // two-sided S(ω) = q²/((ω0² − ω²)² + (2ζω0ω)²) with σ² = q²/(4ζω0³); one-sided in Hz:
    // 2·2π·S(ω)/(2π)… = 4ζω0³·2/((ω0² − ω²)² + (2ζω0ω)²) per unit σ², times dω/df / 2π
    let den = (w0 * w0 - w * w).powi(2) + (2.0 * zeta * w0 * w).powi(2);
    2.0 * 4.0 * zeta * w0.powi(3) / den
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two exact routes to one number (closed form vs term-by-term sum or quadrature).
    const ROUTES_REL_TOL: f64 = 1e-9;

    fn rel(a: f64, b: f64) -> f64 {
        ((a - b) / b).abs()
    }

    /// Composite Simpson rule with `n` (even) panels.
    fn simpson(f: impl Fn(f64) -> f64, a: f64, b: f64, n: usize) -> f64 {
        let h = (b - a) / n as f64;
        let mut s = f(a) + f(b);
        for i in 1..n {
            s += f(a + i as f64 * h) * if i % 2 == 1 { 4.0 } else { 2.0 };
        }
        s * h / 3.0
    }

    /// Slow, obviously correct: E[(mean of block 2 − mean of block 1)²]/2 from R(k), the
    /// double sum over the 2m samples of the two blocks.
    fn slow(m: usize, r: &dyn Fn(i64) -> f64) -> f64 {
        let w = |j: usize| if j < m { -1.0 } else { 1.0 } / m as f64;
        let mut s = 0.0;
        for j in 0..2 * m {
            for l in 0..2 * m {
                s += w(j) * w(l) * r(j as i64 - l as i64);
            }
        }
        s / 2.0
    }

    #[test]
    fn sinusoid_matches_the_double_sum_and_the_continuous_limit() {
        for nu0 in [0.002, 0.01, 0.13, 0.31, 0.45] {
            let r = |k: i64| 0.5 * (2.0 * PI * nu0 * k as f64).cos();
            for m in [1usize, 2, 3, 7, 50, 333] {
                let (a, b) = (sinusoid_avar(m as f64, nu0), slow(m, &r));
                assert!(rel(a, b) < ROUTES_REL_TOL, "ν0 {nu0} m {m}: {a:e} vs {b:e}");
            }
        }
        // IEEE 952's continuous form A²sin⁴(πf₀τ)/(πf₀τ)² when τ0 ≪ 1/f0
        let (f0, tau0) = (0.5, 1e-4);
        for tau in [0.1, 0.74, 2.3, 40.0] {
            let x = PI * f0 * tau;
            let want = x.sin().powi(4) / (x * x);
            let m = (tau / tau0).round();
            assert!(rel(sinusoid_avar(m, f0 * tau0), want) < 1e-6, "τ {tau}");
        }
    }

    #[test]
    fn resonance_matches_the_double_sum_and_tends_to_the_sinusoid() {
        for (f0, bw, tau0) in [(0.5, 0.01, 0.01), (17.0, 2.0, 0.01), (90.0, 4.0, 0.005)] {
            let (a, b) = resonance_poles(f0, bw, tau0);
            let r = |k: i64| {
                let k = k.unsigned_abs() as f64;
                (-a * k).exp() * ((b * k).cos() + a / b * (b * k).sin())
            };
            for m in [1usize, 2, 5, 13, 64, 400, 1500] {
                let (x, y) = (resonance_avar(m, a, b), slow(m, &r));
                assert!(
                    rel(x, y) < 1e-8,
                    "f0 {f0} B {bw} m {m}: closed {x:e} vs sum {y:e}"
                );
            }
        }
        // no damping: twice the unit sinusoid
        let (a, b) = resonance_poles(3.0, 0.0, 0.01);
        for m in [1usize, 4, 30, 999] {
            let want = 2.0 * sinusoid_avar(m as f64, 0.03);
            assert!(rel(resonance_avar(m, a, b), want) < ROUTES_REL_TOL, "m {m}");
        }
    }

    #[test]
    fn resonance_psd_integrates_to_its_variance_and_gives_its_allan_variance() {
        let (f0, bw) = (5.0, 0.8);
        // ∫ S df over (0, ∞): substitution f = f0·tan(u) would do; panels in log f suffice
        let total = simpson(
            |lf: f64| resonance_psd(lf.exp(), f0, bw) * lf.exp(),
            -12.0,
            12.0,
            20_000,
        );
        assert!(rel(total, 1.0) < 1e-6, "{total}");
        // the continuous Allan integral 2∫S₁ sin⁴(πfτ)/(πfτ)² df against the sampled form at
        // small τ0 (continuous limit)
        let tau0 = 1e-4;
        let (a, b) = resonance_poles(f0, bw, tau0);
        for tau in [0.05, 0.2, 1.0] {
            let k = |lf: f64| {
                let f = lf.exp();
                let x = PI * f * tau;
                resonance_psd(f, f0, bw) * x.sin().powi(4) / (x * x) * f
            };
            let cont = 2.0 * simpson(k, -12.0, 12.0, 40_000);
            let m = (tau / tau0).round() as usize;
            assert!(rel(resonance_avar(m, a, b), cont) < 1e-4, "τ {tau}: {cont}");
        }
    }
}
