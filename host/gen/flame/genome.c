/*
 * Reading .flame genomes (flam3 3.1.1's XML) with libxml2: every attribute flam3's parser reads for
 * a still image, its defaults, and its palette forms. What flam3 would drop with a warning (an
 * unknown variation or attribute) is refused here, so that a genome never renders silently different.
 */
#include "genome.h"
#include "scan.h"

#include <libxml/parser.h>
#include <libxml/tree.h>
#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const char *const var_names[99] = {
    "linear",        "sinusoidal",  "spherical",   "swirl",      "horseshoe",   "polar",      "handkerchief",
    "heart",         "disc",        "spiral",      "hyperbolic", "diamond",     "ex",         "julia",
    "bent",          "waves",       "fisheye",     "popcorn",    "exponential", "power",      "cosine",
    "rings",         "fan",         "blob",        "pdj",        "fan2",        "rings2",     "eyefish",
    "bubble",        "cylinder",    "perspective", "noise",      "julian",      "juliascope", "blur",
    "gaussian_blur", "radial_blur", "pie",         "ngon",       "curl",        "rectangles", "arch",
    "tangent",       "square",      "rays",        "blade",      "secant2",     "twintrian",  "cross",
    "disc2",         "super_shape", "flower",      "conic",      "parabola",    "bent2",      "bipolar",
    "boarders",      "butterfly",   "cell",        "cpow",       "curve",       "edisc",      "elliptic",
    "escher",        "foci",        "lazysusan",   "loonie",     "pre_blur",    "modulus",    "oscilloscope",
    "polar2",        "popcorn2",    "scry",        "separation", "split",       "splits",     "stripes",
    "wedge",         "wedge_julia", "wedge_sph",   "whorl",      "waves2",      "exp",        "log",
    "sin",           "cos",         "tan",         "sec",        "csc",         "cot",        "sinh",
    "cosh",          "tanh",        "sech",        "csch",       "coth",        "auger",      "flux",
    "mobius",
};

int fb_flame_variation_of(const char *name)
{
    for (int v = 0; v < 99; v++)
        if (!strcmp(name, var_names[v])) return v;
    return -1;
}

const char *fb_flame_variation_name(int v)
{
    return v >= 0 && v < 99 ? var_names[v] : "?";
}

/* The variations' parameters with flam3's defaults (initialize_xforms). */
static const struct {
    const char *name;
    double def;
} par_spec[FB_FP_COUNT] = {
#define FB_FLAME_PARAM_SPEC(e, name, def) {name, def},
    FB_FLAME_PARAMS(FB_FLAME_PARAM_SPEC)
#undef FB_FLAME_PARAM_SPEC
};

/* The other names flam3's parser gives some of them. */
static const struct {
    const char *alias;
    int par;
} par_alias[] = {
    {"oscope_separation", FB_FP_OSCOPE_SEPARATION},
    {"oscope_frequency", FB_FP_OSCOPE_FREQUENCY},
    {"oscope_amplitude", FB_FP_OSCOPE_AMPLITUDE},
    {"oscope_damping", FB_FP_OSCOPE_DAMPING},
    {"Re_A", FB_FP_MOBIUS_RE_A},
    {"Im_A", FB_FP_MOBIUS_IM_A},
    {"Re_B", FB_FP_MOBIUS_RE_B},
    {"Im_B", FB_FP_MOBIUS_IM_B},
    {"Re_C", FB_FP_MOBIUS_RE_C},
    {"Im_C", FB_FP_MOBIUS_IM_C},
    {"Re_D", FB_FP_MOBIUS_RE_D},
    {"Im_D", FB_FP_MOBIUS_IM_D},
};

/* The parameter named `name` (or an alias of it), or -1. */
static int param_of(const char *name)
{
    for (int k = 0; k < FB_FP_COUNT; k++)
        if (!strcmp(name, par_spec[k].name)) return k;
    for (size_t k = 0; k < sizeof par_alias / sizeof *par_alias; k++)
        if (!strcmp(name, par_alias[k].alias)) return par_alias[k].par;
    return -1;
}

static const char *const filter_shapes[14] = {"gaussian", "hermite",  "box",      "triangle", "bell",
                                              "bspline",  "mitchell", "blackman", "catrom",   "hanning",
                                              "hamming",  "lanczos3", "lanczos2", "quadratic"};

typedef struct reader {
    const char *what; /* the file */
    char where[160];  /* "flame 'x'" or "flame 'x', xform 2" */
} reader;

static fb_result bad(const reader *r, const char *fmt, const char *a, const char *b)
{
    char msg[512];
    snprintf(msg, sizeof msg, fmt, a, b);
    return fb_fail(FB_ERR_INPUT, "%s: %s: %s", r->what, r->where, msg);
}

/* Exactly `n` numbers separated by white space (flam3's sscanf with a trailing %1s check). */
static bool numbers(const char *s, int n, double *out)
{
    char *end;
    for (int i = 0; i < n; i++) {
        out[i] = strtod(s, &end);
        if (end == s || !isfinite(out[i])) return false;
        s = end;
    }
    while (*s == ' ' || *s == '\t' || *s == '\n' || *s == '\r') s++;
    return *s == 0;
}

static fb_result number(const reader *r, const char *att, const char *val, double *out)
{
    if (!numbers(val, 1, out)) return bad(r, "attribute %s: expected a number, found '%s'", att, val);
    return FB_OK;
}

static fb_result integer(const reader *r, const char *att, const char *val, int *out)
{
    char *end;
    long v = strtol(val, &end, 10);
    if (end == val || *end || v < -1000000000L || v > 1000000000L)
        return bad(r, "attribute %s: expected an integer, found '%s'", att, val);
    *out = (int)v;
    return FB_OK;
}

static void init_xform(fb_flame_xform *x, int index)
{
    memset(x, 0, sizeof *x);
    x->color_speed = 0.5;
    x->color = index & 1;
    x->opacity = 1.0;
    x->animate = 1.0;
    x->c[0][0] = x->c[1][1] = 1.0;
    x->post[0][0] = x->post[1][1] = 1.0;
    for (int p = 0; p < FB_FP_COUNT; p++) x->par[p] = par_spec[p].def;
    for (int j = 0; j < FB_FLAME_MAX_XFORMS; j++) x->chaos[j] = 1.0;
}

void fb_flame_xform_init(fb_flame_xform *x, int index)
{
    init_xform(x, index);
}

/* Hex colours: n of them, each "RRGGBB" (chan 3), "RRGGBBAA" (4) or "00RRGGBB" (-4), white space
 * between allowed (flam3_parse_hexformat_colors). */
static fb_result hex_colors(const reader *r, const char *s, int n, int chan, fb_flame_genome *g, bool *set)
{
    int digits = chan == 3 ? 6 : 8;
    for (int i = 0; i < n; i++) {
        while (*s == ' ' || *s == '\t' || *s == '\n' || *s == '\r') s++;
        unsigned v[4] = {0, 0, 0, 255};
        for (int d = 0; d < digits; d++)
            if (!((s[d] >= '0' && s[d] <= '9') || (s[d] >= 'a' && s[d] <= 'f') || (s[d] >= 'A' && s[d] <= 'F'))) {
                char k[16];
                snprintf(k, sizeof k, "%d", i);
                return bad(r, "palette: colour %s: expected %s hexadecimal digits", k, digits == 6 ? "6" : "8");
            }
        char buf[3] = {0, 0, 0};
        int off = chan == -4 ? 2 : 0, nc = chan == 4 ? 4 : 3;
        for (int c = 0; c < nc; c++) {
            buf[0] = s[off + 2 * c], buf[1] = s[off + 2 * c + 1];
            v[c] = (unsigned)strtoul(buf, NULL, 16);
        }
        s += digits;
        if (i < 256) {
            double a = v[3] / 255.0;
            /* flam3 does not premultiply hex colours (only <color>) */
            g->palette[i][0] = v[0] / 255.0, g->palette[i][1] = v[1] / 255.0, g->palette[i][2] = v[2] / 255.0;
            g->palette[i][3] = a;
            set[i] = true;
        }
    }
    while (*s == ' ' || *s == '\t' || *s == '\n' || *s == '\r') s++;
    if (*s) return bad(r, "palette: %s (more data than the %s colours)", "extra data after the colours", "given");
    return FB_OK;
}

/* flam3_interp_missing_colors: entries not given are interpolated between their neighbours, wrapping. */
static void fill_missing(fb_flame_genome *g, bool *set)
{
    int minix = -1, maxix = -1;
    for (int i = 0; i < 256; i++)
        if (set[i]) {
            if (minix < 0) minix = i;
            maxix = i;
        }
    if (minix < 0) return; /* no colours at all: flam3 leaves them black */
    int i = 0;
    while (i < 256) {
        if (set[i]) {
            i++;
            continue;
        }
        int str = i, intl = i - 1, colorli = intl, enr = i, intr = i + 1, colorri = intr;
        while (i < 256 && !set[i]) {
            enr = i;
            intr = i + 1;
            colorri = intr;
            i++;
        }
        if (intl == -1) intl = maxix - 256, colorli = maxix;
        if (intr == 256) intr = minix + 256, colorri = minix;
        for (int j = str; j <= enr; j++) {
            double f = (j - intl) / (double)(intr - intl);
            for (int k = 0; k < 4; k++)
                g->palette[j][k] = g->palette[colorli][k] * (1.0 - f) + g->palette[colorri][k] * f;
            set[j] = true;
        }
        i = colorri + 1;
    }
}

static void rgb2hsv(const double *rgb, double *hsv)
{
    double rd = rgb[0], gd = rgb[1], bd = rgb[2];
    double mx = fmax(rd, fmax(gd, bd)), mn = fmin(rd, fmin(gd, bd)), del = mx - mn, h = 0;
    double s = mx != 0.0 ? del / mx : 0.0;
    if (s != 0.0) {
        double rc = (mx - rd) / del, gc = (mx - gd) / del, bc = (mx - bd) / del;
        if (rd == mx)
            h = bc - gc;
        else if (gd == mx)
            h = 2 + rc - bc;
        else
            h = 4 + gc - rc;
        if (h < 0) h += 6;
    }
    hsv[0] = h, hsv[1] = s, hsv[2] = mx;
}

void fb_flame_hsv2rgb(const double *hsv, double *rgb);
void fb_flame_hsv2rgb(const double *hsv, double *rgb)
{
    double h = hsv[0], s = hsv[1], v = hsv[2];
    while (h >= 6.0) h -= 6.0;
    while (h < 0.0) h += 6.0;
    int j = (int)floor(h);
    double f = h - j, p = v * (1 - s), q = v * (1 - s * f), t = v * (1 - s * (1 - f));
    double r3[6][3] = {{v, t, p}, {q, v, p}, {p, v, t}, {p, q, v}, {t, p, v}, {v, p, q}};
    if (j < 0 || j > 5) j = 0;
    rgb[0] = r3[j][0], rgb[1] = r3[j][1], rgb[2] = r3[j][2];
}

void fb_flame_rgb2hsv(const double *rgb, double *hsv);
void fb_flame_rgb2hsv(const double *rgb, double *hsv)
{
    rgb2hsv(rgb, hsv);
}

/* palette="N": entry N of flam3's palette library, its hue rotated by `hue` turns (flam3_get_palette). */
static fb_result library_palette(const reader *r, const char *palettes, int number, double hue, fb_flame_genome *g)
{
    char *text = NULL;
    size_t len = 0;
    if (fb_flame_slurp(palettes, &text, &len))
        return bad(r, "palette=\"%s\": cannot read flam3's palette library %s", "N", palettes);
    xmlDocPtr doc = NULL;
    fb_result rc = fb_flame_parse(text, len, palettes, &doc);
    free(text);
    if (rc) return rc;
    rc = FB_ERR_INPUT;
    for (xmlNodePtr n = xmlDocGetRootElement(doc)->children; n; n = n->next) {
        if (n->type != XML_ELEMENT_NODE || xmlStrcmp(n->name, (const xmlChar *)"palette")) continue;
        xmlChar *num = xmlGetProp(n, (const xmlChar *)"number"), *data = xmlGetProp(n, (const xmlChar *)"data");
        bool match = num && atoi((const char *)num) == number && data;
        if (match) {
            bool set[256] = {0};
            rc = hex_colors(r, (const char *)data, 256, -4, g, set);
            for (int i = 0; i < 256 && !rc; i++) {
                double hsv[3];
                rgb2hsv(g->palette[i], hsv);
                hsv[0] += hue * 6.0;
                fb_flame_hsv2rgb(hsv, g->palette[i]);
                g->palette[i][3] = 1.0;
            }
        }
        xmlFree(num);
        xmlFree(data);
        if (match) break;
    }
    xmlFreeDoc(doc);
    if (rc == FB_ERR_INPUT) {
        char k[16];
        snprintf(k, sizeof k, "%d", number);
        return bad(r, "palette=\"%s\": no such palette in %s", k, palettes);
    }
    return rc;
}

static fb_result parse_xform(reader *r, xmlNodePtr node, fb_flame_xform *x, bool final, int stdindex)
{
    for (xmlAttrPtr a = node->properties; a; a = a->next) {
        const char *name = (const char *)a->name;
        xmlChar *vx = xmlGetProp(node, a->name);
        const char *val = vx ? (const char *)vx : "";
        fb_result rc = FB_OK;
        double d;
        int v = fb_flame_variation_of(name);
        if (!strcmp(name, "weight")) {
            rc = number(r, name, val, &x->weight);
            if (!rc && x->weight < 0) rc = bad(r, "weight %s: must be non-negative%s", val, "");
            if (!rc && final && x->weight != 0) rc = bad(r, "a final xform has no weight (found %s)%s", val, "");
        } else if (!strcmp(name, "color")) {
            double two[2];
            if (numbers(val, 2, two))
                x->color = two[0];
            else
                rc = number(r, name, val, &x->color);
        } else if (!strcmp(name, "color_speed")) {
            rc = number(r, name, val, &x->color_speed);
        } else if (!strcmp(name, "symmetry")) {
            /* the legacy form of color_speed (flam3's parser) */
            if (!(rc = number(r, name, val, &d))) x->color_speed = (1.0 - d) / 2.0, x->animate = d > 0 ? 0 : 1;
        } else if (!strcmp(name, "animate")) {
            rc = number(r, name, val, &x->animate);
        } else if (!strcmp(name, "name")) {
            /* a label (Apophysis) */
        } else if (!strcmp(name, "motion_frequency") || !strcmp(name, "motion_function")) {
            rc = bad(r, "attribute %s: motion is for animations, not supported%s", name, "");
        } else if (!strcmp(name, "opacity")) {
            rc = number(r, name, val, &x->opacity);
        } else if (!strcmp(name, "plotmode")) {
            if (!strcmp(val, "off")) x->opacity = 0.0;
        } else if (!strcmp(name, "coefs") || !strcmp(name, "post")) {
            double m[6];
            if (!numbers(val, 6, m))
                rc = bad(r, "attribute %s: expected 6 numbers, found '%s'", name, val);
            else
                for (int k = 0; k < 6; k++) (name[0] == 'c' ? x->c : x->post)[k / 2][k % 2] = m[k];
        } else if (!strcmp(name, "chaos")) {
            if (final) {
                rc = bad(r, "attribute %s: a final xform has no xaos%s", name, "");
            } else {
                const char *s = val;
                char *end;
                for (int j = 0; *s; j++) {
                    double c = strtod(s, &end);
                    if (end == s) {
                        while (*s == ' ' || *s == '\t' || *s == '\n') s++;
                        if (*s) rc = bad(r, "attribute chaos: expected numbers, found '%s'%s", val, "");
                        break;
                    }
                    if (c < 0) {
                        rc = bad(r, "attribute chaos: entries must be non-negative, found '%s'%s", val, "");
                        break;
                    }
                    if (j < FB_FLAME_MAX_XFORMS) x->chaos[j] = c;
                    s = end;
                }
            }
        } else if (!strcmp(name, "var1") || !strcmp(name, "var")) {
            rc = bad(r, "attribute %s: the pre-2.0 variation syntax is not supported%s", name, "");
        } else if (v >= 0) {
            rc = number(r, name, val, &x->var[v]);
        } else if (!strcmp(name, "amw_amp")) {
            rc = number(r, name, val, &d); /* flam3 reads it; no variation of 3.1.1 uses it */
        } else {
            int p = param_of(name);
            if (p >= 0)
                rc = number(r, name, val, &x->par[p]);
            else if (!(numbers(val, 1, &d) && d == 0.0))
                rc = bad(r,
                         "unknown variation or attribute '%s' (flam3 3.1.1 would ignore it and render the "
                         "flame differently)%s",
                         name, "");
        }
        xmlFree(vx);
        if (rc) return rc;
    }
    (void)stdindex;
    if (x->par[FB_FP_SUPER_SHAPE_RND] < 0) x->par[FB_FP_SUPER_SHAPE_RND] = 0;
    if (x->par[FB_FP_SUPER_SHAPE_RND] > 1) x->par[FB_FP_SUPER_SHAPE_RND] = 1;
    return FB_OK;
}

static double round6(double x)
{
    x *= 1e6;
    if (x < 0) x -= 1.0;
    return 1e-6 * (int)(x + 0.5);
}

static double det2(const fb_flame_xform *x)
{
    return x->c[0][0] * x->c[1][1] - x->c[0][1] * x->c[1][0];
}

/* <symmetry kind="K"> (flam3_add_symmetry): K >= 2 adds K - 1 rotations by 2 pi / K, K <= -1 a
 * reflection x -> -x and |K| - 1 rotations; weight 1, linear, colour speed and animate 0 each, in
 * flam3's sorted order (a still's image does not depend on it, keyframes' matched xforms do; xaos
 * would name them: xaos with symmetry is refused). */

static fb_result add_symmetry(const reader *r, fb_flame_genome *g, int sym, int *nstd)
{
    if (sym == 0) return bad(r, "<symmetry kind=\"0\">: a random symmetry is not reproducible%s%s", "", "");
    if (sym == 1) return FB_OK;
    int n = sym < 0 ? -sym : sym - 1;
    if (sym < -FB_FLAME_MAX_XFORMS || *nstd + n > FB_FLAME_MAX_XFORMS)
        return bad(r, "<symmetry>: more than %s xforms%s", "24", "");
    int start = *nstd;
    if (sym < 0) {
        fb_flame_xform *x = &g->xf[(*nstd)++];
        init_xform(x, *nstd - 1);
        x->weight = 1, x->color_speed = 0, x->animate = 0, x->var[0] = 1, x->color = 1;
        x->c[0][0] = -1, x->c[1][1] = 1;
        sym = -sym;
    }
    double a = 2 * M_PI / sym;
    for (int k = 1; k < sym; k++) {
        fb_flame_xform *x = &g->xf[(*nstd)++];
        init_xform(x, *nstd - 1);
        x->weight = 1, x->color_speed = 0, x->animate = 0, x->var[0] = 1;
        x->color = sym < 3 ? 0.0 : (k - 1.0) / (sym - 2.0);
        x->c[0][0] = round6(cos(k * a));
        x->c[0][1] = round6(sin(k * a));
        x->c[1][0] = round6(-x->c[0][1]);
        x->c[1][1] = x->c[0][0];
    }
    /* flam3 sorts the added xforms (qsort with compare_xforms, glibc's merge sort: stable). Their
     * colour speeds are all 0, so the key is the determinant of the linear part: the reflection's -1
     * first, then the rotations, whose round6 coefficients put their determinants a little off 1.
     * The order is what keyframes' xforms are matched by. */
    for (int i = start + 1; i < *nstd; i++) {
        fb_flame_xform x = g->xf[i];
        double d = det2(&x);
        int j = i;
        for (; j > start && det2(&g->xf[j - 1]) > d; j--) g->xf[j] = g->xf[j - 1];
        g->xf[j] = x;
    }
    g->symmetry = true;
    return FB_OK;
}

/* Which of `names` (NULL-terminated) val is, or -1 after an error naming the attribute. */
static int choice(const reader *r, const char *att, const char *val, const char *const *names, fb_result *rc)
{
    for (int k = 0; names[k]; k++)
        if (!strcmp(val, names[k])) return k;
    char want[160] = "";
    for (int k = 0; names[k]; k++)
        snprintf(want + strlen(want), sizeof want - strlen(want), "%s%s", k ? ", " : "", names[k]);
    char msg[256];
    snprintf(msg, sizeof msg, "attribute %s: expected %s, found '%%s'%%s", att, want);
    *rc = bad(r, msg, val, "");
    return -1;
}

/* The attributes of <flame> that flam3-animate reads: the keyframe's time and how it moves. */
static const struct {
    const char *name;
    size_t at;                /* offsetof(fb_flame_genome, ...) */
    const char *const *names; /* a choice (stored as an int-sized enum), or NULL: a number */
    double lo, hi;            /* a number's range */
} anim_attrs[] = {
    {"time", offsetof(fb_flame_genome, time), NULL, -1e300, 1e300},
    {"interpolation", offsetof(fb_flame_genome, interpolation), (const char *const[]){"linear", "smooth", NULL}, 0, 0},
    {"interpolation_type", offsetof(fb_flame_genome, interpolation_type),
     (const char *const[]){"log", "linear", "old", "older", NULL}, 0, 0},
    {"interpolation_space", offsetof(fb_flame_genome, interpolation_type),
     (const char *const[]){"log", "linear", "old", "older", NULL}, 0, 0},
    {"palette_interpolation", offsetof(fb_flame_genome, palette_interpolation),
     (const char *const[]){"hsv_circular", "hsv", "sweep", "rgb", NULL}, 0, 0},
    {"hsv_rgb_palette_blend", offsetof(fb_flame_genome, hsv_rgb_palette_blend), NULL, -1e300, 1e300},
    {"temporal_filter_type", offsetof(fb_flame_genome, temporal_filter_type),
     (const char *const[]){"box", "gaussian", "exp", NULL}, 0, 0},
    {"temporal_filter_width", offsetof(fb_flame_genome, temporal_filter_width), NULL, 0, 1e300},
    {"temporal_filter_exp", offsetof(fb_flame_genome, temporal_filter_exp), NULL, -1e300, 1e300},
};

_Static_assert(sizeof(fb_flame_interp) == sizeof(int) && sizeof(fb_flame_itype) == sizeof(int) &&
                   sizeof(fb_flame_palint) == sizeof(int) && sizeof(fb_flame_tfilter) == sizeof(int),
               "anim_attrs stores the choices as int");

static fb_result animation_attr(const reader *r, const char *name, const char *val, fb_flame_genome *g)
{
    fb_result rc = FB_OK;
    if (!strcmp(name, "temporal_samples")) {
        rc = integer(r, name, val, &g->temporal_samples);
        if (!rc && (g->temporal_samples < 1 || g->temporal_samples > 100000))
            rc = bad(r, "attribute temporal_samples: expected 1 to 100000, found '%s'%s", val, "");
        return rc;
    }
    for (size_t a = 0; a < sizeof anim_attrs / sizeof anim_attrs[0]; a++) {
        if (strcmp(name, anim_attrs[a].name)) continue;
        char *field = (char *)g + anim_attrs[a].at;
        if (anim_attrs[a].names) {
            int k = choice(r, name, val, anim_attrs[a].names, &rc);
            if (k >= 0) memcpy(field, &k, sizeof k);
            return rc;
        }
        double d;
        if ((rc = number(r, name, val, &d))) return rc;
        if (!isfinite(d) || d < anim_attrs[a].lo || d > anim_attrs[a].hi)
            return bad(r, "attribute %s: out of range, found '%s'", name, val);
        memcpy(field, &d, sizeof d);
        if (!strcmp(name, "time")) g->has_time = true;
        return FB_OK;
    }
    /* the rest (version, url, nick, notes, contrast...) are credits or not read by flam3's renderer */
    return FB_OK;
}

/* One attribute of <flame>: the camera, the filters, density estimation and the tone map. */
static fb_result flame_attr(reader *r, const char *name, const char *val, fb_flame_genome *g, int *palette_number,
                            double *hue)
{
    fb_result rc = FB_OK;
    double v2[3];
    if (!strcmp(name, "name")) {
        snprintf(g->name, sizeof g->name, "%s", val);
    } else if (!strcmp(name, "size")) {
        if (!numbers(val, 2, v2) || v2[0] < 1 || v2[1] < 1 || v2[0] > 65536 || v2[1] > 65536 || v2[0] != floor(v2[0]) ||
            v2[1] != floor(v2[1]))
            rc = bad(r, "attribute size: expected two positive integers, found '%s'%s", val, "");
        else
            g->width = (int)v2[0], g->height = (int)v2[1];
    } else if (!strcmp(name, "center")) {
        if (!numbers(val, 2, g->center)) rc = bad(r, "attribute center: expected two numbers, found '%s'%s", val, "");
    } else if (!strcmp(name, "background")) {
        if (!numbers(val, 3, g->background))
            rc = bad(r, "attribute background: expected three numbers, found '%s'%s", val, "");
    } else if (!strcmp(name, "scale")) {
        rc = number(r, name, val, &g->scale);
    } else if (!strcmp(name, "zoom")) {
        rc = number(r, name, val, &g->zoom);
    } else if (!strcmp(name, "rotate")) {
        rc = number(r, name, val, &g->rotate);
    } else if (!strcmp(name, "supersample") || !strcmp(name, "oversample")) {
        rc = integer(r, name, val, &g->supersample);
        if (!rc && (g->supersample < 1 || g->supersample > 8))
            rc = bad(r, "attribute %s: expected 1 to 8, found '%s'", name, val);
    } else if (!strcmp(name, "filter")) {
        rc = number(r, name, val, &g->filter);
    } else if (!strcmp(name, "filter_shape")) {
        g->filter_shape = -1;
        for (int k = 0; k < 14; k++)
            if (!strcmp(val, filter_shapes[k])) g->filter_shape = k;
        if (g->filter_shape < 0) rc = bad(r, "attribute filter_shape: unknown shape '%s'%s", val, "");
    } else if (!strcmp(name, "quality")) {
        rc = number(r, name, val, &g->quality);
        if (!rc && !(g->quality > 0)) rc = bad(r, "attribute quality: must be positive, found '%s'%s", val, "");
    } else if (!strcmp(name, "passes")) {
        int p;
        if (!(rc = integer(r, name, val, &p)) && p != 1)
            rc = bad(r, "attribute passes: only 1 is supported, found '%s'%s", val, "");
    } else if (!strcmp(name, "brightness")) {
        rc = number(r, name, val, &g->brightness);
    } else if (!strcmp(name, "gamma")) {
        rc = number(r, name, val, &g->gamma);
        if (!rc && !(g->gamma > 0)) rc = bad(r, "attribute gamma: must be positive, found '%s'%s", val, "");
    } else if (!strcmp(name, "highlight_power")) {
        rc = number(r, name, val, &g->highlight_power);
    } else if (!strcmp(name, "vibrancy")) {
        rc = number(r, name, val, &g->vibrancy);
    } else if (!strcmp(name, "gamma_threshold")) {
        rc = number(r, name, val, &g->gamma_threshold);
    } else if (!strcmp(name, "estimator_radius")) {
        rc = number(r, name, val, &g->estimator);
        if (!rc && (g->estimator < 0 || g->estimator > 100))
            rc = bad(r, "attribute estimator_radius: expected 0 to 100, found '%s'%s", val, "");
    } else if (!strcmp(name, "estimator_minimum")) {
        rc = number(r, name, val, &g->estimator_minimum);
        if (!rc && g->estimator_minimum < 0)
            rc = bad(r, "attribute estimator_minimum: must be >= 0, found '%s'%s", val, "");
    } else if (!strcmp(name, "estimator_curve")) {
        rc = number(r, name, val, &g->estimator_curve);
        if (!rc && !(g->estimator_curve > 0))
            rc = bad(r, "attribute estimator_curve: must be positive, found '%s'%s", val, "");
    } else if (!strcmp(name, "palette_mode")) {
        if (!strcmp(val, "linear"))
            g->palette_mode = FB_FLAME_PALETTE_LINEAR;
        else if (strcmp(val, "step"))
            rc = bad(r, "attribute palette_mode: expected step or linear, found '%s'%s", val, "");
    } else if (!strcmp(name, "palette")) {
        rc = integer(r, name, val, palette_number);
    } else if (!strcmp(name, "hue")) {
        rc = number(r, name, val, hue);
        *hue = fmod(*hue, 1.0);
    } else if (!strcmp(name, "soloxform")) {
        rc = bad(r, "attribute soloxform: an editing aid, not supported%s%s", "", "");
    } else {
        rc = animation_attr(r, name, val, g);
    }
    return rc;
}

/* A <color index rgb|rgba [a]> element: one palette entry, alpha premultiplied. */
static fb_result color_elem(reader *r, xmlNodePtr c, fb_flame_genome *g, bool set[256])
{
    fb_result rc = FB_OK;
    double idx = -1, rgb[4] = {0, 0, 0, 255};
    for (xmlAttrPtr a = c->properties; a && !rc; a = a->next) {
        xmlChar *vx = xmlGetProp(c, a->name);
        const char *an = (const char *)a->name, *val = vx ? (const char *)vx : "";
        if (!strcmp(an, "index")) {
            if (!numbers(val, 1, &idx)) rc = bad(r, "<color index>: expected an integer, found '%s'%s", val, "");
        } else if (!strcmp(an, "rgb")) {
            if (!numbers(val, 3, rgb)) rc = bad(r, "<color rgb>: expected three numbers, found '%s'%s", val, "");
        } else if (!strcmp(an, "rgba")) {
            if (!numbers(val, 4, rgb)) rc = bad(r, "<color rgba>: expected four numbers, found '%s'%s", val, "");
        } else if (!strcmp(an, "a")) {
            if (!numbers(val, 1, &rgb[3])) rc = bad(r, "<color a>: expected a number, found '%s'%s", val, "");
        } else {
            rc = bad(r, "<color>: unknown attribute '%s'%s", an, "");
        }
        xmlFree(vx);
    }
    if (!rc && (idx < 0 || idx > 255 || idx != floor(idx)))
        rc = bad(r, "<color>: a missing or bad index (0 to 255)%s%s", "", "");
    if (!rc) {
        int i = (int)idx;
        double a = rgb[3] / 255.0;
        g->palette[i][3] = a;
        for (int k = 0; k < 3; k++) g->palette[i][k] = a * rgb[k] / 255.0;
        set[i] = true;
    }
    snprintf(g->form, sizeof g->form, "<color> elements");
    return rc;
}

/* A <colors data> or <palette count format> element: hexadecimal colours. */
static fb_result colors_elem(reader *r, xmlNodePtr c, const char *en, fb_flame_genome *g, bool set[256])
{
    fb_result rc = FB_OK;
    bool pal = en[0] == 'p';
    int count = 0, chan = pal ? 0 : -4;
    xmlChar *data = NULL;
    for (xmlAttrPtr a = c->properties; a && !rc; a = a->next) {
        xmlChar *vx = xmlGetProp(c, a->name);
        const char *an = (const char *)a->name, *val = vx ? (const char *)vx : "";
        if (!strcmp(an, "count")) {
            rc = integer(r, "count", val, &count);
            if (!rc && (count < 1 || count > 256)) rc = bad(r, "<%s count>: expected 1 to 256%s", en, "");
        } else if (pal && !strcmp(an, "format")) {
            chan = !strcmp(val, "RGB") ? 3 : !strcmp(val, "RGBA") ? 4 : 0;
            if (!chan) rc = bad(r, "<palette format>: expected RGB or RGBA, found '%s'%s", val, "");
        } else if (!pal && !strcmp(an, "data")) {
            data = xmlStrdup(vx);
        } else if (pal && (!strcmp(an, "index0") || !strcmp(an, "index1") || !strcmp(an, "hue0") ||
                           !strcmp(an, "hue1") || !strcmp(an, "blend"))) {
            rc = bad(r, "<palette %s>: the blend of two library palettes is not supported%s", an, "");
        } else {
            rc = bad(r, "<%s>: unknown attribute '%s'", en, an);
        }
        xmlFree(vx);
    }
    if (!rc && pal) {
        if (!chan) rc = bad(r, "<palette>: no format attribute%s%s", "", "");
        data = xmlNodeGetContent(c);
    }
    if (!rc && !data) rc = bad(r, "<%s>: no colour data%s", en, "");
    if (!rc && !count) rc = bad(r, "<%s>: no count%s", en, "");
    if (!rc) rc = hex_colors(r, (const char *)data, count, chan, g, set);
    xmlFree(data);
    snprintf(g->form, sizeof g->form, pal ? "a <palette> element" : "a <colors> element");
    return rc;
}

static fb_result parse_flame(reader *r, xmlNodePtr node, const char *palettes, fb_flame_genome *g)
{
    memset(g, 0, sizeof *g);
    g->width = g->height = 100;
    g->scale = 50;
    g->supersample = 1;
    g->filter = 0.5;
    g->quality = 1;
    g->brightness = 4, g->gamma = 4, g->vibrancy = 1, g->highlight_power = -1, g->gamma_threshold = 0.01;
    g->estimator = 9, g->estimator_minimum = 0, g->estimator_curve = 0.4;
    g->temporal_samples = 1000, g->temporal_filter_width = 1.0;
    int palette_number = -1;
    double hue = 0;
    fb_result rc = FB_OK;
    for (xmlAttrPtr a = node->properties; a && !rc; a = a->next) {
        const char *name = (const char *)a->name;
        xmlChar *vx = xmlGetProp(node, a->name);
        const char *val = vx ? (const char *)vx : "";
        rc = flame_attr(r, name, val, g, &palette_number, &hue);
        xmlFree(vx);
    }
    if (rc) return rc;
    bool set[256] = {0};
    int nstd = 0;
    for (xmlNodePtr c = node->children; c && !rc; c = c->next) {
        if (c->type != XML_ELEMENT_NODE) continue;
        const char *en = (const char *)c->name;
        if (!strcmp(en, "xform") || !strcmp(en, "finalxform")) {
            bool final = en[0] == 'f';
            if (final && g->has_final) return bad(r, "more than one %s%s", "<finalxform>", "");
            if (!final && nstd == FB_FLAME_MAX_XFORMS) return bad(r, "more than %s xforms%s", "24", "");
            int at = final ? FB_FLAME_MAX_XFORMS : nstd;
            init_xform(&g->xf[at], nstd);
            snprintf(r->where + strlen(r->where), sizeof r->where - strlen(r->where),
                     final ? ", finalxform" : ", xform %d", nstd);
            rc = parse_xform(r, c, &g->xf[at], final, nstd);
            *strrchr(r->where, ',') = 0;
            if (final)
                g->has_final = true;
            else
                nstd++;
        } else if (!strcmp(en, "color")) {
            rc = color_elem(r, c, g, set);
        } else if (!strcmp(en, "colors") || !strcmp(en, "palette")) {
            rc = colors_elem(r, c, en, g, set);
        } else if (!strcmp(en, "symmetry")) {
            xmlChar *kx = xmlGetProp(c, (const xmlChar *)"kind");
            int kind = 0;
            rc = kx ? integer(r, "symmetry kind", (const char *)kx, &kind) : bad(r, "<symmetry>: no kind%s%s", "", "");
            xmlFree(kx);
            if (!rc) rc = add_symmetry(r, g, kind, &nstd);
        }
        /* <edit> is history */
    }
    if (rc) return rc;
    if (!nstd) return bad(r, "no <xform>%s%s", "", "");
    g->nxforms = nstd;
    double total = 0;
    for (int i = 0; i < nstd; i++) total += g->xf[i].weight;
    if (!(total > 0)) return bad(r, "the xforms' weights add up to zero%s%s", "", "");
    if (g->has_final) g->xf[nstd] = g->xf[FB_FLAME_MAX_XFORMS];
    for (int i = 0; i < nstd; i++)
        for (int j = 0; j < nstd; j++)
            if (fabs(g->xf[i].chaos[j] - 1.0) > 1e-10) g->chaos = true;
    if (g->chaos && g->symmetry) return bad(r, "xaos together with <symmetry> is not supported%s%s", "", "");
    for (int i = 0; g->chaos && i < nstd; i++) {
        double s = 0;
        for (int j = 0; j < nstd; j++) s += g->xf[j].weight * g->xf[i].chaos[j];
        if (!(s > 0)) {
            char k[16];
            snprintf(k, sizeof k, "%d", i);
            return bad(r, "xform %s: its xaos row leaves no xform to go to%s", k, "");
        }
    }
    if (palette_number >= 0) {
        rc = library_palette(r, palettes, palette_number, hue, g);
        snprintf(g->form, sizeof g->form, "palette=\"%d\"", palette_number);
    } else {
        fill_missing(g, set);
    }
    if (!rc && !g->form[0]) rc = bad(r, "no palette (<color>, <colors>, <palette> or palette=\"N\")%s%s", "", "");
    return rc;
}

fb_result fb_flame_slurp(const char *path, char **text, size_t *len)
{
    return fb_flame_load(path, text, len);
}

static void find_flames(xmlNodePtr n, xmlNodePtr *out, int *count, int max)
{
    for (; n; n = n->next) {
        if (n->type != XML_ELEMENT_NODE) continue;
        if (!xmlStrcmp(n->name, (const xmlChar *)"flame")) {
            if (*count < max) out[*count] = n;
            (*count)++;
        } else {
            find_flames(n->children, out, count, max);
        }
    }
}

enum { MAXF = 4096 };

/* The parsed document of the XML text and its <flame> elements (*count of them; more than MAXF:
 * the first MAXF listed, *count says how many there are). */
static fb_result flames_of(const char *xml, size_t len, const char *what, xmlDocPtr *doc, xmlNodePtr **flames,
                           int *count)
{
    static _Thread_local xmlNodePtr list[MAXF];
    fb_result rc = fb_flame_parse(xml, len, what, doc);
    if (rc) return rc;
    *count = 0;
    find_flames(xmlDocGetRootElement(*doc), list, count, MAXF);
    *flames = list;
    return FB_OK;
}

fb_result fb_flame_read(const char *xml, size_t len, const char *what, const char *pick, const char *palettes,
                        fb_flame_genome *out, char **element)
{
    xmlDocPtr doc = NULL;
    xmlNodePtr *flames;
    int count;
    fb_result prc = flames_of(xml, len, what, &doc, &flames, &count);
    if (prc) return prc;
    if (count > MAXF) count = MAXF;
    int at = -1;
    if (!pick) {
        at = count ? 0 : -1;
    } else {
        for (int i = 0; i < count && at < 0; i++) {
            xmlChar *nm = xmlGetProp(flames[i], (const xmlChar *)"name");
            if (nm && !strcmp((const char *)nm, pick)) at = i;
            xmlFree(nm);
        }
        char *end;
        long k = strtol(pick, &end, 10);
        if (at < 0 && *pick && !*end && k >= 0 && k < count) at = (int)k;
    }
    fb_result rc = FB_OK;
    if (at < 0) {
        rc = count ? fb_fail(FB_ERR_INPUT, "%s: no <flame> named or numbered '%s' (it has %d)", what, pick, count)
                   : fb_fail(FB_ERR_INPUT, "%s: no <flame> element", what);
    } else {
        reader r = {.what = what};
        xmlChar *nm = xmlGetProp(flames[at], (const xmlChar *)"name");
        if (nm)
            snprintf(r.where, sizeof r.where, "flame '%s'", (const char *)nm);
        else
            snprintf(r.where, sizeof r.where, "flame %d", at);
        xmlFree(nm);
        rc = parse_flame(&r, flames[at], palettes, out);
        if (!rc && element) {
            xmlBufferPtr b = xmlBufferCreate();
            if (!b || xmlNodeDump(b, doc, flames[at], 0, 0) < 0) {
                rc = fb_fail(FB_ERR_NOMEM, "out of memory");
            } else {
                *element = strdup((const char *)xmlBufferContent(b));
                if (!*element) rc = fb_fail(FB_ERR_NOMEM, "out of memory");
            }
            xmlBufferFree(b);
        }
    }
    xmlFreeDoc(doc);
    return rc;
}

/* flam3_parse_xml2's fixes to a file of keyframes: no smooth interpolation on the first or the last
 * segment, and each rotate within 180 degrees of the one before (but for old and older). */
static void fix_keys(fb_flame_genome *k, int n)
{
    if (n >= 1 && k[0].interpolation == FB_FLAME_INTERP_SMOOTH) k[0].interpolation = FB_FLAME_INTERP_LINEAR;
    if (n >= 2 && k[n - 2].interpolation == FB_FLAME_INTERP_SMOOTH) k[n - 2].interpolation = FB_FLAME_INTERP_LINEAR;
    for (int i = 1; i < n; i++) {
        if (k[i - 1].interpolation_type == FB_FLAME_ITYPE_OLD || k[i - 1].interpolation_type == FB_FLAME_ITYPE_OLDER)
            continue;
        while (k[i].rotate < k[i - 1].rotate - 180) k[i].rotate += 360;
        while (k[i].rotate > k[i - 1].rotate + 180) k[i].rotate -= 360;
    }
}

fb_result fb_flame_read_keys(const char *xml, size_t len, const char *what, const char *palettes, fb_flame_genome **out,
                             int *n)
{
    xmlDocPtr doc = NULL;
    xmlNodePtr *flames;
    int count;
    fb_result rc = flames_of(xml, len, what, &doc, &flames, &count);
    if (rc) return rc;
    fb_flame_genome *k = NULL;
    if (count > MAXF)
        rc = fb_fail(FB_ERR_INPUT, "%s: more than %d <flame> keyframes", what, MAXF);
    else if (!count)
        rc = fb_fail(FB_ERR_INPUT, "%s: no <flame> element", what);
    else if (!(k = calloc((size_t)count, sizeof *k)))
        rc = fb_fail(FB_ERR_NOMEM, "out of memory for %d keyframes", count);
    for (int i = 0; i < count && !rc; i++) {
        reader r = {.what = what};
        xmlChar *nm = xmlGetProp(flames[i], (const xmlChar *)"name");
        if (nm)
            snprintf(r.where, sizeof r.where, "flame '%s' (keyframe %d)", (const char *)nm, i);
        else
            snprintf(r.where, sizeof r.where, "keyframe %d", i);
        xmlFree(nm);
        rc = parse_flame(&r, flames[i], palettes, &k[i]);
        char t[2][32];
        snprintf(t[0], sizeof t[0], "%.17g", k[i].time);
        snprintf(t[1], sizeof t[1], "%.17g", i ? k[i - 1].time : 0.0);
        if (!rc && !isfinite(k[i].time)) rc = bad(&r, "attribute time: expected a finite number, found %s%s", t[0], "");
        if (!rc && i > 0 && !(k[i].time > k[i - 1].time))
            rc = bad(&r, "keyframes must be in increasing time: time %s follows %s", t[0], t[1]);
        if (!rc && i > 0 && (k[i].width != k[0].width || k[i].height != k[0].height)) {
            /* flam3-animate renders every frame at the first keyframe's size */
            k[i].width = k[0].width, k[i].height = k[0].height;
        }
    }
    xmlFreeDoc(doc);
    if (rc) {
        free(k);
        return rc;
    }
    fix_keys(k, count);
    *out = k, *n = count;
    return FB_OK;
}
