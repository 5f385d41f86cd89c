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

use std::collections::{BTreeMap, BTreeSet};
use std::fs::File;
use std::io::Read;
use std::os::unix::fs::FileExt;
use std::path::{Path, PathBuf};

use super::record::{
    self, BagHeader, ChunkHeader, ChunkInfo, Connection, Header, INDEX_ENTRY_LEN, IndexData, MAGIC,
    Op, RecordError,
};
use super::{Compression, RosTime};
use crate::error::{Error, TopicSummary};
use crate::source::{self, Encoding, InputKind, Loss, MessageSink, Part, PartRead, Source};

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

/// One topic of a bag as [`BagReader::topics`] lists it.
pub type ConnectionSummary = TopicSummary;

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
        let corrupt = |offset: u64, what: String| Error::Corrupt {
            path: path.to_path_buf(),
            offset,
            what,
        };
        // The bag header names the index; when it is damaged, the chunks after its usual
        // 4104 bytes are walked as for a bag without an index.
        let header = record::raw_record(&head, MAGIC.len())
            .ok_or_else(|| "the bag header record is incomplete".to_string())
            .and_then(|rec| {
                let h = Header::parse(rec.header).map_err(|e| e.to_string())?;
                let b = BagHeader::decode(&h).map_err(|e| match e {
                    RecordError::Unexpected(_) => "the first record is not the bag header".into(),
                    e => e.to_string(),
                })?;
                Ok((b.index_pos.unwrap_or(0), b.chunk_count, rec.end as u64))
            });
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
            reader.contents.notes.push(format!(
                "the bag header is damaged ({e}); the chunks after it were walked without the index"
            ));
        }
        let index_ok = index_pos >= first && index_pos < len;
        let (index_conns, infos) = if index_ok {
            reader.read_index(index_pos)
        } else {
            if header_damage.is_some() {
            } else if index_pos == 0 {
                reader.contents.notes.push("the bag has no index (index_pos = 0: the writer did not finish); its chunks were walked (`rosbag reindex` repairs it)".to_string());
            } else if index_pos >= len {
                reader.contents.losses.push(Loss::new(format!(
                    "the file ends at byte {len}, before its index at byte {index_pos}: it was cut short, and what its last {} or more bytes held is lost; the chunks that are there were walked",
                    index_pos - len
                )));
            } else {
                reader.contents.notes.push(format!(
                    "the bag's index_pos {index_pos} points into its header; its chunks were walked"
                ));
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

    /// Reads the index section record by record: connections and chunk infos. A damaged
    /// record is skipped (noted); damaged framing ends the section (the walk still finds
    /// every chunk).
    fn read_index(&mut self, index_pos: u64) -> (Vec<Connection>, Vec<ChunkInfo>) {
        let mut connections = Vec::new();
        let mut infos = Vec::new();
        let mut pos = index_pos;
        let mut damaged = 0;
        while pos < self.len {
            let Some((hb, data_pos, dlen)) = self.record_at(pos, self.len) else {
                self.contents.notes.push(format!(
                    "the index section is damaged at byte {pos} (a record runs past the end of the file); the chunks were walked instead"
                ));
                break;
            };
            let data = self.bytes_at(data_pos, dlen).unwrap_or_default();
            let decoded = Header::parse(&hb).and_then(|h| match h.op()? {
                Op::Connection => Connection::decode(&h, &data).map(|c| connections.push(c)),
                Op::ChunkInfo => ChunkInfo::decode(&h, &data).map(|i| infos.push(i)),
                other => Err(RecordError::Unexpected(other)),
            });
            if let Err(e) = decoded {
                damaged += 1;
                if damaged == 1 {
                    self.contents.notes.push(format!(
                        "the index section has a damaged record at byte {pos} ({e}); skipped, the chunks themselves were walked"
                    ));
                }
            }
            pos = data_pos + dlen as u64;
        }
        if damaged > 1 {
            self.contents.notes.push(format!(
                "{damaged} damaged index records were skipped in all"
            ));
        }
        (connections, infos)
    }

    /// Walks the chunk section from `first` to `end`: chunk records (header only), the
    /// index-data records after each, and stray connection records. Stops at the index
    /// section or an incomplete record; after a damaged record, resumes at the next chunk.
    fn walk(&mut self, first: u64, end: u64, info_positions: &BTreeSet<u64>) -> Walk {
        let mut w = Walk::default();
        let mut pos = first;
        while pos < end {
            let Some((hb, data_pos, dlen)) = self.record_at(pos, end) else {
                if end == self.len {
                    let at_most = self.tail_capacity(pos);
                    self.contents.losses.push(Loss {
                        at_most,
                        ..Loss::new(format!(
                            "the last {} bytes of the file are an incomplete record (truncated bag); they were skipped",
                            self.len - pos
                        ))
                    });
                } else {
                    self.damaged_at(
                        pos,
                        end,
                        "a record runs past the end of the chunk section",
                        info_positions,
                        &mut pos,
                    );
                    continue;
                }
                break;
            };
            let next = data_pos + dlen as u64;
            let h = match Header::parse(&hb) {
                Ok(h) => h,
                Err(e) => {
                    self.damaged_at(pos, end, &e.to_string(), info_positions, &mut pos);
                    continue;
                }
            };
            match h.op() {
                Ok(Op::Chunk) => {
                    let Ok(chunk) = ChunkHeader::decode(&h) else {
                        self.damaged_at(pos, end, "damaged chunk header", info_positions, &mut pos);
                        continue;
                    };
                    w.chunks.push(ChunkLoc {
                        pos,
                        stored: Some(dlen as u64),
                        size: Some(chunk.size as u64),
                        index_data: BTreeMap::new(),
                        info_counts: None,
                        span: None,
                    });
                }
                Ok(Op::IndexData) => {
                    if let (Some(c), Ok(ix)) = (w.chunks.last_mut(), IndexData::decode(&h)) {
                        // The entries the file holds, whatever the count field says.
                        let count = (ix.count.unwrap_or(u32::MAX) as u64)
                            .min(dlen as u64 / INDEX_ENTRY_LEN as u64);
                        c.index_data
                            .entry(ix.conn)
                            .or_insert(ChunkIndexData { count, data_pos });
                    }
                }
                Ok(Op::Connection) => {
                    if let Ok(data) = self.bytes_at(data_pos, dlen)
                        && let Ok(c) = Connection::decode(&h, &data)
                    {
                        w.connections.push(c);
                    }
                }
                Ok(Op::ChunkInfo) => {
                    // The index section, where the header said it would not be.
                    break;
                }
                Ok(_) | Err(_) => {
                    self.damaged_at(
                        pos,
                        end,
                        "unexpected or unknown record op",
                        info_positions,
                        &mut pos,
                    );
                    continue;
                }
            }
            pos = next;
        }
        w
    }

    /// Records a damaged top-level record at `*pos` and moves `*pos` to the next chunk: the
    /// next position a chunk info names, else the next valid chunk record found in the bytes.
    fn damaged_at(
        &mut self,
        at: u64,
        end: u64,
        why: &str,
        info_positions: &BTreeSet<u64>,
        pos: &mut u64,
    ) {
        let next = info_positions
            .range(at + 1..end)
            .next()
            .copied()
            .or_else(|| self.find_chunk(at + 1, end));
        let to = next.unwrap_or(end);
        self.contents.losses.push(Loss::new(format!(
            "bytes {at}..{to} of the chunk section are damaged ({why}) and were skipped"
        )));
        *pos = to;
    }

    /// The next position in `from..end` where a valid chunk record starts.
    fn find_chunk(&self, from: u64, end: u64) -> Option<u64> {
        let mut at = from;
        let mut buf = vec![0u8; RESYNC_WINDOW];
        while at < end {
            let n = ((end - at) as usize).min(RESYNC_WINDOW);
            buf.resize(n, 0);
            self.file.read_exact_at(&mut buf, at).ok()?;
            // `op=\x05` inside a chunk header; the record starts up to 64 bytes before it.
            let mut i = 0;
            while let Some(k) = find(&buf[i..], b"op=\x05") {
                let q = at + (i + k) as u64;
                for back in 8..=72u64 {
                    let Some(p) = q.checked_sub(back) else { break };
                    if p < from {
                        break;
                    }
                    if let Some((hb, data_pos, dlen)) = self.record_at(p, end)
                        && data_pos > q
                        && let Ok(h) = Header::parse(&hb)
                        && ChunkHeader::decode(&h).is_ok()
                        && data_pos + dlen as u64 <= end
                    {
                        return Some(p);
                    }
                }
                i += k + 1;
            }
            if n < RESYNC_WINDOW {
                break;
            }
            at += (RESYNC_WINDOW - 128) as u64;
        }
        None
    }

    /// Joins what the index section and the walk found, and says where they disagree.
    fn merge(
        &mut self,
        walk: Walk,
        index_conns: Vec<Connection>,
        infos: Vec<ChunkInfo>,
        chunk_count: Option<u32>,
    ) {
        let had_index = !infos.is_empty() || !index_conns.is_empty();
        let mut chunks: BTreeMap<u64, ChunkLoc> =
            walk.chunks.into_iter().map(|c| (c.pos, c)).collect();
        let unlisted = self.join_chunk_infos(&mut chunks, infos);
        if had_index && !unlisted.is_empty() {
            self.contents.notes.push(format!(
                "{} chunk(s) are not listed in the bag's index (first at byte {}); they were read",
                unlisted.len(),
                unlisted.iter().next().copied().unwrap_or(0)
            ));
        }
        if let Some(n) = chunk_count
            && had_index
            && n as usize != chunks.len()
        {
            self.contents.notes.push(format!(
                "the bag header announces {n} chunks; {} were found",
                chunks.len()
            ));
        }
        self.chunks = chunks.into_values().collect();
        let mut connections: BTreeMap<u32, Connection> = BTreeMap::new();
        for c in index_conns.into_iter().chain(walk.connections) {
            connections.entry(c.id).or_insert(c);
        }
        self.scan_chunks(&mut connections, had_index);
        self.index.connections = connections.into_values().collect();
        self.index.chunk_count = self.chunks.len();
        self.index.indexed = had_index;
    }

    /// Gives the walk's chunks the counts and times of their chunk infos (sorted by chunk
    /// position), reads the chunks only the index knows, and returns the positions of the
    /// chunks no info lists.
    fn join_chunk_infos(
        &mut self,
        chunks: &mut BTreeMap<u64, ChunkLoc>,
        mut infos: Vec<ChunkInfo>,
    ) -> BTreeSet<u64> {
        infos.sort_by_key(|i| i.chunk_pos);
        let mut unlisted: BTreeSet<u64> = chunks.keys().copied().collect();
        for info in infos {
            match chunks.get_mut(&info.chunk_pos) {
                Some(c) if c.info_counts.is_none() => {
                    unlisted.remove(&info.chunk_pos);
                    let own = c.promised();
                    let mut mine: Vec<(u32, u64)> =
                        info.counts.iter().map(|&(k, n)| (k, n as u64)).collect();
                    // rosbag lists a chunk's connections in any order.
                    mine.sort_unstable();
                    if own.is_some() && own.as_ref() != Some(&mine) {
                        self.contents.notes.push(format!(
                            "the chunk info of the chunk at byte {} lists {:?} messages per connection, the chunk's own index {:?}; the chunk is read whole and its own index is used",
                            info.chunk_pos,
                            mine,
                            own.unwrap_or_default()
                        ));
                    }
                    c.info_counts = Some(info.counts);
                    c.span = Some((info.start_time, info.end_time));
                }
                Some(_) => self.contents.notes.push(format!(
                    "two chunk infos name the chunk at byte {}; the chunk is read once",
                    info.chunk_pos
                )),
                None => self.unwalked_chunk(chunks, info),
            }
        }
        unlisted
    }

    /// A chunk the index lists and the walk did not reach (it stopped early): read if it is
    /// a chunk, else a loss of the messages its info counts.
    fn unwalked_chunk(&mut self, chunks: &mut BTreeMap<u64, ChunkLoc>, info: ChunkInfo) {
        let ok = self
            .record_at(info.chunk_pos, self.len)
            .and_then(|(hb, _, dlen)| {
                let h = Header::parse(&hb).ok()?;
                (h.op().ok()? == Op::Chunk).then_some(dlen)
            });
        match ok {
            Some(dlen) => {
                chunks.insert(
                    info.chunk_pos,
                    ChunkLoc {
                        pos: info.chunk_pos,
                        stored: Some(dlen as u64),
                        size: None,
                        index_data: BTreeMap::new(),
                        info_counts: Some(info.counts),
                        span: Some((info.start_time, info.end_time)),
                    },
                );
            }
            None => self.contents.losses.push(Loss {
                what: format!(
                    "the index lists a chunk at byte {} that holds no chunk record",
                    info.chunk_pos
                ),
                messages: Some(info.counts.iter().map(|&(_, n)| n as u64).sum()),
                span: Some((info.start_time.as_nanos(), info.end_time.as_nanos())),
                channel: None,
                ..Loss::default()
            }),
        }
    }

    /// Reads the chunks whose connections or counts nothing outside them gives: the
    /// connection records inside them (rosbag also writes each connection record inside
    /// the first chunk that uses it) and, for a chunk without any index, its message count.
    fn scan_chunks(&mut self, connections: &mut BTreeMap<u32, Connection>, had_index: bool) {
        let referenced: BTreeSet<u32> = self
            .chunks
            .iter()
            .flat_map(|c| {
                c.index_data
                    .keys()
                    .copied()
                    .chain(c.info_counts.iter().flatten().map(|(k, _)| *k))
                    .collect::<Vec<_>>()
            })
            .collect();
        let unknown = |m: &BTreeMap<u32, Connection>| referenced.iter().any(|k| !m.contains_key(k));
        if had_index && !unknown(connections) && self.chunks.iter().all(|c| c.promised().is_some())
        {
            return;
        }
        for i in 0..self.chunks.len() {
            let needs_count = self.chunks[i].promised().is_none();
            if !needs_count && !unknown(connections) && had_index {
                continue;
            }
            let pos = self.chunks[i].pos;
            let mut found = Vec::new();
            let mut counts: BTreeMap<u32, u64> = BTreeMap::new();
            let r = self.with_chunk_body(pos, |body| {
                walk_body(body, &Vec::new, &mut |rec| match rec {
                    BodyRecord::Connection(hb, data) => {
                        if let Ok(c) = Header::parse(hb).and_then(|h| Connection::decode(&h, data))
                        {
                            found.push(c);
                        }
                    }
                    BodyRecord::Message(c, ..) => *counts.entry(c).or_default() += 1,
                });
                Ok(())
            });
            if r.is_err() {
                continue;
            }
            for c in found {
                connections.entry(c.id).or_insert(c);
            }
            if needs_count {
                // Counted by reading: the scan's count stands in for the missing index.
                self.chunks[i].info_counts = Some(
                    counts
                        .into_iter()
                        .map(|(k, n)| (k, n.min(u32::MAX as u64) as u32))
                        .collect(),
                );
            }
        }
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
        size.map(|s| s.min(bound) / crate::series::MIN_IMU_PAYLOAD)
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

    /// Reads and decompresses the chunk whose record starts at `pos`, and hands its body to
    /// `f`. The raw and decompressed bytes live in per-thread buffers reused from chunk to
    /// chunk: a 4 h bag is ~1300 chunks, and fresh zeroed buffers cost more than the parsing.
    fn with_chunk_body<R>(
        &self,
        pos: u64,
        f: impl FnOnce(&[u8]) -> Result<R, String>,
    ) -> Result<R, String> {
        let (h, data_pos, dlen) = self
            .record_at(pos, self.len)
            .ok_or("chunk record runs past the end of the file")?;
        BUFFERS.with(|cell| {
            let mut bufs = cell.borrow_mut();
            let (raw, body) = &mut *bufs;
            let compression = self.read_chunk_into(&h, data_pos, dlen, raw, body)?;
            if compression == Compression::None {
                f(raw)
            } else {
                f(body)
            }
        })
    }

    /// Reads the chunk data into `raw` and, when compressed, decompresses it into `body`.
    fn read_chunk_into(
        &self,
        h_bytes: &[u8],
        data_pos: u64,
        dlen: u32,
        raw: &mut Vec<u8>,
        body: &mut Vec<u8>,
    ) -> Result<Compression, String> {
        let h = Header::parse(h_bytes).map_err(|e| e.to_string())?;
        if h.op().map_err(|e| e.to_string())? != Op::Chunk {
            return Err("not a chunk record".into());
        }
        let ChunkHeader { compression, size } =
            ChunkHeader::decode(&h).map_err(|e| e.to_string())?;
        let size = size as usize;
        raw.resize(dlen as usize, 0);
        self.file
            .read_exact_at(raw, data_pos)
            .map_err(|e| e.to_string())?;
        body.clear();
        let got = match compression {
            Compression::None => raw.len(),
            Compression::Bz2 => bzip2::read::BzDecoder::new(&raw[..])
                .take(size as u64 + 1)
                .read_to_end(body)
                .map_err(|e| format!("bz2: {e}"))?,
            Compression::Lz4 => lz4_flex::frame::FrameDecoder::new(&raw[..])
                .take(size as u64 + 1)
                .read_to_end(body)
                .map_err(|e| format!("lz4: {e}"))?,
        };
        if got != size {
            return Err(format!("chunk body is {got} bytes, its header says {size}"));
        }
        Ok(compression)
    }

    /// Calls `f(connection, record time, data)` for each message record of chunk `c` whose
    /// connection `want` accepts, in body order, and reports what the chunk's index lists
    /// that could not be delivered.
    fn for_each_in_chunk(
        &self,
        c: &ChunkLoc,
        want: &dyn Fn(u32) -> bool,
        f: &mut MessageSink<'_>,
    ) -> PartRead {
        let mut out = PartRead::default();
        let mut delivered_at: Vec<u32> = Vec::new();
        let mut per_conn: Vec<(u32, u64)> = Vec::new();
        let mut damage: Vec<String> = Vec::new();
        // The offsets the chunk's index lists, read only if a record turns out damaged.
        let listed_offsets = || {
            let mut v: Vec<u32> = self.index_entries(c).iter().map(|e| e.2).collect();
            v.sort_unstable();
            v
        };
        let r = self.with_chunk_body(c.pos, |body| {
            damage = walk_body(body, &listed_offsets, &mut |rec| {
                if let BodyRecord::Message(conn, t, off, data) = rec
                    && want(conn)
                {
                    f(conn, t, data);
                    out.delivered += 1;
                    delivered_at.push(off);
                    match per_conn.iter_mut().find(|(k, _)| *k == conn) {
                        Some(e) => e.1 += 1,
                        None => per_conn.push((conn, 1)),
                    }
                }
            });
            Ok(())
        });
        if let Err(e) = r {
            out.error = Some(e);
            return out;
        }
        let short = c.index_data.iter().any(|(conn, d)| {
            want(*conn) && per_conn.iter().find(|(k, _)| k == conn).map_or(0, |e| e.1) < d.count
        });
        if short {
            // Listed messages of wanted connections that were not delivered.
            delivered_at.sort_unstable();
            let mut lost: BTreeMap<u32, (u64, u64, u64)> = BTreeMap::new();
            for (conn, t, off) in self.index_entries(c) {
                if want(conn) && delivered_at.binary_search(&off).is_err() {
                    let e = lost.entry(conn).or_insert((0, t, t));
                    e.0 += 1;
                    e.1 = e.1.min(t);
                    e.2 = e.2.max(t);
                }
            }
            let why = if damage.is_empty() {
                "its record is not a readable message".to_string()
            } else {
                damage.join("; ")
            };
            for (conn, (n, a, b)) in lost {
                out.lost.push(Loss {
                    what: format!(
                        "chunk at byte {}: {} that the chunk's index lists could not be read ({why})",
                        c.pos,
                        if n == 1 { "a message" } else { "messages" }
                    ),
                    messages: Some(n),
                    span: Some((a, b)),
                    channel: Some(conn),
                    ..Loss::default()
                });
            }
        }
        if out.lost.is_empty() && !damage.is_empty() {
            out.lost.push(Loss::new(format!(
                "chunk at byte {}: {}",
                c.pos,
                damage.join("; ")
            )));
        }
        out
    }

    /// The `(connection, record time ns, body offset)` entries of the chunk's index data.
    fn index_entries(&self, c: &ChunkLoc) -> Vec<(u32, u64, u32)> {
        let mut out = Vec::new();
        for (conn, d) in &c.index_data {
            let Ok(data) = self.bytes_at(d.data_pos, (d.count * 12) as u32) else {
                continue;
            };
            out.extend(data.chunks_exact(12).map(|e| {
                let t = RosTime::from_bytes(&e[..8]).unwrap_or_default();
                (
                    *conn,
                    t.as_nanos(),
                    u32::from_le_bytes([e[8], e[9], e[10], e[11]]),
                )
            }));
        }
        out
    }

    /// Record-time span of a chunk: its chunk info's, else its index data's.
    fn time_span(&self, c: &ChunkLoc) -> Option<(u64, u64)> {
        if let Some((a, b)) = c.span {
            return Some((a.as_nanos(), b.as_nanos()));
        }
        let e = self.index_entries(c);
        let first = e.first()?.1;
        Some(
            e.iter()
                .fold((first, first), |(a, b), x| (a.min(x.1), b.max(x.1))),
        )
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

/// A whole record inside a chunk body, as [`walk_body`] hands it out.
enum BodyRecord<'a> {
    /// A message: connection, record time (ns), body offset, data.
    Message(u32, u64, u32, &'a [u8]),
    /// A connection record: header bytes and data.
    Connection(&'a [u8], &'a [u8]),
}

/// Walks the records of a chunk body, calling `f` for each whole message or connection
/// record. A record whose framing or header is damaged is skipped: the walk resumes at the
/// next offset in `listed` (the chunk's index, sorted) past it, else at the next valid
/// record found in the bytes. Returns a description of each damaged stretch. The per-message
/// work is [`record::op_conn_time`], which does not allocate.
fn walk_body<'a>(
    body: &'a [u8],
    listed: &dyn Fn() -> Vec<u32>,
    f: &mut dyn FnMut(BodyRecord<'a>),
) -> Vec<String> {
    let mut damage = Vec::new();
    let mut offsets: Option<Vec<u32>> = None;
    let mut pos = 0usize;
    while pos < body.len() {
        let rec = record::raw_record(body, pos);
        let fields = rec.as_ref().map(|r| record::op_conn_time(r.header));
        match (rec, fields) {
            (Some(r), Some(Ok((Some(op), conn, time)))) if op == Op::MessageData as u8 => {
                match (conn, time) {
                    (Some(c), Some(t)) => {
                        f(BodyRecord::Message(c, t.as_nanos(), pos as u32, r.data))
                    }
                    _ => damage.push(format!(
                        "the message record at body offset {pos} lacks its 'conn' or 'time' field"
                    )),
                }
                pos = r.end;
                continue;
            }
            (Some(r), Some(Ok((Some(op), _, _)))) if op == Op::Connection as u8 => {
                f(BodyRecord::Connection(r.header, r.data));
                pos = r.end;
                continue;
            }
            (Some(r), Some(Ok((op, _, _))))
                if r.end == body.len() || parse_body_record(body, r.end).is_some() =>
            {
                // Framing intact, header damaged (op flipped or missing): skip this record.
                damage.push(format!(
                    "the record at body offset {pos} has {}",
                    match op {
                        Some(b) => format!("an unknown op 0x{b:02x}"),
                        None => "no op field".to_string(),
                    }
                ));
                pos = r.end;
                continue;
            }
            _ => {}
        }
        let next = offsets
            .get_or_insert_with(listed)
            .iter()
            .copied()
            .find(|&o| o as usize > pos && parse_body_record(body, o as usize).is_some())
            .map(|o| o as usize)
            .or_else(|| resync(body, pos + 1));
        let to = next.unwrap_or(body.len());
        damage.push(format!(
            "damaged record framing at body offset {pos}: bytes {pos}..{to} skipped"
        ));
        pos = to;
    }
    damage
}

/// The end of the record at `pos` if its framing holds and its header names a message
/// (with `conn` and `time`) or a connection.
fn parse_body_record(body: &[u8], pos: usize) -> Option<usize> {
    let r = record::raw_record(body, pos)?;
    match record::op_conn_time(r.header).ok()? {
        (Some(op), Some(_), Some(_)) if op == Op::MessageData as u8 => Some(r.end),
        (Some(op), Some(_), _) if op == Op::Connection as u8 => Some(r.end),
        _ => None,
    }
}

/// The next offset at or after `from` where a whole message or connection record starts
/// and is followed by another whole record (or the end of the body).
fn resync(body: &[u8], from: usize) -> Option<usize> {
    let mut i = from;
    while let Some(k) = find(&body[i..], b"op=") {
        let q = i + k;
        for back in 4..=96usize {
            let Some(p) = q.checked_sub(back) else { break };
            if p < from {
                break;
            }
            if let Some(end) = parse_body_record(body, p)
                && (end == body.len() || parse_body_record(body, end).is_some())
            {
                return Some(p);
            }
        }
        i = q + 1;
    }
    None
}

/// Position of `needle` in `hay`.
fn find(hay: &[u8], needle: &[u8]) -> Option<usize> {
    hay.windows(needle.len()).position(|w| w == needle)
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
                error: Some("no such chunk".into()),
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
