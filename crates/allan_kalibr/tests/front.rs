//! Issue 21's front door, as a newcomer meets it: one spelling of the shared flags (upstream's
//! as aliases), results in a folder of their own, and the input's only Imu topic read when
//! none is named.

use std::path::Path;
use std::process::{Command, Output};

use clap::Parser;

fn run(args: &[&Path]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_allan_kalibr"))
        .args(args)
        .output()
        .expect("allan_kalibr runs")
}

fn config(args: &[&str]) -> allan_kalibr::Config {
    let a = allan_kalibr::Args::try_parse_from(
        std::iter::once("allan_kalibr").chain(args.iter().copied()),
    )
    .expect("parses");
    allan_kalibr::Config::try_from(a).expect("resolves")
}

#[test]
fn one_spelling_with_upstream_aliases() {
    let spellings = ["-o", "--out-dir", "--outdir"];
    for s in spellings {
        assert_eq!(
            config(&["x.bag", s, "out"]).common.out_dir,
            Path::new("out"),
            "{s}"
        );
    }
    for s in ["--rate", "--update-rate"] {
        assert_eq!(config(&["x.bag", s, "200"]).common.rate, Some(200.0), "{s}");
    }
}

#[test]
fn results_go_to_a_folder_of_their_own_and_the_only_imu_topic_is_read() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("data");
    std::fs::create_dir(&data).unwrap();
    let src = crate::common::testdata().join("p3_short_61s/p3_short_61s.bag");
    let bag = data.join("rec.bag");
    bag2mat::test_tools::retopic(&src, "imu", &bag, &["/camera/imu"]);
    let o = run(&[&bag, Path::new("--compat-only")]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(
        err.contains("reading '/camera/imu', the only sensor_msgs/Imu topic"),
        "{err}"
    );
    assert!(err.contains("wrote 6 files to "), "{err}");
    let names: Vec<String> = std::fs::read_dir(&data)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(names.len(), 2, "the data folder holds {names:?}");
    assert!(
        data.join("rec_allan_kalibr/imu.yaml").is_file(),
        "{names:?}"
    );
    let yaml = std::fs::read_to_string(data.join("rec_allan_kalibr/imu.yaml")).unwrap();
    assert!(
        yaml.lines().any(|l| l
            .split_whitespace()
            .take(2)
            .eq(["rostopic:", "/camera/imu"])),
        "{yaml}"
    );

    // Two Imu topics and none named imu: which one is the user's to say.
    let two = data.join("two.bag");
    bag2mat::test_tools::retopic(&src, "imu", &two, &["/cam0/imu", "/cam1/imu"]);
    let o = run(&[&two, Path::new("-q")]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("several carry sensor_msgs/Imu")
            && err.contains("/cam0/imu")
            && err.contains("/cam1/imu"),
        "{err}"
    );
    assert!(!data.join("two_allan_kalibr").exists());
}
