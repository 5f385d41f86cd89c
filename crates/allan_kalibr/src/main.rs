//! `allan_kalibr`: parses the command line and runs the library; see `allan_kalibr::cli`.

use std::process::ExitCode;

use anyhow::Context;
use clap::Parser;

use allan_kalibr::cli::Args;
use allan_kalibr::{Config, run, run_curves};

fn main() -> ExitCode {
    let config: Config = Args::parse().into();
    if let Some(curves) = &config.curves {
        return match run_curves(&config, curves)
            .map_err(|e| anyhow::anyhow!("{e}"))
            .context("allan_kalibr --curves")
        {
            Ok(out) => {
                print!("{}", out.text);
                for p in &out.written {
                    eprintln!("wrote {}", p.display());
                }
                ExitCode::SUCCESS
            }
            Err(e) => {
                eprintln!("error: {e:#}");
                ExitCode::FAILURE
            }
        };
    }
    // The library's messages already carry their causes inline, so the error is flattened to
    // its text before the context is added (printing the cause chain would repeat them).
    let result = run(&config)
        .map_err(|e| anyhow::anyhow!("{e}"))
        .with_context(|| format!("allan_kalibr {}", config.input.display()));
    match result {
        Ok(outs) => {
            let several = outs.len() > 1;
            for out in &outs {
                if several {
                    println!("===== topic {} =====", out.topic.as_deref().unwrap_or("?"));
                }
                for n in &out.notes {
                    eprintln!("{n}");
                }
                print!("{}", out.text);
                if let Some(t) = &out.ieee952_text {
                    print!("{t}");
                }
                for p in &out.written {
                    eprintln!("wrote {}", p.display());
                }
                if config.timings {
                    eprintln!("{}", out.timings);
                }
            }
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}
