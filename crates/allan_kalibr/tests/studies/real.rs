//! Real-IMU curves (`testdata/real_curves`: DJI A3, DJI N3, Bosch BMI160, written by
//! imu_utils from 2–3.3 h static recordings).

use allan_kalibr::{
    AxisVerdict, B_FLOOR_FACTOR, CurvesOptions, Ieee952Analysis, Ieee952Config, MAX_MISS_SHARE,
    MISS_RUN_SPAN, NoiseTerm, Reading, ReadingKind, Term, Verdict, analyse_curve, chi2_interval,
    read_curves, short,
};
use bag2mat::Sensor;

/// (folder, record length in s from its launch file, see the folder's README).
pub(super) const IMUS: [(&str, f64); 3] = [("A3", 7200.0), ("N3", 7200.0), ("BMI160", 12000.0)];

pub(super) fn analyse_imu_dir(
    name: &str,
    duration: f64,
    cfg: &Ieee952Config,
) -> Vec<(Sensor, Ieee952Analysis)> {
    let c = read_curves(
        &[bag2mat::test_tools::testdata()
            .join("real_curves")
            .join(name)],
        &CurvesOptions {
            duration: Some(duration),
            ..CurvesOptions::default()
        },
    )
    .unwrap();
    let mut out = Vec::new();
    for s in &c.sensors {
        let basis = s.axes[0].basis(cfg.fit.per_octave);
        for a in &s.axes {
            out.push((s.sensor, analyse_curve(a, cfg, basis.as_ref())));
        }
    }
    out
}

pub(super) fn print_row(imu: &str, sensor: Sensor, axis: usize, a: &Ieee952Analysis) {
    let f = a.fit.as_ref();
    let t = |x: &Term| {
        format!(
            "{:.3e} [{:.2e},{:.2e}] {:?}",
            x.value, x.lo, x.hi, x.verdict
        )
    };
    let r = |x: Option<Reading>| {
        x.map_or("-".into(), |x| {
            format!("{:.3e} [{:.2e},{:.2e}] {:?}", x.value, x.lo, x.hi, x.kind)
        })
    };
    println!(
        "{imu:6} {:4} {}: {} | range {:?} chi2/dof {:.3} delta {:.4} misfit {:.3} pts {}\n      N {}\n      B {}\n      K {}\n      Q {}  R {}\n      region N {}  B {}  K {}\n      G {} T {:.3} s, BT {:.3} s, N/reading {:+.1} %",
        sensor.name(),
        ["x", "y", "z"][axis],
        a.verdict,
        f.map(|f| f.tau_range),
        f.map_or(f64::NAN, |f| f.chi2_per_dof),
        f.map_or(f64::NAN, |f| f.delta),
        f.map_or(f64::NAN, |f| f.max_misfit),
        f.map_or(0, |f| f.points),
        t(&a.terms.n),
        t(&a.terms.b),
        t(&a.terms.k),
        t(&a.terms.q),
        t(&a.terms.r),
        r(a.region.n),
        r(a.region.b),
        r(a.region.k),
        t(&a.terms.g),
        a.terms.g_time,
        a.terms.b_corner,
        a.verdict.range().map_or(f64::NAN, |(lo, hi)| 100.0
            * (a.terms.n.value / n_reading_at_1s(a, lo, hi) - 1.0)),
    );
}

#[test]
#[ignore = "development table; --ignored --nocapture"]
fn real_curves_table() {
    let mut cfg = Ieee952Config::default();
    if std::env::var("NO_GM").is_ok() {
        cfg.fit.terms[NoiseTerm::GaussMarkov] = false;
    }
    if std::env::var("NO_CORNER").is_ok() {
        cfg.fit.flicker_corner = false;
    }
    for (name, d) in IMUS {
        for (i, (s, a)) in analyse_imu_dir(name, d, &cfg).iter().enumerate() {
            print_row(name, *s, i % 3, a);
        }
    }
}

#[test]
#[ignore = "development: residuals of one axis (REAL_AXIS=N3:acc:x); --ignored --nocapture"]
fn real_curve_residuals() {
    let spec = std::env::var("REAL_AXIS").unwrap_or("N3:acc:x".into());
    let f: Vec<&str> = spec.split(':').collect();
    let d = IMUS.iter().find(|x| x.0 == f[0]).unwrap().1;
    let all = analyse_imu_dir(f[0], d, &Ieee952Config::default());
    let k = if f[1] == "gyr" { 0 } else { 3 } + "xyz".find(f[2]).unwrap();
    let (s, a) = &all[k];
    print_row(f[0], *s, k % 3, a);
    if let Some(fit) = &a.fit {
        println!("coef {:?}", fit.coef);
    }
    for p in &a.curve {
        println!(
            "{:>10.4} {:.4e} [{:.3e},{:.3e}] model {:.4e} ratio {:+.3} {}",
            p.tau,
            p.adev,
            p.lo95,
            p.hi95,
            p.model,
            p.model / p.adev - 1.0,
            if p.in_range { "*" } else { "" }
        );
    }
}

/// Issue 10: the model within the larger of this and the point's own 95 % band over the
/// declared range (issue 40.5: but for the misses chance gives, [`GROSS_LEVEL`]).
const MODEL_TOL: f64 = 0.10;
/// A miss beyond this band of a point is the model's, never chance's.
const GROSS_LEVEL: f64 = 0.999;
/// Issue 10: N within this of the −½-line reading at τ = 1 s.
const N_READING_TOL: f64 = 0.10;
/// Issue 10: where B is resolved, 0.664·B within this of the curve's floor.
const B_FLOOR_TOL: f64 = 0.20;
/// Issue 10: at least this share of the axes fit over a range with τ = 1 s and two decades.
const MIN_FITTING_SHARE: f64 = 0.90;

/// The −½-line reading at τ = 1 s (IEEE 952), on the full curve (the product reads it on the
/// fit grid, `region::read`): the line of slope −½ fitted to the white-noise points near
/// 1 s — the curve points of [`tau_lo`, `tau_hi`] whose local log-log slope is within 0.1 of
/// −½, within an octave of the one nearest 1 s — read at 1 s (least squares in log: the
/// geometric mean of σ(τ)·√τ over them).
pub(super) fn n_reading_at_1s(a: &Ieee952Analysis, tau_lo: f64, tau_hi: f64) -> f64 {
    const SLOPE_TOL: f64 = 0.1;
    const WINDOW: f64 = 2.0;
    let c: Vec<_> = a
        .curve
        .iter()
        .filter(|p| p.tau >= tau_lo && p.tau <= tau_hi)
        .collect();
    let white: Vec<usize> = (1..c.len().saturating_sub(1))
        .filter(|&i| {
            let s = (c[i + 1].adev / c[i - 1].adev).ln() / (c[i + 1].tau / c[i - 1].tau).ln();
            (s + 0.5).abs() <= SLOPE_TOL
        })
        .collect();
    let centre = *white
        .iter()
        .min_by(|&&x, &&y| c[x].tau.ln().abs().total_cmp(&c[y].tau.ln().abs()))
        .expect("no white-noise region");
    let logs: Vec<f64> = white
        .iter()
        .filter(|&&i| c[i].tau / c[centre].tau <= WINDOW && c[centre].tau / c[i].tau <= WINDOW)
        .map(|&i| (c[i].adev * c[i].tau.sqrt()).ln())
        .collect();
    (logs.iter().sum::<f64>() / logs.len() as f64).exp()
}

/// Checks one analysed real axis; returns (fits over a range with 1 s and 2 decades, line).
pub(super) fn check_real_axis(label: &str, a: &Ieee952Analysis) -> (bool, String) {
    let Some((lo, hi)) = a.verdict.range() else {
        let why = a.verdict.to_string();
        assert!(
            why.len() > 20,
            "{label}: a failed fit must say why: {why:?}"
        );
        return (false, format!("{label}: {why}"));
    };
    // a fit declared "approximately" is one of "the others, with a verdict saying why": the
    // model stays within the tolerance (checked below) but its terms are not claimed
    let approximate = matches!(
        a.verdict,
        AxisVerdict::Fits {
            approximate: Some(_),
            ..
        }
    );
    let wide = lo <= 1.0 && hi >= 1.0 && hi / lo >= 100.0 && !approximate;
    let reading = n_reading_at_1s(a, lo, hi);
    // every point within the tolerance or its 95 % band, but the misses chance gives a
    // model that describes the curve (issue 40.5): within the 99.9 % band, at most
    // MAX_MISS_SHARE of the points, no same-side run wider than MISS_RUN_SPAN
    let in_range: Vec<_> = a.curve.iter().filter(|p| p.in_range).collect();
    let mut misses = 0usize;
    let mut run: Option<(f64, bool)> = None;
    for p in &in_range {
        let mis = p.model / p.adev - 1.0;
        let in_band = p.model >= p.lo95 && p.model <= p.hi95;
        if mis.abs() <= MODEL_TOL || in_band {
            run = None;
            continue;
        }
        misses += 1;
        let (lo, hi) = chi2_interval(p.adev, p.edf, GROSS_LEVEL).expect("a band");
        assert!(
            mis.abs() <= MODEL_TOL || (p.model >= lo && p.model <= hi),
            "{label}: model {:e} vs data {:e} [{:e}, {:e}] (99.9 %: [{lo:e}, {hi:e}]) at τ = {} s, tol {MODEL_TOL}",
            p.model,
            p.adev,
            p.lo95,
            p.hi95,
            p.tau
        );
        let above = p.adev > p.model;
        match run {
            Some((t0, side)) if side == above => assert!(
                p.tau / t0 <= MISS_RUN_SPAN,
                "{label}: the model misses the curve from τ = {t0} s to {} s",
                p.tau
            ),
            _ => run = Some((p.tau, above)),
        }
    }
    assert!(
        misses as f64 <= MAX_MISS_SHARE * in_range.len() as f64,
        "{label}: the model misses {misses} of {} points",
        in_range.len()
    );
    let n = a.terms.n.value;
    assert!(
        approximate || (n / reading - 1.0).abs() <= N_READING_TOL,
        "{label}: N {n:e} vs the −½-line reading {reading:e} at 1 s, tol {N_READING_TOL}"
    );
    let floor = a
        .curve
        .iter()
        .filter(|p| p.in_range)
        .map(|p| p.adev)
        .fold(f64::INFINITY, f64::min);
    let b = a.terms.b;
    if b.verdict == Verdict::Resolved && !approximate {
        let f = B_FLOOR_FACTOR * b.value;
        assert!(
            (f / floor - 1.0).abs() <= B_FLOOR_TOL,
            "{label}: 0.664·B = {f:e} vs the floor {floor:e} of the fitted range, tol {B_FLOOR_TOL}"
        );
    }
    let f = a.fit.as_ref().expect("a fitting axis has a fit");
    let t = |x: &Term| {
        if x.verdict == Verdict::Resolved {
            format!("{:.3e} [{:.2e}, {:.2e}]", x.value, x.lo, x.hi)
        } else {
            format!("< {:.2e} ({:?})", x.hi, x.verdict)
        }
    };
    let r = |x: Option<Reading>| {
        x.map_or("-".into(), |x| match x.kind {
            ReadingKind::Line => {
                format!("{:.3e} [{:.2e}, {:.2e}]", x.value, x.lo, x.hi)
            }
            ReadingKind::UpperBound => format!("< {:.2e}", x.hi),
        })
    };
    (
        wide,
        format!(
            "{label}: {}{} – {} s, χ²/dof {:.2}, δ {:.1} % | N {} | B {} | K {} | region N {} B {} K {} | N/reading {:+.1} %",
            if approximate { "(approximately) " } else { "" },
            short(lo),
            short(hi),
            f.chi2_per_dof,
            100.0 * f.delta,
            t(&a.terms.n),
            t(&a.terms.b),
            t(&a.terms.k),
            r(a.region.n),
            r(a.region.b),
            r(a.region.k),
            100.0 * (n / reading - 1.0)
        ),
    )
}

/// Issue 10's real-curve acceptance on the three IMUs of testdata/real_curves.
#[test]
fn real_curves_acceptance() {
    let mut fitting = 0;
    let mut total = 0;
    for (name, d) in IMUS {
        for (i, (s, a)) in analyse_imu_dir(name, d, &Ieee952Config::default())
            .iter()
            .enumerate()
        {
            let label = format!("{name} {} {}", s.name(), ["x", "y", "z"][i % 3]);
            let (ok, line) = check_real_axis(&label, a);
            println!("{line}");
            fitting += ok as usize;
            total += 1;
        }
    }
    println!("{fitting}/{total} axes fit over a range with τ = 1 s spanning two decades");
    assert!(
        fitting as f64 >= MIN_FITTING_SHARE * total as f64,
        "{fitting}/{total} axes fit, need {MIN_FITTING_SHARE}"
    );
}

/// The same acceptance on other imu_utils data directories: `REAL_CURVES_EXTRA` lists
/// `DIR:SECONDS` pairs separated by commas (the record length from the directory's launch
/// file; `DIR` alone infers the sample count from the grid), e.g. imu_utils' own `data/`
/// split per IMU.
#[test]
#[ignore = "needs REAL_CURVES_EXTRA; --ignored --nocapture"]
fn real_curves_acceptance_elsewhere() {
    let list = std::env::var("REAL_CURVES_EXTRA").expect("REAL_CURVES_EXTRA=DIR:SECONDS,...");
    let (mut fitting, mut total, mut failed) = (0, 0, Vec::new());
    for item in list.split(',').filter(|i| !i.is_empty()) {
        // DIR alone: the sample count inferred from the grid, as without --duration (a ':' in
        // the path is kept unless a number follows the last one)
        let (dir, duration) = match item.rsplit_once(':') {
            Some((d, secs)) if secs.parse::<f64>().is_ok() => (d, secs.parse().ok()),
            _ => (item, None),
        };
        let c = read_curves(
            &[std::path::PathBuf::from(dir)],
            &CurvesOptions {
                duration,
                ..CurvesOptions::default()
            },
        )
        .unwrap();
        let cfg = Ieee952Config::default();
        for s in &c.sensors {
            let basis = s.axes[0].basis(cfg.fit.per_octave);
            for (i, ax) in s.axes.iter().enumerate() {
                let a = analyse_curve(ax, &cfg, basis.as_ref());
                let label = format!("{dir} {} {}", s.sensor.name(), ["x", "y", "z"][i]);
                if std::env::var("REAL_CURVES_ROWS").is_ok() {
                    print_row(dir, s.sensor, i, &a);
                }
                // Every axis is checked (and printed) before the test fails.
                match std::panic::catch_unwind(|| check_real_axis(&label, &a)) {
                    Ok((ok, line)) => {
                        println!("{line}");
                        fitting += ok as usize;
                    }
                    Err(_) => failed.push(label),
                }
                total += 1;
            }
        }
    }
    println!("{fitting}/{total} axes fit over a range with τ = 1 s spanning two decades");
    assert!(failed.is_empty(), "failed: {failed:?}");
    assert!(fitting as f64 >= MIN_FITTING_SHARE * total as f64);
}
