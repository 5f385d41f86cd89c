//! rosbag2's sqlite3 storage (`.db3`), read and written with `rusqlite` (bundled SQLite).
//!
//! Every schema version from Foxy to today shares what the reader needs: `topics(id, name,
//! type, serialization_format, …)` and `messages(id INTEGER PRIMARY KEY, topic_id,
//! timestamp, data)`, where `timestamp` is the receive time in ns (the record time). Later
//! versions add `offered_qos_profiles`, `type_description_hash`, and the `schema`,
//! `metadata` and `message_definitions` tables, which the reader does not need. Parts are
//! ranges of message ids, read in parallel, each on its own connection from a small pool.

use std::path::{Path, PathBuf};
use std::sync::Mutex;

use rusqlite::{Connection, OpenFlags, OptionalExtension, params};

use crate::error::Error;
use crate::source::{self, Encoding, InputKind, Loss, MessageSink, Part, PartRead, Source};

/// Fewer bytes than any stored row takes (cell header, rowid, three columns): bounds the ids
/// a file can hold.
const MIN_ROW_BYTES: i64 = 8;

/// Message ids per part.
const ROWS_PER_PART: i64 = 65_536;

/// An open `.db3`.
pub struct Sqlite3Reader {
    path: PathBuf,
    pool: Mutex<Vec<Connection>>,
    /// Message ids of each part, `a..b` (parallel to the contents' parts).
    ranges: Vec<(i64, i64)>,
    contents: source::Contents,
    /// The `schema` table's version, when the file has one (ROS 2 Iron and later).
    pub schema_version: Option<i64>,
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

impl Sqlite3Reader {
    /// Opens a rosbag2 `.db3` read-only and lists its topics.
    pub fn open(path: &Path) -> Result<Sqlite3Reader, Error> {
        let conn = connect(path).map_err(|e| sql_err(path, e))?;
        let tables: Vec<String> = conn
            .prepare("SELECT name FROM sqlite_master WHERE type = 'table'")
            .and_then(|mut s| {
                s.query_map([], |r| r.get::<_, String>(0))?
                    .collect::<Result<_, _>>()
            })
            .map_err(|e| sql_err(path, e))?;
        for t in ["topics", "messages"] {
            if !tables.iter().any(|x| x == t) {
                return Err(Error::NotABag {
                    path: path.to_path_buf(),
                    what: format!(
                        "an SQLite database without the rosbag2 '{t}' table. Accepted: {}",
                        source::ACCEPTED
                    ),
                });
            }
        }
        let schema_version = if tables.iter().any(|x| x == "schema") {
            conn.query_row("SELECT max(schema_version) FROM schema", [], |r| {
                r.get::<_, Option<i64>>(0)
            })
            .ok()
            .flatten()
        } else {
            None
        };
        let channels = conn
            .prepare("SELECT id, name, type, serialization_format FROM topics ORDER BY id")
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
            .map_err(|e| sql_err(path, e))?;
        let mut notes = Vec::new();
        // The ends of the id range; when a damaged page hides them, every id the file could
        // hold is covered (parts over absent ids are cheap, empty seeks).
        let (lo, hi): (Option<i64>, Option<i64>) = match conn.query_row(
            "SELECT min(id), max(id) FROM messages",
            [],
            |r| Ok((r.get(0)?, r.get(1)?)),
        ) {
            Ok(v) => v,
            Err(e) => {
                let len = std::fs::metadata(path).map(|m| m.len()).unwrap_or(0) as i64;
                notes.push(format!(
                    "the messages table's first or last id is unreadable ({e}); every id the file could hold was tried"
                ));
                (Some(0), Some(len / MIN_ROW_BYTES))
            }
        };
        let mut ranges = Vec::new();
        if let (Some(lo), Some(hi)) = (lo, hi) {
            let mut a = lo;
            while a <= hi {
                let b = a.saturating_add(ROWS_PER_PART).min(hi.saturating_add(1));
                ranges.push((a, b));
                if b <= a {
                    break;
                }
                a = b;
            }
        }
        let parts = ranges
            .iter()
            .map(|(a, b)| Part {
                // Rows hold no count; the bound is never used to size memory.
                bytes: u64::MAX,
                label: format!("message rows {a}..{}", b - 1),
                span: None,
                counts: None,
            })
            .collect();
        Ok(Sqlite3Reader {
            path: path.to_path_buf(),
            pool: Mutex::new(vec![conn]),
            ranges,
            contents: source::Contents {
                channels,
                parts,
                notes,
                losses: Vec::new(),
            },
            schema_version,
        })
    }

    /// Counts the messages of every topic (a full pass over the table).
    pub fn count_messages(&self) -> Result<Vec<(u32, u64)>, Error> {
        let conn = self.take()?;
        let r = conn
            .prepare("SELECT topic_id, count(*) FROM messages GROUP BY topic_id")
            .and_then(|mut s| {
                s.query_map([], |r| {
                    Ok((r.get::<_, i64>(0)? as u32, r.get::<_, i64>(1)? as u64))
                })?
                .collect::<Result<Vec<_>, _>>()
            })
            .map_err(|e| sql_err(&self.path, e));
        self.give(conn);
        r
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
        let Some(&(a, b)) = self.ranges.get(part) else {
            out.error = Some("no such part".into());
            return out;
        };
        let conn = match self.take() {
            Ok(c) => c,
            Err(e) => {
                out.error = Some(e.to_string());
                return out;
            }
        };
        // Rows are read in id order; a damaged page ends the query, and the read resumes at
        // the first id past it that SQLite can read (probed at doubling distances), so one
        // bad page costs its own rows only. What was skipped is reported.
        let mut stray: Option<(u64, u32)> = None;
        let mut lo = a;
        while lo < b {
            let mut last: Option<i64> = None;
            let r = (|| -> Result<(), String> {
                let mut st = conn
                    .prepare_cached(
                        "SELECT id, topic_id, timestamp, data FROM messages WHERE id >= ?1 AND id < ?2",
                    )
                    .map_err(|e| format!("sqlite3: {e}"))?;
                let mut rows = st
                    .query(params![lo, b])
                    .map_err(|e| format!("sqlite3: {e}"))?;
                while let Some(row) = rows.next().map_err(|e| format!("sqlite3: {e}"))? {
                    let id = row.get::<_, i64>(0).map_err(|e| format!("sqlite3: {e}"))?;
                    // Ids come in increasing order inside the range; anything else is a
                    // damaged b-tree (a loop would otherwise deliver rows forever).
                    if id < lo || id >= b || last.is_some_and(|l| id <= l) {
                        return Err(format!("damaged table: row id {id} out of order"));
                    }
                    last = Some(id);
                    let fields = (|| -> Result<(), rusqlite::Error> {
                        let topic = row.get::<_, i64>(1)? as u32;
                        if !want(topic) {
                            if !self.contents.channels.iter().any(|c| c.id == topic) {
                                // A row naming no topic of the table: its message is lost.
                                let e = stray.get_or_insert((0u64, topic));
                                e.0 += 1;
                            }
                            return Ok(());
                        }
                        let t = row.get::<_, i64>(2)?.max(0) as u64;
                        let data = row.get_ref(3)?.as_blob()?;
                        sink(topic, t, data);
                        out.delivered += 1;
                        Ok(())
                    })();
                    if let Err(e) = fields {
                        out.skipped += 1;
                        out.skip_reason
                            .get_or_insert_with(|| format!("row {id}: sqlite3: {e}"));
                    }
                }
                Ok(())
            })();
            let Err(e) = r else { break };
            let from = last.map_or(lo, |l| l + 1);
            let mut step = 1i64;
            let resume = loop {
                let at = from.saturating_add(step);
                if at >= b {
                    break None;
                }
                let ok: Result<Option<i64>, _> = conn
                    .prepare_cached("SELECT id FROM messages WHERE id >= ?1 AND id < ?2 LIMIT 1")
                    .and_then(|mut st| st.query_row(params![at, b], |r| r.get(0)).optional());
                match ok {
                    Ok(Some(id)) => break Some(id),
                    Ok(None) => break None,
                    Err(_) => step = step.saturating_mul(2),
                }
            };
            let to = resume.unwrap_or(b);
            out.lost.push(Loss::new(format!(
                "message rows {from}..{} are unreadable ({e}) and were skipped",
                to - 1
            )));
            lo = to;
        }
        if let Some((n, id)) = stray {
            out.lost.push(Loss {
                what: format!(
                    "message rows {a}..{}: {n} row(s) name topic id {id}{}, which the topics table does not hold (damaged rows)",
                    b - 1,
                    if n > 1 { " or another" } else { "" }
                ),
                messages: Some(n),
                span: None,
                channel: None,
            });
        }
        self.give(conn);
        out
    }
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
