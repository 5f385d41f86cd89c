//! ArduPilot DataFlash logs (`.bin`): messages `0xA3 0x95 type payload`, each type defined
//! by an `FMT` message (type 128: `Type B, Length B, Name n, Format N, Columns Z`). Read as
//! topics like a bag's (named `name`, or `name:k` when the log has several instances):
//!
//! * `IMU` per instance (`I` column; the older `IMU2`/`IMU3` messages are instances 1, 2):
//!   `GyrX..GyrZ` rad/s, `AccX..AccZ` m/s² at `TimeUS`.
//! * `ISB_ACC`, `ISB_GYR` per instance: the high-rate batch sampler — an `ISBH` header
//!   (`N`, sensor `type` 0 accel / 1 gyro, `instance`, `mul`, `smp_cnt`, `SampleUS`,
//!   `smp_rate`) and its `ISBD` data (`seqno`, 32 int16 samples per axis): sample `j` is
//!   `raw / mul` at `SampleUS + j / smp_rate`; the other sensor's columns are NaN.
//!
//! Every other message with a leading `TimeUS` is listed with its times. Bytes that are no
//! message are skipped to the next header and reported; batch data without its header, and
//! batches with fewer samples than their header promises, are losses.

use crate::shared::note::Note;

mod batch;
mod imu;
// The synthetic-log writers of the tests and benchmarks (re-exported by `test_tools`).
#[cfg(any(test, feature = "test-support"))]
pub(crate) mod write;

use std::collections::HashMap;
use std::path::Path;

use crate::cursor::Cursor;
use crate::decoded::{DecodedSource, Stream};
use crate::error::Error;
use crate::rows::Row;
use crate::source::{InputKind, Loss};

/// The two bytes every message starts with.
pub const HEAD: [u8; 2] = [0xA3, 0x95];
/// The type of `FMT` messages.
pub const FMT_TYPE: u8 = 128;
/// Length of an `FMT` message, header included.
pub const FMT_LEN: usize = 89;
/// Samples per axis in one `ISBD` message.
pub const ISBD_SAMPLES: usize = 32;

/// The bytes a format character takes.
pub(crate) fn char_size(c: u8) -> Option<usize> {
    Some(match c {
        b'b' | b'B' | b'M' => 1,
        b'h' | b'H' | b'c' | b'C' => 2,
        b'i' | b'I' | b'e' | b'E' | b'L' | b'f' | b'n' => 4,
        b'd' | b'q' | b'Q' => 8,
        b'N' => 16,
        b'Z' | b'a' => 64,
        _ => return None,
    })
}

/// A message type an `FMT` defined.
#[derive(Debug, Clone)]
struct Def {
    name: String,
    /// Bytes of a message, header included: what its format string adds up to.
    len: usize,
    /// The `FMT`'s length byte when it says otherwise (one of the two is damaged: the
    /// first message of the type decides, by where the next message starts).
    stated: Option<usize>,
    /// Column name → (offset in the payload, format character).
    cols: HashMap<String, (usize, u8)>,
    /// The first column is `TimeUS`.
    time: bool,
    /// The format string does not fill the messages: their columns cannot be read.
    broken: bool,
}

impl Def {
    fn parse(name: &str, fmt: &str, columns: &str, stated: usize) -> Option<Def> {
        let names: Vec<&str> = columns.split(',').collect();
        let mut cols = HashMap::new();
        let mut off = 0;
        for (i, c) in fmt.bytes().enumerate() {
            let s = char_size(c)?;
            if let Some(n) = names.get(i) {
                cols.insert(n.to_string(), (off, c));
            }
            off += s;
        }
        let len = off + 3;
        (len <= u8::MAX as usize && !name.is_empty()).then(|| Def {
            name: name.to_string(),
            len,
            stated: (stated != len && stated >= 3).then_some(stated),
            time: names.first() == Some(&"TimeUS") && fmt.starts_with('Q'),
            cols,
            broken: false,
        })
    }

    /// Column `name` as f64 (scaled types as ArduPilot defines them).
    fn get(&self, p: &[u8], name: &str) -> Option<f64> {
        let &(off, c) = self.cols.get(name)?;
        let mut k = Cursor::new(p.get(off..)?);
        Some(match c {
            b'b' => k.le::<i8>("").ok()? as f64,
            b'B' | b'M' => k.le::<u8>("").ok()? as f64,
            b'h' => k.le::<i16>("").ok()? as f64,
            b'H' => k.le::<u16>("").ok()? as f64,
            b'c' => k.le::<i16>("").ok()? as f64 * 0.01,
            b'C' => k.le::<u16>("").ok()? as f64 * 0.01,
            b'i' | b'L' => k.le::<i32>("").ok()? as f64,
            b'I' => k.le::<u32>("").ok()? as f64,
            b'e' => k.le::<i32>("").ok()? as f64 * 0.01,
            b'E' => k.le::<u32>("").ok()? as f64 * 0.01,
            b'f' => k.le::<f32>("").ok()? as f64,
            b'd' => k.le::<f64>("").ok()?,
            b'q' => k.le::<i64>("").ok()? as f64,
            b'Q' => k.le::<u64>("").ok()? as f64,
            _ => return None,
        })
    }

    fn get_u64(&self, p: &[u8], name: &str) -> Option<u64> {
        let &(off, c) = self.cols.get(name)?;
        let mut k = Cursor::new(p.get(off..)?);
        match c {
            b'Q' => k.le::<u64>("").ok(),
            b'q' => k.le::<i64>("").ok().and_then(|v| u64::try_from(v).ok()),
            _ => self.get(p, name).filter(|v| *v >= 0.0).map(|v| v as u64),
        }
    }

    /// An `a` column: 32 int16, and how many of them `p` holds (a message cut short holds
    /// fewer).
    fn array(&self, p: &[u8], name: &str) -> Option<([i16; ISBD_SAMPLES], usize)> {
        let &(off, c) = self.cols.get(name)?;
        if c != b'a' {
            return None;
        }
        let mut k = Cursor::new(p.get(off..)?);
        let mut v = [0i16; ISBD_SAMPLES];
        let mut n = 0;
        for x in &mut v {
            let Ok(y) = k.le::<i16>("") else { break };
            *x = y;
            n += 1;
        }
        (n > 0).then_some((v, n))
    }
}

/// Opens a DataFlash log.
pub(crate) fn open(path: &Path) -> Result<DecodedSource, Error> {
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    read(path, &bytes)
}

/// Reads a DataFlash log held in memory: message by message, each one's end checked
/// against the next message's header (DataFlash has no checksum): a message the next
/// header starts inside is cut short (counted lost), one whose header is damaged is read by
/// the type its length fits, and bytes that are no message are skipped to the next header
/// with what they held counted.
pub(crate) fn read(path: &Path, bytes: &[u8]) -> Result<DecodedSource, Error> {
    let mut r = Reader::default();
    let len = bytes.len();
    let mut i = 0usize;
    while i + 3 <= len {
        i = r.step(bytes, i);
    }
    if i < len && HEAD.starts_with(&bytes[i..]) {
        // the file ends inside a message's header: of any type (an IMU message may be it)
        r.truncated = Some(i);
        r.imu_unknown += 1;
    }
    r.finish(path)
}

/// What reading a log has gathered: the definitions, the topics, the IMU messages and
/// batches (put together at the end), and what was lost.
#[derive(Default)]
struct Reader {
    defs: HashMap<u8, Def>,
    /// The times-only topics (every message with a `TimeUS` but IMU and batches).
    streams: Vec<Stream>,
    by_key: HashMap<String, usize>,
    imu: Vec<imu::Msg>,
    batches: batch::Batches,
    /// Stretches of bytes that are no message: count, bytes, first offset.
    skipped: (u64, u64, usize),
    /// IMU messages lost whose instance is known: instance → (count, first offset).
    imu_lost: HashMap<u32, (u64, usize)>,
    /// IMU messages (or bytes that may have held some) whose instance is not known.
    imu_unknown: u64,
    /// Repairs by kind: (count, first offset).
    repaired: Vec<(&'static str, u64, usize)>,
    truncated: Option<usize>,
}

fn repaired(r: &mut Vec<(&'static str, u64, usize)>, what: &'static str, at: usize) {
    match r.iter_mut().find(|x| x.0 == what) {
        Some(x) => x.1 += 1,
        None => r.push((what, 1, at)),
    }
}

impl Reader {
    /// The length of a message of type `ty`, if the type is defined.
    fn len_of(&self, ty: u8) -> Option<usize> {
        if ty == FMT_TYPE {
            return Some(FMT_LEN);
        }
        self.defs.get(&ty).map(|d| d.len)
    }

    /// The length of the message whose header is at `i`, if its header is one.
    fn header(&self, bytes: &[u8], i: usize) -> Option<usize> {
        let h = bytes.get(i..i + 3)?;
        (h[..2] == HEAD).then(|| self.len_of(h[2])).flatten()
    }

    /// True when a message may end at `e`: the end of the file, or a header there.
    fn ends_at(&self, bytes: &[u8], e: usize) -> bool {
        e == bytes.len() || (e < bytes.len() && self.header(bytes, e).is_some())
    }

    /// True when a whole message starts at `j` and another (or the end) follows it.
    fn whole_at(&self, bytes: &[u8], j: usize) -> bool {
        self.header(bytes, j)
            .is_some_and(|l| j + l <= bytes.len() && self.ends_at(bytes, j + l))
    }

    /// The message at `i`, read or skipped: where the next one starts.
    fn step(&mut self, bytes: &[u8], i: usize) -> usize {
        let len = bytes.len();
        let ty = bytes[i + 2];
        // an FMT length byte that contradicts its format string: the first message decides
        if bytes[i..i + 2] == HEAD
            && let Some(d) = self.defs.get(&ty)
            && let Some(stated) = d.stated
        {
            let computed = d.len;
            let by_format = i + computed <= len && self.ends_at(bytes, i + computed);
            let by_byte = i + stated <= len && self.ends_at(bytes, i + stated);
            let Some(d) = self.defs.get_mut(&ty) else {
                return i + 1;
            };
            d.stated = None;
            if !by_format && by_byte {
                d.len = stated;
                d.broken = true;
                repaired(
                    &mut self.repaired,
                    "a message type whose FMT format does not fill its messages (its columns are not read)",
                    i,
                );
            } else {
                repaired(
                    &mut self.repaired,
                    "an FMT whose length byte is damaged read by its format",
                    i,
                );
            }
        }
        match self.header(bytes, i) {
            Some(l) if i + l <= len && self.ends_at(bytes, i + l) => {
                self.message(ty, &bytes[i + 3..i + l], i);
                i + l
            }
            Some(l) => {
                // the next header is not where this message ends: cut short (a header
                // starts inside it), of another type (a damaged type byte), or whole with
                // damage after it
                if let Some(j) = (i + 3..(i + l).min(len)).find(|&j| self.whole_at(bytes, j)) {
                    // a message of another type whose type byte is damaged, or one cut short
                    if let Some(t2) = self.type_of_len(j - i, ty) {
                        repaired(
                            &mut self.repaired,
                            "a message with a damaged type byte read as the type its length fits",
                            i,
                        );
                        self.message(t2, &bytes[i + 3..j], i);
                    } else {
                        self.short_message(bytes, i, j);
                    }
                    return j;
                }
                if i + l > len {
                    self.cut(bytes, i);
                    return len;
                }
                if let Some((t2, l2)) = self.other_type(bytes, i, ty) {
                    repaired(
                        &mut self.repaired,
                        "a message with a damaged type byte read as the type its length fits",
                        i,
                    );
                    self.message(t2, &bytes[i + 3..i + l2], i);
                    return i + l2;
                }
                self.message(ty, &bytes[i + 3..i + l], i);
                i + l
            }
            None => {
                // damaged sync bytes: the type's length still frames the message
                if let Some(l) = self.len_of(ty)
                    && i + l <= len
                    && self.ends_at(bytes, i + l)
                {
                    repaired(
                        &mut self.repaired,
                        "a message with damaged header bytes read by its type",
                        i,
                    );
                    self.message(ty, &bytes[i + 3..i + l], i);
                    return i + l;
                }
                let to = (i + 1..len)
                    .find(|&j| self.whole_at(bytes, j))
                    .unwrap_or(len);
                self.stretch(bytes, i, to);
                to
            }
        }
    }

    /// The one defined type other than `ty` whose messages are `l` bytes long.
    fn type_of_len(&self, l: usize, ty: u8) -> Option<u8> {
        let mut found = None;
        for (&t, d) in &self.defs {
            if t != ty && d.len == l && !d.broken {
                if found.is_some() {
                    return None;
                }
                found = Some(t);
            }
        }
        found
    }

    /// The one defined type other than `ty` whose length makes the message at `i` end where
    /// a header starts.
    fn other_type(&self, bytes: &[u8], i: usize, ty: u8) -> Option<(u8, usize)> {
        let mut found = None;
        for (&t, d) in &self.defs {
            if t != ty && i + d.len < bytes.len() && self.header(bytes, i + d.len).is_some() {
                if found.is_some() {
                    return None;
                }
                found = Some((t, d.len));
            }
        }
        found
    }

    /// The message at `i` (type by its header) that ends early at `j`: lost, counted on its
    /// IMU instance when its bytes still say which.
    fn lost_message(&mut self, bytes: &[u8], i: usize, j: usize) {
        let ty = bytes[i + 2];
        let Some(d) = self.defs.get(&ty) else {
            return;
        };
        if matches!(d.name.as_str(), "IMU" | "IMU2" | "IMU3") {
            let inst = match d.cols.get("I") {
                Some(&(off, _)) if i + 3 + off < j => Some(bytes[i + 3 + off] as u32),
                Some(_) => None,
                None => Some(match d.name.as_str() {
                    "IMU2" => 1,
                    "IMU3" => 2,
                    _ => 0,
                }),
            };
            match inst {
                Some(k) => {
                    let e = self.imu_lost.entry(k).or_insert((0, i));
                    e.0 += 1;
                }
                None => self.imu_unknown += 1,
            }
        }
        // a batch data message lost shows in its batch's count
    }

    /// The file ends inside the message at `i`.
    fn cut(&mut self, bytes: &[u8], i: usize) {
        self.truncated = Some(i);
        self.short_message(bytes, i, bytes.len());
    }

    /// The message at `i` that ends early at `j` (the next message starts inside it, or the
    /// file ends): an IMU message whose columns are all there is read (as DFReader reads
    /// it), else it is lost.
    fn short_message(&mut self, bytes: &[u8], i: usize, j: usize) {
        let ty = bytes[i + 2];
        let before = self.imu.len();
        if let Some(d) = self.defs.get(&ty)
            && !d.broken
        {
            let d = d.clone();
            match d.name.as_str() {
                "IMU" | "IMU2" | "IMU3" => {
                    let t_us = if d.time {
                        d.get_u64(&bytes[i + 3..j], "TimeUS")
                    } else {
                        None
                    };
                    self.imu(&d, &bytes[i + 3..j], &d.name, t_us, i);
                }
                // the samples whose three values it still holds (its batch counts the rest)
                "ISBD" => self.batches.data(&d, &bytes[i + 3..j], i),
                _ => {}
            }
        }
        if self.imu.len() > before {
            repaired(
                &mut self.repaired,
                "an IMU message cut short read from the columns it still holds",
                i,
            );
        } else {
            self.lost_message(bytes, i, j);
        }
    }

    /// Bytes `i..to` that are no message: messages of a defined type whose header is
    /// damaged when their lengths fill the stretch, else as many IMU messages as fit.
    fn stretch(&mut self, bytes: &[u8], i: usize, to: usize) {
        let s = &mut self.skipped;
        if s.0 == 0 {
            s.2 = i;
        }
        s.0 += 1;
        s.1 += (to - i) as u64;
        // one message whose header is damaged: its type byte's length fills the stretch
        if let Some(l) = self.len_of(bytes[i + 2.min(to - i - 1)])
            && l == to - i
        {
            self.lost_message(bytes, i, to);
            return;
        }
        let imu_len = self
            .defs
            .values()
            .filter(|d| d.name == "IMU")
            .map(|d| d.len)
            .min();
        if let Some(l) = imu_len {
            self.imu_unknown += (to - i).div_ceil(l) as u64;
        }
    }

    /// The topic of a times-only message `name`, made at its first message.
    fn stream(&mut self, name: &str) -> usize {
        let streams = &mut self.streams;
        *self.by_key.entry(name.to_string()).or_insert_with(|| {
            streams.push(Stream::other(
                format!("{name}:0"),
                format!("ardupilot/{name}"),
            ));
            streams.len() - 1
        })
    }

    /// One message of type `ty`, payload `p`, at `at`.
    fn message(&mut self, ty: u8, p: &[u8], at: usize) {
        if ty == FMT_TYPE {
            self.format(p);
            return;
        }
        // the definitions are only read here: out of `self` for the call (no copy)
        let defs = std::mem::take(&mut self.defs);
        if let Some(d) = defs.get(&ty)
            && !d.broken
        {
            let t_us = if d.time { d.get_u64(p, "TimeUS") } else { None };
            match d.name.as_str() {
                name @ ("IMU" | "IMU2" | "IMU3") => self.imu(d, p, name, t_us, at),
                "ISBH" => self.batches.header(d, p, at),
                "ISBD" => self.batches.data(d, p, at),
                name => {
                    if let Some(t) = t_us {
                        let s = self.stream(name);
                        self.streams[s].push_time(t.saturating_mul(1000));
                    }
                }
            }
        } else if let Some(d) = defs.get(&ty)
            && matches!(d.name.as_str(), "IMU" | "IMU2" | "IMU3")
        {
            self.imu_unknown += 1;
        }
        self.defs = defs;
    }

    /// An `FMT` message: a definition (one that redefines `FMT` itself is ignored).
    fn format(&mut self, p: &[u8]) {
        let mut c = Cursor::new(p);
        let parsed = (|| -> Option<(u8, usize, String, String, String)> {
            let t = c.le::<u8>("type").ok()?;
            let l = c.le::<u8>("length").ok()? as usize;
            let text = |c: &mut Cursor, n| -> Option<String> {
                let b = c.take(n, "text").ok()?;
                let b = &b[..b.iter().position(|&x| x == 0).unwrap_or(b.len())];
                Some(String::from_utf8_lossy(b).into_owned())
            };
            Some((t, l, text(&mut c, 4)?, text(&mut c, 16)?, text(&mut c, 64)?))
        })();
        if let Some((t, l, name, fmt, cols)) = parsed
            && t != FMT_TYPE
            && let Some(d) = Def::parse(&name, &fmt, &cols, l)
        {
            self.defs.insert(t, d);
        }
    }

    /// An `IMU` (`IMU2`, `IMU3`) message: a row of its instance, kept for the repair of
    /// damaged instance bytes ([`imu::repair`]).
    fn imu(&mut self, d: &Def, p: &[u8], name: &str, t_us: Option<u64>, at: usize) {
        let inst = match d.get(p, "I") {
            Some(k) => k as u32,
            None => match name {
                "IMU2" => 1,
                "IMU3" => 2,
                _ => 0,
            },
        };
        let row = || {
            Some(Row {
                stamp: 0,
                gyro: [d.get(p, "GyrX")?, d.get(p, "GyrY")?, d.get(p, "GyrZ")?],
                acc: [d.get(p, "AccX")?, d.get(p, "AccY")?, d.get(p, "AccZ")?],
            })
        };
        let (Some(t_us), Some(row)) = (t_us, row()) else {
            return;
        };
        self.imu.push(imu::Msg {
            at,
            t_us,
            inst,
            row,
        });
    }

    /// The source: the topics, and what was lost said as losses and notes.
    fn finish(mut self, path: &Path) -> Result<DecodedSource, Error> {
        if self.defs.is_empty() {
            return Err(Error::Corrupt {
                path: path.to_path_buf(),
                offset: 0,
                what: "DataFlash: no FMT message could be read".into(),
            });
        }
        let fixed = imu::repair(&mut self.imu);
        self.batches.finish();
        // IMU instances, then batches, then the times-only topics
        let mut streams: Vec<Stream> = Vec::new();
        let mut imu_of: HashMap<u32, usize> = HashMap::new();
        let mut insts: Vec<u32> = self.imu.iter().map(|m| m.inst).collect();
        insts.sort_unstable();
        insts.dedup();
        for &k in &insts {
            imu_of.insert(k, streams.len());
            streams.push(Stream::imu(format!("IMU:{k}"), "ardupilot/IMU"));
        }
        for m in std::mem::take(&mut self.imu) {
            let t = m.t_us.saturating_mul(1000);
            streams[imu_of[&m.inst]].push(t, &Row { stamp: t, ..m.row });
        }
        let mut isb_of: HashMap<batch::Key, usize> = HashMap::new();
        for (key, samples) in std::mem::take(&mut self.batches.samples) {
            let name = if key.0 == 1 { "ISB_GYR" } else { "ISB_ACC" };
            isb_of.insert(key, streams.len());
            let mut s = Stream::imu(format!("{name}:{}", key.1), "ardupilot/ISB");
            s.reserve(samples.len());
            for (t, row) in samples {
                s.push(t, &row);
            }
            streams.push(s);
        }
        streams.append(&mut self.streams);
        super::instance_topics(streams.iter_mut().map(|s| &mut s.topic));
        let topic = |i: usize| streams[i].topic.clone();
        let mut losses = Vec::new();
        let mut notes = Vec::new();
        let (runs, bytes, first) = self.skipped;
        if runs > 0 {
            notes.push(Note::warning(format!(
                "{bytes} bytes in {runs} stretch{} are no DataFlash message and were skipped to the next header (first at byte {first})",
                if runs == 1 { "" } else { "es" },
            )));
        }
        for (what, n, at) in self.repaired.iter().chain(&self.batches.repaired) {
            notes.push(Note::warning(format!("{what}: {n} (first at byte {at})")));
        }
        if fixed.moved.0 > 0 {
            notes.push(Note::warning(format!(
                "IMU messages with a damaged instance byte given back to the instance their loop lacks: {} (first at byte {})",
                fixed.moved.0, fixed.moved.1
            )));
        }
        if let Some(at) = self.truncated {
            notes.push(Note::warning(format!(
                "the log ends inside a message at byte {at} (cut short): read to there"
            )));
        }
        let mut imu_lost: Vec<(u32, (u64, usize))> = self.imu_lost.into_iter().collect();
        imu_lost.sort_unstable();
        for (k, (n, at)) in imu_lost {
            match imu_of.get(&k) {
                Some(&s) => losses.push(Loss {
                    what: format!(
                        "IMU messages of '{}' damaged beyond reading (first at byte {at})",
                        topic(s)
                    ),
                    messages: Some(n),
                    channel: Some(s as u32),
                    ..Loss::default()
                }),
                None => self.imu_unknown += n,
            }
        }
        self.imu_unknown += fixed.dropped.0;
        if self.imu_unknown > 0 {
            for &s in imu_of.values() {
                losses.push(Loss {
                    what: format!(
                        "'{}': damaged bytes or IMU messages of an instance the log does not have may have held messages of it",
                        topic(s)
                    ),
                    at_most: Some(self.imu_unknown),
                    channel: Some(s as u32),
                    ..Loss::default()
                });
            }
        }
        let mut isb_lost: Vec<(batch::Key, (u64, u64))> =
            self.batches.lost.iter().map(|(k, v)| (*k, *v)).collect();
        isb_lost.sort_unstable();
        for (key, (n, short)) in isb_lost {
            if let Some(&s) = isb_of.get(&key) {
                losses.push(Loss {
                    what: format!(
                        "{short} sensor batch{} (ISBH) of '{}' hold fewer samples than its sensor's batches do",
                        if short == 1 { "" } else { "es" },
                        topic(s)
                    ),
                    messages: Some(n),
                    channel: Some(s as u32),
                    ..Loss::default()
                });
            }
        }
        let mut unfinished: Vec<(batch::Key, (u64, usize))> = self
            .batches
            .unfinished
            .iter()
            .map(|(k, v)| (*k, *v))
            .collect();
        unfinished.sort_unstable();
        for (key, (n, at)) in unfinished {
            if let Some(&s) = isb_of.get(&key) {
                losses.push(Loss {
                    what: format!(
                        "the last sensor batch (ISBH at byte {at}) of '{}' holds fewer samples than its sensor's batches do (the log may have stopped before it was written whole)",
                        topic(s)
                    ),
                    at_most: Some(n),
                    channel: Some(s as u32),
                    ..Loss::default()
                });
            }
        }
        if self.batches.orphans > 0 {
            let n = self.batches.orphans * ISBD_SAMPLES as u64;
            for &s in isb_of.values() {
                losses.push(Loss {
                    what: format!(
                        "'{}': {} ISBD batch data messages belong to no batch header that can be read and were skipped",
                        topic(s),
                        self.batches.orphans
                    ),
                    at_most: Some(n),
                    channel: Some(s as u32),
                    ..Loss::default()
                });
            }
        }
        let mut src = DecodedSource::new(InputKind::DataFlash, streams, notes, Vec::new());
        src.add_losses(losses);
        Ok(src)
    }
}
