//! The IEEE 952 terms of a declared fit, each with its interval and verdict, and of an axis
//! without one (the region readings, each bounded by the whole curve).

use super::term::NoiseTerm::{
    self, BiasInstability, GaussMarkov, Quantization, Ramp, RandomWalk, WhiteNoise,
};
use super::{
    B_FLOOR_TOL, Config, LineTerm, Point, RESOLVED_SHARE, Term, Terms, Verdict, fit, region,
};
#[cfg(doc)]
use super::{imu, psd};
use statrs::distribution::{ChiSquared, ContinuousCDF};

/// The χ²(1) levels of a term's two-sided interval at `confidence` and of its one-sided
/// upper bound at the same confidence ([`fit::TWO_SIDED_95`], [`fit::ONE_SIDED_95`] at 95 %).
fn levels(confidence: f64) -> (f64, f64) {
    let q = |p: f64| ChiSquared::new(1.0).ok().map(|c| c.inverse_cdf(p));
    (
        q(confidence).unwrap_or(fit::TWO_SIDED_95),
        q(2.0 * confidence - 1.0).unwrap_or(fit::ONE_SIDED_95),
    )
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
/// `cfg.term_confidence` and its verdict ([`TermsOfFit::fitted`]: the profile of the
/// term, [`fit::Profile`]), then held against the whole record ([`TermsOfFit::bounded`]).
/// `record` are the curve points the whole-record bound is taken over (the fit grid from
/// the range's start on: the band-limited short τ lie below every term's line).
pub(super) fn make_terms(
    f: &fit::FitResult,
    fd: &fit::FitData,
    curve: &[Point],
    record: &[&Point],
    cfg: &Config,
) -> Terms {
    let have_stats = fd.basis.is_some();
    let t = TermsOfFit {
        f,
        fd,
        record,
        cfg,
        have_stats,
        // the measured floor of the fitted range, for B's verdict (see [`B_FLOOR_TOL`])
        floor: curve
            .iter()
            .filter(|p| p.in_range)
            .map(|p| p.adev)
            .fold(f64::INFINITY, f64::min),
        shape_var: line_shape_variance(f, fd, cfg),
        profile: if have_stats {
            fit::Profile::new(fd, f, &cfg.fit)
        } else {
            None
        },
        levels: levels(cfg.term_confidence),
        k_beyond: (have_stats && f.coef[GaussMarkov] > 0.0)
            .then(|| fit::Profile::beyond(fd, f, &cfg.fit, BEYOND_BUMP * f.shapes.gm_t))
            .flatten(),
    };
    // (Q is never held against the record: [`TermsOfFit::bounded`])
    Terms::from_fn(
        |j| t.bounded(j, t.fitted(j)),
        f.shapes.gm_t,
        f.shapes.b_lo,
        std::array::from_fn(|k| {
            f.shapes.lines[k].map(|l| LineTerm {
                frequency: l.frequency,
                bandwidth: l.bandwidth,
                amplitude: f.coef[NoiseTerm::Line(k)].max(0.0).sqrt(),
                psd_amplitude: l.psd_amp2.sqrt(),
            })
        }),
    )
}

/// The fit grid's curve points from `from_tau` on (the points a whole-record bound is
/// taken over, see [`make_terms`]).
pub(super) fn record_points<'c>(
    curve: &'c [Point],
    fd: &fit::FitData,
    from_tau: f64,
) -> Vec<&'c Point> {
    curve
        .iter()
        .filter(|p| p.tau >= from_tau * (1.0 - 1e-12))
        .filter(|p| fd.points.iter().any(|q| q.m == p.m))
        .collect()
}

/// What the terms of one fit are made from.
struct TermsOfFit<'a> {
    f: &'a fit::FitResult,
    fd: &'a fit::FitData<'a>,
    record: &'a [&'a Point],
    cfg: &'a Config,
    /// The fit has a sample count (a statistical covariance): intervals and verdicts.
    have_stats: bool,
    floor: f64,
    shape_var: [f64; fit::TERM_COUNT],
    /// The profile of the terms under the full model (None without statistics).
    profile: Option<fit::Profile<'a, 'a>>,
    /// The χ²(1) levels of the two-sided interval and the one-sided bound ([`levels`]).
    levels: (f64, f64),
    /// With a Gauss–Markov bias in the model: the profile on the points beyond its bump
    /// ([`BEYOND_BUMP`]), K's (None: too few points there, or no bump).
    k_beyond: Option<fit::Profile<'a, 'a>>,
}

/// With a Gauss–Markov bias of correlation time T in the model, K's interval comes from the
/// points from this many T on only: there the bias is white noise (its Allan variance within
/// 20 % of 2σ²T/τ, and its estimates' covariance that of white noise), so a random walk is
/// resolved only where the long end shows it beyond the bump. Below, the bias rises like a
/// random walk of 2σ²/T, decorrelating after T — the power laws' covariance the fit uses
/// there correlates its points far more than they are (0.6 against 0.4 and 0.4 against 0.0
/// between points an octave and a decade apart, Monte Carlo), and a K read there traded
/// with the bump's time (issue 40.4: a gyro K "resolved" at 6× the truth).
pub const BEYOND_BUMP: f64 = 8.0;

impl TermsOfFit<'_> {
    /// The whole record's 95 % upper bound of term `j` ([`region::upper_bound`] over
    /// `record`).
    fn record_bound(&self, j: NoiseTerm) -> f64 {
        let shapes = &self.f.shapes;
        region::upper_bound(self.record.iter().copied(), |tau| {
            fit::term_basis_at(j, tau, shapes).sqrt()
        })
    }

    /// The profile term `j`'s interval comes from: K beyond a bump where the model has one
    /// ([`BEYOND_BUMP`]), else the fit's range.
    fn chosen(&self, j: NoiseTerm) -> Option<&fit::Profile<'_, '_>> {
        if j == RandomWalk && self.f.coef[GaussMarkov] > 0.0 {
            self.k_beyond.as_ref()
        } else {
            self.profile.as_ref()
        }
        .filter(|p| p.has(j.index()))
    }

    /// The interval of term `j`'s coefficient at the χ²(1) `level` (two-sided 95 %, or the
    /// one-sided bound; the lower end only with `lower`, else 0): the profile, widened to
    /// span the flicker floor's plausible shapes ([`fit::FitResult::alternatives`]) and, in
    /// quadrature, the resonances' bandwidths, and always holding the fitted value.
    fn interval(&self, j: NoiseTerm, level: f64, lower: bool) -> (f64, f64) {
        let TermsOfFit { f, fd, cfg, .. } = *self;
        let z = level.sqrt();
        let c = f.coef[j].max(0.0);
        let se_c = f.cov[j][j].max(0.0).sqrt();
        let guess = if se_c.is_finite() && se_c > 0.0 {
            c + z * se_c
        } else {
            self.record_bound(j).powi(2)
        };
        let bump_k = j == RandomWalk && f.coef[GaussMarkov] > 0.0;
        let (mut lo_c, mut hi_c) = match self.chosen(j) {
            Some(p) if p.has(j.index()) => p.interval(j.index(), level, lower, guess),
            // too few points beyond the bump: K is not told from it; its bound is the
            // whole range's
            _ if bump_k => match &self.profile {
                Some(p) if p.has(j.index()) => (0.0, p.interval(j.index(), level, false, guess).1),
                _ => (0.0, self.record_bound(j).powi(2)),
            },
            _ => {
                let (l, h) = fit::inverted_interval(fd, f, &cfg.fit, j.index(), z);
                (if lower { l } else { 0.0 }, h)
            }
        };
        lo_c = lo_c.min(c);
        hi_c = hi_c.max(c);
        for alt in &f.alternatives {
            if lower {
                lo_c = lo_c.min((alt.coef[j] - z * alt.std_err[j]).max(0.0));
            }
            hi_c = hi_c.max(alt.coef[j] + z * alt.std_err[j]);
        }
        let spread = z * self.shape_var[j].sqrt();
        if fit::is_positive(spread) {
            if lower {
                lo_c = (c - (c - lo_c).hypot(spread)).max(0.0);
            }
            hi_c = c + (hi_c - c).hypot(spread);
        }
        (lo_c, hi_c)
    }

    /// Term `j` from the fit alone: its value, interval and verdict.
    fn fitted(&self, j: NoiseTerm) -> Term {
        let TermsOfFit {
            f,
            cfg,
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
        if j == GaussMarkov && (f.left_out[j] || c <= 0.0) {
            // a bump the data do not ask for: not part of the model (no bound: no time)
            return Term::not_fitted();
        }
        if f.left_out[j] || c <= 0.0 {
            return self.absent(j);
        }
        let value = c.sqrt();
        let std_err = nan_if((se_c * se_c + shape_var[j]).sqrt() / (2.0 * value));
        let dominant_somewhere =
            f.max_share[j] >= RESOLVED_SHARE && (j != BiasInstability || floor_shown(value));
        if !have_stats {
            // no sample count: no interval, so nothing is "resolved" statistically; a term the
            // model needs and that dominates somewhere is still the model's
            return Term {
                value,
                std_err,
                lo: f64::NAN,
                hi: f64::NAN,
                verdict: if dominant_somewhere {
                    Verdict::NeverDominant
                } else {
                    Verdict::NotSignificant
                },
            };
        }
        // zero within the two-sided level (or a bump explains the term as well): not
        // resolved, and only the one-sided bound is wanted
        let zero_allowed = f.ambiguous[j]
            || self
                .chosen(j)
                .is_some_and(|p| p.allows(j.index(), 0.0, self.levels.0));
        let (lo_c, hi_c) = if zero_allowed {
            (0.0, f64::NAN)
        } else {
            self.interval(j, self.levels.0, true)
        };
        let verdict = if !fit::is_positive(lo_c) || f.ambiguous[j] {
            Verdict::NotSignificant
        } else if !dominant_somewhere {
            Verdict::NeverDominant
        } else {
            Verdict::Resolved
        };
        let (lo_c, hi_c) = if verdict == Verdict::NotSignificant {
            // zero is in the interval (or a bump explains the term as well): its one-sided
            // 95 % upper bound
            self.interval(j, self.levels.1, false)
        } else {
            (lo_c, hi_c)
        };
        Term {
            value,
            std_err,
            lo: lo_c.sqrt(),
            hi: hi_c.sqrt(),
            verdict,
        }
    }

    /// Term `j` the selection left out or the fit put at its bound: 0 with its one-sided
    /// 95 % upper bound (the profile's; the whole record's where that says nothing).
    fn absent(&self, j: NoiseTerm) -> Term {
        if !self.have_stats {
            return Term {
                value: 0.0,
                std_err: f64::NAN,
                lo: f64::NAN,
                hi: f64::NAN,
                verdict: Verdict::NotSignificant,
            };
        }
        let mut hi = self.interval(j, self.levels.1, false).1.max(0.0).sqrt();
        if !(hi > 0.0 && hi.is_finite()) {
            // an interval the data do not close: bound the term by the curve itself
            hi = self.record_bound(j);
        }
        Term {
            value: 0.0,
            std_err: f64::NAN,
            lo: 0.0,
            hi,
            verdict: Verdict::NotSignificant,
        }
    }

    /// Term `j` held against the whole record: every curve point from the range's start
    /// bounds every term (its Allan deviation is at most the curve's), the points the range
    /// left out at the long end too ([`region::upper_bound`], jointly at 95 %). A resolved
    /// value above that bound is contradicted by the record (a K fitted to the shoulder of a
    /// line, or to a bend the range cut, whose +½ line the long-τ curve does not follow):
    /// not resolved, the record's bound instead. A bound the fit's profile leaves open is
    /// the record's.
    fn bounded(&self, j: NoiseTerm, mut t: Term) -> Term {
        if !self.have_stats || matches!(t.verdict, Verdict::NotFitted) || j == Quantization {
            return t;
        }
        let bound = self.record_bound(j);
        // only a term that lifts the long end can be contradicted by it: near the start of
        // a band-limited range the curve lies a little under the white-noise line (the
        // model's negative 1/τ² correction), so N's bound there is no bound
        let pushes_long = matches!(j, BiasInstability | RandomWalk | Ramp | GaussMarkov);
        // (a term the fit puts above the record's bound, resolved or with its whole interval)
        if pushes_long && (t.value > bound && t.verdict == Verdict::Resolved || t.lo >= bound) {
            return Term {
                value: 0.0,
                std_err: f64::NAN,
                lo: 0.0,
                hi: bound,
                verdict: Verdict::Contradicted,
            };
        }
        if pushes_long && t.verdict != Verdict::Resolved && bound < t.hi {
            // the fit's bound says less than the whole record's: the record's (both are
            // 95 % statements, each conservative — the profile's where its model is free
            // at the long end, the record's by Bonferroni — so the lesser keeps its level
            // in the coverage study; a value the record rules out is not shown)
            t.hi = bound;
            t.value = t.value.min(bound);
            t.lo = t.lo.min(bound);
        }
        t
    }
}

/// The terms of an axis without a reliable fit: N, B and K read from their regions, each
/// held against the whole record (`record`: the points from where the curve starts to fall
/// like white noise on, [`region::upper_bound`]) — a reading above that bound is the bound
/// instead; the rest not fitted.
pub(super) fn region_terms(region: &region::Readings, record: &[&Point]) -> Terms {
    let clamp = |j: NoiseTerm, t: Term| -> Term {
        let bound = region::upper_bound(record.iter().copied(), |tau| {
            fit::term_basis_at(j, tau, &fit::Shapes::FLAT).sqrt()
        });
        match t.verdict {
            Verdict::RegionReading if t.value > bound => Term {
                value: 0.0,
                std_err: f64::NAN,
                lo: 0.0,
                hi: bound,
                verdict: Verdict::RegionBound,
            },
            Verdict::RegionReading => Term {
                hi: t.hi.max(t.value),
                lo: t.lo.min(t.value),
                ..t
            },
            _ => t,
        }
    };
    Terms::from_fn(
        |j| match j {
            WhiteNoise => clamp(j, Term::from_reading(region.n)),
            BiasInstability => clamp(j, Term::from_reading(region.b)),
            RandomWalk => clamp(j, Term::from_reading(region.k)),
            _ => Term::not_fitted(),
        },
        f64::NAN,
        0.0,
        [None; fit::LINE_SLOTS],
    )
}
