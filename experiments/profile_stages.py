#!/usr/bin/env python3
"""profile_stages.py — where a render's time goes: runs `clrt render -v` on scenes (copies prepared as
scripts/bench does: bench/bench.py's SCENES, resolution reduced unless --full) `--runs` times, and prints
the median device time per kernel stage, the sum of kernels and the render stage (wall time of the
render on the host), for each clrt binary given (e.g. before and after a change).

usage: build/bench-venv/bin/python experiments/profile_stages.py [--spp 16] [--runs 3] [--scenes tt_diffuse,sphere_env_light_courtyard]
       [--full] [--clrt build/clrt[,other/clrt]] [--env-sampling S] [--pipelines wavefront,fused]
       (with build/bench-venv/bin/python). Every (binary, pipeline) variant is run once per round, the
       rounds interleaved, so that the machine's drift hits them alike; stages with no time are left out.
"""
import argparse
import os
import re
import statistics
import subprocess
import sys
import tempfile

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))
sys.path.insert(0, os.path.join(ROOT, "bench"))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--spp", type=int, default=16)
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--scenes", default="tt_diffuse,sphere_env_light_courtyard")
    ap.add_argument("--full", action="store_true", help="the scene's own resolution")
    ap.add_argument("--clrt", default=os.path.join(ROOT, "build", "clrt"))
    ap.add_argument("--env-sampling", default="", help="passed to clrt render (default: the scene's)")
    ap.add_argument("--pipelines", default="", help="comma list of clrt --pipeline values (default: clrt's choice)")
    a = ap.parse_args()
    import bench  # (bench.py needs numpy: run with the bench venv's python)
    tmp = tempfile.mkdtemp(prefix="clrt-prof-")
    out = os.path.join(tmp, "o")
    os.makedirs(out)
    for name in a.scenes.split(","):
        sc = next(s for s in bench.SCENES if s["name"] == name)
        if a.full:
            import xml.etree.ElementTree as ET
            cam = ET.parse(sc["path"]).getroot().find("Cameras")[0]
            sc = dict(sc, res=tuple(int(x) for x in cam.find("ImageResolution").text.split()))
        path, _ = bench.prepare_scene(sc, tmp)
        extra = ["--env-sampling", a.env_sampling] if a.env_sampling else []
        variants = [(exe, pipe) for exe in a.clrt.split(",") for pipe in (a.pipelines.split(",") if a.pipelines else [""])]
        stages = {v: {} for v in variants}
        render = {v: [] for v in variants}
        for exe, pipe in variants:  # warm-up
            subprocess.run([exe, "render", path, "-o", out, "--spp", str(a.spp)] + extra +
                           (["--pipeline", pipe] if pipe else []), capture_output=True)
        for run in range(a.runs):
            for v in variants:
                exe, pipe = v
                p = subprocess.run([exe, "render", path, "-o", out, "--spp", str(a.spp), "--seed", str(run + 1), "-v"] + extra +
                                   (["--pipeline", pipe] if pipe else []), capture_output=True, text=True)
                kt = re.search(r"kernel time: (.*?); all kernels ([0-9.]+)s of ([0-9.]+)s render", p.stderr + p.stdout)
                for st, t in re.findall(r"([a-z ]+?) ([0-9.]+)s", kt.group(1)):
                    stages[v].setdefault(st.strip(), []).append(float(t))
                stages[v].setdefault("all kernels", []).append(float(kt.group(2)))
                render[v].append(float(kt.group(3)))
        for v in variants:
            exe, pipe = v
            r = statistics.median(render[v])
            print("%s %dx%d %d spp%s, %s%s (medians of %d):" % (name, sc["res"][0], sc["res"][1], a.spp,
                  " " + a.env_sampling if a.env_sampling else "", os.path.relpath(exe, ROOT),
                  " --pipeline " + pipe if pipe else "", a.runs))
            for st, vals in stages[v].items():
                m = statistics.median(vals)
                if m > 0:
                    print("  %-16s %7.3f s  %5.1f%%" % (st, m, 100 * m / r))
            print("  %-16s %7.3f s  [%.3f-%.3f]" % ("render", r, min(render[v]), max(render[v])))


if __name__ == "__main__":
    main()
