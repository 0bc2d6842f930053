"""A vismask scene as vismask itself loads it: `vismask scene-dump` (src/app/
scene_dump.cpp, the format in its header) run on the scene, so that the tools
that build another renderer's scene (tools/reference's Blender scene,
tools/silhouette-mask, tools/renderpark-run) read no OBJ, MTL or glTF
themselves, see the polygons as mended and the camera vismask chooses, and
refuse exactly what `vismask render` refuses (its message, file:line)."""

import json
import math
import os
import subprocess
import tempfile

from . import ROOT


class InputError(Exception):
    """The scene or an option that vismask refuses (exit 2)."""


def Binary():
    return os.environ.get("VISMASK_BIN", os.path.join(ROOT, "build", "vismask"))


def Dump(scene, args=()):
    """The scene-dump of `scene` with vismask's scene options `args` (such as
    --sky, --sun, --emit, --camera, --width, --height) as a dict."""
    binary = Binary()
    if not os.access(binary, os.X_OK):
        raise InputError("%s not found: the tools read scenes through vismask (make builds it; "
                         "VISMASK_BIN names another)" % binary)
    with tempfile.TemporaryDirectory(prefix="scene-dump.") as tmp:
        out = os.path.join(tmp, "scene.json")
        p = subprocess.run([binary, "scene-dump", scene] + list(args) + ["--quiet", "--out", out],
                           capture_output=True, text=True)
        if p.returncode == 2:
            raise InputError(p.stderr.strip() or scene + ": vismask refuses this scene")
        if p.returncode != 0 or not os.path.exists(out):
            raise OSError("%s scene-dump %s: exit %d: %s" % (binary, scene, p.returncode,
                                                              p.stderr.strip()))
        with open(out) as f:
            return json.load(f)


def LightArgs(sky=None, sun=None):
    """vismask's --sky and --sun arguments for a sky [r, g, b] and a sun
    {toward, irradiance, degrees} (tools/reference's)."""
    args = []
    if isinstance(sky, dict):  # a sky map: {file, sha256}
        args += ["--sky", sky["file"]]
    elif sky is not None:
        args += ["--sky", ",".join(repr(float(v)) for v in sky)]
    if sun is not None:
        args += ["--sun", ",".join(repr(float(v)) for v in
                                   list(sun["toward"]) + list(sun["irradiance"]) + [sun["degrees"]])]
    return args


def CameraArgs(camera, width=None, height=None):
    """vismask's --camera (ten numbers) and the image size its checks need."""
    args = ["--camera", ",".join(repr(float(v)) for v in camera)]
    if width is not None:
        args += ["--width", str(width), "--height", str(height)]
    return args


def Camera(c):
    """A dumped camera as --camera's ten numbers: eye, target, up, fovy."""
    return list(c["eye"]) + list(c["target"]) + list(c["up"]) + [c["fovy"]]


# Corners at one point are one vertex only between faces of one material
# whose normals are within this angle (vismask's --crease default): a quad
# cut in two triangles stays one surface, walls meeting at a corner do not
# share it (RenderPark's display interpolates over shared vertices).
CREASE_COS = math.cos(math.radians(30.0))


def Normal(corners):
    """A polygon's unit normal (Newell's method), or zero."""
    n = [0.0, 0.0, 0.0]
    for k, a in enumerate(corners):
        b = corners[(k + 1) % len(corners)]
        n[0] += (a[1] - b[1]) * (a[2] + b[2])
        n[1] += (a[2] - b[2]) * (a[0] + b[0])
        n[2] += (a[0] - b[0]) * (a[1] + b[1])
    length = math.sqrt(sum(x * x for x in n))
    return [x / length for x in n] if length > 0 else n


def Mesh(d):
    """The dump's polygons as an indexed mesh: (vertices, faces, face
    materials, materials). Vertices in order of first use, a corner reusing
    one at its point when their faces share a material and are within
    CREASE_COS; materials are those faces use, in order of first use, each
    {name, kd, ke, two_sided, texture}."""
    at, vertices, faces, faceMats, order = {}, [], [], [], {}
    for face in d["faces"]:
        n, m = Normal(face["corners"]), face["material"]
        corners = []
        for c in face["corners"]:
            here = at.setdefault(tuple(c), [])
            for v, vm, vn in here:
                if vm == m and sum(x * y for x, y in zip(n, vn)) >= CREASE_COS:
                    break
            else:
                v = len(vertices)
                vertices.append(list(c))
                here.append((v, m, n))
            corners.append(v)
        faces.append(corners)
        faceMats.append(order.setdefault(m, len(order)))
    mats = [None] * len(order)
    for k, i in order.items():
        m = d["materials"][k]
        mats[i] = {"name": m["name"], "kd": m["kd"], "ke": m["ke"], "two_sided": m["two_sided"],
                   "texture": m["texture"]}
    return vertices, faces, faceMats, mats


def Blobs(d):
    """The bytes of every file the scene was read from (the scene file, then
    its MTL files), in the dump's order."""
    blobs = []
    for path in d["files"]:
        with open(path, "rb") as f:
            blobs.append(f.read())
    return blobs
