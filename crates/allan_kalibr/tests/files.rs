//! The files users copy, as a user gets them from the binary: the rate keys carry the
//! record's rate (never the spacing of another tool's curve points), a reused output folder
//! holds only the last run's set of files (and says what went), and imu.yaml points to a
//! `kalibr_imu_ieee952.yaml` only when the run wrote one.

use std::path::Path;
use std::process::{Command, Output};

use bag2mat::test_tools::{OddWriter, odd_record, warnings, yaml_number};

/// The white-noise density and random walk of the curves written by [`avr_csv`] (acc, m/s²).
const ACC: (f64, f64) = (2.0e-3, 3.0e-5);
/// The same for the gyro, rad/s.
const GYRO: (f64, f64) = (1.7e-4, 2.0e-6);

fn run(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_allan_kalibr"))
        .args(args)
        .output()
        .expect("run allan_kalibr")
}

fn ok(o: &Output) -> String {
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn read(dir: &Path, file: &str) -> String {
    std::fs::read_to_string(dir.join(file)).unwrap_or_else(|e| panic!("{file}: {e}"))
}

/// An allan_variance_ros `allan_variance.csv` of white noise and a random walk (its layout:
/// `period accX accY accZ gyroX gyroY gyroZ`, periods 0.1·p s, gyro in deg/s), from the
/// closed form of the Allan deviation.
fn avr_csv(path: &Path) {
    let adev = |t: f64, (n, k): (f64, f64)| (n * n / t + k * k * t / 3.0).sqrt();
    let deg = 180.0 / std::f64::consts::PI;
    let mut body = String::new();
    for p in 1..=2000usize {
        let t = 0.1 * p as f64;
        let (a, g) = (adev(t, ACC), adev(t, GYRO) * deg);
        body.push_str(&format!("{t} {a} {a} {a} {g} {g} {g}\n"));
    }
    std::fs::write(path, body).unwrap();
}

#[test]
fn curves_input_files_carry_the_record_rate_not_the_curve_spacing() {
    let tmp = tempfile::tempdir().unwrap();
    let csv = tmp.path().join("allan_variance.csv");
    avr_csv(&csv);
    let out = tmp.path().join("given");
    let c = csv.to_str().unwrap();
    ok(&run(&[
        "--curves",
        c,
        "--duration",
        "7200",
        "--rate",
        "200",
        "-q",
        "-o",
        out.to_str().unwrap(),
    ]));
    // before: 10.0 (1/τ0 of allan_variance_ros' 0.1 s bins) in every file, --rate or not
    for (file, key) in [
        ("kalibr_imu_ieee952.yaml", "update_rate"),
        ("orbslam3_imu_ieee952.yaml", "IMU.Frequency"),
        ("openvins_kalibr_imu_chain_ieee952.yaml", "imu0/update_rate"),
        ("basalt_imu_noise_ieee952.json", "value0/imu_update_rate"),
    ] {
        assert_eq!(yaml_number(&read(&out, file), key), 200.0, "{file}");
    }
    // the curve's bins are not the IMU's samples: without --rate the rate is unknown, and
    // said; VINS' per-sample values need it and are left out
    let out = tmp.path().join("unknown");
    ok(&run(&[
        "--curves",
        c,
        "--duration",
        "7200",
        "-q",
        "-o",
        out.to_str().unwrap(),
    ]));
    let kalibr = read(&out, "kalibr_imu_ieee952.yaml");
    assert!(
        !kalibr.lines().any(|l| l.starts_with("update_rate")),
        "{kalibr}"
    );
    assert!(kalibr.contains("Record rate: unknown"), "{kalibr}");
    let orb = read(&out, "orbslam3_imu_ieee952.yaml");
    assert!(
        !orb.lines().any(|l| l.starts_with("IMU.Frequency")),
        "{orb}"
    );
    let vins = read(&out, "vins_imu_ieee952.yaml");
    assert!(!vins.lines().any(|l| l.starts_with("acc_n")), "{vins}");
    // what does not depend on the rate is still there
    assert!(yaml_number(&kalibr, "gyroscope_noise_density") > 0.0);
}

#[test]
fn a_reused_output_folder_holds_only_the_last_runs_files() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("out");
    let o = out.to_str().unwrap();
    let p3 = crate::common::CASES[2].bag();
    let p3 = p3.to_str().unwrap();
    ok(&run(&[p3, "-q", "-o", o]));
    let first: Vec<String> = names(&out);
    assert!(
        first.iter().any(|n| n == "kalibr_imu_ieee952.yaml"),
        "{first:?}"
    );
    assert!(read(&out, "imu.yaml").contains("prefer kalibr_imu_ieee952.yaml beside this file"));

    // a moving record into the same folder: its section is not computed
    let moving = tmp.path().join("ellipse.bag");
    crate::common::sim_ellipse_bag(&moving, 120);
    let err = ok(&run(&[moving.to_str().unwrap(), "-q", "-o", o]));
    // before: p3's kalibr_imu_ieee952.yaml (and every other section file) stayed, and
    // imu.yaml pointed to it "beside this file"
    let now = names(&out);
    assert_eq!(
        now,
        [
            "allan_accel.png",
            "allan_accel.svg",
            "allan_curves.csv",
            "allan_gyro.png",
            "allan_gyro.svg",
            "imu.yaml"
        ],
        "{err}"
    );
    let removed = warnings(&err, "removed ");
    assert!(
        removed.len() == 1
            && removed[0].contains("an earlier run left")
            && removed[0].contains("kalibr_imu_ieee952.yaml"),
        "{err}"
    );
    let imu = read(&out, "imu.yaml");
    assert!(!imu.contains("beside this file"), "{imu}");
    assert!(
        imu.contains("NO kalibr_imu_ieee952.yaml was written") && imu.contains("not static"),
        "{imu}"
    );
    assert!(imu.contains(moving.to_str().unwrap()), "{imu}");

    // the static record again: its whole set back, the files it replaces said
    let o2 = run(&[p3, "-o", o]);
    let err = ok(&o2);
    assert_eq!(names(&out), first);
    assert!(err.contains("replacing an earlier run's"), "{err}");
    // --compat-only writes no section: its files go, and imu.yaml says why there is none
    let err = ok(&run(&[p3, "-q", "--compat-only", "-o", o]));
    assert!(!out.join("kalibr_imu_ieee952.yaml").exists(), "{err}");
    assert!(read(&out, "imu.yaml").contains("--compat-only"));
    // a user's own file in the folder is never touched
    std::fs::write(out.join("notes.txt"), "mine").unwrap();
    ok(&run(&[p3, "-q", "-o", o]));
    assert_eq!(read(&out, "notes.txt"), "mine");
}

fn names(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

/// Every file of a run names the input it came from (issue 12's "no yaml names the input").
#[test]
fn every_section_file_names_its_input_tool_and_time() {
    let tmp = tempfile::tempdir().unwrap();
    let bag = tmp.path().join("hand.bag");
    odd_record(OddWriter::Rosbag, &bag, "clean", 120.0, 100.0);
    let out = tmp.path().join("o");
    ok(&run(&[
        bag.to_str().unwrap(),
        "-q",
        "-o",
        out.to_str().unwrap(),
    ]));
    for name in names(&out) {
        if name.ends_with(".png") || name.ends_with(".svg") || name == "allan_curves.csv" {
            continue;
        }
        let text = read(&out, &name);
        let version = format!("allan_kalibr {}", env!("CARGO_PKG_VERSION"));
        assert!(
            text.contains(&version) && text.contains(bag.to_str().unwrap()) && text.contains("Z "),
            "{name} does not say what wrote it, from what and when:\n{text}"
        );
    }
}
