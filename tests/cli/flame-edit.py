#!/usr/bin/env python3
"""Turns a random genome of flam3-genome into a test genome (tests/cli/flame.sh):

    flame-edit.py IN.flame OUT.flame CASE QUALITY [VAR,VAR,...] [SIZE]

SIZE x SIZE (512 unless given; the same view: the scale follows the size), QUALITY samples per
pixel, every variation of the list (flam3's numbers, VAR_LINEAR 0 .. VAR_MOBIUS 98) present (one
the random genome lacks is added to an xform at weight 0.5), and the feature CASE exercises
(`plain`: none, the genome as flam3-genome made it): post, xaos, final, palette-rgb (<palette format="RGB">), colors (<colors>),
library (palette="N" with a hue), opacity (an xform at opacity 0.5 and the legacy symmetry), linear
(palette_mode linear), supersample (2, the mitchell filter), camera (rotate, zoom), tone (DE,
gamma threshold, highlight power, vibrancy, background)."""
import re
import sys
import xml.etree.ElementTree as ET

# flam3 3.1.1's variations by number (flam3.h)
NAMES = """linear sinusoidal spherical swirl horseshoe polar handkerchief heart disc spiral hyperbolic diamond
ex julia bent waves fisheye popcorn exponential power cosine rings fan blob pdj fan2 rings2 eyefish bubble
cylinder perspective noise julian juliascope blur gaussian_blur radial_blur pie ngon curl rectangles arch
tangent square rays blade secant2 twintrian cross disc2 super_shape flower conic parabola bent2 bipolar
boarders butterfly cell cpow curve edisc elliptic escher foci lazysusan loonie pre_blur modulus
oscilloscope polar2 popcorn2 scry separation split splits stripes wedge wedge_julia wedge_sph whorl waves2
exp log sin cos tan sec csc cot sinh cosh tanh sech csch coth auger flux mobius""".split()
assert len(NAMES) == 99

src, dst, case, quality = sys.argv[1:5]
ids = sys.argv[5] if len(sys.argv) > 5 else ""
size = int(sys.argv[6]) if len(sys.argv) > 6 else 512
root = ET.parse(src).getroot()
flame = root if root.tag == "flame" else root.find("flame")
w, h = (int(v) for v in flame.get("size").split())
flame.set("scale", "%.9g" % (float(flame.get("scale")) * size / w))
flame.set("size", "%d %d" % (size, size))
flame.set("quality", quality)
flame.set("name", "test-" + case)
xforms = flame.findall("xform")
names = [NAMES[int(i)] for i in ids.split(",")] if ids else []
for k, v in enumerate(names):
    if not any(x.get(v) for x in xforms):
        xforms[k % len(xforms)].set(v, "0.5")


def colors():
    out = []
    for c in flame.findall("color"):
        out.append([int(round(float(t))) for t in c.get("rgb").split()])
        flame.remove(c)
    return out


if case == "post":
    xforms[0].set("post", "0.8 0.3 -0.3 0.8 0.1 -0.2")
elif case == "xaos":
    xforms[0].set("chaos", " ".join(["0" if j == 0 else "1" for j in range(len(xforms))]))
    if len(xforms) > 1:
        xforms[1].set("chaos", " ".join(["2" if j == 0 else "0.5" for j in range(len(xforms))]))
elif case == "final":
    fx = ET.SubElement(flame, "finalxform", {"color": "0.3", "color_speed": "0.2", "linear": "0.7",
                                             "spherical": "0.3", "coefs": "0.9 0.1 -0.1 0.9 0.05 0"})
elif case == "palette-rgb":
    cs = colors()
    p = ET.SubElement(flame, "palette", {"count": "256", "format": "RGB"})
    p.text = "\n" + "\n".join("".join("%02X%02X%02X" % tuple(c) for c in cs[i:i + 8]) for i in range(0, 256, 8)) + "\n"
elif case == "colors":
    cs = colors()
    ET.SubElement(flame, "colors", {"count": "256", "data": "".join("00%02x%02x%02x" % tuple(c) for c in cs)})
elif case == "library":
    colors()
    flame.set("palette", "17")
    flame.set("hue", "0.25")
elif case == "opacity":
    xforms[0].set("opacity", "0.5")
    if len(xforms) > 1:
        del xforms[1].attrib["color_speed"]
        xforms[1].set("symmetry", "0.4")
elif case == "linear":
    flame.set("palette_mode", "linear")
elif case == "supersample":
    flame.set("supersample", "2")
    flame.set("filter_shape", "mitchell")
    flame.set("filter", "0.8")
elif case == "camera":
    flame.set("rotate", "30")
    flame.set("zoom", "0.4")
elif case == "tone":
    flame.set("estimator_radius", "5")
    flame.set("estimator_minimum", "1")
    flame.set("estimator_curve", "0.6")
    flame.set("gamma_threshold", "0.04")
    flame.set("highlight_power", "1")
    flame.set("vibrancy", "0.6")
    flame.set("gamma", "3")
    flame.set("brightness", "6")
    flame.set("background", "0.1 0.05 0.2")
elif case != "plain":
    sys.exit("flame-edit.py: unknown case " + case)
ET.ElementTree(flame).write(dst)
