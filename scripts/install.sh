#!/usr/bin/env bash
# Installs the four tools (sim, bag2mat, allan_kalibr, allan_imu_utils) into ~/.cargo/bin
# with `cargo install` (the workspace's root manifest is virtual: cargo installs one crate
# at a time). Needs Rust >= 1.89; the first build takes about 20 min on 2 cores.
set -euo pipefail
cd "$(dirname "$0")/.."
for c in sim bag2mat allan_kalibr allan_imu_utils; do
  cargo install --locked --path "crates/$c"
done
echo "installed: sim bag2mat allan_kalibr allan_imu_utils (in ${CARGO_HOME:-$HOME/.cargo}/bin; put it on PATH)" >&2
