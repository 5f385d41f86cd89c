"""The independent readers' view of a log, for bag2mat's cross-checks (run in target/py-venv).

  read_logs.py ulog FILE            pyulog: every IMU topic bag2mat reads, as rows
  read_logs.py ulog-rewrite IN OUT  pyulog reads IN and writes it back as OUT (write_ulog)
  read_logs.py dataflash FILE       pymavlink DFReader: IMU per instance and ISBH/ISBD batches
  read_logs.py csv FILE COLS...     pandas.read_csv (C engine, round-trip floats): the columns

Rows are printed as `# topic N` then N lines `record_ns stamp_ns gx gy gz ax ay az` with
Python's repr (exact for doubles), NaN where a topic lacks a sensor.
"""
import math
import sys

NAN = float("nan")


def emit(topic, rows):
    print(f"# {topic} {len(rows)}")
    for r in rows:
        print(" ".join(repr(v) if isinstance(v, float) else str(v) for v in r))


def ulog(path):
    from pyulog import ULog
    log = ULog(path)
    names = {}
    for d in log.data_list:
        names.setdefault(d.name, set()).add(d.multi_id)
    for d in sorted(log.data_list, key=lambda d: (d.name, d.multi_id)):
        topic = d.name if names[d.name] == {0} else f"{d.name}:{d.multi_id}"
        f = d.data
        n = len(f["timestamp"])
        t = [int(x) * 1000 for x in f["timestamp"]]
        ts = [int(x) * 1000 for x in f["timestamp_sample"]] if "timestamp_sample" in f else t
        rows = []
        if d.name == "sensor_combined":
            for i in range(n):
                rows.append([t[i], t[i]] + [float(f[f"gyro_rad[{k}]"][i]) for k in range(3)]
                            + [float(f[f"accelerometer_m_s2[{k}]"][i]) for k in range(3)])
        elif d.name in ("sensor_gyro", "sensor_accel"):
            for i in range(n):
                v = [float(f[a][i]) for a in "xyz"]
                rows.append([t[i], ts[i]] + (v + [NAN] * 3 if d.name == "sensor_gyro" else [NAN] * 3 + v))
        elif d.name in ("sensor_gyro_fifo", "sensor_accel_fifo"):
            # samples k of N, dt µs apart, the newest at timestamp_sample; x[k] * scale
            for i in range(n):
                N = int(f["samples"][i])
                dt = float(f["dt"][i])
                sc = float(f["scale"][i])
                for k in range(N):
                    off = math.floor((N - 1 - k) * dt * 1000.0 + 0.5)
                    v = [float(int(f[f"{a}[{k}]"][i])) * sc for a in "xyz"]
                    rows.append([t[i] - off, ts[i] - off]
                                + (v + [NAN] * 3 if d.name == "sensor_gyro_fifo" else [NAN] * 3 + v))
        elif d.name == "vehicle_imu":
            for i in range(n):
                da = float(f["delta_angle_dt"][i])
                dv = float(f["delta_velocity_dt"][i])
                if not (da > 0 and dv > 0):
                    continue
                rows.append([t[i], ts[i]] + [float(f[f"delta_angle[{k}]"][i]) / (da * 1e-6) for k in range(3)]
                            + [float(f[f"delta_velocity[{k}]"][i]) / (dv * 1e-6) for k in range(3)])
        else:
            print(f"% {topic} {n}")
            continue
        emit(topic, rows)
    print(f"% dropouts {len(log.dropouts)} {sum(d.duration for d in log.dropouts)}")


def ulog_rewrite(src, dst):
    from pyulog import ULog
    ULog(src).write_ulog(dst)


def dataflash(path):
    from pymavlink import DFReader
    log = DFReader.DFReader_binary(path, zero_time_base=True)
    imu = {}
    batches = {}
    head = {}
    while True:
        m = log.recv_msg()
        if m is None:
            break
        t = m.get_type()
        if t == "IMU":
            imu.setdefault(m.I, []).append(
                [m.TimeUS * 1000, m.TimeUS * 1000, float(m.GyrX), float(m.GyrY), float(m.GyrZ),
                 float(m.AccX), float(m.AccY), float(m.AccZ)])
        elif t == "ISBH":
            head[m.N] = m
        elif t == "ISBD":
            h = head.get(m.N)
            if h is None:
                continue
            gyro = h.type == 1
            key = ("ISB_GYR" if gyro else "ISB_ACC", h.instance)
            rows = batches.setdefault(key, [])
            for k, (x, y, z) in enumerate(zip(m.x, m.y, m.z)):
                j = m.seqno * 32 + k
                if j >= h.smp_cnt:
                    break
                # half away from zero, as Rust's f64::round
                t_ns = h.SampleUS * 1000 + math.floor(j * 1e9 / h.smp_rate + 0.5)
                v = [x / h.mul, y / h.mul, z / h.mul]
                rows.append([t_ns, t_ns] + (v + [NAN] * 3 if gyro else [NAN] * 3 + v))
    # bag2mat's names: `name` when the log has only instance 0 of it, else `name:k`
    def topic(name, i, all_i):
        return name if set(all_i) == {0} else f"{name}:{i}"
    for i in sorted(imu):
        emit(topic("IMU", i, imu), imu[i])
    for (name, i) in sorted(batches):
        emit(topic(name, i, [k for (n, k) in batches if n == name]), batches[(name, i)])


def csv(path, cols):
    import pandas as pd
    df = pd.read_csv(path, engine="c", float_precision="round_trip", comment=None)
    for c in cols:
        print(f"# {c} {len(df)}")
        print("\n".join(repr(float(v)) if df[c].dtype.kind == "f" else str(int(v)) for v in df[c]))


if __name__ == "__main__":
    cmd = sys.argv[1]
    if cmd == "ulog":
        ulog(sys.argv[2])
    elif cmd == "ulog-rewrite":
        ulog_rewrite(sys.argv[2], sys.argv[3])
    elif cmd == "dataflash":
        dataflash(sys.argv[2])
    elif cmd == "csv":
        csv(sys.argv[2], sys.argv[3:])
    else:
        sys.exit(f"unknown command {cmd}")
