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
        let args = allan_imu_utils::cli::Args::try_parse_from([
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
        allan_imu_utils::run::run(&args.try_into().unwrap()).unwrap();
        let read = |f: &str| std::fs::read_to_string(out.join(f)).unwrap();
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
