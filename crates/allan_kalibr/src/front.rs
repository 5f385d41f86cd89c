//! The analysers' one front end: the arguments both `allan_kalibr` and `allan_imu_utils`
//! take ([`CommonArgs`], flattened into each tool's clap struct), their resolution into
//! [`Common`] settings, and the one [`finish`] that runs a job inside an all-or-none output
//! stage and says its results, notes, findings and timings the same way for both tools.
//!
//! A run leaves in each output folder only its own set of files: files of the tool's names
//! ([`Job::output_names`]) that an earlier run left there and this run does not write are
//! removed by the same all-or-none commit, and said (a `warning:` line naming them); files
//! this run writes replace the earlier run's, said in the "wrote" lines.
//!
//! One spelling for both tools: `-o/--out-dir` (kalibr_allan's `--outdir` and imu_utils'
//! `data_save_path` as aliases), `--rate` (`--update-rate` as alias). A flag that would do
//! nothing for the input is an error, never ignored. Results go to a folder of their own
//! (`<input stem>_<tool>/` beside the input) unless `-o` says otherwise: never the data folder.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use bag2mat::Finding;
use bag2mat::shared::note::Note;
use bag2mat::shared::{cli, output};

/// The slowest sample rate accepted, Hz: below it a τ grid of seconds-to-hours is meaningless
/// and the printed numbers run to hundreds of digits.
pub const MIN_RATE_HZ: f64 = 1e-3;
/// The fastest sample rate accepted, Hz (IMUs sample at 1 Hz to a few tens of kHz).
pub const MAX_RATE_HZ: f64 = 1e7;

/// The input the analysers read besides bag2mat's, as their help names it.
pub const MAT_INPUT: &str = "a bagconvert .mat (data_imu, N x 7: t ax ay az wx wy wz)";

/// The topic read when none is named and the input has it: both upstream tools' default.
pub const DEFAULT_TOPIC: &str = "imu";

/// The arguments both analysers take, in one place.
// The field docs are clap's help texts, which write defaults as `<input stem>_<tool>/`:
// rustdoc would read those as HTML tags, and escaping them would show in `--help`.
#[allow(rustdoc::invalid_html_tags)]
#[derive(Debug, Clone, PartialEq, clap::Args)]
pub struct CommonArgs {
    /// The input (its help lists every kind read: bag2mat's and [`MAT_INPUT`]).
    #[arg(required_unless_present = "curves", value_name = "INPUT", help = bag2mat::input_help(&[MAT_INPUT]))]
    pub input: Option<PathBuf>,
    /// Analyse existing Allan curves instead (IEEE 952 section only): an imu_utils data
    /// directory, allan_variance_ros' allan_variance.csv, an allan_curves.csv, an
    /// ieee952_curves.csv, or a plain CSV `tau,x,y,z` (one sensor; give --units). A plain CSV
    /// per sensor may be given twice.
    #[arg(long, value_name = "PATH", conflicts_with = "input")]
    pub curves: Vec<PathBuf>,
    /// Unit of each plain CSV of --curves, in order: rad/s, deg/s, deg/h, imu_utils, m/s^2,
    /// g, mg (the values are Allan deviations).
    #[arg(long, value_name = "UNIT")]
    pub units: Vec<String>,
    /// Length of the record behind --curves, in seconds (for the confidence intervals).
    #[arg(long, value_name = "SECONDS", conflicts_with = "samples", value_parser = cli::positive_f64)]
    pub duration: Option<f64>,
    /// Number of samples behind --curves (for the confidence intervals).
    #[arg(long, value_name = "N")]
    pub samples: Option<u64>,
    /// The sample rate, Hz: of a text log without a time column, or of plain --curves CSVs
    /// whose τ do not start at one sample (allan_kalibr: also the τ grid's update_rate;
    /// default: estimated from the time stamps).
    #[arg(long, value_name = "HZ", visible_alias = "update-rate", value_parser = rate_hz)]
    pub rate: Option<f64>,
    /// Drop the first SECONDS of the record (a warm-up) before any analysis.
    #[arg(long, value_name = "SECONDS", value_parser = cli::positive_f64)]
    pub skip_start: Option<f64>,
    /// Drop the samples the record check finds to be spikes (a sample far off its
    /// neighbours, reported with its time) before any analysis.
    #[arg(long)]
    pub drop_outliers: bool,
    /// The sensor_msgs/Imu topic (`imu` and `/imu` are the same); repeatable, each topic
    /// then gets its own folder under the output directory [default: `imu` when the input
    /// has it, else the input's only Imu topic].
    #[arg(long = "topic", value_name = "TOPIC")]
    pub topics: Vec<String>,
    /// Every topic of the input that carries sensor_msgs/Imu, each into its own folder.
    #[arg(long)]
    pub all_imu_topics: bool,
    /// Output directory, created if missing [default: <input stem>_<tool>/ beside the input].
    #[arg(
        short = 'o',
        long = "out-dir",
        value_name = "DIR",
        visible_aliases = ["outdir", "data-save-path"]
    )]
    pub out_dir: Option<PathBuf>,
    /// Only errors and warnings on stderr: no progress bars, no "wrote" lines (the results
    /// still go to stdout).
    #[arg(short, long)]
    pub quiet: bool,
    /// Print the wall time of each phase on stderr (for benchmarks).
    #[arg(long)]
    pub timings: bool,
    /// Only what the upstream tool produces: skip the IEEE 952 section and its files.
    #[arg(long)]
    pub compat_only: bool,
    /// How the input is read (bag2mat's input flags: units, columns, time).
    #[command(flatten)]
    pub input_args: bag2mat::InputArgs,
}

/// `--rate`: a positive number of Hz within [`MIN_RATE_HZ`, `MAX_RATE_HZ`].
pub(crate) fn rate_hz(s: &str) -> Result<f64, cli::UsageError> {
    let v = cli::positive_f64(s)?;
    if !(MIN_RATE_HZ..=MAX_RATE_HZ).contains(&v) {
        return Err(cli::UsageError(format!(
            "{s} Hz is outside {MIN_RATE_HZ} .. {MAX_RATE_HZ:e} Hz"
        )));
    }
    Ok(v)
}

/// What a run reads: samples, or Allan curves another tool wrote.
#[derive(Debug, Clone, PartialEq)]
pub enum Input {
    /// A bag, a `.mat` or an IMU log.
    Samples(PathBuf),
    /// `--curves`.
    Curves(CurvesInput),
}

impl Input {
    /// The paths the run reads (never an output).
    pub(crate) fn paths(&self) -> Vec<&Path> {
        match self {
            Input::Samples(p) => vec![p.as_path()],
            Input::Curves(c) => c.paths.iter().map(|p| p.as_path()).collect(),
        }
    }

    /// The first path: what the default output folder is named after.
    pub(crate) fn first(&self) -> &Path {
        self.paths().first().copied().unwrap_or(Path::new("."))
    }
}

/// `--curves`: the files and what the user said about them.
#[derive(Debug, Clone, PartialEq)]
pub struct CurvesInput {
    /// A directory (imu_utils) or files.
    pub paths: Vec<PathBuf>,
    /// Record length, sample count, rate, units, name.
    pub options: crate::ieee952::curves_in::Options,
}

/// The settings both analysers share, resolved from [`CommonArgs`].
#[derive(Debug, Clone, PartialEq)]
pub struct Common {
    /// Samples or curves.
    pub input: Input,
    /// Topics (bag2mat's topic rules, `imu` preferred); each of several gets its own folder.
    pub topics: bag2mat::TopicSelector,
    /// The time column.
    pub time: bag2mat::TimeColumn,
    /// `--rate`, Hz.
    pub rate: Option<f64>,
    /// Output directory (created if missing).
    pub out_dir: PathBuf,
    /// Seconds dropped at the start of the record (a warm-up), before everything.
    pub skip_start: Option<f64>,
    /// Drop the samples the record check finds to be spikes, before everything else.
    pub drop_outliers: bool,
    /// No progress bars, no information notes.
    pub quiet: bool,
    /// Print phase timings on stderr.
    pub timings: bool,
    /// Also run the IEEE 952 analysis (section and files beside the compat outputs).
    pub ieee952: bool,
    /// What the user said about a log whose content does not say it all (a text log's
    /// columns, units and, without a time column, its rate).
    pub input_options: bag2mat::InputOptions,
}

impl Common {
    /// Settings for `input` with every other choice at its default (library callers, tests).
    pub fn new(input: Input, out_dir: impl Into<PathBuf>) -> Common {
        Common {
            input,
            topics: default_topics(),
            time: bag2mat::TimeColumn::Record,
            rate: None,
            out_dir: out_dir.into(),
            skip_start: None,
            drop_outliers: false,
            quiet: true,
            timings: false,
            ieee952: true,
            input_options: Default::default(),
        }
    }

    /// The topic a `.mat` or curves input stands for (imu.yaml's `rostopic`): the first
    /// named, else the default.
    pub fn named_topic(&self) -> &str {
        self.topics
            .topics
            .first()
            .or(self.topics.preferred.as_ref())
            .map_or(DEFAULT_TOPIC, |s| s.as_str())
    }

    /// The samples' path (empty with `--curves`).
    pub fn samples_path(&self) -> &Path {
        match &self.input {
            Input::Samples(p) => p,
            Input::Curves(_) => Path::new(""),
        }
    }
}

/// No topic named: `imu` when the input has it, else its only Imu topic.
pub(crate) fn default_topics() -> bag2mat::TopicSelector {
    bag2mat::TopicSelector {
        preferred: Some(DEFAULT_TOPIC.to_string()),
        ..Default::default()
    }
}

/// The default output folder of `tool` for `input`: `<stem>_<tool>` beside it (a bag
/// directory's or curves directory's name stands for the stem), never the data folder; for
/// an input inside an EuRoC/ASL dataset, beside the dataset's root
/// ([`bag2mat::euroc_output_base`]: `MH_01_easy_imu0_<tool>` for `MH_01_easy/mav0/imu0`).
pub(crate) fn default_out_dir(input: &Path, tool: &str) -> PathBuf {
    if let Some((parent, stem)) = bag2mat::euroc_output_base(input) {
        return parent.join(format!("{stem}_{tool}"));
    }
    let input = if input.file_name().is_some_and(|n| n == "metadata.yaml") {
        input.parent().unwrap_or(Path::new("."))
    } else {
        input
    };
    // a directory by its own name ("." included), a file by its stem
    let (parent, stem) = if input.is_dir() {
        let canon = std::fs::canonicalize(input).unwrap_or_else(|_| input.to_path_buf());
        let parent = canon.parent().map(Path::to_path_buf).unwrap_or_default();
        (parent, canon.file_name().map(|s| s.to_os_string()))
    } else {
        let parent = input.parent().map(Path::to_path_buf).unwrap_or_default();
        (parent, input.file_stem().map(|s| s.to_os_string()))
    };
    let stem = stem
        .map(|s| s.to_string_lossy().into_owned())
        .filter(|s| !s.is_empty())
        .unwrap_or_else(|| "input".to_string());
    parent.join(format!("{stem}_{tool}"))
}

impl CommonArgs {
    /// --units, --duration, --samples (and `more`) describe Allan curves: without --curves
    /// they would be ignored in silence.
    pub fn curve_flags_need_curves(&self, more: &[(&str, bool)]) -> Result<(), cli::UsageError> {
        let mut flags = vec![
            ("--units", !self.units.is_empty()),
            ("--duration", self.duration.is_some()),
            ("--samples", self.samples.is_some()),
        ];
        flags.extend_from_slice(more);
        cli::only_with("--curves", !self.curves.is_empty(), &flags)
    }

    /// The settings, for `tool` (the default output folder's suffix), with `time` and the
    /// curves' IMU `name` (imu_utils' `--name`). `out_dir` given by a tool's own source (a
    /// launch file) stands in for a missing `-o`. `timeless_rate` is the rate a text log
    /// without a time column is sampled at.
    pub fn resolve(
        self,
        tool: &str,
        time: bag2mat::TimeColumn,
        name: Option<String>,
        out_dir: Option<PathBuf>,
        timeless_rate: Option<f64>,
    ) -> Common {
        let input = match self.input {
            Some(p) => Input::Samples(p),
            None => Input::Curves(CurvesInput {
                paths: self.curves.clone(),
                options: crate::ieee952::curves_in::Options {
                    duration: self.duration,
                    samples: self.samples,
                    rate: self.rate,
                    units: self.units.clone(),
                    name,
                },
            }),
        };
        let out_dir = self
            .out_dir
            .or(out_dir)
            .unwrap_or_else(|| default_out_dir(input.first(), tool));
        let topics = if self.topics.is_empty() && !self.all_imu_topics {
            default_topics()
        } else {
            bag2mat::TopicSelector {
                topics: self.topics,
                all_imu: self.all_imu_topics,
                preferred: None,
            }
        };
        Common {
            input,
            topics,
            time,
            rate: self.rate,
            out_dir,
            skip_start: self.skip_start,
            drop_outliers: self.drop_outliers,
            quiet: self.quiet,
            timings: self.timings,
            ieee952: !self.compat_only,
            input_options: self.input_args.options(timeless_rate),
        }
    }
}

/// The rate a text log without a time column is sampled at: `--rate` when the input is a
/// text log (for every other input the rate is the stamps'; the reader refuses a rate it
/// cannot use, so a flag that does nothing is an error).
pub fn rate_for_text(input: Option<&Path>, rate: Option<f64>) -> Option<f64> {
    let text =
        input.is_some_and(|p| matches!(bag2mat::input_kind(p), Ok(bag2mat::InputKind::Text)));
    rate.filter(|_| text)
}

/// Why a record the check refuses gets no IEEE 952 section, for the files' words: the
/// finding in short and its first clause ("motion (1.2e1 m/s^2, …): the IMU is not static:
/// in 120 of 120 windows …").
pub fn refusal_text(f: &Finding) -> String {
    let first = f.text.split(';').next().unwrap_or("").trim();
    format!("{}: {first}", f.short())
}

/// What a run says about one topic (or about the curves it read).
#[derive(Debug, Default)]
pub struct Section {
    /// The topic, when the run read several (a header line before its text).
    pub topic: Option<String>,
    /// Notes and warnings, in order.
    pub notes: Vec<Note>,
    /// What the record check found (always said).
    pub findings: Vec<Finding>,
    /// The results (stdout): the reproduced tool's text.
    pub text: String,
    /// The IEEE 952 section printed after it (when enabled and the data allow it).
    pub ieee952_text: Option<String>,
    /// Files written (a "wrote" line each, without --quiet).
    pub written: Vec<PathBuf>,
    /// Phase timings, one line each (with --timings).
    pub timings: Vec<String>,
    /// Why this topic could not be analysed, when the run read several and this one failed
    /// ([`topic_failed`]): said once as an error, the other topics still written.
    pub error: Option<String>,
}

/// The section of a topic that failed in a run of several topics: its reader's `notes`
/// and the error (the run goes on with the other topics, and exits 1).
pub fn topic_failed(topic: &str, notes: Vec<Note>, error: &dyn std::fmt::Display) -> Section {
    Section {
        topic: Some(topic.to_string()),
        notes,
        error: Some(error.to_string()),
        ..Section::default()
    }
}

/// One topic's outcome in a run of several (both tools' `run_topics`): a topic that fails
/// does not stop the others.
#[derive(Debug)]
pub struct TopicOutcome<O, E> {
    /// The topic.
    pub topic: String,
    /// What its reader said (repeated for a topic that failed, whose section has no other).
    pub notes: Vec<Note>,
    /// Its analysis, or why it failed.
    pub result: Result<O, E>,
}

/// The sections of a run's topics, `section` giving an analysis' own: of several topics,
/// one that failed is said as its error ([`topic_failed`]) and the others are still written
/// (both tools' rule); a single topic's error is the run's.
pub fn topic_sections<O, E: std::fmt::Display>(
    topics: Vec<TopicOutcome<O, E>>,
    section: impl Fn(O) -> Section,
) -> Result<Vec<Section>, E> {
    let several = topics.len() > 1;
    topics
        .into_iter()
        .map(|t| match t.result {
            Ok(o) => Ok(section(o)),
            Err(e) if several => Ok(topic_failed(&t.topic, t.notes, &e)),
            Err(e) => Err(e),
        })
        .collect()
}

/// A tool's settings as the front end runs them: the shared part, and the job that turns
/// them into sections.
pub trait Job {
    /// The job's error (said once by `finish`).
    type Error: std::fmt::Display;
    /// The settings both analysers share.
    fn common(&self) -> &Common;
    /// The whole job, every file among `outputs`.
    fn sections(&self, outputs: &output::Outputs) -> Result<Vec<Section>, Self::Error>;
    /// The names of every file a run of the tool may write into an output folder: what an
    /// earlier run of it left there and this run does not write is removed at the commit.
    fn output_names(&self) -> Vec<String>;
}

/// A tool's whole `main`: the worker threads started, the arguments `A` parsed and resolved
/// into the settings `C` ([`command_line`]), the job run inside its output stage and said
/// ([`run_job`]).
pub fn main<A, C>(tool: &str) -> ExitCode
where
    A: clap::Parser,
    C: Job + TryFrom<A>,
    <C as TryFrom<A>>::Error: std::fmt::Display,
{
    match command_line::<A, C>(tool) {
        Ok(config) => run_job(tool, &config),
        Err(code) => code,
    }
}

/// The worker threads started, the arguments `A` parsed and resolved into the settings `C`;
/// or the exit code of `--help`/`--version` (0) or of a command line that cannot be run (2).
pub fn command_line<A, C>(tool: &str) -> Result<C, ExitCode>
where
    A: clap::Parser,
    C: TryFrom<A>,
    <C as TryFrom<A>>::Error: std::fmt::Display,
{
    bag2mat::shared::alloc::start_threads(tool);
    parse::<A, C, _>(tool, C::try_from)
}

/// Runs the job `config` inside its output stage and says what it found (`finish`).
pub fn run_job<C: Job>(tool: &str, config: &C) -> ExitCode {
    finish(tool, config.common(), &config.output_names(), |outputs| {
        config.sections(outputs)
    })
}

/// Parses the tool's arguments into its settings: `--help`/`--version` print and exit 0,
/// a command line that cannot be run is a usage error (exit 2).
fn parse<A: clap::Parser, C, E: std::fmt::Display>(
    tool: &str,
    resolve: impl FnOnce(A) -> Result<C, E>,
) -> Result<C, ExitCode> {
    let args = match A::try_parse() {
        Ok(a) => a,
        Err(e) if !e.use_stderr() => {
            let _ = e.print();
            return Err(ExitCode::SUCCESS);
        }
        Err(e) => return Err(cli::usage(tool, &e.render().to_string())),
    };
    resolve(args).map_err(|e| cli::usage(tool, &e.to_string()))
}

/// The files of the tool's `names` in the folders a run writes into (`out_dir` and each
/// written file's folder) that the run does not write: an earlier run's, to retire.
fn stale_files(out_dir: &Path, sections: &[Section], names: &[String]) -> Vec<PathBuf> {
    let written: Vec<&PathBuf> = sections.iter().flat_map(|s| s.written.iter()).collect();
    let mut folders: Vec<PathBuf> = vec![out_dir.to_path_buf()];
    for p in &written {
        let dir = p.parent().unwrap_or(Path::new("")).to_path_buf();
        if !folders.contains(&dir) {
            folders.push(dir);
        }
    }
    let mut stale = Vec::new();
    for dir in &folders {
        for n in names {
            let p = dir.join(n);
            let is_file = std::fs::symlink_metadata(&p).is_ok_and(|m| m.file_type().is_file());
            if is_file && !written.iter().any(|w| **w == p) {
                stale.push(p);
            }
        }
    }
    stale
}

/// `paths` grouped by folder, in the order each folder first appears: (folder, file names).
fn by_folder(paths: &[PathBuf]) -> Vec<(&Path, Vec<String>)> {
    let mut folders: Vec<(&Path, Vec<String>)> = Vec::new();
    for p in paths {
        let dir = p.parent().unwrap_or(Path::new(""));
        let name = p.file_name().map_or_else(
            || p.display().to_string(),
            |n| n.to_string_lossy().into_owned(),
        );
        match folders.iter_mut().find(|(d, _)| *d == dir) {
            Some((_, names)) => names.push(name),
            None => folders.push((dir, vec![name])),
        }
    }
    folders
}

/// "removed 2 files an earlier run left in DIR/ (this run does not write them): a, b", one
/// line per folder.
fn removed_lines(removed: &[PathBuf]) -> Vec<String> {
    by_folder(removed)
        .into_iter()
        .map(|(dir, names)| {
            let files = if names.len() == 1 { "file" } else { "files" };
            format!(
                "removed {} {files} an earlier run left in {}/ (this run does not write them; they described another run): {}",
                names.len(),
                dir.display(),
                names.join(", ")
            )
        })
        .collect()
}

/// Runs `job` with its outputs staged (all of them or none are put in place, never over an
/// input: [`output::Outputs::staged`]), retiring with them the files of the tool's `names`
/// an earlier run left in the run's folders and this run does not write; then says
/// what it found: per section its notes (warnings always, information without --quiet),
/// the record check's findings, the results on stdout, the files written (and replaced), the
/// files removed, and the timings. The exit code: 0, or 1 with the error said once. A run
/// of several topics in which a topic failed ([`Section::error`]) writes the others, says
/// that topic's error once in its place (`<tool>: error: topic '<topic>': …`) and exits 1:
/// the same rule in both tools.
fn finish<E: std::fmt::Display>(
    tool: &str,
    common: &Common,
    names: &[String],
    job: impl FnOnce(&output::Outputs) -> Result<Vec<Section>, E>,
) -> ExitCode {
    let mut outputs = output::Outputs::staged();
    for p in common.input.paths() {
        outputs.protect_input(p);
    }
    let started = std::time::Instant::now();
    let sections = match job(&outputs) {
        Ok(s) => s,
        Err(e) => return cli::fail(tool, &e),
    };
    let mut removed = Vec::new();
    for p in stale_files(&common.out_dir, &sections, names) {
        // an input is never removed (nor written): it is left as it is
        if outputs.remove_at_commit(&p).is_ok() {
            removed.push(p);
        }
    }
    let replaced: Vec<PathBuf> = sections
        .iter()
        .flat_map(|s| s.written.iter())
        .filter(|p| p.exists())
        .cloned()
        .collect();
    if let Err(e) = outputs.commit() {
        return cli::fail(tool, &e);
    }
    for line in removed_lines(&removed) {
        eprintln!("{}", Note::warning(line).line());
    }
    let several = sections.iter().filter(|s| s.topic.is_some()).count() > 1;
    let mut printing = true;
    let mut failed = false;
    for s in &sections {
        for n in &s.notes {
            if n.is_warning() || !common.quiet {
                eprintln!("{}", n.line());
            }
        }
        if let Some(e) = &s.error {
            failed = true;
            // the topic named once: most errors about a topic name it already
            let topic = bag2mat::escape_printable(s.topic.as_deref().unwrap_or(""));
            if e.contains(&format!("'{topic}'")) {
                eprintln!("{tool}: error: {e}");
            } else {
                eprintln!("{tool}: error: topic '{topic}': {e}");
            }
            continue;
        }
        let topic = s.topic.as_deref().filter(|_| several);
        for f in &s.findings {
            eprintln!("{}", f.line(topic));
        }
        if printing {
            let mut text = String::new();
            if let Some(t) = topic {
                text.push_str(&format!("===== topic {t} =====\n"));
            }
            text.push_str(&s.text);
            text.push_str(s.ieee952_text.as_deref().unwrap_or(""));
            match cli::print(&text) {
                Ok(more) => printing = more,
                Err(e) => return cli::fail(tool, &e),
            }
        }
        if !common.quiet {
            for line in wrote_lines(&s.written, &replaced) {
                eprintln!("{line}");
            }
        }
        if common.timings {
            for t in &s.timings {
                eprintln!("{t}");
            }
        }
    }
    if common.timings {
        eprintln!("timing total {:.3} s", started.elapsed().as_secs_f64());
    }
    if failed {
        ExitCode::from(cli::EXIT_FAILURE)
    } else {
        ExitCode::SUCCESS
    }
}

/// "wrote N files to DIR/: a, b, …", one line per folder, in the order written; "(K of
/// them replacing an earlier run's)" when files of these names were there before.
fn wrote_lines(written: &[PathBuf], replaced: &[PathBuf]) -> Vec<String> {
    by_folder(written)
        .into_iter()
        .map(|(dir, names)| {
            let again = replaced
                .iter()
                .filter(|p| p.parent().unwrap_or(Path::new("")) == dir)
                .count();
            let dir = if dir.as_os_str().is_empty() {
                ".".to_string()
            } else {
                dir.display().to_string()
            };
            let files = if names.len() == 1 { "file" } else { "files" };
            let again = match again {
                0 => String::new(),
                k if k == names.len() => " (replacing an earlier run's)".to_string(),
                k => format!(" ({k} of them replacing an earlier run's)"),
            };
            format!(
                "wrote {} {files} to {dir}/{again}: {}",
                names.len(),
                names.join(", ")
            )
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_default_output_folder_is_beside_the_input_never_in_it() {
        let dir = tempfile::tempdir().unwrap();
        let bag = dir.path().join("rec.bag");
        std::fs::write(&bag, b"x").unwrap();
        assert_eq!(
            default_out_dir(&bag, "allan_kalibr"),
            dir.path().join("rec_allan_kalibr")
        );
        let ros2 = dir.path().join("run1");
        std::fs::create_dir(&ros2).unwrap();
        std::fs::write(ros2.join("metadata.yaml"), b"x").unwrap();
        let canon = std::fs::canonicalize(dir.path()).unwrap();
        assert_eq!(
            default_out_dir(&ros2, "allan_imu_utils"),
            canon.join("run1_allan_imu_utils")
        );
        assert_eq!(
            default_out_dir(&ros2.join("metadata.yaml"), "allan_imu_utils"),
            canon.join("run1_allan_imu_utils")
        );
        assert_eq!(
            default_out_dir(Path::new("x.mat"), "allan_kalibr"),
            PathBuf::from("x_allan_kalibr")
        );
    }

    /// An EuRoC/ASL dataset's IMU (its data.csv, its folder, or mav0) is analysed into a
    /// folder beside the dataset, never inside its tree.
    #[test]
    fn a_euroc_dataset_s_output_folder_is_beside_the_dataset_never_in_it() {
        let dir = tempfile::tempdir().unwrap();
        let imu0 = dir.path().join("MH_01_easy/mav0/imu0");
        std::fs::create_dir_all(&imu0).unwrap();
        std::fs::write(
            imu0.join("data.csv"),
            "#timestamp [ns],w_RS_S_x [rad s^-1],w_RS_S_y [rad s^-1],w_RS_S_z [rad s^-1],a_RS_S_x [m s^-2],a_RS_S_y [m s^-2],a_RS_S_z [m s^-2]\n1,0,0,0,0,0,9.8\n",
        )
        .unwrap();
        let canon = std::fs::canonicalize(dir.path()).unwrap();
        for (input, out) in [
            (imu0.join("data.csv"), "MH_01_easy_imu0_allan_kalibr"),
            (imu0.clone(), "MH_01_easy_imu0_allan_kalibr"),
            (
                dir.path().join("MH_01_easy/mav0"),
                "MH_01_easy_allan_kalibr",
            ),
            (dir.path().join("MH_01_easy"), "MH_01_easy_allan_kalibr"),
        ] {
            assert_eq!(
                default_out_dir(&input, "allan_kalibr"),
                canon.join(out),
                "{}",
                input.display()
            );
        }
    }

    #[test]
    fn the_files_written_are_said_once_per_folder() {
        let w = ["o/a.yaml", "o/b.csv", "o/s/c.png"].map(PathBuf::from);
        assert_eq!(
            wrote_lines(&w, &[]),
            [
                "wrote 2 files to o/: a.yaml, b.csv",
                "wrote 1 file to o/s/: c.png"
            ]
        );
        assert_eq!(
            wrote_lines(&w, &[PathBuf::from("o/b.csv")])[0],
            "wrote 2 files to o/ (1 of them replacing an earlier run's): a.yaml, b.csv"
        );
    }
}
