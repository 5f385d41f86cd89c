#!/usr/bin/env bash
# The IEEE 952 section on the Allan curves of three real IMUs (testdata/real_curves: DJI A3,
# DJI N3, Bosch BMI160, written by imu_utils from 2-3.3 h static recordings): allan_kalibr
# --curves on each imu_utils data directory with the record length of its launch file, then
# one table per IMU (fitted range and verdict, chi2/dof, N, B, K with 95 % intervals, the
# IEEE 952 region readings) in DIR/real_curves.md; the charts are DIR/<IMU>/ieee952_allan.png.
#
# usage: scripts/real_curves.sh [--out DIR]   (default out/real_curves)
# env: BIN_DIR: use these binaries instead of building the release ones (in cargo's target dir).
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/lib.sh
out=out/real_curves
while [ $# -gt 0 ]; do
  case "$1" in
    --out) out=$2; shift 2 ;;
    *) echo "real_curves.sh: unknown argument $1 (see the header of this script)" >&2; exit 2 ;;
  esac
done
if [ -z "${BIN_DIR:-}" ]; then
  build_release allan_kalibr
  BIN_DIR="$(target_dir)/release"
fi
mkdir -p "$out"
args=()
# Record lengths from testdata/real_curves/README.md (the launch files' max_time_min).
for imu in A3:7200 N3:7200 BMI160:12000; do
  name=${imu%%:*} secs=${imu##*:}
  mkdir -p "$out/$name"
  "$BIN_DIR/allan_kalibr" --curves "testdata/real_curves/$name" --duration "$secs" \
    -o "$out/$name" -q > "$out/$name/allan_kalibr.txt"
  args+=("$name=$out/$name")
done
/usr/bin/python3 scripts/terms_table.py "${args[@]}" | tee "$out/real_curves.md"
