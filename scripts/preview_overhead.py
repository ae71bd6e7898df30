#!/usr/bin/env python3
"""preview_overhead.py — what `clrt render --preview` costs the render: the same progressive render
(scenes/preview_box.xml camera 1, a fixed number of passes: --target-error 1e-12 stops at the --spp cap)
run alternately without the preview and with it and one viewer that polls like the page does
(status.json 4 times a second, image.png of the current camera whenever a new image is published).
Reports per mode the median of the `render=` time of clrt's stats line (wall time: on a shared machine
its noise can exceed the effect) and of the process's CPU time (user + system, from wait4: what the
preview's threads add, which on a CPU device is taken from the render), and the differences in percent.
Usage: python3 scripts/preview_overhead.py [--clrt build/clrt] [--runs 5] [--resolution 160x120]
       [--spp 256] [--device cpu]"""
import argparse
import json
import os
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
           "--device", args.device]
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
    times, cpu = {False: [], True: []}, {False: [], True: []}
    with tempfile.TemporaryDirectory() as out:
        run(args, out, False)  # warm-up: kernel cache
        for i in range(args.runs):
            for preview in (False, True) if i % 2 == 0 else (True, False):
                t, c, counts = run(args, out, preview)
                times[preview].append(t)
                cpu[preview].append(c)
                print("run %d %-12s render %.3f s, cpu %.3f s%s" % (i + 1, "preview" if preview else "no preview", t, c,
                      " (viewer: %d status, %d images; preview's own time: render thread %.4f s, server %.4f s)" %
                      (counts["status"], counts["images"], counts["renderThread"], counts["server"]) if preview else ""),
                      flush=True)
    a, b = statistics.median(times[False]), statistics.median(times[True])
    print("median render time: %.3f s without the preview, %.3f s with one viewer: %+.1f%%" % (a, b, 100 * (b - a) / a))
    a, b = statistics.median(cpu[False]), statistics.median(cpu[True])
    print("median CPU time:    %.3f s without the preview, %.3f s with one viewer: %+.1f%%" % (a, b, 100 * (b - a) / a))


if __name__ == "__main__":
    main()
