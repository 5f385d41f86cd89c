"""What the independent readers recover from damaged logs, for bag2mat's fuzz campaign.

Usage: log_rows.py FORMAT TOPIC CLEAN DAMAGED...
  FORMAT: ulog (pyulog), dataflash (pymavlink's DFReader), csv (pandas; bag2mat's
  t,ax,ay,az,wx,wy,wz layout, t in s), euroc (pandas; an EuRoC/ASL data.csv), npy (numpy).
  TOPIC: as bag2mat names it (sensor_combined, IMU:0, ISB_GYR, imu, imu0).

Prints the clean file's rows first (`N count`, then one line per row: time and the six values
gx gy gz ax ay az, repr, NaN where the topic lacks a sensor), then one line per damaged file:
`R ranges other` — the clean rows the reader delivers from it (their indices in the clean
read, as ranges a-b), and how many other rows it delivers — or `E why` when the reader fails
on the file. A row is the clean one when its time and every value are the same (bit for
bit). The readers are used as a user of each library would: pyulog's ULog(), DFReader's
recv_msg() loop with the batch expansion the bag2mat cross-checks use (tests/py/read_logs.py),
pandas.read_csv skipping the lines it cannot split and the rows whose fields are no numbers,
numpy.load.
"""
import contextlib
import io
import math
import signal
import sys

# seconds the reader may take on one file: longer is a hang, counted as a failure to read
TIMEOUT_S = 30


def _timeout(signum, frame):
    raise TimeoutError("the reader took too long")

NAN = float("nan")


def ulog_rows(path, topic):
    from pyulog import ULog
    name, _, multi = topic.partition(":")
    multi = int(multi or 0)
    # pyulog prints its warnings on stdout
    with contextlib.redirect_stdout(io.StringIO()):
        log = ULog(path)
    rows = []
    for d in log.data_list:
        if d.name != name or d.multi_id != multi:
            continue
        f = d.data
        for i in range(len(f["timestamp"])):
            t = int(f["timestamp"][i]) * 1000
            if name == "sensor_combined":
                v = [float(f[f"gyro_rad[{k}]"][i]) for k in range(3)] + \
                    [float(f[f"accelerometer_m_s2[{k}]"][i]) for k in range(3)]
            else:
                xyz = [float(f[a][i]) for a in "xyz"]
                v = xyz + [NAN] * 3 if name == "sensor_gyro" else [NAN] * 3 + xyz
            rows.append([t] + v)
    return rows


def dataflash_rows(path, topic):
    from pymavlink import DFReader
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
        log = DFReader.DFReader_binary(path, zero_time_base=True)
        name, _, inst = topic.partition(":")
        inst = int(inst or 0)
        rows, head = [], {}
        while True:
            m = log.recv_msg()
            if m is None:
                break
            t = m.get_type()
            if t == "IMU" and name == "IMU":
                if m.I == inst:
                    rows.append([m.TimeUS * 1000, float(m.GyrX), float(m.GyrY), float(m.GyrZ),
                                 float(m.AccX), float(m.AccY), float(m.AccZ)])
            elif t == "ISBH":
                head[m.N] = m
            elif t == "ISBD" and name.startswith("ISB_"):
                h = head.get(m.N)
                if h is None or h.instance != inst or (h.type == 1) != (name == "ISB_GYR"):
                    continue
                for k, (x, y, z) in enumerate(zip(m.x, m.y, m.z)):
                    j = m.seqno * 32 + k
                    if j >= h.smp_cnt:
                        break
                    t_ns = h.SampleUS * 1000 + math.floor(j * 1e9 / h.smp_rate + 0.5)
                    v = [x / h.mul, y / h.mul, z / h.mul]
                    rows.append([t_ns] + (v + [NAN] * 3 if name == "ISB_GYR" else [NAN] * 3 + v))
    return rows


def text_rows(path, euroc):
    import pandas as pd
    df = pd.read_csv(path, engine="c", dtype=str, on_bad_lines="skip", comment=None,
                     keep_default_na=False)
    if euroc:
        cols = ["#timestamp [ns]", "w_RS_S_x [rad s^-1]", "w_RS_S_y [rad s^-1]",
                "w_RS_S_z [rad s^-1]", "a_RS_S_x [m s^-2]", "a_RS_S_y [m s^-2]",
                "a_RS_S_z [m s^-2]"]
    else:
        cols = ["t", "wx", "wy", "wz", "ax", "ay", "az"]
    rows = []
    for rec in zip(*(df[c] for c in cols)):
        try:
            t = int(rec[0]) if euroc else float(rec[0])
            rows.append([t] + [float(x) for x in rec[1:]])
        except (TypeError, ValueError):
            continue
    return rows


def npy_rows(path):
    import numpy as np
    a = np.load(path)
    if a.ndim != 2 or a.shape[1] != 7:
        raise ValueError(f"shape {a.shape}")
    # bag2mat's layout: t ax ay az wx wy wz
    return [[float(r[0])] + [float(x) for x in r[4:7]] + [float(x) for x in r[1:4]] for r in a]


def rows_of(fmt, topic, path):
    if fmt == "ulog":
        return ulog_rows(path, topic)
    if fmt == "dataflash":
        return dataflash_rows(path, topic)
    if fmt in ("csv", "euroc"):
        return text_rows(path, fmt == "euroc")
    if fmt == "npy":
        return npy_rows(path)
    sys.exit(f"unknown format {fmt}")


def key(row):
    return tuple(repr(v) for v in row)


def ranges(ix):
    out, start, prev = [], None, None
    for i in sorted(ix):
        if start is None:
            start = prev = i
        elif i == prev + 1:
            prev = i
        else:
            out.append(f"{start}-{prev}")
            start = prev = i
    if start is not None:
        out.append(f"{start}-{prev}")
    return ",".join(out) or "-"


def main():
    fmt, topic, clean_path = sys.argv[1:4]
    clean = rows_of(fmt, topic, clean_path)
    print(f"N {len(clean)}")
    index = {}
    for i, r in enumerate(clean):
        print(" ".join(repr(v) for v in r))
        index.setdefault(key(r), i)
    signal.signal(signal.SIGALRM, _timeout)
    for p in sys.argv[4:]:
        signal.alarm(TIMEOUT_S)
        try:
            got = rows_of(fmt, topic, p)
        except Exception as e:  # the reader gives up on the file: it recovers nothing
            print(f"E {type(e).__name__}")
            continue
        finally:
            signal.alarm(0)
        found, other = set(), 0
        for r in got:
            i = index.get(key(r))
            if i is None:
                other += 1
            else:
                found.add(i)
        print(f"R {ranges(found)} {other}")
    sys.stdout.flush()


main()
