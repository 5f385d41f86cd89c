//! The equivalent degrees of freedom behind each curve point's band, from the fitted model
//! rather than from a per-point guess of the noise type.
//!
//! An IMU's rate noise is white FM (N), flicker FM (B) and random-walk FM (K) — quantization
//! (white PM, Q) only where the model says Q carries the point — plus the shapes the model
//! holds (a Gauss–Markov bump, a flicker floor's corner, vibration lines). The per-point
//! identification of Riley & Greenhall ([`super::noise_id`]: lag-1 ACF, B1) is made for
//! clock data: on an IMU's long-τ points (a few tens of decimated samples) it flips to
//! α = +1 or +2, phase noise a rate output does not have, whose Greenhall EDF is up to
//! thousands of times the number of clusters — a band of ±5 % where four clusters remain.
//!
//! So the variance of each point is the model's: [`CovBasis::point_var`] is the exact
//! variance of the overlapping (or non-overlapping) estimate at that m for the fitted
//! mixture — the covariance the GLS fit itself weights the points with ([`super::avar_cov`]),
//! each shaped term standing in as the power law of its local slope and a resonance adding
//! the variance of its narrow-band estimate — and ν = 2·A(τ)²/Var(Â(τ)) with A the model's
//! Allan variance. The band is then the χ²(ν) interval around the measured point
//! ([`super::ci::chi2_interval`], Stable32's construction with the mixture's EDF). Fit and
//! bands agree with each other: each candidate fit of the declared-fit check is judged by
//! the bands its own model gives (`declare`), and the curve's bands are those of the fit
//! declared.
//!
//! Without a model that describes the curve (no reliable fit, or a model not positive at
//! that τ), a point gets Greenhall's EDF of the FM power law of the curve's local slope
//! there (AVAR ∝ τ^μ: α = −μ − 1 rounded and clamped to white, flicker or random-walk FM).

use super::fit::{self, Shapes, TERM_COUNT};
use super::model::effective_coef;
use super::term::NoiseTerm;
use super::{CovBasis, CurvePoint, Overlap, edf};

/// EDF of the estimate at cluster size `m` (τ = `tau`) under the model `coef`, `shapes`
/// (module docs); `None` where the model's Allan variance is not positive or the basis
/// does not hold the point.
pub(super) fn model_edf(
    basis: &CovBasis,
    coef: &[f64; TERM_COUNT],
    shapes: &Shapes,
    m: usize,
    tau: f64,
) -> Option<f64> {
    let a = fit::predict(coef, shapes, tau);
    if !(fit::is_positive(a) && a.is_finite()) {
        return None;
    }
    // as the fit's covariance has it: a negative 1/τ² coefficient is the low-pass
    // correction, not a quantization; fixed lines at the PSD's coefficient
    let fixed = shapes.fixed_coef();
    let mut cp = *coef;
    let q = NoiseTerm::Quantization;
    cp[q] = cp[q].max(0.0);
    for l in NoiseTerm::LINES {
        if fixed[l] != 0.0 {
            cp[l] = fixed[l];
        }
    }
    let mut var = basis.point_var(m, &effective_coef(&cp, shapes, tau))?;
    for (s, l) in shapes.lines.iter().enumerate() {
        if let Some(l) = l
            && l.bandwidth > 0.0
        {
            let la = cp[NoiseTerm::Line(s)].max(0.0) * l.avar(tau);
            var += 2.0 * la * la / l.edf();
        }
    }
    (fit::is_positive(var) && var.is_finite()).then(|| 2.0 * a * a / var)
}

/// The α of each of `points` (ascending τ) from the curve's local slope (module docs):
/// AVAR ∝ τ^μ over the neighbours within a factor [`SLOPE_SPAN`] of τ either side, α =
/// −μ − 1 rounded, clamped to −2..=0. White FM where no slope can be taken.
pub(super) fn slope_alphas(points: &[&CurvePoint]) -> Vec<i32> {
    let n = points.len();
    (0..n)
        .map(|i| {
            let t = points[i].tau;
            let lo = (0..=i)
                .find(|&k| points[k].tau >= t / SLOPE_SPAN)
                .unwrap_or(i);
            let hi = (i..n)
                .rev()
                .find(|&k| points[k].tau <= t * SLOPE_SPAN)
                .unwrap_or(i);
            if hi == lo {
                return 0;
            }
            let mu =
                (points[hi].avar / points[lo].avar).ln() / (points[hi].tau / points[lo].tau).ln();
            if !mu.is_finite() {
                return 0;
            }
            ((-mu - 1.0).round() as i32).clamp(-2, 0)
        })
        .collect()
}

/// Half-width (a factor of τ) of the local slope in [`slope_alphas`]: an octave each way,
/// so that the scatter of neighbouring long-τ points does not decide the noise type.
pub const SLOPE_SPAN: f64 = 2.0;

/// Greenhall's EDF of the FM law `alpha` at cluster size `m` of `n` samples (the fallback
/// of the module docs).
pub(super) fn slope_edf(alpha: i32, m: usize, n: usize, kind: Overlap) -> Option<f64> {
    edf::greenhall_edf(alpha, m, n + 1, kind)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ieee952::IdMethod;

    /// Greenhall's continuous-time EDF and the exact sampled variance agree to O(1/m)
    /// (`avar_cov`'s test allows 2 % at m ≥ 100).
    const GREENHALL_REL_TOL: f64 = 0.03;

    /// A single power law's model EDF is Greenhall's for that law (white, flicker and
    /// random-walk FM), and a mixture's lies between its components'.
    #[test]
    fn a_single_laws_model_edf_is_greenhalls_and_a_mixtures_lies_between() {
        let (n, tau0) = (200_000usize, 0.01);
        let ms = [100usize, 1000, 10_000, 50_000];
        let basis = CovBasis::new(&ms, n, tau0, Overlap::Overlapping).with_points(&ms, n, tau0);
        let flat = Shapes::FLAT;
        for &m in &ms {
            let tau = m as f64 * tau0;
            let mut nus = Vec::new();
            for t in [
                NoiseTerm::WhiteNoise,
                NoiseTerm::BiasInstability,
                NoiseTerm::RandomWalk,
            ] {
                let alpha = t.facts().alpha;
                let mut c = [0.0; TERM_COUNT];
                c[t] = 1e-4;
                let nu = model_edf(&basis, &c, &flat, m, tau).expect("edf");
                let want = edf::greenhall_edf(alpha, m, n + 1, Overlap::Overlapping).unwrap();
                assert!(
                    (nu / want - 1.0).abs() < GREENHALL_REL_TOL,
                    "m {m} α {alpha}: {nu} vs Greenhall {want}"
                );
                nus.push(nu);
            }
            // white FM and random walk with equal Allan variance at this τ
            let mut c = [0.0; TERM_COUNT];
            let (white, walk) = (NoiseTerm::WhiteNoise, NoiseTerm::RandomWalk);
            c[white] = 1e-4;
            c[walk] = 1e-4 * fit::basis(white, tau) / fit::basis(walk, tau);
            let mix = model_edf(&basis, &c, &flat, m, tau).expect("edf");
            assert!(mix > nus[2] && mix < nus[0], "m {m}: {mix} vs {nus:?}");
            // and never more than about 1.5 n/m
            assert!(mix < 1.6 * n as f64 / m as f64, "m {m}: {mix}");
        }
    }

    #[test]
    fn the_slope_fallback_reads_white_flicker_and_random_walk() {
        let pts: Vec<CurvePoint> = (0..30)
            .map(|k| {
                let tau = 1.5f64.powi(k);
                CurvePoint {
                    m: k as usize + 1,
                    tau,
                    // white below 10 s, flat to 1000 s, random walk above
                    avar: 1.0 / tau.min(10.0) * 0.1 * (tau / 1000.0).max(1.0),
                    id: Some(2),
                    id_method: IdMethod::Lag1,
                }
            })
            .collect();
        let refs: Vec<&CurvePoint> = pts.iter().collect();
        let a = slope_alphas(&refs);
        for (p, al) in pts.iter().zip(&a) {
            let want = if p.tau < 4.0 {
                0
            } else if p.tau > 30.0 && p.tau < 300.0 {
                -1
            } else if p.tau > 3000.0 {
                -2
            } else {
                continue;
            };
            assert_eq!(*al, want, "τ {}", p.tau);
        }
    }
}
