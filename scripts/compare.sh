#!/usr/bin/env bash
# The seed's comparison: for each preset (low, medium, high) simulate a static IMU bag, convert
# it (bag2mat), run both analysers on it, and tabulate what each found against the truth, in
# continuous time and in discrete time at the sample rate (compare.md), with plots.
#
# usage: scripts/compare.sh [--duration S] [--rate HZ] [--out DIR] [--seed N] [--check]
#   defaults: 14400 s (4 h), 200 Hz, out/compare, seed 1. --check fails on figures outside the
#   tolerances `sim compare` states for the data length (used by scripts/test.sh).
# env: BIN_DIR: use these binaries instead of building the release ones (in cargo's target dir).
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/lib.sh
duration=14400 rate=200 out=out/compare seed=1 check=()
while [ $# -gt 0 ]; do
  case "$1" in
    --duration) duration=$2; shift 2 ;;
    --rate) rate=$2; shift 2 ;;
    --out) out=$2; shift 2 ;;
    --seed) seed=$2; shift 2 ;;
    --check) check=(--check); shift ;;
    *) echo "compare.sh: unknown argument $1 (see the header of this script)" >&2; exit 2 ;;
  esac
done
if [ -z "${BIN_DIR:-}" ]; then
  build_release sim bag2mat allan_imu_utils allan_kalibr
  BIN_DIR="$(target_dir)/release"
fi
minutes=$(( (${duration%.*} + 59) / 60 + 1 ))
start=$(date +%s)
i=0
for preset in low medium high; do
  d="$out/$preset"
  # One seed per preset: medium and high have the same N/K ratio, so a shared seed would
  # give them the same relative errors.
  pseed=$((seed + i)); i=$((i + 1))
  rm -rf "$d"; mkdir -p "$d"
  echo "== $preset: sim bag ($duration s at $rate Hz)" >&2
  logged "$d/sim.log" "$BIN_DIR/sim" bag -o "$d/imu.bag" --preset "$preset" --duration "$duration" \
    --rate "$rate" --seed "$pseed" --start-time 1700000000 --quiet
  logged "$d/bag2mat.log" "$BIN_DIR/bag2mat" "$d/imu.bag" imu --quiet
  logged "$d/imu_utils.err" "$BIN_DIR/allan_imu_utils" "$d/imu.bag" --topic imu --name "$preset" \
    --max-time-min "$minutes" --data-save-path "$d/imu_utils" --quiet >"$d/imu_utils.txt"
  logged "$d/kalibr.err" "$BIN_DIR/allan_kalibr" "$d/imu.mat" --update-rate "$rate" --title "$preset" \
    -o "$d/kalibr" --quiet >"$d/kalibr.txt"
  rm -f "$d/imu.bag" "$d/imu.mat" # 1 GB each at 4 h; the tables keep what matters
done
"$BIN_DIR/sim" compare --root "$out" --rate "$rate" --duration "$duration" "${check[@]}"
echo "compare.sh: done in $(( $(date +%s) - start )) s; tables in $out/compare.md" >&2
