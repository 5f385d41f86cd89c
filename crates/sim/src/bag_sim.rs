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
use bag2mat::mcap::ChunkCompression;
use bag2mat::rosbag2::{Ros2BagWriter, Storage, TopicId};
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
    /// Chunk compression (ROS 1 bags).
    pub compression: Compression,
    /// Container: a ROS 1 bag (upstream), or a ROS 2 bag directory (Imu as CDR).
    pub format: BagFormat,
    /// No progress bar.
    pub quiet: bool,
}

/// What `sim bag` writes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum BagFormat {
    /// A ROS 1 bag (format 2.0), as upstream.
    #[default]
    Ros1,
    /// A ROS 2 bag directory with one MCAP file, chunks compressed as given.
    Mcap(ChunkCompression),
    /// A ROS 2 bag directory with one sqlite3 `.db3`.
    Sqlite3,
}

impl BagFormat {
    /// The name on the command line.
    pub fn name(self) -> &'static str {
        match self {
            BagFormat::Ros1 => "ros1",
            BagFormat::Mcap(_) => "mcap",
            BagFormat::Sqlite3 => "sqlite3",
        }
    }
}

/// The writer behind [`ImuBagSink`].
enum SinkWriter {
    Ros1(BagWriter, ConnId),
    Ros2(Box<Ros2BagWriter>, TopicId),
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
    writer: SinkWriter,
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
        Self::create_format(path, BagFormat::Ros1, compression, topic, frame_id)
    }

    /// Create a bag of the given format (a ROS 2 bag is a directory) with one Imu topic.
    pub fn create_format(
        path: &std::path::Path,
        format: BagFormat,
        compression: Compression,
        topic: &str,
        frame_id: &str,
    ) -> Result<Self> {
        let writer = match format {
            BagFormat::Ros1 => {
                let mut w = BagWriter::create(path, compression)?;
                let c = w.add_imu_connection(topic);
                SinkWriter::Ros1(w, c)
            }
            BagFormat::Mcap(c) => {
                let mut w = Ros2BagWriter::create(path, Storage::Mcap(c))?;
                let t = w.add_imu_topic(topic)?;
                SinkWriter::Ros2(Box::new(w), t)
            }
            BagFormat::Sqlite3 => {
                let mut w = Ros2BagWriter::create(path, Storage::Sqlite3)?;
                let t = w.add_imu_topic(topic)?;
                SinkWriter::Ros2(Box::new(w), t)
            }
        };
        // `header.seq` stays 0 and the covariances zero, as upstream's default-constructed
        // message (quirk_03, spec §4).
        let imu = Imu {
            frame_id: frame_id.to_string(),
            ..Imu::default()
        };
        Ok(Self {
            writer,
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
        match &mut self.writer {
            SinkWriter::Ros1(w, c) => w.write_imu(*c, stamp, &self.imu)?,
            SinkWriter::Ros2(w, t) => w.write_imu(*t, stamp.as_nanos(), &self.imu)?,
        }
        self.first.get_or_insert(stamp);
        self.last = stamp;
        self.count += 1;
        Ok(())
    }

    /// Write the index and move the file into place.
    pub fn finish(self) -> Result<BagSummary> {
        match self.writer {
            SinkWriter::Ros1(w, _) => w.finish()?,
            SinkWriter::Ros2(w, _) => w.finish()?,
        }
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
    if cfg.format != BagFormat::Ros1 && cfg.compression != Compression::None {
        return Err(SimError::InvalidArgument(format!(
            "--compression {} is for ROS 1 bags; --format mcap takes --compression none, zstd or lz4, sqlite3 none",
            cfg.compression.name()
        )));
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
    let mut sink = ImuBagSink::create_format(
        &cfg.out,
        cfg.format,
        cfg.compression,
        &cfg.topic,
        &cfg.frame_id,
    )?;
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
