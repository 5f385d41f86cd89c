//! A text log read window by window, for a file that cannot be mapped whole (a file larger
//! than the address space a memory limit leaves): the memory it takes is its rows and one
//! window, never the file's size. Each window is whole lines, read as a mapped file's body is
//! ([`super::read_body`]); a line longer than a window (no row is) is passed without being
//! held, as one malformed line.

use std::fs::File;
use std::os::unix::fs::FileExt;
use std::path::Path;

use super::body::Summary;
use super::layout::Layout;
use super::{InputOptions, MAX_HEAD_BYTES, RANGE_BYTES, SNIFF_BYTES, cut_last_line, layout};
use crate::error::Error;
use crate::rows::Rows;

/// Bytes of the file read at a time.
const WINDOW_BYTES: usize = 64 << 20;

/// `n` bytes of `file` at `at` (fewer at its end).
fn read_at(file: &File, path: &Path, at: u64, n: usize, len: u64) -> Result<Vec<u8>, Error> {
    let n = (n as u64).min(len.saturating_sub(at)) as usize;
    let mut b = vec![0u8; n];
    file.read_exact_at(&mut b, at)
        .map_err(|e| Error::io(path, e))?;
    Ok(b)
}

/// The layout, rows and range summaries of the text log `file` (`len` bytes), and the line
/// number of a last line cut inside its last number (not read).
pub(super) fn read(
    path: &Path,
    file: &File,
    len: u64,
    opts: &InputOptions,
) -> Result<(Layout, Rows, Vec<Summary>, Option<u64>), Error> {
    let head = read_at(file, path, 0, SNIFF_BYTES, len)?;
    let lay = match layout(path, &head, len, opts) {
        Err(Error::NotABag { .. }) if len > SNIFF_BYTES as u64 => {
            let head = read_at(file, path, 0, MAX_HEAD_BYTES, len)?;
            layout(path, &head, len, opts)?
        }
        r => r?,
    };
    // a decimal-comma file or one of several sensors is read from a copy of its body
    // (`super::body_copy`), which a file past the memory limit cannot have
    if lay.decimal_comma || lay.sensor_column.is_some() {
        return Err(super::layout::bad(
            path,
            format!(
                "a {} file of {len} bytes is larger than the memory limit lets it be read whole, which its {} needs: raise the limit (ulimit -v) or convert it first",
                if lay.decimal_comma {
                    "decimal-comma"
                } else {
                    "several-sensor"
                },
                if lay.decimal_comma {
                    "decimal commas"
                } else {
                    "sensor column"
                },
            ),
        ));
    }
    // room for a row per line, counted first (the rows are never copied to grow)
    let mut lines = 0usize;
    let mut at = lay.body as u64;
    while at < len {
        let b = read_at(file, path, at, WINDOW_BYTES, len)?;
        lines += memchr::memchr_iter(b'\n', &b).count();
        at += b.len() as u64;
    }
    let mut rows = Rows::default();
    rows.reserve(lines + 1);
    let mut chunks: Vec<Summary> = Vec::new();
    let (mut at, mut line) = (lay.body as u64, lay.body_line);
    let mut cut = None;
    while at < len {
        let b = read_at(file, path, at, WINDOW_BYTES, len)?;
        let end = at + b.len() as u64;
        let take = match memchr::memrchr(b'\n', &b) {
            _ if end == len => b.len(),
            Some(p) => p + 1,
            None => {
                // a line longer than a window: no row; passed to its end unheld
                let mut e = end;
                let stop = loop {
                    let more = read_at(file, path, e, WINDOW_BYTES, len)?;
                    if let Some(p) = memchr::memchr(b'\n', &more) {
                        break e + p as u64 + 1;
                    }
                    e += more.len() as u64;
                    if more.is_empty() || e >= len {
                        break len;
                    }
                };
                chunks.push(Summary {
                    lines: 1,
                    bad: 1,
                    first_bad: Some((
                        1,
                        format!("a line of {} bytes, longer than any row", stop - at),
                    )),
                    ..Summary::default()
                });
                line += 1;
                at = stop;
                continue;
            }
        };
        let mut win = &b[..take];
        let w_lay = Layout {
            body: 0,
            body_line: line,
            ..lay.clone()
        };
        if at + take as u64 == len
            && let Some((l, n)) = cut_last_line(win, &w_lay)
        {
            cut = Some(l);
            win = &win[..win.len() - n];
        }
        let (w_rows, w_chunks) = super::read_body(win, &w_lay, RANGE_BYTES);
        rows.append(&w_rows);
        line += w_chunks.iter().map(|c| c.lines).sum::<u64>();
        chunks.extend(w_chunks);
        at += take as u64;
    }
    Ok((lay, rows, chunks, cut))
}
