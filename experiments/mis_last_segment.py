"""MIS at the last path vertex (docs/studies/2026-12-04-mitsuba-path.md, addendum): noise and mean of clrt's
MultipleImportanceSampling against its NextEventEstimation on the hw6 box (bench_mitsuba_path's scene copy).
For each binary (--exe, repeatable: e.g. a build before and after a change), each strategy and each of
--pairs seed pairs: relMSE between two independent renders (seeds 2k+1, 2k+2; bench.rel_mse, W = 1)
and the share of that error in the top 1% of pixels; and the MIS/NEE ratio of the
image means at each --depth (--mean-spp in two halves of seeds 11, 12; SE from their per-pixel differences).
  CLRT_SHARED_SCENES=/work/shared/scenes python experiments/mis_last_segment.py --exe build/clrt ...
Prints one line per measurement."""
import argparse
import os
import sys
import tempfile

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "bench"))
import bench as B  # noqa: E402
import bench_mitsuba_path as BMP  # noqa: E402

STRATEGIES = {"NEE": "NextEventEstimation ImportanceSampling", "MIS": "MultipleImportanceSampling"}


def scene(tmp, res, depth, label):
    sc = dict(BMP.SCENES[0], res=(res, res), name="box-%s" % label)
    return BMP.make_scene(sc, tmp, depth=depth, params=STRATEGIES[label])


def noise(clrt, path, spp, pairs):
    out = []
    for k in range(pairs):
        a = clrt.render(path, spp, 2 * k + 1)[1]
        b = clrt.render(path, spp, 2 * k + 2)[1]
        per = np.mean((a - b) ** 2 / (b ** 2 + B.EPS_REL), axis=-1)  # bench.rel_mse(a, b, 1) per pixel
        top = np.sort(per.ravel())[::-1]
        out.append((float(np.mean(per)), float(top[:max(1, top.size // 100)].sum() / top.sum())))
    return out


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--exe", action="append", required=True)
    ap.add_argument("--res", type=int, default=64)
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--pairs", type=int, default=3)
    ap.add_argument("--depth", type=int, default=3)
    ap.add_argument("--mean-depths", default="0,3")
    ap.add_argument("--mean-spp", type=int, default=1024)
    a = ap.parse_args()
    tmp = tempfile.mkdtemp(prefix="mislast-")
    for exe in a.exe:
        clrt = B.Clrt(exe, None, "--env-sampling")
        for label in STRATEGIES:
            r = noise(clrt, scene(tmp, a.res, a.depth, label), a.spp, a.pairs)
            print("%s %s d=%d %d^2 %d spp: relMSE %s (mean %.4f), top-1%% share %s" % (
                exe, label, a.depth, a.res, a.spp, " ".join("%.4f" % x for x, _ in r), np.mean([x for x, _ in r]),
                " ".join("%.3f" % s for _, s in r)), flush=True)
        for d in (int(x) for x in a.mean_depths.split(",") if x):
            m = {}
            for label in STRATEGIES:  # two halves: the per-pixel differences give the mean's standard error
                path = scene(tmp, a.res, d, label)
                h1, h2 = (clrt.render(path, a.mean_spp // 2, seed)[1] for seed in (11, 12))
                m[label] = (0.5 * (h1 + h2)).mean(axis=(0, 1)), np.sqrt(np.mean((h1 - h2) ** 2, axis=(0, 1)) / (4 * h1[..., 0].size))
            ratio = m["MIS"][0] / m["NEE"][0]
            se = ratio * np.hypot(m["MIS"][1] / m["MIS"][0], m["NEE"][1] / m["NEE"][0])
            print("%s d=%d %d spp: mean MIS/NEE (R G B) %s, SE %s" % (
                exe, d, a.mean_spp, " ".join("%.4f" % x for x in ratio), " ".join("%.4f" % x for x in se)), flush=True)


if __name__ == "__main__":
    main()
