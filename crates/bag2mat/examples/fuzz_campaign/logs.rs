//! The campaign's logs from outside ROS (issue 45): PX4 ULog (with and without sync markers),
//! ArduPilot DataFlash (`IMU` instances and `ISBH`/`ISBD` batches), CSV and EuRoC/ASL text,
//! NumPy `.npy`. Each clean file is written by a small generator of the campaign's own from the
//! public format descriptions (never by bag2mat's writers), damaged `variants` times from one
//! seed, read by the real `bag2mat` binary (as the bag formats are) and by the independent
//! reader of the format (pyulog, pymavlink's DFReader, pandas, numpy:
//! `tests/py/log_rows.py`, run once per format over every variant), and the rows compared by
//! value with the generator's.
//!
//! Damage: bit flips, byte runs, truncations, bytes inserted or deleted anywhere, and each
//! format's own field edits — ULog message sizes, type bytes, message ids, subscriptions
//! re-bound, format definitions changed (array lengths, types) or given twice, incompatible
//! flags; DataFlash batch counts, sensor types, instances, sequence numbers, messages cut
//! short or lengthened, `FMT` fields, the first byte; text lines with an unterminated quote, a
//! value that is no number (also in the first data row), comment lines (also right after the
//! header), a long junk line, lines merged or split, a cut inside the last number; npy header
//! fields.
//!
//! A variant passes when bag2mat's rows and warnings are consistent with what was lost: rows
//! not delivered (a row whose values changed counts as delivered, altered) are counted in the
//! topic's `warning:` summary — at least as many (no silent or under-reported loss), and no
//! exact count above the rows lost (no false loss) — the independent reader recovers no clean
//! row bag2mat does not, and a file the independent reader reads is not refused. A truncated
//! file is expected to hold the rows whose message (line) starts before the cut.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

use super::{ChildRun, Rng, py_script, run_child, venv_tool};
use bag2mat::test_tools::reported_losses;

/// Generator rows of the topic read, in each clean file (other topics besides).
const ROWS: usize = 1000;
/// Samples per DataFlash batch (32 `ISBD` messages of 32).
const BATCH: usize = 1024;
/// Batches of each sensor in the DataFlash log.
const BATCHES: usize = 5;
/// How far a time bag2mat prints (seconds, f64) may be from its row's: far below any period,
/// above an f64's rounding near 1.7e9 s.
const TIME_TOLERANCE_NS: f64 = 1000.0;

/// The log formats of the campaign.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum LogFormat {
    /// PX4 ULog with a sync marker every 64 messages; topic `sensor_combined`.
    Ulog,
    /// The same without sync markers (PX4 writes them rarely).
    UlogNoSync,
    /// ArduPilot DataFlash, topic `IMU:0` (two instances).
    DataflashImu,
    /// The same log, topic `ISB_GYR` (the gyro's batch samples).
    DataflashIsb,
    /// bag2mat's CSV layout (`t,ax,ay,az,wx,wy,wz`).
    Csv,
    /// An EuRoC/ASL `mav0/imu0/data.csv`.
    Euroc,
    /// bag2mat's npy layout.
    Npy,
}

pub(crate) const ALL: [LogFormat; 7] = [
    LogFormat::Ulog,
    LogFormat::UlogNoSync,
    LogFormat::DataflashImu,
    LogFormat::DataflashIsb,
    LogFormat::Csv,
    LogFormat::Euroc,
    LogFormat::Npy,
];

impl LogFormat {
    pub(crate) fn name(self) -> &'static str {
        match self {
            LogFormat::Ulog => "ulog",
            LogFormat::UlogNoSync => "ulog-nosync",
            LogFormat::DataflashImu => "dataflash-imu",
            LogFormat::DataflashIsb => "dataflash-isb",
            LogFormat::Csv => "csv",
            LogFormat::Euroc => "euroc",
            LogFormat::Npy => "npy",
        }
    }

    fn topic(self) -> &'static str {
        match self {
            LogFormat::Ulog | LogFormat::UlogNoSync => "sensor_combined",
            LogFormat::DataflashImu => "IMU:0",
            LogFormat::DataflashIsb => "ISB_GYR",
            LogFormat::Csv | LogFormat::Npy => "imu",
            LogFormat::Euroc => "imu0",
        }
    }

    /// The format name tests/py/log_rows.py knows.
    fn reader(self) -> &'static str {
        match self {
            LogFormat::Ulog | LogFormat::UlogNoSync => "ulog",
            LogFormat::DataflashImu | LogFormat::DataflashIsb => "dataflash",
            LogFormat::Csv => "csv",
            LogFormat::Euroc => "euroc",
            LogFormat::Npy => "npy",
        }
    }

    fn file_name(self) -> &'static str {
        match self {
            LogFormat::Ulog | LogFormat::UlogNoSync => "log.ulg",
            LogFormat::DataflashImu | LogFormat::DataflashIsb => "00000001.BIN",
            LogFormat::Csv => "imu.csv",
            LogFormat::Euroc => "data.csv",
            LogFormat::Npy => "imu.npy",
        }
    }
}

/// One row the generator wrote: record time (ns) and gx gy gz ax ay az (NaN: no sensor).
#[derive(Debug, Clone, Copy)]
struct GenRow {
    t_ns: u64,
    v: [f64; 6],
}

/// Where the format-specific edits aim.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Site {
    /// A ULog message header (size u16, type byte) of a message of this type.
    UlogHeader(u8),
    /// A ULog data message's id (u16).
    UlogMsgId,
    /// An `A` message's id (u16).
    UlogAddId,
    /// An `F` message of an IMU format (its text follows the header).
    UlogFormat,
    /// The flag bits' incompat bytes.
    UlogIncompat,
    /// A DataFlash message of this name (its header's first byte).
    DfMessage(&'static str),
    /// `ISBH`: smp_cnt (u16), type (u8), instance (u8).
    DfSmpCnt,
    DfSensorType,
    DfInstance,
    /// `ISBD`: N (u16), seqno (u16).
    DfBatchN,
    DfSeqno,
    /// `FMT` of IMU/ISBH/ISBD: its message start.
    DfFmt,
    /// A text data line (start).
    Line,
    /// The npy header dictionary.
    NpyHeader,
}

/// A clean log: its bytes, the rows of the topic read, where each row's message or line
/// starts and ends, and the sites of the format's fields.
struct Log {
    bytes: Vec<u8>,
    rows: Vec<GenRow>,
    spans: Vec<(usize, usize)>,
    sites: Vec<(Site, usize)>,
    /// Byte offset where the body (data) starts, for the text formats' header edits.
    body: usize,
}

fn noise(rng: &mut Rng) -> f64 {
    (rng.next() >> 11) as f64 / (1u64 << 53) as f64 - 0.5
}

// ---- ULog (the PX4 documentation's "ULog File Format") ----

const ULOG_MAGIC: &[u8] = b"ULog\x01\x12\x35";
const ULOG_SYNC: [u8; 8] = [0x2F, 0x73, 0x13, 0x20, 0x25, 0x0C, 0xBB, 0x12];
const SENSOR_COMBINED: &str = "sensor_combined:uint64_t timestamp;float[3] gyro_rad;uint32_t gyro_integral_dt;int32_t accelerometer_timestamp_relative;float[3] accelerometer_m_s2;uint32_t accelerometer_integral_dt;uint8_t accelerometer_clipping;uint8_t gyro_clipping;uint8_t accel_calibration_count;uint8_t gyro_calibration_count;";
const SENSOR_GYRO: &str = "sensor_gyro:uint64_t timestamp;uint64_t timestamp_sample;uint32_t device_id;float x;float y;float z;float temperature;uint32_t error_count;uint8_t[3] clip_counter;uint8_t samples;";
const VEHICLE_STATUS: &str = "vehicle_status:uint64_t timestamp;uint8_t arming_state;uint8_t nav_state;uint8_t[6] _padding0;";
const VEHICLE_ATTITUDE: &str = "vehicle_attitude:uint64_t timestamp;uint64_t timestamp_sample;float[4] q;uint8_t quat_reset_counter;uint8_t[7] _padding0;";

struct UlogOut {
    b: Vec<u8>,
    sites: Vec<(Site, usize)>,
    since_sync: usize,
    sync: bool,
}

impl UlogOut {
    fn msg(&mut self, ty: u8, body: &[u8]) -> usize {
        let at = self.b.len();
        self.sites.push((Site::UlogHeader(ty), at));
        self.b.extend_from_slice(&(body.len() as u16).to_le_bytes());
        self.b.push(ty);
        self.b.extend_from_slice(body);
        if ty == b'D' {
            self.sites.push((Site::UlogMsgId, at + 3));
            self.since_sync += 1;
            if self.sync && self.since_sync >= 64 {
                self.since_sync = 0;
                self.msg(b'S', &ULOG_SYNC);
            }
        }
        at
    }
    fn add(&mut self, multi: u8, id: u16, name: &str) {
        let mut b = vec![multi];
        b.extend_from_slice(&id.to_le_bytes());
        b.extend_from_slice(name.as_bytes());
        let at = self.msg(b'A', &b);
        self.sites.push((Site::UlogAddId, at + 4));
    }
    fn info(&mut self, ty: u8, key: &str, value: &[u8]) {
        let mut b = vec![key.len() as u8];
        b.extend_from_slice(key.as_bytes());
        b.extend_from_slice(value);
        self.msg(ty, &b);
    }
}

/// A flight log as PX4's logger writes it: header, flag bits, info, formats, parameters,
/// subscriptions, then data (sensor_combined and sensor_gyro at 200 Hz, vehicle_status at
/// 4 Hz, vehicle_attitude subscribed in mid-file), log messages and a parameter change.
fn ulog(seed: u64, sync: bool) -> Log {
    let mut rng = Rng(seed);
    let mut u = UlogOut {
        b: Vec::new(),
        sites: Vec::new(),
        since_sync: 0,
        sync,
    };
    u.b.extend_from_slice(ULOG_MAGIC);
    u.b.push(1);
    u.b.extend_from_slice(&1_000_000u64.to_le_bytes());
    let at = u.msg(b'B', &[0u8; 40]);
    u.sites.push((Site::UlogIncompat, at + 3 + 8));
    u.info(b'I', "char[8] sys_name", b"PX4\0\0\0\0\0");
    u.info(b'I', "char[10] ver_hw", b"PX4_FMU_V5");
    for f in [
        SENSOR_COMBINED,
        SENSOR_GYRO,
        VEHICLE_STATUS,
        VEHICLE_ATTITUDE,
    ] {
        let at = u.msg(b'F', f.as_bytes());
        if f.starts_with("sensor_") {
            u.sites.push((Site::UlogFormat, at));
        }
    }
    u.info(b'P', "float IMU_GYRO_CUTOFF", &30.0f32.to_le_bytes());
    u.info(b'P', "int32_t SDLOG_PROFILE", &3i32.to_le_bytes());
    u.add(0, 0, "sensor_combined");
    u.add(0, 1, "sensor_gyro");
    u.add(0, 2, "vehicle_status");
    let mut rows = Vec::with_capacity(ROWS);
    let mut spans = Vec::with_capacity(ROWS);
    let t0 = 20_000_000u64;
    for i in 0..ROWS {
        let t = t0 + 5_000 * i as u64;
        let gyro: [f32; 3] = std::array::from_fn(|_| (2e-3 * noise(&mut rng)) as f32);
        let acc: [f32; 3] = std::array::from_fn(|k| {
            (if k == 2 { -9.81 } else { 0.0 } + 0.05 * noise(&mut rng)) as f32
        });
        let mut b = Vec::with_capacity(64);
        b.extend_from_slice(&0u16.to_le_bytes());
        b.extend_from_slice(&t.to_le_bytes());
        gyro.iter()
            .for_each(|x| b.extend_from_slice(&x.to_le_bytes()));
        b.extend_from_slice(&5000u32.to_le_bytes());
        b.extend_from_slice(&0i32.to_le_bytes());
        acc.iter()
            .for_each(|x| b.extend_from_slice(&x.to_le_bytes()));
        b.extend_from_slice(&5000u32.to_le_bytes());
        b.extend_from_slice(&[0, 0, 1, 1]);
        let at = u.msg(b'D', &b);
        spans.push((at, u.b.len()));
        rows.push(GenRow {
            t_ns: t * 1000,
            v: [
                gyro[0] as f64,
                gyro[1] as f64,
                gyro[2] as f64,
                acc[0] as f64,
                acc[1] as f64,
                acc[2] as f64,
            ],
        });
        let mut b = Vec::with_capacity(64);
        b.extend_from_slice(&1u16.to_le_bytes());
        b.extend_from_slice(&(t + 120).to_le_bytes());
        b.extend_from_slice(&(t - 30).to_le_bytes());
        b.extend_from_slice(&0x0024_0010u32.to_le_bytes());
        for x in gyro {
            b.extend_from_slice(&(x + 1e-4).to_le_bytes());
        }
        b.extend_from_slice(&41.5f32.to_le_bytes());
        b.extend_from_slice(&0u32.to_le_bytes());
        b.extend_from_slice(&[0, 0, 0, 1]);
        u.msg(b'D', &b);
        if i % 50 == 0 {
            let mut b = 2u16.to_le_bytes().to_vec();
            b.extend_from_slice(&t.to_le_bytes());
            b.extend_from_slice(&[1, 4]);
            u.msg(b'D', &b);
        }
        if i == ROWS / 3 {
            u.add(0, 3, "vehicle_attitude");
            let mut b = vec![b'6'];
            b.extend_from_slice(&t.to_le_bytes());
            b.extend_from_slice(b"[commander] Takeoff detected");
            u.msg(b'L', &b);
        }
        if i > ROWS / 3 && i % 20 == 0 {
            let mut b = 3u16.to_le_bytes().to_vec();
            b.extend_from_slice(&t.to_le_bytes());
            b.extend_from_slice(&t.to_le_bytes());
            for q in [1.0f32, 0.0, 0.0, 0.0] {
                b.extend_from_slice(&q.to_le_bytes());
            }
            b.push(0);
            u.msg(b'D', &b);
        }
        if i == 2 * ROWS / 3 {
            u.info(b'P', "float IMU_GYRO_CUTOFF", &40.0f32.to_le_bytes());
        }
    }
    Log {
        bytes: u.b,
        rows,
        spans,
        sites: u.sites,
        body: 0,
    }
}

// ---- DataFlash (ArduPilot's "Log file format": FMT-defined binary messages) ----

const DF_HEAD: [u8; 2] = [0xA3, 0x95];
const IMU_FMT: (&str, &str) = (
    "QBffffffIIfBBHH",
    "TimeUS,I,GyrX,GyrY,GyrZ,AccX,AccY,AccZ,EG,EA,T,GH,AH,GHz,AHz",
);
const ISBH_FMT: (&str, &str) = (
    "QHBBHHQf",
    "TimeUS,N,type,instance,mul,smp_cnt,SampleUS,smp_rate",
);
const ISBD_FMT: (&str, &str) = ("QHHaaa", "TimeUS,N,seqno,x,y,z");

fn df_size(fmt: &str) -> usize {
    fmt.bytes()
        .map(|c| match c {
            b'b' | b'B' | b'M' => 1,
            b'h' | b'H' | b'c' | b'C' => 2,
            b'i' | b'I' | b'e' | b'E' | b'L' | b'f' | b'n' => 4,
            b'd' | b'q' | b'Q' => 8,
            b'N' => 16,
            b'Z' | b'a' => 64,
            _ => 0,
        })
        .sum::<usize>()
        + 3
}

struct DfOut {
    b: Vec<u8>,
    sites: Vec<(Site, usize)>,
}

impl DfOut {
    fn msg(&mut self, ty: u8, name: &'static str, payload: &[u8]) -> usize {
        let at = self.b.len();
        self.sites.push((Site::DfMessage(name), at));
        self.b.extend_from_slice(&DF_HEAD);
        self.b.push(ty);
        self.b.extend_from_slice(payload);
        at
    }
    fn fmt(&mut self, ty: u8, name: &str, fmt: &str, cols: &str) {
        let pad = |s: &str, n: usize| {
            let mut v = s.as_bytes().to_vec();
            v.resize(n, 0);
            v
        };
        let mut p = vec![ty, df_size(fmt) as u8];
        p.extend(pad(name, 4));
        p.extend(pad(fmt, 16));
        p.extend(pad(cols, 64));
        let at = self.msg(0x80, "FMT", &p);
        if ty != 0x80 && name != "BARO" {
            self.sites.push((Site::DfFmt, at));
        }
    }
}

/// An ArduPilot log: IMU instances 0 and 1 at 400 Hz (the same TimeUS each loop, as
/// `AP_InertialSensor` logs them), BARO at 10 Hz, and batches of `BATCH` samples of the
/// accelerometer and the gyro of instance 0 (ISBH then its 32 ISBD), every half second.
/// `isb`: the rows are the gyro batches' samples, else IMU instance 0's.
fn dataflash(seed: u64, isb: bool) -> Log {
    let mut rng = Rng(seed);
    let mut d = DfOut {
        b: Vec::new(),
        sites: Vec::new(),
    };
    d.fmt(0x80, "FMT", "BBnNZ", "Type,Length,Name,Format,Columns");
    d.fmt(129, "IMU", IMU_FMT.0, IMU_FMT.1);
    d.fmt(130, "ISBH", ISBH_FMT.0, ISBH_FMT.1);
    d.fmt(131, "ISBD", ISBD_FMT.0, ISBD_FMT.1);
    d.fmt(132, "BARO", "QBfff", "TimeUS,I,Alt,Press,Temp");
    let mut rows = Vec::new();
    let mut spans = Vec::new();
    let t0 = 3_000_000u64;
    let rate = 3200.0f32;
    let (acc_mul, gyro_mul) = (209u16, 939u16);
    let loops = 1000;
    let mut n = 0u16;
    let mut batches = 0;
    for i in 0..loops {
        let t = t0 + 2_500 * i as u64;
        for k in 0..2u8 {
            let v: [f32; 6] = std::array::from_fn(|a| {
                (if a == 5 { -9.80665 } else { 0.0 }
                    + if a < 3 { 1e-3 } else { 3e-2 } * noise(&mut rng)) as f32
            });
            let mut p = t.to_le_bytes().to_vec();
            p.push(k);
            v.iter().for_each(|x| p.extend_from_slice(&x.to_le_bytes()));
            p.extend_from_slice(&[0; 8]);
            p.extend_from_slice(&45.25f32.to_le_bytes());
            p.extend_from_slice(&[1, 1]);
            p.extend_from_slice(&1600u16.to_le_bytes());
            p.extend_from_slice(&1600u16.to_le_bytes());
            let at = d.msg(129, "IMU", &p);
            d.sites.push((Site::DfInstance, at + 3 + 8));
            if k == 0 && !isb {
                spans.push((at, d.b.len()));
                rows.push(GenRow {
                    t_ns: t * 1000,
                    v: v.map(|x| x as f64),
                });
            }
        }
        if i % 40 == 0 {
            let mut p = t.to_le_bytes().to_vec();
            p.push(0);
            for x in [12.5f32, 101_325.0, 30.0] {
                p.extend_from_slice(&x.to_le_bytes());
            }
            d.msg(132, "BARO", &p);
        }
        if i % 200 == 100 && batches < BATCHES {
            batches += 1;
            for (kind, mul) in [(0u8, acc_mul), (1u8, gyro_mul)] {
                let start = t - 400_000;
                let mut p = t.to_le_bytes().to_vec();
                p.extend_from_slice(&n.to_le_bytes());
                p.extend_from_slice(&[kind, 0]);
                p.extend_from_slice(&mul.to_le_bytes());
                p.extend_from_slice(&(BATCH as u16).to_le_bytes());
                p.extend_from_slice(&start.to_le_bytes());
                p.extend_from_slice(&rate.to_le_bytes());
                let at = d.msg(130, "ISBH", &p);
                d.sites.push((Site::DfSmpCnt, at + 3 + 14));
                d.sites.push((Site::DfSensorType, at + 3 + 10));
                d.sites.push((Site::DfInstance, at + 3 + 11));
                for seq in 0..(BATCH / 32) as u16 {
                    let mut p = t.to_le_bytes().to_vec();
                    p.extend_from_slice(&n.to_le_bytes());
                    p.extend_from_slice(&seq.to_le_bytes());
                    let mut xyz = [[0i16; 32]; 3];
                    for (axis, col) in xyz.iter_mut().enumerate() {
                        for x in col.iter_mut() {
                            let g = if kind == 0 && axis == 2 {
                                -9.80665
                            } else {
                                0.0
                            };
                            *x = ((g + 0.05 * noise(&mut rng)) * mul as f64).round() as i16;
                        }
                    }
                    xyz.iter()
                        .flatten()
                        .for_each(|x| p.extend_from_slice(&x.to_le_bytes()));
                    let at = d.msg(131, "ISBD", &p);
                    d.sites.push((Site::DfBatchN, at + 3 + 8));
                    d.sites.push((Site::DfSeqno, at + 3 + 10));
                    if kind == 1 && isb {
                        for k in 0..32 {
                            let j = seq as usize * 32 + k;
                            let tn =
                                start * 1000 + (j as f64 * 1e9 / rate as f64 + 0.5).floor() as u64;
                            let v = xyz.map(|c| c[k] as f64 / mul as f64);
                            spans.push((at, d.b.len()));
                            rows.push(GenRow {
                                t_ns: tn,
                                v: [v[0], v[1], v[2], f64::NAN, f64::NAN, f64::NAN],
                            });
                        }
                    }
                }
                n = n.wrapping_add(1);
            }
        }
    }
    Log {
        bytes: d.b,
        rows,
        spans,
        sites: d.sites,
        body: 0,
    }
}

// ---- text ----

/// A CSV in bag2mat's own layout (t in s with 9 decimals, values as Python's repr would print
/// them), or an EuRoC/ASL data.csv (ns stamps, gyro then acc, CRLF line ends as the datasets
/// have them).
fn text(seed: u64, euroc: bool) -> Log {
    let mut rng = Rng(seed);
    let mut s = String::new();
    let nl = if euroc { "\r\n" } else { "\n" };
    if euroc {
        s.push_str("#timestamp [ns],w_RS_S_x [rad s^-1],w_RS_S_y [rad s^-1],w_RS_S_z [rad s^-1],a_RS_S_x [m s^-2],a_RS_S_y [m s^-2],a_RS_S_z [m s^-2]");
    } else {
        s.push_str("t,ax,ay,az,wx,wy,wz");
    }
    s.push_str(nl);
    let body = s.len();
    let mut rows = Vec::new();
    let mut spans = Vec::new();
    let mut sites = Vec::new();
    let t0: u64 = 1_700_000_000_000_000_000;
    for i in 0..ROWS {
        let t = t0 + 2_500_000 * i as u64;
        let v: [f64; 6] = std::array::from_fn(|a| {
            let level = if a == 5 { 9.81 } else { 0.0 };
            level + if a < 3 { 1e-3 } else { 0.05 } * noise(&mut rng)
        });
        let at = s.len();
        if euroc {
            s.push_str(&format!(
                "{t},{:?},{:?},{:?},{:?},{:?},{:?}",
                v[0], v[1], v[2], v[3], v[4], v[5]
            ));
        } else {
            s.push_str(&format!(
                "{}.{:09},{:?},{:?},{:?},{:?},{:?},{:?}",
                t / 1_000_000_000,
                t % 1_000_000_000,
                v[3],
                v[4],
                v[5],
                v[0],
                v[1],
                v[2]
            ));
        }
        s.push_str(nl);
        sites.push((Site::Line, at));
        spans.push((at, s.len()));
        rows.push(GenRow { t_ns: t, v });
    }
    Log {
        bytes: s.into_bytes(),
        rows,
        spans,
        sites,
        body,
    }
}

// ---- npy ----

/// bag2mat's npy layout: float64 (N, 7), t ax ay az wx wy wz.
fn npy(seed: u64) -> Log {
    let mut rng = Rng(seed);
    let dict = format!("{{'descr': '<f8', 'fortran_order': False, 'shape': ({ROWS}, 7), }}");
    let header_len = (10 + dict.len() + 1).div_ceil(64) * 64 - 10;
    let mut b = b"\x93NUMPY\x01\x00".to_vec();
    b.extend_from_slice(&(header_len as u16).to_le_bytes());
    b.extend_from_slice(dict.as_bytes());
    b.resize(10 + header_len - 1, b' ');
    b.push(b'\n');
    let body = b.len();
    let mut rows = Vec::new();
    let mut spans = Vec::new();
    for i in 0..ROWS {
        let t_ns = 1_700_000_000_000_000_000 + 2_500_000 * i as u64;
        let t = (t_ns / 1_000_000_000) as f64 + (t_ns % 1_000_000_000) as f64 * 1e-9;
        let v: [f64; 6] = std::array::from_fn(|a| {
            let level = if a == 5 { 9.81 } else { 0.0 };
            level + if a < 3 { 1e-3 } else { 0.05 } * noise(&mut rng)
        });
        let at = b.len();
        for x in [t, v[3], v[4], v[5], v[0], v[1], v[2]] {
            b.extend_from_slice(&x.to_le_bytes());
        }
        spans.push((at, b.len()));
        rows.push(GenRow { t_ns, v });
    }
    Log {
        bytes: b,
        rows,
        spans,
        sites: vec![(Site::NpyHeader, 10)],
        body,
    }
}

fn make(f: LogFormat, seed: u64) -> Log {
    match f {
        LogFormat::Ulog => ulog(seed, true),
        LogFormat::UlogNoSync => ulog(seed, false),
        LogFormat::DataflashImu => dataflash(seed, false),
        LogFormat::DataflashIsb => dataflash(seed, true),
        LogFormat::Csv => text(seed, false),
        LogFormat::Euroc => text(seed, true),
        LogFormat::Npy => npy(seed),
    }
}

// ---- damage ----

fn sites_of(log: &Log, pred: impl Fn(Site) -> bool) -> Vec<usize> {
    log.sites
        .iter()
        .filter(|(s, _)| pred(*s))
        .map(|(_, at)| *at)
        .collect()
}

fn pick<T: Copy>(rng: &mut Rng, v: &[T]) -> Option<T> {
    (!v.is_empty()).then(|| v[rng.below(v.len())])
}

/// A new value for a u16 field: 0, max, ±1, doubled, halved, a bit flipped, random.
fn edit_u16(rng: &mut Rng, old: u16) -> u16 {
    match rng.below(8) {
        0 => 0,
        1 => u16::MAX,
        2 => old.wrapping_add(1),
        3 => old.wrapping_sub(1),
        4 => old.wrapping_mul(2),
        5 => old / 2,
        6 => old ^ (1 << rng.below(16)),
        _ => rng.next() as u16,
    }
}

fn get16(b: &[u8], at: usize) -> u16 {
    u16::from_le_bytes([b[at], b[at + 1]])
}

fn put16(b: &mut [u8], at: usize, v: u16) {
    b[at..at + 2].copy_from_slice(&v.to_le_bytes());
}

/// Damage common to every format: bit flips, byte runs, a cut, bytes inserted or deleted.
fn generic(b: &mut Vec<u8>, rng: &mut Rng, op: usize, from: usize) -> (String, Option<usize>) {
    let len = b.len();
    let at = from + rng.below(len - from);
    match op {
        0 => {
            let n = 1 + rng.below(3);
            for _ in 0..n {
                let k = from + rng.below(len - from);
                b[k] ^= 1 << rng.below(8);
            }
            (format!("{n} bit flip(s) from {at}"), None)
        }
        1 => {
            let n = (1 + rng.below(64)).min(len - at);
            let fill = rng.below(3);
            for x in &mut b[at..at + n] {
                *x = match fill {
                    0 => 0,
                    1 => 0xFF,
                    _ => rng.next() as u8,
                };
            }
            (format!("{n}-byte run at {at}"), None)
        }
        2 => {
            b.truncate(at);
            (format!("truncated at {at}"), Some(at))
        }
        3 => {
            let n = 1 + rng.below(40);
            let junk: Vec<u8> = (0..n).map(|_| rng.next() as u8).collect();
            b.splice(at..at, junk);
            (format!("{n} random bytes inserted at {at}"), None)
        }
        _ => {
            let n = (1 + rng.below(40)).min(len - at);
            b.drain(at..at + n);
            (format!("{n} bytes deleted at {at}"), None)
        }
    }
}

/// Variant `v` of a clean log: its bytes, what was done, and where it was cut (if it was).
fn mutate(f: LogFormat, log: &Log, rng: &mut Rng, v: usize) -> (Vec<u8>, String, Option<usize>) {
    let mut b = log.bytes.clone();
    // a third generic damage, two thirds the format's own edits
    if v.is_multiple_of(3) {
        let (what, cut) = generic(&mut b, rng, (v / 3) % 5, 0);
        return (b, what, cut);
    }
    let k = v / 3 + v % 3;
    let (what, cut) = match f {
        LogFormat::Ulog | LogFormat::UlogNoSync => ulog_edit(&mut b, log, rng, k),
        LogFormat::DataflashImu | LogFormat::DataflashIsb => df_edit(&mut b, log, rng, k),
        LogFormat::Csv | LogFormat::Euroc => text_edit(&mut b, log, rng, k, f == LogFormat::Euroc),
        LogFormat::Npy => npy_edit(&mut b, log, rng, k),
    };
    (b, what, cut)
}

fn ulog_edit(b: &mut Vec<u8>, log: &Log, rng: &mut Rng, k: usize) -> (String, Option<usize>) {
    let data = sites_of(log, |s| s == Site::UlogHeader(b'D'));
    let any = sites_of(log, |s| matches!(s, Site::UlogHeader(_)));
    match k % 9 {
        0 => {
            // a message's size
            let at = if rng.below(4) == 0 {
                pick(rng, &any)
            } else {
                pick(rng, &data)
            }
            .unwrap_or(16);
            let old = get16(b, at);
            let new = edit_u16(rng, old);
            put16(b, at, new);
            (format!("msg_size at {at}: {old} -> {new}"), None)
        }
        1 => {
            // a type byte
            let at = if rng.below(3) == 0 {
                pick(rng, &any)
            } else {
                pick(rng, &data)
            }
            .unwrap_or(16)
                + 2;
            let old = b[at];
            let new = if rng.below(4) == 0 {
                [0u8, b'X', b'z', 0xFF][rng.below(4)]
            } else {
                b"BFIMPQARDLCSO"[rng.below(13)]
            };
            b[at] = new;
            (
                format!("type byte at {at}: {} -> {}", old as char, new as char),
                None,
            )
        }
        2 => {
            // a data message's id: another topic's, or any
            let at = pick(rng, &sites_of(log, |s| s == Site::UlogMsgId)).unwrap_or(19);
            let old = get16(b, at);
            let new = if rng.below(2) == 0 {
                rng.below(4) as u16
            } else {
                edit_u16(rng, old)
            };
            put16(b, at, new);
            (format!("message id at {at}: {old} -> {new}"), None)
        }
        3 => {
            // a subscription's id: re-bound to the IMU topic's (or another)
            let at = pick(rng, &sites_of(log, |s| s == Site::UlogAddId)).unwrap_or(19);
            let old = get16(b, at);
            let new = if rng.below(2) == 0 {
                0
            } else {
                edit_u16(rng, old)
            };
            put16(b, at, new);
            (format!("subscription id at {at}: {old} -> {new}"), None)
        }
        4 | 5 => {
            // a format's text: an array length, a type, a name, a separator
            let at = pick(rng, &sites_of(log, |s| s == Site::UlogFormat)).unwrap_or(16);
            let size = get16(b, at) as usize;
            let text = String::from_utf8_lossy(&b[at + 3..at + 3 + size]).into_owned();
            let edits: [(&str, &str); 8] = [
                ("float[3]", "float[4]"),
                ("float[3]", "float[2]"),
                ("float[3]", "float[100000000]"),
                ("uint32_t", "uint64_t"),
                ("float x", "double x"),
                ("uint64_t timestamp;", "uint64_t timestamp"),
                (":uint64_t", "uint64_t"),
                ("uint8_t", "uint8_z"),
            ];
            let (from, to) = edits[rng.below(edits.len())];
            let new = text.replacen(from, to, 1);
            let mut m = (new.len() as u16).to_le_bytes().to_vec();
            m.push(b'F');
            m.extend_from_slice(new.as_bytes());
            b.splice(at..at + 3 + size, m);
            (format!("format at {at}: '{from}' -> '{to}'"), None)
        }
        6 => {
            // a second definition of an IMU format, in mid-file
            let at = pick(rng, &data[data.len() / 3..]).unwrap_or(16);
            let text = if rng.below(2) == 0 {
                SENSOR_COMBINED.replacen("float[3] gyro_rad", "float[4] gyro_rad", 1)
            } else {
                SENSOR_COMBINED.to_string()
            };
            let mut m = (text.len() as u16).to_le_bytes().to_vec();
            m.push(b'F');
            m.extend_from_slice(text.as_bytes());
            b.splice(at..at, m);
            (format!("a second sensor_combined format at {at}"), None)
        }
        7 => {
            // incompatible flags
            let at = pick(rng, &sites_of(log, |s| s == Site::UlogIncompat)).unwrap_or(30);
            let byte = rng.below(8);
            let bit = if byte == 0 {
                1 + rng.below(7)
            } else {
                rng.below(8)
            };
            b[at + byte] |= 1 << bit;
            (format!("incompat flag bit {bit} of byte {byte}"), None)
        }
        _ => {
            // a subscription in mid-file re-binding the IMU topic's id to another topic
            let at = pick(rng, &data[data.len() / 4..]).unwrap_or(16);
            let name = ["vehicle_status", "sensor_gyro", "vehicle_attitude"][rng.below(3)];
            let mut body = vec![rng.below(2) as u8];
            body.extend_from_slice(&0u16.to_le_bytes());
            body.extend_from_slice(name.as_bytes());
            let mut m = (body.len() as u16).to_le_bytes().to_vec();
            m.push(b'A');
            m.extend(body);
            b.splice(at..at, m);
            (
                format!("an A message re-binding id 0 to {name} at {at}"),
                None,
            )
        }
    }
}

fn df_edit(b: &mut Vec<u8>, log: &Log, rng: &mut Rng, k: usize) -> (String, Option<usize>) {
    let imu = sites_of(log, |s| s == Site::DfMessage("IMU"));
    let all = sites_of(log, |s| matches!(s, Site::DfMessage(_)));
    match k % 10 {
        0 => {
            let at = pick(rng, &sites_of(log, |s| s == Site::DfSmpCnt)).unwrap_or(0);
            let old = get16(b, at);
            let new = edit_u16(rng, old);
            put16(b, at, new);
            (format!("ISBH smp_cnt at {at}: {old} -> {new}"), None)
        }
        1 => {
            let at = pick(rng, &sites_of(log, |s| s == Site::DfSensorType)).unwrap_or(0);
            let old = b[at];
            let new = if rng.below(2) == 0 {
                old ^ (1 << rng.below(8))
            } else {
                rng.next() as u8
            };
            b[at] = new;
            (format!("ISBH type at {at}: {old} -> {new}"), None)
        }
        2 => {
            let at = pick(rng, &sites_of(log, |s| s == Site::DfInstance)).unwrap_or(0);
            let old = b[at];
            let new = old ^ (1 << rng.below(8));
            b[at] = new;
            (format!("instance byte at {at}: {old} -> {new}"), None)
        }
        3 => {
            let site = if rng.below(2) == 0 {
                Site::DfSeqno
            } else {
                Site::DfBatchN
            };
            let at = pick(rng, &sites_of(log, |s| s == site)).unwrap_or(0);
            let old = get16(b, at);
            let new = edit_u16(rng, old);
            put16(b, at, new);
            (format!("{site:?} at {at}: {old} -> {new}"), None)
        }
        4 | 5 => {
            // a message cut short (bytes removed at its end) or lengthened
            let at = if rng.below(2) == 0 {
                pick(rng, &imu)
            } else {
                pick(rng, &all)
            }
            .unwrap_or(0);
            let next = all.iter().copied().find(|&x| x > at).unwrap_or(b.len());
            let len = next - at;
            if k % 10 == 4 {
                let n = 1 + rng.below(len - 1);
                b.drain(next - n..next);
                (
                    format!("message at {at} shortened by {n} of {len} bytes"),
                    None,
                )
            } else {
                let n = 1 + rng.below(16);
                let junk: Vec<u8> = (0..n).map(|_| rng.next() as u8).collect();
                b.splice(next..next, junk);
                (format!("message at {at} lengthened by {n} bytes"), None)
            }
        }
        6 => {
            // an FMT's length, type, format string or name
            let at = pick(rng, &sites_of(log, |s| s == Site::DfFmt)).unwrap_or(0);
            let (field, off) = [
                ("type", 3),
                ("length", 4),
                ("name", 5),
                ("format", 9 + rng.below(6)),
            ][rng.below(4)];
            let old = b[at + off];
            b[at + off] ^= 1 << rng.below(8);
            (
                format!(
                    "FMT {field} at {}: {old:#x} -> {:#x}",
                    at + off,
                    b[at + off]
                ),
                None,
            )
        }
        7 => {
            let old = b[0];
            b[0] = rng.next() as u8;
            (format!("first byte {old:#x} -> {:#x}", b[0]), None)
        }
        8 => {
            // a message header's sync bytes or type
            let at = pick(rng, &all).unwrap_or(0) + rng.below(3);
            let old = b[at];
            b[at] = if rng.below(2) == 0 {
                old ^ (1 << rng.below(8))
            } else {
                128 + rng.below(6) as u8
            };
            (
                format!("message header byte at {at}: {old:#x} -> {:#x}", b[at]),
                None,
            )
        }
        _ => {
            // a cut inside a message near the end
            let at = pick(rng, &all[all.len() * 9 / 10..]).unwrap_or(0) + 1 + rng.below(50);
            let at = at.min(b.len() - 1);
            b.truncate(at);
            (format!("truncated inside a message at {at}"), Some(at))
        }
    }
}

fn text_edit(
    b: &mut Vec<u8>,
    log: &Log,
    rng: &mut Rng,
    k: usize,
    euroc: bool,
) -> (String, Option<usize>) {
    let lines = sites_of(log, |s| s == Site::Line);
    let line_end = |b: &[u8], at: usize| {
        at + b[at..]
            .iter()
            .position(|&c| c == b'\n')
            .unwrap_or(b.len() - at)
    };
    let at = pick(rng, &lines).unwrap_or(log.body);
    match k % 11 {
        0 => {
            // an unterminated quote
            let e = line_end(b, at);
            let p = at + rng.below(e - at);
            b.insert(p, b'"');
            (format!("an unterminated quote at {p}"), None)
        }
        1 | 2 => {
            // a value that is no number (in the first data row, or any)
            let at = if k % 11 == 1 { log.body } else { at };
            let e = line_end(b, at);
            let fields: Vec<usize> = std::iter::once(at)
                .chain((at..e).filter(|&i| b[i] == b',').map(|i| i + 1))
                .collect();
            let f = fields[rng.below(fields.len())];
            let fe = (f..e).find(|&i| b[i] == b',' || b[i] == b'\r').unwrap_or(e);
            let new: &[u8] = [&b"abc"[..], b"1.2.3", b"", b"0x1F", b"--1"][rng.below(5)];
            b.splice(f..fe, new.iter().copied());
            (
                format!("field at {f} -> {:?}", String::from_utf8_lossy(new)),
                None,
            )
        }
        3 => {
            // a comment line (right after the header, or anywhere)
            let p = if rng.below(2) == 0 { log.body } else { at };
            let c: &[u8] = if euroc {
                b"# a comment\r\n"
            } else {
                b"# a comment\n"
            };
            b.splice(p..p, c.iter().copied());
            (format!("a comment line inserted at {p}"), None)
        }
        4 => {
            // a long junk line (with or without delimiters)
            let n = 1000 + rng.below(100_000);
            let comma = rng.below(2) == 0;
            let mut junk: Vec<u8> = (0..n)
                .map(|i| {
                    if comma && i % 10 == 9 {
                        b','
                    } else {
                        b'a' + (i % 26) as u8
                    }
                })
                .collect();
            junk.push(b'\n');
            b.splice(at..at, junk);
            (
                format!("a {n}-byte junk line at {at} (delimiters: {comma})"),
                None,
            )
        }
        5 => {
            // two lines merged (a line end removed)
            let e = line_end(b, at);
            if e < b.len() {
                b.remove(e);
                if e > 0 && b[e - 1] == b'\r' {
                    b.remove(e - 1);
                }
            }
            (format!("line end at {e} removed"), None)
        }
        6 => {
            // a line split
            let e = line_end(b, at);
            let p = at + 1 + rng.below(e - at - 1);
            b.insert(p, b'\n');
            (format!("a line end inserted at {p}"), None)
        }
        7 => {
            // a cut inside the last line (its last number, mostly)
            let last = *lines.last().unwrap_or(&log.body);
            let e = line_end(b, last);
            let p = if rng.below(3) == 0 {
                last + rng.below(e - last)
            } else {
                e - 1 - rng.below(6)
            };
            b.truncate(p);
            (format!("truncated in the last line at {p}"), Some(p))
        }
        8 => {
            // a delimiter changed in one line
            let e = line_end(b, at);
            let commas: Vec<usize> = (at..e).filter(|&i| b[i] == b',').collect();
            let p = pick(rng, &commas).unwrap_or(at);
            b[p] = [b';', b' ', b'\t', b'.'][rng.below(4)];
            (format!("delimiter at {p} -> {:?}", b[p] as char), None)
        }
        9 => {
            // a control or non-UTF-8 byte
            let p = at + rng.below(line_end(b, at) - at);
            let new = [0u8, 0x01, 0x7F, 0xC3, 0xFF, b'\r'][rng.below(6)];
            b.insert(p, new);
            (format!("byte {new:#x} inserted at {p}"), None)
        }
        _ => {
            // a line duplicated
            let e = (line_end(b, at) + 1).min(b.len());
            let line = b[at..e].to_vec();
            b.splice(e..e, line);
            (format!("line at {at} duplicated"), None)
        }
    }
}

fn npy_edit(b: &mut Vec<u8>, log: &Log, rng: &mut Rng, k: usize) -> (String, Option<usize>) {
    let header = String::from_utf8_lossy(&b[10..log.body]).into_owned();
    match k % 4 {
        0 => {
            let edits = [
                (format!("({ROWS},"), format!("({},", ROWS + 1)),
                (format!("({ROWS},"), format!("({},", ROWS - 1)),
                (format!("({ROWS},"), "(99999999999,".to_string()),
                ("'<f8'".to_string(), "'<f4'".to_string()),
                ("'<f8'".to_string(), "'>f8'".to_string()),
                ("False".to_string(), "True ".to_string()),
                (", 7)".to_string(), ", 8)".to_string()),
            ];
            let (from, to) = &edits[rng.below(edits.len())];
            let new = header.replacen(from.as_str(), to, 1);
            if new.len() == header.len() {
                b[10..log.body].copy_from_slice(new.as_bytes());
            } else {
                // keep the header's length: take the spaces of its padding
                let mut n = new.into_bytes();
                while n.len() > header.len() {
                    if let Some(p) = n.iter().rposition(|&c| c == b' ') {
                        n.remove(p);
                    } else {
                        break;
                    }
                }
                n.resize(header.len(), b' ');
                b[10..log.body].copy_from_slice(&n);
            }
            (format!("header '{from}' -> '{to}'"), None)
        }
        1 => {
            let at = log.body + rng.below(b.len() - log.body);
            b.truncate(at);
            (format!("data cut at {at}"), Some(at))
        }
        _ => {
            let op = rng.below(2);
            generic(b, rng, op, log.body)
        }
    }
}

// ---- reading and judging ----

/// What bag2mat delivered of the topic: how often each generator row, and other rows.
#[derive(Debug, Default)]
struct Ours {
    got: Vec<u32>,
    other: u64,
}

/// The generator rows by time (ns), for matching printed rows.
struct ByTime(BTreeMap<u64, Vec<u32>>);

fn same(a: f64, b: f64) -> bool {
    a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan())
}

impl ByTime {
    fn new(rows: &[GenRow]) -> ByTime {
        let mut m: BTreeMap<u64, Vec<u32>> = BTreeMap::new();
        for (i, r) in rows.iter().enumerate() {
            m.entry(r.t_ns).or_default().push(i as u32);
        }
        ByTime(m)
    }

    /// The generator row a printed CSV row `t,ax,ay,az,wx,wy,wz` is, if it is one exactly.
    fn find(&self, rows: &[GenRow], line: &str) -> Option<u32> {
        let v: Vec<f64> = line
            .split(',')
            .map(|x| x.parse::<f64>())
            .collect::<Result<_, _>>()
            .ok()?;
        if v.len() != 7 {
            return None;
        }
        let t = v[0] * 1e9;
        let lo = (t - TIME_TOLERANCE_NS).max(0.0) as u64;
        let hi = (t + TIME_TOLERANCE_NS).max(0.0) as u64;
        let vals = [v[4], v[5], v[6], v[1], v[2], v[3]];
        self.0
            .range(lo..=hi)
            .flat_map(|(_, ix)| ix.iter().copied())
            .find(|&i| {
                rows[i as usize]
                    .v
                    .iter()
                    .zip(&vals)
                    .all(|(a, b)| same(*a, *b))
            })
    }
}

fn read_ours(rows: &[GenRow], by: &ByTime, out: &Path) -> Option<Ours> {
    let csv = std::fs::read_to_string(out).ok()?;
    let mut o = Ours {
        got: vec![0; rows.len()],
        other: 0,
    };
    for line in csv.lines().skip(1) {
        match by.find(rows, line) {
            Some(i) => o.got[i as usize] += 1,
            None => o.other += 1,
        }
    }
    Some(o)
}

/// One variant's run, kept for the verdict once the independent reader has read them all.
struct Run {
    v: usize,
    what: String,
    cut: Option<usize>,
    child: ChildRun,
    ours: Option<Ours>,
    file: PathBuf,
}

/// The independent reader's rows of a variant: the clean rows it delivers (or `None`: it
/// fails on the file) and how many others.
#[derive(Debug, Clone)]
struct Theirs {
    rows: Option<Vec<bool>>,
}

/// How a log variant ended (the failures are `Err`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Verdict {
    Clean,
    Altered,
    Warned,
    Duplicated,
    Error,
}

fn judge(f: LogFormat, log: &Log, r: &Run, theirs: &Theirs) -> Result<Verdict, String> {
    let c = &r.child;
    if c.timed_out {
        return Err("hang".into());
    }
    if let Some(s) = c.signal {
        return Err(format!("killed by signal {s}: {}", excerpt(&c.stderr)));
    }
    if c.stderr.contains("panicked") || c.stderr.contains("memory allocation") {
        return Err(format!("panic or abort: {}", excerpt(&c.stderr)));
    }
    if c.stderr.contains("bag2mat: error: out of memory") {
        return Err(format!("memory blow-up: {}", excerpt(&c.stderr)));
    }
    if let Some(l) = c.stderr.lines().find(|l| l.len() > 2000) {
        return Err(format!("a {}-byte stderr line", l.len()));
    }
    // a truncated file holds the rows whose message (line) starts before the cut
    let expected: Vec<bool> = log
        .spans
        .iter()
        .map(|&(s, _)| r.cut.is_none_or(|c| s < c))
        .collect();
    let theirs_n = theirs.rows.as_ref().map_or(0, |t| {
        t.iter().zip(&expected).filter(|(a, e)| **a && **e).count()
    });
    match c.code {
        Some(0) => {}
        Some(1) => {
            let errors = c
                .stderr
                .lines()
                .filter(|l| l.starts_with("bag2mat: error: "))
                .count();
            if errors != 1 {
                return Err(format!(
                    "exit 1 without one clear error line: {}",
                    excerpt(&c.stderr)
                ));
            }
            if theirs_n > 0 {
                return Err(format!(
                    "refused a file {} reads ({theirs_n} rows): {}",
                    f.reader(),
                    excerpt(&c.stderr)
                ));
            }
            return Ok(Verdict::Error);
        }
        code => return Err(format!("exit code {code:?}: {}", excerpt(&c.stderr))),
    }
    let Some(o) = &r.ours else {
        return Err("exit 0 but no output".into());
    };
    let missing = expected
        .iter()
        .zip(&o.got)
        .filter(|(e, n)| **e && **n == 0)
        .count() as u64;
    let twice = o.got.iter().filter(|&&n| n > 1).count();
    let lost = missing.saturating_sub(o.other);
    let more = theirs.rows.as_ref().map_or(0, |t| {
        t.iter()
            .zip(&o.got)
            .filter(|(t, n)| **t && **n == 0)
            .count() as u64
    });
    if more > o.other {
        return Err(format!(
            "{} recovers {more} rows bag2mat does not deliver: {}",
            f.reader(),
            excerpt(&c.stderr)
        ));
    }
    let rep = reported_losses(&c.stderr, f.topic());
    if lost > 0 && !rep.said {
        return Err(format!(
            "{lost} rows lost in silence: {}",
            excerpt(&c.stderr)
        ));
    }
    if rep.total() < lost {
        return Err(format!(
            "{lost} rows lost, {} reported: {}",
            rep.total(),
            excerpt(&c.stderr)
        ));
    }
    if rep.lost + rep.undecodable > lost {
        return Err(format!(
            "false loss: {} rows reported lost, {lost} lost: {}",
            rep.lost + rep.undecodable,
            excerpt(&c.stderr)
        ));
    }
    Ok(if lost > 0 {
        Verdict::Warned
    } else if twice > 0 {
        Verdict::Duplicated
    } else if missing > 0 || o.other > 0 {
        Verdict::Altered
    } else {
        Verdict::Clean
    })
}

/// The first lines of a stderr, short (a warning must quote little; this is for the report).
fn excerpt(s: &str) -> String {
    let t: String = s.trim().lines().take(6).collect::<Vec<_>>().join(" | ");
    t.chars().take(600).collect()
}

fn parse_ranges(s: &str, n: usize) -> Vec<bool> {
    let mut v = vec![false; n];
    if s == "-" {
        return v;
    }
    for r in s.split(',') {
        let (a, b) = r.split_once('-').unwrap_or((r, r));
        let (a, b): (usize, usize) = (a.parse().unwrap_or(0), b.parse().unwrap_or(0));
        for x in v.iter_mut().take(b.min(n.saturating_sub(1)) + 1).skip(a) {
            *x = true;
        }
    }
    v
}

/// Runs tests/py/log_rows.py over the clean file and every variant; checks its clean rows
/// are the generator's and returns its rows of each variant.
fn independent(f: LogFormat, clean: &Path, log: &Log, files: &[PathBuf]) -> Vec<Theirs> {
    let out = Command::new(venv_tool("python"))
        .arg(py_script("log_rows.py"))
        .args([f.reader(), f.topic()])
        .arg(clean)
        .args(files)
        .output()
        .expect("run log_rows.py");
    assert!(
        out.status.success(),
        "log_rows.py: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8_lossy(&out.stdout);
    let mut lines = text.lines();
    let n: usize = lines
        .next()
        .and_then(|l| l.strip_prefix("N "))
        .and_then(|x| x.parse().ok())
        .expect("log_rows.py: the clean count");
    assert_eq!(
        n,
        log.rows.len(),
        "{}: the independent reader's clean rows",
        f.name()
    );
    for (i, r) in log.rows.iter().enumerate() {
        let l = lines.next().expect("a clean row");
        let v: Vec<f64> = l.split(' ').map(|x| x.parse().expect("a number")).collect();
        let t_ok = (v[0] - r.t_ns as f64).abs() <= TIME_TOLERANCE_NS
            || (v[0] * 1e9 - r.t_ns as f64).abs() <= TIME_TOLERANCE_NS;
        assert!(
            t_ok && v[1..].iter().zip(&r.v).all(|(a, b)| same(*a, *b)),
            "{}: the independent reader's clean row {i} is {l}, the generator's {r:?}",
            f.name()
        );
    }
    let theirs: Vec<Theirs> = lines
        .map(|l| {
            if l.starts_with("E ") {
                return Theirs { rows: None };
            }
            let ranges = l.split(' ').nth(1).unwrap_or("-");
            Theirs {
                rows: Some(parse_ranges(ranges, n)),
            }
        })
        .collect();
    assert_eq!(
        theirs.len(),
        files.len(),
        "log_rows.py: one line per variant"
    );
    theirs
}

/// The counts of one format's variants (and the slowest), for the summary line.
#[derive(Default)]
pub(crate) struct LogTally {
    pub(crate) clean: usize,
    pub(crate) altered: usize,
    pub(crate) warned: usize,
    pub(crate) duplicated: usize,
    pub(crate) error: usize,
    pub(crate) failed: usize,
    pub(crate) secs: f64,
}

/// How the campaign runs: the binary, a work directory, the seed, variants per format (or
/// only one, kept), and whether every variant that does not read clean is printed.
pub(crate) struct Settings<'a> {
    pub(crate) bin: &'a Path,
    pub(crate) dir: &'a Path,
    pub(crate) seed: u64,
    pub(crate) variants: usize,
    pub(crate) only: Option<usize>,
    pub(crate) verbose: bool,
}

/// Runs the damaged copies of format `f` (number `fi`) through bag2mat and the independent
/// reader; prints each failure (and, `verbose`, each variant that does not read clean).
pub(crate) fn campaign(f: LogFormat, fi: usize, set: &Settings) -> LogTally {
    let Settings {
        bin,
        dir,
        seed,
        variants,
        only,
        verbose,
    } = *set;
    let t0 = Instant::now();
    let log = make(f, seed ^ 0x4545);
    let base = dir.join(format!("log{fi}"));
    std::fs::create_dir_all(&base).expect("dir");
    let input_of = |root: &Path| -> PathBuf {
        if f == LogFormat::Euroc {
            let d = root.join("mav0/imu0");
            std::fs::create_dir_all(&d).expect("euroc dir");
            d.join(f.file_name())
        } else {
            std::fs::create_dir_all(root).expect("dir");
            root.join(f.file_name())
        }
    };
    let clean = input_of(&base.join("clean"));
    std::fs::write(&clean, &log.bytes).expect("write clean log");
    let by = ByTime::new(&log.rows);
    let r = run_child(bin, &clean, f.topic(), &base.join("clean.csv"));
    assert!(
        r.code == Some(0) && r.stderr.is_empty(),
        "{}: the clean log does not read cleanly: {r:?}",
        f.name()
    );
    let o = read_ours(&log.rows, &by, &base.join("clean.csv")).expect("clean output");
    assert!(
        o.other == 0 && o.got.iter().all(|&n| n == 1),
        "{}: the clean read is not the generator's rows",
        f.name()
    );
    let keep = base.join("kept");
    std::fs::create_dir_all(&keep).expect("keep dir");
    let runs: Mutex<Vec<Run>> = Mutex::new(Vec::new());
    let next = AtomicUsize::new(0);
    let threads = std::thread::available_parallelism()
        .map(|n| n.get())
        .unwrap_or(2);
    std::thread::scope(|s| {
        for w in 0..threads {
            let (log, runs, next, by, keep, base) = (&log, &runs, &next, &by, &keep, &base);
            s.spawn(move || {
                let work = base.join(format!("w{w}"));
                let input = input_of(&work);
                let out = work.join("out.csv");
                loop {
                    let v = next.fetch_add(1, Ordering::Relaxed);
                    if v >= variants {
                        break;
                    }
                    if only.is_some_and(|k| k != v) {
                        continue;
                    }
                    let mut rng =
                        Rng(seed ^ ((fi as u64 + 100) << 48) ^ (v as u64).wrapping_mul(0x9E37));
                    let (bad, what, cut) = mutate(f, log, &mut rng, v);
                    std::fs::write(&input, &bad).expect("write variant");
                    let file = keep.join(format!("v{v}_{}", f.file_name()));
                    std::fs::write(&file, &bad).expect("keep variant");
                    if only.is_some() {
                        println!("kept {what} as {}", file.display());
                    }
                    let _ = std::fs::remove_file(&out);
                    let child = run_child(bin, &input, f.topic(), &out);
                    let ours = (child.code == Some(0))
                        .then(|| read_ours(&log.rows, by, &out))
                        .flatten();
                    runs.lock().expect("runs").push(Run {
                        v,
                        what,
                        cut,
                        child,
                        ours,
                        file,
                    });
                }
            });
        }
    });
    let mut runs = runs.into_inner().expect("runs");
    runs.sort_by_key(|r| r.v);
    let files: Vec<PathBuf> = runs.iter().map(|r| r.file.clone()).collect();
    let theirs = independent(f, &clean, &log, &files);
    let mut t = LogTally::default();
    for (r, th) in runs.iter().zip(&theirs) {
        let verdict = judge(f, &log, r, th);
        if verbose && !matches!(verdict, Ok(Verdict::Clean)) {
            let first = r
                .child
                .stderr
                .lines()
                .find(|l| l.contains("error") || l.contains("warning"))
                .unwrap_or("");
            println!("{} {} {}: {verdict:?}: {first}", f.name(), r.v, r.what);
        }
        match verdict {
            Ok(Verdict::Clean) => t.clean += 1,
            Ok(Verdict::Altered) => t.altered += 1,
            Ok(Verdict::Warned) => t.warned += 1,
            Ok(Verdict::Duplicated) => t.duplicated += 1,
            Ok(Verdict::Error) => t.error += 1,
            Err(e) => {
                t.failed += 1;
                println!("FAIL {} variant {} ({}): {e}", f.name(), r.v, r.what);
            }
        }
    }
    if only.is_none() {
        let _ = std::fs::remove_dir_all(&keep);
    }
    t.secs = t0.elapsed().as_secs_f64();
    t
}

impl LogFormat {
    /// The independent reader, as the summary names it.
    pub(crate) fn reader_name(self) -> &'static str {
        match self.reader() {
            "ulog" => "pyulog",
            "dataflash" => "DFReader",
            "npy" => "numpy",
            _ => "pandas",
        }
    }
}
