//! One interface over every container the workspace reads: ROS 1 bags, MCAP files, rosbag2
//! sqlite3 files and rosbag2 bag directories (split files, zstd file or message compression).
//!
//! [`crate::input::open`] recognises the input from its content (never its extension,
//! [`crate::detect`]) and returns a [`Source`]: the channels with their type, encoding and the message count the container
//! promises, the independently readable parts (chunks, row ranges), and what opening found
//! (notes, and [`Loss`]es: data the container held or promised that cannot be delivered).
//! Reading a part hands out `(channel, record time, payload)` for the channels asked for and
//! says how many it delivered and why it stopped early. Decoding, the topic rules, progress
//! and sorting are written once on top of this, in [`crate::series`].

mod part_error;

pub use part_error::{McapChunkError, NoSuchPart, PartError, Ros1ChunkError, SkipReason};

use crate::shared::note::Note;

/// What an input is, recognised from its first bytes (or `metadata.yaml` for a directory).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum InputKind {
    /// `#ROSBAG V2.0\n`.
    Ros1Bag,
    /// `\x89MCAP0\r\n`.
    Mcap,
    /// `SQLite format 3\0`: a rosbag2 `.db3`.
    Sqlite3,
    /// A directory holding `metadata.yaml` and its storage files.
    Rosbag2Dir,
    /// A zstd frame: a FILE-mode compressed `.mcap.zstd` or `.db3.zstd`.
    Zstd,
    /// Delimited text (CSV, TSV, whitespace; EuRoC/ASL `data.csv`): `formats::text`.
    Text,
    /// An EuRoC/ASL dataset folder: `formats::euroc`.
    EurocDir,
    /// `\x93NUMPY`: `formats::npy`.
    Npy,
    /// `ULog\x01\x12\x35`: a PX4 log, `formats::ulog`.
    Ulog,
    /// `\xA3\x95\x80`: an ArduPilot DataFlash log, `formats::dataflash`.
    DataFlash,
}

/// What the workspace says about one kind of input: its name in messages, its phrase in
/// the list of accepted inputs, and how the non-Imu topics of a log its reader decodes
/// are labelled. One row per kind ([`InputKind::facts`]); how a kind is recognised and
/// opened is the format registry's (`crate::registry`), which sits above the readers.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct KindFacts {
    /// How the kind is named in messages ("ROS 1 bag").
    pub name: &'static str,
    /// Its phrase in [`accepted`]'s list.
    pub accepted: &'static str,
    /// The encoding named for a decoded log's non-Imu topics (`None`: a container whose
    /// channels carry their own encoding).
    pub other_topics: Option<&'static str>,
}

impl InputKind {
    /// Every kind, in the order [`accepted`] lists them (and the format registry tries
    /// them: magic numbers in this order, then the text sniffer).
    pub const ALL: [InputKind; 10] = [
        InputKind::Ros1Bag,
        InputKind::Rosbag2Dir,
        InputKind::Mcap,
        InputKind::Sqlite3,
        InputKind::Zstd,
        InputKind::EurocDir,
        InputKind::Text,
        InputKind::Ulog,
        InputKind::DataFlash,
        InputKind::Npy,
    ];

    /// The kind's facts (one row per kind: a new kind is a compile error here until it
    /// has its row).
    pub const fn facts(self) -> KindFacts {
        const fn f(
            name: &'static str,
            accepted: &'static str,
            other_topics: Option<&'static str>,
        ) -> KindFacts {
            KindFacts {
                name,
                accepted,
                other_topics,
            }
        }
        match self {
            InputKind::Ros1Bag => f("ROS 1 bag", "a ROS 1 bag (format 2.0)", None),
            InputKind::Rosbag2Dir => f(
                "ROS 2 bag directory",
                "a ROS 2 bag directory (metadata.yaml with .db3 or .mcap files)",
                None,
            ),
            InputKind::Mcap => f("MCAP file", "an .mcap file", None),
            InputKind::Sqlite3 => f(
                "rosbag2 sqlite3 file",
                "a rosbag2 .db3 (sqlite3) file",
                None,
            ),
            InputKind::Zstd => f("zstd-compressed file", "a zstd-compressed .mcap/.db3", None),
            InputKind::EurocDir => f(
                "EuRoC/ASL dataset",
                "a EuRoC/ASL dataset (data.csv, its imuN folder or the dataset root)",
                Some("text"),
            ),
            InputKind::Text => f("text log", "a CSV/TSV/whitespace text log", Some("text")),
            InputKind::Ulog => f("PX4 ULog", "a PX4 ULog (.ulg)", Some("ulog")),
            InputKind::DataFlash => f(
                "ArduPilot DataFlash log",
                "an ArduPilot DataFlash log (.bin)",
                Some("df"),
            ),
            InputKind::Npy => f(
                "NumPy .npy",
                "a NumPy .npy (N x 7, bag2mat's layout)",
                Some("text"),
            ),
        }
    }

    /// How the kind is named in messages.
    pub fn describe(self) -> &'static str {
        self.facts().name
    }
}

/// Every kind of input accepted, for error messages: [`InputKind::ALL`]'s phrases.
pub fn accepted() -> &'static str {
    static TEXT: std::sync::OnceLock<String> = std::sync::OnceLock::new();
    TEXT.get_or_init(|| or_list(InputKind::ALL.iter().map(|k| k.facts().accepted)))
}

/// `a, b, or c`.
fn or_list<'a>(items: impl IntoIterator<Item = &'a str>) -> String {
    let p: Vec<&str> = items.into_iter().collect();
    let (last, rest) = p.split_last().expect("a list of inputs is not empty");
    format!("{}, or {last}", rest.join(", "))
}

/// The help text of an input argument, from [`InputKind::ALL`]'s phrases: `extra` names
/// the inputs a tool reads besides bag2mat's (the analysers' bagconvert `.mat`), first. A
/// new kind shows in every tool's `--help` with its row of [`InputKind::facts`].
pub fn input_help(extra: &[&str]) -> String {
    let kinds = InputKind::ALL.iter().map(|k| k.facts().accepted);
    format!(
        "The input, recognised from its content: {}.",
        or_list(extra.iter().copied().chain(kinds))
    )
}

/// The magic line of a ROS 1 bag.
pub const ROS1_MAGIC: &[u8] = b"#ROSBAG V2.0\n";
/// The first 16 bytes of every SQLite 3 database.
pub const SQLITE_MAGIC: &[u8] = b"SQLite format 3\0";
/// The magic number of a zstd frame.
pub const ZSTD_MAGIC: &[u8] = &[0x28, 0xB5, 0x2F, 0xFD];

/// How a channel's payloads are serialized.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Encoding {
    /// ROS 1 serialization (ROS 1 bags, MCAP `ros1` channels).
    Ros1,
    /// CDR (ROS 2).
    Cdr,
    /// Samples a log reader already decoded ([`crate::Row`]).
    Row,
    /// Anything else, named as the container names it.
    Other(String),
}

impl Encoding {
    /// From a container's encoding name (`ros1`, `cdr`, …).
    pub(crate) fn from_name(name: &str) -> Encoding {
        match name {
            "ros1" => Encoding::Ros1,
            "cdr" => Encoding::Cdr,
            other => Encoding::Other(other.to_string()),
        }
    }
    /// The name.
    pub(crate) fn name(&self) -> &str {
        match self {
            Encoding::Ros1 => "ros1",
            Encoding::Cdr => "cdr",
            Encoding::Row => "row",
            Encoding::Other(s) => s,
        }
    }
}

/// A stream of messages of one type on one topic (a ROS 1 connection, an MCAP channel, a
/// rosbag2 topic). Several channels may share a topic.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Channel {
    /// Id, unique within the source.
    pub id: u32,
    /// Topic name as recorded.
    pub topic: String,
    /// Message type as recorded (`sensor_msgs/Imu`, `sensor_msgs/msg/Imu`).
    pub msg_type: String,
    /// Payload serialization.
    pub encoding: Encoding,
    /// The ROS 1 md5 of the type, when the container records it.
    pub md5sum: Option<String>,
    /// Messages the container's index or summary promises; `None` when it keeps no count.
    pub count: Option<u64>,
}

/// An independently readable piece of a source (a chunk, a range of rows).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Part {
    /// Where it is, for messages ("chunk at byte 4117").
    pub label: String,
    /// Record-time span (ns) the container states for it, if any.
    pub span: Option<(u64, u64)>,
    /// Messages per channel the container promises in it, if it says.
    pub counts: Option<Vec<(u32, u64)>>,
    /// An upper bound of the bytes its records take once decompressed, backed by bytes in
    /// the file: what a reader may size buffers by (a damaged count never sizes memory).
    pub bytes: u64,
}

/// The largest decompressed/stored size ratio a part's byte bound assumes for compressed
/// data whose decompressed size is not backed by the file: IMU records (noisy doubles)
/// compress by less than 4×; a part that expands more is still read whole, it only costs a
/// buffer instead of a preallocated slot.
pub const MAX_EXPANSION: u64 = 64;

/// Data that the container held or promised and that cannot be delivered.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Loss {
    /// What was lost and why.
    pub what: String,
    /// Messages lost, when known.
    pub messages: Option<u64>,
    /// When the exact count is not known: the most `sensor_msgs/Imu` messages the lost
    /// bytes can hold (the tools read Imu topics; other topics' messages may be more).
    pub at_most: Option<u64>,
    /// Record-time span (ns) of the lost data, when known.
    pub span: Option<(u64, u64)>,
    /// The channel the lost messages belong to, when known.
    pub channel: Option<u32>,
}

impl Loss {
    /// A loss of unknown size, on no particular channel.
    pub(crate) fn new(what: impl Into<String>) -> Loss {
        Loss {
            what: what.into(),
            ..Loss::default()
        }
    }
}

impl std::fmt::Display for Loss {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}", self.what)?;
        match (self.messages, self.at_most) {
            (Some(n), _) => write!(f, "; {n} message{} lost", if n == 1 { "" } else { "s" })?,
            (None, Some(n)) => write!(f, "; up to {n} messages lost")?,
            (None, None) => {}
        }
        if let Some((a, b)) = self.span {
            write!(
                f,
                " (record time {} .. {})",
                crate::RosTime::from_nanos(a),
                crate::RosTime::from_nanos(b)
            )?;
        }
        Ok(())
    }
}

/// What reading one part delivered.
#[derive(Debug, Clone, Default)]
pub struct PartRead {
    /// Messages of the wanted channels handed to the callback.
    pub delivered: u64,
    /// Why the part stopped before its end, by kind (the messages before it were delivered).
    pub error: Option<PartError>,
    /// Messages of wanted channels found but not handed out (e.g. a payload that does not
    /// decompress), and why the first of them was skipped.
    pub skipped: u64,
    /// Why the first skipped message was skipped, by kind.
    pub skip_reason: Option<SkipReason>,
    /// Messages the part's own index promises that could not be delivered (damaged record
    /// headers, a resynchronised stretch), with their channel, count and time span.
    pub lost: Vec<Loss>,
    /// What the read found and worked around without losing data (a row read in place of
    /// one whose id is damaged, rows a damaged page holds twice read once, …).
    pub notes: Vec<Note>,
}

/// The callback of [`Source::read_part`]: `(channel id, record time in ns, payload)`.
pub type MessageSink<'a> = dyn FnMut(u32, u64, &[u8]) + 'a;

/// The callback of [`Source::read_part_rows`]: `(channel id, record time in ns, row)`.
pub type RowSink<'a> = dyn FnMut(u32, u64, &crate::rows::Row) + 'a;

/// A container opened for reading.
pub trait Source: Sync {
    /// What it is.
    fn kind(&self) -> InputKind;
    /// What opening found: channels, parts, notes and losses.
    fn contents(&self) -> &Contents;
    /// Its channels.
    fn channels(&self) -> &[Channel] {
        &self.contents().channels
    }
    /// Its parts, in storage order.
    fn parts(&self) -> &[Part] {
        &self.contents().parts
    }
    /// What opening found (unindexed, truncated, scanned, …).
    fn notes(&self) -> &[Note] {
        &self.contents().notes
    }
    /// What opening found lost (incomplete records, unreadable index entries, …).
    fn losses(&self) -> &[Loss] {
        &self.contents().losses
    }
    /// Reads part `part`, calling `sink` for each message of a channel `want` accepts, in
    /// storage order.
    fn read_part(
        &self,
        part: usize,
        want: &(dyn Fn(u32) -> bool + Sync),
        sink: &mut MessageSink<'_>,
    ) -> PartRead;
    /// [`Source::read_part`] for a reader that decodes its Imu channels' rows itself
    /// ([`Encoding::Row`]): the rows go to `sink` as they are, without a payload to encode
    /// and decode again; the channels of other encodings are not delivered. `None`: the
    /// reader has no such path (the bag formats).
    fn read_part_rows(
        &self,
        _part: usize,
        _want: &(dyn Fn(u32) -> bool + Sync),
        _sink: &mut RowSink<'_>,
    ) -> Option<PartRead> {
        None
    }
    /// The whole of an Imu channel's rows, moved out of a reader that decoded them on
    /// opening, for a read that owns the source and reads it once
    /// (`series::read_owned`): no part of the channel delivers rows afterwards.
    /// `None`: the reader keeps no such columns (read the parts).
    fn take_rows(&self, _channel: u32) -> Option<crate::rows::Rows> {
        None
    }
    /// What only a complete read can tell was lost (the rows past the last one a damaged
    /// table still holds, which its timestamp index lists): called once every part was read.
    fn losses_after_read(&self) -> Vec<Loss> {
        Vec::new()
    }
}

/// What a source found on opening, the same for every format: each reader fills one.
#[derive(Debug, Clone, Default)]
pub struct Contents {
    /// Its channels.
    pub channels: Vec<Channel>,
    /// Its parts, in storage order.
    pub parts: Vec<Part>,
    /// What opening found (unindexed, truncated, scanned, …).
    pub notes: Vec<Note>,
    /// What opening found lost.
    pub losses: Vec<Loss>,
    /// When the log itself says it started, ns (a PX4 ULog's header): a message stamped
    /// before it is one its logger wrote when it subscribed (a topic's last message, maybe
    /// long before), not part of the record's span.
    pub log_start: Option<u64>,
    /// Channels of integrated deltas (PX4 `vehicle_imu`), with their rows' median
    /// integration intervals ([`crate::Integration`]).
    pub integration: Vec<(u32, crate::Integration)>,
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The list of accepted inputs every "not a bag" message ends with, as the messages
    /// said it before the list came from the kinds' facts (its bytes are part of the CLI's
    /// output).
    const ACCEPTED_BEFORE: &str = "a ROS 1 bag (format 2.0), a ROS 2 bag directory (metadata.yaml with .db3 or .mcap files), an .mcap file, a rosbag2 .db3 (sqlite3) file, a zstd-compressed .mcap/.db3, a EuRoC/ASL dataset (data.csv, its imuN folder or the dataset root), a CSV/TSV/whitespace text log, a PX4 ULog (.ulg), an ArduPilot DataFlash log (.bin), or a NumPy .npy (N x 7, bag2mat's layout)";

    #[test]
    fn the_accepted_list_is_every_kinds_phrase_unchanged() {
        assert_eq!(accepted(), ACCEPTED_BEFORE);
    }

    #[test]
    fn every_kind_is_in_all_once() {
        for k in InputKind::ALL {
            // exhaustive: a new kind fails to compile here until it is placed in ALL
            let listed = match k {
                InputKind::Ros1Bag
                | InputKind::Mcap
                | InputKind::Sqlite3
                | InputKind::Rosbag2Dir
                | InputKind::Zstd
                | InputKind::Text
                | InputKind::EurocDir
                | InputKind::Npy
                | InputKind::Ulog
                | InputKind::DataFlash => InputKind::ALL.iter().filter(|&&x| x == k).count(),
            };
            assert_eq!(listed, 1, "{k:?}");
        }
        let names: std::collections::HashSet<&str> =
            InputKind::ALL.iter().map(|k| k.describe()).collect();
        assert_eq!(names.len(), InputKind::ALL.len(), "two kinds share a name");
    }
}
