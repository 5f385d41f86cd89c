//! Delimited text logs: CSV, TSV, `;` or whitespace separated, with or without a header,
//! with `#` comment lines — what microcontroller and phone loggers, `rostopic echo -p` and
//! the EuRoC/ASL datasets (`#timestamp [ns],w_RS_S_x [rad s^-1],…`) write.
//!
//! Columns are found from the header by common names ([`role_of`]: `t`/`time`/`timestamp`,
//! `gx`/`gyro_x`/`wx`/`w_RS_S_x`/…, `ax`/`acc_x`/`a_RS_S_x`/…) or given with `--columns`.
//! Units come from the header (`[ns]`, `[rad s^-1]`, `(deg/s)`), bag2mat's own CSV layout
//! (`t,ax,ay,az,wx,wy,wz`: s, m/s², rad/s), or the flags. Nothing is guessed: two columns
//! for one role, a time column without a unit, or values that cannot be SI without a unit
//! are errors that say what to add. A line that does not parse is skipped with a warning
//! naming its line number and the count of such lines; past [`MAX_BAD_FRACTION`] of the
//! lines the file is refused. Stamps that go backwards or repeat are reported.
//!
//! The body is read a byte range at a time, the ranges in parallel (`body`): plain lines in
//! one pass with `fast-float2`, any other line by the `csv` crate; times are parsed as
//! decimals straight to nanoseconds, so `1403636579.758555` s keeps every digit.

use crate::shared::note::Note;
use std::path::Path;

use rayon::prelude::*;

mod body;
mod layout;
mod window;

use super::InputOptions;
use crate::RosTime;
use crate::decoded::{DecodedSource, Stream};
use crate::error::Error;
use crate::rows::{Row, Rows};
use crate::source::InputKind;
use crate::units::AccUnit;
/// The test tools read times as the body does.
#[cfg(any(test, feature = "test-support"))]
pub(crate) use body::parse_time_ns;
use body::{Chunk, Summary, line_range, parse_lines, room};
use layout::{Delim, Layout, bad, layout};

/// Bytes looked at to decide whether a file is text, and to find its header.
pub const SNIFF_BYTES: usize = 64 * 1024;
/// Lines that fail to parse beyond this fraction of the data lines (and beyond
/// [`MIN_BAD_LIMIT`]) make the file an error rather than a log with a few damaged lines.
pub const MAX_BAD_FRACTION: f64 = 0.01;
/// Malformed lines always tolerated (with warnings), whatever the file's length.
pub const MIN_BAD_LIMIT: u64 = 10;
/// Bytes per parallel parse range.
const RANGE_BYTES: usize = 4 << 20;
/// Rows sampled for the unit plausibility checks.
const PLAUSIBILITY_ROWS: usize = 4096;
/// A gyroscope stated in no unit whose largest |value| exceeds this cannot be rad/s: 40
/// rad/s is 2300 deg/s, beyond the range of common MEMS gyros (±2000 deg/s).
pub const MAX_PLAUSIBLE_RAD_S: f64 = 40.0;
/// An accelerometer stated in no unit whose median |a| lies in this band reads ≈1 at rest:
/// it is in g, not m/s² (≈9.8 at rest).
pub const G_LIKE_BAND: (f64, f64) = (0.3, 3.0);
/// An accelerometer stated in no unit whose median |a| exceeds this (m/s², 20 g) is in mg
/// or raw counts.
pub const MAX_PLAUSIBLE_M_S2: f64 = 200.0;

/// Bytes that are no text (control bytes but tab, CR, LF; bytes of no UTF-8 character) a
/// text log may hold in its first [`SNIFF_BYTES`], per this many: a few damaged bytes do not
/// make a log unreadable (pandas reads it), a binary file holds far more.
pub const MAX_NON_TEXT_PER_MILLE: usize = 2;

/// True when the first bytes of `path` are text: UTF-8 without control bytes but tab, CR
/// and LF, up to [`MAX_NON_TEXT_PER_MILLE`] damaged bytes, its first line whole text.
pub(crate) fn looks_like_text(path: &Path) -> bool {
    let Ok(head) = read_head(path) else {
        return false;
    };
    if head.is_empty() {
        return false;
    }
    let control = |b: u8| (b < 0x20 && b != b'\t' && b != b'\n' && b != b'\r') || b == 0x7F;
    let mut bad = head.iter().filter(|&&b| control(b)).count();
    let mut rest: &[u8] = &head;
    loop {
        match std::str::from_utf8(rest) {
            Ok(_) => break,
            // a multi-byte character cut by the sniff window
            Err(e) if e.error_len().is_none() => break,
            Err(e) => {
                bad += 1;
                rest = &rest[e.valid_up_to() + e.error_len().unwrap_or(1)..];
            }
        }
    }
    let first_line = &head[..memchr::memchr(b'\n', &head).unwrap_or(head.len())];
    let first_ok =
        std::str::from_utf8(first_line).is_ok() && !first_line.iter().any(|&b| control(b));
    first_ok && bad * 1000 <= head.len() * MAX_NON_TEXT_PER_MILLE
}

fn read_head(path: &Path) -> std::io::Result<Vec<u8>> {
    use std::io::Read;
    let mut v = Vec::with_capacity(SNIFF_BYTES);
    std::fs::File::open(path)?
        .take(SNIFF_BYTES as u64)
        .read_to_end(&mut v)?;
    Ok(v)
}

/// A parsed text log: one stream, and what reading it found.
pub struct Parsed {
    /// The samples: the topic's stream.
    pub streams: Vec<Stream>,
    /// Notes (units assumed, stamps out of order, malformed lines).
    pub notes: Vec<Note>,
    /// The rows the malformed lines held, and why they were lost (the stream's loss).
    pub lost: Option<(u64, String)>,
}

/// Bytes of the file looked at for its header and first data line when its first
/// [`SNIFF_BYTES`] hold none (a long damaged line right after the header).
const MAX_HEAD_BYTES: usize = 16 << 20;

/// Parses the text log at `path` into a stream named `topic`.
pub(crate) fn parse(path: &Path, topic: &str, opts: &InputOptions) -> Result<Parsed, Error> {
    let io = |e| Error::io(path, e);
    let file = std::fs::File::open(path).map_err(io)?;
    let len = file.metadata().map_err(io)?.len();
    // mapped whole where it fits the address space, else read window by window
    let map = if crate::mapped::Mapped::fits(len) {
        crate::mapped::Mapped::of(&file, path).ok()
    } else {
        None
    };
    let (lay, mut rows, chunks, cut) = match &map {
        Some(m) => read_mapped(path, m.bytes(), opts)?,
        None => window::read(path, &file, len, opts)?,
    };
    let msg_type = if lay.euroc { "euroc/imu" } else { "text/imu" };
    let line_starts = line_starts(&chunks, lay.body_line);
    let mut notes = lay.warnings.clone();
    let mut lost = malformed_lines(path, &chunks, &line_starts)?;
    if let Some(line) = cut {
        let what = format!(
            "the last line ({line}) has no line end and its last number is shorter than in the lines before it: the file was cut inside it, and its row is not read"
        );
        lost = Some(match lost {
            Some((k, w)) => (k + 1, format!("{w}; {what}")),
            None => (1, what),
        });
    }
    // malformed lines that held no row (junk): a note
    if let Some((0, what)) = &lost {
        notes.push(Note::warning(what.clone()));
        lost = None;
    }
    if lay.time.is_none() {
        // no time column: the rows are numbered at the given rate
        let rate = opts.rate.unwrap_or(1.0);
        for (k, (r, s)) in rows.record_time.iter_mut().zip(&mut rows.stamp).enumerate() {
            let t = RosTime::from_nanos((k as f64 * 1e9 / rate).round() as u64);
            (*r, *s) = (t, t);
        }
    } else {
        notes.extend(stamp_order(&chunks, &line_starts));
    }
    check_plausible(path, &lay, &rows)?;
    check_physics(path, &lay, &rows, opts)?;
    let scaled = opts.gyro_scale.is_some() || opts.acc_scale.is_some();
    if !(lay.gyro_stated && lay.acc_stated) || lay.gyro.is_none() || lay.acc.is_none() || scaled {
        notes.push(Note::warning(format!("{}: {}", path.display(), lay.what)));
    }
    if lay.gyro.is_none() {
        notes.push(Note::warning(format!(
            "'{topic}' has no gyroscope columns: its gyro values are NaN"
        )));
    }
    if lay.acc.is_none() {
        notes.push(Note::warning(format!(
            "'{topic}' has no accelerometer columns: its acc values are NaN"
        )));
    }
    Ok(Parsed {
        streams: vec![Stream::of_rows(topic, msg_type, rows)],
        notes,
        lost,
    })
}

/// What a mapped text log holds: its layout, rows and range summaries, and the line number
/// of a last line cut inside its last number (not read).
fn read_mapped(
    path: &Path,
    bytes: &[u8],
    opts: &InputOptions,
) -> Result<(Layout, Rows, Vec<Summary>, Option<u64>), Error> {
    let head = |n: usize| &bytes[..bytes.len().min(n)];
    let len = bytes.len() as u64;
    let mut lay = match layout(path, head(SNIFF_BYTES), len, opts) {
        Err(Error::NotABag { .. }) if bytes.len() > SNIFF_BYTES => {
            layout(path, head(MAX_HEAD_BYTES), len, opts)?
        }
        r => r?,
    };
    // a decimal-comma file or one sensor of several: a copy of the body to read, byte for
    // byte where it is read (line numbers and offsets stay the file's)
    let mut copy_notes = Vec::new();
    let copy = body_copy(path, bytes, &lay, opts, &mut copy_notes)?;
    lay.warnings.extend(copy_notes);
    let bytes = copy.as_deref().unwrap_or(bytes);
    // a last line without its line end whose last number is cut: not read
    let cut = cut_last_line(bytes, &lay);
    let body = &bytes[..bytes.len() - cut.map_or(0, |c| c.1)];
    let (rows, chunks) = read_body(body, &lay, RANGE_BYTES);
    Ok((lay, rows, chunks, cut.map(|c| c.0)))
}

/// Lines whose last field a cut last line is compared with.
const CUT_CHECK_LINES: usize = 16;

/// The last line of `bytes` when it has no line end while the lines before it have, its
/// last field is a column read, and that field is shorter than it is in every one of the
/// [`CUT_CHECK_LINES`] lines before it (a number cut by the end of the file): its line
/// number and length.
fn cut_last_line(bytes: &[u8], lay: &Layout) -> Option<(u64, usize)> {
    if bytes.last().is_none_or(|&b| b == b'\n') || body::columns(lay).len() != lay.n_cols {
        return None;
    }
    let start = memchr::memrchr(b'\n', bytes)? + 1;
    if start <= lay.body {
        return None;
    }
    let last_field = |line: &[u8]| -> usize {
        let line = line.strip_suffix(b"\r").unwrap_or(line);
        let line = line.trim_ascii_end();
        let from = match lay.delim {
            layout::Delim::Byte(d) => memchr::memrchr(d, line).map_or(0, |p| p + 1),
            layout::Delim::Whitespace(_) => line
                .iter()
                .rposition(|&c| c == b' ' || c == b'\t')
                .map_or(0, |p| p + 1),
        };
        line.len() - from
    };
    let mine = last_field(&bytes[start..]);
    let mut end = start - 1;
    let mut shortest = usize::MAX;
    for _ in 0..CUT_CHECK_LINES {
        if end <= lay.body {
            break;
        }
        let s = memchr::memrchr(b'\n', &bytes[..end])
            .map_or(0, |p| p + 1)
            .max(lay.body);
        let line = &bytes[s..end];
        if !line.trim_ascii().is_empty() {
            shortest = shortest.min(last_field(line));
        }
        end = s.saturating_sub(1);
        if s == 0 {
            break;
        }
    }
    let lines_before = memchr::memchr_iter(b'\n', &bytes[lay.body..start]).count() as u64;
    (shortest != usize::MAX && mine < shortest)
        .then_some((lay.body_line + lines_before, bytes.len() - start))
}

/// The body of a file (`bytes`, laid out as `lay` says) in ranges of about `range_bytes`
/// ([`RANGE_BYTES`]; the tests' are smaller) parsed in parallel, each straight into its slot
/// of the topic's columns (room for one row per line: no copy of the file nor of the rows),
/// and what each range found. A line is read on its own: a quote never runs past it.
fn read_body(bytes: &[u8], lay: &Layout, range_bytes: usize) -> (Rows, Vec<Summary>) {
    let ranges: Vec<&[u8]> = (lay.body..bytes.len())
        .step_by(range_bytes)
        .map(|a| {
            let (s, e) = line_range(bytes, lay.body, (a, (a + range_bytes).min(bytes.len())));
            &bytes[s..e]
        })
        .collect();
    let room: Vec<usize> = ranges.par_iter().map(|r| room(r)).collect();
    let mut rows = Rows::zeroed(room.iter().sum());
    let got: Vec<Summary> = ranges
        .par_iter()
        .zip(rows.split(&room))
        .map(|(text, slot)| {
            let out = Chunk {
                slot,
                ..Chunk::default()
            };
            parse_lines(text, lay, out).got
        })
        .collect();
    // the rows of each range follow those of the ranges before it
    let mut n = 0;
    for (g, at) in got.iter().zip(room.iter().scan(0, |a, r| {
        *a += r;
        Some(*a - r)
    })) {
        if at != n {
            rows.move_down(at, g.filled, n);
        }
        n += g.filled;
    }
    rows.truncate(n);
    (rows, got)
}

/// The 1-based line number of each range's first line, the first range's being `first`.
fn line_starts(chunks: &[Summary], first: u64) -> Vec<u64> {
    chunks
        .iter()
        .scan(first, |l, c| {
            let at = *l;
            *l += c.lines;
            Some(at)
        })
        .collect()
}

/// The rows the malformed lines held and what they were (their count and the first, by its
/// line number), or the error when more than [`MAX_BAD_FRACTION`] of the lines are
/// malformed.
fn malformed_lines(
    path: &Path,
    chunks: &[Summary],
    line_starts: &[u64],
) -> Result<Option<(u64, String)>, Error> {
    let total_bad: u64 = chunks.iter().map(|c| c.bad).sum();
    if total_bad == 0 {
        return Ok(None);
    }
    let total_lines: u64 = chunks.iter().map(|c| c.lines).sum();
    let (l, why) = chunks
        .iter()
        .zip(line_starts)
        .find_map(|(c, l0)| {
            c.first_bad
                .as_ref()
                .map(|(l, why)| (l0 + l - 1, why.clone()))
        })
        .unwrap_or((0, String::new()));
    let limit = MIN_BAD_LIMIT.max((MAX_BAD_FRACTION * total_lines as f64) as u64);
    let msg = format!(
        "{total_bad} malformed line{} skipped (first: line {l}: {why})",
        if total_bad == 1 { "" } else { "s" }
    );
    if total_bad > limit {
        return Err(Error::Log {
            path: path.to_path_buf(),
            what: format!(
                "{msg}: more than {limit} of its {total_lines} lines ({}%) do not parse; check the delimiter and --columns",
                MAX_BAD_FRACTION * 100.0
            ),
        });
    }
    let lost: u64 = chunks.iter().map(|c| c.lost).sum();
    Ok(Some((lost, msg)))
}

/// The notes on stamps that go backwards or repeat, with the line of the first of each,
/// within the ranges and across their borders.
fn stamp_order(chunks: &[Summary], line_starts: &[u64]) -> Vec<Note> {
    let (mut back, mut dup) = (0u64, 0u64);
    let (mut first_back, mut first_dup) = (None, None);
    let mut prev: Option<u64> = None;
    for (c, l0) in chunks.iter().zip(line_starts) {
        let o = &c.order;
        let at = |l: u64| l0 + l - 1;
        if let (Some(p), Some((t, l))) = (prev, o.first) {
            if t < p {
                back += 1;
                first_back.get_or_insert(at(l));
            } else if t == p {
                dup += 1;
                first_dup.get_or_insert(at(l));
            }
        }
        back += o.back;
        dup += o.dup;
        if let Some(l) = o.first_back {
            first_back.get_or_insert(at(l));
        }
        if let Some(l) = o.first_dup {
            first_dup.get_or_insert(at(l));
        }
        prev = o.last.or(prev);
    }
    let mut notes = Vec::new();
    if back > 0 {
        notes.push(Note::warning(format!(
            "{back} time stamp{} backwards (first at line {})",
            if back == 1 { " goes" } else { "s go" },
            first_back.unwrap_or(0)
        )));
    }
    if dup > 0 {
        notes.push(Note::warning(format!(
            "{dup} time stamp{} the one before (first at line {}); the rows are kept",
            if dup == 1 { " repeats" } else { "s repeat" },
            first_dup.unwrap_or(0)
        )));
    }
    notes
}

/// The body of a file to read in place of its bytes, when they cannot be read as they are:
/// decimal commas as points (the fields are separated by `;` or tabs), and, in a file of
/// several sensors (a sensor column), every other sensor's lines turned into comment lines
/// of the same length. `None`: read the file as it is. A file of several sensors without
/// `--sensor-id` is an error that says what they are; `--sensor-id` on a file without a
/// sensor column, or naming no sensor it has, too.
fn body_copy(
    path: &Path,
    bytes: &[u8],
    lay: &Layout,
    opts: &InputOptions,
    notes: &mut Vec<Note>,
) -> Result<Option<Vec<u8>>, Error> {
    let ids = lay
        .sensor_column
        .as_ref()
        .map(|(col, name)| (*col, name, sensor_ids(bytes, lay, *col)));
    let keep: Option<(usize, &str)> = match (&ids, &opts.sensor_id) {
        (None, Some(id)) => {
            return Err(layout::bad(
                path,
                format!(
                    "--sensor-id {id}: the file has no column saying which sensor a row is from ({})",
                    layout::SENSOR_ID_NAMES.join(", ")
                ),
            ));
        }
        (Some((_, name, found)), Some(id)) if !found.iter().any(|(v, _)| v == id) => {
            return Err(layout::bad(
                path,
                format!("--sensor-id {id}: column '{name}' holds {}", id_list(found)),
            ));
        }
        (Some((col, name, found)), Some(id)) => {
            let n: u64 = found.iter().map(|(_, c)| c).sum();
            let mine = found.iter().find(|(v, _)| v == id).map_or(0, |x| x.1);
            notes.push(Note::warning(format!(
                "--sensor-id {id}: {mine} of the {n} rows (column '{name}'; the file holds {})",
                id_list(found)
            )));
            Some((*col, id.as_str()))
        }
        (Some((_, name, found)), None) if found.len() > 1 => {
            let first = &found[0].0;
            return Err(layout::bad(
                path,
                format!(
                    "the rows come from {} sensors (column '{name}' holds {}), one row each in turn: each is an IMU of its own, with its own bias and noise, and read together they are neither (at {}× the rate): pick one with --sensor-id {first}",
                    found.len(),
                    id_list(found),
                    found.len()
                ),
            ));
        }
        _ => None,
    };
    if !lay.decimal_comma && keep.is_none() {
        return Ok(None);
    }
    let mut copy = bytes.to_vec();
    let body = &mut copy[lay.body..];
    if lay.decimal_comma {
        for b in body.iter_mut().filter(|b| **b == b',') {
            *b = b'.';
        }
    }
    if let Some((col, id)) = keep {
        let mut at = 0;
        while at < body.len() {
            let end = memchr::memchr(b'\n', &body[at..]).map_or(body.len(), |p| at + p + 1);
            let line = &body[at..end];
            if !line.starts_with(b"#") && field(line, lay, col).is_some_and(|f| f != id.as_bytes())
            {
                // blanked, not commented out: a comment holding a row's numbers is a
                // damaged row (`body::comment_row`), a blank line is no row
                let text_end = at
                    + line
                        .iter()
                        .take_while(|&&b| b != b'\n' && b != b'\r')
                        .count();
                body[at..text_end].fill(b' ');
            }
            at = end;
        }
    }
    Ok(Some(copy))
}

/// Field `col` of a line (without the line end), trimmed of blanks and quotes.
fn field<'l>(line: &'l [u8], lay: &Layout, col: usize) -> Option<&'l [u8]> {
    let line = line.strip_suffix(b"\n").unwrap_or(line);
    let line = line.strip_suffix(b"\r").unwrap_or(line);
    let f = match lay.delim {
        Delim::Byte(d) => line.split(|b| *b == d).nth(col),
        Delim::Whitespace(_) => line
            .split(|b| b.is_ascii_whitespace())
            .filter(|f| !f.is_empty())
            .nth(col),
    }?;
    Some(body::trim(f))
}

/// The values of the sensor column `col` over the body, with how many rows each has, in
/// the order first met (at most [`MAX_SENSOR_IDS`] values).
fn sensor_ids(bytes: &[u8], lay: &Layout, col: usize) -> Vec<(String, u64)> {
    let mut found: Vec<(String, u64)> = Vec::new();
    for line in bytes[lay.body..].split(|b| *b == b'\n') {
        if line.is_empty() || line.starts_with(b"#") {
            continue;
        }
        let Some(f) = field(line, lay, col).filter(|f| !f.is_empty()) else {
            continue;
        };
        if let Some(e) = found.iter_mut().find(|(v, _)| v.as_bytes() == f) {
            e.1 += 1;
        } else if found.len() < MAX_SENSOR_IDS {
            found.push((String::from_utf8_lossy(f).into_owned(), 1));
        }
    }
    found
}

/// Distinct sensor ids listed at most.
const MAX_SENSOR_IDS: usize = 16;

/// `0 (5000 rows), 1 (5000 rows)`.
fn id_list(found: &[(String, u64)]) -> String {
    found
        .iter()
        .map(|(v, n)| format!("{v} ({n} rows)"))
        .collect::<Vec<_>>()
        .join(", ")
}

/// The rows' sample rate for the unit checks: one over the median step between sorted time
/// stamps (the unit question is one of orders of magnitude, and a damaged row's stamp —
/// a line split inside its number — must not move it: the record check's nominal rate,
/// which counts missing samples across every gap, would read one stray stamp as a gap of
/// years).
fn median_rate(rows: &Rows) -> Option<f64> {
    let sorted = rows.stamp.is_sorted();
    if sorted && let Some(step) = median_step_by_count(&rows.stamp) {
        return Some(1e9 / step as f64);
    }
    // the steps of the sorted stamps, but zero: straight from the rows when they are in
    // order (the usual log), else in place over a sorted copy (one buffer either way)
    let mut d: Vec<u64> = Vec::with_capacity(rows.stamp.len());
    if sorted {
        d.extend(
            rows.stamp
                .windows(2)
                .map(|w| w[1].as_nanos() - w[0].as_nanos())
                .filter(|&x| x > 0),
        );
    } else {
        d.extend(rows.stamp.iter().map(|s| s.as_nanos()));
        d.sort_unstable();
        let mut kept = 0;
        for i in 1..d.len() {
            let step = d[i] - d[i - 1];
            if step > 0 {
                // kept < i: it overwrites a stamp no later step reads
                d[kept] = step;
                kept += 1;
            }
        }
        d.truncate(kept);
    }
    if d.is_empty() {
        return None;
    }
    let mid = d.len() / 2;
    let (_, m, _) = d.select_nth_unstable(mid);
    Some(1e9 / *m as f64)
}

/// Steps sampled for the candidate median step of stamps in order.
const MEDIAN_STEP_SAMPLE: usize = 4096;

/// The median positive step of stamps in order (`t` sorted), found without a buffer of
/// every step when a sample's median is it: the median of the steps at
/// [`MEDIAN_STEP_SAMPLE`] evenly spaced places is the median of all of them exactly when
/// fewer than half of all positive steps (rounded down) are below it and more are at or
/// below it — one counting pass. A logger's steps mostly take a few values (the nominal
/// step, give or take its clock's resolution), so the sample's median usually is the
/// median; else `None` (the caller then selects over a buffer of every step).
fn median_step_by_count(t: &[RosTime]) -> Option<u64> {
    let step = |i: usize| t[i + 1].as_nanos() - t[i].as_nanos();
    let n = t.len().saturating_sub(1);
    let stride = (n / MEDIAN_STEP_SAMPLE).max(1);
    let mut sample: Vec<u64> = (0..n)
        .step_by(stride)
        .map(step)
        .filter(|&d| d > 0)
        .collect();
    if sample.is_empty() {
        return None;
    }
    let mid = sample.len() / 2;
    let c = *sample.select_nth_unstable(mid).1;
    let (mut positive, mut below, mut at_most) = (0usize, 0usize, 0usize);
    for w in t.windows(2) {
        let d = w[1].as_nanos() - w[0].as_nanos();
        positive += usize::from(d > 0);
        below += usize::from(d > 0 && d < c);
        at_most += usize::from(d > 0 && d <= c);
    }
    // the sorted positive steps' element positive / 2 is c
    let mid = positive / 2;
    (below <= mid && mid < at_most).then_some(c)
}

/// The physics of what the layout read, whatever units it was told (the rules:
/// `crate::record_check::units`): a median specific force another accelerometer unit puts at
/// gravity, a rate another time unit puts among IMUs', or an unstated gyroscope unit whose
/// noise no rad/s gyroscope has, are errors that name the flag to fix (it overrides the
/// header). What no other unit explains is left to the record check's warnings.
fn check_physics(path: &Path, lay: &Layout, rows: &Rows, opts: &InputOptions) -> Result<(), Error> {
    use crate::record_check::units;
    let over = |stated: bool| {
        if stated {
            " (it overrides the header)"
        } else {
            ""
        }
    };
    // (raw counts with a scale are the scale's to get right: no unit explains them)
    if lay.acc.is_some()
        && opts.acc_scale.is_none()
        && let Some(m) = units::median_norm([&rows.acc[0], &rows.acc[1], &rows.acc[2]])
    {
        let given = lay.acc_unit.unwrap_or(AccUnit::Ms2);
        if let Some(v) = units::gravity_unit_fix(m, given) {
            return Err(layout::bad(
                path,
                format!(
                    "the accelerometer read in {} has a median magnitude of {m:.4} m/s^2, not gravity's 9.81: in {} it is {:.4} m/s^2: give --acc-unit {}{}",
                    given.name(),
                    v.name(),
                    m / given.si() * v.si(),
                    v.name(),
                    over(lay.acc_stated && opts.acc_unit.is_none())
                ),
            ));
        }
    }
    // one sort of the stamps for both checks below, and none when neither runs
    let rate_cell = std::cell::OnceCell::new();
    let rate = || *rate_cell.get_or_init(|| median_rate(rows));
    if lay.time.is_some()
        && let Some(rate) = rate()
        && let Some((u, r)) = units::rate_unit_fix(rate, lay.time_unit)
    {
        return Err(layout::bad(
            path,
            format!(
                "the time column read in {} gives a sample rate of {rate:.4} Hz, outside what IMUs have ({} Hz – {} kHz); in {} it gives {r:.1} Hz: give --time-unit {}{}",
                lay.time_unit.name(),
                units::IMU_RATE_HZ.0,
                units::IMU_RATE_HZ.1 / 1e3,
                u.name(),
                u.name(),
                over(!lay.time_from_flag && lay.time_stated)
            ),
        ));
    }
    if lay.gyro.is_some() && !lay.gyro_stated && opts.gyro_scale.is_none() {
        let rate = rate();
        for (k, axis) in rows.gyro.iter().enumerate() {
            let sigma = crate::record_check::outliers::noise_scale(axis);
            let Some(n) = rate.map(|r| units::gyro_density(sigma, r)) else {
                break;
            };
            if n > units::MAX_GYRO_DENSITY {
                return Err(layout::bad(
                    path,
                    format!(
                        "the gyroscope columns state no unit, and read as rad/s their white noise is {n:.3e} rad/s/sqrt(Hz) (gyro {}), more than any IMU gyroscope has (at most {:.0e}); in deg/s it is {:.3e}: give --gyro-unit deg/s (or --gyro-unit rad/s if that is right)",
                        ['x', 'y', 'z'][k],
                        units::MAX_GYRO_DENSITY,
                        n * std::f64::consts::PI / 180.0
                    ),
                ));
            }
        }
    }
    Ok(())
}

/// Values stated in no unit must be plausible in SI: else the error says which unit to add.
fn check_plausible(path: &Path, lay: &Layout, rows: &Rows) -> Result<(), Error> {
    let n = rows.len();
    let step = (n / PLAUSIBILITY_ROWS).max(1);
    let sample: Vec<Row> = (0..n).step_by(step).map(|i| rows.row(i)).collect();
    if sample.is_empty() {
        return Ok(());
    }
    if lay.gyro.is_some() && !lay.gyro_stated {
        let m = sample
            .iter()
            .flat_map(|r| r.gyro)
            .map(f64::abs)
            .filter(|v| v.is_finite())
            .fold(0.0, f64::max);
        if m > MAX_PLAUSIBLE_RAD_S {
            return Err(bad(
                path,
                format!(
                    "the gyroscope columns state no unit and reach {m}, which is not rad/s (beyond {MAX_PLAUSIBLE_RAD_S}): give --gyro-unit deg/s, or --gyro-scale LSB with --gyro-unit for raw counts"
                ),
            ));
        }
    }
    if lay.acc.is_some() && !lay.acc_stated {
        let mut mags: Vec<f64> = sample
            .iter()
            .map(|r| (r.acc[0] * r.acc[0] + r.acc[1] * r.acc[1] + r.acc[2] * r.acc[2]).sqrt())
            .filter(|v| v.is_finite())
            .collect();
        if !mags.is_empty() {
            let k = mags.len() / 2;
            let m = *mags.select_nth_unstable_by(k, f64::total_cmp).1;
            if m > G_LIKE_BAND.0 && m < G_LIKE_BAND.1 {
                return Err(bad(
                    path,
                    format!(
                        "the accelerometer columns state no unit and their median magnitude is {m:.4}, about 1 g, not m/s^2 (9.8 at rest): give --acc-unit g (or --acc-unit m/s^2 if that is right)"
                    ),
                ));
            }
            if m > MAX_PLAUSIBLE_M_S2 {
                return Err(bad(
                    path,
                    format!(
                        "the accelerometer columns state no unit and their median magnitude is {m:.1}, not m/s^2: give --acc-unit mg, or --acc-scale LSB with --acc-unit for raw counts"
                    ),
                ));
            }
        }
    }
    Ok(())
}

/// Opens a text log: one topic, `imu` (a `data.csv` in an EuRoC `imuN` folder is opened
/// as that folder's by [`super::open`]).
pub(crate) fn open(path: &Path, opts: &InputOptions) -> Result<DecodedSource, Error> {
    let p = parse(path, "imu", opts)?;
    let mut src = DecodedSource::new(InputKind::Text, p.streams, p.notes, Vec::new());
    src.add_losses(p.lost.into_iter().map(|l| lost_rows(0, l)).collect());
    Ok(src)
}

/// What the malformed lines of stream `channel` held, as its loss.
pub(crate) fn lost_rows(channel: u32, (n, what): (u64, String)) -> crate::source::Loss {
    crate::source::Loss {
        what,
        messages: Some(n),
        channel: Some(channel),
        ..Default::default()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use layout::Delim;

    /// The median-step rate is one over the median of the positive steps of the sorted
    /// stamps, as the plain sort-and-collect computes it, for stamps in order, out of
    /// order, repeated, and too few.
    #[test]
    fn the_median_rate_is_that_of_the_sorted_stamps() {
        let slow = |t: &[u64]| -> Option<f64> {
            let mut t = t.to_vec();
            t.sort_unstable();
            let mut d: Vec<u64> = t
                .windows(2)
                .map(|w| w[1] - w[0])
                .filter(|&x| x > 0)
                .collect();
            d.sort_unstable();
            d.get(d.len() / 2).map(|m| 1e9 / *m as f64)
        };
        let mut st = 0x2026_1208_3ED1_A4E5_u64;
        let mut next = || {
            st = st
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            st >> 33
        };
        for case in 0..400 {
            let n = (next() % 20_000) as usize;
            let mut t: Vec<u64> = Vec::with_capacity(n);
            let mut now = 1_403_636_579_758_555_392u64;
            for _ in 0..n {
                // regular steps with a few repeats and a few jittered ones, or every
                // step jittered (the sample's median then seldom is the median)
                now += match (case % 4, next() % 10) {
                    (_, 0) => 0,
                    (2, _) | (_, 1) => 5_000_000 + next() % 1_000,
                    _ => 5_000_000,
                };
                t.push(now);
            }
            if case % 2 == 1 && n > 1 {
                // a few swapped or thrown far back
                for _ in 0..3 {
                    let (a, b) = ((next() as usize) % n, (next() as usize) % n);
                    t.swap(a, b);
                }
                t[0] = t[0].saturating_sub(next() << 20);
            }
            let mut rows = Rows::zeroed(n);
            for (s, &x) in rows.stamp.iter_mut().zip(&t) {
                *s = RosTime::from_nanos(x);
            }
            assert_eq!(
                median_rate(&rows).map(f64::to_bits),
                slow(&t).map(f64::to_bits),
                "case {case}"
            );
        }
    }

    /// Bytes per range that make a test body of a few hundred kB many ranges.
    const SMALL_RANGE: usize = 4096;

    /// A body read in many small ranges, in parallel, gives what it gives
    /// read as one range: the same rows bit for bit, lines, malformed lines and stamp notes.
    #[test]
    fn a_body_in_many_ranges_reads_as_in_one() {
        const LINES: u64 = 12_000;
        let lay = Layout::for_test(
            Delim::Byte(b','),
            Some(0),
            ([1, 2, 3], [4, 5, 6]),
            (1.0, 1.0),
        );
        let mut st = 0x2026_1207_5EED_u64;
        let mut text = String::new();
        for i in 0..LINES {
            st = st
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            let v = |k: u32| {
                format!(
                    "{}{}.{:017}",
                    if (st >> k) & 1 == 1 { "-" } else { "" },
                    (st >> (k + 1)) % 10,
                    (st >> 20) % 100_000_000_000_000_000
                )
            };
            // a stamp that repeats, one that goes back, a malformed line, a comment and a
            // CRLF now and then
            let t = 1_403_636_579_758_555_392 + 5_000_000 * (i - u64::from(i % 997 == 500))
                - 10_000_000 * u64::from(i % 1499 == 700);
            match i % 613 {
                0 => text += "1,2\n",
                1 => text += "# a comment\n",
                _ => {
                    text += &format!("{t},{},{},{},{},{},{}", v(1), v(3), v(5), v(7), v(9), v(11));
                    text += if i % 7 == 0 { "\r\n" } else { "\n" };
                }
            }
        }
        assert!(
            text.len() / SMALL_RANGE >= 4 * rayon::current_num_threads(),
            "too few ranges for two to a task"
        );
        let read = |range_bytes| {
            let (rows, chunks) = read_body(text.as_bytes(), &lay, range_bytes);
            let line_starts = line_starts(&chunks, lay.body_line);
            let bad = malformed_lines(Path::new("t.csv"), &chunks, &line_starts);
            let notes = (bad.ok().flatten(), stamp_order(&chunks, &line_starts));
            let lines: u64 = chunks.iter().map(|c| c.lines).sum();
            (rows, lines, notes)
        };
        let (many, one) = (read(SMALL_RANGE), read(usize::MAX / 2));
        assert!(
            many.0.len() as u64 > LINES * 9 / 10,
            "{} rows",
            many.0.len()
        );
        assert_eq!((many.1, &many.2), (one.1, &one.2));
        assert!(many.2.0.is_some() && many.2.1.len() == 2, "{:?}", many.2);
        assert_eq!(many.0.len(), one.0.len());
        for i in 0..many.0.len() {
            let (a, b) = (many.0.row(i), one.0.row(i));
            assert_eq!(a.stamp, b.stamp, "row {i}");
            for c in 0..3 {
                assert_eq!(a.acc[c].to_bits(), b.acc[c].to_bits(), "row {i}");
                assert_eq!(a.gyro[c].to_bits(), b.gyro[c].to_bits(), "row {i}");
            }
        }
    }
}
