#!/usr/bin/env python3
"""rr_glass_blocks.py — the course's glass box (hw6/hw7 cornellbox_jaroslav_path_glass.xml, 512², 100 spp) against
its references, per block of scripts/check_course's 8x8 grid, for kernel variants (CLRT_KERNEL_DIR).

  rr   the roulette cameras (--rr-rule course, --sampler independent, seeds 2s-1 and 2s, every K-th row): each
       block's clipped-mean ratio clrt / reference (check_course's roulette rule: clipped at the reference's 95th
       percentile of the block) for the glass sphere's blocks, the worst block's score (ok <= 1) and how many
       block values are over.
  noise a camera without roulette: per block mse(a, ref) / mse(a, b) (relMSE weights) of two renders: about 1 where
       the reference is as noisy as clrt, 0.5 where it has no noise.
  values the glass sphere's pixel values (green, x 130-229, y 320-419) times the spp, as a histogram with 1-wide
       bins (the bins holding at least 8 pixels), for the reference and one clrt render (--seed SEED, --rr-rule
       course on roulette cameras): a pixel whose 100 samples are one light hit and 99 zeros shows that sample's
       value, so the peaks are the rule's sample values (Le·kd/(1 - F) = 26.8 on camera 8: both Fresnel children).

Usage (from the repository root; the EXR reader is scripts/check_course's venv):
  build/check-venv/bin/python experiments/rr_glass_blocks.py rr    SCENE CAMS SEEDPAIR K [KERNEL_DIR]
  [SEEDS=1,2] build/check-venv/bin/python experiments/rr_glass_blocks.py noise SCENE CAM K [KERNEL_DIR]
  build/check-venv/bin/python experiments/rr_glass_blocks.py values SCENE CAM SEED [KERNEL_DIR]
SCENE: the glass box's XML with its references beside it (e.g. a copy of the course's 2020 package,
chroma-works/Chroma-RayTracer assets/scenes/hw7/pathTracing). Study: docs/studies/2026-12-03-russian-roulette-
references.md, addendum 2026-12-05.
"""
import os
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "scripts"))
import check_course as cc  # noqa: E402
import numpy as np  # noqa: E402

GLASS = [(5, 1), (5, 2), (6, 1), (6, 2), (5, 3), (4, 2)]   # the glass sphere's blocks (row, column)


def renders(scene, cam, seeds, k, kernel_dir, extra):
    env = dict(os.environ, CLRT_CACHE_DIR=os.path.join(tempfile.gettempdir(), "rr_glass_cache_" +
                                                       (kernel_dir or "main").replace("/", "_")))
    if kernel_dir:
        env["CLRT_KERNEL_DIR"] = kernel_dir
    out = []
    with tempfile.TemporaryDirectory() as tmp:
        for seed in seeds:
            cmd = [os.path.join(ROOT, "build", "clrt"), "render", scene, "-o", tmp, "--camera", cam["id"],
                   "--seed", str(seed), "--sampler", os.environ.get("SAMPLER", "independent")] + extra
            name = cam["image"]
            if k > 1:
                cmd += ["--part", "1/%d" % k, "--tile-pixels", "512"]
                name += ".part1of%d.exr" % k
            subprocess.run(cmd, env=env, check=True, capture_output=True)
            out.append(cc.read_image(os.path.join(tmp, name)))
    return out


def rr(scene, cams, pair, k, kernel_dir):
    for cam in cc.cameras_of(cc.load_scene_tree(scene)):
        if cam["id"] not in cams:
            continue
        ref = cc.read_image(os.path.join(os.path.dirname(scene), cam["image"]))
        h, w = ref.shape[:2]
        imgs = renders(scene, cam, (2 * pair - 1, 2 * pair), k, kernel_dir, ["--rr-rule", "course"])
        bound = np.percentile(cc.blocks(ref, 8), 95, axis=2, keepdims=True)
        picked = cc.blocks(np.repeat((np.arange(h) % k == 0)[:, None, None], w, axis=1).repeat(3, axis=2), 8)
        sel = picked[0, 0, :, 0] > 0
        ca, cb, cr = (np.minimum(cc.blocks(i, 8)[:, :, sel], bound) for i in (*imgs, ref))
        n = ca.shape[2]
        m, mr = 0.5 * (ca.mean(axis=2) + cb.mean(axis=2)), cr.mean(axis=2)
        sigma = np.sqrt((ca - cb).var(axis=2) / 2.0 * (1.0 / (2.0 * n) + 1.0 / n))
        score = np.abs(m - mr) / (0.01 * mr + 4 * sigma)
        ratio = m / np.maximum(mr, 1e-12)
        bi, bj, ch = np.unravel_index(int(np.argmax(score)), score.shape)
        print("cam %s seeds %d,%d: glass blocks %s | worst %.2f at %d%d (%.3f), %d over" % (
            cam["id"], 2 * pair - 1, 2 * pair, " ".join("%d%d:%.3f" % (i, j, ratio[i, j].mean()) for i, j in GLASS),
            score.max(), bi, bj, ratio[bi, bj, ch], int((score > 1).sum())), flush=True)


def noise(scene, cam_id, k, kernel_dir):
    cam = [c for c in cc.cameras_of(cc.load_scene_tree(scene)) if c["id"] == cam_id][0]
    ref = cc.read_image(os.path.join(os.path.dirname(scene), cam["image"]))
    seeds = tuple(int(x) for x in os.environ.get("SEEDS", "1,2").split(","))   # SEEDS=3,4: another pair
    a, b = (x[::k] for x in renders(scene, cam, seeds, k, kernel_dir, []))
    r = ref[::k]
    wgt = 1.0 / (r ** 2 + 1e-2)
    A, B, R, W = (cc.blocks(x, 8) for x in (a, b, r, wgt))
    ratio = (W * (A - R) ** 2).mean(axis=(2, 3)) / (W * (A - B) ** 2).mean(axis=(2, 3))
    np.set_printoptions(precision=2, linewidth=150)
    print("cam %s (%s): mse(a, ref) / mse(a, b) per block" % (cam_id, cam["image"]))
    print(ratio)


def values(scene, cam_id, seed, kernel_dir):
    cam = [c for c in cc.cameras_of(cc.load_scene_tree(scene)) if c["id"] == cam_id][0]
    ref = cc.read_image(os.path.join(os.path.dirname(scene), cam["image"]))
    extra = ["--rr-rule", "course"] if cam["rr"] else []
    img = renders(scene, cam, (seed,), 1, kernel_dir, extra)[0]
    spp = float(cam["spp"])
    for name, x in (("reference", ref), ("clrt", img)):
        v = x[320:420, 130:230, 1].ravel() * spp
        h, e = np.histogram(v, bins=np.arange(0.5, 130.5, 1.0))
        print("%s: zero pixels %.3f, clipped (95th pct) mean %.2f" % (name, np.mean(v == 0),
                                                                    np.minimum(v, np.percentile(v, 95)).mean()))
        print("  " + "  ".join("%.1f:%d" % (a, b) for a, b in zip(e, h) if b >= 8))


if __name__ == "__main__":
    if len(sys.argv) >= 6 and sys.argv[1] == "rr":
        rr(sys.argv[2], sys.argv[3].split(","), int(sys.argv[4]), int(sys.argv[5]), sys.argv[6] if len(sys.argv) > 6 else "")
    elif len(sys.argv) >= 5 and sys.argv[1] == "values":
        values(sys.argv[2], sys.argv[3], int(sys.argv[4]), sys.argv[5] if len(sys.argv) > 5 else "")
    elif len(sys.argv) >= 5 and sys.argv[1] == "noise":
        noise(sys.argv[2], sys.argv[3], int(sys.argv[4]), sys.argv[5] if len(sys.argv) > 5 else "")
    else:
        sys.exit(__doc__)
