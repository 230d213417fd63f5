/*
 * The op layer: one channel NAME.Y computed per pixel, on the host, from channels of other layers
 * of the same strip (after them: the scene orders layers by their references). The arithmetic is in
 * double, rounded once to float, so the result depends only on the inputs' values.
 */
#include "../gen.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

typedef struct op_state {
    int plane[FB_OP_MAX_INPUTS + 1]; /* inputs, then the mask: index among all planes of a strip, or -1 */
    bool is_uint[FB_OP_MAX_INPUTS + 1];
} op_state;

fb_result fb_gen_op_init(fb_gen *g)
{
    const fb_layer *L = g->layer;
    g->nchannels = 1;
    snprintf(g->channel_names[0], sizeof g->channel_names[0], "%s.Y", L->name);
    g->channel_types[0] = L->half ? EXRIO_HALF : EXRIO_FLOAT;
    g->preview_channel = 0;
    g->host_op = true;
    op_state st;
    for (int k = 0; k <= FB_OP_MAX_INPUTS; k++) st.plane[k] = -1, st.is_uint[k] = false;
    memcpy(g->params, &st, sizeof st);
    return FB_OK;
}

fb_result fb_gen_op_resolve(fb_gen *g, const fb_gen *const *gens, const int *plane_offset)
{
    const fb_op_params *o = &g->layer->op;
    op_state st;
    memcpy(&st, g->params, sizeof st);
    for (int k = 0; k <= o->ninputs; k++) {
        const fb_ref *r = k < o->ninputs ? &o->inputs[k] : &o->mask;
        if (r->layer < 0 || (k == o->ninputs && o->op != FB_OP_MIX)) continue;
        const fb_gen *src = gens[r->layer];
        int c = fb_gen_channel_of(src, r->channel, g->layer->name, k < o->ninputs ? "input" : "mask");
        if (c < 0) return FB_ERR_INPUT;
        st.plane[k] = plane_offset[r->layer] + c;
        st.is_uint[k] = src->channel_types[c] == EXRIO_UINT;
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

void fb_gen_op_rows(const fb_gen *g, size_t count, const void *const *planes, float *out)
{
    const fb_op_params *o = &g->layer->op;
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
