//! End-to-end parity with upstream on every reference case (docs/upstream/imu_utils.md §8): the library
//! runs on the case's bag with the arguments upstream used, and every output is compared
//! with `testdata/<case>/imu_utils/`. Each check collects all its failures (case, item,
//! expected, actual, tolerance) and prints the parity figures.

use std::collections::BTreeMap;

use allan_imu_utils::Config;
use allan_imu_utils::{Outcome, run};

use crate::common::{AXES, CASES, Case, parse_c_float, rel_err};
use crate::fit_reference::{CHAOTIC_W_REL_TOL, YAML_REL_TOL};

/// Deterministic double arithmetic; only the summation order of the fast path differs.
const ALLAN_REL_TOL: f64 = 1e-9;
/// Continuous yaml against the reading of upstream's fitted Q N B K R: the raw parameters
/// of fits stopped at the attempt cap are looser than the compat values (§8: "no tight
/// bound"); measured ≤ 4.1e-4 (p2 gyro x, √3·|K| on a flat valley), so 1e-3.
const CONTINUOUS_REL_TOL: f64 = 1e-3;
/// p2 gyro z avg-axis gyr_w (§8: the chaotic axis pulls the average).
const CHAOTIC_AVG_W_REL_TOL: f64 = 2e-2;
/// `%.10g` files: equal when parsed at their printed precision (half a unit of the 10th
/// significant digit each side, so one unit apart at most).
const PRINTED_10G_REL_TOL: f64 = 1e-9;
/// Fit-dependent printed numbers (§8: may differ in the last printed digit; compared
/// within the yaml tolerance).
const FITTED_PRINT_REL_TOL: f64 = 1e-3;

fn run_case(case: &Case, out: &std::path::Path) -> Outcome {
    let mut config = Config::new(allan_kalibr::Input::Samples(case.bag()), out);
    config.common.topics = bag2mat::TopicSelector::one(case.topic);
    config.name = case.name.into();
    config.max_time_min = case.max_time_min;
    config.plots = false;
    // Parity of the compat outputs; the IEEE 952 section is checked in allan_kalibr and in
    // cli.rs.
    config.common.ieee952 = false;
    run(&config, &bag2mat::shared::output::Outputs::direct())
        .unwrap_or_else(|e| panic!("{}: run failed: {e}", case.dir))
        .remove(0)
}

/// Leaf `key: value` pairs of an OpenCV yaml, keyed by their path (`Gyr/x-axis/gyr_n`).
fn yaml_values(text: &str) -> BTreeMap<String, String> {
    let mut stack: Vec<(usize, String)> = Vec::new();
    let mut out = BTreeMap::new();
    for line in text.lines().skip(2) {
        let indent = line.len() - line.trim_start().len();
        let (k, v) = line.trim().split_once(':').unwrap();
        while stack.last().is_some_and(|(i, _)| *i >= indent) {
            stack.pop();
        }
        let mut path: Vec<&str> = stack.iter().map(|(_, s)| s.as_str()).collect();
        path.push(k);
        if v.trim().is_empty() {
            stack.push((indent, k.to_string()));
        } else {
            out.insert(path.join("/"), v.trim().to_string());
        }
    }
    out
}

/// Replaces every number of a yaml line by `#` to compare layouts.
fn layout(line: &str) -> String {
    match line.split_once(": ") {
        Some((k, v)) if v.parse::<f64>().is_ok() || v == ".Nan" => {
            // Keep the shape of the number: mantissa digits and exponent width.
            let shape: String = v
                .chars()
                .map(|c| if c.is_ascii_digit() { '9' } else { c })
                .collect();
            format!("{k}: {shape}")
        }
        _ => line.to_string(),
    }
}

fn fit_dependent_line(line: &str) -> bool {
    line.starts_with("C ")
        || line.starts_with(" Bias Instability")
        || line.starts_with(" White Noise")
}

#[test]
fn reference_cases_end_to_end() {
    let mut failures: Vec<String> = Vec::new();
    let mut fail = |s: String| failures.push(s);
    for case in CASES {
        let dir = tempfile::tempdir().unwrap();
        let out = run_case(case, dir.path());
        let an = &out.analysis;
        let c = case.dir;

        // Samples used, factor list (exact), freq and gyro means (1e-9).
        let summary = case.read("ref_dump_summary.txt");
        let fed: usize = summary.split_whitespace().nth(1).unwrap().parse().unwrap();
        if an.axes[0].n != fed {
            fail(format!(
                "{c} messages used: expected {fed}, actual {}",
                an.axes[0].n
            ));
        }
        if an.axes[0].factors != case.factors() {
            fail(format!(
                "{c} factor list differs: expected {:?}, actual {:?}",
                case.factors(),
                an.axes[0].factors
            ));
        }
        let means: Vec<f64> = summary
            .lines()
            .find(|l| l.starts_with("gyr_mean_degh"))
            .unwrap()
            .split_whitespace()
            .skip(1)
            .map(parse_c_float)
            .collect();
        let mut max_mean = 0.0f64;
        for k in 0..3 {
            let r = rel_err(an.gyro_mean[k], means[k]);
            max_mean = max_mean.max(r);
            if !(r <= ALLAN_REL_TOL) {
                fail(format!(
                    "{c} gyro mean {k}: expected {:e}, actual {:e}, tol {ALLAN_REL_TOL:e}",
                    means[k], an.gyro_mean[k]
                ));
            }
        }

        // Taus and Allan variances (1e-9 relative).
        let mut max_tau = 0.0f64;
        let mut max_var = 0.0f64;
        for (i, axis) in AXES.iter().enumerate() {
            let freq = case.summary_value(axis, "freq");
            let r = rel_err(an.axes[i].freq, freq);
            if !(r <= ALLAN_REL_TOL) {
                fail(format!(
                    "{c} {axis} freq: expected {freq:e}, actual {:e}, tol {ALLAN_REL_TOL:e}",
                    an.axes[i].freq
                ));
            }
            let (taus, var) = case.tau_var(axis);
            if taus.len() != an.axes[i].taus.len() {
                fail(format!(
                    "{c} {axis}: expected {} points, actual {}",
                    taus.len(),
                    an.axes[i].taus.len()
                ));
                continue;
            }
            for j in 0..taus.len() {
                let rt = rel_err(an.axes[i].taus[j], taus[j]);
                let rv = rel_err(an.axes[i].variance[j], var[j]);
                max_tau = max_tau.max(rt);
                max_var = max_var.max(rv);
                if !(rt <= ALLAN_REL_TOL && rv <= ALLAN_REL_TOL) {
                    fail(format!(
                        "{c} {axis} index {j}: expected tau {:e} var {:e}, actual tau {:e} var {:e}, tol {ALLAN_REL_TOL:e}",
                        taus[j], var[j], an.axes[i].taus[j], an.axes[i].variance[j]
                    ));
                }
            }
        }

        // Continuous yaml: the corrected reading of upstream's own fitted parameters
        // (docs/upstream/imu_utils.md §7), |N|, √3·|K|, |B|/0.664 in SI units.
        let cont = std::fs::read_to_string(
            dir.path()
                .join(format!("{}_imu_param_continuous.yaml", case.name)),
        )
        .unwrap();
        let cv = yaml_values(&cont);
        let mut max_cont = 0.0f64;
        for (i, axis) in AXES.iter().enumerate() {
            let unit = if i < 3 { 57.3 * 3600.0 } else { 1.0 };
            let (sensor, short) = if i < 3 {
                ("Gyr", "gyr")
            } else {
                ("Acc", "acc")
            };
            let xyz = ["x", "y", "z"][i % 3];
            let expected = [
                ("n", case.summary_value(axis, "N").abs() / unit),
                (
                    "w",
                    3f64.sqrt() * case.summary_value(axis, "K").abs() / unit,
                ),
                (
                    "bias_instability",
                    case.summary_value(axis, "B").abs() / 0.6642824703 / unit,
                ),
            ];
            for (key, want) in expected {
                let k = format!("{sensor}/{xyz}-axis/{short}_{key}");
                let got: f64 = cv
                    .get(&k)
                    .unwrap_or_else(|| panic!("{c}: continuous yaml lacks {k}"))
                    .parse()
                    .unwrap();
                let r = rel_err(got, want);
                // The chaotic axis has no bound on its raw parameters (§8); there √3·|K|
                // moves by ~20 %.
                if c == "p2_medium_100hz" && *axis == "gyr_z" {
                    continue;
                }
                max_cont = max_cont.max(r);
                if !(r <= CONTINUOUS_REL_TOL) {
                    fail(format!(
                        "{c} continuous {k}: expected {want:e}, actual {got:e}, rel {r:e}, tol {CONTINUOUS_REL_TOL:e}"
                    ));
                }
            }
        }

        // Compat yaml: identical layout, values within 1e-3 (looser on the chaotic axis).
        let yname = format!("{}_imu_param.yaml", case.name);
        let ours = std::fs::read_to_string(dir.path().join(&yname)).unwrap();
        let theirs = case.read(&yname);
        let (ol, tl): (Vec<String>, Vec<String>) = (
            ours.lines().map(layout).collect(),
            theirs.lines().map(layout).collect(),
        );
        if ol != tl || !ours.ends_with('\n') {
            fail(format!(
                "{c} {yname}: layout differs:\n--- expected\n{theirs}--- actual\n{ours}"
            ));
        }
        let (ov, tv) = (yaml_values(&ours), yaml_values(&theirs));
        let mut max_yaml = 0.0f64;
        let mut max_yaml_chaotic = 0.0f64;
        for (k, t) in &tv {
            let Some(o) = ov.get(k) else {
                fail(format!("{c} {yname}: missing {k}"));
                continue;
            };
            let Ok(tn) = t.parse::<f64>() else {
                if o != t {
                    fail(format!("{c} {yname} {k}: expected {t}, actual {o}"));
                }
                continue;
            };
            let on: f64 = o.parse().unwrap();
            let r = rel_err(on, tn);
            let chaotic =
                c == "p2_medium_100hz" && (k == "Gyr/z-axis/gyr_w" || k == "Gyr/avg-axis/gyr_w");
            let tol = match (chaotic, k.as_str()) {
                (true, "Gyr/z-axis/gyr_w") => CHAOTIC_W_REL_TOL,
                (true, _) => CHAOTIC_AVG_W_REL_TOL,
                _ => YAML_REL_TOL,
            };
            if chaotic {
                max_yaml_chaotic = max_yaml_chaotic.max(r);
            } else {
                max_yaml = max_yaml.max(r);
            }
            if !(r <= tol) {
                fail(format!(
                    "{c} {yname} {k}: expected {t}, actual {o}, rel {r:e}, tol {tol:e}"
                ));
            }
        }

        // Curve files: same line counts; data curves equal at printed precision, fitted
        // curves within the fit tolerance.
        let mut max_txt = 0.0f64;
        let mut max_sim = 0.0f64;
        for entry in std::fs::read_dir(case.ref_dir()).unwrap() {
            let fname = entry.unwrap().file_name().to_string_lossy().into_owned();
            if !fname.starts_with("data_") {
                continue;
            }
            let theirs = case.read(&fname);
            let Ok(ours) = std::fs::read_to_string(dir.path().join(&fname)) else {
                fail(format!("{c}: {fname} not written"));
                continue;
            };
            let (o, t): (Vec<&str>, Vec<&str>) = (ours.lines().collect(), theirs.lines().collect());
            if o.len() != t.len() || !ours.ends_with('\n') {
                fail(format!(
                    "{c} {fname}: expected {} lines, actual {}",
                    t.len(),
                    o.len()
                ));
                continue;
            }
            let sim = fname.contains("_sim_") && !fname.ends_with("_t.txt");
            let chaotic = c == "p2_medium_100hz" && fname.contains("sim_gyr_z");
            for (j, (a, b)) in o.iter().zip(&t).enumerate() {
                let r = rel_err(parse_c_float(a), parse_c_float(b));
                let tol = match (sim, chaotic) {
                    (true, true) => CHAOTIC_W_REL_TOL,
                    (true, false) => YAML_REL_TOL,
                    _ => PRINTED_10G_REL_TOL,
                };
                if sim && !chaotic {
                    max_sim = max_sim.max(r);
                } else if !sim {
                    max_txt = max_txt.max(r);
                }
                if !(r <= tol) {
                    fail(format!(
                        "{c} {fname} line {}: expected {b}, actual {a}, rel {r:e}, tol {tol:e}",
                        j + 1
                    ));
                }
            }
        }

        // stdout: line by line; fit-dependent lines compared number by number.
        let theirs = case.read("stdout.txt");
        let (o, t): (Vec<&str>, Vec<&str>) =
            (out.section.text.lines().collect(), theirs.lines().collect());
        if o.len() != t.len() {
            fail(format!(
                "{c} stdout: expected {} lines, actual {}",
                t.len(),
                o.len()
            ));
        }
        let mut fitted_lines_differing = 0;
        let mut max_stdout = 0.0f64;
        for (j, (a, b)) in o.iter().zip(&t).enumerate() {
            if a == b {
                continue;
            }
            if !fit_dependent_line(b) {
                fail(format!(
                    "{c} stdout line {}: expected {b:?}, actual {a:?}",
                    j + 1
                ));
                continue;
            }
            fitted_lines_differing += 1;
            let (ta, tb): (Vec<&str>, Vec<&str>) = (
                a.split_whitespace().collect(),
                b.split_whitespace().collect(),
            );
            // The gyro-z block of p2 follows the chaotic fit.
            let in_chaotic_block = c == "p2_medium_100hz"
                && t[..j]
                    .iter()
                    .rev()
                    .find(|l| l.starts_with("Gyro ") || l.starts_with("acc "))
                    .is_some_and(|h| h.starts_with("Gyro z"));
            let tol = if in_chaotic_block {
                CHAOTIC_W_REL_TOL
            } else {
                FITTED_PRINT_REL_TOL
            };
            let ok = ta.len() == tb.len()
                && ta
                    .iter()
                    .zip(&tb)
                    .all(|(x, y)| match (x.parse::<f64>(), y.parse::<f64>()) {
                        (Ok(p), Ok(q)) => {
                            let r = rel_err(p, q);
                            if !in_chaotic_block {
                                max_stdout = max_stdout.max(r);
                            }
                            r <= tol
                        }
                        _ => x == y,
                    });
            if !ok {
                fail(format!(
                    "{c} stdout line {}: expected {b:?}, actual {a:?}, tol {tol:e}",
                    j + 1
                ));
            }
        }

        // stderr: upstream's reference run printed only the end-of-bag warning (p3); this
        // tool's own notes (the stop rule cutting what the IEEE 952 section keeps) are
        // additions, not upstream's words
        let stderr_ref = case.read("stderr.txt");
        let ours_err: String = out
            .section
            .notes
            .iter()
            .filter(|n| n.upstream_prefix.is_some())
            .map(|n| format!("{n}\n"))
            .collect();
        if ours_err != stderr_ref {
            fail(format!(
                "{c} stderr: expected {stderr_ref:?}, actual {ours_err:?}"
            ));
        }

        eprintln!(
            "parity {c}: N {} | max rel: tau {max_tau:.1e} var {max_var:.1e} gyro-mean {max_mean:.1e} | yaml {max_yaml:.1e} (chaotic p2 gyr_w {max_yaml_chaotic:.1e}) | continuous yaml {max_cont:.1e} | data txt {max_txt:.1e} sim txt {max_sim:.1e} | stdout: {fitted_lines_differing} fit lines differ, max rel {max_stdout:.1e}",
            an.axes[0].n
        );
    }
    assert!(
        failures.is_empty(),
        "{} failures:\n{}",
        failures.len(),
        failures.join("\n")
    );
}
