#!/usr/bin/env python3
"""An independent implementation of fractalbake's fBm pixel (gradient noise), written from the
formulas, for pinning k_fbm_pixel's values in tests/test_kernels.c.

fbm(u, v) = sum_i G^i shape(noise_i(x_i)), x_0 = (u fx, v fy) + offset,
x_{i+1} = L R x_i + o_{i+1}; gradient noise on a square lattice: eight gradients (+-1, +-2),
(+-2, +-1) picked by an integer hash of the cell, quintic fade 6t^5 - 15t^4 + 10t^3, scaled by
1 / (sqrt(5) sqrt(2) / 2) = 0.6324555. Randomness: Wellons' lowbias32 finaliser.

Every operation is rounded to binary32 as the kernel computes it (a single +, -, * in double and
rounded once to float is the correctly rounded float result), so the values should agree bit for
bit; the test allows 1e-6.

Usage: fbm_reference.py   prints the C table the test holds.
"""
import math
import struct

M = 0xFFFFFFFF


def f32(x):
    return struct.unpack('<f', struct.pack('<f', x))[0]


def h(x):  # lowbias32
    x &= M
    x ^= x >> 16
    x = (x * 0x7FEB352D) & M
    x ^= x >> 15
    x = (x * 0x846CA68B) & M
    x ^= x >> 16
    return x


def h3(seed, stream, index):
    return h(index ^ h(stream ^ h(seed ^ 0x9E3779B9)))


def h2i(seed, ix, iy):
    return h(((ix * 0x9E3779B1) & M) ^ h(iy ^ seed ^ 0x632BE5AB))


def add(a, b): return f32(a + b)
def sub(a, b): return f32(a - b)
def mul(a, b): return f32(a * b)


def grad(hh, x, y):
    b = hh & 7
    u, v = (x, y) if b < 4 else (y, x)
    a = -u if b & 1 else u
    c = mul(-2.0, v) if b & 2 else mul(2.0, v)
    return add(a, c)


def fade(t):
    return mul(mul(mul(t, t), t), add(mul(t, sub(mul(t, 6.0), 15.0)), 10.0))


def mix(a, b, t):
    return add(a, mul(sub(b, a), t))


PERIOD = 4096  # the lattice wraps far beyond any visible scale


def gradient_noise(seed, x, y):
    fx, fy = float(math.floor(x)), float(math.floor(y))
    tx, ty = sub(x, fx), sub(y, fy)
    ix0, iy0 = int(fx) % PERIOD, int(fy) % PERIOD
    ix1, iy1 = (ix0 + 1) % PERIOD, (iy0 + 1) % PERIOD
    n00 = grad(h2i(seed, ix0, iy0), tx, ty)
    n10 = grad(h2i(seed, ix1, iy0), sub(tx, 1.0), ty)
    n01 = grad(h2i(seed, ix0, iy1), tx, sub(ty, 1.0))
    n11 = grad(h2i(seed, ix1, iy1), sub(tx, 1.0), sub(ty, 1.0))
    u, v = fade(tx), fade(ty)
    return mul(f32(0.6324555), mix(mix(n00, n10, u), mix(n01, n11, u), v))


def shape(n, ridged):
    if ridged:
        r = sub(1.0, abs(n))
        return mul(r, r)
    return n


def fbm_uv(p, stream, u, v):
    seed = h3(p['seed'], stream, 0x0FB0)
    x = add(mul(u, p['fx']), p['ox'])
    y = add(mul(v, p['fy']), p['oy'])
    amp, total = 1.0, 0.0
    c, s, L = p['rc'], p['rs'], p['lac']
    for i in range(p['octaves']):
        hh = h((seed + i * 0x9E3779B9) & M)
        total = add(total, mul(amp, shape(gradient_noise(hh, x, y), p['ridged'])))
        amp = mul(amp, p['gain'])
        nx = mul(L, sub(mul(c, x), mul(s, y)))
        ny = mul(L, add(mul(s, x), mul(c, y)))
        ho = h(hh ^ 0x5BD1E995)
        x = add(nx, mul(float(ho & 0xFFFF), f32(64.0 / 65536.0)))
        y = add(ny, mul(float(ho >> 16), f32(64.0 / 65536.0)))
    return total


def fbm_pixel(p, px, py):
    u = mul(add(float(px), 0.5), p['iw'])
    v = sub(1.0, mul(add(float(py), 0.5), p['ih']))
    if p['warp'] != 0.0:
        du, dv = fbm_uv(p, 1, u, v), fbm_uv(p, 2, u, v)
        u = add(u, mul(mul(p['warp'], du), p['ifx']))
        v = add(v, mul(mul(p['warp'], dv), p['ify']))
    return fbm_uv(p, 0, u, v)


def params(seed, octaves, hurst, lac, rot_deg, fx, fy, ox, oy, warp, w, hgt, ridged):
    a = math.radians(rot_deg)
    return dict(seed=seed, octaves=octaves, gain=f32(2.0 ** -hurst), lac=f32(lac), rc=f32(math.cos(a)),
                rs=f32(math.sin(a)), fx=f32(fx), fy=f32(fy), ox=f32(ox), oy=f32(oy), warp=f32(warp),
                iw=f32(1.0 / w), ih=f32(1.0 / hgt), ifx=f32(1.0 / fx), ify=f32(1.0 / fy), w=w, h=hgt,
                ridged=ridged)


CASES = [
    params(1, 8, 0.5, 2.0, 0.0, 4.0, 4.0, 0.0, 0.0, 0.0, 256, 256, False),
    params(77, 12, 0.8, 2.1, 30.0, 6.0, 3.0, -17.25, 3.5, 0.0, 300, 150, False),
    params(4000000000, 6, 0.3, 2.5, -20.0, 5.0, 5.0, 2.0, 1.0, 0.7, 128, 128, True),
]
PIXELS = [(0, 0), (1, 0), (0, 1), (17, 5), (100, 100), (127, 3), (64, 127), (99, 41)]

if __name__ == '__main__':
    for k, p in enumerate(CASES):
        vals = ', '.join('%.9ef' % fbm_pixel(p, x, y) for x, y in PIXELS)
        print('    /* case %d */ {%s},' % (k, vals))
