//! rosbag2's sqlite3 storage (`.db3`), read and written with `rusqlite` (bundled SQLite).
//!
//! Every schema version from Foxy to today shares what the reader needs: `topics(id, name,
//! type, serialization_format, …)` and `messages(id INTEGER PRIMARY KEY, topic_id,
//! timestamp, data)`, where `timestamp` is the receive time in ns (the record time). Later
//! versions add `offered_qos_profiles`, `type_description_hash`, and the `schema`,
//! `metadata` and `message_definitions` tables, which the reader does not need.
//!
//! A damaged page must never cost rows in silence, and SQLite answers many questions from
//! the timestamp index (`min(id)`, `max(id)`, `count(*)`) or stops a range scan at a damaged
//! row id. So the reader never asks the index and never scans with an upper bound: parts
//! start at ids sought in the table's own b-tree (`NOT INDEXED`), and each part walks the
//! leaves from there in order until it meets the next part's first id, first the ids and
//! record times only (checked by [`super::table_walk`] against the contiguous ids rosbag2
//! writes), then the payloads. A walk that SQLite stops with an error resumes at the next id
//! it can seek. Once every part was read, the timestamp index is asked only which ids it
//! lists past the last row the table holds (a tail the table lost), and a file without one
//! gets `PRAGMA quick_check`.

use crate::shared::note::Note;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

use rusqlite::types::ValueRef;
use rusqlite::{Connection, OpenFlags, OptionalExtension, params};

use super::table_walk::{self, Walk};
use crate::error::Error;
use crate::source::{self, Encoding, InputKind, Loss, MessageSink, Part, PartRead, Source};

/// Fewer bytes than any stored row takes (cell header, rowid, three columns): bounds the ids
/// and rows a file can hold.
const MIN_ROW_BYTES: u64 = 8;

/// Message ids per part.
const ROWS_PER_PART: i64 = 16_384;

/// The first id at or after ?1 that the table's b-tree finds by its key.
const SEEK_SQL: &str = "SELECT id FROM messages NOT INDEXED WHERE id >= ?1 LIMIT 1";

/// An open `.db3`.
pub struct Sqlite3Reader {
    /// The file SQLite reads (a private copy when the input is truncated).
    path: PathBuf,
    _copy: Option<tempfile::TempDir>,
    pool: Mutex<Vec<Connection>>,
    /// First id of each part (parallel to the contents' parts); part `k` ends before
    /// `starts[k + 1]`.
    starts: Vec<i64>,
    /// Rows the file can hold at most: bounds every walk and every count.
    capacity: u64,
    /// The index SQLite keeps on `messages` (rosbag2's `timestamp_idx`), if any.
    index: Option<String>,
    /// What the last part's walk found: the highest and lowest id held in place, and
    /// whether any walk broke.
    walked: Mutex<Walked>,
    contents: source::Contents,
}

/// What the parts' walks found that only the whole read can judge.
#[derive(Debug, Default)]
struct Walked {
    /// Highest id the last part holds in place, with its record time.
    max_id: Option<(i64, i64)>,
    /// Lowest id the first part holds in place.
    min_id: Option<i64>,
    /// Rows every part walked (doubles included).
    rows: u64,
    /// Parts read.
    parts: usize,
}

fn sql_err(path: &Path, e: rusqlite::Error) -> Error {
    Error::Storage {
        path: path.to_path_buf(),
        what: format!("sqlite3: {e}"),
    }
}

fn connect(path: &Path) -> Result<Connection, rusqlite::Error> {
    Connection::open_with_flags(
        path,
        OpenFlags::SQLITE_OPEN_READ_ONLY | OpenFlags::SQLITE_OPEN_NO_MUTEX,
    )
}

/// A private copy of a truncated sqlite3 file that SQLite accepts: its whole pages, the
/// header's page count set to them. `None` when the file is not shorter than its header
/// says (or its header is not whole). Returns the copy's directory, the pages kept, the
/// pages the header announces and the page size.
type TruncatedCopy = (tempfile::TempDir, u32, u32, u64);

fn truncated_copy(path: &Path) -> Result<Option<TruncatedCopy>, Error> {
    let b = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    if b.len() < 100 || !b.starts_with(source::SQLITE_MAGIC) {
        return Ok(None);
    }
    let page = match u16::from_be_bytes([b[16], b[17]]) {
        1 => 65536usize,
        n if n >= 512 && n.is_power_of_two() => n as usize,
        _ => return Ok(None),
    };
    let announced = u32::from_be_bytes(b[28..32].try_into().expect("4 bytes"));
    let kept = (b.len() / page) as u32;
    if kept == 0 || announced <= kept && b.len() % page == 0 {
        return Ok(None);
    }
    let dir = tempfile::Builder::new()
        .prefix("bag2mat-db3.")
        .tempdir()
        .map_err(|e| Error::io(std::env::temp_dir(), e))?;
    let mut c = b[..kept as usize * page].to_vec();
    c[28..32].copy_from_slice(&kept.to_be_bytes());
    // The count is valid only with the version-valid-for number equal to the change counter.
    let counter: [u8; 4] = c[24..28].try_into().expect("4 bytes");
    c[92..96].copy_from_slice(&counter);
    let to = dir.path().join("truncated.db3");
    std::fs::write(&to, &c).map_err(|e| Error::io(&to, e))?;
    // Indexes whose pages the cut took would fail every statement: the copy drops them.
    let dropped = Connection::open(&to).and_then(|rw| {
        rw.execute_batch("PRAGMA writable_schema = ON;")?;
        rw.execute(
            "DELETE FROM sqlite_master WHERE type = 'index' AND rootpage > ?1",
            params![kept],
        )
    });
    if let Err(e) = dropped {
        return Err(sql_err(path, e));
    }
    Ok(Some((dir, kept, announced.max(kept), page as u64)))
}

/// The first id at or after `at` the table's b-tree finds; `Err` when a damaged page is in
/// the way.
fn seek(conn: &Connection, at: i64) -> Result<Option<i64>, rusqlite::Error> {
    conn.prepare_cached(SEEK_SQL)?
        .query_row(params![at], |r| r.get(0))
        .optional()
}

/// The first id past `after` (and before `stop`) that can be sought, probing at doubling
/// distances past a damaged page; `None` when there is none.
fn seek_past(conn: &Connection, after: i64, stop: Option<i64>, capacity: u64) -> Option<i64> {
    let mut step = 1i64;
    loop {
        let at = after.checked_add(step)?;
        if stop.is_some_and(|s| at >= s) || step as u64 > capacity.saturating_mul(2) {
            return None;
        }
        match seek(conn, at) {
            Ok(Some(id)) if stop.is_none_or(|s| id < s) => return Some(id),
            Ok(_) => return None,
            Err(_) => step = step.saturating_mul(2),
        }
    }
}

impl Sqlite3Reader {
    /// Opens a rosbag2 `.db3` read-only, lists its topics and plans its parts.
    pub(crate) fn open(path: &Path) -> Result<Sqlite3Reader, Error> {
        let Connected {
            conn,
            read_path,
            copy,
            tables,
            mut notes,
            mut losses,
        } = Connected::to(path)?;
        for t in ["topics", "messages"] {
            if !tables.iter().any(|x| x == t) {
                return Err(Error::NotABag {
                    path: path.to_path_buf(),
                    what: format!(
                        "an SQLite database without the rosbag2 '{t}' table. Accepted: {}",
                        source::accepted()
                    ),
                });
            }
        }
        let index: Option<String> = conn
            .query_row(
                "SELECT name FROM sqlite_master WHERE type = 'index' AND tbl_name = 'messages' ORDER BY name LIKE '%timestamp%' DESC LIMIT 1",
                [],
                |r| r.get(0),
            )
            .optional()
            .ok()
            .flatten();
        let channels = topics(&conn).map_err(|e| sql_err(path, e))?;
        let len = std::fs::metadata(path)
            .map_err(|e| Error::io(path, e))?
            .len();
        let capacity = (len / MIN_ROW_BYTES).max(1);
        let starts = plan_parts(&conn, capacity, &mut notes, &mut losses);
        let parts = row_parts(&starts);
        Ok(Sqlite3Reader {
            path: read_path,
            _copy: copy,
            pool: Mutex::new(vec![conn]),
            starts,
            capacity,
            index,
            walked: Mutex::new(Walked::default()),
            contents: source::Contents {
                channels,
                parts,
                notes,
                losses,
                log_start: None,
                integration: Vec::new(),
            },
        })
    }

    fn take(&self) -> Result<Connection, Error> {
        let c = self.pool.lock().ok().and_then(|mut p| p.pop());
        match c {
            Some(c) => Ok(c),
            None => connect(&self.path).map_err(|e| sql_err(&self.path, e)),
        }
    }

    fn give(&self, c: Connection) {
        if let Ok(mut p) = self.pool.lock() {
            p.push(c);
        }
    }

    /// What the plan of a part's table walk found: rows missing or unreadable (losses) and
    /// rows read where their ids belong or read once of two (notes).
    fn plan_losses(&self, plan: &table_walk::Plan, start: i64, out: &mut PartRead) {
        for h in &plan.holes {
            let (a, b) = h.ids;
            let what = match &h.error {
                Some(e) => {
                    format!("message rows {a}..{b} could not be read ({e}) and were skipped")
                }
                None => format!(
                    "message rows {a}..{b} are missing from the table (a damaged page; rosbag2 numbers its rows without gaps)"
                ),
            };
            let span = match h.around {
                (Some(x), Some(y)) => Some((x.max(0) as u64, y.max(0) as u64)),
                (Some(x), None) | (None, Some(x)) => Some((x.max(0) as u64, x.max(0) as u64)),
                (None, None) => None,
            };
            out.lost.push(Loss {
                what,
                messages: Some(h.lost.min(self.capacity)),
                span,
                channel: None,
                ..Loss::default()
            });
        }
        if plan.moved.0 > 0 {
            out.notes.push(Note::warning(format!(
                "message rows {start}..: {} row(s) stored out of place (a damaged row id such as {}) were read where their ids belong",
                plan.moved.0,
                plan.moved.1.unwrap_or_default()
            )));
        }
        if plan.doubles > 0 {
            out.notes.push(Note::warning(format!(
                "message rows {start}..: {} row(s) that damaged pages of the table show twice were read once",
                plan.doubles
            )));
        }
    }

    /// The payload of a walked row (at walk position `pos`, of `topic`, recorded at `ts`)
    /// when its topic is wanted; a row naming no topic the table holds is noted as stray.
    fn take_payload(
        &self,
        w: &mut Walked2,
        row: &rusqlite::Row,
        (pos, topic, ts): (u64, u32, i64),
        wanted: &[u32],
    ) -> Result<(), rusqlite::Error> {
        if let Some(data) = row.get_ref(3)?.as_blob_or_null()? {
            let a = w.arena.len();
            w.arena.extend_from_slice(data);
            w.rows
                .push((pos, topic, ts.max(0) as u64, a..w.arena.len()));
        } else if wanted.contains(&topic) {
            return Err(rusqlite::Error::InvalidColumnType(
                3,
                "data".into(),
                rusqlite::types::Type::Null,
            ));
        } else if !self.contents.channels.iter().any(|c| c.id == topic) {
            w.stray_topic.push((pos, topic));
        }
        Ok(())
    }

    /// Walks the rows from `start` until `stop` (the next part's first id), resuming past
    /// damaged pages: the ids and record times of all, and the payloads of the topics
    /// `wanted` names (buffered until the walk is judged).
    fn walk(&self, conn: &Connection, start: i64, stop: Option<i64>, wanted: &[u32]) -> Walked2 {
        let mut w = Walked2::default();
        // A walk longer than the file can hold goes round a loop of damaged pages.
        let limit = match stop {
            Some(s) => (s.saturating_sub(start) as u64)
                .saturating_mul(2)
                .saturating_add(1024)
                .min(self.capacity),
            None => self.capacity,
        };
        let sql = walk_sql(wanted);
        let mut seek_at = Some(start);
        while let Some(at) = seek_at.take() {
            let mut rows = 0u64;
            let mut last_in_window: Option<i64> = None;
            let r = (|| -> Result<(), rusqlite::Error> {
                let mut st = conn.prepare_cached(&sql)?;
                let mut q = st.query(params![at])?;
                while let Some(row) = q.next()? {
                    let id: i64 = row.get(0)?;
                    if Some(id) == stop {
                        return Ok(());
                    }
                    // A field of the wrong type is this row's damage, not the page's.
                    let ts = match row.get_ref(1)? {
                        ValueRef::Integer(v) => Some(v),
                        _ => None,
                    };
                    let topic = match row.get_ref(2)? {
                        ValueRef::Integer(v) => u32::try_from(v).ok(),
                        _ => None,
                    };
                    let pos = w.walk.rows();
                    w.walk.push(id, ts.unwrap_or(0));
                    rows += 1;
                    if id >= start && stop.is_none_or(|s| id < s) {
                        last_in_window = Some(id);
                    }
                    let (Some(ts), Some(topic)) = (ts, topic) else {
                        w.bad_fields.push((
                            pos,
                            topic,
                            format!("row {id}: its topic_id or timestamp is not an integer"),
                        ));
                        continue;
                    };
                    // A field that does not read is this row's loss only.
                    let fields = self.take_payload(&mut w, row, (pos, topic, ts), wanted);
                    if let Err(e) = fields {
                        w.bad_fields
                            .push((pos, Some(topic), format!("row {id}: sqlite3: {e}")));
                    }
                    if w.walk.rows() >= limit {
                        return Ok(());
                    }
                }
                Ok(())
            })();
            let error = r.err().map(|e| format!("sqlite3: {e}"));
            let broke = error.is_some();
            w.walk.segments.push(table_walk::Segment {
                seek: at,
                rows,
                error,
            });
            if broke {
                let from = last_in_window.unwrap_or(at);
                seek_at = seek_past(conn, from, stop, self.capacity);
            }
        }
        w
    }
}

/// The query of a part's walk: every row from an id on, the payload only of the wanted
/// topics.
fn walk_sql(wanted: &[u32]) -> String {
    let list: Vec<String> = wanted.iter().map(|c| c.to_string()).collect();
    format!(
        "SELECT id, timestamp, topic_id, CASE WHEN topic_id IN ({}) THEN data END FROM messages NOT INDEXED WHERE id >= ?1",
        if list.is_empty() {
            "NULL".to_string()
        } else {
            list.join(",")
        }
    )
}

/// The rows of a part's walk that were kept but do not read, as losses: rows whose fields
/// do not read (on their topic when it reads) and rows that name no topic the table holds.
fn row_losses(
    w: &Walked2,
    start: i64,
    kept: &dyn Fn(u64) -> bool,
    want: &(dyn Fn(u32) -> bool + Sync),
) -> Vec<Loss> {
    let mut lost = Vec::new();
    // Rows whose fields do not read are lost, on their topic when it reads.
    let mut bad: std::collections::BTreeMap<Option<u32>, (u64, &str)> = Default::default();
    for (pos, topic, why) in &w.bad_fields {
        if kept(*pos) && topic.is_none_or(want) {
            let e = bad.entry(*topic).or_insert((0, why.as_str()));
            e.0 += 1;
        }
    }
    for (topic, (n, why)) in bad {
        lost.push(Loss {
            what: format!(
                "message rows {start}..: {n} row(s) whose fields do not read (first: {why})"
            ),
            messages: Some(n),
            channel: topic,
            ..Loss::default()
        });
    }
    let strays: Vec<u32> = w
        .stray_topic
        .iter()
        .filter(|(p, _)| kept(*p))
        .map(|x| x.1)
        .collect();
    if let Some(id) = strays.first() {
        let n = strays.len();
        lost.push(Loss {
            what: format!(
                "message rows {start}..: {n} row(s) name topic id {id}{}, which the topics table does not hold (damaged rows)",
                if n > 1 { " or another" } else { "" }
            ),
            messages: Some(n as u64),
            ..Loss::default()
        });
    }
    lost
}

/// A database opened for reading, with its table names: the file itself, or the whole
/// pages of a truncated one from a private copy (with the note and loss that says so).
struct Connected {
    conn: Connection,
    read_path: std::path::PathBuf,
    copy: Option<tempfile::TempDir>,
    tables: Vec<String>,
    notes: Vec<Note>,
    losses: Vec<Loss>,
}

impl Connected {
    fn to(path: &Path) -> Result<Connected, Error> {
        let tables_of = |conn: &Connection| -> Result<Vec<String>, rusqlite::Error> {
            conn.prepare("SELECT name FROM sqlite_master WHERE type = 'table'")
                .and_then(|mut s| {
                    s.query_map([], |r| r.get::<_, String>(0))?
                        .collect::<Result<_, _>>()
                })
        };
        let mut notes = Vec::new();
        let mut losses = Vec::new();
        let mut read_path = path.to_path_buf();
        let mut copy = None;
        let mut conn = connect(path).map_err(|e| sql_err(path, e))?;
        let mut tables = tables_of(&conn);
        if tables.is_err()
            && let Some((tmp, kept, pages, page)) = truncated_copy(path)?
        {
            // SQLite refuses a file shorter than its header says; its whole pages are read
            // from a private copy that says what it holds.
            notes.push(Note::warning(format!(
                "the file is truncated: it holds {kept} of the {pages} pages its header announces; they were read from a private copy"
            )));
            losses.push(Loss {
                what: format!(
                    "the last {} page(s) of the file are missing (truncated)",
                    pages - kept
                ),
                at_most: Some(
                    ((pages - kept) as u64).saturating_mul(page) / crate::imu_msg::MIN_IMU_PAYLOAD,
                ),
                ..Loss::default()
            });
            read_path = tmp.path().join("truncated.db3");
            conn = connect(&read_path).map_err(|e| sql_err(path, e))?;
            tables = tables_of(&conn);
            copy = Some(tmp);
        }
        let tables = tables.map_err(|e| sql_err(path, e))?;
        Ok(Connected {
            conn,
            read_path,
            copy,
            tables,
            notes,
            losses,
        })
    }
}

/// The topics table, as channels.
fn topics(conn: &Connection) -> Result<Vec<source::Channel>, rusqlite::Error> {
    conn.prepare("SELECT id, name, type, serialization_format FROM topics ORDER BY id")
        .and_then(|mut s| {
            s.query_map([], |r| {
                Ok(source::Channel {
                    id: r.get::<_, i64>(0)? as u32,
                    topic: r.get(1)?,
                    msg_type: r.get(2)?,
                    encoding: Encoding::from_name(&r.get::<_, String>(3)?),
                    md5sum: None,
                    count: None,
                })
            })?
            .collect::<Result<Vec<_>, _>>()
        })
}

/// The parts of the message rows that start at `starts`.
fn row_parts(starts: &[i64]) -> Vec<Part> {
    starts
        .iter()
        .enumerate()
        .map(|(k, a)| Part {
            // Rows hold no count; the bound is never used to size memory.
            bytes: u64::MAX,
            label: match starts.get(k + 1) {
                Some(b) => format!("message rows {a}..{}", b - 1),
                None => format!("message rows {a}.."),
            },
            span: None,
            counts: None,
        })
        .collect()
}

/// One part's walk with the payloads it keeps.
#[derive(Default)]
struct Walked2 {
    walk: Walk,
    /// Wanted rows: (walk position, topic, record time, bytes in the arena).
    rows: Vec<(u64, u32, u64, std::ops::Range<usize>)>,
    arena: Vec<u8>,
    /// Rows naming no topic of the topics table: (walk position, topic id).
    stray_topic: Vec<(u64, u32)>,
    /// Rows whose fields did not read: (walk position, topic if it read, why).
    bad_fields: Vec<(u64, Option<u32>, String)>,
}

/// The first id of each part: the table's first id, then one id sought every
/// [`ROWS_PER_PART`] ids up to its last (bounded by what the file can hold, so that a
/// damaged last id cannot make millions of parts).
fn plan_parts(
    conn: &Connection,
    capacity: u64,
    notes: &mut Vec<Note>,
    losses: &mut Vec<Loss>,
) -> Vec<i64> {
    let first = match seek(conn, i64::MIN) {
        Ok(Some(id)) => Some(id),
        Ok(None) => None,
        Err(e) => {
            notes.push(Note::warning(format!(
                "the messages table's first page is unreadable (sqlite3: {e}); reading from the first id that can be sought"
            )));
            seek_past(conn, 0, None, capacity)
        }
    };
    let Some(first) = first else {
        return Vec::new();
    };
    let last: i64 = match conn.query_row("SELECT max(id) FROM messages NOT INDEXED", [], |r| {
        r.get::<_, Option<i64>>(0)
    }) {
        Ok(Some(v)) => v,
        Ok(None) => first,
        Err(e) => {
            losses.push(Loss::new(format!(
                "the messages table's last page is unreadable (sqlite3: {e})"
            )));
            first.saturating_add(capacity as i64)
        }
    };
    let end = last.min(first.saturating_add(capacity.min(i64::MAX as u64) as i64));
    let mut starts = vec![first];
    let mut at = first;
    while let Some(next) = at.checked_add(ROWS_PER_PART) {
        if next > end {
            break;
        }
        at = next;
        let prev = *starts.last().expect("one start");
        let found = match seek(conn, at) {
            Ok(v) => v,
            Err(_) => seek_past(conn, at, at.checked_add(ROWS_PER_PART), capacity),
        };
        match found {
            Some(id) if id > prev && id <= end => starts.push(id),
            Some(_) | None => {}
        }
    }
    starts
}

impl Source for Sqlite3Reader {
    fn kind(&self) -> InputKind {
        InputKind::Sqlite3
    }
    fn contents(&self) -> &source::Contents {
        &self.contents
    }
    fn read_part(
        &self,
        part: usize,
        want: &(dyn Fn(u32) -> bool + Sync),
        sink: &mut MessageSink<'_>,
    ) -> PartRead {
        let mut out = PartRead::default();
        let Some(&start) = self.starts.get(part) else {
            out.error = Some(source::PartError::NoSuchPart {
                index: part,
                wording: source::NoSuchPart::Part,
            });
            return out;
        };
        let stop = self.starts.get(part + 1).copied();
        let conn = match self.take() {
            Ok(c) => c,
            Err(e) => {
                out.error = Some(source::PartError::Storage(e.into()));
                return out;
            }
        };
        // One walk: ids, record times and the wanted payloads; judged, then delivered.
        let wanted: Vec<u32> = self
            .contents
            .channels
            .iter()
            .map(|c| c.id)
            .filter(|&c| want(c))
            .collect();
        let w = self.walk(&conn, start, stop, &wanted);
        let mut ts_of = |id: i64| -> Option<i64> {
            conn.prepare_cached("SELECT timestamp FROM messages NOT INDEXED WHERE id = ?1")
                .and_then(|mut s| s.query_row(params![id], |r| r.get(0)).optional())
                .ok()
                .flatten()
        };
        let plan = table_walk::plan(&w.walk, start, stop, &mut ts_of);
        self.give(conn);
        let kept = |pos: u64| {
            let k = plan.skip.partition_point(|s| s.1 <= pos);
            plan.skip.get(k).is_none_or(|s| s.0 > pos)
        };
        for (pos, topic, t, bytes) in &w.rows {
            if kept(*pos) {
                sink(*topic, *t, &w.arena[bytes.clone()]);
                out.delivered += 1;
            }
        }
        out.lost.extend(row_losses(&w, start, &kept, want));
        self.plan_losses(&plan, start, &mut out);
        let walk_rows = w.walk.rows();
        if let Ok(mut w) = self.walked.lock() {
            w.rows += walk_rows;
            w.parts += 1;
            if stop.is_none() {
                w.max_id = plan.max_id;
            }
            if part == 0 {
                w.min_id = plan.min_id;
            }
        }
        out
    }

    fn losses_after_read(&self) -> Vec<Loss> {
        let (max_id, min_id) = match self.walked.lock() {
            Ok(w) if w.parts == self.starts.len() => (w.max_id, w.min_id),
            _ => return Vec::new(),
        };
        let Ok(conn) = self.take() else {
            return Vec::new();
        };
        let mut out = Vec::new();
        match &self.index {
            Some(index) => {
                out.extend(self.index_tail(&conn, index, max_id, min_id));
            }
            None => {
                let r: Result<Vec<String>, _> = conn
                    .prepare("PRAGMA quick_check(3)")
                    .and_then(|mut s| s.query_map([], |r| r.get(0))?.collect());
                match r {
                    Ok(v) if v.len() == 1 && v[0] == "ok" => {}
                    Ok(v) => {
                        // Its first findings, on one line.
                        let said: Vec<&str> = v
                            .iter()
                            .flat_map(|x| x.lines())
                            .filter(|l| !l.starts_with("***"))
                            .take(2)
                            .collect();
                        out.push(Loss::new(format!(
                            "the file is damaged (sqlite3 quick_check: {}); the table keeps no index to count the rows it may have lost",
                            said.join("; ")
                        )))
                    }
                    Err(e) => out.push(Loss::new(format!(
                        "the file is damaged (sqlite3 quick_check: {e}); the table keeps no index to count the rows it may have lost"
                    ))),
                }
            }
        }
        self.give(conn);
        out
    }
}

impl Sqlite3Reader {
    /// The rows the timestamp index lists past either end of what the table holds: a
    /// contiguous run of ids from the table's last (or down to its first) is rows the
    /// table lost; other ids are damage of the index itself. The index is scanned whole;
    /// when a damaged page of it stops the scan, its tail is sought by record time.
    fn index_tail(
        &self,
        conn: &Connection,
        index: &str,
        max_id: Option<(i64, i64)>,
        min_id: Option<i64>,
    ) -> Vec<Loss> {
        let hi = max_id.map_or(0, |m| m.0);
        let lo = min_id.unwrap_or(1);
        let index = format!("\"{}\"", index.replace('"', "\"\""));
        let scan = |sql: &str, p: &[i64]| index_rows(conn, sql, p, self.capacity);
        let whole = format!(
            "SELECT id, timestamp FROM messages INDEXED BY {index} WHERE id > ?1 OR id < ?2"
        );
        // Record times grow with the ids rosbag2 gives: the rows past the last one the table
        // holds are recorded after it.
        let tail = format!(
            "SELECT id, timestamp FROM messages INDEXED BY {index} WHERE timestamp >= ?1 AND id > ?2"
        );
        let mut found = match scan(&whole, &[hi, lo]) {
            Ok(v) => v,
            Err(e) => match scan(&tail, &[max_id.map_or(i64::MIN, |m| m.1), hi]) {
                Ok(v) => v,
                Err(_) => {
                    return vec![Loss::new(format!(
                        "the table's timestamp index is damaged (sqlite3: {e}); rows past the last one the table holds cannot be counted"
                    ))];
                }
            },
        };
        found.sort_unstable();
        found.dedup_by_key(|x| x.0);
        let mut out = Vec::new();
        let take_run = |ids: &mut dyn Iterator<Item = &(i64, i64)>, from: i64, up: bool| {
            listed_run(ids, from, up, self.capacity)
        };
        out.extend(take_run(
            &mut found.iter().filter(|x| x.0 > hi),
            hi.saturating_add(1),
            true,
        ));
        if lo > 1 {
            out.extend(take_run(
                &mut found.iter().rev().filter(|x| x.0 < lo),
                lo - 1,
                false,
            ));
        }
        out
    }
}

/// The (id, record time) rows a query over the timestamp index gives, at most one past
/// `capacity` (what the file can hold).
fn index_rows(
    conn: &Connection,
    sql: &str,
    p: &[i64],
    capacity: u64,
) -> Result<Vec<(i64, i64)>, rusqlite::Error> {
    let mut st = conn.prepare(sql)?;
    let mut q = st.query(rusqlite::params_from_iter(p))?;
    let mut found = Vec::new();
    while let Some(row) = q.next()? {
        found.push((row.get(0)?, row.get::<_, Option<i64>>(1)?.unwrap_or(0)));
        if found.len() as u64 > capacity {
            break;
        }
    }
    Ok(found)
}

/// The run of consecutive ids from `from` (upwards or downwards) that the index lists and
/// the table lacks, as a loss.
fn listed_run(
    ids: &mut dyn Iterator<Item = &(i64, i64)>,
    from: i64,
    up: bool,
    capacity: u64,
) -> Option<Loss> {
    let mut expect = from;
    let (mut n, mut t0, mut t1) = (0u64, i64::MAX, i64::MIN);
    let mut ends = (from, from);
    for &(id, ts) in ids {
        if id != expect {
            break;
        }
        n += 1;
        t0 = t0.min(ts);
        t1 = t1.max(ts);
        ends = if up { (from, id) } else { (id, from) };
        expect = if up {
            id.saturating_add(1)
        } else {
            id.saturating_sub(1)
        };
    }
    (n > 0).then(|| Loss {
        what: format!(
            "message rows {}..{} that the table's timestamp index lists are missing from the table (a damaged page)",
            ends.0, ends.1
        ),
        messages: Some(n.min(capacity)),
        span: Some((t0.max(0) as u64, t1.max(0) as u64)),
        ..Loss::default()
    })
}

/// Writes a rosbag2 `.db3` in the current schema (version 4: `schema`, `metadata`,
/// `topics` with QoS and type hash, `message_definitions`, `messages`).
pub struct Sqlite3Writer {
    path: PathBuf,
    conn: Connection,
}

impl Sqlite3Writer {
    /// Creates the database with its tables, in one transaction until [`Self::finish`].
    pub fn create(path: &Path) -> Result<Sqlite3Writer, Error> {
        let conn = Connection::open(path).map_err(|e| sql_err(path, e))?;
        conn.execute_batch(
            "PRAGMA journal_mode = MEMORY;
             PRAGMA synchronous = OFF;
             CREATE TABLE schema(schema_version INTEGER PRIMARY KEY, ros_distro TEXT NOT NULL);
             INSERT INTO schema VALUES (4, '');
             CREATE TABLE metadata(id INTEGER PRIMARY KEY, metadata_version INTEGER NOT NULL, metadata TEXT NOT NULL);
             CREATE TABLE topics(id INTEGER PRIMARY KEY, name TEXT NOT NULL, type TEXT NOT NULL, serialization_format TEXT NOT NULL, offered_qos_profiles TEXT NOT NULL, type_description_hash TEXT NOT NULL);
             CREATE TABLE message_definitions(id INTEGER PRIMARY KEY, topic_type TEXT NOT NULL, encoding TEXT NOT NULL, encoded_message_definition TEXT NOT NULL, type_description_hash TEXT NOT NULL);
             CREATE TABLE messages(id INTEGER PRIMARY KEY, topic_id INTEGER NOT NULL, timestamp INTEGER NOT NULL, data BLOB NOT NULL);
             BEGIN;",
        )
        .map_err(|e| sql_err(path, e))?;
        Ok(Sqlite3Writer {
            path: path.to_path_buf(),
            conn,
        })
    }

    /// Declares a topic (and its type's definition); returns its id.
    pub fn add_topic(
        &mut self,
        name: &str,
        msg_type: &str,
        definition: &str,
        type_hash: &str,
        qos: &str,
    ) -> Result<i64, Error> {
        let r = (|| {
            self.conn.execute(
                "INSERT INTO topics (name, type, serialization_format, offered_qos_profiles, type_description_hash) VALUES (?1, ?2, 'cdr', ?3, ?4)",
                params![name, msg_type, qos, type_hash],
            )?;
            let id = self.conn.last_insert_rowid();
            let known: i64 = self.conn.query_row(
                "SELECT count(*) FROM message_definitions WHERE topic_type = ?1",
                params![msg_type],
                |r| r.get(0),
            )?;
            if known == 0 {
                self.conn.execute(
                    "INSERT INTO message_definitions (topic_type, encoding, encoded_message_definition, type_description_hash) VALUES (?1, 'ros2msg', ?2, ?3)",
                    params![msg_type, definition, type_hash],
                )?;
            }
            Ok(id)
        })();
        r.map_err(|e| sql_err(&self.path, e))
    }

    /// Appends one message with its receive time (ns).
    pub fn write(&mut self, topic: i64, time_ns: u64, data: &[u8]) -> Result<(), Error> {
        let t = i64::try_from(time_ns).map_err(|_| Error::BadMessage {
            what: format!("record time {time_ns} ns does not fit rosbag2's int64"),
        })?;
        self.conn
            .prepare_cached("INSERT INTO messages (topic_id, timestamp, data) VALUES (?1, ?2, ?3)")
            .and_then(|mut s| s.execute(params![topic, t, data]))
            .map(|_| ())
            .map_err(|e| sql_err(&self.path, e))
    }

    /// Stores the bag's metadata, builds the timestamp index and commits.
    pub fn finish(self, metadata_yaml: &str) -> Result<(), Error> {
        let r = (|| {
            self.conn.execute(
                "INSERT INTO metadata (metadata_version, metadata) VALUES (8, ?1)",
                params![metadata_yaml],
            )?;
            self.conn
                .execute_batch("CREATE INDEX timestamp_idx ON messages (timestamp ASC); COMMIT;")
        })();
        r.map_err(|e| sql_err(&self.path, e))?;
        self.conn.close().map_err(|(_, e)| sql_err(&self.path, e))
    }
}
