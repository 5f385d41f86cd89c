//! MATLAB Level-5 MAT files holding `data_imu`, the N×7 double matrix kalibr_allan's
//! `bagconvert` writes (columns `t ax ay az wx wy wz`, `t` the bag record time in seconds).
//!
//! Writing produces the uncompressed v5 layout of rust_stack.md §6.2 (192 + 56·N bytes;
//! loads in MATLAB, GNU Octave and scipy). Reading accepts what MATLAB's `save`/libmat write by
//! default: v5/v6 uncompressed elements and v7 zlib-compressed (`miCOMPRESSED`) elements,
//! little-endian, with the real part stored as any numeric type. v7.3 files are HDF5 and are
//! refused with a message saying how to re-save them.

use std::io::Read;
use std::path::Path;

use crate::error::Error;
use crate::output::write_atomic;

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
        DataImu { columns: std::array::from_fn(|_| Vec::with_capacity(n)) }
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

/// Writes `data` as the variable `data_imu` into a v5 MAT file, atomically.
pub fn write_data_imu(path: &Path, data: &DataImu) -> Result<(), Error> {
    let n = data.rows();
    let real_bytes = 8 * (COLS as u64) * n as u64;
    if 56 + real_bytes > MAX_MATRIX_BYTES {
        return Err(Error::Mat {
            path: path.to_path_buf(),
            what: format!("{n} rows exceed what a MAT v5 variable can hold (2 GB); split the bag"),
        });
    }
    write_atomic(path, |w| {
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
    })
}

/// Reads the variable `data_imu` (N×7) from a Level-5 MAT file.
pub fn read_data_imu(path: &Path) -> Result<DataImu, Error> {
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    let err = |what: String| Error::Mat { path: path.to_path_buf(), what };
    if bytes.len() >= 8 && &bytes[..8] == b"\x89HDF\r\n\x1a\n" || bytes.starts_with(b"MATLAB 7.3") {
        return Err(err("MAT v7.3 (HDF5) files are not supported; re-save with save(..., '-v7')".into()));
    }
    if bytes.len() < 128 || bytes[..4].contains(&0) {
        return Err(err("not a MATLAB Level-5 MAT file (header missing)".into()));
    }
    match &bytes[126..128] {
        b"IM" => {}
        b"MI" => return Err(err("big-endian MAT files are not supported".into())),
        _ => return Err(err("not a MATLAB Level-5 MAT file (no endian indicator)".into())),
    }
    let mut pos = 128;
    let mut names = Vec::new();
    while pos < bytes.len() {
        let (ty, data, next) = element(&bytes, pos).map_err(|w| err(format!("byte {pos}: {w}")))?;
        let inflated;
        let (ty, data) = if ty == MI_COMPRESSED {
            let mut out = Vec::new();
            flate2::read::ZlibDecoder::new(data).read_to_end(&mut out).map_err(|e| err(format!("byte {pos}: zlib: {e}")))?;
            inflated = out;
            let (ity, idata, _) = element(&inflated, 0).map_err(|w| err(format!("compressed element at byte {pos}: {w}")))?;
            (ity, idata)
        } else {
            (ty, data)
        };
        if ty == MI_MATRIX {
            match matrix(data).map_err(|w| err(format!("variable at byte {pos}: {w}")))? {
                Matrix { name, .. } if name != VAR_NAME => names.push(name),
                Matrix { rows, cols, values, .. } => {
                    if cols != COLS {
                        return Err(err(format!("data_imu is {rows}×{cols}; expected N×7 [t ax ay az wx wy wz]")));
                    }
                    let columns = std::array::from_fn(|c| values[c * rows..(c + 1) * rows].to_vec());
                    return Ok(DataImu { columns });
                }
            }
        }
        pos = next;
    }
    Err(err(if names.is_empty() {
        "no variable 'data_imu' in the file (it holds no variables)".to_string()
    } else {
        format!("no variable 'data_imu' in the file; it holds: {}", names.join(", "))
    }))
}

/// Splits the data element at `pos`: (type, data, offset of the next element). Handles the
/// "small data element" form (type and size packed in the first 4 bytes).
fn element(buf: &[u8], pos: usize) -> Result<(u32, &[u8], usize), String> {
    let word = |p: usize| -> Result<u32, String> {
        buf.get(p..p + 4).map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]])).ok_or_else(|| "truncated element tag".to_string())
    };
    let first = word(pos)?;
    if first >> 16 != 0 {
        let (ty, n) = (first & 0xffff, (first >> 16) as usize);
        if n > 4 {
            return Err("small data element longer than 4 bytes".into());
        }
        let data = buf.get(pos + 4..pos + 4 + n).ok_or("truncated small element")?;
        return Ok((ty, data, pos + 8));
    }
    let n = word(pos + 4)? as usize;
    let data = buf.get(pos + 8..pos + 8 + n).ok_or_else(|| format!("element of {n} bytes runs past the end of the file"))?;
    // Compressed elements are not padded; all others are padded to 8 bytes.
    let padded = if first == MI_COMPRESSED { n } else { n.div_ceil(8) * 8 };
    Ok((first, data, pos + 8 + padded))
}

struct Matrix {
    name: String,
    rows: usize,
    cols: usize,
    values: Vec<f64>,
}

fn matrix(data: &[u8]) -> Result<Matrix, String> {
    let (ty, flags, p) = element(data, 0)?;
    if ty != MI_UINT32 || flags.len() < 8 {
        return Err("array flags missing".into());
    }
    let class = flags[0];
    let complex = flags[1] & 0x08 != 0;
    let (ty, dims, p) = element(data, p)?;
    if ty != MI_INT32 {
        return Err("dimensions missing".into());
    }
    let dims: Vec<usize> = dims.chunks_exact(4).map(|b| i32::from_le_bytes([b[0], b[1], b[2], b[3]]).max(0) as usize).collect();
    let (_, name, p) = element(data, p)?;
    let name = String::from_utf8_lossy(name).into_owned();
    // Classes 6..=15 are numeric (double, single, int8 … uint64); cells, structs, objects,
    // chars and sparse matrices are only listed by name.
    if !(6..=15).contains(&class) {
        if name == VAR_NAME {
            return Err(format!("'{name}' is not a numeric matrix (class {class})"));
        }
        return Ok(Matrix { name, rows: 0, cols: 0, values: Vec::new() });
    }
    if dims.len() != 2 {
        return Err(format!("'{name}' has {} dimensions; expected a 2-D matrix", dims.len()));
    }
    if complex {
        return Err(format!("'{name}' is complex"));
    }
    let (ty, real, _) = element(data, p)?;
    let values = numbers(ty, real)?;
    if values.len() != dims[0] * dims[1] {
        return Err(format!("'{name}' holds {} values for {}×{}", values.len(), dims[0], dims[1]));
    }
    Ok(Matrix { name, rows: dims[0], cols: dims[1], values })
}

fn numbers(ty: u32, b: &[u8]) -> Result<Vec<f64>, String> {
    macro_rules! conv {
        ($t:ty, $n:expr) => {
            b.chunks_exact($n).map(|c| <$t>::from_le_bytes(c.try_into().expect("exact chunk")) as f64).collect()
        };
    }
    Ok(match ty {
        1 => b.iter().map(|&v| v as i8 as f64).collect(),
        2 => b.iter().map(|&v| v as f64).collect(),
        3 => conv!(i16, 2),
        4 => conv!(u16, 2),
        5 => conv!(i32, 4),
        6 => conv!(u32, 4),
        7 => conv!(f32, 4),
        9 => conv!(f64, 8),
        12 => conv!(i64, 8),
        13 => conv!(u64, 8),
        other => return Err(format!("unsupported numeric storage type {other}")),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Write;

    fn sample(n: usize) -> DataImu {
        let mut d = DataImu::with_capacity(n);
        for i in 0..n {
            let x = i as f64;
            d.push([1.6e9 + x * 0.005, x, -x, 9.81, 1e-3 * x, f64::MIN_POSITIVE, -0.0]);
        }
        d
    }

    #[test]
    fn write_then_read_round_trip() {
        let dir = tempfile::tempdir().unwrap();
        for n in [0, 1, 7, 1000] {
            let p = dir.path().join(format!("m{n}.mat"));
            let d = sample(n);
            write_data_imu(&p, &d).unwrap();
            assert_eq!(std::fs::metadata(&p).unwrap().len(), 192 + 56 * n as u64);
            assert_eq!(read_data_imu(&p).unwrap(), d, "n = {n}");
        }
    }

    #[test]
    fn compressed_v7_element_is_read() {
        // Build a v7 file by hand: the same miMATRIX element, zlib-wrapped in miCOMPRESSED.
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("v5.mat");
        let d = sample(5);
        write_data_imu(&p, &d).unwrap();
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
        write_data_imu(&p, &d).unwrap();
        let good = std::fs::read(&p).unwrap();
        for len in [0, 10, 128, 136, 150, 191, good.len() - 1] {
            std::fs::write(&p, &good[..len]).unwrap();
            assert!(read_data_imu(&p).is_err(), "len {len}");
        }
    }
}
