"""The width of a straight shadow edge in an image (issue 41's sun-shadow
goal): the 10%-90% rise of the light across it, in pixels, measured the
same way in vismask's image and in Cycles'.

The edge is a segment on a surface whose ends are known from the geometry
(sunroom.edges), projected into the image by the camera (`project`, as
`vismask render --camera` frames it). Every pixel centre in a band along
the segment's middle (its ends, near the patch's corners, left out) is a
sample of the edge's profile at its signed distance from the line, lit
side positive: many parallel profiles, each crossing the line at another
sub-pixel offset, merged into one finely binned profile (the slanted-edge
method). The profile is normalised between its two plateaus (the medians
of its outer thirds on each side) and the width is where it first reaches
90% less where it last fell to 10% before that, both interpolated between
bins. A pixel is a 1-pixel box over the scene in both renderers, so even a
step edge measures about 0.8 px: the measure's floor."""

import math

from .files import read_pfm

BIN = 0.25          # profile bins, pixels
KEEP = (0.2, 0.8)   # the part of the segment sampled (its ends are corners)


def _sub(a, b):
    return [a[i] - b[i] for i in range(3)]


def _dot(a, b):
    return sum(a[i] * b[i] for i in range(3))


def _cross(a, b):
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]


def _unit(a):
    n = math.sqrt(_dot(a, a))
    return [x / n for x in a]


def project(camera, w, h, p):
    """Image position (x right, y down, pixel centres at k + 0.5) of the 3D
    point p seen by `camera` (vismask's ten comma-separated numbers: eye,
    target, up, vertical fov in degrees) on a w x h image."""
    c = [float(v) for v in camera.split(",")]
    eye, target, up, fovy = c[0:3], c[3:6], c[6:9], c[9]
    f = _unit(_sub(target, eye))
    r = _unit(_cross(f, up))
    u = _cross(r, f)
    d = _sub(p, eye)
    z = _dot(d, f)
    t = math.tan(math.radians(fovy) / 2)
    sx = _dot(d, r) / z / (t * w / h)
    sy = _dot(d, u) / z / t
    return (0.5 * (sx + 1) * w, 0.5 * (1 - sy) * h)


def profile(lum, w, h, a, b, lit, reach):
    """The merged profile across the line a-b (image points) within `reach`
    pixels of it: {bin: mean}, bin k holding distances [k, k + 1) x BIN, the
    distance positive on the side of the image point `lit`."""
    ex, ey = b[0] - a[0], b[1] - a[1]
    length = math.hypot(ex, ey)
    ex, ey = ex / length, ey / length
    nx, ny = -ey, ex
    if (lit[0] - a[0]) * nx + (lit[1] - a[1]) * ny < 0:
        nx, ny = -nx, -ny
    sums, counts = {}, {}
    lo_x = int(max(0, min(a[0], b[0]) - reach - 1))
    hi_x = int(min(w, max(a[0], b[0]) + reach + 2))
    lo_y = int(max(0, min(a[1], b[1]) - reach - 1))
    hi_y = int(min(h, max(a[1], b[1]) + reach + 2))
    for y in range(lo_y, hi_y):
        for x in range(lo_x, hi_x):
            px, py = x + 0.5 - a[0], y + 0.5 - a[1]
            s = (px * ex + py * ey) / length
            d = px * nx + py * ny
            if KEEP[0] <= s <= KEEP[1] and abs(d) <= reach:
                k = math.floor(d / BIN)
                sums[k] = sums.get(k, 0.0) + lum[y * w + x]
                counts[k] = counts.get(k, 0) + 1
    return {k: sums[k] / counts[k] for k in sums}


def width(prof, reach):
    """The 10%-90% width (pixels) of a merged profile, or nan when it has no
    rise (plateaus equal, or a crossing missing)."""
    ks = sorted(prof)
    if len(ks) < 4:
        return float("nan")
    dist = [(k + 0.5) * BIN for k in ks]
    vals = [prof[k] for k in ks]

    def median(xs):
        xs = sorted(xs)
        return xs[len(xs) // 2] if xs else float("nan")
    dark = median([v for d, v in zip(dist, vals) if d <= -2 * reach / 3])
    lit = median([v for d, v in zip(dist, vals) if d >= 2 * reach / 3])
    if not lit > dark:
        return float("nan")
    p = [(v - dark) / (lit - dark) for v in vals]
    i90 = next((i for i in range(1, len(p)) if p[i] >= 0.9 and p[i - 1] < 0.9), None)
    if i90 is None:
        return float("nan")
    i10 = next((i for i in range(i90, 0, -1) if p[i - 1] <= 0.1 < p[i]), None)
    if i10 is None:
        return float("nan")

    def at(i, level):
        return dist[i - 1] + (level - p[i - 1]) / (p[i] - p[i - 1]) * (dist[i] - dist[i - 1])
    return at(i90, 0.9) - at(i10, 0.1)


def offset(prof):
    """Where the merged profile crosses half-way between its outermost
    values on each side, pixels from the geometric line (lit side
    positive): near 0 when the renderer put the edge where the geometry, the
    camera and the sun's direction say; nan without a crossing."""
    ks = sorted(prof)
    if len(ks) < 2:
        return float("nan")
    mid = 0.5 * (prof[ks[0]] + prof[ks[-1]])
    for k0, k1 in zip(ks, ks[1:]):
        a, b = prof[k0], prof[k1]
        if a < mid <= b:
            return ((k0 + 0.5) + (mid - a) / (b - a) * (k1 - k0)) * BIN
    return float("nan")


def floor_edges(opening, toward, names):
    """The edges of the sunlit patch an opening (its corners in order, 3D)
    casts on the floor y = 0 along the sun's central direction (`toward`
    points at the sun): [(name, A, B)], edge k from corner k to k + 1."""
    tx, ty, tz = toward
    hit = [(x - tx * y / ty, 0.0, z - tz * y / ty) for x, y, z in opening]
    return [(names[k], hit[k], hit[(k + 1) % len(hit)]) for k in range(len(hit))]


def patch_centre(edges):
    """The mean of the edges' first ends (a convex patch's inside point)."""
    return tuple(sum(e[1][i] for e in edges) / len(edges) for i in range(3))


def luminance(px):
    return [px[3 * k] + px[3 * k + 1] + px[3 * k + 2] for k in range(len(px) // 3)]


def edge_widths(pfm, camera, edges, centre, reach):
    """{name: (10%-90% width, offset), in pixels} of each edge (name, A, B,
    ...) of a patch whose centre (3D) is `centre`, in the image PFM seen by
    `camera`."""
    w, h, px = read_pfm(pfm)
    lum = luminance(px)
    lit = project(camera, w, h, centre)
    out = {}
    for e in edges:
        a, b = project(camera, w, h, e[1]), project(camera, w, h, e[2])
        prof = profile(lum, w, h, a, b, lit, reach)
        out[e[0]] = (width(prof, reach), offset(prof))
    return out


def reach_for(w):
    """How far from the line the profile reaches, pixels: past the widest
    penumbra expected (a few pixels) onto both plateaus, yet inside the
    patch; more at a larger image."""
    return max(4.0, w / 32)


# --- selftest: synthetic edges of known width ---------------------------------

def _ramp_image(w, h, a, b, ramp, lit_level, dark_level):
    """A w x h luminance image of a straight edge through a-b (image points):
    the exact 1-pixel box average (16 x 16 sub-samples) of a linear ramp of
    width `ramp` pixels across it (0: a step) from dark_level to lit_level,
    lit on the left of a->b."""
    ex, ey = b[0] - a[0], b[1] - a[1]
    n = math.hypot(ex, ey)
    nx, ny = -ey / n, ex / n
    img = []
    for y in range(h):
        for x in range(w):
            acc = 0.0
            for j in range(16):
                for i in range(16):
                    d = (x + (i + 0.5) / 16 - a[0]) * nx + (y + (j + 0.5) / 16 - a[1]) * ny
                    t = 1.0 if d >= ramp / 2 else 0.0 if d <= -ramp / 2 else d / ramp + 0.5
                    acc += dark_level + t * (lit_level - dark_level)
            img.append(acc / 256)
    return img, (a[0] + 0.5 * ex + 6 * nx, a[1] + 0.5 * ey + 6 * ny)


def selftest():
    """Synthetic edges: a ramp of width R has a 10%-90% width of 0.8 R
    (widened a little by the pixel's box); a step about 0.8 px; a slanted
    and a steep edge; a segment given the other way round; returns the
    failures."""
    w, h = 48, 40
    cases = [((8.0, 30.0), (40.0, 14.0), 5.0, 4.0, 0.25),   # slanted ramp: 0.8 x 5
             ((30.0, 5.0), (22.0, 36.0), 8.0, 6.4, 0.25),   # steep ramp, lit left of a->b
             ((12.0, 34.0), (38.0, 6.0), 0.0, 0.8, 0.3),    # a step: the box filter alone
             ((40.0, 14.0), (8.0, 30.0), 3.0, 2.4, 0.25)]   # the other way round
    failed = 0
    for a, b, ramp, want, tol in cases:
        img, lit = _ramp_image(w, h, a, b, ramp, 5.0, 0.5)
        got = width(profile(img, w, h, a, b, lit, 8.0), 8.0)
        off = offset(profile(img, w, h, a, b, lit, 8.0))
        ok = abs(got - want) <= tol and abs(off) <= 0.1
        failed += not ok
        print("sun-edge selftest: ramp %.1f px from %s to %s: %.3f px (want %.2f +- %.2f), "
              "centred %.3f px off the line %s"
              % (ramp, a, b, got, want, tol, off, "ok" if ok else "FAILED"))
    # A flat image has no edge: nan, not a number that looks like one.
    flat = width(profile([1.0] * (w * h), w, h, (8.0, 30.0), (40.0, 14.0), (24.0, 10.0), 8.0), 8.0)
    failed += not math.isnan(flat)
    print("sun-edge selftest: a flat image gives %r %s" % (flat, "ok" if math.isnan(flat) else "FAILED"))
    return failed
