//! The one error type of the bag2mat library. Binaries add context and print it once.

use std::path::PathBuf;

/// A topic in a bag, as listed when the requested topic is missing.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct TopicSummary {
    /// Topic name.
    pub topic: String,
    /// Message type.
    pub msg_type: String,
    /// Number of messages (from the index, or counted while scanning).
    pub count: u64,
}

/// Everything that can go wrong reading or writing bags and `.mat` files.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// An operating-system error on a path.
    // The cause is part of the message and deliberately not a `source`: anyhow's chained
    // output would print it twice.
    #[error("{}: {}", .path.display(), describe(.cause))]
    Io {
        /// The file.
        path: PathBuf,
        /// The cause.
        cause: std::io::Error,
    },
    /// An output that must not be written (an input of the run, a directory, …).
    #[error("{}: not written: {what}", .path.display())]
    Output {
        /// The output path as given.
        path: PathBuf,
        /// Why.
        what: String,
    },
    /// The input is none of the accepted kinds (see [`crate::source::accepted`]).
    #[error("{path}: not a bag this tool reads: {what}")]
    NotABag {
        /// The file.
        path: PathBuf,
        /// What was found instead.
        what: String,
    },
    /// A log (text, ULog, DataFlash, NumPy) was recognised but cannot be read as asked: what
    /// to add or change is in the message.
    #[error("{}: {what}", .path.display())]
    Log {
        /// The file.
        path: PathBuf,
        /// What is wrong, and what to add.
        what: String,
    },
    /// A topic that carries one sensor only (its other sensor's columns are NaN) was given to
    /// an analysis that needs both.
    #[error(
        "topic '{}' carries no {} (a topic of one sensor: PX4 sensor_gyro/sensor_accel, ArduPilot ISB batches, a text log without those columns); the analysers fit both sensors together: analyse a topic with both (sensor_combined, vehicle_imu, IMU), or convert this one with bag2mat",
        crate::printable::escape(.topic),
        .missing.name()
    )]
    OneSensor {
        /// The topic.
        topic: String,
        /// The sensor it lacks.
        missing: crate::Sensor,
    },
    /// A topic of integrated deltas whose rows do not tile the time: no samples to analyse.
    #[error(transparent)]
    DeadTime(#[from] crate::integrated::DeadTime),
    /// A storage file (sqlite3, metadata.yaml) could not be read.
    #[error("{path}: {what}")]
    Storage {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        what: String,
    },
    /// A record or chunk could not be parsed.
    #[error("{path}: corrupt bag at byte {offset}: {what}")]
    Corrupt {
        /// The file.
        path: PathBuf,
        /// File offset of the bad record.
        offset: u64,
        /// What is wrong.
        what: String,
    },
    /// No topic of that name (in either slash form).
    #[error("{}", topic_not_found(.topic, .available))]
    TopicNotFound {
        /// The topic asked for.
        topic: String,
        /// Every topic in the bag.
        available: Vec<TopicSummary>,
    },
    /// `--all-imu-topics` found no topic carrying `sensor_msgs/Imu`.
    #[error("{}", no_imu_topic(.available))]
    NoImuTopic {
        /// Every topic in the bag.
        available: Vec<TopicSummary>,
    },
    /// No topic named and several carry `sensor_msgs/Imu`: which one is the user's to say.
    #[error("{}", several_imu_topics(.available))]
    SeveralImuTopics {
        /// Every topic in the bag.
        available: Vec<TopicSummary>,
    },
    /// The topic exists but does not carry `sensor_msgs/Imu` (with the right md5 for ROS 1).
    #[error(
        "topic '{}' carries {} [{}], not sensor_msgs/Imu [{}] or sensor_msgs/msg/Imu [cdr]",
        crate::printable::escape(.topic),
        crate::printable::escape(.msg_type),
        crate::printable::escape(.md5sum),
        crate::imu_msg::MD5
    )]
    WrongType {
        /// The topic.
        topic: String,
        /// Its type.
        msg_type: String,
        /// Its md5.
        md5sum: String,
    },
    /// The input holds no topic at all (empty, or cut short before any complete chunk).
    #[error("{}", no_topics(.why))]
    NoTopics {
        /// What the reader found (truncation, damage).
        why: Vec<String>,
    },
    /// A topic the user asked for yielded no row at all (every message lost or undecodable,
    /// or none recorded): an error, never an empty matrix.
    #[error("{}", nothing_read(.topic, .why))]
    NothingRead {
        /// The topic.
        topic: String,
        /// What the reader found (losses, notes).
        why: Vec<String>,
    },
    /// A message's bytes do not decode as the expected type.
    #[error("bad message: {what}")]
    BadMessage {
        /// What is wrong.
        what: String,
    },
    /// A plot could not be drawn.
    #[error("plot {path}: {what}")]
    Plot {
        /// The output file.
        path: PathBuf,
        /// The backend's message.
        what: DrawError,
    },
    /// A `.mat` file could not be read or written as an N×7 `data_imu`.
    #[error("{path}: {what}")]
    Mat {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        what: String,
    },
}

fn no_topics(why: &[String]) -> String {
    if why.is_empty() {
        return "the input holds no topic at all".to_string();
    }
    let mut s = "the input holds no readable topic:".to_string();
    for w in why {
        s.push_str("\n  ");
        s.push_str(w);
    }
    s
}

fn nothing_read(topic: &str, why: &[String]) -> String {
    if why.is_empty() {
        return format!(
            "topic '{}' holds no message",
            crate::printable::escape(topic)
        );
    }
    let mut s = format!(
        "no message of topic '{}' could be read:",
        crate::printable::escape(topic)
    );
    for w in why {
        s.push_str("\n  ");
        s.push_str(w);
    }
    s
}

fn no_imu_topic(available: &[TopicSummary]) -> String {
    let mut s = "no topic carries sensor_msgs/Imu".to_string();
    list_topics(&mut s, available);
    s
}

fn several_imu_topics(available: &[TopicSummary]) -> String {
    let mut s = "no topic named and several carry sensor_msgs/Imu: name one (TOPIC, --topic) or pass --all-imu-topics".to_string();
    list_topics(&mut s, available);
    s
}

fn topic_not_found(topic: &str, available: &[TopicSummary]) -> String {
    let mut s = format!(
        "no sensor_msgs/Imu topic '{}' in the bag",
        crate::printable::escape(topic)
    );
    list_topics(&mut s, available);
    s
}

fn list_topics(s: &mut String, available: &[TopicSummary]) {
    if available.is_empty() {
        s.push_str(" (the bag has no topics at all)");
    } else {
        s.push_str("; topics in the bag:");
        for t in available {
            // Names come from the file: control bytes are escaped.
            s.push_str(&format!(
                "\n  {:<30} {:>10} msgs : {}",
                crate::printable::escape(&t.topic),
                t.count,
                crate::printable::escape(&t.msg_type)
            ));
        }
    }
}

impl Error {
    /// Wraps an I/O error with its path.
    pub fn io(path: impl Into<PathBuf>, cause: std::io::Error) -> Error {
        Error::Io {
            path: path.into(),
            cause,
        }
    }
}

impl From<crate::imu_msg::BadMessage> for Error {
    fn from(e: crate::imu_msg::BadMessage) -> Error {
        Error::BadMessage { what: e.0 }
    }
}

/// A plain description of an OS error: no "(os error N)", and the usual causes named the
/// way a person reads them.
pub fn describe(e: &std::io::Error) -> String {
    use std::io::ErrorKind as K;
    match e.kind() {
        K::NotFound => "no such file or directory".into(),
        K::PermissionDenied => "permission denied".into(),
        K::AlreadyExists => "a file is in the way (it already exists)".into(),
        K::IsADirectory => "it is a directory".into(),
        K::NotADirectory => "a component of the path is not a directory".into(),
        K::StorageFull => "no space left on the device".into(),
        K::ReadOnlyFilesystem => "the file system is read-only".into(),
        K::DirectoryNotEmpty => "a directory that is not empty is in the way".into(),
        _ => without_errno(&e.to_string()),
    }
}

/// An OS error's text without its "(os error N)".
pub(crate) fn without_errno(s: &str) -> String {
    match s.find(" (os error") {
        Some(i) => s[..i].to_string(),
        None => s.to_string(),
    }
}

/// A chart that could not be drawn, said in words: plotters' errors are generic over the
/// backend, so each becomes its text where it arises (a failed write as every tool says an
/// I/O error: `shared::plot::present`).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{0}")]
pub struct DrawError(pub(crate) String);

impl<E: std::error::Error + Send + Sync> From<plotters::drawing::DrawingAreaErrorKind<E>>
    for DrawError
{
    fn from(e: plotters::drawing::DrawingAreaErrorKind<E>) -> DrawError {
        DrawError(e.to_string())
    }
}

impl From<Box<dyn std::error::Error>> for DrawError {
    fn from(e: Box<dyn std::error::Error>) -> DrawError {
        DrawError(e.to_string())
    }
}

impl From<&str> for DrawError {
    fn from(what: &str) -> DrawError {
        DrawError(what.to_owned())
    }
}
