#!/usr/bin/env python3
"""An independent SSIM for `fractalbake compare --ssim`, in plain Python (no numpy).

Writes test pictures as 16-bit grey PNGs into OUTDIR and prints, as one JSON object, the mean SSIM
of each pair computed here straight from the definition of Wang, Bovik, Sheikh and Simoncelli,
"Image quality assessment: from error visibility to structural similarity" (IEEE Transactions on
Image Processing 13(4), 2004): eq. 13 with the 11 x 11 Gaussian window of standard deviation 1.5
(normalised), K1 = 0.01, K2 = 0.03, L = 1 (a PNG's full scale), averaged (eq. 17) over every
position where the window lies inside the image. No separable filtering, no streaming: a direct
double loop over each window, so that it shares nothing with the C implementation but the paper.

Also prints the closed form for two constant pictures a and b, where every window has zero
variance and covariance: SSIM = (2ab + C1) / (a^2 + b^2 + C1).

Usage: ssim_reference.py OUTDIR
"""
import json
import math
import os
import struct
import sys
import zlib


def f32(v):
    """v rounded to binary32, as fractalbake holds a PNG sample."""
    return struct.unpack("<f", struct.pack("<f", v))[0]


def write_png16(path, w, h, samples):
    raw = bytearray()
    for y in range(h):
        raw.append(0)  # filter: none
        for x in range(w):
            raw += struct.pack(">H", samples[y * w + x])

    def chunk(kind, data):
        c = struct.pack(">I", len(data)) + kind + data
        return c + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)

    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n")
        f.write(chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 16, 0, 0, 0, 0)))
        f.write(chunk(b"IDAT", zlib.compress(bytes(raw))))
        f.write(chunk(b"IEND", b""))


def ssim(a, b, w, h, L=1.0):
    r, sigma = 5, 1.5
    g = [math.exp(-((i - r) ** 2 + (j - r) ** 2) / (2 * sigma * sigma)) for j in range(11) for i in range(11)]
    s = sum(g)
    g = [v / s for v in g]
    c1, c2 = (0.01 * L) ** 2, (0.03 * L) ** 2
    total, n = 0.0, 0
    for y in range(r, h - r):
        for x in range(r, w - r):
            ma = mb = aa = bb = ab = 0.0
            k = 0
            for j in range(-r, r + 1):
                row = (y + j) * w
                for i in range(-r, r + 1):
                    wgt = g[k]
                    k += 1
                    va, vb = a[row + x + i], b[row + x + i]
                    ma += wgt * va
                    mb += wgt * vb
                    aa += wgt * va * va
                    bb += wgt * vb * vb
                    ab += wgt * va * vb
            var_a, var_b, cov = aa - ma * ma, bb - mb * mb, ab - ma * mb
            total += ((2 * ma * mb + c1) * (2 * cov + c2)) / ((ma * ma + mb * mb + c1) * (var_a + var_b + c2))
            n += 1
    return total / n


def main():
    out = sys.argv[1]
    w, h = 40, 31
    seed = 12345

    def rnd():
        nonlocal seed
        seed = (seed * 1103515245 + 12345) & 0x7FFFFFFF
        return seed / 0x7FFFFFFF

    # a smooth texture, and versions of it: noisy, shifted in level, lower in contrast
    base = [0.5 + 0.3 * math.sin(x * 0.31) * math.cos(y * 0.23) + 0.1 * rnd() for y in range(h) for x in range(w)]
    variants = {
        "noisy": [min(1.0, max(0.0, v + 0.08 * (rnd() - 0.5))) for v in base],
        "shifted": [min(1.0, v + 0.1) for v in base],
        "flat": [0.5 + 0.5 * (v - 0.5) for v in base],
    }
    q = lambda vs: [int(round(v * 65535)) for v in vs]
    write_png16(os.path.join(out, "base.png"), w, h, q(base))
    result = {}
    A = [f32(u / 65535) for u in q(base)]
    for name, vs in variants.items():
        write_png16(os.path.join(out, name + ".png"), w, h, q(vs))
        B = [f32(u / 65535) for u in q(vs)]
        result[name] = ssim(A, B, w, h)
    # two constant pictures: 0.2 and 0.4 are exact in 16 bits (13107 and 26214 of 65535)
    write_png16(os.path.join(out, "c02.png"), 16, 12, [13107] * 192)
    write_png16(os.path.join(out, "c04.png"), 16, 12, [26214] * 192)
    a, b, c1 = f32(13107 / 65535), f32(26214 / 65535), 0.01**2
    result["constant_closed_form"] = (2 * a * b + c1) / (a * a + b * b + c1)
    C = [a] * 192
    D = [b] * 192
    result["constant_direct"] = ssim(C, D, 16, 12)
    print(json.dumps(result))


main()
