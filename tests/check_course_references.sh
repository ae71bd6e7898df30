#!/usr/bin/env bash
# Tests scripts/check_course's reference lookup under --references (packages laid out as inputs/ and
# outputs/): a camera whose image name has two files equally near the scene (the course's outputs/ and a
# student's my_outputs/ beside it) is SKIPPED as ambiguous, naming both, never judged against whichever the
# file system lists first; --references-exclude leaves one out, and the check then judges against the other
# (ok against a copy of clrt's own render, FAIL against a black image).
# Usage: bash tests/check_course_references.sh   (after the build; scripts/test.sh runs it)
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
pkg=$tmp/pkg
mkdir -p "$pkg/hw1/inputs" "$pkg/hw1/outputs" "$pkg/hw1/my_outputs" "$tmp/render"
cp "$root/scenes/transparency.xml" "$pkg/hw1/inputs/"
"$root/build/clrt" render "$pkg/hw1/inputs/transparency.xml" -o "$tmp/render" --ldr-quantize floor >/dev/null
cp "$tmp/render/transparency.png" "$pkg/hw1/outputs/"
cp "$tmp/render/transparency.png" "$pkg/hw1/my_outputs/"
fails=0
expect() {  # expect WHAT PATTERN [check_course args...]
  local what=$1 pattern=$2; shift 2
  local out; out=$(bash "$root/scripts/check_course" --scenes "$pkg" --references "$pkg" "$@" 2>&1 || true)
  if grep -qE "$pattern" <<<"$out"; then echo "ok: $what"; else echo "FAILED: $what"; echo "$out"; fails=$((fails + 1)); fi
}
expect "two equally near references: SKIPPED, both named" \
  'SKIPPED +ambiguous reference, 2 files .*hw1/my_outputs/transparency.png, hw1/outputs/transparency.png'
# my_outputs/ becomes a black 161x161 PNG, written with the standard library of the Python that check_course has
# set up by now (a fresh machine has none before it).
"$root/build/check-venv/bin/python" - "$pkg/hw1/my_outputs/transparency.png" <<'PY'
import struct, sys, zlib
w = h = 161
def chunk(kind, data):
    return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xffffffff)
raw = b"".join(b"\0" + b"\0" * (3 * w) for _ in range(h))
png = (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0))
       + chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b""))
open(sys.argv[1], "wb").write(png)
PY
expect "my_outputs/ left out: judged against outputs/ (clrt's own render)" \
  'transparency.png +deterministic +ok +PSNR' --references-exclude '(^|/)my_outputs/'
expect "outputs/ left out: judged against my_outputs/ (black)" \
  'transparency.png +deterministic +FAIL' --references-exclude '^hw1/outputs/'
[ "$fails" -eq 0 ] && echo "check_course_references: 3 checks passed" || { echo "check_course_references: $fails failed"; exit 1; }
