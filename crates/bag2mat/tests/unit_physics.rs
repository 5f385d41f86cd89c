//! Units a user gets wrong are checked against physics whatever the flags or the header
//! say, and refused with the flag to fix: a static record's specific force is gravity in
//! the unit given (g read as m/s² is ≈1), stamps in s read as ms make a 200 kHz IMU, a
//! `time [s]` header over milliseconds a 0.2 Hz one, deg/s read as rad/s a gyroscope noise
//! no IMU has. Text logs written with numpy (an independent writer, known truth).

use std::path::Path;
use std::process::Command;

use bag2mat::test_tools::{run_ok, venv_python};

use crate::common::run;

/// A 60 s static record at 200 Hz (white noise of a good MEMS IMU, gravity on z) written by
/// numpy as `columns` with time, gyro and acc scaled by the given factors (from s, rad/s,
/// m/s²) and the time offset.
fn numpy_csv(path: &Path, header: &str, t_scale: f64, t0: f64, g_scale: f64, a_scale: f64) {
    let script = format!(
        r#"
import numpy as np
rng = np.random.default_rng(7)
n, rate = 12000, 200.0
t = np.arange(n) / rate
g = rng.normal(0, 2e-4 * np.sqrt(rate), (n, 3)) + [1e-3, -2e-3, 5e-4]
a = rng.normal(0, 2e-3 * np.sqrt(rate), (n, 3)); a[:, 2] += 9.80665
cols = np.column_stack([t * {t_scale} + {t0}, g * {g_scale}, a * {a_scale}])
np.savetxt(r"{}", cols, delimiter=",", header="{header}", comments="", fmt="%.17g")
"#,
        path.display()
    );
    run_ok(Command::new(venv_python()).args(["-c", &script]));
}

fn bag2mat(path: &Path, flags: &[&str]) -> (bool, String) {
    let out = path.with_extension("out.csv");
    let (ok, _, err) = run(Command::new(env!("CARGO_BIN_EXE_bag2mat"))
        .arg(path)
        .args(flags)
        .args(["-q", "-o"])
        .arg(&out));
    (ok, err)
}

#[test]
fn an_accelerometer_in_g_read_as_m_s2_is_refused_naming_acc_unit() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("in_g.csv");
    numpy_csv(&p, "t,gx,gy,gz,ax,ay,az", 1.0, 0.0, 1.0, 1.0 / 9.80665);
    // before: accepted, every acc figure 9.81× small
    let (ok, err) = bag2mat(&p, &["--time-unit", "s", "--acc-unit", "m/s^2"]);
    assert!(!ok, "{err}");
    assert!(
        err.contains("median magnitude of 1.0") && err.contains("give --acc-unit g"),
        "{err}"
    );
    // and m/s² data read as g
    let p = dir.path().join("in_ms2.csv");
    numpy_csv(&p, "t,gx,gy,gz,ax,ay,az", 1.0, 0.0, 1.0, 1.0);
    let (ok, err) = bag2mat(&p, &["--time-unit", "s", "--acc-unit", "g"]);
    assert!(!ok && err.contains("give --acc-unit m/s^2"), "{err}");
    assert!(bag2mat(&p, &["--time-unit", "s", "--acc-unit", "m/s^2"]).0);
}

#[test]
fn stamps_in_seconds_read_as_ms_are_refused_naming_time_unit() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("secs.csv");
    numpy_csv(&p, "t,gx,gy,gz,ax,ay,az", 1.0, 1.7e9, 1.0, 1.0);
    // before: a "200 kHz" IMU, update_rate 200000 in every yaml
    let (ok, err) = bag2mat(&p, &["--time-unit", "ms"]);
    assert!(!ok, "{err}");
    assert!(
        err.contains("outside what IMUs have") && err.contains("give --time-unit s"),
        "{err}"
    );
}

#[test]
fn a_seconds_header_over_milliseconds_is_refused_and_the_flag_overrides_it() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("ms.csv");
    numpy_csv(&p, "time [s],gx,gy,gz,ax,ay,az", 1000.0, 0.0, 1.0, 1.0);
    // before: a 0.2 Hz IMU, N 31.6× too large
    let (ok, err) = bag2mat(&p, &[]);
    assert!(!ok, "{err}");
    assert!(
        err.contains("0.2000 Hz") && err.contains("give --time-unit ms (it overrides the header)"),
        "{err}"
    );
    let (ok, err) = bag2mat(&p, &["--time-unit", "ms"]);
    assert!(ok, "{err}");
    assert!(
        err.contains("warning: the header says the time is in s, --time-unit says ms"),
        "{err}"
    );
}

#[test]
fn degrees_per_second_with_no_unit_are_refused_naming_gyro_unit() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("deg.csv");
    numpy_csv(
        &p,
        "t,gx,gy,gz,ax,ay,az",
        1.0,
        0.0,
        180.0 / std::f64::consts::PI,
        1.0,
    );
    // before: "SI assumed", every yaml 57× too large
    let (ok, err) = bag2mat(&p, &["--time-unit", "s"]);
    assert!(!ok, "{err}");
    assert!(err.contains("give --gyro-unit deg/s"), "{err}");
    assert!(bag2mat(&p, &["--time-unit", "s", "--gyro-unit", "deg/s"]).0);
}

#[test]
fn the_record_check_says_units_the_physics_contradicts_in_any_input() {
    // a bag whose driver publishes g: no flag to give, a warning on every tool's stderr
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("in_g.csv");
    numpy_csv(&p, "t,gx,gy,gz,ax,ay,az", 1.0, 0.0, 1.0, 1.0 / 9.80665);
    let npy = dir.path().join("in_g.npy");
    // the scale given as raw counts (1 LSB per m/s^2) passes the reader: the check sees g
    let (ok, _, err) = run(Command::new(env!("CARGO_BIN_EXE_bag2mat"))
        .arg(&p)
        .args([
            "--time-unit",
            "s",
            "--acc-unit",
            "m/s^2",
            "--acc-scale",
            "1",
            "-q",
            "-o",
        ])
        .arg(&npy));
    assert!(ok, "{err}");
    let info = bag2mat::info(&npy, true).unwrap();
    let f: Vec<_> = info.topics[0]
        .findings
        .iter()
        .filter(|f| f.kind == bag2mat::FindingKind::Units)
        .collect();
    assert!(
        f.len() == 1 && f[0].text.contains("the values are in g, not m/s^2"),
        "{f:?}"
    );
}
