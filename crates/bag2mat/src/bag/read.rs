//! Streaming reader for bag format 2.0.
//!
//! [`BagReader::open`] reads the bag header and the index section (connections and chunk
//! infos). When the index is missing or unreadable — a writer that never finished leaves
//! `index_pos = 0`, a truncated copy loses the index at the end — the chunk section is
//! scanned record by record instead, every complete chunk is used, and the notes say how
//! many bytes at the end were lost. Chunks are read with positioned reads and decompressed
//! in parallel batches, so memory stays at a few chunks beyond what the caller keeps.

use std::collections::BTreeMap;
use std::fs::File;
use std::io::Read;
use std::os::unix::fs::FileExt;
use std::path::{Path, PathBuf};

use rayon::prelude::*;

use super::record::{self, ChunkInfo, Connection, Header, MAGIC, Op};
use super::{Compression, RosTime};
use crate::error::{Error, TopicSummary};
use crate::imu_msg::{self, ImuSample};

thread_local! {
    /// Per-thread (raw, decompressed) chunk buffers, reused across chunks.
    static BUFFERS: std::cell::RefCell<(Vec<u8>, Vec<u8>)> = const { std::cell::RefCell::new((Vec::new(), Vec::new())) };
}

/// Chunks decoded in parallel per batch (about 48 MiB of uncompressed body).
const BATCH_CHUNKS: usize = 64;

/// Where a chunk is, and (when the bag is indexed) what it holds.
#[derive(Debug, Clone)]
struct ChunkLoc {
    pos: u64,
    /// `(connection, count)` from the chunk info; empty when scanned.
    counts: Vec<(u32, u32)>,
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

/// Which connections to read, decided by [`BagReader::select_imu_topic`].
#[derive(Debug, Clone)]
pub struct TopicSelection {
    /// The topic as it is in the bag.
    pub topic: String,
    /// Its connection ids.
    pub conns: Vec<u32>,
    /// Messages expected (from the index).
    pub expected: u64,
    /// Set when the other slash form was used.
    pub note: Option<String>,
}

/// What a read returned besides the samples.
#[derive(Debug, Clone, Default)]
pub struct StreamReport {
    /// When the messages were not in record-time order in the file: the stable order by
    /// record time (indices into the delivery order). `None` means already in order.
    pub order: Option<Vec<usize>>,
    /// Things to tell the user (lost chunks, unindexed bag, topic fallback).
    pub notes: Vec<String>,
    /// Messages delivered.
    pub delivered: u64,
}

/// An open bag.
pub struct BagReader {
    path: PathBuf,
    file: File,
    len: u64,
    chunks: Vec<ChunkLoc>,
    index: BagIndex,
    notes: Vec<String>,
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
        Ok(reader)
    }

    /// Notes gathered while opening (unindexed or truncated bag).
    pub fn notes(&self) -> &[String] {
        &self.notes
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
                self.notes.push(format!(
                    "the last {} bytes of the file are an incomplete record (truncated bag); they were skipped",
                    self.len - pos
                ));
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
                            });
                        }
                        Err(e) => self.notes.push(format!(
                            "chunk at byte {pos} is unreadable and was skipped: {e}"
                        )),
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

    /// Resolves `topic` to its `sensor_msgs/Imu` connections: the exact name first, else the
    /// other slash form (`imu` ↔ `/imu`, with a note); errors list every topic of the bag.
    pub fn select_imu_topic(&self, topic: &str) -> Result<TopicSelection, Error> {
        let matching = |t: &str| -> Vec<&Connection> {
            self.index
                .connections
                .iter()
                .filter(|c| c.topic == t)
                .collect()
        };
        let mut chosen = topic.to_string();
        let mut conns = matching(topic);
        let mut note = None;
        if conns.is_empty() {
            let other = match topic.strip_prefix('/') {
                Some(rest) => rest.to_string(),
                None => format!("/{topic}"),
            };
            let alt = matching(&other);
            if !alt.is_empty() {
                note = Some(format!(
                    "topic '{topic}' is not in the bag; using '{other}'"
                ));
                chosen = other;
                conns = alt;
            }
        }
        if conns.is_empty() {
            return Err(Error::TopicNotFound {
                topic: topic.to_string(),
                available: self.topics(),
            });
        }
        if let Some(bad) = conns
            .iter()
            .find(|c| c.msg_type != imu_msg::TYPE || c.md5sum != imu_msg::MD5)
        {
            return Err(Error::WrongType {
                topic: chosen,
                msg_type: bad.msg_type.clone(),
                md5sum: bad.md5sum.clone(),
            });
        }
        let ids: Vec<u32> = conns.iter().map(|c| c.id).collect();
        let expected = ids
            .iter()
            .map(|id| self.index.counts.get(id).copied().unwrap_or(0))
            .sum();
        Ok(TopicSelection {
            topic: chosen,
            conns: ids,
            expected,
            note,
        })
    }

    /// Streams every Imu sample of the selection to `sink` as `(record time, sample)`, in file
    /// order, reading and decoding chunks in parallel batches. A chunk that cannot be read is
    /// skipped with a note counting its lost messages. The report carries the record-time
    /// order when the file order differs from it.
    pub fn stream_imu(
        &self,
        sel: &TopicSelection,
        quiet: bool,
        sink: &mut dyn FnMut(RosTime, &ImuSample),
    ) -> Result<StreamReport, Error> {
        let mut report = StreamReport::default();
        report.notes.extend(self.notes.iter().cloned());
        report.notes.extend(sel.note.iter().cloned());
        let wanted = |conn: u32| sel.conns.contains(&conn);
        let chunks: Vec<&ChunkLoc> = self
            .chunks
            .iter()
            .filter(|c| {
                c.counts.is_empty() || c.counts.iter().any(|(conn, n)| wanted(*conn) && *n > 0)
            })
            .collect();
        let pb = crate::progress::bar(sel.expected.max(1), quiet, "msgs");
        pb.set_message("reading");
        let mut times: Vec<u64> = Vec::with_capacity(sel.expected as usize);
        let mut sorted = true;
        let mut last = 0u64;
        let mut lost = 0u64;
        for batch in chunks.chunks(BATCH_CHUNKS) {
            let decoded: Vec<Result<Vec<(RosTime, ImuSample)>, String>> = batch
                .par_iter()
                .map(|c| self.decode_chunk(c.pos, &sel.conns))
                .collect();
            for (loc, res) in batch.iter().zip(decoded) {
                match res {
                    Ok(samples) => {
                        for (t, s) in &samples {
                            let ns = t.as_nanos();
                            sorted &= ns >= last;
                            last = ns;
                            times.push(ns);
                            sink(*t, s);
                        }
                        pb.inc(samples.len() as u64);
                    }
                    Err(e) => {
                        let n: u64 = loc
                            .counts
                            .iter()
                            .filter(|(c, _)| wanted(*c))
                            .map(|(_, n)| *n as u64)
                            .sum();
                        lost += n;
                        report.notes.push(format!(
                            "chunk at byte {} is unreadable ({e}); {n} messages of the topic lost",
                            loc.pos
                        ));
                    }
                }
            }
        }
        pb.finish_and_clear();
        if lost > 0 {
            report.notes.push(format!(
                "{lost} of {} messages were lost to unreadable chunks",
                sel.expected
            ));
        }
        report.delivered = times.len() as u64;
        if !sorted {
            let mut order: Vec<usize> = (0..times.len()).collect();
            order.sort_by_key(|&i| times[i]);
            report.notes.push(
                "messages were not stored in record-time order; sorted as rosbag::View does"
                    .to_string(),
            );
            report.order = Some(order);
        }
        Ok(report)
    }

    fn decode_chunk(&self, pos: u64, conns: &[u32]) -> Result<Vec<(RosTime, ImuSample)>, String> {
        let mut out = Vec::new();
        self.for_each_in_chunk(pos, conns, |t, s| out.push((t, *s)))?;
        Ok(out)
    }

    /// Calls `f(record time, sample)` for each selected Imu message of the chunk at `pos`, in
    /// body order; returns how many there were.
    fn for_each_in_chunk(
        &self,
        pos: u64,
        conns: &[u32],
        mut f: impl FnMut(RosTime, &ImuSample),
    ) -> Result<usize, String> {
        self.with_chunk_body(pos, |body| {
            let mut n = 0;
            let mut bpos = 0;
            while bpos < body.len() {
                let rec = record::raw_record(body, bpos)
                    .ok_or_else(|| format!("incomplete record at body offset {bpos}"))?;
                let (op, conn, time) = record::op_conn_time(rec.header)?;
                if op == Some(Op::MessageData as u8) {
                    let conn = conn.ok_or("message record without 'conn'")?;
                    if conns.contains(&conn) {
                        let t = time.ok_or("message record without 'time'")?;
                        f(t, &ImuSample::decode(rec.data).map_err(|e| e.to_string())?);
                        n += 1;
                    }
                }
                bpos = rec.end;
            }
            Ok(n)
        })
    }

    /// For an indexed bag: the chunks holding the selection, in file order, with the number
    /// of selected messages in each (from the chunk infos). `None` for a scanned bag.
    pub fn chunk_plan(&self, sel: &TopicSelection) -> Option<Vec<(u64, usize)>> {
        if !self.index.indexed {
            return None;
        }
        Some(
            self.chunks
                .iter()
                .map(|c| {
                    (
                        c.pos,
                        c.counts
                            .iter()
                            .filter(|(conn, _)| sel.conns.contains(conn))
                            .map(|(_, n)| *n as usize)
                            .sum(),
                    )
                })
                .filter(|(_, n)| *n > 0)
                .collect(),
        )
    }

    /// Splits a column of the whole selection into one slice per planned chunk.
    pub fn split_rows<'a, T>(column: &'a mut [T], plan: &[(u64, usize)]) -> Vec<&'a mut [T]> {
        let mut rest = column;
        plan.iter()
            .map(|&(_, k)| {
                let (head, tail) = std::mem::take(&mut rest).split_at_mut(k);
                rest = tail;
                head
            })
            .collect()
    }

    /// Decodes the planned chunks in parallel, each into its own `part` (the caller splits
    /// its output so that part `i` holds exactly the rows of chunk `i` of `plan`):
    /// `put(part, row within the chunk, record time, sample)`. Fails — and the caller falls
    /// back to [`BagReader::stream_imu`] — when a chunk is unreadable or holds a different
    /// number of messages than its chunk info says.
    pub fn decode_planned<P: Send>(
        &self,
        sel: &TopicSelection,
        plan: &[(u64, usize)],
        parts: &mut [P],
        quiet: bool,
        put: impl Fn(&mut P, usize, RosTime, &ImuSample) + Sync,
    ) -> Result<(), String> {
        if plan.len() != parts.len() {
            return Err("plan and parts differ in length".into());
        }
        let total: u64 = plan.iter().map(|(_, k)| *k as u64).sum();
        let pb = crate::progress::bar(total.max(1), quiet, "msgs");
        pb.set_message("reading");
        let r =
            parts
                .par_iter_mut()
                .zip(plan.par_iter())
                .try_for_each(|(part, &(pos, expected))| {
                    let mut k = 0;
                    let got = self.for_each_in_chunk(pos, &sel.conns, |t, s| {
                        if k < expected {
                            put(part, k, t, s);
                        }
                        k += 1;
                    })?;
                    if got != expected {
                        return Err(format!(
                            "chunk at byte {pos} holds {got} messages, its index says {expected}"
                        ));
                    }
                    pb.inc(expected as u64);
                    Ok(())
                });
        pb.finish_and_clear();
        r
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
