//! ROS 2 bags (rosbag2): a directory with `metadata.yaml` and one or more storage files
//! (`.db3` sqlite3 or `.mcap`), split files read in order, and rosbag2's compression: FILE
//! mode (each storage file one `.zstd` file) and MESSAGE mode (each payload one zstd frame).
//!
//! * [`metadata`]: `metadata.yaml`, read and written.
//! * [`sqlite`]: the `.db3` storage, read and written.
//! * [`BagDir`]: a bag directory (or a bare FILE-compressed file) as one
//!   [`crate::source::Source`], with channels merged across files by topic and type.
//! * [`Ros2BagWriter`]: a bag directory with one storage file, Imu as CDR.

use crate::shared::note::Note;

pub(crate) mod metadata;
pub(crate) mod sqlite;
mod table_walk;

pub use sqlite::{Sqlite3Reader, Sqlite3Writer};

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use crate::cdr;
use crate::error::Error;
use crate::imu_msg::Imu;
use crate::mcap::{ChunkCompression, McapReader, McapWriter};
use crate::shared::output::{AtomicDir, Outputs};
use crate::source::{self, Channel, InputKind, Loss, MessageSink, PartRead, Source};
use crate::zstd::Decompressed;
use metadata::{BagInfo, OFFERED_QOS_PROFILES, WrittenBag, WrittenTopic};

thread_local! {
    /// Per-thread buffer for MESSAGE-mode decompression.
    static PAYLOAD: std::cell::RefCell<Vec<u8>> = const { std::cell::RefCell::new(Vec::new()) };
}

/// Fewer bytes than any stored message takes (a sqlite3 row's least): bounds the messages
/// storage files can hold.
const MIN_STORED_MESSAGE: u64 = 8;

/// Largest decompressed message accepted in MESSAGE mode (a damaged frame cannot make the
/// reader allocate more).
const MAX_MESSAGE_BYTES: u64 = 1 << 30;

struct FileSource {
    src: Box<dyn Source>,
    /// Channel id in this file → id in the bag.
    ids: BTreeMap<u32, u32>,
    _tmp: Option<Decompressed>,
}

/// A ROS 2 bag directory, read as one source.
pub struct BagDir {
    files: Vec<FileSource>,
    /// Part in the bag → (file, part in the file).
    part_map: Vec<(usize, usize)>,
    /// Each channel's count as its storage files state it (before metadata.yaml's).
    file_counts: BTreeMap<u32, Option<u64>>,
    message_zstd: bool,
    contents: source::Contents,
    /// The parsed `metadata.yaml`, when there is one.
    pub info: Option<BagInfo>,
}

fn open_storage(path: &Path) -> Result<(Box<dyn Source>, Option<Decompressed>), Error> {
    let (inner, tmp) = match crate::detect::input_kind(path)? {
        InputKind::Zstd => {
            let d = crate::zstd::decompress_zstd_file(path)?;
            (d.path.clone(), Some(d))
        }
        _ => (path.to_path_buf(), None),
    };
    let src: Box<dyn Source> = match crate::detect::input_kind(&inner)? {
        InputKind::Mcap => Box::new(McapReader::open(&inner)?),
        InputKind::Sqlite3 => Box::new(Sqlite3Reader::open(&inner)?),
        other => {
            return Err(Error::NotABag {
                path: path.to_path_buf(),
                what: format!(
                    "a {} where a rosbag2 storage file (.db3 or .mcap) was expected",
                    other.describe()
                ),
            });
        }
    };
    Ok((src, tmp))
}

impl BagDir {
    /// Opens the bag directory `dir` (its `metadata.yaml` lists the storage files).
    pub(crate) fn open(dir: &Path) -> Result<BagDir, Error> {
        let meta_path = dir.join("metadata.yaml");
        let text = std::fs::read_to_string(&meta_path).map_err(|e| Error::io(&meta_path, e))?;
        let mut notes = Vec::new();
        let mut losses = Vec::new();
        // A damaged metadata.yaml costs its promises, not the storage files beside it.
        let mut damaged = false;
        let info = BagInfo::parse(&text).unwrap_or_else(|e| {
            damaged = true;
            notes.push(Note::warning(format!(
                "{} is damaged ({e}); the storage files in the directory were read without it (it promises no counts)",
                meta_path.display()
            )));
            BagInfo::default()
        });
        let paths = storage_paths(dir, &info, damaged, &mut notes, &mut losses)?;
        let mut files = Vec::new();
        for p in &paths {
            if !p.exists() {
                losses.push(Loss {
                    what: format!("{} is listed in metadata.yaml but missing", p.display()),
                    messages: None,
                    span: None,
                    channel: None,
                    ..Loss::default()
                });
                continue;
            }
            let (src, tmp) = open_storage(p)?;
            files.push((src, tmp));
        }
        if files.is_empty() {
            return Err(Error::Storage {
                path: meta_path,
                what: "the bag directory holds none of its storage files".into(),
            });
        }
        let message_zstd = info.compression_mode() == "message";
        if message_zstd && info.compression_format() != "zstd" {
            return Err(Error::Storage {
                path: meta_path,
                what: format!(
                    "unsupported message compression '{}' (zstd is)",
                    info.compression_format()
                ),
            });
        }
        let held = held_bytes(&paths, &info);
        let mut d = Self::assemble(files, Some(info), message_zstd, notes, losses);
        d.bound_promises(held);
        Ok(d)
    }

    /// Drops a count of `metadata.yaml` that is more than `bytes` of storage can hold (a
    /// damaged count), with a note; the storage's own count stands.
    fn bound_promises(&mut self, bytes: u64) {
        for c in self.contents.channels.iter_mut() {
            let least = if crate::series::is_imu(c) {
                crate::imu_msg::MIN_IMU_PAYLOAD
            } else {
                MIN_STORED_MESSAGE
            };
            let most = bytes / least;
            if let Some(n) = c.count
                && n > most
            {
                self.contents.notes.push(Note::warning(format!(
                    "metadata.yaml promises {n} messages on '{}', more than its storage files can hold (at most {most}): the count is damaged and not used",
                    crate::printable::escape(&c.topic)
                )));
                c.count = self.file_counts.get(&c.id).copied().flatten();
            }
        }
    }

    /// Opens a bare FILE-mode compressed storage file (`.mcap.zstd`, `.db3.zstd`).
    pub(crate) fn open_compressed_file(path: &Path) -> Result<BagDir, Error> {
        let (src, tmp) = open_storage(path)?;
        Ok(Self::assemble(
            vec![(src, tmp)],
            None,
            false,
            Vec::new(),
            Vec::new(),
        ))
    }

    fn assemble(
        files: Vec<(Box<dyn Source>, Option<Decompressed>)>,
        info: Option<BagInfo>,
        message_zstd: bool,
        mut notes: Vec<Note>,
        mut losses: Vec<Loss>,
    ) -> BagDir {
        let mut channels: Vec<Channel> = Vec::new();
        let mut out_files = Vec::new();
        let mut part_map = Vec::new();
        let mut parts = Vec::new();
        let multi = files.len() > 1;
        for (fi, (src, tmp)) in files.into_iter().enumerate() {
            let ids = merge_channels(&mut channels, src.as_ref());
            for (pi, p) in src.parts().iter().enumerate() {
                part_map.push((fi, pi));
                let mut p = p.clone();
                if multi {
                    p.label = format!("file {}: {}", fi + 1, p.label);
                }
                p.counts = p.counts.map(|v| {
                    v.into_iter()
                        .filter_map(|(c, n)| ids.get(&c).map(|g| (*g, n)))
                        .collect()
                });
                parts.push(p);
            }
            notes.extend(src.notes().iter().cloned());
            losses.extend(src.losses().iter().map(|l| Loss {
                channel: l.channel.and_then(|c| ids.get(&c).copied()),
                ..l.clone()
            }));
            out_files.push(FileSource {
                src,
                ids,
                _tmp: tmp,
            });
        }
        let file_counts: BTreeMap<u32, Option<u64>> =
            channels.iter().map(|c| (c.id, c.count)).collect();
        if let Some(info) = &info {
            promised_counts(&mut channels, info);
        }
        BagDir {
            files: out_files,
            file_counts,
            part_map,
            message_zstd,
            contents: source::Contents {
                channels,
                parts,
                notes,
                losses,
                log_start: None,
                integration: Vec::new(),
            },
            info,
        }
    }
}

impl Source for BagDir {
    fn kind(&self) -> InputKind {
        if self.info.is_some() {
            InputKind::Rosbag2Dir
        } else {
            InputKind::Zstd
        }
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
        let Some(&(fi, pi)) = self.part_map.get(part) else {
            return PartRead {
                error: Some(source::PartError::NoSuchPart {
                    index: part,
                    wording: source::NoSuchPart::Part,
                }),
                ..PartRead::default()
            };
        };
        let f = &self.files[fi];
        let local_want = |c: u32| f.ids.get(&c).is_some_and(|g| want(*g));
        let mut skipped = 0;
        let mut skip_reason = None;
        let mut r = f.src.read_part(pi, &local_want, &mut |c, t, data| {
            let g = f.ids[&c];
            if !self.message_zstd {
                sink(g, t, data);
                return;
            }
            PAYLOAD.with(|cell| {
                let mut buf = cell.borrow_mut();
                match crate::zstd::decompress_into(data, &mut buf, MAX_MESSAGE_BYTES) {
                    Ok(()) => sink(g, t, &buf),
                    Err(e) => {
                        skipped += 1;
                        skip_reason.get_or_insert(source::SkipReason::Decompress(e.into()));
                    }
                }
            });
        });
        r.delivered -= skipped;
        r.skipped += skipped;
        if r.skip_reason.is_none() {
            r.skip_reason = skip_reason;
        }
        for l in r.lost.iter_mut() {
            l.channel = l.channel.and_then(|c| f.ids.get(&c).copied());
        }
        r
    }
    fn losses_after_read(&self) -> Vec<Loss> {
        let multi = self.files.len() > 1;
        let mut out = Vec::new();
        for (fi, f) in self.files.iter().enumerate() {
            for mut l in f.src.losses_after_read() {
                l.channel = l.channel.and_then(|c| f.ids.get(&c).copied());
                if multi {
                    l.what = format!("file {}: {}", fi + 1, l.what);
                }
                out.push(l);
            }
        }
        out
    }
}

/// The storage of a bag [`Ros2BagWriter`] writes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Storage {
    /// One `.db3`.
    Sqlite3,
    /// One `.mcap`, chunks compressed as given.
    Mcap(ChunkCompression),
}

enum StorageWriter {
    Sqlite3(Sqlite3Writer),
    Mcap(Box<McapWriter>),
}

/// A topic handle of [`Ros2BagWriter`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct TopicId(usize);

/// Writes a ROS 2 bag directory: `metadata.yaml` plus one storage file named after the
/// directory (`<name>_0.db3` or `<name>_0.mcap`), the way `ros2 bag record` lays it out.
pub struct Ros2BagWriter {
    dir: AtomicDir,
    storage: StorageWriter,
    file: String,
    topics: Vec<(WrittenTopic, i64)>,
    span: Option<(u64, u64)>,
    scratch: Vec<u8>,
}

impl Ros2BagWriter {
    /// Starts the bag directory `dir` (which must not exist yet) among the run's `outputs`.
    pub fn create(outputs: &Outputs, dir: &Path, storage: Storage) -> Result<Ros2BagWriter, Error> {
        let d = AtomicDir::create(outputs, dir)?;
        let stem = dir
            .file_name()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| "bag".into());
        let (file, storage) = match storage {
            Storage::Sqlite3 => {
                let f = format!("{stem}_0.db3");
                let w = Sqlite3Writer::create(&d.path().join(&f))?;
                (f, StorageWriter::Sqlite3(w))
            }
            Storage::Mcap(c) => {
                let f = format!("{stem}_0.mcap");
                let w = McapWriter::create(&Outputs::direct(), &d.path().join(&f), "ros2", c)?;
                (f, StorageWriter::Mcap(Box::new(w)))
            }
        };
        Ok(Ros2BagWriter {
            dir: d,
            storage,
            file,
            topics: Vec::new(),
            span: None,
            scratch: Vec::with_capacity(512),
        })
    }

    /// Sets the MCAP chunk size (bytes of records per chunk; no effect on sqlite3).
    pub fn set_mcap_chunk_size(&mut self, bytes: usize) {
        if let StorageWriter::Mcap(w) = &mut self.storage {
            w.set_chunk_size(bytes);
        }
    }

    /// Declares a topic of any type with its `ros2msg` definition and type hash.
    pub fn add_topic(
        &mut self,
        name: &str,
        msg_type: &str,
        definition: &str,
        type_hash: &str,
    ) -> Result<TopicId, Error> {
        let id = match &mut self.storage {
            StorageWriter::Sqlite3(w) => {
                w.add_topic(name, msg_type, definition, type_hash, OFFERED_QOS_PROFILES)?
            }
            StorageWriter::Mcap(w) => {
                let s = w.add_schema(msg_type, cdr::SCHEMA_ENCODING, definition.as_bytes())?;
                w.add_channel(
                    s,
                    name,
                    cdr::ENCODING,
                    &[(
                        "offered_qos_profiles".to_string(),
                        OFFERED_QOS_PROFILES.to_string(),
                    )],
                )? as i64
            }
        };
        self.topics.push((
            WrittenTopic {
                name: name.to_string(),
                msg_type: msg_type.to_string(),
                type_hash: type_hash.to_string(),
                count: 0,
            },
            id,
        ));
        Ok(TopicId(self.topics.len() - 1))
    }

    /// Declares a `sensor_msgs/msg/Imu` topic.
    pub fn add_imu_topic(&mut self, name: &str) -> Result<TopicId, Error> {
        self.add_topic(name, cdr::TYPE, &cdr::definition(), cdr::TYPE_HASH)
    }

    /// Appends one Imu message (CDR, little-endian) with its record time (ns).
    pub fn write_imu(&mut self, topic: TopicId, time_ns: u64, imu: &Imu) -> Result<(), Error> {
        let mut buf = std::mem::take(&mut self.scratch);
        buf.clear();
        let r = cdr::encode(imu, cdr::Endian::Little, &mut buf)
            .and_then(|_| self.write_raw(topic, time_ns, &buf));
        self.scratch = buf;
        r
    }

    /// Appends one already-serialized (CDR) message with its record time (ns).
    pub fn write_raw(&mut self, topic: TopicId, time_ns: u64, data: &[u8]) -> Result<(), Error> {
        let (t, id) = self
            .topics
            .get_mut(topic.0)
            .ok_or_else(|| Error::BadMessage {
                what: format!("unknown topic {}", topic.0),
            })?;
        match &mut self.storage {
            StorageWriter::Sqlite3(w) => w.write(*id, time_ns, data)?,
            StorageWriter::Mcap(w) => {
                let seq = t.count as u32;
                w.write(*id as u16, seq, time_ns, time_ns, data)?
            }
        }
        t.count += 1;
        self.span = Some(match self.span {
            None => (time_ns, time_ns),
            Some((a, b)) => (a.min(time_ns), b.max(time_ns)),
        });
        Ok(())
    }

    /// Finishes the storage file, writes `metadata.yaml` and renames the directory into
    /// place.
    pub fn finish(self) -> Result<(), Error> {
        let bag = WrittenBag {
            storage: match self.storage {
                StorageWriter::Sqlite3(_) => "sqlite3",
                StorageWriter::Mcap(_) => "mcap",
            },
            file: self.file.clone(),
            topics: self.topics.iter().map(|(t, _)| t.clone()).collect(),
            span: self.span,
        };
        let yaml = metadata::write_yaml(&bag);
        match self.storage {
            StorageWriter::Sqlite3(w) => w.finish(&yaml)?,
            StorageWriter::Mcap(w) => w.finish()?,
        }
        // Files inside the bag's temporary directory go in place with it (its one rename).
        Outputs::direct().write_atomic(&self.dir.path().join("metadata.yaml"), |w| {
            w.write_all(yaml.as_bytes())
        })?;
        self.dir.commit()
    }
}

/// Adds the channels of one storage file to the bag's (one per topic, type and encoding,
/// their counts summed); returns the file's channel ids → the bag's.
fn merge_channels(channels: &mut Vec<Channel>, src: &dyn Source) -> BTreeMap<u32, u32> {
    let mut ids = BTreeMap::new();
    for c in src.channels() {
        let found = channels
            .iter_mut()
            .find(|g| g.topic == c.topic && g.msg_type == c.msg_type && g.encoding == c.encoding);
        let gid = match found {
            Some(g) => {
                g.count = g.count.zip(c.count).map(|(a, b)| a + b);
                g.id
            }
            None => {
                let id = channels.len() as u32 + 1;
                channels.push(Channel { id, ..c.clone() });
                id
            }
        };
        ids.insert(c.id, gid);
    }
    ids
}

/// Sets each channel's count to what metadata.yaml states for its topic and type.
fn promised_counts(channels: &mut [Channel], info: &BagInfo) {
    // metadata.yaml's counts are what the recorder promised for the whole bag.
    for c in channels.iter_mut() {
        if let Some(t) = info
            .topics_with_message_count
            .iter()
            .find(|t| t.topic_metadata.name == c.topic && t.topic_metadata.msg_type == c.msg_type)
        {
            c.count = Some(t.message_count);
        }
    }
}

/// The storage files to read: those `metadata.yaml` lists, or, when none of them is there
/// (some tools leave the list empty), the storage files in the directory in name order,
/// with a note and a loss per listed file that is missing.
fn storage_paths(
    dir: &Path,
    info: &BagInfo,
    damaged: bool,
    notes: &mut Vec<Note>,
    losses: &mut Vec<Loss>,
) -> Result<Vec<PathBuf>, Error> {
    let mut paths: Vec<PathBuf> = info
        .relative_file_paths
        .iter()
        .map(|r| dir.join(r))
        .collect();
    let listed = paths.len();
    if !paths.iter().any(|p| p.exists()) {
        // Some tools leave the list empty; take the storage files in name order (also
        // when none of those listed is there).
        let mut found: Vec<PathBuf> = std::fs::read_dir(dir)
            .map_err(|e| Error::io(dir, e))?
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| {
                let n = p.to_string_lossy();
                [".db3", ".mcap", ".db3.zstd", ".mcap.zstd"]
                    .iter()
                    .any(|x| n.ends_with(x))
            })
            .collect();
        found.sort();
        if listed == 0 && !damaged {
            notes.push(Note::warning(format!(
                "metadata.yaml lists no storage files; reading the {} found in the directory",
                found.len()
            )));
        } else if listed > 0 && !found.is_empty() {
            notes.push(Note::warning(format!(
                "none of the {listed} storage file(s) metadata.yaml lists is in the directory; reading the {} found there",
                found.len()
            )));
        }
        for p in &paths {
            losses.push(Loss::new(format!(
                "{} is listed in metadata.yaml but missing",
                p.display()
            )));
        }
        paths = found;
    }
    Ok(paths)
}

/// What the storage files can hold, in bytes: it bounds the counts metadata.yaml states
/// (compressed data, MCAP chunks included, expands by at most MAX_EXPANSION).
fn held_bytes(paths: &[PathBuf], info: &BagInfo) -> u64 {
    paths
        .iter()
        .filter_map(|p| {
            let len = std::fs::metadata(p).ok()?.len();
            let raw = crate::detect::input_kind(p).ok()? == InputKind::Sqlite3
                && info.compression_mode().is_empty();
            Some(if raw {
                len
            } else {
                len.saturating_mul(source::MAX_EXPANSION)
            })
        })
        .fold(0u64, |a, b| a.saturating_add(b))
}
