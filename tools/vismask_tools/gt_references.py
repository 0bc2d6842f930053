"""The ground truths of the experiments (issue 15): Blender Cycles renders
made by tools/reference (cached under build/reference-cache/), or a
reference committed under docs/results/reference/ when present."""

import gzip
import os
import shutil
import subprocess

from . import ROOT
from .cornell import SCENE
from .files import load_json, read_pfm, read_pgm
from .images import rel_rmse
from .runner import log, shown
from .scales import CAMERA, arg

# The Cornell box's original camera (eye, target, up, vertical fov).
ORIGINAL = "278,273,-800,278,273,0,0,1,0,39.3076"
COMMITTED = os.path.join(ROOT, "docs", "results", "reference")


def have_blender():
    return shutil.which("blender") is not None


class Reference:
    """A ground truth: its PFM, its mask (PGM), the pixels kept (1) or
    excluded (0), its own noise (relative RMSE) and how it was made."""

    def __init__(self, pfm, pgm, noise, what):
        self.pfm, self.pgm, self.noise, self.what = pfm, pgm, noise, what
        self.w, self.h, self.px = read_pfm(pfm)
        self.keep = [0 if m else 1 for m in read_pgm(pgm)[2]]

    def args(self):
        return ["--reference", self.pfm, "--exclude", self.pgm]

    def error(self, img, mask=None):
        keep = self.keep if mask is None else [k and m for k, m in zip(self.keep, mask)]
        return rel_rmse(img, self.px, keep)


def cycles_halves(ctx, scene, camera, width, height, spp, out, extra=()):
    """tools/reference's Cycles render of `scene` into `out` as two halves
    (their difference gives its own noise), cached by tools/reference;
    returns its json."""
    cmd = [os.path.join(ROOT, "tools", "reference"), scene, "--camera", camera, "--size",
           str(width), str(height), "--spp", str(spp), "--halves"] + list(extra) + [
           "--quiet", "--out", out]
    log("  " + shown(cmd))
    subprocess.run(cmd, check=True, env=dict(os.environ, VISMASK_BIN=ctx.bin))
    return load_json(out[:-4] + ".json")


def render_reference(ctx, name, camera, size, spp):
    """tools/reference with --halves into runs/gt/NAME.pfm (cached by tools/reference)."""
    d = os.path.join(ctx.runs, "gt")
    os.makedirs(d, exist_ok=True)
    out = os.path.join(d, f"{name}.pfm")
    cmd = [os.path.join(ROOT, "tools", "reference"), SCENE] + (
        ["--camera", camera] if camera else []) + [
        "--size", str(size), str(size), "--spp", str(spp), "--halves", "--quiet", "--out", out]
    log("  " + " ".join(os.path.relpath(c, ROOT) if c.startswith(ROOT) else c for c in cmd))
    subprocess.run(cmd, check=True, env=dict(os.environ, VISMASK_BIN=ctx.bin))
    meta = load_json(out[:-4] + ".json")
    return Reference(out, out[:-4] + ".mask.pgm", meta["noise_relative_rmse"],
                     f"tools/reference scenes/cornell.obj{' --camera ' + camera.replace(',', ' ') if camera else ''} "
                     f"--size {size} {size} "
                     f"--spp {spp} --halves (Blender {meta.get('blender', '?')}, "
                     f"{meta.get('wall_seconds', 0):.0f} s)")


def committed(ctx, stem):
    """docs/results/reference/STEM.pfm.gz (+ mask, + json), decompressed into
    the runs directory, or None."""
    src = os.path.join(COMMITTED, stem)
    if not os.path.exists(src + ".pfm.gz"):
        return None
    d = os.path.join(ctx.runs, "gt")
    os.makedirs(d, exist_ok=True)
    out = {}
    for ext in (".pfm", ".mask.pgm", ".json"):
        dst = os.path.join(d, "committed-" + stem + ext)
        for cand in (src + ext + ".gz", src + ext):
            if os.path.exists(cand):
                opener = gzip.open if cand.endswith(".gz") else open
                with opener(cand, "rb") as f, open(dst, "wb") as g:
                    shutil.copyfileobj(f, g)
                out[ext] = dst
                break
    if ".mask.pgm" not in out:
        return None
    meta = load_json(out[".json"]) if ".json" in out else {}
    noise = meta.get("noise_relative_rmse", meta.get("noise", float("nan")))
    return Reference(out[".pfm"], out[".mask.pgm"], noise,
                     f"docs/results/reference/{stem}.pfm.gz (committed: "
                     f"{meta.get('command', 'command in its json')})")


def original_reference(ctx):
    g = ctx.s["gt"]
    ref = committed(ctx, f"cornell-original-{g['size']}") if ctx.scale == "full" else None
    return ref or render_reference(ctx, f"cornell-original-{g['size']}", ORIGINAL, g["size"], g["spp"])


def demo_reference(ctx):
    """At vismask's default camera (make demo's), full scale only."""
    g = ctx.s["gt"]
    return render_reference(ctx, f"cornell-default-{g['size']}", None, g["size"], g["spp"])


def experiments_reference(ctx):
    """At the experiments' own camera and size (CAMERA): the committed one
    when there is one, else rendered; None without blender."""
    g = ctx.s["gt"]
    w = int(arg(ctx.s["common"], "--width"))
    ref = committed(ctx, f"cornell-experiments-{w}") if ctx.scale == "full" else None
    if ref:
        return ref
    if not have_blender():
        return None
    return render_reference(ctx, f"cornell-experiments-{w}", arg(CAMERA, "--camera"), w,
                            g["exp_spp"])


_EXP = {}


def exp_reference(ctx):
    """The experiments camera's reference, made once per process (None without blender)."""
    if ctx.out not in _EXP:
        _EXP[ctx.out] = experiments_reference(ctx)
    return _EXP[ctx.out]
