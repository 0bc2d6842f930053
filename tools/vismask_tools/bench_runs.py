"""make bench's measurements (bench/run): the settings of a full and a
quick run, and the runs of each part (rays, parallel, masks) into the
output directory. docs/BENCHMARKS.md is written from them by bench_doc."""

import filecmp
import json
import os
import re
import shutil
import subprocess
import sys

from .reps import Runs, timed_run
from .runner import log

SCENE = "scenes/cornell.obj"
PARTS = ("rays", "parallel", "masks")
CAMERA_IN_ROOM = "0.5,1.6,0.5,8,1.2,8,0,1,0,70"
MASK_RES = (20, 50, 100, 250)
OVERSUBSCRIBED = ("2", "2x1x2", "2x2x2", "4x2x2")  # 2, 4, 8 and 16 environments
MPI_ENV = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1")


def say(msg):
    log("bench: " + msg)


class Settings:
    """What a run measures, and where. Commands are strings, as the
    document shows them; `build`, `out` are paths relative to the repository
    (or absolute)."""

    def __init__(self, build="build", out=None, reps=3, quick=False, parts=PARTS):
        self.build, self.out, self.quick = build, out or os.path.join(build, "bench"), quick
        self.parts = list(parts)
        self.reps = 2 if quick else reps
        self.rayargs = ("--rays 4096 --reps 2 --benchmark_min_time=0.01" if quick
                        else "--benchmark_min_time=0.2")
        # The ray-casting scenes (issue 45): the Cornell box from 500 to a
        # million patches, the building, and two furnished interiors of
        # uneven density (tools/gen-interior), written into OUT by rays().
        self.cornell_sizes = "80" if quick else "80, 19.5, 4.7 and 1.66"
        self.building_size = "1" if quick else "0.25"
        self.interior_sizes = "0.5" if quick else "0.25 and 0.1"
        sizes = lambda text: text.replace(" and ", ",").replace(", ", ",")
        self.rayscenes = " ".join([
            f"--scene {SCENE}@{sizes(self.cornell_sizes)}",
            f"--scene {self.out}/building.obj@{self.building_size}",
            f"--scene {self.out}/living.obj@{sizes(self.interior_sizes)}",
            f"--scene {self.out}/library.obj@{sizes(self.interior_sizes)}"])
        stop1, stop2, mshots, bstop, self.brooms = (("0.3", "0.5", 10, "0.7", "4x4") if quick else
                                                    ("2e-2", "5e-2", 200, "0.55", "8x8"))
        self.dens = [2, 4] if quick else [1, 2, 4, 8]
        # Issue 45's end-to-end effect: the living room's default solve, and
        # Method B's centre casts in it (every open pixel's centre ray, a
        # round a shot), each with the sub-grids (the default) and without
        # (--sub-grids 0: the uniform grid of before).
        room = (f"render {self.out}/living.obj --width 64 --height 64" +
                (" --patch-size 0.5 --max-shots 200" if quick else ""))
        self.e2e = [("e2eSolve", "the default solve", room),
                    ("e2eB", "Method B, every open pixel's centre cast, 2 environments",
                     room + " --mask-method B --envs 2 --round-shots 1 --mask-res 50 "
                     "--centre-rays all" + ("" if quick else " --max-shots 1500"))]
        # The cell-size table's sets (quick: rayargs' own), one repetition a
        # round: the rounds alternate the densities.
        self.densargs = "" if quick else "--sizes 19.5,4.7 --rays 32768 --reps 1"
        # The Cornell box in 2 environments, to the same unshot threshold:
        # short enough to repeat. p0 is the default 2-rank run's command (no
        # --envs: --ranks 2 and mpirun -np 2 mean --envs auto:2); p the
        # uniform split.
        self.p0 = f"render {SCENE} --rays 1024 --mask-res 20 --stop-unshot {stop1} --width 64 --height 64"
        self.p = self.p0 + " --envs 2"
        # The default case's 1-rank baseline: its two environments in one
        # process (also what pair_throughput runs alone and two at once).
        self.p0_one = self.p0 + " --envs auto:2 --transport loop"
        self.o = f"render {SCENE} --rays 1024 --mask-res 20 --stop-unshot {stop2} --width 64 --height 64"
        self.bld = (f"render {self.out}/building.obj --patch-size 0.25 --rays 512 --mask-res 20 "
                    f"--stop-unshot {bstop} --width 64 --height 64 --camera {CAMERA_IN_ROOM}")
        self.m = f"render {SCENE} --envs 2 --max-shots {mshots} --width 64 --height 64"
        # Issue 19: the experiments' set-up (vismask_tools/scales.py, full scale).
        self.x = (f"render {SCENE} --envs 2 --patch-size 140 --rays 256 --stop-unshot 0.3 --width 32 --height 32"
                  if quick else
                  f"render {SCENE} --envs 2 --camera 278,545,300,278,0,300,0,0,1,76 --patch-size 70 "
                  "--rays 4096 --stop-unshot 1e-2 --width 256 --height 256")
        # Every default but the image size, in 2 environments: Method B (the
        # default, R = 50), R and none, whole solves.
        self.d = (f"render {SCENE} --envs 2 --patch-size 140 --stop-unshot 0.3 --width 32 --height 32"
                  if quick else f"render {SCENE} --envs 2 --width 128 --height 128")
        self.d4 = self.d.replace("--envs 2 ", "--envs 2x1x2 ")
        self.mpi = (os.access(self.bin("vismask-mpi"), os.X_OK) and shutil.which("mpirun") is not None)

    def has(self, part):
        return part in self.parts

    def bin(self, name="vismask"):
        return os.path.join(self.build, name)

    def dir(self, name):
        return os.path.join(self.out, name)

    def names(self, prefix):
        """prefix1 .. prefixREPS."""
        return [f"{prefix}{i}" for i in range(1, self.reps + 1)]

    def runs(self, names):
        return Runs([self.dir(n) for n in names])

    def run(self, name, cmd, *extra, env=None):
        """One solve: `cmd` (a command string) and `extra` arguments, its
        outputs in OUT/NAME/, its log in OUT/NAME.log."""
        timed_run(cmd.split() + list(extra), self.dir(name), self.dir(name + ".log"), env)

    def vismask(self, name, args, *extra):
        self.run(name, f"{self.bin()} {args}", *extra)

    def mpirun(self, name, args, *extra):
        self.run(name, f"mpirun -np 2 --oversubscribe {self.bin('vismask-mpi')} {args}", *extra,
                 env=MPI_ENV)


def rays(s):
    """vismask_bench: the grid against Embree (OUT/rays.md), and the grid
    alone at each cell density (OUT/densD.md)."""
    say("ray casting (vismask_bench)")
    gen_scenes(s)
    bench(s, "rays", ["--md", s.dir("rays.md")] + s.rayscenes.split() + ["--uniform"] +
          s.rayargs.split())
    # Cell size: the grid alone at 1, 2, 4 and 8 cells per patch.
    base = s.rayargs.split()
    more = s.densargs.split() or ["--sizes", "80"]
    # The densities in turn, s.reps rounds of them, so that the machine's
    # drift falls on every density alike (run one after another, the first
    # and the last density saw different machines).
    for r in range(s.reps):
        for d in s.dens:
            bench(s, f"dens{d}.{r}", ["--md", s.dir(f"dens{d}.{r}.md"), "--density", str(d),
                                      "--benchmark_filter=vismask"] + base + more)
    # The sub-grids end to end, by turns.
    say("end to end: the sub-grids against the uniform grid")
    for i in range(1, s.reps + 1):
        for name, _, args in s.e2e:
            s.vismask(f"{name}N{i}", args)
            s.vismask(f"{name}U{i}", args, "--sub-grids", "0")


def gen_scenes(s):
    """The building and the two furnished interiors, into OUT."""
    subprocess.run(["tools/gen-building", "--rooms", s.brooms, "--floors", "2", "--out",
                    s.dir("building.obj")], check=True, stdout=subprocess.DEVNULL)
    for kind in ("living", "library"):
        subprocess.run(["tools/gen-interior", "--kind", kind, "--out", s.dir(kind + ".obj")],
                       check=True, stdout=subprocess.DEVNULL)


def bench(s, name, args):
    with open(s.dir(name + ".log"), "w") as f:
        rc = subprocess.run([s.bin("vismask_bench")] + args, stdout=f, stderr=subprocess.STDOUT).returncode
    if rc != 0:
        sys.stderr.write(open(s.dir(name + ".log")).read())
        sys.exit(1)


def parallel(s):
    """The default 2-rank run and the uniform split on 1 and 2 ranks (pipe,
    and MPI once), each kind of round; 4 to 16 environments; the building in
    16 environments on one process."""
    say(f"parallel solve: {s.p}")
    for i in range(1, s.reps + 1):
        s.vismask(f"loop{i}", s.p, "--transport", "loop")
        s.vismask(f"pipe{i}", s.p, "--ranks", "2", "--transport", "pipe")
        s.vismask(f"loop1_{i}", s.p, "--transport", "loop", "--round-shots", "1")
        s.vismask(f"pipe1_{i}", s.p, "--ranks", "2", "--transport", "pipe", "--round-shots", "1")
        s.vismask(f"aloop{i}", s.p0_one)
        s.vismask(f"apipe{i}", s.p0, "--ranks", "2")
        if s.mpi:
            s.mpirun(f"mpi2_{i}", s.p, "--transport", "mpi")
            s.mpirun(f"ampi2_{i}", s.p0)
    # The same bytes on every transport and rank count, for each kind of round.
    pairs = [("loop1", "pipe1"), ("loop1_1", "pipe1_1"), ("aloop1", "apipe1")]
    if s.mpi:
        pairs += [("loop1", "mpi2_1"), ("aloop1", "ampi2_1")]
    for a, b in pairs:
        if not filecmp.cmp(s.dir(a + "/patches.csv"), s.dir(b + "/patches.csv"), shallow=False):
            sys.exit(f"bench: {b}: patches.csv differs from {a}")

    pair_throughput(s)

    # 4, 8, 16 environments, each on its own rank (pipe), on 2 cores.
    say(f"oversubscribed: {s.o}")
    for e in OVERSUBSCRIBED:
        n = envs_count(e)
        s.vismask(f"over{n}", s.o, "--envs", e, "--ranks", str(n), "--transport", "pipe")
        if n == 16:
            s.vismask(f"overK{n}", s.o, "--envs", e, "--transport", "loop", "--round-shots", "1")

    # The building in 16 environments on one process: the critical path of
    # a rank per environment is measured per environment
    # (critical_env_cpu_seconds, critical_env_steps), so 16 ranks need not run.
    say("building, 16 environments")
    subprocess.run(["tools/gen-building", "--rooms", s.brooms, "--floors", "2", "--out",
                    s.dir("building.obj")], check=True, stdout=subprocess.DEVNULL)
    # Each default run several times: its critical CPU is a sum of per-round
    # maxima over 16 environments' CPU seconds, which this shared machine's
    # noise inflates.
    for i in range(1, s.reps + 1):
        s.vismask(f"bldU{i}", s.bld, "--envs", "4x1x4", "--transport", "loop")
        s.vismask(f"bldA{i}", s.bld, "--envs", "auto:16", "--transport", "loop")
    s.vismask("bld1", s.bld, "--envs", "auto:16", "--transport", "loop", "--round-shots", "1")


def pair_throughput(s):
    """The default 2-rank case's 1-rank baseline alone and two at once, REPS
    times each: the CPU seconds of each process (os.wait4), in
    OUT/throughput.json."""
    command = s.p0_one
    say(f"two at once: {command}")
    cmd = [s.bin()] + command.split() + ["--quiet", "--out"]

    def start(name):
        log_file = open(s.dir(name + ".log"), "w")
        return subprocess.Popen(cmd + [s.dir(name)], stdout=log_file, stderr=subprocess.STDOUT), log_file

    def cpu(proc):
        _, status, ru = os.wait4(proc[0].pid, 0)
        proc[1].close()
        if status != 0:
            sys.exit(f"bench: {command}: exit status {status}")
        return ru.ru_utime + ru.ru_stime

    alone, paired = [], []
    for i in range(1, s.reps + 1):
        alone.append(cpu(start(f"alone{i}")))
        a, b = start(f"pairA{i}"), start(f"pairB{i}")
        paired += [cpu(a), cpu(b)]
    with open(s.dir("throughput.json"), "w") as f:
        json.dump({"command": command, "alone": alone, "paired": paired}, f)


def envs_count(e):
    n = 1
    for k in e.split("x"):
        n *= int(k)
    return n


def patch_balance(s, envs):
    """`vismask footprint`'s most patches / mean for the building's split."""
    p = subprocess.run([s.bin()] + ["footprint"] + s.bld.split()[1:] + ["--envs", envs, "--json"],
                       capture_output=True, text=True)
    return json.loads(p.stdout)["split"]["patch_balance"]


# The mask methods timed at the defaults (R is the default since issue 39).
DEFAULT_METHODS = ("none", "R", "B")
# Method B's centre rays both ways at the defaults (--centre-rays; auto is
# the default): the run names' suffix and the option's value.
CENTRE_CHOICES = (("Ball", "all"),)
# The defaults in 2x1x2 environments, where foreign shooters pass masks on:
# one run each (Method B casting every open pixel takes about 40 s).
DEFAULT4_RUNS = (("none", ["--mask-method", "none"]), ("R", []),
                 ("B", ["--mask-method", "B"]),
                 ("Ball", ["--mask-method", "B", "--centre-rays", "all"]))


def masks(s):
    """Methods A and B at each R against none, to the same number of shots;
    none, B and C in the experiments' set-up; none, R and B at the defaults;
    callgrind of B at R = 100."""
    say(f"mask cost: {s.m}")
    for i in range(1, s.reps + 1):
        s.vismask(f"none{i}", s.m, "--mask-method", "none")
        for r in MASK_RES:
            s.vismask(f"A{r}_{i}", s.m, "--mask-method", "A", "--mask-res", str(r))
            s.vismask(f"B{r}_{i}", s.m, "--mask-method", "B", "--mask-res", str(r))
    say(f"mask cost, experiments' set-up: {s.x}")
    for i in range(1, s.reps + 1):
        for m in ("none", "B", "C"):
            s.vismask(f"x{m}{i}", s.x, "--mask-method", m, "--mask-res", "100")
    say(f"mask cost, defaults: {s.d}")
    for i in range(1, s.reps + 1):
        for m in DEFAULT_METHODS:
            s.vismask(f"d{m}{i}", s.d, "--mask-method", m)
        for name, how in CENTRE_CHOICES:
            s.vismask(f"d{name}{i}", s.d, "--mask-method", "B", "--centre-rays", how)
    say(f"mask cost, defaults in 2x1x2 environments: {s.d4}")
    for name, extra in DEFAULT4_RUNS:
        s.vismask(f"d4{name}1", s.d4, *extra)
    if s.quick or shutil.which("valgrind") is None:
        return None
    # Where Method B's time goes at R = 100: callgrind's instruction counts
    # by function (a short run).
    say("callgrind: Method B, R = 100")
    cg = s.dir("callgrind.out")
    with open(s.dir("callgrind.log"), "w") as f:
        subprocess.run(["valgrind", "--tool=callgrind", f"--callgrind-out-file={cg}", s.bin(), "render", SCENE,
                        "--envs", "2", "--max-shots", "20", "--width", "32", "--height", "32",
                        "--mask-method", "B", "--mask-res", "100", "--out", s.dir("prof"), "--quiet"],
                       stdout=f, stderr=subprocess.STDOUT)
    p = subprocess.run(["callgrind_annotate", "--inclusive=no", cg], capture_output=True, text=True)
    return top_functions(p.stdout)


def top_functions(annotated, n=8):
    """The first n function lines of callgrind_annotate's table (after its
    sixth line of dashes), without file prefixes '???:' and ' [object]'."""
    out, dashes = [], 0
    for line in annotated.splitlines():
        if re.fullmatch(r"-+", line):
            dashes += 1
            continue
        if dashes == 6 and len(line.split()) > 1 and len(out) < n:
            out.append(re.sub(r" \[[^]]*\]$", "", line).lstrip(" ").replace("???:", "", 1))
    return "\n".join(out)
