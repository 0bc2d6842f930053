"""Facts about the machine and the commit, for the head of a report."""

import os
import subprocess
import time

from . import ROOT


def sh(cmd):
    try:
        return subprocess.run(cmd, shell=True, capture_output=True, text=True).stdout.strip()
    except OSError:
        return ""


def commit_state(paths=("src", "include", "platform")):
    """(the short commit or "unknown", whether `paths` have local changes)."""
    short = sh(f"git -C {ROOT} rev-parse --short HEAD") or "unknown"
    return short, bool(sh(f"git -C {ROOT} status --porcelain -- " + " ".join(paths)))


def commit():
    """The short commit, marked when src/, include/ or platform/ have local changes."""
    short, dirty = commit_state()
    return ("?" if short == "unknown" else short) + (" (with local changes)" if dirty else "")


def cores():
    """The cores this process may run on (as nproc counts them)."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:
        return os.cpu_count()


def threads_per_core():
    return sh("lscpu | sed -n 's/^Thread(s) per core: *//p'") or "?"


def kernel():
    return os.uname().release


def loadavg():
    return " ".join(f"{x:.2f}" for x in os.getloadavg())


def facts():
    """A dict: date (UTC), commit, cpu model, cores, memory (GiB), compiler."""
    mem = 0
    try:
        with open("/proc/meminfo") as f:
            for line in f:
                if line.startswith("MemTotal:"):
                    mem = int(line.split()[1]) / 2**20
    except OSError:
        pass
    return dict(date=time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()), commit=commit(),
                cpu=sh("lscpu | sed -n 's/^Model name: *//p'") or "?", cores=os.cpu_count(),
                mem_gib=round(mem, 1), compiler=sh("${CXX:-g++} --version | head -1") or "?",
                load=loadavg())
