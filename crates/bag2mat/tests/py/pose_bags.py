"""Writes pose and odometry topics with an independent writer, rosbags (the venv's pinned
0.11.9): a ROS 1 bag, or a ROS 2 bag directory (mcap or sqlite3 storage, CDR). Four topics,
one per type bag2mat reads as a reference trajectory, each with N messages whose stamps,
positions and orientations follow this script's own formulas; the values written are
printed on stdout, a line per message: topic, header ns, record ns, x y z qx qy qz qw
(Python's repr: the shortest text of each double).

usage: pose_bags.py ros1|mcap|sqlite3 OUT [--n N]
       pose_bags.py ros1|mcap|sqlite3 OUT --from-tum FILE
  (the second form writes FILE's poses as geometry_msgs/PoseStamped on /mocap/body, header
  stamp and record time both the file's time: a motion-capture topic)
"""
import math
import sys

from rosbags.typesys import Stores, get_typestore

T0_NS = 1_700_000_000 * 10**9


def poses(n, k):
    """Pose i of topic k: a slow helix with a rotation about a tilted axis."""
    out = []
    for i in range(n):
        t = i * 0.01
        header = T0_NS + i * 10_000_000 + 1_234 * k
        record = header + 2_500_000 + 17 * i  # transport latency
        ang = 0.3 * math.sin(0.7 * t + k)
        ax = [0.6, 0.0, 0.8]
        s, c = math.sin(ang / 2), math.cos(ang / 2)
        q = [ax[0] * s, ax[1] * s, ax[2] * s, c]
        p = [math.cos(t) + k, math.sin(t), 0.1 * t]
        out.append([header, record] + p + q)
    return out


def main():
    a = sys.argv[1:]
    kind, out = a[0], a[1]
    n = int(a[a.index("--n") + 1]) if "--n" in a else 50
    store = Stores.ROS1_NOETIC if kind == "ros1" else Stores.ROS2_HUMBLE
    ts = get_typestore(store)
    T = ts.types
    Time = T["builtin_interfaces/msg/Time"]
    Header = T["std_msgs/msg/Header"]
    Point, Quat = T["geometry_msgs/msg/Point"], T["geometry_msgs/msg/Quaternion"]
    Vec3 = T["geometry_msgs/msg/Vector3"]
    Pose = T["geometry_msgs/msg/Pose"]
    PoseCov = T["geometry_msgs/msg/PoseWithCovariance"]
    Twist = T["geometry_msgs/msg/Twist"]
    TwistCov = T["geometry_msgs/msg/TwistWithCovariance"]
    import numpy as np

    def header(ns, frame):
        stamp = Time(sec=ns // 10**9, nanosec=ns % 10**9)
        if kind == "ros1":
            return Header(seq=7, stamp=stamp, frame_id=frame)
        return Header(stamp=stamp, frame_id=frame)

    def pose(r):
        return Pose(position=Point(x=r[2], y=r[3], z=r[4]),
                    orientation=Quat(x=r[5], y=r[6], z=r[7], w=r[8]))

    cov = np.arange(36, dtype=np.float64)
    topics = {
        "/vicon/body": ("geometry_msgs/msg/PoseStamped",
                        lambda r: T["geometry_msgs/msg/PoseStamped"](header=header(r[0], "world"), pose=pose(r))),
        "/pose_cov": ("geometry_msgs/msg/PoseWithCovarianceStamped",
                      lambda r: T["geometry_msgs/msg/PoseWithCovarianceStamped"](
                          header=header(r[0], "map"), pose=PoseCov(pose=pose(r), covariance=cov))),
        "/odom": ("nav_msgs/msg/Odometry",
                  lambda r: T["nav_msgs/msg/Odometry"](
                      header=header(r[0], "odom"), child_frame_id="base_link_frame",
                      pose=PoseCov(pose=pose(r), covariance=cov),
                      twist=TwistCov(twist=Twist(linear=Vec3(x=1.0, y=2.0, z=3.0),
                                                 angular=Vec3(x=0.0, y=0.0, z=0.5)),
                                     covariance=cov))),
        "/tf_body": ("geometry_msgs/msg/TransformStamped",
                     lambda r: T["geometry_msgs/msg/TransformStamped"](
                         header=header(r[0], "w"), child_frame_id="b",
                         transform=T["geometry_msgs/msg/Transform"](
                             translation=Vec3(x=r[2], y=r[3], z=r[4]),
                             rotation=Quat(x=r[5], y=r[6], z=r[7], w=r[8])))),
    }
    truth = {}
    if kind == "ros1":
        from rosbags.rosbag1 import Writer
        w = Writer(out)
        w.open()
        conns = {} if "--from-tum" in a else {t: w.add_connection(t, mt, typestore=ts) for t, (mt, _) in topics.items()}
        ser = lambda m, mt: ts.serialize_ros1(m, mt)
    else:
        from rosbags.rosbag2 import StoragePlugin, Writer
        plugin = StoragePlugin.MCAP if kind == "mcap" else StoragePlugin.SQLITE3
        w = Writer(out, version=8, storage_plugin=plugin)
        w.open()
        conns = {} if "--from-tum" in a else {t: w.add_connection(t, mt, typestore=ts) for t, (mt, _) in topics.items()}
        ser = lambda m, mt: ts.serialize_cdr(m, mt)
    if "--from-tum" in a:
        mt = "geometry_msgs/msg/PoseStamped"
        conn = w.add_connection("/mocap/body", mt, typestore=ts)
        for line in open(a[a.index("--from-tum") + 1]):
            f = line.split()
            if not f or f[0].startswith("#"):
                continue
            sec, frac = f[0].split(".")
            ns = int(sec) * 10**9 + int(frac.ljust(9, "0")[:9])
            r = [ns, ns] + [float(x) for x in f[1:8]]
            w.write(conn, ns, bytes(ser(topics["/vicon/body"][1](r), mt)))
        w.close()
        return
    for k, (t, (mt, make)) in enumerate(topics.items()):
        rows = poses(n, k)
        truth[t] = rows
        for r in rows:
            w.write(conns[t], r[1], bytes(ser(make(r), mt)))
    w.close()
    for t, rows in truth.items():
        for r in rows:
            print(t, *[repr(v) for v in r])


main()
