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

#endif
