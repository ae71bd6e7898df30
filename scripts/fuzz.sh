#!/usr/bin/env bash
# Builds the libFuzzer targets in fuzz/ (clang++, -fsanitize=fuzzer,address,undefined; the needed src/
# files compiled directly, stb_image instrumented from source, pugixml/OpenEXR from the system) into
# build-fuzz/, seeds their corpora from ../shared/scenes (copied under build-fuzz/, never into the
# repository), and runs each target for SECONDS (default 60) with one job.
#
# Usage: bash scripts/fuzz.sh [SECONDS] [TARGET...]     TARGET: scene ply image (default: all three)
#        FUZZ_BUILD_ONLY=1 bash scripts/fuzz.sh          build only
# Smoke run for CI (~20 s in all, plus the build): FUZZ_SEED=1 bash scripts/fuzz.sh 6
# FUZZ_SEED=N fixes libFuzzer's random seed (0, the default, picks a new one each run).
# Findings (crash-*, oom-*, timeout-*, leak-*) are written to build-fuzz/findings/<target>/; the script
# exits non-zero if any target found something. Reproduce one: build-fuzz/fuzz_<target> <file>.
set -euo pipefail
cd "$(dirname "$0")/.."
ROOT=$PWD
SECONDS_EACH=${1:-60}
shift || true
TARGETS=("$@")
[ ${#TARGETS[@]} -eq 0 ] && TARGETS=(scene ply image)
B=${FUZZ_BUILD_DIR:-$ROOT/build-fuzz}
SHARED=${CLRT_SHARED_DIR:-$ROOT/../shared}
CXX=${FUZZ_CXX:-clang++}
mkdir -p "$B/obj"

FLAGS=(-std=c++17 -g -O1 -fno-omit-frame-pointer -fsanitize=fuzzer-no-link,address,undefined
       -fno-sanitize-recover=undefined -I"$ROOT/src" -I"$ROOT/fuzz"
       $(pkg-config --cflags OpenEXR) -I/usr/include/stb)
LINK=(-fsanitize=fuzzer,address,undefined $(pkg-config --libs OpenEXR) -lpugixml -pthread)

compile() {  # compile SRC -> $B/obj/NAME.o unless the object is newer than SRC and every header
    local src=$1 obj=$B/obj/$(basename "${1%.*}").o
    if [ ! -f "$obj" ] || [ "$src" -nt "$obj" ] || [ -n "$(find src fuzz -name '*.h' -newer "$obj" | head -1)" ]; then
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
SCENE=$(objs src/scene/scene_walker.cpp src/scene/xml_node.cpp src/scene/json_node.cpp src/scene/ply_reader.cpp src/scene/transforms.cpp)
IMAGE=$(objs src/image/image_io.cpp fuzz/stb_impl.cpp)
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

# Seed corpora (kept between runs; new inputs found by the fuzzer are added to them).
seed() {  # seed DIR FILES...
    local dir=$1; shift
    mkdir -p "$dir"
    for f in "$@"; do [ -f "$f" ] && cp -n "$f" "$dir/$(echo "$f" | md5sum | cut -c1-16)$(basename "$f" | sed 's/.*\(\.[^.]*\)$/\1/')"; done
    return 0
}
if [ -d "$SHARED/scenes" ]; then
    # Scene seeds: the smaller XML/JSON scenes (big inline meshes only slow the fuzzer down).
    seed "$B/corpus/scene" $(find "$SHARED/scenes" \( -name '*.xml' -o -name '*.json' \) -size -64k)
    seed "$B/corpus/ply" $(find "$SHARED/scenes" -name '*.ply' -size -64k | head -40)
    seed "$B/corpus/image" $(find "$SHARED/scenes" \( -iname '*.png' -o -iname '*.jpg' -o -iname '*.jpeg' -o -iname '*.exr' \) -size -48k | head -40)
fi
for t in scene ply image; do mkdir -p "$B/corpus/$t"; done
# Tiny hand-made seeds so the corpora are never empty (and reach the EXR and binary PLY paths).
printf '<Scene><Cameras/></Scene>' >"$B/corpus/scene/min.xml"
printf '{"Scene":{"MaxRecursionDepth":"2"}}' >"$B/corpus/scene/min.json"
printf 'ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n' >"$B/corpus/ply/min.ply"
{ printf 'ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n'
  printf '\0\0\0\0\0\0\0\0\0\0\0\0\0\0\x80\x3f\0\0\0\0\0\0\0\0\0\0\0\0\0\0\x80\x3f\0\0\0\0\x03\0\0\0\0\x01\0\0\0\x02\0\0\0'; } >"$B/corpus/ply/min_binary.ply"

status=0
for t in "${TARGETS[@]}"; do
    out=$B/findings/$t
    mkdir -p "$out"
    echo "== fuzz_$t for ${SECONDS_EACH}s (corpus $B/corpus/$t, findings $out)"
    # -rss_limit_mb: an input that makes a reader allocate gigabytes is a finding (readers must refuse
    # absurd sizes up front). -timeout: one input taking longer than 10 s is a finding.
    ASAN_OPTIONS=allocator_may_return_null=1:detect_leaks=1 \
        "$B/fuzz_$t" "$B/corpus/$t" -max_total_time="$SECONDS_EACH" -rss_limit_mb=3072 -malloc_limit_mb=3072 \
        -timeout=10 -max_len=65536 -print_final_stats=1 -close_fd_mask=3 -artifact_prefix="$out/" \
        -seed="${FUZZ_SEED:-0}" \
        >"$B/fuzz_$t.log" 2>&1 || status=1
    tail -n 25 "$B/fuzz_$t.log"
    if ls "$out" | grep -q .; then echo "findings for $t:"; ls -l "$out"; status=1; fi
done
exit $status
