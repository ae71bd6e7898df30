#!/usr/bin/env bash
# oclgrind suite: tiny renders (8x8, 1 spp) of every kernel feature variant listed in
# scripts/kernel_variants.txt, each with both pipelines (--pipeline wavefront and fused), plus
# `clrt tonemap` with each operator (8-bit and float output) and
# the device struct-layout kernel (clrt_tests "[layout]"), run on Oclgrind's simulator with its checks:
#   pass 1  memory (always on), API misuse and data races  (OCLGRIND_CHECK_API, OCLGRIND_DATA_RACES)
#           on the optimised program, as clrt builds it;
#   pass 2  API misuse and uninitialised values (OCLGRIND_UNINITIALIZED), with -cl-opt-disable:
#           oclgrind 21.10's uninitialised-value plugin aborts on LLVM's `freeze` instruction that
#           the optimiser emits ("Unsupported instruction: freeze").
# The uninit pass copies the scene buffers (CLRT_HUGE_PAGES=0, src/cl/scene_buffers.h): oclgrind 21.10's
# uninitialised-value plugin counts a CL_MEM_USE_HOST_PTR buffer's contents as never written (262 reports on
# sphere_nearest_bilinear's texels, 0 with the copy), so that pass checks the kernels on copied buffers and
# the races pass (memory checks included) on the huge-page buffers clrt uses on CPU devices.
# clEnqueueFillBuffer is turned into a host write (tests/oclgrind/fill_as_write.c, LD_PRELOAD):
# oclgrind 21.10 does not count a fill as initialising memory, which reports every read of a
# zero-filled buffer. Oclgrind's reports go to a log per run (OCLGRIND_LOG); the suite fails on any
# report, on a clrt failure, on a render that did not run on the Oclgrind device, or when oclgrind is
# missing. A negative control runs first: tests/oclgrind/oob_probe.c (an out-of-bounds read and an
# uninitialised value) must be reported in each pass. Logs: build/oclgrind/.
# Runs go CLRT_OCLGRIND_JOBS at a time (default: the number of cores, at most one per 6 GB of available
# memory; oclgrind's compile and simulation of one run keep one core busy). Each run's verdict goes to build/oclgrind/<run>.verdict; the summary counts them.
# Usage: bash scripts/oclgrind_suite.sh [--quick]   (--quick: pass 1 only)
set -uo pipefail
cd "$(dirname "$0")/.."
ROOT=$PWD
SCENES=$ROOT/../shared/scenes
OUT=$ROOT/build/oclgrind
RT=/usr/lib/oclgrind/liboclgrind-rt.so
SHIM=$ROOT/build/oclgrind-fill-shim.so
fail() { echo "oclgrind_suite: FAIL: $*"; exit 1; }
[ -f "$RT" ] || RT=$(dpkg -L oclgrind 2>/dev/null | grep '/liboclgrind-rt\.so$' | head -1)
[ -n "$RT" ] && [ -f "$RT" ] || fail "oclgrind is not installed (Debian package oclgrind; scripts/setup.sh installs it)"
[ -x build/clrt ] && [ -x build/clrt_tests ] || fail "build/clrt or build/clrt_tests missing (run scripts/setup.sh)"
[ -d "$SCENES" ] || fail "no shared scenes at $SCENES"
PASSES="races uninit"
[ "${1:-}" = "--quick" ] && PASSES="races"
rm -rf "$OUT"; mkdir -p "$OUT/img"
if [ ! -f "$SHIM" ] || [ tests/oclgrind/fill_as_write.c -nt "$SHIM" ]; then
  cc -shared -fPIC -O2 -o "$SHIM" tests/oclgrind/fill_as_write.c -lOpenCL || fail "cannot build $SHIM"
fi
PROBE=$ROOT/build/oclgrind-oob-probe
if [ ! -x "$PROBE" ] || [ tests/oclgrind/oob_probe.c -nt "$PROBE" ]; then
  cc -O1 -o "$PROBE" tests/oclgrind/oob_probe.c -lOpenCL || fail "cannot build $PROBE"
fi

# One run per core, and at most one per 6 GB of available memory (the largest run left in, the TT's
# fused races pass, peaks at 5.3 GB).
mem_jobs=$(( $(awk '/^MemAvailable:/ {print $2}' /proc/meminfo 2>/dev/null || echo 0) / (6 * 1024 * 1024) ))
JOBS=${CLRT_OCLGRIND_JOBS:-$(nproc)}
[ -n "${CLRT_OCLGRIND_JOBS:-}" ] || [ "$JOBS" -le "$mem_jobs" ] || JOBS=$(( mem_jobs > 1 ? mem_jobs : 1 ))
# check NAME PASS [--pipeline-of PIPE] CMD...: runs CMD on oclgrind and writes NAME.PASS.verdict: "ok", or
# the problem (a non-zero exit or any oclgrind report, with the first lines of the log). With --pipeline-of,
# the run must also say it ran on Oclgrind with that pipeline.
check() {
  local name=$1 pass=$2 pipe=""; shift 2
  [ "$1" = --pipeline-of ] && { pipe=$2; shift 2; }
  local log=$OUT/$name.$pass.oclgrind.log out=$OUT/$name.$pass.out verdict=$OUT/$name.$pass.verdict
  local -a env=(LD_PRELOAD="$SHIM:$RT" OCLGRIND_LOG="$log" OCLGRIND_CHECK_API=1 OCLGRIND_GLOBAL_MEM_SIZE=1073741824
                CLRT_NO_CACHE=1 CLRT_NO_PROFILE=1)
  if [ "$pass" = races ]; then env+=(OCLGRIND_DATA_RACES=1)
  else env+=(OCLGRIND_UNINITIALIZED=1 OCLGRIND_BUILD_OPTIONS=-cl-opt-disable CLRT_HUGE_PAGES=0); fi
  : > "$log"
  env "${env[@]}" "$@" < /dev/null > "$out" 2>&1
  local rc=$?
  {
    if [ $rc -ne 0 ] || [ -s "$log" ] || grep -q "OCLGRIND\|Oclgrind - " "$out"; then
      echo "oclgrind_suite: $name ($pass): rc $rc, $(grep -c "Kernel:" "$log") reports; first lines:"
      { head -12 "$log"; grep -v "^$" "$out" | grep -v "^wrote\|^times:\|^stats:\|done$" | head -6; } | sed 's/^/    /'
    elif [ -n "$pipe" ] && ! grep -q "(Oclgrind)" "$out"; then echo "oclgrind_suite: $name did not run on Oclgrind"
    elif [ -n "$pipe" ] && ! grep -q "pipeline $pipe" "$out"; then echo "oclgrind_suite: $name did not render with the $pipe pipeline"
    else echo ok; fi
  } > "$verdict"
}
# check in the background, at most JOBS at a time.
spawn() {
  while [ "$(jobs -rp | wc -l)" -ge "$JOBS" ]; do wait -n; done
  check "$@" &
}

for pass in $PASSES; do
  check probe "$pass" "$PROBE" > /dev/null
  grep -q "Invalid read" "$OUT/probe.$pass.oclgrind.log" ||
    fail "oclgrind did not report the probe's out-of-bounds read ($pass pass): it would not see real faults either"
  if [ "$pass" = uninit ]; then grep -qi "uninitiali" "$OUT/probe.$pass.oclgrind.log" ||
    fail "oclgrind did not report the probe's uninitialised value"; fi
done
rm -f "$OUT"/*.verdict; skipped=0

# Scenes left out of the races pass (kept in the uninit pass, which checks memory too): oclgrind's race
# detector adds a cost per kernel launch that grows with the scene's buffers. Measured on 2 cores: veachAjar
# (382k triangles, depth 8) took 277 s wavefront and 120 s fused in the races pass (uninit: 2.7 s and 6 s);
# the Audi TT (hw5/tt) 59 s wavefront (fused 19 s, kept). Their kernels' code is race-checked all the same:
# the two --all-features programs of kernel_variants.txt compile a superset of every feature set, and run
# both pipelines in both passes on small scenes.
RACES_NONE=" classic/veachAjar.xml "               # no races pass at all
RACES_FUSED_ONLY=" hw5/tt/scene_pisa_courtyard.xml "  # races pass for the fused pipeline only
n=0
while read -r scene args; do
  case "$scene" in ''|\#*) continue ;; esac
  n=$((n + 1)); name=$(printf "%02d-%s" $n "$(basename "${scene%.*}")")
  for pass in $PASSES; do
    for pipe in wavefront fused; do
      if [ "$pass" = races ] && { [[ "$RACES_NONE" == *" $scene "* ]] ||
           { [ "$pipe" = wavefront ] && [[ "$RACES_FUSED_ONLY" == *" $scene "* ]]; }; }; then
        skipped=$((skipped + 1)); continue
      fi
      mkdir -p "$OUT/img/$name-$pipe-$pass"
      # shellcheck disable=SC2086  # $args: the variant's extra options, space-separated
      spawn "$name-$pipe" "$pass" --pipeline-of $pipe build/clrt render "$SCENES/$scene" --resolution 8x8 --spp 1 \
        -o "$OUT/img/$name-$pipe-$pass" -v --pipeline $pipe $args
    done
  done
done < scripts/kernel_variants.txt
# The lanes kernel (cl_kernels/lanes.cl, render_lanes), four samples so that every lane works: the hw6 path
# box (LightMesh and point light, eight cameras: NEE, importance, MIS, roulette), scenes/lanes_mix.xml
# (a textured hit per lane; a glossy BRDF, sphere, area, point, spot and directional lights in lanes; a mirror, misses), and a classic
# camera under an environment map with a mirror (Lanes_Direct: the MIS pair in steps across the lanes, then
# the children: Lanes_DirectChildren).
for pass in $PASSES; do
  mkdir -p "$OUT/img/lanes-$pass" "$OUT/img/lanes-mix-$pass" "$OUT/img/lanes-env-$pass"
  spawn lanes-env "$pass" --pipeline-of lanes build/clrt render scenes/env_turned.xml \
    --resolution 8x8 --spp 4 -o "$OUT/img/lanes-env-$pass" -v --pipeline lanes
  spawn lanes "$pass" --pipeline-of lanes build/clrt render "$SCENES/hw6/cornellbox_jaroslav_path_diffuse.xml" \
    --resolution 8x8 --spp 4 -o "$OUT/img/lanes-$pass" -v --pipeline lanes
  spawn lanes-mix "$pass" --pipeline-of lanes build/clrt render scenes/lanes_mix.xml \
    --resolution 8x8 --spp 4 -o "$OUT/img/lanes-mix-$pass" -v --pipeline lanes
done
wait

# Tone mapping: every operator, 8-bit and float output, on the tiny HDR render of cube_point_hdr.
exr=$(ls "$OUT"/img/*/cube_point_hdr.exr 2>/dev/null | head -1)
[ -n "$exr" ] || fail "cube_point_hdr.exr was not rendered"
for tmo in photographic aces filmic; do
  for pass in $PASSES; do
    spawn "tonemap-$tmo" "$pass" build/clrt tonemap "$exr" --tmo "$tmo" -o "$OUT/img/tm-$tmo-$pass.png"
    spawn "tonemap-$tmo-float" "$pass" build/clrt tonemap "$exr" --tmo "$tmo" -o "$OUT/img/tm-$tmo-$pass.exr"
  done
done
# The struct-layout kernel (cl_kernels/layout.cl) through its test.
for pass in $PASSES; do spawn "layout" "$pass" build/clrt_tests "[layout]" --use-colour no; done
wait
runs=$(ls "$OUT"/*.verdict | wc -l)
bad=$(grep -L -x ok "$OUT"/*.verdict | wc -l)
grep -h -v -x ok "$OUT"/*.verdict

echo "oclgrind_suite: $runs runs on oclgrind ($PASSES), $bad with reports or failures, $skipped left out of the races pass (RACES_NONE, RACES_FUSED_ONLY); logs in build/oclgrind"
[ $bad -eq 0 ] || fail "$bad runs reported problems"
echo "oclgrind_suite: ok"
