#!/usr/bin/python3
"""Renders every scene of a folder with clrt and lays the images out on one contact sheet PNG.

usage: /usr/bin/python3 scripts/contact_sheet.py SCENE_DIR [SCENE_DIR...] OUT.png [--spp N] [--device SPEC]
                                                 [--cols C] [--references DIR|auto] [--ldr-quantize floor|round]

Each scene is rendered into a temporary folder (all its cameras); the sheet shows the first image of
each scene with the scene name and render time, or the error if it failed. With --references (a folder
of the course's reference PNGs, named as the scene's ImageName), each scene is one row instead:
reference | clrt | |difference| x4, with the PSNR of clrt against the reference (8-bit); --references auto
takes each scene's own SCENE_DIR/_reference_outputs (several folders on one sheet, e.g. hw1 hw2 hw2/grass hw3).
Scenes render at their own NumSamples unless --spp is given. Needs python3-matplotlib
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
    ap.add_argument("scene_dirs", nargs="+")
    ap.add_argument("out")
    ap.add_argument("--spp", type=int, default=0, help="override samples per pixel (0: the scene's)")
    ap.add_argument("--device", default="")
    ap.add_argument("--cols", type=int, default=5)
    ap.add_argument("--references", default="", help="folder of reference PNGs, or auto (each scene folder's "
                    "_reference_outputs): one row per scene with the difference")
    ap.add_argument("--ldr-quantize", default="", help="passed to clrt render (floor: the course's 8-bit convention)")
    ap.add_argument("--clrt", default=os.path.join(os.path.dirname(__file__), "..", "build", "clrt"))
    args = ap.parse_args()
    ensure_matplotlib()
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    scenes = []
    for d in args.scene_dirs:
        scenes += sorted(glob.glob(os.path.join(d, "*.xml")) + glob.glob(os.path.join(d, "*.json")))
    results = []
    for s in scenes:
        with tempfile.TemporaryDirectory() as tmp:
            cmd = [args.clrt, "render", s, "-o", tmp]
            if args.spp:
                cmd += ["--spp", str(args.spp)]
            if args.device:
                cmd += ["--device", args.device]
            if args.ldr_quantize:
                cmd += ["--ldr-quantize", args.ldr_quantize]
            t0 = time.time()
            p = subprocess.run(cmd, capture_output=True, text=True)
            dt = time.time() - t0
            imgs = sorted(glob.glob(os.path.join(tmp, "*.png")))
            img = plt.imread(imgs[0]) if (p.returncode == 0 and imgs) else None
            err = "" if p.returncode == 0 else (p.stderr.strip().splitlines() or ["exit %d" % p.returncode])[-1]
            print("%-40s %6.1fs %s" % (os.path.basename(s), dt, "ok" if not err else err), flush=True)
            ref = None
            if args.references and imgs:
                refs = os.path.join(os.path.dirname(s), "_reference_outputs") if args.references == "auto" else args.references
                rp = os.path.join(refs, os.path.basename(imgs[0]))
                ref = plt.imread(rp)[..., :3] if os.path.exists(rp) else None
            label = os.path.join(os.path.basename(os.path.dirname(s)), os.path.basename(s)) if len(args.scene_dirs) > 1 \
                else os.path.basename(s)
            results.append((label, img, dt, err, ref))

    if args.references:
        return reference_sheet(results, args.out, plt, np)
    n = len(results)
    cols = min(args.cols, max(n, 1))
    rows = (n + cols - 1) // cols
    fig, axes = plt.subplots(rows, cols, figsize=(3.2 * cols, 3.0 * rows), squeeze=False)
    for ax in axes.flat:
        ax.axis("off")
    for ax, (name, img, dt, err, _) in zip(axes.flat, results):
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


def reference_sheet(results, out, plt, np):
    """One row per scene: reference | clrt | |clrt - reference| x 4 (8-bit values), PSNR in the title."""
    fig, axes = plt.subplots(len(results), 3, figsize=(9.0, 3.1 * len(results)), squeeze=False)
    ok = True
    for row, (name, img, dt, err, ref) in zip(axes, results):
        for ax in row:
            ax.axis("off")
        if img is None or ref is None or img.shape[:2] != ref.shape[:2]:
            ok = False
            row[1].text(0.5, 0.5, "FAILED\n" + (err or "no reference or size mismatch")[:80], ha="center", va="center",
                        fontsize=6, color="red")
            row[1].set_title(name, fontsize=8)
            continue
        a = np.round(img[..., :3] * 255.0)
        b = np.round(ref * 255.0)
        mse = float(np.mean((a - b) ** 2))
        psnr = float("inf") if mse == 0 else 10.0 * np.log10(255.0 ** 2 / mse)
        row[0].imshow(ref)
        row[0].set_title("%s: reference" % name, fontsize=8)
        row[1].imshow(img[..., :3])
        row[1].set_title("clrt (%.1fs), PSNR %.1f dB" % (dt, psnr), fontsize=8)
        row[2].imshow(np.clip(np.abs(a - b) * 4.0, 0, 255).astype(np.uint8))
        row[2].set_title("|difference| x4", fontsize=8)
    fig.tight_layout()
    fig.savefig(out, dpi=80)
    print("wrote", out)
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
