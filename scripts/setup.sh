#!/usr/bin/env bash
# Installs clrt's Debian build dependencies (when missing) and builds it into build/ (Release).
# With --test also what the test command needs beyond that: oclgrind, clang (fuzz gate, GPU-target
# compiles), python3-venv, Intel's OpenCL CPU runtime from PyPI in build/venv-intel, and OpenMPI
# (openmpi-bin, libopenmpi-dev: the [mpi] tests run `mpirun -np 3 clrt render`; the build uses MPI
# whenever libopenmpi-dev is there, and works without it), and for the preview's browser test Debian's
# chromium + chromium-driver and Selenium from PyPI in build/venv-preview (CLRT_NO_BROWSER_TEST=1: none).
# Usage: bash scripts/setup.sh [--test]   (run as root, or with sudo available, on Debian/Ubuntu)
set -euo pipefail
cd "$(dirname "$0")/.."

PKGS="cmake g++ make pkg-config ocl-icd-opencl-dev opencl-clhpp-headers pocl-opencl-icd libopenexr-dev libpugixml-dev catch2 libstb-dev clinfo nlohmann-json3-dev zlib1g-dev libcpp-httplib-dev"
[ "${1:-}" = "--test" ] && PKGS="$PKGS oclgrind clang libclang-rt-dev python3-venv openmpi-bin libopenmpi-dev"
# The preview's browser test (scripts/preview_browser_test.py): headless Chromium and its WebDriver.
[ "${1:-}" = "--test" ] && [ -z "${CLRT_NO_BROWSER_TEST:-}" ] && PKGS="$PKGS chromium chromium-driver"
missing=""
for p in $PKGS; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing="$missing $p"
done
if [ -n "$missing" ]; then
  echo "setup: installing:$missing"
  SUDO=""
  [ "$(id -u)" -ne 0 ] && SUDO="sudo"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends $missing >/dev/null
fi

cmake -S . -B build -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build build -j"$(nproc)"
# Intel's OpenCL CPU runtime (PyPI) in build/venv-intel, beside PoCL; CLRT_NO_INTEL_OCL=1 skips it.
[ "${1:-}" = "--test" ] && bash scripts/setup_intel_ocl.sh
# Selenium (PyPI) in build/venv-preview for the preview's browser test; CLRT_NO_BROWSER_TEST=1 skips it.
if [ "${1:-}" = "--test" ] && [ -z "${CLRT_NO_BROWSER_TEST:-}" ] && [ ! -x build/venv-preview/bin/python ]; then
  python3 -m venv build/venv-preview && build/venv-preview/bin/pip install -q selenium
fi
exit 0
