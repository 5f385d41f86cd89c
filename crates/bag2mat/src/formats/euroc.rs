//! EuRoC/ASL datasets (also TUM-VI and many Kalibr-format datasets): `mav0/imuN/data.csv`
//! with the header `#timestamp [ns],w_RS_S_x [rad s^-1],…,a_RS_S_z [m s^-2]`, given as the
//! file, its `imuN` folder or the dataset root (every `imuN` found is a topic named after
//! its folder, like several topics of a bag). The `sensor.yaml` beside a `data.csv` states
//! the dataset's own noise figures: they are read and said next to ours, for the user to
//! judge whether they hold.

use crate::shared::note::Note;
use std::path::{Path, PathBuf};

use super::InputOptions;
use crate::decoded::DecodedSource;
use crate::error::Error;
use crate::source::InputKind;

/// The noise figures and rate a `sensor.yaml` states (continuous time, as Kalibr's).
#[derive(Debug, Clone, Default, PartialEq, serde::Deserialize)]
pub struct Stated {
    /// `rate_hz`.
    pub rate_hz: Option<f64>,
    /// `gyroscope_noise_density`, rad/s/√Hz.
    pub gyroscope_noise_density: Option<f64>,
    /// `gyroscope_random_walk`, rad/s²/√Hz.
    pub gyroscope_random_walk: Option<f64>,
    /// `accelerometer_noise_density`, m/s²/√Hz.
    pub accelerometer_noise_density: Option<f64>,
    /// `accelerometer_random_walk`, m/s³/√Hz.
    pub accelerometer_random_walk: Option<f64>,
}

impl Stated {
    /// One line: every figure stated, with its unit.
    pub(crate) fn describe(&self) -> String {
        let mut v = Vec::new();
        for (name, val, unit) in [
            (
                "gyroscope_noise_density",
                self.gyroscope_noise_density,
                "rad/s/sqrt(Hz)",
            ),
            (
                "gyroscope_random_walk",
                self.gyroscope_random_walk,
                "rad/s^2/sqrt(Hz)",
            ),
            (
                "accelerometer_noise_density",
                self.accelerometer_noise_density,
                "m/s^2/sqrt(Hz)",
            ),
            (
                "accelerometer_random_walk",
                self.accelerometer_random_walk,
                "m/s^3/sqrt(Hz)",
            ),
            ("rate_hz", self.rate_hz, "Hz"),
        ] {
            if let Some(x) = val {
                v.push(format!("{name} {x} {unit}"));
            }
        }
        v.join(", ")
    }
}

/// A `sensor.yaml` that does not parse: its path and the parser's message (its first line:
/// the rest draws the text around the error).
#[derive(Debug, thiserror::Error)]
#[error("{}: {}", .path.display(), .source.to_string().lines().next().unwrap_or(""))]
pub(crate) struct SensorYamlError {
    path: std::path::PathBuf,
    source: serde_saphyr::Error,
}

/// The `sensor.yaml` beside `data_csv`, if there is one: its figures, or why they cannot be
/// read.
pub(crate) fn sensor_yaml(data_csv: &Path) -> Option<Result<Stated, SensorYamlError>> {
    let p = data_csv.parent()?.join("sensor.yaml");
    let text = std::fs::read_to_string(&p).ok()?;
    Some(
        serde_saphyr::from_str::<Stated>(&plain_yaml(&text))
            .map_err(|source| SensorYamlError { path: p, source }),
    )
}

/// The YAML of a `sensor.yaml` as OpenCV's `FileStorage` writes it (`%YAML:1.0`, which a
/// YAML 1.2 parser refuses as a directive, and `!!opencv-matrix` tags on matrices): the
/// directive line dropped and the tags taken off; any other file as it is.
fn plain_yaml(text: &str) -> String {
    text.lines()
        .filter(|l| !l.trim_start().starts_with("%YAML"))
        .map(|l| l.replacen("!!opencv-matrix", "", 1) + "\n")
        .collect()
}

/// The figures the `sensor.yaml` of topic `topic` of the input at `path` states (for the
/// analysers, which print them next to theirs).
pub fn stated_for(path: &Path, topic: &str) -> Option<Stated> {
    let files = if path.is_dir() {
        imu_files(path)
    } else {
        // only a data.csv in an EuRoC imuN folder has a sensor.yaml of its own
        let dir = data_csv_folder(path)?;
        vec![(folder_topic(dir), path.to_path_buf())]
    };
    let (_, f) = files.into_iter().find(|(t, _)| t == topic)?;
    sensor_yaml(&f)?.ok()
}

/// Where a tool's default output folder goes for an input inside an EuRoC/ASL dataset (a
/// `data.csv` of an `imuN` folder, the folder, or its `mav0`): beside the dataset's root
/// (the folder holding `mav0`), never inside the dataset tree, named after the root and,
/// for one IMU's folder or file, that IMU (`MH_01_easy` + `imu0`). Returns the folder to
/// put it in and the name's stem; `None` for any other input (a dataset root is a folder
/// like any other: its output goes beside it already).
pub fn output_base(path: &Path) -> Option<(PathBuf, String)> {
    let path = std::fs::canonicalize(path).ok()?;
    let (mav0, imu) = if path.is_dir() && path.file_name().is_some_and(|n| n == "mav0") {
        (path.clone(), None)
    } else {
        let dir = if path.is_dir() {
            is_imu_folder(&path).then_some(path.as_path())?
        } else {
            data_csv_folder(&path)?
        };
        (dir.parent()?.to_path_buf(), Some(folder_topic(dir)))
    };
    // the root holds mav0; an imuN folder outside a mav0 counts its parent as the root
    let root = if mav0.file_name().is_some_and(|n| n == "mav0") {
        mav0.parent()?.to_path_buf()
    } else {
        mav0
    };
    let name = root.file_name()?.to_string_lossy().into_owned();
    let stem = match imu {
        Some(t) => format!("{name}_{t}"),
        None => name,
    };
    Some((root.parent()?.to_path_buf(), stem))
}

/// The topic of an `imuN` folder: its name.
pub(crate) fn folder_topic(dir: &Path) -> String {
    dir.file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "imu0".into())
}

/// The EuRoC `imuN` folder `path` is the `data.csv` of, if it is one.
pub(crate) fn data_csv_folder(path: &Path) -> Option<&Path> {
    let dir = path.parent()?;
    (path.file_name().is_some_and(|n| n == "data.csv") && is_imu_folder(dir)).then_some(dir)
}

/// True when `dir` holds a `data.csv` with the EuRoC/ASL IMU header.
pub(crate) fn is_imu_folder(dir: &Path) -> bool {
    let f = dir.join("data.csv");
    let Ok(file) = std::fs::File::open(&f) else {
        return false;
    };
    let mut line = String::new();
    use std::io::BufRead;
    let mut r = std::io::BufReader::new(std::io::Read::take(file, 4096));
    r.read_line(&mut line).is_ok() && line.contains("w_RS_S_x") && line.contains("a_RS_S_x")
}

/// Every IMU `data.csv` of an EuRoC/ASL layout at `path` (the `imuN` folder, the `mav0`
/// folder or the dataset root), with its topic, sorted by topic.
pub(crate) fn imu_files(path: &Path) -> Vec<(String, PathBuf)> {
    if is_imu_folder(path) {
        return vec![(folder_topic(path), path.join("data.csv"))];
    }
    for base in [path.to_path_buf(), path.join("mav0")] {
        let Ok(rd) = std::fs::read_dir(&base) else {
            continue;
        };
        let mut v: Vec<(String, PathBuf)> = rd
            .filter_map(|e| e.ok())
            .map(|e| e.path())
            .filter(|p| p.is_dir() && is_imu_folder(p))
            .map(|p| (folder_topic(&p), p.join("data.csv")))
            .collect();
        if !v.is_empty() {
            v.sort();
            return v;
        }
    }
    Vec::new()
}

/// Opens the dataset at `path`.
pub(crate) fn open(path: &Path, opts: &InputOptions) -> Result<DecodedSource, Error> {
    open_files(imu_files(path), opts)
}

/// Opens the given `(topic, data.csv)` files as one source.
pub(crate) fn open_files(
    files: Vec<(String, PathBuf)>,
    opts: &InputOptions,
) -> Result<DecodedSource, Error> {
    let mut streams = Vec::new();
    let mut notes = Vec::new();
    let mut losses = Vec::new();
    for (topic, f) in files {
        let p = super::text::parse(&f, &topic, opts)?;
        notes.extend(p.notes.into_iter().map(|n| Note {
            text: format!("{topic}: {}", n.text),
            ..n
        }));
        if let Some((n, what)) = p.lost {
            // one stream per topic: its channel is its place
            let ch = streams.len() as u32;
            losses.push(super::text::lost_rows(ch, (n, format!("{topic}: {what}"))));
        }
        match sensor_yaml(&f) {
            Some(Ok(s)) if s != Stated::default() => notes.push(Note::warning(format!(
                "{topic}: the dataset's sensor.yaml states {} (compare with the figures measured here)",
                s.describe()
            ))),
            Some(Err(e)) => notes.push(Note::warning(format!("{topic}: sensor.yaml does not parse: {e}"))),
            _ => {}
        }
        streams.extend(p.streams);
    }
    let mut src = DecodedSource::new(InputKind::EurocDir, streams, notes, Vec::new());
    src.add_losses(losses);
    Ok(src)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An OpenCV-style sensor.yaml (`%YAML:1.0`, an `!!opencv-matrix`), as EuRoC-format
    /// datasets written through OpenCV's FileStorage hold it, states its figures like a
    /// plain one.
    #[test]
    fn an_opencv_style_sensor_yaml_is_read() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(
            dir.path().join("sensor.yaml"),
            "%YAML:1.0\n---\nsensor_type: imu\ncomment: VI-Sensor IMU (ADIS16448)\nT_BS: !!opencv-matrix\n   rows: 4\n   cols: 4\n   dt: d\n   data: [ 1., 0., 0., 0., 0., 1., 0., 0., 0., 0., 1., 0., 0., 0., 0., 1. ]\nrate_hz: 200\ngyroscope_noise_density: 1.6968e-04\ngyroscope_random_walk: 1.9393e-05\naccelerometer_noise_density: 2.0000e-3\naccelerometer_random_walk: 3.0000e-3\n",
        )
        .unwrap();
        let s = sensor_yaml(&dir.path().join("data.csv")).unwrap().unwrap();
        assert_eq!(s.rate_hz, Some(200.0));
        assert_eq!(s.gyroscope_noise_density, Some(1.6968e-4));
        assert_eq!(s.accelerometer_random_walk, Some(3e-3));
        // a file that does not parse is said in one line
        std::fs::write(
            dir.path().join("sensor.yaml"),
            "rate_hz: [\n  1, 2\n gyro: x\n",
        )
        .unwrap();
        let e = sensor_yaml(&dir.path().join("data.csv"))
            .unwrap()
            .unwrap_err();
        assert_eq!(e.to_string().lines().count(), 1, "{e}");
    }
}
