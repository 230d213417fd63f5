"""Run by tests/cli/blender-plants.sh inside Blender: the plant instances stand where docs/plants.md says.

    blender -b --factory-startup -P tests/blender/test_plants.py -- REPO PLANTS.ply HEIGHTS.png SCENE.json

SCENE.json bakes a terrain layer (its heightmap HEIGHTS.png) and an ifs population over it whose
instances (PLANTS.ply, Z up) stand on it. Blender loads both through the recipes of docs/examples/blender/
(plants.py: Blender's PLY importer and a Geometry Nodes instance per plant; terrain.py: the plane
displaced by the heightmap). Checked here: the number of points and of instances against the
population enumerated by this script from the scene's maps; their positions (east, north) and
sizes against it; each instance's transform; and each plant standing on the displaced terrain as
Blender has it (its height within the heights of the four vertices around it, and a ray cast down
meeting the surface there), which a plant placed north-south mirrored would not be.
"""
import json
import math
import os
import sys

import bpy
import numpy as np
from mathutils import Vector

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from checks import ARGS as args, check, finish  # noqa: E402 (it puts the recipes on sys.path)

ROOT, PLY, PNG, SCENE = args[:4]
import plants as recipe  # noqa: E402
import terrain  # noqa: E402

scene = json.load(open(SCENE))
W, H = scene["size"]
ground = next(L for L in scene["layers"] if L["type"] == "terrain")
ifs = next(L for L in scene["layers"] if L["type"] == "ifs")
TB, FRAME = ground["bounds"], ifs["bounds"]
maps = [m[:6] for m in ifs["maps"]]


def population(cond_height, min_size):
    """Every plant's base and size in the IFS's units: C's base (the origin) under every word of maps."""
    scale = math.sqrt(abs(maps[0][0] * maps[0][3] - maps[0][1] * maps[0][2]))
    level, gen, out = [(0.0, 0.0)], 0, []
    while cond_height * scale**gen >= min_size:
        out += [(x, y, cond_height * scale**gen) for x, y in level
                if FRAME[0] <= x <= FRAME[1] and FRAME[2] <= y <= FRAME[3]]
        level = [(m[0] * x + m[1] * y + m[4], m[2] * x + m[3] * y + m[5]) for x, y in level for m in maps]
        gen += 1
    return out


px = math.sqrt(W / (FRAME[1] - FRAME[0]) * H / (FRAME[3] - FRAME[2]))  # pixels per IFS unit
ref = population(ifs["condensation"]["height"], ifs["instances-min-size"] / px)
# the IFS frame onto the image, the image onto the terrain's bounds (x east, y north)
ex, ey = (TB[1] - TB[0]) / (FRAME[1] - FRAME[0]), (TB[3] - TB[2]) / (FRAME[3] - FRAME[2])
want = sorted((TB[0] + (x - FRAME[0]) * ex, TB[2] + (y - FRAME[2]) * ey, s * math.sqrt(ex * ey)) for x, y, s in ref)

bpy.ops.wm.read_factory_settings(use_empty=True)
land = terrain.displaced_plane(PNG, TB)
pts = recipe.instances(PLY)
deps = bpy.context.evaluated_depsgraph_get()
placed = [i.matrix_world.copy() for i in deps.object_instances if i.is_instance and i.parent.original == pts]
P = np.array([tuple(pts.matrix_world @ v.co) for v in pts.data.vertices])
check("Blender's importer reads one point per plant of the population", len(P) == len(ref) > 20,
      "%d points, %d plants" % (len(P), len(ref)))
check("one instance per point", len(placed) == len(P), "%d instances" % len(placed))
got = sorted((m.translation.x, m.translation.y, m.to_scale()[0]) for m in placed)
worst = max((max(abs(a[0] - b[0]), abs(a[1] - b[1])), abs(a[2] - b[2]) / b[2]) for a, b in zip(got, want))
check("instances at the plants' places (east, north) and of their heights", len(got) == len(want) and
      worst[0] < 1e-3 * (TB[1] - TB[0]) and worst[1] < 1e-5, "worst %.3g units, %.3g relative size" % worst)
check("instances upright, turned about Z only",
      all(abs((m.to_3x3().normalized() @ Vector((0, 0, 1))).z - 1) < 1e-5 for m in placed))
check("instances stand on their points", all(min((m.translation - Vector(p)).length for p in P[:, :3]) < 1e-4
                                              for m in placed))

# on the ground, as Blender displaced it
mesh = land.evaluated_get(deps).to_mesh()
V = np.array([tuple(land.matrix_world @ v.co) for v in mesh.vertices])
dx, dy = (TB[1] - TB[0]) / W, (TB[3] - TB[2]) / H
grid = np.full((H, W), np.nan)
grid[np.rint((V[:, 1] - TB[2]) / dy - 0.5).astype(int), np.rint((V[:, 0] - TB[0]) / dx - 0.5).astype(int)] = V[:, 2]
step = (np.nanmax(grid) - np.nanmin(grid)) / 65535


def corners(x, y):
    i, j = (x - TB[0]) / dx - 0.5, (y - TB[2]) / dy - 0.5
    i0, j0 = min(max(int(math.floor(i)), 0), W - 2), min(max(int(math.floor(j)), 0), H - 2)
    return grid[j0:j0 + 2, i0:i0 + 2]


def on_ground(p, y):
    c = corners(p[0], y)
    return c.min() - step <= p[2] <= c.max() + step


inside = [p for p in P if TB[0] + dx / 2 <= p[0] <= TB[1] - dx / 2 and TB[2] + dy / 2 <= p[1] <= TB[3] - dy / 2]
ok = sum(on_ground(p, p[1]) for p in inside)
check("every plant between the heights of the four vertices around it", ok == len(inside) > 20,
      "%d of %d" % (ok, len(inside)))
hits = []
for p in inside:
    hit, loc, _, _ = land.ray_cast(land.matrix_world.inverted() @ Vector((p[0], p[1], 1e4)), Vector((0, 0, -1)),
                                   depsgraph=deps)
    c = corners(p[0], p[1])
    hits.append(hit and abs((land.matrix_world @ loc).z - p[2]) <= c.max() - c.min() + step)
check("a ray cast down meets the displaced terrain at each plant's height", all(hits),
      "%d of %d" % (sum(hits), len(hits)))
mirrored = sum(on_ground(p, TB[2] + TB[3] - p[1]) for p in inside)
check("north-south mirrored, most plants would float or sink", mirrored < len(inside) / 2,
      "%d of %d would stand on the ground" % (mirrored, len(inside)))

finish()
