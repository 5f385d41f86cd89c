//! The IEEE 952 analysis of a whole IMU, as both analysers run it next to their compat
//! outputs: up to six axes (gyro x y z, accelerometer x y z) from samples or from another
//! tool's curves, the record-length advice per axis, the record check's findings
//! (`bag2mat::check_record`, named in the verdicts), and the printed section. The files it writes are in [`super::files`].
//!
//! One value per sensor goes into the configuration files: the largest of the three axes
//! (the conservative choice, as allan_variance_ros writes), and never a number the data do
//! not support — see [`ImuAnalysis::sensor_value`].

use crate::consumers::SensorValue;
use std::fmt::Write as _;

use rayon::prelude::*;

use super::advisor::{self, Advice};
use super::{
    Analysis, AxisVerdict, Config, CovBasis, CurveData, Ieee952Error, Term, Verdict, analyse_curve,
    short,
};
use bag2mat::{Finding, FindingLevel};

/// τ/T_lo from which a flicker floor with lower corner T_lo is within 2 % of 0.664·B in
/// deviation (ψ(40) = 0.965: [`super::fit::flicker_band`]).
const BAND_FLOOR_X: f64 = 40.0;

use bag2mat::Sensor;

/// One analysed axis.
#[derive(Debug, Clone)]
pub struct AxisResult {
    /// Gyro or accelerometer.
    pub sensor: Sensor,
    /// 0, 1, 2 for x, y, z.
    pub axis: usize,
    /// The analysis.
    pub analysis: Analysis,
    /// Record-length advice (None without a sample count).
    pub advice: Option<Advice>,
}

/// The analysis of an IMU.
#[derive(Debug, Clone)]
pub struct ImuAnalysis {
    /// Sample rate, Hz (1/τ0).
    pub rate: f64,
    /// The axes, gyro first, x y z.
    pub axes: Vec<AxisResult>,
    /// What the record check found (samples only): gaps, clocks, outliers, warm-up, …
    pub checks: Vec<Finding>,
    /// Where the curves came from and what was inferred (for the printed section).
    pub notes: Vec<String>,
}

/// Groups curves by what their statistical covariance depends on, so each basis is built
/// once (the axes of an IMU share the grid, the sample count and the estimator).
fn bases(curves: &[&CurveData], cfg: &Config) -> Vec<Option<CovBasis>> {
    type Key = (Vec<usize>, Option<usize>, u64, super::Overlap);
    let mut keys: Vec<(Key, &CurveData)> = Vec::new();
    let mut which = Vec::with_capacity(curves.len());
    for c in curves {
        let key = (c.valid_ms(), c.n, c.tau0.to_bits(), c.kind);
        let i = keys.iter().position(|k| k.0 == key).unwrap_or_else(|| {
            keys.push((key, c));
            keys.len() - 1
        });
        which.push(i);
    }
    let built: Vec<Option<CovBasis>> = keys
        .par_iter()
        .map(|(_, c)| c.basis(cfg.fit.per_octave))
        .collect();
    which.into_iter().map(|i| built[i].clone()).collect()
}

/// Analyses measured curves: `sensors` holds each sensor's three axes; `rate` is 1/τ0.
pub fn analyse_curves(
    sensors: &[(Sensor, [CurveData; 3])],
    rate: f64,
    cfg: &Config,
) -> ImuAnalysis {
    let flat: Vec<(Sensor, usize, &CurveData)> = sensors
        .iter()
        .flat_map(|(s, axes)| axes.iter().enumerate().map(move |(i, c)| (*s, i, c)))
        .collect();
    let curves: Vec<&CurveData> = flat.iter().map(|x| x.2).collect();
    let basis = bases(&curves, cfg);
    let axes = flat
        .par_iter()
        .zip(basis.par_iter())
        .map(|((sensor, axis, c), b)| {
            let analysis = analyse_curve(c, cfg, b.as_ref());
            AxisResult {
                sensor: *sensor,
                axis: *axis,
                advice: advisor::advise(&analysis),
                analysis,
            }
        })
        .collect();
    ImuAnalysis {
        rate,
        axes,
        checks: Vec::new(),
        notes: Vec::new(),
    }
}

/// The part of the analysis of six rate series that reads the samples: each axis' curve.
/// What follows ([`ImuCurves::finish`]) needs only these, so a caller may hand
/// the sample columns on (the compat path turns them into prefix sums in place) while the
/// fits run.
#[derive(Debug, Clone)]
pub struct ImuCurves {
    /// Sample rate, Hz.
    pub rate: f64,
    /// Gyro x y z, then acc x y z (a sensor the topic does not carry left out).
    pub sensors: Vec<(Sensor, [CurveData; 3])>,
}

impl ImuCurves {
    /// Curves of six rate series (gyro x y z in rad/s, then acc x y z in m/s²) at `rate`
    /// Hz, the axes in parallel.
    pub fn from_samples(
        series: [&[f64]; 6],
        rate: f64,
        cfg: &Config,
    ) -> Result<ImuCurves, Ieee952Error> {
        Self::from_samples_of(series, None, rate, cfg)
    }

    /// [`ImuCurves::from_samples`] without the `absent` sensor's three series (a
    /// one-sensor topic: they are a stand-in, not read).
    pub(crate) fn from_samples_of(
        series: [&[f64]; 6],
        absent: Option<Sensor>,
        rate: f64,
        cfg: &Config,
    ) -> Result<ImuCurves, Ieee952Error> {
        let tau0 = 1.0 / rate;
        let present: Vec<Sensor> = [Sensor::Gyro, Sensor::Acc]
            .into_iter()
            .filter(|s| Some(*s) != absent)
            .collect();
        let wanted: Vec<&[f64]> = present
            .iter()
            .flat_map(|s| {
                let base = if *s == Sensor::Gyro { 0 } else { 3 };
                series[base..base + 3].iter().copied()
            })
            .collect();
        let data: Vec<CurveData> = wanted
            .par_iter()
            .map(|y| CurveData::from_samples(y, tau0, cfg))
            .collect::<Result<Vec<_>, _>>()?;
        let mut it = data.into_iter();
        let sensors = present
            .into_iter()
            .map(|s| {
                (
                    s,
                    std::array::from_fn(|_| it.next().expect("three per sensor")),
                )
            })
            .collect();
        Ok(ImuCurves { rate, sensors })
    }

    /// The fits and the advice; `checks` are the record check's findings on the series
    /// (`bag2mat::check_record`, which the caller has run to cut the record), named by the
    /// section and the files.
    pub fn finish(&self, checks: Vec<Finding>, cfg: &Config) -> ImuAnalysis {
        let mut an = analyse_curves(&self.sensors, self.rate, cfg);
        an.checks = checks;
        an
    }
}

/// The sample-reading part of the section both binaries print beside their compat output
/// ([`ImuCurves::from_samples_of`] with the default settings, without the `absent` sensor of
/// a one-sensor topic): data the analysis cannot use (too short, non-finite) only cost the
/// section, and the reason is added to `notes`.
pub(crate) fn section_curves_of(
    series: [&[f64]; 6],
    absent: Option<Sensor>,
    rate: f64,
    notes: &mut Vec<bag2mat::shared::note::Note>,
) -> Option<ImuCurves> {
    match ImuCurves::from_samples_of(series, absent, rate, &Config::default()) {
        Ok(c) => Some(c),
        Err(e) => {
            notes.push(bag2mat::shared::note::Note::warning(format!(
                "IEEE 952 analysis skipped: {e}"
            )));
            None
        }
    }
}

impl ImuAnalysis {
    /// The sensors present, gyro first.
    pub fn sensors(&self) -> Vec<Sensor> {
        let mut s: Vec<Sensor> = self.axes.iter().map(|a| a.sensor).collect();
        s.sort();
        s.dedup();
        s
    }

    /// The axes of one sensor.
    pub(crate) fn sensor_axes(&self, s: Sensor) -> impl Iterator<Item = &AxisResult> {
        self.axes.iter().filter(move |a| a.sensor == s)
    }

    /// One value of a term for a sensor (`term` picks it from the terms): the largest axis'
    /// value where any axis reports one (resolved, or an IEEE 952 region reading, marked);
    /// when none does, the largest 95 % upper bound, marked. Never capped by anything else:
    /// each axis' term already says what its data support (a resolved value above the whole
    /// record's bound is not resolved, [`Verdict::Contradicted`]). `None` when the sensor is
    /// absent or nothing is known.
    pub fn sensor_value(&self, s: Sensor, term: fn(&super::Terms) -> &Term) -> Option<SensorValue> {
        let terms: Vec<&Term> = self
            .sensor_axes(s)
            .map(|a| term(&a.analysis.terms))
            .collect();
        if terms.is_empty() {
            return None;
        }
        let reported = terms
            .iter()
            .filter_map(|t| {
                t.reported()
                    .map(|v| (v, t.verdict == Verdict::RegionReading))
            })
            .fold(None, |acc: Option<(f64, bool)>, x| match acc {
                Some(a) if a.0 >= x.0 => Some(a),
                _ => Some(x),
            });
        if let Some((v, region)) = reported {
            return Some(SensorValue {
                value: v,
                upper_bound: false,
                region: region || terms.iter().any(|t| t.verdict == Verdict::RegionReading),
            });
        }
        let hi = terms
            .iter()
            .map(|t| t.hi)
            .filter(|v| v.is_finite())
            .fold(f64::NAN, f64::max);
        hi.is_finite().then_some(SensorValue {
            value: hi,
            upper_bound: true,
            region: terms
                .iter()
                .any(|t| matches!(t.verdict, Verdict::RegionReading | Verdict::RegionBound)),
        })
    }

    /// White-noise density N of a sensor (see [`ImuAnalysis::sensor_value`]).
    pub fn noise_density(&self, s: Sensor) -> Option<SensorValue> {
        self.sensor_value(s, |t| &t.n)
    }

    /// Random walk K of a sensor (see [`ImuAnalysis::sensor_value`]).
    pub fn random_walk(&self, s: Sensor) -> Option<SensorValue> {
        self.sensor_value(s, |t| &t.k)
    }

    /// The record check's warnings on one axis (a warm-up, a spike).
    pub(crate) fn axis_checks(
        &self,
        sensor: Sensor,
        axis: usize,
    ) -> impl Iterator<Item = &Finding> {
        self.checks.iter().filter(move |f| {
            f.level >= FindingLevel::Warning
                && f.axis
                    .is_some_and(|x| x.sensor == sensor && x.index == axis)
        })
    }

    /// The record check's warnings, for the files' caveats.
    pub(crate) fn warnings(&self) -> impl Iterator<Item = &Finding> {
        self.checks
            .iter()
            .filter(|f| f.level >= FindingLevel::Warning)
    }

    /// Axes without a reliable fit, as `gyro y` labels.
    pub(crate) fn failed_axes(&self, s: Sensor) -> Vec<&'static str> {
        self.sensor_axes(s)
            .filter(|a| !a.analysis.verdict.fits())
            .map(|a| a.sensor.axis_label(a.axis))
            .collect()
    }

    /// Axes of one sensor whose fitted range was cut at the long end, by label, with the
    /// range's last τ.
    pub(crate) fn truncated_axes(&self, s: Sensor) -> Vec<String> {
        self.sensor_axes(s)
            .filter_map(|a| match a.analysis.verdict {
                AxisVerdict::Fits {
                    long_cut: true,
                    range,
                    ..
                } => Some(format!(
                    "{} (τ ≤ {} s)",
                    a.sensor.axis_label(a.axis),
                    short(range.1)
                )),
                _ => None,
            })
            .collect()
    }

    /// Axes of one sensor whose fit is declared only approximately (see
    /// [`AxisVerdict::Fits`]), by label.
    pub(crate) fn approximate_axes(&self, s: Sensor) -> Vec<&'static str> {
        self.sensor_axes(s)
            .filter(|a| {
                matches!(
                    a.analysis.verdict,
                    AxisVerdict::Fits {
                        approximate: Some(_),
                        ..
                    }
                )
            })
            .map(|a| a.sensor.axis_label(a.axis))
            .collect()
    }
}

fn term_text(t: &Term, unit: &str) -> String {
    let iv = |t: &Term| {
        if t.lo.is_finite() && t.hi.is_finite() {
            format!(" [95 %: {:.3e}, {:.3e}]", t.lo, t.hi)
        } else if t.hi.is_infinite() {
            format!(" [95 %: {:.3e}, unbounded]", t.lo)
        } else {
            " (no interval: sample count unknown)".into()
        }
    };
    match t.verdict {
        Verdict::Resolved => format!("{:.4e} {unit}{}", t.value, iv(t)),
        Verdict::NotSignificant => {
            if t.hi.is_finite() {
                format!("not resolved (95 % upper bound {:.2e} {unit})", t.hi)
            } else {
                "not resolved".into()
            }
        }
        Verdict::NeverDominant => format!(
            "not resolved: the curve never shows it on its own (fit {:.2e} {unit}; 95 % upper bound {:.2e} {unit})",
            t.value, t.hi
        ),
        Verdict::Contradicted => format!(
            "not resolved: the whole record does not agree with the fit (95 % upper bound from the curve {:.2e} {unit})",
            t.hi
        ),
        Verdict::RegionReading => {
            format!("{:.4e} {unit}{} (IEEE 952 region reading)", t.value, iv(t))
        }
        Verdict::RegionBound => format!(
            "not resolved (95 % upper bound {:.2e} {unit}, IEEE 952 region rule)",
            t.hi
        ),
        Verdict::NotFitted => "not in the fitted model".to_string(),
    }
}

fn verdict_line(a: &Analysis) -> String {
    let mut s = format!("{}", a.verdict);
    if let Some(f) = &a.fit
        && a.verdict.fits()
    {
        let _ = write!(s, "; χ²/dof {:.2}", f.chi2_per_dof);
        if f.delta > 0.0 {
            let _ = write!(s, ", model discrepancy {:.1} %", 100.0 * f.delta);
        }
    }
    if let AxisVerdict::NoReliableFit { .. } = a.verdict {
        s.push_str(" — terms below are IEEE 952 region readings");
    }
    s
}

/// The section both binaries print after their compat output.
pub fn summary_text(a: &ImuAnalysis) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "\n=> IEEE 952 noise terms (overlapping Allan deviation, Greenhall EDF, GLS fit with model discrepancy), continuous time, {} Hz",
        // the rate as measured (or implied by another tool's grid), to 4 decimals
        format!("{:.4}", a.rate)
            .trim_end_matches('0')
            .trim_end_matches('.')
    );
    for n in &a.notes {
        let _ = writeln!(s, "   note: {n}");
    }
    s.push_str(&lines_text(a));
    for ax in &a.axes {
        s.push_str(&axis_text(a, ax));
    }
    s.push_str(&advice_text(a));
    s.push_str(&checks_text(a));
    s.push_str(&values_text(a));
    s
}

/// One axis' lines of [`summary_text`]: the fit verdict, the terms, the cross-checks and
/// the caveats.
fn axis_text(a: &ImuAnalysis, ax: &AxisResult) -> String {
    let mut s = String::new();
    let an = &ax.analysis;
    let sensor = ax.sensor;
    let lab = sensor.axis_label(ax.axis);
    let _ = writeln!(s, "{lab:<7} fit: {}", verdict_line(an));
    let _ = writeln!(
        s,
        "{:<7} white noise N  = {}",
        "",
        term_text(&an.terms.n, sensor.n_unit())
    );
    let _ = writeln!(
        s,
        "{:<7} random walk K  = {}",
        "",
        term_text(&an.terms.k, sensor.k_unit())
    );
    let b = &an.terms.b;
    if b.verdict != Verdict::NotFitted {
        let _ = writeln!(
            s,
            "{:<7} bias instab. B = {}",
            "",
            term_text(b, sensor.unit())
        );
    }
    if an.terms.b_corner > 0.0 && an.terms.b.verdict != Verdict::NotFitted {
        let _ = writeln!(
            s,
            "{:<7} B's floor has a lower corner: within 2 % of 0.664*B from tau = {} s on (1/f spectrum down to a correlation time of {} s)",
            "",
            short(BAND_FLOOR_X * an.terms.b_corner),
            short(an.terms.b_corner)
        );
    }
    for (name, t, unit) in [
        ("quantiz. Q", &an.terms.q, sensor.q_unit()),
        ("rate ramp R", &an.terms.r, sensor.r_unit()),
    ] {
        if t.verdict == Verdict::Resolved {
            let _ = writeln!(s, "{:<7} {name:<15}= {}", "", term_text(t, unit));
        }
    }
    if an.terms.g.verdict != Verdict::NotFitted {
        let _ = writeln!(
            s,
            "{:<7} Gauss–Markov bias σ = {}, correlation time {} s (a bump: exponentially correlated noise, not B or K)",
            "",
            term_text(&an.terms.g, sensor.unit()),
            short(an.terms.g_time)
        );
    }
    if an.verdict.fits() {
        s.push_str(&readings_text(an));
    }
    for f in a.axis_checks(sensor, ax.axis) {
        let _ = writeln!(
            s,
            "{:<7} caveat: {} (see the warning on stderr)",
            "",
            f.short()
        );
    }
    s
}

/// An axis' region readings and PSD level, the cross-check beside its fit.
fn readings_text(an: &Analysis) -> String {
    let mut s = String::new();
    let r = &an.region;
    let rd = |x: Option<super::region::Reading>| match x {
        Some(x) if x.kind == super::region::ReadingKind::Line => format!("{:.3e}", x.value),
        Some(x) => format!("< {:.2e}", x.hi),
        None => "-".into(),
    };
    let psd_n = an
        .psd
        .as_ref()
        .zip(an.fit.as_ref())
        .zip(an.verdict.range())
        .and_then(|((p, f), (start, _))| {
            super::psd::white_density(p, &f.coef, &f.shapes, an.tau0, start)
        })
        .map_or("-".into(), |v| format!("{v:.3e}"));
    let _ = writeln!(
        s,
        "{:<7} region readings (cross-check): N {}  B {}  K {}; N from the PSD level {psd_n}",
        "",
        rd(r.n),
        rd(r.b),
        rd(r.k)
    );
    s
}

/// The continuous-time values per sensor that go to Kalibr, and which file holds them.
fn values_text(a: &ImuAnalysis) -> String {
    let mut s = String::new();
    for sensor in a.sensors() {
        let fmt = |v: Option<SensorValue>, unit: &str| match v {
            Some(v) => format!(
                "{:.8e} {unit}{}{}",
                v.value,
                if v.upper_bound {
                    " (not resolved: 95 % upper bound)"
                } else {
                    ""
                },
                if v.region { " (region reading)" } else { "" }
            ),
            None => "unknown".into(),
        };
        let _ = writeln!(
            s,
            "{}_noise_density = {}   {}_random_walk = {}",
            sensor.name(),
            fmt(a.noise_density(sensor), sensor.n_unit()),
            sensor.name(),
            fmt(a.random_walk(sensor), sensor.k_unit()),
        );
    }
    if !a.sensors().is_empty() {
        s.push_str(
            "for Kalibr: the kalibr_imu_ieee952.yaml written with these values (the upstream-compatible yaml reproduces the upstream tool)\n",
        );
    }
    s
}

/// One line over a sensor's axes: (frequency, largest ratio, amplitude, axes, in the model
/// on some axis, a resonance).
type LineGroup = (f64, f64, f64, Vec<&'static str>, bool, bool);

/// Lines of one sensor's axes whose frequencies agree within this fraction are one line.
pub const SAME_LINE_REL: f64 = 0.02;

/// The vibration lines the PSDs show, per sensor: "a line at 0.52 Hz, 6× the floor, on acc x
/// y z" (× the floor: the line's Allan bump over the white noise's deviation there, the
/// largest of its axes), and whether the model holds it.
pub(crate) fn lines_text(a: &ImuAnalysis) -> String {
    let mut s = String::new();
    for sensor in a.sensors() {
        let mut groups: Vec<LineGroup> = Vec::new();
        for ax in a.sensor_axes(sensor) {
            let modelled: Vec<f64> = ax
                .analysis
                .terms
                .lines
                .iter()
                .flatten()
                .map(|l| l.frequency)
                .collect();
            for l in &ax.analysis.lines {
                let in_model = modelled.contains(&l.frequency);
                let axis = ["x", "y", "z"][ax.axis];
                match groups
                    .iter_mut()
                    .find(|g| (g.0 / l.frequency - 1.0).abs() <= SAME_LINE_REL)
                {
                    Some(g) => {
                        if !g.3.contains(&axis) {
                            g.3.push(axis);
                        }
                        g.1 = g.1.max(l.allan_ratio());
                        g.2 = g.2.max(l.amplitude);
                        g.4 |= in_model;
                        g.5 |= l.bandwidth > 0.0;
                    }
                    None => groups.push((
                        l.frequency,
                        l.allan_ratio(),
                        l.amplitude,
                        vec![axis],
                        in_model,
                        l.bandwidth > 0.0,
                    )),
                }
            }
        }
        if groups.is_empty() {
            continue;
        }
        groups.sort_by(|x, y| x.0.total_cmp(&y.0));
        let list: Vec<String> = groups
            .iter()
            .map(|(f, r, amp, axes, m, res)| {
                format!(
                    "a {} at {} Hz, {:.1}× the floor (amplitude {:.2e} {}), on {} {}{}",
                    if *res { "resonance" } else { "line" },
                    short(*f),
                    r,
                    amp,
                    sensor.unit(),
                    sensor.short(),
                    axes.join(" "),
                    if *m {
                        ""
                    } else {
                        " (too weak to move the Allan curve)"
                    }
                )
            })
            .collect();
        let _ = writeln!(
            s,
            "{} PSD lines: {} — fitted as IEEE 952 sinusoidal terms, so the model describes the curve on both sides",
            sensor.name(),
            list.join("; ")
        );
    }
    s
}

/// The record-length advice lines.
pub(crate) fn advice_text(a: &ImuAnalysis) -> String {
    let mut s = String::new();
    let Some(record) = a.axes.iter().find_map(|x| x.advice.map(|v| v.record)) else {
        return s;
    };
    let _ = writeln!(
        s,
        "record length {}: 95 % precision of each term now, and the record for ±25 % / ±10 %",
        advisor::duration_text(record)
    );
    for ax in &a.axes {
        let Some(adv) = ax.advice else { continue };
        let one = |name: &str, t: &advisor::TermAdvice, term: &Term| -> String {
            if t.precision.is_finite() {
                // one decimal below 10 % (a white noise is often known to a few tenths), whole percent above
                let pct = 100.0 * t.precision;
                let d = if pct < 10.0 { 1 } else { 0 };
                format!(
                    "{name} ±{pct:.d$} % ({} / {})",
                    advisor::duration_text(t.record_25),
                    advisor::duration_text(t.record_10)
                )
            } else if term.verdict == Verdict::NotFitted {
                format!("{name} -")
            } else if t.at_least {
                format!(
                    "{name} not resolved: at least {} / {}",
                    advisor::duration_text(t.record_25),
                    advisor::duration_text(t.record_10)
                )
            } else {
                format!("{name} not resolved: longer than this record")
            }
        };
        let t = &ax.analysis.terms;
        let _ = writeln!(
            s,
            "{:<7} {}   {}   {}",
            ax.sensor.axis_label(ax.axis),
            one("N", &adv.n, &t.n),
            one("B", &adv.b, &t.b),
            one("K", &adv.k, &t.k)
        );
    }
    s
}

/// The record check's findings that concern no single axis (clocks, gaps, motion), one
/// line each; the warnings themselves are on stderr.
pub(crate) fn checks_text(a: &ImuAnalysis) -> String {
    let mut s = String::new();
    for f in a
        .checks
        .iter()
        .filter(|f| f.axis.is_none() && f.level >= FindingLevel::Warning)
    {
        let _ = writeln!(s, "record check: {} (see the warning on stderr)", f.short());
    }
    s
}
