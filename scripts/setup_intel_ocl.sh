#!/usr/bin/env bash
# Installs Intel's OpenCL CPU runtime (PyPI intel-opencl-rt + intel-cmplr-lib-rt) into build/venv-intel
# and registers it beside the system's ICDs (PoCL) in a private ICD folder, build/opencl-vendors.
# Nothing system-wide changes. One setting then makes clrt and its tests see both implementations:
#     source build/opencl-env.sh          (exports OCL_ICD_VENDORS=<repo>/build/opencl-vendors)
# scripts/test.sh sources it when present. Without it (or when this script is skipped or cannot reach
# PyPI) clrt sees only the system's ICDs, as before.
# The wheel's own libOpenCL.so (a loader) is never put on the library path: Debian's ocl-icd loader
# reads the ICD folder. libintelocl.so needs the wheel's libsvml/libimf/libirng/libintlc/libtbb: its
# RUNPATH finds them, except when the process has already loaded Debian's older libtbb.so.12 (e.g.
# build/ray_bench through Embree): then Intel's platform silently fails to load. opencl-env.sh
# therefore puts build/intel-ocl-deps, links to just those libraries, on LD_LIBRARY_PATH (TBB keeps
# backward compatibility within a soname, so Embree runs on the wheel's newer TBB).
# Usage: bash scripts/setup_intel_ocl.sh     (idempotent; CLRT_NO_INTEL_OCL=1 skips it)
set -euo pipefail
cd "$(dirname "$0")/.."
ROOT=$PWD
VENV=$ROOT/build/venv-intel
ICD=$ROOT/build/opencl-vendors
ENVF=$ROOT/build/opencl-env.sh
say() { echo "setup_intel_ocl: $*"; }
mkdir -p build
[ -n "${CLRT_NO_INTEL_OCL:-}" ] && { rm -f "$ENVF"; say "skipped (CLRT_NO_INTEL_OCL set; $ENVF removed)"; exit 0; }

lib=$VENV/lib/libintelocl.so
if [ ! -e "$lib" ]; then
  say "installing intel-opencl-rt and intel-cmplr-lib-rt into $VENV"
  rm -rf "$VENV"
  if ! /usr/bin/python3 -m venv "$VENV" || ! "$VENV/bin/pip" install -q --disable-pip-version-check \
        intel-opencl-rt intel-cmplr-lib-rt; then
    rm -rf "$VENV" "$ENVF"
    say "WARNING: could not install Intel's OpenCL runtime (no network or no python3-venv?); only the system's OpenCL ICDs will be used"
    exit 0
  fi
fi
[ -e "$lib" ] || { say "WARNING: $lib missing after install"; rm -f "$ENVF"; exit 0; }

# The ICD folder: the system's ICD files (PoCL) plus Intel's.
rm -rf "$ICD"; mkdir -p "$ICD"
cp /etc/OpenCL/vendors/*.icd "$ICD/" 2>/dev/null || true
echo "$lib" > "$ICD/intel-cpu.icd"

# Links to the runtime libraries libintelocl.so needs (never libOpenCL.so).
deps=$ROOT/build/intel-ocl-deps; rm -rf "$deps"; mkdir -p "$deps"
for f in "$VENV"/lib/lib{svml,imf,irng,intlc,tbb,tbbmalloc}.so*; do [ -e "$f" ] && ln -sf "$f" "$deps/"; done
cat > "$ENVF" <<ENV
# Written by scripts/setup_intel_ocl.sh: OpenCL ICDs = the system's (PoCL) + Intel's CPU runtime.
export OCL_ICD_VENDORS=$ICD
export LD_LIBRARY_PATH=$deps\${LD_LIBRARY_PATH:+:\$LD_LIBRARY_PATH}
ENV
# Check that the loader now sees Intel's platform (clrt may not be built yet: use clinfo if present).
if command -v clinfo >/dev/null && ! (OCL_ICD_VENDORS=$ICD clinfo -l 2>/dev/null | grep -q "Intel(R) OpenCL"); then
  say "WARNING: the ICD loader does not list Intel's platform; removing $ENVF"
  rm -f "$ENVF"; exit 0
fi
say "ok: source build/opencl-env.sh to see PoCL and Intel's runtime ($ICD)"
