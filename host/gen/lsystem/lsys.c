#include "lsys.h"

#include "kernels/hash.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct preset {
    const char *name;
    const char *axiom;
    const char *rules[4];
    int iterations;
    double angle;
} preset;

/* The paper's two examples (Prusinkiewicz and Lindenmayer, The Algorithmic Beauty of Plants, fig.
 * 1.24 and 1.27, as quoted by SPEC.md section 3), and three more from the same figures. */
static const preset presets[] = {
    {"bush", "F", {"F=F[+F]F[-F]F"}, 5, 22.5},
    {"tree", "Y", {"Y=YFX[+Y][-Y]", "X=X[-FFF]F[+FFF]FX"}, 6, 25.7},
    {"sticks", "F", {"F=FF-[-F+F+F]+[+F-F-F]"}, 4, 22.5},
    {"weed", "X", {"X=F[+X]F[-X]+X", "F=FF"}, 7, 20.0},
    {"stochastic", "F", {"F(0.33)=F[+F]F[-F]F", "F(0.33)=F[+F]F", "F(0.34)=F[-F]F"}, 5, 25.7},
};

fb_result fb_lsys_preset(const char *name, fb_lsys *out)
{
    memset(out, 0, sizeof *out);
    for (size_t i = 0; i < sizeof presets / sizeof presets[0]; i++) {
        const preset *p = &presets[i];
        if (strcmp(p->name, name) != 0) continue;
        snprintf(out->axiom, sizeof out->axiom, "%s", p->axiom);
        for (int k = 0; k < 4 && p->rules[k]; k++) {
            char msg[128];
            if (!fb_lsys_parse_rule(p->rules[k], &out->rules[out->nrules++], msg, sizeof msg))
                return fb_fail(FB_ERR_INTERNAL, "preset %s: %s", name, msg);
        }
        out->iterations = p->iterations;
        out->angle = p->angle;
        return FB_OK;
    }
    return fb_fail(FB_ERR_INPUT, "unknown L-system preset \"%s\" (available: %s)", name, FB_LSYS_PRESETS);
}

bool fb_lsys_parse_rule(const char *text, fb_lsys_rule *out, char *msg, size_t n)
{
    memset(out, 0, sizeof *out);
    out->p = -1;
    const char *q = text;
    while (*q == ' ') q++;
    if (!*q || *q == '=' || *q == '(' || *q == ' ') {
        snprintf(msg, n, "expected a rule X=successor, found \"%s\"", text);
        return false;
    }
    out->pred = *q++;
    while (*q == ' ') q++;
    if (*q == '(') {
        char *end;
        out->p = strtod(q + 1, &end);
        if (end == q + 1 || *end != ')' || !isfinite(out->p)) {
            snprintf(msg, n, "expected a probability X(p)=successor, found \"%s\"", text);
            return false;
        }
        q = end + 1;
        while (*q == ' ') q++;
    }
    if (q[0] == '=')
        q++;
    else if (q[0] == '-' && q[1] == '>')
        q += 2;
    else {
        snprintf(msg, n, "expected a rule X=successor (one symbol, then = or ->), found \"%s\"", text);
        return false;
    }
    size_t len = 0;
    for (; *q; q++) {
        if (*q == ' ' || *q == '\t') continue;
        if ((unsigned char)*q < 0x21 || (unsigned char)*q > 0x7e) {
            snprintf(msg, n, "rule \"%s\": successors are printable ASCII symbols", text);
            return false;
        }
        if (len == FB_LSYS_MAX_SUCC) {
            snprintf(msg, n, "rule for %c: successor longer than %d symbols", out->pred, FB_LSYS_MAX_SUCC);
            return false;
        }
        out->succ[len++] = *q;
    }
    return true;
}

/* True when s is balanced, else false with a description of the first problem in msg. */
static bool balanced(const char *s, const char *what, char *msg, size_t n)
{
    long depth = 0;
    for (const char *q = s; *q; q++) {
        depth += *q == '[';
        depth -= *q == ']';
        if (depth < 0) {
            snprintf(msg, n, "%s has unbalanced brackets: ']' at symbol %ld closes nothing", what, (long)(q - s) + 1);
            return false;
        }
    }
    if (depth > 0) {
        snprintf(msg, n, "%s has unbalanced brackets: %ld '[' never closed", what, depth);
        return false;
    }
    return true;
}

bool fb_lsys_valid(const fb_lsys *ls, int *bad, char *msg, size_t n)
{
    *bad = -1;
    if (!ls->axiom[0]) {
        snprintf(msg, n, "the axiom is empty");
        return false;
    }
    for (const char *q = ls->axiom; *q; q++)
        if ((unsigned char)*q < 0x21 || (unsigned char)*q > 0x7e) {
            snprintf(msg, n, "the axiom holds a character that is not a printable ASCII symbol");
            return false;
        }
    if (!balanced(ls->axiom, "the axiom", msg, n)) return false;
    for (int i = 0; i < ls->nrules; i++) {
        const fb_lsys_rule *r = &ls->rules[i];
        char what[32];
        snprintf(what, sizeof what, "the rule for %c", r->pred);
        *bad = i;
        if (r->pred == '[' || r->pred == ']') {
            snprintf(msg, n, "brackets cannot be rewritten (the turtle's push and pop)");
            return false;
        }
        if (!balanced(r->succ, what, msg, n)) return false;
        if (r->p != -1 && !(r->p > 0 && r->p <= 1)) {
            snprintf(msg, n, "probability %g of the rule for %c is not in (0, 1]", r->p, r->pred);
            return false;
        }
    }
    for (int i = 0; i < ls->nrules; i++) {
        const fb_lsys_rule *r = &ls->rules[i];
        *bad = i;
        /* the productions of this symbol, checked at its first rule */
        int first = 0, given = 0, count = 0;
        double sum = 0;
        while (ls->rules[first].pred != r->pred) first++;
        if (first != i) continue;
        for (int k = i; k < ls->nrules; k++) {
            if (ls->rules[k].pred != r->pred) continue;
            count++;
            given += ls->rules[k].p != -1;
            sum += ls->rules[k].p;
        }
        if (given != 0 && given != count) {
            snprintf(msg, n, "symbol %c has %d rules: give every one a probability, or none", r->pred, count);
            return false;
        }
        if (given && fabs(sum - 1) > 1e-6) {
            snprintf(msg, n, "the probabilities of the rules for %c sum to %.9g, not 1", r->pred, sum);
            return false;
        }
    }
    *bad = -1;
    return true;
}

/* Per symbol: its productions and their cumulative thresholds in [0, 2^32). */
typedef struct prodtab {
    int count[256];
    int rule[256][FB_LSYS_MAX_RULES];
    uint64_t thr[256][FB_LSYS_MAX_RULES]; /* production k when r < thr[k] (the last: 2^32) */
    size_t len[FB_LSYS_MAX_RULES];
    size_t nf[FB_LSYS_MAX_RULES]; /* F symbols in the successor */
} prodtab;

static void build_table(const fb_lsys *ls, prodtab *t)
{
    memset(t->count, 0, sizeof t->count);
    for (int i = 0; i < ls->nrules; i++) {
        unsigned char c = (unsigned char)ls->rules[i].pred;
        t->rule[c][t->count[c]++] = i;
        t->len[i] = strlen(ls->rules[i].succ);
        t->nf[i] = 0;
        for (const char *q = ls->rules[i].succ; *q; q++) t->nf[i] += *q == 'F';
    }
    for (int c = 0; c < 256; c++) {
        double cum = 0;
        for (int k = 0; k < t->count[c]; k++) {
            const fb_lsys_rule *r = &ls->rules[t->rule[c][k]];
            cum += r->p == -1 ? 1.0 / t->count[c] : r->p;
            t->thr[c][k] = k + 1 == t->count[c] ? (1ull << 32) : (uint64_t)llround(fmin(cum, 1.0) * 4294967296.0);
        }
    }
}

/* The production applied to symbol c at `pos` of the string of iteration `it`, or -1: none. */
static inline int choose(const prodtab *t, unsigned char c, uint32_t seed, int it, size_t pos)
{
    int n = t->count[c];
    if (n <= 1) return n ? t->rule[c][0] : -1;
    uint64_t r = k_hash3(seed, (uint32_t)it, (uint32_t)pos);
    int k = 0;
    while (r >= t->thr[c][k]) k++;
    return t->rule[c][k];
}

/* Before any string exists: how many of each symbol every iteration holds at least (each symbol
 * rewritten by whichever of its productions gives the fewest) and at most. For a deterministic
 * system the two are the exact counts, so an explosion is refused at once instead of after gigabytes
 * of rewriting; for a stochastic one, only what must happen is refused here, and derive checks each
 * string's real length before allocating it. */
static fb_result predict(const fb_lsys *ls, const prodtab *t, uint64_t max_symbols, uint64_t max_f,
                         const fb_memory *mem, const char *who)
{
    static double lo[256], hi[256], nlo[256], nhi[256]; /* doubles: saturate instead of wrapping */
    double cmin[256], cmax[256];
    memset(lo, 0, sizeof lo);
    for (const char *q = ls->axiom; *q; q++) lo[(unsigned char)*q]++;
    memcpy(hi, lo, sizeof hi);
    double prev = (double)strlen(ls->axiom);
    for (int it = 0; it < ls->iterations; it++) {
        memset(nlo, 0, sizeof nlo);
        memset(nhi, 0, sizeof nhi);
        for (int c = 0; c < 256; c++) {
            if (hi[c] == 0) continue;
            if (t->count[c] == 0) { /* no production: the symbol stays */
                nlo[c] += lo[c], nhi[c] += hi[c];
                continue;
            }
            for (int k = 0; k < 256; k++) cmin[k] = INFINITY, cmax[k] = 0;
            for (int p = 0; p < t->count[c]; p++) {
                double cnt[256] = {0};
                for (const char *q = ls->rules[t->rule[c][p]].succ; *q; q++) cnt[(unsigned char)*q]++;
                for (int k = 0; k < 256; k++) cmin[k] = fmin(cmin[k], cnt[k]), cmax[k] = fmax(cmax[k], cnt[k]);
            }
            for (int k = 0; k < 256; k++)
                if (cmax[k] > 0) nlo[k] += lo[c] * cmin[k], nhi[k] += hi[c] * cmax[k];
        }
        memcpy(lo, nlo, sizeof lo);
        memcpy(hi, nhi, sizeof hi);
        double m = 0;
        for (int k = 0; k < 256; k++) m += lo[k];
        if (m > (double)max_symbols)
            return fb_fail(FB_ERR_INPUT,
                           "%s: the string would exceed max-symbols (%llu) at iteration %d of %d (at least %.4g "
                           "symbols); use fewer iterations or raise max-symbols",
                           who, (unsigned long long)max_symbols, it + 1, ls->iterations, m);
        if (prev + m + 2 > (double)fb_memory_limit(mem)) {
            char need[32], lim[32];
            fb_format_bytes((uint64_t)fmin(prev + m + 2, 9e18), need, sizeof need);
            fb_format_bytes(fb_memory_limit(mem), lim, sizeof lim);
            return fb_fail(FB_ERR_INPUT,
                           "%s: iteration %d of %d needs at least %s for its strings, more than --max-memory %s; use "
                           "fewer iterations",
                           who, it + 1, ls->iterations, need, lim);
        }
        prev = m;
    }
    if (max_f && lo['F'] > (double)max_f)
        return fb_fail(FB_ERR_INPUT,
                       "%s: the derived string would draw at least %.4g segments (F symbols), more than the %llu the "
                       "rasteriser takes; use fewer iterations",
                       who, lo['F'], (unsigned long long)max_f);
    return FB_OK;
}

fb_result fb_lsys_derive(const fb_lsys *ls, uint32_t seed, uint64_t max_symbols, uint64_t max_f, const fb_memory *mem,
                         const char *who, char **out, size_t *len)
{
    *out = NULL;
    *len = 0;
    prodtab *t = malloc(sizeof *t);
    if (!t) return fb_fail(FB_ERR_NOMEM, "out of memory");
    build_table(ls, t);
    size_t n = strlen(ls->axiom);
    if (n > max_symbols) {
        free(t);
        return fb_fail(FB_ERR_INPUT, "%s: the axiom has %zu symbols, more than max-symbols (%llu)", who, n,
                       (unsigned long long)max_symbols);
    }
    fb_result rc = predict(ls, t, max_symbols, max_f, mem, who);
    if (rc) {
        free(t);
        return rc;
    }
    char *cur = malloc(n + 1);
    if (!cur) {
        free(t);
        return fb_fail(FB_ERR_NOMEM, "out of memory");
    }
    memcpy(cur, ls->axiom, n + 1);
    for (int it = 0; it < ls->iterations; it++) {
        /* the new length first, so that an explosion is refused before any memory is asked for */
        uint64_t m = 0, f = 0;
        for (size_t i = 0; i < n && m <= max_symbols; i++) {
            int r = choose(t, (unsigned char)cur[i], seed, it, i);
            m += r < 0 ? 1 : t->len[r];
            f += r < 0 ? cur[i] == 'F' : t->nf[r];
        }
        char need[32], lim[32];
        if (m <= max_symbols && (uint64_t)n + m + 2 > fb_memory_limit(mem)) {
            fb_format_bytes((uint64_t)n + m + 2, need, sizeof need);
            fb_format_bytes(fb_memory_limit(mem), lim, sizeof lim);
            free(cur);
            free(t);
            return fb_fail(FB_ERR_INPUT,
                           "%s: iteration %d of %d needs %s for its strings (%llu symbols), more than --max-memory %s; "
                           "use fewer iterations",
                           who, it + 1, ls->iterations, need, (unsigned long long)m, lim);
        }
        if (m <= max_symbols && max_f && it + 1 == ls->iterations && f > max_f) {
            free(cur);
            free(t);
            return fb_fail(FB_ERR_INPUT,
                           "%s: the derived string would draw %llu segments (F symbols), more than the %llu the "
                           "rasteriser takes; use fewer iterations",
                           who, (unsigned long long)f, (unsigned long long)max_f);
        }
        if (m > max_symbols) {
            free(cur);
            free(t);
            return fb_fail(FB_ERR_INPUT,
                           "%s: the string would exceed max-symbols (%llu) at iteration %d of %d (%zu symbols before "
                           "it); use fewer iterations or raise max-symbols",
                           who, (unsigned long long)max_symbols, it + 1, ls->iterations, n);
        }
        char *next = malloc((size_t)m + 1);
        if (!next) {
            free(cur);
            free(t);
            return fb_fail(FB_ERR_NOMEM, "%s: out of memory for a string of %llu symbols", who, (unsigned long long)m);
        }
        size_t w = 0;
        for (size_t i = 0; i < n; i++) {
            int r = choose(t, (unsigned char)cur[i], seed, it, i);
            if (r < 0) {
                next[w++] = cur[i];
            } else {
                memcpy(next + w, ls->rules[r].succ, t->len[r]);
                w += t->len[r];
            }
        }
        next[w] = 0;
        free(cur);
        cur = next;
        n = w;
    }
    free(t);
    *out = cur;
    *len = n;
    return FB_OK;
}

typedef struct turtle {
    double x, y;
    long turns; /* heading = heading0 + turns * angle + flips * 180 degrees, kept exact */
    long flips;
    int depth;
} turtle;

fb_result fb_lsys_turtle(const char *s, size_t len, double angle, double heading, double step, const char *who,
                         fb_lsys_seg **segs, size_t *nsegs, int *max_depth)
{
    *segs = NULL;
    *nsegs = 0;
    *max_depth = 0;
    size_t nf = 0, stack_cap = 0;
    long depth = 0;
    for (size_t i = 0; i < len; i++) {
        nf += s[i] == 'F';
        depth += s[i] == '[';
        depth -= s[i] == ']';
        if (depth < 0)
            return fb_fail(FB_ERR_INPUT, "%s: unbalanced brackets: ']' at symbol %zu closes nothing", who, i + 1);
        if ((size_t)depth > stack_cap) stack_cap = (size_t)depth;
    }
    if (depth != 0) return fb_fail(FB_ERR_INPUT, "%s: unbalanced brackets: %ld '[' never closed", who, depth);
    fb_lsys_seg *out = malloc((nf ? nf : 1) * sizeof *out);
    turtle *stack = malloc((stack_cap ? stack_cap : 1) * sizeof *stack);
    if (!out || !stack) {
        free(out);
        free(stack);
        return fb_fail(FB_ERR_NOMEM, "%s: out of memory for %zu segments", who, nf);
    }
    const double rad = 3.14159265358979323846 / 180.0;
    turtle T = {0, 0, 0, 0, 0};
    size_t sp = 0, k = 0;
    for (size_t i = 0; i < len; i++) {
        switch (s[i]) {
        case 'F':
        case 'f': {
            double a = fmod(heading + (double)T.turns * angle + 180.0 * (double)(T.flips & 1), 360.0) * rad;
            double x = T.x + step * cos(a), y = T.y + step * sin(a);
            if (s[i] == 'F') out[k++] = (fb_lsys_seg){T.x, T.y, x, y, T.depth};
            T.x = x, T.y = y;
            break;
        }
        case '+':
            T.turns++;
            break;
        case '-':
            T.turns--;
            break;
        case '|':
            T.flips++;
            break;
        case '[':
            stack[sp++] = T;
            T.depth++;
            break;
        case ']':
            T = stack[--sp];
            break;
        default:
            break;
        }
    }
    free(stack);
    for (size_t j = 0; j < k; j++)
        if (out[j].depth > *max_depth) *max_depth = out[j].depth;
    *segs = out;
    *nsegs = k;
    return FB_OK;
}
