//! `sim spline`: IMU data from a pose trajectory through a fitted split B-spline
//! (docs/upstream/vio_data_simulation.md §7.4). Inputs: a TUM file, or the analytic ellipse model's poses
//! (`--from-model`). Outputs: `imu_pose.txt` (spline pose + clean IMU, the 14-column layout
//! of the main simulator, full precision), `imu_pose_noise.txt` (with the §3 noise model)
//! and a bag (orientation = spline pose).

use crate::bag_sim::{BagSummary, ImuBagSink, now_ns};
use crate::error::{Result, SimError};
use crate::noise::{ContinuousNoise, NoiseGenerator};
use crate::rotation::quat_from_matrix;
use crate::spline::{Fit, FitReport, Pose, SplitSpline, knots_from_poses, model_poses};
use crate::textio::{NumFormat, PoseRow, format_pose_rows, format_tum, read_tum, write_string};
use bag2mat::shared::output::Outputs;
use bag2mat::{Compression, RosTime};
use std::path::{Path, PathBuf};

/// Where the poses come from.
#[derive(Debug, Clone)]
pub enum PoseSource {
    /// A TUM file `t tx ty tz qx qy qz qw`.
    Tum(PathBuf),
    /// The analytic ellipse model sampled at `rate` Hz on [0, `duration`] (t_j = j/rate).
    Model {
        /// Seconds.
        duration: f64,
        /// Hz.
        rate: f64,
    },
}

/// Settings of `sim spline`.
#[derive(Debug, Clone)]
pub struct SplineConfig {
    /// Pose input.
    pub source: PoseSource,
    /// Knot spacing (ns); default the median input spacing.
    pub knot_dt_ns: Option<i64>,
    /// Interpolating or approximating fit.
    pub fit: Fit,
    /// IMU output rate, Hz.
    pub rate: f64,
    /// Noise parameters; `None` = the noisy file equals the clean one.
    pub noise: Option<ContinuousNoise>,
    /// RNG seed.
    pub seed: u64,
    /// Output directory, or a `.bag` path (text files then go beside it).
    pub out: PathBuf,
    /// Bag topic.
    pub topic: String,
    /// Bag frame id.
    pub frame_id: String,
    /// Bag time of the first sample (ns); default: the pose times if they look absolute
    /// (≥ 1e9 s), otherwise now.
    pub start_ns: Option<u64>,
    /// Bag compression.
    pub compression: Compression,
    /// Emission window, ns (defaults: the spline's valid range).
    pub t_start_ns: Option<i64>,
    /// End of the emission window, ns.
    pub t_end_ns: Option<i64>,
    /// Gravity magnitude, m/s²: g_w = (0, 0, −gravity), so a level IMU at rest reads
    /// +gravity on z.
    pub gravity: f64,
    /// No progress bar.
    pub quiet: bool,
}

/// What `sim spline` did.
#[derive(Debug, Clone)]
pub struct SplineSummary {
    /// Number of input poses.
    pub poses: usize,
    /// Knots and spacing.
    pub knots: usize,
    /// Knot spacing, s.
    pub knot_dt: f64,
    /// True if the input had to be resampled onto a uniform grid.
    pub resampled: bool,
    /// The fit.
    pub fit: FitReport,
    /// IMU samples emitted.
    pub samples: usize,
    /// Files written.
    pub files: Vec<PathBuf>,
    /// The bag.
    pub bag: BagSummary,
    /// With `--from-model`: max gyro and acc error against the analytic model, ignoring 10
    /// knots at each end (rad/s, m/s²).
    pub model_error: Option<(f64, f64)>,
}

/// Knots trimmed at each end before comparing with the analytic model (the end conditions
/// ring for a few knots, decaying by 2 − √3 per knot; docs/upstream/vio_data_simulation.md §7.3 item 7).
pub const TRIM_KNOTS: i64 = 10;

/// Run `sim spline`: checks, fit, emission, text files, bag, truth.
/// Every file goes among `outputs`.
pub fn run(cfg: &SplineConfig, outputs: &Outputs) -> Result<SplineSummary> {
    if !(cfg.rate.is_finite() && cfg.rate > 0.0) {
        return Err(SimError::InvalidArgument(format!(
            "--rate must be positive, got {}",
            cfg.rate
        )));
    }
    let poses = read_poses(&cfg.source)?;
    let knots = knots_from_poses(&poses, cfg.knot_dt_ns)?;
    if !cfg.gravity.is_finite() {
        return Err(SimError::InvalidArgument(format!(
            "--gravity must be finite, got {}",
            cfg.gravity
        )));
    }
    let (spline, fit) = SplitSpline::fit(knots.t0_ns, knots.dt_ns, &knots.poses, cfg.fit)?;
    let spline = spline.with_gravity(nalgebra::Vector3::new(0.0, 0.0, -cfg.gravity));
    let (t_start, t_end) = emission_window(cfg, spline.range_ns())?;
    let (dir, bag_path) = output_paths(&cfg.out);
    std::fs::create_dir_all(&dir).map_err(|e| SimError::io(&dir, e))?;
    let emitted = emit(cfg, &spline, t_start, t_end);
    let mut files = write_text_files(outputs, cfg, &dir, &emitted, &poses)?;
    let bag = write_bag(outputs, cfg, &bag_path, &emitted.noisy, t_start)?;
    let truth = write_truth(outputs, cfg, &bag_path, emitted.noisy.len())?;
    files.push(bag_path);
    files.extend(truth);
    Ok(SplineSummary {
        poses: poses.len(),
        knots: knots.poses.len(),
        knot_dt: knots.dt_ns as f64 * 1e-9,
        resampled: knots.resampled,
        fit,
        samples: emitted.clean.len(),
        files,
        bag,
        model_error: emitted.model_error,
    })
}

/// The input poses: the TUM file, or the analytic model sampled (its duration and rate
/// checked).
fn read_poses(source: &PoseSource) -> Result<Vec<Pose>> {
    Ok(match source {
        PoseSource::Tum(p) => read_tum(p)?,
        PoseSource::Model { duration, rate } => {
            if !(*duration > 0.0 && *rate > 0.0) {
                return Err(SimError::InvalidArgument(
                    "--duration and --pose-rate must be positive".into(),
                ));
            }
            model_poses(*duration, *rate)
        }
    })
}

/// The emission window (ns): the configured one, by default the spline's valid range
/// `(a, b)`, which it must lie in.
fn emission_window(cfg: &SplineConfig, (a, b): (i64, i64)) -> Result<(i64, i64)> {
    let t_start = cfg.t_start_ns.unwrap_or(a);
    let t_end = cfg.t_end_ns.unwrap_or(b);
    if t_start < a || t_end > b || t_start > t_end {
        return Err(SimError::InvalidArgument(format!(
            "emission window [{:.9}, {:.9}] s is not inside the spline's valid range [{:.9}, {:.9}] s",
            t_start as f64 * 1e-9,
            t_end as f64 * 1e-9,
            a as f64 * 1e-9,
            b as f64 * 1e-9
        )));
    }
    Ok((t_start, t_end))
}

/// The text files' directory and the bag's path: `out` is the bag when it ends in `.bag`
/// (the text files beside it), else the directory of both (bag `imu.bag`).
fn output_paths(out: &Path) -> (PathBuf, PathBuf) {
    if out.extension().is_some_and(|e| e == "bag") {
        let d = out
            .parent()
            .filter(|p| !p.as_os_str().is_empty())
            .unwrap_or(Path::new("."))
            .to_path_buf();
        (d, out.to_path_buf())
    } else {
        (out.to_path_buf(), out.join("imu.bag"))
    }
}

/// The emitted samples, clean and with noise, and with `--from-model` the max gyro and acc
/// error against the analytic model.
struct Emitted {
    clean: Vec<PoseRow>,
    noisy: Vec<PoseRow>,
    model_error: Option<(f64, f64)>,
}

/// Samples the spline at t_k = t_start + round(k·1e9/rate) while ≤ t_end; the model error
/// ignores [`TRIM_KNOTS`] knots at each end of the valid range.
fn emit(cfg: &SplineConfig, spline: &SplitSpline, t_start: i64, t_end: i64) -> Emitted {
    let (a, b) = spline.range_ns();
    let mut clean = Vec::new();
    let mut noisy = Vec::new();
    let mut gen_noise = cfg
        .noise
        .map(|c| NoiseGenerator::new(c.discretize(1.0 / cfg.rate), cfg.seed));
    let mut model_err: Option<(f64, f64)> = None;
    let (ca, cb) = (
        a + TRIM_KNOTS * spline.dt_ns(),
        b - TRIM_KNOTS * spline.dt_ns(),
    );
    let mut k: i64 = 0;
    loop {
        let t = t_start + (k as f64 * 1e9 / cfg.rate).round() as i64;
        if t > t_end {
            break;
        }
        k += 1;
        let s = spline.sample(t);
        let row = PoseRow {
            t: t as f64 * 1e-9,
            q: quat_from_matrix(&s.r),
            p: s.p,
            gyro: s.gyro,
            acc: s.acc,
        };
        if matches!(cfg.source, PoseSource::Model { .. }) && (ca..=cb).contains(&t) {
            let m = crate::motion::ellipse(t as f64 * 1e-9);
            let e = model_err.get_or_insert((0.0, 0.0));
            e.0 = e.0.max((s.gyro - m.gyro).norm());
            e.1 = e.1.max((s.acc - m.acc).norm());
        }
        let mut nrow = row;
        if let Some(g) = gen_noise.as_mut() {
            let (mut gy, mut ac): ([f64; 3], [f64; 3]) = (row.gyro.into(), row.acc.into());
            g.apply(&mut gy, &mut ac);
            nrow.gyro = gy.into();
            nrow.acc = ac.into();
        }
        clean.push(row);
        noisy.push(nrow);
    }
    Emitted {
        clean,
        noisy,
        model_error: model_err,
    }
}

/// `imu_pose.txt`, `imu_pose_noise.txt` and with `--from-model` `model_poses.tum` into `dir`.
fn write_text_files(
    outputs: &Outputs,
    cfg: &SplineConfig,
    dir: &Path,
    emitted: &Emitted,
    poses: &[Pose],
) -> Result<Vec<PathBuf>> {
    let mut files = Vec::new();
    let p = dir.join("imu_pose.txt");
    write_string(
        outputs,
        &p,
        &format_pose_rows(&emitted.clean, NumFormat::Full),
    )?;
    files.push(p);
    let p = dir.join("imu_pose_noise.txt");
    write_string(
        outputs,
        &p,
        &format_pose_rows(&emitted.noisy, NumFormat::Full),
    )?;
    files.push(p);
    if let PoseSource::Model { .. } = cfg.source {
        let p = dir.join("model_poses.tum");
        let rows: Vec<_> = poses
            .iter()
            .map(|q| (q.t_ns as f64 * 1e-9, q.p, quat_from_matrix(&q.r)))
            .collect();
        write_string(outputs, &p, &format_tum(&rows, 9, 9))?;
        files.push(p);
    }
    Ok(files)
}

/// The bag of the noisy IMU, record time = stamp: sample i at t_start + round(i·1e9/rate),
/// shifted to `--start-time`, kept if already absolute (≥ 1e9 s), else to now.
fn write_bag(
    outputs: &Outputs,
    cfg: &SplineConfig,
    bag_path: &Path,
    noisy: &[PoseRow],
    t_start: i64,
) -> Result<BagSummary> {
    let offset: i64 = match cfg.start_ns {
        Some(s) => s as i64 - t_start,
        None if t_start >= 1_000_000_000_000_000_000 => 0,
        None => now_ns() as i64 - t_start,
    };
    let pb = bag2mat::shared::progress::bar(noisy.len() as u64, cfg.quiet, "msgs");
    let mut sink = ImuBagSink::create(
        outputs,
        bag_path,
        cfg.compression,
        &cfg.topic,
        &cfg.frame_id,
    )?;
    for (i, r) in noisy.iter().enumerate() {
        let t_ns = t_start + (i as f64 * 1e9 / cfg.rate).round() as i64 + offset;
        if t_ns < 0 {
            return Err(SimError::InvalidArgument(
                "bag time before the UNIX epoch; give --start-time".into(),
            ));
        }
        sink.push(
            RosTime::from_nanos(t_ns as u64),
            [r.q[1], r.q[2], r.q[3], r.q[0]],
            r.gyro.into(),
            r.acc.into(),
        )?;
        pb.inc(1);
    }
    let bag = sink.finish()?;
    pb.finish_and_clear();
    Ok(bag)
}

/// The truth beside the bag: the noise model (zero with --no-noise) and its Allan deviation.
fn write_truth(
    outputs: &Outputs,
    cfg: &SplineConfig,
    bag_path: &Path,
    samples: usize,
) -> Result<[PathBuf; 2]> {
    let model = crate::noise::model::ImuModel::from_continuous(
        if cfg.noise.is_some() {
            "spline"
        } else {
            "spline (no noise)"
        },
        &cfg.noise.unwrap_or(ContinuousNoise::ZERO),
    );
    crate::noise::truth_file::write(
        outputs,
        &crate::noise::truth_file::TruthInfo {
            bag: bag_path,
            model: &model,
            rate: cfg.rate,
            samples,
            seed: cfg.seed,
            motion: "spline",
        },
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::spline::{SELF_CHECK_ACC_TOL, SELF_CHECK_GYRO_TOL};

    #[test]
    fn nine_decimal_tum_round_trip_still_meets_the_self_check_limits() {
        // docs/upstream/vio_data_simulation.md §7.5: the self-check via a 9-decimal TUM file gives 7.2e-7 rad/s and
        // 3.6e-4 m/s² (input quantisation amplified ~1/Δt²) — still within the limits.
        let d = tempfile::tempdir().unwrap();
        let poses = model_poses(20.0, 200.0);
        let rows: Vec<_> = poses
            .iter()
            .map(|p| (p.t_ns as f64 * 1e-9, p.p, quat_from_matrix(&p.r)))
            .collect();
        let path = d.path().join("m.tum");
        write_string(&Outputs::direct(), &path, &format_tum(&rows, 9, 9)).unwrap();
        let cfg = SplineConfig {
            source: PoseSource::Tum(path),
            knot_dt_ns: None,
            fit: Fit::Interp,
            rate: 400.0,
            noise: None,
            seed: 1,
            out: d.path().join("out"),
            topic: "imu".into(),
            frame_id: "base_link".into(),
            start_ns: Some(1_700_000_000_000_000_000),
            compression: Compression::None,
            t_start_ns: None,
            t_end_ns: None,
            gravity: crate::spline::GRAVITY,
            quiet: true,
        };
        let s = run(&cfg, &Outputs::direct()).unwrap();
        assert_eq!(s.samples, 8001);
        let clean = crate::textio::read_pose_rows(&d.path().join("out/imu_pose.txt")).unwrap();
        let (mut mg, mut ma) = (0.0f64, 0.0f64);
        for r in clean.iter().filter(|r| r.t >= 0.05 && r.t <= 19.95) {
            let m = crate::motion::ellipse(r.t);
            mg = mg.max((r.gyro - m.gyro).norm());
            ma = ma.max((r.acc - m.acc).norm());
        }
        eprintln!(
            "9-decimal TUM round trip: max gyro err {mg:.3e} rad/s, max acc err {ma:.3e} m/s^2"
        );
        assert!(mg <= SELF_CHECK_GYRO_TOL, "gyro err {mg:.3e}");
        assert!(ma <= SELF_CHECK_ACC_TOL, "acc err {ma:.3e}");
        // Quantisation must show: far above the in-memory 1.5e-10 rad/s.
        assert!(
            mg > 1e-8,
            "gyro err {mg:.3e} suspiciously small for 9-decimal input"
        );
    }
}
