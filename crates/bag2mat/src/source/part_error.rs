//! Why a part's read stopped early, and why a message of it was skipped, as kinds: the
//! readers say what happened by variant, and the text users see is each kind's `Display`
//! (code that needs to know what happened matches the kind, never the words).

use std::sync::Arc;

/// Why reading a part stopped before its end ([`crate::PartRead::error`]); the messages
/// before the stop were delivered.
#[derive(Debug, Clone, thiserror::Error)]
pub enum PartError {
    /// The part asked for is past the source's parts: a caller's mistake, not the data's.
    #[error("{}", .wording.text(*.index))]
    NoSuchPart {
        /// The part index asked for.
        index: usize,
        /// How the reader says it.
        wording: NoSuchPart,
    },
    /// A ROS 1 chunk whose record or body cannot be read.
    #[error(transparent)]
    Ros1Chunk(#[from] Ros1ChunkError),
    /// An MCAP part (chunk or run of unchunked records) whose stored records cannot be read.
    #[error(transparent)]
    McapChunk(#[from] McapChunkError),
    /// The storage could not be opened for the read (a rosbag2 sqlite3 database that no
    /// longer opens).
    #[error(transparent)]
    Storage(Arc<crate::Error>),
    /// A decoded log's rows were moved out (`Source::take_rows`) before this read.
    #[error("the rows were handed over to a read already")]
    RowsTaken,
}

/// How a reader words [`PartError::NoSuchPart`] (each as it always has).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NoSuchPart {
    /// "no such chunk" (ROS 1 bags).
    Chunk,
    /// "no such part" (MCAP, rosbag2).
    Part,
    /// "no part N" (the decoded logs).
    Numbered,
}

impl NoSuchPart {
    fn text(self, index: usize) -> String {
        match self {
            NoSuchPart::Chunk => "no such chunk".to_string(),
            NoSuchPart::Part => "no such part".to_string(),
            NoSuchPart::Numbered => format!("no part {index}"),
        }
    }
}

/// Why a ROS 1 chunk's record or body cannot be read.
#[derive(Debug, Clone, thiserror::Error)]
pub enum Ros1ChunkError {
    /// The chunk record's header or data run past the end of the file.
    #[error("chunk record runs past the end of the file")]
    PastEnd,
    /// The record where the index places a chunk is another record.
    #[error("not a chunk record")]
    NotChunk,
    /// The chunk record's header does not parse (its cause is a `bag2mat` record error).
    #[error(transparent)]
    RecordHeader(Arc<dyn std::error::Error + Send + Sync>),
    /// The chunk's bytes cannot be read from the file.
    #[error("{0}")]
    Io(Arc<std::io::Error>),
    /// The chunk's data do not decompress with the codec its header names.
    #[error("{codec}: {source}")]
    Decompress {
        /// The codec (`bz2`, `lz4`).
        codec: &'static str,
        /// What the codec said.
        source: Arc<std::io::Error>,
    },
    /// The decompressed body is not the size its header states.
    #[error("chunk body is {got} bytes, its header says {size}")]
    Size {
        /// Bytes decompressed.
        got: usize,
        /// Bytes the header states.
        size: usize,
    },
}

/// Why an MCAP part's stored records cannot be read.
#[derive(Debug, Clone, thiserror::Error)]
pub enum McapChunkError {
    /// The part's bytes cannot be read from the file.
    #[error("{0}")]
    Io(Arc<std::io::Error>),
    /// The chunk's records run past the end of the file.
    #[error("the chunk's records run past the end of the file")]
    PastEnd,
    /// The chunk's lz4 data do not decompress.
    #[error("lz4: {0}")]
    Lz4(Arc<std::io::Error>),
    /// The chunk's zstd data do not decompress.
    #[error(transparent)]
    Zstd(Arc<crate::zstd::ZstdError>),
    /// A compression this reader does not know.
    #[error("unsupported chunk compression '{0}'")]
    Compression(String),
    /// The decompressed records are not the size the chunk states.
    #[error("chunk records are {got} bytes, its header says {stated}")]
    Size {
        /// Bytes decompressed.
        got: usize,
        /// Bytes the chunk states.
        stated: u64,
    },
    /// The decompressed records' CRC differs from the stored one.
    #[error("chunk CRC {got:08x} differs from the stored {stored:08x}")]
    Crc {
        /// CRC of the records read.
        got: u32,
        /// CRC the chunk stores.
        stored: u32,
    },
}

/// Why the first skipped message of a part was skipped ([`crate::PartRead::skip_reason`]).
#[derive(Debug, Clone, thiserror::Error)]
pub enum SkipReason {
    /// A rosbag2 message whose zstd-compressed payload does not decompress.
    #[error(transparent)]
    Decompress(Arc<crate::zstd::ZstdError>),
    /// A log message whose fields do not decode as its topic's rows (PX4 ULog).
    #[error("'{topic}': {why}")]
    Undecodable {
        /// The topic.
        topic: String,
        /// What does not decode.
        why: &'static str,
    },
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Each kind says what the readers said as text before there were kinds (the words are
    /// part of the output: `warning:` lines, `bag2mat info`'s losses).
    #[test]
    fn every_kind_says_the_text_the_readers_said() {
        let io = || Arc::new(std::io::Error::other("boom"));
        let cases: Vec<(String, &str)> = vec![
            (
                PartError::NoSuchPart {
                    index: 4,
                    wording: NoSuchPart::Chunk,
                }
                .to_string(),
                "no such chunk",
            ),
            (
                PartError::NoSuchPart {
                    index: 4,
                    wording: NoSuchPart::Part,
                }
                .to_string(),
                "no such part",
            ),
            (
                PartError::NoSuchPart {
                    index: 4,
                    wording: NoSuchPart::Numbered,
                }
                .to_string(),
                "no part 4",
            ),
            (
                PartError::RowsTaken.to_string(),
                "the rows were handed over to a read already",
            ),
            (
                PartError::from(Ros1ChunkError::PastEnd).to_string(),
                "chunk record runs past the end of the file",
            ),
            (
                PartError::from(Ros1ChunkError::NotChunk).to_string(),
                "not a chunk record",
            ),
            (
                PartError::from(Ros1ChunkError::Decompress {
                    codec: "bz2",
                    source: io(),
                })
                .to_string(),
                "bz2: boom",
            ),
            (
                PartError::from(Ros1ChunkError::Size { got: 3, size: 4 }).to_string(),
                "chunk body is 3 bytes, its header says 4",
            ),
            (
                PartError::from(Ros1ChunkError::Io(io())).to_string(),
                "boom",
            ),
            (
                PartError::from(McapChunkError::PastEnd).to_string(),
                "the chunk's records run past the end of the file",
            ),
            (
                PartError::from(McapChunkError::Lz4(io())).to_string(),
                "lz4: boom",
            ),
            (
                PartError::from(McapChunkError::Compression("brotli".into())).to_string(),
                "unsupported chunk compression 'brotli'",
            ),
            (
                PartError::from(McapChunkError::Size { got: 3, stated: 4 }).to_string(),
                "chunk records are 3 bytes, its header says 4",
            ),
            (
                PartError::from(McapChunkError::Crc {
                    got: 0xab,
                    stored: 0x1234_5678,
                })
                .to_string(),
                "chunk CRC 000000ab differs from the stored 12345678",
            ),
            (
                SkipReason::Undecodable {
                    topic: "sensor_gyro_fifo".into(),
                    why: "a FIFO message with a zero dt",
                }
                .to_string(),
                "'sensor_gyro_fifo': a FIFO message with a zero dt",
            ),
        ];
        for (said, before) in cases {
            assert_eq!(said, before);
        }
    }
}
