#!/usr/bin/env python3
"""Quick timing of clrt renders: runs each scene N times and prints the median (and min/max) of the
`stats:` line's render seconds and Mrays/s. Not the full benchmark of the speed-vs-error issue; a
tool to check that a change is faster on this machine.

usage: python3 scripts/bench_quick.py [--runs 5] [--spp 1] [--device SPEC] SCENE...
"""
import argparse
import os
import re
import statistics
import subprocess
import sys
import tempfile


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("scenes", nargs="+")
    ap.add_argument("--runs", type=int, default=5)
    ap.add_argument("--spp", type=int, default=1)
    ap.add_argument("--device", default="")
    ap.add_argument("--clrt", default=os.path.join(os.path.dirname(__file__), "..", "build", "clrt"))
    a = ap.parse_args()
    print("%-40s %5s %10s %10s %10s %10s" % ("scene", "runs", "render_s", "camera", "shadow", "secondary"))
    for scene in a.scenes:
        rows = []
        with tempfile.TemporaryDirectory() as tmp:
            for _ in range(a.runs):
                cmd = [a.clrt, "render", scene, "-o", tmp, "--spp", str(a.spp)]
                if a.device:
                    cmd += ["--device", a.device]
                p = subprocess.run(cmd, capture_output=True, text=True)
                if p.returncode != 0:
                    print(scene, "failed:", p.stderr.strip().splitlines()[-1:], file=sys.stderr)
                    break
                m = re.search(r"^stats: (.*)$", p.stdout, re.M)
                kv = dict(x.split("=") for x in m.group(1).split())
                rows.append({k: float(v.rstrip("s")) for k, v in kv.items()})
        if not rows:
            continue
        med = lambda k: statistics.median(r[k] for r in rows)
        spread = lambda k: "%.3f-%.3f" % (min(r[k] for r in rows), max(r[k] for r in rows))
        print("%-40s %5d %10.3f %10.2f %10.2f %10.2f   (render %s s)" % (
            os.path.basename(scene), len(rows), med("render"), med("camera_mrays"), med("shadow_mrays"),
            med("secondary_mrays"), spread("render")))


if __name__ == "__main__":
    sys.exit(main())
