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
//! * one config file per consumer of `crate::consumers::CONSUMERS` (Kalibr, OpenVINS, VINS,
//!   ORB-SLAM3, Basalt, PX4 EKF2, ArduPilot EKF3, GTSAM), rendered by
//!   [`crate::consumers::render`] from the section's figures
//!   ([`super::config_values::file_values`]): one value per sensor (the largest axis); a term
//!   no axis resolves is its 95 % upper bound, marked; an axis without a reliable fit
//!   contributes its IEEE 952 region readings, and the file says so. A missing sensor's keys
//!   are left out (with a comment) rather than written as a number. Every warning of the
//!   record check (`bag2mat::check_record`: warm-up, spike, gaps, clocks) is a caveat.
//!
//! Every file names the tool, its version, the input and the time it was written
//! ([`crate::consumers::Provenance`]); the CSVs in a comment line after their first.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use super::config_values::file_values;
use super::imu::{AxisResult, ImuAnalysis};
use super::{AxisVerdict, Overlap, Term};
use crate::consumers::{CONSUMERS, Provenance};

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

/// The names, each after `prefix`, of every file the section may write: [`write_outputs`]'
/// and its charts' (`super::plot`).
pub fn file_names(prefix: &str) -> Vec<String> {
    let mut v: Vec<String> = [TERMS_FILE, CURVES_FILE, PSD_FILE]
        .iter()
        .chain(CONSUMERS.iter().map(|c| &c.file))
        .map(|n| format!("{prefix}{n}"))
        .collect();
    for stem in [super::plot::STEM, super::psd_plot::STEM] {
        for ext in ["png", "svg"] {
            v.push(format!("{prefix}{stem}.{ext}"));
        }
    }
    v
}

/// Writes the terms and curves CSVs (and the PSD's, from samples) and one configuration file
/// per consumer into `dir`, each name prefixed with `prefix`, among the run's `outputs`, each
/// saying `prov`; returns the paths.
pub fn write_outputs(
    outputs: &bag2mat::shared::output::Outputs,
    a: &ImuAnalysis,
    dir: &Path,
    prefix: &str,
    rostopic: &str,
    prov: &Provenance,
) -> Result<Vec<PathBuf>, bag2mat::Error> {
    let mut files = Vec::new();
    let mut put = |name: &str, text: String| -> Result<(), bag2mat::Error> {
        let p = dir.join(format!("{prefix}{name}"));
        outputs.write_atomic(&p, |w| w.write_all(text.as_bytes()))?;
        files.push(p);
        Ok(())
    };
    let stamp = format!("# {}\n", prov.line());
    put(TERMS_FILE, with_line_after_first(&terms_csv(a), &stamp))?;
    put(CURVES_FILE, with_line_after_first(&curves_csv(a), &stamp))?;
    if a.axes.iter().any(|x| x.analysis.psd.is_some()) {
        put(PSD_FILE, with_line_after_first(&psd_csv(a), &stamp))?;
    }
    let values = file_values(a);
    for c in &CONSUMERS {
        put(
            c.file,
            crate::consumers::render(c.id, &values, prov, rostopic),
        )?;
    }
    Ok(files)
}

/// `text` with `line` inserted after its first line (the CSVs' first comment line is what
/// readers of the files look at first: `# samples=…`).
fn with_line_after_first(text: &str, line: &str) -> String {
    match text.split_once('\n') {
        Some((first, rest)) => format!("{first}\n{line}{rest}"),
        None => format!("{text}{line}"),
    }
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
