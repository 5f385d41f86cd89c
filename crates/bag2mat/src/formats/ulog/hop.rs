//! The serial hop over a ULog's messages: definitions and subscriptions read, every data
//! message checked ([`super::frame`]) and counted to its part, and every decision a walk past
//! damage takes recorded as an [`Event`] that the parts' parallel walks follow, so that they
//! read exactly what the hop counted. What damage costs is counted per topic: a message whose
//! id survives is that topic's loss; bytes that say nothing bound the messages they can hold
//! of each IMU topic whose size fits them.

use std::collections::{BTreeMap, HashMap};

use super::decoder::{Decoder, fifo_offset_ns};
use super::format::{Field, Formats, parse_format};
use super::frame::{self, Ctx, Frame};
use super::{Chan, HEADER_LEN, NO_CHANNEL, PART_BYTES, PartMap, Subs};
use crate::cursor::Cursor;

/// A decision of the hop at a message offset, for the parts' walks.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Event {
    /// Go on at this offset (bytes that are no message, or a message not to read).
    Skip(u64),
    /// A data message of channel `ch` whose header is damaged: its data (after the id) are
    /// `len` bytes from the offset + 5; the next message is at `next`.
    Data { ch: u32, len: u16, next: u64 },
    /// Message id `.0` is channel `.1` from this subscription (`A`) message on.
    Bind(u16, u32),
}

/// What the hop found lost or worked around, beyond the channels.
#[derive(Default)]
pub(super) struct Found {
    /// Dropouts the logger recorded: (latest record time then, ms).
    pub(super) dropouts: Vec<(u64, u16)>,
    /// Rows lost per (channel, why): (rows, first offset).
    pub(super) lost: BTreeMap<(u32, &'static str), (u64, u64)>,
    /// Per channel: the most rows unreadable bytes could have held of it.
    pub(super) bounds: BTreeMap<u32, u64>,
    /// Damage read through without a loss, by kind: (messages, first offset).
    pub(super) repaired: BTreeMap<&'static str, (u64, u64)>,
    /// Stretches of bytes that are no message: (count, bytes, first offset).
    pub(super) skipped: (u64, u64, u64),
    /// Data messages of an id no subscription names: (count, first offset, first id).
    pub(super) orphans: (u64, u64, u16),
    /// The file ends inside a message at this offset.
    pub(super) truncated: Option<u64>,
    /// The flag bits set incompatibility flags this reader does not know.
    pub(super) unknown_incompat: Option<[u8; 8]>,
}

impl Found {
    fn lose(&mut self, ch: u32, why: &'static str, rows: u64, at: u64) {
        let e = self.lost.entry((ch, why)).or_insert((0, at));
        e.0 += rows;
    }

    fn repair(&mut self, what: &'static str, at: u64) {
        self.repaired.entry(what).or_insert((0, at)).0 += 1;
    }
}

/// What counting one part's data messages finds.
#[derive(Default)]
pub(super) struct PartCount {
    /// Rows per channel (a FIFO message is several).
    pub(super) counts: Vec<u64>,
    /// The record times the part spans (a FIFO message from its oldest sample).
    pub(super) span: Option<(u64, u64)>,
    /// The integration intervals of each delta message (`vehicle_imu`): channel, the
    /// gyroscope's and the accelerometer's, µs.
    pub(super) deltas: Vec<(u32, f32, f32)>,
}

impl PartCount {
    /// Counts a data message of channel `ch` (`data`: after the id): its rows (a FIFO
    /// message is several, the oldest (n−1)·dt before its time) and the times spanned.
    /// `None`: it has no time stamp (not delivered).
    fn data(&mut self, ch: u32, data: &[u8], chans: &[Chan]) -> Option<u64> {
        let chan = chans.get(ch as usize)?;
        let t_us = chan.ts.and_then(|s| s.get_u64(data))?;
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
            return Some(t);
        }
        if self.counts.len() <= ch as usize {
            self.counts.resize(ch as usize + 1, 0);
        }
        self.counts[ch as usize] += rows;
        self.span = Some(
            self.span
                .map_or((first, t), |(a, b)| (a.min(first), b.max(t))),
        );
        Some(t)
    }
}

/// An `A` message: multi_id, message id, format name.
fn subscription(body: &[u8]) -> Option<(u8, u16, &str)> {
    let mut m = Cursor::new(body);
    let multi = m.le::<u8>("multi_id").ok()?;
    let id = m.le::<u16>("msg_id").ok()?;
    let n = m.remaining();
    Some((multi, id, m.str(n, "message name").ok()?))
}

/// A subscription that moved an id from one channel to another: undone when the data after
/// it fit the old channel and not the new one (the `A` message was damaged).
struct Rebound {
    old: u32,
    event: usize,
    next: u64,
}

/// What the serial hop over the messages finds.
pub(super) struct Hop {
    pub(super) formats: Formats,
    /// Earlier, different definitions of a format (a format defined twice).
    earlier: HashMap<String, Vec<Vec<Field>>>,
    pub(super) channels: Vec<crate::source::Channel>,
    pub(super) chans: Vec<Chan>,
    /// Each channel's data sizes (without the message id).
    sizes: Vec<Option<(usize, usize)>>,
    /// Data messages counted per channel (all parts).
    msgs: Vec<u64>,
    /// Data messages of each channel that did not fit its format.
    misfits: Vec<u64>,
    pub(super) by_key: HashMap<(String, u8), u32>,
    pub(super) parts: Vec<PartMap>,
    pub(super) events: Vec<(u64, Event)>,
    rebound: HashMap<u16, Rebound>,
    /// `rebound` as (id, old channel), for the checks of a chain of messages.
    rebound_list: Vec<(u16, u32)>,
    /// Dropouts, losses, repairs and a cut end.
    pub(super) found: Found,
    /// What each part's data messages hold.
    pub(super) counted: Vec<PartCount>,
    /// The latest record time logged so far (a dropout's time: its `O` message has none).
    latest: u64,
    appended_at: Option<u64>,
}

/// The hop: every message in file order, checked; the definitions, subscriptions and
/// dropouts read, each data message counted to its part ([`PartCount::data`]; bytes in the
/// cache line the header brought in, so the count costs little beside the check). Parts
/// start at data messages, every [`PART_BYTES`]; they are decoded in parallel, each from
/// the subscriptions at its start (replayed from the [`Event::Bind`]s).
pub(super) fn hop(bytes: &[u8]) -> Hop {
    let len = bytes.len() as u64;
    let mut h = Hop {
        formats: Formats {
            defs: HashMap::new(),
        },
        earlier: HashMap::new(),
        channels: Vec::new(),
        chans: Vec::new(),
        sizes: Vec::new(),
        msgs: Vec::new(),
        misfits: Vec::new(),
        by_key: HashMap::new(),
        parts: Vec::new(),
        events: Vec::new(),
        rebound: HashMap::new(),
        rebound_list: Vec::new(),
        found: Found::default(),
        counted: Vec::new(),
        latest: 0,
        appended_at: None,
    };
    let mut subs = Subs::default();
    let mut at = HEADER_LEN as u64;
    while at < len {
        // the hot path: a data message of a subscribed id that fits its format
        if let Some((size, ty)) = frame::header(bytes, at)
            && ty == b'D'
            && let Some(b) = frame::body(bytes, at, size as usize)
            && h.appended_at
                .is_none_or(|ap| at >= ap || at + 3 + size as u64 <= ap)
            && let Some(ch) = h.ctx(bytes, &subs).data_channel(b)
            && !h.rebound.contains_key(&u16::from_le_bytes([b[0], b[1]]))
        {
            h.count(at, ch, &b[2..]);
            at += 3 + size as u64;
            continue;
        }
        at = h.step(bytes, at, &mut subs);
    }
    if let Some(p) = h.parts.last_mut() {
        p.end = at.min(len);
    }
    h.part_subs();
    h
}

impl Hop {
    fn ctx<'a>(&'a self, bytes: &'a [u8], subs: &'a Subs) -> Ctx<'a> {
        Ctx {
            bytes,
            subs,
            formats: &self.formats,
            sizes: &self.sizes,
            rebound: &self.rebound_list,
        }
    }

    /// Forgets the re-binding of `id` (confirmed or undone).
    fn unbind_check(&mut self, id: u16) -> Option<Rebound> {
        let r = self.rebound.remove(&id)?;
        self.rebound_list.retain(|x| x.0 != id);
        Some(r)
    }

    /// A data message of channel `ch` at `m_at` (`data`: after the id), counted to its part
    /// (a new part when this one is [`PART_BYTES`] long).
    fn count(&mut self, m_at: u64, ch: u32, data: &[u8]) {
        if self
            .parts
            .last()
            .is_none_or(|p| m_at - p.start >= PART_BYTES)
        {
            if let Some(p) = self.parts.last_mut() {
                p.end = m_at;
            }
            self.parts.push(PartMap {
                start: m_at,
                end: u64::MAX,
                subs: Subs::default(),
                events: 0..0,
            });
            self.counted.push(PartCount::default());
        }
        if let Some(c) = self.counted.last_mut()
            && let Some(t) = c.data(ch, data, &self.chans)
        {
            self.latest = self.latest.max(t);
            self.msgs[ch as usize] += 1;
        }
    }

    /// Any message other than a plain whole data message at `at`: where the walk goes on.
    fn step(&mut self, bytes: &[u8], at: u64, subs: &mut Subs) -> u64 {
        let len = bytes.len() as u64;
        // a message cut by the start of appended data (the logger's DATA_APPENDED flag)
        if let Some(ap) = self.appended_at
            && at < ap
            && ap <= len
            && let Some((size, _)) = frame::header(bytes, at)
            && at + 3 + size as u64 > ap
        {
            self.events.push((at, Event::Skip(ap)));
            self.found
                .repair("a message cut by the start of appended data skipped", at);
            return ap;
        }
        match self.ctx(bytes, subs).frame(at) {
            Frame::Whole(ty, size) => {
                let next = at + 3 + size as u64;
                let body = frame::body(bytes, at, size as usize).unwrap_or(&[]);
                if ty == b'D' {
                    // a whole data message of an id a subscription re-bound
                    let id = u16::from_le_bytes([body[0], body[1]]);
                    self.unbind_check(id);
                    if let Some(ch) = self.ctx(bytes, subs).data_channel(body) {
                        self.count(at, ch, &body[2..]);
                    }
                } else {
                    self.definition(at, ty, body, subs, next);
                }
                next
            }
            // a size past the end: the file is cut there, unless whole messages follow
            Frame::Cut
                if frame::header(bytes, at).is_none()
                    || self.ctx(bytes, subs).resync(at) == len =>
            {
                self.cut(bytes, at, subs);
                len
            }
            Frame::Cut | Frame::Bad => self.damaged(bytes, at, subs),
        }
    }

    /// A message other than data at `m_at` (body `body`): what it defines or records.
    fn definition(&mut self, m_at: u64, ty: u8, body: &[u8], subs: &mut Subs, next: u64) {
        let mut m = Cursor::at(body, m_at + 3);
        match ty {
            b'B' => {
                // flag bits: compat[8], incompat[8], appended offsets[3]
                if let (Ok(_), Ok(incompat)) =
                    (m.take(8, "compat flags"), m.take(8, "incompat flags"))
                {
                    // bit 0 of byte 0 (data appended) is the only one the format defines
                    if incompat[0] & !1 != 0 || incompat[1..].iter().any(|&b| b != 0) {
                        let mut f = [0u8; 8];
                        f.copy_from_slice(incompat);
                        self.found.unknown_incompat = Some(f);
                    }
                    if incompat[0] & 1 != 0
                        && let Ok(off) = m.le::<u64>("appended offset")
                        && off > 0
                    {
                        self.appended_at = Some(off);
                    }
                }
            }
            b'F' => {
                if let Some((name, fields)) =
                    std::str::from_utf8(m.rest()).ok().and_then(parse_format)
                {
                    match self.formats.defs.insert(name.clone(), fields) {
                        Some(old) if self.formats.defs.get(&name) != Some(&old) => {
                            self.found.repair(
                                "a format defined a second time, differently (the definition its messages fit is used)",
                                m_at,
                            );
                            self.earlier.entry(name).or_default().push(old);
                        }
                        _ => {}
                    }
                }
            }
            b'A' => {
                if let Some((multi, id, name)) = subscription(body) {
                    let ch = self.channel(name, multi);
                    let old = subs.get(id);
                    subs.set(id, ch);
                    self.events.push((m_at, Event::Bind(id, ch)));
                    if old != NO_CHANNEL && old != ch {
                        self.rebound_list.retain(|x| x.0 != id);
                        self.rebound_list.push((id, old));
                        self.rebound.insert(
                            id,
                            Rebound {
                                old,
                                event: self.events.len() - 1,
                                next,
                            },
                        );
                    }
                }
            }
            b'O' => {
                if let Ok(ms) = m.le::<u16>("dropout duration") {
                    self.found.dropouts.push((self.latest, ms));
                }
            }
            // info, parameters, log text, sync; a remove (`R`) is not followed, as pyulog
            // does not (PX4's logger writes none: a damaged data message is one)
            _ => {}
        }
    }

    /// The channel of topic `name` instance `multi`, made at its first subscription.
    fn channel(&mut self, name: &str, multi: u8) -> u32 {
        let key = (name.to_string(), multi);
        if let Some(&ch) = self.by_key.get(&key) {
            return ch;
        }
        let ch = self.channels.len() as u32;
        self.channels.push(crate::source::Channel {
            id: ch,
            topic: format!("{name}:{multi}"),
            msg_type: Decoder::msg_type(name),
            encoding: crate::source::Encoding::Other("ulog".into()),
            md5sum: None,
            count: Some(0),
        });
        self.chans.push(Chan {
            decoder: None,
            ts: None,
        });
        self.sizes.push(None);
        self.msgs.push(0);
        self.misfits.push(0);
        self.by_key.insert(key, ch);
        self.define(ch, name);
        ch
    }

    /// Channel `ch` of format `name` read by the format's current definition.
    fn define(&mut self, ch: u32, name: &str) {
        let slots = self.formats.slots(name);
        let decoder = slots.as_ref().and_then(|s| Decoder::for_topic(name, s));
        let c = &mut self.channels[ch as usize];
        c.encoding = if decoder.is_some() {
            crate::source::Encoding::Row
        } else {
            crate::source::Encoding::Other("ulog".into())
        };
        self.chans[ch as usize] = Chan {
            ts: slots.as_ref().and_then(|s| s.get("timestamp").copied()),
            decoder,
        };
        self.sizes[ch as usize] = self.formats.data_sizes(name);
    }

    /// The format name of channel `ch`.
    fn format_of(&self, ch: u32) -> Option<String> {
        self.by_key
            .iter()
            .find(|(_, c)| **c == ch)
            .map(|((n, _), _)| n.clone())
    }

    /// A channel with no message yet whose messages fit an earlier definition of its
    /// format and not the current one: read by that definition from now on.
    fn refit(&mut self, ch: u32, data_len: usize) -> bool {
        if self.msgs.get(ch as usize) != Some(&0) {
            return false;
        }
        let Some(name) = self.format_of(ch) else {
            return false;
        };
        let Some(alts) = self.earlier.get(&name) else {
            return false;
        };
        for alt in alts.clone().into_iter().rev() {
            let cur = self.formats.defs.insert(name.clone(), alt.clone());
            let fits = self
                .formats
                .data_sizes(&name)
                .is_some_and(|(lo, hi)| (lo..=hi).contains(&data_len));
            if fits {
                self.define(ch, &name);
                if let Some(cur) = cur {
                    self.formats.defs.insert(name.clone(), cur);
                }
                return true;
            }
            if let Some(cur) = cur {
                self.formats.defs.insert(name.clone(), cur);
            }
        }
        false
    }

    /// Rows a lost data message of channel `ch` held (`data`: after the id, if known).
    fn rows_of(&self, ch: u32, data: Option<&[u8]>) -> u64 {
        match &self.chans.get(ch as usize).and_then(|c| c.decoder.as_ref()) {
            Some(d @ Decoder::Fifo { v, .. }) => {
                data.map_or(v[0].len(), |x| d.rows_in(x).max(1)) as u64
            }
            _ => 1,
        }
    }

    /// A message at `at` that is not whole: read through its damage where its content
    /// allows, else skipped to the next whole messages with what it held counted.
    fn damaged(&mut self, bytes: &[u8], at: u64, subs: &mut Subs) -> u64 {
        let len = bytes.len() as u64;
        let Some((size, ty)) = frame::header(bytes, at) else {
            self.cut(bytes, at, subs);
            return len;
        };
        let next = at + 3 + size as u64;
        let body = frame::body(bytes, at, size as usize);
        // whole messages start inside it: its size is damaged (it would swallow them)
        let swallows = self.ctx(bytes, subs).resync(at) < next;
        if let Some(b) = body
            && b.len() >= 2
        {
            let id = u16::from_le_bytes([b[0], b[1]]);
            let stated = subs.get(id);
            let data_len = b.len() - 2;
            let framed = !swallows && self.ctx(bytes, subs).chain(next);
            if ty == b'D' && framed {
                // its size frames it: its id, its subscription or its format is off
                if stated != NO_CHANNEL {
                    self.misfits[stated as usize] += 1;
                }
                if self
                    .rebound
                    .get(&id)
                    .is_some_and(|r| self.fits(r.old, data_len))
                    && let Some(r) = self.unbind_check(id)
                {
                    // the subscription before it was damaged: undone
                    subs.set(id, r.old);
                    self.events[r.event].1 = Event::Skip(r.next);
                    self.found.repair(
                        "a subscription (A) the data after it contradict ignored",
                        self.events[r.event].0,
                    );
                    self.count(at, r.old, &b[2..]);
                    return next;
                }
                if stated != NO_CHANNEL && self.refit(stated, data_len) {
                    self.found.repair(
                        "a format defined a second time, differently (the definition its messages fit is used)",
                        at,
                    );
                    self.count(at, stated, &b[2..]);
                    return next;
                }
                if let Some(ch) = self.other_fit(subs, stated, data_len) {
                    self.found.repair(
                        "a data message with a damaged message id read by its size",
                        at,
                    );
                    return self.recovered(at, ch, b, data_len, next);
                }
                if stated != NO_CHANNEL {
                    let rows = self.rows_of(stated, Some(&b[2..]));
                    self.found
                        .lose(stated, "do not fit their format's size", rows, at);
                } else {
                    self.orphan(at, id, data_len);
                }
                self.events.push((at, Event::Skip(next)));
                return next;
            }
            if ty != b'D' && framed {
                // a data message whose type byte is damaged
                if let Some(ch) = self.ctx(bytes, subs).data_channel(b) {
                    self.found
                        .repair("a data message with a damaged type byte read as data", at);
                    return self.recovered(at, ch, b, data_len, next);
                }
            }
        }
        // a data message whose size field is damaged (also one past the end of the file):
        // the sizes its format allows
        let a = at as usize;
        if ty == b'D'
            && let Some(idb) = bytes.get(a + 3..a + 5)
            && let stated = subs.get(u16::from_le_bytes([idb[0], idb[1]]))
            && stated != NO_CHANNEL
            && let Some((lo, hi)) = self.sizes[stated as usize]
        {
            for n in lo..=hi.min(lo + 64) {
                let nx = at + 5 + n as u64;
                if nx <= len && nx != next && self.ctx(bytes, subs).chain(nx) {
                    self.found.repair(
                        "a data message with a damaged size read by its format's size",
                        at,
                    );
                    let full = &bytes[a + 3..nx as usize];
                    return self.recovered(at, stated, full, n, nx);
                }
            }
        }
        let ctx = self.ctx(bytes, subs);
        if ty != b'D' && !swallows && ctx.skippable(at, ty, size) {
            // a message of no known type, or a damaged one, skipped by its size (pyulog's
            // rule for a type it does not know)
            self.found.repair(
                if super::IS_TYPE[ty as usize] {
                    "a damaged message (not what its type holds) skipped"
                } else {
                    "a message of a type the format does not have skipped"
                },
                at,
            );
            // it may have been a data message of an IMU channel its size fits
            if size >= 2 {
                for ch in 0..self.chans.len() as u32 {
                    if self.chans[ch as usize].decoder.is_some() && self.fits(ch, size as usize - 2)
                    {
                        let rows = self.rows_of(ch, None);
                        *self.found.bounds.entry(ch).or_default() += rows;
                    }
                }
            }
            self.events.push((at, Event::Skip(next)));
            return next;
        }
        let ctx = self.ctx(bytes, subs);
        let to = ctx.resync(at);
        self.stretch(bytes, at, to, subs);
        self.events.push((at, Event::Skip(to)));
        to
    }

    /// True when `data_len` bytes of data fit channel `ch`'s format.
    fn fits(&self, ch: u32, data_len: usize) -> bool {
        matches!(self.sizes.get(ch as usize), Some(Some((lo, hi))) if (*lo..=*hi).contains(&data_len))
    }

    /// The one subscribed channel other than `stated` whose format `data_len` bytes fit,
    /// unless `stated` is subscribed and fits none of its messages (its format is off, not
    /// this message's id).
    fn other_fit(&self, subs: &Subs, stated: u32, data_len: usize) -> Option<u32> {
        // a channel none of whose messages fit: its format is off, not their ids (the first
        // one is taken for a damaged id)
        if stated != NO_CHANNEL
            && self.msgs.get(stated as usize) == Some(&0)
            && self.misfits.get(stated as usize).is_some_and(|&n| n > 1)
        {
            return None;
        }
        // an id no subscription names: any channel (its subscription may be what was lost)
        let candidates: Vec<u32> = if stated == NO_CHANNEL {
            (0..self.chans.len() as u32).collect()
        } else {
            subs.channels()
        };
        let mut found = None;
        for ch in candidates {
            if ch != stated && self.fits(ch, data_len) {
                if found.is_some_and(|f| f != ch) {
                    return None;
                }
                found = Some(ch);
            }
        }
        found
    }

    /// A data message of channel `ch` read through its damaged header (`b`: id and data).
    fn recovered(&mut self, at: u64, ch: u32, b: &[u8], data_len: usize, next: u64) -> u64 {
        self.events.push((
            at,
            Event::Data {
                ch,
                len: data_len as u16,
                next,
            },
        ));
        self.count(at, ch, &b[2..2 + data_len]);
        next
    }

    /// A whole data message of an id no subscription names (`data_len` bytes of data):
    /// skipped; it may be a message of an IMU channel its size fits.
    fn orphan(&mut self, at: u64, id: u16, data_len: usize) {
        let o = &mut self.found.orphans;
        if o.0 == 0 {
            (o.1, o.2) = (at, id);
        }
        o.0 += 1;
        for ch in 0..self.chans.len() as u32 {
            if self.chans[ch as usize].decoder.is_some() && self.fits(ch, data_len) {
                let rows = self.rows_of(ch, None);
                *self.found.bounds.entry(ch).or_default() += rows;
            }
        }
    }

    /// The file ends inside the message at `at`: a data message of a known channel is that
    /// channel's loss; one of unknown channel may be one of each IMU channel it fits.
    fn cut(&mut self, bytes: &[u8], at: u64, subs: &Subs) {
        self.found.truncated = Some(at);
        let h = frame::header(bytes, at);
        if let Some((_, ty)) = h
            && ty != b'D'
        {
            return;
        }
        let a = at as usize;
        if let Some(id) = bytes.get(a + 3..a + 5) {
            let ch = subs.get(u16::from_le_bytes([id[0], id[1]]));
            if ch != NO_CHANNEL {
                if self.chans[ch as usize].decoder.is_some() {
                    let rows = self.rows_of(ch, None);
                    self.found.lose(ch, "cut by the end of the file", rows, at);
                }
                return;
            }
        }
        for ch in 0..self.chans.len() as u32 {
            let size_fits = h.is_none_or(|(size, _)| size < 2 || self.fits(ch, size as usize - 2));
            if self.chans[ch as usize].decoder.is_some() && size_fits {
                let rows = self.rows_of(ch, None);
                *self.found.bounds.entry(ch).or_default() += rows;
            }
        }
    }

    /// Bytes `at..to` that are no message: the data messages of a known channel whose
    /// header survives in them are that channel's losses; the rest may hold messages of each
    /// IMU channel, as many as fit.
    fn stretch(&mut self, bytes: &[u8], at: u64, to: u64, subs: &Subs) {
        let s = &mut self.found.skipped;
        if s.0 == 0 {
            s.2 = at;
        }
        s.0 += 1;
        s.1 += to - at;
        let mut unaccounted = to - at;
        let mut q = at;
        // the damaged message itself, when its header still names a channel (its id, and
        // a size its format allows)
        if let Some((size, b'D')) = frame::header(bytes, at)
            && let Some(id) = bytes.get(at as usize + 3..at as usize + 5)
        {
            let ch = subs.get(u16::from_le_bytes([id[0], id[1]]));
            if ch != NO_CHANNEL && size >= 2 && self.fits(ch, size as usize - 2) {
                let rows = self.rows_of(ch, None);
                self.found.lose(ch, "are damaged beyond reading", rows, at);
                let min = self.sizes[ch as usize].map_or(0, |s| s.0) as u64 + 5;
                unaccounted = unaccounted.saturating_sub(min);
                q = at + 3;
            }
        }
        while q < to {
            if q > at
                && let Some((size, b'D')) = frame::header(bytes, q)
                && q + 3 + size as u64 <= to
                && let Some(b) = frame::body(bytes, q, size as usize)
                && let Some(ch) = self.ctx(bytes, subs).data_channel(b)
            {
                let rows = self.rows_of(ch, Some(&b[2..]));
                self.found.lose(ch, "are damaged beyond reading", rows, q);
                unaccounted = unaccounted.saturating_sub(3 + size as u64);
                q += 3 + size as u64;
                continue;
            }
            q += 1;
        }
        for ch in 0..self.chans.len() as u32 {
            if self.chans[ch as usize].decoder.is_none() {
                continue;
            }
            if let Some((lo, _)) = self.sizes[ch as usize] {
                // a part of a message is a message lost too
                let k = unaccounted.div_ceil(lo as u64 + 5);
                if k > 0 {
                    let rows = k * self.rows_of(ch, None);
                    *self.found.bounds.entry(ch).or_default() += rows;
                }
            }
        }
    }

    /// Each part's subscriptions at its start and its events, replayed from the events.
    fn part_subs(&mut self) {
        let mut subs = Subs::default();
        let mut k = 0;
        for p in &mut self.parts {
            while k < self.events.len() && self.events[k].0 < p.start {
                if let Event::Bind(id, ch) = self.events[k].1 {
                    subs.set(id, ch);
                }
                k += 1;
            }
            p.subs = subs.clone();
            let first = k;
            let end = self.events[k..].partition_point(|e| e.0 < p.end) + k;
            p.events = first..end;
        }
    }
}
