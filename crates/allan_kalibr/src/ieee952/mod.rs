//! The corrected estimator shared by both analysers (issue 6): fully overlapping Allan
//! deviation on a log grid of distinct cluster sizes, Greenhall EDF confidence intervals,
//! power-law noise identification, and a weighted fit of the IEEE Std 952 terms with a standard
//! error and a "resolved" verdict for each.
//!
//! # Units
//! The input is a rate series y in a unit U (rad/s for a gyro, m/s² for an accelerometer),
//! one sample every τ0 seconds. Deviations are in U. The terms are continuous-time:
//!
//! | term | meaning | unit (gyro / acc) |
//! |---|---|---|
//! | Q | quantization | U·s (rad, m/s) |
//! | N | white noise density (ARW/VRW) | U/√Hz = U·√s (rad/s/√Hz, m/s²/√Hz) |
//! | B | bias instability | U (rad/s, m/s²) |
//! | K | rate/acc random walk | U·√Hz = U/s/√Hz = U/√s (rad/s²/√Hz, m/s³/√Hz) |
//! | R | rate ramp | U/s (rad/s², m/s³) |
//!
//! N is Kalibr's `*_noise_density` and K its `*_random_walk`.
//!
//! # Overview
//! [`analyse`] runs everything: [`oadev::Phase`] (estimator), [`tau_grid::GridSpec`] (which m),
//! [`noise_id::identify`] (α per point, lag-1 ACF or B1), [`edf::greenhall_edf`] (Greenhall &
//! Riley 2004, the EDF behind IEEE 1139 / Stable32 — not the simpler Howe/Barnes formulas),
//! [`ci::chi2_interval`] (per-point χ² bounds), [`fit::fit`] (IEEE 952 terms by generalised
//! least squares with the covariance of the overlapping points from [`avar_cov`]).
//!
//! # How good can K be?
//! For white noise N plus random walk K over T seconds no unbiased estimator beats
//! se(K)/K ≈ √(2N/(K·T)) (Cramér–Rao, Whittle approximation). For the gyro presets of issue 6
//! at 4 h (N/K = 300 s) that is 20 %: about a third of all axes land outside ±20 % whatever the
//! method. The fit here reaches the bound within sampling error in the accuracy study.

pub mod avar_cov;
pub mod ci;
pub mod edf;
pub mod error;
pub mod fit;
pub mod imu;
pub mod noise_id;
pub mod oadev;
pub mod tau_grid;

#[cfg(test)]
mod tests_accuracy;
#[cfg(test)]
mod tests_stable32;

pub use error::Ieee952Error;
pub use fit::{FitConfig, FitMethod};
pub use noise_id::IdMethod;
pub use oadev::{Overlap, Phase};
pub use tau_grid::GridSpec;

use rayon::prelude::*;
use statrs::distribution::{ContinuousCDF, Normal};

/// Analysis settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Config {
    /// Cluster-size grid.
    pub grid: GridSpec,
    /// Confidence level of the per-point deviation bounds (0.683 = Stable32's 1-σ bounds).
    pub curve_confidence: f64,
    /// Confidence level of the term intervals and of the "resolved" test.
    pub term_confidence: f64,
    /// Model fit settings.
    pub fit: FitConfig,
}

impl Default for Config {
    fn default() -> Self {
        Config {
            grid: GridSpec::default(),
            curve_confidence: 0.683,
            term_confidence: 0.95,
            fit: FitConfig::default(),
        }
    }
}

/// Where a point's α (used for its EDF) came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AlphaSource {
    /// Lag-1 autocorrelation noise identification.
    Lag1,
    /// B1 ratio noise identification (few clusters).
    B1,
    /// Not identifiable from the data at this τ: α of the fitted model's dominant term.
    Model,
    /// Nothing available; white FM (α = 0) assumed.
    Assumed,
}

/// One point of the overlapping Allan deviation curve.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Point {
    /// Cluster size in samples.
    pub m: usize,
    /// τ = m·τ0 in seconds.
    pub tau: f64,
    /// Overlapping Allan variance, U².
    pub avar: f64,
    /// Overlapping Allan deviation, U.
    pub adev: f64,
    /// Lower bound of the deviation at `Config::curve_confidence`, U.
    pub lo: f64,
    /// Upper bound of the deviation at `Config::curve_confidence`, U.
    pub hi: f64,
    /// Greenhall EDF used for the bounds.
    pub edf: f64,
    /// Power-law α used for the EDF.
    pub alpha: i32,
    /// Where α came from.
    pub alpha_source: AlphaSource,
    /// Number of second differences averaged.
    pub n_terms: usize,
}

/// Whether a term can be reported.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Verdict {
    /// Positive with its lower bound above 0 and dominant somewhere on the curve.
    Resolved,
    /// The lower bound of its interval is 0: the data do not show the term.
    NotSignificant,
    /// Significant, but never the largest term at any τ of the curve: the record is too short
    /// (or too long) to see it on its own, so its value leans on the model.
    NeverDominant,
    /// Not in the fitted model, or the fit failed.
    NotFitted,
}

/// One IEEE 952 term.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Term {
    /// Estimate in the term's unit (see module docs); 0 when the fit puts it at its bound.
    pub value: f64,
    /// Standard error of `value` (delta method from the coefficient's); NaN when value = 0.
    pub std_err: f64,
    /// Lower end of the interval at `Config::term_confidence`, in the term's unit: the
    /// square root of the coefficient interval {c ≥ 0 : |ĉ − c| ≤ z·se(c)}
    /// ([`fit::inverted_interval`]).
    pub lo: f64,
    /// Upper end of the interval.
    pub hi: f64,
    /// Can this term be reported?
    pub verdict: Verdict,
}

impl Term {
    /// The value when resolved, else `None` ("say so instead of printing a number").
    pub fn reported(&self) -> Option<f64> {
        (self.verdict == Verdict::Resolved).then_some(self.value)
    }

    fn not_fitted() -> Term {
        Term {
            value: f64::NAN,
            std_err: f64::NAN,
            lo: f64::NAN,
            hi: f64::NAN,
            verdict: Verdict::NotFitted,
        }
    }
}

/// The five terms.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Terms {
    /// Quantization, U·s.
    pub q: Term,
    /// White noise density, U/√Hz.
    pub n: Term,
    /// Bias instability, U.
    pub b: Term,
    /// Random walk, U·√Hz (= U/s/√Hz).
    pub k: Term,
    /// Ramp, U/s.
    pub r: Term,
}

impl Terms {
    /// Terms in the order Q, N, B, K, R.
    pub fn as_array(&self) -> [Term; 5] {
        [self.q, self.n, self.b, self.k, self.r]
    }
}

/// Fit diagnostics.
#[derive(Clone, Debug, PartialEq)]
pub struct FitSummary {
    /// Coefficients Q², N², B², K², R².
    pub coef: [f64; 5],
    /// Their covariance (inflated, see [`FitConfig::correlation_inflation`]).
    pub cov: [[f64; 5]; 5],
    /// Re-weighting iterations.
    pub iterations: usize,
    /// Whether the re-weighting converged.
    pub converged: bool,
    /// Weighted χ² per degree of freedom (≈ 1 or below when the model fits).
    pub chi2_per_dof: f64,
}

/// Everything [`analyse`] finds for one series.
#[derive(Clone, Debug, PartialEq)]
pub struct Analysis {
    /// Number of samples analysed.
    pub n: usize,
    /// Sample period, s.
    pub tau0: f64,
    /// Overlapping Allan deviation curve.
    pub curve: Vec<Point>,
    /// IEEE 952 terms.
    pub terms: Terms,
    /// Fit diagnostics (`None` when the fit failed, then every term is `NotFitted`).
    pub fit: Option<FitSummary>,
}

/// Analyses one rate series y (unit U, sample period `tau0` s).
pub fn analyse(y: &[f64], tau0: f64, cfg: &Config) -> Result<Analysis, Ieee952Error> {
    if !(tau0 > 0.0 && tau0.is_finite()) {
        return Err(Ieee952Error::BadSamplePeriod(tau0));
    }
    for c in [cfg.curve_confidence, cfg.term_confidence] {
        if !(c > 0.0 && c < 1.0) {
            return Err(Ieee952Error::BadConfidence(c));
        }
    }
    if let Some((index, &value)) = y.iter().enumerate().find(|(_, v)| !v.is_finite()) {
        return Err(Ieee952Error::NonFinite { index, value });
    }
    let ms = cfg.grid.cluster_sizes(y.len());
    let min = 3 * cfg.grid.min_clusters.max(3);
    if ms.is_empty() || y.len() < min {
        return Err(Ieee952Error::TooShort { n: y.len(), min });
    }
    let phase = Phase::from_rate(y, tau0);
    let n_phase = y.len() + 1;
    // per point: AVAR, noise ID and the EDF for every α (all independent: parallel over m)
    let raw: Vec<(oadev::AvarPoint, noise_id::NoiseId, [f64; 5])> = ms
        .par_iter()
        .filter_map(|&m| {
            let p = phase.avar(m, Overlap::Overlapping)?;
            let id = noise_id::identify(&phase, m);
            let edf: [f64; 5] = std::array::from_fn(|k| {
                edf::greenhall_edf(2 - k as i32, m, n_phase, Overlap::Overlapping)
                    .unwrap_or(f64::NAN)
            });
            Some((p, id, edf))
        })
        .collect();
    let fit_points: Vec<fit::FitPoint> = raw
        .iter()
        .map(|(p, _, edf)| fit::FitPoint {
            m: p.m,
            tau: p.tau,
            avar: p.avar,
            edf: *edf,
        })
        .collect();
    let ids: Vec<Option<i32>> = raw.iter().map(|(_, id, _)| id.alpha).collect();
    let fitted = fit::fit(&fit_points, &ids, y.len(), tau0, &cfg.fit);

    let curve: Vec<Point> = raw
        .iter()
        .enumerate()
        .map(|(i, (p, id, edf))| {
            let (alpha, alpha_source) = match (id.alpha, id.method) {
                (Some(a), IdMethod::Lag1) => (a, AlphaSource::Lag1),
                (Some(a), _) => (a, AlphaSource::B1),
                (None, _) => match &fitted {
                    Some(f) => (fit::TERM_ALPHA[f.dominant[i]], AlphaSource::Model),
                    None => (0, AlphaSource::Assumed),
                },
            };
            let nu = edf[fit::alpha_index(alpha)];
            let adev = p.avar.sqrt();
            let (lo, hi) =
                ci::chi2_interval(adev, nu, cfg.curve_confidence).unwrap_or((f64::NAN, f64::NAN));
            Point {
                m: p.m,
                tau: p.tau,
                avar: p.avar,
                adev,
                lo,
                hi,
                edf: nu,
                alpha,
                alpha_source,
                n_terms: p.n_terms,
            }
        })
        .collect();

    let (terms, fit) = match fitted {
        Some(f) => (make_terms(&f, &fit_points, y.len(), tau0, cfg), Some(f)),
        None => {
            let t = Term::not_fitted();
            (
                Terms {
                    q: t,
                    n: t,
                    b: t,
                    k: t,
                    r: t,
                },
                None,
            )
        }
    };
    let fit = fit.map(|f| FitSummary {
        coef: f.coef,
        cov: f.cov,
        iterations: f.iterations,
        converged: f.converged,
        chi2_per_dof: f.chi2_per_dof,
    });
    Ok(Analysis {
        n: y.len(),
        tau0,
        curve,
        terms,
        fit,
    })
}

fn make_terms(
    f: &fit::FitResult,
    points: &[fit::FitPoint],
    n: usize,
    tau0: f64,
    cfg: &Config,
) -> Terms {
    let z = Normal::new(0.0, 1.0)
        .map(|d| d.inverse_cdf(0.5 + cfg.term_confidence / 2.0))
        .unwrap_or(1.96);
    let one = |j: usize| -> Term {
        if !cfg.fit.terms[j] {
            return Term::not_fitted();
        }
        let c = f.coef[j];
        let se_c = f.cov[j][j].max(0.0).sqrt();
        if f.left_out[j] {
            // left out by the selection: 0, with the all-terms fit's upper bound
            return Term {
                value: 0.0,
                std_err: f64::NAN,
                lo: 0.0,
                hi: (z * se_c).sqrt(),
                verdict: Verdict::NotSignificant,
            };
        }
        let value = c.sqrt();
        let std_err = if c > 0.0 {
            se_c / (2.0 * value)
        } else {
            f64::NAN
        };
        let (lo_c, hi_c) = fit::inverted_interval(points, f, n, tau0, &cfg.fit, j, z);
        let dominant_somewhere = f.dominant.contains(&j);
        let verdict = if !fit::is_positive(lo_c) {
            Verdict::NotSignificant
        } else if !dominant_somewhere {
            Verdict::NeverDominant
        } else {
            Verdict::Resolved
        };
        Term {
            value,
            std_err,
            lo: lo_c.sqrt(),
            hi: hi_c.sqrt(),
            verdict,
        }
    };
    Terms {
        q: one(0),
        n: one(1),
        b: one(2),
        k: one(3),
        r: one(4),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rejects_bad_input() {
        let cfg = Config::default();
        assert_eq!(
            analyse(&[1.0; 100], 0.0, &cfg).unwrap_err(),
            Ieee952Error::BadSamplePeriod(0.0)
        );
        let mut y = vec![1.0; 100];
        y[7] = f64::NAN;
        assert!(matches!(
            analyse(&y, 1.0, &cfg),
            Err(Ieee952Error::NonFinite { index: 7, .. })
        ));
        assert!(matches!(
            analyse(&[1.0; 5], 1.0, &cfg),
            Err(Ieee952Error::TooShort { n: 5, .. })
        ));
        let bad = Config {
            curve_confidence: 1.0,
            ..Config::default()
        };
        assert_eq!(
            analyse(&[1.0; 100], 1.0, &bad).unwrap_err(),
            Ieee952Error::BadConfidence(1.0)
        );
    }

    use rand::SeedableRng;
    use rand::rngs::StdRng;
    use rand_distr::{Distribution, StandardNormal};

    const RNG_SEED: u64 = 0x5407_7000;
    /// White noise has no random walk: K may come out "resolved" only by chance, at about the
    /// one-sided 2.5 % of the 95 % interval; allow up to 3× that over 100 trials.
    const MAX_FALSE_K_RATE: f64 = 0.075;

    #[test]
    fn short_white_series_rarely_claim_k() {
        let mut rng = StdRng::seed_from_u64(RNG_SEED);
        for n in [12usize, 50, 300, 2000] {
            let trials = 100;
            let mut false_k = 0;
            for _ in 0..trials {
                let y: Vec<f64> = (0..n).map(|_| StandardNormal.sample(&mut rng)).collect();
                let a = analyse(&y, 0.01, &Config::default()).unwrap();
                assert!(
                    a.curve.iter().all(|p| p.adev.is_finite() && p.adev > 0.0),
                    "n={n}: bad curve"
                );
                false_k += a.terms.k.reported().is_some() as usize;
            }
            println!("n={n}: K reported on white noise in {false_k}/{trials}");
            assert!(
                (false_k as f64) <= MAX_FALSE_K_RATE * trials as f64,
                "n={n}: K reported in {false_k}/{trials} white series, tol {MAX_FALSE_K_RATE}"
            );
        }
    }

    #[test]
    fn constant_series_gives_zero_curve_and_no_terms() {
        let a = analyse(&[2.5; 1000], 0.01, &Config::default()).unwrap();
        assert!(a.curve.iter().all(|p| p.avar == 0.0));
        assert!(a.terms.as_array().iter().all(|t| t.reported().is_none()));
    }
}
