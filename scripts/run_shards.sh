#!/usr/bin/env bash
# run_shards.sh — the Catch2 test cases that SPEC selects (a clrt_tests test spec: tags, names, exclusions; none:
# all) in N processes at once, each given every N-th case by name: a cold kernel cache makes much of a run
# single-threaded kernel compiles, which then overlap. The environment (CLRT_TEST_DEVICE, CLRT_CACHE_DIR)
# passes on to every process. Writes the names to PREFIX-names.txt, each process's share to PREFIX-shard-I.txt and
# its log to PREFIX-log-I.txt (build/ relative), prints one line ("catch2: 333 test cases in 2 processes") and then
# the logs one after another, and exits non-zero when a process failed or the processes ran fewer cases than were
# listed (Catch2 2.x exits with the number of cases it lists; a name with a double quote cannot be passed this
# way, and the count check then fails). Used by scripts/test.sh and scripts/test_implementations.sh.
# usage: scripts/run_shards.sh N PREFIX [SPEC...]   (from the repository root, clrt_tests built in build/)
set -uo pipefail
cd "$(dirname "$0")/.."
n=$1 prefix=$2
shift 2
[ "$n" -ge 1 ] || n=1
# Names escaped as Catch2's test specs need (\ , [ ]).
{ (cd build && ./clrt_tests "$@" --list-test-names-only) || true; } | sed '/^$/d' |
  sed 's/\\/\\\\/g; s/,/\\,/g; s/\[/\\[/g; s/\]/\\]/g' > "build/$prefix-names.txt"
listed=$(wc -l < "build/$prefix-names.txt")
[ "$n" -le "$listed" ] || n=$((listed > 0 ? listed : 1))  # no process with an empty share (Catch2 would run all)
pids=()
for ((i = 0; i < n; i++)); do
  awk -v n="$n" -v i="$i" '(NR - 1) % n == i' "build/$prefix-names.txt" > "build/$prefix-shard-$i.txt"
  (cd build && ./clrt_tests -f "$prefix-shard-$i.txt") > "build/$prefix-log-$i.txt" 2>&1 &
  pids+=($!)
done
echo "catch2: $listed test cases in $n processes (logs build/$prefix-log-*.txt)"
rc=0
for ((i = 0; i < n; i++)); do wait "${pids[$i]}" || rc=1; done
logs=()
for ((i = 0; i < n; i++)); do cat "build/$prefix-log-$i.txt"; logs+=("build/$prefix-log-$i.txt"); done
read -r passed failed _ < <(bash scripts/catch2_summary.sh "${logs[@]}")
ran=$((passed + failed))
if [ "$rc" -eq 0 ] && [ "$ran" -ne "$listed" ]; then
  echo "catch2: the processes ran $ran test cases of $listed listed"; rc=1
fi
exit $rc
