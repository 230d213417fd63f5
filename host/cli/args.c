/* The command line's one argv reader (args.h). */
#include "args.h"

#include "output.h"
#include "textin.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

bool fb_args_int(const char *s, long lo, long hi, int *out)
{
    long long v;
    if (fb_text_int(s, lo, hi, NULL, &v)) {
        *out = (int)v;
        return true;
    }
    char *end;
    double d = strtod(s, &end);
    if (!*s || *end || !(d >= (double)lo && d <= (double)hi) || d != floor(d) || !strpbrk(s, "eE")) return false;
    *out = (int)d;
    return true;
}

static const fb_arg *find(const fb_argspec *spec, const char *a)
{
    for (const fb_arg *const *t = spec->flags; t && *t; t++)
        for (const fb_arg *f = *t; f->kind != FB_ARG_END; f++)
            if (!strcmp(a, f->name) || (f->alias && !strcmp(a, f->alias))) return f;
    return NULL;
}

static fb_arg_list *list_at(void *opts, size_t off)
{
    return (fb_arg_list *)((char *)opts + off);
}

/* "; did you mean --octaves?" for an unknown flag, from the tables and the handed-on flags. */
static void hint(const fb_argspec *spec, const void *data, const char *a, char *out, size_t size)
{
    const char *cands[512];
    int n = 0;
    for (const fb_arg *const *t = spec->flags; t && *t; t++)
        for (const fb_arg *f = *t; f->kind != FB_ARG_END && n < 512; f++)
            for (int k = 0; k < 2 && n < 512; k++) {
                const char *name = k ? f->alias : f->name;
                if (name && !strncmp(name, "--", 2)) cands[n++] = name + 2;
            }
    if (spec->names) n += spec->names(data, cands + n, 512 - n);
    const char *near = !strncmp(a, "--", 2) ? fb_closest(a + 2, cands, n) : NULL;
    snprintf(out, size, near ? "; did you mean --%s?" : "", near);
}

static fb_result take(const fb_arg *f, const char *a, const char *val, void *opts)
{
    void *field = (char *)opts + f->off;
    switch (f->kind) {
    case FB_ARG_STRING:
        *(const char **)field = val;
        return FB_OK;
    case FB_ARG_OUTPUT:
        *(const char **)field = val;
        return fb_output_format(a, val, f->ext);
    case FB_ARG_INT:
        if (!fb_args_int(val, f->lo, f->hi, field))
            return fb_fail(FB_ERR_USAGE, "%s: expected an integer in %ld..%ld, found \"%s\"", a, f->lo, f->hi, val);
        return FB_OK;
    case FB_ARG_LIST: {
        fb_arg_list *l = field;
        l->v[l->n++] = val;
        return FB_OK;
    }
    case FB_ARG_VALUE:
        return f->parse(a, val, field);
    default:
        return fb_fail(FB_ERR_INTERNAL, "%s: flag table entry without a value kind", a);
    }
}

fb_result fb_args_parse(const fb_argspec *spec, const char *command, const void *data, int argc, char **argv,
                        void *opts)
{
    /* every list gets room for all of argv */
    for (const fb_arg *const *t = spec->flags; t && *t; t++)
        for (const fb_arg *f = *t; f->kind != FB_ARG_END; f++)
            if (f->kind == FB_ARG_LIST && !list_at(opts, f->off)->v &&
                !(list_at(opts, f->off)->v = calloc((size_t)argc + 1, sizeof(char *))))
                return fb_fail(FB_ERR_NOMEM, "out of memory");
    fb_arg_list *files = list_at(opts, spec->files_off), *pass = spec->arity ? list_at(opts, spec->pass_off) : NULL;
    if (!(files->v = calloc((size_t)argc + 1, sizeof(char *))) ||
        (pass && !(pass->v = calloc((size_t)argc + 1, sizeof(char *)))))
        return fb_fail(FB_ERR_NOMEM, "out of memory");
    for (int i = 0; i < argc; i++) {
        char buf[64];
        const char *a = spec->rewrite ? spec->rewrite(argv[i], buf, sizeof buf) : argv[i];
        const char *val = i + 1 < argc ? argv[i + 1] : NULL;
        if (!a) return FB_ERR_USAGE;
        if (a[0] != '-' || !a[1]) { /* a file argument; "-": standard input or output */
            if (files->n >= spec->max_files)
                return spec->max_files
                           ? fb_fail(FB_ERR_USAGE, spec->too_many, a)
                           : fb_fail(FB_ERR_USAGE, "%s: `fractalbake %s` takes no file argument", a, command);
            files->v[files->n++] = a;
            continue;
        }
        const fb_arg *f = find(spec, a);
        if (f && (f->kind == FB_ARG_BOOL || f->kind == FB_ARG_IGNORED || f->kind == FB_ARG_DOCUMENT)) {
            if (f->kind != FB_ARG_IGNORED) *(bool *)((char *)opts + f->off) = true;
            if (f->kind == FB_ARG_DOCUMENT && fb_output_claim_stdout(f->name)) return FB_ERR_USAGE;
            continue;
        }
        if (f) {
            if (!val) return fb_fail(FB_ERR_USAGE, "%s: missing value", a);
            fb_result rc = take(f, a, val, opts);
            if (rc) return rc;
            i++;
            continue;
        }
        int arity = pass && !strncmp(a, "--", 2) ? spec->arity(data, a + 2) : -1;
        if (arity >= 0) {
            pass->v[pass->n++] = argv[i];
            if (arity == 1 && val) pass->v[pass->n++] = argv[++i];
            continue;
        }
        char h[96];
        hint(spec, data, a, h, sizeof h);
        return fb_fail(FB_ERR_USAGE, "%s: unknown flag for `fractalbake %s`%s (see fractalbake %s --help)", a, command,
                       h, command);
    }
    return FB_OK;
}

void fb_args_free(const fb_argspec *spec, void *opts)
{
    for (const fb_arg *const *t = spec->flags; t && *t; t++)
        for (const fb_arg *f = *t; f->kind != FB_ARG_END; f++)
            if (f->kind == FB_ARG_LIST) {
                free(list_at(opts, f->off)->v);
                list_at(opts, f->off)->v = NULL;
            }
    free(list_at(opts, spec->files_off)->v);
    list_at(opts, spec->files_off)->v = NULL;
    if (spec->arity) {
        free(list_at(opts, spec->pass_off)->v);
        list_at(opts, spec->pass_off)->v = NULL;
    }
}
