/*
 * The scene engine's face towards the generators: the key types a schema table is written in, the
 * validation context, and the helpers a generator's parser uses. A generator (host/gen/NAME/layer.c)
 * declares its keys in one table; the engine checks every value against it, fills in the defaults,
 * turns flags into keys and prints --help from it, and writes each value into the field of the
 * generator's parameters that the key names (FB_FIELD); the generator's parse adds only the checks
 * and values that involve several keys.
 */
#ifndef FB_SCHEMA_H
#define FB_SCHEMA_H

#include "fb.h"
#include "palette.h"

#include <jansson.h>

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

/* The shapes a key's value may take. */
typedef enum fb_ktype {
    FB_K_INT,
    FB_K_NUM,
    FB_K_BOOL,
    FB_K_ENUM,
    FB_K_NAME,
    FB_K_VEC2,
    FB_K_SIZE,
    FB_K_LAYERS,
    FB_K_TYPE,
    FB_K_NUMLIST,
    FB_K_STOPS,
    FB_K_STRING, /* any non-empty string (an entry name, a text) */
    FB_K_OUTPUT, /* a file this layer writes besides the EXR: never taken from a stored scene (--from) */
    FB_K_PATH,   /* a file this layer reads (a non-empty string) */
    FB_K_BOUNDS, /* "auto" or [xmin, xmax, ymin, ymax] */
    FB_K_FRACS,  /* 1..count numbers in [lo, hi] */
    FB_K_NAMES,  /* 1..32 distinct names from `enums` (flag: a comma list) */
    FB_K_RULES,  /* up to count strings, each accepted by `check` (flag: repeatable) */
    FB_K_REF,    /* another layer's channel "layer.channel" (or "layer": its Y), or a number */
    FB_K_REFS,   /* 1..count of FB_K_REF */
    FB_K_CUSTOM, /* a shape of the generator's own: keyspec.value says how to check and read it */
} fb_ktype;

struct fb_keyspec;
struct fb_vctx;

/* The C type of the parameter a key fills, derived from the field by FB_FIELD. The schema check
 * writes a given (or defaulted) value there; an absent key leaves the field as it was (zero). */
typedef enum fb_kfield {
    FB_F_NONE = 0, /* no field: refused by fb_schema_declared (a key nobody reads) */
    FB_F_CORE,     /* read by the scene engine or a core helper: type, name, half, compression, the
                    * heightmap keys, the palette and relief keys (fb_schema_palette, fb_schema_relief) */
    FB_F_PARSE,    /* read whole by the class's parse before the check: a preset that stands for other keys */
    FB_F_DOUBLE,   /* a number (or an integer) */
    FB_F_INT,      /* an integer; an enum's index */
    FB_F_UNSIGNED, /* an enum's index; the names of FB_K_NAMES as bits, 1u << index */
    FB_F_U64,      /* an integer */
    FB_F_BOOL,     /* a bool; a two-valued enum, true for its second value */
    FB_F_DOUBLES,  /* double[n]: a vec2, a number list, fractions, bounds (left as they are for "auto") */
    FB_F_CHARS,    /* char[n]: a string or an enum's name (longer ones refused); a value of another
                    * shape (a custom key's inline list) leaves it "" */
    FB_F_REF,      /* fb_ref: another layer's channel (resolved after parsing) or a number */
    FB_F_REFS,     /* fb_ref[n]: a list of them */
    FB_F_VALUE,    /* a type of the generator's own: keyspec.value->read fills it */
} fb_kfield;

/* The field of params struct T a key fills: `{"octaves", FB_K_INT, ..., FB_FIELD(fb_fbm_params, octaves)}`. */
#define FB_FIELD_KIND(x)                                                                                               \
    _Generic((x),                                                                                                      \
        double: FB_F_DOUBLE,                                                                                           \
        int: FB_F_INT,                                                                                                 \
        unsigned: FB_F_UNSIGNED,                                                                                       \
        uint64_t: FB_F_U64,                                                                                            \
        bool: FB_F_BOOL,                                                                                               \
        double *: FB_F_DOUBLES,                                                                                        \
        char *: FB_F_CHARS,                                                                                            \
        struct fb_ref: FB_F_REF,                                                                                       \
        struct fb_ref *: FB_F_REFS,                                                                                    \
        default: FB_F_VALUE)
#define FB_FIELD(T, f) .field = FB_FIELD_KIND(((T *)0)->f), .off = offsetof(T, f), .size = sizeof(((T *)0)->f)
#define FB_CORE        .field = FB_F_CORE
#define FB_PARSE       .field = FB_F_PARSE

/* A value type of a generator's own (FB_K_CUSTOM): an IFS's affine maps, survey points, constraint
 * points. The generator defines it in its folder; the engine calls it for checks and flags. */
typedef struct fb_kvalue {
    /* Checks value j of key k at `path` (report with fb_schema_error). */
    fb_result (*check)(const struct fb_vctx *v, const char *path, const struct fb_keyspec *k, json_t *j);
    /* The JSON value a flag's text stands for; on bad text logs one line naming --flag (fb_fail with
     * FB_ERR_USAGE) and returns NULL. NULL: the text is the value, a string. */
    json_t *(*from_flag)(const struct fb_keyspec *k, const char *flag, const char *text);
    /* Whether a string value names a file the layer reads (in a scene file, relative to the file's folder); NULL:
     * never. */
    bool (*names_file)(const char *text);
    /* Reads checked value j into the key's field (FB_F_VALUE); an error is logged (fb_schema_error). */
    fb_result (*read)(const struct fb_vctx *v, const char *path, const json_t *j, void *field);
} fb_kvalue;

typedef struct fb_keyspec {
    const char *key;
    fb_ktype type;
    double lo, hi;
    bool lo_open;      /* lo < x rather than lo <= x */
    const char *enums; /* "a|b|c" for FB_K_ENUM, FB_K_NAMES, and value types naming presets */
    const char *def;   /* the default as JSON text; NULL: none (optional key, or required) */
    const char *help;
    int count;          /* FB_K_NUMLIST: how many numbers; MAPS, FRACS, RULES, REFS: at most how many */
    const char *flag;   /* its command-line flag when not --KEY ("rule" for rules); "name" is --layer */
    const char *unless; /* "a|b": the default is not filled in when one of these keys is given */
    /* FB_K_RULES: checks one element; false with a message in msg */
    bool (*check)(const char *text, char *msg, size_t size);
    const fb_kvalue *value; /* FB_K_CUSTOM: its type; with FB_F_VALUE, its read */
    /* The parameter it fills (FB_FIELD): with the name, type and range above, what a caller needs to
     * set any numeric key of a layer without knowing the generator. */
    fb_kfield field;
    size_t off, size; /* offsetof and sizeof the field in the params struct */
} fb_keyspec;

#define FB_NKEYS(a) ((int)(sizeof(a) / sizeof((a)[0])))

/* Where the values come from, for messages. */
typedef struct fb_vctx {
    const char *origin; /* file name, or NULL for the command line */
    const char *text;
    /* --set overrides: what the user typed, and the key path each one set ("layers[0].c") */
    const char *const *sets;
    char (*set_paths)[256];
    int nsets;
    const struct fb_gen_class *cls; /* the command line's generator (its flags' names), or NULL */
} fb_vctx;

/* Logs "FILE:LINE: PATH: message" (file), "--set S: message" or "--FLAG: message" (command line) and
 * returns FB_ERR_INPUT (FB_ERR_USAGE for the command line). */
fb_result fb_schema_error(const fb_vctx *v, const char *path, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));

/* "int", "number", "maps"...: a key's type, for listings (fractalbake generators). */
const char *fb_ktype_name(const fb_keyspec *k);

/* The key named `key` of a table, or NULL. */
const fb_keyspec *fb_key_find(const fb_keyspec *keys, int n, const char *key);

/* The command-line flag of key k, without the dashes ("layer" for "name"). */
const char *fb_key_flag(const fb_keyspec *k);

/* Checks every key of `obj` against `keys`, fills in the defaults, then writes each key that is given
 * (or defaulted) into its field of `params` (NULL: none). `what` names the object in messages ("an
 * fbm layer"). */
fb_result fb_schema_check(const fb_vctx *v, const char *path, json_t *obj, const fb_keyspec *keys, int n,
                          const char *what, void *params);
/* Whether every key of a table is read, into a field of a params struct of params_size bytes that
 * holds its value or by the engine (FB_F_CORE); false with the first key that is not in msg. */
bool fb_schema_declared(const fb_keyspec *keys, int n, size_t params_size, char *msg, size_t size);
/* Checks one value against its key. */
fb_result fb_schema_check_value(const fb_vctx *v, const char *path, const fb_keyspec *k, json_t *j);

/* The colour map keys shared by the layers that have one: palette, cosine, stops. */
fb_result fb_schema_palette(const fb_vctx *v, const char *path, const json_t *obj, fb_palette_spec *pal);

/* The keys of a height layer's colour by height under a light (fb_relief_spec, palette.h), for its
 * key table; fb_schema_relief reads them (light, ambient and colour-range only with a palette). */
/* clang-format off */
#define FB_RELIEF_KEYS                                                                                                  \
    {"palette", FB_K_ENUM, 0, 0, false, FB_PALETTE_NAMES, NULL,                                                         \
     "also store R, G, B: the surface lit and coloured by this map by height (or cosine, stops)", FB_CORE},             \
    {"cosine", FB_K_NUMLIST, -10, 10, false, NULL, NULL,                                                                \
     "colour by height, a cosine palette a + b cos(2 pi (c t + d)): 12 numbers aR,aG,aB,bR,bG,bB,cR,cG,cB,dR,dG,dB",    \
     12, FB_CORE},                                                                                                      \
    {"stops", FB_K_STOPS, 0, 1e3, false, NULL, NULL,                                                                    \
     "colour by height, a gradient: [[t, r, g, b], ...], t from 0 (lowest) to 1 (highest) (flag: \"t,r,g,b;...\")",     \
     FB_CORE},                                                                                                          \
    {"light", FB_K_VEC2, -360, 360, false, NULL, NULL,                                                                  \
     "with a palette: the light's azimuth (clockwise from north, y up) and altitude, degrees (default 315,45)",         \
     FB_CORE},                                                                                                          \
    {"ambient", FB_K_NUM, 0, 1, false, NULL, NULL, "with a palette: the light that reaches every slope (default 0.2)",  \
     FB_CORE},                                                                                                          \
    {"colour-range", FB_K_VEC2, -1e15, 1e15, false, NULL, NULL,                                                         \
     "with a palette: the heights at its two ends (default: the layer's lowest and highest)", FB_CORE}
/* clang-format on */
struct fb_relief_spec;
fb_result fb_schema_relief(const fb_vctx *v, const char *path, const json_t *obj, struct fb_relief_spec *out);

/* For fb_kvalue.names_file: every string is a file name. */
bool fb_string_names_file(const char *text);

/* Readers of checked values. */
double fb_json_num(const json_t *obj, const char *key);
bool fb_json_bool(const json_t *obj, const char *key);
void fb_json_vec2(const json_t *obj, const char *key, double out[2]);
/* A short rendering of a JSON value for messages. */
void fb_json_show(const json_t *j, char *buf, size_t n);
/* The index of s in "a|b|c". */
bool fb_enum_index(const char *enums, const char *s, int *idx);

#endif
