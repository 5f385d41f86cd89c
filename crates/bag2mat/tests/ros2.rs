//! ROS 2 inputs and outputs against independent implementations: `rosbags-convert` turns
//! the reference bags into every ROS 2 storage and compression it offers, and bag2mat must
//! read each to the same `data_imu` (sha256) as the ROS 1 bag; our MCAP and sqlite3 output
//! must read back exactly in `rosbags` and in Foxglove's `mcap` reader with CRC validation;
//! damaged MCAP and db3 files give clear errors or noted partial reads, never a panic.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::thread;

use bag2mat::DataImu;
use bag2mat::test_tools::{ROS2_MODES, rosbags_convert, run_ok, venv_python};
use bag2mat::{Compression, ReadOptions, TimeColumn, TopicSelector, read_imu_topics};
use bag2mat::{bag_to_data_imu, data_imu_from_series};
use sha2::{Digest, Sha256};

use crate::common::{CASES, case_bag, run, testdata, write_synthetic};

fn sha(d: &DataImu) -> String {
    let mut h = Sha256::new();
    for i in 0..d.rows() {
        for v in d.row(i) {
            h.update(v.to_le_bytes());
        }
    }
    format!("{:x}", h.finalize())
}

fn reference_sha(case: &str) -> String {
    let json =
        std::fs::read_to_string(testdata().join(case).join("kalibr/bagconvert_mat.json")).unwrap();
    let key = "\"sha256_rowmajor_f64le\"";
    let rest = &json[json.find(key).unwrap() + key.len()..];
    let start = rest.find('"').unwrap() + 1;
    rest[start..start + 64].to_string()
}

fn bag2mat() -> Command {
    Command::new(env!("CARGO_BIN_EXE_bag2mat"))
}

/// Every reference bag in every ROS 2 mode (p4, 360 k messages, in two), two conversions at
/// a time: the matrix of each equals bagconvert's, bit for bit.
#[test]
fn rosbags_converted_reference_bags_give_bagconverts_matrix() {
    let dir = tempfile::tempdir().unwrap();
    let mut jobs: Vec<(&str, &str, &str, &[&str])> = Vec::new();
    for (case, topic) in CASES {
        for (mode, args) in ROS2_MODES {
            if case.starts_with("p4") && !(mode == "mcap" || mode == "sqlite3_zstd_message") {
                continue;
            }
            jobs.push((case, topic, mode, args));
        }
    }
    let results: Vec<String> = thread::scope(|s| {
        let mut out = Vec::new();
        for pair in jobs.chunks(2) {
            let handles: Vec<_> = pair
                .iter()
                .map(|&(case, topic, mode, args)| {
                    let dst = dir.path().join(format!("{case}_{mode}"));
                    s.spawn(move || {
                        rosbags_convert(&[&case_bag(case)], &dst, args);
                        let conv = bag_to_data_imu(&dst, topic, true)
                            .unwrap_or_else(|e| panic!("{case} {mode}: {e}"));
                        let got = sha(&conv.data);
                        if got == reference_sha(case) {
                            String::new()
                        } else {
                            format!(
                                "{case} {mode}: sha {got} ({} rows, notes {:?})",
                                conv.data.rows(),
                                conv.notes
                            )
                        }
                    })
                })
                .collect();
            for h in handles {
                out.push(h.join().unwrap());
            }
        }
        out
    });
    let bad: Vec<&String> = results.iter().filter(|r| !r.is_empty()).collect();
    assert!(bad.is_empty(), "{bad:#?}");
    assert_eq!(results.len(), 3 * ROS2_MODES.len() + 2);
}

/// A bare `.mcap`, a bare `.db3`, a bare FILE-compressed `.db3.zstd` and a path to
/// `metadata.yaml` read like their bag directory.
#[test]
fn bare_storage_files_read_like_their_directory() {
    let dir = tempfile::tempdir().unwrap();
    let case = "p3_short_61s";
    let want = reference_sha(case);
    for (mode, args) in [ROS2_MODES[0], ROS2_MODES[1], ROS2_MODES[2]] {
        let dst = dir.path().join(mode);
        rosbags_convert(&[&case_bag(case)], &dst, args);
        let mut files: Vec<PathBuf> = std::fs::read_dir(&dst)
            .unwrap()
            .map(|e| e.unwrap().path())
            .collect();
        files.sort();
        for f in files {
            let conv =
                bag_to_data_imu(&f, "imu", true).unwrap_or_else(|e| panic!("{}: {e}", f.display()));
            assert_eq!(sha(&conv.data), want, "{}", f.display());
        }
    }
}

/// Two sim bags (Imu on /imu0 and /imu1) and a bag with a non-Imu topic, merged by
/// rosbags-convert into sqlite3 and MCAP: `--all-imu-topics` writes one folder per Imu
/// topic, each equal to bag2mat on its ROS 1 source; `info` lists all three topics.
#[test]
fn two_imu_topics_and_another_in_one_pass() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let sim_bin = bag2mat::test_tools::workspace_binary("sim");
    let mut sources = Vec::new();
    for (topic, seed) in [("/imu0", "1"), ("/imu1", "2")] {
        let p = d.join(format!("{}.bag", &topic[1..]));
        let mut c = Command::new(&sim_bin);
        c.args([
            "bag",
            "--duration",
            "20",
            "--rate",
            "100",
            "--start-time",
            "1700000000",
        ])
        .args(["--topic", topic, "--seed", seed, "-q", "-o"])
        .arg(&p);
        if !sim_bin.exists() {
            // The workspace's sim is built by `cargo test --workspace`; this test needs it.
            panic!(
                "{} not built: run cargo test --workspace",
                sim_bin.display()
            );
        }
        run_ok(&mut c);
        sources.push(p);
    }
    let status = d.join("status.bag");
    write_synthetic(&status, "/status_imu_free", 50, Compression::None, true);
    // The synthetic bag also holds an Imu topic; keep only its non-Imu /status topic.
    let only_status = d.join("status_only");
    rosbags_convert(&[&status], &only_status, &["--include-topic", "/status"]);
    let status_ros1 = d.join("status_only.bag");
    rosbags_convert(&[&only_status], &status_ros1, &[]);
    for (mode, args) in [ROS2_MODES[0], ROS2_MODES[1]] {
        let dst = d.join(format!("rig_{mode}"));
        let src: Vec<&Path> = vec![&sources[0], &sources[1], &status_ros1];
        rosbags_convert(&src, &dst, args);
        let out = d.join(format!("out_{mode}"));
        let (ok, _, err) = run(bag2mat()
            .arg(&dst)
            .arg("--all-imu-topics")
            .arg("-o")
            .arg(&out)
            .arg("-q"));
        assert!(ok, "{mode}: {err}");
        for (i, t) in ["imu0", "imu1"].iter().enumerate() {
            let ours = bag2mat::read_data_imu(&out.join(t).join(format!("rig_{mode}.mat")))
                .unwrap_or_else(|e| panic!("{mode} {t}: {e}"));
            let ros1 = bag_to_data_imu(&sources[i], &format!("/{t}"), true).unwrap();
            assert_eq!(sha(&ours), sha(&ros1.data), "{mode} {t}");
            assert_eq!(ours.rows(), 2000);
        }
        let (ok, info, err) = run(bag2mat().arg("info").arg(&dst).arg("-q"));
        assert!(ok, "{err}");
        let line = |t: &str| {
            info.lines()
                .find(|l| l.contains(t))
                .unwrap_or_else(|| panic!("{t} in\n{info}"))
                .to_string()
        };
        assert!(
            line("/imu0").starts_with('*') && line("/imu0").contains("2000"),
            "{info}"
        );
        assert!(
            line("/imu1").starts_with('*') && line("/imu1").contains("100.000"),
            "{info}"
        );
        assert!(
            line("/status").starts_with(' ') && line("/status").contains("std_msgs/msg/String"),
            "{info}"
        );
        // A missing topic lists the ROS 2 topics with type and count.
        let (ok, _, err) = run(bag2mat().arg(&dst).arg("/cam0").arg("-q"));
        assert!(
            !ok && err.contains("/imu1")
                && err.contains("2000 msgs")
                && err.contains("std_msgs/msg/String"),
            "{err}"
        );
        // A topic of the wrong type is a clear error.
        let (ok, _, err) = run(bag2mat().arg(&dst).arg("/status").arg("-q"));
        assert!(!ok && err.contains("not sensor_msgs/Imu"), "{err}");
    }
}

const DUMP: &str = r#"
import sys
from pathlib import Path
from rosbags.highlevel import AnyReader
from mcap.reader import make_reader
from mcap.stream_reader import StreamReader
from mcap_ros2.decoder import DecoderFactory

kind, path = sys.argv[1], Path(sys.argv[2])
def line(t, m):
    w, a = m.angular_velocity, m.linear_acceleration
    print(t, m.header.stamp.sec * 10**9 + m.header.stamp.nanosec, m.header.frame_id,
          *[repr(float(v)) for v in (w.x, w.y, w.z, a.x, a.y, a.z, m.orientation.w, m.orientation_covariance[0])])
if kind == 'rosbags':
    with AnyReader([path]) as r:
        for c, t, raw in r.messages():
            assert c.msgtype == 'sensor_msgs/msg/Imu', c.msgtype
            line(t, r.deserialize(raw, c.msgtype))
else:
    f = next(path.glob('*.mcap'))
    # Strict: every record walked with CRC validation, then decoded through the summary.
    for _ in StreamReader(open(f, 'rb'), validate_crcs=True).records:
        pass
    with open(f, 'rb') as fh:
        r = make_reader(fh, decoder_factories=[DecoderFactory()], validate_crcs=True)
        assert r.get_header().profile == 'ros2'
        s = r.get_summary()
        assert s is not None and s.statistics is not None
        chans = list(s.channels.values())
        assert all('offered_qos_profiles' in c.metadata for c in chans), chans
        n = 0
        for schema, channel, msg, m in r.iter_decoded_messages():
            line(msg.log_time, m); n += 1
        assert n == s.statistics.message_count, (n, s.statistics.message_count)
"#;

/// `sim bag --format mcap|sqlite3` read back exactly by rosbags and by the strict mcap
/// reader, against the same run written as a ROS 1 bag and read by bag2mat.
#[test]
fn our_mcap_and_sqlite3_read_back_exactly_in_rosbags_and_mcap() {
    let dir = tempfile::tempdir().unwrap();
    let sim = bag2mat::test_tools::workspace_binary("sim");
    let common = [
        "--duration",
        "3",
        "--motion",
        "ellipse",
        "--seed",
        "9",
        "--start-time",
        "1700000000.25",
        "-q",
    ];
    let ros1 = dir.path().join("r.bag");
    run_ok(
        Command::new(&sim)
            .arg("bag")
            .args(common)
            .arg("-o")
            .arg(&ros1),
    );
    let s = bag2mat::read_imu_series(&ros1, "imu", &ReadOptions { quiet: true }).unwrap();
    let want: Vec<String> = (0..s.len())
        .map(|i| {
            let (w, a) = (s.gyro_at(i), s.acc_at(i));
            format!(
                "{} {} base_link {:?} {:?} {:?} {:?} {:?} {:?}",
                s.record_time[i].as_nanos(),
                s.stamp[i].as_nanos(),
                w[0],
                w[1],
                w[2],
                a[0],
                a[1],
                a[2]
            )
        })
        .collect();
    let py = venv_python();
    for (format, comp, readers) in [
        ("mcap", "none", &["rosbags", "mcap"][..]),
        ("mcap", "zstd", &["rosbags", "mcap"][..]),
        ("mcap", "lz4", &["mcap"][..]),
        ("sqlite3", "none", &["rosbags"][..]),
    ] {
        let out = dir.path().join(format!("{format}_{comp}"));
        run_ok(
            Command::new(&sim)
                .arg("bag")
                .args(common)
                .args(["--format", format, "--compression", comp, "-o"])
                .arg(&out),
        );
        // Our own reader gives the ROS 1 matrix too.
        let ours = bag2mat::read_imu_series(&out, "imu", &ReadOptions { quiet: true }).unwrap();
        assert_eq!(
            data_imu_from_series(&ours, TimeColumn::Record),
            data_imu_from_series(&s, TimeColumn::Record),
            "{format} {comp}"
        );
        for reader in readers {
            let text = run_ok(Command::new(&py).arg("-c").arg(DUMP).arg(reader).arg(&out));
            let got: Vec<String> = text
                .lines()
                .map(|l| {
                    // Drop the last two fields (orientation w and cov[0]) after checking them.
                    let f: Vec<&str> = l.split(' ').collect();
                    assert_eq!(f[f.len() - 1], "0.0", "{l}");
                    f[..f.len() - 2].join(" ")
                })
                .collect();
            assert_eq!(got.len(), want.len(), "{format} {comp} {reader}");
            for (i, (g, w)) in got.iter().zip(&want).enumerate() {
                assert_eq!(g, w, "{format} {comp} {reader}: message {i}");
            }
        }
    }
}

/// Foxy and Eloquent/Dashing databases (no `schema` table; `offered_qos_profiles` only in
/// Foxy) read the same: the reader needs only the columns every version has.
#[test]
fn old_sqlite3_schemas_read_the_same() {
    let dir = tempfile::tempdir().unwrap();
    let case = "p3_short_61s";
    let src_dir = dir.path().join("new");
    rosbags_convert(&[&case_bag(case)], &src_dir, ROS2_MODES[0].1);
    let src = src_dir.join("new.db3");
    for (name, topics_sql) in [
        (
            "foxy",
            "CREATE TABLE topics(id INTEGER PRIMARY KEY, name TEXT NOT NULL, type TEXT NOT NULL, serialization_format TEXT NOT NULL, offered_qos_profiles TEXT NOT NULL)",
        ),
        (
            "eloquent",
            "CREATE TABLE topics(id INTEGER PRIMARY KEY, name TEXT NOT NULL, type TEXT NOT NULL, serialization_format TEXT NOT NULL)",
        ),
    ] {
        let out = dir.path().join(format!("{name}.db3"));
        let c = rusqlite::Connection::open(&out).unwrap();
        c.execute_batch(topics_sql).unwrap();
        c.execute_batch("CREATE TABLE messages(id INTEGER PRIMARY KEY, topic_id INTEGER NOT NULL, timestamp INTEGER NOT NULL, data BLOB NOT NULL); CREATE INDEX timestamp_idx ON messages (timestamp ASC);").unwrap();
        c.execute("ATTACH DATABASE ?1 AS src", [src.to_str().unwrap()])
            .unwrap();
        let cols = if name == "foxy" {
            "id, name, type, serialization_format, offered_qos_profiles"
        } else {
            "id, name, type, serialization_format"
        };
        c.execute_batch(&format!("INSERT INTO topics SELECT {cols} FROM src.topics; INSERT INTO messages SELECT * FROM src.messages; DETACH DATABASE src;")).unwrap();
        drop(c);
        let conv = bag_to_data_imu(&out, "imu", true).unwrap();
        assert_eq!(sha(&conv.data), reference_sha(case), "{name}");
    }
}

/// Truncated, corrupted and empty MCAP and db3 inputs: a clear error or a noted partial
/// read, never a panic; a cut MCAP keeps the messages of its complete chunks, in order.
#[test]
fn damaged_mcap_and_db3_never_panic() {
    let dir = tempfile::tempdir().unwrap();
    let src = dir.path().join("src.bag");
    write_synthetic(&src, "imu", 6000, Compression::None, false);
    let mcap_dir = dir.path().join("m");
    rosbags_convert(&[&src], &mcap_dir, ROS2_MODES[1].1);
    let db_dir = dir.path().join("d");
    rosbags_convert(&[&src], &db_dir, ROS2_MODES[0].1);
    let mcap = std::fs::read(mcap_dir.join("m.mcap")).unwrap();
    let db = std::fs::read(db_dir.join("d.db3")).unwrap();
    let path = dir.path().join("x.mcap");
    let read =
        |p: &Path| read_imu_topics(p, &TopicSelector::one("imu"), &ReadOptions { quiet: true });

    // Cut inside the data section: no footer, no summary; the complete chunks are read.
    std::fs::write(&path, &mcap[..mcap.len() * 3 / 4]).unwrap();
    let s = read(&path).unwrap().series.remove(0);
    assert!(!s.is_empty() && s.len() < 6000, "{}", s.len());
    assert!(
        s.notes.iter().any(|n| n.text.contains("no footer")),
        "{:?}",
        s.notes
    );
    assert!(
        s.notes.iter().any(|n| n.text.contains("truncated")),
        "{:?}",
        s.notes
    );
    for (k, seq) in s.stamp.iter().enumerate() {
        assert_eq!(
            seq.as_nanos(),
            crate::common::synthetic(k as u32).1.stamp.as_nanos()
        );
    }
    // Summary damaged but data intact: everything is read, with a note.
    let mut bad_summary = mcap.clone();
    let n = bad_summary.len();
    bad_summary[n - 200] ^= 0xFF;
    std::fs::write(&path, &bad_summary).unwrap();
    if let Ok(r) = read(&path) {
        assert_eq!(r.series[0].len(), 6000);
    }
    // A chunk's body damaged in a file with chunk CRCs (ours; rosbags writes none): the
    // other chunks are read and the loss is named.
    let ours_dir = dir.path().join("ours");
    let mut w = bag2mat::Ros2BagWriter::create(
        &bag2mat::shared::output::Outputs::direct(),
        &ours_dir,
        bag2mat::Storage::Mcap(bag2mat::ChunkCompression::None),
    )
    .unwrap();
    let t = w.add_imu_topic("imu").unwrap();
    for i in 0..6000 {
        let (rt, imu) = crate::common::synthetic(i);
        w.write_imu(t, rt.as_nanos(), &imu).unwrap();
    }
    w.finish().unwrap();
    let ours = std::fs::read(ours_dir.join("ours_0.mcap")).unwrap();
    let mut bad_chunk = ours.clone();
    bad_chunk[ours.len() / 3] ^= 0xFF;
    std::fs::write(&path, &bad_chunk).unwrap();
    let r = read(&path).unwrap();
    assert!(
        r.series[0].len() < 6000 && r.series[0].len() > 1000,
        "{}",
        r.series[0].len()
    );
    assert!(
        r.series[0]
            .notes
            .iter()
            .any(|n| n.text.contains("CRC") || n.text.contains("chunk")),
        "{:?}",
        r.series[0].notes
    );
    // Many cuts and flips: never a panic.
    for k in 0..48 {
        let at = 8 + (k * 7919 * 13) % (mcap.len() - 8);
        let mut b = mcap.clone();
        b[at] ^= 0xA5;
        std::fs::write(&path, &b).unwrap();
        let _ = read(&path);
        std::fs::write(&path, &mcap[..at]).unwrap();
        let _ = read(&path);
    }
    let dbp = dir.path().join("x.db3");
    for k in 0..24 {
        let at = 100 + (k * 104_729) % (db.len() - 100);
        let mut b = db.clone();
        b[at] ^= 0xA5;
        std::fs::write(&dbp, &b).unwrap();
        let _ = read(&dbp);
        std::fs::write(&dbp, &db[..at]).unwrap();
        let _ = read(&dbp);
    }
    // Empty and junk files name what they are and what is accepted.
    for (name, bytes) in [
        ("e.mcap", &b""[..]),
        ("j.db3", b"SQLite format 3\0 but not really"),
        ("m.mcap", b"\x89MCAP0\r\n"),
    ] {
        let p = dir.path().join(name);
        std::fs::write(&p, bytes).unwrap();
        let e = read(&p).unwrap_err().to_string();
        assert!(!e.is_empty() && e.contains(name), "{name}: {e}");
    }
    let (ok, _, err) = run(bag2mat().arg(dir.path().join("e.mcap")).arg("imu"));
    assert!(
        !ok && err.contains("empty") && err.contains("Accepted") && !err.contains("panicked"),
        "{err}"
    );
    // A directory without metadata.yaml says so.
    let (ok, _, err) = run(bag2mat().arg(dir.path()).arg("imu"));
    assert!(!ok && err.contains("metadata.yaml"), "{err}");
}
