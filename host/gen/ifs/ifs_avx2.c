/*
 * The hand-vectorised chaos game, the native backend's fast path (layer.c, in step windows) and
 * the benchmark's reference.
 *
 * fb_ifs_avx2_game: a hand-vectorised AVX2 chaos game. Eight chains per vector, two vectors in
 * flight per thread to hide latency, the map coefficients held in registers and picked with
 * permutes (no memory gathers), and a private histogram per thread (plain adds, merged at the end).
 * It follows kernels/ifs.h operation for operation (same hash, same thresholds, same rounding), so
 * its histogram equals the kernel's bit for bit (tests/test_avx2.c).
 */
#include "ifs_avx2.h"

#include "kernels/ifs.h"
#include "pool.h"

#include <stdlib.h>
#include <string.h>

#if defined(__x86_64__) || defined(__i386__)
#include "avx2_hash.h"

typedef struct avx2_hist {
    uint32_t *hits;
    uint64_t *sum;
} avx2_hist;

typedef struct avx2_job {
    const K_IfsParams *p;
    const K_IfsMap *maps;
    avx2_hist *hist;
    int ntasks;
    size_t cells;
} avx2_job;

#define G 2 /* vectors of 8 chains in flight */

/* Up to 8 maps held in registers (coefficients a..f and colour per lane index) with their
 * thresholds in signed order, for picking and applying a map per lane without memory gathers. */
typedef struct maps8 {
    __m256 a, b, c, d, e, f, col;
    int thr[8];
    uint32_t n;
} maps8;

AVX2 static void maps8_load(maps8 *m, const K_IfsMap *maps, uint32_t n)
{
    float coef[7][8] = {{0}};
    for (uint32_t k = 0; k < 8; k++) {
        const K_IfsMap *q = &maps[k < n ? k : 0];
        const float v[7] = {q->a, q->b, q->c, q->d, q->e, q->f, q->colour};
        for (int i = 0; i < 7; i++) coef[i][k] = v[i];
        m->thr[k] = (int)((k < n ? q->thr : 0xffffffffu) ^ 0x80000000u); /* signed order = unsigned order */
    }
    m->a = _mm256_loadu_ps(coef[0]), m->b = _mm256_loadu_ps(coef[1]), m->c = _mm256_loadu_ps(coef[2]);
    m->d = _mm256_loadu_ps(coef[3]), m->e = _mm256_loadu_ps(coef[4]), m->f = _mm256_loadu_ps(coef[5]);
    m->col = _mm256_loadu_ps(coef[6]);
    m->n = n;
}

/* k_ifs_pick for 8 lanes (rs: the random numbers in signed order): the count of thresholds
 * after the first that are <= r. */
AVX2 static inline __m256i maps8_pick(const maps8 *m, __m256i rs)
{
    __m256i idx = _mm256_setzero_si256();
    for (uint32_t k = 1; k < m->n; k++) /* minus one per threshold <= r */
        idx = _mm256_sub_epi32(idx, _mm256_or_si256(_mm256_cmpgt_epi32(rs, _mm256_set1_epi32(m->thr[k])),
                                                    _mm256_cmpeq_epi32(rs, _mm256_set1_epi32(m->thr[k]))));
    return idx;
}

/* k_ifs_apply for 8 lanes: map idx of each lane applied to (x, y), the colour moved halfway to
 * the map's, in the kernel's order of operations; returns the lanes that escaped (k_ifs_escaped). */
AVX2 static inline __m256 maps8_apply(const maps8 *m, __m256i idx, __m256 *x, __m256 *y, __m256 *col, __m256 lim)
{
    const __m256 absmask = _mm256_castsi256_ps(_mm256_set1_epi32(0x7fffffff));
    __m256 a = _mm256_permutevar8x32_ps(m->a, idx), b = _mm256_permutevar8x32_ps(m->b, idx);
    __m256 c = _mm256_permutevar8x32_ps(m->c, idx), d = _mm256_permutevar8x32_ps(m->d, idx);
    __m256 e = _mm256_permutevar8x32_ps(m->e, idx), f = _mm256_permutevar8x32_ps(m->f, idx);
    __m256 nx = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(a, *x), _mm256_mul_ps(b, *y)), e);
    __m256 ny = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(c, *x), _mm256_mul_ps(d, *y)), f);
    *col = _mm256_mul_ps(_mm256_add_ps(*col, _mm256_permutevar8x32_ps(m->col, idx)), _mm256_set1_ps(0.5f));
    *x = nx, *y = ny;
    return _mm256_or_ps(_mm256_cmp_ps(_mm256_and_ps(nx, absmask), lim, _CMP_NLE_UQ),
                        _mm256_cmp_ps(_mm256_and_ps(ny, absmask), lim, _CMP_NLE_UQ));
}

/* Steps [t0, t1) of chains [c0, c1) (groups of 8 * G chains vectorised, the rest scalar) into
 * histogram h; adds the points outside the frame, discarded and restarted to n[0..2]. A chain starts
 * at t0 == 0 and otherwise from state[chain], where its state after the window is stored (state may
 * be NULL when the window holds every step). */
AVX2 static void game_avx2(const K_IfsParams *p, const K_IfsMap *maps, uint32_t c0, uint32_t c1, uint32_t t0,
                           uint32_t t1, K_IfsChain *state, avx2_hist *h, uint64_t n[3])
{
    maps8 M, CM; /* the maps, and condensation (cmaps > 0): C's IFS, maps nmaps.. of the table */
    maps8_load(&M, maps, p->nmaps);
    const bool cond = p->cmaps > 0;
    if (cond) maps8_load(&CM, maps + p->nmaps, p->cmaps);
    const __m256i w0thr = _mm256_set1_epi32(M.thr[0]); /* r < maps[0].thr: w0, onto C's point */
    const __m256i sign = _mm256_set1_epi32((int)0x80000000u);
    const __m256 x0 = _mm256_set1_ps(p->x0), y0 = _mm256_set1_ps(p->y0), sx = _mm256_set1_ps(p->sx),
                 sy = _mm256_set1_ps(p->sy), zero = _mm256_setzero_ps(), half = _mm256_set1_ps(0.5f);
    const __m256 hw = _mm256_set1_ps((float)p->hist_w), hh = _mm256_set1_ps((float)p->hist_h);
    const __m256 lim = _mm256_set1_ps(p->limit);
    uint32_t c = c0;
    for (; c + 8 * G <= c1; c += 8 * G) {
        __m256 x[G], y[G], col[G], qx[G], qy[G], qc[G];
        __m256i left[G], chainh[G];
        uint32_t total = 0;
        for (int g = 0; g < G; g++) {
            float xs[8], ys[8], cs[8], cxs[8], cys[8], ccs[8];
            int ls[8], hs[8];
            for (int l = 0; l < 8; l++) {
                uint32_t i = c + 8 * (uint32_t)g + (uint32_t)l;
                K_IfsChain s = t0 == 0 ? k_ifs_init(*p, i) : state[i];
                xs[l] = s.x, ys[l] = s.y, cs[l] = s.c, ls[l] = (int)s.left;
                cxs[l] = s.cx, cys[l] = s.cy, ccs[l] = s.cc;
                hs[l] = (int)k_hash(i ^ k_hash(p->seed ^ 0x9e3779b9u));
                uint32_t ti = k_ifs_total(*p, i);
                total = ti > total ? ti : total;
            }
            x[g] = _mm256_loadu_ps(xs), y[g] = _mm256_loadu_ps(ys), col[g] = _mm256_loadu_ps(cs);
            qx[g] = _mm256_loadu_ps(cxs), qy[g] = _mm256_loadu_ps(cys), qc[g] = _mm256_loadu_ps(ccs);
            left[g] = _mm256_loadu_si256((const __m256i *)ls);
            chainh[g] = _mm256_loadu_si256((const __m256i *)hs);
        }
        if (total > t1) total = t1;
        for (uint32_t t = t0; t < total; t++) {
            for (int g = 0; g < G; g++) {
                /* r = k_hash3(seed, chain, t) = hash(t ^ hash(chain ^ hash(seed ^ k))) */
                __m256i r = hash8(_mm256_xor_si256(_mm256_set1_epi32((int)t), chainh[g]));
                __m256i rs = _mm256_xor_si256(r, sign);
                __m256 nx = x[g], ny = y[g], ncol = col[g];
                __m256 bad = maps8_apply(&M, maps8_pick(&M, rs), &nx, &ny, &ncol, lim);
                if (cond) { /* kernels/ifs.h k_ifs_step: C's walk, then w0 takes its point */
                    __m256i rc = hash8(_mm256_xor_si256(r, _mm256_set1_epi32(0x5bd1e995)));
                    __m256 cbad =
                        maps8_apply(&CM, maps8_pick(&CM, _mm256_xor_si256(rc, sign)), &qx[g], &qy[g], &qc[g], lim);
                    __m256 ncx = qx[g], ncy = qy[g];
                    __m256 w0 = _mm256_castsi256_ps(_mm256_cmpgt_epi32(w0thr, rs)); /* r < thr0, unsigned */
                    nx = _mm256_blendv_ps(nx, ncx, w0);
                    ny = _mm256_blendv_ps(ny, ncy, w0);
                    ncol = _mm256_blendv_ps(ncol, qc[g], w0);
                    bad = _mm256_or_ps(cbad, _mm256_andnot_ps(w0, bad));
                }
                x[g] = nx, y[g] = ny, col[g] = ncol;
                if (__builtin_expect(_mm256_movemask_ps(bad) != 0, 0)) { /* restarts: the kernel's own code */
                    float xs[8], ys[8], cs[8], cxs[8], cys[8], ccs[8];
                    int ls[8];
                    _mm256_storeu_ps(xs, x[g]), _mm256_storeu_ps(ys, y[g]), _mm256_storeu_ps(cs, col[g]);
                    _mm256_storeu_ps(cxs, qx[g]), _mm256_storeu_ps(cys, qy[g]), _mm256_storeu_ps(ccs, qc[g]);
                    _mm256_storeu_si256((__m256i *)ls, left[g]);
                    int mask = _mm256_movemask_ps(bad);
                    for (int l = 0; l < 8; l++) {
                        if (!(mask >> l & 1)) continue;
                        K_IfsChain s = k_ifs_restart(*p, (K_IfsChain){0}, c + 8 * (uint32_t)g + (uint32_t)l, t);
                        xs[l] = s.x, ys[l] = s.y, cs[l] = s.c, ls[l] = (int)s.left + 1; /* no plot this step */
                        cxs[l] = s.cx, cys[l] = s.cy, ccs[l] = s.cc;
                    }
                    x[g] = _mm256_loadu_ps(xs), y[g] = _mm256_loadu_ps(ys), col[g] = _mm256_loadu_ps(cs);
                    qx[g] = _mm256_loadu_ps(cxs), qy[g] = _mm256_loadu_ps(cys), qc[g] = _mm256_loadu_ps(ccs);
                    left[g] = _mm256_loadu_si256((const __m256i *)ls);
                }
                /* plot where left == 0, else count one transient step down */
                __m256i plot = _mm256_cmpeq_epi32(left[g], _mm256_setzero_si256());
                left[g] = _mm256_add_epi32(left[g], _mm256_andnot_si256(plot, _mm256_set1_epi32(-1)));
                __m256 px = _mm256_mul_ps(_mm256_sub_ps(x[g], x0), sx);
                __m256 py = _mm256_mul_ps(_mm256_sub_ps(y0, y[g]), sy);
                __m256 in = _mm256_and_ps(
                    _mm256_and_ps(_mm256_cmp_ps(px, zero, _CMP_GE_OQ), _mm256_cmp_ps(py, zero, _CMP_GE_OQ)),
                    _mm256_and_ps(_mm256_cmp_ps(px, hw, _CMP_LT_OQ), _mm256_cmp_ps(py, hh, _CMP_LT_OQ)));
                int active = 0xff;
                if (t >= p->base) /* the last step belongs only to chains below `extra` */
                    for (int l = 0; l < 8; l++)
                        if (c + 8 * (uint32_t)g + (uint32_t)l >= p->extra) active &= ~(1 << l);
                int pm = _mm256_movemask_ps(_mm256_castsi256_ps(plot)) & active;
                int m = _mm256_movemask_ps(in) & pm;
                n[0] += (uint64_t)__builtin_popcount((unsigned)(pm & ~m));
                n[1] += (uint64_t)__builtin_popcount((unsigned)(active & ~pm));
                n[2] += (uint64_t)__builtin_popcount((unsigned)(_mm256_movemask_ps(bad) & active));
                __m256i cell =
                    _mm256_add_epi32(_mm256_mullo_epi32(_mm256_cvttps_epi32(py), _mm256_set1_epi32((int)p->hist_w)),
                                     _mm256_cvttps_epi32(px));
                __m256 qf =
                    _mm256_add_ps(_mm256_mul_ps(_mm256_min_ps(_mm256_max_ps(col[g], zero), _mm256_set1_ps(1.0f)),
                                                _mm256_set1_ps(255.0f)),
                                  half);
                __m256i q = _mm256_cvttps_epi32(qf);
                uint32_t cs[8], qs[8];
                _mm256_storeu_si256((__m256i *)cs, cell);
                _mm256_storeu_si256((__m256i *)qs, q);
                while (m) {
                    int l = __builtin_ctz((unsigned)m);
                    m &= m - 1;
                    h->hits[cs[l]]++;
                    h->sum[cs[l]] += qs[l];
                }
            }
        }
        for (int g = 0; g < G && state; g++) { /* the window ends: where each chain stands */
            float xs[8], ys[8], cs[8], cxs[8], cys[8], ccs[8];
            int ls[8];
            _mm256_storeu_ps(xs, x[g]), _mm256_storeu_ps(ys, y[g]), _mm256_storeu_ps(cs, col[g]);
            _mm256_storeu_ps(cxs, qx[g]), _mm256_storeu_ps(cys, qy[g]), _mm256_storeu_ps(ccs, qc[g]);
            _mm256_storeu_si256((__m256i *)ls, left[g]);
            for (int l = 0; l < 8; l++) {
                K_IfsChain *st = &state[c + 8 * (uint32_t)g + (uint32_t)l];
                st->x = xs[l], st->y = ys[l], st->c = cs[l], st->left = (uint32_t)ls[l];
                st->cx = cxs[l], st->cy = cys[l], st->cc = ccs[l];
                st->status = K_IFS_SKIP; /* the loop reads none of the rest */
            }
        }
    }
    /* the chains left over: the kernel itself */
    for (; c < c1; c++) {
        K_IfsChain s = t0 == 0 ? k_ifs_init(*p, c) : state[c];
        uint32_t total = k_ifs_total(*p, c);
        if (total > t1) total = t1;
        for (uint32_t t = t0; t < total; t++) {
            s = k_ifs_step(*p, s, c, t, maps);
            uint32_t cell = k_ifs_target(*p, s);
            n[0] += k_ifs_outside(s, cell);
            n[1] += k_ifs_discarded(s);
            n[2] += k_ifs_restarted(s);
            if (cell == K_IFS_NONE) continue;
            h->hits[cell]++;
            h->sum[cell] += k_ifs_quant(s.c);
        }
        if (state) state[c] = s;
    }
}

static void avx2_task(void *ctx, int task)
{
    avx2_job *j = ctx;
    uint32_t n = j->p->chains, per = (n / (uint32_t)j->ntasks + 15) / 16 * 16;
    uint32_t c0 = per * (uint32_t)task, c1 = c0 + per < n ? c0 + per : n;
    uint64_t counts[3] = {0, 0, 0};
    if (c0 < n) game_avx2(j->p, j->maps, c0, c1, 0, UINT32_MAX, NULL, &j->hist[task], counts);
}

static void merge_task(void *ctx, int task)
{
    avx2_job *j = ctx;
    size_t c0 = j->cells * (size_t)task / 64, c1 = j->cells * (size_t)(task + 1) / 64;
    for (int h = 1; h < j->ntasks; h++)
        for (size_t c = c0; c < c1; c++) {
            j->hist[0].hits[c] += j->hist[h].hits[c];
            j->hist[0].sum[c] += j->hist[h].sum[c];
        }
}

void fb_ifs_avx2_chains(const void *params, const void *maps, uint32_t c0, uint32_t c1, uint32_t t0, uint32_t t1,
                        void *state, uint32_t *hits, uint64_t *sum, uint64_t counts[3])
{
    avx2_hist h = {hits, sum};
    game_avx2(params, maps, c0, c1, t0, t1, state, &h, counts);
}

bool fb_ifs_avx2_supported(const void *params)
{
    const K_IfsParams *p = params;
    __builtin_cpu_init();
    return __builtin_cpu_supports("avx2") && p->nmaps <= 8 && p->cmaps <= 8 && p->csegs == 0;
}

fb_result fb_ifs_avx2_game(const void *params, const void *maps, int threads, uint32_t *hits, uint64_t *sum)
{
    const K_IfsParams *p = params;
    size_t cells = (size_t)p->hist_w * p->hist_h;
    avx2_job j = {p, maps, calloc((size_t)threads, sizeof(avx2_hist)), threads, cells};
    fb_pool *pool = NULL;
    fb_result rc = j.hist ? fb_pool_create(threads, &pool) : fb_fail(FB_ERR_NOMEM, "out of memory");
    for (int t = 0; t < threads && !rc; t++) {
        j.hist[t].hits = t ? calloc(cells, 4) : hits;
        j.hist[t].sum = t ? calloc(cells, 8) : sum;
        if (!j.hist[t].hits || !j.hist[t].sum) rc = fb_fail(FB_ERR_NOMEM, "out of memory for a histogram");
    }
    if (!rc) {
        memset(hits, 0, cells * 4);
        memset(sum, 0, cells * 8);
        fb_pool_run(pool, threads, avx2_task, &j);
        fb_pool_run(pool, 64, merge_task, &j);
    }
    for (int t = 1; j.hist && t < threads; t++) {
        free(j.hist[t].hits);
        free(j.hist[t].sum);
    }
    free(j.hist);
    fb_pool_destroy(&pool);
    return rc;
}

#else

bool fb_ifs_avx2_supported(const void *params)
{
    (void)params;
    return false;
}

void fb_ifs_avx2_chains(const void *params, const void *maps, uint32_t c0, uint32_t c1, uint32_t t0, uint32_t t1,
                        void *state, uint32_t *hits, uint64_t *sum, uint64_t counts[3])
{
    (void)params, (void)maps, (void)c0, (void)c1, (void)t0, (void)t1, (void)state, (void)hits, (void)sum, (void)counts;
}

fb_result fb_ifs_avx2_game(const void *params, const void *maps, int threads, uint32_t *hits, uint64_t *sum)
{
    (void)params, (void)maps, (void)threads, (void)hits, (void)sum;
    return fb_fail(FB_ERR_INTERNAL, "no AVX2 on this architecture");
}

#endif
