"""Plots through gnuplot (gnuplot-nox; tools/install-deps installs it)."""

import shutil
import subprocess
import sys


def gnuplot(script):
    """Runs a gnuplot script. Scripts ask for `pngcairo`; where this gnuplot
    has no cairo terminal the plain `png` terminal draws it instead."""
    if shutil.which("gnuplot") is None:
        sys.exit("gnuplot not found: tools/install-deps installs gnuplot-nox")
    p = subprocess.run(["gnuplot"], input=script, text=True, capture_output=True)
    if p.returncode != 0 and "pngcairo" in script:
        p = subprocess.run(["gnuplot"], input=script.replace("pngcairo", "png"), text=True,
                           capture_output=True)
    if p.returncode != 0:
        sys.exit("gnuplot failed:\n" + p.stderr)
