"""A fractalbake heightmap (16-bit PNG) as a displaced plane in Blender (docs/terrain.md, "Blender").

    blender -b --factory-startup --python-exit-code 1 -P docs/examples/blender/terrain.py -- HEIGHTS.png
        [--bounds XMIN,XMAX,YMIN,YMAX] [--range LO,HI] [--save OUT.blend]

A grid with one vertex at each pixel's centre, on the plane z = LO, displaced along +Z by a Displace
modifier reading the PNG through its UV map without interpolation: a vertex's height is LO + (HI - LO)
v / 65535 for its pixel's value v. LO and HI come from the PNG's text chunks (fractalbake/height-min and -max, written by
every --heightmap PNG) unless --range gives them. --bounds is the heightmap's extent in world units
(a terrain's bounds, in its survey's units; default: one unit a pixel from the origin): the image's
top row is the north edge, at YMAX, and its left column the west edge, at XMIN, so Blender's +X is
east and +Y north. --save writes the .blend.
"""
import os
import struct
import sys
import zlib

import bpy
import numpy as np


def png_range(path):
    """(height-min, height-max) from a fractalbake heightmap PNG's tEXt chunks, or None."""
    data, at, text = open(path, "rb").read(), 8, {}
    while at + 8 <= len(data):
        size, kind = struct.unpack(">I4s", data[at:at + 8])
        if kind == b"tEXt":
            key, _, value = data[at + 8:at + 8 + size].partition(b"\0")
            text[key.decode("latin-1")] = value.decode("latin-1")
        elif kind == b"zTXt":
            key, _, value = data[at + 8:at + 8 + size].partition(b"\0")
            text[key.decode("latin-1")] = zlib.decompress(value[1:]).decode("latin-1")
        at += 12 + size
    lo, hi = text.get("fractalbake/height-min"), text.get("fractalbake/height-max")
    return (float(lo), float(hi)) if lo is not None and hi is not None else None


def displaced_plane(path, bounds=None, height_range=None, name="terrain"):
    """The object: a grid of the heightmap's pixel centres over bounds, displaced by the heightmap."""
    img = bpy.data.images.load(path, check_existing=True)
    img.colorspace_settings.name = "Non-Color"  # the 16-bit values as they are, no sRGB curve
    w, h = img.size
    xmin, xmax, ymin, ymax = bounds or (0.0, float(w), 0.0, float(h))
    lo, hi = height_range or png_range(path) or (0.0, 1.0)
    dx, dy = (xmax - xmin) / w, (ymax - ymin) / h
    # one vertex at each pixel centre: x = xmin + (i + 1/2) dx, y = ymin + (j + 1/2) dy, j from the bottom row
    bpy.ops.mesh.primitive_grid_add(x_subdivisions=w - 1, y_subdivisions=h - 1, size=1.0)
    obj = bpy.context.active_object
    obj.name = name
    obj.scale = ((w - 1) * dx, (h - 1) * dy, 1.0)
    obj.location = ((xmin + xmax) / 2, (ymin + ymax) / 2, lo)
    bpy.ops.object.transform_apply(location=False, rotation=False, scale=True)
    # the grid's UVs run 0..1 from the first vertex to the last; the texture's pixel i is centred at
    # u = (i + 1/2) / w: map the one onto the other
    uv = obj.data.uv_layers.active.data
    co = np.empty(2 * len(uv), dtype=np.float32)
    uv.foreach_get("uv", co)
    co = co.reshape(-1, 2)
    co[:, 0] = (co[:, 0] * (w - 1) + 0.5) / w
    co[:, 1] = (co[:, 1] * (h - 1) + 0.5) / h
    uv.foreach_set("uv", co.ravel())
    tex = bpy.data.textures.new(name + " heights", type="IMAGE")
    tex.image = img
    tex.extension = "EXTEND"
    tex.use_mipmap = False
    tex.use_interpolation = False  # each vertex takes its own pixel (Blender's filter blurs, most at the edges)
    mod = obj.modifiers.new("heights", "DISPLACE")
    mod.texture = tex
    mod.texture_coords = "UV"
    mod.direction = "Z"
    mod.mid_level = 0.0
    mod.strength = hi - lo
    return obj


def main(argv):
    import argparse
    ap = argparse.ArgumentParser(prog="terrain.py", description="a fractalbake heightmap as a displaced plane")
    ap.add_argument("heightmap")
    ap.add_argument("--bounds", help="XMIN,XMAX,YMIN,YMAX in world units")
    ap.add_argument("--range", help="LO,HI: the heights of 0 and 65535")
    ap.add_argument("--save")
    a = ap.parse_args(argv)
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bounds = [float(v) for v in a.bounds.split(",")] if a.bounds else None
    rng = [float(v) for v in a.range.split(",")] if a.range else None
    obj = displaced_plane(a.heightmap, bounds, rng)
    mesh = obj.evaluated_get(bpy.context.evaluated_depsgraph_get()).to_mesh()
    z = [(obj.matrix_world @ v.co).z for v in mesh.vertices]
    print("terrain.py: %s: %d vertices, heights %.6g to %.6g" % (a.heightmap, len(z), min(z), max(z)))
    if a.save:
        bpy.ops.wm.save_as_mainfile(filepath=os.path.abspath(a.save))


if __name__ == "__main__":
    main(sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else [])
