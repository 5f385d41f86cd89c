//! Overlapping and normal (non-overlapping) Allan variance of a rate series.
//!
//! The rate series y (rad/s, m/s², or fractional frequency), one sample every τ0 seconds, is
//! integrated once into a phase series (prefix sum, n + 1 points, x\[0\] = 0):
//!
//! ```text
//! x[k] = τ0 · Σ_{i<k} (y[i] − ȳ)
//! overlapping AVAR(m) = Σ_{k=0}^{N−2m−1} (x[k+2m] − 2x[k+m] + x[k])² / (2 (mτ0)² (N − 2m))
//! normal      AVAR(m) = Σ_{j=0}^{M−1} (x[(j+2)m] − 2x[(j+1)m] + x[jm])² / (2 (mτ0)² M)
//! ```
//!
//! with N = n + 1 phase points and M = ⌊n/m⌋ − 1 (the definitions Stable32 uses; the counts
//! match its "#" column). Subtracting the mean ȳ first changes no second difference but keeps
//! x near zero, so the compensated prefix sum loses no precision. Each m costs O(N)
//! ([`second_diff_sum`], the kernel both analysers use); a set of m is computed in parallel
//! with rayon.

use rayon::prelude::*;

/// Which Allan variance: every start index (overlapping) or disjoint clusters (normal).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Overlap {
    /// Fully overlapping estimator: all N − 2m second differences.
    Overlapping,
    /// Normal (non-overlapping) estimator: ⌊n/m⌋ − 1 second differences of disjoint clusters.
    Normal,
}

/// One Allan-variance value.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AvarPoint {
    /// Cluster size in samples.
    pub m: usize,
    /// Cluster time τ = m·τ0 in seconds.
    pub tau: f64,
    /// Allan variance in (rate unit)².
    pub avar: f64,
    /// Number of second differences averaged.
    pub n_terms: usize,
}

/// The integrated (phase) series of a rate series, ready for Allan variances at any m.
#[derive(Clone, Debug)]
pub struct Phase {
    x: Vec<f64>,
    tau0: f64,
}

impl Phase {
    /// Integrates `y` (sample period `tau0` > 0, all finite; checked by the caller) after
    /// removing its mean. Uses Neumaier-compensated summation.
    pub fn from_rate(y: &[f64], tau0: f64) -> Phase {
        let mean = neumaier_sum(y.iter().copied()) / y.len().max(1) as f64;
        let mut x = Vec::with_capacity(y.len() + 1);
        x.push(0.0);
        let (mut s, mut c) = (0.0f64, 0.0f64);
        for &v in y {
            let t = (v - mean) * tau0;
            let u = s + t;
            if s.abs() >= t.abs() {
                c += (s - u) + t;
            } else {
                c += (t - u) + s;
            }
            s = u;
            x.push(s + c);
        }
        Phase { x, tau0 }
    }

    /// Phase values (rate unit · s), n + 1 of them.
    pub fn x(&self) -> &[f64] {
        &self.x
    }

    /// Sample period τ0 in seconds.
    pub fn tau0(&self) -> f64 {
        self.tau0
    }

    /// Number of rate samples n.
    pub fn n_rate(&self) -> usize {
        self.x.len() - 1
    }

    /// Allan variance at cluster size `m`; `None` when there is not a single second difference
    /// (m = 0 or m too large for the kind).
    pub fn avar(&self, m: usize, kind: Overlap) -> Option<AvarPoint> {
        let n = self.n_rate();
        if m == 0 {
            return None;
        }
        let x = &self.x;
        let (sum, n_terms) = match kind {
            Overlap::Overlapping => {
                if 2 * m > n {
                    return None;
                }
                (second_diff_sum(x, m), n + 1 - 2 * m)
            }
            Overlap::Normal => {
                let clusters = n / m;
                if clusters < 2 {
                    return None;
                }
                let cnt = clusters - 1;
                let mut acc = 0.0;
                for j in 0..cnt {
                    let d = x[(j + 2) * m] - 2.0 * x[(j + 1) * m] + x[j * m];
                    acc += d * d;
                }
                (acc, cnt)
            }
        };
        let tau = m as f64 * self.tau0;
        Some(AvarPoint {
            m,
            tau,
            avar: sum / (2.0 * tau * tau * n_terms as f64),
            n_terms,
        })
    }

    /// Allan variances at every `m` of `ms` (in parallel), skipping those with no term.
    pub fn avar_many(&self, ms: &[usize], kind: Overlap) -> Vec<AvarPoint> {
        ms.par_iter().filter_map(|&m| self.avar(m, kind)).collect()
    }
}

/// Independent accumulators of [`second_diff_sum`]: enough for the compiler to fill AVX-512
/// registers and hide the add latency.
const LANES: usize = 32;

#[inline(always)]
fn second_diff_sum_body(a: &[f64], b: &[f64], c: &[f64]) -> f64 {
    let mut acc = [0.0f64; LANES];
    let (a8, ar) = a.as_chunks::<LANES>();
    let (b8, br) = b.as_chunks::<LANES>();
    let (c8, cr) = c.as_chunks::<LANES>();
    for ((a, b), c) in a8.iter().zip(b8).zip(c8) {
        for l in 0..LANES {
            // imu_utils' expression order: (x[k+2m] − 2x[k+m]) + x[k].
            let d = (c[l] - 2.0 * b[l]) + a[l];
            acc[l] += d * d;
        }
    }
    // Pairwise reduction of the lanes.
    let mut width = LANES;
    while width > 1 {
        width /= 2;
        for l in 0..width {
            acc[l] += acc[l + width];
        }
    }
    let mut s = acc[0];
    for ((a, b), c) in ar.iter().zip(br).zip(cr) {
        let d = (c - 2.0 * b) + a;
        s += d * d;
    }
    s
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
fn second_diff_sum_avx512(a: &[f64], b: &[f64], c: &[f64]) -> f64 {
    second_diff_sum_body(a, b, c)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn second_diff_sum_avx2(a: &[f64], b: &[f64], c: &[f64]) -> f64 {
    second_diff_sum_body(a, b, c)
}

/// `Σ_k ((x[k+2m] − 2x[k+m]) + x[k])²` over every k with k + 2m < x.len() (0 when there is
/// none): the fully overlapping second-difference sum of both analysers. Each squared term is
/// bit-identical to imu_utils' (its expression order); the sum uses [`LANES`] accumulators
/// and AVX-512 or AVX2 when the CPU has them (chosen at run time), which differs from a
/// sequential sum by rounding only (~1e-13 relative).
pub fn second_diff_sum(x: &[f64], m: usize) -> f64 {
    let n = x.len();
    if n <= 2 * m {
        return 0.0;
    }
    let cnt = n - 2 * m;
    let (a, b, c) = (&x[..cnt], &x[m..m + cnt], &x[2 * m..2 * m + cnt]);
    #[cfg(target_arch = "x86_64")]
    {
        if std::arch::is_x86_feature_detected!("avx512f") {
            // SAFETY: the CPU supports AVX-512F (checked just above).
            return unsafe { second_diff_sum_avx512(a, b, c) };
        }
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the CPU supports AVX2 (checked just above).
            return unsafe { second_diff_sum_avx2(a, b, c) };
        }
    }
    second_diff_sum_body(a, b, c)
}

/// Neumaier-compensated sum.
pub(super) fn neumaier_sum(it: impl Iterator<Item = f64>) -> f64 {
    let (mut s, mut c) = (0.0f64, 0.0f64);
    for v in it {
        let t = s + v;
        if s.abs() >= v.abs() {
            c += (s - t) + v;
        } else {
            c += (v - t) + s;
        }
        s = t;
    }
    s + c
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand::rngs::StdRng;
    use rand_distr::{Distribution, StandardNormal};

    const RNG_SEED: u64 = 0x0ADE_5EED;
    /// Fast and oracle sum the same squares in a different order and through the phase vs
    /// cluster means: agreement to a few ulps times the series length.
    const ORACLE_REL_TOL: f64 = 1e-10;

    /// Obviously-correct Allan variance from cluster averages of y (no phase, no prefix sums).
    fn oracle(y: &[f64], tau0: f64, m: usize, kind: Overlap) -> Option<f64> {
        let n = y.len();
        let mean_at = |k: usize| y[k..k + m].iter().sum::<f64>() / m as f64;
        let starts: Vec<usize> = match kind {
            Overlap::Overlapping => (0..n.checked_sub(2 * m)? + 1).collect(),
            Overlap::Normal => {
                let cl = n / m;
                if cl < 2 {
                    return None;
                }
                (0..cl - 1).map(|j| j * m).collect()
            }
        };
        if starts.is_empty() {
            return None;
        }
        let _ = tau0;
        let s: f64 = starts
            .iter()
            .map(|&k| (mean_at(k + m) - mean_at(k)).powi(2))
            .sum();
        Some(s / (2.0 * starts.len() as f64))
    }

    #[test]
    fn fast_matches_cluster_average_oracle() {
        let mut rng = StdRng::seed_from_u64(RNG_SEED);
        for &n in &[3usize, 4, 7, 50, 257, 1000] {
            // white noise plus a random walk plus an offset, so every term matters
            let mut b = 0.0;
            let y: Vec<f64> = (0..n)
                .map(|_| {
                    let w: f64 = StandardNormal.sample(&mut rng);
                    let s: f64 = StandardNormal.sample(&mut rng);
                    b += 0.1 * s;
                    3.0 + w + b
                })
                .collect();
            let tau0 = 0.005;
            let ph = Phase::from_rate(&y, tau0);
            for m in 1..=n {
                for kind in [Overlap::Overlapping, Overlap::Normal] {
                    let fast = ph.avar(m, kind).map(|p| p.avar);
                    let slow = oracle(&y, tau0, m, kind);
                    match (fast, slow) {
                        (None, None) => {}
                        (Some(f), Some(s)) => assert!(
                            ((f - s) / s).abs() < ORACLE_REL_TOL,
                            "n={n} m={m} {kind:?}: expected {s:e}, got {f:e}, tol {ORACLE_REL_TOL:e}"
                        ),
                        _ => panic!(
                            "n={n} m={m} {kind:?}: presence differs: fast {fast:?} oracle {slow:?}"
                        ),
                    }
                }
            }
        }
    }

    #[test]
    fn counts_match_stable32_convention() {
        // Stable32's "#" column for 241 217 rate points (GPS file): overlapping N−2m, normal ⌊n/m⌋−1.
        let y = vec![0.0; 241_217];
        let ph = Phase::from_rate(&y, 1.0);
        assert_eq!(ph.avar(1, Overlap::Overlapping).unwrap().n_terms, 241_216);
        assert_eq!(
            ph.avar(32768, Overlap::Overlapping).unwrap().n_terms,
            175_682
        );
        assert_eq!(ph.avar(2, Overlap::Normal).unwrap().n_terms, 120_607);
        assert_eq!(ph.avar(40000, Overlap::Normal).unwrap().n_terms, 5);
    }
}
