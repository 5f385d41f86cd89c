#!/usr/bin/env bash
# Issue 20's reading benchmarks (never run by the tests). Usage: scripts/bench_logs.sh [WORKDIR]
#   * a 4 h, 200 Hz EuRoC/ASL data.csv (2,880,000 rows, ~410 MB) read through bag2mat's read
#     path (examples/read_log) vs pandas.read_csv (C engine; timed inside Python, without the
#     interpreter's start; pandas 3.1 uses both cores here, as bag2mat does: its CPU is about
#     twice its wall time, and pinned to one core it took 0.96 s instead of 0.46 s) and
#     `wc -l` (targets: >= 3x faster than pandas, within 5x of wc -l);
#   * a 4 h ULog (sensor_combined, 2 x sensor_gyro/sensor_accel at 200 Hz, vehicle_imu,
#     vehicle_status; ~800 MB) vs pyulog's ULog() (target: >= 20x faster).
# Wall seconds, best of 3 (pyulog: 1 run); CPU seconds (user + sys) beside them, and the load
# average before each line, since the 2-core machine is often shared: on a loaded machine the
# wall ratio says little and the CPU ratio is the one to read. Needs target/py-venv
# (scripts/test.sh installs pandas and pyulog).
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/lib.sh
root=$(pwd)
work=${1:-$(mktemp -d /tmp/imu-bench-logs.XXXXXX)}
mkdir -p "$work"
echo "work dir: $work"
cargo build --release --quiet -p bag2mat --examples
ex="$(target_dir)/release/examples"
py="$root/target/py-venv/bin/python"
[ -x "$py" ] || { echo "target/py-venv is missing: run scripts/test.sh first" >&2; exit 1; }
ratio() { /usr/bin/python3 -c "import sys; a, b = float(sys.argv[1]), float(sys.argv[2]); print('%.1f' % (a / b if b > 0 else float('inf')))" "$1" "$2"; }
# best of 3: "WALL CPU" of a command
best3() {
  local best="" cpu=""
  for _ in 1 2 3; do
    /usr/bin/time -f "%e %U %S" -o "$work/.time" "$@" >/dev/null 2>&1
    read -r w u s < "$work/.time"
    if [ -z "$best" ] || /usr/bin/python3 -c "import sys; sys.exit(0 if $w < $best else 1)"; then
      best=$w; cpu=$(/usr/bin/python3 -c "print(round($u + $s, 2))")
    fi
  done
  echo "$best $cpu"
}

echo
echo "== a 4 h, 200 Hz EuRoC/ASL CSV: bag2mat's read path vs pandas.read_csv vs wc -l"
"$ex/write_logs" euroc "$work/euroc" 14400 200
csv="$work/euroc/mav0/imu0/data.csv"
cat "$csv" > /dev/null # warm the page cache
read -r t_wc _ < <(best3 wc -l "$csv")
read -r t_ours c_ours < <(best3 "$ex/read_log" "$work/euroc")
read -r t_pd c_pd < <("$py" -c "
import sys, time, pandas as pd
best = None
for _ in range(3):
    t, c = time.perf_counter(), time.process_time()
    df = pd.read_csv(sys.argv[1], engine='c')
    w, u = time.perf_counter() - t, time.process_time() - c
    if best is None or w < best[0]:
        best = (w, u)
assert len(df) == 2880000, len(df)
print('%.3f %.2f' % best)" "$csv")
echo "load average: $(cut -d' ' -f1-3 /proc/loadavg)"
echo "$(( $(stat -c %s "$csv") / 1048576 )) MiB: wc -l ${t_wc} s; bag2mat ${t_ours} s (CPU ${c_ours} s); pandas.read_csv ${t_pd} s (CPU ${c_pd} s)"
echo "pandas/bag2mat: $(ratio "$t_pd" "$t_ours")x [target >= 3x] (CPU $(ratio "$c_pd" "$c_ours")x); bag2mat/wc -l: $(ratio "$t_ours" "$t_wc")x [target <= 5x]"

echo
echo "== a 4 h ULog: bag2mat's read path vs pyulog"
"$ex/write_logs" ulog "$work/flight.ulg" 14400 200
cat "$work/flight.ulg" > /dev/null
read -r t_ul c_ul < <(best3 "$ex/read_log" "$work/flight.ulg")
read -r t_py c_py < <("$py" -c "
import sys, time
from pyulog import ULog
t, c = time.perf_counter(), time.process_time()
ULog(sys.argv[1])
print('%.3f %.2f' % (time.perf_counter() - t, time.process_time() - c))" "$work/flight.ulg")
echo "load average: $(cut -d' ' -f1-3 /proc/loadavg)"
echo "$(( $(stat -c %s "$work/flight.ulg") / 1048576 )) MiB: bag2mat ${t_ul} s (CPU ${c_ul} s); pyulog ${t_py} s (CPU ${c_py} s)"
echo "pyulog/bag2mat: $(ratio "$t_py" "$t_ul")x [target >= 20x] (CPU $(ratio "$c_py" "$c_ul")x)"
