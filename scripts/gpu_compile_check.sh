#!/usr/bin/env bash
# Compiles every kernel program variant for GPU targets with Debian's clang, without a GPU:
# nvptx64-nvidia-nvcl (NVIDIA PTX) and amdgcn-amd-amdhsa (AMD, -nogpulib). The programs come from the
# host code itself: clrt renders each scene of scripts/kernel_variants.txt at 1x1, 1 spp on the default
# device with CLRT_DUMP_PROGRAM set, which writes every program's exact source and build options
# (src/cl/program.cpp); each distinct (source, options) pair is then compiled as OpenCL C 1.2:
#   clang -x cl -cl-std=CL1.2 -target T -Xclang -finclude-default-header OPTIONS -S
# This catches what GPU compilers reject and a CPU compiler accepts (address-space mismatches,
# unsupported extensions, recursion, variable-length stack arrays). Fails on any compile error.
# Device quirks (src/cl/quirks.cpp, docs/quirks.md): the dumped options carry the quirk defines of the
# device that built them (PoCL: none), and NVIDIA and AMD devices get none either (tests/test_quirks.cpp
# checks it), so the programs compiled here are the ones those GPUs would build. A quirk that gives
# them a define goes into GPU_QUIRK_DEFINES below.
# Usage: bash scripts/gpu_compile_check.sh [--all-scenes]   (--all-scenes: every scene under
#        ../shared/scenes instead of the variant list; scenes that fail to load are listed, skipped)
set -uo pipefail
cd "$(dirname "$0")/.."
ROOT=$PWD
SCENES=$ROOT/../shared/scenes
OUT=$ROOT/build/gpu-compile
CLANG=${CLANG:-clang}
GPU_QUIRK_DEFINES=""  # -DCLRT_QUIRK_<NAME> that src/cl/quirks.cpp gives NVIDIA/AMD devices: none today
fail() { echo "gpu_compile_check: FAIL: $*"; exit 1; }
command -v "$CLANG" >/dev/null || fail "$CLANG not found (Debian package clang)"
[ -x build/clrt ] || fail "build/clrt missing (run scripts/setup.sh)"
[ -d "$SCENES" ] || fail "no shared scenes at $SCENES"
rm -rf "$OUT"; mkdir -p "$OUT/programs" "$OUT/img"

if [ "${1:-}" = "--all-scenes" ]; then
  list=$(cd "$SCENES" && find . -maxdepth 3 \( -name '*.xml' -o -name '*.json' \) | sed 's|^\./||' | sort)
  list=$(printf '%s\n' "$list"; echo "hw5/cube_point.xml --all-features")
else
  list=$(grep -v '^\s*\(#\|$\)' scripts/kernel_variants.txt)
fi
skipped=0
while read -r scene args; do
  [ -n "$scene" ] || continue
  if ! CLRT_DUMP_PROGRAM=$OUT/programs build/clrt render "$SCENES/$scene" --resolution 1x1 --spp 1 \
        -o "$OUT/img" $args > "$OUT/render.log" 2>&1; then
    [ "${1:-}" = "--all-scenes" ] || { tail -2 "$OUT/render.log"; fail "render of $scene $args"; }
    echo "gpu_compile_check: skipped $scene: $(grep -m1 'error:' "$OUT/render.log")"
    skipped=$((skipped + 1))
  fi
done <<< "$list"

# compile SRC TARGET: one program for one GPU target; the verdict ("ok" or the errors) in SRC.TARGET.verdict.
compile() {
  local src=$1 target=$2 t=${2%% *}
  local opts log=${src%.cl}.$t.log
  opts="$GPU_QUIRK_DEFINES $(cat "${src%.cl}.options")"
  # shellcheck disable=SC2086  # options are a space-separated list of -D flags and -cl-std; target has flags
  if "$CLANG" -x cl -cl-std=CL1.2 -target $target -Xclang -finclude-default-header $opts -S \
        -o "${src%.cl}.$t.s" "$src" > "$log" 2>&1; then echo ok
  else echo "gpu_compile_check: $t: $(basename "$src") ($opts) fails:"; grep -m5 "error:" "$log" | sed 's/^/    /'
  fi > "${src%.cl}.$t.verdict"
}
# The compiles, CLRT_GPU_COMPILE_JOBS at a time (default: the number of cores; clang uses one each).
JOBS=${CLRT_GPU_COMPILE_JOBS:-$(nproc)}
for src in "$OUT"/programs/*.cl; do
  for target in nvptx64-nvidia-nvcl "amdgcn-amd-amdhsa -nogpulib"; do
    while [ "$(jobs -rp | wc -l)" -ge "$JOBS" ]; do wait -n; done
    compile "$src" "$target" &
  done
done
wait
n=$(ls "$OUT"/programs/*.verdict | wc -l)
errors=$(grep -L -x ok "$OUT"/programs/*.verdict | wc -l)
grep -h -v -x ok "$OUT"/programs/*.verdict
warnings=$(cat "$OUT"/programs/*.log | grep -c "warning:")
np=$(ls "$OUT"/programs/*.cl | wc -l)
echo "gpu_compile_check: $np distinct programs (source + options), $n compiles for nvptx64 and amdgcn: $errors failed, $warnings warnings ($("$CLANG" --version | head -1)); $skipped scenes skipped"
[ "$np" -gt 0 ] || fail "no program was dumped"
[ $errors -eq 0 ] || fail "$errors GPU-target compiles failed (logs in $OUT/programs)"
echo "gpu_compile_check: ok"
