#!/usr/bin/env python3
"""check_course.py — every course scene with a reference in ../shared/scenes, rendered and judged.

Run it through scripts/check_course (which sets up numpy, Pillow and OpenEXR). For each camera of each scene
under hw1..hw6 (any depth) whose ImageName has a reference in the scene folder's _reference_outputs/, it
prints one line: scene, camera id, image, rule, figure, ok / FAIL / SKIPPED; then a summary line.
Scenes may be XML or the 2025 JSON form. --scenes DIR --references DIR check another copy of the course's
packages (e.g. ones laid out as inputs/ and outputs/): each camera's reference is then the file of its
ImageName under the --references folder nearest the scene (longest shared path); where several are equally
near (a student's my_outputs/ beside the course's outputs/) the camera is SKIPPED as ambiguous, naming them,
and --references-exclude REGEX leaves some out. Folders without references (classic, json2025) get one line each
saying so. The rules (issue 29):

  deterministic  PSNR of clrt's 8-bit PNG (--ldr-quantize floor) against the reference >= 40 dB. An EXR
                 reference: PSNR of the linear values with the reference's 99.9th percentile as the peak.
  sampled        (NumSamples > 1, AreaLight/LightMesh/LightSphere, SphericalDirectionalLight, path tracing,
                 ApertureSize > 0, MotionBlur, Roughness > 0) two clrt renders a, b with --seed 1 and 2, N spp,
                 --sampler independent (--sampler stratified on request: the hw3 references are jittered, about
                 as noisy as clrt's stratified renders, but the hw6 direct-lighting ones with object lights are
                 noisier than those, so no one choice fits every reference); the
                 reference has R = NumSamples spp. err(x, y) = mean over pixels and channels of
                 w * (x - y)^2, with w = 1 for PNGs (8-bit values: MSE) and w = 1 / (ref^2 + 0.01) for EXRs
                 (relMSE, linear values; the same weights for both errors). Then err(a, ref) ~ v_N + v_R +
                 bias^2 and err(a, b) ~ 2 v_N with v_R = v_N N / R, and the rule "bias^2 <= v_N + v_R" is
                 err(a, ref) <= err(a, b) * (1 + N / R): at N = R, the error against the reference at most
                 2x clrt's own two-render noise. It is applied at two scales, per pixel and over 8x8-pixel
                 blocks of the reference (the block scale sees a brightness bias that per-pixel noise hides);
                 the figure is the larger ratio err(a, ref) / (err(a, b) * (1 + N / R)), ok when <= 1. At N < R a PNG
                 is judged per pixel only (the 8-bit clamp and floor of the noisier image shift its block means).
                 And the image's mean per channel within 1% + 3 sigma of the reference's (sigma: the standard error
                 of the difference of the means, from the two renders). A classic camera with depth of field or an
                 area light that fails is judged again under --sampler correlated (the course's renderer until
                 2022 drew pixel jitter, lens point and light samples from one 2D point); ok when that passes.
  roulette       (a path camera with RussianRoulette in RendererParams) the course's RR references follow a
                 biased rule that `clrt render --rr-rule course` reproduces, with infinite variance (heavy
                 tails: plain means and MSEs swing by tens of per cent between seeds), so they are judged as
                 in docs/studies/2026-12-03-russian-roulette-references.md, by clipped means: two renders a, b
                 (--seed 1 and 2, --sampler independent, --rr-rule course) at the reference's size and spp R
                 (a clipped mean depends on a pixel's sample count and footprint); the image cut into 8x8
                 blocks; in each block and channel every pixel (of a, b and the reference) clipped at the
                 reference's 95th percentile of that block and channel, m = the mean of a's and b's clipped
                 means, m_ref the reference's over the same pixels. ok when in every block and channel
                 |m - m_ref| <= 1% m_ref + 4 sigma, sigma^2 = v (1 / 2n + 1 / n), v the variance of a clipped
                 pixel (half that of the block's clipped a - b differences), n the block's pixels (the
                 reference's pixels as noisy as clrt's: same spp); and the same for the whole image's clipped
                 mean (the mean of the blocks', sigma from theirs). The figure: the image's ratios m / m_ref
                 and the share of its tolerance used, the blocks' range of ratios and the worst block. The
                 95th percentile, not the study's 99th: at the 99th a block of the reduced check keeps too
                 few clipped pixels for a variance from two renders (seeds 1 and 2: a block at 1.25 of its
                 tolerance). clrt's unbiased default rule fails it (--rr-rule unbiased renders with it). The
                 renders sample LightMeshes as the course's renderer did (--mesh-light-sampling area): a clipped
                 mean depends on the noise's distribution too, and clrt's default (directions uniform in a
                 triangle's solid angle) is far less noisy than the references (hw6 path box cam 4: clipped
                 image mean 1.014, 0.94 of its tolerance, one block over, with it; 0.997, 0.18 of it, by area).
  perlin         (a TextureMap type="perlin": its lattice is not the course's, the pattern can't be matched)
                 the luminance (0.2126 R + 0.7152 G + 0.0722 B) mean and standard deviation of the whole
                 image each within 2% of the reference's; the PSNR is printed too.

--rows K (full mode): the sampled rule renders cameras with EXR references on every K-th pixel row only, at the
reference's spp (clrt render --part 1/K --tile-pixels WIDTH), and judges those rows as the image: for references
whose full spp does not fit (the 2020 Veach Ajar's 6400 spp at 1280x720).

Skipped, with the reason: a scene whose input files are missing (hw5's original environment maps), and the
scenes in KNOWN_EDITED, which ../shared edited so that its reference no longer shows the same scene.
--reduced (CI): sampled PNG scenes at N = min(R, 4) spp at full size (their 8-bit values are clamped, so a
smaller render's pixel is not the mean of the reference's block), sampled EXR scenes at a quarter of the width and
height (each clrt pixel against the mean of the reference's 4x4 block) and N = min(R, 16); deterministic and Perlin
scenes are unchanged (their rules need the full image); roulette cameras with an EXR reference render every 8th
pixel row only (clrt render --part 1/8 --tile-pixels WIDTH: the same pixels as the full render's, at R spp), each
block judged on those rows (its clipping bound still from all its reference pixels). --expected FILE: the list of cameras known to fail
(tests/course_expected_failures.txt); a FAIL listed there does not fail the run, a FAIL not listed does, and a
listed camera that passes is reported so the list can shrink.
Exit status: 1 when a camera FAILs (without --expected) or FAILs unlisted (with it), else 0.
"""
import argparse
import glob
import hashlib
import json
import os
import re
import subprocess
import sys
import tempfile
import time
import xml.etree.ElementTree as ET

import numpy as np

from scene_json import json_to_element  # scripts/scene_json.py

try:
    import OpenEXR  # noqa: F401  (PyPI 'openexr'; scripts/check_course puts it in build/check-venv)
    HAVE_OPENEXR = True
except ImportError:
    HAVE_OPENEXR = False

ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
REF_DIR = "_reference_outputs"
REF_INDEX = None   # --references DIR: image file name (lower case) -> the paths under DIR with that name
REF_ROOT = ""      # --references DIR
INPUT_EXT = re.compile(r"^[^\s<>]+\.(ply|png|jpe?g|exr|hdr|tga|bmp|bin)$", re.IGNORECASE)
KNOWN_EDITED = {
    "hw5/dragon_spot_light_msaa.xml": "the dragon mesh is missing from ../shared (its README: 'lost its dragon'); "
                                      "the reference shows it",
}
# References rendered at other spp than their scene's NumSamples, by the MD5 of the image file: the sampled
# rule then takes that R (the noise it expects of the reference, and the spp of the full check's renders).
REFERENCE_SPP = {
    # ../shared hw3 cornellbox_area.png (2022, NumSamples 16): the course's 100-spp image. Its ceiling's
    # pixel-to-pixel noise (the pixel less its 4 neighbours' mean, rows 100-140) is 1.01 levels, as in the 2020
    # hw5 (100 spp, 1.00) and 2025 hw3 (100 spp, 1.05) references of the same scene, where 16-spp renders have
    # 3.3; it is 47.8 dB from the 2020 image (docs/testing.md, session 26).
    "66c50ebf5f2770dc63bbe7775c3f8df1": 100,
}
BLOCK = 8          # block scale of the sampled rule, in reference pixels
REDUCED_SPP_PNG = 4
REDUCED_SPP_EXR = 16
REDUCED_SCALE = 4  # EXR sampled scenes in --reduced: resolution / 4
REDUCED_RR_ROWS = 8  # roulette cameras (EXR) in --reduced: every 8th pixel row (clrt render --part 1/8, a row a tile)
RR_GRID = 8        # roulette rule: the image cut into RR_GRID x RR_GRID blocks
RR_PERCENTILE = 95 # each pixel clipped at the reference's 95th percentile of its block and channel
RR_SIGMAS = 4.0    # a block's clipped mean within RR_FLOOR + RR_SIGMAS sigma of the reference's
RR_FLOOR = 0.01


# ---------------------------------------------------------------- images

def read_image(path):
    """float64 H x W x 3: PNG as 8-bit values (0..255), EXR as linear values (NaN/Inf -> 0)."""
    if path.lower().endswith(".exr"):
        with OpenEXR.File(path) as f:
            ch = f.channels()
            if "RGB" in ch:
                a = np.asarray(ch["RGB"].pixels, dtype=np.float64)
            else:
                a = np.stack([np.asarray(ch[c].pixels, dtype=np.float64) for c in "RGB"], axis=-1)
        return np.nan_to_num(a, nan=0.0, posinf=0.0, neginf=0.0)
    from PIL import Image
    with Image.open(path) as im:
        return np.asarray(im.convert("RGB"), dtype=np.float64)


def down(a, k):
    if k <= 1:
        return a
    h, w = a.shape[0] // k * k, a.shape[1] // k * k
    return a[:h, :w].reshape(h // k, k, w // k, k, 3).mean(axis=(1, 3))


def psnr(a, b, peak):
    mse = float(np.mean((a - b) ** 2))
    return float("inf") if mse == 0 else 10.0 * np.log10(peak * peak / mse)


def luminance_stats(img):
    y = 0.2126 * img[..., 0] + 0.7152 * img[..., 1] + 0.0722 * img[..., 2]
    return float(y.mean()), float(y.std())


# ---------------------------------------------------------------- scenes

def reference_candidates(scene_path, image):
    """The reference images a camera of scene_path may have: [its folder's _reference_outputs/IMAGE], or with
    --references the files of that name under DIR whose paths share the longest prefix with the scene's
    (packages laid out as inputs/ and outputs/), sorted; [] when there is none. More than one is ambiguous
    (e.g. a student's own renders in a folder beside the course's outputs/): see --references-exclude."""
    if REF_INDEX is None:
        p = os.path.join(os.path.dirname(scene_path), REF_DIR, image)
        return [p] if os.path.exists(p) else []
    candidates = REF_INDEX.get(image.lower(), [])
    if not candidates:
        return []
    shared = lambda c: len(os.path.commonprefix([c, os.path.abspath(scene_path)]))
    best = max(shared(c) for c in candidates)
    return sorted(c for c in candidates if shared(c) == best)


def index_references(ref_root, exclude=""):
    """Image file name (lower case) -> the PNG/EXR paths under ref_root with that name, less those whose path
    relative to ref_root matches the regular expression exclude."""
    index = {}
    root = os.path.abspath(ref_root)
    for p in sorted(glob.glob(os.path.join(root, "**", "*"), recursive=True)):
        if exclude and re.search(exclude, os.path.relpath(p, root)):
            continue
        if os.path.isfile(p) and p.lower().endswith((".png", ".exr")):
            index.setdefault(os.path.basename(p).lower(), []).append(p)
    return index


def load_scene_tree(path):
    """The scene's element tree (XML, or JSON mapped by json_to_element); raises ValueError when unreadable."""
    try:
        if path.lower().endswith(".json"):
            with open(path, encoding="utf-8") as f:
                d = json.load(f)
            if not isinstance(d, dict) or len(d) != 1:
                raise ValueError("not one top-level object")
            (tag, value), = d.items()
            return json_to_element(tag, value)
        return ET.parse(path).getroot()
    except (ET.ParseError, json.JSONDecodeError, OSError, UnicodeDecodeError) as e:
        raise ValueError(str(e))


def local(tag):
    return tag.rsplit("}", 1)[-1]


def first_text(elem, name, default=""):
    for e in elem.iter():
        if local(e.tag) == name and e.text is not None:
            return e.text.strip()
    return default


def missing_inputs(root, scene_dir):
    """Input files the scene names (texts and attributes that look like image/PLY paths) that do not exist."""
    missing = []
    for e in root.iter():
        if local(e.tag) == "ImageName":
            continue
        values = list(e.attrib.values()) + ([e.text.strip()] if e.text and e.text.strip() else [])
        for v in values:
            if INPUT_EXT.match(v) and not os.path.exists(os.path.join(scene_dir, v)):
                missing.append(v)
    return sorted(set(missing))


def scene_traits(root):
    """Scene-wide features that make a render sampled, and whether it uses Perlin noise."""
    tags = {local(e.tag) for e in root.iter()}
    traits = set()
    if tags & {"AreaLight", "LightMesh", "LightSphere"}:
        traits.add("area/object light")
    if "SphericalDirectionalLight" in tags:
        traits.add("environment light")
    if "MotionBlur" in tags:
        traits.add("motion blur")
    for e in root.iter():
        if local(e.tag) == "Roughness" and e.text and any(float(x) > 0 for x in e.text.split()):
            traits.add("rough surface")
            break
    perlin = any(local(e.tag) == "TextureMap" and e.get("type", "").lower() == "perlin" for e in root.iter())
    return traits, perlin


def cameras_of(root):
    cams = []
    for i, c in enumerate(e for e in root.iter() if local(e.tag) == "Camera"):
        name = first_text(c, "ImageName")
        spp = int(float(first_text(c, "NumSamples", "1") or 1))
        aperture = float(first_text(c, "ApertureSize", "0") or 0)
        renderer = first_text(c, "Renderer")
        res = [int(x) for x in first_text(c, "ImageResolution", "0 0").split()[:2]]
        rr = "russianroulette" in first_text(c, "RendererParams").lower().split()
        traits = set()
        if spp > 1:
            traits.add("NumSamples %d" % spp)
        if aperture > 0:
            traits.add("depth of field")
        if renderer.lower() == "pathtracing":
            traits.add("path tracing")
        cams.append(dict(id=c.get("id", str(i + 1)), image=name, spp=max(spp, 1), traits=traits, res=res, rr=rr))
    return cams


def find_scenes(scenes_root):
    """(relative path, absolute path) of every XML or JSON scene under hw*/; and the folders without references."""
    found, unreferenced = [], []
    for top in sorted(os.listdir(scenes_root)):
        d = os.path.join(scenes_root, top)
        if not os.path.isdir(d):
            continue
        files = [p for p in glob.glob(os.path.join(d, "**", "*.xml"), recursive=True) if REF_DIR not in p]
        files += [p for p in glob.glob(os.path.join(d, "**", "*.json"), recursive=True) if REF_DIR not in p]
        with_refs = [p for p in files if REF_INDEX is not None or os.path.isdir(os.path.join(os.path.dirname(p), REF_DIR))]
        if not with_refs:
            unreferenced.append((top, len(files)))
        for p in sorted(with_refs):
            found.append((os.path.relpath(p, scenes_root), p))
    return found, unreferenced


# ---------------------------------------------------------------- rendering

class Renderer:
    def __init__(self, args, tmp):
        self.args, self.tmp, self.n = args, tmp, 0

    def render(self, scene, cam, image, seed, spp=None, sampler=None, res=None, rr_rule=None, rows_of=None,
               mesh_lights=None):
        """Renders one camera; returns (image array, None) or (None, error line)."""
        self.n += 1
        out = os.path.join(self.tmp, "r%d" % self.n)
        os.makedirs(out)
        cmd = [self.args.clrt, "render", scene, "-o", out, "--camera", cam, "--seed", str(seed),
               "--ldr-quantize", "floor", "--device", self.args.device]
        if spp:
            cmd += ["--spp", str(spp)]
        if sampler:
            cmd += ["--sampler", sampler]
        if res:
            cmd += ["--resolution", "%dx%d" % tuple(res)]
        if rr_rule:
            cmd += ["--rr-rule", rr_rule]
        if mesh_lights:
            cmd += ["--mesh-light-sampling", mesh_lights]
        if rows_of:  # (n, width): every n-th pixel row from the first, as the EXR part file of --part 1/n
            cmd += ["--part", "1/%d" % rows_of[0], "--tile-pixels", str(rows_of[1])]
            image += ".part1of%d.exr" % rows_of[0]
        try:
            p = subprocess.run(cmd, capture_output=True, text=True, timeout=self.args.timeout)
        except subprocess.TimeoutExpired:
            return None, "timed out after %d s" % self.args.timeout
        path = os.path.join(out, image)
        if p.returncode != 0 or not os.path.exists(path):
            lines = [l for l in p.stderr.splitlines() if l.strip()] or ["exit %d" % p.returncode]
            err = next((l for l in lines if "error" in l), lines[-1])
            err = err.strip().replace(os.path.dirname(scene) + "/", "")
            return None, "clrt exit %d: %s" % (p.returncode, err[:160])
        img = read_image(path)
        for f in os.listdir(out):
            os.remove(os.path.join(out, f))
        return img, None


def judge_deterministic(r, scene, cam, ref, hdr):
    img, err = r.render(scene, cam["id"], cam["image"], 1)
    if err:
        return False, err
    if img.shape != ref.shape:
        return False, "size %dx%d, reference %dx%d" % (img.shape[1], img.shape[0], ref.shape[1], ref.shape[0])
    peak = float(np.percentile(ref, 99.9)) if hdr else 255.0
    p = psnr(img, ref, peak)
    return p >= 40.0, "PSNR %.2f dB (>= 40)%s" % (p, " linear, peak %.3g" % peak if hdr else "")


def judge_perlin(r, scene, cam, ref, hdr):
    img, err = r.render(scene, cam["id"], cam["image"], 1)
    if err:
        return False, err
    if img.shape != ref.shape:
        return False, "size differs from the reference"
    (ma, sa), (mr, sr) = luminance_stats(img), luminance_stats(ref)
    dm, ds = ma / mr - 1.0, sa / sr - 1.0
    p = psnr(img, ref, float(np.percentile(ref, 99.9)) if hdr else 255.0)
    ok = abs(dm) <= 0.02 and abs(ds) <= 0.02
    return ok, "luminance mean %+.2f%%, std %+.2f%% (within 2%%); PSNR %.2f dB" % (100 * dm, 100 * ds, p)


def judge_sampled(r, scene, cam, ref, hdr, reduced, sampler, traits):
    """The noise rule with clrt's renders under `sampler`. Where that fails and the course's older sampler
    could have made the reference (a classic camera with depth of field or an area light), again under
    --sampler correlated: ok when either holds; the figure names the sampler it is for (both figures when
    both were judged)."""
    classic = "path tracing" not in traits
    ok, what = judge_sampled_with(r, scene, cam, ref, hdr, reduced, sampler)
    if ok or not classic or not traits & {"depth of field", "area/object light"}:
        return ok, "--sampler %s: %s" % (sampler, what)
    ok2, what2 = judge_sampled_with(r, scene, cam, ref, hdr, reduced, "correlated")
    first, second = ((sampler, what), ("correlated", what2)) if not ok2 else (("correlated", what2), (sampler, what))
    return ok2, "--sampler %s: %s; --sampler %s: %s" % (*first, *second)


def judge_sampled_with(r, scene, cam, ref, hdr, reduced, sampler):
    R = cam["spp"]
    N = min(R, REDUCED_SPP_EXR if hdr else REDUCED_SPP_PNG) if reduced else R
    f = 1
    res = None
    h, w = ref.shape[:2]
    if reduced and hdr and w % REDUCED_SCALE == 0 and h % REDUCED_SCALE == 0 and min(w, h) >= 128:
        f = REDUCED_SCALE
        res = (w // f, h // f)
    # --rows K (full mode, EXR): every K-th pixel row only, at the reference's spp (a --part 1/K file), judged
    # on those rows as if they were the image (its 8x8 blocks then span 8K rows).
    k_rows = r.args.rows if (hdr and not reduced and r.args.rows > 1) else 1
    rows_of = (k_rows, w) if k_rows > 1 else None
    a, err = r.render(scene, cam["id"], cam["image"], 1, spp=N, sampler=sampler, res=res, rows_of=rows_of)
    if err:
        return False, err
    b, err = r.render(scene, cam["id"], cam["image"], 2, spp=N, sampler=sampler, res=res, rows_of=rows_of)
    if err:
        return False, err
    refd = down(ref, f)
    if k_rows > 1 and a.shape == refd.shape:
        a, b, refd = (x[::k_rows] for x in (a, b, refd))
    if a.shape != refd.shape:
        return False, "size %dx%d, reference %dx%d" % (a.shape[1], a.shape[0], refd.shape[1], refd.shape[0])
    # Noise of the reference at clrt's pixel size: v_R per clrt pixel = v_N * N / (R f^2).
    k = N / (R * f * f)
    # PNG at N < R: the 8-bit clamp and floor of a noisier image shift its block means (hw3 spheres_dof:
    # block ratio 1.22 at 4 vs 16 spp, 0.48 at 16 vs 16), so only the pixel scale is judged there.
    scales = (1,) if (not hdr and N < R) else (1, max(1, BLOCK // f))
    ratios = []
    for scale in scales:
        ad, bd, rd = down(a, scale), down(b, scale), down(refd, scale)
        wgt = 1.0 / (rd ** 2 + 1e-2) if hdr else 1.0
        to_ref = float(np.mean(wgt * (ad - rd) ** 2))
        noise = float(np.mean(wgt * (ad - bd) ** 2))
        limit = noise * (1.0 + k)
        ratios.append(to_ref / limit if limit > 0 else (0.0 if to_ref == 0 else float("inf")))
    ok_means, mean_text = judge_means(a, b, refd, k)
    worst = max(ratios)
    block = "%dx%d block %.2f" % (BLOCK, BLOCK, ratios[1]) if len(ratios) > 1 else "blocks not judged at N < R"
    what = "%s err/limit %.2f (pixel %.2f, %s; %d vs %d spp%s%s); %s" % (
        "relMSE" if hdr else "MSE", worst, ratios[0], block, N, R, ", 1/%d res" % f if f > 1 else "",
        ", 1 row in %d" % k_rows if k_rows > 1 else "", mean_text)
    return worst <= 1.0 and ok_means, what


def judge_means(a, b, ref, k):
    """Per-channel image means: |mean(a) / mean(ref) - 1| <= 1% + 3 sigma, sigma from the two renders' pixel
    differences (independent pixels) and the reference's noise taken as clrt's at its spp (k = v_R / v_N)."""
    n = a.shape[0] * a.shape[1]
    ma, mr = a.reshape(-1, 3).mean(axis=0), np.maximum(ref.reshape(-1, 3).mean(axis=0), 1e-12)
    var_ma = (a - b).reshape(-1, 3).var(axis=0) / (2.0 * n)
    sigma = np.sqrt(var_ma * (1.0 + k)) / mr
    tol = 0.01 + 3.0 * sigma
    ratio = ma / mr
    ok = bool(np.all(np.abs(ratio - 1.0) <= tol))
    return ok, "mean ratio %.3f %.3f %.3f (within %.1f%%)" % (*ratio, 100 * float(tol.max()))


def blocks(img, g):
    """G x G x (pixels per block) x 3: the image cut into a g x g grid of equal blocks."""
    h, w = img.shape[0] // g * g, img.shape[1] // g * g
    bh, bw = h // g, w // g
    return img[:h, :w].reshape(g, bh, g, bw, 3).transpose(0, 2, 1, 3, 4).reshape(g, g, bh * bw, 3)


def judge_roulette(r, scene, cam, ref, reduced, rr_rule):
    """Russian-roulette cameras: block means of values clipped at the reference's percentile (the 2026-12-03
    study's method), the tolerance from clrt's two renders. Renders keep the reference's spp and pixels (a
    clipped mean depends on a pixel's sample count and footprint); --reduced renders every 8th row only."""
    R = cam["spp"]
    h, w = ref.shape[:2]
    if w % RR_GRID or h % RR_GRID:
        return False, "size %dx%d is not divisible into %dx%d blocks" % (w, h, RR_GRID, RR_GRID)
    exr = cam["image"].lower().endswith(".exr")  # a --part file is an EXR: a PNG reference needs the whole image
    k = REDUCED_RR_ROWS if reduced and exr and h % (RR_GRID * REDUCED_RR_ROWS) == 0 else 1
    imgs = []
    for seed in (1, 2):
        img, err = r.render(scene, cam["id"], cam["image"], seed, spp=R, sampler="independent", rr_rule=rr_rule,
                            rows_of=(k, w) if k > 1 else None, mesh_lights="area")
        if err:
            return False, err
        if img.shape[:2] != (h, w):
            return False, "size %dx%d, reference %dx%d" % (img.shape[1], img.shape[0], w, h)
        imgs.append(img)
    rb = blocks(ref, RR_GRID)
    bound = np.percentile(rb, RR_PERCENTILE, axis=2, keepdims=True)   # G x G x 1 x 3, from all its pixels
    # The rendered rows of each block (every k-th row of the image, the same pixels in both renders).
    picked = blocks(np.repeat((np.arange(h) % k == 0)[:, None, None], w, axis=1).repeat(3, axis=2), RR_GRID)
    sel = picked[0, 0, :, 0] > 0        # the same pattern in every block (h divisible by RR_GRID * k)
    ca, cb, cr = (np.minimum(blocks(i, RR_GRID)[:, :, sel], bound) for i in (*imgs, ref))
    n = ca.shape[2]
    m_clrt = 0.5 * (ca.mean(axis=2) + cb.mean(axis=2))
    m_ref = cr.mean(axis=2)
    # Per-pixel variance of a clipped value, from the two renders' differences (independent pixels); the
    # reference's pixels (the same ones) have the same (same spp, same rule when the rule is right).
    v_pix = (ca - cb).var(axis=2) / 2.0
    sigma = np.sqrt(v_pix * (1.0 / (2.0 * n) + 1.0 / n))
    limit = RR_FLOOR * m_ref + RR_SIGMAS * sigma
    dev = np.abs(m_clrt - m_ref)
    score = np.where(limit > 0, dev / np.where(limit > 0, limit, 1.0), np.where(dev > 0, np.inf, 0.0))
    ratio = m_clrt / np.maximum(m_ref, 1e-12)
    worst = float(score.max())
    bi, bj, ch = np.unravel_index(int(np.argmax(score)), score.shape)
    # The whole image: the mean of the blocks' clipped means (equal blocks), its sigma from theirs.
    g2 = RR_GRID * RR_GRID
    im_clrt, im_ref = m_clrt.mean(axis=(0, 1)), m_ref.mean(axis=(0, 1))
    im_limit = RR_FLOOR * im_ref + RR_SIGMAS * np.sqrt((sigma ** 2).sum(axis=(0, 1))) / g2
    im_ratio = im_clrt / np.maximum(im_ref, 1e-12)
    im_worst = float(np.max(np.abs(im_clrt - im_ref) / np.maximum(im_limit, 1e-300)))
    what = ("image clipped-mean ratio %.3f %.3f %.3f (within %.1f%%: %.2f of it); %dx%d blocks %.3f-%.3f, worst %.2f "
            "of its %.1f%% (row %d col %d %s: %.3f), %d over; %d vs %d spp%s, --rr-rule %s") % (
        *im_ratio, 100 * float(np.max(im_limit / np.maximum(im_ref, 1e-12))), im_worst, RR_GRID, RR_GRID,
        float(ratio.min()), float(ratio.max()), worst, 100 * float(limit[bi, bj, ch] / max(m_ref[bi, bj, ch], 1e-12)),
        bi, bj, "RGB"[ch], float(ratio[bi, bj, ch]), int((score > 1.0).sum()), R, R, ", 1 row in %d" % k if k > 1 else "",
        rr_rule)
    return worst <= 1.0 and im_worst <= 1.0, what


# ---------------------------------------------------------------- main

def read_expected(path):
    """{(scene, camera id): line} from the expected-failures list ('scene camera-id  # figure')."""
    exp = {}
    if not path:
        return exp
    with open(path) as fh:
        for line in fh:
            body = line.split("#", 1)[0].split()
            if len(body) >= 2:
                exp[(body[0], body[1])] = line.strip()
    return exp


def judge_camera(r, rel, path, root, cam, reduced, rr_rule="course"):
    """(rule, ok, figure) for one camera: ok is None when it is SKIPPED (figure: the reason)."""
    scene_dir = os.path.dirname(path)
    hdr = cam["image"].lower().endswith(".exr")
    traits, perlin = scene_traits(root)
    traits |= cam["traits"]
    rule = "perlin" if perlin else ("roulette" if cam["rr"] else ("sampled" if traits else "deterministic"))
    missing = missing_inputs(root, scene_dir)
    if missing:
        return rule, None, "missing input: " + ", ".join(missing)
    if rel in KNOWN_EDITED:
        return rule, None, KNOWN_EDITED[rel]
    if hdr and not HAVE_OPENEXR:
        return rule, None, "no OpenEXR Python module to read the EXR reference (scripts/check_course installs it)"
    refs = reference_candidates(path, cam["image"])
    if len(refs) > 1:
        return rule, None, "ambiguous reference, %d files equally near the scene: %s (--references-exclude)" % (
            len(refs), ", ".join(os.path.relpath(p, REF_ROOT) for p in refs))
    ref = read_image(refs[0])
    with open(refs[0], "rb") as f:
        ref_spp = REFERENCE_SPP.get(hashlib.md5(f.read()).hexdigest())
    if ref_spp:
        renamed = {"NumSamples %d" % cam["spp"]}, {"NumSamples %d, the reference's %d" % (cam["spp"], ref_spp)}
        traits = (traits - renamed[0]) | renamed[1]
        cam = dict(cam, spp=ref_spp, traits=(cam["traits"] - renamed[0]) | renamed[1])
    if rule == "deterministic":
        return (rule, *judge_deterministic(r, path, cam, ref, hdr))
    if rule == "perlin":
        return (rule, *judge_perlin(r, path, cam, ref, hdr))
    if rule == "roulette":
        ok, figure = judge_roulette(r, path, cam, ref, reduced, rr_rule)
    else:
        ok, figure = judge_sampled(r, path, cam, ref, hdr, reduced, r.args.sampler, traits)
    return rule, ok, figure + " [" + ", ".join(sorted(traits)) + "]"


class Tally:
    """Counts of ok / FAIL / SKIPPED, and the comparison with the expected-failures list."""

    def __init__(self, expected_path):
        self.path, self.expected = expected_path, read_expected(expected_path)
        self.counts = {"ok": 0, "FAIL": 0, "SKIPPED": 0}
        self.unexpected, self.listed, self.now_passing, self.seen = [], [], [], set()

    def add(self, key, status):
        """Counts one camera; returns the note for its line."""
        self.counts[status] += 1
        self.seen.add(key)
        name = os.path.basename(self.path)
        if status == "FAIL" and self.path:
            if key in self.expected:
                self.listed.append(key)
                return " (listed in %s)" % name
            self.unexpected.append(key)
            return " (NEW: not in %s)" % name
        if status == "ok" and key in self.expected:
            self.now_passing.append(key)
            return " (listed as failing: remove it from %s)" % name
        return ""

    def report(self, mode, seconds, only):
        c = self.counts
        print("check_course: %d cameras: %d ok, %d FAIL, %d SKIPPED; %s mode, %.0f s" % (
            sum(c.values()), c["ok"], c["FAIL"], c["SKIPPED"], mode, seconds))
        if not self.path:
            return 1 if c["FAIL"] else 0
        gone = sorted(k for k in self.expected if k not in self.seen and not only)
        print("check_course: against %s: %d new failure(s), %d listed failure(s), %d listed camera(s) now pass%s" % (
            self.path, len(self.unexpected), len(self.listed), len(self.now_passing),
            "; %d listed camera(s) not checked: %s" % (len(gone), ", ".join("%s cam %s" % g for g in gone)) if gone else ""))
        for k in self.unexpected:
            print("check_course: NEW FAIL %s cam %s" % k)
        for k in self.now_passing:
            print("check_course: now passes, remove from the list: %s cam %s" % k)
        return 1 if self.unexpected else 0


def check_scene(r, tally, rel, path, reduced, rr_rule):
    """Prints one line per camera of the scene that has a reference."""
    try:
        root = load_scene_tree(path)
    except ValueError as e:
        print("%-44s cam ?   %-36s %-13s FAIL    unreadable scene: %s%s" % (rel, "?", "-", e, tally.add((rel, "?"), "FAIL")))
        return
    for cam in cameras_of(root):
        if not reference_candidates(path, cam["image"]):
            continue  # this camera has no reference
        t0 = time.time()
        rule, ok, figure = judge_camera(r, rel, path, root, cam, reduced, rr_rule)
        status = "SKIPPED" if ok is None else ("ok" if ok else "FAIL")
        note = tally.add((rel, cam["id"]), status)
        print("%-44s cam %-3s %-36s %-13s %-7s %s (%.0f s)%s" % (
            rel, cam["id"], cam["image"], rule, status, figure, time.time() - t0, note), flush=True)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--scenes", default=os.path.join(ROOT, "..", "shared", "scenes"))
    ap.add_argument("--clrt", default=os.path.join(ROOT, "build", "clrt"))
    ap.add_argument("--device", default="cpu")
    ap.add_argument("--reduced", action="store_true", help="fewer spp / pixels for sampled scenes (CI)")
    ap.add_argument("--expected", default="", help="expected-failures list (tests/course_expected_failures.txt)")
    ap.add_argument("--only", default="", help="regular expression: check only the scenes whose path matches")
    ap.add_argument("--timeout", type=int, default=1800, help="seconds per clrt render")
    ap.add_argument("--rr-rule", default="course", choices=["course", "unbiased"],
                    help="clrt's --rr-rule for the roulette rule's renders (default course, as the references; "
                         "unbiased shows the rule failing)")
    ap.add_argument("--sampler", default="independent", choices=["independent", "stratified"],
                    help="clrt's --sampler for the sampled rule's renders (default independent); where that fails on a "
                         "classic camera with depth of field or an area light, --sampler correlated is judged too")
    ap.add_argument("--rows", type=int, default=1, metavar="K",
                    help="full mode: the sampled rule renders cameras with EXR references on every K-th pixel row only, "
                         "at the reference's spp (clrt render --part 1/K), and judges those rows (e.g. Veach Ajar's "
                         "6400 spp); default 1: the whole image")
    ap.add_argument("--references", default="",
                    help="folder searched (recursively) for each camera's reference image by its file name, instead "
                         "of each scene folder's _reference_outputs/ (course packages laid out as inputs/ and outputs/); "
                         "where several are equally near a scene the camera is SKIPPED as ambiguous")
    ap.add_argument("--references-exclude", default="", metavar="REGEX",
                    help="with --references: leave out the images whose path relative to that folder matches REGEX "
                         "(e.g. 'my_outputs/': a student's own renders beside the course's)")
    args = ap.parse_args()
    global REF_INDEX, REF_ROOT
    if args.references:
        REF_ROOT = os.path.abspath(args.references)
        REF_INDEX = index_references(args.references, args.references_exclude)
    scenes_root = os.path.normpath(args.scenes)
    if not os.path.isdir(scenes_root):
        print("check_course: %s is not there: nothing to check" % scenes_root)
        return 0
    start = time.time()
    tally = Tally(args.expected)
    found, unreferenced = find_scenes(scenes_root)
    for top, n in unreferenced:
        print("%-44s %d scene(s), no reference images in ../shared: not checked" % (top + "/", n))
    with tempfile.TemporaryDirectory(prefix="check_course.") as tmp:
        r = Renderer(args, tmp)
        for rel, path in found:
            if not args.only or re.search(args.only, rel):
                check_scene(r, tally, rel, path, args.reduced, args.rr_rule)
    return tally.report("reduced" if args.reduced else "full", time.time() - start, args.only)


if __name__ == "__main__":
    sys.exit(main())
