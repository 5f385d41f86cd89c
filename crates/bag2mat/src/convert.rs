//! The bagconvert rules (kalibr_allan `9d38ea9` `bagconvert/src/main.cpp`, kalibr_allan.md §1):
//! one row `[record time, acc x y z, gyro x y z]` per Imu message of the topic, in
//! record-time order, `t = sec + 1e-9·nsec` in double; the output goes beside the bag as
//! `<stem>.mat`. Unlike bagconvert, a missing topic is an error (bagconvert writes an empty
//! 0×7 matrix and exits 0), and the output is written atomically. CSV and NPY are offered
//! for users who do not need MATLAB.

use std::path::{Path, PathBuf};

use crate::bag::RosTime;
use crate::bag::read::BagReader;
use crate::error::Error;
use crate::mat::{self, COLS, DataImu};
use crate::output::write_atomic;
use crate::series::{ImuSeries, permute};

/// Output file formats.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, clap::ValueEnum)]
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

/// bagconvert's row for one message: `[record time (s), acc x y z, gyro x y z]`.
pub fn bagconvert_row(record_time: RosTime, acc: [f64; 3], gyro: [f64; 3]) -> [f64; COLS] {
    [
        record_time.to_sec(),
        acc[0],
        acc[1],
        acc[2],
        gyro[0],
        gyro[1],
        gyro[2],
    ]
}

/// The matrix of one Imu series: `t` is the record time.
pub fn data_imu_from_series(s: &ImuSeries) -> DataImu {
    let mut d = DataImu::with_capacity(s.len());
    for i in 0..s.len() {
        d.push(bagconvert_row(s.record_time[i], s.acc[i], s.gyro[i]));
    }
    d
}

/// What [`bag_to_data_imu`] read.
#[derive(Debug, Clone)]
pub struct Converted {
    /// The matrix.
    pub data: DataImu,
    /// The topic as named in the bag.
    pub topic: String,
    /// Notes for stderr.
    pub notes: Vec<String>,
}

/// Reads the topic straight into the N×7 matrix. For an indexed bag every chunk is decoded in
/// parallel directly into its rows (the chunk infos give each chunk's row count); otherwise,
/// or if that fails, the messages are streamed in order.
pub fn bag_to_data_imu(bag_path: &Path, topic: &str, quiet: bool) -> Result<Converted, Error> {
    let bag = BagReader::open(bag_path)?;
    let sel = bag.select_imu_topic(topic)?;
    if let Some(plan) = bag.chunk_plan(&sel)
        && let Some(conv) = planned(&bag, &sel, &plan, quiet)
    {
        return Ok(conv);
    }
    let mut data = DataImu::with_capacity(sel.expected as usize);
    let report = bag.stream_imu(&sel, quiet, &mut |t, m| {
        data.push(bagconvert_row(t, m.acc, m.gyro));
    })?;
    if let Some(order) = &report.order {
        for c in data.columns.iter_mut() {
            *c = permute(c, order);
        }
    }
    Ok(Converted {
        data,
        topic: sel.topic,
        notes: report.notes,
    })
}

/// One chunk's rows of every column, and of the record times.
struct RowsPart<'a> {
    cols: [&'a mut [f64]; COLS],
    times: &'a mut [u64],
}

/// The parallel path of [`bag_to_data_imu`]; `None` when it does not apply (a chunk that
/// does not match its index) or the record times are out of order (the streaming path sorts).
fn planned(
    bag: &BagReader,
    sel: &crate::bag::read::TopicSelection,
    plan: &[(u64, usize)],
    quiet: bool,
) -> Option<Converted> {
    let n: usize = plan.iter().map(|(_, k)| k).sum();
    let mut columns: [Vec<f64>; COLS] = std::array::from_fn(|_| vec![0.0; n]);
    let mut times = vec![0u64; n];
    {
        let mut cols = columns
            .iter_mut()
            .map(|c| BagReader::split_rows(c, plan).into_iter());
        let mut col_parts: [_; COLS] = std::array::from_fn(|_| cols.next().expect("seven columns"));
        let mut parts: Vec<RowsPart> = BagReader::split_rows(&mut times, plan)
            .into_iter()
            .map(|times| RowsPart {
                cols: std::array::from_fn(|c| col_parts[c].next().expect("one slice per chunk")),
                times,
            })
            .collect();
        bag.decode_planned(sel, plan, &mut parts, quiet, |p, i, t, m| {
            for (c, v) in bagconvert_row(t, m.acc, m.gyro).into_iter().enumerate() {
                p.cols[c][i] = v;
            }
            p.times[i] = t.as_nanos();
        })
        .ok()?;
    }
    if times.windows(2).any(|w| w[1] < w[0]) {
        return None;
    }
    let mut notes = bag.notes().to_vec();
    notes.extend(sel.note.iter().cloned());
    Some(Converted {
        data: DataImu { columns },
        topic: sel.topic.clone(),
        notes,
    })
}

/// Writes the matrix in `format` to `out`, atomically.
pub fn write(out: &Path, data: &DataImu, format: Format) -> Result<(), Error> {
    match format {
        Format::Mat => mat::write_data_imu(out, data),
        Format::Csv => write_atomic(out, |w| {
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
        }),
        Format::Npy => write_atomic(out, |w| {
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
        }),
    }
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
}

/// What the `bag2mat` command runs with.
#[derive(Debug, Clone)]
pub struct Config {
    /// Input bag.
    pub bag: PathBuf,
    /// Imu topic.
    pub topic: String,
    /// Output file (default: beside the bag, see [`default_output`]).
    pub output: Option<PathBuf>,
    /// Output format.
    pub format: Format,
    /// No progress bar, no log lines.
    pub quiet: bool,
}

/// Runs the conversion, logging bagconvert's lines (on stderr) unless quiet. Returns the
/// output path and the number of rows written.
pub fn run(cfg: &Config) -> Result<(PathBuf, usize), Error> {
    let out = cfg
        .output
        .clone()
        .unwrap_or_else(|| default_output(&cfg.bag, cfg.format));
    let log = |s: &str| {
        if !cfg.quiet {
            eprintln!("{s}");
        }
    };
    log(&format!("BAG Path is: {}", cfg.bag.display()));
    log(&format!(
        "{} Path is: {}",
        cfg.format.extension().to_uppercase(),
        out.display()
    ));
    log("Reading in rosbag file...");
    let conv = bag_to_data_imu(&cfg.bag, &cfg.topic, cfg.quiet)?;
    for n in &conv.notes {
        eprintln!("warning: {n}");
    }
    log(&format!(
        "Done processing bag: {} messages on '{}'",
        conv.data.rows(),
        conv.topic
    ));
    write(&out, &conv.data, cfg.format)?;
    log("Done processing IMU data");
    Ok((out, conv.data.rows()))
}
