//! Reading MCAP files: chunked or not, chunks `none`/`lz4`/`zstd`, with or without the
//! summary section.
//!
//! [`McapReader::open`] takes schemas, channels and per-channel message counts from the
//! summary when it is intact (its CRC checked when one is stored), and always walks the
//! data section's top-level records: chunks become the parts read in parallel, runs of
//! unchunked messages become parts of their own, and each chunk's Message Index records give
//! the messages it promises per channel. A file cut short (no footer, no summary: a recorder
//! that was killed) is read up to its last complete record; the channels are then collected
//! from inside the chunks, and the notes and losses say what the incomplete tail held.

use std::collections::BTreeMap;
use std::fs::File;
use std::io::Read;
use std::os::unix::fs::FileExt;
use std::path::{Path, PathBuf};

use super::record::{
    self, ChunkHeader, ChunkIndex, Cursor, FOOTER_CONTENT_LEN, Footer, Header, MAGIC,
    MESSAGE_FIXED_LEN, MessageIndex, Op, RECORD_PREFIX, Schema, Statistics,
};
use crate::error::Error;
use crate::source::{self, Encoding, InputKind, Loss, MessageSink, Part, PartRead, Source};

/// Bytes read at once while walking the top-level records.
const SCAN_WINDOW: usize = 64 * 1024;
/// Unchunked messages are grouped into parts of about this many bytes.
const LOOSE_PART_BYTES: u64 = 4 << 20;
/// Largest schema, channel or header record read during the walk (a damaged length must not
/// make it allocate the file).
const MAX_META_RECORD: u64 = 64 << 20;

thread_local! {
    /// Per-thread (stored, decompressed) chunk buffers, reused from chunk to chunk.
    static BUFFERS: std::cell::RefCell<(Vec<u8>, Vec<u8>)> = const { std::cell::RefCell::new((Vec::new(), Vec::new())) };
}

/// Where a part's bytes are.
#[derive(Debug, Clone)]
enum Loc {
    /// A chunk's stored records.
    Chunk {
        records_pos: u64,
        compressed_size: u64,
        uncompressed_size: u64,
        crc: u32,
        compression: String,
    },
    /// A run of top-level records in the data section.
    Loose { start: u64, end: u64 },
}

/// An open MCAP file.
pub struct McapReader {
    path: PathBuf,
    file: File,
    len: u64,
    /// The Header record (profile, library).
    pub header: Header,
    /// Schemas by id.
    pub schemas: BTreeMap<u16, Schema>,
    /// Channels by id, as recorded.
    pub mcap_channels: BTreeMap<u16, record::Channel>,
    /// The Statistics record of an intact summary.
    pub statistics: Option<Statistics>,
    /// Whether an intact summary section was used.
    pub summary_used: bool,
    /// Where each part's bytes are (parallel to the contents' parts).
    locs: Vec<Loc>,
    contents: source::Contents,
}

/// Positioned reads through a window, for walking many small records cheaply.
struct Window<'a> {
    file: &'a File,
    len: u64,
    buf: Vec<u8>,
    at: u64,
}

impl Window<'_> {
    /// Up to `n` bytes at `pos` (fewer at the end of the file).
    fn get(&mut self, pos: u64, n: usize) -> std::io::Result<&[u8]> {
        let have = pos >= self.at && pos + n as u64 <= self.at + self.buf.len() as u64;
        if !have {
            let want = (n.max(SCAN_WINDOW) as u64).min(self.len.saturating_sub(pos)) as usize;
            self.buf.resize(want, 0);
            self.file.read_exact_at(&mut self.buf, pos)?;
            self.at = pos;
        }
        let off = (pos - self.at) as usize;
        let end = (off + n).min(self.buf.len());
        Ok(&self.buf[off..end])
    }
}

fn op_name(op: u8) -> String {
    match Op::from_byte(op) {
        Some(o) => format!("{o:?}"),
        None => format!("unknown (opcode 0x{op:02x})"),
    }
}

impl McapReader {
    /// Opens an MCAP file: summary (when intact) and a walk of the data section.
    pub fn open(path: &Path) -> Result<McapReader, Error> {
        let file = File::open(path).map_err(|e| Error::io(path, e))?;
        let len = file.metadata().map_err(|e| Error::io(path, e))?.len();
        let mut magic = [0u8; 8];
        let got = (&file)
            .take(8)
            .read(&mut magic)
            .map_err(|e| Error::io(path, e))?;
        if got < 8 || &magic != MAGIC {
            return Err(Error::NotABag {
                path: path.to_path_buf(),
                what: format!("missing the MCAP magic. Accepted: {}", source::ACCEPTED),
            });
        }
        let mut r = McapReader {
            path: path.to_path_buf(),
            file,
            len,
            header: Header::default(),
            schemas: BTreeMap::new(),
            mcap_channels: BTreeMap::new(),
            statistics: None,
            summary_used: false,
            locs: Vec::new(),
            contents: source::Contents::default(),
        };
        let footer = r.read_footer();
        let mut data_end = len;
        let mut chunk_indexes = Vec::new();
        if let Some((footer_pos, f)) = footer {
            data_end = footer_pos;
            if f.summary_start != 0 {
                match r.read_summary(footer_pos, &f) {
                    Ok(ci) => {
                        r.summary_used = true;
                        data_end = f.summary_start;
                        chunk_indexes = ci;
                    }
                    Err(e) => {
                        r.schemas.clear();
                        r.mcap_channels.clear();
                        r.statistics = None;
                        r.contents.notes.push(format!(
                            "the summary section is damaged ({e}); the data section was scanned instead"
                        ));
                    }
                }
            }
        } else {
            r.contents.notes.push(
                "the file has no footer (the recording was cut short, or the file is truncated); its records were scanned".to_string(),
            );
        }
        r.walk(data_end)?;
        r.cross_check(&chunk_indexes);
        r.build_channels();
        Ok(r)
    }

    /// The footer and its offset, when the file ends with a footer record and the magic.
    fn read_footer(&self) -> Option<(u64, Footer)> {
        let tail = RECORD_PREFIX + FOOTER_CONTENT_LEN + MAGIC.len() as u64;
        if self.len < MAGIC.len() as u64 + tail {
            return None;
        }
        let pos = self.len - tail;
        let mut b = vec![0u8; tail as usize];
        self.file.read_exact_at(&mut b, pos).ok()?;
        if &b[tail as usize - 8..] != MAGIC || b[0] != Op::Footer as u8 {
            return None;
        }
        if u64::from_le_bytes(b[1..9].try_into().ok()?) != FOOTER_CONTENT_LEN {
            return None;
        }
        Some((pos, Footer::decode(&b[9..29]).ok()?))
    }

    /// Reads the summary section: schemas, channels, statistics and chunk indexes.
    fn read_summary(&mut self, footer_pos: u64, f: &Footer) -> Result<Vec<ChunkIndex>, String> {
        let end = if f.summary_offset_start != 0 {
            f.summary_offset_start
        } else {
            footer_pos
        };
        if f.summary_start < MAGIC.len() as u64 || f.summary_start > end || end > footer_pos {
            return Err(format!(
                "its offsets {}..{} are outside the file",
                f.summary_start, end
            ));
        }
        if f.summary_crc != 0 {
            // The CRC covers the summary and summary-offset sections and the footer up to
            // (not including) its CRC field.
            let mut b = vec![0u8; (footer_pos + RECORD_PREFIX + 16 - f.summary_start) as usize];
            self.file
                .read_exact_at(&mut b, f.summary_start)
                .map_err(|e| e.to_string())?;
            let crc = crc32fast::hash(&b);
            if crc != f.summary_crc {
                return Err(format!(
                    "CRC {crc:08x} differs from the footer's {:08x}",
                    f.summary_crc
                ));
            }
        }
        let mut b = vec![0u8; (end - f.summary_start) as usize];
        self.file
            .read_exact_at(&mut b, f.summary_start)
            .map_err(|e| e.to_string())?;
        let mut c = Cursor::new(&b);
        let mut chunk_indexes = Vec::new();
        while c.pos() < b.len() {
            let op = c.u8()?;
            let content = c.bytes64()?;
            match Op::from_byte(op) {
                Some(Op::Schema) => {
                    let s = Schema::decode(content)?;
                    self.schemas.insert(s.id, s);
                }
                Some(Op::Channel) => {
                    let ch = record::Channel::decode(content)?;
                    self.mcap_channels.insert(ch.id, ch);
                }
                Some(Op::Statistics) => self.statistics = Some(Statistics::decode(content)?),
                Some(Op::ChunkIndex) => chunk_indexes.push(ChunkIndex::decode(content)?),
                _ => {}
            }
        }
        Ok(chunk_indexes)
    }

    /// Walks the top-level records of the data section, up to `end`.
    fn walk(&mut self, end: u64) -> Result<(), Error> {
        let file = self
            .file
            .try_clone()
            .map_err(|e| Error::io(&self.path, e))?;
        let mut w = Window {
            file: &file,
            len: end,
            buf: Vec::new(),
            at: 0,
        };
        let path = self.path.clone();
        let io = |e: std::io::Error| Error::io(&path, e);
        let mut pos = MAGIC.len() as u64;
        let mut first = true;
        let mut seen_data_end = false;
        let need_inner_channels = !self.summary_used;
        while pos < end {
            let pre = w.get(pos, RECORD_PREFIX as usize).map_err(io)?.to_vec();
            if pre.len() < RECORD_PREFIX as usize {
                self.tail_lost(pos, end, None);
                break;
            }
            let op = pre[0];
            let clen = u64::from_le_bytes(pre[1..9].try_into().expect("8 bytes"));
            let content_pos = pos + RECORD_PREFIX;
            let rec_end = content_pos.checked_add(clen).filter(|&e| e <= end);
            let Some(rec_end) = rec_end else {
                let chunk_header = (op == Op::Chunk as u8)
                    .then(|| {
                        let avail = (end - content_pos).min(4096) as usize;
                        let b = w.get(content_pos, avail).ok()?.to_vec();
                        ChunkHeader::decode(&b).ok().map(|(h, _)| h)
                    })
                    .flatten();
                self.tail_lost(pos, end, Some((op, chunk_header)));
                break;
            };
            if first && op != Op::Header as u8 {
                // The Header only names the profile and library: its damage costs nothing.
                self.contents.notes.push(format!(
                    "the first record (byte {pos}) is not an MCAP Header; the records after the magic were read anyway"
                ));
            }
            let small = |w: &mut Window| -> Result<Option<Vec<u8>>, Error> {
                if clen > MAX_META_RECORD {
                    return Ok(None);
                }
                Ok(Some(
                    w.get(content_pos, clen as usize).map_err(io)?.to_vec(),
                ))
            };
            match Op::from_byte(op) {
                Some(Op::Header) if first => match small(&mut w)?.map(|b| Header::decode(&b)) {
                    Some(Ok(h)) => self.header = h,
                    _ => self.contents.notes.push(format!(
                        "the MCAP Header record at byte {pos} is damaged; the records after it were read anyway"
                    )),
                },
                Some(Op::Schema) => {
                    if let Some(Ok(s)) = small(&mut w)?.map(|b| Schema::decode(&b)) {
                        self.schemas.entry(s.id).or_insert(s);
                    } else {
                        self.contents.notes
                            .push(format!("unreadable Schema record at byte {pos} skipped"));
                    }
                }
                Some(Op::Channel) => {
                    if let Some(Ok(c)) = small(&mut w)?.map(|b| record::Channel::decode(&b)) {
                        self.mcap_channels.entry(c.id).or_insert(c);
                    } else {
                        self.contents.notes
                            .push(format!("unreadable Channel record at byte {pos} skipped"));
                    }
                }
                Some(Op::Chunk) => {
                    let avail = clen.min(4096) as usize;
                    let b = w.get(content_pos, avail).map_err(io)?.to_vec();
                    match ChunkHeader::decode(&b) {
                        Ok((h, off)) if h.compressed_size == clen - off as u64 => {
                            self.locs.push(Loc::Chunk {
                                records_pos: content_pos + off as u64,
                                compressed_size: h.compressed_size,
                                uncompressed_size: h.uncompressed_size,
                                crc: h.uncompressed_crc,
                                compression: h.compression.clone(),
                            });
                            self.contents.parts.push(Part {
                                bytes: h.uncompressed_size.min(
                                    h.compressed_size.saturating_mul(source::MAX_EXPANSION),
                                ),
                                label: format!("chunk at byte {pos}"),
                                span: Some((h.message_start_time, h.message_end_time)),
                                counts: None,
                            });
                            if need_inner_channels {
                                self.collect_inner_channels(self.locs.len() - 1);
                            }
                        }
                        Ok((h, _)) => self.contents.losses.push(Loss {
                            what: format!(
                                "chunk at byte {pos}: its records length disagrees with the record length; skipped"
                            ),
                            messages: None,
                            span: Some((h.message_start_time, h.message_end_time)),
                            channel: None,
                            ..Loss::default()
                        }),
                        Err(e) => self.contents.losses.push(Loss {
                            what: format!("chunk at byte {pos} has an unreadable header ({e}); skipped"),
                            messages: None,
                            span: None,
                            channel: None,
                            ..Loss::default()
                        }),
                    }
                }
                Some(Op::MessageIndex) => {
                    let b = w
                        .get(content_pos, 6.min(clen as usize))
                        .map_err(io)?
                        .to_vec();
                    if let (Ok((ch, n)), Some(p)) = (MessageIndex::count(&b), self.contents.parts.last_mut())
                        && matches!(self.locs.last(), Some(Loc::Chunk { .. }))
                    {
                        p.counts.get_or_insert_with(Vec::new).push((ch as u32, n));
                    }
                }
                Some(Op::Message) => {
                    let b = w
                        .get(content_pos, MESSAGE_FIXED_LEN.min(clen as usize))
                        .map_err(io)?;
                    let t = (b.len() == MESSAGE_FIXED_LEN)
                        .then(|| u64::from_le_bytes(b[6..14].try_into().expect("8 bytes")));
                    self.add_loose(pos, rec_end, t);
                }
                Some(Op::DataEnd) => {
                    seen_data_end = true;
                    break;
                }
                Some(Op::Footer) => break,
                _ => {}
            }
            first = false;
            pos = rec_end;
        }
        if first {
            return Err(Error::Corrupt {
                path: self.path.clone(),
                offset: pos,
                what: "the MCAP file holds no complete record after its magic (truncated)".into(),
            });
        }
        if !seen_data_end && pos >= end && self.summary_used {
            self.contents
                .notes
                .push("the data section has no Data End record".to_string());
        }
        Ok(())
    }

    /// Extends the current run of unchunked records, or starts a new one.
    fn add_loose(&mut self, pos: u64, end: u64, t: Option<u64>) {
        if let (Some(Loc::Loose { start, end: e }), Some(p)) =
            (self.locs.last_mut(), self.contents.parts.last_mut())
            && *e == pos
            && end - *start <= LOOSE_PART_BYTES
        {
            *e = end;
            p.bytes = end - *start;
            if let Some(t) = t {
                p.span = Some(match p.span {
                    Some((a, b)) => (a.min(t), b.max(t)),
                    None => (t, t),
                });
            }
            return;
        }
        self.locs.push(Loc::Loose { start: pos, end });
        self.contents.parts.push(Part {
            bytes: end - pos,
            label: format!("unchunked messages from byte {pos}"),
            span: t.map(|t| (t, t)),
            counts: None,
        });
    }

    /// Notes what the incomplete record at the end of the walk held.
    fn tail_lost(&mut self, pos: u64, end: u64, rec: Option<(u8, Option<ChunkHeader>)>) {
        let what = match &rec {
            Some((op, _)) => format!(
                "the last {} bytes of the file are an incomplete {} record (truncated file); skipped",
                end - pos,
                op_name(*op)
            ),
            None => format!(
                "the last {} bytes of the file are an incomplete record (truncated file); skipped",
                end - pos
            ),
        };
        let span = rec
            .as_ref()
            .and_then(|(_, h)| h.as_ref())
            .map(|h| (h.message_start_time, h.message_end_time));
        let messages = match rec {
            Some((op, _)) if op == Op::Message as u8 => Some(1),
            _ => None,
        };
        self.contents.losses.push(Loss {
            what,
            messages,
            span,
            channel: None,
            ..Loss::default()
        });
    }

    /// Without a summary, the schemas and channels may live only inside chunks.
    fn collect_inner_channels(&mut self, loc: usize) {
        let mut found = Vec::new();
        let _ = self.with_records(loc, |op, content| {
            match Op::from_byte(op) {
                Some(Op::Schema) => {
                    if let Ok(s) = Schema::decode(content) {
                        found.push((Some(s), None));
                    }
                }
                Some(Op::Channel) => {
                    if let Ok(c) = record::Channel::decode(content) {
                        found.push((None, Some(c)));
                    }
                }
                _ => {}
            }
            Ok(())
        });
        for (s, c) in found {
            if let Some(s) = s {
                self.schemas.entry(s.id).or_insert(s);
            }
            if let Some(c) = c {
                self.mcap_channels.entry(c.id).or_insert(c);
            }
        }
    }

    /// Compares the summary's chunk indexes with the chunks found in the data section.
    fn cross_check(&mut self, chunk_indexes: &[ChunkIndex]) {
        if !self.summary_used {
            return;
        }
        let found: std::collections::BTreeSet<u64> = self
            .contents
            .parts
            .iter()
            .filter_map(|p| p.label.strip_prefix("chunk at byte "))
            .filter_map(|s| s.parse().ok())
            .collect();
        for ci in chunk_indexes {
            if !found.contains(&ci.chunk_start_offset) {
                self.contents.losses.push(Loss {
                    what: format!(
                        "the summary lists a chunk at byte {} that the data section does not hold",
                        ci.chunk_start_offset
                    ),
                    messages: None,
                    span: Some((ci.message_start_time, ci.message_end_time)),
                    channel: None,
                    ..Loss::default()
                });
            }
        }
    }

    fn build_channels(&mut self) {
        let stats: Option<BTreeMap<u16, u64>> = self
            .statistics
            .as_ref()
            .map(|s| s.channel_message_counts.iter().copied().collect());
        // Without statistics, the message indexes count the messages when every part has them.
        let indexed: Option<BTreeMap<u16, u64>> = self
            .contents
            .parts
            .iter()
            .all(|p| p.counts.is_some())
            .then(|| {
                let mut m = BTreeMap::new();
                for p in &self.contents.parts {
                    for (c, n) in p.counts.iter().flatten() {
                        *m.entry(*c as u16).or_default() += n;
                    }
                }
                m
            });
        self.contents.channels = self
            .mcap_channels
            .values()
            .map(|c| {
                let schema = self.schemas.get(&c.schema_id);
                let count = match (&stats, &indexed) {
                    (Some(s), _) => Some(s.get(&c.id).copied().unwrap_or(0)),
                    (None, Some(m)) => Some(m.get(&c.id).copied().unwrap_or(0)),
                    _ => None,
                };
                source::Channel {
                    id: c.id as u32,
                    topic: c.topic.clone(),
                    msg_type: schema.map(|s| s.name.clone()).unwrap_or_default(),
                    encoding: Encoding::from_name(&c.message_encoding),
                    md5sum: c
                        .metadata
                        .iter()
                        .find(|(k, _)| k == "md5sum")
                        .map(|(_, v)| v.clone()),
                    count,
                }
            })
            .collect();
    }

    /// Calls `f(opcode, content)` for each record of part `loc`, in order.
    fn with_records(
        &self,
        loc: usize,
        mut f: impl FnMut(u8, &[u8]) -> Result<(), String>,
    ) -> Result<(), String> {
        let loc = self.locs.get(loc).ok_or("no such part")?;
        BUFFERS.with(|cell| {
            let mut bufs = cell.borrow_mut();
            let (raw, body) = &mut *bufs;
            let records: &[u8] = match loc {
                Loc::Loose { start, end } => {
                    raw.resize((end - start) as usize, 0);
                    self.file
                        .read_exact_at(raw, *start)
                        .map_err(|e| e.to_string())?;
                    raw
                }
                Loc::Chunk {
                    records_pos,
                    compressed_size,
                    uncompressed_size,
                    crc,
                    compression,
                } => {
                    raw.resize(*compressed_size as usize, 0);
                    self.file
                        .read_exact_at(raw, *records_pos)
                        .map_err(|e| e.to_string())?;
                    let records: &[u8] = match compression.as_str() {
                        "" => raw,
                        "lz4" => {
                            body.clear();
                            lz4_flex::frame::FrameDecoder::new(&raw[..])
                                .take(uncompressed_size.saturating_add(1))
                                .read_to_end(body)
                                .map_err(|e| format!("lz4: {e}"))?;
                            body
                        }
                        "zstd" => {
                            crate::zstd::decompress_into(raw, body, *uncompressed_size)?;
                            body
                        }
                        other => return Err(format!("unsupported chunk compression '{other}'")),
                    };
                    if records.len() as u64 != *uncompressed_size {
                        return Err(format!(
                            "chunk records are {} bytes, its header says {uncompressed_size}",
                            records.len()
                        ));
                    }
                    if *crc != 0 {
                        let got = crc32fast::hash(records);
                        if got != *crc {
                            return Err(format!(
                                "chunk CRC {got:08x} differs from the stored {crc:08x}"
                            ));
                        }
                    }
                    records
                }
            };
            let mut c = Cursor::new(records);
            let total = records.len();
            while c.pos() < total {
                let at = c.pos();
                let op = c.u8().map_err(|e| format!("record at offset {at}: {e}"))?;
                let content = c
                    .bytes64()
                    .map_err(|_| format!("incomplete record at offset {at}"))?;
                f(op, content)?;
            }
            Ok(())
        })
    }

    /// The file's length.
    pub fn file_len(&self) -> u64 {
        self.len
    }
}

impl Source for McapReader {
    fn kind(&self) -> InputKind {
        InputKind::Mcap
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
        let mut delivered = 0;
        let r = self.with_records(part, |op, content| {
            if op == Op::Message as u8 {
                if content.len() < MESSAGE_FIXED_LEN {
                    return Err("message record shorter than its fixed fields".into());
                }
                let ch = u16::from_le_bytes([content[0], content[1]]) as u32;
                if want(ch) {
                    let t = u64::from_le_bytes(content[6..14].try_into().expect("8 bytes"));
                    sink(ch, t, &content[MESSAGE_FIXED_LEN..]);
                    delivered += 1;
                }
            }
            Ok(())
        });
        PartRead {
            delivered,
            error: r.err(),
            ..PartRead::default()
        }
    }
}
