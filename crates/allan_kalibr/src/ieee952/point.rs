//! One point of the analysed Allan deviation curve: the estimate, its bands and the EDF
//! behind them, and the fitted model there. Its own module because both the verdicts
//! (`result`) and the IEEE 952 region readings (`region`) are made from points, and the
//! result holds the readings.

/// Where a point's EDF (and the α printed beside it) came from (the `band` module: the
/// fitted model's mixture, else the curve's slope).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AlphaSource {
    /// The declared fit's model: the exact variance of the estimate under its mixture of
    /// terms; α is its dominant term's.
    Model,
    /// No model describes the curve: Greenhall's EDF of the FM power law of the curve's
    /// local slope there, α.
    CurveSlope,
}

/// One point of the analysed Allan deviation curve.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Point {
    /// Cluster size in samples.
    pub m: usize,
    /// τ = m·τ0 in seconds.
    pub tau: f64,
    /// Allan variance, U².
    pub avar: f64,
    /// Allan deviation, U.
    pub adev: f64,
    /// Lower bound of the deviation at `Config::curve_confidence`, U (NaN: no sample count).
    pub lo: f64,
    /// Upper bound of the deviation at `Config::curve_confidence`, U.
    pub hi: f64,
    /// Lower bound at 95 %, U.
    pub lo95: f64,
    /// Upper bound at 95 %, U.
    pub hi95: f64,
    /// Equivalent degrees of freedom of the estimate behind the bounds (see `alpha_source`).
    pub edf: f64,
    /// Power-law α of the point's dominant noise (see `alpha_source`).
    pub alpha: i32,
    /// Where α came from.
    pub alpha_source: AlphaSource,
    /// Inside the fitted range.
    pub in_range: bool,
    /// Fitted model deviation at this τ (NaN without a fit).
    pub model: f64,
}
