//! The operating-noise analysis (`--reference`, `--operating`) run as a user runs it, on
//! records the tests' own writer made ([`record`]: closed-form motion and seeded noise, no
//! spline, no sim), against what was injected:
//!
//! * the operating density within [`N_REL_TOL`] of the injected white noise plus the
//!   injected lines' A²/(2 f_s), with a reference at the IMU's rate and at a motion-capture
//!   rate below it;
//! * each injected line found within [`LINE_FREQ_REL_TOL`] of its frequency;
//! * the time offset within [`OFFSET_TOL`];
//! * a static record analysed this way agreeing with the static analysis within
//!   [`STATIC_REL_TOL`].

pub mod record;

use std::path::Path;
use std::process::Command;

/// The tolerance on the operating density (the estimate's own scatter on a few
/// minutes is ~1–2 %; the rest is room for the calibration's and the spline's leftovers).
pub const N_REL_TOL: f64 = 0.10;
/// The tolerance on a line's frequency.
pub const LINE_FREQ_REL_TOL: f64 = 0.02;
/// The tolerance on the time offset, s.
pub const OFFSET_TOL: f64 = 0.5e-3;
/// The agreement of a static record analysed this way with the static analysis.
pub const STATIC_REL_TOL: f64 = 0.05;

pub fn run(args: &[&str]) -> (String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_allan_kalibr"))
        .args(args)
        .output()
        .expect("run allan_kalibr");
    let (o, e) = (
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    );
    assert!(
        out.status.success(),
        "allan_kalibr {args:?} failed:\n{o}\n{e}"
    );
    (o, e)
}

/// `allan_kalibr IMU --reference REF -o out -q` on a written record: (stdout, stderr).
pub fn analyse_against_reference(w: &record::Written, out: &Path) -> (String, String) {
    run(&[
        w.imu.to_str().unwrap(),
        "--reference",
        w.reference.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "-q",
    ])
}

/// The rows of a CSV with `#` comment lines, as (header → value) lookups.
pub fn csv_rows(path: &Path) -> Vec<Vec<(String, String)>> {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut lines = text.lines().filter(|l| !l.starts_with('#'));
    let head: Vec<String> = lines
        .next()
        .unwrap()
        .split(',')
        .map(str::to_string)
        .collect();
    lines
        .map(|l| {
            head.iter()
                .cloned()
                .zip(l.split(',').map(str::to_string))
                .collect()
        })
        .collect()
}

pub fn field<'a>(row: &'a [(String, String)], key: &str) -> &'a str {
    &row.iter()
        .find(|(k, _)| k == key)
        .unwrap_or_else(|| panic!("no column {key}"))
        .1
}

pub fn num(row: &[(String, String)], key: &str) -> f64 {
    field(row, key).parse().unwrap()
}

/// The section axis index (0–2 gyro, 3–5 acc) of a row.
pub fn axis_index(row: &[(String, String)]) -> usize {
    let base = if field(row, "sensor") == "gyroscope" {
        0
    } else {
        3
    };
    base + ["x", "y", "z"]
        .iter()
        .position(|a| *a == field(row, "axis"))
        .unwrap()
}

/// `key: value` of a flat yaml file.
pub fn yaml(path: &Path, key: &str) -> f64 {
    bag2mat::test_tools::yaml_number(&std::fs::read_to_string(path).unwrap(), key)
}

/// Runs the analysis against the reference and checks the proofs on `spec`.
fn check_against_injected(spec: &record::Spec, tag: &str) {
    let d = tempfile::tempdir().unwrap();
    let w = record::write(d.path(), spec);
    if let Ok(keep) = std::env::var("KEEP_OPERATING_RECORD") {
        let k = std::path::Path::new(&keep);
        std::fs::create_dir_all(k).unwrap();
        std::fs::copy(&w.imu, k.join("imu.csv")).unwrap();
        std::fs::copy(&w.reference, k.join("reference.tum")).unwrap();
    }
    let out = d.path().join("out");
    let (text, _) = analyse_against_reference(&w, &out);
    eprintln!("{tag}:\n{text}");
    let want = spec.expected();
    for row in csv_rows(&out.join("operating_noise.csv")) {
        let a = axis_index(&row);
        let n = num(&row, "noise_density");
        let (lo, hi) = (num(&row, "ci95_lo"), num(&row, "ci95_hi"));
        eprintln!(
            "{tag} axis {a}: N_op {n:.4e} [{lo:.4e}, {hi:.4e}] injected {:.4e} ({:+.2} %)",
            want[a],
            100.0 * (n / want[a] - 1.0)
        );
        assert!(
            (n / want[a] - 1.0).abs() < N_REL_TOL,
            "{tag} axis {a}: N_op {n:e}, injected {:e}",
            want[a]
        );
    }
    let lines = csv_rows(&out.join("operating_lines.csv"));
    for (a, f, _) in &spec.lines {
        let found = lines
            .iter()
            .filter(|r| axis_index(r) == *a)
            .map(|r| num(r, "frequency_hz"))
            .min_by(|x, y| (x - f).abs().total_cmp(&(y - f).abs()))
            .unwrap_or(f64::NAN);
        eprintln!("{tag} line axis {a}: injected {f} Hz, found {found} Hz");
        assert!(
            (found / f - 1.0).abs() < LINE_FREQ_REL_TOL,
            "{tag} axis {a}: line {f} Hz found at {found}"
        );
    }
    let dt = yaml(&out.join("operating_calibration.yaml"), "time_offset_s");
    eprintln!(
        "{tag} time offset {:.4} ms (injected {:.4} ms)",
        dt * 1e3,
        spec.ref_offset * 1e3
    );
    assert!(
        (dt - spec.ref_offset).abs() < OFFSET_TOL,
        "{tag}: offset {dt}"
    );
    for f in [
        "operating_psd.png",
        "operating_spectrogram.png",
        "operating_kalibr_imu_ieee952.yaml",
        "operating_basalt_imu_noise_ieee952.json",
    ] {
        assert!(out.join(f).exists(), "{tag}: {f}");
    }
}

#[test]
fn operating_density_offset_and_lines_against_a_reference_at_the_imu_rate() {
    check_against_injected(
        &record::Spec::handheld(200.0, 200.0, 240.0, 1),
        "200 Hz, reference 200 Hz",
    );
}

#[test]
fn operating_density_offset_and_lines_of_a_100_hz_imu() {
    check_against_injected(
        &record::Spec::handheld(100.0, 100.0, 240.0, 3),
        "100 Hz, reference 100 Hz",
    );
}

#[test]
fn operating_density_offset_and_lines_against_a_motion_capture_reference() {
    check_against_injected(
        &record::Spec::handheld(400.0, 120.0, 240.0, 2),
        "400 Hz, reference 120 Hz",
    );
}

/// Two runs of the analysis on one record write the same bytes: the calibration's sums do
/// not depend on how the threads split the work (they did, in the last digits).
#[test]
fn the_operating_analysis_writes_the_same_bytes_on_every_run() {
    let d = tempfile::tempdir().unwrap();
    let w = record::write(d.path(), &record::Spec::handheld(100.0, 100.0, 120.0, 5));
    let outs: Vec<std::path::PathBuf> = (0..RUNS_COMPARED)
        .map(|k| {
            let out = d.path().join(format!("out{k}"));
            analyse_against_reference(&w, &out);
            out
        })
        .collect();
    for f in [
        "operating_noise.csv",
        "operating_lines.csv",
        "operating_psd.csv",
    ] {
        let first = std::fs::read(outs[0].join(f)).unwrap();
        for o in &outs[1..] {
            assert!(
                std::fs::read(o.join(f)).unwrap() == first,
                "{f} differs between runs"
            );
        }
    }
}

/// Runs compared by the reproducibility test (each pair is a chance for a split of the work
/// that differs).
const RUNS_COMPARED: usize = 3;

/// The static record of the agreement test: 20 minutes at 200 Hz, white noise and random
/// walk only (what the static analysis models exactly), a tilted IMU at rest.
fn static_spec(seed: u64) -> record::Spec {
    record::Spec {
        motion: false,
        seconds: 1200.0,
        lines: Vec::new(),
        ref_rate: 100.0,
        ..record::Spec::handheld(200.0, 100.0, 1200.0, seed)
    }
}

#[test]
fn a_static_record_analysed_for_operating_noise_agrees_with_the_static_analysis() {
    let d = tempfile::tempdir().unwrap();
    let spec = static_spec(5);
    let w = record::write(d.path(), &spec);
    let imu = w.imu.to_str().unwrap();
    let dir = |s: &str| d.path().join(s).to_str().unwrap().to_string();
    run(&[imu, "-o", &dir("static"), "-q"]);
    let mut stat = [f64::NAN; 6];
    for row in csv_rows(&d.path().join("static/ieee952_terms.csv")) {
        if field(&row, "term") == "N" {
            stat[axis_index(&row)] = num(&row, "value");
        }
    }
    for (tag, extra) in [
        (
            "reference",
            vec!["--reference", w.reference.to_str().unwrap()],
        ),
        ("no reference", vec!["--operating"]),
    ] {
        let out = dir(tag);
        let mut args = vec![imu, "-o", &out, "-q"];
        args.extend(extra);
        run(&args);
        for row in csv_rows(&Path::new(&out).join("operating_noise.csv")) {
            let a = axis_index(&row);
            let n = num(&row, "noise_density");
            eprintln!(
                "static record, {tag}, axis {a}: operating {n:.4e}, static analysis {:.4e} ({:+.2} %), injected {:.4e}",
                stat[a],
                100.0 * (n / stat[a] - 1.0),
                spec.n[a / 3]
            );
            assert!(
                (n / stat[a] - 1.0).abs() < STATIC_REL_TOL,
                "{tag} axis {a}: {n:e} vs the static analysis' {:e}",
                stat[a]
            );
        }
    }
}

#[test]
fn a_moving_record_is_refused_by_default_and_the_refusal_names_the_operating_analysis() {
    let d = tempfile::tempdir().unwrap();
    let w = record::write(d.path(), &record::Spec::handheld(100.0, 100.0, 120.0, 3));
    let out = d.path().join("out");
    let (text, err) = run(&[w.imu.to_str().unwrap(), "-o", out.to_str().unwrap(), "-q"]);
    let m = bag2mat::test_tools::warnings(&err, "motion");
    assert!(
        m.len() == 1 && m[0].contains("not static") && m[0].contains("not computed"),
        "{err}"
    );
    assert!(
        m[0].contains("--reference POSES") && m[0].contains("--operating"),
        "the refusal names the operating analysis: {}",
        m[0]
    );
    assert!(!text.contains("IEEE 952 noise terms"), "{text}");
    assert!(!out.join("operating_noise.csv").exists());
}

/// The static side of the ratio: a static record of the same IMU (`--static LOG`) gives
/// `static_noise_density` equal to that record's own IEEE 952 N, the ratio is N_op over it,
/// and the static analysis' configuration files lie beside the operating ones (each saying
/// which it is); a given value (`--static-density GYRO,ACC`) is used as given. The same run
/// checks what the calibration estimated against what the writer injected.
#[test]
fn the_ratio_to_a_static_record_or_a_given_density_and_the_calibration() {
    let d = tempfile::tempdir().unwrap();
    let rest_dir = d.path().join("rest");
    let move_dir = d.path().join("moving");
    std::fs::create_dir_all(&rest_dir).unwrap();
    std::fs::create_dir_all(&move_dir).unwrap();
    let rest = record::write(
        &rest_dir,
        &record::Spec {
            seconds: 600.0,
            ..static_spec(41)
        },
    );
    let spec = record::Spec::handheld(200.0, 200.0, 150.0, 42);
    let w = record::write(&move_dir, &spec);
    let dir = |s: &str| d.path().join(s);
    // the static analysis of the static record alone
    run(&[
        rest.imu.to_str().unwrap(),
        "-o",
        dir("alone").to_str().unwrap(),
        "-q",
    ]);
    let mut stat = [f64::NAN; 6];
    for row in csv_rows(&dir("alone").join("ieee952_terms.csv")) {
        if field(&row, "term") == "N" {
            stat[axis_index(&row)] = num(&row, "value");
        }
    }
    let out = dir("out");
    let (text, _) = run(&[
        w.imu.to_str().unwrap(),
        "--reference",
        w.reference.to_str().unwrap(),
        "--static",
        rest.imu.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "-q",
    ]);
    assert!(text.contains("inflate:"), "{text}");
    let want = spec.expected();
    let mut n_max = [0.0f64; 2];
    for row in csv_rows(&out.join("operating_noise.csv")) {
        let a = axis_index(&row);
        let (n, st, r) = (
            num(&row, "noise_density"),
            num(&row, "static_noise_density"),
            num(&row, "ratio"),
        );
        assert!(
            (st / stat[a] - 1.0).abs() < PRINTED_REL_TOL,
            "axis {a}: static {st:e}, the static record's own N {:e}",
            stat[a]
        );
        assert!(
            (r / (n / st) - 1.0).abs() < PRINTED_REL_TOL,
            "axis {a}: ratio {r}"
        );
        let (rl, rh) = (num(&row, "ratio_ci95_lo"), num(&row, "ratio_ci95_hi"));
        assert!(rl < r && r < rh, "axis {a}: ratio {r} [{rl}, {rh}]");
        // the measured inflation factor against the injected one
        let truth = want[a] / spec.n[a / 3];
        assert!(
            (r / truth - 1.0).abs() < N_REL_TOL + STATIC_REL_TOL,
            "axis {a}: ratio {r}, injected {truth}"
        );
        n_max[a / 3] = n_max[a / 3].max(n);
    }
    // the configuration files: the operating values (the largest axis) in operating_*, the
    // static record's own analysis' values (its configuration file's) in static_* beside
    // them, each saying which it is
    let op_file = out.join("operating_kalibr_imu_ieee952.yaml");
    let st_file = out.join("static_kalibr_imu_ieee952.yaml");
    let alone = dir("alone").join("kalibr_imu_ieee952.yaml");
    let (alone_g, alone_a) = (
        yaml(&alone, "gyroscope_noise_density"),
        yaml(&alone, "accelerometer_noise_density"),
    );
    for (file, want_g, want_a, says) in [
        (&op_file, n_max[0], n_max[1], "OPERATING-CONDITION VALUES"),
        (&st_file, alone_g, alone_a, "IEEE 952"),
    ] {
        let g = yaml(file, "gyroscope_noise_density");
        let a = yaml(file, "accelerometer_noise_density");
        assert!(
            (g / want_g - 1.0).abs() < CONFIG_REL_TOL && (a / want_a - 1.0).abs() < CONFIG_REL_TOL,
            "{}: {g:e} {a:e} vs {want_g:e} {want_a:e}",
            file.display()
        );
        let t = std::fs::read_to_string(file).unwrap();
        assert!(t.contains(says), "{}", file.display());
    }
    assert!(
        !std::fs::read_to_string(&st_file)
            .unwrap()
            .contains("OPERATING-CONDITION"),
        "the static file is not labelled operating"
    );
    // what a calibration would estimate, against what was injected (the writer's maps:
    // A = (I + S) R with S symmetric, so S is exactly the injected scale/misalignment)
    let cal = out.join("operating_calibration.yaml");
    let sym = |s: f64, m: f64| {
        [
            s,
            m,
            -0.5 * m,
            m,
            -0.5 * s,
            0.7 * m,
            -0.5 * m,
            0.7 * m,
            0.7 * s,
        ]
    };
    for (name, injected) in [
        ("gyro", sym(spec.scale, spec.misalign)),
        ("acc", sym(-0.8 * spec.scale, 1.3 * spec.misalign)),
    ] {
        let got = yaml_list(&cal, &format!("{name}_scale_misalignment"));
        let se = yaml_list(&cal, &format!("{name}_scale_misalignment_std_err"));
        for k in 0..9 {
            eprintln!(
                "{name} S[{k}]: {:+.5} ± {:.5} (injected {:+.5})",
                got[k], se[k], injected[k]
            );
            assert!(
                (got[k] - injected[k]).abs() < CALIBRATION_SE * se[k] + CALIBRATION_ABS,
                "{name} scale/misalignment [{k}]: {} ± {}, injected {}",
                got[k],
                se[k],
                injected[k]
            );
        }
        assert!(
            text_of(&cal).contains(&format!("{name}_scale_misalignment_excited: true")),
            "{name}: the hand-held motion excites scale and misalignment"
        );
    }
    let lever = yaml_list(&cal, "lever_arm_m");
    for (k, (got, inj)) in lever.iter().zip(spec.lever).enumerate() {
        assert!(
            (got - inj).abs() < LEVER_TOL,
            "lever arm [{k}]: {got} vs {inj}"
        );
    }
    let gs = yaml_list(&cal, "gyro_g_sensitivity_rad_s_per_m_s2");
    for k in [0, 4, 8] {
        assert!(
            (gs[k] - spec.g_sens).abs() < CALIBRATION_ABS,
            "g-sensitivity [{k}]: {} vs {}",
            gs[k],
            spec.g_sens
        );
    }
    // a given static value is used as it is given
    let out2 = dir("given");
    run(&[
        w.imu.to_str().unwrap(),
        "--reference",
        w.reference.to_str().unwrap(),
        "--static-density",
        "1e-3,1.5e-2",
        "-o",
        out2.to_str().unwrap(),
        "-q",
    ]);
    for row in csv_rows(&out2.join("operating_noise.csv")) {
        let a = axis_index(&row);
        let given = [1e-3, 1.5e-2][a / 3];
        assert_eq!(num(&row, "static_noise_density"), given, "axis {a}");
        let r = num(&row, "ratio");
        assert!(
            (r / (num(&row, "noise_density") / given) - 1.0).abs() < PRINTED_REL_TOL,
            "axis {a}: ratio {r}"
        );
    }
    assert!(!out2.join("static_kalibr_imu_ieee952.yaml").exists());
}

/// Numbers printed to the CSVs round-trip; ratios of printed numbers agree to this.
const PRINTED_REL_TOL: f64 = 1e-9;
/// The configuration files print 6 significant digits or more.
const CONFIG_REL_TOL: f64 = 1e-5;
/// A calibrated term within this many of its stated standard errors …
const CALIBRATION_SE: f64 = 4.0;
/// … plus this (0.02 % of scale, 0.2 mrad, 2e-5 rad/s per m/s²: a tenth of the smallest
/// injected error, room for what the spline leaves in the prediction).
const CALIBRATION_ABS: f64 = 2e-4;
/// The lever arm within 5 mm (a hand-held motion's angular accelerations of a few rad/s²
/// make a few mm visible).
const LEVER_TOL: f64 = 5e-3;

fn text_of(path: &Path) -> String {
    std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// `key: [a, b, c]` of a flat yaml file.
fn yaml_list(path: &Path, key: &str) -> Vec<f64> {
    let text = std::fs::read_to_string(path).unwrap();
    let line = text
        .lines()
        .find_map(|l| l.strip_prefix(&format!("{key}:")))
        .unwrap_or_else(|| panic!("{}: no {key}", path.display()));
    line.trim()
        .trim_start_matches('[')
        .trim_end_matches(']')
        .split(',')
        .map(|v| v.trim().parse().unwrap())
        .collect()
}

/// `sim bag --motion handheld --reference-out` writes a record with its truth; analysed
/// with that reference (a 120 Hz motion capture with its noise, under a 400 Hz IMU with
/// its mounting errors), the operating densities, the lines and the offset match the
/// truth file's, and each line says where it lands for an estimator reading the IMU at
/// 100 Hz (`--estimator-rate`).
#[test]
fn a_sim_bag_with_its_reference_is_analysed_to_its_truth() {
    let d = tempfile::tempdir().unwrap();
    let spec = d.path().join("spec.yaml");
    std::fs::write(
        &spec,
        "gyroscope:\n  white_noise: 1.0e-3\n  random_walk: 2.0e-5\n  axes:\n    z: {lines: [{frequency_hz: 29, amplitude: 4.0e-3}]}\naccelerometer:\n  white_noise: 1.5e-2\n  random_walk: 3.0e-4\n  lines: [{frequency_hz: 53, amplitude: 4.0e-2}]\n",
    )
    .unwrap();
    let bag = d.path().join("hand.bag");
    let reference = d.path().join("hand.tum");
    crate::common::sim_bag(&[
        "-o",
        bag.to_str().unwrap(),
        "--motion",
        "handheld",
        "--rate",
        "400",
        "--duration",
        "180",
        "--start-time",
        "1700000000",
        "--seed",
        "11",
        "--noise-spec",
        spec.to_str().unwrap(),
        "--reference-out",
        reference.to_str().unwrap(),
        "--reference-rate",
        "120",
        "--reference-offset",
        "0.0035",
        "--reference-noise",
        "1e-4,3e-4",
        "--imu-rotation",
        "3,-2,90",
        "--lever-arm",
        "0.04,-0.02,0.03",
        "--scale-error",
        "0.005",
        "--misalignment",
        "0.003",
        "--g-sensitivity",
        "2e-4",
        "-q",
    ]);
    let truth = sim::reference_truth_path(&reference);
    let want: Vec<f64> = yaml_list(&truth, "gyroscope_operating_noise_density")
        .into_iter()
        .chain(yaml_list(&truth, "accelerometer_operating_noise_density"))
        .collect();
    let out = d.path().join("out");
    let (text, _) = run(&[
        bag.to_str().unwrap(),
        "--reference",
        reference.to_str().unwrap(),
        "--estimator-rate",
        "100",
        "-o",
        out.to_str().unwrap(),
        "-q",
    ]);
    eprintln!("{text}");
    for row in csv_rows(&out.join("operating_noise.csv")) {
        let a = axis_index(&row);
        let n = num(&row, "noise_density");
        eprintln!(
            "sim bag axis {a}: N_op {n:.4e}, truth {:.4e} ({:+.2} %)",
            want[a],
            100.0 * (n / want[a] - 1.0)
        );
        assert!(
            (n / want[a] - 1.0).abs() < N_REL_TOL,
            "axis {a}: {n:e} vs {:e}",
            want[a]
        );
    }
    let lines = csv_rows(&out.join("operating_lines.csv"));
    for (a, f) in [(2usize, 29.0), (3, 53.0), (4, 53.0), (5, 53.0)] {
        assert!(
            lines.iter().any(|r| axis_index(r) == a
                && (num(r, "frequency_hz") / f - 1.0).abs() < LINE_FREQ_REL_TOL),
            "axis {a}: no line at {f} Hz"
        );
    }
    // an estimator reading this 400 Hz IMU at 100 Hz: the 53 Hz lines fold to 47 Hz, the
    // 29 Hz line stays where it is (below the estimator's 50 Hz Nyquist frequency)
    for r in &lines {
        let f = num(r, "frequency_hz");
        let al = num(r, "alias_hz");
        if (f / 53.0 - 1.0).abs() < LINE_FREQ_REL_TOL {
            assert!((al - (100.0 - f)).abs() < 1e-9, "{f} Hz aliases to {al}");
        } else if f < 50.0 {
            assert!(al.is_nan(), "{f} Hz does not alias: {al}");
        }
    }
    assert!(text.contains("aliases to 47."), "{text}");
    let dt = yaml(&out.join("operating_calibration.yaml"), "time_offset_s");
    assert!(
        (dt - yaml(&truth, "time_offset_s")).abs() < OFFSET_TOL,
        "offset {dt}"
    );
}

/// The reference as a bag's `geometry_msgs/PoseStamped` topic (ROS 1 and ROS 2 MCAP,
/// written by rosbags, an independent writer, from the tests' own TUM file), and the IMU
/// and reference as an EuRoC/ASL dataset (`mav0/imu0`, `mav0/state_groundtruth_estimate0`)
/// given by its root: the same proofs hold.
#[test]
fn the_reference_as_a_bag_topic_and_as_an_euroc_ground_truth() {
    let d = tempfile::tempdir().unwrap();
    let spec = record::Spec::handheld(200.0, 100.0, 150.0, 21);
    let w = record::write(d.path(), &spec);
    let want = spec.expected();
    let check = |out: &Path, tag: &str| {
        for row in csv_rows(&out.join("operating_noise.csv")) {
            let a = axis_index(&row);
            let n = num(&row, "noise_density");
            assert!(
                (n / want[a] - 1.0).abs() < N_REL_TOL,
                "{tag} axis {a}: {n:e} vs {:e}",
                want[a]
            );
        }
        let dt = yaml(&out.join("operating_calibration.yaml"), "time_offset_s");
        assert!(
            (dt - spec.ref_offset).abs() < OFFSET_TOL,
            "{tag}: offset {dt}"
        );
    };
    let script = bag2mat::test_tools::workspace().join("crates/bag2mat/tests/py/pose_bags.py");
    for kind in ["ros1", "mcap"] {
        let bag = d.path().join(if kind == "ros1" {
            "ref.bag"
        } else {
            "ref_mcap"
        });
        bag2mat::test_tools::run_ok(
            Command::new(bag2mat::test_tools::venv_python())
                .arg(&script)
                .arg(kind)
                .arg(&bag)
                .arg("--from-tum")
                .arg(&w.reference),
        );
        let out = d.path().join(format!("out_{kind}"));
        let (text, _) = run(&[
            w.imu.to_str().unwrap(),
            "--reference",
            bag.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
            "-q",
        ]);
        assert!(
            text.contains("topic '/mocap/body' (geometry_msgs"),
            "{text}"
        );
        check(&out, kind);
    }
    // EuRoC/ASL: the IMU's data.csv and the ground truth (w first, ns) in a dataset folder
    let root = d.path().join("MH_test");
    let imu_dir = root.join("mav0/imu0");
    let gt_dir = root.join("mav0/state_groundtruth_estimate0");
    std::fs::create_dir_all(&imu_dir).unwrap();
    std::fs::create_dir_all(&gt_dir).unwrap();
    std::fs::copy(&w.imu, imu_dir.join("data.csv")).unwrap();
    let mut gt = String::from(
        "#timestamp, p_RS_R_x [m], p_RS_R_y [m], p_RS_R_z [m], q_RS_w [], q_RS_x [], q_RS_y [], q_RS_z []\n",
    );
    for line in std::fs::read_to_string(&w.reference).unwrap().lines() {
        let f: Vec<&str> = line.split_whitespace().collect();
        if f.is_empty() || f[0].starts_with('#') {
            continue;
        }
        let (sec, frac) = f[0].split_once('.').unwrap();
        let ns: i64 = sec.parse::<i64>().unwrap() * 1_000_000_000 + frac.parse::<i64>().unwrap();
        gt.push_str(&format!(
            "{ns},{},{},{},{},{},{},{}\n",
            f[1], f[2], f[3], f[7], f[4], f[5], f[6]
        ));
    }
    std::fs::write(gt_dir.join("data.csv"), gt).unwrap();
    let out = d.path().join("out_euroc");
    let (text, _) = run(&[
        root.to_str().unwrap(),
        "--topic",
        "imu0",
        "--reference",
        root.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "-q",
    ]);
    assert!(text.contains("EuRoC/ASL ground truth"), "{text}");
    check(&out, "euroc");
}

/// Flags that cannot run are usage errors (exit 2) that say why; a reference that cannot
/// be used is an error (exit 1) naming it; nothing is written.
#[test]
fn operating_flags_and_references_that_cannot_run() {
    let d = tempfile::tempdir().unwrap();
    let w = record::write(d.path(), &record::Spec::handheld(100.0, 100.0, 60.0, 4));
    let imu = w.imu.to_str().unwrap();
    let out = d.path().join("o");
    let o = out.to_str().unwrap();
    let fail = |args: &[&str], code: i32, says: &str| {
        let r = Command::new(env!("CARGO_BIN_EXE_allan_kalibr"))
            .args(args)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&r.stderr);
        assert_eq!(r.status.code(), Some(code), "{args:?}: {err}");
        assert!(err.contains(says), "{args:?}: {err}");
        assert!(!err.contains("panicked"), "{err}");
    };
    fail(
        &[imu, "--static", imu, "-o", o],
        2,
        "--reference or --operating",
    );
    fail(
        &[imu, "--band", "1:50", "-o", o],
        2,
        "--reference or --operating",
    );
    fail(
        &[imu, "--operating", "--band", "50:1", "-o", o],
        2,
        "LO must be below HI",
    );
    fail(
        &[imu, "--operating", "--static-density", "x", "-o", o],
        2,
        "--static-density",
    );
    fail(
        &[
            imu,
            "--operating",
            "--reference",
            w.reference.to_str().unwrap(),
            "-o",
            o,
        ],
        2,
        "cannot be used with",
    );
    fail(
        &[imu, "--operating", "--compat-only", "-o", o],
        2,
        "--compat-only",
    );
    let missing = d.path().join("missing.tum");
    fail(
        &[imu, "--reference", missing.to_str().unwrap(), "-o", o],
        1,
        "missing.tum",
    );
    // a reference on another clock: no overlap within --max-offset
    let shifted = d.path().join("shifted.tum");
    let text: String = std::fs::read_to_string(&w.reference)
        .unwrap()
        .lines()
        .map(|l| match l.split_once(' ') {
            Some((t, rest)) if !l.starts_with('#') => {
                let (s, f) = t.split_once('.').unwrap();
                format!("{}.{f} {rest}\n", s.parse::<i64>().unwrap() - 5000)
            }
            _ => format!("{l}\n"),
        })
        .collect();
    std::fs::write(&shifted, text).unwrap();
    fail(
        &[imu, "--reference", shifted.to_str().unwrap(), "-o", o],
        1,
        "overlap",
    );
    assert!(!out.exists(), "nothing is written");
}

/// A flight log without a reference, written by the test itself: 90 s on the ground with
/// the motors off, 60 s with them idling (a rotor line at 62 Hz on the accelerometer, no
/// motion), 120 s of flight (the hand-held motion, the rotor line moved to 81 Hz with the
/// throttle). The analysis finds the three phases in order with each phase's line, takes
/// the static value from the still stretch, and counts the rotor line as operating noise.
#[test]
fn a_flight_log_by_phase_without_a_reference() {
    use rand::SeedableRng;
    use rand_distr::{Distribution, StandardNormal};
    let d = tempfile::tempdir().unwrap();
    let rate = 400.0;
    let (still, idle, fly) = (90.0, 60.0, 120.0);
    let (ng, na) = (1.5e-3, 1.8e-2);
    let mut rng = rand::rngs::StdRng::seed_from_u64(33);
    let mut n = || -> f64 { StandardNormal.sample(&mut rng) };
    let mut csv = String::from(
        "#timestamp [ns],w_RS_S_x [rad s^-1],w_RS_S_y [rad s^-1],w_RS_S_z [rad s^-1],a_RS_S_x [m s^-2],a_RS_S_y [m s^-2],a_RS_S_z [m s^-2]\n",
    );
    let count = ((still + idle + fly) * rate) as usize;
    for k in 0..count {
        let t = k as f64 / rate;
        let (w, f, line) = if t < still {
            (
                nalgebra::Vector3::zeros(),
                nalgebra::Vector3::new(0.0, 0.0, record::G),
                None,
            )
        } else if t < still + idle {
            (
                nalgebra::Vector3::zeros(),
                nalgebra::Vector3::new(0.0, 0.0, record::G),
                Some(62.0),
            )
        } else {
            let (_, _, w, f) = record::body(t - still - idle, true);
            (w, f, Some(81.0))
        };
        let mut v = [w.x, w.y, w.z, f.x, f.y, f.z];
        for (a, x) in v.iter_mut().enumerate() {
            *x += if a < 3 { ng } else { na } * rate.sqrt() * n();
        }
        if let Some(fl) = line {
            v[3] += 0.5 * (2.0 * std::f64::consts::PI * fl * t).sin();
            v[4] += 0.3 * (2.0 * std::f64::consts::PI * fl * t + 1.0).sin();
        }
        csv.push_str(&format!(
            "{},{:e},{:e},{:e},{:e},{:e},{:e}\n",
            record::T0_NS + (t * 1e9).round() as i64,
            v[0],
            v[1],
            v[2],
            v[3],
            v[4],
            v[5]
        ));
    }
    let imu = d.path().join("flight.csv");
    std::fs::write(&imu, csv).unwrap();
    let out = d.path().join("out");
    let (text, _) = run(&[
        imu.to_str().unwrap(),
        "--operating",
        "-o",
        out.to_str().unwrap(),
        "-q",
    ]);
    eprintln!("{text}");
    let phases = csv_rows(&out.join("operating_phases.csv"));
    let mut kinds: Vec<(String, f64, f64)> = Vec::new();
    for r in &phases {
        let k = (
            field(r, "kind").to_string(),
            num(r, "t_start_s"),
            num(r, "t_end_s"),
        );
        if kinds.last() != Some(&k) {
            kinds.push(k);
        }
    }
    let names: Vec<&str> = kinds.iter().map(|k| k.0.as_str()).collect();
    assert_eq!(names, ["still", "vibrating", "moving"], "{kinds:?}");
    // the phase boundaries within a spectrogram window (2 s) of the truth
    assert!(
        (kinds[1].1 - still).abs() < 2.5 && (kinds[2].1 - still - idle).abs() < 2.5,
        "{kinds:?}"
    );
    let line_of = |kind: &str| -> Vec<f64> {
        phases
            .iter()
            .filter(|r| field(r, "kind") == kind && axis_index(r) == 3)
            .flat_map(|r| {
                field(r, "lines")
                    .split(';')
                    .filter(|s| !s.is_empty())
                    .map(|s| s.split(':').next().unwrap().parse::<f64>().unwrap())
                    .collect::<Vec<_>>()
            })
            .collect()
    };
    assert!(
        line_of("vibrating")
            .iter()
            .any(|f| (f / 62.0 - 1.0).abs() < LINE_FREQ_REL_TOL),
        "{:?}",
        line_of("vibrating")
    );
    assert!(
        line_of("moving")
            .iter()
            .any(|f| (f / 81.0 - 1.0).abs() < LINE_FREQ_REL_TOL),
        "{:?}",
        line_of("moving")
    );
    assert!(line_of("still").is_empty(), "{:?}", line_of("still"));
    // the static value from the still stretch, and the rotor line in the operating density
    assert!(text.contains("still stretch"), "{text}");
    for row in csv_rows(&out.join("operating_noise.csv")) {
        let a = axis_index(&row);
        let st = num(&row, "static_noise_density");
        let nd = if a < 3 { ng } else { na };
        assert!((st / nd - 1.0).abs() < N_REL_TOL, "axis {a}: static {st:e}");
        if a == 3 {
            assert!(
                num(&row, "ratio") > 1.05,
                "the rotor line lifts acc x: {row:?}"
            );
        }
    }
}
