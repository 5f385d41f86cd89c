//! ROS 1 bag format 2.0: reading and writing, with `none`, `bz2` and `lz4` chunks.
//!
//! * [`record`] holds the byte layout shared by both directions: op codes, header fields,
//!   the connection, chunk-info and index-data records.
//! * [`read`] streams a bag chunk by chunk (never the whole file in memory), decompresses
//!   chunks in parallel, and hands out Imu samples of one topic in record-time order, as
//!   `rosbag::View` does. Bags whose index is missing (a writer that did not finish, a
//!   truncated copy) are scanned record by record: every complete chunk is read, and what
//!   was lost is reported.
//! * [`write`] writes bags that Debian's `rosbag info/check` and the python API accept.
//!
//! Times are [`RosTime`] (module `time`): unsigned seconds and nanoseconds since the UNIX
//! epoch.

pub(crate) mod read;
pub(crate) mod record;
pub(crate) mod write;

pub use read::BagReader;
pub use write::BagWriter;

/// How chunk bodies are stored.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Compression {
    /// Stored as is (what `rosbag record` and vio_data_simulation write by default).
    #[default]
    None,
    /// One bzip2 stream per chunk (level 9, as python rosbag writes).
    Bz2,
    /// One LZ4 frame per chunk, with the content checksum roslz4 requires.
    Lz4,
}

impl Compression {
    /// The value of the chunk record's `compression` field.
    pub fn name(self) -> &'static str {
        match self {
            Compression::None => "none",
            Compression::Bz2 => "bz2",
            Compression::Lz4 => "lz4",
        }
    }

    /// Parses the `compression` field value.
    pub(crate) fn from_name(name: &str) -> Option<Compression> {
        match name {
            "none" => Some(Compression::None),
            "bz2" => Some(Compression::Bz2),
            "lz4" => Some(Compression::Lz4),
            _ => None,
        }
    }
}

impl std::str::FromStr for Compression {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        Compression::from_name(s)
            .ok_or_else(|| format!("unknown compression '{s}' (use none, bz2 or lz4)"))
    }
}
