/*
 * spvexact: the build's SPIR-V pass that makes a shader's float arithmetic the same on every
 * conformant Vulkan device, then embeds the module as a C array.
 *
 *   spvexact IN.spv OUT.h NAME [OUT.spv]
 *
 * 1. Every float arithmetic instruction (OpFAdd, OpFSub, OpFMul, OpFDiv, OpFRem, OpFMod, OpFNegate,
 *    the vector and matrix products, OpDot) gets the NoContraction decoration. Without it "the
 *    implementation may rearrange floating-point operations using any of the mathematical properties
 *    governing the expressions in precise arithmetic" and fuse a multiply with an add (the Vulkan
 *    specification's SPIR-V environment, "Evaluation of Expressions"); GLSL's `precise` decorates
 *    only what feeds a precise variable, so one forgotten qualifier changes an output's bits on a
 *    GPU and nowhere else. The C side is built with -ffp-contract=off: both round every operation.
 * 2. GLSL.std.450 FMin, FMax and FClamp become NMin, NMax and NClamp: the F forms are undefined on
 *    a NaN operand, the N forms return the other operand, as C's fminf and fmaxf do.
 *
 * The header holds `const uint32_t NAME[]` (what glslangValidator's --vn writes); OUT.spv, when
 * given, the patched module itself (tests/spirv_audit.py reads it). Exit 0, or 1 with one line on
 * stderr on a malformed module or an I/O error.
 */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

enum {
    OP_EXT_INST_IMPORT = 11,
    OP_EXT_INST = 12,
    OP_TYPE_VOID = 19,
    OP_DECORATE = 71,
    DEC_NO_CONTRACTION = 42,
    GLSL_FMIN = 37,
    GLSL_FMAX = 40,
    GLSL_FCLAMP = 43,
    GLSL_NMIN = 79,
    GLSL_NMAX = 80,
    GLSL_NCLAMP = 81,
};

/* The opcodes whose result NoContraction governs (SPIR-V's float arithmetic instructions). */
static int is_float_arith(uint32_t op)
{
    switch (op) {
    case 127: /* OpFNegate */
    case 129: /* OpFAdd */
    case 131: /* OpFSub */
    case 133: /* OpFMul */
    case 136: /* OpFDiv */
    case 140: /* OpFRem */
    case 141: /* OpFMod */
    case 142: /* OpVectorTimesScalar */
    case 143: /* OpMatrixTimesScalar */
    case 144: /* OpVectorTimesMatrix */
    case 145: /* OpMatrixTimesVector */
    case 146: /* OpMatrixTimesMatrix */
    case 147: /* OpOuterProduct */
    case 148: /* OpDot */
        return 1;
    }
    return 0;
}

/* The instructions of the sections before the annotations' end (capabilities to decorations):
 * a new OpDecorate goes before the first instruction that is none of these. */
static int is_preamble(uint32_t op)
{
    return (op >= 1 && op <= 8) || op == 10 || op == 11 || op == 14 || op == 15 || op == 16 || op == 17 || op == 330 ||
           op == 331 || (op >= 71 && op <= 75) || op == 332 || op == 5632 || op == 5633;
}

static int fail(const char *what, const char *path)
{
    fprintf(stderr, "spvexact: %s: %s\n", path, what);
    return 1;
}

int main(int argc, char **argv)
{
    if (argc != 4 && argc != 5) {
        fprintf(stderr, "usage: spvexact IN.spv OUT.h NAME [OUT.spv]\n");
        return 2;
    }
    FILE *f = fopen(argv[1], "rb");
    if (!f) return fail("cannot open", argv[1]);
    fseek(f, 0, SEEK_END);
    long bytes = ftell(f);
    fseek(f, 0, SEEK_SET);
    if (bytes < 20 || bytes % 4) {
        fclose(f);
        return fail("not a SPIR-V module (size)", argv[1]);
    }
    size_t n = (size_t)bytes / 4;
    uint32_t *w = malloc(n * 4);
    if (!w || fread(w, 4, n, f) != n) {
        fclose(f);
        return fail("cannot read", argv[1]);
    }
    fclose(f);
    if (w[0] != 0x07230203u) return fail("not a SPIR-V module (magic)", argv[1]);

    /* pass 1: the GLSL.std.450 import, existing NoContraction decorations, where decorations end */
    uint32_t bound = w[3], glsl = 0;
    unsigned char *decorated = calloc(bound, 1);
    size_t insert_at = 0, count = 0;
    for (size_t i = 5; i < n;) {
        uint32_t len = w[i] >> 16, op = w[i] & 0xffffu;
        if (len == 0 || i + len > n) return fail("malformed instruction stream", argv[1]);
        if (op == OP_EXT_INST_IMPORT && len >= 3 && !strcmp((const char *)&w[i + 2], "GLSL.std.450")) glsl = w[i + 1];
        if (op == OP_DECORATE && len == 3 && w[i + 2] == DEC_NO_CONTRACTION && w[i + 1] < bound)
            decorated[w[i + 1]] = 1;
        if (!insert_at && !is_preamble(op)) insert_at = i;
        if (is_float_arith(op) && len >= 3 && !decorated[w[i + 2]]) count++;
        i += len;
    }
    if (!insert_at) return fail("no types or functions", argv[1]);

    /* pass 2: copy, inserting one OpDecorate per undecorated result and renaming FMin/FMax/FClamp */
    uint32_t *o = malloc((n + 3 * count) * 4);
    if (!o) return fail("out of memory", argv[1]);
    size_t k = 0;
    memcpy(o, w, insert_at * 4);
    k = insert_at;
    for (size_t i = insert_at; i < n;) {
        uint32_t len = w[i] >> 16, op = w[i] & 0xffffu;
        if (is_float_arith(op) && !decorated[w[i + 2]]) {
            o[k++] = (3u << 16) | OP_DECORATE;
            o[k++] = w[i + 2];
            o[k++] = DEC_NO_CONTRACTION;
            decorated[w[i + 2]] = 1;
        }
        i += len;
    }
    for (size_t i = insert_at; i < n;) {
        uint32_t len = w[i] >> 16, op = w[i] & 0xffffu;
        memcpy(&o[k], &w[i], len * 4);
        if (op == OP_EXT_INST && len >= 5 && glsl && w[i + 3] == glsl) {
            uint32_t *inst = &o[k + 4];
            if (*inst == GLSL_FMIN)
                *inst = GLSL_NMIN;
            else if (*inst == GLSL_FMAX)
                *inst = GLSL_NMAX;
            else if (*inst == GLSL_FCLAMP)
                *inst = GLSL_NCLAMP;
        }
        k += len;
        i += len;
    }

    FILE *h = fopen(argv[2], "w");
    if (!h) return fail("cannot write", argv[2]);
    fprintf(h, "/* %s: generated by spvexact (cmake/spvexact.c) */\n#pragma once\n#include <stdint.h>\n", argv[3]);
    fprintf(h, "static const uint32_t %s[] = {", argv[3]);
    for (size_t i = 0; i < k; i++) fprintf(h, "%s0x%08x,", i % 8 ? "" : "\n\t", o[i]);
    fprintf(h, "\n};\n");
    if (fclose(h)) return fail("cannot write", argv[2]);
    if (argc == 5) {
        FILE *s = fopen(argv[4], "wb");
        if (!s || fwrite(o, 4, k, s) != k || fclose(s)) return fail("cannot write", argv[4]);
    }
    free(o);
    free(w);
    free(decorated);
    return 0;
}
