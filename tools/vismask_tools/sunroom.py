"""The sun room (issue 41's sun-shadow goal): a closed 5 x 3 x 5 m room with
a window in its west wall (x = 0) and a low block, lit only by a sun
(`--sun`) that shines in through the window at an angle, so that a sunlit
parallelogram with straight edges lands on the floor; the camera stands
inside, in the far corner, looking at it. Written as OBJ + MTL by
tools/gen-sunroom (and by the experiments' sun step) with gen-building's
writer: metres, +y up, every face one-sided looking into the air. The
floor's sunlit parallelogram's four edges (`edges`)
follow from the geometry, so the edge measure (sun_edge.py) knows where to
look without finding the edges in an image."""

import importlib.machinery
import importlib.util
import math
import os

from . import ROOT
from .sun_edge import floor_edges
from .sun_edge import patch_centre as centre_of

ROOM = (5.0, 3.0, 5.0)            # inside, x, y, z
WINDOW_Z = (1.9, 3.1)             # the opening in the wall x = 0
WINDOW_Y = (0.9, 2.3)
BLOCK = ((3.6, 0.0, 0.5), (4.4, 0.8, 1.3))  # a low block, out of the sun
# Towards the sun: from the west (-x), 37 degrees up, a little from -z...
# so the light runs +x, down and towards -z.
SUN_TOWARD = (-1.0, 0.8, 0.35)
SUN_IRRADIANCE = (3.0, 2.9, 2.7)  # W/m^2 facing the sun (Cycles' Strength)
SUN_DEGREES = 0.53                # the real sun's angular diameter
CAMERA = "3.6,1.4,3.4,1.8,0.1,1.7,0,1,0,50"

MATERIALS = """\
# tools/gen-sunroom materials: Kd diffuse reflectance; nothing emits (the sun lights it).
newmtl wall
Kd 0.7 0.7 0.68

newmtl floor
Kd 0.45 0.38 0.3

newmtl ceiling
Kd 0.8 0.8 0.8

newmtl block
Kd 0.6 0.12 0.1
"""


def sun_arg():
    """vismask's (and tools/reference's) --sun value."""
    return ",".join("%g" % v for v in SUN_TOWARD + SUN_IRRADIANCE + (SUN_DEGREES,))


def _building():
    """gen-building's OBJ writer (rectangles and boxes), shared, not copied."""
    path = os.path.join(ROOT, "tools", "gen-building")
    loader = importlib.machinery.SourceFileLoader("gen_building", path)
    spec = importlib.util.spec_from_loader("gen_building", loader)
    mod = importlib.util.module_from_spec(spec)
    loader.exec_module(mod)
    return mod


def obj_lines():
    b = _building()
    obj = b.Obj()
    sx, sy, sz = ROOM
    obj.lines.append("o room")
    obj.rect("floor", 1, 0.0, 1, (0.0, sz), (0.0, sx))
    obj.rect("ceiling", 1, sy, -1, (0.0, sz), (0.0, sx))
    # The west wall around the window (plane x = 0, (b, c) = (y, z)).
    z0, z1 = WINDOW_Z
    y0, y1 = WINDOW_Y
    for yr, zr in (((0.0, sy), (0.0, z0)), ((0.0, sy), (z1, sz)),
                   ((0.0, y0), (z0, z1)), ((y1, sy), (z0, z1))):
        obj.rect("wall", 0, 0.0, 1, yr, zr)
    obj.rect("wall", 0, sx, -1, (0.0, sy), (0.0, sz))
    obj.rect("wall", 2, 0.0, 1, (0.0, sx), (0.0, sy))
    obj.rect("wall", 2, sz, -1, (0.0, sx), (0.0, sy))
    obj.lines.append("o block")
    b.box(obj, "block", *BLOCK)
    return obj.lines


def write(path):
    """Writes the room to PATH (.obj) and its MTL beside it; the same bytes
    every time."""
    mtl = path[:-4] + ".mtl"
    header = ("# tools/gen-sunroom: a 5 x 3 x 5 m room with a window in its west wall, "
              "lit by --sun %s.\n"
              "# Metres, +y up; every face looks into the air, counter-clockwise from its "
              "front.\nmtllib %s\n" % (sun_arg(), os.path.basename(mtl)))
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    for p, text in ((mtl, MATERIALS), (path, header + "\n".join(obj_lines()) + "\n")):
        with open(p + ".tmp", "w", newline="\n") as f:
            f.write(text)
        os.replace(p + ".tmp", p)


def edges():
    """The floor's sunlit parallelogram (the window seen along the sun's
    central direction) as its four edges (name, A, B), each cast by one side
    of the window; the lit side is the patch's centre's side."""
    z0, z1 = WINDOW_Z
    y0, y1 = WINDOW_Y
    window = [(0.0, y0, z0), (0.0, y0, z1), (0.0, y1, z1), (0.0, y1, z0)]
    return floor_edges(window, SUN_TOWARD, ["sill", "north jamb", "lintel", "south jamb"])


def throw(edge_name):
    """The distance, along the sun's light, from the edge's casting window
    edge to the floor at its middle (its penumbra is about this times the
    disc's angle across, before the floor's slant)."""
    tx, ty, tz = SUN_TOWARD
    n = math.sqrt(tx * tx + ty * ty + tz * tz)
    ys = {"sill": [WINDOW_Y[0]], "lintel": [WINDOW_Y[1]]}.get(edge_name, list(WINDOW_Y))
    return sum(y / ty * n for y in ys) / len(ys)


def patch_centre():
    return centre_of(edges())
