//! Issue 42: the operating-noise analysis' 95 % interval, counted over seeds, with the
//! issue's other figures per run (the density against the injected white noise plus the
//! injected lines' share, the lines' frequencies, the time offset). Hand-held records from
//! the tests' own writer (`operating::record`: closed-form motion, seeded noise; no spline,
//! no sim), two set-ups: a reference at the IMU's rate, and a motion-capture reference at
//! 120 Hz with its own noise (0.1 mm, 0.3 mrad) under a 400 Hz IMU. Each run goes through
//! the `allan_kalibr` binary as a user's does.

use allan_kalibr::operating::band;

use crate::operating::{
    LINE_FREQ_REL_TOL, N_REL_TOL, OFFSET_TOL, analyse_against_reference, axis_index, csv_rows, num,
    record, yaml,
};

/// Seeds per set-up.
const SEEDS: u64 = 40;
/// Record length, s (shorter than the tests' 240 s: the interval is wider, the count the
/// same statement).
const SECONDS: f64 = 90.0;
/// The interval is a 95 % statement: over 2 × 40 × 6 = 480 intervals its coverage must be
/// at least this (the binomial 99.9 % lower bound of 95 % at n = 480 is 92.2 %) …
const MIN_COVERAGE: f64 = 0.92;
/// … and not this conservative (an interval that always covers is too wide to be a 95 %
/// statement; the binomial upper bound of 95 % at n = 480 is 97.5 %).
const MAX_COVERAGE: f64 = 0.985;

#[test]
#[ignore = "the operating interval's coverage study: about 4 minutes on two busy cores (scripts/test.sh runs it)"]
fn operating_interval_coverage_study() {
    let setups: [(&str, f64, f64, (f64, f64)); 2] = [
        ("200 Hz IMU, reference 200 Hz", 200.0, 200.0, (0.0, 0.0)),
        (
            "400 Hz IMU, mocap 120 Hz (0.1 mm, 0.3 mrad)",
            400.0,
            120.0,
            (1e-4, 3e-4),
        ),
    ];
    let started = std::time::Instant::now();
    let (mut covered, mut total) = (0usize, 0usize);
    for (tag, rate, ref_rate, noise) in setups {
        let (mut cov, mut n, mut worst_n, mut worst_f, mut worst_dt) =
            (0, 0, 0.0f64, 0.0f64, 0.0f64);
        let mut sum_rel = 0.0;
        let mut missing = 0usize;
        let mut z: Vec<Vec<f64>> = vec![Vec::new(); 6];
        let mut z_oracle: Vec<Vec<f64>> = vec![Vec::new(); 6];
        for seed in 1..=SEEDS {
            let d = tempfile::tempdir().unwrap();
            let mut spec = record::Spec::handheld(rate, ref_rate, SECONDS, 1000 + seed);
            spec.ref_noise = noise;
            let w = record::write(d.path(), &spec);
            let out = d.path().join("out");
            analyse_against_reference(&w, &out);
            let want = spec.expected();
            let cal = out.join("operating_calibration.yaml");
            let first = ((yaml(&cal, "first_sample_time_s") - record::T0_NS as f64 * 1e-9) * rate)
                .round() as usize;
            let count = yaml(&cal, "samples_analysed") as usize;
            for row in csv_rows(&out.join("operating_noise.csv")) {
                let a = axis_index(&row);
                let (v, lo, hi) = (
                    num(&row, "noise_density"),
                    num(&row, "ci95_lo"),
                    num(&row, "ci95_hi"),
                );
                // the oracle: the same estimate on the injected noise of the same samples
                // (no motion, no calibration, no spline): what the pipeline adds is the
                // difference
                let band = (num(&row, "band_lo_hz"), num(&row, "band_hi_hz"));
                let oracle = band::analyse(&band::BandInput {
                    y: &w.noise[a][first..first + count],
                    rate,
                    spline_err: None,
                    band: Some(band),
                    lo_min: band.0,
                })
                .unwrap();
                z_oracle[a].push((v - oracle.n) / ((hi - lo) / (2.0 * 1.96)));
                n += 1;
                if lo <= want[a] && want[a] <= hi {
                    cov += 1;
                }
                // the error in units of the interval's standard error (its half-width / 1.96)
                z[a].push((v - want[a]) / ((hi - lo) / (2.0 * 1.96)));
                let rel = v / want[a] - 1.0;
                sum_rel += rel;
                worst_n = worst_n.max(rel.abs());
            }
            let lines = csv_rows(&out.join("operating_lines.csv"));
            for (a, f, _) in &spec.lines {
                let found = lines
                    .iter()
                    .filter(|r| axis_index(r) == *a)
                    .map(|r| num(r, "frequency_hz"))
                    .min_by(|x, y| (x - f).abs().total_cmp(&(y - f).abs()))
                    .unwrap_or(f64::NAN);
                if found.is_nan() {
                    missing += 1;
                }
                worst_f = worst_f.max((found / f - 1.0).abs());
            }
            let dt = yaml(&out.join("operating_calibration.yaml"), "time_offset_s");
            worst_dt = worst_dt.max((dt - spec.ref_offset).abs());
        }
        eprintln!(
            "{tag}: interval covers the injected density on {cov}/{n} axes ({:.1} %); mean error {:+.2} %, largest |error| {:.2} %; largest line frequency error {:.3} %; largest time offset error {:.1} µs",
            100.0 * cov as f64 / n as f64,
            100.0 * sum_rel / n as f64,
            100.0 * worst_n,
            100.0 * worst_f,
            worst_dt * 1e6
        );
        let sd = |v: &[f64]| {
            let m = v.iter().sum::<f64>() / v.len() as f64;
            (v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (v.len() - 1) as f64).sqrt()
        };
        eprintln!(
            "{tag}: the errors' standard deviation in units of the stated standard error, per axis (gx gy gz ax ay az; 1 for an exact interval): {}",
            z.iter()
                .map(|v| format!("{:.2}", sd(v)))
                .collect::<Vec<_>>()
                .join(" ")
        );
        eprintln!(
            "{tag}: the pipeline's own error (against the same estimate on the injected noise alone) in units of the stated standard error, standard deviation per axis: {}",
            z_oracle
                .iter()
                .map(|v| format!("{:.2}", sd(v)))
                .collect::<Vec<_>>()
                .join(" ")
        );
        assert!(worst_n < N_REL_TOL, "{tag}: density off by {worst_n}");
        assert!(
            missing == 0 && worst_f < LINE_FREQ_REL_TOL,
            "{tag}: {missing} lines not found, one off by {worst_f}"
        );
        assert!(worst_dt < OFFSET_TOL, "{tag}: offset off by {worst_dt}");
        covered += cov;
        total += n;
    }
    let share = covered as f64 / total as f64;
    eprintln!(
        "coverage over both set-ups: {covered}/{total} ({:.1} %); {:.0} s",
        100.0 * share,
        started.elapsed().as_secs_f64()
    );
    assert!(
        (MIN_COVERAGE..=MAX_COVERAGE).contains(&share),
        "coverage {covered}/{total}"
    );
}
