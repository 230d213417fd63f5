/*
 * The output transaction (host/base/output.c): exclusive temporary files, all-or-nothing renames, nesting,
 * refusal of non-regular targets and of one path named twice, and the signal handler's clean-up.
 */
#include "output.h"
#include "testhelp.h"

#include <dirent.h>
#include <fcntl.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

static char g_dir[256];

/* Files in the scratch folder whose name contains `part`. */
static int count_files(const char *part)
{
    DIR *d = opendir(g_dir);
    int n = 0;
    for (struct dirent *e; d && (e = readdir(d));) n += strstr(e->d_name, part) != NULL;
    if (d) closedir(d);
    return n;
}

static const char *at(const char *name)
{
    static char buf[4][512];
    static int k;
    k = (k + 1) % 4;
    snprintf(buf[k], sizeof buf[k], "%s/%s", g_dir, name);
    return buf[k];
}

static bool has(const char *name, const char *text)
{
    char got[64] = {0};
    FILE *f = fopen(at(name), "rb");
    if (!f) return false;
    size_t n = fread(got, 1, sizeof got - 1, f);
    fclose(f);
    return n == strlen(text) && !memcmp(got, text, n);
}

static fb_result write_text(const char *name, const char *what, const char *text)
{
    int fd = -1;
    fb_result rc = fb_output_open(at(name), what, &fd);
    if (rc) return rc;
    rc = write(fd, text, strlen(text)) == (ssize_t)strlen(text) ? FB_OK : FB_ERR_IO;
    close(fd);
    return fb_output_done(at(name), rc);
}

int main(void)
{
    snprintf(g_dir, sizeof g_dir, "/tmp/fb-test-output-XXXXXX");
    REQUIRE(mkdtemp(g_dir) != NULL);

    /* Outside a transaction an output is its own: renamed when done. */
    REQUIRE(write_text("a.txt", "output", "one") == FB_OK);
    CHECK(has("a.txt", "one") && count_files(".tmp") == 0);

    /* Inside one, nothing is renamed before the outermost end; then everything is. */
    fb_outputs_begin();
    CHECK(write_text("a.txt", "output", "two") == FB_OK);
    fb_outputs_begin(); /* nested, as fb_bake inside main */
    CHECK(write_text("b.txt", "preview", "three") == FB_OK);
    CHECK(fb_outputs_end(FB_OK) == FB_OK);
    CHECK(has("a.txt", "one") && access(at("b.txt"), F_OK) != 0);
    CHECK(count_files(".tmp") == 2);
    CHECK(fb_outputs_end(FB_OK) == FB_OK);
    CHECK(has("a.txt", "two") && has("b.txt", "three") && count_files(".tmp") == 0);

    /* A failure at any depth removes every temporary file and renames nothing. */
    fb_outputs_begin();
    CHECK(write_text("a.txt", "output", "four") == FB_OK);
    fb_outputs_begin();
    CHECK(write_text("c.txt", "mesh", "five") == FB_OK);
    CHECK(fb_outputs_end(FB_ERR_IO) == FB_ERR_IO);
    CHECK(fb_outputs_end(FB_OK) == FB_OK); /* the outer level has nothing left to commit */
    CHECK(has("a.txt", "two") && access(at("c.txt"), F_OK) != 0 && count_files(".tmp") == 0);

    /* The temporary name: hidden, beside the target, 16 random hex digits, different every time. */
    fb_outputs_begin();
    CHECK(fb_output_reserve(at("d.txt"), "output") == FB_OK);
    CHECK(fb_output_reserve(at("e.txt"), "output") == FB_OK);
    char names[2][256] = {{0}};
    DIR *d = opendir(g_dir);
    int k = 0;
    for (struct dirent *e; d && (e = readdir(d));)
        if (strstr(e->d_name, ".tmp") && k < 2) snprintf(names[k++], sizeof names[k], "%s", e->d_name);
    if (d) closedir(d);
    CHECK(k == 2);
    for (int i = 0; i < k; i++) {
        const char *n = names[i];
        size_t len = strlen(n);
        bool form = len == strlen(".d.txt.") + 16 + 4 && n[0] == '.' && !strcmp(n + len - 4, ".tmp");
        for (size_t j = len - 20; form && j < len - 4; j++) form = strchr("0123456789abcdef", n[j]) != NULL;
        CHECKF(form, "temporary name %s", n);
    }
    CHECK(strcmp(names[0] + 7, names[1] + 7) != 0);
    /* Reserved but never written is an internal error at commit, and leaves nothing. */
    CHECK(fb_outputs_end(FB_OK) == FB_ERR_INTERNAL);
    CHECK(count_files(".tmp") == 0 && access(at("d.txt"), F_OK) != 0);

    /* One path named twice, in two spellings, is refused; so is a non-regular target. */
    fb_outputs_begin();
    CHECK(fb_output_reserve(at("f.txt"), "output") == FB_OK);
    char alias[512];
    snprintf(alias, sizeof alias, "%s/./f.txt", g_dir);
    CHECK(fb_output_reserve(alias, "preview") == FB_ERR_USAGE);
    int fd = -1;
    CHECK(fb_output_open(alias, "preview", &fd) == FB_OK); /* taking its own reservation is fine */
    CHECK(fb_output_open(at("f.txt"), "mesh", &fd) == FB_ERR_USAGE || (close(fd), 0));
    mkdir(at("g.dir"), 0777);
    CHECK(symlink("a.txt", at("h.lnk")) == 0);
    CHECK(fb_output_reserve(at("g.dir"), "output") == FB_ERR_USAGE);
    CHECK(fb_output_reserve(at("h.lnk"), "output") == FB_ERR_USAGE);
    CHECK(fb_output_reserve("/dev/null", "output") == FB_ERR_USAGE);
    CHECK(fb_output_reserve(at("no/such/folder.txt"), "output") == FB_ERR_USAGE);
    CHECK(fb_outputs_end(FB_ERR_USAGE) == FB_ERR_USAGE);
    CHECK(count_files(".tmp") == 0);

    /* The signal handler's clean-up removes every temporary file. */
    fb_outputs_begin();
    CHECK(fb_output_reserve(at("i.txt"), "output") == FB_OK);
    CHECK(write_text("j.txt", "preview", "six") == FB_OK);
    CHECK(count_files(".tmp") == 2);
    fb_outputs_unlink_all();
    CHECK(count_files(".tmp") == 0);
    fb_outputs_end(FB_ERR_INTERNAL);
    CHECK(access(at("j.txt"), F_OK) != 0);

    char cmd[300];
    snprintf(cmd, sizeof cmd, "rm -rf %s", g_dir);
    CHECK(system(cmd) == 0);
    TEST_REPORT();
}
