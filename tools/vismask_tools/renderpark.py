"""RenderPark (rpkCpp) input and output for issue 41's comparison: a vismask
scene as MGF, and rpkCpp's radiance image (.pic: Radiance RGBE) as linear
RGB. Needs numpy.

The MGF: the scene's vertices times `scale` (rpkCpp's Galerkin is wrong at
millimetre scale: 0.001 gives metres); each material's Kd as a CIE xy
chromaticity and luminance Y under rpkCpp's own primaries (src/common/cie.cpp:
CRT primaries, white point E), so that rpkCpp's RGB of it is Kd again; Ke the
same way as `ed` = Y(Ke) * 183.07 (rpkCpp's white luminous efficacy, lm/W),
which gives radiance Ke/pi in rpkCpp's image, as in vismask's."""

import numpy as np

from .scene_dump import Dump, Mesh

PRIMARIES = ((0.640, 0.330), (0.290, 0.600), (0.150, 0.060))
WHITE = (1.0 / 3.0, 1.0 / 3.0)
WHITE_EFFICACY = 183.07


def _xyz(x, y):
    return np.array([x / y, 1.0, (1.0 - x - y) / y])


def rgb_to_xyz_matrix():
    p = np.stack([_xyz(*c) for c in PRIMARIES], axis=1)
    return p * np.linalg.solve(p, _xyz(*WHITE))


def xy_and_luminance(rgb):
    """(x, y, Y) of a linear RGB under rpkCpp's primaries."""
    X, Y, Z = rgb_to_xyz_matrix() @ np.asarray(rgb, dtype=np.float64)
    s = X + Y + Z
    return (X / s, Y / s, Y) if s > 0 else (WHITE[0], WHITE[1], 0.0)


def scene_to_mgf(obj, scale, args=()):
    """The MGF text of scene `obj` as vismask loads it (vismask scene-dump
    with its options `args`; InputError when vismask refuses them)."""
    vertices, faces, face_mats, mats = Mesh(Dump(obj, args))
    out = []
    for k, m in enumerate(mats):
        x, y, Y = xy_and_luminance(m["kd"])
        out += [f"m m{k} =", "\tc", f"\t\tcxy {x:.6f} {y:.6f}", f"\trd {Y:.6f}"]
        if max(m["ke"]) > 0:
            ex, ey, eY = xy_and_luminance(m["ke"])
            out += ["\tc", f"\t\tcxy {ex:.6f} {ey:.6f}", f"\ted {eY * WHITE_EFFICACY:.6f}"]
    for i, p in enumerate(vertices):
        out += [f"v v{i} =", "\tp " + " ".join(f"{c * scale:.9g}" for c in p)]
    current = None
    for face, k in zip(faces, face_mats):
        if k != current:
            out.append(f"m m{k}")
            current = k
        out.append("f " + " ".join(f"v{i}" for i in face))
    return "\n".join(out) + "\n"


def read_rgbe(path):
    """A Radiance RGBE image (flat or new-style run-length scanlines, -Y H +X W)
    as floats (H, W, 3), row 0 at the top."""
    with open(path, "rb") as f:
        d = f.read()
    i = 0
    while True:
        j = d.index(b"\n", i)
        line, i = d[i:j], j + 1
        if line.startswith(b"-Y"):
            t = line.split()
            if len(t) != 4 or t[2] != b"+X":
                raise ValueError(f"{path}: unsupported orientation '{line.decode()}'")
            h, w = int(t[1]), int(t[3])
            break
    out = np.zeros((h, w, 4), np.uint8)
    for y in range(h):
        if 8 <= w < 32768 and d[i] == 2 and d[i + 1] == 2 and (d[i + 2] << 8 | d[i + 3]) == w:
            i += 4
            for c in range(4):
                x = 0
                while x < w:
                    n = d[i]
                    i += 1
                    if n > 128:
                        n -= 128
                        out[y, x:x + n, c] = d[i]
                        i += 1
                    else:
                        out[y, x:x + n, c] = np.frombuffer(d[i:i + n], np.uint8)
                        i += n
                    x += n
        else:
            out[y] = np.frombuffer(d[i:i + 4 * w], np.uint8).reshape(w, 4)
            i += 4 * w
    e = out[..., 3].astype(np.int32)
    f = np.where(e > 0, np.ldexp(1.0, e - 136), 0.0)
    return (out[..., :3].astype(np.float64) + 0.5 * (e[..., None] > 0)) * f[..., None]


def write_pfm(path, img):
    """(H, W, 3) floats, row 0 at the top, as a little-endian PFM (bottom row first)."""
    h, w, _ = img.shape
    with open(path, "wb") as f:
        f.write(b"PF\n%d %d\n-1.0\n" % (w, h))
        f.write(np.ascontiguousarray(img[::-1]).astype("<f4").tobytes())
