"""Run by tests/cli/blender-sky.sh inside Blender: the lat-long sky lights Blender where docs/sky.md says.

    blender -b --factory-startup -P tests/blender/test_sky.py -- REPO SKY.exr R T0 PSI0 FOV

SKY.exr is a julia layer, latlong, c = 0 and no warp (the orbit z -> z^2: inside exactly where
|z0| <= 1), black outside and bright inside, radius R, centre -R tan(T0/2) exp(i PSI0) (degrees).
With p = R (d.x + i d.z) / (1 + d.y) = R tan(theta/2) exp(i psi) (theta from +Y, psi = atan2(d.z,
d.x)), z0 = p + centre, so the inside is the preimage of the disc |p - P0| <= 1, P0 = R tan(T0/2)
exp(i PSI0): a circle of the plane is a circle of the sphere under the stereographic projection,
so the bright region is a spherical cap on the meridian psi = PSI0 from theta1 = 2 atan((|P0| - 1)
/ R) to theta2 = 2 atan((|P0| + 1) / R), centred at their mean. That is computed here from the
formula alone, and the claim under test is that OpenEXR's (x, y, z) is Blender's (z, x, y).

docs/examples/blender/sky.py (the recipe docs/sky.md gives) makes the sky Blender's World and aims
a camera; Cycles renders a small frame; the bright blob's centroid, turned into a direction by the
camera's own matrix, must lie within 2 degrees of the claim, with the cap's size. The same frame
aimed where a mirrored sky (longitude negated) or an upside-down one (latitude negated) would put
the cap must be dark, and every other signed permutation of the axes would move the cap by more
than the 2 degrees, so any such slip fails.
"""
import math
import os
import sys

import bpy
import numpy as np
from mathutils import Vector

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from checks import ARGS as args, check, finish  # noqa: E402 (it puts the recipes on sys.path)

ROOT, SKY = args[0], args[1]
R, T0, PSI0, FOV = (float(v) for v in args[2:6])
OUT = os.path.dirname(os.path.abspath(SKY))
import sky as recipe  # noqa: E402

def angle(a, b):
    return math.degrees(a.angle(b))


# ---- the cap, from the formula alone ----
t0, psi0, fov = math.radians(T0), math.radians(PSI0), math.radians(FOV)
p0 = R * math.tan(t0 / 2)
th1, th2 = 2 * math.atan((p0 - 1) / R), 2 * math.atan((p0 + 1) / R)
thc, cap = (th1 + th2) / 2, (th2 - th1) / 2
d = (math.sin(thc) * math.cos(psi0), math.cos(thc), math.sin(thc) * math.sin(psi0))  # OpenEXR's frame
lon, lat = math.atan2(d[0], d[2]), math.asin(d[1])  # OpenEXR's longitude (0 at +Z) and latitude
claim = Vector((d[2], d[0], d[1]))  # Blender's frame: EXR +Z = +X, +X = +Y, +Y = +Z
print("cap centre: EXR direction (%.4f, %.4f, %.4f), longitude %.3f, latitude %.3f degrees, radius %.3f"
      % (*d, math.degrees(lon), math.degrees(lat), math.degrees(cap)))

# every other signed permutation of the axes moves the cap by more than the test's 2 degrees
others = []
for perm in ((0, 1, 2), (0, 2, 1), (1, 0, 2), (1, 2, 0), (2, 0, 1), (2, 1, 0)):
    for signs in range(8):
        v = Vector([d[perm[k]] * (-1 if signs >> k & 1 else 1) for k in range(3)])
        if angle(v, claim) > 1e-9:
            others.append(angle(v, claim))
check("47 other axis mappings, each moves the cap by more than 2 degrees", len(others) == 47 and min(others) > 10,
      "nearest %.1f degrees" % min(others))


def frame(lon_, lat_, name, samples):
    """Renders the recipe's camera aimed at (lon_, lat_); the frame's pixels (rows from the bottom) and camera."""
    recipe.look_camera(lon_, lat_, fov)
    path = os.path.join(OUT, name)
    recipe.render(path, SIZE, samples)
    img = bpy.data.images.load(path)
    px = np.array(img.pixels[:], dtype=np.float64).reshape(img.size[1], img.size[0], img.channels)
    return px[:, :, :3].mean(axis=2), bpy.context.scene.camera


SIZE = 64
bpy.ops.wm.read_factory_settings(use_empty=True)
recipe.world_from_latlong(SKY)

# ---- the frame aimed at the claim: the blob, its centroid and its size ----
lum, cam = frame(lon, lat, "probe.exr", 8)
peak = lum.max()
check("the probe frame sees the bright cap", peak > 5, "peak %.3g" % peak)
ys, xs = np.nonzero(lum > peak / 2)
if len(xs):
    t = math.tan(fov / 2)
    cx, cy = (xs + 0.5).mean() / SIZE * 2 - 1, (ys + 0.5).mean() / SIZE * 2 - 1
    seen = cam.matrix_world.to_3x3() @ Vector((cx * t, cy * t, -1.0))
    check("the cap's centroid lies within 2 degrees of where the sky's convention puts it",
          angle(seen, claim) < 2, "%.3f degrees off" % angle(seen, claim))
    # the cap seen from its centre is a disc of radius tan(cap) in the image plane
    want = math.pi * (math.tan(cap) / t * SIZE / 2) ** 2
    check("the blob is the cap's size", abs(len(xs) - want) < 0.15 * want, "%d pixels, %.0f expected" % (len(xs), want))
    edge = np.concatenate([lum[0], lum[-1], lum[:, 0], lum[:, -1]])
    check("the whole cap is in the frame", edge.max() < peak / 2)

# ---- where a mirrored or upside-down sky would put it: dark ----
for lo, la, what in ((-lon, lat, "a mirrored sky (longitude negated, EXR +X = Blender -Y)"),
                     (lon, -lat, "an upside-down sky (latitude negated)")):
    check("the cap is not where %s would put it (%.1f degrees away)" % (what, angle(recipe.blender_direction(lo, la), claim)),
          frame(lo, la, "wrong.exr", 2)[0].max() < peak / 10)

finish()
