//! The record layer of bag format 2.0, shared by the reader and the writer.
//!
//! Every record is `u32 header_len | header | u32 data_len | data`; a header is a list of
//! `u32 len | name=value` fields. Each record type has its op code and its fields here, so
//! the byte layout is written down once (rust_stack.md §3.2–3.3).

use super::{Compression, RosTime};

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

/// The fields of a record header, in file order. Fails on a field that overruns the header.
pub(crate) fn fields(header: &[u8]) -> Result<Vec<(&str, &[u8])>, String> {
    let mut out = Vec::new();
    let mut pos = 0usize;
    while pos < header.len() {
        let len = read_u32(header, pos).ok_or("header field length overruns the header")? as usize;
        pos += 4;
        let field = header
            .get(pos..pos + len)
            .ok_or("header field overruns the header")?;
        let eq = field
            .iter()
            .position(|&b| b == b'=')
            .ok_or("header field without '='")?;
        let name =
            std::str::from_utf8(&field[..eq]).map_err(|_| "header field name is not UTF-8")?;
        out.push((name, &field[eq + 1..]));
        pos += len;
    }
    Ok(out)
}

/// `op`, `conn` and `time` of a record header, each `None` when absent.
pub type OpConnTime = (Option<u8>, Option<u32>, Option<RosTime>);

/// The `op`, `conn` and `time` fields of a record header, found without allocating: the hot
/// path of reading, run once per message. Fields missing from the header stay `None`.
pub(crate) fn op_conn_time(header: &[u8]) -> Result<OpConnTime, String> {
    let (mut op, mut conn, mut time) = (None, None, None);
    let mut pos = 0usize;
    while pos < header.len() {
        let len = read_u32(header, pos).ok_or("header field length overruns the header")? as usize;
        let field = header
            .get(pos + 4..pos + 4 + len)
            .ok_or("header field overruns the header")?;
        match field {
            [b'o', b'p', b'=', v] => op = Some(*v),
            [b'c', b'o', b'n', b'n', b'=', v @ ..] if v.len() == 4 => {
                conn = Some(u32::from_le_bytes([v[0], v[1], v[2], v[3]]))
            }
            [b't', b'i', b'm', b'e', b'=', v @ ..] => time = RosTime::from_bytes(v),
            _ => {}
        }
        pos += 4 + len;
    }
    Ok((op, conn, time))
}

/// A parsed record header, fields looked up by name.
pub struct Header<'a> {
    fields: Vec<(&'a str, &'a [u8])>,
}

impl<'a> Header<'a> {
    /// Parses the header bytes of one record.
    pub fn parse(bytes: &'a [u8]) -> Result<Header<'a>, String> {
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
    pub fn op(&self) -> Result<Op, String> {
        match self.get("op") {
            Some([b]) => Op::from_byte(*b).ok_or_else(|| format!("unknown record op 0x{b:02x}")),
            _ => Err("record header without a one-byte 'op' field".into()),
        }
    }

    /// A required u32 field.
    pub(crate) fn u32(&self, name: &str) -> Result<u32, String> {
        match self.get(name) {
            Some(v) if v.len() == 4 => Ok(u32::from_le_bytes([v[0], v[1], v[2], v[3]])),
            _ => Err(format!("record header lacks a 4-byte '{name}' field")),
        }
    }

    /// A required u64 field.
    pub(crate) fn u64(&self, name: &str) -> Result<u64, String> {
        match self.get(name) {
            Some(v) if v.len() == 8 => {
                let mut b = [0u8; 8];
                b.copy_from_slice(v);
                Ok(u64::from_le_bytes(b))
            }
            _ => Err(format!("record header lacks an 8-byte '{name}' field")),
        }
    }

    /// A required time field.
    pub(crate) fn time(&self, name: &str) -> Result<RosTime, String> {
        self.get(name)
            .and_then(RosTime::from_bytes)
            .ok_or_else(|| format!("record header lacks an 8-byte '{name}' time field"))
    }

    /// A required text field.
    pub(crate) fn str(&self, name: &str) -> Result<&'a str, String> {
        let v = self
            .get(name)
            .ok_or_else(|| format!("record header lacks a '{name}' field"))?;
        std::str::from_utf8(v).map_err(|_| format!("field '{name}' is not UTF-8"))
    }
}

/// Little-endian u32 at `pos`, if the bytes are there.
pub fn read_u32(buf: &[u8], pos: usize) -> Option<u32> {
    let b = buf.get(pos..pos.checked_add(4)?)?;
    Some(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
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
    let hlen = read_u32(buf, pos)? as usize;
    let hstart = pos + 4;
    let header = buf.get(hstart..hstart.checked_add(hlen)?)?;
    let dlen_pos = hstart + hlen;
    let dlen = read_u32(buf, dlen_pos)? as usize;
    let dstart = dlen_pos + 4;
    let data = buf.get(dstart..dstart.checked_add(dlen)?)?;
    Some(RawRecord {
        header,
        data,
        end: dstart + dlen,
    })
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
    pub(crate) fn decode(header: &Header<'_>, data: &[u8]) -> Result<Connection, String> {
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
    pub(crate) fn decode(header: &Header<'_>, data: &[u8]) -> Result<ChunkInfo, String> {
        let count = header.u32("count")? as usize;
        if data.len() != count * 8 {
            return Err(format!(
                "chunk info lists {count} connections in {} bytes",
                data.len()
            ));
        }
        let counts = data
            .chunks_exact(8)
            .map(|c| {
                (
                    u32::from_le_bytes([c[0], c[1], c[2], c[3]]),
                    u32::from_le_bytes([c[4], c[5], c[6], c[7]]),
                )
            })
            .collect();
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
    let mut header = Vec::with_capacity(48);
    push_field(&mut header, "op", &[Op::Chunk as u8]);
    push_field(&mut header, "compression", compression.name().as_bytes());
    push_field(&mut header, "size", &uncompressed_len.to_le_bytes());
    header
}

/// Encodes an index-data record: `(time, offset into the uncompressed chunk body)` per message.
pub fn encode_index_data(out: &mut Vec<u8>, conn: u32, entries: &[(RosTime, u32)]) {
    let mut header = Vec::with_capacity(48);
    push_field(&mut header, "op", &[Op::IndexData as u8]);
    push_field(&mut header, "ver", &1u32.to_le_bytes());
    push_field(&mut header, "conn", &conn.to_le_bytes());
    push_field(&mut header, "count", &(entries.len() as u32).to_le_bytes());
    let mut data = Vec::with_capacity(12 * entries.len());
    for (t, off) in entries {
        data.extend_from_slice(&t.to_bytes());
        data.extend_from_slice(&off.to_le_bytes());
    }
    push_record(out, &header, &data);
}

/// Encodes a message-data record header (`op`, `conn`, `time`).
pub fn message_header(out: &mut Vec<u8>, conn: u32, time: RosTime) {
    push_field(out, "op", &[Op::MessageData as u8]);
    push_field(out, "conn", &conn.to_le_bytes());
    push_field(out, "time", &time.to_bytes());
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
