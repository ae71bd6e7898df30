"""path_noise_vs_mitsuba.py — where clrt's path tracer is noisier than Mitsuba 3's `path` on the hw6 box
(issue 32; docs/studies/2026-12-04-path-noise-vs-mitsuba.md). bench_mitsuba_path's box copy (camera 1,
PointLight removed, MIS, no roulette) at --res², --spp per render, --seeds renders per renderer.

Renderers: clrt with each --clrt-samplers (stratified, independent) for each --exe [LABEL=]PATH (LABEL
names the build in the table and the cache, default clrt), Mitsuba `path`
(llvm_ad_rgb) with each --mi-samplers, the light box (an open LightMesh: five faces, the ceiling closes
it) converted as two back-to-back copies (to_mitsuba_path's rule for an open mesh, open_lights
"two-sided"), or, for a sampler name ending in -outward (independent-outward), as one copy with every
face turned away from the box's centroid (open_lights "outward": the same image, the area clrt samples). For every renderer, depth d in --depths (clrt MaxRecursionDepth d,
Mitsuba max_depth d + 2) and seed: one image. Same seed, different depth: the same path prefixes in
both renderers (each draws its random numbers per depth, not per cap), so D_k = img(k) − img(k−1) is
the contribution of bounce k alone (checked: min D_k >= −1e-4 of the mean).
Per pixel: the variance over seeds (unbiased) of img(dmax) and of each D_k, relative to the common
reference (the mean of every renderer's img(dmax), all seeds): relVar = Var / (ref² + 0.01), averaged over
channels; its image mean is the expected relMSE of one render (bench.rel_mse's metric, W = 1).
Split by the surface a pixel's centre sees (a ray cast of the camera here: light, ceiling within 0.25 of
the light box, rest of the ceiling, back/left/right wall, floor, yellow/blue sphere) and by the top 1%
of pixels.
  CLRT_SHARED_SCENES=/work/shared/scenes DRJIT_LIBLLVM_PATH=... build/bench-venv/bin/python \
      experiments/path_noise_vs_mitsuba.py --exe build/clrt --cache /tmp/noise/run1
Images are cached in --cache (one .npy per render); a second call only analyses."""
import argparse
import os
import sys
import tempfile

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "bench"))
import bench as B  # noqa: E402
import bench_mitsuba_path as BMP  # noqa: E402

CAM = dict(pos=np.array([-0.0439815, -4.12529, 0.222539]), gaze=np.array([0.00688625, 0.998505, -0.0542161]),
           up=np.array([3.73896e-4, 0.0542148, 0.998529]), fovy=45.0)
X0, X1, Y0, Y1, Z0, Z1 = -1.27029, 1.28975, -1.25549, 1.30455, -1.28002, 1.28002
SPHERES = [("yellow sphere", np.array([-0.53885, 0.02453, -0.78002])), ("blue sphere", np.array([0.55831, 0.66454, -0.78002]))]
LIGHT = (-0.25, 0.25, -0.25, 0.25, 1.16002, 1.28002)
REGIONS = ["light", "ceiling near light", "ceiling rest", "back wall", "left wall", "right wall", "floor",
           "yellow sphere", "blue sphere"]


def labels(res):
    """Region index (REGIONS) of the surface each pixel's centre sees (row 0 at the top)."""
    w = CAM["gaze"] / np.linalg.norm(CAM["gaze"])
    u = np.cross(w, CAM["up"])
    u /= np.linalg.norm(u)
    v = np.cross(u, w)
    t = np.tan(np.radians(CAM["fovy"]) / 2)
    j, i = np.meshgrid(np.arange(res) + 0.5, np.arange(res) + 0.5)
    d = (2 * j / res - 1)[..., None] * t * u + (1 - 2 * i / res)[..., None] * t * v + w
    d /= np.linalg.norm(d, axis=-1, keepdims=True)
    o = CAM["pos"]
    best = np.full((res, res), np.inf)
    lab = np.full((res, res), -1)

    def take(tt, k):
        nonlocal best
        m = (tt > 1e-6) & (tt < best)
        best = np.where(m, tt, best)
        lab[m] = k if np.isscalar(k) else k[m]

    with np.errstate(divide="ignore", invalid="ignore"):
        for axis, val, name in ((2, Z0, "floor"), (2, Z1, "ceiling"), (0, X0, "left wall"), (0, X1, "right wall"),
                                (1, Y1, "back wall")):
            tt = (val - o[axis]) / d[..., axis]
            if name == "ceiling":
                p = o + tt[..., None] * d
                near = (np.abs(p[..., 0]) < 0.5) & (np.abs(p[..., 1]) < 0.5)
                take(tt, np.where(near, REGIONS.index("ceiling near light"), REGIONS.index("ceiling rest")))
            else:
                take(tt, REGIONS.index(name))
        for name, c in SPHERES:
            oc = o - c
            b = np.sum(d * oc, -1)
            disc = b * b - (oc @ oc - 0.25)
            tt = np.where(disc > 0, -b - np.sqrt(np.maximum(disc, 0)), np.inf)
            take(tt, REGIONS.index(name))
        lo = np.array([LIGHT[0], LIGHT[2], LIGHT[4]])
        hi = np.array([LIGHT[1], LIGHT[3], LIGHT[5]])
        ta, tb = (lo - o) / d, (hi - o) / d
        tn, tf = np.minimum(ta, tb).max(-1), np.maximum(ta, tb).min(-1)
        take(np.where(tn < tf, tn, np.inf), REGIONS.index("light"))
    return lab


def render_all(a, tmp):
    """{renderer: {depth: [images over seeds]}}, cached as .npy under a.cache."""
    os.makedirs(a.cache, exist_ok=True)
    out = {}
    depths = [int(x) for x in a.depths.split(",")]
    mi = None
    for exe in a.exe:
        label, exe = exe.split("=", 1) if "=" in exe else ("clrt", exe)
        clrt = B.Clrt(exe, "cpu", "--env-sampling")
        for smp in a.clrt_samplers.split(","):
            name = "%s-%s" % (label, smp)
            out[name] = {}
            for d in depths:
                scene = BMP.make_scene(dict(BMP.SCENES[0], res=(a.res, a.res), name="box"), tmp, depth=d)
                imgs = []
                for s in range(1, a.seeds + 1):
                    f = os.path.join(a.cache, "%s-d%d-%d-%d-s%d.npy" % (name, d, a.res, a.spp, s))
                    if not os.path.exists(f):
                        np.save(f, clrt.render(scene, a.spp, s, strategy="default+" + smp)[1])
                    imgs.append(np.load(f))
                out[name][d] = np.array(imgs)
            B.log("%s done" % name)
    for smp in filter(None, a.mi_samplers.split(",")):
        outward = smp.endswith("-outward")
        smp = smp.replace("-outward", "")
        name = "mitsuba-" + smp + ("-outward" if outward else "")
        out[name] = {}
        for d in depths:
            imgs = []
            ms = None
            for s in range(1, a.seeds + 1):
                f = os.path.join(a.cache, "%s-d%d-%d-%d-s%d.npy" % (name, d, a.res, a.spp, s))
                if not os.path.exists(f):
                    if ms is None:
                        if mi is None:
                            import drjit as dr
                            import mitsuba as mi
                            mi.set_variant("llvm_ad_rgb")
                            dr.set_thread_count(2)
                        scene = BMP.make_scene(dict(BMP.SCENES[0], res=(a.res, a.res), name="box"), tmp, depth=d)
                        ms = BMP.MitsubaPath(B, mi, scene, "llvm_ad_rgb", smp, "outward" if outward else "two-sided")
                    np.save(f, ms.image(a.spp, s))
                imgs.append(np.load(f))
            out[name][d] = np.array(imgs)
        B.log("%s done" % name)
    return out, depths


def rel_var(stack, ref):
    """Per-pixel variance over seeds (axis 0) relative to ref, averaged over channels."""
    return np.mean(np.var(stack, axis=0, ddof=1) / (ref ** 2 + B.EPS_REL), axis=-1)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--exe", action="append", required=True)
    ap.add_argument("--res", type=int, default=64)
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--seeds", type=int, default=16)
    ap.add_argument("--depths", default="0,1,2,3")
    ap.add_argument("--clrt-samplers", default="stratified,independent")
    ap.add_argument("--mi-samplers", default="independent")
    ap.add_argument("--cache", required=True)
    a = ap.parse_args()
    tmp = tempfile.mkdtemp(prefix="pathnoise-")
    imgs, depths = render_all(a, tmp)
    dmax = depths[-1]
    ref = np.mean([v[dmax].mean(0) for v in imgs.values()], axis=0)
    lab = labels(a.res)
    print("# hw6 box %d^2, %d spp per render, %d seeds; relVar = expected relMSE of one render" % (a.res, a.spp, a.seeds))
    print("mean per channel (d=%d): %s" % (dmax, "; ".join("%s %s" % (k, " ".join("%.4f" % x for x in v[dmax].mean((0, 1, 2))))
                                                           for k, v in imgs.items())))
    counts = [int((lab == r).sum()) for r in range(len(REGIONS))]
    print("region pixels: %s" % ", ".join("%s %d" % (n, c) for n, c in zip(REGIONS, counts)))
    rows = {}
    for k, v in imgs.items():
        full = rel_var(v[dmax], ref)
        parts = {"total": full}
        for i, d in enumerate(depths[1:], 1):
            diff = v[d] - v[depths[i - 1]]
            lowest = diff.min() / max(v[d].mean(), 1e-12)
            parts["D%d" % d] = rel_var(diff, ref)
            if lowest < -1e-4:  # e.g. a build whose last vertex weighs its light samples otherwise than the others
                B.log("%s: D_%d has min %.3g of the mean: not one bounce's contribution (n/a)" % (k, d, lowest))
                parts["D%d" % d] = np.full_like(full, np.nan)
        parts["d%d" % depths[0]] = rel_var(v[depths[0]], ref)
        rows[k] = parts
        np.save(os.path.join(a.cache, "relvar-%s.npy" % k), full)
    np.save(os.path.join(a.cache, "labels.npy"), lab)
    np.save(os.path.join(a.cache, "ref.npy"), ref)
    names = list(rows)
    print("\n| part | region | " + " | ".join(names) + " |")
    print("|---|---|" + "---|" * len(names))
    for part in rows[names[0]]:
        for r, rn in enumerate(REGIONS + ["all"]):
            m = np.ones_like(lab, dtype=bool) if rn == "all" else lab == r
            # share of the image's relMSE: sum over the region / number of pixels
            vals = [rows[n][part][m].sum() / lab.size for n in names]
            print("| %s | %s | %s |" % (part, rn, " | ".join("%.4g" % x for x in vals)))
    for n in names:
        full = rows[n]["total"]
        top = np.sort(full.ravel())[::-1]
        k1 = max(1, top.size // 100)
        worst = np.argsort(full.ravel())[::-1][:k1]
        where = np.bincount(lab.ravel()[worst], minlength=len(REGIONS))
        print("%s: relMSE %.4g, top-1%% share %.3f, top-1%% pixels by region: %s" % (
            n, full.mean(), top[:k1].sum() / top.sum(), ", ".join("%s %d" % (REGIONS[i], c) for i, c in enumerate(where) if c)))


if __name__ == "__main__":
    main()
