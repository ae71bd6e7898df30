#!/usr/bin/env python3
"""instancing_threshold.py — where does clrt's two-level BVH trace as fast as the flattened scene?

For a height-field mesh (scripts/make_height_field.py) of several sizes placed K times (MeshInstance),
side by side in a grid ("grid": the instances' boxes do not overlap) or all over the same square, each
turned about z ("stack": every ray enters every instance, as in hw2's grass), runs
`ray_bench SCENE --instancing flatten` and `--instancing two-level` back to back, --rounds times
(each process: medians of --runs, Embree timed on the same rays right after clrt), and prints per kind
of ray (camera, shadow, diffuse) the medians over the rounds of clrt Mrays/s of both layouts, of
two-level/flattened, and of the same ratio of clrt/Embree (Embree traces the flattened scene in both
processes, so dividing by it cancels part of the machine's load).
Configurations whose flattened scene exceeds --max-seen triangles are skipped (ray_bench always builds
the flattened scene for Embree and for its ray sets). Standard library only. Run from the repository root.

usage: experiments/instancing_threshold.py [--sizes 90,181,362,724] [--placements 2,4,16]
       [--layouts grid,stack] [--rounds 3] [--runs 3] [--res 256] [--max-seen 4300000] [--extra SCENE.xml ...]
"""
import argparse
import math
import os
import statistics
import subprocess
import sys

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))
sys.path.insert(0, os.path.join(ROOT, "scripts"))
import make_height_field  # noqa: E402
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from ray_bench_ab import parse_rates  # noqa: E402

KINDS = ("camera", "shadow", "diffuse")

SCENE = """<Scene><BackgroundColor>0 0 0</BackgroundColor>
<Cameras><Camera id="1"><Position>%(cx)g %(cy)g %(cz)g</Position><Gaze>0 0 -1</Gaze><Up>0 1 0</Up>
<NearPlane>-0.5 0.5 -0.5 0.5</NearPlane><NearDistance>1</NearDistance>
<ImageResolution>%(res)d %(res)d</ImageResolution><ImageName>x.png</ImageName></Camera></Cameras>
<Lights><AmbientLight>20 20 20</AmbientLight>
<PointLight id="1"><Position>%(cx)g %(cy)g %(lz)g</Position><Intensity>500 500 500</Intensity></PointLight></Lights>
<Materials><Material id="1"><DiffuseReflectance>0.8 0.8 0.8</DiffuseReflectance></Material></Materials>
<Transformations>%(transforms)s</Transformations>
<Objects><Mesh id="1"><Material>1</Material><Transformations>%(t0)s</Transformations><Faces plyFile="%(ply)s"/></Mesh>
%(instances)s</Objects></Scene>
"""


def write_scene(path, ply, k, layout, res):
    """K placements of the unit height field `ply`: instance i > 0 is a MeshInstance of mesh 1."""
    transforms, names = [], []
    cols = int(math.ceil(math.sqrt(k)))
    for i in range(k):
        if layout == "grid":
            transforms.append('<Translation id="%d">%g %g 0</Translation>' % (i + 1, 1.05 * (i % cols), 1.05 * (i // cols)))
            names.append("t%d" % (i + 1))
        else:  # stack: turned about the square's centre, a little higher each
            transforms.append('<Translation id="%d">-0.5 -0.5 %g</Translation>' % (2 * i + 1, 0.01 * i))
            transforms.append('<Rotation id="%d">%g 0 0 1</Rotation>' % (2 * i + 2, 360.0 * i / k))
            transforms.append('<Translation id="%d">0.5 0.5 0</Translation>' % (2 * i + 1000))
            names.append("t%d r%d t%d" % (2 * i + 1, 2 * i + 2, 2 * i + 1000))
    span = 1.05 * (cols - 1) + 1 if layout == "grid" else 1.0
    inst = "\n".join('<MeshInstance id="%d" baseMeshId="1" resetTransform="true"><Transformations>%s</Transformations></MeshInstance>'
                     % (i + 1, names[i]) for i in range(1, k))
    with open(path, "w") as f:
        f.write(SCENE % dict(cx=span / 2, cy=span / 2, cz=span * 1.1, lz=span * 1.5, res=res, transforms="".join(transforms),
                             t0=names[0], ply=os.path.relpath(ply, os.path.dirname(path)), instances=inst))


def ray_bench(exe, scene, mode, runs):
    """{kind: (clrt Mrays/s, embree Mrays/s)} of one ray_bench process."""
    p = subprocess.run([exe, scene, "--runs", str(runs), "--instancing", mode], capture_output=True, text=True)
    if p.returncode != 0:
        sys.exit("ray_bench %s %s failed: %s" % (scene, mode, p.stderr.strip()))
    return parse_rates(p.stdout)


def measure(a, scene):
    """Rounds of (flatten, two-level) processes back to back: per kind, medians of clrt Mrays/s flat and
    two-level, of two/flat, and of two/flat with each divided by its process's Embree figure."""
    rounds = []
    for _ in range(a.rounds):
        rounds.append((ray_bench(a.ray_bench, scene, "flatten", a.runs), ray_bench(a.ray_bench, scene, "two-level", a.runs)))
    med = statistics.median
    out = {}
    for kind in KINDS:
        out[kind] = (med([f[kind][0] for f, _ in rounds]), med([t[kind][0] for _, t in rounds]),
                     med([t[kind][0] / f[kind][0] for f, t in rounds]),
                     med([(t[kind][0] / t[kind][1]) / (f[kind][0] / f[kind][1]) for f, t in rounds]))
    return out


def report(label, seen, m):
    cells = ["%.2f / %.2f (%.2f; %.2f)" % m[kind] for kind in KINDS]
    print("| %s | %s | %s |" % (label, "{:,}".format(seen) if seen else "(see ray_bench)", " | ".join(cells)), flush=True)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--sizes", default="90,181,362,724", help="height-field N (2*N*N triangles)")
    ap.add_argument("--placements", default="2,4,16")
    ap.add_argument("--layouts", default="grid,stack")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--res", type=int, default=256)
    ap.add_argument("--max-seen", type=int, default=4300000)
    ap.add_argument("--ray-bench", default=os.path.join(ROOT, "build", "ray_bench"))
    ap.add_argument("--work", default="/tmp/instancing_threshold")
    ap.add_argument("--extra", nargs="*", default=[], help="other scenes, as they are")
    a = ap.parse_args()
    os.makedirs(a.work, exist_ok=True)
    print("| scene | triangles as seen | camera: Mrays/s flat / two-level (two/flat; two/flat of clrt/Embree) | shadow | diffuse |")
    print("|---|---|---|---|---|")
    for scene in a.extra:
        report(os.path.basename(scene), None, measure(a, scene))
    for n in [int(x) for x in a.sizes.split(",")]:
        ply = os.path.join(a.work, "field%d.ply" % n)
        if not os.path.exists(ply):
            make_height_field.write_ply(n, ply)
        tris = 2 * n * n
        for layout in a.layouts.split(","):
            for k in [int(x) for x in a.placements.split(",")]:
                if k * tris > a.max_seen:
                    print("| %d tris x %d, %s | %d | skipped: flattened over %d |  |  |" % (tris, k, layout, k * tris, a.max_seen))
                    continue
                scene = os.path.join(a.work, "field%d_%s%d.xml" % (n, layout, k))
                write_scene(scene, ply, k, layout, a.res)
                report("%d tris x %d, %s" % (tris, k, layout), k * tris, measure(a, scene))


if __name__ == "__main__":
    main()
