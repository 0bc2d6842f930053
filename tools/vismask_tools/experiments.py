"""The experiment steps of issue #6 (see docs/RESULTS.md). Each step runs
what it needs (runs are cached by their command line under the runs
directory) and writes its CSV tables and images into the results directory.
Run them with tools/experiments [STEP...] [--quick] [--out DIR]: references,
quality, timing, leak, error-time, closed-box, ground-truth, sun, room,
report, or all (the default)."""

import math
import os
import shutil
import subprocess
import sys
import time

from . import ROOT, groundtruth, room_step, sun_step
from .cli import parse
from .cornell import ShadowRegion, region_patch_mean
from .files import load_json, read_csv, read_pfm, write_csv, write_png
from .gt_references import exp_reference
from .images import average_pfm, diff_png, rel_rmse
from .machine import facts, loadavg
from .plot import gnuplot
from .results_report import report
from .runner import log
from .scales import SEED_MINUTES, SPLIT, context
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
    gt = exp_reference(ctx)
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
    gt = exp_reference(ctx)
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
    gt = exp_reference(ctx)
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


# --- all ----------------------------------------------------------------------------

def meta_info(ctx, start, load_start, commit):
    """The run's facts; `commit` as taken at the start, the code the runs used."""
    f = facts()
    return dict(command="make experiments" if ctx.scale == "full" else "tools/experiments --quick",
                commit=commit, date=f["date"], cpu=f["cpu"], cores=f["cores"],
                load_start=load_start, load_end=loadavg(), seconds=time.time() - start)


STEPS = {"references": references, "quality": quality, "timing": timing, "leak": leak,
         "error-time": error_time, "closed-box": closed_box,
         "ground-truth": groundtruth.ground_truth, "sun": sun_step.sun, "room": room_step.room,
         "report": report}


ORDER = ["references", "quality", "leak", "error-time", "timing", "closed-box", "ground-truth",
         "sun", "room"]


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
    commit = facts()["commit"]
    # Every figure from this run: no run is reused from an earlier one.
    shutil.rmtree(ctx.runs, ignore_errors=True)
    os.makedirs(ctx.runs)
    for name in ORDER:
        t0 = time.time()
        log(f"experiments: {name}")
        STEPS[name](ctx)
        log(f"experiments: {name} done in {time.time() - t0:.0f} s")
    report(ctx, meta_info(ctx, start, load_start, commit))
