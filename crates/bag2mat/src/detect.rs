//! What an input is, from its content (never its extension): the first bytes of a file (the
//! bag formats' magic numbers, then the log formats' sniffers), `metadata.yaml` or an EuRoC
//! `imuN` folder for a directory. An input that is none of them is an error naming the
//! formats accepted ([`crate::source::accepted`]).

use std::fs::File;
use std::io::Read;
use std::path::Path;

use crate::error::Error;
use crate::formats::{DATAFLASH_MAGIC, NPY_MAGIC, ULOG_MAGIC};
use crate::source::{InputKind, ROS1_MAGIC, SQLITE_MAGIC, ZSTD_MAGIC, accepted};

/// How a kind of input is recognised: the detection half of the format registry (the other
/// half, how each kind is opened, is `crate::input::open_with`'s match; what it is called,
/// [`InputKind::facts`]).
#[derive(Clone, Copy)]
enum Recognise {
    /// A directory, by what it holds.
    Dir(fn(&Path) -> bool),
    /// A file, by its first bytes (at least 16 where the file has them).
    Magic(fn(&[u8]) -> bool),
    /// A file no magic number claims, by a look at its content (tried after every magic).
    Sniff(fn(&Path) -> bool),
}

/// How `kind` is recognised (one arm per kind: a new kind is a compile error here until it
/// says how).
fn recognise(kind: InputKind) -> Recognise {
    match kind {
        InputKind::Ros1Bag => Recognise::Magic(|h| h.starts_with(ROS1_MAGIC)),
        InputKind::Rosbag2Dir => Recognise::Dir(|p| p.join("metadata.yaml").is_file()),
        InputKind::Mcap => Recognise::Magic(|h| h.starts_with(crate::mcap::MAGIC)),
        InputKind::Sqlite3 => Recognise::Magic(|h| h.starts_with(SQLITE_MAGIC)),
        InputKind::Zstd => Recognise::Magic(|h| h.starts_with(ZSTD_MAGIC)),
        InputKind::EurocDir => Recognise::Dir(|p| !crate::formats::euroc::imu_files(p).is_empty()),
        InputKind::Text => Recognise::Sniff(crate::formats::text::looks_like_text),
        InputKind::Ulog => Recognise::Magic(|h| h.starts_with(ULOG_MAGIC)),
        // the first message defines FMT itself (type 128, 89 bytes, "FMT"): recognised by
        // those too, so that a damaged first byte does not hide a log DFReader reads
        InputKind::DataFlash => Recognise::Magic(|h| {
            h.starts_with(DATAFLASH_MAGIC) || h.get(3..8) == Some(b"\x80\x59FMT")
        }),
        InputKind::Npy => Recognise::Magic(|h| h.starts_with(NPY_MAGIC)),
    }
}

/// Recognises `path` from its content: directories by what they hold, files by their magic
/// numbers in [`InputKind::ALL`]'s order, then by the sniffers.
pub fn input_kind(path: &Path) -> Result<InputKind, Error> {
    let meta = std::fs::metadata(path).map_err(|e| Error::io(path, e))?;
    let kinds = InputKind::ALL.map(|k| (k, recognise(k)));
    if meta.is_dir() {
        if let Some((k, _)) = kinds
            .iter()
            .find(|(_, r)| matches!(r, Recognise::Dir(f) if f(path)))
        {
            return Ok(*k);
        }
        return Err(Error::NotABag {
            path: path.to_path_buf(),
            what: format!(
                "a directory without metadata.yaml or an EuRoC/ASL imuN/data.csv. Accepted: {}",
                accepted()
            ),
        });
    }
    let mut head = [0u8; 16];
    let mut f = File::open(path).map_err(|e| Error::io(path, e))?;
    let mut got = 0;
    while got < head.len() {
        match f.read(&mut head[got..]) {
            Ok(0) => break,
            Ok(n) => got += n,
            Err(e) => return Err(Error::io(path, e)),
        }
    }
    let head = &head[..got];
    if let Some((k, _)) = kinds
        .iter()
        .find(|(_, r)| matches!(r, Recognise::Magic(f) if f(head)))
    {
        return Ok(*k);
    }
    if let Some((k, _)) = kinds
        .iter()
        .find(|(_, r)| matches!(r, Recognise::Sniff(f) if f(path)))
    {
        return Ok(*k);
    }
    let what = if head.is_empty() {
        "the file is empty".to_string()
    } else if head.starts_with(b"#ROSBAG V") {
        let line = head.split(|&b| b == b'\n').next().unwrap_or(head);
        format!(
            "unsupported ROS bag version line {:?} (only 2.0 is read)",
            String::from_utf8_lossy(line)
        )
    } else if head.starts_with(b"\x89MCAP") {
        format!(
            "MCAP major version {:?} is not supported (only 0)",
            head.get(5).map(|&b| b as char)
        )
    } else if head.starts_with(b"rosbag2_bagfile_information") {
        "a metadata.yaml file: pass its directory".to_string()
    } else {
        format!(
            "it starts with {:?}",
            String::from_utf8_lossy(&head[..head.len().min(12)])
        )
    };
    Err(Error::NotABag {
        path: path.to_path_buf(),
        what: format!("{what}. Accepted: {}", accepted()),
    })
}
