//! Issue 17: vibration lines (IEEE 952 sinusoidal noise) must not break the fit. `sim`
//! generates an industrial-MEMS-like axis (white noise, bias instability, random walk, LSB:
//! the ADIS16470 profile's gyroscope without its warm-up) with a line from 0.002 of the rate
//! (the middle of the curve, like 0.5 Hz at 100 Hz) to 0.45 of it (short τ), its Allan bump
//! 3–10× the white noise's deviation there ("× the floor": the line's own Allan deviation at
//! its bump over the noise's at that τ, the measure the verdict prints). Scored against
//! `sim`'s exact truth, as issue 10's studies are.

use allan_kalibr::{
    BUMP_X, CurveData, Ieee952Analysis, Ieee952Config, Verdict, analyse_curve, sinusoid_avar,
};
use bag2mat::Sensor;
use rayon::prelude::*;
use sim::AxisTruth;
use sim::Profile;
use sim::axis_series;
use sim::{AxisModel, ImuModel, Line, SensorModel};

/// Output rate, Hz.
const RATE: f64 = 200.0;
/// Issue 17: N within this of the truth.
const N_REL_TOL: f64 = 0.03;
/// Issue 17: B within this of the truth where it dominates a decade.
const B_REL_TOL: f64 = 0.20;
/// Issue 17: each line's frequency within this.
const LINE_FREQ_REL_TOL: f64 = 0.02;
/// Issue 17: K's interval covers the truth (or K unresolved with a bound at or above it) on
/// at least this share of the axes.
const K_MIN_COVERAGE: f64 = 0.90;
/// Issue 17: the fit of a curve with a mid-curve line reaches τ ≥ T/20.
const RANGE_END_OF_RECORD: f64 = 1.0 / 20.0;
/// Issue 17.1's test: the range goes on past the line's bump by this factor of τ at least
/// (a decade of its ripples and more; before, it ended at the bump).
const BOTH_SIDES: f64 = 20.0;

/// The axis without a line: the ADIS16470 gyro (N, B, K, LSB), no warm-up.
fn base_axis() -> AxisModel {
    AxisModel {
        warmup: None,
        ..Profile::Adis16470.model().gyro.axes[0].clone()
    }
}

/// The line amplitude whose Allan bump is `k` × the white noise's deviation there.
fn amplitude_for(k: f64, frac: f64, white: f64) -> f64 {
    let nu0 = frac;
    let (mut best, mut at) = (0.0, 1.0);
    let mut m = 1.0f64;
    while m < 1e7 {
        let v = sinusoid_avar(m.round(), nu0);
        if v > best {
            (best, at) = (v, m.round());
        }
        m *= 1.02;
    }
    let noise = white / (at / RATE).sqrt();
    k * noise / best.sqrt()
}

fn model_with(line: Line) -> ImuModel {
    let mut a = base_axis();
    a.lines = vec![line];
    ImuModel {
        label: format!("line at {} Hz", line.frequency),
        gyro: SensorModel::uniform(a),
        acc: SensorModel::uniform(AxisModel::default()),
    }
}

struct Case {
    label: String,
    f0: f64,
    n_err: f64,
    b: Option<(f64, Verdict)>,
    b_true: f64,
    k: (Verdict, f64, f64, f64),
    k_true: f64,
    range_end: f64,
    record: f64,
    line_err: f64,
    analysis: Ieee952Analysis,
}

impl Case {
    fn k_ok(&self) -> bool {
        let (v, _, lo, hi) = self.k;
        match v {
            Verdict::Resolved => lo <= self.k_true && self.k_true <= hi,
            _ => hi >= self.k_true,
        }
    }
}

fn run_case(frac: f64, k: f64, seed: u64, duration: f64) -> Case {
    let n = (duration * RATE) as usize;
    let a = base_axis();
    let f0 = frac * RATE;
    let line = Line {
        frequency: f0,
        amplitude: amplitude_for(k, frac, a.white_noise),
        bandwidth: 0.0,
    };
    let m = model_with(line);
    let y = axis_series(&m, Sensor::Gyro, 0, RATE, n, seed, 0.0).expect("series");
    let cfg = Ieee952Config::default();
    let data = CurveData::from_samples(&y, 1.0 / RATE, &cfg).expect("curve");
    let basis = data.basis(cfg.fit.per_octave);
    let an = analyse_curve(&data, &cfg, basis.as_ref());
    let sm = m.sensor(Sensor::Gyro);
    let chain = sm.chain.resolve(Sensor::Gyro, RATE).expect("chain");
    let at = AxisTruth::new(&sm.axes[0], &chain, 1.0 / RATE, n);
    let n_eff = ((at.white().s0() + at.resolution_variance()) / RATE).sqrt();
    let b_true = a.bias_instability.map_or(0.0, |b| b.b);
    let line_err = an
        .lines
        .iter()
        .map(|l| l.frequency / f0 - 1.0)
        .min_by(|x, y| x.abs().total_cmp(&y.abs()))
        .unwrap_or(f64::INFINITY);
    Case {
        label: format!("f0 {frac}·rate ({f0} Hz), {k}× the floor, seed {seed}"),
        f0,
        n_err: an.terms.n.value / n_eff - 1.0,
        b: super::profiles::b_dominates_a_decade(&at, b_true, RATE, n)
            .then_some((an.terms.b.value, an.terms.b.verdict)),
        b_true,
        k: (
            an.terms.k.verdict,
            an.terms.k.value,
            an.terms.k.lo,
            an.terms.k.hi,
        ),
        k_true: a.random_walk,
        range_end: an.verdict.range().map_or(0.0, |r| r.1),
        record: duration,
        line_err,
        analysis: an,
    }
}

fn print(c: &Case) {
    println!(
        "{:48} N {:+6.2} % | B {} (truth {:.2e}) | K {:?} {:.3e} [{:.3e}, {:.3e}] truth {:.1e} {} | line {:+.3} % | {}",
        c.label,
        100.0 * c.n_err,
        c.b.map_or("-".into(), |(v, d)| format!("{v:.3e} {d:?}")),
        c.b_true,
        c.k.0,
        c.k.1,
        c.k.2,
        c.k.3,
        c.k_true,
        if c.k_ok() { "ok" } else { "MISS" },
        100.0 * c.line_err,
        c.analysis.verdict
    );
}

/// Issue 17.1: a line in the middle of the curve (0.5 Hz at 100 Hz, here 0.002 of the rate)
/// put a shoulder on the curve; the fitted range ended before it (τ = 0.64–1.28 s, its bump
/// at 0.37/f₀) and K followed the shoulder (20–50× the truth, "resolved"). The model now
/// holds the line: the fit uses the curve on both sides of it (past its bump by
/// [`BOTH_SIDES`] at least), N is the white level, K is within its interval or bounded at or
/// above the truth, and the line is reported at its frequency. (The study's bar, τ ≥ T/20,
/// is counted there.)
#[test]
fn mid_curve_line_does_not_truncate_the_fit() {
    let c = run_case(0.002, 6.0, 0x17_01, 7200.0);
    print(&c);
    let bump = BUMP_X / (std::f64::consts::PI * c.f0);
    assert!(
        c.range_end >= BOTH_SIDES * bump,
        "{}: range ends at {} s, the line's bump is at {bump} s",
        c.label,
        c.range_end
    );
    assert!(
        c.n_err.abs() <= N_REL_TOL,
        "{}: N {:+.2} %",
        c.label,
        100.0 * c.n_err
    );
    assert!(c.k_ok(), "{}: K {:?} vs {}", c.label, c.k, c.k_true);
    assert!(
        c.line_err.abs() <= LINE_FREQ_REL_TOL,
        "line at {} Hz: {:?}",
        c.f0,
        c.analysis.lines
    );
    assert!(
        c.analysis
            .terms
            .lines
            .iter()
            .flatten()
            .any(|l| (l.frequency / c.f0 - 1.0).abs() <= LINE_FREQ_REL_TOL),
        "the line is in the model"
    );
}

/// Issue 17.2: a line above the white-noise line at short τ was called "band-limited". The
/// vibration profile's 45 Hz gyro resonance (200 Hz): the verdict may not say band-limited
/// (the curve is never below the white-noise line there), and the section names the line.
#[test]
fn a_short_tau_line_is_named_not_called_band_limited() {
    let m = Profile::Vibration.model();
    let n = (3600.0 * RATE) as usize;
    let mut a = m.gyro.axes[0].clone();
    a.warmup = None;
    let model = ImuModel {
        label: "vibration gyro".into(),
        gyro: SensorModel {
            chain: m.gyro.chain,
            axes: [a.clone(), a.clone(), a],
        },
        acc: SensorModel::uniform(AxisModel::default()),
    };
    let y = axis_series(&model, Sensor::Gyro, 0, RATE, n, 0x17_02, 0.0).expect("series");
    let cfg = Ieee952Config::default();
    let data = CurveData::from_samples(&y, 1.0 / RATE, &cfg).expect("curve");
    let basis = data.basis(cfg.fit.per_octave);
    let an = analyse_curve(&data, &cfg, basis.as_ref());
    let text = an.verdict.to_string();
    println!("{text}; lines {:?}", an.lines);
    assert!(!text.contains("band-limited"), "{text}");
    let l = an.lines.first().expect("the resonance is found in the PSD");
    assert!(
        (l.frequency / 45.0 - 1.0).abs() <= LINE_FREQ_REL_TOL,
        "{l:?}"
    );
    assert!(l.bandwidth > 0.0, "a resonance, not a sinusoid: {l:?}");
}

/// Issue 17's acceptance: lines from 0.002 to 0.45 of the rate, 3× and 10× the floor, 3
/// seeds, 2 h at 200 Hz. A study run by scripts/test.sh (release).
#[test]
#[ignore = "study run by scripts/test.sh"]
fn lines_study() {
    let t0 = std::time::Instant::now();
    let mut jobs = Vec::new();
    for frac in [0.002, 0.01, 0.05, 0.2, 0.45] {
        for k in [3.0, 10.0] {
            for seed in super::profiles::SEEDS {
                jobs.push((frac, k, seed));
            }
        }
    }
    let cases: Vec<Case> = jobs
        .par_iter()
        .map(|&(frac, k, seed)| run_case(frac, k, seed, 7200.0))
        .collect();
    for c in &cases {
        print(c);
    }
    let n_fail: Vec<&Case> = cases.iter().filter(|c| c.n_err.abs() > N_REL_TOL).collect();
    let b_checked: Vec<&Case> = cases.iter().filter(|c| c.b.is_some()).collect();
    let b_fail: Vec<&&Case> = b_checked
        .iter()
        .filter(|c| (c.b.unwrap().0 / c.b_true - 1.0).abs() > B_REL_TOL)
        .collect();
    let k_ok = cases.iter().filter(|c| c.k_ok()).count();
    let mid: Vec<&Case> = cases.iter().filter(|c| c.f0 <= 0.01 * RATE).collect();
    let short_range: Vec<&&Case> = mid
        .iter()
        .filter(|c| c.range_end < RANGE_END_OF_RECORD * c.record)
        .collect();
    let line_fail: Vec<&Case> = cases
        .iter()
        .filter(|c| c.line_err.abs() > LINE_FREQ_REL_TOL)
        .collect();
    println!(
        "lines study: {} axes in {:.1} s; N within 3 %: {}/{}; B within 20 % where it dominates a decade: {}/{}; K covered (or bounded at or above the truth): {}/{}; mid-curve fits reaching T/20: {}/{}; lines within 2 % of their frequency: {}/{}",
        cases.len(),
        t0.elapsed().as_secs_f64(),
        cases.len() - n_fail.len(),
        cases.len(),
        b_checked.len() - b_fail.len(),
        b_checked.len(),
        k_ok,
        cases.len(),
        mid.len() - short_range.len(),
        mid.len(),
        cases.len() - line_fail.len(),
        cases.len()
    );
    assert!(n_fail.is_empty(), "N outside 3 %");
    assert!(b_fail.is_empty(), "B outside 20 %");
    assert!(
        k_ok as f64 >= K_MIN_COVERAGE * cases.len() as f64,
        "K coverage {k_ok}"
    );
    assert!(line_fail.is_empty(), "a line off its frequency");
    // issue 17: no yaml value above the data's own bound, on every case
    let over: Vec<String> = cases
        .iter()
        .flat_map(|c| {
            super::profiles::yaml_over_bounds(&c.label, &[(Sensor::Gyro, 0, &c.analysis)])
        })
        .collect();
    assert!(over.is_empty(), "{over:?}");
    // where the flicker floor comes out of the line's ripples (this axis' B corner is at
    // 2 s), some seeds put B 6–11 % high and the curve dips under it at 80–150 s: the
    // extension past that dip is judged jointly (fit::range_end), not point by point
    for c in &short_range {
        println!("  NOT MET (T/20): {} ends at {} s", c.label, c.range_end);
    }
    assert!(short_range.is_empty(), "a mid-curve fit ends before T/20");
}

/// Issue 17.1b: behind a mid-curve line the flicker floor is read off the line's ripples;
/// on this seed B came out 6–11 % high, the curve dipped 20–26 % under that model at
/// τ ≈ 80–150 s, and the point-by-point range check ended the fit there, before T/20. The
/// extension is now judged as a whole (fit::range_end): the fit reaches T/20.
#[test]
fn a_dip_under_the_floor_does_not_end_the_range() {
    let c = run_case(ISSUE17_1B_FRAC, ISSUE17_1B_K, 102, 7200.0);
    print(&c);
    assert!(
        c.range_end >= RANGE_END_OF_RECORD * c.record,
        "{}: range ends at {} s",
        c.label,
        c.range_end
    );
}

/// Issue 17.1b's case: the line's frequency over the rate, and its size over the floor.
const ISSUE17_1B_FRAC: f64 = 0.002;
const ISSUE17_1B_K: f64 = 10.0;

/// Issue 18.5: white noise and random walk only (the high preset, 30 min at 200 Hz, 3
/// seeds, 6 axes): a ramp R "resolved" with a ±2.4 % interval read off the longest points
/// (whose band spans a factor of 3), and K "not resolved" with 95 % bounds below the truth.
/// An interval must be as wide as the data's uncertainty at the τ that carries the term: no
/// R is resolved, and every K is covered by its interval or bounded at or above the truth.
#[test]
fn clean_data_resolve_no_ramp_and_bound_k_above_the_truth() {
    let c = sim::Preset::High.params();
    let model = ImuModel::from_continuous("high", &c);
    let n = (1800.0 * RATE) as usize;
    let cfg = Ieee952Config::default();
    let mut jobs = Vec::new();
    for seed in [0x18_05u64, 0x18_06, 0x18_07] {
        for s in [Sensor::Gyro, Sensor::Acc] {
            for axis in 0..3 {
                jobs.push((seed, s, axis));
            }
        }
    }
    let bad: Vec<String> = jobs
        .par_iter()
        .filter_map(|&(seed, s, axis)| {
            let y = axis_series(&model, s, axis, RATE, n, seed, 0.0).expect("series");
            let data = CurveData::from_samples(&y, 1.0 / RATE, &cfg).expect("curve");
            let basis = data.basis(cfg.fit.per_octave);
            let a = analyse_curve(&data, &cfg, basis.as_ref());
            let k_true = match s {
                Sensor::Gyro => c.gyro_bias_rw,
                Sensor::Acc => c.acc_bias_rw,
            };
            let (r, k) = (a.terms.r, a.terms.k);
            let k_ok = match k.verdict {
                Verdict::Resolved => k.lo <= k_true && k_true <= k.hi,
                _ => k.hi >= k_true,
            };
            (r.verdict == Verdict::Resolved || !k_ok).then(|| {
                format!(
                    "seed {seed:#x} {} {axis}: R {:?} {:.3e} [{:.3e}, {:.3e}], K {:?} {:.3e} [{:.3e}, {:.3e}] vs {k_true:e}",
                    s.short(),
                    r.verdict,
                    r.value,
                    r.lo,
                    r.hi,
                    k.verdict,
                    k.value,
                    k.lo,
                    k.hi
                )
            })
        })
        .collect();
    // K's own 95 % coverage allows a miss in twenty; R, absent, may come out resolved by
    // chance at about the one-sided 2.5 % — at most one of the eighteen axes for either
    assert!(
        bad.len() <= 1,
        "{} of {} axes: {bad:#?}",
        bad.len(),
        jobs.len()
    );
}
