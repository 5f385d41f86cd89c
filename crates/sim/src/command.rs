//! One `sim` command, run as the binary runs it: the pre-flight of a bag (refused before any
//! work when it cannot fit, its size said up front), the run, and what it prints.

use std::process::ExitCode;

use bag2mat::shared::output::Outputs;

use crate::cli::{BagArgs, Cli, Command, SplineArgs, TrajArgs};

/// Standard output through the workspace's one writer: a closed pipe (`| head`) ends the
/// printing quietly; a failed write is an error, not a panic.
fn out(text: &str) -> anyhow::Result<()> {
    bag2mat::shared::cli::print(text)
        .map(|_| ())
        .map_err(anyhow::Error::msg)
}

/// Runs the command the user typed and says what it did (stderr) and found (stdout); the
/// exit code is a failed `--check` or self-check's, errors come back once to the binary.
pub fn run(cli: Cli) -> anyhow::Result<ExitCode> {
    // Each file is put in place when complete: a bag is one file (or one directory's
    // rename), and the other commands' files stand alone.
    let outputs = Outputs::direct();
    match cli.command {
        Command::Bag(a) => run_bag(*a, &outputs)?,
        Command::Traj(a) => run_traj(a, &outputs)?,
        Command::Integrate(a) => {
            let cfg = crate::integrate::IntegrateConfig::try_from(a)?;
            let (table, files) = crate::integrate::run(&cfg, &outputs)?;
            out(&crate::integrate::format_table(&table))?;
            for f in files {
                eprintln!("wrote {}", f.display());
            }
        }
        Command::Compare(a) => {
            let cfg = crate::compare::CompareConfig::try_from(a)?;
            let (text, pass) = crate::compare::run(&cfg, &outputs)?;
            out(&text)?;
            if !pass {
                return Ok(ExitCode::FAILURE);
            }
        }
        Command::Sensors(a) => {
            if a.spec_example {
                out(crate::cli::SPEC_EXAMPLE)?;
            } else {
                crate::bag_sim::validate_rate(a.rate)?;
                out(&crate::noise::profiles::listing(a.rate))?;
            }
        }
        Command::Spline(a) => return run_spline(a, &outputs),
    }
    Ok(ExitCode::SUCCESS)
}

/// `sim bag`: refused before any work when it cannot fit, its size said up front, then the
/// run and what it wrote (stderr, unless quiet).
fn run_bag(a: BagArgs, outputs: &Outputs) -> anyhow::Result<()> {
    let cfg = crate::bag_sim::BagConfig::try_from(a)?;
    crate::bag_sim::validate(&cfg)?;
    crate::bag_sim::check_disk(&cfg)?;
    if !cfg.quiet {
        eprintln!(
            "writing about {} messages, about {:.1} MB",
            crate::bag_sim::estimated_messages(&cfg),
            crate::bag_sim::estimated_bytes(&cfg) as f64 * 1e-6
        );
        eprintln!("{}", crate::report::bag_header(&cfg));
        let n = crate::bag_sim::message_count(cfg.rate, cfg.duration) as usize;
        for w in crate::noise::truth_file::widrow_warnings(&cfg.model, cfg.rate, n)? {
            eprintln!("warning: {w}");
        }
    }
    let s = crate::bag_sim::run(&cfg, outputs)?;
    if !cfg.quiet {
        eprintln!("{}", crate::report::bag_done(&cfg, &s));
    }
    Ok(())
}

/// `sim traj`: the noise model, the run, and what it wrote (stderr).
fn run_traj(a: TrajArgs, outputs: &Outputs) -> anyhow::Result<()> {
    let cfg = crate::traj::TrajConfig::try_from(a)?;
    eprintln!("{}", cfg.noise.describe(cfg.rate));
    let s = crate::traj::run(&cfg, outputs)?;
    eprintln!(
        "wrote {} files into {} ({} IMU samples, {} camera frames, {} landmarks)",
        s.files,
        cfg.out_dir.display(),
        s.imu_samples,
        s.cam_frames,
        s.points
    );
    Ok(())
}

/// `sim spline`: the self-check (its verdict is the exit code), or the run and its summary.
fn run_spline(a: SplineArgs, outputs: &Outputs) -> anyhow::Result<ExitCode> {
    if a.self_check {
        let (text, pass) = crate::report::spline_self_check(a.pose_rate)?;
        out(&text)?;
        return Ok(if pass {
            ExitCode::SUCCESS
        } else {
            ExitCode::FAILURE
        });
    }
    let cfg = crate::spline_sim::SplineConfig::try_from(a)?;
    if let Some(n) = &cfg.noise {
        eprintln!("{}", n.describe(cfg.rate));
    }
    let s = crate::spline_sim::run(&cfg, outputs)?;
    out(&crate::report::spline_summary(&s))?;
    Ok(ExitCode::SUCCESS)
}
