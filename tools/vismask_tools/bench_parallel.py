"""Section 2 of docs/BENCHMARKS.md, the parallel solve, from the runs of
bench_runs.parallel: the 2-rank table, speedups, 4 to 16 environments, a
projection for 16 Raspberry Pi 4 and the parallel efficiency of 16 ranks on
the building."""

import json
import os
import statistics

from .bench_runs import patch_balance
from .files import run_json
from .markdown import table
from .network import BANDWIDTH, LATENCY, NODES, STEPS16, latency_seconds, network_seconds, transfer_seconds
from .stats import median

TARGET_SPEEDUP, TARGET_EFFICIENCY = 1.85, 0.7


def times(x):
    return f"{x:.2f}×"


def verdict(figures):
    """**met** if every figure (as printed, "1.23×") is at least the target."""
    ok = all(float(f.rstrip("×")) >= TARGET_SPEEDUP for f in figures)
    return "**met**" if ok else "**not met**"


class Parallel:
    def __init__(self, s):
        self.s = s
        n = s.names
        self.al, self.ap = n("aloop"), n("apipe")
        self.l, self.pi, self.l1, self.p1 = n("loop"), n("pipe"), n("loop1_"), n("pipe1_")
        self.m2, self.am2 = (n("mpi2_"), n("ampi2_")) if s.mpi else ([], [])

    def json(self, name):
        return run_json(self.s.dir(name))

    def work(self, base, run):
        """work of BASE ÷ RUN's critical_rank_work (counts: no timing)."""
        return times(self.json(base)["result"]["work"] /
                     self.json(run)["result"]["critical_rank_work"])

    def ratio(self, section, key, base, runs):
        return times(self.s.runs(base).median(section, key) / self.s.runs(runs).median(section, key))

    def speed(self, base, runs):
        """median(solve s of base) ÷ median(solve s of runs)."""
        return self.ratio("timings", "solve_seconds", base, runs)

    def crit(self, base, runs):
        return self.ratio("result", "critical_cpu_seconds", base, runs)

    def row(self, label, names):
        r = self.s.runs(names)
        shots, rounds = r.same("result", "shots"), r.same("result", "rounds")
        packets, sent = r.same("result", "packets"), r.same("result", "bytes_sent")
        return [label, r.spread("timings", "solve_seconds"), r.cpu_spread(),
                r.spread("result", "wait_seconds"), r.spread("result", "wait_seconds_max_rank"),
                r.spread("result", "critical_cpu_seconds"), self.work(names[0], names[0]),
                shots, rounds, packets, f"{packets / shots:.1f}", f"{sent / shots:.0f}"]

    def mpi(self, text):
        return text if self.s.mpi else ""


def throughput(s, work):
    """What two processes at once get of this machine's two cores."""
    path = s.dir("throughput.json")
    if not os.path.exists(path):
        return []
    with open(path) as f:
        t = json.load(f)
    alone, paired = statistics.median(t["alone"]), statistics.median(t["paired"])
    speed = alone / paired
    bound = float(work.rstrip("×"))
    # Each repetition: its solo run against the mean of its pair.
    reps = [a / (0.5 * (t["paired"][2 * i] + t["paired"][2 * i + 1]))
            for i, a in enumerate(t["alone"])]
    each = ", ".join(f"{100 * r:.0f}%" for r in reps)
    noise = ("At least one repetition ran faster two at once than alone, so the machine's "
             "noise is as large as the effect and this ceiling is not a reliable one."
             if max(reps) > 1.0 else
             "Every repetition ran slower two at once.")
    return ["", "What the second core gives: the 1-rank baseline of the default case (`" + s.build +
            "/vismask " + t["command"] + "`) alone and two at once, " + str(len(t["alone"])) +
            " times each, alternated. Alone it took",
            f"{alone:.2f} CPU s (median), two at once {paired:.2f} CPU s each: a process runs at "
            f"{100 * speed:.0f}% of its",
            f"speed alone when the other core is busy too (per repetition: {each}; shared",
            "caches, memory and the machine's other load), so on this machine two ranks reach at most",
            f"{times(2 * speed)} with perfect balance and free communication; with the default",
            f"rounds' work bound ({work}), {times(bound * speed)}. {noise} The critical CPU bound above is",
            "measured with both ranks running, so it already includes this."]


def section(s):
    """The section's lines."""
    P = Parallel(s)
    b, aloop = s.build, P.json("aloop1")
    rows = [P.row("default: 1 rank, loop (--envs auto:2)", P.al),
            P.row("default: 2 ranks, pipe (--ranks 2)", P.ap)]
    if s.mpi:
        rows.append(P.row("default: 2 ranks, mpirun -np 2", P.am2))
    rows += [P.row("--envs 2: 1 rank, loop", P.l), P.row("--envs 2: 2 ranks, pipe", P.pi)]
    if s.mpi:
        rows.append(P.row("--envs 2: 2 ranks, mpi", P.m2))
    rows += [P.row("--envs 2: 1 rank, loop, --round-shots 1", P.l1),
             P.row("--envs 2: 2 ranks, pipe, --round-shots 1", P.p1)]
    crit_default = [P.crit(P.al, P.ap)] + ([P.crit(P.al, P.am2)] if s.mpi else [])
    speed_default = [P.speed(P.al, P.ap)] + ([P.speed(P.al, P.am2)] if s.mpi else [])
    L = ["", "## 2. The parallel solve", "",
         "**Every speedup in this section is self-relative**: a split run against the same",
         "split run on one rank, which shows what the transports and the rounds cost, not",
         "whether splitting pays. Against the run a user would otherwise make, one",
         "environment in one process with default options, at equal error, see",
         "docs/PARALLEL.md (`make parallel`). These runs give `--mask-res`, which selects",
         "Method B (the default before issue 39; the default is now R).",
         "",
         f"The default 2-rank run, `{b}/vismask {s.p0} --ranks 2` and",
         f"`mpirun -np 2 --oversubscribe {b}/vismask-mpi {s.p0}`: with no `--envs`,",
         "more than one rank means `--envs auto:2` (balanced planes, per axis",
         f"{json_text(aloop['options']['env_planes'])}), and its 1-rank",
         "baseline is the same two environments in one process (`--envs auto:2",
         "--transport loop`), so all three give the same bytes. The default rounds",
         f"are sized by work (`--round-work`, chosen at init: {aloop['options']['round_work']} units of work, "
         f"at most {aloop['options']['round_shots']} shots).",
         f"For comparison, the uniform split `{b}/vismask {s.p}` (planes at x = 278)",
         """on 1 rank (`--transport loop`), `--ranks 2` and `mpirun -np 2`, with the
default rounds and with the rounds of before (`--round-shots 1`). The outputs
(patches.csv) of every rank count and transport were compared, for each
kind of run, and are the same bytes. MPI speedups are against the 1-rank
loop run of the same kind. *solve s* is run.json's
`solve_seconds` (rank 0's wall clock), *CPU s* the user + system time of
all the processes, *wait s* `wait_seconds`: time rank 0 spent inside
AllToAll and AllGather (blocked until the other rank arrives, plus the
transfer), *max wait s* the most any rank spent there, *critical CPU s*
run.json's `critical_cpu_seconds`: over the rounds, the sum of the most CPU
time any rank spent on that round's shots, which is what the solve would take
with a core per rank and free communication (CPU time does not count the
time a rank is descheduled, so the machine's other load does not enter it).
*work bound*: the 1-rank run's `work` over this run's
`critical_rank_work` (the sum over rounds of the most work any rank did, in
the units rounds are sized by: grid steps plus a ray's, a hit's and a shot's
charge, include/vismask/solve/work.h): the same bound in work, counted, so it is
the same on every run.""", ""]
    L += table(["run", "solve s", "CPU s", "wait s (rank 0)", "max wait s (any rank)", "critical CPU s",
                "work bound", "shots", "rounds", "packets", "packets/shot", "bytes/shot"], rows)
    L += ["", "Speedup bound with a core per rank (median critical CPU s of 1 rank ÷ of 2",
          f"ranks, which the machine's load does not affect): default pipe {crit_default[0]}"
          f"{P.mpi(', mpi ' + crit_default[-1])};",
          f"`--envs 2` pipe {P.crit(P.l, P.pi)}{P.mpi(', mpi ' + P.crit(P.l, P.m2) if s.mpi else '')}, "
          f"`--envs 2 --round-shots 1` {P.crit(P.l1, P.p1)}; in work (counted):",
          f"default {P.work('aloop1', 'apipe1')}, `--envs 2` {P.work('loop1', 'pipe1')}, "
          f"`--envs 2 --round-shots 1` {P.work('loop1_1', 'pipe1_1')}.", "",
          "Measured speedup (median solve s of 1 rank ÷ of 2 ranks, wall clock on this",
          f"shared machine): default pipe {speed_default[0]}{P.mpi(', mpi ' + speed_default[-1])}; "
          "`--envs 2` pipe",
          f"{P.speed(P.l, P.pi)}{P.mpi(', mpi ' + P.speed(P.l, P.m2) if s.mpi else '')}; "
          f"`--envs 2 --round-shots 1` pipe {P.speed(P.l1, P.p1)}.", "",
          f"Target ≥ {TARGET_SPEEDUP}× on 2 ranks with default options, over pipes and under MPI:",
          f"by CPU-time accounting (the critical CPU bound) {verdict(crit_default)}; by wall clock on",
          f"this shared machine {verdict(speed_default)}."]
    L += throughput(s, P.work("aloop1", "apipe1"))
    L += oversubscribed(s) + projection(s, P) + efficiency(s)
    return L


def json_text(v):
    return json.dumps(v)


def oversubscribed(s):
    L = ["", "### 4, 8 and 16 environments", "",
         f"`{s.build}/vismask {s.o} --envs E --ranks N --transport pipe`, one rank per",
         """environment (N up to 16 on 2 cores: oversubscribed, so the times say little;
the counts are exact), and the same with `--transport loop --round-shots 1`
(the rounds of before) for 16 (counts do not depend on the transport or the
number of ranks).""", ""]
    rows = []
    for n in (2, 4, 8, 16):
        for k in ("", "K"):
            d = s.dir(f"over{k}{n}")
            if not os.path.exists(os.path.join(d, "run.json")):
                continue
            j = run_json(d)
            r = j["result"]
            rows.append([n, "by work" if not k else "1 shot", f"{j['timings']['solve_seconds']:.1f}",
                         r["shots"], r["rounds"], f"{r['shots'] / r['rounds']:.1f}", r["rays"],
                         r["mask_rays"], r["packets"], r["bytes_sent"],
                         f"{r['bytes_sent'] / r['shots']:.0f}", f"{r['wait_seconds']:.1f}"])
    return L + table(["environments", "round size", "solve s", "shots", "rounds", "shots/round", "rays",
                      "mask rays", "packets", "bytes sent", "bytes/shot", "wait s (rank 0)"], rows)


def projection(s, P):
    """16 Raspberry Pi 4 on 1 Gbit Ethernet, from the 1-rank loop runs' rate
    and the 16-environment runs' counts."""
    loop = P.json("loop1")["result"]
    rate = (loop["rays"] + loop["mask_rays"]) / median(s.runs(P.l).cpu())  # rays/s of one core here
    pi = rate / 4  # assumption: a Pi 4 core does 1/4 of that
    rows = []
    for label, name in (("by work (default)", "over16"), ("1 shot (before)", "overK16")):
        r = P.json(name)["result"]
        ry = r["rays"] + r["mask_rays"]
        comp, lat, x = ry / NODES / pi, latency_seconds(r), transfer_seconds(r)
        tot = comp + lat + x
        rows.append([label, "%d" % ry, f"{comp:.1f}", r["rounds"], f"{lat:.1f}", r["bytes_sent"],
                     f"{x:.3f}", f"{tot:.1f}", f"{100 * (lat + x) / tot:.0f}%"])
    L = ["", "### Projection: 16 Raspberry Pi 4 on 1 Gbit Ethernet", "",
         f"Measured here: {rate / 1e6:.2f} Mrays/s per core over a whole solve (rays + mask rays ÷ CPU s "
         "of the 1-rank loop runs).", "",
         "Assumptions: one environment per node (16 = 4x2x2), one rank per node; a Pi 4 (Cortex-A72, "
         f"1.5 GHz) casts rays at 1/4 of this core's rate ({pi / 1e6:.2f} Mrays/s) and the 4 cores of a "
         "Pi are not used (one rank per node); the work is spread evenly over the nodes (the counts above "
         "show it is not: this is a lower bound); Open MPI over TCP on a switched 1 Gbit/s network: "
         f"{LATENCY * 1e6:.0f} µs per message step, {BANDWIDTH / 1e6:.0f} MB/s per link, both directions "
         "at once; a round costs one AllToAll that carries the packets and every environment's report "
         "(and the solve one AllGather before the first round: run.json `collectives`), a message from "
         "every rank to every other, posted at once (the sizes travel with the data), counted as if "
         "the 15 went one after another: %d message steps a collective; bytes are spread evenly over "
         "the nodes." % STEPS16,
         ""]
    L += table(["round size", "rays + mask rays", "compute s", "rounds", "latency s", "bytes sent",
                "transfer s", "projected s", "share of time communicating"], rows)
    return L + ["", """The round count, not the bandwidth, is what a Pi cluster pays for: at one
shot per environment per round, the per-round latency of the collectives is
paid thousands of times, and rounds sized by work divide it."""]


BUILDING = (("bldU", "4x1x4 (uniform)", "by work", "4x1x4"), ("bldA", "auto:16", "by work", "auto:16"),
            ("bld1", "auto:16", "1 shot", "auto:16"))


def efficiency(s):
    rows, met = [], []
    for name, envs, rounds, split in BUILDING:
        names = [name] if name == "bld1" else s.names(name)
        names = [n for n in names if os.path.exists(s.dir(n + "/run.json"))]
        if not names:
            continue
        # Each run's efficiency; the row shows the run with the median one,
        # and the range when there were several.
        runs = []
        for n in names:
            r = run_json(s.dir(n))["result"]
            cpu, crit, net = r["compute_cpu_seconds"], r["critical_env_cpu_seconds"], network_seconds(r)
            runs.append((cpu / (16 * (crit + net)), r, cpu, crit, net))
        runs.sort(key=lambda x: x[0])
        here, r, cpu, crit, net = runs[(len(runs) - 1) // 2]
        spread = (f" ({100 * runs[0][0]:.1f}–{100 * runs[-1][0]:.1f}%)" if len(runs) > 1 else "")
        rows.append([envs, rounds, "%d" % r["shots"], "%d" % r["rounds"], f"{patch_balance(s, split):.2f}",
                     f"{100 * r['work'] / (16 * r['critical_env_work']):.0f}%", f"{cpu:.2f}",
                     f"{crit:.3f}", f"{net:.3f}", f"{100 * here:.1f}%{spread}",
                     f"{100 * 4 * cpu / (16 * (4 * crit + net)):.0f}%"])
        if name != "bld1":
            met.append("%s %s (%.1f%%)" % (split, "**met**" if here >= TARGET_EFFICIENCY else "**not met**",
                                           100 * here))
    L = ["", "### Parallel efficiency: 16 ranks on the building (self-relative)", "",
         "The efficiency below is the split run's own (its one-process CPU over 16 times its",
         "critical path) at a stop rule that leaves 55% of the power unshot: it says how evenly",
         "the rounds keep 16 boards busy. Against one environment in one process at",
         "`--stop-unshot 1e-2` see docs/PARALLEL.md and docs/CLUSTER.md.", "",
         f"`{s.build}/vismask {s.bld} --envs E --transport loop` (`tools/gen-building --rooms {s.brooms} "
         "--floors 2`), 16 environments on one process: the",
         """uniform 4x1x4 grid and `--envs auto:16` with the default rounds, and
`--envs auto:16` with the rounds of before (`--round-shots 1`). Sixteen ranks
cannot run in real time on 2 cores, so the time of 16 ranks with a core each
is taken as the critical path, measured per environment on the one-process
run (`critical_env_cpu_seconds`: over the rounds, the sum of the most CPU
any environment spent), plus the network time of the model above (""",
         "%d message steps of 100 µs for each collective (run.json `collectives`: one a round, and "
         "the first totals), the bytes at 117 MB/s spread over 16 links)." % STEPS16,
         """Efficiency = CPU of the one-process solve ÷ (16 × (critical CPU + network));
on a Pi 4 (1/4 of this core's rate, as above) the CPU terms are 4× longer and
the network the same. *work efficiency*: `work` ÷ (16 ×
`critical_env_work`), the same in counted work (what the rounds are sized
by: grid steps plus a ray's, a hit's and a shot's charge) with free
communication.
The default runs are repeated (%d times): the row is the run with the median
efficiency here, with the range of all of them.""" % s.reps, ""]
    L += table(["environments", "round size", "shots", "rounds", "most patches / mean", "work efficiency",
                "CPU s (1 process)", "critical CPU s", "network s", "efficiency here",
                "efficiency on Pi 4"], rows)
    return L + ["", "Target ≥ 70% parallel efficiency at 16 ranks (critical CPU + simulated",
                "network, this core): " + "; ".join(met) + "."]
