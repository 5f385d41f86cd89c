//! Chi-square confidence interval of an Allan deviation from its equivalent degrees of freedom.
//!
//! With σ̂² ~ σ²·χ²(ν)/ν, the two-sided interval at confidence c is
//! σ̂·√(ν/χ²_{(1+c)/2}(ν)) ≤ σ ≤ σ̂·√(ν/χ²_{(1−c)/2}(ν)) (Stable32's Min/Max Sigma at c = 0.683).

use statrs::distribution::{ChiSquared, ContinuousCDF};

/// Above this many degrees of freedom the χ² quantiles come from the Wilson–Hilferty cube
/// (relative error < 1e-6 there, see the tests) instead of statrs' iterative inverse, which
/// is the costly part of bounding a long record's curve.
pub const WILSON_HILFERTY_MIN_EDF: f64 = 1e4;

/// The χ² quantile at probability p.
fn chi2_quantile(edf: f64, p: f64) -> Option<f64> {
    if edf >= WILSON_HILFERTY_MIN_EDF {
        let z = statrs::distribution::Normal::new(0.0, 1.0)
            .ok()?
            .inverse_cdf(p);
        let a = 2.0 / (9.0 * edf);
        return Some(edf * (1.0 - a + z * a.sqrt()).powi(3));
    }
    Some(ChiSquared::new(edf).ok()?.inverse_cdf(p))
}

/// Lower and upper bound of the deviation σ (same unit as `dev`). `None` if `edf` ≤ 0, not
/// finite, or `confidence` not in (0, 1).
pub fn chi2_interval(dev: f64, edf: f64, confidence: f64) -> Option<(f64, f64)> {
    if !(edf > 0.0 && edf.is_finite() && confidence > 0.0 && confidence < 1.0) {
        return None;
    }
    let upper_q = chi2_quantile(edf, 0.5 + confidence / 2.0)?;
    let lower_q = chi2_quantile(edf, 0.5 - confidence / 2.0)?;
    if !(upper_q > 0.0 && lower_q > 0.0) {
        return None;
    }
    Some((dev * (edf / upper_q).sqrt(), dev * (edf / lower_q).sqrt()))
}

/// The one-sided upper limit of the deviation σ at confidence `confidence` (σ̂·√(ν/χ²_{1−c}(ν))).
/// `None` as [`chi2_interval`].
pub fn chi2_upper(dev: f64, edf: f64, confidence: f64) -> Option<f64> {
    if !(edf > 0.0 && edf.is_finite() && confidence > 0.0 && confidence < 1.0) {
        return None;
    }
    let q = chi2_quantile(edf, 1.0 - confidence)?;
    (q > 0.0).then(|| dev * (edf / q).sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// statrs' inverse CDF is iterative; its round trip through the CDF must hold tightly.
    const ROUND_TRIP_TOL: f64 = 1e-9;
    /// Wilson–Hilferty is accurate to O(1/ν) in the quantile; at ν = 1e5 that is < 1e-6 relative.
    const WH_REL_TOL: f64 = 1e-5;

    #[test]
    fn quantiles_round_trip_and_match_wilson_hilferty() {
        for &nu in &[1.5, 3.0, 8.9, 42.2, 962.6, 124_054.2, 2.0e6] {
            let chi = ChiSquared::new(nu).unwrap();
            for &p in &[0.025, 0.1585, 0.8415, 0.975] {
                let q = chi.inverse_cdf(p);
                assert!(
                    (chi.cdf(q) - p).abs() < ROUND_TRIP_TOL,
                    "nu={nu} p={p}: cdf(q)={}",
                    chi.cdf(q)
                );
                if nu > 1e4 {
                    // z from the normal quantile via statrs
                    let z = statrs::distribution::Normal::new(0.0, 1.0)
                        .unwrap()
                        .inverse_cdf(p);
                    let a = 2.0 / (9.0 * nu);
                    let wh = nu * (1.0 - a + z * a.sqrt()).powi(3);
                    assert!(
                        (q / wh - 1.0).abs() < WH_REL_TOL,
                        "nu={nu} p={p}: statrs {q}, WH {wh}"
                    );
                }
            }
        }
    }

    /// The Wilson–Hilferty branch against statrs' exact quantiles just above its threshold.
    const WH_BRANCH_REL_TOL: f64 = 1e-6;

    #[test]
    fn wilson_hilferty_branch_matches_exact() {
        for &nu in &[WILSON_HILFERTY_MIN_EDF, 3e4, 1e6] {
            for &p in &[0.025, 0.1585, 0.8415, 0.975] {
                let exact = ChiSquared::new(nu).unwrap().inverse_cdf(p);
                let wh = chi2_quantile(nu, p).unwrap();
                assert!(
                    (wh / exact - 1.0).abs() < WH_BRANCH_REL_TOL,
                    "nu={nu} p={p}: {wh} vs {exact}"
                );
            }
        }
    }

    #[test]
    fn interval_brackets_and_narrows() {
        let (lo, hi) = chi2_interval(1.0, 10.0, 0.683).unwrap();
        assert!(lo < 1.0 && hi > 1.0);
        let (lo2, hi2) = chi2_interval(1.0, 1000.0, 0.683).unwrap();
        assert!(lo2 > lo && hi2 < hi);
        let (lo3, hi3) = chi2_interval(1.0, 10.0, 0.95).unwrap();
        assert!(lo3 < lo && hi3 > hi);
        assert!(chi2_interval(1.0, 0.0, 0.683).is_none());
        assert!(chi2_interval(1.0, 10.0, 1.0).is_none());
    }
}
