#!/usr/bin/env bash
# Runs every fuzz target of fuzz/ (cargo-fuzz, libFuzzer, nightly) for SECONDS_PER_TARGET
# (default 60) and fails on a crash (panic, abort), a timeout (one input > 10 s) or an input that
# needs more than 2 GB. Usage: scripts/fuzz.sh [SECONDS_PER_TARGET] [TARGET...]
#
# Corpora: fuzz/corpus/TARGET (git-ignored; filled by fuzz/seed.sh when absent) grows with what
# libFuzzer finds; fuzz/regressions/TARGET (committed) is read as extra seeds. A finding is
# written to fuzz/artifacts/TARGET/; minimise it (`cargo +nightly fuzz tmin TARGET FILE`), fix
# the reader, and keep it in fuzz/regressions/TARGET/ so `cargo test` replays it.
#
# Built without a sanitizer: the crate forbids unsafe code, and what is looked for (panics,
# endless loops, huge allocations) libFuzzer catches by itself at two to three times the speed.
# PARTSCENE_FUZZ_SEED=N fixes libFuzzer's seed (CI: 1, so a run can be repeated); 0 = random.
# PARTSCENE_FUZZ_BUILD_ONLY=1 builds the targets and runs none.
# PARTSCENE_FUZZ_SANITIZER=address builds with AddressSanitizer (for the unsafe code of
# dependencies). The fuzz build has its own target dir (PARTSCENE_FUZZ_TARGET_DIR) so it never
# waits on, or invalidates, the main build.
set -euo pipefail
cd "$(dirname "$0")/.."
seconds="${1:-60}"
shift || true
sanitizer="${PARTSCENE_FUZZ_SANITIZER:-none}"
target_dir="${PARTSCENE_FUZZ_TARGET_DIR:-/tmp/partscene-fuzz-target}"

if ! cargo +nightly fuzz --version >/dev/null 2>&1; then
  echo "fuzz: cargo-fuzz on the nightly toolchain is needed: rustup toolchain install nightly && cargo install cargo-fuzz --locked" >&2
  exit 1
fi
if [ "$#" -gt 0 ]; then
  targets=("$@")
else
  mapfile -t targets < <(cargo +nightly fuzz list)
fi
flags=(--sanitizer "$sanitizer" --target-dir "$target_dir")
# PARTSCENE_FUZZ_BUILD_ONLY=1: the targets built, nothing run (CI builds them in the background
# while it does other work; the run later finds the build done).
if [ -n "${PARTSCENE_FUZZ_BUILD_ONLY:-}" ]; then
  cargo +nightly fuzz build "${flags[@]}"
  exit 0
fi
if [ ! -d fuzz/corpus ]; then
  fuzz/seed.sh fuzz/corpus
fi

cargo +nightly fuzz build "${flags[@]}"

logs="$(mktemp -d /tmp/partscene-fuzz-logs.XXXXXX)"
# libFuzzer runs one input at a time on one core: targets run side by side, one lane per core
# (PARTSCENE_FUZZ_JOBS, default every core), so each still has a core of its own for its seconds.
jobs="${PARTSCENE_FUZZ_JOBS:-$(nproc)}"
fuzz_one() {
  local t="$1" status=0
  mkdir -p "fuzz/corpus/$t" "fuzz/artifacts/$t"
  local dirs=("fuzz/corpus/$t")
  if [ -d "fuzz/regressions/$t" ]; then dirs+=("fuzz/regressions/$t"); fi
  cargo +nightly fuzz run "${flags[@]}" "$t" "${dirs[@]}" -- \
    -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 -print_final_stats=1 -seed="${PARTSCENE_FUZZ_SEED:-0}" >"$logs/$t.log" 2>&1 || status=$?
  echo "$status" >"$logs/$t.status"
}
running=0
for t in "${targets[@]}"; do
  if [ "$running" -ge "$jobs" ]; then
    wait -n || true
    running=$((running - 1))
  fi
  echo "== fuzz $t for ${seconds} s"
  fuzz_one "$t" &
  running=$((running + 1))
done
wait || true

failed=()
summary=()
for t in "${targets[@]}"; do
  status="$(cat "$logs/$t.status" 2>/dev/null || echo '?')"
  execs="$(sed -n 's/^stat::number_of_executed_units: *//p' "$logs/$t.log" | tail -n 1)"
  summary+=("$(printf '%-14s %12s executions' "$t" "${execs:-?}")")
  if [ "$status" != 0 ]; then
    failed+=("$t")
    echo "fuzz: $t FAILED (exit $status); the last lines of its log ($logs/$t.log):" >&2
    tail -n 40 "$logs/$t.log" | cut -c1-300 >&2
  fi
done
echo "== fuzz summary (${seconds} s per target, ${jobs} at a time)"
printf '%s\n' "${summary[@]}"
if [ "${#failed[@]}" -gt 0 ]; then
  echo "fuzz: failing targets: ${failed[*]} (inputs in fuzz/artifacts/; logs in $logs)" >&2
  exit 1
fi
rm -rf "$logs"
