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
    let sim::cli::Command::Bag(a) = sim::cli::Cli::try_parse_from([
        "sim",
        "bag",
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
    ])
    .unwrap()
    .command
    else {
        panic!("not a bag command")
    };
    sim::bag_sim::run(&sim::bag_sim::BagConfig::try_from(*a).unwrap()).unwrap();
    let root = bag2mat::test_tools::euroc_dataset_from_bag(
        &bag,
        "imu",
        bag2mat::TimeColumn::Record,
        dir.path(),
    );
    let analyse = |input: &std::path::Path, topic: &str, out: &str| {
        let out = dir.path().join(out);
        let args = allan_kalibr::cli::Args::try_parse_from([
            "allan_kalibr",
            input.to_str().unwrap(),
            "--topic",
            topic,
            "-q",
            "-o",
            out.to_str().unwrap(),
        ])
        .unwrap();
        let run = allan_kalibr::run::run(&args.into()).unwrap().remove(0);
        let read = |f: &str| std::fs::read_to_string(out.join(f)).unwrap();
        (
            read("ieee952_terms.csv"),
            values(&read("imu.yaml")),
            read("basalt_imu_noise_ieee952.json"),
            run.ieee952_text.unwrap_or_default(),
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
