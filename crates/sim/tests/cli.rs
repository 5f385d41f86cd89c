//! The binary as a user runs it: determinism, counts, defaults, errors, files.

use crate::common::{SEED, START, ok, run_in};
use bag2mat::{ReadOptions, read_imu_series};
use sim::{NoiseGenerator, Preset};

#[test]
fn same_flags_give_byte_identical_bags_and_another_seed_differs() {
    let d = tempfile::tempdir().unwrap();
    for name in ["a.bag", "b.bag"] {
        ok(
            d.path(),
            &[
                "bag",
                "-o",
                name,
                "--duration",
                "30",
                "--seed",
                SEED,
                "--start-time",
                START,
                "-q",
            ],
        );
    }
    ok(
        d.path(),
        &[
            "bag",
            "-o",
            "c.bag",
            "--duration",
            "30",
            "--seed",
            "999",
            "--start-time",
            START,
            "-q",
        ],
    );
    let a = std::fs::read(d.path().join("a.bag")).unwrap();
    let b = std::fs::read(d.path().join("b.bag")).unwrap();
    let c = std::fs::read(d.path().join("c.bag")).unwrap();
    assert!(a == b, "same seed: bags differ");
    assert!(a != c, "different seed: bags are identical");
    assert_eq!(a.len(), c.len());
}

#[test]
fn default_bag_content_matches_the_seed_run() {
    // Defaults except the duration: static, 200 Hz, topic imu, base_link, medium preset.
    let d = tempfile::tempdir().unwrap();
    let (_, err) = ok(
        d.path(),
        &[
            "bag",
            "--duration",
            "60",
            "--seed",
            SEED,
            "--start-time",
            START,
        ],
    );
    // The parameters are printed in both forms (without --quiet).
    for needle in [
        "1.5000e-2 rad/s/sqrt(Hz)",
        "2.1213e-1 rad/s per sample",
        "5.0000e-4 m/s^3/sqrt(Hz)",
        "3.5355e-5 m/s^2 per step",
    ] {
        assert!(err.contains(needle), "stderr lacks {needle:?}:\n{err}");
    }
    let s = read_imu_series(
        &d.path().join("imu.bag"),
        "imu",
        &ReadOptions { quiet: true },
    )
    .unwrap();
    let n = sim::message_count(200.0, 60.0);
    assert_eq!(s.len() as u64, n, "message count");
    assert_eq!(s.topic, "imu");
    // Oracle: replay the noise model with the same seed (static: gyro 0, acc (0, 0, 9.81)).
    let mut g = NoiseGenerator::new(
        Preset::Medium.params().discretize(0.005),
        SEED.parse().unwrap(),
    );
    let start_ns: u64 = START.parse::<u64>().unwrap() * 1_000_000_000;
    let mut t = 0.0f64;
    for i in 0..s.len() {
        let (mut w, mut a) = ([0.0; 3], [0.0, 0.0, 9.81]);
        g.apply(&mut w, &mut a);
        assert_eq!(s.gyro_at(i), w, "gyro of message {i}");
        assert_eq!(s.acc_at(i), a, "acc of message {i}");
        let expected = start_ns + (t * 1e9).round() as u64;
        assert_eq!(s.stamp[i].as_nanos(), expected, "stamp of message {i}");
        assert_eq!(
            s.record_time[i], s.stamp[i],
            "record time = stamp, message {i}"
        );
        t += 0.005;
    }
}

#[test]
fn bad_flags_give_clear_errors() {
    let d = tempfile::tempdir().unwrap();
    let cases: &[(&[&str], &str)] = &[
        (&["bag", "--rate", "0", "-q"], "--rate must be a positive"),
        (
            &["bag", "--duration", "-5", "-q"],
            "--duration must be a positive",
        ),
        (
            &["bag", "--gyro-noise", "-1", "-q"],
            "--gyro-noise must be a non-negative",
        ),
        (
            &["bag", "--start-time", "noon", "-q"],
            "--start-time \"noon\" is not a number",
        ),
        (&["bag", "--compression", "zip"], "invalid value 'zip'"),
        (&["bag", "--preset", "extreme"], "invalid value 'extreme'"),
        (&["bag", "--motion", "circle"], "invalid value 'circle'"),
        (&["spline"], "--poses"),
        (&["spline", "--poses", "missing.tum"], "missing.tum"),
        (
            &["integrate", "--input", "nope.txt", "--no-plot"],
            "nope.txt",
        ),
        (&["traj", "--rate", "0"], "--rate must be a positive"),
    ];
    for (args, needle) in cases {
        let (success, _, err) = run_in(d.path(), args);
        assert!(!success, "sim {args:?} should fail");
        assert!(
            err.contains(needle),
            "sim {args:?}: stderr should mention {needle:?}, got:\n{err}"
        );
        assert!(!err.contains("panicked"), "sim {args:?} panicked:\n{err}");
    }
    assert!(
        !d.path().join("imu.bag").exists(),
        "no bag after a failed run"
    );
}

#[test]
fn traj_writes_the_upstream_files() {
    let d = tempfile::tempdir().unwrap();
    ok(d.path(), &["traj", "-o", "out", "--seed", SEED]);
    let o = d.path().join("out");
    let lines = |f: &str| std::fs::read_to_string(o.join(f)).unwrap().lines().count();
    assert_eq!(lines("imu_pose.txt"), 4001);
    assert_eq!(lines("imu_pose_noise.txt"), 4001);
    assert_eq!(lines("cam_pose.txt"), 600);
    assert_eq!(lines("cam_pose_tum.txt"), 600);
    assert_eq!(lines("all_points.txt"), 36);
    assert!(
        o.join("keyframe/all_points_599.txt").exists()
            && o.join("keyframe/all_lines_0.txt").exists()
    );
    let first = std::fs::read_to_string(o.join("imu_pose.txt")).unwrap();
    // docs/upstream/vio_data_simulation.md §2.1 sanity values at t = 0, as upstream prints them (%g, trailing space).
    assert_eq!(
        first.lines().next().unwrap(),
        "0 0.99875 0.0499792 0 0 20 5 5 0 0.230364 0.292623 -1.48044 0.979366 9.76099 "
    );
    let tum = std::fs::read_to_string(o.join("cam_pose_tum.txt")).unwrap();
    assert!(
        tum.lines().nth(1).unwrap().starts_with("0.033333335 "),
        "float camera grid: {}",
        tum.lines().nth(1).unwrap()
    );
}

#[test]
fn integrate_prints_the_table_and_reads_traj_files() {
    let d = tempfile::tempdir().unwrap();
    ok(d.path(), &["traj", "-o", ".", "--seed", SEED]);
    let (out, _) = ok(
        d.path(),
        &["integrate", "--input", "imu_pose.txt", "-o", "int"],
    );
    let row = |input: &str, method: &str| -> Vec<f64> {
        let l = out
            .lines()
            .find(|l| l.starts_with(input) && l.contains(method))
            .unwrap_or_else(|| panic!("no {input} {method} row in\n{out}"));
        l.split_whitespace()
            .skip(2)
            .map(|x| x.parse().unwrap())
            .collect()
    };
    // Reading the 6-digit text changes the results only in the 4th digit (docs/upstream/vio_data_simulation.md §6).
    let (e, m) = (row("clean", "euler"), row("clean", "midpoint"));
    assert!((0.9..=1.1).contains(&e[0]), "euler final {}", e[0]);
    assert!(m[0] <= 0.02, "midpoint final {}", m[0]);
    assert!(
        row("noisy", "euler")[0] > 1.0,
        "noisy file integrated: {out}"
    );
    for f in [
        "imu_int_pose.txt",
        "imu_int_pose_midpoint.txt",
        "imu_int_pose_noise.txt",
        "imu_int_pose_noise_midpoint.txt",
        "integrate_clean.png",
        "integrate_clean.svg",
    ] {
        assert!(d.path().join("int").join(f).exists(), "missing {f}");
    }
    let l = std::fs::read_to_string(d.path().join("int/imu_int_pose.txt")).unwrap();
    assert_eq!(l.lines().count(), 4000);
    assert_eq!(
        l.lines().next().unwrap().split(' ').count(),
        16,
        "15 columns and a trailing space"
    );
}

#[test]
fn spline_self_check_passes_and_from_model_writes_bag_and_text() {
    let d = tempfile::tempdir().unwrap();
    let (out, _) = ok(d.path(), &["spline", "--self-check"]);
    assert!(out.contains("PASS"), "{out}");
    let (out, _) = ok(
        d.path(),
        &[
            "spline",
            "--from-model",
            "-o",
            "s",
            "--start-time",
            START,
            "--seed",
            SEED,
            "-q",
        ],
    );
    assert!(out.contains("vs analytic model"), "{out}");
    let s = read_imu_series(
        &d.path().join("s/imu.bag"),
        "imu",
        &ReadOptions { quiet: true },
    )
    .unwrap();
    assert_eq!(s.len(), 4001);
    assert_eq!(
        std::fs::read_to_string(d.path().join("s/imu_pose.txt"))
            .unwrap()
            .lines()
            .count(),
        4001
    );
    // Round trip through a TUM file written by `sim traj` (9 decimals).
    ok(d.path(), &["traj", "-o", "t"]);
    let (out, _) = ok(
        d.path(),
        &[
            "spline",
            "--poses",
            "t/imu_pose_tum.txt",
            "-o",
            "u/x.bag",
            "--no-noise",
            "--start-time",
            START,
            "-q",
        ],
    );
    assert!(out.contains("knots: 4001"), "{out}");
    assert!(d.path().join("u/x.bag").exists() && d.path().join("u/imu_pose.txt").exists());
}

#[test]
fn time_range_and_size_are_checked_up_front() {
    let d = tempfile::tempdir().unwrap();
    // The last stamp would pass 2^32 s (and saturate, jumping back): refused, exit 2.
    let out = crate::common::sim()
        .current_dir(d.path())
        .args([
            "bag",
            "-o",
            "a.bag",
            "--start-time",
            "4294967294",
            "--duration",
            "2",
            "-q",
        ])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("32-bit ROS time"), "{err}");
    assert!(!d.path().join("a.bag").exists());
    // A job larger than the disk is refused before any work, with its size.
    let t = std::time::Instant::now();
    let out = crate::common::sim()
        .current_dir(d.path())
        .args([
            "bag",
            "-o",
            "b.bag",
            "--rate",
            "1e7",
            "--duration",
            "1e6",
            "-q",
        ])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("GB") && err.contains("free"), "{err}");
    assert!(t.elapsed().as_secs() < 30, "not refused up front");
    // A normal job states its size.
    let (_, err) = ok(d.path(), &["bag", "-o", "c.bag", "--duration", "2"]);
    assert!(err.contains("about 401 messages, about"), "{err}");
}

#[test]
fn one_error_convention() {
    let d = tempfile::tempdir().unwrap();
    let cases: [(&[&str], i32, &str); 4] = [
        (
            &["bag", "--no-such-flag"],
            2,
            "sim: error: unexpected argument",
        ),
        (
            &["bag", "-o", "x.bag", "--rate", "-1", "-q"],
            2,
            "sim: error: invalid argument: --rate must be a positive",
        ),
        (
            &["bag", "-o", "no/such/dir/x.bag", "--duration", "1", "-q"],
            1,
            "sim: error: no/such/dir/x.bag: no such file or directory",
        ),
        (&[], 2, "sim: error: "),
    ];
    for (args, code, start) in cases {
        let out = crate::common::sim()
            .current_dir(d.path())
            .args(args)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(code), "{args:?}: {err}");
        assert!(err.starts_with(start), "{args:?}: {err}");
        assert_eq!(
            err.matches("error:").count(),
            1,
            "{args:?}: printed more than once: {err}"
        );
        assert!(!err.contains("os error"), "{err}");
    }
}

use bag2mat::test_tools::temp_files_in as temps;

#[test]
fn sigterm_and_sigint_remove_temp_files() {
    let d = tempfile::tempdir().unwrap();
    for (sig, code) in [(libc::SIGTERM, 143), (libc::SIGINT, 130)] {
        let mut child = crate::common::sim()
            .current_dir(d.path())
            .args(["bag", "-o", "long.bag", "--duration", "36000", "-q"])
            .spawn()
            .unwrap();
        // Wait until the temporary bag is being written.
        let t = std::time::Instant::now();
        while temps(d.path()).is_empty() {
            assert!(t.elapsed().as_secs() < 60, "no temporary file appeared");
            std::thread::sleep(std::time::Duration::from_millis(20));
        }
        std::thread::sleep(std::time::Duration::from_millis(200));
        // SAFETY: signalling our own child by its id.
        assert_eq!(unsafe { libc::kill(child.id() as i32, sig) }, 0);
        let status = child.wait().unwrap();
        assert_eq!(status.code(), Some(code), "signal {sig}");
        assert_eq!(
            temps(d.path()),
            Vec::<String>::new(),
            "signal {sig}: temp left"
        );
        assert!(!d.path().join("long.bag").exists());
    }
}

/// A standard output that fails (a full disk: /dev/full) is an error in the one convention,
/// exit 1, never a panic (it panicked "failed printing to stdout").
#[test]
fn a_failing_standard_output_is_an_error_not_a_panic() {
    let full = std::fs::OpenOptions::new()
        .write(true)
        .open("/dev/full")
        .expect("/dev/full");
    let o = crate::common::sim()
        .args(["sensors"])
        .stdout(full)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.starts_with("sim: error: standard output:"), "{err}");
    assert!(!err.contains("panicked"), "{err}");
}
