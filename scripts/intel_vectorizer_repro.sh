#!/usr/bin/env bash
# intel_vectorizer_repro.sh — reproduces issue 17: Intel's OpenCL CPU runtime (its implicit work-item
# vectoriser) miscompiles shade_hits unless the kernel carries the vec_type_hint(float4) workaround
# (cl_kernels/shade.cl). Copies the kernel sources to a temporary folder WITHOUT that attribute and
# renders classic/veachAjar (64x48, 2 spp, seed 7; the glass teapot) through CLRT_KERNEL_DIR, never
# from the kernel cache:
#   1. on PoCL (the reference);
#   2. on Intel's runtime, twice (vectorised: differs from PoCL, and from run to run);
#   3. on Intel's runtime with CL_CONFIG_USE_VECTORIZER=False (same source, not vectorised: agrees);
#   4. on Intel's runtime with the sources as they are (workaround in place: agrees).
# Prints one clrt-imgdiff line against PoCL per render. Expected: 2 shows relmse ~0.1 and ~1.5% of
# pixels, 3 and 4 relmse ~1e-8 (the last-bit differences of "Conformance" in the README).
# Then the standalone reproducer, tests/intel_repro/shade_hits_alone.cpp: the same program (dumped by
# CLRT_DUMP_PROGRAM), shade_hits alone on synthetic hits, no scene; its outputs on Intel against PoCL's
# (expected: ~1500 of 16384 child slots differ vectorised, none without the vectoriser or with the hint).
# Needs build/clrt, build/clrt-imgdiff, build/opencl-env.sh (scripts/setup_intel_ocl.sh) and ../shared.
# Usage: bash scripts/intel_vectorizer_repro.sh
set -euo pipefail
cd "$(dirname "$0")/.."
ROOT=$PWD
SCENE=$ROOT/../shared/scenes/classic/veachAjar.xml
[ -f build/opencl-env.sh ] || { echo "intel_vectorizer_repro: no build/opencl-env.sh (run scripts/setup_intel_ocl.sh)"; exit 1; }
. build/opencl-env.sh
build/clrt devices | grep -q "(platform: Intel(R) OpenCL)" || { echo "intel_vectorizer_repro: Intel's platform not listed"; exit 1; }
[ -f "$SCENE" ] || { echo "intel_vectorizer_repro: $SCENE missing"; exit 1; }
TMP=$(mktemp -d); trap 'rm -rf "$TMP"' EXIT
mkdir -p "$TMP/src" && cp -r cl_kernels "$TMP/" && cp -r src/shared "$TMP/src/"
sed -i 's/__kernel __attribute__((vec_type_hint(float4))) void shade_hits(/__kernel void shade_hits(/' "$TMP/cl_kernels/shade.cl"
grep -q "__kernel void shade_hits(" "$TMP/cl_kernels/shade.cl" || { echo "intel_vectorizer_repro: shade_hits declaration not found"; exit 1; }
export CLRT_NO_CACHE=1
render() {  # render NAME KERNEL_DIR DEVICE [env...]
  local name=$1 dir=$2 dev=$3; shift 3
  mkdir -p "$TMP/$name"
  env "$@" CLRT_KERNEL_DIR="$dir" build/clrt render "$SCENE" --resolution 64x48 --spp 2 --seed 7 \
    --device "$dev" -o "$TMP/$name" > "$TMP/$name.log" 2>&1 || { tail -3 "$TMP/$name.log"; exit 1; }
}
render pocl "$TMP/cl_kernels" platform:portable
render intel1 "$TMP/cl_kernels" platform:intel
render intel2 "$TMP/cl_kernels" platform:intel
render novec "$TMP/cl_kernels" platform:intel CL_CONFIG_USE_VECTORIZER=False
render fixed "$ROOT/cl_kernels" platform:intel
ref=$TMP/pocl/VeachAjar.png
for r in "intel1:Intel, vectorised (no workaround)" "intel2:Intel, vectorised, again" \
         "novec:Intel, CL_CONFIG_USE_VECTORIZER=False" "fixed:Intel, with vec_type_hint (cl_kernels as is)"; do
  printf '%-50s %s\n' "${r#*:}" "$(build/clrt-imgdiff "$ref" "$TMP/${r%%:*}/VeachAjar.png")"
done
printf '%-50s %s\n' "Intel run 1 vs run 2 (no workaround)" \
  "$(build/clrt-imgdiff "$TMP/intel1/VeachAjar.png" "$TMP/intel2/VeachAjar.png")"

# The standalone reproducer: shade_hits alone, on synthetic hits.
g++ -std=c++17 -O1 -Isrc -o "$TMP/shade_hits_alone" tests/intel_repro/shade_hits_alone.cpp -lOpenCL
dump() {  # dump NAME KERNEL_DIR: the veachAjar program's source and options
  mkdir -p "$TMP/dump-$1"
  CLRT_DUMP_PROGRAM="$TMP/dump-$1" CLRT_KERNEL_DIR="$2" build/clrt render "$SCENE" --resolution 8x8 --spp 1 \
    --device platform:portable -o "$TMP/pocl" > /dev/null 2>&1
  ls "$TMP/dump-$1"/*.cl > /dev/null
}
dump nohint "$TMP/cl_kernels"
dump hint "$ROOT/cl_kernels"
alone() {  # alone OUT PROGRAM PLATFORM [env...]
  local out=$1 prog=$2 plat=$3; shift 3
  local src; src=$(ls "$TMP/dump-$prog"/*.cl)
  env "$@" "$TMP/shade_hits_alone" "$src" "$(cat "${src%.cl}.options")" "$plat" "$TMP/$out.bin"
}
alone pocl nohint Portable
alone intel nohint Intel
alone novec nohint Intel CL_CONFIG_USE_VECTORIZER=False
alone hint hint Intel
for r in "intel:shade_hits alone, Intel vectorised (no workaround)" "novec:shade_hits alone, Intel without vectoriser" \
         "hint:shade_hits alone, Intel with vec_type_hint"; do
  printf '%-50s %s\n' "${r#*:}" "$("$TMP/shade_hits_alone" --compare "$TMP/pocl.bin" "$TMP/${r%%:*}.bin")"
done
