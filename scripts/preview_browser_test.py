#!/usr/bin/env python3
"""preview_browser_test.py — `clrt render --preview` in a real browser: headless Chromium (Debian's
chromium + chromium-driver) driven by Selenium (PyPI, in build/venv-preview) opens the page of a real
progressive render of scenes/preview_box.xml at a tiny resolution and checks that
  * a wrong token gets 403;
  * the image changes between passes and the spp counter rises;
  * a tone-map control changes the pixels (the page's own control, and the server's views of one image
    version: the scene's Photographic block against linear at +2 stops);
  * Stop writes the partial EXR (its header says so) and clrt exits with Ctrl-C's status, 130.
Screenshots go to OUT (default build/preview-test/). Usage:
  build/venv-preview/bin/python scripts/preview_browser_test.py [--clrt build/clrt] [--out DIR]
      [--resolution 96x72] [--device cpu] [--window 1100,760] [--shot-only FILE.png]
(docs/preview.png: --resolution 240x180 --time-limit 24 --window 960,660 --shot-only docs/preview.png)
Exit 0 when every check passed; prints one line per check and the time taken."""
import argparse
import hashlib
import os
import re
import subprocess
import sys
import time
import urllib.error
import urllib.request

from selenium import webdriver
from selenium.webdriver.chrome.options import Options
from selenium.webdriver.chrome.service import Service
from selenium.webdriver.common.by import By
from selenium.webdriver.support.ui import Select

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
failures = []


def check(ok, what):
    print(("ok    " if ok else "FAIL  ") + what, flush=True)
    if not ok:
        failures.append(what)


def wait_for(pred, timeout, step=0.1):
    end = time.time() + timeout
    while time.time() < end:
        v = pred()
        if v:
            return v
        time.sleep(step)
    return None


def start_render(args, outdir, log):
    cmd = [args.clrt, "render", os.path.join(ROOT, "scenes", "preview_box.xml"), "-o", outdir,
           "--resolution", args.resolution, "--time-limit", str(args.time_limit), "--spp", "65536",
           "--device", args.device, "--preview", "127.0.0.1:0"]
    proc = subprocess.Popen(cmd, stdout=log, stderr=log)
    url = wait_for(lambda: re.search(r"preview: (http://\S+/)\n", open(log.name).read()), 120)
    if not url:
        proc.kill()
        sys.exit("clrt printed no preview URL:\n" + open(log.name).read())
    return proc, url.group(1)


def browser(window):
    o = Options()
    for a in ["--headless=new", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage", "--window-size=" + window]:
        o.add_argument(a)
    o.binary_location = "/usr/bin/chromium"
    return webdriver.Chrome(service=Service("/usr/bin/chromedriver"), options=o)


# The pixels of an <img> (or of an image URL) as a hash, read through a canvas in the page.
PIXELS_OF_ELEMENT = """
const img = document.getElementById(arguments[0]);
if (!img || !img.naturalWidth) return null;
const c = document.createElement('canvas'); c.width = img.naturalWidth; c.height = img.naturalHeight;
const x = c.getContext('2d'); x.drawImage(img, 0, 0);
return Array.from(x.getImageData(0, 0, c.width, c.height).data).join(',');"""
PIXELS_OF_URL = """
const done = arguments[arguments.length - 1];
const img = new Image();
img.onload = () => { const c = document.createElement('canvas'); c.width = img.naturalWidth; c.height = img.naturalHeight;
  const x = c.getContext('2d'); x.drawImage(img, 0, 0);
  done(Array.from(x.getImageData(0, 0, c.width, c.height).data).join(',')); };
img.onerror = () => done(null);
img.src = arguments[0];"""


def digest(s):
    return hashlib.sha1(s.encode()).hexdigest()[:12] if s else None


def spp(drv):
    try:
        return int(drv.find_element(By.ID, "spp").text)
    except ValueError:
        return 0


def status(drv):
    return drv.execute_async_script(
        "const d = arguments[0]; fetch('status.json').then(r => r.json()).then(d, () => d(null));")


def tonemap_views_differ(drv):
    """The server's Photographic and linear views of one image version differ (retried if a pass lands between)."""
    for _ in range(10):
        s = status(drv)
        cam = s["current"]
        v = s["cameras"][cam]["version"]
        a = drv.execute_async_script(PIXELS_OF_URL, "image.png?cam=%d&tmo=scene&ev=0&v=%d" % (cam, v))
        b = drv.execute_async_script(PIXELS_OF_URL, "image.png?cam=%d&tmo=linear&ev=2&v=%d" % (cam, v))
        if status(drv)["cameras"][cam]["version"] == v:
            return a is not None and b is not None and a != b
    return False


def run_checks(args, drv, url, proc, outdir):
    drv.get(url)
    check(wait_for(lambda: spp(drv) > 0 and drv.execute_script(PIXELS_OF_ELEMENT, "main"), 120) is not None,
          "the page shows an image and a spp count")
    s1, p1 = spp(drv), drv.execute_script(PIXELS_OF_ELEMENT, "main")
    drv.save_screenshot(os.path.join(args.out, "1-first-pass.png"))
    got = wait_for(lambda: spp(drv) > s1 and drv.execute_script(PIXELS_OF_ELEMENT, "main") != p1, 120)
    s2 = spp(drv)
    check(got is not None, "spp rises (%d -> %d) and the image changes (%s -> %s)" %
          (s1, s2, digest(p1), digest(drv.execute_script(PIXELS_OF_ELEMENT, "main"))))
    drv.save_screenshot(os.path.join(args.out, "2-later-pass.png"))
    check(tonemap_views_differ(drv), "the server re-tone-maps one image version: Photographic != linear +2 stops")
    before = drv.find_element(By.ID, "main").get_attribute("src")
    Select(drv.find_element(By.ID, "tmo")).select_by_value("linear")
    drv.execute_script("const e = document.getElementById('ev'); e.value = '2'; e.dispatchEvent(new Event('input'));")
    after = wait_for(lambda: "tmo=linear&ev=2" in (drv.find_element(By.ID, "main").get_attribute("src") or "") and
                     drv.find_element(By.ID, "main").get_attribute("src"), 30)
    check(after is not None and after != before, "the page's TMO and exposure controls reload the image (%s)" %
          (after or "").split("/")[-1])
    drv.save_screenshot(os.path.join(args.out, "3-linear-plus2.png"))
    Select(drv.find_element(By.ID, "tmo")).select_by_value("scene")
    drv.execute_script("const e = document.getElementById('ev'); e.value = '0'; e.dispatchEvent(new Event('input'));")
    time.sleep(0.5)
    drv.find_element(By.ID, "stop").click()
    try:
        rc = proc.wait(timeout=120)
    except subprocess.TimeoutExpired:
        proc.kill()
        rc = None
    check(rc == 130, "Stop ends clrt with Ctrl-C's status (exit %s, expected 130)" % rc)
    exr = os.path.join(outdir, "preview_box.exr")
    head = open(exr, "rb").read(4096) if os.path.exists(exr) else b""
    check(b"partial" in head and b"interrupted after" in head, "Stop wrote the partial EXR (%s, header 'partial')" % exr)
    time.sleep(0.6)
    drv.save_screenshot(os.path.join(args.out, "4-stopped.png"))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--clrt", default=os.path.join(ROOT, "build", "clrt"))
    ap.add_argument("--out", default=os.path.join(ROOT, "build", "preview-test"))
    ap.add_argument("--resolution", default="96x72")
    ap.add_argument("--time-limit", type=float, default=30)
    ap.add_argument("--device", default=os.environ.get("CLRT_TEST_DEVICE", "cpu"))
    ap.add_argument("--window", default="1100,760", help="the browser window's size, W,H")
    ap.add_argument("--shot-only", help="only take a screenshot of the page into this file, after --time-limit/2 s")
    args = ap.parse_args()
    t0 = time.time()
    os.makedirs(args.out, exist_ok=True)
    outdir = os.path.join(args.out, "render")
    os.makedirs(outdir, exist_ok=True)
    for f in os.listdir(outdir):
        os.remove(os.path.join(outdir, f))
    log = open(os.path.join(args.out, "clrt-log.txt"), "w")
    proc, url = start_render(args, outdir, log)
    drv = None
    try:
        bad = re.sub(r"/[0-9a-f]{32}/$", "/" + "0" * 32 + "/", url)
        try:
            code = urllib.request.urlopen(bad + "status.json", timeout=10).status
        except urllib.error.HTTPError as e:
            code = e.code
        check(code == 403, "a wrong token gets 403 (got %s)" % code)
        drv = browser(args.window)
        if args.shot_only:
            drv.get(url)
            time.sleep(args.time_limit / 2)
            drv.save_screenshot(args.shot_only)
            proc.send_signal(2)
            proc.wait(timeout=120)
        else:
            run_checks(args, drv, url, proc, outdir)
    finally:
        if drv:
            drv.quit()
        if proc.poll() is None:
            proc.kill()
    print("preview_browser_test: %d failed; %.1f s; screenshots in %s" % (len(failures), time.time() - t0, args.out))
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
