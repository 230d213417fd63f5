/*
 * Scene parsing and validation (jansson), driven by one schema table per generator.
 */
#include "scene.h"

#include "textin.h"

#include "palette.h"

#include "../kernels/noise.h"

#include <jansson.h>

#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <ctype.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

typedef enum ktype {
    T_INT,
    T_NUM,
    T_BOOL,
    T_ENUM,
    T_NAME,
    T_VEC2,
    T_SIZE,
    T_LAYERS,
    T_TYPE,
    T_NUMLIST,
    T_STOPS,
    T_STRING,   /* any non-empty string (a file path, an entry name) */
    T_OUTPUT,   /* a file this layer writes besides the EXR: never taken from a stored scene (--from) */
    T_MAPS,     /* IFS maps: [[a, b, c, d, e, f(, p)], ...] */
    T_BOUNDS,   /* "auto" or [xmin, xmax, ymin, ymax] */
    T_FRACS,    /* 1..64 numbers in [lo, hi] */
    T_NAMES,    /* 1..32 distinct names from `enums` (flag: a comma list) */
    T_IFSREF,   /* a preset name or a map list */
    T_POINTS,   /* a file path, or an inline list [[x, y, z], ...] */
    T_RULES,    /* L-system productions: ["X=successor", "X(p)=successor", ...] (flag: --rule, repeatable) */
    T_REF,      /* another layer's channel "layer.channel" (or "layer": its Y), or a number */
    T_REFS,     /* 1..8 of T_REF */
    T_CPOINTS,  /* a file, or [[x, y], ...] integer pixels */
    T_CREGIONS, /* a file, or [[x, y, "T" or "H", value], ...] */
} ktype;

typedef struct keyspec {
    const char *key;
    ktype type;
    double lo, hi;
    bool lo_open;      /* lo < x rather than lo <= x */
    const char *enums; /* "a|b|c" for T_ENUM */
    const char *def;   /* the default as JSON text; NULL: none (optional key, or required) */
    const char *help;
    int count; /* T_NUMLIST: how many numbers */
} keyspec;

static const keyspec scene_keys[] = {
    {"size", T_SIZE, 1, FB_MAX_DIM, false, NULL, "[1024, 1024]", "image size in pixels (flag: --size WxH)"},
    {"seed", T_INT, 0, 4294967295.0, false, NULL, "1", "random seed"},
    {"compression", T_ENUM, 0, 0, false, "zip|piz|none", "\"zip\"", "EXR compression"},
    {"parts", T_ENUM, 0, 0, false, "single|per-layer", "\"single\"",
     "one EXR part with every layer, or one part per layer (multi-part; each may have its own compression)"},
    {"layers", T_LAYERS, 1, FB_MAX_LAYERS, false, NULL, NULL, "the layers, each a generator"},
};

static const char *const noise_names = "gradient|value|simplex|cellular|cellular-f2|sine";

static const keyspec fbm_keys[] = {
    {"type", T_TYPE, 0, 0, false, NULL, NULL, "generator: \"fbm\""},
    {"name", T_NAME, 0, 0, false, NULL, "\"fbm\"", "layer name; the channel is NAME.Y (flag: --layer)"},
    {"noise", T_ENUM, 0, 0, false, "gradient|value|simplex|cellular|cellular-f2|sine", "\"gradient\"", "base noise"},
    {"hurst", T_NUM, 0, 1, false, NULL, "1.0", "Hurst exponent H; gain G = 2^-H"},
    {"gain", T_NUM, 0, 2, true, NULL, NULL, "octave gain G, instead of hurst"},
    {"octaves", T_INT, 1, 32, false, NULL, "8", "number of octaves"},
    {"lacunarity", T_NUM, 1.01, 8, false, NULL, "2.0", "frequency ratio between octaves"},
    {"rotation", T_NUM, -180, 180, false, NULL, "36.87", "rotation between octaves, degrees"},
    {"frequency", T_NUM, 0, 1e6, true, NULL, "4.0", "cycles of the first octave across the image width"},
    {"offset", T_VEC2, -1e6, 1e6, false, NULL, "[0.0, 0.0]", "domain offset, in first-octave cells (X,Y)"},
    {"ridged", T_BOOL, 0, 0, false, NULL, "false", "ridged octaves (1 - |n|)^2"},
    {"billow", T_BOOL, 0, 0, false, NULL, "false", "billow octaves 2|n| - 1"},
    {"warp", T_NUM, 0, 100, false, NULL, "0.0", "domain-warp strength, in first-octave cells"},
    {"tileable", T_BOOL, 0, 0, false, NULL, "false", "periodic in x and y: the image wraps without a seam"},
    {"half", T_BOOL, 0, 0, false, NULL, "false", "store as half instead of float (flags: --half, --float)"},
    {"compression", T_ENUM, 0, 0, false, "zip|piz|none", NULL,
     "this layer's compression (default: the scene's); needs \"parts\": \"per-layer\""},
};

static const keyspec julia_keys[] = {
    {"type", T_TYPE, 0, 0, false, NULL, NULL, "generator: \"julia\""},
    {"name", T_NAME, 0, 0, false, NULL, "\"sky\"",
     "layer name; channels NAME.iter, .n, .inside, .de, .R, .G, .B (flag: --layer)"},
    {"mapping", T_ENUM, 0, 0, false, "rect|polar", "\"rect\"",
     "starting grid: rect (eq. 7) or polar (eq. 8, seamless left/right)"},
    {"scale", T_VEC2, 0, 1e6, false, NULL, NULL, "rect: width and height of the grid (default 3 wide, square pixels)"},
    {"radius", T_NUM, 0, 1e6, true, NULL, "1.5", "polar: radius r of p = r v exp(i 2 pi u)"},
    {"center", T_VEC2, -1e6, 1e6, false, NULL, "[0.0, 0.0]", "centre of the starting grid (RE,IM)"},
    {"rotation", T_NUM, -360, 360, false, NULL, "0.0", "rotation of the starting grid, degrees"},
    {"alpha", T_VEC2, -1e6, 1e6, false, NULL, "[0.0, 0.0]", "allpass warp coefficient a (RE,IM); 0: plain Julia set"},
    {"c", T_VEC2, -1e6, 1e6, false, NULL, "[-0.8, 0.156]", "Julia constant c (RE,IM)"},
    {"max-iter", T_INT, 1, 1000000, false, NULL, "256", "iteration limit"},
    {"bailout", T_NUM, 2, 1e6, false, NULL, "2.0", "escape radius R (iter counts steps until |z| >= R)"},
    {"turbulence", T_NUM, 0, 10, false, NULL, "0.0", "lambda of eq. 13: z0 = A(1/p) + lambda W(p), W fBm in [0, 1]"},
    {"turbulence-hurst", T_NUM, 0, 1, false, NULL, "0.8", "Hurst exponent of W"},
    {"turbulence-octaves", T_INT, 1, 32, false, NULL, "6", "octaves of W"},
    {"turbulence-frequency", T_NUM, 0, 1e4, true, NULL, "4.0", "cycles of W's first octave across the image"},
    {"samples", T_INT, 1, 1024, false, NULL, "1", "jittered colour samples per pixel (iter, n, inside, de: centre)"},
    {"precision", T_ENUM, 0, 0, false, "float|double", "\"float\"",
     "the grid and orbits in float, or double (escape counts as a double reference has them; Vulkan "
     "devices need shaderFloat64)"},
    {"channels", T_NAMES, 0, 0, false, "iter|n|inside|de|R|G|B",
     "[\"iter\", \"n\", \"inside\", \"de\", \"R\", \"G\", \"B\"]",
     "channels to store; what none of them needs is not computed (R, G, B go together)"},
    {"palette", T_ENUM, 0, 0, false, FB_PALETTE_NAMES, "\"night\"", "named colour map"},
    {"cosine", T_NUMLIST, -10, 10, false, NULL, NULL,
     "cosine palette a + b cos(2 pi (c t + d)): 12 numbers aR,aG,aB,bR,bG,bB,cR,cG,cB,dR,dG,dB", 12},
    {"stops", T_STOPS, 0, 1e3, false, NULL, NULL,
     "gradient: [[t, r, g, b], ...], t rising from 0 to 1 (flag: \"t,r,g,b;t,r,g,b\")"},
    {"period", T_NUM, 0, 1e6, true, NULL, "24.0", "smooth-count units per palette sweep"},
    {"palette-offset", T_NUM, -1e6, 1e6, false, NULL, "0.0", "palette position at count 0, in sweeps"},
    {"brightness", T_NUM, 0, 1e3, false, NULL, "1.0", "linear colour scale"},
    {"gamma", T_NUM, 0, 10, true, NULL, "1.0", "exponent on the colour"},
    {"density", T_NUM, 0, 16, false, NULL, "1.5", "contrast: larger keeps only pixels near the set bright"},
    {"density-count", T_NUM, 1, 1e6, false, NULL, "48.0", "smooth count at which brightness is full"},
    {"inside-color", T_NUMLIST, 0, 1e3, false, NULL, "[0.0, 0.0, 0.0]", "colour of points inside the set (R,G,B)", 3},
    {"half", T_BOOL, 0, 0, false, NULL, "true", "store R, G, B as half (flags: --half, --float)"},
    {"compression", T_ENUM, 0, 0, false, "zip|piz|none", NULL,
     "this layer's compression (default: the scene's); needs \"parts\": \"per-layer\""},
};

static const keyspec ifs_keys[] = {
    {"type", T_TYPE, 0, 0, false, NULL, NULL, "generator: \"ifs\""},
    {"name", T_NAME, 0, 0, false, NULL, "\"plants\"",
     "layer name; channels NAME.count, .density, .colour, .R, .G, .B, .A (flag: --layer)"},
    {"preset", T_ENUM, 0, 0, false, FB_IFS_PRESETS, NULL, "built-in IFS (default fern when no maps or file)"},
    {"maps", T_MAPS, -1e6, 1e6, false, NULL, NULL,
     "affine maps [[a, b, c, d, e, f, p], ...]: x' = a x + b y + e, y' = c x + d y + f (flag: \"a,b,c,d,e,f,p;...\")"},
    {"file", T_STRING, 0, 0, false, NULL, NULL, "a Fractint .ifs file (its maps are stored in the scene)"},
    {"entry", T_STRING, 0, 0, false, NULL, NULL, "the entry of the .ifs file (flag: --name; default the first)"},
    {"colors", T_FRACS, 0, 1, false, NULL, NULL, "colour coordinate of each map, in [0, 1] (default spread evenly)"},
    {"condensation", T_IFSREF, -1e6, 1e6, false, NULL, NULL,
     "condensation set C: an IFS preset name or map list, or an L-system {\"preset\": \"tree\", ...} (flag: "
     "lsystem:tree); w0 sends any point onto C"},
    {"condensation-probability", T_NUM, 0, 1, true, NULL, "0.5", "probability of the condensation map w0"},
    {"points", T_INT, 0, 1e14, false, NULL, "0",
     "chaos-game steps in all (0: 64 per histogram cell); at about 1e8 a second, 1e14 takes days: "
     "progress is shown and Ctrl-C stops it"},
    {"skip", T_INT, 0, 1000000, false, NULL, "0",
     "transient steps discarded after each (re)start (0: from the maps' mean contraction)"},
    {"chains", T_INT, 0, 1048576, false, NULL, "0", "independent chains (0: from points and skip, at most 65536)"},
    {"bounds", T_BOUNDS, -1e9, 1e9, false, NULL, "\"auto\"",
     "frame XMIN,XMAX,YMIN,YMAX, or auto (from a short pre-run, square units)"},
    {"oversample", T_INT, 1, 4, false, NULL, "1", "histogram at K x K the resolution, box-filtered down"},
    {"palette", T_ENUM, 0, 0, false, FB_PALETTE_NAMES, "\"foliage\"", "named colour map"},
    {"cosine", T_NUMLIST, -10, 10, false, NULL, NULL,
     "cosine palette a + b cos(2 pi (c t + d)): 12 numbers aR,aG,aB,bR,bG,bB,cR,cG,cB,dR,dG,dB", 12},
    {"stops", T_STOPS, 0, 1e3, false, NULL, NULL,
     "gradient: [[t, r, g, b], ...], t rising from 0 to 1 (flag: \"t,r,g,b;t,r,g,b\")"},
    {"brightness", T_NUM, 0, 1e3, false, NULL, "1.0", "scale of the log density (1: the 99.5th percentile is full)"},
    {"gamma", T_NUM, 0, 10, true, NULL, "2.2", "density gamma"},
    {"gamma-threshold", T_NUM, 0, 1, false, NULL, "0.01", "below this alpha the gamma curve is linear"},
    {"vibrancy", T_NUM, 0, 1, false, NULL, "1.0", "1: gamma on alpha (saturated); 0: gamma per channel"},
    {"highlight-power", T_NUM, -1, 100, false, NULL, "1.0",
     "over-bright pixels: < 0 clip per channel, 0 keep hue, larger fade to white"},
    {"half", T_BOOL, 0, 0, false, NULL, "true", "store R, G, B, A as half (flags: --half, --float)"},
    {"compression", T_ENUM, 0, 0, false, "zip|piz|none", NULL,
     "this layer's compression (default: the scene's); needs \"parts\": \"per-layer\""},
};

static const keyspec lsystem_keys[] = {
    {"type", T_TYPE, 0, 0, false, NULL, NULL, "generator: \"lsystem\""},
    {"name", T_NAME, 0, 0, false, NULL, "\"plants\"",
     "layer name; channels NAME.A (coverage), .R, .G, .B (flag: --layer)"},
    {"preset", T_ENUM, 0, 0, false, FB_LSYS_PRESETS, NULL,
     "built-in L-system (default bush when no axiom); axiom, rules, iterations and angle override it"},
    {"axiom", T_STRING, 0, 0, false, NULL, NULL, "the starting string"},
    {"rules", T_RULES, 0, FB_LSYS_MAX_RULES, false, NULL, NULL,
     "productions \"X=successor\" or stochastic \"X(0.3)=successor\" (flag: --rule, repeatable)"},
    {"iterations", T_INT, 0, 64, false, NULL, NULL, "parallel rewriting steps"},
    {"angle", T_NUM, -360, 360, false, NULL, NULL, "degrees turned by + and -"},
    {"heading", T_NUM, -360, 360, false, NULL, "90.0", "initial heading, degrees counter-clockwise from +x (90: up)"},
    {"step", T_NUM, 0, 1e6, true, NULL, "1.0", "length of F and f, turtle units"},
    {"width", T_NUM, 0, 100, false, NULL, "0.6", "branch width at the base (bracket depth 0), in steps"},
    {"taper", T_NUM, 0, 1, true, NULL, "0.65", "width factor per bracket depth"},
    {"max-symbols", T_INT, 1, 2147483648.0, false, NULL, "268435456",
     "longest string allowed while rewriting (a longer one stops with an error)"},
    {"bounds", T_BOUNDS, -1e9, 1e9, false, NULL, "\"auto\"",
     "frame XMIN,XMAX,YMIN,YMAX in turtle units, or auto (the drawing, padded 4%, square units)"},
    {"palette", T_ENUM, 0, 0, false, FB_PALETTE_NAMES, "\"foliage\"", "named colour map, by bracket depth"},
    {"cosine", T_NUMLIST, -10, 10, false, NULL, NULL,
     "cosine palette a + b cos(2 pi (c t + d)): 12 numbers aR,aG,aB,bR,bG,bB,cR,cG,cB,dR,dG,dB", 12},
    {"stops", T_STOPS, 0, 1e3, false, NULL, NULL,
     "gradient: [[t, r, g, b], ...], t rising from 0 to 1 (flag: \"t,r,g,b;t,r,g,b\")"},
    {"half", T_BOOL, 0, 0, false, NULL, "true", "store A, R, G, B as half (flags: --half, --float)"},
    {"compression", T_ENUM, 0, 0, false, "zip|piz|none", NULL,
     "this layer's compression (default: the scene's); needs \"parts\": \"per-layer\""},
};

static const keyspec terrain_keys[] = {
    {"type", T_TYPE, 0, 0, false, NULL, NULL, "generator: \"terrain\""},
    {"name", T_NAME, 0, 0, false, NULL, "\"terrain\"", "layer name; channels NAME.Y (height) and NAME.A (in the hull)"},
    {"points", T_POINTS, -1e15, 1e15, false, NULL, NULL,
     "survey points: an XYZ / CSV file (x y z per line) or a list [[x, y, z], ...]"},
    {"from-heightfield", T_STRING, 0, 0, false, NULL, NULL, "instead of points: IN.exr[:layer.channel] sampled"},
    {"sample", T_INT, 1, 65536, false, NULL, NULL, "with from-heightfield: every N-th pixel (default 16)"},
    {"insert", T_INT, 0, 1e8, false, NULL, "40000", "points inserted by random midpoint displacement"},
    {"hurst", T_NUM, 0, 1, true, NULL, "0.85", "Hurst exponent H in (0, 1); D = 3 - H"},
    {"dimension", T_NUM, 2, 3, true, NULL, NULL, "fractal dimension D in (2, 3), instead of hurst"},
    {"sigma", T_NUM, 0, 1e15, false, NULL, NULL,
     "standard deviation of height increments at unit distance (default: estimated from the points)"},
    {"order", T_ENUM, 0, 0, false, "random|sweep", "\"random\"",
     "insertion triangles: random (by area) or an ordered sweep"},
    {"variance", T_ENUM, 0, 0, false, "stage|local", "\"stage\"",
     "var(z_abc - z_*): over the mesh per doubling (stage) or the triangle's neighbourhood (local)"},
    {"centers", T_STRING, 0, 0, false, NULL, NULL, "CSV of centres x,y,D,sigma: regions of their own D and sigma"},
    {"bounds", T_BOUNDS, -1e15, 1e15, false, NULL, "\"auto\"",
     "area rasterised: \"auto\" (the points' bounding box) or [xmin, xmax, ymin, ymax]"},
    {"mesh", T_OUTPUT, 0, 0, false, NULL, NULL, "also write the refined mesh: OUT.ply (binary) or OUT.obj"},
    {"half", T_BOOL, 0, 0, false, NULL, "false", "store Y as half (flags: --half, --float)"},
    {"compression", T_ENUM, 0, 0, false, "zip|piz|none", NULL,
     "this layer's compression (default: the scene's); needs \"parts\": \"per-layer\""},
};

static const keyspec op_keys[] = {
    {"type", T_TYPE, 0, 0, false, NULL, NULL, "generator: \"op\""},
    {"name", T_NAME, 0, 0, false, NULL, "\"op\"", "layer name; the channel is NAME.Y"},
    {"op", T_ENUM, 0, 0, false, "add|multiply|mix|remap|threshold", NULL,
     "add: sum of w_i x_i; multiply: product; mix: a + (b - a) m; remap: linear range change; threshold: 0/1 step"},
    {"inputs", T_REFS, 0, 0, false, NULL, NULL,
     "channels \"layer.channel\" (\"layer\": its Y) or numbers: 2-8 (add, multiply), 2 (mix), 1 (remap, threshold)"},
    {"weights", T_FRACS, -1e15, 1e15, false, NULL, NULL, "add: one weight per input (default all 1)"},
    {"mask", T_REF, 0, 0, false, NULL, NULL, "mix: the mask m, clamped to [0, 1]"},
    {"from", T_VEC2, -1e15, 1e15, false, NULL, NULL, "remap: the source range [lo, hi]"},
    {"to", T_VEC2, -1e15, 1e15, false, NULL, NULL, "remap: the target range [lo, hi] (default [0, 1])"},
    {"clamp", T_BOOL, 0, 0, false, NULL, NULL, "remap: clamp to the target range (default true)"},
    {"level", T_NUM, -1e15, 1e15, false, NULL, NULL, "threshold: 1 at and above the level, 0 below"},
    {"width", T_NUM, 0, 1e15, false, NULL, NULL, "threshold: a smooth step this wide around the level (default 0)"},
    {"half", T_BOOL, 0, 0, false, NULL, "false", "store Y as half (flags: --half, --float)"},
    {"compression", T_ENUM, 0, 0, false, "zip|piz|none", NULL,
     "this layer's compression (default: the scene's); needs \"parts\": \"per-layer\""},
};

static const keyspec constrain_keys[] = {
    {"type", T_TYPE, 0, 0, false, NULL, NULL, "generator: \"constrain\""},
    {"name", T_NAME, 0, 0, false, NULL, "\"terrain\"", "layer name; channels NAME.Y, .macro, .detail, .T, .H"},
    {"macro", T_STRING, 0, 0, false, NULL, NULL,
     "macro shape d: cone | ridge | boss | bowl, or IN.exr[:layer.channel] (default boss)"},
    {"macro-height", T_NUM, -1e6, 1e6, false, NULL, "10.0", "height of a built-in macro shape"},
    {"profile", T_STRING, 0, 0, false, NULL, NULL, "1D (height 1): a CSV profile (d, or x,d per line) as the macro"},
    {"T", T_NUM, 0, 1e6, true, NULL, "0.3", "approximation degree T > 0 (small: close to the macro shape)"},
    {"hurst", T_NUM, 0, 1, true, NULL, "0.8", "roughness degree H in (0, 1) (large: smoother)"},
    {"sigma", T_NUM, 0, 1e6, true, NULL, "1.0", "standard deviation of P_fbm's first level"},
    {"delta", T_NUM, 0, 1e6, true, NULL, "0.01", "delta of Z = 1 / (sqrt(6) sigma + delta)"},
    {"points", T_CPOINTS, 0, 0, false, NULL, NULL,
     "discrete constraints D = d: a file of x,y per line or [[x, y], ...] (pixels from the top left)"},
    {"regions", T_CREGIONS, 0, 0, false, NULL, NULL,
     "continuous constraints: a file of x,y,T|H,value per line or [[x, y, \"H\", 0.95], ...]"},
    {"domain", T_INT, 0, 16, false, NULL, "4", "a region reaches pixels within 2^domain (L1 distance, eq. 13)"},
    {"falloff", T_NUM, 0, 1e6, false, NULL, "0.01", "f_d of eq. 14: fall-off with the squared distance"},
    {"buffering", T_ENUM, 0, 0, false, "regional|none|naive", "\"regional\"",
     "discrete constraints: regional buffering, none (zeroed when made), naive (zeroed after)"},
    {"water", T_NUM, -1e15, 1e15, false, NULL, NULL, "a water level: channel NAME.A is 1 where D >= water"},
    {"csv", T_OUTPUT, 0, 0, false, NULL, NULL, "1D: also write x, d, D per line to this CSV file"},
    {"plot", T_OUTPUT, 0, 0, false, NULL, NULL,
     "1D: also draw d (blue), D (black) and the constraints (red) to this PNG"},
    {"half", T_BOOL, 0, 0, false, NULL, "false", "store the channels as half (flags: --half, --float)"},
    {"compression", T_ENUM, 0, 0, false, "zip|piz|none", NULL,
     "this layer's compression (default: the scene's); needs \"parts\": \"per-layer\""},
};

/* The keys of an L-system condensation set of an ifs layer ("condensation": {"preset": "tree"}). */
static const keyspec cond_lsystem_keys[] = {
    {"preset", T_ENUM, 0, 0, false, FB_LSYS_PRESETS, NULL, "built-in L-system"},
    {"axiom", T_STRING, 0, 0, false, NULL, NULL, "the starting string"},
    {"rules", T_RULES, 0, FB_LSYS_MAX_RULES, false, NULL, NULL, "productions \"X=successor\""},
    {"iterations", T_INT, 0, 64, false, NULL, NULL, "parallel rewriting steps"},
    {"angle", T_NUM, -360, 360, false, NULL, NULL, "degrees turned by + and -"},
    {"heading", T_NUM, -360, 360, false, NULL, "90.0", "initial heading, degrees (90: up)"},
    {"height", T_NUM, 0, 1e6, true, NULL, "0.25",
     "the drawing's largest extent in the IFS's units, base at the origin"},
    {"max-symbols", T_INT, 1, 2147483648.0, false, NULL, "268435456", "longest string allowed while rewriting"},
};

#define NKEYS(a) ((int)(sizeof(a) / sizeof((a)[0])))

static const keyspec *find_key(const keyspec *keys, int n, const char *key)
{
    for (int i = 0; i < n; i++)
        if (!strcmp(keys[i].key, key)) return &keys[i];
    return NULL;
}

static bool kind_keys(const char *kind, const keyspec **keys, int *n)
{
    if (!strcmp(kind, "fbm")) {
        *keys = fbm_keys;
        *n = NKEYS(fbm_keys);
        return true;
    }
    if (!strcmp(kind, "julia")) {
        *keys = julia_keys;
        *n = NKEYS(julia_keys);
        return true;
    }
    if (!strcmp(kind, "ifs")) {
        *keys = ifs_keys;
        *n = NKEYS(ifs_keys);
        return true;
    }
    if (!strcmp(kind, "lsystem")) {
        *keys = lsystem_keys;
        *n = NKEYS(lsystem_keys);
        return true;
    }
    if (!strcmp(kind, "terrain")) {
        *keys = terrain_keys;
        *n = NKEYS(terrain_keys);
        return true;
    }
    if (!strcmp(kind, "op")) {
        *keys = op_keys;
        *n = NKEYS(op_keys);
        return true;
    }
    if (!strcmp(kind, "constrain")) {
        *keys = constrain_keys;
        *n = NKEYS(constrain_keys);
        return true;
    }
    return false;
}

/* ---- locating a key path in the source text ------------------------------------------------- */

typedef struct cursor {
    const char *p;
    int line;
} cursor;

static void skip_ws(cursor *c)
{
    while (*c->p == ' ' || *c->p == '\t' || *c->p == '\r' || *c->p == '\n') {
        if (*c->p == '\n') c->line++;
        c->p++;
    }
}

static bool skip_string(cursor *c)
{
    if (*c->p != '"') return false;
    for (c->p++; *c->p && *c->p != '"'; c->p++)
        if (*c->p == '\\' && c->p[1]) c->p++;
    if (*c->p != '"') return false;
    c->p++;
    return true;
}

static bool skip_value(cursor *c)
{
    skip_ws(c);
    char open = *c->p;
    if (open == '"') return skip_string(c);
    if (open == '{' || open == '[') {
        char close = open == '{' ? '}' : ']';
        c->p++;
        skip_ws(c);
        if (*c->p == close) {
            c->p++;
            return true;
        }
        for (;;) {
            if (open == '{') {
                skip_ws(c);
                if (!skip_string(c)) return false;
                skip_ws(c);
                if (*c->p++ != ':') return false;
            }
            if (!skip_value(c)) return false;
            skip_ws(c);
            if (*c->p == ',') {
                c->p++;
                continue;
            }
            if (*c->p == close) {
                c->p++;
                return true;
            }
            return false;
        }
    }
    while (*c->p && !strchr(",]} \t\r\n", *c->p)) c->p++;
    return true;
}

/* The line of the element at `path` ("layers[0].octaves") in JSON text, or of the deepest enclosing
 * element that exists. The text has already been parsed successfully by jansson. */
static int locate(cursor *c, const char *path)
{
    skip_ws(c);
    if (*path == '.') path++;
    if (!*path) return c->line;
    int here = c->line;
    if (*path == '[') {
        long idx = strtol(path + 1, NULL, 10);
        const char *rest = strchr(path, ']');
        if (!rest || *c->p != '[') return here;
        c->p++;
        for (long i = 0; i < idx; i++) {
            if (!skip_value(c)) return here;
            skip_ws(c);
            if (*c->p++ != ',') return here;
        }
        return locate(c, rest + 1);
    }
    size_t klen = strcspn(path, ".[");
    if (*c->p != '{') return here;
    c->p++;
    for (;;) {
        skip_ws(c);
        if (*c->p != '"') return here;
        int key_line = c->line;
        const char *k = c->p + 1;
        if (!skip_string(c)) return here;
        bool match = (size_t)(c->p - 1 - k) == klen && !strncmp(k, path, klen);
        skip_ws(c);
        if (*c->p++ != ':') return here;
        if (match) return path[klen] ? locate(c, path + klen) : key_line;
        if (!skip_value(c)) return here;
        skip_ws(c);
        if (*c->p++ != ',') return here;
    }
}

/* ---- validation ----------------------------------------------------------------------------- */

typedef struct vctx {
    const char *origin; /* file name, or NULL for the command line */
    const char *text;
    /* --set overrides: what the user typed, and the key path each one set ("layers[0].c") */
    const char *const *sets;
    char (*set_paths)[256];
    int nsets;
} vctx;

/* Logs "FILE:LINE: PATH: message" (file) or "--KEY: message" (command line) and returns FB_ERR_INPUT. */
static fb_result verr(const vctx *v, const char *path, const char *fmt, ...) __attribute__((format(printf, 3, 4)));
static fb_result verr(const vctx *v, const char *path, const char *fmt, ...)
{
    char msg[1024];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    for (int i = v->nsets - 1; i >= 0; i--) { /* a value given by --set is reported as that --set */
        size_t n = strlen(v->set_paths[i]);
        if (!strncmp(path, v->set_paths[i], n) && (!path[n] || path[n] == '.' || path[n] == '['))
            return fb_fail(FB_ERR_USAGE, "--set %s: %s%s%s", v->sets[i], path[n] ? path + n + 1 : "",
                           path[n] ? ": " : "", msg);
    }
    if (v->origin) {
        cursor c = {v->text, 1};
        int line = locate(&c, path);
        return fb_fail(FB_ERR_INPUT, "%s:%d: %s: %s", v->origin, line, path[0] ? path : "(top level)", msg);
    }
    const char *inner = strstr(path, ".condensation.");
    if (inner) /* a key of an L-system condensation set given as one --condensation JSON value */
        return fb_fail(FB_ERR_USAGE, "--condensation: %s: %s", inner + strlen(".condensation."), msg);
    const char *leaf = strrchr(path, '.');
    leaf = leaf ? leaf + 1 : path;
    if (!strcmp(leaf, "name")) leaf = "layer";
    if (!strcmp(leaf, "entry")) leaf = "name";
    if (!strncmp(leaf, "rules", 5)) leaf = "rule";
    return fb_fail(FB_ERR_USAGE, "--%s: %s", leaf, msg);
}

/* A short rendering of a JSON value for messages. */
static void show(const json_t *j, char *buf, size_t n)
{
    char *s = json_dumps(j, JSON_ENCODE_ANY | JSON_COMPACT);
    snprintf(buf, n, "%s", s ? s : "?");
    if (strlen(buf) > 40) strcpy(buf + 37, "...");
    free(s);
}

static bool enum_index(const char *enums, const char *s, int *idx)
{
    size_t n = strlen(s);
    int i = 0;
    for (const char *p = enums; *p; i++) {
        size_t len = strcspn(p, "|");
        if (len == n && !strncmp(p, s, n)) {
            *idx = i;
            return true;
        }
        p += len + (p[len] == '|');
    }
    return false;
}

static fb_result check_number(const vctx *v, const char *path, const keyspec *k, const json_t *j, bool integer)
{
    char shown[64];
    show(j, shown, sizeof shown);
    if (integer ? !json_is_integer(j) : !json_is_number(j))
        return verr(v, path, "expected %s, found %s", integer ? "an integer" : "a number", shown);
    double x = json_number_value(j);
    if (!isfinite(x)) return verr(v, path, "expected a finite number, found %s", shown);
    bool in_range = (k->lo_open ? x > k->lo : x >= k->lo) && x <= k->hi;
    if (!in_range) {
        if (integer) return verr(v, path, "expected an integer in %.0f..%.0f, found %s", k->lo, k->hi, shown);
        return verr(v, path, "expected a number in %s%g, %g], found %s", k->lo_open ? "(" : "[", k->lo, k->hi, shown);
    }
    return FB_OK;
}

/* [[a, b, c, d, e, f(, p)], ...]: 1..64 maps of 6 or 7 finite numbers, p >= 0. */
static fb_result check_maps(const vctx *v, const char *path, const keyspec *k, const json_t *j)
{
    char shown[64], sub[256];
    show(j, shown, sizeof shown);
    size_t n = json_is_array(j) ? json_array_size(j) : 0;
    if (n < 1 || n > FB_IFS_MAX_MAPS)
        return verr(v, path, "expected a list of 1 to %d maps [a, b, c, d, e, f, p], found %s", FB_IFS_MAX_MAPS, shown);
    for (size_t i = 0; i < n; i++) {
        const json_t *m = json_array_get(j, i);
        size_t len = json_is_array(m) ? json_array_size(m) : 0;
        snprintf(sub, sizeof sub, "%s[%zu]", path, i);
        show(m, shown, sizeof shown);
        if (len != 6 && len != 7)
            return verr(v, sub, "expected a map [a, b, c, d, e, f] or [a, b, c, d, e, f, p], found %s", shown);
        for (size_t c = 0; c < len; c++) {
            const json_t *e = json_array_get(m, c);
            double x = json_is_number(e) ? json_number_value(e) : NAN;
            if (!isfinite(x) || x < k->lo || x > k->hi)
                return verr(v, sub, "coefficient %c is not a finite number in %g..%g (found %s)", "abcdefp"[c], k -> lo,
                            k -> hi, shown);
            if (c == 6 && x < 0) return verr(v, sub, "probability %g is negative", x);
        }
    }
    return FB_OK;
}

static fb_result check_value(const vctx *v, const char *path, const keyspec *k, json_t *j)
{
    char shown[64];
    show(j, shown, sizeof shown);
    int idx;
    switch (k->type) {
    case T_INT:
        return check_number(v, path, k, j, true);
    case T_NUM:
        return check_number(v, path, k, j, false);
    case T_BOOL:
        if (!json_is_boolean(j)) return verr(v, path, "expected true or false, found %s", shown);
        return FB_OK;
    case T_ENUM:
        if (!json_is_string(j) || !enum_index(k->enums, json_string_value(j), &idx))
            return verr(v, path, "expected one of %s, found %s", k->enums, shown);
        return FB_OK;
    case T_TYPE:
        if (!json_is_string(j)) return verr(v, path, "expected a generator name such as \"fbm\", found %s", shown);
        return FB_OK;
    case T_NAME: {
        const char *s = json_is_string(j) ? json_string_value(j) : NULL;
        bool ok = s && *s && strlen(s) < 64;
        for (const char *p = s; ok && *p; p++)
            ok = (*p >= 'a' && *p <= 'z') || (*p >= 'A' && *p <= 'Z') || (*p >= '0' && *p <= '9') || *p == '_' ||
                 *p == '-';
        if (!ok) return verr(v, path, "expected a name of 1 to 63 letters, digits, '_' or '-', found %s", shown);
        return FB_OK;
    }
    case T_VEC2:
    case T_SIZE: {
        bool isz = k->type == T_SIZE;
        if (!json_is_array(j) || json_array_size(j) != 2)
            return verr(v, path, "expected %s, found %s", isz ? "[width, height]" : "[x, y]", shown);
        for (size_t i = 0; i < 2; i++) {
            const json_t *e = json_array_get(j, i);
            bool good = isz ? json_is_integer(e) : json_is_number(e);
            double x = good ? json_number_value(e) : 0;
            if (!good || !isfinite(x) || x < k->lo || x > k->hi)
                return verr(v, path, "expected %s with each %s in %g..%g, found %s", isz ? "[width, height]" : "[x, y]",
                            isz ? "side an integer" : "component", k->lo, k->hi, shown);
        }
        if (isz) {
            unsigned long long px =
                (unsigned long long)json_integer_value(json_array_get(j, 0)) * json_integer_value(json_array_get(j, 1));
            if (px > FB_MAX_PIXELS)
                return verr(v, path, "%s is %llu pixels; at most %llu are supported", shown, px, FB_MAX_PIXELS);
        }
        return FB_OK;
    }
    case T_NUMLIST: {
        bool good = json_is_array(j) && (int)json_array_size(j) == k->count;
        for (size_t i = 0; good && i < json_array_size(j); i++) {
            const json_t *e = json_array_get(j, i);
            double x = json_is_number(e) ? json_number_value(e) : NAN;
            good = isfinite(x) && x >= k->lo && x <= k->hi;
        }
        if (!good) return verr(v, path, "expected %d numbers in %g..%g, found %s", k->count, k->lo, k->hi, shown);
        return FB_OK;
    }
    case T_STOPS: {
        size_t n = json_is_array(j) ? json_array_size(j) : 0;
        bool good = n >= 2 && n <= FB_PALETTE_MAX_STOPS;
        double prev = -1;
        for (size_t i = 0; good && i < n; i++) {
            const json_t *e = json_array_get(j, i);
            good = json_is_array(e) && json_array_size(e) == 4;
            for (size_t c = 0; good && c < 4; c++) {
                const json_t *x = json_array_get(e, c);
                double d = json_is_number(x) ? json_number_value(x) : NAN;
                good = isfinite(d) && d >= 0 && (c > 0 ? d <= k->hi : d <= 1.0);
            }
            if (good) {
                double t = json_number_value(json_array_get(e, 0));
                good = t > prev && (i > 0 || t == 0.0) && (i + 1 < n || t == 1.0);
                prev = t;
            }
        }
        if (!good)
            return verr(v, path,
                        "expected 2 to %d stops [t, r, g, b] with t rising from 0 to exactly 1 and colours >= 0, "
                        "found %s",
                        FB_PALETTE_MAX_STOPS, shown);
        return FB_OK;
    }
    case T_REFS:
        if (!json_is_array(j) || json_array_size(j) < 1 || json_array_size(j) > FB_OP_MAX_INPUTS)
            return verr(v, path, "expected a list of 1 to %d channels or numbers, found %s", FB_OP_MAX_INPUTS, shown);
        for (size_t i = 0; i < json_array_size(j); i++) {
            char sub[300];
            snprintf(sub, sizeof sub, "%s[%zu]", path, i);
            fb_result rc = check_value(v, sub, &(keyspec){.type = T_REF}, json_array_get(j, i));
            if (rc) return rc;
        }
        return FB_OK;
    case T_CPOINTS:
    case T_CREGIONS: {
        bool reg = k->type == T_CREGIONS;
        if (json_is_string(j) && *json_string_value(j) && strlen(json_string_value(j)) < 1024) return FB_OK;
        size_t n = json_is_array(j) ? json_array_size(j) : 0;
        if (!n)
            return verr(v, path, "expected a file name or a list %s, found %s",
                        reg ? "[[x, y, \"T\" or \"H\", value], ...]" : "[[x, y], ...]", shown);
        for (size_t i = 0; i < n; i++) {
            const json_t *pt = json_array_get(j, i);
            bool good = json_is_array(pt) && json_array_size(pt) == (reg ? 4u : 2u);
            for (size_t c = 0; good && c < 2; c++) good = json_is_integer(json_array_get(pt, c));
            if (good && reg) {
                const char *kind = json_string_value(json_array_get(pt, 2));
                const json_t *val = json_array_get(pt, 3);
                good = kind && (!strcmp(kind, "T") || !strcmp(kind, "H")) && json_is_number(val) &&
                       isfinite(json_number_value(val));
            }
            if (!good) {
                char sub[256];
                snprintf(sub, sizeof sub, "%s[%zu]", path, i);
                show(pt, shown, sizeof shown);
                return verr(v, sub, "expected %s, found %s",
                            reg ? "[x, y, \"T\" or \"H\", value] with integer pixel x, y" : "[x, y] integer pixels",
                            shown);
            }
        }
        return FB_OK;
    }
    case T_REF: {
        if (json_is_number(j)) {
            if (!isfinite(json_number_value(j))) return verr(v, path, "expected a finite number, found %s", shown);
            return FB_OK;
        }
        const char *r = json_is_string(j) ? json_string_value(j) : NULL;
        bool ok = r && *r && strlen(r) < 128 && r[0] != '.' && r[strlen(r) - 1] != '.';
        if (!ok) return verr(v, path, "expected \"layer.channel\", \"layer\" or a number, found %s", shown);
        return FB_OK;
    }
    case T_STRING:
    case T_OUTPUT:
        if (!json_is_string(j) || !*json_string_value(j) || strlen(json_string_value(j)) >= 4096)
            return verr(v, path, "expected a non-empty string, found %s", shown);
        return FB_OK;
    case T_IFSREF:
        if (json_is_object(j)) return FB_OK; /* an L-system: checked by parse_ifs */
        if (json_is_string(j)) {
            if (!enum_index(FB_IFS_PRESETS, json_string_value(j), &idx) || !strcmp(json_string_value(j), "population"))
                return verr(v, path,
                            "expected an IFS preset name (fern|sierpinski|maple|tree|spiral), a map list or an "
                            "L-system {\"preset\": ...}, found %s",
                            shown);
            return FB_OK;
        }
        return check_maps(v, path, k, j);
    case T_MAPS:
        return check_maps(v, path, k, j);
    case T_POINTS: {
        if (json_is_string(j) && *json_string_value(j) && strlen(json_string_value(j)) < 1024) return FB_OK;
        size_t n = json_is_array(j) ? json_array_size(j) : 0;
        if (!n) return verr(v, path, "expected a file name or a list of points [[x, y, z], ...], found %s", shown);
        for (size_t i = 0; i < n; i++) {
            const json_t *pt = json_array_get(j, i);
            bool good = json_is_array(pt) && json_array_size(pt) == 3;
            for (size_t c = 0; good && c < 3; c++) {
                const json_t *e = json_array_get(pt, c);
                double x = json_is_number(e) ? json_number_value(e) : NAN;
                good = isfinite(x) && x >= k->lo && x <= k->hi;
            }
            if (!good) {
                char sub[256];
                snprintf(sub, sizeof sub, "%s[%zu]", path, i);
                show(pt, shown, sizeof shown);
                return verr(v, sub, "expected a point [x, y, z] of finite numbers, found %s", shown);
            }
        }
        return FB_OK;
    }
    case T_BOUNDS: {
        if (json_is_string(j) && !strcmp(json_string_value(j), "auto")) return FB_OK;
        bool good = json_is_array(j) && json_array_size(j) == 4;
        double b[4] = {0};
        for (size_t i = 0; good && i < 4; i++) {
            const json_t *e = json_array_get(j, i);
            b[i] = json_is_number(e) ? json_number_value(e) : NAN;
            good = isfinite(b[i]) && b[i] >= k->lo && b[i] <= k->hi;
        }
        if (!good || !(b[1] > b[0] && b[3] > b[2]))
            return verr(v, path,
                        "expected \"auto\" or [xmin, xmax, ymin, ymax] with xmin < xmax and ymin < ymax, "
                        "found %s",
                        shown);
        return FB_OK;
    }
    case T_FRACS: {
        size_t n = json_is_array(j) ? json_array_size(j) : 0;
        bool good = n >= 1 && n <= FB_IFS_MAX_MAPS;
        for (size_t i = 0; good && i < n; i++) {
            const json_t *e = json_array_get(j, i);
            double x = json_is_number(e) ? json_number_value(e) : NAN;
            good = isfinite(x) && x >= k->lo && x <= k->hi;
        }
        if (!good)
            return verr(v, path, "expected 1 to %d numbers in %g..%g, found %s", FB_IFS_MAX_MAPS, k->lo, k->hi, shown);
        return FB_OK;
    }
    case T_NAMES: {
        size_t n = json_is_array(j) ? json_array_size(j) : 0;
        bool good = n >= 1 && n <= 32;
        for (size_t i = 0; good && i < n; i++) {
            const json_t *e = json_array_get(j, i);
            good = json_is_string(e) && enum_index(k->enums, json_string_value(e), &idx);
            for (size_t m = 0; good && m < i; m++)
                good = strcmp(json_string_value(json_array_get(j, m)), json_string_value(e));
        }
        if (!good) return verr(v, path, "expected a list of distinct names from %s, found %s", k->enums, shown);
        return FB_OK;
    }
    case T_RULES: {
        size_t n = json_is_array(j) ? json_array_size(j) : 0;
        if (!json_is_array(j) || n > FB_LSYS_MAX_RULES)
            return verr(v, path, "expected a list of at most %d rules \"X=successor\", found %s", FB_LSYS_MAX_RULES,
                        shown);
        for (size_t i = 0; i < n; i++) {
            const json_t *e = json_array_get(j, i);
            char sub[256], msg[256];
            fb_lsys_rule rule;
            snprintf(sub, sizeof sub, "%s[%zu]", path, i);
            if (!json_is_string(e)) {
                show(e, shown, sizeof shown);
                return verr(v, sub, "expected a rule \"X=successor\", found %s", shown);
            }
            if (!fb_lsys_parse_rule(json_string_value(e), &rule, msg, sizeof msg)) return verr(v, sub, "%s", msg);
        }
        return FB_OK;
    }
    case T_LAYERS:
        if (!json_is_array(j) || json_array_size(j) < 1 || json_array_size(j) > FB_MAX_LAYERS)
            return verr(v, path, "expected an array of 1 to %d layers, found %s", FB_MAX_LAYERS, shown);
        return FB_OK;
    }
    return FB_OK;
}

/* Checks every key of `obj` against `keys` and fills in the defaults. */
static fb_result check_object(const vctx *v, const char *path, json_t *obj, const keyspec *keys, int n,
                              const char *what)
{
    const char *key;
    json_t *val;
    char sub[256];
    json_object_foreach(obj, key, val)
    {
        snprintf(sub, sizeof sub, "%s%s%s", path, path[0] ? "." : "", key);
        const keyspec *k = find_key(keys, n, key);
        if (!k) {
            char known[512] = "";
            for (int i = 0; i < n; i++)
                snprintf(known + strlen(known), sizeof known - strlen(known), "%s%s", i ? ", " : "", keys[i].key);
            if (!v->origin && !strstr(sub, ".condensation."))
                return fb_fail(FB_ERR_USAGE, "--%s: unknown flag for %s", key, what);
            return verr(v, sub, "unknown key for %s (known keys: %s)", what, known);
        }
        fb_result rc = check_value(v, sub, k, val);
        if (rc) return rc;
    }
    for (int i = 0; i < n; i++) {
        if (!keys[i].def || json_object_get(obj, keys[i].key)) continue;
        if (!strcmp(keys[i].key, "hurst") && (json_object_get(obj, "gain") || json_object_get(obj, "dimension")))
            continue;
        json_t *d = json_loads(keys[i].def, JSON_DECODE_ANY, NULL);
        if (!d || json_object_set_new(obj, keys[i].key, d) != 0) return fb_fail(FB_ERR_NOMEM, "out of memory");
    }
    return FB_OK;
}

static double num(const json_t *obj, const char *key)
{
    return json_number_value(json_object_get(obj, key));
}

static bool boolean(const json_t *obj, const char *key)
{
    return json_is_true(json_object_get(obj, key));
}

static fb_result parse_fbm(const vctx *v, const char *path, json_t *obj, fb_layer *L)
{
    char sub[256];
    fb_result rc = check_object(v, path, obj, fbm_keys, NKEYS(fbm_keys), "an fbm layer");
    if (rc) return rc;
    fb_fbm_params *f = &L->fbm;
    if (json_object_get(obj, "hurst") && json_object_get(obj, "gain")) {
        snprintf(sub, sizeof sub, "%s.gain", path);
        return verr(v, sub, "give hurst or gain, not both");
    }
    int idx = 0;
    enum_index(noise_names, json_string_value(json_object_get(obj, "noise")), &idx);
    static const unsigned kinds[] = {K_NOISE_GRADIENT, K_NOISE_VALUE,       K_NOISE_SIMPLEX,
                                     K_NOISE_CELLULAR, K_NOISE_CELLULAR_F2, K_NOISE_SINE};
    f->noise = kinds[idx];
    f->gain_given = json_object_get(obj, "gain") != NULL;
    f->hurst = f->gain_given ? -log2(num(obj, "gain")) : num(obj, "hurst");
    f->gain = f->gain_given ? num(obj, "gain") : exp2(-f->hurst);
    f->octaves = (int)json_integer_value(json_object_get(obj, "octaves"));
    f->lacunarity = num(obj, "lacunarity");
    f->rotation = num(obj, "rotation");
    f->frequency = num(obj, "frequency");
    json_t *off = json_object_get(obj, "offset");
    f->offset[0] = json_number_value(json_array_get(off, 0));
    f->offset[1] = json_number_value(json_array_get(off, 1));
    f->ridged = boolean(obj, "ridged");
    f->billow = boolean(obj, "billow");
    f->tileable = boolean(obj, "tileable");
    f->warp = num(obj, "warp");
    L->half = boolean(obj, "half");
    if (f->ridged && f->billow) {
        snprintf(sub, sizeof sub, "%s.billow", path);
        return verr(v, sub, "ridged and billow cannot both be set");
    }
    if (f->tileable && f->noise == K_NOISE_SIMPLEX) {
        snprintf(sub, sizeof sub, "%s.tileable", path);
        return verr(v, sub,
                    "simplex noise lives on a skewed lattice that does not tile a rectangle; use gradient, "
                    "value, cellular, cellular-f2 or sine noise for tileable fBm");
    }
    return FB_OK;
}

static void vec2_of(const json_t *obj, const char *key, double out[2])
{
    json_t *a = json_object_get(obj, key);
    out[0] = json_number_value(json_array_get(a, 0));
    out[1] = json_number_value(json_array_get(a, 1));
}

/* The colour map keys shared by julia and ifs layers: palette, cosine, stops. */
static fb_result parse_palette(const vctx *v, const char *path, const json_t *obj, fb_palette_spec *pal)
{
    enum_index(FB_PALETTE_NAMES, json_string_value(json_object_get(obj, "palette")), &pal->named);
    json_t *cos_j = json_object_get(obj, "cosine"), *stops_j = json_object_get(obj, "stops");
    if (cos_j && stops_j) {
        char sub[256];
        snprintf(sub, sizeof sub, "%s.stops", path);
        return verr(v, sub, "give cosine or stops, not both");
    }
    pal->has_cosine = cos_j != NULL;
    for (size_t i = 0; cos_j && i < 12; i++) pal->cosine[i] = json_number_value(json_array_get(cos_j, i));
    pal->nstops = stops_j ? (int)json_array_size(stops_j) : 0;
    for (int i = 0; i < pal->nstops; i++)
        for (int c = 0; c < 4; c++)
            pal->stops[i][c] = json_number_value(json_array_get(json_array_get(stops_j, (size_t)i), (size_t)c));
    return FB_OK;
}

static fb_result parse_julia(const vctx *v, const char *path, json_t *obj, const fb_scene *s, fb_layer *L)
{
    /* The default grid is 3 units wide with square pixels, so it depends on the image size. */
    if (!json_object_get(obj, "scale") && s->width > 0)
        json_object_set_new(obj, "scale", json_pack("[ff]", 3.0, 3.0 * s->height / s->width));
    fb_result rc = check_object(v, path, obj, julia_keys, NKEYS(julia_keys), "a julia layer");
    if (rc) return rc;
    fb_julia_params *j = &L->julia;
    j->polar = !strcmp(json_string_value(json_object_get(obj, "mapping")), "polar");
    vec2_of(obj, "scale", j->scale);
    vec2_of(obj, "center", j->center);
    vec2_of(obj, "alpha", j->alpha);
    vec2_of(obj, "c", j->c);
    j->radius = num(obj, "radius");
    j->rotation = num(obj, "rotation");
    j->max_iter = (int)json_integer_value(json_object_get(obj, "max-iter"));
    j->bailout = num(obj, "bailout");
    rc = parse_palette(v, path, obj, &j->palette);
    if (rc) return rc;
    j->turbulence = num(obj, "turbulence");
    j->turb_hurst = num(obj, "turbulence-hurst");
    j->turb_octaves = (int)json_integer_value(json_object_get(obj, "turbulence-octaves"));
    j->turb_frequency = num(obj, "turbulence-frequency");
    j->samples = (int)json_integer_value(json_object_get(obj, "samples"));
    j->period = num(obj, "period");
    j->palette_offset = num(obj, "palette-offset");
    j->brightness = num(obj, "brightness");
    j->gamma = num(obj, "gamma");
    j->density = num(obj, "density");
    j->density_count = num(obj, "density-count");
    json_t *ic = json_object_get(obj, "inside-color");
    for (size_t i = 0; i < 3; i++) j->inside_color[i] = json_number_value(json_array_get(ic, i));
    j->double_precision = !strcmp(json_string_value(json_object_get(obj, "precision")), "double");
    json_t *chs = json_object_get(obj, "channels");
    j->channels = 0;
    for (size_t i = 0; i < json_array_size(chs); i++) {
        int idx = 0;
        enum_index("iter|n|inside|de|R|G|B", json_string_value(json_array_get(chs, i)), &idx);
        j->channels |= 1u << idx;
    }
    unsigned rgb = j->channels & 0x70u;
    if (rgb && rgb != 0x70u) {
        char sub[256];
        snprintf(sub, sizeof sub, "%s.channels", path);
        return verr(v, sub, "R, G and B go together: list all three or none");
    }
    L->half = boolean(obj, "half");
    if (!(j->scale[0] > 0 && j->scale[1] > 0)) {
        char sub[256];
        snprintf(sub, sizeof sub, "%s.scale", path);
        return verr(v, sub, "both sides of the grid must be positive");
    }
    return FB_OK;
}

/* A validated map list (T_MAPS) into an fb_ifs; a missing probability is -1. */
static void maps_of(const json_t *j, fb_ifs *out)
{
    memset(out, 0, sizeof *out);
    out->n = (int)json_array_size(j);
    for (int k = 0; k < out->n; k++) {
        const json_t *m = json_array_get(j, (size_t)k);
        double c[7] = {0, 0, 0, 0, 0, 0, -1};
        for (size_t i = 0; i < json_array_size(m); i++) c[i] = json_number_value(json_array_get(m, i));
        out->m[k] = (fb_ifs_map){c[0], c[1], c[2], c[3], c[4], c[5], c[6]};
    }
}

static json_t *maps_json(const fb_ifs *ifs)
{
    json_t *arr = json_array();
    for (int k = 0; arr && k < ifs->n; k++) {
        const fb_ifs_map *m = &ifs->m[k];
        json_t *e = json_pack("[ffffff]", m->a, m->b, m->c, m->d, m->e, m->f);
        if (e && m->p != -1) json_array_append_new(e, json_real(m->p));
        json_array_append_new(arr, e);
    }
    return arr;
}

static fb_result check_ifs(const vctx *v, const char *path, const fb_ifs *ifs)
{
    int bad;
    char msg[256], sub[256];
    if (fb_ifs_valid(ifs, &bad, msg, sizeof msg)) return FB_OK;
    if (bad >= 0)
        snprintf(sub, sizeof sub, "%s[%d]", path, bad);
    else
        snprintf(sub, sizeof sub, "%s", path);
    return verr(v, sub, "%s", msg);
}

static void spread_colors(const json_t *given, int n, double *out)
{
    for (int k = 0; k < n; k++)
        out[k] = given ? json_number_value(json_array_get(given, (size_t)k)) : n > 1 ? (double)k / (n - 1) : 0.5;
}

static fb_result parse_lsys_def(const vctx *v, const char *path, json_t *obj, const keyspec *keys, int nkeys,
                                const char *what, fb_lsys *ls);

static fb_result parse_ifs(const vctx *v, const char *path, json_t *obj, const fb_scene *s, fb_layer *L)
{
    char sub[256];
    fb_ifs_params *f = &L->ifs;
    json_t *file = json_object_get(obj, "file"), *entry = json_object_get(obj, "entry");
    int sources = (json_object_get(obj, "preset") != NULL) + (json_object_get(obj, "maps") != NULL) + (file != NULL);
    if (sources > 1) {
        snprintf(sub, sizeof sub, "%s.%s", path, file ? "file" : "maps");
        return verr(v, sub, "give one of preset, maps or file");
    }
    if (entry && !file) {
        snprintf(sub, sizeof sub, "%s.entry", path);
        return verr(v, sub, "an entry name needs a file");
    }
    if (!sources) json_object_set_new(obj, "preset", json_string("fern"));
    fb_result rc = check_object(v, path, obj, ifs_keys, NKEYS(ifs_keys), "an ifs layer");
    if (rc) return rc;
    snprintf(sub, sizeof sub, "%s.maps", path);
    const char *preset = json_string_value(json_object_get(obj, "preset"));
    if (file) {
        /* The file's maps go into the stored scene, so that the bake can be reproduced without it. */
        rc = fb_ifs_read_file(json_string_value(file), entry ? json_string_value(entry) : NULL, &f->maps);
        if (rc) return rc;
        json_t *mj = maps_json(&f->maps);
        if (!mj) return fb_fail(FB_ERR_NOMEM, "out of memory");
        json_object_set_new(obj, "maps", mj);
        json_object_del(obj, "file");
        json_object_del(obj, "entry");
        snprintf(sub, sizeof sub, "%s.file", path);
    } else if (preset) {
        rc = fb_ifs_preset(preset, &f->maps, &f->cond, &f->has_cond);
        if (rc) return rc;
    } else {
        maps_of(json_object_get(obj, "maps"), &f->maps);
    }
    if ((rc = check_ifs(v, sub, &f->maps))) return rc;

    json_t *cond = json_object_get(obj, "condensation");
    snprintf(sub, sizeof sub, "%s.condensation", path);
    if (cond && f->has_cond) return verr(v, sub, "the population preset has its own condensation set");
    if (cond && json_is_object(cond)) {
        f->has_cond = f->cond_lsys = true;
        rc = parse_lsys_def(v, sub, cond, cond_lsystem_keys, NKEYS(cond_lsystem_keys), "an L-system condensation set",
                            &f->cond_sys);
        if (rc) return rc;
        f->cond_heading = num(cond, "heading");
        f->cond_height = num(cond, "height");
        f->cond_max_symbols = (uint64_t)json_integer_value(json_object_get(cond, "max-symbols"));
    } else if (cond) {
        f->has_cond = true;
        if (json_is_string(cond))
            rc = fb_ifs_preset(json_string_value(cond), &f->cond, NULL, NULL);
        else
            maps_of(cond, &f->cond);
        if (rc || (rc = check_ifs(v, sub, &f->cond))) return rc;
    }
    f->cond_p = num(obj, "condensation-probability");
    json_t *colors = json_object_get(obj, "colors");
    if (colors && (int)json_array_size(colors) != f->maps.n) {
        snprintf(sub, sizeof sub, "%s.colors", path);
        return verr(v, sub, "%zu colour coordinates for %d maps", json_array_size(colors), f->maps.n);
    }
    spread_colors(colors, f->maps.n, f->colors);
    spread_colors(NULL, f->cond.n, f->cond_colors);
    f->points = (double)json_integer_value(json_object_get(obj, "points"));
    f->skip = (int)json_integer_value(json_object_get(obj, "skip"));
    f->chains = (int)json_integer_value(json_object_get(obj, "chains"));
    f->oversample = (int)json_integer_value(json_object_get(obj, "oversample"));
    json_t *b = json_object_get(obj, "bounds");
    f->auto_bounds = json_is_string(b);
    for (size_t i = 0; !f->auto_bounds && i < 4; i++) f->bounds[i] = json_number_value(json_array_get(b, i));
    if ((rc = parse_palette(v, path, obj, &f->palette))) return rc;
    f->brightness = num(obj, "brightness");
    f->gamma = num(obj, "gamma");
    f->gamma_threshold = num(obj, "gamma-threshold");
    f->vibrancy = num(obj, "vibrancy");
    f->highlight_power = num(obj, "highlight-power");
    L->half = boolean(obj, "half");
    uint64_t cells = (uint64_t)s->width * s->height * (uint64_t)(f->oversample * f->oversample);
    if (cells > (1ull << 28)) {
        snprintf(sub, sizeof sub, "%s.oversample", path);
        return verr(v, sub, "the histogram would have %llu cells (size x oversample^2); at most 2^28 are supported",
                    (unsigned long long)cells);
    }
    return FB_OK;
}

/* The L-system of `obj` (a layer, or an ifs layer's condensation set): a preset fills in what the
 * object does not give, and the stored scene then spells it out; keys checked against `keys`. */
static fb_result parse_lsys_def(const vctx *v, const char *path, json_t *obj, const keyspec *keys, int nkeys,
                                const char *what, fb_lsys *ls)
{
    char sub[256], msg[256];
    json_t *preset = json_object_get(obj, "preset");
    if (!preset && !json_object_get(obj, "axiom")) {
        if (json_object_get(obj, "rules")) {
            snprintf(sub, sizeof sub, "%s.rules", path);
            return verr(v, sub, "rules need an axiom (or a preset)");
        }
        json_object_set_new(obj, "preset", json_string("bush"));
        preset = json_object_get(obj, "preset");
    }
    if (preset) {
        fb_lsys ps;
        int idx;
        if (json_is_string(preset) && enum_index(FB_LSYS_PRESETS, json_string_value(preset), &idx) &&
            !fb_lsys_preset(json_string_value(preset), &ps)) {
            json_t *rules = json_array();
            for (int k = 0; k < ps.nrules; k++) {
                char text[FB_LSYS_MAX_SUCC + 64];
                if (ps.rules[k].p >= 0)
                    snprintf(text, sizeof text, "%c(%g)=%s", ps.rules[k].pred, ps.rules[k].p, ps.rules[k].succ);
                else
                    snprintf(text, sizeof text, "%c=%s", ps.rules[k].pred, ps.rules[k].succ);
                json_array_append_new(rules, json_string(text));
            }
            if (!json_object_get(obj, "axiom")) json_object_set_new(obj, "axiom", json_string(ps.axiom));
            if (!json_object_get(obj, "rules"))
                json_object_set_new(obj, "rules", rules);
            else
                json_decref(rules);
            if (!json_object_get(obj, "iterations"))
                json_object_set_new(obj, "iterations", json_integer(ps.iterations));
            if (!json_object_get(obj, "angle")) json_object_set_new(obj, "angle", json_real(ps.angle));
        }
    }
    if (!json_object_get(obj, "rules")) json_object_set_new(obj, "rules", json_array());
    if (!json_object_get(obj, "iterations")) json_object_set_new(obj, "iterations", json_integer(1));
    if (!json_object_get(obj, "angle")) json_object_set_new(obj, "angle", json_real(25.0));
    fb_result rc = check_object(v, path, obj, keys, nkeys, what);
    if (rc) return rc;
    memset(ls, 0, sizeof *ls);
    const char *axiom = json_string_value(json_object_get(obj, "axiom"));
    snprintf(sub, sizeof sub, "%s.axiom", path);
    if (strlen(axiom) > FB_LSYS_MAX_SUCC) return verr(v, sub, "longer than %d symbols", FB_LSYS_MAX_SUCC);
    snprintf(ls->axiom, sizeof ls->axiom, "%s", axiom);
    json_t *rules = json_object_get(obj, "rules");
    ls->nrules = (int)json_array_size(rules);
    for (int k = 0; k < ls->nrules; k++)
        fb_lsys_parse_rule(json_string_value(json_array_get(rules, (size_t)k)), &ls->rules[k], msg, sizeof msg);
    ls->iterations = (int)json_integer_value(json_object_get(obj, "iterations"));
    ls->angle = num(obj, "angle");
    int bad;
    if (!fb_lsys_valid(ls, &bad, msg, sizeof msg)) {
        if (bad >= 0)
            snprintf(sub, sizeof sub, "%s.rules[%d]", path, bad);
        else
            snprintf(sub, sizeof sub, "%s.axiom", path);
        return verr(v, sub, "%s", msg);
    }
    return FB_OK;
}

static fb_result parse_lsystem(const vctx *v, const char *path, json_t *obj, fb_layer *L)
{
    fb_lsystem_params *f = &L->lsystem;
    fb_result rc = parse_lsys_def(v, path, obj, lsystem_keys, NKEYS(lsystem_keys), "an lsystem layer", &f->sys);
    if (rc) return rc;
    f->heading = num(obj, "heading");
    f->step = num(obj, "step");
    f->width = num(obj, "width");
    f->taper = num(obj, "taper");
    f->max_symbols = (uint64_t)json_integer_value(json_object_get(obj, "max-symbols"));
    json_t *b = json_object_get(obj, "bounds");
    f->auto_bounds = json_is_string(b);
    for (size_t i = 0; !f->auto_bounds && i < 4; i++) f->bounds[i] = json_number_value(json_array_get(b, i));
    if ((rc = parse_palette(v, path, obj, &f->palette))) return rc;
    L->half = boolean(obj, "half");
    return FB_OK;
}

static void string_to(const json_t *obj, const char *key, char *out, size_t size)
{
    const json_t *j = json_object_get(obj, key);
    snprintf(out, size, "%s", json_is_string(j) ? json_string_value(j) : "");
}

static fb_result parse_terrain(const vctx *v, const char *path, json_t *obj, fb_layer *L)
{
    char sub[256];
    bool h_given = json_object_get(obj, "hurst") != NULL, d_given = json_object_get(obj, "dimension") != NULL;
    fb_result rc = check_object(v, path, obj, terrain_keys, NKEYS(terrain_keys), "a terrain layer");
    if (rc) return rc;
    fb_terrain_layer_params *t = &L->terrain;
    json_t *pts = json_object_get(obj, "points");
    bool hf = json_object_get(obj, "from-heightfield") != NULL;
    if (!pts == !hf) {
        snprintf(sub, sizeof sub, "%s.points", path);
        return verr(v, sub, "give the survey points (points) or a height field to sample (from-heightfield)%s",
                    pts ? ", not both" : "");
    }
    if (json_object_get(obj, "sample") && !hf) {
        snprintf(sub, sizeof sub, "%s.sample", path);
        return verr(v, sub, "sample is the step of from-heightfield, which is not given");
    }
    if (h_given && d_given) {
        snprintf(sub, sizeof sub, "%s.dimension", path);
        return verr(v, sub, "give hurst or dimension, not both");
    }
    if (json_object_get(obj, "centers") && (h_given || d_given)) {
        snprintf(sub, sizeof sub, "%s.%s", path, h_given ? "hurst" : "dimension");
        return verr(v, sub, "the centres file gives each region its own D; drop %s", h_given ? "hurst" : "dimension");
    }
    t->points_inline = json_is_array(pts);
    string_to(obj, "points", t->points, sizeof t->points);
    string_to(obj, "from-heightfield", t->heightfield, sizeof t->heightfield);
    t->sample = json_object_get(obj, "sample") ? (int)json_integer_value(json_object_get(obj, "sample")) : 16;
    t->insert = (uint64_t)json_integer_value(json_object_get(obj, "insert"));
    t->hurst = d_given ? 3 - num(obj, "dimension") : num(obj, "hurst");
    if (!(t->hurst > 0 && t->hurst < 1)) {
        snprintf(sub, sizeof sub, "%s.%s", path, d_given ? "dimension" : "hurst");
        return verr(v, sub, "%s must lie strictly inside %s", d_given ? "D" : "H", d_given ? "(2, 3)" : "(0, 1)");
    }
    t->sigma = json_object_get(obj, "sigma") ? num(obj, "sigma") : -1;
    t->sweep = !strcmp(json_string_value(json_object_get(obj, "order")), "sweep");
    t->local_variance = !strcmp(json_string_value(json_object_get(obj, "variance")), "local");
    string_to(obj, "centers", t->centers, sizeof t->centers);
    string_to(obj, "mesh", t->mesh, sizeof t->mesh);
    json_t *b = json_object_get(obj, "bounds");
    t->auto_bounds = json_is_string(b);
    for (size_t i = 0; !t->auto_bounds && i < 4; i++) t->bounds[i] = json_number_value(json_array_get(b, i));
    L->half = boolean(obj, "half");
    const char *too_long = strlen(t->heightfield) >= sizeof t->heightfield - 1              ? "from-heightfield"
                           : strlen(t->centers) >= sizeof t->centers - 1                    ? "centers"
                           : strlen(t->mesh) >= sizeof t->mesh - 1                          ? "mesh"
                           : !t->points_inline && strlen(t->points) >= sizeof t->points - 1 ? "points"
                                                                                            : NULL;
    if (too_long) {
        snprintf(sub, sizeof sub, "%s.%s", path, too_long);
        return verr(v, sub, "file name longer than %zu characters", sizeof t->mesh - 2);
    }
    if (t->mesh[0]) {
        const char *dot = strrchr(t->mesh, '.');
        if (!dot || (strcasecmp(dot, ".ply") && strcasecmp(dot, ".obj"))) {
            snprintf(sub, sizeof sub, "%s.mesh", path);
            return verr(v, sub, "\"%s\": the mesh format comes from the extension, .ply or .obj", t->mesh);
        }
    }
    return FB_OK;
}

static void ref_of(const json_t *j, fb_ref *r)
{
    memset(r, 0, sizeof *r);
    r->layer = -1;
    if (json_is_number(j)) {
        r->value = json_number_value(j);
        return;
    }
    r->layer = -2; /* resolved by name in resolve_refs; the whole reference is kept in channel until then */
    snprintf(r->channel, sizeof r->channel, "%s", json_string_value(j));
}

static fb_result parse_op(const vctx *v, const char *path, json_t *obj, fb_layer *L)
{
    fb_result rc = check_object(v, path, obj, op_keys, NKEYS(op_keys), "an op layer");
    if (rc) return rc;
    char sub[256];
    fb_op_params *o = &L->op;
    o->mask.layer = -1; /* no mask unless mix */
    const json_t *opj = json_object_get(obj, "op"), *in = json_object_get(obj, "inputs");
    if (!opj || !in) {
        snprintf(sub, sizeof sub, "%s.%s", path, opj ? "inputs" : "op");
        return verr(v, sub, "required for an op layer (%s)",
                    opj ? "the channels it combines" : "add|multiply|mix|remap|threshold");
    }
    int idx = 0;
    enum_index("add|multiply|mix|remap|threshold", json_string_value(opj), &idx);
    o->op = (fb_op_kind)idx;
    o->ninputs = (int)json_array_size(in);
    for (int i = 0; i < o->ninputs; i++) {
        ref_of(json_array_get(in, (size_t)i), &o->inputs[i]);
        o->weights[i] = 1.0;
    }
    static const int lo[] = {2, 2, 2, 1, 1}, hi[] = {8, 8, 2, 1, 1};
    static const char *const names[] = {"add", "multiply", "mix", "remap", "threshold"};
    if (o->ninputs < lo[idx] || o->ninputs > hi[idx]) {
        snprintf(sub, sizeof sub, "%s.inputs", path);
        if (lo[idx] == hi[idx])
            return verr(v, sub, "%s takes %d input%s, found %d", names[idx], lo[idx], lo[idx] == 1 ? "" : "s",
                        o->ninputs);
        return verr(v, sub, "%s takes %d to %d inputs, found %d", names[idx], lo[idx], hi[idx], o->ninputs);
    }
    /* each option belongs to one op; given to another it would be ignored, so it is refused */
    static const struct {
        const char *key;
        fb_op_kind op;
    } owner[] = {{"weights", FB_OP_ADD}, {"mask", FB_OP_MIX},        {"from", FB_OP_REMAP},     {"to", FB_OP_REMAP},
                 {"clamp", FB_OP_REMAP}, {"level", FB_OP_THRESHOLD}, {"width", FB_OP_THRESHOLD}};
    for (size_t k = 0; k < sizeof owner / sizeof owner[0]; k++)
        if (json_object_get(obj, owner[k].key) && owner[k].op != o->op) {
            snprintf(sub, sizeof sub, "%s.%s", path, owner[k].key);
            return verr(v, sub, "only for op %s, not %s", names[owner[k].op], names[idx]);
        }
    static const struct {
        const char *key;
        fb_op_kind op;
    } required[] = {{"mask", FB_OP_MIX}, {"from", FB_OP_REMAP}, {"level", FB_OP_THRESHOLD}};
    for (size_t k = 0; k < sizeof required / sizeof required[0]; k++)
        if (required[k].op == o->op && !json_object_get(obj, required[k].key)) {
            snprintf(sub, sizeof sub, "%s.%s", path, required[k].key);
            return verr(v, sub, "required for op %s", names[idx]);
        }
    const json_t *w = json_object_get(obj, "weights");
    if (w) {
        if ((int)json_array_size(w) != o->ninputs) {
            snprintf(sub, sizeof sub, "%s.weights", path);
            return verr(v, sub, "expected one weight per input (%d), found %zu", o->ninputs, json_array_size(w));
        }
        for (int i = 0; i < o->ninputs; i++) o->weights[i] = json_number_value(json_array_get(w, (size_t)i));
    }
    if (o->op == FB_OP_MIX) ref_of(json_object_get(obj, "mask"), &o->mask);
    if (o->op == FB_OP_REMAP) {
        vec2_of(obj, "from", o->from);
        o->to[0] = 0, o->to[1] = 1;
        if (json_object_get(obj, "to")) vec2_of(obj, "to", o->to);
        o->clamp = json_object_get(obj, "clamp") ? boolean(obj, "clamp") : true;
        if (!(o->from[1] != o->from[0])) {
            snprintf(sub, sizeof sub, "%s.from", path);
            return verr(v, sub, "the source range must not be empty ([lo, hi] with lo != hi)");
        }
    }
    if (o->op == FB_OP_THRESHOLD) {
        o->level = num(obj, "level");
        o->width = json_object_get(obj, "width") ? num(obj, "width") : 0.0;
    }
    L->half = boolean(obj, "half");
    return FB_OK;
}

/* Resolves the op layers' references to layer indices and orders the layers so that each comes
 * after those it uses; a missing layer or a cycle is an error that names both layers. */
/* The references of layer i to other layers (op inputs and mask, a constrain layer's macro). */
static int layer_refs(fb_scene *s, int i, fb_ref **out, char names[][24])
{
    fb_layer *L = &s->layers[i];
    int n = 0;
    if (L->kind == FB_LAYER_OP) {
        for (int k = 0; k < L->op.ninputs; k++) {
            snprintf(names[n], 24, "inputs[%d]", k);
            out[n++] = &L->op.inputs[k];
        }
        if (L->op.mask.layer != -1) {
            snprintf(names[n], 24, "mask");
            out[n++] = &L->op.mask;
        }
    } else if (L->kind == FB_LAYER_CONSTRAIN && L->constrain.macro_ref.layer != -1) {
        snprintf(names[n], 24, "macro");
        out[n++] = &L->constrain.macro_ref;
    }
    return n;
}

/* Resolves the references between layers to layer indices and orders the layers so that each comes
 * after those it uses; a missing layer or a cycle is an error that names both layers. */
static fb_result resolve_refs(const vctx *v, fb_scene *s)
{
    char sub[128], names[FB_MAX_LAYERS * 66], rn[FB_OP_MAX_INPUTS + 1][24];
    fb_ref *refs[FB_OP_MAX_INPUTS + 1];
    fb_scene_layer_names(s, names, sizeof names);
    for (int i = 0; i < s->nlayers; i++) {
        int nr = layer_refs(s, i, refs, rn);
        for (int k = 0; k < nr; k++) {
            fb_ref *r = refs[k];
            if (r->layer != -2) continue;
            char name[128];
            snprintf(name, sizeof name, "%s", r->channel);
            char *dot = strchr(name, '.');
            if (dot) *dot = 0;
            r->layer = -1;
            for (int j = 0; j < s->nlayers; j++)
                if (!strcmp(s->layers[j].name, name)) r->layer = j;
            snprintf(sub, sizeof sub, "layers[%d].%s", i, rn[k]);
            if (r->layer < 0 && !strcmp(rn[k], "macro"))
                return verr(v, sub,
                            "\"%s\" is not cone, ridge, boss, bowl, IN.exr[:layer.channel] or a layer of the scene "
                            "(layers: %s)",
                            r->channel, names);
            if (r->layer < 0)
                return verr(v, sub, "layer \"%s\" refers to \"%s\", but no layer is named \"%s\" (layers: %s)",
                            s->layers[i].name, r->channel, name, names);
            snprintf(r->channel, sizeof r->channel, "%s", dot ? dot + 1 : ""); /* name was a copy */
        }
    }
    /* depth-first topological order; state 1: on the stack, 2: placed */
    int state[FB_MAX_LAYERS] = {0}, n = 0;
    int stack[FB_MAX_LAYERS], next[FB_MAX_LAYERS], top = 0;
    for (int root = 0; root < s->nlayers; root++) {
        if (state[root]) continue;
        stack[top] = root, next[top++] = 0, state[root] = 1;
        while (top) {
            int cur = stack[top - 1];
            int nr = layer_refs(s, cur, refs, rn);
            if (next[top - 1] >= nr) {
                state[cur] = 2;
                s->order[n++] = cur;
                top--;
                continue;
            }
            const fb_ref *r = refs[next[top - 1]++];
            if (r->layer < 0 || state[r->layer] == 2) continue;
            if (state[r->layer] == 1) {
                snprintf(sub, sizeof sub, "layers[%d]", cur);
                return verr(v, sub, "layer \"%s\" uses layer \"%s\", which depends on \"%s\": a cycle",
                            s->layers[cur].name, s->layers[r->layer].name, s->layers[cur].name);
            }
            stack[top] = r->layer, next[top++] = 0, state[r->layer] = 1;
        }
    }
    return FB_OK;
}

static fb_result parse_constrain(const vctx *v, const char *path, json_t *obj, const fb_scene *s, fb_layer *L)
{
    fb_result rc = check_object(v, path, obj, constrain_keys, NKEYS(constrain_keys), "a constrain layer");
    if (rc) return rc;
    fb_constrain_params *c = &L->constrain;
    char sub[256];
    const json_t *macro = json_object_get(obj, "macro"), *prof = json_object_get(obj, "profile");
    if (macro && prof) {
        snprintf(sub, sizeof sub, "%s.profile", path);
        return verr(v, sub, "give a macro or a profile, not both");
    }
    if (prof && s->height != 1) {
        snprintf(sub, sizeof sub, "%s.profile", path);
        return verr(v, sub, "a CSV profile is a 1D macro: the scene's height must be 1 (it is %d)", s->height);
    }
    for (int k = 0; k < 2; k++)
        if (json_object_get(obj, k ? "plot" : "csv") && s->height != 1) {
            snprintf(sub, sizeof sub, "%s.%s", path, k ? "plot" : "csv");
            return verr(v, sub, "%s output is for 1D profiles: the scene's height must be 1 (it is %d)",
                        k ? "plot" : "CSV", s->height);
        }
    snprintf(c->macro, sizeof c->macro, "%s", macro ? json_string_value(macro) : prof ? "" : "boss");
    string_to(obj, "profile", c->profile, sizeof c->profile);
    string_to(obj, "csv", c->csv, sizeof c->csv);
    string_to(obj, "plot", c->plot, sizeof c->plot);
    c->macro_ref.layer = -1;
    if (macro && !strstr(c->macro, ".exr") && strcmp(c->macro, "cone") && strcmp(c->macro, "ridge") &&
        strcmp(c->macro, "boss") && strcmp(c->macro, "bowl")) {
        /* another layer of the scene, "layer" or "layer.channel": resolved with the op layers' inputs */
        size_t len = strlen(c->macro);
        if (c->macro[0] == '.' || c->macro[len - 1] == '.' || len >= sizeof c->macro_ref.channel) {
            snprintf(sub, sizeof sub, "%s.macro", path);
            return verr(
                v, sub,
                "expected cone, ridge, boss, bowl, IN.exr[:layer.channel] or a layer of the scene, found \"%s\"",
                c->macro);
        }
        c->macro_ref.layer = -2;
        snprintf(c->macro_ref.channel, sizeof c->macro_ref.channel, "%s", c->macro);
    }
    if (num(obj, "hurst") >= 1) {
        snprintf(sub, sizeof sub, "%s.hurst", path);
        return verr(v, sub, "expected a roughness H in (0, 1), found %g", num(obj, "hurst"));
    }
    c->macro_height = num(obj, "macro-height");
    c->T = num(obj, "T");
    c->hurst = num(obj, "hurst");
    c->sigma = num(obj, "sigma");
    c->delta = num(obj, "delta");
    c->domain = (int)json_integer_value(json_object_get(obj, "domain"));
    c->falloff = num(obj, "falloff");
    int b = 0;
    enum_index("regional|none|naive", json_string_value(json_object_get(obj, "buffering")), &b);
    c->buffering = b;
    c->has_water = json_object_get(obj, "water") != NULL;
    c->water = c->has_water ? num(obj, "water") : 0;
    const json_t *pts = json_object_get(obj, "points"), *regs = json_object_get(obj, "regions");
    c->points_inline = pts && json_is_array(pts);
    c->regions_inline = regs && json_is_array(regs);
    if (pts && !c->points_inline) string_to(obj, "points", c->points, sizeof c->points);
    if (regs && !c->regions_inline) string_to(obj, "regions", c->regions, sizeof c->regions);
    /* inline points and regions: inside the image; region values in range */
    for (size_t i = 0; c->points_inline && i < json_array_size(pts); i++) {
        const json_t *p = json_array_get(pts, i);
        long long x = json_integer_value(json_array_get(p, 0)), y = json_integer_value(json_array_get(p, 1));
        if (x < 0 || y < 0 || x >= s->width || y >= s->height) {
            snprintf(sub, sizeof sub, "%s.points[%zu]", path, i);
            return verr(v, sub, "pixel (%lld, %lld) is outside the %d x %d image", x, y, s->width, s->height);
        }
    }
    for (size_t i = 0; c->regions_inline && i < json_array_size(regs); i++) {
        const json_t *p = json_array_get(regs, i);
        long long x = json_integer_value(json_array_get(p, 0)), y = json_integer_value(json_array_get(p, 1));
        bool is_h = !strcmp(json_string_value(json_array_get(p, 2)), "H");
        double val = json_number_value(json_array_get(p, 3));
        snprintf(sub, sizeof sub, "%s.regions[%zu]", path, i);
        if (x < 0 || y < 0 || x >= s->width || y >= s->height)
            return verr(v, sub, "pixel (%lld, %lld) is outside the %d x %d image", x, y, s->width, s->height);
        if (is_h ? !(val > 0 && val < 1) : !(val > 0))
            return verr(v, sub, "%s = %g is out of range (%s)", is_h ? "H" : "T", val, is_h ? "0 < H < 1" : "T > 0");
    }
    L->half = boolean(obj, "half");
    return FB_OK;
}

static fb_result parse_root(const vctx *v, json_t *root, fb_scene *s)
{
    char path[64];
    if (!json_is_object(root)) return verr(v, "", "expected a JSON object with \"size\", \"seed\" and \"layers\"");
    if (!json_object_get(root, "layers")) return verr(v, "", "missing key \"layers\" (an array of layers)");
    fb_result rc = check_object(v, "", root, scene_keys, NKEYS(scene_keys), "a scene");
    if (rc) return rc;
    json_t *size = json_object_get(root, "size");
    s->width = (int)json_integer_value(json_array_get(size, 0));
    s->height = (int)json_integer_value(json_array_get(size, 1));
    s->seed = (uint32_t)json_integer_value(json_object_get(root, "seed"));
    s->compression =
        (exrio_compression)exrio_compression_parse(json_string_value(json_object_get(root, "compression")));
    s->multipart = !strcmp(json_string_value(json_object_get(root, "parts")), "per-layer");
    json_t *layers = json_object_get(root, "layers");
    s->nlayers = (int)json_array_size(layers);
    for (int i = 0; i < s->nlayers; i++) {
        json_t *lj = json_array_get(layers, (size_t)i);
        snprintf(path, sizeof path, "layers[%d]", i);
        if (!json_is_object(lj)) return verr(v, path, "expected a layer object with a \"type\"");
        json_t *type = json_object_get(lj, "type");
        if (!type) return verr(v, path, "missing key \"type\" (the generator, e.g. \"fbm\")");
        const char *t = json_is_string(type) ? json_string_value(type) : "";
        fb_layer *L = &s->layers[i];
        memset(L, 0, sizeof *L);
        if (!strcmp(t, "fbm")) {
            L->kind = FB_LAYER_FBM;
            rc = parse_fbm(v, path, lj, L);
        } else if (!strcmp(t, "julia")) {
            L->kind = FB_LAYER_JULIA;
            rc = parse_julia(v, path, lj, s, L);
        } else if (!strcmp(t, "ifs")) {
            L->kind = FB_LAYER_IFS;
            rc = parse_ifs(v, path, lj, s, L);
        } else if (!strcmp(t, "lsystem")) {
            L->kind = FB_LAYER_LSYSTEM;
            rc = parse_lsystem(v, path, lj, L);
        } else if (!strcmp(t, "terrain")) {
            L->kind = FB_LAYER_TERRAIN;
            rc = parse_terrain(v, path, lj, L);
        } else if (!strcmp(t, "op")) {
            L->kind = FB_LAYER_OP;
            rc = parse_op(v, path, lj, L);
        } else if (!strcmp(t, "constrain")) {
            L->kind = FB_LAYER_CONSTRAIN;
            rc = parse_constrain(v, path, lj, s, L);
        } else {
            char sub[80], shown[64];
            snprintf(sub, sizeof sub, "%s.type", path);
            show(type, shown, sizeof shown);
            rc = verr(v, sub,
                      "unknown generator %s (available: \"fbm\", \"julia\", \"ifs\", \"lsystem\", \"terrain\", \"op\", "
                      "\"constrain\")",
                      shown);
        }
        if (rc) return rc;
        snprintf(L->name, sizeof L->name, "%s", json_string_value(json_object_get(lj, "name")));
        const json_t *lc = json_object_get(lj, "compression");
        L->compression = lc ? (exrio_compression)exrio_compression_parse(json_string_value(lc)) : s->compression;
        if (lc && !s->multipart) {
            char sub[80];
            snprintf(sub, sizeof sub, "%s.compression", path);
            return verr(v, sub, "a compression per layer needs \"parts\": \"per-layer\" (an EXR part has one)");
        }
        for (int k = 0; k < i; k++)
            if (!strcmp(s->layers[k].name, L->name)) {
                char sub[80];
                snprintf(sub, sizeof sub, "%s.name", path);
                return verr(v, sub, "layer name \"%s\" is already used by layers[%d]", L->name, k);
            }
    }
    return resolve_refs(v, s);
}

/* ---- --set KEY.PATH=VALUE -------------------------------------------------------------------- */

/* The value of a --set: JSON when it parses as JSON ("5", "[1, 2]", "\"x\"", "true"); WxH as
 * [W, H]; a comma-separated list as an array of such values; anything else as a string. */
static json_t *set_value(const char *text)
{
    json_t *j = json_loads(text, JSON_DECODE_ANY, NULL);
    if (j) return j;
    int w, h, used = 0;
    if (sscanf(text, "%d%*[x]%d%n", &w, &h, &used) == 2 && !text[used]) return json_pack("[ii]", w, h);
    if (!strchr(text, ',')) return json_string(text);
    json_t *arr = json_array();
    for (const char *p = text; arr;) {
        size_t n = strcspn(p, ",");
        char *item = strndup(p, n);
        json_t *e = item ? json_loads(item, JSON_DECODE_ANY, NULL) : NULL;
        if (!e && item) e = json_string(item);
        free(item);
        if (!e || json_array_append_new(arr, e) != 0) {
            json_decref(arr);
            return NULL;
        }
        if (!p[n]) break;
        p += n + 1;
    }
    return arr;
}

/* The default name of a layer of type `type` (its keys' "name" default), or "". */
static void default_layer_name(const json_t *layer, char *out, size_t n)
{
    const keyspec *keys, *k;
    int nk;
    const char *type = json_string_value(json_object_get(layer, "type"));
    const char *def = type && kind_keys(type, &keys, &nk) && (k = find_key(keys, nk, "name")) ? k->def : "\"\"";
    snprintf(out, n, "%.*s", (int)strlen(def) - 2, def + 1);
}

/* Applies one override to the scene's JSON, creating intermediate objects as needed; writes the key
 * path it set (layers[2].c) to jpath. In lists, a segment is an index or a layer name. */
static fb_result apply_set(json_t *root, const char *set, char jpath[256])
{
    const char *eq = strchr(set, '=');
    if (!eq || eq == set)
        return fb_fail(FB_ERR_USAGE, "--set %s: expected KEY.PATH=VALUE (e.g. layers.sky.c=-0.8,0.156)", set);
    json_t *node = root, *val = set_value(eq + 1);
    if (!val) return fb_fail(FB_ERR_NOMEM, "out of memory");
    jpath[0] = 0;
    const char *seg = set;
    size_t created = 0; /* the length of jpath where the first object this override created starts */
    for (;;) {
        size_t n = strcspn(seg, ".=");
        bool last = seg[n] == '=';
        char key[128];
        if (n == 0 || n >= sizeof key) {
            json_decref(val);
            return fb_fail(FB_ERR_USAGE, "--set %s: empty or overlong key in the path", set);
        }
        snprintf(key, sizeof key, "%.*s", (int)n, seg);
        size_t at = strlen(jpath);
        json_t *child = NULL;
        if (json_is_object(node)) {
            snprintf(jpath + at, 256 - at, "%s%s", at ? "." : "", key);
            if (last) {
                if (created) jpath[created] = 0; /* errors inside what it created are this override's */
                return json_object_set_new(node, key, val) ? fb_fail(FB_ERR_NOMEM, "out of memory") : FB_OK;
            }
            child = json_object_get(node, key);
            if (!child) {
                if (!created) created = strlen(jpath);
                child = json_object();
                if (!child || json_object_set_new(node, key, child) != 0) {
                    json_decref(val);
                    return fb_fail(FB_ERR_NOMEM, "out of memory");
                }
            }
        } else if (json_is_array(node)) {
            char *end;
            long idx = strtol(key, &end, 10);
            size_t count = json_array_size(node);
            if (*end || end == key) { /* a name: the element whose "name" (or default name) is key */
                idx = -1;
                for (size_t i = 0; i < count && idx < 0; i++) {
                    json_t *e = json_array_get(node, i);
                    char name[128];
                    if (json_is_string(json_object_get(e, "name")))
                        snprintf(name, sizeof name, "%s", json_string_value(json_object_get(e, "name")));
                    else
                        default_layer_name(e, name, sizeof name);
                    if (!strcmp(name, key)) idx = (long)i;
                }
                if (idx < 0) {
                    json_decref(val);
                    return fb_fail(FB_ERR_USAGE, "--set %s: no element named \"%s\" in %s", set, key,
                                   at ? jpath : "the scene");
                }
            } else if (idx < 0 || (size_t)idx >= count) {
                json_decref(val);
                return fb_fail(FB_ERR_USAGE, "--set %s: index %ld is out of range (%s has %zu)", set, idx,
                               at ? jpath : "the list", count);
            }
            snprintf(jpath + at, 256 - at, "[%ld]", idx);
            if (last)
                return json_array_set_new(node, (size_t)idx, val) ? fb_fail(FB_ERR_NOMEM, "out of memory") : FB_OK;
            child = json_array_get(node, (size_t)idx);
        } else {
            json_decref(val);
            return fb_fail(FB_ERR_USAGE, "--set %s: %s is a value, not an object or a list", set, jpath);
        }
        node = child;
        seg += n + 1;
    }
}

fb_result fb_scene_parse(const char *text, const char *origin, fb_scene *out)
{
    return fb_scene_parse_sets(text, origin, NULL, 0, out);
}

fb_result fb_scene_parse_sets(const char *text, const char *origin, const char *const *sets, int nsets, fb_scene *out)
{
    memset(out, 0, sizeof *out);
    json_error_t err;
    json_t *root = json_loads(text, JSON_REJECT_DUPLICATES, &err);
    if (!root) {
        if (origin)
            return fb_fail(FB_ERR_INPUT, "%s:%d:%d: malformed JSON: %s", origin, err.line, err.column, err.text);
        return fb_fail(FB_ERR_INPUT, "scene: malformed JSON: %s", err.text);
    }
    char(*paths)[256] = nsets > 0 ? calloc((size_t)nsets, sizeof *paths) : NULL;
    fb_result rc = nsets > 0 && !paths ? fb_fail(FB_ERR_NOMEM, "out of memory") : FB_OK;
    if (!rc && nsets > 0 && !json_is_object(root))
        rc = fb_fail(FB_ERR_INPUT, "%s: expected a JSON object with \"size\", \"seed\" and \"layers\"",
                     origin ? origin : "scene");
    for (int i = 0; i < nsets && !rc; i++) rc = apply_set(root, sets[i], paths[i]);
    vctx v = {origin, text, sets, paths, nsets};
    if (!rc) rc = parse_root(&v, root, out);
    if (!rc) {
        out->json = json_dumps(root, JSON_SORT_KEYS | JSON_INDENT(2) | JSON_REAL_PRECISION(17));
        if (!out->json) rc = fb_fail(FB_ERR_NOMEM, "out of memory");
    }
    free(paths);
    json_decref(root);
    return rc;
}

fb_result fb_scene_load(const char *path, fb_scene *out)
{
    return fb_scene_load_sets(path, NULL, 0, out);
}

fb_result fb_scene_load_sets(const char *path, const char *const *sets, int nsets, fb_scene *out)
{
    memset(out, 0, sizeof *out);
    FILE *f = NULL;
    fb_result orc = fb_input_open(path, "scene", &f);
    if (orc) return orc;
    char *text = NULL;
    size_t len = 0, cap = 0;
    for (;;) {
        if (len + 4096 + 1 > cap) {
            cap = cap ? 2 * cap : 8192;
            if (cap > (16u << 20)) {
                free(text);
                fclose(f);
                return fb_fail(FB_ERR_INPUT, "%s: scene file larger than 16 MiB", path);
            }
            char *t = realloc(text, cap);
            if (!t) {
                free(text);
                fclose(f);
                return fb_fail(FB_ERR_NOMEM, "out of memory");
            }
            text = t;
        }
        size_t n = fread(text + len, 1, 4096, f);
        len += n;
        if (n < 4096) break;
    }
    bool bad = ferror(f);
    fclose(f);
    if (bad) {
        free(text);
        return fb_fail(FB_ERR_INPUT, "%s: cannot read scene: %s", path, strerror(errno));
    }
    text[len] = 0;
    if (strlen(text) != len) {
        free(text);
        return fb_fail(FB_ERR_INPUT, "%s: scene contains a NUL byte (not a JSON text file)", path);
    }
    fb_result rc = fb_scene_parse_sets(text, path, sets, nsets, out);
    free(text);
    return rc;
}

void fb_scene_layer_names(const fb_scene *s, char *out, size_t size)
{
    out[0] = 0;
    for (int i = 0; i < s->nlayers; i++)
        snprintf(out + strlen(out), size - strlen(out), "%s%s", i ? ", " : "", s->layers[i].name);
}

int fb_scene_outputs(const fb_scene *s, const char **paths, const char **what, int max)
{
    int n = 0;
    for (int i = 0; i < s->nlayers; i++) {
        const fb_layer *l = &s->layers[i];
        const char *p[2] = {NULL, NULL}, *w[2] = {NULL, NULL};
        if (l->kind == FB_LAYER_TERRAIN) p[0] = l->terrain.mesh, w[0] = "mesh";
        if (l->kind == FB_LAYER_CONSTRAIN)
            p[0] = l->constrain.csv, w[0] = "csv", p[1] = l->constrain.plot, w[1] = "plot";
        for (int k = 0; k < 2; k++)
            if (p[k] && p[k][0] && n < max) paths[n] = p[k], what[n++] = w[k];
    }
    return n;
}

fb_result fb_scene_drop_outputs(const char *text, char **out, char *dropped, size_t size)
{
    dropped[0] = 0;
    *out = NULL;
    json_t *root = json_loads(text, 0, NULL);
    if (!root) return fb_fail(FB_ERR_INPUT, "the stored scene is not JSON");
    json_t *layers = json_object_get(root, "layers");
    for (size_t i = 0; i < json_array_size(layers); i++) {
        json_t *l = json_array_get(layers, i);
        const char *type = json_string_value(json_object_get(l, "type"));
        const char *name = json_string_value(json_object_get(l, "name"));
        const keyspec *keys;
        int nk;
        if (!type || !kind_keys(type, &keys, &nk)) continue;
        for (int k = 0; k < nk; k++) {
            const char *v = keys[k].type == T_OUTPUT ? json_string_value(json_object_get(l, keys[k].key)) : NULL;
            if (!v) continue;
            snprintf(dropped + strlen(dropped), size - strlen(dropped), "%slayers.%s.%s=%s", dropped[0] ? ", " : "",
                     name ? name : "?", keys[k].key, v);
            json_object_del(l, keys[k].key);
        }
    }
    *out = json_dumps(root, JSON_COMPACT);
    json_decref(root);
    return *out ? FB_OK : fb_fail(FB_ERR_NOMEM, "out of memory");
}

void fb_scene_fini(fb_scene *s)
{
    if (!s) return;
    free(s->json);
    memset(s, 0, sizeof *s);
}

/* The showcase: a polar night sky (a warped Julia galaxy with turbulence), a terrain refined from a
 * small built-in survey (48 points over 1000 x 190 units, the hull's top edge a ridge, so the
 * terrain sits below the sky in the frame), and the paper's plant population in front. */
const char *fb_scene_default_json(void)
{
    return "{\n"
           "  \"size\": [1024, 512],\n"
           "  \"seed\": 7,\n"
           "  \"layers\": [\n"
           "    {\"type\": \"julia\", \"name\": \"sky\", \"mapping\": \"polar\", \"alpha\": [-0.3, 0], \"turbulence\": "
           "0.2,\n"
           "     \"palette\": \"nebula\", \"density\": 2.5, \"samples\": 4},\n"
           "    {\"type\": \"terrain\", \"name\": \"terrain\", \"insert\": 20000, \"hurst\": 0.85, \"bounds\": [0, "
           "1000, 0, 500],\n"
           "     \"points\": [\n"
           "      [0, 115, 29.1], [125, 143.7, 69.8], [250, 168, 96], [375, 184.3, 112.6], [500, 190, 85.3],\n"
           "      [625, 184.3, 82], [750, 168, 74.9], [875, 143.7, 38.7], [1000, 115, 7.1], [0, 0, 26.8],\n"
           "      [125, 0, 34.7], [250, 0, 50.3], [375, 0, 48.2], [500, 0, 46.2], [625, 0, 49.9],\n"
           "      [750, 0, 50.5], [875, 0, 24.9], [1000, 0, 11.7], [613.1, 132.6, 113.9], [771.6, 146, 98.1],\n"
           "      [720.7, 150.8, 109.8], [66.7, 61.5, 44.3], [907.9, 85.5, 29.8], [868.8, 24.2, 41.2],\n"
           "      [471.5, 51.8, 75.5], [540.3, 107.2, 114.7], [52.1, 33.2, 33.7], [297.1, 152.3, 128.5],\n"
           "      [744.5, 33.8, 79.1], [773.4, 30, 77.3], [608.1, 31, 75.4], [41.6, 101.3, 33.2],\n"
           "      [232.7, 41.3, 66.2], [943.8, 104.4, 18.7], [306.2, 160.5, 114.1], [536.1, 124.9, 112.5],\n"
           "      [228.4, 145.8, 106.5], [675.4, 163.6, 105.6], [862.2, 47.8, 42.4], [372.3, 37.2, 66.2],\n"
           "      [174, 18.7, 57.4], [317.3, 105.3, 125.6], [43.1, 81.3, 33.5], [350.9, 60.2, 91.1],\n"
           "      [793, 77.5, 99.7], [330.5, 86.8, 121.1], [688.3, 19, 71.5], [937.1, 12.5, 13]\n"
           "     ]},\n"
           "    {\"type\": \"ifs\", \"name\": \"plants\", \"preset\": \"population\", \"points\": 60000000, "
           "\"brightness\": 6,\n"
           "     \"bounds\": [-0.08, 1.06, -0.03, 0.54]}\n"
           "  ]\n"
           "}\n";
}

/* ---- command-line flags --------------------------------------------------------------------- */

static const keyspec *flag_spec(const char *kind, const char *flag, bool *scene_level)
{
    const keyspec *keys;
    int n;
    *scene_level = false;
    if (!strcmp(flag, "name") && !strcmp(kind, "ifs"))
        flag = "entry"; /* --file X.ifs --name ENTRY */
    else if (!strcmp(flag, "layer"))
        flag = "name";
    else if (!strcmp(flag, "rule") && !strcmp(kind, "lsystem"))
        flag = "rules"; /* --rule X=... (repeatable) */
    if (!strcmp(flag, "type") || !strcmp(flag, "layers")) return NULL;
    if (!strcmp(flag, "compression") || !strcmp(flag, "parts")) { /* the file's, not the layer's */
        *scene_level = true;
        return find_key(scene_keys, NKEYS(scene_keys), flag);
    }
    if (kind_keys(kind, &keys, &n)) {
        const keyspec *k = find_key(keys, n, flag);
        if (k) return k;
    }
    *scene_level = true;
    return find_key(scene_keys, NKEYS(scene_keys), flag);
}

int fb_scene_flag_arity(const char *kind, const char *flag)
{
    bool scene_level;
    if (!strcmp(flag, "float")) return 0;
    const keyspec *k = flag_spec(kind, flag, &scene_level);
    if (!k) return -1;
    return k->type == T_BOOL ? 0 : 1;
}

static bool parse_double(const char *s, double *out)
{
    char *end;
    errno = 0;
    *out = strtod(s, &end);
    return *s && !*end && errno == 0;
}

/* Converts one flag's text to the JSON value its key takes; logs and returns NULL on failure. */
static json_t *flag_value(const keyspec *k, const char *flag, const char *s)
{
    double a, b;
    char *end;
    switch (k->type) {
    case T_INT: {
        errno = 0;
        long long x = strtoll(s, &end, 10);
        if (*s && *end && !errno && parse_double(s, &a) && a == floor(a) && fabs(a) <= 9007199254740992.0)
            return json_integer((json_int_t)a); /* 1e9: an integer written in exponent form */
        if (!*s || *end || errno) {
            fb_fail(FB_ERR_USAGE, "--%s: expected an integer, found \"%s\"", flag, s);
            return NULL;
        }
        return json_integer(x);
    }
    case T_NUM:
        if (!parse_double(s, &a) || !isfinite(a)) {
            fb_fail(FB_ERR_USAGE, "--%s: expected a finite number, found \"%s\"", flag, s);
            return NULL;
        }
        return json_real(a);
    case T_VEC2: {
        const char *comma = strchr(s, ',');
        char first[64];
        if (!comma || comma - s >= 63) goto bad_vec;
        snprintf(first, sizeof first, "%.*s", (int)(comma - s), s);
        if (!parse_double(first, &a) || !parse_double(comma + 1, &b) || !isfinite(a) || !isfinite(b)) goto bad_vec;
        return json_pack("[ff]", a, b);
    bad_vec:
        fb_fail(FB_ERR_USAGE, "--%s: expected two finite numbers X,Y, found \"%s\"", flag, s);
        return NULL;
    }
    case T_SIZE: {
        errno = 0;
        long long w = strtoll(s, &end, 10);
        if (end == s || (*end != 'x' && *end != 'X') || errno) goto bad_size;
        const char *hs = end + 1;
        long long h = strtoll(hs, &end, 10);
        if (end == hs || *end || errno) goto bad_size;
        if (w < 1 || h < 1 || w > FB_MAX_DIM || h > FB_MAX_DIM) {
            fb_fail(FB_ERR_USAGE, "--%s: each side must be in 1..%d, found \"%s\"", flag, FB_MAX_DIM, s);
            return NULL;
        }
        return json_pack("[II]", (json_int_t)w, (json_int_t)h);
    bad_size:
        fb_fail(FB_ERR_USAGE, "--%s: expected WIDTHxHEIGHT such as 1024x512, found \"%s\"", flag, s);
        return NULL;
    }
    case T_NUMLIST: {
        json_t *arr = json_array();
        const char *q = s;
        for (int i = 0; i < k->count; i++) {
            char *e;
            double x = strtod(q, &e);
            if (e == q || !isfinite(x) || (i + 1 < k->count ? *e != ',' : *e != 0)) {
                json_decref(arr);
                fb_fail(FB_ERR_USAGE, "--%s: expected %d comma-separated finite numbers, found \"%s\"", flag, k->count,
                        s);
                return NULL;
            }
            json_array_append_new(arr, json_real(x));
            q = e + 1;
        }
        return arr;
    }
    case T_STOPS: {
        /* "t,r,g,b;t,r,g,b;...": the scene's [[t, r, g, b], ...] on one line */
        json_t *arr = json_array();
        const char *q = s;
        while (*q) {
            double t[4];
            for (int c = 0; c < 4; c++) {
                char *e;
                t[c] = strtod(q, &e);
                if (e == q || !isfinite(t[c]) || (c < 3 && *e != ',') || (c == 3 && *e != ';' && *e != 0)) {
                    json_decref(arr);
                    fb_fail(FB_ERR_USAGE, "--%s: expected stops t,r,g,b;t,r,g,b;..., found \"%s\"", flag, s);
                    return NULL;
                }
                q = *e ? e + 1 : e;
            }
            json_array_append_new(arr, json_pack("[ffff]", t[0], t[1], t[2], t[3]));
        }
        return arr;
    }
    case T_MAPS:
    case T_IFSREF: {
        /* "a,b,c,d,e,f[,p];..." or, for a condensation set, a preset name */
        if (k->type == T_IFSREF && !strncmp(s, "lsystem:", 8)) return json_pack("{ss}", "preset", s + 8);
        if (k->type == T_IFSREF && *s == '{') {
            json_t *obj = json_loads(s, JSON_REJECT_DUPLICATES, NULL);
            if (json_is_object(obj)) return obj;
            json_decref(obj);
            fb_fail(FB_ERR_USAGE, "--%s: expected a JSON object such as {\"preset\": \"tree\"}, found \"%s\"", flag, s);
            return NULL;
        }
        if (k->type == T_IFSREF && (isalpha((unsigned char)*s))) return json_string(s);
        json_t *arr = json_array();
        const char *q = s;
        while (*q) {
            json_t *m = json_array();
            for (int c = 0; c < 7; c++) {
                char *e;
                double x = strtod(q, &e);
                if (e == q || !isfinite(x) || (*e != ',' && *e != ';' && *e != 0) || (c == 6 && *e == ',')) {
                    json_decref(m);
                    json_decref(arr);
                    fb_fail(FB_ERR_USAGE, "--%s: expected maps a,b,c,d,e,f[,p];..., found \"%s\"", flag, s);
                    return NULL;
                }
                json_array_append_new(m, json_real(x));
                q = *e == ',' ? e + 1 : e;
                if (*e != ',') break;
            }
            json_array_append_new(arr, m);
            if (*q == ';') q++;
        }
        return arr;
    }
    case T_NAMES: { /* "iter,n,R,G,B": the names are checked with the scene */
        json_t *arr = json_array();
        for (const char *q = s;;) {
            const char *e = strchr(q, ',');
            size_t len = e ? (size_t)(e - q) : strlen(q);
            json_array_append_new(arr, json_stringn(q, len));
            if (!e) break;
            q = e + 1;
        }
        return arr;
    }
    case T_BOUNDS:
    case T_FRACS: {
        if (k->type == T_BOUNDS && !strcmp(s, "auto")) return json_string(s);
        json_t *arr = json_array();
        const char *q = s;
        while (*q) {
            char *e;
            double x = strtod(q, &e);
            if (e == q || !isfinite(x) || (*e != ',' && *e != 0)) {
                json_decref(arr);
                fb_fail(FB_ERR_USAGE, "--%s: expected comma-separated finite numbers%s, found \"%s\"", flag,
                        k->type == T_BOUNDS ? " XMIN,XMAX,YMIN,YMAX or auto" : "", s);
                return NULL;
            }
            json_array_append_new(arr, json_real(x));
            q = *e ? e + 1 : e;
        }
        return arr;
    }
    default:
        return json_string(s);
    }
}

fb_result fb_scene_from_flags(const char *kind, int argc, char **argv, char **json)
{
    fb_result rc = FB_OK;
    json_t *root = json_object(), *layer = json_object(), *layers = json_array();
    if (!root || !layer || !layers) {
        rc = fb_fail(FB_ERR_NOMEM, "out of memory");
        goto out;
    }
    json_object_set_new(layer, "type", json_string(kind));
    for (int i = 0; i < argc; i++) {
        const char *a = argv[i];
        if (strncmp(a, "--", 2) != 0) {
            rc = fb_fail(FB_ERR_USAGE, "%s: unexpected argument (flags start with --)", a);
            goto out;
        }
        const char *flag = a + 2;
        if (!strcmp(flag, "float") || !strcmp(flag, "half")) {
            json_object_set_new(layer, "half", json_boolean(!strcmp(flag, "half")));
            continue;
        }
        bool scene_level;
        const keyspec *k = flag_spec(kind, flag, &scene_level);
        if (!k) {
            rc = fb_fail(FB_ERR_USAGE, "--%s: unknown flag for `fractalbake %s` (see fractalbake %s --help)", flag,
                         kind, kind);
            goto out;
        }
        json_t *target = scene_level ? root : layer;
        json_t *val;
        if (k->type == T_RULES) { /* repeatable: each --rule adds one production */
            if (i + 1 >= argc) {
                rc = fb_fail(FB_ERR_USAGE, "--%s: missing value", flag);
                goto out;
            }
            json_t *list = json_object_get(layer, k->key);
            if (!list) json_object_set_new(layer, k->key, list = json_array());
            json_array_append_new(list, json_string(argv[++i]));
            continue;
        }
        if (k->type == T_BOOL) {
            val = json_true();
        } else {
            if (i + 1 >= argc) {
                rc = fb_fail(FB_ERR_USAGE, "--%s: missing value", flag);
                goto out;
            }
            val = flag_value(k, flag, argv[++i]);
            if (!val) {
                rc = FB_ERR_USAGE;
                goto out;
            }
        }
        json_object_set_new(target, k->key, val);
    }
    json_array_append_new(layers, layer);
    layer = NULL;
    json_object_set_new(root, "layers", layers);
    layers = NULL;
    *json = json_dumps(root, JSON_SORT_KEYS | JSON_REAL_PRECISION(17));
    if (!*json) rc = fb_fail(FB_ERR_NOMEM, "out of memory");
out:
    json_decref(layer);
    json_decref(layers);
    json_decref(root);
    return rc;
}

void fb_scene_print_keys(const char *kind, void (*print)(const char *line, void *user), void *user)
{
    const keyspec *keys;
    int n;
    char line[512];
    if (!kind_keys(kind, &keys, &n)) return;
    for (int pass = 0; pass < 2; pass++) {
        const keyspec *ks = pass ? scene_keys : keys;
        int nk = pass ? NKEYS(scene_keys) : n;
        for (int i = 0; i < nk; i++) {
            const keyspec *k = &ks[i];
            if (k->type == T_TYPE || k->type == T_LAYERS) continue;
            if (!pass && !strcmp(k->key, "compression")) continue; /* the flag sets the scene's (listed below) */
            char range[96] = "";
            if (k->type == T_INT || k->type == T_NUM)
                snprintf(range, sizeof range, " %s%g..%g%s", k->lo_open ? "(" : "[", k->lo, k->hi, "]");
            else if (k->type == T_ENUM)
                snprintf(range, sizeof range, " %s", k->enums);
            else if (k->type == T_NAMES)
                snprintf(range, sizeof range, " (comma list of %s)", k->enums);
            const char *flag = !strcmp(k->key, "name") ? "layer" : k->type == T_RULES ? "rule" : k->key;
            snprintf(line, sizeof line, "  --%-12s %s%s%s%s", flag, k->help, range, k->def ? "; default " : "",
                     k->def ? k->def : "");
            print(line, user);
        }
    }
}
