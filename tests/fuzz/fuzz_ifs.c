/* The Fractint .ifs reader: every entry, then the first, validated as the ifs layer would. */
#include "fuzz_common.h"
#include "ifs.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fuzz_quiet();
    int fd;
    char path[64], msg[256];
    fuzz_file(data, size, &fd, path);
    fb_ifs ifs;
    int bad;
    if (fb_ifs_read_file(path, NULL, &ifs) == FB_OK) fb_ifs_valid(&ifs, &bad, msg, sizeof msg);
    if (fb_ifs_read_file(path, "fern", &ifs) == FB_OK) fb_ifs_valid(&ifs, &bad, msg, sizeof msg);
    close(fd);
    return 0;
}
