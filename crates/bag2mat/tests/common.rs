//! Shared helpers: where the reference data is, and a deterministic synthetic Imu stream.

use std::path::{Path, PathBuf};

use bag2mat::BagWriter;
use bag2mat::Imu;
use bag2mat::{Compression, RosTime};

/// The workspace's `testdata/` folder.
pub fn testdata() -> PathBuf {
    bag2mat::test_tools::testdata()
}

/// The reference cases with their Imu topic.
pub const CASES: [(&str, &str); 4] = [
    ("p1_high_200hz", "imu"),
    ("p2_medium_100hz", "/imu/data"),
    ("p3_short_61s", "imu"),
    ("p4_high_100hz_60min", "imu"),
];

/// The bag of a reference case.
pub fn case_bag(case: &str) -> PathBuf {
    testdata().join(case).join(format!("{case}.bag"))
}

/// Message `i` of the synthetic stream: values that exercise every field and all bits.
pub fn synthetic(i: u32) -> (RosTime, Imu) {
    let t = RosTime::from_nanos(1_700_000_000_000_000_000 + i as u64 * 5_000_000);
    let x = i as f64;
    let imu = Imu {
        seq: i,
        stamp: t,
        frame_id: "imu_link".into(),
        orientation: [0.0, 0.0, (x * 1e-3).sin(), (x * 1e-3).cos()],
        orientation_covariance: [-1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
        angular_velocity: [(x * 0.37).sin() / 3.0, -x * 1e-7, 1.0 / (x + 3.0)],
        angular_velocity_covariance: [0.0; 9],
        linear_acceleration: [(x * 0.11).cos() * 0.1, 1e-300 * x, 9.81 + x * 1e-9],
        linear_acceleration_covariance: [0.0; 9],
    };
    (t, imu)
}

/// Writes `n` synthetic messages on `topic` (plus an optional second, non-Imu topic).
pub fn write_synthetic(path: &Path, topic: &str, n: u32, compression: Compression, extra: bool) {
    let mut w = BagWriter::create(
        &bag2mat::shared::output::Outputs::direct(),
        path,
        compression,
    )
    .unwrap();
    let c = w.add_imu_connection(topic);
    let s = extra.then(|| bag2mat::test_tools::add_string_connection(&mut w, "/status"));
    for i in 0..n {
        let (t, imu) = synthetic(i);
        w.write_imu(c, t, &imu).unwrap();
        if let (Some(s), true) = (s, i % 100 == 0) {
            let data = bag2mat::test_tools::string_message(&format!("status {i}"));
            w.write_raw(s, t, &data).unwrap();
        }
    }
    w.finish().unwrap();
}

/// Runs a command, returning (success, stdout, stderr).
pub fn run(cmd: &mut std::process::Command) -> (bool, String, String) {
    let out = cmd
        .output()
        .unwrap_or_else(|e| panic!("cannot run {cmd:?}: {e} (scripts/test.sh installs the tools)"));
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}
