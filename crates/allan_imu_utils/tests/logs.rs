//! Issue 20's round trip for imu_utils' analysis: a reference bag → `bag2mat -o x.csv
//! --time header` (imu_utils reads header stamps) → an EuRoC/ASL dataset → the same
//! imu_utils parameters and IEEE 952 terms as from the bag.

use clap::Parser;

use crate::common::CASES;

#[test]
fn bag_to_csv_to_euroc_gives_the_bags_parameters() {
    let case = &CASES[2];
    let dir = tempfile::tempdir().unwrap();
    let root = bag2mat::test_tools::euroc_dataset_from_bag(
        &case.bag(),
        case.topic,
        bag2mat::TimeColumn::Header,
        dir.path(),
    );
    let analyse = |input: &std::path::Path, topic: &str, out: &str| {
        let out = dir.path().join(out);
        let args = allan_imu_utils::Args::try_parse_from([
            "allan_imu_utils",
            input.to_str().unwrap(),
            "--topic",
            topic,
            "--name",
            "p3",
            "-q",
            "--no-plots",
            "--data-save-path",
            out.to_str().unwrap(),
        ])
        .unwrap();
        allan_imu_utils::run(
            &args.try_into().unwrap(),
            &bag2mat::shared::output::Outputs::direct(),
        )
        .unwrap();
        // the files name their input and the time they were written: the rest must agree
        let read = |f: &str| {
            std::fs::read_to_string(out.join(f))
                .unwrap()
                .lines()
                .filter(|l| !l.contains("Written by"))
                .map(|l| format!("{l}\n"))
                .collect::<String>()
        };
        (
            read("p3_imu_param.yaml"),
            read("p3_ieee952_terms.csv"),
            read("p3_openvins_kalibr_imu_chain_ieee952.yaml"),
        )
    };
    let from_bag = analyse(&case.bag(), case.topic, "bag");
    let from_euroc = analyse(&root, "imu0", "euroc");
    assert_eq!(from_bag.0, from_euroc.0, "imu_utils' yaml");
    assert_eq!(from_bag.1, from_euroc.1, "IEEE 952 terms");
    let no_topic = |s: &str| {
        s.lines()
            .filter(|l| !l.contains("rostopic"))
            .collect::<Vec<_>>()
            .join("\n")
    };
    assert_eq!(
        no_topic(&from_bag.2),
        no_topic(&from_euroc.2),
        "OpenVINS file"
    );
}

/// Issue 20: a one-sensor topic (PX4 `sensor_gyro:0`, `sensor_accel:1`) of a ULog pyulog's
/// writer laid out is analysed from the command line: the sensor present gets exactly the
/// files and yaml block the same samples get in a layout with both sensors (a EuRoC pairing
/// of the two topics); the absent sensor's files, block and lines are left out.
#[test]
fn one_sensor_ulog_topics_are_analysed_and_the_absent_sensor_left_out() {
    let dir = tempfile::tempdir().unwrap();
    let log = bag2mat::test_tools::pyulog_imu_log(dir.path(), 600.0, 100.0);
    let run = |input: &std::path::Path, topic: &str, out: &std::path::Path| {
        let o = std::process::Command::new(env!("CARGO_BIN_EXE_allan_imu_utils"))
            .arg(input)
            .args(["--topic", topic, "--max-time-min", "9", "--data-save-path"])
            .arg(out)
            .output()
            .unwrap();
        let (stdout, stderr) = (
            String::from_utf8_lossy(&o.stdout).into_owned(),
            String::from_utf8_lossy(&o.stderr).into_owned(),
        );
        assert!(o.status.success(), "{topic}: {stdout}{stderr}");
        (stdout, stderr)
    };
    // the yaml from the line of `block` (`Gyr:`/`Acc:`) to the next top-level key
    let block = |d: &std::path::Path, f: &str, block: &str| -> String {
        let text = std::fs::read_to_string(d.join(f)).unwrap();
        let mut out = String::new();
        let mut inside = false;
        for l in text.lines() {
            if !l.starts_with(' ') {
                inside = l.starts_with(block);
            }
            if inside {
                out.push_str(l);
                out.push('\n');
            }
        }
        out
    };
    for (gyro, acc, topic, present, absent) in [
        (
            "sensor_gyro:0",
            "sensor_accel:0",
            "sensor_gyro:0",
            ("gyr", "Gyr"),
            ("acc", "Acc"),
        ),
        (
            "sensor_gyro:1",
            "sensor_accel:1",
            "sensor_accel:1",
            ("acc", "Acc"),
            ("gyr", "Gyr"),
        ),
    ] {
        let tag = topic.replace(':', "_");
        let (one, both) = (
            dir.path().join(format!("one_{tag}")),
            dir.path().join(format!("both_{tag}")),
        );
        let (stdout, stderr) = run(&log, topic, &one);
        let root = bag2mat::test_tools::euroc_pairing(&log, gyro, acc, &dir.path().join(&tag));
        let _ = run(&root, "imu0", &both);
        let absent_name = if absent.0 == "gyr" {
            "gyroscope"
        } else {
            "accelerometer"
        };
        assert!(
            stdout.contains(&format!("{absent_name}: absent from this topic")),
            "{stdout}"
        );
        assert!(
            stderr.contains(&format!("the topic carries no {absent_name}")),
            "{stderr}"
        );
        for f in ["imu_imu_param.yaml", "imu_imu_param_continuous.yaml"] {
            let b = block(&one, f, present.1);
            assert!(b.len() > 20, "{f}: {b}");
            assert_eq!(b, block(&both, f, present.1), "{topic} {f}");
            assert_eq!(block(&one, f, absent.1), "", "{topic} {f}");
        }
        for axis in ["t", "x", "y", "z"] {
            for sim in ["", "sim_"] {
                let f = format!("data_imu_{sim}{}_{axis}.txt", present.0);
                let text = std::fs::read_to_string(one.join(&f)).unwrap();
                assert_eq!(text, std::fs::read_to_string(both.join(&f)).unwrap(), "{f}");
                assert!(
                    !one.join(format!("data_imu_{sim}{}_{axis}.txt", absent.0))
                        .exists()
                );
            }
        }
        assert!(!one.join(format!("allan_{}.png", absent.0)).exists());
        assert!(one.join(format!("allan_{}.png", present.0)).exists());
    }
}
