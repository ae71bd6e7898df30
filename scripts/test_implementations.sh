#!/usr/bin/env bash
# The OpenCL-implementation part of scripts/test.sh (issue 17), after the main suite has passed on
# PoCL:
#   1. the device tests (Catch2 tags [cl] [lights] [tonemap] [render] [lanes], in CLRT_TEST_SHARDS processes
#      as the suite: scripts/run_shards.sh; intersection, light and
#      environment sampling, tone mapping against the host references, struct layout, determinism,
#      course references) on every other CPU implementation present: Intel's OpenCL CPU runtime when
#      scripts/setup_intel_ocl.sh installed it (build/opencl-env.sh); except the cases tagged
#      [one-implementation]: what they check does not depend on the implementation (XML and JSON parse to
#      the same scene) or a smaller case checks it there (the two-level BVH against flattening, the path
#      tracer's furnaces), and PoCL's run of the suite has checked them;
#   2. the oclgrind suite (scripts/oclgrind_suite.sh);
#   3. every kernel variant compiled for nvptx64 and amdgcn with clang (scripts/gpu_compile_check.sh).
# Prints one line per part; exits non-zero when a part fails. CLRT_NO_OCLGRIND=1 / CLRT_NO_GPU_COMPILE=1
# skip parts 2 / 3 (saying so).
# Usage: bash scripts/test_implementations.sh
set -uo pipefail
cd "$(dirname "$0")/.."
[ -f build/opencl-env.sh ] && . build/opencl-env.sh
export CLRT_CACHE_DIR="${CLRT_CACHE_DIR:-$PWD/build/kernel-cache}"
DEVICE_TAGS="[cl]~[one-implementation],[lights]~[one-implementation],[tonemap]~[one-implementation],[render]~[one-implementation],[lanes]"
# In as many processes as the suite (scripts/run_shards.sh): Intel's cold-cache compiles overlap (2 cores: 305 s
# against 415 s in one process, session 36).
shards=${CLRT_TEST_SHARDS:-$(nproc)}; [ "$shards" -gt 4 ] && shards=4
rc=0

# 1. Device tests on each CPU platform other than PoCL.
if [ -f build/opencl-env.sh ] && ! build/clrt devices | grep -q "(platform: Intel(R) OpenCL)"; then
  echo "implementations: FAIL: build/opencl-env.sh is set up but Intel's OpenCL platform is not listed:"
  build/clrt devices; rc=1
fi
platforms=$(build/clrt devices | sed -n 's/^\[[0-9]*\] *CPU .*(platform: \(.*\))  compute units.*/\1/p' | sort -u |
            grep -v "^Portable Computing Language$" || true)
while read -r plat; do
  [ -n "$plat" ] || continue
  name=test-$(echo "$plat" | tr -c 'A-Za-z0-9\n' '_')
  log=build/$name.txt
  t0=$SECONDS
  CLRT_TEST_DEVICE="platform:$plat" bash scripts/run_shards.sh "$shards" "$name" "$DEVICE_TAGS" > "$log" 2>&1
  r=$?
  read -r c f a < <(bash scripts/catch2_summary.sh "$log")  # the processes' summaries as one
  sum="All tests passed ($a assertions in $c test cases)"
  [ "$f" -eq 0 ] || sum="$f of $((c + f)) test cases failed ($a assertions)"
  [ $((c + f)) -gt 0 ] || sum="no summary"
  echo "implementations: device tests $DEVICE_TAGS on \"$plat\" in $shards processes: $sum (log $log, $((SECONDS - t0)) s)"
  if [ $r -ne 0 ]; then grep -B3 -A12 "FAILED:\|^catch2: the processes" "$log" | head -60; rc=1; fi
done <<< "$platforms"
[ -n "$platforms" ] || echo "implementations: no CPU OpenCL implementation besides PoCL (scripts/setup_intel_ocl.sh installs Intel's)"

# 2. oclgrind.
if [ -n "${CLRT_NO_OCLGRIND:-}" ]; then echo "implementations: oclgrind suite SKIPPED (CLRT_NO_OCLGRIND set)"
else t0=$SECONDS; bash scripts/oclgrind_suite.sh > build/oclgrind-log.txt 2>&1 || { tail -40 build/oclgrind-log.txt; rc=1; }
     echo "$(tail -2 build/oclgrind-log.txt | head -1) ($((SECONDS - t0)) s)"; fi

# 3. GPU-target compiles.
if [ -n "${CLRT_NO_GPU_COMPILE:-}" ]; then echo "implementations: GPU-target compile SKIPPED (CLRT_NO_GPU_COMPILE set)"
else t0=$SECONDS; bash scripts/gpu_compile_check.sh > build/gpu-compile-log.txt 2>&1 || { tail -30 build/gpu-compile-log.txt; rc=1; }
     echo "$(tail -2 build/gpu-compile-log.txt | head -1) ($((SECONDS - t0)) s)"; fi
exit $rc
