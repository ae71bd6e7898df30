#!/usr/bin/env python3
"""make_sky_sun.py — writes scenes/sky_sun.exr, the lat-long sky of scenes/env_turned.xml, drawn for clrt:
a blue gradient above the horizon (radiance 0.3-0.8), a brown ground below (0.15), and a sun 6 degrees
wide of radiance 400 up and to the right of -z (direction (0.5, 0.55, -0.67)), in the lat-long mapping of
SCENE_FORMAT.md (u: phi = pi(2u - 1) from -z towards +x; v: theta = pi v from +y). An uncompressed
half-float OpenEXR written with the standard library alone.
usage: python3 scripts/make_sky_sun.py [OUT.exr]"""
import math
import struct
import sys

W, H = 128, 64
SUN = (0.5, 0.55, -0.67)


def radiance(u, v):
    th, ph = math.pi * v, math.pi * (2 * u - 1)
    d = (math.sin(th) * math.sin(ph), math.cos(th), -math.sin(th) * math.cos(ph))
    n = math.sqrt(sum(s * s for s in SUN))
    if sum(a * b / n for a, b in zip(d, SUN)) > math.cos(math.radians(3)):
        return (400.0, 390.0, 360.0)
    if d[1] < 0:
        return (0.15, 0.12, 0.09)
    return (0.8 - 0.5 * d[1], 0.85 - 0.4 * d[1], 1.0 - 0.2 * d[1])


def attribute(name, kind, value):
    return name.encode() + b"\0" + kind.encode() + b"\0" + struct.pack("<i", len(value)) + value


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else "scenes/sky_sun.exr"
    channels = b"".join(c + b"\0" + struct.pack("<iB3xii", 1, 0, 1, 1) for c in (b"B", b"G", b"R")) + b"\0"
    box = struct.pack("<iiii", 0, 0, W - 1, H - 1)
    header = (b"\x76\x2f\x31\x01" + struct.pack("<i", 2) + attribute("channels", "chlist", channels) +
              attribute("compression", "compression", b"\0") + attribute("dataWindow", "box2i", box) +
              attribute("displayWindow", "box2i", box) + attribute("lineOrder", "lineOrder", b"\0") +
              attribute("pixelAspectRatio", "float", struct.pack("<f", 1.0)) +
              attribute("screenWindowCenter", "v2f", struct.pack("<ff", 0.0, 0.0)) +
              attribute("screenWindowWidth", "float", struct.pack("<f", 1.0)) + b"\0")
    lines = []
    for y in range(H):
        px = [radiance((x + 0.5) / W, (y + 0.5) / H) for x in range(W)]
        data = b"".join(struct.pack("<%de" % W, *(p[c] for p in px)) for c in (2, 1, 0))  # B, G, R
        lines.append(struct.pack("<ii", y, len(data)) + data)
    offset = len(header) + 8 * H
    table = b""
    for line in lines:
        table += struct.pack("<Q", offset)
        offset += len(line)
    with open(out, "wb") as f:
        f.write(header + table + b"".join(lines))


if __name__ == "__main__":
    main()
