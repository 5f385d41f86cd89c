//! Streaming reader for bag format 2.0.
//!
//! [`BagReader::open`] never trusts one structure alone. It reads the index section
//! (connections and chunk infos) record by record, skipping what is damaged, and it always
//! walks the chunk section itself: every chunk record and the index-data records that follow
//! it (the chunk's own `(time, offset)` list per connection). Every chunk found either way is
//! a [`Part`]; the chunk infos are cross-checked against the chunks (a chunk the index does
//! not list is read and noted; an info that points nowhere is reported). The walk stops at
//! the end of the chunks (the index section, an incomplete record at a truncation) and
//! resynchronises on the next chunk after a damaged record. Counts from the file never size
//! memory: promises come from the chunk's own index data, which the file physically holds.
//!
//! Reading a chunk walks its records; a record whose framing is damaged is skipped and the
//! walk resumes at the next message its index data lists (or the next valid record), and
//! every message the chunk's index lists that was not delivered is reported with its count
//! and time span.

use crate::shared::note::Note;

mod chunk;
mod layout;

use std::collections::{BTreeMap, BTreeSet};
use std::fs::File;
use std::io::Read;
use std::os::unix::fs::FileExt;
use std::path::{Path, PathBuf};

use super::Compression;
use super::record::{
    self, BagHeader, ChunkHeader, ChunkInfo, Connection, Header, INDEX_ENTRY_LEN, IndexData, MAGIC,
    Op, RecordError,
};
use crate::error::{Error, TopicSummary};
use crate::source::{
    self, Encoding, InputKind, Loss, MessageSink, Part, PartRead, Ros1ChunkError, Source,
};
use crate::time::RosTime;
use chunk::{BodyRecord, find, walk_body};

thread_local! {
    /// Per-thread (raw, decompressed) chunk buffers, reused across chunks.
    static BUFFERS: std::cell::RefCell<(Vec<u8>, Vec<u8>)> = const { std::cell::RefCell::new((Vec::new(), Vec::new())) };
}

/// Largest record header accepted (real headers are under 1 KiB: a damaged length must not
/// make the reader allocate the file).
const MAX_RECORD_HEADER: u64 = 64 * 1024;
/// Bytes searched, after a damaged top-level record, for the next chunk record.
const RESYNC_WINDOW: usize = 1 << 20;

/// One index-data record of a chunk (the `(time, offset in the chunk body)` of each
/// message of one connection): where its entries are and how many the file holds. The
/// entries are read only when a chunk does not deliver what they list.
#[derive(Debug, Clone, Copy, Default)]
struct ChunkIndexData {
    count: u64,
    data_pos: u64,
}

/// Where a chunk is, and what it and the index say it holds.
#[derive(Debug, Clone)]
struct ChunkLoc {
    pos: u64,
    /// Bytes of the chunk record's data (compressed body), when the walk saw it.
    stored: Option<u64>,
    /// Uncompressed body size from the chunk header, when the walk saw it.
    size: Option<u64>,
    /// The chunk's own index data per connection (found after the chunk by the walk).
    index_data: BTreeMap<u32, ChunkIndexData>,
    /// `(connection, count)` from the chunk info, when the index lists the chunk.
    info_counts: Option<Vec<(u32, u32)>>,
    /// Time span from the chunk info.
    span: Option<(RosTime, RosTime)>,
}

impl ChunkLoc {
    /// Messages per connection the bag promises for this chunk: its own index data when
    /// present (entries the file physically holds), else the chunk info.
    fn promised(&self) -> Option<Vec<(u32, u64)>> {
        if !self.index_data.is_empty() {
            return Some(self.index_data.iter().map(|(c, d)| (*c, d.count)).collect());
        }
        self.info_counts
            .as_ref()
            .map(|v| v.iter().map(|&(c, n)| (c, n as u64)).collect())
    }
}

/// What the bag holds: its connections and the number of messages on each.
#[derive(Debug, Clone)]
pub struct BagIndex {
    /// Every connection, in id order.
    pub connections: Vec<Connection>,
    /// Messages per connection id.
    pub counts: BTreeMap<u32, u64>,
    /// Number of chunks.
    pub chunk_count: usize,
    /// Whether the index section was used (false: the chunks were scanned).
    pub indexed: bool,
}

/// An open bag.
pub struct BagReader {
    path: PathBuf,
    file: File,
    len: u64,
    chunks: Vec<ChunkLoc>,
    index: BagIndex,
    contents: source::Contents,
}

/// The top-level records a walk found.
#[derive(Default)]
struct Walk {
    chunks: Vec<ChunkLoc>,
    connections: Vec<Connection>,
}

/// A record's header bytes, data position and data length.
type RecordAt = (Vec<u8>, u64, u32);

impl BagReader {
    /// Opens a bag: reads its index section, walks its chunk section, and cross-checks them.
    pub fn open(path: &Path) -> Result<BagReader, Error> {
        let mut file = File::open(path).map_err(|e| Error::io(path, e))?;
        let len = file.metadata().map_err(|e| Error::io(path, e))?.len();
        let mut head = vec![0u8; 13 + 8 + record::BAG_HEADER_PADDED_LEN];
        let got = read_up_to(&mut file, &mut head).map_err(|e| Error::io(path, e))?;
        head.truncate(got);
        magic_line(path, &head)?;
        let corrupt = |offset: u64, what: String| Error::Corrupt {
            path: path.to_path_buf(),
            offset,
            what,
        };
        // The bag header names the index; when it is damaged, the chunks after its usual
        // 4104 bytes are walked as for a bag without an index.
        let header = bag_header(&head);
        let mut header_damage = None;
        let (index_pos, chunk_count, first) = match header {
            Ok(h) => h,
            Err(e) if len > record::FIRST_RECORD_POS => {
                header_damage = Some(e);
                (0, None, record::FIRST_RECORD_POS)
            }
            Err(_) => {
                return Err(corrupt(
                    13,
                    format!(
                        "the bag header record is incomplete (the file is {len} bytes: truncated, no complete chunk)"
                    ),
                ));
            }
        };
        let mut reader = BagReader {
            path: path.to_path_buf(),
            file,
            len,
            chunks: Vec::new(),
            index: BagIndex {
                connections: Vec::new(),
                counts: BTreeMap::new(),
                chunk_count: 0,
                indexed: false,
            },
            contents: source::Contents::default(),
        };
        if let Some(e) = &header_damage {
            reader.contents.notes.push(Note::warning(format!(
                "the bag header is damaged ({e}); the chunks after it were walked without the index"
            )));
        }
        let index_ok = index_pos >= first && index_pos < len;
        let (index_conns, infos) = if index_ok {
            reader.read_index(index_pos)
        } else {
            if header_damage.is_none() {
                reader.no_index(index_pos);
            }
            (Vec::new(), Vec::new())
        };
        let walk_end = if index_ok { index_pos } else { len };
        let info_positions: BTreeSet<u64> = infos.iter().map(|i| i.chunk_pos).collect();
        let walk = reader.walk(first, walk_end, &info_positions);
        reader.merge(walk, index_conns, infos, chunk_count);
        if reader.chunks.is_empty() && reader.index.connections.is_empty() {
            let what = if len <= first + 8 {
                "truncated, no complete chunk (only the bag header is there)".to_string()
            } else {
                "truncated or damaged, no complete chunk".to_string()
            };
            return Err(corrupt(first, what));
        }
        reader.build_interface();
        Ok(reader)
    }

    /// Why the chunks are walked without the index, when the bag header is intact: no
    /// index, one past the end of the file (a loss), or one that points into the header.
    fn no_index(&mut self, index_pos: u64) {
        let len = self.len;
        if index_pos == 0 {
            self.contents.notes.push(Note::warning("the bag has no index (index_pos = 0: the writer did not finish); its chunks were walked (`rosbag reindex` repairs it)".to_string()));
        } else if index_pos >= len {
            self.contents.losses.push(Loss::new(format!(
                "the file ends at byte {len}, before its index at byte {index_pos}: it was cut short, and what its last {} or more bytes held is lost; the chunks that are there were walked",
                index_pos - len
            )));
        } else {
            self.contents.notes.push(Note::warning(format!(
                "the bag's index_pos {index_pos} points into its header; its chunks were walked"
            )));
        }
    }

    /// The channels and parts of the [`Source`] interface.
    fn build_interface(&mut self) {
        let all_counted = self.chunks.iter().all(|c| c.promised().is_some());
        let mut counts: BTreeMap<u32, u64> = BTreeMap::new();
        for c in &self.chunks {
            for (conn, n) in c.promised().into_iter().flatten() {
                *counts.entry(conn).or_default() += n;
            }
        }
        self.index.counts = counts.clone();
        self.contents.channels = self
            .index
            .connections
            .iter()
            .map(|c| source::Channel {
                id: c.id,
                topic: c.topic.clone(),
                msg_type: c.msg_type.clone(),
                encoding: Encoding::Ros1,
                md5sum: Some(c.md5sum.clone()),
                count: all_counted.then(|| counts.get(&c.id).copied().unwrap_or(0)),
            })
            .collect();
        let ends: Vec<u64> = self
            .chunks
            .iter()
            .skip(1)
            .map(|c| c.pos)
            .chain([self.len])
            .collect();
        self.contents.parts = self
            .chunks
            .iter()
            .zip(ends)
            .map(|(c, end)| {
                let stored = c.stored.unwrap_or(end.saturating_sub(c.pos));
                Part {
                    label: format!("chunk at byte {}", c.pos),
                    span: self.time_span(c),
                    counts: c.promised(),
                    bytes: c
                        .size
                        .unwrap_or(u64::MAX)
                        .min(stored.saturating_mul(source::MAX_EXPANSION)),
                }
            })
            .collect();
    }

    /// Connections and counts.
    pub fn index(&self) -> &BagIndex {
        &self.index
    }

    /// Every topic with its type and message count, sorted by topic.
    pub fn topics(&self) -> Vec<TopicSummary> {
        let mut by_topic: BTreeMap<(&str, &str), u64> = BTreeMap::new();
        for c in &self.index.connections {
            *by_topic.entry((&c.topic, &c.msg_type)).or_default() +=
                self.index.counts.get(&c.id).copied().unwrap_or(0);
        }
        by_topic
            .into_iter()
            .map(|((t, ty), count)| TopicSummary {
                topic: t.to_string(),
                msg_type: ty.to_string(),
                count,
            })
            .collect()
    }

    fn bytes_at(&self, pos: u64, len: u32) -> Result<Vec<u8>, Error> {
        if pos + len as u64 > self.len {
            return Err(self.corrupt(pos, "record runs past the end of the file"));
        }
        let mut buf = vec![0u8; len as usize];
        self.file
            .read_exact_at(&mut buf, pos)
            .map_err(|e| Error::io(&self.path, e))?;
        Ok(buf)
    }

    fn corrupt(&self, offset: u64, what: impl Into<String>) -> Error {
        Error::Corrupt {
            path: self.path.clone(),
            offset,
            what: what.into(),
        }
    }

    /// The header bytes, data position and data length of the record at `pos`, if it is
    /// whole before `end` and its header is of a sane size.
    /// The most Imu messages the incomplete record at `pos` (the end of a truncated bag)
    /// can have held: a chunk its header's uncompressed size, bounded by what its stored
    /// bytes decompress to; else what the bytes left hold.
    fn tail_capacity(&self, pos: u64) -> Option<u64> {
        let stored = self.len.saturating_sub(pos);
        let mut b4 = [0u8; 4];
        let size = self
            .file
            .read_exact_at(&mut b4, pos)
            .ok()
            .map(|_| u32::from_le_bytes(b4) as u64)
            .filter(|&h| h <= MAX_RECORD_HEADER && pos + 4 + h <= self.len)
            .and_then(|h| {
                let mut hb = vec![0u8; h as usize];
                self.file.read_exact_at(&mut hb, pos + 4).ok()?;
                let hd = Header::parse(&hb).ok()?;
                (hd.op().ok()? == Op::Chunk).then_some(())?;
                hd.u32("size").ok().map(|s| s as u64)
            });
        let bound = stored.saturating_mul(source::MAX_EXPANSION);
        // A header cut short says nothing of the records after it.
        size.map(|s| s.min(bound) / crate::imu_msg::MIN_IMU_PAYLOAD)
    }

    fn record_at(&self, pos: u64, end: u64) -> Option<RecordAt> {
        let mut b4 = [0u8; 4];
        self.file.read_exact_at(&mut b4, pos).ok()?;
        let hlen = u32::from_le_bytes(b4) as u64;
        if hlen > MAX_RECORD_HEADER || pos + 4 + hlen + 4 > end {
            return None;
        }
        let mut header = vec![0u8; hlen as usize];
        self.file.read_exact_at(&mut header, pos + 4).ok()?;
        self.file.read_exact_at(&mut b4, pos + 4 + hlen).ok()?;
        let dlen = u32::from_le_bytes(b4);
        let data_pos = pos + 8 + hlen;
        if data_pos + dlen as u64 > end {
            return None;
        }
        Some((header, data_pos, dlen))
    }

    /// The path this reader was opened on.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// File size in bytes.
    pub fn file_len(&self) -> u64 {
        self.len
    }
}

impl Source for BagReader {
    fn kind(&self) -> InputKind {
        InputKind::Ros1Bag
    }
    fn contents(&self) -> &source::Contents {
        &self.contents
    }
    fn read_part(
        &self,
        part: usize,
        want: &(dyn Fn(u32) -> bool + Sync),
        sink: &mut MessageSink<'_>,
    ) -> PartRead {
        match self.chunks.get(part) {
            Some(c) => self.for_each_in_chunk(c, want, sink),
            None => PartRead {
                error: Some(source::PartError::NoSuchPart {
                    index: part,
                    wording: source::NoSuchPart::Chunk,
                }),
                ..PartRead::default()
            },
        }
    }
}

fn read_up_to(file: &mut File, buf: &mut [u8]) -> std::io::Result<usize> {
    let mut got = 0;
    while got < buf.len() {
        let n = file.read(&mut buf[got..])?;
        if n == 0 {
            break;
        }
        got += n;
    }
    Ok(got)
}

/// The version line: an error naming what is there when it is not ROS 1's `#ROSBAG V2.0`.
fn magic_line(path: &Path, head: &[u8]) -> Result<(), Error> {
    if head.len() < MAGIC.len() || &head[..MAGIC.len()] != MAGIC {
        let what = if head.starts_with(b"#ROSBAG V") {
            format!(
                "unsupported version line {:?}",
                String::from_utf8_lossy(&head[..head.len().min(13)])
            )
        } else {
            "missing the '#ROSBAG V2.0' magic line".to_string()
        };
        return Err(Error::NotABag {
            path: path.to_path_buf(),
            what,
        });
    }
    Ok(())
}

/// The bag header after the version line: the index position (0: none), the chunk count
/// it states and where the first record after it starts; or what is wrong with it.
fn bag_header(head: &[u8]) -> Result<(u64, Option<u32>, u64), BagHeaderDamage> {
    let rec = record::raw_record(head, MAGIC.len()).ok_or(BagHeaderDamage::Incomplete)?;
    let h = Header::parse(rec.header)?;
    let b = BagHeader::decode(&h).map_err(|e| match e {
        RecordError::Unexpected(_) => BagHeaderDamage::NotFirst,
        e => BagHeaderDamage::Record(e),
    })?;
    Ok((b.index_pos.unwrap_or(0), b.chunk_count, rec.end as u64))
}

/// Why the bag header does not read (the chunks after it are then walked without the
/// index).
#[derive(Debug, thiserror::Error)]
enum BagHeaderDamage {
    #[error("the bag header record is incomplete")]
    Incomplete,
    #[error("the first record is not the bag header")]
    NotFirst,
    #[error(transparent)]
    Record(#[from] RecordError),
}
