"""The '## Against a path-traced ground truth' section of docs/RESULTS.md
and its bullet in the Reading, from the gt-*.csv tables of the
ground-truth step (groundtruth.py)."""

import os

from .files import csv_dicts
from .plot import gnuplot
from .groundtruth import RENDERPARK
from .gt_references import ORIGINAL
from .stats import pct


def report_section(ctx, w, link, table_md):
    """The '## Against a path-traced ground truth' section of RESULTS.md."""
    g = ctx.s["gt"]
    w("## Against a path-traced ground truth (issue 15)\n")
    skip = ctx.result("gt-skipped.txt")
    if os.path.exists(skip) or not os.path.exists(ctx.result("gt-goals.csv")):
        why = open(skip).read().strip() if os.path.exists(skip) else "no results"
        w(f"**Skipped**: {why}. The ground-truth columns of the tables above are empty for the "
          "same reason.\n")
        return
    refs = csv_dicts(ctx.result("gt-references.csv"))
    ref = refs[0]
    noise = float(ref["noise"])
    w(f"The Cornell box at its original camera (`--camera {ORIGINAL}`: eye 278,273,−800, target "
      f"278,273,0, up +y, fovy 39.3076°), {g['size']}², one environment, one process (loop "
      "transport, one core), against a Blender Cycles render under vismask's conventions "
      "(tools/reference). The pixels that see the emitter, dilated by 2 px, are left out "
      "(`--exclude`, the reference's mask). Errors are relative RMSEs "
      "√(Σ(a−b)²/Σb²) over the RGB values of the other pixels; times are `solve_seconds`. "
      "Runs at other settings than the defaults: " + (" ".join(g["common"]) or "none") + ".\n")
    w(table_md(ctx.result("gt-references.csv")) + "\n")
    w("The references are cached (build/reference-cache/, keyed by scene, camera, size, spp, "
      "seed and Blender's version); the render time in `what` is in this run's wall time only "
      "if they were not already there. A reference committed as "
      "docs/results/reference/cornell-original-SIZE.pfm.gz (with its mask and json) replaces "
      "the original camera's.\n")
    w(f"`noise` is the reference's own relative RMSE against the noise-free image, estimated from "
      f"its two halves (tools/reference --halves). **No measured error can fall below it**: an "
      f"image equal to the truth would measure {pct(noise)}. Where a column says "
      "`minus_ref_noise` it is √(measured² − noise²), the error against the noise-free image "
      "estimated by removing the reference's noise in quadrature (the two are independent); "
      "it is the better estimate of vismask's own error, and the less certain the closer the "
      "measured figure is to the noise.\n")

    w("### Error against solve time\n")
    w(f"Each run measured its image against the reference about {g['points']} times during the "
      "solve (`--error-every`, off the clock). `today` is the render before issue 15 "
      "(`--rays 4096 --sampler random --elements 0 --aa off --patch-size 34.95`, the former "
      "extent/16); `default` every default option "
      "(power allocation, `--emitted-rays 4000000`, `--min-rays 16`, patches of extent/28, "
      "Sobol', elements, exact-coverage antialiasing); the `emitted-*` runs the defaults with "
      "another `--emitted-rays` (one also with `--stop-unshot 3e-3`), chosen so that they "
      "converge in about 0.3, 1, 3, 10 and 30 s here, and the `patch-15-*` runs the same with "
      "finer patches (their measured times are in the table: a budget figure below uses what "
      "was reached by then). A converged solve takes some 30 000 shots of at least "
      "`--min-rays` rays, so no setting "
      "of `--emitted-rays` converges in 0.1 s: `cap-0.1s` is a `--max-seconds 0.1` cap (its "
      "result depends on the machine's speed). `noise_seed` is the run's own Monte Carlo noise: "
      "the RMSE between seeds 1 and 2 over √2. The front (orange) is the lowest error any "
      "run other than `today` had reached within each solve time; the grey dots are "
      "RenderPark (below).\n")
    w(f"![error against time, ground truth]({link('gt-error-time.png')})\n")
    w(table_md(ctx.result("gt-time.csv")) + "\n")

    w("### The goals of issue 15\n")
    rows = ["| figure | goal | measured | minus the reference's noise | how | verdict | "
            "verdict minus the reference's noise |", "|---|---|---|---|---|---|---|"]
    for r in csv_dicts(ctx.result("gt-goals.csv")):
        ratio = r["figure"].startswith("ratio")
        f = (lambda x: f"{float(x):.2f}") if ratio else pct
        rows.append(f"| {r['figure']} | {r['goal']} | {f(r['measured']) if r['measured'] else ''} | "
                    f"{f(r['minus_ref_noise']) if r['minus_ref_noise'] else ''} | {r['how']} | "
                    f"{r['verdict']} | {r['verdict_minus_ref_noise']} |")
    w("\n".join(rows) + "\n")
    w("The error within a time is the front's: the lowest error any run (other than `today`) "
      "had measured by then. "
      + (f"The demo row is `make demo`'s command itself at its own camera (vismask's default, "
         f"which frames the scene's box: eye 278,274.4,−809.7), against a second reference "
         f"at that camera: {refs[1]['what']}, noise {pct(refs[1]['noise'])}."
         if len(refs) > 1 else "At quick scale the demo row is the default run above.") + "\n")

    w("### RenderPark, quoted\n")
    w("Measured by an earlier session on this machine (issue 15), **not rerun by make "
      "experiments**, against that session's Cycles reference of the same view (not the one "
      "above), so the comparison is indicative:\n")
    w("| RenderPark method | solve time | relative RMSE |\n|---|---|---|\n" + "\n".join(
        f"| {m} | {t:g} s | {100 * e:.1f}% |" for m, t, e in RENDERPARK) + "\n")
    w("vismask's front (this run) at the same solve times:\n")
    w(table_md(ctx.result("gt-renderpark.csv")) + "\n")

    if os.path.exists(ctx.result("gt-silhouettes.csv")):
        w("### Without the 1-px silhouettes (issue 41)\n")
        w("A one-sample-per-pixel raycast (RenderPark's image) aliases on the geometric edges of "
          "the image. tools/silhouette-mask marks the pixels within 1 px of one: one ray through "
          "each pixel centre with vismask's camera, and a pixel whose 3x3 neighbourhood sees more "
          "than one surface (a plane with one material) or misses the scene. `vs_gt` leaves out "
          "the emitter's pixels as above; `vs_gt_no_silhouettes` leaves out the emitter's and "
          "the silhouettes' (runs/gt/original-silhouettes.pgm, for `vismask compare --exclude`):\n")
        w(table_md(ctx.result("gt-silhouette-mask.csv")) + "\n")
        w(f"`--max-seconds T` at otherwise default options (`anytime-T`), and the fixed "
          "settings of the error-against-time runs above (read, not rerun). "
          "`best_fixed_within`: the fixed setting with the lowest `vs_gt` among those whose "
          "solve took at most T; issue 41's anytime goal is `anytime_over_best_fixed` <= 1.25. "
          "The `--max-seconds` runs were repeated `reps` times by turns with RenderPark's "
          "(below); each row is the median repetition by `vs_gt`. `cpu_seconds`: the solve's "
          "CPU seconds on the rank (run.json's `compute_cpu_seconds`), beside `solve_seconds`, "
          "its wall clock, which `--max-seconds` limits.\n")
        w(table_md(ctx.result("gt-silhouettes.csv")) + "\n")
        w("The same runs and RenderPark's (below) drawn: each run's final error at its solve "
          "time (RenderPark's: its CPU seconds); `--max-seconds T` (orange) beside the fixed "
          "settings (blue), with the emitter's pixels left out (left) and the silhouettes' as "
          "well (right):\n")
        w(f"![anytime against the fixed settings]({link(anytime_plot(ctx))})\n")
        w("RenderPark measured in this run: rpkCpp's hierarchical Galerkin "
          "(tools/renderpark-run: the scene in metres, a one-ray-per-pixel raycast of the "
          "solution), by its own CPU seconds, interleaved with the `--max-seconds` runs above "
          "(`run_order`: each repetition's place in the one sequence of both; each row is its "
          "median repetition by `vs_gt`, `vs_gt_range` over all of them, and `cpu_seconds` the "
          "median of their CPU seconds):\n")
        skipped = ctx.result("gt-renderpark-skipped.txt")
        if os.path.exists(ctx.result("gt-renderpark-measured.csv")):
            w(table_md(ctx.result("gt-renderpark-measured.csv")) + "\n")
            w("Issue 41's goal without the 1-px silhouettes, budget by budget: vismask's "
              "`--max-seconds T` row above (its median repetition) against RenderPark's best "
              "setting whose CPU seconds were at most T (`renderpark_within`; a setting that took "
              "longer does not count at T, as vismask's runs may not take longer either), and "
              "against the figure issue 41 quotes for T (`issue_quoted`):\n")
            w(table_md(ctx.result("gt-renderpark-vs.csv")) + "\n")
        else:
            w("**Skipped**: " + (open(skipped).read().strip() if os.path.exists(skipped)
                                 else "no results") + ".\n")

    w("### Where the error comes from\n")
    w("Per configuration, from three runs: seed 1 (`total_vs_gt`), seed 2, and seed 1 drawn with "
      "the other `--aa` (the same seed gives the same solve: `same_solve_aa_on_off` says whether "
      "their patches.csv are identical). `noise` = RMSE(seed 1, seed 2)/√2; `aa_off_vs_on` = "
      "RMSE between the `--aa off` and `--aa on` images of the same solve; `aliasing` is that "
      "difference for the configurations drawn with `--aa off`, and 0 for those drawn with "
      "`--aa on` (each pixel is then the exact box-filtered mean of what it sees, the "
      "reference's own pixel filter); `discretisation` the rest: "
      "√(total² − noise² − aliasing² − ref_noise²), clamped at 0 where that is negative (`note` "
      "says so). The split assumes the parts independent, which noise and the reference's "
      "noise are, but aliasing and discretisation need not be: read the last two as "
      "estimates.\n")
    w(table_md(ctx.result("gt-decomposition.csv")) + "\n")
    w(f"The image minus the ground truth (channels averaged, over the reference's mean): red "
      f"where vismask is brighter, blue where darker, full colour at ±{100 * g['diff_scale']:.0f}% "
      "of the reference's mean; grey: excluded pixels. `today` (left) and `default` (right):\n")
    w(f"![today minus ground truth]({link('img/gt-diff-today.png')}) "
      f"![default minus ground truth]({link('img/gt-diff-default.png')})\n")

    w("### Two environments against one\n")
    w(f"`--envs 2` (split at x = 278) with Method B at `--mask-res {g['env_res']}` and with "
      f"Method R, against one environment, all at the default options: capped at "
      f"`--max-seconds {g['env_seconds']:g}` (a run that converges sooner stops there: `stop`), "
      "and run to convergence. Goal: within 0.3 points of one environment at the same "
      "solve time.\n")
    w(table_md(ctx.result("gt-envs.csv")) + "\n")
    w(f"The seam: the converged 2-environment image minus the converged 1-environment image, "
      f"over the latter's mean, averaged over rows {int(g['band'][0] * g['size'])}–"
      f"{int(g['band'][1] * g['size']) - 1} per pixel column; the plane x = 278 projects to the "
      "middle of the image (dashed). `max_abs_at_seam` is the largest |profile| in the 4 middle "
      "columns, `mean_abs_elsewhere` its mean more than 8 columns away, "
      "`step_left_minus_right` the mean of the 8 columns left of the middle minus the 8 right "
      "of it.\n")
    w(f"![seam profile]({link('gt-seam.png')})\n")
    w(table_md(ctx.result("gt-seam.csv")) + "\n")
    w(f"Difference images (2 environments − 1, red brighter, blue darker, full colour at "
      f"±{100 * g['seam_scale']:.0f}% of the 1-environment image's mean): Method B (left), "
      "Method R (right):\n")
    w(f"![B seam]({link('img/gt-seam-env2-B.png')}) ![R seam]({link('img/gt-seam-env2-R.png')})\n")


def anytime_plot(ctx):
    """gt-anytime.png from gt-silhouettes.csv and gt-renderpark-measured.csv:
    error against seconds, with and without the silhouettes; returns its name."""
    name = "gt-anytime.png"
    rows = csv_dicts(ctx.result("gt-silhouettes.csv"))
    rpk_csv = ctx.result("gt-renderpark-measured.csv")
    rpk = csv_dicts(rpk_csv) if os.path.exists(rpk_csv) else []

    def block(points):
        return "".join(f"{x} {y}\n" for x, y in points) + "e\n"

    panels = []
    for col, title in (("vs_gt", "emitter's pixels left out"),
                       ("vs_gt_no_silhouettes", "emitter's and 1-px silhouettes left out")):
        anytime = [(float(r["solve_seconds"]), float(r[col])) for r in rows if r["max_seconds"]]
        fixed = [(float(r["solve_seconds"]), float(r[col])) for r in rows if not r["max_seconds"]]
        plots = ["'-' using 1:2 with points pt 7 ps 1.2 lc rgb '#1f77b4' title 'fixed settings'",
                 "'-' using 1:2 with linespoints pt 5 ps 1.4 lw 2 lc rgb '#ff7f0e' "
                 "title '--max-seconds T'"]
        data = block(sorted(fixed)) + block(anytime)
        if rpk:
            plots.append("'-' using 1:2 with linespoints pt 9 ps 1.4 lw 2 lc rgb '#7f7f7f' "
                         "title 'RenderPark (CPU s)'")
            data += block([(float(r["cpu_seconds"]), float(r[col])) for r in rpk])
        panels.append(f"set title \"{title}\"\nplot {', '.join(plots)}\n{data}")
    gnuplot(f"""set terminal pngcairo size 1000,420 noenhanced font ',10'
set output '{ctx.result(name)}'
set multiplot layout 1,2
set logscale xy
set grid
set key top right
set xlabel 'seconds of solve'
set ylabel 'relative RMSE against the Cycles ground truth'
{"".join(panels)}unset multiplot
""")
    return name


def reading(ctx, w):
    """A bullet for the report's Reading."""
    if not os.path.exists(ctx.result("gt-goals.csv")) or os.path.exists(ctx.result("gt-skipped.txt")):
        return
    goals = csv_dicts(ctx.result("gt-goals.csv"))
    noise = float(csv_dicts(ctx.result("gt-references.csv"))[0]["noise"])
    parts = []
    for r in goals:
        if not r["goal"] or not r["measured"]:
            continue
        ratio = r["figure"].startswith("ratio")
        f = (lambda x: f"{float(x):.2f}") if ratio else pct
        parts.append(f"{r['figure']}: {f(r['measured'])} ({f(r['minus_ref_noise'])} without the "
                     f"reference's noise), goal {r['goal']}: {r['verdict']}"
                     + ("" if r["verdict"] == r["verdict_minus_ref_noise"]
                        else f" ({r['verdict_minus_ref_noise']} without the reference's noise)"))
    envs = csv_dicts(ctx.result("gt-envs.csv"))
    env_parts = [f"{e['run']} {pct(e['vs_gt'])} ({float(e['minus_1_env_points']) * 100:+.2f} points: "
                 f"{e['within_0.3']})" for e in envs if e["max_seconds"] != "none" and e["minus_1_env_points"]]
    rp = csv_dicts(ctx.result("gt-renderpark.csv"))
    rp_parts = [f"{r['who']} at {r['solve_seconds']} s ({pct(r['vismask_front_vs_gt'])} against "
                f"{r['renderpark']}'s quoted {pct(r['renderpark_vs_gt'], 1)})" for r in rp if r["who"]]
    seam = csv_dicts(ctx.result("gt-seam.csv"))
    seam_parts = [f"{r['run']} {pct(r['max_abs_at_seam'])} at the middle columns against "
                  f"{pct(r['mean_abs_elsewhere'])} elsewhere" for r in seam]
    w(f"- **Against the ground truth (issue 15).** " + "; ".join(parts) + ". Two environments "
      f"at the same capped solve time: " + "; ".join(env_parts) + ". Converged: " + "; ".join(
          f"{e['run']} {pct(e['vs_gt'])} in {float(e['solve_seconds']):.3g} s"
          for e in envs if e["max_seconds"] == "none") + ". The seam (2 environments − 1, "
      "column profile): " + "; ".join(seam_parts) + f". The reference's own noise "
      f"is {pct(noise)}: every measured figure includes it. Against RenderPark's quoted figures "
      "(another session's reference, so indicative only): " + ("; ".join(rp_parts) or
                                                               "no vismask measurement that early") + ".")
