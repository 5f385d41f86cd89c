#!/usr/bin/env bash
# Every `sim` sensor profile against its truth: for each profile, simulate a static bag
# (`sim bag --sensor P`, which writes <bag>.truth.{yaml,csv} beside it), run allan_kalibr's
# default analysis on it (its ieee952_allan.{png,svg} overlays the truth curve on the
# generated Allan deviation, with the 95 % band, the fitted range and each term's line), and
# tabulate the fitted N, B, K per axis against the truth in the yaml (profiles.md). Where the
# record check warns of a warm-up, the bag is analysed again with the --skip-start it advises.
#
# usage: scripts/profiles.sh [--duration S] [--rate HZ] [--seed N] [--out DIR]
#   defaults: 14400 s (4 h), 200 Hz, seed 1, out/profiles. Each bag is deleted once analysed
#   (a 4 h bag is 1.1 GB); the plots, terms and truth files stay in DIR/<profile>/.
# env: BIN_DIR: use these binaries instead of building the release ones (in cargo's target dir).
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/lib.sh
duration=14400 rate=200 seed=1 out=out/profiles
while [ $# -gt 0 ]; do
  case "$1" in
    --duration) duration=$2; shift 2 ;;
    --rate) rate=$2; shift 2 ;;
    --seed) seed=$2; shift 2 ;;
    --out) out=$2; shift 2 ;;
    *) echo "profiles.sh: unknown argument $1 (see the header of this script)" >&2; exit 2 ;;
  esac
done
if [ -z "${BIN_DIR:-}" ]; then
  build_release sim allan_kalibr
  BIN_DIR="$(target_dir)/release"
fi
mkdir -p "$out"
profiles=$("$BIN_DIR/sim" sensors | awk '/^[a-z0-9]+ — /{print $1}')
for p in $profiles; do
  d="$out/$p"
  mkdir -p "$d"
  "$BIN_DIR/sim" bag --sensor "$p" --duration "$duration" --rate "$rate" --seed "$seed" \
    --start-time 1700000000 -o "$d/imu.bag" --quiet
  "$BIN_DIR/allan_kalibr" "$d/imu.bag" -o "$d" -q > "$d/allan_kalibr.txt" 2> "$d/allan_kalibr.err"
  # As a user would: when a warm-up is warned of (stderr), follow the largest --skip-start.
  skip=$( (grep -E '^warning: warm-up' "$d/allan_kalibr.err" | grep -oE 'with --skip-start [0-9.]+' || true) | awk '{print $3}' | sort -g | tail -1)
  if [ -n "$skip" ]; then
    "$BIN_DIR/allan_kalibr" "$d/imu.bag" -o "$d" -q --skip-start "$skip" > "$d/allan_kalibr.txt" 2> "$d/allan_kalibr.err"
    echo "$p: warm-up warning followed: analysed again with --skip-start $skip"
  fi
  rm -f "$d/imu.bag"
  echo "$p: $d/ieee952_allan.png"
done
args=()
for p in $profiles; do args+=("$p=$out/$p:$out/$p/imu.bag.truth.yaml"); done
/usr/bin/python3 scripts/terms_table.py "${args[@]}" | tee "$out/profiles.md"
