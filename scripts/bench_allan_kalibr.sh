#!/usr/bin/env bash
# Benchmark of allan_kalibr (issues 3, 10): time the compat (prefix-sum) and --bit-exact runs on
# INPUT (.bag or .mat), then allantools' adev (pip, in a venv made here) on the same samples
# and the same cluster sizes m, and print the ratio. Peak memory is reported against the
# size of the samples; then the default run with the IEEE 952 section (issue 10: 1.0 s, 2x the
# samples). No pass/fail: figures only.
#
# usage: scripts/bench_allan_kalibr.sh INPUT [--topic imu] [--update-rate HZ] [--no-bit-exact]
# env:   BENCH_VENV (default $CARGO_TARGET_DIR/bench-venv),
#        BENCH_RUNS (default 3: best of N for the default path)
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
INPUT="${1:?usage: $0 INPUT(.bag|.mat) [--topic T] [--update-rate HZ] [--no-bit-exact]}"
shift
TOPIC=imu
RATE=""
BIT_EXACT=1
while [[ $# -gt 0 ]]; do
  case "$1" in
    --topic) TOPIC="$2"; shift 2 ;;
    --update-rate) RATE="$2"; shift 2 ;;
    --no-bit-exact) BIT_EXACT=0; shift ;;
    *) echo "unknown argument: $1" >&2; exit 2 ;;
  esac
done
[[ -f "$INPUT" ]] || { echo "no such file: $INPUT" >&2; exit 2; }
TARGET=$(cd "$ROOT" && . scripts/lib.sh && target_dir)
VENV="${BENCH_VENV:-$TARGET/bench-venv}"
RUNS="${BENCH_RUNS:-3}"
PY=/usr/bin/python3 # Debian python: numpy/scipy come from the system (--system-site-packages)

echo "== building (release)"
(cd "$ROOT" && . scripts/lib.sh && build_release allan_kalibr bag2mat)
AK="$TARGET/release/allan_kalibr"
B2M="$TARGET/release/bag2mat"

if [[ ! -x "$VENV/bin/python" ]] || ! "$VENV/bin/python" -c "import allantools" 2>/dev/null; then
  echo "== making venv $VENV with allantools"
  "$PY" -m venv --system-site-packages "$VENV"
  "$VENV/bin/pip" install -q "allantools==2024.6"
fi

WORK="$(mktemp -d)"
trap 'rm -rf "$WORK"' EXIT
RATE_ARGS=()
[[ -n "$RATE" ]] && RATE_ARGS=(--update-rate "$RATE")
CPUS="$(nproc)"
echo "== input $INPUT ($(du -h "$INPUT" | cut -f1)), $CPUS CPUs"

# Runs allan_kalibr once; prints "<wall s> <maxrss KB> <load s> <allan+fit s> <outputs s>".
run_ak() {
  local out="$1"; shift
  /usr/bin/time -f "%e %M" -o "$WORK/time.txt" \
    "$AK" "$INPUT" --topic "$TOPIC" "${RATE_ARGS[@]}" -q --timings --compat-only -o "$out" "$@" \
    >"$WORK/stdout.txt" 2>"$WORK/stderr.txt"
  local t; t="$(grep '^timings:' "$WORK/stderr.txt" | sed -E 's/timings: load ([0-9.]+) s, allan\+fit ([0-9.]+) s, ieee952 ([0-9.]+) s, outputs ([0-9.]+) s, checks ([0-9.]+) s/\1 \2 \4/')"
  echo "$(cat "$WORK/time.txt") $t"
}

echo "== allan_kalibr (default: prefix sums), best of $RUNS"
best=""
for _ in $(seq "$RUNS"); do
  r="$(run_ak "$WORK/out")"
  echo "   wall/maxrss/load/allan+fit/outputs: $r"
  a="$(echo "$r" | cut -d' ' -f4)"
  if [[ -z "$best" ]] || awk -v a="$a" -v b="$(echo "$best" | cut -d' ' -f4)" 'BEGIN{exit !(a<b)}'; then best="$r"; fi
done
read -r AK_WALL AK_RSS AK_LOAD AK_ALLAN AK_OUT <<<"$best"
echo "== allan_kalibr (default) on one core (RAYON_NUM_THREADS=1), best of $RUNS: the same work as single-threaded allantools"
best1=""
for _ in $(seq "$RUNS"); do
  r="$(RAYON_NUM_THREADS=1 run_ak "$WORK/out1")"
  a="$(echo "$r" | cut -d' ' -f4)"
  if [[ -z "$best1" ]] || awk -v a="$a" -v b="$(echo "$best1" | cut -d' ' -f4)" 'BEGIN{exit !(a<b)}'; then best1="$r"; fi
done
echo "   wall/maxrss/load/allan+fit/outputs: $best1"
AK1_ALLAN="$(echo "$best1" | cut -d' ' -f4)"
grep -E '^(accelerometer|gyroscope)_' "$WORK/stdout.txt" | sed 's/^/   /'
if [[ "$BIT_EXACT" == 1 ]]; then
  echo "== allan_kalibr --bit-exact (recursion, once per distinct m, parallel over axes and m)"
  r="$(run_ak "$WORK/out_bitexact" --bit-exact)"
  echo "   wall/maxrss/load/allan+fit/outputs: $r"
  read -r BE_WALL BE_RSS BE_LOAD BE_ALLAN BE_OUT <<<"$r"
fi

# The default run (issue 10: with the IEEE 952 section, its files and chart; target 1.0 s on
# two cores and peak memory within 2x the sample columns).
echo "== allan_kalibr default (with the IEEE 952 section), best of $RUNS"
bestd=""
for _ in $(seq "$RUNS"); do
  /usr/bin/time -f "%e %M" -o "$WORK/time.txt" \
    "$AK" "$INPUT" --topic "$TOPIC" "${RATE_ARGS[@]}" -q --timings -o "$WORK/outd" \
    >"$WORK/stdout.txt" 2>"$WORK/stderr.txt"
  r="$(cat "$WORK/time.txt") $(grep '^timings:' "$WORK/stderr.txt" | sed -E 's/timings: load ([0-9.]+) s, allan\+fit ([0-9.]+) s, ieee952 ([0-9.]+) s, outputs ([0-9.]+) s, checks ([0-9.]+) s/\1 \2 \3 \4/')"
  echo "   wall/maxrss/load/allan+fit/ieee952/outputs: $r"
  if [[ -z "$bestd" ]] || awk -v a="${r%% *}" -v b="${bestd%% *}" 'BEGIN{exit !(a<b)}'; then bestd="$r"; fi
done
read -r D_WALL D_RSS D_LOAD D_ALLAN D_IEEE D_OUT <<<"$bestd"

echo "== samples for allantools"
case "${INPUT,,}" in
  *.bag) "$B2M" "$INPUT" "$TOPIC" -o "$WORK/samples.npy" --format npy -q; SAMPLES="$WORK/samples.npy" ;;
  *.mat) SAMPLES="$INPUT" ;;
  *) echo "INPUT must be .bag or .mat" >&2; exit 2 ;;
esac

USED_RATE="$(grep -E '^update_rate:' "$WORK/out/imu.yaml" | awk '{print $2}')"
"$VENV/bin/python" - "$SAMPLES" "$USED_RATE" "$WORK/out/allan_curves.csv" "$AK_ALLAN" "$AK_WALL" "$AK_LOAD" "$AK_RSS" "$CPUS" "$AK1_ALLAN" \
  "$D_WALL" "$D_RSS" "$D_LOAD" "$D_ALLAN" "$D_IEEE" "$D_OUT" <<'PYEOF'
import sys, time
import numpy as np
import allantools

samples, rate, curves, ak_allan, ak_wall, ak_load, ak_rss, cpus, ak1_allan = sys.argv[1:10]
d_wall, d_rss, d_load, d_allan, d_ieee, d_out = sys.argv[10:16]
rate, ak_allan, ak_wall, ak_load = float(rate), float(ak_allan), float(ak_wall), float(ak_load)
ak1_allan = float(ak1_allan)
if samples.endswith(".npy"):
    d = np.load(samples)
else:
    import scipy.io
    d = scipy.io.loadmat(samples)["data_imu"]
d = np.ascontiguousarray(d, dtype=np.float64)
n = d.shape[0]
c = np.genfromtxt(curves, delimiter=",", names=True)
tau1 = c["tau1"]
m_all = np.rint(tau1 * rate).astype(np.int64)
m = np.unique(m_all[m_all > 0])
taus = m / rate
cols = [np.ascontiguousarray(d[:, k]) for k in range(1, 7)]
t_at = float("inf")
for _ in range(3):  # best of 3, like the allan_kalibr runs
    t0 = time.perf_counter()
    res = [allantools.adev(x, rate=rate, data_type="freq", taus=taus) for x in cols]
    t_at = min(t_at, time.perf_counter() - t0)
# Same estimator? Compare allantools' deviations with ours at the same m.
names = ["ax", "ay", "az", "wx", "wy", "wz"]
worst = 0.0
for k, (t_used, dev, _, _) in enumerate(res):
    ours = {}
    for mi, v in zip(m_all, c[names[k]]):
        if mi > 0:
            ours[int(mi)] = v
    mu = np.rint(np.asarray(t_used) * rate).astype(np.int64)
    o = np.array([ours[int(x)] for x in mu])
    worst = max(worst, float(np.nanmax(np.abs(dev - o) / o)))
sample_bytes = n * 7 * 8
print(f"== allantools {allantools.__version__} adev (non-overlapping), 6 axes x {len(m)} m values, N = {n}")
print(f"   allantools (best of 3): {t_at:.3f} s; max rel diff vs allan_kalibr curves {worst:.2e}")
print(f"   allan_kalibr allan+fit (same work + fits), {cpus} threads: {ak_allan:.3f} s  -> ratio {t_at / ak_allan:.1f}x")
print(f"   allan_kalibr allan+fit, 1 thread: {ak1_allan:.3f} s  -> ratio {t_at / ak1_allan:.1f}x")
print(f"   allan_kalibr whole run: {ak_wall:.2f} s wall, of which load {ak_load:.3f} s; compute beyond reading {ak_wall - ak_load:.3f} s")
print(f"   peak RSS {int(ak_rss) / 1024:.0f} MiB = {int(ak_rss) * 1024 / sample_bytes:.2f}x the samples ({sample_bytes / 2**20:.0f} MiB as N x 7 float64)")
print(f"== allan_kalibr default run (IEEE 952 section, files and chart): {d_wall} s wall "
      f"(load {d_load} s, allan+fit {d_allan} s, IEEE 952 {d_ieee} s, outputs {d_out} s), "
      f"peak RSS {int(d_rss) / 1024:.0f} MiB = {int(d_rss) * 1024 / sample_bytes:.2f}x the samples")
PYEOF
if [[ "$BIT_EXACT" == 1 ]]; then
  echo "   --bit-exact: allan+fit ${BE_ALLAN} s, wall ${BE_WALL} s, peak RSS $((BE_RSS / 1024)) MiB"
fi
