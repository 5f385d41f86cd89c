//! `allan_kalibr check` as a user runs it: on the tool's own config files it finds nothing
//! (against the analysis that wrote them, against the log itself, and alone); on configs
//! with the mistakes users make, written by hand here, it names each mistake and its key.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use allan_kalibr::consumers::sci;
use bag2mat::test_tools::yaml_number;

use crate::common::CASES;

fn run(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_allan_kalibr"))
        .args(args)
        .output()
        .expect("run allan_kalibr")
}

/// `check` on `configs` (`extra` flags first): its stdout lines; it must exit 0.
fn check(configs: &[PathBuf], extra: &[&str]) -> Vec<String> {
    let mut args = vec!["check"];
    args.extend_from_slice(extra);
    let c: Vec<String> = configs.iter().map(|p| p.display().to_string()).collect();
    args.extend(c.iter().map(|s| s.as_str()));
    let o = run(&args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    String::from_utf8_lossy(&o.stdout)
        .lines()
        .map(str::to_string)
        .collect()
}

/// The section's config files of an analysis folder (imu.yaml, kalibr_allan's method, is
/// not one: it may hold .nan and other numbers than the fit's).
fn section_configs(dir: &Path) -> Vec<PathBuf> {
    allan_kalibr::consumers::CONSUMERS
        .iter()
        .map(|c| dir.join(c.file))
        .collect()
}

/// The analysis of p4 (60 min at 100 Hz; N resolved on every axis, the gyro K only bounded)
/// in `dir`.
fn analysed(dir: &Path) -> PathBuf {
    let out = dir.join("p4");
    let case = &CASES[3];
    let o = run(&[
        case.bag().to_str().unwrap(),
        "--topic",
        case.topic,
        "-q",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    out
}

fn findings(lines: &[String]) -> Vec<&String> {
    lines.iter().filter(|l| l.contains(": finding (")).collect()
}

#[test]
fn check_finds_nothing_in_the_tools_own_files() {
    let tmp = tempfile::tempdir().unwrap();
    let out = analysed(tmp.path());
    let configs = section_configs(&out);
    let against = out.to_str().unwrap();
    // against the analysis that wrote them: one line per key, every one "ok"
    let lines = check(&configs, &["--against", against]);
    assert!(findings(&lines).is_empty(), "{lines:#?}");
    // 4 keys of 7 consumers, Basalt's 4 on 3 axes, the 4 rate keys (Kalibr, OpenVINS,
    // ORB-SLAM3, Basalt)
    assert_eq!(lines.len(), 7 * 4 + 4 * 3 + 4, "{}", lines.join("\n"));
    assert!(lines.iter().all(|l| l.contains(": ok: ")), "{lines:#?}");
    // alone, and against the record itself (analysed again, nothing written)
    let lines = check(&configs, &[]);
    assert!(findings(&lines).is_empty(), "{lines:#?}");
    let bag = CASES[3].bag();
    let lines = check(&configs, &["--against", bag.to_str().unwrap()]);
    assert!(findings(&lines).is_empty(), "{lines:#?}");
    assert!(
        lines[0].contains("the IEEE 952 analysis of"),
        "{}",
        lines[0]
    );
}

/// On a 15-minute record whose gyro random walk no axis resolves (p1), the files carry its
/// 95 % bound; that bound and the record's Allan floor are of one size, and `check` against
/// the log must not call the tool's own bound imu_utils' bias instability.
#[test]
fn check_takes_a_random_walk_inside_the_records_bound_as_allowed() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("p1");
    let case = &CASES[0];
    let o = run(&[
        case.bag().to_str().unwrap(),
        "--topic",
        case.topic,
        "-q",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let terms = std::fs::read_to_string(out.join("ieee952_terms.csv")).unwrap();
    assert!(
        !terms
            .lines()
            .any(|l| l.starts_with("gyroscope,") && l.contains(",K,") && l.contains(",true,")),
        "the case needs a gyro K that no axis resolves:\n{terms}"
    );
    let configs = section_configs(&out);
    for against in [out.clone(), case.bag()] {
        let lines = check(&configs, &["--against", against.to_str().unwrap()]);
        for (file, key) in [
            ("kalibr_imu_ieee952.yaml", "gyroscope_random_walk"),
            ("vins_imu_ieee952.yaml", "gyr_w"),
            ("orbslam3_imu_ieee952.yaml", "IMU.GyroWalk"),
            ("px4_ekf2_ieee952.params", "EKF2_GYR_B_NOISE"),
            ("gtsam_imu_params_ieee952.yaml", "biasOmegaCovariance"),
        ] {
            let l = line_of(&lines, &out.join(file), key);
            // the section's own files carry the bound itself (an unresolved K is written
            // as its 95 % upper bound): at it, or within it after a consumer's rounding
            assert!(
                l.contains(": ok: ")
                    && (l.contains("within the bound") || l.contains("at the bound")),
                "{l}"
            );
        }
    }
}

/// The one line of `lines` for `key` in `file`.
fn line_of<'a>(lines: &'a [String], file: &Path, key: &str) -> &'a str {
    let f = file.display().to_string();
    let hit: Vec<&String> = lines
        .iter()
        .filter(|l| l.starts_with(&format!("{f}: {key}")))
        .collect();
    assert_eq!(hit.len(), 1, "{key} in {f}: {lines:#?}");
    hit[0]
}

#[test]
fn check_names_each_seeded_mistake_and_its_key() {
    let tmp = tempfile::tempdir().unwrap();
    let out = analysed(tmp.path());
    let kalibr = std::fs::read_to_string(out.join("kalibr_imu_ieee952.yaml")).unwrap();
    let v = |k: &str| yaml_number(&kalibr, k);
    let (an, ak, gn, gk) = (
        v("accelerometer_noise_density"),
        v("accelerometer_random_walk"),
        v("gyroscope_noise_density"),
        v("gyroscope_random_walk"),
    );
    let rate: f64 = 100.0;
    let s = rate.sqrt();
    // the lowest gyro Allan deviation of the record: imu_utils' gyr_w is that floor
    let curves = std::fs::read_to_string(out.join("ieee952_curves.csv")).unwrap();
    let floor = curves
        .lines()
        .filter(|l| l.starts_with("gx,"))
        .map(|l| l.split(',').nth(3).unwrap().parse::<f64>().unwrap())
        .fold(f64::INFINITY, f64::min);
    let write = |name: &str, text: String| {
        let p = tmp.path().join(name);
        std::fs::write(&p, text).unwrap();
        p
    };
    // (file, key, the mistake check must name)
    let mut cases: Vec<(PathBuf, &str, &str)> = Vec::new();
    let k = write(
        "kalibr_discrete.yaml",
        format!(
            "accelerometer_noise_density: {}\naccelerometer_random_walk: {}\ngyroscope_noise_density: {}\ngyroscope_random_walk: {}\nupdate_rate: 100.0\n",
            sci(an),
            sci(ak),
            sci(gn * s),
            sci(gk)
        ),
    );
    cases.push((k, "gyroscope_noise_density", "discrete value"));
    let k = write(
        "kalibr_variance.yaml",
        format!(
            "accelerometer_noise_density: {}\nupdate_rate: 100.0\n",
            sci(an * an)
        ),
    );
    cases.push((k.clone(), "accelerometer_noise_density", "variance"));
    cases.push((k, "gyroscope_noise_density", "missing"));
    let k = write(
        "kalibr_strings.yaml",
        "gyroscope_random_walk: 2e-5\ngyroscope_noise_density:     0.000000016263488241019355#Bias random walk\nupdate_rate: 100\n".into(),
    );
    cases.push((k.clone(), "gyroscope_random_walk", "a string to PyYAML"));
    cases.push((k, "gyroscope_noise_density", "not a number"));
    let k = write(
        "vins.yaml",
        format!(
            "%YAML:1.0\nacc_n: {an}          # Kalibr's continuous value, unconverted\ngyr_n: {}\nacc_w: {}\ngyr_w: {floor}    # imu_utils' gyr_w\ng_norm: 9.81\n",
            gn * s,
            ak * s
        ),
    );
    cases.push((k.clone(), "acc_n", "continuous value"));
    cases.push((k, "gyr_w", "bias instability"));
    let k = write(
        "orb.yaml",
        format!(
            "%YAML:1.0\nIMU.NoiseGyro: {gn}\nIMU.NoiseAcc: {an}\nIMU.GyroWalk: {gk}\nIMU.AccWalk: {ak}\nIMU.Frequency: 200\n"
        ),
    );
    cases.push((k, "IMU.Frequency", "rate"));
    let k = write(
        "orb_real.yaml",
        format!("%YAML:1.0\nIMU.NoiseGyro: {gn}\nIMU.Frequency: 100.0\n"),
    );
    cases.push((k, "IMU.Frequency", "not an integer"));
    let k = write(
        "px4.params",
        format!(
            "# Onboard parameters for Vehicle 1\n#\n# Vehicle-Id Component-Id Name Value Type\n1\t1\tEKF2_GYR_NOISE\t{gn}\t9\n1\t1\tEKF2_ACC_NOISE\t{}\t9\n",
            an / 0.01f64.sqrt() * 20.0
        ),
    );
    cases.push((k.clone(), "EKF2_GYR_NOISE", "continuous value"));
    cases.push((k, "EKF2_ACC_NOISE", "inflated"));
    let k = write(
        "ardupilot.param",
        format!(
            "EK3_GYRO_P_NSE,{}\nEK3_ACC_P_NSE,{}\n",
            gn / 0.012f64.sqrt() * 0.5,
            an / 0.012f64.sqrt()
        ),
    );
    cases.push((k.clone(), "EK3_GYRO_P_NSE", "deflated"));
    cases.push((k, "EK3_ACC_P_NSE", "ok"));
    let k = write(
        "basalt.json",
        format!(
            "{{\"value0\": {{\"imu_update_rate\": 100.0, \"gyro_noise_std\": [{gn}, {gn}, {}], \"accel_noise_std\": [{an}, {an}, {an}]}}}}",
            gn * gn
        ),
    );
    cases.push((k, "value0/gyro_noise_std[2]", "variance"));
    let k = write(
        "gtsam.yaml",
        format!("gyroscopeCovariance: [[{gn}, 0.0, 0.0], [0.0, {gn}, 0.0], [0.0, 0.0, {gn}]]\n"),
    );
    cases.push((k, "gyroscopeCovariance", "standard deviation"));
    // imu_utils' own yaml of this very bag (testdata: the real imu_utils)
    let iu = CASES[3].dir().join("imu_utils/p4_imu_param.yaml");
    cases.push((iu.clone(), "Gyr/avg-axis/gyr_w", "bias instability"));
    cases.push((iu, "Gyr/avg-axis/gyr_n", "discrete value"));
    let files: Vec<PathBuf> = {
        let mut f: Vec<PathBuf> = cases.iter().map(|c| c.0.clone()).collect();
        f.dedup();
        f
    };
    let lines = check(&files, &["--against", out.to_str().unwrap()]);
    for (file, key, what) in &cases {
        let l = line_of(&lines, file, key);
        if *what == "ok" {
            assert!(l.contains(": ok: "), "{l}");
        } else {
            assert!(
                l.contains(&format!(": finding ({what}")),
                "expected {what}: {l}"
            );
        }
    }
    // the ratio and what it does, as users ask ("x20: inflated")
    let px4 = line_of(&lines, &tmp.path().join("px4.params"), "EKF2_ACC_NOISE");
    assert!(
        px4.contains("x20") && px4.contains("weighs the IMU"),
        "{px4}"
    );
    // without a measurement: a value no IMU has, named with the likely mistake
    let k = write(
        "degrees.yaml",
        format!(
            "gyroscope_noise_density: {}\nupdate_rate: 100.0\n",
            sci(1.7)
        ),
    );
    let lines = check(std::slice::from_ref(&k), &[]);
    let l = line_of(&lines, &k, "gyroscope_noise_density");
    assert!(
        l.contains("finding (no IMU has it") && l.contains("in degrees?"),
        "{l}"
    );
}

#[test]
fn check_refuses_what_it_cannot_read() {
    let tmp = tempfile::tempdir().unwrap();
    let o = run(&["check", tmp.path().join("missing.yaml").to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(1));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.starts_with("allan_kalibr: error:") && err.contains("missing.yaml"),
        "{err}"
    );
    let o = run(&["check", "x.yaml", "--against", tmp.path().to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&o.stderr).contains("ieee952_terms.csv"));
    // a log that cannot be analysed: the message names the flag it came from
    let missing = tmp.path().join("missing.bag");
    let o = run(&["check", "x.yaml", "--against", missing.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(1));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.starts_with(&format!(
            "allan_kalibr: error: --against {}: ",
            missing.display()
        )),
        "{err}"
    );
    // the analysis' own command line is unchanged: an input named as before
    let o = run(&[
        CASES[2].bag().to_str().unwrap(),
        "--compat-only",
        "-q",
        "-o",
        tmp.path().join("o").to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}
