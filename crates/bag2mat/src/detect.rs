//! What an input is, from its content (never its extension): the first bytes of a file (the
//! bag formats' magic numbers, then the log formats' sniffers), `metadata.yaml` or an EuRoC
//! `imuN` folder for a directory. An input that is none of them is an error naming the
//! formats accepted ([`crate::source::ACCEPTED`]).

use std::fs::File;
use std::io::Read;
use std::path::Path;

use crate::error::Error;
use crate::source::{ACCEPTED, InputKind, ROS1_MAGIC, SQLITE_MAGIC, ZSTD_MAGIC};

/// Recognises `path` from its content.
pub fn input_kind(path: &Path) -> Result<InputKind, Error> {
    let meta = std::fs::metadata(path).map_err(|e| Error::io(path, e))?;
    if meta.is_dir() {
        if path.join("metadata.yaml").is_file() {
            return Ok(InputKind::Rosbag2Dir);
        }
        if let Some(kind) = crate::formats::detect_dir(path) {
            return Ok(kind);
        }
        return Err(Error::NotABag {
            path: path.to_path_buf(),
            what: format!(
                "a directory without metadata.yaml or an EuRoC/ASL imuN/data.csv. Accepted: {ACCEPTED}"
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
    if head.starts_with(ROS1_MAGIC) {
        return Ok(InputKind::Ros1Bag);
    }
    if head.starts_with(crate::mcap::MAGIC) {
        return Ok(InputKind::Mcap);
    }
    if head.starts_with(SQLITE_MAGIC) {
        return Ok(InputKind::Sqlite3);
    }
    if head.starts_with(ZSTD_MAGIC) {
        return Ok(InputKind::Zstd);
    }
    if let Some(kind) = crate::formats::detect_file(path, head) {
        return Ok(kind);
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
        what: format!("{what}. Accepted: {ACCEPTED}"),
    })
}
