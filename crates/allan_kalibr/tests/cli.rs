//! The `allan_kalibr` binary run as a user would: on a bag, on a .mat, and on bad inputs
//! (clear error, non-zero exit, no output file left behind).

use std::path::Path;
use std::process::{Command, Output};

use allan_kalibr::load_input;
use bag2mat::{DataImu, write_data_imu};

use crate::common::{CASES, final_full, process_lines, rel_err};

/// The four numbers read back from imu.yaml: they are written in shortest round-trip form,
/// so they carry the run's value exactly; vs the reference the 1e-9 of docs/upstream/kalibr_allan.md §7 applies.
const NUMBERS_REL_TOL: f64 = 1e-9;
/// The outputs a successful run writes.
const OUTPUTS: [&str; 6] = [
    "imu.yaml",
    "allan_curves.csv",
    "allan_accel.png",
    "allan_accel.svg",
    "allan_gyro.png",
    "allan_gyro.svg",
];

fn run(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_allan_kalibr"))
        .args(args)
        .output()
        .expect("run allan_kalibr")
}

fn s(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

fn yaml_value(text: &str, key: &str) -> f64 {
    bag2mat::test_tools::yaml_number(text, key)
}

fn assert_no_outputs(dir: &Path) {
    if dir.exists() {
        let left: Vec<_> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        assert!(
            left.is_empty(),
            "outputs left behind in {}: {left:?}",
            dir.display()
        );
    }
}

/// The line that opens the IEEE 952 section after upstream's text.
const IEEE_MARKER: &str = "\n=> IEEE 952 noise terms";
/// What the IEEE 952 section writes beside the compat outputs.
const IEEE_OUTPUTS: [&str; 15] = [
    "ieee952_terms.csv",
    "ieee952_curves.csv",
    "ieee952_psd.csv",
    "kalibr_imu_ieee952.yaml",
    "vins_imu_ieee952.yaml",
    "orbslam3_imu_ieee952.yaml",
    "openvins_kalibr_imu_chain_ieee952.yaml",
    "basalt_imu_noise_ieee952.json",
    "px4_ekf2_ieee952.params",
    "ardupilot_ekf3_ieee952.param",
    "gtsam_imu_params_ieee952.yaml",
    "ieee952_allan.png",
    "ieee952_allan.svg",
    "ieee952_psd.png",
    "ieee952_psd.svg",
];

/// p3 (uncompressed, 61 s): stdout is upstream's text, imu.yaml holds the four numbers.
#[test]
fn bag_input_prints_upstream_text_and_writes_outputs() {
    let case = &CASES[2];
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("out");
    let o = run(&[
        case.bag().to_str().unwrap(),
        "--topic",
        case.topic,
        "-o",
        out.to_str().unwrap(),
        "--title",
        "p3",
    ]);
    assert!(o.status.success(), "stderr: {}", s(&o.stderr));
    // Upstream's text comes first, unchanged; the IEEE 952 section follows it.
    let full = s(&o.stdout);
    let at = full
        .find(IEEE_MARKER)
        .unwrap_or_else(|| panic!("no IEEE 952 section:\n{full}"));
    assert!(
        full[at..].contains("accelerometer_noise_density = "),
        "{}",
        &full[at..]
    );
    for f in IEEE_OUTPUTS {
        assert!(out.join(f).exists(), "{f} missing");
    }
    let stdout = full[..at].to_string();
    let lines: Vec<&str> = stdout.lines().collect();
    assert_eq!(lines[0], "=> opening the mat file.");
    assert_eq!(lines[1], "=> plotting accelerometer.");
    assert_eq!(lines[6], "=> plotting gyroscope.");
    assert_eq!(lines[11], "=> final results");
    let chart: Vec<String> = lines[2..6]
        .iter()
        .chain(&lines[7..11])
        .map(|l| l.to_string())
        .collect();
    assert_eq!(chart, process_lines(case));
    let fin: Vec<&str> = lines[12..].to_vec();
    assert_eq!(fin.join("\n"), case.kalibr("final.txt").trim_end());
    // The estimated rate is announced on stderr.
    assert!(
        s(&o.stderr).contains("update rate: 200 Hz"),
        "stderr: {}",
        s(&o.stderr)
    );
    for f in OUTPUTS {
        let p = out.join(f);
        let len = std::fs::metadata(&p).map(|m| m.len()).unwrap_or(0);
        assert!(len > 0, "{} missing or empty", p.display());
    }
    let yaml = std::fs::read_to_string(out.join("imu.yaml")).unwrap();
    let want = final_full(case).values;
    let keys = [
        "accelerometer_noise_density",
        "accelerometer_random_walk",
        "gyroscope_noise_density",
        "gyroscope_random_walk",
    ];
    for (k, key) in keys.iter().enumerate() {
        let got = yaml_value(&yaml, key);
        let e = rel_err(got, want[k]);
        assert!(
            e <= NUMBERS_REL_TOL,
            "{}: {key} expected {:e} actual {got:e} rel {e:e} tol {NUMBERS_REL_TOL:e}",
            case.name,
            want[k]
        );
    }
    assert!(yaml.contains("rostopic:                    imu "), "{yaml}");
    assert!(
        yaml.contains("update_rate:                 200.0"),
        "{yaml}"
    );
    let csv = std::fs::read_to_string(out.join("allan_curves.csv")).unwrap();
    assert_eq!(csv.lines().count(), 2001);
    // No temporary files remain.
    let names: Vec<String> = std::fs::read_dir(&out)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(names.len(), OUTPUTS.len() + IEEE_OUTPUTS.len(), "{names:?}");
}

/// The same samples as a .mat (written through bag2mat) give the same text; `--bit-exact`
/// runs; a wrong `--update-rate` is used but warned about.
#[test]
fn mat_input_matches_bag_input() {
    let case = &CASES[2];
    let d = load_input(&case.bag(), case.topic, true).unwrap();
    let tmp = tempfile::tempdir().unwrap();
    let mat = tmp.path().join("p3.mat");
    let mut m = DataImu::with_capacity(d.len());
    for i in 0..d.len() {
        m.push([
            d.t[i],
            d.axes[0][i],
            d.axes[1][i],
            d.axes[2][i],
            d.axes[3][i],
            d.axes[4][i],
            d.axes[5][i],
        ]);
    }
    write_data_imu(&bag2mat::shared::output::Outputs::direct(), &mat, &m).unwrap();
    // Default output folder: <stem>_allan_kalibr/ beside the input (issue 21: never the data
    // folder itself).
    let o = run(&[
        mat.to_str().unwrap(),
        "--update-rate",
        "200",
        "--bit-exact",
        "--compat-only",
        "-q",
    ]);
    assert!(o.status.success(), "stderr: {}", s(&o.stderr));
    let chart: Vec<String> = s(&o.stdout)
        .lines()
        .filter(|l| l.starts_with("tau = ") || l.starts_with("h_fit"))
        .map(str::to_owned)
        .collect();
    assert_eq!(chart, process_lines(case));
    assert!(s(&o.stdout).ends_with(&case.kalibr("final.txt")));
    let default_out = mat.with_file_name(format!(
        "{}_allan_kalibr",
        mat.file_stem().unwrap().to_string_lossy()
    ));
    for f in OUTPUTS {
        assert!(default_out.join(f).exists(), "{f} not in {default_out:?}");
        assert!(
            !tmp.path().join(f).exists(),
            "{f} written into the data folder"
        );
    }
    let warn = run(&[
        mat.to_str().unwrap(),
        "--update-rate",
        "100",
        "-o",
        tmp.path().join("w").to_str().unwrap(),
    ]);
    assert!(warn.status.success(), "stderr: {}", s(&warn.stderr));
    assert!(
        s(&warn.stderr)
            .contains("warning: update rate: --update-rate 100 Hz but the stamps give 200"),
        "stderr: {}",
        s(&warn.stderr)
    );
}

#[test]
fn missing_file_is_a_clear_error() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("out");
    for input in ["nope.bag", "nope.mat"] {
        let p = tmp.path().join(input);
        let o = run(&[p.to_str().unwrap(), "-o", out.to_str().unwrap()]);
        assert!(!o.status.success());
        let err = s(&o.stderr);
        assert!(
            err.contains(input) && err.contains("error"),
            "{input}: {err}"
        );
        assert!(!err.contains("panicked"), "{err}");
        assert_no_outputs(&out);
    }
}

#[test]
fn unknown_extension_and_wrong_topic_are_clear_errors() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("out");
    let txt = tmp.path().join("data.txt");
    std::fs::write(&txt, "1 2 3\n").unwrap();
    let o = run(&[txt.to_str().unwrap(), "-o", out.to_str().unwrap()]);
    assert!(!o.status.success());
    // numbers in a text file are a text log (issue 20): the error says what to add
    assert!(
        s(&o.stderr).contains("no header line naming its 3 columns: give them with --columns"),
        "{}",
        s(&o.stderr)
    );
    let bin = tmp.path().join("data.bin");
    std::fs::write(&bin, [0u8, 7, 200, 1]).unwrap();
    let o = run(&[bin.to_str().unwrap(), "-o", out.to_str().unwrap()]);
    assert!(!o.status.success());
    assert!(
        s(&o.stderr).contains("expected a .mat file or a bag"),
        "{}",
        s(&o.stderr)
    );
    // p2's bag holds /imu/data and /status: asking for `imu0` lists both.
    let bag = CASES[1].bag();
    let o = run(&[
        bag.to_str().unwrap(),
        "--topic",
        "imu0",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(!o.status.success());
    let err = s(&o.stderr);
    assert!(
        err.contains("imu0") && err.contains("/imu/data") && err.contains("/status"),
        "{err}"
    );
    assert_no_outputs(&out);
}

/// Upstream crashes (log10 of 0 or of a negative taumax) on 0, 1 or 2 samples; we say why.
#[test]
fn empty_and_too_short_inputs_are_clear_errors() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("out");
    for n in [0usize, 1, 2] {
        let mat = tmp.path().join(format!("n{n}.mat"));
        let mut m = DataImu::with_capacity(n);
        for i in 0..n {
            m.push([i as f64 * 0.005, 0.1, 0.2, 9.8, 0.01, 0.02, 0.03]);
        }
        write_data_imu(&bag2mat::shared::output::Outputs::direct(), &mat, &m).unwrap();
        let o = run(&[
            mat.to_str().unwrap(),
            "--update-rate",
            "200",
            "-o",
            out.to_str().unwrap(),
        ]);
        assert!(!o.status.success(), "n={n}");
        let err = s(&o.stderr);
        assert!(
            err.contains("too few samples") && err.contains(&format!(": {n} ")),
            "n={n}: {err}"
        );
        assert_no_outputs(&out);
    }
    // Three samples are enough for a (useless but defined) run.
    let mat = tmp.path().join("n3.mat");
    let mut m = DataImu::with_capacity(3);
    for i in 0..3 {
        m.push([
            i as f64 * 0.005,
            0.1 * i as f64,
            0.2,
            9.8,
            0.01,
            0.02,
            0.03 * i as f64,
        ]);
    }
    write_data_imu(&bag2mat::shared::output::Outputs::direct(), &mat, &m).unwrap();
    let o = run(&[mat.to_str().unwrap(), "-o", out.to_str().unwrap()]);
    assert!(o.status.success(), "n=3: {}", s(&o.stderr));
}

#[test]
fn non_finite_samples_are_a_clear_error() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("out");
    let mat = tmp.path().join("nan.mat");
    let mut m = DataImu::with_capacity(100);
    for i in 0..100 {
        let wy = if i == 41 { f64::NAN } else { 0.02 };
        m.push([i as f64 * 0.01, 0.1, 0.2, 9.8, 0.01, wy, 0.03]);
    }
    write_data_imu(&bag2mat::shared::output::Outputs::direct(), &mat, &m).unwrap();
    let o = run(&[mat.to_str().unwrap(), "-o", out.to_str().unwrap()]);
    assert!(!o.status.success());
    assert!(
        s(&o.stderr).contains("sample 42 of wy is NaN"),
        "{}",
        s(&o.stderr)
    );
    assert_no_outputs(&out);
}

/// A small .mat of white noise at 100 Hz (seeded LCG), `n` rows.
fn noise_mat(path: &Path, n: usize) {
    noise_mat_seeded(path, n, 0x5EED);
}

/// [`noise_mat`] from another seed of the LCG.
pub fn noise_mat_seeded(path: &Path, n: usize, seed: u64) {
    let mut d = DataImu::with_capacity(n);
    let mut s: u64 = seed;
    let mut next = || {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((s >> 11) as f64 / (1u64 << 53) as f64) - 0.5
    };
    for i in 0..n {
        d.push([
            1.7e9 + i as f64 * 0.01,
            next(),
            next(),
            9.81 + next(),
            next() * 1e-3,
            next() * 1e-3,
            next() * 1e-3,
        ]);
    }
    write_data_imu(&bag2mat::shared::output::Outputs::direct(), path, &d).unwrap();
}

#[test]
fn one_error_convention() {
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("missing.bag");
    let m = missing.to_str().unwrap();
    let cases: [(Vec<&str>, i32, String); 4] = [
        (
            vec![m],
            1,
            format!("allan_kalibr: error: {m}: no such file or directory"),
        ),
        (
            vec!["--no-such-flag"],
            2,
            "allan_kalibr: error: unexpected argument".into(),
        ),
        (
            vec![m, "--update-rate", "-1"],
            2,
            "allan_kalibr: error: invalid value '-1'".into(),
        ),
        (vec![], 2, "allan_kalibr: error: ".into()),
    ];
    for (args, code, start) in cases {
        let out = run(&args);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(code), "{args:?}: {err}");
        assert!(err.starts_with(&start), "{args:?}: {err}");
        assert_eq!(err.matches("error:").count(), 1, "{args:?}: {err}");
        assert!(!err.contains("os error"), "{err}");
    }
    let out = run(&[m, "--update-rate", "-1"]);
    assert!(String::from_utf8_lossy(&out.stderr).contains("must be positive"));
}

#[test]
fn update_rate_range_is_validated() {
    let dir = tempfile::tempdir().unwrap();
    let mat = dir.path().join("n.mat");
    noise_mat(&mat, 2000);
    for r in ["1e-300", "0", "inf", "1e12"] {
        let out = run(&[mat.to_str().unwrap(), "--update-rate", r, "-q"]);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "--update-rate {r}: {err}");
        assert!(err.starts_with("allan_kalibr: error:"), "{err}");
    }
}

#[test]
fn quiet_prints_only_errors_and_warnings() {
    let dir = tempfile::tempdir().unwrap();
    let mat = dir.path().join("n.mat");
    noise_mat(&mat, 2000);
    let out = run(&[
        mat.to_str().unwrap(),
        "--update-rate",
        "100",
        "-q",
        "--compat-only",
        "-o",
        dir.path().join("o").to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    assert!(
        err.lines()
            .all(|l| l.starts_with("warning") || l.contains("error")),
        "--quiet printed: {err}"
    );
}

#[test]
fn outputs_are_all_or_none() {
    let dir = tempfile::tempdir().unwrap();
    let mat = dir.path().join("n.mat");
    noise_mat(&mat, 2000);
    let o = dir.path().join("o");
    std::fs::create_dir_all(o.join("allan_gyro.svg/in_the_way")).unwrap();
    let out = run(&[
        mat.to_str().unwrap(),
        "--update-rate",
        "100",
        "-q",
        "-o",
        o.to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(err.starts_with("allan_kalibr: error:"), "{err}");
    let left: Vec<String> = std::fs::read_dir(&o)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(
        left,
        vec!["allan_gyro.svg".to_string()],
        "outputs or temp files left: {left:?}"
    );
}

#[test]
fn the_input_is_never_overwritten() {
    let dir = tempfile::tempdir().unwrap();
    // A bag named like an output, in the output directory: refused, not replaced.
    let bag = dir.path().join("allan_curves.csv");
    std::fs::copy(
        crate::common::testdata().join("p3_short_61s/p3_short_61s.bag"),
        &bag,
    )
    .unwrap();
    let before = std::fs::read(&bag).unwrap();
    let out = run(&[
        bag.to_str().unwrap(),
        "--topic",
        "imu",
        "-q",
        "--compat-only",
        "-o",
        dir.path().to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(err.contains("input"), "{err}");
    assert_eq!(
        std::fs::read(&bag).unwrap(),
        before,
        "the input bag was overwritten"
    );
}

/// Writes `t` with seeded white noise as a .mat.
fn mat_at(path: &Path, t: &[f64], scale: f64) {
    let mut d = DataImu::with_capacity(t.len());
    let mut s: u64 = 0xA11A;
    let mut next = || {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((s >> 11) as f64 / (1u64 << 53) as f64) - 0.5
    };
    for &ti in t {
        d.push([
            ti,
            next() * scale,
            next() * scale,
            9.81 + next() * scale,
            next() * 1e-3,
            next() * 1e-3,
            next() * 1e-3,
        ]);
    }
    write_data_imu(&bag2mat::shared::output::Outputs::direct(), path, &d).unwrap();
}

#[test]
fn a_gap_is_found_and_only_the_longest_stretch_analysed() {
    let dir = tempfile::tempdir().unwrap();
    // 60 s at 100 Hz, a 1 h gap, 30 s more; and the first 60 s alone.
    let first: Vec<f64> = (0..6000).map(|i| 1.7e9 + i as f64 * 0.01).collect();
    let mut gapped = first.clone();
    gapped.extend((0..3000).map(|i| 1.7e9 + 3660.0 + i as f64 * 0.01));
    let (g, c) = (dir.path().join("gap.mat"), dir.path().join("clean.mat"));
    mat_at(&g, &gapped, 0.01);
    mat_at(&c, &first, 0.01);
    let run_on = |m: &Path, o: &str| {
        let out = run(&[
            m.to_str().unwrap(),
            "--compat-only",
            "-o",
            dir.path().join(o).to_str().unwrap(),
        ]);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        (
            String::from_utf8_lossy(&out.stderr).into_owned(),
            std::fs::read_to_string(dir.path().join(o).join("imu.yaml")).unwrap(),
        )
    };
    let (err, yaml) = run_on(&g, "g");
    let (_, clean_yaml) = run_on(&c, "c");
    assert!(
        err.contains("update rate: 100 Hz"),
        "rate not from the median period: {err}"
    );
    assert!(
        err.contains("warning: gaps:")
            && err.contains("in 1 gap(s)")
            && err.contains("not one continuous record"),
        "{err}"
    );
    // The same numbers (the first line names the input file).
    let body = |y: &str| y.lines().skip(1).collect::<Vec<_>>().join("\n");
    assert_eq!(
        body(&yaml),
        body(&clean_yaml),
        "the longest stretch is the first 60 s"
    );
}

#[test]
fn degenerate_values_are_explained() {
    let dir = tempfile::tempdir().unwrap();
    let t: Vec<f64> = (0..3000).map(|i| 1.7e9 + i as f64 * 0.01).collect();
    // Constant accelerometer axes (scale 0): warned, with the reason for the NaN.
    let c = dir.path().join("const.mat");
    mat_at(&c, &t, 0.0);
    let out = run(&[
        c.to_str().unwrap(),
        "--compat-only",
        "-q",
        "-o",
        dir.path().join("o").to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    assert!(
        err.contains("warning: ax is constant") && err.contains("NaN"),
        "{err}"
    );
    // Values of 1e300: an error that says why.
    let big = dir.path().join("big.mat");
    mat_at(&big, &t, 1e300);
    let out = run(&[
        big.to_str().unwrap(),
        "--compat-only",
        "-q",
        "-o",
        dir.path().join("p").to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(
        err.starts_with("allan_kalibr: error:") && err.contains("overflow"),
        "{err}"
    );
}

/// `-h` names every kind of input the registry holds and the bagconvert .mat: the list comes
/// from [`bag2mat::InputKind::ALL`] and [`allan_kalibr::MAT_INPUT`], not a hand-written copy.
#[test]
fn help_lists_every_input_kind() {
    let out = run(&["-h"]);
    assert!(out.status.success());
    bag2mat::test_tools::assert_help_lists_every_input(&out.stdout, &[allan_kalibr::MAT_INPUT]);
}
