#!/usr/bin/env bash
# crosscheck_pfstmo.sh — compares clrt's Photographic tone mapping (run on the OpenCL device) with
# pfstmo_reinhard02 from pfstools (Debian: apt-get install pfstmo pfstools), a tool nobody here wrote,
# on an environment map: both luminance mappings must agree within 1% on every pixel.
#
# usage: scripts/crosscheck_pfstmo.sh [IMAGE.exr] [KEY]     (env CLRT=path/to/clrt, DEVICE=spec)
#
# pfstmo_reinhard02 without --scales is the global operator of Reinhard et al. 2002:
#   Ȳ = exp(mean(log(1e-5 + Y))), L = key·Y/Ȳ, Yo = L(1 + L/L_max²)/(1 + L) with L_max the largest L,
#   no clamp, colours scaled by Yo/Y. clrt is configured to do the same:
#   --delta 1e-5        pfstmo's δ (clrt's default 1e-6 is the course's);
#   --burn 1e-5         the (100 − 1e-5)th percentile is the largest L (nearest rank, any n < 10^7);
#   --saturation 0      output grey Yo, so clrt's per-channel clamp to [0,1] cannot alter it (Yo <= 1);
#   --gamma 1, -o X.exr the float display values, not quantised to 8 bits.
# The luminance of both outputs (pfstools' own RGB->XYZ, Y = 0.2126R + 0.7152G + 0.0722B) is compared.
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/.." && pwd)
CLRT=${CLRT:-$ROOT/build/clrt}
IMAGE=${1:-$ROOT/../shared/envmaps/interior.exr}
KEY=${2:-0.18}
for tool in pfsin pfsout pfsclamp pfstmo_reinhard02 python3; do
    command -v "$tool" >/dev/null || { echo "crosscheck: $tool not found (apt-get install pfstmo pfstools)" >&2; exit 2; }
done
[ -x "$CLRT" ] || { echo "crosscheck: $CLRT is not built" >&2; exit 2; }
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT

# The shared maps hold a few slightly negative texels (DWA artefacts): clrt reads them as 0, pfstmo
# would take log() of them and turn the whole image into NaN. Both read one cleaned copy instead.
pfsin "$IMAGE" 2>/dev/null | pfsclamp --rgb --min 0 --max 1e30 | pfsout "$TMP/input.exr" 2>/dev/null
pfsin "$TMP/input.exr" 2>/dev/null | pfstmo_reinhard02 --key "$KEY" > "$TMP/pfstmo.pfs"
"$CLRT" tonemap "$TMP/input.exr" -o "$TMP/clrt.exr" --tmo photographic --key "$KEY" --burn 1e-5 --delta 1e-5 \
    --saturation 0 --gamma 1 ${DEVICE:+--device "$DEVICE"} -v
pfsin "$TMP/clrt.exr" 2>/dev/null > "$TMP/clrt.pfs"

python3 - "$TMP/pfstmo.pfs" "$TMP/clrt.pfs" "$IMAGE" <<'PY'
import sys, array

def read_pfs(path):
    """The channels of the first frame of a pfs stream: {name: array('f')}, width, height."""
    data = open(path, 'rb').read()
    pos = 0
    def line():
        nonlocal pos
        end = data.index(b'\n', pos)
        s = data[pos:end].decode('latin-1')
        pos = end + 1
        return s
    assert line() == 'PFS1', path + ': not a pfs stream'
    w, h = map(int, line().split())
    nch = int(line())
    for _ in range(int(line())): line()            # frame tags
    names = []
    for _ in range(nch):
        names.append(line())
        for _ in range(int(line())): line()        # channel tags
    assert data[pos:pos + 4] == b'ENDH', path + ': no ENDH'
    pos += 4
    chans = {}
    for n in names:
        a = array.array('f')
        a.frombytes(data[pos:pos + 4 * w * h])
        if sys.byteorder != 'little': a.byteswap()
        chans[n] = a
        pos += 4 * w * h
    return chans, w, h

ref, w, h = read_pfs(sys.argv[1])
got, w2, h2 = read_pfs(sys.argv[2])
assert (w, h) == (w2, h2), 'size mismatch'
yr, yg = ref['Y'], got['Y']
worst, worst_i, total, counted = 0.0, -1, 0.0, 0
for i in range(w * h):
    r, g = yr[i], yg[i]
    if r != r or g != g:                           # NaN: a failure, not a skip
        worst, worst_i = float('inf'), i
        break
    if r <= 1e-6 and g <= 1e-6: continue           # both black
    rel = abs(g - r) / max(r, 1e-6)
    total += rel; counted += 1
    if rel > worst: worst, worst_i = rel, i
print(f"crosscheck {sys.argv[3]}: {w}x{h}, {counted} non-black pixels; luminance mapping clrt vs pfstmo_reinhard02:")
print(f"  max relative difference {worst*100:.4f}% (pixel {worst_i % w},{worst_i // w}: pfstmo {yr[worst_i]:.6g}, clrt {yg[worst_i]:.6g}); mean {total/max(counted,1)*100:.5f}%")
print(f"  brightest: pfstmo {max(yr):.6f}, clrt {max(yg):.6f}")
ok = worst <= 0.01
print("  PASS (within 1%)" if ok else "  FAIL (more than 1%)")
sys.exit(0 if ok else 1)
PY
