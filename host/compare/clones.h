/*
 * FB_CLONES: a function compiled three times, for AVX-512 (F), AVX2 and the x86-64 baseline (SSE2),
 * the best one the CPU can run chosen when the program loads. The project compiles without
 * contraction (-ffp-contract=off) and the vectoriser never reassociates, so every clone does the
 * same operations on each value, in the same order: the same bits (an AVX-512 clone only runs a
 * loop 16 lanes wide where AVX2 runs it 8; explicit 8-lane vectors stay 8 lanes).
 */
#ifndef FB_CLONES_H
#define FB_CLONES_H

#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#define FB_CLONES __attribute__((target_clones("avx512f", "avx2", "default")))
#else
#define FB_CLONES
#endif

#endif
