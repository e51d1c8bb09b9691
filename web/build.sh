#!/usr/bin/env bash
# Builds the browser editor into web/dist (index.html + partscene_web.js + partscene_web_bg.wasm).
# Needs the wasm32 target and the wasm-bindgen CLI of the version in Cargo.lock (installed here if
# missing). Serve web/dist with any static server, e.g. `python3 -m http.server -d web/dist 8080`.
set -euo pipefail
cd "$(dirname "$0")/.."
rustup target list --installed 2>/dev/null | grep -q wasm32-unknown-unknown || rustup target add wasm32-unknown-unknown
want=$(awk '/^name = "wasm-bindgen"$/ {getline; gsub(/"/, "", $3); print $3; exit}' Cargo.lock)
have=$(wasm-bindgen --version 2>/dev/null | awk '{print $2}' || true)
if [ "$have" != "$want" ]; then
  echo "installing wasm-bindgen-cli $want (had: ${have:-none})" >&2
  cargo install wasm-bindgen-cli --version "$want"
fi
cargo build --locked --release --target wasm32-unknown-unknown --no-default-features --features web --bin partscene-web
target_dir=$(cargo metadata --format-version 1 --no-deps | python3 -c 'import json,sys; print(json.load(sys.stdin)["target_directory"])')
rm -rf web/dist
mkdir -p web/dist
wasm-bindgen --target web --no-typescript --out-dir web/dist --out-name partscene_web \
  "$target_dir/wasm32-unknown-unknown/release/partscene-web.wasm"
cp web/index.html web/dist/
ls -la web/dist >&2
