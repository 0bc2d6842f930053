"""The ground-truth step's silhouette part (issue 41): vismask against the
Cycles ground truth at the original camera with the emitter's pixels left out
(REF.mask.pgm) and with the 1-px silhouettes left out as well
(tools/silhouette-mask, run as a command since it needs numpy): `--max-seconds
T` at otherwise default options, and the fixed settings of the
error-against-time runs; and RenderPark (rpkCpp's hierarchical Galerkin, by
tools/renderpark-run) when make renderpark has built it. Writes
gt-silhouette-mask.csv, gt-silhouettes.csv and gt-renderpark-measured.csv."""

import os
import subprocess
import sys

from . import ROOT
from .cornell import SCENE
from .files import load_json, read_pfm, read_pgm
from .gt_references import ORIGINAL
from .runner import log


def silhouette_keep(ctx, ref):
    """Writes runs/gt/original-silhouettes.pgm (emitter + silhouettes, what
    `vismask compare --exclude` takes) and returns its pixels kept (1) or left
    out (0), and the figures of gt-silhouette-mask.csv."""
    out = os.path.join(ctx.runs, "gt", "original-silhouettes.pgm")
    os.makedirs(os.path.dirname(out), exist_ok=True)
    cmd = [os.path.join(ROOT, "tools", "silhouette-mask"), SCENE, "--camera", ORIGINAL,
           "--size", str(ref.w), str(ref.h), "--exclude", ref.pgm, "--out", out]
    log("  " + " ".join(os.path.relpath(c, ROOT) if c.startswith(ROOT) else c for c in cmd))
    subprocess.run(cmd, check=True, stdout=sys.stderr)
    left = [1 if m else 0 for m in read_pgm(out)[2]]
    total, both, emit = len(left), sum(left), len(left) - sum(ref.keep)
    # The silhouettes alone: the tool's mask without the emitter's pixels
    # counts those of them that are not also the emitter's.
    sil = sum(1 for m, k in zip(left, ref.keep) if m and k)
    keep = [1 - m for m in left]
    rows = [["emitter (REF.mask.pgm)", emit, emit / total],
            ["1-px silhouettes outside the emitter's pixels", sil, sil / total],
            ["emitter + silhouettes", both, both / total]]
    return keep, rows


def silhouettes(ctx, ref, fixed, run, image, write_csv):
    """`fixed`: (name, options) of the error-against-time runs already made
    (run names gt-NAME, read, not rerun); `run`, `image`, `write_csv`:
    groundtruth.py's."""
    g = ctx.s["gt"]
    keep, mask_rows = silhouette_keep(ctx, ref)
    write_csv(ctx.result("gt-silhouette-mask.csv"), ["left_out", "pixels", "fraction"], mask_rows)
    rows, fixed_rows = [], []
    for name, args in fixed:
        if "--max-seconds" in args:
            continue
        j = load_json(ctx.path("gt-" + name, "run.json"))
        img = image(ctx, name)
        fixed_rows.append([name, " ".join(args) or "(defaults)", "", j["timings"]["solve_seconds"],
                           j["result"]["stop_reason"], j["result"]["shots"], ref.error(img),
                           ref.error(img, keep)])
    for T in g["anytime"]:
        args = g["default"] + ["--max-seconds", f"{T:g}"]
        name = f"anytime-{T:g}s"
        j = run(ctx, name, args, ref)
        img = image(ctx, name)
        rows.append([name, " ".join(args), T, j["timings"]["solve_seconds"],
                     j["result"]["stop_reason"], j["result"]["shots"], ref.error(img),
                     ref.error(img, keep)])
    # The anytime goal: within 1.25x of the best fixed setting whose solve
    # finished within T (emitter mask).
    for r in rows:
        best = [f for f in fixed_rows if f[3] <= r[2]]
        b = min(best, key=lambda f: f[6]) if best else None
        r += ["" if b is None else b[0], "" if b is None else b[6],
              "" if b is None else r[6] / b[6]]
    for f in fixed_rows:
        f += ["", "", ""]
    write_csv(ctx.result("gt-silhouettes.csv"),
              ["run", "options", "max_seconds", "solve_seconds", "stop", "shots", "vs_gt",
               "vs_gt_no_silhouettes", "best_fixed_within", "best_fixed_vs_gt",
               "anytime_over_best_fixed"], rows + fixed_rows)
    renderpark(ctx, ref, keep, write_csv)


def rpk_binary():
    """$RPK_BIN, else make renderpark's build/renderpark/build/rpk, or None."""
    b = os.environ.get("RPK_BIN") or os.path.join(ROOT, "build", "renderpark", "build", "rpk")
    return b if os.access(b, os.X_OK) else None


def renderpark(ctx, ref, keep, write_csv):
    """rpkCpp at each of gt.rpk's option lists: its CPU seconds (its own last
    "CPU time" line) and errors, or a note that it is not built."""
    out = ctx.result("gt-renderpark-measured.csv")
    note = ctx.result("gt-renderpark-skipped.txt")
    for p in (out, note):
        if os.path.exists(p):
            os.remove(p)
    rpk = rpk_binary()
    if rpk is None:
        with open(note, "w") as f:
            f.write("RenderPark not built (make renderpark RPK_SRC=DIR, a checkout of "
                    "github.com/OscarChavarro/rpkCpp 37e5ff4e; or RPK_BIN=BINARY)\n")
        log("experiments: RenderPark not built, its measured rows skipped")
        return
    rows = []
    for k, opts in enumerate(ctx.s["gt"]["rpk"]):
        pfm = os.path.join(ctx.runs, "gt", f"renderpark-{k}.pfm")
        cmd = [os.path.join(ROOT, "tools", "renderpark-run"), "render", "--rpk", rpk, SCENE,
               "--camera", ORIGINAL, "--size", str(ref.w), str(ref.h), "--out", pfm, "--"] + opts
        log("  " + " ".join(os.path.relpath(c, ROOT) if c.startswith(ROOT) else c for c in cmd))
        r = subprocess.run(cmd, check=True, capture_output=True, text=True)
        cpu = float(r.stdout.split("CPU time ")[1].split()[0])
        img = read_pfm(pfm)[2]
        rows.append(["rpkCpp hierarchical Galerkin", " ".join(opts), cpu, ref.error(img),
                     ref.error(img, keep)])
    write_csv(out, ["renderpark", "options", "cpu_seconds", "vs_gt", "vs_gt_no_silhouettes"], rows)
