//! The walk over an MCAP file's top-level records: chunks and runs of loose messages become
//! parts, damage is passed to the next whole record and counted, a cut end is read to its
//! last complete record.

use super::*;
use crate::shared::note::Note;

/// A top-level record the walk met: where, its opcode, and the content length it states.
#[derive(Clone, Copy)]
struct Rec {
    pos: u64,
    op: u8,
    clen: u64,
    content_pos: u64,
}

/// Where the walk goes after a record.
enum Flow {
    /// On to this position, the record read.
    Read(u64),
    /// On to this position past bytes that were not read as records.
    Skip(u64),
    /// No further record can be read.
    Stop,
    /// The end of the data section: the rest is the summary.
    DataEnd,
}

/// What the walk carries from record to record.
struct Walk<'h> {
    /// The end of what is walked.
    end: u64,
    /// Chunk positions the summary gives, for resynchronising.
    hints: &'h [u64],
    /// What a resynchronisation may land on (loose records only in an unchunked file).
    landing: Landing,
    /// What the last record was (a Message Index belongs to the chunk before it).
    after: After,
    /// A record was read.
    any: bool,
    seen_data_end: bool,
    /// Summary records found past a Data End when the summary was not used.
    found_summary: Option<Summary>,
}

impl McapReader {
    /// The end of the record at `pos` when it frames as a top-level record a walk may land
    /// on (see [`Landing`]) and its content checks out for its opcode.
    pub(super) fn frames(
        &self,
        w: &mut Window,
        pos: u64,
        end: u64,
        landing: Landing,
    ) -> Option<u64> {
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
    pub(super) fn resync(
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
    pub(super) fn walk(&mut self, end: u64, hints: &[u64]) -> Result<Option<Summary>, Error> {
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
        let mut st = Walk {
            end,
            hints,
            landing: Landing::Unchunked,
            after: After::Other,
            any: false,
            seen_data_end: false,
            found_summary: None,
        };
        let mut pos = MAGIC.len() as u64;
        let mut first = true;
        while pos < end {
            st.landing = if self.locs.iter().any(|l| matches!(l, Loc::Chunk { .. })) {
                Landing::Chunked
            } else {
                Landing::Unchunked
            };
            let Some((op, clen)) = w.prefix(pos) else {
                self.tail_lost(&mut w, pos, end, None);
                break;
            };
            let rec = Rec {
                pos,
                op,
                clen,
                content_pos: pos + RECORD_PREFIX,
            };
            let flow = match rec.content_pos.checked_add(clen).filter(|&e| e <= end) {
                None => self.overlong(&mut w, rec, &mut st)?,
                Some(rec_end) => {
                    if first && op != Op::Header as u8 {
                        // The Header only names the profile and library: its damage costs
                        // nothing.
                        self.contents.notes.push(Note::warning(format!(
                            "the first record (byte {pos}) is not an MCAP Header; the records after the magic were read anyway"
                        )));
                    }
                    first = false;
                    self.record(&mut w, rec, rec_end, &mut st)?
                }
            };
            match flow {
                Flow::Read(next) => {
                    st.any = true;
                    pos = next;
                }
                Flow::Skip(next) => pos = next,
                Flow::Stop => break,
                Flow::DataEnd => {
                    st.any = true;
                    pos = end;
                    break;
                }
            }
        }
        if !st.any {
            return Err(Error::Corrupt {
                path: self.path.clone(),
                offset: pos,
                what: "the MCAP file holds no complete record after its magic (truncated)".into(),
            });
        }
        if !st.seen_data_end && pos >= end && self.summary_used {
            self.contents.notes.push(Note::warning(
                "the data section has no Data End record".to_string(),
            ));
        }
        Ok(st.found_summary)
    }

    /// A record whose length runs past the end: truncation, or a damaged length with
    /// records after. A chunk's own records are never landed on (they frame as loose ones).
    fn overlong(&mut self, w: &mut Window, rec: Rec, st: &mut Walk) -> Result<Flow, Error> {
        let Rec {
            pos,
            op,
            content_pos,
            ..
        } = rec;
        let end = st.end;
        let is_chunk = op == Op::Chunk as u8
            && w.get(content_pos, (end - content_pos).min(4096) as usize)
                .ok()
                .is_some_and(|b| ChunkHeader::decode(b).is_ok());
        if is_chunk && let Some(e) = self.chunk_by_size(w, pos, st) {
            // a chunk whose record length is damaged: its header's size frames it
            let k = self.add_chunk(w, pos, e - content_pos, None)?;
            self.contents.notes.push(Note::warning(format!(
                "the chunk at byte {pos} has a damaged record length; it was read as its header's size frames it"
            )));
            st.after = After::Chunk(k);
            return Ok(Flow::Read(e));
        }
        let landing = if is_chunk {
            Landing::Chunked
        } else {
            st.landing
        };
        Ok(match self.resync(w, pos + 1, end, st.hints, landing) {
            Some(next) => {
                st.after =
                    self.damaged(w, pos, next, op, "its length runs past the end of the file");
                Flow::Skip(next)
            }
            None => {
                self.tail_lost(w, pos, end, Some(op));
                Flow::Stop
            }
        })
    }

    /// A whole record (content up to `rec_end`): what it adds, and where the walk goes on.
    fn record(
        &mut self,
        w: &mut Window,
        rec: Rec,
        rec_end: u64,
        st: &mut Walk,
    ) -> Result<Flow, Error> {
        let Rec {
            pos,
            op,
            clen,
            content_pos,
        } = rec;
        // a chunk whose opcode is damaged into another one's (a message index, a message):
        // its stored length and compression frame it as a chunk, which its CRC checks
        if op != Op::Chunk as u8 && chunk_header(w, content_pos, clen).is_some() {
            self.contents.notes.push(Note::warning(format!(
                "the record at byte {pos} has opcode 0x{op:02x} but holds a chunk (a damaged opcode); it was read as the chunk"
            )));
            let k = self.add_chunk(w, pos, clen, None)?;
            st.after = After::Chunk(k);
            return Ok(Flow::Read(rec_end));
        }
        // a record (but a chunk, its message indexes and the section's end) whose length is
        // damaged but still inside the file: what follows it is no record, and the records
        // it swallowed (chunks) are found by walking on from its start
        let lands = |r: &Self, w: &mut Window| {
            rec_end == st.end || r.frames(w, rec_end, st.end, st.landing).is_some()
        };
        if matches!(
            Op::from_byte(op),
            Some(
                Op::Header | Op::Schema | Op::Channel | Op::Message | Op::Attachment | Op::Metadata
            )
        ) && !lands(self, w)
            && let Some(next) = self.resync(w, pos + 1, st.end, st.hints, st.landing)
            && next < rec_end
        {
            st.after = self.damaged(w, pos, next, op, "its length runs past the next record");
            return Ok(Flow::Skip(next));
        }
        match Op::from_byte(op) {
            Some(Op::Header) if pos == MAGIC.len() as u64 => {
                match self.small(w, rec)?.map(|b| Header::decode(&b)) {
                    Some(Ok(h)) => self.header = h,
                    _ => self.contents.notes.push(Note::warning(format!(
                        "the MCAP Header record at byte {pos} is damaged; the records after it were read anyway"
                    ))),
                }
                st.after = After::Other;
            }
            Some(Op::Schema) => {
                if let Some(Ok(s)) = self.small(w, rec)?.map(|b| Schema::decode(&b)) {
                    offer(&mut self.schemas, s.id, s, schema_plausible);
                } else {
                    self.contents.notes.push(Note::warning(format!(
                        "unreadable Schema record at byte {pos} skipped"
                    )));
                }
                st.after = After::Other;
            }
            Some(Op::Channel) => {
                if let Some(Ok(c)) = self.small(w, rec)?.map(|b| record::Channel::decode(&b)) {
                    offer(&mut self.mcap_channels, c.id, c, channel_plausible);
                } else {
                    self.contents.notes.push(Note::warning(format!(
                        "unreadable Channel record at byte {pos} skipped"
                    )));
                }
                st.after = After::Other;
            }
            Some(Op::Chunk) => {
                // Its stored length and compression frame it (its times may be damaged).
                if chunk_header(w, content_pos, clen).is_some() {
                    let k = self.add_chunk(w, pos, clen, None)?;
                    st.after = After::Chunk(k);
                } else if lands(self, w)
                    && let Some(k) = self.chunk_by_record(w, pos, clen)?
                {
                    // its header's size field is damaged: the record, which the next one
                    // follows, frames its stored records (its CRC checks them)
                    self.contents.notes.push(Note::warning(format!(
                        "the chunk at byte {pos} has a damaged size field; its records were read as its record frames them"
                    )));
                    st.after = After::Chunk(k);
                } else if let Some(e) = self.chunk_by_size(w, pos, st) {
                    // its record length is damaged: its header's size frames it
                    let k = self.add_chunk(w, pos, e - content_pos, None)?;
                    self.contents.notes.push(Note::warning(format!(
                        "the chunk at byte {pos} has a damaged record length; it was read as its header's size frames it"
                    )));
                    st.after = After::Chunk(k);
                    return Ok(Flow::Read(e));
                } else {
                    let next = self.resync(w, pos + 1, st.end, st.hints, st.landing);
                    let to = next.unwrap_or(st.end);
                    st.after = self.damaged(w, pos, to, op, "its header is damaged");
                    return Ok(Flow::Skip(to));
                }
            }
            Some(Op::MessageIndex) => {
                if !self.message_index(w, rec, st.after)? {
                    st.after = self.damaged(
                        w,
                        pos,
                        rec_end,
                        op,
                        "its entries do not index the chunk before it",
                    );
                    return Ok(Flow::Skip(rec_end));
                }
            }
            Some(Op::Message) => {
                let b = w
                    .get(content_pos, MESSAGE_FIXED_LEN.min(clen as usize))
                    .map_err(|e| Error::io(&self.path, e))?;
                let t = (b.len() == MESSAGE_FIXED_LEN)
                    .then(|| u64::from_le_bytes(b[6..14].try_into().expect("8 bytes")));
                self.add_loose(pos, rec_end, t);
                st.after = After::Other;
            }
            Some(Op::Attachment | Op::Metadata) => st.after = After::Other,
            Some(end_op @ (Op::DataEnd | Op::Footer))
                if clen
                    == if end_op == Op::DataEnd {
                        4
                    } else {
                        FOOTER_CONTENT_LEN
                    } =>
            {
                return Ok(self.section_end(w, rec, rec_end, st));
            }
            Some(_) | None => return self.odd_record(w, rec, rec_end, st),
        }
        Ok(Flow::Read(rec_end))
    }

    /// The content of a metadata record (schema, channel, header) small enough to hold.
    fn small(&self, w: &mut Window, rec: Rec) -> Result<Option<Vec<u8>>, Error> {
        if rec.clen > MAX_META_RECORD {
            return Ok(None);
        }
        Ok(Some(
            w.get(rec.content_pos, rec.clen as usize)
                .map_err(|e| Error::io(&self.path, e))?
                .to_vec(),
        ))
    }

    /// A Message Index record: its entries belong to the chunk (or lost stretch) before it.
    /// False when its entries cannot index the chunk before it (offsets past its records,
    /// times outside its span): the record is damage (a chunk whose opcode and header are
    /// damaged), not that chunk's index.
    fn message_index(&mut self, w: &mut Window, rec: Rec, after: After) -> Result<bool, Error> {
        let Rec {
            clen, content_pos, ..
        } = rec;
        let b = w
            .get(content_pos, 6.min(clen as usize))
            .map_err(|e| Error::io(&self.path, e))?
            .to_vec();
        if b.len() == 6 {
            let channel = u16::from_le_bytes([b[0], b[1]]);
            let stated = u32::from_le_bytes(b[2..6].try_into().expect("4 bytes")) as u64;
            // A damaged length counts no more entries than the record holds.
            let count = stated.min(clen.saturating_sub(6)) / INDEX_ENTRY;
            let ix = IndexRef {
                channel,
                entries_pos: content_pos + 6,
                count,
            };
            match after {
                After::Chunk(k) => {
                    if !self.indexes_chunk(k, &ix) {
                        return Ok(false);
                    }
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
        Ok(true)
    }

    /// True when the entries of `ix` may index chunk part `k`: each offset inside its
    /// records and each time inside its span.
    fn indexes_chunk(&self, k: usize, ix: &IndexRef) -> bool {
        let Some(Loc::Chunk {
            uncompressed_size,
            compressed_size,
            compression,
            ..
        }) = self.locs.get(k)
        else {
            return true;
        };
        let size = if compression.is_empty() {
            *uncompressed_size.max(compressed_size)
        } else {
            *uncompressed_size
        };
        let span = self.contents.parts[k].span;
        self.entries(ix)
            .iter()
            .all(|&(t, off)| off < size && span.is_none_or(|(a, b)| a > b || (a..=b).contains(&t)))
    }

    /// A Data End or Footer record of its length: the end of the data section, unless
    /// data-section records follow it (its opcode is damaged).
    fn section_end(&mut self, w: &mut Window, rec: Rec, rec_end: u64, st: &mut Walk) -> Flow {
        let Rec { pos, op, .. } = rec;
        let end = st.end;
        let data_follows = rec_end < end
            && self.frames(w, rec_end, end, st.landing).is_some_and(|_| {
                w.prefix(rec_end).is_some_and(|(o, _)| {
                    matches!(
                        Op::from_byte(o),
                        Some(Op::Chunk | Op::MessageIndex | Op::Message)
                    )
                })
            });
        if data_follows {
            self.contents.notes.push(Note::warning(format!(
                "a {} record at byte {pos} stands in the middle of the data section (a damaged opcode?); the records after it were read",
                op_name(op)
            )));
            st.after = After::Other;
            return Flow::Read(rec_end);
        }
        st.seen_data_end = op == Op::DataEnd as u8;
        if !self.summary_used && rec_end < end {
            // A file cut in its summary section still holds summary records.
            let mut b = vec![0u8; (end - rec_end).min(MAX_META_RECORD) as usize];
            if self.file.read_exact_at(&mut b, rec_end).is_ok()
                && let Ok(ci) = self.summary_records(&b, false)
            {
                self.statistics = None;
                st.found_summary = Some(Summary {
                    chunk_indexes: ci,
                    trusted: false,
                });
            }
        }
        Flow::DataEnd
    }

    /// An opcode the data section does not hold (or a Data End or Footer opcode on a record
    /// of another length). A chunk whose opcode is damaged is still read (its CRC checks
    /// it); private records (0x80 and up) are skipped; anything else is damage, counted.
    fn odd_record(
        &mut self,
        w: &mut Window,
        rec: Rec,
        rec_end: u64,
        st: &mut Walk,
    ) -> Result<Flow, Error> {
        let Rec {
            pos,
            op,
            clen,
            content_pos,
        } = rec;
        let end = st.end;
        let as_chunk = {
            let avail = clen.min(4096) as usize;
            let b = w
                .get(content_pos, avail)
                .map_err(|e| Error::io(&self.path, e))?;
            matches!(ChunkHeader::decode(b), Ok((h, off)) if h.compressed_size == clen - off as u64)
        };
        if as_chunk {
            self.contents.notes.push(Note::warning(format!(
                "the record at byte {pos} has opcode 0x{op:02x} but holds a chunk (a damaged opcode); it was read as the chunk"
            )));
            let k = self.add_chunk(w, pos, clen, None)?;
            st.after = After::Chunk(k);
            return Ok(Flow::Read(rec_end));
        }
        let next_ok = rec_end == end || self.frames(w, rec_end, end, st.landing).is_some();
        if op >= 0x80 && next_ok {
            // A private record followed by a whole one.
            st.after = After::Other;
            return Ok(Flow::Read(rec_end));
        }
        let to = if next_ok {
            rec_end
        } else {
            self.resync(w, pos + 1, end, st.hints, st.landing)
                .unwrap_or(end)
        };
        st.after = self.damaged(
            w,
            pos,
            to,
            op,
            "its opcode is not one the data section holds",
        );
        Ok(Flow::Skip(to))
    }

    /// Records the bytes `pos..to` the walk could not read as records.
    pub(super) fn damaged(
        &mut self,
        w: &mut Window,
        pos: u64,
        to: u64,
        op: u8,
        why: &str,
    ) -> After {
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
            range: (pos, to),
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

    /// The end of the chunk record at `pos` as its header's compressed size frames it, when
    /// a whole record (or the end) follows there and its compression is one read here.
    fn chunk_by_size(&self, w: &mut Window, pos: u64, st: &Walk) -> Option<u64> {
        let content_pos = pos + RECORD_PREFIX;
        let avail = st.end.saturating_sub(content_pos).min(4096) as usize;
        let b = w.get(content_pos, avail).ok()?;
        let (h, off) = ChunkHeader::decode(b).ok()?;
        if !["", "lz4", "zstd"].contains(&h.compression.as_str()) {
            return None;
        }
        let e = (content_pos + off as u64).checked_add(h.compressed_size)?;
        (e <= st.end && (e == st.end || self.frames(w, e, st.end, Landing::Chunked).is_some()))
            .then_some(e)
    }

    /// Adds the chunk record at `pos` (content length `clen`) whose header's compressed
    /// size disagrees with the record's length, reading the records the record holds
    /// (when its compression is one read here).
    fn chunk_by_record(
        &mut self,
        w: &mut Window,
        pos: u64,
        clen: u64,
    ) -> Result<Option<usize>, Error> {
        let content_pos = pos + RECORD_PREFIX;
        let b = w
            .get(content_pos, clen.min(4096) as usize)
            .map_err(|e| Error::io(&self.path, e))?;
        let Ok((h, off)) = ChunkHeader::decode(b) else {
            return Ok(None);
        };
        if !["", "lz4", "zstd"].contains(&h.compression.as_str()) || (off as u64) > clen {
            return Ok(None);
        }
        let k = self.add_chunk(w, pos, clen, None)?;
        if let Some(Loc::Chunk {
            compressed_size, ..
        }) = self.locs.get_mut(k)
        {
            *compressed_size = clen - off as u64;
        }
        Ok(Some(k))
    }

    /// Adds the chunk record at `pos` (content length `clen`) as a part; `from_index` gives
    /// the summary's fields when the record's own header is not to be trusted.
    pub(super) fn add_chunk(
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
    pub(super) fn add_loose(&mut self, pos: u64, end: u64, t: Option<u64>) {
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
    pub(super) fn tail_lost(&mut self, w: &mut Window, pos: u64, end: u64, op: Option<u8>) {
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
}
