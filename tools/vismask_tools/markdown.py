"""Markdown for the generated docs: tables, and sections replaced in place."""


def table(header, rows):
    """A Markdown table's lines from a header and rows of cells (str()ed)."""
    out = ["| " + " | ".join(str(h) for h in header) + " |",
           "|" + "---|" * len(header)]
    for r in rows:
        out.append("| " + " | ".join(str(c) for c in r) + " |")
    return out


def replace_section(text, heading, lines):
    """`text` with the section starting at the line `heading` (up to the next
    heading of the same level, or the end) replaced by `lines`; the section
    is appended when `text` has none."""
    level = heading.split(" ", 1)[0]
    src = text.split("\n")
    start = next((i for i, line in enumerate(src) if line.strip() == heading), None)
    new = [line.rstrip("\n") for line in lines]
    if start is None:
        return text.rstrip("\n") + "\n\n" + "\n".join(new) + "\n"
    end = next((i for i in range(start + 1, len(src))
                if src[i].startswith(level + " ") and not src[i].startswith(level + "#")), len(src))
    tail = src[end:]
    return "\n".join(src[:start] + new + ([""] if tail else []) + tail).rstrip("\n") + "\n"


def replace_marked(text, begin, end, lines, before):
    """`text` with the part from the line `begin` to the line `end` (markers
    included; `lines` holds them) replaced by `lines`; when there is no such
    part, `lines` and a blank line go just before the line `before`."""
    new = "\n".join(lines)
    if begin in text:
        a, b = text.index(begin), text.index(end) + len(end)
        return text[:a] + new + text[b:]
    at = text.index(before)
    return text[:at] + new + "\n\n" + text[at:]


def skipped(ctx, w, step, table_csv):
    """For a step's section of RESULTS.md: when the step wrote STEP-skipped.txt
    or not its table, writes why and returns True."""
    import os
    skip = ctx.result(f"{step}-skipped.txt")
    if not os.path.exists(skip) and os.path.exists(ctx.result(table_csv)):
        return False
    why = open(skip).read().strip() if os.path.exists(skip) else f"no results (tools/experiments {step})"
    w(f"**Skipped**: {why}.\n")
    return True
