//! The cluster-size grid ("factors") of imu_utils: `max_cluster` log-spaced sizes from 1 to the
//! largest power of two ≤ N/2, rounded up and de-duplicated.
//!
//! Mirrors imu_utils `2cdda91` `AllanGyr::initStrides` + `getLogSpace` (docs/upstream/imu_utils.md §3.4),
//! including its single-precision quirks: the end exponent is passed as a `float`, the step
//! exponent is a `float` division, and the grid is a cumulative product. Because of that the
//! last factor can be `maxStride + 1` (quirk tests below).

/// Largest power of two ≤ n/2 (1 when n < 4), by upstream's integer halving loop.
pub fn max_stride(n: usize) -> usize {
    let mut mode = n / 2;
    let mut max_stride = 1usize;
    let mut shft = 0u32;
    while mode != 0 {
        mode >>= 1;
        max_stride = 1usize << shft;
        shft += 1;
    }
    max_stride
}

/// The raw (not yet rounded) log-spaced values, `max_cluster` of them.
pub fn raw_log_space(n: usize, max_cluster: usize) -> Vec<f64> {
    // `getLogSpace(float a, float b)` receives log10(maxStride) rounded to f32.
    let b = (max_stride(n) as f64).log10() as f32 as f64;
    let start = 10f64.powf(0.0);
    let end = 10f64.powf(b);
    // `(float)1 / (numCluster - 1)`: a float division, then promoted for pow().
    let expo = (1.0f32 / (max_cluster as f32 - 1.0)) as f64;
    let prog = (end / start).powf(expo);
    let mut ls = Vec::with_capacity(max_cluster);
    if max_cluster == 0 {
        return ls;
    }
    ls.push(start);
    for i in 1..max_cluster {
        ls.push(ls[i - 1] * prog);
    }
    ls
}

/// The cluster sizes m used for the Allan variance of `n` samples.
pub fn factors(n: usize, max_cluster: usize) -> Vec<usize> {
    let ls: Vec<f64> = raw_log_space(n, max_cluster)
        .into_iter()
        .map(f64::ceil)
        .collect();
    let mut out = Vec::with_capacity(ls.len());
    for (i, &v) in ls.iter().enumerate() {
        if i == 0 || v != ls[i - 1] {
            out.push(v as usize);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The table of docs/upstream/imu_utils.md §3.4 (verified there against the upstream implementation).
    #[test]
    fn spec_table_of_grids() {
        let rows: &[(usize, usize, usize, usize, Option<usize>)] = &[
            (1_440_002, 100, 524_288, 92, Some(524_288)),
            (720_002, 100, 262_144, 91, Some(262_145)),
            (2_880_002, 100, 1_048_576, 93, Some(1_048_576)),
            (168_002, 100, 65_536, 89, Some(65_537)),
            (66_002, 100, 32_768, 88, Some(32_769)),
            (354_002, 100, 131_072, 90, Some(131_072)),
            (12_200, 100, 4_096, 82, Some(4_097)),
            (12_201, 100, 4_096, 82, Some(4_097)),
            (1_440_002, 50, 524_288, 48, None),
            (1_440_002, 200, 524_288, 174, None),
        ];
        for &(n, m, ms, count, last) in rows {
            assert_eq!(max_stride(n), ms, "maxStride for N={n}");
            let f = factors(n, m);
            assert_eq!(f.len(), count, "numFactors for N={n}, M={m}");
            if let Some(last) = last {
                assert_eq!(*f.last().unwrap(), last, "last factor for N={n}, M={m}");
            }
        }
    }

    /// docs/upstream/imu_utils.md §3.4: the raw last value is not exactly maxStride because of the f32
    /// exponent; for N = 168 002 it is 65536.0339, so the grid ends at maxStride + 1.
    #[test]
    fn quirk_f32_exponent_last_factor_can_be_max_stride_plus_one() {
        let raw = raw_log_space(168_002, 100);
        let last = *raw.last().unwrap();
        assert!((last - 65536.0339).abs() < 1e-4, "raw last {last}");
        assert_eq!(*factors(168_002, 100).last().unwrap(), 65_537);
        let raw = raw_log_space(1_440_002, 100);
        assert!((raw[99] - 524287.7104).abs() < 1e-4, "raw last {}", raw[99]);
    }

    #[test]
    fn tiny_inputs() {
        assert_eq!(factors(2, 100), vec![1]);
        assert_eq!(factors(1_440_002, 1), vec![1]);
        let f = factors(168_002, 100);
        assert_eq!(
            &f[..18],
            &[
                1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 14, 15, 17, 19, 21, 24
            ]
        );
        assert!(f.windows(2).all(|w| w[0] < w[1]));
    }
}
