//! The binary as a user runs it: the launch file of `launch_equivalents/`, bad inputs with
//! clear errors, and the yaml files read back by OpenCV's own `cv2.FileStorage`.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use bag2mat::BagWriter;
use bag2mat::Imu;
use bag2mat::RosTime;

use crate::common::CASES;

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_allan_imu_utils"))
}

fn launch_file() -> PathBuf {
    bag2mat::test_tools::workspace().join("launch_equivalents/my_imu.launch")
}

fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

fn run(cmd: &mut Command) -> Output {
    cmd.output().expect("binary runs")
}

/// Seed of the synthetic bags' noise (a fixed LCG).
const SEED: u64 = 0xB0A7_5EED;

/// A 200 Hz bag of `n` messages of white noise; `nan_at` puts a NaN into acc y there.
pub fn write_bag(path: &Path, n: usize, nan_at: Option<usize>) {
    write_bag_dt(path, n, nan_at, 5_000_000);
}

/// As [`write_bag`] with stamps `dt_ns` apart.
fn write_bag_dt(path: &Path, n: usize, nan_at: Option<usize>, dt_ns: u64) {
    write_noise_bag(
        path,
        n,
        |i| 1_600_000_000_000_000_000 + i as u64 * dt_ns,
        1.0,
        nan_at,
    );
}

/// A bag of white noise whose message `i` is stamped `stamp_ns(i)`; `scale` multiplies the
/// accelerometer noise.
fn write_bag_at(path: &Path, n: usize, stamp_ns: impl Fn(usize) -> u64, scale: f64) {
    write_noise_bag(path, n, stamp_ns, scale, None);
}

/// `n` seeded white-noise Imu messages on `/imu`: message `i` stamped `stamp_ns(i)`, the
/// accelerometer noise times `scale`, a NaN in acc y at `nan_at`.
fn write_noise_bag(
    path: &Path,
    n: usize,
    stamp_ns: impl Fn(usize) -> u64,
    scale: f64,
    nan_at: Option<usize>,
) {
    let mut w = BagWriter::create(
        &bag2mat::shared::output::Outputs::direct(),
        path,
        bag2mat::Compression::None,
    )
    .unwrap();
    let conn = w.add_imu_connection("/imu");
    let mut state = SEED;
    let mut next = || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    };
    for i in 0..n {
        let stamp = RosTime::from_nanos(stamp_ns(i));
        let mut m = Imu {
            seq: i as u32,
            stamp,
            ..Imu::default()
        };
        m.angular_velocity = [next() * 0.1, next() * 0.1, next() * 0.1];
        m.linear_acceleration = [next() * scale, next() * scale, 9.81 + next() * scale];
        if nan_at == Some(i) {
            m.linear_acceleration[1] = f64::NAN;
        }
        w.write_imu(conn, stamp, &m).unwrap();
    }
    w.finish().unwrap();
}

#[test]
fn launch_file_with_overrides_reproduces_p3() {
    let case = &CASES[2];
    let dir = tempfile::tempdir().unwrap();
    let out = run(bin()
        .arg(case.bag())
        .arg("--launch")
        .arg(launch_file())
        .args(["--name", "p3", "--quiet", "--data-save-path"])
        .arg(dir.path()));
    let stderr = text(&out.stderr);
    assert!(
        out.status.success(),
        "exit {:?}, stderr:\n{stderr}",
        out.status
    );
    // the bag ends before max_time_min, as every ordinary record does: information, which
    // --quiet keeps off stderr (the words stay upstream's: reference.rs)
    assert!(!stderr.contains("bag ended"), "stderr:\n{stderr}");
    // Upstream's report comes first, unchanged; the IEEE 952 section follows it.
    let full = text(&out.stdout);
    let marker = "\n=> IEEE 952 noise terms";
    let at = full
        .find(marker)
        .unwrap_or_else(|| panic!("no IEEE 952 section in stdout:\n{full}"));
    let ours = &full[..at];
    assert!(
        full[at..].contains("gyroscope_noise_density = "),
        "{}",
        &full[at..]
    );
    for f in [
        "p3_ieee952_terms.csv",
        "p3_kalibr_imu_ieee952.yaml",
        "p3_vins_imu_ieee952.yaml",
        "p3_orbslam3_imu_ieee952.yaml",
    ] {
        assert!(dir.path().join(f).exists(), "{f} missing");
    }
    let theirs = case.read("stdout.txt");
    assert_eq!(
        ours.lines().count(),
        theirs.lines().count(),
        "stdout line count"
    );
    for (i, (a, b)) in ours.lines().zip(theirs.lines()).enumerate() {
        let fitted = b.starts_with("C ") || b.starts_with(" Bias") || b.starts_with(" White");
        assert!(
            fitted || a == b,
            "stdout line {}: expected {b:?}, actual {a:?}",
            i + 1
        );
    }
    for f in [
        "p3_imu_param.yaml",
        "p3_imu_param_continuous.yaml",
        "allan_gyr.png",
        "allan_acc.svg",
        "data_p3_sim_acc_z.txt",
    ] {
        assert!(dir.path().join(f).is_file(), "{f} not written");
    }
}

#[test]
fn launch_substitution_without_flag_names_the_flag() {
    let out = run(bin()
        .arg(CASES[2].bag())
        .arg("--launch")
        .arg(launch_file())
        .arg("--quiet"));
    let stderr = text(&out.stderr);
    assert!(!out.status.success());
    assert!(
        stderr.contains("--data-save-path") && stderr.contains("$(find imu_utils)"),
        "stderr:\n{stderr}"
    );
}

#[test]
fn missing_topic_lists_the_bag_topics() {
    let dir = tempfile::tempdir().unwrap();
    let out = run(bin()
        .arg(CASES[1].bag())
        .args(["--topic", "/nope", "--quiet", "--data-save-path"])
        .arg(dir.path()));
    let stderr = text(&out.stderr);
    assert!(!out.status.success());
    assert!(
        stderr.contains("/nope") && stderr.contains("/imu/data") && stderr.contains("/status"),
        "stderr:\n{stderr}"
    );
    assert_eq!(
        std::fs::read_dir(dir.path()).unwrap().count(),
        0,
        "nothing written on error"
    );
}

#[test]
fn too_few_samples_is_an_error() {
    let dir = tempfile::tempdir().unwrap();
    let bag = dir.path().join("tiny.bag");
    write_bag(&bag, 9, None);
    let out = run(bin()
        .arg(&bag)
        .args(["--quiet", "--data-save-path"])
        .arg(dir.path()));
    let stderr = text(&out.stderr);
    assert!(!out.status.success());
    assert!(
        stderr.contains("too few samples") && stderr.contains("9 messages"),
        "stderr:\n{stderr}"
    );
}

#[test]
fn nan_in_the_data_is_an_error() {
    let dir = tempfile::tempdir().unwrap();
    let bag = dir.path().join("nan.bag");
    write_bag(&bag, 3000, Some(1234));
    let out = run(bin()
        .arg(&bag)
        .args(["--quiet", "--data-save-path"])
        .arg(dir.path()));
    let stderr = text(&out.stderr);
    assert!(!out.status.success());
    assert!(
        stderr.contains("linear_acceleration.y") && stderr.contains("message 1234"),
        "stderr:\n{stderr}"
    );
}

#[test]
fn frozen_stamps_are_an_error() {
    let dir = tempfile::tempdir().unwrap();
    let bag = dir.path().join("frozen.bag");
    write_bag_dt(&bag, 3000, None, 0);
    let out = run(bin()
        .arg(&bag)
        .args(["--quiet", "--data-save-path"])
        .arg(dir.path()));
    let stderr = text(&out.stderr);
    assert!(!out.status.success());
    assert!(stderr.contains("do not advance"), "stderr:\n{stderr}");
}

/// Reads every real of a FileStorage yaml with OpenCV (Debian python3-opencv, the system
/// python) and prints `path value` lines.
const CV2_DUMP: &str = r#"
import sys, cv2
fs = cv2.FileStorage(sys.argv[1], cv2.FILE_STORAGE_READ)
assert fs.isOpened(), "OpenCV could not open " + sys.argv[1]
print("name", fs.getNode("name").string())
for s in ("Gyr", "Acc"):
    n = fs.getNode(s)
    print(s + "/unit", repr(n.getNode("unit").string()))
    for ax in ("avg-axis", "x-axis", "y-axis", "z-axis"):
        a = n.getNode(ax)
        for k in a.keys():
            print("%s/%s/%s %.17g" % (s, ax, k, a.getNode(k).real()))
"#;

#[test]
fn opencv_reads_both_yaml_files() {
    let dir = tempfile::tempdir().unwrap();
    let out = run(bin()
        .arg(CASES[2].bag())
        .args([
            "--topic",
            "imu",
            "--name",
            "16448",
            "--quiet",
            "--no-plots",
            "--data-save-path",
        ])
        .arg(dir.path()));
    assert!(out.status.success(), "{}", text(&out.stderr));
    for (file, unit) in [
        ("16448_imu_param.yaml", "' rad/s'"),
        (
            "16448_imu_param_continuous.yaml",
            "'gyr_n: rad / s / sqrt(Hz)",
        ),
    ] {
        let path = dir.path().join(file);
        let py = run(Command::new("/usr/bin/python3")
            .args(["-c", CV2_DUMP])
            .arg(&path));
        let dump = text(&py.stdout);
        assert!(
            py.status.success(),
            "cv2 failed on {file}: {}",
            text(&py.stderr)
        );
        assert!(
            dump.contains("name 16448\n"),
            "{file}: name not read back:\n{dump}"
        );
        assert!(
            dump.lines()
                .any(|l| l.starts_with("Gyr/unit ") && l.contains(unit)),
            "{file}: unit:\n{dump}"
        );
        // Every value OpenCV reads equals the one we wrote.
        let ours = std::fs::read_to_string(&path).unwrap();
        let mut n = 0;
        for line in dump.lines().filter(|l| l.contains("-axis/")) {
            let (key, v) = line.split_once(' ').unwrap();
            let cv: f64 = v.parse().unwrap();
            let leaf = key.rsplit('/').next().unwrap();
            let written: Vec<f64> = ours
                .lines()
                .filter_map(|l| l.trim().strip_prefix(&format!("{leaf}: ")))
                .map(|s| s.parse().unwrap())
                .collect();
            assert!(
                written.contains(&cv),
                "{file}: OpenCV read {key} = {cv:e}, not among the written {written:?}"
            );
            n += 1;
        }
        let expected = if file.contains("continuous") { 24 } else { 16 };
        assert_eq!(n, expected, "{file}: values read by OpenCV:\n{dump}");
    }
}

#[test]
fn max_cluster_is_validated_against_the_data() {
    let bag = crate::common::testdata().join("p3_short_61s/p3_short_61s.bag");
    let dir = tempfile::tempdir().unwrap();
    for m in ["4294967296", "1000000000", "100000"] {
        let t = std::time::Instant::now();
        let out = run(bin()
            .arg(&bag)
            .args([
                "--topic",
                "imu",
                "--max-cluster",
                m,
                "-q",
                "--no-plots",
                "--compat-only",
            ])
            .arg("--data-save-path")
            .arg(dir.path()));
        let err = text(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "--max-cluster {m}: {err}");
        assert!(
            err.contains("--max-cluster") && err.contains("samples allow"),
            "{err}"
        );
        assert!(
            t.elapsed().as_secs() < 30,
            "--max-cluster {m} ran for {:?}",
            t.elapsed()
        );
    }
    let out = run(bin().arg(&bag).args(["--max-cluster", "-1"]));
    assert_eq!(out.status.code(), Some(2));
    assert!(
        text(&out.stderr).contains("must be positive"),
        "{}",
        text(&out.stderr)
    );
}

#[test]
fn one_error_convention() {
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("missing.bag");
    let m = missing.to_str().unwrap();
    let cases: [(Vec<&str>, i32, String); 3] = [
        (
            vec![m],
            1,
            format!("allan_imu_utils: error: {m}: no such file or directory"),
        ),
        (
            vec!["--no-such-flag"],
            2,
            "allan_imu_utils: error: unexpected argument".into(),
        ),
        (
            vec![m, "--max-time-min", "-5"],
            2,
            "allan_imu_utils: error: invalid value '-5'".into(),
        ),
    ];
    for (args, code, start) in cases {
        let out = run(bin().args(&args));
        let err = text(&out.stderr);
        assert_eq!(out.status.code(), Some(code), "{args:?}: {err}");
        assert!(err.starts_with(&start), "{args:?}: {err}");
        assert_eq!(err.matches("error:").count(), 1, "{args:?}: {err}");
        assert!(!err.contains("os error"), "{err}");
    }
}

/// imu_utils' own outputs only (no plots, no IEEE 952 section) of `/imu` in `bag`, into `out`.
fn run_compat(bag: &Path, out: &Path) -> std::process::Output {
    run(bin()
        .arg(bag)
        .args([
            "--topic",
            "/imu",
            "--no-plots",
            "--compat-only",
            "-q",
            "--data-save-path",
        ])
        .arg(out))
}

#[test]
fn a_gap_is_found_and_only_the_longest_stretch_analysed() {
    let dir = tempfile::tempdir().unwrap();
    const T0: u64 = 1_600_000_000_000_000_000;
    // 60 s at 200 Hz, a 1 h gap, 30 s more; and the first 60 s alone.
    let gap = dir.path().join("gap.bag");
    write_bag_at(
        &gap,
        18_000,
        |i| {
            if i < 12_000 {
                T0 + i as u64 * 5_000_000
            } else {
                T0 + 3_660_000_000_000 + (i - 12_000) as u64 * 5_000_000
            }
        },
        1.0,
    );
    let clean = dir.path().join("clean.bag");
    write_bag_at(&clean, 12_000, |i| T0 + i as u64 * 5_000_000, 1.0);
    let go = |bag: &Path, o: &str| {
        let out = run_compat(bag, &dir.path().join(o));
        assert!(out.status.success(), "{}", text(&out.stderr));
        (
            text(&out.stderr),
            std::fs::read_to_string(dir.path().join(o).join("imu_imu_param.yaml")).unwrap(),
        )
    };
    let (err, yaml) = go(&gap, "g");
    let (_, clean_yaml) = go(&clean, "c");
    assert!(
        err.contains("warning: gaps:") && err.contains("not one continuous record"),
        "{err}"
    );
    assert_eq!(yaml, clean_yaml, "the longest stretch is the first 60 s");
}

#[test]
fn degenerate_values_are_explained() {
    let dir = tempfile::tempdir().unwrap();
    // a 60 s, 200 Hz bag whose accelerometer noise is scaled by `value` (0: constant);
    // returns the run's output
    let analyse = |name: &str, value: f64| {
        let bag = dir.path().join(name);
        write_bag_at(
            &bag,
            12_000,
            |i| 1_600_000_000_000_000_000 + i as u64 * 5_000_000,
            value,
        );
        run_compat(&bag, dir.path())
    };
    let out = analyse("const.bag", 0.0);
    let err = text(&out.stderr);
    assert!(
        err.contains("linear_acceleration.x is constant") && err.contains("NaN"),
        "{err}"
    );
    let out = analyse("big.bag", 1e300);
    let err = text(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(err.contains("overflow"), "{err}");
}

/// `--help` names every kind of input the registry holds and the bagconvert .mat (the
/// analysers' shared argument, from [`bag2mat::InputKind::ALL`]).
#[test]
fn help_lists_every_input_kind() {
    let out = bin().arg("--help").output().unwrap();
    assert!(out.status.success());
    bag2mat::test_tools::assert_help_lists_every_input(&out.stdout, &[allan_kalibr::MAT_INPUT]);
}
