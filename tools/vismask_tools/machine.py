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


def commit():
    """The short commit, marked when src/, include/ or platform/ have local changes."""
    c = sh(f"git -C {ROOT} rev-parse --short HEAD") or "?"
    if sh(f"git -C {ROOT} status --porcelain -- src include platform"):
        c += " (with local changes)"
    return c


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
