#!/usr/bin/python3
"""tools/vismask_tools/scale.py IMAGE.pfm REF.pfm [MASK.pgm]: how IMAGE relates
to REF over the pixels outside MASK (nonzero = left out): the relative RMSE
(as vismask compare --exclude), the least-squares scale s = sum(a*b)/sum(b*b)
overall and per channel, the ratio of the means, and the relative RMSE left
after scaling by s. A scale off 1 by more than the reference's noise points
at a convention mismatch (Ke/pi, one-sidedness, bounces), not at noise.
Needs numpy (tools/install-deps --reference)."""
import sys

import numpy as np


def ReadPfm(path):
    data = open(path, "rb").read()
    parts = data.split(b"\n", 3)
    w, h = map(int, parts[1].split())
    dtype = "<f4" if float(parts[2]) < 0 else ">f4"
    img = np.frombuffer(parts[3][:12 * w * h], dtype=dtype).reshape(h, w, 3)
    return img[::-1].astype(np.float64)  # row 0 at the top


def ReadPgm(path):
    data = open(path, "rb").read()
    parts = data.split(b"\n", 3)
    w, h = map(int, parts[1].split())
    return np.frombuffer(parts[3][:w * h], dtype=np.uint8).reshape(h, w)


def main():
    if len(sys.argv) not in (3, 4):
        print(__doc__, file=sys.stderr)
        sys.exit(2)
    a, b = ReadPfm(sys.argv[1]), ReadPfm(sys.argv[2])
    keep = np.ones(a.shape[:2], bool) if len(sys.argv) == 3 else ReadPgm(sys.argv[3]) == 0
    A, B = a[keep], b[keep]
    rmse = np.sqrt(((A - B) ** 2).sum() / (B ** 2).sum())
    s = (A * B).sum() / (B * B).sum()
    sc = (A * B).sum(0) / (B * B).sum(0)
    after = np.sqrt(((A - s * B) ** 2).sum() / ((s * B) ** 2).sum())
    print("pixels %d of %d" % (keep.sum(), keep.size))
    print("relative_rmse %.6f" % rmse)
    print("scale %.6f" % s)
    print("scale_rgb %.6f %.6f %.6f" % tuple(sc))
    print("mean_ratio_rgb %.6f %.6f %.6f" % tuple(A.mean(0) / B.mean(0)))
    print("relative_rmse_after_scale %.6f" % after)


if __name__ == "__main__":
    main()
