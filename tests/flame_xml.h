/*
 * Random flame xforms over chosen variations, for the flame's tests (test_flame, test_flame_vars):
 * coefficients, colours and weights from a fixed hash sequence, and every parameter of each
 * variation in the spirit of flam3-genome's ranges. Include after render.h.
 */
#ifndef FB_TESTS_FLAME_XML_H
#define FB_TESTS_FLAME_XML_H

#include <stdio.h>
#include <string.h>

/* the sequence */
static uint32_t g_h = 99;
static double uni(double lo, double hi)
{
    g_h = k_hash(g_h + 0x9e3779b9u);
    return lo + (hi - lo) * (g_h / 4294967296.0);
}

/* A parameter's random value, in the spirit of flam3-genome's ranges (flam3_random): counts and
 * powers small integers, lengths and sizes positive, the rest within [-1.5, 1.5] of 0 or its default. */
static double param_value(const char *name)
{
    static const char *const ints[] = {"julian_power",      "juliascope_power", "pie_slices", "ngon_sides",
                                       "cpow_power",        "wedge_count",      "blob_waves", "wedge_julia_power",
                                       "wedge_julia_count", "wedge_sph_count",  "auger_freq"};
    for (size_t k = 0; k < sizeof ints / sizeof *ints; k++)
        if (!strcmp(name, ints[k])) return (double)(int)uni(2, 7);
    static const char *const pos[] = {"cell_size",        "curve_xlength",      "curve_ylength",
                                      "julian_dist",      "juliascope_dist",    "wedge_julia_dist",
                                      "perspective_dist", "conic_eccentricity", "oscilloscope_separation",
                                      "super_shape_n1"};
    for (size_t k = 0; k < sizeof pos / sizeof *pos; k++)
        if (!strcmp(name, pos[k])) return uni(0.5, 2.5);
    if (!strcmp(name, "super_shape_rnd")) return uni(0, 1);
    return uni(-1.5, 1.5);
}

/* The parameters' names. A parameter belongs to the variation whose name and '_' is the longest
 * beginning of it (flam3's convention: wedge_julia_dist is wedge_julia's, not wedge's). */
static const char *const all_params[] = {
#define FB_FLAME_PARAM_NAME(e, name, def) name,
    FB_FLAME_PARAMS(FB_FLAME_PARAM_NAME)
#undef FB_FLAME_PARAM_NAME
};

static int param_owner(const char *par)
{
    int best = -1;
    size_t len = 0;
    for (int v = 0; v < (int)K_V_COUNT; v++) {
        const char *vn = fb_flame_variation_name(v);
        size_t n = strlen(vn);
        if (n > len && !strncmp(par, vn, n) && par[n] == '_') best = v, len = n;
    }
    return best;
}

/* Appends an xform with variations vars[0 .. n) (and their parameters) to buf. */
static void xform_xml(char *buf, size_t cap, const int *vars, int n, bool post)
{
    size_t at = strlen(buf);
    at += (size_t)snprintf(buf + at, cap - at, "<xform weight=\"1\" color=\"%.6f\" color_speed=\"%.6f\"", uni(0, 1),
                           uni(0, 1));
    at += (size_t)snprintf(buf + at, cap - at, " coefs=\"%.6f %.6f %.6f %.6f %.6f %.6f\"", uni(-1, 1), uni(-1, 1),
                           uni(-1, 1), uni(-1, 1), uni(-1, 1), uni(-1, 1));
    if (post)
        at += (size_t)snprintf(buf + at, cap - at, " post=\"%.6f %.6f %.6f %.6f %.6f %.6f\"", uni(-1, 1), uni(-1, 1),
                               uni(-1, 1), uni(-1, 1), uni(-0.5, 0.5), uni(-0.5, 0.5));
    for (int k = 0; k < n; k++) {
        const char *vn = fb_flame_variation_name(vars[k]);
        /* pre_blur a small blur; the others' weights around 1 (some read the weight as a length) */
        double w = vars[k] == (int)K_V_PRE_BLUR ? uni(0.02, 0.2) : uni(0.4, 1.2);
        at += (size_t)snprintf(buf + at, cap - at, " %s=\"%.6f\"", vn, w);
        for (size_t p = 0; p < sizeof all_params / sizeof *all_params; p++)
            if (param_owner(all_params[p]) == vars[k])
                at += (size_t)snprintf(buf + at, cap - at, " %s=\"%.6f\"", all_params[p], param_value(all_params[p]));
    }
    snprintf(buf + at, cap - at, "/>");
}

#endif
