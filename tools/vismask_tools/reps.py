"""Repeated runs of one command: each run's output directory holds its
run.json and a `time` file (wall, user and system seconds of the command and
its children, as written by `timed_run`). Counts (shots, rounds, packets,
bytes, rays) do not depend on timing and must be the same in every run;
timings are given as median (min–max)."""

import os
import sys

from .files import run_json
from .runner import timed
from .stats import fmt_spread, median


def timed_run(cmd, out, log_path, env=None):
    """`cmd --out OUT --quiet` with its output in log_path and its times in
    OUT/time ("wall user system"). A failing command ends the script with its
    log's tail."""
    rc, wall, user, system = timed(list(cmd) + ["--out", out, "--quiet"], log_path, env)
    if rc != 0:
        with open(log_path) as f:
            tail = f.read()[-3000:]
        sys.exit(f"{' '.join(str(c) for c in cmd)}: exit status {rc}; {log_path} ends:\n{tail}")
    os.makedirs(out, exist_ok=True)
    with open(os.path.join(out, "time"), "w") as f:
        f.write(f"{wall:.3f} {user:.3f} {system:.3f}\n")


def cpu_seconds(out):
    """User + system seconds of a timed run."""
    with open(os.path.join(out, "time")) as f:
        _, user, system = (float(x) for x in f.read().split())
    return user + system


class Runs:
    """Runs of one command, by output directory (named in messages by their
    base names)."""

    def __init__(self, dirs):
        self.dirs = list(dirs)
        self.json = [run_json(d) for d in self.dirs]

    def values(self, section, key):
        return [j[section][key] for j in self.json]

    def same(self, section, key):
        """The value of a count, which must be the same in every run (the
        script ends with a message if it is not)."""
        vals = self.values(section, key)
        for d, v in zip(self.dirs, vals):
            if v != vals[0]:
                sys.exit(f"{key} differs between runs {os.path.basename(self.dirs[0])} "
                         f"({vals[0]}) and {os.path.basename(d)} ({v})")
        return vals[0]

    def median(self, section, key):
        return median(self.values(section, key))

    def spread(self, section, key, fmt="{:.2f}"):
        """"median (min–max)", also for a single run."""
        return fmt_spread(self.values(section, key), fmt, alone=False)

    def cpu(self):
        return [cpu_seconds(d) for d in self.dirs]

    def cpu_spread(self, fmt="{:.2f}"):
        return fmt_spread(self.cpu(), fmt, alone=False)

    def median_cpu(self):
        return median(self.cpu())
