//! The noise the estimator will see: the operating-condition noise density of a moving
//! record, with a 95 % interval, its ratio to the static value and where the excess comes
//! from (`allan_kalibr LOG --reference POSES`, or `--operating` without a reference).
//!
//! A static Allan analysis measures the sensor at rest; in operation an estimator also
//! meets vibration lines, a broadband floor lifted by the platform, motion-correlated errors
//! (scale, misalignment, g-sensitivity), timing errors — and, when the motion is known only
//! through a reference, the reference's own error. The analysis separates them:
//!
//! * **With a reference** ([`reference`](mod@reference), [`calibrate`]): the continuous-time B-spline
//!   ([`crate::spline`]) is fitted to the poses with the knot spacing that leaves the widest
//!   clean band (its own error, model and reference noise, is estimated for each candidate);
//!   it predicts the body rate and the specific force; the IMU-to-reference rotation, the
//!   time offset, scale and misalignment, g-sensitivity, the lever arm, the gravity direction
//!   and the biases with their drift are estimated **jointly** (what a calibration would
//!   remove, so it is not counted as noise); the residual is the operating noise.
//! * **Without a reference** ([`signal`]): the motion's band is read from the signal's
//!   own PSD (where it rises above the high-frequency floor); above it the signal is the
//!   operating noise, and what cannot be told apart there is said plainly.
//!
//! In both, [`band`] computes per axis the operating noise density N_op — the white-noise
//! density whose per-sample variance equals the residual's in the estimator's band (the
//! density the estimator's discretisation σ_d = N·√f_s needs) — with its 95 % interval
//! (Satterthwaite's χ² on the Welch bins, the lines as deterministic sinusoids, the spline's
//! taken-out error counted whole), and its parts: the broadband floor, each vibration line
//! (frequency, amplitude, and whether it aliases at the estimator's rate), and beside them
//! what the calibration removed (motion-correlated errors, the time offset) and the spline's
//! error. [`phases`] cuts the record by flight phase (still, vibrating in place, moving) on
//! the signal's spectrogram and gives each phase its lines and density; its longest still
//! stretch gives a static value when no `--static` record or value is given. The outputs
//! (`files`, `plot`, `report`) are `operating_noise.csv`, `operating_lines.csv`,
//! `operating_phases.csv`, `operating_calibration.yaml`, the residual PSD chart and the
//! spectrogram, and the Kalibr/VINS/ORB-SLAM3/OpenVINS/Basalt files with the operating values
//! (`operating_*`), the static analysis' beside them (`static_*`).

pub mod band;
pub mod calibrate;
mod files;
pub mod phases;
mod plot;
pub mod reference;
mod report;
pub mod signal;

use std::path::{Path, PathBuf};

use bag2mat::Sensor;
use bag2mat::shared::note::Note;
use bag2mat::shared::output::Outputs;

use crate::consumers::{Provenance, RecordRate, input_text};
use crate::error::Error;
pub use crate::error::OperatingError;
use crate::front::Common;
use crate::front::Section;
use crate::ieee952::imu::{ImuAnalysis, ImuCurves};
use crate::input::{self, ImuData};

/// The flags of the analysis, flattened into `allan_kalibr`'s arguments.
#[derive(Debug, Clone, PartialEq, clap::Args)]
pub struct OperatingArgs {
    /// Analyse the noise in operation against this reference trajectory: a TUM file (t tx ty
    /// tz qx qy qz qw), an EuRoC/ASL ground truth (state_groundtruth_estimate0/data.csv, its
    /// folder or the dataset), or a bag with a pose or odometry topic.
    #[arg(long, value_name = "POSES")]
    pub reference: Option<PathBuf>,
    /// The pose topic of a --reference bag (PoseStamped, PoseWithCovarianceStamped,
    /// TransformStamped, Odometry) [default: its only pose topic].
    #[arg(long, value_name = "TOPIC", requires = "reference")]
    pub reference_topic: Option<String>,
    /// Analyse the noise in operation of a moving record without a reference (flight or
    /// drive log): the motion's band from the signal, the noise above it.
    #[arg(long, conflicts_with = "reference")]
    pub operating: bool,
    /// A static record of the same IMU whose IEEE 952 noise density the operating one is
    /// compared with [default: the record's own longest still stretch, if any].
    #[arg(long = "static", value_name = "LOG")]
    pub static_log: Option<PathBuf>,
    /// The static noise densities to compare with, GYRO,ACC in rad/s/√Hz and m/s²/√Hz
    /// (continuous time, Kalibr's *_noise_density).
    #[arg(long, value_name = "GYRO,ACC", conflicts_with = "static_log")]
    pub static_density: Option<String>,
    /// The estimator's band, LO:HI in Hz [default: from the bias and motion band (or the
    /// spline's error) to the Nyquist frequency].
    #[arg(long, value_name = "LO:HI")]
    pub band: Option<String>,
    /// The reference spline's knot spacing, s [default: chosen from the reference's noise
    /// and the motion].
    #[arg(long, value_name = "S", value_parser = bag2mat::shared::cli::positive_f64)]
    pub knot_dt: Option<f64>,
    /// The largest time offset between the IMU's and the reference's clocks searched, s.
    #[arg(long, value_name = "S", default_value_t = 1.0, value_parser = bag2mat::shared::cli::positive_f64)]
    pub max_offset: f64,
    /// The rate the estimator reads the IMU at, Hz, when lower than the log's: lines above
    /// its Nyquist frequency alias [default: the log's rate].
    #[arg(long, value_name = "HZ", value_parser = bag2mat::shared::cli::positive_f64)]
    pub estimator_rate: Option<f64>,
}

/// Where the static value comes from.
#[derive(Debug, Clone, PartialEq)]
pub enum StaticSource {
    /// The IEEE 952 analysis of a static record.
    Log(PathBuf),
    /// Given densities, gyro and acc.
    Density(f64, f64),
    /// The record's own longest still stretch.
    StillStretch,
}

/// The analysis' settings.
#[derive(Debug, Clone, PartialEq)]
pub struct Settings {
    /// The reference and its topic (`None`: no reference).
    pub reference: Option<(PathBuf, Option<String>)>,
    /// The static value's source.
    pub static_source: StaticSource,
    /// A band the user gave, Hz.
    pub band: Option<(f64, f64)>,
    /// A knot spacing the user gave, ns.
    pub knot_dt_ns: Option<i64>,
    /// Time-offset search range, s.
    pub max_offset: f64,
    /// The estimator's rate, Hz.
    pub estimator_rate: Option<f64>,
}

impl OperatingArgs {
    /// The settings, `None` when neither `--reference` nor `--operating` asks for the
    /// analysis (its other flags are then an error).
    pub fn resolve(self) -> Result<Option<Settings>, bag2mat::shared::cli::UsageError> {
        use bag2mat::shared::cli::{UsageError, only_with};
        let on = self.reference.is_some() || self.operating;
        only_with(
            "--reference or --operating",
            on,
            &[
                ("--static", self.static_log.is_some()),
                ("--static-density", self.static_density.is_some()),
                ("--band", self.band.is_some()),
                ("--knot-dt", self.knot_dt.is_some()),
                ("--estimator-rate", self.estimator_rate.is_some()),
            ],
        )?;
        if !on {
            return Ok(None);
        }
        let pair = |flag: &str, s: &str, sep: char| -> Result<(f64, f64), UsageError> {
            let bad = || UsageError(format!("{flag} {s:?}: give two positive numbers A{sep}B"));
            let (a, b) = s.split_once(sep).ok_or_else(bad)?;
            let (a, b): (f64, f64) = (
                a.trim().parse().map_err(|_| bad())?,
                b.trim().parse().map_err(|_| bad())?,
            );
            if !(a.is_finite() && b.is_finite() && a >= 0.0 && b > 0.0) {
                return Err(bad());
            }
            Ok((a, b))
        };
        let static_source = match (&self.static_log, &self.static_density) {
            (Some(p), _) => StaticSource::Log(p.clone()),
            (None, Some(s)) => {
                let (g, a) = pair("--static-density", s, ',')?;
                if g <= 0.0 {
                    return Err(UsageError(
                        "--static-density: both densities must be positive".into(),
                    ));
                }
                StaticSource::Density(g, a)
            }
            (None, None) => StaticSource::StillStretch,
        };
        let band = match &self.band {
            Some(s) => {
                let (lo, hi) = pair("--band", s, ':')?;
                if lo >= hi {
                    return Err(UsageError(format!("--band {s:?}: LO must be below HI")));
                }
                Some((lo, hi))
            }
            None => None,
        };
        Ok(Some(Settings {
            reference: self.reference.map(|r| (r, self.reference_topic)),
            static_source,
            band,
            knot_dt_ns: self.knot_dt.map(|s| (s * 1e9).round() as i64),
            max_offset: self.max_offset,
            estimator_rate: self.estimator_rate,
        }))
    }
}

/// A static value of one axis.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StaticValue {
    /// The density.
    pub value: f64,
    /// Its 95 % interval (NaN when unknown).
    pub lo: f64,
    /// Upper end.
    pub hi: f64,
    /// The value is a 95 % upper bound (the static analysis did not resolve N).
    pub bound: bool,
}

/// One analysed axis.
#[derive(Debug, Clone, PartialEq)]
pub struct AxisOperating {
    /// Gyro or accelerometer.
    pub sensor: Sensor,
    /// 0, 1, 2 for x, y, z.
    pub axis: usize,
    /// N_op in its band, with its interval and parts.
    pub band: band::AxisBand,
    /// What the calibration's scale, misalignment and g-sensitivity removed, as a density
    /// in the band (what they add if the estimator does not calibrate them; NaN without a
    /// reference).
    pub motion_n: f64,
    /// The time offset's share if the estimator did not compensate it, as a density.
    pub offset_n: f64,
    /// The IMU stamps' jitter's share (in N_op), as a density.
    pub jitter_n: f64,
    /// The static value.
    pub static_n: Option<StaticValue>,
}

impl AxisOperating {
    /// N_op / N_static with its 95 % interval (the two intervals' log-widths in
    /// quadrature, each read as ±1.96 standard errors).
    pub fn ratio(&self) -> Option<(f64, f64, f64)> {
        let s = self.static_n?;
        let r = self.band.n / s.value;
        let w = |v: f64, lo: f64, hi: f64| {
            if lo > 0.0 && hi > 0.0 && lo.is_finite() && hi.is_finite() {
                ((hi / lo).ln() / 2.0).max((v / lo).ln()).max((hi / v).ln())
            } else {
                0.0
            }
        };
        let a = w(self.band.n, self.band.lo, self.band.hi);
        let b = if s.bound { 0.0 } else { w(s.value, s.lo, s.hi) };
        let hw = (a * a + b * b).sqrt();
        Some((r, r * (-hw).exp(), r * hw.exp()))
    }
}

/// The reference side of an analysis.
#[derive(Debug, Clone)]
pub struct WithReference {
    /// What was read.
    pub what: String,
    /// Poses read.
    pub poses: usize,
    /// Median pose spacing, s.
    pub pose_dt: f64,
    /// The reference noise, m and rad per coordinate.
    pub noise: (f64, f64),
    /// Knot spacing kept, s, and each candidate's clean band edge (s, Hz).
    pub knot_dt: f64,
    /// The candidates weighed.
    pub candidates: Vec<(f64, f64)>,
    /// The knot spacing was given.
    pub knot_given: bool,
    /// The calibration.
    pub calibration: calibrate::Calibration,
    /// The stamps' jitter, s (RMS about a uniform grid).
    pub jitter: f64,
}

/// The whole analysis of one topic.
#[derive(Debug, Clone)]
pub struct Operating {
    /// The reference side (`None`: from the signal alone).
    pub reference: Option<WithReference>,
    /// Sample rate, Hz.
    pub rate: f64,
    /// The estimator's rate, Hz.
    pub estimator_rate: f64,
    /// Samples analysed.
    pub samples: usize,
    /// First analysed sample's time, s (the IMU's clock).
    pub t0: f64,
    /// The analysed samples: the checked record's indices `range.0..range.1`.
    pub range: (usize, usize),
    /// The axes, gyro first.
    pub axes: Vec<AxisOperating>,
    /// The motion band's upper edge per sensor from the signal, Hz (gyro, acc).
    pub motion_edge: [Option<f64>; 2],
    /// The record by flight phase.
    pub phases: Vec<phases::Phase>,
    /// The spectrogram the phases come from.
    pub spectrogram: phases::Spectrogram,
    /// Where the static value comes from (words).
    pub static_source: String,
    /// The static IEEE 952 analysis, when there is one.
    pub static_an: Option<ImuAnalysis>,
    /// The IEEE 952 analysis of the operating noise series (residual plus its bias): K
    /// and the carrier of the configuration files.
    pub operating_an: Option<ImuAnalysis>,
    /// The operating noise series per section axis (the residual with its bias, or the
    /// signal above the motion band), which that analysis reads.
    pub noise_series: [Vec<f64>; 6],
    /// What the report says besides the numbers.
    pub notes: Vec<String>,
    /// What this analysis cannot separate, plainly.
    pub cannot_separate: Vec<String>,
}

/// The six analysed series: index in the section order (gyro x y z, acc x y z), sensor, axis.
pub const AXES: [(usize, Sensor, usize); 6] = [
    (0, Sensor::Gyro, 0),
    (1, Sensor::Gyro, 1),
    (2, Sensor::Gyro, 2),
    (3, Sensor::Acc, 0),
    (4, Sensor::Acc, 1),
    (5, Sensor::Acc, 2),
];

/// The section's six series (gyro x y z, then acc x y z) of the `data_imu`-ordered columns.
fn series_of(a: &[Vec<f64>; 6]) -> [&[f64]; 6] {
    [&a[3], &a[4], &a[5], &a[0], &a[1], &a[2]]
}

/// The record after the checks that do not concern motion (gaps, clocks, duplicates,
/// spikes): the samples kept, the findings (motion dropped: it is what is analysed), the
/// rate.
fn prepare(
    common: &Common,
    mut data: ImuData,
    notes: &mut Vec<Note>,
) -> Result<(ImuData, Vec<bag2mat::Finding>, f64), Error> {
    if let Some(skip) = common.skip_start {
        input::skip_start(&mut data, skip, notes)?;
    }
    if data.len() < 3 {
        return Err(Error::TooShort { n: data.len() });
    }
    let scans = data.scan_checked()?;
    input::check_scans(&scans, data.absent, notes)?;
    let check = bag2mat::check_record(
        &data.record(),
        &bag2mat::CheckOptions {
            drop_outliers: common.drop_outliers,
        },
    );
    let mut findings: Vec<bag2mat::Finding> = check
        .findings
        .iter()
        .filter(|f| f.kind != bag2mat::FindingKind::Motion)
        .cloned()
        .collect();
    bag2mat::drop_absent(&mut findings, data.absent);
    notes.extend(data.absent.map(bag2mat::absent_warning));
    let data = data.select(&check.keep);
    let rate = input::choose_rate(common.rate, check.rate, data.len())?;
    findings.extend(rate.finding.clone());
    Ok((data, findings, rate.section))
}

/// The static IEEE 952 analysis of `path` (its first topic as the config's selection reads
/// it), refused when it moves.
fn static_analysis(common: &Common, path: &Path) -> Result<ImuAnalysis, Error> {
    let err = |what: String| OperatingError::Static {
        path: path.to_path_buf(),
        what,
    };
    let mut datas = input::load_all(
        path,
        &common.topics,
        common.time,
        true,
        &common.input_options,
    )?;
    if datas.is_empty() {
        return Err(err("no IMU topic".into()).into());
    }
    let data = datas.remove(0);
    let scans = data.scan_checked()?;
    input::check_scans(&scans, data.absent, &mut Vec::new())?;
    let check = bag2mat::check_record(&data.record(), &bag2mat::CheckOptions::default());
    if let Some(r) = check.refusal() {
        return Err(err(format!("not a static record: {}", r.short())).into());
    }
    let absent = data.absent;
    let findings = check.findings.clone();
    let data = data.select(&check.keep);
    let rate = input::choose_rate(None, check.rate, data.len())?;
    let curves = ImuCurves::from_samples_of(
        series_of(&data.axes),
        absent,
        rate.section,
        &crate::ieee952::Config::default(),
    )
    .map_err(|e| err(e.to_string()))?;
    Ok(curves.finish(findings, &crate::ieee952::Config::default()))
}

/// The static value of an axis from an IEEE 952 analysis.
fn static_of(an: &ImuAnalysis, sensor: Sensor, axis: usize) -> Option<StaticValue> {
    let ax = an
        .axes
        .iter()
        .find(|a| a.sensor == sensor && a.axis == axis)?;
    let t = &ax.analysis.terms.n;
    match t.reported() {
        Some(v) => Some(StaticValue {
            value: v,
            lo: t.lo,
            hi: t.hi,
            bound: false,
        }),
        None => t.hi.is_finite().then_some(StaticValue {
            value: t.hi,
            lo: f64::NAN,
            hi: t.hi,
            bound: true,
        }),
    }
}

/// What every topic of one run shares: the run's settings, the reference and static
/// analysis read once, and where the files go.
struct RunContext<'a> {
    /// The tool writing the files (their provenance).
    tool: &'a str,
    /// The settings both analysers share.
    common: &'a Common,
    /// The chart title (empty: the input's file stem).
    title: &'a str,
    /// The analysis' own settings.
    settings: &'a Settings,
    /// The reference trajectory (`--reference`).
    reference: Option<&'a bag2mat::PoseSeries>,
    /// The static record's IEEE 952 analysis (`--static LOG`).
    static_an: Option<&'a ImuAnalysis>,
    /// The run's output stage.
    outputs: &'a Outputs,
}

/// Runs the analysis on every selected topic; each gets its own folder when there are
/// several. Every file among `outputs`, said as written by `tool`.
pub(crate) fn sections(
    tool: &str,
    common: &Common,
    title: &str,
    s: &Settings,
    outputs: &Outputs,
) -> Result<Vec<Section>, Error> {
    let datas = input::load_all(
        common.samples_path(),
        &common.topics,
        common.time,
        common.quiet,
        &common.input_options,
    )?;
    let reference = match &s.reference {
        Some((path, topic)) => Some(
            bag2mat::read_poses(
                path,
                &bag2mat::PoseOptions {
                    topic: topic.clone(),
                    time: common.time,
                },
            )
            .map_err(|e| OperatingError::Reference {
                path: path.clone(),
                what: e.to_string(),
            })?,
        ),
        None => None,
    };
    let static_an = match &s.static_source {
        StaticSource::Log(p) => Some(static_analysis(common, p)?),
        _ => None,
    };
    let several = datas.len() > 1 || common.topics.all_imu;
    let names: Vec<String> = datas
        .iter()
        .map(|d| d.topic.clone().unwrap_or_default())
        .collect();
    let names: Vec<&str> = names.iter().map(|s| s.as_str()).collect();
    let folders = bag2mat::topic_folder_names(&names);
    let ctx = RunContext {
        tool,
        common,
        title,
        settings: s,
        reference: reference.as_ref(),
        static_an: static_an.as_ref(),
        outputs,
    };
    let mut out = Vec::new();
    for (data, folder) in datas.into_iter().zip(folders) {
        let dir = if several {
            common.out_dir.join(folder)
        } else {
            common.out_dir.clone()
        };
        let topic = data.topic.clone().unwrap_or_default();
        let notes = data.notes.clone();
        match run_topic(&ctx, data, &dir) {
            Ok(section) => out.push(section),
            // one topic of several: said as its error, the others still written (the rule
            // of both analysers' own runs, `crate::run::sections`)
            Err(e) if several => out.push(crate::front::topic_failed(&topic, notes, &e)),
            Err(e) => return Err(e),
        }
    }
    Ok(out)
}

/// One topic: checks, the analysis, its files and its text.
fn run_topic(ctx: &RunContext, data: ImuData, dir: &Path) -> Result<Section, Error> {
    let RunContext {
        tool,
        common,
        title,
        settings: s,
        reference,
        static_an,
        outputs,
    } = *ctx;
    let mut notes = data.notes.clone();
    let topic_name = data.topic.clone();
    let topic = data
        .topic
        .clone()
        .unwrap_or_else(|| common.named_topic().to_string());
    let (data, findings, rate) = prepare(common, data, &mut notes)?;
    if let Some(r) = reference {
        notes.extend(r.notes.iter().map(|n| Note {
            text: format!("reference: {}", n.text),
            ..n.clone()
        }));
    }
    let mut op = match reference {
        Some(r) => analyse_with_reference(&data, rate, r, s)?,
        None => signal::analyse(&data, rate, s).map_err(OperatingError::Record)?,
    };
    // the static value
    match (&s.static_source, static_an) {
        (StaticSource::Log(p), Some(an)) => {
            op.static_source = format!("{} (IEEE 952 fit of the static record)", p.display());
            op.static_an = Some(an.clone());
        }
        (StaticSource::Density(g, a), _) => {
            op.static_source = format!("given: gyro {g:e} rad/s/√Hz, acc {a:e} m/s²/√Hz");
        }
        _ => {
            let series = series_of(&data.axes);
            let cols: [&[f64]; 6] = std::array::from_fn(|i| &series[i][op.range.0..op.range.1]);
            if let Some((an, from, to)) =
                phases::still_analysis(&cols, data.absent, rate, &op.phases)
            {
                op.static_source =
                    format!("the record's still stretch {from:.1} – {to:.1} s (IEEE 952 fit)");
                op.static_an = Some(an);
            } else {
                op.static_source = "none: no --static record or value, and no still stretch long enough in the record".into();
            }
        }
    }
    for ax in op.axes.iter_mut() {
        ax.static_n = match &s.static_source {
            StaticSource::Density(g, a) => Some(StaticValue {
                value: if ax.sensor == Sensor::Gyro { *g } else { *a },
                lo: f64::NAN,
                hi: f64::NAN,
                bound: false,
            }),
            _ => op
                .static_an
                .as_ref()
                .and_then(|an| static_of(an, ax.sensor, ax.axis)),
        };
    }
    op.operating_an = files::operating_analysis(&op, &findings);
    let title = if title.is_empty() {
        common
            .input
            .first()
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default()
    } else {
        title.to_string()
    };
    outputs.ensure_dir(dir)?;
    let prov = Provenance::new(
        tool,
        input_text(common.samples_path(), topic_name.as_deref()),
        match common.rate {
            Some(r) => RecordRate::Given(r),
            None => RecordRate::Measured(rate),
        },
    );
    let mut written = files::write(outputs, &op, dir, &topic, &prov)?;
    written.extend(plot::write(outputs, &op, &title, dir)?);
    Ok(Section {
        topic: topic_name,
        notes,
        findings,
        text: report::text(&op),
        ieee952_text: None,
        written,
        timings: Vec::new(),
        error: None,
    })
}

/// The analysis against a reference (module docs).
fn analyse_with_reference(
    data: &ImuData,
    rate: f64,
    r: &bag2mat::PoseSeries,
    s: &Settings,
) -> Result<Operating, Error> {
    let rerr = |what: String| OperatingError::Reference {
        path: s
            .reference
            .as_ref()
            .map(|x| x.0.clone())
            .unwrap_or_default(),
        what,
    };
    let poses = reference::poses_of(r);
    let series = series_of(&data.axes);
    let present = |sensor: Sensor| data.absent != Some(sensor);
    // the IMU's floor per sensor (its signal's PSD high above the motion)
    let floor = [Sensor::Gyro, Sensor::Acc].map(|sensor| {
        present(sensor)
            .then(|| signal::high_floor(&series, sensor, rate))
            .flatten()
    });
    let choice = reference::choose(&poses, s.knot_dt_ns, rate, floor).map_err(rerr)?;
    let pose_gap = (3 * choice.pose_dt_ns).max(2 * choice.fits.dt_ns);
    let covered = |t: i64| {
        let i = poses.partition_point(|p| p.t_ns < t);
        i > 0 && i < poses.len() && poses[i].t_ns - poses[i - 1].t_ns <= pose_gap
    };
    let t_ns = &data.clock.t_ns;
    let imu = calibrate::ImuSeries {
        t_ns,
        gyro: present(Sensor::Gyro).then_some([series[0], series[1], series[2]]),
        acc: present(Sensor::Acc).then_some([series[3], series[4], series[5]]),
        rate,
    };
    // the covered test also moves with the offset: a sample is covered when its
    // reference time is (the offset is at most --max-offset, within the margin)
    let (cal, fitted) = calibrate::calibrate(
        &imu,
        &choice.fits.spline,
        choice.fits.dt_ns,
        &covered,
        s.max_offset,
    )
    .map_err(rerr)?;
    let (k0, k1) = fitted.range;
    let shift = (cal.dt * 1e9).round() as i64;
    // the spline's error at the samples, in the IMU's axes
    let errs: Vec<(nalgebra::Vector3<f64>, nalgebra::Vector3<f64>)> = {
        use rayon::prelude::*;
        (k0..k1)
            .into_par_iter()
            .map(|k| {
                let (g, a) = choice.fits.error_at(t_ns[k] + shift);
                (cal.a_g * g, cal.a_a * a)
            })
            .collect()
    };
    let jitter = stamp_jitter(&t_ns[k0..k1]);
    let mut axes = Vec::new();
    let band_lo_min = signal::BAND_LO_MIN.max(signal::BIAS_BAND_FACTOR / cal.bias_knot);
    for (a, sensor, axis) in AXES {
        if !present(sensor) {
            continue;
        }
        let err: Vec<f64> = errs
            .iter()
            .map(|e| if a < 3 { e.0[axis] } else { e.1[axis] })
            .collect();
        let b = band::analyse(&band::BandInput {
            y: &fitted.residual[a],
            rate,
            spline_err: Some(&err),
            band: s.band,
            lo_min: band_lo_min,
        })
        .map_err(|e| OperatingError::Record(format!("{}: {e}", sensor.axis_label(axis))))?;
        let motion_n = band::band_density(&fitted.motion[a], rate, b.band).unwrap_or(f64::NAN);
        let d = &fitted.derivative[a];
        let offset_series: Vec<f64> = d.iter().map(|x| x * cal.dt).collect();
        let offset_n = band::band_density(&offset_series, rate, b.band).unwrap_or(f64::NAN);
        let jitter_series: Vec<f64> = d.iter().map(|x| x * jitter).collect();
        let jitter_n = band::band_density(&jitter_series, rate, b.band).unwrap_or(f64::NAN);
        axes.push(AxisOperating {
            sensor,
            axis,
            band: b,
            motion_n,
            offset_n,
            jitter_n,
            static_n: None,
        });
    }
    // the record's phases, on the raw signal of the samples used
    let cols: [&[f64]; 6] = std::array::from_fn(|i| &series[i][k0..k1]);
    let residual: [&[f64]; 6] = std::array::from_fn(|i| fitted.residual[i].as_slice());
    let split = axes
        .iter()
        .map(|a| a.band.band.0)
        .fold(signal::BAND_LO_MIN, f64::max);
    let (spectrogram, phases) = phases::phases(&cols, &residual, data.absent, rate, split, s.band);
    let noise_series: [Vec<f64>; 6] = std::array::from_fn(|i| {
        fitted.residual[i]
            .iter()
            .zip(&fitted.bias[i])
            .map(|(r, b)| r + b)
            .collect()
    });
    let op = Operating {
        reference: Some(WithReference {
            what: r.what.clone(),
            poses: r.len(),
            pose_dt: choice.pose_dt_ns as f64 * 1e-9,
            noise: choice.noise,
            knot_dt: choice.fits.dt_ns as f64 * 1e-9,
            candidates: choice.candidates.iter().map(|(h, e)| (*h as f64 * 1e-9, *e)).collect(),
            knot_given: choice.given,
            calibration: cal,
            jitter,
        }),
        rate,
        estimator_rate: s.estimator_rate.unwrap_or(rate),
        samples: k1 - k0,
        t0: t_ns[k0] as f64 * 1e-9,
        range: (k0, k1),
        axes,
        motion_edge: [None, None],
        phases,
        spectrogram,
        static_source: String::new(),
        static_an: None,
        operating_an: None,
        noise_series,
        notes: Vec::new(),
        cannot_separate: vec![
            "the reference's own error below the band's lower edge (there the floor is assumed)".into(),
            "a vibration line inside the motion's band (it is calibrated or fitted away with the motion)".into(),
        ],
    };
    Ok(op)
}

/// The RMS deviation of stamps from a uniform grid (a least-squares line through them), s.
pub(crate) fn stamp_jitter(t: &[i64]) -> f64 {
    let n = t.len();
    if n < 3 {
        return 0.0;
    }
    let t0 = t[0];
    let x: Vec<f64> = (0..n).map(|i| i as f64).collect();
    let y: Vec<f64> = t.iter().map(|v| (v - t0) as f64 * 1e-9).collect();
    let (mx, my) = (
        x.iter().sum::<f64>() / n as f64,
        y.iter().sum::<f64>() / n as f64,
    );
    let sxy: f64 = x.iter().zip(&y).map(|(a, b)| (a - mx) * (b - my)).sum();
    let sxx: f64 = x.iter().map(|a| (a - mx).powi(2)).sum();
    let slope = sxy / sxx;
    let r2: f64 = x
        .iter()
        .zip(&y)
        .map(|(a, b)| (b - my - slope * (a - mx)).powi(2))
        .sum();
    (r2 / n as f64).sqrt()
}
