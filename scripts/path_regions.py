#!/usr/bin/env python3
"""path_regions.py — per-channel means of the large regions of hw6/cornellbox_jaroslav_path_diffuse's
view (back wall, floor, left/right walls, ceiling without the light, the two spheres) for linear EXRs
of any square size (regions are given in the reference's 512² pixels and scaled), issue 16's
Russian-roulette comparison. Also the median (robust against the references' heavy tails).
Usage: build/venv/bin/python scripts/path_regions.py A.exr [B.exr ...]
       build/venv/bin/python scripts/path_regions.py --table NAME CLRT_RR.exr CLRT_D40.exr REF_RR.exr REF_D3.exr
         (one block of docs/path_rr_regions.txt: the means side by side, and the ratio REF_RR / CLRT_RR)"""
import sys
import os

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import exr_stats  # noqa: E402

REGIONS = [("back", 130, 110, 390, 280), ("floor", 150, 460, 370, 510), ("left", 10, 120, 95, 400),
           ("right", 420, 120, 500, 400), ("ceiling", 130, 5, 390, 40), ("yellow", 130, 320, 230, 420),
           ("blue", 285, 305, 375, 395)]


def region_means(img):
    s = img.shape[0] / 512.0
    out = {}
    for name, x0, y0, x1, y1 in REGIONS:
        r = img[int(y0 * s):int(y1 * s), int(x0 * s):int(x1 * s)].reshape(-1, 3)
        out[name] = (r.mean(axis=0), np.median(r, axis=0))
    out["image"] = (img.reshape(-1, 3).mean(axis=0), np.median(img.reshape(-1, 3), axis=0))
    return out


def table(name, paths):
    ms = [region_means(exr_stats.load(p)) for p in paths]
    print(name)
    for k in ms[0]:
        cols = " | ".join("%.3f %.3f %.3f" % tuple(m[k][0]) for m in ms)
        ratio = ms[2][k][0] / np.maximum(ms[0][k][0], 1e-9)
        print("  %-7s | %s | ref/clrt %.2f %.2f %.2f" % ((k, cols) + tuple(ratio)))


def main(paths):
    if paths and paths[0] == "--table":
        return table(paths[1], paths[2:6])
    for p in paths:
        m = region_means(exr_stats.load(p))
        print(os.path.basename(os.path.dirname(p)) + "/" + os.path.basename(p))
        for k, (mean, med) in m.items():
            print("  %-8s mean %6.3f %6.3f %6.3f   median %6.3f %6.3f %6.3f" % ((k,) + tuple(mean) + tuple(med)))


if __name__ == "__main__":
    main(sys.argv[1:])
