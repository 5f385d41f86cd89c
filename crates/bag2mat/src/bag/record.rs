//! The record layer of bag format 2.0, shared by the reader and the writer.
//!
//! Every record is `u32 header_len | header | u32 data_len | data`; a header is a list of
//! `u32 len | name=value` fields. Each record type has its op code and its fields here, so
//! the byte layout is written down once (docs/formats.md §3.2–3.3). Bytes are read through
//! the crate's bounds-checked [`Cursor`]; what does not parse is a typed [`RecordError`],
//! which the reader turns into the crate's error (or a note) with the file offset.
//!
//! Records as types, parsed from the header fields (as rosbag-rs does): [`BagHeader`],
//! [`ChunkHeader`], [`Connection`], [`MessageData`], [`IndexData`], [`ChunkInfo`].

use super::Compression;
use crate::cursor::Cursor;
use crate::time::RosTime;

/// What is wrong with a record's header or data.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum RecordError {
    /// A field's `u32` length is cut off by the end of the header.
    #[error("header field length overruns the header")]
    FieldLengthOverruns,
    /// A field's bytes run past the end of the header.
    #[error("header field overruns the header")]
    FieldOverruns,
    /// A field that is not `name=value`.
    #[error("header field without '='")]
    NoEquals,
    /// A field name that is not text.
    #[error("header field name is not UTF-8")]
    NameNotUtf8,
    /// An `op` this format does not define.
    #[error("unknown record op 0x{0:02x}")]
    UnknownOp(u8),
    /// No `op` field, or not one byte.
    #[error("record header without a one-byte 'op' field")]
    NoOp,
    /// A required field absent or of the wrong width.
    #[error("record header lacks {} '{name}' {}", .kind.article(), .kind.noun())]
    Missing {
        /// The field.
        name: String,
        /// What it should hold.
        kind: FieldKind,
    },
    /// A text field that is not UTF-8.
    #[error("field '{0}' is not UTF-8")]
    NotUtf8(String),
    /// A chunk's `compression` this format does not define.
    #[error("unknown chunk compression '{0}'")]
    UnknownCompression(String),
    /// A chunk-info record whose data does not hold its `count` entries.
    #[error("chunk info lists {count} connections in {len} bytes")]
    ChunkInfoLength {
        /// The `count` field.
        count: usize,
        /// The data length.
        len: usize,
    },
    /// A record of another op where this one was expected.
    #[error("unexpected {0:?} record")]
    Unexpected(Op),
}

/// What a required header field holds (for [`RecordError::Missing`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FieldKind {
    /// A `u32`.
    U32,
    /// A `u64`.
    U64,
    /// A [`RosTime`].
    Time,
    /// Text.
    Text,
}

impl FieldKind {
    fn article(self) -> &'static str {
        match self {
            FieldKind::U32 => "a 4-byte",
            FieldKind::U64 | FieldKind::Time => "an 8-byte",
            FieldKind::Text => "a",
        }
    }
    fn noun(self) -> &'static str {
        match self {
            FieldKind::Time => "time field",
            _ => "field",
        }
    }
}

/// The 13-byte magic line that opens every version 2.0 bag.
pub const MAGIC: &[u8; 13] = b"#ROSBAG V2.0\n";
/// The bag header record is padded with spaces so that header plus data is 4096 bytes.
pub const BAG_HEADER_PADDED_LEN: usize = 4096;
/// Offset of the first chunk: the magic plus the 4104-byte bag header record.
pub const FIRST_RECORD_POS: u64 = 13 + 4 + BAG_HEADER_PADDED_LEN as u64 + 4;

/// Record op codes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[repr(u8)]
pub enum Op {
    /// A message: header `conn`, `time`; data is the serialized message.
    MessageData = 0x02,
    /// The bag header: `index_pos`, `conn_count`, `chunk_count`.
    BagHeader = 0x03,
    /// Per connection and chunk: `(time, offset)` of each message in the chunk body.
    IndexData = 0x04,
    /// A (possibly compressed) run of connection and message records.
    Chunk = 0x05,
    /// Per chunk, in the index section: position, time range, messages per connection.
    ChunkInfo = 0x06,
    /// A topic with its type, md5 and definition.
    Connection = 0x07,
}

impl Op {
    /// The op for a header's `op` byte.
    pub(crate) fn from_byte(b: u8) -> Option<Op> {
        Some(match b {
            0x02 => Op::MessageData,
            0x03 => Op::BagHeader,
            0x04 => Op::IndexData,
            0x05 => Op::Chunk,
            0x06 => Op::ChunkInfo,
            0x07 => Op::Connection,
            _ => return None,
        })
    }
}

/// Appends one `len | name=value` header field.
pub fn push_field(out: &mut Vec<u8>, name: &str, value: &[u8]) {
    out.extend_from_slice(&((name.len() + 1 + value.len()) as u32).to_le_bytes());
    out.extend_from_slice(name.as_bytes());
    out.push(b'=');
    out.extend_from_slice(value);
}

/// Appends a whole record: header fields already encoded in `header`, then `data`.
pub fn push_record(out: &mut Vec<u8>, header: &[u8], data: &[u8]) {
    out.extend_from_slice(&(header.len() as u32).to_le_bytes());
    out.extend_from_slice(header);
    out.extend_from_slice(&(data.len() as u32).to_le_bytes());
    out.extend_from_slice(data);
}

/// The next `len | name=value` field of a header, as its raw bytes.
fn next_field<'a>(c: &mut Cursor<'a>) -> Result<&'a [u8], RecordError> {
    let len = c
        .le::<u32>("header field length")
        .map_err(|_| RecordError::FieldLengthOverruns)? as usize;
    c.take(len, "header field")
        .map_err(|_| RecordError::FieldOverruns)
}

/// The fields of a record header, in file order. Fails on a field that overruns the header.
pub(crate) fn fields(header: &[u8]) -> Result<Vec<(&str, &[u8])>, RecordError> {
    let mut out = Vec::new();
    let mut c = Cursor::new(header);
    while !c.is_empty() {
        let field = next_field(&mut c)?;
        let eq = field
            .iter()
            .position(|&b| b == b'=')
            .ok_or(RecordError::NoEquals)?;
        let name = std::str::from_utf8(&field[..eq]).map_err(|_| RecordError::NameNotUtf8)?;
        out.push((name, &field[eq + 1..]));
    }
    Ok(out)
}

/// `op`, `conn` and `time` of a record header, each `None` when absent.
pub type OpConnTime = (Option<u8>, Option<u32>, Option<RosTime>);

/// The `op`, `conn` and `time` fields of a record header, found without allocating: the hot
/// path of reading, run once per message. Fields missing from the header stay `None`.
pub(crate) fn op_conn_time(header: &[u8]) -> Result<OpConnTime, RecordError> {
    let (mut op, mut conn, mut time) = (None, None, None);
    let mut c = Cursor::new(header);
    while !c.is_empty() {
        match next_field(&mut c)? {
            [b'o', b'p', b'=', v] => op = Some(*v),
            [b'c', b'o', b'n', b'n', b'=', v @ ..] if v.len() == 4 => {
                conn = Cursor::new(v).le::<u32>("conn").ok()
            }
            [b't', b'i', b'm', b'e', b'=', v @ ..] => time = RosTime::from_bytes(v),
            _ => {}
        }
    }
    Ok((op, conn, time))
}

/// A parsed record header, fields looked up by name.
pub struct Header<'a> {
    fields: Vec<(&'a str, &'a [u8])>,
}

impl<'a> Header<'a> {
    /// Parses the header bytes of one record.
    pub fn parse(bytes: &'a [u8]) -> Result<Header<'a>, RecordError> {
        Ok(Header {
            fields: fields(bytes)?,
        })
    }

    /// The raw value of a field.
    pub(crate) fn get(&self, name: &str) -> Option<&'a [u8]> {
        self.fields
            .iter()
            .find(|(n, _)| *n == name)
            .map(|(_, v)| *v)
    }

    /// The record's op.
    pub fn op(&self) -> Result<Op, RecordError> {
        match self.get("op") {
            Some([b]) => Op::from_byte(*b).ok_or(RecordError::UnknownOp(*b)),
            _ => Err(RecordError::NoOp),
        }
    }

    /// A required fixed-width field.
    fn fixed<T: crate::cursor::Le>(&self, name: &str, kind: FieldKind) -> Result<T, RecordError> {
        self.get(name)
            .filter(|v| v.len() == T::SIZE)
            .and_then(|v| Cursor::new(v).le::<T>("header field").ok())
            .ok_or_else(|| RecordError::Missing {
                name: name.to_string(),
                kind,
            })
    }

    /// A required u32 field.
    pub(crate) fn u32(&self, name: &str) -> Result<u32, RecordError> {
        self.fixed(name, FieldKind::U32)
    }

    /// A required u64 field.
    pub(crate) fn u64(&self, name: &str) -> Result<u64, RecordError> {
        self.fixed(name, FieldKind::U64)
    }

    /// A required time field.
    pub(crate) fn time(&self, name: &str) -> Result<RosTime, RecordError> {
        self.get(name)
            .and_then(RosTime::from_bytes)
            .ok_or_else(|| RecordError::Missing {
                name: name.to_string(),
                kind: FieldKind::Time,
            })
    }

    /// A required text field.
    pub(crate) fn str(&self, name: &str) -> Result<&'a str, RecordError> {
        let v = self.get(name).ok_or_else(|| RecordError::Missing {
            name: name.to_string(),
            kind: FieldKind::Text,
        })?;
        std::str::from_utf8(v).map_err(|_| RecordError::NotUtf8(name.to_string()))
    }
}

/// Little-endian u32 at `pos`, if the bytes are there.
#[cfg(any(test, feature = "test-support"))]
pub fn read_u32(buf: &[u8], pos: usize) -> Option<u32> {
    let mut c = Cursor::new(buf);
    c.skip(pos, "record").ok()?;
    c.le::<u32>("length").ok()
}

/// One record inside a byte buffer: its header and data, and where the next one starts.
pub struct RawRecord<'a> {
    /// Header bytes (fields).
    pub header: &'a [u8],
    /// Data bytes.
    pub data: &'a [u8],
    /// Offset just past this record.
    pub end: usize,
}

/// Splits the record at `pos` of `buf`; `None` if it is incomplete.
pub fn raw_record(buf: &[u8], pos: usize) -> Option<RawRecord<'_>> {
    let mut c = Cursor::new(buf);
    c.skip(pos, "record").ok()?;
    let hlen = c.le::<u32>("header length").ok()? as usize;
    let header = c.take(hlen, "header").ok()?;
    let dlen = c.le::<u32>("data length").ok()? as usize;
    let data = c.take(dlen, "data").ok()?;
    Some(RawRecord {
        header,
        data,
        end: c.pos(),
    })
}

/// The bag header record's fields, each `None` when absent or of the wrong width: a damaged
/// bag header leaves the chunks to be walked.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct BagHeader {
    /// File offset of the index section (0 while a writer has not finished).
    pub index_pos: Option<u64>,
    /// Connections in the index section.
    pub conn_count: Option<u32>,
    /// Chunks in the file.
    pub chunk_count: Option<u32>,
}

impl BagHeader {
    /// Reads the fields of a bag header record.
    pub(crate) fn decode(header: &Header<'_>) -> Result<BagHeader, RecordError> {
        match header.op()? {
            Op::BagHeader => Ok(BagHeader {
                index_pos: header.u64("index_pos").ok(),
                conn_count: header.u32("conn_count").ok(),
                chunk_count: header.u32("chunk_count").ok(),
            }),
            other => Err(RecordError::Unexpected(other)),
        }
    }
}

/// A chunk record's header: how its data is stored and how long it is once decompressed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ChunkHeader {
    /// How the data is stored.
    pub compression: Compression,
    /// Length of the decompressed body.
    pub size: u32,
}

impl ChunkHeader {
    /// Reads a chunk record's header (an error for any other op).
    pub(crate) fn decode(header: &Header<'_>) -> Result<ChunkHeader, RecordError> {
        match header.op()? {
            Op::Chunk => {
                let name = header.str("compression")?;
                let compression = Compression::from_name(name)
                    .ok_or_else(|| RecordError::UnknownCompression(name.to_string()))?;
                Ok(ChunkHeader {
                    compression,
                    size: header.u32("size")?,
                })
            }
            other => Err(RecordError::Unexpected(other)),
        }
    }

    /// Encodes the header fields (`op`, `compression`, `size`).
    pub fn encode(&self) -> Vec<u8> {
        let mut header = Vec::with_capacity(48);
        push_field(&mut header, "op", &[Op::Chunk as u8]);
        push_field(
            &mut header,
            "compression",
            self.compression.name().as_bytes(),
        );
        push_field(&mut header, "size", &self.size.to_le_bytes());
        header
    }
}

/// A message-data record's header: its connection and record time. (The reader's hot path
/// finds these fields with [`op_conn_time`], which does not allocate.)
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct MessageData {
    /// The connection id.
    pub conn: u32,
    /// The record time.
    pub time: RosTime,
}

impl MessageData {
    /// Encodes the header fields (`op`, `conn`, `time`).
    pub fn encode_header(&self, out: &mut Vec<u8>) {
        push_field(out, "op", &[Op::MessageData as u8]);
        push_field(out, "conn", &self.conn.to_le_bytes());
        push_field(out, "time", &self.time.to_bytes());
    }
}

/// An index-data record's header: the connection and how many `(time, offset)` entries its
/// data holds (a damaged `count` is `None`; the data length then bounds the entries).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct IndexData {
    /// The connection id.
    pub conn: u32,
    /// Entries, as the `count` field says.
    pub count: Option<u32>,
}

/// Bytes of one index-data entry: a time and a `u32` offset into the chunk body.
pub const INDEX_ENTRY_LEN: usize = 12;

impl IndexData {
    /// Reads the header fields of an index-data record.
    pub(crate) fn decode(header: &Header<'_>) -> Result<IndexData, RecordError> {
        Ok(IndexData {
            conn: header.u32("conn")?,
            count: header.u32("count").ok(),
        })
    }

    /// Encodes the record: `(time, offset into the uncompressed chunk body)` per message.
    pub fn encode(out: &mut Vec<u8>, conn: u32, entries: &[(RosTime, u32)]) {
        let mut header = Vec::with_capacity(48);
        push_field(&mut header, "op", &[Op::IndexData as u8]);
        push_field(&mut header, "ver", &1u32.to_le_bytes());
        push_field(&mut header, "conn", &conn.to_le_bytes());
        push_field(&mut header, "count", &(entries.len() as u32).to_le_bytes());
        let mut data = Vec::with_capacity(INDEX_ENTRY_LEN * entries.len());
        for (t, off) in entries {
            data.extend_from_slice(&t.to_bytes());
            data.extend_from_slice(&off.to_le_bytes());
        }
        push_record(out, &header, &data);
    }
}

/// A connection: one topic with its message type.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Connection {
    /// The connection id used by message and index records.
    pub id: u32,
    /// Topic name as recorded.
    pub topic: String,
    /// Message type, e.g. `sensor_msgs/Imu`.
    pub msg_type: String,
    /// md5 of the message definition, 32 lower-case hex characters.
    pub md5sum: String,
    /// Full message definition text.
    pub message_definition: String,
    /// Publishing node, when recorded.
    pub callerid: Option<String>,
    /// `"1"` when the publisher latched.
    pub latching: Option<String>,
}

impl Connection {
    /// Encodes the connection record (header `op`, `topic`, `conn`; data the field list).
    pub fn encode(&self, out: &mut Vec<u8>) {
        let mut header = Vec::with_capacity(64);
        push_field(&mut header, "op", &[Op::Connection as u8]);
        push_field(&mut header, "topic", self.topic.as_bytes());
        push_field(&mut header, "conn", &self.id.to_le_bytes());
        let mut data = Vec::with_capacity(self.message_definition.len() + 128);
        push_field(&mut data, "topic", self.topic.as_bytes());
        push_field(&mut data, "type", self.msg_type.as_bytes());
        push_field(&mut data, "md5sum", self.md5sum.as_bytes());
        push_field(
            &mut data,
            "message_definition",
            self.message_definition.as_bytes(),
        );
        if let Some(c) = &self.callerid {
            push_field(&mut data, "callerid", c.as_bytes());
        }
        if let Some(l) = &self.latching {
            push_field(&mut data, "latching", l.as_bytes());
        }
        push_record(out, &header, &data);
    }

    /// Decodes a connection record from its header and data.
    pub(crate) fn decode(header: &Header<'_>, data: &[u8]) -> Result<Connection, RecordError> {
        let id = header.u32("conn")?;
        let storage_topic = header.str("topic")?;
        let d = Header::parse(data)?;
        let opt = |n: &str| d.get(n).map(|v| String::from_utf8_lossy(v).into_owned());
        Ok(Connection {
            id,
            topic: d.str("topic").unwrap_or(storage_topic).to_string(),
            msg_type: d.str("type")?.to_string(),
            md5sum: d.str("md5sum")?.to_string(),
            message_definition: opt("message_definition").unwrap_or_default(),
            callerid: opt("callerid"),
            latching: opt("latching"),
        })
    }
}

/// Chunk-info record contents: where a chunk is and what it holds.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ChunkInfo {
    /// File offset of the chunk record.
    pub chunk_pos: u64,
    /// Earliest message time in the chunk.
    pub start_time: RosTime,
    /// Latest message time in the chunk.
    pub end_time: RosTime,
    /// `(connection id, message count)` for each connection in the chunk.
    pub counts: Vec<(u32, u32)>,
}

impl ChunkInfo {
    /// Encodes the record (`ver` = 1; `count` is the number of connections).
    pub fn encode(&self, out: &mut Vec<u8>) {
        let mut header = Vec::with_capacity(96);
        push_field(&mut header, "op", &[Op::ChunkInfo as u8]);
        push_field(&mut header, "ver", &1u32.to_le_bytes());
        push_field(&mut header, "chunk_pos", &self.chunk_pos.to_le_bytes());
        push_field(&mut header, "start_time", &self.start_time.to_bytes());
        push_field(&mut header, "end_time", &self.end_time.to_bytes());
        push_field(
            &mut header,
            "count",
            &(self.counts.len() as u32).to_le_bytes(),
        );
        let mut data = Vec::with_capacity(8 * self.counts.len());
        for (conn, count) in &self.counts {
            data.extend_from_slice(&conn.to_le_bytes());
            data.extend_from_slice(&count.to_le_bytes());
        }
        push_record(out, &header, &data);
    }

    /// Decodes the record.
    pub(crate) fn decode(header: &Header<'_>, data: &[u8]) -> Result<ChunkInfo, RecordError> {
        let count = header.u32("count")? as usize;
        if Some(data.len()) != count.checked_mul(8) {
            return Err(RecordError::ChunkInfoLength {
                count,
                len: data.len(),
            });
        }
        let mut c = Cursor::new(data);
        let counts = (0..count)
            .map(|_| Ok((c.le::<u32>("conn")?, c.le::<u32>("count")?)))
            .collect::<Result<Vec<_>, crate::cursor::CursorError>>()
            .map_err(|_| RecordError::ChunkInfoLength {
                count,
                len: data.len(),
            })?;
        Ok(ChunkInfo {
            chunk_pos: header.u64("chunk_pos")?,
            start_time: header.time("start_time")?,
            end_time: header.time("end_time")?,
            counts,
        })
    }
}

/// Encodes a chunk record header (`compression`, `size` = uncompressed length).
pub fn chunk_header(compression: Compression, uncompressed_len: u32) -> Vec<u8> {
    ChunkHeader {
        compression,
        size: uncompressed_len,
    }
    .encode()
}

/// Encodes an index-data record: `(time, offset into the uncompressed chunk body)` per message.
pub fn encode_index_data(out: &mut Vec<u8>, conn: u32, entries: &[(RosTime, u32)]) {
    IndexData::encode(out, conn, entries)
}

/// Encodes a message-data record header (`op`, `conn`, `time`).
pub fn message_header(out: &mut Vec<u8>, conn: u32, time: RosTime) {
    MessageData { conn, time }.encode_header(out)
}

/// Encodes the bag header record, padded with spaces to 4096 bytes of header plus data.
pub fn bag_header(index_pos: u64, conn_count: u32, chunk_count: u32) -> Vec<u8> {
    let mut header = Vec::with_capacity(80);
    push_field(&mut header, "op", &[Op::BagHeader as u8]);
    push_field(&mut header, "index_pos", &index_pos.to_le_bytes());
    push_field(&mut header, "conn_count", &conn_count.to_le_bytes());
    push_field(&mut header, "chunk_count", &chunk_count.to_le_bytes());
    let padding = vec![b' '; BAG_HEADER_PADDED_LEN - header.len()];
    let mut out = Vec::with_capacity(BAG_HEADER_PADDED_LEN + 8);
    push_record(&mut out, &header, &padding);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bag_header_record_is_4104_bytes() {
        let h = bag_header(123, 1, 2);
        assert_eq!(h.len(), 4104);
        assert_eq!(read_u32(&h, 0), Some(69));
        assert_eq!(MAGIC.len() as u64 + h.len() as u64, FIRST_RECORD_POS);
    }

    #[test]
    fn connection_round_trip() {
        let c = Connection {
            id: 3,
            topic: "/imu".into(),
            msg_type: "sensor_msgs/Imu".into(),
            md5sum: "6a62c6daae103f4ff57a132d6f95cec2".into(),
            message_definition: "float64 x \n".into(),
            callerid: Some("/sim".into()),
            latching: Some("0".into()),
        };
        let mut buf = Vec::new();
        c.encode(&mut buf);
        let r = raw_record(&buf, 0).unwrap();
        assert_eq!(r.end, buf.len());
        let h = Header::parse(r.header).unwrap();
        assert_eq!(h.op(), Ok(Op::Connection));
        assert_eq!(Connection::decode(&h, r.data).unwrap(), c);
    }

    #[test]
    fn truncated_record_is_none_not_a_panic() {
        let mut buf = Vec::new();
        ChunkInfo {
            chunk_pos: 4117,
            start_time: RosTime::default(),
            end_time: RosTime::default(),
            counts: vec![(0, 5)],
        }
        .encode(&mut buf);
        for len in 0..buf.len() {
            assert!(raw_record(&buf[..len], 0).is_none(), "len {len}");
        }
        assert!(raw_record(&buf, 0).is_some());
    }
}
