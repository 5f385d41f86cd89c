//! PX4 ULog (`.ulg`, the ULog file format of the PX4 documentation): the IMU topics the
//! flight stack logs, each a topic like a bag's, named `name` when the log holds only its
//! instance 0 and `name:k` (the ULog `multi_id`) otherwise:
//!
//! * `sensor_combined`: `gyro_rad`, `accelerometer_m_s2` (the gyro's `timestamp`).
//! * `sensor_gyro`, `sensor_accel` (every instance; the raw per-IMU topics where the log
//!   has them): `x y z` at `timestamp_sample`; the other sensor's columns are NaN.
//! * `vehicle_imu`: `delta_angle`/`delta_angle_dt` and `delta_velocity`/`delta_velocity_dt`,
//!   each delta divided by its own dt (µs); a message with a zero dt is skipped and counted.
//!
//! The record time is the message's `timestamp`, the stamp its `timestamp_sample` where the
//! topic has one (µs since boot, as ns). Every other topic is listed with its message count
//! and times (`bag2mat info`). Dropouts the logger recorded (`O` messages) are losses;
//! bytes that do not parse are skipped to the next sync marker and reported.
//!
//! Our own parser (with [`crate::cursor`]): PX4's `px4-ulog` crate and `yule_log` stream
//! the file through callbacks in one pass and panic on some malformed lengths; the read
//! path wants every message's record time, typed errors and the losses spelt out.

pub mod write;

use std::collections::HashMap;
use std::path::Path;

use crate::cursor::{Cursor, CursorError};
use crate::decoded::{DecodedSource, Row, Stream};
use crate::error::Error;
use crate::source::{InputKind, Loss};

/// The file's first 7 bytes (then a version byte and the start time, µs).
pub const MAGIC: &[u8] = super::ULOG_MAGIC;
/// The sync marker (`S` message body) a reader resynchronises on.
pub const SYNC: [u8; 8] = [0x2F, 0x73, 0x13, 0x20, 0x25, 0x0C, 0xBB, 0x12];
/// Bytes of the file header.
pub const HEADER_LEN: usize = 16;

/// One field of a format: its type, array length (1 for a scalar) and name.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Field {
    /// `float`, `uint64_t`, or another format's name.
    pub ty: String,
    /// Array length, 1 for a scalar.
    pub len: usize,
    /// Name.
    pub name: String,
}

/// The bytes of a scalar type, or `None` for a nested format.
pub fn scalar_size(ty: &str) -> Option<usize> {
    Some(match ty {
        "int8_t" | "uint8_t" | "bool" | "char" => 1,
        "int16_t" | "uint16_t" => 2,
        "int32_t" | "uint32_t" | "float" => 4,
        "int64_t" | "uint64_t" | "double" => 8,
        _ => return None,
    })
}

/// Parses a format message's text `name:type field;…`.
pub fn parse_format(text: &str) -> Option<(String, Vec<Field>)> {
    let (name, rest) = text.split_once(':')?;
    let mut fields = Vec::new();
    for f in rest.split(';').filter(|f| !f.trim().is_empty()) {
        let (ty, fname) = f.trim().rsplit_once(' ')?;
        let (ty, len) = match ty.split_once('[') {
            Some((t, n)) => (t, n.strip_suffix(']')?.parse().ok()?),
            None => (ty, 1),
        };
        fields.push(Field {
            ty: ty.to_string(),
            len,
            name: fname.to_string(),
        });
    }
    Some((name.to_string(), fields))
}

/// A scalar's place in a message: byte offset and type.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Slot {
    offset: usize,
    ty: Scalar,
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    I64,
    U64,
    F32,
    F64,
}

impl Scalar {
    fn of(ty: &str) -> Option<Scalar> {
        Some(match ty {
            "int8_t" => Scalar::I8,
            "uint8_t" | "bool" | "char" => Scalar::U8,
            "int16_t" => Scalar::I16,
            "uint16_t" => Scalar::U16,
            "int32_t" => Scalar::I32,
            "uint32_t" => Scalar::U32,
            "int64_t" => Scalar::I64,
            "uint64_t" => Scalar::U64,
            "float" => Scalar::F32,
            "double" => Scalar::F64,
            _ => return None,
        })
    }
}

impl Slot {
    /// The value as f64, or `None` past the end of `data`.
    fn get(&self, data: &[u8]) -> Option<f64> {
        let mut c = Cursor::new(data.get(self.offset..)?);
        let r: Result<f64, CursorError> = match self.ty {
            Scalar::I8 => c.le::<i8>("").map(f64::from),
            Scalar::U8 => c.le::<u8>("").map(f64::from),
            Scalar::I16 => c.le::<i16>("").map(f64::from),
            Scalar::U16 => c.le::<u16>("").map(f64::from),
            Scalar::I32 => c.le::<i32>("").map(f64::from),
            Scalar::U32 => c.le::<u32>("").map(f64::from),
            Scalar::I64 => c.le::<i64>("").map(|v| v as f64),
            Scalar::U64 => c.le::<u64>("").map(|v| v as f64),
            Scalar::F32 => c.le::<f32>("").map(f64::from),
            Scalar::F64 => c.le::<f64>(""),
        };
        r.ok()
    }

    fn get_u64(&self, data: &[u8]) -> Option<u64> {
        let mut c = Cursor::new(data.get(self.offset..)?);
        match self.ty {
            Scalar::U64 => c.le::<u64>("").ok(),
            Scalar::I64 => c.le::<i64>("").ok().and_then(|v| u64::try_from(v).ok()),
            Scalar::U32 => c.le::<u32>("").ok().map(u64::from),
            _ => None,
        }
    }
}

/// Formats by name, and the flattened scalar slots of each (`gyro_rad[1]`, `a.b`).
struct Formats {
    defs: HashMap<String, Vec<Field>>,
}

impl Formats {
    /// Every scalar of a format with its flattened name.
    fn slots(&self, name: &str) -> Option<HashMap<String, Slot>> {
        let mut out = HashMap::new();
        self.flatten(name, "", 0, &mut out, 0)?;
        Some(out)
    }

    fn flatten(
        &self,
        name: &str,
        prefix: &str,
        base: usize,
        out: &mut HashMap<String, Slot>,
        depth: usize,
    ) -> Option<usize> {
        if depth > 16 {
            return None;
        }
        let mut off = base;
        for fld in self.defs.get(name)? {
            for k in 0..fld.len {
                let n = if fld.len > 1 {
                    format!("{prefix}{}[{k}]", fld.name)
                } else {
                    format!("{prefix}{}", fld.name)
                };
                match Scalar::of(&fld.ty) {
                    Some(ty) => {
                        out.insert(n, Slot { offset: off, ty });
                        off += scalar_size(&fld.ty)?;
                    }
                    None => {
                        off = self.flatten(&fld.ty, &format!("{n}."), off, out, depth + 1)?;
                    }
                }
            }
        }
        Some(off)
    }
}

/// How the messages of one IMU topic become rows.
#[derive(Debug, Clone)]
enum Decoder {
    Combined {
        gyro: [Slot; 3],
        acc: [Slot; 3],
    },
    Gyro {
        sample: Option<Slot>,
        v: [Slot; 3],
    },
    Accel {
        sample: Option<Slot>,
        v: [Slot; 3],
    },
    Deltas {
        sample: Option<Slot>,
        angle: [Slot; 3],
        angle_dt: Slot,
        vel: [Slot; 3],
        vel_dt: Slot,
    },
}

fn three(s: &HashMap<String, Slot>, base: &str) -> Option<[Slot; 3]> {
    let a = |k: usize| s.get(&format!("{base}[{k}]")).copied();
    Some([a(0)?, a(1)?, a(2)?])
}

fn xyz(s: &HashMap<String, Slot>) -> Option<[Slot; 3]> {
    Some([*s.get("x")?, *s.get("y")?, *s.get("z")?])
}

impl Decoder {
    fn for_topic(name: &str, s: &HashMap<String, Slot>) -> Option<Decoder> {
        let sample = s.get("timestamp_sample").copied();
        match name {
            "sensor_combined" => Some(Decoder::Combined {
                gyro: three(s, "gyro_rad")?,
                acc: three(s, "accelerometer_m_s2")?,
            }),
            "sensor_gyro" => Some(Decoder::Gyro { sample, v: xyz(s)? }),
            "sensor_accel" => Some(Decoder::Accel { sample, v: xyz(s)? }),
            "vehicle_imu" => Some(Decoder::Deltas {
                sample,
                angle: three(s, "delta_angle")?,
                angle_dt: *s.get("delta_angle_dt")?,
                vel: three(s, "delta_velocity")?,
                vel_dt: *s.get("delta_velocity_dt")?,
            }),
            _ => None,
        }
    }

    fn msg_type(name: &str) -> String {
        format!("px4/{name}")
    }

    /// The row of a data message (`data` starts with the timestamp), or why not.
    fn row(&self, t_ns: u64, data: &[u8]) -> Result<Row, &'static str> {
        let v3 = |s: &[Slot; 3]| -> Result<[f64; 3], &'static str> {
            let mut v = [0.0; 3];
            for k in 0..3 {
                v[k] = s[k].get(data).ok_or("message shorter than its format")?;
            }
            Ok(v)
        };
        let stamp = |s: &Option<Slot>| -> u64 {
            s.and_then(|s| s.get_u64(data))
                .map_or(t_ns, |us| us.saturating_mul(1000))
        };
        let nan = [f64::NAN; 3];
        Ok(match self {
            Decoder::Combined { gyro, acc } => Row {
                stamp: t_ns,
                gyro: v3(gyro)?,
                acc: v3(acc)?,
            },
            Decoder::Gyro { sample, v } => Row {
                stamp: stamp(sample),
                gyro: v3(v)?,
                acc: nan,
            },
            Decoder::Accel { sample, v } => Row {
                stamp: stamp(sample),
                gyro: nan,
                acc: v3(v)?,
            },
            Decoder::Deltas {
                sample,
                angle,
                angle_dt,
                vel,
                vel_dt,
            } => {
                let da = angle_dt
                    .get(data)
                    .ok_or("message shorter than its format")?;
                let dv = vel_dt.get(data).ok_or("message shorter than its format")?;
                if !(da > 0.0 && dv > 0.0) {
                    return Err("a delta with a zero dt");
                }
                let (a, v) = (v3(angle)?, v3(vel)?);
                Row {
                    stamp: stamp(sample),
                    gyro: a.map(|x| x / (da * 1e-6)),
                    acc: v.map(|x| x / (dv * 1e-6)),
                }
            }
        })
    }
}

/// A subscription (`A` message): which stream its data go to and how they decode.
struct Sub {
    stream: usize,
    decoder: Option<Decoder>,
    /// Offset of the leading `timestamp` (the first field of every logged topic).
    ts: Option<Slot>,
}

/// What reading found, beyond the rows.
#[derive(Default)]
struct Found {
    dropouts: Vec<(u64, u16)>,
    /// Rows a decoder refused, per stream: count and first reason.
    refused: HashMap<usize, (u64, &'static str)>,
    /// Bytes skipped to resynchronise: (offset, length).
    skipped: Vec<(u64, u64)>,
    /// Data messages for an id no `A` message announced.
    orphans: u64,
    /// The file ends inside a message at this offset.
    truncated: Option<u64>,
}

/// Bytes read at a time: the file is parsed through one window, never held whole.
const WINDOW: usize = 8 << 20;

/// A window on the file, moved forward as the parser asks for bytes.
struct Window {
    file: std::fs::File,
    len: u64,
    buf: Vec<u8>,
    start: u64,
}

impl Window {
    /// Bytes `at..at + n` of the file, or `None` past its end.
    fn get(&mut self, at: u64, n: usize) -> std::io::Result<Option<&[u8]>> {
        use std::os::unix::fs::FileExt;
        let end = at.saturating_add(n as u64);
        if end > self.len {
            return Ok(None);
        }
        if at < self.start || end > self.start + self.buf.len() as u64 {
            let to = self.len.min(at + WINDOW.max(n) as u64);
            self.buf.resize((to - at) as usize, 0);
            self.file.read_exact_at(&mut self.buf, at)?;
            self.start = at;
        }
        let i = (at - self.start) as usize;
        Ok(Some(&self.buf[i..i + n]))
    }
}

/// Data messages per message id, from a hop over the message headers (sizes only): what
/// each stream reserves room for. A damaged stretch ends the hop; it only sizes memory.
fn count_data(win: &mut Window, mut at: u64) -> std::io::Result<HashMap<u16, usize>> {
    let mut n: HashMap<u16, usize> = HashMap::new();
    while let Some(h) = win.get(at, 5)? {
        let (size, ty) = (u16::from_le_bytes([h[0], h[1]]), h[2]);
        if ty == b'D' {
            *n.entry(u16::from_le_bytes([h[3], h[4]])).or_default() += 1;
        } else if !b"BFIMPQARLCSO".contains(&ty) {
            break;
        }
        at += 3 + size as u64;
    }
    Ok(n)
}

/// Opens a ULog file.
pub fn open(path: &Path) -> Result<DecodedSource, Error> {
    let file = std::fs::File::open(path).map_err(|e| Error::io(path, e))?;
    let len = file.metadata().map_err(|e| Error::io(path, e))?.len();
    read(
        path,
        Window {
            file,
            len,
            buf: Vec::new(),
            start: 0,
        },
    )
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

/// Reads a ULog through a window on it.
fn read(path: &Path, mut win: Window) -> Result<DecodedSource, Error> {
    let io = |e| Error::io(path, e);
    let header = win
        .get(0, HEADER_LEN.min(win.len as usize))
        .map_err(io)?
        .unwrap_or(&[]);
    let mut c = Cursor::new(header);
    let magic = c
        .take(MAGIC.len(), "ULog magic")
        .map_err(|e| corrupt(path, e))?;
    if magic != MAGIC {
        return Err(corrupt(path, c.invalid("not a ULog file")));
    }
    let _version = c.le::<u8>("ULog version").map_err(|e| corrupt(path, e))?;
    let _start_us = c
        .le::<u64>("ULog start time")
        .map_err(|e| corrupt(path, e))?;
    let mut formats = Formats {
        defs: HashMap::new(),
    };
    let mut streams: Vec<Stream> = Vec::new();
    let mut by_key: HashMap<(String, u8), usize> = HashMap::new();
    let mut instances: HashMap<String, Vec<u8>> = HashMap::new();
    let mut subs: HashMap<u16, Sub> = HashMap::new();
    let mut found = Found::default();
    let mut last_t: u64 = 0;
    let mut appended_at: Option<u64> = None;
    let mut at = HEADER_LEN as u64;
    // exact room for each subscription's messages (a hop over the message headers)
    let counts = count_data(&mut win, at).map_err(io)?;
    while at < win.len {
        let Some(h) = win.get(at, 3).map_err(io)? else {
            found.truncated = Some(at);
            break;
        };
        let (size, ty) = (u16::from_le_bytes([h[0], h[1]]), h[2]);
        let known = matches!(
            ty,
            b'B' | b'F'
                | b'I'
                | b'M'
                | b'P'
                | b'Q'
                | b'A'
                | b'R'
                | b'D'
                | b'L'
                | b'C'
                | b'S'
                | b'O'
        );
        if !known {
            // resynchronise on the next sync marker
            let n = WINDOW.min((win.len - at) as usize);
            let rest = win.get(at, n).map_err(io)?.unwrap_or(&[]);
            let skip = match rest.windows(SYNC.len()).position(|w| w == SYNC) {
                Some(p) => p.saturating_sub(3),
                None if at + (n as u64) < win.len => n - SYNC.len(),
                None => n,
            };
            let skip = skip.max(1) as u64;
            found.skipped.push((at, skip));
            at += skip;
            continue;
        }
        // a message cut by the start of appended data (the logger's DATA_APPENDED flag)
        if let Some(ap) = appended_at
            && at < ap
            && at + 3 + size as u64 > ap
            && ap <= win.len
        {
            found.skipped.push((at, ap - at));
            at = ap;
            continue;
        }
        let Some(body) = win.get(at + 3, size as usize).map_err(io)? else {
            found.truncated = Some(at);
            break;
        };
        let mut m = Cursor::at(body, at + 3);
        let msg_at = at;
        at += 3 + size as u64;
        match ty {
            b'B' => {
                // flag bits: compat[8], incompat[8], appended offsets[3]
                if let (Ok(_), Ok(incompat)) =
                    (m.take(8, "compat flags"), m.take(8, "incompat flags"))
                {
                    if incompat[0] & 1 != 0
                        && let Ok(off) = m.le::<u64>("appended offset")
                        && off > 0
                    {
                        appended_at = Some(off);
                    }
                }
            }
            b'F' => {
                if let Some((name, fields)) =
                    std::str::from_utf8(m.rest()).ok().and_then(parse_format)
                {
                    formats.defs.insert(name, fields);
                }
            }
            b'A' => {
                let parsed = (|| -> Result<(u8, u16, &str), CursorError> {
                    let multi = m.le::<u8>("multi_id")?;
                    let id = m.le::<u16>("msg_id")?;
                    let n = m.remaining();
                    Ok((multi, id, m.str(n, "message name")?))
                })();
                let Ok((multi, id, name)) = parsed else {
                    found.skipped.push((msg_at, size as u64 + 3));
                    continue;
                };
                let key = (name.to_string(), multi);
                let slots = formats.slots(name);
                let decoder = slots.as_ref().and_then(|s| Decoder::for_topic(name, s));
                let stream = *by_key.entry(key).or_insert_with(|| {
                    let v = instances.entry(name.to_string()).or_default();
                    if !v.contains(&multi) {
                        v.push(multi);
                    }
                    let topic = format!("{name}:{multi}");
                    streams.push(if decoder.is_some() {
                        Stream::imu(topic, Decoder::msg_type(name))
                    } else {
                        Stream::other(topic, Decoder::msg_type(name))
                    });
                    streams.len() - 1
                });
                let room = counts.get(&id).copied().unwrap_or(0);
                streams[stream].reserve(room);
                let ts = slots.as_ref().and_then(|s| s.get("timestamp").copied());
                subs.insert(
                    id,
                    Sub {
                        stream,
                        decoder,
                        ts,
                    },
                );
            }
            b'R' => {
                if let Ok(id) = m.le::<u16>("msg_id") {
                    subs.remove(&id);
                }
            }
            b'D' => {
                let Ok(id) = m.le::<u16>("msg_id") else {
                    found.skipped.push((msg_at, size as u64 + 3));
                    continue;
                };
                let data = m.rest();
                let Some(sub) = subs.get(&id) else {
                    found.orphans += 1;
                    continue;
                };
                let Some(t_us) = sub.ts.and_then(|s| s.get_u64(data)) else {
                    found.orphans += 1;
                    continue;
                };
                let t = t_us.saturating_mul(1000);
                last_t = last_t.max(t);
                let s = &mut streams[sub.stream];
                match &sub.decoder {
                    None => s.push_time(t),
                    Some(d) => match d.row(t, data) {
                        Ok(row) => s.push(t, &row),
                        Err(why) => {
                            let e = found.refused.entry(sub.stream).or_insert((0, why));
                            e.0 += 1;
                        }
                    },
                }
            }
            b'O' => {
                if let Ok(ms) = m.le::<u16>("dropout duration") {
                    found.dropouts.push((last_t, ms));
                }
            }
            _ => {} // info, parameters, log text, sync
        }
    }
    if formats.defs.is_empty() && streams.is_empty() {
        return Err(Error::Corrupt {
            path: path.to_path_buf(),
            offset: HEADER_LEN as u64,
            what: "ULog: no format or subscription could be read".into(),
        });
    }
    // Names: `name` when the log has only instance 0 of it, else `name:k`.
    for s in &mut streams {
        if let Some((name, k)) = s.topic.rsplit_once(':')
            && k == "0"
            && instances.get(name).is_some_and(|v| v.len() == 1)
        {
            s.topic = name.to_string();
        }
    }
    let mut losses = Vec::new();
    let mut notes = Vec::new();
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
            .map_or(0, |d| d.0 + d.1 as u64 * 1_000_000);
        losses.push(Loss {
            what: format!(
                "the logger recorded {} dropout{} totalling {total} ms (longest {} ms at {:.3} s): every topic lost its messages of that time",
                found.dropouts.len(),
                if found.dropouts.len() == 1 { "" } else { "s" },
                longest.1,
                longest.0 as f64 * 1e-9
            ),
            messages: None,
            span: Some((first, last)),
            channel: None,
        });
    }
    for (id, (n, why)) in &found.refused {
        losses.push(Loss {
            what: format!(
                "{n} messages of '{}' do not give a sample ({why})",
                streams[*id].topic
            ),
            messages: Some(*n),
            span: None,
            channel: Some(*id as u32),
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
    if let Some(at) = found.truncated {
        notes.push(format!(
            "the log ends inside a message at byte {at} (cut short): read to there"
        ));
    }
    Ok(DecodedSource::new(InputKind::Ulog, streams, notes, losses))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn formats_parse_and_flatten() {
        let (n, f) = parse_format(
            "sensor_combined:uint64_t timestamp;float[3] gyro_rad;uint8_t[2] _padding0;",
        )
        .unwrap();
        assert_eq!(n, "sensor_combined");
        assert_eq!(
            f[1],
            Field {
                ty: "float".into(),
                len: 3,
                name: "gyro_rad".into()
            }
        );
        let mut defs = HashMap::new();
        defs.insert(n.clone(), f);
        defs.insert(
            "outer".into(),
            parse_format("outer:uint64_t timestamp;sensor_combined[2] s;")
                .unwrap()
                .1,
        );
        let fm = Formats { defs };
        let s = fm.slots("outer").unwrap();
        assert_eq!(s["s[1].gyro_rad[2]"].offset, 8 + 22 + 8 + 8);
        assert!(fm.slots("missing").is_none());
    }
}
