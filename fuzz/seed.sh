#!/usr/bin/env bash
# Fills fuzz/corpus/TARGET/ (git-ignored) with valid inputs: files partscene generates (`demo`,
# `scan-asset`, `reconstruct` of small scans, recordings from `gap::generate`) and the shared
# benchmark objects and recordings (read in place under ../shared/data, copied only into the
# corpus). Run from anywhere: fuzz/seed.sh [CORPUS_DIR]. Needs python3 (to cut scans down).
#
# Environment: PARTSCENE_BIN (a release `partscene`; default: built here), PARTSCENE_SHARED
# (default ../shared), PARTSCENE_FUZZ_SEED_MAX_BYTES (largest seed kept, default 128 KiB:
# libFuzzer's input size follows the largest seed, and small inputs mutate faster).
set -euo pipefail
cd "$(dirname "$0")/.."
corpus="${1:-fuzz/corpus}"
shared="${PARTSCENE_SHARED:-../shared}"
max_bytes="${PARTSCENE_FUZZ_SEED_MAX_BYTES:-131072}"
work="$(mktemp -d /tmp/partscene-fuzz-seed.XXXXXX)"
trap 'rm -rf "$work"' EXIT

if [ -n "${PARTSCENE_BIN:-}" ]; then
  bin="$PARTSCENE_BIN"
else
  cargo build --locked --release --quiet
  bin="$(cargo metadata --locked --format-version 1 --no-deps | python3 -c 'import json, sys; print(json.load(sys.stdin)["target_directory"])')/release/partscene"
fi

# add TARGET FILE...: copies each file of at most $max_bytes into the target's corpus, named by
# content (libFuzzer's convention), so re-running adds nothing twice.
add() {
  local target="$1" f sum
  shift
  mkdir -p "$corpus/$target"
  for f in "$@"; do
    [ -f "$f" ] || continue
    [ "$(stat -c %s "$f")" -le "$max_bytes" ] || continue
    sum="$(sha1sum "$f" | cut -d' ' -f1)"
    cp "$f" "$corpus/$target/$sum"
    chmod u+w "$corpus/$target/$sum"
  done
}

# small_scan IN.ply OUT.ply [ascii]: at most ~1500 vertices, every part kept (at least 24 points
# each), in the PLY's own layout or as ascii; the labels JSON beside IN is copied beside OUT.
small_scan() {
  python3 - "$@" <<'PY'
import shutil, struct, sys
from pathlib import Path
src, dst = Path(sys.argv[1]), Path(sys.argv[2])
ascii_out = len(sys.argv) > 3
data = src.read_bytes()
end = data.index(b"end_header\n") + len(b"end_header\n")
lines = data[:end].decode().splitlines()
fmt = next(l.split()[1] for l in lines if l.startswith("format"))
assert fmt == "binary_little_endian", fmt
codes = {"char": "b", "uchar": "B", "short": "h", "ushort": "H", "int": "i", "uint": "I", "float": "f", "double": "d",
         "int8": "b", "uint8": "B", "int16": "h", "uint16": "H", "int32": "i", "uint32": "I", "float32": "f", "float64": "d"}
props, count, in_vertex = [], 0, False
for l in lines:
    w = l.split()
    if w[0] == "element":
        in_vertex = w[1] == "vertex"
        if in_vertex:
            count = int(w[2])
    elif w[0] == "property" and in_vertex:
        props.append((w[1], w[2]))
row = struct.Struct("<" + "".join(codes[t] for t, _ in props))
part_at = [n for _, n in props].index("part")
by_part = {}
for i in range(count):
    v = row.unpack_from(data, end + i * row.size)
    by_part.setdefault(v[part_at], []).append(v)
budget = 1500
keep = []
for part, vs in sorted(by_part.items()):
    n = max(24, budget * len(vs) // count)
    step = max(1, len(vs) // n)
    keep.extend(vs[::step][:n])
header = [l for l in lines if not l.startswith(("element", "property", "end_header", "format"))]
header.insert(1, "format ascii 1.0" if ascii_out else "format binary_little_endian 1.0")
header.append(f"element vertex {len(keep)}")
header += [f"property {t} {n}" for t, n in props]
header.append("end_header")
out = ("\n".join(header) + "\n").encode()
if ascii_out:
    out += "".join(" ".join(f"{x:.6g}" if isinstance(x, float) else str(x) for x in v) + "\n" for v in keep).encode()
else:
    out += b"".join(row.pack(*v) for v in keep)
dst.write_bytes(out)
labels = src.with_suffix(".json")
if labels.exists():
    shutil.copy(labels, dst.with_suffix(".json"))
PY
}

# with_labels PLY: the scan_ply input (the PLY, then the labels after the separator line).
with_labels() {
  local ply="$1" out="$work/joined/$(basename "$1" .ply).scan"
  mkdir -p "$work/joined"
  { cat "$ply"; printf '\n#labels#\n'; cat "${ply%.ply}.json"; } >"$out"
  echo "$out"
}

echo "seeding $corpus from generated files and $shared/data"
# The shared folders searched, each only where present (a clone on its own has none: then only
# generated files seed, said once); `find` on a missing folder would fail its pipeline.
recordings_dir=()
objects_dir=()
if [ -d "$shared/data/recordings" ]; then recordings_dir=("$shared/data/recordings"); fi
if [ -d "$shared/data/objects" ]; then objects_dir=("$shared/data/objects"); fi
if [ "${#recordings_dir[@]}" -eq 0 ] && [ "${#objects_dir[@]}" -eq 0 ]; then
  echo "seed: $shared/data is absent: seeding from generated files only" >&2
fi
"$bin" demo --seed 0 --out "$work/demo0" >"$work/demo0.log" 2>&1
"$bin" demo --seed 3 --clean --out "$work/demo3" >"$work/demo3.log" 2>&1

# The shared objects, scanned virtually (the asset file chosen as bench::manifest does).
assets=()
for dir in "$shared"/data/objects/*/*/; do
  [ -d "$dir" ] || continue
  asset=""
  for f in "$dir"*_obj.urdf "$dir"urdf/*_obj.urdf "$dir"*_standalone.xml "$dir"urdf/*_standalone.xml; do
    if [ -f "$f" ]; then asset="$f"; break; fi
  done
  if [ -z "$asset" ]; then
    mapfile -t found < <(find "$dir" "$dir/urdf" -maxdepth 1 -type f \( -name '*.urdf' -o -name '*.xml' \) 2>/dev/null | sort -u)
    if [ "${#found[@]}" -eq 1 ]; then asset="${found[0]}"; fi
  fi
  [ -n "$asset" ] || continue
  assets+=("$asset")
  name="$(basename "$(dirname "$dir")")-$(basename "$dir")"
  "$bin" scan-asset "$asset" --out "$work/assets/$name.ply" >/dev/null 2>&1 || echo "seed: scan-asset $asset failed, skipped" >&2
done

# Small scans of everything scanned, reconstructed: small scene.json / URDF / MJCF / GLB files.
mkdir -p "$work/small"
for ply in "$work"/demo*/scan.ply "$work"/assets/*.ply; do
  [ -f "$ply" ] || continue
  name="$(basename "$(dirname "$ply")")-$(basename "$ply" .ply)"
  small_scan "$ply" "$work/small/$name.ply"
  "$bin" reconstruct "$work/small/$name.ply" --out "$work/rec/$name" >/dev/null 2>&1 || echo "seed: reconstruct $name failed, skipped" >&2
done
small_scan "$work/demo0/scan.ply" "$work/small/demo0-ascii.ply" ascii

for ply in "$work"/small/*.ply; do
  add scan_ply "$ply"
  [ -f "${ply%.ply}.json" ] && add scan_ply "$(with_labels "$ply")"
done

# Recordings: gap::generate on the small reconstructions' URDFs and the shared recordings' models
# (through the ignored test that writes them), and the first rows of the shared recordings.
urdfs="$(find "$work/rec" "${recordings_dir[@]}" -name '*.urdf' | sort | head -n 6 | paste -sd: -)"
PARTSCENE_FUZZ_SEED_URDFS="$urdfs" PARTSCENE_FUZZ_SEED_OUT="$work/gap" \
  cargo test --locked --quiet --test fuzz_regressions -- --ignored --exact write_generated_gap_seeds >/dev/null
add gap_recording "$work"/gap/*.csv
for csv in "$shared"/data/recordings/*/recording*.csv; do
  [ -f "$csv" ] || continue
  head -n 200 "$csv" >"$work/gap/head-$(basename "$(dirname "$csv")")-$(basename "$csv")"
done
add gap_recording "$work"/gap/head-*.csv

mapfile -t urdf_files < <(find "$work" "${recordings_dir[@]}" "${objects_dir[@]}" -name '*.urdf' | sort)
add gap_model "${urdf_files[@]}"
add asset_urdf "${urdf_files[@]}"
mapfile -t mjcf_files < <({ find "$work" -name '*.mjcf.xml'; [ "${#objects_dir[@]}" -eq 0 ] || find "${objects_dir[@]}" -name '*.xml'; } | sort)
add asset_mjcf "${mjcf_files[@]}"

for ext in obj stl glb msh; do
  mapfile -t meshes < <(find "$work" "${objects_dir[@]}" -iname "*.$ext" | sort)
  add "mesh_$ext" "${meshes[@]}"
done

mapfile -t scenes < <(find "$work" -name scene.json | sort)
add scene_json "${scenes[@]}"
mapfile -t truths < <(find "$work" \( -name gt.json -o -name '*.gt.json' \) | sort)
add gt_json "${truths[@]}"

# NumPy scans and MultiScan scenes: the test fixtures written to those formats (a MultiScan input
# is the face-annotated PLY, the labels separator, then the annotations JSON).
add scan_npz tests/fixtures/npz/*.npz
for dir in tests/fixtures/multiscan/*/; do
  name="$(basename "$dir")"
  { cat "$dir/$name.ply"; printf '\n#labels#\n'; cat "$dir/$name.annotations.json"; } >"$work/multiscan-$name"
done
add multiscan "$work"/multiscan-*

# Sessions: the pins the editor saves, on the parts of the object the session target assembles.
PARTSCENE_FUZZ_SEED_OUT="$work/sessions" \
  cargo test --locked --quiet --test fuzz_regressions -- --ignored --exact write_session_seeds >/dev/null
add session "$work"/sessions/*.json

for dir in "$corpus"/*/; do
  echo "  $(basename "$dir"): $(find "$dir" -type f | wc -l) seeds"
done
