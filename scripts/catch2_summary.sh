#!/usr/bin/env bash
# catch2_summary.sh — "PASSED FAILED ASSERTIONS": the test cases passed and failed and the assertions, summed over
# the Catch2 summary lines ("All tests passed (N assertions in N test cases)", "test cases: N | N passed | N
# failed", "assertions: N | ...") of the logs given. A log with a failure line but no count counts one failure.
# Used by scripts/test.sh, scripts/run_shards.sh and scripts/test_implementations.sh.
# usage: scripts/catch2_summary.sh LOG...
p=0 f=0 a=0
while read -r line; do
  case "$line" in
    "All tests passed"*) p=$((p + $(echo "$line" | sed -n 's/.* in \([0-9]*\) test case.*/\1/p')))
                         a=$((a + $(echo "$line" | sed -n 's/.*(\([0-9]*\) assertion.*/\1/p'))) ;;
    "test cases:"*) p=$((p + $(echo "$line" | sed -n 's/.*| *\([0-9]*\) passed.*/\1/p' | grep . || echo 0)))
                    f=$((f + $(echo "$line" | sed -n 's/.*| *\([0-9]*\) failed.*/\1/p' | grep . || echo 1))) ;;
    "assertions:"*) a=$((a + $(echo "$line" | sed -n 's/assertions: *\([0-9]*\).*/\1/p' | grep . || echo 0))) ;;
  esac
done < <(cat "$@" 2>/dev/null | grep -E "^(All tests passed|test cases:|assertions:)")
echo "$p $f $a"
