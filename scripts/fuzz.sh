#!/usr/bin/env bash
# Builds the libFuzzer targets in fuzz/ (clang++, -fsanitize=fuzzer,address,undefined; the needed src/
# files compiled directly, stb_image instrumented from source, pugixml/OpenEXR from the system) into
# build-fuzz/, then runs them in one of two modes:
#
#   bash scripts/fuzz.sh --gate [TARGET...]
#       The deterministic check that scripts/test.sh runs: replays every file of fuzz/regressions/<t>/
#       (past findings) and fuzz/corpus/<t>/ (committed seeds), then a fixed number of libFuzzer runs
#       (FUZZ_RUNS, default per target below) with -seed=1 starting from fuzz/corpus/<t> alone. Same binary,
#       same files: the same inputs every time, on any machine (no time limit decides anything; the
#       per-input -timeout is only a hang guard, far above what an input takes).
#   bash scripts/fuzz.sh [SECONDS] [TARGET...]
#       Exploration for SECONDS (default 60) per target with one job: corpora under build-fuzz/corpus/
#       (kept between runs), seeded from fuzz/corpus, fuzz/regressions and ../shared/scenes (copies,
#       never written into the repository). FUZZ_SEED=N fixes libFuzzer's seed (0, the default, picks a
#       new one each run); how far it gets still depends on the machine's speed.
#   FUZZ_BUILD_ONLY=1 bash scripts/fuzz.sh      build only
#
# TARGET: scene ply image (default: all three). Findings (crash-*, oom-*, timeout-*, leak-*) are written
# to build-fuzz/findings/<target>/ and make the script exit non-zero. Reproduce one with
# build-fuzz/fuzz_<target> FILE; once fixed, add it (minimised: fuzz_<target> -minimize_crash=1 FILE)
# to fuzz/regressions/<target>/ and its expected outcome to tests/test_fuzz_regressions.cpp.
set -euo pipefail
cd "$(dirname "$0")/.."
ROOT=$PWD
GATE=0
if [ "${1:-}" = "--gate" ]; then GATE=1; shift; fi
SECONDS_EACH=60
if [ $GATE = 0 ] && [[ "${1:-}" =~ ^[0-9]+$ ]]; then SECONDS_EACH=$1; shift; fi
TARGETS=("$@")
[ ${#TARGETS[@]} -eq 0 ] && TARGETS=(scene ply image)
B=${FUZZ_BUILD_DIR:-$ROOT/build-fuzz}
SHARED=${CLRT_SHARED_DIR:-$ROOT/../shared}
CXX=${FUZZ_CXX:-clang++}
mkdir -p "$B/obj"

FLAGS=(-std=c++17 -g -O1 -fno-omit-frame-pointer -fsanitize=fuzzer-no-link,address,undefined
       -fno-sanitize-recover=undefined -DCLRT_EXR_THREADS=0 -I"$ROOT/src" -I"$ROOT/fuzz"
       $(pkg-config --cflags OpenEXR) -I/usr/include/stb)
LINK=(-fsanitize=fuzzer,address,undefined $(pkg-config --libs OpenEXR) -lpugixml -pthread)

compile() {  # compile SRC -> $B/obj/NAME.o unless the object is newer than SRC and every header
    local src=$1 obj=$B/obj/$(basename "${1%.*}").o
    if [ ! -f "$obj" ] || [ "$src" -nt "$obj" ] || [ "$ROOT/scripts/fuzz.sh" -nt "$obj" ] || [ -n "$(find src fuzz -name '*.h' -newer "$obj" | head -1)" ]; then
        echo "compile $src" >&2
        # stb_image passes a null pointer to memcpy with length 0 for a zero-length PNG IDAT chunk
        # (valid PNG; harmless in practice, UB by the letter): that one check is off for stb alone.
        local extra=()
        case "$src" in *stb_impl.cpp) extra=(-fno-sanitize=nonnull-attribute) ;; esac
        "$CXX" "${FLAGS[@]}" "${extra[@]}" -c "$src" -o "$obj"
    fi
    echo "$obj"
}
objs() { for s in "$@"; do compile "$s" | tail -1; done; }

UTIL=$(objs src/util/error.cpp)
SCENE=$(objs src/scene/scene_walker.cpp src/scene/read_*.cpp src/scene/xml_node.cpp src/scene/json_node.cpp src/scene/ply_reader.cpp src/scene/transforms.cpp)
IMAGE=$(objs src/image/image_io.cpp src/image/chromaticities.cpp fuzz/stb_impl.cpp)
for t in scene ply image; do objs "fuzz/fuzz_$t.cpp" >/dev/null; done

link() {  # link target NAME from object lists
    local name=$1; shift
    echo "link $name"
    "$CXX" -o "$B/fuzz_$name" "$B/obj/fuzz_$name.o" "$@" "${LINK[@]}"
}
link scene $SCENE $UTIL
link ply $B/obj/ply_reader.o $UTIL
link image $IMAGE $UTIL
[ "${FUZZ_BUILD_ONLY:-0}" = 1 ] && exit 0

# Options common to both modes. -rss_limit_mb/-malloc_limit_mb: an input that makes a reader allocate
# gigabytes is a finding (readers must refuse absurd sizes up front). -close_fd_mask=3: the readers'
# warnings are not shown (libFuzzer's own report still is).
COMMON=(-rss_limit_mb=3072 -malloc_limit_mb=3072 -close_fd_mask=3 -print_final_stats=1)
export ASAN_OPTIONS=allocator_may_return_null=1:detect_leaks=1
status=0

if [ $GATE = 1 ]; then
    # Runs per target: 10-20 s each on a busy 2-core machine (their number, not the
    # time, is what is fixed). FUZZ_RUNS=N overrides all three.
    declare -A RUNS=([scene]=6000 [ply]=15000 [image]=2500)
    NOASLR=""
    if setarch "$(uname -m)" -R true 2>/dev/null; then NOASLR="setarch $(uname -m) -R"
    else echo "fuzz: setarch -R is not available: addresses are randomised, runs may differ slightly" >&2; fi
    for t in "${TARGETS[@]}"; do
        out=$B/findings/$t
        rm -rf "$out" "$B/gate/$t"
        mkdir -p "$out" "$B/gate/$t"
        files=()
        for d in "$ROOT/fuzz/regressions/$t" "$ROOT/fuzz/corpus/$t"; do
            [ -d "$d" ] && while IFS= read -r f; do files+=("$f"); done < <(find "$d" -type f | LC_ALL=C sort)
        done
        # Each target runs in a scratch folder of its own and writes its inputs there as ./<name>
        # (fuzz_common.h), under setarch -R (no address randomisation: pointer values that reach a
        # comparison would otherwise steer the mutations differently in each run).
        work=$B/gate/$t-cwd
        rm -rf "$work" && mkdir -p "$work"
        run() { (cd "$work" && CLRT_FUZZ_INPUT_DIR=. $NOASLR "$B/fuzz_$t" "$@"); }
        echo "== fuzz_$t: replay ${#files[@]} committed inputs"
        run "${COMMON[@]}" -timeout=60 -artifact_prefix="$out/" "${files[@]}" \
            >"$B/gate-$t-replay.log" 2>&1 || { tail -n 30 "$B/gate-$t-replay.log"; status=1; continue; }
        n=${FUZZ_RUNS:-${RUNS[$t]}}
        echo "== fuzz_$t: $n runs, -seed=1, from fuzz/corpus/$t"
        # New inputs go to the first folder, a scratch one emptied above (never into the repository);
        # -reload=0: nothing is re-read from it on a timer. The regressions are replayed above but are
        # no seeds here: some name absolute paths (/dev/zero), and a mutated path could reach files
        # that differ between machines.
        run "$B/gate/$t" "$ROOT/fuzz/corpus/$t" "${COMMON[@]}" \
            -runs="$n" -seed=1 -reload=0 -max_len=4096 -timeout=60 -artifact_prefix="$out/" \
            >"$B/gate-$t.log" 2>&1 || status=1
        grep -E "^#[0-9]+[[:space:]]+DONE" "$B/gate-$t.log" | tail -1 || true
        if [ $status != 0 ] || ls "$out" | grep -q .; then
            tail -n 30 "$B/gate-$t.log"; echo "findings for $t:"; ls -l "$out"; status=1
        fi
    done
    exit $status
fi

# Exploration: corpora kept between runs; new inputs found by the fuzzer are added to them.
seed() {  # seed DIR FILES...
    local dir=$1; shift
    mkdir -p "$dir"
    for f in "$@"; do [ -f "$f" ] && cp -n "$f" "$dir/$(echo "$f" | md5sum | cut -c1-16)$(basename "$f" | sed 's/.*\(\.[^.]*\)$/\1/')"; done
    return 0
}
for t in scene ply image; do
    seed "$B/corpus/$t" $(find "$ROOT/fuzz/corpus/$t" "$ROOT/fuzz/regressions/$t" -type f 2>/dev/null)
done
if [ -d "$SHARED/scenes" ]; then
    # Scene seeds: the smaller XML/JSON scenes (big inline meshes only slow the fuzzer down).
    seed "$B/corpus/scene" $(find "$SHARED/scenes" \( -name '*.xml' -o -name '*.json' \) -size -64k)
    seed "$B/corpus/ply" $(find "$SHARED/scenes" -name '*.ply' -size -64k | head -40)
    seed "$B/corpus/image" $(find "$SHARED/scenes" \( -iname '*.png' -o -iname '*.jpg' -o -iname '*.jpeg' -o -iname '*.exr' \) -size -48k | head -40)
fi

for t in "${TARGETS[@]}"; do
    out=$B/findings/$t
    mkdir -p "$out"
    echo "== fuzz_$t for ${SECONDS_EACH}s (corpus $B/corpus/$t, findings $out)"
    # -timeout: one input taking longer than 10 s is a finding.
    "$B/fuzz_$t" "$B/corpus/$t" "${COMMON[@]}" -max_total_time="$SECONDS_EACH" -timeout=10 -max_len=65536 \
        -artifact_prefix="$out/" -seed="${FUZZ_SEED:-0}" >"$B/fuzz_$t.log" 2>&1 || status=1
    tail -n 25 "$B/fuzz_$t.log"
    if ls "$out" | grep -q .; then echo "findings for $t:"; ls -l "$out"; status=1; fi
done
exit $status
