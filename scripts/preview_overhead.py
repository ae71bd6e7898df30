#!/usr/bin/env python3
"""preview_overhead.py — what `clrt render --preview` costs the render: the same progressive render
(scenes/preview_box.xml camera 1, a fixed number of passes: --target-error 1e-12 stops at the --spp cap)
run alternately without the preview and with it and one viewer that polls like the page does
(status.json 4 times a second, image.png of the current camera whenever a new image is published).
Reports per mode the median of the `render=` time of clrt's stats line (wall time: on a shared machine
its noise can exceed the effect) and of the process's CPU time (user + system, from wait4: what the
preview's threads add, which on a CPU device is taken from the render), and the differences in percent.
Runs come in pairs (one of each mode, back to back, alternating which goes first), so a slow drift of the
machine's load cancels in each pair's ratio; the script prints the median of the pairs' ratios with a
bootstrap 95% interval (10,000 resamples, fixed seed), and the preview's own time as clrt measures it
(status.json: the render thread's time spent on the preview, the server threads' time) as a share of
the process's CPU time.
Usage: python3 scripts/preview_overhead.py [--clrt build/clrt] [--runs 5] [--resolution 160x120]
       [--spp 256] [--device cpu]"""
import argparse
import json
import os
import random
import re
import statistics
import subprocess
import sys
import tempfile
import threading
import time
import urllib.request

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def viewer(url, stop, counts):
    """Polls like page.js: status.json every 250 ms, image.png when the camera's version changes."""
    seen = -1
    while not stop.is_set():
        try:
            s = json.load(urllib.request.urlopen(url + "status.json", timeout=5))
            counts["status"] += 1
            counts["renderThread"], counts["server"] = s["renderThreadSeconds"], s["serverSeconds"]
            cur = s["current"]
            if cur >= 0 and s["cameras"][cur]["version"] != seen and s["cameras"][cur]["hasImage"]:
                seen = s["cameras"][cur]["version"]
                urllib.request.urlopen(url + "image.png?cam=%d&tmo=scene&ev=0&v=%d" % (cur, seen), timeout=5).read()
                counts["images"] += 1
        except Exception:
            pass
        stop.wait(0.25)


def run(args, out, preview):
    cmd = [args.clrt, "render", os.path.join(ROOT, "scenes", "preview_box.xml"), "--camera", "1", "-o", out,
           "--resolution", args.resolution, "--spp", str(args.spp), "--target-error", "1e-12", "--seed", "1",
           "--device", args.device, "-v"]
    if preview:
        cmd += ["--preview", "127.0.0.1:0"]
    log = os.path.join(out, "log.txt")
    with open(log, "w") as f:
        p = subprocess.Popen(cmd, stdout=f, stderr=f)
        stop, counts, t = threading.Event(), {"status": 0, "images": 0, "renderThread": 0, "server": 0}, None
        if preview:
            url = None
            while url is None and p.poll() is None:
                m = re.search(r"preview: (http://\S+/)\n", open(log).read())
                url = m.group(1) if m else time.sleep(0.05)
            if url:
                t = threading.Thread(target=viewer, args=(url, stop, counts))
                t.start()
        _, status, usage = os.wait4(p.pid, 0)
        rc = p.returncode = os.waitstatus_to_exitcode(status)
        stop.set()
        if t:
            t.join()
    text = open(log).read()
    m = re.search(r"render=([0-9.]+)s", text)
    own = re.search(r"preview: render thread ([0-9.]+) s, server threads ([0-9.]+) s", text)
    if own:  # the final figures (status.json's were the last the viewer polled)
        counts["renderThread"], counts["server"] = float(own.group(1)), float(own.group(2))
    if rc != 0 or not m:
        sys.exit("clrt failed (exit %d):\n%s" % (rc, text))
    return float(m.group(1)), usage.ru_utime + usage.ru_stime, counts


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--clrt", default=os.path.join(ROOT, "build", "clrt"))
    ap.add_argument("--runs", type=int, default=5)
    ap.add_argument("--resolution", default="160x120")
    ap.add_argument("--spp", type=int, default=256)
    ap.add_argument("--device", default="cpu")
    args = ap.parse_args()
    times, cpu, own = {False: [], True: []}, {False: [], True: []}, []
    with tempfile.TemporaryDirectory() as out:
        run(args, out, False)  # warm-up: kernel cache
        for i in range(args.runs):
            for preview in (False, True) if i % 2 == 0 else (True, False):
                t, c, counts = run(args, out, preview)
                times[preview].append(t)
                cpu[preview].append(c)
                if preview:
                    own.append(counts["renderThread"] + counts["server"])
                print("run %d %-12s render %.3f s, cpu %.3f s%s" % (i + 1, "preview" if preview else "no preview", t, c,
                      " (viewer: %d status, %d images; preview's own time: render thread %.4f s, server %.4f s)" %
                      (counts["status"], counts["images"], counts["renderThread"], counts["server"]) if preview else ""),
                      flush=True)
    for name, v in (("render time", times), ("CPU time   ", cpu)):
        a, b = statistics.median(v[False]), statistics.median(v[True])
        ratios = [y / x for x, y in zip(v[False], v[True])]
        lo, hi = bootstrap_median(ratios)
        print("median %s: %.3f s without the preview, %.3f s with one viewer: %+.1f%%; median of the %d pairs' "
              "ratios %+.1f%% (95%% interval %+.1f%% .. %+.1f%%)" % (name, a, b, 100 * (b - a) / a, len(ratios),
              100 * (statistics.median(ratios) - 1), 100 * (lo - 1), 100 * (hi - 1)))
    share = [o / c for o, c in zip(own, cpu[True])]
    print("the preview's own time (render thread + server) as a share of the process's CPU time: median %.2f%%, "
          "max %.2f%%" % (100 * statistics.median(share), 100 * max(share)))


def bootstrap_median(xs, n=10000):
    """95% interval of the median of xs by resampling (fixed seed: the same figures for the same runs)."""
    rng = random.Random(1)
    meds = sorted(statistics.median(rng.choices(xs, k=len(xs))) for _ in range(n))
    return meds[int(0.025 * n)], meds[int(0.975 * n) - 1]

if __name__ == "__main__":
    main()
