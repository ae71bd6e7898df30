"""sampler_compare.py — relMSE of clrt's pixel samplers (--sampler stratified / zsobol / independent) at
equal spp on the benchmark's direct-lighting scenes (bench/bench.py SCENES, resolution halved) and the
path scenes (bench/bench_path.py: the hw6 path box and its glass variant, MIS and NEE+RR), for the
study docs/studies/2026-12-04-sobol-sampler.md. Reference per scene: `stratified` at REF_SPP as two
independent halves; its own relMSE (relMSE(half a, half b) / 4) is subtracted from every point. Also the
render time of each run (clrt's stats line: kernel seconds), so a sampler's cost shows separately.
Writes CSV rows to stdout: scene, sampler, spp, seed, relmse, floor, seconds, and relmse2: the relMSE
after a 2x2 box downsample of image and reference (floor not subtracted), which credits error that
cancels between neighbouring pixels (the Z order's blue noise) where per-pixel relMSE cannot.
usage: python3 experiments/sampler_compare.py CLRT_EXE [scene ...] [--spp 4,16,64] [--runs 3]"""
import os
import sys
import tempfile

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "bench"))
import bench  # noqa: E402
import bench_path  # noqa: E402

import numpy as np  # noqa: E402

REF_SPP = int(os.environ.get("CLRT_REF_SPP", "1024"))  # the reference: stratified, two halves


def scenes(tmp):
    """name -> (scene copy, white): the bench scenes at half resolution, the path scenes at 64x64 (MIS, NEE+RR)."""
    out = {}
    for sc in bench.SCENES:
        if sc["name"] == "tt_diffuse":
            continue
        sc = dict(sc, res=(sc["res"][0] // 2, sc["res"][1] // 2))
        path, hdr = bench.prepare_scene(sc, tmp)
        out[sc["name"]] = (path, 1.0 if hdr else 255.0)
    for sc in bench_path.PATH_SCENES:
        for label, params in (("MIS", "MultipleImportanceSampling"), ("NEE+RR", "NextEventEstimation RussianRoulette")):
            sc2 = dict(sc, res=(64, 64))
            out[sc["name"] + "_" + label] = (bench_path.make_scene(sc2, params, tmp, label), 1.0)  # bench_path: white 1
    return out


def box2(a):
    """a (h, w, 3) averaged over 2x2 pixel blocks (odd last row/column dropped)."""
    h, w = a.shape[0] // 2 * 2, a.shape[1] // 2 * 2
    a = a[:h, :w]
    return 0.25 * (a[0::2, 0::2] + a[1::2, 0::2] + a[0::2, 1::2] + a[1::2, 1::2])


def main():
    exe = sys.argv[1]
    args = sys.argv[2:]
    spps, runs = [4, 16, 64], 3
    if "--spp" in args:
        i = args.index("--spp"); spps = [int(x) for x in args[i + 1].split(",")]; del args[i:i + 2]
    if "--runs" in args:
        i = args.index("--runs"); runs = int(args[i + 1]); del args[i:i + 2]
    clrt = bench.Clrt(exe, os.environ.get("CLRT_DEVICE", "cpu"), "--env-sampling")
    tmp = tempfile.mkdtemp(prefix="sampler-cmp-")
    all_scenes = scenes(tmp)
    names = args or list(all_scenes)
    print("scene,sampler,spp,seed,relmse,floor,seconds,relmse2", flush=True)
    for name in names:
        path, white = all_scenes[name]
        _, a, _ = clrt.render(path, REF_SPP // 2, 1000001, "default+stratified")
        _, b, _ = clrt.render(path, REF_SPP // 2, 1000002, "default+stratified")
        ref = 0.5 * (a + b)
        floor = bench.rel_mse(a, b, white) / 4
        for spp in spps:
            for seed in range(1, runs + 1):
                for smp in ("stratified", "zsobol", "independent"):
                    st, img, _ = clrt.render(path, spp, seed, "default+" + smp)
                    e = bench.rel_mse(img, ref, white) - floor
                    e2 = bench.rel_mse(box2(img), box2(ref), white)
                    print("%s,%s,%d,%d,%.6g,%.3g,%.4f,%.6g" % (name, smp, spp, seed, e, floor, st.get("render", st["wall"]), e2),
                          flush=True)


if __name__ == "__main__":
    main()
