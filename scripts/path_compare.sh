#!/usr/bin/env bash
# path_compare.sh — the issue-16 check of the hw6 path-tracing cameras at full size: every camera of
# cornellbox_jaroslav_path_diffuse.xml rendered twice (seeds 1 and 2) at the reference's 512² and spp,
# both linear EXRs and the reference reduced to 8×8 block means, then (scripts/exr_stats.py bias)
#   relMSE(a, ref), relMSE(a, b) and their ratio: ≤ 2 means no bias beyond the noise (at equal spp
#   relMSE(a, ref) ≈ v + v_ref + bias², relMSE(a, b) ≈ 2v, v_ref = v).
# Russian-roulette cameras: per-channel means (and medians) of the large regions (back wall, floor,
# left/right walls, ceiling, spheres; scripts/path_regions.py) and of the whole image, for clrt and the
# reference (the references are heavy-tailed and brighter: README).
# Usage: scripts/path_compare.sh [--spp N] [--size S] [--out DIR] [--device SPEC] [--clrt BIN]
#   (defaults: the scene's 100 spp, 512, build/path_compare, cpu). Needs build/venv with numpy, OpenEXR.
# A smaller --size keeps clrt's 8×8 blocks and reduces the reference to the same blocks (8·512/size).
set -euo pipefail
cd "$(dirname "$0")/.."
spp= size=512 out=build/path_compare device=cpu clrt=build/clrt
while [ $# -gt 0 ]; do
  case "$1" in
    --spp) spp=$2; shift 2 ;;
    --size) size=$2; shift 2 ;;
    --out) out=$2; shift 2 ;;
    --device) device=$2; shift 2 ;;
    --clrt) clrt=$2; shift 2 ;;
    *) echo "unknown option $1" >&2; exit 1 ;;
  esac
done
scene=../shared/scenes/hw6/cornellbox_jaroslav_path_diffuse.xml
refs=../shared/scenes/hw6/_reference_outputs
py=build/venv/bin/python
mkdir -p "$out/a" "$out/b"
opts=(--device "$device" --resolution "${size}x${size}")
[ -n "$spp" ] && opts+=(--spp "$spp")
"$clrt" render "$scene" -o "$out/a" --seed 1 "${opts[@]}" | grep '^stats:'
"$clrt" render "$scene" -o "$out/b" --seed 2 "${opts[@]}" | grep '^stats:'
for n in diffuse_next diffuse_next_importance diffuse diffuse_importance; do
  echo "$n: $($py scripts/exr_stats.py bias "$out/a/$n.exr" "$out/b/$n.exr" "$refs/$n.exr" --down 8 --down-ref $(( 8 * 512 / size )))"
done
for n in diffuse_next_russian diffuse_next_importance_russian diffuse_russian diffuse_importance_russian; do
  echo "$n: per-channel region means (scripts/path_regions.py), clrt then the course's reference"
  $py scripts/path_regions.py "$out/a/$n.exr" "$refs/$n.exr"
done
