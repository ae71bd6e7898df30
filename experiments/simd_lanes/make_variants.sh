#!/usr/bin/env bash
# make_variants.sh — kernel directories for the SIMD-lanes prototype (docs/studies/2026-12-05-simd-lanes-prototype.md).
# Each ROOT/VARIANT is a copy of cl_kernels/ and src/shared/ whose render_fused kernel is replaced by
# experiments/simd_lanes/simd_proto.cl, with ROOT/VARIANT/cl_kernels/simd_variant.h choosing the lane width
# (PW 4, 8, 16) and options (LANE_TRACE: clrt's scalar traversal one lane at a time; HYBRID N: packet
# traversal, a lane alone through a subtree that at most N lanes enter; ONE_PATH: one active lane per packet,
# the control; REAL_SAMPLER, LANE_SAMPLER, CAMERA_PACKETS: simd_proto.cl's header). Render with
# CLRT_KERNEL_DIR=ROOT/VARIANT/cl_kernels CLRT_CACHE_DIR=ROOT/VARIANT/cache and --pipeline fused (auto takes
# render_lanes, the kernel that grew out of this prototype, where it can).
# The prototype renders only what the hw6 diffuse box needs (see simd_proto.cl's header): other scenes
# render wrong images with it.
# usage: experiments/simd_lanes/make_variants.sh ROOT      then time_variants.py build/clrt ROOT SCENES
set -euo pipefail
cd "$(dirname "$0")/../.."
root=${1:?usage: make_variants.sh ROOT}
mk() {
    local d=$root/$1
    rm -rf "$d"; mkdir -p "$d/src"
    cp -r cl_kernels "$d/"; cp -r src/shared "$d/src/"
    cp experiments/simd_lanes/simd_proto.cl "$d/cl_kernels/"
    python3 - "$d/cl_kernels/fused.cl" <<'PY'
import sys
p = sys.argv[1]; s = open(p).read()
a = s.index('__kernel CLRT_KERNEL_VEC_HINT void render_fused'); b = s.index('#endif /* CLRT_FUSED_CL */')
open(p, 'w').write(s[:a] + '#include "simd_proto.cl"\n\n' + s[b:])
PY
    printf "$2" > "$d/cl_kernels/simd_variant.h"
}
mk w4 '#define PW 4\n'
mk w8 '#define PW 8\n'
mk w16 '#define PW 16\n'
mk w4one '#define PW 4\n#define ONE_PATH\n'
mk w4lane '#define PW 4\n#define LANE_TRACE\n'
mk w8lane '#define PW 8\n#define LANE_TRACE\n'
mk w4h1 '#define PW 4\n#define HYBRID 1\n'
mk w8h1 '#define PW 8\n#define HYBRID 1\n'
mk w8h2 '#define PW 8\n#define HYBRID 2\n'
mk w4real '#define PW 4\n#define REAL_SAMPLER\n'
mk w4lanereal '#define PW 4\n#define LANE_TRACE\n#define REAL_SAMPLER\n'
mk w8lanereal '#define PW 8\n#define LANE_TRACE\n#define REAL_SAMPLER\n'
mk w4lanels '#define PW 4\n#define LANE_TRACE\n#define REAL_SAMPLER\n#define LANE_SAMPLER\n'
mk w4ls '#define PW 4\n#define REAL_SAMPLER\n#define LANE_SAMPLER\n'
mk w8lanels '#define PW 8\n#define LANE_TRACE\n#define REAL_SAMPLER\n#define LANE_SAMPLER\n'
mk w4lanelscp '#define PW 4\n#define LANE_TRACE\n#define REAL_SAMPLER\n#define LANE_SAMPLER\n#define CAMERA_PACKETS\n'
mk w8lanelscp '#define PW 8\n#define LANE_TRACE\n#define REAL_SAMPLER\n#define LANE_SAMPLER\n#define CAMERA_PACKETS\n'
echo "variants in $root: w4 w8 w16 w4one w4lane w8lane w4h1 w8h1 w8h2 w4real w4lanereal w8lanereal w4lanels w4ls w8lanels w4lanelscp w8lanelscp"
