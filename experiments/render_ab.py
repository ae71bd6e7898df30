#!/usr/bin/env python3
"""render_ab.py — two clrt builds (old, new) rendering the same scene alternately, for time per sample.

The render-side sibling of ray_bench_ab.py: on a shared machine the load drifts, so each round renders
with OLD then NEW (the order swapped every other round) and the figure is the median over rounds of the
paired ratio new/old of the `stats:` line's render seconds, with its min–max. The first render of each
build (kernel compile into each build's own CLRT_CACHE_DIR) is not counted. Both builds' images are
compared byte for byte after the EXR header's renderTime (`identical` column). Standard library only.

usage: experiments/render_ab.py OLD_CLRT NEW_CLRT SCENE [--rounds 7] [-- extra clrt render options]
"""
import argparse
import os
import re
import statistics
import subprocess
import sys
import tempfile


def render(exe, scene, out, cache, extra):
    env = dict(os.environ, CLRT_CACHE_DIR=cache)
    p = subprocess.run([exe, "render", scene, "-o", out] + extra, capture_output=True, text=True, env=env)
    if p.returncode != 0:
        sys.exit("%s failed: %s" % (exe, p.stderr.strip()[-2000:]))
    m = re.search(r"stats:.*\brender=([0-9.]+)s", p.stdout + p.stderr)
    if not m:
        sys.exit("%s: no stats line" % exe)
    return float(m.group(1))


def pixels(folder):
    """Each image's bytes from its last header attribute on (renderTime is before it)."""
    out = {}
    for name in sorted(os.listdir(folder)):
        data = open(os.path.join(folder, name), "rb").read()
        i = data.find(b"screenWindowWidth") if name.endswith(".exr") else 0
        out[name] = data[max(i, 0):]
    return out


def main():
    argv = sys.argv[1:]
    extra = []
    if "--" in argv:
        extra = argv[argv.index("--") + 1:]
        argv = argv[:argv.index("--")]
    ap = argparse.ArgumentParser()
    ap.add_argument("old")
    ap.add_argument("new")
    ap.add_argument("scene")
    ap.add_argument("--rounds", type=int, default=7)
    a = ap.parse_args(argv)
    tmp = tempfile.mkdtemp(prefix="render_ab_")
    dirs = {}
    for side, exe in (("old", a.old), ("new", a.new)):
        dirs[side] = os.path.join(tmp, side)
        os.makedirs(dirs[side])
        render(exe, a.scene, dirs[side], os.path.join(tmp, "cache_" + side), extra)  # compile, not counted
    times = {"old": [], "new": []}
    for r in range(a.rounds):
        order = ("old", "new") if r % 2 == 0 else ("new", "old")
        for side in order:
            exe = a.old if side == "old" else a.new
            times[side].append(render(exe, a.scene, dirs[side], os.path.join(tmp, "cache_" + side), extra))
    ratios = [n / o for o, n in zip(times["old"], times["new"])]
    same = pixels(dirs["old"]) == pixels(dirs["new"])
    print("scene %s %s" % (os.path.basename(a.scene), " ".join(extra)))
    print("render s old median %.3f [%.3f-%.3f]  new median %.3f [%.3f-%.3f]" % (
        statistics.median(times["old"]), min(times["old"]), max(times["old"]),
        statistics.median(times["new"]), min(times["new"]), max(times["new"])))
    print("new/old paired median %.3f [%.3f-%.3f] over %d rounds; images identical: %s" % (
        statistics.median(ratios), min(ratios), max(ratios), a.rounds, "yes" if same else "NO"))


if __name__ == "__main__":
    main()
