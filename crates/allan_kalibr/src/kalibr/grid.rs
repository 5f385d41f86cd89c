//! The 2000-point τ grid of `SCRIPT_allan_matparallel.m`, built with the same float
//! operations as upstream so that every cluster size `m` comes out identical.
//!
//! Upstream (rpng/kalibr_allan `9d38ea9`, spec docs/upstream/kalibr_allan.md §2 and §8 items 4–6):
//! `delta = 1/update_rate`, `taumax = floor((N-1)/2)`,
//! `tau = delta*logspace(log10(delta), log10(taumax), 2000)`, then in `allan.m`
//! `m = floor(tau*rate)` and `tau1 = m/rate`. The grid therefore starts at δ² (issue #25),
//! holds m = 0 points (NaN results), duplicate m values, and a last point that is taumax or
//! taumax − 1 depending on how `10^log10(taumax)` rounds.

use std::hint::black_box;

use crate::error::Error;

/// Number of τ points upstream always uses (`logspace(…, 2000)`).
pub const GRID_POINTS: usize = 2000;

/// The τ grid of one run: per grid point the cluster size `m` and `tau1 = m/rate`.
#[derive(Debug, Clone, PartialEq)]
pub struct TauGrid {
    /// `update_rate` in Hz, as given (it drives the grid; timestamps do not).
    pub rate: f64,
    /// Number of samples N the grid was built for.
    pub n: usize,
    /// `floor((N-1)/2)`, the largest cluster size upstream asks for.
    pub taumax: u64,
    /// Cluster size per grid point (0 for τ·rate < 1), non-decreasing, with duplicates.
    pub m: Vec<u64>,
    /// `m/rate` per grid point: the x axis of every later step (0 where m = 0).
    pub tau1: Vec<f64>,
}

impl TauGrid {
    /// Builds the grid for `n` samples at `rate` Hz.
    ///
    /// Errors where upstream crashes or produces only garbage: `n < 3` (taumax < 1, so
    /// `log10(taumax)` is −Inf or complex) or a rate that is not finite and positive.
    pub fn new(n: usize, rate: f64) -> Result<Self, Error> {
        if !(rate.is_finite() && rate > 0.0) {
            return Err(Error::BadRate(rate));
        }
        if n < 3 {
            return Err(Error::TooShort { n });
        }
        let taumax = ((n - 1) / 2) as u64;
        let delta = 1.0 / rate;
        let exponents = matlab_linspace(delta.log10(), (taumax as f64).log10(), GRID_POINTS);
        // `black_box` keeps LLVM from rewriting pow(10, x) into exp10(x), which can round
        // differently from glibc's pow that Octave/MATLAB call for `10.^x`.
        let ten = black_box(10.0_f64);
        let m: Vec<u64> = exponents
            .iter()
            .map(|&l| {
                let tau = delta * ten.powf(l);
                // floor of a non-negative finite value: the cast is exact.
                (tau * rate).floor() as u64
            })
            .collect();
        let tau1 = m.iter().map(|&mi| mi as f64 / rate).collect();
        Ok(Self {
            rate,
            n,
            taumax,
            m,
            tau1,
        })
    }

    /// Number of grid points with m = 0 (all NaN upstream).
    pub fn m0_count(&self) -> usize {
        self.m.iter().filter(|&&m| m == 0).count()
    }

    /// The distinct non-zero cluster sizes, ascending (each is computed once).
    pub fn distinct_m(&self) -> Vec<u64> {
        let mut v: Vec<u64> = self.m.iter().copied().filter(|&m| m > 0).collect();
        v.dedup(); // the grid is non-decreasing, so dedup removes every repeat
        v
    }

    /// Cluster size of the last grid point (`taumax` or `taumax − 1`, the knife edge).
    pub fn m_end(&self) -> u64 {
        *self.m.last().expect("grid has GRID_POINTS > 0 points")
    }
}

/// MATLAB's `linspace(d1, d2, n)`: `d1 + (i*(d2-d1))/(n-1)` with both end points set
/// exactly (docs/upstream/kalibr_allan.md §2 "The m grid"; Octave's symmetric formula gives the same m on
/// every case in §7, MATLAB's is the contract).
pub(crate) fn matlab_linspace(d1: f64, d2: f64, n: usize) -> Vec<f64> {
    let n1 = (n - 1) as f64;
    let mut v: Vec<f64> = (0..n).map(|i| d1 + (i as f64 * (d2 - d1)) / n1).collect();
    if let Some(first) = v.first_mut() {
        *first = d1;
    }
    if let Some(last) = v.last_mut() {
        *last = d2;
    }
    v
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Grid facts computed from the formulas alone (docs/upstream/kalibr_allan.md §7, second table):
    /// (N, rate, taumax, m_end, m0 count, distinct m ≥ 1).
    const FORMULA_CASES: [(usize, f64, u64, u64, usize, usize); 8] = [
        (180_000, 200.0, 89_999, 89_999, 634, 912),
        (72_000, 100.0, 35_999, 35_999, 610, 874),
        (12_200, 200.0, 6_099, 6_099, 756, 678),
        (360_000, 100.0, 179_999, 179_998, 552, 995),
        (720_000, 200.0, 359_999, 359_998, 586, 1004),
        (720_000, 100.0, 359_999, 359_998, 530, 1039),
        (2_880_000, 200.0, 1_439_999, 1_439_999, 544, 1082),
        (5_760_000, 400.0, 2_879_999, 2_879_999, 575, 1083),
    ];

    #[test]
    fn grid_facts_match_spec_table() {
        for (n, rate, taumax, m_end, m0, distinct) in FORMULA_CASES {
            let g = TauGrid::new(n, rate).unwrap();
            assert_eq!(g.m.len(), GRID_POINTS);
            assert_eq!(g.taumax, taumax, "N={n} rate={rate}: taumax");
            assert_eq!(g.m_end(), m_end, "N={n} rate={rate}: m_end");
            assert_eq!(g.m0_count(), m0, "N={n} rate={rate}: m=0 count");
            assert_eq!(
                g.distinct_m().len(),
                distinct,
                "N={n} rate={rate}: distinct m"
            );
        }
    }

    /// Mirrors kalibr_allan `9d38ea9` SCRIPT_allan_matparallel.m, issue #25: the grid starts
    /// at δ² (τ·rate = δ < 1 → m = 0), and all m = 0 points come first.
    #[test]
    fn quirk_25_grid_starts_at_delta_squared() {
        let g = TauGrid::new(180_000, 200.0).unwrap();
        assert_eq!(g.m[0], 0);
        let m0 = g.m0_count();
        assert!(g.m[..m0].iter().all(|&m| m == 0));
        assert!(g.m[m0..].iter().all(|&m| m >= 1));
        assert!(
            g.m.windows(2).all(|w| w[0] <= w[1]),
            "grid must be non-decreasing"
        );
    }

    /// Mirrors the knife-edge last point (docs/upstream/kalibr_allan.md §2): 10^log10(taumax) rounds
    /// below taumax for 179999 (p4, m_end = taumax − 1) but not for 89999 (p1).
    #[test]
    fn quirk_knife_edge_last_point() {
        assert_eq!(TauGrid::new(360_000, 100.0).unwrap().m_end(), 179_998);
        assert_eq!(TauGrid::new(180_000, 200.0).unwrap().m_end(), 89_999);
    }

    #[test]
    fn too_short_and_bad_rate_are_errors() {
        assert!(matches!(
            TauGrid::new(2, 200.0),
            Err(Error::TooShort { n: 2 })
        ));
        assert!(matches!(
            TauGrid::new(0, 200.0),
            Err(Error::TooShort { n: 0 })
        ));
        assert!(TauGrid::new(3, 200.0).is_ok());
        assert!(matches!(TauGrid::new(100, 0.0), Err(Error::BadRate(_))));
        assert!(matches!(
            TauGrid::new(100, f64::NAN),
            Err(Error::BadRate(_))
        ));
    }

    #[test]
    fn linspace_end_points_exact() {
        let v = matlab_linspace(-2.3, 5.1, 2000);
        assert_eq!(v[0], -2.3);
        assert_eq!(v[1999], 5.1);
        assert_eq!(v.len(), 2000);
    }
}
