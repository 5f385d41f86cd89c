//! The offline part of imu_utils' run on collected samples (docs/upstream/imu_utils.md §3–4): per axis the
//! `calc()` quantities (period, factors, taus, Allan variances), the gyro means, then the six
//! fits. Gyro then acc, x, y, z, as upstream.

use rayon::prelude::*;

use crate::collect::Collected;
use crate::error::Error;
use crate::estimator;
use crate::factors;
use crate::fit::AxisFit;
use bag2mat::Sensor;

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
    /// The IEEE 952 section's noise identification at each factor (empty unless asked for).
    pub noise_ids: Vec<allan_kalibr::NoiseId>,
}

impl AxisAllan {
    /// Allan deviations (`getDeviation`).
    pub fn deviation(&self) -> Vec<f64> {
        self.variance.iter().map(|v| v.sqrt()).collect()
    }
}

/// The Allan step alone, all six axes (the part the benchmark times), plus the gyro means
/// (`getAvgValue`: the same sequential sum θ is built from, over N). Fails on the first
/// non-finite value. One axis at a time: its θ (23 MB for a 4 h 200 Hz bag) stays in cache
/// while both cores sweep the factors, and only one θ is alive. With `ieee`, also what the
/// IEEE 952 section takes from θ while it is there: the noise identification at each factor
/// (no second pass over the samples).
pub fn allan_step(
    c: &Collected<'_>,
    max_cluster: usize,
    ieee: bool,
) -> Result<(Vec<AxisAllan>, [f64; 3]), Error> {
    use allan_kalibr::identify_on;
    let n = c.len();
    let period = estimator::mean_period(&c.t);
    let freq = 1.0 / period;
    let f = factors::factors(n, max_cluster);
    let taus = estimator::taus(period, &f);
    let mut axes = Vec::with_capacity(6);
    let mut sums = [0.0; 6];
    let mut first_bad: Option<(usize, usize)> = None; // (index, axis)
    for (axis, name) in AXIS_NAMES.into_iter().enumerate() {
        let (theta, sum, bad) = match axis {
            0..3 => estimator::thetas_checked(c.gyro_values(axis), n, freq),
            _ => estimator::thetas_checked(c.acc_values(axis - 3), n, freq),
        };
        sums[axis] = sum;
        if let Some(i) = bad {
            if first_bad.is_none_or(|b| i < b.0) {
                first_bad = Some((i, axis));
            }
            continue;
        }
        if first_bad.is_some() {
            continue;
        }
        let variance = estimator::allan_variance(&theta, &f, period);
        let noise_ids = if ieee {
            f.par_iter().map(|&m| identify_on(&theta, m)).collect()
        } else {
            Vec::new()
        };
        axes.push(AxisAllan {
            name,
            n,
            start_t: c.t[0],
            end_t: c.t[n - 1],
            freq,
            period,
            factors: f.clone(),
            taus: taus.clone(),
            variance,
            noise_ids,
        });
    }
    if let Some((index, axis)) = first_bad {
        return Err(c.non_finite(axis, index));
    }
    let gyro_mean = [0, 1, 2].map(|k| sums[k] / n as f64);
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
    /// A sensor the topic does not carry (PX4 `sensor_gyro`, …): its three axes above were
    /// computed on a stand-in (the present sensor's samples) and are never printed nor
    /// written.
    pub absent: Option<bag2mat::Sensor>,
}

impl Analysis {
    /// True when axis `i` (gyr x y z, acc x y z) belongs to a sensor the topic carries.
    pub fn present(&self, i: usize) -> bool {
        let s = if i < 3 {
            bag2mat::Sensor::Gyro
        } else {
            bag2mat::Sensor::Acc
        };
        self.absent != Some(s)
    }
}

impl Analysis {
    /// The analysis of curves read from an imu_utils data directory (docs/upstream/imu_utils.md §5.2): the
    /// taus and deviations of its files (pseudo-deg/h for the gyro), the given fits, at the
    /// rate `freq`; sample-dependent fields (counts, stamps, gyro means) are unknown.
    pub fn from_curves(raw: &allan_kalibr::ImuUtilsRaw, fits: Vec<AxisFit>, freq: f64) -> Analysis {
        let period = 1.0 / freq;
        let axis = |name: &'static str, t: &[f64], dev: &[f64]| AxisAllan {
            name,
            n: 0,
            start_t: f64::NAN,
            end_t: f64::NAN,
            freq,
            period,
            factors: t.iter().map(|x| (x / t[0]).round() as usize).collect(),
            taus: t.to_vec(),
            variance: dev.iter().map(|d| d * d).collect(),
            noise_ids: Vec::new(),
        };
        let axes = (0..3)
            .map(|k| axis(AXIS_NAMES[k], &raw.gyr_t, &raw.gyr[k]))
            .chain((0..3).map(|k| axis(AXIS_NAMES[3 + k], &raw.acc_t, &raw.acc[k])))
            .collect();
        Analysis {
            max_cluster: 0,
            axes,
            gyro_mean: [f64::NAN; 3],
            fits,
            absent: None,
        }
    }
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
