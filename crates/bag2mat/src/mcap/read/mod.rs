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
use crate::source::{self, Encoding, InputKind, Loss, MessageSink, Part, PartRead, Source};

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
    RECORD_PREFIX + MESSAGE_FIXED_LEN as u64 + crate::series::MIN_IMU_PAYLOAD;
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
            indexes: Vec::new(),
            lost: Vec::new(),
            contents: source::Contents::default(),
        };
        let footer = r.read_footer();
        let mut data_end = len;
        let mut summary = None;
        if let Some((footer_pos, f)) = footer {
            data_end = footer_pos;
            if f.summary_start != 0 {
                match r.read_summary(footer_pos, &f) {
                    Ok(s) => {
                        r.summary_used = true;
                        if s.trusted {
                            data_end = f.summary_start;
                        } else {
                            // A damaged footer may misplace the summary: the walk goes on
                            // to the footer and ends at the Data End record.
                            r.statistics = None;
                        }
                        summary = Some(s);
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
        let mut hints: Vec<u64> = Vec::new();
        if let Some(s) = &summary {
            for ci in &s.chunk_indexes {
                hints.push(ci.chunk_start_offset);
                hints.extend(ci.message_index_offsets.iter().map(|x| x.1));
            }
        }
        hints.sort_unstable();
        hints.dedup();
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
        r.account_lost();
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

    /// Reads the summary section: schemas, channels, statistics and chunk indexes. A CRC
    /// that does not match leaves its counts untrusted; its chunk indexes still locate
    /// chunks (each is checked against the data section).
    fn read_summary(&mut self, footer_pos: u64, f: &Footer) -> Result<Summary, String> {
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
        let mut trusted = true;
        if f.summary_crc != 0 {
            // The CRC covers the summary and summary-offset sections and the footer up to
            // (not including) its CRC field.
            let mut b = vec![0u8; (footer_pos + RECORD_PREFIX + 16 - f.summary_start) as usize];
            self.file
                .read_exact_at(&mut b, f.summary_start)
                .map_err(|e| e.to_string())?;
            let crc = crc32fast::hash(&b);
            if crc != f.summary_crc {
                trusted = false;
                self.contents.notes.push(format!(
                    "the summary section is damaged (CRC {crc:08x} differs from the footer's {:08x}): its counts are not used, its chunk indexes only locate chunks",
                    f.summary_crc
                ));
            }
        }
        let mut b = vec![0u8; (end - f.summary_start) as usize];
        self.file
            .read_exact_at(&mut b, f.summary_start)
            .map_err(|e| e.to_string())?;
        let chunk_indexes = self.summary_records(&b, trusted)?;
        Ok(Summary {
            chunk_indexes,
            trusted,
        })
    }

    /// Parses summary records (schemas, channels, statistics, chunk indexes). Untrusted,
    /// a record that does not parse ends the section instead of failing it.
    fn summary_records(&mut self, b: &[u8], trusted: bool) -> Result<Vec<ChunkIndex>, String> {
        let mut c = Cursor::new(b);
        let mut chunk_indexes = Vec::new();
        while c.pos() < b.len() {
            // Framing first: an untrusted summary skips a record whose content does not
            // parse, and ends at framing that does not hold.
            let framed = c.le::<u8>("opcode").and_then(|op| Ok((op, c.bytes64()?)));
            let (op, content) = match framed {
                Ok(x) => x,
                Err(e) if trusted => return Err(e.to_string()),
                Err(_) => break,
            };
            let rec = (|| -> Result<(), CursorError> {
                match Op::from_byte(op) {
                    Some(Op::Schema) => {
                        let s = Schema::decode(content)?;
                        offer(&mut self.schemas, s.id, s, schema_plausible);
                    }
                    Some(Op::Channel) => {
                        let ch = record::Channel::decode(content)?;
                        offer(&mut self.mcap_channels, ch.id, ch, channel_plausible);
                    }
                    Some(Op::Statistics) => self.statistics = Some(Statistics::decode(content)?),
                    Some(Op::ChunkIndex) => {
                        let ci = ChunkIndex::decode(content)?;
                        if ci.chunk_start_offset < self.len {
                            chunk_indexes.push(ci);
                        }
                    }
                    _ => {}
                }
                Ok(())
            })();
            if let Err(e) = rec
                && trusted
            {
                return Err(e.to_string());
            }
        }
        Ok(chunk_indexes)
    }

    /// The end of the record at `pos` when it frames as a top-level record a walk may land
    /// on (see [`Landing`]) and its content checks out for its opcode.
    fn frames(&self, w: &mut Window, pos: u64, end: u64, landing: Landing) -> Option<u64> {
        let (op, clen) = w.prefix(pos)?;
        let content_pos = pos + RECORD_PREFIX;
        let rec_end = content_pos.checked_add(clen).filter(|&e| e <= end)?;
        match Op::from_byte(op)? {
            Op::Chunk => {
                // Landing on bytes that only look like a chunk is ruled out by its times too.
                let h = chunk_header(w, content_pos, clen)?;
                (h.message_start_time <= h.message_end_time).then_some(rec_end)
            }
            Op::MessageIndex => {
                let b = w.get(content_pos, 6.min(clen as usize)).ok()?;
                (b.len() == 6
                    && u32::from_le_bytes(b[2..6].try_into().expect("4 bytes")) as u64 == clen - 6
                    && (clen - 6) % INDEX_ENTRY == 0)
                    .then_some(rec_end)
            }
            Op::DataEnd => (clen == 4).then_some(rec_end),
            Op::Footer => (clen == FOOTER_CONTENT_LEN).then_some(rec_end),
            Op::Message if landing == Landing::Unchunked => {
                (clen >= MESSAGE_FIXED_LEN as u64).then_some(rec_end)
            }
            Op::Schema | Op::Channel if landing == Landing::Unchunked => {
                if clen > MAX_META_RECORD {
                    return None;
                }
                let b = w.get(content_pos, clen as usize).ok()?;
                let ok = if op == Op::Schema as u8 {
                    Schema::decode(b).is_ok()
                } else {
                    record::Channel::decode(b).is_ok()
                };
                ok.then_some(rec_end)
            }
            _ => None,
        }
    }

    /// The next position at or after `from` where a whole record starts that is followed
    /// by another (or by the end): a chunk the summary locates, else the first such bytes.
    fn resync(
        &self,
        w: &mut Window,
        from: u64,
        end: u64,
        hints: &[u64],
        landing: Landing,
    ) -> Option<u64> {
        let followed = |w: &mut Window, p: u64| -> bool {
            match self.frames(w, p, end, landing) {
                Some(e) => e == end || self.frames(w, e, end, landing).is_some(),
                None => false,
            }
        };
        let k = hints.partition_point(|&h| h < from);
        if let Some(&h) = hints[k..].iter().find(|&&h| h < end && followed(w, h)) {
            return Some(h);
        }
        let mut p = from;
        while p + RECORD_PREFIX <= end {
            let b = w.get(p, 1).ok()?;
            let op = *b.first()?;
            let candidate = matches!(
                Op::from_byte(op),
                Some(Op::Chunk | Op::MessageIndex | Op::DataEnd | Op::Footer)
            ) || (landing == Landing::Unchunked
                && matches!(
                    Op::from_byte(op),
                    Some(Op::Message | Op::Schema | Op::Channel)
                ));
            if candidate && followed(w, p) {
                return Some(p);
            }
            p += 1;
        }
        None
    }

    /// Walks the top-level records of the data section, up to `end`. Returns the summary
    /// records found after a Data End when the file has no usable footer (a file cut in
    /// its summary section).
    // Long: one loop over the records whose state (position, the chunk the next index
    // follows, Data End seen, resync) every opcode's arm reads and moves; split per opcode
    // it would thread that state through each arm.
    fn walk(&mut self, end: u64, hints: &[u64]) -> Result<Option<Summary>, Error> {
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
        let mut any = false;
        let mut seen_data_end = false;
        let mut after = After::Other;
        let mut found_summary = None;
        while pos < end {
            let landing = if self.locs.iter().any(|l| matches!(l, Loc::Chunk { .. })) {
                Landing::Chunked
            } else {
                Landing::Unchunked
            };
            let Some((op, clen)) = w.prefix(pos) else {
                self.tail_lost(&mut w, pos, end, None);
                break;
            };
            let content_pos = pos + RECORD_PREFIX;
            let rec_end = content_pos.checked_add(clen).filter(|&e| e <= end);
            let Some(rec_end) = rec_end else {
                // A length past the end: truncation, or a damaged length with records after.
                // A chunk's own records are never landed on (they frame as loose ones).
                let is_chunk = op == Op::Chunk as u8
                    && w.get(content_pos, (end - content_pos).min(4096) as usize)
                        .ok()
                        .is_some_and(|b| ChunkHeader::decode(b).is_ok());
                let landing = if is_chunk { Landing::Chunked } else { landing };
                match self.resync(&mut w, pos + 1, end, hints, landing) {
                    Some(next) => {
                        after = self.damaged(
                            &mut w,
                            pos,
                            next,
                            op,
                            "its length runs past the end of the file",
                        );
                        pos = next;
                        continue;
                    }
                    None => {
                        self.tail_lost(&mut w, pos, end, Some(op));
                        break;
                    }
                }
            };
            if first && op != Op::Header as u8 {
                // The Header only names the profile and library: its damage costs nothing.
                self.contents.notes.push(format!(
                    "the first record (byte {pos}) is not an MCAP Header; the records after the magic were read anyway"
                ));
            }
            first = false;
            let small = |w: &mut Window| -> Result<Option<Vec<u8>>, Error> {
                if clen > MAX_META_RECORD {
                    return Ok(None);
                }
                Ok(Some(
                    w.get(content_pos, clen as usize).map_err(io)?.to_vec(),
                ))
            };
            match Op::from_byte(op) {
                Some(Op::Header) if pos == MAGIC.len() as u64 => {
                    match small(&mut w)?.map(|b| Header::decode(&b)) {
                        Some(Ok(h)) => self.header = h,
                        _ => self.contents.notes.push(format!(
                            "the MCAP Header record at byte {pos} is damaged; the records after it were read anyway"
                        )),
                    }
                    after = After::Other;
                }
                Some(Op::Schema) => {
                    if let Some(Ok(s)) = small(&mut w)?.map(|b| Schema::decode(&b)) {
                        offer(&mut self.schemas, s.id, s, schema_plausible);
                    } else {
                        self.contents
                            .notes
                            .push(format!("unreadable Schema record at byte {pos} skipped"));
                    }
                    after = After::Other;
                }
                Some(Op::Channel) => {
                    if let Some(Ok(c)) = small(&mut w)?.map(|b| record::Channel::decode(&b)) {
                        offer(&mut self.mcap_channels, c.id, c, channel_plausible);
                    } else {
                        self.contents
                            .notes
                            .push(format!("unreadable Channel record at byte {pos} skipped"));
                    }
                    after = After::Other;
                }
                Some(Op::Chunk) => {
                    // Its stored length and compression frame it (its times may be damaged).
                    if chunk_header(&mut w, content_pos, clen).is_some() {
                        let k = self.add_chunk(&mut w, pos, clen, None)?;
                        after = After::Chunk(k);
                    } else {
                        let next = self.resync(&mut w, pos + 1, end, hints, landing);
                        let to = next.unwrap_or(end);
                        after = self.damaged(&mut w, pos, to, op, "its header is damaged");
                        pos = to;
                        continue;
                    }
                }
                Some(Op::MessageIndex) => {
                    let b = w
                        .get(content_pos, 6.min(clen as usize))
                        .map_err(io)?
                        .to_vec();
                    if b.len() == 6 {
                        let channel = u16::from_le_bytes([b[0], b[1]]);
                        let stated =
                            u32::from_le_bytes(b[2..6].try_into().expect("4 bytes")) as u64;
                        // A damaged length counts no more entries than the record holds.
                        let count = stated.min(clen.saturating_sub(6)) / INDEX_ENTRY;
                        let ix = IndexRef {
                            channel,
                            entries_pos: content_pos + 6,
                            count,
                        };
                        match after {
                            After::Chunk(k) => {
                                self.indexes[k].push(ix);
                                self.contents.parts[k]
                                    .counts
                                    .get_or_insert_with(Vec::new)
                                    .push((channel as u32, count));
                            }
                            After::Lost(k) => self.lost[k].indexes.push(ix),
                            After::Other => {}
                        }
                    }
                }
                Some(Op::Message) => {
                    let b = w
                        .get(content_pos, MESSAGE_FIXED_LEN.min(clen as usize))
                        .map_err(io)?;
                    let t = (b.len() == MESSAGE_FIXED_LEN)
                        .then(|| u64::from_le_bytes(b[6..14].try_into().expect("8 bytes")));
                    self.add_loose(pos, rec_end, t);
                    after = After::Other;
                }
                Some(Op::Attachment | Op::Metadata) => after = After::Other,
                Some(op @ (Op::DataEnd | Op::Footer))
                    if clen
                        == if op == Op::DataEnd {
                            4
                        } else {
                            FOOTER_CONTENT_LEN
                        } =>
                {
                    let op = op as u8;
                    // The end of the data section, unless data-section records follow it
                    // (its opcode is damaged).
                    let data_follows = rec_end < end
                        && self.frames(&mut w, rec_end, end, landing).is_some_and(|_| {
                            w.prefix(rec_end).is_some_and(|(o, _)| {
                                matches!(
                                    Op::from_byte(o),
                                    Some(Op::Chunk | Op::MessageIndex | Op::Message)
                                )
                            })
                        });
                    if data_follows {
                        self.contents.notes.push(format!(
                            "a {} record at byte {pos} stands in the middle of the data section (a damaged opcode?); the records after it were read",
                            op_name(op)
                        ));
                        after = After::Other;
                    } else {
                        seen_data_end = op == Op::DataEnd as u8;
                        if !self.summary_used && rec_end < end {
                            // A file cut in its summary section still holds summary records.
                            let mut b = vec![0u8; (end - rec_end).min(MAX_META_RECORD) as usize];
                            if self.file.read_exact_at(&mut b, rec_end).is_ok()
                                && let Ok(ci) = self.summary_records(&b, false)
                            {
                                self.statistics = None;
                                found_summary = Some(Summary {
                                    chunk_indexes: ci,
                                    trusted: false,
                                });
                            }
                        }
                        pos = end;
                        any = true;
                        break;
                    }
                }
                Some(_) | None => {
                    // An opcode the data section does not hold (or a Data End or Footer
                    // opcode on a record of another length). A chunk whose opcode is
                    // damaged is still read (its CRC checks it); private records (0x80 and
                    // up) are skipped; anything else is damage, counted.
                    let as_chunk = {
                        let avail = clen.min(4096) as usize;
                        let b = w.get(content_pos, avail).map_err(io)?;
                        matches!(ChunkHeader::decode(b), Ok((h, off)) if h.compressed_size == clen - off as u64)
                    };
                    if as_chunk {
                        self.contents.notes.push(format!(
                            "the record at byte {pos} has opcode 0x{op:02x} but holds a chunk (a damaged opcode); it was read as the chunk"
                        ));
                        let k = self.add_chunk(&mut w, pos, clen, None)?;
                        after = After::Chunk(k);
                    } else {
                        let next_ok =
                            rec_end == end || self.frames(&mut w, rec_end, end, landing).is_some();
                        if op >= 0x80 && next_ok {
                            // A private record followed by a whole one.
                            after = After::Other;
                            any = true;
                            pos = rec_end;
                            continue;
                        }
                        let to = if next_ok {
                            rec_end
                        } else {
                            self.resync(&mut w, pos + 1, end, hints, landing)
                                .unwrap_or(end)
                        };
                        after = self.damaged(
                            &mut w,
                            pos,
                            to,
                            op,
                            "its opcode is not one the data section holds",
                        );
                        pos = to;
                        continue;
                    }
                }
            }
            any = true;
            pos = rec_end;
        }
        if !any {
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
        Ok(found_summary)
    }

    /// Records the bytes `pos..to` the walk could not read as records.
    fn damaged(&mut self, w: &mut Window, pos: u64, to: u64, op: u8, why: &str) -> After {
        let header = (op == Op::Chunk as u8)
            .then(|| {
                let avail = (to.saturating_sub(pos + RECORD_PREFIX)).min(4096) as usize;
                let b = w.get(pos + RECORD_PREFIX, avail).ok()?.to_vec();
                ChunkHeader::decode(&b).ok().map(|(h, _)| h)
            })
            .flatten();
        // What the stretch held: a chunk's stated records, bounded by what the rest of the
        // file can hold; else what its own bytes can hold.
        let stored = to.saturating_sub(pos);
        let rest = self.len.saturating_sub(pos);
        let bytes = match &header {
            Some(h) if h.compression.is_empty() => h.uncompressed_size.min(rest).max(stored),
            Some(h) => h
                .uncompressed_size
                .min(rest.saturating_mul(source::MAX_EXPANSION))
                .max(stored),
            None => stored.saturating_mul(source::MAX_EXPANSION),
        };
        self.lost.push(Lost {
            what: format!(
                "bytes {pos}..{to} could not be read as records (a {} record at byte {pos}: {why}); skipped",
                op_name(op)
            ),
            span: header.map(|h| (h.message_start_time, h.message_end_time)),
            bytes,
            indexes: Vec::new(),
        });
        After::Lost(self.lost.len() - 1)
    }

    /// Adds the chunk record at `pos` (content length `clen`) as a part; `from_index` gives
    /// the summary's fields when the record's own header is not to be trusted.
    fn add_chunk(
        &mut self,
        w: &mut Window,
        pos: u64,
        clen: u64,
        from_index: Option<&ChunkIndex>,
    ) -> Result<usize, Error> {
        let content_pos = pos + RECORD_PREFIX;
        let (h, off) = match from_index {
            None => {
                let avail = clen.min(4096) as usize;
                let b = w
                    .get(content_pos, avail)
                    .map_err(|e| Error::io(&self.path, e))?;
                ChunkHeader::decode(b).map_err(|e| Error::Corrupt {
                    path: self.path.clone(),
                    offset: pos,
                    what: e.to_string(),
                })?
            }
            Some(ci) => {
                // The header's own fields at their places; the CRC as stored (a damaged one
                // fails the chunk, it never passes damaged records).
                let b = w
                    .get(content_pos + 24, 4)
                    .map_err(|e| Error::io(&self.path, e))?;
                let crc = if b.len() == 4 {
                    u32::from_le_bytes(b.try_into().expect("4 bytes"))
                } else {
                    0
                };
                (
                    ChunkHeader {
                        message_start_time: ci.message_start_time,
                        message_end_time: ci.message_end_time,
                        uncompressed_size: ci.uncompressed_size,
                        uncompressed_crc: crc,
                        compression: ci.compression.clone(),
                        compressed_size: ci.compressed_size,
                    },
                    8 + 8 + 8 + 4 + 4 + ci.compression.len() + 8,
                )
            }
        };
        self.locs.push(Loc::Chunk {
            pos,
            records_pos: content_pos + off as u64,
            compressed_size: h.compressed_size,
            uncompressed_size: h.uncompressed_size,
            crc: h.uncompressed_crc,
            compression: h.compression.clone(),
        });
        self.indexes.push(Vec::new());
        self.contents.parts.push(Part {
            bytes: h
                .uncompressed_size
                .min(h.compressed_size.saturating_mul(source::MAX_EXPANSION)),
            label: format!("chunk at byte {pos}"),
            span: Some((h.message_start_time, h.message_end_time)),
            counts: None,
        });
        Ok(self.locs.len() - 1)
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
        self.indexes.push(Vec::new());
        self.contents.parts.push(Part {
            bytes: end - pos,
            label: format!("unchunked messages from byte {pos}"),
            span: t.map(|t| (t, t)),
            counts: None,
        });
    }

    /// Notes what the incomplete record at the end of the walk held.
    fn tail_lost(&mut self, w: &mut Window, pos: u64, end: u64, op: Option<u8>) {
        let what = match op {
            Some(op) => format!(
                "the last {} bytes of the file are an incomplete {} record (truncated file); skipped",
                end - pos,
                op_name(op)
            ),
            None => format!(
                "the last {} bytes of the file are an incomplete record (truncated file); skipped",
                end - pos
            ),
        };
        let header = (op == Some(Op::Chunk as u8))
            .then(|| {
                let avail = (end.saturating_sub(pos + RECORD_PREFIX)).min(4096) as usize;
                let b = w.get(pos + RECORD_PREFIX, avail).ok()?.to_vec();
                ChunkHeader::decode(&b).ok().map(|(h, _)| h)
            })
            .flatten();
        // What the incomplete record can have held: a chunk its stated records (bounded by
        // what its stored bytes decompress to), a message one.
        let (messages, at_most) = match (op, &header) {
            (Some(o), _) if o == Op::Message as u8 => (Some(1), None),
            (_, Some(h)) => {
                let bytes = if h.compression.is_empty() {
                    h.uncompressed_size.min(h.compressed_size)
                } else {
                    h.uncompressed_size
                        .min(h.compressed_size.saturating_mul(source::MAX_EXPANSION))
                };
                (None, Some(bytes / MIN_IMU_RECORD))
            }
            // A header cut short says nothing of the records after it.
            _ => (None, None),
        };
        self.contents.losses.push(Loss {
            what,
            messages,
            at_most,
            span: header.map(|h| (h.message_start_time, h.message_end_time)),
            ..Loss::default()
        });
    }

    /// Chunks the summary locates that the walk did not find (their record framing is
    /// damaged): read from the summary's fields when their bytes are in the file, counted
    /// from their Message Index records otherwise.
    fn chunks_from_summary(&mut self, chunk_indexes: &[ChunkIndex]) {
        let found: std::collections::BTreeSet<u64> = self
            .locs
            .iter()
            .filter_map(|l| match l {
                Loc::Chunk { pos, .. } => Some(*pos),
                Loc::Loose { .. } => None,
            })
            .collect();
        let Ok(file) = self.file.try_clone() else {
            return;
        };
        let mut w = Window {
            file: &file,
            len: self.len,
            buf: Vec::new(),
            at: 0,
        };
        for ci in chunk_indexes {
            let k = if found.contains(&ci.chunk_start_offset) {
                self.locs.iter().position(
                    |l| matches!(l, Loc::Chunk { pos, .. } if *pos == ci.chunk_start_offset),
                )
            } else {
                let fits = ci
                    .chunk_start_offset
                    .checked_add(ci.chunk_length)
                    .is_some_and(|e| e <= self.len)
                    && ci.chunk_length > RECORD_PREFIX;
                let added = fits
                    .then(|| {
                        self.add_chunk(
                            &mut w,
                            ci.chunk_start_offset,
                            ci.chunk_length - RECORD_PREFIX,
                            Some(ci),
                        )
                        .ok()
                    })
                    .flatten();
                if added.is_some() {
                    self.contents.notes.push(format!(
                        "the chunk at byte {} has a damaged record header; it was read where the summary locates it",
                        ci.chunk_start_offset
                    ));
                }
                added
            };
            // The summary's message indexes count the chunk when the walk found none.
            let indexes: Vec<IndexRef> = ci
                .message_index_offsets
                .iter()
                .filter_map(|&(ch, off)| {
                    let (op, clen) = w.prefix(off)?;
                    let b = w.get(off + RECORD_PREFIX, 6).ok()?;
                    (op == Op::MessageIndex as u8
                        && b.len() == 6
                        && u16::from_le_bytes([b[0], b[1]]) == ch)
                        .then(|| IndexRef {
                            channel: ch,
                            entries_pos: off + RECORD_PREFIX + 6,
                            count: (u32::from_le_bytes(b[2..6].try_into().expect("4 bytes"))
                                as u64)
                                .min(clen.saturating_sub(6))
                                / INDEX_ENTRY,
                        })
                })
                .collect();
            match k {
                Some(k) if self.indexes[k].is_empty() && !indexes.is_empty() => {
                    self.contents.parts[k].counts = Some(
                        indexes
                            .iter()
                            .map(|i| (i.channel as u32, i.count))
                            .collect(),
                    );
                    self.indexes[k] = indexes;
                }
                Some(_) => {}
                None => self.lost.push(Lost {
                    what: format!(
                        "the summary lists a chunk at byte {} that the data section does not hold",
                        ci.chunk_start_offset
                    ),
                    span: Some((ci.message_start_time, ci.message_end_time)),
                    bytes: ci
                        .uncompressed_size
                        .min(ci.compressed_size.saturating_mul(source::MAX_EXPANSION)),
                    indexes,
                }),
            }
        }
    }

    /// Turns each unreadable stretch into losses: per channel from the Message Index
    /// records that count it, else as many Imu messages as its bytes can hold.
    fn account_lost(&mut self) {
        for l in std::mem::take(&mut self.lost) {
            if l.indexes.is_empty() {
                self.contents.losses.push(Loss {
                    what: l.what,
                    at_most: Some(l.bytes / MIN_IMU_RECORD),
                    span: l.span,
                    ..Loss::default()
                });
                continue;
            }
            let mut per: BTreeMap<u16, (u64, u64, u64)> = BTreeMap::new();
            for ix in &l.indexes {
                let e = per.entry(ix.channel).or_insert((0, u64::MAX, 0));
                e.0 += ix.count;
                for (t, _) in self.entries(ix) {
                    e.1 = e.1.min(t);
                    e.2 = e.2.max(t);
                }
            }
            for (ch, (n, a, b)) in per {
                self.contents.losses.push(Loss {
                    what: l.what.clone(),
                    messages: Some(n),
                    span: (a <= b).then_some((a, b)).or(l.span),
                    channel: Some(ch as u32),
                    ..Loss::default()
                });
            }
        }
    }

    /// The `(log time, offset in the chunk's records)` entries of a Message Index record.
    fn entries(&self, ix: &IndexRef) -> Vec<(u64, u64)> {
        let n = ix.count.min(self.len / INDEX_ENTRY);
        let mut b = vec![0u8; (n * INDEX_ENTRY) as usize];
        if self.file.read_exact_at(&mut b, ix.entries_pos).is_err() {
            return Vec::new();
        }
        b.chunks_exact(INDEX_ENTRY as usize)
            .map(|e| {
                (
                    u64::from_le_bytes(e[..8].try_into().expect("8 bytes")),
                    u64::from_le_bytes(e[8..].try_into().expect("8 bytes")),
                )
            })
            .collect()
    }

    /// Schemas and channels may live only inside chunks: without a summary they are
    /// collected from every chunk; with one, from the chunks in order while a channel the
    /// message indexes name, or a channel's schema, is missing or damaged in it.
    fn complete_channels(&mut self) {
        let needed = |r: &McapReader| -> bool {
            r.mcap_channels.is_empty()
                || r.indexes
                    .iter()
                    .flatten()
                    .any(|i| !r.mcap_channels.contains_key(&i.channel))
                || r.mcap_channels.values().any(|c| {
                    !channel_plausible(c)
                        || (c.schema_id != 0
                            && !r.schemas.get(&c.schema_id).is_some_and(schema_plausible))
                })
        };
        for k in 0..self.locs.len() {
            if self.summary_used && !needed(self) {
                break;
            }
            if matches!(self.locs[k], Loc::Chunk { .. }) {
                self.collect_inner_channels(k);
            }
        }
    }

    /// Collects the schemas and channels inside part `loc`.
    fn collect_inner_channels(&mut self, loc: usize) {
        let mut found = Vec::new();
        let _ = self.with_records(
            loc,
            |_, op, content| {
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
            },
            &|| Vec::new(),
        );
        for (s, c) in found {
            if let Some(s) = s {
                offer(&mut self.schemas, s.id, s, schema_plausible);
            }
            if let Some(c) = c {
                offer(&mut self.mcap_channels, c.id, c, channel_plausible);
            }
        }
    }

    fn build_channels(&mut self) {
        // No count a file states exceeds the messages it can hold.
        let capacity = self.len / MIN_MESSAGE_RECORD;
        let stats: Option<BTreeMap<u16, u64>> = self.statistics.as_ref().map(|s| {
            s.channel_message_counts
                .iter()
                .map(|&(c, n)| (c, n.min(capacity)))
                .collect()
        });
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
                for l in &self.contents.losses {
                    if let (Some(c), Some(n)) = (l.channel, l.messages) {
                        *m.entry(c as u16).or_default() += n;
                    }
                }
                m
            });
        let mut notes = Vec::new();
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
                // A damaged encoding name in a ROS 2 file (profile `ros2`, a `ros2msg`
                // schema) is CDR, the one encoding rosbag2 writes.
                let encoding = if !channel_plausible(c)
                    && (self.header.profile == "ros2"
                        || schema.is_some_and(|s| s.encoding == "ros2msg"))
                {
                    notes.push(format!(
                        "the Channel record of '{}' names the encoding {:?} (damaged); read as cdr, the encoding of ROS 2 files",
                        crate::shared::cli::escape(&c.topic),
                        c.message_encoding
                    ));
                    Encoding::Cdr
                } else {
                    Encoding::from_name(&c.message_encoding)
                };
                source::Channel {
                    id: c.id as u32,
                    topic: c.topic.clone(),
                    msg_type: schema.map(|s| s.name.clone()).unwrap_or_default(),
                    encoding,
                    md5sum: c
                        .metadata
                        .iter()
                        .find(|(k, _)| k == "md5sum")
                        .map(|(_, v)| v.clone()),
                    count: count.map(|n| n.min(capacity)),
                }
            })
            .collect();
        self.contents.notes.extend(notes);
    }

    /// Calls `f(offset, opcode, content)` for each record of part `loc`, in order. A record
    /// whose framing is damaged is skipped to the next offset `listed()` gives (the chunk's
    /// message indexes, sorted), else ends the part with an error.
    fn with_records(
        &self,
        loc: usize,
        mut f: impl FnMut(u64, u8, &[u8]) -> Result<(), String>,
        listed: &dyn Fn() -> Vec<u64>,
    ) -> Result<Vec<(String, u64)>, String> {
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
                    ..
                } => {
                    if records_pos.saturating_add(*compressed_size) > self.len {
                        return Err("the chunk's records run past the end of the file".into());
                    }
                    raw.resize(*compressed_size as usize, 0);
                    self.file
                        .read_exact_at(raw, *records_pos)
                        .map_err(|e| e.to_string())?;
                    // A damaged size field must not fail records the CRC vouches for: the
                    // output is bounded by what the stored bytes decompress to (or the size
                    // stated, if larger), never preallocated.
                    let limit = (*uncompressed_size)
                        .max(compressed_size.saturating_mul(source::MAX_EXPANSION));
                    let records: &[u8] = match compression.as_str() {
                        "" => raw,
                        "lz4" => {
                            body.clear();
                            lz4_flex::frame::FrameDecoder::new(&raw[..])
                                .take(limit.saturating_add(1))
                                .read_to_end(body)
                                .map_err(|e| format!("lz4: {e}"))?;
                            body
                        }
                        "zstd" => {
                            crate::zstd::decompress_into(raw, body, limit)?;
                            body
                        }
                        other => return Err(format!("unsupported chunk compression '{other}'")),
                    };
                    let crc_ok = *crc != 0 && crc32fast::hash(records) == *crc;
                    // Without a CRC, the stored records of an uncompressed chunk are what
                    // its record length frames, whatever its size field says.
                    let framed = *crc == 0 && compression.is_empty();
                    if records.len() as u64 != *uncompressed_size && !crc_ok && !framed {
                        return Err(format!(
                            "chunk records are {} bytes, its header says {uncompressed_size}",
                            records.len()
                        ));
                    }
                    if *crc != 0 && !crc_ok {
                        return Err(format!(
                            "chunk CRC {:08x} differs from the stored {crc:08x}",
                            crc32fast::hash(records)
                        ));
                    }
                    records
                }
            };
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
                    Some((op, content, n)) if op != Op::Message as u8 || content.len() >= MESSAGE_FIXED_LEN => {
                        f(at as u64, op, content)?;
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
            Ok(damage)
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
                        return Ok(());
                    }
                    if want(ch as u32) {
                        let t = u64::from_le_bytes(content[6..14].try_into().expect("8 bytes"));
                        sink(ch as u32, t, &content[MESSAGE_FIXED_LEN..]);
                        out.delivered += 1;
                        delivered_at.push((ch, at));
                    }
                }
                Ok(())
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
            let why = if damage.is_empty() && no_channel > 0 {
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
            };
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
                out.lost.push(Loss {
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
            let what = format!(
                "{}: {}",
                self.contents.parts[part].label,
                damage
                    .iter()
                    .map(|d| d.0.as_str())
                    .collect::<Vec<_>>()
                    .join("; ")
            );
            if indexes.is_empty() {
                // Nothing counts what the skipped bytes held: as many Imu messages as fit.
                let bytes: u64 = damage.iter().map(|d| d.1).sum();
                out.lost.push(Loss {
                    what,
                    at_most: Some(bytes / MIN_IMU_RECORD),
                    ..Loss::default()
                });
            } else {
                // Every message the index lists was delivered: the damage cost none.
                out.notes.push(what);
            }
        }
        out
    }
}
