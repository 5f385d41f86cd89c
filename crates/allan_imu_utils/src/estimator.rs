//! The overlapping Allan variance exactly as imu_utils computes it (docs/upstream/imu_utils.md §3.2–3.6):
//! mean-period frequency, integrated signal θ, then for each cluster size m
//! `σ²(m) = Σ ((θ[k+2m] − 2θ[k+m]) + θ[k])² / ((2 (period·m)²) (N − 2m))`.
//!
//! The fast path ([`allan_variance`]) runs the O(N) pass of every factor in parallel (rayon)
//! through the workspace's overlapping kernel, which sums with 32 independent accumulators
//! so the compiler vectorises it (AVX-512/AVX2 chosen at run time). Each squared term is bit-identical to upstream's; only the summation
//! order differs, which moves the result by ~1e-13 relative, far inside the 1e-9 parity
//! tolerance. One axis is processed at a time so its θ (23 MB for a 4 h 200 Hz bag) stays in
//! the shared L3 cache while both cores sweep it. The naive sequential oracle lives in the
//! tests.

use rayon::prelude::*;

/// Mean sample period: sequential sum of stamp differences over N−1 (`getAvgDt`).
/// Jitter and gaps are ignored (quirk 8, docs/upstream/imu_utils.md §6).
pub fn mean_period(t: &[f64]) -> f64 {
    let mut sum_dt = 0.0;
    for w in t.windows(2) {
        sum_dt += w[1] - w[0];
    }
    sum_dt / (t.len() as f64 - 1.0)
}

/// Integrated signal `θ[k] = (x[0] + … + x[k]) / freq` (`calcThetas`: a division by the
/// frequency, not a product with the period).
pub fn thetas(x: &[f64], freq: f64) -> Vec<f64> {
    let mut sum = 0.0;
    x.iter()
        .map(|&v| {
            sum += v;
            sum / freq
        })
        .collect()
}

/// [`thetas`] from an iterator of `n` values, also returning the final running sum (for the
/// mean) and the index of the first non-finite value, if any.
pub fn thetas_checked(
    x: impl Iterator<Item = f64>,
    n: usize,
    freq: f64,
) -> (Vec<f64>, f64, Option<usize>) {
    let mut sum = 0.0;
    let mut bad = None;
    let mut out = Vec::with_capacity(n);
    advise_huge_pages(&mut out);
    for (i, v) in x.enumerate() {
        if !v.is_finite() && bad.is_none() {
            bad = Some(i);
        }
        sum += v;
        out.push(sum / freq);
    }
    (out, sum, bad)
}

/// Asks Linux to back a large, not yet touched buffer with transparent huge pages (the
/// kernel's default here is `madvise`): a 4 h bag's six θ buffers are 138 MB, i.e. 34 000
/// page faults with 4 KiB pages, a sizeable share of the run's system time. Only a hint;
/// failure changes nothing.
#[cfg(target_os = "linux")]
fn advise_huge_pages(v: &mut Vec<f64>) {
    const MIN_BYTES: usize = 4 << 20;
    const PAGE: usize = 4096;
    let bytes = v.capacity() * std::mem::size_of::<f64>();
    if bytes < MIN_BYTES {
        return;
    }
    let start = v.as_mut_ptr() as usize;
    let aligned = start.next_multiple_of(PAGE);
    let len = (start + bytes - aligned) / PAGE * PAGE;
    // SAFETY: [aligned, aligned + len) lies inside the Vec's own allocation, page-aligned as
    // madvise requires; MADV_HUGEPAGE only changes how the kernel backs those pages, never
    // their contents or validity.
    unsafe {
        libc::madvise(aligned as *mut libc::c_void, len, libc::MADV_HUGEPAGE);
    }
}

#[cfg(not(target_os = "linux"))]
fn advise_huge_pages(_: &mut Vec<f64>) {}

/// Plain mean (`getAvgValue`): sequential sum over N.
#[cfg(test)]
pub fn mean(x: &[f64]) -> f64 {
    let mut sum = 0.0;
    for &v in x {
        sum += v;
    }
    sum / x.len() as f64
}

/// `tau[i] = period * m[i]`.
pub fn taus(period: f64, factors: &[usize]) -> Vec<f64> {
    factors.iter().map(|&m| period * m as f64).collect()
}

/// The divisor `(2 (period·m)²) (N − 2m)`; N − 2m may be zero or negative (docs/upstream/imu_utils.md §3.4
/// edge cases: 0/0 → NaN, 0/negative → −0.0).
pub fn divisor(n: usize, m: usize, period: f64) -> f64 {
    let cluster_period2 = (period * m as f64) * (period * m as f64);
    2.0 * cluster_period2 * (n as i64 - 2 * m as i64) as f64
}

/// `Σ_k ((θ[k+2m] − 2θ[k+m]) + θ[k])²`, 0 when N − 2m ≤ 0: the workspace's overlapping
/// kernel (`allan_kalibr::second_diff_sum`), whose squared terms are upstream's bit for bit.
#[cfg(test)]
pub fn second_diff_sum(theta: &[f64], m: usize) -> f64 {
    allan_kalibr::second_diff_sum(theta, m)
}

/// Factors per sweep of [`allan_variance`]: enough that the small ones share each tile of θ
/// read from memory, few enough that the groups keep both cores busy (93 factors for a 4 h
/// 200 Hz bag: 12 groups).
const FACTORS_PER_SWEEP: usize = 8;

/// Overlapping Allan variances of one axis for every factor, in factor order
/// (`calcVariance`): groups of consecutive factors in parallel, each group in one
/// cache-blocked sweep over θ (`allan_kalibr::second_diff_sums`, the same sums as
/// `second_diff_sum` bit for bit).
pub fn allan_variance(theta: &[f64], factors: &[usize], period: f64) -> Vec<f64> {
    let n = theta.len();
    factors
        .par_chunks(FACTORS_PER_SWEEP)
        .with_max_len(1)
        .flat_map_iter(|g| {
            allan_kalibr::second_diff_sums(theta, g)
                .into_iter()
                .zip(g)
                .map(move |(s, &m)| s / divisor(n, m, period))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Seed of the test signal generator (a fixed LCG, no external RNG needed).
    const SEED: u64 = 0x5EED_1234_ABCD_0001;
    /// Different summation order only: a few hundred ulps at most for these lengths.
    const FAST_VS_NAIVE_REL_TOL: f64 = 1e-11;

    /// Upstream's loop as written: one sequential sum per factor.
    fn naive_allan_variance(theta: &[f64], factors: &[usize], period: f64) -> Vec<f64> {
        let n = theta.len() as i64;
        factors
            .iter()
            .map(|&m| {
                let m = m as i64;
                let mut s = 0.0;
                let mut k = 0;
                while k < n - 2 * m {
                    let i = k as usize;
                    let mu = m as usize;
                    let d = theta[i + 2 * mu] - 2.0 * theta[i + mu] + theta[i];
                    s += d * d;
                    k += 1;
                }
                s / divisor(n as usize, m as usize, period)
            })
            .collect()
    }

    fn noise(n: usize) -> Vec<f64> {
        let mut state = SEED;
        (0..n)
            .map(|_| {
                state = state
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                ((state >> 11) as f64 / (1u64 << 53) as f64 - 0.5) * 1000.0 + 200.0
            })
            .collect()
    }

    #[test]
    fn fast_matches_naive_oracle() {
        for &n in &[12_203usize, 40_001] {
            let x = noise(n);
            let t: Vec<f64> = (0..n).map(|i| 1.6e9 + i as f64 * 0.005).collect();
            let period = mean_period(&t);
            let theta = thetas(&x, 1.0 / period);
            let f = crate::factors::factors(n, 100);
            let fast = allan_variance(&theta, &f, period);
            let slow = naive_allan_variance(&theta, &f, period);
            for (i, (a, b)) in fast.iter().zip(&slow).enumerate() {
                let rel = ((a - b) / b).abs();
                assert!(
                    rel <= FAST_VS_NAIVE_REL_TOL,
                    "n {n} factor index {i} (m {}): expected {b:e}, actual {a:e}, rel {rel:e}, tol {FAST_VS_NAIVE_REL_TOL:e}",
                    f[i]
                );
            }
        }
    }

    #[test]
    fn grouped_sweeps_equal_one_pass_per_factor_bit_for_bit() {
        let n = 40_001;
        let theta = thetas(&noise(n), 200.0);
        let f = crate::factors::factors(n, 100);
        let fast = allan_variance(&theta, &f, 0.005);
        assert_eq!(fast.len(), f.len());
        for (&m, v) in f.iter().zip(&fast) {
            let one = second_diff_sum(&theta, m) / divisor(n, m, 0.005);
            assert_eq!(v.to_bits(), one.to_bits(), "m={m}: {v:e} vs {one:e}");
        }
    }

    #[test]
    fn thetas_checked_equals_thetas_and_mean() {
        let mut x = noise(1000);
        let (th, sum, bad) = thetas_checked(x.iter().copied(), x.len(), 199.999_999_972_752_3);
        assert_eq!(th, thetas(&x, 199.999_999_972_752_3));
        assert_eq!(sum / 1000.0, mean(&x));
        assert_eq!(bad, None);
        x[17] = f64::NAN;
        x[40] = f64::INFINITY;
        assert_eq!(thetas_checked(x.iter().copied(), x.len(), 1.0).2, Some(17));
    }

    /// docs/upstream/imu_utils.md §3.4/§3.7: N − 2m = 0 gives 0/0 = NaN, N − 2m < 0 gives −0.0.
    #[test]
    fn quirk_degenerate_last_factor_nan_and_negative_zero() {
        let theta = thetas(&[1.0, 2.0], 100.0);
        let v = allan_variance(&theta, &[1], 0.01);
        assert!(v[0].is_nan());
        let theta = thetas(&[1.0, 2.0, 3.0], 100.0);
        let v = allan_variance(&theta, &[2], 0.01);
        assert!(v[0] == 0.0 && v[0].is_sign_negative(), "got {:e}", v[0]);
    }
}
