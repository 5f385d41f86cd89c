//! The layout of a ROS 1 bag: its index section, the walk over its top-level records (damage
//! passed and counted), and the two joined, with a note wherever they disagree.

use super::*;
use crate::shared::note::Note;

impl BagReader {
    /// Reads the index section record by record: connections and chunk infos. A damaged
    /// record is skipped (noted); damaged framing ends the section (the walk still finds
    /// every chunk).
    pub(super) fn read_index(&mut self, index_pos: u64) -> (Vec<Connection>, Vec<ChunkInfo>) {
        let mut connections = Vec::new();
        let mut infos = Vec::new();
        let mut pos = index_pos;
        let mut damaged = 0;
        while pos < self.len {
            let Some((hb, data_pos, dlen)) = self.record_at(pos, self.len) else {
                self.contents.notes.push(Note::warning(format!(
                    "the index section is damaged at byte {pos} (a record runs past the end of the file); the chunks were walked instead"
                )));
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
                    self.contents.notes.push(Note::warning(format!(
                        "the index section has a damaged record at byte {pos} ({e}); skipped, the chunks themselves were walked"
                    )));
                }
            }
            pos = data_pos + dlen as u64;
        }
        if damaged > 1 {
            self.contents.notes.push(Note::warning(format!(
                "{damaged} damaged index records were skipped in all"
            )));
        }
        (connections, infos)
    }

    /// Walks the chunk section from `first` to `end`: chunk records (header only), the
    /// index-data records after each, and stray connection records. Stops at the index
    /// section or an incomplete record; after a damaged record, resumes at the next chunk.
    pub(super) fn walk(&mut self, first: u64, end: u64, info_positions: &BTreeSet<u64>) -> Walk {
        let mut w = Walk::default();
        let mut pos = first;
        while pos < end {
            let Some((hb, data_pos, dlen)) = self.record_at(pos, end) else {
                if end == self.len {
                    self.truncated_tail(pos);
                    break;
                }
                self.damaged_at(
                    pos,
                    end,
                    "a record runs past the end of the chunk section",
                    info_positions,
                    &mut pos,
                );
                continue;
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
                Ok(op @ (Op::Chunk | Op::IndexData | Op::Connection)) => {
                    if let Err(why) = self.top_record(&mut w, op, &h, pos, data_pos, dlen) {
                        self.damaged_at(pos, end, why, info_positions, &mut pos);
                        continue;
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

    /// The incomplete record the file ends with (a truncated bag), as a loss.
    fn truncated_tail(&mut self, pos: u64) {
        let at_most = self.tail_capacity(pos);
        self.contents.losses.push(Loss {
            at_most,
            ..Loss::new(format!(
                "the last {} bytes of the file are an incomplete record (truncated bag); they were skipped",
                self.len - pos
            ))
        });
    }

    /// A chunk, index data or connection record at `pos` (data at `data_pos`, `dlen`
    /// bytes) the walk met: what it adds, or why the record is damaged.
    fn top_record(
        &mut self,
        w: &mut Walk,
        op: Op,
        h: &Header,
        pos: u64,
        data_pos: u64,
        dlen: u32,
    ) -> Result<(), &'static str> {
        match op {
            Op::Chunk => {
                let Ok(chunk) = ChunkHeader::decode(h) else {
                    return Err("damaged chunk header");
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
            Op::IndexData => {
                if let (Some(c), Ok(ix)) = (w.chunks.last_mut(), IndexData::decode(h)) {
                    // The entries the file holds, whatever the count field says.
                    let count = (ix.count.unwrap_or(u32::MAX) as u64)
                        .min(dlen as u64 / INDEX_ENTRY_LEN as u64);
                    c.index_data
                        .entry(ix.conn)
                        .or_insert(ChunkIndexData { count, data_pos });
                }
            }
            Op::Connection => {
                if let Ok(data) = self.bytes_at(data_pos, dlen)
                    && let Ok(c) = Connection::decode(h, &data)
                {
                    w.connections.push(c);
                }
            }
            _ => {}
        }
        Ok(())
    }

    /// Records a damaged top-level record at `*pos` and moves `*pos` to the next chunk: the
    /// next position a chunk info names, else the next valid chunk record found in the bytes.
    pub(super) fn damaged_at(
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
    pub(super) fn find_chunk(&self, from: u64, end: u64) -> Option<u64> {
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
    pub(super) fn merge(
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
            self.contents.notes.push(Note::warning(format!(
                "{} chunk(s) are not listed in the bag's index (first at byte {}); they were read",
                unlisted.len(),
                unlisted.iter().next().copied().unwrap_or(0)
            )));
        }
        if let Some(n) = chunk_count
            && had_index
            && n as usize != chunks.len()
        {
            self.contents.notes.push(Note::warning(format!(
                "the bag header announces {n} chunks; {} were found",
                chunks.len()
            )));
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
    pub(super) fn join_chunk_infos(
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
                        self.contents.notes.push(Note::warning(format!(
                            "the chunk info of the chunk at byte {} lists {:?} messages per connection, the chunk's own index {:?}; the chunk is read whole and its own index is used",
                            info.chunk_pos,
                            mine,
                            own.unwrap_or_default()
                        )));
                    }
                    c.info_counts = Some(info.counts);
                    c.span = Some((info.start_time, info.end_time));
                }
                Some(_) => self.contents.notes.push(Note::warning(format!(
                    "two chunk infos name the chunk at byte {}; the chunk is read once",
                    info.chunk_pos
                ))),
                None => self.unwalked_chunk(chunks, info),
            }
        }
        unlisted
    }

    /// A chunk the index lists and the walk did not reach (it stopped early): read if it is
    /// a chunk, else a loss of the messages its info counts.
    pub(super) fn unwalked_chunk(&mut self, chunks: &mut BTreeMap<u64, ChunkLoc>, info: ChunkInfo) {
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
    pub(super) fn scan_chunks(
        &mut self,
        connections: &mut BTreeMap<u32, Connection>,
        had_index: bool,
    ) {
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
}
