/* The scene parser with --set overrides: JSON text, then optional lines "\n--set KEY=VALUE". The
 * stored-scene path (--from) drops output keys first, as render does. */
#include "fuzz_common.h"
#include "scene.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fuzz_quiet();
    char *text = fuzz_text(data, size);
    const char *sets[8];
    int nsets = 0;
    for (char *at = strstr(text, "\n--set "); at && nsets < 8; at = strstr(at + 1, "\n--set ")) {
        *at = 0;
        sets[nsets++] = at + 7;
    }
    for (int i = 0; i < nsets; i++) { /* each set ends at the next line */
        char *nl = strchr(sets[i], '\n');
        if (nl) *nl = 0;
    }
    fb_scene s;
    if (fb_scene_parse_sets(text, "fuzz", sets, nsets, &s) == FB_OK) fb_scene_fini(&s);
    char *kept = NULL, dropped[512];
    if (fb_scene_drop_outputs(text, &kept, dropped, sizeof dropped) == FB_OK) {
        if (fb_scene_parse(kept, "fuzz (stored)", &s) == FB_OK) fb_scene_fini(&s);
    }
    free(kept);
    free(text);
    return 0;
}
