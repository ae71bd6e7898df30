#!/usr/bin/env bash
# GPU bring-up in one command. On a machine with a GPU and its OpenCL driver this
#   1. builds clrt (scripts/setup.sh), or takes prebuilt binaries (CLRT_PREBUILT=DIR, see --bundle);
#   2. finds the GPU; if NVIDIA's OpenCL library is installed but not registered with the ICD loader
#      (containers often lack /etc/OpenCL/vendors/nvidia.icd), registers it in a private folder
#      through OCL_ICD_VENDORS (nothing system-wide is changed);
#   3. runs the whole test suite with the GPU as the test device (CLRT_TEST_DEVICE=gpu);
#   4. renders the speed-table scenes (scripts/speed_table.py --device gpu) and prints their table;
#   5. renders those scenes at a fixed seed on the GPU and, where PoCL's CPU device is present, on it
#      too, and compares the two with clrt-imgdiff (conformance); without PoCL the GPU images are
#      left in OUT for comparing elsewhere.
# It fails loudly (exit 1, a line starting "device_check: FAIL") when no GPU is found, the suite
# fails, or a render fails. Shared scenes are read from ../shared/scenes.
#
# usage: bash scripts/device_check.sh [--runs N] [--out DIR]     (default 3 runs, OUT build/device-check)
#        bash scripts/device_check.sh --bundle DIR   copy build/{clrt,clrt_tests,clrt-imgdiff} and the
#            shared libraries they need beyond a base system into DIR (bin/, lib/), for a GPU machine
#            that has no package registry: there run CLRT_PREBUILT=DIR bash scripts/device_check.sh
set -euo pipefail
cd "$(dirname "$0")/.."
ROOT=$PWD
RUNS=3
OUT=$ROOT/build/device-check
SPP_CONFORMANCE=${SPP_CONFORMANCE:-4}
SCENES=(hw5/cube_point.xml classic/veachAjar.xml hw5/tt/scene_pisa_courtyard.xml)
fail() { echo "device_check: FAIL: $*"; exit 1; }

bundle() {  # bundle DIR: binaries and their non-base shared libraries
    local dir=$1
    mkdir -p "$dir/bin" "$dir/lib"
    cp build/clrt build/clrt_tests build/clrt-imgdiff "$dir/bin/"
    ldd build/clrt build/clrt_tests | awk '/=> \//{print $3}' | sort -u |
        grep -Ev '/(libc|libm|libgcc_s|libstdc\+\+|libz|libpthread|libdl|librt)\.so' |
        while read -r lib; do cp -L "$lib" "$dir/lib/"; done
    echo "device_check: bundle in $dir: $(ls "$dir/bin" | tr '\n' ' ')+ $(ls "$dir/lib" | wc -l) libraries"
}

while [ $# -gt 0 ]; do
    case "$1" in
        --runs) RUNS=$2; shift 2 ;;
        --out) OUT=$(realpath -m "$2"); shift 2 ;;
        --bundle) bundle "$2"; exit 0 ;;
        -h|--help) sed -n '2,20p' "$0"; exit 0 ;;
        *) fail "unknown argument $1" ;;
    esac
done
mkdir -p "$OUT"

# 1. Binaries.
if [ -n "${CLRT_PREBUILT:-}" ]; then
    BIN=$(realpath "$CLRT_PREBUILT")/bin
    export LD_LIBRARY_PATH=$(realpath "$CLRT_PREBUILT")/lib${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}
    mkdir -p build && cp "$BIN"/* build/   # clrt_tests runs build/clrt
else
    bash scripts/setup.sh
fi
BIN=$ROOT/build
"$BIN/clrt" --help >/dev/null || fail "build/clrt does not run"

# 2. A GPU, registering NVIDIA's OpenCL library when the loader does not know it.
has_gpu() { "$BIN/clrt" devices 2>/dev/null | grep -q '^\[[0-9]*\] *GPU'; }
if ! has_gpu; then
    lib=$(ldconfig -p 2>/dev/null | awk '/libnvidia-opencl\.so\.1 /{print $NF; exit}')
    [ -n "$lib" ] || lib=$(find /usr/local/nvidia /usr/lib/x86_64-linux-gnu /usr/lib64 /usr/local/cuda*/ \
                              -name 'libnvidia-opencl.so.1' 2>/dev/null | head -1 || true)
    if [ -n "$lib" ]; then
        icd=$OUT/icd; mkdir -p "$icd"
        cp /etc/OpenCL/vendors/*.icd "$icd/" 2>/dev/null || true
        echo "$lib" > "$icd/nvidia.icd"
        export OCL_ICD_VENDORS=$icd
        echo "device_check: registered $lib through OCL_ICD_VENDORS=$icd"
    fi
fi
"$BIN/clrt" devices | tee "$OUT/devices.txt"
has_gpu || fail "no GPU among the OpenCL devices above (is the vendor's OpenCL driver installed?)"
GPU_LINE=$(grep -m1 '^\[[0-9]*\] *GPU' "$OUT/devices.txt")
HAS_CPU=$(grep -c '^\[[0-9]*\] *CPU' "$OUT/devices.txt" || true)
export CLRT_CACHE_DIR=$OUT/kernel-cache

# 3. The test suite on the GPU.
echo "device_check: test suite on the GPU"
set +e
(cd build && CLRT_TEST_DEVICE=gpu timeout 300 ./clrt_tests) > "$OUT/tests-gpu.txt" 2>&1
suite_rc=$?
set -e
grep -E "^(All tests passed|test cases:)" "$OUT/tests-gpu.txt" | tail -1
grep -B2 -A12 "FAILED:" "$OUT/tests-gpu.txt" | head -80 || true

# 4. Speed table on the GPU (medians of RUNS).
echo "device_check: speed table (--device gpu --runs $RUNS)"
python3 scripts/speed_table.py --device gpu --runs "$RUNS" --build "$BIN" | tee "$OUT/speed-gpu.md"

# 5. Conformance: the same scene and seed on the GPU and on PoCL.
conf_rc=0
for s in "${SCENES[@]}"; do
    scene=$ROOT/../shared/scenes/$s
    [ -f "$scene" ] || { echo "device_check: missing $scene"; conf_rc=1; continue; }
    name=$(basename "${s%.*}")
    for dev in gpu cpu; do
        [ "$dev" = cpu ] && [ "$HAS_CPU" = 0 ] && continue
        d=$OUT/img-$name-$dev; mkdir -p "$d"
        "$BIN/clrt" render "$scene" -o "$d" --device "$dev" --spp "$SPP_CONFORMANCE" --seed 7 \
            > "$d/log.txt" 2>&1 || { tail -3 "$d/log.txt"; fail "render of $s on $dev"; }
    done
    if [ "$HAS_CPU" != 0 ]; then
        for f in "$OUT/img-$name-gpu"/*.exr "$OUT/img-$name-gpu"/*.png; do
            [ -f "$f" ] || continue
            echo -n "conformance $name/$(basename "$f") gpu vs PoCL: "
            "$BIN/clrt-imgdiff" "$f" "$OUT/img-$name-cpu/$(basename "$f")" || conf_rc=1
        done
    fi
done
[ "$HAS_CPU" = 0 ] && echo "device_check: no CPU OpenCL device here: GPU images left in $OUT/img-*-gpu for comparison elsewhere"

echo "device_check: GPU row: | $(date +%F) | ${GPU_LINE#*] } |"
[ $suite_rc -eq 0 ] || fail "test suite on the GPU (rc $suite_rc; $OUT/tests-gpu.txt)"
echo "device_check: ok"
