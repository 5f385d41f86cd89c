//! Data collection as imu_utils' node does it (docs/upstream/imu_utils.md §2): header stamps, message
//! order, gyro in pseudo-deg/h (`(w·57.3)·3600`), accelerations unchanged, and the stop rule.
//!
//! Mirrors imu_utils `2cdda91` `imu_an.cpp` callback: the sample is pushed first, then
//! collection ends when `(t − t_first)/60 > max_time_min` (strict), so the crossing message is
//! kept (quirk 10). Where the node waits forever because the bag ended first (issues #15,
//! #25), we stop at the end and report it.
//!
//! The pushed values are not copied into columns: [`Collected::gyro_values`] and
//! [`Collected::acc_values`] yield them from the
//! bag reader's rows on demand, and the Allan step turns them straight into θ (one pass, no
//! extra 160 MB of columns for a 4 h bag).

use crate::error::Error;
use crate::fit::{IMU_UTILS_DEG_PER_RAD, SECONDS_PER_HOUR};

/// How collection ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Stop {
    /// The stop rule fired at this (0-based) message, which is included.
    Fired {
        /// Index of the crossing message.
        index: usize,
    },
    /// The bag ended before the limit; every message was used.
    EndOfBag,
}

/// Upstream's six pushed series, in accumulator order.
pub const FIELDS: [&str; 6] = [
    "angular_velocity.x",
    "angular_velocity.y",
    "angular_velocity.z",
    "linear_acceleration.x",
    "linear_acceleration.y",
    "linear_acceleration.z",
];

/// The messages the node would have pushed: the first `n` of the series.
#[derive(Debug, Clone)]
pub struct Collected<'a> {
    series: &'a bag2mat::ImuSeries,
    /// Index in the series of the first sample used (0 unless restricted to a stretch).
    offset: usize,
    /// `header.stamp.toSec()` (or the record time, with `--time record`) of each used message.
    pub t: Vec<f64>,
    /// How collection ended.
    pub stop: Stop,
}

impl<'a> Collected<'a> {
    /// Number of samples used.
    pub fn len(&self) -> usize {
        self.t.len()
    }

    /// The first `n` messages of `series` on the chosen clock, collection having ended as
    /// `stop` says (the messages the record check kept of a collection).
    pub fn first(
        series: &'a bag2mat::ImuSeries,
        n: usize,
        time: bag2mat::TimeColumn,
        stop: Stop,
    ) -> Collected<'a> {
        Collected {
            series,
            offset: 0,
            t: series.time(time)[..n].iter().map(|s| s.to_sec()).collect(),
            stop,
        }
    }

    fn used(&self) -> std::ops::Range<usize> {
        self.offset..self.offset + self.len()
    }

    /// Topic name as stored in the bag.
    pub fn topic(&self) -> &str {
        &self.series.topic
    }

    /// The pushed gyro values of axis `k` (0–2: x, y, z) in pseudo-deg/h, in message order.
    pub fn gyro_values(&self, k: usize) -> impl Iterator<Item = f64> + '_ {
        self.series.gyro[k][self.used()]
            .iter()
            .map(move |w| w * IMU_UTILS_DEG_PER_RAD * SECONDS_PER_HOUR)
    }

    /// The pushed gyro values of axis `k` (0–2) in rad/s, as the bag holds them.
    pub fn gyro_rad_s(&self, k: usize) -> &[f64] {
        &self.series.gyro[k][self.used()]
    }

    /// The pushed accelerations of axis `k` (0–2) in m/s², as the bag holds them.
    pub fn acc_m_s2(&self, k: usize) -> &[f64] {
        &self.series.acc[k][self.used()]
    }

    /// The pushed accelerations of axis `k` (0–2: x, y, z) in m/s², in message order.
    pub fn acc_values(&self, k: usize) -> impl Iterator<Item = f64> + '_ {
        self.series.acc[k][self.used()].iter().copied()
    }

    /// The error for a non-finite value of accumulator `axis` at message `index`.
    pub fn non_finite(&self, axis: usize, index: usize) -> Error {
        Error::NonFinite {
            topic: self.series.topic.clone(),
            what: FIELDS[axis].to_string(),
            index,
        }
    }
}

/// Applies the stop rule to a series read from a bag, on the chosen time column (imu_utils
/// uses `header.stamp`).
pub fn collect(
    series: &bag2mat::ImuSeries,
    max_time_min: u32,
    time: bag2mat::TimeColumn,
) -> Collected<'_> {
    let limit = max_time_min as f64;
    let mut t = Vec::with_capacity(series.len());
    let mut stop = Stop::EndOfBag;
    for st in series.time(time) {
        let ts = st.to_sec();
        t.push(ts);
        if t.len() > 1 && (ts - t[0]) / 60.0 > limit {
            stop = Stop::Fired { index: t.len() - 1 };
            break;
        }
    }
    Collected {
        series,
        offset: 0,
        t,
        stop,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use bag2mat::RosTime;

    pub(crate) fn series(n: usize, dt_ns: u64) -> bag2mat::ImuSeries {
        let t0 = 1_600_000_000_000_000_000u64;
        let stamp: Vec<RosTime> = (0..n as u64)
            .map(|i| RosTime::from_nanos(t0 + i * dt_ns))
            .collect();
        bag2mat::ImuSeries {
            topic: "/imu".into(),
            record_time: stamp.clone(),
            stamp,
            seq: (0..n as u32).collect(),
            acc: [vec![0.0; n], vec![0.0; n], vec![9.81; n]],
            gyro: [vec![0.001; n], vec![0.0; n], vec![0.0; n]],
            ..Default::default()
        }
    }

    /// docs/upstream/imu_utils.md §2: at rate f the stop rule keeps max_time_min·60·f + 2 samples.
    #[test]
    fn quirk_10_stop_rule_keeps_the_crossing_message() {
        let ser = series(200 * 60 + 50, 5_000_000);
        let c = collect(&ser, 1, bag2mat::TimeColumn::Header);
        assert_eq!(c.len(), 200 * 60 + 2);
        assert_eq!(
            c.stop,
            Stop::Fired {
                index: 200 * 60 + 1
            }
        );
        let ser = series(1000, 5_000_000);
        let c = collect(&ser, 1, bag2mat::TimeColumn::Header);
        assert_eq!((c.len(), c.stop), (1000, Stop::EndOfBag));
        assert_eq!(c.gyro_values(0).next(), Some(0.001 * 57.3 * 3600.0));
        assert_eq!(c.acc_values(2).nth(999), Some(9.81));
        assert_eq!(c.acc_values(1).count(), 1000);
    }
}
