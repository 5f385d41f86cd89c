//! Raw IMU logs from outside ROS, each a [`crate::source::Source`] over rows its reader decoded
//! ([`crate::decoded`]), recognised from the content like the bag formats:
//!
//! * [`text`]: delimited text (CSV, TSV, whitespace; header or not; comment lines), and
//!   the EuRoC/ASL `data.csv` header; [`euroc`]: an EuRoC/ASL dataset folder (`mav0/imuN`,
//!   `imuN` or the folder holding `data.csv`), with its `sensor.yaml` figures.
//! * [`npy`]: NumPy `.npy` in bag2mat's own N×7 layout (`bag2mat -o x.npy`).
//! * [`ulog`]: PX4 ULog (`sensor_combined`, `sensor_gyro`/`sensor_accel` instances, the
//!   raw `sensor_gyro_fifo`/`sensor_accel_fifo` samples,
//!   `vehicle_imu` deltas), dropouts as losses.
//! * [`dataflash`]: ArduPilot DataFlash `.bin` (`IMU` per instance, `ISBH`/`ISBD` batches).
//!
//! What the content cannot say (a text log's columns and units, a rate without a time
//! column) comes from [`InputOptions`], the flags every tool shares ([`InputArgs`]).

pub(crate) mod dataflash;
pub(crate) mod euroc;
pub(crate) mod npy;
pub(crate) mod text;
pub(crate) mod ulog;

use std::path::Path;

use crate::error::Error;
use crate::source::Source;

use crate::units::{AccUnit, GyroUnit, TimeUnit};

/// What the user said about an input whose content does not say it all (text logs).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct InputOptions {
    /// The file's columns in order (`t,gx,gy,gz,ax,ay,az`; `_` skips one), instead of its
    /// header.
    pub columns: Option<String>,
    /// Unit of the gyroscope columns.
    pub gyro_unit: Option<GyroUnit>,
    /// Unit of the accelerometer columns.
    pub acc_unit: Option<AccUnit>,
    /// Unit of the time column.
    pub time_unit: Option<TimeUnit>,
    /// Sample rate, Hz, for a log without a time column.
    pub rate: Option<f64>,
    /// Gyroscope columns in raw counts: LSB per gyro unit.
    pub gyro_scale: Option<f64>,
    /// Accelerometer columns in raw counts: LSB per acc unit.
    pub acc_scale: Option<f64>,
    /// A text log of several sensors (a `sensor_id` column): the one to read.
    pub sensor_id: Option<String>,
}

/// The input flags every tool shares (flattened into each binary's arguments). The rate
/// for a log without a time column is each tool's own rate flag.
#[derive(Debug, Clone, Default, PartialEq, clap::Args)]
pub struct InputArgs {
    /// Text logs: the file's columns in order, e.g. `t,gx,gy,gz,ax,ay,az` (`_` skips a
    /// column) [default: from the header's names].
    #[arg(long, value_name = "NAMES")]
    pub columns: Option<String>,
    /// Text logs: unit of the gyroscope columns (rad/s, deg/s).
    #[arg(long, value_name = "UNIT", value_parser = GyroUnit::parse)]
    pub gyro_unit: Option<GyroUnit>,
    /// Text logs: unit of the accelerometer columns (m/s^2, g, mg).
    #[arg(long, value_name = "UNIT", value_parser = AccUnit::parse)]
    pub acc_unit: Option<AccUnit>,
    /// Text logs: unit of the time column (s, ms, us, ns).
    #[arg(long, value_name = "UNIT", value_parser = TimeUnit::parse)]
    pub time_unit: Option<TimeUnit>,
    /// Text logs: the gyroscope columns are raw counts, this many LSB per --gyro-unit.
    #[arg(long, value_name = "LSB", value_parser = crate::shared::cli::positive_f64)]
    pub gyro_scale: Option<f64>,
    /// Text logs: the accelerometer columns are raw counts, this many LSB per --acc-unit.
    #[arg(long, value_name = "LSB", value_parser = crate::shared::cli::positive_f64)]
    pub acc_scale: Option<f64>,
    /// Text logs of several sensors in one file (a column sensor_id, imu_id, device_id, …):
    /// read only the rows of this sensor.
    #[arg(long, value_name = "ID")]
    pub sensor_id: Option<String>,
}

impl InputArgs {
    /// The options, with the tool's rate (for a log without a time column).
    pub fn options(&self, rate: Option<f64>) -> InputOptions {
        InputOptions {
            columns: self.columns.clone(),
            gyro_unit: self.gyro_unit,
            acc_unit: self.acc_unit,
            time_unit: self.time_unit,
            rate,
            gyro_scale: self.gyro_scale,
            acc_scale: self.acc_scale,
            sensor_id: self.sensor_id.clone(),
        }
    }
}

/// The topic of instance `k` of a logged message `name`: `name` when the log holds only
/// instance 0 of it, else `name:k` (ULog `multi_id`, DataFlash `I`/`instance`); `topics`
/// come in as `name:k` and are renamed in place.
pub(crate) fn instance_topics<'a>(topics: impl Iterator<Item = &'a mut String>) {
    let topics: Vec<&mut String> = topics.collect();
    let mut count: std::collections::HashMap<String, usize> = Default::default();
    for t in &topics {
        if let Some((name, _)) = t.rsplit_once(':') {
            *count.entry(name.to_string()).or_default() += 1;
        }
    }
    for t in topics {
        if let Some((name, k)) = t.rsplit_once(':')
            && k == "0"
            && count.get(name) == Some(&1)
        {
            *t = name.to_string();
        }
    }
}

/// Bell-shaped deterministic noise (SplitMix64, a sum of four uniforms, variance 1/3) for
/// the synthetic logs the test and benchmark writers make.
#[cfg(any(test, feature = "test-support"))]
pub fn synthetic_noise(state: &mut u64) -> f64 {
    let mut s = 0.0;
    for _ in 0..4 {
        *state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = *state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        s += (z >> 11) as f64 / (1u64 << 53) as f64 - 0.5;
    }
    s
}

/// The first bytes of a ULog file.
pub const ULOG_MAGIC: &[u8] = b"ULog\x01\x12\x35";
/// The first bytes of a DataFlash log: a message header and the FMT type (128).
pub const DATAFLASH_MAGIC: &[u8] = &[0xA3, 0x95, 0x80];
/// The first bytes of a NumPy file.
pub const NPY_MAGIC: &[u8] = b"\x93NUMPY";

/// Opens a text log: a `data.csv` in an EuRoC `imuN` folder is that folder's topic, with its
/// `sensor.yaml`; any other, a plain text log.
pub(crate) fn open_text(path: &Path, opts: &InputOptions) -> Result<Box<dyn Source>, Error> {
    Ok(match euroc::data_csv_folder(path) {
        Some(dir) => Box::new(euroc::open_files(
            vec![(euroc::folder_topic(dir), path.to_path_buf())],
            opts,
        )?),
        None => Box::new(text::open(path, opts)?),
    })
}
