#!/usr/bin/env python3
"""Plant instances of an ifs population (docs/plants.md, "Plant instances").

Independent readers (a PLY and CSV reader, an OpenEXR scanline reader: tests/exrfile.py) and an
independent enumeration of the population check what `--instances` writes: the attribute names and
count, the plants' positions, sizes and generations, that they stand on the terrain layer's surface
(the EXR's heights, bilinear between pixel centres), the normal, the orientation, CSV and PLY
agreeing, the Z-up variant, and the same bytes whatever the thread count, strip height or backend.
Usage: instances.py PATH/TO/fractalbake
"""
import json
import math
import os
import struct
import subprocess
import sys
import tempfile

from exrfile import read_exr_channel

FB = os.path.abspath(sys.argv[1])
NAMES = ["id", "x", "y", "z", "nx", "ny", "nz", "pscale", "orient_x", "orient_y", "orient_z", "orient_w", "variant"]
failures = 0


def check(what, cond, detail=""):
    global failures
    if not cond:
        failures += 1
        print(f"FAIL: {what} {detail}")


def run(*args, env=None):
    p = subprocess.run([FB, *args], capture_output=True, text=True, env=env)
    if p.returncode != 0:
        print(f"FAIL: fractalbake {' '.join(args)}: exit {p.returncode}: {p.stderr.strip()}")
        sys.exit(1)
    return p


def f32(v):
    return struct.unpack("<f", struct.pack("<f", v))[0]


def read_ply(path):
    data = open(path, "rb").read()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    lines = data[:end].decode().split("\n")
    assert lines[0] == "ply" and lines[1] == "format binary_little_endian 1.0", lines[:2]
    count, props = None, []
    for line in lines:
        w = line.split()
        if w[:2] == ["element", "vertex"]:
            count = int(w[2])
        elif w[:1] == ["property"]:
            props.append((w[1], w[2]))
    fmt = "<" + "".join({"int": "i", "float": "f"}[t] for t, _ in props)
    size = struct.calcsize(fmt)
    check("PLY size", len(data) == end + count * size, f"{len(data)} != {end} + {count} x {size}")
    rows = [dict(zip([n for _, n in props], struct.unpack_from(fmt, data, end + i * size))) for i in range(count)]
    return [n for _, n in props], [t for t, _ in props], rows


def read_csv(path):
    lines = open(path).read().splitlines()
    names = lines[0].split(",")
    rows = []
    for line in lines[1:]:
        vals = line.split(",")
        rows.append({n: int(v) if n in ("id", "variant") else f32(float(v)) for n, v in zip(names, vals)})
    return names, rows


def population(maps, cond_height, frame, min_size):
    """Every word's base and size, generation by generation (w_i o W, not W o w_j: the same multiset)."""
    scale = math.sqrt(abs(maps[0][0] * maps[0][3] - maps[0][1] * maps[0][2]))
    assert all(abs(math.sqrt(abs(m[0] * m[3] - m[1] * m[2])) - scale) < 1e-12 for m in maps)
    level, gen, out = [(0.0, 0.0)], 0, []
    while cond_height * scale**gen >= min_size:
        out += [(x, y, cond_height * scale**gen, gen) for x, y in level
                if frame[0] <= x <= frame[1] and frame[2] <= y <= frame[3]]
        level = [(m[0] * x + m[1] * y + m[4], m[2] * x + m[3] * y + m[5]) for x, y in level for m in maps]
        gen += 1
    return out


def bilinear(H, u, v):
    h, w = len(H), len(H[0])
    fu, fv = u - 0.5, v - 0.5
    i, j = math.floor(fu), math.floor(fv)
    s, t = fu - i, fv - j

    def at(r, c):
        return H[min(max(r, 0), h - 1)][min(max(c, 0), w - 1)]

    corners = [at(j, i), at(j, i + 1), at(j + 1, i), at(j + 1, i + 1)]
    val = (1 - t) * ((1 - s) * corners[0] + s * corners[1]) + t * ((1 - s) * corners[2] + s * corners[3])
    du = (1 - t) * (corners[1] - corners[0]) + t * (corners[3] - corners[2])
    dv = (1 - s) * (corners[2] - corners[0]) + s * (corners[3] - corners[1])
    return val, du, dv, corners


os.chdir(tempfile.mkdtemp(prefix="fb-instances-"))

# ---- 1. the paper's row of trees: counts and positions in closed form ----
W1, H1, B1 = 320, 120, [-0.08, 1.02, -0.02, 0.39]
run("ifs", "--maps", "0.75,0,0,0.75,0.25,0", "--condensation", "lsystem:tree", "--size", f"{W1}x{H1}", "--bounds",
    ",".join(map(str, B1)), "--points", "200000", "--instances", "row.ply", "--instances-min-size", "3", "--quiet",
    "-o", "row.exr")
names, types, rows = read_ply("row.ply")
check("PLY attribute names", names == NAMES, str(names))
check("PLY attribute types", types == ["int"] + ["float"] * 11 + ["int"], str(types))
px = math.sqrt(W1 / (B1[1] - B1[0]) * H1 / (B1[3] - B1[2]))
expect = [k for k in range(200) if 0.25 * 0.75**k * px >= 3]
check("row: one instance per plant at least 3 pixels tall", len(rows) == len(expect), f"{len(rows)} != {len(expect)}")
for k, r in zip(expect, rows):
    check(f"row plant {k}: id, x, height 0, z, pscale, generation",
          r["id"] == k and r["x"] == f32(1 - 0.75**k) and r["y"] == 0 and r["z"] == 0 and
          abs(r["pscale"] - 0.25 * 0.75**k) <= 1e-6 * 0.25 * 0.75**k and r["variant"] == k, str(r))
    check(f"row plant {k}: N up, orient a unit quaternion about y",
          (r["nx"], r["ny"], r["nz"]) == (0, 1, 0) and r["orient_x"] == 0 and r["orient_z"] == 0 and
          abs(r["orient_y"]**2 + r["orient_w"]**2 - 1) < 1e-6, str(r))
angles = {round(math.atan2(r["orient_y"], r["orient_w"]), 3) for r in rows}
check("row: every plant its own angle", len(angles) == len(rows), str(angles))

# ---- 2. a 2D population on a terrain layer ----
TB = [0, 100, 0, 50]
MAPS = [[0.5, 0, 0, 0.5, 0, 0], [0.5, 0, 0, 0.5, 0.5, 0], [0.5, 0, 0, 0.5, 0.25, 0.45]]
FRAME = [-0.05, 1.05, -0.05, 1.0]
scene = {"size": [128, 64], "seed": 5, "compression": "none", "layers": [
    {"type": "terrain", "name": "ground", "half": False, "insert": 800, "bounds": TB,
     "points": [[0, 0, 0], [100, 0, 10], [0, 50, 20], [100, 50, 40], [50, 25, 80], [20, 40, 5], [80, 10, 60]]},
    {"type": "ifs", "name": "plants", "maps": [m + [1 / 3] for m in MAPS], "condensation": {"preset": "bush",
     "height": 0.1}, "bounds": FRAME, "points": 300000, "instances": "t.ply", "instances-surface": "ground",
     "instances-min-size": 0.5}]}
open("t.json", "w").write(json.dumps(scene))
run("render", "t.json", "--quiet", "-o", "t.exr")
_, _, rows = read_ply("t.ply")
px = math.sqrt(128 / (FRAME[1] - FRAME[0]) * 64 / (FRAME[3] - FRAME[2]))
ref = population(MAPS, 0.1, FRAME, 0.5 / px)
check("terrain: one instance per plant of the population", len(rows) == len(ref), f"{len(rows)} != {len(ref)}")
cx, cy = (TB[1] - TB[0]) / 128, (TB[3] - TB[2]) / 64
world = math.sqrt(cx * 128 / (FRAME[1] - FRAME[0]) * cy * 64 / (FRAME[3] - FRAME[2]))
want = sorted((round(TB[0] + (x - FRAME[0]) / (FRAME[1] - FRAME[0]) * 128 * cx, 3),
               round(TB[3] - (FRAME[3] - y) / (FRAME[3] - FRAME[2]) * 64 * cy, 3), round(s * world, 4), g)
              for x, y, s, g in ref)
got = sorted((round(r["x"], 3), round(-r["z"], 3), round(r["pscale"], 4), r["variant"]) for r in rows)
check("terrain: positions (east, north), pscale and generations match the population", got == want,
      str([(a, b) for a, b in zip(got, want) if a != b][:3]))
check("terrain: ids are 0..n-1 in order", [r["id"] for r in rows] == list(range(len(rows))))
summary = json.loads(run("render", "t.json", "--json", "-o", "t.exr").stdout)["layers"][1]["summary"]
check("terrain: the --json summary counts the instances written", summary["instances"] == len(rows) and
      summary["instances_left_out"] == 0, str(summary))
Hgt = read_exr_channel("t.exr", "ground.Y")
worst = 0
for r in rows:
    u, v = (r["x"] - TB[0]) / cx, (TB[3] - (-r["z"])) / cy
    h, du, dv, corners = bilinear(Hgt, u, v)
    worst = max(worst, abs(r["y"] - h))
    check(f"terrain: instance {r['id']} between its four pixels' heights",
          min(corners) - 1e-4 <= r["y"] <= max(corners) + 1e-4, f"{r['y']} not in {corners}")
    n = (-du / cx, 1, -dv / cy)  # y up; v grows south, and so does z = -north
    ln = math.sqrt(sum(c * c for c in n))
    check(f"terrain: instance {r['id']}'s N is the surface normal",
          all(abs(a - b / ln) < 1e-4 for a, b in zip((r["nx"], r["ny"], r["nz"]), n)), f"{r} vs {n}")
check("terrain: P.y is the EXR's height at the plant (bilinear)", worst < 1e-4 * 80, f"worst {worst}")

# ---- 3. CSV and PLY agree; Z up; a constant height ----
scene["layers"][1]["instances"] = "t.csv"
open("c.json", "w").write(json.dumps(scene))
run("render", "c.json", "--quiet", "-o", "c.exr")
names, crows = read_csv("t.csv")
check("CSV header", names == NAMES, str(names))
check("CSV and PLY agree", crows == rows, f"{len(crows)} vs {len(rows)} rows")
scene["layers"][1]["instances"] = "z.ply"
scene["layers"][1]["instances-up"] = "z"
open("z.json", "w").write(json.dumps(scene))
run("render", "z.json", "--quiet", "-o", "z.exr")
_, _, zrows = read_ply("z.ply")
check("Z up: x east, y north, z the height, orient about z",
      len(zrows) == len(rows) and all(
          (a["x"], a["y"], a["z"], a["nx"], a["ny"], a["nz"], a["orient_z"], a["orient_w"], a["orient_y"]) ==
          (b["x"], -b["z"] + 0.0, b["y"], b["nx"], -b["nz"] + 0.0, b["ny"], b["orient_y"], b["orient_w"], 0)
          for a, b in zip(zrows, rows)))
del scene["layers"][1]["instances-up"]
scene["layers"][1]["instances"] = "k.ply"
scene["layers"][1]["instances-surface"] = 12.5
open("k.json", "w").write(json.dumps(scene))
run("render", "k.json", "--quiet", "-o", "k.exr")
_, _, krows = read_ply("k.ply")
check("a constant surface: every plant at that height, N up",
      len(krows) == len(rows) and all(r["y"] == 12.5 and r["ny"] == 1 for r in krows))

# ---- 4. the same bytes whatever threads, strips or backend ----
scene["layers"][1]["instances-surface"] = "ground"
base = open("t.ply", "rb").read()
scene["layers"][1]["instances"] = "t.ply"
for i, extra in enumerate([["--threads", "1", "--backend", "native"], ["--threads", "3", "--strip-rows", "7"],
                           ["--backend", "vulkan"]]):
    scene["layers"][1]["instances"] = f"d{i}.ply"
    open(f"d{i}.json", "w").write(json.dumps(scene))
    p = subprocess.run([FB, "render", f"d{i}.json", "--quiet", "-o", f"d{i}.exr", *extra], capture_output=True, text=True,
                       env=dict(os.environ, XDG_RUNTIME_DIR=os.environ.get("XDG_RUNTIME_DIR", "/tmp")))
    if p.returncode != 0 and "vulkan" in extra:
        print(f"note: no Vulkan device, the backend comparison is not run ({p.stderr.strip()})")
        continue
    check(f"bake {' '.join(extra)}", p.returncode == 0, p.stderr)
    check(f"the same instance bytes with {' '.join(extra)}", open(f"d{i}.ply", "rb").read() == base)

if failures:
    print(f"{failures} failure(s)")
    sys.exit(1)
print(f"instances: all checks passed ({len(expect)} plants in a row, {len(rows)} on the terrain)")
