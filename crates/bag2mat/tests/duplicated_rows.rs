//! Rows stored twice, on the container side — a chunk recorded twice in a ROS 1 bag Debian's
//! python3-rosbag wrote, a storage file listed twice in a rosbags-written ROS 2 bag's
//! `metadata.yaml` (more rows than the container promises) — are reported by `bag2mat info`
//! as duplicated samples, with the rate of those it keeps.

use std::path::Path;

use bag2mat::test_tools::BagOp;
use bag2mat::test_tools::{OddWriter, ROS2_MODES, odd_record, rosbags_convert};
use bag2mat::{Finding, FindingKind};

use crate::ros1_damage_and_outputs::{field, records};

/// Messages of the clean record: 300 s at 200 Hz.
const N: usize = 60_000;

/// `bag2mat info`'s Imu topic: its rate, and its findings of `kind`.
fn imu_topic(path: &Path, kind: FindingKind) -> (f64, Vec<Finding>) {
    let info = bag2mat::info(path, true).unwrap();
    let t = info.topics.iter().find(|t| t.imu).expect("an Imu topic");
    let f = t
        .findings
        .iter()
        .filter(|f| f.kind == kind)
        .cloned()
        .collect();
    (t.rate.expect("a rate"), f)
}

/// A copy of the bag's last chunk (with its index records) stored again after it.
fn record_last_chunk_twice(bag: &Path) -> usize {
    let bytes = std::fs::read(bag).unwrap();
    let recs = records(&bytes);
    let last = recs.iter().rposition(|r| r.op == BagOp::Chunk).unwrap();
    let end = recs[last + 1..]
        .iter()
        .find(|r| r.op != BagOp::IndexData)
        .expect("the index section")
        .pos;
    let copy = bytes[recs[last].pos..end].to_vec();
    let mut out = bytes[..end].to_vec();
    out.extend_from_slice(&copy);
    out.extend_from_slice(&bytes[end..]);
    // the index section moved by the copy's length
    let head = recs.iter().find(|r| r.op == BagOp::BagHeader).unwrap();
    let at = field(&out, &head.header, "index_pos");
    let pos = u64::from_le_bytes(out[at..at + 8].try_into().unwrap()) + copy.len() as u64;
    out[at..at + 8].copy_from_slice(&pos.to_le_bytes());
    std::fs::write(bag, out).unwrap();
    // messages in the copied chunk: its index records count them
    recs[last + 1..]
        .iter()
        .take_while(|r| r.op == BagOp::IndexData)
        .map(|r| {
            let c = field(&bytes, &r.header, "count");
            u32::from_le_bytes(bytes[c..c + 4].try_into().unwrap()) as usize
        })
        .sum()
}

#[test]
fn rows_stored_twice_are_more_than_the_container_promises() {
    let tmp = tempfile::tempdir().unwrap();
    let bag = tmp.path().join("chunk_twice.bag");
    odd_record(OddWriter::Rosbag, &bag, "clean", 300.0, 200.0);
    let extra = record_last_chunk_twice(&bag);
    assert!(extra > 0);
    // the reader reads the chunk the index does not list (and says so); its rows are the
    // duplicates (before: nothing said, the copy's rows analysed twice)
    let (rate, d) = imu_topic(&bag, FindingKind::Duplicates);
    assert!(
        d.len() == 1 && d[0].size == Some(extra as f64),
        "{extra} rows stored twice: {d:?}"
    );
    assert!((rate - 200.0).abs() < 1e-6, "{rate}");

    // a ROS 2 bag whose metadata.yaml lists its storage file twice
    let clean = tmp.path().join("clean.bag");
    odd_record(OddWriter::Rosbag, &clean, "clean", 300.0, 200.0);
    let dir = tmp.path().join("twice");
    rosbags_convert(&[&clean], &dir, ROS2_MODES[1].1);
    let meta = dir.join("metadata.yaml");
    let text = std::fs::read_to_string(&meta).unwrap();
    let listed = "  - twice.mcap\n";
    assert!(text.contains(listed), "{text}");
    std::fs::write(&meta, text.replace(listed, &listed.repeat(2))).unwrap();
    let (rate, f) = imu_topic(&dir, FindingKind::ExtraRows);
    assert!(f.len() == 1 && f[0].size == Some(N as f64), "{f:?}");
    let (_, d) = imu_topic(&dir, FindingKind::Duplicates);
    assert!(d.len() == 1 && d[0].size == Some(N as f64), "{d:?}");
    assert!((rate - 200.0).abs() < 1e-6, "{rate}");
}
