//! The record must be what the analysis assumes, on `allan_imu_utils` (header.stamp, as
//! imu_utils reads it) and across the tools: records written by an independent writer
//! (Debian's python3-rosbag, Foxglove's mcap_ros2 writer with header jitter and transport
//! latency; bag2mat's `tests/py/odd_records.py`), the binary run as a user would, and
//! `allan_kalibr` and `bag2mat info` through their libraries where the same record must give
//! the same finding.

use std::path::Path;
use std::process::Command;

use bag2mat::test_tools::{OddRecord, OddWriter, odd_record, warnings};
use bag2mat::{Finding, FindingKind};

use crate::common::kalibr_config;

/// The mean over six axes of N / truth: five minutes at 200 Hz give each axis' N to ±0.6 %
/// (95 %), their mean to ±0.25 %; 0.5 % is twice that, and half the +1 % of a mean-period
/// rate with 2 % of the samples lost.
const N_MEAN_REL_TOL: f64 = 0.005;

/// Runs the binary on `bag` (`-q`, output into `out`); must succeed: (stdout, stderr).
fn imu_utils(bag: &Path, topic: &str, out: &Path, extra: &[&str]) -> (String, String) {
    let o = Command::new(env!("CARGO_BIN_EXE_allan_imu_utils"))
        .arg(bag)
        .args(["--topic", topic, "--name", "x", "-q", "--no-plots"])
        .arg("--data-save-path")
        .arg(out)
        .args(extra)
        .output()
        .expect("run allan_imu_utils");
    let text = |b: &[u8]| String::from_utf8_lossy(b).into_owned();
    assert!(o.status.success(), "{}", text(&o.stderr));
    (text(&o.stdout), text(&o.stderr))
}

/// The six N of the printed section (gyro x y z, acc x y z) over their truth.
fn n_ratios(section: &str, truth: &OddRecord) -> Vec<f64> {
    let n: Vec<f64> = section
        .lines()
        .filter_map(|l| l.trim_start().strip_prefix("white noise N  = "))
        .map(|v| v.split_whitespace().next().unwrap().parse().unwrap())
        .collect();
    assert_eq!(n.len(), 6, "{section}");
    (0..6)
        .map(|k| n[k] / if k < 3 { truth.gyro.0 } else { truth.acc.0 })
        .collect()
}

#[test]
fn dropped_samples_keep_the_nominal_rate_in_imu_utils() {
    // 2 % of the messages lost one at a time, MCAP with header jitter and latency
    let tmp = tempfile::tempdir().unwrap();
    let mcap = tmp.path().join("drop.mcap");
    let truth = odd_record(OddWriter::Mcap, &mcap, "dropouts", 300.0, 200.0);
    let out = tmp.path().join("o");
    let (text, _) = imu_utils(&mcap, "/imu", &out, &[]);
    // before: 195.88 Hz (imu_utils' mean period), every N +1 %
    assert!(text.contains("continuous time, 200 Hz"), "{text}");
    let yaml = std::fs::read_to_string(out.join("x_kalibr_imu_ieee952.yaml")).unwrap();
    assert!(
        yaml.lines()
            .any(|l| l.starts_with("update_rate:") && l.contains(" 200.0 ")),
        "{yaml}"
    );
    let r = n_ratios(&text, &truth);
    let mean = r.iter().sum::<f64>() / 6.0;
    assert!((mean - 1.0).abs() < N_MEAN_REL_TOL, "N / truth: {r:?}");
}

#[test]
fn header_and_record_clocks_are_cross_checked() {
    // record time at 100 Hz, header.stamp advancing at 200 Hz
    let tmp = tempfile::tempdir().unwrap();
    let bag = tmp.path().join("h2x.bag");
    odd_record(OddWriter::Rosbag, &bag, "header2x", 300.0, 100.0);
    let (text, err) = imu_utils(&bag, "imu", &tmp.path().join("u"), &[]);
    let w = warnings(&err, "clock mismatch");
    // before: nothing said, N 29 % low on the header's rate
    assert!(
        w.len() == 1
            && w[0].contains("the record time advances at 100.0000 Hz")
            && w[0].contains("header.stamp (analysed) at 200.0000 Hz")
            && w[0].contains("every N here is off by ×0.707"),
        "{err}"
    );
    assert!(text.contains("record check: clock mismatch"), "{text}");
    let yaml = std::fs::read_to_string(tmp.path().join("u/x_kalibr_imu_ieee952.yaml")).unwrap();
    assert!(yaml.contains("# RECORD CHECK: clock mismatch"), "{yaml}");
    // allan_kalibr, on the record time, says the same the other way round
    let k = allan_kalibr::run(
        &kalibr_config(&bag, "imu", &tmp.path().join("k")),
        &bag2mat::shared::output::Outputs::direct(),
    )
    .unwrap()
    .remove(0);
    let f: Vec<&Finding> = k
        .section
        .findings
        .iter()
        .filter(|f| f.kind == FindingKind::ClockMismatch)
        .collect();
    assert!(f.len() == 1 && f[0].size == Some(200.0), "{f:?}");
}

#[test]
fn missing_samples_are_counted_exactly_in_every_tool() {
    // 2 % single-sample dropouts: 1,200-odd missing of 60,000
    let tmp = tempfile::tempdir().unwrap();
    let bag = tmp.path().join("drop.bag");
    let truth = odd_record(OddWriter::Rosbag, &bag, "dropouts", 300.0, 200.0);
    let lost = (60_000 - truth.messages) as f64;
    // allan_imu_utils (header.stamp; the writer stamps both clocks alike)
    let (_, err) = imu_utils(&bag, "imu", &tmp.path().join("u"), &[]);
    let w = warnings(&err, "gaps");
    // before: nothing (single dropouts were not gaps); 58 gaps, "≈ 119 missing" at 2 %
    assert!(
        w.len() == 1 && w[0].contains(&format!("{lost} samples missing")),
        "{err}"
    );
    let gaps = |fs: &[Finding]| -> Finding {
        let g: Vec<&Finding> = fs.iter().filter(|f| f.kind == FindingKind::Gaps).collect();
        assert_eq!(g.len(), 1, "{fs:?}");
        g[0].clone()
    };
    // allan_kalibr (record time), through its library
    let k = allan_kalibr::run(
        &kalibr_config(&bag, "imu", &tmp.path().join("k")),
        &bag2mat::shared::output::Outputs::direct(),
    )
    .unwrap()
    .remove(0);
    let gk = gaps(&k.section.findings);
    assert_eq!(gk.size, Some(lost));
    // the same line, the longest gap's place included
    assert_eq!(w[0], gk.to_string());
    assert!(gk.text.contains(&format!("in {lost} gap(s)")), "{gk}");
    assert!(gk.time.is_some() && gk.sample.is_some());
    // bag2mat info
    let info = bag2mat::info(&bag, true).unwrap();
    let t = &info.topics[0];
    assert_eq!((t.missing as f64, t.gaps as f64), (lost, lost), "{t:?}");
    assert_eq!(gaps(&t.findings), gk);
}

#[test]
fn a_header_that_steps_back_is_a_clock_step_not_a_gap() {
    let tmp = tempfile::tempdir().unwrap();
    let bag = tmp.path().join("hstep.bag");
    odd_record(OddWriter::Rosbag, &bag, "headerstep", 300.0, 200.0);
    let (text, err) = imu_utils(&bag, "imu", &tmp.path().join("u"), &[]);
    let w = warnings(&err, "clock step");
    assert!(
        w.len() == 1 && w[0].contains("header.stamp steps back") && w[0].contains("0.495 s back"),
        "{err}"
    );
    assert!(warnings(&err, "gaps").is_empty(), "{err}");
    // the longer stretch (the first 60 %) is analysed at its own rate
    assert!(w[0].contains("36000 of 60000"), "{err}");
    assert!(text.contains("continuous time, 200 Hz"), "{text}");
}
