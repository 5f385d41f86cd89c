//! The IEEE 952 terms of a declared fit, each with its interval and verdict, and of an axis
//! without one (the region readings, each bounded by the whole curve).

use statrs::distribution::{ContinuousCDF, Normal};

use super::{
    B_FLOOR_TOL, Config, LineTerm, Point, RESOLVED_SHARE, Term, Terms, Verdict, fit, region,
};
#[cfg(doc)]
use super::{imu, psd};

/// The z of the two-sided interval at `confidence`.
fn z_of(confidence: f64) -> f64 {
    Normal::new(0.0, 1.0)
        .map(|d| d.inverse_cdf(0.5 + confidence / 2.0))
        .unwrap_or(1.96)
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

/// The terms of a fit the axis verdict declares: each term's value, its interval at
/// `cfg.term_confidence` and its verdict ([`TermsOfFit::fitted`]), then bounded by the whole
/// record ([`TermsOfFit::bounded`]).
pub(super) fn make_terms(
    f: &fit::FitResult,
    fd: &fit::FitData,
    curve: &[Point],
    cfg: &Config,
) -> Terms {
    let t = TermsOfFit {
        f,
        fd,
        curve,
        cfg,
        z: z_of(cfg.term_confidence),
        have_stats: fd.basis.is_some(),
        // the measured floor of the fitted range, for B's verdict (see [`B_FLOOR_TOL`])
        floor: curve
            .iter()
            .filter(|p| p.in_range)
            .map(|p| p.adev)
            .fold(f64::INFINITY, f64::min),
        shape_var: line_shape_variance(f, fd, cfg),
    };
    let term = |j: usize| t.bounded(j, t.fitted(j));
    Terms {
        q: t.fitted(0),
        n: term(1),
        b: term(2),
        k: term(3),
        r: term(4),
        g: term(fit::GM),
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

/// What the terms of one fit are made from.
struct TermsOfFit<'a> {
    f: &'a fit::FitResult,
    fd: &'a fit::FitData<'a>,
    curve: &'a [Point],
    cfg: &'a Config,
    /// The normal quantile of the terms' confidence.
    z: f64,
    /// The fit has a sample count (a statistical covariance): intervals and verdicts.
    have_stats: bool,
    floor: f64,
    shape_var: [f64; fit::TERM_COUNT],
}

impl TermsOfFit<'_> {
    /// Term `j` from the fit alone: its value, interval and verdict.
    fn fitted(&self, j: usize) -> Term {
        let TermsOfFit {
            f,
            fd,
            cfg,
            z,
            have_stats,
            floor,
            ref shape_var,
            ..
        } = *self;
        let floor_shown = |b: f64| (region::B_FLOOR_FACTOR * b / floor - 1.0).abs() <= B_FLOOR_TOL;
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
            return self.absent(j, se_c);
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
    }

    /// Term `j` the selection left out or the fit put at its bound (standard error `se_c`
    /// of its coefficient): 0 with its upper bound.
    fn absent(&self, j: usize, se_c: f64) -> Term {
        let TermsOfFit {
            f,
            fd,
            curve,
            cfg,
            z,
            have_stats,
            ..
        } = *self;
        let nan_if = |v: f64| if have_stats { v } else { f64::NAN };
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
        Term {
            value: 0.0,
            std_err: f64::NAN,
            lo: nan_if(0.0),
            hi: nan_if(hi),
            verdict: Verdict::NotSignificant,
        }
    }

    /// Term `j` bounded by the whole record's say (issue 17): every curve point bounds every
    /// term (its Allan deviation is at most the point's upper 95 % band), the points the
    /// range left out too;
    /// and a term that pushes the model up at long τ (B, K, R, a Gauss–Markov bias) is not
    /// resolved where the model then rises above the upper band of a point beyond the range
    /// and the term's own share is what lifts it there (a K fitted to the shoulder of a line,
    /// or to a bend the range cut, whose +½ line the long-τ curve does not follow).
    fn bounded(&self, j: usize, mut t: Term) -> Term {
        let TermsOfFit {
            f,
            fd,
            curve,
            have_stats,
            ..
        } = *self;
        let range_end = f.used.last().map_or(f64::INFINITY, |&i| fd.points[i].tau);
        let long_cut = f.used.last().is_some_and(|&i| i + 1 < fd.points.len());
        let record_bound = |j: usize| {
            region::upper_bound(curve.iter(), |tau| fit::basis_at(j, tau, &f.shapes).sqrt())
        };
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
    }
}

/// The terms of an axis without a reliable fit: N, B and K read from their regions, a
/// reading above what another point's upper band allows is that bound instead; the rest
/// not fitted.
pub(super) fn region_terms(region: &region::Readings, curve: &[Point]) -> Terms {
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
