//! Topics of integrated deltas (PX4 `vehicle_imu`: `delta_angle` over `delta_angle_dt`,
//! `delta_velocity` over `delta_velocity_dt`): each row is the mean rate over its own
//! integration interval, which need not be the rows' spacing.
//!
//! **The rule.** Rows whose intervals tile the time (each integrates, within
//! [`CONTIGUOUS_TOL`], the time since the row before) are samples like any others: the mean
//! rate over one sample period is what an Allan analysis averages anyway, so they are
//! analysed at their spacing. Rows far apart that each integrate a few ms (the logger keeping
//! one message in a hundred) are a *dead-time* sampling, and are refused ([`check`]):
//!
//! * a row's scatter is that of a mean over its own interval `T_i` (white noise of density
//!   N gives `N²/T_i`), while an Allan analysis at the spacing `T_s` reads it as the mean over
//!   `T_s`: its white noise comes out `√(T_s/T_i)` too high (10× for 4.9 ms rows 0.5 s
//!   apart), and the rows say nothing about τ below `T_s`;
//! * the drift terms (B, K, R) live on the spacing, where a mean over `T_i` or over `T_s`
//!   barely differs — so no one time axis is right for both, and the dead time biases every
//!   term in between (Barnes' bias functions, which need the noise type first).
//!
//! The honest figures come from the samples these deltas integrate, which the same log
//! usually holds (`sensor_combined`, `sensor_gyro`/`sensor_accel`, the FIFO topics), or from
//! `vehicle_imu` logged at its full rate.
//!
//! The refusal is this module's own error ([`DeadTime`]); the crate's `Error` wraps it, so
//! that this module needs nothing from the error module.

/// Rows whose integration interval is within this fraction of their spacing tile the time
/// (PX4's integrator restarts at each message; the intervals vary by a sample period of a
/// kHz IMU around a 4 ms spacing, 25 % at most, but their median is the spacing's).
pub const CONTIGUOUS_TOL: f64 = 0.1;

/// The median integration intervals of a topic's rows, s.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Integration {
    /// The gyroscope's (`delta_angle_dt`).
    pub gyro: f64,
    /// The accelerometer's (`delta_velocity_dt`).
    pub acc: f64,
}

impl Integration {
    /// The medians of a topic's intervals in µs, as logged (`None` without one).
    pub(crate) fn of_us(gyro: &mut [f32], acc: &mut [f32]) -> Option<Integration> {
        let median = |v: &mut [f32]| -> Option<f64> {
            if v.is_empty() {
                return None;
            }
            let k = v.len() / 2;
            Some(*v.select_nth_unstable_by(k, f32::total_cmp).1 as f64 * 1e-6)
        };
        Some(Integration {
            gyro: median(gyro)?,
            acc: median(acc)?,
        })
    }
}

/// The error for a topic of integrated deltas that do not tile the time ([`check`]): the
/// topic, the rows' integration interval and their spacing, s.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error(
    "topic '{}' holds integrated deltas, and they are no samples to analyse: each row is the mean rate over its own {:.1} ms (its delta_angle_dt, delta_velocity_dt), but the rows are {:.1} ms apart, so {:.0} % of the time is in no row (a dead-time sampling: the logger kept one message in about {:.0}). Read at their spacing, the white noise comes out √({:.1}/{:.1}) = {:.1}× too high (a row scatters as a {:.1} ms mean, Allan's clusters assume {:.1} ms ones) and no τ below {:.1} ms exists, while the drift terms live on the spacing: no one time axis is right for both. Analyse the samples the deltas integrate (sensor_combined, sensor_gyro/sensor_accel or sensor_gyro_fifo/sensor_accel_fifo of the same log), or log the topic at its full rate, where its rows tile the time",
    crate::printable::escape(.topic),
    1e3 * .integration,
    1e3 * .spacing,
    100.0 * (1.0 - .integration / .spacing).max(0.0),
    .spacing / .integration,
    1e3 * .spacing,
    1e3 * .integration,
    (.spacing / .integration).sqrt(),
    1e3 * .integration,
    1e3 * .spacing,
    1e3 * .spacing
)]
pub struct DeadTime {
    /// The topic.
    pub topic: String,
    /// The rows' (longer) integration interval, s.
    pub integration: f64,
    /// The rows' median spacing, s.
    pub spacing: f64,
}

/// Whether the rows of `topic` (their integration `integration`, their stamps `stamps` in
/// ns) may be analysed as samples: yes when the topic integrates nothing or its intervals
/// tile the time ([`CONTIGUOUS_TOL`]); else the [`DeadTime`] that says why not.
pub fn check(
    topic: &str,
    integration: Option<Integration>,
    stamps: &[i64],
) -> Result<(), DeadTime> {
    let Some(i) = integration else {
        return Ok(());
    };
    let Some(spacing) = crate::timing::analyse(stamps)
        .median_period_ns
        .map(|p| p as f64 * 1e-9)
    else {
        return Ok(());
    };
    // the interval further from the spacing decides
    let worst = [i.gyro, i.acc]
        .into_iter()
        .max_by(|a, b| {
            (a / spacing - 1.0)
                .abs()
                .total_cmp(&(b / spacing - 1.0).abs())
        })
        .unwrap_or(spacing);
    if (worst / spacing - 1.0).abs() <= CONTIGUOUS_TOL {
        return Ok(());
    }
    Err(DeadTime {
        topic: topic.to_string(),
        integration: worst,
        spacing,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_that_tile_the_time_pass_and_rows_far_apart_are_refused() {
        let stamps = |spacing_us: i64| -> Vec<i64> {
            (0..200)
                .map(|k| 1_000_000_000 + k * spacing_us * 1000)
                .collect()
        };
        let int = |us: f64| {
            Some(Integration {
                gyro: us * 1e-6,
                acc: us * 1e-6,
            })
        };
        assert!(check("vehicle_imu", int(4000.0), &stamps(4000)).is_ok());
        assert!(check("vehicle_imu", int(3800.0), &stamps(4000)).is_ok());
        assert!(check("sensor_combined", None, &stamps(500_000)).is_ok());
        let d = check("vehicle_imu", int(4900.0), &stamps(500_000)).unwrap_err();
        assert!((d.spacing - 0.5).abs() < 1e-12 && (d.integration - 4.9e-3).abs() < 1e-12);
        // the crate's error says it as it is
        let text = crate::error::Error::from(d).to_string();
        assert!(text.contains("√(500.0/4.9) = 10.1× too high"), "{text}");
    }
}
