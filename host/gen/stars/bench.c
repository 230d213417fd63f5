/*
 * The stars benchmark: a lat-long sky to magnitude 8 (about 47,000 stars) with the Milky Way, on
 * every backend, in Mpix/s (the catalogue and its binning included in the end-to-end bake).
 */
#include "benchkit.h"
#include "gen_stars.h"

#include <stdio.h>

fb_result fb_stars_bench(fb_bench *b)
{
    int w = b->width, h = b->width / 2;
    char json[512];
    snprintf(json, sizeof json,
             "{\"size\": [%d, %d], \"seed\": 1, \"layers\": [{\"type\": \"stars\", \"mapping\": \"latlong\", "
             "\"limit\": 8, \"milky-way\": 3}]}",
             w, h);
    fb_bench_heading(b, "stars %d x %d lat-long, to magnitude 8 with the Milky Way; median of 3 runs after a warm-up",
                     w, h);
    fb_bench_case bc = {"stars", "Mpix/s", (double)w * h, 1e6, NULL, 0};
    fb_scene s;
    fb_result rc = fb_scene_parse(json, NULL, &s);
    if (!rc) rc = fb_bench_layer(b, &bc, &s, -1);
    fb_scene_fini(&s);
    return rc;
}
