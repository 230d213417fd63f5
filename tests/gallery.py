#!/usr/bin/env python3
"""The gallery (docs/gallery.md): every docs/examples/gallery-*.json is shown there with its picture
(docs/img/gallery-NAME.png, which exists), and bakes (scripts/gallery.sh at 320 pixels wide) into a
picture of the scene's aspect that is not flat: at least 1% of its pixels lit and its luminance
spread (standard deviation) at least 2 levels of 255.

Usage: gallery.py ROOT FRACTALBAKE
"""
import glob
import json
import os
import struct
import subprocess
import sys
import tempfile
import zlib


def png_pixels(path):
    """Width, height and every pixel, as a tuple of its 1 or 3 samples, of an 8-bit RGB or grey PNG."""
    d = open(path, 'rb').read()
    w, h, depth, kind = struct.unpack('>IIBB', d[16:26])
    assert depth == 8 and kind in (0, 2), (path, depth, kind)
    ch = 3 if kind == 2 else 1
    idat, i = b'', 8
    while i < len(d):
        n, t = struct.unpack('>I4s', d[i:i + 8])
        if t == b'IDAT':
            idat += d[i + 8:i + 8 + n]
        i += 12 + n
    raw, stride, prev, px = zlib.decompress(idat), w * ch, bytearray(w * ch), []
    for y in range(h):
        f, row = raw[y * (stride + 1)], bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for x in range(stride):
            a = row[x - ch] if x >= ch else 0
            b, c = prev[x], prev[x - ch] if x >= ch else 0
            if f == 1: row[x] = (row[x] + a) & 255
            elif f == 2: row[x] = (row[x] + b) & 255
            elif f == 3: row[x] = (row[x] + (a + b) // 2) & 255
            elif f == 4:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                row[x] = (row[x] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
        prev = row
        px += [tuple(row[x * ch:(x + 1) * ch]) for x in range(w)]
    return w, h, px


def png_grey(path):
    """Width, height and the luminance of every pixel of an 8-bit RGB or grey PNG."""
    w, h, px = png_pixels(path)
    return w, h, [sum(p) / len(p) for p in px]


def main():
    root, fb = sys.argv[1], sys.argv[2]
    scenes = sorted(glob.glob(os.path.join(root, 'docs', 'examples', 'gallery-*.json')))
    text = open(os.path.join(root, 'docs', 'gallery.md'), encoding='utf-8').read()
    bad = []
    if len(scenes) < 6:
        bad.append('%d gallery scenes, want 6' % len(scenes))
    for s in scenes:
        name = os.path.basename(s)[:-5]
        for ref in ('examples/%s.json' % name, 'img/%s.png' % name):
            if ref not in text:
                bad.append('docs/gallery.md does not show %s' % ref)
        if not os.path.exists(os.path.join(root, 'docs', 'img', name + '.png')):
            bad.append('docs/img/%s.png is missing' % name)
    with tempfile.TemporaryDirectory() as out:
        env = dict(os.environ, FB=fb)
        p = subprocess.run(['bash', os.path.join(root, 'scripts', 'gallery.sh'), '--width', '320', out], env=env,
                           capture_output=True, text=True)
        if p.returncode:
            bad.append('gallery.sh failed: ' + p.stderr.strip())
        for s in scenes if not p.returncode else []:
            name = os.path.basename(s)[:-5]
            W, H = json.loads(subprocess.run([fb, 'scene', s], capture_output=True, text=True, cwd=root).stdout)['size']
            w, h, lum = png_grey(os.path.join(out, name + '.png'))
            if (w, h) != (320, max(1, round(H * 320 / W))):
                bad.append('%s: %d x %d, want 320 x %d' % (name, w, h, round(H * 320 / W)))
            lit = sum(1 for v in lum if v > 8) / len(lum)
            mean = sum(lum) / len(lum)
            sd = (sum((v - mean) ** 2 for v in lum) / len(lum)) ** 0.5
            if lit < 0.01 or sd < 2:
                bad.append('%s: a flat picture (%.1f%% of pixels lit, sd %.2f)' % (name, 100 * lit, sd))
            else:
                print('%s: %d x %d, %.0f%% lit, sd %.1f' % (name, w, h, 100 * lit, sd))
    for b in bad:
        print('FAIL: ' + b, file=sys.stderr)
    print('%d scenes, %d failures' % (len(scenes), len(bad)))
    return 1 if bad else 0


if __name__ == '__main__':
    sys.exit(main())
