/*
 * The op layer: one channel NAME.Y computed per pixel, on the host, from channels of other layers
 * of the same strip (after them: the scene orders layers by their references). The arithmetic is in
 * double, rounded once to float, so the result depends only on the inputs' values.
 */
#include "gen_op.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

/* ---- the scene keys and their parser ---------------------------------------------------------- */

static const fb_keyspec op_keys[] = {
    {"type", FB_K_TYPE, 0, 0, false, NULL, NULL, "generator: \"op\"", FB_CORE},
    {"name", FB_K_NAME, 0, 0, false, NULL, "\"op\"", "layer name; the channel is NAME.Y", FB_CORE},
    {"op", FB_K_ENUM, 0, 0, false, "add|multiply|mix|remap|threshold", NULL,
     "add: sum of w_i x_i; multiply: product; mix: a + (b - a) m; remap: linear range change; threshold: 0/1 step",
     FB_FIELD(fb_op_params, op)},
    {"inputs", FB_K_REFS, 0, 0, false, NULL, NULL,
     "channels \"layer.channel\" (\"layer\": its Y) or numbers: 2-8 (add, multiply), 2 (mix), 1 (remap, threshold)",
     FB_OP_MAX_INPUTS, FB_FIELD(fb_op_params, inputs)},
    {"weights", FB_K_FRACS, -1e15, 1e15, false, NULL, NULL, "add: one weight per input (default all 1)",
     FB_OP_MAX_INPUTS, FB_FIELD(fb_op_params, weights)},
    {"mask", FB_K_REF, 0, 0, false, NULL, NULL, "mix: the mask m, clamped to [0, 1]", FB_FIELD(fb_op_params, mask)},
    {"from", FB_K_VEC2, -1e15, 1e15, false, NULL, NULL, "remap: the source range [lo, hi]",
     FB_FIELD(fb_op_params, from)},
    {"to", FB_K_VEC2, -1e15, 1e15, false, NULL, NULL, "remap: the target range [lo, hi] (default [0, 1])",
     FB_FIELD(fb_op_params, to)},
    {"clamp", FB_K_BOOL, 0, 0, false, NULL, NULL, "remap: clamp to the target range (default true)",
     FB_FIELD(fb_op_params, clamp)},
    {"level", FB_K_NUM, -1e15, 1e15, false, NULL, NULL, "threshold: 1 at and above the level, 0 below",
     FB_FIELD(fb_op_params, level)},
    {"width", FB_K_NUM, 0, 1e15, false, NULL, NULL, "threshold: a smooth step this wide around the level (default 0)",
     FB_FIELD(fb_op_params, width)},
    {"half", FB_K_BOOL, 0, 0, false, NULL, "false", "store Y as half (flags: --half, --float)", FB_CORE},
    FB_COMPRESSION_KEY,
};

static fb_result parse_op(const fb_vctx *v, const char *path, json_t *obj, const fb_scene *s, fb_layer *L)
{
    fb_op_params *o = (void *)L->params;
    fb_result rc = fb_schema_check(v, path, obj, op_keys, FB_NKEYS(op_keys), "an op layer", o);
    if (rc) return rc;
    char sub[256];
    const json_t *opj = json_object_get(obj, "op"), *in = json_object_get(obj, "inputs");
    if (!opj || !in) {
        snprintf(sub, sizeof sub, "%s.%s", path, opj ? "inputs" : "op");
        return fb_schema_error(v, sub, "required for an op layer (%s)",
                               opj ? "the channels it combines" : "add|multiply|mix|remap|threshold");
    }
    int idx = (int)o->op; /* the op's names in the order of fb_op_kind */
    o->ninputs = (int)json_array_size(in);
    static const int lo[] = {2, 2, 2, 1, 1}, hi[] = {8, 8, 2, 1, 1};
    static const char *const names[] = {"add", "multiply", "mix", "remap", "threshold"};
    if (o->ninputs < lo[idx] || o->ninputs > hi[idx]) {
        snprintf(sub, sizeof sub, "%s.inputs", path);
        if (lo[idx] == hi[idx])
            return fb_schema_error(v, sub, "%s takes %d input%s, found %d", names[idx], lo[idx],
                                   lo[idx] == 1 ? "" : "s", o->ninputs);
        return fb_schema_error(v, sub, "%s takes %d to %d inputs, found %d", names[idx], lo[idx], hi[idx], o->ninputs);
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
            return fb_schema_error(v, sub, "only for op %s, not %s", names[owner[k].op], names[idx]);
        }
    static const struct {
        const char *key;
        fb_op_kind op;
    } required[] = {{"mask", FB_OP_MIX}, {"from", FB_OP_REMAP}, {"level", FB_OP_THRESHOLD}};
    for (size_t k = 0; k < sizeof required / sizeof required[0]; k++)
        if (required[k].op == o->op && !json_object_get(obj, required[k].key)) {
            snprintf(sub, sizeof sub, "%s.%s", path, required[k].key);
            return fb_schema_error(v, sub, "required for op %s", names[idx]);
        }
    const json_t *w = json_object_get(obj, "weights");
    if (w && (int)json_array_size(w) != o->ninputs) {
        snprintf(sub, sizeof sub, "%s.weights", path);
        return fb_schema_error(v, sub, "expected one weight per input (%d), found %zu", o->ninputs, json_array_size(w));
    }
    for (int i = 0; !w && i < o->ninputs; i++) o->weights[i] = 1.0;
    if (!json_object_get(obj, "mask")) o->mask.layer = -1; /* no mask unless mix */
    if (o->op == FB_OP_REMAP && !json_object_get(obj, "to")) o->to[0] = 0, o->to[1] = 1;
    if (o->op == FB_OP_REMAP && !json_object_get(obj, "clamp")) o->clamp = true;
    if (o->op == FB_OP_REMAP && !(o->from[1] != o->from[0])) {
        snprintf(sub, sizeof sub, "%s.from", path);
        return fb_schema_error(v, sub, "the source range must not be empty ([lo, hi] with lo != hi)");
    }
    return FB_OK;
}

/* ---- the layer --------------------------------------------------------------------------------- */

typedef struct op_state {
    int plane[FB_OP_MAX_INPUTS + 1]; /* inputs, then the mask: index among all planes of a strip, or -1 */
    bool is_uint[FB_OP_MAX_INPUTS + 1];
} op_state;

static fb_result op_resolve(fb_gen *g, const fb_gen *const *gens, const int *plane_offset);
static void op_rows(const fb_gen *g, size_t count, const void *const *planes, float *out);

static fb_result op_init(fb_gen *g)
{
    const fb_layer *L = g->layer;
    g->store.nchannels = 1;
    snprintf(g->store.channel_names[0], sizeof g->store.channel_names[0], "%s.Y", L->name);
    g->store.channel_types[0] = L->half ? EXRIO_HALF : EXRIO_FLOAT;
    g->store.preview_channel = 0;
    g->resolve = op_resolve;
    g->compute.host_rows = op_rows;
    op_state st;
    for (int k = 0; k <= FB_OP_MAX_INPUTS; k++) st.plane[k] = -1, st.is_uint[k] = false;
    memcpy(g->params, &st, sizeof st);
    return FB_OK;
}

static fb_result op_resolve(fb_gen *g, const fb_gen *const *gens, const int *plane_offset)
{
    const fb_op_params *o = fb_layer_params(g->layer);
    op_state st;
    memcpy(&st, g->params, sizeof st);
    for (int k = 0; k <= o->ninputs; k++) {
        const fb_ref *r = k < o->ninputs ? &o->inputs[k] : &o->mask;
        if (r->layer < 0 || (k == o->ninputs && o->op != FB_OP_MIX)) continue;
        const fb_gen *src = gens[r->layer];
        int c = fb_gen_channel_of(src, r->channel, g->layer->name, k < o->ninputs ? "input" : "mask");
        if (c < 0) return FB_ERR_INPUT;
        st.plane[k] = plane_offset[r->layer] + c;
        st.is_uint[k] = src->store.channel_types[c] == EXRIO_UINT;
    }
    memcpy(g->params, &st, sizeof st);
    return FB_OK;
}

static double value_at(const op_state *st, const fb_ref *r, int k, const void *const *planes, size_t i)
{
    if (st->plane[k] < 0) return r->value;
    const void *p = planes[st->plane[k]];
    return st->is_uint[k] ? (double)((const uint32_t *)p)[i] : (double)((const float *)p)[i];
}

static void op_rows(const fb_gen *g, size_t count, const void *const *planes, float *out)
{
    const fb_op_params *o = fb_layer_params(g->layer);
    op_state st;
    memcpy(&st, g->params, sizeof st);
    for (size_t i = 0; i < count; i++) {
        double x = value_at(&st, &o->inputs[0], 0, planes, i), y;
        switch (o->op) {
        case FB_OP_ADD:
            y = o->weights[0] * x;
            for (int k = 1; k < o->ninputs; k++) y += o->weights[k] * value_at(&st, &o->inputs[k], k, planes, i);
            break;
        case FB_OP_MULTIPLY:
            y = x;
            for (int k = 1; k < o->ninputs; k++) y *= value_at(&st, &o->inputs[k], k, planes, i);
            break;
        case FB_OP_MIX: {
            double b = value_at(&st, &o->inputs[1], 1, planes, i);
            double m = value_at(&st, &o->mask, o->ninputs, planes, i);
            m = m < 0 ? 0 : m > 1 ? 1 : m; /* NaN stays NaN */
            y = x + (b - x) * m;
            break;
        }
        case FB_OP_REMAP: {
            double t = (x - o->from[0]) / (o->from[1] - o->from[0]);
            if (o->clamp) t = t < 0 ? 0 : t > 1 ? 1 : t;
            y = o->to[0] + (o->to[1] - o->to[0]) * t;
            break;
        }
        case FB_OP_THRESHOLD:
        default:
            if (o->width > 0) {
                double t = (x - (o->level - 0.5 * o->width)) / o->width;
                t = t < 0 ? 0 : t > 1 ? 1 : t;
                y = isnan(x) ? x : t * t * (3 - 2 * t);
            } else {
                y = isnan(x) ? x : x >= o->level ? 1.0 : 0.0;
            }
            break;
        }
        out[i] = (float)y;
    }
}

static int op_refs(fb_layer *L, fb_ref_slot *out)
{
    fb_op_params *o = (void *)L->params;
    int n = 0;
    for (int k = 0; k < o->ninputs; k++) {
        out[n] = (fb_ref_slot){&o->inputs[k], "", NULL};
        snprintf(out[n++].key, sizeof out[0].key, "inputs[%d]", k);
    }
    if (o->mask.layer != -1) out[n++] = (fb_ref_slot){&o->mask, "mask", NULL};
    return n;
}

/* The plan's cost model: seconds of one core of the reference machine (docs/scenes.md). */
static fb_result op_cost(const fb_scene *s, int layer, double *rows, double *total)
{
    double row = (double)s->width * (4.0e-9 /* a pixel */);
    *total = 0;
    for (int y = 0; y < s->height; y++) rows[y] = row, *total += row;
    return FB_OK;
}

const fb_gen_class fb_gen_op = {
    .name = "op",
    .synopsis = NULL,
    .summary = "a channel computed from other layers' channels",
    .what = "an op layer",
    .keys = op_keys,
    .nkeys = FB_NKEYS(op_keys),
    .params_size = sizeof(fb_op_params),
    .parse = parse_op,
    .refs = op_refs,
    .envmap_of_refs = true, /* pixel by pixel: an op of environment maps is one */
    .init = op_init,
    .share = FB_SHARE_BAND,
    .cost = op_cost,
    .example = "[{\"type\": \"fbm\", \"name\": \"a\"}, {\"type\": \"op\", \"name\": \"b\", \"op\": \"add\", "
               "\"inputs\": [\"a\", 1]}]",
    .tolerance = {0, 0}, /* exact arithmetic: the same bits as its inputs on every backend */
};
