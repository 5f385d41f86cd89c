"""Independent writers of the logs the tests feed the tools, with a known truth (seeded numpy):

  write_logs.py ros1 OUT SPEC   Debian's python rosbag (run with /usr/bin/python3): a ROS 1 bag
  write_logs.py ulog OUT SPEC   pyulog's own writer (ULog.write_ulog, run in target/py-venv)

SPEC is JSON. Every IMU topic is white noise of the given densities (continuous time,
rad/s/sqrt(Hz) and m/s^2/sqrt(Hz)) around a bias, gravity on acc z, at `rate` Hz from `t0`.

ros1: {"seed", "t0", "topics": [{"topic", "n", "rate", "gyro_n", "acc_n",
       "recv_delay_s": mean of an exponential receive delay (record time = the later of the
       previous record time and stamp + delay; 0: the stamp),
       "drop_every": [k, r]: the samples i with i % k == r are lost (not written),
       "drop_ranges": [[first, count], ...]: runs of samples lost}]}
ulog: {"seed", "start_us", "topics": [...]} with topics of kinds
       {"kind": "sensor_combined", "rate", "seconds", "t0_us", "gyro_n", "acc_n"}
       {"kind": "vehicle_imu", "row_us": spacing of the logged rows, "dt_us": what each row
        integrates (the mean rate over dt_us, ending at the row's timestamp_sample), "seconds",
        "t0_us", "gyro_n", "acc_n"}
       {"kind": "stale", "name", "times_us": [...]}: a topic of other messages (a uint64
        timestamp and a float) at the given times, e.g. one published before the log started
"""
import json
import struct
import sys

import numpy as np

G = 9.80665


def ros1(out, spec):
    import rosbag
    import rospy
    from sensor_msgs.msg import Imu

    rng = np.random.default_rng(spec["seed"])
    t0 = spec.get("t0", 1700000000.0)
    with rosbag.Bag(out, "w") as bag:
        for tp in spec["topics"]:
            n, rate = tp["n"], tp["rate"]
            sg = tp["gyro_n"] * np.sqrt(rate)
            sa = tp["acc_n"] * np.sqrt(rate)
            w = rng.normal(0.0, sg, (n, 3))
            a = rng.normal(0.0, sa, (n, 3))
            a[:, 2] += G
            stamp_ns = (round(t0 * 1e9) + np.round(np.arange(n) * 1e9 / rate)).astype(np.int64)
            delay = tp.get("recv_delay_s", 0.0)
            if delay > 0:
                d = np.round(rng.exponential(delay, n) * 1e9).astype(np.int64)
                rec = np.maximum.accumulate(stamp_ns + d)
            else:
                rec = stamp_ns
            lost = set()
            if "drop_every" in tp:
                k, r = tp["drop_every"]
                lost.update(i for i in range(n) if i % k == r)
            for first, count in tp.get("drop_ranges", []):
                lost.update(range(first, first + count))
            for i in range(n):
                if i in lost:
                    continue
                m = Imu()
                m.header.seq = i
                m.header.stamp = rospy.Time(0, int(stamp_ns[i]))
                m.angular_velocity.x, m.angular_velocity.y, m.angular_velocity.z = w[i]
                m.linear_acceleration.x, m.linear_acceleration.y, m.linear_acceleration.z = a[i]
                bag.write(tp["topic"], m, rospy.Time(0, int(rec[i])))


VEHICLE_IMU = ("uint64_t timestamp;uint64_t timestamp_sample;uint32_t accel_device_id;"
               "uint32_t gyro_device_id;float[3] delta_angle;float[3] delta_velocity;"
               "uint16_t delta_angle_dt;uint16_t delta_velocity_dt;uint8_t delta_angle_clipping;"
               "uint8_t delta_velocity_clipping;uint8_t accel_calibration_count;"
               "uint8_t gyro_calibration_count;")
SENSOR_COMBINED = ("uint64_t timestamp;float[3] gyro_rad;uint32_t gyro_integral_dt;"
                   "int32_t accelerometer_timestamp_relative;float[3] accelerometer_m_s2;"
                   "uint32_t accelerometer_integral_dt;uint8_t accelerometer_clipping;"
                   "uint8_t gyro_clipping;uint8_t accel_calibration_count;"
                   "uint8_t gyro_calibration_count;")
STALE = "uint64_t timestamp;float value;"


def topic_rows(tp, rng):
    """The format and the columns of one topic."""
    kind = tp["kind"]
    if kind == "sensor_combined":
        rate = tp["rate"]
        n = int(round(tp["seconds"] * rate))
        t = tp["t0_us"] + np.round(np.arange(n) * 1e6 / rate).astype(np.uint64)
        cols = {"timestamp": t, "gyro_integral_dt": np.full(n, int(1e6 / rate)),
                "accelerometer_integral_dt": np.full(n, int(1e6 / rate))}
        w = rng.normal(0.0, tp["gyro_n"] * np.sqrt(rate), (n, 3))
        a = rng.normal(0.0, tp["acc_n"] * np.sqrt(rate), (n, 3))
        a[:, 2] += G
        for k in range(3):
            cols[f"gyro_rad[{k}]"] = w[:, k]
            cols[f"accelerometer_m_s2[{k}]"] = a[:, k]
        return "sensor_combined", SENSOR_COMBINED, cols
    if kind == "vehicle_imu":
        row_us, dt_us = tp["row_us"], tp["dt_us"]
        n = int(tp["seconds"] * 1e6 // row_us)
        ts = tp["t0_us"] + np.arange(1, n + 1, dtype=np.uint64) * np.uint64(row_us)
        # the mean of white noise of density N over dt has the standard deviation N/sqrt(dt)
        w = rng.normal(0.0, tp["gyro_n"] / np.sqrt(dt_us * 1e-6), (n, 3))
        a = rng.normal(0.0, tp["acc_n"] / np.sqrt(dt_us * 1e-6), (n, 3))
        a[:, 2] += G
        cols = {"timestamp": ts + np.uint64(300), "timestamp_sample": ts,
                "delta_angle_dt": np.full(n, dt_us), "delta_velocity_dt": np.full(n, dt_us)}
        for k in range(3):
            cols[f"delta_angle[{k}]"] = w[:, k] * dt_us * 1e-6
            cols[f"delta_velocity[{k}]"] = a[:, k] * dt_us * 1e-6
        return "vehicle_imu", VEHICLE_IMU, cols
    if kind == "stale":
        t = np.array(tp["times_us"], dtype=np.uint64)
        return tp["name"], STALE, {"timestamp": t, "value": np.zeros(len(t))}
    raise SystemExit(f"unknown topic kind {kind}")


def ulog(out, spec):
    from pyulog import ULog

    rng = np.random.default_rng(spec["seed"])
    log = ULog(None)
    log._file_version = 1
    log._start_timestamp = spec["start_us"]
    tables = [topic_rows(tp, rng) for tp in spec["topics"]]
    for name, fmt, _ in tables:
        log._message_formats[name] = ULog.MessageFormat(f"{name}:{fmt}".encode(), None)
    for msg_id, (name, _, cols) in enumerate(tables):
        add = ULog._MessageAddLogged(struct.pack("<BH", 0, msg_id) + name.encode(), None,
                                     log._message_formats)
        n = len(cols["timestamp"])
        arr = np.zeros(n, dtype=add.dtype)
        for k, v in cols.items():
            arr[k] = v
        add.buffer = bytearray(arr.tobytes())
        log._data_list.append(ULog.Data(add))
    log.write_ulog(out)


if __name__ == "__main__":
    cmd, out, spec = sys.argv[1], sys.argv[2], json.loads(sys.argv[3])
    {"ros1": ros1, "ulog": ulog}[cmd](out, spec)
