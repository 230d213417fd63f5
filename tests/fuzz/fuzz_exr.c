/* The EXR reader as info, compare, merge and tonemap use it: open (header bounds), the attributes,
 * every row of every channel, and info's listing. */
#include "compare.h"
#include "exrio.h"
#include "fuzz_common.h"

static void drop_line(const char *line, void *user)
{
    (void)line, (void)user;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fuzz_quiet();
    int fd;
    char path[64];
    fuzz_file(data, size, &fd, path);
    exrio_reader *r = NULL;
    if (exrio_open(path, &r) == FB_OK) {
        exrio_attr_string(r, "fractalbake/scene");
        int w = exrio_width(r), h = exrio_height(r), nc = exrio_nchannels(r);
        void **planes = calloc((size_t)nc + 1, sizeof *planes);
        for (int c = 0; c < nc; c++) planes[c] = malloc((size_t)w * 16 * 4);
        for (int y = 0; y < h; y += 16) {
            int n = h - y < 16 ? h - y : 16;
            if (exrio_read_rows(r, y, n, planes) != FB_OK) break;
        }
        for (int c = 0; c < nc; c++) free(planes[c]);
        free(planes);
        exrio_close(&r);
    }
    fb_info(path, false, drop_line, NULL);
    close(fd);
    return 0;
}
