/*
 * A minimal test harness in the manner of Redis's testhelp.h: CHECK counts failures and reports the
 * file, line and condition; tests end with TEST_REPORT(), which prints "N passed, N failed" and
 * returns non-zero on any failure. REQUIRE is a CHECK that stops the test when it fails (a setup the
 * rest depends on). TEST_SKIP() returns 77, which CTest reports as not run.
 */
#ifndef FB_TESTHELP_H
#define FB_TESTHELP_H

#include <stdio.h>
#include <stdlib.h>

static int th_passed, th_failed;

#define CHECK(cond)                                                                                                    \
    do {                                                                                                               \
        if (cond) {                                                                                                    \
            th_passed++;                                                                                               \
        } else {                                                                                                       \
            th_failed++;                                                                                               \
            fprintf(stderr, "FAIL %s:%d: %s\n", __FILE__, __LINE__, #cond);                                            \
        }                                                                                                              \
    } while (0)

#define CHECKF(cond, ...)                                                                                              \
    do {                                                                                                               \
        if (cond) {                                                                                                    \
            th_passed++;                                                                                               \
        } else {                                                                                                       \
            th_failed++;                                                                                               \
            fprintf(stderr, "FAIL %s:%d: %s: ", __FILE__, __LINE__, #cond);                                            \
            fprintf(stderr, __VA_ARGS__);                                                                              \
            fprintf(stderr, "\n");                                                                                     \
        }                                                                                                              \
    } while (0)

/* A check that the rest of the test depends on: on failure, report and stop (exit 1). */
#define REQUIRE(cond)                                                                                                  \
    do {                                                                                                               \
        if (cond) {                                                                                                    \
            th_passed++;                                                                                               \
        } else {                                                                                                       \
            fprintf(stderr, "FAIL (fatal) %s:%d: %s\n", __FILE__, __LINE__, #cond);                                    \
            printf("%d passed, %d failed\n", th_passed, th_failed + 1);                                                \
            exit(1);                                                                                                   \
        }                                                                                                              \
    } while (0)

#define TEST_REPORT()                                                                                                  \
    do {                                                                                                               \
        printf("%d passed, %d failed\n", th_passed, th_failed);                                                        \
        return th_failed ? 1 : 0;                                                                                      \
    } while (0)

#define TEST_SKIP(why)                                                                                                 \
    do {                                                                                                               \
        printf("skipped: %s\n", why);                                                                                  \
        return 77;                                                                                                     \
    } while (0)

#endif
