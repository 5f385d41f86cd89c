//! The analysed curve: each measured point with its EDF, its bounds and whether the declared
//! fit describes it (`pipeline` builds the axis's curve with it; `declare` each candidate
//! fit's, to judge the fit by the bands its own model gives).

use super::term::NoiseTerm;
use super::{AlphaSource, Config, CovBasis, CurveData, CurvePoint, Point, band, ci, fit};

/// The analysed curve: each valid point with its EDF and α ([`band`]: from `band_model`,
/// the fit declared, whose exact variance `basis` gives; without one, from the curve's
/// local slope), its bounds at `cfg.curve_confidence` and at 95 %, whether it is in the
/// declared `range`, and the model `fitted` there.
pub(super) fn curve_points(
    data: &CurveData,
    cfg: &Config,
    fitted: Option<&fit::FitResult>,
    band_model: Option<&fit::FitResult>,
    basis: Option<&CovBasis>,
    range: Option<(f64, f64)>,
) -> Vec<Point> {
    let valid: Vec<&CurvePoint> = data
        .points
        .iter()
        .filter(|p| p.avar > 0.0 && p.avar.is_finite())
        .collect();
    let slope = band::slope_alphas(&valid);
    valid
        .iter()
        .zip(slope)
        .map(|(p, slope_alpha)| {
            let from_model = band_model.zip(basis).and_then(|(f, b)| {
                let nu = band::model_edf(b, &f.coef, &f.shapes, p.m, p.tau)?;
                let dominant = fit::dominant_term(&f.coef, &f.shapes, p.tau);
                Some((
                    nu,
                    NoiseTerm::at(dominant).facts().alpha,
                    AlphaSource::Model,
                ))
            });
            let (nu, alpha, alpha_source) = from_model.unwrap_or_else(|| {
                let nu = data
                    .n
                    .and_then(|n| band::slope_edf(slope_alpha, p.m, n, data.kind))
                    .unwrap_or(f64::NAN);
                (nu, slope_alpha, AlphaSource::CurveSlope)
            });
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
                model: fitted.map_or(f64::NAN, |f| f.predict(p.tau).max(0.0).sqrt()),
            }
        })
        .collect()
}
