#!/usr/bin/env bash
# Runs each argument (one shell command line) with at most PARALLEL_JOBS (default: every core)
# at a time, prints each one's output whole when all have ended, in the order given, and fails
# when any failed. For CI's independent, single-threaded steps (the gap suite's generators: one
# simulator process each), so that a 2-core machine runs two at once instead of one.
# Usage: scripts/parallel.sh 'command one' 'command two' ...
set -euo pipefail
jobs="${PARALLEL_JOBS:-$(nproc)}"
logs="$(mktemp -d /tmp/partscene-parallel.XXXXXX)"
trap 'rm -rf "$logs"' EXIT
i=0
for cmd in "$@"; do
  while [ "$(jobs -rp | wc -l)" -ge "$jobs" ]; do
    wait -n || true
  done
  (
    set +e
    start=$SECONDS
    bash -c "$cmd" >"$logs/$i.log" 2>&1
    echo "$? $((SECONDS - start))" >"$logs/$i.status"
  ) &
  i=$((i + 1))
done
wait
failed=0
k=0
for cmd in "$@"; do
  read -r rc seconds <"$logs/$k.status"
  echo "-- ($seconds s) $cmd"
  cat "$logs/$k.log"
  if [ "$rc" != 0 ]; then
    echo "parallel: failed with exit status $rc: $cmd" >&2
    failed=1
  fi
  k=$((k + 1))
done
exit "$failed"
