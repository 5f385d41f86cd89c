//! A ROS 1 bag's chunks read: the body decompressed, its records walked (resynchronised past
//! damage), the messages handed on with their connection and time.

use super::*;

/// A chunk record whose header does not parse: the part's error says so by its kind.
impl From<RecordError> for Ros1ChunkError {
    fn from(e: RecordError) -> Ros1ChunkError {
        Ros1ChunkError::RecordHeader(std::sync::Arc::new(e))
    }
}

impl BagReader {
    /// Reads and decompresses the chunk whose record starts at `pos`, and hands its body to
    /// `f`. The raw and decompressed bytes live in per-thread buffers reused from chunk to
    /// chunk: a 4 h bag is ~1300 chunks, and fresh zeroed buffers cost more than the parsing.
    pub(super) fn with_chunk_body<R>(
        &self,
        pos: u64,
        f: impl FnOnce(&[u8]) -> R,
    ) -> Result<R, Ros1ChunkError> {
        let (h, data_pos, dlen) = self
            .record_at(pos, self.len)
            .ok_or(Ros1ChunkError::PastEnd)?;
        BUFFERS.with(|cell| {
            let mut bufs = cell.borrow_mut();
            let (raw, body) = &mut *bufs;
            let compression = self.read_chunk_into(&h, data_pos, dlen, raw, body)?;
            Ok(if compression == Compression::None {
                f(raw)
            } else {
                f(body)
            })
        })
    }

    /// Reads the chunk data into `raw` and, when compressed, decompresses it into `body`.
    pub(super) fn read_chunk_into(
        &self,
        h_bytes: &[u8],
        data_pos: u64,
        dlen: u32,
        raw: &mut Vec<u8>,
        body: &mut Vec<u8>,
    ) -> Result<Compression, Ros1ChunkError> {
        let h = Header::parse(h_bytes)?;
        if h.op()? != Op::Chunk {
            return Err(Ros1ChunkError::NotChunk);
        }
        let ChunkHeader { compression, size } = ChunkHeader::decode(&h)?;
        let size = size as usize;
        raw.resize(dlen as usize, 0);
        self.file
            .read_exact_at(raw, data_pos)
            .map_err(|e| Ros1ChunkError::Io(e.into()))?;
        body.clear();
        let got = match compression {
            Compression::None => raw.len(),
            Compression::Bz2 => bzip2::read::BzDecoder::new(&raw[..])
                .take(size as u64 + 1)
                .read_to_end(body)
                .map_err(|source| Ros1ChunkError::Decompress {
                    codec: "bz2",
                    source: source.into(),
                })?,
            Compression::Lz4 => lz4_flex::frame::FrameDecoder::new(&raw[..])
                .take(size as u64 + 1)
                .read_to_end(body)
                .map_err(|source| Ros1ChunkError::Decompress {
                    codec: "lz4",
                    source: source.into(),
                })?,
        };
        if got != size {
            return Err(Ros1ChunkError::Size { got, size });
        }
        Ok(compression)
    }

    /// Calls `f(connection, record time, data)` for each message record of chunk `c` whose
    /// connection `want` accepts, in body order, and reports what the chunk's index lists
    /// that could not be delivered.
    pub(super) fn for_each_in_chunk(
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
        });
        if let Err(e) = r {
            out.error = Some(e.into());
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
    pub(super) fn index_entries(&self, c: &ChunkLoc) -> Vec<(u32, u64, u32)> {
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
    pub(super) fn time_span(&self, c: &ChunkLoc) -> Option<(u64, u64)> {
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
}

/// A whole record inside a chunk body, as [`walk_body`] hands it out.
pub(super) enum BodyRecord<'a> {
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
pub(super) fn walk_body<'a>(
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
pub(super) fn parse_body_record(body: &[u8], pos: usize) -> Option<usize> {
    let r = record::raw_record(body, pos)?;
    match record::op_conn_time(r.header).ok()? {
        (Some(op), Some(_), Some(_)) if op == Op::MessageData as u8 => Some(r.end),
        (Some(op), Some(_), _) if op == Op::Connection as u8 => Some(r.end),
        _ => None,
    }
}

/// The next offset at or after `from` where a whole message or connection record starts
/// and is followed by another whole record (or the end of the body).
pub(super) fn resync(body: &[u8], from: usize) -> Option<usize> {
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
pub(super) fn find(hay: &[u8], needle: &[u8]) -> Option<usize> {
    hay.windows(needle.len()).position(|w| w == needle)
}
