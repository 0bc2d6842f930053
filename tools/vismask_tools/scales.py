"""The experiments' settings at each scale (full: docs/RESULTS.md; quick:
the same pipeline in seconds), and the Context that says where a scale's
runs and results go."""

import os

from . import ROOT
from .cornell import SCENE
from .runner import render

# The paper's Table 1 (minutes on its uniprocessor), for the ratio column.
SEED_MINUTES = {("A", 20): 196 + 38 / 60, ("A", 50): 205 + 11 / 60, ("A", 100): 209 + 24 / 60,
                ("B", 20): 171 + 10 / 60, ("B", 50): 179 + 30 / 60, ("B", 100): 202 + 37 / 60}

SPLIT = ["--envs", "2"]  # the Cornell box's box is 0..556 in x: split at x = 278
# Looking down from just under the light: from the paper's front view, the
# part of the tall block's shadow that lies in the second environment
# (x < 278, behind the block) is hidden by the blocks. Image right is -x, as
# in the front view, so the second environment is the right half.
CAMERA = ["--camera", "278,545,300,278,0,300,0,0,1,76"]

# Two scales: "full" is what docs/RESULTS.md shows (make experiments, under
# 15 minutes on 2 cores); "quick" (--quick) is the same pipeline in seconds, for
# the test that keeps it from rotting.
SCALES = {
    "full": dict(common=CAMERA + ["--patch-size", "70", "--rays", "4096", "--stop-unshot", "1e-2",
                         "--width", "256", "--height", "256"],
                 ref_b=["--rays", "8192", "--stop-unshot", "1e-3"],
                 ref_seeds=[1001, 1002],
                 ref_res=250, table_res=[20, 50, 100], curve_res=[20, 50, 100, 250],
                 leak_res=250, reps=3, error_every=100,
                 # The ground truth (groundtruth.py): a Cycles reference of
                 # size^2 at spp (two halves) for the original camera, and of
                 # the experiments' camera at exp_spp. --emitted-rays settings
                 # chosen so that runs converge in about 0.3, 1, 3, 10 and 30 s
                 # of solve on this machine, and a 0.1 s cap (a converged run
                 # needs ~30 000 shots of at least --min-rays: >= 0.3 s).
                 gt=dict(size=512, spp=1024, exp_spp=1024,
                         settings=[("cap-0.1s", ["--emitted-rays", "100000", "--max-seconds", "0.1"]),
                                   ("emitted-1e5", ["--emitted-rays", "100000"]),
                                   ("emitted-7e5", ["--emitted-rays", "700000"]),
                                   ("emitted-1.1e6-stop-3e-3",
                                    ["--emitted-rays", "1100000", "--stop-unshot", "3e-3"]),
                                   ("emitted-1.3e6-stop-3e-3",
                                    ["--emitted-rays", "1300000", "--stop-unshot", "3e-3"]),
                                   ("emitted-3e6", ["--emitted-rays", "3000000"]),
                                   ("emitted-1.2e7", ["--emitted-rays", "12000000"]),
                                   ("emitted-4e7", ["--emitted-rays", "40000000"]),
                                   # Finer patches than the default extent/28 (20 units here).
                                   ("patch-15-emitted-1.2e7",
                                    ["--patch-size", "15", "--emitted-rays", "12000000"]),
                                   ("patch-15-emitted-4e7",
                                    ["--patch-size", "15", "--emitted-rays", "40000000"])],
                         points=40, budgets=[1, 10, 30], env_seconds=10, env_res=100,
                         # --max-seconds T at otherwise default options (issue 41).
                         anytime=[0.1, 0.3, 1, 3, 10],
                         # The anytime runs and RenderPark's, by turns, this
                         # many times (each row its median repetition).
                         reps=3,
                         # rpkCpp's Galerkin (make renderpark): 30 Jacobi
                         # iterations at four link error thresholds (2e-5:
                         # 0.13-0.19 CPU s here, so that a setting counts at
                         # 0.3 s where 1e-5 takes longer than that).
                         rpk=[["-iterations", "30", "-gr-link-error-threshold", t]
                              for t in ("2e-5", "1e-5", "1e-6", "1e-7")],
                         band=[0.3, 0.7], diff_scale=0.2, seam_scale=0.1,
                         common=[], default=[], today_rays=4096),
                 # The sun room (sun_step.py, issue 41's sun-shadow goal): Cycles at
                 # spp (two halves); vismask's runs (name, options, k): its defaults,
                 # more shadow rays, no elements (no pieces split along the edges),
                 # the defaults at k = 2 times the size box-averaged down (where
                 # in a pixel the gather's rays leave from), and in 2x1x2
                 # environments (the sun through the other environments' maps).
                 sun=dict(width=256, height=192, spp=1024,
                          runs=[("default", [], 1), ("direct-128", ["--direct-samples", "128"], 1),
                                ("elements-0", ["--elements", "0"], 1), ("default-2x", [], 2),
                                ("envs-2x1x2", ["--envs", "2x1x2"], 1)]),
                 # The occluded room (room_step.py, issue 41): make parallel's room and
                 # reference, one environment at the defaults; errors over k x k blocks.
                 room=dict(width=384, height=192, spp=4096, options=[], blocks=[1, 2, 4, 8])),
    "quick": dict(common=CAMERA + ["--patch-size", "140", "--rays", "256", "--stop-unshot", "5e-2",
                         "--width", "48", "--height", "48"],
                 ref_b=["--rays", "1024", "--stop-unshot", "1e-2"],
                 ref_seeds=[1001, 1002],
                 ref_res=16, table_res=[4, 8], curve_res=[4, 8, 16],
                 leak_res=16, reps=3, error_every=10,
                 gt=dict(size=48, spp=8, exp_spp=8,
                         settings=[("cap-0.02s", ["--emitted-rays", "20000", "--max-seconds", "0.02"]),
                                   ("emitted-2e4", ["--emitted-rays", "20000"])],
                         points=10, budgets=[0.05, 0.2, 0.5], env_seconds=0.2, env_res=8,
                         anytime=[0.02, 0.05], reps=2,
                         rpk=[["-iterations", "30", "-gr-link-error-threshold", "1e-5"]],
                         vs_from=0.02,
                         band=[0.3, 0.7], diff_scale=0.2, seam_scale=0.1,
                         common=["--patch-size", "140", "--stop-unshot", "5e-2"],
                         default=["--emitted-rays", "50000"], today_rays=256),
                 sun=dict(width=64, height=48, spp=16,
                          runs=[("default", ["--emitted-rays", "100000"], 1),
                                ("default-2x", ["--emitted-rays", "100000"], 2)]),
                 room=dict(width=96, height=48, spp=16, options=["--emitted-rays", "100000"],
                           blocks=[1, 4])),
}


class Context:
    """Where a scale's runs and results go, and how vismask is started."""

    def __init__(self, scale, out, runs):
        self.scale = scale
        self.s = SCALES[scale]
        self.out = out  # results: CSV tables, images, plots
        self.runs = runs  # one directory per run (outputs of vismask)
        self.bin = os.environ.get("VISMASK_BIN", os.path.join(ROOT, "build", "vismask"))
        os.makedirs(self.out, exist_ok=True)
        os.makedirs(self.runs, exist_ok=True)

    def run(self, name, args, fresh=False, common=None):
        """Runs `vismask render SCENE common args --out runs/name` unless the
        same command already ran there; returns run.json. `fresh` always
        reruns (timed repetitions); `common` replaces the scale's common
        arguments (the ground-truth runs)."""
        return render(SCENE, (self.s["common"] if common is None else common) + list(args),
                      os.path.join(self.runs, name), fresh=fresh, binary=self.bin)

    def path(self, name, f):
        return os.path.join(self.runs, name, f)

    def result(self, f):
        return os.path.join(self.out, f)


def context(args):
    """The Context of parsed arguments (cli.parse): the scale, and where
    results and runs go. Results default to docs/results/, with runs under
    build/experiments/SCALE/; with --out DIR, runs go to DIR/runs."""
    scale = "quick" if args.quick else "full"
    out = os.path.abspath(args.out or os.path.join(ROOT, "docs", "results"))
    runs = os.path.join(ROOT, "build", "experiments", scale) if out.startswith(
        os.path.join(ROOT, "docs")) else os.path.join(out, "runs")
    return Context(scale, out, runs)


def arg(args, flag):
    """The value after the last `flag` in an argument list."""
    return [args[i + 1] for i, a in enumerate(args[:-1]) if a == flag][-1]



