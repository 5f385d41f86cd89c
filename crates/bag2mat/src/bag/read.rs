//! Streaming reader for bag format 2.0.
//!
//! [`BagReader::open`] reads the bag header and the index section (connections and chunk
//! infos). When the index is missing or unreadable — a writer that never finished leaves
//! `index_pos = 0`, a truncated copy loses the index at the end — the chunk section is
//! scanned record by record instead, every complete chunk is used, and the notes say how
//! many bytes at the end were lost. Each chunk is one [`Part`] of the [`Source`] interface,
//! read with positioned reads and decompressed by whichever thread reads it.

use std::collections::BTreeMap;
use std::fs::File;
use std::io::Read;
use std::os::unix::fs::FileExt;
use std::path::{Path, PathBuf};

use super::record::{self, ChunkInfo, Connection, Header, MAGIC, Op};
use super::{Compression, RosTime};
use crate::error::{Error, TopicSummary};
use crate::source::{self, Encoding, InputKind, Loss, MessageSink, Part, PartRead, Source};

thread_local! {
    /// Per-thread (raw, decompressed) chunk buffers, reused across chunks.
    static BUFFERS: std::cell::RefCell<(Vec<u8>, Vec<u8>)> = const { std::cell::RefCell::new((Vec::new(), Vec::new())) };
}

/// Where a chunk is, and (when the bag is indexed) what it holds.
#[derive(Debug, Clone)]
struct ChunkLoc {
    pos: u64,
    /// `(connection, count)` from the chunk info; empty when scanned.
    counts: Vec<(u32, u32)>,
    /// Time span from the chunk info.
    span: Option<(RosTime, RosTime)>,
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
    notes: Vec<String>,
    losses: Vec<Loss>,
    channels: Vec<source::Channel>,
    parts: Vec<Part>,
}

impl BagReader {
    /// Opens a bag and reads its index (or scans it when the index is missing).
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
        let rec = record::raw_record(&head, MAGIC.len())
            .ok_or_else(|| corrupt(13, "bag header record is incomplete".into()))?;
        let h = Header::parse(rec.header).map_err(|w| corrupt(13, w))?;
        if h.op().map_err(|w| corrupt(13, w))? != Op::BagHeader {
            return Err(corrupt(13, "first record is not the bag header".into()));
        }
        let index_pos = h.u64("index_pos").map_err(|w| corrupt(13, w))?;
        let chunk_count = h.u32("chunk_count").map_err(|w| corrupt(13, w))?;
        let first = rec.end as u64;
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
            notes: Vec::new(),
            losses: Vec::new(),
            channels: Vec::new(),
            parts: Vec::new(),
        };
        let indexed = index_pos >= first
            && index_pos < len
            && reader.read_index(index_pos, chunk_count).is_ok();
        if !indexed {
            reader.notes.push(if index_pos == 0 {
                "the bag has no index (index_pos = 0: the writer did not finish); scanning its chunks (`rosbag reindex` repairs it)".to_string()
            } else {
                format!("the bag's index at byte {index_pos} is missing or unreadable (file is {len} bytes: truncated?); scanning its chunks")
            });
            reader.scan(first)?;
        }
        reader.build_interface();
        Ok(reader)
    }

    /// The channels and parts of the [`Source`] interface.
    fn build_interface(&mut self) {
        self.channels = self
            .index
            .connections
            .iter()
            .map(|c| source::Channel {
                id: c.id,
                topic: c.topic.clone(),
                msg_type: c.msg_type.clone(),
                encoding: Encoding::Ros1,
                md5sum: Some(c.md5sum.clone()),
                count: Some(self.index.counts.get(&c.id).copied().unwrap_or(0)),
            })
            .collect();
        let ends: Vec<u64> = self
            .chunks
            .iter()
            .skip(1)
            .map(|c| c.pos)
            .chain([self.len])
            .collect();
        self.parts = self
            .chunks
            .iter()
            .zip(ends)
            .map(|(c, end)| Part {
                bytes: end
                    .saturating_sub(c.pos)
                    .saturating_mul(source::MAX_EXPANSION),
                label: format!("chunk at byte {}", c.pos),
                span: c.span.map(|(a, b)| (a.as_nanos(), b.as_nanos())),
                counts: self
                    .index
                    .indexed
                    .then(|| c.counts.iter().map(|&(conn, n)| (conn, n as u64)).collect()),
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

    fn corrupt(&self, offset: u64, what: impl Into<String>) -> Error {
        Error::Corrupt {
            path: self.path.clone(),
            offset,
            what: what.into(),
        }
    }

    fn read_index(&mut self, index_pos: u64, chunk_count: u32) -> Result<(), String> {
        let mut buf = vec![0u8; (self.len - index_pos) as usize];
        self.file
            .read_exact_at(&mut buf, index_pos)
            .map_err(|e| e.to_string())?;
        let mut pos = 0;
        let mut connections = Vec::new();
        let mut infos = Vec::new();
        while pos < buf.len() {
            let rec =
                record::raw_record(&buf, pos).ok_or("incomplete record in the index section")?;
            let h = Header::parse(rec.header)?;
            match h.op()? {
                Op::Connection => connections.push(Connection::decode(&h, rec.data)?),
                Op::ChunkInfo => infos.push(ChunkInfo::decode(&h, rec.data)?),
                other => return Err(format!("unexpected {other:?} record in the index section")),
            }
            pos = rec.end;
        }
        if infos.len() != chunk_count as usize {
            return Err(format!(
                "bag header announces {chunk_count} chunks, index lists {}",
                infos.len()
            ));
        }
        infos.sort_by_key(|i| i.chunk_pos);
        for info in &infos {
            for (conn, n) in &info.counts {
                *self.index.counts.entry(*conn).or_default() += *n as u64;
            }
        }
        connections.sort_by_key(|c: &Connection| c.id);
        connections.dedup_by_key(|c| c.id);
        self.index.connections = connections;
        self.index.chunk_count = infos.len();
        self.chunks = infos
            .into_iter()
            .map(|i| ChunkLoc {
                pos: i.chunk_pos,
                counts: i.counts,
                span: Some((i.start_time, i.end_time)),
            })
            .collect();
        self.index.indexed = true;
        Ok(())
    }

    /// Walks the chunk section record by record; stops at the first incomplete record.
    fn scan(&mut self, first: u64) -> Result<(), Error> {
        let mut pos = first;
        let mut connections: BTreeMap<u32, Connection> = BTreeMap::new();
        while pos < self.len {
            let Some((h_bytes, data_pos, data_len)) = self.record_at(pos) else {
                self.losses.push(Loss {
                    what: format!(
                        "the last {} bytes of the file are an incomplete record (truncated bag); they were skipped",
                        self.len - pos
                    ),
                    messages: None,
                    span: None,
                    channel: None,
                });
                break;
            };
            let h = Header::parse(&h_bytes).map_err(|w| self.corrupt(pos, w))?;
            match h.op().map_err(|w| self.corrupt(pos, w))? {
                Op::Chunk => {
                    let (mut raw, mut decompressed) = (Vec::new(), Vec::new());
                    match self.read_chunk_into(
                        &h_bytes,
                        data_pos,
                        data_len,
                        &mut raw,
                        &mut decompressed,
                    ) {
                        Ok(compression) => {
                            let body = if compression == Compression::None {
                                &raw
                            } else {
                                &decompressed
                            };
                            let mut bpos = 0;
                            while let Some(rec) = record::raw_record(body, bpos) {
                                if let Ok(bh) = Header::parse(rec.header) {
                                    match bh.op() {
                                        Ok(Op::Connection) => {
                                            if let Ok(c) = Connection::decode(&bh, rec.data) {
                                                connections.entry(c.id).or_insert(c);
                                            }
                                        }
                                        Ok(Op::MessageData) => {
                                            if let Ok(c) = bh.u32("conn") {
                                                *self.index.counts.entry(c).or_default() += 1;
                                            }
                                        }
                                        _ => {}
                                    }
                                }
                                bpos = rec.end;
                            }
                            self.chunks.push(ChunkLoc {
                                pos,
                                counts: Vec::new(),
                                span: None,
                            });
                        }
                        Err(e) => self.losses.push(Loss {
                            what: format!("chunk at byte {pos} is unreadable and was skipped: {e}"),
                            messages: None,
                            span: None,
                            channel: None,
                        }),
                    }
                }
                Op::Connection => {
                    if let Ok(c) = Connection::decode(&h, &self.bytes_at(data_pos, data_len)?) {
                        connections.entry(c.id).or_insert(c);
                    }
                }
                _ => {}
            }
            pos = data_pos + data_len as u64;
        }
        self.index.connections = connections.into_values().collect();
        self.index.chunk_count = self.chunks.len();
        Ok(())
    }

    fn bytes_at(&self, pos: u64, len: u32) -> Result<Vec<u8>, Error> {
        let mut buf = vec![0u8; len as usize];
        self.file
            .read_exact_at(&mut buf, pos)
            .map_err(|e| Error::io(&self.path, e))?;
        Ok(buf)
    }

    /// The header bytes, data position and data length of the record at `pos`, if whole.
    fn record_at(&self, pos: u64) -> Option<(Vec<u8>, u64, u32)> {
        let mut b4 = [0u8; 4];
        self.file.read_exact_at(&mut b4, pos).ok()?;
        let hlen = u32::from_le_bytes(b4) as u64;
        if pos + 4 + hlen + 4 > self.len {
            return None;
        }
        let mut header = vec![0u8; hlen as usize];
        self.file.read_exact_at(&mut header, pos + 4).ok()?;
        self.file.read_exact_at(&mut b4, pos + 4 + hlen).ok()?;
        let dlen = u32::from_le_bytes(b4);
        let data_pos = pos + 8 + hlen;
        if data_pos + dlen as u64 > self.len {
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
            .record_at(pos)
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
        let h = Header::parse(h_bytes)?;
        if h.op()? != Op::Chunk {
            return Err("index points at a record that is not a chunk".into());
        }
        let name = h.str("compression")?;
        let compression = Compression::from_name(name)
            .ok_or_else(|| format!("unknown chunk compression '{name}'"))?;
        let size = h.u32("size")? as usize;
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

    /// Calls `f(connection, record time, data)` for each message record of the chunk at
    /// `pos` whose connection `want` accepts, in body order. Returns how many it delivered
    /// and, when the body could not be read to its end, why.
    fn for_each_in_chunk(
        &self,
        pos: u64,
        want: &dyn Fn(u32) -> bool,
        f: &mut MessageSink<'_>,
    ) -> PartRead {
        let mut out = PartRead::default();
        let r = self.with_chunk_body(pos, |body| {
            let mut bpos = 0;
            while bpos < body.len() {
                let rec = record::raw_record(body, bpos)
                    .ok_or_else(|| format!("incomplete record at body offset {bpos}"))?;
                let (op, conn, time) = record::op_conn_time(rec.header)?;
                if op == Some(Op::MessageData as u8) {
                    let conn = conn.ok_or("message record without 'conn'")?;
                    if want(conn) {
                        let t = time.ok_or("message record without 'time'")?;
                        f(conn, t.as_nanos(), rec.data);
                        out.delivered += 1;
                    }
                }
                bpos = rec.end;
            }
            Ok(())
        });
        out.error = r.err();
        out
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
    fn channels(&self) -> &[source::Channel] {
        &self.channels
    }
    fn parts(&self) -> &[Part] {
        &self.parts
    }
    fn notes(&self) -> &[String] {
        &self.notes
    }
    fn losses(&self) -> &[Loss] {
        &self.losses
    }
    fn read_part(
        &self,
        part: usize,
        want: &(dyn Fn(u32) -> bool + Sync),
        sink: &mut MessageSink<'_>,
    ) -> PartRead {
        match self.chunks.get(part) {
            Some(c) => self.for_each_in_chunk(c.pos, want, sink),
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
