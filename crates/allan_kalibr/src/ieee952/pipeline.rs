//! The analysis of one axis, step by step: the fit grid's data, the declared fit
//! ([`super::declare`]), the curve with its bounds, what the left-out short τ are, the region
//! readings, the terms ([`super::terms`]) and the fit's diagnostics.

use super::analysed_curve::curve_points;
use super::declare::declare_fit;
use super::term::NoiseTerm;
use super::terms::{make_terms, record_points, region_terms};
use super::{
    Analysis, AxisVerdict, Config, CovBasis, CurveData, CurvePoint, FIT_TOL, FitSummary,
    Ieee952Error, Point, fit, region,
};

/// Analyses one rate series y (unit U, sample period `tau0` s).
pub fn analyse(y: &[f64], tau0: f64, cfg: &Config) -> Result<Analysis, Ieee952Error> {
    let data = CurveData::from_samples(y, tau0, cfg)?;
    let basis = data.basis(cfg.fit.per_octave);
    Ok(analyse_curve(&data, cfg, basis.as_ref()))
}

/// Analyses a measured curve. `basis` is the statistical covariance of its fit grid
/// ([`CurveData::basis`]; shared by the axes of an IMU), `None` when the sample count is
/// unknown.
pub fn analyse_curve(data: &CurveData, cfg: &Config, basis: Option<&CovBasis>) -> Analysis {
    let valid: Vec<&CurvePoint> = data
        .points
        .iter()
        .filter(|p| p.avar > 0.0 && p.avar.is_finite())
        .collect();
    let fd = fit_data(data, cfg, &valid, basis);

    // the range and the fit, then the declared-fit check
    let start = fit::choose_start(&fd, &cfg.fit);
    let (fitted, mut verdict, max_misfit) = declare_fit(data, &fd, &valid, cfg, start);
    // the curve with its bounds
    let range = verdict.range();
    let band_model = fitted.as_ref().filter(|_| verdict.fits());
    let curve = curve_points(data, cfg, fitted.as_ref(), band_model, basis, range);
    if let Some(f) = &fitted {
        name_short_cut(&mut verdict, f, &curve);
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

    // the whole record's bounds are taken from where the curve is the model's at short τ
    // on: the fitted range's start, or without a fit where it starts to fall like white
    // noise (the band-limited points below lie under every term's line)
    let from_tau = range.map_or_else(|| fd.points.get(start).map_or(0.0, |p| p.tau), |(lo, _)| lo);
    let record = record_points(&curve, &fd, from_tau);
    let terms = match (&fitted, verdict.fits()) {
        (Some(f), true) => make_terms(f, &fd, &curve, &record, cfg),
        _ => region_terms(&region, &record),
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
        region::upper_bound(record.iter().copied(), |t| {
            fit::basis(NoiseTerm::WhiteNoise, t).sqrt()
        }),
        region::upper_bound(record.iter().copied(), |t| {
            fit::basis(NoiseTerm::RandomWalk, t).sqrt()
        }),
    );
    drop(record);
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

/// The fit's data: the `valid` points of the curve on the fit grid, where each sits on the
/// curve and in `basis` (kept only when it holds every point of the grid), and the lines
/// the model holds.
fn fit_data<'a>(
    data: &CurveData,
    cfg: &Config,
    valid: &[&CurvePoint],
    basis: Option<&'a CovBasis>,
) -> fit::FitData<'a> {
    let fit_ms = data.fit_ms(cfg.fit.per_octave);
    let basis = basis.filter(|b| fit_ms.iter().all(|m| b.ms().binary_search(m).is_ok()));
    fit::FitData {
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
        basis,
        basis_index: fit_ms
            .iter()
            .map(|m| basis.map_or(0, |b| b.ms().binary_search(m).unwrap_or(0)))
            .collect(),
        lines: data.model_lines(),
    }
}

/// What the left-out short τ of a declared fit `f` are, named from where those points lie
/// against the fitted white-noise line N/√τ (the model's N alone: a negative 1/τ²
/// low-pass correction bends the model under that line, and a point between the two is
/// below the white noise, not a bump over the model): below it beyond the larger of
/// [`FIT_TOL`] and the point's 95 % band, band-limited (the sensor's low-pass filter or
/// decimation); above it so, a bump (a vibration, a resonance); both, both; neither (every
/// left-out point within its band of the line), "its first points are out of line".
fn name_short_cut(verdict: &mut AxisVerdict, f: &fit::FitResult, curve: &[Point]) {
    let AxisVerdict::Fits {
        range,
        short_cut: true,
        short_feature,
        band_limited,
        ..
    } = verdict
    else {
        return;
    };
    let (mut above, mut below) = (false, false);
    for p in curve.iter().filter(|p| p.tau < range.0 * (1.0 - 1e-12)) {
        let n = NoiseTerm::WhiteNoise;
        let white = (f.coef[n] * fit::basis(n, p.tau)).max(0.0).sqrt();
        if !fit::is_positive(white) {
            continue;
        }
        // the line outside the point's band (its value alone without a sample count)
        let r = p.adev / white - 1.0;
        let lo = if p.lo95.is_finite() { p.lo95 } else { p.adev };
        let hi = if p.hi95.is_finite() { p.hi95 } else { p.adev };
        above |= r > FIT_TOL && white < lo;
        below |= r < -FIT_TOL && white > hi;
    }
    *short_feature = above;
    *band_limited = below;
}
