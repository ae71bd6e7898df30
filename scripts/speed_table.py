#!/usr/bin/python3
"""Speed table for the README: the machine (CPU model, cores, OpenCL device), then
  1. ray_bench on cube_point, veachAjar and the Audi TT: clrt's intersection kernels against Embree 3's
     single-ray API on the same camera/shadow/diffuse rays (Mrays/s and the ratio), medians of --runs;
  2. `clrt render` of the Audi TT (tt/scene_pisa_courtyard.xml) at 1 spp, --runs times: the median (and
     min-max) of every stage of the `stats:` line, and the time after parsing (flatten + bvh + kernel
     build + render + output), the issue's "renders in <= 1.5 s after parsing";
  3. the same for every scene given with --scenes (default: the three above), camera/shadow/secondary
     Mrays/s from the stats line (rays per second of device time of their trace kernel).
Prints Markdown on stdout. Builds build/clrt and build/ray_bench first (cmake --build build --target
ray_bench clrt; needs Debian libembree-dev); reads ../shared/scenes. Uses only the standard library.

usage: scripts/speed_table.py [--runs 5] [--device cpu] [--build build] [--threads 1,2] [--rays-only] [--embree-robust]
  --threads: one ray_bench table per thread count, each run with ray_bench --threads T (Embree on T
  threads, the process pinned to T CPUs, PoCL told T workers); default: one table, Embree on 2 threads,
  nothing pinned. --rays-only: the ray_bench tables only, no renders. --embree-robust: Embree with
  RTC_SCENE_FLAG_ROBUST (ray_bench --embree-robust), its mode for rays that must not slip between triangles.
"""
import argparse
import datetime
import os
import re
import statistics
import subprocess
import sys
import tempfile

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))
SHARED = os.path.abspath(os.path.join(ROOT, "..", "shared", "scenes"))
SCENES = [("cube_point", "hw5/cube_point.xml"), ("veachAjar", "classic/veachAjar.xml"),
          ("Audi TT (pisa_courtyard)", "hw5/tt/scene_pisa_courtyard.xml")]


def sh(cmd):
    try:
        return subprocess.run(cmd, capture_output=True, text=True)
    except OSError as e:  # a missing tool (lscpu on a bare machine) is reported, not fatal
        return subprocess.CompletedProcess(cmd, 127, "", str(e))


def machine(clrt, device):
    cpu = "?"
    for line in sh(["lscpu"]).stdout.splitlines():
        if line.startswith("Model name:"):
            cpu = line.split(":", 1)[1].strip()
    lines = sh([clrt, "devices"]).stdout.strip().splitlines()
    # The line of the device the spec names (first match): an index, platform:NAME, cpu/gpu, else the first.
    spec = device.lower()
    pick = [l for l in lines if (spec.isdigit() and l.startswith("[%s]" % spec)) or
            (spec.startswith("platform:") and spec[9:] in l.lower().split("(platform:", 1)[-1]) or
            (spec in ("cpu", "gpu") and re.match(r"\[\d+\]\s+%s\b" % spec.upper(), l))]
    dev = (pick or lines or ["?"])[0].strip()
    m = re.match(r"\[\d+\]\s+\S+\s+(.*?)\s+\(platform: (.*?)\)\s+compute units.*?driver:\s*(\S+)", dev)
    if m:  # "[0] CPU  NAME  (platform: P) ... driver: D" -> "NAME (P D)"
        dev = "%s (%s %s)" % (m.group(1), m.group(2), m.group(3))
    return cpu, os.cpu_count(), dev


def med(xs):
    return statistics.median(xs), min(xs), max(xs)


def fmt(m, digits=2):
    return "%.*f [%.*f–%.*f]" % (digits, m[0], digits, m[1], digits, m[2])


def ray_bench(exe, scene, runs, device, threads=None, robust=False):
    p = sh([exe, scene, "--runs", str(runs), "--device", device] + (["--threads", str(threads)] if threads else []) +
           (["--embree-robust"] if robust else []))
    if p.returncode != 0:
        return None, p.stderr.strip().splitlines()[-1:]
    rows = {}
    for line in p.stdout.splitlines():
        m = re.match(r"^(camera|shadow|diffuse)\s+(\d+)\s+([\d.]+)\s+([\d.]+)\s+([\d.]+)\s+([\d.]+)%", line)
        if m:
            rows[m.group(1)] = (float(m.group(3)), float(m.group(4)), float(m.group(5)), float(m.group(6)))
    tris = re.search(r"(\d+) triangles", p.stdout)
    return (rows, tris.group(1) if tris else "?"), None


def renders(clrt, scene, runs, device, spp):
    out = []
    with tempfile.TemporaryDirectory() as tmp:
        # One warm-up run, not counted: it fills the kernel binary cache (a scene's first run builds).
        sh([clrt, "render", scene, "-o", tmp, "--spp", str(spp), "--device", device])
        for i in range(runs):
            p = sh([clrt, "render", scene, "-o", tmp, "--spp", str(spp), "--device", device, "--seed", str(i + 1)])
            if p.returncode != 0:
                print("render failed:", scene, p.stderr.strip().splitlines()[-1:], file=sys.stderr)
                return []
            m = re.search(r"^stats: (.*)$", p.stdout, re.M)
            out.append({k: float(v.rstrip("s")) for k, v in (x.split("=") for x in m.group(1).split())})
    return out


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--runs", type=int, default=5)
    ap.add_argument("--device", default="cpu")
    ap.add_argument("--build", default=os.path.join(ROOT, "build"))
    ap.add_argument("--threads", default="", help="comma-separated thread counts for ray_bench, e.g. 1,2")
    ap.add_argument("--rays-only", action="store_true", help="only the ray_bench tables")
    ap.add_argument("--embree-robust", action="store_true", help="Embree in its robust mode (RTC_SCENE_FLAG_ROBUST)")
    a = ap.parse_args()
    clrt, rb = os.path.join(a.build, "clrt"), os.path.join(a.build, "ray_bench")
    # ray_bench is not in `all` (EXCLUDE_FROM_ALL): built here, it cannot lag behind the kernels it embeds.
    if os.path.exists(os.path.join(a.build, "CMakeCache.txt")):
        subprocess.run(["cmake", "--build", a.build, "--target", "ray_bench", "clrt"], stdout=subprocess.DEVNULL, check=True)
    cpu, cores, dev = machine(clrt, a.device)
    print("Measured %s on %s, %d cores; OpenCL device %s. Medians of %d runs [min–max].\n"
          % (datetime.date.today().isoformat(), cpu, cores, dev, a.runs))

    for threads in [int(t) for t in a.threads.split(",") if t] or [None]:
        if threads:
            print("ray_bench --threads %d%s (Embree on %d threads; the process pinned to %d CPUs):\n"
                  % (threads, " --embree-robust" if a.embree_robust else "", threads, threads))
        print("| scene | triangles | camera clrt / Embree%s Mrays/s (ratio) | shadow | diffuse | hit agreement |"
              % (" robust" if a.embree_robust else ""))
        print("|---|---|---|---|---|---|")
        for name, rel in SCENES:
            path = os.path.join(SHARED, rel)
            if not os.path.exists(path) or not os.path.exists(rb):
                continue
            res, err = ray_bench(rb, path, a.runs, a.device, threads, a.embree_robust)
            if res is None:
                print("| %s | ray_bench failed: %s | | | | |" % (name, err))
                continue
            rows, tris = res
            cells = ["%.2f / %.2f (%.2f)" % (rows[k][0], rows[k][1], rows[k][2]) for k in ("camera", "shadow", "diffuse")]
            agree = min(rows[k][3] for k in rows)
            print("| %s | %s | %s | %s | %s | ≥ %.3f%% |" % (name, tris, cells[0], cells[1], cells[2], agree))
        print()
    if a.rays_only:
        return

    print("\n`clrt render SCENE --spp 1` (full resolution, after one uncounted warm-up run that fills the kernel "
          "cache; seconds; Mrays/s per kind from the `stats:` line):\n")
    print("| scene | parse | flatten | bvh | kernel build | render | output | after parsing | camera | shadow | secondary |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for name, rel in SCENES:
        path = os.path.join(SHARED, rel)
        if not os.path.exists(path):
            continue
        st = renders(clrt, path, a.runs, a.device, 1)
        if not st:
            continue
        col = lambda k: med([s.get(k, 0.0) for s in st])
        after = med([s.get("flatten", 0) + s["bvh"] + s["build"] + s["render"] + s["output"] for s in st])
        print("| %s | %s | %s | %s | %s | %s | %s | **%s** | %s | %s | %s |" % (
            name, fmt(col("parse")), fmt(col("flatten")), fmt(col("bvh")), fmt(col("build")), fmt(col("render")),
            fmt(col("output")), fmt(after), fmt(col("camera_mrays"), 1), fmt(col("shadow_mrays"), 1),
            fmt(col("secondary_mrays"), 1)))


if __name__ == "__main__":
    main()
