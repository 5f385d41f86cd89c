//! `sim` binary: parse the command line, run the library, report errors once.

use clap::Parser;
use sim::cli::{Cli, Command};
use std::process::ExitCode;

const TOOL: &str = "sim";

/// Out of memory is reported as an error, not an abort.
#[global_allocator]
static ALLOC: bag2mat::shared::alloc::ExitOnOom = bag2mat::shared::alloc::ExitOnOom::new(TOOL);

fn main() -> ExitCode {
    bag2mat::shared::alloc::start_threads(TOOL);
    let cli = match Cli::try_parse() {
        Ok(c) => c,
        // No subcommand: say so in one line (clap's message would be the whole description).
        Err(e) if e.kind() == clap::error::ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand => {
            return bag2mat::shared::cli::usage(
                TOOL,
                "a command is required: bag, traj, integrate, spline, compare or sensors (`sim --help` says what each does)\n\nUsage: sim <COMMAND>",
            );
        }
        Err(e) if !e.use_stderr() => {
            let _ = e.print();
            return ExitCode::SUCCESS;
        }
        Err(e) => return bag2mat::shared::cli::usage(TOOL, &e.render().to_string()),
    };
    match run(cli) {
        Ok(code) => code,
        // What the user typed cannot be run: a usage error (exit 2).
        Err(e)
            if matches!(
                e.downcast_ref::<sim::error::SimError>(),
                Some(sim::error::SimError::InvalidArgument(_))
            ) =>
        {
            bag2mat::shared::cli::usage(TOOL, &format!("{e:#}"))
        }
        Err(e) => bag2mat::shared::cli::fail(TOOL, &format!("{e:#}")),
    }
}

/// Standard output through the workspace's one writer: a closed pipe (`| head`) ends the
/// printing quietly; a failed write is an error, not a panic.
fn out(text: &str) -> anyhow::Result<()> {
    bag2mat::shared::cli::print(text)
        .map(|_| ())
        .map_err(anyhow::Error::msg)
}

fn run(cli: Cli) -> anyhow::Result<ExitCode> {
    match cli.command {
        Command::Bag(a) => {
            let cfg = sim::bag_sim::BagConfig::try_from(*a)?;
            // Refused before any work when it cannot fit; its size said up front.
            sim::bag_sim::validate(&cfg)?;
            sim::bag_sim::check_disk(&cfg)?;
            if !cfg.quiet {
                eprintln!(
                    "writing about {} messages, about {:.1} MB",
                    sim::bag_sim::estimated_messages(&cfg),
                    sim::bag_sim::estimated_bytes(&cfg) as f64 * 1e-6
                );
                eprintln!("{}", sim::report::bag_header(&cfg));
                let n = sim::bag_sim::message_count(cfg.rate, cfg.duration) as usize;
                for w in sim::noise::truth_file::widrow_warnings(&cfg.model, cfg.rate, n)? {
                    eprintln!("warning: {w}");
                }
            }
            let s = sim::bag_sim::run(&cfg)?;
            if !cfg.quiet {
                eprintln!("{}", sim::report::bag_done(&cfg, &s));
            }
        }
        Command::Traj(a) => {
            let cfg = sim::traj::TrajConfig::try_from(a)?;
            eprintln!("{}", cfg.noise.describe(cfg.rate));
            let s = sim::traj::run(&cfg)?;
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
            out(&sim::integrate::format_table(&table))?;
            for f in files {
                eprintln!("wrote {}", f.display());
            }
        }
        Command::Compare(a) => {
            let cfg = sim::compare::CompareConfig::try_from(a)?;
            let (text, pass) = sim::compare::run(&cfg)?;
            out(&text)?;
            if !pass {
                return Ok(ExitCode::FAILURE);
            }
        }
        Command::Sensors(a) => {
            if a.spec_example {
                out(sim::cli_model::SPEC_EXAMPLE)?;
            } else {
                sim::bag_sim::validate_rate(a.rate)?;
                out(&sim::noise::profiles::listing(a.rate))?;
            }
        }
        Command::Spline(a) => {
            if a.self_check {
                let (text, pass) = sim::report::spline_self_check(a.pose_rate)?;
                out(&text)?;
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
            out(&sim::report::spline_summary(&s))?;
        }
    }
    Ok(ExitCode::SUCCESS)
}
