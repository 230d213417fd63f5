"""fractalbake's plant instances (a .ply of --instances-up z) as instances in Blender (docs/plants.md).

    blender -b --factory-startup --python-exit-code 1 -P docs/examples/blender/plants.py -- PLANTS.ply [--heightmap HEIGHTS.png
        --bounds XMIN,XMAX,YMIN,YMAX] [--save OUT.blend]

Blender's own PLY importer reads the points (x east, y north, z the height: write them with
`--instances-up z`, Blender's Z up); it keeps their positions only, so this script reads each plant's
`pscale` and `orient` from the same file and gives them to the points as attributes. A Geometry Nodes
modifier then puts a model on every point (here a cone one unit tall standing on its base: replace
it with your tree), scaled by `pscale` and turned about Z by the quaternion's angle. With
--heightmap, the terrain they stand on comes in too, through docs/examples/blender/terrain.py.
--save writes the .blend.
"""
import math
import os
import struct
import sys

import bpy

PLY_TYPES = {"char": "b", "uchar": "B", "short": "h", "ushort": "H", "int": "i", "uint": "I", "float": "f", "double": "d"}


def read_instances(path):
    """The PLY's vertices as dicts of its properties (binary little-endian, as fractalbake writes them)."""
    data = open(path, "rb").read()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    count, props, comments = 0, [], []
    for line in data[:end].decode("ascii").split("\n"):
        w = line.split()
        if w[:2] == ["format", "binary_little_endian"]:
            pass
        elif w[:1] == ["format"]:
            raise ValueError("%s: not a binary little-endian PLY" % path)
        elif w[:1] == ["comment"]:
            comments.append(line)
        elif w[:2] == ["element", "vertex"]:
            count = int(w[2])
        elif w[:1] == ["property"]:
            props.append((w[2], PLY_TYPES[w[1]]))
    if not any("Z (x east, y north) up" in c for c in comments):
        raise ValueError("%s: not written with --instances-up z (Blender's Z up)" % path)
    fmt = "<" + "".join(t for _, t in props)
    size = struct.calcsize(fmt)
    return [dict(zip([n for n, _ in props], struct.unpack_from(fmt, data, end + k * size))) for k in range(count)]


def plant_model(name="plant"):
    """A cone one unit tall, its base's centre at the origin: the model every point gets."""
    bpy.ops.mesh.primitive_cone_add(radius1=0.25, depth=1.0, location=(0, 0, 0.5))
    cone = bpy.context.active_object
    cone.name = name
    bpy.ops.object.origin_set(type="ORIGIN_CURSOR")  # the cursor is at the origin: the base's centre
    for c in cone.users_collection:  # out of the scene: it is seen only where it is instanced
        c.objects.unlink(cone)
    return cone


def instances(path, model=None):
    """The points of path (Blender's PLY importer) with a Geometry Nodes modifier instancing model."""
    plants = read_instances(path)
    bpy.ops.import_mesh.ply(filepath=path)
    pts = bpy.context.selected_objects[0]
    if len(pts.data.vertices) != len(plants):
        raise ValueError("%s: Blender read %d points, the file has %d" % (path, len(pts.data.vertices), len(plants)))
    scale = pts.data.attributes.new("pscale", "FLOAT", "POINT")
    scale.data.foreach_set("value", [p["pscale"] for p in plants])
    turn = pts.data.attributes.new("rotation", "FLOAT_VECTOR", "POINT")
    yaw = [2 * math.atan2(p["orient_z"], p["orient_w"]) for p in plants]  # orient: a turn about Z
    turn.data.foreach_set("vector", [c for a in yaw for c in (0.0, 0.0, a)])
    model = model or plant_model()

    group = bpy.data.node_groups.new("plants", "GeometryNodeTree")
    group.inputs.new("NodeSocketGeometry", "Geometry")
    group.outputs.new("NodeSocketGeometry", "Geometry")
    n, link = group.nodes, group.links.new
    src, out = n.new("NodeGroupInput"), n.new("NodeGroupOutput")
    obj = n.new("GeometryNodeObjectInfo")
    obj.inputs["Object"].default_value = model
    put = n.new("GeometryNodeInstanceOnPoints")
    rot, size = n.new("GeometryNodeInputNamedAttribute"), n.new("GeometryNodeInputNamedAttribute")
    rot.data_type, size.data_type = "FLOAT_VECTOR", "FLOAT"
    rot.inputs["Name"].default_value, size.inputs["Name"].default_value = "rotation", "pscale"
    link(src.outputs["Geometry"], put.inputs["Points"])
    link(obj.outputs["Geometry"], put.inputs["Instance"])
    # the node has an output of each type; the one of its data_type is the one enabled
    link(next(o for o in rot.outputs if o.enabled), put.inputs["Rotation"])
    link(next(o for o in size.outputs if o.enabled), put.inputs["Scale"])
    link(put.outputs["Instances"], out.inputs["Geometry"])
    pts.modifiers.new("plants", "NODES").node_group = group
    return pts


def main(argv):
    import argparse
    ap = argparse.ArgumentParser(prog="plants.py", description="fractalbake plant instances in Blender")
    ap.add_argument("instances")
    ap.add_argument("--heightmap")
    ap.add_argument("--bounds", help="the heightmap's XMIN,XMAX,YMIN,YMAX")
    ap.add_argument("--save")
    a = ap.parse_args(argv)
    bpy.ops.wm.read_factory_settings(use_empty=True)
    if a.heightmap:
        sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
        import terrain
        terrain.displaced_plane(a.heightmap, [float(v) for v in a.bounds.split(",")] if a.bounds else None)
    pts = instances(a.instances)
    deps = bpy.context.evaluated_depsgraph_get()
    placed = sum(1 for i in deps.object_instances if i.is_instance and i.parent.original == pts)
    print("plants.py: %s: %d plants placed" % (a.instances, placed))
    if a.save:
        bpy.ops.wm.save_as_mainfile(filepath=os.path.abspath(a.save))


if __name__ == "__main__":
    main(sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else [])
