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
//! The body is read with the `csv` crate (one reader per byte range, in parallel) and the
//! numbers with `fast-float2`; times are parsed as decimals straight to nanoseconds, so
//! `1403636579.758555` s keeps every digit.

use std::path::{Path, PathBuf};

use rayon::prelude::*;

use super::InputOptions;
use crate::RosTime;
use crate::decoded::{DecodedSource, Row, Stream};
use crate::error::Error;
use crate::series::{Rows, RowsMut};
use crate::source::InputKind;

/// Bytes looked at to decide whether a file is text, and to find its header.
pub const SNIFF_BYTES: usize = 64 * 1024;
/// Lines that fail to parse beyond this fraction of the data lines (and beyond
/// [`MIN_BAD_LIMIT`]) make the file an error rather than a log with a few damaged lines.
pub const MAX_BAD_FRACTION: f64 = 0.01;
/// Malformed lines always tolerated (with warnings), whatever the file's length.
pub const MIN_BAD_LIMIT: u64 = 10;
/// Standard gravity, m/s² (the `g` unit; CGPM 1901).
pub const STANDARD_GRAVITY: f64 = 9.80665;
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

/// Unit of a time column.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TimeUnit {
    /// Seconds.
    S,
    /// Milliseconds.
    Ms,
    /// Microseconds.
    Us,
    /// Nanoseconds.
    Ns,
}

impl TimeUnit {
    /// Nanoseconds per unit.
    pub(crate) fn nanos(self) -> u64 {
        match self {
            TimeUnit::S => 1_000_000_000,
            TimeUnit::Ms => 1_000_000,
            TimeUnit::Us => 1_000,
            TimeUnit::Ns => 1,
        }
    }
    /// The name.
    pub(crate) fn name(self) -> &'static str {
        match self {
            TimeUnit::S => "s",
            TimeUnit::Ms => "ms",
            TimeUnit::Us => "us",
            TimeUnit::Ns => "ns",
        }
    }
    /// From a flag or header text.
    pub(crate) fn parse(s: &str) -> Result<TimeUnit, String> {
        match unit_key(s).as_str() {
            "s" | "sec" | "secs" | "second" | "seconds" => Ok(TimeUnit::S),
            "ms" | "msec" => Ok(TimeUnit::Ms),
            "us" | "µs" | "usec" => Ok(TimeUnit::Us),
            "ns" | "nsec" => Ok(TimeUnit::Ns),
            _ => Err(format!("'{s}' is not a time unit (s, ms, us, ns)")),
        }
    }
}

/// Unit of the gyroscope columns.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum GyroUnit {
    /// rad/s.
    RadS,
    /// deg/s.
    DegS,
}

impl GyroUnit {
    /// rad/s per unit.
    pub(crate) fn si(self) -> f64 {
        match self {
            GyroUnit::RadS => 1.0,
            GyroUnit::DegS => std::f64::consts::PI / 180.0,
        }
    }
    /// The name.
    pub(crate) fn name(self) -> &'static str {
        match self {
            GyroUnit::RadS => "rad/s",
            GyroUnit::DegS => "deg/s",
        }
    }
    /// From a flag or header text.
    pub(crate) fn parse(s: &str) -> Result<GyroUnit, String> {
        match unit_key(s).as_str() {
            "rad/s" | "rads^-1" | "rad*s^-1" | "rads-1" | "radps" => Ok(GyroUnit::RadS),
            "deg/s" | "°/s" | "dps" | "degs^-1" | "degps" => Ok(GyroUnit::DegS),
            _ => Err(format!("'{s}' is not a gyroscope unit (rad/s, deg/s)")),
        }
    }
}

/// Unit of the accelerometer columns.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum AccUnit {
    /// m/s².
    Ms2,
    /// Standard gravity.
    G,
    /// Thousandths of standard gravity.
    Mg,
}

impl AccUnit {
    /// m/s² per unit.
    pub(crate) fn si(self) -> f64 {
        match self {
            AccUnit::Ms2 => 1.0,
            AccUnit::G => STANDARD_GRAVITY,
            AccUnit::Mg => STANDARD_GRAVITY * 1e-3,
        }
    }
    /// The name.
    pub(crate) fn name(self) -> &'static str {
        match self {
            AccUnit::Ms2 => "m/s^2",
            AccUnit::G => "g",
            AccUnit::Mg => "mg",
        }
    }
    /// From a flag or header text.
    pub(crate) fn parse(s: &str) -> Result<AccUnit, String> {
        match unit_key(s).as_str() {
            "m/s^2" | "m/s2" | "ms^-2" | "m*s^-2" | "ms-2" | "m/s/s" | "mps2" => Ok(AccUnit::Ms2),
            "g" => Ok(AccUnit::G),
            "mg" => Ok(AccUnit::Mg),
            _ => Err(format!("'{s}' is not an accelerometer unit (m/s^2, g, mg)")),
        }
    }
}

/// A unit's text without spaces, lower case (`rad s^-1` → `rads^-1`).
fn unit_key(s: &str) -> String {
    s.chars()
        .filter(|c| !c.is_whitespace())
        .flat_map(char::to_lowercase)
        .collect()
}

/// What a column holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Role {
    /// The time.
    Time,
    /// Gyroscope axis 0–2.
    Gyro(usize),
    /// Accelerometer axis 0–2.
    Acc(usize),
}

impl Role {
    fn describe(self) -> String {
        match self {
            Role::Time => "the time".into(),
            Role::Gyro(a) => format!("gyro {}", ['x', 'y', 'z'][a]),
            Role::Acc(a) => format!("acc {}", ['x', 'y', 'z'][a]),
        }
    }
}

const TIME_NAMES: [&str; 8] = [
    "t",
    "time",
    "timestamp",
    "stamp",
    "ts",
    "sec",
    "seconds",
    "fieldheaderstamp",
];
const GYRO_PREFIXES: [&str; 11] = [
    "g",
    "gyro",
    "gyr",
    "gyroscope",
    "w",
    "omega",
    "wrss",
    "angularvelocity",
    "fieldangularvelocity",
    "angvel",
    "rot",
];
const ACC_PREFIXES: [&str; 9] = [
    "a",
    "acc",
    "accel",
    "accelerometer",
    "acceleration",
    "arss",
    "linearacceleration",
    "fieldlinearacceleration",
    "linacc",
];

/// The role a column name means, and the time unit a suffix states (`time_ms`), if any.
pub(crate) fn role_of(name: &str) -> Option<(Role, Option<TimeUnit>)> {
    let n: String = name
        .chars()
        .filter(|c| c.is_ascii_alphanumeric())
        .map(|c| c.to_ascii_lowercase())
        .collect();
    // `t_s`, `time_ms`, `timestamp_ns` (a unit after a separator), then `timeus`
    let lower = name.trim().to_ascii_lowercase();
    if let Some((base, suffix)) = lower.rsplit_once(['_', ' ', '.'])
        && let Ok(u) = TimeUnit::parse(suffix)
        && ["t", "time", "timestamp", "stamp"].contains(&base)
    {
        return Some((Role::Time, Some(u)));
    }
    if TIME_NAMES.contains(&n.as_str()) {
        return Some((Role::Time, None));
    }
    for u in [TimeUnit::Ns, TimeUnit::Us, TimeUnit::Ms] {
        if let Some(base) = n.strip_suffix(u.name())
            && ["time", "timestamp", "stamp"].contains(&base)
        {
            return Some((Role::Time, Some(u)));
        }
    }
    let axis = |c: char| "xyz".find(c);
    // `gx`, `gyro_x`, `w_RS_S_x` (axis last) or `xgyro` (MAVLink's order).
    let (a, p) = match (
        n.chars().last().and_then(axis),
        n.chars().next().and_then(axis),
    ) {
        (Some(a), _) if n.len() > 1 => (a, &n[..n.len() - 1]),
        (_, Some(a)) if n.len() > 1 => (a, &n[1..]),
        _ => return None,
    };
    if GYRO_PREFIXES.contains(&p) {
        return Some((Role::Gyro(a), None));
    }
    if ACC_PREFIXES.contains(&p) {
        return Some((Role::Acc(a), None));
    }
    None
}

/// True when the first bytes of `path` are text (UTF-8, no control bytes but tab, CR, LF).
pub(crate) fn looks_like_text(path: &Path) -> bool {
    let Ok(head) = read_head(path) else {
        return false;
    };
    if head.is_empty() {
        return false;
    }
    let valid = match std::str::from_utf8(&head) {
        Ok(_) => true,
        // a multi-byte character cut by the sniff window
        Err(e) => e.error_len().is_none() && head.len() == SNIFF_BYTES,
    };
    valid
        && !head
            .iter()
            .any(|&b| b < 0x20 && b != b'\t' && b != b'\n' && b != b'\r')
}

fn read_head(path: &Path) -> std::io::Result<Vec<u8>> {
    use std::io::Read;
    let mut v = Vec::with_capacity(SNIFF_BYTES);
    std::fs::File::open(path)?
        .take(SNIFF_BYTES as u64)
        .read_to_end(&mut v)?;
    Ok(v)
}

/// How fields are separated.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Delim {
    Byte(u8),
    /// Runs of spaces (or of tabs).
    Whitespace(u8),
}

/// Everything the preamble and the options decided.
#[derive(Debug, Clone)]
struct Layout {
    delim: Delim,
    /// Column index of the time, or `None` (a rate is given).
    time: Option<usize>,
    gyro: Option<[usize; 3]>,
    acc: Option<[usize; 3]>,
    time_unit: TimeUnit,
    /// Multiplier from the file's value to SI, per sensor.
    gyro_si: f64,
    acc_si: f64,
    /// True where the unit was stated (header, flag or a known layout); false: SI assumed
    /// and checked for plausibility.
    gyro_stated: bool,
    acc_stated: bool,
    /// Byte offset and 1-based line number of the first line after the preamble.
    body: usize,
    body_line: u64,
    /// What the layout is, for notes.
    what: String,
    /// The EuRoC/ASL header was found.
    euroc: bool,
}

/// The header of bag2mat's own CSV output (t in s, m/s², rad/s).
pub const BAG2MAT_CSV_HEADER: &str = "t,ax,ay,az,wx,wy,wz";

fn split_fields(line: &str, delim: Delim) -> Vec<&str> {
    match delim {
        Delim::Byte(b) => line.split(b as char).map(str::trim).collect(),
        Delim::Whitespace(_) => line.split_whitespace().collect(),
    }
}

fn is_number(s: &str) -> bool {
    let s = s.trim().trim_matches('"');
    !s.is_empty() && fast_float2::parse::<f64, _>(s).is_ok()
}

fn is_comment(line: &str) -> bool {
    let l = line.trim_start();
    l.starts_with('#') || l.starts_with('%') || l.starts_with("//")
}

fn strip_comment(line: &str) -> &str {
    let l = line.trim_start();
    l.trim_start_matches('#')
        .trim_start_matches('%')
        .trim_start_matches("//")
}

fn pick_delim(line: &str) -> Delim {
    for b in [b',', b'\t', b';'] {
        if line.as_bytes().contains(&b) {
            return Delim::Byte(b);
        }
    }
    Delim::Whitespace(b' ')
}

/// A header field's name and the unit in its last `[...]` or `(...)`.
fn name_and_unit(field: &str) -> (&str, Option<&str>) {
    let f = field.trim().trim_matches('"');
    for (open, close) in [('[', ']'), ('(', ')')] {
        if let (Some(a), Some(b)) = (f.rfind(open), f.rfind(close))
            && a < b
        {
            return (f[..a].trim(), Some(f[a + 1..b].trim()));
        }
    }
    (f, None)
}

fn bad(path: &Path, what: String) -> Error {
    Error::Log {
        path: path.to_path_buf(),
        what,
    }
}

/// Finds the header, delimiter, columns and units.
fn layout(path: &Path, head: &[u8], file_len: u64, opts: &InputOptions) -> Result<Layout, Error> {
    let head = &head[..head.len().min(SNIFF_BYTES)];
    let head = match std::str::from_utf8(head) {
        Ok(s) => s,
        Err(e) => std::str::from_utf8(&head[..e.valid_up_to()]).unwrap_or(""),
    };
    let not_table = |why: &str| Error::NotABag {
        path: path.to_path_buf(),
        what: format!(
            "it is text, but {why}. Accepted: {}",
            crate::source::ACCEPTED
        ),
    };
    // The preamble: blank and comment lines, then a header or the first data line.
    let mut offset = 0usize;
    let mut line_no = 0u64;
    let mut last_comment: Option<&str> = None;
    let mut header: Option<&str> = None;
    let mut first_data: Option<&str> = None;
    let (mut body, mut body_line) = (0usize, 1u64);
    for raw in head.split_inclusive('\n') {
        if !raw.ends_with('\n') && ((raw.len() + offset) as u64) < file_len {
            break; // cut by the sniff window
        }
        line_no += 1;
        let start = offset;
        offset += raw.len();
        let line = raw.trim_end_matches(['\n', '\r']);
        if line.trim().is_empty() {
            continue;
        }
        if is_comment(line) {
            last_comment = Some(line);
            continue;
        }
        let d = pick_delim(line);
        let fields = split_fields(line, d);
        if fields.iter().all(|f| is_number(f)) {
            first_data = Some(line);
            body = start;
            body_line = line_no;
            // a comment right before the data with as many fields is its header (EuRoC)
            if header.is_none()
                && let Some(c) = last_comment
            {
                let c = strip_comment(c);
                let cf = split_fields(c, pick_delim(c));
                if cf.len() == fields.len() && cf.iter().any(|f| !is_number(f)) {
                    header = Some(c);
                }
            }
            break;
        }
        if header.is_some() {
            return Err(not_table(&format!(
                "line {line_no} is neither a number row nor a comment after the header line"
            )));
        }
        header = Some(line);
        last_comment = None;
    }
    let Some(data) = first_data else {
        return Err(not_table(&format!(
            "no line of numbers in its first {} bytes",
            head.len()
        )));
    };
    let delim = pick_delim(header.unwrap_or(data));
    let delim = match (delim, pick_delim(data)) {
        (Delim::Whitespace(_), Delim::Byte(b)) => Delim::Byte(b),
        (d, _) => d,
    };
    let delim = match delim {
        Delim::Whitespace(_) if data.contains('\t') && !data.contains(' ') => {
            Delim::Whitespace(b'\t')
        }
        d => d,
    };
    let n_cols = split_fields(data, delim).len();

    // Roles: --columns, else the header.
    let mut roles: Vec<Option<(Role, Option<TimeUnit>)>> = Vec::new();
    let mut units: Vec<Option<String>> = Vec::new();
    let names: Vec<String>;
    let from_flag = opts.columns.is_some();
    if let Some(cols) = &opts.columns {
        names = cols.split(',').map(|s| s.trim().to_string()).collect();
        for n in &names {
            if n == "_" || n == "-" || n.is_empty() {
                roles.push(None);
            } else {
                roles.push(Some(role_of(n).ok_or_else(|| {
                    bad(
                        path,
                        format!(
                            "--columns: '{n}' names no column bag2mat reads (t, gx gy gz, ax ay az, or _ to skip)"
                        ),
                    )
                })?));
            }
            units.push(None);
        }
        if names.len() > n_cols {
            return Err(bad(
                path,
                format!(
                    "--columns names {} columns, the file's rows have {n_cols}",
                    names.len()
                ),
            ));
        }
    } else if let Some(h) = header {
        names = split_fields(h, delim)
            .iter()
            .map(|s| s.to_string())
            .collect();
        for f in &names {
            let (n, u) = name_and_unit(f);
            roles.push(role_of(n));
            units.push(u.map(str::to_string));
        }
    } else {
        return Err(bad(
            path,
            format!(
                "the text log has no header line naming its {n_cols} columns: give them with --columns (e.g. --columns t,gx,gy,gz,ax,ay,az, _ to skip one) and their units (--time-unit, --gyro-unit, --acc-unit)"
            ),
        ));
    }
    let own_layout = !from_flag && header.map(str::trim) == Some(BAG2MAT_CSV_HEADER);
    let euroc =
        !from_flag && header.is_some_and(|h| h.contains("w_RS_S_x") && h.contains("a_RS_S_x"));
    let mut found: Vec<(Role, usize)> = Vec::new();
    for (i, r) in roles.iter().enumerate() {
        let Some((role, _)) = r else { continue };
        if let Some((_, j)) = found.iter().find(|(x, _)| x == role) {
            return Err(bad(
                path,
                format!(
                    "columns '{}' ({}) and '{}' ({}) both look like {}: say which with --columns (e.g. --columns t,gx,gy,gz,ax,ay,az, _ to skip one)",
                    names[*j],
                    j + 1,
                    names[i],
                    i + 1,
                    role.describe()
                ),
            ));
        }
        found.push((*role, i));
    }
    let col = |r: Role| found.iter().find(|(x, _)| *x == r).map(|(_, i)| *i);
    let sensor = |mk: fn(usize) -> Role, what: &str| -> Result<Option<[usize; 3]>, Error> {
        let c: Vec<Option<usize>> = (0..3).map(|a| col(mk(a))).collect();
        match c.iter().filter(|x| x.is_some()).count() {
            0 => Ok(None),
            3 => Ok(Some([
                c[0].unwrap_or(0),
                c[1].unwrap_or(0),
                c[2].unwrap_or(0),
            ])),
            _ => Err(bad(
                path,
                format!(
                    "the {what} has {} of its three axis columns ({}): name all three with --columns",
                    c.iter().filter(|x| x.is_some()).count(),
                    names.join(", ")
                ),
            )),
        }
    };
    let gyro = sensor(Role::Gyro, "gyroscope")?;
    let acc = sensor(Role::Acc, "accelerometer")?;
    if gyro.is_none() && acc.is_none() {
        return Err(not_table(&format!(
            "no column of its header ({}) names a gyroscope or accelerometer axis (gx/gyro_x/wx/w_RS_S_x, ax/acc_x/a_RS_S_x, …): name them with --columns",
            names.join(", ")
        )));
    }
    let time = col(Role::Time);
    if time.is_some() && opts.rate.is_some() {
        return Err(bad(
            path,
            "the log has a time column and a rate was given: give one of them (drop the rate, or skip the time column with --columns and _)".into(),
        ));
    }
    if time.is_none() && opts.rate.is_none() {
        return Err(bad(
            path,
            format!(
                "no time column among {} (t, time, timestamp, …): name it with --columns, or give the sample rate (--rate, in every tool)",
                names.join(", ")
            ),
        ));
    }
    // Units: stated by the header, the flag, or the layout; a contradiction is an error.
    let stated = |cols: &[usize]| -> Vec<String> {
        let mut u: Vec<String> = cols
            .iter()
            .filter_map(|&i| units.get(i).cloned().flatten())
            .collect();
        u.dedup();
        u
    };
    let time_unit = match time {
        None => TimeUnit::Ns,
        Some(i) => {
            let header_unit = match (stated(&[i]).first(), roles[i].and_then(|r| r.1)) {
                (Some(u), _) => Some(
                    TimeUnit::parse(u)
                        .map_err(|e| bad(path, format!("header of column {}: {e}", i + 1)))?,
                ),
                (None, u) => u,
            };
            let known = own_layout.then_some(TimeUnit::S);
            match (opts.time_unit, header_unit.or(known)) {
                (Some(f), Some(h)) if f != h => {
                    return Err(bad(
                        path,
                        format!(
                            "the header says the time is in {}, --time-unit says {}",
                            h.name(),
                            f.name()
                        ),
                    ));
                }
                (Some(f), _) => f,
                (None, Some(h)) => h,
                (None, None) => {
                    return Err(bad(
                        path,
                        format!(
                            "the time column '{}' states no unit: give --time-unit s|ms|us|ns",
                            names[i]
                        ),
                    ));
                }
            }
        }
    };
    fn resolve<U: Copy + PartialEq>(
        path: &Path,
        what: &str,
        flag: Option<U>,
        header: &[String],
        parse: fn(&str) -> Result<U, String>,
        known: Option<U>,
        name: fn(U) -> &'static str,
    ) -> Result<Option<U>, Error> {
        if header.len() > 1 {
            return Err(bad(
                path,
                format!(
                    "the {what} axes state different units ({})",
                    header.join(", ")
                ),
            ));
        }
        let h = match header.first() {
            Some(u) => Some(parse(u).map_err(|e| bad(path, format!("header: {e}")))?),
            None => known,
        };
        match (flag, h) {
            (Some(f), Some(h)) if f != h => Err(bad(
                path,
                format!(
                    "the header says the {what} is in {}, the flag says {}",
                    name(h),
                    name(f)
                ),
            )),
            (Some(f), _) => Ok(Some(f)),
            (None, h) => Ok(h),
        }
    }
    let gyro_unit = match gyro {
        Some(c) => resolve(
            path,
            "gyroscope",
            opts.gyro_unit,
            &stated(&c),
            GyroUnit::parse,
            own_layout.then_some(GyroUnit::RadS),
            GyroUnit::name,
        )?,
        None => None,
    };
    let acc_unit = match acc {
        Some(c) => resolve(
            path,
            "accelerometer",
            opts.acc_unit,
            &stated(&c),
            AccUnit::parse,
            own_layout.then_some(AccUnit::Ms2),
            AccUnit::name,
        )?,
        None => None,
    };
    if opts.gyro_scale.is_some() && gyro_unit.is_none() && gyro.is_some() {
        return Err(bad(
            path,
            "--gyro-scale gives LSB per unit: say which unit with --gyro-unit rad/s|deg/s".into(),
        ));
    }
    if opts.acc_scale.is_some() && acc_unit.is_none() && acc.is_some() {
        return Err(bad(
            path,
            "--acc-scale gives LSB per unit: say which unit with --acc-unit m/s^2|g|mg".into(),
        ));
    }
    let gyro_si = gyro_unit.map_or(1.0, GyroUnit::si) / opts.gyro_scale.unwrap_or(1.0);
    let acc_si = acc_unit.map_or(1.0, AccUnit::si) / opts.acc_scale.unwrap_or(1.0);
    let mut what = format!(
        "{} columns ({}), time {}",
        n_cols,
        match delim {
            Delim::Byte(b',') => "comma-separated",
            Delim::Byte(b'\t') => "tab-separated",
            Delim::Byte(_) => "semicolon-separated",
            Delim::Whitespace(_) => "whitespace-separated",
        },
        match time {
            Some(_) => time_unit.name().to_string(),
            None => format!("from --rate {} Hz", opts.rate.unwrap_or(0.0)),
        }
    );
    let unit_text = |u: Option<&'static str>, scale: Option<f64>| match (u, scale) {
        (Some(u), Some(s)) => format!("raw counts, {s} LSB per {u}"),
        (Some(u), None) => u.to_string(),
        (None, _) => "no unit stated (SI assumed)".to_string(),
    };
    if gyro.is_some() {
        what.push_str(&format!(
            ", gyro {}",
            unit_text(gyro_unit.map(GyroUnit::name), opts.gyro_scale)
        ));
    }
    if acc.is_some() {
        what.push_str(&format!(
            ", acc {}",
            unit_text(acc_unit.map(AccUnit::name), opts.acc_scale)
        ));
    }
    let _ = n_cols;
    Ok(Layout {
        delim,
        time,
        gyro,
        acc,
        time_unit,
        gyro_si,
        acc_si,
        gyro_stated: gyro_unit.is_some(),
        acc_stated: acc_unit.is_some(),
        body,
        body_line,
        what,
        euroc,
    })
}

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

fn trim(s: &[u8]) -> &[u8] {
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

fn num(s: &[u8]) -> Option<f64> {
    fast_float2::parse(trim(s)).ok()
}

/// What one byte range of the body gave; its rows are written into its slot of the
/// topic's columns.
#[derive(Default)]
struct Chunk<'a> {
    /// The range's rows: its slot of the columns, filled from the start.
    slot: RowsMut<'a>,
    got: Summary,
}

/// What a range gave besides its rows.
#[derive(Default)]
struct Summary {
    /// Rows in the slot.
    filled: usize,
    /// Lines in the range (so later ranges know their line numbers).
    lines: u64,
    bad: u64,
    /// Line (in the range, 1-based) and reason of the first malformed line.
    first_bad: Option<(u64, String)>,
    /// A line the csv crate read held a quote: a quoted field may hold a line break, so the
    /// file is read by the csv crate whole.
    quoted: bool,
    /// The order of the range's stamps.
    order: Order,
}

/// How the stamps of a range follow each other: counts and first lines (in the range) of
/// those that go backwards or repeat, and the range's first and last stamps (with the
/// first one's line), for the check across ranges.
#[derive(Debug, Clone, Copy, Default)]
struct Order {
    first: Option<(u64, u64)>,
    last: Option<u64>,
    back: u64,
    first_back: Option<u64>,
    dup: u64,
    first_dup: Option<u64>,
}

impl Order {
    fn next(&mut self, line: u64, t: u64) {
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
fn row_of<'f>(
    lay: &Layout,
    n_fields: usize,
    get: impl Fn(usize) -> Option<&'f [u8]>,
) -> Result<Row, String> {
    let t = match lay.time {
        Some(i) => {
            let f =
                get(i).ok_or_else(|| format!("{n_fields} fields, the time is field {}", i + 1))?;
            parse_time_ns(f, lay.time_unit).ok_or_else(|| {
                format!(
                    "time '{}' is not a non-negative number",
                    String::from_utf8_lossy(f)
                )
            })?
        }
        None => 0,
    };
    let three = |cols: Option<[usize; 3]>, si: f64| -> Result<[f64; 3], String> {
        let Some(c) = cols else {
            return Ok([f64::NAN; 3]);
        };
        let mut v = [0.0; 3];
        for a in 0..3 {
            let f = get(c[a])
                .ok_or_else(|| format!("{n_fields} fields, expected at least {}", c[a] + 1))?;
            v[a] = num(f).ok_or_else(|| {
                format!(
                    "field {} '{}' is not a number",
                    c[a] + 1,
                    String::from_utf8_lossy(f)
                )
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

impl Chunk<'_> {
    fn take(&mut self, line: u64, r: Result<Row, String>) {
        match r {
            Ok(row) if self.got.filled < self.slot.cap() => {
                self.slot.set_row(self.got.filled, row.stamp, &row);
                self.got.filled += 1;
                self.got.order.next(line, row.stamp);
            }
            Ok(_) => self.take(
                line,
                Err("more rows than lines in a range (a reader defect)".into()),
            ),
            Err(why) => {
                self.got.bad += 1;
                self.got.first_bad.get_or_insert((line, why));
            }
        }
    }
}

/// Reads `text` with the `csv` crate (quoting, comments, flexible rows): for a range whose
/// fields may be quoted, and for each line [`fast_row`] does not take.
fn parse_csv(text: &[u8], lay: &Layout, line0: u64, out: &mut Chunk) -> u64 {
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
                out.got.first_bad.get_or_insert((line, e.to_string()));
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
enum Col {
    Skip,
    Time,
    Gyro(usize),
    Acc(usize),
}

/// The columns of a layout, in file order, up to the last one read.
fn columns(lay: &Layout) -> Vec<Col> {
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
fn fast_row(b: &[u8], lay: &Layout, cols: &[Col]) -> Option<(Row, usize)> {
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
                // an integer of up to 19 digits (EuRoC's ns) in one pass, else every form
                let st = i;
                let mut v = 0u64;
                while i < b.len() && b[i].is_ascii_digit() && i - st < 19 {
                    v = v * 10 + (b[i] - b'0') as u64;
                    i += 1;
                }
                if i < b.len() && (b[i] == b'.' || b[i].is_ascii_digit()) || i == st {
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
    match (b.get(i), b.get(i + 1)) {
        (None, _) => return (i > 0).then_some((row, i)),
        (Some(b'\n'), _) => return Some((row, i + 1)),
        (Some(b'\r'), Some(b'\n')) => return Some((row, i + 2)),
        _ => {}
    }
    // the rest of the line: further columns are skipped (no quote in them)
    let rest = &b[i..];
    let end = rest.iter().position(|&c| c == b'\n').unwrap_or(rest.len());
    let tail = &rest[..end];
    if !tail.is_empty() {
        let t = tail.strip_suffix(b"\r").unwrap_or(tail);
        let ok = t.is_empty() || (ws && blank(t[0])) || (!ws && t[0] == d);
        if !ok || t.contains(&b'"') || t.contains(&b'#') {
            return None;
        }
    }
    let took = i + end + usize::from(end < rest.len());
    (took > 0).then_some((row, took))
}

/// Parses the lines of `text` into `slot` (room for every line of it).
fn parse_range<'a>(text: &[u8], lay: &Layout, quoted: bool, slot: RowsMut<'a>) -> Chunk<'a> {
    let mut out = Chunk {
        slot,
        ..Chunk::default()
    };
    if quoted {
        out.got.lines = parse_csv(text, lay, 1, &mut out);
        return out;
    }
    let cols = columns(lay);
    let mut pos = 0;
    let mut line = 0u64;
    while pos < text.len() {
        line += 1;
        let rest = &text[pos..];
        if let Some((row, took)) = fast_row(rest, lay, &cols) {
            out.take(line, Ok(row));
            pos += took;
            continue;
        }
        let end = rest
            .iter()
            .position(|&c| c == b'\n')
            .map_or(rest.len(), |p| p + 1);
        out.got.quoted |= rest[..end].contains(&b'"');
        parse_csv(&rest[..end], lay, line, &mut out);
        pos += end;
    }
    out.got.lines = line;
    out
}

/// Rows a range of text can hold: one per line, as [`parse_range`] counts them.
fn room(text: &[u8]) -> usize {
    memchr::memchr_iter(b'\n', text).count() + usize::from(text.last().is_some_and(|&c| c != b'\n'))
}

/// The lines of the body that start in `a..b` (file offsets): the range of `bytes` they
/// take. Ranges that partition the body partition its lines.
fn line_range(bytes: &[u8], body: usize, (a, b): (usize, usize)) -> (usize, usize) {
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

/// A parsed text log: one stream, and what reading it found.
pub struct Parsed {
    /// The samples: the topic's stream.
    pub streams: Vec<Stream>,
    /// Notes (units assumed, stamps out of order, malformed lines).
    pub notes: Vec<String>,
    /// True when the header is EuRoC/ASL's.
    pub euroc: bool,
}

/// Parses the text log at `path` into a stream named `topic`.
pub(crate) fn parse(path: &Path, topic: &str, opts: &InputOptions) -> Result<Parsed, Error> {
    let io = |e| Error::io(path, e);
    let file = std::fs::File::open(path).map_err(io)?;
    let map = crate::mapped::Mapped::of(&file, path)?;
    let bytes = map.bytes();
    let head = &bytes[..bytes.len().min(SNIFF_BYTES)];
    let lay = layout(path, head, bytes.len() as u64, opts)?;
    let msg_type = if lay.euroc { "euroc/imu" } else { "text/imu" };
    // The body in ranges parsed in parallel, each straight into its slot of the topic's
    // columns (room for one row per line: no copy of the file nor of the rows). A quoted
    // field may hold a line break: a file whose lines hold quotes is read by the csv crate
    // whole instead.
    let ranges: Vec<&[u8]> = (lay.body..bytes.len())
        .step_by(RANGE_BYTES)
        .map(|a| {
            let (s, e) = line_range(bytes, lay.body, (a, (a + RANGE_BYTES).min(bytes.len())));
            &bytes[s..e]
        })
        .collect();
    let parse_into = |ranges: &[&[u8]], quoted: bool| {
        let room: Vec<usize> = ranges.par_iter().map(|r| room(r)).collect();
        let mut rows = Rows::zeroed(room.iter().sum());
        let got: Vec<Summary> = ranges
            .par_iter()
            .zip(rows.split(&room))
            .map(|(r, slot)| parse_range(r, &lay, quoted, slot).got)
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
    };
    let (mut rows, mut chunks) = parse_into(&ranges, false);
    if chunks.iter().any(|c| c.quoted) && !matches!(lay.delim, Delim::Whitespace(_)) {
        (rows, chunks) = parse_into(&[&bytes[lay.body..]], true);
    }
    let mut notes = Vec::new();
    let total_bad: u64 = chunks.iter().map(|c| c.bad).sum();
    let total_lines: u64 = chunks.iter().map(|c| c.lines).sum();
    let mut first_bad: Option<(u64, String)> = None;
    let mut line0 = lay.body_line;
    let mut line_starts = Vec::with_capacity(chunks.len());
    for c in &chunks {
        line_starts.push(line0);
        if first_bad.is_none()
            && let Some((l, why)) = &c.first_bad
        {
            first_bad = Some((line0 + l - 1, why.clone()));
        }
        line0 += c.lines;
    }
    if total_bad > 0 {
        let (l, why) = first_bad.unwrap_or((0, String::new()));
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
        notes.push(msg);
    }
    if lay.time.is_none() {
        // no time column: the rows are numbered at the given rate
        let rate = opts.rate.unwrap_or(1.0);
        for (k, (r, s)) in rows.record_time.iter_mut().zip(&mut rows.stamp).enumerate() {
            let t = RosTime::from_nanos((k as f64 * 1e9 / rate).round() as u64);
            (*r, *s) = (t, t);
        }
    } else {
        // stamps that go backwards or repeat, with the line of the first of each
        let (mut back, mut dup) = (0u64, 0u64);
        let (mut first_back, mut first_dup) = (None, None);
        let mut prev: Option<u64> = None;
        for (c, l0) in chunks.iter().zip(&line_starts) {
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
        if back > 0 {
            notes.push(format!(
                "{back} time stamp{} backwards (first at line {})",
                if back == 1 { " goes" } else { "s go" },
                first_back.unwrap_or(0)
            ));
        }
        if dup > 0 {
            notes.push(format!(
                "{dup} time stamp{} the one before (first at line {}); the rows are kept",
                if dup == 1 { " repeats" } else { "s repeat" },
                first_dup.unwrap_or(0)
            ));
        }
    }
    check_plausible(path, &lay, &rows)?;
    let scaled = opts.gyro_scale.is_some() || opts.acc_scale.is_some();
    if !(lay.gyro_stated && lay.acc_stated) || lay.gyro.is_none() || lay.acc.is_none() || scaled {
        notes.push(format!("{}: {}", path.display(), lay.what));
    }
    if lay.gyro.is_none() {
        notes.push(format!(
            "'{topic}' has no gyroscope columns: its gyro values are NaN"
        ));
    }
    if lay.acc.is_none() {
        notes.push(format!(
            "'{topic}' has no accelerometer columns: its acc values are NaN"
        ));
    }
    Ok(Parsed {
        streams: vec![Stream::of_rows(topic, msg_type, rows)],
        notes,
        euroc: lay.euroc,
    })
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

/// Opens a text log: one topic, `imu`.
pub(crate) fn open(path: &Path, opts: &InputOptions) -> Result<DecodedSource, Error> {
    // a data.csv in an EuRoC imuN folder is that folder's topic, with its sensor.yaml
    if let Some(dir) = path.parent()
        && path.file_name().is_some_and(|n| n == "data.csv")
        && super::euroc::is_imu_folder(dir)
    {
        return super::euroc::open_files(
            vec![(super::euroc::folder_topic(dir), PathBuf::from(path))],
            opts,
        );
    }
    let p = parse(path, "imu", opts)?;
    Ok(DecodedSource::new(
        InputKind::Text,
        p.streams,
        p.notes,
        Vec::new(),
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn header_names_map_to_roles() {
        for (n, r) in [
            ("t", Role::Time),
            ("timestamp", Role::Time),
            ("%time", Role::Time),
            ("gx", Role::Gyro(0)),
            ("gyro_y", Role::Gyro(1)),
            ("w_RS_S_z", Role::Gyro(2)),
            ("field.angular_velocity.x", Role::Gyro(0)),
            ("xgyro", Role::Gyro(0)),
            ("ax", Role::Acc(0)),
            ("acc_z", Role::Acc(2)),
            ("a_RS_S_y", Role::Acc(1)),
            ("field.linear_acceleration.z", Role::Acc(2)),
        ] {
            assert_eq!(role_of(n).map(|x| x.0), Some(r), "{n}");
        }
        assert_eq!(role_of("time_ms"), Some((Role::Time, Some(TimeUnit::Ms))));
        assert_eq!(role_of("t_s"), Some((Role::Time, Some(TimeUnit::S))));
        assert_eq!(
            role_of("timestampus"),
            Some((Role::Time, Some(TimeUnit::Us)))
        );
        for n in ["temperature", "seq", "field.orientation.x", "x", "mag_x"] {
            assert_eq!(role_of(n), None, "{n}");
        }
    }

    /// The one-pass reader and the csv crate give the same rows, and the lines the one
    /// pass does not take go to the csv crate.
    #[test]
    fn the_fast_path_reads_what_the_csv_crate_reads() {
        let lay = |delim, time: Option<usize>| Layout {
            delim,
            time,
            gyro: Some([1, 2, 3]),
            acc: Some([5, 6, 7]),
            time_unit: TimeUnit::Ns,
            gyro_si: 0.5,
            acc_si: 2.0,
            gyro_stated: true,
            acc_stated: true,
            body: 0,
            body_line: 1,
            what: String::new(),
            euroc: false,
        };
        let csv = "1,0.5,-1e-3,3,temp,1.25e2,-0,7,extra\r\n2, 0.25 ,2,3,x,4,5,6\n# comment\n\n3,1,2,3,\"q\",4,5,6\n4,1,2\n5,1,2,3,x,4,5,nan";
        let ws = "  1   0.5 -1e-3\t3 t 1.25e2 -0 7\n2 1 2 3 x 4 5 6 9 9\n";
        for (text, d) in [(csv, Delim::Byte(b',')), (ws, Delim::Whitespace(b' '))] {
            let l = lay(d, Some(0));
            let n = room(text.as_bytes());
            let (mut fast_rows, mut slow_rows) = (Rows::zeroed(n), Rows::zeroed(n));
            let fast = parse_range(text.as_bytes(), &l, false, fast_rows.split(&[n]).remove(0));
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

    #[test]
    fn units_parse_from_headers_and_flags() {
        assert_eq!(GyroUnit::parse("rad s^-1"), Ok(GyroUnit::RadS));
        assert_eq!(GyroUnit::parse("deg/s"), Ok(GyroUnit::DegS));
        assert_eq!(AccUnit::parse("m s^-2"), Ok(AccUnit::Ms2));
        assert_eq!(AccUnit::parse("mg"), Ok(AccUnit::Mg));
        assert_eq!(TimeUnit::parse("ns"), Ok(TimeUnit::Ns));
        assert!(AccUnit::parse("furlong").is_err());
    }
}
