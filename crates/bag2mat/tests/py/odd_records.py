"""Writes IMU records that break what an Allan analysis assumes, with an independent writer:
Debian's python3-rosbag (a ROS 1 bag; run with /usr/bin/python3) or Foxglove's mcap_ros2
writer (a bare ROS 2 .mcap with header jitter and transport latency; run with the venv's
python). The noise is this script's own (Python's seeded random): white noise + bias random
walk per axis, continuous-time truth printed as JSON on stdout.

usage: odd_records.py rosbag|mcap OUT CASE [--seconds S] [--rate HZ] [--seed N]

CASE (comma-separated, combined in order):
  clean       nothing odd
  dropouts    2 % of the messages lost, one at a time (never two in a row, never the first
              or the last: the span holds every lost one)
  wrong_rate  nothing odd in the record (the test passes a wrong --update-rate)
  warmup      0.02 rad/s * exp(-t / 100 s) on the three gyro axes
  warmup5s    5 sigma (per sample) * exp(-t / 300 s) on all six axes
  handheld    slow hand-held motion (0.1-0.2 rad orientation swings at 0.05-0.2 Hz)
  clockstep   the clock (record time and header) steps back halfway, by a third of the
              record (at most 1200 s): the halves overlap in time
  dup2pct     2 % of the messages written twice (same stamps, same values)
  spike       one message with angular_velocity.x = 1e6 rad/s, at 40 % of the record
  header2x    record time at the rate, header.stamp advancing twice as fast
  headerstep  header.stamp steps back 0.5 s at 60 % of the record (the record time does not)
"""
import json
import math
import random
import sys

T0_NS = 1_700_000_000 * 10**9
GRAVITY = 9.80665
# continuous-time truth (gyro rad/s/sqrt(Hz), rad/s^2/sqrt(Hz); acc m/s^2/sqrt(Hz), m/s^3/sqrt(Hz))
TRUTH = {"gyro_n": 1.0e-3, "gyro_k": 2.0e-5, "acc_n": 2.0e-2, "acc_k": 4.0e-4}


def args():
    a = sys.argv[1:]
    opt = {"--seconds": 300.0, "--rate": 200.0, "--seed": 1}
    pos = []
    i = 0
    while i < len(a):
        if a[i] in opt:
            opt[a[i]] = type(opt[a[i]])(a[i + 1])
            i += 2
        else:
            pos.append(a[i])
            i += 1
    writer, out, cases = pos
    return writer, out, cases.split(","), opt["--seconds"], opt["--rate"], opt["--seed"]


def samples(cases, seconds, rate, seed):
    """(record ns, header ns, gyro xyz, acc xyz) per message, in the order written."""
    rng = random.Random(seed)
    n = int(round(seconds * rate))
    sw_g = TRUTH["gyro_n"] * math.sqrt(rate)
    sk_g = TRUTH["gyro_k"] / math.sqrt(rate)
    sw_a = TRUTH["acc_n"] * math.sqrt(rate)
    sk_a = TRUTH["acc_k"] / math.sqrt(rate)
    bias = [0.01, -0.02, 0.005, 0.05, -0.03, 0.0]
    rows = []
    period_ns = round(1e9 / rate)
    phases = [rng.uniform(0, 2 * math.pi) for _ in range(6)]
    for i in range(n):
        t = i / rate
        g = []
        for k in range(3):
            bias[k] += rng.gauss(0, sk_g)
            g.append(bias[k] + rng.gauss(0, sw_g))
        a = []
        for k in range(3):
            bias[3 + k] += rng.gauss(0, sk_a)
            a.append(bias[3 + k] + rng.gauss(0, sw_a))
        a[2] += GRAVITY
        if "warmup" in cases:
            for k in range(3):
                g[k] += 0.02 * math.exp(-t / 100.0)
        if "warmup5s" in cases:
            for k in range(3):
                g[k] += 5 * sw_g * math.exp(-t / 300.0)
                a[k] += 5 * sw_a * math.exp(-t / 300.0)
        if "handheld" in cases:
            # roll, pitch, yaw swings; body rates ~ their derivatives (small angles)
            amp = [0.15, 0.1, 0.2]
            freq = [0.07, 0.11, 0.05]
            ang = [amp[k] * math.sin(2 * math.pi * freq[k] * t + phases[k]) for k in range(3)]
            for k in range(3):
                g[k] += amp[k] * 2 * math.pi * freq[k] * math.cos(2 * math.pi * freq[k] * t + phases[k])
            roll, pitch = ang[0], ang[1]
            # gravity in the tilted body frame, plus a small hand translation (5 cm at 0.3 Hz)
            lin = 0.05 * (2 * math.pi * 0.3) ** 2 * math.sin(2 * math.pi * 0.3 * t + phases[3])
            a[0] += -GRAVITY * math.sin(pitch) + lin
            a[1] += GRAVITY * math.sin(roll) * math.cos(pitch)
            a[2] += GRAVITY * (math.cos(roll) * math.cos(pitch) - 1.0)
        if "spike" in cases and i == int(0.4 * n):
            g[0] = 1e6
        rec = T0_NS + i * period_ns
        hdr = rec
        if "header2x" in cases:
            hdr = T0_NS + i * period_ns // 2
        if "headerstep" in cases and i >= int(0.6 * n):
            hdr -= 500_000_000
        if "clockstep" in cases and i >= n // 2:
            step = int(min(1200.0, seconds / 3) * 1e9)
            rec -= step
            hdr -= step
        rows.append((rec, hdr, g, a))
    if "dropouts" in cases:
        keep = []
        last_dropped = False
        for idx, r in enumerate(rows):
            drop = not last_dropped and rng.random() < 0.02 / 0.98
            # never the first or the last: every lost message is inside the span
            if drop and 0 < len(keep) and idx < len(rows) - 1:
                last_dropped = True
                continue
            last_dropped = False
            keep.append(r)
        rows = keep
    if "dup2pct" in cases:
        out = []
        for r in rows:
            out.append(r)
            if rng.random() < 0.02:
                out.append(r)
        rows = out
    return rows


def write_rosbag(out, rows, jitter):
    import rosbag
    import rospy
    from sensor_msgs.msg import Imu

    with rosbag.Bag(out, "w") as bag:
        for seq, (rec, hdr, g, a) in enumerate(rows):
            m = Imu()
            m.header.seq = seq
            m.header.frame_id = "imu"
            m.header.stamp = rospy.Time(hdr // 10**9, hdr % 10**9)
            m.orientation.w = 1.0
            m.angular_velocity.x, m.angular_velocity.y, m.angular_velocity.z = g
            m.linear_acceleration.x, m.linear_acceleration.y, m.linear_acceleration.z = a
            bag.write("imu", m, rospy.Time(rec // 10**9, rec % 10**9))


IMU_MSGDEF = """std_msgs/Header header
geometry_msgs/Quaternion orientation
float64[9] orientation_covariance
geometry_msgs/Vector3 angular_velocity
float64[9] angular_velocity_covariance
geometry_msgs/Vector3 linear_acceleration
float64[9] linear_acceleration_covariance
================================================================================
MSG: std_msgs/Header
builtin_interfaces/Time stamp
string frame_id
================================================================================
MSG: builtin_interfaces/Time
int32 sec
uint32 nanosec
================================================================================
MSG: geometry_msgs/Quaternion
float64 x 0
float64 y 0
float64 z 0
float64 w 1
================================================================================
MSG: geometry_msgs/Vector3
float64 x
float64 y
float64 z
"""


def write_mcap(out, rows, seed):
    """Header stamps with 50 us of jitter, log time 0.5-3 ms of transport latency later."""
    from mcap_ros2.writer import Writer

    rng = random.Random(seed + 1000)
    with open(out, "wb") as f:
        w = Writer(f)
        schema = w.register_msgdef("sensor_msgs/msg/Imu", IMU_MSGDEF)
        for seq, (rec, hdr, g, a) in enumerate(rows):
            hdr_j = hdr + int(rng.gauss(0, 50_000))
            log = rec + int(rng.uniform(0.5e6, 3e6))
            msg = {
                "header": {"stamp": {"sec": hdr_j // 10**9, "nanosec": hdr_j % 10**9}, "frame_id": "imu"},
                "orientation": {"x": 0.0, "y": 0.0, "z": 0.0, "w": 1.0},
                "orientation_covariance": [0.0] * 9,
                "angular_velocity": {"x": g[0], "y": g[1], "z": g[2]},
                "angular_velocity_covariance": [0.0] * 9,
                "linear_acceleration": {"x": a[0], "y": a[1], "z": a[2]},
                "linear_acceleration_covariance": [0.0] * 9,
            }
            w.write_message("/imu", schema, msg, log_time=log, publish_time=log, sequence=seq)
        w.finish()


def main():
    writer, out, cases, seconds, rate, seed = args()
    rows = samples(cases, seconds, rate, seed)
    if writer == "rosbag":
        write_rosbag(out, rows, False)
    elif writer == "mcap":
        write_mcap(out, rows, seed)
    else:
        raise SystemExit(f"unknown writer {writer}")
    info = dict(TRUTH)
    info.update({"messages": len(rows), "rate": rate, "seconds": seconds, "cases": cases})
    print(json.dumps(info))


main()
