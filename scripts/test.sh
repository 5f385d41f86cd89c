#!/usr/bin/env bash
# Runs every test of the workspace. Installs, when missing, the real tools the tests check our
# files with: Debian's python3-rosbag (rosbag info/check, python API), GNU Octave, scipy,
# numpy, OpenCV's python bindings (cv2.FileStorage) and PyYAML. Tests never skip for a
# missing tool: they fail.
set -euo pipefail
cd "$(dirname "$0")/.."

need=()
command -v rosbag >/dev/null 2>&1 || need+=(python3-rosbag)
command -v octave >/dev/null 2>&1 || need+=(octave)
for mod in scipy:python3-scipy numpy:python3-numpy cv2:python3-opencv yaml:python3-yaml sensor_msgs:python3-sensor-msgs; do
  /usr/bin/python3 -c "import ${mod%%:*}" >/dev/null 2>&1 || need+=("${mod##*:}")
done
if [ ${#need[@]} -gt 0 ]; then
  echo "installing test tools: ${need[*]}"
  SUDO=""; [ "$(id -u)" -ne 0 ] && SUDO="sudo"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq "${need[@]}" >/dev/null
fi

cargo test --workspace "$@"

# The seed's comparison, short enough for CI (30 min at 100 Hz, three presets), with the
# tolerances `sim compare --check` states for that length, on the binaries cargo test built.
target_dir=$(cargo metadata --format-version 1 --no-deps | /usr/bin/python3 -c 'import json, sys; print(json.load(sys.stdin)["target_directory"])')
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
BIN_DIR="$target_dir/debug" scripts/compare.sh --duration 1800 --rate 100 --out "$out" --check
