/*
 * A flame's chaos game on the native thread pool: chains of kernels/flame.h, their points scattered
 * into one integer histogram per thread, folded into the total at the end (same bits for any thread
 * count: each chain's points are fixed, and integer sums do not depend on their order).
 */
#ifndef FB_FLAME_GAME_H
#define FB_FLAME_GAME_H

#include "pool.h"
#include "progress.h"
#include "render.h"

/* Bytes of one thread's histogram cell for setup S: 16 where every xform is opaque and the palette
 * step-mode and opaque (red, green, blue, hits: the alpha and opacity sums are 4080 x hits), else
 * 24 (fb_flame_cell32). */
size_t fb_flame_cell_bytes(const fb_flame_setup *S);

/* Plays chains [cr0, cr1) of S on `threads` threads of pool (NULL: this thread) and adds their
 * points into total (hist_w x hist_h cells, zeroed or holding earlier sums); *bad gets the bad
 * values. prog (or NULL) counts points. scalar: every chain through the portable step, never the
 * AVX2 lanes (the same bits: the benchmark's scalar reference, fb_gen.scalar). */
fb_result fb_flame_play(const fb_flame_setup *S, fb_pool *pool, int threads, bool scalar, uint32_t cr0, uint32_t cr1,
                        fb_flame_cell *total, uint64_t *bad, fb_progress *prog);

/* The threads' histograms of a chaos game played in several calls (an animated frame's temporal
 * samples: one setup after another on the same frame), folded into total once at the end. */
typedef struct fb_flame_hists {
    void *hist[64];
    uint64_t bad[64];
    int threads;
    bool compact; /* 16-byte cells: every setup played must be fb_flame_cell_bytes 16 */
    size_t cells;
    fb_pool *pool;
    fb_flame_cell *total;
} fb_flame_hists;

/* Histograms for the frame of S (its size), on up to `threads` threads of pool (NULL: this thread),
 * folding into total. Errors: FB_ERR_NOMEM. */
fb_result fb_flame_hists_init(fb_flame_hists *h, const fb_flame_setup *S, bool compact, fb_pool *pool, int threads,
                              fb_flame_cell *total);
/* Plays chains [cr0, cr1) of S (the frame of init) into them. */
fb_result fb_flame_hists_play(fb_flame_hists *h, const fb_flame_setup *S, bool scalar, uint32_t cr0, uint32_t cr1,
                              fb_progress *prog);
/* Plays chains [cr[i][0], cr[i][1]) of each S[i] (n of them, at most FB_FLAME_BATCH) into them, with
 * one wake-up of the pool: the same sums as one fb_flame_hists_play after another. */
#define FB_FLAME_BATCH 32
fb_result fb_flame_hists_play_batch(fb_flame_hists *h, const fb_flame_setup *const *S, const uint32_t (*cr)[2], int n,
                                    bool scalar);
/* Adds them into total (and the bad values into *bad); they are left as they were. */
void fb_flame_hists_fold(fb_flame_hists *h, uint64_t *bad);
void fb_flame_hists_fini(fb_flame_hists *h);

#endif
