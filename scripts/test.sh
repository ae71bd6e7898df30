#!/usr/bin/env bash
# Sets up (scripts/setup.sh) and runs the whole test suite on the PoCL CPU device.
# Usage: bash scripts/test.sh [catch2 args...]
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
# Tests run on PoCL's CPU device; a private kernel-binary cache keeps reruns fast.
export CLRT_TEST_DEVICE="${CLRT_TEST_DEVICE:-cpu}"
export CLRT_CACHE_DIR="${CLRT_CACHE_DIR:-$PWD/build/kernel-cache}"
cd build
./clrt_tests "$@"
