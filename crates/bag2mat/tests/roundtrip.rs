//! Our writer and reader against each other and against genpy's golden bytes; broken bags.

use bag2mat::{BagReader, BagWriter};
use bag2mat::{Compression, Error, ReadOptions, RosTime, read_imu_series};
use bag2mat::{IMU_MD5, Imu, imu_definition};
use md5::{Digest, Md5};

use crate::common::{synthetic, write_synthetic};

const COMPRESSIONS: [Compression; 3] = [Compression::None, Compression::Bz2, Compression::Lz4];

#[test]
fn imu_bytes_equal_genpy() {
    // tests/fixtures/imu_golden.bin: genpy's serialization (Debian python3-sensor-msgs) of an Imu
    // with seq 7, stamp 1600000000.005, frame "imu", w = 1, cov[0] = -1, gyro (0.1,-0.2,0.3),
    // acc (1.5,-2.5,9.81).
    let golden = include_bytes!("fixtures/imu_golden.bin");
    let mut cov = [0.0; 9];
    cov[0] = -1.0;
    let imu = Imu {
        seq: 7,
        stamp: RosTime {
            sec: 1_600_000_000,
            nsec: 5_000_000,
        },
        frame_id: "imu".into(),
        orientation: [0.0, 0.0, 0.0, 1.0],
        orientation_covariance: cov,
        angular_velocity: [0.1, -0.2, 0.3],
        linear_acceleration: [1.5, -2.5, 9.81],
        ..Imu::default()
    };
    let mut buf = Vec::new();
    imu.encode(&mut buf);
    assert_eq!(buf.len(), 315);
    assert_eq!(&buf[..], &golden[..]);
    assert_eq!(Imu::decode(golden).unwrap(), imu);
}

#[test]
fn definition_equals_genpy_full_text() {
    let golden = include_str!("fixtures/imu_full_text.txt");
    assert_eq!(imu_definition().len(), 2571);
    assert_eq!(imu_definition(), golden);
}

/// The ROS 1 md5 recipe (docs/formats.md §5.2) applied to the vendored .msg files.
#[test]
fn md5_recomputed_from_msg_files() {
    fn hash_text(msg: &str, deps: &[(&str, String)]) -> String {
        let lines: Vec<String> = msg
            .lines()
            .map(|l| l.split('#').next().unwrap().trim().to_string())
            .filter(|l| !l.is_empty())
            .map(|l| {
                let (ty, name) = l.split_once(char::is_whitespace).unwrap();
                let base = ty.rsplit('/').next().unwrap();
                match deps.iter().find(|(d, _)| *d == base) {
                    Some((_, md5)) => format!("{md5} {}", name.trim()),
                    None => format!("{ty} {}", name.trim()),
                }
            })
            .collect();
        format!("{:x}", Md5::digest(lines.join("\n").as_bytes()))
    }
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("msg");
    let read = |f: &str| std::fs::read_to_string(dir.join(f)).unwrap();
    let header = hash_text(&read("std_msgs_Header.msg"), &[]);
    let quat = hash_text(&read("geometry_msgs_Quaternion.msg"), &[]);
    let vec3 = hash_text(&read("geometry_msgs_Vector3.msg"), &[]);
    assert_eq!(header, "2176decaecbce78abc3b96ef049fabed");
    assert_eq!(quat, "a779879fadf0160734f906b8c19c7004");
    assert_eq!(vec3, "4a842b65f413084dc2b10fb484ea7f17");
    let deps = [
        ("Header".to_string(), header),
        ("Quaternion".into(), quat),
        ("Vector3".into(), vec3),
    ];
    let deps: Vec<(&str, String)> = deps.iter().map(|(a, b)| (a.as_str(), b.clone())).collect();
    assert_eq!(hash_text(&read("sensor_msgs_Imu.msg"), &deps), IMU_MD5);
}

#[test]
fn write_then_read_every_compression() {
    let dir = tempfile::tempdir().unwrap();
    const N: u32 = 6000; // about three 768 KiB chunks
    for c in COMPRESSIONS {
        let path = dir.path().join(format!("rt_{}.bag", c.name()));
        write_synthetic(&path, "/imu0", N, c, true);
        let s = read_imu_series(&path, "/imu0", &ReadOptions { quiet: true }).unwrap();
        assert_eq!(s.len(), N as usize, "{c:?}");
        assert!(s.notes.is_empty(), "{c:?}: {:?}", s.notes);
        for i in 0..N {
            let (t, imu) = synthetic(i);
            let k = i as usize;
            assert_eq!(
                (
                    s.record_time[k],
                    s.stamp[k],
                    s.seq[k],
                    s.gyro_at(k),
                    s.acc_at(k)
                ),
                (
                    t,
                    imu.stamp,
                    imu.seq,
                    imu.angular_velocity,
                    imu.linear_acceleration
                ),
                "{c:?} message {i}"
            );
        }
        let bag = BagReader::open(&path).unwrap();
        assert!(bag.index().indexed);
        assert_eq!(bag.index().chunk_count, 3, "{c:?}");
    }
}

#[test]
fn slash_form_fallback_is_noted() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("a.bag");
    write_synthetic(&path, "imu", 10, Compression::None, false);
    let s = read_imu_series(&path, "/imu", &ReadOptions { quiet: true }).unwrap();
    assert_eq!((s.len(), s.topic.as_str()), (10, "imu"));
    assert!(
        s.notes.iter().any(|n| n.text.contains("using 'imu'")),
        "{:?}",
        s.notes
    );
}

#[test]
fn missing_topic_lists_every_topic() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("a.bag");
    write_synthetic(&path, "/imu0", 1000, Compression::Lz4, true);
    let err = read_imu_series(&path, "/cam0", &ReadOptions { quiet: true }).unwrap_err();
    let msg = err.to_string();
    assert!(matches!(err, Error::TopicNotFound { .. }), "{msg}");
    assert!(
        msg.contains("/imu0") && msg.contains("1000 msgs") && msg.contains("sensor_msgs/Imu"),
        "{msg}"
    );
    assert!(
        msg.contains("/status") && msg.contains("10 msgs") && msg.contains("std_msgs/String"),
        "{msg}"
    );
    let err = read_imu_series(&path, "/status", &ReadOptions { quiet: true }).unwrap_err();
    assert!(matches!(err, Error::WrongType { .. }), "{err}");
}

#[test]
fn out_of_order_record_times_come_out_sorted() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("ooo.bag");
    let mut w = BagWriter::create(
        &bag2mat::shared::output::Outputs::direct(),
        &path,
        Compression::None,
    )
    .unwrap();
    let c = w.add_imu_connection("imu");
    let order = [0u32, 2, 1, 4, 3, 5];
    for &i in &order {
        let (t, imu) = synthetic(i);
        w.write_imu(c, t, &imu).unwrap();
    }
    w.finish().unwrap();
    let s = read_imu_series(&path, "imu", &ReadOptions { quiet: true }).unwrap();
    assert_eq!(s.seq, vec![0, 1, 2, 3, 4, 5]);
    assert!(s.notes.iter().any(|n| n.text.contains("sorted")));
}

#[test]
fn truncated_bag_keeps_complete_chunks() {
    let dir = tempfile::tempdir().unwrap();
    for c in COMPRESSIONS {
        let path = dir.path().join(format!("t_{}.bag", c.name()));
        write_synthetic(&path, "imu", 6000, c, false);
        let full = std::fs::read(&path).unwrap();
        // Cut inside the third chunk: the index is gone and so is the last chunk.
        let cut = full.len() * 3 / 4;
        std::fs::write(&path, &full[..cut]).unwrap();
        let s = read_imu_series(&path, "imu", &ReadOptions { quiet: true }).unwrap();
        assert!(
            !s.is_empty() && s.len() < 6000,
            "{c:?}: {} messages",
            s.len()
        );
        assert!(
            s.notes.iter().any(|n| n.text.contains("truncated")),
            "{c:?}: {:?}",
            s.notes
        );
        for (k, seq) in s.seq.iter().enumerate() {
            assert_eq!(
                *seq as usize, k,
                "{c:?}: messages of the complete chunks, in order"
            );
        }
    }
}

/// `dir/u.bag`: 3000 Imu messages in bz2 chunks, as a writer that crashed leaves them (it
/// never rewrote the header: index_pos = 0).
fn unfinished_bag(dir: &std::path::Path) -> std::path::PathBuf {
    let path = dir.join("u.bag");
    write_synthetic(&path, "imu", 3000, Compression::Bz2, false);
    let mut bytes = std::fs::read(&path).unwrap();
    let h = &mut bytes[13..13 + 4104];
    let at = h.windows(10).position(|w| w == b"index_pos=").unwrap() + 10;
    h[at..at + 8].fill(0);
    std::fs::write(&path, &bytes).unwrap();
    path
}

/// A reader's note is said by whoever prints it, in its own way: the converter as a
/// `warning:` line on stderr, `bag2mat info` as a `note:` line of its report (never both
/// prefixes, never the note's level as part of its text).
#[test]
fn a_readers_note_is_a_warning_to_the_converter_and_a_note_to_info() {
    let dir = tempfile::tempdir().unwrap();
    let path = unfinished_bag(dir.path());
    let said = "the bag has no index (index_pos = 0: the writer did not finish)";
    let bin = || std::process::Command::new(env!("CARGO_BIN_EXE_bag2mat"));
    let (ok, out, err) = crate::common::run(bin().arg("info").arg(&path));
    assert!(ok, "{err}");
    let lines = |t: &str| -> Vec<String> {
        t.lines()
            .filter(|l| l.contains(said))
            .map(str::to_string)
            .collect()
    };
    let info = lines(&format!("{out}{err}"));
    assert_eq!(info.len(), 1, "{out}{err}");
    assert!(info[0].starts_with(&format!("note: {said}")), "{info:?}");
    let csv = dir.path().join("u.csv");
    let (ok, _, err) = crate::common::run(bin().arg(&path).args(["imu", "-q", "-o"]).arg(&csv));
    assert!(ok, "{err}");
    let conv = lines(&err);
    assert_eq!(conv.len(), 1, "{err}");
    assert!(conv[0].starts_with(&format!("warning: {said}")), "{conv:?}");
}

#[test]
fn unfinished_bag_is_scanned() {
    let dir = tempfile::tempdir().unwrap();
    let path = unfinished_bag(dir.path());
    let s = read_imu_series(&path, "imu", &ReadOptions { quiet: true }).unwrap();
    assert_eq!(s.len(), 3000);
    assert!(
        s.notes.iter().any(|n| n.text.contains("index_pos = 0")),
        "{:?}",
        s.notes
    );
}

#[test]
fn corrupt_bytes_never_panic() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("c.bag");
    write_synthetic(&path, "imu", 2500, Compression::Lz4, false);
    let good = std::fs::read(&path).unwrap();
    // Flip bytes at many places (fixed stride, no RNG needed) and cut at many lengths.
    for k in 0..64 {
        let mut bad = good.clone();
        let at = 13 + (k * 7919) % (good.len() - 13);
        bad[at] ^= 0xA5;
        std::fs::write(&path, &bad).unwrap();
        let _ = read_imu_series(&path, "imu", &ReadOptions { quiet: true });
        std::fs::write(&path, &good[..at]).unwrap();
        let _ = read_imu_series(&path, "imu", &ReadOptions { quiet: true });
    }
    for junk in [&b""[..], b"#ROSBAG V1.2\n", b"hello world, not a bag"] {
        std::fs::write(&path, junk).unwrap();
        let e = read_imu_series(&path, "imu", &ReadOptions { quiet: true }).unwrap_err();
        assert!(matches!(e, Error::NotABag { .. }), "{e}");
    }
}

#[test]
fn unfinished_writer_leaves_nothing_behind() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("never.bag");
    {
        let mut w = BagWriter::create(
            &bag2mat::shared::output::Outputs::direct(),
            &path,
            Compression::Lz4,
        )
        .unwrap();
        let c = w.add_imu_connection("imu");
        for i in 0..5000 {
            let (t, imu) = synthetic(i);
            w.write_imu(c, t, &imu).unwrap();
        }
        // dropped here without finish(): an interrupted run
    }
    assert_eq!(
        std::fs::read_dir(dir.path()).unwrap().count(),
        0,
        "no bag and no temporary file"
    );
}

/// `bag_to_data_imu` (which consumes the series column by column) and the row-by-row
/// conversion of the same series agree exactly, and an out-of-order bag comes out sorted.
#[test]
fn matrix_routes_agree_and_sort() {
    use bag2mat::{bag_to_data_imu, data_imu_from_series};
    let p2 = crate::common::case_bag("p2_medium_100hz");
    let planned = bag_to_data_imu(&p2, "/imu/data", true).unwrap().data;
    let streamed = data_imu_from_series(
        &read_imu_series(&p2, "/imu/data", &ReadOptions { quiet: true }).unwrap(),
        bag2mat::TimeColumn::Record,
    );
    assert_eq!(planned, streamed);

    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("ooo.bag");
    let mut w = BagWriter::create(
        &bag2mat::shared::output::Outputs::direct(),
        &path,
        Compression::None,
    )
    .unwrap();
    let c = w.add_imu_connection("imu");
    for i in [0u32, 2, 1, 4, 3, 5] {
        let (t, imu) = synthetic(i);
        w.write_imu(c, t, &imu).unwrap();
    }
    w.finish().unwrap();
    let conv = bag_to_data_imu(&path, "imu", true).unwrap();
    let want: Vec<f64> = (0..6).map(|i| synthetic(i).0.to_sec()).collect();
    assert_eq!(conv.data.t(), &want[..]);
    assert!(
        conv.notes.iter().any(|n| n.text.contains("sorted")),
        "{:?}",
        conv.notes
    );
}
