//! The files of the IEEE 952 section, written atomically through `bag2mat::output`:
//!
//! * `ieee952_terms.csv`: per axis and term the value, its 95 % interval and verdict, how
//!   the axis was fitted (range, χ²/dof, model discrepancy), the region reading and the
//!   record-length advice. Column names are the `COL_*` constants, which `sim compare`
//!   reads by.
//! * `ieee952_curves.csv`: the Allan deviation of every axis with its 68.3 % and 95 %
//!   bounds, whether the point is in the fitted range, and the fitted model there; a first
//!   comment line states the sample count (`# samples=N`) so that `--curves` can read the
//!   file back with intervals.
//! * `kalibr_imu_ieee952.yaml`, `vins_imu_ieee952.yaml`, `orbslam3_imu_ieee952.yaml`: the
//!   values users feed into Kalibr, VINS-Mono/VINS-Fusion and ORB-SLAM3, each saying that it
//!   is continuous-time (docs/noise_terms.md §3–4). One value per sensor (the largest axis); a term no
//!   axis resolves is its 95 % upper bound, marked; an axis without a reliable fit
//!   contributes its IEEE 952 region readings, and the file says so. A missing sensor's keys
//!   are left out (with a comment) rather than written as a number. Every warning of the
//!   record check (`bag2mat::check_record`: warm-up, spike, gaps, clocks) is a caveat.
//! * OpenVINS' `kalibr_imu_chain.yaml` and Basalt's calibration noise fields:
//!   [`super::vio_files`].

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use super::config_values::{file_values, inline_note};
use super::imu::{AxisResult, ImuAnalysis, SensorValue};
use super::{AxisVerdict, Overlap, Term};
use crate::yaml::yaml_float;

/// `ieee952_terms.csv`: sensor name (`gyroscope`, `accelerometer`).
pub const COL_SENSOR: &str = "sensor";
/// Axis (`x`, `y`, `z`).
pub const COL_AXIS: &str = "axis";
/// Term (`Q`, `N`, `B`, `K`, `R`).
pub const COL_TERM: &str = "term";
/// Value in `COL_UNIT`.
pub const COL_VALUE: &str = "value";
/// Standard error.
pub const COL_STD_ERR: &str = "std_err";
/// 95 % interval, lower end.
pub const COL_CI95_LO: &str = "ci95_lo";
/// 95 % interval, upper end.
pub const COL_CI95_HI: &str = "ci95_hi";
/// `true` when the term is resolved (a fit the data show, or a region reading).
pub const COL_RESOLVED: &str = "resolved";
/// The term's verdict.
pub const COL_VERDICT: &str = "verdict";
/// Unit of value and interval.
pub const COL_UNIT: &str = "unit";
/// `fit` or `region` (IEEE 952 region reading: no reliable fit).
pub const COL_SOURCE: &str = "source";
/// The axis' fit: `fits`, `fits_range` (part of the curve), `fits_approximately` (the model
/// misses the curve beyond its statistics; see `AxisVerdict::Fits`) or `no_reliable_fit`.
pub const COL_FIT: &str = "fit";
/// First τ of the fitted range, s.
pub const COL_FIT_TAU_LO: &str = "fit_tau_lo";
/// Last τ of the fitted range, s.
pub const COL_FIT_TAU_HI: &str = "fit_tau_hi";
/// Statistical χ²/dof over the fitted range.
pub const COL_CHI2_DOF: &str = "chi2_per_dof";
/// Relative model discrepancy δ.
pub const COL_DISCREPANCY: &str = "model_discrepancy";
/// IEEE 952 region reading of the term (N, B, K).
pub const COL_REGION: &str = "region_value";
/// Its 95 % interval, lower end (0 for an upper bound).
pub const COL_REGION_LO: &str = "region_ci95_lo";
/// Its 95 % interval, upper end.
pub const COL_REGION_HI: &str = "region_ci95_hi";
/// Relative half-width of the 95 % interval of this record.
pub const COL_PRECISION: &str = "precision95";
/// Record length for ±10 % at 95 %, s.
pub const COL_RECORD_10: &str = "record_for_10pct_s";
/// Record length for ±25 % at 95 %, s.
pub const COL_RECORD_25: &str = "record_for_25pct_s";
/// The two records are lower bounds (a term not resolved: from its 95 % upper bound).
pub const COL_RECORD_AT_LEAST: &str = "record_is_lower_bound";

/// The columns of `ieee952_terms.csv`, in order.
pub const TERMS_COLUMNS: [&str; 23] = [
    COL_SENSOR,
    COL_AXIS,
    COL_TERM,
    COL_VALUE,
    COL_STD_ERR,
    COL_CI95_LO,
    COL_CI95_HI,
    COL_RESOLVED,
    COL_VERDICT,
    COL_UNIT,
    COL_SOURCE,
    COL_FIT,
    COL_FIT_TAU_LO,
    COL_FIT_TAU_HI,
    COL_CHI2_DOF,
    COL_DISCREPANCY,
    COL_REGION,
    COL_REGION_LO,
    COL_REGION_HI,
    COL_PRECISION,
    COL_RECORD_10,
    COL_RECORD_25,
    COL_RECORD_AT_LEAST,
];

/// `ieee952_curves.csv`: axis code (`gx` … `az`).
pub const CURVE_AXIS: &str = "axis";
/// Cluster size m.
pub const CURVE_M: &str = "m";
/// τ, s.
pub const CURVE_TAU: &str = "tau";
/// Allan deviation.
pub const CURVE_ADEV: &str = "adev";
/// The columns of `ieee952_curves.csv`, in order.
pub const CURVES_COLUMNS: [&str; 12] = [
    CURVE_AXIS,
    CURVE_M,
    CURVE_TAU,
    CURVE_ADEV,
    "adev_lo",
    "adev_hi",
    "edf",
    "alpha",
    "adev_lo95",
    "adev_hi95",
    "in_fit_range",
    "model_adev",
];

/// `ieee952_psd.csv`: the columns, in order (one-sided PSD in the axis' unit²/Hz).
pub const PSD_COLUMNS: [&str; 5] = ["axis", "freq_hz", "psd", "floor", "model_psd"];
/// PSD file name.
pub const PSD_FILE: &str = "ieee952_psd.csv";

/// File names (before the caller's prefix).
pub const TERMS_FILE: &str = "ieee952_terms.csv";
/// Curves file name.
pub const CURVES_FILE: &str = "ieee952_curves.csv";
/// Kalibr yaml file name.
pub const KALIBR_FILE: &str = "kalibr_imu_ieee952.yaml";
/// VINS yaml file name.
pub const VINS_FILE: &str = "vins_imu_ieee952.yaml";
/// ORB-SLAM3 yaml file name.
pub const ORBSLAM3_FILE: &str = "orbslam3_imu_ieee952.yaml";

/// The sample count a curves file states in its `# samples=N` comment line.
pub(crate) fn stated_samples(text: &str) -> Option<usize> {
    text.lines()
        .take_while(|l| l.starts_with('#'))
        .find_map(|l| {
            l.split(|c: char| c == ',' || c.is_whitespace())
                .find_map(|w| w.strip_prefix("samples="))
                .and_then(|v| v.parse().ok())
        })
}

/// Writes the terms and curves CSVs and the three configuration files into `dir`, each name
/// prefixed with `prefix`, among the run's `outputs`; returns the paths.
pub fn write_outputs(
    outputs: &bag2mat::shared::output::Outputs,
    a: &ImuAnalysis,
    dir: &Path,
    prefix: &str,
    rostopic: &str,
) -> Result<Vec<PathBuf>, bag2mat::Error> {
    let mut files = Vec::new();
    let mut put = |name: &str, text: String| -> Result<(), bag2mat::Error> {
        let p = dir.join(format!("{prefix}{name}"));
        outputs.write_atomic(&p, |w| w.write_all(text.as_bytes()))?;
        files.push(p);
        Ok(())
    };
    put(TERMS_FILE, terms_csv(a))?;
    put(CURVES_FILE, curves_csv(a))?;
    if a.axes.iter().any(|x| x.analysis.psd.is_some()) {
        put(PSD_FILE, psd_csv(a))?;
    }
    put(KALIBR_FILE, kalibr_yaml(a, rostopic))?;
    put(VINS_FILE, vins_yaml(a))?;
    put(ORBSLAM3_FILE, orbslam3_yaml(a))?;
    put(
        super::vio_files::OPENVINS_FILE,
        super::vio_files::openvins_yaml(a, rostopic),
    )?;
    put(
        super::vio_files::BASALT_FILE,
        super::vio_files::basalt_json(a),
    )?;
    Ok(files)
}

fn fit_code(v: &AxisVerdict) -> &'static str {
    match v {
        AxisVerdict::Fits {
            approximate: Some(_),
            ..
        } => "fits_approximately",
        AxisVerdict::Fits {
            short_cut: false,
            long_cut: false,
            ..
        } => "fits",
        AxisVerdict::Fits { .. } => "fits_range",
        AxisVerdict::NoReliableFit { .. } => "no_reliable_fit",
    }
}

/// Per axis and term: value, standard error, 95 % interval, verdict, unit, the axis' fit,
/// the region reading and the advice. Rust's `{}` float output is the shortest text that
/// reads back to the same double.
pub(crate) fn terms_csv(a: &ImuAnalysis) -> String {
    let mut s = String::from(
        "# IEEE 952 terms per axis, continuous time (N: noise density, K: random walk, B: bias instability, Q: quantization, R: ramp; G: Gauss-Markov bias sigma, GT its correlation time; BT: the bias-instability floor's lower corner, 0 for a flat floor)\n",
    );
    if let Some(x) = a.axes.first() {
        let _ = writeln!(
            s,
            "# samples={}, rate={} Hz",
            x.analysis.n.map_or("unknown".into(), |n| n.to_string()),
            a.rate
        );
    }
    s.push_str(&TERMS_COLUMNS.join(","));
    s.push('\n');
    for ax in &a.axes {
        write_axis_terms(&mut s, ax);
    }
    s
}

/// One row of [`terms_csv`] before it is written: the term's name, the term, its unit, its
/// region reading and its advice.
type TermRow<'a> = (
    &'static str,
    &'a Term,
    &'static str,
    Option<super::region::Reading>,
    super::advisor::TermAdvice,
);

/// The rows of [`terms_csv`] for the axis `ax`: its terms, then its shape parameters (the
/// Gauss–Markov correlation time and the flicker floor's lower corner).
fn write_axis_terms(s: &mut String, ax: &AxisResult) {
    let an = &ax.analysis;
    let sensor = ax.sensor;
    let axis = ["x", "y", "z"][ax.axis];
    let (lo_t, hi_t) = an.verdict.range().unwrap_or((f64::NAN, f64::NAN));
    let (chi, delta) = an
        .fit
        .as_ref()
        .filter(|_| an.verdict.fits())
        .map_or((f64::NAN, f64::NAN), |f| (f.chi2_per_dof, f.delta));
    for (name, t, unit, reg, adv) in term_rows(ax) {
        let source = if an.verdict.fits() { "fit" } else { "region" };
        let (rv, rl, rh) = reg.map_or((f64::NAN, f64::NAN, f64::NAN), |r| (r.value, r.lo, r.hi));
        let _ = writeln!(
            s,
            "{},{axis},{name},{},{},{},{},{},{:?},{unit},{source},{},{lo_t},{hi_t},{chi},{delta},{rv},{rl},{rh},{},{},{},{}",
            sensor.name(),
            t.value,
            t.std_err,
            t.lo,
            t.hi,
            t.reported().is_some(),
            t.verdict,
            fit_code(&an.verdict),
            adv.precision,
            adv.record_10,
            adv.record_25,
            adv.at_least
        );
    }
    // the shape parameters, as rows of their own: the Gauss–Markov correlation time
    // and the flicker floor's lower corner
    for (name, value, t) in [
        ("GT", an.terms.g_time, &an.terms.g),
        ("BT", an.terms.b_corner, &an.terms.b),
    ] {
        let _ = writeln!(
            s,
            "{},{axis},{name},{value},NaN,NaN,NaN,{},{:?},s,{},{},{lo_t},{hi_t},{chi},{delta},NaN,NaN,NaN,NaN,NaN,NaN,false",
            sensor.name(),
            t.reported().is_some(),
            t.verdict,
            if an.verdict.fits() { "fit" } else { "region" },
            fit_code(&an.verdict),
        );
    }
}

/// The six terms of the axis `ax` as [`terms_csv`] rows: Q, N, B, K, R and the Gauss–Markov
/// σ, with the region readings and advice of N, B and K (NaN advice for the others and
/// without a sample count).
fn term_rows(ax: &AxisResult) -> [TermRow<'_>; 6] {
    let an = &ax.analysis;
    let sensor = ax.sensor;
    let nan_adv = super::advisor::TermAdvice {
        precision: f64::NAN,
        record_10: f64::NAN,
        record_25: f64::NAN,
        at_least: false,
    };
    let adv = ax.advice;
    [
        ("Q", &an.terms.q, sensor.q_unit(), None, nan_adv),
        (
            "N",
            &an.terms.n,
            sensor.n_unit(),
            an.region.n,
            adv.map_or(nan_adv, |v| v.n),
        ),
        (
            "B",
            &an.terms.b,
            sensor.unit(),
            an.region.b,
            adv.map_or(nan_adv, |v| v.b),
        ),
        (
            "K",
            &an.terms.k,
            sensor.k_unit(),
            an.region.k,
            adv.map_or(nan_adv, |v| v.k),
        ),
        ("R", &an.terms.r, sensor.r_unit(), None, nan_adv),
        ("G", &an.terms.g, sensor.unit(), None, nan_adv),
    ]
}

/// The Allan deviation of every axis with its bounds, range flag and the fitted model.
pub(crate) fn curves_csv(a: &ImuAnalysis) -> String {
    let mut s = String::new();
    if let Some(x) = a.axes.first() {
        let _ = writeln!(
            s,
            "# samples={} tau0={} estimator={}",
            x.analysis.n.map_or("unknown".into(), |n| n.to_string()),
            x.analysis.tau0,
            match x.analysis.kind {
                Overlap::Overlapping => "overlapping",
                Overlap::Normal => "normal",
            }
        );
    }
    s.push_str(&CURVES_COLUMNS.join(","));
    s.push('\n');
    for ax in &a.axes {
        let code = ax.sensor.axis_code(ax.axis);
        for p in &ax.analysis.curve {
            let _ = writeln!(
                s,
                "{code},{},{},{},{},{},{},{},{},{},{},{}",
                p.m, p.tau, p.adev, p.lo, p.hi, p.edf, p.alpha, p.lo95, p.hi95, p.in_range, p.model
            );
        }
    }
    s
}

/// The Welch PSD of every axis (one-sided, unit²/Hz: rad²/s²/Hz, m²/s⁴/Hz), its local
/// floor, and the fitted model's PSD; comment lines list the lines found per axis.
pub(crate) fn psd_csv(a: &ImuAnalysis) -> String {
    let mut s = String::from(
        "# Welch PSD per axis: one-sided, in the axis unit squared per Hz (gyro rad^2/s^2/Hz, accelerometer m^2/s^4/Hz); white noise of density N has the level 2*N^2. floor: the running median the lines are found against; model_psd: the fitted IEEE 952 terms (a sinusoidal line has no density: listed below)\n",
    );
    for ax in &a.axes {
        let code = ax.sensor.axis_code(ax.axis);
        if let Some(p) = &ax.analysis.psd {
            let _ = writeln!(
                s,
                "# {code}: {} segments of {} samples (Hann, back to back), resolution {} Hz",
                p.segments,
                p.segment,
                p.resolution()
            );
        }
        for l in &ax.analysis.lines {
            let _ = writeln!(
                s,
                "# {code}: line at {} Hz, amplitude {} {}, bandwidth {} Hz, peak {}x the floor, Allan bump {}x the white noise's",
                l.frequency,
                l.amplitude,
                ax.sensor.unit(),
                l.bandwidth,
                l.peak_ratio,
                l.allan_ratio()
            );
        }
    }
    s.push_str(&PSD_COLUMNS.join(","));
    s.push('\n');
    for ax in &a.axes {
        let Some(p) = &ax.analysis.psd else { continue };
        let code = ax.sensor.axis_code(ax.axis);
        let fl = super::psd::floor(p);
        let fit = ax
            .analysis
            .fit
            .as_ref()
            .filter(|_| ax.analysis.verdict.fits());
        for ((f, d), fl) in p.freq.iter().zip(&p.density).zip(&fl) {
            let model = fit.map_or(f64::NAN, |x| {
                super::psd::model_psd(*f, &x.coef, &x.shapes, ax.analysis.tau0)
            });
            let _ = writeln!(s, "{code},{f},{d},{fl},{model}");
        }
    }
    s
}

fn key_line(o: &mut String, key: &str, v: Option<SensorValue>, comment: &str) {
    if let Some(v) = v {
        let c = format!("{comment}{}", inline_note(Some(v)));
        o.push_str(&crate::yaml::key_line(key, &yaml_float(v.value), &c));
    }
}

/// Kalibr `imu.yaml` (continuous-time, as Kalibr expects), in the layout of the compat file
/// ([`crate::yaml::ImuYaml`]).
pub(crate) fn kalibr_yaml(a: &ImuAnalysis, rostopic: &str) -> String {
    let v = file_values(
        a,
        [
            "accelerometer_noise_density",
            "accelerometer_random_walk",
            "gyroscope_noise_density",
            "gyroscope_random_walk",
        ],
    );
    let mut o = String::new();
    for c in [
        "IMU noise model for Kalibr from the IEEE 952 fit of the overlapping Allan deviation",
        "(largest of the three axes). These are CONTINUOUS-TIME values; Kalibr discretises",
        "them with update_rate. Values from static data are optimistic: users commonly",
        "inflate them (x10 or more) before use.",
        "This is the file to give Kalibr (imu.yaml beside it reproduces kalibr_allan's).",
    ] {
        let _ = writeln!(o, "# {c}");
    }
    for c in &v.comments {
        let _ = writeln!(o, "# {c}");
    }
    o.push_str("#Accelerometers\n");
    key_line(
        &mut o,
        "accelerometer_noise_density",
        v.acc_n,
        "Noise density (continuous-time)  [m/s^2/sqrt(Hz)]",
    );
    key_line(
        &mut o,
        "accelerometer_random_walk",
        v.acc_w,
        "Bias random walk                  [m/s^3/sqrt(Hz)]",
    );
    o.push_str("#Gyroscopes\n");
    key_line(
        &mut o,
        "gyroscope_noise_density",
        v.gyr_n,
        "Noise density (continuous-time)  [rad/s/sqrt(Hz)]",
    );
    key_line(
        &mut o,
        "gyroscope_random_walk",
        v.gyr_w,
        "Bias random walk                  [rad/s^2/sqrt(Hz)]",
    );
    o.push_str(&crate::yaml::key_line(
        "rostopic",
        &crate::yaml::yaml_str(rostopic),
        "the IMU ROS topic",
    ));
    o.push_str(&crate::yaml::key_line(
        "update_rate",
        &yaml_float(a.rate),
        "Hz (for discretization of the values above)",
    ));
    o
}

/// VINS-Mono / VINS-Fusion keys. Their comments say "standard deviation"; VINS uses them as
/// continuous-time densities (it multiplies by the integration period), so these are the
/// continuous-time values, stated in the file.
pub(crate) fn vins_yaml(a: &ImuAnalysis) -> String {
    let v = file_values(a, ["acc_n", "acc_w", "gyr_n", "gyr_w"]);
    let mut o = String::from("%YAML:1.0\n");
    let _ = writeln!(
        o,
        "# VINS-Mono / VINS-Fusion IMU parameters from the IEEE 952 fit (largest of the three axes).\n\
         # CONTINUOUS-TIME noise densities and random walks, not per-sample values at {} Hz.\n\
         # Static data give optimistic values: inflate before use.",
        a.rate
    );
    for c in &v.comments {
        let _ = writeln!(o, "# {c}");
    }
    let line = |o: &mut String, key: &str, x: Option<SensorValue>, c: &str| {
        if let Some(x) = x {
            let _ = writeln!(
                o,
                "{key}: {}   # {c}{}",
                yaml_float(x.value),
                inline_note(Some(x))
            );
        }
    };
    line(
        &mut o,
        "acc_n",
        v.acc_n,
        "accelerometer noise density [m/s^2/sqrt(Hz)]",
    );
    line(
        &mut o,
        "gyr_n",
        v.gyr_n,
        "gyroscope noise density [rad/s/sqrt(Hz)]",
    );
    line(
        &mut o,
        "acc_w",
        v.acc_w,
        "accelerometer bias random walk [m/s^3/sqrt(Hz)]",
    );
    line(
        &mut o,
        "gyr_w",
        v.gyr_w,
        "gyroscope bias random walk [rad/s^2/sqrt(Hz)]",
    );
    o.push_str("g_norm: 9.81   # gravity magnitude [m/s^2]\n");
    o
}

/// ORB-SLAM3 settings keys (continuous-time densities; ORB-SLAM3 discretises with
/// IMU.Frequency).
pub(crate) fn orbslam3_yaml(a: &ImuAnalysis) -> String {
    let v = file_values(
        a,
        [
            "IMU.NoiseAcc",
            "IMU.AccWalk",
            "IMU.NoiseGyro",
            "IMU.GyroWalk",
        ],
    );
    let mut o = String::from(
        "%YAML:1.0\n\
         # ORB-SLAM3 IMU noise from the IEEE 952 fit (largest of the three axes).\n\
         # CONTINUOUS-TIME values; ORB-SLAM3 discretises them with IMU.Frequency.\n\
         # Static data give optimistic values: inflate before use.\n",
    );
    for c in &v.comments {
        let _ = writeln!(o, "# {c}");
    }
    let line = |o: &mut String, key: &str, x: Option<SensorValue>, c: &str| {
        if let Some(x) = x {
            let _ = writeln!(
                o,
                "{key}: {}   # {c}{}",
                yaml_float(x.value),
                inline_note(Some(x))
            );
        }
    };
    line(&mut o, "IMU.NoiseGyro", v.gyr_n, "[rad/s/sqrt(Hz)]");
    line(&mut o, "IMU.NoiseAcc", v.acc_n, "[m/s^2/sqrt(Hz)]");
    line(&mut o, "IMU.GyroWalk", v.gyr_w, "[rad/s^2/sqrt(Hz)]");
    line(&mut o, "IMU.AccWalk", v.acc_w, "[m/s^3/sqrt(Hz)]");
    let _ = writeln!(o, "IMU.Frequency: {}   # [Hz]", yaml_float(a.rate));
    o
}
