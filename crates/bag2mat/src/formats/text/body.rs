//! A text log's body, a byte range at a time: plain lines in one pass ([`fast_row`]), any
//! other line by the `csv` crate; each range straight into its slot of the columns.

use super::layout::{Delim, Layout};
use crate::rows::{Row, RowsMut};
use crate::units::TimeUnit;

/// Parses a decimal time in `unit` to nanoseconds, every digit kept (exponents through f64).
pub(crate) fn parse_time_ns(s: &[u8], unit: TimeUnit) -> Option<u64> {
    let s = trim(s);
    let mult = unit.nanos();
    let (int, frac) = match s.iter().position(|&b| b == b'.') {
        Some(p) => (&s[..p], &s[p + 1..]),
        None => (s, &s[..0]),
    };
    let digits = |d: &[u8]| d.iter().all(u8::is_ascii_digit);
    if !int.is_empty() && digits(int) && digits(frac) && int.len() <= 19 {
        // 19 digits stay below u64::MAX (1.8e19)
        let v = int.iter().fold(0u64, |v, &b| v * 10 + (b - b'0') as u64);
        let mut ns = v.checked_mul(mult)?;
        // the fraction, to the nanosecond (rounded half up)
        let mut scale = mult;
        let mut add = 0u64;
        for (k, &b) in frac.iter().enumerate() {
            let d = (b - b'0') as u64;
            if scale >= 10 {
                scale /= 10;
                add += d * scale;
            } else {
                if d >= 5 && k < frac.len() {
                    add += 1;
                }
                break;
            }
        }
        ns = ns.checked_add(add)?;
        return Some(ns);
    }
    let v: f64 = fast_float2::parse(s).ok()?;
    let ns = v * mult as f64;
    (ns.is_finite() && ns >= 0.0 && ns < u64::MAX as f64).then(|| ns.round() as u64)
}

/// Eight ASCII bytes (little-endian: the first byte lowest) that are all digits.
#[inline]
fn all_digits(v: u64) -> bool {
    const HIGH: u64 = 0xF0F0_F0F0_F0F0_F0F0;
    const THREES: u64 = 0x3030_3030_3030_3030;
    // each byte 0x30..=0x3F, and still 0x3_ after adding 6 (so not 0x3A..=0x3F); no byte
    // carries into the next when the first test holds
    v & HIGH == THREES && v.wrapping_add(0x0606_0606_0606_0606) & HIGH == THREES
}

/// The number eight ASCII digits make (little-endian: the first, most significant digit in
/// the lowest byte).
#[inline]
fn eight_digits(v: u64) -> u64 {
    let v = v - 0x3030_3030_3030_3030;
    // pairs, then fours, then the eight: each lane's value stays below its width
    let v = (v * 10 + (v >> 8)) & 0x00FF_00FF_00FF_00FF;
    let v = (v * 100 + (v >> 16)) & 0x0000_FFFF_0000_FFFF;
    (v.wrapping_mul(10_000) + (v >> 32)) & 0xFFFF_FFFF
}

/// Reads the digits of `b` from `i` on, eight at a time while eight are left, into `m`
/// (`m · 10 + digit` each, wrapping: a caller checks their count before using `m`), and
/// returns where they end. A 19-digit EuRoC stamp took 19 dependent multiply-adds.
#[inline]
pub(super) fn digits(b: &[u8], mut i: usize, m: &mut u64) -> usize {
    while let Some(w) = b.get(i..).and_then(|r| r.first_chunk::<8>()) {
        let v = u64::from_le_bytes(*w);
        if !all_digits(v) {
            break;
        }
        *m = m.wrapping_mul(100_000_000).wrapping_add(eight_digits(v));
        i += 8;
    }
    while let Some(&c) = b.get(i)
        && c.is_ascii_digit()
    {
        *m = m.wrapping_mul(10).wrapping_add(u64::from(c - b'0'));
        i += 1;
    }
    i
}

pub(super) fn trim(s: &[u8]) -> &[u8] {
    let a = s
        .iter()
        .position(|b| !b.is_ascii_whitespace() && *b != b'"')
        .unwrap_or(s.len());
    let b = s
        .iter()
        .rposition(|b| !b.is_ascii_whitespace() && *b != b'"')
        .map_or(a, |p| p + 1);
    &s[a..b.max(a)]
}

pub(super) fn num(s: &[u8]) -> Option<f64> {
    fast_float2::parse(trim(s)).ok()
}

/// Bytes a line may have and still be read as a row (a row of hundreds of columns takes a
/// few kB; a longer line is damage, not parsed).
pub(super) const MAX_LINE_BYTES: usize = 1 << 20;

/// Bytes of a line a warning quotes at most.
pub(super) const EXCERPT_BYTES: usize = 32;

/// A short, printable excerpt of a field or line for a warning (never the whole of a long
/// one).
pub(super) fn excerpt(b: &[u8]) -> String {
    let cut = b.len() > EXCERPT_BYTES;
    let s: String = String::from_utf8_lossy(&b[..b.len().min(EXCERPT_BYTES)])
        .chars()
        .map(|c| if c.is_control() { '?' } else { c })
        .collect();
    if cut {
        format!("{s}... ({} bytes)", b.len())
    } else {
        s
    }
}

/// The fields of a raw line (delimiters counted, quotes not honoured) and how many of them
/// are numbers.
pub(super) fn raw_fields(line: &[u8], lay: &Layout) -> (usize, usize) {
    let line = line.strip_suffix(b"\n").unwrap_or(line);
    let line = line.strip_suffix(b"\r").unwrap_or(line);
    let numeric = |f: &[u8]| usize::from(!trim(f).is_empty() && num(f).is_some());
    match lay.delim {
        Delim::Byte(d) => line
            .split(|&c| c == d)
            .fold((0, 0), |(n, k), f| (n + 1, k + numeric(f))),
        Delim::Whitespace(_) => line
            .split(|&c| c == b' ' || c == b'\t')
            .filter(|f| !f.is_empty())
            .fold((0, 0), |(n, k), f| (n + 1, k + numeric(f))),
    }
}

/// What one byte range of the body gave; its rows are written into its slot of the
/// topic's columns.
#[derive(Default)]
pub(super) struct Chunk<'a> {
    /// The range's rows: its slot of the columns, filled from the start.
    pub(super) slot: RowsMut<'a>,
    pub(super) got: Summary,
    /// The runs of malformed lines, counted at the range's end.
    pub(super) runs: Vec<Run>,
}

/// What a range gave besides its rows.
#[derive(Default)]
pub(super) struct Summary {
    /// Rows in the slot.
    pub(super) filled: usize,
    /// Lines in the range (so later ranges know their line numbers).
    pub(super) lines: u64,
    pub(super) bad: u64,
    /// Line (in the range, 1-based) and reason of the first malformed line.
    pub(super) first_bad: Option<(u64, String)>,
    /// Rows the malformed lines held ([`Chunk::malformed`]).
    pub(super) lost: u64,
    /// The order of the range's stamps.
    pub(super) order: Order,
}

/// How the stamps of a range follow each other: counts and first lines (in the range) of
/// those that go backwards or repeat, and the range's first and last stamps (with the
/// first one's line), for the check across ranges.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct Order {
    pub(super) first: Option<(u64, u64)>,
    pub(super) last: Option<u64>,
    pub(super) back: u64,
    pub(super) first_back: Option<u64>,
    pub(super) dup: u64,
    pub(super) first_dup: Option<u64>,
}

impl Order {
    #[inline]
    pub(super) fn next(&mut self, line: u64, t: u64) {
        match self.last {
            None => self.first = Some((t, line)),
            Some(p) if t < p => {
                self.back += 1;
                self.first_back.get_or_insert(line);
            }
            Some(p) if t == p => {
                self.dup += 1;
                self.first_dup.get_or_insert(line);
            }
            Some(_) => {}
        }
        self.last = Some(t);
    }
}

/// The row of a record's fields (`get(i)`: field `i`), or why not. Without a time column
/// the stamp is 0 and numbered later.
pub(super) fn row_of<'f>(
    lay: &Layout,
    n_fields: usize,
    get: impl Fn(usize) -> Option<&'f [u8]>,
) -> Result<Row, BadRow> {
    if n_fields != lay.n_cols {
        return Err(BadRow(format!(
            "{n_fields} fields, the file's rows have {}",
            lay.n_cols
        )));
    }
    let t = match lay.time {
        Some(i) => {
            let f = get(i)
                .ok_or_else(|| BadRow(format!("{n_fields} fields, the time is field {}", i + 1)))?;
            parse_time_ns(f, lay.time_unit).ok_or_else(|| {
                BadRow(format!(
                    "time '{}' is not a non-negative number",
                    excerpt(f)
                ))
            })?
        }
        None => 0,
    };
    let three = |cols: Option<[usize; 3]>, si: f64| -> Result<[f64; 3], BadRow> {
        let Some(c) = cols else {
            return Ok([f64::NAN; 3]);
        };
        let mut v = [0.0; 3];
        for a in 0..3 {
            let f = get(c[a]).ok_or_else(|| {
                BadRow(format!("{n_fields} fields, expected at least {}", c[a] + 1))
            })?;
            v[a] = num(f).ok_or_else(|| {
                BadRow(format!(
                    "field {} '{}' is not a number",
                    c[a] + 1,
                    excerpt(f)
                ))
            })? * si;
        }
        Ok(v)
    };
    let gyro = three(lay.gyro, lay.gyro_si)?;
    let acc = three(lay.acc, lay.acc_si)?;
    Ok(Row {
        stamp: t,
        acc,
        gyro,
    })
}

/// Why a line is no row (counted, and the first one said with its line number).
#[derive(Debug, Clone, PartialEq, Eq)]
pub(super) struct BadRow(pub(super) String);

impl Chunk<'_> {
    pub(super) fn take(&mut self, line: u64, r: Result<Row, BadRow>) {
        match r {
            Ok(row) if self.got.filled < self.slot.cap() => {
                self.slot.set_row(self.got.filled, row.stamp, &row);
                self.got.filled += 1;
                self.got.order.next(line, row.stamp);
            }
            Ok(_) => self.take(
                line,
                Err(BadRow(
                    "more rows than lines in a range (a reader defect)".into(),
                )),
            ),
            Err(why) => {
                self.got.bad += 1;
                self.got.first_bad.get_or_insert((line, why.0));
            }
        }
    }

    /// A malformed line `line` (raw bytes `raw`; `cut`: the file ends inside it, a row
    /// however little of it is left): counted with the run of consecutive malformed lines it
    /// belongs to ([`Summary::lost`]).
    pub(super) fn malformed(&mut self, line: u64, raw: &[u8], lay: &Layout, cut: bool) {
        let (_, numbers) = raw_fields(raw, lay);
        let (numbers, bytes) = (numbers as u64, raw.len() as u64);
        match self.runs.last_mut() {
            Some(r) if r.last + 1 >= line => {
                r.last = line;
                r.numbers += numbers;
                r.bytes += bytes;
                r.cut |= cut;
            }
            _ => self.runs.push(Run {
                last: line,
                numbers,
                bytes,
                cut,
            }),
        }
    }

    /// The rows the runs of malformed lines held, from the numbers and bytes in them
    /// against a row's (`row_bytes`: a row line's length in the range): a row whose value
    /// is damaged holds most of a row's numbers and a row's bytes, two rows run together
    /// twice as many, a row split in two has them across its two lines (a piece alone
    /// is no row), a line with no number in it (junk inserted) held no row, and a long line
    /// holds no more rows than its numbers fill.
    pub(super) fn count_runs(&mut self, lay: &Layout, row_bytes: f64) {
        let cols = lay.n_cols.max(1) as f64;
        for r in self.runs.drain(..) {
            if r.numbers == 0 {
                continue;
            }
            let by_numbers = r.numbers as f64 / cols;
            let by_bytes = r.bytes as f64 / row_bytes.max(1.0);
            let rows = by_numbers.max(by_bytes.min(by_numbers.ceil())).round() as u64;
            self.got.lost += if r.cut { rows.max(1) } else { rows };
        }
    }
}

/// A run of consecutive malformed lines: its last line, the numbers and bytes in it, and
/// whether it ends the file without a line end.
#[derive(Debug, Clone, Copy)]
pub(super) struct Run {
    last: u64,
    numbers: u64,
    bytes: u64,
    cut: bool,
}

/// Reads `text` with the `csv` crate (quoting, comments, flexible rows): each line
/// [`fast_row`] does not take. A quoted field never runs past its line: a line is read on its
/// own (a quote left open by damage costs that line only).
pub(super) fn parse_csv(text: &[u8], lay: &Layout, line0: u64, out: &mut Chunk) -> u64 {
    let (delim, ws) = match lay.delim {
        Delim::Byte(b) => (b, false),
        Delim::Whitespace(b) => (b, true),
    };
    let mut rdr = csv::ReaderBuilder::new()
        .has_headers(false)
        .flexible(true)
        .delimiter(delim)
        .comment(Some(b'#'))
        .quoting(!ws)
        // a line ends at LF only: a CR inside a line is damage, not a line end
        .terminator(csv::Terminator::Any(b'\n'))
        .from_reader(text);
    let mut rec = csv::ByteRecord::new();
    // a record's line: the line of the last byte the reader took for it (the csv crate's own
    // record position is where it started reading, before skipped comment and blank lines)
    let (mut at, mut line) = (0usize, line0);
    let mut line_of = |end: u64| {
        let b = (end.saturating_sub(1) as usize).min(text.len()).max(at);
        line += text[at..b].iter().filter(|&&c| c == b'\n').count() as u64;
        at = b;
        line
    };
    loop {
        match rdr.read_byte_record(&mut rec) {
            Ok(false) => break,
            Ok(true) => {}
            Err(e) => {
                let line = line_of(rdr.position().byte());
                out.got.bad += 1;
                let why = e.to_string();
                out.got
                    .first_bad
                    .get_or_insert((line, excerpt(why.as_bytes())));
                continue;
            }
        }
        let line = line_of(rdr.position().byte());
        // whitespace: runs of spaces and tabs separate fields
        let ws_fields = || {
            rec.iter()
                .flat_map(|f| f.split(|&c| c == b'\t'))
                .filter(|f| !f.is_empty())
        };
        let n_fields = if ws { ws_fields().count() } else { rec.len() };
        if n_fields == 0 || n_fields == 1 && rec.get(0).is_some_and(|f| trim(f).is_empty()) {
            continue; // blank line
        }
        let r = row_of(lay, n_fields, |i| {
            if ws { ws_fields().nth(i) } else { rec.get(i) }
        });
        out.take(line, r);
    }
    let lines = text.iter().filter(|&&c| c == b'\n').count() as u64;
    lines + u64::from(!text.is_empty() && !text.ends_with(b"\n"))
}

/// What a column of the fast path holds.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum Col {
    Skip,
    Time,
    Gyro(usize),
    Acc(usize),
}

/// The columns of a layout, in file order, up to the last one read.
pub(super) fn columns(lay: &Layout) -> Vec<Col> {
    let mut c = Vec::new();
    let mut set = |i: usize, v: Col| {
        if c.len() <= i {
            c.resize(i + 1, Col::Skip);
        }
        c[i] = v;
    };
    if let Some(i) = lay.time {
        set(i, Col::Time);
    }
    for (k, &i) in lay.gyro.iter().flatten().enumerate() {
        set(i, Col::Gyro(k));
    }
    for (k, &i) in lay.acc.iter().flatten().enumerate() {
        set(i, Col::Acc(k));
    }
    c
}

/// One pass over a plain line (no quotes, no comment, every field where the layout says):
/// the row and the bytes it took with its line end; `None` hands the line to the `csv`
/// crate ([`parse_csv`]), which reads it or says why not. Trailing columns past the last
/// one read are skipped.
// Long because: the hot loop of the text reader (every field of every line); one body
// keeps the position and the row in registers, and issue 20's benchmark holds it to time.
pub(super) fn fast_row(b: &[u8], lay: &Layout, cols: &[Col]) -> Option<(Row, usize)> {
    let ws = matches!(lay.delim, Delim::Whitespace(_));
    let d = match lay.delim {
        Delim::Byte(x) => x,
        Delim::Whitespace(_) => b' ',
    };
    let blank = |c: u8| c == b' ' || c == b'\t';
    let mut i = 0;
    let mut row = Row {
        stamp: 0,
        acc: [f64::NAN; 3],
        gyro: [f64::NAN; 3],
    };
    for (k, col) in cols.iter().enumerate() {
        while i < b.len() && blank(b[i]) && (ws || d != b'\t') {
            i += 1;
        }
        match col {
            Col::Time => {
                // an integer of up to 19 digits (EuRoC's ns; 10^19 < 2^64) eight digits at
                // a time, else every form
                let st = i;
                let mut v = 0u64;
                i = digits(b, i, &mut v);
                if i - st > 19 || b.get(i) == Some(&b'.') || i == st {
                    i = st
                        + b[st..]
                            .iter()
                            .position(|&c| !(c.is_ascii_digit() || c == b'.'))
                            .unwrap_or(b.len() - st);
                    row.stamp = parse_time_ns(&b[st..i], lay.time_unit)?;
                } else {
                    row.stamp = v.checked_mul(lay.time_unit.nanos())?;
                }
            }
            Col::Gyro(a) | Col::Acc(a) => {
                let (v, n) = fast_float2::parse_partial::<f64, _>(&b[i..]).ok()?;
                i += n;
                match col {
                    Col::Gyro(_) => row.gyro[*a] = v * lay.gyro_si,
                    _ => row.acc[*a] = v * lay.acc_si,
                }
            }
            Col::Skip => {
                while i < b.len()
                    && b[i] != d
                    && b[i] != b'\n'
                    && b[i] != b'\r'
                    && !(ws && blank(b[i]))
                {
                    if b[i] == b'"' {
                        return None;
                    }
                    i += 1;
                }
            }
        }
        while i < b.len() && blank(b[i]) && (ws || d != b'\t') {
            i += 1;
        }
        let last = k + 1 == cols.len();
        if !last {
            if ws {
                if i == 0 || !blank(b[i - 1]) {
                    return None;
                }
            } else if b.get(i) == Some(&d) {
                i += 1;
            } else {
                return None;
            }
        }
    }
    // the line end, straight after the last column read (the usual case)
    let extra = lay.n_cols.saturating_sub(cols.len());
    match (b.get(i), b.get(i + 1)) {
        (None, _) if extra == 0 => return (i > 0).then_some((row, i)),
        (Some(b'\n'), _) if extra == 0 => return Some((row, i + 1)),
        (Some(b'\r'), Some(b'\n')) if extra == 0 => return Some((row, i + 2)),
        _ => {}
    }
    // the rest of the line: the further columns the file's rows have, skipped (no quote in
    // them); a line with more or fewer is no row
    let rest = &b[i..];
    let end = memchr::memchr(b'\n', rest).unwrap_or(rest.len());
    let tail = &rest[..end];
    let t = tail.strip_suffix(b"\r").unwrap_or(tail);
    let ok = t.is_empty() || (ws && blank(t[0])) || (!ws && t[0] == d);
    if !ok || t.contains(&b'"') || t.contains(&b'#') {
        return None;
    }
    let more = if ws {
        t.split(|&c| blank(c)).filter(|f| !f.is_empty()).count()
    } else {
        memchr::memchr_iter(d, t).count()
    };
    if more != extra {
        return None;
    }
    let took = i + end + usize::from(end < rest.len());
    (took > 0).then_some((row, took))
}

/// A range being read: its text, where reading is, the lines read so far and what it gave.
struct Cursor<'t, 'a> {
    text: &'t [u8],
    pos: usize,
    line: u64,
    out: Chunk<'a>,
}

impl Cursor<'_, '_> {
    fn done(&self) -> bool {
        self.pos >= self.text.len()
    }

    /// Reads the next line by [`fast_row`], else by the csv crate.
    fn line_by_line(&mut self, lay: &Layout, cols: &[Col]) {
        self.line += 1;
        let rest = &self.text[self.pos..];
        if let Some((row, took)) = fast_row(rest, lay, cols) {
            self.out.take(self.line, Ok(row));
            self.pos += took;
            return;
        }
        let end = memchr::memchr(b'\n', rest).map_or(rest.len(), |p| p + 1);
        let raw = &rest[..end];
        // a CR inside the line: a line end too, as pandas reads it (a damaged LF of a CRLF
        // file leaves one); each piece is read as a line of its own
        let inner = raw.strip_suffix(b"\n").unwrap_or(raw);
        let inner = inner.strip_suffix(b"\r").unwrap_or(inner);
        // the file's last line, cut short
        let cut = !raw.ends_with(b"\n");
        if memchr::memchr(b'\r', inner).is_some() {
            let pieces: Vec<&[u8]> = inner
                .split(|&c| c == b'\r')
                .filter(|p| !p.is_empty())
                .collect();
            for (k, piece) in pieces.iter().enumerate() {
                self.read_line(piece, lay, cols, cut && k + 1 == pieces.len());
            }
            self.pos += end;
            return;
        }
        self.read_line(raw, lay, cols, cut);
        self.pos += end;
    }

    /// A line (`raw`; `cut`: the file ends inside it) [`fast_row`] did not take: read by the
    /// csv crate, its damage counted.
    fn read_line(&mut self, raw: &[u8], lay: &Layout, cols: &[Col], cut: bool) {
        if raw.len() > MAX_LINE_BYTES {
            // no row is this long: not parsed (the csv crate would hold it whole)
            self.out.take(
                self.line,
                Err(BadRow(format!(
                    "a line of {} bytes, longer than any row",
                    raw.len()
                ))),
            );
            self.out.malformed(self.line, raw, lay, cut);
            return;
        }
        if let Some((row, took)) = fast_row(raw, lay, cols)
            && took == raw.len()
        {
            self.out.take(self.line, Ok(row));
            return;
        }
        let bad = self.out.got.bad;
        if comment_row(raw, lay) {
            // a comment that holds a row's numbers: a row whose first byte is damaged
            self.out.take(
                self.line,
                Err(BadRow(format!(
                    "a comment line that holds a row's numbers: '{}'",
                    excerpt(raw)
                ))),
            );
        } else {
            parse_csv(raw, lay, self.line, &mut self.out);
        }
        if self.out.got.bad > bad {
            self.out.malformed(self.line, raw, lay, cut);
        }
    }
}

/// One range: each line by [`fast_row`], else by the csv crate.
pub(super) fn parse_lines<'a>(text: &[u8], lay: &Layout, out: Chunk<'a>) -> Chunk<'a> {
    let cols = columns(lay);
    let mut c = Cursor {
        text,
        pos: 0,
        line: 0,
        out,
    };
    while !c.done() {
        c.line_by_line(lay, &cols);
    }
    c.out.got.lines = c.line;
    // a row line's length: the range's bytes over its lines
    let row_bytes = c.text.len() as f64 / (c.line.max(1) as f64);
    c.out.count_runs(lay, row_bytes);
    c.out
}

/// True for a comment line (`#`) whose fields are the row's count and mostly numbers: a
/// data row whose first byte is damaged (a `#` comment in a log holds words).
fn comment_row(raw: &[u8], lay: &Layout) -> bool {
    let t = raw.trim_ascii_start();
    let Some(rest) = t.strip_prefix(b"#") else {
        return false;
    };
    let (n, numbers) = raw_fields(rest, lay);
    n == lay.n_cols && 2 * numbers >= n
}

/// Rows a range of text can hold: one per line, as [`parse_lines`] counts them.
pub(super) fn room(text: &[u8]) -> usize {
    memchr::memchr_iter(b'\n', text).count() + usize::from(text.last().is_some_and(|&c| c != b'\n'))
}

/// The lines of the body that start in `a..b` (file offsets): the range of `bytes` they
/// take. Ranges that partition the body partition its lines.
pub(super) fn line_range(bytes: &[u8], body: usize, (a, b): (usize, usize)) -> (usize, usize) {
    // the first line start at or after offset x
    let start_at = |x: usize| -> usize {
        if x <= body {
            return x;
        }
        if x >= bytes.len() {
            return bytes.len();
        }
        bytes[x - 1..]
            .iter()
            .position(|&c| c == b'\n')
            .map_or(bytes.len(), |p| x + p)
    };
    let e = start_at(b);
    (start_at(a).min(e), e)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rows::Rows;

    /// The one-pass reader and the csv crate give the same rows, and the lines the one
    /// pass does not take go to the csv crate.
    #[test]
    fn the_fast_path_reads_what_the_csv_crate_reads() {
        let lay = |delim, time: Option<usize>| {
            Layout::for_test(delim, time, ([1, 2, 3], [5, 6, 7]), (0.5, 2.0))
        };
        let csv = "1,0.5,-1e-3,3,temp,1.25e2,-0,7,extra\r\n2, 0.25 ,2,3,x,4,5,6\n# comment\n\n3,1,2,3,\"q\",4,5,6\n4,1,2\n5,1,2,3,x,4,5,nan";
        let ws = "  1   0.5 -1e-3\t3 t 1.25e2 -0 7\n2 1 2 3 x 4 5 6 9 9\n";
        for (text, d) in [(csv, Delim::Byte(b',')), (ws, Delim::Whitespace(b' '))] {
            let l = lay(d, Some(0));
            let n = room(text.as_bytes());
            let (mut fast_rows, mut slow_rows) = (Rows::zeroed(n), Rows::zeroed(n));
            let fast = parse_lines(
                text.as_bytes(),
                &l,
                Chunk {
                    slot: fast_rows.split(&[n]).remove(0),
                    ..Chunk::default()
                },
            );
            let mut slow = Chunk {
                slot: slow_rows.split(&[n]).remove(0),
                ..Chunk::default()
            };
            slow.got.lines = parse_csv(text.as_bytes(), &l, 1, &mut slow);
            assert!(
                fast.got.filled > 0 && fast.got.filled == slow.got.filled,
                "{text:?}"
            );
            let (fo, so) = (fast.got.order, slow.got.order);
            assert_eq!(
                (fo.first, fo.last, fo.back, fo.dup),
                (so.first, so.last, so.back, so.dup)
            );
            assert_eq!(
                (fast.got.bad, fast.got.lines),
                (slow.got.bad, slow.got.lines)
            );
            assert_eq!(fast.got.first_bad, slow.got.first_bad);
            let filled = fast.got.filled;
            drop((fast, slow));
            for i in 0..filled {
                let (a, b) = (fast_rows.row(i), slow_rows.row(i));
                assert_eq!(format!("{a:?}"), format!("{b:?}"), "{text:?}");
                assert_eq!(fast_rows.record_time[i], slow_rows.record_time[i]);
            }
        }
    }

    /// Integer fields of a seeded corpus.
    const DIGIT_STRINGS: usize = 1_000_000;

    /// [`digits`] reads what `str::parse::<u64>` reads, for every length up to 19 digits
    /// (leading zeros, any byte after them), and stops where the digits stop.
    #[test]
    fn digits_read_as_str_parse_reads_them() {
        let mut st = 0x2026_1208_D161_7500_u64;
        let mut next = || {
            st = st
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            st >> 17
        };
        for n in 0..DIGIT_STRINGS {
            let len = 1 + (next() % 19) as usize;
            let s: String = (0..len)
                .map(|_| char::from(b'0' + (next() % 10) as u8))
                .collect();
            let after = [",", "\n", ".5", "x", "", " ", ":"][(next() % 7) as usize];
            let text = format!("{s}{after}");
            let lead = (next() % 3) as usize;
            let text = format!("{}{text}", "a".repeat(lead));
            let mut m = 0;
            let end = digits(text.as_bytes(), lead, &mut m);
            assert_eq!(end, lead + len, "string {n}: {text:?}");
            assert_eq!(Some(m), s.parse::<u64>().ok(), "string {n}: {text:?}");
        }
    }

    #[test]
    fn times_keep_every_digit() {
        assert_eq!(
            parse_time_ns(b"1403636579758555392", TimeUnit::Ns),
            Some(1403636579758555392)
        );
        assert_eq!(
            parse_time_ns(b"1403636579.758555392", TimeUnit::S),
            Some(1403636579758555392)
        );
        assert_eq!(parse_time_ns(b"12.5", TimeUnit::Ms), Some(12_500_000));
        assert_eq!(parse_time_ns(b"0.0000000016", TimeUnit::S), Some(2));
        assert_eq!(parse_time_ns(b"1e-3", TimeUnit::S), Some(1_000_000));
        assert_eq!(parse_time_ns(b"-1", TimeUnit::S), None);
        assert_eq!(parse_time_ns(b"abc", TimeUnit::S), None);
    }
}
