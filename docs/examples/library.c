/* Bakes the default scene in-process (arguments: --set overrides, "size=256x128") and prints each
 * channel's name and the FNV-1a hash of its samples, for comparison with `fractalbake render`. */
#include <fractalbake.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

int main(int argc, char **argv)
{
    fractalbake_context *ctx;
    fractalbake_scene *scene = NULL;
    fractalbake_image *img = NULL;
    fractalbake_context_desc desc = {.api = FRACTALBAKE_API, .backend = "native"};
    if (fractalbake_context_create(&desc, &ctx) ||
        fractalbake_scene_load(ctx, NULL, NULL, (const char *const *)argv + 1, argc - 1, &scene) ||
        fractalbake_render(ctx, scene, NULL, &img))
        return fprintf(stderr, "%s\n", fractalbake_error(ctx)), 2;
    int w, h, n = fractalbake_image_channels(img);
    fractalbake_image_window(img, NULL, NULL, &w, &h, NULL, NULL);
    void **planes = calloc((size_t)n, sizeof *planes); /* 4 bytes a sample: float or uint32_t */
    for (int c = 0; c < n; c++) planes[c] = malloc((size_t)w * h * 4);
    if (fractalbake_image_read(ctx, img, planes)) return fprintf(stderr, "%s\n", fractalbake_error(ctx)), 3;
    for (int c = 0; c < n; c++) {
        uint64_t hash = 14695981039346656037u;
        for (size_t i = 0; i < (size_t)w * h * 4; i++) hash = (hash ^ ((uint8_t *)planes[c])[i]) * 1099511628211u;
        printf("%s %016llx\n", fractalbake_image_channel(img, c), (unsigned long long)hash);
    }
    return 0; /* fractalbake_image_destroy, _scene_destroy, _context_destroy: a longer program's cleanup */
}
