#!/usr/bin/env python3
"""exr_stats.py — numbers for comparing path-traced renders (issue 16), linear EXRs only.
  exr_stats.py mean A.exr [x0 y0 x1 y1]           per-channel mean (of a region)
  exr_stats.py relmse A.exr B.exr [--down 8]      relMSE of A against B after k x k box downsampling:
                                                   mean((A-B)^2 / (B^2 + 1e-2)) over pixels and channels
  exr_stats.py bias A1.exr A2.exr REF.exr [--down 8] [--down-ref K (REF's block size, default --down)]
      relMSE(A1, REF), relMSE(A1, A2) / 2 ... prints ratio = relMSE(A1,REF) / relMSE(A1,A2):
      for an unbiased A, relMSE(A1,REF) ~ var(A)+var(REF) and relMSE(A1,A2) ~ 2 var(A)."""
import sys
import numpy as np
import OpenEXR


def load(path):
    with OpenEXR.File(path) as f:
        ch = f.channels()
        if "RGB" in ch:
            a = np.asarray(ch["RGB"].pixels, dtype=np.float64)
        else:
            a = np.stack([np.asarray(ch[c].pixels, dtype=np.float64) for c in "RGB"], axis=-1)
    return np.nan_to_num(a, nan=0.0, posinf=0.0, neginf=0.0)


def down(a, k):
    if k <= 1:
        return a
    h, w = a.shape[0] // k * k, a.shape[1] // k * k
    a = a[:h, :w]
    return a.reshape(h // k, k, w // k, k, 3).mean(axis=(1, 3))


def relmse(a, b):
    return float(np.mean((a - b) ** 2 / (b ** 2 + 1e-2)))


def main(argv):
    k, kref = 8, None
    if "--down-ref" in argv:
        i = argv.index("--down-ref")
        kref = int(argv[i + 1])
        argv = argv[:i] + argv[i + 2:]
    if "--down" in argv:
        i = argv.index("--down")
        k = int(argv[i + 1])
        argv = argv[:i] + argv[i + 2:]
    cmd = argv[1]
    if cmd == "mean":
        a = load(argv[2])
        if len(argv) > 3:
            x0, y0, x1, y1 = map(int, argv[3:7])
            a = a[y0:y1, x0:x1]
        m = a.reshape(-1, 3).mean(axis=0)
        print("mean %.5f %.5f %.5f" % tuple(m))
    elif cmd == "relmse":
        print("relmse %.6g" % relmse(down(load(argv[2]), k), down(load(argv[3]), k)))
    elif cmd == "bias":
        a1, a2 = (down(load(p), k) for p in argv[2:4])
        ref = down(load(argv[4]), kref or k)
        r_ref, r_self = relmse(a1, ref), relmse(a1, a2)
        print("relmse_to_ref %.6g relmse_between_two %.6g ratio %.3f" % (r_ref, r_self, r_ref / r_self))
    else:
        sys.exit("unknown command " + cmd)


if __name__ == "__main__":
    main(sys.argv)
