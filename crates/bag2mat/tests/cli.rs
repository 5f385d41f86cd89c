//! The `bag2mat` binary as a user runs it.

use std::process::Command;

use bag2mat::Compression;

use crate::common::{case_bag, run, synthetic, write_synthetic};

fn bag2mat() -> Command {
    Command::new(env!("CARGO_BIN_EXE_bag2mat"))
}

#[test]
fn default_output_goes_beside_the_bag() {
    let dir = tempfile::tempdir().unwrap();
    let bag = dir.path().join("rec.2024.bag");
    std::fs::copy(case_bag("p3_short_61s"), &bag).unwrap();
    let (ok, _, err) = run(bag2mat().arg(&bag).arg("imu"));
    assert!(ok, "{err}");
    assert!(
        err.contains("BAG Path is:") && err.contains("Done processing IMU data"),
        "{err}"
    );
    let d = bag2mat::read_data_imu(&dir.path().join("rec.2024.mat")).unwrap();
    assert_eq!(d.rows(), 12200);
}

#[test]
fn missing_topic_fails_lists_topics_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let bag = dir.path().join("two.bag");
    write_synthetic(&bag, "/imu0", 300, Compression::Bz2, true);
    let (ok, _, err) = run(bag2mat().arg(&bag).arg("/camera"));
    assert!(!ok);
    assert!(
        err.contains("no sensor_msgs/Imu topic '/camera'")
            && err.contains("/imu0")
            && err.contains("/status"),
        "{err}"
    );
    let left: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(left.len(), 1, "only the bag remains: {left:?}");
}

#[test]
fn slash_fallback_is_said_on_stderr() {
    let dir = tempfile::tempdir().unwrap();
    let (ok, _, err) = run(bag2mat()
        .arg(case_bag("p1_high_200hz"))
        .arg("/imu")
        .arg("--format")
        .arg("csv")
        .arg("-o")
        .arg(dir.path().join("x.csv")));
    assert!(ok, "{err}");
    assert!(err.contains("using 'imu'"), "{err}");
    let text = std::fs::read_to_string(dir.path().join("x.csv")).unwrap();
    assert_eq!(text.lines().count(), 180_001);
    assert!(
        text.starts_with("t,ax,ay,az,wx,wy,wz\n1600000000,"),
        "{}",
        &text[..60]
    );
}

#[test]
fn bad_inputs_fail_cleanly() {
    let dir = tempfile::tempdir().unwrap();
    let junk = dir.path().join("junk.bag");
    std::fs::write(&junk, b"not a bag at all").unwrap();
    for (args, needle) in [
        (
            vec![
                dir.path().join("missing.bag").display().to_string(),
                "imu".into(),
            ],
            "no such file",
        ),
        (
            vec![junk.display().to_string(), "imu".into()],
            "not a bag this tool reads",
        ),
        (
            vec![dir.path().display().to_string(), "imu".into()],
            "error",
        ),
    ] {
        let (ok, _, err) = run(bag2mat().args(&args).arg("-q"));
        assert!(!ok, "{args:?} should fail");
        assert!(
            err.contains(needle) && !err.contains("panicked"),
            "{args:?}: {err}"
        );
    }
    let (ok, _, err) = run(bag2mat()
        .arg(case_bag("p3_short_61s"))
        .arg("imu")
        .arg("-o")
        .arg("/nonexistent-dir/x.mat")
        .arg("-q"));
    assert!(
        !ok && err.contains("/nonexistent-dir") && !err.contains("panicked"),
        "{err}"
    );
}

/// A standard output that fails (a full disk: /dev/full) is an error in the one convention,
/// exit 1, never a panic (`bag2mat info` panicked "failed printing to stdout").
#[test]
fn a_failing_standard_output_is_an_error_not_a_panic() {
    let dir = tempfile::tempdir().unwrap();
    let bag = dir.path().join("s.bag");
    write_synthetic(&bag, "imu", 300, Compression::None, false);
    for args in [vec!["info"], vec![]] {
        let full = std::fs::OpenOptions::new()
            .write(true)
            .open("/dev/full")
            .expect("/dev/full");
        let mut cmd = bag2mat();
        cmd.args(&args).arg(&bag);
        if args.is_empty() {
            cmd.args(["imu", "-o", "-", "--format", "csv", "-q"]);
        }
        let o = cmd.stdout(full).output().unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{args:?}: {err}");
        assert!(
            err.contains("bag2mat: error: standard output:"),
            "{args:?}: {err}"
        );
        assert!(!err.contains("panicked"), "{args:?}: {err}");
    }
}

#[test]
fn the_only_imu_topic_is_the_default_and_several_must_be_named() {
    // a newcomer's first run: `bag2mat BAG -o x.mat` on a bag with one Imu topic (and a
    // status topic) reads that topic and says so; with two, which is the user's to say
    let dir = tempfile::tempdir().unwrap();
    let bag = dir.path().join("one.bag");
    write_synthetic(&bag, "/imu0", 300, Compression::None, true);
    let mat = dir.path().join("one.mat");
    let (ok, _, err) = run(bag2mat().arg(&bag).arg("-o").arg(&mat));
    assert!(ok, "{err}");
    assert!(
        err.contains("no topic named: reading '/imu0', the only sensor_msgs/Imu topic"),
        "{err}"
    );
    assert_eq!(bag2mat::read_data_imu(&mat).unwrap().rows(), 300);
    let two = dir.path().join("two.bag");
    {
        let mut w = bag2mat::BagWriter::create(
            &bag2mat::shared::output::Outputs::direct(),
            &two,
            Compression::None,
        )
        .unwrap();
        let a = w.add_imu_connection("/imu0");
        let b = w.add_imu_connection("/imu1");
        for i in 0..10 {
            let (t, m) = synthetic(i);
            w.write_imu(a, t, &m).unwrap();
            w.write_imu(b, t, &m).unwrap();
        }
        w.finish().unwrap();
    }
    let out = dir.path().join("two.mat");
    let (ok, _, err) = run(bag2mat().arg(&two).arg("-o").arg(&out));
    assert!(!ok);
    assert!(
        err.contains("several carry sensor_msgs/Imu")
            && err.contains("--all-imu-topics")
            && err.contains("/imu0")
            && err.contains("/imu1"),
        "{err}"
    );
    assert!(!out.exists());
}

/// `--help` (for the conversion and for `info`) names every kind of input the registry
/// holds: the list comes from [`bag2mat::InputKind::ALL`], not a hand-written copy.
#[test]
fn help_lists_every_input_kind() {
    for args in [&["--help"][..], &["info", "--help"][..]] {
        let out = bag2mat().args(args).output().unwrap();
        assert!(out.status.success());
        bag2mat::test_tools::assert_help_lists_every_input(&out.stdout, &[]);
    }
}
