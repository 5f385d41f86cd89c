//! `allan_imu_utils --curves` as a user runs it: on an imu_utils data directory it re-runs
//! imu_utils' own fit (the yaml files imu_utils wrote for those curves come back) and the
//! IEEE 952 section; other formats get the section alone; bad input is a clear error.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use crate::common::testdata;

/// Issue 10: imu_utils' yaml reproduced within this (relative) from its own curves. The
/// curves hold imu_utils' printed precision (6 significant digits), so the fit differs from
/// the run that wrote them in the 7th digit: measured ≤ 6e-7.
const YAML_REL_TOL: f64 = 1e-3;

fn run(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_allan_imu_utils"))
        .args(args)
        .output()
        .expect("run allan_imu_utils")
}

fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

/// Every number of a yaml file, in order, with the section path (`Gyr/x-axis/gyr_n`).
fn yaml_numbers(path: &Path) -> Vec<(String, f64)> {
    let body = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    bag2mat::test_tools::yaml_numbers(&body)
}

fn real(name: &str) -> PathBuf {
    testdata().join("real_curves").join(name)
}

#[test]
fn curves_dir_reproduces_bmi160_yaml_and_adds_the_ieee952_section() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let src = real("BMI160");
    let o = run(&[
        "--curves",
        src.to_str().unwrap(),
        "--name",
        "BMI160",
        "--data-save-path",
        out.to_str().unwrap(),
        "-q",
    ]);
    assert!(o.status.success(), "stderr: {}", text(&o.stderr));
    let stdout = text(&o.stdout);
    // imu_utils' report, then the section, which says how it got the sample count
    assert!(stdout.contains("Gyro X"), "{stdout}");
    assert!(stdout.contains("=> IEEE 952 noise terms"), "{stdout}");
    assert!(stdout.contains("sample count not given"), "{stdout}");
    let want = yaml_numbers(&src.join("BMI160_imu_param.yaml"));
    let got = yaml_numbers(&out.join("BMI160_imu_param.yaml"));
    assert_eq!(want.len(), 16, "{want:?}");
    assert_eq!(
        want.iter().map(|w| &w.0).collect::<Vec<_>>(),
        got.iter().map(|g| &g.0).collect::<Vec<_>>()
    );
    for ((k, w), (_, g)) in want.iter().zip(&got) {
        assert!(
            ((g - w) / w).abs() <= YAML_REL_TOL,
            "{k}: {g:e} vs imu_utils' {w:e}"
        );
    }
    for f in [
        "BMI160_imu_param_continuous.yaml",
        "BMI160_ieee952_terms.csv",
        "BMI160_ieee952_curves.csv",
        "BMI160_kalibr_imu_ieee952.yaml",
        "BMI160_vins_imu_ieee952.yaml",
        "BMI160_orbslam3_imu_ieee952.yaml",
        "BMI160_ieee952_allan.png",
        "BMI160_ieee952_allan.svg",
    ] {
        assert!(out.join(f).is_file(), "{f} missing");
    }
}

#[test]
fn curves_of_an_unknown_format_is_a_clear_error() {
    let dir = tempfile::tempdir().unwrap();
    let f = dir.path().join("notes.txt");
    std::fs::write(&f, "hello\nworld\n").unwrap();
    let out = dir.path().join("out");
    let o = run(&[
        "--curves",
        f.to_str().unwrap(),
        "--data-save-path",
        out.to_str().unwrap(),
    ]);
    assert!(!o.status.success());
    let err = text(&o.stderr);
    for fmt in [
        "imu_utils",
        "allan_variance",
        "allan_curves.csv",
        "ieee952_curves.csv",
        "tau,x,y,z",
    ] {
        assert!(err.contains(fmt), "the error must list {fmt}: {err}");
    }
    assert!(!err.contains("panicked"), "{err}");
    assert!(
        !out.exists() || std::fs::read_dir(&out).unwrap().next().is_none(),
        "no outputs on error"
    );
}

/// `allan_imu_utils … | head`: a reader that closed the pipe is not an error (it printed
/// "standard output: Broken pipe (os error 32)" and exited 1).
#[test]
fn stdout_closed_by_the_reader_is_not_an_error() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let src = real("BMI160");
    let mut child = Command::new(env!("CARGO_BIN_EXE_allan_imu_utils"))
        .args(["--curves", src.to_str().unwrap(), "--name", "BMI160", "-q"])
        .arg("--data-save-path")
        .arg(&out)
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("run allan_imu_utils");
    // The reader goes away before a byte is written.
    drop(child.stdout.take());
    let o = child.wait_with_output().unwrap();
    let err = text(&o.stderr);
    assert!(o.status.success(), "exit {:?}: {err}", o.status);
    assert!(!err.contains("error"), "{err}");
}
