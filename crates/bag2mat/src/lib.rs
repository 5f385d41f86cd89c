//! ROS 1 bag I/O, the `sensor_msgs/Imu` codec and MAT files, without ROS.
//!
//! This crate owns every file format of the workspace, so no other crate encodes a record:
//!
//! * [`bag`]: bag format 2.0 — [`bag::BagReader`] (index or scan, parallel chunk decoding,
//!   `none`/`bz2`/`lz4`) and [`bag::BagWriter`] (files `rosbag info/check` accept).
//! * [`imu_msg`]: the `sensor_msgs/Imu` layout, md5 and 2571-byte definition.
//! * [`read_imu_series`]: one Imu topic as columns in record-time order, with the topic
//!   rules both analysers share (exact name, else the other slash form; a missing topic
//!   lists the bag's topics).
//! * [`mat`]: the N×7 `data_imu` MAT file of kalibr_allan's `bagconvert`, read and written.
//! * [`convert`]: the bagconvert rules (rows, output path) and the csv/npy alternatives.
//! * [`cfmt`]: C `printf` number layouts (`%g`, `%.16e`) for upstream-compatible text.
//! * [`output`], [`progress`], [`plot`]: atomic output files, progress bars and the embedded
//!   plot font, shared by every binary of the workspace.
//!
//! Units: times are [`RosTime`] (UNIX epoch); accelerations m/s², angular rates rad/s.

#![deny(missing_docs)]

pub mod bag;
pub mod cfmt;
pub mod convert;
mod error;
pub mod imu_msg;
pub mod mat;
pub mod output;
pub mod plot;
pub mod progress;
mod series;

pub use bag::{Compression, RosTime};
pub use error::{Error, TopicSummary};
pub use series::{ImuSeries, ReadOptions, permute, read_imu_series};
