/*
 * Counter-based randomness: every random number is a pure function of (seed, stream, index), so
 * a sample is the same whichever thread, strip or device computes it. There is no generator state.
 *
 * k_hash is Chris Wellons' "lowbias32" integer finaliser (bias 0.17, hash-prospector), chosen for
 * being four multiplies/xorshifts that wrap identically in C uint32_t and GLSL uint.
 */
#ifndef FB_KERNELS_HASH_H
#define FB_KERNELS_HASH_H

#include "common.h"

K_FN uint k_hash(uint x)
{
    x ^= x >> 16;
    x *= 0x7feb352du;
    x ^= x >> 15;
    x *= 0x846ca68bu;
    x ^= x >> 16;
    return x;
}

/* Hash of a (seed, stream, index) triple. Chained so that every input bit reaches every output. */
K_FN uint k_hash3(uint seed, uint stream, uint index)
{
    return k_hash(index ^ k_hash(stream ^ k_hash(seed ^ 0x9e3779b9u)));
}

/* Hash of 2D integer lattice coordinates under an (already hashed) seed. Two rounds, the inner one
 * depending on the row only: the four corners of a lattice cell share two inner hashes, which the
 * compiler computes once (common subexpressions), so a cell costs 6 rounds instead of 12. The odd
 * multiplier keeps small x differences from cancelling small row-hash differences. */
K_FN uint k_hash2i(uint seed, uint ix, uint iy)
{
    return k_hash((ix * 0x9e3779b1u) ^ k_hash(iy ^ seed ^ 0x632be5abu));
}

/* The top 24 bits of h as a float in [0, 1): exact in binary32, the same in both languages. */
K_FN float k_u01(uint h)
{
    return K_F(h >> 8) * (1.0f / 16777216.0f);
}

/* Uniform float in [0, 1) for (seed, stream, index). */
K_FN float k_rand01(uint seed, uint stream, uint index)
{
    return k_u01(k_hash3(seed, stream, index));
}

#endif
