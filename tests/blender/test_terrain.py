"""Run by tests/cli/blender-terrain.sh inside Blender: a heightmap PNG displaces a plane as docs/terrain.md says.

    blender -b --factory-startup -P tests/blender/test_terrain.py -- REPO HEIGHTS.png XMIN,XMAX,YMIN,YMAX

HEIGHTS.png is the heightmap of a terrain of survey points with no insertions (a plane of triangles):
corners at height 0 over XMIN..XMAX x YMIN..YMAX, a square plateau at 40 in the north-east (140..170
east, 60..90 north) and one at 10 in the south-west (20..60, 10..40). docs/examples/blender/terrain.py
(the recipe docs/terrain.md gives) builds the displaced plane; here every vertex's height is checked
against the PNG decoded by this script (its first row the north edge), and the plateaus' heights at
their places against the survey itself: a heightmap turned upside down or mirrored puts the highest
one elsewhere, which the checks at its mirror images show.
"""
import os
import struct
import sys
import zlib

import bpy
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from checks import ARGS as args, check, finish  # noqa: E402 (it puts the recipes on sys.path)

ROOT, PNG = args[0], args[1]
XMIN, XMAX, YMIN, YMAX = (float(v) for v in args[2].split(","))
import terrain as recipe  # noqa: E402

def read_png16(path):
    """A 16-bit grey PNG's samples, rows top first, and its text chunks: a reader of its own."""
    data, at, idat, text = open(path, "rb").read(), 8, b"", {}
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    while at < len(data):
        size, kind = struct.unpack(">I4s", data[at:at + 8])
        body = data[at + 8:at + 8 + size]
        if kind == b"IHDR":
            w, h, depth, colour, _, _, interlace = struct.unpack(">IIBBBBB", body)
            assert (depth, colour, interlace) == (16, 0, 0), (depth, colour, interlace)
        elif kind == b"IDAT":
            idat += body
        elif kind == b"tEXt":
            k, _, v = body.partition(b"\0")
            text[k.decode()] = v.decode()
        at += 12 + size
    raw, stride, bpp = zlib.decompress(idat), 2 * w, 2
    rows, prev = [], bytearray(stride)
    for y in range(h):
        f, line = raw[y * (stride + 1)], bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for i in range(stride):
            a = line[i - bpp] if i >= bpp else 0
            b, c = prev[i], prev[i - bpp] if i >= bpp else 0
            if f == 1:
                line[i] = (line[i] + a) & 255
            elif f == 2:
                line[i] = (line[i] + b) & 255
            elif f == 3:
                line[i] = (line[i] + (a + b) // 2) & 255
            elif f == 4:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                line[i] = (line[i] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
        rows.append(struct.unpack(">%dH" % w, line))
        prev = line
    return np.array(rows, dtype=np.float64), text


samples, text = read_png16(PNG)
H, W = samples.shape
LO, HI = float(text["fractalbake/height-min"]), float(text["fractalbake/height-max"])
step = (HI - LO) / 65535

bpy.ops.wm.read_factory_settings(use_empty=True)
obj = recipe.displaced_plane(PNG, (XMIN, XMAX, YMIN, YMAX))
mesh = obj.evaluated_get(bpy.context.evaluated_depsgraph_get()).to_mesh()
co = np.array([tuple(obj.matrix_world @ v.co) for v in mesh.vertices])
check("one vertex per pixel", len(co) == W * H, "%d vertices for %d x %d pixels" % (len(co), W, H))

# every vertex: its pixel (x east from the left column, y north from the bottom row) in the PNG
dx, dy = (XMAX - XMIN) / W, (YMAX - YMIN) / H
i, j = (co[:, 0] - XMIN) / dx - 0.5, (co[:, 1] - YMIN) / dy - 0.5
check("vertices at the pixel centres over the bounds",
      np.abs(i - np.rint(i)).max() < 1e-3 and np.abs(j - np.rint(j)).max() < 1e-3 and
      np.rint(i).min() == 0 and np.rint(i).max() == W - 1 and np.rint(j).min() == 0 and np.rint(j).max() == H - 1)
i, j = np.rint(i).astype(int), np.rint(j).astype(int)
want = LO + step * samples[H - 1 - j, i]  # the PNG's first row is the north edge, the top of +Y
err = np.abs(co[:, 2] - want)
check("every vertex at its pixel's height, the PNG's first row north", err.max() < 1e-5 * max(abs(LO), abs(HI), 1),
      "worst %.3g at (%.2f, %.2f)" % (err.max(), *co[err.argmax(), :2]))


def height_at(x, y):
    k = np.argmin((co[:, 0] - x) ** 2 + (co[:, 1] - y) ** 2)
    return co[k, 2]


# the survey's plateaus: every vertex a pixel inside them at their height (within half a 16-bit step)
for (x0, x1, y0, y1, z) in ((140, 170, 60, 90, 40.0), (20, 60, 10, 40, 10.0)):
    inside = (co[:, 0] > x0 + dx) & (co[:, 0] < x1 - dx) & (co[:, 1] > y0 + dy) & (co[:, 1] < y1 - dy)
    worst = np.abs(co[inside, 2] - z).max()
    check("the plateau over %g..%g east, %g..%g north at height %g" % (x0, x1, y0, y1, z),
          inside.sum() > 100 and worst <= step / 2 + 1e-4 * z, "%d vertices, worst %.3g" % (inside.sum(), worst))
    if z != 40.0:
        continue
    # the highest place of the survey, so nothing else is as high
    cx, cy = (x0 + x1) / 2, (y0 + y1) / 2
    for mx, my, what in ((cx, YMIN + YMAX - cy, "north-south"), (XMIN + XMAX - cx, cy, "east-west"),
                         (XMIN + XMAX - cx, YMIN + YMAX - cy, "both ways")):
        h = height_at(mx, my)
        check("the plateau at %g is not at its %s mirror image (%g, %g)" % (z, what, mx, my), abs(h - z) > 10,
              "height %.3f there" % h)

finish()
