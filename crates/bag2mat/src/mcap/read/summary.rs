//! The summary section of an MCAP file: the footer, the summary records (schemas, channels,
//! statistics, chunk indexes; their CRC checked when stored) and the chunks they locate.

use super::*;
use crate::shared::note::Note;

/// Why the summary section cannot be used (the note says so, and the data section is
/// scanned instead).
#[derive(Debug, thiserror::Error)]
pub(super) enum SummaryError {
    #[error("its offsets {start}..{end} are outside the file")]
    Outside { start: u64, end: u64 },
    #[error("{0}")]
    Io(#[from] std::io::Error),
    #[error("{0}")]
    Record(#[from] CursorError),
}

impl McapReader {
    /// The footer and its offset, when the file ends with a footer record and the magic.
    pub(super) fn read_footer(&self) -> Option<(u64, Footer)> {
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
    pub(super) fn read_summary(
        &mut self,
        footer_pos: u64,
        f: &Footer,
    ) -> Result<Summary, SummaryError> {
        let end = if f.summary_offset_start != 0 {
            f.summary_offset_start
        } else {
            footer_pos
        };
        if f.summary_start < MAGIC.len() as u64 || f.summary_start > end || end > footer_pos {
            return Err(SummaryError::Outside {
                start: f.summary_start,
                end,
            });
        }
        let mut trusted = true;
        if f.summary_crc != 0 {
            // The CRC covers the summary and summary-offset sections and the footer up to
            // (not including) its CRC field.
            let mut b = vec![0u8; (footer_pos + RECORD_PREFIX + 16 - f.summary_start) as usize];
            self.file.read_exact_at(&mut b, f.summary_start)?;
            let crc = crc32fast::hash(&b);
            if crc != f.summary_crc {
                trusted = false;
                self.contents.notes.push(Note::warning(format!(
                    "the summary section is damaged (CRC {crc:08x} differs from the footer's {:08x}): its counts are not used, its chunk indexes only locate chunks",
                    f.summary_crc
                )));
            }
        }
        let mut b = vec![0u8; (end - f.summary_start) as usize];
        self.file.read_exact_at(&mut b, f.summary_start)?;
        let chunk_indexes = self.summary_records(&b, trusted)?;
        Ok(Summary {
            chunk_indexes,
            trusted,
        })
    }

    /// Parses summary records (schemas, channels, statistics, chunk indexes). Untrusted,
    /// a record that does not parse ends the section instead of failing it.
    pub(super) fn summary_records(
        &mut self,
        b: &[u8],
        trusted: bool,
    ) -> Result<Vec<ChunkIndex>, SummaryError> {
        let mut c = Cursor::new(b);
        let mut chunk_indexes = Vec::new();
        while c.pos() < b.len() {
            // Framing first: an untrusted summary skips a record whose content does not
            // parse, and ends at framing that does not hold.
            let framed = c.le::<u8>("opcode").and_then(|op| Ok((op, c.bytes64()?)));
            let (op, content) = match framed {
                Ok(x) => x,
                Err(e) if trusted => return Err(e.into()),
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
                return Err(e.into());
            }
        }
        Ok(chunk_indexes)
    }

    /// Chunks the summary locates that the walk did not find (their record framing is
    /// damaged): read from the summary's fields when their bytes are in the file, counted
    /// from their Message Index records otherwise.
    pub(super) fn chunks_from_summary(&mut self, chunk_indexes: &[ChunkIndex]) {
        // the chunks the walk found, by where their records lie
        let found: Vec<(u64, u64)> = self
            .locs
            .iter()
            .filter_map(|l| match l {
                Loc::Chunk {
                    pos,
                    records_pos,
                    compressed_size,
                    ..
                } => Some((*pos, records_pos.saturating_add(*compressed_size))),
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
        // the message index records the walk found after its chunks
        let attached: std::collections::BTreeSet<u64> = self
            .indexes
            .iter()
            .flatten()
            .map(|ix| ix.entries_pos - 6 - RECORD_PREFIX)
            .collect();
        for ci in chunk_indexes {
            let cs = ci.chunk_start_offset;
            let describes_found = ci
                .message_index_offsets
                .iter()
                .any(|(_, o)| attached.contains(o));
            if !found.iter().any(|&(a, _)| a == cs) && describes_found {
                // a chunk index whose offset is damaged: its message indexes follow a chunk
                // the walk read
                self.contents.notes.push(Note::warning(format!(
                    "the summary lists a chunk at byte {cs} whose message indexes follow another chunk (a damaged chunk index); ignored"
                )));
                continue;
            }
            if found.iter().any(|&(a, e)| a < cs && cs < e) {
                // a damaged chunk index pointing inside a chunk the walk read whole
                self.contents.notes.push(Note::warning(format!(
                    "the summary lists a chunk at byte {cs}, inside a chunk the data section holds whole (a damaged chunk index); ignored"
                )));
                continue;
            }
            let k = if found.iter().any(|&(a, _)| a == cs) {
                self.locs
                    .iter()
                    .position(|l| matches!(l, Loc::Chunk { pos, .. } if *pos == cs))
            } else {
                self.summary_chunk(&mut w, ci)
            };
            // The summary's message indexes count the chunk when the walk found none.
            let indexes = summary_indexes(&mut w, ci);
            if k.is_some() && !found.iter().any(|&(a, _)| a == cs) {
                // the stretch the walk could not read because of this chunk's damaged record
                // header (with the message indexes after it, which count it) is this chunk,
                // read now: not lost
                let record = |ix: &IndexRef| ix.entries_pos - 6 - RECORD_PREFIX;
                let mine: Vec<u64> = ci.message_index_offsets.iter().map(|x| x.1).collect();
                let next = chunk_indexes
                    .iter()
                    .map(|c| c.chunk_start_offset)
                    .filter(|&o| o > cs)
                    .min()
                    .unwrap_or(self.len);
                self.lost.retain_mut(|l| {
                    let had = l.indexes.len();
                    l.indexes.retain(|ix| !mine.contains(&record(ix)));
                    let explained = (had > 0 && l.indexes.is_empty())
                        || (had == 0 && (cs..next).contains(&l.range.0));
                    !explained
                });
            }
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
                    range: (cs, cs.saturating_add(ci.chunk_length)),
                    what: format!(
                        "the summary lists a chunk at byte {cs} that the data section does not hold"
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

    /// A chunk the summary locates where the walk found none (its record header is
    /// damaged): added as a part, with the summary's fields, when it fits in the file.
    fn summary_chunk(&mut self, w: &mut Window, ci: &ChunkIndex) -> Option<usize> {
        let fits = ci
            .chunk_start_offset
            .checked_add(ci.chunk_length)
            .is_some_and(|e| e <= self.len)
            && ci.chunk_length > RECORD_PREFIX;
        let added = fits
            .then(|| {
                self.add_chunk(
                    w,
                    ci.chunk_start_offset,
                    ci.chunk_length - RECORD_PREFIX,
                    Some(ci),
                )
                .ok()
            })
            .flatten();
        if added.is_some() {
            self.contents.notes.push(Note::warning(format!(
                "the chunk at byte {} has a damaged record header; it was read where the summary locates it",
                ci.chunk_start_offset
            )));
        }
        added
    }
}

/// The summary's message indexes of chunk `ci` that frame as such records.
fn summary_indexes(w: &mut Window, ci: &ChunkIndex) -> Vec<IndexRef> {
    ci.message_index_offsets
        .iter()
        .filter_map(|&(ch, off)| {
            let (op, clen) = w.prefix(off)?;
            let b = w.get(off + RECORD_PREFIX, 6).ok()?;
            (op == Op::MessageIndex as u8 && b.len() == 6 && u16::from_le_bytes([b[0], b[1]]) == ch)
                .then(|| IndexRef {
                    channel: ch,
                    entries_pos: off + RECORD_PREFIX + 6,
                    count: (u32::from_le_bytes(b[2..6].try_into().expect("4 bytes")) as u64)
                        .min(clen.saturating_sub(6))
                        / INDEX_ENTRY,
                })
        })
        .collect()
}
