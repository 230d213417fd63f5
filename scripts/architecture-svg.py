#!/usr/bin/env python3
"""Draws docs/img/architecture.svg from the code: the folders of host/, every generator of
host/gen/list.c, and an arrow for each include that scripts/check-layers.sh allows and no other
arrow implies (the allowed folders are closed under inclusion: a folder may include what its
arrows reach).

    scripts/architecture-svg.py [ROOT]    the SVG on standard output (ROOT: this tree)

After adding a folder or a generator: scripts/architecture-svg.py > docs/img/architecture.svg (the
test `rules` fails while the picture differs from what this draws). A new folder needs its place
and its line below.
"""
import html
import os
import re
import subprocess
import sys

W = 900
# a folder's place: (row, left, right) and what it holds, in a line
PLACES = {
    "gen": (0, 20, 520, "the one list of generators, fb_gen_list[]"),
    "cli": (0, 560, 710, "the commands: argv, environment, print"),
    "lib": (0, 730, 880, "libfractalbake: its API"),
    "compare": (1, 560, 880, "images compared: statistics, FLIP, SSIM, reports"),
    "core": (2, 20, 620, "scene, schema, gen.h (fb_gen_class), engines, bake, plan, merge"),
    "geom": (2, 660, 880, "exact predicates, Delaunay"),
    "io": (3, 20, 620, "Vulkan (vkc), EXR, PNG, heightmaps"),
    "base": (4, 20, 880, "fb.h, log, output transaction, text input, pool, progress"),
}
GENS = (1, 20, 520, "gen/NAME/: keys, parser, layer, algorithms, bench")
ROW_H, GAP, GEN_W, GEN_H = 48, 34, 72, 26


def allowed(out):
    """{folder: the other folders it may include}, from check-layers.sh --allowed's output."""
    return {f.strip(): set(rest.split()) - {f.strip()} for f, _, rest in (l.partition(":") for l in out.splitlines())}


def draw(root, layers=None):
    """The SVG's text; layers: check-layers.sh --allowed's output (run here when None)."""
    if layers is None:
        layers = subprocess.run(["bash", os.path.join(root, "scripts/check-layers.sh"), "--allowed",
                                 os.path.join(root, "host")], capture_output=True, text=True, check=True).stdout
    may = allowed(layers)
    gens = re.findall(r"\bX\((\w+)\)", open(os.path.join(root, "host/gen/list.c")).read())
    # a name of the list without its folder, or a folder the list does not name, is for tests/rules.py
    gens = [g for g in gens if "gen/" + g in may]
    shown = {f for f in may if not f.startswith("gen/") or f[4:] in gens}
    may = {f: may[f] & shown for f in shown}
    missing = sorted(f for f in may if not f.startswith("gen/") and f not in PLACES)
    if missing:
        sys.exit(f"architecture-svg.py: no place for host/{', host/'.join(missing)}/: add it to PLACES")
    # the arrows: each allowed include that no other allowed folder implies
    edges = sorted((a, b) for a in may for b in may[a] if not any(b in may.get(c, ()) for c in may[a] - {b}))
    # the generators in the list's order, but each that uses another right after it, and those that
    # use a folder outside host/gen and core (terrain: geom) last, nearest that folder
    order = []
    for g in gens:
        for u in [u[4:] for u in sorted(may["gen/" + g]) if u[4:] in gens] + [g]:
            if u not in order:
                order.append(u)
    outside = [g for g in order if any(b not in ("core", "io", "base") and not b.startswith("gen/")
                                       for b in may["gen/" + g])]
    gens = [g for g in order if g not in outside] + outside
    # the generators' group: rows of five boxes
    per_row = 5
    grid_rows = (len(gens) + per_row - 1) // per_row
    group_h = 26 + grid_rows * (GEN_H + 8) + 4
    row_h = [ROW_H, max(ROW_H, group_h), ROW_H, ROW_H, ROW_H]
    row_y = [40]
    for h in row_h[:-1]:
        row_y.append(row_y[-1] + h + GAP)
    height = row_y[-1] + row_h[-1] + 40
    box = {}  # folder -> (x0, y0, x1, y1)
    for f, (r, x0, x1, _) in PLACES.items():
        if f in may:
            box[f] = (x0, row_y[r], x1, row_y[r] + ROW_H)
    r, gx0, gx1, _ = GENS
    box["gen/*"] = (gx0, row_y[r], gx1, row_y[r] + group_h)
    step = (gx1 - gx0 - 20 - GEN_W) / (per_row - 1)
    for i, g in enumerate(gens):
        x = gx0 + 10 + (i % per_row) * step
        y = row_y[r] + 26 + (i // per_row) * (GEN_H + 8)
        box["gen/" + g] = (round(x), y, round(x + GEN_W), y + GEN_H)

    out = [
        f'<svg xmlns="http://www.w3.org/2000/svg" width="{W}" height="{height}" viewBox="0 0 {W} {height}" '
        'font-family="DejaVu Sans, Arial, sans-serif" font-size="13">',
        '  <defs><marker id="a" viewBox="0 0 10 10" refX="9" refY="5" markerWidth="7" markerHeight="7" '
        'orient="auto"><path d="M0,0 L10,5 L0,10 z" fill="#555"/></marker></defs>',
        f'  <rect width="{W}" height="{height}" fill="#fbfbf8"/>',
        f'  <text x="{W // 2}" y="24" text-anchor="middle" font-size="15" font-weight="bold">host/: one library per '
        "folder; an arrow points to what a folder may include, and so on down</text>",
    ]
    colours = {"cli": ("#dbe9f7", "#4a78a8"), "compare": ("#dbeef2", "#3f8a99"), "gen": ("#e4f2dc", "#5c8f45"),
               "core": ("#f7ecd6", "#a8823f"), "io": ("#f3e0e0", "#a85a5a"), "geom": ("#ebe2f3", "#7b5ca8"),
               "base": ("#e8e8e8", "#777777")}
    for f, (r, x0, x1, text) in PLACES.items():
        if f not in box:
            continue
        _, y0, _, y1 = box[f]
        fill, stroke = colours.get(f, ("#ffffff", "#555555"))
        name = "gen/list.c" if f == "gen" else f + "/"
        out.append(f'  <rect x="{x0}" y="{y0}" width="{x1 - x0}" height="{y1 - y0}" rx="6" fill="{fill}" '
                   f'stroke="{stroke}"/>')
        out.append(f'  <text x="{(x0 + x1) // 2}" y="{y0 + 19}" text-anchor="middle" font-weight="bold">'
                   f"{html.escape(name)}</text>")
        out.append(f'  <text x="{(x0 + x1) // 2}" y="{y0 + 37}" text-anchor="middle" font-size="12">'
                   f"{html.escape(text)}</text>")
    x0, y0, x1, y1 = box["gen/*"]
    out.append(f'  <rect x="{x0}" y="{y0}" width="{x1 - x0}" height="{y1 - y0}" rx="6" fill="#eef7e8" '
               'stroke="#5c8f45"/>')
    out.append(f'  <text x="{(x0 + x1) // 2}" y="{y0 + 17}" text-anchor="middle" font-size="12">'
               f'<tspan font-weight="bold">gen/NAME/</tspan>: {html.escape(GENS[3].split(": ", 1)[1])}</text>')
    for g in gens:
        x0, y0, x1, y1 = box["gen/" + g]
        out.append(f'  <rect x="{x0}" y="{y0}" width="{x1 - x0}" height="{y1 - y0}" rx="4" fill="#fff" '
                   f'stroke="#5c8f45"/><text x="{(x0 + x1) // 2}" y="{y0 + 18}" text-anchor="middle">{g}</text>')

    # arrows: those of every generator to one folder, and of the list to every generator, drawn once
    # from or to the group; an arrow between two generators curves below them
    gen_dirs = ["gen/" + g for g in gens]
    lines = []
    shared = {b for b in may if all((g, b) in edges or any(b in may.get(c, ()) for c in may[g]) for g in gen_dirs)}
    drawn = set()
    for a, b in edges:
        if a in gen_dirs and b in shared and b not in gen_dirs:
            a = "gen/*"
        if a == "gen" and b in gen_dirs:
            b = "gen/*"
        if (a, b) in drawn:
            continue
        drawn.add((a, b))
        ax0, ay0, ax1, ay1 = box[a]
        bx0, by0, bx1, by1 = box[b]
        if a in gen_dirs and b in gen_dirs:
            y = (ay0 + ay1) // 2
            if ay0 == by0 and abs(gens.index(a[4:]) - gens.index(b[4:])) == 1:  # neighbours: straight
                sx, tx = (ax0, bx1 + 2) if bx0 < ax0 else (ax1, bx0 - 2)
                lines.append(f'    <line x1="{sx}" y1="{y}" x2="{tx}" y2="{y}"/>')
            else:
                sx, tx = (ax0 + ax1) // 2, (bx0 + bx1) // 2
                lines.append(f'    <path d="M{sx},{ay1} C{sx},{ay1 + 14} {tx},{ay1 + 14} {tx},{by1 + 2}"/>')
            continue
        lo, hi = max(ax0, bx0), min(ax1, bx1)
        if hi - lo > 40:
            x = (lo + hi) // 2
            lines.append(f'    <line x1="{x}" y1="{ay1}" x2="{x}" y2="{by0 - 2}"/>')
        else:
            lines.append(f'    <line x1="{(ax0 + ax1) // 2}" y1="{ay1}" x2="{(bx0 + bx1) // 2}" y2="{by0 - 2}"/>')
    out.append('  <g stroke="#555" stroke-width="1.5" fill="none" marker-end="url(#a)">')
    out += lines
    out.append("  </g>")
    # core reads the list's one symbol at link time: no include
    cx0, cy0, _, cy1 = box["core"]
    lx0, ly0, _, ly1 = box["gen"]
    ymid = (cy0 + cy1) // 2
    out.append(f'  <path d="M{cx0},{ymid} C{cx0 - 14},{ymid} {lx0 - 14},{(ly0 + ly1) // 2} {lx0 - 1},'
               f'{(ly0 + ly1) // 2}" stroke="#999" stroke-width="1.3" stroke-dasharray="5,4" fill="none" '
               'marker-end="url(#a)"/>')
    out.append(f'  <text x="{W // 2}" y="{height - 14}" text-anchor="middle" font-size="11" fill="#777">dashed: core '
               "reads the list (fb_gen_list) at link time, with no include; the program links every folder</text>")
    out.append("</svg>")
    return "\n".join(out) + "\n"


if __name__ == "__main__":
    sys.stdout.write(draw(os.path.abspath(sys.argv[1] if len(sys.argv) > 1 else
                                          os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))))
