//! What the analysis finds for one axis: the analysed curve ([`Point`], its own module), the IEEE 952
//! terms with their intervals and verdicts ([`Terms`], [`Verdict`]), the verdict on the
//! axis ([`AxisVerdict`]), the fit's diagnostics ([`FitSummary`]), all in [`Analysis`].

use super::term::NoiseTerm;
#[cfg(doc)]
use super::{APPROX_DELTA, B_FLOOR_TOL, FIT_TOL, analyse};
use super::{Overlap, Point, fit, psd, region};

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
    /// 0.664·B within `B_FLOOR_TOL`. Its value leans on the model.
    NeverDominant,
    /// No reliable fit: the value is the IEEE 952 region reading, with its own interval.
    RegionReading,
    /// No reliable fit and no region for the term: only the 95 % upper bound is known.
    RegionBound,
    /// Fitted, but the whole record does not agree with it: its value (or its whole
    /// interval) lies above the 95 % bound the curve's points give it jointly. Only that
    /// bound is reported (value 0, interval [0, bound]).
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
    /// profile of the term under the joint fit (`fit::Profile`); 0 for a term not resolved,
    /// whose `hi` is then its one-sided upper bound. The value always lies inside. NaN
    /// without a sample count.
    pub lo: f64,
    /// Upper end of the interval (a term not resolved: its one-sided 95 % upper bound).
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

    pub(super) fn not_fitted() -> Term {
        Term {
            value: f64::NAN,
            std_err: f64::NAN,
            lo: f64::NAN,
            hi: f64::NAN,
            verdict: Verdict::NotFitted,
        }
    }

    pub(super) fn from_reading(r: Option<region::Reading>) -> Term {
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
    /// spectrum (0: IEEE 952's flat floor; see `model::flicker_band`). The floor is within
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
    /// Terms in the order Q, N, B, K, R ([`NoiseTerm::POWER_LAWS`]).
    pub fn as_array(&self) -> [Term; 5] {
        NoiseTerm::POWER_LAWS.map(|t| self.get(t).unwrap_or_else(Term::not_fitted))
    }

    /// The estimate of term `t` (None for a line: [`Terms::lines`]).
    pub fn get(&self, t: NoiseTerm) -> Option<Term> {
        match t {
            NoiseTerm::Quantization => Some(self.q),
            NoiseTerm::WhiteNoise => Some(self.n),
            NoiseTerm::BiasInstability => Some(self.b),
            NoiseTerm::RandomWalk => Some(self.k),
            NoiseTerm::Ramp => Some(self.r),
            NoiseTerm::GaussMarkov => Some(self.g),
            NoiseTerm::Line(_) => None,
        }
    }

    /// The terms `term` gives for Q, N, B, K, R and the Gauss–Markov σ, with its time
    /// `g_time`, the flicker floor's corner `b_corner` and the `lines`.
    pub(super) fn from_fn(
        mut term: impl FnMut(NoiseTerm) -> Term,
        g_time: f64,
        b_corner: f64,
        lines: [Option<LineTerm>; fit::LINE_SLOTS],
    ) -> Terms {
        Terms {
            q: term(NoiseTerm::Quantization),
            n: term(NoiseTerm::WhiteNoise),
            b: term(NoiseTerm::BiasInstability),
            k: term(NoiseTerm::RandomWalk),
            r: term(NoiseTerm::Ramp),
            g: term(NoiseTerm::GaussMarkov),
            g_time,
            b_corner,
            lines,
        }
    }
}

/// What the fit says about one axis.
#[derive(Clone, Debug, PartialEq)]
pub enum AxisVerdict {
    /// The model describes the curve over `range` (τ of the first and last fit point, s):
    /// every curve point there is within `FIT_TOL` or its own 95 % band of the model.
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
        /// (when above `APPROX_DELTA`: within `FIT_TOL` but the terms are approximate).
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
    pub fn fits(&self) -> bool {
        matches!(self, AxisVerdict::Fits { .. })
    }

    /// The declared range, when the model fits.
    pub fn range(&self) -> Option<(f64, f64)> {
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

/// A number in 3 significant digits, as the section's messages print it.
pub fn short(x: f64) -> String {
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
    /// Coefficients Q², N², B², K², R², σ_GM², the lines' A², indexed by [`NoiseTerm`] (Q² < 0:
    /// the low-pass correction).
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
    pub fn predict(&self, tau: f64) -> f64 {
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
    /// The largest N and K the whole record allows at 95 %, jointly over the points of the
    /// fit grid from the fitted range's start on (each point below its one-sided limit at
    /// 1 − 0.05/k, Bonferroni: see `region::upper_bound`); ∞ without a sample count.
    pub bounds: (f64, f64),
}
