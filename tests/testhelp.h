/*
 * A minimal test harness in the manner of Redis's testhelp.h: CHECK counts failures and reports the
 * file, line and condition; tests end with TEST_REPORT(), which prints "N passed, N failed" and
 * returns non-zero on any failure. REQUIRE is a CHECK that stops the test when it fails (a setup the
 * rest depends on). TEST_SKIP() returns 77, which CTest reports as not run.
 */
#ifndef FB_TESTHELP_H
#define FB_TESTHELP_H

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <unistd.h>

static int th_passed, th_failed;

/* xorshift64 for tests that draw their own inputs: th_next() 64 random bits, th_unif() in [0, 1).
 * Reseed by assigning th_rng (never 0). */
static uint64_t th_rng = 88172645463325252ull;
static inline uint64_t th_next(void)
{
    th_rng ^= th_rng << 13;
    th_rng ^= th_rng >> 7;
    th_rng ^= th_rng << 17;
    return th_rng;
}
static inline double th_unif(void)
{
    return (double)(th_next() >> 11) * 0x1p-53;
}

/* qsort's comparison of doubles, ascending. */
static inline int th_cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

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

/* A scratch folder of this test process's own (mkdtemp under $TMPDIR or /tmp), removed at exit, and
 * paths in it: no fixed names that two tests under `ctest -j` could share. */
static char th_dir[512];
static void th_rmdir(void)
{
    char cmd[600];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", th_dir);
    if (th_dir[0] && system(cmd) != 0) fprintf(stderr, "could not remove %s\n", th_dir);
}
static __attribute__((unused)) const char *th_path(const char *name)
{
    static char buf[8][600];
    static int k;
    if (!th_dir[0]) {
        const char *tmp = getenv("TMPDIR");
        snprintf(th_dir, sizeof th_dir, "%s/fb-test-XXXXXX", tmp && *tmp ? tmp : "/tmp");
        if (!mkdtemp(th_dir)) {
            fprintf(stderr, "FAIL (fatal): no scratch folder\n");
            exit(1);
        }
        atexit(th_rmdir);
    }
    k = (k + 1) % 8;
    snprintf(buf[k], sizeof buf[k], "%s/%s", th_dir, name);
    return buf[k];
}

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
