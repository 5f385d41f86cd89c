# Shared by the scripts in this folder (sourced, not run): where cargo puts the binaries, a
# release build that says how long the first one takes, and running a step whose stderr goes
# to a log without hiding why it failed.

# The target directory cargo builds into ($CARGO_TARGET_DIR, a config file's build.target-dir
# or <repo>/target): asked of cargo itself, so the scripts run what they just built.
target_dir() {
  cargo metadata --format-version 1 --no-deps |
    /usr/bin/python3 -c 'import json, sys; print(json.load(sys.stdin)["target_directory"])'
}

# build_release PKG...: the optimised binaries of these packages, in "$(target_dir)/release".
build_release() {
  local args=() p
  for p in "$@"; do args+=(-p "$p"); done
  local dir; dir=$(target_dir)
  if [ ! -x "$dir/release/$1" ]; then
    echo "building the release binaries (${*}); the first build from a clean clone takes about 20 min on 2 cores…" >&2
  fi
  cargo build --release --quiet "${args[@]}"
}

# logged LOG CMD...: runs CMD with its stderr in LOG; when it fails, says which command failed
# and shows the end of LOG on the terminal, then exits with its status.
logged() {
  local log=$1; shift
  local rc=0
  "$@" 2>"$log" || rc=$?
  if [ "$rc" -ne 0 ]; then
    echo "${0##*/}: failed (exit $rc): $*" >&2
    tail -n 20 "$log" | sed 's/^/  | /' >&2
    exit "$rc"
  fi
}
