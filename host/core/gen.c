#include "gen.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

const fb_gen_class *fb_gen_find(const char *name)
{
    if (!name) return NULL;
    for (int i = 0; fb_gen_list[i]; i++)
        if (!strcmp(fb_gen_list[i]->name, name)) return fb_gen_list[i];
    return NULL;
}

void fb_gen_names(char *out, size_t size)
{
    out[0] = 0;
    for (int i = 0; fb_gen_list[i]; i++)
        snprintf(out + strlen(out), size - strlen(out), "%s\"%s\"", i ? ", " : "", fb_gen_list[i]->name);
}

fb_result fb_gen_init(fb_gen *g, const fb_scene *scene, const fb_layer *layer)
{
    return fb_gen_init_run(g, scene, layer, &(fb_gen_run){{0, 0}, {0, 0}, false});
}

fb_result fb_gen_init_run(fb_gen *g, const fb_scene *scene, const fb_layer *layer, const fb_gen_run *run)
{
    memset(g, 0, sizeof *g);
    g->scene = scene;
    g->layer = layer;
    g->run = *run;
    g->store.preview_rgb = -1;
    if (!layer->cls) return fb_fail(FB_ERR_INTERNAL, "layer %s: no generator", layer->name);
    return layer->cls->init(g);
}

void fb_gen_fini(fb_gen *g)
{
    if (!g) return;
    if (g->fini) g->fini(g);
    g->fini = NULL;
    free(g->owned);
    g->owned = NULL;
    g->compute.shader.input = NULL;
}

void fb_gen_push(const fb_gen *g, int y0, int n, void *out)
{
    uint32_t strip[2] = {(uint32_t)y0, (uint32_t)n};
    memcpy(out, g->params, g->compute.shader.params_size);
    memcpy((uint8_t *)out + g->compute.shader.params_size, strip, sizeof strip);
}

int fb_gen_nplanes(const fb_gen *g)
{
    return g->compute.nkernel > 0 ? g->compute.nkernel : g->store.nchannels;
}

int fb_gen_plane_of(const fb_gen *g, int c)
{
    return g->compute.nkernel > 0 ? g->compute.kernel_of[c] : c;
}

bool fb_gen_plane_stored(const fb_gen *g, int k)
{
    for (int c = 0; c < g->store.nchannels; c++)
        if (fb_gen_plane_of(g, c) == k) return true;
    return false;
}

void fb_gen_groups(const fb_gen *g, int n, uint32_t out[3])
{
    uint32_t per = g->compute.shader.per_invocation > 1 ? (uint32_t)g->compute.shader.per_invocation : 1u;
    out[0] = ((uint32_t)g->scene->width + 64 * per - 1) / (64 * per);
    out[1] = (uint32_t)n;
    out[2] = 1;
}

int fb_gen_channel_of(const fb_gen *src, const char *channel, const char *who, const char *what)
{
    char want[160], have[FB_GEN_MAX_CHANNELS * 40] = "";
    snprintf(want, sizeof want, "%s.%s", src->layer->name, channel[0] ? channel : "Y");
    int c = -1;
    for (int i = 0; i < src->store.nchannels; i++) {
        if (!strcmp(src->store.channel_names[i], want)) c = i;
        snprintf(have + strlen(have), sizeof have - strlen(have), "%s%s", i ? ", " : "",
                 strchr(src->store.channel_names[i], '.') + 1);
    }
    if (c < 0)
        fb_fail(FB_ERR_INPUT, "layer \"%s\": %s \"%s\": layer \"%s\" has no channel %s (channels: %s)", who, what, want,
                src->layer->name, channel[0] ? channel : "Y (name one)", have);
    return c;
}

fb_result fb_source_find(fb_source *out, const fb_gen *g, const fb_gen *const *gens, const fb_ref *r, const char *key,
                         const char *op_hint)
{
    const fb_gen *l = gens[r->layer];
    int c = fb_gen_channel_of(l, r->channel, g->layer->name, key);
    if (c < 0) return FB_ERR_INPUT;
    if (l->compute.host_rows)
        return fb_fail(FB_ERR_INPUT, "layer \"%s\": %s \"%s\": an op layer cannot be read yet (%s)", g->layer->name,
                       key, l->store.channel_names[c], op_hint ? op_hint : "bake it, or name the layer it reads");
    if (l->store.channel_types[c] == EXRIO_UINT)
        return fb_fail(FB_ERR_INPUT, "layer \"%s\": %s \"%s\": a channel of integers, not heights", g->layer->name, key,
                       l->store.channel_names[c]);
    *out = (fb_source){l, c};
    return FB_OK;
}

fb_result fb_source_read_grid(const fb_source *src, const fb_gen *g, const char *key, int cw, int ch, float *out)
{
    const fb_gen *l = src->gen;
    const fb_scene *sc = g->scene;
    const int W = sc->width, whole = cw == W && ch == sc->height, band = whole ? FB_SOURCE_BAND : 1;
    fb_result rc = FB_OK;
    void *planes[FB_GEN_MAX_CHANNELS] = {0};
    for (int k = 0; k < fb_gen_nplanes(l) && !rc; k++)
        if (fb_gen_plane_stored(l, k) && !(planes[k] = malloc((size_t)W * band * 4)))
            rc = fb_fail(FB_ERR_NOMEM, "out of memory");
    if (whole)
        for (int y0 = 0; y0 < sc->height && !rc; y0 += band) {
            int n = y0 + band <= sc->height ? band : sc->height - y0;
            l->compute.native_rows(l, y0, n, planes);
            memcpy(out + (size_t)y0 * W, planes[fb_gen_plane_of(l, src->channel)], (size_t)n * W * 4);
        }
    else
        for (int j = 0; j < ch && !rc; j++) {
            l->compute.native_rows(l, (int)((j + 0.5) * sc->height / ch), 1, planes);
            const float *row = planes[fb_gen_plane_of(l, src->channel)];
            for (int i = 0; i < cw; i++) out[(size_t)j * cw + i] = row[(int)((i + 0.5) * W / cw)];
        }
    for (int k = 0; k < FB_GEN_MAX_CHANNELS; k++) free(planes[k]);
    for (size_t i = 0; !rc && i < (size_t)cw * ch; i++)
        if (!isfinite(out[i]))
            rc = fb_fail(FB_ERR_INPUT, "layer \"%s\": %s \"%s\" has a NaN or infinite value at (%zu, %zu)%s",
                         g->layer->name, key, l->store.channel_names[src->channel], i % cw, i / cw,
                         whole ? "" : " of the coarse grid");
    return rc;
}

fb_result fb_source_read(const fb_source *src, const fb_gen *g, const char *key, float *out)
{
    return fb_source_read_grid(src, g, key, g->scene->width, g->scene->height, out);
}
