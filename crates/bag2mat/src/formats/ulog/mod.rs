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

mod decoder;
mod format;
// The synthetic-log writers of the tests and benchmarks (re-exported by `test_tools`).
#[cfg(any(test, feature = "test-support"))]
pub(crate) mod write;

use std::collections::HashMap;
use std::path::Path;

use crate::cursor::{Cursor, CursorError};
use crate::error::Error;
use crate::rows::Row;
use crate::source::{InputKind, Loss};

use decoder::{Decoder, fifo_offset_ns};

use format::{Formats, Slot, parse_format};

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

/// What the hop over the file found, beyond the channels.
#[derive(Default)]
struct Found {
    dropouts: Vec<(u64, u16)>,
    /// Bytes skipped to resynchronise: (offset, length).
    skipped: Vec<(u64, u64)>,
    /// Data messages for an id no `A` message announced.
    orphans: u64,
    /// The file ends inside a message at this offset.
    truncated: Option<u64>,
}

/// Bytes per part: the unit of parallel decoding, at a message boundary.
const PART_BYTES: u64 = 4 << 20;
/// Bytes searched at a time for the next sync marker.
const WINDOW: usize = 8 << 20;

/// The file's bytes up to `len` (the whole file, or a part's end).
struct Window<'f> {
    data: &'f [u8],
    len: u64,
}

impl<'f> Window<'f> {
    /// Bytes `at..at + n` of the file, or `None` past `len`.
    fn get(&self, at: u64, n: usize) -> Option<&'f [u8]> {
        let end = at.saturating_add(n as u64);
        if end > self.len.min(self.data.len() as u64) {
            return None;
        }
        Some(&self.data[at as usize..end as usize])
    }
}

/// One step of the walk over the messages.
enum Step {
    /// A message: its offset, type and size (its body follows the 3 header bytes).
    Msg(u64, u8, u16),
    /// Bytes that are no message (resynchronised to the next sync marker) or cut by the
    /// start of appended data: offset and length.
    Skip(u64, u64),
    /// The file ends inside a message at this offset.
    Cut(u64),
}

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

/// The step at `at`: the hop and every part walk the messages the same way.
#[inline(always)]
fn step(win: &Window, at: u64, appended_at: Option<u64>) -> Step {
    let Some(h) = win.get(at, 3) else {
        return Step::Cut(at);
    };
    let (size, ty) = (u16::from_le_bytes([h[0], h[1]]), h[2]);
    if !IS_TYPE[ty as usize] {
        let n = WINDOW.min((win.len - at) as usize);
        let rest = win.get(at, n).unwrap_or(&[]);
        let skip = match rest.windows(SYNC.len()).position(|w| w == SYNC) {
            Some(p) => p.saturating_sub(3),
            None if at + (n as u64) < win.len => n - SYNC.len(),
            None => n,
        };
        return Step::Skip(at, skip.max(1) as u64);
    }
    // a message cut by the start of appended data (the logger's DATA_APPENDED flag)
    if let Some(ap) = appended_at
        && at < ap
        && at + 3 + size as u64 > ap
        && ap <= win.len
    {
        return Step::Skip(at, ap - at);
    }
    if at + 3 + size as u64 > win.len {
        return Step::Cut(at);
    }
    Step::Msg(at, ty, size)
}

/// An `A` message: multi_id, message id, format name.
fn subscription(body: &[u8]) -> Option<(u8, u16, &str)> {
    let mut m = Cursor::new(body);
    let multi = m.le::<u8>("multi_id").ok()?;
    let id = m.le::<u16>("msg_id").ok()?;
    let n = m.remaining();
    Some((multi, id, m.str(n, "message name").ok()?))
}

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
}

/// A message id without a subscription.
const NO_CHANNEL: u32 = u32::MAX;

/// A part: its byte range and the subscriptions at its start.
#[derive(Debug, Clone)]
struct PartMap {
    start: u64,
    end: u64,
    subs: Subs,
}

/// A PX4 ULog opened for reading: channels and parts from one hop over the file; each part
/// is read and decoded on its own, in parallel.
pub struct UlogReader {
    map: crate::mapped::Mapped,
    contents: crate::source::Contents,
    chans: Vec<Chan>,
    by_key: HashMap<(String, u8), u32>,
    parts: Vec<PartMap>,
    appended_at: Option<u64>,
}

/// Opens a ULog file: one serial hop over the messages (definitions, subscriptions, the
/// parts and what each part's data messages hold, [`hop`]).
pub(crate) fn open(path: &Path) -> Result<UlogReader, Error> {
    let io = |e| Error::io(path, e);
    let file = std::fs::File::open(path).map_err(io)?;
    let map = crate::mapped::Mapped::of(&file, path)?;
    let start_us = check_header(path, map.bytes())?;
    // the page tables filled on the other core while the serial hop runs
    let (hop, ()) = rayon::join(|| hop(map.bytes()), || map.fill_pages());
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
        by_key: hop.by_key,
        parts: hop.parts,
        appended_at: hop.appended_at,
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
    super::instance_topics(channels.iter_mut().map(|c| &mut c.topic));
    let mut contents = crate::source::Contents {
        losses: losses(&found),
        log_start: Some(start_us.saturating_mul(1000)),
        ..Default::default()
    };
    if let Some(at) = found.truncated {
        contents.notes.push(format!(
            "the log ends inside a message at byte {at} (cut short): read to there"
        ));
    }
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

/// What the serial hop over the message headers finds.
struct Hop {
    formats: Formats,
    channels: Vec<crate::source::Channel>,
    chans: Vec<Chan>,
    by_key: HashMap<(String, u8), u32>,
    parts: Vec<PartMap>,
    /// Dropouts, skipped stretches, orphans and a cut end, in file order.
    found: Found,
    /// What each part's data messages hold.
    counted: Vec<PartCount>,
    /// The latest record time logged so far (a dropout's time: its `O` message has none).
    latest: u64,
    appended_at: Option<u64>,
}

/// The hop: every message in file order, the definitions, subscriptions and dropouts read,
/// each data message counted to its part ([`PartCount::data`]: its id, time stamp and, for
/// a FIFO message, its sample count; bytes in the cache line the header brought in, so the
/// count costs little beside the step, where a second walk per part cost a tenth of the
/// read). Parts start at data messages, every [`PART_BYTES`], each with the subscriptions
/// then; they are decoded in parallel.
fn hop(bytes: &[u8]) -> Hop {
    let len = bytes.len() as u64;
    let win = Window { data: bytes, len };
    let mut h = Hop {
        formats: Formats {
            defs: HashMap::new(),
        },
        channels: Vec::new(),
        chans: Vec::new(),
        by_key: HashMap::new(),
        parts: Vec::new(),
        found: Found::default(),
        counted: Vec::new(),
        latest: 0,
        appended_at: None,
    };
    let mut subs = Subs::default();
    let mut at = HEADER_LEN as u64;
    while at < len {
        let (m_at, ty, size) = match step(&win, at, h.appended_at) {
            Step::Msg(a, t, n) => (a, t, n),
            Step::Skip(a, n) => {
                h.found.skipped.push((a, n));
                at = a + n;
                continue;
            }
            Step::Cut(a) => {
                h.found.truncated = Some(a);
                break;
            }
        };
        at = m_at + 3 + size as u64;
        if ty == b'D' {
            if h.parts.last().is_none_or(|p| m_at - p.start >= PART_BYTES) {
                if let Some(p) = h.parts.last_mut() {
                    p.end = m_at;
                }
                h.parts.push(PartMap {
                    start: m_at,
                    end: len,
                    subs: subs.clone(),
                });
                h.counted.push(PartCount::default());
            }
            // step said the body is there
            let body = win.get(m_at + 3, size as usize).unwrap_or(&[]);
            let Some(c) = h.counted.last_mut() else {
                continue;
            };
            match c.data(body, &subs, &h.chans) {
                Data::Counted(t) => h.latest = h.latest.max(t),
                Data::Orphan => h.found.orphans += 1,
                Data::Short => h.found.skipped.push((m_at, size as u64 + 3)),
            }
            continue;
        }
        let Some(body) = win.get(m_at + 3, size as usize) else {
            h.found.truncated = Some(m_at);
            break;
        };
        h.definition(m_at, ty, body, &mut subs);
    }
    if let Some(p) = h.parts.last_mut() {
        p.end = at.min(len);
    }
    h
}

impl Hop {
    /// A message other than data at `m_at` (body `body`): what it defines or records.
    fn definition(&mut self, m_at: u64, ty: u8, body: &[u8], subs: &mut Subs) {
        let mut m = Cursor::at(body, m_at + 3);
        match ty {
            b'B' => {
                // flag bits: compat[8], incompat[8], appended offsets[3]
                if let (Ok(_), Ok(incompat)) =
                    (m.take(8, "compat flags"), m.take(8, "incompat flags"))
                    && incompat[0] & 1 != 0
                    && let Ok(off) = m.le::<u64>("appended offset")
                    && off > 0
                {
                    self.appended_at = Some(off);
                }
            }
            b'F' => {
                if let Some((name, fields)) =
                    std::str::from_utf8(m.rest()).ok().and_then(parse_format)
                {
                    self.formats.defs.insert(name, fields);
                }
            }
            b'A' => match subscription(body) {
                Some((multi, id, name)) => subs.set(id, self.channel(name, multi)),
                None => self.found.skipped.push((m_at, body.len() as u64 + 3)),
            },
            b'R' => {
                if let Ok(id) = m.le::<u16>("msg_id") {
                    subs.set(id, NO_CHANNEL);
                }
            }
            b'O' => {
                if let Ok(ms) = m.le::<u16>("dropout duration") {
                    self.found.dropouts.push((self.latest, ms));
                }
            }
            _ => {} // info, parameters, log text, sync
        }
    }

    /// The channel of topic `name` instance `multi`, made at its first subscription.
    fn channel(&mut self, name: &str, multi: u8) -> u32 {
        let key = (name.to_string(), multi);
        if let Some(&ch) = self.by_key.get(&key) {
            return ch;
        }
        let slots = self.formats.slots(name);
        let decoder = slots.as_ref().and_then(|s| Decoder::for_topic(name, s));
        let ts = slots.as_ref().and_then(|s| s.get("timestamp").copied());
        let ch = self.channels.len() as u32;
        self.channels.push(crate::source::Channel {
            id: ch,
            topic: format!("{name}:{multi}"),
            msg_type: Decoder::msg_type(name),
            encoding: if decoder.is_some() {
                crate::source::Encoding::Row
            } else {
                crate::source::Encoding::Other("ulog".into())
            },
            md5sum: None,
            count: Some(0),
        });
        self.chans.push(Chan { decoder, ts });
        self.by_key.insert(key, ch);
        ch
    }
}

/// What counting one part's data messages finds.
#[derive(Default)]
struct PartCount {
    /// Rows per channel (a FIFO message is several).
    counts: Vec<u64>,
    /// The record times the part spans (a FIFO message from its oldest sample).
    span: Option<(u64, u64)>,
    /// The integration intervals of each delta message (`vehicle_imu`): channel, the
    /// gyroscope's and the accelerometer's, µs.
    deltas: Vec<(u32, f32, f32)>,
}

/// What a data message was to the count.
enum Data {
    /// Counted, logged at this record time (ns).
    Counted(u64),
    /// Of no subscription, or without its time stamp.
    Orphan,
    /// Too short for its message id.
    Short,
}

impl PartCount {
    /// Counts a data message (body `body`) of the part: its rows (a FIFO message is
    /// several, the oldest (n−1)·dt before its time) and the times spanned.
    fn data(&mut self, body: &[u8], subs: &Subs, chans: &[Chan]) -> Data {
        if body.len() < 2 {
            return Data::Short;
        }
        let ch = subs.get(u16::from_le_bytes([body[0], body[1]]));
        let data = &body[2..];
        let Some(chan) = chans.get(ch as usize) else {
            return Data::Orphan;
        };
        let Some(t_us) = chan.ts.and_then(|s| s.get_u64(data)) else {
            return Data::Orphan;
        };
        let t = t_us.saturating_mul(1000);
        let (rows, first) = match &chan.decoder {
            Some(d @ Decoder::Fifo { dt, .. }) => {
                let n = d.rows_in(data);
                let dt = dt.get(data).unwrap_or(0.0).max(0.0);
                (n as u64, t.saturating_sub(fifo_offset_ns(n.max(1), 0, dt)))
            }
            Some(Decoder::Deltas {
                angle_dt, vel_dt, ..
            }) => {
                if let (Some(a), Some(v)) = (angle_dt.get(data), vel_dt.get(data))
                    && a > 0.0
                    && v > 0.0
                {
                    self.deltas.push((ch, a as f32, v as f32));
                }
                (1, t)
            }
            _ => (1, t),
        };
        if rows == 0 {
            return Data::Counted(t);
        }
        if self.counts.len() <= ch as usize {
            self.counts.resize(ch as usize + 1, 0);
        }
        self.counts[ch as usize] += rows;
        self.span = Some(
            self.span
                .map_or((first, t), |(a, b)| (a.min(first), b.max(t))),
        );
        Data::Counted(t)
    }
}

/// The messages from `start` to the window's end, each given to `on` with its offset, type
/// and body: the hop and every part walk the messages the same way ([`step`]).
// generic, not `dyn`: the walk is the hot loop of every part, and `on` is inlined into it
fn walk(win: &Window, start: u64, appended_at: Option<u64>, mut on: impl FnMut(u64, u8, &[u8])) {
    let mut at = start;
    while at < win.len {
        let (m_at, ty, size) = match step(win, at, appended_at) {
            Step::Msg(a, t, n) => (a, t, n),
            Step::Skip(a, n) => {
                at = a + n;
                continue;
            }
            Step::Cut(_) => break,
        };
        at = m_at + 3 + size as u64;
        let Some(body) = win.get(m_at + 3, size as usize) else {
            break;
        };
        on(m_at, ty, body);
    }
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

/// What the hop found lost, as losses.
fn losses(found: &Found) -> Vec<Loss> {
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
    if !found.skipped.is_empty() {
        let bytes: u64 = found.skipped.iter().map(|s| s.1).sum();
        losses.push(Loss::new(format!(
            "{bytes} bytes in {} stretch{} do not parse as ULog messages and were skipped to the next sync marker (first at byte {})",
            found.skipped.len(),
            if found.skipped.len() == 1 { "" } else { "es" },
            found.skipped[0].0
        )));
    }
    if found.orphans > 0 {
        losses.push(Loss::new(format!(
            "{} data messages belong to no subscription and were skipped",
            found.orphans
        )));
    }
    losses
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
    /// A subscription (`A`) or its end (`R`) met walking a part: `subs` follows it (the
    /// hop made every channel).
    fn follow(&self, ty: u8, body: &[u8], subs: &mut Subs) {
        match ty {
            b'A' => {
                if let Some((multi, id, name)) = subscription(body)
                    && let Some(&ch) = self.by_key.get(&(name.to_string(), multi))
                {
                    subs.set(id, ch);
                }
            }
            b'R' if body.len() >= 2 => {
                subs.set(u16::from_le_bytes([body[0], body[1]]), NO_CHANNEL);
            }
            _ => {}
        }
    }

    /// The window, start and subscriptions of part `part`.
    fn part_walk(&self, part: usize) -> Option<(Window<'_>, u64, Subs)> {
        let p = self.parts.get(part)?;
        let win = Window {
            data: self.map.bytes(),
            len: p.end,
        };
        Some((win, p.start, p.subs.clone()))
    }

    /// Walks part `part`, handing each message of a channel `want` accepts to `deliver`:
    /// its row for an IMU channel (a FIFO message gives several), `None` for another topic.
    /// Generic, not `dyn`, and `want` asked once per channel: this is the hot loop.
    fn walk_part(
        &self,
        part: usize,
        want: impl Fn(u32) -> bool,
        mut deliver: impl FnMut(u32, u64, Option<&Row>),
    ) -> crate::source::PartRead {
        let mut r = crate::source::PartRead::default();
        let wanted: Vec<bool> = (0..self.chans.len() as u32).map(want).collect();
        let Some((win, start, mut subs)) = self.part_walk(part) else {
            r.error = Some(format!("no part {part}"));
            return r;
        };
        walk(&win, start, self.appended_at, |_, ty, body| match ty {
            b'A' | b'R' => self.follow(ty, body, &mut subs),
            b'D' if body.len() >= 2 => {
                let ch = subs.get(u16::from_le_bytes([body[0], body[1]]));
                if !wanted.get(ch as usize).is_some_and(|&w| w) {
                    return; // NO_CHANNEL is past the table
                }
                let data = &body[2..];
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
                    r.skip_reason.get_or_insert_with(|| {
                        format!("'{}': {why}", self.contents.channels[ch as usize].topic)
                    });
                }
            }
            _ => {}
        });
        r
    }
}
