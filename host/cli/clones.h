/*
 * FB_CLONES: a function compiled twice, for AVX2 and for the x86-64 baseline (SSE2), the one the
 * CPU can run chosen when the program loads. The project compiles without contraction
 * (-ffp-contract=off) and the vectoriser never reassociates, so both clones do the same operations
 * on each value, in the same order: the same bits.
 */
#ifndef FB_CLONES_H
#define FB_CLONES_H

#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#define FB_CLONES __attribute__((target_clones("avx2", "default")))
#else
#define FB_CLONES
#endif

#endif
