//! Issue 21's front door for allan_imu_utils: the shared flags' one spelling (imu_utils'
//! `data_save_path` as an alias), results in a folder of their own (not the current
//! directory), and a flag that would do nothing is an error.

use std::path::Path;
use std::process::{Command, Output};

use clap::Parser;

fn run(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_allan_imu_utils"))
        .current_dir(dir)
        .args(args)
        .output()
        .expect("allan_imu_utils runs")
}

#[test]
fn one_spelling_with_upstream_aliases() {
    for s in ["-o", "--out-dir", "--data-save-path", "--outdir"] {
        let a = allan_imu_utils::Args::try_parse_from(["allan_imu_utils", "x.bag", s, "o"])
            .expect("parses");
        let c = allan_imu_utils::Config::try_from(a).expect("resolves");
        assert_eq!(c.common.out_dir, Path::new("o"), "{s}");
    }
}

#[test]
fn results_go_to_a_folder_of_their_own_and_rate_with_a_bag_is_an_error() {
    let dir = tempfile::tempdir().unwrap();
    let bag = dir.path().join("rec.bag");
    let src = crate::common::testdata().join("p3_short_61s/p3_short_61s.bag");
    bag2mat::test_tools::retopic(&src, "imu", &bag, &["/camera/imu"]);
    let o = run(dir.path(), &["rec.bag", "--compat-only", "--no-plots"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(
        err.contains("reading '/camera/imu', the only sensor_msgs/Imu topic"),
        "{err}"
    );
    let names: Vec<String> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(names.len(), 2, "the current folder holds {names:?}");
    assert!(
        dir.path()
            .join("rec_allan_imu_utils/imu_imu_param.yaml")
            .is_file()
    );

    // --rate with a bag used to be accepted and ignored
    let o = run(dir.path(), &["rec.bag", "--rate", "100", "-o", "x"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("--rate 100 does nothing for a ROS 1 bag"),
        "{err}"
    );
    assert!(!dir.path().join("x").exists());
}
