//! Log-spaced grid of distinct cluster sizes m.
//!
//! m_k = round(2^(k/p)) for k = 0, 1, …, de-duplicated, so short τ are not repeated (the
//! kalibr_allan grid spends a full pass on each repeated or zero m). The grid stops at
//! m_max = ⌊n / min_clusters⌋: with at least `min_clusters` disjoint clusters there are at
//! least `min_clusters − 1` independent second differences. The default 4 matches where
//! Stable32 stops its all-τ table (OCXO file: n = 19 982, last m = 4 929 ≤ n/4). Points
//! near m_max have very few degrees of freedom; the EDF carries that into the intervals
//! and the fit weights.

/// How dense and how long the grid is.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GridSpec {
    /// Points per octave of τ (≥ 1).
    pub per_octave: u32,
    /// Smallest number of disjoint clusters ⌊n/m⌋ a grid point must leave (≥ 3).
    pub min_clusters: usize,
}

impl Default for GridSpec {
    fn default() -> Self {
        GridSpec {
            per_octave: 8,
            min_clusters: 4,
        }
    }
}

impl GridSpec {
    /// Largest cluster size for n rate samples.
    pub(crate) fn m_max(&self, n: usize) -> usize {
        n / self.min_clusters.max(3)
    }

    /// Distinct ascending cluster sizes for n rate samples (empty when n < 3·min_clusters).
    pub fn cluster_sizes(&self, n: usize) -> Vec<usize> {
        let m_max = self.m_max(n);
        let p = self.per_octave.max(1) as f64;
        let mut out: Vec<usize> = Vec::new();
        let mut k = 0u32;
        loop {
            let m = (2f64.powf(k as f64 / p)).round() as usize;
            if m > m_max {
                break;
            }
            if out.last() != Some(&m) {
                out.push(m);
            }
            k += 1;
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn distinct_ascending_bounded() {
        for &n in &[0usize, 11, 12, 100, 19_982, 2_880_000] {
            for p in [1u32, 3, 8, 16] {
                let spec = GridSpec {
                    per_octave: p,
                    min_clusters: 4,
                };
                let g = spec.cluster_sizes(n);
                assert!(
                    g.windows(2).all(|w| w[0] < w[1]),
                    "n={n} p={p}: not strictly ascending: {g:?}"
                );
                if let Some(&last) = g.last() {
                    assert!(
                        n / last >= 4,
                        "n={n} p={p}: last m={last} leaves {} clusters",
                        n / last
                    );
                    assert_eq!(g[0], 1);
                    // the next grid value would break the bound: the grid reaches within one step of m_max
                    let step = 2f64.powf(1.0 / p as f64);
                    assert!(
                        last as f64 * step * step > spec.m_max(n) as f64,
                        "n={n} p={p}: grid stops early at {last}"
                    );
                } else {
                    assert!(n < 4, "n={n}: empty grid");
                }
            }
        }
    }

    #[test]
    fn octave_grid_is_powers_of_two() {
        let g = GridSpec {
            per_octave: 1,
            min_clusters: 4,
        }
        .cluster_sizes(241_217);
        let want: Vec<usize> = (0..=15).map(|k| 1usize << k).collect();
        assert_eq!(g, want);
    }
}
