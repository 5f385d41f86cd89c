//! The corrected estimator shared by both analysers: the fully overlapping Allan deviation
//! (every start index at every cluster size, [`oadev`]) on a log grid of distinct cluster
//! sizes, Greenhall EDF confidence intervals, power-law noise identification, a Welch PSD
//! with the vibration lines in it ([`psd`]), and a fit of the IEEE Std 952 terms that holds
//! on real sensors — a τ range the model can describe, weights that survive model error, a
//! goodness of fit and a verdict per axis, a 95 % interval and a verdict per term, and the
//! classic region readings as a cross-check and fallback.
//!
//! # Units
//! The input is a rate series y in a unit U (rad/s for a gyro, m/s² for an accelerometer),
//! one sample every τ0 seconds, or an Allan curve in U. Deviations are in U. The terms are
//! continuous-time:
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
//! [`analyse`] (samples) and [`analyse_curve`] (a curve from any tool) run everything:
//! [`oadev::Phase`] (estimator), [`tau_grid::GridSpec`] (which m), [`noise_id::identify`]
//! (α per point, lag-1 ACF or B1), [`edf::greenhall_edf`] (Greenhall & Riley 2004, the EDF
//! behind IEEE 1139 / Stable32), [`ci::chi2_interval`] (per-point χ² bounds),
//! [`fit`] (the τ range, the GLS fit with its model-discrepancy component, term selection —
//! the rules are in that module's docs) with the covariance of the points from
//! [`avar_cov`], [`region`] (the IEEE 952 graphical readings), [`curves_in`] (reading other tools'
//! curves), [`imu`] (the six axes as both analysers print them) and [`files`] (the terms
//! and curves CSVs and the Kalibr/VINS/ORB-SLAM3 files).
//!
//! # Verdicts
//! Per axis ([`AxisVerdict`]): the model fits the whole curve; the model fits from τ_lo on
//! (the shorter τ are band-limited: the sensor's low-pass filter or decimation); or no
//! reliable fit (then the terms are the region readings, and say so). A fit is declared only
//! where the fitted model stays within the larger of [`FIT_TOL`] and the point's own 95 %
//! band at every curve point of its range. Per term ([`Verdict`]): resolved only with a
//! 95 % lower bound above 0, a fitting model, and where the data show it: the term's own line
//! comes within 20 % of the model somewhere in the fitted range ([`RESOLVED_SHARE`] of the
//! Allan variance) — a bias instability only where there is a floor, not at the V where the
//! white-noise and random-walk lines cross, and only where that floor is the curve's own
//! lowest point within [`B_FLOOR_TOL`]. Where the data leave the flicker
//! floor's shape open (a flat floor or one with a lower corner, [`fit::flicker_band`]), each
//! interval spans every plausible shape ([`fit::FitResult::alternatives`]). A fit whose
//! model misses the curve beyond its statistics by more than [`APPROX_DELTA`], or whose
//! χ²/dof exceeds [`APPROX_CHI2`], is declared "approximately" (its terms lean on the
//! model's shape).
//!
//! Without a reliable fit the terms are IEEE 952's region readings ([`region`]: N from the
//! −½ line at τ = 1 s, B from the flat floor / 0.664, K from the +½ line at τ = 3 s), each
//! with its own interval or, where its region is absent, a 95 % upper bound — stated as such
//! in the text, the terms file (`source` = `region`) and the yaml files. The yaml files never
//! carry a term as if it were measured when it is not: an unresolved term is written as its
//! 95 % upper bound and marked so in a comment ([`files`]).
//!
//! # Vibration lines (issue 17)
//! A line (a pump, a fan, a structural resonance: IEEE 952's sinusoidal noise) puts a bump
//! of 0.725·A near τ = 0.37/f₀ on the curve and ripples decaying as A/(πf₀τ) for decades
//! after it. Three ways to handle it were open; this one is a **term of the model**: the
//! PSD of the samples ([`psd`]) finds each line (frequency, amplitude, bandwidth), and each
//! that the Allan curve feels ([`CurveData::model_lines`]) enters the fit with its exact
//! sampled Allan variance ([`lines`]; [`fit::LineShape`]), its A² a coefficient like the
//! others. Why not the alternatives: removing the line before the Allan analysis needs the
//! samples (not there for `--curves`), cannot remove a resonance without taking the white
//! noise under it, and would label a cleaned curve as the record's; a fitted range with a
//! hole loses exactly what the issue asks for, because the ripples' share of the variance
//! falls only as 1/τ against the white noise while the points' precision falls as √τ, so
//! the hole would eat two to three decades after a strong line. With the term the model
//! describes the curve on both sides of the line, the line included, and the region of the
//! curve the line dominates carries its own variance (a resonance's estimate has about
//! 2πB·T degrees of freedom, [`fit::LineShape::edf`]). A curve without samples has no PSD:
//! then lines are met as before (a short-τ bump is skipped, a long-τ one cuts the range).
//!
//! # How good can K be?
//! For white noise N plus random walk K over T seconds no unbiased estimator beats
//! se(K)/K ≈ √(2N/(K·T)) (Cramér–Rao, Whittle approximation). For the gyro presets of issue 6
//! at 4 h (N/K = 300 s) that is 20 %: about a third of all axes land outside ±20 % whatever the
//! method. The fit here reaches the bound within sampling error in the accuracy study.

pub mod advisor;
pub mod avar_cov;
pub mod ci;
pub mod curves_in;
pub mod edf;
pub mod files;
pub mod fit;
pub mod imu;
pub mod input_error;
pub mod lines;
pub mod noise_id;
pub mod oadev;
pub mod plot;
pub mod psd;
pub mod psd_plot;
pub mod region;
pub mod stated;
pub mod tau_grid;
pub mod vio_files;

#[cfg(test)]
mod tests_accuracy;
#[cfg(test)]
mod tests_bandlimited;
#[cfg(test)]
mod tests_lines;
#[cfg(test)]
mod tests_profiles;
#[cfg(test)]
mod tests_real;
#[cfg(test)]
mod tests_stable32;

pub use avar_cov::CovBasis;
pub use fit::FitConfig;
pub use input_error::Ieee952Error;
pub use noise_id::IdMethod;
pub use oadev::{Overlap, Phase};
pub use tau_grid::GridSpec;

use rayon::prelude::*;
use statrs::distribution::{ContinuousCDF, Normal};

/// The model may miss a curve point by this fraction (ADEV) where the point's own 95 % band
/// is narrower: the issue's bar for "the model describes the curve".
pub const FIT_TOL: f64 = 0.10;
/// A term is resolved only where its own Allan variance is at least this share of the
/// measured one somewhere in the fitted range: its line within 20 % (0.8² = 0.64) of the
/// curve.
pub const RESOLVED_SHARE: f64 = 0.64;
/// A bias instability is resolved only where the measured curve shows its floor: 0.664·B
/// within this fraction of the curve's lowest point in the fitted range. A B the model
/// infers from the curve's bend (a floor with a corner it never reaches, a bump, the white
/// noise still adding at the minimum) is "never dominant", with its value and interval.
pub const B_FLOOR_TOL: f64 = 0.20;
/// A fit whose model discrepancy δ exceeds this is declared "approximately": the model stays
/// within [`FIT_TOL`] of the curve, yet misses points whose own error is far smaller, so
/// the terms lean on the model's shape rather than on the data (5 %: half the tolerance;
/// the real curves of `testdata/real_curves` have δ ≤ 4 % except a heavily filtered
/// accelerometer whose curve bends slowly over four decades, δ 7 %).
pub const APPROX_DELTA: f64 = 0.05;
/// A fit whose statistical χ²/dof exceeds this is declared "approximately" whatever its δ:
/// its model misses the points by thirty times their own error and more (a hand-held record
/// was labelled "model fits" at χ²/dof 4,314; the real curves of `testdata/real_curves`
/// stay below 400).
pub const APPROX_CHI2: f64 = 1000.0;
/// The misses of one short-τ feature (a bump above the white-noise line) lie within this
/// factor of τ of its first miss (two octaves: a resonance's Allan bump is about that wide).
pub const SHORT_FEATURE_SPAN: f64 = 4.0;
/// A fit starts past a short-τ feature instead of ending before it only when that leaves a
/// range wider by this many decades (a clear gain, so a long-end bend is still cut there).
pub const SHORT_FEATURE_GAIN: f64 = 1.0;
/// Where IEEE 952 reads N (s): a fit only moves its start past a short-τ feature while the
/// range keeps this τ, so that N is read, not extrapolated.
pub const N_READING_TAU: f64 = 1.0;
/// A declared fit range spans at least this many decades of τ; shorter is "no reliable fit".
pub const MIN_RANGE_DECADES: f64 = 1.0;
/// A line of the PSD enters the model where its own Allan variance is at least this share
/// of the measured one at some point (1 %: half a percent in deviation, about the precision
/// of the short-τ points of a long record).
pub const LINE_MIN_SHARE: f64 = 0.01;

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

/// One measured point handed to the analysis.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CurvePoint {
    /// Cluster size in samples (of τ0).
    pub m: usize,
    /// τ = m·τ0 in seconds.
    pub tau: f64,
    /// Allan variance, U² (NaN or ≤ 0 when the tool gave none).
    pub avar: f64,
    /// Identified α, when the samples were at hand.
    pub id: Option<i32>,
    /// How α was identified.
    pub id_method: IdMethod,
}

/// A measured Allan curve of one axis, from samples or from another tool's file.
#[derive(Clone, Debug, PartialEq)]
pub struct CurveData {
    /// Sample period τ0 (or the curve's τ unit), s.
    pub tau0: f64,
    /// Rate samples behind the curve; `None` when unknown (then no intervals).
    pub n: Option<usize>,
    /// Estimator of the curve.
    pub kind: Overlap,
    /// Points, ascending m.
    pub points: Vec<CurvePoint>,
    /// The Welch PSD of the samples (none for a curve alone).
    pub psd: Option<psd::Psd>,
    /// The lines found in it, strongest first.
    pub lines: Vec<psd::Line>,
}

impl CurveData {
    /// A curve without samples behind it (no PSD, no lines).
    pub fn from_points(
        tau0: f64,
        n: Option<usize>,
        kind: Overlap,
        points: Vec<CurvePoint>,
    ) -> Self {
        CurveData {
            tau0,
            n,
            kind,
            points,
            psd: None,
            lines: Vec::new(),
        }
    }

    /// The same curve with the PSD and the lines of its samples `y` ([`psd`]).
    pub fn with_spectrum(mut self, y: &[f64]) -> Self {
        self.psd = psd::welch(y, 1.0 / self.tau0);
        self.lines = self.psd.as_ref().map(psd::find_lines).unwrap_or_default();
        self
    }

    /// The lines the model holds: the strongest ([`fit::LINE_SLOTS`] at most) whose own Allan
    /// variance (as the PSD measured them) reaches [`LINE_MIN_SHARE`] of the curve at one of
    /// its points at least; weaker ones leave the curve alone.
    pub(crate) fn model_lines(&self) -> fit::LineSlots {
        let mut out: fit::LineSlots = Default::default();
        let mut k = 0;
        for l in &self.lines {
            if k == fit::LINE_SLOTS {
                break;
            }
            let shape = fit::LineShape {
                frequency: l.frequency,
                bandwidth: l.bandwidth,
                bandwidth_se: l.bandwidth_se,
                tau0: self.tau0,
                psd_amp2: l.amplitude * l.amplitude,
                record: self.n.unwrap_or(0) as f64 * self.tau0,
            };
            let matters = self.points.iter().any(|p| {
                p.avar > 0.0 && shape.psd_amp2 * shape.avar(p.tau) >= LINE_MIN_SHARE * p.avar
            });
            if matters {
                out[k] = Some(shape);
                k += 1;
            }
        }
        out
    }
    /// Overlapping Allan variance of `y` on the grid of `cfg`, with the noise identification.
    pub(crate) fn from_samples(
        y: &[f64],
        tau0: f64,
        cfg: &Config,
    ) -> Result<CurveData, Ieee952Error> {
        check_config(tau0, cfg)?;
        if let Some((index, &value)) = y.iter().enumerate().find(|(_, v)| !v.is_finite()) {
            return Err(Ieee952Error::NonFinite { index, value });
        }
        let ms = cfg.grid.cluster_sizes(y.len());
        let min = 3 * cfg.grid.min_clusters.max(3);
        if ms.is_empty() || y.len() < min {
            return Err(Ieee952Error::TooShort { n: y.len(), min });
        }
        let phase = Phase::from_rate(y, tau0);
        let avars = phase.avar_curve(&ms);
        let points = avars
            .par_iter()
            .map(|p| {
                let id = noise_id::identify(&phase, p.m);
                CurvePoint {
                    m: p.m,
                    tau: p.tau,
                    avar: p.avar,
                    id: id.alpha,
                    id_method: id.method,
                }
            })
            .collect();
        Ok(
            CurveData::from_points(tau0, Some(y.len()), Overlap::Overlapping, points)
                .with_spectrum(y),
        )
    }

    /// Cluster sizes of the fit grid (the valid points nearest 2^(k/p)).
    pub(crate) fn fit_ms(&self, per_octave: u32) -> Vec<usize> {
        let valid: Vec<usize> = self
            .points
            .iter()
            .filter(|p| p.avar > 0.0 && p.avar.is_finite())
            .map(|p| p.m)
            .collect();
        fit::thin_to_grid(&valid, per_octave)
            .into_iter()
            .map(|i| valid[i])
            .collect()
    }

    /// The statistical covariance basis of the fit grid (None without a sample count).
    pub fn basis(&self, per_octave: u32) -> Option<CovBasis> {
        let n = self.n?;
        Some(CovBasis::new(
            &self.fit_ms(per_octave),
            n,
            self.tau0,
            self.kind,
        ))
    }
}

fn check_config(tau0: f64, cfg: &Config) -> Result<(), Ieee952Error> {
    if !(tau0 > 0.0 && tau0.is_finite()) {
        return Err(Ieee952Error::BadSamplePeriod(tau0));
    }
    for c in [cfg.curve_confidence, cfg.term_confidence] {
        if !(c > 0.0 && c < 1.0) {
            return Err(Ieee952Error::BadConfidence(c));
        }
    }
    Ok(())
}

/// One point of the analysed Allan deviation curve.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Point {
    /// Cluster size in samples.
    pub m: usize,
    /// τ = m·τ0 in seconds.
    pub tau: f64,
    /// Allan variance, U².
    pub avar: f64,
    /// Allan deviation, U.
    pub adev: f64,
    /// Lower bound of the deviation at `Config::curve_confidence`, U (NaN: no sample count).
    pub lo: f64,
    /// Upper bound of the deviation at `Config::curve_confidence`, U.
    pub hi: f64,
    /// Lower bound at 95 %, U.
    pub lo95: f64,
    /// Upper bound at 95 %, U.
    pub hi95: f64,
    /// Greenhall EDF used for the bounds.
    pub edf: f64,
    /// Power-law α used for the EDF.
    pub alpha: i32,
    /// Where α came from.
    pub alpha_source: AlphaSource,
    /// Inside the fitted range.
    pub in_range: bool,
    /// Fitted model deviation at this τ (NaN without a fit).
    pub model: f64,
}

/// Whether a term can be reported.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Verdict {
    /// Positive with its lower bound above 0, and its own line within 20 % of the curve
    /// somewhere in the fitted range.
    Resolved,
    /// The lower bound of its interval is 0: the data do not show the term.
    NotSignificant,
    /// Significant, but the curve never shows it on its own: its line never comes within
    /// 20 % of the curve in the fitted range (e.g. a bias instability under the V of the
    /// white-noise and random-walk lines), or, for B, the curve's lowest point is not at
    /// 0.664·B within [`B_FLOOR_TOL`]. Its value leans on the model.
    NeverDominant,
    /// No reliable fit: the value is the IEEE 952 region reading, with its own interval.
    RegionReading,
    /// No reliable fit and no region for the term: only the 95 % upper bound is known.
    RegionBound,
    /// Fitted, but the whole record does not agree with it: its value is above what every
    /// point's upper 95 % band allows, or the model it lifts rises above the curve's upper
    /// band beyond the fitted range. Only the record's 95 % upper bound is reported.
    Contradicted,
    /// Not in the fitted model, or nothing could be computed.
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
    /// ([`fit::inverted_interval`]). NaN without a sample count.
    pub lo: f64,
    /// Upper end of the interval.
    pub hi: f64,
    /// Can this term be reported?
    pub verdict: Verdict,
}

impl Term {
    /// The value when resolved (or read from its region), else `None` ("say so instead of
    /// printing a number").
    pub(crate) fn reported(&self) -> Option<f64> {
        matches!(self.verdict, Verdict::Resolved | Verdict::RegionReading).then_some(self.value)
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

    fn from_reading(r: Option<region::Reading>) -> Term {
        match r {
            Some(r) if r.kind == region::ReadingKind::Line => Term {
                value: r.value,
                std_err: f64::NAN,
                lo: r.lo,
                hi: r.hi,
                verdict: Verdict::RegionReading,
            },
            Some(r) => Term {
                value: 0.0,
                std_err: f64::NAN,
                lo: 0.0,
                hi: r.hi,
                verdict: Verdict::RegionBound,
            },
            None => Term::not_fitted(),
        }
    }
}

/// The five IEEE 952 terms and the exponentially correlated (Gauss–Markov) bias.
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
    /// Gauss–Markov (exponentially correlated) bias: its σ, U. Not one of the five power-law
    /// terms: in the model so that a bump is not read as bias instability or random walk.
    pub g: Term,
    /// Its correlation time, s (NaN when it is not in the model).
    pub g_time: f64,
    /// The flicker floor's lower corner T_lo, s: the shortest correlation time of its 1/f
    /// spectrum (0: IEEE 952's flat floor; see [`fit::flicker_band`]). The floor is within
    /// 2 % of 0.664·B from τ ≈ 40·T_lo on.
    pub b_corner: f64,
    /// The lines in the model (IEEE 952 sinusoidal noise), by slot.
    pub lines: [Option<LineTerm>; fit::LINE_SLOTS],
}

/// A vibration line of the model.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LineTerm {
    /// Frequency (from the PSD), Hz.
    pub frequency: f64,
    /// −3 dB bandwidth (from the PSD), Hz; 0 for a sinusoid.
    pub bandwidth: f64,
    /// Amplitude A the Allan fit gives (√ of its coefficient; 0 when the fit puts it at or
    /// below 0), U.
    pub amplitude: f64,
    /// Amplitude the PSD gives (√(2·power)), U.
    pub psd_amplitude: f64,
}

impl Terms {
    /// Terms in the order Q, N, B, K, R.
    pub(crate) fn as_array(&self) -> [Term; 5] {
        [self.q, self.n, self.b, self.k, self.r]
    }
}

/// What the fit says about one axis.
#[derive(Clone, Debug, PartialEq)]
pub enum AxisVerdict {
    /// The model describes the curve over `range` (τ of the first and last fit point, s):
    /// every curve point there is within [`FIT_TOL`] or its own 95 % band of the model.
    Fits {
        /// Declared range, s.
        range: (f64, f64),
        /// Shorter τ left out.
        short_cut: bool,
        /// Among the shorter τ left out, points above the model (a bump over the white-noise
        /// line: a vibration, a resonance).
        short_feature: bool,
        /// Among the shorter τ left out, points below the model's white-noise line: the
        /// sensor's low-pass filter or decimation (the only case called "band-limited").
        band_limited: bool,
        /// Longer τ left out: the curve does something the model has no term for there (a
        /// bump, a dip, a turn-down).
        long_cut: bool,
        /// The model misses the curve beyond its statistics by this relative discrepancy δ
        /// (when above [`APPROX_DELTA`]: within [`FIT_TOL`] but the terms are approximate).
        approximate: Option<f64>,
    },
    /// No reliable fit; the terms are the IEEE 952 region readings.
    NoReliableFit {
        /// Why, in words.
        reason: String,
    },
}

impl AxisVerdict {
    /// The model describes a declared range.
    pub(crate) fn fits(&self) -> bool {
        matches!(self, AxisVerdict::Fits { .. })
    }

    /// The declared range, when the model fits.
    pub(crate) fn range(&self) -> Option<(f64, f64)> {
        match self {
            AxisVerdict::Fits { range, .. } => Some(*range),
            AxisVerdict::NoReliableFit { .. } => None,
        }
    }
}

impl std::fmt::Display for AxisVerdict {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            AxisVerdict::Fits {
                range,
                short_cut,
                short_feature,
                band_limited,
                long_cut,
                approximate,
            } => {
                let why_short = match (band_limited, short_feature) {
                    (true, true) => "band-limited, and a bump above the white-noise line",
                    (true, false) => "band-limited",
                    (false, true) => "a bump above the white-noise line",
                    (false, false) => "its first points are out of line with the rest",
                };
                if let Some(d) = approximate {
                    write!(
                        f,
                        "approximately (the model misses the curve by {:.0} % beyond its statistics; the terms are approximate): ",
                        100.0 * d
                    )?;
                }
                if !short_cut && !long_cut {
                    return write!(f, "model fits");
                }
                write!(
                    f,
                    "model fits τ = {} – {} s; ",
                    short(range.0),
                    short(range.1)
                )?;
                match (short_cut, long_cut) {
                    (true, true) => write!(
                        f,
                        "does not describe τ < {} s ({why_short}) nor τ > {} s (the curve bends where the model has no term)",
                        short(range.0),
                        short(range.1)
                    ),
                    (true, false) => write!(
                        f,
                        "does not describe τ < {} s ({why_short})",
                        short(range.0)
                    ),
                    _ => write!(
                        f,
                        "does not describe τ > {} s (the curve bends where the model has no term)",
                        short(range.1)
                    ),
                }
            }
            AxisVerdict::NoReliableFit { reason } => write!(f, "no reliable fit: {reason}"),
        }
    }
}

/// A number in 3 significant digits for messages.
pub(crate) fn short(x: f64) -> String {
    if x == 0.0 || !x.is_finite() {
        return format!("{x}");
    }
    let e = x.abs().log10().floor() as i32;
    if (-3..5).contains(&e) {
        let d = (2 - e).max(0) as usize;
        format!("{x:.d$}")
    } else {
        format!("{x:.2e}")
    }
}

/// Fit diagnostics.
#[derive(Clone, Debug, PartialEq)]
pub struct FitSummary {
    /// Coefficients Q², N², B², K², R², σ_GM² (Q² < 0: the low-pass correction).
    pub coef: [f64; fit::TERM_COUNT],
    /// Their covariance.
    pub cov: [[f64; fit::TERM_COUNT]; fit::TERM_COUNT],
    /// Shapes of the Gauss–Markov bias and of the flicker floor.
    pub shapes: fit::Shapes,
    /// Re-weighting iterations.
    pub iterations: usize,
    /// Whether the re-weighting converged.
    pub converged: bool,
    /// Statistical χ² per degree of freedom over the fitted range (NaN without a sample
    /// count); ≈ 1 when the model describes the points within their statistics.
    pub chi2_per_dof: f64,
    /// Relative model discrepancy δ: the fraction by which the model misses a point beyond
    /// the statistics (0 when it does not).
    pub delta: f64,
    /// Fitted range (τ of the first and last fit point), s.
    pub tau_range: (f64, f64),
    /// Fit points used.
    pub points: usize,
    /// Largest |model/data − 1| (ADEV) over the curve points of the range.
    pub max_misfit: f64,
}

impl FitSummary {
    /// Model AVAR at τ.
    pub(crate) fn predict(&self, tau: f64) -> f64 {
        fit::predict(&self.coef, &self.shapes, tau)
    }
}

/// Everything [`analyse`] finds for one series.
#[derive(Clone, Debug, PartialEq)]
pub struct Analysis {
    /// Number of samples analysed (None: unknown, curve given without it).
    pub n: Option<usize>,
    /// Sample period, s.
    pub tau0: f64,
    /// Estimator of the curve.
    pub kind: Overlap,
    /// Allan deviation curve.
    pub curve: Vec<Point>,
    /// IEEE 952 terms.
    pub terms: Terms,
    /// Fit diagnostics (`None` when no fit was possible).
    pub fit: Option<FitSummary>,
    /// The verdict on the axis.
    pub verdict: AxisVerdict,
    /// The region readings (cross-check; the terms when there is no reliable fit).
    pub region: region::Readings,
    /// The Welch PSD of the samples (none for a curve alone).
    pub psd: Option<psd::Psd>,
    /// Every line the PSD shows, strongest first (those in the model are in `terms.lines`).
    pub lines: Vec<psd::Line>,
    /// The largest N and K every curve point allows at 95 % (its upper band over the
    /// term's Allan deviation per unit, the minimum over the whole curve: for K,
    /// min σ_hi95(τ)·√(3/τ)); the yaml files never write more.
    pub bounds: (f64, f64),
}

/// Analyses one rate series y (unit U, sample period `tau0` s).
pub fn analyse(y: &[f64], tau0: f64, cfg: &Config) -> Result<Analysis, Ieee952Error> {
    let data = CurveData::from_samples(y, tau0, cfg)?;
    let basis = data.basis(cfg.fit.per_octave);
    Ok(analyse_curve(&data, cfg, basis.as_ref()))
}

/// The z of the two-sided interval at `confidence`.
fn z_of(confidence: f64) -> f64 {
    Normal::new(0.0, 1.0)
        .map(|d| d.inverse_cdf(0.5 + confidence / 2.0))
        .unwrap_or(1.96)
}

/// Analyses a measured curve. `basis` is the statistical covariance of its fit grid
/// ([`CurveData::basis`]; shared by the axes of an IMU), `None` when the sample count is
/// unknown.
pub(crate) fn analyse_curve(data: &CurveData, cfg: &Config, basis: Option<&CovBasis>) -> Analysis {
    let fit_ms = data.fit_ms(cfg.fit.per_octave);
    let valid: Vec<&CurvePoint> = data
        .points
        .iter()
        .filter(|p| p.avar > 0.0 && p.avar.is_finite())
        .collect();
    let basis = basis.filter(|b| fit_ms.iter().all(|m| b.ms().binary_search(m).is_ok()));
    let fd = fit::FitData {
        points: fit_ms
            .iter()
            .map(|&m| {
                let p = valid
                    .iter()
                    .find(|p| p.m == m)
                    .expect("fit grid from valid");
                fit::FitPoint {
                    m,
                    tau: p.tau,
                    avar: p.avar,
                }
            })
            .collect(),
        curve_index: fit_ms
            .iter()
            .map(|&m| data.points.iter().position(|p| p.m == m).unwrap_or(0))
            .collect(),
        basis,
        basis_index: fit_ms
            .iter()
            .map(|m| basis.map_or(0, |b| b.ms().binary_search(m).unwrap_or(0)))
            .collect(),
        lines: data.model_lines(),
    };
    let n_phase = data.n.map(|n| n + 1);

    // the range and the fit, then the declared-fit check
    let (fitted, verdict, max_misfit) = declare_fit(data, &fd, &valid, cfg);
    // the curve with its bounds
    let range = verdict.range();
    let curve: Vec<Point> = data
        .points
        .iter()
        .filter(|p| p.avar > 0.0 && p.avar.is_finite())
        .map(|p| {
            let (alpha, alpha_source) = match (p.id, p.id_method) {
                (Some(a), IdMethod::Lag1) => (a, AlphaSource::Lag1),
                (Some(a), _) => (a, AlphaSource::B1),
                (None, _) => match &fitted {
                    Some(f) => (
                        fit::TERM_ALPHA[fit::dominant_term(&f.coef, &f.shapes, p.tau)],
                        AlphaSource::Model,
                    ),
                    None => (0, AlphaSource::Assumed),
                },
            };
            let nu = n_phase
                .and_then(|np| edf::greenhall_edf(alpha, p.m, np, data.kind))
                .unwrap_or(f64::NAN);
            let adev = p.avar.sqrt();
            let (lo, hi) =
                ci::chi2_interval(adev, nu, cfg.curve_confidence).unwrap_or((f64::NAN, f64::NAN));
            let (lo95, hi95) = ci::chi2_interval(adev, nu, 0.95).unwrap_or((f64::NAN, f64::NAN));
            let in_range = range
                .is_some_and(|(a, b)| p.tau >= a * (1.0 - 1e-12) && p.tau <= b * (1.0 + 1e-12));
            Point {
                m: p.m,
                tau: p.tau,
                avar: p.avar,
                adev,
                lo,
                hi,
                lo95,
                hi95,
                edf: nu,
                alpha,
                alpha_source,
                in_range,
                model: fitted
                    .as_ref()
                    .map_or(f64::NAN, |f| f.predict(p.tau).max(0.0).sqrt()),
            }
        })
        .collect();

    // what the left-out short τ are: below the model's white-noise line (band-limited), above
    // it (a bump), or both — said from the points themselves, not from how the range was cut
    let mut verdict = verdict;
    if let (
        AxisVerdict::Fits {
            range,
            short_cut: true,
            short_feature,
            band_limited,
            ..
        },
        Some(f),
    ) = (&mut verdict, &fitted)
    {
        let (mut above, mut below, mut lean) = (false, false, 0.0);
        for p in curve.iter().filter(|p| p.tau < range.0 * (1.0 - 1e-12)) {
            let model = f.predict(p.tau).max(0.0).sqrt();
            let band = (p.hi95 / p.adev - 1.0).max(0.0);
            if !fit::is_positive(model) {
                continue;
            }
            let mis = p.adev / model - 1.0;
            // below the white-noise line (with the quantization's): what a band limit does;
            // a point under the model but over that line is the model's line or bump shape
            let white = (f.coef[0].max(0.0) * fit::basis(0, p.tau)
                + f.coef[1] * fit::basis(1, p.tau))
            .max(0.0)
            .sqrt();
            let under_white = p.adev / white - 1.0;
            lean += under_white.min(0.0) + mis.max(0.0);
            if band.is_finite() && mis > FIT_TOL.max(band) {
                above = true;
            } else if band.is_finite() && under_white < -FIT_TOL.max(band) {
                below = true;
            }
        }
        // by the misses beyond the points' bands; without any, as the range was cut (a
        // feature the start moved past, else the band limit of old)
        if above || below {
            *short_feature = above;
            *band_limited = below;
        } else {
            // within their bands: below the model's white-noise line only if they lean below
            *band_limited = lean < 0.0 && !*short_feature;
        }
    }
    let verdict = verdict;
    // region readings on the fit grid of the declared range (all of it without a fit)
    let (rlo, rhi) = range.unwrap_or((0.0, f64::INFINITY));
    let region_pts: Vec<Point> = fd
        .points
        .iter()
        .filter(|fp| fp.tau >= rlo * (1.0 - 1e-12) && fp.tau <= rhi * (1.0 + 1e-12))
        .filter_map(|fp| curve.iter().find(|c| c.m == fp.m).copied())
        .collect();
    let region = region::read(&region_pts);

    let terms = match (&fitted, verdict.fits()) {
        (Some(f), true) => make_terms(f, &fd, &curve, cfg),
        _ => {
            // a reading above what another point's upper band allows is that bound instead
            let clamp = |j: usize, t: Term| -> Term {
                let bound = region::upper_bound(curve.iter(), |tau| {
                    fit::basis_at(j, tau, &fit::Shapes::FLAT).sqrt()
                });
                match t.verdict {
                    Verdict::RegionReading if t.value > bound => Term {
                        value: 0.0,
                        std_err: f64::NAN,
                        lo: 0.0,
                        hi: bound,
                        verdict: Verdict::RegionBound,
                    },
                    Verdict::RegionBound => Term {
                        hi: t.hi.min(bound),
                        ..t
                    },
                    _ => t,
                }
            };
            Terms {
                q: Term::not_fitted(),
                n: clamp(1, Term::from_reading(region.n)),
                b: clamp(2, Term::from_reading(region.b)),
                k: clamp(3, Term::from_reading(region.k)),
                r: Term::not_fitted(),
                g: Term::not_fitted(),
                g_time: f64::NAN,
                b_corner: 0.0,
                lines: [None; fit::LINE_SLOTS],
            }
        }
    };
    let fit = fitted.map(|f| FitSummary {
        coef: f.coef,
        cov: f.cov,
        shapes: f.shapes,
        iterations: f.iterations,
        converged: f.converged,
        chi2_per_dof: f.chi2_per_dof,
        delta: f.delta,
        tau_range: (
            fd.points[f.used[0]].tau,
            fd.points[*f.used.last().unwrap_or(&0)].tau,
        ),
        points: f.used.len(),
        max_misfit,
    });
    let bounds = (
        region::upper_bound(curve.iter(), |t| fit::basis(1, t).sqrt()),
        region::upper_bound(curve.iter(), |t| fit::basis(3, t).sqrt()),
    );
    Analysis {
        n: data.n,
        tau0: data.tau0,
        kind: data.kind,
        curve,
        terms,
        fit,
        verdict,
        region,
        psd: data.psd.clone(),
        lines: data.lines.clone(),
        bounds,
    }
}

/// Chooses the fitted range and fits it: the start from [`fit::choose_start`], then the
/// declared-fit check — every curve point of the range within the larger of [`FIT_TOL`] and
/// its 95 % band of the model. A miss among the first points of the range moves the start
/// past it; a miss further up ends the range before it (the long τ the model cannot
/// describe). Where that miss may instead be a short-τ feature — the data above the model
/// over at most [`SHORT_FEATURE_SPAN`], before [`N_READING_TAU`] — both are carried to the
/// end, and the start past the feature is kept only if its range still holds
/// [`N_READING_TAU`] and is wider by [`SHORT_FEATURE_GAIN`] decades. Fewer than
/// [`fit::MIN_FIT_POINTS`] points or less than [`MIN_RANGE_DECADES`] left: no reliable fit.
/// Returns the last fit, the verdict and the largest misfit.
fn declare_fit(
    data: &CurveData,
    fd: &fit::FitData,
    valid: &[&CurvePoint],
    cfg: &Config,
) -> Declared {
    let bounds = Bounds {
        start: fit::choose_start(fd, &cfg.fit),
        end: fd.points.len(),
        long_cut: false,
        feature: false,
        last_miss: None,
    };
    declare_from(data, fd, valid, cfg, bounds)
}

/// The last fit, the verdict and the largest misfit.
type Declared = (Option<fit::FitResult>, AxisVerdict, f64);

/// A candidate range of [`declare_fit`] on the fit grid, and how it was reached.
#[derive(Clone, Copy, Debug)]
struct Bounds {
    start: usize,
    end: usize,
    /// The end was cut before a miss (the range may grow back while the check holds).
    long_cut: bool,
    /// The start was moved past a short-τ feature.
    feature: bool,
    /// The largest miss met so far (τ, size), for the reason of a failure.
    last_miss: Option<(f64, f64)>,
}

/// Decades of τ a declared fit spans (0 without a fit).
fn declared_decades(d: &Declared) -> f64 {
    d.1.range().map_or(0.0, |(lo, hi)| (hi / lo).log10())
}

/// [`declare_fit`] from the candidate range `b`.
fn declare_from(
    data: &CurveData,
    fd: &fit::FitData,
    valid: &[&CurvePoint],
    cfg: &Config,
    mut b: Bounds,
) -> Declared {
    let np = fd.points.len();
    let mut last_fit = None;
    let pos_from = |tau: f64| fd.points.iter().position(|p| p.tau >= tau).unwrap_or(np);
    loop {
        if b.end <= b.start || b.end - b.start < fit::MIN_FIT_POINTS {
            let reason = match b.last_miss {
                Some((tau, mis)) => format!(
                    "the best model misses the curve by {:.0} % at τ = {} s",
                    100.0 * mis,
                    short(tau)
                ),
                None => format!("only {} usable points", b.end.saturating_sub(b.start)),
            };
            return (last_fit, AxisVerdict::NoReliableFit { reason }, f64::NAN);
        }
        let Some((f, misses, max_mis)) = fit_and_check(data, fd, valid, cfg, b.start, b.end) else {
            return (
                None,
                AxisVerdict::NoReliableFit {
                    reason: "the fit found no positive model".into(),
                },
                f64::NAN,
            );
        };
        if misses.is_empty() {
            let (mut f, mut max_mis, mut end) = (f, max_mis, b.end);
            // after a cut at the long end, extend again while the check holds: the first miss
            // is where the model stops following, not necessarily where the curve bends
            if b.long_cut {
                while end < np {
                    match fit_and_check(data, fd, valid, cfg, b.start, end + 1) {
                        Some((g, m, mm)) if m.is_empty() => {
                            f = g;
                            max_mis = mm;
                            end += 1;
                        }
                        _ => break,
                    }
                }
            }
            let (lo_t, hi_t) = (fd.points[b.start].tau, fd.points[end - 1].tau);
            if (hi_t / lo_t).log10() < MIN_RANGE_DECADES {
                let reason = match b.last_miss {
                    Some((tau, mis)) => format!(
                        "the best model misses the curve by {:.0} % at τ = {} s, and fits only {} – {} s",
                        100.0 * mis,
                        short(tau),
                        short(lo_t),
                        short(hi_t)
                    ),
                    None => format!(
                        "the usable range {} – {} s is shorter than a decade",
                        short(lo_t),
                        short(hi_t)
                    ),
                };
                return (Some(f), AxisVerdict::NoReliableFit { reason }, max_mis);
            }
            let verdict = AxisVerdict::Fits {
                range: (lo_t, hi_t),
                short_cut: b.start > 0,
                short_feature: b.feature,
                band_limited: b.start > 0,
                long_cut: end < np,
                approximate: (f.delta > APPROX_DELTA || f.chi2_per_dof > APPROX_CHI2)
                    .then_some(f.delta),
            };
            return (Some(f), verdict, max_mis);
        }
        let first = misses[0];
        b.last_miss = misses
            .iter()
            .max_by(|x, y| x.size.total_cmp(&y.size))
            .map(|m| (m.tau, m.size));
        let start_zone = fd.points[(b.start + 2).min(b.end - 1)].tau;
        if first.tau <= start_zone * (1.0 + 1e-12) {
            // past the last miss inside the start zone
            let last_in_zone = misses
                .iter()
                .filter(|m| m.tau <= start_zone * (1.0 + 1e-12))
                .map(|m| m.tau)
                .fold(first.tau, f64::max);
            b.start = pos_from(last_in_zone * (1.0 + 1e-12));
        } else {
            let cut = Bounds {
                end: pos_from(first.tau * (1.0 - 1e-12)),
                long_cut: true,
                ..b
            };
            // or a short-τ feature: the data above the model from the first miss on, for at
            // most SHORT_FEATURE_SPAN, ending before N_READING_TAU
            let feature: Vec<&Miss> = misses
                .iter()
                .take_while(|m| m.tau <= first.tau * SHORT_FEATURE_SPAN)
                .collect();
            let feature_end = feature.iter().map(|m| m.tau).fold(first.tau, f64::max);
            let past = pos_from(feature_end * (1.0 + 1e-12));
            if feature.iter().all(|m| m.above)
                && past < b.end
                && fd.points[past].tau <= N_READING_TAU
            {
                let ended = declare_from(data, fd, valid, cfg, cut);
                let moved = Bounds {
                    start: past,
                    feature: true,
                    ..b
                };
                let moved = declare_from(data, fd, valid, cfg, moved);
                let keeps_n = moved
                    .1
                    .range()
                    .is_some_and(|(lo, hi)| lo <= N_READING_TAU && hi >= N_READING_TAU);
                return if keeps_n
                    && declared_decades(&moved) > declared_decades(&ended) + SHORT_FEATURE_GAIN
                {
                    moved
                } else {
                    ended
                };
            }
            b = cut;
        }
        last_fit = Some(f);
    }
}

/// A curve point the fitted model misses (beyond [`FIT_TOL`] and its own 95 % band).
#[derive(Clone, Copy, Debug)]
struct Miss {
    /// τ, s.
    tau: f64,
    /// |model/data − 1| in Allan deviation.
    size: f64,
    /// The data lie above the model.
    above: bool,
}

/// A fit with its check: the misses in ascending τ and the largest misfit.
type Checked = (fit::FitResult, Vec<Miss>, f64);

/// Fits positions `start..end` of `fd` and checks every curve point of that τ range: returns
/// the fit, the misses in ascending τ and the largest misfit.
fn fit_and_check(
    data: &CurveData,
    fd: &fit::FitData,
    valid: &[&CurvePoint],
    cfg: &Config,
    start: usize,
    end: usize,
) -> Option<Checked> {
    let n_phase = data.n.map(|n| n + 1);
    let used: Vec<usize> = (start..end).collect();
    let f = fit::fit(fd, &used, &cfg.fit)?;
    let (lo_t, hi_t) = (fd.points[start].tau, fd.points[end - 1].tau);
    let in_range = |t: f64| t >= lo_t * (1.0 - 1e-12) && t <= hi_t * (1.0 + 1e-12);
    let mut misses: Vec<Miss> = Vec::new();
    let mut max_mis: f64 = 0.0;
    let level = check_level(data.kind, valid.iter().filter(|p| in_range(p.tau)).count());
    for p in valid.iter().filter(|p| in_range(p.tau)) {
        let model = f.predict(p.tau);
        let mis = if model > 0.0 {
            (model / p.avar).sqrt() - 1.0
        } else {
            -1.0
        };
        max_mis = max_mis.max(mis.abs());
        let alpha = fit::TERM_ALPHA[fit::dominant_term(&f.coef, &f.shapes, p.tau)];
        // the model within the data's 95 % interval: model/data ∈ [lo, hi]
        let band = n_phase
            .and_then(|np| edf::greenhall_edf(alpha, p.m, np, data.kind))
            .and_then(|nu| ci::chi2_interval(1.0, nu, level))
            .map(|(lo, hi)| if mis > 0.0 { hi - 1.0 } else { 1.0 - lo })
            .unwrap_or(0.0);
        if model <= 0.0 || mis.abs() > FIT_TOL.max(band) {
            misses.push(Miss {
                tau: p.tau,
                size: mis.abs(),
                above: mis < 0.0,
            });
        }
    }
    Some((f, misses, max_mis))
}

/// The level of each point's band in the range check of `points` points of a curve of
/// estimator `kind`. Overlapping estimates at neighbouring τ of the fit grid share most of
/// their second differences, so the grid's points miss their 95 % bands together or not at
/// all, and the per-point band is the curve's. Non-overlapping estimates (kalibr_allan's
/// `sig2`, allan_variance_ros) at different τ share far less (see [`avar_cov`]): nearly
/// independent, about one point in twenty misses its 95 % band by chance, and a range check
/// at 95 % per point cuts a clean record's curve (issue 18.10: allan_variance_ros' curve of
/// white noise and random walk cut at 4.5 s). For them the band is simultaneous over the
/// points checked (Šidák: 0.95^(1/points) each).
fn check_level(kind: Overlap, points: usize) -> f64 {
    match kind {
        Overlap::Overlapping => 0.95,
        Overlap::Normal => 0.95f64.powf(1.0 / points.max(1) as f64),
    }
}

/// The largest value of term `j` the fitted points allow on their own (the curve's upper
/// 95 % band, [`region::upper_bound`]): the upper bound of a term the fit left at zero whose
/// interval says nothing (0 or ∞).
fn data_bound(j: usize, f: &fit::FitResult, fd: &fit::FitData, curve: &[Point]) -> f64 {
    let used = f
        .used
        .iter()
        .filter_map(|&i| curve.iter().find(|c| c.m == fd.points[i].m));
    region::upper_bound(used, |tau| fit::basis_at(j, tau, &f.shapes).sqrt())
}

/// The variance each coefficient takes from the resonances' bandwidths: the PSD measures a
/// bandwidth with a standard error ([`psd::Line::bandwidth_se`]), and the fit takes the
/// resonance's shape as known — its flat low-frequency part is white noise at long τ, and
/// the share of the curve's white level the model gives it (rather than N) scales with the
/// bandwidth (issue 17's vibration profile: a 45 Hz, 1 Hz wide gyro resonance holds a
/// third of the long-τ white level). Each line's bandwidth moved by ±1 standard error, the
/// range refitted: half the coefficients' change, squared, summed over the lines (a term
/// the refit selects differently takes nothing from it).
fn line_shape_variance(
    f: &fit::FitResult,
    fd: &fit::FitData,
    cfg: &Config,
) -> [f64; fit::TERM_COUNT] {
    let mut var = [0.0; fit::TERM_COUNT];
    if fd.basis.is_none() {
        return var;
    }
    for s in 0..fit::LINE_SLOTS {
        let Some(l) = fd.lines[s] else { continue };
        if !(fit::is_positive(l.bandwidth) && fit::is_positive(l.bandwidth_se)) {
            continue;
        }
        let refit = |bw: f64| {
            let mut d = fd.clone();
            if let Some(x) = d.lines[s].as_mut() {
                x.bandwidth = bw;
            }
            fit::fit(&d, &f.used, &cfg.fit)
        };
        let se = l.bandwidth_se.min(0.5 * l.bandwidth);
        let (Some(up), Some(dn)) = (refit(l.bandwidth + se), refit(l.bandwidth - se)) else {
            continue;
        };
        for (j, v) in var.iter_mut().enumerate() {
            if up.left_out[j] == f.left_out[j] && dn.left_out[j] == f.left_out[j] {
                let d = 0.5 * (up.coef[j] - dn.coef[j]);
                *v += d * d;
            }
        }
    }
    var
}

fn make_terms(f: &fit::FitResult, fd: &fit::FitData, curve: &[Point], cfg: &Config) -> Terms {
    let z = z_of(cfg.term_confidence);
    let have_stats = fd.basis.is_some();
    // the measured floor of the fitted range, for B's verdict (see [`B_FLOOR_TOL`])
    let floor = curve
        .iter()
        .filter(|p| p.in_range)
        .map(|p| p.adev)
        .fold(f64::INFINITY, f64::min);
    let floor_shown = |b: f64| (region::B_FLOOR_FACTOR * b / floor - 1.0).abs() <= B_FLOOR_TOL;
    let shape_var = line_shape_variance(f, fd, cfg);
    let one = |j: usize| -> Term {
        if !cfg.fit.terms[j] {
            return Term::not_fitted();
        }
        let c = f.coef[j];
        let se_c = f.cov[j][j].max(0.0).sqrt();
        let nan_if = |v: f64| if have_stats { v } else { f64::NAN };
        if j == fit::GM && (f.left_out[j] || c <= 0.0) {
            // a bump the data do not ask for: not part of the model (no bound: no time)
            return Term::not_fitted();
        }
        if f.left_out[j] || c <= 0.0 {
            // left out by the selection, at its bound, or the 1/τ² coefficient negative
            // (the low-pass correction, not a quantization): 0 with the upper bound
            let mut hi = if f.left_out[j] {
                (f.left_out_coef[j] + z * se_c).sqrt()
            } else {
                fit::inverted_interval(fd, f, &cfg.fit, j, z)
                    .1
                    .max(0.0)
                    .sqrt()
            };
            if !(hi > 0.0 && hi.is_finite()) {
                // The fit's own error says nothing here (a term left out where the full fit
                // had it at its bound has no standard error; an interval the data do not
                // close is ∞): bound the term by the curve itself, never "< 0".
                hi = data_bound(j, f, fd, curve);
            }
            return Term {
                value: 0.0,
                std_err: f64::NAN,
                lo: nan_if(0.0),
                hi: nan_if(hi),
                verdict: Verdict::NotSignificant,
            };
        }
        let value = c.sqrt();
        let std_err = nan_if((se_c * se_c + shape_var[j]).sqrt() / (2.0 * value));
        let (mut lo_c, mut hi_c) = fit::inverted_interval(fd, f, &cfg.fit, j, z);
        // spanning the shapes of the flicker floor the data do not reject
        for alt in &f.alternatives {
            lo_c = lo_c.min((alt.coef[j] - z * alt.std_err[j]).max(0.0));
            hi_c = hi_c.max(alt.coef[j] + z * alt.std_err[j]);
        }
        // and the resonances' bandwidths the PSD measured, in quadrature
        let spread = z * shape_var[j].sqrt();
        if fit::is_positive(spread) {
            lo_c = (c - (c - lo_c).hypot(spread)).max(0.0);
            hi_c = c + (hi_c - c).hypot(spread);
        }
        let dominant_somewhere = f.max_share[j] >= RESOLVED_SHARE && (j != 2 || floor_shown(value));
        let verdict = if !have_stats {
            // no sample count: no interval, so nothing is "resolved" statistically; a term the
            // model needs and that dominates somewhere is still the model's
            if dominant_somewhere {
                Verdict::NeverDominant
            } else {
                Verdict::NotSignificant
            }
        } else if !fit::is_positive(lo_c) || f.ambiguous[j] {
            Verdict::NotSignificant
        } else if !dominant_somewhere {
            Verdict::NeverDominant
        } else {
            Verdict::Resolved
        };
        Term {
            value,
            std_err,
            lo: nan_if(lo_c.sqrt()),
            hi: nan_if(hi_c.sqrt()),
            verdict,
        }
    };
    // The whole record's say (issue 17): every curve point bounds every term (its Allan
    // deviation is at most the point's upper 95 % band), the points the range left out too;
    // and a term that pushes the model up at long τ (B, K, R, a Gauss–Markov bias) is not
    // resolved where the model then rises above the upper band of a point beyond the range
    // and the term's own share is what lifts it there (a K fitted to the shoulder of a line,
    // or to a bend the range cut, whose +½ line the long-τ curve does not follow).
    let range_end = f.used.last().map_or(f64::INFINITY, |&i| fd.points[i].tau);
    let long_cut = f.used.last().is_some_and(|&i| i + 1 < fd.points.len());
    let record_bound =
        |j: usize| region::upper_bound(curve.iter(), |tau| fit::basis_at(j, tau, &f.shapes).sqrt());
    let contradicted = |j: usize| {
        curve
            .iter()
            .filter(|p| p.tau > range_end * (1.0 + 1e-12) && p.hi95.is_finite())
            .any(|p| {
                let model = f.predict(p.tau);
                let over = model - p.hi95 * p.hi95;
                over > 0.0 && f.coef[j] * fit::basis_at(j, p.tau, &f.shapes) >= over
            })
    };
    let bounded = |j: usize, mut t: Term| -> Term {
        if !have_stats || matches!(t.verdict, Verdict::NotFitted) || j == 0 {
            return t;
        }
        let bound = record_bound(j);
        let pushes_long = matches!(j, 2 | 3 | 4 | fit::GM);
        // (a resolved value above the curve's bound stays resolved here — one point's band
        // of many is below the truth by chance often enough — and the yaml files take the
        // bound instead, [`imu::ImuAnalysis::sensor_value`])
        if t.verdict == Verdict::Resolved && pushes_long && contradicted(j) {
            t.verdict = Verdict::Contradicted;
        }
        if t.verdict != Verdict::Resolved && bound.is_finite() && (long_cut || !t.hi.is_finite()) {
            // an unresolved term where the long end was cut: the fit's own interval speaks for
            // the range only, the bound is the whole curve's. (Elsewhere the fit's inverted
            // interval is the 95 % statement: the minimum of many points' 95 % bands is below
            // the truth far more often than one in twenty — issue 18.5 — so it is not taken
            // here; the yaml files never write more than it, [`imu::ImuAnalysis::random_walk`].)
            t.hi = bound;
            t.lo = t.lo.min(t.hi);
        }
        t
    };
    Terms {
        q: one(0),
        n: bounded(1, one(1)),
        b: bounded(2, one(2)),
        k: bounded(3, one(3)),
        r: bounded(4, one(4)),
        g: bounded(fit::GM, one(fit::GM)),
        g_time: f.shapes.gm_t,
        b_corner: f.shapes.b_lo,
        lines: std::array::from_fn(|k| {
            f.shapes.lines[k].map(|l| LineTerm {
                frequency: l.frequency,
                bandwidth: l.bandwidth,
                amplitude: f.coef[fit::LINE0 + k].max(0.0).sqrt(),
                psd_amplitude: l.psd_amp2.sqrt(),
            })
        }),
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
                false_k += (a.terms.k.verdict == Verdict::Resolved) as usize;
            }
            println!("n={n}: K reported on white noise in {false_k}/{trials}");
            assert!(
                (false_k as f64) <= MAX_FALSE_K_RATE * trials as f64,
                "n={n}: K reported in {false_k}/{trials} white series, tol {MAX_FALSE_K_RATE}"
            );
        }
    }

    /// The white level survives what the rules take out or skip: the share a left-out Q or a
    /// skipped bump's tail still has where the fit starts (a few percent), not more.
    const N_WHITE_TOL: f64 = 0.03;
    /// A noisy tail moves B's value by far less than the issue's 20 % for B.
    const B_SAME_TOL: f64 = 0.2;

    /// An exact-model curve of `n` samples at `tau0` on a 1.25-geometric m grid up to n/2.3
    /// (imu_utils' longest τ), as `--curves` delivers it; `avar(τ)` gives the values.
    fn exact_curve(n: usize, tau0: f64, avar: impl Fn(f64) -> f64) -> CurveData {
        let mut ms = Vec::new();
        let mut m = 1.0f64;
        while (m as usize) <= (n as f64 / 2.3) as usize {
            let k = m.round() as usize;
            if ms.last() != Some(&k) {
                ms.push(k);
            }
            m *= 1.25;
        }
        CurveData {
            psd: None,
            lines: Vec::new(),
            tau0,
            n: Some(n),
            kind: Overlap::Overlapping,
            points: ms
                .into_iter()
                .map(|m| {
                    let tau = m as f64 * tau0;
                    CurvePoint {
                        m,
                        tau,
                        avar: avar(tau),
                        id: None,
                        id_method: IdMethod::None,
                    }
                })
                .collect(),
        }
    }

    fn analyse_exact(c: &CurveData) -> Analysis {
        let cfg = Config::default();
        let basis = c.basis(cfg.fit.per_octave);
        analyse_curve(c, &cfg, basis.as_ref())
    }

    /// The floor the verdict compares 0.664·B with: the lowest curve point of the range.
    fn range_floor(a: &Analysis) -> f64 {
        a.curve
            .iter()
            .filter(|p| p.in_range)
            .map(|p| p.adev)
            .fold(f64::INFINITY, f64::min)
    }

    /// A B-dominated floor is resolved; the same curve whose last, noisiest points fall (the
    /// "falling tail" of a few clusters, kalibr_allan#64, seen on real imu_utils curves) has
    /// a floor below 0.664·B by more than [`B_FLOOR_TOL`]: B is no longer called resolved,
    /// though the model and its value barely move.
    #[test]
    fn a_bias_instability_is_resolved_only_where_the_curve_shows_its_floor() {
        let (n, tau0) = (2_400_000, 0.005);
        let (nn, b, k) = (7.6e-4f64, 2.5e-4f64, 2e-6f64);
        let model = |t: f64| nn * nn / t + fit::FLICKER_AVAR * b * b + k * k * t / 3.0;
        let clean = analyse_exact(&exact_curve(n, tau0, model));
        assert_eq!(
            clean.terms.b.verdict,
            Verdict::Resolved,
            "{}",
            clean.verdict
        );
        // the tail: the points beyond T/4 fall to 40 % of the model (within their 95 % band)
        let t_end = n as f64 * tau0;
        let tail = |t: f64| model(t) * if t > t_end / 4.0 { 0.16 } else { 1.0 };
        let dipped = analyse_exact(&exact_curve(n, tau0, tail));
        assert!(dipped.verdict.fits(), "{}", dipped.verdict);
        let floor = range_floor(&dipped);
        let ratio = region::B_FLOOR_FACTOR * dipped.terms.b.value / floor;
        assert!(
            ratio > 1.0 + B_FLOOR_TOL,
            "the tail sets the floor: {ratio}"
        );
        assert_eq!(dipped.terms.b.verdict, Verdict::NeverDominant);
        assert!(
            (dipped.terms.b.value / b - 1.0).abs() < B_SAME_TOL,
            "{}",
            dipped.terms.b.value
        );
    }

    /// A τ⁻² excess over the white-noise line that never comes near the curve (the short-τ
    /// bend of a sensor's chain, or a quantization too small to read) is not fitted as Q:
    /// N is then the white-noise level the −½ line shows, not that level minus Q's share.
    #[test]
    fn a_quantization_that_never_dominates_is_left_out_of_the_model() {
        let (n, tau0) = (2_400_000, 0.0025);
        let (nn, q) = (5.0e-5f64, 1.0e-6f64);
        // Q's share of the AVAR at τ0: 3Q²/τ0² / (that + N²/τ0) ≈ 0.3, below 0.64
        let model = |t: f64| 3.0 * q * q / (t * t) + nn * nn / t + 1e-9 * t;
        let a = analyse_exact(&exact_curve(n, tau0, model));
        assert!(a.verdict.fits(), "{}", a.verdict);
        assert_eq!(a.terms.q.value, 0.0, "Q left out");
        assert!(
            a.terms.q.hi >= q,
            "with an upper bound above the Q the data show"
        );
        // N: the white level, within the share Q still has where the fit starts
        assert!(
            (a.terms.n.value / nn - 1.0).abs() < N_WHITE_TOL,
            "{}",
            a.terms.n.value
        );
    }

    /// White noise N and random walk K with a ±4 % log-periodic ripple: a real curve's misfit
    /// everywhere, so that a bump is not trimmed as a statistical outlier at the start but
    /// met as a miss mid-range.
    fn rippled(nn: f64, k: f64, t: f64) -> f64 {
        (nn * nn / t + k * k * t / 3.0) * (1.0 + 0.04 * (4.0 * t.ln()).sin())
    }

    /// Allan variance of a sinusoid of amplitude `amp` at `f0` Hz: A²·sin⁴(πf₀τ)/(πf₀τ)².
    fn line_avar(amp: f64, f0: f64, t: f64) -> f64 {
        let x = std::f64::consts::PI * f0 * t;
        amp * amp * x.sin().powi(4) / (x * x)
    }

    /// A vibration line at 10 Hz puts an Allan bump (AVAR of a sinusoid of amplitude A:
    /// A²·sin⁴(πf₀τ)/(πf₀τ)²) above the white-noise line between the start and the white
    /// region, as on a real MicroStrain GX4 accelerometer's curve. The fit starts past it
    /// instead of ending before it (which left no reliable fit): a range with τ = 1 s over
    /// three decades, N the white level.
    #[test]
    fn a_short_tau_bump_moves_the_start_past_it() {
        let (n, tau0) = (2_900_000, 0.002);
        let (nn, k, amp, f0) = (8e-4f64, 2e-5f64, 4e-3f64, 10.0f64);
        let model = |t: f64| rippled(nn, k, t) + line_avar(amp, f0, t);
        let a = analyse_exact(&exact_curve(n, tau0, model));
        let (lo, hi) = a.verdict.range().expect("a fit past the bump");
        assert!(lo > 0.05 && lo < 1.0 && hi / lo > 1e3, "{}", a.verdict);
        assert!(
            (a.terms.n.value / nn - 1.0).abs() < N_WHITE_TOL,
            "{}",
            a.terms.n.value
        );
    }

    /// The same rippled curve with the bump where it is not a short-τ feature: a slow line
    /// (0.01 Hz, bump near 40 s, past τ = 1 s) or a dip below the white-noise line at short
    /// τ. The range then ends before the miss as it always did; the start never skips it.
    #[test]
    fn a_bump_past_one_second_or_a_dip_is_not_skipped_at_the_start() {
        let (n, tau0) = (2_900_000, 0.002);
        let (nn, k) = (8e-4f64, 2e-5f64);
        let slow = |t: f64| rippled(nn, k, t) + line_avar(1.5e-4, 0.01, t);
        let dip = |t: f64| rippled(nn, k, t) * (1.0 - 0.4 * (-(t / 0.05).ln().powi(2) / 0.3).exp());
        for (name, curve) in [("slow line", &slow as &dyn Fn(f64) -> f64), ("dip", &dip)] {
            let a = analyse_exact(&exact_curve(n, tau0, curve));
            assert!(
                !matches!(
                    a.verdict,
                    AxisVerdict::Fits {
                        short_feature: true,
                        ..
                    }
                ),
                "{name}: {}",
                a.verdict
            );
            if name == "slow line" {
                let (lo, hi) = a.verdict.range().expect("the range before the bump");
                let long_cut = matches!(a.verdict, AxisVerdict::Fits { long_cut: true, .. });
                assert!(lo < 0.1 && hi > 1.0 && long_cut, "{name}: {}", a.verdict);
            }
        }
    }

    /// A curve so precise (10⁹ samples) that a ±4 % ripple is far beyond its statistics:
    /// χ²/dof in the thousands is never a plain "model fits" (issue 18, item 4).
    #[test]
    fn issue18_4_no_fits_label_at_a_chi2_in_the_thousands() {
        let (n, tau0) = (1_000_000_000, 0.005);
        let (nn, k) = (8e-4f64, 2e-5f64);
        let a = analyse_exact(&exact_curve(n, tau0, |t| rippled(nn, k, t)));
        let f = a.fit.as_ref().expect("a fit");
        assert!(f.chi2_per_dof > APPROX_CHI2, "χ²/dof {}", f.chi2_per_dof);
        assert!(
            matches!(
                a.verdict,
                AxisVerdict::Fits {
                    approximate: Some(_),
                    ..
                }
            ),
            "χ²/dof {}, δ {}: {}",
            f.chi2_per_dof,
            f.delta,
            a.verdict
        );
    }

    #[test]
    fn constant_series_gives_zero_curve_and_no_terms() {
        let a = analyse(&[2.5; 1000], 0.01, &Config::default()).unwrap();
        assert!(a.curve.is_empty() || a.curve.iter().all(|p| p.avar == 0.0));
        assert!(a.terms.as_array().iter().all(|t| t.reported().is_none()));
    }
}
