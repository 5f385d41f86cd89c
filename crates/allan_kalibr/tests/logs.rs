//! Issue 20's round trip: `sim bag` → `bag2mat -o x.csv` → an EuRoC/ASL dataset → the
//! analysis gives the same terms as from the bag (the CSV keeps every double's digits; the
//! stamps come back in ns).

use clap::Parser;

/// The numeric lines of a yaml (comments and the topic line, which names the input, left out).
fn values(yaml: &str) -> Vec<String> {
    yaml.lines()
        .filter(|l| !l.trim_start().starts_with('#') && !l.starts_with("rostopic"))
        .map(str::to_string)
        .collect()
}

#[test]
fn sim_bag_to_csv_to_euroc_gives_the_bags_terms() {
    let dir = tempfile::tempdir().unwrap();
    let bag = dir.path().join("sim.bag");
    crate::common::sim_bag(&[
        "-o",
        bag.to_str().unwrap(),
        "--duration",
        "600",
        "--rate",
        "100",
        "--start-time",
        "1700000000.25",
        "--seed",
        "20",
        "-q",
    ]);
    let root = bag2mat::test_tools::euroc_dataset_from_bag(
        &bag,
        "imu",
        bag2mat::TimeColumn::Record,
        dir.path(),
    );
    let analyse = |input: &std::path::Path, topic: &str, out: &str| {
        let out = dir.path().join(out);
        let args = allan_kalibr::Args::try_parse_from([
            "allan_kalibr",
            input.to_str().unwrap(),
            "--topic",
            topic,
            "-q",
            "-o",
            out.to_str().unwrap(),
        ])
        .unwrap();
        let run = allan_kalibr::run(
            &args.try_into().unwrap(),
            &bag2mat::shared::output::Outputs::direct(),
        )
        .unwrap()
        .remove(0);
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
            read("ieee952_terms.csv"),
            values(&read("imu.yaml")),
            read("basalt_imu_noise_ieee952.json"),
            run.section.ieee952_text.unwrap_or_default(),
        )
    };
    let from_bag = analyse(&bag, "imu", "bag");
    // the dataset states its own figures: printed beside ours
    std::fs::write(
        root.join("mav0/imu0/sensor.yaml"),
        "sensor_type: imu\nrate_hz: 100\ngyroscope_noise_density: 1.6968e-04\n",
    )
    .unwrap();
    let from_euroc = analyse(&root, "imu0", "euroc");
    assert!(!from_bag.3.contains("sensor.yaml"));
    let stated = &from_euroc.3[from_euroc
        .3
        .find("=> the dataset's sensor.yaml for 'imu0'")
        .unwrap()..];
    assert!(
        stated.contains("gyroscope_noise_density      1.6968e-4")
            && stated.contains("rate_hz                      100")
            && !stated.contains("accelerometer"),
        "{stated}"
    );
    assert_eq!(from_bag.0, from_euroc.0, "IEEE 952 terms");
    assert_eq!(from_bag.1, from_euroc.1, "kalibr_allan's imu.yaml values");
    assert_eq!(from_bag.2, from_euroc.2, "Basalt's fields");
}

/// Issue 20: a one-sensor topic (PX4 `sensor_gyro:1`, `sensor_accel:0`) of a ULog pyulog's
/// writer laid out is analysed from the command line: the sensor present gets exactly the
/// figures the same samples get in a layout with both sensors (a EuRoC pairing of the two
/// topics), and the absent one gets no figures (left out of every file, said on stdout and
/// stderr).
#[test]
fn one_sensor_ulog_topics_are_analysed_and_the_absent_sensor_left_out() {
    let dir = tempfile::tempdir().unwrap();
    let log = bag2mat::test_tools::pyulog_imu_log(dir.path(), 600.0, 100.0);
    let run = |input: &std::path::Path, topic: &str, out: &str| {
        let out = dir.path().join(out);
        let o = std::process::Command::new(env!("CARGO_BIN_EXE_allan_kalibr"))
            .arg(input)
            .args(["--topic", topic, "-o"])
            .arg(&out)
            .output()
            .unwrap();
        let (stdout, stderr) = (
            String::from_utf8_lossy(&o.stdout).into_owned(),
            String::from_utf8_lossy(&o.stderr).into_owned(),
        );
        assert!(o.status.success(), "{topic}: {stdout}{stderr}");
        (out, stdout, stderr)
    };
    let read = |d: &std::path::Path, f: &str| std::fs::read_to_string(d.join(f)).unwrap();
    // rows of the terms CSV and yaml lines of one sensor
    let terms = |d: &std::path::Path, sensor: &str| -> Vec<String> {
        read(d, "ieee952_terms.csv")
            .lines()
            .filter(|l| l.starts_with(&format!("{sensor},")))
            .map(str::to_string)
            .collect()
    };
    let keys = |d: &std::path::Path, prefix: &str| -> Vec<String> {
        values(&read(d, "imu.yaml"))
            .into_iter()
            .filter(|l| l.starts_with(prefix))
            .collect()
    };
    for (gyro, acc, topic, present, absent, chart, gone) in [
        (
            "sensor_gyro:1",
            "sensor_accel:1",
            "sensor_gyro:1",
            ("gyroscope", "gyroscope_"),
            ("accelerometer", "accelerometer_"),
            "allan_gyro.png",
            "allan_accel.png",
        ),
        (
            "sensor_gyro:0",
            "sensor_accel:0",
            "sensor_accel:0",
            ("accelerometer", "accelerometer_"),
            ("gyroscope", "gyroscope_"),
            "allan_accel.png",
            "allan_gyro.png",
        ),
    ] {
        let (one, stdout, stderr) = run(&log, topic, &format!("one_{}", topic.replace(':', "_")));
        let pair_dir = dir.path().join(format!("pair_{}", topic.replace(':', "_")));
        std::fs::create_dir_all(&pair_dir).unwrap();
        let root = bag2mat::test_tools::euroc_pairing(&log, gyro, acc, &pair_dir);
        let (both, _, _) = run(&root, "imu0", &format!("both_{}", topic.replace(':', "_")));
        assert!(
            stdout.contains(&format!("=> {}: absent from this topic", absent.0)),
            "{stdout}"
        );
        assert!(
            stderr.contains(&format!("the topic carries no {}", absent.0)),
            "{stderr}"
        );
        // the present sensor: the same figures as from the pairing, in the same layouts
        assert!(!terms(&one, present.0).is_empty());
        assert_eq!(terms(&one, present.0), terms(&both, present.0), "{topic}");
        assert_eq!(keys(&one, present.1), keys(&both, present.1), "{topic}");
        assert_eq!(keys(&one, present.1).len(), 2);
        assert!(one.join(chart).exists());
        // the absent one: no figures anywhere
        assert!(terms(&one, absent.0).is_empty(), "{topic}");
        assert!(keys(&one, absent.1).is_empty(), "{topic}");
        assert!(!one.join(gone).exists());
        let head = read(&one, "allan_curves.csv")
            .lines()
            .next()
            .unwrap()
            .to_string();
        let absent_cols = if absent.0 == "gyroscope" { "wx" } else { "ax" };
        assert!(!head.contains(absent_cols), "{head}");
        for f in [
            "kalibr_imu_ieee952.yaml",
            "openvins_kalibr_imu_chain_ieee952.yaml",
            "basalt_imu_noise_ieee952.json",
        ] {
            let text = read(&one, f);
            let key = if absent.0 == "gyroscope" {
                "gyro"
            } else {
                "acc"
            };
            // yaml keys and JSON members of the absent sensor (comments and the JSON
            // `_convention` text name what was left out)
            let member = |l: &str| {
                let l = l.trim_start().trim_start_matches('"');
                l.starts_with(key)
            };
            assert!(
                !text
                    .lines()
                    .any(|l| !l.trim_start().starts_with('#') && member(l)),
                "{f}: {text}"
            );
        }
    }
}
