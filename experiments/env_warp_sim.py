#!/usr/bin/env python3
# env_warp_sim.py — would a hierarchical (quadtree) warp of the environment's importance distribution keep a
# (0,2)-net's strata better than clrt's marginal/conditional inversion? A numpy model, not clrt's code:
# per-cell weights luminance x sin(theta) (+1e-3 of the mean), bilinear luminance, uniform (u, v) within a
# cell; for 5 shading normals, the relative variance of a light-sampling-only estimate of
# E(n) = ∫ L(w) max(0, n.w) dw from N samples, over 300 repetitions: independent uniforms, and scipy's
# scrambled Sobol points (a (0,2)-net), each through both warps. Reads an EXR lat-long map (W = 2H,
# powers of two). Usage (the bench venv, which sees Debian packages, plus Debian python3-scipy):
#   build/bench-venv/bin/python experiments/env_warp_sim.py ../shared/envmaps/courtyard.exr 16
# Printed 2026-11-30 (courtyard, 16 samples): net variance quad/rowcol 1.20 (n = up), 0.52, 0.65, 0.50,
# 0.53; at 64 samples 2.94 (up), 0.12, 0.36, 0.38, 0.54 (README "Tried for time per sample ...").
import sys, numpy as np, OpenEXR, Imath
from scipy.stats import qmc
f = OpenEXR.InputFile(sys.argv[1]); dw = f.header()['dataWindow']; W, H = dw.max.x-dw.min.x+1, dw.max.y-dw.min.y+1
img = np.stack([np.frombuffer(f.channel(c, Imath.PixelType(Imath.PixelType.FLOAT)), np.float32).reshape(H, W) for c in "RGB"], -1).astype(np.float64)
lum = img @ np.array([0.2126, 0.7152, 0.0722])
th = (np.arange(H) + 0.5) / H * np.pi
w = lum * np.sin(th)[:, None]; w += 1e-3 * w.mean(); P = w / w.sum()
# (a) row/column CDFs
marg = np.concatenate([[0], np.cumsum(P.sum(1))]); marg /= marg[-1]
cond = np.concatenate([np.zeros((H, 1)), np.cumsum(P, 1)], 1); cond /= cond[:, -1:]
def warp_rowcol(u):
    j = np.clip(np.searchsorted(marg, u[:, 1], side='right') - 1, 0, H - 1)
    dv = (u[:, 1] - marg[j]) / (marg[j + 1] - marg[j])
    i = np.array([np.clip(np.searchsorted(cond[jj], uu, side='right') - 1, 0, W - 1) for jj, uu in zip(j, u[:, 0])])
    du = (u[:, 0] - cond[j, i]) / (cond[j, i + 1] - cond[j, i])
    return i, j, du, dv
# (b) quadtree: pyramid of sums; levels from coarse (2x1) to fine (W x H); W = 2H, powers of two
levels = [P]
while levels[-1].shape[0] > 1:
    q = levels[-1]; levels.append(q[0::2, 0::2] + q[1::2, 0::2] + q[0::2, 1::2] + q[1::2, 1::2])
levels = levels[::-1]  # levels[0]: 1 x 2
def warp_quad(u):
    u = u.copy(); n = len(u)
    top = levels[0][0]; pl = top[0] / top.sum()
    i = (u[:, 0] >= pl).astype(int); u[:, 0] = np.where(i == 0, u[:, 0] / pl, (u[:, 0] - pl) / (1 - pl)); j = np.zeros(n, int)
    for L in levels[1:]:
        i2, j2 = 2 * i, 2 * j
        a, b, c, d = L[j2, i2], L[j2, i2 + 1], L[j2 + 1, i2], L[j2 + 1, i2 + 1]
        pl = (a + c) / (a + b + c + d)
        right = u[:, 0] >= pl; u[:, 0] = np.where(right, (u[:, 0] - pl) / (1 - pl), u[:, 0] / pl)
        t = np.where(right, b, a); bt = np.where(right, d, c); pt = t / (t + bt)
        down = u[:, 1] >= pt; u[:, 1] = np.where(down, (u[:, 1] - pt) / (1 - pt), u[:, 1] / pt)
        i = i2 + right; j = j2 + down
    return i, j, np.clip(u[:, 0], 0, 1), np.clip(u[:, 1], 0, 1)
def bilinear(uu, vv):
    px, py = uu * W - 0.5, vv * H - 0.5; x0 = np.floor(px).astype(int); y0 = np.floor(py).astype(int); fx, fy = px - x0, py - y0
    X0, X1 = x0 % W, (x0 + 1) % W; Y0, Y1 = np.clip(y0, 0, H - 1), np.clip(y0 + 1, 0, H - 1)
    l = lambda y, x: lum[y, x]
    return l(Y0, X0) * (1 - fx) * (1 - fy) + l(Y0, X1) * fx * (1 - fy) + l(Y1, X0) * (1 - fx) * fy + l(Y1, X1) * fx * fy
def estimate(warp, u, nrm):
    i, j, du, dv = warp(u)
    uu, vv = (i + du) / W, (j + dv) / H
    phi, theta = 2 * np.pi * uu, np.pi * vv
    d = np.stack([np.sin(theta) * np.cos(phi), np.cos(theta), np.sin(theta) * np.sin(phi)], 1)
    pdf = P[j, i] * W * H / (2 * np.pi ** 2 * np.maximum(np.sin(theta), 1e-12))
    return np.mean(bilinear(uu, vv) * np.maximum(0, d @ nrm) / pdf)
rng = np.random.default_rng(1); N = int(sys.argv[2]); R = 300
normals = [np.array([0, 1.0, 0]), np.array([1.0, 0.3, 0]), np.array([0, 0.2, 1.0]), np.array([-1.0, 0.1, 0.2]), np.array([0.3, -0.2, -1.0])]
print("env %s %dx%d, %d samples per estimate, %d repetitions" % (sys.argv[1].split('/')[-1], W, H, N, R))
for nrm in normals:
    nrm = nrm / np.linalg.norm(nrm); res = {}
    for name, warp in (("rowcol", warp_rowcol), ("quad", warp_quad)):
        for kind in ("indep", "net"):
            vals = []
            for r in range(R):
                u = rng.random((N, 2)) if kind == "indep" else qmc.Sobol(2, scramble=True, seed=rng.integers(1 << 31)).random(N)
                vals.append(estimate(warp, np.minimum(u, 1 - 1e-12), nrm))
            res[name + "-" + kind] = (np.mean(vals), np.var(vals))
    m = res["rowcol-indep"][0]
    print("n=%s mean %.4g | var/mean^2: rowcol indep %.3g net %.3g | quad indep %.3g net %.3g | net quad/rowcol %.2f" % (
        np.round(nrm, 2), m, res["rowcol-indep"][1] / m**2, res["rowcol-net"][1] / m**2, res["quad-indep"][1] / m**2, res["quad-net"][1] / m**2,
        res["quad-net"][1] / res["rowcol-net"][1]))
