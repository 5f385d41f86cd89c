//! Logs whose readers decode the samples themselves (text, NumPy, PX4 ULog, ArduPilot
//! DataFlash): their rows reach the one read path ([`crate::series`]) as payloads of one
//! fixed layout, [`Row`], on channels of encoding [`Encoding::Row`], so the topic rules,
//! sorting, progress and loss accounting stay written once.
//!
//! Such a reader parses its file when it opens (the formats have no index to plan by) into
//! one [`Stream`] per topic and hands them to [`DecodedSource`], which serves them in parts of
//! at most [`PART_ROWS`] messages with exact counts. Topics the tools do not read as Imu keep
//! only their log times (for `bag2mat info`) and deliver empty payloads.

use crate::RosTime;
use crate::error::Error;
use crate::imu_msg::ImuSample;
use crate::source::{self, Channel, Contents, Encoding, InputKind, Loss, MessageSink, Part};

/// Bytes of one [`Row`] payload: the sample time (u64 ns), then acc x y z and gyro x y z
/// (f64), little-endian.
pub const ROW_LEN: usize = 56;

/// Messages per part (a part is the unit of parallel decoding and of the progress bar).
pub const PART_ROWS: usize = 1 << 16;

/// One decoded sample. A sensor a topic does not carry (a gyro-only topic's accelerometer)
/// is NaN.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Row {
    /// The sensor's sample time, ns (`header.stamp` of the series).
    pub stamp: u64,
    /// Linear acceleration, m/s².
    pub acc: [f64; 3],
    /// Angular velocity, rad/s.
    pub gyro: [f64; 3],
}

impl Row {
    /// The payload.
    pub fn encode(&self) -> [u8; ROW_LEN] {
        let mut b = [0u8; ROW_LEN];
        b[..8].copy_from_slice(&self.stamp.to_le_bytes());
        for (i, v) in self.acc.iter().chain(&self.gyro).enumerate() {
            b[8 + 8 * i..16 + 8 * i].copy_from_slice(&v.to_le_bytes());
        }
        b
    }

    /// The sample of a payload.
    pub fn decode(b: &[u8]) -> Result<ImuSample, Error> {
        if b.len() != ROW_LEN {
            return Err(Error::BadMessage {
                what: format!("a decoded row is {ROW_LEN} bytes, this one {}", b.len()),
            });
        }
        let mut c = crate::cursor::Cursor::new(b);
        let bad = |e: crate::cursor::CursorError| Error::BadMessage {
            what: e.to_string(),
        };
        let stamp = c.le::<u64>("row stamp").map_err(bad)?;
        let mut v = [0f64; 6];
        for x in &mut v {
            *x = c.le::<f64>("row value").map_err(bad)?;
        }
        Ok(ImuSample {
            seq: 0,
            stamp: RosTime::from_nanos(stamp),
            acc: [v[0], v[1], v[2]],
            gyro: [v[3], v[4], v[5]],
        })
    }
}

/// One topic's messages (or a piece of them): their log (record) times and, for an Imu
/// topic, their rows.
#[derive(Debug, Clone, Default)]
pub struct Stream {
    /// Topic name.
    pub topic: String,
    /// Type as the format names it (`px4/sensor_combined`, `ardupilot/IMU`, `text/imu`).
    pub msg_type: String,
    /// True when its messages are rows (an Imu topic); false for times only.
    pub imu: bool,
    /// Record (log) time of each message, ns.
    pub record: Vec<u64>,
    /// [`ROW_LEN`] bytes per message (empty unless `imu`).
    pub rows: Vec<u8>,
}

impl Stream {
    /// An empty Imu topic.
    pub fn imu(topic: impl Into<String>, msg_type: impl Into<String>) -> Stream {
        Stream {
            topic: topic.into(),
            msg_type: msg_type.into(),
            imu: true,
            record: Vec::new(),
            rows: Vec::new(),
        }
    }

    /// An empty topic of another type (times only).
    pub fn other(topic: impl Into<String>, msg_type: impl Into<String>) -> Stream {
        Stream {
            imu: false,
            ..Stream::imu(topic, msg_type)
        }
    }

    /// Appends a row logged at `record` ns.
    pub fn push(&mut self, record: u64, row: &Row) {
        self.record.push(record);
        self.rows.extend_from_slice(&row.encode());
    }

    /// Room for `n` more messages.
    pub fn reserve(&mut self, n: usize) {
        self.record.reserve(n);
        if self.imu {
            self.rows.reserve(n * ROW_LEN);
        }
    }

    /// Appends a message of a times-only topic.
    pub fn push_time(&mut self, record: u64) {
        self.record.push(record);
    }

    /// Messages.
    pub fn len(&self) -> usize {
        self.record.len()
    }

    /// True when empty.
    pub fn is_empty(&self) -> bool {
        self.record.is_empty()
    }
}

/// A [`source::Source`] over streams already decoded.
pub struct DecodedSource {
    kind: InputKind,
    contents: Contents,
    streams: Vec<Stream>,
    /// Part → (stream, channel, first message, end).
    map: Vec<(usize, u32, usize, usize)>,
}

impl DecodedSource {
    /// Serves `streams`, with what opening found. Consecutive streams of one topic and type
    /// are pieces of one channel (a reader that parsed in parallel hands its pieces over
    /// without joining them); channel ids count the channels in order.
    pub fn new(
        kind: InputKind,
        streams: Vec<Stream>,
        notes: Vec<String>,
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
                        Encoding::Other(kind_encoding(kind).to_string())
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
                let t = &s.record[a..b];
                contents.parts.push(Part {
                    label: format!(
                        "messages {}..{} of '{}'",
                        before + a as u64 + 1,
                        before + b as u64,
                        s.topic
                    ),
                    span: t.iter().min().zip(t.iter().max()).map(|(x, y)| (*x, *y)),
                    counts: Some(vec![(id, (b - a) as u64)]),
                    bytes: ((b - a) * if s.imu { ROW_LEN } else { 0 }) as u64,
                });
                map.push((k, id, a, b));
                a = b;
            }
        }
        DecodedSource {
            kind,
            contents,
            streams,
            map,
        }
    }
}

/// How a format's non-Imu topics' encoding is named.
fn kind_encoding(kind: InputKind) -> &'static str {
    match kind {
        InputKind::Ulog => "ulog",
        InputKind::DataFlash => "df",
        _ => "text",
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
            r.error = Some(format!("no part {part}"));
            return r;
        };
        if !want(id) {
            return r;
        }
        let s = &self.streams[k];
        for i in a..b {
            let payload = if s.imu {
                &s.rows[i * ROW_LEN..(i + 1) * ROW_LEN]
            } else {
                &[][..]
            };
            sink(id, s.record[i], payload);
        }
        r.delivered = (b - a) as u64;
        r
    }
}

#[cfg(test)]
mod tests {
    use super::*;
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
        let mut s2 = s.clone();
        s2.record.drain(n / 2..);
        s2.rows.drain(n / 2 * ROW_LEN..);
        let mut s3 = s.clone();
        s3.record.drain(..n / 2);
        s3.rows.drain(..n / 2 * ROW_LEN);
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
    }
}
