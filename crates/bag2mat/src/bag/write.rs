//! Writing bag format 2.0 (no released crate does). The layout follows rosbag's own writer:
//! magic, a 4104-byte bag header rewritten on close, chunks of ~768 KiB each followed by
//! their index-data records, then the index section (every connection again, one chunk info
//! per chunk). lz4 chunks are LZ4 frames with the content checksum, which roslz4 requires.
//! The file is written under a temporary name and renamed into place by [`BagWriter::finish`].
//!
//! Closed chunks go to a background thread that compresses and writes them, so encoding the
//! next chunk overlaps with compression and the write system calls; the chunk buffers travel
//! back to be reused (a fresh 800 KB buffer per chunk would cost a page fault per 4 KB).

use std::io::{Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};
use std::sync::mpsc::{Receiver, SyncSender, sync_channel};
use std::thread::JoinHandle;

use super::Compression;
use super::record::{self, ChunkInfo, Connection, MAGIC};
use crate::error::Error;
use crate::imu_msg::{self, Imu};
use crate::shared::output::{AtomicFile, Outputs};
use crate::time::RosTime;

/// rosbag's default chunk threshold: a chunk is closed once its body reaches 768 KiB.
pub const DEFAULT_CHUNK_THRESHOLD: usize = 768 * 1024;
/// Closed chunks that may wait for the writer thread (bounds the memory to a few MB).
const QUEUED_CHUNKS: usize = 4;

/// A connection handle returned by [`BagWriter::add_connection`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ConnId(pub u32);

/// A closed chunk on its way to the writer thread.
struct ChunkJob {
    body: Vec<u8>,
    start_time: RosTime,
    end_time: RosTime,
    /// Per connection with messages in the chunk: `(time, offset in body)` of each.
    index: Vec<(u32, Vec<(RosTime, u32)>)>,
}

/// The file side: owned by the writer thread while chunks flow, then by `finish`.
struct ChunkSink {
    out: AtomicFile,
    path: PathBuf,
    compression: Compression,
    /// File offset where the next record goes.
    pos: u64,
    chunk_infos: Vec<ChunkInfo>,
    compressed: Vec<u8>,
}

impl ChunkSink {
    fn io(&self, e: std::io::Error) -> Error {
        Error::io(&self.path, e)
    }

    fn write_chunk(&mut self, job: &ChunkJob) -> Result<(), Error> {
        self.compressed.clear();
        match self.compression {
            Compression::None => {}
            Compression::Bz2 => {
                let mut enc =
                    bzip2::write::BzEncoder::new(&mut self.compressed, bzip2::Compression::best());
                let r = enc
                    .write_all(&job.body)
                    .and_then(|_| enc.finish().map(|_| ()));
                r.map_err(|e| Error::io(&self.path, e))?;
            }
            Compression::Lz4 => {
                use lz4_flex::frame::{BlockMode, BlockSize, FrameEncoder, FrameInfo};
                let info = FrameInfo::new()
                    .block_size(BlockSize::Max1MB)
                    .block_mode(BlockMode::Independent)
                    .content_checksum(true);
                let mut enc = FrameEncoder::with_frame_info(info, &mut self.compressed);
                enc.write_all(&job.body)
                    .map_err(|e| Error::io(&self.path, e))?;
                enc.finish()
                    .map_err(|e| Error::io(&self.path, std::io::Error::other(e)))?;
            }
        }
        let body: &[u8] = if self.compression == Compression::None {
            &job.body
        } else {
            &self.compressed
        };
        let header = record::chunk_header(self.compression, job.body.len() as u32);
        let mut tail =
            Vec::with_capacity(256 + 12 * job.index.iter().map(|(_, e)| e.len()).sum::<usize>());
        for (conn, entries) in &job.index {
            record::encode_index_data(&mut tail, *conn, entries);
        }
        let w = self.out.writer();
        let r = (|| {
            w.write_all(&(header.len() as u32).to_le_bytes())?;
            w.write_all(&header)?;
            w.write_all(&(body.len() as u32).to_le_bytes())?;
            w.write_all(body)?;
            w.write_all(&tail)
        })();
        r.map_err(|e| self.io(e))?;
        let chunk_pos = self.pos;
        self.pos += 8 + header.len() as u64 + body.len() as u64 + tail.len() as u64;
        self.chunk_infos.push(ChunkInfo {
            chunk_pos,
            start_time: job.start_time,
            end_time: job.end_time,
            counts: job
                .index
                .iter()
                .map(|(c, e)| (*c, e.len() as u32))
                .collect(),
        });
        Ok(())
    }

    /// Writes the index section, rewrites the bag header and renames the file into place.
    fn finish(mut self, connections: &[Connection]) -> Result<(), Error> {
        let index_pos = self.pos;
        let mut index = Vec::new();
        for c in connections {
            c.encode(&mut index);
        }
        for ci in &self.chunk_infos {
            ci.encode(&mut index);
        }
        let header = record::bag_header(
            index_pos,
            connections.len() as u32,
            self.chunk_infos.len() as u32,
        );
        let w = self.out.writer();
        let r = (|| {
            w.write_all(&index)?;
            w.flush()?;
            let f = w.get_mut();
            f.seek(SeekFrom::Start(MAGIC.len() as u64))?;
            f.write_all(&header)?;
            f.seek(SeekFrom::End(0)).map(|_| ())
        })();
        r.map_err(|e| self.io(e))?;
        self.out.commit()
    }
}

/// Streams messages into a new bag.
pub struct BagWriter {
    chunk_threshold: usize,
    connections: Vec<Connection>,
    /// Whether each connection's record has been written into a chunk yet.
    conn_written: Vec<bool>,
    chunk: Vec<u8>,
    chunk_range: Option<(RosTime, RosTime)>,
    /// Per connection: index entries of the open chunk.
    chunk_index: Vec<Vec<(RosTime, u32)>>,
    scratch: Vec<u8>,
    jobs: Option<SyncSender<ChunkJob>>,
    spare: Receiver<Vec<u8>>,
    thread: Option<JoinHandle<Result<ChunkSink, Error>>>,
}

impl BagWriter {
    /// Starts a bag at `path` among the run's `outputs` (written as a temporary file until
    /// [`BagWriter::finish`]).
    pub fn create(
        outputs: &Outputs,
        path: &Path,
        compression: Compression,
    ) -> Result<BagWriter, Error> {
        let mut out = AtomicFile::create(outputs, path)?;
        let header = record::bag_header(0, 0, 0);
        let w = out.writer();
        w.write_all(MAGIC)
            .and_then(|_| w.write_all(&header))
            .map_err(|e| Error::io(path, e))?;
        let mut sink = ChunkSink {
            out,
            path: path.to_path_buf(),
            compression,
            pos: record::FIRST_RECORD_POS,
            chunk_infos: Vec::new(),
            compressed: Vec::new(),
        };
        let (jobs, job_rx) = sync_channel::<ChunkJob>(QUEUED_CHUNKS);
        let (spare_tx, spare) = sync_channel::<Vec<u8>>(QUEUED_CHUNKS + 2);
        let thread = std::thread::Builder::new()
            .name("bag-writer".into())
            .spawn(move || {
                for job in job_rx {
                    sink.write_chunk(&job)?;
                    let mut body = job.body;
                    body.clear();
                    let _ = spare_tx.try_send(body);
                }
                Ok(sink)
            })
            .map_err(|e| Error::io(path, e))?;
        Ok(BagWriter {
            chunk_threshold: DEFAULT_CHUNK_THRESHOLD,
            connections: Vec::new(),
            conn_written: Vec::new(),
            chunk: Vec::with_capacity(DEFAULT_CHUNK_THRESHOLD + 64 * 1024),
            chunk_range: None,
            chunk_index: Vec::new(),
            scratch: Vec::with_capacity(512),
            jobs: Some(jobs),
            spare,
            thread: Some(thread),
        })
    }

    /// Changes the chunk threshold (bytes of uncompressed body).
    pub fn set_chunk_threshold(&mut self, bytes: usize) {
        self.chunk_threshold = bytes.max(1);
    }

    /// Declares a topic with its type, md5 and full definition.
    pub fn add_connection(
        &mut self,
        topic: &str,
        msg_type: &str,
        md5sum: &str,
        definition: &str,
    ) -> ConnId {
        let id = self.connections.len() as u32;
        self.connections.push(Connection {
            id,
            topic: topic.to_string(),
            msg_type: msg_type.to_string(),
            md5sum: md5sum.to_string(),
            message_definition: definition.to_string(),
            callerid: None,
            latching: None,
        });
        self.conn_written.push(false);
        self.chunk_index.push(Vec::new());
        ConnId(id)
    }

    /// Declares a `sensor_msgs/Imu` topic.
    pub fn add_imu_connection(&mut self, topic: &str) -> ConnId {
        self.add_connection(topic, imu_msg::TYPE, imu_msg::MD5, imu_msg::definition())
    }

    /// Appends one Imu message with its record time.
    pub fn write_imu(&mut self, conn: ConnId, time: RosTime, imu: &Imu) -> Result<(), Error> {
        let mut data = std::mem::take(&mut self.scratch);
        data.clear();
        imu.encode(&mut data);
        let r = self.write_raw(conn, time, &data);
        self.scratch = data;
        r
    }

    /// Appends one already-serialized message with its record time.
    pub fn write_raw(&mut self, conn: ConnId, time: RosTime, data: &[u8]) -> Result<(), Error> {
        let c = conn.0 as usize;
        if c >= self.connections.len() {
            return Err(Error::BadMessage {
                what: format!("unknown connection {}", conn.0),
            });
        }
        if !self.conn_written[c] {
            self.connections[c].encode(&mut self.chunk);
            self.conn_written[c] = true;
        }
        let offset = self.chunk.len() as u32;
        // Header written in place, its length patched in after: no allocation per message.
        self.chunk.extend_from_slice(&[0u8; 4]);
        record::message_header(&mut self.chunk, conn.0, time);
        let hlen = (self.chunk.len() - offset as usize - 4) as u32;
        self.chunk[offset as usize..offset as usize + 4].copy_from_slice(&hlen.to_le_bytes());
        self.chunk
            .extend_from_slice(&(data.len() as u32).to_le_bytes());
        self.chunk.extend_from_slice(data);
        self.chunk_index[c].push((time, offset));
        self.chunk_range = Some(match self.chunk_range {
            None => (time, time),
            Some((a, b)) => (a.min(time), b.max(time)),
        });
        if self.chunk.len() >= self.chunk_threshold {
            self.close_chunk()?;
        }
        Ok(())
    }

    /// Hands the open chunk to the writer thread.
    fn close_chunk(&mut self) -> Result<(), Error> {
        let Some((start_time, end_time)) = self.chunk_range.take() else {
            return Ok(());
        };
        let next = self
            .spare
            .try_recv()
            .unwrap_or_else(|_| Vec::with_capacity(self.chunk_threshold + 64 * 1024));
        let body = std::mem::replace(&mut self.chunk, next);
        let index = self
            .chunk_index
            .iter_mut()
            .enumerate()
            .filter(|(_, e)| !e.is_empty())
            .map(|(c, e)| (c as u32, std::mem::take(e)))
            .collect();
        let job = ChunkJob {
            body,
            start_time,
            end_time,
            index,
        };
        let sent = self
            .jobs
            .as_ref()
            .map(|tx| tx.send(job).is_ok())
            .unwrap_or(false);
        if !sent {
            // The writer thread stopped: its error says why.
            return Err(self.join().err().unwrap_or_else(|| Error::BadMessage {
                what: "bag writer thread stopped".into(),
            }));
        }
        Ok(())
    }

    /// Stops the writer thread and takes back the file side.
    fn join(&mut self) -> Result<ChunkSink, Error> {
        self.jobs = None;
        match self.thread.take().map(|t| t.join()) {
            Some(Ok(r)) => r,
            Some(Err(_)) => Err(Error::BadMessage {
                what: "bag writer thread panicked".into(),
            }),
            None => Err(Error::BadMessage {
                what: "bag writer already finished".into(),
            }),
        }
    }

    /// Closes the last chunk, writes the index section, rewrites the bag header and renames
    /// the file into place.
    pub fn finish(mut self) -> Result<(), Error> {
        self.close_chunk()?;
        let sink = self.join()?;
        sink.finish(&self.connections)
    }
}

impl Drop for BagWriter {
    fn drop(&mut self) {
        // Unfinished: stop the thread; dropping its AtomicFile removes the temporary file.
        if self.thread.is_some() {
            let _ = self.join();
        }
    }
}
