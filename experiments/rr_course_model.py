#!/usr/bin/env python3
"""rr_course_model.py — which Russian-roulette rule made the course's hw6 RR references?
(study: docs/studies/2026-12-03-russian-roulette-references.md)

  rr_course_model.py chain [--p 0.0156] [--albedo 0.803922] [--n 2000000]
      A Markov-chain model of the Cornell box seen on its back wall, cosine sampling, no NEE: every
      bounce hits the light (Le, black) with probability p, else a white wall (albedo ρ, f = ρ/π, weight
      ρ). For each candidate rule: mean / truth, and the per-path rates of the sample values ('atoms')
      Le·ρ (X1) and Le·π (Y1) relative to the rate of one-bounce light hits.
  rr_course_model.py refs RR.exr NORR.exr [x0 y0 x1 y1]
      Splits the white pixels of a region (default: the back wall of cameras 7/8) of a 100-spp
      reference into those atoms (pixel·100 = a sum of sample values) and prints the rate of each, for
      the RR reference (diffuse_importance_russian) and the depth-3 one without RR (diffuse_importance),
      and what the course rule predicts from the latter: X1 = (1 − f)·k1, Y1 = f·k1, X2 + Y2 ≈ k2.
Needs numpy (and OpenEXR for refs): build/bench-venv/bin/python."""
import itertools
import os
import sys

import numpy as np

LE, KD = 31.831, 0.803922


def chain(rule, p, rho, n, rng, max_bounces=60):
    """Sample values of n paths under `rule`; also returns the value kinds of one-bounce light hits."""
    f = rho / np.pi
    total = np.zeros(n)
    beta = np.ones(n)        # path weight (what clrt calls throughput)
    T = np.ones(n)           # product of BRDF values (the course's throughput)
    alive = np.ones(n, bool)
    x1 = y1 = 0
    for k in range(1, max_bounces + 1):
        # at wall hit k (k = 1: the camera ray's hit): roulette before the bounce, as each rule places it
        u = rng.random(n)
        if rule == "unbiased":                      # clrt: q = min(1, max β) after the bounce weight
            pass
        elif rule in ("T-prev", "depth3"):          # q = T so far (1 at the first hit), emission outside
            q = np.minimum(1, T)
            surv = u < q
            alive &= surv
            beta = np.where(surv, beta / q, beta)
        elif rule == "T-incl":                      # q = T including this hit's f, emission outside
            q = np.minimum(1, T * f)
            surv = u < q
            alive &= surv
            beta = np.where(surv, beta / q, beta)
        elif rule == "no-divide":                   # q = T, survivors not divided
            alive &= u < np.minimum(1, T)
        beta = beta * rho
        T = T * f
        if rule == "unbiased":
            q = np.minimum(1, beta)
            surv = rng.random(n) < q
            alive &= surv
            beta = np.where(surv, beta / q, beta)
        if rule == "depth3" and k > 3:
            alive[:] = False
        light = alive & (rng.random(n) < p)
        if rule == "course":
            # the light hit plays the roulette with q = T; killed: Le undivided, survived: Le/q
            q = np.minimum(1, T)
            surv = rng.random(n) < q
            val = np.where(surv, beta * LE / q, beta * LE)
            if k == 1:
                x1 += int(np.sum(light & ~surv)); y1 += int(np.sum(light & surv))
            total += np.where(light, val, 0)
            alive &= ~light
            # a wall hit plays it too (no radiance of its own without NEE): dies, or divides by q
            u2 = rng.random(n)
            surv_w = u2 < q
            alive &= surv_w
            beta = np.where(surv_w, beta / q, beta)
        else:
            if k == 1 and rule == "T-incl":
                y1 += int(np.sum(light))       # its one-bounce value is Le·ρ/f = Le·π
            elif k == 1:
                x1 += int(np.sum(light))
            total += np.where(light, beta * LE, 0)
            alive &= ~light
        if not alive.any():
            break
    return total, x1, y1


def run_chain(argv):
    p = float(argv[argv.index("--p") + 1]) if "--p" in argv else 0.0156
    rho = float(argv[argv.index("--albedo") + 1]) if "--albedo" in argv else KD
    n = int(argv[argv.index("--n") + 1]) if "--n" in argv else 2000000
    truth = LE * rho * p / (1 - rho * (1 - p))
    f = rho / np.pi
    print(f"chain model: p {p}, albedo {rho}, f {f:.4f}, truth {truth:.5f} (Le·ρ·p / (1 − ρ(1 − p)))")
    print(f"{'rule':10s} {'mean/truth':>10s} {'X1 rate':>8s} {'Y1 rate':>8s}   (rates per one-bounce light hit, p·n)")
    for rule in ["unbiased", "T-prev", "T-incl", "no-divide", "depth3", "course"]:
        rng = np.random.default_rng(1)
        vals, x1, y1 = chain(rule, p, rho, n, rng)
        print(f"{rule:10s} {vals.mean() / truth:10.4f} {x1 / (p * n):8.4f} {y1 / (p * n):8.4f}")
    # the course rule in closed form: hit k's light counts (2 − q_k) times, q_k = f^k
    terms = [(rho * (1 - p)) ** (k - 1) * p * rho * LE for k in range(1, 200)]
    course = sum(t * (2 - f ** k) for k, t in enumerate(terms, start=1))
    print(f"course rule in closed form: mean/truth {course / truth:.4f}")


def decompose(img, region, atoms):
    x0, y0, x1, y1 = region
    a = img[y0:y1, x0:x1].reshape(-1, 3) * 100
    white = a[(np.abs(a[:, 0] - a[:, 1]) < 0.05) & (np.abs(a[:, 0] - a[:, 2]) < 0.05)][:, 0]
    vals = np.array(list(atoms.values()))
    ranges = [range(12), range(8), range(5), range(3), range(3)][:len(vals)]
    combos = np.array(list(itertools.product(*ranges)))
    sums = combos @ vals
    counts = np.zeros(len(vals))
    bad = 0
    for v in white:
        i = int(np.argmin(np.abs(sums - v)))
        if abs(sums[i] - v) > 0.01 * max(v, 50):
            bad += 1
            continue
        counts += combos[i]
    return counts / len(white), len(white), len(a), bad


def run_refs(argv):
    sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "scripts"))
    import exr_stats
    rr, norr = exr_stats.load(argv[0]), exr_stats.load(argv[1])
    region = tuple(int(v) for v in argv[2:6]) if len(argv) >= 6 else (130, 110, 390, 280)
    pi, f = np.pi, KD / np.pi
    norr_atoms = {"k1 Le·kd": LE * KD, "k2 Le·kd²": LE * KD ** 2, "k3 Le·kd³": LE * KD ** 3}
    rr_atoms = {"X1 Le·kd": LE * KD, "Y1 Le·π": LE * pi, "X2 Le·π·kd": LE * pi * KD, "X3 Le·π³": LE * pi ** 3,
                "Y2 Le·π³/kd": LE * pi ** 3 / KD}
    r0, nw0, n0, bad0 = decompose(norr, region, norr_atoms)
    r1, nw1, n1, bad1 = decompose(rr, region, rr_atoms)
    print(f"{argv[1]}: {nw0} white pixels of {n0} ({bad0} not decomposed); samples per pixel:")
    for (name, v), r in zip(norr_atoms.items(), r0):
        print(f"  {name:12s} {v:8.2f}  {r:.4f}")
    print(f"{argv[0]}: {nw1} white pixels of {n1} ({bad1} not decomposed); samples per pixel:")
    pred = {"X1 Le·kd": (1 - f) * r0[0], "Y1 Le·π": f * r0[0]}
    for (name, v), r in zip(rr_atoms.items(), r1):
        extra = f"   course rule predicts {pred[name]:.4f}" if name in pred else ""
        print(f"  {name:12s} {v:8.2f}  {r:.4f}{extra}")
    print(f"  share of Y1 among one-bounce light hits: {r1[1] / (r1[0] + r1[1]):.4f} (course rule: f = kd/π = {f:.4f})")
    k2 = r1[2] * LE * pi * KD + r1[4] * LE * pi ** 3 / KD
    print(f"  two-bounce light: X2 + Y2 = {k2 / 100:.4f} per pixel, course rule (2 − f²)·k2 = "
          f"{(2 - f * f) * r0[1] * LE * KD ** 2 / 100:.4f}, unbiased k2 = {r0[1] * LE * KD ** 2 / 100:.4f}")


if __name__ == "__main__":
    if len(sys.argv) >= 2 and sys.argv[1] == "chain":
        run_chain(sys.argv[2:])
    elif len(sys.argv) >= 4 and sys.argv[1] == "refs":
        run_refs(sys.argv[2:])
    else:
        print(__doc__)
        sys.exit(1)
