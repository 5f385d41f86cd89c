//! The estimator `gen_chart` reads: `sig2`, the NON-overlapping Allan deviation on the
//! cluster means D(1), D(1+m), D(1+2m), … of `allan.m` (allan_v3, docs/upstream/kalibr_allan.md §2.1).
//!
//! For K = floor(n/m) clusters: `sig2 = sqrt(0.5 * mean(diff(D)^2))`; m = 0 gives NaN.
//! Three ways to compute it, all per distinct m only:
//! * [`Estimator::PrefixSum`] (default): compensated prefix sums, O(n/m) per m, all m walked
//!   together tile by tile so the samples stream through the cache once ([`sig2_prefix_fused`]).
//!   Agrees with upstream within ~1e-9 relative on the reference cases (the gap is upstream's
//!   own running-mean rounding, docs/upstream/kalibr_allan.md §2, which can reach ~1e-7 on low-noise axes).
//! * [`Estimator::BitExact`]: replays upstream's recursive running mean, O(n) per m, so the
//!   curves are bit-identical to the reference.
//! * `sig2_oracle`: the textbook definition (each block summed directly), for tests.

use std::hint::black_box;

use rayon::prelude::*;

use super::grid::TauGrid;

/// How `sig2` is computed (chosen once, by `--bit-exact`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Estimator {
    /// Block means from prefix sums: fast, within ~1e-7 relative of upstream.
    #[default]
    PrefixSum,
    /// Upstream's running-mean recursion, bit-identical to the reference curves.
    BitExact,
}

/// `sig2` for all six axes on every grid point (NaN at m = 0, duplicates copied).
///
/// `axes` are the six sample columns ax ay az wx wy wz, each of length `grid.n`; the fast
/// path turns each column into its prefix sums in place (no second copy of the samples).
/// `on_progress` is called once per finished (axis, m) job.
pub(crate) fn sig2_curves(
    mut axes: [Vec<f64>; 6],
    grid: &TauGrid,
    estimator: Estimator,
    on_progress: &(dyn Fn() + Sync),
) -> [Vec<f64>; 6] {
    let ms = grid.distinct_m();
    let per_m: Vec<Vec<f64>> = match estimator {
        Estimator::PrefixSum => axes
            .par_iter_mut()
            .map(|x| {
                let v = sig2_prefix_fused(x, &ms);
                for _ in 0..ms.len() {
                    on_progress();
                }
                v
            })
            .collect(),
        Estimator::BitExact => {
            // Parallel over axes and m; each job is one O(n) replay of the recursion.
            let jobs: Vec<(usize, usize)> = (0..6)
                .flat_map(|a| (0..ms.len()).map(move |j| (a, j)))
                .collect();
            let flat: Vec<f64> = jobs
                .par_iter()
                .map(|&(a, j)| {
                    let v = sig2_recursive(&axes[a], ms[j] as usize);
                    on_progress();
                    v
                })
                .collect();
            flat.chunks(ms.len()).map(<[f64]>::to_vec).collect()
        }
    };
    std::array::from_fn(|a| expand(&grid.m, &ms, &per_m[a]))
}

/// Spreads per-distinct-m values back over the 2000 grid points (NaN for m = 0).
fn expand(grid_m: &[u64], ms: &[u64], values: &[f64]) -> Vec<f64> {
    let mut j = 0;
    grid_m
        .iter()
        .map(|&m| {
            if m == 0 {
                return f64::NAN;
            }
            while ms[j] != m {
                j += 1;
            }
            values[j]
        })
        .collect()
}

/// Turns `x` into its prefix sums in place: afterwards `x[i] = P[i+1] = Σ_{k≤i} (x[k] − c)`
/// (`P[0] = 0` is implicit), where `c` is the first sample.
///
/// Subtracting `c` keeps a constant offset (gravity on acc z) out of the sums, and the
/// running sum is Kahan-compensated so each stored `P[i]` is within about an ulp of the exact
/// value: a block sum `P[j] − P[i]` then carries no error accumulated along the way. The
/// offset cancels in the difference of two block means.
pub fn prefix_in_place(x: &mut [f64]) {
    let mut k = KahanPrefix::new(x.first().copied().unwrap_or(0.0));
    k.extend(x);
}

/// A running Kahan-compensated sum of `x − c`, carried from one slice to the next.
struct KahanPrefix {
    c: f64,
    sum: f64,
    comp: f64,
}

impl KahanPrefix {
    fn new(c: f64) -> Self {
        Self {
            c,
            sum: 0.0,
            comp: 0.0,
        }
    }

    /// Replaces each element of `x` by the running sum up to and including it.
    ///
    /// Two levels: within a chunk of [`PREFIX_CHUNK`] samples a plain running sum `local`
    /// (a few small roundings: the chunk's centred values are of the order of the noise), and
    /// the chunk totals are added Kahan-compensated into `sum`. Each stored value
    /// `sum + local` is then within about an ulp of the exact prefix, like a fully
    /// compensated sum, at a quarter of the dependency chain.
    fn extend(&mut self, x: &mut [f64]) {
        let (c, mut sum, mut comp) = (self.c, self.sum, self.comp);
        for chunk in x.chunks_mut(PREFIX_CHUNK) {
            let mut local = 0.0;
            for xi in chunk.iter_mut() {
                local += *xi - c;
                *xi = sum + local;
            }
            let y = local - comp;
            let t = sum + y;
            comp = (t - sum) - y;
            sum = t;
        }
        (self.sum, self.comp) = (sum, comp);
    }
}

/// Samples per plain-summed chunk of [`KahanPrefix::extend`].
const PREFIX_CHUNK: usize = 64;

/// Prefix sums with `P[0] = 0` (length n + 1), for `sig2_from_prefix` (tests only).
#[cfg(test)]
pub fn compensated_prefix(x: &[f64]) -> Vec<f64> {
    let mut p = Vec::with_capacity(x.len() + 1);
    p.push(0.0);
    p.extend_from_slice(x);
    prefix_in_place(&mut p[1..]);
    p
}

/// `sig2` for cluster size `m ≥ 1` from `compensated_prefix` output (length n + 1); one m
/// at a time (the reference for [`sig2_tiled`]; tests only).
#[cfg(test)]
pub fn sig2_from_prefix(prefix: &[f64], m: usize) -> f64 {
    let n = prefix.len() - 1;
    if m == 0 || m > n {
        return f64::NAN;
    }
    let k = n / m; // clusters
    let mf = m as f64;
    let mut prev = (prefix[m] - prefix[0]) / mf;
    let mut acc = 0.0;
    for c in 1..k {
        let mean = (prefix[(c + 1) * m] - prefix[c * m]) / mf;
        let d = mean - prev;
        acc += d * d;
        prev = mean;
    }
    (0.5 * (acc / (k - 1) as f64)).sqrt()
}

/// Prefix entries per tile of [`sig2_tiled`] (128 KiB: stays in L2 while every m walks it).
const TILE: usize = 16 * 1024;

/// `sig2` for every m in `ms` (ascending, ≥ 1) straight from the samples `x`, which are
/// overwritten by their prefix sums tile by tile, each tile walked while it is in cache.
pub fn sig2_prefix_fused(x: &mut [f64], ms: &[u64]) -> Vec<f64> {
    let mut k = KahanPrefix::new(x.first().copied().unwrap_or(0.0));
    walk_tiles(x, ms, |tile| k.extend(tile))
}

/// `sig2` for every m in `ms` (ascending, ≥ 1) from in-place prefix sums `p[i] = P[i+1]`.
///
/// Cache-blocked: the prefix array is walked tile by tile and every m takes its cluster
/// boundaries (multiples of m) inside the tile, so each tile comes from memory once instead
/// of once per m. Squared differences of block sums are accumulated and divided by m² at the
/// end. Matches `sig2_from_prefix` to rounding.
pub fn sig2_tiled(p: &mut [f64], ms: &[u64]) -> Vec<f64> {
    walk_tiles(p, ms, |_| {})
}

/// The tiled walk of [`sig2_tiled`]; `prepare` is called on each tile (`p` entries of the
/// tile) just before it is walked.
fn walk_tiles(p: &mut [f64], ms: &[u64], mut prepare: impl FnMut(&mut [f64])) -> Vec<f64> {
    let n = p.len();
    let mut st: Vec<TileWalk> = ms.iter().map(|&m| TileWalk::new(m as usize, n)).collect();
    let mut tile_start = 1;
    while tile_start <= n {
        let tile_end = (tile_start + TILE).min(n + 1);
        prepare(&mut p[tile_start - 1..tile_end - 1]);
        let p: &[f64] = p;
        for s in st.iter_mut() {
            s.walk(p, tile_end);
        }
        tile_start = tile_end;
    }
    st.iter()
        .map(|s| {
            let k = n.checked_div(s.m).unwrap_or(0);
            if k < 2 {
                return f64::NAN;
            }
            let mf = s.m as f64;
            (0.5 * (s.acc / (k - 1) as f64)).sqrt() / mf
        })
        .collect()
}

/// Where the walk of one m in [`walk_tiles`] stands between tiles.
struct TileWalk {
    m: usize,
    next: usize, // next boundary, in P numbering (P[next] = p[next-1])
    end: usize,  // last boundary K*m
    last_p: f64,
    last_b: f64,
    have_b: bool,
    acc: f64,
}

impl TileWalk {
    /// Before the first tile, for cluster size `m` on `n` prefix entries.
    fn new(m: usize, n: usize) -> Self {
        TileWalk {
            m,
            next: m.max(1),
            end: n.checked_div(m).unwrap_or(0) * m,
            last_p: 0.0, // P[0]
            last_b: 0.0,
            have_b: false,
            acc: 0.0,
        }
    }

    /// Walks this m's cluster boundaries inside the tile ending before P numbering
    /// `tile_end`, accumulating the squared differences of the block sums.
    #[inline]
    fn walk(&mut self, p: &[f64], tile_end: usize) {
        let s = self;
        let stop = (tile_end - 1).min(s.end);
        if s.next > stop {
            return;
        }
        let m = s.m;
        // Locals (registers) for the walk; four accumulators break the add chain.
        let (mut next, mut lp, mut lb) = (s.next, s.last_p, s.last_b);
        let (mut acc0, mut acc1, mut acc2, mut acc3) = (s.acc, 0.0, 0.0, 0.0);
        if !s.have_b {
            let pv = p[next - 1];
            lb = pv - lp;
            lp = pv;
            next += m;
            s.have_b = true;
        }
        while next + 3 * m <= stop {
            let p1 = p[next - 1];
            let p2 = p[next + m - 1];
            let p3 = p[next + 2 * m - 1];
            let p4 = p[next + 3 * m - 1];
            let (b1, b2, b3, b4) = (p1 - lp, p2 - p1, p3 - p2, p4 - p3);
            let (d1, d2, d3, d4) = (b1 - lb, b2 - b1, b3 - b2, b4 - b3);
            acc0 += d1 * d1;
            acc1 += d2 * d2;
            acc2 += d3 * d3;
            acc3 += d4 * d4;
            lb = b4;
            lp = p4;
            next += 4 * m;
        }
        while next <= stop {
            let pv = p[next - 1];
            let b = pv - lp;
            let d = b - lb;
            acc0 += d * d;
            lb = b;
            lp = pv;
            next += m;
        }
        s.next = next;
        s.last_p = lp;
        s.last_b = lb;
        s.acc = (acc0 + acc1) + (acc2 + acc3);
    }
}

/// `sig2` for cluster size `m` exactly as `allan.m` computes it (docs/upstream/kalibr_allan.md §2.1):
/// `D(1) = sum(x(1:m))/m` (sequential), `D(i) = D(i-1) + (x(i+m-1) - x(i-1))/m` for every
/// i up to n−m+1 (the recursion is replayed in full: it is what makes the rounding match),
/// then `sqrt(0.5*mean(diff(D(1:m:n-m+1)).^2))` with a sequential mean.
///
/// Mirrors Octave squaring a single difference with glibc `pow(d, 2)` when there are
/// exactly 2 clusters (docs/upstream/kalibr_allan.md §2.1; see `quirk_two_clusters_square_with_pow`).
pub(crate) fn sig2_recursive(x: &[f64], m: usize) -> f64 {
    let n = x.len();
    if m == 0 || m > n {
        return f64::NAN;
    }
    let mf = m as f64;
    let k = n / m;
    let mut d = x[..m].iter().fold(0.0, |s, &v| s + v) / mf;
    // The kept means are D(1), D(1+m), …: after D(1), every run of m recursion steps ends
    // on the next kept D. Steps i = 2 … n−m+1 (1-based) are replayed in full; the last
    // n − K·m steps only feed D values that are never kept, so they are skipped (they cannot
    // change any kept value).
    let mut prev = d;
    let mut acc = 0.0;
    let two = black_box(2.0_f64);
    let mut kept = 1;
    for c in 1..k {
        // Steps i = 2+(c−1)m … 1+cm use x(i+m−1) − x(i−1), i.e. 0-based x[i+m−2] − x[i−2].
        let lo = &x[(c - 1) * m..c * m];
        let hi = &x[c * m..(c + 1) * m];
        for (&h, &l) in hi.iter().zip(lo) {
            d += (h - l) / mf;
        }
        let diff = d - prev;
        acc += if k == 2 { diff.powf(two) } else { diff * diff };
        prev = d;
        kept += 1;
    }
    debug_assert_eq!(kept, k);
    (0.5 * (acc / (k - 1) as f64)).sqrt()
}

/// The slow, obviously-correct `sig2`: sum each of the K blocks directly, take the mean,
/// average the squared differences of consecutive means. O(n) per m; tests only.
#[cfg(test)]
pub fn sig2_oracle(x: &[f64], m: usize) -> f64 {
    if m == 0 || m > x.len() {
        return f64::NAN;
    }
    let means: Vec<f64> = x
        .chunks_exact(m)
        .map(|b| b.iter().sum::<f64>() / m as f64)
        .collect();
    let diffs: Vec<f64> = means.windows(2).map(|w| (w[1] - w[0]).powi(2)).collect();
    (0.5 * diffs.iter().sum::<f64>() / diffs.len() as f64).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Seed of the test signal generator.
    const RNG_SEED: u64 = 0x5eed_a11a;
    /// Oracle vs fast paths on well-conditioned data: a few ulp per operation, summed.
    const ORACLE_REL_TOL: f64 = 1e-10;

    /// Small deterministic generator (splitmix64 → uniform → sum of 4 for a rough bell).
    fn signal(n: usize, offset: f64, walk: f64) -> Vec<f64> {
        let mut s = RNG_SEED;
        let mut next = || {
            s = s.wrapping_add(0x9e37_79b9_7f4a_7c15);
            let mut z = s;
            z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
            ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        let mut bias = 0.0;
        (0..n)
            .map(|_| {
                bias += walk * next();
                offset + bias + (next() + next() + next() + next()) * 0.3
            })
            .collect()
    }

    fn rel(a: f64, b: f64) -> f64 {
        ((a - b) / b).abs()
    }

    #[test]
    fn fast_and_recursive_agree_with_oracle() {
        let x = signal(5003, 9.81, 0.01);
        let prefix = compensated_prefix(&x);
        for m in [1, 2, 3, 7, 50, 333, 1000, 1667, 2501] {
            let o = sig2_oracle(&x, m);
            let f = sig2_from_prefix(&prefix, m);
            let r = sig2_recursive(&x, m);
            assert!(rel(f, o) < ORACLE_REL_TOL, "m={m}: fast {f} oracle {o}");
            assert!(
                rel(r, o) < ORACLE_REL_TOL,
                "m={m}: recursive {r} oracle {o}"
            );
        }
    }

    #[test]
    fn tiled_matches_single_m_over_tile_boundaries() {
        // Longer than several tiles, with m values that straddle tile edges.
        let x = signal(3 * TILE + 777, 9.81, 0.01);
        let prefix = compensated_prefix(&x);
        let ms: Vec<u64> = vec![1, 2, 3, 5, 8, 13, 999, 4096, 16_385, 20_000, 24_000];
        let mut p = x.clone();
        prefix_in_place(&mut p);
        let tiled = sig2_tiled(&mut p, &ms);
        let fused = sig2_prefix_fused(&mut x.clone(), &ms);
        assert_eq!(
            tiled, fused,
            "fused prefix+walk must equal prefix then walk"
        );
        for (j, &m) in ms.iter().enumerate() {
            let single = sig2_from_prefix(&prefix, m as usize);
            let o = sig2_oracle(&x, m as usize);
            assert!(
                rel(tiled[j], single) < ORACLE_REL_TOL,
                "m={m}: tiled {} single {single}",
                tiled[j]
            );
            assert!(
                rel(tiled[j], o) < ORACLE_REL_TOL,
                "m={m}: tiled {} oracle {o}",
                tiled[j]
            );
        }
    }

    /// The hard case of docs/upstream/kalibr_allan.md §2: a low-noise axis carrying gravity, many samples, large m.
    /// The prefix-sum path must stay accurate there (the reference's own recursion does
    /// not); checked against block means of `x − x[0]` summed with Kahan compensation.
    #[test]
    fn fast_path_accurate_on_low_noise_gravity_axis() {
        /// Both sides are accurate to a few ulp of the block sums; the differences of two
        /// block means are ~1e-6 of them at the largest m, so 1e-9 leaves a wide margin.
        const LOW_NOISE_REL_TOL: f64 = 1e-9;
        let x: Vec<f64> = signal(400_000, 0.0, 0.0)
            .iter()
            .map(|v| 9.81 + v * 1e-4)
            .collect();
        let ms: Vec<u64> = vec![1, 2, 7, 100, 1000, 10_000, 100_000, 199_999];
        let fast = sig2_prefix_fused(&mut x.clone(), &ms);
        for (j, &m) in ms.iter().enumerate() {
            let m = m as usize;
            let means: Vec<f64> = x
                .chunks_exact(m)
                .map(|b| {
                    let (mut sum, mut comp) = (0.0_f64, 0.0_f64);
                    for &v in b {
                        let y = (v - x[0]) - comp;
                        let t = sum + y;
                        comp = (t - sum) - y;
                        sum = t;
                    }
                    sum / m as f64
                })
                .collect();
            let d2: f64 = means.windows(2).map(|w| (w[1] - w[0]).powi(2)).sum();
            let want = (0.5 * d2 / (means.len() - 1) as f64).sqrt();
            assert!(
                rel(fast[j], want) < LOW_NOISE_REL_TOL,
                "m={m}: fast {} reference {want} rel {:e} tol {LOW_NOISE_REL_TOL:e}",
                fast[j],
                rel(fast[j], want)
            );
        }
    }

    #[test]
    fn oracle_matches_hand_computed_value() {
        // Blocks of m=2: means 1.5, 3.5, 5.5 → diffs 2, 2 → sqrt(0.5*4) = sqrt(2).
        let x = [1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 100.0];
        assert_eq!(sig2_oracle(&x, 2), 2.0_f64.sqrt());
        assert_eq!(sig2_recursive(&x, 2), 2.0_f64.sqrt());
        assert_eq!(sig2_from_prefix(&compensated_prefix(&x), 2), 2.0_f64.sqrt());
        let mut p = x.to_vec();
        prefix_in_place(&mut p);
        assert_eq!(sig2_tiled(&mut p, &[2]), vec![2.0_f64.sqrt()]);
    }

    #[test]
    fn m_zero_is_nan() {
        let x = signal(100, 0.0, 0.0);
        assert!(sig2_recursive(&x, 0).is_nan());
        assert!(sig2_from_prefix(&compensated_prefix(&x), 0).is_nan());
        assert!(sig2_oracle(&x, 0).is_nan());
    }

    /// Mirrors Octave's `diff(D).^2` on a one-element array going through glibc `pow(d, 2)`
    /// (docs/upstream/kalibr_allan.md §2.1): with exactly 2 clusters the square is `pow(d, 2)`, which for
    /// this d is one ulp away from d*d, and the difference survives the sqrt.
    #[test]
    fn quirk_two_clusters_square_with_pow() {
        // Found by a random search: about 1 in 2400 doubles differ this way after the sqrt.
        let d = -0.06937708308698594_f64;
        let with_pow = 0.04905700590975029_f64; // sqrt(0.5*pow(d,2)) with glibc pow
        let with_mul = 0.0490570059097503_f64; // sqrt(0.5*(d*d))
        assert_ne!(with_pow, with_mul);
        assert_eq!((0.5 * (d * d)).sqrt(), with_mul);
        // x = [0, d], m = 1: D = [0, d], K = 2, one difference d.
        assert_eq!(sig2_recursive(&[0.0, d], 1), with_pow);
        // With 3 clusters the squares are products again: [0, d, 0] → diffs d, −d.
        assert_eq!(
            sig2_recursive(&[0.0, d, 0.0], 1),
            (0.5 * ((d * d + d * d) / 2.0)).sqrt()
        );
        // And on noise with K = 2 it still agrees with the oracle to rounding.
        let x = signal(1001, 9.81, 0.0);
        let (r, o) = (sig2_recursive(&x, 400), sig2_oracle(&x, 400));
        assert!(rel(r, o) < ORACLE_REL_TOL, "recursive {r} oracle {o}");
    }

    #[test]
    fn curves_expand_duplicates_and_nan() {
        let axes: [Vec<f64>; 6] = std::array::from_fn(|a| signal(2000 + a, a as f64, 0.0));
        let axes: [Vec<f64>; 6] = std::array::from_fn(|a| axes[a][..2000].to_vec());
        let grid = TauGrid::new(2000, 100.0).unwrap();
        for est in [Estimator::PrefixSum, Estimator::BitExact] {
            let c = sig2_curves(axes.clone(), &grid, est, &|| {});
            for a in 0..6 {
                for (i, &m) in grid.m.iter().enumerate() {
                    let o = sig2_oracle(&axes[a], m as usize);
                    if m == 0 {
                        assert!(c[a][i].is_nan(), "{est:?} axis {a} index {i}");
                    } else {
                        assert!(
                            rel(c[a][i], o) < ORACLE_REL_TOL,
                            "{est:?} axis {a} index {i} m {m}: got {} oracle {o}",
                            c[a][i]
                        );
                    }
                }
            }
        }
    }
}
