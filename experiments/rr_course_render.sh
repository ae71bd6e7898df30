#!/usr/bin/env bash
# rr_course_render.sh — renders the Russian-roulette cameras (2, 4, 6, 8) of hw6
# cornellbox_jaroslav_path_diffuse at the references' size and spp (512², 100) with --rr-rule R, seed S,
# into OUT/<rule>-s<seed>/ (study: docs/studies/2026-12-03-russian-roulette-references.md).
# Usage: experiments/rr_course_render.sh OUT RULE SEED [SIZE] [CAMERAS]   (from the repository root)
set -euo pipefail
out=$1 rule=$2 seed=$3 size=${4:-512} cams=${5:-"2 4 6 8"}
scene=${SCENE:-../shared/scenes/hw6/cornellbox_jaroslav_path_diffuse.xml}
[ -f "$scene" ] || scene=/work/shared/scenes/hw6/cornellbox_jaroslav_path_diffuse.xml
dir="$out/$rule-s$seed-$size"
mkdir -p "$dir"
export CLRT_CACHE_DIR=${CLRT_CACHE_DIR:-$PWD/build/kernel-cache}
for c in $cams; do
  build/clrt render "$scene" --camera "$c" --resolution "${size}x${size}" --rr-rule "$rule" --seed "$seed" \
    --device cpu -o "$dir" | grep -E '^stats:' | sed "s/^/camera $c: /"
done
