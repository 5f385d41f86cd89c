//! Test support shared by every crate's tests (not part of the tools): where the Python
//! virtual environment with the independent ROS 2 implementations is (`rosbags`, Foxglove's
//! `mcap` + `mcap-ros2-support`, installed by `scripts/test.sh`), and running them. A test
//! that needs them fails, never skips, when they are missing.

use std::path::{Path, PathBuf};
use std::process::Command;

// The raw record helpers of ROS 1 bags and the synthetic-log writers, for the tests and
// benchmarks that build or damage files byte by byte.
pub use crate::bag::record::{
    Header as BagRecordHeader, Op as BagOp, RawRecord as RawBagRecord,
    raw_record as raw_bag_record, read_u32,
};
pub use crate::formats::dataflash::write::imu_log as dataflash_imu_log;
pub use crate::formats::synthetic_noise;
pub use crate::formats::ulog::write::{
    ImuLogSpec as UlogImuSpec, SENSOR_COMBINED as ULOG_SENSOR_COMBINED,
    VEHICLE_IMU as ULOG_VEHICLE_IMU, Writer as UlogWriter, fifo_log as ulog_fifo_log,
    imu_log as ulog_imu_log,
};

/// The workspace root.
pub fn workspace() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// The repository's `testdata/` folder (the reference outputs and real curves).
pub fn testdata() -> PathBuf {
    workspace().join("testdata")
}

/// A binary of the workspace (`sim`, `allan_kalibr`, …) as `cargo test --workspace` built it
/// beside the running test (in cargo's target directory, wherever that is); panics with
/// what to run when it is missing.
pub fn workspace_binary(name: &str) -> PathBuf {
    let exe = std::env::current_exe().expect("the test binary's path");
    // <target>/<profile>/deps/<test> → <target>/<profile>/<name>
    let p = exe
        .parent()
        .and_then(Path::parent)
        .map(|d| d.join(name))
        .expect("the test binary is in <target>/<profile>/deps");
    assert!(
        p.exists(),
        "{} not built: run cargo test --workspace",
        p.display()
    );
    p
}

/// The virtual environment `scripts/test.sh` installs.
pub fn venv() -> PathBuf {
    workspace().join("target/py-venv")
}

/// The venv's Python interpreter; panics (failing the test) when it is missing.
pub fn venv_python() -> PathBuf {
    let p = venv().join("bin/python");
    assert!(
        p.exists(),
        "{} is missing: run scripts/test.sh, which installs rosbags, mcap and mcap-ros2-support",
        p.display()
    );
    p
}

/// Runs a command; panics with its output when it fails. Returns stdout.
pub fn run_ok(cmd: &mut Command) -> String {
    let out = cmd
        .output()
        .unwrap_or_else(|e| panic!("cannot run {cmd:?}: {e} (scripts/test.sh installs it)"));
    assert!(
        out.status.success(),
        "{cmd:?} failed:\n{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// A log of `kind` at `out`, by an independent writer with a known truth
/// (`tests/py/write_logs.py`: `ros1` through Debian's python rosbag, `ulog` through pyulog's
/// writer), as its JSON `spec` describes.
pub fn independent_log(kind: &str, out: &Path, spec: &str) {
    let python = match kind {
        "ros1" => PathBuf::from("/usr/bin/python3"),
        _ => venv_python(),
    };
    run_ok(
        Command::new(python)
            .arg(workspace().join("crates/bag2mat/tests/py/write_logs.py"))
            .arg(kind)
            .arg(out)
            .arg(spec),
    );
}

/// `rosbags-convert --src SRC… --dst DST EXTRA…` from the venv.
pub fn rosbags_convert(src: &[&Path], dst: &Path, extra: &[&str]) {
    let _ = venv_python();
    let mut c = Command::new(venv().join("bin/rosbags-convert"));
    c.arg("--src").args(src).arg("--dst").arg(dst).args(extra);
    run_ok(&mut c);
}

/// The rosbags-convert options of each ROS 2 destination the tests check: storage, and
/// compression mode (zstd) when compressed.
pub const ROS2_MODES: [(&str, &[&str]); 7] = [
    ("sqlite3", &["--dst-storage", "sqlite3"]),
    ("mcap", &["--dst-storage", "mcap"]),
    (
        "sqlite3_zstd_file",
        &[
            "--dst-storage",
            "sqlite3",
            "--compress",
            "zstd",
            "--compress-mode",
            "file",
        ],
    ),
    (
        "sqlite3_zstd_message",
        &[
            "--dst-storage",
            "sqlite3",
            "--compress",
            "zstd",
            "--compress-mode",
            "message",
        ],
    ),
    (
        "mcap_zstd_file",
        &[
            "--dst-storage",
            "mcap",
            "--compress",
            "zstd",
            "--compress-mode",
            "file",
        ],
    ),
    (
        "mcap_zstd_message",
        &[
            "--dst-storage",
            "mcap",
            "--compress",
            "zstd",
            "--compress-mode",
            "message",
        ],
    ),
    (
        "mcap_zstd_storage",
        &[
            "--dst-storage",
            "mcap",
            "--compress",
            "zstd",
            "--compress-mode",
            "storage",
        ],
    ),
];

/// The hidden temporary files of atomic outputs (`.<name>.<pid>.<n>.tmp`, see
/// [`crate::shared::output`]) left in `dir`: a test of an interrupted or failed run expects
/// none.
pub fn temp_files_in(dir: &Path) -> Vec<String> {
    let Ok(rd) = std::fs::read_dir(dir) else {
        // No directory (a failed run made none): nothing left in it.
        return Vec::new();
    };
    rd.map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with('.') && n.contains(".tmp"))
        .collect()
}

/// A `std_msgs/String` connection on `topic`: the non-Imu topic the tests and the fuzz
/// campaign put beside the Imu one (its md5 and definition as genpy writes them).
pub fn add_string_connection(
    w: &mut crate::bag::BagWriter,
    topic: &str,
) -> crate::bag::write::ConnId {
    w.add_connection(
        topic,
        "std_msgs/String",
        "992ce8a1687cec8c8bd883ec73ca41d1",
        "string data",
    )
}

/// A `std_msgs/String` message body: the text with its u32 length.
pub fn string_message(text: &str) -> Vec<u8> {
    let mut d = (text.len() as u32).to_le_bytes().to_vec();
    d.extend_from_slice(text.as_bytes());
    d
}

/// One b-tree page of a SQLite file: what the page-level damage of the tests and the fuzz
/// campaign aims at (index pages, row ids, cell counts, child pointers).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct BtreePage {
    /// The table or index it belongs to.
    pub tree: String,
    /// Page number (1-based).
    pub number: u32,
    /// File offset of its b-tree header (100 bytes into page 1).
    pub header: usize,
    /// 0x0D table leaf, 0x05 table interior, 0x0A index leaf, 0x02 index interior.
    pub kind: u8,
    /// Its cell count.
    pub cells: u16,
    /// File offsets of its cells, in cell-pointer order.
    pub cell_offsets: Vec<usize>,
}

impl BtreePage {
    /// True for a leaf page.
    pub fn is_leaf(&self) -> bool {
        self.kind == 0x0D || self.kind == 0x0A
    }

    /// File offset of its cell count (big-endian u16).
    pub fn cell_count_at(&self) -> usize {
        self.header + 3
    }

    /// File offsets of its child pointers (big-endian u32: one per cell, then the
    /// right-most one in the header) when it is an interior page.
    pub fn child_pointers(&self) -> Vec<usize> {
        if self.is_leaf() {
            return Vec::new();
        }
        let mut v = self.cell_offsets.clone();
        v.push(self.header + 8);
        v
    }
}

/// A SQLite varint at `at`: its value and length.
pub fn sqlite_varint(b: &[u8], at: usize) -> (u64, usize) {
    let mut v = 0u64;
    for k in 0..9 {
        let c = b[at + k];
        if k == 8 {
            return ((v << 8) | c as u64, 9);
        }
        v = (v << 7) | (c & 0x7f) as u64;
        if c < 0x80 {
            return (v, k + 1);
        }
    }
    (v, 9)
}

/// File offset and length of the row id of each cell of a table leaf page.
pub fn rowid_fields(bytes: &[u8], page: &BtreePage) -> Vec<(usize, usize)> {
    if page.kind != 0x0D {
        return Vec::new();
    }
    page.cell_offsets
        .iter()
        .map(|&c| {
            let (_, n) = sqlite_varint(bytes, c);
            let (_, m) = sqlite_varint(bytes, c + n);
            (c + n, m)
        })
        .collect()
}

/// Every b-tree page of every table and index of an undamaged SQLite file, root first.
pub fn btree_pages(path: &Path) -> Vec<BtreePage> {
    let bytes = std::fs::read(path).expect("read sqlite file");
    let page_size = match u16::from_be_bytes([bytes[16], bytes[17]]) {
        1 => 65536,
        n => n as usize,
    };
    let conn =
        rusqlite::Connection::open_with_flags(path, rusqlite::OpenFlags::SQLITE_OPEN_READ_ONLY)
            .expect("open sqlite file");
    let roots: Vec<(String, u32)> = conn
        .prepare("SELECT name, rootpage FROM sqlite_master WHERE rootpage > 0")
        .and_then(|mut s| {
            s.query_map([], |r| Ok((r.get(0)?, r.get(1)?)))?
                .collect::<Result<_, _>>()
        })
        .expect("sqlite_master");
    let mut out = Vec::new();
    for (tree, root) in roots {
        let mut todo = vec![root];
        while let Some(p) = todo.pop() {
            let start = (p as usize - 1) * page_size;
            let header = start + if p == 1 { 100 } else { 0 };
            let kind = bytes[header];
            let cells = u16::from_be_bytes([bytes[header + 3], bytes[header + 4]]);
            let ptrs = header + if kind == 0x0D || kind == 0x0A { 8 } else { 12 };
            let cell_offsets: Vec<usize> = (0..cells as usize)
                .map(|k| {
                    start
                        + u16::from_be_bytes([bytes[ptrs + 2 * k], bytes[ptrs + 2 * k + 1]])
                            as usize
                })
                .collect();
            let page = BtreePage {
                tree: tree.clone(),
                number: p,
                header,
                kind,
                cells,
                cell_offsets,
            };
            let mut children: Vec<u32> = page
                .child_pointers()
                .iter()
                .map(|&o| u32::from_be_bytes(bytes[o..o + 4].try_into().expect("4 bytes")))
                .collect();
            children.reverse();
            todo.extend(children);
            out.push(page);
        }
    }
    out
}

/// What a run's warnings say was lost on one topic: the per-topic summary line the read
/// path ends with (`N of M messages on 'T' were lost`, `, and up to K more`, `up to K
/// messages on 'T'`, or that the damaged data does not count them), and the messages it
/// says do not decode.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Reported {
    /// Messages said lost on the topic.
    pub lost: u64,
    /// Messages of unknown topic said lost besides (they may be the topic's).
    pub more: u64,
    /// A loss the warnings cannot count.
    pub uncounted: bool,
    /// Messages said not to decode as Imu (found, but lost as rows).
    pub undecodable: u64,
    /// A summary line was found.
    pub said: bool,
}

/// Reads the per-topic loss summary of `topic` from a run's stderr.
pub fn reported_losses(stderr: &str, topic: &str) -> Reported {
    let mut r = Reported::default();
    let on = format!(" messages on '{topic}' ");
    for line in stderr.lines() {
        let Some(l) = line.strip_prefix("warning: ") else {
            continue;
        };
        if l.starts_with("messages on '") && l.contains(&format!("'{topic}' may have been lost")) {
            r.said = true;
            r.uncounted = true;
            continue;
        }
        let Some(i) = l.find(&on) else { continue };
        let head = &l[..i];
        let rest = &l[i + on.len()..];
        if rest.starts_with("do not decode")
            && let Ok(n) = head.trim().parse::<u64>()
        {
            r.undecodable = r.undecodable.max(n);
            r.said = true;
            continue;
        }
        if !rest.starts_with("were lost") {
            continue;
        }
        let num = |s: &str| s.trim().parse::<u64>().ok();
        if let Some(n) = head.strip_prefix("up to ").and_then(num) {
            r.more = r.more.max(n);
        } else if let Some((n, _)) = head.split_once(" of ")
            && let Some(n) = num(n)
        {
            r.lost = r.lost.max(n);
            if let Some(k) = rest
                .split_once(", and up to ")
                .and_then(|(_, x)| x.split_whitespace().next())
                .and_then(num)
            {
                r.more = r.more.max(k);
            }
        } else {
            continue;
        }
        r.said = true;
        r.uncounted |= rest.contains("does not count");
    }
    r
}

/// A top-level record of an MCAP file: where it starts, its opcode and its content.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct McapRecord {
    /// File offset of its opcode.
    pub pos: usize,
    /// Opcode.
    pub op: u8,
    /// File offsets of its content.
    pub content: std::ops::Range<usize>,
}

/// The top-level records of an undamaged MCAP file, in file order (up to the footer).
pub fn mcap_records(b: &[u8]) -> Vec<McapRecord> {
    let mut out = Vec::new();
    let mut pos = 8;
    while pos + 9 <= b.len() {
        let op = b[pos];
        let len = u64::from_le_bytes(b[pos + 1..pos + 9].try_into().expect("8 bytes")) as usize;
        let Some(end) = (pos + 9).checked_add(len).filter(|&e| e <= b.len()) else {
            break;
        };
        out.push(McapRecord {
            pos,
            op,
            content: pos + 9..end,
        });
        if op == 0x02 {
            break;
        }
        pos = end;
    }
    out
}

/// The records of an uncompressed chunk's content: (file offset, opcode, content range).
pub fn mcap_chunk_records(
    b: &[u8],
    chunk: &McapRecord,
) -> Vec<(usize, u8, std::ops::Range<usize>)> {
    let c = chunk.content.start;
    let slen = u32::from_le_bytes(b[c + 28..c + 32].try_into().expect("4 bytes")) as usize;
    let mut pos = c + 32 + slen + 8;
    let mut out = Vec::new();
    while pos + 9 <= chunk.content.end {
        let len = u64::from_le_bytes(b[pos + 1..pos + 9].try_into().expect("8 bytes")) as usize;
        out.push((pos, b[pos], pos + 9..pos + 9 + len));
        pos += 9 + len;
    }
    out
}

impl Reported {
    /// Rows the warnings account for at most: lost, of unknown topic, undecodable.
    pub fn total(&self) -> u64 {
        self.lost + self.more + self.undecodable
    }
}

/// Rewrites a `bag2mat -o x.csv` file (`t,ax,ay,az,wx,wy,wz`, t in s) as an EuRoC/ASL
/// dataset under `root` (`mav0/imu0/data.csv`: ns stamps, gyro before acc, the same
/// decimals), as a user's script would; returns the `data.csv` path.
pub fn euroc_from_bag2mat_csv(csv: &Path, root: &Path) -> PathBuf {
    let text = std::fs::read_to_string(csv).expect("read the bag2mat CSV");
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some("t,ax,ay,az,wx,wy,wz"));
    let mut out = String::from(
        "#timestamp [ns],w_RS_S_x [rad s^-1],w_RS_S_y [rad s^-1],w_RS_S_z [rad s^-1],a_RS_S_x [m s^-2],a_RS_S_y [m s^-2],a_RS_S_z [m s^-2]\n",
    );
    for l in lines {
        let f: Vec<&str> = l.split(',').collect();
        let ns = crate::formats::text::parse_time_ns(f[0].as_bytes(), crate::units::TimeUnit::S)
            .expect("a time in seconds");
        out.push_str(&format!(
            "{ns},{},{},{},{},{},{}\n",
            f[4], f[5], f[6], f[1], f[2], f[3]
        ));
    }
    let dir = root.join("mav0/imu0");
    std::fs::create_dir_all(&dir).expect("create mav0/imu0");
    let p = dir.join("data.csv");
    std::fs::write(&p, out).expect("write data.csv");
    p
}

/// `bag2mat BAG TOPIC --time TIME -o DIR/x.csv`, then that CSV as an EuRoC/ASL dataset at
/// `DIR/dataset` ([`euroc_from_bag2mat_csv`]); returns the dataset root.
pub fn euroc_dataset_from_bag(
    bag: &Path,
    topic: &str,
    time: crate::TimeColumn,
    dir: &Path,
) -> PathBuf {
    let csv = dir.join("x.csv");
    let cfg = crate::convert::Config {
        bag: bag.to_path_buf(),
        topics: crate::TopicSelector::one(topic),
        output: Some(csv.clone()),
        format: crate::convert::Format::Csv,
        time,
        quiet: true,
        input: Default::default(),
    };
    crate::convert::run(&cfg, crate::shared::output::Outputs::direct()).expect("bag2mat -o x.csv");
    let root = dir.join("dataset");
    euroc_from_bag2mat_csv(&csv, &root);
    root
}

/// What [`odd_record`] wrote: the message count and the continuous-time truth of its noise.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OddRecord {
    /// Messages written.
    pub messages: usize,
    /// Gyro white noise N (rad/s/√Hz) and random walk K (rad/s²/√Hz).
    pub gyro: (f64, f64),
    /// Accelerometer N (m/s²/√Hz) and K (m/s³/√Hz).
    pub acc: (f64, f64),
}

/// Which independent writer [`odd_record`] uses.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum OddWriter {
    /// Debian's python3-rosbag: a ROS 1 bag, topic `imu`.
    Rosbag,
    /// Foxglove's mcap_ros2 writer (venv): a bare `.mcap`, topic `/imu`, with header jitter
    /// and transport latency.
    Mcap,
}

/// Writes an IMU record that breaks what an Allan analysis assumes (`cases`, see
/// `tests/py/odd_records.py`) with an independent writer: `seconds` at `rate` Hz.
pub fn odd_record(
    writer: OddWriter,
    out: &Path,
    cases: &str,
    seconds: f64,
    rate: f64,
) -> OddRecord {
    let script = workspace().join("crates/bag2mat/tests/py/odd_records.py");
    let (python, name) = match writer {
        OddWriter::Rosbag => (PathBuf::from("/usr/bin/python3"), "rosbag"),
        OddWriter::Mcap => (venv_python(), "mcap"),
    };
    let json = run_ok(
        Command::new(python)
            .arg(script)
            .arg(name)
            .arg(out)
            .arg(cases)
            .args([
                "--seconds",
                &seconds.to_string(),
                "--rate",
                &rate.to_string(),
            ]),
    );
    // a flat JSON object of numbers (and the case list): read by key
    let num = |key: &str| -> f64 {
        let at = json
            .find(&format!("\"{key}\": "))
            .unwrap_or_else(|| panic!("no {key} in {json}"));
        json[at + key.len() + 4..]
            .split([',', '}'])
            .next()
            .and_then(|v| v.trim().parse().ok())
            .unwrap_or_else(|| panic!("bad {key} in {json}"))
    };
    OddRecord {
        messages: num("messages") as usize,
        gyro: (num("gyro_n"), num("gyro_k")),
        acc: (num("acc_n"), num("acc_k")),
    }
}

/// The lines of a tool's stderr that are record-check warnings of `kind` (the start of the
/// finding's line after `warning: `, e.g. `gaps`, `warm-up on gyro x`).
pub fn warnings<'a>(stderr: &'a str, kind: &str) -> Vec<&'a str> {
    stderr
        .lines()
        .filter(|l| l.starts_with(&format!("warning: {kind}")))
        .collect()
}

/// A PX4 ULog of `seconds` at `rate` Hz (two `sensor_gyro`/`sensor_accel` instances,
/// `sensor_combined`, `vehicle_imu`; [`ulog_imu_log`]) as pyulog's
/// own writer lays it out (`ULog.write_ulog`, an independent writer): `dir/pyulog.ulg`.
pub fn pyulog_imu_log(dir: &Path, seconds: f64, rate: f64) -> PathBuf {
    let ours = dir.join("ours.ulg");
    let spec = crate::formats::ulog::write::ImuLogSpec {
        seconds,
        rate,
        instances: 2,
        dropout_ms: None,
        seed: 20,
    };
    let f = std::io::BufWriter::new(std::fs::File::create(&ours).expect("create ours.ulg"));
    crate::formats::ulog::write::imu_log(f, &spec).expect("write ours.ulg");
    let theirs = dir.join("pyulog.ulg");
    run_ok(
        Command::new(venv_python())
            .arg(workspace().join("crates/bag2mat/tests/py/read_logs.py"))
            .args(["ulog-rewrite"])
            .arg(&ours)
            .arg(&theirs),
    );
    theirs
}

/// An EuRoC/ASL `data.csv` (under `dir/paired/mav0/imu0`) holding the gyro of topic `gyro`
/// and the accelerometer of topic `acc` of `log`, paired row by row on the gyro topic's
/// sample stamps (the topics must have as many rows): the same samples as the one-sensor
/// topics, in a layout that has both. Returns the dataset root.
pub fn euroc_pairing(log: &Path, gyro: &str, acc: &str, dir: &Path) -> PathBuf {
    use std::fmt::Write as _;
    let read = |t: &str| {
        crate::input::read_imu_topics_with(
            log,
            &crate::TopicSelector::one(t),
            &crate::ReadOptions { quiet: true },
            &Default::default(),
        )
        .expect("read the log")
        .series
        .remove(0)
    };
    let (g, a) = (read(gyro), read(acc));
    assert_eq!(g.len(), a.len(), "{gyro} and {acc} differ in length");
    let mut s = String::from(
        "#timestamp [ns],w_RS_S_x [rad s^-1],w_RS_S_y [rad s^-1],w_RS_S_z [rad s^-1],a_RS_S_x [m s^-2],a_RS_S_y [m s^-2],a_RS_S_z [m s^-2]\n",
    );
    let t = crate::timing::ns_of_times(&g.record_time);
    for (i, t) in t.iter().enumerate() {
        let (w, f) = (g.gyro_at(i), a.acc_at(i));
        let _ = writeln!(
            s,
            "{t},{},{},{},{},{},{}",
            w[0], w[1], w[2], f[0], f[1], f[2]
        );
    }
    let root = dir.join("paired");
    let imu0 = root.join("mav0/imu0");
    std::fs::create_dir_all(&imu0).expect("create the dataset");
    std::fs::write(imu0.join("data.csv"), s).expect("write data.csv");
    root
}

/// The Imu samples of `topic` in `src` written again as a ROS 1 bag at `dst`, under each of
/// `topics` (the same messages on every one): a bag whose only Imu topic is not `imu`, or
/// one with several.
pub fn retopic(src: &Path, topic: &str, dst: &Path, topics: &[&str]) {
    let s = crate::read_imu_series(src, topic, &crate::ReadOptions { quiet: true })
        .expect("read the source bag");
    let mut w = crate::bag::BagWriter::create(
        &crate::shared::output::Outputs::direct(),
        dst,
        crate::Compression::None,
    )
    .expect("create");
    let conns: Vec<_> = topics.iter().map(|t| w.add_imu_connection(t)).collect();
    for i in 0..s.len() {
        let m = crate::imu_msg::Imu {
            seq: s.seq[i],
            stamp: s.stamp[i],
            angular_velocity: s.gyro_at(i),
            linear_acceleration: s.acc_at(i),
            ..Default::default()
        };
        for &c in &conns {
            w.write_imu(c, s.record_time[i], &m).expect("write");
        }
    }
    w.finish().expect("finish the bag");
}

/// A parsed YAML document as the tests read it: maps keep their order.
#[derive(Debug, Clone, PartialEq)]
pub enum YamlNode {
    /// A mapping, its entries in document order.
    Map(Vec<(String, YamlNode)>),
    /// A sequence.
    Seq(Vec<YamlNode>),
    /// A number (YAML's `.nan`/`.inf` included).
    Number(f64),
    /// Any other scalar.
    Text(String),
    /// `true`/`false`.
    Bool(bool),
    /// `~`, `null` or nothing.
    Null,
}

impl<'de> serde::Deserialize<'de> for YamlNode {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> serde::de::Visitor<'de> for V {
            type Value = YamlNode;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a YAML node")
            }
            fn visit_bool<E>(self, v: bool) -> Result<YamlNode, E> {
                Ok(YamlNode::Bool(v))
            }
            fn visit_i64<E>(self, v: i64) -> Result<YamlNode, E> {
                Ok(YamlNode::Number(v as f64))
            }
            fn visit_u64<E>(self, v: u64) -> Result<YamlNode, E> {
                Ok(YamlNode::Number(v as f64))
            }
            fn visit_f64<E>(self, v: f64) -> Result<YamlNode, E> {
                Ok(YamlNode::Number(v))
            }
            fn visit_str<E>(self, v: &str) -> Result<YamlNode, E> {
                Ok(YamlNode::Text(v.to_string()))
            }
            fn visit_unit<E>(self) -> Result<YamlNode, E> {
                Ok(YamlNode::Null)
            }
            fn visit_none<E>(self) -> Result<YamlNode, E> {
                Ok(YamlNode::Null)
            }
            fn visit_seq<A: serde::de::SeqAccess<'de>>(
                self,
                mut a: A,
            ) -> Result<YamlNode, A::Error> {
                let mut v = Vec::new();
                while let Some(x) = a.next_element()? {
                    v.push(x);
                }
                Ok(YamlNode::Seq(v))
            }
            fn visit_map<A: serde::de::MapAccess<'de>>(
                self,
                mut a: A,
            ) -> Result<YamlNode, A::Error> {
                let mut v = Vec::new();
                while let Some((k, x)) = a.next_entry::<String, YamlNode>()? {
                    v.push((k, x));
                }
                Ok(YamlNode::Map(v))
            }
        }
        d.deserialize_any(V)
    }
}

/// Every number of a YAML file (also OpenCV's `%YAML:1.0` files, whose directive line a YAML
/// 1.2 parser refuses and which spell NaN `.Nan`), in document order, keyed by its path of
/// map keys joined with `/` (`Gyr/x-axis/gyr_n`); parsed by the YAML library the workspace
/// uses, not by lines. Panics with the text when it is not YAML.
pub fn yaml_numbers(text: &str) -> Vec<(String, f64)> {
    let body: String = text
        .lines()
        .filter(|l| !l.starts_with("%YAML"))
        .map(|l| format!("{l}\n"))
        .collect();
    // The tools write NaN where a term has no value (`.nan`): read it as the number it is.
    let options = serde_saphyr::options! {
        non_finite_float_policy: serde_saphyr::NonFiniteFloatPolicy::PassThrough,
    };
    let doc: YamlNode = serde_saphyr::from_str_with_options(&body, options)
        .unwrap_or_else(|e| panic!("not YAML ({e}):\n{text}"));
    fn walk(n: &YamlNode, path: &mut Vec<String>, out: &mut Vec<(String, f64)>) {
        match n {
            YamlNode::Map(m) => {
                for (k, v) in m {
                    path.push(k.clone());
                    walk(v, path, out);
                    path.pop();
                }
            }
            YamlNode::Number(x) => out.push((path.join("/"), *x)),
            YamlNode::Text(s) if s.eq_ignore_ascii_case(".nan") => {
                out.push((path.join("/"), f64::NAN))
            }
            _ => {}
        }
    }
    let mut out = Vec::new();
    walk(&doc, &mut Vec::new(), &mut out);
    out
}

/// The number at `path` (see [`yaml_numbers`]) of a YAML text; panics with the text when it
/// has none.
pub fn yaml_number(text: &str, path: &str) -> f64 {
    yaml_numbers(text)
        .into_iter()
        .find(|(k, _)| k == path)
        .map(|(_, x)| x)
        .unwrap_or_else(|| panic!("no number at {path} in:\n{text}"))
}

/// Asserts that a binary's help output (`stdout` of `--help`) names every kind of input the
/// registry holds ([`crate::InputKind::ALL`]'s phrases) and each of `extra`, in clap's
/// wrapping (whitespace compared collapsed).
pub fn assert_help_lists_every_input(stdout: &[u8], extra: &[&str]) {
    let help = String::from_utf8_lossy(stdout)
        .split_whitespace()
        .collect::<Vec<_>>()
        .join(" ");
    let kinds = crate::InputKind::ALL.iter().map(|k| k.facts().accepted);
    for phrase in extra.iter().copied().chain(kinds) {
        assert!(help.contains(phrase), "{phrase:?} missing from {help}");
    }
}

/// `dir/rig.bag`, a ROS 1 bag written by Debian's python rosbag ([`independent_log`]): two
/// 30 s Imu topics at 100 Hz (`/imu0`, `/imu1`) and `/short` with `short` messages (the
/// analysers' several-topics tests: one topic that cannot be analysed among good ones).
pub fn several_topics_bag(dir: &Path, short: usize) -> PathBuf {
    let bag = dir.join("rig.bag");
    let topic = |t: &str, n: usize| {
        format!(r#"{{"topic": "{t}", "n": {n}, "rate": 100, "gyro_n": 1e-4, "acc_n": 1e-3}}"#)
    };
    let spec = format!(
        r#"{{"seed": 41, "topics": [{}, {}, {}]}}"#,
        topic("/imu0", 3000),
        topic("/imu1", 3000),
        topic("/short", short)
    );
    independent_log("ros1", &bag, &spec);
    bag
}
