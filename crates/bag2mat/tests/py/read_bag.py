"""Reads every message of a bag with Debian's python rosbag API and prints one line each:
topic, record time ns, seq, stamp ns, frame_id, md5, then the 37 doubles of the Imu as hex.
Used by the Rust tests to check that bags we write read back exactly in the real tools."""
import struct
import sys

import rosbag

with rosbag.Bag(sys.argv[1]) as bag:
    for topic, msg, t in bag.read_messages():
        d = [msg.orientation.x, msg.orientation.y, msg.orientation.z, msg.orientation.w]
        d += list(msg.orientation_covariance)
        d += [msg.angular_velocity.x, msg.angular_velocity.y, msg.angular_velocity.z]
        d += list(msg.angular_velocity_covariance)
        d += [msg.linear_acceleration.x, msg.linear_acceleration.y, msg.linear_acceleration.z]
        d += list(msg.linear_acceleration_covariance)
        print(topic, t.to_nsec(), msg.header.seq, msg.header.stamp.to_nsec(), msg.header.frame_id,
              msg._md5sum, " ".join(struct.pack("<d", v).hex() for v in d))
