#!/usr/bin/env python3
"""Keyframes for tests/cli/flame-animate.sh, from flame files:

    flame-keys.py OUT.flame SIZE QUALITY TIME:FILE[:INDEX] ... [ATTRIBUTE=VALUE ...]

Each TIME:FILE gives the INDEX-th <flame> of FILE (the first unless given) the time TIME; a bare FILE
keeps every <flame> of FILE with its own time (flam3-genome's sequence, inter and rotate). Every
keyframe is made SIZE x SIZE (the same view: the scale follows the size) at QUALITY samples per
pixel, and has each ATTRIBUTE=VALUE set (interpolation, interpolation_type, temporal_filter_type ...).
"""
import sys
import xml.etree.ElementTree as ET

out, size, quality = sys.argv[1], int(sys.argv[2]), sys.argv[3]
keys, attrs = [], []
for a in sys.argv[4:]:
    (attrs if "=" in a else keys).append(a)


def flames(path):
    root = ET.parse(path).getroot()
    return [root] if root.tag == "flame" else root.findall(".//flame")


frames = []
for k in keys:
    parts = k.split(":")
    if len(parts) == 1:
        frames += flames(parts[0])
        continue
    f = flames(parts[1])[int(parts[2]) if len(parts) > 2 else 0]
    f.set("time", parts[0])
    frames.append(f)
root = ET.Element("flames")
for f in frames:
    w = int(f.get("size").split()[0])
    f.set("scale", "%.9g" % (float(f.get("scale")) * size / w))
    f.set("size", "%d %d" % (size, size))
    f.set("quality", quality)
    for a in attrs:
        name, value = a.split("=", 1)
        f.set(name, value)
    root.append(f)
ET.ElementTree(root).write(out)
