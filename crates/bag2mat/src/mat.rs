//! MATLAB Level-5 MAT files holding `data_imu`, the N×7 double matrix kalibr_allan's
//! `bagconvert` writes (columns `t ax ay az wx wy wz`, `t` the bag record time in seconds).
//!
//! Writing produces the uncompressed v5 layout of docs/formats.md §6.2 (192 + 56·N bytes;
//! loads in MATLAB, GNU Octave and scipy). Reading accepts what MATLAB's `save`/libmat write by
//! default: v5/v6 uncompressed elements and v7 zlib-compressed (`miCOMPRESSED`) elements,
//! little-endian, with the real part stored as any numeric type. v7.3 files are HDF5 and are
//! refused with a message saying how to re-save them.

use std::io::Read;
use std::path::Path;

use crate::cursor::Le;
use crate::error::Error;
use crate::shared::output::Outputs;

/// The variable name bagconvert writes.
pub const VAR_NAME: &str = "data_imu";
/// Column count: t, ax, ay, az, wx, wy, wz.
pub const COLS: usize = 7;

const MI_INT8: u32 = 1;
const MI_INT32: u32 = 5;
const MI_UINT32: u32 = 6;
const MI_DOUBLE: u32 = 9;
const MI_MATRIX: u32 = 14;
const MI_COMPRESSED: u32 = 15;
const MX_DOUBLE_CLASS: u8 = 6;
/// One miMATRIX element's size field is a u32 (and MATLAB wants v7.3 beyond 2 GB).
const MAX_MATRIX_BYTES: u64 = i32::MAX as u64;

/// The N×7 `data_imu` matrix, stored by columns as MATLAB does.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct DataImu {
    /// `columns[0]` = t (s), `[1..4]` = acc x y z (m/s²), `[4..7]` = gyro x y z (rad/s).
    pub columns: [Vec<f64>; COLS],
}

impl DataImu {
    /// An empty matrix with room for `n` rows.
    pub fn with_capacity(n: usize) -> DataImu {
        DataImu {
            columns: std::array::from_fn(|_| Vec::with_capacity(n)),
        }
    }

    /// Number of rows.
    pub fn rows(&self) -> usize {
        self.columns[0].len()
    }

    /// Appends a row `[t, ax, ay, az, wx, wy, wz]`.
    pub fn push(&mut self, row: [f64; COLS]) {
        for (c, v) in self.columns.iter_mut().zip(row) {
            c.push(v);
        }
    }

    /// Row `i`.
    pub fn row(&self, i: usize) -> [f64; COLS] {
        std::array::from_fn(|c| self.columns[c][i])
    }

    /// The time column.
    pub fn t(&self) -> &[f64] {
        &self.columns[0]
    }
}

/// Writes `data` as the variable `data_imu` into a v5 MAT file, atomically among the run's
/// `outputs`.
pub fn write_data_imu(outputs: &Outputs, path: &Path, data: &DataImu) -> Result<(), Error> {
    check_size(path, data)?;
    outputs.write_atomic(path, |w| encode_data_imu(w, data))
}

/// Fails when the matrix is too large for a MAT v5 variable.
pub fn check_size(path: &Path, data: &DataImu) -> Result<(), Error> {
    let n = data.rows();
    if 56 + 8 * (COLS as u64) * n as u64 > MAX_MATRIX_BYTES {
        return Err(Error::Mat {
            path: path.to_path_buf(),
            what: format!("{n} rows exceed what a MAT v5 variable can hold (2 GB); split the bag"),
        });
    }
    Ok(())
}

/// The bytes of a v5 MAT file holding `data` as `data_imu` (see [`check_size`]).
pub fn encode_data_imu(w: &mut dyn std::io::Write, data: &DataImu) -> std::io::Result<()> {
    let n = data.rows();
    let real_bytes = 8 * (COLS as u64) * n as u64;
    {
        let mut header = [b' '; 128];
        let text = b"MATLAB 5.0 MAT-file, Platform: GLNXA64, Created by: bag2mat (kalibr_allan bagconvert layout)";
        header[..text.len()].copy_from_slice(text);
        header[116..124].fill(0);
        header[124..126].copy_from_slice(&0x0100u16.to_le_bytes());
        header[126..128].copy_from_slice(b"IM");
        w.write_all(&header)?;
        let mut el = Vec::with_capacity(64);
        let tag = |el: &mut Vec<u8>, ty: u32, nbytes: u32| {
            el.extend_from_slice(&ty.to_le_bytes());
            el.extend_from_slice(&nbytes.to_le_bytes());
        };
        tag(&mut el, MI_MATRIX, (56 + real_bytes) as u32);
        tag(&mut el, MI_UINT32, 8);
        el.extend_from_slice(&(MX_DOUBLE_CLASS as u32).to_le_bytes());
        el.extend_from_slice(&0u32.to_le_bytes());
        tag(&mut el, MI_INT32, 8);
        el.extend_from_slice(&(n as i32).to_le_bytes());
        el.extend_from_slice(&(COLS as i32).to_le_bytes());
        tag(&mut el, MI_INT8, 8);
        el.extend_from_slice(VAR_NAME.as_bytes());
        tag(&mut el, MI_DOUBLE, real_bytes as u32);
        w.write_all(&el)?;
        let mut buf = Vec::with_capacity(1 << 16);
        for col in &data.columns {
            for chunk in col.chunks(8192) {
                buf.clear();
                for v in chunk {
                    buf.extend_from_slice(&v.to_le_bytes());
                }
                w.write_all(&buf)?;
            }
        }
        Ok(())
    }
}

/// Reads the variable `data_imu` (N×7) from a Level-5 MAT file. The file is streamed: the
/// values go straight from the (possibly zlib-compressed) element into the columns, so the
/// peak memory is the matrix itself, not the file plus the matrix.
pub fn read_data_imu(path: &Path) -> Result<DataImu, Error> {
    let file = std::fs::File::open(path).map_err(|e| Error::io(path, e))?;
    let len = file.metadata().map_err(|e| Error::io(path, e))?.len();
    let mut r = std::io::BufReader::with_capacity(1 << 20, file);
    let err = |what: String| Error::Mat {
        path: path.to_path_buf(),
        what,
    };
    let mut header = [0u8; 128];
    let got = read_full(&mut r, &mut header).map_err(|e| Error::io(path, e))?;
    level5_header(&header[..got]).map_err(|e| err(e.to_string()))?;
    let mut pos = 128u64;
    let mut names = Vec::new();
    while pos < len {
        let at = |w: String| err(format!("byte {pos}: {w}"));
        let Tag { ty, n, small, .. } = Tag::read(&mut r).map_err(|e| at(e.to_string()))?;
        if small {
            pos += 8;
            continue;
        }
        let found = match ty {
            MI_COMPRESSED => {
                let mut z = flate2::read::ZlibDecoder::new((&mut r).take(n as u64));
                let inner = Tag::read(&mut z).map_err(|e| at(format!("zlib: {e}")))?;
                let found = if inner.ty == MI_MATRIX {
                    Some(matrix(&mut z, false).map_err(|e| at(e.to_string()))?)
                } else {
                    None
                };
                std::io::copy(z.get_mut(), &mut std::io::sink()).map_err(|e| at(e.to_string()))?;
                pos += 8 + n as u64;
                found
            }
            _ => {
                let padded = (n as u64).div_ceil(8) * 8;
                let mut body = (&mut r).take(padded);
                let found = if ty == MI_MATRIX {
                    Some(matrix(&mut body, VALUES_AT).map_err(|e| at(e.to_string()))?)
                } else {
                    None
                };
                if let Some(Parsed::Values(v)) = &found {
                    // the values, read by the columns in parallel straight from the file
                    let start = pos + 8 + (padded - body.limit());
                    if start + v.bytes() > pos + 8 + padded {
                        return Err(at("values: failed to fill whole buffer".into()));
                    }
                    return read_columns_at(r.get_ref(), start, v)
                        .map_err(|e| at(format!("values: {e}")));
                }
                std::io::copy(&mut body, &mut std::io::sink()).map_err(|e| at(e.to_string()))?;
                pos += 8 + padded;
                found
            }
        };
        match found {
            Some(Parsed::DataImu(d)) => return Ok(d),
            Some(Parsed::Other(name)) => names.push(name),
            Some(Parsed::Values(_)) | None => {}
        }
    }
    Err(err(if names.is_empty() {
        "no variable 'data_imu' in the file (it holds no variables)".to_string()
    } else {
        format!(
            "no variable 'data_imu' in the file; it holds: {}",
            names.join(", ")
        )
    }))
}

/// What is wrong with the bytes of a MAT file (the text each gives is the `Error::Mat` the
/// user reads).
#[derive(Debug, thiserror::Error)]
enum MatFormatError {
    /// The 128-byte header is not a little-endian Level-5 one.
    #[error("{0}")]
    Header(&'static str),
    #[error("{what}: {source}")]
    Io {
        what: &'static str,
        source: std::io::Error,
    },
    /// A sub-element larger than names and dimension lists are.
    #[error("{what} of {n} bytes")]
    Oversized { what: &'static str, n: u32 },
    #[error("{0} missing")]
    Missing(&'static str),
    #[error("'{name}' is not a numeric matrix (class {class})")]
    NotNumeric { name: String, class: u8 },
    /// `data_imu`'s dimensions, when they are not N×7.
    #[error("data_imu is {0}; expected N×7 [t ax ay az wx wy wz]")]
    Shape(String),
    #[error("'{0}' is complex")]
    Complex(String),
    #[error("'{name}' holds {n} bytes of type {ty} for {rows}×{COLS}")]
    Size {
        name: String,
        n: u32,
        ty: u32,
        rows: usize,
    },
    #[error("unsupported numeric storage type {0}")]
    StorageType(u32),
}

/// The 128-byte header of a MATLAB Level-5 MAT file (`header`: what the file holds of it),
/// little-endian; else what it is instead (v7.3/HDF5, big-endian, no MAT file).
fn level5_header(header: &[u8]) -> Result<(), MatFormatError> {
    if header.len() >= 8 && &header[..8] == b"\x89HDF\r\n\x1a\n"
        || header.starts_with(b"MATLAB 7.3")
    {
        return Err(MatFormatError::Header(
            "MAT v7.3 (HDF5) files are not supported; re-save with save(..., '-v7')",
        ));
    }
    if header.len() < 128 || header[..4].contains(&0) {
        return Err(MatFormatError::Header(
            "not a MATLAB Level-5 MAT file (header missing)",
        ));
    }
    match &header[126..128] {
        b"IM" => {}
        b"MI" => {
            return Err(MatFormatError::Header(
                "big-endian MAT files are not supported",
            ));
        }
        _ => {
            return Err(MatFormatError::Header(
                "not a MATLAB Level-5 MAT file (no endian indicator)",
            ));
        }
    }
    Ok(())
}

/// Reads until `buf` is full or the input ends; returns the bytes read.
fn read_full(r: &mut impl Read, buf: &mut [u8]) -> std::io::Result<usize> {
    let mut got = 0;
    while got < buf.len() {
        match r.read(&mut buf[got..])? {
            0 => break,
            k => got += k,
        }
    }
    Ok(got)
}

/// An element's 8-byte tag, the one record every MAT element starts with.
#[derive(Debug, Clone, Copy)]
struct Tag {
    /// The data type (`miMATRIX`, `miDOUBLE`, …).
    ty: u32,
    /// The data's byte count.
    n: u32,
    /// The small-element form: type and count share the first word, and the data (at most
    /// 4 bytes) sits in the second.
    small: bool,
    /// The second word's bytes (a small element's data).
    word: [u8; 4],
}

impl Tag {
    /// The tag the 8 bytes `t` hold.
    fn parse(t: &[u8; 8]) -> Tag {
        let (first, second) = t.split_at(4);
        let first = <u32 as Le>::from_le(first);
        let word = [second[0], second[1], second[2], second[3]];
        if first >> 16 != 0 {
            return Tag {
                ty: first & 0xffff,
                n: first >> 16,
                small: true,
                word,
            };
        }
        Tag {
            ty: first,
            n: <u32 as Le>::from_le(second),
            small: false,
            word,
        }
    }

    /// Reads the next tag (in the small form, its data too).
    fn read(r: &mut impl Read) -> std::io::Result<Tag> {
        let mut t = [0u8; 8];
        r.read_exact(&mut t)?;
        Ok(Tag::parse(&t))
    }
}

/// A small sub-element (flags, dimensions, name): type and bytes, padding consumed.
fn small_element(r: &mut impl Read, what: &'static str) -> Result<(u32, Vec<u8>), MatFormatError> {
    /// Names and dimension lists are short; a larger size means a corrupt file.
    const MAX_SUB_ELEMENT: u32 = 1 << 16;
    let tag = Tag::read(r).map_err(|source| MatFormatError::Io { what, source })?;
    if tag.small {
        let n = (tag.n as usize).min(4);
        return Ok((tag.ty, tag.word[..n].to_vec()));
    }
    if tag.n > MAX_SUB_ELEMENT {
        return Err(MatFormatError::Oversized { what, n: tag.n });
    }
    let mut data = vec![0u8; (tag.n as usize).div_ceil(8) * 8];
    r.read_exact(&mut data)
        .map_err(|source| MatFormatError::Io { what, source })?;
    data.truncate(tag.n as usize);
    Ok((tag.ty, data))
}

enum Parsed {
    DataImu(DataImu),
    /// `data_imu`'s values follow (the parse stopped before them, see [`matrix`]).
    Values(Values),
    Other(String),
}

/// The layout of `data_imu`'s values: `rows` × [`COLS`] of storage type `ty`, by columns.
struct Values {
    rows: usize,
    ty: u32,
    width: usize,
}

impl Values {
    fn bytes(&self) -> u64 {
        (self.rows * COLS * self.width) as u64
    }
}

/// Whether an uncompressed `data_imu` leaves its values to [`read_columns_at`] (positioned
/// reads need a Unix file; elsewhere the values are streamed like a compressed element's).
const VALUES_AT: bool = cfg!(unix);

/// Values per read of [`read_columns_at`] (1 MiB of doubles).
const VALUES_PER_READ: usize = 1 << 17;

/// Reads the values of `v` starting at byte `start` of `file`, the columns in parallel
/// (rayon): positioned reads straight into each column, so the kernel's copy of a large
/// file and the decoding are shared by the cores instead of one thread reading it through
/// a buffer.
#[cfg(unix)]
fn read_columns_at(file: &std::fs::File, start: u64, v: &Values) -> std::io::Result<DataImu> {
    use rayon::prelude::*;
    use std::os::unix::fs::FileExt;
    let mut d = DataImu::with_capacity(v.rows);
    let col_bytes = (v.rows * v.width) as u64;
    d.columns
        .par_iter_mut()
        .enumerate()
        .try_for_each(|(c, col)| {
            let mut buf = vec![0u8; VALUES_PER_READ.min(v.rows.max(1)) * v.width];
            let mut done = 0;
            while done < v.rows {
                let k = (v.rows - done).min(VALUES_PER_READ);
                let b = &mut buf[..k * v.width];
                file.read_exact_at(b, start + c as u64 * col_bytes + (done * v.width) as u64)?;
                decode_into(col, v.ty, b);
                done += k;
            }
            Ok::<(), std::io::Error>(())
        })?;
    Ok(d)
}

#[cfg(not(unix))]
fn read_columns_at(_: &std::fs::File, _: u64, _: &Values) -> std::io::Result<DataImu> {
    unreachable!("VALUES_AT is false off Unix")
}

/// Appends the values stored as type `ty` in `b` to `col` (doubles, the usual storage,
/// without a per-value dispatch).
fn decode_into(col: &mut Vec<f64>, ty: u32, b: &[u8]) {
    if ty == 9 {
        let (whole, _) = b.as_chunks::<8>();
        col.extend(whole.iter().map(|w| f64::from_le_bytes(*w)));
    } else {
        let width = type_width(ty).unwrap_or(8);
        col.extend(b.chunks_exact(width).map(|w| number(ty, w)));
    }
}

/// Parses a miMATRIX body; reads the values only when it is `data_imu`, and with
/// `defer_values` not even then: it stops before them ([`Parsed::Values`]).
fn matrix(r: &mut impl Read, defer_values: bool) -> Result<Parsed, MatFormatError> {
    let (ty, flags) = small_element(r, "array flags")?;
    if ty != MI_UINT32 || flags.len() < 8 {
        return Err(MatFormatError::Missing("array flags"));
    }
    let (class, complex) = (flags[0], flags[1] & 0x08 != 0);
    let (ty, dims) = small_element(r, "dimensions")?;
    if ty != MI_INT32 {
        return Err(MatFormatError::Missing("dimensions"));
    }
    let dims: Vec<usize> = dims
        .chunks_exact(4)
        .map(|b| <i32 as Le>::from_le(b).max(0) as usize)
        .collect();
    let (_, name) = small_element(r, "array name")?;
    let name = String::from_utf8_lossy(&name).into_owned();
    if name != VAR_NAME {
        return Ok(Parsed::Other(name));
    }
    // Classes 6..=15 are numeric (double, single, int8 … uint64).
    if !(6..=15).contains(&class) {
        return Err(MatFormatError::NotNumeric { name, class });
    }
    if dims.len() != 2 || dims[1] != COLS {
        return Err(MatFormatError::Shape(
            dims.iter()
                .map(|d| d.to_string())
                .collect::<Vec<_>>()
                .join("×"),
        ));
    }
    if complex {
        return Err(MatFormatError::Complex(name));
    }
    let rows = dims[0];
    let Tag {
        ty,
        n,
        small: inline,
        ..
    } = Tag::read(r).map_err(|source| MatFormatError::Io {
        what: "real part",
        source,
    })?;
    let width = type_width(ty)?;
    if n as usize != rows * COLS * width {
        return Err(MatFormatError::Size { name, n, ty, rows });
    }
    if inline {
        // Only an empty matrix fits in a small element here (0 bytes).
        return Ok(Parsed::DataImu(DataImu::with_capacity(0)));
    }
    if defer_values {
        return Ok(Parsed::Values(Values { rows, ty, width }));
    }
    let mut d = DataImu::with_capacity(rows);
    let mut buf = vec![0u8; 8192 * width];
    for col in d.columns.iter_mut() {
        let mut left = rows;
        while left > 0 {
            let k = left.min(8192);
            r.read_exact(&mut buf[..k * width])
                .map_err(|source| MatFormatError::Io {
                    what: "values",
                    source,
                })?;
            decode_into(col, ty, &buf[..k * width]);
            left -= k;
        }
    }
    Ok(Parsed::DataImu(d))
}

fn type_width(ty: u32) -> Result<usize, MatFormatError> {
    Ok(match ty {
        1 | 2 => 1,
        3 | 4 => 2,
        5..=7 => 4,
        9 | 12 | 13 => 8,
        other => return Err(MatFormatError::StorageType(other)),
    })
}

/// One value of storage type `ty` from its `b` (exactly [`type_width`] bytes).
fn number(ty: u32, b: &[u8]) -> f64 {
    match ty {
        1 => <i8 as Le>::from_le(b) as f64,
        2 => <u8 as Le>::from_le(b) as f64,
        3 => <i16 as Le>::from_le(b) as f64,
        4 => <u16 as Le>::from_le(b) as f64,
        5 => <i32 as Le>::from_le(b) as f64,
        6 => <u32 as Le>::from_le(b) as f64,
        7 => <f32 as Le>::from_le(b) as f64,
        9 => <f64 as Le>::from_le(b),
        12 => <i64 as Le>::from_le(b) as f64,
        _ => <u64 as Le>::from_le(b) as f64,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Write;

    fn sample(n: usize) -> DataImu {
        let mut d = DataImu::with_capacity(n);
        for i in 0..n {
            let x = i as f64;
            d.push([
                1.6e9 + x * 0.005,
                x,
                -x,
                9.81,
                1e-3 * x,
                f64::MIN_POSITIVE,
                -0.0,
            ]);
        }
        d
    }

    #[test]
    fn write_then_read_round_trip() {
        let dir = tempfile::tempdir().unwrap();
        for n in [0, 1, 7, 1000] {
            let p = dir.path().join(format!("m{n}.mat"));
            let d = sample(n);
            write_data_imu(&crate::shared::output::Outputs::direct(), &p, &d).unwrap();
            assert_eq!(std::fs::metadata(&p).unwrap().len(), 192 + 56 * n as u64);
            assert_eq!(read_data_imu(&p).unwrap(), d, "n = {n}");
        }
    }

    /// A matrix longer than one positioned read per column, read by the parallel column
    /// reads, equals the one written; cut short anywhere in its values it is an error.
    #[test]
    fn columns_longer_than_one_read_round_trip() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("long.mat");
        let d = sample(2 * VALUES_PER_READ + 3);
        write_data_imu(&crate::shared::output::Outputs::direct(), &p, &d).unwrap();
        assert_eq!(read_data_imu(&p).unwrap(), d);
        let good = std::fs::read(&p).unwrap();
        for len in [200, good.len() / 2, good.len() - 9] {
            std::fs::write(&p, &good[..len]).unwrap();
            let e = read_data_imu(&p).unwrap_err().to_string();
            assert!(e.contains("values"), "len {len}: {e}");
        }
    }

    #[test]
    fn compressed_v7_element_is_read() {
        // Build a v7 file by hand: the same miMATRIX element, zlib-wrapped in miCOMPRESSED.
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("v5.mat");
        let d = sample(5);
        write_data_imu(&crate::shared::output::Outputs::direct(), &p, &d).unwrap();
        let v5 = std::fs::read(&p).unwrap();
        let mut z = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::default());
        z.write_all(&v5[128..]).unwrap();
        let z = z.finish().unwrap();
        let mut v7 = v5[..128].to_vec();
        v7.extend_from_slice(&MI_COMPRESSED.to_le_bytes());
        v7.extend_from_slice(&(z.len() as u32).to_le_bytes());
        v7.extend_from_slice(&z);
        let p7 = dir.path().join("v7.mat");
        std::fs::write(&p7, v7).unwrap();
        assert_eq!(read_data_imu(&p7).unwrap(), d);
    }

    #[test]
    fn garbage_is_an_error_not_a_panic() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("g.mat");
        let d = sample(3);
        write_data_imu(&crate::shared::output::Outputs::direct(), &p, &d).unwrap();
        let good = std::fs::read(&p).unwrap();
        for len in [0, 10, 128, 136, 150, 191, good.len() - 1] {
            std::fs::write(&p, &good[..len]).unwrap();
            assert!(read_data_imu(&p).is_err(), "len {len}");
        }
    }
}
