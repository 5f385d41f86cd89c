# Sourced by the scripts in this folder: `tool NAME ARGS…` runs one of the workspace's
# binaries — the installed one when it is on PATH (scripts/install.sh), else the release
# build in this clone (built on first use; the first build takes about 20 min on 2 cores).
here=$(cd "$(dirname "$0")" && pwd)
tool() {
  name=$1; shift
  if command -v "$name" >/dev/null 2>&1; then
    exec "$name" "$@"
  fi
  root=$(dirname "$here")
  dir=$(cd "$root" && cargo metadata --format-version 1 --no-deps |
    python3 -c 'import json, sys; print(json.load(sys.stdin)["target_directory"])') || exit 1
  if [ ! -x "$dir/release/$name" ]; then
    echo "$name is not installed (scripts/install.sh): building it in $root (the first build takes about 20 min on 2 cores)…" >&2
  fi
  (cd "$root" && cargo build --release --quiet -p "$name") || exit 1
  exec "$dir/release/$name" "$@"
}
