//! Opens any accepted input: [`crate::detect`] says what it is, and its reader opens it as
//! a [`Source`]; [`read_imu_topics`] opens it and reads its Imu topics through the one read
//! path ([`crate::series`]).

use std::path::Path;

use crate::error::Error;
use crate::series::{ImuRead, ImuSeries, ReadOptions, TopicSelector};
use crate::source::{InputKind, Source};

/// Opens any accepted input. A path to a bag directory's `metadata.yaml` opens the directory.
/// The opening half of the format registry: one arm per [`InputKind`] (the detection half
/// is `crate::detect`, the names [`InputKind::facts`]).
pub fn open(path: &Path) -> Result<Box<dyn Source>, Error> {
    open_with(path, &crate::formats::InputOptions::default())
}

/// [`open`], with what the user said about a log whose content does not say it all.
pub(crate) fn open_with(
    path: &Path,
    opts: &crate::formats::InputOptions,
) -> Result<Box<dyn Source>, Error> {
    if path.file_name().is_some_and(|n| n == "metadata.yaml")
        && path.is_file()
        && let Some(dir) = path.parent()
    {
        let dir = if dir.as_os_str().is_empty() {
            Path::new(".")
        } else {
            dir
        };
        return Ok(Box::new(crate::rosbag2::BagDir::open(dir)?));
    }
    Ok(match crate::detect::input_kind(path)? {
        InputKind::Ros1Bag => Box::new(crate::bag::BagReader::open(path)?),
        InputKind::Mcap => Box::new(crate::mcap::McapReader::open(path)?),
        InputKind::Sqlite3 => Box::new(crate::rosbag2::Sqlite3Reader::open(path)?),
        InputKind::Rosbag2Dir => Box::new(crate::rosbag2::BagDir::open(path)?),
        InputKind::Zstd => Box::new(crate::rosbag2::BagDir::open_compressed_file(path)?),
        InputKind::Text => crate::formats::open_text(path, opts)?,
        InputKind::EurocDir => Box::new(crate::formats::euroc::open(path, opts)?),
        InputKind::Npy => Box::new(crate::formats::npy::open(path)?),
        InputKind::Ulog => Box::new(crate::formats::ulog::open(path)?),
        InputKind::DataFlash => Box::new(crate::formats::dataflash::open(path)?),
    })
}

/// Reads the selected Imu topics of `path` (any accepted input) in one pass.
pub fn read_imu_topics(
    path: &Path,
    sel: &TopicSelector,
    opts: &ReadOptions,
) -> Result<ImuRead, Error> {
    read_imu_topics_with(path, sel, opts, &crate::formats::InputOptions::default())
}

/// [`read_imu_topics`], with what the user said about a log whose content does not say it
/// all (a text log's columns and units).
pub fn read_imu_topics_with(
    path: &Path,
    sel: &TopicSelector,
    opts: &ReadOptions,
    input: &crate::formats::InputOptions,
) -> Result<ImuRead, Error> {
    crate::series::read_owned(open_with(path, input)?, sel, opts)
}

/// Reads one Imu topic (see [`read_imu_topics`] for the rules and errors).
pub fn read_imu_series(path: &Path, topic: &str, opts: &ReadOptions) -> Result<ImuSeries, Error> {
    let mut r = read_imu_topics(path, &TopicSelector::one(topic), opts)?;
    Ok(r.series.remove(0))
}
