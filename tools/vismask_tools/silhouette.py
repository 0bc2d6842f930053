"""The 1-px silhouette mask (issue 41): the pixels within 1 px of a
geometric edge of the image, where a one-sample-per-pixel raycast (such as
RenderPark's) aliases. One ray through each pixel centre, with vismask's
camera (src/display/camera.cpp MakeView), finds the surface it sees: faces on one
plane with one material are one surface (the left wall's two triangles are
one). A pixel is marked when its 3x3 neighbourhood of centre rays sees more
than one surface or misses the scene: silhouettes, occlusions, creases and
material boundaries. Needs numpy (tools/install-deps --reference)."""

import math

import numpy as np

from .scene_dump import CameraArgs, Dump, Mesh


# Faces are one surface when their normals are within about 0.8 degrees and
# each corner of one lies within this fraction of the scene's extent of the
# other's plane: the Cornell box's left wall is two triangles whose corners
# are 0.8 mm off their best-fit plane; one triangle's far corner is 3.2 mm
# (0.0057 of 559 mm) off the other's plane, their normals 0.37 degrees apart.
PLANE_TOL = 1e-2


def surfaces(vertices, faces, face_mats):
    """Each face's surface: faces share one when they have one material and
    are coplanar within PLANE_TOL (a crease this flat draws no edge)."""
    vs = np.asarray(vertices, dtype=np.float64)
    extent = float(np.max(np.ptp(vs, axis=0))) or 1.0
    planes, ids = [], []
    for f, m in zip(faces, face_mats):
        p = vs[f]
        n = np.zeros(3)
        for k in range(len(p)):  # Newell's normal
            a, b = p[k], p[(k + 1) % len(p)]
            n += np.cross(a, b)
        n /= np.linalg.norm(n) or 1.0
        d = float(np.dot(n, p.mean(axis=0)))
        for k, (n2, d2, m2) in enumerate(planes):
            if m2 == m and np.dot(n, n2) > 1 - 1e-4 and np.all(
                    np.abs(p @ n2 - d2) <= PLANE_TOL * extent):
                ids.append(k)
                break
        else:
            ids.append(len(planes))
            planes.append((n, d, m))
    return ids


def view(camera, width, height):
    """vismask's View: eye, right, up, forward and the focal length in pixels."""
    eye, target, up = (np.asarray(camera[i:i + 3], dtype=np.float64) for i in (0, 3, 6))
    f = target - eye
    f /= np.linalg.norm(f)
    r = np.cross(f, up)
    r /= np.linalg.norm(r)
    u = np.cross(r, f)
    focal = 0.5 * height / math.tan(0.5 * camera[9] * math.pi / 180.0)
    return eye, r, u, f, focal


def surface_map(vertices, faces, face_mats, camera, width, height):
    """The surface seen through each pixel centre (rows top to bottom), -1
    where the ray misses every face. Faces are fanned into triangles (they
    are convex in the scenes this is for)."""
    eye, r, u, f, focal = view(camera, width, height)
    x = np.arange(width) + 0.5 - 0.5 * width
    y = 0.5 * height - (np.arange(height) + 0.5)
    d = focal * f[None, None, :] + x[None, :, None] * r[None, None, :] + y[:, None, None] * u[None, None, :]
    d = d.reshape(-1, 3)
    best = np.full(d.shape[0], np.inf)
    seen = np.full(d.shape[0], -1, dtype=np.int64)
    vs = np.asarray(vertices, dtype=np.float64)
    for sid, face in zip(surfaces(vertices, faces, face_mats), faces):
        for k in range(1, len(face) - 1):  # Moller-Trumbore, both sides
            a, b, c = vs[face[0]], vs[face[k]], vs[face[k + 1]]
            e1, e2 = b - a, c - a
            p = np.cross(d, e2)
            det = p @ e1
            ok = np.abs(det) > 1e-12
            inv = np.where(ok, 1.0 / np.where(ok, det, 1.0), 0.0)
            s = eye - a
            bu = (p @ s) * inv
            q = np.cross(s, e1)
            bv = (d @ q) * inv
            t = (q @ e2) * inv
            hit = ok & (bu >= 0) & (bv >= 0) & (bu + bv <= 1) & (t > 0) & (t < best)
            best[hit] = t[hit]
            seen[hit] = sid
    return seen.reshape(height, width)


def edge_mask(ids):
    """1 where the 3x3 neighbourhood (clipped at the border) holds more than
    one value of `ids` or a -1 (a miss)."""
    h, w = ids.shape
    pad = np.pad(ids, 1, mode="edge")
    out = ids < 0
    for dy in (-1, 0, 1):
        for dx in (-1, 0, 1):
            nb = pad[1 + dy:1 + dy + h, 1 + dx:1 + dx + w]
            out = out | (nb != ids) | (nb < 0)
    return out.astype(np.uint8)


def read_pgm(path):
    with open(path, "rb") as f:
        data = f.read()
    parts = data.split(maxsplit=4)
    if parts[0] != b"P5":
        raise ValueError(path + ": not a binary PGM (P5)")
    w, h = int(parts[1]), int(parts[2])
    return np.frombuffer(data[len(data) - w * h:], dtype=np.uint8).reshape(h, w)


def write_pgm(path, mask):
    h, w = mask.shape
    with open(path, "wb") as f:
        f.write(b"P5\n%d %d\n255\n" % (w, h))
        f.write((np.where(mask > 0, 255, 0).astype(np.uint8)).tobytes())


def silhouette_mask(obj, camera, width, height):
    # The scene and the camera as vismask loads and checks them (InputError
    # when it refuses either).
    vertices, faces, face_mats, _ = Mesh(Dump(obj, CameraArgs(camera, width, height)))
    return edge_mask(surface_map(vertices, faces, face_mats, camera, width, height))


def write_combined(obj, camera, width, height, out, exclude=None):
    """Writes OUT.pgm: 255 on the silhouette pixels and on EXCLUDE's nonzero
    pixels. Returns (silhouette pixels, pixels in OUT, pixels in all)."""
    sil = silhouette_mask(obj, camera, width, height)
    both = sil.copy()
    if exclude is not None:
        base = read_pgm(exclude)
        if base.shape != sil.shape:
            raise ValueError("%s: %dx%d, not %dx%d" % (exclude, base.shape[1], base.shape[0], width, height))
        both = both | (base > 0)
    write_pgm(out, both)
    return int(sil.sum()), int((both > 0).sum()), width * height
