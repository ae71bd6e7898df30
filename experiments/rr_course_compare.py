#!/usr/bin/env python3
"""rr_course_compare.py — per-region means and medians of clrt's Russian-roulette renders against the
course's references (hw6 cornellbox_jaroslav_path_diffuse cameras 2, 4, 6, 8; regions of
scripts/path_regions.py), study docs/studies/2026-12-03-russian-roulette-references.md.
Usage: build/bench-venv/bin/python experiments/rr_course_compare.py REFDIR DIR_A [DIR_B ...]
  For each RR image of REFDIR found in DIR_A: per region the reference's mean, DIR_A's mean and the
  ratio A/ref per channel; the same for medians (robust against the heavy tails); with a DIR_B (the
  same rule, another seed) also B/ref, the two renders' own spread."""
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "scripts"))
import exr_stats  # noqa: E402
import path_regions  # noqa: E402

NAMES = ["diffuse_next_russian", "diffuse_next_importance_russian", "diffuse_russian", "diffuse_importance_russian"]


def fmt(v):
    return " ".join(f"{x:6.3f}" for x in v)


def main(argv):
    ref_dir, dirs = argv[0], argv[1:]
    for name in NAMES:
        imgs = [os.path.join(d, name + ".exr") for d in dirs]
        if not os.path.exists(imgs[0]):
            continue
        ref = path_regions.region_means(exr_stats.load(os.path.join(ref_dir, name + ".exr")))
        runs = [path_regions.region_means(exr_stats.load(p)) for p in imgs if os.path.exists(p)]
        print(name)
        for region in ref:
            rm, rmed = ref[region]
            line = f"  {region:8s} ref {fmt(rm)} | clrt {fmt(runs[0][region][0])} | mean ratio"
            for r in runs:
                line += f" {fmt(r[region][0] / rm)} |"
            line += " median ratio"
            for r in runs:
                line += f" {fmt(r[region][1] / np.maximum(rmed, 1e-9))} |"
            print(line)


if __name__ == "__main__":
    if len(sys.argv) < 3:
        print(__doc__)
        sys.exit(1)
    main(sys.argv[1:])
