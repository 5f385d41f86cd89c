"""Rewrites an MCAP file with Foxglove's writer: the same schemas, channels and messages (log
time, publish time, sequence, bytes), in chunks of CHUNK_BYTES compressed as named (none, lz4,
zstd), with message indexes, statistics, summary offsets and CRCs as that writer makes them.
The fuzz campaign corrupts such files: an independent writer's layout, our payloads.

Usage: mcap_rewrite.py SRC.mcap DST.mcap CHUNK_BYTES COMPRESSION"""
import sys

from mcap.reader import SeekingReader
from mcap.writer import CompressionType, Writer

src, dst, chunk, compression = sys.argv[1], sys.argv[2], int(sys.argv[3]), sys.argv[4]
kind = {"none": CompressionType.NONE, "lz4": CompressionType.LZ4, "zstd": CompressionType.ZSTD}
with open(src, "rb") as f, open(dst, "wb") as out:
    r = SeekingReader(f, validate_crcs=True)
    header = r.get_header()
    w = Writer(out, chunk_size=chunk, compression=kind[compression])
    w.start(profile=header.profile, library="mcap-python (fuzz campaign)")
    schemas, channels = {}, {}
    for schema, channel, msg in r.iter_messages(log_time_order=False):
        if schema is not None and schema.id not in schemas:
            schemas[schema.id] = w.register_schema(schema.name, schema.encoding, schema.data)
        if channel.id not in channels:
            channels[channel.id] = w.register_channel(
                channel.topic,
                channel.message_encoding,
                schemas.get(channel.schema_id, 0),
                channel.metadata,
            )
        w.add_message(
            channels[channel.id], msg.log_time, msg.data, msg.publish_time, msg.sequence
        )
    w.finish()
