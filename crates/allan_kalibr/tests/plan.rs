//! `allan_kalibr plan` as a user runs it, and once against the analysis (the study with every
//! sensor and seed is `studies::plan::plan_study`): the plan's records agree with the advice
//! printed after a record of the same sensor; datasheet units convert; a datasheet without a
//! random walk gets a bound, never a guess; `-o DIR` writes every consumer's file, marked.

use std::process::{Command, Output};

use allan_kalibr::plan::{Walk, plan_sensor};
use bag2mat::Sensor;

use crate::studies::plan::{SENSORS, advice_of, ratios, within};

fn run(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_allan_kalibr"))
        .args(args)
        .output()
        .expect("run allan_kalibr")
}

#[test]
fn plan_agrees_with_the_advice_of_a_simulated_record() {
    let (name, n, k, rate) = SENSORS[2];
    let plan = plan_sensor(Sensor::Acc, n, Some(k), None, rate);
    let (pn, pk) = (plan.n_records.unwrap(), plan.k_records.unwrap());
    let (_, adv) = advice_of(n, k, rate, 2.0 * pk.r25, 0x9_1a50);
    let r = ratios(&pn, &pk, &adv);
    assert!(r.iter().all(|x| within(*x)), "{name}: advice/plan {r:?}");
}

#[test]
fn plan_from_datasheet_figures_bounds_k_and_writes_marked_files() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("plan");
    // a consumer MEMS: 0.3 deg/sqrt(h), 10 deg/h; 100 ug/sqrt(Hz), 0.05 mg
    let o = run(&[
        "plan",
        "--rate",
        "200",
        "--gyro-arw",
        "0.3",
        "--gyro-bias-instability",
        "10",
        "--acc-noise-density-ug",
        "100",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = String::from_utf8_lossy(&o.stdout);
    // 0.3 deg/sqrt(h) = 0.3·(π/180)/60 rad/s/sqrt(Hz)
    assert!(text.contains("N = 8.7266e-5 rad/s/sqrt(Hz)"), "{text}");
    // K bounded by the floor: sqrt(3)·(10 deg/h)²/(2N), said as a bound
    let floor = 10.0f64.to_radians() / 3600.0;
    let bound = 3f64.sqrt() * floor * floor / (2.0 * 0.3f64.to_radians() / 60.0);
    assert!(
        text.contains(&format!("at most {bound:.3e}")),
        "{bound:e}: {text}"
    );
    assert!(text.contains("record for K: at least"), "{text}");
    // the accelerometer: no K, no bias instability: nothing bounds K
    assert!(text.contains("nothing bounds it"), "{text}");
    assert!(text.contains("FROM A DATASHEET, NOT MEASURED"), "{text}");
    for c in &allan_kalibr::consumers::CONSUMERS {
        let f = std::fs::read_to_string(out.join(c.file)).unwrap();
        assert!(f.contains("FROM A DATASHEET, NOT MEASURED"), "{}", c.file);
    }
    let kalibr = std::fs::read_to_string(out.join("kalibr_imu_ieee952.yaml")).unwrap();
    assert!(
        kalibr.contains("NOT RESOLVED: 95 % upper bound") || kalibr.contains("upper bound"),
        "{kalibr}"
    );
    assert!(
        !kalibr
            .lines()
            .any(|l| l.starts_with("accelerometer_random_walk")),
        "{kalibr}"
    );
    // and the library's plan says the same
    let p = plan_sensor(
        Sensor::Gyro,
        0.3f64.to_radians() / 60.0,
        None,
        Some(floor),
        200.0,
    );
    assert!(
        matches!(p.k, Walk::Bound(b) if (b / bound - 1.0).abs() < 1e-12),
        "{:?}",
        p.k
    );
}

#[test]
fn plan_refuses_figures_it_cannot_plan() {
    let o = run(&["plan", "--rate", "200", "--gyro-random-walk", "1e-5"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&o.stderr).contains("needs its noise density"));
    let o = run(&["plan", "--gyro-arw", "0.3"]);
    assert_eq!(o.status.code(), Some(2), "--rate is required");
    let o = run(&[
        "plan",
        "--rate",
        "200",
        "--gyro-arw",
        "0.3",
        "--gyro-noise-density",
        "1e-4",
    ]);
    assert_eq!(o.status.code(), Some(2), "two gyro densities");
}
