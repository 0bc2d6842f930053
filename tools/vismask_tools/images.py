"""Image error and difference images, over the flat pixel lists of files.py."""

import math

from .files import read_pfm, write_pfm, write_png


def diff_png(path, w, h, a, b, gain, region=None):
    """|a - b| (channels summed) as a heat image, scaled so that `gain` times
    the reference's mean value is white; the region's outline in blue."""
    mean = sum(b) / len(b)
    out = []
    for i in range(w * h):
        d = sum(abs(a[3 * i + c] - b[3 * i + c]) for c in range(3)) / 3
        v = max(0.0, min(1.0, d / (mean / gain)))
        px = [int(255 * min(1, 3 * v)), int(255 * min(1, max(0, 3 * v - 1))),
              int(255 * min(1, max(0, 3 * v - 2)))]
        if region is not None and region[i] and not all(
                region[j] for j in neighbours(i, w, h)):
            px = [60, 120, 255]
        out += px
    write_png(path, w, h, out)


def dilated_mask(hit, w, h, d):
    """255 within d pixels (a (2d+1)^2 square) of every true entry of `hit`
    (w x h, rows in order), else 0: the bytes of a PGM's pixels."""
    mask = bytearray(w * h)
    for i in [i for i in range(w * h) if hit[i]]:
        y, x = divmod(i, w)
        for yy in range(max(0, y - d), min(h, y + d + 1)):
            for xx in range(max(0, x - d), min(w, x + d + 1)):
                mask[yy * w + xx] = 255
    return mask


def neighbours(i, w, h):
    x, y = i % w, i // w
    for dx, dy in ((1, 0), (-1, 0), (0, 1), (0, -1)):
        if 0 <= x + dx < w and 0 <= y + dy < h:
            yield (y + dy) * w + x + dx


def rel_rmse(a, b, mask=None):
    """sqrt(sum (a-b)^2 / sum b^2) over every channel of the pixels in mask
    (all pixels without one): the same figure as `vismask compare`."""
    num = den = 0.0
    for i in range(len(b) // 3):
        if mask is not None and not mask[i]:
            continue
        for c in range(3):
            d = a[3 * i + c] - b[3 * i + c]
            num += d * d
            den += b[3 * i + c] ** 2
    return math.sqrt(num / den) if den > 0 else float("nan")


def average_pfm(paths, out):
    imgs = [read_pfm(p) for p in paths]
    w, h = imgs[0][0], imgs[0][1]
    n = len(imgs)
    px = [sum(img[2][i] for img in imgs) / n for i in range(w * h * 3)]
    write_pfm(out, w, h, px)

