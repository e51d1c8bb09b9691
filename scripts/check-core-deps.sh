#!/usr/bin/env bash
# The core (built with --no-default-features) must not depend on GUI or viewer crates.
# Like rerun's forbidden-dependency check: fail loudly, naming the crate and the path to it.
set -euo pipefail
forbidden='^(egui|eframe|egui-wgpu|egui_kittest|egui_plot|egui-winit|wgpu|wgpu-core|winit|rfd|rerun|re_[a-z_]+)$'
tree=$(cargo tree --no-default-features -e normal --prefix none --format '{p}' 2>/dev/null | awk '{print $1}' | sort -u)
bad=$(echo "$tree" | grep -E "$forbidden" || true)
if [ -n "$bad" ]; then
  echo "error: the core dependency tree contains GUI/viewer crates:" >&2
  echo "$bad" >&2
  for c in $bad; do cargo tree --no-default-features -e normal -i "$c" >&2 || true; done
  exit 1
fi
# No core module may import them either.
leaks=$(grep -rlE '^\s*(pub )?use (egui|eframe|egui_wgpu|egui_plot|egui_kittest|wgpu|winit|rfd|rerun|re_log_encoding)\b' src \
  | grep -vE '^src/(app|render|web\.rs|observe/rerun\.rs)' || true)
if [ -n "$leaks" ]; then
  echo "error: core modules import GUI/viewer crates:" >&2
  echo "$leaks" >&2
  exit 1
fi
# The browser front end depends on the app, never the other way (the app calls app::Platform).
back=$(grep -rnE '^[^/]*\bcrate::web\b' src/app || true)
if [ -n "$back" ]; then
  echo "error: src/app uses crate::web (the front end must implement app::Platform instead):" >&2
  echo "$back" >&2
  exit 1
fi
echo "core dependency check: ok ($(echo "$tree" | wc -l) crates, none forbidden)"
