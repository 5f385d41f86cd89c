//! Units a user gets wrong, checked against physics whatever the flags or the header say:
//!
//! * **gravity**: a record's specific force has the magnitude of gravity, 9.81 m/s², at rest
//!   and on average in most motion. Its median over the record in the unit given must be
//!   that ([`GRAVITY_BAND`]): ≈1 is g read as m/s², ≈96 m/s² read as g; ≈0 is an
//!   acceleration with gravity taken out (a phone's "linear" or "user" acceleration, which
//!   its sensor fusion computed: its noise is the fusion's, not the sensor's).
//! * **rate**: IMUs sample at 1 Hz to a few tens of kHz ([`IMU_RATE_HZ`]); stamps in s read
//!   as ms give a "200 kHz" IMU, a `time [s]` header over milliseconds a 0.2 Hz one.
//! * **gyroscope noise**: no IMU gyroscope has a white noise above [`MAX_GYRO_DENSITY`]
//!   (0.17 deg/s/√Hz; phone gyroscopes have about 0.01 deg/s/√Hz): deg/s read as rad/s
//!   is 57× its density.
//!
//! The one place these rules live: the text reader refuses a unit another unit explains,
//! naming the flag to fix ([`gravity_unit_fix`], [`rate_unit_fix`]); the record check says
//! every implausible figure of any input as a warning ([`findings`]).

use super::{Axis, Finding, Kind, Level};
use crate::Sensor;
use crate::units::{AccUnit, TimeUnit};

/// The median specific-force magnitude a record may have, m/s²: gravity is 9.78–9.83 on
/// Earth's surface, a MEMS accelerometer's scale and bias errors add a few percent, and a
/// moving record's median is still gravity's within a few tenths.
pub const GRAVITY_BAND: (f64, f64) = (8.0, 12.0);
/// Below this median magnitude, m/s², the accelerometer holds no gravity.
pub const NO_GRAVITY: f64 = 0.5;
/// The sample rates IMUs have, Hz.
pub const IMU_RATE_HZ: (f64, f64) = (1.0, 40_000.0);
/// The rates a unit mix-up usually hides, Hz: what a fix is suggested for.
const TYPICAL_RATE_HZ: (f64, f64) = (10.0, 10_000.0);
/// The largest white-noise density an IMU gyroscope has, rad/s/√Hz (0.17 deg/s/√Hz; the
/// noisiest MEMS gyroscopes in datasheets are about 0.1 deg/s/√Hz).
pub const MAX_GYRO_DENSITY: f64 = 3e-3;

/// The median of `|a|` over the samples (at most [`SAMPLES`] of them, evenly spread), of
/// the rows where all three axes are finite.
pub fn median_norm(acc: [&[f64]; 3]) -> Option<f64> {
    let n = acc[0].len();
    let stride = n.div_ceil(SAMPLES).max(1);
    let mut m: Vec<f64> = (0..n)
        .step_by(stride)
        .map(|i| (acc[0][i].powi(2) + acc[1][i].powi(2) + acc[2][i].powi(2)).sqrt())
        .filter(|v| v.is_finite())
        .collect();
    if m.is_empty() {
        return None;
    }
    let k = m.len() / 2;
    Some(*m.select_nth_unstable_by(k, f64::total_cmp).1)
}

/// Samples the median magnitude is taken over at most.
const SAMPLES: usize = 1 << 16;

/// The accelerometer unit that puts a median magnitude within [`GRAVITY_BAND`] when the
/// unit the values were read in, `given`, does not: `m` is the magnitude in m/s² as read
/// (the file's number times `given`'s m/s²).
pub fn gravity_unit_fix(m: f64, given: AccUnit) -> Option<AccUnit> {
    if in_band(m) || m < NO_GRAVITY {
        return None;
    }
    [AccUnit::Ms2, AccUnit::G, AccUnit::Mg]
        .into_iter()
        .find(|u| *u != given && in_band(m / given.si() * u.si()))
}

fn in_band(m: f64) -> bool {
    (GRAVITY_BAND.0..=GRAVITY_BAND.1).contains(&m)
}

/// The time unit that puts a rate `rate` (Hz) read in `given` among the rates IMUs usually
/// have, when `given` puts it outside [`IMU_RATE_HZ`]; with the rate it gives.
pub fn rate_unit_fix(rate: f64, given: TimeUnit) -> Option<(TimeUnit, f64)> {
    if (IMU_RATE_HZ.0..=IMU_RATE_HZ.1).contains(&rate) {
        return None;
    }
    [TimeUnit::S, TimeUnit::Ms, TimeUnit::Us, TimeUnit::Ns]
        .into_iter()
        .filter(|u| *u != given)
        .map(|u| (u, rate * given.nanos() as f64 / u.nanos() as f64))
        .find(|(_, r)| (TYPICAL_RATE_HZ.0..=TYPICAL_RATE_HZ.1).contains(r))
}

/// A gyroscope's white-noise density, rad/s/√Hz, from its per-sample short-term noise
/// `sigma` (rad/s) at `rate` Hz.
pub fn gyro_density(sigma: f64, rate: f64) -> f64 {
    sigma / rate.sqrt()
}

/// The record check's findings on units: the median specific force against gravity, the
/// rate against what IMUs have, the gyroscope's noise density against what IMU gyroscopes
/// have (`values`: gyro x y z, acc x y z; `sigma`: each axis' per-sample short-term noise;
/// `rate` Hz). Warnings: the data may be fine and the physics odd, but every figure from a
/// unit mix-up is off by its factor.
pub fn findings(values: [&[f64]; 6], sigma: &[f64; 6], rate: Option<f64>) -> Vec<Finding> {
    let mut out = Vec::new();
    if let Some(m) = median_norm([values[3], values[4], values[5]]) {
        if m < NO_GRAVITY {
            out.push(Finding::new(
                Level::Warning,
                Kind::Units,
                format!(
                    "the accelerometer's median magnitude is {m:.3} m/s^2: gravity (9.81) is not in it — an acceleration with gravity taken out (a phone's linear or user acceleration, Sensor Logger's Accelerometer.csv), which sensor fusion computed: its noise is the fusion's, not the sensor's. Analyse the raw accelerometer (Sensor Logger's TotalAcceleration.csv, phyphox's acceleration with g)"
                ),
            ).on(Axis::new(Sensor::Acc, 2)).sized(m, "m/s^2"));
        } else if !in_band(m) {
            let fix = gravity_unit_fix(m, AccUnit::Ms2).map_or_else(
                || "raw counts? give the LSB per unit (text logs: --acc-scale)".to_string(),
                |u| {
                    format!(
                        "the values are in {}, not m/s^2 (text logs: --acc-unit {}); every acc figure here is off by ×{:.4}",
                        u.name(),
                        u.name(),
                        1.0 / u.si()
                    )
                },
            );
            out.push(Finding::new(
                Level::Warning,
                Kind::Units,
                format!(
                    "the accelerometer's median magnitude is {m:.4} m/s^2, not gravity's 9.81 (within {:.0} – {:.0}): {fix}",
                    GRAVITY_BAND.0, GRAVITY_BAND.1
                ),
            ).on(Axis::new(Sensor::Acc, 2)).sized(m, "m/s^2"));
        }
    }
    let Some(rate) = rate.filter(|r| r.is_finite() && *r > 0.0) else {
        return out;
    };
    if !(IMU_RATE_HZ.0..=IMU_RATE_HZ.1).contains(&rate) {
        // the factor of a time unit mixed up (1000 between s, ms, us and ns) that gives a
        // rate IMUs usually have
        let fix = [1e3, 1e6, 1e9, 1e-3, 1e-6, 1e-9]
            .into_iter()
            .map(|f| rate / f)
            .find(|r| (TYPICAL_RATE_HZ.0..=TYPICAL_RATE_HZ.1).contains(r))
            .map_or_else(String::new, |r| {
                format!(
                    ": a time unit mixed up? ({r:.1} Hz at ×{:.0e} the stamps; text logs: --time-unit)",
                    rate / r
                )
            });
        out.push(
            Finding::new(
                Level::Warning,
                Kind::Units,
                format!(
                    "the stamps give a sample rate of {rate:.4} Hz, outside what IMUs have ({} Hz – {} kHz){fix}; every N here is off by the root of the rate's error",
                    IMU_RATE_HZ.0,
                    IMU_RATE_HZ.1 / 1e3
                ),
            )
            .sized(rate, "Hz"),
        );
    }
    for (k, &s) in sigma.iter().enumerate().take(3) {
        let n = gyro_density(s, rate);
        if n > MAX_GYRO_DENSITY && values[k].iter().any(|v| *v != 0.0) {
            out.push(
                Finding::new(
                    Level::Warning,
                    Kind::Units,
                    format!(
                        "the gyroscope's white noise is about {n:.3e} rad/s/sqrt(Hz), more than any IMU gyroscope has (at most {MAX_GYRO_DENSITY:.0e}): deg/s read as rad/s? (57.3× too large; text logs: --gyro-unit deg/s)"
                    ),
                )
                .on(Axis::new(Sensor::Gyro, k))
                .sized(n, "rad/s/sqrt(Hz)"),
            );
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_unit_that_explains_a_magnitude_or_a_rate_is_found() {
        assert_eq!(gravity_unit_fix(1.0, AccUnit::Ms2), Some(AccUnit::G));
        assert_eq!(gravity_unit_fix(96.2, AccUnit::G), Some(AccUnit::Ms2));
        assert_eq!(gravity_unit_fix(9.8, AccUnit::Ms2), None);
        assert_eq!(gravity_unit_fix(0.01, AccUnit::Ms2), None);
        assert_eq!(
            rate_unit_fix(200_000.0, TimeUnit::Ms).map(|x| x.0),
            Some(TimeUnit::S)
        );
        assert_eq!(
            rate_unit_fix(0.2, TimeUnit::S).map(|x| x.0),
            Some(TimeUnit::Ms)
        );
        assert_eq!(rate_unit_fix(200.0, TimeUnit::S), None);
    }
}
