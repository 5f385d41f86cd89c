#!/usr/bin/env bash
# Runs every test of the workspace. Installs, when missing, the real tools the tests check our
# files with: Debian's python3-rosbag (rosbag info/check, python API), GNU Octave, scipy,
# numpy, OpenCV's python bindings (cv2.FileStorage), PyYAML, and g++ with cereal (Basalt's JSON
# library, libcereal-dev); and, in a virtual environment
# at target/py-venv, the independent ROS 2 implementations (rosbags, Foxglove's mcap and
# mcap-ros2-support), pyulog, pymavlink and pandas, pinned. Tests never skip for a missing tool: they fail.
set -euo pipefail
cd "$(dirname "$0")/.."

# Every `docs/…md §N` citation in the code names a section that exists (seconds, no build).
/usr/bin/python3 scripts/doc_citations.py

need=()
command -v rosbag >/dev/null 2>&1 || need+=(python3-rosbag)
command -v octave >/dev/null 2>&1 || need+=(octave)
/usr/bin/python3 -c "import ensurepip, venv" >/dev/null 2>&1 || need+=(python3-venv)
command -v g++ >/dev/null 2>&1 || need+=(g++)
[ -f /usr/include/cereal/archives/json.hpp ] || need+=(libcereal-dev)
for mod in scipy:python3-scipy numpy:python3-numpy cv2:python3-opencv yaml:python3-yaml sensor_msgs:python3-sensor-msgs; do
  /usr/bin/python3 -c "import ${mod%%:*}" >/dev/null 2>&1 || need+=("${mod##*:}")
done
if [ ${#need[@]} -gt 0 ]; then
  echo "installing test tools: ${need[*]}"
  SUDO=""; [ "$(id -u)" -ne 0 ] && SUDO="sudo"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq "${need[@]}" >/dev/null
fi

# The independent readers the cross-checks run, pinned (bag2mat::test_tools finds them
# here): the ROS 2 implementations; for the logs from outside ROS pyulog (ULog, also its
# writer), pymavlink's DFReader (DataFlash) and pandas/numpy (CSV layouts); allantools (the
# IEEE 952 curve against its oadev); GTSAM's Python bindings (the GTSAM file read back through
# PreintegrationCombinedParams' setters and getters).
venv=target/py-venv
pins=(rosbags==0.11.9 mcap==1.6.0 mcap-ros2-support==0.6.0 pyulog==1.3.0 pymavlink==2.4.50 pandas==3.1.1 numpy==2.4.6 allantools==2024.6 gtsam==4.3.0)
if ! "$venv/bin/python" -c "import rosbags, mcap, mcap_ros2, pyulog, pymavlink, pandas, numpy, allantools, gtsam" >/dev/null 2>&1 \
   || [ "$("$venv/bin/python" -m pip freeze 2>/dev/null | grep -icxF "$(printf '%s\n' "${pins[@]}")")" != ${#pins[@]} ]; then
  echo "installing ${pins[*]} into $venv"
  /usr/bin/python3 -m venv "$venv"
  "$venv/bin/python" -m pip install -q "${pins[@]}"
fi

# House rules (ARCHITECTURE.md): formatted, clippy-clean with every lint an error (the
# workspace's [workspace.lints] included: documented public items, SAFETY comments on unsafe
# blocks), docs that build without a warning (broken and private links), no module cycles.
cargo fmt --all -- --check
cargo clippy --workspace --all-targets -- -D warnings
RUSTDOCFLAGS="-D warnings" cargo doc --workspace --no-deps --quiet
/usr/bin/python3 scripts/module_cycles.py

cargo test --workspace "$@"

# Issue 10's accuracy studies of the IEEE 952 estimator (ignored by a plain `cargo test`;
# about a minute on two cores in the optimised test build just made): every sim profile ×
# 3 seeds, 4 h at 200 Hz, and the band-limited BMI088-like gyro and accelerometer (3.2 kHz
# → 400 Hz through low-pass corners 0.05–0.45 of the output rate, one of them via a .mat).
# Issue 17's line study (a line from 0.002 to 0.45 of the rate, 3× and 10× the floor, 3 seeds)
# runs beside them, issue 40's coverage study (126 axes of known truth: how often each
# interval, bound and band holds it; about a minute), `allan_kalibr plan` against the
# analysis' advice on four simulated sensors × 5 seeds (issue 43), and issue 42's coverage
# count of the operating-noise interval (80 seeded hand-held records with a reference,
# through the allan_kalibr binary: 249 s measured on two cores shared with other builds).
# --nocapture: each study's counts (coverage numerators/denominators) go into the CI log.
cargo test -p allan_kalibr --test main -- --ignored --exact --nocapture \
  studies::profiles::profiles_study studies::bandlimited::bandlimited_study \
  studies::lines::lines_study studies::coverage::coverage_study \
  studies::plan::plan_study studies::operating::operating_interval_coverage_study

# The warm-up detector's power study (issue 41): detections of drifts of 6–14 σ of the
# detection window's mean, time constants of one window to an eighth of the record, and false
# alarms on drift-free white noise and random walk, from 10 min to 24 h (a few minutes).
cargo test -p bag2mat --test main -- --ignored --exact warmup_power::warmup_power_study

# Issues 12, 19 and 45's seeded corruption campaign (300 variants per input format — ROS 1,
# MCAP with its summary and cut short, sqlite3 bare and in its bag directory, metadata.yaml
# edits, files written by rosbags and Foxglove's writer, and the logs from outside ROS: ULog
# with and without sync markers, DataFlash IMU and batch samples, CSV, EuRoC, npy — through
# the real bag2mat binary, each under an address-space limit and a timeout; rows compared by
# value with the generator's, and for the logs with pyulog's, DFReader's, pandas' or numpy's
# read of the same variant); its last line gives the counts per format, and any panic, hang,
# memory blow-up, silent, under-counted or (MCAP, logs) false loss, a refusal of a log the
# independent reader reads, or an independent reader recovering more than bag2mat fails it.
cargo build -q -p bag2mat --bin bag2mat --example fuzz_campaign
"$(cargo metadata --format-version 1 --no-deps | /usr/bin/python3 -c 'import json, sys; print(json.load(sys.stdin)["target_directory"])')/debug/examples/fuzz_campaign"

# The seed's comparison, short enough for CI (30 min at 100 Hz, three presets), with the
# tolerances `sim compare --check` states for that length, on the binaries cargo test built.
target_dir=$(cargo metadata --format-version 1 --no-deps | /usr/bin/python3 -c 'import json, sys; print(json.load(sys.stdin)["target_directory"])')
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
BIN_DIR="$target_dir/debug" scripts/compare.sh --duration 1800 --rate 100 --out "$out" --check

# The launch_equivalents scripts as a user runs them once scripts/install.sh has put the
# binaries on PATH (here: the ones cargo test built), each output where the script says.
le="$out/launch_equivalents"
mkdir -p "$le"
PATH="$target_dir/debug:$PATH" launch_equivalents/simulate.sh "$le/imu.bag" --duration 120 --rate 100 --seed 3 --quiet
PATH="$target_dir/debug:$PATH" launch_equivalents/kalibr_convert.sh "$le/imu.bag" > /dev/null 2>&1
PATH="$target_dir/debug:$PATH" launch_equivalents/kalibr_analyse.sh "$le/imu.mat" -q > /dev/null
PATH="$target_dir/debug:$PATH" launch_equivalents/imu_utils.sh "$le/imu.bag" "$le/iu" -q > /dev/null 2>&1
PATH="$target_dir/debug:$PATH" launch_equivalents/ros2_info.sh "$le/imu.bag" > /dev/null
for f in imu.mat imu_allan_kalibr/imu.yaml imu_allan_kalibr/kalibr_imu_ieee952.yaml iu/imu_imu_param.yaml; do
  [ -f "$le/$f" ] || { echo "launch_equivalents: $le/$f was not written" >&2; exit 1; }
done
echo "launch_equivalents: simulate, convert, analyse (both tools) and info ran" >&2
