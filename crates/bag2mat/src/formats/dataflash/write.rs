//! A DataFlash writer, for tests and benchmarks: `FMT` definitions and messages packed by
//! their format characters, and [`imu_log`], a log of `IMU` instances and `ISBH`/`ISBD`
//! batches in ArduPilot's layouts that pymavlink's DFReader reads.

use std::io::{self, Write};

use super::{FMT_LEN, FMT_TYPE, HEAD, ISBD_SAMPLES};

/// ArduPilot's `IMU` message (4.x): format and columns.
pub const IMU: (&str, &str) = (
    "QBffffffIIfBBHH",
    "TimeUS,I,GyrX,GyrY,GyrZ,AccX,AccY,AccZ,EG,EA,T,GH,AH,GHz,AHz",
);
/// ArduPilot's `ISBH` batch header.
pub const ISBH: (&str, &str) = (
    "QHBBHHQf",
    "TimeUS,N,type,instance,mul,smp_cnt,SampleUS,smp_rate",
);
/// ArduPilot's `ISBD` batch data.
pub const ISBD: (&str, &str) = ("QHHaaa", "TimeUS,N,seqno,x,y,z");
/// A message the tools do not read as Imu.
pub const BARO: (&str, &str) = ("QBfff", "TimeUS,I,Alt,Press,Temp");

/// Writes messages.
pub struct Writer<W: Write> {
    w: W,
}

fn padded(s: &str, n: usize) -> Vec<u8> {
    let mut b = s.as_bytes().to_vec();
    b.resize(n, 0);
    b
}

impl<W: Write> Writer<W> {
    /// Starts a log with the `FMT` message that defines `FMT` itself.
    pub fn new(w: W) -> io::Result<Writer<W>> {
        let mut me = Writer { w };
        me.define(FMT_TYPE, "FMT", "BBnNZ", "Type,Length,Name,Format,Columns")?;
        Ok(me)
    }

    /// An `FMT` message defining `ty`.
    pub fn define(&mut self, ty: u8, name: &str, fmt: &str, cols: &str) -> io::Result<()> {
        let len: usize = 3 + fmt
            .bytes()
            .map(|c| super::char_size(c).unwrap_or(0))
            .sum::<usize>();
        let mut b = vec![ty, len as u8];
        b.extend(padded(name, 4));
        b.extend(padded(fmt, 16));
        b.extend(padded(cols, 64));
        debug_assert_eq!(b.len() + 3, FMT_LEN);
        self.message(FMT_TYPE, &b)
    }

    /// A message of type `ty` with its packed payload.
    pub fn message(&mut self, ty: u8, payload: &[u8]) -> io::Result<()> {
        self.w.write_all(&HEAD)?;
        self.w.write_all(&[ty])?;
        self.w.write_all(payload)
    }

    /// The underlying writer.
    pub fn finish(mut self) -> io::Result<W> {
        self.w.flush()?;
        Ok(self.w)
    }
}

/// Writes `seconds` of two `IMU` instances at `rate` Hz, `BARO` at 10 Hz, and instance 0's
/// accelerometer and gyro batches (`ISBH`/`ISBD`, 4× the rate, 256 samples a batch; the
/// last batch's data cut short, as a log stopped mid-batch is).
pub fn imu_log<W: Write>(w: W, seconds: f64, rate: f64, seed: u64) -> io::Result<W> {
    let mut d = Writer::new(w)?;
    d.define(129, "IMU", IMU.0, IMU.1)?;
    d.define(130, "ISBH", ISBH.0, ISBH.1)?;
    d.define(131, "ISBD", ISBD.0, ISBD.1)?;
    d.define(132, "BARO", BARO.0, BARO.1)?;
    let mut st = seed;
    let n = (seconds * rate) as u64;
    let dt = (1e6 / rate).round() as u64;
    let t0 = 5_000_000u64;
    let mut b = Vec::with_capacity(256);
    let batch = Batch {
        len: 256,
        rate: 4.0 * rate,
    };
    let (mut isb_n, mut next_batch) = (0u16, t0);
    let batch_us = (batch.len as f64 / (4.0 * rate) * 1e6) as u64;
    let (acc_mul, gyro_mul) = (
        32768.0f32 / (16.0 * 9.80665),
        32768.0f32 / (2000.0f32.to_radians()),
    );
    for i in 0..n {
        let t = t0 + i * dt;
        for k in 0..2u8 {
            imu_body(&mut b, t, k, rate, &mut st);
            d.message(129, &b)?;
        }
        if i % ((rate / 10.0).round().max(1.0) as u64) == 0 {
            b.clear();
            b.extend_from_slice(&t.to_le_bytes());
            b.push(0);
            for v in [12.5f32, 101_325.0, 30.0] {
                b.extend_from_slice(&v.to_le_bytes());
            }
            d.message(132, &b)?;
        }
        if t >= next_batch && t + 2 * batch_us < t0 + n * dt {
            let last = t + 4 * batch_us >= t0 + n * dt;
            for (kind, mul) in [(0u8, acc_mul), (1u8, gyro_mul)] {
                batch.write(&mut d, &mut b, (t, isb_n, kind, mul), last, &mut st)?;
                isb_n = isb_n.wrapping_add(1);
            }
            next_batch = t + 2 * batch_us;
        }
    }
    d.finish()
}

/// An IMU message of instance `k` at `t` µs: noise around rest (gravity on −z).
fn imu_body(b: &mut Vec<u8>, t: u64, k: u8, rate: f64, st: &mut u64) {
    b.clear();
    b.extend_from_slice(&t.to_le_bytes());
    b.push(k);
    for a in 0..6 {
        let base = if a == 5 { -9.80665 } else { 0.0 };
        let scale = if a < 3 { 1e-3 } else { 2e-2 };
        b.extend_from_slice(
            &((base + scale * crate::formats::synthetic_noise(st)) as f32).to_le_bytes(),
        );
    }
    b.extend_from_slice(&0u32.to_le_bytes());
    b.extend_from_slice(&0u32.to_le_bytes());
    b.extend_from_slice(&41.5f32.to_le_bytes());
    b.extend_from_slice(&[1, 1]);
    b.extend_from_slice(&(rate as u16 * 4).to_le_bytes());
    b.extend_from_slice(&(rate as u16 * 4).to_le_bytes());
}

/// The high-rate sensor batches of [`imu_log`]: `len` samples at `rate` Hz each.
struct Batch {
    len: usize,
    rate: f64,
}

impl Batch {
    /// One batch (`t` µs, number `isb_n`, sensor `kind` 0 acc / 1 gyro, `mul` LSB per
    /// unit): its ISBH header and ISBD chunks, the last chunk left out on the `last` batch.
    fn write<W: Write>(
        &self,
        d: &mut Writer<W>,
        b: &mut Vec<u8>,
        (t, isb_n, kind, mul): (u64, u16, u8, f32),
        last: bool,
        st: &mut u64,
    ) -> io::Result<()> {
        b.clear();
        b.extend_from_slice(&t.to_le_bytes());
        b.extend_from_slice(&isb_n.to_le_bytes());
        b.push(kind);
        b.push(0);
        b.extend_from_slice(&(mul.round() as u16).to_le_bytes());
        b.extend_from_slice(&(self.len as u16).to_le_bytes());
        b.extend_from_slice(&t.to_le_bytes());
        b.extend_from_slice(&(self.rate as f32).to_le_bytes());
        d.message(130, b)?;
        let chunks = self.len / ISBD_SAMPLES - usize::from(last);
        for seq in 0..chunks {
            b.clear();
            b.extend_from_slice(&t.to_le_bytes());
            b.extend_from_slice(&isb_n.to_le_bytes());
            b.extend_from_slice(&(seq as u16).to_le_bytes());
            for axis in 0..3 {
                for _ in 0..ISBD_SAMPLES {
                    let g = if kind == 0 && axis == 2 {
                        -9.80665
                    } else {
                        0.0
                    };
                    let v = (g + 0.05 * crate::formats::synthetic_noise(st)) * mul as f64;
                    b.extend_from_slice(&(v.round() as i16).to_le_bytes());
                }
            }
            d.message(131, b)?;
        }
        Ok(())
    }
}
