"""Files the tools read and write: JSON (run.json), CSV (patches.csv and
the reports' tables), PFM and PGM images, and 8-bit PNG."""

import json
import math
import os
import struct
import zlib

def load_json(path):
    with open(path) as f:
        return json.load(f)


def run_json(out_dir):
    """The run.json of a vismask output directory."""
    return load_json(os.path.join(out_dir, "run.json"))


def read_csv(path):
    with open(path) as f:
        rows = [line.rstrip("\n").split(",") for line in f if line.strip()]
    return rows[0], rows[1:]


def csv_dicts(path):
    """A CSV file's rows as dicts keyed by its header."""
    header, rows = read_csv(path)
    return [dict(zip(header, r)) for r in rows]


def write_csv(path, header, rows):
    with open(path, "w") as f:
        f.write(",".join(header) + "\n")
        for r in rows:
            f.write(",".join(fmt(v) for v in r) + "\n")


def fmt(v):
    if isinstance(v, float):
        return f"{v:.6g}"
    return str(v)


# --- images ------------------------------------------------------------------

def read_pfm(path, top_first=True):
    """A colour PFM as (width, height, floats), row 0 at the top (or, with
    top_first=False, in the file's order: the bottom row first)."""
    with open(path, "rb") as f:
        data = f.read()
    parts = data.split(b"\n", 3)
    assert parts[0] == b"PF", path
    w, h = (int(x) for x in parts[1].split())
    scale = float(parts[2])
    fmt_ = "<" if scale < 0 else ">"
    px = struct.unpack(f"{fmt_}{w * h * 3}f", parts[3][: w * h * 12])
    if not top_first:
        return w, h, list(px)
    rows = [px[(h - 1 - y) * w * 3:(h - y) * w * 3] for y in range(h)]
    return w, h, [v for r in rows for v in r]


def read_pgm(path):
    """A binary PGM (P5, maxval <= 255) as (width, height, values)."""
    with open(path, "rb") as f:
        data = f.read()
    parts = data.split(maxsplit=4)
    assert parts[0] == b"P5", path
    w, h = int(parts[1]), int(parts[2])
    # The pixels are the file's last w*h bytes (splitting would eat pixel
    # values that look like whitespace).
    return w, h, list(data[len(data) - w * h:])


def write_pfm(path, w, h, px):
    with open(path, "wb") as f:
        f.write(f"PF\n{w} {h}\n-1.0\n".encode())
        for y in range(h - 1, -1, -1):
            f.write(struct.pack(f"<{w * 3}f", *px[y * w * 3:(y + 1) * w * 3]))


def write_png(path, w, h, rgb):
    """8-bit RGB PNG from a flat list of w*h*3 ints (row 0 at the top)."""
    raw = b"".join(b"\0" + bytes(rgb[y * w * 3:(y + 1) * w * 3]) for y in range(h))

    def chunk(tag, body):
        return struct.pack(">I", len(body)) + tag + body + struct.pack(
            ">I", zlib.crc32(tag + body) & 0xffffffff)

    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0))
                + chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b""))


def write_hdr(path, w, h, texel):
    """A Radiance HDR file (uncompressed RGBE scanlines, rows top to bottom):
    texel(i, j) gives the linear RGB of column i, row j (0 the top)."""
    def rgbe(r, g, b):
        v = max(r, g, b)
        if v < 1e-32:
            return bytes(4)
        m, e = math.frexp(v)
        k = m * 256.0 / v
        return bytes([int(r * k), int(g * k), int(b * k), e + 128])
    with open(path + ".tmp", "wb") as f:
        f.write(b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y %d +X %d\n" % (h, w))
        for j in range(h):
            f.write(b"".join(rgbe(*texel(i, j)) for i in range(w)))
    os.replace(path + ".tmp", path)
