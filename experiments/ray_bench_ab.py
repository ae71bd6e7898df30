#!/usr/bin/env python3
"""ray_bench_ab.py — two ray_bench builds (old, new) interleaved on the same scenes and thread counts.

On a shared machine the load changes from minute to minute, so one build's figures taken an hour after
the other's say little. This runs `OLD SCENE --runs R --threads T` and `NEW SCENE --runs R --threads T`
alternately, ROUNDS times (R = 3 by default: each process's median of 3 drops the first launch of the
shadow kernel, which includes PoCL's compile of it), and prints per scene, thread count and ray kind the medians over the rounds
of clrt Mrays/s (old, new), of new/old, and of clrt/Embree (each process times Embree on the same rays
right after clrt, so that ratio is the less load-sensitive figure). Standard library only.

usage: experiments/ray_bench_ab.py OLD_RAY_BENCH NEW_RAY_BENCH [--rounds 5] [--runs 3] [--threads 1,2] [--device cpu]
       [--scenes cube_point,veachAjar,tt]
"""
import argparse
import os
import statistics
import subprocess
import sys

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))
SHARED = os.path.abspath(os.path.join(ROOT, "..", "shared", "scenes"))
SCENES = {"cube_point": "hw5/cube_point.xml", "veachAjar": "classic/veachAjar.xml",
          "tt": "hw5/tt/scene_pisa_courtyard.xml"}
KINDS = ("camera", "shadow", "diffuse")


def run(exe, scene, threads, device, runs):
    """{kind: (clrt Mrays/s, embree Mrays/s)} of one ray_bench run."""
    p = subprocess.run([exe, scene, "--runs", str(runs), "--threads", str(threads), "--device", device],
                       capture_output=True, text=True)
    if p.returncode != 0:
        sys.exit("%s failed: %s" % (exe, p.stderr.strip()))
    return parse_rates(p.stdout)


def parse_rates(stdout):
    """ray_bench's per-kind lines as {kind: (clrt Mrays/s, embree Mrays/s)}."""
    out = {}
    for line in stdout.splitlines():
        f = line.split()
        if f and f[0] in KINDS and len(f) >= 4:
            out[f[0]] = (float(f[2]), float(f[3]))
    return out


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("old")
    ap.add_argument("new")
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--threads", default="1,2")
    ap.add_argument("--device", default="cpu")
    ap.add_argument("--scenes", default="cube_point,veachAjar,tt")
    a = ap.parse_args()
    print("| scene | threads | rays | clrt old Mrays/s | clrt new Mrays/s | new/old | clrt/Embree old | clrt/Embree new |")
    print("|---|---|---|---|---|---|---|---|")
    for name in a.scenes.split(","):
        scene = os.path.join(SHARED, SCENES.get(name, name))
        for t in [int(x) for x in a.threads.split(",")]:
            res = {"old": [], "new": []}
            for _ in range(a.rounds):
                for which in ("old", "new"):
                    res[which].append(run(getattr(a, which), scene, t, a.device, a.runs))
            for k in KINDS:
                med = statistics.median
                co = [r[k][0] for r in res["old"]]
                cn = [r[k][0] for r in res["new"]]
                ro = [r[k][0] / r[k][1] for r in res["old"]]
                rn = [r[k][0] / r[k][1] for r in res["new"]]
                gain = [n / o for n, o in zip(cn, co)]
                print("| %s | %d | %s | %.2f | %.2f | %.2f [%.2f–%.2f] | %.2f [%.2f–%.2f] | %.2f [%.2f–%.2f] |" %
                      (name, t, k, med(co), med(cn), med(gain), min(gain), max(gain), med(ro), min(ro), max(ro),
                       med(rn), min(rn), max(rn)))
            sys.stdout.flush()


if __name__ == "__main__":
    main()
