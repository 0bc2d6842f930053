"""Error against a path-traced ground truth (issue 15): the 'ground-truth' step
of the experiments (runs at the original camera against its reference,
tables gt-*.csv, plots and difference images). The references are in
gt_references.py, the report's section in gt_report.py. Python 3 standard
library only."""

import math
import os

from .files import load_json, read_csv, read_pfm, write_csv as write_csv_, write_png
from .gt_references import ORIGINAL, demo_reference, have_blender, original_reference
from .gt_silhouettes import silhouettes
from .images import rel_rmse
from .plot import gnuplot
from .runner import log
from .scales import arg

# Issue 15's configurations. "today" is the render before issue 15.
TODAY = ["--rays", "4096", "--sampler", "random", "--elements", "0", "--aa", "off"]


def today(ctx):
    # Before issue 15 the automatic patch size was extent/16: 34.95 here.
    patch = ["--patch-size", "34.95"] if ctx.scale == "full" else []
    return ["--rays", str(ctx.s["gt"]["today_rays"])] + TODAY[2:] + patch


def configs(ctx):
    """Issue 15's configurations; at quick scale "default" is made cheaper."""
    d = ctx.s["gt"]["default"]
    return [("today", today(ctx)), ("default", d), ("elements-0", d + ["--elements", "0"]),
            ("aa-off", d + ["--aa", "off"])]

# RenderPark on this machine (issue 15): quoted, not rerun.
RENDERPARK = [("hierarchical Galerkin", 0.12, 0.038), ("hierarchical Galerkin", 0.67, 0.036),
              ("stochastic Jacobi (linear basis)", 1.7, 0.051)]

# The goals of issue 15.
GOAL_1S, GOAL_10S, GOAL_RATIO, GOAL_DEMO, GOAL_DEMO_S, GOAL_ENVS = 0.03, 0.02, 2.0, 0.025, 10.0, 0.003


# Columns of the ground-truth tables shown as percentages (results_report.pretty), and
# as differences in percentage points.
PERCENT = {"vs_gt_minus_ref_noise", "noise_seed", "total_vs_gt", "aa_off_vs_on", "aliasing",
           "ref_noise", "discretisation", "renderpark_vs_gt", "vismask_front_vs_gt",
           "max_abs_at_seam", "mean_abs_elsewhere", "final_vs_gt", "run_final_vs_gt",
           "minus_ref_noise_percent", "vismask_no_silhouettes", "renderpark_no_silhouettes",
           "issue_quoted"}
POINTS = {"minus_1_env_points", "step_left_minus_right"}


def write_csv(path, header, rows):
    """files.write_csv with no comma inside a cell (files.read_csv splits on them)."""
    write_csv_(path, header, [[c.replace(",", ";") if isinstance(c, str) else c for c in r]
                                 for r in rows])


# --- runs --------------------------------------------------------------------------

def gt_common(ctx, camera=ORIGINAL):
    size = str(ctx.s["gt"]["size"])
    return (["--camera", camera] if camera else []) + ["--width", size, "--height", size] + ctx.s["gt"]["common"]


def run(ctx, name, args, ref, every=None, camera=ORIGINAL):
    extra = ref.args() + (["--error-every", str(every)] if every else [])
    return ctx.run("gt-" + name, list(args) + extra, common=gt_common(ctx, camera))


def image(ctx, name):
    return read_pfm(ctx.path("gt-" + name, "image.pfm"))[2]


def verdict(ok):
    return "met" if ok else "NOT met"


def in_quadrature(total, *parts):
    """sqrt(total^2 - sum parts^2), and whether it was clamped at 0."""
    r = total * total - sum(p * p for p in parts)
    return (math.sqrt(r), False) if r >= 0 else (0.0, True)


def curve(ctx, name):
    header, rows = read_csv(ctx.path("gt-" + name, "convergence.csv"))
    ix = {k: i for i, k in enumerate(header)}
    return [(float(r[ix["seconds"]]), float(r[ix["relative_rmse"]]))
            for r in rows if len(r) > ix["relative_rmse"] and r[ix["relative_rmse"]]]


def signed_png(path, w, h, a, b, keep, scale):
    """(a - b) averaged over the channels, over b's mean: red where a is
    brighter, blue where darker, white where equal, full colour at +-scale;
    excluded pixels grey."""
    n = sum(keep)
    mean = sum(b[3 * i + c] for i in range(w * h) if keep[i] for c in range(3)) / (3 * max(1, n))
    out = []
    for i in range(w * h):
        if not keep[i]:
            out += [128, 128, 128]
            continue
        d = sum(a[3 * i + c] - b[3 * i + c] for c in range(3)) / 3 / mean / scale
        v = max(-1.0, min(1.0, d))
        k = int(255 * (1 - abs(v)))
        out += [255, k, k] if v > 0 else [k, k, 255]
    write_png(path, w, h, out)


# --- the step -----------------------------------------------------------------------

def ground_truth(ctx):
    """Error against the Cycles ground truth at the original camera: error
    against solve time, the goals, a decomposition, difference images, and
    two environments against one. Writes gt-*.csv, gt-*.png, img/gt-*.png."""
    skip = ctx.result("gt-skipped.txt")
    if os.path.exists(skip):
        os.remove(skip)
    if not have_blender():
        with open(skip, "w") as f:
            f.write("blender not found: the ground-truth section was skipped "
                    "(tools/install-deps --reference installs it)\n")
        log("experiments: blender not found, ground-truth section skipped")
        return
    g = ctx.s["gt"]
    ref = original_reference(ctx)
    os.makedirs(ctx.result("img"), exist_ok=True)
    refs = [["original", ref.what, g["size"], ref.noise, sum(1 for k in ref.keep if not k)]]

    # Error against solve time: a curve per setting. A first run with seed 2
    # (the noise partner) counts the shots; the curve run (seed 1) then
    # measures its error about `points` times.
    settings = [("today", today(ctx)), ("default", g["default"])] + [(n, list(a)) for n, a in g["settings"]]
    rows, series = [], []
    for name, args in settings:
        j2 = run(ctx, name + "-seed2", args + ["--seed", "2"], ref)
        every = max(1, j2["result"]["shots"] // g["points"])
        j = run(ctx, name, args, ref, every)
        e, noise = j["result"]["relative_rmse"], rel_rmse(image(ctx, name + "-seed2"), image(ctx, name),
                                                              ref.keep) / math.sqrt(2)
        rows.append([name, " ".join(args) or "(defaults)", j["result"]["shots"], j["result"]["rays"],
                     j["timings"]["solve_seconds"], j["result"]["stop_reason"], e,
                     in_quadrature(e, ref.noise)[0], noise])
        series.append((name, curve(ctx, name)))
        dat = ctx.result(f"curves/gt-{name}.dat")
        os.makedirs(os.path.dirname(dat), exist_ok=True)
        with open(dat, "w") as f:
            f.write("# seconds relative_rmse\n")
            for t, x in series[-1][1]:
                f.write(f"{t:.6f} {x:.9g}\n")
    write_csv(ctx.result("gt-time.csv"),
                  ["run", "options", "shots", "rays", "solve_seconds", "stop", "vs_gt",
                   "vs_gt_minus_ref_noise", "noise_seed"], rows)

    # The front: the lowest error any run had reached within a budget.
    points = sorted((t, x, name) for name, c in series for t, x in c)

    def within(budget, names=None):
        best = None
        for t, x, name in points:
            if t <= budget and (names is None or name in names) and (best is None or x < best[1]):
                best = (t, x, name)
        return best
    with open(ctx.result("curves/gt-front.dat"), "w") as f:
        best = float("inf")
        for t, x, name in points:
            if x < best:
                best = x
                f.write(f"{t:.6f} {x:.9g} {name}\n")
    # Goals. The "new" runs: every setting but today's.
    new = [n for n, _ in settings if n != "today"]
    b = g["budgets"]  # 1 s, 10 s, 30 s at full scale
    goals = []
    got = {}
    for label, budget, goal in (("error within 1 s of solve", b[0], GOAL_1S),
                                ("error within 10 s of solve", b[1], GOAL_10S),
                                ("error within 30 s of solve", b[2], None)):
        w_ = within(budget, new)
        got[budget] = w_
        if w_:
            goals.append([label.replace("1 s", f"{b[0]:g} s").replace("10 s", f"{b[1]:g} s")
                          .replace("30 s", f"{b[2]:g} s"), "" if goal is None else f"<= {100 * goal:.1f}%",
                          w_[1], in_quadrature(w_[1], ref.noise)[0],
                          f"{w_[2]} at {w_[0]:.3g} s",
                          "" if goal is None else verdict(w_[1] <= goal),
                          "" if goal is None else verdict(in_quadrature(w_[1], ref.noise)[0] <= goal)])
        else:
            goals.append([label, "", "", "", "no measurement within the budget", "NOT met", "NOT met"])
    if got[b[0]] and got[b[2]]:
        r1 = got[b[0]][1] / got[b[2]][1]
        q1, q30 = in_quadrature(got[b[0]][1], ref.noise)[0], in_quadrature(got[b[2]][1], ref.noise)[0]
        goals.append([f"ratio error({b[0]:g} s) / error({b[2]:g} s)", f">= {GOAL_RATIO:g}", r1,
                      q1 / q30 if q30 > 0 else "", "from the two rows above",
                      verdict(r1 >= GOAL_RATIO), verdict(q30 > 0 and q1 / q30 >= GOAL_RATIO)])
    if ctx.scale == "full":
        dref = demo_reference(ctx)
        refs.append(["demo camera", dref.what, g["size"], dref.noise, sum(1 for k in dref.keep if not k)])
        jd = run(ctx, "demo", [], dref, camera=None)
        ed, td = jd["result"]["relative_rmse"], jd["timings"]["solve_seconds"]
        goals.append(["make demo's options (every default at vismask's default camera)", f"<= {100 * GOAL_DEMO:.1f}% in <= {GOAL_DEMO_S:g} s", ed,
                      in_quadrature(ed, dref.noise)[0], f"solve {td:.3g} s",
                      verdict(ed <= GOAL_DEMO and td <= GOAL_DEMO_S),
                      verdict(in_quadrature(ed, dref.noise)[0] <= GOAL_DEMO and td <= GOAL_DEMO_S)])
    else:
        j = load_json(ctx.path("gt-default", "run.json"))
        ed, td = j["result"]["relative_rmse"], j["timings"]["solve_seconds"]
        goals.append(["make demo's options (quick: the default run above at the original camera)",
                      f"<= {100 * GOAL_DEMO:.1f}% in <= {GOAL_DEMO_S:g} s", ed,
                      in_quadrature(ed, ref.noise)[0], f"solve {td:.3g} s",
                      verdict(ed <= GOAL_DEMO and td <= GOAL_DEMO_S),
                      verdict(in_quadrature(ed, ref.noise)[0] <= GOAL_DEMO and td <= GOAL_DEMO_S)])
    write_csv(ctx.result("gt-goals.csv"),
              ["figure", "goal", "measured", "minus_ref_noise", "how", "verdict", "verdict_minus_ref_noise"],
              goals)
    write_csv(ctx.result("gt-references.csv"),
                  ["camera", "what", "size", "noise", "masked_pixels"], refs)
    plot(ctx, series, ref.noise)

    # RenderPark against vismask's front at its times.
    rp = []
    for what, t, e in RENDERPARK:
        w_ = within(t, new)
        rp.append([what, t, e, "" if not w_ else w_[1], "" if not w_ else w_[2],
                   "" if not w_ else ("vismask ahead" if w_[1] < e else "vismask behind")])
    write_csv(ctx.result("gt-renderpark.csv"),
                  ["renderpark", "solve_seconds", "renderpark_vs_gt", "vismask_front_vs_gt",
                   "vismask_run", "who"], rp)

    decomposition(ctx, ref)
    environments(ctx, ref)
    silhouettes(ctx, ref, settings, run, image, write_csv)


def decomposition(ctx, ref):
    """Noise, aliasing and discretisation for each configuration."""
    rows = []
    for name, args in configs(ctx):
        aa_off = "--aa" in args and arg(args, "--aa") == "off"
        base = [a for i, a in enumerate(args) if a != "--aa" and (i == 0 or args[i - 1] != "--aa")]
        # Plain runs (no curve), so that configurations share them.
        key = lambda aa, seed: f"plain-{'-'.join(base).replace('--', '') or 'default'}-aa{aa}-seed{seed}"
        me = "off" if aa_off else "on"
        other = "on" if aa_off else "off"
        j1 = run(ctx, key(me, 1), base + ["--aa", me], ref)
        run(ctx, key(me, 2), base + ["--aa", me, "--seed", "2"], ref)
        jt = run(ctx, key(other, 1), base + ["--aa", other], ref)
        x1, x2, xt = image(ctx, key(me, 1)), image(ctx, key(me, 2)), image(ctx, key(other, 1))
        same = open(ctx.path("gt-" + key(me, 1), "patches.csv")).read() == open(
            ctx.path("gt-" + key(other, 1), "patches.csv")).read()
        total = j1["result"]["relative_rmse"]
        noise = rel_rmse(x2, x1, ref.keep) / math.sqrt(2)
        aa_diff = rel_rmse(x1, xt, ref.keep)
        alias = aa_diff if aa_off else 0.0
        disc, clamped = in_quadrature(total, noise, alias, ref.noise)
        rows.append([name, " ".join(args) or "(defaults)", j1["timings"]["solve_seconds"], total, noise,
                     aa_diff, alias, ref.noise, disc, "clamped at 0" if clamped else "",
                     "yes" if same else "NO"])
        if name in ("today", "default"):
            signed_png(ctx.result(f"img/gt-diff-{name}.png"), ref.w, ref.h, x1, ref.px, ref.keep,
                       ctx.s["gt"]["diff_scale"])
    write_csv(ctx.result("gt-decomposition.csv"),
                  ["config", "options", "solve_seconds", "total_vs_gt", "noise", "aa_off_vs_on",
                   "aliasing", "ref_noise", "discretisation", "note", "same_solve_aa_on_off"], rows)


def environments(ctx, ref):
    """Two environments (B at R = env_res, and R) against one: capped at the
    same solve time, and converged; the seam at x = 278."""
    g = ctx.s["gt"]
    T = g["env_seconds"]
    d = g["default"]
    cfg = [("1 environment", "env1", d),
           (f"2 environments: Method B R = {g['env_res']}", "env2-B",
            d + ["--envs", "2", "--mask-method", "B", "--mask-res", str(g["env_res"])]),
           ("2 environments: Method R", "env2-R", d + ["--envs", "2", "--mask-method", "R"])]
    rows, errs = [], {}
    for label, name, args in cfg:
        for cap in (True, False):
            n = name + ("-capped" if cap else "")
            j = run(ctx, n, args + (["--max-seconds", str(T)] if cap else []), ref)
            e = j["result"]["relative_rmse"]
            errs[n] = e
            rows.append([label, f"{T:g}" if cap else "none", j["timings"]["solve_seconds"],
                         j["result"]["stop_reason"], j["result"]["shots"], e, ""])
    k = 0
    for label, name, _ in cfg:
        for cap in (True, False):
            n = name + ("-capped" if cap else "")
            base = "env1-capped" if cap else "env1"
            d = errs[n] - errs[base]
            rows[k][6] = "" if name == "env1" else d
            rows[k].append("" if name == "env1" else verdict(abs(d) <= GOAL_ENVS))
            k += 1
    write_csv(ctx.result("gt-envs.csv"),
                  ["run", "max_seconds", "solve_seconds", "stop", "shots", "vs_gt",
                   "minus_1_env_points", "within_0.3"], rows)
    # The seam: (2 environments - 1) over the 1-environment image's mean, per
    # column, averaged over a band of rows; x = 278 projects to the middle column.
    one = image(ctx, "env1")
    w, h = ref.w, ref.h
    lo, hi = int(h * g["band"][0]), int(h * g["band"][1])
    prof_rows, seam = [], []
    profiles = {}
    for name in ("env2-B", "env2-R"):
        two = image(ctx, name)
        signed_png(ctx.result(f"img/gt-seam-{name}.png"), w, h, two, one, ref.keep, g["seam_scale"])
        mean = sum(one[3 * (y * w + x) + c] for y in range(lo, hi) for x in range(w) for c in range(3)) / (
            3 * w * (hi - lo))
        p = [sum(two[3 * (y * w + x) + c] - one[3 * (y * w + x) + c] for y in range(lo, hi)
                 for c in range(3)) / (3 * (hi - lo)) / mean for x in range(w)]
        profiles[name] = p
        mid = w // 2
        near = [abs(p[x]) for x in range(mid - 2, mid + 2)]
        far = [abs(v) for x, v in enumerate(p) if abs(x + 0.5 - w / 2) > 8]
        step = (sum(p[mid - 8:mid]) / 8) - (sum(p[mid:mid + 8]) / 8)
        seam.append([name, lo, hi, max(near), sum(far) / len(far), step])
    with open(ctx.result("curves/gt-seam.dat"), "w") as f:
        f.write("# column env2-B env2-R\n")
        for x in range(w):
            f.write(f"{x} {profiles['env2-B'][x]:.6g} {profiles['env2-R'][x]:.6g}\n")
    write_csv(ctx.result("gt-seam.csv"),
                  ["run", "row_from", "row_to", "max_abs_at_seam", "mean_abs_elsewhere",
                   "step_left_minus_right"], seam)
    gnuplot(f"""set terminal pngcairo size 900,400 noenhanced font ',11'
set output '{ctx.result("gt-seam.png")}'
set grid
set xlabel 'pixel column (x = 278 projects between columns {w // 2 - 1} and {w // 2})'
set ylabel '(2 envs - 1 env) / mean of 1 env'
set title 'Seam: rows {lo}-{hi - 1} averaged'
set xrange [0:{w}]
set arrow from {w / 2},graph 0 to {w / 2},graph 1 nohead dt 2
plot '{ctx.result("curves/gt-seam.dat")}' using 1:2 with lines lw 2 title 'env2-B', \\
     '' using 1:3 with lines lw 2 title 'env2-R'
""")


def plot(ctx, series, noise):
    png = ctx.result("gt-error-time.png")
    colours = ["#000000", "#1f77b4", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2",
               "#17becf", "#bcbd22"]
    plots = [f"'{ctx.result(f'curves/gt-{name}.dat')}' using 1:2 with lines lw 2 "
             f"lc rgb '{colours[k % len(colours)]}' title '{name}'" for k, (name, _) in enumerate(series)]
    plots.append(f"'{ctx.result('curves/gt-front.dat')}' using 1:2 with steps lw 3 lc rgb '#ff7f0e' "
                 "title 'front'")
    plots.append(f"{noise} with lines dt 2 lw 2 lc rgb '#7f7f7f' title 'reference noise'")
    for what, t, e in RENDERPARK:
        plots.append(f"'-' using 1:2 with points pt 7 ps 1.5 lc rgb '#7f7f7f' notitle")
    data = "".join(f"{t} {e}\ne\n" for _, t, e in RENDERPARK)
    gnuplot(f"""set terminal pngcairo size 900,600 noenhanced font ',11'
set output '{png}'
set logscale xy
set grid
set key outside right
set xlabel 'solve time, seconds (error measuring excluded)'
set ylabel 'relative RMSE against the Cycles ground truth'
set title 'Cornell box, original camera, 1 environment (grey dots: RenderPark, quoted)'
plot {', '.join(plots)}
{data}""")
