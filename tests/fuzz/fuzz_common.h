/*
 * Shared by the libFuzzer harnesses: the fuzzer's bytes as a NUL-terminated string, or as a file
 * (an anonymous memory file named by /proc/self/fd, so that the readers take it exactly as they
 * take a user's file).
 */
#ifndef FB_FUZZ_COMMON_H
#define FB_FUZZ_COMMON_H

#define _GNU_SOURCE
#include "fb.h"

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <unistd.h>

static char *fuzz_text(const uint8_t *data, size_t size)
{
    char *s = malloc(size + 1);
    if (!s) abort();
    memcpy(s, data, size);
    s[size] = 0;
    return s;
}

/* Writes the bytes to a memory file; *fd to close after use, path its name. */
static void fuzz_file(const uint8_t *data, size_t size, int *fd, char path[64])
{
    *fd = memfd_create("fuzz", 0);
    if (*fd < 0 || write(*fd, data, size) != (ssize_t)size) abort();
    lseek(*fd, 0, SEEK_SET);
    snprintf(path, 64, "/proc/self/fd/%d", *fd);
}

/* Errors are logged to a sink that drops them: the harness wants crashes and sanitizer reports. */
static void fuzz_quiet(void)
{
    fb_log_set_sink(NULL, NULL);
}

#endif
