/* The L-system parser: lines "AXIOM", then rules "X=successor" or "X(p)=successor", then the
 * derivation (a small max-symbols) and the turtle, as the lsystem layer runs them. */
#include "fuzz_common.h"
#include "lsys.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fuzz_quiet();
    char *text = fuzz_text(data, size), msg[256];
    fb_lsys ls;
    memset(&ls, 0, sizeof ls);
    char *save = NULL, *line = strtok_r(text, "\n", &save);
    snprintf(ls.axiom, sizeof ls.axiom, "%s", line ? line : "F");
    ls.iterations = size ? data[0] % 8 : 3;
    ls.angle = 25;
    for (line = strtok_r(NULL, "\n", &save); line && ls.nrules < FB_LSYS_MAX_RULES; line = strtok_r(NULL, "\n", &save))
        if (fb_lsys_parse_rule(line, &ls.rules[ls.nrules], msg, sizeof msg)) ls.nrules++;
    int bad;
    if (fb_lsys_valid(&ls, &bad, msg, sizeof msg)) {
        char *s = NULL;
        size_t len = 0;
        if (fb_lsys_derive(&ls, 7, 1u << 16, 1u << 14,
                           &(fb_memory){(uint64_t)1 << 30, 0} /* refused beyond, never allocated */, "fuzz", &s,
                           &len) == FB_OK) {
            fb_lsys_seg *segs = NULL;
            size_t nsegs = 0;
            int depth = 0;
            if (fb_lsys_turtle(s, len, ls.angle, 90, 1, "fuzz", &segs, &nsegs, &depth) == FB_OK) free(segs);
            free(s);
        }
    }
    free(text);
    return 0;
}
