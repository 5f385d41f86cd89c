//! `bag2mat info` and the converter say what the record is, consistently: the table's gaps
//! are the ones its warnings count; a log's duration is its own span, not a stale message's;
//! a batch topic's losses are its own; gaps bridged at a cost to the time axis say so;
//! receive-time jitter is no lost sample; integrated deltas far apart are said to be no
//! samples; rows stored twice are said by the converter too. On logs independent writers
//! made: Debian's python rosbag, pyulog's writer, rosbags.

use std::path::Path;
use std::process::Command;

use bag2mat::test_tools::independent_log;
use bag2mat::{FindingKind, TopicInfo};

use crate::common::run;

fn bag2mat() -> Command {
    Command::new(env!("CARGO_BIN_EXE_bag2mat"))
}

/// `bag2mat info`'s entry for `topic`.
fn topic(path: &Path, topic: &str) -> TopicInfo {
    let info = bag2mat::info(path, true).unwrap();
    info.topics
        .into_iter()
        .find(|t| t.topic == topic)
        .unwrap_or_else(|| panic!("no topic {topic}"))
}

/// A ROS 1 bag of one 200 Hz topic `imu` of `n` messages, with `extra` JSON members for it.
fn ros1(path: &Path, n: usize, rate: f64, extra: &str) {
    let spec = format!(
        r#"{{"seed": 5, "topics": [{{"topic": "imu", "n": {n}, "rate": {rate}, "gyro_n": 1e-4, "acc_n": 1e-3{extra}}}]}}"#
    );
    independent_log("ros1", path, &spec);
}

#[test]
fn the_info_table_counts_the_gaps_its_warning_counts() {
    let dir = tempfile::tempdir().unwrap();
    let bag = dir.path().join("gaps.bag");
    // 60 s at 200 Hz with two long dropouts (4 % of the span): cut to the longest stretch
    ros1(
        &bag,
        12_000,
        200.0,
        r#", "drop_ranges": [[3000, 200], [9000, 280]]"#,
    );
    let t = topic(&bag, "imu");
    let gaps: Vec<_> = t
        .findings
        .iter()
        .filter(|f| f.kind == FindingKind::Gaps)
        .collect();
    assert_eq!(gaps.len(), 1, "{:?}", t.findings);
    assert_eq!(gaps[0].size, Some(480.0), "{}", gaps[0].text);
    // the table says what the warning says (before: 0 missing in the kept stretch)
    assert_eq!((t.missing, t.gaps), (480, 2), "{t:?}");
}

#[test]
fn a_ulogs_duration_is_its_own_span_not_a_stale_messages() {
    let dir = tempfile::tempdir().unwrap();
    let log = dir.path().join("flight.ulg");
    // the log starts at 112 s after boot and runs 69 s; battery_status's last message from
    // 0.5 s after boot is written when the logger subscribes
    independent_log(
        "ulog",
        &log,
        r#"{"seed": 2, "start_us": 112000000, "topics": [
            {"kind": "sensor_combined", "rate": 250, "seconds": 69, "t0_us": 112500000, "gyro_n": 1e-3, "acc_n": 1e-2},
            {"kind": "stale", "name": "battery_status", "times_us": [500000, 113000000, 150000000]}]}"#,
    );
    let (ok, out, err) = run(bag2mat().arg("info").arg(&log));
    assert!(ok, "{err}");
    // before: 180.996 s (from the stale message at 0.5 s to the last sample at 181.496 s)
    assert!(out.contains("duration:  68.996 s"), "{out}");
    assert!(
        out.contains("note: 1 message of 'battery_status' is stamped before the log started"),
        "{out}"
    );
}

#[test]
fn batch_sample_losses_are_the_batch_topics_own() {
    let dir = tempfile::tempdir().unwrap();
    let log = dir.path().join("00000042.BIN");
    let f = std::io::BufWriter::new(std::fs::File::create(&log).unwrap());
    // IMU:0 and IMU:1 whole; the last accelerometer batch short of its header's count (the
    // writer's log pymavlink reads sample for sample, tests/logs.rs)
    bag2mat::test_tools::dataflash_imu_log(f, 12.0, 200.0, 3).unwrap();
    let sel = bag2mat::TopicSelector {
        all_imu: true,
        ..Default::default()
    };
    let read = bag2mat::read_imu_topics(&log, &sel, &bag2mat::ReadOptions { quiet: true }).unwrap();
    for s in &read.series {
        let notes = bag2mat::shared::note::texts(&s.notes);
        if s.topic.starts_with("ISB_") {
            // each batch topic's last batch is short by 32 samples: its own, said on it (as
            // a bound: the log may have stopped before the batch was written whole)
            let other = if s.topic == "ISB_ACC" {
                "ISB_GYR"
            } else {
                "ISB_ACC"
            };
            assert!(
                notes.contains(&format!("up to 32 messages on '{}' were lost", s.topic))
                    && !notes.contains(other),
                "{}: {notes}",
                s.topic
            );
        } else {
            // before: the batches' 64 samples were said lost on every topic, IMU:0 included
            assert!(!notes.contains("lost"), "{}: {notes}", s.topic);
        }
    }
}

#[test]
fn bridged_gaps_say_the_time_axis_they_shrink() {
    let dir = tempfile::tempdir().unwrap();
    let bag = dir.path().join("holes.bag");
    // one sample in four lost, one at a time: bridged, 8.1 s of samples for a 10.8 s record
    ros1(&bag, 2160, 200.0, r#", "drop_every": [4, 1]"#);
    let t = topic(&bag, "imu");
    let gaps = t
        .findings
        .iter()
        .find(|f| f.kind == FindingKind::Gaps)
        .expect("a gaps finding");
    assert!(
        gaps.text
            .contains("analysis' time axis is 8.1 s of samples for a 10.8 s record")
            && gaps.text.contains("25 % of the time is gone"),
        "{}",
        gaps.text
    );
}

#[test]
fn receive_time_jitter_at_400_hz_is_no_lost_sample() {
    let dir = tempfile::tempdir().unwrap();
    let bag = dir.path().join("jitter.bag");
    // 400 Hz stamps received through a queue with an exponential delay of 0.6 ms mean
    // (a quarter period): long intervals beside short ones, nothing lost
    ros1(&bag, 24_000, 400.0, r#", "recv_delay_s": 0.0006"#);
    let t = topic(&bag, "imu");
    // before: hundreds of "missing" samples
    assert_eq!((t.missing, t.gaps), (0, 0), "{:?}", t.findings);
    // and the sensor's rate (before: 401.1 Hz, each jittered interval rounded to periods);
    // the span's ends are late by a receive delay each, a few ms over 60 s
    const RATE_REL_TOL: f64 = 1e-4;
    let rate = t.rate.expect("a rate");
    assert!((rate / 400.0 - 1.0).abs() < RATE_REL_TOL, "{rate} Hz");
    assert!(
        !t.findings.iter().any(|f| f.kind == FindingKind::Gaps),
        "{:?}",
        t.findings
    );
    // and real losses among the same jitter are counted exactly
    let lossy = dir.path().join("jitter_lossy.bag");
    ros1(
        &lossy,
        24_000,
        400.0,
        r#", "recv_delay_s": 0.0006, "drop_every": [200, 77]"#,
    );
    let t = topic(&lossy, "imu");
    assert_eq!((t.missing, t.gaps), (120, 120), "{:?}", t.findings);
}

#[test]
fn integrated_deltas_far_apart_are_said_to_be_no_samples_by_info_and_the_converter() {
    let dir = tempfile::tempdir().unwrap();
    let log = dir.path().join("deltas.ulg");
    independent_log(
        "ulog",
        &log,
        r#"{"seed": 3, "start_us": 1000000, "topics": [
            {"kind": "sensor_combined", "rate": 250, "seconds": 60, "t0_us": 1000000, "gyro_n": 1e-3, "acc_n": 1e-2},
            {"kind": "vehicle_imu", "row_us": 500000, "dt_us": 4900, "seconds": 60, "t0_us": 1000000, "gyro_n": 1e-3, "acc_n": 1e-2}]}"#,
    );
    let t = topic(&log, "vehicle_imu");
    let refused = t.refused.expect("refused");
    assert!(
        refused.contains("4.9 ms") && refused.contains("500.0 ms apart"),
        "{refused}"
    );
    // and the checks that read values as samples say nothing of rows that are none
    // (before: "deg/s read as rad/s?" on each gyro axis, the white noise read at 2 Hz)
    assert!(
        !t.findings.iter().any(|f| f.kind == FindingKind::Units),
        "{:?}",
        t.findings
    );
    assert!(topic(&log, "sensor_combined").refused.is_none());
    let out = dir.path().join("v.csv");
    let (ok, _, err) = run(bag2mat()
        .arg(&log)
        .args(["--topic", "vehicle_imu", "-q", "-o"])
        .arg(&out));
    assert!(ok, "{err}");
    assert!(
        err.contains("warning: topic 'vehicle_imu' holds integrated deltas"),
        "{err}"
    );
}

#[test]
fn the_converter_says_a_storage_file_listed_twice() {
    use bag2mat::test_tools::{OddWriter, ROS2_MODES, odd_record, rosbags_convert};
    let tmp = tempfile::tempdir().unwrap();
    let clean = tmp.path().join("clean.bag");
    odd_record(OddWriter::Rosbag, &clean, "clean", 15.0, 200.0);
    let dir = tmp.path().join("twice");
    rosbags_convert(&[&clean], &dir, ROS2_MODES[1].1);
    let meta = dir.join("metadata.yaml");
    let text = std::fs::read_to_string(&meta).unwrap();
    let listed = "  - twice.mcap\n";
    assert!(text.contains(listed), "{text}");
    std::fs::write(&meta, text.replace(listed, &listed.repeat(2))).unwrap();
    let out = tmp.path().join("twice.csv");
    let (ok, _, err) = run(bag2mat().arg(&dir).args(["-q", "-o"]).arg(&out));
    assert!(ok, "{err}");
    // before: 6,000 rows for 3,000 promised, nothing said
    assert!(
        err.contains(
            "warning: the container promises 3000 messages on this topic and 6000 rows were read"
        ),
        "{err}"
    );
    assert!(err.contains("3000 samples are stored twice"), "{err}");
}
