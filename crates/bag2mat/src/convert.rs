//! The bagconvert rules (kalibr_allan `9d38ea9` `bagconvert/src/main.cpp`, docs/upstream/kalibr_allan.md §1):
//! one row `[record time, acc x y z, gyro x y z]` per Imu message of the topic, in
//! record-time order, `t = sec + 1e-9·nsec` in double; the output goes beside the bag as
//! `<stem>.mat`. Unlike bagconvert, a missing topic is an error (bagconvert writes an empty
//! 0×7 matrix and exits 0), and the output is written atomically. CSV and NPY are offered
//! for users who do not need MATLAB. Any input the workspace reads is accepted (ROS 1 bag,
//! ROS 2 bag directory, `.mcap`, `.db3`); for ROS 2 the record time is the storage's receive
//! time. `--time header` puts `header.stamp` in the `t` column instead (rows stay in
//! record-time order). Several topics are read in one pass, each into its own folder.

use std::io::Write;
use std::path::{Path, PathBuf};

use crate::error::Error;
use crate::mat::{self, COLS, DataImu};
use crate::series::{ImuSeries, ReadOptions, TimeColumn, TopicSelector, topic_folder_names};
use crate::shared::output::Outputs;

/// Output file formats.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Format {
    /// MATLAB Level-5 `.mat` with the variable `data_imu` (what kalibr_allan loads).
    #[default]
    Mat,
    /// Comma-separated text with a header line, shortest round-trip decimals.
    Csv,
    /// NumPy `.npy`, float64, shape (N, 7), row-major.
    Npy,
}

impl Format {
    /// The file extension.
    pub fn extension(self) -> &'static str {
        match self {
            Format::Mat => "mat",
            Format::Csv => "csv",
            Format::Npy => "npy",
        }
    }
}

/// bagconvert's output path: the bag's directory, its stem (the last extension removed, as
/// boost::filesystem's `stem`) and the format's extension.
pub fn default_output(bag: &Path, format: Format) -> PathBuf {
    let stem = bag
        .file_stem()
        .map(|s| s.to_os_string())
        .unwrap_or_else(|| "out".into());
    let mut name = stem;
    name.push(".");
    name.push(format.extension());
    match bag.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.join(name),
        _ => PathBuf::from(name),
    }
}

/// The matrix of one Imu series with the chosen time column.
pub fn data_imu_from_series(s: &ImuSeries, time: TimeColumn) -> DataImu {
    let t = s.time(time).iter().map(|r| r.to_sec()).collect();
    let [ax, ay, az] = s.acc.clone();
    let [wx, wy, wz] = s.gyro.clone();
    DataImu {
        columns: [t, ax, ay, az, wx, wy, wz],
    }
}

/// The matrix of one Imu series, consuming it: the six value columns are moved, not copied,
/// and only the time column is computed (peak memory stays near the size of the matrix).
/// The values are bagconvert's row (`[record time (s), acc x y z, gyro x y z]`) column by
/// column.
pub fn into_data_imu(s: ImuSeries, time: TimeColumn) -> DataImu {
    let ImuSeries {
        record_time,
        stamp,
        acc,
        gyro,
        ..
    } = s;
    let t_src = match time {
        TimeColumn::Record => {
            drop(stamp);
            record_time
        }
        TimeColumn::Header => {
            drop(record_time);
            stamp
        }
    };
    let t: Vec<f64> = t_src.iter().map(|r| r.to_sec()).collect();
    drop(t_src);
    let [ax, ay, az] = acc;
    let [wx, wy, wz] = gyro;
    DataImu {
        columns: [t, ax, ay, az, wx, wy, wz],
    }
}

/// What [`bag_to_data_imu`] read.
#[derive(Debug, Clone)]
pub struct Converted {
    /// The matrix.
    pub data: DataImu,
    /// The topic as named in the bag.
    pub topic: String,
    /// Notes for stderr.
    pub notes: Vec<crate::shared::note::Note>,
}

/// Reads one topic straight into bagconvert's N×7 matrix (record time).
pub fn bag_to_data_imu(bag_path: &Path, topic: &str, quiet: bool) -> Result<Converted, Error> {
    let s = crate::input::read_imu_series(bag_path, topic, &ReadOptions { quiet })?;
    let topic = s.topic.clone();
    let notes = s.notes.clone();
    Ok(Converted {
        data: into_data_imu(s, TimeColumn::Record),
        topic,
        notes,
    })
}

/// The output path that means standard output.
pub const STDOUT: &str = "-";

/// The format an output name implies by its extension (`.mat`, `.csv`, `.npy`).
pub fn format_of(path: &Path) -> Option<Format> {
    let e = path.extension()?.to_string_lossy().to_ascii_lowercase();
    [Format::Mat, Format::Csv, Format::Npy]
        .into_iter()
        .find(|f| f.extension() == e)
}

/// The format to write: `--format` when given, else the output's extension, else MAT. A
/// `--format` that contradicts the output's extension is refused (the file would be
/// misnamed), with the message for the user.
pub fn resolve_format(
    given: Option<Format>,
    output: Option<&Path>,
) -> Result<Format, crate::shared::cli::UsageError> {
    let implied = output
        .filter(|o| *o != Path::new(STDOUT))
        .and_then(format_of);
    match (given, implied) {
        (Some(g), Some(i)) if g != i => Err(crate::shared::cli::UsageError(format!(
            "--format {} contradicts the output name {} (.{}); give one or make them agree",
            g.extension(),
            output.map(|o| o.display().to_string()).unwrap_or_default(),
            i.extension()
        ))),
        (Some(g), _) => Ok(g),
        (None, Some(i)) => Ok(i),
        (None, None) => Ok(Format::Mat),
    }
}

/// The bytes of the matrix in `format`.
pub fn encode(w: &mut dyn Write, data: &DataImu, format: Format) -> std::io::Result<()> {
    match format {
        Format::Mat => mat::encode_data_imu(w, data),
        Format::Csv => {
            writeln!(w, "t,ax,ay,az,wx,wy,wz")?;
            for i in 0..data.rows() {
                let r = data.row(i);
                writeln!(
                    w,
                    "{},{},{},{},{},{},{}",
                    r[0], r[1], r[2], r[3], r[4], r[5], r[6]
                )?;
            }
            Ok(())
        }
        Format::Npy => {
            let dict = format!(
                "{{'descr': '<f8', 'fortran_order': False, 'shape': ({}, {COLS}), }}",
                data.rows()
            );
            // NPY v1.0: magic, version, u16 header length; header padded with spaces and a
            // final newline so that the data starts on a 64-byte boundary.
            let unpadded = 10 + dict.len() + 1;
            let header_len = unpadded.div_ceil(64) * 64 - 10;
            w.write_all(b"\x93NUMPY\x01\x00")?;
            w.write_all(&(header_len as u16).to_le_bytes())?;
            w.write_all(dict.as_bytes())?;
            w.write_all(&vec![b' '; header_len - dict.len() - 1])?;
            w.write_all(b"\n")?;
            let mut buf = Vec::with_capacity(56 * 1024);
            for i in 0..data.rows() {
                for v in data.row(i) {
                    buf.extend_from_slice(&v.to_le_bytes());
                }
                if buf.len() >= 56 * 1000 {
                    w.write_all(&buf)?;
                    buf.clear();
                }
            }
            w.write_all(&buf)
        }
    }
}

/// Writes the matrix in `format` to `out` (atomically among the run's `outputs`; `-` is
/// standard output).
pub fn write(outputs: &Outputs, out: &Path, data: &DataImu, format: Format) -> Result<(), Error> {
    if format == Format::Mat {
        mat::check_size(out, data)?;
    }
    if out == Path::new(STDOUT) {
        return crate::shared::cli::to_stdout(|w| encode(w, data, format))
            .map(|_| ())
            .map_err(|e| Error::io("standard output", e));
    }
    outputs.write_atomic(out, |w| encode(w, data, format))
}

/// What the `bag2mat` conversion runs with.
#[derive(Debug, Clone)]
pub struct Config {
    /// Input (any accepted kind).
    pub bag: PathBuf,
    /// Topics to convert.
    pub topics: TopicSelector,
    /// Output file for one topic, or output directory for several (default: beside the bag).
    pub output: Option<PathBuf>,
    /// Output format.
    pub format: Format,
    /// The `t` column: record time (bagconvert) or `header.stamp`.
    pub time: TimeColumn,
    /// No progress bar, no log lines.
    pub quiet: bool,
    /// What the user said about a log whose content does not say it all.
    pub input: crate::formats::InputOptions,
}

/// Where each topic's file goes: with one topic, bagconvert's path (or `-o FILE`); with
/// several, `<dir>/<topic folder>/<stem>.<ext>` where `<dir>` is `-o` or the bag's directory.
pub fn output_paths(cfg: &Config, topics: &[&str]) -> Vec<PathBuf> {
    if topics.len() == 1 && !cfg.topics.all_imu {
        return vec![
            cfg.output
                .clone()
                .unwrap_or_else(|| default_output(&cfg.bag, cfg.format)),
        ];
    }
    let file = default_output(&cfg.bag, cfg.format);
    let name = file
        .file_name()
        .map(|n| n.to_os_string())
        .unwrap_or_default();
    let dir = cfg
        .output
        .clone()
        .unwrap_or_else(|| match cfg.bag.parent() {
            Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
            _ => PathBuf::from("."),
        });
    topic_folder_names(topics)
        .into_iter()
        .map(|f| dir.join(f).join(&name))
        .collect()
}

/// What a converted topic holds that the analysers would refuse or drop, said by the
/// converter too (which writes every row as read, bagconvert's rule): integrated deltas far
/// apart, more rows than the container promises, samples stored twice.
fn conversion_warnings(s: &crate::ImuSeries, time: TimeColumn) -> Vec<String> {
    let mut out = Vec::new();
    if let Err(e) = s.check_integration() {
        out.push(format!("{e}; converted as the rates the rows hold"));
    }
    let stored = crate::record_check::stored_twice(s, time);
    if !stored.is_empty() {
        out.extend(stored.iter().map(|f| f.text.clone()));
        out.push(format!(
            "the output keeps every row read on '{}' (bagconvert's rule); allan_kalibr and allan_imu_utils drop the samples stored twice",
            crate::printable::escape(&s.topic)
        ));
    }
    out
}

/// Runs the conversion, logging bagconvert's lines (on stderr) unless quiet, its outputs
/// written among `outputs` and committed before the last line (the binary's are staged: all
/// files or none; the input is protected here). Returns each output path with its number of
/// rows.
pub fn run(cfg: &Config, mut outputs: Outputs) -> Result<Vec<(PathBuf, usize)>, Error> {
    let log = |s: &str| {
        if !cfg.quiet {
            eprintln!("{s}");
        }
    };
    log(&format!("BAG Path is: {}", cfg.bag.display()));
    let single = cfg.topics.topics.len() == 1 && !cfg.topics.all_imu;
    if single {
        let out = output_paths(cfg, &[cfg.topics.topics[0].as_str()]).remove(0);
        log(&format!(
            "{} Path is: {}",
            cfg.format.extension().to_uppercase(),
            out.display()
        ));
    }
    log("Reading in rosbag file...");
    outputs.protect_input(&cfg.bag);
    let read = crate::input::read_imu_topics_with(
        &cfg.bag,
        &cfg.topics,
        &ReadOptions { quiet: cfg.quiet },
        &cfg.input,
    )?;
    if read.series.len() > 1 && cfg.output.as_deref() == Some(Path::new(STDOUT)) {
        return Err(Error::Output {
            path: PathBuf::from(STDOUT),
            what: format!(
                "{} topics cannot share standard output; name an output directory",
                read.series.len()
            ),
        });
    }
    let names: Vec<String> = read.series.iter().map(|s| s.topic.clone()).collect();
    let names: Vec<&str> = names.iter().map(|s| s.as_str()).collect();
    let outs = output_paths(cfg, &names);
    let mut written = Vec::new();
    for (s, out) in read.series.into_iter().zip(outs) {
        for n in &s.notes {
            eprintln!("{}", n.line());
        }
        for w in conversion_warnings(&s, cfg.time) {
            eprintln!("warning: {w}");
        }
        let topic = s.topic.clone();
        if !single {
            log(&format!(
                "{} Path is: {}",
                cfg.format.extension().to_uppercase(),
                out.display()
            ));
        }
        let data = into_data_imu(s, cfg.time);
        log(&format!(
            "Done processing bag: {} messages on '{}'",
            data.rows(),
            topic
        ));
        if let Some(dir) = out.parent()
            && !single
            && !dir.as_os_str().is_empty()
        {
            outputs.ensure_dir(dir)?;
        }
        write(&outputs, &out, &data, cfg.format)?;
        written.push((out, data.rows()));
    }
    outputs.commit()?;
    log("Done processing IMU data");
    Ok(written)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn default_output_follows_boost_stem() {
        assert_eq!(
            default_output(Path::new("/a/b/foo.bag"), Format::Mat),
            PathBuf::from("/a/b/foo.mat")
        );
        assert_eq!(
            default_output(Path::new("a.b.bag"), Format::Mat),
            PathBuf::from("a.b.mat")
        );
        assert_eq!(
            default_output(Path::new("dir/x.bag"), Format::Csv),
            PathBuf::from("dir/x.csv")
        );
    }

    #[test]
    fn several_topics_get_a_folder_each() {
        let cfg = Config {
            bag: PathBuf::from("/d/rig.mcap"),
            topics: TopicSelector {
                topics: vec!["/imu0".into(), "/imu1".into()],
                all_imu: false,
                preferred: None,
            },
            output: None,
            format: Format::Mat,
            time: TimeColumn::Record,
            quiet: true,
            input: Default::default(),
        };
        assert_eq!(
            output_paths(&cfg, &["/imu0", "/imu1"]),
            vec![
                PathBuf::from("/d/imu0/rig.mat"),
                PathBuf::from("/d/imu1/rig.mat")
            ]
        );
        let one = Config {
            topics: TopicSelector::one("/imu0"),
            output: Some("x.csv".into()),
            ..cfg
        };
        assert_eq!(output_paths(&one, &["/imu0"]), vec![PathBuf::from("x.csv")]);
    }
}
