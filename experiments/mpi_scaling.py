#!/usr/bin/env python3
"""Scaling of `mpirun -np N clrt render` on this machine, and the figures of the README's model:
wall time of one process and of 1..N ranks (each rank's PoCL limited to --threads threads, so that a
rank is a fixed share of the machine), CPU seconds of the whole job (rusage of the children: less
sensitive to other jobs on a shared machine than wall time), what each rank sent per tile, how long it
waited for a tile id and took to send a tile, rank 0's time serving the others, and the renderer's
per-tile overhead (one process, --part 1/1 at several tile sizes). Checks that every run wrote the
same image bytes. Standard library only.

usage: python3 experiments/mpi_scaling.py [--runs 3] [--ranks 1,2] [--threads 1] [--scene scenes/demo.xml]
                                      [--resolution 640x480] [--spp 16] [--device cpu]
"""
import argparse
import hashlib
import os
import re
import resource
import statistics
import subprocess
import sys
import tempfile
import time

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")


def run(cmd, env):
    """Runs cmd; returns (wall seconds, CPU seconds of it and its children, stdout+stderr)."""
    r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.monotonic()
    p = subprocess.run(cmd, env=env, capture_output=True, text=True)
    wall = time.monotonic() - t0
    r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    if p.returncode != 0:
        sys.exit("failed (%d): %s\n%s" % (p.returncode, " ".join(cmd), p.stderr[-2000:]))
    cpu = (r1.ru_utime - r0.ru_utime) + (r1.ru_stime - r0.ru_stime)
    return wall, cpu, p.stdout + p.stderr


def stats(log):
    m = re.search(r"^stats: (.*)$", log, re.M)
    return {k: float(v.rstrip("s")) for k, v in (x.split("=") for x in m.group(1).split())}


def digest(folder):
    h = hashlib.md5()
    for name in sorted(os.listdir(folder)):
        if name.endswith(".png"):
            h.update(open(os.path.join(folder, name), "rb").read())
    return h.hexdigest()[:12]


def med(xs):
    return statistics.median(xs) if xs else float("nan")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--ranks", default="1,2")
    ap.add_argument("--threads", type=int, default=1, help="POCL_MAX_PTHREAD_COUNT of each rank (0: PoCL's default)")
    ap.add_argument("--scene", default=os.path.join(ROOT, "scenes", "demo.xml"))
    ap.add_argument("--resolution", default="640x480")
    ap.add_argument("--spp", type=int, default=16)
    ap.add_argument("--device", default="cpu")
    ap.add_argument("--clrt", default=os.path.join(ROOT, "build", "clrt"))
    ap.add_argument("--mpirun", default="mpirun")
    a = ap.parse_args()
    env = dict(os.environ, OMPI_MCA_plm="isolated", OMPI_MCA_btl_vader_single_copy_mechanism="none",
               HWLOC_COMPONENTS="-opencl")
    if a.threads > 0:
        env["POCL_MAX_PTHREAD_COUNT"] = str(a.threads)
    w, h = map(int, a.resolution.split("x"))
    base = [a.clrt, "render", a.scene, "--resolution", a.resolution, "--spp", str(a.spp), "--device", a.device]
    mpi = [a.mpirun, "--oversubscribe", "--allow-run-as-root", "-np"]
    print("machine: %d cores, load average %s; scene %s %s, %d spp, PoCL threads per rank: %s" % (
        os.cpu_count(), " ".join("%.2f" % x for x in os.getloadavg()), os.path.basename(a.scene), a.resolution, a.spp,
        a.threads or "default"))

    configs = [("1 process", [])] + [("mpirun -np %s" % n, mpi + [n]) for n in a.ranks.split(",")]
    digests, rows = set(), []
    with tempfile.TemporaryDirectory() as tmp:
        for _ in range(a.runs):  # interleaved, so that a change of load hits every configuration alike
            for label, prefix in configs:
                out = os.path.join(tmp, re.sub(r"\W+", "_", label))
                os.makedirs(out, exist_ok=True)
                wall, cpu, log = run(prefix + base + ["-o", out], env)
                digests.add(digest(out))
                s = stats(log)
                per = re.findall(r"^rank (\d+): (\d+) tiles, sent ([\d.]+) KB \(([\d.]+) KB a tile\); per tile ([\d.]+) ms "
                                 r"waiting for its id, ([\d.]+) ms sending it", log, re.M)
                served = re.search(r"^rank 0 .*: (\d+) tiles; served the other ranks for ([\d.]+) s in all \((\d+) messages",
                                   log, re.M)
                rows.append(dict(label=label, wall=wall, cpu=cpu, render=s["render"],
                                 setup=s["parse"] + s["flatten"] + s["bvh"] + s["build"], output=s["output"],
                                 kb=[float(p[3]) for p in per], wait=[float(p[4]) for p in per],
                                 send=[float(p[5]) for p in per], remote=sum(int(p[1]) for p in per),
                                 served=float(served.group(2)) if served else 0.0,
                                 messages=int(served.group(3)) if served else 0))
        print("\nimage digests (PNG bytes) of every run: %s (%s)" % (", ".join(sorted(digests)),
                                                                    "identical" if len(digests) == 1 else "DIFFERENT"))
        print("\n| run | wall s | render s | speed-up (wall) | CPU s | setup s | KB a tile | ms waiting for a tile id | ms sending a tile | rank 0 serving, ms a message |")
        print("|---|---|---|---|---|---|---|---|---|---|")
        ref = None
        for label, _ in configs:
            rs = [r for r in rows if r["label"] == label]
            wall = med([r["wall"] for r in rs])
            ref = ref or wall
            remote = sum(r["remote"] for r in rs)
            print("| %s | %.2f [%.2f-%.2f] | %.2f | %.2f | %.2f | %.2f | %s | %s | %s | %s |" % (
                label, wall, min(r["wall"] for r in rs), max(r["wall"] for r in rs), med([r["render"] for r in rs]),
                ref / wall, med([r["cpu"] for r in rs]), med([r["setup"] for r in rs]),
                "%.1f" % med(sum((r["kb"] for r in rs), [])) if remote else "-",
                "%.2f" % med(sum((r["wait"] for r in rs), [])) if remote else "-",
                "%.2f" % med(sum((r["send"] for r in rs), [])) if remote else "-",
                "%.3f" % (1e3 * sum(r["served"] for r in rs) / max(1, sum(r["messages"] for r in rs))) if remote else "-"))

        # The renderer's cost per tile: one process, the same image in tiles of several sizes.
        print("\n| tile pixels | tiles | render s (one process, --part 1/1) | CPU s (per tile over one tile) |")
        print("|---|---|---|---|")
        sizes = [256, 1024, 4096, 16384, w * h]
        res = {}
        for _ in range(a.runs):
            for tp in sizes:
                out = os.path.join(tmp, "tiles%d" % tp)
                os.makedirs(out, exist_ok=True)
                wall, cpu, log = run(base + ["-o", out, "--part", "1/1", "--tile-pixels", str(tp)], env)
                res.setdefault(tp, []).append((stats(log)["render"], cpu))
        one = med([x[0] for x in res[w * h]])
        cpu1 = med([x[1] for x in res[w * h]])
        for tp in sizes:
            n = (w * h + tp - 1) // tp
            r = med([x[0] for x in res[tp]])
            c = med([x[1] for x in res[tp]])
            extra = "" if n == 1 else " (%+.3f ms a tile over one tile)" % (1e3 * (c - cpu1) / (n - 1))
            print("| %d | %d | %.3f | %.2f%s |" % (tp, n, r, c, extra))
        print("\nrender time per pixel (all %d samples), one rank: %.2f us wall, %.2f us CPU" % (
            a.spp, 1e6 * one / (w * h), 1e6 * cpu1 / (w * h)))

        # Fixed cost of a job: mpirun start-up + every rank's parse/BVH/kernel build + output, measured
        # on a 16x12 image with 2 ranks.
        starts = []
        for _ in range(a.runs):
            out = os.path.join(tmp, "tiny")
            os.makedirs(out, exist_ok=True)
            starts.append(run(mpi + ["2", a.clrt, "render", a.scene, "--resolution", "16x12", "--spp", "1",
                                     "--device", a.device, "-o", out], env)[0])
        s0 = med(starts)
        print("fixed cost of a 2-rank job (16x12 image, 1 spp): %.2f s" % s0)
        remote = [r for r in rows if r["remote"]]
        c = sum(r["served"] for r in remote) / max(1, sum(r["messages"] for r in remote))  # seconds a message
        over = max(0.0, (med([x[1] for x in res[sizes[0]]]) - cpu1) / ((w * h + sizes[0] - 1) // sizes[0] - 1))
        model(cpu1 / (w * h), s0, over, c, (w, h), a.spp)


def model(wpix, s0, over, c, size0, spp0):
    """Predicted speed-up S(N) = T(1) / T(N) of N ranks, each as fast as one rank here:
    T(N) = S0 + max(ceil(n / N) (W / n + o), 12 Pix / B, 2 n c): n tiles of equal cost handed out
    dynamically (a rank takes the next tile when it finishes one), rank 0's link carrying 12 bytes a
    pixel, rank 0 handling 2 messages a tile. W = per-pixel CPU time here x pixels x (spp / spp here)."""
    print("\nmodel: W = %.3g us a pixel-sample x pixels x spp, S0 = %.2f s, per-tile overhead o = %.3g ms, "
          "rank 0 per message c = %.3g ms, 12 bytes a pixel to rank 0" % (1e6 * wpix / spp0, s0, 1e3 * over, 1e3 * c))
    ns = [1, 2, 4, 8, 16, 32, 64, 128, 256, 512]
    print("\n| image | spp | tiles | W (one rank) | " + " | ".join("N=%d" % n for n in ns) +
          " | ranks that fill rank 0's link, 1 / 10 Gb/s |")
    print("|---|---|---|---|" + "---|" * len(ns) + "---|")
    for (wd, ht, spp) in [(size0[0], size0[1], spp0), (1920, 1080, 64), (3840, 2160, 1024), (7680, 4320, 256)]:
        pix = wd * ht
        tile = min(65536, max(4096, (pix + 63) // 64))
        n = (pix + tile - 1) // tile
        W = wpix / spp0 * spp * pix
        def T(N, B):
            return s0 + max(-(-n // N) * (W / n + over), 12 * pix / B, 2 * n * c)
        cells = ["%.1f" % (T(1, 125e6) / T(N, 125e6)) for N in ns]
        nbw = [W / (12 * pix / B) for B in (125e6, 1250e6)]
        print("| %dx%d | %d | %d | %.3g s | %s | %.0f / %.0f |" % (wd, ht, spp, n, W, " | ".join(cells), nbw[0], nbw[1]))

if __name__ == "__main__":
    sys.exit(main())
