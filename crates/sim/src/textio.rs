//! The upstream text layouts (docs/upstream/vio_data_simulation.md §5), read and written. Writers go
//! through bag2mat's atomic file helper; numbers use [`bag2mat::shared::cfmt`] for upstream parity
//! (`%g`, 6 significant digits) or the shortest round-trip form for full precision.

use crate::error::{Result, SimError};
use crate::rotation::matrix_from_quat;
use crate::spline::Pose;
use bag2mat::shared::cfmt::push_g;
use bag2mat::shared::output::Outputs;
use nalgebra::Vector3;
use std::fmt::Write as _;
use std::path::Path;

/// How numbers are printed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NumFormat {
    /// C++ ostream default (`%g`, 6 significant digits) — upstream parity.
    CppG,
    /// Shortest representation that reads back to the same f64.
    Full,
}

fn push(out: &mut String, x: f64, f: NumFormat) {
    match f {
        NumFormat::CppG => push_g(out, x, 6),
        NumFormat::Full => {
            let _ = write!(out, "{x:?}");
        }
    }
}

/// One row of `imu_pose.txt`: `t qw qx qy qz px py pz gx gy gz ax ay az`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PoseRow {
    /// Time, s.
    pub t: f64,
    /// Quaternion body → world `[w, x, y, z]` (signs as written).
    pub q: [f64; 4],
    /// Position, m.
    pub p: Vector3<f64>,
    /// Gyro, rad/s.
    pub gyro: Vector3<f64>,
    /// Acc (specific force), m/s².
    pub acc: Vector3<f64>,
}

/// Write a file atomically from a string, among the run's `outputs`.
pub fn write_string(outputs: &Outputs, path: &Path, s: &str) -> Result<()> {
    outputs.write_atomic(path, |w| w.write_all(s.as_bytes()))?;
    Ok(())
}

/// `imu_pose.txt` / `imu_pose_noise.txt` / `cam_pose.txt` layout (14 columns, each value
/// followed by a space — upstream `save_Pose`).
pub fn format_pose_rows(rows: &[PoseRow], f: NumFormat) -> String {
    let mut s = String::with_capacity(rows.len() * 160);
    for r in rows {
        let vals = [
            r.t, r.q[0], r.q[1], r.q[2], r.q[3], r.p.x, r.p.y, r.p.z, r.gyro.x, r.gyro.y, r.gyro.z,
            r.acc.x, r.acc.y, r.acc.z,
        ];
        for v in vals {
            push(&mut s, v, f);
            s.push(' ');
        }
        s.push('\n');
    }
    s
}

/// `imu_int_pose*.txt` layout: `t qw qx qy qz px py pz` twice (15 columns, trailing space —
/// upstream `testImu`: "imu stored twice since no cam").
pub fn format_int_rows(rows: &[(f64, [f64; 4], Vector3<f64>)], f: NumFormat) -> String {
    let mut s = String::with_capacity(rows.len() * 170);
    for (t, q, p) in rows {
        push(&mut s, *t, f);
        s.push(' ');
        for _ in 0..2 {
            for v in [q[0], q[1], q[2], q[3], p.x, p.y, p.z] {
                push(&mut s, v, f);
                s.push(' ');
            }
        }
        s.push('\n');
    }
    s
}

/// TUM layout `t tx ty tz qx qy qz qw`, fixed decimals, no trailing space (upstream
/// `save_Pose_asTUM` uses 9 and 5 decimals).
pub fn format_tum(
    rows: &[(f64, Vector3<f64>, [f64; 4])],
    t_decimals: usize,
    decimals: usize,
) -> String {
    let mut s = String::with_capacity(rows.len() * 100);
    for (t, p, q) in rows {
        let _ = writeln!(
            s,
            "{t:.td$} {:.d$} {:.d$} {:.d$} {:.d$} {:.d$} {:.d$} {:.d$}",
            p.x,
            p.y,
            p.z,
            q[1],
            q[2],
            q[3],
            q[0],
            td = t_decimals,
            d = decimals
        );
    }
    s
}

fn read_to_string(path: &Path) -> Result<String> {
    std::fs::read_to_string(path).map_err(|e| SimError::io(path, e))
}

fn parse_fields(path: &Path, line_no: usize, line: &str, n: usize) -> Result<Vec<f64>> {
    let v: std::result::Result<Vec<f64>, _> =
        line.split_whitespace().map(str::parse::<f64>).collect();
    let v = v.map_err(|e| SimError::Parse {
        path: path.into(),
        line: line_no,
        msg: format!("not a number ({e})"),
    })?;
    if v.len() < n {
        return Err(SimError::Parse {
            path: path.into(),
            line: line_no,
            msg: format!("expected {n} columns, found {}", v.len()),
        });
    }
    Ok(v)
}

/// Read a 14-column `imu_pose.txt`-style file (upstream `LoadPose`; blank lines skipped).
pub fn read_pose_rows(path: &Path) -> Result<Vec<PoseRow>> {
    let text = read_to_string(path)?;
    let mut rows = Vec::new();
    for (i, line) in text.lines().enumerate() {
        if line.trim().is_empty() || line.trim_start().starts_with('#') {
            continue;
        }
        let v = parse_fields(path, i + 1, line, 14)?;
        rows.push(PoseRow {
            t: v[0],
            q: [v[1], v[2], v[3], v[4]],
            p: Vector3::new(v[5], v[6], v[7]),
            gyro: Vector3::new(v[8], v[9], v[10]),
            acc: Vector3::new(v[11], v[12], v[13]),
        });
    }
    if rows.len() < 2 {
        return Err(SimError::Parse {
            path: path.into(),
            line: 0,
            msg: format!("need at least 2 rows, found {}", rows.len()),
        });
    }
    Ok(rows)
}

/// Parse a decimal time in seconds into integer nanoseconds exactly (no f64 rounding for
/// plain decimals; exponent forms go through f64).
pub(crate) fn parse_time_ns(s: &str) -> Option<i64> {
    let s = s.trim();
    if s.contains(['e', 'E']) {
        let x: f64 = s.parse().ok()?;
        return x.is_finite().then(|| (x * 1e9).round() as i64);
    }
    let (neg, body) = match s.strip_prefix('-') {
        Some(b) => (true, b),
        None => (false, s.strip_prefix('+').unwrap_or(s)),
    };
    let (int, frac) = body.split_once('.').unwrap_or((body, ""));
    if (int.is_empty() && frac.is_empty())
        || !int.bytes().all(|b| b.is_ascii_digit())
        || !frac.bytes().all(|b| b.is_ascii_digit())
    {
        return None;
    }
    let whole: i64 = if int.is_empty() { 0 } else { int.parse().ok()? };
    let mut ns: i64 = 0;
    let digits = frac.as_bytes();
    for k in 0..9 {
        ns = ns * 10 + digits.get(k).map_or(0, |d| (d - b'0') as i64);
    }
    // Round half up on the 10th digit.
    if digits.get(9).is_some_and(|d| *d >= b'5') {
        ns += 1;
    }
    let v = whole.checked_mul(1_000_000_000)?.checked_add(ns)?;
    Some(if neg { -v } else { v })
}

/// Maximum allowed deviation of an input quaternion's norm from 1 (docs/upstream/vio_data_simulation.md §7.4 item 1).
pub const TUM_QUAT_NORM_TOL: f64 = 1e-3;

/// Read a TUM trajectory `t tx ty tz qx qy qz qw` (`#` comments, any whitespace).
pub fn read_tum(path: &Path) -> Result<Vec<Pose>> {
    let text = read_to_string(path)?;
    let mut out = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let err = |msg: String| SimError::Parse {
            path: path.into(),
            line: i + 1,
            msg,
        };
        let mut it = line.split_whitespace();
        let t = it.next().ok_or_else(|| err("empty line".into()))?;
        let t_ns = parse_time_ns(t).ok_or_else(|| err(format!("bad time {t:?}")))?;
        let rest: Vec<&str> = it.collect();
        let v = parse_fields(path, i + 1, &rest.join(" "), 7)?;
        let q = [v[6], v[3], v[4], v[5]];
        let n = q.iter().map(|x| x * x).sum::<f64>().sqrt();
        if (n - 1.0).abs() > TUM_QUAT_NORM_TOL {
            return Err(err(format!(
                "quaternion norm {n} is not 1 (±{TUM_QUAT_NORM_TOL})"
            )));
        }
        out.push(Pose {
            t_ns,
            p: Vector3::new(v[0], v[1], v[2]),
            r: matrix_from_quat(q),
        });
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn time_parsing_is_exact() {
        assert_eq!(
            parse_time_ns("1700000000.123456789"),
            Some(1_700_000_000_123_456_789)
        );
        assert_eq!(parse_time_ns("0.033333335"), Some(33_333_335));
        assert_eq!(parse_time_ns("12"), Some(12_000_000_000));
        assert_eq!(parse_time_ns(".5"), Some(500_000_000));
        assert_eq!(parse_time_ns("1.00000000049"), Some(1_000_000_000));
        assert_eq!(parse_time_ns("1.0000000005"), Some(1_000_000_001));
        assert_eq!(parse_time_ns("1e-3"), Some(1_000_000));
        assert_eq!(parse_time_ns("-2.5"), Some(-2_500_000_000));
        assert_eq!(parse_time_ns("abc"), None);
        assert_eq!(parse_time_ns("1.2.3"), None);
    }

    #[test]
    fn pose_rows_round_trip_full_precision() {
        let rows = vec![
            PoseRow {
                t: 0.005,
                q: [0.9, 0.1, -0.2, 0.3],
                p: Vector3::new(20.0, 5.0, 5.0),
                gyro: Vector3::new(1e-9, 0.0, -0.0),
                acc: Vector3::new(-1.48, 0.97, 9.76)
            };
            3
        ];
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("x.txt");
        write_string(
            &Outputs::direct(),
            &p,
            &format_pose_rows(&rows, NumFormat::Full),
        )
        .unwrap();
        assert_eq!(read_pose_rows(&p).unwrap(), rows);
        let g = format_pose_rows(&rows[..1], NumFormat::CppG);
        assert_eq!(
            g,
            "0.005 0.9 0.1 -0.2 0.3 20 5 5 1e-09 0 -0 -1.48 0.97 9.76 \n"
        );
    }
}
