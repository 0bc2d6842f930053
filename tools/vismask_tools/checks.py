"""Checks of one vismask output directory: no NaN, Inf or negative value in
patches.csv's b or in image.pfm, and the energy ledger of run.json."""
import math

from .files import read_pfm, run_json


def check(out):
    """Returns a dict: bad_b, bad_pixels (non-finite or negative counts),
    min_b, max_b, ledger (max over channels of |residual| / emitted),
    and the run.json it read."""
    bad_b, min_b, max_b, n = 0, math.inf, -math.inf, 0
    with open(out + "/patches.csv") as f:
        next(f)
        for line in f:
            cols = line.rstrip("\n").split(",")
            for x in cols[15:18]:
                v = float(x)
                n += 1
                if not math.isfinite(v) or v < 0:
                    bad_b += 1
                else:
                    min_b, max_b = min(min_b, v), max(max_b, v)
    _, _, pixels = read_pfm(out + "/image.pfm")
    bad_pixels = sum(1 for v in pixels if not math.isfinite(v) or v < 0)
    run = run_json(out)
    e = run["energy"]
    ledger = 0.0
    for c in range(3):
        em = e["emitted"][c]
        res = em - e["absorbed"][c] - e["escaped"][c] - e["unshot"][c]
        ledger = max(ledger, abs(res) / em if em > 0 else abs(res))
    return {"bad_b": bad_b, "bad_pixels": bad_pixels, "min_b": min_b, "max_b": max_b,
            "values": n, "ledger": ledger, "run": run,
            "max_pixel": max(v for v in pixels if math.isfinite(v)) if pixels else 0.0}
