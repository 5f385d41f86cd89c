#!/usr/bin/env python3
"""Writes the `allan_variance.csv` that ori-drs/allan_variance_ros computes from a ROS 1 bag,
independently of this project (Debian's python3-rosbag to read, plain Python to compute), for
the `--curves` tests. Run with /usr/bin/python3.

What allan_variance_ros does (AllanVarianceComputor.cpp, read for these facts): it reads the
topic's sensor_msgs/Imu messages with rosbag, drops a message whose header stamp is before the
last kept one, keeps every (imu_rate/measure_rate)-th message (the counter starts at 1), then
for each period p = 1 … 9999 (0.1·p s) averages the kept samples in back-to-back bins of
int(0.1·p·measure_rate) samples, starting bins while j < n − bin, and writes
sqrt(Σ(a[k+1] − a[k])² / (2·(bins − 1))) per axis (gyro converted to deg/s), space separated
as `period accX accY accZ gyroX gyroY gyroZ ` (period with 19 significant digits, values 7).

usage: avr_curve.py BAG TOPIC OUT.csv [IMU_RATE MEASURE_RATE]
"""
import math
import sys

import rosbag


def fmt(v, digits):
    if math.isnan(v):
        return "nan"
    return f"{v:.{digits}g}"


def main():
    bag, topic, out = sys.argv[1:4]
    imu_rate = float(sys.argv[4]) if len(sys.argv) > 4 else 200.0
    measure_rate = float(sys.argv[5]) if len(sys.argv) > 5 else imu_rate
    skip = int(imu_rate / measure_rate)
    rows = []
    counter = 0
    last = None
    with rosbag.Bag(bag) as b:
        for _, msg, _ in b.read_messages(topics=[topic]):
            counter += 1
            if counter % skip != 0:
                continue
            t = msg.header.stamp.to_nsec()
            if last is not None and t < last:
                continue
            last = t
            a, w = msg.linear_acceleration, msg.angular_velocity
            d = 180.0 / math.pi
            rows.append((a.x, a.y, a.z, w.x * d, w.y * d, w.z * d))
    n = len(rows)
    csum = [[0.0] * (n + 1) for _ in range(6)]
    for c in range(6):
        s, col = 0.0, csum[c]
        for i, r in enumerate(rows):
            s += r[c]
            col[i + 1] = s
    with open(out, "w") as f:
        for p in range(1, 10000):
            period = p * 0.1
            size = int(period * measure_rate)
            starts = range(0, max(n - size, 0), size) if size > 0 else range(0)
            dev = []
            for c in range(6):
                col = csum[c]
                avg = [(col[j + size] - col[j]) / size for j in starts]
                if len(avg) >= 2:
                    acc = sum((avg[k + 1] - avg[k]) ** 2 for k in range(len(avg) - 1))
                    dev.append(math.sqrt(acc / (2 * (len(avg) - 1))))
                elif len(avg) == 1:
                    dev.append(float("nan"))  # 0 / 0
                else:
                    dev.append(-0.0)  # sqrt(0 / -2)
            f.write(" ".join([fmt(period, 19)] + [fmt(v, 7) for v in dev]) + " \n")


if __name__ == "__main__":
    main()
