#!/usr/bin/env bash
# hw6_direct_compare.sh — the full-size check of the point-lit hw6 cornell boxes (cornellbox_jaroslav_diffuse
# and _glossy, 512², BRDF materials): two independent clrt renders at the references' 100 spp against the
# course's EXRs, both box-downsampled 8×8; passes when relMSE(clrt, reference) ≤ 2 × relMSE(clrt seed 1,
# clrt seed 2; independent jitter, as the references) and every channel mean is within 1% of the reference's. It is the [hw6] test of
# tests/test_brdf.cpp at CLRT_HW6_SPP=100 (the suite runs it at 8 spp; a few minutes on 2 cores), plus the
# brdf_* PSNR test. Prints the numbers (relMSE, limit, per-channel mean ratios, PSNR).
# Usage: scripts/hw6_direct_compare.sh [SPP]   (default 100; needs build/clrt_tests and ../shared)
set -euo pipefail
cd "$(dirname "$0")/.."
spp=${1:-100}
export CLRT_TEST_DEVICE=${CLRT_TEST_DEVICE:-cpu} CLRT_CACHE_DIR=${CLRT_CACHE_DIR:-$PWD/build/kernel-cache}
CLRT_HW6_SPP=$spp build/clrt_tests '[hw6]' 2>&1 | grep -v '^\s*$' | grep -v '^\.\.\.\|^---\|~~~'
