#!/usr/bin/env python3
"""path_convergence.py — convergence of clrt's path tracer per option set (issue 16).

For every camera of hw6/cornellbox_jaroslav_path_diffuse.xml (one option set each) and for
spp in SPPS, REPEATS pairs of independent renders a, b (seeds 2k+1, 2k+2; every spp level has its own
seeds, so the levels share no samples) at SIZE² are compared: mean((a-b)²/(r²+1e-2))/2 is the relative
variance of one render, after BLOCK×BLOCK block means, averaged over the pairs; r is the course's
reference reduced to the same blocks (a fixed denominator: b's own noise in it would bias the estimate
at low spp). For an unbiased estimator of finite variance it falls as 1/spp: the slope of log relMSE
against log spp is fitted by least squares and must lie within 10% of -1.
--variant lowered [--gap G]: the scene with its LightMesh moved G (default 0.05) down, off the ceiling (the NEE check: the
course's area sampling of a light that touches the ceiling has infinite variance, see README).
Writes docs/studies/img/path_convergence.png (log-log plot) and prints one line per camera.
Usage: build/venv/bin/python experiments/path_convergence.py [--size 64] [--block 4] [--repeats 2]
       [--spp 4,16,64,256] [--device cpu] [--clrt build/clrt] [--only MIS,NEE] [--variant lowered [--gap 0.05]]"""
import argparse
import os
import subprocess
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "scripts"))
import exr_stats  # noqa: E402  (scripts/exr_stats.py)

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SCENE = os.path.join(ROOT, "..", "shared", "scenes", "hw6", "cornellbox_jaroslav_path_diffuse.xml")
REFS = os.path.join(ROOT, "..", "shared", "scenes", "hw6", "_reference_outputs")
CAMERAS = [(1, "diffuse_next", "NEE"), (2, "diffuse_next_russian", "NEE RR"), (3, "diffuse_next_importance", "NEE IS"),
           (4, "diffuse_next_importance_russian", "NEE IS RR"), (5, "diffuse", "IS (cam 5)"),
           (6, "diffuse_russian", "RR"), (7, "diffuse_importance", "IS"), (8, "diffuse_importance_russian", "IS RR"),
           (3, "diffuse_next_importance", "MIS")]  # camera 3 with clrt's MultipleImportanceSampling (a scene copy)


def render(clrt, scene, cam, spp, seed, size, device, out):
    os.makedirs(out, exist_ok=True)
    subprocess.run([clrt, "render", scene, "-o", out, "--camera", str(cam), "--spp",
                    str(spp), "--seed", str(seed), "--resolution", "%dx%d" % (size, size), "--device", device],
                   check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--size", type=int, default=64)
    ap.add_argument("--spp", default="4,16,64,256")
    ap.add_argument("--device", default="cpu")
    ap.add_argument("--clrt", default=os.path.join(ROOT, "build", "clrt"))
    ap.add_argument("--out", default=os.path.join(ROOT, "build", "path_convergence"))
    ap.add_argument("--only", default="", help="comma list of labels to run (default: all)")
    ap.add_argument("--plot", default=os.path.join(ROOT, "docs", "studies", "img", "path_convergence.png"))
    ap.add_argument("--block", type=int, default=4)
    ap.add_argument("--repeats", type=int, default=2)
    ap.add_argument("--variant", default="", help="'lowered': the LightMesh --gap below the ceiling")
    ap.add_argument("--gap", type=float, default=0.05, help="how far --variant lowered moves the light box down")
    args = ap.parse_args()
    spps = [int(s) for s in args.spp.split(",")]
    results = []
    worst = 0.0
    os.makedirs(args.out, exist_ok=True)
    mis_scene = os.path.join(args.out, "path_diffuse_mis.xml")
    with open(SCENE) as f:
        text = f.read()
    if args.variant == "lowered":  # the light box's z = 1.16 / 1.28 vertices, --gap down
        lo, hi = "%.5f" % (1.16002 - args.gap), "%.5f" % (1.28002 - args.gap)
        # "0.25     z" also matches the "-0.25     z" vertices: the box's eight corners, all moved
        if text.count("0.25     1.16002") != 4 or text.count("0.25     1.28002") != 4:
            sys.exit("path_convergence: the light box's eight vertices were not found in " + SCENE)
        text = text.replace("0.25     1.16002", "0.25     " + lo).replace("0.25     1.28002", "0.25     " + hi)
    base_scene = os.path.join(args.out, "path_diffuse_variant.xml")
    with open(base_scene, "w") as f:
        f.write(text)
    with open(mis_scene, "w") as f:  # camera 3 only (the first NEE + IS camera)
        f.write(text.replace("NextEventEstimation ImportanceSampling</RendererParams>",
                             "MultipleImportanceSampling</RendererParams>", 1))
    only = [o for o in args.only.split(",") if o]
    for cam, stem, label in CAMERAS:
        if only and label not in only:
            continue
        scene = mis_scene if label == "MIS" else base_scene
        errs = []
        for spp in spps:
            d = os.path.join(args.out, "c%d%s_s%d" % (cam, "mis" if label == "MIS" else "", spp))
            ref = exr_stats.down(exr_stats.load(os.path.join(REFS, stem + ".exr")), args.block * 512 // args.size)
            pair_errs = []
            for k in range(args.repeats):
                seeds = (1000 * spp + 2 * k + 1, 1000 * spp + 2 * k + 2)
                for seed in seeds:
                    render(args.clrt, scene, cam, spp, seed, args.size, args.device, os.path.join(d, str(seed)))
                a, b = (exr_stats.down(exr_stats.load(os.path.join(d, str(s), stem + ".exr")), args.block) for s in seeds)
                pair_errs.append(float(np.mean((a - b) ** 2 / (ref ** 2 + 1e-2))) / 2)
            errs.append(float(np.mean(pair_errs)))
        slope = float(np.polyfit(np.log(spps), np.log(errs), 1)[0])
        worst = max(worst, abs(slope + 1))
        results.append((label, errs, slope))
        print("camera %d %-10s relMSE %s slope %.3f %s" % (cam, label, " ".join("%.3g" % e for e in errs), slope,
                                                            "ok" if abs(slope + 1) <= 0.1 else "OUTSIDE 10%"))
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        fig, ax = plt.subplots(figsize=(7, 5))
        for label, errs, slope in results:
            ax.loglog(spps, errs, marker="o", label="%s (slope %.2f)" % (label, slope))
        ax.loglog(spps, [results[0][1][0] * spps[0] / s for s in spps], "k--", label="1/spp")
        ax.set_xlabel("samples per pixel")
        ax.set_ylabel("relMSE of one render (two independent renders / 2)")
        ax.set_title("clrt path tracing, cornellbox_jaroslav_path_diffuse%s, %d² (%dx%d blocks, %d pairs)"
                     % (" (light lowered %.2f)" % args.gap if args.variant else "", args.size, args.block, args.block, args.repeats), fontsize=9)
        ax.legend(fontsize=7)
        fig.tight_layout()
        fig.savefig(args.plot, dpi=110)
        print("wrote", args.plot)
    except ImportError:
        print("matplotlib missing: no plot")
    sys.exit(0 if worst <= 0.1 else 1)


if __name__ == "__main__":
    main()
