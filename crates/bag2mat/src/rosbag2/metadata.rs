//! rosbag2's `metadata.yaml`: read (every version from Foxy on; unknown fields are ignored)
//! and written (version 8 fields, which ROS 2 Iron and later write and older readers skip).

use serde::Deserialize;

/// The parts of `rosbag2_bagfile_information` the readers use.
#[derive(Debug, Clone, Default, Deserialize)]
#[serde(default)]
pub struct BagInfo {
    /// Metadata version.
    pub version: u32,
    /// `sqlite3` or `mcap`.
    pub storage_identifier: Option<String>,
    /// The storage files, in recording order, relative to the bag directory.
    pub relative_file_paths: Vec<String>,
    /// `zstd` or empty.
    pub compression_format: Option<String>,
    /// `file`, `message` or empty.
    pub compression_mode: Option<String>,
    /// Messages in the bag.
    pub message_count: u64,
    /// Every topic with its message count.
    pub topics_with_message_count: Vec<TopicWithCount>,
}

/// One entry of `topics_with_message_count`.
#[derive(Debug, Clone, Default, Deserialize)]
#[serde(default)]
pub struct TopicWithCount {
    /// The topic.
    pub topic_metadata: TopicMetadata,
    /// Messages recorded on it.
    pub message_count: u64,
}

/// `topic_metadata`.
#[derive(Debug, Clone, Default, Deserialize)]
#[serde(default)]
pub struct TopicMetadata {
    /// Topic name.
    pub name: String,
    /// ROS 2 type, e.g. `sensor_msgs/msg/Imu`.
    #[serde(rename = "type")]
    pub msg_type: String,
    /// `cdr` (or `ros1` for converted bags).
    pub serialization_format: String,
}

#[derive(Deserialize)]
struct MetadataFile {
    rosbag2_bagfile_information: BagInfo,
}

/// Why a `metadata.yaml` is no bag's metadata: the YAML parser's message.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{0}")]
pub(crate) struct MetadataError(String);

impl BagInfo {
    /// Parses the text of a `metadata.yaml`.
    pub(crate) fn parse(text: &str) -> Result<BagInfo, MetadataError> {
        // The parser's message: its first line (the excerpt after it is the file's text),
        // without its own "error: ".
        serde_saphyr::from_str::<MetadataFile>(text)
            .map(|m| m.rosbag2_bagfile_information)
            .map_err(|e| {
                let s = e.to_string();
                let first = s.lines().next().unwrap_or("").trim();
                MetadataError(first.strip_prefix("error: ").unwrap_or(first).to_string())
            })
    }

    /// The compression format, empty when none.
    pub(crate) fn compression_format(&self) -> &str {
        self.compression_format.as_deref().unwrap_or("")
    }

    /// The compression mode in lower case, empty when none.
    pub(crate) fn compression_mode(&self) -> String {
        self.compression_mode
            .as_deref()
            .unwrap_or("")
            .to_ascii_lowercase()
    }
}

/// The QoS profile `ros2 bag record` stores for a reliable, volatile sensor topic, in the
/// YAML form every rosbag2 release reads (integer policy values, infinite durations).
pub const OFFERED_QOS_PROFILES: &str = "- history: 3\n  depth: 0\n  reliability: 1\n  durability: 2\n  deadline:\n    sec: 9223372036\n    nsec: 854775807\n  lifespan:\n    sec: 9223372036\n    nsec: 854775807\n  liveliness: 1\n  liveliness_lease_duration:\n    sec: 9223372036\n    nsec: 854775807\n  avoid_ros_namespace_conventions: false";

/// A topic as written into `metadata.yaml`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct WrittenTopic {
    /// Topic name.
    pub name: String,
    /// ROS 2 type.
    pub msg_type: String,
    /// Type description hash (`RIHS01_…`), empty when unknown.
    pub type_hash: String,
    /// Messages written.
    pub count: u64,
}

/// What a finished bag holds, for [`write_yaml`].
#[derive(Debug, Clone)]
pub struct WrittenBag {
    /// `sqlite3` or `mcap`.
    pub storage: &'static str,
    /// The one storage file, relative to the directory.
    pub file: String,
    /// Topics in declaration order.
    pub topics: Vec<WrittenTopic>,
    /// First and last record time, ns.
    pub span: Option<(u64, u64)>,
}

fn quoted(s: &str) -> String {
    let mut o = String::from("\"");
    for c in s.chars() {
        match c {
            '"' => o.push_str("\\\""),
            '\\' => o.push_str("\\\\"),
            '\n' => o.push_str("\\n"),
            c => o.push(c),
        }
    }
    o.push('"');
    o
}

/// The `metadata.yaml` text of a finished bag.
pub fn write_yaml(b: &WrittenBag) -> String {
    let (start, end) = b.span.unwrap_or((0, 0));
    let duration = end - start;
    let total: u64 = b.topics.iter().map(|t| t.count).sum();
    let mut s = String::from("rosbag2_bagfile_information:\n");
    s.push_str("  version: 8\n");
    s.push_str(&format!("  storage_identifier: {}\n", b.storage));
    s.push_str(&format!(
        "  duration:\n    nanoseconds: {duration}\n  starting_time:\n    nanoseconds_since_epoch: {start}\n"
    ));
    s.push_str(&format!("  message_count: {total}\n"));
    s.push_str("  topics_with_message_count:\n");
    for t in &b.topics {
        s.push_str(&format!(
            "    - topic_metadata:\n        name: {}\n        type: {}\n        serialization_format: cdr\n        offered_qos_profiles: {}\n        type_description_hash: {}\n      message_count: {}\n",
            quoted(&t.name),
            t.msg_type,
            quoted(OFFERED_QOS_PROFILES),
            quoted(&t.type_hash),
            t.count
        ));
    }
    s.push_str("  compression_format: \"\"\n  compression_mode: \"\"\n");
    s.push_str(&format!(
        "  relative_file_paths:\n    - {}\n",
        quoted(&b.file)
    ));
    s.push_str(&format!(
        "  files:\n    - path: {}\n      starting_time:\n        nanoseconds_since_epoch: {start}\n      duration:\n        nanoseconds: {duration}\n      message_count: {total}\n",
        quoted(&b.file)
    ));
    s.push_str("  custom_data: ~\n  ros_distro: \"\"\n");
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn written_yaml_parses_back() {
        let b = WrittenBag {
            storage: "mcap",
            file: "x_0.mcap".into(),
            topics: vec![WrittenTopic {
                name: "/imu0".into(),
                msg_type: "sensor_msgs/msg/Imu".into(),
                type_hash: "RIHS01_ab".into(),
                count: 12,
            }],
            span: Some((5, 9)),
        };
        let i = BagInfo::parse(&write_yaml(&b)).unwrap();
        assert_eq!(i.version, 8);
        assert_eq!(i.relative_file_paths, vec!["x_0.mcap".to_string()]);
        assert_eq!(i.message_count, 12);
        assert_eq!(i.topics_with_message_count[0].topic_metadata.name, "/imu0");
        assert_eq!(i.compression_mode(), "");
    }

    /// Foxy's metadata (version 4: QoS as a string, no compression keys, no custom_data).
    #[test]
    fn old_versions_parse() {
        let foxy = "rosbag2_bagfile_information:\n  version: 4\n  storage_identifier: sqlite3\n  relative_file_paths:\n    - a_0.db3\n  duration:\n    nanoseconds: 10\n  starting_time:\n    nanoseconds_since_epoch: 1\n  message_count: 3\n  topics_with_message_count:\n    - topic_metadata:\n        name: /imu\n        type: sensor_msgs/msg/Imu\n        serialization_format: cdr\n        offered_qos_profiles: \"- history: 3\\n  depth: 0\"\n      message_count: 3\n  compression_format: \"\"\n  compression_mode: \"\"\n";
        let i = BagInfo::parse(foxy).unwrap();
        assert_eq!(i.storage_identifier.as_deref(), Some("sqlite3"));
        assert_eq!(i.topics_with_message_count[0].message_count, 3);
        assert!(BagInfo::parse("not: [yaml").is_err());
    }
}
