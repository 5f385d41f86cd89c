"""What Foxglove's MCAP reader recovers from damaged files, as a user of the library gets it.

Usage: mcap_recover.py TOPIC CLEAN.mcap DAMAGED.mcap...
For each damaged file, prints one line: the number of messages on TOPIC that the better of
Foxglove's two readers yields and that are messages of the clean file (same log time, same
bytes): its seeking reader (summary and chunk indexes, falling back to a linear pass when
there is none) and its non-seeking reader (one linear pass), both with CRCs checked, each
stopping at its first error. The Rust tests and the fuzz campaign require bag2mat to recover
at least as many."""
import sys

from mcap.reader import NonSeekingReader, SeekingReader


def recovered(path, topic, clean):
    best = 0
    for make in (SeekingReader, NonSeekingReader):
        got = set()
        try:
            with open(path, "rb") as f:
                for _, channel, msg in make(f, validate_crcs=True).iter_messages(
                    topics=[topic], log_time_order=False
                ):
                    key = (msg.log_time, bytes(msg.data))
                    if channel.topic == topic and key in clean:
                        got.add(key)
        except Exception:
            pass
        best = max(best, len(got))
    return best


def main():
    topic, clean_path = sys.argv[1], sys.argv[2]
    with open(clean_path, "rb") as f:
        clean = {
            (m.log_time, bytes(m.data))
            for _, _, m in SeekingReader(f, validate_crcs=True).iter_messages(topics=[topic])
        }
    for p in sys.argv[3:]:
        print(recovered(p, topic, clean))


main()
