//! The figures and caveats every configuration file of the section carries
//! ([`crate::consumers::ConfigValues`], rendered per consumer by `crate::consumers::render`):
//! one value per sensor and quantity as [`ImuAnalysis`] chooses it
//! ([`ImuAnalysis::noise_density`], [`ImuAnalysis::random_walk`]), each axis' own (resolved,
//! else its 95 % upper bound) for a consumer that takes them, and the comments saying where a
//! value is not a plain fitted value.

use super::imu::ImuAnalysis;
use crate::consumers::values::AxisValue;
use crate::consumers::{ConfigValues, Origin, Quantity};
use bag2mat::Sensor;

/// A term per axis (x y z) of the quantity `q`: the resolved value, else its 95 % upper
/// bound (so marked); `None` when the sensor is absent or an axis has neither.
fn per_axis(a: &ImuAnalysis, q: Quantity) -> Option<[AxisValue; 3]> {
    let mut v = [AxisValue {
        value: f64::NAN,
        upper_bound: false,
    }; 3];
    for ax in a.sensor_axes(q.sensor()) {
        let t = if q.is_walk() {
            &ax.analysis.terms.k
        } else {
            &ax.analysis.terms.n
        };
        v[ax.axis] = match t.reported() {
            Some(x) => AxisValue {
                value: x,
                upper_bound: false,
            },
            None => AxisValue {
                value: t.hi,
                upper_bound: true,
            },
        };
    }
    v.iter().all(|x| x.value.is_finite()).then_some(v)
}

/// The figures of the configuration files of `a`, with its caveats.
pub(crate) fn file_values(a: &ImuAnalysis) -> ConfigValues {
    let values = Quantity::ALL.map(|q| {
        if q.is_walk() {
            a.random_walk(q.sensor())
        } else {
            a.noise_density(q.sensor())
        }
    });
    let mut comments = Vec::new();
    for s in [Sensor::Gyro, Sensor::Acc] {
        if a.sensor_axes(s).next().is_none() {
            comments.push(format!(
                "No {} curves were analysed: its keys are left out.",
                s.name()
            ));
            continue;
        }
        let failed = a.failed_axes(s);
        if !failed.is_empty() {
            comments.push(format!(
                "NO RELIABLE FIT on {}: values from those axes are IEEE 952 region readings.",
                failed.join(", ")
            ));
        }
        let cut = a.truncated_axes(s);
        if !cut.is_empty() {
            comments.push(format!(
                "TRUNCATED FIT on {}: the model describes the curve only up to there; a random walk it does not resolve is the whole curve's 95 % bound.",
                cut.join(", ")
            ));
        }
        let approx = a.approximate_axes(s);
        if !approx.is_empty() {
            comments.push(format!(
                "APPROXIMATE FIT on {}: the model misses the curve beyond its statistics there; those values are approximate.",
                approx.join(", ")
            ));
        }
    }
    // what the record breaks of the analysis' assumptions (bag2mat::check_record)
    for f in a.warnings() {
        comments.push(format!(
            "RECORD CHECK: {}; the values above carry it (the tool's warning says what to do).",
            f.short()
        ));
    }
    ConfigValues {
        values,
        axes: Quantity::ALL.map(|q| per_axis(a, q)),
        comments,
        origin: Origin::Measured,
    }
}
