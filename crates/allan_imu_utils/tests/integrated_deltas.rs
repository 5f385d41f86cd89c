//! PX4 `vehicle_imu` rows far apart that each integrate a few ms are refused with the reason,
//! as allan_kalibr refuses them (the rule: `bag2mat::check_integration`). On a log pyulog's
//! writer made.

use std::process::Command;

#[test]
fn vehicle_imu_rows_far_apart_are_refused_with_the_reason() {
    let dir = tempfile::tempdir().unwrap();
    let log = dir.path().join("deltas.ulg");
    bag2mat::test_tools::independent_log(
        "ulog",
        &log,
        r#"{"seed": 9, "start_us": 1000000, "topics": [
            {"kind": "sensor_combined", "rate": 250, "seconds": 120, "t0_us": 1000000, "gyro_n": 1e-3, "acc_n": 1e-2},
            {"kind": "vehicle_imu", "row_us": 500000, "dt_us": 4900, "seconds": 120, "t0_us": 1000000, "gyro_n": 1e-3, "acc_n": 1e-2}]}"#,
    );
    let out = dir.path().join("o");
    let o = Command::new(env!("CARGO_BIN_EXE_allan_imu_utils"))
        .arg(&log)
        .args(["--all-imu-topics", "-q", "-o"])
        .arg(&out)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    // one topic refused, the other written (the rule for several topics)
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("allan_imu_utils: error: topic 'vehicle_imu' holds integrated deltas")
            && err.contains("√(500.0/4.9) = 10.1× too high"),
        "{err}"
    );
    assert!(
        out.join("sensor_combined/imu_imu_param.yaml").is_file(),
        "{err}"
    );
    assert!(!out.join("vehicle_imu").exists());
}
