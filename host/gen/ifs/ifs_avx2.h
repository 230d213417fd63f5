/* The hand-vectorised chaos game: the native fast path and the benchmark's reference (see
 * ifs_avx2.c). `params` is a K_IfsParams, `maps` its
 * K_IfsMap table. */
#ifndef FB_IFS_AVX2_H
#define FB_IFS_AVX2_H

#include "fb.h"

#include <stdbool.h>
#include <stdint.h>

/* True when this CPU has AVX2 and the run is one the loop implements (at most 8 maps, and a
 * condensation set that is an IFS of at most 8 maps if any: not an L-system drawing). */
bool fb_ifs_avx2_supported(const void *params);

/* The whole run of `params` (every chain, every step) on `threads` threads into hits[] and colour
 * sums sum[] (hist_w * hist_h cells each, overwritten): the same sums as the kernel. */
fb_result fb_ifs_avx2_game(const void *params, const void *maps, int threads, uint32_t *hits, uint64_t *sum);

/* Steps [t0, t1) of chains [c0, c1) of `params`, added to hits[] and sum[]; adds the points outside
 * the frame, discarded and restarted to counts[0..2]. Chains start at t0 == 0, else resume from
 * state[chain] (a K_IfsChain per chain of the run), where the window's end is stored; state may be
 * NULL for a window of every step (t0 = 0, t1 = UINT32_MAX). Windows one after another give the
 * sums of one window of every step, bit for bit. Needs fb_ifs_avx2_supported. */
void fb_ifs_avx2_chains(const void *params, const void *maps, uint32_t c0, uint32_t c1, uint32_t t0, uint32_t t1,
                        void *state, uint32_t *hits, uint64_t *sum, uint64_t counts[3]);

#endif
