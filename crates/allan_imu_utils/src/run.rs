//! One whole run: read the bag, collect with the stop rule, analyse, write every output.

use std::path::PathBuf;
use std::time::{Duration, Instant};

use crate::analysis::{self, Analysis};
use crate::cli::Config;
use crate::collect::{self, Stop};
use crate::error::Error;
use crate::opencv_yaml::{self, YamlMode};
use crate::{plot, report};

/// What a run produced; the binary prints `stdout` and `notes`.
#[derive(Debug)]
pub struct Outcome {
    /// Upstream's terminal output.
    pub stdout: String,
    /// Things to say on stderr (end of bag, topic fallback, …).
    pub notes: Vec<String>,
    /// Files written.
    pub files: Vec<PathBuf>,
    /// The analysis itself.
    pub analysis: Analysis,
    /// (phase, wall time).
    pub timings: Vec<(&'static str, Duration)>,
}

/// Runs the whole pipeline for `config`.
pub fn run(config: &Config) -> Result<Outcome, Error> {
    let mut timings = Vec::new();
    let t0 = Instant::now();
    let series = bag2mat::read_imu_series(
        &config.bag,
        &config.topic,
        &bag2mat::ReadOptions {
            quiet: config.quiet,
        },
    )?;
    timings.push(("read_bag", t0.elapsed()));
    let mut notes = series.notes.clone();
    let collected = collect::collect(&series, config.max_time_min);
    if collected.stop == Stop::EndOfBag {
        notes.push(format!(
            "WARNING: bag ended after {} messages before max_time_min ({}) was exceeded; the ROS node would wait forever. Processing what was read.",
            collected.len(),
            config.max_time_min
        ));
    }
    analysis::check_enough(&collected, config.max_cluster)?;
    let t1 = Instant::now();
    let (axes, gyro_mean) = analysis::allan_step(&collected, config.max_cluster)?;
    timings.push(("allan", t1.elapsed()));
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
        source: e,
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
    timings.push(("write_outputs", t2.elapsed()));
    Ok(Outcome {
        stdout: report::stdout_text(&analysis),
        notes,
        files,
        analysis,
        timings,
    })
}
