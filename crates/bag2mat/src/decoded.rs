//! Logs whose readers decode the samples themselves (text, NumPy, PX4 ULog, ArduPilot
//! DataFlash): their rows reach the one read path ([`crate::series`]) as payloads of one
//! fixed layout, [`Row`], on channels of encoding [`Encoding::Row`] (handed over as they are
//! through [`source::Source::read_part_rows`], or as payload bytes), so the topic rules,
//! sorting, progress and loss accounting stay written once.
//!
//! Such a reader parses its file when it opens (the formats have no index to plan by) into
//! one [`Stream`] per topic and hands them to [`DecodedSource`], which serves them in parts of
//! at most [`PART_ROWS`] messages with exact counts. Topics the tools do not read as Imu keep
//! only their log times (for `bag2mat info`) and deliver empty payloads.

use crate::rows::{ROW_LEN, Row, Rows};
use crate::source::{self, Channel, Contents, Encoding, InputKind, Loss, MessageSink, Part};

/// Messages per part (a part is the unit of parallel decoding and of the progress bar).
pub const PART_ROWS: usize = 1 << 16;

/// One topic's messages (or a piece of them): their log (record) times and, for an Imu
/// topic, their rows, kept as the columns the read path delivers ([`crate::series`]), so a
/// reader that decoded a whole topic hands them over without a copy.
#[derive(Debug, Clone, Default)]
pub struct Stream {
    /// Topic name.
    pub topic: String,
    /// Type as the format names it (`px4/sensor_combined`, `ardupilot/IMU`, `text/imu`).
    pub msg_type: String,
    /// True when its messages are rows (an Imu topic); false for times only.
    pub imu: bool,
    /// Record (log) time of each message of a times-only topic, ns (an Imu topic's are in
    /// its rows).
    times: Vec<u64>,
    /// An Imu topic's rows: record time, stamp, acc, gyro (seq 0).
    pub(crate) rows: Rows,
}

impl Stream {
    /// An empty Imu topic.
    pub fn imu(topic: impl Into<String>, msg_type: impl Into<String>) -> Stream {
        Stream {
            topic: topic.into(),
            msg_type: msg_type.into(),
            imu: true,
            ..Stream::default()
        }
    }

    /// An empty topic of another type (times only).
    pub(crate) fn other(topic: impl Into<String>, msg_type: impl Into<String>) -> Stream {
        Stream {
            imu: false,
            ..Stream::imu(topic, msg_type)
        }
    }

    /// An Imu topic whose rows a reader wrote into columns itself.
    pub(crate) fn of_rows(topic: &str, msg_type: &str, rows: Rows) -> Stream {
        Stream {
            rows,
            ..Stream::imu(topic, msg_type)
        }
    }

    /// Appends a row logged at `record` ns.
    pub(crate) fn push(&mut self, record: u64, row: &Row) {
        self.rows.push_row(record, row);
    }

    /// Room for `n` more messages.
    pub(crate) fn reserve(&mut self, n: usize) {
        if self.imu {
            self.rows.reserve(n);
        } else {
            self.times.reserve(n);
        }
    }

    /// Appends a message of a times-only topic.
    pub(crate) fn push_time(&mut self, record: u64) {
        self.times.push(record);
    }

    /// Messages.
    pub(crate) fn len(&self) -> usize {
        if self.imu {
            self.rows.len()
        } else {
            self.times.len()
        }
    }

    /// Record time of message `i`, ns.
    pub(crate) fn record(&self, i: usize) -> u64 {
        if self.imu {
            self.rows.record_time[i].as_nanos()
        } else {
            self.times[i]
        }
    }

    /// Row `i` of an Imu topic (the unit tests').
    #[cfg(test)]
    pub(crate) fn row(&self, i: usize) -> Row {
        self.rows.row(i)
    }
}

/// A [`source::Source`] over streams already decoded.
pub struct DecodedSource {
    kind: InputKind,
    contents: Contents,
    /// The streams' names, types and times-only messages (their rows are in `rows`).
    streams: Vec<Stream>,
    /// Each stream's rows; [`source::Source::take_rows`] moves them out.
    rows: Vec<std::sync::RwLock<Rows>>,
    /// Part → (stream, channel, first message, end).
    map: Vec<(usize, u32, usize, usize)>,
}

impl DecodedSource {
    /// Serves `streams`, with what opening found. Consecutive streams of one topic and type
    /// are pieces of one channel (a reader that parsed in parallel hands its pieces over
    /// without joining them); channel ids count the channels in order.
    pub(crate) fn new(
        kind: InputKind,
        mut streams: Vec<Stream>,
        notes: Vec<crate::shared::note::Note>,
        losses: Vec<Loss>,
    ) -> DecodedSource {
        let mut contents = Contents {
            notes,
            losses,
            ..Contents::default()
        };
        let mut map = Vec::new();
        for (k, s) in streams.iter().enumerate() {
            if let Some(c) = contents.channels.last_mut()
                && c.topic == s.topic
                && c.msg_type == s.msg_type
                && k > 0
            {
                c.count = c.count.map(|n| n + s.len() as u64);
            } else {
                contents.channels.push(Channel {
                    id: contents.channels.len() as u32,
                    topic: s.topic.clone(),
                    msg_type: s.msg_type.clone(),
                    encoding: if s.imu {
                        Encoding::Row
                    } else {
                        Encoding::Other(
                            kind.facts()
                                .other_topics
                                .unwrap_or(kind.describe())
                                .to_string(),
                        )
                    },
                    md5sum: None,
                    count: Some(s.len() as u64),
                });
            }
            let id = contents.channels.len() as u32 - 1;
            let before: u64 = map
                .iter()
                .filter(|m: &&(usize, u32, usize, usize)| m.1 == id)
                .map(|m| (m.3 - m.2) as u64)
                .sum();
            let mut a = 0;
            while a < s.len() {
                let b = (a + PART_ROWS).min(s.len());
                let (lo, hi) = (a..b)
                    .map(|i| s.record(i))
                    .fold((u64::MAX, 0), |(lo, hi), t| (lo.min(t), hi.max(t)));
                contents.parts.push(Part {
                    label: format!(
                        "messages {}..{} of '{}'",
                        before + a as u64 + 1,
                        before + b as u64,
                        s.topic
                    ),
                    span: Some((lo, hi)),
                    counts: Some(vec![(id, (b - a) as u64)]),
                    bytes: ((b - a) * if s.imu { ROW_LEN } else { 0 }) as u64,
                });
                map.push((k, id, a, b));
                a = b;
            }
        }
        let rows = streams
            .iter_mut()
            .map(|s| std::sync::RwLock::new(std::mem::take(&mut s.rows)))
            .collect();
        DecodedSource {
            kind,
            contents,
            streams,
            rows,
            map,
        }
    }
}

impl DecodedSource {
    /// Adds what the reader found lost of its streams: a loss on a channel adds its
    /// messages to the channel's count (they were promised, and the per-topic summary
    /// says "N of M").
    pub(crate) fn add_losses(&mut self, losses: Vec<Loss>) {
        for l in &losses {
            if let (Some(c), Some(n)) = (l.channel, l.messages)
                && let Some(ch) = self.contents.channels.get_mut(c as usize)
            {
                ch.count = ch.count.map(|x| x.saturating_add(n));
            }
        }
        self.contents.losses.extend(losses);
    }
}

impl source::Source for DecodedSource {
    fn kind(&self) -> InputKind {
        self.kind
    }
    fn contents(&self) -> &Contents {
        &self.contents
    }
    fn read_part(
        &self,
        part: usize,
        want: &(dyn Fn(u32) -> bool + Sync),
        sink: &mut MessageSink<'_>,
    ) -> source::PartRead {
        let mut r = source::PartRead::default();
        let Some(&(k, id, a, b)) = self.map.get(part) else {
            r.error = Some(source::PartError::NoSuchPart {
                index: part,
                wording: source::NoSuchPart::Numbered,
            });
            return r;
        };
        if !want(id) {
            return r;
        }
        let s = &self.streams[k];
        if !s.imu {
            for &t in &s.times[a..b] {
                sink(id, t, &[]);
            }
            r.delivered = (b - a) as u64;
            return r;
        }
        let rows = self.rows[k].read().unwrap_or_else(|e| e.into_inner());
        if rows.len() < b {
            r.error = Some(source::PartError::RowsTaken);
            return r;
        }
        for i in a..b {
            sink(id, rows.record_time[i].as_nanos(), &rows.row(i).encode());
        }
        r.delivered = (b - a) as u64;
        r
    }
    fn read_part_rows(
        &self,
        part: usize,
        want: &(dyn Fn(u32) -> bool + Sync),
        sink: &mut source::RowSink<'_>,
    ) -> Option<source::PartRead> {
        let &(k, id, a, b) = self.map.get(part)?;
        let mut r = source::PartRead::default();
        if !self.streams[k].imu || !want(id) {
            return Some(r);
        }
        let rows = self.rows[k].read().unwrap_or_else(|e| e.into_inner());
        if rows.len() < b {
            r.error = Some(source::PartError::RowsTaken);
            return Some(r);
        }
        for i in a..b {
            sink(id, rows.record_time[i].as_nanos(), &rows.row(i));
        }
        r.delivered = (b - a) as u64;
        Some(r)
    }
    fn take_rows(&self, channel: u32) -> Option<Rows> {
        let mut of_channel = self.map.iter().filter(|m| m.1 == channel).map(|m| m.0);
        let k = of_channel.next()?;
        if of_channel.any(|j| j != k) || !self.streams[k].imu {
            return None; // pieces: read part by part
        }
        let mut rows = self.rows[k].write().unwrap_or_else(|e| e.into_inner());
        Some(std::mem::take(&mut *rows))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::error::Error;
    use crate::series::{ReadOptions, TopicSelector, read_from};
    use crate::source::Source;

    #[test]
    fn rows_round_trip_through_the_read_path() {
        let mut s = Stream::imu("imu", "text/imu");
        let n = PART_ROWS + 10;
        for i in 0..n as u64 {
            let v = i as f64;
            s.push(
                1_000 + 5 * i,
                &Row {
                    stamp: 7 + 5 * i,
                    acc: [v, -v, 9.81],
                    gyro: [v * 1e-3, f64::NAN, 0.5],
                },
            );
        }
        let mut o = Stream::other("status", "text/other");
        o.push_time(3);
        // a reader that parsed in parallel hands its pieces over: one channel
        let (mut s2, mut s3) = (
            Stream::imu("imu", "text/imu"),
            Stream::imu("imu", "text/imu"),
        );
        for i in 0..n {
            let piece = if i < n / 2 { &mut s2 } else { &mut s3 };
            piece.push(s.record(i), &s.row(i));
        }
        let src = DecodedSource::new(InputKind::Text, vec![s, o], vec![], vec![]);
        assert_eq!(src.contents().parts.len(), 3);
        let pieces = DecodedSource::new(InputKind::Text, vec![s2, s3], vec![], vec![]);
        assert_eq!(pieces.channels().len(), 1);
        assert_eq!(pieces.channels()[0].count, Some(n as u64));
        let whole = read_from(
            &pieces,
            &TopicSelector::one("imu"),
            &ReadOptions { quiet: true },
        )
        .unwrap();
        assert_eq!(whole.series[0].record_time.len(), n);
        assert_eq!(whole.series[0].acc[0][n - 1], (n - 1) as f64);
        let r = read_from(
            &src,
            &TopicSelector::one("imu"),
            &ReadOptions { quiet: true },
        )
        .unwrap();
        let s = &r.series[0];
        assert_eq!(s.len(), n);
        assert_eq!(s.record_time[n - 1].as_nanos(), 1_000 + 5 * (n as u64 - 1));
        assert_eq!(s.stamp[3].as_nanos(), 22);
        assert_eq!(s.acc_at(4), [4.0, -4.0, 9.81]);
        assert!(s.gyro[1][9].is_nan() && s.gyro[2][9] == 0.5);
        assert!(s.notes.is_empty(), "{:?}", s.notes);
        assert!(Row::decode(&[0u8; 8]).is_err());
        // the payload path gives the same rows as the row path
        let mut by_payload = Vec::new();
        src.read_part(0, &|_| true, &mut |_, t, p| {
            by_payload.push((t, Row::decode(p).map(|x| x.acc[0])))
        });
        assert_eq!(by_payload.len(), PART_ROWS);
        assert_eq!(by_payload[4].0, 1_020);
        assert_eq!(by_payload[4].1.as_ref().ok(), Some(&4.0));
    }

    /// A read that owns the source takes a whole topic's rows as they are (no copy) and
    /// gives the series a read of its parts gives, losses accounted the same; the pieces of
    /// a parallel parse are read part by part.
    #[test]
    fn an_owned_read_takes_a_whole_topic_and_reads_pieces() {
        let stream = |from: u64, n: u64| {
            let mut s = Stream::imu("imu", "text/imu");
            for i in from..from + n {
                let v = i as f64;
                s.push(
                    10 * i,
                    &Row {
                        stamp: 10 * i + 1,
                        acc: [v, 2.0 * v, 3.0],
                        gyro: [-v, f64::NAN, 0.25],
                    },
                );
            }
            s
        };
        let n = PART_ROWS as u64 * 2 + 3;
        let opts = ReadOptions { quiet: true };
        let sel = TopicSelector::one("imu");
        let whole = || DecodedSource::new(InputKind::Text, vec![stream(0, n)], vec![], vec![]);
        let by_parts = read_from(&whole(), &sel, &opts).unwrap();
        let src = whole();
        assert!(src.take_rows(0).is_some_and(|r| r.len() == n as usize));
        // taken: its parts say so (by kind) instead of delivering nothing in silence
        let part = src.read_part(0, &|_| true, &mut |_, _, _| {});
        assert!(
            matches!(part.error, Some(source::PartError::RowsTaken)),
            "{:?}",
            part.error
        );
        let taken = source::PartError::RowsTaken.to_string();
        let after = read_from(&src, &sel, &opts);
        assert!(
            matches!(&after, Err(Error::NothingRead { why, .. }) if why.iter().any(|w| w.contains(&taken))),
            "{:?}",
            after.map(|r| r.series.len())
        );
        let pieces = || {
            DecodedSource::new(
                InputKind::Text,
                vec![stream(0, n / 2), stream(n / 2, n - n / 2)],
                vec![],
                vec![],
            )
        };
        assert!(pieces().take_rows(0).is_none());
        for owned in [
            crate::series::read_owned(Box::new(whole()), &sel, &opts).unwrap(),
            crate::series::read_owned(Box::new(pieces()), &sel, &opts).unwrap(),
        ] {
            let (a, b) = (&owned.series[0], &by_parts.series[0]);
            assert_eq!(a.len(), n as usize);
            assert_eq!(
                (&a.record_time, &a.stamp, &a.acc),
                (&b.record_time, &b.stamp, &b.acc)
            );
            assert_eq!(a.gyro[0], b.gyro[0]);
            assert!(a.gyro[1].iter().all(|v| v.is_nan()));
            assert_eq!((&a.report, &a.notes), (&b.report, &b.notes));
            assert_eq!(a.report.delivered, n);
        }
    }
}
