"""A lat-long sky baked by fractalbake as the World of a Blender scene (docs/sky.md, "Blender").

    blender -b --factory-startup --python-exit-code 1 -P docs/examples/blender/sky.py -- SKY.exr [--look LON,LAT]
        [--fov DEGREES] [--size PIXELS] [--samples N] [--render OUT.png|OUT.exr] [--save OUT.blend]

The file goes into an Environment Texture (projection Equirectangular) behind the World's Background,
as it is: no Mapping node. Blender's equirectangular lookup then turns the sky's frame (OpenEXR's,
+Y up, longitude 0 at +Z, +90 at +X) into its own, Z up, by a rotation: OpenEXR's +Z is Blender's
+X, +X is +Y and +Y is +Z. So a direction of the sky at longitude LON and latitude LAT is Blender's
azimuth LON (counter-clockwise from +X, seen from above) at elevation LAT.

--look aims a camera at the origin at (LON, LAT) in the sky's own degrees (a perspective lens of
--fov degrees across, default 60), for --render: a Cycles frame on the CPU, --size pixels square
(default 128), --samples per pixel (default 16). --save writes the .blend.

Blender reads an EXR with several layers as a multilayer image and shows its first layer: hand it a
file whose one colour layer is the sky (bake the sky alone), or the layer as plain R, G, B
(`oiiotool sky.exr --ch R=sky.R,G=sky.G,B=sky.B -o sky-rgb.exr`).
"""
import math
import os
import sys

import bpy
from mathutils import Vector


def blender_direction(lon, lat):
    """The unit vector in Blender's frame of the sky's longitude and latitude (radians)."""
    # the sky's direction (sin lon cos lat, sin lat, cos lon cos lat), its (z, x, y) in Blender
    return Vector((math.cos(lon) * math.cos(lat), math.sin(lon) * math.cos(lat), math.sin(lat)))


def world_from_latlong(path, scene=None):
    """Makes the lat-long EXR at path the World of scene (the current one by default)."""
    scene = scene or bpy.context.scene
    world = bpy.data.worlds.new("fractalbake sky")
    world.use_nodes = True
    nodes = world.node_tree.nodes
    env = nodes.new("ShaderNodeTexEnvironment")
    env.image = bpy.data.images.load(path, check_existing=True)
    env.projection = "EQUIRECTANGULAR"
    world.node_tree.links.new(env.outputs["Color"], nodes["Background"].inputs["Color"])
    scene.world = world
    return world


def look_camera(lon, lat, fov, scene=None):
    """A perspective camera at the origin looking at (lon, lat) (radians), fov radians across, up +Z."""
    scene = scene or bpy.context.scene
    cam = bpy.data.objects.new("probe", bpy.data.cameras.new("probe"))
    cam.data.angle = fov
    cam.rotation_mode = "QUATERNION"
    cam.rotation_quaternion = blender_direction(lon, lat).to_track_quat("-Z", "Y")
    scene.collection.objects.link(cam)
    scene.camera = cam
    return cam


def render(path, size=128, samples=16, scene=None):
    """A Cycles frame of scene's camera on the CPU, size pixels square, written to path (.png, .exr)."""
    scene = scene or bpy.context.scene
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = samples
    scene.cycles.use_denoising = False
    scene.render.resolution_x = scene.render.resolution_y = size
    scene.render.resolution_percentage = 100
    scene.view_settings.view_transform = "Standard"
    scene.render.image_settings.file_format = "OPEN_EXR" if path.lower().endswith(".exr") else "PNG"
    scene.render.filepath = path
    bpy.ops.render.render(write_still=True)


def main(argv):
    import argparse
    ap = argparse.ArgumentParser(prog="sky.py", description="a fractalbake lat-long sky as Blender's World")
    ap.add_argument("sky")
    ap.add_argument("--look", default="0,0", help="LON,LAT in the sky's degrees")
    ap.add_argument("--fov", type=float, default=60.0)
    ap.add_argument("--size", type=int, default=128)
    ap.add_argument("--samples", type=int, default=16)
    ap.add_argument("--render")
    ap.add_argument("--save")
    a = ap.parse_args(argv)
    bpy.ops.wm.read_factory_settings(use_empty=True)
    world_from_latlong(a.sky)
    lon, lat = (math.radians(float(v)) for v in a.look.split(","))
    look_camera(lon, lat, math.radians(a.fov))
    if a.render:
        render(a.render, a.size, a.samples)
    if a.save:
        bpy.ops.wm.save_as_mainfile(filepath=os.path.abspath(a.save))


if __name__ == "__main__":
    main(sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else [])
