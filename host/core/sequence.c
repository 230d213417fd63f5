/*
 * A sequence of frames (sequence.h): the frames' selection, their file names, each frame's scene,
 * and whether a frame is already done.
 */
#include "sequence.h"

#include "exrio.h"
#include "gen.h"
#include "jsonout.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

/* A decimal long at *s (an optional '-'), advancing *s. */
static bool read_long(const char **s, long *out)
{
    char *end;
    errno = 0;
    long v = strtol(*s, &end, 10);
    if (end == *s || errno || (**s != '-' && (**s < '0' || **s > '9'))) return false;
    if (v < -1000000000L || v > 1000000000L) return false;
    *s = end, *out = v;
    return true;
}

fb_result fb_frames_parse(const char *what, const char *text, fb_frames *out)
{
    const char *s = text;
    fb_frames f = {0, 0, 1};
    bool ok = read_long(&s, &f.first);
    f.last = f.first;
    if (ok && *s == '-') s++, ok = read_long(&s, &f.last);
    if (ok && *s == ':') s++, ok = read_long(&s, &f.step) && f.step >= 1;
    if (!ok || *s)
        return fb_fail(FB_ERR_USAGE, "%s: expected frames A-B or A-B:STEP (integers, STEP >= 1), found \"%s\"", what,
                       text);
    if (f.last < f.first)
        return fb_fail(FB_ERR_USAGE, "%s: the last frame %ld comes before the first %ld", what, f.last, f.first);
    *out = f;
    return FB_OK;
}

long fb_frames_count(const fb_frames *f)
{
    return (f->last - f->first) / f->step + 1;
}

fb_result fb_scene_frames(const fb_scene *s, bool *has, fb_frames *out)
{
    json_t *root = json_loads(s->json, 0, NULL);
    const char *text = json_string_value(json_object_get(root, "frames"));
    fb_result rc = text ? fb_frames_parse("frames", text, out) : FB_OK;
    *has = text != NULL;
    json_decref(root);
    return rc;
}

void fb_frames_share(const fb_frames *f, int k, int n, long *i0, long *i1)
{
    long count = fb_frames_count(f);
    *i0 = count * k / n, *i1 = count * (k + 1) / n;
}

fb_result fb_frame_pattern(const char *what, const char *path, bool *has)
{
    int n = 0;
    for (const char *p = path; *p; p++) {
        if (*p != '%') continue;
        if (p[1] == '%') {
            p++;
            continue;
        }
        const char *q = p + 1;
        if (*q == '0' && q[1] >= '1' && q[1] <= '9') q += 2;
        if (*q != 'd')
            return fb_fail(FB_ERR_USAGE, "%s: \"%s\": a frame number is %%d or %%0Nd (N 1 to 9); write %% as %%%%",
                           what, path);
        n++;
        p = q;
    }
    if (n > 1) return fb_fail(FB_ERR_USAGE, "%s: \"%s\": more than one frame number", what, path);
    *has = n == 1;
    return FB_OK;
}

void fb_frame_path(const char *pattern, long frame, char *out, size_t size)
{
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wformat-nonliteral"
    /* fb_frame_pattern allowed one %d or %0Nd alone: an int argument */
    snprintf(out, size, pattern, (int)frame);
#pragma GCC diagnostic pop
}

/* Whether the class has a key named `key`. */
static bool has_key(const fb_gen_class *c, const char *key)
{
    for (int k = 0; c && k < c->nkeys; k++)
        if (!strcmp(c->keys[k].key, key)) return true;
    return false;
}

fb_result fb_frame_scene_json(const fb_scene *s, long frame, char **out)
{
    json_t *root = json_loads(s->json, 0, NULL);
    if (!root) return fb_fail(FB_ERR_NOMEM, "out of memory");
    json_object_del(root, "frames");
    json_t *layers = json_object_get(root, "layers");
    int moving = 0;
    for (size_t i = 0; i < json_array_size(layers); i++) {
        json_t *L = json_array_get(layers, i);
        if (!has_key(fb_gen_find(json_string_value(json_object_get(L, "type"))), "time")) continue;
        json_object_set_new(L, "time", json_integer(frame));
        moving++;
    }
    char *text = moving ? fb_json_dumps(root, 0) : NULL;
    json_decref(root);
    if (!moving) return fb_fail(FB_ERR_INPUT, "a sequence needs a layer that moves in time (a flame's keyframes)");
    if (!text) return fb_fail(FB_ERR_NOMEM, "out of memory");
    *out = text;
    return FB_OK;
}

fb_result fb_frame_done(const char *path, const char *json, bool *done)
{
    struct stat st;
    *done = false;
    if (stat(path, &st) != 0) return FB_OK;
    exrio_reader *r = NULL;
    fb_result rc = exrio_open(path, &r);
    if (rc) return fb_fail(FB_ERR_INPUT, "%s: a frame of the sequence is there but cannot be read: not replaced", path);
    const char *stored = exrio_attr_string(r, "fractalbake/scene");
    if (stored && !strcmp(stored, json))
        *done = true;
    else
        rc = fb_fail(FB_ERR_INPUT, "%s: there, baked from %s: not replaced (remove it to bake this frame again)", path,
                     stored ? "another scene" : "no scene of fractalbake");
    exrio_close(&r);
    return rc;
}
