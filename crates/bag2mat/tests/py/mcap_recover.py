"""What Foxglove's MCAP reader recovers from damaged files, as a user of the library gets it.

Usage: mcap_recover.py TOPIC CLEAN.mcap DAMAGED.mcap...
For each damaged file, prints one line: the number of messages on TOPIC that the better of
Foxglove's two readers yields under the clean file's schema name (what a typed decoder such
as mcap_ros2 needs) and that are messages of the clean file (same log time, same bytes): its seeking reader (summary and chunk indexes, falling back to a linear pass when
there is none) and its non-seeking reader (one linear pass), both with CRCs checked, each
stopping at its first error. The Rust tests and the fuzz campaign require bag2mat to recover
at least as many."""
import sys

from mcap.reader import NonSeekingReader, SeekingReader


def recovered(path, topic, clean, schema_name):
    best = 0
    for make in (SeekingReader, NonSeekingReader):
        got = set()
        try:
            with open(path, "rb") as f:
                for schema, channel, msg in make(f, validate_crcs=True).iter_messages(
                    topics=[topic], log_time_order=False
                ):
                    key = (msg.log_time, bytes(msg.data))
                    name = schema.name if schema is not None else None
                    if channel.topic == topic and name == schema_name and key in clean:
                        got.add(key)
        except Exception:
            pass
        best = max(best, len(got))
    return best


def main():
    topic, clean_path = sys.argv[1], sys.argv[2]
    # The clean file may itself be cut short: what either reader reads of it.
    clean = set()
    schema_name = None
    for make in (SeekingReader, NonSeekingReader):
        try:
            with open(clean_path, "rb") as f:
                for s, _, m in make(f, validate_crcs=True).iter_messages(
                    topics=[topic], log_time_order=False
                ):
                    clean.add((m.log_time, bytes(m.data)))
                    schema_name = s.name if s is not None else None
        except Exception:
            pass
    for p in sys.argv[3:]:
        print(recovered(p, topic, clean, schema_name))


main()
