//! The workspace's I/O crate: every file format the tools read or write, without ROS.
//!
//! No other crate encodes a record. The modules are private; callers reach the crate
//! through the flat names below (renamed at the root where a module's own name would
//! collide or not say its job: [`check_record`], [`CheckOptions`], [`FindingKind`],
//! [`analyse_timing`], [`find_warmup`], [`MCAP_MAGIC`], [`OutputFormat`], [`write_matrix`],
//! [`sensor_yaml_for`], …). Two modules stay public on purpose: [`shared`], the helpers every
//! binary of the workspace uses, and `test_tools`, the test support behind the
//! `test-support` feature.
//!
//! * `source`: one interface ([`Source`]) over every input — a ROS 1 bag, a ROS 2 bag directory, an
//!   `.mcap`, a `.db3`, a zstd-compressed storage file — recognised from its content.
//! * `series`: the one read path ([`read_imu_topics`]): Imu topics as columns in record-time order, with the
//!   topic rules every tool shares (exact name, else the other slash form; a missing topic
//!   lists the input's topics), parallel decode, sorting and the accounting of what the
//!   container promised against what was delivered.
//! * `bag`: ROS 1 bag format 2.0 — [`BagReader`] (index or scan, `none`/`bz2`/`lz4`)
//!   and [`BagWriter`] (files `rosbag info/check` accept).
//! * `mcap`: MCAP, our own record-level reader (with or without summary, recovery of files
//!   cut short) and writer ([`ChunkCompression`], [`MCAP_MAGIC`]).
//! * `rosbag2`: ROS 2 bag directories, `metadata.yaml`, the sqlite3 storage and rosbag2's
//!   FILE/MESSAGE zstd compression; [`Ros2BagWriter`].
//! * `imu_msg`: the ROS 1 `sensor_msgs/Imu` layout ([`Imu`]), md5 ([`IMU_MD5`]) and 2571-byte
//!   definition ([`imu_definition`]); `cdr`: `sensor_msgs/msg/Imu` in CDR (ROS 2);
//!   [`Sensor`]: its two sensors and their units, the one sensor type of the workspace.
//! * `mat`: the N×7 `data_imu` MAT file of kalibr_allan's `bagconvert`, read and written
//!   ([`DataImu`], [`read_data_imu`], [`write_data_imu`]); `convert`: the bagconvert rules
//!   (rows, output paths) and the csv/npy alternatives ([`OutputFormat`], [`write_matrix`]).
//! * `poses`: reference trajectories ([`read_poses`]): a TUM file, the EuRoC/ASL ground
//!   truth, or a pose/odometry topic of a bag (`poses::msg`: `PoseStamped`,
//!   `PoseWithCovarianceStamped`, `TransformStamped`, `Odometry`, ROS 1 and CDR).
//! * `info`: what an input holds ([`info()`]) (`bag2mat info`); `record_check`: is a record
//!   fit for an Allan analysis ([`check_record`]: clocks, duplicates, gaps through `timing`
//!   ([`analyse_timing`]), the one gap rule; outliers, warm-up, motion), typed findings
//!   ([`Finding`]) every tool prints and the analysers obey.
//! * `formats`: raw IMU logs from outside ROS — EuRoC/ASL and plain text, NumPy, PX4
//!   ULog, ArduPilot DataFlash — each a [`Source`] over rows its reader decoded
//!   (`decoded`), read with [`InputOptions`]; `cursor`: the bounds-checked byte reader the
//!   binary formats parse with.
//! * [`shared`] (public): helpers every binary shares — the CLI helpers, atomic outputs,
//!   notes, progress bars, the plot font and the PNG+SVG chart writer, C `printf` formats,
//!   the allocator.
//!
//! Units: times are [`RosTime`] (UNIX epoch); accelerations m/s², angular rates rad/s.

#![deny(missing_docs)]

mod bag;
mod cdr;
mod cli;
mod convert;
mod cursor;
mod decoded;
mod detect;
mod error;
mod formats;
mod imu_msg;
mod info;
mod input;
mod integrated;
mod mapped;
mod mat;
mod mcap;
mod poses;
mod printable;
mod record_check;
mod rosbag2;
mod rows;
mod sensor;
mod series;
pub mod shared;
mod source;
#[cfg(any(test, feature = "test-support"))]
pub mod test_tools;
mod time;
mod timing;
mod units;
mod zstd;

pub use bag::read::BagIndex;
pub use bag::record::Connection as BagConnection;
pub use bag::write::ConnId;
pub use bag::{BagReader, BagWriter, Compression};
pub use cli::{Args, Invocation, run};
pub use cli::{Command, FormatArg};
pub use convert::{
    Converted, Format as OutputFormat, bag_to_data_imu, data_imu_from_series, into_data_imu,
    write as write_matrix,
};
pub use detect::input_kind;
pub use error::{Error, TopicSummary};
pub use formats::euroc::{
    Stated as SensorYaml, output_base as euroc_output_base, stated_for as sensor_yaml_for,
};
pub use formats::{InputArgs, InputOptions};
pub use imu_msg::BadMessage;
pub use imu_msg::{Imu, MD5 as IMU_MD5, definition as imu_definition};
pub use info::{InfoReport, TopicInfo, info, info_with};
pub use input::{open as open_input, read_imu_series, read_imu_topics, read_imu_topics_with};
pub use integrated::{CONTIGUOUS_TOL, DeadTime, Integration, check as check_integration};
pub use mat::{DataImu, read_data_imu, write_data_imu};
pub use mcap::{ChunkCompression, MAGIC as MCAP_MAGIC};
pub use poses::msg::{POSE_TYPES, PoseMsg, PoseType, Wire as PoseWire, decode as decode_pose};
pub use poses::{PoseOptions, PoseSeries, QUAT_NORM_TOL, parse_time_ns, read_poses, read_tum};
pub use printable::escape as escape_printable;
pub use record_check::Axis as FindingAxis;
pub use record_check::warmup::{
    DETECT_WINDOWS as WARMUP_DETECT_WINDOWS, Fit as WarmupFit, WARMUP_WINDOWS, WARMUP_Z,
    find as find_warmup,
};
pub use record_check::{
    Check as RecordCheck, Finding, Keep as KeepRows, Kind as FindingKind, Level as FindingLevel,
    Options as CheckOptions, RATE_ARGUMENT_REL, Record as CheckInput, SkipError,
    check as check_record, checked_skip, drop_absent, rate_argument,
};
pub use rosbag2::{Ros2BagWriter, Storage, TopicId};
pub use rows::{ROW_LEN, Row, Rows, permute};
pub use sensor::Sensor;
pub use series::{
    ImuRead, ImuSeries, ReadOptions, StandIn, TimeColumn, TopicReport, TopicSelector,
    absent_warning, topic_folder_names,
};
pub use source::{
    Channel as SourceChannel, Contents as SourceContents, Encoding as MessageEncoding,
    Loss as SourceLoss, McapChunkError, NoSuchPart, Part as SourcePart, PartError, PartRead,
    Ros1ChunkError, SkipReason,
};
pub use source::{InputKind, KindFacts, Source, accepted, input_help};
pub use time::RosTime;
pub use timing::{Gap as TimingGap, Segment as TimingSegment};
pub use timing::{Timing, analyse as analyse_timing, ns_of_seconds, ns_of_times};
pub use units::{AccUnit, GyroUnit, STANDARD_GRAVITY, TimeUnit};
pub use zstd::ZstdError;
