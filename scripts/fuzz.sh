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
if [ ! -d fuzz/corpus ]; then
  fuzz/seed.sh fuzz/corpus
fi

flags=(--sanitizer "$sanitizer" --target-dir "$target_dir")
cargo +nightly fuzz build "${flags[@]}"

logs="$(mktemp -d /tmp/partscene-fuzz-logs.XXXXXX)"
failed=()
summary=()
for t in "${targets[@]}"; do
  mkdir -p "fuzz/corpus/$t" "fuzz/artifacts/$t"
  echo "== fuzz $t for ${seconds} s"
  dirs=("fuzz/corpus/$t")
  if [ -d "fuzz/regressions/$t" ]; then dirs+=("fuzz/regressions/$t"); fi
  status=0
  cargo +nightly fuzz run "${flags[@]}" "$t" "${dirs[@]}" -- \
    -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 -print_final_stats=1 -seed="${PARTSCENE_FUZZ_SEED:-0}" >"$logs/$t.log" 2>&1 || status=$?
  execs="$(sed -n 's/^stat::number_of_executed_units: *//p' "$logs/$t.log" | tail -n 1)"
  summary+=("$(printf '%-14s %12s executions' "$t" "${execs:-?}")")
  if [ "$status" -ne 0 ]; then
    failed+=("$t")
    echo "fuzz: $t FAILED (exit $status); the last lines of its log ($logs/$t.log):" >&2
    tail -n 40 "$logs/$t.log" | cut -c1-300 >&2
  fi
done
echo "== fuzz summary (${seconds} s per target)"
printf '%s\n' "${summary[@]}"
if [ "${#failed[@]}" -gt 0 ]; then
  echo "fuzz: failing targets: ${failed[*]} (inputs in fuzz/artifacts/; logs in $logs)" >&2
  exit 1
fi
rm -rf "$logs"
