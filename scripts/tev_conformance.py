#!/usr/bin/env python3
"""tev_conformance.py — `clrt render --display-server` against tev's own Python client (tevclient, PyPI,
by tev's author): a listener takes everything clrt sends while it renders scenes/preview_box.xml
progressively, splits it into tev's packets, and re-encodes each one with tevclient.packet
(create_image / update_image, from the fields it decoded): every packet must equal, byte for byte, what
tevclient would send for the same image, name, channels and tile. Then the tiles of the last update,
put together, must equal the EXR clrt wrote (float32, bit for bit), and cover it exactly.
A real tev is not packaged in Debian and this machine has no display; tevclient is the protocol's
reference encoder, so this checks the bytes a real tev would read.
Needs tevclient, numpy and OpenEXR in the interpreter's environment: build/check-venv (scripts/check_course
makes it, with numpy and OpenEXR) plus tevclient:
  build/check-venv/bin/pip install tevclient
Usage: build/check-venv/bin/python scripts/tev_conformance.py [--clrt build/clrt]
Exit 0 and "tev_conformance: ok ..." when every packet matches."""
import argparse
import os
import socket
import struct
import subprocess
import sys
import tempfile
import threading

import numpy as np
import OpenEXR
from tevclient import packet as tevpacket

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def cstr(buf, at):
    end = buf.index(b"\0", at)
    return buf[at:end].decode("utf-8"), end + 1


def decode(pkt):
    """The fields of one packet, as tev's server reads them (types 4 CreateImage, 6 UpdateImage)."""
    kind, grab = pkt[4], bool(pkt[5])
    name, at = cstr(pkt, 6)
    if kind == 4:
        w, h, n = struct.unpack_from("<iii", pkt, at)
        at += 12
        chans = []
        for _ in range(n):
            c, at = cstr(pkt, at)
            chans.append(c)
        return {"kind": kind, "grab": grab, "name": name, "w": w, "h": h, "chans": chans, "end": at}
    if kind == 6:
        (n,) = struct.unpack_from("<i", pkt, at)
        at += 4
        chans = []
        for _ in range(n):
            c, at = cstr(pkt, at)
            chans.append(c)
        x, y, w, h = struct.unpack_from("<iiii", pkt, at)
        at += 16
        offsets = struct.unpack_from("<%dq" % n, pkt, at)
        at += 8 * n
        strides = struct.unpack_from("<%dq" % n, pkt, at)
        at += 8 * n
        data = np.frombuffer(bytes(pkt[at:]), dtype="<f4")
        if data.size != w * h * n or list(offsets) != list(range(n)) or list(strides) != [n] * n:
            raise SystemExit("tev_conformance: FAIL: update of %s: %d floats for %dx%dx%d, offsets %s, strides %s"
                             % (name, data.size, w, h, n, offsets, strides))
        return {"kind": kind, "grab": grab, "name": name, "chans": chans, "x": x, "y": y,
                "tile": data.reshape(h, w, n)}
    raise SystemExit("tev_conformance: FAIL: packet type %d (clrt sends 4 and 6 only)" % kind)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--clrt", default=os.path.join(ROOT, "build", "clrt"))
    args = ap.parse_args()
    srv = socket.socket()
    srv.bind(("127.0.0.1", 0))
    srv.listen(1)
    port = srv.getsockname()[1]
    received = bytearray()

    def listen():
        conn, _ = srv.accept()
        while True:
            b = conn.recv(1 << 20)
            if not b:
                break
            received.extend(b)

    t = threading.Thread(target=listen)
    t.start()
    with tempfile.TemporaryDirectory() as out:
        cmd = [args.clrt, "render", os.path.join(ROOT, "scenes", "preview_box.xml"), "--camera", "1", "-o", out,
               "--resolution", "150x100", "--spp", "16", "--target-error", "1e-12", "--seed", "1",
               "--display-server", "127.0.0.1:%d" % port]
        r = subprocess.run(cmd, capture_output=True, text=True)
        if r.returncode != 0:
            raise SystemExit("tev_conformance: FAIL: clrt exited %d:\n%s" % (r.returncode, r.stderr))
        t.join(timeout=30)
        exrs = [f for f in os.listdir(out) if f.endswith(".exr")]
        if len(exrs) != 1:
            raise SystemExit("tev_conformance: FAIL: expected one EXR in the output, found %s" % exrs)
        with OpenEXR.File(os.path.join(out, exrs[0])) as f:
            ch = f.channels()
            exr = (np.asarray(ch["RGB"].pixels) if "RGB" in ch else
                   np.stack([np.asarray(ch[c].pixels) for c in "RGB"], axis=-1)).astype(np.float32)
    packets, at = [], 0
    while at < len(received):
        (n,) = struct.unpack_from("<I", received, at)
        if n < 6 or at + n > len(received):
            raise SystemExit("tev_conformance: FAIL: a packet of %d bytes at offset %d of %d" % (n, at, len(received)))
        packets.append(bytes(received[at:at + n]))
        at += n
    creates = updates = 0
    last = {}  # (x, y) -> tile of the latest update
    for i, pkt in enumerate(packets):
        d = decode(pkt)
        if d["kind"] == 4:
            ref = tevpacket.create_image(d["name"], d["w"], d["h"], d["chans"], d["grab"])
            creates += 1
            size = (d["h"], d["w"])
        else:
            ref = tevpacket.update_image(d["name"], d["tile"], d["chans"], d["x"], d["y"], d["grab"])
            updates += 1
            last[(d["x"], d["y"])] = d["tile"]
        if bytes(ref) != pkt:
            diff = next(k for k in range(min(len(ref), len(pkt))) if ref[k] != pkt[k]) if len(ref) == len(pkt) else -1
            raise SystemExit("tev_conformance: FAIL: packet %d (type %d, %d bytes) differs from tevclient's (%d bytes; "
                             "first differing byte %d)" % (i, pkt[4], len(pkt), len(ref), diff))
    if creates != 1 or updates == 0:
        raise SystemExit("tev_conformance: FAIL: %d CreateImage and %d UpdateImage packets" % (creates, updates))
    img = np.full(size + (3,), np.nan, dtype=np.float32)
    for (x, y), tile in last.items():
        img[y:y + tile.shape[0], x:x + tile.shape[1], :] = tile[..., :3]
    if exr.shape != img.shape or np.isnan(img).any() or not np.array_equal(img, exr):
        raise SystemExit("tev_conformance: FAIL: the last update's tiles do not give the EXR clrt wrote "
                         "(shape %s against %s)" % (img.shape, exr.shape))
    print("tev_conformance: ok: %d packets (%d CreateImage, %d UpdateImage, %d bytes) equal tevclient %s's "
          "encoding byte for byte; the last update's %d tiles are the %dx%d EXR bit for bit"
          % (len(packets), creates, updates, len(received), tevclient_version(), len(last), size[1], size[0]))


def tevclient_version():
    try:
        from importlib.metadata import version
        return version("tevclient")
    except Exception:
        return "?"


if __name__ == "__main__":
    main()
