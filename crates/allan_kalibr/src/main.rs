//! `allan_kalibr`: parses the command line and runs the library; see `allan_kalibr::cli`.

use std::process::ExitCode;

use anyhow::Context;
use clap::Parser;

use allan_kalibr::cli::Args;
use allan_kalibr::{Config, run};

fn main() -> ExitCode {
    let config: Config = Args::parse().into();
    match run(&config).with_context(|| format!("allan_kalibr {}", config.input.display())) {
        Ok(out) => {
            for n in &out.notes {
                eprintln!("{n}");
            }
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
    }
}
