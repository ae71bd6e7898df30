#!/usr/bin/env bash
# path_compare.sh — the issue-16 check of the hw6 path-tracing cameras at full size: every camera of
# cornellbox_jaroslav_path_diffuse.xml at the reference's 512² and spp, compared with the course's EXRs.
# Non-RR cameras (1 next, 3 next_importance, 5 diffuse, 7 diffuse_importance): rendered twice (seeds 1
# and 2, independent), both linear EXRs and the reference reduced to 8×8 block means, then
# (scripts/exr_stats.py bias) relMSE(a, ref), relMSE(a, b) and their ratio: ≤ 2 is the issue's rule
# (at equal spp relMSE(a, ref) ≈ v + v_ref + bias², relMSE(a, b) ≈ 2v, v_ref = v: ≈ 1 without bias).
# Cameras 5 and 7 have the same RendererParams (ImportanceSampling; the course file's slip, hw6
# README), and clrt's random numbers depend on (seed, pixel, sample, path, dimension) only, so their
# renders are bit-identical: camera 5's pair is rendered once and compared with both references.
# Russian-roulette cameras (2, 4, 6, 8): one render (seed 1) each; per-channel means of the large
# regions (scripts/path_regions.py --table) against clrt's own unbiased answer without roulette (a
# scene copy at MaxRecursionDepth 40, RussianRoulette removed, --d40-spp samples; NEE for 2 and 4,
# importance sampling for 6 and 8) and the course's RR and depth-3 references; the table goes to
# docs/path_rr_regions.txt when the size is 512 (else OUT/path_rr_regions.txt).
# Renders run one at a time (nice); with --reuse an EXR already in OUT is not rendered again.
# Usage: scripts/path_compare.sh [--spp N] [--size S] [--d40-spp N] [--out DIR] [--device SPEC]
#   [--clrt BIN] [--reuse]   (defaults: the scene's 100 spp, 512, 32, build/path_compare, cpu).
#   Needs build/venv with numpy, OpenEXR. A smaller --size keeps clrt's 8×8 blocks and reduces the
#   reference to the same blocks (8·512/size per block).
set -euo pipefail
cd "$(dirname "$0")/.."
spp= size=512 d40spp=32 out=build/path_compare device=cpu clrt=build/clrt reuse=0
while [ $# -gt 0 ]; do
  case "$1" in
    --spp) spp=$2; shift 2 ;;
    --size) size=$2; shift 2 ;;
    --d40-spp) d40spp=$2; shift 2 ;;
    --out) out=$2; shift 2 ;;
    --device) device=$2; shift 2 ;;
    --clrt) clrt=$2; shift 2 ;;
    --reuse) reuse=1; shift ;;
    *) echo "unknown option $1" >&2; exit 1 ;;
  esac
done
scene=../shared/scenes/hw6/cornellbox_jaroslav_path_diffuse.xml
refs=../shared/scenes/hw6/_reference_outputs
py=build/venv/bin/python
mkdir -p "$out/a" "$out/b" "$out/d40"
opts=(--device "$device" --resolution "${size}x${size}")
[ -n "$spp" ] && opts+=(--spp "$spp")

# render DIR SCENE CAMERA SEED NAME [extra options]: one camera, unless DIR/NAME.exr is there (--reuse)
render() {
  local dir=$1 sc=$2 cam=$3 seed=$4 name=$5; shift 5
  if [ "$reuse" = 1 ] && [ -f "$dir/$name.exr" ]; then echo "reuse $dir/$name.exr"; return; fi
  echo "camera $cam seed $seed -> $dir/$name.exr ($(date -u +%H:%M:%S))"
  nice "$clrt" render "$sc" -o "$dir" --camera "$cam" --seed "$seed" "$@" | grep '^stats:' | tr ' ' '\n' \
    | grep -E '^(render|spp)=' | tr '\n' ' '
  echo
}
render "$out/a" "$scene" 1 1 diffuse_next "${opts[@]}"
render "$out/b" "$scene" 1 2 diffuse_next "${opts[@]}"
render "$out/a" "$scene" 3 1 diffuse_next_importance "${opts[@]}"
render "$out/b" "$scene" 3 2 diffuse_next_importance "${opts[@]}"
render "$out/a" "$scene" 5 1 diffuse "${opts[@]}"
render "$out/b" "$scene" 5 2 diffuse "${opts[@]}"
for n in diffuse_next_russian:2 diffuse_next_importance_russian:4 diffuse_russian:6 diffuse_importance_russian:8; do
  render "$out/a" "$scene" "${n#*:}" 1 "${n%%:*}" "${opts[@]}"
done
# clrt's own answer without roulette: MaxRecursionDepth 40, RussianRoulette dropped from every camera
d40=$out/d40/path_diffuse_depth40.xml
sed -e 's|<MaxRecursionDepth>3</MaxRecursionDepth>|<MaxRecursionDepth>40</MaxRecursionDepth>|' \
    -e 's| RussianRoulette</RendererParams>|</RendererParams>|' \
    -e 's|<RendererParams>RussianRoulette</RendererParams>|<RendererParams>ImportanceSampling</RendererParams>|' \
    "$scene" > "$d40"
grep -q '<MaxRecursionDepth>40<' "$d40" && ! grep -q RussianRoulette "$d40" || { echo "depth-40 copy failed" >&2; exit 1; }
d40opts=(--device "$device" --resolution "${size}x${size}" --spp "$d40spp")
render "$out/d40" "$d40" 2 1 diffuse_next_russian "${d40opts[@]}"        # NEE, depth 40
render "$out/d40" "$d40" 8 1 diffuse_importance_russian "${d40opts[@]}"  # IS, depth 40

echo "date $(date -u '+%Y-%m-%d %H:%M UTC'), ${size}², spp ${spp:-100}, clrt $(git rev-parse --short HEAD)"
for n in diffuse_next diffuse_next_importance diffuse:diffuse diffuse_importance:diffuse; do
  ref=${n%%:*} run=${n#*:}
  echo "$ref: $($py scripts/exr_stats.py bias "$out/a/$run.exr" "$out/b/$run.exr" "$refs/$ref.exr" --down 8 \
    --down-ref $(( 8 * 512 / size )))"
  echo "  image means clrt $($py scripts/exr_stats.py mean "$out/a/$run.exr") | reference $($py scripts/exr_stats.py mean "$refs/$ref.exr")"
done
table=docs/path_rr_regions.txt
[ "$size" = 512 ] || table=$out/path_rr_regions.txt
{
  for n in diffuse_next_russian:diffuse_next_russian:diffuse_next diffuse_next_importance_russian:diffuse_next_russian:diffuse_next_importance \
           diffuse_russian:diffuse_importance_russian:diffuse diffuse_importance_russian:diffuse_importance_russian:diffuse_importance; do
    IFS=: read -r rr d40n d3 <<< "$n"
    $py scripts/path_regions.py --table "$rr" "$out/a/$rr.exr" "$out/d40/$d40n.exr" "$refs/$rr.exr" "$refs/$d3.exr"
  done
  echo "columns: clrt RR (${size}², ${spp:-100} spp, seed 1) | clrt without RR at depth 40 (${size}², $d40spp spp; NEE for the"
  echo "NEE cameras, importance sampling for the others) | course RR reference | course depth-3 reference | ratio course RR / clrt RR"
  echo "(scripts/path_compare.sh --size $size${spp:+ --spp $spp} --d40-spp $d40spp, $(date -u '+%Y-%m-%d'))"
} | tee "$table"
