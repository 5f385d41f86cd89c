//! Writing MCAP files the ROS 2 tooling reads: magic, Header (`ros2` profile), Schema and
//! Channel records as they are declared, chunks (none, zstd or lz4) each followed by one
//! Message Index per channel, Data End with the data-section CRC, then the summary (schemas,
//! channels, statistics, chunk indexes), the summary offsets and a Footer with the summary
//! CRC. Written under a temporary name and renamed into place by [`McapWriter::finish`].

use std::collections::BTreeMap;
use std::io::Write;
use std::path::{Path, PathBuf};

use super::record::{
    self, ChunkHeader, ChunkIndex, MAGIC, MessageIndex, MessageRef, Op, Put, Schema, Statistics,
};
use crate::error::Error;
use crate::shared::output::{AtomicFile, Outputs};

/// Chunks are closed once their records reach this size (rosbag2's MCAP default, 768 KiB).
pub const DEFAULT_CHUNK_SIZE: usize = 768 * 1024;

/// How chunk records are stored.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ChunkCompression {
    /// Stored as is.
    #[default]
    None,
    /// One zstd frame per chunk.
    Zstd,
    /// One LZ4 frame per chunk.
    Lz4,
}

impl ChunkCompression {
    /// The chunk record's `compression` field.
    pub fn name(self) -> &'static str {
        match self {
            ChunkCompression::None => "",
            ChunkCompression::Zstd => "zstd",
            ChunkCompression::Lz4 => "lz4",
        }
    }
}

/// Streams messages into a new MCAP file.
pub struct McapWriter {
    out: AtomicFile,
    path: PathBuf,
    pos: u64,
    data_crc: crc32fast::Hasher,
    compression: ChunkCompression,
    chunk_size: usize,
    schemas: Vec<Schema>,
    channels: Vec<record::Channel>,
    chunk: Vec<u8>,
    chunk_span: Option<(u64, u64)>,
    chunk_index: BTreeMap<u16, Vec<(u64, u64)>>,
    chunk_indexes: Vec<ChunkIndex>,
    counts: BTreeMap<u16, u64>,
    span: Option<(u64, u64)>,
    compressed: Vec<u8>,
    buf: Vec<u8>,
}

impl McapWriter {
    /// Starts a file at `path` with the given profile (`ros2` for ROS 2 bags).
    pub fn create(
        outputs: &Outputs,
        path: &Path,
        profile: &str,
        compression: ChunkCompression,
    ) -> Result<McapWriter, Error> {
        let out = AtomicFile::create(outputs, path)?;
        let mut w = McapWriter {
            out,
            path: path.to_path_buf(),
            pos: 0,
            data_crc: crc32fast::Hasher::new(),
            compression,
            chunk_size: DEFAULT_CHUNK_SIZE,
            schemas: Vec::new(),
            channels: Vec::new(),
            chunk: Vec::with_capacity(DEFAULT_CHUNK_SIZE + 64 * 1024),
            chunk_span: None,
            chunk_index: BTreeMap::new(),
            chunk_indexes: Vec::new(),
            counts: BTreeMap::new(),
            span: None,
            compressed: Vec::new(),
            buf: Vec::new(),
        };
        let mut b = MAGIC.to_vec();
        record::Header {
            profile: profile.to_string(),
            library: format!("bag2mat {}", env!("CARGO_PKG_VERSION")),
        }
        .encode(&mut b);
        w.emit_data(&b)?;
        Ok(w)
    }

    /// Changes the chunk size (bytes of uncompressed records).
    pub fn set_chunk_size(&mut self, bytes: usize) {
        self.chunk_size = bytes.max(1);
    }

    fn emit_data(&mut self, b: &[u8]) -> Result<(), Error> {
        self.data_crc.update(b);
        self.emit(b)
    }

    fn emit(&mut self, b: &[u8]) -> Result<(), Error> {
        self.out
            .writer()
            .write_all(b)
            .map_err(|e| Error::io(&self.path, e))?;
        self.pos += b.len() as u64;
        Ok(())
    }

    /// Declares a schema; returns its id.
    pub fn add_schema(&mut self, name: &str, encoding: &str, data: &[u8]) -> Result<u16, Error> {
        let s = Schema {
            id: self.schemas.len() as u16 + 1,
            name: name.to_string(),
            encoding: encoding.to_string(),
            data: data.to_vec(),
        };
        let mut b = Vec::new();
        s.encode(&mut b);
        self.emit_data(&b)?;
        let id = s.id;
        self.schemas.push(s);
        Ok(id)
    }

    /// Declares a channel on `topic` with its schema, message encoding and metadata.
    pub fn add_channel(
        &mut self,
        schema_id: u16,
        topic: &str,
        message_encoding: &str,
        metadata: &[(String, String)],
    ) -> Result<u16, Error> {
        let c = record::Channel {
            id: self.channels.len() as u16 + 1,
            schema_id,
            topic: topic.to_string(),
            message_encoding: message_encoding.to_string(),
            metadata: metadata.to_vec(),
        };
        let mut b = Vec::new();
        c.encode(&mut b);
        self.emit_data(&b)?;
        let id = c.id;
        self.channels.push(c);
        Ok(id)
    }

    /// Appends one message (`log_time` is the record time, ns).
    pub fn write(
        &mut self,
        channel: u16,
        sequence: u32,
        log_time: u64,
        publish_time: u64,
        data: &[u8],
    ) -> Result<(), Error> {
        if channel == 0 || channel as usize > self.channels.len() {
            return Err(Error::BadMessage {
                what: format!("unknown MCAP channel {channel}"),
            });
        }
        let offset = self.chunk.len() as u64;
        MessageRef {
            channel_id: channel,
            sequence,
            log_time,
            publish_time,
            data,
        }
        .encode(&mut self.chunk);
        self.chunk_index
            .entry(channel)
            .or_default()
            .push((log_time, offset));
        *self.counts.entry(channel).or_default() += 1;
        let widen = |s: Option<(u64, u64)>| match s {
            None => (log_time, log_time),
            Some((a, b)) => (a.min(log_time), b.max(log_time)),
        };
        self.chunk_span = Some(widen(self.chunk_span));
        self.span = Some(widen(self.span));
        if self.chunk.len() >= self.chunk_size {
            self.close_chunk()?;
        }
        Ok(())
    }

    fn close_chunk(&mut self) -> Result<(), Error> {
        let Some((start, end)) = self.chunk_span.take() else {
            return Ok(());
        };
        let records: &[u8] = match self.compression {
            ChunkCompression::None => &self.chunk,
            ChunkCompression::Zstd => {
                crate::zstd::compress(&self.chunk, &mut self.compressed);
                &self.compressed
            }
            ChunkCompression::Lz4 => {
                self.compressed.clear();
                let mut enc = lz4_flex::frame::FrameEncoder::new(&mut self.compressed);
                enc.write_all(&self.chunk)
                    .map_err(|e| Error::io(&self.path, e))?;
                enc.finish()
                    .map_err(|e| Error::io(&self.path, std::io::Error::other(e)))?;
                &self.compressed
            }
        };
        let header = ChunkHeader {
            message_start_time: start,
            message_end_time: end,
            uncompressed_size: self.chunk.len() as u64,
            uncompressed_crc: crc32fast::hash(&self.chunk),
            compression: self.compression.name().to_string(),
            compressed_size: records.len() as u64,
        };
        let mut buf = std::mem::take(&mut self.buf);
        buf.clear();
        header.encode(records, &mut buf);
        let chunk_start = self.pos;
        let chunk_length = buf.len() as u64;
        let mut offsets = Vec::new();
        let index_start = chunk_start + chunk_length;
        for (ch, entries) in std::mem::take(&mut self.chunk_index) {
            offsets.push((ch, chunk_start + buf.len() as u64));
            MessageIndex {
                channel_id: ch,
                records: entries,
            }
            .encode(&mut buf);
        }
        let r = self.emit_data(&buf);
        self.chunk_indexes.push(ChunkIndex {
            message_start_time: start,
            message_end_time: end,
            chunk_start_offset: chunk_start,
            chunk_length,
            message_index_offsets: offsets,
            message_index_length: chunk_start + buf.len() as u64 - index_start,
            compression: header.compression,
            compressed_size: header.compressed_size,
            uncompressed_size: header.uncompressed_size,
        });
        self.buf = buf;
        self.chunk.clear();
        r
    }

    /// Closes the last chunk, writes Data End, the summary, the summary offsets and the
    /// footer, and renames the file into place.
    pub fn finish(mut self) -> Result<(), Error> {
        self.close_chunk()?;
        let mut b = Vec::new();
        let crc = self.data_crc.clone().finalize();
        record::push_record(&mut b, Op::DataEnd, |o| o.put_u32(crc));
        self.emit(&b)?;
        let summary_start = self.pos;
        let mut s = Vec::new();
        let mut groups = Vec::new();
        let mut group = |s: &mut Vec<u8>, op: Op, fill: &dyn Fn(&mut Vec<u8>)| {
            let at = s.len();
            fill(s);
            if s.len() > at {
                groups.push((op, summary_start + at as u64, (s.len() - at) as u64));
            }
        };
        group(&mut s, Op::Schema, &|s| {
            self.schemas.iter().for_each(|x| x.encode(s))
        });
        group(&mut s, Op::Channel, &|s| {
            self.channels.iter().for_each(|x| x.encode(s))
        });
        let (start, end) = self.span.unwrap_or((0, 0));
        let stats = Statistics {
            message_count: self.counts.values().sum(),
            schema_count: self.schemas.len() as u16,
            channel_count: self.channels.len() as u32,
            attachment_count: 0,
            metadata_count: 0,
            chunk_count: self.chunk_indexes.len() as u32,
            message_start_time: start,
            message_end_time: end,
            channel_message_counts: self.counts.iter().map(|(k, v)| (*k, *v)).collect(),
        };
        group(&mut s, Op::Statistics, &|s| stats.encode(s));
        group(&mut s, Op::ChunkIndex, &|s| {
            self.chunk_indexes.iter().for_each(|x| x.encode(s))
        });
        let summary_offset_start = summary_start + s.len() as u64;
        for (op, at, len) in &groups {
            record::encode_summary_offset(&mut s, *op, *at, *len);
        }
        let mut footer = Vec::new();
        footer.push(Op::Footer as u8);
        footer.put_u64(record::FOOTER_CONTENT_LEN);
        footer.put_u64(summary_start);
        footer.put_u64(summary_offset_start);
        let mut h = crc32fast::Hasher::new();
        h.update(&s);
        h.update(&footer);
        footer.put_u32(h.finalize());
        s.extend_from_slice(&footer);
        s.extend_from_slice(MAGIC);
        self.emit(&s)?;
        self.out.commit()
    }
}
