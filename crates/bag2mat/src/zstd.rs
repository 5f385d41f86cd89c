//! zstd in pure Rust (`ruzstd`): MCAP chunk and rosbag2 message/file compression.

use std::fs::File;
use std::io::{Read, Write};
use std::path::{Path, PathBuf};

use crate::error::Error;

/// Decompresses one or more concatenated zstd frames from `input` into `out`.
pub(crate) fn decompress_stream<R: Read, W: Write>(input: R, out: &mut W) -> std::io::Result<u64> {
    let mut input = std::io::BufReader::new(input);
    let mut total = 0u64;
    loop {
        // Stop cleanly at the end of the input, between frames.
        if std::io::BufRead::fill_buf(&mut input)?.is_empty() {
            return Ok(total);
        }
        let mut dec = ruzstd::decoding::StreamingDecoder::new(&mut input)
            .map_err(|e| std::io::Error::other(e.to_string()))?;
        total += std::io::copy(&mut dec, out)?;
    }
}

/// Decompresses `data` (whole zstd frames) into `out`, which is cleared first. At most
/// `limit` bytes are accepted (a damaged size field cannot make it allocate more).
pub(crate) fn decompress_into(data: &[u8], out: &mut Vec<u8>, limit: u64) -> Result<(), ZstdError> {
    out.clear();
    let mut w = LimitedWriter { out, limit };
    decompress_stream(data, &mut w)?;
    Ok(())
}

/// Data that does not decompress as zstd (or past its limit).
#[derive(Debug, thiserror::Error)]
#[error("zstd: {0}")]
pub struct ZstdError(#[from] std::io::Error);

struct LimitedWriter<'a> {
    out: &'a mut Vec<u8>,
    limit: u64,
}

impl Write for LimitedWriter<'_> {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        if self.out.len() as u64 + buf.len() as u64 > self.limit {
            return Err(std::io::Error::other(format!(
                "decompressed data exceeds the {} bytes announced",
                self.limit
            )));
        }
        self.out.extend_from_slice(buf);
        Ok(buf.len())
    }
    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

/// Compresses `data` as one zstd frame (ruzstd's fastest level, about zstd level 1).
pub fn compress(data: &[u8], out: &mut Vec<u8>) {
    out.clear();
    ruzstd::encoding::compress(data, &mut *out, ruzstd::encoding::CompressionLevel::Fastest);
}

/// A file decompressed from a zstd FILE-mode input into a private temporary file, removed
/// when dropped.
pub struct Decompressed {
    /// Where the decompressed bytes are.
    pub path: PathBuf,
    _dir: tempfile::TempDir,
}

/// Decompresses every zstd frame of `src` into a temporary file (FILE-mode rosbag2
/// compression stores each storage file as one `.zstd` file).
pub(crate) fn decompress_zstd_file(src: &Path) -> Result<Decompressed, Error> {
    let dir = tempfile::Builder::new()
        .prefix("bag2mat-zstd.")
        .tempdir()
        .map_err(|e| Error::io(std::env::temp_dir(), e))?;
    let name = src
        .file_stem()
        .map(|s| s.to_os_string())
        .unwrap_or_else(|| "decompressed".into());
    let path = dir.path().join(name);
    let input = File::open(src).map_err(|e| Error::io(src, e))?;
    let mut out = std::io::BufWriter::new(File::create(&path).map_err(|e| Error::io(&path, e))?);
    decompress_stream(std::io::BufReader::new(input), &mut out).map_err(|e| Error::Corrupt {
        path: src.to_path_buf(),
        offset: 0,
        what: format!("zstd: {e}"),
    })?;
    std::io::Write::flush(&mut out).map_err(|e| Error::io(&path, e))?;
    Ok(Decompressed { path, _dir: dir })
}

#[cfg(test)]
mod tests {
    #[test]
    fn round_trip_and_limit() {
        let data: Vec<u8> = (0..200_000u32)
            .flat_map(|i| (i % 251).to_le_bytes())
            .collect();
        let mut z = Vec::new();
        super::compress(&data, &mut z);
        assert!(z.len() < data.len() / 2);
        let mut back = Vec::new();
        super::decompress_into(&z, &mut back, data.len() as u64).unwrap();
        assert_eq!(back, data);
        assert!(super::decompress_into(&z, &mut back, 1000).is_err());
        assert!(super::decompress_into(&z[..z.len() / 2], &mut back, u64::MAX).is_err());
    }
}
