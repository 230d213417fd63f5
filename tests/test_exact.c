/*
 * kernels/exact.h's portable division and square root against the CPU's IEEE 754 operations, bit
 * for bit: the special values and their NaN answers, subnormal operands and results, ties, the
 * overflow and underflow edges, and 2 x 10^7 random operands spread over every exponent. The soft
 * paths' first estimate is perturbed by up to PERTURB ulp (more than the 2.5 ulp of a Vulkan
 * device's OpFDiv, and than its sqrt's error), so that the exact correction does the work; a second
 * pass with the true estimate checks the path a perfect device takes.
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#define PERTURB 4
static int g_perturb; /* the estimate's offset in ulp, -PERTURB .. PERTURB */
static float perturb(float v)
{
    uint32_t u;
    memcpy(&u, &v, 4);
    u += (uint32_t)g_perturb;
    memcpy(&v, &u, 4);
    return v;
}
#define KX_TEST_ESTIMATE(v) perturb(v)
/* a double estimate no better than single precision: what Vulkan promises for doubles */
static double g_dscale = 1.0;
static double dperturb(double v)
{
    return (double)(float)(v * g_dscale);
}
#define KX_TEST_DESTIMATE(v) dperturb(v)
#include "kernels/exact.h"

static uint32_t bits(float x)
{
    uint32_t u;
    memcpy(&u, &x, 4);
    return u;
}
static float fl(uint32_t u)
{
    float x;
    memcpy(&x, &u, 4);
    return x;
}

static uint64_t rng = 0x9e3779b97f4a7c15ull;
static uint32_t next(void)
{
    rng ^= rng << 13;
    rng ^= rng >> 7;
    rng ^= rng << 17;
    return (uint32_t)(rng >> 16);
}

static long failures;
static uint64_t dbits(double x)
{
    uint64_t u;
    memcpy(&u, &x, 8);
    return u;
}
static double dfl(uint64_t u)
{
    double x;
    memcpy(&x, &u, 8);
    return x;
}
static void check_ddiv(double a, double b)
{
    volatile double va = a, vb = b;
    uint64_t want = dbits(va / vb), got = dbits(kx_ddiv_soft(a, b));
    if (want != got && failures++ < 10)
        printf("ddiv %016llx / %016llx (%g / %g): want %016llx, got %016llx\n", (unsigned long long)dbits(a),
               (unsigned long long)dbits(b), a, b, (unsigned long long)want, (unsigned long long)got);
}
static void check_div(float a, float b)
{
    /* volatile: the compiler must divide at run time, as the native path does */
    volatile float va = a, vb = b;
    uint32_t want = bits(va / vb), got = bits(kx_div_soft(a, b));
    if (want != got && failures++ < 10)
        printf("div %08x / %08x (%g / %g): want %08x, got %08x (estimate %+d ulp)\n", bits(a), bits(b), a, b, want, got,
               g_perturb);
}
static void check_sqrt(float x)
{
    volatile float vx = x;
    uint32_t want = bits(sqrtf(vx)), got = bits(kx_sqrt_soft(x));
    if (want != got && failures++ < 10)
        printf("sqrt %08x (%g): want %08x, got %08x (estimate %+d ulp)\n", bits(x), x, want, got, g_perturb);
}

int main(void)
{
    static const uint32_t edge[] = {
        0x00000000, 0x80000000, 0x00000001, 0x80000001, 0x00000002, 0x007fffff, 0x00400000, 0x00800000,
        0x00800001, 0x00ffffff, 0x01000000, 0x3f800000, 0xbf800000, 0x3f800001, 0x3f7fffff, 0x40000000,
        0x40400000, 0x3eaaaaab, 0x7f7fffff, 0xff7fffff, 0x7f000000, 0x7f800000, 0xff800000, 0x7fc00000,
        0xffc00000, 0x7f800001, 0x7fa00000, 0xff812345, 0x34000000, 0x0b000000, 0x4b000000, 0x33800000,
    };
    const int ne = (int)(sizeof edge / sizeof edge[0]);
    long n = 0;
    for (g_perturb = -PERTURB; g_perturb <= PERTURB; g_perturb++) {
        for (int i = 0; i < ne; i++) {
            check_sqrt(fl(edge[i]));
            for (int j = 0; j < ne; j++) check_div(fl(edge[i]), fl(edge[j])), n++;
        }
        /* random bit patterns (every exponent, subnormals and specials included) */
        for (int i = 0; i < 1000000; i++) {
            check_div(fl(next()), fl(next()));
            check_sqrt(fl(next()));
            n += 2;
        }
        /* quotients near 1 and exact ties: a = b q with q of 25 bits lands halfway between floats */
        for (int i = 0; i < 200000; i++) {
            uint32_t mb = 0x800000u | (next() & 0x7fffffu), q = 0x1000000u | (next() & 0xffffffu) | 1u;
            float b = (float)mb, a = (float)((double)mb * q); /* often inexact: a near-tie */
            check_div(a, b);
            check_div(a * 0x1p-140f, b); /* the same quotients, subnormal */
            check_div(fl(bits(b) + (next() & 7)), b);
            n += 3;
        }
        /* results near the subnormal boundary and overflow */
        for (int i = 0; i < 200000; i++) {
            float a = fl((next() & 0x80ffffffu) | (uint32_t)(1 + next() % 40) << 23);
            float b = fl((next() & 0x007fffffu) | (uint32_t)(150 + next() % 80) << 23);
            check_div(a, b);
            check_div(b, a);
            check_sqrt(a);
            n += 3;
        }
    }
    g_perturb = 0;
    /* double: random significands over a wide range of exponents (the quotient normal), integers and
     * the julia layer's own divisions (pixel coordinates by the width, 1 by a denominator) */
    for (int k = 0; k < 3; k++) {
        g_dscale = k == 0 ? 1.0 : k == 1 ? 1.0 + 0x1p-21 : 1.0 - 0x1p-21; /* estimates off by ~4 float ulp */
        for (int i = 0; i < 1000000; i++) {
            uint64_t ua = ((uint64_t)next() << 32 | next()) & 0x800fffffffffffffull,
                     ub = ((uint64_t)next() << 32 | next()) & 0x800fffffffffffffull;
            ua |= (uint64_t)(1023 - 300 + next() % 600) << 52;
            ub |= (uint64_t)(1023 - 300 + next() % 600) << 52;
            check_ddiv(dfl(ua), dfl(ub));
            check_ddiv((double)(next() % 100000) + 0.5, (double)(1 + next() % 16384));
            check_ddiv(1.0, dfl(ub));
            n += 3;
        }
        static const double sp[] = {0.0, -0.0, 1.0, -1.0, 3.0, 1e300, 1e-300, 0x1p-1074, INFINITY, -INFINITY};
        for (int i = 0; i < 10; i++)
            for (int j = 0; j < 10; j++) check_ddiv(sp[i], sp[j]), n++;
    }
    printf("exact: %ld operations, %ld differ from IEEE 754 (estimates perturbed by up to %d ulp)\n", n, failures,
           PERTURB);
    return failures ? 1 : 0;
}
