//! `allan_imu_utils BAG [--topic imu] [--name imu] [--data-save-path DIR] [--max-time-min 120]
//! [--max-cluster 100] [--launch FILE.launch]`: imu_utils without ROS.

use std::process::ExitCode;

use clap::Parser;

use allan_imu_utils::cli::{Args, Config};
use bag2mat::shared::{cli, output};

const TOOL: &str = "allan_imu_utils";

/// Out of memory is reported as an error, not an abort.
#[global_allocator]
static ALLOC: bag2mat::shared::alloc::ExitOnOom = bag2mat::shared::alloc::ExitOnOom::new(TOOL);

fn main() -> ExitCode {
    bag2mat::shared::alloc::start_threads(TOOL);
    let t = std::time::Instant::now();
    let args = match Args::try_parse() {
        Ok(a) => a,
        Err(e) if !e.use_stderr() => {
            let _ = e.print();
            return ExitCode::SUCCESS;
        }
        Err(e) => return cli::usage(TOOL, &e.render().to_string()),
    };
    let config = match Config::try_from(args) {
        Ok(c) => c,
        Err(e) => return cli::usage(TOOL, &e.to_string()),
    };
    match &config.curves {
        Some(c) => c.paths.iter().for_each(|p| output::protect_input(p)),
        None => output::protect_input(&config.bag),
    }
    // Every output of the run, or none.
    let staging = output::Staging::begin();
    if config.curves.is_some() {
        let o = match allan_imu_utils::run::run_curves(&config).map_err(|e| e.to_string()) {
            Ok(o) => o,
            Err(e) => return cli::fail(TOOL, &e),
        };
        if let Err(e) = staging.commit() {
            return cli::fail(TOOL, &e);
        }
        for note in &o.notes {
            if note.to_ascii_lowercase().starts_with("warning") {
                eprintln!("{}", cli::warning_line(note));
            } else if !config.quiet {
                eprintln!("{note}");
            }
        }
        if let Err(e) = cli::print(&(o.stdout + &o.ieee952_text)) {
            return cli::fail(TOOL, &e);
        }
        return ExitCode::SUCCESS;
    }
    let outcomes = match allan_imu_utils::run::run(&config).map_err(|e| e.to_string()) {
        Ok(o) => o,
        Err(e) => return cli::fail(TOOL, &e),
    };
    if let Err(e) = staging.commit() {
        return cli::fail(TOOL, &e);
    }
    let several = outcomes.len() > 1;
    let mut printing = true;
    for outcome in &outcomes {
        let mut text = String::new();
        if several {
            text.push_str(&format!("===== topic {} =====\n", outcome.topic));
        }
        for note in &outcome.notes {
            eprintln!("{}", cli::warning_line(note));
        }
        // the record check's findings, always
        for f in &outcome.findings {
            eprintln!("{}", f.line(several.then_some(outcome.topic.as_str())));
        }
        text.push_str(&outcome.stdout);
        if let Some(t) = &outcome.ieee952_text {
            text.push_str(t);
        }
        if printing {
            match cli::print(&text) {
                Ok(more) => printing = more,
                Err(e) => return cli::fail(TOOL, &e),
            }
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
    ExitCode::SUCCESS
}
