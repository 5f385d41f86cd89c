//! Issue 10's band-limited acceptance: a BMI088-like gyroscope (white noise 2.44e-4
//! rad/s/√Hz, random walk 2e-6 rad/s²/√Hz) generated at 3.2 kHz, through a 2nd-order
//! Butterworth low-pass, decimated to 400 Hz, 2 h; and its accelerometer twin (BMI088's
//! accelerometer white noise and random walk through the same chain). For low-pass corners
//! from 0.05 to 0.45 of the output rate: N within 5 % of the truth, and K's 95 % interval
//! covering the truth (or K unresolved with an upper bound at or above it) on
//! [`K_MIN_COVERAGE`] of the cases.
//!
//! Simulated by `sim`'s generator (issue 9's filter and decimation chain; truth from its
//! exact `AxisTruth`). One corner also goes the way a user's file does: written as a `.mat`
//! and analysed by `allan_kalibr`'s run, the terms read back from `ieee952_terms.csv` by
//! their column names.

use allan_kalibr::{CurveData, Ieee952Config, Verdict, analyse_curve};
use bag2mat::Sensor;
use rayon::prelude::*;
use sim::AxisTruth;
use sim::Profile;
use sim::axis_series;
use sim::{AxisModel, Chain, Filter, ImuModel, SensorModel};

/// Output rate, Hz.
const RATE: f64 = 400.0;
/// Internal rate, Hz.
const INTERNAL_RATE: f64 = 3200.0;
/// Record length, s.
const DURATION: f64 = 2.0 * 3600.0;
/// Low-pass corners as fractions of the output rate (issue 10: 0.05–0.45).
const CORNERS: [f64; 5] = [0.05, 0.15, 0.25, 0.35, 0.45];
/// The corner that also goes through a `.mat` file and the binary's run.
const MAT_CORNER: f64 = 0.125;
/// Issue 10: N within this of the truth.
const N_REL_TOL: f64 = 0.05;
/// Seed of the in-memory cases (one stream per corner, sensor and axis).
const SEED: u64 = 0xB088;

/// The BMI088-like model with the low-pass corner at `frac` of the output rate.
pub(super) fn model(frac: f64) -> ImuModel {
    let chain = Chain {
        internal_rate_hz: Some(INTERNAL_RATE),
        filter: Filter::Butterworth2 {
            cutoff_hz: frac * RATE,
        },
    };
    let gyro = AxisModel {
        white_noise: 2.44e-4,
        random_walk: 2e-6,
        ..Default::default()
    };
    let bmi = Profile::Bmi088.model();
    let acc = AxisModel {
        white_noise: bmi.acc.axes[0].white_noise,
        random_walk: bmi.acc.axes[0].random_walk,
        ..Default::default()
    };
    ImuModel {
        label: format!("bmi088-like, low-pass at {frac} of the output rate"),
        gyro: SensorModel {
            chain,
            axes: [gyro.clone(), gyro.clone(), gyro],
        },
        acc: SensorModel {
            chain,
            axes: [acc.clone(), acc.clone(), acc],
        },
    }
}

/// (N as the data show it, K) of one axis.
fn truth(m: &ImuModel, s: Sensor, axis: usize, n: usize) -> (f64, f64) {
    let sm = m.sensor(s);
    let chain = sm.chain.resolve(s, RATE).expect("chain");
    let a = &sm.axes[axis];
    let at = AxisTruth::new(a, &chain, 1.0 / RATE, n);
    (
        ((at.white().s0() + at.resolution_variance()) / RATE).sqrt(),
        a.random_walk,
    )
}

/// One checked case: (label, N error, K verdict, K value, K lo, K hi, K truth).
#[derive(Debug, Clone)]
struct Outcome {
    label: String,
    n_err: f64,
    k: (Verdict, f64, f64, f64),
    k_true: f64,
    range: String,
}

impl Outcome {
    fn k_ok(&self) -> bool {
        let (v, _, lo, hi) = self.k;
        match v {
            Verdict::Resolved => lo <= self.k_true && self.k_true <= hi,
            _ => hi >= self.k_true,
        }
    }
}

fn print(o: &Outcome) {
    println!(
        "{:34} N {:+6.2} % | K {:?} {:.3e} [{:.3e}, {:.3e}] truth {:.1e} {} | {}",
        o.label,
        100.0 * o.n_err,
        o.k.0,
        o.k.1,
        o.k.2,
        o.k.3,
        o.k_true,
        if o.k_ok() { "ok" } else { "MISS" },
        o.range
    );
}

fn in_memory_cases() -> Vec<Outcome> {
    let n = (DURATION * RATE) as usize;
    let cfg = Ieee952Config::default();
    let jobs: Vec<(f64, Sensor)> = CORNERS
        .iter()
        .flat_map(|&f| [Sensor::Gyro, Sensor::Acc].map(|s| (f, s)))
        .collect();
    jobs.par_iter()
        .enumerate()
        .map(|(i, &(frac, s))| {
            let m = model(frac);
            let y = axis_series(&m, s, 0, RATE, n, SEED + i as u64, 0.0).expect("series");
            let data = CurveData::from_samples(&y, 1.0 / RATE, &cfg).expect("curve");
            let basis = data.basis(cfg.fit.per_octave);
            let a = analyse_curve(&data, &cfg, basis.as_ref());
            let (n_true, k_true) = truth(&m, s, 0, n);
            Outcome {
                label: format!("corner {frac:.2}·rate {}", s.short()),
                n_err: a.terms.n.value / n_true - 1.0,
                k: (
                    a.terms.k.verdict,
                    a.terms.k.value,
                    a.terms.k.lo,
                    a.terms.k.hi,
                ),
                k_true,
                range: a.verdict.to_string(),
            }
        })
        .collect()
}

/// The `.mat` way: six axes written as `data_imu`, `allan_kalibr`'s run, the terms file.
fn mat_cases() -> Vec<Outcome> {
    let n = (DURATION * RATE) as usize;
    let m = model(MAT_CORNER);
    let jobs: Vec<(Sensor, usize)> = [Sensor::Acc, Sensor::Gyro]
        .into_iter()
        .flat_map(|s| (0..3).map(move |a| (s, a)))
        .collect();
    let cols: Vec<Vec<f64>> = jobs
        .par_iter()
        .enumerate()
        .map(|(i, &(s, a))| {
            axis_series(&m, s, a, RATE, n, SEED + 100 + i as u64, 0.0).expect("series")
        })
        .collect();
    let mut data = bag2mat::DataImu::with_capacity(n);
    data.columns[0] = (0..n).map(|i| i as f64 / RATE).collect();
    for (c, col) in cols.into_iter().enumerate() {
        data.columns[1 + c] = col;
    }
    let dir = tempfile::tempdir().expect("temp dir");
    let mat = dir.path().join("bmi088_like.mat");
    bag2mat::write_data_imu(&bag2mat::shared::output::Outputs::direct(), &mat, &data)
        .expect("write .mat");
    drop(data);
    let out = dir.path().join("out");
    let mut config = allan_kalibr::Config::new(allan_kalibr::Input::Samples(mat), out.clone());
    config.common.topics = bag2mat::TopicSelector::one("/imu0");
    config.title = "bmi088-like".into();
    allan_kalibr::run(&config, &bag2mat::shared::output::Outputs::direct())
        .expect("allan_kalibr run on the .mat");
    let rows = crate::ieee952::terms(&out);
    let mut out_cases = Vec::new();
    for (s, sname) in [(Sensor::Gyro, "gyroscope"), (Sensor::Acc, "accelerometer")] {
        for (a, aname) in ["x", "y", "z"].iter().enumerate() {
            let find = |t: &str| crate::ieee952::term(&rows, sname, aname, t);
            let (nr, kr) = (find("N"), find("K"));
            let verdict = match kr.verdict.as_str() {
                "Resolved" => Verdict::Resolved,
                "NotSignificant" => Verdict::NotSignificant,
                "NeverDominant" => Verdict::NeverDominant,
                "RegionReading" => Verdict::RegionReading,
                "RegionBound" => Verdict::RegionBound,
                "Contradicted" => Verdict::Contradicted,
                other => panic!("verdict {other}"),
            };
            let (n_true, k_true) = truth(&m, s, a, n);
            out_cases.push(Outcome {
                label: format!(".mat corner {MAT_CORNER}·rate {} {aname}", s.short()),
                n_err: nr.value / n_true - 1.0,
                k: (verdict, kr.value, kr.lo, kr.hi),
                k_true,
                range: String::new(),
            });
        }
    }
    out_cases
}

/// Issue 10's band-limited acceptance. A study (≈ 15 s on two cores in the optimised test
/// build) that scripts/test.sh runs: `cargo test -p allan_kalibr --test main bandlimited_study
/// -- --ignored`.
#[test]
#[ignore = "study run by scripts/test.sh"]
fn bandlimited_study() {
    let t0 = std::time::Instant::now();
    let mut cases = in_memory_cases();
    cases.extend(mat_cases());
    for c in &cases {
        print(c);
    }
    let k_miss: Vec<&Outcome> = cases.iter().filter(|c| !c.k_ok()).collect();
    println!(
        "band-limited study: {} cases in {:.1} s; N within 5 %: {}/{}; K covered (or bounded): {}/{}",
        cases.len(),
        t0.elapsed().as_secs_f64(),
        cases.iter().filter(|c| c.n_err.abs() <= N_REL_TOL).count(),
        cases.len(),
        cases.len() - k_miss.len(),
        cases.len()
    );
    for c in &cases {
        assert!(
            c.n_err.abs() <= N_REL_TOL,
            "{}: N off by {:+.2} %",
            c.label,
            100.0 * c.n_err
        );
    }
    assert!(
        (cases.len() - k_miss.len()) as f64 >= K_MIN_COVERAGE * cases.len() as f64,
        "K not covered: {k_miss:?}"
    );
}

/// K's interval holds the truth, or its upper bound is at or above it, on this share of the
/// cases at least. A bound is a one-sided 95 % statement (issue 40): of 16 cases one or two
/// miss by chance (two or more with probability 19 %, three or more 4 %); the coverage
/// study counts it over 126 axes.
const K_MIN_COVERAGE: f64 = 0.85;
