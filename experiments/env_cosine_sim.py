#!/usr/bin/env python3
# env_cosine_sim.py — does the mis env strategy's cosine-weighted light sampling (src/flatten/env_distribution.h,
# EnvCosineTable) beat the map's own distribution, for every normal? A numpy model, not clrt's code: per
# texel of a lat-long map, the exact variance of the 1+1 MIS estimate (one light sample, one cosine sample,
# power heuristic) of E(n) = ∫ L(w) max(0, n.w) dw, no visibility, relative to E(n)^2, for 16 normals (up and
# 15 random). Light sampling densities compared with the map's (luminance + 1e-3 of the mean, per texel):
#   cone+texel   (clrt's): a bucket of a k x k octahedral grid of normals; cells of f x f texels weighted by
#                the map's mass in the cell x (the largest cosine between the cell centre and any normal of
#                the bucket, cos(max(0, θ − radius)), + floor); a texel of the cell by its share of the mass;
#   centre+texel: the same with the cosine to the bucket's centre;
#   centre coarse: the centre's cosine, uniform within cells of f x f texels (no texel step).
# Prints, per variant, the variance ratio map/variant: min and median over the normals (> 1: better).
# Usage (the bench venv): build/bench-venv/bin/python experiments/env_cosine_sim.py ../shared/envmaps/courtyard.exr
# Printed 2026-11-30 for the 8 maps of ../shared/envmaps, min / median over the normals:
#   cone+texel (k = 12, floor 0.01, cells of 8 x 8): courtyard 3.19/4.31, sunset 1.80/2.83, city 1.92/2.62,
#     night 1.40/4.85, sunrise 1.41/2.25, interior 1.98/3.90, studio 1.79/7.18, forest 1.90/3.76;
#   centre+texel: medians higher (2.63-9.72) but min 0.35 (night) and 0.78 (studio);
#   centre coarse (k = 6, floor 0.03, cells of 2 x 2): min 0.13-2.60 (loses on 6 of the 8 maps).
import sys, numpy as np, OpenEXR, Imath
f = OpenEXR.InputFile(sys.argv[1]); dw = f.header()['dataWindow']; W, H = dw.max.x-dw.min.x+1, dw.max.y-dw.min.y+1
img = np.stack([np.frombuffer(f.channel(c, Imath.PixelType(Imath.PixelType.FLOAT)), np.float32).reshape(H, W) for c in "RGB"], -1).astype(np.float64)
lum = np.nan_to_num(img, nan=0.0, posinf=0.0).clip(0) @ np.array([0.2126, 0.7152, 0.0722])
th = (np.arange(H) + 0.5) / H * np.pi; ph = (np.arange(W) + 0.5) / W * 2 * np.pi
D = np.stack([np.sin(th)[:, None] * np.cos(ph)[None], np.cos(th)[:, None] * np.ones(W)[None], np.sin(th)[:, None] * np.sin(ph)[None]], -1)
dOm = (2 * np.pi / W) * (np.pi / H) * np.sin(th)[:, None] * np.ones((1, W))
print("%s %dx%d; share of its luminance below the horizon (y < 0): %.3f" % (sys.argv[1].split('/')[-1], W, H, (lum * dOm)[D[..., 1] < 0].sum() / (lum * dOm).sum()))

def mis_relvar(nrm, p):  # p: light-sampling density per steradian, per texel (normalised here)
    cos = np.maximum(0, D @ nrm); fv = lum * cos
    pl = p / (p * dOm).sum(); pb = cos / np.pi
    den = pl ** 2 + pb ** 2 + 1e-300
    gl = np.where(pl > 0, fv * (pl ** 2 / den) / np.maximum(pl, 1e-300), 0)
    gb = np.where(pb > 0, fv * (pb ** 2 / den) / np.maximum(pb, 1e-300), 0)
    I = (fv * dOm).sum()
    El, Eb = (gl * pl * dOm).sum(), (gb * pb * dOm).sum()
    assert abs((El + Eb) / I - 1) < 1e-9  # unbiased: the weights sum to one wherever f > 0
    return ((gl ** 2 * pl * dOm).sum() - El ** 2 + (gb ** 2 * pb * dOm).sum() - Eb ** 2) / I ** 2

def oct_dir(a, b):  # as octahedralDir in env_distribution.cpp
    x, z = a, b; y = 1 - abs(x) - abs(z)
    if y < 0: x, z = (1 - abs(b)) * np.sign(a), (1 - abs(a)) * np.sign(b)
    v = np.array([x, y, z]); return v / np.linalg.norm(v)

def buckets(k):  # centres and radii (largest angle to the cell's border)
    out = []
    for bj in range(k):
        for bi in range(k):
            c = oct_dir((bi + 0.5) / k * 2 - 1, (bj + 0.5) / k * 2 - 1)
            border = [oct_dir((bi + s) / k * 2 - 1, (bj + t) / k * 2 - 1) for s in np.linspace(0, 1, 33) for t in (0, 1)] + \
                     [oct_dir((bi + s) / k * 2 - 1, (bj + t) / k * 2 - 1) for t in np.linspace(0, 1, 33) for s in (0, 1)]
            out.append((c, max(np.arccos(np.clip(d @ c, -1, 1)) for d in border)))
    return out

own = lum + 1e-3 * (lum * dOm).sum() / dOm.sum()
def cells(a, f):  # sum over f x f texel cells
    return a.reshape(H // f, f, W // f, f).sum((1, 3))
def spread(c, f):
    return np.repeat(np.repeat(c, f, 0), f, 1)
def density(nk, radius, floor, f, texel):
    cellCentreDir = D.reshape(H // f, f, W // f, f, 3).mean((1, 3)); cellCentreDir /= np.linalg.norm(cellCentreDir, axis=-1, keepdims=True)
    theta = np.arccos(np.clip(cellCentreDir @ nk, -1, 1))
    cosMax = np.where(theta - radius < np.pi / 2, np.cos(np.clip(theta - radius, 0, None)), 0.0)
    mass = cells(own * dOm, f) * (cosMax + floor)
    if texel:  # texel by its share of the cell's mass
        return spread(mass / cells(own * dOm, f), f) * own
    return spread(mass / cells(dOm, f), f)  # uniform in solid angle within the cell

rng = np.random.default_rng(3)
normals = [np.array([0, 1.0, 0])] + [v / np.linalg.norm(v) for v in rng.normal(size=(15, 3))]
for name, k, floor, f, cone, texel in [("cone+texel", 12, 0.01, 8, True, True), ("centre+texel", 12, 0.01, 8, False, True),
                                         ("centre coarse", 6, 0.03, 2, False, False)]:
    B = buckets(k); r = []
    for n in normals:
        c, radius = B[int(np.argmax([b @ n for b, _ in B]))]
        r.append(mis_relvar(n, own) / mis_relvar(n, density(c, radius if cone else 0.0, floor, f, texel)))
    print("%-13s (k %d, floor %g, cells %dx%d): min %.2f median %.2f  [%s]" % (name, k, floor, f, f, min(r), np.median(r), " ".join("%.2f" % x for x in r)))
