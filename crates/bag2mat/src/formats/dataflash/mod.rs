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
    len: usize,
    /// Column name → (offset in the payload, format character).
    cols: HashMap<String, (usize, u8)>,
    /// The first column is `TimeUS`.
    time: bool,
}

impl Def {
    fn parse(name: &str, fmt: &str, columns: &str, len: usize) -> Option<Def> {
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
        (off + 3 == len).then(|| Def {
            name: name.to_string(),
            len,
            time: names.first() == Some(&"TimeUS") && fmt.starts_with('Q'),
            cols,
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

    /// An `a` column: 32 int16.
    fn array(&self, p: &[u8], name: &str) -> Option<[i16; ISBD_SAMPLES]> {
        let &(off, c) = self.cols.get(name)?;
        if c != b'a' {
            return None;
        }
        let mut k = Cursor::new(p.get(off..)?);
        let mut v = [0i16; ISBD_SAMPLES];
        for x in &mut v {
            *x = k.le::<i16>("").ok()?;
        }
        Some(v)
    }
}

/// A batch header being filled.
struct Batch {
    stream: usize,
    mul: f64,
    count: usize,
    start_us: u64,
    rate: f64,
    gyro: bool,
    got: usize,
}

/// Opens a DataFlash log.
pub(crate) fn open(path: &Path) -> Result<DecodedSource, Error> {
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    read(path, &bytes)
}

/// Reads a DataFlash log held in memory.
pub(crate) fn read(path: &Path, bytes: &[u8]) -> Result<DecodedSource, Error> {
    let mut r = Reader::default();
    let mut i = 0usize;
    let mut in_skip = false;
    while i + 3 <= bytes.len() {
        let ty = bytes[i + 2];
        let len = match (bytes[i..i + 2] == HEAD, ty == FMT_TYPE, r.defs.get(&ty)) {
            (true, true, _) => Some(FMT_LEN),
            (true, false, Some(d)) => Some(d.len),
            _ => None,
        };
        let Some(len) = len else {
            // no message here: skip a byte, counting the stretch once
            if !in_skip {
                r.skip_runs += 1;
                r.first_skip.get_or_insert(i);
                in_skip = true;
            }
            r.skipped += 1;
            i += 1;
            continue;
        };
        if i + len > bytes.len() {
            r.truncated = Some(i);
            break;
        }
        in_skip = false;
        r.message(ty, &bytes[i + 3..i + len]);
        i += len;
    }
    r.finish(path)
}

/// What reading a log has gathered: the definitions, the topics, open batches and what was
/// lost.
#[derive(Default)]
struct Reader {
    defs: HashMap<u8, Def>,
    streams: Vec<Stream>,
    by_key: HashMap<(String, u32), usize>,
    batches: HashMap<u16, Batch>,
    /// Bytes skipped, the stretches they form, and the first one's offset.
    skipped: u64,
    skip_runs: u64,
    first_skip: Option<usize>,
    orphan_isbd: u64,
    /// Per batch topic (its stream): batches that hold fewer samples than their header
    /// promises, and the samples they lack.
    short: std::collections::BTreeMap<usize, (u64, u64)>,
    truncated: Option<usize>,
}

impl Reader {
    /// The stream of topic `name` instance `k`, made at its first message.
    fn stream(&mut self, name: &str, k: u32, imu: bool) -> usize {
        let streams = &mut self.streams;
        *self.by_key.entry((name.to_string(), k)).or_insert_with(|| {
            let topic = format!("{name}:{k}");
            let ty = format!("ardupilot/{name}");
            streams.push(if imu {
                Stream::imu(topic, ty)
            } else {
                Stream::other(topic, ty)
            });
            streams.len() - 1
        })
    }

    /// A batch that is complete or replaced: counted when it holds fewer samples than its
    /// header promised.
    fn close(&mut self, b: &Batch) {
        if b.got < b.count {
            let e = self.short.entry(b.stream).or_default();
            e.0 += 1;
            e.1 += (b.count - b.got) as u64;
        }
    }

    /// One message of type `ty`, payload `p`.
    fn message(&mut self, ty: u8, p: &[u8]) {
        if ty == FMT_TYPE {
            self.format(p);
            return;
        }
        // the definitions are only read here: out of `self` for the call (no copy)
        let defs = std::mem::take(&mut self.defs);
        if let Some(d) = defs.get(&ty) {
            let t_us = if d.time { d.get_u64(p, "TimeUS") } else { None };
            match d.name.as_str() {
                name @ ("IMU" | "IMU2" | "IMU3") => self.imu(d, p, name, t_us),
                "ISBH" => self.batch_header(d, p),
                "ISBD" => self.batch_data(d, p),
                name => {
                    if let Some(t) = t_us {
                        let s = self.stream(name, 0, false);
                        self.streams[s].push_time(t.saturating_mul(1000));
                    }
                }
            }
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

    /// An `IMU` (`IMU2`, `IMU3`) message: a row of its instance's topic.
    fn imu(&mut self, d: &Def, p: &[u8], name: &str, t_us: Option<u64>) {
        let k = match d.get(p, "I") {
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
        let (Some(t), Some(row)) = (t_us, row()) else {
            return;
        };
        let s = self.stream("IMU", k, true);
        let t = t.saturating_mul(1000);
        self.streams[s].push(t, &Row { stamp: t, ..row });
    }

    /// An `ISBH` batch header: opens its batch (closing one with the same number).
    fn batch_header(&mut self, d: &Def, p: &[u8]) {
        let h = (|| {
            Some((
                d.get(p, "N")? as u16,
                d.get(p, "type")? as u8,
                d.get(p, "instance")? as u32,
                d.get(p, "mul")?,
                d.get(p, "smp_cnt")? as usize,
                d.get_u64(p, "SampleUS")?,
                d.get(p, "smp_rate")?,
            ))
        })();
        let Some((n, kind, inst, mul, count, start_us, rate)) = h else {
            return;
        };
        let gyro = kind == 1;
        let stream = self.stream(if gyro { "ISB_GYR" } else { "ISB_ACC" }, inst, true);
        let batch = Batch {
            stream,
            mul,
            count,
            start_us,
            rate,
            gyro,
            got: 0,
        };
        if let Some(old) = self.batches.insert(n, batch) {
            self.close(&old);
        }
    }

    /// An `ISBD` batch data message: its samples, as rows of its batch's topic.
    fn batch_data(&mut self, d: &Def, p: &[u8]) {
        let (Some(n), Some(seq)) = (d.get(p, "N"), d.get(p, "seqno")) else {
            return;
        };
        let Some(b) = self.batches.get_mut(&(n as u16)) else {
            self.orphan_isbd += 1;
            return;
        };
        let (Some(x), Some(y), Some(z)) = (d.array(p, "x"), d.array(p, "y"), d.array(p, "z"))
        else {
            return;
        };
        if !(b.mul > 0.0 && b.rate > 0.0) {
            return;
        }
        for k in 0..ISBD_SAMPLES {
            let j = seq as usize * ISBD_SAMPLES + k;
            if j >= b.count {
                break;
            }
            let t = b
                .start_us
                .saturating_mul(1000)
                .saturating_add((j as f64 * 1e9 / b.rate).round() as u64);
            let v = [
                x[k] as f64 / b.mul,
                y[k] as f64 / b.mul,
                z[k] as f64 / b.mul,
            ];
            let nan = [f64::NAN; 3];
            let (gyro, acc) = if b.gyro { (v, nan) } else { (nan, v) };
            self.streams[b.stream].push(
                t,
                &Row {
                    stamp: t,
                    gyro,
                    acc,
                },
            );
            b.got += 1;
        }
    }

    /// The source: the topics, and what was lost said as losses and notes.
    fn finish(mut self, path: &Path) -> Result<DecodedSource, Error> {
        for b in std::mem::take(&mut self.batches).values() {
            self.close(b);
        }
        if self.defs.is_empty() {
            return Err(Error::Corrupt {
                path: path.to_path_buf(),
                offset: 0,
                what: "DataFlash: no FMT message could be read".into(),
            });
        }
        super::instance_topics(self.streams.iter_mut().map(|s| &mut s.topic));
        let mut losses = Vec::new();
        let mut notes = Vec::new();
        if self.skipped > 0 {
            losses.push(Loss::new(format!(
                "{} bytes in {} stretch{} are no DataFlash message and were skipped to the next header (first at byte {})",
                self.skipped,
                self.skip_runs,
                if self.skip_runs == 1 { "" } else { "es" },
                self.first_skip.unwrap_or(0)
            )));
        }
        if self.orphan_isbd > 0 {
            losses.push(Loss::new(format!(
                "{} ISBD batch data messages have no ISBH header and were skipped",
                self.orphan_isbd
            )));
        }
        // each batch topic's own loss: a channel's id is its stream's index (every stream
        // here is a topic of its own, and the source numbers the channels in stream order)
        for (&stream, &(batches, samples)) in &self.short {
            losses.push(Loss {
                what: format!(
                    "{batches} sensor batch{} (ISBH) of '{}' hold{} fewer samples than {} header{} promise{}",
                    if batches == 1 { "" } else { "es" },
                    self.streams[stream].topic,
                    if batches == 1 { "s" } else { "" },
                    if batches == 1 { "its" } else { "their" },
                    if batches == 1 { "" } else { "s" },
                    if batches == 1 { "s" } else { "" },
                ),
                messages: Some(samples),
                at_most: None,
                span: None,
                channel: Some(stream as u32),
            });
        }
        if let Some(at) = self.truncated {
            notes.push(format!(
                "the log ends inside a message at byte {at} (cut short): read to there"
            ));
        }
        Ok(DecodedSource::new(
            InputKind::DataFlash,
            self.streams,
            notes,
            losses,
        ))
    }
}
