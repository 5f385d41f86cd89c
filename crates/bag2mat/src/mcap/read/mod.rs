//! Reading MCAP files: chunked or not, chunks `none`/`lz4`/`zstd`, with or without the
//! summary section, damaged or cut short, never losing a message in silence.
//!
//! [`McapReader::open`] takes schemas, channels and per-channel message counts from the
//! summary when it is intact (its CRC checked when one is stored), and always walks the
//! data section's top-level records: chunks become the parts read in parallel, runs of
//! unchunked messages become parts of their own, and the Message Index records after each
//! chunk give the messages it holds per channel (with their times and offsets).
//!
//! Damage is walked past, never stopped at. A record whose length or opcode is damaged is
//! skipped to the next whole record: with a summary, the next chunk its chunk indexes
//! locate; without, the next bytes that frame a chunk or message index followed by another
//! whole record. A chunk whose own record header is damaged but that the summary locates is
//! read from the summary's fields (its CRC still checks it); a chunk that cannot be read is
//! counted from its Message Index records. A Data End or Footer in mid-file, an unknown
//! opcode, a message naming no channel: each is passed and counted, never a silent end. A
//! file cut short (no footer, no summary: a recorder that was killed) is read up to its last
//! complete record, and the Data End and summary records it may still hold after its chunks
//! are used.

use crate::shared::note::Note;

mod channels;
mod summary;
mod walk;

use std::collections::BTreeMap;
use std::fs::File;
use std::io::Read;
use std::os::unix::fs::FileExt;
use std::path::{Path, PathBuf};

use super::record::{
    self, ChunkHeader, ChunkIndex, FOOTER_CONTENT_LEN, Footer, Header, MAGIC, MESSAGE_FIXED_LEN,
    McapFields, Op, RECORD_PREFIX, Schema, Statistics,
};
use crate::cursor::{Cursor, CursorError};
use crate::error::Error;
use crate::source::{
    self, Encoding, InputKind, Loss, McapChunkError, MessageSink, Part, PartError, PartRead, Source,
};

/// Bytes read at once while walking the top-level records.
const SCAN_WINDOW: usize = 64 * 1024;
/// Unchunked messages are grouped into parts of about this many bytes.
const LOOSE_PART_BYTES: u64 = 4 << 20;
/// Largest schema, channel or header record read during the walk (a damaged length must not
/// make it allocate the file).
const MAX_META_RECORD: u64 = 64 << 20;
/// Bytes a Message record of a `sensor_msgs/Imu` takes at least (record prefix, fixed
/// fields, the smallest Imu payload): bounds the Imu messages lost bytes can hold.
pub const MIN_IMU_RECORD: u64 =
    RECORD_PREFIX + MESSAGE_FIXED_LEN as u64 + crate::imu_msg::MIN_IMU_PAYLOAD;
/// Bytes a Message record takes at least: bounds any count a file states.
const MIN_MESSAGE_RECORD: u64 = RECORD_PREFIX + MESSAGE_FIXED_LEN as u64;
/// Bytes of a Message Index entry (log time, offset).
const INDEX_ENTRY: u64 = 16;

thread_local! {
    /// Per-thread (stored, decompressed) chunk buffers, reused from chunk to chunk.
    static BUFFERS: std::cell::RefCell<(Vec<u8>, Vec<u8>)> = const { std::cell::RefCell::new((Vec::new(), Vec::new())) };
}

/// Where a part's bytes are.
#[derive(Debug, Clone)]
enum Loc {
    /// A chunk's stored records.
    Chunk {
        /// File offset of the chunk record.
        pos: u64,
        records_pos: u64,
        compressed_size: u64,
        uncompressed_size: u64,
        crc: u32,
        compression: String,
    },
    /// A run of top-level records in the data section.
    Loose { start: u64, end: u64 },
}

/// A Message Index record: its channel, where its entries are, how many the file holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct IndexRef {
    channel: u16,
    entries_pos: u64,
    count: u64,
}

/// Bytes the walk could not read as records, with the Message Index records found after
/// them (which count what they held).
#[derive(Debug, Clone)]
struct Lost {
    what: String,
    /// The file offsets of the stretch.
    range: (u64, u64),
    span: Option<(u64, u64)>,
    /// Bytes of records (decompressed, when known) the stretch held.
    bytes: u64,
    indexes: Vec<IndexRef>,
}

/// What the summary section gave.
struct Summary {
    chunk_indexes: Vec<ChunkIndex>,
    /// Its CRC matched (or none is stored): its counts are promises.
    trusted: bool,
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
    /// Each part's Message Index records (chunks only).
    indexes: Vec<Vec<IndexRef>>,
    /// Stretches the walk could not read.
    lost: Vec<Lost>,
    /// The summary used stores no CRC: nothing checks it.
    summary_unchecked: bool,
    /// The schemas and channels of a summary whose CRC does not match.
    untrusted_meta: Option<(BTreeMap<u16, Schema>, BTreeMap<u16, record::Channel>)>,
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
        if pos >= self.len {
            return Ok(&[]);
        }
        let n = (n as u64).min(self.len - pos) as usize;
        let have = pos >= self.at && pos - self.at + n as u64 <= self.buf.len() as u64;
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

    /// The opcode and content length of the record at `pos`, if its prefix is in the file.
    fn prefix(&mut self, pos: u64) -> Option<(u8, u64)> {
        let p = self.get(pos, RECORD_PREFIX as usize).ok()?;
        (p.len() == RECORD_PREFIX as usize).then(|| {
            (
                p[0],
                u64::from_le_bytes(p[1..9].try_into().expect("8 bytes")),
            )
        })
    }
}

fn op_name(op: u8) -> String {
    match Op::from_byte(op) {
        Some(o) => format!("{o:?}"),
        None => format!("unknown (opcode 0x{op:02x})"),
    }
}

/// The header of the chunk whose content (`clen` bytes) starts at `content_pos`, when it
/// frames the record: its stored length fills the record and its compression is known.
fn chunk_header(w: &mut Window, content_pos: u64, clen: u64) -> Option<ChunkHeader> {
    let avail = clen.min(4096) as usize;
    let b = w.get(content_pos, avail).ok()?;
    let (h, off) = ChunkHeader::decode(b).ok()?;
    (h.compressed_size == clen - off as u64
        && ["", "lz4", "zstd"].contains(&h.compression.as_str()))
    .then_some(h)
}

/// Keeps the first record of an id, unless it is implausible (damaged) and a later copy
/// (summary and data section each hold one) is not.
fn offer<T>(m: &mut BTreeMap<u16, T>, id: u16, v: T, plausible: fn(&T) -> bool) {
    match m.get(&id) {
        Some(old) if plausible(old) || !plausible(&v) => {}
        _ => {
            m.insert(id, v);
        }
    }
}

/// A name as writers spell them: printable, no spaces.
fn name_like(s: &str) -> bool {
    !s.is_empty() && s.chars().all(|c| c.is_ascii_graphic())
}

fn schema_plausible(s: &Schema) -> bool {
    name_like(&s.name) && name_like(&s.encoding)
}

fn channel_plausible(c: &record::Channel) -> bool {
    name_like(&c.topic)
        && !c.message_encoding.is_empty()
        && c.message_encoding
            .chars()
            .all(|c| c.is_ascii_lowercase() || c.is_ascii_digit())
}

/// What the Message Index records the walk meets next belong to.
#[derive(Clone, Copy)]
enum After {
    /// The chunk of this part.
    Chunk(usize),
    /// The unreadable stretch of this index in `McapReader::lost`.
    Lost(usize),
    /// Nothing (they are not counted).
    Other,
}

/// Which records a resynchronisation may land on: those that appear at the top level of a
/// chunked data section (loose messages and their schemas only when the file has no chunk,
/// so that the walk never lands inside an uncompressed chunk).
#[derive(Clone, Copy, PartialEq, Eq)]
enum Landing {
    Chunked,
    Unchunked,
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
                what: format!("missing the MCAP magic. Accepted: {}", source::accepted()),
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
            indexes: Vec::new(),
            lost: Vec::new(),
            untrusted_meta: None,
            summary_unchecked: false,
            contents: source::Contents::default(),
        };
        let (data_end, mut summary) = r.summary_and_data_end();
        let hints = resync_hints(summary.as_ref());
        let found_summary = r.walk(data_end, &hints)?;
        if summary.is_none()
            && let Some(s) = found_summary
        {
            summary = Some(s);
        }
        if let Some(s) = &summary {
            r.chunks_from_summary(&s.chunk_indexes);
        }
        r.complete_channels();
        // a summary whose CRC does not match: its schemas and channels stand in only for
        // those the data section (and its chunks) lack
        if let Some((schemas, channels)) = r.untrusted_meta.take() {
            for (id, s) in schemas {
                r.schemas.entry(id).or_insert(s);
            }
            for (id, c) in channels {
                r.mcap_channels.entry(id).or_insert(c);
            }
        }
        r.account_lost();
        r.build_channels();
        Ok(r)
    }

    /// The summary (when the footer locates one that reads) and where the data section
    /// ends; a note when there is no footer or the summary is damaged.
    fn summary_and_data_end(&mut self) -> (u64, Option<Summary>) {
        let footer = self.read_footer();
        let mut data_end = self.len;
        let mut summary = None;
        if let Some((footer_pos, f)) = footer {
            data_end = footer_pos;
            if f.summary_start != 0 {
                match self.read_summary(footer_pos, &f) {
                    Ok(s) => {
                        self.summary_used = true;
                        self.summary_unchecked = f.summary_crc == 0;
                        if s.trusted {
                            data_end = f.summary_start;
                        } else {
                            // A damaged footer may misplace the summary: the walk goes on
                            // to the footer and ends at the Data End record. Its schemas and
                            // channels only stand in for those the data section lacks.
                            self.statistics = None;
                            self.untrusted_meta = Some((
                                std::mem::take(&mut self.schemas),
                                std::mem::take(&mut self.mcap_channels),
                            ));
                        }
                        summary = Some(s);
                    }
                    Err(e) => {
                        self.schemas.clear();
                        self.mcap_channels.clear();
                        self.statistics = None;
                        self.contents.notes.push(Note::warning(format!(
                            "the summary section is damaged ({e}); the data section was scanned instead"
                        )));
                    }
                }
            }
        } else {
            self.contents.notes.push(Note::warning(
                "the file has no footer (the recording was cut short, or the file is truncated); its records were scanned".to_string(),
            ));
        }
        (data_end, summary)
    }

    /// The damage a part's walk skipped, as a loss when nothing counts what it held
    /// (`unindexed`: as many Imu messages as its bytes fit), else as a note (the index
    /// shows every message it lists was delivered).
    fn damage_report(
        &self,
        part: usize,
        unindexed: bool,
        damage: &[(String, u64)],
        out: &mut PartRead,
    ) {
        let what = format!(
            "{}: {}",
            self.contents.parts[part].label,
            damage
                .iter()
                .map(|d| d.0.as_str())
                .collect::<Vec<_>>()
                .join("; ")
        );
        if unindexed {
            // Nothing counts what the skipped bytes held: as many Imu messages as fit.
            let bytes: u64 = damage.iter().map(|d| d.1).sum();
            out.lost.push(Loss {
                what,
                at_most: Some(bytes / MIN_IMU_RECORD),
                ..Loss::default()
            });
        } else {
            // Every message the index lists was delivered: the damage cost none.
            out.notes.push(Note::warning(what));
        }
    }

    /// The messages the chunk's message index lists for a wanted channel that were not
    /// delivered (`delivered_at`: channel and offset, sorted), as one loss per channel.
    fn unread_listed(
        &self,
        part: usize,
        indexes: &[IndexRef],
        want: &(dyn Fn(u32) -> bool + Sync),
        delivered_at: &[(u16, u64)],
        why: &str,
    ) -> Vec<Loss> {
        let mut losses = Vec::new();
        let mut lost: BTreeMap<u16, (u64, u64, u64)> = BTreeMap::new();
        for ix in indexes.iter().filter(|ix| want(ix.channel as u32)) {
            for (t, off) in self.entries(ix) {
                if delivered_at.binary_search(&(ix.channel, off)).is_err() {
                    let e = lost.entry(ix.channel).or_insert((0, t, t));
                    e.0 += 1;
                    e.1 = e.1.min(t);
                    e.2 = e.2.max(t);
                }
            }
        }
        let label = &self.contents.parts[part].label;
        for (ch, (n, a, b)) in lost {
            losses.push(Loss {
                what: format!(
                    "{label}: {} that the chunk's message index lists could not be read ({why})",
                    if n == 1 { "a message" } else { "messages" }
                ),
                messages: Some(n),
                span: Some((a, b)),
                channel: Some(ch as u32),
                ..Loss::default()
            });
        }
        losses
    }

    /// Calls `f(offset, opcode, content)` for each record of part `loc`, in order. A record
    /// whose framing is damaged is skipped to the next offset `listed()` gives (the chunk's
    /// message indexes, sorted), else ends the part with an error.
    fn with_records(
        &self,
        loc: usize,
        f: impl FnMut(u64, u8, &[u8]),
        listed: &dyn Fn() -> Vec<u64>,
    ) -> Result<Vec<(String, u64)>, PartError> {
        let loc = self.locs.get(loc).ok_or(PartError::NoSuchPart {
            index: loc,
            wording: source::NoSuchPart::Part,
        })?;
        BUFFERS.with(|cell| {
            let mut bufs = cell.borrow_mut();
            let (raw, body) = &mut *bufs;
            let records = self.records_of(loc, raw, body)?;
            Ok(frame_records(records, f, listed))
        })
    }

    /// The stored records of part `loc`: read into `raw` (a chunk's decompressed into
    /// `body`), and checked against the chunk's CRC and stated size.
    fn records_of<'b>(
        &self,
        loc: &Loc,
        raw: &'b mut Vec<u8>,
        body: &'b mut Vec<u8>,
    ) -> Result<&'b [u8], McapChunkError> {
        match loc {
            Loc::Loose { start, end } => {
                raw.resize((end - start) as usize, 0);
                self.file
                    .read_exact_at(raw, *start)
                    .map_err(|e| McapChunkError::Io(e.into()))?;
                Ok(raw)
            }
            Loc::Chunk {
                records_pos,
                compressed_size,
                uncompressed_size,
                crc,
                compression,
                ..
            } => {
                if records_pos.saturating_add(*compressed_size) > self.len {
                    return Err(McapChunkError::PastEnd);
                }
                raw.resize(*compressed_size as usize, 0);
                self.file
                    .read_exact_at(raw, *records_pos)
                    .map_err(|e| McapChunkError::Io(e.into()))?;
                // A damaged size field must not fail records the CRC vouches for: the
                // output is bounded by what the stored bytes decompress to (or the size
                // stated, if larger), never preallocated.
                let limit =
                    (*uncompressed_size).max(compressed_size.saturating_mul(source::MAX_EXPANSION));
                let raw: &'b [u8] = raw;
                let records: &'b [u8] = match compression.as_str() {
                    "" => raw,
                    "lz4" => {
                        body.clear();
                        lz4_flex::frame::FrameDecoder::new(raw)
                            .take(limit.saturating_add(1))
                            .read_to_end(body)
                            .map_err(|e| McapChunkError::Lz4(e.into()))?;
                        body
                    }
                    "zstd" => {
                        crate::zstd::decompress_into(raw, body, limit)
                            .map_err(|e| McapChunkError::Zstd(e.into()))?;
                        body
                    }
                    other => return Err(McapChunkError::Compression(other.to_string())),
                };
                let crc_ok = *crc != 0 && crc32fast::hash(records) == *crc;
                // Without a CRC, the stored records of an uncompressed chunk are what
                // its record length frames, whatever its size field says.
                let framed = *crc == 0 && compression.is_empty();
                if records.len() as u64 != *uncompressed_size && !crc_ok && !framed {
                    return Err(McapChunkError::Size {
                        got: records.len(),
                        stated: *uncompressed_size,
                    });
                }
                if *crc != 0 && !crc_ok {
                    return Err(McapChunkError::Crc {
                        got: crc32fast::hash(records),
                        stored: *crc,
                    });
                }
                Ok(records)
            }
        }
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
        let mut out = PartRead::default();
        let indexes = self.indexes.get(part).map(|v| v.as_slice()).unwrap_or(&[]);
        // The chunk's message offsets, read only when a record turns out damaged or a
        // channel short.
        let listed = || {
            let mut v: Vec<u64> = indexes
                .iter()
                .flat_map(|ix| self.entries(ix).into_iter().map(|e| e.1))
                .collect();
            v.sort_unstable();
            v
        };
        let mut delivered_at: Vec<(u16, u64)> = Vec::new();
        let mut no_channel = 0u64;
        let r = self.with_records(
            part,
            |at, op, content| {
                if op == Op::Message as u8 {
                    let ch = u16::from_le_bytes([content[0], content[1]]);
                    if !self.mcap_channels.contains_key(&ch) {
                        no_channel += 1;
                        return;
                    }
                    if want(ch as u32) {
                        let t = u64::from_le_bytes(content[6..14].try_into().expect("8 bytes"));
                        sink(ch as u32, t, &content[MESSAGE_FIXED_LEN..]);
                        out.delivered += 1;
                        delivered_at.push((ch, at));
                    }
                }
            },
            &listed,
        );
        let damage = match r {
            Ok(d) => d,
            Err(e) => {
                out.error = Some(e);
                return out;
            }
        };
        // Each wanted channel against what its message index lists.
        let short = indexes.iter().any(|ix| {
            want(ix.channel as u32)
                && (delivered_at.iter().filter(|d| d.0 == ix.channel).count() as u64) < ix.count
        });
        if short {
            delivered_at.sort_unstable();
            let why = short_reason(&damage, no_channel);
            out.lost
                .extend(self.unread_listed(part, indexes, want, &delivered_at, &why));
        } else if no_channel > 0 && indexes.is_empty() {
            out.lost.push(Loss {
                what: format!(
                    "{}: {no_channel} message record(s) name a channel no Channel record defines (a damaged channel id)",
                    self.contents.parts[part].label
                ),
                messages: Some(no_channel),
                ..Loss::default()
            });
        }
        if !damage.is_empty() && (out.lost.is_empty() || !short) {
            self.damage_report(part, indexes.is_empty(), &damage, &mut out);
        }
        out
    }
}

/// Why messages the index lists could not be read: the damage met, else records naming
/// an undefined channel, else records that are no readable message.
fn short_reason(damage: &[(String, u64)], no_channel: u64) -> String {
    if damage.is_empty() && no_channel > 0 {
        format!(
            "{no_channel} message record(s) name a channel no Channel record defines (a damaged channel id)"
        )
    } else if damage.is_empty() {
        "its record is not a readable message".to_string()
    } else {
        damage
            .iter()
            .map(|d| d.0.as_str())
            .collect::<Vec<_>>()
            .join("; ")
    }
}

/// The positions the summary gives of chunks and message indexes, sorted: where a walk
/// past damage tries to land first.
fn resync_hints(summary: Option<&Summary>) -> Vec<u64> {
    let mut hints: Vec<u64> = Vec::new();
    if let Some(s) = summary {
        for ci in &s.chunk_indexes {
            hints.push(ci.chunk_start_offset);
            hints.extend(ci.message_index_offsets.iter().map(|x| x.1));
        }
    }
    hints.sort_unstable();
    hints.dedup();
    hints
}

/// Calls `f(offset, opcode, content)` for each record of `records`, in order; a record
/// whose framing is damaged is skipped to the next offset `listed()` gives. Returns what
/// was skipped: (why, bytes).
fn frame_records(
    records: &[u8],
    mut f: impl FnMut(u64, u8, &[u8]),
    listed: &dyn Fn() -> Vec<u64>,
) -> Vec<(String, u64)> {
    let total = records.len();
    let mut damage = Vec::new();
    let mut offsets: Option<Vec<u64>> = None;
    let mut at = 0usize;
    while at < total {
        let rec = (|| {
            let mut c = Cursor::new(&records[at..]);
            let op = c.le::<u8>("opcode").ok()?;
            let content = c.bytes64().ok()?;
            Some((op, content, c.pos()))
        })();
        match rec {
            Some((op, content, n))
                if op != Op::Message as u8 || content.len() >= MESSAGE_FIXED_LEN =>
            {
                f(at as u64, op, content);
                at += n;
            }
            _ => {
                let next = offsets
                    .get_or_insert_with(listed)
                    .iter()
                    .copied()
                    .find(|&o| o > at as u64 && o < total as u64);
                let to = next.map_or(total, |o| o as usize);
                damage.push((
                    format!(
                        "damaged record framing at offset {at} of the chunk's records: bytes {at}..{to} skipped"
                    ),
                    (to - at) as u64,
                ));
                at = to;
            }
        }
    }
    damage
}
