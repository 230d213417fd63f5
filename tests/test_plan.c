/*
 * The plan (core/plan.c): for scenes of every sharing mode and N from 1 to 64, the tasks' shares
 * tile the image exactly once (bands cover every row once in order, of the same layers; the points
 * parts of a chaos game are 1..n once each; every other layer is computed by one task), the split's
 * total stays within the 10% budget, the plan reads back from its JSON as it was, a tampered plan
 * is refused, and every layer's cost is positive and grows with the image.
 */
#include "plan.h"
#include "scene.h"

#include "testhelp.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const char *const k_scenes[] = {
    /* per-pixel layers and an op: bands */
    "{\"size\": [512, 256], \"layers\": [{\"type\": \"fbm\", \"name\": \"a\", \"octaves\": 12},"
    " {\"type\": \"fbm\", \"name\": \"b\"}, {\"type\": \"op\", \"name\": \"c\", \"op\": \"add\", \"inputs\": [\"a\", "
    "\"b\"]}]}",
    /* a chaos game alone: points parts */
    "{\"size\": [256, 256], \"layers\": [{\"type\": \"ifs\", \"name\": \"f\", \"points\": 400000000}]}",
    /* whole layers, a banded Julia sky and a chaos game together */
    "{\"size\": [256, 128], \"layers\": [{\"type\": \"julia\", \"name\": \"sky\"},"
    " {\"type\": \"terrain\", \"name\": \"t\", \"insert\": 20000, \"points\": [[0, 0, 0], [100, 0, 10], [0, 50, 20],"
    " [100, 50, 40], [50, 25, 80]]}, {\"type\": \"lsystem\", \"name\": \"l\"},"
    " {\"type\": \"ifs\", \"name\": \"p\", \"points\": 100000000}]}",
    /* an op using a chaos game: the game stays whole */
    "{\"size\": [128, 128], \"layers\": [{\"type\": \"ifs\", \"name\": \"p\", \"points\": 100000000},"
    " {\"type\": \"op\", \"name\": \"m\", \"op\": \"threshold\", \"inputs\": [\"p.A\"], \"level\": 0.5}]}",
};

/* Checks that plan p tiles scene s exactly once. */
static void check_tiling(const fb_scene *s, const fb_plan *p, const char *what)
{
    CHECKF(p->nactive >= 1 && p->nactive <= p->ntasks, "%s: %d active of %d", what, p->nactive, p->ntasks);
    int covered[FB_MAX_LAYERS] = {0}, parts_of[FB_MAX_LAYERS][65] = {{0}};
    int y = 0, nb = 0;
    for (int k = 0; k < p->nactive; k++) {
        const fb_task *t = &p->tasks[k];
        CHECKF(t->layers != 0, "%s: task %d has work", what, k);
        if (t->band) {
            CHECKF(t->y0 == y && t->y1 > t->y0, "%s: band %d starts at row %d (found %d-%d)", what, k, y, t->y0, t->y1);
            y = t->y1, nb++;
            continue;
        }
        for (int i = 0; i < s->nlayers; i++) {
            if (!(t->layers >> i & 1)) continue;
            if (t->points >> i & 1) {
                CHECKF(t->part >= 1 && t->part <= t->nparts && t->nparts <= 64, "%s: part %d/%d", what, t->part,
                       t->nparts);
                if (t->part >= 1 && t->part <= 64) parts_of[i][t->part]++;
            } else {
                covered[i]++;
            }
        }
    }
    CHECKF(nb == p->nbands, "%s: %d bands, the plan says %d", what, nb, p->nbands);
    if (nb) CHECKF(y == s->height, "%s: the bands end at row %d of %d", what, y, s->height);
    for (int i = 0; i < s->nlayers; i++) {
        if (p->share[i] == FB_SHARE_BAND) {
            CHECKF(covered[i] == 0 && nb > 0, "%s: banded layer %d only in bands", what, i);
            for (int k = 0; k < nb; k++) CHECKF(p->tasks[k].layers >> i & 1, "%s: band %d has layer %d", what, k, i);
        } else if (p->share[i] == FB_SHARE_POINTS) {
            CHECKF(covered[i] == 0, "%s: a points layer is not also whole", what);
            for (int part = 1; part <= p->nparts && part <= 64; part++)
                CHECKF(parts_of[i][part] == 1, "%s: layer %d part %d given %d times", what, i, part, parts_of[i][part]);
        } else {
            CHECKF(covered[i] == 1, "%s: whole layer %d computed %d times", what, i, covered[i]);
        }
        CHECKF(s->layers[i].cls->share == FB_SHARE_BAND || p->share[i] != FB_SHARE_BAND,
               "%s: layer %d of a class that is not banded was cut into bands", what, i);
    }
    CHECKF(p->total <= 1.10 * p->one + 1e-9, "%s: the split costs %g against one bake's %g", what, p->total, p->one);
    CHECKF(p->longest <= p->one + 1e-9, "%s: the longest task (%g) is not longer than one bake (%g)", what, p->longest,
           p->one);
}

static void test_tiling(void)
{
    const int ns[] = {1, 2, 3, 5, 8, 16, 64};
    const double startups[] = {-1, 0};
    for (size_t sc = 0; sc < sizeof k_scenes / sizeof k_scenes[0]; sc++) {
        fb_scene s;
        REQUIRE(fb_scene_parse(k_scenes[sc], "test", &s) == FB_OK);
        bool split_seen = false;
        for (size_t n = 0; n < sizeof ns / sizeof ns[0]; n++)
            for (int st = 0; st < 2; st++) {
                fb_plan *p = malloc(sizeof *p), *q = malloc(sizeof *q);
                REQUIRE(p && q);
                char what[64];
                snprintf(what, sizeof what, "scene %zu, %d tasks, start-up %g", sc, ns[n], startups[st]);
                CHECKF(fb_plan_make(&s, ns[n], startups[st], p) == FB_OK, "%s: planned", what);
                check_tiling(&s, p, what);
                split_seen |= p->nactive > 1;
                /* what render --task stores and merge reads back */
                char *text = fb_plan_json(&s, p, false);
                CHECKF(text && fb_plan_parse(text, &s, q) == FB_OK, "%s: its JSON reads back", what);
                CHECKF(q->ntasks == p->ntasks && q->nactive == p->nactive && q->nbands == p->nbands &&
                           q->nparts == p->nparts,
                       "%s: the same plan read back", what);
                for (int k = 0; k < p->nactive && k < q->nactive; k++)
                    CHECKF(q->tasks[k].band == p->tasks[k].band && q->tasks[k].y0 == p->tasks[k].y0 &&
                               q->tasks[k].y1 == p->tasks[k].y1 && q->tasks[k].layers == p->tasks[k].layers &&
                               q->tasks[k].points == p->tasks[k].points && q->tasks[k].part == p->tasks[k].part,
                           "%s: task %d read back", what, k);
                free(text);
                free(p);
                free(q);
            }
        if (sc < 3)
            CHECKF(split_seen, "scene %zu: some N splits it", sc); /* scene 3 is one whole unit */
        else
            CHECKF(!split_seen, "scene %zu: one unit, never split", sc);
        fb_scene_fini(&s);
    }
}

/* A stored plan that does not tile the image is refused, whatever was changed. */
static void test_tampered(void)
{
    fb_scene s;
    REQUIRE(fb_scene_parse(k_scenes[0], "test", &s) == FB_OK);
    fb_plan *p = malloc(sizeof *p), *q = malloc(sizeof *q);
    REQUIRE(p && q && fb_plan_make(&s, 4, 0, p) == FB_OK && p->nbands >= 2);
    char *good = fb_plan_json(&s, p, false);
    REQUIRE(good != NULL);
    char rows[64];
    snprintf(rows, sizeof rows, "\"rows\":[%d,%d]", p->tasks[1].y0, p->tasks[1].y1);
    REQUIRE(strstr(good, rows) != NULL);
    const struct {
        const char *from, *to, *why;
    } edits[] = {
        {rows, "\"rows\":[1,2]", "a band that does not start where the last ended"},
        {"\"tasks\":4", "\"tasks\":2", "fewer tasks than active ones"},
        {"\"tasks\":4", "\"tasks\":0", "no tasks"},
        {"\"bands\":", "\"bands\":9", "a band count the list does not have"},
        {"\"layers\":[\"a\",\"b\",\"c\"]", "\"layers\":[\"a\",\"zz\",\"c\"]", "a layer the scene does not have"},
    };
    for (size_t e = 0; e < sizeof edits / sizeof edits[0]; e++) {
        const char *at = strstr(good, edits[e].from);
        CHECKF(at != NULL, "edit %zu applies", e);
        if (!at) continue;
        char *bad = malloc(strlen(good) + 64);
        sprintf(bad, "%.*s%s%s", (int)(at - good), good, edits[e].to, at + strlen(edits[e].from));
        CHECKF(fb_plan_parse(bad, &s, q) != FB_OK, "refused: %s", edits[e].why);
        free(bad);
    }
    free(good);
    free(p);
    free(q);
    fb_scene_fini(&s);
}

/* Each layer's cost is positive and grows with the image (the plan's model is monotone in size). */
static void test_costs(void)
{
    for (size_t sc = 0; sc < sizeof k_scenes / sizeof k_scenes[0]; sc++) {
        double prev[FB_MAX_LAYERS] = {0};
        const char *sizes[] = {"size=64x32", "size=256x128", "size=1024x512"};
        for (int z = 0; z < 3; z++) {
            fb_scene s;
            const char *sets[1] = {sizes[z]};
            REQUIRE(fb_scene_parse_sets(k_scenes[sc], "test", sets, 1, &s) == FB_OK);
            fb_plan *p = malloc(sizeof *p);
            REQUIRE(p && fb_plan_make(&s, 1, -1, p) == FB_OK);
            for (int i = 0; i < s.nlayers; i++) {
                CHECKF(p->layer_seconds[i] > 0 && isfinite(p->layer_seconds[i]), "scene %zu layer %d: cost %g", sc, i,
                       p->layer_seconds[i]);
                CHECKF(p->layer_seconds[i] > prev[i], "scene %zu layer %d: %g at %s, %g smaller", sc, i,
                       p->layer_seconds[i], sizes[z], prev[i]);
                prev[i] = p->layer_seconds[i];
            }
            free(p);
            fb_scene_fini(&s);
        }
    }
}

int main(void)
{
    test_tiling();
    test_tampered();
    test_costs();
    TEST_REPORT();
}
