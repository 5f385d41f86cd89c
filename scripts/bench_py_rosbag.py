"""Benchmark partner for scripts/bench.sh: the same work done by Debian's python rosbag.

  write OUT.bag N [none|lz4]   writes N sensor_msgs/Imu messages at 200 Hz on topic 'imu'
  read  BAG N                  reads the first N messages and builds the N x 7 rows bagconvert writes
Prints the elapsed seconds of the work itself (imports excluded)."""
import sys
import time

import rosbag
import rospy
from sensor_msgs.msg import Imu


def write(path, n, compression):
    msg = Imu()
    msg.header.frame_id = "base_link"
    msg.orientation.w = 1.0
    t0 = time.perf_counter()
    with rosbag.Bag(path, "w", compression=compression) as bag:
        for i in range(n):
            stamp = rospy.Time(1700000000 + i // 200, (i % 200) * 5000000)
            msg.header.stamp = stamp
            msg.angular_velocity.x = 1e-3 * (i % 97)
            msg.linear_acceleration.z = 9.81 + 1e-3 * (i % 89)
            bag.write("imu", msg, stamp)
    return time.perf_counter() - t0


def read(path, n):
    t0 = time.perf_counter()
    rows = []
    with rosbag.Bag(path) as bag:
        for k, (_, m, t) in enumerate(bag.read_messages(topics=["imu"])):
            if k >= n:
                break
            a, w = m.linear_acceleration, m.angular_velocity
            rows.append((t.to_sec(), a.x, a.y, a.z, w.x, w.y, w.z))
    return time.perf_counter() - t0


if __name__ == "__main__":
    if sys.argv[1] == "write":
        print("%.3f" % write(sys.argv[2], int(sys.argv[3]), sys.argv[4] if len(sys.argv) > 4 else "none"))
    else:
        print("%.3f" % read(sys.argv[2], int(sys.argv[3])))
