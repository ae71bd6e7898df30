#!/usr/bin/env python3
"""make_height_field.py N OUT.ply [--scene OUT.xml] — a binary little-endian PLY height field of
2*N*N triangles ((N+1)^2 vertices: float x y z; faces: list uchar int), z a smooth deterministic
bump pattern, for scripts/bench_scale and tests. With --scene, also a one-mesh clrt scene (one
64x64 camera above it, one point light) that places the PLY (path relative to the scene)."""
import math
import os
import struct
import sys


def write_ply(n, path):
    v = n + 1
    with open(path, "wb") as f:
        f.write(("ply\nformat binary_little_endian 1.0\nelement vertex %d\n"
                 "property float x\nproperty float y\nproperty float z\n"
                 "element face %d\nproperty list uchar int vertex_indices\nend_header\n" % (v * v, 2 * n * n)).encode())
        row = struct.Struct("<%df" % (3 * v))
        for j in range(v):
            y = j / n
            vals = []
            for i in range(v):
                x = i / n
                vals += (x, y, 0.05 * math.sin(12.0 * x) * math.cos(9.0 * y))
            f.write(row.pack(*vals))
        face_row = struct.Struct("<" + "B3i" * (2 * n))
        for j in range(n):
            vals = []
            base = j * v
            for i in range(n):
                a = base + i
                c = a + v
                vals += (3, a, a + 1, c + 1, 3, a, c + 1, c)
            f.write(face_row.pack(*vals))


SCENE = """<Scene>
    <BackgroundColor>0 0 0</BackgroundColor>
    <Cameras><Camera id="1"><Position>0.5 0.5 2</Position><Gaze>0 0 -1</Gaze><Up>0 1 0</Up>
        <NearPlane>-0.3 0.3 -0.3 0.3</NearPlane><NearDistance>1</NearDistance>
        <ImageResolution>64 64</ImageResolution><ImageName>%s.png</ImageName></Camera></Cameras>
    <Lights><AmbientLight>20 20 20</AmbientLight>
        <PointLight id="1"><Position>0.5 0.5 3</Position><Intensity>500 500 500</Intensity></PointLight></Lights>
    <Materials><Material id="1"><DiffuseReflectance>0.8 0.8 0.8</DiffuseReflectance></Material></Materials>
    <Objects><Mesh id="1"><Material>1</Material><Faces plyFile="%s"/></Mesh></Objects>
</Scene>
"""


def main():
    n, out = int(sys.argv[1]), sys.argv[2]
    write_ply(n, out)
    if "--scene" in sys.argv:
        scene = sys.argv[sys.argv.index("--scene") + 1]
        rel = os.path.relpath(out, os.path.dirname(os.path.abspath(scene)))
        stem = os.path.splitext(os.path.basename(scene))[0]
        with open(scene, "w") as f:
            f.write(SCENE % (stem, rel))


if __name__ == "__main__":
    main()
