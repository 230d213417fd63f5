/*
 * The Julia layer's native path on eight AVX2 lanes, whole: the grid (rect and polar), the
 * turbulence fBm, the allpass warp, the orbit to the bailout and on to the big radius, the smooth
 * count, the distance estimate, and the colour through the palette with its jittered samples. The
 * same operations in the same order as kernels/julia.h and kernels/palette.h, no FMA, so every
 * channel is bit-identical to the scalar kernel's (tests/test_avx2.c). Only correctly rounded
 * operations run on the lanes (+, -, *, /, sqrt, floor, min/max, conversions, bit operations): log2
 * and pow are kernels/explog.h's polynomials, the kernel's own, restated eight lanes at a time; sin
 * and cos (the polar grid) are the scalar C library's, called per lane, so they give the scalar
 * loop's bits.
 *
 * The orbit loop runs the eight orbits in one loop on a shared step counter i: a lane that reaches
 * the bailout records n = i and goes on to the big radius (at most K_JULIA_EXTRA_ITER more steps)
 * while the others still iterate, so lanes escaping early do useful work instead of waiting. A lane
 * that is finished records its state when it finishes (rare events, a branch); its arithmetic goes
 * on unused until the block ends.
 */
#include "layer_avx2.h"

#include <string.h>

#if defined(__x86_64__) || defined(__i386__)
#include "avx2_hash.h"
#include "fbm3_avx2.h"
#include "fbm_avx2_ops.h"

typedef struct v8 {
    __m256 zr, zi, dz2; /* z0 and |dz0/dx|^2 (kernels/julia.h, K_JuliaZ) */
    __m256 ok;          /* all ones: the orbit starts (not at the pole, z0 finite) */
} v8start;

/* ---- turbulence: k_fbm_uv of gradient noise, tileable or not -------------------------------------- */

AVX2 static inline __m256 grad8(__m256i h, __m256 x, __m256 y)
{
    __m256i b = _mm256_and_si256(h, _mm256_set1_epi32(7));
    __m256 lt4 = _mm256_castsi256_ps(_mm256_cmpgt_epi32(_mm256_set1_epi32(4), b));
    __m256 u = _mm256_blendv_ps(y, x, lt4);
    __m256 v = _mm256_blendv_ps(x, y, lt4);
    /* bit 0 of b is the sign of u, bit 1 that of 2v (a negation is a sign flip, exact) */
    __m256 su = _mm256_xor_ps(u, _mm256_castsi256_ps(_mm256_slli_epi32(b, 31)));
    __m256 v2 = _mm256_mul_ps(_mm256_set1_ps(2.0f), v);
    __m256 sv = _mm256_xor_ps(v2, _mm256_castsi256_ps(_mm256_slli_epi32(_mm256_srli_epi32(b, 1), 31)));
    return _mm256_add_ps(su, sv);
}

/* k_wrap_cell(i, p) for eight lanes: the mask while every lane is exact and p a power of two, else
 * the kernel's function per lane. */
AVX2 static inline __m256i wrap8p(__m256 i, uint32_t p)
{
    const __m256 absmask = _mm256_castsi256_ps(_mm256_set1_epi32(0x7fffffff));
    __m256 small = _mm256_cmp_ps(_mm256_and_ps(i, absmask), _mm256_set1_ps(16777216.0f), _CMP_LT_OQ);
    if (__builtin_expect((p & (p - 1u)) == 0u && _mm256_movemask_ps(small) == 0xff, 1))
        return _mm256_and_si256(_mm256_cvttps_epi32(i), _mm256_set1_epi32((int)(p - 1u)));
    float f[8];
    uint32_t r[8];
    _mm256_storeu_ps(f, i);
    for (int k = 0; k < 8; k++) r[k] = k_wrap_cell(f[k], p);
    return _mm256_loadu_si256((const __m256i *)r);
}

/* k_cell_add(c, 1, p) */
AVX2 static inline __m256i next_cell8(__m256i c, uint32_t p)
{
    if ((p & (p - 1u)) == 0u)
        return _mm256_and_si256(_mm256_add_epi32(c, _mm256_set1_epi32(1)), _mm256_set1_epi32((int)(p - 1u)));
    uint32_t r[8];
    _mm256_storeu_si256((__m256i *)r, c);
    for (int k = 0; k < 8; k++) r[k] = k_cell_add(r[k], 1, p);
    return _mm256_loadu_si256((const __m256i *)r);
}

/* k_gradient_noise */
AVX2 static __m256 gradient8(uint32_t seed, __m256 x, __m256 y, uint32_t px, uint32_t py)
{
    __m256 fx = _mm256_floor_ps(x), fy = _mm256_floor_ps(y);
    __m256 tx = _mm256_sub_ps(x, fx), ty = _mm256_sub_ps(y, fy);
    __m256i ix0 = wrap8p(fx, px), iy0 = wrap8p(fy, py);
    __m256i ix1 = next_cell8(ix0, px), iy1 = next_cell8(iy0, py);
    __m256i s = _mm256_set1_epi32((int)(seed ^ 0x632be5abu));
    __m256i r0 = hash8(_mm256_xor_si256(iy0, s)), r1 = hash8(_mm256_xor_si256(iy1, s));
    __m256 one = _mm256_set1_ps(1.0f);
    __m256 tx1 = _mm256_sub_ps(tx, one), ty1 = _mm256_sub_ps(ty, one);
    __m256 n00 = grad8(cell_hash8(ix0, r0), tx, ty);
    __m256 n10 = grad8(cell_hash8(ix1, r0), tx1, ty);
    __m256 n01 = grad8(cell_hash8(ix0, r1), tx, ty1);
    __m256 n11 = grad8(cell_hash8(ix1, r1), tx1, ty1);
    __m256 u = fade8(tx), v = fade8(ty);
    return _mm256_mul_ps(_mm256_set1_ps(0.6324555f), mix8(mix8(n00, n10, u), mix8(n01, n11, u), v));
}

/* k_fbm_uv(t, stream, u, v) for the turbulence's fBm (gradient noise, plain shape); other noises or
 * shapes go through the kernel per lane. */
AVX2 static __m256 fbm8(const K_FbmParams *t, uint32_t stream, __m256 u, __m256 v)
{
    if (t->noise != K_NOISE_GRADIENT || (t->flags & ~K_FBM_TILEABLE) != 0u) {
        float uu[8], vv[8], r[8];
        _mm256_storeu_ps(uu, u);
        _mm256_storeu_ps(vv, v);
        for (int k = 0; k < 8; k++) r[k] = k_fbm_uv(*t, stream, uu[k], vv[k]);
        return _mm256_loadu_ps(r);
    }
    uint32_t seed = k_hash3(t->seed, stream, 0x0fb0u);
    bool tileable = (t->flags & K_FBM_TILEABLE) != 0u;
    __m256 x = _mm256_add_ps(_mm256_mul_ps(u, _mm256_set1_ps(t->freq_x)), _mm256_set1_ps(t->offset_x));
    __m256 y = _mm256_add_ps(_mm256_mul_ps(v, _mm256_set1_ps(t->freq_y)), _mm256_set1_ps(t->offset_y));
    const __m256 L = _mm256_set1_ps(t->lacunarity), c = _mm256_set1_ps(t->rot_c), s = _mm256_set1_ps(t->rot_s);
    float cells_x = t->freq_x, cells_y = t->freq_y, amp = 1.0f;
    __m256 sum = _mm256_setzero_ps();
    for (uint32_t i = 0; i < t->octaves; i++) {
        uint32_t h = k_hash(seed + i * 0x9e3779b9u);
        uint32_t per_x = K_NOISE_PERIOD, per_y = K_NOISE_PERIOD;
        __m256 qx = x, qy = y;
        if (tileable) {
            float rx = k_max(k_floor(cells_x + 0.5f), 1.0f);
            float ry = k_max(k_floor(cells_y + 0.5f), 1.0f);
            per_x = K_U(K_I(k_min(rx, 16777216.0f)));
            per_y = K_U(K_I(k_min(ry, 16777216.0f)));
            qx = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(u, _mm256_set1_ps(rx)), _mm256_set1_ps(K_F(h & 255u))),
                               _mm256_set1_ps(t->offset_x));
            qy =
                _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(v, _mm256_set1_ps(ry)), _mm256_set1_ps(K_F((h >> 8) & 255u))),
                              _mm256_set1_ps(t->offset_y));
        }
        sum = _mm256_add_ps(sum, _mm256_mul_ps(_mm256_set1_ps(amp), gradient8(h, qx, qy, per_x, per_y)));
        amp *= t->gain;
        cells_x *= t->lacunarity;
        cells_y *= t->lacunarity;
        __m256 nx = _mm256_mul_ps(L, _mm256_sub_ps(_mm256_mul_ps(c, x), _mm256_mul_ps(s, y)));
        __m256 ny = _mm256_mul_ps(L, _mm256_add_ps(_mm256_mul_ps(s, x), _mm256_mul_ps(c, y)));
        uint32_t ho = k_hash(h ^ 0x5bd1e995u);
        x = _mm256_add_ps(nx, _mm256_set1_ps(K_F(ho & 0xffffu) * (64.0f / 65536.0f)));
        y = _mm256_add_ps(ny, _mm256_set1_ps(K_F(ho >> 16) * (64.0f / 65536.0f)));
    }
    return sum;
}

/* ---- the start: k_julia_start_at --------------------------------------------------------------- */

/* Environment maps: each lane's point and direction, projection and warp from the portable kernel
 * (k_julia_env_start: a small part of a pixel's work next to its orbit), its turbulence's 3D fBm on
 * the lanes (fbm3_avx2.c, bit-exact with k_fbm3), then the orbits on the lanes. */
AVX2 static v8start start8_env(const fb_julia_avx2_ctx *cx, __m256 fx, __m256 fy)
{
    const K_JuliaParams *p = cx->p;
    float x[8], y[8], zr[8], zi[8], dz2[8], d[3][8], w1[8], w2[8];
    uint32_t ok[8];
    K_JuliaHom e[8];
    _mm256_storeu_ps(x, fx);
    _mm256_storeu_ps(y, fy);
    for (int k = 0; k < 8; k++) {
        e[k] = k_julia_env_point(*p, x[k] - 0.5f, y[k] - 0.5f); /* k_julia_start_at's env position */
        d[0][k] = e[k].dir.x, d[1][k] = e[k].dir.y, d[2][k] = e[k].dir.z;
    }
    const bool lanes = p->lambda != 0.0f && fb_fbm3_avx2_supported(cx->turb);
    if (lanes) {
        fb_fbm3_avx2_lanes(cx->turb, 1u, d, w1);
        fb_fbm3_avx2_lanes(cx->turb, 2u, d, w2);
    }
    for (int k = 0; k < 8; k++) {
        k_vec2 w = lanes ? k_julia_turbulence_of(*p, w1[k], w2[k]) : k_julia_turbulence3(*p, *cx->turb, e[k].dir);
        K_JuliaStart s = k_julia_env_begin(*p, e[k], w.x, w.y);
        zr[k] = s.o.zr, zi[k] = s.o.zi, dz2[k] = s.o.dz2;
        ok[k] = s.ok ? 0xffffffffu : 0u;
    }
    v8start st;
    st.zr = _mm256_loadu_ps(zr);
    st.zi = _mm256_loadu_ps(zi);
    st.dz2 = _mm256_loadu_ps(dz2);
    st.ok = _mm256_castsi256_ps(_mm256_loadu_si256((const __m256i *)ok));
    return st;
}

AVX2 static v8start start8(const fb_julia_avx2_ctx *cx, __m256 fx, __m256 fy)
{
    const K_JuliaParams *p = cx->p;
    if (p->mapping >= K_JULIA_LATLONG) return start8_env(cx, fx, fy);
    __m256 u = _mm256_mul_ps(fx, _mm256_set1_ps(p->inv_width));
    __m256 v = _mm256_sub_ps(_mm256_set1_ps(1.0f), _mm256_mul_ps(fy, _mm256_set1_ps(p->inv_height)));
    __m256 x, y, dx, dy;
    if (p->mapping == K_JULIA_POLAR) {
        __m256 rr = _mm256_mul_ps(_mm256_set1_ps(p->radius), v);
        __m256 ang = _mm256_mul_ps(_mm256_set1_ps(K_TAU), _mm256_sub_ps(u, _mm256_floor_ps(u)));
        float a[8], sn[8], cs[8];
        _mm256_storeu_ps(a, ang);
        for (int k = 0; k < 8; k++) {
            k_vec2 sc = k_sincos(a[k]); /* as k_julia_start: the same bits on every device */
            sn[k] = sc.x, cs[k] = sc.y;
        }
        __m256 s = _mm256_loadu_ps(sn), c = _mm256_loadu_ps(cs);
        x = _mm256_mul_ps(rr, c);
        y = _mm256_mul_ps(rr, s);
        /* k = K_TAU * radius * v * inv_width; dx = -k sin, dy = k cos */
        __m256 k = _mm256_mul_ps(_mm256_mul_ps(_mm256_set1_ps(K_TAU * p->radius), v), _mm256_set1_ps(p->inv_width));
        dx = _mm256_mul_ps(_mm256_xor_ps(k, _mm256_set1_ps(-0.0f)), s);
        dy = _mm256_mul_ps(k, c);
    } else {
        x = _mm256_mul_ps(_mm256_set1_ps(p->scale_u), _mm256_sub_ps(u, _mm256_set1_ps(0.5f)));
        y = _mm256_mul_ps(_mm256_set1_ps(p->scale_v), _mm256_sub_ps(v, _mm256_set1_ps(0.5f)));
        dx = _mm256_set1_ps(p->scale_u * p->inv_width);
        dy = _mm256_setzero_ps();
    }
    const __m256 rc = _mm256_set1_ps(p->rot_c), rs = _mm256_set1_ps(p->rot_s);
    __m256 px = _mm256_add_ps(_mm256_set1_ps(p->center_re), _mm256_sub_ps(_mm256_mul_ps(rc, x), _mm256_mul_ps(rs, y)));
    __m256 py = _mm256_add_ps(_mm256_set1_ps(p->center_im), _mm256_add_ps(_mm256_mul_ps(rs, x), _mm256_mul_ps(rc, y)));
    __m256 dpx = _mm256_sub_ps(_mm256_mul_ps(rc, dx), _mm256_mul_ps(rs, dy));
    __m256 dpy = _mm256_add_ps(_mm256_mul_ps(rs, dx), _mm256_mul_ps(rc, dy));
    /* k_julia_turbulence: lambda W(u, v) */
    __m256 twr = _mm256_setzero_ps(), twi = _mm256_setzero_ps();
    if (p->lambda != 0.0f) {
        const __m256 half = _mm256_set1_ps(0.5f), hn = _mm256_set1_ps(0.5f * p->turb_norm);
        __m256 wr = clamp8(_mm256_add_ps(half, _mm256_mul_ps(hn, fbm8(cx->turb, 1u, u, v))), 0.0f, 1.0f);
        __m256 wi = clamp8(_mm256_add_ps(half, _mm256_mul_ps(hn, fbm8(cx->turb, 2u, u, v))), 0.0f, 1.0f);
        twr = _mm256_mul_ps(_mm256_set1_ps(p->lambda), wr);
        twi = _mm256_mul_ps(_mm256_set1_ps(p->lambda), wi);
    }
    /* k_julia_begin: z0 = (p - conj(a)) / (1 - a p), dz0/dx = (1 - |a|^2) / (1 - a p)^2 dp/dx */
    const __m256 are = _mm256_set1_ps(p->a_re), aim = _mm256_set1_ps(p->a_im), one = _mm256_set1_ps(1.0f);
    __m256 nr = _mm256_sub_ps(px, are), ni = _mm256_add_ps(py, aim);
    __m256 dr = _mm256_sub_ps(one, _mm256_sub_ps(_mm256_mul_ps(are, px), _mm256_mul_ps(aim, py)));
    __m256 di = _mm256_xor_ps(_mm256_add_ps(_mm256_mul_ps(are, py), _mm256_mul_ps(aim, px)), _mm256_set1_ps(-0.0f));
    __m256 den = _mm256_add_ps(_mm256_mul_ps(dr, dr), _mm256_mul_ps(di, di));
    __m256 ok = _mm256_cmp_ps(den, _mm256_set1_ps(1.0e-30f), _CMP_GT_OQ);
    __m256 inv = _mm256_div_ps(one, den);
    __m256 zr = _mm256_add_ps(_mm256_mul_ps(_mm256_add_ps(_mm256_mul_ps(nr, dr), _mm256_mul_ps(ni, di)), inv), twr);
    __m256 zi = _mm256_add_ps(_mm256_mul_ps(_mm256_sub_ps(_mm256_mul_ps(ni, dr), _mm256_mul_ps(nr, di)), inv), twi);
    const float kk = 1.0f - (p->a_re * p->a_re + p->a_im * p->a_im);
    __m256 sr = _mm256_mul_ps(_mm256_mul_ps(_mm256_sub_ps(_mm256_mul_ps(dr, dr), _mm256_mul_ps(di, di)), inv), inv);
    __m256 si = _mm256_mul_ps(_mm256_mul_ps(_mm256_mul_ps(_mm256_mul_ps(_mm256_set1_ps(-2.0f), dr), di), inv), inv);
    __m256 wr = _mm256_mul_ps(_mm256_set1_ps(kk), sr), wi = _mm256_mul_ps(_mm256_set1_ps(kk), si);
    v8start st;
    st.zr = zr;
    st.zi = zi;
    __m256 dzr = _mm256_sub_ps(_mm256_mul_ps(wr, dpx), _mm256_mul_ps(wi, dpy));
    __m256 dzi = _mm256_add_ps(_mm256_mul_ps(wr, dpy), _mm256_mul_ps(wi, dpx));
    st.dz2 = _mm256_add_ps(_mm256_mul_ps(dzr, dzr), _mm256_mul_ps(dzi, dzi));
    __m256 r2 = _mm256_add_ps(_mm256_mul_ps(zr, zr), _mm256_mul_ps(zi, zi));
    st.ok = _mm256_and_ps(ok, _mm256_cmp_ps(r2, _mm256_set1_ps(1.0e30f), _CMP_LT_OQ));
    return st;
}

/* ---- the orbit and its result: k_julia_run ----------------------------------------------------- */

typedef struct v8result {
    uint32_t iter[8];
    float inside[8], nsmooth[8], de[8];
} v8result;

/* The orbit loop runs NB blocks of eight lanes together on a shared step counter i (two blocks: two
 * independent dependency chains fill the pipeline, which one orbit's chain of multiply, subtract
 * and add leaves idle), and its fast path tests one condition a step: every lane has a threshold on
 * |z|^2 (the bailout while iterating, just above the big radius after it, NaN once finished: never
 * reached) and a step at which it must stop (max_iter, n + K_JULIA_EXTRA_ITER, never). Either event
 * takes the slow path, which moves the lanes on: a few times a block. */
#define AI inline __attribute__((always_inline))

typedef struct orbit8 {
    __m256 zr, zi, dz2; /* dz2: |z'|^2 */
    __m256 A, B;        /* lanes iterating to the bailout; escaped, on to the big radius */
    __m256 inside, escaped, thr;
    __m256i deadline, n_at, m_at;
    __m256 r2_at, dz2_at; /* at the end of the orbit */
} orbit8;

/* r2 > 2^32 is r2 >= 2^32 + 512 (the next float), NaN failing both */
#define BIG2_NEXT 4294967808.0f
/* (K_JULIA_BIG_RADIUS2 is 2^32: checked by test_avx2, which compares every channel with the kernel;
 * a float comparison is no integer constant expression for clang's _Static_assert.) */

AVX2 static AI void orbit_init(orbit8 *o, const K_JuliaParams *p, const v8start *st)
{
    const __m256 nan = _mm256_castsi256_ps(_mm256_set1_epi32(0x7fc00000));
    o->zr = st->zr, o->zi = st->zi, o->dz2 = st->dz2;
    o->A = st->ok;
    o->B = o->inside = o->escaped = _mm256_setzero_ps();
    o->thr = _mm256_blendv_ps(nan, _mm256_set1_ps(p->bailout2), o->A);
    o->deadline =
        _mm256_blendv_epi8(_mm256_set1_epi32(-1), _mm256_set1_epi32((int)p->max_iter), _mm256_castps_si256(o->A));
    o->n_at = o->m_at = _mm256_setzero_si256();
    o->r2_at = o->dz2_at = _mm256_setzero_ps();
}

/* The slow path of one block at step iv, |z|^2 = r2; hit: r2 >= thr. */
AVX2 static AI void orbit_event(orbit8 *o, __m256 r2, __m256 hit, __m256 dl, __m256i iv, const uint32_t want)
{
    const __m256 nan = _mm256_castsi256_ps(_mm256_set1_epi32(0x7fc00000)), big2 = _mm256_set1_ps(BIG2_NEXT);
    const __m256i never = _mm256_set1_epi32(-1);
    /* iterating lanes at the bailout escape with n = i; at max_iter the others are inside */
    __m256 endA = _mm256_and_ps(o->A, _mm256_or_ps(hit, dl)), esc = _mm256_and_ps(o->A, hit);
    if (_mm256_movemask_ps(endA)) {
        o->n_at = _mm256_blendv_epi8(o->n_at, iv, _mm256_castps_si256(endA));
        o->inside = _mm256_or_ps(o->inside, _mm256_andnot_ps(hit, endA));
        o->A = _mm256_andnot_ps(endA, o->A);
        o->escaped = _mm256_or_ps(o->escaped, esc);
        __m256 gone = endA;
        if (want) {
            o->B = _mm256_or_ps(o->B, esc);
            o->thr = _mm256_blendv_ps(o->thr, big2, esc);
            o->deadline = _mm256_blendv_epi8(o->deadline, _mm256_add_epi32(iv, _mm256_set1_epi32(K_JULIA_EXTRA_ITER)),
                                             _mm256_castps_si256(esc));
            gone = _mm256_andnot_ps(esc, endA);
        }
        o->thr = _mm256_blendv_ps(o->thr, nan, gone);
        o->deadline = _mm256_blendv_epi8(o->deadline, never, _mm256_castps_si256(gone));
    }
    if (want) {
        /* past the big radius, or K_JULIA_EXTRA_ITER steps after the bailout: finished */
        __m256 fin = _mm256_and_ps(o->B, _mm256_or_ps(_mm256_cmp_ps(r2, big2, _CMP_GE_OQ),
                                                      _mm256_castsi256_ps(_mm256_cmpeq_epi32(iv, o->deadline))));
        if (_mm256_movemask_ps(fin)) {
            __m256i f = _mm256_castps_si256(fin);
            o->m_at = _mm256_blendv_epi8(o->m_at, iv, f);
            o->r2_at = _mm256_blendv_ps(o->r2_at, r2, fin);
            o->dz2_at = _mm256_blendv_ps(o->dz2_at, o->dz2, fin);
            o->B = _mm256_andnot_ps(fin, o->B);
            o->thr = _mm256_blendv_ps(o->thr, nan, fin);
            o->deadline = _mm256_blendv_epi8(o->deadline, never, f);
        }
    }
}

/* k_julia_step or k_julia_step_z, on every lane (finished lanes' values are not used); r2: |z|^2 */
AVX2 static AI void orbit_step(orbit8 *o, __m256 r2, __m256 cre, __m256 cim, const uint32_t want)
{
    const __m256 two = _mm256_set1_ps(2.0f);
    __m256 zr = o->zr, zi = o->zi;
    if (want & K_JULIA_WANT_DE) o->dz2 = _mm256_mul_ps(o->dz2, _mm256_mul_ps(_mm256_set1_ps(4.0f), r2));
    o->zr = _mm256_add_ps(_mm256_sub_ps(_mm256_mul_ps(zr, zr), _mm256_mul_ps(zi, zi)), cre);
    o->zi = _mm256_add_ps(_mm256_mul_ps(_mm256_mul_ps(two, zr), zi), cim);
}

/* ---- kernels/explog.h on eight lanes: the same operations in the same order ------------------- */

/* a x + b */
AVX2 static inline __m256 lin8(__m256 x, float a, float b)
{
    return _mm256_add_ps(_mm256_mul_ps(_mm256_set1_ps(a), x), _mm256_set1_ps(b));
}

/* k_log2_parts: *e the integer part, *t the rest */
AVX2 static inline void log2_parts8(__m256 x, __m256 *e_out, __m256 *t_out)
{
    const __m256 one = _mm256_set1_ps(1.0f);
    __m256 sub = _mm256_cmp_ps(x, _mm256_set1_ps(1.17549435e-38f), _CMP_LT_OQ);
    __m256i b = _mm256_castps_si256(_mm256_blendv_ps(x, _mm256_mul_ps(x, _mm256_set1_ps(16777216.0f)), sub));
    __m256i bias = _mm256_blendv_epi8(_mm256_set1_epi32(126), _mm256_set1_epi32(150), _mm256_castps_si256(sub));
    __m256i e = _mm256_sub_epi32(_mm256_srli_epi32(b, 23), bias);
    __m256 m = _mm256_castsi256_ps(
        _mm256_or_si256(_mm256_and_si256(b, _mm256_set1_epi32(0x007fffff)), _mm256_set1_epi32(0x3f000000)));
    __m256 low = _mm256_cmp_ps(m, _mm256_set1_ps(0.70710678f), _CMP_LT_OQ);
    __m256 f = _mm256_blendv_ps(_mm256_sub_ps(m, one), _mm256_sub_ps(_mm256_add_ps(m, m), one), low);
    e = _mm256_add_epi32(e, _mm256_castps_si256(low)); /* all ones: -1 */
    __m256 z = _mm256_mul_ps(f, f);
    __m256 z2 = _mm256_mul_ps(z, z);
    __m256 p01 = lin8(f, 7.0376836292e-2f, -1.1514610310e-1f), p23 = lin8(f, 1.1676998740e-1f, -1.2420140846e-1f);
    __m256 p45 = lin8(f, 1.4249322787e-1f, -1.6668057665e-1f), p67 = lin8(f, 2.0000714765e-1f, -2.4999993993e-1f);
    __m256 q = _mm256_add_ps(_mm256_mul_ps(_mm256_add_ps(_mm256_mul_ps(_mm256_add_ps(_mm256_mul_ps(p01, z), p23), z2),
                                                         _mm256_add_ps(_mm256_mul_ps(p45, z), p67)),
                                           f),
                             _mm256_set1_ps(3.3333331174e-1f));
    __m256 y = _mm256_mul_ps(f, _mm256_mul_ps(z, q));
    y = _mm256_add_ps(y, _mm256_mul_ps(_mm256_set1_ps(-0.5f), z));
    const __m256 l2ea = _mm256_set1_ps(0.44269504f);
    __m256 t = _mm256_mul_ps(y, l2ea);
    t = _mm256_add_ps(t, _mm256_mul_ps(f, l2ea));
    t = _mm256_add_ps(t, y);
    *t_out = _mm256_add_ps(t, f);
    *e_out = _mm256_cvtepi32_ps(e);
}

/* k_log2_poly */
AVX2 static inline __m256 log2p8(__m256 x)
{
    __m256 e, t;
    log2_parts8(x, &e, &t);
    return _mm256_add_ps(t, e);
}

/* k_exp2_split: 2^(r + k) */
AVX2 static inline __m256 exp2_split8(__m256 r, __m256 k)
{
    __m256 r2 = _mm256_mul_ps(r, r);
    __m256 pa = lin8(r, 1.535336188e-4f, 1.339887440e-3f), pb = lin8(r, 9.618437357e-3f, 5.550332471e-2f);
    __m256 pc = lin8(r, 2.402264791e-1f, 6.931472028e-1f);
    __m256 p =
        _mm256_add_ps(_mm256_mul_ps(_mm256_add_ps(_mm256_mul_ps(_mm256_add_ps(_mm256_mul_ps(pa, r2), pb), r2), pc), r),
                      _mm256_set1_ps(1.0f));
    __m256 k1 = _mm256_floor_ps(_mm256_mul_ps(k, _mm256_set1_ps(0.5f))), k2 = _mm256_sub_ps(k, k1);
    const __m256i bias = _mm256_set1_epi32(127);
    __m256 s1 = _mm256_castsi256_ps(_mm256_slli_epi32(_mm256_add_epi32(_mm256_cvttps_epi32(k1), bias), 23));
    __m256 s2 = _mm256_castsi256_ps(_mm256_slli_epi32(_mm256_add_epi32(_mm256_cvttps_epi32(k2), bias), 23));
    return _mm256_mul_ps(_mm256_mul_ps(p, s1), s2);
}

/* k_pow_poly(x, y) on every lane (x >= 0, y > 0) */
AVX2 static inline __m256 powp8(__m256 x, float y)
{
    const __m256 half = _mm256_set1_ps(0.5f);
    const float c = 4097.0f * y, yh = c - (c - y), yl = y - yh;
    __m256 e, t;
    log2_parts8(x, &e, &t);
    __m256 a = _mm256_mul_ps(_mm256_set1_ps(yh), e);
    __m256 b = _mm256_add_ps(_mm256_mul_ps(_mm256_set1_ps(yl), e), _mm256_mul_ps(_mm256_set1_ps(y), t));
    __m256 k1 = _mm256_floor_ps(_mm256_add_ps(a, half));
    __m256 s = _mm256_add_ps(_mm256_sub_ps(a, k1), b);
    __m256 k2 = _mm256_floor_ps(_mm256_add_ps(s, half));
    __m256 r = _mm256_sub_ps(s, k2);
    __m256 k = clamp8(_mm256_add_ps(k1, k2), -151.0f, 129.0f);
    __m256 v = exp2_split8(r, k);
    return _mm256_andnot_ps(_mm256_cmp_ps(x, _mm256_setzero_ps(), _CMP_EQ_OQ), v); /* x = 0: +0 */
}

/* k_julia_end */
AVX2 static AI void orbit_end(const orbit8 *o, const K_JuliaParams *p, const uint32_t want, v8result *out)
{
    _mm256_storeu_si256((__m256i *)out->iter, o->n_at);
    __m256 zero = _mm256_setzero_ps();
    __m256 ns = _mm256_and_ps(o->inside, _mm256_set1_ps(K_F(p->max_iter)));
    __m256 dev = zero;
    int live = want ? _mm256_movemask_ps(o->escaped) : 0;
    if (live) {
        /* every lane (lanes not escaped are not used; their r2 of 0 gives a finite log2) */
        __m256 lnr = _mm256_mul_ps(_mm256_mul_ps(_mm256_set1_ps(0.5f), log2p8(o->r2_at)), _mm256_set1_ps(0.69314718f));
        if (want & K_JULIA_WANT_SMOOTH) {
            __m256 s = _mm256_sub_ps(_mm256_add_ps(_mm256_cvtepi32_ps(o->m_at), _mm256_set1_ps(1.0f)), log2p8(lnr));
            ns = _mm256_blendv_ps(ns, s, o->escaped);
        }
        if (want & K_JULIA_WANT_DE) {
            __m256 dz = _mm256_sqrt_ps(o->dz2_at);
            __m256 good = _mm256_and_ps(_mm256_cmp_ps(dz, zero, _CMP_GT_OQ),
                                        _mm256_cmp_ps(dz, _mm256_set1_ps(3.0e38f), _CMP_LT_OQ));
            __m256 d = _mm256_div_ps(_mm256_mul_ps(_mm256_sqrt_ps(o->r2_at), lnr), dz);
            dev = _mm256_and_ps(_mm256_and_ps(good, o->escaped), d);
        }
    }
    _mm256_storeu_ps(out->nsmooth, ns);
    _mm256_storeu_ps(out->de, dev);
    _mm256_storeu_ps(out->inside, _mm256_and_ps(o->inside, _mm256_set1_ps(1.0f)));
}

AVX2 static AI __m256 live8(const orbit8 *o)
{
    return _mm256_or_ps(o->A, o->B);
}

/* k_julia_run of one block (nb = 1) or two (nb = 2) */
AVX2 static AI void run_t(const K_JuliaParams *p, const v8start *st, const int nb, const uint32_t want, v8result *out)
{
    const __m256 cre = _mm256_set1_ps(p->c_re), cim = _mm256_set1_ps(p->c_im);
    orbit8 o0, o1;
    orbit_init(&o0, p, &st[0]);
    if (nb == 2) orbit_init(&o1, p, &st[1]);
    __m256i iv = _mm256_setzero_si256();
    const __m256i one = _mm256_set1_epi32(1);
    __m256 any = nb == 2 ? _mm256_or_ps(o0.A, o1.A) : o0.A;
    if (_mm256_movemask_ps(any) != 0)
        for (;;) {
            __m256 r2a = _mm256_add_ps(_mm256_mul_ps(o0.zr, o0.zr), _mm256_mul_ps(o0.zi, o0.zi));
            __m256 ha = _mm256_cmp_ps(r2a, o0.thr, _CMP_GE_OQ);
            __m256 da = _mm256_castsi256_ps(_mm256_cmpeq_epi32(iv, o0.deadline));
            __m256 ev = _mm256_or_ps(ha, da);
            __m256 r2b, hb, db;
            if (nb == 2) {
                r2b = _mm256_add_ps(_mm256_mul_ps(o1.zr, o1.zr), _mm256_mul_ps(o1.zi, o1.zi));
                hb = _mm256_cmp_ps(r2b, o1.thr, _CMP_GE_OQ);
                db = _mm256_castsi256_ps(_mm256_cmpeq_epi32(iv, o1.deadline));
                ev = _mm256_or_ps(ev, _mm256_or_ps(hb, db));
            }
            if (__builtin_expect(_mm256_movemask_ps(ev) != 0, 0)) {
                if (_mm256_movemask_ps(_mm256_or_ps(ha, da))) orbit_event(&o0, r2a, ha, da, iv, want);
                if (nb == 2 && _mm256_movemask_ps(_mm256_or_ps(hb, db))) orbit_event(&o1, r2b, hb, db, iv, want);
                __m256 live = nb == 2 ? _mm256_or_ps(live8(&o0), live8(&o1)) : live8(&o0);
                if (_mm256_movemask_ps(live) == 0) break;
            }
            orbit_step(&o0, r2a, cre, cim, want);
            if (nb == 2) orbit_step(&o1, r2b, cre, cim, want);
            iv = _mm256_add_epi32(iv, one);
        }
    orbit_end(&o0, p, want, &out[0]);
    if (nb == 2) orbit_end(&o1, p, want, &out[1]);
}

/* k_julia_run, compiled once per block count and `want` */
AVX2 static void run8(const K_JuliaParams *p, const v8start *st, int nb, uint32_t want, v8result *out)
{
#define RUN_WANT(NB)                                                                                                   \
    switch (want) {                                                                                                    \
    case 0u:                                                                                                           \
        run_t(p, st, NB, 0u, out);                                                                                     \
        break;                                                                                                         \
    case K_JULIA_WANT_SMOOTH:                                                                                          \
        run_t(p, st, NB, K_JULIA_WANT_SMOOTH, out);                                                                    \
        break;                                                                                                         \
    case K_JULIA_WANT_DE:                                                                                              \
        run_t(p, st, NB, K_JULIA_WANT_DE, out);                                                                        \
        break;                                                                                                         \
    default:                                                                                                           \
        run_t(p, st, NB, K_JULIA_WANT_ALL, out);                                                                       \
        break;                                                                                                         \
    }
    if (nb == 2) {
        RUN_WANT(2)
    } else {
        RUN_WANT(1)
    }
#undef RUN_WANT
}

/* ---- colour: k_sky_rgb with the table's entries ---------------------------------------------- */

/* Adds sample colours (k_sky_rgb) to rgb[3]; first: set them instead. */
AVX2 static void colour8(const fb_julia_avx2_ctx *cx, const v8result *r, bool first, __m256 rgb[3])
{
    const K_SkyColour *c = cx->colour;
    __m256 n = _mm256_loadu_ps(r->nsmooth);
    __m256 in = _mm256_cmp_ps(_mm256_loadu_ps(r->inside), _mm256_setzero_ps(), _CMP_NEQ_UQ);
    /* k_palette_pos */
    __m256 x = _mm256_add_ps(_mm256_mul_ps(n, _mm256_set1_ps(c->inv_period)), _mm256_set1_ps(c->offset));
    __m256 f =
        _mm256_sub_ps(x, _mm256_mul_ps(_mm256_set1_ps(2.0f), _mm256_floor_ps(_mm256_mul_ps(x, _mm256_set1_ps(0.5f)))));
    __m256 t =
        _mm256_blendv_ps(_mm256_sub_ps(_mm256_set1_ps(2.0f), f), f, _mm256_cmp_ps(f, _mm256_set1_ps(1.0f), _CMP_LT_OQ));
    __m256 pos = _mm256_mul_ps(clamp8(t, 0.0f, 1.0f), _mm256_set1_ps(K_F(K_PALETTE_SIZE - 1u)));
    __m256i i0 = _mm256_cvttps_epi32(pos);
    __m256i i1 = _mm256_min_epi32(_mm256_add_epi32(i0, _mm256_set1_epi32(1)), _mm256_set1_epi32(K_PALETTE_SIZE - 1));
    __m256 fr = _mm256_sub_ps(pos, _mm256_cvtepi32_ps(i0));
    /* k_sky_weight */
    __m256 w = clamp8(_mm256_mul_ps(n, _mm256_set1_ps(c->inv_n_ref)), 0.0f, 1.0f);
    /* (inside lanes take the inside colour: their weight is not used) */
    w = c->density > 0.0f ? powp8(w, c->density) : _mm256_set1_ps(1.0f);
    __m256 bw = _mm256_mul_ps(_mm256_set1_ps(c->brightness), w);
    const float *base = &cx->entries[0][0];
    __m256i o0 = _mm256_slli_epi32(i0, 2), o1 = _mm256_slli_epi32(i1, 2);
    const float inside_rgb[3] = {c->inside_r, c->inside_g, c->inside_b};
    for (int ch = 0; ch < 3; ch++) {
        __m256 e0 = _mm256_i32gather_ps(base + ch, o0, 4), e1 = _mm256_i32gather_ps(base + ch, o1, 4);
        __m256 v = _mm256_mul_ps(bw, mix8(e0, e1, fr)); /* k_sky_channel */
        if (c->gamma != 1.0f) v = powp8(_mm256_max_ps(v, _mm256_setzero_ps()), c->gamma);
        v = _mm256_blendv_ps(v, _mm256_set1_ps(inside_rgb[ch]), in);
        rgb[ch] = first ? v : _mm256_add_ps(rgb[ch], v);
    }
}

/* ---- the rows ---------------------------------------------------------------------------------- */

/* The first cnt of eight values to dst */
AVX2 static inline void put8(void *dst, const void *src, uint32_t cnt)
{
    if (cnt == 8)
        _mm256_storeu_si256((__m256i *)dst, _mm256_loadu_si256((const __m256i *)src));
    else
        memcpy(dst, src, cnt * 4);
}

AVX2 static void rows8(const fb_julia_avx2_ctx *cx, int y0, int n, void *const *planes)
{
    const K_JuliaParams *p = cx->p;
    const K_SkyColour *col = cx->colour;
    const bool colour = planes[4] != NULL;
    const uint32_t W = p->width;
    const __m256i lane = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
    const uint32_t hs = k_hash(col->seed ^ 0x9e3779b9u);
    for (int r = 0; r < n; r++) {
        const uint32_t y = (uint32_t)(y0 + r);
        const __m256 fyc = _mm256_set1_ps(K_F(y) + 0.5f);
        /* two blocks of eight pixels at a time (one where fewer than nine are left) */
        for (uint32_t x0 = 0; x0 < W; x0 += 16) {
            const int nb = W - x0 > 8 ? 2 : 1;
            __m256i xi[2];
            __m256 xf[2];
            v8start st[2];
            v8result res[2];
            for (int b = 0; b < nb; b++) {
                /* lanes past the row's end repeat its last pixel (computed, not stored) */
                xi[b] = _mm256_min_epi32(_mm256_add_epi32(_mm256_set1_epi32((int)(x0 + 8 * b)), lane),
                                         _mm256_set1_epi32((int)(W - 1)));
                xf[b] = _mm256_cvtepi32_ps(xi[b]);
                st[b] = start8(cx, _mm256_add_ps(xf[b], _mm256_set1_ps(0.5f)), fyc);
            }
            run8(p, st, nb, cx->want, res);
            __m256 rgb[2][3];
            for (int b = 0; b < nb; b++) {
                const uint32_t xb = x0 + 8 * b, cnt = W - xb < 8 ? W - xb : 8;
                size_t at = (size_t)r * W + xb;
                if (planes[0]) put8((uint32_t *)planes[0] + at, res[b].iter, cnt);
                if (planes[1]) put8((float *)planes[1] + at, res[b].nsmooth, cnt);
                if (planes[2]) put8((float *)planes[2] + at, res[b].inside, cnt);
                if (planes[3]) put8((float *)planes[3] + at, res[b].de, cnt);
                if (colour) colour8(cx, &res[b], true, rgb[b]);
            }
            if (!colour) continue;
            /* k_julia_sample_xy: jitter by k_rand01(seed, 0x5a00 + 2k (+1), y W + x) */
            for (uint32_t k = 1; k < col->samples; k++) {
                const uint32_t hx = k_hash((0x5a00u + 2u * k) ^ hs), hy = k_hash((0x5a01u + 2u * k) ^ hs);
                const __m256 u24 = _mm256_set1_ps(1.0f / 16777216.0f);
                for (int b = 0; b < nb; b++) {
                    __m256i idx = _mm256_add_epi32(_mm256_set1_epi32((int)(y * W)), xi[b]);
                    __m256i jx = _mm256_srli_epi32(hash8(_mm256_xor_si256(idx, _mm256_set1_epi32((int)hx))), 8);
                    __m256i jy = _mm256_srli_epi32(hash8(_mm256_xor_si256(idx, _mm256_set1_epi32((int)hy))), 8);
                    __m256 fx = _mm256_add_ps(xf[b], _mm256_mul_ps(_mm256_cvtepi32_ps(jx), u24));
                    __m256 fy = _mm256_add_ps(_mm256_set1_ps(K_F(y)), _mm256_mul_ps(_mm256_cvtepi32_ps(jy), u24));
                    st[b] = start8(cx, fx, fy);
                }
                run8(p, st, nb, K_JULIA_WANT_SMOOTH, res);
                for (int b = 0; b < nb; b++) colour8(cx, &res[b], false, rgb[b]);
            }
            for (int b = 0; b < nb; b++) {
                const uint32_t xb = x0 + 8 * b, cnt = W - xb < 8 ? W - xb : 8;
                size_t at = (size_t)r * W + xb;
                for (int ch = 0; ch < 3; ch++) {
                    float v[8];
                    __m256 c = rgb[b][ch];
                    if (col->samples != 1) c = _mm256_mul_ps(c, _mm256_set1_ps(col->inv_samples));
                    _mm256_storeu_ps(v, c);
                    put8((float *)planes[4 + ch] + at, v, cnt);
                }
            }
        }
    }
}

bool fb_julia_avx2_layer_supported(const K_JuliaParams *p)
{
    return __builtin_cpu_supports("avx2") && p->mapping <= K_JULIA_CUBE;
}

void fb_julia_avx2_layer_rows(const fb_julia_avx2_ctx *c, int y0, int n, void *const *planes)
{
    rows8(c, y0, n, planes);
}

#else

bool fb_julia_avx2_layer_supported(const K_JuliaParams *p)
{
    (void)p;
    return false;
}

void fb_julia_avx2_layer_rows(const fb_julia_avx2_ctx *c, int y0, int n, void *const *planes)
{
    (void)c, (void)y0, (void)n, (void)planes;
}

#endif
