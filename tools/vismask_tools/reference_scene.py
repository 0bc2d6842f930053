"""tools/reference's reading of a scene: OBJ + MTL as vismask's loader reads
them (src/scene/scene.cpp), with the same refusals, and vismask's cameras."""

import math
import os


class InputError(Exception):
    pass


def Tokens(line):
    return line.split("#", 1)[0].split()


def Floats(tokens, where):
    try:
        xs = [float(t) for t in tokens]
    except ValueError:
        raise InputError(where + ": bad number in '" + " ".join(tokens) + "'")
    if not all(math.isfinite(x) for x in xs):
        raise InputError(where + ": number not finite")
    return xs


def LoadMtl(path, materials, where):
    try:
        with open(path, "rb") as f:
            data = f.read()
    except OSError as e:
        raise InputError("%s: cannot open MTL file '%s' (%s)" % (where, path, e.strerror))
    current = None
    for n, line in enumerate(data.decode("utf-8", "replace").splitlines(), 1):
        t = Tokens(line)
        if not t:
            continue
        at = "%s:%d" % (path, n)
        if t[0] == "newmtl":
            if len(t) != 2:
                raise InputError(at + ": 'newmtl' needs 1 name")
            if t[1] in materials:
                raise InputError(at + ": duplicate material '" + t[1] + "'")
            current = materials[t[1]] = {"kd": [0.0] * 3, "ke": [0.0] * 3}
        elif t[0] in ("Kd", "Ke"):
            if current is None:
                raise InputError(at + ": '" + t[0] + "' before any 'newmtl'")
            if len(t) != 4:
                raise InputError(at + ": '" + t[0] + "' needs 3 numbers")
            v = Floats(t[1:], at)
            if t[0] == "Kd" and not all(0.0 <= x < 1.0 for x in v):
                raise InputError(at + ": Kd must be in [0, 1)")
            if t[0] == "Ke" and not all(x >= 0.0 for x in v):
                raise InputError(at + ": Ke must be >= 0")
            current[t[0].lower()] = v
    return data


def LoadScene(obj, lit=False):
    """The scene as vismask's loader reads it (src/scene/scene.cpp): vertices, faces
    (0-based corner lists), each face's material, the materials, and the bytes
    of the OBJ and every MTL (for the cache key). vismask's own loader checks
    it first when build/vismask exists (exact same errors)."""
    try:
        with open(obj, "rb") as f:
            data = f.read()
    except OSError as e:
        raise InputError("%s: cannot open (%s)" % (obj, e.strerror))
    blobs = [data]
    materials, order = {}, {}
    vertices, faces, faceMats, mat = [], [], [], None
    for n, line in enumerate(data.decode("utf-8", "replace").splitlines(), 1):
        t = Tokens(line)
        if not t:
            continue
        at = "%s:%d" % (obj, n)
        if t[0] == "v":
            if len(t) not in (4, 5):
                raise InputError(at + ": 'v' needs 3 or 4 numbers")
            vertices.append(Floats(t[1:4], at))
        elif t[0] == "f":
            if len(t) < 4:
                raise InputError(at + ": face with fewer than 3 vertices")
            if mat is None:
                raise InputError(at + ": face before any 'usemtl'")
            face = []
            for c in t[1:]:
                try:
                    i = int(c.split("/")[0])
                except ValueError:
                    raise InputError(at + ": bad face vertex '" + c + "'")
                i = i - 1 if i > 0 else len(vertices) + i
                if not 0 <= i < len(vertices):
                    raise InputError(at + ": vertex index out of range in '" + c + "'")
                face.append(i)
            faces.append(face)
            faceMats.append(order.setdefault(mat, len(order)))
        elif t[0] == "usemtl":
            if len(t) != 2 or t[1] not in materials:
                raise InputError(at + ": undefined material '" + " ".join(t[1:]) + "'")
            mat = t[1]
        elif t[0] == "mtllib":
            for name in t[1:]:
                blobs.append(LoadMtl(os.path.join(os.path.dirname(obj), name), materials, at))
        elif t[0] not in ("vn", "vt", "o", "g", "s"):
            raise InputError(at + ": unknown statement '" + t[0] + "'")
    if not faces:
        raise InputError(obj + ": no faces")
    mats = [None] * len(order)
    for name, k in order.items():
        mats[k] = materials[name]
    if not lit and not any(max(m["ke"]) > 0 for m in mats):  # lit: --sky or --sun
        raise InputError(obj + ": no emitter: no face has a material with Ke > 0")
    return vertices, faces, faceMats, mats, blobs


def DefaultCamera(vertices, faces):
    """vismask's DefaultCamera (src/display/camera.cpp: the front side's camera, not
    the side vismask may choose) over the bounds of all polygon corners, in
    float32 arithmetic as far as it matters here."""
    used = [vertices[i] for f in faces for i in f]
    lo = [min(v[k] for v in used) for k in range(3)]
    hi = [max(v[k] for v in used) for k in range(3)]
    fovy = 39.3
    centre = [0.5 * (lo[k] + hi[k]) for k in range(3)]
    half = [0.5 * (hi[k] - lo[k]) for k in range(3)]
    tanHalf = math.tan(0.5 * fovy * 3.14159265358979 / 180.0)
    reach = max(half[0], half[1])
    if reach <= 0.0:
        reach = max(half[2], 1.0)
    distance = 1.04 * reach / tanHalf
    return [centre[0], centre[1], lo[2] - distance, centre[0], centre[1], lo[2], 0.0, 1.0, 0.0, fovy]


def CheckCamera(c):
    eye, target, up, fovy = c[0:3], c[3:6], c[6:9], c[9]
    f = [target[k] - eye[k] for k in range(3)]
    cr = [f[1] * up[2] - f[2] * up[1], f[2] * up[0] - f[0] * up[2], f[0] * up[1] - f[1] * up[0]]
    n = lambda v: math.sqrt(sum(x * x for x in v))  # noqa: E731
    if not (0.0 < fovy < 180.0) or not n(f) > 0.0 or not n(cr) > 1e-6 * n(up) * n(f):
        raise InputError("--camera: eye != target, up not parallel to the view direction, 0 < fovy < 180")
