"""Times the rosbags Python library reading (and deserializing) the first N Imu messages of a
ROS 2 bag: the Python baseline of scripts/bench.sh. Usage: bench_rosbags_read.py BAGDIR N.
Prints the seconds."""
import sys
import time
from pathlib import Path

from rosbags.highlevel import AnyReader

path, n = Path(sys.argv[1]), int(sys.argv[2])
t0 = time.perf_counter()
k = 0
with AnyReader([path]) as r:
    for c, t, raw in r.messages():
        m = r.deserialize(raw, c.msgtype)
        _ = (t, m.linear_acceleration.x, m.angular_velocity.z)
        k += 1
        if k >= n:
            break
print(time.perf_counter() - t0)
