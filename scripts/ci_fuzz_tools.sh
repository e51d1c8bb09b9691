#!/usr/bin/env bash
# The nightly toolchain and cargo-fuzz 0.13.2 that scripts/fuzz.sh needs, installed where missing
# (CI: `.ci/run` runs it in the background at the start, then again before fuzzing, when it finds
# them there). Fails, saying so, when they can be neither found nor installed.
set -euo pipefail
if ! { rustup toolchain list | grep -q '^nightly' || rustup toolchain install nightly --profile minimal; } ||
   ! { cargo +nightly fuzz --version >/dev/null 2>&1 || cargo install cargo-fuzz --version 0.13.2 --locked; }; then
  echo "CI: fuzzing needs the nightly toolchain and cargo-fuzz 0.13.2, and neither is installed nor installable" >&2
  exit 1
fi
