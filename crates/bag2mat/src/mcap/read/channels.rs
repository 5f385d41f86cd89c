//! An MCAP file's channels and what it lost: channels completed from the records inside
//! chunks, the per-channel counts of the Message Index records, and the losses accounted.

use super::*;
use crate::shared::note::Note;

impl McapReader {
    /// Turns each unreadable stretch into losses: per channel from the Message Index
    /// records that count it, else as many Imu messages as its bytes can hold.
    pub(super) fn account_lost(&mut self) {
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
    pub(super) fn entries(&self, ix: &IndexRef) -> Vec<(u64, u64)> {
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
    pub(super) fn complete_channels(&mut self) {
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
        // a summary without a CRC may be damaged unseen: the copies in the first chunk (its
        // CRC checked) win where they differ
        if self.summary_unchecked
            && let Some(k) = self
                .locs
                .iter()
                .position(|l| matches!(l, Loc::Chunk { .. }))
        {
            let (schemas, channels) = self.inner_channels(k);
            for s in schemas {
                if self.schemas.get(&s.id).is_some_and(|old| *old != s) {
                    self.contents.notes.push(Note::warning(format!(
                        "the summary's Schema record {} differs from the one in the first chunk (whose CRC holds): the chunk's is used",
                        s.id
                    )));
                }
                self.schemas.insert(s.id, s);
            }
            for c in channels {
                self.mcap_channels.insert(c.id, c);
            }
        }
        for k in 0..self.locs.len() {
            if self.summary_used && !needed(self) {
                break;
            }
            if matches!(self.locs[k], Loc::Chunk { .. }) {
                self.collect_inner_channels(k);
            }
        }
    }

    /// The schemas and channels inside part `loc` that decode.
    fn inner_channels(&self, loc: usize) -> (Vec<Schema>, Vec<record::Channel>) {
        let (mut schemas, mut channels) = (Vec::new(), Vec::new());
        let _ = self.with_records(
            loc,
            |_, op, content| match Op::from_byte(op) {
                Some(Op::Schema) => schemas.extend(Schema::decode(content).ok()),
                Some(Op::Channel) => channels.extend(record::Channel::decode(content).ok()),
                _ => {}
            },
            &|| Vec::new(),
        );
        (schemas, channels)
    }

    /// Collects the schemas and channels inside part `loc`.
    pub(super) fn collect_inner_channels(&mut self, loc: usize) {
        let mut found = Vec::new();
        let _ = self.with_records(
            loc,
            |_, op, content| match Op::from_byte(op) {
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

    pub(super) fn build_channels(&mut self) {
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
                    notes.push(Note::warning(format!(
                        "the Channel record of '{}' names the encoding {:?} (damaged); read as cdr, the encoding of ROS 2 files",
                        crate::printable::escape(&c.topic),
                        c.message_encoding
                    )));
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
}
