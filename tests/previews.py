#!/usr/bin/env python3
"""Previews show what the layers made (docs/scenes.md, "Previews"), read back with the tests' own PNG and
EXR readers:
- a rivers layer without a palette: its hillshade with its rivers and lakes drawn over it in blue, every
  pixel the EXR marks as river or lake blue in the picture and every other pixel grey;
- a composite: a layer of data with no colour and no coverage (an fBm field) in front of others is left
  out (the line says so), so that the sky and terrain of docs/examples/night.json show; at the back,
  alone, or named with --preview-layer it is drawn;
- the default scene's plants: filled silhouettes that cover a visible part of the picture; the trees of
  docs/examples/rivers-plants.json off the grid their maps once drew.

Usage: previews.py ROOT FRACTALBAKE
"""
import os
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from exrfile import read_exr_channel  # noqa: E402
from gallery import png_pixels  # noqa: E402

ROOT, FB = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2])
failures = []


def check(what, ok):
    print(("ok     " if ok else "FAIL   ") + what)
    if not ok:
        failures.append(what)


def png_rgb(path):
    """Width, height and the pixels (r, g, b) of an 8-bit RGB or grey PNG (grey repeated)."""
    w, h, px = png_pixels(path)
    return w, h, [p * 3 if len(p) == 1 else p for p in px]


def run(*args):
    p = subprocess.run([FB, *args], capture_output=True, text=True)
    assert p.returncode == 0, (args, p.stderr)
    return p.stderr


os.chdir(tempfile.mkdtemp(prefix="fb-previews-"))
# ---- a rivers layer's own preview: its water over its hillshade ----
run("rivers", "--size", "128x128", "--steps", "60", "--lakes", "keep", "--backend", "native", "-q", "-o", "r.exr",
    "--preview", "r.png")
w, h, px = png_rgb("r.png")
river, lake = read_exr_channel("r.exr", "rivers.river"), read_exr_channel("r.exr", "rivers.lake")
wet = [river[y][x] > 0 or lake[y][x] > 0 for y in range(h) for x in range(w)]
blue = [b > r + 20 and b > g for (r, g, b) in px]
grey = [r == g == b for (r, g, b) in px]
check(f"rivers: {sum(wet)} water pixels of {w * h}, some and not most", 0.002 * w * h < sum(wet) < 0.5 * w * h)
check("rivers: every water pixel is blue in the preview", all(b for b, m in zip(blue, wet) if m))
check("rivers: every other pixel is grey (the hillshade)", all(g for g, m in zip(grey, wet) if not m))
check("rivers: the hillshade has relief (grey levels spread)", len({p[0] for p, m in zip(px, wet) if not m}) > 20)

# ---- the composite: an opaque data layer in front is left out, at the back it is drawn ----
small = ["--set", "size=128x64", "--set", "layers.terrain.insert=2000", "--backend", "native", "-o", "n.exr"]
line = run("render", os.path.join(ROOT, "docs/examples/night.json"), *small, "--preview", "over.png")
run("render", os.path.join(ROOT, "docs/examples/night.json"), *small, "--preview", "terrain.png",
    "--preview-layer", "terrain")
run("render", os.path.join(ROOT, "docs/examples/night.json"), *small, "--preview", "detail.png",
    "--preview-layer", "detail")
check("night.json: the line names what is drawn and what is left out: " + line.strip().split("\n")[-1],
      "preview over.png: sky and terrain composited" in line and "in front): detail, ground" in line)
_, _, over = png_rgb("over.png")
_, _, det = png_rgb("detail.png")
check("night.json: the composite is not the detail layer's grey field",
      sum(a != b for a, b in zip(over, det)) > 0.9 * len(over))
check("night.json: the composite is in colour (the terrain's tint over the sky)",
      sum(r != b for (r, g, b) in over) > 0.5 * len(over))
# the same kind of field at the back, under a layer with coverage: drawn
scene = ('{"size": [96, 64], "layers": [{"type": "fbm", "name": "field", "octaves": 4}, '
         '{"type": "ifs", "name": "fern", "preset": "fern", "points": 200000}]}')
open("back.json", "w").write(scene)
run("render", "back.json", "--backend", "native", "-q", "-o", "b.exr", "--preview", "back.png")
run("render", "back.json", "--backend", "native", "-q", "-o", "b.exr", "--preview", "field.png",
    "--preview-layer", "field")
_, _, back = png_rgb("back.png")
_, _, field = png_rgb("field.png")
check("a data layer at the back is drawn: the fern's empty pixels show the field",
      sum(1 for a, f in zip(back, field) if a[0] == a[1] == a[2] and a[0] > 0) > 0.3 * len(back))

# ---- the default scene's plants: filled silhouettes, seen ----
# A filled silhouette covers each column of it from its top pixel to its bottom one; an outline (the
# paper's branching tree drawn by its chaos game) only its rims: 67% of the span at this size, two runs
# a column. Seen: at least 3% of the image, where the old outlines covered 1.4%.
run("render", "--set", "size=512x256", "--set", "layers.terrain.insert=2000", "--backend", "native", "-q",
    "-o", "d.exr")
A = read_exr_channel("d.exr", "plants.A")
cov = span = runs = cols = 0
for x in range(len(A[0])):
    ys = [y for y in range(len(A)) if A[y][x] >= 0.5]
    if ys:
        cov, span, cols = cov + len(ys), span + max(ys) - min(ys) + 1, cols + 1
        runs += 1 + sum(1 for a, b in zip(ys, ys[1:]) if b > a + 1)
check(f"default scene: the plants fill {cov / max(span, 1):.0%} of their columns' spans (filled: at least 90%)",
      cov >= 0.9 * span)
check(f"default scene: {runs / max(cols, 1):.2f} runs a column (filled: under 1.5, an outline 2)", runs < 1.5 * cols)
check(f"default scene: the plants cover {cov / (len(A) * len(A[0])):.1%} of the image (at least 3%)",
      cov >= 0.03 * len(A) * len(A[0]))

# ---- docs/examples/rivers-plants.json's trees: not on a grid ----
# Its four maps of scale 1/2 once stood on the dyadic lattice (every plant's x a multiple of 1/1024 of the
# extent: a grid of dots); turned a little about the square's corners, the bases leave it.
run("render", os.path.join(ROOT, "docs/examples/rivers-plants.json"), "--set", "size=128x128", "--set",
    "layers.range.steps=20", "--set", "layers.trees.instances=trees.csv", "--set",
    "layers.trees.instances-min-size=0.1", "--backend", "native", "-q", "-o", "rp.exr")
rows = open("trees.csv").read().split("\n")[1:]
xs = {float(r.split(",")[1]) for r in rows if r}
step = 30000 / 1024  # the layer's extent over 1024
lattice = sum(1 for x in xs if abs(x / step - round(x / step)) < 1e-3)
check(f"rivers-plants: {len(xs)} distinct plant positions, {lattice} on the 1/1024 lattice (a grid: all; at most 10%)",
      len(xs) >= 20 and lattice <= 0.1 * len(xs))

print(f"{len(failures)} failed" if failures else "all previews as they should be")
sys.exit(1 if failures else 0)
