//! Data collection as imu_utils' node does it (imu_utils.md §2): header stamps, message
//! order, gyro in pseudo-deg/h (`(w·57.3)·3600`), accelerations unchanged, and the stop rule.
//!
//! Mirrors imu_utils `2cdda91` `imu_an.cpp` callback: the sample is pushed first, then
//! collection ends when `(t − t_first)/60 > max_time_min` (strict), so the crossing message is
//! kept (quirk 10). Where the node waits forever because the bag ended first (issues #15,
//! #25), we stop at the end and report it.

use rayon::prelude::*;

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

/// The six pushed series.
#[derive(Debug, Clone)]
pub struct Samples {
    /// Topic name as stored in the bag.
    pub topic: String,
    /// `header.stamp.toSec()` of each used message.
    pub t: Vec<f64>,
    /// Gyro x, y, z in pseudo-deg/h.
    pub gyro: [Vec<f64>; 3],
    /// Acc x, y, z in m/s².
    pub acc: [Vec<f64>; 3],
    /// How collection ended.
    pub stop: Stop,
    /// Messages on the topic in the bag.
    pub available: usize,
}

impl Samples {
    /// Number of samples used.
    pub fn len(&self) -> usize {
        self.t.len()
    }

    /// True when nothing was collected.
    pub fn is_empty(&self) -> bool {
        self.t.is_empty()
    }
}

/// Applies the stop rule to a series read from a bag and converts units.
pub fn collect(series: &bag2mat::ImuSeries, max_time_min: u32) -> Result<Samples, Error> {
    let limit = max_time_min as f64;
    let mut n = series.len();
    let mut stop = Stop::EndOfBag;
    let mut start_t = 0.0;
    for (i, st) in series.stamp.iter().enumerate() {
        let t = st.to_sec();
        if i == 0 {
            start_t = t;
        } else if (t - start_t) / 60.0 > limit {
            n = i + 1;
            stop = Stop::Fired { index: i };
            break;
        }
    }
    // Seven independent column conversions, in parallel.
    let col = |k: usize| -> Vec<f64> {
        match k {
            0 => series.stamp[..n].iter().map(|st| st.to_sec()).collect(),
            1..=3 => series.gyro[..n]
                .iter()
                .map(|w| w[k - 1] * IMU_UTILS_DEG_PER_RAD * SECONDS_PER_HOUR)
                .collect(),
            _ => series.acc[..n].iter().map(|a| a[k - 4]).collect(),
        }
    };
    let mut cols: Vec<Vec<f64>> = (0..7usize).into_par_iter().map(col).collect();
    // The first non-finite value (lowest message index; gyro before acc, x before y before z).
    const FIELDS: [&str; 6] = [
        "angular_velocity.x",
        "angular_velocity.y",
        "angular_velocity.z",
        "linear_acceleration.x",
        "linear_acceleration.y",
        "linear_acceleration.z",
    ];
    let first_bad: Vec<Option<usize>> = cols[1..]
        .par_iter()
        .map(|c| c.iter().position(|v| !v.is_finite()))
        .collect();
    if let Some((field, index)) = first_bad
        .iter()
        .enumerate()
        .filter_map(|(f, i)| i.map(|i| (f, i)))
        .min_by_key(|&(f, i)| (i, f))
    {
        return Err(non_finite(series, FIELDS[field].to_string(), index));
    }
    let acc = [
        cols.pop().unwrap_or_default(),
        cols.pop().unwrap_or_default(),
        cols.pop().unwrap_or_default(),
    ];
    let acc = {
        let [z, y, x] = acc;
        [x, y, z]
    };
    let gyro = [cols.remove(1), cols.remove(1), cols.remove(1)];
    let t = cols.remove(0);
    Ok(Samples {
        topic: series.topic.clone(),
        t,
        gyro,
        acc,
        stop,
        available: series.len(),
    })
}

fn non_finite(series: &bag2mat::ImuSeries, what: String, index: usize) -> Error {
    Error::NonFinite {
        topic: series.topic.clone(),
        what,
        index,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use bag2mat::RosTime;

    fn series(n: usize, dt_ns: u64) -> bag2mat::ImuSeries {
        let t0 = 1_600_000_000_000_000_000u64;
        let stamp: Vec<RosTime> = (0..n as u64)
            .map(|i| RosTime::from_nanos(t0 + i * dt_ns))
            .collect();
        bag2mat::ImuSeries {
            topic: "/imu".into(),
            record_time: stamp.clone(),
            stamp,
            seq: (0..n as u32).collect(),
            acc: vec![[0.0, 0.0, 9.81]; n],
            gyro: vec![[0.001, 0.0, 0.0]; n],
            notes: vec![],
        }
    }

    /// imu_utils.md §2: at rate f the stop rule keeps max_time_min·60·f + 2 samples.
    #[test]
    fn quirk_10_stop_rule_keeps_the_crossing_message() {
        let s = collect(&series(200 * 60 + 50, 5_000_000), 1).unwrap();
        assert_eq!(s.len(), 200 * 60 + 2);
        assert_eq!(
            s.stop,
            Stop::Fired {
                index: 200 * 60 + 1
            }
        );
        let s = collect(&series(1000, 5_000_000), 1).unwrap();
        assert_eq!((s.len(), s.stop), (1000, Stop::EndOfBag));
        assert_eq!(s.gyro[0][0], 0.001 * 57.3 * 3600.0);
    }

    #[test]
    fn nan_is_an_error() {
        let mut ser = series(100, 5_000_000);
        ser.acc[7][1] = f64::NAN;
        let e = collect(&ser, 1).unwrap_err().to_string();
        assert!(
            e.contains("linear_acceleration.y") && e.contains("message 7"),
            "{e}"
        );
    }
}
