//! The IEEE 952 configuration files read by the parsers their consumers use: Kalibr loads
//! `imu.yaml` with PyYAML; VINS-Mono/VINS-Fusion and ORB-SLAM3 read their settings with
//! OpenCV's `cv2.FileStorage`, and so does OpenVINS for its `kalibr_imu_chain.yaml`; Basalt's
//! noise fields are JSON (Python's `json`), merged into a calibration and loaded with cereal
//! (Basalt's JSON library) as Basalt loads its calibration. Run on p4 (60 min at 100 Hz), whose terms are all resolved
//! except where the record is too short; the values read back must be the ones in
//! `ieee952_terms.csv` (largest axis), exactly.

use std::process::Command;

use crate::common::CASES;

/// Debian's interpreter, which sees python3-yaml and python3-opencv.
const PYTHON: &str = "/usr/bin/python3";

fn python(code: &str) -> String {
    let o = Command::new(PYTHON)
        .arg("-c")
        .arg(code)
        .output()
        .expect("run /usr/bin/python3 (scripts/test.sh installs it)");
    assert!(
        o.status.success(),
        "python failed: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    String::from_utf8_lossy(&o.stdout).into_owned()
}

/// The value the files carry for a term (the documented rule of `ieee952::imu`): the
/// largest resolved axis value; for K with no resolved axis, the largest 95 % upper bound.
fn largest(csv: &str, sensor: &str, term: &str) -> f64 {
    let rows: Vec<Vec<&str>> = csv
        .lines()
        .filter(|l| !l.starts_with('#'))
        .map(|l| l.split(',').collect::<Vec<_>>())
        .filter(|f| f.len() > 7 && f[0] == sensor && f[2] == term)
        .collect();
    let num = |s: &str| s.parse::<f64>().unwrap();
    let resolved = rows
        .iter()
        .filter(|f| f[7] == "true" || term == "N")
        .map(|f| num(f[3]))
        .fold(f64::NAN, f64::max);
    if resolved.is_finite() {
        resolved
    } else {
        rows.iter().map(|f| num(f[6])).fold(f64::NAN, f64::max)
    }
}

#[test]
fn pyyaml_and_opencv_read_the_ieee952_files() {
    let case = &CASES[3];
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path();
    let o = Command::new(env!("CARGO_BIN_EXE_allan_kalibr"))
        .arg(case.bag())
        .args(["--topic", case.topic, "-q", "-o"])
        .arg(out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let csv = std::fs::read_to_string(out.join("ieee952_terms.csv")).unwrap();
    let (gn, an) = (
        largest(&csv, "gyroscope", "N"),
        largest(&csv, "accelerometer", "N"),
    );
    let (gk, ak) = (
        largest(&csv, "gyroscope", "K"),
        largest(&csv, "accelerometer", "K"),
    );

    let kalibr = python(&format!(
        "import yaml; d = yaml.safe_load(open('{}')); print(repr(d['gyroscope_noise_density']), repr(d['gyroscope_random_walk']), repr(d['accelerometer_noise_density']), repr(d['accelerometer_random_walk']), repr(d['update_rate']), d['rostopic'])",
        out.join("kalibr_imu_ieee952.yaml").display()
    ));
    let v: Vec<&str> = kalibr.split_whitespace().collect();
    let num = |s: &str| {
        s.parse::<f64>()
            .unwrap_or_else(|_| panic!("not a float: {s} in {kalibr}"))
    };
    assert_eq!(
        [num(v[0]), num(v[1]), num(v[2]), num(v[3]), num(v[4])],
        [gn, gk, an, ak, 100.0],
        "{kalibr}"
    );
    assert_eq!(v[5], "imu");
    // The compat imu.yaml reads with PyYAML too.
    python(&format!(
        "import yaml; d = yaml.safe_load(open('{}')); assert isinstance(d['gyroscope_noise_density'], float)",
        out.join("imu.yaml").display()
    ));

    let cv = |file: &str, keys: &[&str]| -> Vec<f64> {
        let code = format!(
            "import cv2; fs = cv2.FileStorage('{}', cv2.FILE_STORAGE_READ); print(' '.join(repr(fs.getNode(k).real()) for k in {:?}))",
            out.join(file).display(),
            keys
        );
        python(&code)
            .split_whitespace()
            .map(|x| x.parse().unwrap())
            .collect()
    };
    assert_eq!(
        cv(
            "vins_imu_ieee952.yaml",
            &["acc_n", "gyr_n", "acc_w", "gyr_w", "g_norm"]
        ),
        vec![an, gn, ak, gk, 9.81]
    );
    assert_eq!(
        cv(
            "orbslam3_imu_ieee952.yaml",
            &[
                "IMU.NoiseGyro",
                "IMU.NoiseAcc",
                "IMU.GyroWalk",
                "IMU.AccWalk",
                "IMU.Frequency"
            ]
        ),
        vec![gn, an, gk, ak, 100.0]
    );

    // OpenVINS reads kalibr_imu_chain.yaml with cv::FileStorage: the imu0 block, T_i_b
    // element by element as its parser does, the four values, the rate and the model.
    let ov = python(&format!(
        "import cv2; fs = cv2.FileStorage('{}', cv2.FILE_STORAGE_READ); n = fs.getNode('imu0'); t = n.getNode('T_i_b'); print(' '.join(repr(t.at(r).at(c).real()) for r in range(4) for c in range(4)), ' '.join(repr(n.getNode(k).real()) for k in ['accelerometer_noise_density', 'accelerometer_random_walk', 'gyroscope_noise_density', 'gyroscope_random_walk', 'update_rate', 'time_offset']), n.getNode('rostopic').string(), n.getNode('model').string())",
        out.join("openvins_kalibr_imu_chain_ieee952.yaml").display()
    ));
    let v: Vec<&str> = ov.split_whitespace().collect();
    let f: Vec<f64> = v[..22].iter().map(|x| x.parse().unwrap()).collect();
    let identity: Vec<f64> = (0..16).map(|i| f64::from(i % 5 == 0)).collect();
    assert_eq!(&f[..16], &identity[..], "{ov}");
    assert_eq!(&f[16..], &[an, ak, gn, gk, 100.0, 0.0], "{ov}");
    assert_eq!(&v[22..], ["imu", "kalibr"], "{ov}");

    // Basalt's noise fields, per axis, read as JSON: each axis' value from the terms table
    // (resolved, else its 95 % upper bound, named in _not_resolved), the convention stated.
    let axis = |sensor: &str, term: &str| -> Vec<f64> {
        ["x", "y", "z"]
            .iter()
            .map(|a| {
                let f: Vec<&str> = csv
                    .lines()
                    .map(|l| l.split(',').collect::<Vec<_>>())
                    .find(|f| f.len() > 7 && f[0] == sensor && f[1] == *a && f[2] == term)
                    .unwrap();
                f[if f[7] == "true" { 3 } else { 6 }].parse().unwrap()
            })
            .collect()
    };
    let b = python(&format!(
        "import json; d = json.load(open('{}'))['value0']; print(' '.join(repr(x) for k in ['accel_noise_std', 'gyro_noise_std', 'accel_bias_std', 'gyro_bias_std'] for x in d[k]), repr(d['imu_update_rate']), 'CONTINUOUS-TIME' in d['_convention'] and 'sqrt(imu_update_rate)' in d['_convention'], len(d['_not_resolved']))",
        out.join("basalt_imu_noise_ieee952.json").display()
    ));
    let v: Vec<&str> = b.split_whitespace().collect();
    let f: Vec<f64> = v[..13].iter().map(|x| x.parse().unwrap()).collect();
    let want: Vec<f64> = [
        axis("accelerometer", "N"),
        axis("gyroscope", "N"),
        axis("accelerometer", "K"),
        axis("gyroscope", "K"),
    ]
    .concat();
    assert_eq!(&f[..12], &want[..], "{b}");
    assert_eq!(f[12], 100.0);
    assert_eq!(v[13], "True", "{b}");
    let unresolved = csv
        .lines()
        .filter(|l| {
            let f: Vec<&str> = l.split(',').collect();
            f.len() > 7 && (f[2] == "N" || f[2] == "K") && f[7] == "false"
        })
        .count();
    assert_eq!(v[14].parse::<usize>().unwrap(), unresolved, "{b}");

    // Basalt's loader: the fragment merged into a calibration (its members replacing the
    // calibration's, the `_` members added) is read by cereal's JSON archive the way Basalt
    // reads basalt::Calibration, with the same values; the fragment alone is not a
    // calibration (cereal misses `T_imu_cam`), as its `_convention` says.
    let merged = out.join("calib_merged.json");
    python(&format!(
        "import json; frag = json.load(open('{}'), parse_constant=lambda c: exec('raise ValueError(c)'))['value0']; \
         calib = {{'value0': {{'T_imu_cam': [], 'intrinsics': [], 'resolution': [], 'calib_accel_bias': [0.0] * 9, 'calib_gyro_bias': [0.0] * 12, 'imu_update_rate': 200.0, 'accel_noise_std': [1.0] * 3, 'gyro_noise_std': [1.0] * 3, 'accel_bias_std': [1.0] * 3, 'gyro_bias_std': [1.0] * 3, 'cam_time_offset_ns': 0, 'vignette': []}}}}; \
         assert set(k for k in frag if not k.startswith('_')) <= set(calib['value0']), frag.keys(); \
         calib['value0'].update(frag); json.dump(calib, open('{}', 'w'), indent=2)",
        out.join("basalt_imu_noise_ieee952.json").display(),
        merged.display()
    ));
    let loader = cereal_loader(out);
    let o = Command::new(&loader).arg(&merged).output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let got: Vec<f64> = String::from_utf8_lossy(&o.stdout)
        .split_whitespace()
        .map(|x| x.parse().unwrap())
        .collect();
    assert_eq!(got[0], 100.0);
    assert_eq!(&got[1..], &want[..], "cereal's values");
    let o = Command::new(&loader)
        .arg(out.join("basalt_imu_noise_ieee952.json"))
        .output()
        .unwrap();
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("T_imu_cam"));
}

/// Builds `tests/cereal/basalt_imu_load.cpp` (Basalt's way of loading its calibration JSON
/// with cereal, Debian's libcereal-dev) into `dir`.
fn cereal_loader(dir: &std::path::Path) -> std::path::PathBuf {
    let exe = dir.join("basalt_imu_load");
    let src =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/cereal/basalt_imu_load.cpp");
    let o = Command::new("g++")
        .args(["-std=c++17", "-O0", "-o"])
        .arg(&exe)
        .arg(&src)
        .output()
        .expect("run g++ (scripts/test.sh installs g++ and libcereal-dev)");
    assert!(
        o.status.success(),
        "g++ {}: {}",
        src.display(),
        String::from_utf8_lossy(&o.stderr)
    );
    exe
}
