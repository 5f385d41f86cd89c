//! NumPy `.npy` files in bag2mat's own layout: float64, shape (N, 7), columns
//! `t ax ay az wx wy wz` (t in seconds, m/s², rad/s) — what `bag2mat -o x.npy` writes, so
//! a conversion reads back into the analysers. Format versions 1–3, either byte order, C or
//! Fortran order.

use crate::shared::note::Note;
use std::path::Path;

use crate::cursor::Cursor;
use crate::decoded::{DecodedSource, Stream};
use crate::error::Error;
use crate::mat::COLS;
use crate::rows::Row;
use crate::source::InputKind;

/// The header's fields that matter: element type, order and shape.
#[derive(Debug, Clone, PartialEq)]
struct Header {
    big_endian: bool,
    fortran: bool,
    rows: usize,
}

fn header(path: &Path, c: &mut Cursor) -> Result<Header, Error> {
    let bad = |what: String| Error::Log {
        path: path.to_path_buf(),
        what: format!("a NumPy file bag2mat does not read: {what}"),
    };
    let cur = |e: crate::cursor::CursorError| bad(e.to_string());
    c.skip(6, "magic").map_err(cur)?;
    let major = c.le::<u8>("version").map_err(cur)?;
    c.skip(1, "minor version").map_err(cur)?;
    let len = match major {
        1 => c.le::<u16>("header length").map_err(cur)? as usize,
        2 | 3 => c.le::<u32>("header length").map_err(cur)? as usize,
        v => return Err(bad(format!("format version {v}"))),
    };
    let dict = c.str(len, "header").map_err(cur)?;
    let value = |key: &str| -> Option<&str> {
        let k = dict.find(&format!("'{key}'"))?;
        let rest = dict[k + key.len() + 2..]
            .trim_start()
            .strip_prefix(':')?
            .trim_start();
        Some(rest)
    };
    let descr = value("descr").ok_or_else(|| bad("no 'descr'".into()))?;
    let big_endian = if descr.starts_with("'<f8'") {
        false
    } else if descr.starts_with("'>f8'") {
        true
    } else {
        return Err(bad(format!(
            "element type {} (bag2mat's layout is float64, '<f8')",
            descr.split(',').next().unwrap_or(descr)
        )));
    };
    let fortran = value("fortran_order").is_some_and(|v| v.starts_with("True"));
    let shape = value("shape").ok_or_else(|| bad("no 'shape'".into()))?;
    let inner = shape
        .strip_prefix('(')
        .and_then(|s| s.split(')').next())
        .ok_or_else(|| bad(format!("shape {shape}")))?;
    let dims: Vec<usize> = inner
        .split(',')
        .map(str::trim)
        .filter(|s| !s.is_empty())
        .map(|s| s.parse::<usize>())
        .collect::<Result<_, _>>()
        .map_err(|_| bad(format!("shape ({inner})")))?;
    match dims.as_slice() {
        [n, 7] => Ok(Header {
            big_endian,
            fortran,
            rows: *n,
        }),
        _ => Err(bad(format!(
            "shape ({inner}); bag2mat's layout is (N, 7): t ax ay az wx wy wz"
        ))),
    }
}

/// Seconds (as `sec + 1e-9·nsec`, bagconvert's t) back to nanoseconds: the whole seconds and
/// the rounded fraction, so that the row's t is written back unchanged.
pub(crate) fn seconds_to_ns(t: f64) -> Option<u64> {
    if !(t.is_finite() && t >= 0.0 && t < u32::MAX as f64) {
        return None;
    }
    let s = t.floor();
    let n = ((t - s) * 1e9).round().min(999_999_999.0);
    Some(s as u64 * 1_000_000_000 + n as u64)
}

/// Opens a `.npy` of bag2mat's layout: one topic, `imu`.
pub(crate) fn open(path: &Path) -> Result<DecodedSource, Error> {
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    let mut c = Cursor::new(&bytes);
    let h = header(path, &mut c)?;
    let data = c.rest();
    let row_bytes = COLS * 8;
    let need = h.rows.checked_mul(row_bytes);
    let whole = data.len() / row_bytes;
    let mut notes = Vec::new();
    let mut losses = Vec::new();
    // the rows the file holds: as many as the header says where the data hold them (numpy
    // reads no more), all of them where the data are whole rows and the header says
    // otherwise (a damaged count), else the whole ones (a file cut short)
    let rows = if need == Some(data.len()) {
        h.rows
    } else if h.fortran {
        // column by column: a count that does not fit the data places no column
        return Err(Error::Corrupt {
            path: path.to_path_buf(),
            offset: c.offset(),
            what: format!(
                "the header says {} rows of 7 doubles in Fortran (column) order ({} bytes), the file holds {} bytes of data",
                h.rows,
                need.map_or("too many".to_string(), |n| n.to_string()),
                data.len()
            ),
        });
    } else if data.len().is_multiple_of(row_bytes) {
        notes.push(Note::warning(format!(
            "the header says {} rows, the data hold {whole} whole rows: all of them were read",
            h.rows
        )));
        whole
    } else if whole >= h.rows {
        notes.push(Note::warning(format!(
            "{} bytes after the {} rows the header says were not read",
            data.len() - h.rows * row_bytes,
            h.rows
        )));
        h.rows
    } else {
        // cut short: the row it ends inside is lost; the header promised the rest
        losses.push(crate::source::Loss {
            what: format!(
                "the file ends inside row {} of the {} its header says (cut short)",
                whole + 1,
                h.rows
            ),
            messages: Some(1),
            channel: Some(0),
            ..Default::default()
        });
        if h.rows > whole + 1 {
            losses.push(crate::source::Loss {
                what: "rows the header counts past the end of the file".into(),
                at_most: Some((h.rows - whole - 1) as u64),
                channel: Some(0),
                ..Default::default()
            });
        }
        whole
    };
    let h = Header { rows, ..h };
    let at = |r: usize, k: usize| {
        let i = if h.fortran {
            k * h.rows + r
        } else {
            r * COLS + k
        };
        let mut b = [0u8; 8];
        b.copy_from_slice(&data[8 * i..8 * i + 8]);
        if h.big_endian {
            f64::from_be_bytes(b)
        } else {
            f64::from_le_bytes(b)
        }
    };
    let mut s = Stream::imu("imu", "bag2mat/data_imu");
    s.reserve(h.rows);
    let mut bad_t: Option<(usize, f64)> = None;
    for r in 0..h.rows {
        let t = at(r, 0);
        let Some(ns) = seconds_to_ns(t) else {
            bad_t.get_or_insert((r, t));
            continue;
        };
        s.push(
            ns,
            &Row {
                stamp: ns,
                acc: [at(r, 1), at(r, 2), at(r, 3)],
                gyro: [at(r, 4), at(r, 5), at(r, 6)],
            },
        );
    }
    if let Some((r, t)) = bad_t {
        let n = h.rows - s.len();
        losses.push(crate::source::Loss {
            what: format!("{n} rows have a time that is not a non-negative number of seconds (first: row {}, t = {t})", r + 1),
            messages: Some(n as u64),
            at_most: None,
            span: None,
            channel: Some(0),
        });
    }
    let mut src = DecodedSource::new(InputKind::Npy, vec![s], notes, Vec::new());
    src.add_losses(losses);
    Ok(src)
}
