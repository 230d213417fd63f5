/* The text readers: survey points and centres (terrain), constraint points, regions and a 1D profile
 * (constrain, through its layer's init as a bake runs it). */
#include "fuzz_common.h"
#include "gen.h"
#include "scene.h"
#include "terrain_io.h"

static void constrain_reads(const char *key, const char *path, int height)
{
    char json[512];
    snprintf(json, sizeof json, "{\"size\": [33, %d], \"layers\": [{\"type\": \"constrain\", \"%s\": \"%s\"}]}", height,
             key, path);
    fb_scene s;
    if (fb_scene_parse(json, "fuzz", &s) != FB_OK) return;
    fb_gen g;
    fb_gen_init(&g, &s, &s.layers[0]);
    fb_gen_fini(&g);
    fb_scene_fini(&s);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fuzz_quiet();
    int fd;
    char path[64];
    fuzz_file(data, size, &fd, path);
    double *xyz = NULL;
    size_t n = 0;
    if (fb_terrain_read_points(path, &xyz, &n) == FB_OK) free(xyz);
    fb_terrain_center *c = NULL;
    int nc = 0;
    if (fb_terrain_read_centers(path, &c, &nc) == FB_OK) free(c);
    constrain_reads("points", path, 17);
    constrain_reads("regions", path, 17);
    constrain_reads("profile", path, 1);
    close(fd);
    return 0;
}
