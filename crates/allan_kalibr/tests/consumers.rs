//! The config files read by the parsers their consumers use: Kalibr loads `imu.yaml` with
//! PyYAML; VINS-Mono/VINS-Fusion, ORB-SLAM3 and OpenVINS read their settings with OpenCV's
//! `cv2.FileStorage`; Basalt's noise fields are JSON (Python's `json`), merged into a
//! calibration and loaded with cereal (Basalt's JSON library) as Basalt loads its
//! calibration; PX4's `.params` by QGroundControl's documented format (comment lines, then
//! tab-separated `Vehicle-Id Component-Id Name Value Type`, type 9 a float32); ArduPilot's
//! `.param` by pymavlink's `MAVParmDict.load` (what MAVProxy's `param load` runs); GTSAM's
//! covariances set on `gtsam.PreintegrationCombinedParams` (GTSAM's Python bindings, pinned in
//! `scripts/test.sh`) and read back with its getters.
//!
//! Two ways: files rendered from chosen figures from 1e-12 to 1e3 must give back exactly the
//! number each consumer's convention asks for; and the files of a real run (p4, 60 min at
//! 100 Hz) must carry the terms of its `ieee952_terms.csv` (largest axis), converted.

use std::path::{Path, PathBuf};
use std::process::Command;

use allan_kalibr::SensorValue;
use allan_kalibr::consumers::{
    AxisValue, CONSUMERS, ConfigValues, ConsumerId, Origin, Provenance, Quantity, RecordRate,
    consumer, render,
};
use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};

use crate::common::CASES;

/// Debian's interpreter, which sees python3-yaml and python3-opencv.
const PYTHON: &str = "/usr/bin/python3";
/// The seed of the figures written in the range test.
const RANGE_SEED: u64 = 0x0c0f_f1e5;
/// Files written in the range test (4 figures each).
const RANGE_FILES: usize = 12;
/// The record rate of the range test's files, Hz (VINS' values depend on it).
const RANGE_RATE: f64 = 200.0;

fn run_python(python: &Path, code: &str) -> String {
    let o = Command::new(python)
        .arg("-c")
        .arg(code)
        .output()
        .unwrap_or_else(|e| {
            panic!(
                "run {} ({e}; scripts/test.sh installs it)",
                python.display()
            )
        });
    assert!(
        o.status.success(),
        "python failed: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    String::from_utf8_lossy(&o.stdout).into_owned()
}

fn python(code: &str) -> String {
    run_python(Path::new(PYTHON), code)
}

fn floats(text: &str) -> Vec<f64> {
    text.split_whitespace()
        .map(|x| {
            x.parse()
                .unwrap_or_else(|_| panic!("not a float: {x} in {text}"))
        })
        .collect()
}

fn prov(rate: f64) -> Provenance {
    Provenance {
        tool: "allan_kalibr test".into(),
        input: "figures of the test".into(),
        written: "2025-01-01T00:00:00Z".into(),
        rate: RecordRate::Measured(rate),
    }
}

/// The four keys of consumer `id` read from each of `files` by its consumer's parser, in
/// [`Quantity::ALL`] order, and the rate key when it has one.
fn read_back(id: ConsumerId, files: &[PathBuf], scratch: &Path) -> Vec<Vec<f64>> {
    let c = consumer(id);
    let keys: Vec<&str> = c.keys.iter().map(|k| k.name).collect();
    let list = format!(
        "[{}]",
        files
            .iter()
            .map(|f| format!("'{}'", f.display()))
            .collect::<Vec<_>>()
            .join(", ")
    );
    let out = match id {
        ConsumerId::Kalibr => python(&format!(
            "import yaml\nfor f in {list}:\n d = yaml.safe_load(open(f))\n assert all(isinstance(d[k], float) for k in {keys:?} + ['update_rate']), d\n print(' '.join(repr(d[k]) for k in {keys:?} + ['update_rate']))"
        )),
        ConsumerId::Vins | ConsumerId::OrbSlam3 => {
            let rate = if id == ConsumerId::OrbSlam3 {
                // ORB-SLAM3's legacy reader wants an integer (node.isInt())
                " + ' ' + repr(float(fs.getNode('IMU.Frequency').real())) + (' int' if fs.getNode('IMU.Frequency').isInt() else ' notint')"
            } else {
                ""
            };
            python(&format!(
                "import cv2\nfor f in {list}:\n fs = cv2.FileStorage(f, cv2.FILE_STORAGE_READ)\n assert all(fs.getNode(k).isReal() for k in {keys:?})\n print(' '.join(repr(fs.getNode(k).real()) for k in {keys:?}){rate})"
            ))
        }
        ConsumerId::OpenVins => python(&format!(
            "import cv2\nfor f in {list}:\n fs = cv2.FileStorage(f, cv2.FILE_STORAGE_READ)\n n = fs.getNode('imu0')\n print(' '.join(repr(n.getNode(k).real()) for k in {keys:?} + ['update_rate']))"
        )),
        ConsumerId::Basalt => python(&format!(
            "import json\nfor f in {list}:\n d = json.load(open(f), parse_constant=lambda c: exec('raise ValueError(c)'))['value0']\n print(' '.join(repr(d[k][0]) for k in {keys:?}), repr(d['imu_update_rate']))"
        )),
        ConsumerId::Px4 => python(&format!(
            // QGroundControl's .params: '#' lines are comments; each other line is
            // Vehicle-Id, Component-Id, Name, Value, Type separated by tabs; type 9 is a
            // float32 (MAV_PARAM_TYPE_REAL32)
            "import numpy as np\nfor f in {list}:\n p = {{}}\n for line in open(f):\n  if line.startswith('#') or not line.strip(): continue\n  c = line.rstrip('\\n').split('\\t')\n  assert len(c) == 5 and c[4] == '9', line\n  p[c[2]] = float(np.float32(c[3]))\n print(' '.join(repr(p[k]) for k in {keys:?}))"
        )),
        ConsumerId::ArduPilot => run_python(
            &bag2mat::test_tools::venv_python(),
            &format!(
                "import numpy as np\nfrom pymavlink import mavparm\nfor f in {list}:\n p = mavparm.MAVParmDict()\n import contextlib, io\n with contextlib.redirect_stdout(io.StringIO()): assert p.load(f)\n print(' '.join(repr(float(np.float32(p[k]))) for k in {keys:?}))"
            ),
        ),
        ConsumerId::Gtsam => {
            // PyYAML (Debian's) to JSON, then GTSAM's own setters and getters (the venv's)
            let json = scratch.join("gtsam.json");
            python(&format!(
                "import yaml, json\njson.dump([yaml.safe_load(open(f)) for f in {list}], open('{}', 'w'))",
                json.display()
            ));
            run_python(
                &bag2mat::test_tools::venv_python(),
                &format!(
                    "import json, numpy as np, gtsam\nfor d in json.load(open('{}')):\n p = gtsam.PreintegrationCombinedParams.MakeSharedU(9.81)\n p.setAccelerometerCovariance(np.array(d['accelerometerCovariance']))\n p.setBiasAccCovariance(np.array(d['biasAccCovariance']))\n p.setGyroscopeCovariance(np.array(d['gyroscopeCovariance']))\n p.setBiasOmegaCovariance(np.array(d['biasOmegaCovariance']))\n m = [p.getAccelerometerCovariance(), p.getBiasAccCovariance(), p.getGyroscopeCovariance(), p.getBiasOmegaCovariance()]\n assert all(x[i, j] == 0.0 for x in m for i in range(3) for j in range(3) if i != j)\n assert all(x[0, 0] == x[1, 1] == x[2, 2] for x in m)\n print(' '.join(repr(float(x[0, 0])) for x in m))",
                    json.display()
                ),
            )
        }
    };
    out.lines()
        .map(|l| {
            l.split_whitespace()
                .map(|x| match x {
                    "int" => 1.0,
                    "notint" => 0.0,
                    x => x
                        .parse()
                        .unwrap_or_else(|_| panic!("not a float: {x} in {out}")),
                })
                .collect()
        })
        .collect()
}

/// The number consumer `c` should read for the continuous `x` of quantity `q`: its form's
/// conversion, as float32 for the flight stacks' parameters.
fn wanted(id: ConsumerId, x: f64, rate: f64) -> f64 {
    let v = consumer(id).form.from_continuous(x, Some(rate)).unwrap();
    match id {
        ConsumerId::Px4 | ConsumerId::ArduPilot => f64::from(v as f32),
        _ => v,
    }
}

#[test]
fn consumer_parsers_read_figures_from_1e_12_to_1e3_as_meant() {
    let mut rng = StdRng::seed_from_u64(RANGE_SEED);
    let tmp = tempfile::tempdir().unwrap();
    // log-uniform over 15 decades, the ends included
    let mut figures: Vec<[f64; 4]> = (0..RANGE_FILES)
        .map(|_| std::array::from_fn(|_| 10f64.powf(rng.random_range(-12.0..3.0))))
        .collect();
    figures[0] = [1e-12, 1e3, 1.0000000000000002e-12, 999.9999999999999];
    for c in &CONSUMERS {
        let files: Vec<PathBuf> = figures
            .iter()
            .enumerate()
            .map(|(i, f)| {
                let v = ConfigValues::plain(f.map(Some), Origin::Measured);
                let p = tmp.path().join(format!("{i}_{}", c.file));
                std::fs::write(&p, render(c.id, &v, &prov(RANGE_RATE), "/imu")).unwrap();
                p
            })
            .collect();
        let got = read_back(c.id, &files, tmp.path());
        assert_eq!(got.len(), files.len(), "{}", c.name);
        for (f, g) in figures.iter().zip(&got) {
            let want: Vec<f64> = f.iter().map(|x| wanted(c.id, *x, RANGE_RATE)).collect();
            assert_eq!(&g[..4], &want[..], "{}: {f:?}", c.name);
            match c.id {
                ConsumerId::Kalibr | ConsumerId::OpenVins | ConsumerId::Basalt => {
                    assert_eq!(g[4], RANGE_RATE, "{}", c.name)
                }
                ConsumerId::OrbSlam3 => assert_eq!(&g[4..], &[RANGE_RATE, 1.0], "{}", c.name),
                _ => assert_eq!(g.len(), 4),
            }
        }
    }
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
fn consumer_parsers_read_the_files_of_a_run() {
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
    // Quantity::ALL order: acc N, acc K, gyro N, gyro K
    let measured = [
        largest(&csv, "accelerometer", "N"),
        largest(&csv, "accelerometer", "K"),
        largest(&csv, "gyroscope", "N"),
        largest(&csv, "gyroscope", "K"),
    ];
    for c in &CONSUMERS {
        if c.id == ConsumerId::Basalt {
            continue; // per axis: below
        }
        let got = read_back(c.id, &[out.join(c.file)], out);
        let want: Vec<f64> = measured.iter().map(|x| wanted(c.id, *x, 100.0)).collect();
        assert_eq!(&got[0][..4], &want[..], "{}", c.name);
    }
    // every file names the tool, the input and the time
    for c in &CONSUMERS {
        let text = std::fs::read_to_string(out.join(c.file)).unwrap();
        assert!(
            text.contains("Written by allan_kalibr ")
                && text.contains(&case.bag().display().to_string()),
            "{}:\n{text}",
            c.file
        );
    }
    // The compat imu.yaml reads with PyYAML too.
    python(&format!(
        "import yaml; d = yaml.safe_load(open('{}')); assert isinstance(d['gyroscope_noise_density'], float)",
        out.join("imu.yaml").display()
    ));

    // OpenVINS reads kalibr_imu_chain.yaml with cv::FileStorage: the imu0 block, T_i_b
    // element by element as its parser does, the rate and the model.
    let ov = python(&format!(
        "import cv2; fs = cv2.FileStorage('{}', cv2.FILE_STORAGE_READ); n = fs.getNode('imu0'); t = n.getNode('T_i_b'); print(' '.join(repr(t.at(r).at(c).real()) for r in range(4) for c in range(4)), ' '.join(repr(n.getNode(k).real()) for k in ['update_rate', 'time_offset']), n.getNode('rostopic').string(), n.getNode('model').string())",
        out.join(consumer(ConsumerId::OpenVins).file).display()
    ));
    let v: Vec<&str> = ov.split_whitespace().collect();
    let f: Vec<f64> = v[..18].iter().map(|x| x.parse().unwrap()).collect();
    let identity: Vec<f64> = (0..16).map(|i| f64::from(i % 5 == 0)).collect();
    assert_eq!(&f[..16], &identity[..], "{ov}");
    assert_eq!(&f[16..], &[100.0, 0.0], "{ov}");
    assert_eq!(&v[18..], ["imu", "kalibr"], "{ov}");

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
    let basalt = out.join(consumer(ConsumerId::Basalt).file);
    let b = python(&format!(
        "import json; d = json.load(open('{}'))['value0']; print(' '.join(repr(x) for k in ['accel_noise_std', 'gyro_noise_std', 'accel_bias_std', 'gyro_bias_std'] for x in d[k]), repr(d['imu_update_rate']), 'CONTINUOUS-TIME' in d['_convention'] and 'sqrt(imu_update_rate)' in d['_convention'], len(d['_not_resolved']))",
        basalt.display()
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
    merge_into_calibration(&basalt, &merged);
    let loader = cereal_loader(out);
    let o = Command::new(&loader).arg(&merged).output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let got = floats(&String::from_utf8_lossy(&o.stdout));
    assert_eq!(got[0], 100.0);
    assert_eq!(&got[1..], &want[..], "cereal's values");
    let o = Command::new(&loader).arg(&basalt).output().unwrap();
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("T_imu_cam"));
}

/// Merges a Basalt noise fragment into a calibration whose other members are placeholders.
fn merge_into_calibration(fragment: &Path, merged: &Path) {
    python(&format!(
        "import json; frag = json.load(open('{}'), parse_constant=lambda c: exec('raise ValueError(c)'))['value0']; \
         calib = {{'value0': {{'T_imu_cam': [], 'intrinsics': [], 'resolution': [], 'calib_accel_bias': [0.0] * 9, 'calib_gyro_bias': [0.0] * 12, 'imu_update_rate': 200.0, 'accel_noise_std': [1.0] * 3, 'gyro_noise_std': [1.0] * 3, 'accel_bias_std': [1.0] * 3, 'gyro_bias_std': [1.0] * 3, 'cam_time_offset_ns': 0, 'vignette': []}}}}; \
         assert set(k for k in frag if not k.startswith('_')) <= set(calib['value0']), frag.keys(); \
         calib['value0'].update(frag); json.dump(calib, open('{}', 'w'), indent=2)",
        fragment.display(),
        merged.display()
    ));
}

/// Cereal reads per-axis Basalt values from 1e-12 to 1e3 (each axis its own) as written.
#[test]
fn cereal_reads_per_axis_basalt_figures_as_written() {
    let tmp = tempfile::tempdir().unwrap();
    let mut rng = StdRng::seed_from_u64(RANGE_SEED + 1);
    let mut v = ConfigValues::plain([Some(1.0); 4], Origin::Measured);
    let mut want = Vec::new();
    // Basalt's order: accel noise, gyro noise, accel bias, gyro bias
    for q in [
        Quantity::AccNoise,
        Quantity::GyroNoise,
        Quantity::AccWalk,
        Quantity::GyroWalk,
    ] {
        let axes: [AxisValue; 3] = std::array::from_fn(|_| AxisValue {
            value: 10f64.powf(rng.random_range(-12.0..3.0)),
            upper_bound: false,
        });
        want.extend(axes.iter().map(|a| a.value));
        v.axes[q.index()] = Some(axes);
        v.values[q.index()] = Some(SensorValue {
            value: axes[0].value,
            upper_bound: false,
            region: false,
        });
    }
    let frag = tmp.path().join("b.json");
    std::fs::write(&frag, render(ConsumerId::Basalt, &v, &prov(400.0), "")).unwrap();
    let merged = tmp.path().join("m.json");
    merge_into_calibration(&frag, &merged);
    let o = Command::new(cereal_loader(tmp.path()))
        .arg(&merged)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let got = floats(&String::from_utf8_lossy(&o.stdout));
    assert_eq!(got[0], 400.0);
    assert_eq!(&got[1..], &want[..]);
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
