#!/bin/sh
# env_sampling_compare.sh — renders a sphere on a ground plane under ../shared/envmaps/sunset.exr with
# each env strategy (uniform, cosine, importance, mis) at equal spp, and a high-spp MIS reference;
# prints each sampler's relMSE against the reference and writes docs/env_sampling_sunset.png (left to
# right: uniform, cosine, importance, mis, reference) and docs/env_sampling_sunset.txt.
# The work is the [envcompare] test case of clrt_tests (tests/test_lights.cpp), which fails unless
# importance and MIS have >= 10x lower relMSE than uniform.
# usage: scripts/env_sampling_compare.sh [BUILD_DIR] [SIZE] [SPP] [REF_SPP]   (defaults: build 128 16 1024)
set -eu
root=$(cd "$(dirname "$0")/.." && pwd)
build=${1:-$root/build}
mkdir -p "$root/docs"
CLRT_ENV_COMPARE_SIZE=${2:-128} CLRT_ENV_COMPARE_SPP=${3:-16} CLRT_ENV_COMPARE_REF_SPP=${4:-1024} \
CLRT_ENV_COMPARE_OUT="$root/docs" "$build/clrt_tests" "[envcompare]" -s 2>&1 | grep -E "relMSE|passed|failed|FAILED" || true
cat "$root/docs/env_sampling_sunset.txt"
