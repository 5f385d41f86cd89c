//! imu_utils' stop rule (`max_time_min`, 120 by default): the upstream-compatible part stops
//! where imu_utils would, said as a warning; this tool's own IEEE 952 section and its
//! record-length advice use the whole record; a record shorter than the limit (every
//! ordinary run) gets no warning for it.

use std::path::{Path, PathBuf};
use std::process::Command;

/// A static record of `seconds` at 10 Hz (a 2.5 h record in 90,000 messages), written by
/// Debian's python rosbag.
fn long_bag(dir: &Path, seconds: u32) -> PathBuf {
    let bag = dir.join("long.bag");
    let spec = format!(
        r#"{{"seed": 8, "topics": [{{"topic": "imu", "n": {}, "rate": 10, "gyro_n": 1e-4, "acc_n": 1e-3}}]}}"#,
        seconds * 10
    );
    bag2mat::test_tools::independent_log("ros1", &bag, &spec);
    bag
}

fn analyse(bag: &Path, out: &Path, quiet: bool) -> (String, String) {
    let mut c = Command::new(env!("CARGO_BIN_EXE_allan_imu_utils"));
    c.arg(bag).arg("-o").arg(out);
    if quiet {
        c.arg("-q");
    }
    let o = c.output().unwrap();
    let (stdout, stderr) = (
        String::from_utf8_lossy(&o.stdout).into_owned(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    );
    assert!(o.status.success(), "{stderr}");
    (stdout, stderr)
}

#[test]
fn past_max_time_min_the_section_uses_the_whole_record_and_the_cut_is_a_warning() {
    let dir = tempfile::tempdir().unwrap();
    let bag = long_bag(dir.path(), 9000);
    let (stdout, stderr) = analyse(&bag, &dir.path().join("o"), true);
    let cut: Vec<&str> = stderr
        .lines()
        .filter(|l| l.starts_with("warning: max_time_min 120"))
        .collect();
    assert_eq!(cut.len(), 1, "{stderr}");
    assert!(
        cut[0].contains("uses the first 120.0 min")
            && cut[0].contains("of this 150.0 min record")
            && cut[0].contains("--max-time-min 150 uses all of it")
            && cut[0]
                .contains("IEEE 952 section and its record-length advice use the whole record"),
        "{stderr}"
    );
    // the section's advice is for the 2.5 h record, not for the first 2 h
    assert!(
        stdout.contains("record length 2.5 h:"),
        "{}",
        &stdout[stdout.find("record length").unwrap_or(0)..]
    );
}

#[test]
fn a_record_shorter_than_max_time_min_gets_no_warning_for_it() {
    let dir = tempfile::tempdir().unwrap();
    let bag = long_bag(dir.path(), 600);
    let (_, stderr) = analyse(&bag, &dir.path().join("q"), true);
    assert!(!stderr.contains("max_time_min"), "{stderr}");
    // said as information without --quiet, in imu_utils' words
    let (_, stderr) = analyse(&bag, &dir.path().join("v"), false);
    assert!(
        stderr.lines().any(|l| l
            .starts_with("bag ended after 6000 messages before max_time_min (120) was exceeded")),
        "{stderr}"
    );
    assert!(!stderr.contains("warning: bag ended"), "{stderr}");
}
