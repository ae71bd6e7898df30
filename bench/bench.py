#!/usr/bin/env python3
"""Speed against error: the benchmark behind `scripts/bench` (see bench/README.md).

Renders a fixed set of small scenes with clrt on one device, several runs (seeds) per point, and writes
bench/results/<device>/:
  bench.csv         one row per (scene, strategy, spp): medians and spreads of stage times, Mrays/s,
                    relMSE, RMSE, FLIP, efficiency, and the reference's spp and noise floor
  runs.csv          every single run
  refs.csv          the references: spp, seeds, their own estimated relMSE/RMSE, FLIP between halves
  features.csv      specialised build vs --all-features (render time; cold/warm kernel build time)
  ray_bench.txt/csv clrt's intersection kernels vs Embree 3 (bench/ray_bench.cpp), when built
  <scene>.png       relMSE and FLIP against render time (log-log, one curve per strategy, the
                    reference's noise floor dashed) and efficiency 1/(relMSE x time) against spp
  report.md         all tables

Runs with Debian's python3 (numpy, matplotlib) plus OpenEXR and flip-evaluator from PyPI
(scripts/bench puts them into a venv under the build folder).
"""
import argparse
import csv
import hashlib
import json
import os
import re
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
import types
import xml.etree.ElementTree as ET

import numpy as np

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))
SHARED = os.path.abspath(os.path.join(ROOT, "..", "shared", "scenes"))

# The fixed scene set. res: the resolution the copy is rendered at; spp: the points of each curve;
# ref_spp: the reference (two independent halves of ref_spp/2); env: sampling strategies apply.
SCENES = [
    dict(name="demo", path=os.path.join(ROOT, "scenes", "demo.xml"), res=(320, 240), spp=[1, 4, 16, 64], ref_spp=1024),
    dict(name="cube_point", path=os.path.join(SHARED, "hw5", "cube_point.xml"), res=(200, 200), spp=[1, 4, 16, 64], ref_spp=1024),
    dict(name="veachAjar", path=os.path.join(SHARED, "classic", "veachAjar.xml"), res=(256, 180), spp=[1, 4, 16, 64], ref_spp=1024),
    dict(name="sphere_env_light_courtyard", path=os.path.join(SHARED, "hw5", "sphere_env_light_courtyard.xml"),
         res=(256, 128), spp=[1, 4, 16, 64, 256], ref_spp=4096, env=True, mitsuba=True),
    dict(name="tt_pisa_courtyard", path=os.path.join(SHARED, "hw5", "tt", "scene_pisa_courtyard.xml"),
         res=(300, 167), spp=[1, 4, 16, 64], ref_spp=1024, env=True),
    # Issue 18's comparison scene: the Audi TT with specular and mirror reflectance zeroed and the
    # textures dropped (a diffuse-only copy that Mitsuba renders the same; see bench/to_mitsuba.py).
    dict(name="tt_diffuse", path=os.path.join(SHARED, "hw5", "tt", "scene_pisa_courtyard.xml"),
         res=(300, 167), spp=[1, 4, 16, 64], ref_spp=1024, env=True, diffuse=True, mitsuba=True),
]
FEATURE_SPP = 16
FEATURE_SCENES = ["cube_point", "veachAjar", "tt_pisa_courtyard"]
RAY_BENCH_SCENES = ["cube_point", "veachAjar", "tt_pisa_courtyard"]
ALL_STRATEGIES = ["uniform", "cosine", "importance", "mis"]
REF_SEEDS = (1000001, 1000002)
CLRT_SAMPLERS = ("stratified", "independent", "zsobol")  # clrt render --sampler
MITSUBA_SAMPLERS = ("independent", "stratified", "multijitter", "ldsampler", "orthogonal")
EPS_REL = 1e-2


def log(*a):
    print(*a, file=sys.stderr, flush=True)


# ---------------------------------------------------------------------------------------------- scenes
def prepare_scene(sc, tmpdir):
    """A copy of the scene with ImageResolution reduced, one camera, ImageName -> img.exr and every
    relative path (PLY, binaryFile, Image) made absolute, so it can live outside the read-only tree.
    Returns (path, hdr) where hdr tells whether the original camera wrote an .exr (an HDR scene)."""
    src = sc["path"]
    base = os.path.dirname(os.path.abspath(src))
    tree = ET.parse(src)
    root = tree.getroot()
    absp = lambda p: p if os.path.isabs(p) else os.path.normpath(os.path.join(base, p))
    for el in root.iter():
        for attr in ("plyFile", "binaryFile"):
            if attr in el.attrib:
                el.attrib[attr] = absp(el.attrib[attr])
    for img in root.iter("Image"):
        if img.text and img.text.strip():
            img.text = absp(img.text.strip())
    if sc.get("diffuse"):
        make_diffuse(root)
    cams = root.find("Cameras")
    hdr = False
    for i, cam in enumerate(list(cams)):
        if i > 0:
            cams.remove(cam)
            continue
        name = cam.find("ImageName")
        hdr = name.text.strip().lower().endswith(".exr")
        name.text = "img.exr"
        cam.find("ImageResolution").text = "%d %d" % sc["res"]
        # A Scissor (if any) would refer to the original resolution.
        for s in cam.findall("Scissor"):
            cam.remove(s)
    out = os.path.join(tmpdir, sc["name"] + ".xml")
    tree.write(out)
    return out, hdr


def make_diffuse(root):
    """Diffuse-only copy: specular and mirror reflectance zeroed, material types (mirror, ...) and
    per-object textures removed."""
    for m in root.iter("Material"):
        m.attrib.pop("type", None)
        for tag in ("SpecularReflectance", "MirrorReflectance"):
            for e in m.findall(tag):
                e.text = "0 0 0"
    for obj in root.iter():
        for t in obj.findall("Textures"):
            if obj.tag != "Scene":
                obj.remove(t)


def scene_hash(path):
    """sha256 of the rewritten scene and the contents of every file it refers to."""
    h = hashlib.sha256()
    data = open(path, "rb").read()
    h.update(data)
    text = data.decode("utf-8", "replace")
    files = re.findall(r'(?:plyFile|binaryFile)="([^"]+)"', text) + re.findall(r"<Image[^>]*>([^<]+)</Image>", text)
    for f in sorted(set(files)):
        h.update(f.encode())
        try:
            with open(f, "rb") as fh:
                for chunk in iter(lambda: fh.read(1 << 20), b""):
                    h.update(chunk)
        except OSError:
            h.update(b"missing")
    return h.hexdigest()[:16]


# ----------------------------------------------------------------------------------------------- clrt
class Clrt:
    def __init__(self, exe, device, env_flag):
        self.exe, self.device, self.env_flag = exe, device, env_flag

    def render(self, scene, spp, seed, strategy=None, all_features=False, env=None, verbose=False):
        out = tempfile.mkdtemp(prefix="clrt-bench-")
        cmd = [self.exe, "render", scene, "-o", out, "--spp", str(spp), "--seed", str(seed)]
        if self.device:
            cmd += ["--device", self.device]
        # "mis+fused+independent": --env-sampling mis --pipeline fused --sampler independent
        strategy, *extra = (strategy or "").split("+")
        for x in extra:
            cmd += ["--sampler" if x in CLRT_SAMPLERS else "--pipeline", x]
        if strategy and strategy != "default":
            cmd += [self.env_flag, strategy]
        if all_features:
            cmd.append("--all-features")
        if verbose:
            cmd.append("-v")
        t0 = time.perf_counter()
        p = subprocess.run(cmd, capture_output=True, text=True, env=env)
        wall = time.perf_counter() - t0
        if p.returncode != 0:
            shutil.rmtree(out, ignore_errors=True)
            raise RuntimeError("%s failed (%d): %s" % (" ".join(cmd), p.returncode, p.stderr.strip()[-600:]))
        m = re.search(r"^stats: (.*)$", p.stdout, re.M)
        stats = {k: float(v.rstrip("s")) for k, v in (x.split("=") for x in m.group(1).split())}
        stats["wall"] = wall
        stats.pop("spp", None)
        img = read_exr(os.path.join(out, "img.exr"))
        shutil.rmtree(out, ignore_errors=True)
        return stats, img, p.stderr


def read_exr(path):
    import OpenEXR
    with OpenEXR.File(path) as f:
        ch = f.channels()
        if "RGB" in ch:
            a = ch["RGB"].pixels
        elif "RGBA" in ch:
            a = ch["RGBA"].pixels[..., :3]
        else:
            a = np.stack([ch[c].pixels for c in ("R", "G", "B")], axis=-1)
    return np.asarray(a, dtype=np.float64)


# -------------------------------------------------------------------------------------------- metrics
def rel_mse(x, ref, white=1.0):
    """mean over pixels and channels of (x-ref)^2 / (ref^2 + 1e-2 white^2): images in units of the
    display white (255 for the course's LDR scenes, whose PNGs clamp radiance at 255; 1 for HDR ones)."""
    return float(np.mean((x - ref) ** 2 / (ref ** 2 + EPS_REL * white * white)))


def rmse(x, ref):
    return float(np.sqrt(np.mean((x - ref) ** 2)))


def lum(a):
    return 0.2126 * a[..., 0] + 0.7152 * a[..., 1] + 0.0722 * a[..., 2]


def to_ldr(a, ref, hdr):
    """The display both images of a FLIP comparison go through (the same for test and reference).
    LDR scenes (the course writes them as PNG: radiance clamped to [0,255]): a/255 clamped.
    HDR scenes: global Reinhard with key 0.18 on the reference's log-average luminance,
    x/(1+x) per channel, then gamma 1/2.2 (the scenes' own Tonemap settings, without the burn)."""
    if not hdr:
        return np.clip(a / 255.0, 0.0, 1.0)
    la = np.exp(np.mean(np.log(1e-6 + np.maximum(lum(ref), 0.0))))
    s = 0.18 / la * np.maximum(a, 0.0)
    return np.clip(s / (1.0 + s), 0.0, 1.0) ** (1.0 / 2.2)


def flip(x, ref, hdr):
    import flip_evaluator
    r = np.ascontiguousarray(to_ldr(ref, ref, hdr), dtype=np.float32)
    t = np.ascontiguousarray(to_ldr(x, ref, hdr), dtype=np.float32)
    _, mean, _ = flip_evaluator.evaluate(r, t, "LDR", inputsRGB=True, applyMagma=False)
    return float(mean)


def med(v):
    return statistics.median(v)


def spread(v):
    return min(v), max(v)


# -------------------------------------------------------------------------------------------- mitsuba
MITSUBA_PASS_SPP = 64  # a high-spp Mitsuba render is made of passes of this many spp (bounded memory)


def load_mitsuba(threads):
    """(mitsuba module, version) or (None, reason). scripts/bench sets DRJIT_LIBLLVM_PATH."""
    try:
        import mitsuba as mi
        import drjit as dr
        mi.set_variant("llvm_ad_rgb")
        dr.set_thread_count(threads)
        return mi, mi.__version__
    except Exception as e:  # ImportError, no LLVM, no variant: the benchmark goes on without it
        return None, "%s: %s" % (type(e).__name__, str(e).splitlines()[0] if str(e) else "")


class Mitsuba:
    """Renders a converted scene (bench/to_mitsuba.py): one render per image, the camera-visible
    environment included, as clrt renders it."""

    def __init__(self, mi, scene_path, spp_list, samplers=("independent",)):
        import to_mitsuba
        self.mi = mi
        self.code = to_mitsuba.code_hash()
        scene, self.warnings = to_mitsuba.scene_dict(scene_path, 1, warn=log)
        self.scene = mi.load_dict(to_mitsuba.materialize(scene, mi))  # independent sampler: the references
        self.scenes = {}  # the timed renders, one scene per sampler (the sensor's sampler)
        for smp in samplers:
            scene["sensor"]["sampler"] = dict(scene["sensor"]["sampler"], type=smp)
            self.scenes[smp] = mi.load_dict(to_mitsuba.materialize(scene, mi))

    def _render(self, scene, spp, seed):
        return np.array(self.mi.render(scene, spp=spp, seed=seed), dtype=np.float64)[..., :3]

    def render(self, spp, seed, sampler="independent"):
        """(seconds, image): the timed render with `sampler`."""
        scene = self.scenes.get(sampler, self.scene)
        t0 = time.perf_counter()
        img = self._render(scene, spp, seed)
        return time.perf_counter() - t0, img

    def render_high(self, spp, seed0):
        acc, k = 0.0, 0
        for k in range(max(1, spp // MITSUBA_PASS_SPP)):
            acc = acc + self._render(self.scene, min(spp, MITSUBA_PASS_SPP), seed0 + 7919 * k)
        return acc / (k + 1)

    def reference(self, name, key, ref_spp, cache_dir, refresh):
        """Two independent halves (like clrt's), cached (the scene's hash and the converter's, to_mitsuba.code_hash,
        in the name)."""
        d = os.path.join(cache_dir, "%s-mitsuba-c%s-%s-%d" % (name, self.code, key, ref_spp))
        files = [os.path.join(d, f) for f in ("half_a.npy", "half_b.npy")]
        if not refresh and all(os.path.exists(f) for f in files):
            a, b = (np.load(f).astype(np.float64) for f in files)
            log("  mitsuba reference %s (cached)" % os.path.basename(d))
            return a, b
        os.makedirs(d, exist_ok=True)
        log("  mitsuba reference: 2 x %d spp ..." % (ref_spp // 2))
        a = self.render_high(ref_spp // 2, REF_SEEDS[0])
        b = self.render_high(ref_spp // 2, REF_SEEDS[1])
        for f, v in zip(files, (a, b)):
            np.save(f, v.astype(np.float32))
        return a, b


def mitsuba_setup(mi, sc, scene_path, hdr, clrt_ref, a):
    """The converted scene and its reference; checks that the two renderers agree (reference means)."""
    white = 1.0 if hdr else 255.0
    ms = Mitsuba(mi, scene_path, sc["spp"], a.mi_samplers)
    ma, mb = ms.reference(sc["name"], scene_hash(scene_path), sc["ref_spp"], a.refs, a.refresh_refs)
    ms.ref = 0.5 * (ma + mb)
    ms.floor = float(np.mean((ma - mb) ** 2 / (ms.ref ** 2 + EPS_REL * white * white)) / 4.0)
    # Agreement of the two renderers: per-channel means of the references, and their relMSE.
    cm, mm = clrt_ref.reshape(-1, 3).mean(0), ms.ref.reshape(-1, 3).mean(0)
    ms.ratio = mm / np.maximum(cm, 1e-30)
    ms.cross = rel_mse(ms.ref, clrt_ref, white)
    ms.agree = bool(np.all(np.abs(ms.ratio - 1.0) <= 0.01))
    log("  mitsuba/clrt reference mean per channel: %s; relMSE between the references %.3g; %s" % (
        " ".join("%.4f" % r for r in ms.ratio), ms.cross, "agree" if ms.agree else "DISAGREE (> 1%): efficiency not comparable"))
    return ms


def mitsuba_rows(ms, sc, spp, ts, es, clrt_rows, clrt_runs, a, mi_sampler="independent"):
    """Rows comparing Mitsuba's runs with `mi_sampler` (times ts, relMSEs es) at spp with each clrt variant's
    (strategy label)."""
    rows = []
    for crow in sorted((r for r in clrt_rows if r["spp"] == spp), key=lambda r: (not r["strategy"].startswith("mis"), r["strategy"])):
        if not crow["strategy"].startswith("mis") and any(r["strategy"].startswith("mis") for r in clrt_rows):
            continue  # the comparison is with clrt's MIS (Mitsuba's path integrator uses MIS)
        row = dict(scene=sc["name"], spp=spp, runs=a.runs, mitsuba_sampler=mi_sampler, mitsuba_s=med(ts), mitsuba_s_min=min(ts), mitsuba_s_max=max(ts),
                   mitsuba_relmse=med(es), mitsuba_relmse_min=min(es), mitsuba_relmse_max=max(es),
                   mitsuba_ref_relmse=ms.floor, mean_ratio_r=ms.ratio[0], mean_ratio_g=ms.ratio[1], mean_ratio_b=ms.ratio[2],
                   refs_relmse=ms.cross, agree=int(ms.agree), warnings=len(ms.warnings))
        row["mitsuba_eff"] = 1.0 / (row["mitsuba_relmse"] * row["mitsuba_s"])
        row.update(clrt_strategy=crow["strategy"], clrt_s=crow["render_s"], clrt_relmse=crow["relmse"],
                   clrt_eff=crow["efficiency"])
        row["eff_ratio"] = row["clrt_eff"] / row["mitsuba_eff"]          # clrt / Mitsuba
        row["time_factor"] = row["mitsuba_s"] / row["clrt_s"]            # > 1: clrt faster
        row["noise_factor"] = row["mitsuba_relmse"] / row["clrt_relmse"]  # > 1: clrt less noisy
        # Spread: run k of clrt against run k of Mitsuba (same seed number, run back to back), per pair.
        cr = [r for r in clrt_runs if r["spp"] == spp and r["strategy"] == crow["strategy"]]
        pairs = [(1.0 / (c["relmse"] * c["render"])) / (1.0 / (e * t)) for c, e, t in zip(cr, es, ts)]
        if pairs:
            row["eff_ratio_min"], row["eff_ratio_max"] = min(pairs), max(pairs)
        tpairs = [t / c["render"] for c, t in zip(cr, ts)]
        if tpairs:
            row["time_factor_min"], row["time_factor_max"] = min(tpairs), max(tpairs)
        rows.append(row)
        log("  mitsuba %s spp %4d: render %.3fs [%.3f-%.3f]  relMSE %.4g [%.4g-%.4g]  clrt %s/mitsuba efficiency %.3f" % (
            mi_sampler, spp, row["mitsuba_s"], min(ts), max(ts), row["mitsuba_relmse"], min(es), max(es), crow["strategy"],
            row["eff_ratio"]))
    return rows


# ----------------------------------------------------------------------------------------- references
def reference(clrt, sc, scene_path, strategy, cache_dir, hdr, refresh):
    """The reference of a scene, cached under cache_dir by the scene's hash: two independent halves
    a, b of ref_spp/2 each (seeds REF_SEEDS); reference = (a+b)/2. Returns (ref, meta) where meta holds
    its own estimated error: Var(a-b) = 2 Var(half) and Var(ref) = Var(half)/2, so the reference's
    squared error is estimated by |a-b|^2/4 (relMSE and RMSE alike)."""
    key = "%s-%s-%d-%s" % (sc["name"], scene_hash(scene_path), sc["ref_spp"], strategy)
    d = os.path.join(cache_dir, key)
    meta_path = os.path.join(d, "meta.json")
    pa, pb = os.path.join(d, "half_a.npy"), os.path.join(d, "half_b.npy")
    if not refresh and os.path.exists(meta_path) and os.path.exists(pa) and os.path.exists(pb):
        meta = json.load(open(meta_path))
        a, b = np.load(pa).astype(np.float64), np.load(pb).astype(np.float64)
        log("  reference %s (cached, %d spp)" % (key, meta["spp"]))
    else:
        os.makedirs(d, exist_ok=True)
        half = sc["ref_spp"] // 2
        log("  reference %s: rendering 2 x %d spp (%s) ..." % (key, half, strategy))
        t0 = time.perf_counter()
        _, a, _ = clrt.render(scene_path, half, REF_SEEDS[0], strategy)
        _, b, _ = clrt.render(scene_path, half, REF_SEEDS[1], strategy)
        np.save(pa, a.astype(np.float32))
        np.save(pb, b.astype(np.float32))
        meta = dict(scene=sc["name"], hash=key, spp=sc["ref_spp"], strategy=strategy, seeds=list(REF_SEEDS),
                    seconds=time.perf_counter() - t0)
        json.dump(meta, open(meta_path, "w"), indent=1)
    ref = 0.5 * (a + b)
    white = 1.0 if hdr else 255.0
    meta = dict(meta, relmse=float(np.mean((a - b) ** 2 / (ref ** 2 + EPS_REL * white * white)) / 4.0),
                rmse=float(np.sqrt(np.mean((a - b) ** 2) / 4.0)), flip_halves=flip(a, b, hdr))
    return ref, meta


# ---------------------------------------------------------------------------------------------- plots
def plot_strategy(ax, strat, rs):
    """One strategy's curves: relMSE and FLIP against render time, efficiency against spp."""
    t = np.array([r["render_s"] for r in rs])
    terr = np.array([[r["render_s"] - r["render_s_min"] for r in rs], [r["render_s_max"] - r["render_s"] for r in rs]])
    e = np.array([r["relmse"] for r in rs])
    eerr = np.array([[r["relmse"] - r["relmse_min"] for r in rs], [r["relmse_max"] - r["relmse"] for r in rs]])
    ok = np.array([r["above_floor"] for r in rs], dtype=bool)
    line = ax[0].errorbar(t[ok], e[ok], xerr=terr[:, ok], yerr=eerr[:, ok], marker="o", capsize=2, label=strat)
    if (~ok).any():
        ax[0].plot(t[~ok], e[~ok], "o", mfc="none", color=line[0].get_color())
    for r in rs:
        ax[0].annotate("%d" % r["spp"], (r["render_s"], r["relmse"]), fontsize=7, xytext=(3, 3), textcoords="offset points")
    ax[1].plot(t, np.array([r["flip"] for r in rs]), marker="o", label=strat)
    ax[2].plot([r["spp"] for r in rs], np.array([r["efficiency"] for r in rs]), marker="o", label=strat)


def plot_scene(name, rows, meta_by_strategy, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(1, 3, figsize=(15, 4.4))
    floor = min(m["relmse"] for m in meta_by_strategy.values())
    for strat in sorted({r["strategy"] for r in rows}):
        plot_strategy(ax, strat, sorted((r for r in rows if r["strategy"] == strat), key=lambda r: r["spp"]))
    ax[0].axhline(floor, ls="--", color="gray", lw=1, label="reference noise floor")
    for a in ax:
        a.set_xscale("log")
        a.set_yscale("log")
        a.grid(True, which="both", alpha=0.3)
        a.legend(fontsize=8)
    ax[0].set_xlabel("render time [s] (median)")
    ax[0].set_ylabel("relMSE (median; bars: min-max)")
    ax[1].set_xlabel("render time [s] (median)")
    ax[1].set_ylabel("FLIP (LDR, median)")
    ax[2].set_xlabel("spp")
    ax[2].set_ylabel("efficiency 1/(relMSE x render s)")
    fig.suptitle("%s: error against time (hollow: within 2x of the reference's noise floor)" % name)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def replot(d):
    rows = list(csv.DictReader(open(os.path.join(d, "bench.csv"))))
    refs = {r["scene"]: r for r in csv.DictReader(open(os.path.join(d, "refs.csv")))}
    num = lambda r: {k: (v if k in ("scene", "strategy") else float(v)) for k, v in r.items()}
    rows = [num(r) for r in rows]
    for name in dict.fromkeys(r["scene"] for r in rows):
        meta = {refs[name]["ref_strategy"]: dict(relmse=float(refs[name]["ref_relmse"]))}
        plot_scene(name, [r for r in rows if r["scene"] == name], meta, os.path.join(d, name + ".png"))
    log("bench: plots redrawn in %s" % d)


# -------------------------------------------------------------------------------------------- helpers
def write_csv(path, rows, cols):
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=cols, extrasaction="ignore")
        w.writeheader()
        for r in rows:
            w.writerow({k: ("%.6g" % v if isinstance(v, float) else v) for k, v in r.items()})


def md_table(rows, cols, fmt=None):
    fmt = fmt or {}
    out = ["| " + " | ".join(cols) + " |", "|" + "---|" * len(cols)]
    for r in rows:
        out.append("| " + " | ".join((fmt.get(c, "%s") % r[c]) if c in r else "" for c in cols) + " |")
    return "\n".join(out)


def slug(s):
    return re.sub(r"[^a-z0-9]+", "-", s.lower()).strip("-")


# ------------------------------------------------------------------------------------------------ main
def parse_args(argv=None):
    ap = argparse.ArgumentParser(description="speed against error benchmark (see bench/README.md)")
    ap.add_argument("--build", default=os.path.join(ROOT, "build"), help="build folder with clrt (and ray_bench)")
    ap.add_argument("--device", default="cpu", help="clrt --device SPEC (default cpu)")
    ap.add_argument("--runs", type=int, default=3, help="runs (seeds) per point; figures are medians")
    ap.add_argument("--scenes", default="", help="comma list of scene names (default: all present)")
    ap.add_argument("--strategies", default="", help="comma list of env sampling strategies (default: all the build offers)")
    ap.add_argument("--out", default="", help="output folder (default bench/results/<device>)")
    ap.add_argument("--refs", default=os.path.join(ROOT, "bench", "results", "refs"), help="reference cache folder")
    ap.add_argument("--refresh-refs", action="store_true", help="re-render the references")
    ap.add_argument("--no-features", action="store_true", help="skip the specialised vs --all-features part")
    ap.add_argument("--no-ray-bench", action="store_true", help="skip ray_bench")
    ap.add_argument("--no-mitsuba", action="store_true", help="skip the comparison with Mitsuba 3")
    ap.add_argument("--mitsuba-only", action="store_true", help="only the scenes compared with Mitsuba, strategy mis")
    ap.add_argument("--quick", action="store_true", help="1 run, first two spp points: a smoke test")
    ap.add_argument("--spp", default="", help="comma list: only these spp points of each scene (default: all)")
    ap.add_argument("--pipelines", default="", help="comma list of clrt --pipeline values (fused, wavefront), each run "
                    "as its own variant (strategy label 'mis+fused'), interleaved run by run; default: clrt's own choice")
    ap.add_argument("--samplers", default="", help="comma list of clrt --sampler values (stratified, independent, zsobol), each "
                    "run as its own variant (label 'mis+fused+independent'; the default sampler adds nothing); default: "
                    "clrt's own (stratified)")
    ap.add_argument("--mitsuba-samplers", default="independent,multijitter", help="comma list of Mitsuba samplers, "
                    "each compared with every clrt variant (default independent,multijitter: Mitsuba's default and its "
                    "least noisy at 16 and 64 spp on these scenes)")
    ap.add_argument("--path-only", action="store_true", help="only the path-traced scenes (bench/bench_path.py)")
    ap.add_argument("--no-path", action="store_true", help="skip the path-traced scenes")
    ap.add_argument("--mitsuba-path", action="store_true", help="only the path-traced scenes against Mitsuba 3's path "
                    "integrator (bench/bench_mitsuba_path.py; --scenes, --spp, --runs apply)")
    ap.add_argument("--mitsuba-variant", default="llvm_ad_rgb", choices=["llvm_ad_rgb", "scalar_rgb"],
                    help="Mitsuba variant for --mitsuba-path (default llvm_ad_rgb: the faster on 2 cores)")
    ap.add_argument("--scene-file", default="", metavar="FILE[@CAMERA],...",
                    help="with --mitsuba-path: these course XML scenes instead of the benchmark's (camera N with @N)")
    ap.add_argument("--path-res", type=int, default=128, help="with --scene-file: the long side of the render (default 128)")
    ap.add_argument("--path-params", default="", help="with --scene-file: clrt's RendererParams instead of the camera's "
                    "(e.g. MultipleImportanceSampling, what Mitsuba's path does)")
    ap.add_argument("--path-ref-spp", type=int, default=1024, help="with --scene-file: each reference's spp (default 1024)")
    ap.add_argument("--depth-check", action="store_true", help="with --mitsuba-path: also the depth-mapping test")
    ap.add_argument("--replot", metavar="DIR", help="only redraw the plots of DIR (a results folder) from its CSVs")
    return ap.parse_args(argv)


def clrt_setup(a):
    """The clrt binary of --build and what it offers: (Clrt, its `render --help` text, env strategies)."""
    exe = os.path.join(a.build, "clrt")
    if not os.access(exe, os.X_OK):
        sys.exit("bench: %s not found (build it first, or run scripts/bench)" % exe)
    help_text = subprocess.run([exe, "render", "--help"], capture_output=True, text=True).stdout
    env_flag = "--env-sampling" if "--env-sampling" in help_text else None
    strategies = [s for s in (a.strategies.split(",") if a.strategies else ALL_STRATEGIES) if s]
    if env_flag:
        offered = [s for s in ALL_STRATEGIES if s in help_text]
        strategies = [s for s in strategies if s in offered]
    else:
        log("bench: this clrt has no --env-sampling option; env scenes run with its default sampler only")
        strategies = ["default"]
    return Clrt(exe, a.device, env_flag or "--env-sampling"), help_text, strategies


def mitsuba_module(a):
    """(mitsuba module or None, its version or why not), said on stderr."""
    mi, mi_version = (None, "--no-mitsuba") if a.no_mitsuba else load_mitsuba(os.cpu_count() or 2)
    if mi is None:
        log("bench: Mitsuba 3 not available (%s): the comparison with Mitsuba is skipped" % mi_version)
    else:
        log("bench: Mitsuba %s (llvm_ad_rgb, %d threads) for the scenes it converts" % (mi_version, os.cpu_count() or 2))
    return mi, mi_version


def offered(values, flag, help_text):
    """values, or none (said so) when this clrt has no such option."""
    if values and flag not in help_text:
        log("bench: this clrt has no %s option; %ss ignored" % (flag, flag))
        return []
    return values


def comma_list(text, allowed, option):
    """The comma list of an option, each value one of allowed (else exit with a usage message)."""
    values = [x for x in text.split(",") if x]
    if any(x not in allowed for x in values):
        sys.exit("bench: %s: expected a comma list of %s" % (option, ", ".join(allowed)))
    return values


def variant_options(a, help_text, strategies):
    """--mitsuba-only, --pipelines, --samplers and --mitsuba-samplers against what this clrt offers:
    (strategies, pipelines, samplers); sets a.mi_samplers (and a.no_features/no_ray_bench for --mitsuba-only)."""
    if a.mitsuba_only:
        a.no_features = a.no_ray_bench = True
        strategies = [x for x in strategies if x == "mis"] or strategies[-1:]
    pipelines = offered([p for p in a.pipelines.split(",") if p], "--pipeline", help_text)
    samplers = offered(comma_list(a.samplers, CLRT_SAMPLERS, "--samplers"), "--sampler", help_text)
    a.mi_samplers = comma_list(a.mitsuba_samplers, MITSUBA_SAMPLERS, "--mitsuba-samplers")
    if not a.mi_samplers:
        sys.exit("bench: --mitsuba-samplers: expected a comma list of %s" % ", ".join(MITSUBA_SAMPLERS))
    return strategies, pipelines, samplers


def select_scenes(a):
    """SCENES filtered by --scenes and --mitsuba-only, less those whose files are not present (said so)."""
    wanted = set(filter(None, a.scenes.split(",")))
    scenes = [s for s in SCENES if (not wanted or s["name"] in wanted) and (not a.mitsuba_only or s.get("mitsuba"))]
    missing = [s["name"] for s in scenes if not os.path.exists(s["path"])]
    if missing:
        log("bench: skipping scenes not present: " + ", ".join(missing))
    return [s for s in scenes if os.path.exists(s["path"])]


def device_folder(clrt, scene_path, a):
    """The device's name, from a verbose warm-up render of scene_path (which also fills the kernel cache), and
    the results folder (--out, or bench/results/<device>); creates it and the reference cache folder."""
    _, _, err = clrt.render(scene_path, 1, 0, verbose=True)
    m = re.search(r"device: \[\d+\] (.*?) \(", err)
    device_name = m.group(1).strip() if m else (a.device or "default")
    out = a.out or os.path.join(ROOT, "bench", "results", slug(device_name))
    os.makedirs(out, exist_ok=True)
    os.makedirs(a.refs, exist_ok=True)
    return device_name, out


# ------------------------------------------------------------------------------------- one scene, one spp
def scene_variants(sc, ctx):
    """The variant labels a scene runs ('mis', 'mis+fused', 'mis+fused+independent', ...) and the strategy
    of its reference."""
    strats = ctx.strategies if sc.get("env") else ["default"]
    ref_strategy = ("mis" if "mis" in strats else strats[-1]) if sc.get("env") else "default"
    if ctx.pipelines:
        strats = ["%s+%s" % (st, p) for st in strats for p in ctx.pipelines]
    if ctx.samplers:  # the default (stratified) adds no label part
        strats = [st if smp == "stratified" else "%s+%s" % (st, smp) for st in strats for smp in ctx.samplers]
    return strats, ref_strategy


def clrt_run(ctx, sc, scene_path, hdr, spp, seed, strat, ref):
    """One clrt render and its error against ref; the run's row (also appended to ctx.runs_rows)."""
    st, img, _ = ctx.clrt.render(scene_path, spp, seed, strat)
    r = dict(scene=sc["name"], strategy=strat, spp=spp, seed=seed, **st)
    r["relmse"] = rel_mse(img, ref, 1.0 if hdr else 255.0)
    r["rmse"] = rmse(img, ref)
    r["flip"] = flip(img, ref, hdr)
    ctx.runs_rows.append(r)
    return r


def summary_row(sc, strat, spp, rs, meta):
    """bench.csv's row of one variant at one spp from its runs rs: medians, spreads, efficiency, floor flag."""
    row = dict(scene=sc["name"], strategy=strat, spp=spp, runs=len(rs), width=sc["res"][0], height=sc["res"][1])
    for k in ("parse", "bvh", "build", "render", "output", "wall", "camera_mrays", "shadow_mrays",
              "secondary_mrays", "relmse", "rmse", "flip"):
        v = [r[k] for r in rs]
        kk = k + "_s" if k in ("parse", "bvh", "build", "render", "output", "wall") else k
        row[kk] = med(v)
        row[kk + "_min"], row[kk + "_max"] = spread(v)
    row["efficiency"] = 1.0 / (row["relmse"] * max(row["render_s"], 1e-9))
    row["ref_spp"] = meta["spp"]
    row["ref_relmse"] = meta["relmse"]
    row["above_floor"] = int(row["relmse"] >= 2.0 * meta["relmse"])
    log("  %-10s spp %4d: render %.3fs [%.3f-%.3f]  relMSE %.4g [%.4g-%.4g]  FLIP %.4f" % (
        strat, spp, row["render_s"], row["render_s_min"], row["render_s_max"], row["relmse"],
        row["relmse_min"], row["relmse_max"], row["flip"]))
    return row


def mitsuba_runs(ms, samplers, spp, seed, white, mts, mes):
    """Mitsuba's render of one seed under each sampler: time into mts, relMSE into mes (per sampler)."""
    for smp in samplers:
        t, img = ms.render(spp, seed, smp)
        mts[smp].append(t)
        mes[smp].append(rel_mse(img, ms.ref, white))


def run_point(ctx, sc, scene_path, hdr, spp, strats, ref, meta, ms):
    """Every variant (and Mitsuba under each of its samplers) at one spp, --runs times; run k of each back to
    back, so that the machine's drift hits all alike. Returns the variants' summary rows."""
    a = ctx.a
    by_strat = {strat: [] for strat in strats}
    mts, mes = {smp: [] for smp in a.mi_samplers}, {smp: [] for smp in a.mi_samplers}
    if ms is not None:
        for smp in a.mi_samplers:
            ms.render(spp, 0, smp)  # warm-up: Dr.Jit compiles (and caches) the kernel for this size
    for run in range(a.runs):
        for strat in strats:
            by_strat[strat].append(clrt_run(ctx, sc, scene_path, hdr, spp, run + 1, strat, ref))
        if ms is not None:
            mitsuba_runs(ms, a.mi_samplers, spp, run + 1, 1.0 if hdr else 255.0, mts, mes)
    spp_rows = [summary_row(sc, strat, spp, by_strat[strat], meta) for strat in strats]
    scene_runs = [r for r in ctx.runs_rows if r["scene"] == sc["name"]]
    for smp in (a.mi_samplers if ms is not None else []):
        ctx.mi_rows += mitsuba_rows(ms, sc, spp, mts[smp], mes[smp], spp_rows, scene_runs, a, smp)
    return spp_rows


def run_scene(ctx, sc, scene_path, hdr, out):
    """One scene: its reference (refs.csv row), every variant at every spp, Mitsuba where it converts the
    scene, and the scene's plot. Returns the scene's bench.csv rows."""
    a, clrt = ctx.a, ctx.clrt
    strats, ref_strategy = scene_variants(sc, ctx)
    log("%s (%dx%d, %s)" % (sc["name"], sc["res"][0], sc["res"][1], "HDR" if hdr else "LDR"))
    ref, meta = reference(clrt, sc, scene_path, ref_strategy, a.refs, hdr, a.refresh_refs)
    ctx.ref_rows.append(dict(scene=sc["name"], ref_spp=meta["spp"], ref_strategy=meta["strategy"],
                             ref_seeds="%d+%d" % tuple(meta["seeds"]), ref_relmse=meta["relmse"], ref_rmse=meta["rmse"],
                             ref_flip_halves=meta["flip_halves"], ref_seconds=meta["seconds"], hash=meta["hash"]))
    spps = sc["spp"][:2] if a.quick else sc["spp"]
    if a.spp:
        spps = [x for x in spps if str(x) in a.spp.split(",")]
    ms = mitsuba_setup(ctx.mi, sc, scene_path, hdr, ref, a) if ctx.mi is not None and sc.get("mitsuba") else None
    for strat in strats:
        clrt.render(scene_path, 1, 0, strat)  # warm-up: kernel cache, file cache
    scene_rows = []
    for spp in spps:
        scene_rows += run_point(ctx, sc, scene_path, hdr, spp, strats, ref, meta, ms)
    plot_scene(sc["name"], scene_rows, {ref_strategy: meta}, os.path.join(out, sc["name"] + ".png"))
    return scene_rows


def write_run_csvs(out, summary, runs_rows, ref_rows):
    """bench.csv, runs.csv and refs.csv."""
    cols = ["scene", "strategy", "spp", "runs", "width", "height"]
    for k in ("parse_s", "bvh_s", "build_s", "render_s", "output_s", "wall_s", "camera_mrays", "shadow_mrays",
              "secondary_mrays", "relmse", "rmse", "flip"):
        cols += [k, k + "_min", k + "_max"]
    cols += ["efficiency", "ref_spp", "ref_relmse", "above_floor"]
    write_csv(os.path.join(out, "bench.csv"), summary, cols)
    write_csv(os.path.join(out, "runs.csv"), runs_rows,
              ["scene", "strategy", "spp", "seed", "parse", "bvh", "build", "render", "output", "wall", "camera_mrays",
               "shadow_mrays", "secondary_mrays", "relmse", "rmse", "flip"])
    write_csv(os.path.join(out, "refs.csv"), ref_rows, list(ref_rows[0].keys()) if ref_rows else ["scene"])


# --------------------------------------------------------------------- specialised vs --all-features
def feature_times(clrt, a, scene_path, spp, fruns):
    """{all_features: {cold: [...], warm: [...], render: [...]}} for the specialised and --all-features builds."""
    res = {False: dict(cold=[], warm=[], render=[]), True: dict(cold=[], warm=[], render=[])}
    # Cold/warm kernel build: fresh clrt and PoCL caches per run; the second run finds the binary.
    for run in range(a.runs):
        for allf in (False, True):
            cdir = tempfile.mkdtemp(prefix="clrt-bench-cache-")
            env = dict(os.environ, CLRT_CACHE_DIR=os.path.join(cdir, "clrt"), POCL_CACHE_DIR=os.path.join(cdir, "pocl"))
            st1, _, _ = clrt.render(scene_path, 1, 0, all_features=allf, env=env)
            st2, _, _ = clrt.render(scene_path, 1, 0, all_features=allf, env=env)
            res[allf]["cold"].append(st1["build"])
            res[allf]["warm"].append(st2["build"])
            shutil.rmtree(cdir, ignore_errors=True)
    # Render time, the two variants interleaved so that drift of the machine hits both alike.
    for allf in (False, True):
        clrt.render(scene_path, 1, 0, all_features=allf)  # warm the default cache
    for run in range(fruns):
        for allf in (False, True):
            st, _, _ = clrt.render(scene_path, spp, run + 1, all_features=allf)
            res[allf]["render"].append(st["render"])
    return res


def feature_rows(clrt, a, name, scene_path):
    """features.csv's two rows (specialised, all-features) of one scene."""
    fruns, spp, rows = max(a.runs, 5), FEATURE_SPP, []
    res = feature_times(clrt, a, scene_path, spp, fruns)
    for allf in (False, True):
        variant = "all-features" if allf else "specialised"
        _, _, err = clrt.render(scene_path, 1, 0, all_features=allf, verbose=True)
        fm = re.search(r"kernel flags:([^\n(]*)", err)
        R, C, W = res[allf]["render"], res[allf]["cold"], res[allf]["warm"]
        rows.append(dict(scene=name, variant=variant, spp=spp, runs=fruns, build_runs=a.runs,
                         render_s=med(R), render_s_min=min(R), render_s_max=max(R),
                         build_cold_s=med(C), build_cold_s_min=min(C), build_cold_s_max=max(C),
                         build_warm_s=med(W), build_warm_s_min=min(W), build_warm_s_max=max(W),
                         flags=(fm.group(1).strip() if fm else "")))
        log("  %-12s %-12s render %.3fs [%.3f-%.3f]  build cold %.2fs [%.2f-%.2f]  warm %.3fs" % (
            name, variant, med(R), min(R), max(R), med(C), min(C), max(C), med(W)))
    rows[0]["speedup"] = rows[1]["render_s"] / rows[0]["render_s"]
    rows[1]["speedup"] = 1.0
    return rows


def run_features(clrt, a, prepared, out):
    """Specialised build against --all-features on FEATURE_SCENES; writes features.csv, returns its rows."""
    log("specialised vs --all-features")
    feat_rows = []
    for name in FEATURE_SCENES:
        if name in prepared:
            feat_rows += feature_rows(clrt, a, name, prepared[name][0])
    write_csv(os.path.join(out, "features.csv"), feat_rows,
              ["scene", "variant", "spp", "runs", "build_runs", "render_s", "render_s_min", "render_s_max", "speedup",
               "build_cold_s", "build_cold_s_min", "build_cold_s_max", "build_warm_s", "build_warm_s_min",
               "build_warm_s_max", "flags"])
    return feat_rows


# ------------------------------------------------------------------------------------------ ray_bench
def run_ray_bench(a, out):
    """clrt's intersection kernels against Embree 3 (bench/ray_bench) on RAY_BENCH_SCENES, when built and not
    --no-ray-bench; writes ray_bench.txt/csv. Returns (rows, the program's output)."""
    rb_rows, rb_text = [], ""
    rb = os.path.join(a.build, "ray_bench")
    if a.no_ray_bench:
        return rb_rows, rb_text
    if not os.access(rb, os.X_OK):
        log("bench: %s not built (needs libembree-dev); ray_bench skipped" % rb)
        return rb_rows, rb_text
    log("ray_bench (clrt vs Embree)")
    for name in RAY_BENCH_SCENES:
        sc = next((s for s in SCENES if s["name"] == name), None)
        if sc is None or not os.path.exists(sc["path"]):
            continue
        cmd = [rb, sc["path"], "--runs", str(max(a.runs, 3)), "--threads", str(os.cpu_count() or 2)]
        if a.device:
            cmd += ["--device", a.device]
        p = subprocess.run(cmd, capture_output=True, text=True)
        rb_text += "$ %s\n%s\n" % (" ".join(os.path.relpath(c, ROOT) if os.path.isabs(c) else c for c in cmd), p.stdout)
        for line in p.stdout.splitlines():
            f = line.split()
            if len(f) == 7 and f[0] in ("camera", "shadow", "diffuse"):
                rb_rows.append(dict(scene=name, rays=f[0], count=int(f[1]), clrt_mrays=float(f[2]),
                                    embree_mrays=float(f[3]), ratio=float(f[4]), hit_agree=f[5], prim_agree=f[6]))
    open(os.path.join(out, "ray_bench.txt"), "w").write(rb_text)
    write_csv(os.path.join(out, "ray_bench.csv"), rb_rows,
              ["scene", "rays", "count", "clrt_mrays", "embree_mrays", "ratio", "hit_agree", "prim_agree"])
    return rb_rows, rb_text


# --------------------------------------------------------------------------------------------- report
def report_errors(device_name, a, t_bench, ref_rows, summary):
    """The report's title, its references and its error-against-time table."""
    rep = ["# clrt benchmark: %s" % device_name, "",
           "%s; clrt device `%s`; %d runs per point (seeds 1..%d), figures are medians, [min-max] the spread; "
           "benchmark part took %.0f s." % (time.strftime("%Y-%m-%d"), a.device, a.runs, a.runs, t_bench), "",
           "## References", "",
           "Rendered by clrt as two independent halves (seeds %d, %d); reference = their mean. Its own error is "
           "estimated from the halves: relMSE_ref = mean((a-b)^2/(ref^2+%g W^2))/4, RMSE_ref likewise; FLIP(a,b) is the "
           "FLIP of one half against the other; W = 255 (the display white) for LDR scenes, 1 for HDR ones. Points within 2x of relMSE_ref are flagged (above_floor=0, "
           "hollow in the plots)." % (REF_SEEDS[0], REF_SEEDS[1], EPS_REL), "",
           md_table(ref_rows, ["scene", "ref_spp", "ref_strategy", "ref_relmse", "ref_rmse", "ref_flip_halves", "ref_seconds"],
                    {"ref_relmse": "%.3g", "ref_rmse": "%.3g", "ref_flip_halves": "%.4f", "ref_seconds": "%.1f"}), "",
           "## Error against time", ""]
    for r in summary:
        r["render_fmt"] = "%.3f [%.3f-%.3f]" % (r["render_s"], r["render_s_min"], r["render_s_max"])
        r["relmse_fmt"] = "%.3g [%.3g-%.3g]" % (r["relmse"], r["relmse_min"], r["relmse_max"])
        r["mrays_fmt"] = "%.2f / %.2f / %.2f" % (r["camera_mrays"], r["shadow_mrays"], r["secondary_mrays"])
        r["stages_fmt"] = "%.2f / %.2f / %.2f / %.2f" % (r["parse_s"], r["bvh_s"], r["build_s"], r["output_s"])
    rep.append(md_table(summary, ["scene", "strategy", "spp", "render_fmt", "stages_fmt", "mrays_fmt", "relmse_fmt", "rmse",
                                  "flip", "efficiency", "above_floor"],
                        {"rmse": "%.3g", "flip": "%.4f", "efficiency": "%.3g"}))
    rep += ["", "Columns: render s median [min-max]; stages = parse / bvh / kernel build / output s (medians); Mrays/s = "
            "camera / shadow / secondary rays per render second; efficiency = 1/(relMSE x render s).", ""]
    return rep


def format_mitsuba_row(r):
    """The report's formatted columns of one Mitsuba comparison row."""
    nan = float("nan")
    r["clrt_fmt"] = "%.3f / %.3g" % (r.get("clrt_s", nan), r.get("clrt_relmse", nan))
    r["mi_fmt"] = "%.3f [%.3f-%.3f] / %.3g [%.3g-%.3g]" % (r["mitsuba_s"], r["mitsuba_s_min"], r["mitsuba_s_max"],
                                                         r["mitsuba_relmse"], r["mitsuba_relmse_min"], r["mitsuba_relmse_max"])
    r["ratio_fmt"] = "%.2f [%.2f-%.2f]" % (r.get("eff_ratio", nan), r.get("eff_ratio_min", nan), r.get("eff_ratio_max", nan))
    r["means_fmt"] = "%.4f %.4f %.4f" % (r["mean_ratio_r"], r["mean_ratio_g"], r["mean_ratio_b"])
    r["time_fmt"] = "%.2f [%.2f-%.2f]" % (r["time_factor"], r.get("time_factor_min", nan), r.get("time_factor_max", nan))


def report_mitsuba(mi, mi_version, mi_rows, out):
    """The report's "clrt against Mitsuba 3" section; writes mitsuba.csv when there are rows."""
    rep = ["## clrt against Mitsuba 3", ""]
    if mi is None:
        return rep + ["Mitsuba 3 was not available (%s): no comparison in this run." % mi_version, ""]
    if not mi_rows:
        return rep
    for r in mi_rows:
        format_mitsuba_row(r)
    rep += ["Mitsuba %s, variant llvm_ad_rgb, %d threads, path integrator max_depth 2 (direct light), box filter, "
            "the sampler of the mitsuba_sampler column (its references: independent); clrt's strategy label says its "
            "--pipeline and, when not its default stratified sampler, its --sampler; scene converted by bench/to_mitsuba.py (diffuse reflectance x pi for the course's "
            "convention; one render per image, the environment seen by the camera included, as in clrt's). Each renderer's error is "
            "against its own reference of the same spp as clrt's (two independent halves). efficiency ratio = "
            "clrt / Mitsuba = time factor (Mitsuba s / clrt s) x noise factor (Mitsuba relMSE / clrt relMSE); "
            "[min-max] over the run pairs of equal seed number. means = Mitsuba/clrt reference mean per channel; "
            "refs relMSE = between the two references (both noise floors plus any bias)."
            % (mi_version, os.cpu_count() or 2), "",
            md_table(mi_rows, ["scene", "spp", "clrt_strategy", "mitsuba_sampler", "clrt_fmt", "mi_fmt", "time_fmt", "noise_factor",
                               "ratio_fmt", "means_fmt", "refs_relmse", "agree"],
                     {"time_factor": "%.2f", "noise_factor": "%.2f", "refs_relmse": "%.3g"}), "",
            "Columns: clrt s / relMSE (medians); Mitsuba s / relMSE median [min-max]; agree: means within 1%.", ""]
    write_csv(os.path.join(out, "mitsuba.csv"), mi_rows,
              ["scene", "spp", "runs", "clrt_strategy", "mitsuba_sampler", "clrt_s", "clrt_relmse", "clrt_eff", "mitsuba_s", "mitsuba_s_min",
               "mitsuba_s_max", "mitsuba_relmse", "mitsuba_relmse_min", "mitsuba_relmse_max", "mitsuba_eff",
               "mitsuba_ref_relmse", "eff_ratio", "eff_ratio_min", "eff_ratio_max", "time_factor", "noise_factor",
               "mean_ratio_r", "mean_ratio_g", "mean_ratio_b", "refs_relmse", "agree", "warnings"])
    return rep


def point_of(rows, r, strategy):
    """The rows of rows at r's scene and spp with the given strategy label."""
    return [x for x in rows if (x["scene"], x["spp"], x["strategy"]) == (r["scene"], r["spp"], strategy)]


def pipeline_rows(summary, runs_rows):
    """Fused against wavefront (clrt --pipeline) where both variants of a point ran."""
    rows = []
    for r in summary:
        parts = r["strategy"].split("+")
        if "fused" not in parts:
            continue
        st = "+".join(x for x in parts if x != "fused")
        w = next(iter(point_of(summary, r, "+".join("wavefront" if x == "fused" else x for x in parts))), None)
        if w is None:
            continue
        fr, wr = point_of(runs_rows, r, r["strategy"]), point_of(runs_rows, r, w["strategy"])
        pairs = [b["render"] / f["render"] for f, b in zip(fr, wr)]
        rows.append(dict(scene=r["scene"], strategy=st, spp=r["spp"], fused_s=r["render_s"], wavefront_s=w["render_s"],
                         speedup="%.2f [%.2f-%.2f]" % (w["render_s"] / r["render_s"], min(pairs), max(pairs)),
                         relmse_same="yes" if r["relmse"] == w["relmse"] else "NO (%.4g vs %.4g)" % (r["relmse"], w["relmse"])))
    return rows


def report_rest(summary, runs_rows, feat_rows, rb_rows, rb_text):
    """The report's sections after Mitsuba: fused against wavefront, --all-features, ray_bench."""
    rep, pipe_rows = [], pipeline_rows(summary, runs_rows)
    if pipe_rows:
        rep += ["## Fused against wavefront (clrt --pipeline)", "",
                "Render s medians of the interleaved runs; speedup = wavefront s / fused s, [min-max] over the run pairs "
                "of equal seed; relMSE same: the two pipelines' images have the same error (they are the same image).", "",
                md_table(pipe_rows, ["scene", "strategy", "spp", "fused_s", "wavefront_s", "speedup", "relmse_same"],
                         {"fused_s": "%.3f", "wavefront_s": "%.3f"}), ""]
    if feat_rows:
        for r in feat_rows:
            r["render_fmt"] = "%.3f [%.3f-%.3f]" % (r["render_s"], r["render_s_min"], r["render_s_max"])
            r["cold_fmt"] = "%.2f [%.2f-%.2f]" % (r["build_cold_s"], r["build_cold_s_min"], r["build_cold_s_max"])
            r["warm_fmt"] = "%.3f [%.3f-%.3f]" % (r["build_warm_s"], r["build_warm_s_min"], r["build_warm_s_max"])
        rep += ["## Specialised kernels vs --all-features", "",
                "Render s at %d spp (the scenes above, same resolution; %d runs, the two variants interleaved); kernel "
                "build s cold (fresh CLRT_CACHE_DIR and POCL_CACHE_DIR) and warm (a second run with the same folders), "
                "%d runs each; speedup = all-features render s / specialised render s."
                % (FEATURE_SPP, feat_rows[0]["runs"], feat_rows[0]["build_runs"]), "",
                md_table(feat_rows, ["scene", "variant", "render_fmt", "speedup", "cold_fmt", "warm_fmt", "flags"],
                         {"speedup": "%.2f"}), ""]
    if rb_text:
        rep += ["## Intersection: clrt kernels vs Embree 3 (ray_bench)", "",
                md_table(rb_rows, ["scene", "rays", "count", "clrt_mrays", "embree_mrays", "ratio", "hit_agree", "prim_agree"],
                         {"clrt_mrays": "%.2f", "embree_mrays": "%.2f", "ratio": "%.2f"}), ""]
    return rep


def main():
    a = parse_args()
    if a.replot:
        return replot(a.replot)
    if a.quick:
        a.runs = 1
    clrt, help_text, strategies = clrt_setup(a)
    if a.path_only:  # issue 16's strategies on the path-traced scenes alone
        import bench_path
        return bench_path.main_path_only(sys.modules[__name__], clrt, a)
    if a.mitsuba_path:  # issue 32: the path tracer against Mitsuba's path integrator
        import bench_mitsuba_path
        return bench_mitsuba_path.main(sys.modules[__name__], clrt, a)
    mi, mi_version = mitsuba_module(a)
    strategies, pipelines, samplers = variant_options(a, help_text, strategies)
    scenes = select_scenes(a)
    tmp = tempfile.mkdtemp(prefix="clrt-bench-scenes-")
    prepared = {sc["name"]: prepare_scene(sc, tmp) for sc in scenes}
    device_name, out = device_folder(clrt, prepared[scenes[0]["name"]][0], a)
    log("bench: device '%s' -> %s; %d runs per point; strategies: %s" % (device_name, out, a.runs, ", ".join(strategies)))

    ctx = types.SimpleNamespace(a=a, clrt=clrt, mi=mi, strategies=strategies, pipelines=pipelines, samplers=samplers,
                                runs_rows=[], ref_rows=[], mi_rows=[])
    summary, t_start = [], time.perf_counter()
    for sc in scenes:
        summary += run_scene(ctx, sc, *prepared[sc["name"]], out)
    t_bench = time.perf_counter() - t_start
    write_run_csvs(out, summary, ctx.runs_rows, ctx.ref_rows)
    feat_rows = [] if a.no_features else run_features(clrt, a, prepared, out)
    rb_rows, rb_text = run_ray_bench(a, out)

    rep = report_errors(device_name, a, t_bench, ctx.ref_rows, summary)
    rep += report_mitsuba(mi, mi_version, ctx.mi_rows, out)
    rep += report_rest(summary, ctx.runs_rows, feat_rows, rb_rows, rb_text)
    if not a.no_path:  # issue 16: the path-traced scenes, every strategy (bench/bench_path.py)
        import bench_path
        rep += bench_path.run(sys.modules[__name__], clrt, a, out, tmp)
    open(os.path.join(out, "report.md"), "w").write("\n".join(rep) + "\n")
    print("\n".join(rep))
    shutil.rmtree(tmp, ignore_errors=True)
    log("bench: wrote %s" % out)


if __name__ == "__main__":
    sys.exit(main())
