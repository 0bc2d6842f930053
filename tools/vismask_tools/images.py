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


def edge_width(w, h, px):
    """The median 10%-90% width, in pixels along rows, of the edges of the
    brightest region of a flat RGB image (channels summed): each row that
    crosses the region with at least 4 pixels at 90% of the row's range
    (and its neighbours too, so the region's corners are left out) gives
    its left and right rise, each interpolated between pixel centres."""
    lum = [px[3 * k] + px[3 * k + 1] + px[3 * k + 2] for k in range(w * h)]
    top = max(lum)

    def crossing(row, xs, level):
        prev = None
        for x in xs:
            if prev is not None and (row[prev] - level) * (row[x] - level) <= 0 and row[x] != row[prev]:
                return prev + (level - row[prev]) / (row[x] - row[prev]) * (x - prev)
            prev = x
        return None

    def wide(y):
        if y < 0 or y >= h:
            return False
        row = lum[y * w:(y + 1) * w]
        lo, hi = min(row), max(row)
        return hi > 0.5 * top and sum(v >= lo + 0.9 * (hi - lo) for v in row) >= 4

    widths = []
    for y in range(h):
        if not (wide(y - 1) and wide(y) and wide(y + 1)):
            continue
        row = lum[y * w:(y + 1) * w]
        lo, hi = min(row), max(row)
        t10, t90 = lo + 0.1 * (hi - lo), lo + 0.9 * (hi - lo)
        for xs in (range(w), range(w - 1, -1, -1)):
            a, b = crossing(row, xs, t10), crossing(row, xs, t90)
            if a is not None and b is not None:
                widths.append(abs(b - a))
    widths.sort()
    return widths[len(widths) // 2] if widths else float("nan")
