//! `sim bag`: the IMU bag of vio_data_simulation `ros_version` `gener_alldata.cpp`
//! (spec §4), written with bag2mat's [`BagWriter`].
//!
//! Defaults reproduce the seed's run: static level IMU, 200 Hz, 14400 s on the
//! double-accumulated grid ⇒ 2 880 001 messages, medium preset, topic `imu` (no slash),
//! frame `base_link`, `header.seq` 0, orientation filled, zero covariances, uncompressed.
//! Record time = `header.stamp` = start + t in integer nanoseconds (upstream computes
//! `ros::Time(begin + t)` in double, jittering stamps by ~0.1 µs; here t is rounded to the
//! nearest ns of the accumulated double, so the last stamp is start + 14399.999999160 s and
//! `rosbag info` shows the same duration as upstream's bag).

use crate::error::{Result, SimError};
use crate::grid::Grid;
use crate::motion::Motion;
use crate::noise::{ContinuousNoise, NoiseGenerator};
use crate::rotation::quat_from_matrix;
use bag2mat::bag::BagWriter;
use bag2mat::bag::write::ConnId;
use bag2mat::imu_msg::Imu;
use bag2mat::{Compression, RosTime};
use std::path::PathBuf;

/// Settings of `sim bag`.
#[derive(Debug, Clone)]
pub struct BagConfig {
    /// Output bag.
    pub out: PathBuf,
    /// Continuous-time noise parameters.
    pub noise: ContinuousNoise,
    /// Sample rate, Hz.
    pub rate: f64,
    /// Duration, s (samples at t = 0, Δt, … while t < duration, double accumulation).
    pub duration: f64,
    /// RNG seed.
    pub seed: u64,
    /// Time of the first message, ns since the UNIX epoch.
    pub start_ns: u64,
    /// Topic name (upstream: `imu`).
    pub topic: String,
    /// `header.frame_id` (upstream: `base_link`).
    pub frame_id: String,
    /// Motion model.
    pub motion: Motion,
    /// Chunk compression.
    pub compression: Compression,
    /// No progress bar.
    pub quiet: bool,
}

/// What was written.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BagSummary {
    /// Messages written.
    pub messages: u64,
    /// First record time.
    pub first: RosTime,
    /// Last record time.
    pub last: RosTime,
}

/// Streams Imu messages into a bag, reusing one message value (no per-message allocation).
pub struct ImuBagSink {
    writer: BagWriter,
    conn: ConnId,
    imu: Imu,
    count: u64,
    first: Option<RosTime>,
    last: RosTime,
}

impl ImuBagSink {
    /// Create the bag (a temp file until [`ImuBagSink::finish`]) with one Imu topic.
    pub fn create(
        path: &std::path::Path,
        compression: Compression,
        topic: &str,
        frame_id: &str,
    ) -> Result<Self> {
        let mut writer = BagWriter::create(path, compression)?;
        let conn = writer.add_imu_connection(topic);
        // `header.seq` stays 0 and the covariances zero, as upstream's default-constructed
        // message (quirk_03, spec §4).
        let imu = Imu {
            frame_id: frame_id.to_string(),
            ..Imu::default()
        };
        Ok(Self {
            writer,
            conn,
            imu,
            count: 0,
            first: None,
            last: RosTime::default(),
        })
    }

    /// Append one message; record time = stamp. `q_xyzw` is the orientation.
    #[inline]
    pub fn push(
        &mut self,
        stamp: RosTime,
        q_xyzw: [f64; 4],
        gyro: [f64; 3],
        acc: [f64; 3],
    ) -> Result<()> {
        self.imu.stamp = stamp;
        self.imu.orientation = q_xyzw;
        self.imu.angular_velocity = gyro;
        self.imu.linear_acceleration = acc;
        self.writer.write_imu(self.conn, stamp, &self.imu)?;
        self.first.get_or_insert(stamp);
        self.last = stamp;
        self.count += 1;
        Ok(())
    }

    /// Write the index and move the file into place.
    pub fn finish(self) -> Result<BagSummary> {
        self.writer.finish()?;
        Ok(BagSummary {
            messages: self.count,
            first: self.first.unwrap_or_default(),
            last: self.last,
        })
    }
}

/// Largest representable ROS time, ns (u32 seconds).
const MAX_ROS_NS: u64 = (u32::MAX as u64 + 1) * 1_000_000_000 - 1;

/// Validate a bag configuration.
pub fn validate(cfg: &BagConfig) -> Result<()> {
    if !(cfg.rate.is_finite() && cfg.rate > 0.0) {
        return Err(SimError::InvalidArgument(format!(
            "--rate must be a positive number of Hz, got {}",
            cfg.rate
        )));
    }
    if !(cfg.duration.is_finite() && cfg.duration > 0.0) {
        return Err(SimError::InvalidArgument(format!(
            "--duration must be a positive number of seconds, got {}",
            cfg.duration
        )));
    }
    if cfg.topic.is_empty() {
        return Err(SimError::InvalidArgument(
            "--topic must not be empty".into(),
        ));
    }
    let end = cfg.start_ns as f64 + cfg.duration * 1e9;
    if end > MAX_ROS_NS as f64 {
        return Err(SimError::InvalidArgument(
            "start time + duration exceeds the ROS time range (year 2106)".into(),
        ));
    }
    Ok(())
}

/// Number of messages `sim bag` writes: upstream's double-accumulated loop (quirk_01).
pub fn message_count(rate: f64, duration: f64) -> u64 {
    Grid::AccumulatedF64.times(duration, rate).count() as u64
}

/// Write the bag.
pub fn run(cfg: &BagConfig) -> Result<BagSummary> {
    validate(cfg)?;
    let n = message_count(cfg.rate, cfg.duration);
    let pb = bag2mat::shared::progress::bar(n, cfg.quiet, "msgs");
    pb.set_message("writing");
    let mut sink = ImuBagSink::create(&cfg.out, cfg.compression, &cfg.topic, &cfg.frame_id)?;
    let mut noise = NoiseGenerator::new(cfg.noise.discretize(1.0 / cfg.rate), cfg.seed);
    // The static model does not depend on t (upstream calls MotionModel(0)): compute it once.
    let fixed = (cfg.motion == Motion::Static).then(|| cfg.motion.sample(0.0));
    let to_xyzw = |q: [f64; 4]| [q[1], q[2], q[3], q[0]];
    let fixed_q = fixed.map(|m| to_xyzw(quat_from_matrix(&m.r_wb)));
    const PROGRESS_STEP: u64 = 1 << 14;
    for (i, t) in Grid::AccumulatedF64
        .times(cfg.duration, cfg.rate)
        .enumerate()
    {
        let (m, q) = match (fixed, fixed_q) {
            (Some(m), Some(q)) => (m, q),
            _ => {
                let m = cfg.motion.sample(t);
                (m, to_xyzw(quat_from_matrix(&m.r_wb)))
            }
        };
        let (mut g, mut a): ([f64; 3], [f64; 3]) = (m.gyro.into(), m.acc.into());
        noise.apply(&mut g, &mut a);
        let stamp = RosTime::from_nanos(cfg.start_ns + (t * 1e9).round() as u64);
        sink.push(stamp, q, g, a)?;
        if (i as u64 + 1).is_multiple_of(PROGRESS_STEP) {
            pb.inc(PROGRESS_STEP);
        }
    }
    pb.set_message("indexing");
    let s = sink.finish()?;
    pb.finish_and_clear();
    Ok(s)
}

/// Now, ns since the UNIX epoch (upstream: `ros::Time::now()`).
pub fn now_ns() -> u64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_nanos() as u64)
        .unwrap_or(0)
}

/// Parse `--start-time` (UNIX seconds, decimal) into ns, exactly.
pub fn parse_start_time(s: &str) -> Result<u64> {
    match crate::textio::parse_time_ns(s) {
        Some(ns) if (0..=MAX_ROS_NS as i64).contains(&ns) => Ok(ns as u64),
        Some(_) => Err(SimError::InvalidArgument(format!(
            "--start-time {s:?} is outside the ROS time range (0 to 4294967295 s)"
        ))),
        None => Err(SimError::InvalidArgument(format!(
            "--start-time {s:?} is not a number of seconds"
        ))),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn default_count_is_upstream() {
        assert_eq!(message_count(200.0, 14400.0), 2_880_001);
        // The 2 h txt tool's count (spec §4).
        assert_eq!(message_count(200.0, 7200.0), 1_440_000);
    }

    #[test]
    fn start_time_parsing() {
        assert_eq!(
            parse_start_time("1700000000.5").unwrap(),
            1_700_000_000_500_000_000
        );
        assert!(parse_start_time("-1").is_err());
        assert!(parse_start_time("abc").is_err());
        assert!(parse_start_time("5000000000").is_err());
    }
}
