//! Times the Allan step alone on synthetic data of a given size (default: 4 h at 200 Hz,
//! six axes), phase by phase. `cargo run --release --example bench_allan [N] [REPEATS]`.

use std::time::Instant;

use allan_imu_utils::{allan_variance, factors, mean_period, thetas};

/// Seed of the synthetic white noise (a fixed LCG).
const SEED: u64 = 0x0123_4567_89AB_CDEF;

fn main() {
    let mut args = std::env::args().skip(1);
    let n: usize = args
        .next()
        .and_then(|s| s.parse().ok())
        .unwrap_or(2_880_002);
    let repeats: usize = args.next().and_then(|s| s.parse().ok()).unwrap_or(3);
    let mut state = SEED;
    let axes: Vec<Vec<f64>> = (0..6)
        .map(|_| {
            (0..n)
                .map(|_| {
                    state = state
                        .wrapping_mul(6364136223846793005)
                        .wrapping_add(1442695040888963407);
                    ((state >> 11) as f64 / (1u64 << 53) as f64 - 0.5) * 1000.0
                })
                .collect()
        })
        .collect();
    let t: Vec<f64> = (0..n).map(|i| 1.6e9 + i as f64 * 0.005).collect();
    let f = factors(n, 100);
    println!(
        "N {n}, {} factors, 6 axes, {} threads",
        f.len(),
        rayon::current_num_threads()
    );
    for _ in 0..repeats {
        let t0 = Instant::now();
        let period = mean_period(&t);
        let thetas: Vec<Vec<f64>> = axes.iter().map(|x| thetas(x, 1.0 / period)).collect();
        let t1 = Instant::now();
        let mut check = 0.0;
        for th in &thetas {
            check += allan_variance(th, &f, period)[0];
        }
        let t2 = Instant::now();
        println!(
            "thetas {:.3} s, variances {:.3} s, total {:.3} s (check {check:e})",
            (t1 - t0).as_secs_f64(),
            (t2 - t1).as_secs_f64(),
            (t2 - t0).as_secs_f64()
        );
    }
}
