/*
 * Anti-aliased coverage of L-system segments (SPEC.md section 3), one pixel at a time.
 *
 * A segment is a rectangle: from its start point (ax, ay) along the unit direction (ux, uy) for
 * `len` pixels, `hw` pixels to either side. A pixel's coverage by it is the area of the pixel's
 * unit box, in the segment's own frame, that the rectangle covers: the product of the overlap of
 * [s - 1/2, s + 1/2] with [-hw, hw] across and of [t - 1/2, t + 1/2] with [0, len] along, where
 * (t, s) is the pixel centre's position along and across. This is exact for the box filter turned
 * with the segment; a line of width w then deposits w coverage per pixel of length whatever its
 * width, so sub-pixel branches fade instead of vanishing or aliasing. Butt ends make consecutive
 * collinear segments add up to exactly one rectangle.
 *
 * A pixel sums its segments' coverages (order-independent up to rounding; the order is fixed: the
 * segments' drawing order) and clamps the sum to 1: coverage adds where branches are disjoint and
 * saturates where they overlap. Colour is the coverage-weighted mean of the segments' colours,
 * premultiplied by the clamped coverage.
 *
 * Only adds, multiplies, min and max, all `precise`: C built with -ffp-contract=off and a shader
 * round identically, so the native and Vulkan backends give the same bits.
 */
#ifndef FB_KERNELS_LSYS_H
#define FB_KERNELS_LSYS_H

#include "common.h"
#include "exact.h"

#define K_LSYS_SEG_WORDS 9u /* ax ay ux uy len hw r g b */

/* The push constants: the image, its tiles, and where the lists start in the input words. The
 * input holds tile_start[tiles + 1] (offsets into the index list), the index list (segment numbers,
 * each tile's in drawing order) at word idx_off, and the segments at seg_off, 9 words each. */
K_STRUCT(K_LsysParams)
{
    uint width, height;
    uint tiles_x;    /* tiles per row */
    uint tile_shift; /* tiles are (1 << tile_shift) pixels square */
    uint idx_off;
    uint seg_off;
    uint pad0, pad1;
}
K_END(K_LsysParams)

K_STRUCT(K_LsysSeg)
{
    float ax, ay, ux, uy, len, hw;
    float r, g, b;
}
K_END(K_LsysSeg)

/* Coverage sums of one pixel. */
K_STRUCT(K_LsysAcc)
{
    float a, r, g, b;
}
K_END(K_LsysAcc)

/* The overlap of [c - 1/2, c + 1/2] with [lo, hi]. */
K_FN float k_lsys_overlap(float c, float lo, float hi)
{
    K_PRECISE float o = k_min(c + 0.5f, hi) - k_max(c - 0.5f, lo);
    return k_max(o, 0.0f);
}

/* The coverage of the pixel centred at (px, py) by segment s. */
K_FN float k_lsys_cover(K_LsysSeg s, float px, float py)
{
    K_PRECISE float dx = px - s.ax;
    K_PRECISE float dy = py - s.ay;
    K_PRECISE float t = dx * s.ux + dy * s.uy;
    K_PRECISE float q = dx * s.uy - dy * s.ux;
    K_PRECISE float c = k_lsys_overlap(q, -s.hw, s.hw) * k_lsys_overlap(t, 0.0f, s.len);
    return c;
}

K_FN K_LsysAcc k_lsys_add(K_LsysAcc acc, K_LsysSeg s, float px, float py)
{
    K_PRECISE float c = k_lsys_cover(s, px, py);
    K_PRECISE float a = acc.a + c;
    K_PRECISE float r = acc.r + c * s.r;
    K_PRECISE float g = acc.g + c * s.g;
    K_PRECISE float b = acc.b + c * s.b;
    K_LsysAcc o;
    o.a = a;
    o.r = r;
    o.g = g;
    o.b = b;
    return o;
}

/* Clamps the coverage to 1 and scales the colour sums with it (premultiplied colour). */
K_FN K_LsysAcc k_lsys_finish(K_LsysAcc acc)
{
    if (acc.a <= 1.0f) return acc;
    K_PRECISE float k = kx_div(1.0f, acc.a);
    K_PRECISE float r = acc.r * k;
    K_PRECISE float g = acc.g * k;
    K_PRECISE float b = acc.b * k;
    K_LsysAcc o;
    o.a = 1.0f;
    o.r = r;
    o.g = g;
    o.b = b;
    return o;
}

#endif
