#!/usr/bin/env bash
# Sets up (scripts/setup.sh --test), runs the whole Catch2 test suite on the PoCL CPU device, then the
# preview's browser test (scripts/preview_browser_test.py; skip with CLRT_NO_BROWSER_TEST=1), then the
# OpenCL-implementation checks (scripts/test_implementations.sh: the device tests on Intel's CPU
# runtime, the oclgrind suite, GPU-target compiles of every kernel variant), then the course check
# (tests/check_course_references.sh, the check's reference lookup, then scripts/check_course --reduced against
# tests/course_expected_failures.txt: every course scene with a
# reference in ../shared; skip with CLRT_NO_COURSE_CHECK=1), then the deterministic fuzz check of the
# scene/PLY/image readers (scripts/fuzz.sh --gate: the committed
# regressions and seeds replayed under ASan/UBSan, then a fixed number of fixed-seed libFuzzer runs;
# skip with CLRT_NO_FUZZ=1).
# Usage: bash scripts/test.sh [catch2 args...]
set -euo pipefail
cd "$(dirname "$0")/.."
# Wall time of each part, one line each at the end ("time: setup 212 s, ..."): the CI budget is 25 min.
times=(); t0=$SECONDS
lap() { times+=("$1 $((SECONDS - t0)) s"); t0=$SECONDS; }
report_times() { [ ${#times[@]} -gt 0 ] && (IFS=,; echo "time:${times[*]/#/ }"); }
trap report_times EXIT
bash scripts/setup.sh --test
lap setup
# Intel's OpenCL CPU runtime beside PoCL when scripts/setup_intel_ocl.sh installed it; "cpu" is PoCL.
[ -f build/opencl-env.sh ] && . build/opencl-env.sh
# Tests run on PoCL's CPU device; a private kernel-binary cache keeps reruns fast.
export CLRT_TEST_DEVICE="${CLRT_TEST_DEVICE:-cpu}"
export CLRT_CACHE_DIR="${CLRT_CACHE_DIR:-$PWD/build/kernel-cache}"
log=build/test-log.txt
# Test cases tagged [course] check what the course check below checks again (the same cameras, the same
# rule): when that check runs, the suite leaves them out ("~[.]": hidden tests stay hidden).
args=("$@")
if [ $# -eq 0 ] && [ -z "${CLRT_NO_COURSE_CHECK:-}" ] && [ -d ../shared/scenes ]; then args=("~[course]~[.]"); fi
# The suite runs in CLRT_TEST_SHARDS processes at once (default: the cores, at most 4; scripts/run_shards.sh),
# each given every n-th test case by name: a cold kernel cache makes much of the suite single-threaded compiles,
# which then overlap. With arguments (a tag, a name) it runs as one process.
shards=${CLRT_TEST_SHARDS:-$(nproc)}; [ "$shards" -gt 4 ] && shards=4
[ $# -eq 0 ] || shards=1
if [ "$shards" -le 1 ]; then
  set +e
  (cd build && ./clrt_tests "${args[@]}") 2>&1 | tee "$log"
  rc=${PIPESTATUS[0]}
  set -e
else
  set +e
  bash scripts/run_shards.sh "$shards" test "${args[@]}" 2>&1 | tee "$log"
  rc=${PIPESTATUS[0]}
  set -e
fi
# One plain summary line: "tests: N passed, N failed" (test cases, all shards).
read -r p f _ < <(bash scripts/catch2_summary.sh "$log")
[ "$rc" -eq 0 ] || [ "$f" -gt 0 ] || f=1
echo "tests: $p passed, $f failed"
lap catch2
[ "$rc" -eq 0 ] || exit "$rc"
# The live preview in a real browser (headless Chromium + Selenium; screenshots in build/preview-test/);
# skip with CLRT_NO_BROWSER_TEST=1.
if [ -z "${CLRT_NO_BROWSER_TEST:-}" ] && [ $# -eq 0 ]; then
  echo "preview browser test (scripts/preview_browser_test.py):"
  build/venv-preview/bin/python scripts/preview_browser_test.py > build/preview-browser-log.txt 2>&1 \
    || { cat build/preview-browser-log.txt; echo "preview browser test: failed"; exit 1; }
  tail -1 build/preview-browser-log.txt
  lap browser
fi
[ $# -eq 0 ] && { bash scripts/test_implementations.sh || exit 1; lap implementations; }
if [ -z "${CLRT_NO_COURSE_CHECK:-}" ] && [ $# -eq 0 ] && [ -d ../shared/scenes ]; then
  # Reduced spp/size for sampled scenes; a listed failure is reported, a new one fails the run.
  # The check's reference lookup for other packages (--references): ambiguity, --references-exclude.
  bash tests/check_course_references.sh > build/check-course-references-log.txt 2>&1 \
    || { cat build/check-course-references-log.txt; exit 1; }
  tail -1 build/check-course-references-log.txt
  echo "course check (scripts/check_course --reduced --expected tests/course_expected_failures.txt):"
  bash scripts/check_course --reduced --expected tests/course_expected_failures.txt > build/course-check-log.txt 2>&1 \
    || { cat build/course-check-log.txt; echo "course check: a camera failed that tests/course_expected_failures.txt does not list"; exit 1; }
  grep -E "^check_course:" build/course-check-log.txt
  lap course
fi
if [ -z "${CLRT_NO_FUZZ:-}" ] && [ $# -eq 0 ]; then
  command -v clang++ >/dev/null || { [ "$(id -u)" -eq 0 ] && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq clang >/dev/null; }
  echo "fuzz gate (fuzz/regressions + fuzz/corpus replayed, then a fixed number of -seed=1 runs per target):"
  # The same inputs on every machine and every run; time-limited exploration: bash scripts/fuzz.sh SECONDS.
  bash scripts/fuzz.sh --gate > build/fuzz-log.txt 2>&1 || { tail -40 build/fuzz-log.txt; echo "fuzz: the gate found a problem"; exit 1; }
  grep -E "^==|DONE" build/fuzz-log.txt
  lap fuzz
fi
