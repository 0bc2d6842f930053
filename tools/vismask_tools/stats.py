"""Small statistics for reports: medians with their spread."""

import statistics


def median(xs):
    return statistics.median(xs)


def spread(xs):
    """(median, min, max) of a non-empty list."""
    return statistics.median(xs), min(xs), max(xs)


def fmt_spread(xs, fmt="{:.2f}", alone=True):
    """"median (min-max)" of a list, or (alone=True) the one value of a list
    of one."""
    m, lo, hi = spread(xs)
    if alone and len(xs) == 1:
        return fmt.format(m)
    return f"{fmt.format(m)} ({fmt.format(lo)}–{fmt.format(hi)})"


def pct(x, digits=2):
    """A fraction (a number or its text, as read from a CSV) as a percentage string."""
    return f"{100 * float(x):.{digits}f}%"
