#!/usr/bin/env python3
"""compare_hit_dumps.py — what differs between two `ray_bench SCENE --runs 1 --dump FILE` dumps.

A dump holds, as raw bytes: the camera rays' hits twice (warm-up and timed run), the shadow rays
(dev::ShadowRay, 48 bytes: contribution 0 = occluded) and the diffuse rays' hits (dev::Hit, 16 bytes:
t, prim, u, v). Shadow and diffuse rays start at the camera hits (one per camera ray that hit), so a
camera hit on another primitive moves them too. Two hits are the same if t, u and v are bit for bit
(the primitive's number is not compared: the renderer stores triangles in leaf order, so another tree
renumbers them; the same triangle gives the same t, u, v). Counts:
  camera: rays whose hit differs; of those, ties (the same t bit for bit, another u, v: another
          triangle at the same distance, e.g. a ray through a shared edge or coincident triangles)
          and the rest (a real difference);
  shadow, diffuse: rays that differ: those whose camera ray's hit moved (so the ray itself moved),
          ties (diffuse: same t, another u, v) and the rest (a real difference).
usage: experiments/compare_hit_dumps.py OLD NEW CAMERA_RAYS   (standard library only)
"""
import struct
import sys


def main():
    old, new = open(sys.argv[1], "rb").read(), open(sys.argv[2], "rb").read()
    if len(old) != len(new):
        sys.exit("sizes differ: %d vs %d bytes" % (len(old), len(new)))
    cam = int(sys.argv[3])  # the camera ray count ray_bench prints
    if (len(old) - 32 * cam) % 64:
        sys.exit("the dump does not hold %d camera rays" % cam)
    nsec = (len(old) - 32 * cam) // 64
    camOld = struct.unpack_from("<" + "fiff" * cam, old, 16 * cam)
    camNew = struct.unpack_from("<" + "fiff" * cam, new, 16 * cam)
    tBits = lambda v, i: struct.pack("<f", v[4 * i])
    ties = real = 0
    moved = set()  # camera rays (by the index of their shadow/diffuse ray) whose hit differs
    k = 0
    for i in range(cam):
        a, b = camOld[4 * i:4 * i + 4], camNew[4 * i:4 * i + 4]
        if (a[0], a[2], a[3]) != (b[0], b[2], b[3]) or (a[1] < 0) != (b[1] < 0):
            if tBits(camOld, i) == tBits(camNew, i) and a[1] >= 0 and b[1] >= 0:
                ties += 1
            else:
                real += 1
            moved.add(k)
        k += a[1] >= 0
    print("camera: %d rays, %d differ: %d ties (same t, another u, v), %d other" % (cam, ties + real, ties, real))
    for name, off, size in (("shadow", 32 * cam, 48), ("diffuse", 32 * cam + 48 * nsec, 16)):
        fromMoved = tie = other = 0
        for j in range(nsec):
            a, b = old[off + size * j:off + size * (j + 1)], new[off + size * j:off + size * (j + 1)]
            if a == b or (size == 16 and a[:4] + a[8:] == b[:4] + b[8:] and
                          (struct.unpack("<i", a[4:8])[0] < 0) == (struct.unpack("<i", b[4:8])[0] < 0)):
                continue
            if j in moved:
                fromMoved += 1
            elif size == 16 and a[:4] == b[:4] and struct.unpack("<i", a[4:8])[0] >= 0 and struct.unpack("<i", b[4:8])[0] >= 0:
                tie += 1
            else:
                other += 1
        print("%s: %d rays, %d differ: %d from a moved camera hit, %d ties, %d other" %
              (name, nsec, fromMoved + tie + other, fromMoved, tie, other))

if __name__ == "__main__":
    main()
