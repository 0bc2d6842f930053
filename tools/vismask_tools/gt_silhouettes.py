"""The ground-truth step's silhouette part (issue 41): vismask against the
Cycles ground truth at the original camera with the emitter's pixels left out
(REF.mask.pgm) and with the 1-px silhouettes left out as well
(tools/silhouette-mask, run as a command since it needs numpy): `--max-seconds
T` at otherwise default options, and the fixed settings of the
error-against-time runs; and RenderPark (rpkCpp's hierarchical Galerkin, by
tools/renderpark-run) when make renderpark has built it. Writes
gt-silhouette-mask.csv, gt-silhouettes.csv, gt-renderpark-measured.csv and
gt-renderpark-vs.csv."""

import os
import statistics
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
    keep, mask_rows = silhouette_keep(ctx, ref)
    write_csv(ctx.result("gt-silhouette-mask.csv"), ["left_out", "pixels", "fraction"], mask_rows)
    fixed_rows, fixed_cpu = [], []
    for name, args in fixed:
        if "--max-seconds" in args:
            continue
        j = load_json(ctx.path("gt-" + name, "run.json"))
        img = image(ctx, name)
        fixed_rows.append([name, " ".join(args) or "(defaults)", "", j["timings"]["solve_seconds"],
                           j["result"]["stop_reason"], j["result"]["shots"], ref.error(img),
                           ref.error(img, keep)])
        fixed_cpu.append(j["result"]["compute_cpu_seconds"])
    rows, rpk_rows = interleaved(ctx, ref, keep, run, image)
    # The anytime goal: within 1.25x of the best fixed setting whose solve
    # finished within T (emitter mask).
    for r in rows:
        best = [f for f in fixed_rows if f[3] <= r[2]]
        b = min(best, key=lambda f: f[6]) if best else None
        r[8:8] = ["" if b is None else b[0], "" if b is None else b[6],
                  "" if b is None else r[6] / b[6]]
    for f, cpu in zip(fixed_rows, fixed_cpu):
        f += ["", "", "", cpu, 1, "", ""]
    write_csv(ctx.result("gt-silhouettes.csv"),
              ["run", "options", "max_seconds", "solve_seconds", "stop", "shots", "vs_gt",
               "vs_gt_no_silhouettes", "best_fixed_within", "best_fixed_vs_gt",
               "anytime_over_best_fixed", "cpu_seconds", "reps", "vs_gt_range", "run_order"],
              rows + fixed_rows)
    if rpk_rows:
        write_csv(ctx.result("gt-renderpark-measured.csv"), ["renderpark", "options", "cpu_seconds", "vs_gt", "vs_gt_no_silhouettes",
                        "reps", "vs_gt_range", "run_order"], rpk_rows)
        write_csv(ctx.result("gt-renderpark-vs.csv"),
                  ["budget", "vismask_run", "vismask_cpu_seconds", "vismask_no_silhouettes",
                   "renderpark_within", "renderpark_cpu_seconds", "renderpark_no_silhouettes",
                   "below_renderpark", "issue_quoted", "below_issue_quoted"],
                  against_renderpark(rows, rpk_rows, ctx.s["gt"].get("vs_from", 0.3)))


# Issue 41's RenderPark figures without the 1-px silhouettes (quoted, by budget).
ISSUE_QUOTED = {0.3: 0.0166, 1: 0.0127, 10: 0.0102, 30: 0.0099}


def against_renderpark(rows, rpk_rows, first):
    """Issue 41's comparison without the 1-px silhouettes, at each
    `--max-seconds` budget T from `first` (the issue's: 0.3 s): vismask's
    anytime-T row (`rows`: gt-silhouettes.csv's, the best-fixed columns
    in) against RenderPark's best setting whose CPU seconds (the median of
    its repetitions) were at most T, the issue's own comparison by budget
    ("none" where no setting finished within T), and against the figure the
    issue quotes for T."""
    out = []
    for r in rows:
        T = r[2]
        if T < first:
            continue
        within = [k for k in rpk_rows if k[2] <= T]
        b = min(within, key=lambda k: k[4]) if within else None
        q = ISSUE_QUOTED.get(T)
        out.append([f"{T:g}", r[0], r[11], r[7], "none" if b is None else b[1],
                    "" if b is None else b[2], "" if b is None else b[4],
                    "" if b is None else ("yes" if r[7] < b[4] else "NO"),
                    "" if q is None else q, "" if q is None else ("yes" if r[7] < q else "NO")])
    return out


def median_rep(reps):
    """The rep whose vs_gt is the median (the lower middle of an even count),
    with how many there were, their vs_gt range and their places in the
    run order, as the row's last three cells."""
    by = sorted(reps, key=lambda r: r["vs_gt"])
    m = by[(len(by) - 1) // 2]
    return m, [len(by), f"{100 * by[0]['vs_gt']:.3f}-{100 * by[-1]['vs_gt']:.3f}%",
               ";".join(str(r["order"]) for r in reps)]


def interleaved(ctx, ref, keep, run, image):
    """`--max-seconds T` at otherwise default options and RenderPark at each
    of gt.rpk's option lists, run by turns (vismask's i-th budget, then
    RenderPark's i-th setting, then the next of each), the whole sequence
    gt.reps times, so that both see the machine's load alike. Each row is
    its median repetition by vs_gt. Returns the anytime rows (their best-fixed
    columns still to insert at 8) and RenderPark's (empty, with a note
    written, when it is not built)."""
    g = ctx.s["gt"]
    out, note = ctx.result("gt-renderpark-measured.csv"), ctx.result("gt-renderpark-skipped.txt")
    for p in (out, note, ctx.result("gt-renderpark-vs.csv")):
        if os.path.exists(p):
            os.remove(p)
    rpk = rpk_binary()
    if rpk is None:
        with open(note, "w") as f:
            f.write("RenderPark not built (make renderpark RPK_SRC=DIR, a checkout of "
                    "github.com/OscarChavarro/rpkCpp 37e5ff4e; or RPK_BIN=BINARY)\n")
        log("experiments: RenderPark not built, its measured rows skipped")
    budgets, settings = g["anytime"], (g["rpk"] if rpk else [])
    vm = [[] for _ in budgets]
    rp = [[] for _ in settings]
    order = 0
    for rep in range(g.get("reps", 1)):
        for i in range(max(len(budgets), len(settings))):
            if i < len(budgets):
                order += 1
                vm[i].append(dict(order=order, **anytime_run(ctx, ref, keep, run, image,
                                                             budgets[i], rep)))
            if i < len(settings):
                order += 1
                rp[i].append(dict(order=order, **renderpark_run(ctx, ref, keep, rpk, i,
                                                                settings[i], rep)))
    rows = []
    for T, reps in zip(budgets, vm):
        m, tail = median_rep(reps)
        rows.append([m["name"], m["options"], T, m["solve_seconds"], m["stop"], m["shots"],
                     m["vs_gt"], m["vs_gt_no_silhouettes"], m["cpu_seconds"]] + tail)
    rpk_rows = []
    for opts, reps in zip(settings, rp):
        m, tail = median_rep(reps)
        cpu = statistics.median_low(r["cpu_seconds"] for r in reps)  # median_rep's middle
        rpk_rows.append(["rpkCpp hierarchical Galerkin", " ".join(opts), cpu,
                         m["vs_gt"], m["vs_gt_no_silhouettes"]] + tail)
    return rows, rpk_rows


def anytime_run(ctx, ref, keep, run, image, T, rep):
    """One `--max-seconds T` run (repetition rep: the first keeps the name
    anytime-T, the others get -repN)."""
    args = ctx.s["gt"]["default"] + ["--max-seconds", f"{T:g}"]
    name = f"anytime-{T:g}s" + (f"-rep{rep + 1}" if rep else "")
    j = run(ctx, name, args, ref)
    img = image(ctx, name)
    return dict(name=name, options=" ".join(args), solve_seconds=j["timings"]["solve_seconds"],
                stop=j["result"]["stop_reason"], shots=j["result"]["shots"],
                cpu_seconds=j["result"]["compute_cpu_seconds"], vs_gt=ref.error(img),
                vs_gt_no_silhouettes=ref.error(img, keep))


def renderpark_run(ctx, ref, keep, rpk, k, opts, rep):
    """rpkCpp at one option list: its CPU seconds (its own last "CPU time"
    line) and errors."""
    pfm = os.path.join(ctx.runs, "gt", f"renderpark-{k}" + (f"-rep{rep + 1}" if rep else "") + ".pfm")
    cmd = [os.path.join(ROOT, "tools", "renderpark-run"), "render", "--rpk", rpk, SCENE,
           "--camera", ORIGINAL, "--size", str(ref.w), str(ref.h), "--out", pfm, "--"] + opts
    log("  " + " ".join(os.path.relpath(c, ROOT) if c.startswith(ROOT) else c for c in cmd))
    r = subprocess.run(cmd, check=True, capture_output=True, text=True)
    img = read_pfm(pfm)[2]
    return dict(cpu_seconds=float(r.stdout.split("CPU time ")[1].split()[0]), vs_gt=ref.error(img),
                vs_gt_no_silhouettes=ref.error(img, keep))


def rpk_binary():
    """$RPK_BIN, else make renderpark's build/renderpark/build/rpk, or None."""
    b = os.environ.get("RPK_BIN") or os.path.join(ROOT, "build", "renderpark", "build", "rpk")
    return b if os.access(b, os.X_OK) else None
