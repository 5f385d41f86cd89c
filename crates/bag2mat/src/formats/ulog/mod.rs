//! PX4 ULog (`.ulg`, the ULog file format of the PX4 documentation): the IMU topics the
//! flight stack logs, each a topic like a bag's, named `name` when the log holds only its
//! instance 0 and `name:k` (the ULog `multi_id`) otherwise:
//!
//! * `sensor_combined`: `gyro_rad`, `accelerometer_m_s2` (the gyro's `timestamp`).
//! * `sensor_gyro`, `sensor_accel` (every instance; the raw per-IMU topics where the log
//!   has them): `x y z` at `timestamp_sample`; the other sensor's columns are NaN.
//! * `sensor_gyro_fifo`, `sensor_accel_fifo` (every instance; the raw high-rate samples
//!   PX4 logs with `SDLOG_PROFILE` high-rate/debug): each message packs `samples` (≤ 32)
//!   int16 `x[] y[] z[]` at `dt` µs apart, in physical units after × `scale`; the newest
//!   sample is at `timestamp_sample` (PX4's drivers stamp the FIFO read, and
//!   `PX4Gyroscope::updateFIFO` integrates up to sample N−1 at that stamp), so sample k of N
//!   is at `timestamp_sample − (N−1−k)·dt`, and its record time is the message's `timestamp`
//!   less the same offset. Values are `x[k] · scale` in f64 (exact: 16 × 24 bits).
//! * `vehicle_imu`: `delta_angle`/`delta_angle_dt` and `delta_velocity`/`delta_velocity_dt`,
//!   each delta divided by its own dt (µs); a message with a zero dt is skipped and counted.
//!
//! The record time is the message's `timestamp`, the stamp its `timestamp_sample` where the
//! topic has one (µs since boot, as ns). Every other topic is listed with its message count
//! and times (`bag2mat info`). Dropouts the logger recorded (`O` messages) are losses;
//! bytes that do not parse are skipped to the next sync marker and reported.
//!
//! Opening hops once over the message headers (definitions, subscriptions, dropouts, counts)
//! and cuts the data into message-aligned byte ranges; each range is then read and decoded
//! on its own, in parallel, straight into the read path (nothing is held but the result).
//!
//! Our own parser (with [`crate::cursor`]): PX4's `px4-ulog` crate (0.6) and `yule_log`
//! (0.4) stream the whole file through callbacks in one pass (no ranges to decode in
//! parallel), and `px4-ulog`'s unpack helpers panic on short slices by design; the read path
//! wants every message's record time, typed errors and the losses spelt out.

use crate::shared::note::Note;

mod decoder;
mod format;
mod frame;
mod hop;
// The synthetic-log writers of the tests and benchmarks (re-exported by `test_tools`).
#[cfg(any(test, feature = "test-support"))]
pub(crate) mod write;

use std::path::Path;

use crate::cursor::{Cursor, CursorError};
use crate::error::Error;
use crate::rows::Row;
use crate::source::{InputKind, Loss};

use decoder::Decoder;
use format::Slot;
use hop::{Event, Found, PartCount};

/// The file's first 7 bytes (then a version byte and the start time, µs).
pub const MAGIC: &[u8] = super::ULOG_MAGIC;
/// The sync marker (`S` message body) a reader resynchronises on.
pub const SYNC: [u8; 8] = [0x2F, 0x73, 0x13, 0x20, 0x25, 0x0C, 0xBB, 0x12];
/// Bytes of the file header.
pub const HEADER_LEN: usize = 16;

/// How a channel's data messages are read: its decoder (an IMU topic) and where its
/// `timestamp` is (the first field of every logged topic).
#[derive(Debug, Clone)]
struct Chan {
    decoder: Option<Decoder>,
    ts: Option<Slot>,
}

/// Bytes per part: the unit of parallel decoding, at a message boundary.
const PART_BYTES: u64 = 4 << 20;

/// The message types of the format.
const TYPES: &[u8] = b"BFIMPQARDLCSO";

/// True for a message type of the format (a table: asked of every message).
const IS_TYPE: [bool; 256] = {
    let mut t = [false; 256];
    let mut i = 0;
    while i < TYPES.len() {
        t[TYPES[i] as usize] = true;
        i += 1;
    }
    t
};

/// Subscriptions: message id → channel ([`NO_CHANNEL`] when none), a table for the hot loop
/// as long as the largest id subscribed (ids count up from 0), so that each part's copy
/// is small.
#[derive(Debug, Clone, Default)]
struct Subs(Vec<u32>);

impl Subs {
    #[inline]
    fn get(&self, id: u16) -> u32 {
        self.0.get(id as usize).copied().unwrap_or(NO_CHANNEL)
    }

    fn set(&mut self, id: u16, ch: u32) {
        let i = id as usize;
        if self.0.len() <= i {
            self.0.resize(i + 1, NO_CHANNEL);
        }
        self.0[i] = ch;
    }

    /// The channels subscribed, each once.
    fn channels(&self) -> Vec<u32> {
        let mut v: Vec<u32> = self
            .0
            .iter()
            .copied()
            .filter(|&c| c != NO_CHANNEL)
            .collect();
        v.sort_unstable();
        v.dedup();
        v
    }
}

/// A message id without a subscription.
const NO_CHANNEL: u32 = u32::MAX;

/// A part: its byte range, the subscriptions at its start and the hop's events in it.
#[derive(Debug, Clone)]
struct PartMap {
    start: u64,
    end: u64,
    subs: Subs,
    events: std::ops::Range<usize>,
}

/// A PX4 ULog opened for reading: channels and parts from one hop over the file; each part
/// is read and decoded on its own, in parallel.
pub struct UlogReader {
    map: crate::mapped::Mapped,
    contents: crate::source::Contents,
    chans: Vec<Chan>,
    parts: Vec<PartMap>,
    /// The hop's decisions past damage, in file order ([`hop::Event`]).
    events: Vec<(u64, Event)>,
}

/// Opens a ULog file: one serial hop over the messages (definitions, subscriptions, the
/// parts and what each part's data messages hold, [`hop::hop`]).
pub(crate) fn open(path: &Path) -> Result<UlogReader, Error> {
    let io = |e| Error::io(path, e);
    let file = std::fs::File::open(path).map_err(io)?;
    let map = crate::mapped::Mapped::of(&file, path)?;
    let start_us = check_header(path, map.bytes())?;
    // the page tables filled on the other core while the serial hop runs
    let (hop, ()) = rayon::join(|| hop::hop(map.bytes()), || map.fill_pages());
    if let Some(f) = hop.found.unknown_incompat {
        // pyulog refuses such a log too: what the flags announce changes how it reads
        return Err(Error::Corrupt {
            path: path.to_path_buf(),
            offset: HEADER_LEN as u64 + 3 + 8,
            what: format!(
                "ULog: the flag bits set incompatibility flags this reader does not know ({f:02x?}): the log cannot be read safely"
            ),
        });
    }
    if hop.formats.defs.is_empty() && hop.channels.is_empty() {
        return Err(Error::Corrupt {
            path: path.to_path_buf(),
            offset: HEADER_LEN as u64,
            what: "ULog: no format or subscription could be read".into(),
        });
    }
    let mut reader = UlogReader {
        map,
        contents: crate::source::Contents::default(),
        chans: hop.chans,
        parts: hop.parts,
        events: hop.events,
    };
    let counted = hop.counted;
    let found = hop.found;
    let mut channels = hop.channels;
    for c in &counted {
        for (ch, n) in c.counts.iter().enumerate() {
            if let Some(total) = channels[ch].count.as_mut() {
                *total += n;
            }
        }
    }
    // the messages lost are promised too
    for ((ch, _), (n, _)) in &found.lost {
        if let Some(total) = channels[*ch as usize].count.as_mut() {
            *total += n;
        }
    }
    // a subscription without a message names no topic (pyulog lists none): a damaged one
    // must not rename the topics of the others
    super::instance_topics(
        channels
            .iter_mut()
            .filter(|c| c.count.is_some_and(|n| n > 0))
            .map(|c| &mut c.topic),
    );
    let mut contents = crate::source::Contents {
        losses: losses(&found, &channels),
        notes: notes(&found),
        log_start: Some(start_us.saturating_mul(1000)),
        ..Default::default()
    };
    for (p, c) in reader.parts.iter().zip(&counted) {
        let counts: Vec<(u32, u64)> = c
            .counts
            .iter()
            .enumerate()
            .filter(|(_, n)| **n > 0)
            .map(|(ch, n)| (ch as u32, *n))
            .collect();
        // what the part delivers: one Row payload per message of an IMU channel
        let rows: u64 = counts
            .iter()
            .filter(|(ch, _)| reader.chans[*ch as usize].decoder.is_some())
            .map(|(_, n)| *n)
            .sum();
        contents.parts.push(crate::source::Part {
            label: format!("bytes {}..{}", p.start, p.end),
            span: c.span,
            counts: Some(counts),
            bytes: rows * crate::rows::ROW_LEN as u64,
        });
    }
    contents.integration = integration(&counted);
    contents.channels = channels;
    reader.contents = contents;
    Ok(reader)
}

/// The median integration intervals of each channel of deltas the parts counted.
fn integration(counted: &[PartCount]) -> Vec<(u32, crate::Integration)> {
    let mut by: std::collections::BTreeMap<u32, (Vec<f32>, Vec<f32>)> = Default::default();
    for &(ch, a, v) in counted.iter().flat_map(|c| &c.deltas) {
        let e = by.entry(ch).or_default();
        e.0.push(a);
        e.1.push(v);
    }
    by.into_iter()
        .filter_map(|(ch, (mut a, mut v))| {
            crate::Integration::of_us(&mut a, &mut v).map(|i| (ch, i))
        })
        .collect()
}

/// The file header: the magic, a version byte and the start time (µs, returned).
fn check_header(path: &Path, bytes: &[u8]) -> Result<u64, Error> {
    let mut c = Cursor::new(&bytes[..bytes.len().min(HEADER_LEN)]);
    let magic = c
        .take(MAGIC.len(), "ULog magic")
        .map_err(|e| corrupt(path, e))?;
    if magic != MAGIC {
        return Err(corrupt(path, c.invalid("not a ULog file")));
    }
    c.le::<u8>("ULog version").map_err(|e| corrupt(path, e))?;
    c.le::<u64>("ULog start time").map_err(|e| corrupt(path, e))
}

fn corrupt(path: &Path, e: CursorError) -> Error {
    let offset = match &e {
        CursorError::Short { offset, .. } | CursorError::Invalid { offset, .. } => *offset,
    };
    Error::Corrupt {
        path: path.to_path_buf(),
        offset,
        what: format!("ULog: {e}"),
    }
}

/// What the hop found lost, as losses: the dropouts the logger recorded, and per IMU topic
/// the rows of the messages damage cost (exact where their header names the topic, bounded
/// where bytes say nothing).
fn losses(found: &Found, channels: &[crate::source::Channel]) -> Vec<Loss> {
    let mut losses = Vec::new();
    if !found.dropouts.is_empty() {
        let total: u64 = found.dropouts.iter().map(|d| d.1 as u64).sum();
        let longest = found
            .dropouts
            .iter()
            .max_by_key(|d| d.1)
            .copied()
            .unwrap_or((0, 0));
        let first = found.dropouts[0].0;
        let last = found
            .dropouts
            .last()
            .map_or(0, |d| d.0.saturating_add(d.1 as u64 * 1_000_000));
        losses.push(Loss {
            what: format!(
                "the logger recorded {} dropout{} totalling {total} ms (longest {} ms at {:.3} s): every topic lost its messages of that time",
                found.dropouts.len(),
                if found.dropouts.len() == 1 { "" } else { "s" },
                longest.1,
                longest.0 as f64 * 1e-9
            ),
            messages: None,
            at_most: None,
            span: Some((first, last)),
            channel: None,
        });
    }
    let topic = |ch: u32| channels.get(ch as usize).map_or("?", |c| c.topic.as_str());
    for ((ch, why), (n, at)) in &found.lost {
        losses.push(Loss {
            what: format!(
                "data messages of '{}' {why} (first at byte {at})",
                topic(*ch)
            ),
            messages: Some(*n),
            channel: Some(*ch),
            ..Loss::default()
        });
    }
    for (ch, n) in &found.bounds {
        let (stretches, bytes, first) = found.skipped;
        let orphans = found.orphans.0;
        losses.push(Loss {
            what: format!(
                "'{}': {}{}{} may have held messages of it",
                topic(*ch),
                if stretches > 0 {
                    format!("{bytes} bytes that are no ULog message (first at byte {first})")
                } else {
                    String::new()
                },
                if stretches > 0 && orphans > 0 {
                    " and "
                } else {
                    ""
                },
                if orphans > 0 {
                    format!("{orphans} data messages of no subscription")
                } else if stretches == 0 {
                    "the message the log ends inside".to_string()
                } else {
                    String::new()
                },
            ),
            at_most: Some(*n),
            channel: Some(*ch),
            ..Loss::default()
        });
    }
    losses
}

/// What the hop found and read through, or skipped, as notes.
fn notes(found: &Found) -> Vec<Note> {
    let mut notes = Vec::new();
    let (stretches, bytes, first) = found.skipped;
    if stretches > 0 {
        notes.push(Note::warning(format!(
            "{bytes} bytes in {stretches} stretch{} do not parse as ULog messages and were skipped to the next whole messages (first at byte {first})",
            if stretches == 1 { "" } else { "es" },
        )));
    }
    let (orphans, at, id) = found.orphans;
    if orphans > 0 {
        notes.push(Note::warning(format!(
            "{orphans} data message{} of an id no subscription names were skipped (first at byte {at}, id {id})",
            if orphans == 1 { "" } else { "s" },
        )));
    }
    for (what, (n, at)) in &found.repaired {
        notes.push(Note::warning(format!("{what}: {n} (first at byte {at})")));
    }
    if let Some(at) = found.truncated {
        notes.push(Note::warning(format!(
            "the log ends inside a message at byte {at} (cut short): read to there"
        )));
    }
    notes
}

impl crate::source::Source for UlogReader {
    fn kind(&self) -> InputKind {
        InputKind::Ulog
    }
    fn contents(&self) -> &crate::source::Contents {
        &self.contents
    }
    fn read_part(
        &self,
        part: usize,
        want: &(dyn Fn(u32) -> bool + Sync),
        sink: &mut crate::source::MessageSink<'_>,
    ) -> crate::source::PartRead {
        self.walk_part(part, want, |ch, t, row| match row {
            Some(row) => sink(ch, t, &row.encode()),
            None => sink(ch, t, &[]),
        })
    }
    fn read_part_rows(
        &self,
        part: usize,
        want: &(dyn Fn(u32) -> bool + Sync),
        sink: &mut crate::source::RowSink<'_>,
    ) -> Option<crate::source::PartRead> {
        let imu = |ch: u32| want(ch) && self.chans[ch as usize].decoder.is_some();
        Some(self.walk_part(part, imu, |ch, t, row| {
            if let Some(row) = row {
                sink(ch, t, row);
            }
        }))
    }
}

impl UlogReader {
    /// Walks part `part`, handing each message of a channel `want` accepts to `deliver`:
    /// its row for an IMU channel (a FIFO message gives several), `None` for another topic.
    /// The hop checked every message: the walk follows its events (subscriptions, damage
    /// read through or skipped) and reads the rest as they stand. Generic, not `dyn`, and
    /// `want` asked once per channel: this is the hot loop.
    fn walk_part(
        &self,
        part: usize,
        want: impl Fn(u32) -> bool,
        mut deliver: impl FnMut(u32, u64, Option<&Row>),
    ) -> crate::source::PartRead {
        let mut r = crate::source::PartRead::default();
        let wanted: Vec<bool> = (0..self.chans.len() as u32).map(want).collect();
        let Some(p) = self.parts.get(part) else {
            r.error = Some(crate::source::PartError::NoSuchPart {
                index: part,
                wording: crate::source::NoSuchPart::Numbered,
            });
            return r;
        };
        let bytes = self.map.bytes();
        let mut subs = p.subs.clone();
        let mut events = self.events[p.events.clone()].iter().peekable();
        let mut data = |ch: u32, data: &[u8], r: &mut crate::source::PartRead| {
            if !wanted.get(ch as usize).is_some_and(|&w| w) {
                return; // NO_CHANNEL is past the table
            }
            let c = &self.chans[ch as usize];
            let Some(t_us) = c.ts.and_then(|s| s.get_u64(data)) else {
                return;
            };
            let t = t_us.saturating_mul(1000);
            let Some(d) = &c.decoder else {
                deliver(ch, t, None);
                r.delivered += 1;
                return;
            };
            let rows = d.rows(t, data, |rt, row| {
                deliver(ch, rt, Some(&row));
                r.delivered += 1;
            });
            if let Err(why) = rows {
                r.skipped += d.rows_in(data).max(1) as u64;
                r.skip_reason
                    .get_or_insert_with(|| crate::source::SkipReason::Undecodable {
                        topic: self.contents.channels[ch as usize].topic.clone(),
                        why,
                    });
            }
        };
        let mut at = p.start;
        while at < p.end {
            if let Some(&&(off, e)) = events.peek()
                && off == at
            {
                events.next();
                match e {
                    Event::Skip(to) => {
                        at = to;
                        continue;
                    }
                    Event::Data { ch, len, next } => {
                        let a = at as usize + 5;
                        if let Some(d) = bytes.get(a..a + len as usize) {
                            data(ch, d, &mut r);
                        }
                        at = next;
                        continue;
                    }
                    // then the subscription message itself, skipped below
                    Event::Bind(id, ch) => subs.set(id, ch),
                }
            }
            let Some((size, ty)) = frame::header(bytes, at) else {
                break;
            };
            let next = at + 3 + size as u64;
            if next > p.end {
                break;
            }
            if ty == b'D'
                && let Some(b) = frame::body(bytes, at, size as usize)
                && b.len() >= 2
            {
                data(subs.get(u16::from_le_bytes([b[0], b[1]])), &b[2..], &mut r);
            }
            at = next;
        }
        r
    }
}
