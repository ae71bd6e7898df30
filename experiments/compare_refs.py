#!/usr/bin/env python3
"""compare_refs.py — are two sets of benchmark references the same image in expectation?

Each reference folder of bench/bench.py (REFS/<scene>-<hash>-<spp>-<strategy>/half_a.npy, half_b.npy)
holds two independent halves; its noise floor is mean((a-b)^2/(ref^2 + 0.01))/4. For every reference
present in both OLD and NEW (same folder name: same scene, inputs, spp and strategy), this prints the
relMSE between the two references, the sum of their floors (what that relMSE is when they differ by
noise alone), their ratio (~1: no change in expectation; a bias adds to it), and the per-channel ratio
of their means. Used for issue 18's sampler change (README, "Sampler"): OLD rendered with the
independent sampler, NEW with the stratified one.

usage: experiments/compare_refs.py OLD_REFS NEW_REFS        (numpy; e.g. build/bench-venv/bin/python)
"""
import os
import sys

import numpy as np


def halves(d):
    return [np.load(os.path.join(d, "half_%s.npy" % h)).astype(np.float64) for h in "ab"]


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__.strip().splitlines()[-1])
    old_root, new_root = sys.argv[1:]
    rel = lambda a, b: float(np.mean((a - b) ** 2 / (b ** 2 + 0.01)))
    common = sorted(set(os.listdir(old_root)) & set(os.listdir(new_root)))
    for name in common:
        if not os.path.exists(os.path.join(old_root, name, "half_a.npy")):
            continue
        (oa, ob), (na, nb) = halves(os.path.join(old_root, name)), halves(os.path.join(new_root, name))
        ro, rn = 0.5 * (oa + ob), 0.5 * (na + nb)
        fo = float(np.mean((oa - ob) ** 2 / (ro ** 2 + 0.01))) / 4
        fn = float(np.mean((na - nb) ** 2 / (rn ** 2 + 0.01))) / 4
        d = rel(rn, ro)
        means = rn.reshape(-1, 3).mean(0) / ro.reshape(-1, 3).mean(0)
        print("%s: relMSE(new, old) %.3g; floors old %.3g + new %.3g = %.3g; ratio %.2f; means new/old %s"
              % (name, d, fo, fn, fo + fn, d / (fo + fn), " ".join("%.5f" % m for m in means)))


if __name__ == "__main__":
    main()
