//! The whole job: load → choose rate → grid → sig2 → gen_chart ×2 → text, yaml, CSV, plots.
//!
//! Everything is computed before the first file is written, so a bad input leaves no output
//! behind; each file is written atomically.

use std::path::{Path, PathBuf};
use std::time::Instant;

use crate::consumers::{Provenance, RecordRate, input_text};
use crate::error::Error;
use crate::front::Section;
use crate::input::{self, ImuData, RateChoice};
use crate::kalibr::chart::{self, Chart};
use crate::kalibr::chart_fit::{ChartFit, gen_chart};
use crate::kalibr::curves;
use crate::kalibr::estimator::{Estimator, sig2_curves};
use crate::kalibr::grid::TauGrid;
use crate::kalibr::imu_yaml::{ImuYaml, SectionFile};
use crate::kalibr::report;
use bag2mat::shared::note::Note;
use bag2mat::shared::output::Outputs;

/// The tool's name: its default output folder is `<input stem>_allan_kalibr/`, its files'
/// provenance and its messages name it. Here, with the job, so that the commands above the
/// job (`cli`, `check`, `plan`) and the job itself read one name; the analyses below it
/// (`operating`) are given it.
pub const TOOL: &str = "allan_kalibr";

/// What the program runs with (resolved from the command line in `cli`).
#[derive(Debug, Clone, PartialEq)]
pub struct Config {
    /// What both analysers share: input, topics, time column, `--rate` (here also the τ
    /// grid's update_rate; `None`: estimated from the time stamps), output folder, …
    pub common: crate::front::Common,
    /// Chart title prefix (upstream's hard-coded `titlestr`).
    pub title: String,
    /// Fast prefix sums or the bit-exact recursion.
    pub estimator: Estimator,
    /// The operating-noise analysis instead of the static one (`--reference`,
    /// `--operating`).
    pub operating: Option<crate::operating::Settings>,
}

impl Config {
    /// Settings for `input` with every other choice at its default.
    pub fn new(input: crate::front::Input, out_dir: impl Into<PathBuf>) -> Config {
        Config {
            common: crate::front::Common::new(input, out_dir),
            title: String::new(),
            estimator: Estimator::PrefixSum,
            operating: None,
        }
    }
}

/// The numbers of one run.
#[derive(Debug, Clone)]
pub struct Analysis {
    /// The τ grid.
    pub grid: TauGrid,
    /// sig2 curves ax ay az wx wy wz over the grid.
    pub sig2: [Vec<f64>; 6],
    /// gen_chart on the accelerometer curves.
    pub accel: ChartFit,
    /// gen_chart on the gyroscope curves.
    pub gyro: ChartFit,
    /// A sensor the topic does not carry: its curves and fit above were computed on a
    /// stand-in (the present sensor's samples) and are never printed nor written.
    pub absent: Option<bag2mat::Sensor>,
}

/// Computes grid, curves and both fits for `axes` (each N samples) at `rate` Hz. The
/// columns are consumed: the fast path turns them into prefix sums in place.
pub fn analyse(
    axes: [Vec<f64>; 6],
    rate: f64,
    estimator: Estimator,
    quiet: bool,
) -> Result<Analysis, Error> {
    let grid = TauGrid::new(axes[0].len(), rate)?;
    let jobs = 6 * grid.distinct_m().len() as u64;
    let bar =
        bag2mat::shared::progress::bar(jobs, quiet || estimator == Estimator::PrefixSum, "taus");
    bar.set_message("allan");
    let sig2 = sig2_curves(axes, &grid, estimator, &|| bar.inc(1));
    bar.finish_and_clear();
    let accel = gen_chart(&grid.tau1, &sig2[0], &sig2[1], &sig2[2]);
    let gyro = gen_chart(&grid.tau1, &sig2[3], &sig2[4], &sig2[5]);
    Ok(Analysis {
        grid,
        sig2,
        accel,
        gyro,
        absent: None,
    })
}

/// Result of [`run`] for one topic: what the binary says, and the numbers behind it.
#[derive(Debug)]
pub struct RunOutput {
    /// The topic (None for a `.mat`), upstream's text, the IEEE 952 section, the record
    /// check's findings, the notes, the files written and the phase timings.
    pub section: Section,
    /// The numbers.
    pub analysis: Analysis,
    /// How the update rate was chosen.
    pub rate: RateChoice,
}

/// Wall-clock seconds per phase of [`run`] (said as one line with --timings).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
struct Timings {
    /// Reading the bag or .mat.
    load: f64,
    /// τ grid, sig2 curves and both fits.
    analyse: f64,
    /// The IEEE 952 analysis (0 when disabled): its curves (made beside the record check
    /// when it keeps the record whole, so the phases then overlap), and the part of its
    /// fits that outlasted the compat path they run beside.
    ieee952: f64,
    /// Rendering and writing yaml, CSV and plots.
    output: f64,
    /// The record check (`bag2mat::check_record`).
    checks: f64,
}

impl std::fmt::Display for Timings {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "timings: load {:.3} s, allan+fit {:.3} s, ieee952 {:.3} s, outputs {:.3} s, checks {:.3} s",
            self.load, self.analyse, self.ieee952, self.output, self.checks
        )
    }
}

/// The whole job as the binary says it: [`run`] or `run_curves`, one [`Section`] per
/// topic (or for the curves read). Every file goes among `outputs`.
pub fn sections(config: &Config, outputs: &Outputs) -> Result<Vec<Section>, Error> {
    if let crate::front::Input::Curves(curves) = &config.common.input {
        return Ok(vec![run_curves(config, curves, outputs)?]);
    }
    if let Some(s) = &config.operating {
        return crate::operating::sections(TOOL, &config.common, &config.title, s, outputs);
    }
    crate::front::topic_sections(run_topics(config, outputs)?, |out| out.section)
}

/// One topic's outcome in a run of several ([`run_topics`]).
pub type TopicRun = crate::front::TopicOutcome<RunOutput, Error>;

impl crate::front::Job for Config {
    type Error = Error;
    fn common(&self) -> &crate::front::Common {
        &self.common
    }
    fn sections(&self, outputs: &Outputs) -> Result<Vec<Section>, Error> {
        sections(self, outputs)
    }
    fn output_names(&self) -> Vec<String> {
        output_names()
    }
}

/// Every file a run of allan_kalibr may write into an output folder.
pub(crate) fn output_names() -> Vec<String> {
    let mut v: Vec<String> = ["imu.yaml", "allan_curves.csv"]
        .iter()
        .map(|s| s.to_string())
        .collect();
    for stem in ["allan_accel", "allan_gyro"] {
        for ext in ["png", "svg"] {
            v.push(format!("{stem}.{ext}"));
        }
    }
    v.extend(crate::ieee952::files::file_names(""));
    v
}

/// Runs the whole job for `config`, one analysis per topic, all topics read in one pass.
/// With one topic the outputs go into `outdir`; with several, into `outdir/<topic folder>`;
/// every file among `outputs`.
pub fn run(config: &Config, outputs: &Outputs) -> Result<Vec<RunOutput>, Error> {
    run_topics(config, outputs)?
        .into_iter()
        .map(|t| t.result)
        .collect()
}

/// [`run`] with each topic's outcome on its own: a topic that fails does not stop the
/// others (what the binary does with a run of several topics).
pub fn run_topics(config: &Config, outputs: &Outputs) -> Result<Vec<TopicRun>, Error> {
    let start = Instant::now();
    let datas = input::load_all(
        config.common.samples_path(),
        &config.common.topics,
        config.common.time,
        config.common.quiet,
        &config.common.input_options,
    )?;
    let load = start.elapsed().as_secs_f64();
    let several = datas.len() > 1 || config.common.topics.all_imu;
    let names: Vec<String> = datas
        .iter()
        .map(|d| d.topic.clone().unwrap_or_default())
        .collect();
    let names: Vec<&str> = names.iter().map(|s| s.as_str()).collect();
    let folders = bag2mat::topic_folder_names(&names);
    let mut outs = Vec::new();
    for (data, folder) in datas.into_iter().zip(folders) {
        let mut c = config.clone();
        if several {
            c.common.out_dir = config.common.out_dir.join(folder);
        }
        let topic = data
            .topic
            .clone()
            .unwrap_or_else(|| config.common.named_topic().to_string());
        let notes = data.notes.clone();
        outs.push(TopicRun {
            topic,
            notes,
            result: run_on(&c, data, load, outputs),
        });
    }
    Ok(outs)
}

/// The IEEE 952 analysis of `config`'s first topic, nothing written (what `allan_kalibr
/// check --against LOG` compares with): the analysis, or why the record cannot have one.
pub(crate) fn section_only(
    config: &Config,
) -> Result<Result<crate::ieee952::imu::ImuAnalysis, String>, Error> {
    let mut datas = input::load_all(
        config.common.samples_path(),
        &config.common.topics,
        config.common.time,
        true,
        &config.common.input_options,
    )?;
    if datas.is_empty() {
        return Ok(Err("no IMU topic".into()));
    }
    let mut data = datas.swap_remove(0);
    let mut notes = Vec::new();
    if let Some(skip) = config.common.skip_start {
        input::skip_start(&mut data, skip, &mut notes)?;
    }
    if data.len() < 3 {
        return Err(Error::TooShort { n: data.len() });
    }
    let mut c = check_record(config, data, &mut notes)?;
    if let Some(r) = &c.refusal {
        return Ok(Err(format!(
            "the record breaks the IEEE 952 analysis' assumptions ({}): nothing measured to compare with",
            crate::front::refusal_text(r)
        )));
    }
    let (curves, _) = section_curves(config, &mut c, &mut notes);
    Ok(curves
        .map(|cv| cv.finish(c.findings.clone(), &crate::ieee952::Config::default()))
        .ok_or_else(|| {
            let why: Vec<String> = notes.iter().map(|n| n.line()).collect();
            format!("no IEEE 952 analysis of this record ({})", why.join("; "))
        }))
}

/// The section's six series (gyro x y z, then acc x y z) of the `data_imu`-ordered columns.
fn section_series(a: &[Vec<f64>; 6]) -> [&[f64]; 6] {
    [&a[3], &a[4], &a[5], &a[0], &a[1], &a[2]]
}

/// [`run`] on samples already in memory (read in `load` seconds): the record checked, the
/// rate chosen, both analyses side by side, then every output rendered and written.
fn run_on(
    config: &Config,
    mut data: ImuData,
    load: f64,
    outputs: &Outputs,
) -> Result<RunOutput, Error> {
    // What the reader found (losses, fallbacks) is always said, also with --quiet.
    let mut notes = data.notes.clone();
    let data_topic = data.topic.clone();
    // integrated deltas far apart are no samples to analyse
    bag2mat::check_integration(
        data_topic.as_deref().unwrap_or(""),
        data.integration,
        &data.clock.t_ns,
    )
    .map_err(bag2mat::Error::from)?;
    if let Some(skip) = config.common.skip_start {
        input::skip_start(&mut data, skip, &mut notes)?;
    }
    if data.len() < 3 {
        return Err(Error::TooShort { n: data.len() });
    }
    let mut c = check_record(config, data, &mut notes)?;
    let topic = c
        .data
        .topic
        .clone()
        .unwrap_or_else(|| config.common.named_topic().to_string());
    let absent = c.data.absent;
    // The IEEE 952 analysis reads the raw columns, so its curves are made before the compat
    // path turns them into prefix sums; its fits then run beside the compat path. Data too
    // short for it only cost the section, with a note.
    let (curves, curves_s) = section_curves(config, &mut c, &mut notes);
    let section_file = match (&curves, &c.refusal) {
        _ if !config.common.ieee952 => SectionFile::CompatOnly,
        (Some(_), _) => SectionFile::Written,
        (None, Some(r)) => SectionFile::NotComputed(format!(
            "the IEEE 952 section was not computed, the record breaks its assumptions ({})",
            crate::front::refusal_text(r)
        )),
        (None, None) => SectionFile::NotComputed(
            "the IEEE 952 analysis could not run on this record (the warning says why)".into(),
        ),
    };
    let prov = Provenance::new(
        TOOL,
        input_text(config.common.samples_path(), data_topic.as_deref()),
        record_rate(config, &c.rate),
    );
    let axes = compat_axes(c.data);
    let ((ieee, fits_s), analysis) = rayon::join(
        || {
            let start = Instant::now();
            let an = curves
                .as_ref()
                .map(|cv| cv.finish(c.findings.clone(), &crate::ieee952::Config::default()));
            (an, start.elapsed().as_secs_f64())
        },
        || {
            let start = Instant::now();
            analyse(axes, c.rate.used, config.estimator, config.common.quiet)
                .map(|a| (a, start.elapsed()))
        },
    );
    let (mut analysis, analyse_t) = analysis?;
    analysis.absent = absent;
    let analyse_s = analyse_t.as_secs_f64();
    // the section's share of the wall time: its curves, and its fits less what they overlapped
    let ieee_s = curves_s + (fits_s - analyse_s).max(0.0);
    let start = Instant::now();
    let text = report::full_text_of(&analysis.accel, &analysis.gyro, absent);
    let written = write_outputs(
        outputs,
        config,
        &analysis,
        Written {
            ieee: ieee.as_ref(),
            update_rate: c.rate.used,
            topic: &topic,
            prov: &prov,
            section: &section_file,
        },
    )?;
    let timings = Timings {
        load,
        analyse: analyse_s,
        ieee952: ieee_s,
        output: start.elapsed().as_secs_f64(),
        checks: c.checks_s,
    };
    let section = Section {
        topic: data_topic,
        notes,
        findings: c.findings,
        text,
        ieee952_text: ieee
            .as_ref()
            .map(|a| crate::ieee952::stated::section_text(a, config.common.samples_path(), &topic)),
        written,
        timings: vec![timings.to_string()],
        error: None,
    };
    Ok(RunOutput {
        section,
        analysis,
        rate: c.rate,
    })
}

/// A record after its checks: the samples analysed, what the checks found, the rate, and
/// the section's curves made beside the checks (see [`check_record`]).
struct Checked {
    data: ImuData,
    findings: Vec<bag2mat::Finding>,
    rate: RateChoice,
    /// The check kept every sample.
    whole: bool,
    /// What makes the record unfit for the IEEE 952 section, if anything.
    refusal: Option<bag2mat::Finding>,
    /// The section's curves made beside the check (taken by [`section_curves`]).
    early: Option<EarlyCurves>,
    checks_s: f64,
}

/// The section's curves made beside the record check: the rate assumed, the curves, their
/// notes and seconds.
type EarlyCurves = (f64, Option<crate::ieee952::imu::ImuCurves>, Vec<Note>, f64);

/// The finiteness and value checks of each column, then the record check
/// (bag2mat::check_record): duplicates, a clock that steps back and a record that is not
/// one continuous stretch are cut, spikes dropped when asked, and what the record breaks of
/// the analysis' assumptions is found; then the rate.
fn check_record(config: &Config, data: ImuData, notes: &mut Vec<Note>) -> Result<Checked, Error> {
    let scans = data.scan_checked()?;
    // The section's curves need only the columns and the rate. On a record the check keeps
    // whole (the usual case) they are made beside it, at the rate the run will most likely
    // choose (the one given, else the stamps' mean), so the check's serial parts leave no
    // core idle; they are made again after it only if it cuts the record or the rate
    // differs.
    let absent = data.absent;
    let guess = config
        .common
        .ieee952
        .then(|| {
            config
                .common
                .rate
                .or_else(|| input::measured_rate(&data.t).map(input::snap_rate))
        })
        .flatten()
        .filter(|r| r.is_finite() && *r > 0.0);
    let ((check, checks_s), early) = rayon::join(
        || {
            let start = Instant::now();
            let check = bag2mat::check_record(
                &data.record(),
                &bag2mat::CheckOptions {
                    drop_outliers: config.common.drop_outliers,
                },
            );
            (check, start.elapsed().as_secs_f64())
        },
        || {
            guess.map(|rate| {
                let start = Instant::now();
                let mut notes = Vec::new();
                let curves = crate::ieee952::imu::section_curves_of(
                    section_series(&data.axes),
                    absent,
                    rate,
                    &mut notes,
                );
                (rate, curves, notes, start.elapsed().as_secs_f64())
            })
        },
    );
    let mut findings = check.findings.clone();
    bag2mat::drop_absent(&mut findings, absent);
    notes.extend(absent.map(bag2mat::absent_warning));
    let whole = check.keep.is_all();
    let data = data.select(&check.keep);
    if data.len() < 3 {
        return Err(Error::TooShort { n: data.len() });
    }
    // the column scans describe the analysed samples unless some were left out
    let scans = if whole {
        scans
    } else {
        std::array::from_fn(|a| input::ColumnScan::of(&data.axes[a]))
    };
    input::check_scans(&scans, absent, notes)?;
    let rate = input::choose_rate(config.common.rate, check.rate, data.len())?;
    notes.extend(rate.message.clone().map(Note::info));
    findings.extend(rate.finding.clone());
    Ok(Checked {
        data,
        findings,
        rate,
        whole,
        refusal: check.refusal().cloned(),
        early,
        checks_s,
    })
}

/// The IEEE 952 section's curves and the seconds they took: none when the section is off
/// or the record breaks its assumptions (said in a note), those made beside the check when
/// they fit what the check kept and the rate chosen, else made now.
fn section_curves(
    config: &Config,
    c: &mut Checked,
    notes: &mut Vec<Note>,
) -> (Option<crate::ieee952::imu::ImuCurves>, f64) {
    let start = Instant::now();
    if let (true, Some(r)) = (config.common.ieee952, &c.refusal) {
        notes.push(Note::warning(format!(
            "IEEE 952 section not computed: the record breaks its assumptions ({})",
            r.short()
        )));
    }
    match c.early.take() {
        _ if !config.common.ieee952 || c.refusal.is_some() => (None, 0.0),
        Some((r, curves, early_notes, early_s)) if c.whole && r == c.rate.section => {
            notes.extend(early_notes);
            (curves, early_s)
        }
        _ => {
            let cv = crate::ieee952::imu::section_curves_of(
                section_series(&c.data.axes),
                c.data.absent,
                c.rate.section,
                notes,
            );
            (cv, start.elapsed().as_secs_f64())
        }
    }
}

/// The six columns the compat path runs on: the absent sensor's get the present one's
/// samples as a stand-in, whose results are dropped afterwards.
fn compat_axes(data: ImuData) -> [Vec<f64>; 6] {
    let absent = data.absent;
    let ImuData { mut axes, .. } = data;
    if let Some(s) = absent {
        let (to, from) = if s == bag2mat::Sensor::Acc {
            (0, 3)
        } else {
            (3, 0)
        };
        for k in 0..3 {
            axes[to + k] = axes[from + k].clone();
        }
    }
    axes
}

/// The record's rate as the files state it: the stamps' nominal rate (the section's), or the
/// rate given when the stamps give none.
fn record_rate(config: &Config, rate: &RateChoice) -> RecordRate {
    match (rate.measured, config.common.rate) {
        (None, Some(g)) => RecordRate::Given(g),
        _ => RecordRate::Measured(rate.section),
    }
}

/// What a run's files are written from besides the compat analysis: the section, the
/// compat imu.yaml's update_rate, the topic, the files' provenance, and what became of the
/// section's Kalibr file (imu.yaml's header says it).
struct Written<'a> {
    ieee: Option<&'a crate::ieee952::imu::ImuAnalysis>,
    update_rate: f64,
    topic: &'a str,
    prov: &'a Provenance,
    section: &'a SectionFile,
}

/// Renders the yaml and the curves' CSV (before the output folder is touched), then writes
/// them, the compat charts and the section's files and chart; returns the paths written.
fn write_outputs(
    outputs: &Outputs,
    config: &Config,
    analysis: &Analysis,
    w: Written<'_>,
) -> Result<Vec<PathBuf>, Error> {
    let Written {
        ieee,
        update_rate,
        topic,
        prov,
        section,
    } = w;
    let absent = analysis.absent;
    let yaml = ImuYaml {
        accelerometer_noise_density: analysis.accel.white,
        accelerometer_random_walk: analysis.accel.bias,
        gyroscope_noise_density: analysis.gyro.white,
        gyroscope_random_walk: analysis.gyro.bias,
        rostopic: topic.to_string(),
        update_rate,
        absent,
    }
    .render(prov, section);
    let mut csv = Vec::new();
    curves::write_csv_of(
        &mut csv,
        &analysis.grid.tau1,
        &analysis.sig2,
        &analysis.accel.sigavg,
        &analysis.gyro.sigavg,
        absent,
    )
    .map_err(|e| bag2mat::Error::io("allan_curves.csv", e))?;

    let dir = &config.common.out_dir;
    outputs.ensure_dir(dir)?;
    let mut written = Vec::new();
    let yaml_path = dir.join("imu.yaml");
    outputs.write_atomic(&yaml_path, |w| w.write_all(yaml.as_bytes()))?;
    written.push(yaml_path);
    let csv_path = dir.join("allan_curves.csv");
    outputs.write_atomic(&csv_path, |w| w.write_all(&csv))?;
    written.push(csv_path);
    let title = chart_title(config);
    // The charts are rendered in parallel (each is one thread's work).
    let (compat_plots, section_files) = rayon::join(
        || write_plots(outputs, analysis, &title, dir),
        || -> Result<Vec<PathBuf>, Error> {
            let Some(an) = ieee else {
                return Ok(Vec::new());
            };
            let mut w = crate::ieee952::files::write_outputs(outputs, an, dir, "", topic, prov)?;
            let truth = crate::ieee952::plot::find_truth(config.common.samples_path(), an);
            w.extend(crate::ieee952::plot::write_chart(
                outputs,
                an,
                &title,
                truth.as_ref(),
                dir,
                "",
            )?);
            Ok(w)
        },
    );
    written.extend(compat_plots?);
    written.extend(section_files?);
    Ok(written)
}

/// `--curves`: the IEEE 952 analysis of curves another tool wrote (no samples: no compat
/// outputs), with the same files and chart as from a bag.
pub fn run_curves(
    config: &Config,
    curves: &crate::front::CurvesInput,
    outputs: &Outputs,
) -> Result<Section, Error> {
    let mut opts = curves.options.clone();
    if opts.rate.is_none() {
        opts.rate = config.common.rate;
    }
    let c = crate::ieee952::curves_in::read(&curves.paths, &opts)?;
    let sensors: Vec<_> = c
        .sensors
        .iter()
        .map(|s| (s.sensor, s.axes.clone()))
        .collect();
    let mut an =
        crate::ieee952::imu::analyse_curves(&sensors, c.rate, &crate::ieee952::Config::default());
    an.notes = vec![format!("curves: {}", c.format)];
    an.notes.extend(c.notes.iter().cloned());
    let dir = &config.common.out_dir;
    outputs.ensure_dir(dir)?;
    let title = chart_title(config);
    let rostopic = config.common.named_topic();
    let prov = Provenance::new(
        TOOL,
        curves_text(&curves.paths),
        curves_rate(config.common.rate, &c),
    );
    let mut written = crate::ieee952::files::write_outputs(outputs, &an, dir, "", rostopic, &prov)?;
    written.extend(crate::ieee952::plot::write_chart(
        outputs, &an, &title, None, dir, "",
    )?);
    Ok(Section {
        text: crate::ieee952::imu::summary_text(&an),
        written,
        ..Default::default()
    })
}

/// "curves a.csv, b.csv": the input a file written from `--curves` names.
pub fn curves_text(paths: &[PathBuf]) -> String {
    let p: Vec<String> = paths.iter().map(|p| p.display().to_string()).collect();
    format!("the Allan curves {}", p.join(", "))
}

/// The record's rate behind curves read with `--curves`: `--rate`, else what the format says
/// of the samples (a curve this project or imu_utils wrote starts at one sample; kalibr_allan's
/// grid is in samples), else unknown — allan_variance_ros' 0.1 s bins and a plain CSV's first
/// τ do not say the IMU's rate.
pub fn curves_rate(given: Option<f64>, c: &crate::ieee952::curves_in::Curves) -> RecordRate {
    use crate::ieee952::curves_in::Format;
    if let Some(r) = given {
        return RecordRate::Given(r);
    }
    match c.format {
        Format::Ieee952 | Format::ImuUtils | Format::KalibrAllan => RecordRate::Curves {
            // 1/τ0 of a printed τ: the round rate it stands for (0.005000000001 s is 200 Hz)
            rate: input::snap_rate(c.rate),
            how: format!(
                "1/tau0 of the {} curves (their first point is one sample)",
                c.format
            ),
        },
        Format::AllanVarianceRos | Format::Plain => {
            RecordRate::Unknown(format!("{} does not state the IMU's rate", c.format))
        }
    }
}

/// The charts' title: `--title`, else the input's file stem (upstream hard-codes its
/// `titlestr`).
fn chart_title(config: &Config) -> String {
    if config.title.is_empty() {
        config
            .common
            .input
            .first()
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default()
    } else {
        config.title.clone()
    }
}

/// Writes `allan_accel.{png,svg}` and `allan_gyro.{png,svg}` into `dir`.
pub(crate) fn write_plots(
    outputs: &Outputs,
    a: &Analysis,
    title: &str,
    dir: &Path,
) -> Result<Vec<PathBuf>, Error> {
    let join = |name: &str| {
        if title.is_empty() {
            name.to_owned()
        } else {
            format!("{title} {name}")
        }
    };
    let accel = Chart {
        title: join("acceleration"),
        name: "acceleration",
        unit: "m/s^2",
        unit_white: "m/s^2/sqrt(Hz)",
        unit_bias: "m/s^3/sqrt(Hz)",
        tau: &a.grid.tau1,
        axes: [&a.sig2[0], &a.sig2[1], &a.sig2[2]],
        fit: &a.accel,
    };
    let gyro = Chart {
        title: join("gyroscope"),
        name: "gyroscope",
        unit: "rad/s",
        unit_white: "rad/s/sqrt(Hz)",
        unit_bias: "rad/s^2/sqrt(Hz)",
        tau: &a.grid.tau1,
        axes: [&a.sig2[3], &a.sig2[4], &a.sig2[5]],
        fit: &a.gyro,
    };
    let mut out = Vec::new();
    if a.absent != Some(bag2mat::Sensor::Acc) {
        out.extend(chart::write_chart(outputs, &accel, dir, "allan_accel")?);
    }
    if a.absent != Some(bag2mat::Sensor::Gyro) {
        out.extend(chart::write_chart(outputs, &gyro, dir, "allan_gyro")?);
    }
    Ok(out)
}
