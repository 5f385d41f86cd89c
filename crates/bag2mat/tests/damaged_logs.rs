//! Damaged logs from outside ROS lose nothing in silence (issue 45): each class of damage
//! the corruption campaign found in the ULog, DataFlash, text and npy readers, on a log a
//! small generator of the test's own writes, damaged one way, read by the real binary. A row
//! is read where the data hold it (at least where the independent reader — pyulog,
//! DFReader, pandas — reads it), and every row not delivered is counted in the topic's
//! `warning:` summary, no more than were lost; a warning quotes little of a bad line; counts
//! in a file never size memory.

use std::io::Write;
use std::os::unix::process::CommandExt;
use std::path::{Path, PathBuf};
use std::process::Command;

use bag2mat::test_tools::{Reported, reported_losses, venv_python, workspace};
use bag2mat::{NoSuchPart, PartError, SkipReason};

fn bag2mat() -> Command {
    Command::new(env!("CARGO_BIN_EXE_bag2mat"))
}

/// What converting one topic gave: success, stderr and the rows printed.
struct Conv {
    ok: bool,
    stderr: String,
    rows: Vec<String>,
}

impl Conv {
    fn lost(&self, topic: &str) -> Reported {
        reported_losses(&self.stderr, topic)
    }
}

/// Converts `topic` of `input` to CSV (`cmd` may limit the child first).
fn convert_with(input: &Path, topic: &str, limit: Option<u64>) -> Conv {
    let out = input.with_file_name(format!(
        "{}.{}.csv",
        input.file_name().unwrap().to_string_lossy(),
        topic.replace(':', "_")
    ));
    let _ = std::fs::remove_file(&out);
    let mut cmd = bag2mat();
    cmd.arg(input)
        .arg(topic)
        .arg("-o")
        .arg(&out)
        .args(["--format", "csv", "-q"]);
    if let Some(bytes) = limit {
        // SAFETY: setrlimit is async-signal-safe and touches only the child.
        unsafe {
            cmd.pre_exec(move || {
                let lim = libc::rlimit {
                    rlim_cur: bytes,
                    rlim_max: bytes,
                };
                if libc::setrlimit(libc::RLIMIT_AS, &lim) != 0 {
                    return Err(std::io::Error::last_os_error());
                }
                Ok(())
            });
        }
    }
    let o = cmd.output().expect("run bag2mat");
    let rows = std::fs::read_to_string(&out)
        .map(|s| s.lines().skip(1).map(str::to_string).collect())
        .unwrap_or_default();
    Conv {
        ok: o.status.success(),
        stderr: String::from_utf8_lossy(&o.stderr).into_owned(),
        rows,
    }
}

fn convert(input: &Path, topic: &str) -> Conv {
    convert_with(input, topic, None)
}

/// Rows of `clean` lost in `damaged`: missing from it, less the rows it has that `clean`
/// has not (a row whose values damage changed is delivered, altered, not lost).
fn missing(clean: &Conv, damaged: &Conv) -> usize {
    let have: std::collections::HashSet<&String> = damaged.rows.iter().collect();
    let had: std::collections::HashSet<&String> = clean.rows.iter().collect();
    let gone = clean.rows.iter().filter(|r| !have.contains(r)).count();
    let other = damaged.rows.iter().filter(|r| !had.contains(r)).count();
    gone.saturating_sub(other)
}

/// How many rows of the clean file the independent reader of `format` recovers from
/// `damaged` (tests/py/log_rows.py), or `None` when it fails on it.
fn independent(format: &str, topic: &str, clean: &Path, damaged: &Path) -> Option<usize> {
    let out = Command::new(venv_python())
        .arg(workspace().join("crates/bag2mat/tests/py/log_rows.py"))
        .args([format, topic])
        .arg(clean)
        .arg(damaged)
        .output()
        .expect("run log_rows.py");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8_lossy(&out.stdout).into_owned();
    let last = text.lines().last().unwrap_or("");
    let ranges = last.strip_prefix("R ")?.split(' ').next()?;
    if ranges == "-" {
        return Some(0);
    }
    Some(
        ranges
            .split(',')
            .map(|r| {
                let (a, b) = r.split_once('-').unwrap();
                b.parse::<usize>().unwrap() - a.parse::<usize>().unwrap() + 1
            })
            .sum(),
    )
}

// ---- a ULog of the test's own ----

const SYNC: [u8; 8] = [0x2F, 0x73, 0x13, 0x20, 0x25, 0x0C, 0xBB, 0x12];
const COMBINED: &str = "sensor_combined:uint64_t timestamp;float[3] gyro_rad;uint32_t gyro_integral_dt;int32_t accelerometer_timestamp_relative;float[3] accelerometer_m_s2;uint32_t accelerometer_integral_dt;uint8_t accelerometer_clipping;uint8_t gyro_clipping;uint8_t accel_calibration_count;uint8_t gyro_calibration_count;";
const STATUS: &str = "vehicle_status:uint64_t timestamp;uint8_t arming_state;uint8_t nav_state;uint8_t[6] _padding0;";
const ATTITUDE: &str = "vehicle_attitude:uint64_t timestamp;float[4] q;";

/// A ULog as PX4 writes one: `sensor_combined` (id 0) at 200 Hz, `vehicle_status` (id 1)
/// now and then, a sync marker every `sync` data messages (0: none). Returns the bytes and
/// where each message starts, with its type.
struct Ulog {
    b: Vec<u8>,
    msgs: Vec<(usize, u8)>,
}

impl Ulog {
    fn msg(&mut self, ty: u8, body: &[u8]) {
        self.msgs.push((self.b.len(), ty));
        self.b.extend_from_slice(&(body.len() as u16).to_le_bytes());
        self.b.push(ty);
        self.b.extend_from_slice(body);
    }

    fn new(rows: u64, sync: usize, formats: &[&str]) -> Ulog {
        let mut u = Ulog {
            b: b"ULog\x01\x12\x35\x01".to_vec(),
            msgs: Vec::new(),
        };
        u.b.extend_from_slice(&0u64.to_le_bytes());
        u.msg(b'B', &[0u8; 40]);
        for f in formats {
            u.msg(b'F', f.as_bytes());
        }
        let add = |u: &mut Ulog, id: u16, name: &str| {
            let mut a = vec![0u8];
            a.extend_from_slice(&id.to_le_bytes());
            a.extend_from_slice(name.as_bytes());
            u.msg(b'A', &a);
        };
        add(&mut u, 0, "sensor_combined");
        add(&mut u, 1, "vehicle_status");
        for i in 0..rows {
            let t = 1_000_000 + 5_000 * i;
            let mut d = 0u16.to_le_bytes().to_vec();
            d.extend_from_slice(&t.to_le_bytes());
            for k in 0..3 {
                d.extend_from_slice(&((i as f32) * 1e-4 + k as f32).to_le_bytes());
            }
            d.extend_from_slice(&[0u8; 8]);
            for k in 0..3 {
                d.extend_from_slice(&(9.81 - (i % 7) as f32 * 1e-3 + k as f32).to_le_bytes());
            }
            d.extend_from_slice(&[0u8; 8]);
            u.msg(b'D', &d);
            if i % 25 == 0 {
                let mut s = 1u16.to_le_bytes().to_vec();
                s.extend_from_slice(&t.to_le_bytes());
                s.extend_from_slice(&[1, 2]);
                u.msg(b'D', &s);
            }
            if sync > 0 && i as usize % sync == sync - 1 {
                u.msg(b'S', &SYNC);
            }
        }
        u
    }

    /// The `k`-th data message of `sensor_combined` (its offset).
    fn combined(&self, k: usize) -> usize {
        self.msgs
            .iter()
            .filter(|(at, ty)| *ty == b'D' && self.b[at + 3] == 0)
            .nth(k)
            .unwrap()
            .0
    }

    fn write(&self, dir: &Path, name: &str) -> PathBuf {
        let p = dir.join(name);
        std::fs::write(&p, &self.b).unwrap();
        p
    }
}

/// The clean log and its conversion.
fn clean_ulog(dir: &Path, sync: usize) -> (Ulog, PathBuf, Conv) {
    let u = Ulog::new(2000, sync, &[COMBINED, STATUS, ATTITUDE]);
    let p = u.write(dir, "clean.ulg");
    let c = convert(&p, "sensor_combined");
    assert!(
        c.ok && c.rows.len() == 2000 && c.stderr.is_empty(),
        "{}",
        c.stderr
    );
    (u, p, c)
}

/// A damaged variant, written and converted; asserts that what was not delivered is counted
/// (at least, and no more than lost) and that pyulog recovers no row it does not.
fn check_ulog(dir: &Path, clean: (&Path, &Conv), bytes: &[u8], name: &str) -> (Conv, usize) {
    let p = dir.join(name);
    std::fs::write(&p, bytes).unwrap();
    let d = convert(&p, "sensor_combined");
    assert!(d.ok, "{name}: {}", d.stderr);
    let lost = missing(clean.1, &d);
    let said = d.lost("sensor_combined");
    assert!(
        said.total() >= lost as u64 && said.lost <= lost as u64,
        "{name}: {lost} rows lost, said {said:?}: {}",
        d.stderr
    );
    if let Some(theirs) = independent("ulog", "sensor_combined", clean.0, &p) {
        assert!(
            d.rows.len() >= theirs,
            "{name}: pyulog recovers {theirs} rows, bag2mat {}",
            d.rows.len()
        );
    }
    (d, lost)
}

/// A message size made too large swallows no message in silence: the message is read by its
/// format's size, and what it swallowed is read too.
#[test]
fn ulog_a_data_message_size_too_large_swallows_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let (u, p, c) = clean_ulog(dir.path(), 0);
    for (k, add) in [(100usize, 1u16), (700, 53), (1500, 0x4000)] {
        let mut b = u.b.clone();
        let at = u.combined(k);
        let size = u16::from_le_bytes([b[at], b[at + 1]]);
        b[at..at + 2].copy_from_slice(&(size + add).to_le_bytes());
        let (d, lost) = check_ulog(dir.path(), (&p, &c), &b, &format!("size{k}.ulg"));
        assert_eq!(lost, 0, "+{add}: every row is read: {}", d.stderr);
    }
}

/// A data message that does not fit its subscription is read where its bytes say which
/// topic it is (a message id landing on another topic, a type byte turned to `S`, `F`, `B`,
/// `R`), and a subscription naming no format does not re-bind the IMU topic's id.
#[test]
fn ulog_a_data_message_that_does_not_fit_its_subscription_is_read_as_what_it_is() {
    let dir = tempfile::tempdir().unwrap();
    let (u, p, c) = clean_ulog(dir.path(), 0);
    // a message id landing on vehicle_status's, and on vehicle_attitude's (no data yet)
    for (k, id) in [(300usize, 1u16), (400, 2)] {
        let mut b = u.b.clone();
        let at = u.combined(k);
        b[at + 3..at + 5].copy_from_slice(&id.to_le_bytes());
        let (d, lost) = check_ulog(dir.path(), (&p, &c), &b, &format!("id{k}.ulg"));
        assert_eq!(lost, 0, "id {id}: {}", d.stderr);
    }
    // a type byte turned into another type's
    for (k, ty) in [
        (500usize, b'S'),
        (600, b'F'),
        (700, b'B'),
        (800, b'R'),
        (900, b'O'),
    ] {
        let mut b = u.b.clone();
        b[u.combined(k) + 2] = ty;
        let (d, lost) = check_ulog(dir.path(), (&p, &c), &b, &format!("ty{k}.ulg"));
        assert_eq!(lost, 0, "{}: {}", ty as char, d.stderr);
    }
    // a data message's type byte turned into A in mid-file: a subscription to no format
    let mut b = u.b.clone();
    b[u.combined(1000) + 2] = b'A';
    let (d, lost) = check_ulog(dir.path(), (&p, &c), &b, "add.ulg");
    assert!(lost <= 1, "{}", d.stderr);
}

/// PX4's gyro FIFO topic as the firmware defines it: `samples` rows of `x`/`y`/`z` (scaled by
/// `scale`), `dt` µs apart.
const GYRO_FIFO: &str = "sensor_gyro_fifo:uint64_t timestamp;uint64_t timestamp_sample;uint32_t device_id;float dt;float scale;int16_t[32] x;int16_t[32] y;int16_t[32] z;uint8_t samples;uint8_t rotation;uint8_t[2] _padding0;";

/// A FIFO message of several samples whose `dt` is zero cannot place its samples in time:
/// it is skipped with the kind that says it does not decode, naming its topic, and every
/// other message of its part is delivered. Told by the skip reason's kind, not its words.
#[test]
fn ulog_a_fifo_message_with_a_zero_dt_is_skipped_as_undecodable() {
    const MESSAGES: u64 = 200;
    const SAMPLES: u8 = 4;
    const BAD: u64 = 120;
    let dir = tempfile::tempdir().unwrap();
    let mut u = Ulog {
        b: b"ULog\x01\x12\x35\x01".to_vec(),
        msgs: Vec::new(),
    };
    u.b.extend_from_slice(&0u64.to_le_bytes());
    u.msg(b'B', &[0u8; 40]);
    u.msg(b'F', GYRO_FIFO.as_bytes());
    u.msg(b'A', b"\x00\x00\x00sensor_gyro_fifo");
    for i in 0..MESSAGES {
        let t = 1_000_000 + 1_000 * i;
        let mut d = 0u16.to_le_bytes().to_vec();
        d.extend_from_slice(&t.to_le_bytes()); // timestamp
        d.extend_from_slice(&t.to_le_bytes()); // timestamp_sample
        d.extend_from_slice(&7u32.to_le_bytes()); // device_id
        let dt: f32 = if i == BAD { 0.0 } else { 250.0 };
        d.extend_from_slice(&dt.to_le_bytes());
        d.extend_from_slice(&1e-3f32.to_le_bytes()); // scale
        for axis in 0..3i16 {
            for k in 0..32i16 {
                d.extend_from_slice(&(axis * 100 + k).to_le_bytes());
            }
        }
        d.extend_from_slice(&[SAMPLES, 0, 0, 0]); // samples, rotation, padding
        u.msg(b'D', &d);
    }
    let p = dir.path().join("fifo.ulg");
    std::fs::write(&p, &u.b).unwrap();
    let src = bag2mat::open_input(&p).unwrap();
    let (mut rows, mut skipped, mut reasons) = (0u64, 0u64, Vec::new());
    for k in 0..src.parts().len() {
        let r = src.read_part(k, &|_| true, &mut |_, _, _| {});
        assert!(r.error.is_none(), "{:?}", r.error);
        rows += r.delivered;
        skipped += r.skipped;
        reasons.extend(r.skip_reason);
    }
    let per = u64::from(SAMPLES);
    assert_eq!((rows, skipped), ((MESSAGES - 1) * per, per), "{reasons:?}");
    assert!(
        matches!(
            reasons.as_slice(),
            [SkipReason::Undecodable { topic, .. }] if topic == "sensor_gyro_fifo"
        ),
        "{reasons:?}"
    );
    let past = src.read_part(src.parts().len(), &|_| true, &mut |_, _, _| {});
    assert!(
        matches!(
            past.error,
            Some(PartError::NoSuchPart {
                wording: NoSuchPart::Numbered,
                ..
            })
        ),
        "{:?}",
        past.error
    );
}

/// An unknown message type is skipped by its size (as pyulog skips it), not to the next
/// sync marker; without sync markers one bad byte costs one message, counted on its topic.
#[test]
fn ulog_damage_costs_the_damaged_message_only_and_is_counted_per_topic() {
    let dir = tempfile::tempdir().unwrap();
    for sync in [64usize, 0] {
        let (u, p, c) = clean_ulog(dir.path(), sync);
        // an unknown type
        let mut b = u.b.clone();
        b[u.combined(200) + 2] = b'X';
        let (d, lost) = check_ulog(dir.path(), (&p, &c), &b, "unknown.ulg");
        assert!(lost <= 1, "sync {sync}: {}", d.stderr);
        // a byte run over a message's header
        let mut b = u.b.clone();
        let at = u.combined(1202);
        b[at..at + 20].fill(0xFF);
        let (d, lost) = check_ulog(dir.path(), (&p, &c), &b, "run.ulg");
        assert_eq!(lost, 1, "sync {sync}: {}", d.stderr);
        assert!(
            d.stderr.contains("messages on 'sensor_combined' were lost"),
            "a per-topic count: {}",
            d.stderr
        );
    }
}

/// A declared array length never sizes memory or time: `float[100000000]` in a small log
/// is refused (a format larger than any message) at once, under a tight memory limit.
#[test]
fn ulog_a_huge_array_length_sizes_no_memory() {
    /// Address space the child may take: far less than 1e8 slots would.
    const LIMIT: u64 = 256 << 20;
    let dir = tempfile::tempdir().unwrap();
    let u = Ulog::new(
        200,
        0,
        &[
            &COMBINED.replace("float[3] gyro_rad", "float[100000000] gyro_rad"),
            STATUS,
            ATTITUDE,
        ],
    );
    let p = u.write(dir.path(), "huge.ulg");
    let t = std::time::Instant::now();
    let d = convert_with(&p, "sensor_combined", Some(LIMIT));
    assert!(
        !d.ok && d.stderr.starts_with("bag2mat: error: ") && !d.stderr.contains("out of memory"),
        "{}",
        d.stderr
    );
    assert!(t.elapsed().as_secs() < 10, "{:?}", t.elapsed());
}

/// A format changed by one byte (`float[3]` → `float[4]`) scrambles no row in silence: the
/// messages do not fit it, and the topic says so with their count; a second, different
/// definition is read by the one the messages fit.
#[test]
fn ulog_a_damaged_or_repeated_format_scrambles_no_row() {
    let dir = tempfile::tempdir().unwrap();
    let (_, p, c) = clean_ulog(dir.path(), 0);
    let wrong = COMBINED.replace("float[3] gyro_rad", "float[4] gyro_rad");
    let u = Ulog::new(2000, 0, &[&wrong, STATUS, ATTITUDE]);
    let d = convert(&u.write(dir.path(), "f4.ulg"), "sensor_combined");
    assert!(d.rows.is_empty(), "no scrambled row: {}", d.rows.len());
    assert!(
        d.stderr
            .contains("2000 of 2000 messages on 'sensor_combined' were lost")
            && d.stderr.contains("do not fit their format's size"),
        "{}",
        d.stderr
    );
    // defined twice: the damaged one last (it would win), the messages fit the first
    let u = Ulog::new(2000, 0, &[COMBINED, &wrong, STATUS, ATTITUDE]);
    let (d, lost) = check_ulog(dir.path(), (&p, &c), &u.b, "twice.ulg");
    assert_eq!(lost, 0, "{}", d.stderr);
    assert!(d.stderr.contains("defined a second time"), "{}", d.stderr);
}

/// Incompatibility flags the reader does not know refuse the log (pyulog refuses it too);
/// definitions pyulog reads through (an unused topic's format damaged, an information
/// message damaged) do not.
#[test]
fn ulog_unknown_incompatibility_flags_refuse_and_unused_definitions_do_not() {
    let dir = tempfile::tempdir().unwrap();
    let (u, p, c) = clean_ulog(dir.path(), 0);
    let flags = u.msgs[0].0 + 3 + 8;
    let mut b = u.b.clone();
    b[flags] |= 0x04;
    std::fs::write(dir.path().join("flags.ulg"), &b).unwrap();
    let d = convert(&dir.path().join("flags.ulg"), "sensor_combined");
    assert!(
        !d.ok && d.stderr.contains("incompatibility flags"),
        "{}",
        d.stderr
    );
    // the unused vehicle_attitude format damaged: its text no definition
    let f = u.msgs.iter().filter(|m| m.1 == b'F').nth(2).unwrap().0;
    let mut b = u.b.clone();
    b[f + 3 + 16] = b';';
    let (d, lost) = check_ulog(dir.path(), (&p, &c), &b, "deffmt.ulg");
    assert_eq!(lost, 0, "{}", d.stderr);
    // vehicle_status's format damaged: its subscription names no format, its data are orphans
    let f = u.msgs.iter().filter(|m| m.1 == b'F').nth(1).unwrap().0;
    let mut b = u.b.clone();
    b[f + 3 + 3] = b':';
    let (d, lost) = check_ulog(dir.path(), (&p, &c), &b, "defstatus.ulg");
    assert_eq!(lost, 0, "{}", d.stderr);
}

// ---- a DataFlash log of the test's own ----

/// An ArduPilot log: FMT, IMU instances 0 and 1 each loop (one TimeUS), and gyro batches
/// (ISBH and 32 ISBD of 32 samples) of instance 0. Returns the bytes and the offset of each
/// message with its type.
fn dataflash(loops: u64, batches: u16) -> (Vec<u8>, Vec<(usize, u8)>) {
    struct Out {
        b: Vec<u8>,
        at: Vec<(usize, u8)>,
    }
    impl Out {
        fn msg(&mut self, ty: u8, p: &[u8]) {
            self.at.push((self.b.len(), ty));
            self.b.extend_from_slice(&[0xA3, 0x95, ty]);
            self.b.extend_from_slice(p);
        }
        fn fmt(&mut self, ty: u8, name: &str, f: &str, cols: &str, len: u8) {
            let mut p = vec![ty, len];
            for (s, n) in [(name, 4), (f, 16), (cols, 64)] {
                let mut v = s.as_bytes().to_vec();
                v.resize(n, 0);
                p.extend(v);
            }
            self.msg(0x80, &p);
        }
    }
    let mut o = Out {
        b: Vec::new(),
        at: Vec::new(),
    };
    o.fmt(0x80, "FMT", "BBnNZ", "Type,Length,Name,Format,Columns", 89);
    o.fmt(
        129,
        "IMU",
        "QBffffff",
        "TimeUS,I,GyrX,GyrY,GyrZ,AccX,AccY,AccZ",
        36,
    );
    o.fmt(
        130,
        "ISBH",
        "QHBBHHQf",
        "TimeUS,N,type,instance,mul,smp_cnt,SampleUS,smp_rate",
        31,
    );
    o.fmt(131, "ISBD", "QHHaaa", "TimeUS,N,seqno,x,y,z", 207);
    let mut n = 0u16;
    for i in 0..loops {
        let t = 1_000_000 + 2_500 * i;
        for k in 0..2u8 {
            let mut p = t.to_le_bytes().to_vec();
            p.push(k);
            for a in 0..6 {
                let v = (i % 13) as f32 * 1e-3 + a as f32 + k as f32 * 10.0;
                p.extend_from_slice(&v.to_le_bytes());
            }
            o.msg(129, &p);
        }
        if i % 400 == 200 && n < batches {
            let mut p = t.to_le_bytes().to_vec();
            p.extend_from_slice(&n.to_le_bytes());
            p.extend_from_slice(&[1, 0]);
            p.extend_from_slice(&939u16.to_le_bytes());
            p.extend_from_slice(&1024u16.to_le_bytes());
            p.extend_from_slice(&(t - 400_000).to_le_bytes());
            p.extend_from_slice(&3200f32.to_le_bytes());
            o.msg(130, &p);
            for seq in 0..32u16 {
                let mut p = t.to_le_bytes().to_vec();
                p.extend_from_slice(&n.to_le_bytes());
                p.extend_from_slice(&seq.to_le_bytes());
                for a in 0..3i16 {
                    for s in 0..32i16 {
                        p.extend_from_slice(&(a * 1000 + s * 7 + seq as i16).to_le_bytes());
                    }
                }
                o.msg(131, &p);
            }
            n += 1;
        }
    }
    (o.b, o.at)
}

/// Converts `topic` of the damaged log; asserts what was not delivered is counted (at least,
/// no more than lost) and DFReader recovers no row bag2mat does not.
fn check_df(
    dir: &Path,
    clean: (&Path, &Conv),
    bytes: &[u8],
    topic: &str,
    name: &str,
) -> (Conv, usize) {
    let p = dir.join(name);
    std::fs::write(&p, bytes).unwrap();
    let d = convert(&p, topic);
    assert!(d.ok, "{name}: {}", d.stderr);
    let lost = missing(clean.1, &d);
    let said = d.lost(topic);
    assert!(
        said.total() >= lost as u64 && said.lost <= lost as u64,
        "{name}: {lost} rows lost, said {said:?}: {}",
        d.stderr
    );
    if let Some(theirs) = independent("dataflash", topic, clean.0, &p) {
        assert!(
            d.rows.len() >= theirs,
            "{name}: DFReader recovers {theirs}, bag2mat {}",
            d.rows.len()
        );
    }
    (d, lost)
}

/// A batch header's sample count or sensor type, when damaged, is read as the sensor's other
/// batches say: no sample dropped in silence, no loss said that did not happen.
#[test]
fn dataflash_batch_counts_and_sensor_types_are_read_against_the_sensors_other_batches() {
    let dir = tempfile::tempdir().unwrap();
    let (b0, at) = dataflash(2400, 6);
    let p = dir.path().join("clean.bin");
    std::fs::write(&p, &b0).unwrap();
    let c = convert(&p, "ISB_GYR");
    assert!(
        c.ok && c.rows.len() == 6 * 1024 && c.stderr.is_empty(),
        "{}",
        c.stderr
    );
    let headers: Vec<usize> = at.iter().filter(|m| m.1 == 130).map(|m| m.0).collect();
    for (what, off, val) in [
        ("count 512", 3 + 14, 512u16.to_le_bytes().to_vec()),
        ("count 65535", 3 + 14, u16::MAX.to_le_bytes().to_vec()),
        ("count 0", 3 + 14, 0u16.to_le_bytes().to_vec()),
        ("type 7", 3 + 10, vec![7]),
        ("type 0", 3 + 10, vec![0]),
        ("instance 4", 3 + 11, vec![4]),
    ] {
        let mut b = b0.clone();
        let h = headers[2] + off;
        b[h..h + val.len()].copy_from_slice(&val);
        let (d, lost) = check_df(dir.path(), (&p, &c), &b, "ISB_GYR", "isb.bin");
        assert_eq!(lost, 0, "{what}: {}", d.stderr);
        assert!(
            !d.stderr.contains("were lost"),
            "{what}: no loss said: {}",
            d.stderr
        );
    }
}

/// A flipped instance byte does not move a row to another instance in silence: the row goes
/// back to the instance its loop lacks. A message cut short by 1..53 bytes is read where its
/// columns are all there (as DFReader reads it), else counted on its instance; a damaged
/// first byte does not hide the log.
#[test]
fn dataflash_damaged_imu_messages_stay_with_their_instance_or_are_counted() {
    let dir = tempfile::tempdir().unwrap();
    let (b0, at) = dataflash(2000, 0);
    let p = dir.path().join("clean.bin");
    std::fs::write(&p, &b0).unwrap();
    let c = convert(&p, "IMU:0");
    assert!(
        c.ok && c.rows.len() == 2000 && c.stderr.is_empty(),
        "{}",
        c.stderr
    );
    let imu: Vec<usize> = at.iter().filter(|m| m.1 == 129).map(|m| m.0).collect();
    for flip in [1u8, 2, 0x80] {
        let mut b = b0.clone();
        b[imu[600] + 3 + 8] ^= flip; // instance 0 of loop 300
        let (d, lost) = check_df(dir.path(), (&p, &c), &b, "IMU:0", "inst.bin");
        assert_eq!(lost, 0, "flip {flip}: {}", d.stderr);
    }
    for cut in [1usize, 10, 20, 30, 33] {
        let mut b = b0.clone();
        let end = imu[801];
        b.drain(end - cut..end); // instance 0 of loop 400, cut short
        let (d, lost) = check_df(dir.path(), (&p, &c), &b, "IMU:0", "short.bin");
        assert!(lost <= 1, "cut {cut}: {}", d.stderr);
    }
    let mut b = b0.clone();
    b[0] = 0x13;
    let (d, lost) = check_df(dir.path(), (&p, &c), &b, "IMU:0", "first.bin");
    assert_eq!(lost, 0, "{}", d.stderr);
}

// ---- text ----

/// A CSV in bag2mat's layout: `n` rows.
fn csv(n: usize) -> String {
    let mut s = String::from("t,ax,ay,az,wx,wy,wz\n");
    for i in 0..n {
        s += &format!(
            "{}.{:09},{},{},{},{},{},{}\n",
            1_700_000_000 + i / 200,
            (i % 200) * 5_000_000,
            0.125 + i as f64 * 1e-6,
            -0.25,
            9.8125,
            1e-3,
            -2e-3 * (i % 5) as f64,
            0.5
        );
    }
    s
}

fn check_text(dir: &Path, clean: (&Path, &Conv), text: &[u8], name: &str) -> (Conv, usize) {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    let d = convert(&p, "imu");
    assert!(d.ok, "{name}: {}", d.stderr);
    let lost = missing(clean.1, &d);
    let said = d.lost("imu");
    assert!(
        said.total() >= lost as u64 && said.lost <= lost as u64,
        "{name}: {lost} rows lost, said {said:?}: {}",
        d.stderr
    );
    if let Some(theirs) = independent("csv", "imu", clean.0, &p) {
        assert!(
            d.rows.len() >= theirs,
            "{name}: pandas recovers {theirs}, bag2mat {}",
            d.rows.len()
        );
    }
    (d, lost)
}

/// An unterminated quote costs its line only, said with that line's number and a short
/// excerpt; a bad value in the first data row costs that row, not the file; every malformed
/// row is counted in the topic's summary.
#[test]
fn text_damaged_lines_cost_themselves_only_and_are_counted() {
    let dir = tempfile::tempdir().unwrap();
    let text = csv(5000);
    let p = dir.path().join("clean.csv");
    std::fs::write(&p, &text).unwrap();
    let c = convert(&p, "imu");
    assert!(c.ok && c.rows.len() == 5000, "{}", c.stderr);
    let line_at = |n: usize| text.match_indices('\n').nth(n - 2).unwrap().0 + 1;
    // a quote opened on line 1001 (row 1000) and never closed
    let mut b = text.clone().into_bytes();
    b.insert(line_at(1001) + 3, b'"');
    let (d, lost) = check_text(dir.path(), (&p, &c), &b, "quote.csv");
    assert_eq!(lost, 1, "{}", d.stderr);
    assert!(d.stderr.contains("line 1001"), "{}", d.stderr);
    assert!(
        d.stderr.contains("1 of 5000 messages on 'imu' were lost"),
        "{}",
        d.stderr
    );
    // a bad value in the first data row
    let mut b = text.clone().into_bytes();
    let f = line_at(2) + 21;
    b[f] = b'x';
    let (d, lost) = check_text(dir.path(), (&p, &c), &b, "first.csv");
    assert_eq!((lost, d.rows.len()), (1, 4999), "{}", d.stderr);
    // two rows run together, a row split in two, a line of junk: 2 + 1 + 0 rows
    let mut b = text.clone().into_bytes();
    b.remove(line_at(3001) - 1);
    let s = line_at(2000) + 40;
    b.insert(s, b'\n');
    b.splice(
        line_at(4000)..line_at(4000),
        b"no numbers here at all\n".iter().copied(),
    );
    let (d, lost) = check_text(dir.path(), (&p, &c), &b, "runs.csv");
    assert_eq!(lost, 3, "{}", d.stderr);
}

/// A malformed line is quoted in a short excerpt, however long it is, and read without
/// holding it more than once: a 16 MiB line gives a short warning and a small footprint.
#[test]
fn text_a_long_malformed_line_is_quoted_short_and_costs_little_memory() {
    /// Address space the child may take: well below what parsing the line as a record took.
    const LIMIT: u64 = 128 << 20;
    let dir = tempfile::tempdir().unwrap();
    let text = csv(1000);
    let p = dir.path().join("clean.csv");
    std::fs::write(&p, &text).unwrap();
    let c = convert(&p, "imu");
    let mut b = text.into_bytes();
    let at = b.len() / 2;
    let at = at + b[at..].iter().position(|&x| x == b'\n').unwrap() + 1;
    let mut junk = vec![b'7'; 16 << 20];
    junk.push(b'\n');
    b.splice(at..at, junk);
    let q = dir.path().join("long.csv");
    std::fs::write(&q, &b).unwrap();
    let d = convert_with(&q, "imu", Some(LIMIT));
    assert!(d.ok, "{}", d.stderr);
    assert!(d.stderr.len() < 1000, "{} bytes of stderr", d.stderr.len());
    assert_eq!(missing(&c, &d), 0);
}

/// A text file larger than the address space a memory limit leaves reads window by window:
/// the memory it takes is its rows', not the file's size.
#[test]
fn text_a_file_larger_than_the_memory_limit_reads_window_by_window() {
    /// The child's address-space limit, and the file's size above it.
    const LIMIT: u64 = 256 << 20;
    const FILE_BYTES: usize = 300 << 20;
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("wide.csv");
    let mut f = std::io::BufWriter::new(std::fs::File::create(&p).unwrap());
    // wide rows (180 columns not read): few rows for many bytes
    let tail: String = ",1.25".repeat(180);
    write!(f, "t_s,ax,ay,az,wx,wy,wz").unwrap();
    for k in 0..180 {
        write!(f, ",x{k}").unwrap();
    }
    writeln!(f).unwrap();
    let (mut n, mut bytes) = (0usize, 0usize);
    while bytes < FILE_BYTES {
        let line = format!(
            "{}.{:09},0.1,0.2,9.8,0.01,0.02,0.03{tail}\n",
            1_700_000_000 + n / 200,
            (n % 200) * 5_000_000
        );
        f.write_all(line.as_bytes()).unwrap();
        bytes += line.len();
        n += 1;
    }
    f.flush().unwrap();
    drop(f);
    let d = convert_with(&p, "imu", Some(LIMIT));
    assert!(d.ok, "{}", d.stderr);
    assert_eq!(d.rows.len(), n);
}

/// A file cut inside its last number does not deliver the cut number as a row: the row is
/// not read and counted.
#[test]
fn text_a_file_cut_inside_its_last_number_does_not_deliver_it() {
    let dir = tempfile::tempdir().unwrap();
    let text = csv(1000);
    let p = dir.path().join("clean.csv");
    std::fs::write(&p, &text).unwrap();
    let c = convert(&p, "imu");
    let cut = &text.as_bytes()[..text.len() - 3]; // "0.5\n" -> "0"
    let q = dir.path().join("cut.csv");
    std::fs::write(&q, cut).unwrap();
    let d = convert(&q, "imu");
    assert!(d.ok, "{}", d.stderr);
    assert_eq!(d.rows.len(), 999, "the cut row is not delivered");
    assert_eq!(missing(&c, &d), 1);
    assert!(
        d.stderr.contains("1 of 1000 messages on 'imu' were lost"),
        "{}",
        d.stderr
    );
}

/// A `#` comment right after the EuRoC header is a comment, not a refusal.
#[test]
fn euroc_a_comment_after_the_header_is_read_as_a_comment() {
    let dir = tempfile::tempdir().unwrap();
    let imu = dir.path().join("mav0/imu0");
    std::fs::create_dir_all(&imu).unwrap();
    let mut s = String::from(
        "#timestamp [ns],w_RS_S_x [rad s^-1],w_RS_S_y [rad s^-1],w_RS_S_z [rad s^-1],a_RS_S_x [m s^-2],a_RS_S_y [m s^-2],a_RS_S_z [m s^-2]\n# recorded on the bench\n",
    );
    for i in 0..500u64 {
        s += &format!(
            "{},0.001,0.002,0.003,0.1,0.2,9.8\n",
            1_403_636_579_758_555_392 + 5_000_000 * i
        );
    }
    std::fs::write(imu.join("data.csv"), s).unwrap();
    let d = convert(&imu.join("data.csv"), "imu0");
    assert!(d.ok && d.rows.len() == 500, "{}", d.stderr);
}

/// An npy file cut short keeps its whole rows, the cut one counted (numpy refuses it).
#[test]
fn npy_a_file_cut_short_keeps_its_whole_rows() {
    let dir = tempfile::tempdir().unwrap();
    let dict = "{'descr': '<f8', 'fortran_order': False, 'shape': (100, 7), }";
    let mut b = b"\x93NUMPY\x01\x00".to_vec();
    let hl = (10 + dict.len() + 1).div_ceil(64) * 64 - 10;
    b.extend_from_slice(&(hl as u16).to_le_bytes());
    b.extend_from_slice(dict.as_bytes());
    b.resize(10 + hl - 1, b' ');
    b.push(b'\n');
    for i in 0..100 {
        for v in [
            1_700_000_000.0 + i as f64 * 0.005,
            0.1,
            0.2,
            9.8,
            0.01,
            0.02,
            0.03,
        ] {
            b.extend_from_slice(&f64::to_le_bytes(v));
        }
    }
    let p = dir.path().join("cut.npy");
    std::fs::write(&p, &b[..b.len() - 56 * 30 - 20]).unwrap();
    let d = convert(&p, "imu");
    assert!(d.ok, "{}", d.stderr);
    assert_eq!(d.rows.len(), 69);
    let said = d.lost("imu");
    assert!(
        said.lost == 1 && said.total() >= 31,
        "{said:?}: {}",
        d.stderr
    );
}
