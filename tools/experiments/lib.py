"""Shared by the experiment scripts (tools/experiments/*): the settings of a
scale, running vismask with a run cache, PFM and PNG files, the shadow
region, and small statistics. Python 3 standard library only."""

import json
import math
import os
import shutil
import statistics
import struct
import subprocess
import sys
import zlib

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
SCENE = os.path.join(ROOT, "scenes", "cornell.obj")

# The paper's Table 1 (minutes on its uniprocessor), for the ratio column.
SEED_MINUTES = {("A", 20): 196 + 38 / 60, ("A", 50): 205 + 11 / 60, ("A", 100): 209 + 24 / 60,
                ("B", 20): 171 + 10 / 60, ("B", 50): 179 + 30 / 60, ("B", 100): 202 + 37 / 60}

SPLIT = ["--envs", "2"]  # the Cornell box's box is 0..556 in x: split at x = 278
# Looking down from just under the light: from the paper's front view, the
# part of the tall block's shadow that lies in the second environment
# (x < 278, behind the block) is hidden by the blocks. Image right is -x, as
# in the front view, so the second environment is the right half.
CAMERA = ["--camera", "278,545,300,278,0,300,0,0,1,76"]

# Two scales: "full" is what docs/RESULTS.md shows (make experiments, under
# 15 minutes on 2 cores); "mini" is the same pipeline in seconds, for the
# test that keeps it from rotting.
SCALES = {
    "full": dict(common=CAMERA + ["--patch-size", "70", "--rays", "4096", "--stop-unshot", "1e-2",
                         "--width", "256", "--height", "256"],
                 ref_b=["--rays", "8192", "--stop-unshot", "1e-3"],
                 ref_seeds=[1001, 1002],
                 ref_res=250, table_res=[20, 50, 100], curve_res=[20, 50, 100, 250],
                 leak_res=250, reps=3, error_every=100,
                 # The ground truth (groundtruth.py): a Cycles reference of
                 # size^2 at spp (two halves) for the original camera, and of
                 # the experiments' camera at exp_spp. --emitted-rays settings
                 # chosen so that runs converge in about 0.3, 1, 3, 10 and 30 s
                 # of solve on this machine, and a 0.1 s cap (a converged run
                 # needs ~30 000 shots of at least --min-rays: >= 0.3 s).
                 gt=dict(size=512, spp=1024, exp_spp=1024,
                         settings=[("cap-0.1s", ["--emitted-rays", "100000", "--max-seconds", "0.1"]),
                                   ("emitted-1e5", ["--emitted-rays", "100000"]),
                                   ("emitted-7e5", ["--emitted-rays", "700000"]),
                                   ("emitted-1.1e6-stop-3e-3",
                                    ["--emitted-rays", "1100000", "--stop-unshot", "3e-3"]),
                                   ("emitted-1.3e6-stop-3e-3",
                                    ["--emitted-rays", "1300000", "--stop-unshot", "3e-3"]),
                                   ("emitted-3e6", ["--emitted-rays", "3000000"]),
                                   ("emitted-1.2e7", ["--emitted-rays", "12000000"]),
                                   ("emitted-4e7", ["--emitted-rays", "40000000"]),
                                   # Finer patches than the default extent/28 (20 units here).
                                   ("patch-15-emitted-1.2e7",
                                    ["--patch-size", "15", "--emitted-rays", "12000000"]),
                                   ("patch-15-emitted-4e7",
                                    ["--patch-size", "15", "--emitted-rays", "40000000"])],
                         points=40, budgets=[1, 10, 30], env_seconds=10, env_res=100,
                         band=[0.3, 0.7], diff_scale=0.2, seam_scale=0.1,
                         common=[], default=[], today_rays=4096)),
    "mini": dict(common=CAMERA + ["--patch-size", "140", "--rays", "256", "--stop-unshot", "5e-2",
                         "--width", "48", "--height", "48"],
                 ref_b=["--rays", "1024", "--stop-unshot", "1e-2"],
                 ref_seeds=[1001, 1002],
                 ref_res=16, table_res=[4, 8], curve_res=[4, 8, 16],
                 leak_res=16, reps=3, error_every=10,
                 gt=dict(size=48, spp=8, exp_spp=8,
                         settings=[("cap-0.02s", ["--emitted-rays", "20000", "--max-seconds", "0.02"]),
                                   ("emitted-2e4", ["--emitted-rays", "20000"])],
                         points=10, budgets=[0.05, 0.2, 0.5], env_seconds=0.2, env_res=8,
                         band=[0.3, 0.7], diff_scale=0.2, seam_scale=0.1,
                         common=["--patch-size", "140", "--stop-unshot", "5e-2"],
                         default=["--emitted-rays", "50000"], today_rays=256)),
}


class Context:
    """Where a scale's runs and results go, and how vismask is started."""

    def __init__(self, scale, out, runs):
        self.scale = scale
        self.s = SCALES[scale]
        self.out = out  # results: CSV tables, images, plots
        self.runs = runs  # one directory per run (outputs of vismask)
        self.bin = os.environ.get("VISMASK_BIN", os.path.join(ROOT, "build", "vismask"))
        os.makedirs(self.out, exist_ok=True)
        os.makedirs(self.runs, exist_ok=True)

    def run(self, name, args, fresh=False, common=None):
        """Runs `vismask render SCENE common args --out runs/name` unless the
        same command already ran there (its args.txt matches); returns run.json.
        `fresh` always reruns (timed repetitions); `common` replaces the
        scale's common arguments (the ground-truth runs)."""
        d = os.path.join(self.runs, name)
        cmd = [self.bin, "render", SCENE] + (self.s["common"] if common is None else common) + list(
            args) + ["--out", d, "--quiet"]
        key = " ".join(os.path.relpath(c, ROOT) if c.startswith(ROOT) else c for c in cmd[1:])
        stamp = os.path.join(d, "args.txt")
        if not fresh and os.path.exists(stamp) and open(stamp).read() == key:
            return load_json(os.path.join(d, "run.json"))
        log(f"  vismask {key}")
        subprocess.run(cmd, check=True)
        with open(stamp, "w") as f:
            f.write(key)
        return load_json(os.path.join(d, "run.json"))

    def path(self, name, f):
        return os.path.join(self.runs, name, f)

    def result(self, f):
        return os.path.join(self.out, f)


def context_from_argv(argv, doc):
    """Parses the scripts' shared arguments: [--mini] [--out DIR]."""
    scale, out = "full", None
    i = 1
    while i < len(argv):
        a = argv[i]
        if a == "--mini":
            scale = "mini"
        elif a == "--out" and i + 1 < len(argv):
            out = argv[i + 1]
            i += 1
        elif a in ("-h", "--help"):
            print(doc.strip())
            sys.exit(0)
        else:
            sys.exit(f"{argv[0]}: unknown argument '{a}' (try --help)")
        i += 1
    out = os.path.abspath(out or os.path.join(ROOT, "docs", "results"))
    runs = os.path.join(ROOT, "build", "experiments", scale) if out.startswith(
        os.path.join(ROOT, "docs")) else os.path.join(out, "runs")
    return Context(scale, out, runs)


def arg(args, flag):
    """The value after the last `flag` in an argument list."""
    return [args[i + 1] for i, a in enumerate(args[:-1]) if a == flag][-1]


def log(msg):
    print(msg, file=sys.stderr, flush=True)


def load_json(path):
    with open(path) as f:
        return json.load(f)


def read_csv(path):
    with open(path) as f:
        rows = [line.rstrip("\n").split(",") for line in f if line.strip()]
    return rows[0], rows[1:]


def write_csv(path, header, rows):
    with open(path, "w") as f:
        f.write(",".join(header) + "\n")
        for r in rows:
            f.write(",".join(fmt(v) for v in r) + "\n")


def fmt(v):
    if isinstance(v, float):
        return f"{v:.6g}"
    return str(v)


# --- images -----------------------------------------------------------------

def read_pfm(path):
    """A colour PFM as (width, height, floats), row 0 at the top."""
    with open(path, "rb") as f:
        data = f.read()
    parts = data.split(b"\n", 3)
    assert parts[0] == b"PF", path
    w, h = (int(x) for x in parts[1].split())
    scale = float(parts[2])
    fmt_ = "<" if scale < 0 else ">"
    px = struct.unpack(f"{fmt_}{w * h * 3}f", parts[3][: w * h * 12])
    rows = [px[(h - 1 - y) * w * 3:(h - y) * w * 3] for y in range(h)]
    return w, h, [v for r in rows for v in r]


def write_pfm(path, w, h, px):
    with open(path, "wb") as f:
        f.write(f"PF\n{w} {h}\n-1.0\n".encode())
        for y in range(h - 1, -1, -1):
            f.write(struct.pack(f"<{w * 3}f", *px[y * w * 3:(y + 1) * w * 3]))


def write_png(path, w, h, rgb):
    """8-bit RGB PNG from a flat list of w*h*3 ints (row 0 at the top)."""
    raw = b"".join(b"\0" + bytes(rgb[y * w * 3:(y + 1) * w * 3]) for y in range(h))

    def chunk(tag, body):
        return struct.pack(">I", len(body)) + tag + body + struct.pack(
            ">I", zlib.crc32(tag + body) & 0xffffffff)

    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0))
                + chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b""))


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


# --- the shadow region --------------------------------------------------------
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


# --- statistics ---------------------------------------------------------------

def median(xs):
    return statistics.median(xs)


def gnuplot(script):
    if shutil.which("gnuplot") is None:
        sys.exit("gnuplot not found: tools/install-deps installs gnuplot-nox")
    subprocess.run(["gnuplot"], input=script.encode(), check=True)
