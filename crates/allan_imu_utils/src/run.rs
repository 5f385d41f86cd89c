//! One whole run: read the bag, collect with the stop rule, analyse, write every output.

use std::path::PathBuf;
use std::time::{Duration, Instant};

use crate::analysis::{self, Analysis};
use crate::cli::Config;
use crate::collect::{self, Stop};
use crate::error::Error;
use crate::opencv_yaml::{self, YamlMode};
use crate::{plot, report};

/// What a run produced for one topic; the binary prints `stdout` and `notes`.
#[derive(Debug)]
pub struct Outcome {
    /// The topic, as named in the bag.
    pub topic: String,
    /// Upstream's terminal output.
    pub stdout: String,
    /// The IEEE 952 section printed after it (when enabled and the data allow it).
    pub ieee952_text: Option<String>,
    /// Things to say on stderr (end of bag, topic fallback, …).
    pub notes: Vec<String>,
    /// Files written.
    pub files: Vec<PathBuf>,
    /// The analysis itself.
    pub analysis: Analysis,
    /// (phase, wall time).
    pub timings: Vec<(&'static str, Duration)>,
}

/// Runs the whole pipeline for `config`: every selected topic is read in one pass and
/// analysed on its own. With one topic the outputs go into `out_dir`; with several, into
/// `out_dir/<topic folder>`.
pub fn run(config: &Config) -> Result<Vec<Outcome>, Error> {
    let t0 = Instant::now();
    let read = bag2mat::read_imu_topics(
        &config.bag,
        &bag2mat::TopicSelector {
            topics: config.topics.clone(),
            all_imu: config.all_imu,
        },
        &bag2mat::ReadOptions {
            quiet: config.quiet,
        },
    )?;
    let read_time = t0.elapsed();
    let several = read.series.len() > 1 || config.all_imu;
    let names: Vec<String> = read.series.iter().map(|s| s.topic.clone()).collect();
    let names: Vec<&str> = names.iter().map(|s| s.as_str()).collect();
    let folders = bag2mat::series::topic_folder_names(&names);
    let mut outs = Vec::new();
    for (series, folder) in read.series.into_iter().zip(folders) {
        let mut c = config.clone();
        if several {
            c.out_dir = config.out_dir.join(folder);
        }
        outs.push(run_series(&c, series, read_time)?);
    }
    Ok(outs)
}

/// The pipeline on one topic's series.
fn run_series(
    config: &Config,
    series: bag2mat::ImuSeries,
    read_time: Duration,
) -> Result<Outcome, Error> {
    let mut timings = vec![("read_bag", read_time)];
    let topic = series.topic.clone();
    let mut notes = series.notes.clone();
    let collected = collect::collect(&series, config.max_time_min, config.time);
    if collected.stop == Stop::EndOfBag {
        notes.push(format!(
            "WARNING: bag ended after {} messages before max_time_min ({}) was exceeded; the ROS node would wait forever. Processing what was read.",
            collected.len(),
            config.max_time_min
        ));
    }
    // The Allan variance assumes one constant rate with no gap: a record that is not one
    // continuous stretch is cut to its longest (bag2mat::timing finds gaps and rate changes).
    let mut collected = collected;
    let tm = bag2mat::timing::analyse(&collected.t);
    if !tm.is_continuous()
        && let Some(seg) = tm.longest()
    {
        notes.push(format!(
            "warning: the stamps of '{topic}' are not one continuous record ({}); an Allan variance across it would be meaningless, so only its longest continuous stretch is analysed: messages {}..{} ({} of {})",
            tm.describe(),
            seg.start,
            seg.end,
            seg.len(),
            collected.len()
        ));
        collected.restrict(seg.start..seg.end);
    } else if !tm.gaps.is_empty() {
        notes.push(format!(
            "warning: the stamps of '{topic}' have small gaps ({}); analysed as one record",
            tm.describe()
        ));
    }
    analysis::check_enough(&collected, config.max_cluster)?;
    for (k, name) in collect::FIELDS.iter().enumerate() {
        let col: Vec<f64> = if k < 3 {
            collected.gyro_rad_s(k)
        } else {
            collected.acc_values(k - 3).collect()
        };
        match allan_kalibr::input::value_problem(name, &col) {
            Some((true, what)) => return Err(Error::Config(what)),
            Some((false, what)) => notes.push(format!("warning: {what}")),
            None => {}
        }
    }
    let t1 = Instant::now();
    let (axes, gyro_mean) = analysis::allan_step(&collected, config.max_cluster)?;
    timings.push(("allan", t1.elapsed()));
    // The IEEE 952 analysis of the same samples (rad/s, m/s²) at imu_utils' mean-period
    // rate. Data too short for it only costs the section, with a note.
    let t1 = Instant::now();
    let ieee = if config.ieee952 {
        let cols: Vec<Vec<f64>> = (0..3)
            .map(|k| collected.gyro_rad_s(k))
            .chain((0..3).map(|k| collected.acc_values(k).collect()))
            .collect();
        let series = [
            &cols[0][..],
            &cols[1][..],
            &cols[2][..],
            &cols[3][..],
            &cols[4][..],
            &cols[5][..],
        ];
        allan_kalibr::ieee952::imu::analyse_section(series, axes[0].freq, &mut notes)
    } else {
        None
    };
    timings.push(("ieee952", t1.elapsed()));
    drop(collected);
    drop(series);
    let t1 = Instant::now();
    let fits = analysis::fit_all(&axes);
    let analysis = Analysis {
        max_cluster: config.max_cluster,
        axes,
        gyro_mean,
        fits,
    };
    timings.push(("fit", t1.elapsed()));
    let t2 = Instant::now();
    std::fs::create_dir_all(&config.out_dir).map_err(|e| Error::Io {
        path: config.out_dir.clone(),
        cause: e,
    })?;
    let mut files = report::write_curve_files(&analysis, &config.name, &config.out_dir)?;
    for mode in [YamlMode::Compat, YamlMode::Continuous] {
        let p = config.out_dir.join(mode.file_name(&config.name));
        report::write_text(&p, &opencv_yaml::yaml_text(&analysis, &config.name, mode))?;
        files.push(p);
    }
    if config.plots {
        files.extend(plot::write_plots(&analysis, &config.name, &config.out_dir)?);
    }
    if let Some(an) = &ieee {
        let prefix = format!("{}_", config.name);
        files.extend(allan_kalibr::ieee952::imu::write_outputs(
            an,
            &config.out_dir,
            &prefix,
            &topic,
        )?);
    }
    timings.push(("write_outputs", t2.elapsed()));
    Ok(Outcome {
        topic,
        stdout: report::stdout_text(&analysis),
        ieee952_text: ieee.as_ref().map(allan_kalibr::ieee952::imu::summary_text),
        notes,
        files,
        analysis,
        timings,
    })
}
