"""Errors at a coarser scale: both images averaged over k x k pixel blocks.

A path-traced reference of an indirectly lit room is noisy per pixel (its
own error can exceed the error being measured), and that noise is
independent from pixel to pixel, so averaging k x k blocks divides it by
about k, while a renderer's error at the scale of its patches stays. The
block means are what both renderers would give at 1/k of the resolution
with a box pixel filter (vismask's --aa on is the exact box filter). The
reference's own noise at the same scale comes from its two halves, as at
full resolution (tools/reference --halves).

Needs numpy (tools/install-deps --reference)."""
import math
import os

from .files import load_json, read_pgm
from .scale import ReadPfm as _image


def blocks(img, k):
    """Means over k x k blocks (the last partial row and column dropped)."""
    h, w = img.shape[0] // k * k, img.shape[1] // k * k
    a = img[:h, :w]
    if a.ndim == 2:
        return a.reshape(h // k, k, w // k, k).mean(axis=(1, 3))
    return a.reshape(h // k, k, w // k, k, a.shape[2]).mean(axis=(1, 3))


def kept_blocks(mask_path, shape, k):
    """Blocks with no excluded pixel (a mask pixel > 0 is excluded)."""
    import numpy as np
    if not mask_path or not os.path.exists(mask_path):
        return np.ones((shape[0] // k, shape[1] // k), dtype=bool)
    w, h, v = read_pgm(mask_path)
    m = np.array(v, dtype=np.float64).reshape(h, w) > 0
    return blocks(m.astype(np.float64), k) == 0


def rel_rmse(a, b, keep):
    """sqrt(sum (a-b)^2 / sum b^2) over the kept blocks' RGB values."""
    d = ((a - b) ** 2)[keep].sum()
    n = (b ** 2)[keep].sum()
    return math.sqrt(d / n) if n > 0 else None


def halves(ref_pfm, cache_dir):
    """The reference's two half renders (from its json's cache keys), or None."""
    j = load_json(ref_pfm[:-4] + ".json")
    paths = [os.path.join(cache_dir, h.get("cache_key", ""), "ref.pfm")
             for h in j.get("halves", [])]
    return paths if len(paths) == 2 and all(os.path.exists(p) for p in paths) else None


def half_noise(h1, h2, keep):
    """The two halves' average's relative RMSE against the noise-free image:
    sqrt(sum (h1-h2)^2 / sum ((h1+h2)/2)^2) / 2, as tools/reference states it."""
    d = ((h1 - h2) ** 2)[keep].sum()
    n = (((h1 + h2) / 2) ** 2)[keep].sum()
    return math.sqrt(d / n) / 2 if n > 0 else None


def at_scale(images, ref_pfm, cache_dir, k):
    """{name: error} for each image, plus 'ref_noise' (None without the
    halves), all over k x k block means with the reference's mask."""
    ref = _image(ref_pfm)
    keep = kept_blocks(ref_pfm[:-4] + ".mask.pgm", ref.shape, k)
    rb = blocks(ref, k)
    out = {name: rel_rmse(blocks(_image(p), k), rb, keep) for name, p in images.items()}
    hp = halves(ref_pfm, cache_dir)
    out["ref_noise"] = (half_noise(blocks(_image(hp[0]), k), blocks(_image(hp[1]), k), keep)
                        if hp else None)
    return out


def selftest():
    """Synthetic checks; returns the number of failures."""
    import numpy as np
    failed = 0

    def check(ok, what):
        nonlocal failed
        if not ok:
            failed += 1
            print("coarse selftest FAILED: " + what)

    a = np.arange(4 * 6 * 3, dtype=np.float64).reshape(4, 6, 3)
    b = blocks(a, 2)
    check(b.shape == (2, 3, 3) and b[0, 0, 0] == (0 + 3 + 18 + 21) / 4, "block means")
    check(blocks(a, 4).shape == (1, 1, 3), "partial blocks dropped")
    # A flat truth of 1 seen through two halves with independent per-pixel
    # noise of sigma: their average's error is sigma/sqrt(2), and k x k block
    # means divide it by k.
    rng = np.random.default_rng(7)
    sigma, n = 0.1, 256
    h1 = 1.0 + sigma * rng.standard_normal((n, n, 3))
    h2 = 1.0 + sigma * rng.standard_normal((n, n, 3))
    for k in (1, 2, 4, 8):
        keep = np.ones((n // k, n // k), dtype=bool)
        got = half_noise(blocks(h1, k), blocks(h2, k), keep)
        want = sigma / math.sqrt(2) / k
        check(abs(got - want) < 0.05 * want, "half noise at %dx%d: %.5f, not %.5f" % (k, k, got, want))
    # An error constant over 8 x 8 patches stays at every k up to 8.
    patch = np.kron(rng.choice([-0.03, 0.03], size=(n // 8, n // 8)), np.ones((8, 8)))
    img = 1.0 + patch[:, :, None] * np.ones(3)
    truth = np.ones((n, n, 3))
    for k in (1, 2, 4, 8):
        keep = np.ones((n // k, n // k), dtype=bool)
        got = rel_rmse(blocks(img, k), blocks(truth, k), keep)
        check(abs(got - 0.03) < 1e-9, "patch-scale error at %dx%d: %.5f" % (k, k, got))
    # A block holding an excluded pixel is left out.
    m = np.zeros((n, n))
    m[3, 5] = 1.0
    keep = blocks(m, 4) == 0
    check(keep.sum() == (n // 4) ** 2 - 1 and not keep[0, 1], "excluded block")
    return failed
