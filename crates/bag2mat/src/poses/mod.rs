//! Reference trajectories: timestamped poses from a motion-capture system, a ground-truth
//! file or an odometry topic, for the operating-noise analysis (`allan_kalibr --reference`)
//! and `sim spline`. Like every input, recognised from its content:
//!
//! * a TUM trajectory, `t tx ty tz qx qy qz qw` per line (seconds, metres, `#` comments,
//!   any whitespace), the time read exactly as a decimal ([`parse_time_ns`]);
//! * the EuRoC/ASL ground truth, `state_groundtruth_estimate0/data.csv` (`#timestamp`, ns,
//!   then `p_RS_R_{x,y,z}` and `q_RS_{w,x,y,z}`; a `vicon0/data.csv` has the same leading
//!   columns), given as the file, its folder, the `mav0` folder or the dataset root;
//! * a pose or odometry topic of a bag (any container [`crate::open_input`] opens):
//!   `geometry_msgs/PoseStamped`, `PoseWithCovarianceStamped`, `TransformStamped` or
//!   `nav_msgs/Odometry`, ROS 1 or CDR ([`msg`]). With no topic named, the input's only
//!   such topic.
//!
//! The poses come back sorted by time, with what was read said in [`PoseSeries::what`]
//! and anything the user should know (a topic under its other slash form, undecodable
//! messages, repeated stamps dropped) in [`PoseSeries::notes`].

use crate::shared::note::Note;

pub mod msg;

use std::path::{Path, PathBuf};

use crate::error::Error;
use crate::series::TimeColumn;
use crate::source::{Encoding, InputKind, Source};

/// Maximum deviation of a quaternion's norm from 1 in a text file (a file whose
/// quaternions are not unit is in another convention or damaged).
pub const QUAT_NORM_TOL: f64 = 1e-3;

/// Timestamped poses of a rigid body (body → world), sorted by time.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct PoseSeries {
    /// What was read ("TUM trajectory", "EuRoC/ASL ground truth", "topic '/vicon'
    /// (geometry_msgs/PoseStamped)").
    pub what: String,
    /// Time of each pose, ns (the file's epoch; a bag's header stamp or record time).
    pub t_ns: Vec<i64>,
    /// Position of the body in the world, m.
    pub position: Vec<[f64; 3]>,
    /// Orientation body → world, `[x, y, z, w]` as recorded.
    pub orientation: Vec<[f64; 4]>,
    /// What the user should know about the read (warnings).
    pub notes: Vec<Note>,
}

impl PoseSeries {
    /// Number of poses.
    pub fn len(&self) -> usize {
        self.t_ns.len()
    }

    /// True when there is no pose.
    pub fn is_empty(&self) -> bool {
        self.t_ns.is_empty()
    }

    fn push(&mut self, t: i64, p: [f64; 3], q: [f64; 4]) {
        self.t_ns.push(t);
        self.position.push(p);
        self.orientation.push(q);
    }

    /// Sorted by time (stable: a bag delivers in record order), a repeated stamp keeping
    /// its first pose (said in a note).
    fn sorted(mut self) -> PoseSeries {
        let mut idx: Vec<usize> = (0..self.len()).collect();
        idx.sort_by_key(|&i| self.t_ns[i]);
        let mut out = PoseSeries {
            what: std::mem::take(&mut self.what),
            notes: std::mem::take(&mut self.notes),
            ..PoseSeries::default()
        };
        let mut repeated = 0usize;
        for i in idx {
            if out.t_ns.last() == Some(&self.t_ns[i]) {
                repeated += 1;
                continue;
            }
            out.push(self.t_ns[i], self.position[i], self.orientation[i]);
        }
        if repeated > 0 {
            out.notes.push(Note::warning(format!(
                "{repeated} pose(s) repeat an earlier pose's time and were dropped"
            )));
        }
        out
    }
}

/// How to read a reference.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct PoseOptions {
    /// The pose topic of a bag (either slash form); `None`: the bag's only pose topic.
    pub topic: Option<String>,
    /// A bag's header stamp or record time.
    pub time: TimeColumn,
}

/// Reads the reference trajectory at `path` (module docs for what it may be).
pub fn read_poses(path: &Path, opts: &PoseOptions) -> Result<PoseSeries, Error> {
    if let Some(csv) = euroc_ground_truth(path) {
        refuse_topic(path, opts)?;
        return read_euroc(&csv);
    }
    let kind = if path.is_dir() && !path.join("metadata.yaml").is_file() {
        return Err(Error::Log {
            path: path.to_path_buf(),
            what: "a directory without metadata.yaml (a ROS 2 bag) or an EuRoC/ASL state_groundtruth_estimate0/data.csv: give the pose file or bag".into(),
        });
    } else if path.is_dir() {
        InputKind::Rosbag2Dir
    } else {
        match crate::detect::input_kind(path) {
            Ok(k) => k,
            // not a bag nor a log the IMU readers know: a TUM file is plain text too
            Err(_) => InputKind::Text,
        }
    };
    match kind {
        InputKind::Ros1Bag
        | InputKind::Mcap
        | InputKind::Sqlite3
        | InputKind::Rosbag2Dir
        | InputKind::Zstd => {
            let src = crate::input::open(path)?;
            read_topic(path, src.as_ref(), opts)
        }
        InputKind::Text => {
            refuse_topic(path, opts)?;
            read_text(path)
        }
        other => Err(Error::Log {
            path: path.to_path_buf(),
            what: format!(
                "a {} holds no poses; a reference is a TUM trajectory (t tx ty tz qx qy qz qw), an EuRoC/ASL state_groundtruth_estimate0/data.csv, or a bag's pose or odometry topic",
                other.describe()
            ),
        }),
    }
}

/// A topic given for a file that has none is an error, never ignored.
fn refuse_topic(path: &Path, opts: &PoseOptions) -> Result<(), Error> {
    match &opts.topic {
        Some(t) => Err(Error::Log {
            path: path.to_path_buf(),
            what: format!(
                "a pose file has no topics, but the reference topic '{}' was given",
                crate::printable::escape(t)
            ),
        }),
        None => Ok(()),
    }
}

/// The EuRoC/ASL ground-truth `data.csv` that `path` is or holds: the file itself, its
/// `state_groundtruth_estimate0` (or `vicon0`) folder, the `mav0` folder or the root.
fn euroc_ground_truth(path: &Path) -> Option<PathBuf> {
    if path.is_file() {
        return is_euroc_pose_csv(path).then(|| path.to_path_buf());
    }
    let mut candidates = vec![path.join("data.csv")];
    for base in [path.to_path_buf(), path.join("mav0")] {
        for folder in ["state_groundtruth_estimate0", "vicon0"] {
            candidates.push(base.join(folder).join("data.csv"));
        }
    }
    candidates
        .into_iter()
        .find(|c| c.is_file() && is_euroc_pose_csv(c))
}

/// True when the first line names the EuRoC/ASL pose columns.
fn is_euroc_pose_csv(path: &Path) -> bool {
    let Ok(f) = std::fs::File::open(path) else {
        return false;
    };
    use std::io::BufRead;
    let mut line = String::new();
    let mut r = std::io::BufReader::new(std::io::Read::take(f, 4096));
    r.read_line(&mut line).is_ok() && line.contains("p_RS_R_x") && line.contains("q_RS_w")
}

fn log_error(path: &Path, line: usize, msg: impl std::fmt::Display) -> Error {
    Error::Log {
        path: path.to_path_buf(),
        what: format!("line {line}: {msg}"),
    }
}

/// The numbers of a line (any whitespace), at least `n` of them.
fn fields(path: &Path, line_no: usize, line: &str, n: usize) -> Result<Vec<f64>, Error> {
    let v: Result<Vec<f64>, _> = line.split_whitespace().map(str::parse::<f64>).collect();
    let v = v.map_err(|e| log_error(path, line_no, format!("not a number ({e})")))?;
    if v.len() < n {
        return Err(log_error(
            path,
            line_no,
            format!("expected {n} columns, found {}", v.len()),
        ));
    }
    Ok(v)
}

/// `[w, x, y, z]` of unit norm within [`QUAT_NORM_TOL`].
fn check_unit(path: &Path, line: usize, q: [f64; 4]) -> Result<(), Error> {
    let n = q.iter().map(|x| x * x).sum::<f64>().sqrt();
    if (n - 1.0).abs() > QUAT_NORM_TOL {
        return Err(log_error(
            path,
            line,
            format!("quaternion norm {n} is not 1 (±{QUAT_NORM_TOL})"),
        ));
    }
    Ok(())
}

/// A TUM trajectory `t tx ty tz qx qy qz qw` (`#` comments, any whitespace; the time an
/// exact decimal of seconds), in file order: the poses [`read_poses`] sorts, and
/// `sim spline`'s input as it is.
pub fn read_tum(path: &Path) -> Result<PoseSeries, Error> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    let mut out = PoseSeries {
        what: "TUM trajectory".into(),
        ..PoseSeries::default()
    };
    for (i, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let mut it = line.split_whitespace();
        let t = it
            .next()
            .ok_or_else(|| log_error(path, i + 1, "empty line"))?;
        let t_ns =
            parse_time_ns(t).ok_or_else(|| log_error(path, i + 1, format!("bad time {t:?}")))?;
        let rest: Vec<&str> = it.collect();
        let v = fields(path, i + 1, &rest.join(" "), 7)?;
        check_unit(path, i + 1, [v[6], v[3], v[4], v[5]])?;
        out.push(t_ns, [v[0], v[1], v[2]], [v[3], v[4], v[5], v[6]]);
    }
    Ok(out)
}

/// A text reference: the EuRoC/ASL pose CSV or a TUM trajectory.
fn read_text(path: &Path) -> Result<PoseSeries, Error> {
    let s = read_tum(path)?;
    if s.is_empty() {
        return Err(Error::Log {
            path: path.to_path_buf(),
            what: "no pose in the file (a TUM trajectory has lines `t tx ty tz qx qy qz qw`)"
                .into(),
        });
    }
    Ok(s.sorted())
}

/// The EuRoC/ASL pose CSV: `#timestamp [ns]`, `p_RS_R_{x,y,z}` [m], `q_RS_{w,x,y,z}`, then
/// columns not read (velocity, biases).
fn read_euroc(path: &Path) -> Result<PoseSeries, Error> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    let mut out = PoseSeries {
        what: "EuRoC/ASL ground truth".into(),
        ..PoseSeries::default()
    };
    for (i, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let cols: Vec<&str> = line.split(',').map(str::trim).collect();
        if cols.len() < 8 {
            return Err(log_error(
                path,
                i + 1,
                format!("expected at least 8 columns, found {}", cols.len()),
            ));
        }
        let t: i64 = cols[0]
            .parse()
            .map_err(|_| log_error(path, i + 1, format!("bad time {:?} (ns)", cols[0])))?;
        let mut v = [0.0; 7];
        for (k, c) in cols[1..8].iter().enumerate() {
            v[k] = c
                .parse()
                .map_err(|e| log_error(path, i + 1, format!("not a number {c:?} ({e})")))?;
        }
        check_unit(path, i + 1, [v[3], v[4], v[5], v[6]])?;
        out.push(t, [v[0], v[1], v[2]], [v[4], v[5], v[6], v[3]]);
    }
    if out.is_empty() {
        return Err(Error::Log {
            path: path.to_path_buf(),
            what: "no pose in the ground-truth file".into(),
        });
    }
    Ok(out.sorted())
}

/// The pose topic of a bag (module docs), decoded by [`msg::decode`].
fn read_topic(path: &Path, src: &dyn Source, opts: &PoseOptions) -> Result<PoseSeries, Error> {
    let chans = src.channels();
    let pose_topics = || {
        let mut t: Vec<&str> = chans
            .iter()
            .filter(|c| msg::PoseType::of(&c.msg_type).is_some())
            .map(|c| c.topic.as_str())
            .collect();
        t.sort();
        t.dedup();
        t
    };
    let listing = || {
        let mut s = String::new();
        for t in crate::series::topic_summaries(src) {
            s.push_str(&format!(
                "\n  {:<30} {:>10} msgs : {}",
                crate::printable::escape(&t.topic),
                t.count,
                crate::printable::escape(&t.msg_type)
            ));
        }
        s
    };
    let mut notes = Vec::new();
    let topic = match &opts.topic {
        Some(t) if chans.iter().any(|c| &c.topic == t) => t.clone(),
        Some(t) => {
            let other = match t.strip_prefix('/') {
                Some(r) => r.to_string(),
                None => format!("/{t}"),
            };
            if !chans.iter().any(|c| c.topic == other) {
                return Err(Error::Log {
                    path: path.to_path_buf(),
                    what: format!(
                        "no topic '{}' in the bag; topics in the bag:{}",
                        crate::printable::escape(t),
                        listing()
                    ),
                });
            }
            notes.push(Note::warning(format!(
                "reference topic '{}' is not in the bag; using '{}'",
                crate::printable::escape(t),
                crate::printable::escape(&other)
            )));
            other
        }
        None => match pose_topics().as_slice() {
            [one] => one.to_string(),
            [] => {
                return Err(Error::Log {
                    path: path.to_path_buf(),
                    what: format!(
                        "no topic carries a pose ({}); topics in the bag:{}",
                        msg::POSE_TYPES.join(", "),
                        listing()
                    ),
                });
            }
            _ => {
                return Err(Error::Log {
                    path: path.to_path_buf(),
                    what: format!(
                        "several topics carry poses: name one with --reference-topic; topics in the bag:{}",
                        listing()
                    ),
                });
            }
        },
    };
    let mut wanted: Vec<(u32, msg::PoseType, msg::Wire)> = Vec::new();
    let mut types: Vec<String> = Vec::new();
    for c in chans.iter().filter(|c| c.topic == topic) {
        let (Some(ty), Some(wire)) = (
            msg::PoseType::of(&c.msg_type),
            match c.encoding {
                Encoding::Ros1 => Some(msg::Wire::Ros1),
                Encoding::Cdr => Some(msg::Wire::Cdr),
                _ => None,
            },
        ) else {
            types.push(c.msg_type.clone());
            continue;
        };
        wanted.push((c.id, ty, wire));
        types.push(c.msg_type.clone());
    }
    types.sort();
    types.dedup();
    if wanted.is_empty() {
        return Err(Error::Log {
            path: path.to_path_buf(),
            what: format!(
                "topic '{}' carries {}, not a pose ({})",
                crate::printable::escape(&topic),
                crate::printable::escape(&types.join(", ")),
                msg::POSE_TYPES.join(", ")
            ),
        });
    }
    let mut out = PoseSeries {
        what: format!(
            "topic '{}' ({})",
            crate::printable::escape(&topic),
            crate::printable::escape(&types.join(", "))
        ),
        notes,
        ..PoseSeries::default()
    };
    let (mut bad, mut first_bad): (u64, Option<String>) = (0, None);
    let ids: Vec<u32> = wanted.iter().map(|w| w.0).collect();
    let want = |c: u32| ids.contains(&c);
    for part in 0..src.parts().len() {
        let read = src.read_part(part, &want, &mut |c, record, data| {
            let Some(&(_, ty, wire)) = wanted.iter().find(|w| w.0 == c) else {
                return;
            };
            match msg::decode(ty, wire, data) {
                Ok(m) => {
                    let t = match opts.time {
                        TimeColumn::Header => m.stamp.as_nanos() as i64,
                        TimeColumn::Record => record as i64,
                    };
                    out.push(t, m.position, m.orientation);
                }
                Err(e) => {
                    bad += 1;
                    first_bad.get_or_insert(e);
                }
            }
        });
        if let Some(e) = read.error {
            out.notes
                .push(Note::warning(format!("{}: {e}", src.parts()[part].label)));
        }
        for l in read.lost {
            out.notes.push(Note::warning(l.to_string()));
        }
    }
    if bad > 0 {
        out.notes.push(Note::warning(format!(
            "{bad} message(s) on '{}' did not decode and were skipped (the first: {})",
            crate::printable::escape(&topic),
            first_bad.unwrap_or_default()
        )));
    }
    if out.is_empty() {
        return Err(Error::NothingRead {
            topic,
            why: out.notes.into_iter().map(|n| n.text).collect(),
        });
    }
    Ok(out.sorted())
}

/// A decimal time in seconds as integer nanoseconds, exactly for plain decimals (rounded
/// half up at the tenth digit); exponent forms go through f64. `None` for anything else.
pub fn parse_time_ns(s: &str) -> Option<i64> {
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
    fn tum_and_euroc_files_read_with_their_conventions() {
        let d = tempfile::tempdir().unwrap();
        let tum = d.path().join("ref.txt");
        std::fs::write(
            &tum,
            "# t tx ty tz qx qy qz qw\n1.5 1 2 3 0 0 0 1\n1.0\t4 5 6 0 0 0.6 0.8\n\n",
        )
        .unwrap();
        let s = read_poses(&tum, &PoseOptions::default()).unwrap();
        assert_eq!(s.t_ns, vec![1_000_000_000, 1_500_000_000], "sorted");
        assert_eq!(s.position[0], [4.0, 5.0, 6.0]);
        assert_eq!(s.orientation[0], [0.0, 0.0, 0.6, 0.8]);
        // EuRoC: w first in the file, [x, y, z, w] out; found from the dataset root
        let gt = d.path().join("MH/mav0/state_groundtruth_estimate0");
        std::fs::create_dir_all(&gt).unwrap();
        std::fs::write(
            gt.join("data.csv"),
            "#timestamp, p_RS_R_x [m], p_RS_R_y [m], p_RS_R_z [m], q_RS_w [], q_RS_x [], q_RS_y [], q_RS_z [], v_RS_R_x [m s^-1]\n\
             1403636580838555648,4.688,-1.786,0.783,0.8,0.6,0,0,0.1\n",
        )
        .unwrap();
        let s = read_poses(&d.path().join("MH"), &PoseOptions::default()).unwrap();
        assert_eq!(s.t_ns, vec![1_403_636_580_838_555_648]);
        assert_eq!(s.orientation[0], [0.6, 0.0, 0.0, 0.8]);
        assert_eq!(s.what, "EuRoC/ASL ground truth");
        // a topic for a file, a bad quaternion, a bad line: errors that say where
        let topic = PoseOptions {
            topic: Some("/vicon".into()),
            ..Default::default()
        };
        assert!(read_poses(&tum, &topic).is_err());
        std::fs::write(&tum, "1 0 0 0 0 0 0 2\n").unwrap();
        let e = read_poses(&tum, &PoseOptions::default())
            .unwrap_err()
            .to_string();
        assert!(e.contains("line 1") && e.contains("norm"), "{e}");
        std::fs::write(&tum, "1 0 0 x 0 0 0 1\n").unwrap();
        let e = read_poses(&tum, &PoseOptions::default())
            .unwrap_err()
            .to_string();
        assert!(e.contains("line 1") && e.contains("not a number"), "{e}");
    }
}
