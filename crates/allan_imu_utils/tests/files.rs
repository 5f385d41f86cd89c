//! This project's own files from allan_imu_utils, as a user gets them: no
//! `<name>_imu_param_continuous.yaml` from a record that is not static (its numbers would be
//! the motion's), and a reused `data_save_path` keeps only the last run's files of that IMU
//! name (another name's are another IMU's, kept).

use std::path::Path;
use std::process::{Command, Output};

use bag2mat::test_tools::{OddWriter, odd_record, warnings};

fn imu_utils(bag: &Path, name: &str, out: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_allan_imu_utils"))
        .arg(bag)
        .args(["--topic", "imu", "--name", name, "-q", "--no-plots"])
        .arg("--data-save-path")
        .arg(out)
        .output()
        .expect("run allan_imu_utils")
}

fn ok(o: &Output) -> String {
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    String::from_utf8_lossy(&o.stderr).into_owned()
}

#[test]
fn a_moving_record_gets_no_continuous_yaml_and_the_folder_keeps_only_its_own_files() {
    let tmp = tempfile::tempdir().unwrap();
    let (still, hand) = (tmp.path().join("still.bag"), tmp.path().join("hand.bag"));
    odd_record(OddWriter::Rosbag, &still, "clean", 120.0, 100.0);
    odd_record(OddWriter::Rosbag, &hand, "handheld", 600.0, 100.0);
    let out = tmp.path().join("data");
    ok(&imu_utils(&still, "x", &out));
    ok(&imu_utils(&still, "other", &out));
    assert!(out.join("x_imu_param_continuous.yaml").exists());
    assert!(out.join("x_kalibr_imu_ieee952.yaml").exists());
    let cont = std::fs::read_to_string(out.join("x_imu_param_continuous.yaml")).unwrap();
    assert!(
        cont.contains(&format!("allan_imu_utils {}", env!("CARGO_PKG_VERSION")))
            && cont.contains(still.to_str().unwrap()),
        "{cont}"
    );

    // OpenCV (VINS-style loaders) reads it, the comments included, with its numbers
    let cv = Command::new("/usr/bin/python3")
        .arg("-c")
        .arg(format!(
            "import cv2; fs = cv2.FileStorage('{}', cv2.FILE_STORAGE_READ); print(' '.join(repr(fs.getNode(s).getNode('avg-axis').getNode(k).real()) for s, k in [('Gyr', 'gyr_n'), ('Gyr', 'gyr_w'), ('Acc', 'acc_n'), ('Acc', 'acc_w')]), repr(fs.getNode('update_rate').real()))",
            out.join("x_imu_param_continuous.yaml").display()
        ))
        .output()
        .expect("python3 with OpenCV (scripts/test.sh installs it)");
    assert!(
        cv.status.success(),
        "{}",
        String::from_utf8_lossy(&cv.stderr)
    );
    let got: Vec<f64> = String::from_utf8_lossy(&cv.stdout)
        .split_whitespace()
        .map(|x| x.parse().unwrap())
        .collect();
    let want: Vec<f64> = [
        "Gyr/avg-axis/gyr_n",
        "Gyr/avg-axis/gyr_w",
        "Acc/avg-axis/acc_n",
        "Acc/avg-axis/acc_w",
        "update_rate",
    ]
    .iter()
    .map(|k| bag2mat::test_tools::yaml_number(&cont, k))
    .collect();
    assert_eq!(got, want, "{cont}");
    assert_eq!(got[4], 100.0);

    let err = ok(&imu_utils(&hand, "x", &out));
    // before: written from the hand-held record with no word of motion, and the still
    // record's section files stayed beside it
    assert!(!out.join("x_imu_param_continuous.yaml").exists(), "{err}");
    let w = warnings(&err, "x_imu_param_continuous.yaml not written");
    assert!(w.len() == 1 && w[0].contains("not static"), "{err}");
    assert!(!out.join("x_kalibr_imu_ieee952.yaml").exists(), "{err}");
    assert!(
        warnings(&err, "removed ")
            .iter()
            .any(|l| l.contains("x_kalibr_imu_ieee952.yaml")
                && l.contains("x_imu_param_continuous.yaml")),
        "{err}"
    );
    // upstream's file is written as upstream would, and another IMU name's files are kept
    assert!(out.join("x_imu_param.yaml").exists());
    assert!(out.join("other_imu_param_continuous.yaml").exists());
    assert!(out.join("other_kalibr_imu_ieee952.yaml").exists());
}
