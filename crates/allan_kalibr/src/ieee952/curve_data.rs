//! The measured curve the analysis starts from: its points (from the samples, or from
//! another tool's file), the samples' PSD and lines, and the fit grid's covariance basis.

use rayon::prelude::*;

use super::{
    Config, CovBasis, IdMethod, Ieee952Error, LINE_MIN_SHARE, Overlap, Phase, fit, line_check,
    noise_id, psd,
};

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

    /// The same curve with the PSD and the lines of its samples `y` (`psd`; a line near
    /// the PSD's lowest bins only where a sinusoid over the whole record confirms it,
    /// `line_check`).
    pub fn with_spectrum(mut self, y: &[f64]) -> Self {
        self.psd = psd::welch(y, 1.0 / self.tau0);
        self.lines = self
            .psd
            .as_ref()
            .map(|p| line_check::confirmed(y, p, psd::find_lines(p)))
            .unwrap_or_default();
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
    pub fn from_samples(y: &[f64], tau0: f64, cfg: &Config) -> Result<CurveData, Ieee952Error> {
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
        let valid = self.valid_ms();
        fit::thin_to_grid(&valid, per_octave)
            .into_iter()
            .map(|i| valid[i])
            .collect()
    }

    /// The statistical covariance basis of the fit grid, with the variance of every valid
    /// point of the curve (None without a sample count).
    pub fn basis(&self, per_octave: u32) -> Option<CovBasis> {
        let n = self.n?;
        Some(
            CovBasis::new(&self.fit_ms(per_octave), n, self.tau0, self.kind).with_points(
                &self.valid_ms(),
                n,
                self.tau0,
            ),
        )
    }

    /// Cluster sizes of the valid points (AVAR positive and finite), ascending.
    pub(crate) fn valid_ms(&self) -> Vec<usize> {
        self.points
            .iter()
            .filter(|p| p.avar > 0.0 && p.avar.is_finite())
            .map(|p| p.m)
            .collect()
    }
}

/// The settings' own checks: a positive finite τ0 and confidence levels in (0, 1).
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
