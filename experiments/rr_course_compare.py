#!/usr/bin/env python3
"""rr_course_compare.py — per-region means and medians of clrt's Russian-roulette renders against the
course's references (hw6 cornellbox_jaroslav_path_diffuse cameras 2, 4, 6, 8; regions of
scripts/path_regions.py), study docs/studies/2026-12-03-russian-roulette-references.md.
Usage: build/bench-venv/bin/python experiments/rr_course_compare.py REFDIR DIR_A [DIR_B ...]
  For each RR image of REFDIR found in DIR_A, per region and channel: the ratio of the means (A/ref,
  B/ref, ...: with a DIR_B of the same rule and another seed, the renders' own spread), and the ratio
  of the clipped means (every pixel clipped at the reference's 99th percentile of that region and
  channel: robust against the heavy tails, yet continuous where a median sits on a discrete value or
  at zero)."""
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "scripts"))
import exr_stats  # noqa: E402
import path_regions  # noqa: E402

NAMES = ["diffuse_next_russian", "diffuse_next_importance_russian", "diffuse_russian", "diffuse_importance_russian"]


def fmt(v):
    return " ".join(f"{x:6.3f}" for x in v)


def clipped_means(img, ref):
    """Per region: the mean of img clipped at ref's 99th percentile (per channel), and that bound."""
    s = img.shape[0] / 512.0
    regions = path_regions.REGIONS + [("image", 0, 0, 512, 512)]
    out = {}
    for name, x0, y0, x1, y1 in regions:
        cut = lambda a: a[int(y0 * s):int(y1 * s), int(x0 * s):int(x1 * s)].reshape(-1, 3)
        bound = np.percentile(cut(ref), 99, axis=0)
        out[name] = np.minimum(cut(img), bound).mean(axis=0)
    return out


def main(argv):
    ref_dir, dirs = argv[0], argv[1:]
    for name in NAMES:
        paths = [os.path.join(d, name + ".exr") for d in dirs if os.path.exists(os.path.join(d, name + ".exr"))]
        if not paths:
            continue
        ref_img = exr_stats.load(os.path.join(ref_dir, name + ".exr"))
        ref, ref_clip = path_regions.region_means(ref_img), clipped_means(ref_img, ref_img)
        imgs = [exr_stats.load(p) for p in paths]
        runs = [path_regions.region_means(i) for i in imgs]
        clips = [clipped_means(i, ref_img) for i in imgs]
        print(name + "  (" + ", ".join(paths) + ")")
        for region in ref:
            line = f"  {region:8s} ref mean {fmt(ref[region][0])} | mean ratio"
            for r in runs:
                line += f" {fmt(r[region][0] / ref[region][0])} |"
            line += " clipped-mean ratio"
            for c in clips:
                line += f" {fmt(c[region] / np.maximum(ref_clip[region], 1e-9))} |"
            print(line)


if __name__ == "__main__":
    if len(sys.argv) < 3:
        print(__doc__)
        sys.exit(1)
    main(sys.argv[1:])
