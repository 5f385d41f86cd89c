//! `sim traj`: the text files of vio_data_simulation `master` (docs/upstream/vio_data_simulation.md §5) from the analytic
//! ellipse model — IMU poses (clean and noisy), camera poses (14-column and TUM), the house
//! landmarks and the per-frame observations in normalised image coordinates.
//!
//! Differences from upstream: f64 model constants by default (see [`crate::motion`]; with
//! `--compat` the float constants are emulated and the clean files match upstream byte for
//! byte); the unused gyro/acc
//! columns of `cam_pose.txt` (uninitialised memory upstream) are written as 0; the noise
//! comes from a seeded generator. Additional file: `imu_pose_tum.txt` (IMU poses, TUM layout
//! with 9 decimals — a suitable `sim spline --poses` input, unlike the 5-decimal camera file).

use crate::error::{Result, SimError};
use crate::grid::Grid;
use crate::integrate::model_rows;
use crate::motion::{Mode, ellipse_with};
use crate::noise::{ContinuousNoise, NoiseGenerator};
use crate::rotation::quat_from_matrix;
use crate::textio::{NumFormat, PoseRow, format_pose_rows, format_tum, write_string};
use bag2mat::shared::cfmt::push_g;
use bag2mat::shared::output::Outputs;
use nalgebra::{Matrix3, Vector3};
use std::path::{Path, PathBuf};

/// Settings of `sim traj`.
#[derive(Debug, Clone)]
pub struct TrajConfig {
    /// Output directory (created if missing).
    pub out_dir: PathBuf,
    /// Duration, s (upstream 20).
    pub duration: f64,
    /// IMU rate, Hz (upstream 200).
    pub rate: f64,
    /// Camera rate, Hz (upstream 30).
    pub cam_rate: f64,
    /// Continuous-time noise parameters.
    pub noise: ContinuousNoise,
    /// RNG seed.
    pub seed: u64,
    /// Time grid (upstream: `float` accumulation).
    pub grid: Grid,
    /// Model constants.
    pub mode: Mode,
}

/// The house model of upstream `bin/house_model/house.txt`: 23 segments (x0 y0 z0 x1 y1 z1,
/// metres) — a 10×10 m house, walls to 6.5 m, roof to 10 m, a door and a window.
pub const HOUSE_SEGMENTS: [[f64; 6]; 23] = [
    [0., 0., 0., 0., 0., 6.5],
    [10., 0., 0., 10., 0., 6.5],
    [10., 10., 0., 10., 10., 6.5],
    [0., 10., 0., 0., 10., 6.5],
    [0., 0., 0., 10., 0., 0.],
    [10., 0., 0., 10., 10., 0.],
    [10., 10., 0., 0., 10., 0.],
    [0., 10., 0., 0., 0., 0.],
    [0., 0., 6.5, 0., 5., 10.],
    [0., 5., 10., 0., 10., 6.5],
    [10., 0., 6.5, 10., 5., 10.],
    [10., 5., 10., 10., 10., 6.5],
    [0., 5., 10., 10., 5., 10.],
    [0., 0., 6.5, 10., 0., 6.5],
    [0., 10., 6.5, 10., 10., 6.5],
    [0., 6., 0., 0., 8., 0.],
    [0., 8., 0., 0., 8., 5.],
    [0., 8., 5., 0., 6., 5.],
    [0., 6., 5., 0., 6., 0.],
    [0., 2., 2.5, 0., 4., 2.5],
    [0., 4., 2.5, 0., 4., 5.],
    [0., 4., 5., 0., 2., 5.],
    [0., 2., 5., 0., 2., 2.5],
];

/// Camera axes in the body frame (upstream `param.cpp` `R_bc`): cam-z = −body-x.
pub fn r_bc() -> Matrix3<f64> {
    Matrix3::new(0., 0., -1., -1., 0., 0., 0., 1., 0.)
}

/// Camera origin in the body frame, m (upstream `t_bc`).
pub const T_BC: Vector3<f64> = Vector3::new(0.05, 0.04, 0.03);

/// A landmark line segment (two endpoints, world, m).
pub type Segment = (Vector3<f64>, Vector3<f64>);

/// Landmark points and lines as upstream `CreatePointsLines` builds them: segment endpoints
/// de-duplicated by exact equality in first-seen order (18), then each point repeated with
/// offset (+0.5, +0.5, −0.5) (36 in all); lines = all 23 segments.
pub fn landmarks() -> (Vec<Vector3<f64>>, Vec<Segment>) {
    let mut points: Vec<Vector3<f64>> = Vec::new();
    let mut lines = Vec::new();
    for s in HOUSE_SEGMENTS {
        let a = Vector3::new(s[0], s[1], s[2]);
        let b = Vector3::new(s[3], s[4], s[5]);
        for p in [a, b] {
            if !points.contains(&p) {
                points.push(p);
            }
        }
        lines.push((a, b));
    }
    let n = points.len();
    for j in 0..n {
        points.push(points[j] + Vector3::new(0.5, 0.5, -0.5));
    }
    (points, lines)
}

/// One camera frame: time, R_wc, t_wc.
#[derive(Debug, Clone, Copy)]
pub struct CamFrame {
    /// Time, s.
    pub t: f64,
    /// Camera → world rotation.
    pub r_wc: Matrix3<f64>,
    /// Camera origin in world, m.
    pub t_wc: Vector3<f64>,
}

/// Camera frames: R_wc = R_wb·R_bc, t_wc = t_wb + R_wb·t_bc.
pub fn cam_frames(grid: Grid, mode: Mode, duration: f64, cam_rate: f64) -> Vec<CamFrame> {
    let rbc = r_bc();
    grid.times(duration, cam_rate)
        .map(|t| {
            let m = ellipse_with(t, mode);
            CamFrame {
                t,
                r_wc: m.r_wb * rbc,
                t_wc: m.p + m.r_wb * T_BC,
            }
        })
        .collect()
}

/// Point in the camera frame; `None` if behind the camera (upstream skips z < 0).
fn to_cam(f: &CamFrame, pw: &Vector3<f64>) -> Option<Vector3<f64>> {
    let pc = f.r_wc.transpose() * (pw - f.t_wc);
    (pc.z >= 0.0).then_some(pc)
}

/// What [`run`] wrote.
#[derive(Debug, Clone)]
pub struct TrajSummary {
    /// IMU samples.
    pub imu_samples: usize,
    /// Camera frames.
    pub cam_frames: usize,
    /// Landmark points.
    pub points: usize,
    /// Files written.
    pub files: usize,
}

fn g_line(out: &mut String, vals: &[f64], trailing_space: bool) {
    for (i, v) in vals.iter().enumerate() {
        if i > 0 {
            out.push(' ');
        }
        push_g(out, *v, 6);
    }
    if trailing_space {
        out.push(' ');
    }
    out.push('\n');
}

/// `all_points.txt`: every landmark point as `x y z 1`.
fn points_text(points: &[Vector3<f64>]) -> String {
    let mut s = String::new();
    for p in points {
        g_line(&mut s, &[p.x, p.y, p.z, 1.0], false);
    }
    s
}

/// The camera frames as pose rows (the gyro/acc columns 0: uninitialised upstream).
fn cam_pose_rows(frames: &[CamFrame]) -> Vec<PoseRow> {
    frames
        .iter()
        .map(|f| PoseRow {
            t: f.t,
            q: quat_from_matrix(&f.r_wc),
            p: f.t_wc,
            gyro: Vector3::zeros(),
            acc: Vector3::zeros(),
        })
        .collect()
}

/// `keyframe/all_points_<n>.txt`: each point in front of camera `f`, world coordinates and
/// normalised image coordinates (x/z, y/z), no intrinsics or bounds (upstream).
fn frame_points_text(f: &CamFrame, points: &[Vector3<f64>]) -> String {
    let mut s = String::new();
    for p in points {
        if let Some(c) = to_cam(f, p) {
            g_line(&mut s, &[p.x, p.y, p.z, 1.0, c.x / c.z, c.y / c.z], true);
        }
    }
    s
}

/// `keyframe/all_lines_<n>.txt`: each line with both ends in front of camera `f`, its ends
/// in normalised image coordinates.
fn frame_lines_text(f: &CamFrame, lines: &[Segment]) -> String {
    let mut s = String::new();
    for (a, b) in lines {
        if let (Some(c1), Some(c2)) = (to_cam(f, a), to_cam(f, b)) {
            g_line(
                &mut s,
                &[c1.x / c1.z, c1.y / c1.z, c2.x / c2.z, c2.y / c2.z],
                true,
            );
        }
    }
    s
}

/// Write every file of `sim traj` into `cfg.out_dir`: the upstream `master` file writer top
/// to bottom, one block per file.
/// Every file goes among `outputs`.
pub fn run(cfg: &TrajConfig, outputs: &Outputs) -> Result<TrajSummary> {
    if !(cfg.duration > 0.0 && cfg.rate > 0.0 && cfg.cam_rate > 0.0) {
        return Err(SimError::InvalidArgument(
            "duration, rate and cam-rate must be positive".into(),
        ));
    }
    let dir = &cfg.out_dir;
    let kf = dir.join("keyframe");
    std::fs::create_dir_all(&kf).map_err(|e| SimError::io(&kf, e))?;
    let mut files = 0;
    let mut write = |name: &Path, s: &str| -> Result<()> {
        files += 1;
        write_string(outputs, name, s)
    };

    // Landmarks.
    let (points, lines) = landmarks();
    write(&dir.join("all_points.txt"), &points_text(&points))?;

    // IMU.
    let truth = model_rows(cfg.grid, cfg.mode, cfg.duration, cfg.rate, None);
    let mut noise_gen = NoiseGenerator::new(cfg.noise.discretize(1.0 / cfg.rate), cfg.seed);
    let noisy = model_rows(
        cfg.grid,
        cfg.mode,
        cfg.duration,
        cfg.rate,
        Some(&mut noise_gen),
    );
    write(
        &dir.join("imu_pose.txt"),
        &format_pose_rows(&truth, NumFormat::CppG),
    )?;
    write(
        &dir.join("imu_pose_noise.txt"),
        &format_pose_rows(&noisy, NumFormat::CppG),
    )?;
    let tum: Vec<_> = truth.iter().map(|r| (r.t, r.p, r.q)).collect();
    write(&dir.join("imu_pose_tum.txt"), &format_tum(&tum, 9, 9))?;

    // Cameras.
    let frames = cam_frames(cfg.grid, cfg.mode, cfg.duration, cfg.cam_rate);
    let cam_rows = cam_pose_rows(&frames);
    write(
        &dir.join("cam_pose.txt"),
        &format_pose_rows(&cam_rows, NumFormat::CppG),
    )?;
    let tum: Vec<_> = cam_rows.iter().map(|r| (r.t, r.p, r.q)).collect();
    write(&dir.join("cam_pose_tum.txt"), &format_tum(&tum, 9, 5))?;

    // Observations.
    for (n, f) in frames.iter().enumerate() {
        write(
            &kf.join(format!("all_points_{n}.txt")),
            &frame_points_text(f, &points),
        )?;
        write(
            &kf.join(format!("all_lines_{n}.txt")),
            &frame_lines_text(f, &lines),
        )?;
    }
    Ok(TrajSummary {
        imu_samples: truth.len(),
        cam_frames: frames.len(),
        points: points.len(),
        files,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn landmark_counts() {
        let (p, l) = landmarks();
        assert_eq!((p.len(), l.len()), (36, 23));
        assert_eq!(p[18], Vector3::new(0.5, 0.5, -0.5));
    }

    #[test]
    fn camera_looks_inward_and_sees_the_house() {
        // Cam-z = −body-x; at t = 0 the body x axis points away from the ellipse centre, so
        // the house (centred near (5, 5)) is in front of the camera.
        let f = &cam_frames(Grid::AccumulatedF32, Mode::Double, 20.0, 30.0)[0];
        let (points, _) = landmarks();
        let visible = points.iter().filter(|p| to_cam(f, p).is_some()).count();
        assert_eq!(visible, points.len(), "all landmarks in front at t = 0");
        assert_eq!(
            cam_frames(Grid::AccumulatedF32, Mode::Double, 20.0, 30.0).len(),
            600
        );
    }
}
