#!/usr/bin/env bash
# render_all.sh — renders every scene file (*.xml, *.json) under a scenes folder with a fixed seed and
# a small spp, one output folder per scene, then prints the md5sum of every EXR/PNG written. Used to
# show that a refactor changes no output byte: run it before and after, then --compare the two.
# Scenes are never edited; resolution is each camera's own (clrt has no resolution option).
# A scene that fails because a file it needs is missing (exit 2 naming a path that does not exist)
# is listed as skipped; any other failure is listed with its exit code and counts as a difference.
#
# Usage: scripts/render_all.sh [--clrt BIN] [--scenes DIR] [--out DIR] [--spp N] [--seed N]
#                              [--device SPEC] [--timeout S] [--compare BASELINE_DIR] [--rehash]
#                              [--pipeline fused|wavefront] (clrt render --pipeline; default: clrt's auto)
#   defaults: --clrt build/clrt --scenes ../shared/scenes --out build/render_all --spp 1 --seed 1
#             --device cpu --timeout 900
#   Writes OUT/<scene path with / -> __>/..., OUT/md5sums.txt (outputs; EXR sums leave out the
#   renderTime attribute, see below), OUT/status.txt (one line per
#   scene: exit code, or SKIPPED/FAILED with the error line). --compare diffs both files against
#   BASELINE_DIR's and exits 1 if they differ. --rehash: render nothing, recompute OUT/md5sums.txt.
set -uo pipefail
cd "$(dirname "$0")/.."
clrt=build/clrt scenes=../shared/scenes out=build/render_all spp=1 seed=1 device=cpu timeout=900 compare= rehash=
pipeline=()
while [ $# -gt 0 ]; do
  case "$1" in
    --clrt) clrt=$2; shift 2 ;;
    --scenes) scenes=$2; shift 2 ;;
    --out) out=$2; shift 2 ;;
    --spp) spp=$2; shift 2 ;;
    --seed) seed=$2; shift 2 ;;
    --device) device=$2; shift 2 ;;
    --timeout) timeout=$2; shift 2 ;;
    --compare) compare=$2; shift 2 ;;
    --rehash) rehash=1; shift ;;
    --pipeline) pipeline=(--pipeline "$2"); shift 2 ;;
    -h|--help) sed -n '2,18p' "$0"; exit 0 ;;
    *) echo "render_all.sh: unknown option $1" >&2; exit 1 ;;
  esac
done
[ -x "$clrt" ] || { echo "render_all.sh: $clrt is not built" >&2; exit 1; }
clrt=$(realpath "$clrt")
export CLRT_CACHE_DIR="${CLRT_CACHE_DIR:-$PWD/build/kernel-cache}"
mkdir -p "$out"
out=$(realpath "$out")
: > "$out/status.txt.new"
start=$(date +%s)
skipped=()
[ -n "$rehash" ] || while IFS= read -r scene; do
  rel=${scene#"$scenes"/}
  dir="$out/${rel//\//__}"
  rm -rf "$dir" && mkdir -p "$dir"
  t0=$(date +%s)
  timeout "$timeout" "$clrt" render "$scene" -o "$dir" --spp "$spp" --seed "$seed" --device "$device" \
    "${pipeline[@]}" > "$dir/.log" 2>&1
  rc=$?
  err=$(grep -m1 '^clrt: error:' "$dir/.log")
  status="rc=$rc"
  if [ $rc -eq 2 ]; then
    # A missing input file: the error names a path that does not exist.
    missing=$(echo "$err" | grep -oE "[^ :'\"]+\.(ply|png|jpg|jpeg|exr|hdr|tga|bmp|xml|json)" | while read -r f; do
      [ -e "$f" ] || [ -e "$(dirname "$scene")/$f" ] || echo "$f"; done | head -1)
    if [ -n "$missing" ]; then status="SKIPPED (missing $missing)"; skipped+=("$rel: $missing"); fi
  fi
  [ $rc -ne 0 ] && [ "${status#SKIPPED}" = "$status" ] && status="FAILED rc=$rc: $err"
  echo "$rel $status" >> "$out/status.txt.new"
  echo "$rel $status ($(( $(date +%s) - t0 )) s)" >&2
done < <(find "$scenes" -path '*/_reference_outputs' -prune -o \( -name '*.xml' -o -name '*.json' \) -print | sort)

[ -n "$rehash" ] && rm -f "$out/status.txt.new" || mv "$out/status.txt.new" "$out/status.txt"
grep -o 'SKIPPED (missing .*)' "$out/status.txt" > /dev/null && mapfile -t skipped < <(sed -n 's/^\([^ ]*\) SKIPPED (missing \(.*\))$/\1: \2/p' "$out/status.txt")
# PNG: md5 of the file. EXR: md5 of the file less its renderTime header attribute (a wall time, the
# one part of an output that differs between two runs) and less the chunk offset table (absolute
# offsets, which move with that attribute's length): every other header attribute and every
# compressed pixel chunk is hashed, so equal sums still mean equal pixels.
(cd "$out" && find . -type f \( -name '*.exr' -o -name '*.png' \) | sort | python3 -c '
import hashlib, struct, sys
LINES = {0: 1, 1: 1, 2: 1, 3: 16, 4: 32, 5: 16, 6: 32, 7: 32, 8: 256, 9: 256}
for path in sys.stdin.read().split("\n"):
    if not path: continue
    data = open(path, "rb").read()
    if not path.endswith(".exr"):
        print(hashlib.md5(data).hexdigest() + "  " + path); continue
    h = hashlib.md5(); pos = 8; h.update(data[:8]); ymin = ymax = 0; comp = 0
    while data[pos] != 0:
        name_end = data.index(b"\0", pos); type_end = data.index(b"\0", name_end + 1)
        name = data[pos:name_end]; size = struct.unpack_from("<i", data, type_end + 1)[0]
        value = data[type_end + 5:type_end + 5 + size]
        if name == b"dataWindow": _, ymin, _, ymax = struct.unpack_from("<4i", value)
        if name == b"compression": comp = value[0]
        if name != b"renderTime": h.update(data[pos:type_end + 5 + size])
        pos = type_end + 5 + size
    chunks = -(-(ymax - ymin + 1) // LINES[comp])
    h.update(data[pos + 1 + 8 * chunks:])
    print(h.hexdigest() + "  " + path + " (exr less renderTime)")
') > "$out/md5sums.txt"
cat "$out/md5sums.txt"
echo "render_all: $(wc -l < "$out/md5sums.txt") images, $(wc -l < "$out/status.txt") scenes, $(( $(date +%s) - start )) s; spp=$spp seed=$seed"
if [ ${#skipped[@]} -gt 0 ]; then
  echo "skipped (missing files):"
  printf '  %s\n' "${skipped[@]}"
fi
grep ' FAILED ' "$out/status.txt" | sed 's/^/failed: /'
if [ -n "$compare" ]; then
  if diff "$compare/md5sums.txt" "$out/md5sums.txt" && diff "$compare/status.txt" "$out/status.txt"; then
    echo "compare: identical to $compare ($(wc -l < "$out/md5sums.txt") images)"
  else
    echo "compare: DIFFERENT from $compare"
    exit 1
  fi
fi
