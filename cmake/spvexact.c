/*
 * spvexact: the build's SPIR-V pass that makes a shader's float arithmetic the same on every
 * conformant Vulkan device, then embeds the module as a C array.
 *
 *   spvexact IN.spv OUT.spv NATIVE.spv
 *   spvexact --embed NAME OUT.spv NATIVE.spv OUT.h
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
 * OUT.spv is the patched module (tests/spirv_audit.py reads it). NATIVE.spv is the same module with
 * the specialisation constant K_EXACT_NATIVE (SpecId 127, kernels/exact.h) made the constant true:
 * the build runs spirv-opt's dead-branch and dead-function passes over it, so that a device known to
 * divide exactly (lavapipe) never compiles the portable division's code. Mesa inlines every call
 * before it folds a specialisation constant, and that inlined dead code doubled lavapipe's compile
 * time and memory (a Julia pipeline: 0.8 s and 100 MiB more).
 *
 * --embed writes the header: `static const uint32_t NAME[]` holding the portable module, then the
 * native one, then two words: the portable module's length in words and SPV_VARIANTS_MAGIC
 * (host/io/spvpatch.h picks one of the two). Exit 0, or 1 with one line on stderr on a malformed
 * module or an I/O error.
 */
#include <stdbool.h>
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
    OP_SPEC_CONSTANT_TRUE = 48,
    OP_SPEC_CONSTANT_FALSE = 49,
    OP_CONSTANT_TRUE = 41,
    DEC_SPEC_ID = 1,
    SPEC_EXACT_NATIVE = 127,         /* K_SPEC_EXACT_NATIVE, kernels/exact.h */
    SPV_VARIANTS_MAGIC = 0x564e4246, /* "FBNV": host/io/spvpatch.h */
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

/* The whole module at `path`: *n words, checked for SPIR-V's magic. NULL after one line on stderr. */
static uint32_t *read_module(const char *path, size_t *n)
{
    FILE *f = fopen(path, "rb");
    if (!f) {
        fail("cannot open", path);
        return NULL;
    }
    fseek(f, 0, SEEK_END);
    long bytes = ftell(f);
    fseek(f, 0, SEEK_SET);
    uint32_t *w = bytes >= 20 && bytes % 4 == 0 ? malloc((size_t)bytes) : NULL;
    *n = (size_t)bytes / 4;
    if (!w || fread(w, 4, *n, f) != *n || w[0] != 0x07230203u) {
        fclose(f);
        free(w);
        fail("not a SPIR-V module", path);
        return NULL;
    }
    fclose(f);
    return w;
}

static int write_module(const char *path, const uint32_t *w, size_t n)
{
    FILE *s = fopen(path, "wb");
    if (!s || fwrite(w, 4, n, s) != n || fclose(s)) return fail("cannot write", path);
    return 0;
}

/* The header: the portable module, the native one, their split and the magic (see the top). */
static int embed(const char *name, const char *portable, const char *native, const char *header)
{
    size_t np = 0, nn = 0;
    uint32_t *p = read_module(portable, &np), *q = p ? read_module(native, &nn) : NULL;
    if (!q) return 1;
    FILE *h = fopen(header, "w");
    if (!h) return fail("cannot write", header);
    fprintf(h, "/* %s: generated by spvexact (cmake/spvexact.c): portable module, native module, split */\n", name);
    fprintf(h, "#pragma once\n#include <stdint.h>\nstatic const uint32_t %s[] = {", name);
    size_t k = 0;
    for (size_t i = 0; i < np; i++, k++) fprintf(h, "%s0x%08x,", k % 8 ? "" : "\n\t", p[i]);
    for (size_t i = 0; i < nn; i++, k++) fprintf(h, "%s0x%08x,", k % 8 ? "" : "\n\t", q[i]);
    fprintf(h, "\n\t0x%08zx,0x%08x,\n};\n", np, (unsigned)SPV_VARIANTS_MAGIC);
    free(p);
    free(q);
    if (fclose(h)) return fail("cannot write", header);
    return 0;
}

int main(int argc, char **argv)
{
    if (argc == 6 && !strcmp(argv[1], "--embed")) return embed(argv[2], argv[3], argv[4], argv[5]);
    if (argc != 4) {
        fprintf(stderr, "usage: spvexact IN.spv OUT.spv NATIVE.spv | spvexact --embed NAME OUT.spv NATIVE.spv OUT.h\n");
        return 2;
    }
    size_t n = 0;
    uint32_t *w = read_module(argv[1], &n);
    if (!w) return 1;

    /* pass 1: the GLSL.std.450 import, existing NoContraction decorations, where decorations end,
     * the id that SpecId 127 names */
    uint32_t bound = w[3], glsl = 0, spec_native = 0;
    unsigned char *decorated = calloc(bound, 1);
    size_t insert_at = 0, count = 0;
    for (size_t i = 5; i < n;) {
        uint32_t len = w[i] >> 16, op = w[i] & 0xffffu;
        if (len == 0 || i + len > n) return fail("malformed instruction stream", argv[1]);
        if (op == OP_EXT_INST_IMPORT && len >= 3 && !strcmp((const char *)&w[i + 2], "GLSL.std.450")) glsl = w[i + 1];
        if (op == OP_DECORATE && len == 3 && w[i + 2] == DEC_NO_CONTRACTION && w[i + 1] < bound)
            decorated[w[i + 1]] = 1;
        if (op == OP_DECORATE && len == 4 && w[i + 2] == DEC_SPEC_ID && w[i + 3] == SPEC_EXACT_NATIVE)
            spec_native = w[i + 1];
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

    if (write_module(argv[2], o, k)) return 1;
    /* the native variant: SpecId 127's decoration removed and its constant made OpConstantTrue */
    size_t m = 5;
    for (size_t i = 5; i < k;) {
        uint32_t len = o[i] >> 16, op = o[i] & 0xffffu;
        bool spec_dec = op == OP_DECORATE && len == 4 && o[i + 1] == spec_native && o[i + 2] == DEC_SPEC_ID;
        if (!(spec_native && spec_dec)) {
            memmove(&o[m], &o[i], len * 4);
            if (spec_native && (op == OP_SPEC_CONSTANT_TRUE || op == OP_SPEC_CONSTANT_FALSE) && o[m + 2] == spec_native)
                o[m] = (3u << 16) | OP_CONSTANT_TRUE;
            m += len;
        }
        i += len;
    }
    int rc = write_module(argv[3], o, m);
    free(o);
    free(w);
    free(decorated);
    return rc;
}
