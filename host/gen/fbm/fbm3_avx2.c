/*
 * fBm on the sphere on eight AVX2 lanes: k_fbm3 of kernels/fbm.h over every 3D noise of
 * kernels/noise3.h, and k_fbm_dir with its warp, eight directions at a time. The same operations in
 * the same order as the kernel, no FMA (the build's -ffp-contract=off, and no FMA target here), the
 * same hashes: every value is the scalar kernel's to the bit (tests/test_avx2.c). Where the kernel
 * branches per point, each lane takes the kernel's branch through masks: the simplex's six
 * orderings and its corners' cut-off, and the cellular search's skipped cells (against each lane's
 * own F2 so far; a cell that no lane needs is not computed). k_sincos's polynomial is on the lanes
 * for sine noise.
 *
 * Used by the fbm layer's lat-long and cube rows (layer.c) and by the Julia layer's turbulence on
 * the sphere (julia/layer_avx2.c).
 */
#include "fbm3_avx2.h"

#include <string.h>

#if defined(__x86_64__) || defined(__i386__)
#include "fbm_avx2_ops.h"

#define AI inline __attribute__((always_inline))

typedef struct v3 {
    __m256 x, y, z;
} v3;

/* ---- the lattice: k_hash3i(seed, ix, iy, iz) = k_hash2i(k_hash(iz ^ seed ^ 0x2545f491), ix, iy) ----- */

/* the layer's hash, k_hash(iz ^ seed ^ 0x2545f491) */
AVX2 static inline __m256i layer8(uint32_t seed, __m256i iz)
{
    return hash8(_mm256_xor_si256(iz, _mm256_set1_epi32((int)(seed ^ 0x2545f491u))));
}

/* k_hash2i's row hash under that layer, k_hash(iy ^ layer ^ 0x632be5ab) */
AVX2 static inline __m256i row8(__m256i layer, __m256i iy)
{
    return hash8(_mm256_xor_si256(_mm256_xor_si256(iy, layer), _mm256_set1_epi32(0x632be5ab)));
}

AVX2 static inline __m256i hash3i8(uint32_t seed, __m256i ix, __m256i iy, __m256i iz)
{
    return cell_hash8(ix, row8(layer8(seed, iz), iy));
}

/* k_cell_add(c, d, K_NOISE_PERIOD) for d = 0 or 1 given as a mask (0 or all ones: c - mask) */
AVX2 static inline __m256i add_mask8(__m256i c, __m256 m)
{
    return _mm256_and_si256(_mm256_sub_epi32(c, _mm256_castps_si256(m)), _mm256_set1_epi32((int)(K_NOISE_PERIOD - 1u)));
}

/* k_grad3: Perlin's 12 edge gradients (16 with four repeated) dotted with (x, y, z) */
AVX2 static inline __m256 grad3_8(__m256i h, __m256 x, __m256 y, __m256 z)
{
    __m256i b = _mm256_and_si256(h, _mm256_set1_epi32(15));
    __m256 lt8 = _mm256_castsi256_ps(_mm256_cmpgt_epi32(_mm256_set1_epi32(8), b));
    __m256 lt4 = _mm256_castsi256_ps(_mm256_cmpgt_epi32(_mm256_set1_epi32(4), b));
    /* b == 12 or b == 14: b | 2 == 14 (no other b < 16 gives 14) */
    __m256 e = _mm256_castsi256_ps(_mm256_cmpeq_epi32(_mm256_or_si256(b, _mm256_set1_epi32(2)), _mm256_set1_epi32(14)));
    __m256 u = _mm256_blendv_ps(y, x, lt8);
    __m256 v = _mm256_blendv_ps(_mm256_blendv_ps(z, x, e), y, lt4);
    /* bit 0 of b is the sign of u, bit 1 that of v (a negation is a sign flip, exact) */
    __m256 su = _mm256_xor_ps(u, _mm256_castsi256_ps(_mm256_slli_epi32(b, 31)));
    __m256 sv = _mm256_xor_ps(v, _mm256_castsi256_ps(_mm256_slli_epi32(_mm256_srli_epi32(b, 1), 31)));
    return _mm256_add_ps(su, sv);
}

/* The unit cell of q: its corners' indices, the offsets t in it and t - 1, and the fades. */
typedef struct cell8 {
    __m256i ix0, ix1, iy0, iy1, iz0, iz1;
    __m256 tx, ty, tz, tx1, ty1, tz1, u, v, w;
} cell8;

AVX2 static AI cell8 cell_of8(v3 q)
{
    cell8 c;
    __m256 fx = _mm256_floor_ps(q.x), fy = _mm256_floor_ps(q.y), fz = _mm256_floor_ps(q.z);
    c.tx = _mm256_sub_ps(q.x, fx), c.ty = _mm256_sub_ps(q.y, fy), c.tz = _mm256_sub_ps(q.z, fz);
    c.ix0 = wrap8(fx), c.iy0 = wrap8(fy), c.iz0 = wrap8(fz);
    c.ix1 = next8(c.ix0), c.iy1 = next8(c.iy0), c.iz1 = next8(c.iz0);
    const __m256 one = _mm256_set1_ps(1.0f);
    c.tx1 = _mm256_sub_ps(c.tx, one), c.ty1 = _mm256_sub_ps(c.ty, one), c.tz1 = _mm256_sub_ps(c.tz, one);
    c.u = fade8(c.tx), c.v = fade8(c.ty), c.w = fade8(c.tz);
    return c;
}

/* k_gradient_noise3 */
AVX2 static AI __m256 gradient3_8(uint32_t seed, v3 q)
{
    cell8 c = cell_of8(q);
    __m256i l0 = layer8(seed, c.iz0), l1 = layer8(seed, c.iz1);
    __m256i r00 = row8(l0, c.iy0), r10 = row8(l0, c.iy1), r01 = row8(l1, c.iy0), r11 = row8(l1, c.iy1);
    __m256 a0 = mix8(grad3_8(cell_hash8(c.ix0, r00), c.tx, c.ty, c.tz),
                     grad3_8(cell_hash8(c.ix1, r00), c.tx1, c.ty, c.tz), c.u);
    __m256 b0 = mix8(grad3_8(cell_hash8(c.ix0, r10), c.tx, c.ty1, c.tz),
                     grad3_8(cell_hash8(c.ix1, r10), c.tx1, c.ty1, c.tz), c.u);
    __m256 a1 = mix8(grad3_8(cell_hash8(c.ix0, r01), c.tx, c.ty, c.tz1),
                     grad3_8(cell_hash8(c.ix1, r01), c.tx1, c.ty, c.tz1), c.u);
    __m256 b1 = mix8(grad3_8(cell_hash8(c.ix0, r11), c.tx, c.ty1, c.tz1),
                     grad3_8(cell_hash8(c.ix1, r11), c.tx1, c.ty1, c.tz1), c.u);
    return clamp8(mix8(mix8(a0, b0, c.v), mix8(a1, b1, c.v), c.w), -1.0f, 1.0f);
}

/* k_value_noise3 */
AVX2 static AI __m256 value3_8(uint32_t seed, v3 q)
{
    cell8 c = cell_of8(q);
    __m256i l0 = layer8(seed, c.iz0), l1 = layer8(seed, c.iz1);
    __m256i r00 = row8(l0, c.iy0), r10 = row8(l0, c.iy1), r01 = row8(l1, c.iy0), r11 = row8(l1, c.iy1);
    __m256 a0 = mix8(u01_8(cell_hash8(c.ix0, r00)), u01_8(cell_hash8(c.ix1, r00)), c.u);
    __m256 b0 = mix8(u01_8(cell_hash8(c.ix0, r10)), u01_8(cell_hash8(c.ix1, r10)), c.u);
    __m256 a1 = mix8(u01_8(cell_hash8(c.ix0, r01)), u01_8(cell_hash8(c.ix1, r01)), c.u);
    __m256 b1 = mix8(u01_8(cell_hash8(c.ix0, r11)), u01_8(cell_hash8(c.ix1, r11)), c.u);
    __m256 m = mix8(mix8(a0, b0, c.v), mix8(a1, b1, c.v), c.w);
    return _mm256_sub_ps(_mm256_mul_ps(_mm256_set1_ps(2.0f), m), _mm256_set1_ps(1.0f));
}

/* k_simplex3_corner: (0.6 - r^2)^4 (g . d), 0 where the kernel returns early (t <= 0 false also for
 * a NaN t, which then goes on as in the kernel) */
AVX2 static inline __m256 corner3_8(__m256i h, __m256 x, __m256 y, __m256 z)
{
    __m256 t =
        _mm256_sub_ps(_mm256_sub_ps(_mm256_sub_ps(_mm256_set1_ps(0.6f), _mm256_mul_ps(x, x)), _mm256_mul_ps(y, y)),
                      _mm256_mul_ps(z, z));
    __m256 keep = _mm256_cmp_ps(t, _mm256_setzero_ps(), _CMP_NLE_UQ);
    t = _mm256_mul_ps(t, t);
    return _mm256_and_ps(keep, _mm256_mul_ps(_mm256_mul_ps(t, t), grad3_8(h, x, y, z)));
}

/* k_simplex_noise3 */
AVX2 static AI __m256 simplex3_8(uint32_t seed, v3 q)
{
    const float F3 = 1.0f / 3.0f, G3 = 1.0f / 6.0f;
    __m256 s = _mm256_mul_ps(_mm256_add_ps(_mm256_add_ps(q.x, q.y), q.z), _mm256_set1_ps(F3));
    __m256 fi = _mm256_floor_ps(_mm256_add_ps(q.x, s)), fj = _mm256_floor_ps(_mm256_add_ps(q.y, s)),
           fk = _mm256_floor_ps(_mm256_add_ps(q.z, s));
    __m256 t = _mm256_mul_ps(_mm256_add_ps(_mm256_add_ps(fi, fj), fk), _mm256_set1_ps(G3));
    __m256 x0 = _mm256_sub_ps(q.x, _mm256_sub_ps(fi, t)), y0 = _mm256_sub_ps(q.y, _mm256_sub_ps(fj, t)),
           z0 = _mm256_sub_ps(q.z, _mm256_sub_ps(fk, t));
    /* the kernel's six branches as masks, each test as the kernel writes it (>= or <) */
    __m256 A = _mm256_cmp_ps(x0, y0, _CMP_GE_OQ);
    __m256 B = _mm256_cmp_ps(y0, z0, _CMP_GE_OQ), C = _mm256_cmp_ps(x0, z0, _CMP_GE_OQ);
    __m256 Bl = _mm256_cmp_ps(y0, z0, _CMP_LT_OQ), Cl = _mm256_cmp_ps(x0, z0, _CMP_LT_OQ);
    __m256 nA = _mm256_xor_ps(A, _mm256_castsi256_ps(_mm256_set1_epi32(-1)));
    __m256 c1 = _mm256_and_ps(A, B);                            /* i1 i2 j2 */
    __m256 c2 = _mm256_and_ps(_mm256_andnot_ps(B, A), C);       /* i1 i2 k2 */
    __m256 c3 = _mm256_andnot_ps(C, _mm256_andnot_ps(B, A));    /* k1 i2 k2 */
    __m256 c4 = _mm256_and_ps(nA, Bl);                          /* k1 j2 k2 */
    __m256 c5 = _mm256_and_ps(_mm256_andnot_ps(Bl, nA), Cl);    /* j1 j2 k2 */
    __m256 c6 = _mm256_andnot_ps(Cl, _mm256_andnot_ps(Bl, nA)); /* j1 i2 j2 */
    __m256 i1 = _mm256_or_ps(c1, c2), j1 = _mm256_or_ps(c5, c6), k1 = _mm256_or_ps(c3, c4);
    __m256 i2 = _mm256_or_ps(_mm256_or_ps(c1, c2), _mm256_or_ps(c3, c6));
    __m256 j2 = _mm256_or_ps(_mm256_or_ps(c1, c4), _mm256_or_ps(c5, c6));
    __m256 k2 = _mm256_or_ps(_mm256_or_ps(c2, c3), _mm256_or_ps(c4, c5));
    __m256i ii = wrap8(fi), jj = wrap8(fj), kk = wrap8(fk);
    const __m256 one = _mm256_set1_ps(1.0f), g1 = _mm256_set1_ps(G3), g2 = _mm256_set1_ps(2.0f * G3),
                 g3 = _mm256_set1_ps(3.0f * G3);
    /* x0 - K_F(i1) + G3: the mask's 1.0f or 0.0f */
    __m256 n0 = corner3_8(hash3i8(seed, ii, jj, kk), x0, y0, z0);
    __m256 n1 = corner3_8(hash3i8(seed, add_mask8(ii, i1), add_mask8(jj, j1), add_mask8(kk, k1)),
                          _mm256_add_ps(_mm256_sub_ps(x0, _mm256_and_ps(i1, one)), g1),
                          _mm256_add_ps(_mm256_sub_ps(y0, _mm256_and_ps(j1, one)), g1),
                          _mm256_add_ps(_mm256_sub_ps(z0, _mm256_and_ps(k1, one)), g1));
    __m256 n2 = corner3_8(hash3i8(seed, add_mask8(ii, i2), add_mask8(jj, j2), add_mask8(kk, k2)),
                          _mm256_add_ps(_mm256_sub_ps(x0, _mm256_and_ps(i2, one)), g2),
                          _mm256_add_ps(_mm256_sub_ps(y0, _mm256_and_ps(j2, one)), g2),
                          _mm256_add_ps(_mm256_sub_ps(z0, _mm256_and_ps(k2, one)), g2));
    __m256 n3 = corner3_8(hash3i8(seed, next8(ii), next8(jj), next8(kk)), _mm256_add_ps(_mm256_sub_ps(x0, one), g3),
                          _mm256_add_ps(_mm256_sub_ps(y0, one), g3), _mm256_add_ps(_mm256_sub_ps(z0, one), g3));
    __m256 sum = _mm256_add_ps(_mm256_add_ps(_mm256_add_ps(n0, n1), n2), n3);
    return clamp8(_mm256_mul_ps(_mm256_set1_ps(32.0f), sum), -1.0f, 1.0f);
}

/* k_sincos(x).x (sincos.h: Cody and Waite's reduction, Cephes' polynomials) */
AVX2 static inline __m256 sin8(__m256 x)
{
    __m256 q = _mm256_floor_ps(_mm256_add_ps(_mm256_mul_ps(x, _mm256_set1_ps(0.636619772f)), _mm256_set1_ps(0.5f)));
    __m256 r = _mm256_sub_ps(_mm256_sub_ps(_mm256_sub_ps(x, _mm256_mul_ps(q, _mm256_set1_ps(1.5703125f))),
                                           _mm256_mul_ps(q, _mm256_set1_ps(4.837512969970703125e-4f))),
                             _mm256_mul_ps(q, _mm256_set1_ps(7.54978995489188216e-8f)));
    __m256 z = _mm256_mul_ps(r, r);
    __m256 ps = _mm256_add_ps(_mm256_set1_ps(-1.6666654611e-1f),
                              _mm256_mul_ps(z, _mm256_add_ps(_mm256_set1_ps(8.3321608736e-3f),
                                                             _mm256_mul_ps(z, _mm256_set1_ps(-1.9515295891e-4f)))));
    __m256 sn = _mm256_add_ps(r, _mm256_mul_ps(_mm256_mul_ps(r, z), ps));
    __m256 pc = _mm256_add_ps(_mm256_set1_ps(4.166664568298827e-2f),
                              _mm256_mul_ps(z, _mm256_add_ps(_mm256_set1_ps(-1.388731625493765e-3f),
                                                             _mm256_mul_ps(z, _mm256_set1_ps(2.443315711809948e-5f)))));
    __m256 cs = _mm256_add_ps(_mm256_sub_ps(_mm256_set1_ps(1.0f), _mm256_mul_ps(_mm256_set1_ps(0.5f), z)),
                              _mm256_mul_ps(_mm256_mul_ps(z, z), pc));
    /* n = K_I(q) & 3: sn, cs, -sn, -cs; bit 0 picks cs, bit 1 the sign */
    __m256i n = _mm256_and_si256(_mm256_cvttps_epi32(q), _mm256_set1_epi32(3));
    __m256 odd =
        _mm256_castsi256_ps(_mm256_cmpeq_epi32(_mm256_and_si256(n, _mm256_set1_epi32(1)), _mm256_set1_epi32(1)));
    __m256 v = _mm256_blendv_ps(sn, cs, odd);
    return _mm256_xor_ps(v, _mm256_castsi256_ps(_mm256_slli_epi32(_mm256_srli_epi32(n, 1), 31)));
}

/* k_sine_noise3 */
AVX2 static AI __m256 sine3_8(v3 q)
{
    const __m256 tau = _mm256_set1_ps(K_TAU);
    __m256 fx = _mm256_floor_ps(q.x), fy = _mm256_floor_ps(q.y), fz = _mm256_floor_ps(q.z);
    __m256 xr = _mm256_add_ps(_mm256_cvtepi32_ps(wrap8(fx)), _mm256_sub_ps(q.x, fx));
    __m256 yr = _mm256_add_ps(_mm256_cvtepi32_ps(wrap8(fy)), _mm256_sub_ps(q.y, fy));
    __m256 zr = _mm256_add_ps(_mm256_cvtepi32_ps(wrap8(fz)), _mm256_sub_ps(q.z, fz));
    return _mm256_mul_ps(_mm256_mul_ps(sin8(_mm256_mul_ps(tau, xr)), sin8(_mm256_mul_ps(tau, yr))),
                         sin8(_mm256_mul_ps(tau, zr)));
}

/* k_cell_gap2(d, t): the squared distance from offset t to cell d along one axis (d a constant) */
AVX2 static inline __m256 gap2_8(int d, __m256 t)
{
    __m256 g = d > 0   ? _mm256_sub_ps(_mm256_set1_ps(K_F(d)), t)
               : d < 0 ? _mm256_sub_ps(t, _mm256_set1_ps(K_F(d + 1)))
                       : _mm256_setzero_ps();
    return _mm256_mul_ps(g, g);
}

/* k_cellular3: F1 and F2 over the 5 x 5 x 5 neighbourhood. Each lane skips the cells the kernel
 * skips for it (its own F2 so far: a lane takes a cell where the kernel's `>= f2` is false, NaN
 * included, and its F1 and F2 move only then); a cell no lane takes is not computed. Returns F1 and
 * F2 squared (the kernel's f1, f2 before their square roots). */
AVX2 static AI void cellular3_8(uint32_t seed, v3 q, __m256 *f1out, __m256 *f2out)
{
    __m256 fx = _mm256_floor_ps(q.x), fy = _mm256_floor_ps(q.y), fz = _mm256_floor_ps(q.z);
    __m256 tx = _mm256_sub_ps(q.x, fx), ty = _mm256_sub_ps(q.y, fy), tz = _mm256_sub_ps(q.z, fz);
    __m256i cx = wrap8(fx), cy = wrap8(fy), cz = wrap8(fz);
    const __m256i m = _mm256_set1_epi32((int)(K_NOISE_PERIOD - 1u));
    __m256 f1 = _mm256_set1_ps(1.0e9f), f2 = _mm256_set1_ps(1.0e9f);
    __m256 gx[5];
    for (int dx = -2; dx <= 2; dx++) gx[dx + 2] = gap2_8(dx, tx);
    for (int dz = -2; dz <= 2; dz++) {
        __m256 gz = gap2_8(dz, tz);
        __m256i layer = layer8(seed, _mm256_and_si256(_mm256_add_epi32(cz, _mm256_set1_epi32(dz)), m));
        for (int dy = -2; dy <= 2; dy++) {
            __m256 gyz = _mm256_add_ps(gz, gap2_8(dy, ty));
            if (_mm256_movemask_ps(_mm256_cmp_ps(gyz, f2, _CMP_NGE_UQ)) == 0) continue;
            __m256i row = row8(layer, _mm256_and_si256(_mm256_add_epi32(cy, _mm256_set1_epi32(dy)), m));
            for (int dx = -2; dx <= 2; dx++) {
                /* the kernel's two tests, gyz >= f2 and gyz + gap >= f2, against this lane's f2 now */
                __m256 take = _mm256_and_ps(_mm256_cmp_ps(gyz, f2, _CMP_NGE_UQ),
                                            _mm256_cmp_ps(_mm256_add_ps(gyz, gx[dx + 2]), f2, _CMP_NGE_UQ));
                if (_mm256_movemask_ps(take) == 0) continue;
                __m256i h = cell_hash8(_mm256_and_si256(_mm256_add_epi32(cx, _mm256_set1_epi32(dx)), m), row);
                __m256i h2 = hash8(h);
                __m256 ox = _mm256_sub_ps(_mm256_add_ps(_mm256_set1_ps(K_F(dx)), u01_8(h)), tx);
                __m256 oy = _mm256_sub_ps(_mm256_add_ps(_mm256_set1_ps(K_F(dy)), u01_8(h2)), ty);
                __m256 oz = _mm256_sub_ps(_mm256_add_ps(_mm256_set1_ps(K_F(dz)), u01_8(hash8(h2))), tz);
                __m256 d2 =
                    _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(ox, ox), _mm256_mul_ps(oy, oy)), _mm256_mul_ps(oz, oz));
                __m256 lt1 = _mm256_and_ps(take, _mm256_cmp_ps(d2, f1, _CMP_LT_OQ));
                __m256 lt2 = _mm256_andnot_ps(lt1, _mm256_and_ps(take, _mm256_cmp_ps(d2, f2, _CMP_LT_OQ)));
                f2 = _mm256_blendv_ps(f2, f1, lt1);
                f1 = _mm256_blendv_ps(f1, d2, lt1);
                f2 = _mm256_blendv_ps(f2, d2, lt2);
            }
        }
    }
    *f1out = f1, *f2out = f2;
}

/* k_noise3's cellular kinds: F1 mapped from [0, sqrt(3)], F2 - F1 from [0, 1] (clamped), to [-1, 1] */
AVX2 static AI __m256 cellular_noise3_8(const uint32_t kind, uint32_t seed, v3 q)
{
    __m256 f1, f2;
    cellular3_8(seed, q, &f1, &f2);
    __m256 a = _mm256_sqrt_ps(f1), one = _mm256_set1_ps(1.0f);
    if (kind == K_NOISE_CELLULAR)
        return _mm256_min_ps(_mm256_sub_ps(_mm256_mul_ps(a, _mm256_set1_ps(1.15470054f)), one), one);
    __m256 e = _mm256_min_ps(_mm256_sub_ps(_mm256_sqrt_ps(f2), a), one);
    return _mm256_sub_ps(_mm256_mul_ps(_mm256_set1_ps(2.0f), e), one);
}

/* k_noise3 for the kinds the lanes implement (a constant in each clone of fbm3_t below) */
AVX2 static AI __m256 noise3_8(const uint32_t kind, uint32_t seed, v3 q)
{
    if (kind == K_NOISE_VALUE) return value3_8(seed, q);
    if (kind == K_NOISE_SIMPLEX) return simplex3_8(seed, q);
    if (kind == K_NOISE_SINE) return sine3_8(q);
    if (kind == K_NOISE_CELLULAR || kind == K_NOISE_CELLULAR_F2) return cellular_noise3_8(kind, seed, q);
    return gradient3_8(seed, q);
}

/* k_fbm_shape */
AVX2 static inline __m256 shape8(__m256 n, uint32_t flags)
{
    if ((flags & K_FBM_RIDGED) != 0u) {
        __m256 r = _mm256_sub_ps(_mm256_set1_ps(1.0f), _mm256_andnot_ps(_mm256_set1_ps(-0.0f), n));
        return _mm256_mul_ps(r, r);
    }
    if ((flags & K_FBM_BILLOW) != 0u)
        return _mm256_sub_ps(_mm256_mul_ps(_mm256_set1_ps(2.0f), _mm256_andnot_ps(_mm256_set1_ps(-0.0f), n)),
                             _mm256_set1_ps(1.0f));
    return n;
}

/* k_fbm3(p, stream, d) of one noise kind */
AVX2 static AI __m256 fbm3_t(const uint32_t kind, const K_FbmParams *p, uint32_t stream, v3 d)
{
    uint32_t seed = k_hash3(p->seed, stream, 0x0fb3u);
    const __m256 k = _mm256_set1_ps(p->freq_x * (1.0f / K_TAU));
    v3 q = {_mm256_add_ps(_mm256_mul_ps(d.x, k), _mm256_set1_ps(p->offset_x)),
            _mm256_add_ps(_mm256_mul_ps(d.y, k), _mm256_set1_ps(p->offset_y)), _mm256_mul_ps(d.z, k)};
    const __m256 L = _mm256_set1_ps(p->lacunarity), c = _mm256_set1_ps(p->rot_c), s = _mm256_set1_ps(p->rot_s);
    float amp = 1.0f;
    __m256 sum = _mm256_setzero_ps();
    for (uint32_t i = 0; i < p->octaves; i++) {
        uint32_t h = k_hash(seed + i * 0x9e3779b9u);
        sum = _mm256_add_ps(sum, _mm256_mul_ps(_mm256_set1_ps(amp), shape8(noise3_8(kind, h, q), p->flags)));
        amp *= p->gain;
        __m256 ax = _mm256_sub_ps(_mm256_mul_ps(c, q.x), _mm256_mul_ps(s, q.y));
        __m256 ay = _mm256_add_ps(_mm256_mul_ps(s, q.x), _mm256_mul_ps(c, q.y));
        __m256 by = _mm256_sub_ps(_mm256_mul_ps(c, ay), _mm256_mul_ps(s, q.z));
        __m256 bz = _mm256_add_ps(_mm256_mul_ps(s, ay), _mm256_mul_ps(c, q.z));
        uint32_t ho = k_hash(h ^ 0x5bd1e995u), ho2 = k_hash(ho);
        q.x = _mm256_add_ps(_mm256_mul_ps(L, ax), _mm256_set1_ps(K_F(ho & 0xffffu) * (64.0f / 65536.0f)));
        q.y = _mm256_add_ps(_mm256_mul_ps(L, by), _mm256_set1_ps(K_F(ho >> 16) * (64.0f / 65536.0f)));
        q.z = _mm256_add_ps(_mm256_mul_ps(L, bz), _mm256_set1_ps(K_F(ho2 & 0xffffu) * (64.0f / 65536.0f)));
    }
    return sum;
}

/* k_fbm3: the lanes' clone of each kind (the kernel per lane for a kind unknown here) */
AVX2 static __m256 fbm3_8(const K_FbmParams *p, uint32_t stream, v3 d)
{
    switch (p->noise) {
    case K_NOISE_GRADIENT:
        return fbm3_t(K_NOISE_GRADIENT, p, stream, d);
    case K_NOISE_VALUE:
        return fbm3_t(K_NOISE_VALUE, p, stream, d);
    case K_NOISE_SIMPLEX:
        return fbm3_t(K_NOISE_SIMPLEX, p, stream, d);
    case K_NOISE_SINE:
        return fbm3_t(K_NOISE_SINE, p, stream, d);
    case K_NOISE_CELLULAR:
        return fbm3_t(K_NOISE_CELLULAR, p, stream, d);
    case K_NOISE_CELLULAR_F2:
        return fbm3_t(K_NOISE_CELLULAR_F2, p, stream, d);
    default: {
        float x[8], y[8], z[8], r[8];
        _mm256_storeu_ps(x, d.x);
        _mm256_storeu_ps(y, d.y);
        _mm256_storeu_ps(z, d.z);
        for (int k = 0; k < 8; k++) r[k] = k_fbm3(*p, stream, k_vec3(x[k], y[k], z[k]));
        return _mm256_loadu_ps(r);
    }
    }
}

/* k_fbm_dir: the direction normalised, the optional warp d' = d + w (fbm_1, fbm_2, fbm_3)(d) / k,
 * then fbm_0(d') */
AVX2 static __m256 dir8(const K_FbmParams *p, v3 d)
{
    __m256 len = _mm256_sqrt_ps(
        _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(d.x, d.x), _mm256_mul_ps(d.y, d.y)), _mm256_mul_ps(d.z, d.z)));
    v3 u = {_mm256_div_ps(d.x, len), _mm256_div_ps(d.y, len), _mm256_div_ps(d.z, len)};
    if (p->warp != 0.0f) {
        const __m256 s = _mm256_set1_ps(p->warp * K_TAU / p->freq_x);
        __m256 wx = fbm3_8(p, 1u, u), wy = fbm3_8(p, 2u, u), wz = fbm3_8(p, 3u, u);
        u.x = _mm256_add_ps(u.x, _mm256_mul_ps(s, wx));
        u.y = _mm256_add_ps(u.y, _mm256_mul_ps(s, wy));
        u.z = _mm256_add_ps(u.z, _mm256_mul_ps(s, wz));
    }
    return fbm3_8(p, 0u, u);
}

AVX2 static void lanes_avx2(const K_FbmParams *p, uint32_t stream, const float d[3][8], float out[8])
{
    v3 v = {_mm256_loadu_ps(d[0]), _mm256_loadu_ps(d[1]), _mm256_loadu_ps(d[2])};
    _mm256_storeu_ps(out, fbm3_8(p, stream, v));
}

AVX2 static void rows_avx2(const K_FbmParams *p, int y0, int n, float *out)
{
    const uint32_t W = p->width;
    for (int r = 0; r < n; r++) {
        const float y = K_F(y0 + r);
        float *row = out + (size_t)r * W;
        for (uint32_t x0 = 0; x0 < W; x0 += 8) {
            /* each lane's direction from the kernel (a few sines a pixel); lanes past the row's end
             * repeat its last pixel (computed, not stored) */
            float d[3][8], v[8];
            for (uint32_t k = 0; k < 8; k++) {
                uint32_t x = x0 + k < W ? x0 + k : W - 1u;
                k_vec3 e = k_env_dir_exact(p->mapping, K_F(x), y, W, p->height);
                d[0][k] = e.x, d[1][k] = e.y, d[2][k] = e.z;
            }
            v3 dv = {_mm256_loadu_ps(d[0]), _mm256_loadu_ps(d[1]), _mm256_loadu_ps(d[2])};
            __m256 f = dir8(p, dv);
            if (W - x0 >= 8) {
                _mm256_storeu_ps(row + x0, f);
            } else {
                _mm256_storeu_ps(v, f);
                memcpy(row + x0, v, (W - x0) * sizeof(float));
            }
        }
    }
}

bool fb_fbm3_avx2_supported(const K_FbmParams *p)
{
    return p->noise < K_NOISE_COUNT && __builtin_cpu_supports("avx2");
}

void fb_fbm3_avx2_lanes(const K_FbmParams *p, uint32_t stream, const float d[3][8], float out[8])
{
    lanes_avx2(p, stream, d, out);
}

void fb_fbm3_avx2_rows(const K_FbmParams *p, int y0, int n, float *out)
{
    rows_avx2(p, y0, n, out);
}

#else

bool fb_fbm3_avx2_supported(const K_FbmParams *p)
{
    (void)p;
    return false;
}

void fb_fbm3_avx2_lanes(const K_FbmParams *p, uint32_t stream, const float d[3][8], float out[8])
{
    for (int k = 0; k < 8; k++) out[k] = k_fbm3(*p, stream, k_vec3(d[0][k], d[1][k], d[2][k]));
}

void fb_fbm3_avx2_rows(const K_FbmParams *p, int y0, int n, float *out)
{
    for (int r = 0; r < n; r++)
        for (uint32_t x = 0; x < p->width; x++)
            out[(size_t)r * p->width + x] = k_fbm_map_pixel(*p, x, (uint32_t)(y0 + r));
}

#endif
