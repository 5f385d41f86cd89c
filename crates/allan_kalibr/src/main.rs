//! `allan_kalibr INPUT [--update-rate HZ] [--topic T] [-o OUTDIR]`: kalibr_allan without
//! MATLAB; `allan_kalibr --curves PATH…` analyses Allan curves another tool wrote.

use std::process::ExitCode;

use clap::Parser;

use allan_kalibr::cli::Args;
use allan_kalibr::{Config, run, run_curves};
use bag2mat::shared::{cli, output};

const TOOL: &str = "allan_kalibr";

/// Out of memory is reported as an error, not an abort.
#[global_allocator]
static ALLOC: bag2mat::shared::alloc::ExitOnOom = bag2mat::shared::alloc::ExitOnOom::new(TOOL);

fn main() -> ExitCode {
    bag2mat::shared::alloc::start_threads(TOOL);
    let config: Config = match Args::try_parse() {
        Ok(a) => match a.curve_flags_need_curves() {
            Ok(()) => a.into(),
            Err(e) => return cli::usage(TOOL, &e),
        },
        Err(e) if !e.use_stderr() => {
            let _ = e.print();
            return ExitCode::SUCCESS;
        }
        Err(e) => return cli::usage(TOOL, &e.render().to_string()),
    };
    if let Some(curves) = &config.curves {
        for p in &curves.paths {
            output::protect_input(p);
        }
    } else {
        output::protect_input(&config.input);
    }
    // Every output of the run, or none.
    let staging = output::Staging::begin();
    if let Some(curves) = &config.curves {
        let out = match run_curves(&config, curves) {
            Ok(o) => o,
            Err(e) => return cli::fail(TOOL, &e),
        };
        if let Err(e) = staging.commit() {
            return cli::fail(TOOL, &e);
        }
        if let Err(e) = cli::print(&out.text) {
            return cli::fail(TOOL, &e);
        }
        if !config.quiet {
            for p in &out.written {
                eprintln!("wrote {}", p.display());
            }
        }
        return ExitCode::SUCCESS;
    }
    let outs = match run(&config) {
        Ok(o) => o,
        Err(e) => return cli::fail(TOOL, &e),
    };
    if let Err(e) = staging.commit() {
        return cli::fail(TOOL, &e);
    }
    let several = outs.len() > 1;
    let mut printing = true;
    for out in &outs {
        let mut text = String::new();
        if several {
            text.push_str(&format!(
                "===== topic {} =====\n",
                out.topic.as_deref().unwrap_or("?")
            ));
        }
        // The reader's warnings always, other notes (the estimated rate) only without
        // --quiet; then the record check's findings, always.
        for n in &out.notes {
            if n.to_ascii_lowercase().starts_with("warning") {
                eprintln!("{}", cli::warning_line(n));
            } else if !config.quiet {
                eprintln!("{n}");
            }
        }
        for f in &out.findings {
            eprintln!("{}", f.line(out.topic.as_deref().filter(|_| several)));
        }
        text.push_str(&out.text);
        if let Some(t) = &out.ieee952_text {
            text.push_str(t);
        }
        if printing {
            match cli::print(&text) {
                Ok(more) => printing = more,
                Err(e) => return cli::fail(TOOL, &e),
            }
        }
        if !config.quiet {
            for p in &out.written {
                eprintln!("wrote {}", p.display());
            }
        }
        if config.timings {
            eprintln!("{}", out.timings);
        }
    }
    ExitCode::SUCCESS
}
