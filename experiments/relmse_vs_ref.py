#!/usr/bin/env python3
# relmse_vs_ref.py — relMSE of clrt renders against a bench reference (bench/results/refs/<scene>-.../
# half_a.npy, half_b.npy), for kernel variants side by side, and a bias check. The same relMSE as
# bench/bench.py (mean of (x - ref)^2 / (ref^2 + 0.01)). Usage (the bench venv):
#   build/bench-venv/bin/python experiments/relmse_vs_ref.py SCENE REFDIR --spp 16 --seeds 3 [--kernels A,B]
#       renders seeds 1..N with build/clrt (--pipeline, default fused); --kernels: CLRT_KERNEL_DIR values
#       (directories holding cl_kernels/ and src/shared/ copies), one column each.
#   ... --bias --spp 512: two renders (seeds 101, 102) averaged; prints relMSE against the reference and the
#       sum of both noise floors it should match if the expectations agree, and the per-channel mean ratio.
import argparse, os, re, subprocess, tempfile, numpy as np, OpenEXR

ap = argparse.ArgumentParser()
ap.add_argument("scene"); ap.add_argument("refdir")
ap.add_argument("--spp", type=int, default=16); ap.add_argument("--seeds", type=int, default=3)
ap.add_argument("--kernels", default=""); ap.add_argument("--bias", action="store_true")
ap.add_argument("--pipeline", default="fused")
ap.add_argument("--clrt", default=os.path.join(os.path.dirname(__file__), "..", "build", "clrt"))
a = ap.parse_args()

def read(path):
    with OpenEXR.File(path) as f:
        ch = f.channels(); px = ch["RGB"].pixels if "RGB" in ch else ch["RGBA"].pixels[..., :3]
    return np.asarray(px, np.float64)

def render(seed, kdir=""):
    env = dict(os.environ)
    if kdir: env.update(CLRT_KERNEL_DIR=os.path.join(kdir, "cl_kernels"), CLRT_CACHE_DIR=os.path.join(kdir, "cache"))
    with tempfile.TemporaryDirectory() as out:
        p = subprocess.run([a.clrt, "render", a.scene, "--spp", str(a.spp), "--seed", str(seed), "-o", out, "-v",
                            "--pipeline", a.pipeline], env=env, capture_output=True, text=True, check=True)
        m = re.search(r"render ([0-9.]+)s", p.stderr + p.stdout)
        return read(os.path.join(out, "img.exr")), float(m.group(1)) if m else float("nan")

ha, hb = np.load(os.path.join(a.refdir, "half_a.npy")), np.load(os.path.join(a.refdir, "half_b.npy"))
ref = (ha + hb) / 2
rel = lambda x, r: float(np.mean((x - r) ** 2 / (r ** 2 + 1e-2)))
if a.bias:
    (x1, _), (x2, _) = render(101), render(102)
    x = (x1 + x2) / 2
    floor = rel(x1, x2) / 4 + rel(ha, hb) / 4
    print("relMSE(renders, reference) %.3g; both noise floors %.3g; ratio %.3f" % (rel(x, ref), floor, rel(x, ref) / floor))
    print("mean ratio renders/reference per channel", (x.reshape(-1, 3).mean(0) / ref.reshape(-1, 3).mean(0)).round(5))
else:
    variants = a.kernels.split(",") if a.kernels else [""]
    res = {v: [] for v in variants}
    for s in range(1, a.seeds + 1):
        for v in variants:  # interleaved, so drift of the machine's load hits all alike
            img, t = render(s, v)
            res[v].append((rel(img, ref), t))
    for v in variants:
        e = [r for r, _ in res[v]]; t = [t for _, t in res[v]]
        print("%s: relMSE mean %.4g [%s], render s median %.3f" % (v or "build/clrt", np.mean(e), " ".join("%.4g" % x for x in e), np.median(t)))
