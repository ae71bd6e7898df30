#!/usr/bin/env python3
"""time_variants.py — the SIMD-lanes prototype (experiments/simd_lanes/) against clrt's fused kernel.

Each variant is a kernel directory (a copy of cl_kernels/ whose render_fused is simd_proto.cl, with
simd_variant.h choosing the lane width and options; make_variants.sh builds them); "base" is clrt's
own kernels. Rounds alternate the variants; per run the fused kernel's seconds ("kernel time: ...
fused X s" of clrt render -v) are read. Prints the median, min and max per scene and variant, and the
ratio base/variant of the medians.

usage: time_variants.py CLRT VARIANT_ROOT SCENE[,SCENE...] [--rounds 5] [--spp 64] [--variants base,w4,...]
"""
import argparse, os, re, statistics, subprocess, sys, tempfile

ap = argparse.ArgumentParser()
ap.add_argument("clrt"); ap.add_argument("root"); ap.add_argument("scenes")
ap.add_argument("--rounds", type=int, default=5); ap.add_argument("--spp", type=int, default=64)
ap.add_argument("--variants", default="base,w4,w8,w16,w4one,w4lane,w8lane")
ap.add_argument("--device", default="cpu")
a = ap.parse_args()
variants = a.variants.split(",")
out = tempfile.mkdtemp()

def run(variant, scene):
    env = dict(os.environ)
    if variant != "base":
        env["CLRT_KERNEL_DIR"] = os.path.join(a.root, variant, "cl_kernels")
        env["CLRT_CACHE_DIR"] = os.path.join(a.root, variant, "cache")
    # --pipeline fused: the kernel the variants replace (auto would take render_lanes where it can)
    p = subprocess.run([a.clrt, "render", scene, "-o", out, "--spp", str(a.spp), "-v", "--device", a.device, "--pipeline", "fused"],
                       env=env, capture_output=True, text=True)
    m = re.search(r"fused ([0-9.]+)s", p.stdout + p.stderr)
    if not m:
        sys.exit("no fused time for %s on %s:\n%s" % (variant, scene, (p.stdout + p.stderr)[-2000:]))
    return float(m.group(1))

times = {}
for scene in a.scenes.split(","):
    for v in variants:
        run(v, scene)  # warm-up: kernel build and cache
    for r in range(a.rounds):
        for v in (variants if r % 2 == 0 else variants[::-1]):
            times.setdefault((scene, v), []).append(run(v, scene))
for scene in a.scenes.split(","):
    base = statistics.median(times[(scene, variants[0])])
    print(os.path.basename(scene))
    for v in variants:
        t = times[(scene, v)]
        med = statistics.median(t)
        print("  %-8s median %.3f s [%.3f-%.3f]  %s/variant %.2f" % (v, med, min(t), max(t), variants[0], base / med))
