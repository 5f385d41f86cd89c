//! The declared fit: the τ range over which the fitted model describes the curve (every
//! curve point within [`FIT_TOL`] or its own 95 % band), and the verdict on the axis that
//! follows from it ([`AxisVerdict`]).

use std::ops::ControlFlow;

#[cfg(doc)]
use super::avar_cov;
use super::{
    APPROX_CHI2, APPROX_DELTA, AxisVerdict, Config, CurveData, CurvePoint, FIT_TOL, MAX_MISS_SHARE,
    MIN_RANGE_DECADES, MISS_RUN_SPAN, N_READING_TAU, Overlap, SHORT_FEATURE_GAIN,
    SHORT_FEATURE_SPAN, Term, Verdict, analysed_curve, band, ci, fit, short, terms,
};

/// Chooses the fitted range and fits it: from `start` ([`fit::choose_start`]), then the
/// declared-fit check — every curve point of the range within the larger of [`FIT_TOL`] and
/// its 95 % band of the model. A miss among the first points of the range moves the start
/// past it; a miss further up ends the range before it (the long τ the model cannot
/// describe). Where that miss may instead be a short-τ feature — the data above the model
/// over at most [`SHORT_FEATURE_SPAN`], before [`N_READING_TAU`] — both are carried to the
/// end, and the start past the feature is kept only if its range still holds
/// [`N_READING_TAU`] and is wider by [`SHORT_FEATURE_GAIN`] decades. Fewer than
/// [`fit::MIN_FIT_POINTS`] points or less than [`MIN_RANGE_DECADES`] left: no reliable fit.
/// Returns the last fit, the verdict and the largest misfit.
pub(super) fn declare_fit(
    data: &CurveData,
    fd: &fit::FitData,
    valid: &[&CurvePoint],
    cfg: &Config,
    start: usize,
) -> Declared {
    let bounds = Bounds {
        start,
        end: fd.points.len(),
        long_cut: false,
        feature: false,
        last_miss: None,
    };
    declare_from(data, fd, valid, cfg, bounds)
}

/// The last fit, the verdict and the largest misfit.
pub(super) type Declared = (Option<fit::FitResult>, AxisVerdict, f64);

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
    let mut last_fit = None;
    loop {
        if b.end <= b.start || b.end - b.start < fit::MIN_FIT_POINTS {
            return (last_fit, too_few_points(&b), f64::NAN);
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
            return declare_clean(data, fd, valid, cfg, &b, f, max_mis);
        }
        match past_misses(data, fd, valid, cfg, b, &misses) {
            ControlFlow::Break(declared) => return declared,
            ControlFlow::Continue(next) => b = next,
        }
        last_fit = Some(f);
    }
}

/// The first position of the fit grid at or past `tau` (the grid's length when none is).
fn position_from(fd: &fit::FitData, tau: f64) -> usize {
    let np = fd.points.len();
    fd.points.iter().position(|p| p.tau >= tau).unwrap_or(np)
}

/// The verdict when too few points are left in `b`: the largest miss met, or the count.
fn too_few_points(b: &Bounds) -> AxisVerdict {
    let reason = match b.last_miss {
        Some((tau, mis)) => format!(
            "the best model misses the curve by {:.0} % at τ = {} s",
            100.0 * mis,
            short(tau)
        ),
        None => format!("only {} usable points", b.end.saturating_sub(b.start)),
    };
    AxisVerdict::NoReliableFit { reason }
}

/// The declared fit of a range `b` whose fit `f` (largest misfit `max_mis`) misses no
/// point: grown at the long end when it was cut there ([`extend_long_end`]), then a fit
/// if it spans [`MIN_RANGE_DECADES`].
fn declare_clean(
    data: &CurveData,
    fd: &fit::FitData,
    valid: &[&CurvePoint],
    cfg: &Config,
    b: &Bounds,
    f: fit::FitResult,
    max_mis: f64,
) -> Declared {
    let np = fd.points.len();
    let (f, max_mis, end) = if b.long_cut {
        extend_long_end(data, fd, valid, cfg, b.start, (f, max_mis, b.end))
    } else {
        (f, max_mis, b.end)
    };
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
        approximate: approximate(&f).then_some(f.delta),
    };
    (Some(f), verdict, max_mis)
}

/// The next candidate range after the fit of `b` missed `misses` (ascending τ): a miss in
/// the start zone moves the start past the last miss there; a miss further up cuts the end
/// before it — or, where it may be a short-τ feature, both ways are declared to the end and
/// the better returned ([`Break`](ControlFlow::Break)).
fn past_misses(
    data: &CurveData,
    fd: &fit::FitData,
    valid: &[&CurvePoint],
    cfg: &Config,
    mut b: Bounds,
    misses: &[Miss],
) -> ControlFlow<Declared, Bounds> {
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
        b.start = position_from(fd, last_in_zone * (1.0 + 1e-12));
        return ControlFlow::Continue(b);
    }
    let cut = Bounds {
        end: position_from(fd, first.tau * (1.0 - 1e-12)),
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
    let past = position_from(fd, feature_end * (1.0 + 1e-12));
    if feature.iter().all(|m| m.above) && past < b.end && fd.points[past].tau <= N_READING_TAU {
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
        return ControlFlow::Break(
            if keeps_n && declared_decades(&moved) > declared_decades(&ended) + SHORT_FEATURE_GAIN {
                moved
            } else {
                ended
            },
        );
    }
    ControlFlow::Continue(cut)
}

/// The level of the band beyond which a miss is never chance ([`by_chance`]): a stretch of
/// correlated points moves together, but a point outside its 99.9 % band is the model's.
const GROSS_LEVEL: f64 = 0.999;

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

/// The fitted range `start..end` of `accepted` (its fit, its largest misfit), after a cut at
/// the long end, grown again while the check holds — the first miss is where the model
/// stops following, not necessarily where the curve bends — and then past the first
/// point-wise miss to the longest extension the data accept jointly ([`fit::range_end`]).
fn extend_long_end(
    data: &CurveData,
    fd: &fit::FitData,
    valid: &[&CurvePoint],
    cfg: &Config,
    start: usize,
    accepted: (fit::FitResult, f64, usize),
) -> (fit::FitResult, f64, usize) {
    let np = fd.points.len();
    let (mut f, mut max_mis, mut end) = accepted;
    while end < np {
        match fit_and_check(data, fd, valid, cfg, start, end + 1) {
            Some((g, m, mm)) if m.is_empty() => {
                f = g;
                max_mis = mm;
                end += 1;
            }
            _ => break,
        }
    }
    // past the first point-wise miss: the longest extension the data accept
    // jointly (fit::range_end)
    let accepted_tau = fd.points[end - 1].tau * (1.0 + 1e-12);
    for e in (end + 1..=np).rev() {
        if let Some((g, m, mm)) = fit_and_check(data, fd, valid, cfg, start, e)
            && m.iter().all(|x| x.tau > accepted_tau)
            && fit::extension_agrees(fd, &f, &g, &cfg.fit)
        {
            // only the longest extension the test accepts is a candidate: a
            // shorter one would be a range chosen for the terms it gives
            if extension_is_honest(data, fd, cfg, &f, &g) {
                f = g;
                max_mis = mm;
                end = e;
            }
            break;
        }
    }
    (f, max_mis, end)
}

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
    let used: Vec<usize> = (start..end).collect();
    let f = fit::fit(fd, &used, &cfg.fit)?;
    let (lo_t, hi_t) = (fd.points[start].tau, fd.points[end - 1].tau);
    let in_range = |t: f64| t >= lo_t * (1.0 - 1e-12) && t <= hi_t * (1.0 + 1e-12);
    let mut misses: Vec<Miss> = Vec::new();
    let mut max_mis: f64 = 0.0;
    let count = valid.iter().filter(|p| in_range(p.tau)).count();
    let level = check_level(data.kind, count);
    // each point's state in τ order: None within its band, Some(above) a miss
    let mut states: Vec<(f64, Option<(bool, bool)>)> = Vec::with_capacity(count);
    for p in valid.iter().filter(|p| in_range(p.tau)) {
        let model = f.predict(p.tau);
        let mis = if model > 0.0 {
            (model / p.avar).sqrt() - 1.0
        } else {
            -1.0
        };
        max_mis = max_mis.max(mis.abs());
        // the model within the data's 95 % interval (the EDF its own mixture gives the
        // point, [`band`]): model/data ∈ [lo, hi]
        let nu = fd
            .basis
            .and_then(|b| band::model_edf(b, &f.coef, &f.shapes, p.m, p.tau));
        let band_at = |c: f64| {
            nu.and_then(|nu| ci::chi2_interval(1.0, nu, c))
                .map(|(lo, hi)| if mis > 0.0 { hi - 1.0 } else { 1.0 - lo })
                .unwrap_or(0.0)
        };
        if model <= 0.0 || mis.abs() > FIT_TOL.max(band_at(level)) {
            misses.push(Miss {
                tau: p.tau,
                size: mis.abs(),
                above: mis < 0.0,
            });
            let gross = model <= 0.0 || mis.abs() > FIT_TOL.max(band_at(GROSS_LEVEL));
            states.push((p.tau, Some((mis < 0.0, gross))));
        } else {
            states.push((p.tau, None));
        }
    }
    if by_chance(&states) {
        misses.clear();
    }
    Some((f, misses, max_mis))
}

/// Whether the misses among `states` (each curve point of a range in τ order: its τ and,
/// for a miss, whether the data lie above the model and whether it is gross) are what
/// chance gives a model that describes the curve: none beyond the point's
/// [`GROSS_LEVEL`] band, at most [`MAX_MISS_SHARE`] of the points, and no run of
/// consecutive misses on one side wider than [`MISS_RUN_SPAN`] in τ. Overlapping estimates
/// at neighbouring τ share most of their data, so a chance excursion of the curve takes a
/// stretch of points past their 95 % bands together (a clean 30-minute record's white
/// noise 10 % low over 10–16 s cut its fit at 7 s); a model that misses the curve does so
/// by more, over a wider stretch, or at many points.
fn by_chance(states: &[(f64, Option<(bool, bool)>)]) -> bool {
    let missed = states.iter().filter(|s| s.1.is_some()).count();
    if missed == 0 {
        return true;
    }
    if missed as f64 > MAX_MISS_SHARE * states.len() as f64
        || states.iter().any(|s| s.1.is_some_and(|m| m.1))
    {
        return false;
    }
    let mut run: Option<(f64, bool)> = None; // (first τ, side) of the run going on
    for &(tau, st) in states {
        match (st.map(|m| m.0), run) {
            (Some(side), Some((t0, s0))) if side == s0 => {
                if tau / t0 > MISS_RUN_SPAN {
                    return false;
                }
            }
            (Some(side), _) => run = Some((tau, side)),
            (None, _) => run = None,
        }
    }
    true
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

/// Whether the extended fit `ext` may replace the accepted fit `base` (issue 17.1b): the
/// joint test ([`fit::extension_agrees`]) says the added points are described, and this
/// says the extension does not buy its terms. It is refused when it makes the fit
/// approximate ([`APPROX_DELTA`], [`APPROX_CHI2`]) where the accepted one was not, or when
/// a term it newly resolves lies above the accepted fit's upper bound for that term: the
/// long-τ points then carry a term the accepted range rules out (on a record with a
/// mid-curve line, a random walk read off the last, noisiest points), not one it merely
/// sharpens.
fn extension_is_honest(
    data: &CurveData,
    fd: &fit::FitData,
    cfg: &Config,
    base: &fit::FitResult,
    ext: &fit::FitResult,
) -> bool {
    if approximate(ext) && !approximate(base) {
        return false;
    }
    let terms = |x: &fit::FitResult| {
        let first = fd.points[x.used[0]].tau;
        let last = fd.points[x.used[x.used.len() - 1]].tau;
        let curve = analysed_curve::curve_points(
            data,
            cfg,
            Some(x),
            Some(x),
            fd.basis,
            Some((first, last)),
        );
        let record = terms::record_points(&curve, fd, first);
        let t = terms::make_terms(x, fd, &curve, &record, cfg);
        t.as_array().into_iter().chain([t.g])
    };
    let resolved = |t: &Term| t.verdict == Verdict::Resolved;
    terms(base)
        .zip(terms(ext))
        .all(|(w, n)| !resolved(&n) || resolved(&w) || n.value <= w.hi)
}

/// A fit whose model misses the curve beyond its statistics by more than [`APPROX_DELTA`],
/// or whose χ²/dof exceeds [`APPROX_CHI2`]: its terms are declared approximate.
fn approximate(f: &fit::FitResult) -> bool {
    f.delta > APPROX_DELTA || f.chi2_per_dof > APPROX_CHI2
}
