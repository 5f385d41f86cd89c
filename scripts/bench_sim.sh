#!/usr/bin/env bash
# Benchmark of `sim` (figures only, no pass/fail): writing the default 4 h, 200 Hz static bag
# (2,880,001 messages) with each compression, best of BENCH_RUNS, split into user time (RNG,
# normal sampling, message encoding) and system time (writing ~1.09 GB); then the 20 s
# trajectory, integration and spline commands.
#
# usage: scripts/bench_sim.sh [WORKDIR]
# env:   BENCH_RUNS (default 3)
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
WORK="${1:-$(mktemp -d /tmp/sim-bench.XXXXXX)}"
mkdir -p "$WORK"
TARGET=$(cd "$ROOT" && . scripts/lib.sh && target_dir)
RUNS="${BENCH_RUNS:-3}"
(cd "$ROOT" && . scripts/lib.sh && build_release sim)
SIM="$TARGET/release/sim"
echo "work dir: $WORK"

# "wall user sys peakKB" of a command
measure() { /usr/bin/time -f "%e %U %S %M" -o "$WORK/.time" "$@" >/dev/null 2>&1; cat "$WORK/.time"; }

echo "== sim bag, 4 h default (2,880,001 msgs), best of $RUNS"
printf "%-12s %8s %8s %8s %10s %12s\n" compression wall_s user_s sys_s peak_KB size_B
for c in none lz4 bz2; do
  best=""
  for _ in $(seq "$RUNS"); do
    read -r w u s kb < <(measure "$SIM" bag -o "$WORK/imu_$c.bag" --start-time 1700000000 --compression "$c" --quiet)
    if [ -z "$best" ] || /usr/bin/python3 -c "import sys; sys.exit(0 if $w < $best else 1)"; then best=$w; bu=$u; bs=$s; bkb=$kb; fi
  done
  printf "%-12s %8s %8s %8s %10s %12s\n" "$c" "$best" "$bu" "$bs" "$bkb" "$(stat -c %s "$WORK/imu_$c.bag")"
  [ "$c" = none ] || rm -f "$WORK/imu_$c.bag"
done

echo
echo "== sim bag, 4 h, 200 Hz: every noise term on (scripts/bench_all_terms.yaml: internal 1 kHz,"
echo "   Butterworth 50 Hz, decimation 5, flicker, Gauss-Markov, ramp, Q, LSB, warm-up) vs the"
echo "   default white + random-walk bag, uncompressed, best of $RUNS [target: <= 3x]"
printf "%-12s %8s %8s %8s %10s\n" model wall_s user_s sys_s peak_KB
for model in default all_terms; do
  best=""
  for _ in $(seq "$RUNS"); do
    rm -f "$WORK/imu_$model.bag"
    if [ "$model" = default ]; then
      read -r w u s kb < <(measure "$SIM" bag -o "$WORK/imu_$model.bag" --start-time 1700000000 --quiet)
    else
      read -r w u s kb < <(measure "$SIM" bag -o "$WORK/imu_$model.bag" --start-time 1700000000 --quiet --noise-spec "$ROOT/scripts/bench_all_terms.yaml")
    fi
    if [ -z "$best" ] || /usr/bin/python3 -c "import sys; sys.exit(0 if $w < $best else 1)"; then best=$w; bu=$u; bs=$s; bkb=$kb; fi
  done
  printf "%-12s %8s %8s %8s %10s\n" "$model" "$best" "$bu" "$bs" "$bkb"
  eval "best_$model=$best"
  rm -f "$WORK/imu_$model.bag" "$WORK/imu_$model.bag.truth.yaml" "$WORK/imu_$model.bag.truth.csv"
done
echo "ratio all_terms/default: $(/usr/bin/python3 -c "print('%.2f' % ($best_all_terms / $best_default))")x   [target <= 3x]"

echo
echo "== 20 s trajectory commands (wall user sys peakKB)"
echo "traj:             $(measure "$SIM" traj -o "$WORK/traj")"
echo "integrate:        $(measure "$SIM" integrate -o "$WORK/int")"
echo "spline self-check: $(measure "$SIM" spline --self-check)"
echo "spline from-model: $(measure "$SIM" spline --from-model -o "$WORK/spline" --start-time 1700000000 --quiet)"
