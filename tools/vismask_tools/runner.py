"""Running vismask from the report scripts: which binary, and a run cache.

A cached run keeps its command line in OUT/args.txt; the same command line
later reuses OUT's files instead of running again."""

import os
import resource
import subprocess
import sys
import time

from . import ROOT
from .files import run_json


def log(msg):
    """A progress line on stderr."""
    print(msg, file=sys.stderr, flush=True)


def vismask_bin(name="vismask"):
    """$VISMASK_BIN (for "vismask"), else build/NAME ($BUILD or build/)."""
    if name == "vismask" and os.environ.get("VISMASK_BIN"):
        return os.environ["VISMASK_BIN"]
    return os.path.join(os.environ.get("BUILD", os.path.join(ROOT, "build")), name)


def shown(cmd):
    """A command line as the reports print it: paths under the repository
    relative to it, the binary as its base name."""
    out = [os.path.basename(cmd[0])]
    for c in cmd[1:]:
        c = str(c)
        out.append(os.path.relpath(c, ROOT) if c.startswith(ROOT) else c)
    return " ".join(out)


def render(scene, args, out, fresh=False, quiet=True, binary=None):
    """`vismask render SCENE ARGS --out OUT [--quiet]`, unless the same command
    already ran into OUT (fresh=True always runs). Returns OUT's run.json.
    A failing run raises subprocess.CalledProcessError."""
    cmd = [binary or vismask_bin(), "render", scene] + [str(a) for a in args] + ["--out", out]
    if quiet:
        cmd.append("--quiet")
    key = shown(cmd)[len(os.path.basename(cmd[0])) + 1:]
    stamp = os.path.join(out, "args.txt")
    if not fresh and os.path.exists(stamp):
        with open(stamp) as f:
            if f.read() == key:
                return run_json(out)
    log(f"  vismask {key}")
    subprocess.run(cmd, check=True)
    with open(stamp, "w") as f:
        f.write(key)
    return run_json(out)


def run(cmd, **kw):
    """Runs a command, capturing its text output; returns (returncode,
    stdout, stderr, seconds)."""
    t0 = time.time()
    p = subprocess.run([str(c) for c in cmd], capture_output=True, text=True, **kw)
    return p.returncode, p.stdout, p.stderr, time.time() - t0


def timed(cmd, log_path, env=None):
    """Runs a command with its stdout and stderr into log_path; returns
    (returncode, wall seconds, user seconds, system seconds), the CPU times
    those of the command and every child it waited for (as bash's `time`)."""
    r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.monotonic()
    with open(log_path, "w") as log:
        rc = subprocess.run([str(c) for c in cmd], stdout=log, stderr=subprocess.STDOUT,
                            env=env).returncode
    wall = time.monotonic() - t0
    r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    return rc, wall, r1.ru_utime - r0.ru_utime, r1.ru_stime - r0.ru_stime
