//! Byte-for-byte parity with the real vio_data_simulation master (fixtures/upstream_master,
//! see its README): `sim traj --compat` reproduces every clean file, and `sim integrate
//! --compat` reproduces `testImu`'s output on upstream's own input files (clean and noisy).

use crate::util::ok;
use std::io::Read;
use std::path::{Path, PathBuf};

fn fixtures() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/upstream_master")
}

fn gunzip(name: &str) -> String {
    let f = std::fs::File::open(fixtures().join(format!("{name}.gz")))
        .unwrap_or_else(|e| panic!("fixture {name}: {e}"));
    let mut s = String::new();
    flate2::read::GzDecoder::new(f)
        .read_to_string(&mut s)
        .unwrap();
    s
}

/// Compare two texts line by line; report the first differing line.
fn same_text(case: &str, expected: &str, actual: &str) {
    let (e, a): (Vec<&str>, Vec<&str>) =
        (expected.split('\n').collect(), actual.split('\n').collect());
    for (i, (x, y)) in e.iter().zip(&a).enumerate() {
        assert_eq!(
            x,
            y,
            "{case}: line {} differs (expected upstream, actual ours)",
            i + 1
        );
    }
    assert_eq!(e.len(), a.len(), "{case}: line count");
}

#[test]
fn traj_compat_matches_upstream_byte_for_byte() {
    let d = tempfile::tempdir().unwrap();
    ok(d.path(), &["traj", "--compat", "-o", "."]);
    for name in ["imu_pose.txt", "cam_pose_tum.txt", "all_points.txt"] {
        same_text(
            name,
            &gunzip(name),
            &std::fs::read_to_string(d.path().join(name)).unwrap(),
        );
    }
    // cam_pose.txt: columns 9–14 are uninitialised memory upstream; we write 0.
    let cols = |s: &str| -> String {
        s.lines()
            .map(|l| l.split(' ').take(8).collect::<Vec<_>>().join(" ") + "\n")
            .collect()
    };
    same_text(
        "cam_pose.txt columns 1-8",
        &cols(&gunzip("cam_pose.txt")),
        &cols(&std::fs::read_to_string(d.path().join("cam_pose.txt")).unwrap()),
    );
    // All 1200 keyframe files.
    let kf = gunzip("keyframe.txt");
    let mut count = 0;
    for block in kf.split("### ").skip(1) {
        let (name, content) = block.split_once('\n').unwrap();
        let ours =
            std::fs::read_to_string(d.path().join(name)).unwrap_or_else(|e| panic!("{name}: {e}"));
        same_text(name, content, &ours);
        count += 1;
    }
    assert_eq!(count, 1200);
}

#[test]
fn default_traj_differs_from_upstream_only_by_the_float_constants() {
    // Spec §8 item 2: with exact f64 constants 2843 of the 4001 imu_pose.txt lines differ in
    // some printed digit.
    let d = tempfile::tempdir().unwrap();
    ok(d.path(), &["traj", "-o", "."]);
    let up = gunzip("imu_pose.txt");
    let ours = std::fs::read_to_string(d.path().join("imu_pose.txt")).unwrap();
    let differing = up.lines().zip(ours.lines()).filter(|(a, b)| a != b).count();
    assert_eq!(differing, 2843);
}

#[test]
fn integrate_compat_matches_upstream_test_imu() {
    let d = tempfile::tempdir().unwrap();
    for name in ["imu_pose.txt", "imu_pose_noise.txt"] {
        std::fs::write(d.path().join(name), gunzip(name)).unwrap();
    }
    ok(
        d.path(),
        &[
            "integrate",
            "--compat",
            "--input",
            "imu_pose.txt",
            "--method",
            "euler",
            "--no-plot",
            "-o",
            "out",
        ],
    );
    for name in ["imu_int_pose.txt", "imu_int_pose_noise.txt"] {
        same_text(
            name,
            &gunzip(name),
            &std::fs::read_to_string(d.path().join("out").join(name)).unwrap(),
        );
    }
}
