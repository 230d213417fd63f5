/*
 * IFS map lists: presets, the Fractint .ifs reader and the checks. See ifs.h.
 */
#include "ifs.h"

#include "textin.h"

#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ---- presets -------------------------------------------------------------------------------- */

typedef struct preset {
    const char *name;
    int n;
    fb_ifs_map m[4];
} preset;

static const preset k_presets[] = {
    /* Barnsley's fern (Fractals Everywhere, table III.3) */
    {"fern",
     4,
     {{0, 0, 0, 0.16, 0, 0, 0.01},
      {0.85, 0.04, -0.04, 0.85, 0, 1.6, 0.85},
      {0.2, -0.26, 0.23, 0.22, 0, 1.6, 0.07},
      {-0.15, 0.28, 0.26, 0.24, 0, 0.44, 0.07}}},
    /* the Sierpinski triangle: three half-size copies */
    {"sierpinski",
     3,
     {{0.5, 0, 0, 0.5, 0, 0, 1.0 / 3},
      {0.5, 0, 0, 0.5, 0.5, 0, 1.0 / 3},
      {0.5, 0, 0, 0.5, 0.25, 0.4330127018922193, 1.0 / 3}}},
    /* a maple leaf (Barnsley) */
    {"maple",
     4,
     {{0.14, 0.01, 0, 0.51, -0.08, -1.31, 0.10},
      {0.43, 0.52, -0.45, 0.50, 1.49, -0.75, 0.35},
      {0.45, -0.49, 0.47, 0.47, -1.62, -0.74, 0.35},
      {0.49, 0, 0, 0.51, 0.02, 1.62, 0.20}}},
    /* a tree: trunk, two rotated half-size crowns and a small centre copy */
    {"tree",
     4,
     {{0, 0, 0, 0.5, 0, 0, 0.05},
      {0.42, -0.42, 0.42, 0.42, 0, 0.2, 0.40},
      {0.42, 0.42, -0.42, 0.42, 0, 0.2, 0.40},
      {0.1, 0, 0, 0.1, 0, 0.2, 0.15}}},
    /* Fractint's spiral */
    {"spiral",
     3,
     {{0.787879, -0.424242, 0.242424, 0.859848, 1.758647, 1.408065, 0.895652},
      {-0.121212, 0.257576, 0.151515, 0.053030, -6.721654, 1.377236, 0.052174},
      {0.181818, -0.136364, 0.090909, 0.181818, 6.086107, 1.568035, 0.052174}}},
};

/* The population's tree: the `tree` preset scaled by 1/4 about the origin (conjugating by a scaling
 * keeps the linear parts and scales the translations), so that the row's trees stand apart. */
#define POPULATION_TREE_SCALE 0.25

fb_result fb_ifs_preset(const char *name, fb_ifs *out, fb_ifs *cond, bool *has_cond)
{
    memset(out, 0, sizeof *out);
    if (has_cond) *has_cond = false;
    if (!strcmp(name, "population")) {
        /* SPEC.md 3: w1(x, y) = (0.75x + 0.25, 0.75y) applied to a tree standing at the origin */
        out->n = 1;
        out->m[0] = (fb_ifs_map){0.75, 0, 0, 0.75, 0.25, 0, -1};
        if (cond) {
            fb_result rc = fb_ifs_preset("tree", cond, NULL, NULL);
            if (rc) return rc;
            for (int k = 0; k < cond->n; k++) {
                cond->m[k].e *= POPULATION_TREE_SCALE;
                cond->m[k].f *= POPULATION_TREE_SCALE;
            }
        }
        if (has_cond) *has_cond = true;
        return FB_OK;
    }
    for (size_t i = 0; i < sizeof k_presets / sizeof k_presets[0]; i++) {
        if (strcmp(k_presets[i].name, name) != 0) continue;
        out->n = k_presets[i].n;
        memcpy(out->m, k_presets[i].m, sizeof(fb_ifs_map) * (size_t)out->n);
        return FB_OK;
    }
    return fb_fail(FB_ERR_USAGE, "unknown IFS preset \"%s\" (known: %s)", name, FB_IFS_PRESETS);
}

/* ---- Fractint .ifs files -------------------------------------------------------------------- */

typedef struct lexer {
    const char *s, *p, *origin;
    int line, col;
} lexer;

static void lex_advance(lexer *L)
{
    if (*L->p == '\n') {
        L->line++;
        L->col = 1;
    } else {
        L->col++;
    }
    L->p++;
}

/* Skips white space and `;` comments. */
static void lex_skip(lexer *L)
{
    for (;;) {
        while (*L->p && isspace((unsigned char)*L->p)) lex_advance(L);
        if (*L->p != ';') return;
        while (*L->p && *L->p != '\n') lex_advance(L);
    }
}

static fb_result lex_error(const lexer *L, const char *fmt, const char *arg)
{
    char msg[256];
    snprintf(msg, sizeof msg, fmt, arg);
    return fb_fail(FB_ERR_INPUT, "%s:%d:%d: %s", L->origin, L->line, L->col, msg);
}

fb_result fb_ifs_parse_text(const char *text, const char *origin, const char *entry, fb_ifs *out)
{
    lexer L = {text, text, origin, 1, 1};
    char names[512] = "";
    memset(out, 0, sizeof *out);
    for (;;) {
        lex_skip(&L);
        if (!*L.p) break;
        /* a name: everything up to white space, '{' or '(' */
        char name[128];
        int len = 0;
        int line = L.line, col = L.col;
        while (*L.p && !isspace((unsigned char)*L.p) && *L.p != '{' && *L.p != '(' && *L.p != ';') {
            if (*L.p == '}') return lex_error(&L, "unexpected '}'%s", "");
            if (len < (int)sizeof name - 1) name[len++] = *L.p;
            lex_advance(&L);
        }
        name[len] = 0;
        if (!len) return lex_error(&L, "expected an entry name before '%.1s'", L.p);
        lex_skip(&L);
        bool three_d = false;
        if (*L.p == '(') {
            const char *close = strchr(L.p, ')');
            if (!close) return lex_error(&L, "unclosed '(' after entry %s", name);
            three_d = (close - L.p == 3) && (L.p[1] == '3') && (L.p[2] == 'D' || L.p[2] == 'd');
            while (L.p <= close) lex_advance(&L);
            lex_skip(&L);
        }
        if (*L.p != '{') return lex_error(&L, "expected '{' after entry name %s", name);
        lex_advance(&L);
        bool want = !three_d && (entry ? !strcmp(entry, name) : out->n == 0);
        if (strlen(names) + strlen(name) + 3 < sizeof names)
            snprintf(names + strlen(names), sizeof names - strlen(names), "%s%s", names[0] ? ", " : "", name);
        double v[FB_IFS_MAX_MAPS * 7];
        int count = 0;
        lexer close;
        for (;;) {
            lex_skip(&L);
            if (!*L.p) return lex_error(&L, "entry %s is not closed with '}'", name);
            if (*L.p == '}') {
                close = L;
                lex_advance(&L);
                break;
            }
            char *end;
            errno = 0;
            double x = strtod(L.p, &end);
            if (end == L.p || errno || !isfinite(x) ||
                (*end && !isspace((unsigned char)*end) && *end != '}' && *end != ';')) {
                char tok[32];
                int n = 0;
                while (L.p[n] && !isspace((unsigned char)L.p[n]) && n < 31) n++;
                snprintf(tok, sizeof tok, "%.*s", n, L.p);
                return lex_error(&L, "expected a number, found \"%s\"", tok);
            }
            if (count == FB_IFS_MAX_MAPS * 7 && !three_d) {
                char lim[64];
                snprintf(lim, sizeof lim, "%s has more than %d maps", name, FB_IFS_MAX_MAPS);
                return lex_error(&L, "entry %s", lim);
            }
            if (count < FB_IFS_MAX_MAPS * 7) v[count] = x;
            count++;
            while (L.p < end) lex_advance(&L);
        }
        if (three_d && entry && !strcmp(entry, name))
            return fb_fail(FB_ERR_INPUT,
                           "%s:%d:%d: entry %s is a 3D IFS; only 2D entries (7 numbers per map) are "
                           "supported",
                           origin, line, col, name);
        if (!three_d && count % 7 != 0) {
            char what[160];
            snprintf(what, sizeof what, "entry %s has %d numbers; a 2D IFS has 7 per map (a b c d e f p)", name, count);
            return lex_error(&close, "%s", what);
        }
        if (want && !three_d) {
            out->n = count / 7;
            for (int k = 0; k < out->n; k++)
                out->m[k] = (fb_ifs_map){v[7 * k],     v[7 * k + 1], v[7 * k + 2], v[7 * k + 3],
                                         v[7 * k + 4], v[7 * k + 5], v[7 * k + 6]};
            if (!out->n) return fb_fail(FB_ERR_INPUT, "%s:%d:%d: entry %s has no maps", origin, line, col, name);
            if (!entry) return FB_OK;
        }
    }
    if (out->n) return FB_OK;
    if (entry) return fb_fail(FB_ERR_INPUT, "%s: no 2D entry named \"%s\" (entries: %s)", origin, entry, names);
    return fb_fail(FB_ERR_INPUT, "%s: no 2D IFS entries in the file", origin);
}

fb_result fb_ifs_read_file(const char *path, const char *entry, fb_ifs *out)
{
    char *text = NULL;
    size_t len = 0;
    fb_result orc = fb_input_slurp(path, ".ifs", (size_t)64 << 20, &text, &len);
    if (orc) return orc;
    if (strlen(text) != len) {
        free(text);
        return fb_fail(FB_ERR_INPUT, "%s: contains a NUL byte; not an .ifs text file", path);
    }
    fb_result rc = fb_ifs_parse_text(text, path, entry, out);
    free(text);
    return rc;
}

/* ---- checks and derived values -------------------------------------------------------------- */

double fb_ifs_contraction(const fb_ifs_map *m)
{
    double t = m->a * m->a + m->b * m->b + m->c * m->c + m->d * m->d;
    double det = m->a * m->d - m->b * m->c;
    double disc = t * t - 4 * det * det;
    return sqrt((t + sqrt(disc > 0 ? disc : 0)) / 2);
}

bool fb_ifs_valid(const fb_ifs *ifs, int *bad, char *msg, size_t len)
{
    *bad = -1;
    if (ifs->n < 1) return snprintf(msg, len, "the map list is empty"), false;
    if (ifs->n > FB_IFS_MAX_MAPS) return snprintf(msg, len, "more than %d maps", FB_IFS_MAX_MAPS), false;
    int given = 0;
    double sum = 0;
    for (int k = 0; k < ifs->n; k++) {
        const fb_ifs_map *m = &ifs->m[k];
        const double v[6] = {m->a, m->b, m->c, m->d, m->e, m->f};
        *bad = k;
        for (int i = 0; i < 6; i++)
            if (!isfinite(v[i]) || fabs(v[i]) > 1e6)
                return snprintf(msg, len, "coefficient %c is not a finite number within +-1e6", "abcdef"[i]), false;
        double s = fb_ifs_contraction(m);
        if (!(s < 1))
            return snprintf(msg, len,
                            "the map is not contractive (largest singular value %.4g >= 1); the chaos game needs "
                            "every map to shrink distances",
                            s),
                   false;
        if (m->p == -1) continue; /* not given */
        if (!isfinite(m->p)) return snprintf(msg, len, "the probability is not a finite number"), false;
        if (m->p < 0) return snprintf(msg, len, "probability %g is negative", m->p), false;
        given++;
        sum += m->p;
    }
    *bad = -1;
    if (given && given != ifs->n)
        return snprintf(msg, len, "give a probability for every map or for none (%d of %d given)", given, ifs->n),
               false;
    if (given && !(sum > 0)) return snprintf(msg, len, "the probabilities sum to 0"), false;
    return true;
}

void fb_ifs_probabilities(const fb_ifs *ifs, double *p)
{
    double sum = 0, top = 0;
    bool given = ifs->n > 0 && ifs->m[0].p >= 0;
    for (int k = 0; k < ifs->n; k++) {
        const fb_ifs_map *m = &ifs->m[k];
        p[k] = given ? m->p : fabs(m->a * m->d - m->b * m->c);
        if (p[k] > top) top = p[k];
    }
    for (int k = 0; k < ifs->n; k++) {
        if (!given) p[k] = top > 0 ? fmax(p[k], 0.01 * top) : 1.0;
        sum += p[k];
    }
    for (int k = 0; k < ifs->n; k++) p[k] /= sum;
}

int fb_ifs_auto_skip(const fb_ifs *ifs)
{
    double p[FB_IFS_MAX_MAPS], lambda = 0;
    fb_ifs_probabilities(ifs, p);
    for (int k = 0; k < ifs->n; k++) {
        double s = fb_ifs_contraction(&ifs->m[k]);
        lambda += p[k] * log(s > 1e-6 ? s : 1e-6);
    }
    double steps = lambda < 0 ? 24 * log(2.0) / -lambda : 1e9;
    return steps < 20 ? 20 : steps > 10000 ? 10000 : (int)ceil(steps);
}

/* ---- tone mapping ----------------------------------------------------------------------------- */

/* The 99.5th percentile of the positive densities by a two-pass radix selection on the bit
 * patterns (ordered like the values for positive floats): exact, O(n), no copy. */
double fb_ifs_density_ref(const float *density, size_t n)
{
    size_t m = 0;
    for (size_t i = 0; i < n; i++) m += density[i] > 0;
    if (!m) return 1.0;
    size_t k = (size_t)(0.995 * (double)(m - 1)); /* rank among the positive values, from 0 */
    uint32_t *bins = calloc(65536, sizeof *bins);
    if (!bins) return 1.0;
    uint32_t hi = 0, lo = 0;
    for (int pass = 0; pass < 2; pass++) {
        memset(bins, 0, 65536 * sizeof *bins);
        for (size_t i = 0; i < n; i++) {
            if (!(density[i] > 0)) continue;
            uint32_t u;
            memcpy(&u, &density[i], 4);
            if (pass == 0)
                bins[u >> 16]++;
            else if (u >> 16 == hi)
                bins[u & 0xffff]++;
        }
        uint32_t b = 0;
        while (k >= bins[b]) k -= bins[b++];
        if (pass == 0)
            hi = b;
        else
            lo = b;
    }
    free(bins);
    uint32_t u = hi << 16 | lo;
    float r;
    memcpy(&r, &u, 4);
    return r;
}

static double tone_gamma(const fb_ifs_tone *t, double x)
{
    double g = 1.0 / t->gamma;
    if (x <= 0) return 0;
    if (x < t->threshold) return x * pow(t->threshold, g - 1); /* linear through 0, meeting the curve */
    return pow(x, g);
}

void fb_ifs_tonemap_row(const fb_ifs_tone *t, const float *density, const float *colour, size_t n, float *R, float *G,
                        float *B, float *A)
{
    double norm = 1.0 / log1p(t->dref > 0 ? t->dref : 1.0);
    for (size_t i = 0; i < n; i++) {
        if (!(density[i] > 0)) {
            R[i] = G[i] = B[i] = A[i] = 0;
            continue;
        }
        double alin = t->brightness * log1p(density[i]) * norm;
        double alpha = tone_gamma(t, alin);
        /* the palette at the mean colour coordinate, interpolated */
        double pos = (colour[i] < 0 ? 0 : colour[i] > 1 ? 1 : colour[i]) * 255.0;
        int i0 = (int)pos, i1 = i0 < 255 ? i0 + 1 : 255;
        double f = pos - i0, c[3];
        for (int ch = 0; ch < 3; ch++) {
            double rgb = t->palette[i0][ch] + (t->palette[i1][ch] - t->palette[i0][ch]) * f;
            c[ch] = t->vibrancy * rgb * alpha + (1 - t->vibrancy) * tone_gamma(t, rgb * alin);
        }
        double top = fmax(c[0], fmax(c[1], c[2]));
        if (top > 1) {
            if (t->highlight < 0) {
                for (int ch = 0; ch < 3; ch++) c[ch] = fmin(c[ch], 1.0);
            } else { /* keep the hue, and fade toward white as the pixel gets brighter */
                double s = 1 / top, w = 1 - pow(s, t->highlight);
                for (int ch = 0; ch < 3; ch++) c[ch] = c[ch] * s * (1 - w) + w;
            }
        }
        double a = alpha < 1 ? alpha : 1;
        R[i] = (float)c[0], G[i] = (float)c[1], B[i] = (float)c[2], A[i] = (float)a;
    }
}
