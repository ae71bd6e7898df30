#!/usr/bin/env python3
"""env_mis_compare.py — does environment MIS ever lose? For each environment map (the shared ones in
../shared/envmaps and a dim map with one very hot texel made here), renders a diffuse sphere that fills
most of the frame with every --env-sampling strategy, `--runs` seeds each at `--spp`, against an
independent high-spp reference (two halves, importance sampling), and prints relMSE per strategy, MIS's
ratio to the best single strategy at equal spp, and at equal time (relMSE x render s).

usage: build/bench-venv/bin/python experiments/env_mis_compare.py [--spp 16] [--runs 3] [--ref-spp 1024]
       [--maps courtyard,night,...] [--res 96x72] [--out FILE.md]
Needs build/clrt and numpy + OpenEXR (scripts/bench's venv has both).
"""
import argparse
import os
import re
import statistics
import subprocess
import sys
import tempfile

import numpy as np

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))
ENVMAPS = os.path.abspath(os.path.join(ROOT, "..", "shared", "envmaps"))
STRATS = ["uniform", "cosine", "importance", "mis"]
BASELINE = ""

SCENE = """<Scene>
  <Cameras><Camera id="1" type="lookAt"><Position>0 0 0</Position><GazePoint>0 0 -1</GazePoint><Up>0 1 0</Up>
    <FovY>36</FovY><NearDistance>1</NearDistance><ImageResolution>{w} {h}</ImageResolution><ImageName>img.exr</ImageName>
  </Camera></Cameras>
  <VertexData>0 0 -6</VertexData>
  <Materials><Material id="1"><DiffuseReflectance>0.8 0.8 0.8</DiffuseReflectance></Material></Materials>
  <Textures><Images><Image id="1">{map}</Image></Images></Textures>
  <Lights><SphericalDirectionalLight id="1" sampler="{sampler}"><ImageId>1</ImageId></SphericalDirectionalLight></Lights>
  <Objects><Sphere id="1"><Center>1</Center><Radius>2</Radius><Material>1</Material></Sphere></Objects>
</Scene>
"""


def write_exr(path, img):
    import OpenEXR
    OpenEXR.File({"compression": OpenEXR.ZIP_COMPRESSION}, {"RGB": np.ascontiguousarray(img.astype(np.float32))}).write(path)


def read_exr(path):
    import OpenEXR
    with OpenEXR.File(path) as f:
        ch = f.channels()
        a = ch["RGB"].pixels if "RGB" in ch else ch["RGBA"].pixels[..., :3]
    return np.asarray(a, dtype=np.float64)


def hot_texel_map(path):
    """A dim map (0.02) with one texel 2e5 times brighter, up and in front of the sphere's visible side."""
    img = np.full((128, 256, 3), 0.02, dtype=np.float32)
    img[40, 100] = 4000.0  # v = 40.5/128 (~57 deg from up), u = 100.5/256 (in front, to the left)
    write_exr(path, img)


def render(exe, scene, spp, seed, out):
    exe = BASELINE if scene.endswith("_mis-baseline.xml") else exe
    p = subprocess.run([exe, "render", scene, "-o", out, "--spp", str(spp), "--seed", str(seed)], capture_output=True, text=True)
    if p.returncode:
        sys.exit(p.stderr)
    st = re.search(r"render=([0-9.]+)s", p.stdout)
    return float(st.group(1)), read_exr(os.path.join(out, "img.exr"))


def rel_mse(x, r):
    return float(np.mean((x - r) ** 2 / (r ** 2 + 1e-2)))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--spp", type=int, default=16)
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--ref-spp", type=int, default=1024)
    ap.add_argument("--res", default="96x72")
    ap.add_argument("--maps", default="courtyard,night,studio,sunset,hot_texel")
    ap.add_argument("--out", default="")
    ap.add_argument("--baseline", default="", help="another clrt whose mis is listed too (e.g. before a change)")
    a = ap.parse_args()
    w, h = (int(x) for x in a.res.split("x"))
    global BASELINE, STRATS
    if a.baseline:
        BASELINE = os.path.abspath(a.baseline)
        STRATS = STRATS + ["mis-baseline"]
    exe = os.path.join(ROOT, "build", "clrt")
    tmp = tempfile.mkdtemp(prefix="clrt-envmis-")
    out = os.path.join(tmp, "o")
    os.makedirs(out)
    lines = None
    for m in a.maps.split(","):
        path = os.path.join(tmp, "hot.exr") if m == "hot_texel" else os.path.join(ENVMAPS, m + ".exr")
        if m == "hot_texel":
            hot_texel_map(path)
        scenes = {}
        for s in STRATS:
            scenes[s] = os.path.join(tmp, "%s_%s.xml" % (m, s))
            open(scenes[s], "w").write(SCENE.format(w=w, h=h, map=path, sampler=s.replace("-baseline", "")))
        _, ra = render(exe, scenes["importance"], a.ref_spp // 2, 1000001, out)
        _, rb = render(exe, scenes["importance"], a.ref_spp // 2, 1000002, out)
        ref = 0.5 * (ra + rb)
        floor = rel_mse(ra, rb) / 4  # approximately: the halves' difference, as bench.py
        res = {}
        for s in STRATS:
            render(exe, scenes[s], 1, 0, out)  # warm-up
        # Interleaved (run k of every strategy, then run k+1): drift of a shared machine hits all alike.
        ts, es, ms = {s: [] for s in STRATS}, {s: [] for s in STRATS}, {s: [] for s in STRATS}
        for run in range(a.runs):
            for s in STRATS:
                t, img = render(exe, scenes[s], a.spp, run + 1, out)
                ts[s].append(t)
                es[s].append(rel_mse(img, ref))
                ms[s].append(float(np.mean(img) / np.mean(ref)))
        for s in STRATS:
            res[s] = (statistics.median(es[s]), statistics.median(ts[s]), statistics.mean(ms[s]))
            print("%-10s %-12s relMSE %.4g  render %.3fs [%.3f-%.3f]  mean/ref %.4f" % (
                m, s, res[s][0], res[s][1], min(ts[s]), max(ts[s]), res[s][2]), file=sys.stderr, flush=True)
        if lines is None:
            lines = ["| map | " + " | ".join(STRATS) + " | best single (at equal time) | MIS/best relMSE (equal spp) | "
                     "MIS/best relMSE·s (equal time) | render s: " + " / ".join(STRATS) + " |",
                     "|---|" + "---|" * (len(STRATS) + 4)]
        singles = [s for s in STRATS if not s.startswith("mis")]
        best = min(singles, key=lambda s: res[s][0])
        best_t = min(singles, key=lambda s: res[s][0] * res[s][1])
        lines.append("| %s | %s | %s (%s) | %.2f | %.2f | %s |" % (
            m, " | ".join("%.3g" % res[s][0] for s in STRATS), best, best_t, res["mis"][0] / res[best][0],
            (res["mis"][0] * res["mis"][1]) / (res[best_t][0] * res[best_t][1]),
            " / ".join("%.3f" % res[s][1] for s in STRATS)))
        print("  reference floor %.3g; best at equal time: %s" % (floor, best_t), file=sys.stderr)
    text = "\n".join(lines)
    print(text)
    if a.out:
        open(a.out, "w").write(text + "\n")


if __name__ == "__main__":
    main()
