//! Recording-length advice (users ask exactly this: imu_utils#18, kalibr_allan#30): how
//! precise each figure of this record is, and how long a record gives the random walk K and
//! the bias instability B to ±10 % and ±25 % at 95 %.
//!
//! The precision of a term is the relative half-width of its 95 % interval,
//! z·se(T)/T with se from the fit's covariance (delta method from its coefficient, the
//! expected rather than the realised interval, so that the advice does not jump with the
//! noise of one record). It improves as 1/√(record length): exactly so for K on white noise
//! plus a random walk (the Cramér–Rao bound se(K)/K ≈ √(2N/(K·T)), module docs of
//! [`super`]), and for a flicker floor B, whose information grows with the number of
//! independent clusters in the floor. So a precision p of this record T becomes x after
//! T·(p/x)². A term the record does not resolve has no precision; its 95 % upper bound says
//! how small it is, and that a longer record is needed to see it at all. For K that bound
//! still answers "how long?": by the Cramér–Rao bound a K at its upper bound K⁺ would need
//! T_x = 2·N·z²/(K⁺·x²) for ±x, a smaller K longer (and every other term only adds to the
//! record needed), so T_x — and at least this record — is a lower bound, marked as such.

use super::{Analysis, Term, Verdict};

/// The two precision targets of the advice (relative, 95 %).
pub const TARGETS: [f64; 2] = [0.10, 0.25];

/// Advice on one term.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TermAdvice {
    /// Relative half-width of the 95 % interval of this record (NaN when not resolved).
    pub precision: f64,
    /// Record length (s) for ±10 % at 95 % (NaN when not resolved).
    pub record_10: f64,
    /// Record length (s) for ±25 % at 95 %.
    pub record_25: f64,
    /// The records are lower bounds (a term not resolved, from its 95 % upper bound).
    pub at_least: bool,
}

impl TermAdvice {
    fn none() -> TermAdvice {
        TermAdvice {
            precision: f64::NAN,
            record_10: f64::NAN,
            record_25: f64::NAN,
            at_least: false,
        }
    }
}

/// Advice for one axis.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Advice {
    /// This record's length, s.
    pub record: f64,
    /// White noise N.
    pub n: TermAdvice,
    /// Bias instability B.
    pub b: TermAdvice,
    /// Random walk K.
    pub k: TermAdvice,
}

/// The z of the 95 % intervals.
const Z95: f64 = 1.959_963_984_540_054;

/// Advice for a term of a record of `record` seconds: from its standard error where the fit
/// resolves it; for an IEEE 952 region reading (a value the report prints) from its own
/// 95 % interval's relative half-width, so that the advice never calls a printed value "not
/// resolved".
fn term_advice(t: &Term, record: f64) -> TermAdvice {
    if !super::fit::is_positive(t.value) {
        return TermAdvice::none();
    }
    let p = match t.verdict {
        Verdict::Resolved if t.std_err.is_finite() => Z95 * t.std_err / t.value,
        Verdict::RegionReading if t.lo.is_finite() && t.hi.is_finite() => {
            0.5 * (t.hi - t.lo) / t.value
        }
        _ => return TermAdvice::none(),
    };
    let needed = |x: f64| record * (p / x).powi(2);
    TermAdvice {
        precision: p,
        record_10: needed(TARGETS[0]),
        record_25: needed(TARGETS[1]),
        at_least: false,
    }
}

/// For a K the record does not resolve: the record it needs at least, from its 95 % upper
/// bound and the white noise N (module docs); none without both.
fn k_at_least(k: &Term, n: &Term, record: f64) -> TermAdvice {
    let fine = |v: f64| super::fit::is_positive(v) && v.is_finite();
    if k.verdict == Verdict::Resolved || !fine(k.hi) || !fine(n.value) {
        return TermAdvice::none();
    }
    let needed = |x: f64| (2.0 * n.value * Z95 * Z95 / (k.hi * x * x)).max(record);
    TermAdvice {
        precision: f64::NAN,
        record_10: needed(TARGETS[0]),
        record_25: needed(TARGETS[1]),
        at_least: true,
    }
}

/// The advice for an analysed axis (None without a sample count: no precision known).
pub fn advise(a: &Analysis) -> Option<Advice> {
    let n = a.n?;
    let record = n as f64 * a.tau0;
    Some(Advice {
        record,
        n: term_advice(&a.terms.n, record),
        b: term_advice(&a.terms.b, record),
        k: match term_advice(&a.terms.k, record) {
            t if t.precision.is_finite() => t,
            _ => k_at_least(&a.terms.k, &a.terms.n, record),
        },
    })
}

/// The analysis and its advice for a record of `record` seconds at `rate` Hz whose Allan
/// variance is exactly the model of white noise `n`, bias instability `b` and random walk `k`
/// (one axis, the points where this analysis puts them): what [`advise`] says of such a
/// record, by the very rule it applies to a measured one. `allan_kalibr plan` asks this, so
/// that a plan and the advice of the analysis of a record of that sensor agree.
pub(crate) fn expected(
    n: f64,
    b: f64,
    k: f64,
    rate: f64,
    record: f64,
) -> (Analysis, Option<Advice>) {
    use super::model::basis;
    use super::term::NoiseTerm;
    use super::{CurveData, CurvePoint, IdMethod, Overlap};
    let cfg = super::Config::default();
    let tau0 = 1.0 / rate;
    let samples = (record * rate).round().max(3.0) as usize;
    let points = cfg
        .grid
        .cluster_sizes(samples)
        .into_iter()
        .map(|m| {
            let tau = m as f64 * tau0;
            CurvePoint {
                m,
                tau,
                avar: n * n * basis(NoiseTerm::WhiteNoise, tau)
                    + b * b * basis(NoiseTerm::BiasInstability, tau)
                    + k * k * basis(NoiseTerm::RandomWalk, tau),
                id: None,
                id_method: IdMethod::None,
            }
        })
        .collect();
    let data = CurveData::from_points(tau0, Some(samples), Overlap::Overlapping, points);
    let basis = data.basis(cfg.fit.per_octave);
    let a = super::analyse_curve(&data, &cfg, basis.as_ref());
    let advice = advise(&a);
    (a, advice)
}

/// A duration in the unit that reads best (s, min, h, d).
pub(crate) fn duration_text(s: f64) -> String {
    if !s.is_finite() {
        return "-".into();
    }
    if s < 1.0 {
        // a second of data already gives that precision ("0 s" read as nothing)
        "< 1 s".into()
    } else if s < 120.0 {
        format!("{s:.0} s")
    } else if s < 7200.0 {
        format!("{:.0} min", s / 60.0)
    } else if s < 3.0 * 86400.0 {
        format!("{:.1} h", s / 3600.0)
    } else {
        format!("{:.1} d", s / 86400.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn term(value: f64, se: f64, verdict: Verdict) -> Term {
        Term {
            value,
            std_err: se,
            lo: value - 2.0 * se,
            hi: value + 2.0 * se,
            verdict,
        }
    }

    #[test]
    fn unresolved_k_gets_the_record_its_upper_bound_needs_at_least() {
        let n = term(0.01, 1e-5, Verdict::Resolved);
        let k = Term {
            value: 0.0,
            std_err: f64::NAN,
            lo: 0.0,
            hi: 1e-4,
            verdict: Verdict::NotSignificant,
        };
        // 2·N·z²/(K⁺·x²) with x = 25 %: 2·0.01·3.8415/(1e-4·0.0625) = 12 293 s
        let a = k_at_least(&k, &n, 3600.0);
        assert!(a.at_least && a.precision.is_nan());
        let want = 2.0 * 0.01 * Z95 * Z95 / (1e-4 * 0.0625);
        assert!((a.record_25 - want).abs() < 1e-6 * want, "{a:?}");
        assert!((a.record_10 - want * 6.25).abs() < 1e-6 * want * 6.25);
        // never less than the record that did not resolve it
        let long = k_at_least(&k, &n, 1e6);
        assert_eq!((long.record_10, long.record_25), (1e6, 1e6));
        // a resolved K, or no bound, gets nothing from here
        assert!(!k_at_least(&n, &n, 3600.0).at_least);
        assert!(
            !k_at_least(
                &Term {
                    hi: f64::INFINITY,
                    ..k
                },
                &n,
                3600.0
            )
            .at_least
        );
    }

    #[test]
    fn precision_scales_with_the_square_root_of_the_record() {
        // ±20 % of a 4 h record: ±10 % needs 4× the record, ±25 % 0.64×
        let t = term(1.0, 0.2 / Z95, Verdict::Resolved);
        let a = term_advice(&t, 14_400.0);
        assert!((a.precision - 0.2).abs() < 1e-12);
        assert!((a.record_10 - 4.0 * 14_400.0).abs() < 1e-6);
        assert!((a.record_25 - 0.64 * 14_400.0).abs() < 1e-6);
        let u = term_advice(&term(0.0, f64::NAN, Verdict::NotSignificant), 14_400.0);
        assert!(u.precision.is_nan() && u.record_10.is_nan());
        assert_eq!(duration_text(14_400.0), "4.0 h");
        assert_eq!(duration_text(90.0), "90 s");
        assert_eq!(duration_text(0.4), "< 1 s");
    }
}
