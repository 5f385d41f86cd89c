//! `allan_imu_utils BAG [--topic imu] [--name imu] [--data-save-path DIR] [--max-time-min 120]
//! [--max-cluster 100] [--launch FILE.launch]`: imu_utils without ROS.

use std::io::Write;
use std::process::ExitCode;

use anyhow::Context;
use clap::Parser;

use allan_imu_utils::cli::{Args, Config};

fn main() -> ExitCode {
    match run() {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("allan_imu_utils: error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

fn run() -> anyhow::Result<()> {
    let t = std::time::Instant::now();
    let config = Config::try_from(Args::parse()).context("bad arguments")?;
    let what = match &config.curves {
        Some(c) => c
            .paths
            .iter()
            .map(|p| p.display().to_string())
            .collect::<Vec<_>>()
            .join(", "),
        None => config.bag.display().to_string(),
    };
    if config.curves.is_some() {
        let o = allan_imu_utils::run::run_curves(&config)
            .with_context(|| format!("analysing {what}"))?;
        for note in &o.notes {
            eprintln!("{note}");
        }
        let mut out = std::io::stdout().lock();
        out.write_all(o.stdout.as_bytes())
            .and_then(|_| out.write_all(o.ieee952_text.as_bytes()))
            .context("writing stdout")?;
        return Ok(());
    }
    let outcomes =
        allan_imu_utils::run::run(&config).with_context(|| format!("analysing {what}"))?;
    let several = outcomes.len() > 1;
    for outcome in &outcomes {
        let mut out = std::io::stdout().lock();
        if several {
            writeln!(out, "===== topic {} =====", outcome.topic).context("writing stdout")?;
        }
        for note in &outcome.notes {
            eprintln!("{note}");
        }
        out.write_all(outcome.stdout.as_bytes())
            .context("writing stdout")?;
        if let Some(t) = &outcome.ieee952_text {
            out.write_all(t.as_bytes()).context("writing stdout")?;
        }
        if config.timings {
            for (phase, d) in &outcome.timings {
                eprintln!("timing {phase} {:.3} s", d.as_secs_f64());
            }
        }
    }
    if config.timings {
        eprintln!("timing total {:.3} s", t.elapsed().as_secs_f64());
    }
    Ok(())
}
