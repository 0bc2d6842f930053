"""The experiment steps of issue #6 (see docs/RESULTS.md). Each step runs
what it needs (runs are cached by their command line under the runs
directory) and writes its CSV tables and images into the results directory.
Run them with tools/experiments [STEP...] [--quick] [--out DIR]: references,
quality, timing, leak, error-time, closed-box, ground-truth, report, or all
(the default)."""

import json
import math
import os
import shutil
import subprocess
import sys
import time

from . import ROOT, groundtruth
from .scales import CAMERA, SCALES, SEED_MINUTES, SPLIT, arg, context
from .cli import parse
from .cornell import SCENE, ShadowRegion, region_patch_mean
from .files import load_json, read_csv, read_pfm, write_csv, write_png
from .images import average_pfm, diff_png, rel_rmse
from .machine import commit, facts, loadavg
from .plot import gnuplot
from .runner import log, render
from .stats import median

METHODS_CURVES = ["A", "B", "C"]  # masks of R x 4R pixels, at each R
SINGLE = ("none", "R")  # no resolution: one run each


def mask_args(method, res):
    return SPLIT + ["--mask-method", method] + (
        [] if method in SINGLE else ["--mask-res", str(res)])


def configs(resolutions, methods=METHODS_CURVES):
    """(method, R) in table order: none, the masks at each R, then R."""
    return [("none", 0)] + [(m, r) for m in methods for r in resolutions] + [("R", 0)]


# --- references ---------------------------------------------------------------

def references(ctx):
    """(b) the converged single-environment solution: two seeds, averaged;
    its own noise from the difference of the two. (a) is the paper's: Method
    B at R = ref_res, which is also that curve's run (curves())."""
    s = ctx.s
    seeds = s["ref_seeds"]
    jsons = [ctx.run(f"ref-b-seed{k}", ["--envs", "1"] + s["ref_b"] + ["--seed", str(k)])
             for k in seeds]
    ref_b = ref_b_path(ctx)
    average_pfm([ctx.path(f"ref-b-seed{k}", "image.pfm") for k in seeds], ref_b)
    _, _, a = read_pfm(ctx.path(f"ref-b-seed{seeds[0]}", "image.pfm"))
    _, _, b = read_pfm(ctx.path(f"ref-b-seed{seeds[1]}", "image.pfm"))
    mask = region_mask(ctx, jsons[0])
    # Two independent solves differ by sqrt(2) sigma; their mean has sigma/sqrt(2).
    d_whole, d_region = rel_rmse(a, b), rel_rmse(a, b, mask)
    rows = [["b", "1 environment " + " ".join(s["ref_b"]) + f" seeds {seeds[0]} and {seeds[1]} averaged",
             sum(j["result"]["shots"] for j in jsons), sum(j["timings"]["solve_seconds"] for j in jsons),
             d_whole / 2, d_region / 2]]
    write_csv(ctx.result("references.csv"),
                  ["reference", "what", "shots", "solve_seconds", "noise_whole", "noise_region"], rows)
    # The reference images themselves.
    os.makedirs(ctx.result("img"), exist_ok=True)
    shutil.copy(ctx.path(f"ref-b-seed{seeds[0]}", "image.png"), ctx.result("img/ref-b.png"))
    return ref_b


def ref_b_path(ctx):
    return os.path.join(ctx.runs, "ref-b.pfm")


def region_mask(ctx, run_json, right_only=False):
    """The shadow region's pixels (1) for this run's camera and size; with
    right_only, only its part in the second environment (x < 278)."""
    w, h = run_json["options"]["width"], run_json["options"]["height"]
    cache = os.path.join(ctx.runs, f"region-{w}x{h}.txt")
    mask = ShadowRegion().pixel_mask(run_json["options"]["camera"], w, h, cache)
    return [1 if (m == 2 if right_only else m > 0) else 0 for m in mask]


def ensure_references(ctx):
    if not os.path.exists(ctx.result("references.csv")) or not os.path.exists(ref_b_path(ctx)):
        references(ctx)
    return ref_b_path(ctx)


# --- the runs with error curves -----------------------------------------------

def curve_run(ctx, method, res):
    """The run of a method (and R) with its error against reference (b) every
    error_every shots: the error-time curve, and Fig. 2 / Fig. 3's image."""
    ref_b = ensure_references(ctx)
    name = method if method in SINGLE else f"{method}-{res}"
    j = ctx.run(name, mask_args(method, res) + ["--reference", ref_b, "--error-every",
                                                 str(ctx.s["error_every"])])
    return name, j


def curve_runs(ctx):
    return [curve_run(ctx, m, r) for m, r in configs(ctx.s["curve_res"])]


# --- Fig. 2 -> table ------------------------------------------------------------

def quality(ctx):
    s = ctx.s
    ref_b = ensure_references(ctx)
    ref_a_name, ref_a_json = curve_run(ctx, "B", s["ref_res"])
    mask = region_mask(ctx, ref_a_json)
    right = region_mask(ctx, ref_a_json, right_only=True)
    _, _, ra = read_pfm(ctx.path(ref_a_name, "image.pfm"))
    w, h, rb = read_pfm(ref_b)
    gt = groundtruth.exp_reference(ctx)
    rows = []
    os.makedirs(ctx.result("img"), exist_ok=True)
    for r in s["table_res"] + [s["ref_res"]]:
        name, j = curve_run(ctx, "B", r)
        _, _, img = read_pfm(ctx.path(name, "image.pfm"))
        ref = r == s["ref_res"]
        rows.append([r, "" if ref else rel_rmse(img, ra),
                     "" if ref else rel_rmse(img, ra, mask),
                     "" if ref else rel_rmse(img, ra, right),
                     rel_rmse(img, rb), rel_rmse(img, rb, mask), rel_rmse(img, rb, right),
                     j["timings"]["solve_seconds"]] + gt_columns(gt, img, mask, right))
        shutil.copy(ctx.path(name, "image.png"), ctx.result(f"img/fig2-B-{r}.png"))
        diff_png(ctx.result(f"img/fig2-B-{r}-diff.png"), w, h, img, ra, 10, mask)
    # The noise floor of a comparison between two 2-environment runs: the
    # lowest R again with another seed.
    low = s["table_res"][0]
    j2 = ctx.run(f"B-{low}-seed2", mask_args("B", low) + ["--seed", "2"])
    _, _, x1 = read_pfm(ctx.path(f"B-{low}", "image.pfm"))
    _, _, x2 = read_pfm(ctx.path(f"B-{low}-seed2", "image.pfm"))
    rows.append([f"{low} (seed 2 vs seed 1)", rel_rmse(x2, x1), rel_rmse(x2, x1, mask),
                 rel_rmse(x2, x1, right), "", "", "", j2["timings"]["solve_seconds"], "", "", ""])
    write_csv(ctx.result("fig2-quality.csv"),
                  ["mask_res", "vs_ref_a_whole", "vs_ref_a_region", "vs_ref_a_right",
                   "vs_ref_b_whole", "vs_ref_b_region", "vs_ref_b_right", "solve_seconds",
                   "vs_gt_whole", "vs_gt_region", "vs_gt_right"], rows)
    # The ground truth of this camera, and reference (b) against it.
    if gt is not None:
        groundtruth.write_csv(ctx.result("gt-experiments.csv"),
                      ["what", "noise", "ref_b_vs_gt_whole", "ref_b_vs_gt_region", "ref_b_vs_gt_right"],
                      [[gt.what, gt.noise] + gt_columns(gt, rb, mask, right)])
    elif os.path.exists(ctx.result("gt-experiments.csv")):
        os.remove(ctx.result("gt-experiments.csv"))
    # The region itself, for the doc.
    region_png(ctx, w, h, rb, mask)


def gt_columns(gt, img, mask, right):
    """The image's relative RMSE against the ground truth (emitter pixels
    excluded): whole, shadow region, its right part; blank without one."""
    if gt is None:
        return ["", "", ""]
    return [gt.error(img), gt.error(img, mask), gt.error(img, right)]


def region_mean(img, mask):
    """Mean over the mask's pixels, channels summed."""
    n = sum(mask)
    return sum(sum(img[3 * i:3 * i + 3]) for i in range(len(mask)) if mask[i]) / max(1, n)


def region_png(ctx, w, h, ref, mask):
    """The reference image, darkened outside the shadow region."""
    out = []
    mean = sum(ref) / len(ref)
    ex = 0.18 / mean if mean > 0 else 1
    for i in range(w * h):
        k = 1.0 if mask[i] else 0.25
        for c in range(3):
            v = max(0.0, min(1.0, ref[3 * i + c] * ex * k))
            out.append(int(255 * (v ** (1 / 2.2))))
    write_png(ctx.result("img/region.png"), w, h, out)


# --- Table 1 -> table -----------------------------------------------------------

def timing(ctx):
    s = ctx.s
    rows = []
    for m, r in configs(s["table_res"]):
        secs, j = [], None
        for k in range(s["reps"]):
            # The first is the curve run (its error measurements are off
            # the clock); the others are plain runs, always rerun.
            if k == 0:
                _, j = curve_run(ctx, m, r)
            else:
                j = ctx.run(f"time-{m}-{r}-{k}", mask_args(m, r), fresh=True)
            secs.append(j["timings"]["solve_seconds"])
        res = j["result"]
        seed = SEED_MINUTES.get((m, r))
        med = median(secs)
        rows.append([m, "" if m in SINGLE else r, med, min(secs), max(secs), res["shots"],
                     res["rays"], res["mask_rays"], res["bytes_sent"],
                     "" if seed is None else f"{int(seed)}m {round(60 * (seed - int(seed)))}s",
                     "" if seed is None else med / (seed * 60)])
    write_csv(ctx.result("table1-time.csv"),
                  ["method", "mask_res", "median_solve_seconds", "min_seconds", "max_seconds",
                   "shots", "rays", "mask_rays", "bytes_sent", "seed_time",
                   "ratio_to_seed"], rows)


# --- Fig. 3 -> number -----------------------------------------------------------

def leak(ctx):
    s = ctx.s
    ensure_references(ctx)
    region = ShadowRegion()
    seeds = s["ref_seeds"]
    refs = [region_patch_mean(ctx.path(f"ref-b-seed{k}", "patches.csv"), region, True)
            for k in seeds]
    ref_mean = sum(m for m, _ in refs) / len(refs)
    # Beside the patch measure, the same in the image: the mean over the
    # right part's pixels, against (b)'s image and against the ground truth's.
    gt = groundtruth.exp_reference(ctx)
    _, _, rb = read_pfm(ref_b_path(ctx))
    right = region_mask(ctx, load_json(ctx.path(f"ref-b-seed{seeds[0]}", "run.json")), right_only=True)
    if gt is not None:
        right_gt = [k and m for k, m in zip(gt.keep, right)]
        gt_mean = region_mean(gt.px, right_gt)
    b_img = region_mean(rb, right)
    rows = [["reference (b) seed spread", "",
             100 * (refs[1][0] - refs[0][0]) / ref_mean, refs[0][1], "", "", "", "", "",
             "" if gt is None else 100 * (region_mean(rb, right_gt) - gt_mean) / gt_mean]]
    for m, r in configs(s["curve_res"]):
        name, j = curve_run(ctx, m, r)
        mean, area = region_patch_mean(ctx.path(name, "patches.csv"), region, True)
        res = j["result"]
        _, _, img = read_pfm(ctx.path(name, "image.pfm"))
        rows.append([m, "" if m in SINGLE else r, 100 * (mean - ref_mean) / ref_mean, area,
                     res["rays"], res["mask_rays"], res["bytes_sent"],
                     j["timings"]["solve_seconds"], 100 * (region_mean(img, right) - b_img) / b_img,
                     "" if gt is None else 100 * (region_mean(img, right_gt) - gt_mean) / gt_mean])
    write_csv(ctx.result("fig3-leak.csv"),
                  ["method", "mask_res", "leak_percent", "region_area", "rays", "mask_rays",
                   "bytes_sent", "solve_seconds", "image_leak_vs_b_percent",
                   "image_leak_vs_gt_percent"], rows)
    os.makedirs(ctx.result("img"), exist_ok=True)
    name = f"A-{s['leak_res']}"
    shutil.copy(ctx.path(name, "image.png"), ctx.result(f"img/fig3-{name}.png"))
    # Against B at the same R and seed: the same Monte Carlo rays, so what
    # differs is the mask.
    b_name, _ = curve_run(ctx, "B", s["leak_res"])
    w, h, rb = read_pfm(ctx.path(b_name, "image.pfm"))
    _, _, img = read_pfm(ctx.path(name, "image.pfm"))
    j = load_json(ctx.path(name, "run.json"))
    diff_png(ctx.result(f"img/fig3-{name}-diff.png"), w, h, img, rb, 10,
                 region_mask(ctx, j, right_only=True))


# --- error against run time -------------------------------------------------------

def error_time(ctx):
    runs = curve_runs(ctx)
    points, series = [], []
    for name, j in runs:
        header, rows = read_csv(ctx.path(name, "convergence.csv"))
        ix = {k: i for i, k in enumerate(header)}
        data = [(float(r[ix["seconds"]]), float(r[ix["relative_rmse"]]), int(r[ix["shot"]]))
                for r in rows if len(r) > ix["relative_rmse"] and r[ix["relative_rmse"]]]
        dat = ctx.result(f"curves/{name}.dat")
        os.makedirs(os.path.dirname(dat), exist_ok=True)
        with open(dat, "w") as f:
            f.write("# seconds relative_rmse shot\n")
            for t, e, k in data:
                f.write(f"{t:.6f} {e:.9g} {k}\n")
        series.append((name, dat, j))
        points += [(t, e, name) for t, e, _ in data]
    # Pareto front: the lowest error reached by any run within each budget.
    points.sort()
    front, best = [], float("inf")
    for t, e, name in points:
        if e < best:
            best = e
            front.append((t, e, name))
    with open(ctx.result("curves/pareto.dat"), "w") as f:
        f.write("# seconds relative_rmse run\n")
        for t, e, name in front:
            f.write(f"{t:.6f} {e:.9g} {name}\n")
    # The front at round budgets, and which run gives it.
    horizon = max(t for t, _, _ in points)
    budgets = [b for b in (0.5, 1, 2, 5, 10, 20, 50, 100, 200, 500) if b <= horizon * 1.01] + [horizon]
    rows = []
    for b in budgets:
        reach = [p for p in front if p[0] <= b]
        if reach:
            t, e, name = reach[-1]
            rows.append([b, e, name, t])
    # The ground truth: the curves measure against (b) only; beside them, the
    # final image of the same run against the ground truth.
    gt = groundtruth.exp_reference(ctx)
    final_gt = {}
    for name, _, _ in series:
        final_gt[name] = "" if gt is None else gt.error(read_pfm(ctx.path(name, "image.pfm"))[2])
    for r in rows:
        r.append(final_gt[r[2]])
    write_csv(ctx.result("pareto.csv"), ["budget_seconds", "lowest_relative_rmse", "run", "at_seconds",
                                             "run_final_vs_gt"], rows)
    # Per run: the final error, its time, what measuring cost.
    rows = []
    for name, _, j in series:
        rows.append([name, j["result"]["shots"], j["timings"]["solve_seconds"],
                     j["result"]["relative_rmse"], j["result"]["error_measurements"],
                     j["timings"]["error_seconds"], final_gt[name]])
    write_csv(ctx.result("curves.csv"), ["run", "shots", "solve_seconds", "final_relative_rmse",
                                             "error_measurements", "error_seconds", "final_vs_gt"], rows)
    plot_curves(ctx, series)


def plot_curves(ctx, series):
    colours = {"none": "#000000", "A": "#d62728", "B": "#1f77b4", "C": "#2ca02c", "R": "#9467bd"}
    dashes = {}
    plots = []
    for name, dat, _ in series:
        m = name.split("-")[0]
        k = dashes.setdefault(m, 0)
        dashes[m] += 1
        plots.append(f"'{dat}' using 1:2 with lines lw 2 lc rgb '{colours.get(m, '#888888')}' "
                     f"dt {1 + k} title '{name}'")
    front = ctx.result("curves/pareto.dat")
    plots.append(f"'{front}' using 1:2 with steps lw 3 lc rgb '#ff7f0e' title 'Pareto front'")
    png = ctx.result("error-time.png")
    errs = [float(line.split()[1]) for _, dat, _ in series for line in open(dat) if not line.startswith("#")]
    lo, hi = min(errs) / 1.15, max(errs) * 1.15
    step = 10 ** math.floor(math.log10(hi - lo))  # a tick every step, as a list
    ticks = ", ".join(f"'{k * step:g}' {k * step:g}" for k in range(int(lo / step) + 1, int(hi / step) + 1))
    gnuplot(f"""set terminal pngcairo size 900,600 noenhanced font ',11'
set output '{png}'
set logscale xy
set yrange [{lo}:{hi}]
set ytics ({ticks})
set grid
set key outside right
set xlabel 'solve time, seconds (error measuring excluded)'
set ylabel 'relative RMSE against reference (b)'
set title 'Cornell box, 2 environments: error against run time'
plot {', '.join(plots)}
""")


# --- Methods C and R in the closed box ----------------------------------------------

def closed_box(ctx):
    """tools/closed-box-methods (issue #10): a closed box of one
    material around a block, split 2x2x2: mean B against E/(1-rho) over
    several seeds, with its standard error, for none (1 env), B and R."""
    seeds, rays = ("4", "500") if ctx.scale == "full" else ("2", "100")
    env = dict(os.environ, RAYS=rays, VISMASK_BIN=ctx.bin)
    out = subprocess.run([os.path.join(ROOT, "tools", "closed-box-methods"),
                          os.path.join(ctx.runs, "closed-box"), seeds], env=env, check=True,
                         capture_output=True, text=True).stdout
    with open(ctx.result("closed-box.csv"), "w") as f:
        f.write(out)


# --- docs/RESULTS.md --------------------------------------------------------------

def table_md(path, header_map=None, digits=None):
    header, rows = read_csv(path)
    names = [header_map.get(h, h) if header_map else h for h in header]
    out = ["| " + " | ".join(names) + " |", "|" + "---|" * len(names)]
    for r in rows:
        cells = []
        for h, v in zip(header, r):
            cells.append(pretty(v, h))
        out.append("| " + " | ".join(cells) + " |")
    return "\n".join(out)


def pretty(v, h):
    try:
        x = float(v)
    except ValueError:
        return v
    if v.isdigit():
        return f"{int(v):,}".replace(",", " ")
    if h.startswith("mean_b") or h == "std_error":
        return f"{x:.6f}"
    if "percent" in h:
        return f"{x:+.1f}%"
    if h in groundtruth.POINTS:
        return f"{100 * x:+.2f} pt"
    if "rmse" in h or h.startswith("vs_") or h.startswith("noise") or h in groundtruth.PERCENT:
        return f"{100 * x:.3f}%"
    if "ratio" in h:
        return f"{x:.2e}"
    return f"{x:.3g}"


def rows_of(ctx, f):
    header, rows = read_csv(ctx.result(f))
    return [dict(zip(header, r)) for r in rows]


def report(ctx, meta=None):
    s = ctx.s
    # The run's facts, kept from `all` so that the report can be remade alone.
    meta_path = ctx.result("meta.json")
    if meta:
        with open(meta_path, "w") as f:
            json.dump(meta, f, indent=1)
    elif os.path.exists(meta_path):
        meta = load_json(meta_path)
    meta = meta or {}
    doc = os.path.join(os.path.dirname(ctx.out), "RESULTS.md") if ctx.out.endswith(
        os.path.join("docs", "results")) else os.path.join(ctx.out, "RESULTS.md")
    rel = os.path.relpath(ctx.out, os.path.dirname(doc))
    link = lambda f: f"{rel}/{f}" if rel != "." else f

    q = rows_of(ctx, "fig2-quality.csv")
    t = rows_of(ctx, "table1-time.csv")
    lk = rows_of(ctx, "fig3-leak.csv")
    pareto = rows_of(ctx, "pareto.csv")
    ref = rows_of(ctx, "references.csv")[0]
    pct = lambda x: f"{100 * float(x):.2f}%"
    floor = q[-1]
    by_r = {r["mask_res"]: r for r in q}
    tm = {(r["method"], r["mask_res"]): float(r["median_solve_seconds"]) for r in t}
    none_s = tm[("none", "")]
    leak_of = {(r["method"], r["mask_res"]): float(r["leak_percent"]) for r in lk}
    spread = abs(float(lk[0]["leak_percent"]))
    hi = str(s["leak_res"])

    L = []
    w = L.append
    w("# Results: the paper's figures and table as numbers\n")
    w("Generated by `make experiments` (tools/experiments); every figure below comes from "
      "that run. Do not edit by hand.\n")
    if meta:
        w(f"- command: `{meta.get('command', 'tools/experiments')}`, scale `{ctx.scale}`")
        w(f"- commit {meta.get('commit', '?')}, {meta.get('date', '?')}")
        w(f"- machine: {meta.get('cpu', '?')}, {meta.get('cores', '?')} cores; load average "
          f"{meta.get('load_start', '?')} at the start, {meta.get('load_end', '?')} at the end")
        w(f"- wall time of the whole run: {meta.get('seconds', 0):.0f} s\n")
    common = " ".join(s["common"])
    w("## Set-up\n")
    w(f"The Cornell box (scenes/cornell.obj) split into two environments at x = 278 (`--envs 2`), "
      f"rendered with `{common}` unless a row says otherwise. Times are `solve_seconds` from run.json: "
      "the solve alone, without init, output, or the error measurements of `--error-every` "
      "(their cost is in the last table).\n")
    w("**References.** (a) the paper's: Method B at R = "
      f"{s['ref_res']}, two environments, the same settings. (b) a converged single-environment "
      "solution (no masks): " + ref["what"] + ". Its own noise is estimated from the two seeds: "
      "two independent solves differ by √2 σ, so one has σ = RMSE(seed 1, seed 2)/√2 and their "
      "mean σ/√2 = RMSE/2.\n")
    w(table_md(ctx.result("references.csv")) + "\n")
    lowest = min(float(r["vs_ref_b_whole"]) for r in q if r["vs_ref_b_whole"])
    w(f"Reference (b)'s noise, {pct(ref['noise_whole'])} over the image and "
      f"{pct(ref['noise_region'])} in the shadow region, against the smallest difference measured "
      f"against it below, {pct(lowest)}: "
      + ("well below (under a third)." if float(ref["noise_whole"]) < lowest / 3 else
         "NOT well below: the differences against (b) below include its noise.") + "\n")
    gtx = ctx.result("gt-experiments.csv")
    if os.path.exists(gtx):
        x = rows_of(ctx, "gt-experiments.csv")[0]
        w("**Ground truth (c)**, a path-traced reference of the same view (issue 15): "
          f"{x['what']}; its own noise {pct(x['noise'])} (from its two halves; a measured error "
          "cannot fall below it). The pixels that see the emitter are left out of every comparison "
          "with it (its mask). Reference (b) against it: "
          f"{pct(x['ref_b_vs_gt_whole'])} over the image, {pct(x['ref_b_vs_gt_region'])} in the "
          f"shadow region, {pct(x['ref_b_vs_gt_right'])} in its right part. The `vs_gt` columns "
          "below are against (c), beside those against (b).\n")
    else:
        w("**Ground truth (c)**: not made (blender not found; tools/install-deps --reference "
          "installs it): the `vs_gt` columns below are empty.\n")
    w("**The shadow region** (below, bright): the points of the floor and back wall from which at "
      "least one of 5 × 5 points spread over the light is hidden by the tall block (umbra and "
      "penumbra), as seen from the camera: the pixels whose visible surface is such a point. The "
      "right environment's part is its x < 278 side (the image's right half looks at x < 278).\n")
    w(f"![shadow region]({link('img/region.png')})\n")

    w("## Fig. 2 → table: quality against mask resolution (Method B)\n")
    w(table_md(ctx.result("fig2-quality.csv")) + "\n")
    w("Relative RMSE = √(Σ(a−b)²/Σb²) over all channels of the pixels: the whole image, the shadow "
      "region, or its part in the second environment (`right`, x < 278). "
      "The last row is the noise floor of any comparison between two two-environment runs: the "
      "lowest R again with another seed.\n")
    imgs = " ".join(f"![B R={r}]({link(f'img/fig2-B-{r}.png')})" for r in s["table_res"] + [s["ref_res"]])
    w("Images, R = " + ", ".join(str(r) for r in s["table_res"]) + f" and reference (a), R = {s['ref_res']}:\n")
    w(imgs + "\n")
    w("|x − reference (a)| (same seed: what differs is the mask; black = equal, white = 10% of the "
      "image's mean), the shadow region outlined in blue:\n")
    w(" ".join(f"![diff R={r}]({link(f'img/fig2-B-{r}-diff.png')})" for r in s["table_res"] + [s["ref_res"]]) + "\n")

    w("## Table 1 → table: time of Method A and Method B\n")
    w(table_md(ctx.result("table1-time.csv")) + "\n")
    w(f"Median of {s['reps']} runs each (min and max beside it), one after another on this machine; "
      "the first of each is the error-curve run below, whose measurements are off its clock. "
      "`mask_rays` are Method B's centre rays; `bytes_sent` the packet bytes (128-byte header and "
      "the mask) sent between the environments. `seed_time` is the paper's Table 1 and `ratio_to_seed` our median time over it.\n")

    w("## Fig. 3 → number: light leaking through Method A's masks\n")
    w(table_md(ctx.result("fig3-leak.csv")) + "\n")
    w("`leak_percent`: the area-weighted mean radiosity of the patches in the right environment's "
      "shadow region (patch centre in the region, x < 278), above reference (b)'s, in percent "
      "(power received = mean radiosity × area). The first row is the difference between reference "
      "(b)'s two seeds: the noise of this measure.\n")
    w("`image_leak_vs_b_percent` and `image_leak_vs_gt_percent`: the same in the image, the mean "
      "of the pixels in the right environment's part of the shadow region above reference (b)'s "
      "image and above the ground truth (c)'s; in the first row, (b)'s image above (c)'s.\n")
    w(f"Method A at R = {hi}, and |A − B| at R = {hi} with the same seed (what differs is the mask; "
      "white = 10% of the image's mean), the right environment's part of the shadow region outlined "
      "in blue:\n")
    w(f"![A R={hi}]({link(f'img/fig3-A-{hi}.png')}) ![A R={hi} diff]({link(f'img/fig3-A-{hi}-diff.png')})\n")

    w("## Error against run time\n")
    w(f"Every curve run measured its image against reference (b) every {s['error_every']} shots "
      "(`--reference`, `--error-every`).\n")
    w(f"![error against time]({link('error-time.png')})\n")
    w("The Pareto front: the lowest error any run had reached within each time budget. The curves "
      "are against reference (b); `run_final_vs_gt` is the final image of the run named in that "
      "row against the ground truth (c) (`final_vs_gt` in the last table).\n")
    w(table_md(ctx.result("pareto.csv")) + "\n")
    w("What measuring cost (not in the solve times):\n")
    w(table_md(ctx.result("curves.csv")) + "\n")

    w("## Beyond the paper: Methods C and R\n")
    w("Method C marks, per pixel, whether a form-factor ray hit or passed, and casts B's centre ray "
      "only where the marks disagree or no ray came; Method R sends one bit per Monte Carlo ray "
      "(docs/DESIGN.md). From the curve runs above (one run each):\n")
    by = {(r["method"], r["mask_res"]): r for r in lk}
    cmp_rows = ["| R | B mask rays | C mask rays | C / B | B leak | C leak | B s | C s |",
                "|---|---|---|---|---|---|---|---|"]
    for r in s["curve_res"]:
        b, c = by.get(("B", str(r))), by.get(("C", str(r)))
        if b and c:
            cmp_rows.append(f"| {r} | {num(b['mask_rays'])} | {num(c['mask_rays'])} | "
                            f"{int(c['mask_rays']) / max(1, int(b['mask_rays'])):.2f} | "
                            f"{float(b['leak_percent']):+.1f}% | {float(c['leak_percent']):+.1f}% | "
                            f"{float(b['solve_seconds']):.1f} | {float(c['solve_seconds']):.1f} |")
    w("\n".join(cmp_rows) + "\n")
    rr = by.get(("R", ""))
    if rr:
        n = int(arg(s["common"], "--rays"))
        w(f"Method R: leak {float(rr['leak_percent']):+.1f}%, {num(rr['bytes_sent'])} bytes sent "
          f"({num(rr['rays'])} rays traced, no mask rays), {float(rr['solve_seconds']):.1f} s. Its "
          "packet is 128 + N/8 bytes for N rays a shot, a mask's 128 + 4R²/8: here N = "
          f"{n}, so R's packet is the size of a mask of R = {math.sqrt(n / 4):.0f}, smaller than "
          "the masks above it and larger than those below.\n")
    if os.path.exists(ctx.result("closed-box.csv")):
        w("**The closed box** (tools/closed-box-methods): a unit cube around a block "
          "[0.3, 0.7]³, one material (kd 0.5, Ke 2, so B = 4 everywhere), split 2×2×2; the mean of B "
          "over the patches against 4, with its standard error over the seeds, the noise of one "
          "patch (RMS), and the ledger's largest residual (emitted − absorbed − escaped − unshot − "
          "in flight, over emitted). A closed box of one material fixes the mean by conservation, "
          "so a bias beyond the standard error is rays lost or counted twice.\n")
        w(table_md(ctx.result("closed-box.csv")) + "\n")

    groundtruth.report_section(ctx, w, link, table_md)

    w("## Reading\n")
    res = [str(r) for r in s["table_res"]]
    r_lo, r_hi = res[0], res[-1]
    fl = float(floor["vs_ref_a_right"])

    def vs(r):
        return float(by_r[r]["vs_ref_a_right"])
    w("- **Quality against resolution (Fig. 2).** In the second environment's part of the shadow "
      "region, where the occluder (the tall block) is in the shooter's environment and only the mask "
      "stands for it, Method B differs from "
      "reference (a) by " + ", ".join(f"{pct(vs(r))} at R = {r}" for r in res) +
      f". Every run uses seed 1, so their Monte Carlo noise is largely shared (common random "
      f"numbers) and these differences are mostly the masks'; two runs that differ only in their "
      f"seed differ by {pct(fl)}. " +
      ("So the paper's ordering holds: the error falls with R and R = "
       f"{r_hi} is within the noise of R = {s['ref_res']}." if vs(r_lo) > vs(r_hi) and vs(r_hi) <= 1.2 * fl
       else "The paper's ordering does not show clearly above the Monte Carlo noise here.")
      + " Over the whole image the mask's effect is swamped by that noise: the shadow edge is a "
      "small part of the picture.")
    ratio = [tm[("B", int_or(r))] / tm[("A", int_or(r))] for r in s["table_res"]]
    seed_ratio = [SEED_MINUTES[("B", r)] / SEED_MINUTES[("A", r)]
                  for r in s["table_res"] if ("B", r) in SEED_MINUTES]
    b_slower = all(x > 1.0 for x in ratio)
    w(f"- **Time (Table 1).** Method A costs {fmt_pct(tm[('A', int_or(r_lo))] / none_s - 1)} to "
      f"{fmt_pct(tm[('A', int_or(r_hi))] / none_s - 1)} over no mask (marking, packing, sending, "
      "merging and reading the masks). Method B's time over A's is " +
      ", ".join(f"{x:.2f}×" for x in ratio) + " at R = " + ", ".join(str(r) for r in s["table_res"]) +
      ("; in the paper it was " + ", ".join(f"{x:.2f}×" for x in seed_ratio) + ". "
       if seed_ratio else " (the paper has no times at these R). ") +
      ("Here B is the slower at every R: the paper's A paid for wasteful marking (\"pixels may be "
       "marked off multiple times\"), which here is one bit write per ray that hits, while B's one "
       "extra ray per open pixel (4R² per shot that sends a mask) outweighs it. The paper's finding "
       "that B is faster does not carry over; its finding that B's cost grows with R does."
       if b_slower else "B is not the slower at every R here; see the table."))
    a_hi, b_hi = leak_of.get(("A", hi)), leak_of.get(("B", hi))
    if a_hi is not None and b_hi is not None:
        w(f"- **Leak (Fig. 3).** At R = {hi}, Method A puts {a_hi:+.1f}% more light in the right "
          f"environment's shadow than reference (b); Method B {b_hi:+.1f}%; the reference's own "
          f"seed-to-seed spread is {spread:.1f}%. " +
          ("The paper's light leak is reproduced and measured." if a_hi > max(3 * spread, b_hi + 3 * spread)
           else "The leak is not clearly above the noise at this scale."))
    cs = [(r, by.get(("B", str(r))), by.get(("C", str(r)))) for r in s["curve_res"]]
    cs = [(r, b, c) for r, b, c in cs if b and c]
    if cs:
        fewer = [r for r, b, c in cs if int(c["mask_rays"]) < int(b["mask_rays"])]
        leak_gap = max(abs(float(c["leak_percent"]) - float(b["leak_percent"])) for _, b, c in cs)
        darker = all(float(c["leak_percent"]) <= float(b["leak_percent"]) + spread for _, b, c in cs)
        w(f"- **Method C** cast fewer centre rays than B at R = {', '.join(str(r) for r in fewer) or 'none'} "
          f"(C/B from {min(int(c['mask_rays']) / max(1, int(b['mask_rays'])) for _, b, c in cs):.2f} to "
          f"{max(int(c['mask_rays']) / max(1, int(b['mask_rays'])) for _, b, c in cs):.2f}; the saving "
          "shrinks as R grows, because pixels then outnumber the rays and most get no mark). Its leak "
          f"differs from B's by at most {leak_gap:.1f} points, against the reference's seed spread of "
          f"{spread:.1f}%" + (": no leak beyond B's; where it differs it is darker (a pixel whose "
                              "rays all hit is closed, even where its centre ray would pass)."
                              if darker else "; at some R it lets more light through than B."))
    if rr:
        line = (f"- **Method R** has {float(rr['leak_percent']):+.1f}% in the same region (the "
                f"reference's seed spread is {spread:.1f}%): it has no mask; every ray is traced "
                "until it is absorbed in exactly one environment or escapes.")
        curves = {r["run"]: r for r in rows_of(ctx, "curves.csv")}
        if "R" in curves and f"B-{hi}" in curves:
            line += (f" Its whole-image error, {pct(curves['R']['final_relative_rmse'])} against "
                     f"B-{hi}'s {pct(curves[f'B-{hi}']['final_relative_rmse'])}, is most likely noise (the "
                     "region and the closed box show no bias): R traces "
                     "each ray once, so the second environment receives only the rays that reach "
                     "it, where the other methods draw --rays fresh rays in every environment.")
        if os.path.exists(ctx.result("closed-box.csv")):
            cb = {r["method"]: r for r in rows_of(ctx, "closed-box.csv")}
            if "R" in cb and "B" in cb:
                f = lambda r: (f"{float(r['mean_b_over_analytic']):.6f} ± {float(r['std_error']):.6f} "
                               f"(ledger residual {float(r['max_ledger_residual']):.2g})")
                line += (f" In the closed box split 2×2×2 its mean B over the analytic value is "
                         f"{f(cb['R'])}, B's {f(cb['B'])}, one environment's {f(cb['none'])}.")
        w(line)
    if pareto:
        names = []
        for p in pareto:
            if p["run"] not in names:
                names.append(p["run"])
        curves = rows_of(ctx, "curves.csv")
        best = min(curves, key=lambda r: float(r["final_relative_rmse"]))
        w(f"- **Error against time.** The Pareto front is made of {', '.join(names)}: at each "
          "budget, the lowest whole-image error any run had reached came from these. The lowest "
          f"final error is {best['run']}'s, {pct(best['final_relative_rmse'])} after "
          f"{float(best['solve_seconds']):.1f} s; the final errors range from "
          f"{pct(min(float(r['final_relative_rmse']) for r in curves))} to "
          f"{pct(max(float(r['final_relative_rmse']) for r in curves))}, against reference (b)'s "
          f"own noise of {pct(ref['noise_whole'])}.")
    groundtruth.reading(ctx, w)
    w("")
    with open(doc, "w") as f:
        f.write("\n".join(L) + "\n")
    log(f"wrote {doc}")
    return doc


def num(v):
    return f"{int(v):,}".replace(",", " ")


def int_or(r):
    try:
        return str(int(r))
    except (TypeError, ValueError):
        return r


def fmt_pct(x):
    return f"{100 * x:+.0f}%"


# --- all ----------------------------------------------------------------------------

def meta_info(ctx, start, load_start):
    f = facts()
    return dict(command="make experiments" if ctx.scale == "full" else "tools/experiments --quick",
                commit=f["commit"], date=f["date"], cpu=f["cpu"], cores=f["cores"],
                load_start=load_start, load_end=loadavg(), seconds=time.time() - start)


STEPS = {"references": references, "quality": quality, "timing": timing, "leak": leak,
         "error-time": error_time, "closed-box": closed_box,
         "ground-truth": groundtruth.ground_truth, "report": report}


ORDER = ["references", "quality", "leak", "error-time", "timing", "closed-box", "ground-truth"]


def main(argv, doc):
    """tools/experiments [STEP...] [--quick] [--out DIR]: the steps named, or
    all of them and the report ('all', the default)."""
    args = parse(argv, doc, positional=len(STEPS) + 1)
    steps = args.positional or ["all"]
    for s in steps:
        if s != "all" and s not in STEPS:
            print(f"{argv[0]}: unknown step '{s}' (steps: all, {', '.join(STEPS)})", file=sys.stderr)
            sys.exit(2)
    ctx = context(args)
    if steps != ["all"]:
        for s in steps:
            STEPS[s](ctx)
        return
    start = time.time()
    load_start = loadavg()
    # Every figure from this run: no run is reused from an earlier one.
    shutil.rmtree(ctx.runs, ignore_errors=True)
    os.makedirs(ctx.runs)
    for name in ORDER:
        t0 = time.time()
        log(f"experiments: {name}")
        STEPS[name](ctx)
        log(f"experiments: {name} done in {time.time() - t0:.0f} s")
    report(ctx, meta_info(ctx, start, load_start))
