#!/usr/bin/python3
"""Renders every scene of a folder with clrt and lays the images out on one contact sheet PNG.

usage: /usr/bin/python3 scripts/contact_sheet.py SCENE_DIR OUT.png [--spp N] [--device SPEC] [--cols C]

Each scene is rendered into a temporary folder (all its cameras); the sheet shows the first image of
each scene with the scene name and render time, or the error if it failed. Needs python3-matplotlib
and python3-numpy (Debian); installs them with apt-get when missing and running as root.
"""
import argparse
import glob
import os
import subprocess
import sys
import tempfile
import time


def ensure_matplotlib():
    try:
        import matplotlib  # noqa: F401
        import numpy  # noqa: F401
    except ImportError:
        subprocess.check_call(["apt-get", "install", "-y", "-qq", "python3-matplotlib", "python3-numpy"])


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("scene_dir")
    ap.add_argument("out")
    ap.add_argument("--spp", type=int, default=0, help="override samples per pixel (0: the scene's)")
    ap.add_argument("--device", default="")
    ap.add_argument("--cols", type=int, default=5)
    ap.add_argument("--clrt", default=os.path.join(os.path.dirname(__file__), "..", "build", "clrt"))
    args = ap.parse_args()
    ensure_matplotlib()
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    scenes = sorted(glob.glob(os.path.join(args.scene_dir, "*.xml")) + glob.glob(os.path.join(args.scene_dir, "*.json")))
    results = []
    for s in scenes:
        with tempfile.TemporaryDirectory() as tmp:
            cmd = [args.clrt, "render", s, "-o", tmp]
            if args.spp:
                cmd += ["--spp", str(args.spp)]
            if args.device:
                cmd += ["--device", args.device]
            t0 = time.time()
            p = subprocess.run(cmd, capture_output=True, text=True)
            dt = time.time() - t0
            imgs = sorted(glob.glob(os.path.join(tmp, "*.png")))
            img = plt.imread(imgs[0]) if (p.returncode == 0 and imgs) else None
            err = "" if p.returncode == 0 else (p.stderr.strip().splitlines() or ["exit %d" % p.returncode])[-1]
            print("%-40s %6.1fs %s" % (os.path.basename(s), dt, "ok" if not err else err), flush=True)
            results.append((os.path.basename(s), img, dt, err))

    n = len(results)
    cols = min(args.cols, max(n, 1))
    rows = (n + cols - 1) // cols
    fig, axes = plt.subplots(rows, cols, figsize=(3.2 * cols, 3.0 * rows), squeeze=False)
    for ax in axes.flat:
        ax.axis("off")
    for ax, (name, img, dt, err) in zip(axes.flat, results):
        if img is not None:
            ax.imshow(img)
            ax.set_title("%s (%.1fs)" % (name, dt), fontsize=8)
        else:
            ax.text(0.5, 0.5, "FAILED\n" + err[:80], ha="center", va="center", fontsize=6, wrap=True, color="red")
            ax.set_title(name, fontsize=8)
    fig.tight_layout()
    fig.savefig(args.out, dpi=100)
    print("wrote", args.out)
    return 0 if all(not r[3] for r in results) else 1


if __name__ == "__main__":
    sys.exit(main())
