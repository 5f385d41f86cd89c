//! The analysis' files, written atomically among the run's outputs:
//!
//! * `operating_noise.csv`: per sensor and axis the operating density with its 95 %
//!   interval, the static value with its interval, the ratio with its interval, the band,
//!   and the breakdown ([`NOISE_COLUMNS`]).
//! * `operating_lines.csv`: every line of every axis' residual PSD: frequency, amplitude,
//!   bandwidth, peak over the floor, in the band or not, its share as a density, and where
//!   it lands at the estimator's rate when it aliases there.
//! * `operating_phases.csv`: each phase's kind, span, density and lines per axis.
//! * `operating_psd.csv`: the residual's PSD per axis with its floor and the spline error's.
//! * `operating_calibration.yaml` (with a reference): the estimated calibration.
//! * The configuration files with the operating values: one per consumer of
//!   [`crate::consumers::CONSUMERS`], rendered by [`crate::consumers::render`] from an analysis whose
//!   noise densities are the operating ones ([`operating_analysis`]), named `operating_…`,
//!   each with a header saying what its values are; and, when there is a static analysis,
//!   that analysis' own files and CSVs named `static_…` beside them.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use bag2mat::Sensor;
use bag2mat::shared::output::Outputs;

use super::Operating;
use crate::consumers::{CONSUMERS, ConsumerId, Provenance};
use crate::ieee952::imu::{ImuAnalysis, ImuCurves};
use crate::ieee952::{AxisVerdict, Term, Verdict};

/// `operating_noise.csv`'s columns, in order.
pub const NOISE_COLUMNS: [&str; 23] = [
    "sensor",
    "axis",
    "noise_density",
    "ci95_lo",
    "ci95_hi",
    "static_noise_density",
    "static_ci95_lo",
    "static_ci95_hi",
    "static_is_upper_bound",
    "ratio",
    "ratio_ci95_lo",
    "ratio_ci95_hi",
    "band_lo_hz",
    "band_hi_hz",
    "floor_density",
    "lines_density",
    "lines_in_band",
    "spline_error_density",
    "motion_uncalibrated_density",
    "time_offset_uncompensated_density",
    "stamp_jitter_density",
    "dof",
    "unit",
];
/// File names.
pub const NOISE_FILE: &str = "operating_noise.csv";
/// Lines file.
pub const LINES_FILE: &str = "operating_lines.csv";
/// Phases file.
pub const PHASES_FILE: &str = "operating_phases.csv";
/// PSD file.
pub const PSD_FILE: &str = "operating_psd.csv";
/// Calibration file.
pub const CALIBRATION_FILE: &str = "operating_calibration.yaml";
/// Prefix of the configuration files with the operating values.
pub const OPERATING_PREFIX: &str = "operating_";
/// Prefix of the static analysis' files.
pub const STATIC_PREFIX: &str = "static_";

/// The analysis that carries the operating values into the configuration files: the
/// IEEE 952 analysis of the operating noise series (its lines and K as that fit reads them),
/// each axis' N replaced by N_op (resolved, with its interval; no curve bound, for N_op
/// counts the lines the curve's bound does not), its fit verdict replaced by a plain fit
/// (the comments the files would draw from it concern that series' Allan fit, not N_op), and
/// K the static analysis' where there is one; without a reference and without a static
/// analysis K is left out (a high-passed series has no random walk to read).
pub(crate) fn operating_analysis(
    op: &Operating,
    findings: &[bag2mat::Finding],
) -> Option<ImuAnalysis> {
    let absent = if op.noise_series[0].is_empty() {
        Some(Sensor::Gyro)
    } else if op.noise_series[3].is_empty() {
        Some(Sensor::Acc)
    } else {
        None
    };
    let s: [&[f64]; 6] = std::array::from_fn(|i| {
        if op.noise_series[i].is_empty() {
            // a stand-in the analysis leaves out (the absent sensor)
            op.noise_series[(i + 3) % 6].as_slice()
        } else {
            op.noise_series[i].as_slice()
        }
    });
    let cfg = crate::ieee952::Config::default();
    let base = ImuCurves::from_samples_of(s, absent, op.rate, &cfg)
        .ok()
        .map(|c| c.finish(findings.to_vec(), &cfg))
        .or_else(|| op.static_an.clone())?;
    let mut an = base;
    an.rate = op.rate;
    for ax in an.axes.iter_mut() {
        let Some(o) = op
            .axes
            .iter()
            .find(|o| o.sensor == ax.sensor && o.axis == ax.axis)
        else {
            continue;
        };
        let b = &o.band;
        ax.analysis.terms.n = Term {
            value: b.n,
            std_err: (b.hi - b.lo) / (2.0 * 1.96),
            lo: b.lo,
            hi: b.hi,
            verdict: Verdict::Resolved,
        };
        ax.analysis.bounds.0 = f64::INFINITY;
        let tau0 = 1.0 / op.rate;
        ax.analysis.verdict = AxisVerdict::Fits {
            range: (tau0, tau0 * op.samples as f64 / 2.0),
            short_cut: false,
            short_feature: false,
            band_limited: false,
            long_cut: false,
            approximate: None,
        };
        let stat = op.static_an.as_ref().and_then(|s| {
            s.axes
                .iter()
                .find(|x| x.sensor == ax.sensor && x.axis == ax.axis)
        });
        match (stat, &op.reference) {
            (Some(st), _) => {
                ax.analysis.terms.k = st.analysis.terms.k;
                ax.analysis.bounds.1 = st.analysis.bounds.1;
            }
            (None, Some(_)) => {}
            (None, None) => {
                ax.analysis.terms.k = Term {
                    value: f64::NAN,
                    std_err: f64::NAN,
                    lo: f64::NAN,
                    hi: f64::NAN,
                    verdict: Verdict::NotFitted,
                };
                ax.analysis.bounds.1 = f64::NAN;
            }
        }
    }
    Some(an)
}

/// A number for the CSVs: Rust's shortest round-trip text (NaN as `NaN`).
fn num(x: f64) -> String {
    format!("{x}")
}

/// `operating_noise.csv`.
fn noise_csv(op: &Operating) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "# operating noise density per axis, continuous time ({}), {} Hz: the white-noise density whose per-sample variance equals the residual's in the band (below band_lo_hz the floor is assumed); noise_density^2 = floor_density^2 + lines_density^2. ci95: 95 % interval. static: {}. ratio = noise_density / static_noise_density. spline_error_density: the reference spline's estimated error, taken out. motion_uncalibrated_density, time_offset_uncompensated_density: what the calibration removed (scale, misalignment, g-sensitivity; the time offset), i.e. what they add if the estimator does not estimate them. stamp_jitter_density: the IMU stamps' jitter's share (inside noise_density). NaN: not measured (no reference).",
        if op.reference.is_some() {
            "against a reference trajectory"
        } else {
            "from the signal alone"
        },
        op.rate,
        op.static_source
    );
    s.push_str(&NOISE_COLUMNS.join(","));
    s.push('\n');
    for a in &op.axes {
        let b = &a.band;
        let st = a.static_n;
        let (r, rl, rh) = a.ratio().unwrap_or((f64::NAN, f64::NAN, f64::NAN));
        let in_band = b.lines.iter().filter(|l| l.in_band).count();
        let _ = writeln!(
            s,
            "{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}",
            a.sensor.name(),
            ["x", "y", "z"][a.axis],
            num(b.n),
            num(b.lo),
            num(b.hi),
            num(st.map_or(f64::NAN, |v| v.value)),
            num(st.map_or(f64::NAN, |v| v.lo)),
            num(st.map_or(f64::NAN, |v| v.hi)),
            st.is_some_and(|v| v.bound),
            num(r),
            num(rl),
            num(rh),
            num(b.band.0),
            num(b.band.1),
            num(b.floor_n),
            num(b.lines_n),
            in_band,
            num(b.spline_n),
            num(a.motion_n),
            num(a.offset_n),
            num(a.jitter_n),
            num(b.dof),
            a.sensor.n_unit()
        );
    }
    s
}

/// Where a line at `f` Hz lands at the estimator's rate `fe` when it is above its Nyquist
/// frequency (a sample rate folds every frequency into 0 … fe/2).
pub fn alias(f: f64, fe: f64) -> Option<f64> {
    if f <= fe / 2.0 {
        return None;
    }
    let r = f % fe;
    Some(if r > fe / 2.0 { fe - r } else { r })
}

/// `operating_lines.csv`.
fn lines_csv(op: &Operating) -> String {
    let mut s = format!(
        "# lines of the residual PSD per axis (frequency, amplitude A = sqrt(2*power), bandwidth 0 for a sinusoid, peak over the local floor); density: the line's share of the operating density, sqrt(A^2/2/f_s); alias_hz: where it lands at the estimator's rate ({} Hz) when above its Nyquist frequency, else NaN\n",
        op.estimator_rate
    );
    s.push_str("sensor,axis,frequency_hz,amplitude,bandwidth_hz,peak_over_floor,in_band,density,alias_hz,unit\n");
    for a in &op.axes {
        for l in &a.band.lines {
            let _ = writeln!(
                s,
                "{},{},{},{},{},{},{},{},{},{}",
                a.sensor.name(),
                ["x", "y", "z"][a.axis],
                num(l.line.frequency),
                num(l.line.amplitude),
                num(l.line.bandwidth),
                num(l.line.peak_ratio),
                l.in_band,
                num(l.density),
                num(alias(l.line.frequency, op.estimator_rate).unwrap_or(f64::NAN)),
                a.sensor.unit()
            );
        }
    }
    s
}

/// `operating_phases.csv`.
fn phases_csv(op: &Operating) -> String {
    let mut s = String::from(
        "# the record by phase (still, vibrating in place, moving) from the signal's spectrogram; per axis the operating density of the phase with its 95 % interval and the lines in its band (frequency:amplitude, separated by ;)\n",
    );
    s.push_str(
        "phase,kind,t_start_s,t_end_s,sensor,axis,noise_density,ci95_lo,ci95_hi,lines,unit\n",
    );
    for (k, p) in op.phases.iter().enumerate() {
        for a in &p.axes {
            let lines: Vec<String> = a
                .lines
                .iter()
                .map(|(f, amp)| format!("{f:.4}:{amp:.4e}"))
                .collect();
            let _ = writeln!(
                s,
                "{},{},{},{},{},{},{},{},{},{},{}",
                k + 1,
                p.kind.name(),
                num(p.start as f64 / op.rate),
                num(p.end as f64 / op.rate),
                a.sensor.name(),
                ["x", "y", "z"][a.axis],
                num(a.n.0),
                num(a.n.1),
                num(a.n.2),
                lines.join(";"),
                a.sensor.n_unit()
            );
        }
    }
    s
}

/// `operating_psd.csv`.
fn psd_csv(op: &Operating) -> String {
    let mut s = String::from(
        "# Welch PSD of each axis' residual (one-sided, unit^2/Hz; white noise of density N has the level 2*N^2), its local floor (lines left out) and the reference spline's estimated error (0 without a reference)\n",
    );
    s.push_str("axis,freq_hz,psd,floor,spline_error_psd\n");
    for a in &op.axes {
        let code = a.sensor.axis_code(a.axis);
        let p = &a.band.psd;
        for k in 0..p.freq.len() {
            let _ = writeln!(
                s,
                "{code},{},{},{},{}",
                p.freq[k], p.density[k], p.floor[k], a.band.spline_psd[k]
            );
        }
    }
    s
}

/// `operating_calibration.yaml`.
fn calibration_yaml(op: &Operating) -> Option<String> {
    let r = op.reference.as_ref()?;
    let c = &r.calibration;
    let mut s = String::from(
        "# What a calibration would estimate, estimated jointly with the operating noise (allan_kalibr --reference).\n# time_offset: the IMU sample stamped t is the reference at t + time_offset.\n# Matrices row-major. scale/misalignment: S = A R^T - I of each sensor's map A = (I + S) R (R its nearest rotation; S in the IMU's axes): diagonal = scale errors, off-diagonal = misalignment (symmetric). excited: the motion determined the term (its standard error below a fifth of its prior's); otherwise it is the prior's (0).\n",
    );
    let f = |x: f64| crate::yaml::yaml_float(x);
    let mat = |m: &nalgebra::Matrix3<f64>| {
        format!(
            "[{}]",
            (0..3)
                .flat_map(|i| (0..3).map(move |j| (i, j)))
                .map(|(i, j)| f(m[(i, j)]))
                .collect::<Vec<_>>()
                .join(", ")
        )
    };
    let _ = writeln!(s, "reference: {}", crate::yaml::yaml_str(&r.what));
    let _ = writeln!(s, "reference_poses: {}", r.poses);
    let _ = writeln!(s, "reference_pose_spacing_s: {}", f(r.pose_dt));
    let _ = writeln!(s, "reference_noise_position_m: {}", f(r.noise.0));
    let _ = writeln!(s, "reference_noise_rotation_rad: {}", f(r.noise.1));
    let _ = writeln!(s, "spline_knot_spacing_s: {}", f(r.knot_dt));
    let _ = writeln!(s, "spline_knot_spacing_given: {}", r.knot_given);
    let _ = writeln!(s, "time_offset_s: {}", f(c.dt));
    let _ = writeln!(s, "time_offset_std_err_s: {}", f(c.dt_se));
    let _ = writeln!(s, "time_offset_observable: {}", c.dt_observable);
    let rg = super::reference::polar(&c.a_g);
    let q = nalgebra::UnitQuaternion::from_matrix(&rg);
    let _ = writeln!(
        s,
        "rotation_imu_from_reference_xyzw: [{}, {}, {}, {}]",
        f(q.i),
        f(q.j),
        f(q.k),
        f(q.w)
    );
    let _ = writeln!(s, "rotation_imu_from_reference: {}", mat(&rg));
    for (name, a, se, prior) in [
        ("gyro", &c.a_g, &c.a_g_se, super::calibrate::PRIOR_SCALE),
        ("acc", &c.a_a, &c.a_a_se, super::calibrate::PRIOR_SCALE),
    ] {
        let r = super::reference::polar(a);
        let sm = a * r.transpose() - nalgebra::Matrix3::identity();
        let excited = (0..9).all(|k| super::calibrate::Calibration::excited(se[k], prior));
        let _ = writeln!(s, "{name}_scale_misalignment: {}", mat(&sm));
        let _ = writeln!(s, "{name}_scale_misalignment_std_err: {}", mat(se));
        let _ = writeln!(s, "{name}_scale_misalignment_excited: {excited}");
    }
    let ra = super::reference::polar(&c.a_a);
    let between = crate::spline::so3::log(&(rg.transpose() * ra)).norm();
    let _ = writeln!(s, "acc_to_gyro_axes_angle_rad: {}", f(between));
    let _ = writeln!(s, "gyro_g_sensitivity_rad_s_per_m_s2: {}", mat(&c.g_sens));
    let _ = writeln!(s, "gyro_g_sensitivity_std_err: {}", mat(&c.g_sens_se));
    let _ = writeln!(
        s,
        "gyro_g_sensitivity_excited: {}",
        (0..9).all(|k| super::calibrate::Calibration::excited(
            c.g_sens_se[k],
            super::calibrate::PRIOR_G_SENS
        ))
    );
    let _ = writeln!(
        s,
        "lever_arm_m: [{}, {}, {}]",
        f(c.lever.x),
        f(c.lever.y),
        f(c.lever.z)
    );
    let _ = writeln!(
        s,
        "lever_arm_std_err_m: [{}, {}, {}]",
        f(c.lever_se.x),
        f(c.lever_se.y),
        f(c.lever_se.z)
    );
    let _ = writeln!(
        s,
        "gravity_in_reference_world_m_s2: [{}, {}, {}]",
        f(c.gravity_w.x),
        f(c.gravity_w.y),
        f(c.gravity_w.z)
    );
    let _ = writeln!(s, "bias_knot_spacing_s: {}", f(c.bias_knot));
    for (name, b) in [("gyro", &c.bias_g), ("acc", &c.bias_a)] {
        let (first, last) = (b[0], b[b.len() - 1]);
        let drift = (0..3)
            .map(|i| {
                let (lo, hi) = b
                    .iter()
                    .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), v| {
                        (l.min(v[i]), h.max(v[i]))
                    });
                hi - lo
            })
            .collect::<Vec<_>>();
        let _ = writeln!(
            s,
            "{name}_bias_start: [{}, {}, {}]",
            f(first.x),
            f(first.y),
            f(first.z)
        );
        let _ = writeln!(
            s,
            "{name}_bias_end: [{}, {}, {}]",
            f(last.x),
            f(last.y),
            f(last.z)
        );
        let _ = writeln!(
            s,
            "{name}_bias_drift_range: [{}, {}, {}]",
            f(drift[0]),
            f(drift[1]),
            f(drift[2])
        );
    }
    let _ = writeln!(
        s,
        "residual_std_per_sample: [{}, {}]",
        f(c.sigma[0]),
        f(c.sigma[1])
    );
    let _ = writeln!(s, "imu_stamp_jitter_s: {}", f(r.jitter));
    let _ = writeln!(s, "iterations: {}", c.iterations);
    let _ = writeln!(s, "first_sample_time_s: {}", f(op.t0));
    let _ = writeln!(s, "samples_analysed: {}", op.samples);
    Some(s)
}

/// The header every operating configuration file starts with (after a `%YAML:1.0` line):
/// what its values are.
fn operating_header(op: &Operating, name: &str) -> Vec<String> {
    let band = op
        .axes
        .first()
        .map_or((f64::NAN, f64::NAN), |a| a.band.band);
    let k = if op.static_an.is_some() {
        format!(
            "the random walks are the static analysis' ({STATIC_PREFIX}{name} beside this file says how they were fitted)"
        )
    } else if op.reference.is_some() {
        "the random walks are the IEEE 952 fit of this record's own residual (a short record bounds them loosely)".to_string()
    } else {
        "the random walks are not measured without a reference or a static record (give --static LOG)".to_string()
    };
    vec![
        format!(
            "OPERATING-CONDITION VALUES (allan_kalibr {}): the noise densities below are the noise this IMU showed in operation (the largest axis), not a static Allan value: the white-noise density with the residual's per-sample variance in the estimator's band ({:.3} - {:.3} Hz), vibration lines included. Use them as they are: do not inflate them again.",
            if op.reference.is_some() { "--reference" } else { "--operating" },
            band.0,
            band.1
        ),
        format!("Static values: {}.", op.static_source),
        format!("{k}."),
        "What follows is the file's usual header; its advice to inflate static values does not apply here.".to_string(),
    ]
}

/// A configuration file's text with the operating header put in (after `%YAML:1.0`, or as
/// a `_operating` member of Basalt's JSON).
pub(crate) fn relabel(text: &str, header: &[String], json: bool) -> String {
    if json {
        let at = text
            .find("\"value0\": {\n")
            .map(|i| i + "\"value0\": {\n".len());
        let Some(at) = at else {
            return text.to_string();
        };
        let joined = header.join(" ").replace('\\', "\\\\").replace('"', "\\\"");
        return format!(
            "{}    \"_operating\": \"{joined}\",\n{}",
            &text[..at],
            &text[at..]
        );
    }
    let (head, rest) = match text.strip_prefix("%YAML:1.0\n") {
        Some(r) => ("%YAML:1.0\n", r),
        None => ("", text),
    };
    let mut o = String::from(head);
    for h in header {
        let _ = writeln!(o, "# {h}");
    }
    o.push_str(rest);
    o
}

/// Writes every file of the analysis into `dir`; returns the paths.
pub(crate) fn write(
    outputs: &Outputs,
    op: &Operating,
    dir: &Path,
    rostopic: &str,
    prov: &Provenance,
) -> Result<Vec<PathBuf>, bag2mat::Error> {
    let mut files = Vec::new();
    let mut put = |name: &str, text: String| -> Result<(), bag2mat::Error> {
        let p = dir.join(name);
        outputs.write_atomic(&p, |w| w.write_all(text.as_bytes()))?;
        files.push(p);
        Ok(())
    };
    put(NOISE_FILE, noise_csv(op))?;
    put(LINES_FILE, lines_csv(op))?;
    put(PHASES_FILE, phases_csv(op))?;
    put(PSD_FILE, psd_csv(op))?;
    if let Some(y) = calibration_yaml(op) {
        put(CALIBRATION_FILE, y)?;
    }
    if let Some(an) = &op.operating_an {
        let values = crate::ieee952::config_values::file_values(an);
        for c in &CONSUMERS {
            let text = crate::consumers::render(c.id, &values, prov, rostopic);
            let h = operating_header(op, c.file);
            put(
                &format!("{OPERATING_PREFIX}{}", c.file),
                relabel(&text, &h, c.id == ConsumerId::Basalt),
            )?;
        }
    }
    if let Some(st) = &op.static_an {
        files.extend(crate::ieee952::files::write_outputs(
            outputs,
            st,
            dir,
            STATIC_PREFIX,
            rostopic,
            prov,
        )?);
    }
    Ok(files)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_line_above_the_estimators_nyquist_folds() {
        assert_eq!(alias(30.0, 100.0), None);
        assert_eq!(alias(70.0, 100.0), Some(30.0));
        assert_eq!(alias(130.0, 100.0), Some(30.0));
        assert_eq!(alias(180.0, 100.0), Some(20.0));
    }

    #[test]
    fn the_operating_header_goes_after_the_yaml_line_and_into_basalts_value0() {
        let h = vec!["A \"quoted\" header.".to_string()];
        assert_eq!(
            relabel("%YAML:1.0\n# x\nk: 1\n", &h, false),
            "%YAML:1.0\n# A \"quoted\" header.\n# x\nk: 1\n"
        );
        assert_eq!(
            relabel("# x\nk: 1\n", &h, false),
            "# A \"quoted\" header.\n# x\nk: 1\n"
        );
        assert_eq!(
            relabel("{\n  \"value0\": {\n    \"a\": 1\n  }\n}\n", &h, true),
            "{\n  \"value0\": {\n    \"_operating\": \"A \\\"quoted\\\" header.\",\n    \"a\": 1\n  }\n}\n"
        );
    }
}
