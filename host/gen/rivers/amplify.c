/*
 * The amplification of a coarse stream-power solution (amplify.h).
 */
#include "amplify.h"

#include "kernels/hash.h"
#include "kernels/noise.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* A channel's reach, coarse units: no further from its segment, a channel is not looked at (so the
 * 5 x 5 cells around a pixel hold every channel that reaches it: a segment lies within 1.3 cells of
 * its cell's centre). */
#define REACH 0.7
/* How far a channel's point lies from its cell's centre, at most (coarse units, each axis). */
#define JITTER 0.3
/* The bed's half-width: world units per square root of the drainage area, and its bounds. */
#define BED_PER_SQRT_AREA 0.001
#define BED_MAX           0.45
/* The land's detail is faded out within this many pixels of the bed of a channel draining this many
 * coarse cells or more. */
#define FADE_CELLS 4
/* The banks rise at least this many times as fast as the bed falls. */
#define BANK_PER_FALL 3
#define FADE_PIXELS   3

uint64_t fb_rivers_amp_memory(int cw, int ch)
{
    uint64_t n = (uint64_t)cw * ch;
    /* h, slope, lake, seg, and the order's scratch while it is built (receiver, count, order) */
    return n * (8 + 4 + 4 + sizeof(fb_rivers_seg) + 12);
}

void fb_rivers_amp_fini(fb_rivers_amp *a)
{
    if (!a) return;
    free(a->h), free(a->slope), free(a->lake), free(a->seg);
    memset(a, 0, sizeof *a);
}

/* The spacing of single-precision values at |x| and below 2 |x|: an upper bound of one step. */
static double ulp2(double x)
{
    float f = (float)fmin(2 * fabs(x) + FLT_MIN, FLT_MAX);
    return (double)nextafterf(f, INFINITY) - f;
}

/* Cell i's channel point: off the grid's lines, from the seed; an outlet on the grid's edge at the
 * image's edge, so that its channels run out of the image rather than end inside it. */
static void point_of(const fb_rivers_amp *a, const int32_t *rcv, int32_t i, double *px, double *py)
{
    const int cw = a->cw, ch = a->ch, x = i % cw, y = i / cw;
    *px = x + 2 * JITTER * (k_u01(k_hash3(a->seed, 0x61706a78u /* apjx */, (uint32_t)i)) - 0.5);
    *py = y + 2 * JITTER * (k_u01(k_hash3(a->seed, 0x61706a79u /* apjy */, (uint32_t)i)) - 0.5);
    if (rcv[i] != i) return;
    if (x == 0) *px = -0.5;
    if (x == cw - 1) *px = cw - 0.5;
    if (y == 0) *py = -0.5;
    if (y == ch - 1) *py = ch - 0.5;
}

/* Receivers before donors (Kahn's from the cells no other drains to, read backwards). */
static bool order_of(const int32_t *rcv, size_t n, int32_t *order)
{
    uint32_t *cnt = calloc(n, sizeof *cnt);
    if (!cnt) return false;
    for (size_t i = 0; i < n; i++)
        if (rcv[i] != (int32_t)i) cnt[rcv[i]]++;
    size_t tail = 0;
    for (size_t i = 0; i < n; i++)
        if (!cnt[i]) order[tail++] = (int32_t)i;
    for (size_t head = 0; head < tail; head++) {
        int32_t i = order[head], r = rcv[i];
        if (r != i && !--cnt[r]) order[tail++] = r;
    }
    free(cnt);
    for (size_t k = 0; k < tail / 2; k++) {
        int32_t t = order[k];
        order[k] = order[tail - 1 - k], order[tail - 1 - k] = t;
    }
    return tail == n;
}

/* The coarse surface raised, receivers first, so that each cell stands above its receiver by more
 * than single precision resolves over its segment's pixels; its slope; every channel. */
static void build(fb_rivers_amp *a, const fb_rivers_desc *d, const fb_rivers_out *o, const int32_t *order)
{
    const int cw = a->cw, ch = a->ch;
    const size_t n = (size_t)cw * ch;
    const double cell = d->cell, per_px = 1 / a->sx; /* output pixels per coarse unit */
    for (size_t k = 0; k < n; k++) {
        int32_t i = order[k], r = o->receiver[i];
        bool sea = d->has_sea && (double)o->height[i] < d->sea_level;
        double s = d->keep_lakes && !sea ? (double)o->height[i] + o->lake[i] : o->height[i];
        if (r != i) {
            double len = (abs(i % cw - r % cw) + abs(i / cw - r / cw) > 1 ? M_SQRT2 : 1) * per_px;
            double need = 2 * (len + 4) * ulp2(fmax(fabs(a->h[r]), fabs(s)));
            if (s < a->h[r] + need) s = a->h[r] + need;
        }
        a->h[i] = s;
        if (a->lake) a->lake[i] = d->keep_lakes && !sea ? o->lake[i] : 0;
    }
    for (int y = 0; y < ch; y++)
        for (int x = 0; x < cw; x++) {
            int xl = x > 0 ? x - 1 : x, xr = x + 1 < cw ? x + 1 : x, yu = y > 0 ? y - 1 : y,
                yd = y + 1 < ch ? y + 1 : y;
            double gx = xr > xl ? (a->h[(size_t)y * cw + xr] - a->h[(size_t)y * cw + xl]) / ((xr - xl) * cell) : 0;
            double gy = yd > yu ? (a->h[(size_t)yd * cw + x] - a->h[(size_t)yu * cw + x]) / ((yd - yu) * cell) : 0;
            a->slope[(size_t)y * cw + x] = (float)sqrt(gx * gx + gy * gy);
        }
    for (size_t k = 0; k < n; k++) {
        int32_t i = order[k], r = o->receiver[i];
        fb_rivers_seg *s = &a->seg[i];
        double px, py, qx, qy;
        point_of(a, o->receiver, i, &px, &py);
        s->px = (float)px, s->py = (float)py, s->area = o->area[i];
        double hb = BED_PER_SQRT_AREA * sqrt(o->area[i]) / cell;
        hb = fmin(fmax(hb, 0.75 * a->sx), BED_MAX);
        s->hb = (float)hb;
        s->bank = fmax(1.5 * a->slope[i], 0.05) * cell;
        if (r == i) { /* an outlet: the bed is the surface */
            s->c0 = s->c1 = a->h[i];
            continue;
        }
        point_of(a, o->receiver, r, &qx, &qy);
        s->ex = (float)(qx - px), s->ey = (float)(qy - py);
        s->inv_len2 = 1.0f / (s->ex * s->ex + s->ey * s->ey);
        double want = a->h[i] - s->bank * (hb + 1.5 * a->sx) - 0.1 * hb * cell;
        double c1 = a->seg[r].c0;
        s->c0 = fmax(want, c1 + 0.5 * (a->h[i] - a->h[r]));
        s->c1 = c1;
        /* banks steeper than the bed falls, so that the water beside it runs into it, not along it */
        s->bank = fmax(s->bank, BANK_PER_FALL * (s->c0 - s->c1) * sqrt(s->inv_len2));
    }
}

fb_result fb_rivers_amp_init(fb_rivers_amp *a, const fb_rivers_desc *d, const fb_rivers_out *o, int W, int H,
                             double detail)
{
    memset(a, 0, sizeof *a);
    a->W = W, a->H = H, a->cw = d->width, a->ch = d->height;
    a->sx = (double)a->cw / W, a->sy = (double)a->ch / H;
    a->cell = d->cell * a->sx;
    a->has_sea = d->has_sea, a->sea_level = d->sea_level, a->river_area = d->river_area;
    a->detail = detail, a->seed = d->seed;
    a->lambda = 2 / a->sx;
    a->octaves = (int)lround(log2(a->lambda));
    if (a->octaves < 1) a->octaves = 1;
    size_t n = (size_t)a->cw * a->ch;
    int32_t *order = malloc(n * sizeof *order);
    a->h = malloc(n * sizeof *a->h);
    a->slope = malloc(n * sizeof *a->slope);
    a->lake = d->keep_lakes ? malloc(n * sizeof *a->lake) : NULL;
    a->seg = calloc(n, sizeof *a->seg);
    bool ok = order && a->h && a->slope && (a->lake || !d->keep_lakes) && a->seg;
    if (ok && !order_of(o->receiver, n, order)) {
        free(order);
        fb_rivers_amp_fini(a);
        return fb_fail(FB_ERR_INTERNAL, "rivers: the coarse receivers form a loop");
    }
    if (ok) build(a, d, o, order);
    free(order);
    if (!ok) {
        fb_rivers_amp_fini(a);
        return fb_fail(FB_ERR_NOMEM, "rivers: out of memory for the amplification of %d x %d cells", d->width,
                       d->height);
    }
    return FB_OK;
}

/* ---- the rows ----------------------------------------------------------------------------------- */

/* Catmull-Rom weights at t in [0, 1). */
static void cubic(double t, double w[4])
{
    double t2 = t * t, t3 = t2 * t;
    w[0] = 0.5 * (-t3 + 2 * t2 - t);
    w[1] = 0.5 * (3 * t3 - 5 * t2 + 2);
    w[2] = 0.5 * (-3 * t3 + 4 * t2 + t);
    w[3] = 0.5 * (t3 - t2);
}

/* Value j of a line of n (row or column), extended linearly beyond its ends. */
static double line_at(const double *v, size_t stride, int n, int j)
{
    if (n == 1) return v[0];
    if (j < 0) return v[0] + j * (v[stride] - v[0]);
    if (j >= n)
        return v[(size_t)(n - 1) * stride] + (j - n + 1) * (v[(size_t)(n - 1) * stride] - v[(size_t)(n - 2) * stride]);
    return v[(size_t)j * stride];
}

static int clampi(int v, int lo, int hi)
{
    return v < lo ? lo : v > hi ? hi : v;
}

/* The land's interpolated surface and slope at coarse (u, v). */
static void land_at(const fb_rivers_amp *a, double u, double v, double *h, double *slope)
{
    int x0 = (int)floor(u), y0 = (int)floor(v);
    double wx[4], wy[4];
    cubic(u - x0, wx), cubic(v - y0, wy);
    double sh = 0, ss = 0;
    for (int j = 0; j < 4; j++) {
        int y = y0 - 1 + j;
        double rh = 0, rs = 0;
        if (y >= 0 && y < a->ch) {
            const double *row = a->h + (size_t)y * a->cw;
            for (int i = 0; i < 4; i++) rh += wx[i] * line_at(row, 1, a->cw, x0 - 1 + i);
        } else { /* beyond the grid: each column extended linearly */
            for (int i = 0; i < 4; i++) {
                int x = clampi(x0 - 1 + i, 0, a->cw - 1);
                double cv = line_at(a->h + x, (size_t)a->cw, a->ch, y);
                if (x != x0 - 1 + i) { /* a corner: extended along the row too */
                    double e = line_at(a->h + (size_t)clampi(y, 0, a->ch - 1) * a->cw, 1, a->cw, x0 - 1 + i);
                    cv += e - a->h[(size_t)clampi(y, 0, a->ch - 1) * a->cw + x];
                }
                rh += wx[i] * cv;
            }
        }
        int yc = clampi(y, 0, a->ch - 1);
        for (int i = 0; i < 4; i++) rs += wx[i] * a->slope[(size_t)yc * a->cw + clampi(x0 - 1 + i, 0, a->cw - 1)];
        sh += wy[j] * rh, ss += wy[j] * rs;
    }
    *h = sh, *slope = ss > 0 ? ss : 0;
}

/* Bilinear depth of kept lakes at coarse (u, v). */
static double lake_at(const fb_rivers_amp *a, double u, double v)
{
    int x0 = (int)floor(u), y0 = (int)floor(v);
    double tx = u - x0, ty = v - y0;
    int xa = clampi(x0, 0, a->cw - 1), xb = clampi(x0 + 1, 0, a->cw - 1);
    int ya = clampi(y0, 0, a->ch - 1), yb = clampi(y0 + 1, 0, a->ch - 1);
    const float *l = a->lake;
    double top = l[(size_t)ya * a->cw + xa] * (1 - tx) + l[(size_t)ya * a->cw + xb] * tx;
    double bot = l[(size_t)yb * a->cw + xa] * (1 - tx) + l[(size_t)yb * a->cw + xb] * tx;
    return top * (1 - ty) + bot * ty;
}

/* fBm of gradient noise at output pixel (x, y), its octaves' amplitudes halving: about 1 in
 * amplitude, its slope per pixel about octaves / lambda. */
static double fbm_at(const fb_rivers_amp *a, int x, int y)
{
    double f = 0, amp = 1, freq = 1 / a->lambda;
    for (int o = 0; o < a->octaves; o++) {
        f += amp * k_gradient_noise(a->seed + 0x9e3779b9u * (uint32_t)(o + 1), (float)(x * freq), (float)(y * freq),
                                    1u << 24, 1u << 24);
        amp *= 0.5, freq *= 2;
    }
    return f;
}

typedef struct channel_hit {
    double level; /* the lowest channel's surface (+infinity: none reaches) */
    double d, hb; /* its distance and bed half-width */
    float area;   /* */
    double fade;  /* the detail's factor: 0 beside a channel, 1 away from them */
} channel_hit;

static void channels_at(const fb_rivers_amp *a, double u, double v, channel_hit *hit)
{
    int x0 = (int)floor(u), y0 = (int)floor(v);
    double fade_area = FADE_CELLS * a->cell * a->cell / (a->sx * a->sx);
    hit->level = INFINITY, hit->fade = 1, hit->d = 0, hit->hb = 0, hit->area = 0;
    for (int y = y0 - 2 > 0 ? y0 - 2 : 0; y <= y0 + 2 && y < a->ch; y++)
        for (int x = x0 - 2 > 0 ? x0 - 2 : 0; x <= x0 + 2 && x < a->cw; x++) {
            const fb_rivers_seg *s = &a->seg[(size_t)y * a->cw + x];
            if (s->inv_len2 == 0) continue;
            double rx = u - s->px, ry = v - s->py;
            double t = (rx * s->ex + ry * s->ey) * s->inv_len2;
            t = t < 0 ? 0 : t > 1 ? 1 : t;
            double dx = rx - t * s->ex, dy = ry - t * s->ey, dist = sqrt(dx * dx + dy * dy);
            if (dist > REACH) continue;
            double fall = s->c0 - s->c1; /* the bed leans to its line by as much as it falls along it */
            double level =
                s->c0 - fall * t + fall * sqrt(s->inv_len2) * fmin(dist, s->hb) + s->bank * fmax(0, dist - s->hb);
            if (level < hit->level) hit->level = level, hit->d = dist, hit->hb = s->hb, hit->area = s->area;
            if (s->area >= fade_area) {
                double f = (dist - s->hb) / (FADE_PIXELS * a->sx);
                f = f < 0 ? 0 : f > 1 ? 1 : f;
                f = f * f * (3 - 2 * f);
                if (f < hit->fade) hit->fade = f;
            }
        }
}

void fb_rivers_amp_rows(const fb_rivers_amp *a, int y0, int n, float *Y, float *area, float *river, float *lake)
{
    const double cell2 = a->cell * a->cell, norm = a->lambda * a->cell / (0.8 * a->octaves);
    for (int y = y0; y < y0 + n; y++) {
        double v = (y + 0.5) * a->sy - 0.5;
        for (int x = 0; x < a->W; x++) {
            size_t o = (size_t)(y - y0) * a->W + x;
            double u = (x + 0.5) * a->sx - 0.5, base, slope;
            land_at(a, u, v, &base, &slope);
            channel_hit hit;
            channels_at(a, u, v, &hit);
            double land = base + a->detail * slope * norm * hit.fade * fbm_at(a, x, y);
            bool in_channel = hit.level < land;
            double s = in_channel ? hit.level : land;
            double wet = a->lake ? lake_at(a, u, v) : 0;
            float z = (float)(s - wet);
            bool bed = in_channel && hit.d <= hit.hb + 0.5 * a->sx;
            bool sea = a->has_sea && (double)z < a->sea_level;
            if (Y) Y[o] = z;
            if (area) area[o] = bed ? hit.area : (float)cell2;
            if (river) river[o] = bed && !sea && hit.area >= a->river_area ? 1.0f : 0.0f;
            if (lake) lake[o] = sea ? fmaxf((float)(a->sea_level - z), FLT_TRUE_MIN) : wet > 0 ? (float)wet : 0.0f;
        }
    }
}
