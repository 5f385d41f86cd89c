//! Timing of the IEEE 952 overlapping Allan sweep on six axes of a .mat (development aid):
//! wall and CPU seconds of the phase integration and of the sweep, best of 5.
//! `cargo run --release -p allan_kalibr --example bench_oadev -- FILE.mat RATE`
//! (a long input: `sim bag --duration 14400 -o x.bag`, then `bag2mat x.bag -o x.mat`)
use std::time::Instant;

use allan_kalibr::{GridSpec, Phase};
use rayon::prelude::*;

fn cpu_seconds() -> f64 {
    // utime + stime of the process, from /proc (Linux; 0 elsewhere)
    let Ok(s) = std::fs::read_to_string("/proc/self/stat") else {
        return 0.0;
    };
    let f: Vec<&str> = s
        .rsplit(')')
        .next()
        .unwrap_or("")
        .split_whitespace()
        .collect();
    let tick = |i: usize| f.get(i).and_then(|v| v.parse::<f64>().ok()).unwrap_or(0.0);
    (tick(11) + tick(12)) / 100.0
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    if std::env::var("PSD").is_ok() {
        let a: Vec<String> = std::env::args().collect();
        let d = bag2mat::read_data_imu(std::path::Path::new(&a[1]))?;
        let t = Instant::now();
        let n: usize = d.columns[1..]
            .par_iter()
            .map(|y| {
                allan_kalibr::welch(y, 200.0).map_or(0, |p| allan_kalibr::find_lines(&p).len())
            })
            .sum();
        eprintln!(
            "psd + lines of 6 axes: {:.3} s ({n} lines)",
            t.elapsed().as_secs_f64()
        );
        return Ok(());
    }
    if std::env::var("L1").is_ok() {
        l1_kernel();
        return Ok(());
    }
    let a: Vec<String> = std::env::args().collect();
    let d = bag2mat::read_data_imu(std::path::Path::new(&a[1]))?;
    let rate: f64 = a[2].parse()?;
    let cols: Vec<&Vec<f64>> = d.columns[1..].iter().collect();
    let all = GridSpec::default().cluster_sizes(cols[0].len());
    let lo: usize = std::env::var("M_LO")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(0);
    let hi: usize = std::env::var("M_HI")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(usize::MAX);
    let ms: Vec<usize> = all.into_iter().filter(|&m| m >= lo && m <= hi).collect();
    let n = cols[0].len();
    let terms: f64 = ms.iter().map(|&m| (n + 1 - 2 * m) as f64).sum::<f64>() * 6.0;
    let phases: Vec<Phase> = cols
        .par_iter()
        .map(|y| Phase::from_rate(y, 1.0 / rate))
        .collect();
    let (mut best_wall, mut best_cpu) = (f64::INFINITY, f64::INFINITY);
    let mut check = 0.0;
    for _ in 0..5 {
        let (t, c) = (Instant::now(), cpu_seconds());
        let v: Vec<f64> = if std::env::var("PER_M").is_ok() {
            phases
                .par_iter()
                .map(|p| {
                    ms.iter()
                        .map(|&m| allan_kalibr::second_diff_sum(p.x(), m))
                        .sum()
                })
                .collect()
        } else {
            phases
                .par_iter()
                .map(|p| p.avar_curve(&ms).iter().map(|x| x.avar).sum())
                .collect()
        };
        best_wall = best_wall.min(t.elapsed().as_secs_f64());
        best_cpu = best_cpu.min(cpu_seconds() - c);
        check = v[0];
    }
    eprintln!(
        "sweep of {} m on 6 axes: wall {best_wall:.4} s, cpu {best_cpu:.2} s, {:.2} G terms/cpu s (checksum {check:e})",
        ms.len(),
        terms / best_cpu / 1e9
    );
    Ok(())
}

#[allow(dead_code)]
fn l1_kernel() {
    use allan_kalibr::second_diff_sum;
    let x: Vec<f64> = (0..1200).map(|i| (i as f64 * 0.37).sin()).collect();
    let t = Instant::now();
    let mut s = 0.0;
    let reps = 2_000_000;
    for _ in 0..reps {
        s += second_diff_sum(std::hint::black_box(&x), 100);
    }
    let terms = reps as f64 * 1000.0;
    eprintln!(
        "L1 kernel: {:.2} G terms/s ({s:e})",
        terms / t.elapsed().as_secs_f64() / 1e9
    );
}
