//! Accuracy of the N and K estimates on simulated static IMU data (issue 6 targets).
//!
//! Each axis is simulated by the workspace's own generator, `sim::NoiseGenerator`
//! (vio_data_simulation's `addIMUnoise`: white σ/√Δt plus the bias, then the bias step
//! σ_b·√Δt), with the presets of `sim::Preset`. Relative errors and interval coverage are
//! tabulated; the full 4 h × 200 Hz × 3 presets × 3 seeds study is `#[ignore]`d (run it with
//! `cargo test --release -p allan_kalibr --test main accuracy_full -- --ignored --nocapture`),
//! a short variant runs always.

use allan_kalibr::{Ieee952Analysis, Ieee952Config, Verdict, advise, analyse_ieee952};
use rayon::prelude::*;

/// Base of every simulation seed (preset p, seed s, axis a use BASE_SEED + 1000·s + 10·p + a,
/// so presets are independent draws: with a shared seed the gyro medium and high presets, whose
/// N/K ratios are both 300 s, would give identical relative errors).
const BASE_SEED: u64 = 0x1EEE_0952;

/// A noise preset: continuous-time (gyro N, gyro K, acc N, acc K).
#[derive(Clone, Copy, Debug)]
pub(super) struct Preset {
    pub name: &'static str,
    pub gyro_n: f64,
    pub gyro_k: f64,
    pub acc_n: f64,
    pub acc_k: f64,
}

/// The three presets, with their values from `sim::Preset`.
pub(super) fn presets() -> [Preset; 3] {
    use sim::Preset as P;
    [("low", P::Low), ("medium", P::Medium), ("high", P::High)].map(|(name, p)| {
        let c = p.params();
        Preset {
            name,
            gyro_n: c.gyro_noise,
            gyro_k: c.gyro_bias_rw,
            acc_n: c.acc_noise,
            acc_k: c.acc_bias_rw,
        }
    })
}

/// One axis: white noise density n and random walk k (continuous), `len` samples at `dt`,
/// from sim's generator.
pub(super) use sim::white_rw_axis as simulate_axis;

/// Result of one (preset, seed, axis).
#[derive(Clone, Debug)]
pub(super) struct Case {
    pub preset: &'static str,
    pub seed: u64,
    pub axis: &'static str,
    pub n_true: f64,
    pub k_true: f64,
    pub n_est: f64,
    pub n_se: f64,
    pub n_in: bool,
    pub k_est: f64,
    pub k_se: f64,
    pub k_lo: f64,
    pub k_hi: f64,
    pub k_in: bool,
    pub k_verdict: Verdict,
}

impl Case {
    pub(crate) fn n_err(&self) -> f64 {
        self.n_est / self.n_true - 1.0
    }
    pub(crate) fn k_err(&self) -> f64 {
        self.k_est / self.k_true - 1.0
    }
    pub(crate) fn is_gyro(&self) -> bool {
        self.axis.starts_with('g')
    }
}

const AXES: [&str; 6] = ["gx", "gy", "gz", "ax", "ay", "az"];

/// Runs the study for `presets` × `seeds` × 6 axes.
pub(super) fn study(
    rate: f64,
    duration: f64,
    presets: &[Preset],
    seeds: &[u64],
    cfg: &Ieee952Config,
) -> Vec<Case> {
    let dt = 1.0 / rate;
    let len = (duration * rate).round() as usize;
    let mut out = Vec::new();
    for (pi, p) in presets.iter().enumerate() {
        for &s in seeds {
            let truths: Vec<(f64, f64)> = (0..6)
                .map(|a| {
                    if a < 3 {
                        (p.gyro_n, p.gyro_k)
                    } else {
                        (p.acc_n, p.acc_k)
                    }
                })
                .collect();
            let cases: Vec<Case> = (0..6usize)
                .into_par_iter()
                .map(|a| {
                    let (n, k) = truths[a];
                    let y = simulate_axis(
                        n,
                        k,
                        dt,
                        len,
                        BASE_SEED + 1000 * s + 10 * pi as u64 + a as u64,
                    );
                    let r = analyse_ieee952(&y, dt, cfg).expect("simulated series must analyse");
                    let (tn, tk) = (r.terms.n, r.terms.k);
                    Case {
                        preset: p.name,
                        seed: s,
                        axis: AXES[a],
                        n_true: n,
                        k_true: k,
                        n_est: tn.value,
                        n_se: tn.std_err,
                        n_in: tn.lo <= n && n <= tn.hi,
                        k_est: tk.value,
                        k_se: tk.std_err,
                        k_lo: tk.lo,
                        k_hi: tk.hi,
                        k_in: tk.lo <= k && k <= tk.hi,
                        k_verdict: tk.verdict,
                    }
                })
                .collect();
            out.extend(cases);
        }
    }
    out
}

pub(super) fn print_table(cases: &[Case]) {
    println!(
        "preset  seed axis   N err %  N se %  N in | K err %  K se %  K 95% interval          K in  K verdict"
    );
    for c in cases {
        println!(
            "{:<7} {:>4} {:<4} {:>8.3} {:>7.3} {:>4} | {:>7.1} {:>7.1}  [{:>9.3e}, {:>9.3e}] {:>5}  {:?}",
            c.preset,
            c.seed,
            c.axis,
            100.0 * c.n_err(),
            100.0 * c.n_se / c.n_est,
            c.n_in,
            100.0 * c.k_err(),
            100.0 * c.k_se / c.k_est,
            c.k_lo,
            c.k_hi,
            c.k_in,
            c.k_verdict
        );
    }
}

/// Summary per (preset, sensor): max |N err|, RMS and max |K err|, coverage.
pub(super) fn print_summary(cases: &[Case]) {
    println!(
        "preset  sensor  cases  max|N err|%  rms K err%  max|K err|%  K>20%  N cover  K cover  K resolved"
    );
    let mut presets: Vec<&str> = cases.iter().map(|c| c.preset).collect();
    presets.dedup();
    for p in presets {
        for gyro in [true, false] {
            let cs: Vec<&Case> = cases
                .iter()
                .filter(|c| c.preset == p && c.is_gyro() == gyro)
                .collect();
            if cs.is_empty() {
                continue;
            }
            let nmax = cs.iter().map(|c| c.n_err().abs()).fold(0.0, f64::max);
            let krms = (cs.iter().map(|c| c.k_err().powi(2)).sum::<f64>() / cs.len() as f64).sqrt();
            let kmax = cs.iter().map(|c| c.k_err().abs()).fold(0.0, f64::max);
            let kbad = cs.iter().filter(|c| c.k_err().abs() > 0.2).count();
            let ncov = cs.iter().filter(|c| c.n_in).count();
            let kcov = cs.iter().filter(|c| c.k_in).count();
            let kres = cs
                .iter()
                .filter(|c| c.k_verdict == Verdict::Resolved)
                .count();
            println!(
                "{:<7} {:<6} {:>6} {:>12.3} {:>11.1} {:>12.1} {:>6} {:>5}/{:<3} {:>4}/{:<3} {:>5}/{}",
                p,
                if gyro { "gyro" } else { "acc" },
                cs.len(),
                100.0 * nmax,
                100.0 * krms,
                100.0 * kmax,
                kbad,
                ncov,
                cs.len(),
                kcov,
                cs.len(),
                kres,
                cs.len()
            );
        }
    }
    let all = cases.len();
    let cov_both = cases.iter().filter(|c| c.n_in && c.k_in).count();
    let cov_n = cases.iter().filter(|c| c.n_in).count();
    let cov_k = cases.iter().filter(|c| c.k_in).count();
    println!(
        "coverage of the 95 % intervals: N {cov_n}/{all}, K {cov_k}/{all}, both {cov_both}/{all}"
    );
}

/// The accuracy study, run by the test suite: static, 200 Hz, 4 h, 3 presets × 3
/// seeds × 6 axes (54 series of 2.88 M samples, ~40 s on two cores).
#[test]
fn accuracy_full() {
    let t0 = std::time::Instant::now();
    let cases = study(
        200.0,
        4.0 * 3600.0,
        &presets(),
        &[1, 2, 3],
        &Ieee952Config::default(),
    );
    println!(
        "full study: {} series in {:.1} s",
        cases.len(),
        t0.elapsed().as_secs_f64()
    );
    print_table(&cases);
    print_summary(&cases);
    let (n_cov, k_cov, all) = check_targets(&cases, 4.0 * 3600.0, true);
    println!("full study: N covered {n_cov}/{all}, K covered {k_cov}/{all}");
}

/// Cramér–Rao bound on the relative standard error of K for white noise N plus random walk K
/// observed for T seconds (Whittle approximation, fully known model): the Fisher information
/// of K² is T/(8·N·K³), so se(K)/K ≈ √(2N/(K·T)).
pub(super) fn k_rel_bound(n: f64, k: f64, t: f64) -> f64 {
    (2.0 * n / (k * t)).sqrt()
}

#[test]
#[ignore = "method comparison on 20 Hz data (K statistics do not depend on the rate); --ignored --nocapture"]
fn accuracy_methods() {
    use allan_kalibr::FitConfig;
    let seeds: Vec<u64> = (1..=8).collect();
    let presets = [presets()[1]];
    let base = Ieee952Config::default();
    let with = |f: FitConfig| Ieee952Config { fit: f, ..base };
    let variants: [(&str, Ieee952Config); 5] = [
        ("default (discrepancy, trim, band limit, selection)", base),
        (
            "plain GLS (no discrepancy)",
            with(FitConfig {
                discrepancy: false,
                ..FitConfig::default()
            }),
        ),
        (
            "full model, no selection",
            with(FitConfig {
                select: false,
                ..FitConfig::default()
            }),
        ),
        (
            "4/oct",
            with(FitConfig {
                per_octave: 4,
                ..FitConfig::default()
            }),
        ),
        (
            "N+K only",
            with(FitConfig {
                terms: [false, true, false, true, false, false, true, true, true],
                ..FitConfig::default()
            }),
        ),
    ];
    let t = 4.0 * 3600.0;
    println!(
        "CR bound on se(K)/K at 4 h, medium: gyro {:.1} %, acc {:.1} %",
        100.0 * k_rel_bound(0.015, 5e-5, t),
        100.0 * k_rel_bound(0.019, 5e-4, t)
    );
    for (name, cfg) in variants {
        let t0 = std::time::Instant::now();
        let cases = study(20.0, t, &presets, &seeds, &cfg);
        println!("## {name} ({:.1} s)", t0.elapsed().as_secs_f64());
        print_summary(&cases);
        for gyro in [true, false] {
            let cs: Vec<&Case> = cases.iter().filter(|c| c.is_gyro() == gyro).collect();
            let mean = cs.iter().map(|c| c.k_err()).sum::<f64>() / cs.len() as f64;
            let mean_se = cs
                .iter()
                .filter(|c| c.k_se.is_finite())
                .map(|c| c.k_se / c.k_est)
                .sum::<f64>()
                / cs.len() as f64;
            println!(
                "   {}: mean K err {:+.1} %, mean reported se(K)/K {:.1} %",
                if gyro { "gyro" } else { "acc" },
                100.0 * mean,
                100.0 * mean_se
            );
        }
    }
}

/// Issue 6: N within 3 % of the truth on every axis.
const N_REL_TOL: f64 = 0.03;
/// Issue 6: K within 20 % (medium, high) — attainable for the accelerometers only, see
/// [`accuracy_full`]; used for them.
const K_REL_TOL: f64 = 0.20;
/// Issue 6: for the low preset K within 35 % or reported as not resolved.
const K_LOW_REL_TOL: f64 = 0.35;
/// Issue 6: the 95 % intervals must contain the truth in at least 90 % of the cases.
const MIN_COVERAGE: f64 = 0.90;
/// For the gyro K at 4 h no estimator reaches 20 % reliably (Cramér–Rao 20.4 %); we demand
/// that the resolved ones' 95 % intervals hold the truth this often — the interval is
/// honest (before issue 40 the estimate within 3 of its Gaussian standard errors: the
/// error of a K read off few-cluster points is skewed, and one series whose random walk
/// ran at 0.3× its variance over 300–1500 s lies 4.5 of them off, 1.7 of its interval's
/// half-width) —…
const K_GYRO_MIN_COVERAGE: f64 = 0.90;
/// …and that the RMS error is within this factor of the bound.
const K_GYRO_RMS_OVER_BOUND: f64 = 1.5;

/// Asserts the targets that are statistically attainable; returns (N covered, K
/// covered, cases).
fn check_targets(cases: &[Case], duration: f64, coverage: bool) -> (usize, usize, usize) {
    for c in cases {
        let case = format!("{} seed {} {}", c.preset, c.seed, c.axis);
        assert!(
            c.n_err().abs() < N_REL_TOL,
            "{case}: N expected {:e}, got {:e}, tol {N_REL_TOL}",
            c.n_true,
            c.n_est
        );
        let resolved = c.k_verdict == Verdict::Resolved;
        if c.preset == "low" {
            assert!(
                !resolved || c.k_err().abs() < K_LOW_REL_TOL,
                "{case}: resolved K expected {:e}, got {:e}, tol {K_LOW_REL_TOL}",
                c.k_true,
                c.k_est
            );
        } else if !c.is_gyro() {
            assert!(
                resolved && c.k_err().abs() < K_REL_TOL,
                "{case}: K expected {:e}, got {:e} ({:?}), tol {K_REL_TOL}",
                c.k_true,
                c.k_est,
                c.k_verdict
            );
        }
    }
    // the gyro K a record resolves: its 95 % interval (the profile's, skewed where the
    // long-τ points have few degrees of freedom) holds the truth as often as it says
    let gyro_resolved: Vec<&Case> = cases
        .iter()
        .filter(|c| c.is_gyro() && c.preset != "low" && c.k_verdict == Verdict::Resolved)
        .collect();
    let gyro_in = gyro_resolved.iter().filter(|c| c.k_in).count();
    assert!(
        gyro_in as f64 >= K_GYRO_MIN_COVERAGE * gyro_resolved.len() as f64,
        "resolved gyro K covered {gyro_in}/{}",
        gyro_resolved.len()
    );
    for preset in ["medium", "high"] {
        let gy: Vec<&Case> = cases
            .iter()
            .filter(|c| c.preset == preset && c.is_gyro())
            .collect();
        if gy.is_empty() {
            continue;
        }
        let rms = (gy.iter().map(|c| c.k_err().powi(2)).sum::<f64>() / gy.len() as f64).sqrt();
        let bound = k_rel_bound(gy[0].n_true, gy[0].k_true, duration);
        println!(
            "{preset} gyro: RMS K error {:.1} % vs Cramér–Rao bound {:.1} % ({} cases)",
            100.0 * rms,
            100.0 * bound,
            gy.len()
        );
        assert!(
            rms < K_GYRO_RMS_OVER_BOUND * bound,
            "{preset} gyro: RMS K error {rms:.3} > {K_GYRO_RMS_OVER_BOUND} × bound {bound:.3}"
        );
    }
    let n_cov = cases.iter().filter(|c| c.n_in).count();
    let k_cov = cases.iter().filter(|c| c.k_in).count();
    let all = cases.len();
    if !coverage {
        return (n_cov, k_cov, all);
    }
    assert!(
        n_cov as f64 >= MIN_COVERAGE * all as f64,
        "N coverage {n_cov}/{all} < {MIN_COVERAGE}"
    );
    assert!(
        k_cov as f64 >= MIN_COVERAGE * all as f64,
        "K coverage {k_cov}/{all} < {MIN_COVERAGE}"
    );
    (n_cov, k_cov, all)
}

#[test]
fn accuracy_short() {
    // CI variant: 4 h at 20 Hz (the K statistics depend on the record length, not the rate),
    // medium preset, one seed: 6 series of 288 000 samples.
    let duration = 4.0 * 3600.0;
    let cases = study(
        20.0,
        duration,
        &presets()[1..2],
        &[1],
        &Ieee952Config::default(),
    );
    print_table(&cases);
    print_summary(&cases);
    // Six cases say nothing about a 95 % coverage (all six are covered only 74 % of the time
    // with perfectly calibrated intervals): coverage is asserted on the 54 cases of
    // `accuracy_full`.
    let (n_cov, k_cov, all) = check_targets(&cases, duration, false);
    println!("short study: N covered {n_cov}/{all}, K covered {k_cov}/{all}");
}

#[test]
#[ignore = "coverage study: 3 presets × 10 seeds × 6 axes at 20 Hz; --ignored --nocapture"]
fn accuracy_coverage() {
    let duration = 4.0 * 3600.0;
    let seeds: Vec<u64> = (11..=20).collect();
    let t0 = std::time::Instant::now();
    let cases = study(
        20.0,
        duration,
        &presets(),
        &seeds,
        &Ieee952Config::default(),
    );
    println!(
        "coverage study: {} series in {:.1} s",
        cases.len(),
        t0.elapsed().as_secs_f64()
    );
    print_summary(&cases);
    for preset in ["low", "medium", "high"] {
        for gyro in [true, false] {
            let cs: Vec<&Case> = cases
                .iter()
                .filter(|c| c.preset == preset && c.is_gyro() == gyro)
                .collect();
            let bound = k_rel_bound(cs[0].n_true, cs[0].k_true, duration);
            let within20 = cs.iter().filter(|c| c.k_err().abs() < 0.2).count();
            println!(
                "{preset} {}: K within 20 %: {within20}/{}; CR bound {:.1} % ⇒ expected ≈ {:.0} %",
                if gyro { "gyro" } else { "acc" },
                cs.len(),
                100.0 * bound,
                100.0 * erf_approx(0.2 / bound / std::f64::consts::SQRT_2)
            );
        }
    }
}

/// erf, Abramowitz–Stegun 7.1.26 (|error| < 1.5e-7), only for the printed expectation.
fn erf_approx(x: f64) -> f64 {
    let t = 1.0 / (1.0 + 0.327_591_1 * x.abs());
    let y = 1.0
        - (((((1.061_405_429 * t - 1.453_152_027) * t) + 1.421_413_741) * t - 0.284_496_736) * t
            + 0.254_829_592)
            * t
            * (-x * x).exp();
    if x >= 0.0 { y } else { -y }
}

/// The N estimate's spread may exceed its reported standard error by this factor at most
/// (120 replications estimate a standard deviation to ±6.5 %).
const N_SE_HONEST_FACTOR: f64 = 1.2;

#[test]
#[ignore = "efficiency of N: 240 series of 50 000 samples; --ignored --nocapture"]
fn n_efficiency() {
    // Sample standard deviation of N over replications vs the reported standard error and the
    // Cramér–Rao bound 1/√(2n) for white noise of known form.
    let dt = 0.05;
    for (label, k) in [("white only", 0.0), ("white+rw low", 1e-5)] {
        let mut errs = Vec::new();
        let mut ses = Vec::new();
        let mut chis = Vec::new();
        for s in 0..120u64 {
            let y = simulate_axis(0.01, k, dt, 50_000, BASE_SEED + 777 + s);
            let r = analyse_ieee952(&y, dt, &Ieee952Config::default()).unwrap();
            errs.push(r.terms.n.value / 0.01 - 1.0);
            ses.push(r.terms.n.std_err / r.terms.n.value);
            chis.push(r.fit.unwrap().chi2_per_dof);
        }
        let m = errs.iter().sum::<f64>() / errs.len() as f64;
        let sd =
            (errs.iter().map(|e| (e - m).powi(2)).sum::<f64>() / (errs.len() - 1) as f64).sqrt();
        let se = ses.iter().sum::<f64>() / ses.len() as f64;
        let chi = chis.iter().sum::<f64>() / chis.len() as f64;
        println!(
            "{label}: mean err {:+.4}%, sd {:.4}%, mean se {:.4}%, CR {:.4}%, mean chi2/dof {chi:.2}",
            100.0 * m,
            100.0 * sd,
            100.0 * se,
            100.0 / (2.0f64 * 50_000.0).sqrt()
        );
        assert!(
            sd < N_SE_HONEST_FACTOR * se,
            "{label}: N spread {sd:e} vs reported se {se:e}, tol factor {N_SE_HONEST_FACTOR}"
        );
    }
}

#[test]
#[ignore = "timing breakdown on one 2.88 M-sample axis; --ignored --nocapture (release)"]
fn timing_breakdown() {
    use allan_kalibr::{Overlap, Phase, greenhall_edf, identify};
    let y = simulate_axis(0.015, 5e-5, 0.005, 2_880_000, BASE_SEED);
    let cfg = Ieee952Config::default();
    let ms = cfg.grid.cluster_sizes(y.len());
    let t = std::time::Instant::now();
    let ph = Phase::from_rate(&y, 0.005);
    let pts = ph.avar_many(&ms, Overlap::Overlapping);
    let t_avar = t.elapsed().as_secs_f64();
    let t = std::time::Instant::now();
    let ids: Vec<_> = ms.iter().map(|&m| identify(&ph, m)).collect();
    let t_id = t.elapsed().as_secs_f64();
    let n_phase = y.len() + 1;
    let t = std::time::Instant::now();
    let e: f64 = ms
        .iter()
        .flat_map(|&m| {
            (-2..=2).map(move |a| greenhall_edf(a, m, n_phase, Overlap::Overlapping).unwrap())
        })
        .sum();
    let t_edf = t.elapsed().as_secs_f64();
    let t = std::time::Instant::now();
    let a = analyse_ieee952(&y, 0.005, &cfg).unwrap();
    let t_all = t.elapsed().as_secs_f64();
    println!(
        "{} m: phase+OADEV {t_avar:.3} s (parallel), noise ID {t_id:.3} s (serial), EDF×5 {t_edf:.3} s (serial), analyse total {t_all:.3} s; fit iterations {} ({} ids, {} pts, edf sum {e:.0})",
        ms.len(),
        a.fit.unwrap().iterations,
        ids.len(),
        pts.len()
    );
}

#[test]
#[ignore = "development: one simulated axis (SIM_CASE=medium:1:2); --ignored --nocapture"]
fn one_case() {
    let spec = std::env::var("SIM_CASE").unwrap_or("medium:1:2".into());
    let f: Vec<&str> = spec.split(':').collect();
    let pi = ["low", "medium", "high"]
        .iter()
        .position(|p| *p == f[0])
        .unwrap();
    let p = presets()[pi];
    let s: u64 = f[1].parse().unwrap();
    let a: usize = f[2].parse().unwrap();
    let (n, k) = if a < 3 {
        (p.gyro_n, p.gyro_k)
    } else {
        (p.acc_n, p.acc_k)
    };
    // the study numbers presets by their position in the list it was given
    let seed_pi: u64 = f.get(3).map_or(pi as u64, |v| v.parse().unwrap());
    let y = simulate_axis(
        n,
        k,
        0.05,
        288_000,
        BASE_SEED + 1000 * s + 10 * seed_pi + a as u64,
    );
    let r = analyse_ieee952(&y, 0.05, &Ieee952Config::default()).unwrap();
    println!("truth N {n:e} K {k:e}");
    super::real::print_row(
        "sim",
        if a < 3 {
            bag2mat::Sensor::Gyro
        } else {
            bag2mat::Sensor::Acc
        },
        a % 3,
        &r,
    );
    for p in &r.curve {
        println!(
            "{:>10.3} {:.4e} [{:.3e},{:.3e}] model {:.4e} {:+.3} {}",
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

#[test]
#[ignore = "OADEV cost per cluster size on one 2.88 M-sample axis; --ignored --nocapture (release)"]
fn oadev_cost_per_m() {
    use allan_kalibr::{Overlap, Phase};
    let y = simulate_axis(0.015, 5e-5, 0.005, 2_880_000, BASE_SEED);
    let ph = Phase::from_rate(&y, 0.005);
    for m in [1usize, 8, 64, 512, 4096, 32768, 262_144] {
        let t = std::time::Instant::now();
        let reps = 5;
        let mut s = 0.0;
        for _ in 0..reps {
            s += ph.avar(m, Overlap::Overlapping).unwrap().avar;
        }
        let dt = t.elapsed().as_secs_f64() / reps as f64;
        println!(
            "m={m}: {:.2} ms, {:.3} ns/element ({s:e})",
            dt * 1e3,
            dt * 1e9 / (2_880_000 - 2 * m) as f64
        );
    }
}

/// The analysis of one gyro axis of preset `preset` (seed's low, medium, high), 4 h at 20 Hz.
fn gyro_4h_at_20hz(preset: usize, seed: u64) -> Ieee952Analysis {
    let (rate, duration) = (20.0, 4.0 * 3600.0);
    let p = presets()[preset];
    let y = simulate_axis(
        p.gyro_n,
        p.gyro_k,
        1.0 / rate,
        (duration * rate) as usize,
        seed,
    );
    analyse_ieee952(&y, 1.0 / rate, &Ieee952Config::default()).expect("simulated series analyses")
}

/// A term the data do not show is reported with a usable 95 % upper bound: positive and
/// finite, and no looser than the curve allows (its Allan deviation at the bound stays within
/// the curve's upper 95 % band at some fitted point). On the seed's ideal IMU the selection
/// leaves B, Q and R out, and their bounds used to be "< 0" (B, R) or "< ∞" (Q).
#[test]
fn unresolved_terms_have_a_positive_finite_upper_bound() {
    let r = gyro_4h_at_20hz(0, BASE_SEED + 7);
    assert!(r.verdict.fits(), "{:?}", r.verdict);
    let t = &r.terms;
    let mut checked = 0;
    for (name, term) in [("Q", &t.q), ("B", &t.b), ("K", &t.k), ("R", &t.r)] {
        if term.verdict != Verdict::NotSignificant {
            continue;
        }
        checked += 1;
        assert!(
            term.hi > 0.0 && term.hi.is_finite(),
            "{name}: upper bound {} ({term:?})",
            term.hi
        );
    }
    assert!(checked >= 2, "B and R at least are not in this data: {t:?}");
}

/// The advisor's lower bound for an unresolved K (Cramér–Rao: T_x = 2·N·z²/(K·x²)) agrees
/// with the record the fit's own covariance asks for where K is resolved: on the medium
/// preset, 4 h, the two records for ±25 % are within a factor [`CR_RECORD_FACTOR`].
#[test]
fn k_record_formula_matches_the_fit_where_k_is_resolved() {
    /// The bound ignores the covariance between terms and the finite τ range (measured
    /// ratio 1.09 on this seed); a factor 2 either way still tells a user hours from days.
    const CR_RECORD_FACTOR: f64 = 2.0;
    let a = gyro_4h_at_20hz(1, BASE_SEED + 11);
    assert_eq!(a.terms.k.verdict, Verdict::Resolved, "{:?}", a.terms.k);
    let adv = advise(&a).expect("sample count known");
    let z2 = 1.959_963_984_540_054f64.powi(2);
    let cr = 2.0 * a.terms.n.value * z2 / (a.terms.k.value * 0.25 * 0.25);
    let ratio = adv.k.record_25 / cr;
    println!(
        "K record for ±25 %: fit {:.0} s, Cramér–Rao {cr:.0} s, ratio {ratio:.2}",
        adv.k.record_25
    );
    assert!(
        (1.0 / CR_RECORD_FACTOR..=CR_RECORD_FACTOR).contains(&ratio),
        "ratio {ratio}"
    );
}

#[test]
#[ignore = "timing of the section's stages on six 2.88 M-sample axes; --ignored --nocapture"]
fn section_stage_timings() {
    use allan_kalibr::{ImuCurves, Phase, analyse_curve, find_lines, identify, welch};
    let ys: Vec<Vec<f64>> = (0..6)
        .map(|a| simulate_axis(0.015, 5e-5, 0.005, 2_880_000, BASE_SEED + a))
        .collect();
    let cfg = Ieee952Config::default();
    let ms = cfg.grid.cluster_sizes(ys[0].len());
    let t = std::time::Instant::now();
    let ph = Phase::from_rate(&ys[0], 0.005);
    let pts = ph.avar_curve(&ms);
    let t_avar = t.elapsed().as_secs_f64();
    let t = std::time::Instant::now();
    let _ids: Vec<_> = pts.iter().map(|p| identify(&ph, p.m)).collect();
    let t_id = t.elapsed().as_secs_f64();
    let t = std::time::Instant::now();
    let p = welch(&ys[0], 200.0).unwrap();
    let t_psd = t.elapsed().as_secs_f64();
    let t = std::time::Instant::now();
    let _l = find_lines(&p);
    let t_lines = t.elapsed().as_secs_f64();
    println!(
        "one axis: {} m, phase+OADEV {t_avar:.3} s, noise ID {t_id:.3} s (serial), PSD {t_psd:.3} s, lines {t_lines:.3} s",
        ms.len()
    );
    let t = std::time::Instant::now();
    let series: [&[f64]; 6] = std::array::from_fn(|i| ys[i].as_slice());
    let curves = ImuCurves::from_samples(series, 200.0, &cfg).unwrap();
    let t_curves = t.elapsed().as_secs_f64();
    let t = std::time::Instant::now();
    let basis = curves.sensors[0].1[0].basis(cfg.fit.per_octave);
    let t_basis = t.elapsed().as_secs_f64();
    let mut t_fits = Vec::new();
    for (_, axes) in &curves.sensors {
        for c in axes {
            let t = std::time::Instant::now();
            let _ = analyse_curve(c, &cfg, basis.as_ref());
            t_fits.push(t.elapsed().as_secs_f64());
        }
    }
    let t = std::time::Instant::now();
    let _ = curves.finish(Vec::new(), &cfg);
    let t_finish = t.elapsed().as_secs_f64();
    println!(
        "six axes: curves {t_curves:.3} s (parallel), one basis {t_basis:.3} s, analyse_curve per axis (serial) {t_fits:.3?} s, finish (parallel, bases included) {t_finish:.3} s"
    );
}
