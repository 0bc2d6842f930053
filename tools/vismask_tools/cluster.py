"""make cluster-experiments' runs (tools/cluster-experiments): the settings
of a full and a quick run, the one-process references, the simulated
clusters (tools/cluster-sim), the board that is too small, the
million-patch building and the parallel efficiency of 16 ranks.
docs/CLUSTER.md is written from them by cluster_doc."""

import filecmp
import json
import os
import shlex
import shutil
import signal
import subprocess
import time

from .files import load_json, run_json
from .network import network_seconds
from .runner import log as log_line, run as run_cmd

LINKS = ["100mbit", "1gbit"]
CAMERA_IN_ROOM = "0.5,1.6,0.5,8,1.2,8,0,1,0,70"
COMPARED = ["image.pfm", "patches.csv"]
MILLION_BEGIN, MILLION_END = "<!-- million: begin -->", "<!-- million: end -->"
EFF_BEGIN, EFF_END = "<!-- efficiency: begin -->", "<!-- efficiency: end -->"
RESUME_BEGIN, RESUME_END = "<!-- resume: begin -->", "<!-- resume: end -->"


def log(msg):
    log_line("cluster-experiments: " + msg)


def run(cmd):
    """Runs a command (logged); returns (returncode, stderr, wall seconds)."""
    log("$ " + " ".join(shlex.quote(c) for c in cmd))
    rc, _, err, wall = run_cmd(cmd)
    return rc, err, wall


def fresh(d):
    """An empty directory d."""
    shutil.rmtree(d, ignore_errors=True)
    os.makedirs(d)


def same_bytes(a, b):
    return all(filecmp.cmp(os.path.join(a, f), os.path.join(b, f), shallow=False)
               if os.path.exists(os.path.join(a, f)) and os.path.exists(os.path.join(b, f)) else False
               for f in COMPARED)


class Config:
    """What a run measures. --quick: 2 nodes, a tenth of the shots, a small
    building and a small 'million' case (the pipeline, in minutes; its figures
    mean nothing). Runs go to build/cluster/ (build/cluster-quick/), the
    document and its figure to DOC_DIR (docs/)."""

    def __init__(self, quick=False, doc_dir=None):
        self.quick = quick
        self.out = "build/cluster-quick" if quick else "build/cluster"
        self.doc_dir = doc_dir or "docs"
        self.doc = os.path.join(self.doc_dir, "CLUSTER.md")
        self.png = os.path.join(self.doc_dir, "img", "cluster-time.png")
        self.command = "sudo tools/cluster-experiments --quick" if quick else "sudo make cluster-experiments"
        self.nodes = [int(n) for n in os.environ.get("CLUSTER_NODES", "2" if quick else "2 4 8 16").split()]
        self.rooms = "4x4" if quick else "8x8"
        self.building = os.path.join(self.out, "building.obj") if quick else "build/building.obj"
        shots = (lambda n: str(n // 10)) if quick else str
        self.scenes = [
            ("cornell", "the Cornell box", "scenes/cornell.obj",
             ["--envs", "4x1x4", "--rays", "1024", "--max-shots", shots(1600), "--width", "128",
              "--height", "128"]),
            ("building", f"a building of {self.rooms}x2 rooms (tools/gen-building)", self.building,
             ["--patch-size", "0.25", "--envs", "4x1x4", "--rays", "512", "--max-shots", shots(800),
              "--width", "128", "--height", "128", "--camera", CAMERA_IN_ROOM]),
        ]
        # A million patches on sixteen 1 GB boards (issue 20): the building's
        # faces written as triangles of at most 0.2 m, one patch each.
        self.million_scene = os.path.join(self.out, "building-1m.obj") if quick else "build/building-1m.obj"
        self.million_gen = ["tools/gen-building", "--rooms", "2x2" if quick else "8x8", "--floors",
                            "1" if quick else "2", "--tile", "0.5" if quick else "0.2", "--out",
                            self.million_scene]
        # --rank-timeout: ranks 1-15 wait at init's agreement while rank 0
        # runs the emitter check (9216 emitting triangles, 65536 polygons at
        # a time), on 16 ranks sharing this machine's 2 cores: minutes,
        # beyond the default 60 s.
        self.million_args = ["--patch-size", "1", "--envs", "4x1x4", "--rays", "256", "--max-shots",
                             shots(320), "--width", "128", "--height", "128", "--camera", CAMERA_IN_ROOM,
                             "--rank-timeout", "1800"]
        self.million_nodes, self.million_mem = (2 if quick else 16), "1G"
        # A scene too big for a 512 MiB board (Pi Zero 2 W): refused at init.
        # R = 4096 (8 MB mask packets): about 690 MB a rank. R = 3000 was
        # refused only while the queue held 8 times as many slots; with the
        # default queue it fits in 400 MB and runs (a shot every 5 s).
        self.refuse_cmd = ["tools/cluster-sim", "--nodes", "2", "--link", "100mbit", "--mem", "512M", "--",
                           "render", "scenes/cornell.obj", "--envs", "2", "--mask-res", "4096",
                           "--out", self.out + "/refused", "--quiet"]
        # Issue 20: 16 ranks on the building, judged by the critical path
        # measured per environment on one process and a modelled network;
        # issue 39: against one environment in one process (eff_baseline),
        # default options, at a stop rule that leaves 1% of the power unshot.
        self.eff_args = ["--patch-size", "0.25", "--stop-unshot", "0.1" if quick else "1e-2",
                         "--width", "64", "--height", "64", "--camera", CAMERA_IN_ROOM, "--quiet"]
        # Issue 43: 16 boards, one killed mid-solve, the run resumed on 15 from
        # its checkpoint. The building in rounds of 4 shots an environment (so
        # the solve has rounds to lose), a checkpoint every round.
        self.resume_nodes = 2 if quick else 16
        self.resume_args = ["--patch-size", "0.25", "--envs", "4x1x4", "--rays", "512",
                            "--max-shots", shots(800), "--round-shots", "2" if quick else "4",
                            "--width", "128", "--height", "128", "--camera", CAMERA_IN_ROOM]
        self.resume_kill_round = 2 if quick else 6  # the node dies once a checkpoint holds this round
        self.resume_victim = 1 if quick else 5      # the rank (node - 1) killed
        self.eff_baseline = ("one environment, one process (the baseline)", [])
        self.eff_cases = [("uniform 4x1x4, rounds by work (default)", ["--envs", "4x1x4"]),
                          ("auto:16, rounds by work (default)", ["--envs", "auto:16"])]

    def path(self, *parts):
        return os.path.join(self.out, *parts)

    def save(self, name, data):
        with open(self.path(name), "w") as f:
            json.dump(data, f, indent=1)

    def gen_building(self):
        rc, err, _ = run(["tools/gen-building", "--rooms", self.rooms, "--floors", "2", "--out",
                          self.building])
        if rc != 0:
            log(err)
        return rc == 0


def reference(c, name, scene, args):
    """The one-process run of a scene: its figures."""
    ref = c.path(name + "-ref")
    shutil.rmtree(ref, ignore_errors=True)
    rc, err, wall = run(["build/vismask", "render", scene] + args + ["--out", ref, "--quiet"])
    if rc != 0:
        log(err)
        return None
    rj = run_json(ref)
    return {"wall": wall, "solve": rj["timings"]["solve_seconds"],
            "init": rj["timings"]["init_seconds"], "rounds": rj["result"]["rounds"],
            "patches": rj["counts"]["patches"], "sent": rj["result"]["bytes_sent"],
            "packet_bytes": rj["result"]["packet_bytes"], "predicted": rj["memory"]["predicted_bytes"]}


def sim(c, name, scene, args, nodes, link, slots=1):
    """One cluster-sim run; returns a row of figures (None if it failed)."""
    d = c.path("%s-%s-%d" % (name, link if slots == 1 else "lo", nodes * slots))
    fresh(d)
    rc, err, _ = run(["tools/cluster-sim", "--nodes", str(nodes), "--link", link, "--slots", str(slots),
                      "--report", os.path.join(d, "report.json"), "--",
                      "render", scene] + args + ["--out", os.path.join(d, "out"), "--quiet"])
    with open(os.path.join(d, "log.txt"), "w") as f:
        f.write(err)
    if rc != 0:
        log("FAILED (%d):\n%s" % (rc, err[-3000:]))
        return None
    rep = load_json(os.path.join(d, "report.json"))
    rj = run_json(os.path.join(d, "out"))
    links = rep["links"]
    mpi = sorted(rep["mpi_collective_seconds"])
    return {
        "nodes": nodes * slots, "link": link if slots == 1 else "loopback",
        "wall": rep["wall_seconds"], "init": rj["timings"]["init_seconds"],
        "solve": rj["timings"]["solve_seconds"], "output": rj["timings"]["output_seconds"],
        "rounds": rj["result"]["rounds"], "shots": rj["result"]["shots"],
        "sent": rj["result"]["bytes_sent"],
        "up_bytes": sum(l["up_bytes"] for l in links),
        "up_packets": sum(l["up_packets"] for l in links),
        "max_up": max(l["up_bytes"] for l in links),
        "max_down": max(l["down_bytes"] for l in links),
        "drops": sum(l["drops"] for l in links),
        "lo_bytes": sum(l["lo_bytes"] for l in links),
        "mpi_min": mpi[0] if mpi else float("nan"),
        "mpi_med": mpi[len(mpi) // 2] if mpi else float("nan"),
        "mpi_max": mpi[-1] if mpi else float("nan"),
        "mpi_span": max(rep["mpi_span_seconds"]) if rep["mpi_span_seconds"] else float("nan"),
        "identical": same_bytes(os.path.join(d, "out"), c.path(name + "-ref")),
        "shaper": rep["shaper"],
    }


def refused(c):
    """The scene too big for a 512 MiB board: exit status and message."""
    shutil.rmtree(c.path("refused"), ignore_errors=True)
    rc, err, _ = run(c.refuse_cmd)
    return {"code": rc,
            "lines": [l for l in err.splitlines() if l.startswith("vismask:") or "ulimit" in l],
            "no_output": not os.path.exists(c.path("refused"))}


def efficiency_runs(c):
    """The building in 16 environments on one process, for each case: its
    counts, CPU and critical path, and the modelled network time."""
    rows = []
    for label, extra in [c.eff_baseline] + c.eff_cases:
        d = c.path("eff-" + str(len(rows)))
        shutil.rmtree(d, ignore_errors=True)
        rc, err, _ = run(["build/vismask", "render", c.building] + c.eff_args + extra + ["--out", d])
        if rc != 0:
            log(err)
            return None
        r = run_json(d)["result"]
        net = network_seconds(r) if extra else 0.0  # one process: no network
        rows.append({"label": label, "args": extra, "rounds": r["rounds"], "shots": r["shots"],
                     "collectives": r["collectives"],
                     "cpu": r.get("total_cpu_seconds", r["compute_cpu_seconds"]),
                     "crit": r["critical_env_cpu_seconds"],
                     "steps": r["work"], "crit_steps": r["critical_env_work"], "net": net})
    return rows


def million(c):
    """The million-patch building: one process, then 16 nodes of 1 GB."""
    scene = c.million_scene
    if not (os.environ.get("CLUSTER_MILLION_REUSE") == "1" and os.path.exists(scene)):
        rc, err, _ = run(c.million_gen)
        if rc != 0:
            log(err)
            return None
    ref = c.path("million-ref")
    ref_cmd = ["build/vismask", "render", scene] + c.million_args + ["--out", ref, "--quiet"]
    stamp = c.path("million-ref.cmd")
    # The one-process run is reused when its command, binary and scene are
    # older than its outputs (CLUSTER_MILLION_REUSE=1; it takes minutes).
    reuse = (os.environ.get("CLUSTER_MILLION_REUSE") == "1" and os.path.exists(stamp) and
             open(stamp).read() == " ".join(ref_cmd) and os.path.exists(os.path.join(ref, "run.json")) and
             os.path.getmtime(os.path.join(ref, "run.json")) > max(os.path.getmtime("build/vismask"),
                                                                  os.path.getmtime(scene)))
    ref_wall = None
    if not reuse:
        shutil.rmtree(ref, ignore_errors=True)
        rc, err, ref_wall = run(ref_cmd)
        if rc != 0:
            log(err[-3000:])
            return None
        with open(stamp, "w") as f:
            f.write(" ".join(ref_cmd))
    rj = run_json(ref)
    m = {"ref": {"wall": ref_wall, "solve": rj["timings"]["solve_seconds"],
                 "init": rj["timings"]["init_seconds"], "rounds": rj["result"]["rounds"],
                 "patches": rj["counts"]["patches"], "polygons": rj["counts"].get("polygons"),
                 "predicted": rj["memory"]["predicted_bytes"],
                 "init_peak": rj["memory"]["init_peak_predicted_bytes"],
                 "peak_rss": rj["memory"]["peak_rss_bytes"],
                 "file_rss": rj["memory"]["file_rss_bytes"]}}
    d = c.path("million-%d" % c.million_nodes)
    fresh(d)
    cmd = ["tools/cluster-sim", "--nodes", str(c.million_nodes), "--link", "1gbit", "--mem", c.million_mem,
           "--report", os.path.join(d, "report.json"), "--", "render", scene] + c.million_args + \
          ["--out", os.path.join(d, "out"), "--quiet"]
    rc, err, _ = run(cmd)
    with open(os.path.join(d, "log.txt"), "w") as f:
        f.write(err)
    m["cmd"] = cmd
    m["code"] = rc
    m["log_tail"] = [l for l in err.splitlines() if l.startswith("vismask") or "ulimit" in l][-20:]
    if rc == 0:
        rj = run_json(os.path.join(d, "out"))
        rep = load_json(os.path.join(d, "report.json"))
        m["run"] = {"wall": rep["wall_seconds"], "solve": rj["timings"]["solve_seconds"],
                    "init": rj["timings"]["init_seconds"], "rounds": rj["result"]["rounds"],
                    "sent": rj["result"]["bytes_sent"], "ranks": rj["memory"]["ranks"],
                    "budget": rep["mem_budget"],
                    "identical": same_bytes(os.path.join(d, "out"), ref)}
    return m


def manifest(d):
    """DIR/manifest's lines as a dict ({} when there is none)."""
    try:
        with open(os.path.join(d, "manifest")) as f:
            return dict(l.rstrip("\n").split(" ", 1) for l in f if " " in l)
    except OSError:
        return {}


def rank_pid(parent, rank):
    """The pid of the vismask-mpi process of MPI rank `rank` among the
    descendants of `parent` (by OMPI_COMM_WORLD_RANK), or None."""
    key = ("OMPI_COMM_WORLD_RANK=%d" % rank).encode()
    for pid in os.listdir("/proc"):
        if not pid.isdigit():
            continue
        try:
            with open("/proc/%s/cmdline" % pid, "rb") as f:
                if b"vismask-mpi" not in f.read():
                    continue
            with open("/proc/%s/environ" % pid, "rb") as f:
                if key in f.read().split(b"\0"):
                    return int(pid)
        except OSError:
            continue
    return None


def resume_run(c):
    """Issue 43: the building on N simulated nodes, uninterrupted; then with
    --checkpoint (every round) and one node's rank killed (SIGKILL) once a
    checkpoint holds round K; then resumed on N - 1 nodes. Returns the
    figures (None if a step failed before anything could be compared)."""
    scene, args, n = c.building, c.resume_args, c.resume_nodes
    ref = c.path("resume-ref")
    shutil.rmtree(ref, ignore_errors=True)
    rc, err, ref_wall = run(["build/vismask", "render", scene] + args + ["--out", ref, "--quiet"])
    if rc != 0:
        log(err)
        return None
    r = {"nodes": n, "args": args, "kill_round": c.resume_kill_round, "victim": c.resume_victim}
    sim = ["tools/cluster-sim", "--nodes", str(n), "--link", "1gbit", "--report"]
    def sim_render(name, extra, more=lambda rj: {}):
        """A render on the N nodes into resume-NAME/out with `extra` options:
        its wall time (cluster-sim's), solve time and rounds, then more(its
        run.json), then whether its outputs are the one-process run's; None
        if it failed."""
        d = c.path("resume-" + name)
        fresh(d)
        out = os.path.join(d, "out")
        rc, err, wall = run(sim + [os.path.join(d, "report.json"), "--", "render", scene] + args +
                            ["--out", out, "--quiet"] + extra)
        if rc != 0:
            log(err[-3000:])
            return None
        rj = run_json(out)
        fig = {"wall": load_json(os.path.join(d, "report.json"))["wall_seconds"],
               "solve": rj["timings"]["solve_seconds"], "rounds": rj["result"]["rounds"]}
        fig.update(more(rj))
        fig["identical"] = same_bytes(out, ref)
        return fig

    # The uninterrupted run, and what a checkpoint a round costs.
    r["whole"] = sim_render("whole", [])
    if r["whole"] is None:
        return None
    r["every"] = sim_render(
        "every", ["--checkpoint", c.path("resume-every", "ck"), "--checkpoint-every", "0"],
        lambda rj: {"written": rj["checkpoint"]["written"],
                    "write_seconds": rj["checkpoint"]["rank0_write_seconds"],
                    "rank_bytes": rj["checkpoint"]["rank_bytes"]})
    if r["every"] is None:
        return None
    # Killed: rank `victim` (a whole node: its one rank) once the manifest holds round K.
    d = c.path("resume-killed")
    fresh(d)
    ck = os.path.join(d, "ck")
    cmd = sim + [os.path.join(d, "report.json"), "--", "render", scene] + args + \
        ["--out", os.path.join(d, "out"), "--quiet", "--checkpoint", ck, "--checkpoint-every", "0"]
    r["killed_cmd"] = cmd
    log("$ " + " ".join(shlex.quote(x) for x in cmd))
    t0 = time.monotonic()
    with open(os.path.join(d, "log.txt"), "w") as logf:
        p = subprocess.Popen(cmd, stdout=logf, stderr=subprocess.STDOUT)
        killed_at = None
        while p.poll() is None:
            if killed_at is None and int(manifest(ck).get("rounds", "0")) >= c.resume_kill_round:
                pid = rank_pid(p.pid, c.resume_victim)
                if pid is not None:
                    os.kill(pid, signal.SIGKILL)
                    killed_at = time.monotonic() - t0
                    r["killed_rounds"] = int(manifest(ck).get("rounds", "0"))
            time.sleep(0.05)
    r["killed"] = {"code": p.returncode, "wall": time.monotonic() - t0, "kill_seconds": killed_at}
    m = manifest(ck)
    r["checkpoint_rounds"] = int(m.get("rounds", "0"))
    r["checkpoint_shots"] = int(m.get("shots", "0"))
    if killed_at is None or not m:
        log("the node was not killed (the run ended first) or no checkpoint was written")
        return r
    # Resumed on N - 1 nodes: the environments stay 4x1x4 (--envs is given).
    d = c.path("resume-resumed")
    fresh(d)
    cmd = ["tools/cluster-sim", "--nodes", str(n - 1), "--link", "1gbit", "--report",
           os.path.join(d, "report.json"), "--", "render", scene] + args + \
        ["--out", os.path.join(d, "out"), "--quiet", "--resume", ck]
    r["resumed_cmd"] = cmd
    rc, err, wall = run(cmd)
    with open(os.path.join(d, "log.txt"), "w") as f:
        f.write(err)
    r["resumed"] = {"code": rc, "wall": wall}
    if rc == 0:
        rj = run_json(os.path.join(d, "out"))
        r["resumed"].update({"wall": load_json(os.path.join(d, "report.json"))["wall_seconds"],
                             "solve": rj["timings"]["solve_seconds"],
                             "rounds": rj["result"]["rounds"],
                             "from_rounds": rj["checkpoint"]["resumed_from_rounds"],
                             "identical": same_bytes(os.path.join(d, "out"), ref),
                             "identical_whole": same_bytes(os.path.join(d, "out"),
                                                           c.path("resume-whole", "out"))})
    return r
