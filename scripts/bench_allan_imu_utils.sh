#!/usr/bin/env bash
# Benchmark of allan_imu_utils (called by scripts/bench.sh): end-to-end wall time of the
# binary on a bag, and the time of the Allan step alone (θ + overlapping AVAR over all
# factors and six axes), reported by the binary's --timings.
#
# Usage: scripts/bench_allan_imu_utils.sh [BAG] [RUNS]
#   BAG   default: a 4 h 200 Hz uncompressed simulated bag (made once with `sim bag`,
#         kept in ${BENCH_DIR:-target/bench}/imu_4h_200hz.bag)
#   RUNS  default 5; the minimum and median of the runs are printed.
# The whole bag is used (--max-time-min 100000: the stop rule never fires). Targets on the
# 2-core machine for the 4 h bag: < 0.6 s end to end with --compat-only; the default run
# (with the IEEE 952 section) < 1.0 s, peak memory < 2x the sample columns (issue 10).
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/lib.sh
runs="${2:-5}"
target=$(target_dir)
build_release allan_imu_utils
bin="$target/release/allan_imu_utils"
bag="${1:-}"
if [ -z "$bag" ]; then
  dir="${BENCH_DIR:-$target/bench}"
  bag="$dir/imu_4h_200hz.bag"
  if [ ! -f "$bag" ]; then
    mkdir -p "$dir"
    cargo build --release -q -p sim
    "$target/release/sim" bag --output "$bag" --rate 200 --duration 14400 --start-time 1600000000 --compression none --quiet >/dev/null 2>&1
  fi
fi
out="$(mktemp -d)"
trap 'rm -rf "$out"' EXIT
cat "$bag" >/dev/null # warm the page cache, as the other tools' benchmarks do
echo "allan_imu_utils on $bag ($(du -h "$bag" | cut -f1)), $runs runs"
totals=(); allans=(); reads=(); fits=()
for _ in $(seq "$runs"); do
  start=$(date +%s.%N)
  "$bin" "$bag" --max-time-min 100000 --data-save-path "$out" --quiet --no-plots --compat-only --timings >/dev/null 2>"$out/stderr"
  end=$(date +%s.%N)
  totals+=("$(echo "$end - $start" | bc -l)")
  allans+=("$(awk '$1=="timing" && $2=="allan" {print $3}' "$out/stderr")")
  reads+=("$(awk '$1=="timing" && $2=="read_bag" {print $3}' "$out/stderr")")
  fits+=("$(awk '$1=="timing" && $2=="fit" {print $3}' "$out/stderr")")
done
stats() { printf '%s\n' "$@" | sort -g | awk '{a[NR]=$1} END {printf "min %.3f s  median %.3f s", a[1], a[int((NR+1)/2)]}'; }
echo "  --compat-only (what imu_utils does):"
echo "  end to end : $(stats "${totals[@]}")"
echo "  read bag   : $(stats "${reads[@]}")"
echo "  Allan step : $(stats "${allans[@]}")"
echo "  fits       : $(stats "${fits[@]}")"
grep -m1 "messages" "$out/stderr" || true

# The default run (issue 10: with the IEEE 952 section, its files and plots; target 1.0 s
# and peak memory within 2x the sample columns, N x 7 float64).
dtotals=(); ieees=(); rss=()
for _ in $(seq "$runs"); do
  /usr/bin/time -f "%e %M" -o "$out/time" \
    "$bin" "$bag" --max-time-min 100000 --data-save-path "$out" --quiet --timings >/dev/null 2>"$out/stderr"
  read -r wall kb <"$out/time"
  dtotals+=("$wall"); rss+=("$kb")
  ieees+=("$(awk '$1=="timing" && $2=="ieee952" {print $3}' "$out/stderr")")
done
n="$(grep -m1 -oE '[0-9]+ messages' "$out/stderr" | cut -d' ' -f1 || true)"
echo "  default (IEEE 952 section, files and plots):"
echo "  end to end : $(stats "${dtotals[@]}")"
echo "  IEEE 952   : $(stats "${ieees[@]}")"
peak="$(printf '%s\n' "${rss[@]}" | sort -g | tail -1)"
if [ -n "$n" ]; then
  echo "  peak RSS   : $((peak / 1024)) MiB = $(echo "$peak * 1024 / ($n * 56)" | bc -l | xargs printf '%.2f')x the samples ($((n * 56 / 1048576)) MiB as N x 7 float64)"
else
  echo "  peak RSS   : $((peak / 1024)) MiB"
fi
