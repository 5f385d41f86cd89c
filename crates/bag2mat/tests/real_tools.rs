//! What we write, read by the real tools: Debian's `rosbag info`/`rosbag check` and the
//! python rosbag API for bags (all three compressions), GNU Octave and scipy for `.mat`.
//! scripts/test.sh installs them; a missing tool fails the test rather than skipping it.

use std::process::Command;

use bag2mat::Compression;
use bag2mat::{OutputFormat, data_imu_from_series, write_matrix};
use bag2mat::{ReadOptions, TimeColumn, read_imu_series};

use crate::common::{run, synthetic, write_synthetic};

/// Debian's interpreter: the one that sees python3-rosbag and python3-scipy.
const PYTHON: &str = "/usr/bin/python3";
const N: u32 = 5000;

fn yaml_value<'a>(yaml: &'a str, key: &str) -> &'a str {
    yaml.lines()
        .find_map(|l| l.trim_start().strip_prefix(&format!("{key}:")))
        .unwrap_or_else(|| panic!("no {key} in\n{yaml}"))
        .trim()
}

#[test]
fn rosbag_info_check_and_python_read_our_bags() {
    let dir = tempfile::tempdir().unwrap();
    let script = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/py/read_bag.py");
    for c in [Compression::None, Compression::Bz2, Compression::Lz4] {
        let path = dir.path().join(format!("ours_{}.bag", c.name()));
        write_synthetic(&path, "imu", N, c, false);

        let (ok, info, err) = run(Command::new("rosbag").arg("info").arg("--yaml").arg(&path));
        assert!(ok, "{c:?}: rosbag info failed: {err}");
        assert_eq!(
            yaml_value(&info, "messages"),
            N.to_string(),
            "{c:?}\n{info}"
        );
        assert_eq!(yaml_value(&info, "compression"), c.name(), "{c:?}\n{info}");
        let duration: f64 = yaml_value(&info, "duration").parse().unwrap();
        assert!(
            (duration - (N - 1) as f64 * 0.005).abs() < 1e-9,
            "{c:?}: duration {duration}"
        );
        assert!(
            info.contains("type: sensor_msgs/Imu")
                && info.contains("md5: 6a62c6daae103f4ff57a132d6f95cec2"),
            "{info}"
        );
        assert!(
            info.contains("topic: imu") && info.contains(&format!("messages: {N}")),
            "{info}"
        );

        let (ok, out, err) = run(Command::new("rosbag").arg("check").arg(&path));
        assert!(ok, "{c:?}: rosbag check failed: {out}{err}");
        assert!(
            out.contains("does not need any migrations"),
            "{c:?}: {out}{err}"
        );

        let (ok, out, err) = run(Command::new(PYTHON).arg(&script).arg(&path));
        assert!(ok, "{c:?}: python rosbag read failed: {err}");
        let lines: Vec<&str> = out.lines().collect();
        assert_eq!(lines.len(), N as usize, "{c:?}");
        for (i, line) in lines.iter().enumerate() {
            let (t, imu) = synthetic(i as u32);
            let mut buf = Vec::new();
            imu.encode(&mut buf);
            let doubles: Vec<String> = buf[buf.len() - 296..]
                .chunks(8)
                .map(|b| b.iter().map(|x| format!("{x:02x}")).collect())
                .collect();
            let want = format!(
                "imu {} {} {} {} {} {}",
                t.as_nanos(),
                imu.seq,
                imu.stamp.as_nanos(),
                imu.frame_id,
                bag2mat::IMU_MD5,
                doubles.join(" ")
            );
            assert_eq!(*line, want, "{c:?}: message {i}");
        }
    }
}

#[test]
fn octave_and_scipy_load_our_mat() {
    let dir = tempfile::tempdir().unwrap();
    let bag = dir.path().join("m.bag");
    write_synthetic(&bag, "imu", 777, Compression::Lz4, false);
    let s = read_imu_series(&bag, "imu", &ReadOptions { quiet: true }).unwrap();
    let d = data_imu_from_series(&s, TimeColumn::Record);
    let mat = dir.path().join("m.mat");
    write_matrix(
        &bag2mat::shared::output::Outputs::direct(),
        &mat,
        &d,
        OutputFormat::Mat,
    )
    .unwrap();
    // Octave prints the size, the first time at full precision, and the sum of each column.
    let script = format!(
        "load('{}'); printf('%d %d %.17g %.17g %.17g\\n', size(data_imu), data_imu(1,1), data_imu(end,7), data_imu(400,4));",
        mat.display()
    );
    let (ok, out, err) = run(Command::new("octave")
        .args(["--no-gui", "--quiet", "--eval"])
        .arg(&script));
    assert!(ok, "octave failed: {err}");
    let v: Vec<f64> = out.split_whitespace().map(|x| x.parse().unwrap()).collect();
    assert_eq!(
        v,
        vec![777.0, 7.0, d.row(0)[0], d.row(776)[6], d.row(399)[3]],
        "octave: {out}"
    );

    let code = format!(
        "import scipy.io; m = scipy.io.loadmat('{}')['data_imu']; print(m.shape[0], m.shape[1], repr(float(m[0,0])), repr(float(m[-1,6])), repr(float(m[399,3])))",
        mat.display()
    );
    let (ok, out, err) = run(Command::new(PYTHON).arg("-c").arg(&code));
    assert!(ok, "scipy failed: {err}");
    let v: Vec<f64> = out.split_whitespace().map(|x| x.parse().unwrap()).collect();
    assert_eq!(
        v,
        vec![777.0, 7.0, d.row(0)[0], d.row(776)[6], d.row(399)[3]],
        "scipy: {out}"
    );

    // An empty matrix (0×7) loads too.
    let empty = dir.path().join("e.mat");
    write_matrix(
        &bag2mat::shared::output::Outputs::direct(),
        &empty,
        &bag2mat::DataImu::default(),
        OutputFormat::Mat,
    )
    .unwrap();
    let (ok, out, err) = run(Command::new("octave")
        .args(["--no-gui", "--quiet", "--eval"])
        .arg(format!("load('{}'); disp(size(data_imu))", empty.display())));
    assert!(
        ok && out.split_whitespace().collect::<Vec<_>>() == ["0", "7"],
        "octave empty: {out}{err}"
    );
}

#[test]
fn octave_v7_compressed_mat_reads_back() {
    // Octave's `save -v7` writes zlib-compressed elements, as MATLAB's default does.
    let dir = tempfile::tempdir().unwrap();
    let mat = dir.path().join("v7.mat");
    let script = format!(
        "data_imu = [1600000000 + (0:99)'*0.005, reshape(sin(1:600), 100, 6)]; other = 'x'; save('-v7', '{}', 'other', 'data_imu');",
        mat.display()
    );
    let (ok, _, err) = run(Command::new("octave")
        .args(["--no-gui", "--quiet", "--eval"])
        .arg(&script));
    assert!(ok, "octave failed: {err}");
    let d = bag2mat::read_data_imu(&mat).unwrap();
    assert_eq!(d.rows(), 100);
    assert_eq!(d.row(0)[0], 1_600_000_000.0);
    assert_eq!(d.row(99)[0], 1_600_000_000.0 + 99.0 * 0.005);
    // Column 2 is sin(1..100) as Octave computed it: compare to Rust's sin within 1 ulp.
    for i in 0..100 {
        let want = ((i + 1) as f64).sin();
        assert!(
            (d.row(i)[1] - want).abs() <= f64::EPSILON,
            "row {i}: {} vs {want}",
            d.row(i)[1]
        );
    }
}

#[test]
fn numpy_loads_our_npy_and_csv() {
    let dir = tempfile::tempdir().unwrap();
    let mut d = bag2mat::DataImu::default();
    for i in 0..50 {
        let (t, imu) = synthetic(i);
        let (a, g) = (imu.linear_acceleration, imu.angular_velocity);
        d.push([t.to_sec(), a[0], a[1], a[2], g[0], g[1], g[2]]);
    }
    let npy = dir.path().join("d.npy");
    let csv = dir.path().join("d.csv");
    write_matrix(
        &bag2mat::shared::output::Outputs::direct(),
        &npy,
        &d,
        OutputFormat::Npy,
    )
    .unwrap();
    write_matrix(
        &bag2mat::shared::output::Outputs::direct(),
        &csv,
        &d,
        OutputFormat::Csv,
    )
    .unwrap();
    let code = format!(
        "import numpy as np; a = np.load('{}'); b = np.loadtxt('{}', delimiter=',', skiprows=1); print(a.shape, a.dtype, bool((a == b).all()), repr(float(a[49, 6])))",
        npy.display(),
        csv.display()
    );
    let (ok, out, err) = run(Command::new(PYTHON).arg("-c").arg(&code));
    assert!(ok, "numpy failed: {err}");
    assert_eq!(
        out.trim(),
        format!("(50, 7) float64 True {:?}", d.row(49)[6])
    );
}
