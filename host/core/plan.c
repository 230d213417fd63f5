/*
 * Splitting a bake over N tasks: the cost model and the plan. See plan.h.
 */
#include "plan.h"

#include "gen.h"
#include "jsonout.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ---- the cost model -------------------------------------------------------------------------- */

/* Seconds of one core of the reference machine (a 2-core AMD EPYC Zen 4, Mesa 22.3 lavapipe; the
 * calibration is in docs/scenes.md) for each unit of work, written EXR channels included. */
#define C_STARTUP FB_PLAN_STARTUP
#define BUDGET    1.10 /* a split may cost this much of one bake, start-ups included */

/* Layer i's cost in *total, from its class (gen.h: cost); a banded layer's also per row, into
 * rows[] (zeroed here). */
static fb_result layer_cost(const fb_scene *s, int i, double *rows, double *total)
{
    const fb_layer *L = &s->layers[i];
    for (int y = 0; y < s->height; y++) rows[y] = 0;
    *total = 0;
    if (!L->cls->cost) return fb_fail(FB_ERR_INTERNAL, "generator %s has no cost model for the plan", L->cls->name);
    fb_result rc = L->cls->cost(s, i, rows, total);
    if (!rc && !(*total >= 0 && isfinite(*total)))
        rc = fb_fail(FB_ERR_INTERNAL, "generator %s: the cost of layer %s is %g", L->cls->name, L->name, *total);
    return rc;
}

/* ---- units ----------------------------------------------------------------------------------- */

static int find(int *parent, int i)
{
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
}

typedef struct unit {
    uint32_t layers;
    double seconds;
    bool has_points; /* a layer of a points-split class */
} unit;

/* A candidate split: b bands, pp points parts, and the whole-image tasks' layers and loads (the
 * points tasks first). */
typedef struct layout {
    int b, pp, m; /* m: tasks in all */
    int nbins;
    uint32_t bins[FB_PLAN_MAX_TASKS];
    double load[FB_PLAN_MAX_TASKS];
    double total, longest;
} layout;

/* Everything in one task, whole: one bake. */
static void one_task(const fb_plan *p, const fb_scene *s, layout *l)
{
    memset(l, 0, sizeof *l);
    l->bins[0] = (uint32_t)((1ull << s->nlayers) - 1);
    l->load[0] = p->one - p->startup;
    l->nbins = 1, l->m = 1;
    l->total = l->longest = p->one;
}

/* The layout for target tau (see fb_plan_make); false when it needs more than ntasks tasks. wu[0 ..
 * nwhole) are the whole units (the banded units follow them, unused here). */
static bool lay_out(const fb_scene *s, double startup, double tau, int ntasks, double band_total, uint32_t band_mask,
                    double points_total, uint32_t points_mask, double pixels, double part_pixel, const unit *wu,
                    int nwhole, layout *l)
{
    memset(l, 0, offsetof(layout, bins));
    if (band_mask) {
        double b = ceil(band_total / tau - 1e-9);
        l->b = b < 1 ? 1 : b > s->height ? s->height : (int)b;
    }
    unit items[FB_MAX_LAYERS + 1];
    int n = 0;
    for (int u = 0; u < nwhole; u++) items[n++] = wu[u];
    double part_px = pixels * part_pixel;
    if (points_mask) {
        if (points_total <= tau) {
            items[n++] = (unit){points_mask, points_total, true};
        } else {
            double pp = tau > 2 * part_px ? ceil(points_total / (tau - part_px) - 1e-9) : 256;
            l->pp = pp < 2 ? 2 : pp > 256 ? 256 : (int)pp;
        }
    }
    if (l->b + l->pp > ntasks) return false;
    l->nbins = l->pp;
    for (int t = 0; t < l->pp; t++) l->bins[t] = points_mask, l->load[t] = points_total / l->pp + part_px;
    /* first fit, largest first (stable) */
    int order[FB_MAX_LAYERS + 1];
    for (int k = 0; k < n; k++) order[k] = k;
    for (int a = 1; a < n; a++)
        for (int c = a; c > 0 && items[order[c]].seconds > items[order[c - 1]].seconds; c--) {
            int tmp = order[c];
            order[c] = order[c - 1], order[c - 1] = tmp;
        }
    for (int k = 0; k < n; k++) {
        const unit *u = &items[order[k]];
        int t = 0;
        while (t < l->nbins && l->load[t] + u->seconds > tau + 1e-9) t++;
        if (t == l->nbins) {
            if (l->b + l->nbins + 1 > ntasks) return false;
            l->bins[t] = 0, l->load[t] = 0;
            l->nbins++;
        }
        l->bins[t] |= u->layers;
        l->load[t] += u->seconds;
    }
    l->m = l->b + l->nbins;
    l->total = band_total + l->m * startup;
    l->longest = l->b ? band_total / l->b + startup : 0;
    for (int t = 0; t < l->nbins; t++) {
        l->total += l->load[t];
        if (l->load[t] + startup > l->longest) l->longest = l->load[t] + startup;
    }
    return true;
}

fb_result fb_plan_make(const fb_scene *s, int ntasks, double startup, fb_plan *p)
{
    if (ntasks < 1 || ntasks > FB_PLAN_MAX_TASKS)
        return fb_fail(FB_ERR_USAGE, "tasks: %d is not in 1..%d", ntasks, FB_PLAN_MAX_TASKS);
    memset(p, 0, sizeof *p);
    p->ntasks = ntasks;
    p->startup = startup >= 0 ? startup : C_STARTUP;
    double *rows = calloc((size_t)s->height, sizeof *rows), *band_rows = calloc((size_t)s->height + 1, sizeof *rows);
    fb_result rc = !rows || !band_rows ? fb_fail(FB_ERR_NOMEM, "out of memory") : FB_OK;
    /* the units: layers joined by their references */
    int parent[FB_MAX_LAYERS];
    for (int i = 0; i < s->nlayers; i++) parent[i] = i;
    for (int i = 0; i < s->nlayers && !rc; i++) {
        fb_ref_slot slots[FB_MAX_REFS];
        fb_layer *L = (fb_layer *)&s->layers[i]; /* refs() lists, it does not change */
        int nr = L->cls->refs ? L->cls->refs(L, slots) : 0;
        for (int k = 0; k < nr; k++)
            if (slots[k].ref->layer >= 0) parent[find(parent, i)] = find(parent, slots[k].ref->layer);
    }
    /* each layer's kind by its generator alone */
    fb_share kind[FB_MAX_LAYERS];
    for (int i = 0; i < s->nlayers && !rc; i++)
        kind[i] = s->layers[i].heightmap[0] ? FB_SHARE_WHOLE : s->layers[i].cls->share;
    /* a unit is banded when all its layers are; split by points when it is one chaos game alone */
    unit units[FB_MAX_LAYERS];
    int nunits = 0, unit_of[FB_MAX_LAYERS];
    for (int i = 0; i < s->nlayers && !rc; i++) {
        int r = find(parent, i), u = -1;
        for (int k = 0; k < i && u < 0; k++)
            if (find(parent, k) == r) u = unit_of[k];
        if (u < 0) u = nunits++, units[u] = (unit){0};
        unit_of[i] = u;
        units[u].layers |= 1u << i;
        units[u].has_points |= s->layers[i].cls->share == FB_SHARE_POINTS;
    }
    fb_share ushare[FB_MAX_LAYERS];
    for (int u = 0; u < nunits; u++) {
        bool all_band = true;
        int n = 0;
        for (int i = 0; i < s->nlayers; i++)
            if (units[u].layers >> i & 1) all_band = all_band && kind[i] == FB_SHARE_BAND, n++;
        ushare[u] = all_band ? FB_SHARE_BAND : n == 1 && units[u].has_points ? FB_SHARE_POINTS : FB_SHARE_WHOLE;
    }
    /* a chaos game inside a whole unit (an op using it) keeps every game whole: a task's points part
     * would apply to it too */
    bool can_split_points = true;
    for (int u = 0; u < nunits; u++)
        can_split_points = can_split_points && !(ushare[u] == FB_SHARE_WHOLE && units[u].has_points);
    uint32_t band_mask = 0, points_mask = 0;
    for (int u = 0; u < nunits; u++) {
        if (ushare[u] == FB_SHARE_BAND) band_mask |= units[u].layers;
        if (ushare[u] == FB_SHARE_POINTS && can_split_points) points_mask |= units[u].layers;
    }
    /* each layer's cost, once; the banded layers' per row, cumulated */
    double part_pixel = 0; /* what each points part pays per pixel: its costliest image */
    for (int i = 0; i < s->nlayers && !rc; i++) {
        rc = layer_cost(s, i, rows, &p->layer_seconds[i]);
        if (points_mask >> i & 1 && s->layers[i].cls->part_pixel_seconds > part_pixel)
            part_pixel = s->layers[i].cls->part_pixel_seconds;
        units[unit_of[i]].seconds += p->layer_seconds[i];
        for (int y = 0; y < s->height && band_mask >> i & 1; y++) band_rows[y + 1] += rows[y];
    }
    for (int y = 0; y < s->height; y++) band_rows[y + 1] += band_rows[y];
    double band_total = band_rows[s->height], points_total = 0;
    for (int u = 0; u < nunits; u++)
        if (units[u].layers & points_mask) points_total += units[u].seconds;
    /* the whole units (banded ones too, for splits with no band), largest first */
    unit wu[FB_MAX_LAYERS];
    int nwu = 0, nwhole_only = 0;
    for (int u = 0; u < nunits; u++)
        if (ushare[u] == FB_SHARE_WHOLE || (ushare[u] == FB_SHARE_POINTS && !can_split_points)) wu[nwu++] = units[u];
    nwhole_only = nwu;
    for (int u = 0; u < nunits; u++)
        if (ushare[u] == FB_SHARE_BAND) wu[nwu++] = units[u];
    double pixels = (double)s->width * s->height;
    double one = p->startup;
    for (int i = 0; i < s->nlayers; i++) one += p->layer_seconds[i];
    p->one = one;

    /* The search, over the longest task's target tau: ceil(band / tau) bands, the chaos games in
     * ceil(points / tau) parts (whole when they fit in one), the whole units packed first-fit
     * decreasing onto the points tasks and new tasks of capacity tau. Of the layouts within the
     * budget, the one whose longest task is shortest, then the one with fewest tasks; one task
     * doing everything is always within it. */
    layout best = {0}, cur;
    one_task(p, s, &best);
    double tau_min = 0;
    for (int u = 0; u < nwhole_only; u++) tau_min = wu[u].seconds > tau_min ? wu[u].seconds : tau_min;
    if (tau_min < one / ntasks / 2) tau_min = one / ntasks / 2;
    for (double tau = tau_min; tau <= one * 1.0001 && !rc; tau *= 1.01) {
        if (!lay_out(s, p->startup, tau, ntasks, band_total, band_mask, points_total, points_mask, pixels, part_pixel,
                     wu, nwhole_only, &cur))
            continue;
        bool fits = cur.total <= BUDGET * one + 1e-9;
        if (fits && (cur.longest < best.longest - 1e-9 || (cur.longest <= best.longest + 1e-9 && cur.m < best.m)))
            best = cur;
    }
    if (!rc) {
        /* laid out: bands top to bottom, then the points tasks, then the others */
        int b = best.b;
        p->nbands = b;
        p->nparts = best.pp;
        p->nactive = best.m;
        int y = 0;
        for (int k = 0; k < b; k++) { /* band k ends where the cumulated cost passes (k+1)/b of it */
            fb_task *t = &p->tasks[k];
            int y1 = y + 1;
            double target = band_total * (k + 1) / b;
            while (y1 < s->height && band_rows[y1] < target - 1e-12) y1++;
            if (y1 > s->height - (b - 1 - k)) y1 = s->height - (b - 1 - k); /* a row for each band left */
            if (k == b - 1) y1 = s->height;
            *t = (fb_task){.band = true, .y0 = y, .y1 = y1, .layers = band_mask};
            t->seconds = band_rows[y1] - band_rows[y] + p->startup;
            y = y1;
        }
        for (int t = 0; t < best.m - b; t++) {
            fb_task *tk = &p->tasks[b + t];
            *tk = (fb_task){.layers = best.bins[t], .seconds = best.load[t] + p->startup};
            if (t < best.pp) tk->points = points_mask, tk->part = t + 1, tk->nparts = best.pp;
        }
        p->total = 0, p->longest = 0;
        for (int t = 0; t < p->nactive; t++) {
            p->total += p->tasks[t].seconds;
            if (p->tasks[t].seconds > p->longest) p->longest = p->tasks[t].seconds;
        }
        for (int i = 0; i < s->nlayers; i++)
            p->share[i] = (band_mask >> i & 1) && b > 0           ? FB_SHARE_BAND
                          : (points_mask >> i & 1) && best.pp > 0 ? FB_SHARE_POINTS
                                                                  : FB_SHARE_WHOLE;
    }
    free(rows);
    free(band_rows);
    return rc;
}

/* ---- text ------------------------------------------------------------------------------------ */

static void names_of(const fb_scene *s, uint32_t mask, char *out, size_t size)
{
    out[0] = 0;
    for (int i = 0; i < s->nlayers; i++)
        if (mask >> i & 1)
            snprintf(out + strlen(out), size - strlen(out), "%s%s", out[0] ? ", " : "", s->layers[i].name);
}

void fb_plan_describe(const fb_scene *s, const fb_task *t, char *out, size_t size)
{
    char a[FB_MAX_LAYERS * 66], b[FB_MAX_LAYERS * 66];
    if (t->band) {
        names_of(s, t->layers, a, sizeof a);
        snprintf(out, size, "rows %d-%d of %s", t->y0, t->y1 - 1, a);
        return;
    }
    names_of(s, t->layers & ~t->points, a, sizeof a);
    names_of(s, t->points, b, sizeof b);
    if (t->points)
        snprintf(out, size, "%s%s%spoints part %d/%d of %s", a[0] ? "whole " : "", a, a[0] ? "; " : "", t->part,
                 t->nparts, b);
    else
        snprintf(out, size, "whole %s", a);
}

static json_t *names_json(const fb_scene *s, uint32_t mask)
{
    json_t *a = json_array();
    for (int i = 0; i < s->nlayers; i++)
        if (mask >> i & 1) json_array_append_new(a, json_string(s->layers[i].name));
    return a;
}

const char *fb_plan_share_name(fb_share share)
{
    return share == FB_SHARE_BAND ? "bands" : share == FB_SHARE_POINTS ? "points parts" : "whole";
}

char *fb_plan_json(const fb_scene *s, const fb_plan *p, bool pretty)
{
    json_t *o = json_object(), *layers = json_array(), *tasks = json_array();
    json_object_set_new(o, "tasks", json_integer(p->ntasks));
    json_object_set_new(o, "active", json_integer(p->nactive));
    json_object_set_new(o, "numbering", json_string("0-based, like SLURM_ARRAY_TASK_ID"));
    json_object_set_new(o, "startup", json_real(p->startup));
    json_object_set_new(o, "bands", json_integer(p->nbands));
    json_object_set_new(o, "points_parts", json_integer(p->nparts));
    json_object_set_new(o, "size", json_pack("[ii]", s->width, s->height));
    for (int i = 0; i < s->nlayers; i++)
        json_array_append_new(layers,
                              json_pack("{sssssssf}", "name", s->layers[i].name, "type", s->layers[i].cls->name,
                                        "split", fb_plan_share_name(p->share[i]), "seconds", p->layer_seconds[i]));
    json_object_set_new(o, "layers", layers);
    for (int k = 0; k < p->nactive; k++) {
        const fb_task *t = &p->tasks[k];
        json_t *j = json_pack("{si}", "task", k);
        if (t->band) json_object_set_new(j, "rows", json_pack("[ii]", t->y0, t->y1));
        json_object_set_new(j, "layers", names_json(s, t->layers));
        if (t->points) {
            json_object_set_new(j, "points_part", json_pack("[ii]", t->part, t->nparts));
            json_object_set_new(j, "points_layers", names_json(s, t->points));
        }
        json_object_set_new(j, "seconds", json_real(t->seconds));
        json_array_append_new(tasks, j);
    }
    json_object_set_new(o, "task_list", tasks);
    json_object_set_new(
        o, "model_seconds",
        json_pack("{sfsfsfsf}", "startup", p->startup, "one_bake", p->one, "split", p->total, "longest", p->longest));
    char *text = fb_json_dumps(o, pretty ? 2 : 0);
    json_decref(o);
    return text;
}

static uint32_t mask_of(const fb_scene *s, const json_t *names, bool *ok)
{
    uint32_t m = 0;
    size_t k;
    const json_t *v;
    if (!json_is_array(names)) *ok = false;
    json_array_foreach(names, k, v)
    {
        int found = -1;
        for (int i = 0; i < s->nlayers && json_is_string(v); i++)
            if (!strcmp(s->layers[i].name, json_string_value(v))) found = i;
        if (found < 0)
            *ok = false;
        else
            m |= 1u << found;
    }
    return m;
}

/* An integer of a stored plan, range-checked (a "tasks" of 4294967302 is not 6): *ok goes false on
 * anything else. */
static int int_of(const json_t *v, int lo, int hi, bool *ok)
{
    json_int_t x = json_integer_value(v);
    if (!json_is_integer(v) || x < lo || x > hi) {
        *ok = false;
        return lo;
    }
    return (int)x;
}

fb_result fb_plan_parse(const char *text, const fb_scene *s, fb_plan *p)
{
    memset(p, 0, sizeof *p);
    json_error_t err;
    json_t *o = json_loads(text, 0, &err);
    bool ok = o != NULL;
    p->ntasks = int_of(json_object_get(o, "tasks"), 1, FB_PLAN_MAX_TASKS, &ok);
    p->nactive = int_of(json_object_get(o, "active"), 1, FB_PLAN_MAX_TASKS, &ok);
    p->nbands = int_of(json_object_get(o, "bands"), 0, FB_PLAN_MAX_TASKS, &ok);
    p->nparts = int_of(json_object_get(o, "points_parts"), 0, FB_PLAN_MAX_TASKS, &ok);
    p->startup = json_number_value(json_object_get(o, "startup"));
    const json_t *tl = json_object_get(o, "task_list");
    ok = ok && p->ntasks >= 1 && p->ntasks <= FB_PLAN_MAX_TASKS && p->nactive >= 1 && p->nactive <= p->ntasks &&
         json_is_array(tl) && json_array_size(tl) == (size_t)p->nactive;
    for (int k = 0; ok && k < p->nactive; k++) {
        const json_t *j = json_array_get(tl, (size_t)k), *r = json_object_get(j, "rows"),
                     *pp = json_object_get(j, "points_part");
        fb_task *t = &p->tasks[k];
        ok = int_of(json_object_get(j, "task"), 0, FB_PLAN_MAX_TASKS, &ok) == k && ok;
        t->layers = mask_of(s, json_object_get(j, "layers"), &ok);
        t->seconds = json_number_value(json_object_get(j, "seconds"));
        if (r) {
            t->band = true;
            t->y0 = int_of(json_array_get(r, 0), 0, s->height, &ok);
            t->y1 = int_of(json_array_get(r, 1), 0, s->height, &ok);
            ok = ok && 0 <= t->y0 && t->y0 < t->y1 && t->y1 <= s->height;
        }
        if (pp) {
            t->part = int_of(json_array_get(pp, 0), 1, FB_PLAN_MAX_TASKS, &ok);
            t->nparts = int_of(json_array_get(pp, 1), 1, FB_PLAN_MAX_TASKS, &ok);
            t->points = mask_of(s, json_object_get(j, "points_layers"), &ok);
            ok = ok && 1 <= t->part && t->part <= t->nparts && t->points && !(t->points & ~t->layers);
        }
        ok = ok && t->layers;
    }
    /* each layer's split, from the tasks; every layer in exactly one way */
    uint32_t seen = 0;
    for (int i = 0; i < s->nlayers; i++) p->share[i] = FB_SHARE_WHOLE;
    for (int k = 0; ok && k < p->nactive; k++) {
        const fb_task *t = &p->tasks[k];
        for (int i = 0; i < s->nlayers; i++)
            if (t->layers >> i & 1)
                p->share[i] = t->band ? FB_SHARE_BAND : t->points >> i & 1 ? FB_SHARE_POINTS : FB_SHARE_WHOLE;
        seen |= t->layers;
    }
    ok = ok && seen == (uint32_t)((1ull << s->nlayers) - 1);
    /* the bands tile the rows in order, all of the same layers; the points parts are 1..n once each */
    int y = 0, nb = 0, np = 0;
    uint32_t band_layers = 0, parts_seen[FB_PLAN_MAX_TASKS / 32 + 1] = {0};
    for (int k = 0; ok && k < p->nactive; k++) {
        const fb_task *t = &p->tasks[k];
        if (t->band) {
            ok = t->y0 == y && (nb == 0 || t->layers == band_layers) && !t->points;
            y = t->y1, band_layers = t->layers, nb++;
        }
        if (t->points) {
            ok = ok && t->nparts == p->nparts && t->nparts <= FB_PLAN_MAX_TASKS &&
                 !(parts_seen[t->part / 32] >> (t->part % 32) & 1);
            if (ok) parts_seen[t->part / 32] |= 1u << (t->part % 32);
            np++;
        }
        for (int j = 0; ok && j < k; j++) /* a layer is whole in one task only, or in all bands / parts */
            ok = !(p->tasks[j].layers & t->layers & ~(t->band ? band_layers : t->points));
    }
    ok = ok && (nb == 0 || y == s->height) && nb == p->nbands && np == p->nparts && p->nparts <= FB_PLAN_MAX_TASKS;
    json_decref(o);
    return ok ? FB_OK : fb_fail(FB_ERR_INPUT, "the stored plan (attribute fractalbake/plan) does not parse");
}

/* ---- a scene of some layers ------------------------------------------------------------------ */

fb_result fb_scene_subset(const fb_scene *s, uint32_t mask, fb_scene *out)
{
    int map[FB_MAX_LAYERS], n = 0;
    memset(out, 0, sizeof *out);
    out->width = s->width, out->height = s->height, out->seed = s->seed;
    out->compression = s->compression, out->multipart = s->multipart;
    for (int i = 0; i < s->nlayers; i++) map[i] = mask >> i & 1 ? n++ : -1;
    for (int i = 0; i < s->nlayers; i++) {
        if (map[i] < 0) continue;
        fb_layer *L = &out->layers[map[i]];
        memcpy(L, &s->layers[i], sizeof *L);
        /* its own parameters (the references in them are renumbered below) and tile names */
        size_t ntiles = (size_t)L->tiles[0] * L->tiles[1];
        L->params = malloc(L->cls->params_size ? L->cls->params_size : 1);
        L->tile_paths = ntiles ? malloc(ntiles * FB_TILE_PATH) : NULL;
        if (!L->params || (ntiles && !L->tile_paths)) {
            fb_scene_fini(out);
            return fb_fail(FB_ERR_NOMEM, "out of memory");
        }
        memcpy(L->params, s->layers[i].params, L->cls->params_size);
        if (ntiles) memcpy(L->tile_paths, s->layers[i].tile_paths, ntiles * FB_TILE_PATH);
        fb_ref_slot slots[FB_MAX_REFS];
        int nr = L->cls->refs ? L->cls->refs(L, slots) : 0;
        for (int k = 0; k < nr; k++) {
            fb_ref *r = slots[k].ref;
            if (r->layer < 0) continue;
            if (map[r->layer] < 0) {
                fb_scene_fini(out);
                return fb_fail(FB_ERR_INTERNAL, "layer %s uses %s, which the task does not compute", L->name,
                               s->layers[r->layer].name);
            }
            r->layer = map[r->layer];
        }
    }
    out->nlayers = n;
    for (int j = 0, k = 0; j < s->nlayers; j++)
        if (map[s->order[j]] >= 0) out->order[k++] = map[s->order[j]];
    out->json = strdup(s->json);
    return out->json ? FB_OK : fb_fail(FB_ERR_NOMEM, "out of memory");
}
