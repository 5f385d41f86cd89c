//! The offline part of imu_utils' run on collected samples (imu_utils.md §3–4): per axis the
//! `calc()` quantities (period, factors, taus, Allan variances), the gyro means, then the six
//! fits. Gyro then acc, x, y, z, as upstream.

use rayon::prelude::*;

use crate::collect::Collected;
use crate::error::Error;
use crate::estimator;
use crate::factors;
use crate::fit::{AxisFit, Sensor};

/// Upstream's accumulator names, in creation order.
pub const AXIS_NAMES: [&str; 6] = ["gyr x", "gyr y", "gyr z", "acc x", "acc y", "acc z"];

/// The fit has five parameters, so it needs at least this many Allan points with data.
pub const MIN_VALID_POINTS: usize = 5;

/// What `calc()` computes for one axis.
#[derive(Debug, Clone)]
pub struct AxisAllan {
    /// Upstream name (`gyr x` …).
    pub name: &'static str,
    /// Samples.
    pub n: usize,
    /// First and last stamp (s).
    pub start_t: f64,
    /// Last stamp (s).
    pub end_t: f64,
    /// Mean-period frequency (Hz) and period (s).
    pub freq: f64,
    /// Mean period (s).
    pub period: f64,
    /// Cluster sizes.
    pub factors: Vec<usize>,
    /// Cluster times (s).
    pub taus: Vec<f64>,
    /// Allan variances (pseudo-(deg/h)² or (m/s²)²).
    pub variance: Vec<f64>,
}

impl AxisAllan {
    /// Allan deviations (`getDeviation`).
    pub fn deviation(&self) -> Vec<f64> {
        self.variance.iter().map(|v| v.sqrt()).collect()
    }
}

/// The Allan step alone, all six axes (the part the benchmark times), plus the gyro means
/// (`getAvgValue`: the same sequential sum θ is built from, over N). Fails on the first
/// non-finite value.
pub fn allan_step(
    c: &Collected<'_>,
    max_cluster: usize,
) -> Result<(Vec<AxisAllan>, [f64; 3]), Error> {
    let n = c.len();
    let period = estimator::mean_period(&c.t);
    let freq = 1.0 / period;
    let f = factors::factors(n, max_cluster);
    let taus = estimator::taus(period, &f);
    // θ for all axes at once, straight from the bag rows (one sequential cumulative sum
    // each), then one axis at a time so its θ stays in cache while the factors run in
    // parallel.
    let integrated: Vec<(Vec<f64>, f64, Option<usize>)> = (0..6usize)
        .into_par_iter()
        .map(|axis| match axis {
            0..3 => estimator::thetas_checked(c.gyro_values(axis), n, freq),
            _ => estimator::thetas_checked(c.acc_values(axis - 3), n, freq),
        })
        .collect();
    if let Some((axis, index)) = integrated
        .iter()
        .enumerate()
        .filter_map(|(a, (_, _, bad))| bad.map(|i| (a, i)))
        .min_by_key(|&(a, i)| (i, a))
    {
        return Err(c.non_finite(axis, index));
    }
    let gyro_mean = [0, 1, 2].map(|k| integrated[k].1 / n as f64);
    let axes = integrated
        .iter()
        .zip(AXIS_NAMES)
        .map(|((theta, _, _), name)| AxisAllan {
            name,
            n,
            start_t: c.t[0],
            end_t: c.t[n - 1],
            freq,
            period,
            factors: f.clone(),
            taus: taus.clone(),
            variance: estimator::allan_variance(theta, &f, period),
        })
        .collect();
    Ok((axes, gyro_mean))
}

/// Everything the outputs are made of.
#[derive(Debug, Clone)]
pub struct Analysis {
    /// `max_cluster` as given.
    pub max_cluster: usize,
    /// The six axes: gyr x, y, z, acc x, y, z.
    pub axes: Vec<AxisAllan>,
    /// Gyro means in pseudo-deg/h (`getAvgValue`).
    pub gyro_mean: [f64; 3],
    /// The six fits, same order as `axes`.
    pub fits: Vec<AxisFit>,
}

/// Fails with [`Error::TooFewSamples`] unless the grid has [`MIN_VALID_POINTS`] factors with
/// N − 2m > 0, and when the stamps give no positive mean period (upstream would print NaNs).
pub fn check_enough(c: &Collected<'_>, max_cluster: usize) -> Result<(), Error> {
    let n = c.len();
    // Cluster sizes are distinct integers m with N > 2m: more than N/2 of them cannot exist,
    // and a larger request would only size memory and time by a number the data cannot use.
    // (The shipped default never trips this: a short record gets "too few samples".)
    let allowed = (n / 2).max(crate::cli::DEFAULT_MAX_CLUSTER);
    if max_cluster > allowed {
        return Err(Error::Config(format!(
            "--max-cluster {max_cluster} exceeds what {n} samples allow (at most {allowed}: cluster sizes m need N > 2m)"
        )));
    }
    let valid = if n < 2 {
        0
    } else {
        factors::factors(n, max_cluster)
            .iter()
            .filter(|&&m| n > 2 * m)
            .count()
    };
    if valid < MIN_VALID_POINTS {
        return Err(Error::TooFewSamples {
            topic: c.topic().to_string(),
            n,
            valid,
            needed: MIN_VALID_POINTS,
        });
    }
    let period = estimator::mean_period(&c.t);
    if !(period.is_finite() && period > 0.0) {
        return Err(Error::BadStamps {
            topic: c.topic().to_string(),
            period,
            n,
        });
    }
    Ok(())
}

/// The six fits (gyro classes for the first three axes, acc for the rest), in parallel.
pub fn fit_all(axes: &[AxisAllan]) -> Vec<AxisFit> {
    axes.par_iter()
        .enumerate()
        .map(|(i, a)| {
            let sensor = if i < 3 { Sensor::Gyro } else { Sensor::Acc };
            AxisFit::fit(sensor, &a.taus, &a.variance, a.freq)
        })
        .collect()
}

/// Checks there is enough data, runs the Allan step and the fits.
pub fn analyse(c: &Collected<'_>, max_cluster: usize) -> Result<Analysis, Error> {
    check_enough(c, max_cluster)?;
    let (axes, gyro_mean) = allan_step(c, max_cluster)?;
    let fits = fit_all(&axes);
    Ok(Analysis {
        max_cluster,
        axes,
        gyro_mean,
        fits,
    })
}
