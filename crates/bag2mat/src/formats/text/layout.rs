//! A text log's layout, decided once from its first lines and the options: the preamble,
//! the delimiter, which column holds what (header names or `--columns`) and in which unit.
//! Nothing is guessed: an ambiguity is an error that says what to add.

use crate::shared::note::Note;
use std::path::Path;

use super::InputOptions;
use crate::error::Error;
use crate::units::{AccUnit, GyroUnit, TimeUnit};

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
    pub(super) fn describe(self) -> String {
        match self {
            Role::Time => "the time".into(),
            Role::Gyro(a) => format!("gyro {}", ['x', 'y', 'z'][a]),
            Role::Acc(a) => format!("acc {}", ['x', 'y', 'z'][a]),
        }
    }
}

pub(super) const TIME_NAMES: [&str; 8] = [
    "t",
    "time",
    "timestamp",
    "stamp",
    "ts",
    "sec",
    "seconds",
    "fieldheaderstamp",
];
pub(super) const GYRO_PREFIXES: [&str; 11] = [
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
pub(super) const ACC_PREFIXES: [&str; 9] = [
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

/// How fields are separated.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Delim {
    Byte(u8),
    /// Runs of spaces (or of tabs).
    Whitespace(u8),
}

/// Everything the preamble and the options decided.
#[derive(Debug, Clone)]
pub(super) struct Layout {
    pub(super) delim: Delim,
    /// Column index of the time, or `None` (a rate is given).
    pub(super) time: Option<usize>,
    pub(super) gyro: Option<[usize; 3]>,
    pub(super) acc: Option<[usize; 3]>,
    pub(super) time_unit: TimeUnit,
    /// Multiplier from the file's value to SI, per sensor.
    pub(super) gyro_si: f64,
    pub(super) acc_si: f64,
    /// True where the unit was stated (header, flag or a known layout); false: SI assumed
    /// and checked for plausibility.
    pub(super) gyro_stated: bool,
    pub(super) acc_stated: bool,
    /// Fields of a row (the first data line's): a line with another count is no row.
    pub(super) n_cols: usize,
    /// Byte offset and 1-based line number of the first line after the preamble.
    pub(super) body: usize,
    pub(super) body_line: u64,
    /// What the layout is, for notes.
    pub(super) what: String,
    /// The EuRoC/ASL header was found.
    pub(super) euroc: bool,
    /// Numbers are written with a decimal comma (`3,82E-2`; a `;` or tab between fields, as
    /// phyphox's and European spreadsheets' exports): the body is read with points.
    pub(super) decimal_comma: bool,
    /// A column that says which sensor each row is from (`sensor_id`, …): index and name.
    pub(super) sensor_column: Option<(usize, String)>,
    /// What deciding the layout found worth a warning (a flag over the header's unit).
    pub(super) warnings: Vec<Note>,
    /// The accelerometer's unit (stated, given or known; `None`: none, SI assumed).
    pub(super) acc_unit: Option<AccUnit>,
    /// The time unit came from the flag.
    pub(super) time_from_flag: bool,
    /// The header states a time unit (in its text or its name).
    pub(super) time_stated: bool,
}

#[cfg(test)]
impl Layout {
    /// A test layout: the body from byte 0, nanosecond times, both units stated.
    pub(super) fn for_test(
        delim: Delim,
        time: Option<usize>,
        (gyro, acc): ([usize; 3], [usize; 3]),
        (gyro_si, acc_si): (f64, f64),
    ) -> Layout {
        Layout {
            delim,
            time,
            gyro: Some(gyro),
            acc: Some(acc),
            time_unit: TimeUnit::Ns,
            gyro_si,
            acc_si,
            gyro_stated: true,
            acc_stated: true,
            n_cols: 1 + time.into_iter().chain(gyro).chain(acc).max().unwrap_or(0),
            body: 0,
            body_line: 1,
            what: String::new(),
            euroc: false,
            decimal_comma: false,
            sensor_column: None,
            warnings: Vec::new(),
            acc_unit: None,
            time_from_flag: false,
            time_stated: false,
        }
    }
}

/// The header of bag2mat's own CSV output (t in s, m/s², rad/s).
pub const BAG2MAT_CSV_HEADER: &str = "t,ax,ay,az,wx,wy,wz";

pub(super) fn split_fields(line: &str, delim: Delim) -> Vec<&str> {
    match delim {
        Delim::Byte(b) => line.split(b as char).map(str::trim).collect(),
        Delim::Whitespace(_) => line.split_whitespace().collect(),
    }
}

pub(super) fn is_number(s: &str) -> bool {
    let s = s.trim().trim_matches('"');
    !s.is_empty() && fast_float2::parse::<f64, _>(s).is_ok()
}

pub(super) fn is_comment(line: &str) -> bool {
    let l = line.trim_start();
    l.starts_with('#') || l.starts_with('%') || l.starts_with("//")
}

pub(super) fn strip_comment(line: &str) -> &str {
    let l = line.trim_start();
    l.trim_start_matches('#')
        .trim_start_matches('%')
        .trim_start_matches("//")
}

/// The delimiter and number style of a line of numbers, or `None` when it is no such
/// line: the delimiter [`pick_delim`] finds with decimal points, else a `;` or tab with
/// decimal commas (`3,822818600E-2;1,573801041E-2`: phyphox's "semicolon, decimal comma"
/// export, a European spreadsheet's CSV).
pub(super) fn data_line(line: &str) -> Option<(Delim, bool)> {
    let d = pick_delim(line);
    if split_fields(line, d).iter().all(|f| is_number(f)) {
        return Some((d, false));
    }
    let d = [b';', b'\t']
        .into_iter()
        .find(|b| line.as_bytes().contains(b))
        .map(Delim::Byte)?;
    split_fields(line, d)
        .iter()
        .all(|f| f.contains(',') && is_number(&f.replace(',', ".")) || is_number(f))
        .then_some((d, true))
}

pub(super) fn pick_delim(line: &str) -> Delim {
    for b in [b',', b'\t', b';'] {
        if line.as_bytes().contains(&b) {
            return Delim::Byte(b);
        }
    }
    Delim::Whitespace(b' ')
}

/// A header field's name and the unit in its last `[...]` or `(...)`.
pub(super) fn name_and_unit(field: &str) -> (&str, Option<&str>) {
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

pub(super) fn bad(path: &Path, what: String) -> Error {
    Error::Log {
        path: path.to_path_buf(),
        what,
    }
}

/// Finds the header, delimiter, columns and units.
pub(super) fn layout(
    path: &Path,
    head: &[u8],
    file_len: u64,
    opts: &InputOptions,
) -> Result<Layout, Error> {
    let head = match std::str::from_utf8(head) {
        Ok(s) => s,
        Err(e) => std::str::from_utf8(&head[..e.valid_up_to()]).unwrap_or(""),
    };
    let pre = preamble(path, head, file_len)?;
    let (delim, decimal_comma) = match data_line(pre.data) {
        Some((d, true)) => (d, true),
        _ => (delimiter(pre.header, pre.data), false),
    };
    let n_cols = split_fields(pre.data, delim).len();
    let mut named = Named::of(path, opts, pre.header, delim, n_cols)?;
    let own_layout = !named.from_flag && pre.header.map(str::trim) == Some(BAG2MAT_CSV_HEADER);
    let euroc = !named.from_flag
        && pre
            .header
            .is_some_and(|h| h.contains("w_RS_S_x") && h.contains("a_RS_S_x"));
    let phone = named.phone_app(path, pre.header)?;
    let (time, gyro, acc) = named.place(path, opts)?;
    let mut warnings = Vec::new();
    let time_unit = named.time_unit(path, time, opts, own_layout, phone, &mut warnings)?;
    let time_stated = time.is_some_and(|i| {
        !named.stated(&[i]).is_empty() || named.roles[i].is_some_and(|r| r.1.is_some())
    });
    let gyro_unit = match gyro {
        Some(c) => resolve_unit(
            path,
            "gyroscope",
            opts.gyro_unit,
            &named.stated(&c),
            GyroUnit::parse,
            own_layout
                .then_some(GyroUnit::RadS)
                .or(phone.and_then(|p| p.gyro)),
            GyroUnit::name,
            &mut warnings,
        )?,
        None => None,
    };
    let acc_unit = match acc {
        Some(c) => resolve_unit(
            path,
            "accelerometer",
            opts.acc_unit,
            &named.stated(&c),
            AccUnit::parse,
            own_layout
                .then_some(AccUnit::Ms2)
                .or(phone.and_then(|p| p.acc)),
            AccUnit::name,
            &mut warnings,
        )?,
        None => None,
    };
    scales_have_units(
        path,
        opts,
        gyro_unit.is_some() || gyro.is_none(),
        acc_unit.is_some() || acc.is_none(),
    )?;
    let mut what = layout_text(
        n_cols,
        delim,
        time.map(|_| time_unit),
        opts,
        gyro.map(|_| gyro_unit.map(GyroUnit::name)),
        acc.map(|_| acc_unit.map(AccUnit::name)),
    );
    if decimal_comma {
        what.push_str(", decimal commas");
    }
    if let Some(p) = phone {
        what = format!("{} export; {what}", p.app);
    }
    let sensor_column = named.sensor_column();
    Ok(Layout {
        delim,
        time,
        gyro,
        acc,
        time_unit,
        gyro_si: gyro_unit.map_or(1.0, GyroUnit::si) / opts.gyro_scale.unwrap_or(1.0),
        acc_si: acc_unit.map_or(1.0, AccUnit::si) / opts.acc_scale.unwrap_or(1.0),
        gyro_stated: gyro_unit.is_some(),
        acc_stated: acc_unit.is_some(),
        n_cols,
        body: pre.body,
        body_line: pre.body_line,
        what,
        euroc,
        decimal_comma,
        sensor_column,
        warnings,
        acc_unit,
        time_from_flag: opts.time_unit.is_some(),
        time_stated,
    })
}

/// A phone app's export whose header does not say everything ([`Named::phone_app`]): the
/// app, and the units it writes.
#[derive(Debug, Clone, Copy)]
pub(super) struct PhoneApp {
    app: &'static str,
    time: Option<TimeUnit>,
    gyro: Option<GyroUnit>,
    acc: Option<AccUnit>,
}

/// Sensor Logger's header (every sensor's CSV): `time` in ns since the epoch,
/// `seconds_elapsed` in s, then the axes in z, y, x order.
pub const SENSOR_LOGGER_HEADER: [&str; 5] = ["time", "seconds_elapsed", "z", "y", "x"];

/// Column names that say which sensor a row is from (a log of several IMUs in one file).
pub(super) const SENSOR_ID_NAMES: [&str; 9] = [
    "sensorid", "sensor", "imuid", "imu", "deviceid", "device", "id", "instance", "source",
];

/// A raw-count scale (`--gyro-scale`, `--acc-scale`) needs the unit it counts in
/// (`gyro_ok`, `acc_ok`: the unit is known, or the sensor has no columns).
fn scales_have_units(
    path: &Path,
    opts: &InputOptions,
    gyro_ok: bool,
    acc_ok: bool,
) -> Result<(), Error> {
    if opts.gyro_scale.is_some() && !gyro_ok {
        return Err(bad(
            path,
            "--gyro-scale gives LSB per unit: say which unit with --gyro-unit rad/s|deg/s".into(),
        ));
    }
    if opts.acc_scale.is_some() && !acc_ok {
        return Err(bad(
            path,
            "--acc-scale gives LSB per unit: say which unit with --acc-unit m/s^2|g|mg".into(),
        ));
    }
    Ok(())
}

/// A file that is text but no table of numbers, for the input-kind error.
fn not_table(path: &Path, why: &str) -> Error {
    Error::NotABag {
        path: path.to_path_buf(),
        what: format!(
            "it is text, but {why}. Accepted: {}",
            crate::source::accepted()
        ),
    }
}

/// What precedes the body: the header line (a comment right before the data counts, as
/// EuRoC's), the first data line, and where the body starts.
struct Preamble<'h> {
    header: Option<&'h str>,
    data: &'h str,
    /// Byte offset and 1-based line number of the first data line.
    body: usize,
    body_line: u64,
}

/// The preamble of `head` (the file's first bytes; the file is `file_len` long): blank and
/// comment lines, then a header or the first data line.
fn preamble<'h>(path: &Path, head: &'h str, file_len: u64) -> Result<Preamble<'h>, Error> {
    let mut offset = 0usize;
    let mut line_no = 0u64;
    // the comment lines since the last other line (the header may be any of them: a
    // comment right after EuRoC's is a comment)
    let mut comments: Vec<&str> = Vec::new();
    let mut header: Option<&str> = None;
    // the first line that is a data row with a damaged value: the body starts there
    let mut damaged: Option<(usize, u64)> = None;
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
            comments.push(line);
            continue;
        }
        // a line of numbers (a decimal-comma export's too: `data_line`) or not
        let (fields, numbers_only) = match data_line(line) {
            Some((d, _)) => (split_fields(line, d), true),
            None => (split_fields(line, pick_delim(line)), false),
        };
        // the fields a row has where a header (or a comment that may be one) says so: a
        // line of numbers with another count is a damaged row (a line split in two)
        let counts: Vec<usize> = match header {
            Some(h) => vec![split_fields(h, pick_delim(h)).len()],
            None => comments
                .iter()
                .map(|c| split_fields(strip_comment(c), pick_delim(strip_comment(c))))
                .filter(|cf| cf.len() > 1 && cf.iter().any(|f| !is_number(f)))
                .map(|cf| cf.len())
                .collect(),
        };
        let fits = counts.is_empty() || counts.contains(&fields.len());
        if numbers_only && fits {
            // a comment before the data with as many fields is its header (EuRoC)
            if header.is_none() {
                header = comments.iter().rev().map(|c| strip_comment(c)).find(|c| {
                    let cf = split_fields(c, pick_delim(c));
                    cf.len() == fields.len() && cf.iter().any(|f| !is_number(f))
                });
            }
            let (body, body_line) = damaged.unwrap_or((start, line_no));
            return Ok(Preamble {
                header,
                data: line,
                body,
                body_line,
            });
        }
        // after the header, or with most of its fields numbers: a data row with a damaged
        // value or a damaged line, not a header (the first whole row gives the layout; the
        // body, its malformed lines counted, starts here)
        let numbers = fields.iter().filter(|f| is_number(f)).count();
        if header.is_some()
            || damaged.is_some()
            || (fields.len() > 1 && 2 * numbers >= fields.len())
        {
            damaged.get_or_insert((start, line_no));
            continue;
        }
        header = Some(line);
        comments.clear();
    }
    Err(not_table(
        path,
        &format!("no line of numbers in its first {} bytes", head.len()),
    ))
}

/// The delimiter: the header's, unless the data line says otherwise.
fn delimiter(header: Option<&str>, data: &str) -> Delim {
    let delim = match (pick_delim(header.unwrap_or(data)), pick_delim(data)) {
        (Delim::Whitespace(_), Delim::Byte(b)) => Delim::Byte(b),
        (d, _) => d,
    };
    match delim {
        Delim::Whitespace(_) if data.contains('\t') && !data.contains(' ') => {
            Delim::Whitespace(b'\t')
        }
        d => d,
    }
}

/// The columns as named by `--columns` or the header: names, roles, stated units.
struct Named {
    names: Vec<String>,
    roles: Vec<Option<(Role, Option<TimeUnit>)>>,
    units: Vec<Option<String>>,
    /// The names come from `--columns`.
    from_flag: bool,
}

impl Named {
    /// The columns of a file with `n_cols` fields per row: `--columns`, else the header.
    fn of(
        path: &Path,
        opts: &InputOptions,
        header: Option<&str>,
        delim: Delim,
        n_cols: usize,
    ) -> Result<Named, Error> {
        let mut named = Named {
            names: Vec::new(),
            roles: Vec::new(),
            units: Vec::new(),
            from_flag: opts.columns.is_some(),
        };
        if let Some(cols) = &opts.columns {
            named.names = cols.split(',').map(|s| s.trim().to_string()).collect();
            for n in &named.names {
                if n == "_" || n == "-" || n.is_empty() {
                    named.roles.push(None);
                } else {
                    named.roles.push(Some(role_of(n).ok_or_else(|| {
                        bad(
                            path,
                            format!(
                                "--columns: '{n}' names no column bag2mat reads (t, gx gy gz, ax ay az, or _ to skip)"
                            ),
                        )
                    })?));
                }
            }
            // --columns renames the columns; the units a header states stay stated
            let header_units: Vec<Option<String>> = header
                .map(|h| {
                    split_fields(h, delim)
                        .iter()
                        .map(|f| name_and_unit(f).1.map(str::to_string))
                        .collect::<Vec<_>>()
                })
                .filter(|u| u.len() == n_cols)
                .unwrap_or_default();
            named.units = (0..named.names.len())
                .map(|i| header_units.get(i).cloned().flatten())
                .collect();
            if named.names.len() > n_cols {
                return Err(bad(
                    path,
                    format!(
                        "--columns names {} columns, the file's rows have {n_cols}",
                        named.names.len()
                    ),
                ));
            }
        } else if let Some(h) = header {
            named.names = split_fields(h, delim)
                .iter()
                .map(|s| s.to_string())
                .collect();
            for f in &named.names {
                let (n, u) = name_and_unit(f);
                named.roles.push(role_of(n).or_else(|| axis_by_unit(n, u)));
                named.units.push(u.map(str::to_string));
            }
        } else {
            return Err(bad(
                path,
                format!(
                    "the text log has no header line naming its {n_cols} columns: give them with --columns (e.g. --columns t,gx,gy,gz,ax,ay,az, _ to skip one) and their units (--time-unit, --gyro-unit, --acc-unit)"
                ),
            ));
        }
        Ok(named)
    }

    /// A phone app's export whose header names its axes but not its sensor, recognised
    /// from the header (not from `--columns`): Sensor Logger's `time,seconds_elapsed,z,y,x`
    /// (`time` in ns, axes in z, y, x order), whose file name says the sensor
    /// (`Gyroscope*.csv` in rad/s, `TotalAcceleration.csv` or `Accelerometer*.csv` in
    /// m/s²). Sets the columns' roles; returns the app and its units.
    fn phone_app(&mut self, path: &Path, header: Option<&str>) -> Result<Option<PhoneApp>, Error> {
        let Some(h) = header.filter(|_| !self.from_flag) else {
            return Ok(None);
        };
        let fields: Vec<String> = split_fields(h, pick_delim(h))
            .iter()
            .map(|f| f.trim().trim_matches('"').to_ascii_lowercase())
            .collect();
        if fields.len() < SENSOR_LOGGER_HEADER.len()
            || fields[..SENSOR_LOGGER_HEADER.len()] != SENSOR_LOGGER_HEADER
        {
            return Ok(None);
        }
        let stem = path
            .file_stem()
            .map(|s| s.to_string_lossy().to_ascii_lowercase())
            .unwrap_or_default();
        let gyro = stem.starts_with("gyroscope");
        if !gyro && !stem.starts_with("totalacceleration") && !stem.starts_with("accelerometer") {
            return Err(bad(
                path,
                format!(
                    "a Sensor Logger export (time,seconds_elapsed,z,y,x) says its sensor by its file name, and '{}' is not Gyroscope.csv, TotalAcceleration.csv nor Accelerometer.csv: name the columns with --columns (e.g. t,_,gz,gy,gx) and their units",
                    path.file_name()
                        .map_or(String::new(), |n| n.to_string_lossy().into_owned())
                ),
            ));
        }
        let role = |a: usize| Some((if gyro { Role::Gyro(a) } else { Role::Acc(a) }, None));
        self.roles = vec![Some((Role::Time, None)), None, role(2), role(1), role(0)];
        self.roles.resize(fields.len(), None);
        Ok(Some(PhoneApp {
            app: "Sensor Logger",
            time: Some(TimeUnit::Ns),
            gyro: gyro.then_some(GyroUnit::RadS),
            acc: (!gyro).then_some(AccUnit::Ms2),
        }))
    }

    /// The column that says which sensor each row is from, if the header names one.
    fn sensor_column(&self) -> Option<(usize, String)> {
        self.names.iter().enumerate().find_map(|(i, f)| {
            let n: String = name_and_unit(f)
                .0
                .chars()
                .filter(|c| c.is_ascii_alphanumeric())
                .map(|c| c.to_ascii_lowercase())
                .collect();
            (self.roles.get(i).is_some_and(|r| r.is_none())
                && SENSOR_ID_NAMES.contains(&n.as_str()))
            .then(|| (i, name_and_unit(f).0.to_string()))
        })
    }

    /// The time column and the three axis columns of each sensor, checked: one column per
    /// role, all three axes or none, a sensor at all, a time column or a rate (not both).
    #[allow(clippy::type_complexity)]
    fn place(
        &self,
        path: &Path,
        opts: &InputOptions,
    ) -> Result<(Option<usize>, Option<[usize; 3]>, Option<[usize; 3]>), Error> {
        let names = &self.names;
        let mut found: Vec<(Role, usize)> = Vec::new();
        for (i, r) in self.roles.iter().enumerate() {
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
            return Err(not_table(
                path,
                &format!(
                    "no column of its header ({}) names a gyroscope or accelerometer axis (gx/gyro_x/wx/w_RS_S_x, ax/acc_x/a_RS_S_x, …): name them with --columns",
                    names.join(", ")
                ),
            ));
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
        Ok((time, gyro, acc))
    }

    /// The distinct units the header states for columns `cols`.
    fn stated(&self, cols: &[usize]) -> Vec<String> {
        let mut u: Vec<String> = cols
            .iter()
            .filter_map(|&i| self.units.get(i).cloned().flatten())
            .collect();
        u.dedup();
        u
    }

    /// The time column's unit: stated by the header, the flag, or the layout (bag2mat's own
    /// CSV, a phone app's export); a flag over another unit in the header wins, with a
    /// warning in `warnings` (a header can be wrong: the physics checks say so); no unit at
    /// all is an error (no time column: ns, unused).
    fn time_unit(
        &self,
        path: &Path,
        time: Option<usize>,
        opts: &InputOptions,
        own_layout: bool,
        phone: Option<PhoneApp>,
        warnings: &mut Vec<Note>,
    ) -> Result<TimeUnit, Error> {
        let Some(i) = time else {
            return Ok(TimeUnit::Ns);
        };
        let header_unit = match (self.stated(&[i]).first(), self.roles[i].and_then(|r| r.1)) {
            (Some(u), _) => Some(
                TimeUnit::parse(u)
                    .map_err(|e| bad(path, format!("header of column {}: {e}", i + 1)))?,
            ),
            (None, u) => u,
        };
        let known = own_layout
            .then_some(TimeUnit::S)
            .or(phone.and_then(|p| p.time));
        match (opts.time_unit, header_unit.or(known)) {
            (Some(f), Some(h)) if f != h => {
                warnings.push(Note::warning(format!(
                    "the header says the time is in {}, --time-unit says {}: read in {}",
                    h.name(),
                    f.name(),
                    f.name()
                )));
                Ok(f)
            }
            (Some(f), _) => Ok(f),
            (None, Some(h)) => Ok(h),
            (None, None) => Err(bad(
                path,
                format!(
                    "the time column '{}' states no unit: give --time-unit s|ms|us|ns",
                    self.names[i]
                ),
            )),
        }
    }
}

/// A column named only by its axis (`X (rad/s)`, as phyphox's newer exports write), whose
/// unit says the sensor: a gyroscope unit, or an accelerometer one.
fn axis_by_unit(name: &str, unit: Option<&str>) -> Option<(Role, Option<TimeUnit>)> {
    let a = match name.trim().to_ascii_lowercase().as_str() {
        "x" => 0,
        "y" => 1,
        "z" => 2,
        _ => return None,
    };
    let u = unit?;
    if GyroUnit::parse(u).is_ok() {
        Some((Role::Gyro(a), None))
    } else if AccUnit::parse(u).is_ok() {
        Some((Role::Acc(a), None))
    } else {
        None
    }
}

/// A sensor's unit from its flag, the units its header states and the layout's known
/// unit: one of them, or the same from several; a flag over another unit in the header
/// wins, with a warning in `warnings`.
#[allow(clippy::too_many_arguments)]
fn resolve_unit<U: Copy + PartialEq>(
    path: &Path,
    what: &str,
    flag: Option<U>,
    header: &[String],
    parse: fn(&str) -> Result<U, crate::units::UnknownUnit>,
    known: Option<U>,
    name: fn(U) -> &'static str,
    warnings: &mut Vec<Note>,
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
        (Some(f), Some(h)) if f != h => {
            warnings.push(Note::warning(format!(
                "the header says the {what} is in {}, the flag says {}: read in {}",
                name(h),
                name(f),
                name(f)
            )));
            Ok(Some(f))
        }
        (Some(f), _) => Ok(Some(f)),
        (None, h) => Ok(h),
    }
}

/// What the layout is, for the notes: columns, delimiter, time unit (`None`: from the
/// rate), and each present sensor's unit (`Some(None)`: none stated).
fn layout_text(
    n_cols: usize,
    delim: Delim,
    time_unit: Option<TimeUnit>,
    opts: &InputOptions,
    gyro: Option<Option<&'static str>>,
    acc: Option<Option<&'static str>>,
) -> String {
    let mut what = format!(
        "{} columns ({}), time {}",
        n_cols,
        match delim {
            Delim::Byte(b',') => "comma-separated",
            Delim::Byte(b'\t') => "tab-separated",
            Delim::Byte(_) => "semicolon-separated",
            Delim::Whitespace(_) => "whitespace-separated",
        },
        match time_unit {
            Some(u) => u.name().to_string(),
            None => format!("from --rate {} Hz", opts.rate.unwrap_or(0.0)),
        }
    );
    let unit_text = |u: Option<&'static str>, scale: Option<f64>| match (u, scale) {
        (Some(u), Some(s)) => format!("raw counts, {s} LSB per {u}"),
        (Some(u), None) => u.to_string(),
        (None, _) => "no unit stated (SI assumed)".to_string(),
    };
    if let Some(u) = gyro {
        what.push_str(&format!(", gyro {}", unit_text(u, opts.gyro_scale)));
    }
    if let Some(u) = acc {
        what.push_str(&format!(", acc {}", unit_text(u, opts.acc_scale)));
    }
    what
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
}
