//! The offline part of imu_utils' run on collected samples (imu_utils.md §3–4): per axis the
//! `calc()` quantities (period, factors, taus, Allan variances), the gyro means, then the six
//! fits. Gyro then acc, x, y, z, as upstream.

use rayon::prelude::*;

use crate::collect::Samples;
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

/// The Allan step alone, all six axes (the part the benchmark times). Consumes the samples:
/// each axis' column becomes its θ in place.
pub fn allan_step(samples: Samples, max_cluster: usize) -> Vec<AxisAllan> {
    let n = samples.len();
    let period = estimator::mean_period(&samples.t);
    let freq = 1.0 / period;
    let f = factors::factors(n, max_cluster);
    let taus = estimator::taus(period, &f);
    let (start_t, end_t) = (samples.t[0], samples.t[n - 1]);
    let Samples { gyro, acc, .. } = samples;
    let mut thetas: Vec<Vec<f64>> = gyro.into_iter().chain(acc).collect();
    // θ for all axes at once (one sequential cumulative sum each), then one axis at a time so
    // its θ stays in cache while the factors run in parallel.
    thetas.par_iter_mut().for_each(|x| estimator::thetas_in_place(x, freq));
    thetas
        .iter()
        .zip(AXIS_NAMES)
        .map(|(theta, name)| AxisAllan {
            name,
            n,
            start_t,
            end_t,
            freq,
            period,
            factors: f.clone(),
            taus: taus.clone(),
            variance: estimator::allan_variance(theta, &f, period),
        })
        .collect()
}

/// Gyro means in pseudo-deg/h (`getAvgValue`).
pub fn gyro_means(samples: &Samples) -> [f64; 3] {
    [0, 1, 2].map(|k| estimator::mean(&samples.gyro[k]))
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
/// N − 2m > 0.
pub fn check_enough(samples: &Samples, max_cluster: usize) -> Result<(), Error> {
    let n = samples.len();
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
            topic: samples.topic.clone(),
            n,
            valid,
            needed: MIN_VALID_POINTS,
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
pub fn analyse(samples: &Samples, max_cluster: usize) -> Result<Analysis, Error> {
    check_enough(samples, max_cluster)?;
    let gyro_mean = gyro_means(samples);
    let axes = allan_step(samples.clone(), max_cluster);
    let fits = fit_all(&axes);
    Ok(Analysis {
        max_cluster,
        axes,
        gyro_mean,
        fits,
    })
}
