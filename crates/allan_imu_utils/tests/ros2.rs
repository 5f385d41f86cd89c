//! Both analysers on ROS 2 bags: `rosbags-convert` turns the reference bags p2 (two
//! topics) and p3 into sqlite3 and MCAP bags (uncompressed and zstd), and every output —
//! imu_utils' printed report and yaml, kalibr_allan's printed results and imu.yaml — equals
//! the run on the ROS 1 bag.

use std::path::Path;

use allan_imu_utils::Config;
use bag2mat::test_tools::{ROS2_MODES, rosbags_convert};

use crate::common::{CASES, imu_utils_config, kalibr_config};

fn imu_utils(bag: &Path, topic: &str, out: &Path) -> (String, String) {
    let mut c: Config = imu_utils_config(bag, topic, out);
    c.common.ieee952 = false;
    let o = allan_imu_utils::run(&c, &bag2mat::shared::output::Outputs::direct())
        .unwrap_or_else(|e| panic!("{}: {e}", bag.display()))
        .remove(0);
    let yaml = std::fs::read_to_string(out.join("x_imu_param.yaml")).unwrap();
    (
        o.section.text + o.section.ieee952_text.as_deref().unwrap_or(""),
        yaml,
    )
}

fn kalibr(bag: &Path, topic: &str, out: &Path) -> (String, String) {
    let mut c = kalibr_config(bag, topic, out);
    c.common.ieee952 = false;
    let o = allan_kalibr::run(&c, &bag2mat::shared::output::Outputs::direct())
        .unwrap_or_else(|e| panic!("{}: {e}", bag.display()))
        .remove(0);
    let yaml = std::fs::read_to_string(out.join("imu.yaml")).unwrap();
    // imu.yaml names its source file; the rest must be identical.
    let yaml: String = yaml.lines().filter(|l| !l.starts_with('#')).collect();
    (
        o.section.text + o.section.ieee952_text.as_deref().unwrap_or(""),
        yaml,
    )
}

#[test]
fn both_analysers_give_the_same_results_on_ros2_bags() {
    let dir = tempfile::tempdir().unwrap();
    for case in [&CASES[1], &CASES[2]] {
        let ros1 = case.bag();
        let want_iu = imu_utils(&ros1, case.topic, &dir.path().join("iu_ros1"));
        let want_k = kalibr(&ros1, case.topic, &dir.path().join("k_ros1"));
        for (mode, args) in [ROS2_MODES[0], ROS2_MODES[1], ROS2_MODES[3], ROS2_MODES[6]] {
            let dst = dir.path().join(format!("{}_{mode}", case.dir));
            rosbags_convert(&[&ros1], &dst, args);
            let got_iu = imu_utils(&dst, case.topic, &dir.path().join(format!("iu_{mode}")));
            assert_eq!(got_iu, want_iu, "{} {mode}: allan_imu_utils", case.dir);
            let got_k = kalibr(&dst, case.topic, &dir.path().join(format!("k_{mode}")));
            assert_eq!(got_k, want_k, "{} {mode}: allan_kalibr", case.dir);
        }
    }
}
