//! `sim` binary: parse the command line, run the library, report errors once.

use anyhow::Context;
use clap::Parser;
use sim::cli::{Cli, Command};
use std::process::ExitCode;

fn main() -> ExitCode {
    match run(Cli::parse()) {
        Ok(code) => code,
        Err(e) => {
            eprintln!("sim: error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

fn run(cli: Cli) -> anyhow::Result<ExitCode> {
    match cli.command {
        Command::Bag(a) => {
            let cfg = sim::bag_sim::BagConfig::try_from(*a)?;
            if !cfg.quiet {
                eprintln!("{}", sim::report::bag_header(&cfg));
                let n = sim::bag_sim::message_count(cfg.rate, cfg.duration) as usize;
                for w in sim::noise::truth_file::widrow_warnings(&cfg.model, cfg.rate, n)? {
                    eprintln!("warning: {w}");
                }
            }
            let s = sim::bag_sim::run(&cfg)
                .with_context(|| format!("writing {}", cfg.out.display()))?;
            if !cfg.quiet {
                eprintln!("{}", sim::report::bag_done(&cfg, &s));
            }
        }
        Command::Traj(a) => {
            let cfg = sim::traj::TrajConfig::try_from(a)?;
            eprintln!("{}", cfg.noise.describe(cfg.rate));
            let s = sim::traj::run(&cfg)
                .with_context(|| format!("writing into {}", cfg.out_dir.display()))?;
            eprintln!(
                "wrote {} files into {} ({} IMU samples, {} camera frames, {} landmarks)",
                s.files,
                cfg.out_dir.display(),
                s.imu_samples,
                s.cam_frames,
                s.points
            );
        }
        Command::Integrate(a) => {
            let cfg = sim::integrate::IntegrateConfig::try_from(a)?;
            let (table, files) = sim::integrate::run(&cfg)?;
            print!("{}", sim::integrate::format_table(&table));
            for f in files {
                eprintln!("wrote {}", f.display());
            }
        }
        Command::Compare(a) => {
            let cfg = sim::compare::CompareConfig::try_from(a)?;
            if !sim::compare::run(&cfg)? {
                return Ok(ExitCode::FAILURE);
            }
        }
        Command::Sensors(a) => {
            if a.spec_example {
                print!("{}", sim::cli_model::SPEC_EXAMPLE);
            } else {
                sim::bag_sim::validate_rate(a.rate)?;
                print!("{}", sim::noise::profiles::listing(a.rate));
            }
        }
        Command::Spline(a) => {
            if a.self_check {
                let (text, pass) = sim::report::spline_self_check(a.pose_rate)?;
                print!("{text}");
                return Ok(if pass {
                    ExitCode::SUCCESS
                } else {
                    ExitCode::FAILURE
                });
            }
            let cfg = sim::spline_sim::SplineConfig::try_from(a)?;
            if let Some(n) = &cfg.noise {
                eprintln!("{}", n.describe(cfg.rate));
            }
            let s = sim::spline_sim::run(&cfg)?;
            print!("{}", sim::report::spline_summary(&s));
        }
    }
    Ok(ExitCode::SUCCESS)
}
