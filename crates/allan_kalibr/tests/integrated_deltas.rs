//! PX4 `vehicle_imu` (integrated deltas, `delta_angle_dt`/`delta_velocity_dt` µs): rows far
//! apart that each integrate a few ms are refused with the reason (a dead-time sampling:
//! read at their spacing the white noise is √(spacing/interval) too high); rows that tile the
//! time are samples, and give the noise the log's samples give. On logs pyulog's writer
//! made, with a known truth.

use std::process::Command;

/// The log's truth, continuous-time white noise.
const GYRO_N: f64 = 1e-3;
const ACC_N: f64 = 1e-2;

fn log(dir: &std::path::Path, row_us: u32, dt_us: u32) -> std::path::PathBuf {
    let p = dir.join(format!("deltas_{row_us}.ulg"));
    let spec = format!(
        r#"{{"seed": 9, "start_us": 1000000, "topics": [
            {{"kind": "sensor_combined", "rate": 250, "seconds": 120, "t0_us": 1000000, "gyro_n": {GYRO_N}, "acc_n": {ACC_N}}},
            {{"kind": "vehicle_imu", "row_us": {row_us}, "dt_us": {dt_us}, "seconds": 120, "t0_us": 1000000, "gyro_n": {GYRO_N}, "acc_n": {ACC_N}}}]}}"#
    );
    bag2mat::test_tools::independent_log("ulog", &p, &spec);
    p
}

fn analyse(log: &std::path::Path, out: &std::path::Path) -> (Option<i32>, String, String) {
    let o = Command::new(env!("CARGO_BIN_EXE_allan_kalibr"))
        .arg(log)
        .args(["--topic", "vehicle_imu", "-q", "-o"])
        .arg(out)
        .output()
        .unwrap();
    (
        o.status.code(),
        String::from_utf8_lossy(&o.stdout).into_owned(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

#[test]
fn vehicle_imu_rows_far_apart_are_refused_with_the_reason() {
    let dir = tempfile::tempdir().unwrap();
    let log = log(dir.path(), 500_000, 4900);
    let out = dir.path().join("far");
    let (code, _, err) = analyse(&log, &out);
    // before: analysed at 2 Hz, N ~10× the truth and "resolved"
    assert_eq!(code, Some(1), "{err}");
    assert!(
        err.contains("allan_kalibr: error: topic 'vehicle_imu' holds integrated deltas")
            && err.contains("√(500.0/4.9) = 10.1× too high"),
        "{err}"
    );
    assert!(!out.exists());
}

#[test]
fn vehicle_imu_rows_that_tile_the_time_are_samples_with_the_logs_noise() {
    let dir = tempfile::tempdir().unwrap();
    let log = log(dir.path(), 4000, 4000);
    let out = dir.path().join("tiled");
    let (code, _, err) = analyse(&log, &out);
    assert_eq!(code, Some(0), "{err}");
    let yaml = std::fs::read_to_string(out.join("kalibr_imu_ieee952.yaml")).unwrap();
    let n = |key: &str| bag2mat::test_tools::yaml_number(&yaml, key);
    // 30,000 rows give N to about ±1 % (95 %); the largest axis of three is written
    const N_REL_TOL: f64 = 0.05;
    for (key, truth) in [
        ("gyroscope_noise_density", GYRO_N),
        ("accelerometer_noise_density", ACC_N),
    ] {
        assert!(
            (n(key) / truth - 1.0).abs() < N_REL_TOL,
            "{key} {} against {truth}\n{yaml}",
            n(key)
        );
    }
}
