//! One whole run: read the bag, collect with the stop rule, analyse, write every output — or,
//! with `--curves`, the same outputs from Allan curves another tool wrote.

use std::path::PathBuf;
use std::time::{Duration, Instant};

use bag2mat::shared::note::Note;
use bag2mat::shared::output::Outputs;
use rayon::prelude::*;

use allan_kalibr::consumers::{Provenance, RecordRate, input_text};
use allan_kalibr::{
    CurveData, CurvePoint, ImuAnalysis, Overlap, Section, analyse_imu_curves, ieee952_summary_text,
    read_curves, write_ieee952_files,
};
use bag2mat::Sensor;

use crate::analysis::{self, Analysis, AxisAllan};
use crate::cli::Config;
use crate::collect::{self, Stop};
use crate::error::Error;
use crate::fit::{AxisFit, IMU_UTILS_DEG_PER_RAD, SECONDS_PER_HOUR};
use crate::opencv_yaml::{self, YamlMode};
use crate::{plot, report};

/// What a run produced for one topic: what the binary says, and the numbers behind it.
#[derive(Debug)]
pub struct Outcome {
    /// The topic, upstream's terminal output, the IEEE 952 section, the record check's
    /// findings, the notes (end of bag, topic fallback, …), the files written and the
    /// phase timings.
    pub section: Section,
    /// The analysis itself.
    pub analysis: Analysis,
    /// The IEEE 952 analysis.
    pub ieee952: Option<ImuAnalysis>,
}

/// The IEEE 952 curve of one axis from imu_utils' own Allan variances: the same overlapping
/// estimator on its cluster grid, converted to SI (the gyro from pseudo-deg/h), with the
/// noise identification the Allan step made on θ, at the sample period `tau0` (the stamps'
/// nominal one: imu_utils' variances at cluster m do not depend on the period it assumed,
/// only their τ = m·period does). No second pass over the samples.
pub fn ieee952_curve(a: &AxisAllan, gyro: bool, tau0: f64) -> CurveData {
    let scale = if gyro {
        1.0 / (IMU_UTILS_DEG_PER_RAD * SECONDS_PER_HOUR).powi(2)
    } else {
        1.0
    };
    let points = a
        .factors
        .iter()
        .zip(&a.taus)
        .zip(&a.variance)
        .enumerate()
        // N − 2m ≤ 0 (the knife-edge last factor) has no estimate
        .filter(|(_, ((m, _), v))| 2 * **m < a.n && v.is_finite() && **v > 0.0)
        .map(|(i, ((&m, _), &v))| {
            let id = a.noise_ids.get(i).copied();
            CurvePoint {
                m,
                tau: m as f64 * tau0,
                avar: v * scale,
                id: id.and_then(|x| x.alpha),
                id_method: id.map_or(allan_kalibr::IdMethod::None, |x| x.method),
            }
        })
        .collect();
    CurveData::from_points(tau0, Some(a.n), Overlap::Overlapping, points)
}

/// The record check of the first `n` messages of `series` on the chosen clock, the other
/// cross-checked.
fn check_record(series: &bag2mat::ImuSeries, n: usize, config: &Config) -> bag2mat::RecordCheck {
    let (used, other) = match config.common.time {
        bag2mat::TimeColumn::Header => (&series.stamp, &series.record_time),
        bag2mat::TimeColumn::Record => (&series.record_time, &series.stamp),
    };
    let t = bag2mat::ns_of_times(&used[..n]);
    let o = bag2mat::ns_of_times(&other[..n]);
    let mut rec = bag2mat::CheckInput::of_series(series, config.common.time, &t, &o);
    rec.storage_order = rec.storage_order.map(|s| &s[..n]);
    for v in rec.values.iter_mut() {
        *v = &v[..n];
    }
    bag2mat::check_record(
        &rec,
        &bag2mat::CheckOptions {
            drop_outliers: config.common.drop_outliers,
        },
    )
}

/// Drops the messages whose header stamp is within `seconds` of the first (a warm-up), as
/// `rosbag play --start` would before imu_utils saw them; returns how many.
fn skip_start(
    series: &mut bag2mat::ImuSeries,
    seconds: f64,
) -> Result<(usize, Option<String>), Error> {
    let t: Vec<f64> = series.stamp.iter().map(|s| s.to_sec()).collect();
    let (k, warning) = bag2mat::checked_skip(&t, seconds)?;
    series.stamp.drain(..k);
    series.record_time.drain(..k);
    series.seq.drain(..k);
    for c in series.acc.iter_mut().chain(series.gyro.iter_mut()) {
        c.drain(..k);
    }
    Ok((k, warning))
}

/// What `--curves` produced: what the binary says, and the numbers behind it.
#[derive(Debug)]
pub struct CurvesOutcome {
    /// imu_utils' fit blocks (imu_utils data directories only), the IEEE 952 section, the
    /// notes and the files written.
    pub section: Section,
    /// imu_utils' analysis of an imu_utils data directory.
    pub analysis: Option<Analysis>,
    /// The IEEE 952 analysis.
    pub ieee952: ImuAnalysis,
}

/// The whole job as the binary says it: [`run`] or [`run_curves`], one [`Section`] per
/// topic (or for the curves read); every file among `outputs`.
pub fn sections(config: &Config, outputs: &Outputs) -> Result<Vec<Section>, Error> {
    if matches!(config.common.input, allan_kalibr::Input::Curves(_)) {
        return Ok(vec![run_curves(config, outputs)?.section]);
    }
    allan_kalibr::topic_sections(run_topics(config, outputs)?, |o| o.section)
}

/// One topic's outcome in a run of several ([`run_topics`]).
pub type TopicRun = allan_kalibr::TopicOutcome<Outcome, Error>;

impl allan_kalibr::Job for Config {
    type Error = Error;
    fn common(&self) -> &allan_kalibr::Common {
        &self.common
    }
    fn sections(&self, outputs: &Outputs) -> Result<Vec<Section>, Error> {
        sections(self, outputs)
    }
    fn output_names(&self) -> Vec<String> {
        output_names(&self.name)
    }
}

/// Every file a run of allan_imu_utils with IMU name `name` may write into an output folder
/// (another name's files are another IMU's, kept: imu_utils' `data_save_path` holds several).
pub fn output_names(name: &str) -> Vec<String> {
    let mut v = Vec::new();
    for sensor in ["gyr", "acc"] {
        for part in ["t", "x", "y", "z"] {
            v.push(format!("data_{name}_sim_{sensor}_{part}.txt"));
            v.push(format!("data_{name}_{sensor}_{part}.txt"));
        }
        for ext in ["png", "svg"] {
            v.push(format!("allan_{sensor}.{ext}"));
        }
    }
    v.push(YamlMode::Compat.file_name(name));
    v.push(YamlMode::Continuous.file_name(name));
    v.extend(allan_kalibr::ieee952_file_names(&format!("{name}_")));
    v
}

/// Runs the whole pipeline for `config` (a bag; see [`run_curves`] for `--curves`): every
/// selected topic is read in one pass and analysed on its own. With one topic the outputs go
/// into `out_dir`; with several, into `out_dir/<topic folder>`; every file among `outputs`.
pub fn run(config: &Config, outputs: &Outputs) -> Result<Vec<Outcome>, Error> {
    run_topics(config, outputs)?
        .into_iter()
        .map(|t| t.result)
        .collect()
}

/// [`run`] with each topic's outcome on its own: a topic that fails does not stop the
/// others (what the binary does with a run of several topics).
pub fn run_topics(config: &Config, outputs: &Outputs) -> Result<Vec<TopicRun>, Error> {
    let t0 = Instant::now();
    let read = bag2mat::read_imu_topics_with(
        config.common.samples_path(),
        &config.common.topics,
        &bag2mat::ReadOptions {
            quiet: config.common.quiet,
        },
        &config.common.input_options,
    )?;
    let read_time = t0.elapsed();
    let several = read.series.len() > 1 || config.common.topics.all_imu;
    let names: Vec<String> = read.series.iter().map(|s| s.topic.clone()).collect();
    let names: Vec<&str> = names.iter().map(|s| s.as_str()).collect();
    let folders = bag2mat::topic_folder_names(&names);
    let mut outs = Vec::new();
    for (series, folder) in read.series.into_iter().zip(folders) {
        let mut c = config.clone();
        if several {
            c.common.out_dir = config.common.out_dir.join(folder);
        }
        let topic = series.topic.clone();
        let notes = series.notes.clone();
        outs.push(TopicRun {
            topic,
            notes,
            result: run_series(&c, series, read_time, outputs),
        });
    }
    Ok(outs)
}

/// The pipeline on one topic's series.
fn run_series(
    config: &Config,
    mut series: bag2mat::ImuSeries,
    read_time: Duration,
    outputs: &Outputs,
) -> Result<Outcome, Error> {
    let mut timings: Vec<(&str, Duration)> = vec![("read_bag", read_time)];
    let topic = series.topic.clone();
    let mut notes = series.notes.clone();
    // integrated deltas far apart are no samples to analyse
    series.check_integration()?;
    let absent = stand_in_and_skip(config, &mut series, &mut notes)?;
    let collected = collect::collect(&series, config.max_time_min, config.common.time);
    notes.extend(stop_note(&collected, &series, config));
    let (n, stop) = (collected.len(), collected.stop);
    drop(collected);
    // The record check (bag2mat::check_record) on the whole record: duplicates, a clock
    // that steps back and a record that is not one continuous stretch are cut, spikes
    // dropped when asked; what the record breaks of the analysis' assumptions is found.
    let t1 = Instant::now();
    let whole_n = series.len();
    let mut check = check_record(&series, whole_n, config);
    bag2mat::drop_absent(&mut check.findings, absent);
    timings.push(("record_check", t1.elapsed()));
    let series = kept_series(series, &check, whole_n, absent);
    // The upstream-compatible part: the kept messages among the first `n`, where imu_utils'
    // stop rule (max_time_min) ends its collection.
    let n_compat = match &check.keep {
        bag2mat::KeepRows::All => n,
        bag2mat::KeepRows::Rows(rows) => rows.partition_point(|&i| i < n),
    };
    let collected = collect::Collected::first(&series, n_compat, config.common.time, stop);
    analysis::check_enough(&collected, config.max_cluster)?;
    check_values(&collected, absent, &mut notes)?;
    let t1 = Instant::now();
    let (axes, gyro_mean) =
        analysis::allan_step(&collected, config.max_cluster, config.common.ieee952)?;
    timings.push(("allan", t1.elapsed()));
    let t1 = Instant::now();
    let section_rate = check
        .rate
        .map(allan_kalibr::snap_rate)
        .unwrap_or(axes[0].freq);
    // This tool's own section uses the whole record: past the stop rule, the Allan step runs
    // again on every kept message.
    let ieee = if n_compat < series.len() && config.common.ieee952 && check.refusal().is_none() {
        let all = collect::Collected::first(&series, series.len(), config.common.time, stop);
        check_values(&all, absent, &mut Vec::new())?;
        let (all_axes, _) = analysis::allan_step(&all, config.max_cluster, true)?;
        ieee952_section(
            config,
            &check,
            &all_axes,
            &all,
            absent,
            section_rate,
            &mut notes,
        )
    } else {
        ieee952_section(
            config,
            &check,
            &axes,
            &collected,
            absent,
            section_rate,
            &mut notes,
        )
    };
    timings.push(("ieee952", t1.elapsed()));
    let prov = Provenance::new(
        crate::cli::TOOL,
        input_text(config.common.samples_path(), Some(&topic)),
        RecordRate::Measured(section_rate),
    );
    let motion = check.refusal().map(allan_kalibr::refusal_text);
    if let Some(m) = &motion {
        notes.push(Note::warning(format!(
            "{} not written: the record breaks the analysis' assumptions ({m}); imu_utils' own {} is written as upstream writes it, but its numbers describe this record, not the IMU's noise",
            YamlMode::Continuous.file_name(&config.name),
            YamlMode::Compat.file_name(&config.name)
        )));
    }
    let caveats: Vec<String> = check
        .findings
        .iter()
        .filter(|f| f.level >= bag2mat::FindingLevel::Warning)
        .map(|f| format!("RECORD CHECK: {}; the values below carry it.", f.short()))
        .collect();
    drop(collected);
    drop(series);
    let t1 = Instant::now();
    let fits = analysis::fit_all(&axes);
    let analysis = Analysis {
        max_cluster: config.max_cluster,
        axes,
        gyro_mean,
        fits,
        absent,
    };
    timings.push(("fit", t1.elapsed()));
    let t2 = Instant::now();
    let files = write_outputs(
        outputs,
        &analysis,
        ieee.as_ref(),
        config,
        &topic,
        &Continuous {
            prov: &prov,
            caveats: (motion.is_none()).then_some(caveats),
        },
    )?;
    timings.push(("write_outputs", t2.elapsed()));
    let ieee952_text = ieee
        .as_ref()
        .map(|a| allan_kalibr::ieee952_section_text(a, config.common.samples_path(), &topic));
    let section = Section {
        topic: Some(topic),
        notes,
        findings: check.findings,
        text: report::stdout_text(&analysis),
        ieee952_text,
        written: files,
        timings: timings
            .iter()
            .map(|(phase, d)| format!("timing {phase} {:.3} s", d.as_secs_f64()))
            .collect(),
        error: None,
    };
    Ok(Outcome {
        section,
        analysis,
        ieee952: ieee,
    })
}

/// A one-sensor topic (PX4 sensor_gyro, …): zeros stand in for the absent sensor in the
/// record check (the present one's samples in the Allan step, [`kept_series`]); nothing of
/// it is printed nor written. Then `--skip-start`. Returns the absent sensor; both are said
/// in `notes`.
fn stand_in_and_skip(
    config: &Config,
    series: &mut bag2mat::ImuSeries,
    notes: &mut Vec<Note>,
) -> Result<Option<bag2mat::Sensor>, Error> {
    let absent = series.stand_in_absent(bag2mat::StandIn::Zeros);
    notes.extend(absent.map(bag2mat::absent_warning));
    if let Some(s) = config.common.skip_start {
        let (k, warning) = skip_start(series, s)?;
        notes.extend(warning.map(Note::warning));
        notes.push(Note::info(format!(
            "--skip-start {s}: dropped the first {k} messages ({} left)",
            series.len()
        )));
    }
    Ok(absent)
}

/// What the stop rule did. The bag ended before `max_time_min` (every record shorter than
/// it): imu_utils' own words (the reference runs' stderr.txt), said as information — every
/// ordinary run prints it, so it is no warning. The rule fired: a warning, since the
/// upstream-compatible part then leaves the rest of the record out (the IEEE 952 section
/// uses all of it).
fn stop_note(
    collected: &collect::Collected,
    series: &bag2mat::ImuSeries,
    config: &Config,
) -> Option<Note> {
    match collected.stop {
        Stop::EndOfBag => Some(Note::upstream_info(
            "WARNING: ",
            format!(
                "bag ended after {} messages before max_time_min ({}) was exceeded; the ROS node would wait forever. Processing what was read.",
                collected.len(),
                config.max_time_min
            ),
        )),
        Stop::Fired { .. } => {
            let t = series.time(config.common.time);
            let minutes = |k: usize| (t[k].to_sec() - t[0].to_sec()) / 60.0;
            let (used, total) = (minutes(collected.len() - 1), minutes(series.len() - 1));
            let section = if config.common.ieee952 {
                "; the IEEE 952 section and its record-length advice use the whole record"
            } else {
                ""
            };
            Some(Note::warning(format!(
                "max_time_min {}: imu_utils stops at the first stamp past it, so the upstream-compatible part (its report, {name}_imu_param.yaml, {name}_imu_param_continuous.yaml, the data_{name}_*.txt curves and plots) uses the first {used:.1} min ({} of {} messages) of this {total:.1} min record (--max-time-min {} uses all of it){section}",
                config.max_time_min,
                collected.len(),
                series.len(),
                total.floor() as u64 + 1,
                name = config.name,
            )))
        }
    }
}

/// The messages of the first `n` that the record check keeps; for a one-sensor topic the
/// present sensor's samples then stand in for the absent one's.
fn kept_series(
    series: bag2mat::ImuSeries,
    check: &bag2mat::RecordCheck,
    n: usize,
    absent: Option<bag2mat::Sensor>,
) -> bag2mat::ImuSeries {
    let mut series = if check.keep.is_all() && n == series.len() {
        series
    } else {
        check.keep.select_series(&series, n)
    };
    match absent {
        Some(bag2mat::Sensor::Acc) => series.acc = series.gyro.clone(),
        Some(bag2mat::Sensor::Gyro) => series.gyro = series.acc.clone(),
        None => {}
    }
    series
}

/// The IEEE 952 section on imu_utils' own overlapping curve (rad/s, m/s²) at the stamps'
/// nominal rate (lost samples do not change it; imu_utils' mean period does), with the
/// record check's findings; not on a record that breaks its assumptions (said in `notes`).
fn ieee952_section(
    config: &Config,
    check: &bag2mat::RecordCheck,
    axes: &[AxisAllan],
    collected: &collect::Collected,
    absent: Option<Sensor>,
    section_rate: f64,
    notes: &mut Vec<Note>,
) -> Option<ImuAnalysis> {
    if let (true, Some(r)) = (config.common.ieee952, check.refusal()) {
        notes.push(Note::warning(format!(
            "IEEE 952 section not computed: the record breaks its assumptions ({})",
            r.short()
        )));
    }
    if config.common.ieee952 && check.refusal().is_none() {
        Some(section(
            axes,
            collected,
            absent,
            section_rate,
            &check.findings,
        ))
    } else {
        None
    }
}

/// The value check of every analysed column (`allan_kalibr::value_problem`): a
/// column no analysis can use is an error, an odd one a warning.
fn check_values(
    collected: &collect::Collected,
    absent: Option<Sensor>,
    notes: &mut Vec<Note>,
) -> Result<(), Error> {
    let problems: Vec<_> = (0..collect::FIELDS.len())
        .into_par_iter()
        .filter(|&k| absent != Some(if k < 3 { Sensor::Gyro } else { Sensor::Acc }))
        .map(|k| {
            let col = if k < 3 {
                collected.gyro_rad_s(k)
            } else {
                collected.acc_m_s2(k - 3)
            };
            allan_kalibr::value_problem(collect::FIELDS[k], col)
        })
        .collect();
    for problem in problems {
        match problem {
            Some((true, what)) => return Err(Error::Config(what)),
            Some((false, what)) => notes.push(Note::warning(what)),
            None => {}
        }
    }
    Ok(())
}

/// The IEEE 952 section on imu_utils' overlapping curves (rad/s, m/s²), with the PSD and
/// lines of the samples (SI units) and the record check's `findings`.
fn section(
    axes: &[AxisAllan],
    collected: &collect::Collected,
    absent: Option<Sensor>,
    section_rate: f64,
    findings: &[bag2mat::Finding],
) -> ImuAnalysis {
    let curves: Vec<CurveData> = axes
        .par_iter()
        .enumerate()
        .filter(|(i, _)| absent != Some(if *i < 3 { Sensor::Gyro } else { Sensor::Acc }))
        .map(|(i, a)| {
            let y = if i < 3 {
                collected.gyro_rad_s(i)
            } else {
                collected.acc_m_s2(i - 3)
            };
            ieee952_curve(a, i < 3, 1.0 / section_rate).with_spectrum(y)
        })
        .collect();
    let mut it = curves.into_iter();
    let sensors: Vec<(Sensor, [CurveData; 3])> = [Sensor::Gyro, Sensor::Acc]
        .into_iter()
        .filter(|s| Some(*s) != absent)
        .map(|s| {
            (
                s,
                std::array::from_fn(|_| it.next().expect("three per sensor")),
            )
        })
        .collect();
    let mut an = analyse_imu_curves(
        &sensors,
        section_rate,
        &allan_kalibr::Ieee952Config::default(),
    );
    an.checks = findings.to_vec();
    an
}

/// What `<name>_imu_param_continuous.yaml` (this project's file) is written with: the files'
/// provenance, and the record check's caveats — `None` when the record is not fit for a
/// noise analysis at all (a moving record), and the file is not written.
struct Continuous<'a> {
    prov: &'a Provenance,
    caveats: Option<Vec<String>>,
}

impl Continuous<'_> {
    /// The record's rate the files state.
    fn rate(&self) -> Option<f64> {
        self.prov.rate.hz()
    }
}

/// Writes imu_utils' two yaml files: upstream's as upstream writes it, the continuous one
/// as `c` says; returns the paths.
fn write_yaml_files(
    outputs: &Outputs,
    analysis: &Analysis,
    config: &Config,
    c: &Continuous<'_>,
) -> Result<Vec<PathBuf>, Error> {
    let mut files = Vec::new();
    for mode in [YamlMode::Compat, YamlMode::Continuous] {
        let caveats = match (mode, &c.caveats) {
            (YamlMode::Compat, _) => Vec::new(),
            (YamlMode::Continuous, Some(v)) => v.clone(),
            (YamlMode::Continuous, None) => continue,
        };
        let mut comments = vec![c.prov.line(), c.prov.rate_line()];
        comments.extend(caveats);
        let extra = opencv_yaml::Extra {
            comments,
            rate: c.rate(),
        };
        let p = config.common.out_dir.join(mode.file_name(&config.name));
        report::write_text(
            outputs,
            &p,
            &opencv_yaml::yaml_text(analysis, &config.name, mode, &extra),
        )?;
        files.push(p);
    }
    Ok(files)
}

/// imu_utils' files (curves, both yaml modes, plots) and the section's.
fn write_outputs(
    outputs: &Outputs,
    analysis: &Analysis,
    ieee: Option<&ImuAnalysis>,
    config: &Config,
    topic: &str,
    c: &Continuous<'_>,
) -> Result<Vec<PathBuf>, Error> {
    outputs.ensure_dir(&config.common.out_dir)?;
    let mut files =
        report::write_curve_files(outputs, analysis, &config.name, &config.common.out_dir)?;
    files.extend(write_yaml_files(outputs, analysis, config, c)?);
    if config.plots {
        files.extend(plot::write_plots(
            outputs,
            analysis,
            &config.name,
            &config.common.out_dir,
        )?);
    }
    if let Some(an) = ieee {
        files.extend(write_ieee952(outputs, an, config, topic, c.prov)?);
    }
    Ok(files)
}

/// The section's files (prefixed `<name>_`) and chart.
fn write_ieee952(
    outputs: &Outputs,
    an: &ImuAnalysis,
    config: &Config,
    rostopic: &str,
    prov: &Provenance,
) -> Result<Vec<PathBuf>, Error> {
    let prefix = format!("{}_", config.name);
    let mut out =
        write_ieee952_files(outputs, an, &config.common.out_dir, &prefix, rostopic, prov)?;
    if config.plots {
        let truth = allan_kalibr::find_truth(config.common.samples_path(), an);
        out.extend(allan_kalibr::write_ieee952_chart(
            outputs,
            an,
            &config.name,
            truth.as_ref(),
            &config.common.out_dir,
            &prefix,
        )?);
    }
    Ok(out)
}

/// `--curves`: imu_utils' own fit and yaml files when the curves are an imu_utils data
/// directory (its `*_n` needs the rate, taken as 1/first τ as the files imply), and the
/// IEEE 952 section on any format.
pub fn run_curves(config: &Config, outputs: &Outputs) -> Result<CurvesOutcome, Error> {
    let allan_kalibr::Input::Curves(input) = &config.common.input else {
        return Err(Error::Config("no --curves given".into()));
    };
    let c = read_curves(&input.paths, &input.options)?;
    let prov = Provenance::new(
        crate::cli::TOOL,
        allan_kalibr::curves_text(&input.paths),
        allan_kalibr::curves_rate(config.common.rate, &c),
    );
    let mut notes = Vec::new();
    let mut stdout = String::new();
    let mut files = Vec::new();
    outputs.ensure_dir(&config.common.out_dir)?;
    let mut analysis = None;
    if let Some(raw) = &c.imu_utils {
        let freq = 1.0 / raw.gyr_t[0];
        let fit = |sensor: bag2mat::Sensor, t: &[f64], dev: &[f64]| {
            let var: Vec<f64> = dev.iter().map(|d| d * d).collect();
            AxisFit::fit(sensor, t, &var, freq)
        };
        let fits: Vec<AxisFit> = (0..3)
            .map(|k| fit(bag2mat::Sensor::Gyro, &raw.gyr_t, &raw.gyr[k]))
            .chain((0..3).map(|k| fit(bag2mat::Sensor::Acc, &raw.acc_t, &raw.acc[k])))
            .collect();
        let an = Analysis::from_curves(raw, fits, freq);
        stdout.push_str(&report::fit_text(&an));
        files.extend(write_yaml_files(
            outputs,
            &an,
            config,
            &Continuous {
                prov: &prov,
                caveats: Some(Vec::new()),
            },
        )?);
        analysis = Some(an);
    } else {
        notes.push(Note::info(format!(
            "{}: imu_utils' own fit runs on imu_utils data directories only; IEEE 952 section only",
            c.format
        )));
    }
    let sensors: Vec<_> = c
        .sensors
        .iter()
        .map(|s| (s.sensor, s.axes.clone()))
        .collect();
    let mut an = analyse_imu_curves(&sensors, c.rate, &allan_kalibr::Ieee952Config::default());
    an.notes = vec![format!("curves: {}", c.format)];
    an.notes.extend(c.notes.iter().cloned());
    let rostopic = config.common.named_topic();
    files.extend(write_ieee952(outputs, &an, config, rostopic, &prov)?);
    let section = Section {
        notes,
        text: stdout,
        ieee952_text: Some(ieee952_summary_text(&an)),
        written: files,
        ..Default::default()
    };
    Ok(CurvesOutcome {
        section,
        analysis,
        ieee952: an,
    })
}
