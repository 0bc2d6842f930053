"""The Cornell box's geometry as the experiments need it: its polygons,
Moller-Trumbore hits, and the tall block's shadow region."""

import math
import os

from . import ROOT
from .files import read_csv

SCENE = os.path.join(ROOT, "scenes", "cornell.obj")

#
# The tall block's shadow region: the points of the floor and the back wall
# from which at least one of 5 x 5 points spread over the light is hidden by
# the tall block (umbra and penumbra). In the image: the pixels whose visible
# surface is such a point. The right environment's part: those with x < 278
# (the image's right half looks at x < 278: the camera looks along +z).

def load_polygons(path=SCENE):
    verts, polys, name = [], [], None
    with open(path) as f:
        for line in f:
            p = line.split()
            if not p:
                continue
            if p[0] == "o":
                name = p[1]
            elif p[0] == "v":
                verts.append(tuple(float(x) for x in p[1:4]))
            elif p[0] == "f":
                polys.append((name, [verts[int(t.split("/")[0]) - 1] for t in p[1:]]))
    return polys


def sub(a, b):
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def tri_hit(o, d, a, b, c):
    """Moller-Trumbore: t of the hit, or None."""
    e1, e2 = sub(b, a), sub(c, a)
    p = cross(d, e2)
    det = dot(e1, p)
    if abs(det) < 1e-12:
        return None
    inv = 1.0 / det
    s = sub(o, a)
    u = dot(s, p) * inv
    if u < 0 or u > 1:
        return None
    q = cross(s, e1)
    v = dot(d, q) * inv
    if v < 0 or u + v > 1:
        return None
    t = dot(e2, q) * inv
    return t if t > 1e-6 else None


def first_hit(o, d, tris):
    best, what = float("inf"), None
    for name, (a, b, c) in tris:
        t = tri_hit(o, d, a, b, c)
        if t is not None and t < best:
            best, what = t, name
    return best, what


def triangles(polys):
    out = []
    for name, v in polys:
        for k in range(1, len(v) - 1):
            out.append((name, (v[0], v[k], v[k + 1])))
    return out


class ShadowRegion:
    def __init__(self):
        polys = load_polygons()
        self.tris = triangles(polys)
        self.block = [t for t in self.tris if t[0].startswith("tall_block")]
        light = [v for n, v in polys if n == "light"][0]
        lo = [min(p[a] for p in light) for a in range(3)]
        hi = [max(p[a] for p in light) for a in range(3)]
        y = light[0][1]
        self.light = [(lo[0] + (i + 0.5) * (hi[0] - lo[0]) / 5, y - 1e-3,
                       lo[2] + (j + 0.5) * (hi[2] - lo[2]) / 5) for i in range(5) for j in range(5)]

    def shadowed(self, p):
        """At least one light point hidden by the tall block."""
        for q in self.light:
            d = sub(q, p)
            for _, (a, b, c) in self.block:
                t = tri_hit(p, d, a, b, c)
                if t is not None and t < 1.0:
                    return True
        return False

    def in_region(self, p, n):
        """A point of the floor (n = +y) or the back wall (n = -z) in the shadow."""
        floor = n[1] > 0.9 and abs(p[1]) < 1.0
        back = n[2] < -0.9 and abs(p[2] - 559.2) < 1.0
        return (floor or back) and self.shadowed(p)

    def pixel_mask(self, camera, w, h, cache=None):
        """Per pixel: 0 outside the region, 1 in it at x >= 278 (the first
        environment), 2 in it at x < 278 (the second)."""
        if cache and os.path.exists(cache):
            with open(cache) as f:
                return [int(c) for c in f.read().strip()]
        eye, target, up, fovy = camera[0:3], camera[3:6], camera[6:9], camera[9]
        f = sub(target, eye)
        f = scale(f, 1 / math.sqrt(dot(f, f)))
        r = cross(f, up)
        r = scale(r, 1 / math.sqrt(dot(r, r)))
        u = cross(r, f)
        focal = 0.5 * h / math.tan(0.5 * math.radians(fovy))
        mask = []
        for y in range(h):
            for x in range(w):
                px, py = x + 0.5 - 0.5 * w, 0.5 * h - (y + 0.5)
                d = tuple(f[k] * focal + r[k] * px + u[k] * py for k in range(3))
                t, what = first_hit(eye, d, self.tris)
                if what not in ("floor", "back_wall"):
                    mask.append(0)
                    continue
                p = tuple(eye[k] + t * d[k] for k in range(3))
                n = (0, 1, 0) if what == "floor" else (0, 0, -1)
                mask.append((2 if p[0] < 278 else 1) if self.in_region(p, n) else 0)
        if cache:
            with open(cache, "w") as f_:
                f_.write("".join(str(m) for m in mask))
        return mask


def scale(v, s):
    return (v[0] * s, v[1] * s, v[2] * s)


def region_patch_mean(patches_csv, region, right_only):
    """Area-weighted mean radiosity (channels summed) of the patches whose
    centre is in the region (and at x < 278 with right_only), and their area."""
    header, rows = read_csv(patches_csv)
    ix = {k: i for i, k in enumerate(header)}
    power = area = 0.0
    for r in rows:
        c = tuple(float(r[ix[k]]) for k in ("cx", "cy", "cz"))
        n = tuple(float(r[ix[k]]) for k in ("nx", "ny", "nz"))
        if right_only and c[0] >= 278:
            continue
        if not region.in_region(c, n):
            continue
        a = float(r[ix["area"]])
        power += a * sum(float(r[ix[k]]) for k in ("b_r", "b_g", "b_b"))
        area += a
    return (power / area if area > 0 else float("nan")), area
