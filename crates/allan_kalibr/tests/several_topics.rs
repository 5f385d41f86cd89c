//! Several topics in one run (`--all-imu-topics`, `--topic` repeated): a topic that cannot be
//! analysed is an error for that topic alone, said once; the other topics are analysed and
//! written; the exit status is 1 — the rule allan_imu_utils follows too.

use std::process::Command;

#[test]
fn a_topic_too_short_fails_alone_and_the_other_topics_are_written() {
    let dir = tempfile::tempdir().unwrap();
    // 2 messages: no Allan variance at all
    let bag = bag2mat::test_tools::several_topics_bag(dir.path(), 2);
    let out = dir.path().join("out");
    let o = Command::new(env!("CARGO_BIN_EXE_allan_kalibr"))
        .arg(&bag)
        .args(["--all-imu-topics", "-q", "-o"])
        .arg(&out)
        .output()
        .unwrap();
    let (stdout, stderr) = (
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr),
    );
    assert_eq!(o.status.code(), Some(1), "{stderr}");
    let errors: Vec<&str> = stderr
        .lines()
        .filter(|l| l.starts_with("allan_kalibr: error:"))
        .collect();
    assert_eq!(errors.len(), 1, "{stderr}");
    assert!(
        errors[0].starts_with("allan_kalibr: error: topic '/short':"),
        "{stderr}"
    );
    for t in ["imu0", "imu1"] {
        assert!(
            out.join(t).join("imu.yaml").is_file(),
            "{t} not written:\n{stderr}"
        );
        assert!(
            stdout.contains(&format!("===== topic /{t} =====")),
            "{stdout}"
        );
    }
    assert!(!out.join("short").exists());
}
