/* compare's HTML and JUnit reports (report.h). */
#include "report.h"

#include "output.h"

#include <jansson.h>

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static void esc(FILE *f, const char *s)
{
    for (; s && *s; s++) switch (*s) {
        case '<':
            fputs("&lt;", f);
            break;
        case '>':
            fputs("&gt;", f);
            break;
        case '&':
            fputs("&amp;", f);
            break;
        case '"':
            fputs("&quot;", f);
            break;
        case '\'':
            fputs("&#39;", f);
            break;
        default:
            fputc(*s, f);
        }
}

static void base64(FILE *f, const uint8_t *p, size_t n)
{
    static const char t[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    for (size_t i = 0; i < n; i += 3) {
        uint32_t v = (uint32_t)p[i] << 16 | (i + 1 < n ? (uint32_t)p[i + 1] << 8 : 0) | (i + 2 < n ? p[i + 2] : 0);
        char o[4] = {t[v >> 18 & 63], t[v >> 12 & 63], i + 1 < n ? t[v >> 6 & 63] : '=', i + 2 < n ? t[v & 63] : '='};
        fwrite(o, 1, 4, f);
    }
}

static const char *vname(fb_verdict v)
{
    return v == FB_VERDICT_FAIL ? "fail" : v == FB_VERDICT_WARN ? "warn" : "pass";
}

static const char CSS[] =
    "body{font:14px/1.4 sans-serif;margin:0;background:#fafafa;color:#222}"
    "header{padding:12px 20px;background:#fff;border-bottom:1px solid #ddd}"
    "h1{font-size:18px;margin:0 0 4px}section{margin:16px 20px;background:#fff;border:1px solid #ddd}"
    ".banner{padding:8px 12px;color:#fff;font-weight:bold}.fail{background:#c62828}.warn{background:#ef6c00}"
    ".pass{background:#2e7d32}.pics{display:flex;flex-wrap:wrap;gap:12px;padding:12px}"
    "figure{margin:0}figcaption{font-size:12px;color:#555}"
    "img.thumb{width:256px;image-rendering:pixelated;cursor:zoom-in;border:1px solid #ccc;background:#000}"
    "table{border-collapse:collapse;margin:0 12px 12px}td,th{padding:2px 8px;border-bottom:1px solid #eee;"
    "text-align:left;font-family:monospace;font-size:12px}td.v-fail{color:#c62828}td.v-warn{color:#ef6c00}"
    "#full{display:none;position:fixed;inset:0;background:rgba(0,0,0,.85);overflow:auto;cursor:zoom-out}"
    "#full img{display:block;margin:20px auto;image-rendering:pixelated}ul{margin:4px 0}";

/* A click shows a picture at full size (and #full=N in the address opens picture N so); once loaded,
 * body[data-images] says how many of how many pictures loaded, for a reader and for tests. */
static const char JS[] =
    "function show(i){var f=document.getElementById('full');f.firstChild.src=i.src;f.style.display='block';}"
    "document.getElementById('full').onclick=function(){this.style.display='none';};"
    "window.addEventListener('load',function(){var im=document.querySelectorAll('img.thumb'),ok=0;"
    "for(var k=0;k<im.length;k++)if(im[k].complete&&im[k].naturalWidth>0)ok++;"
    "document.body.setAttribute('data-images',ok+'/'+im.length);"
    "var m=/^#full=(\\d+)$/.exec(location.hash);if(m&&im[+m[1]])show(im[+m[1]]);});";

static void layer_html(FILE *f, const fb_report_layer *L, int index)
{
    fprintf(f, "<section id=\"layer-%d\" class=\"layer\" data-verdict=\"%s\"><div class=\"banner %s\">", index,
            vname(L->verdict), vname(L->verdict));
    esc(f, L->name[0] ? L->name : "(channels without a layer)");
    fprintf(f, ": %s</div><div class=\"pics\">",
            L->verdict == FB_VERDICT_FAIL   ? "FAIL"
            : L->verdict == FB_VERDICT_WARN ? "WARN"
                                            : "PASS");
    for (int i = 0; i < L->nimg; i++) {
        fputs("<figure><img class=\"thumb\" onclick=\"show(this)\" alt=\"", f);
        esc(f, L->img[i].label);
        fputs("\" src=\"data:image/png;base64,", f);
        base64(f, L->img[i].png, L->img[i].size);
        fputs("\"><figcaption>", f);
        esc(f, L->img[i].label);
        fprintf(f, " (%d x %d; click for full size)</figcaption></figure>", L->img[i].width, L->img[i].height);
    }
    fputs("</div><table><tr><th>channel</th><th>statistics</th><th>verdict</th></tr>", f);
    for (int i = 0; i < L->nrows; i++) {
        const fb_report_row *r = &L->rows[i];
        fputs("<tr><td>", f);
        esc(f, r->name);
        fputs("</td><td>", f);
        esc(f, r->stats);
        fprintf(f, "</td><td class=\"v-%s\">%s", vname(r->verdict), vname(r->verdict));
        if (r->why[0]) fputs(": ", f), esc(f, r->why);
        fputs("</td></tr>", f);
    }
    fputs("</table></section>\n", f);
}

fb_result fb_report_html(const char *path, const fb_report *r)
{
    FILE *f = NULL;
    fb_result rc = fb_output_fopen(path, "HTML report", (void **)&f);
    if (rc) return rc;
    fprintf(f,
            "<!DOCTYPE html><html lang=\"en\"><head><meta charset=\"utf-8\"><title>compare: %s</title>"
            "<style>%s</style></head><body>\n<header><h1>",
            vname(r->verdict), CSS);
    esc(f, r->a);
    fputs(" vs ", f);
    esc(f, r->b);
    fprintf(f, ": <span class=\"v-%s\">%s</span></h1><div>", vname(r->verdict), vname(r->verdict));
    if (r->reason && r->reason[0]) esc(f, r->reason);
    fprintf(f, "</div><div>%d x %d", r->width, r->height);
    if (r->shown_width != r->width) fprintf(f, ", pictures shown at %d x %d", r->shown_width, r->shown_height);
    fprintf(f, "; %d layers, failing first</div><div>Scene keys that differ: ", r->nlayers);
    if (r->scene_note) {
        esc(f, r->scene_note);
    } else if (r->ndiffs == 0) {
        fputs("none", f);
    } else {
        fputs("<ul>", f);
        for (int i = 0; i < r->ndiffs; i++) fputs("<li>", f), esc(f, r->scene_diffs[i]), fputs("</li>", f);
        fputs("</ul>", f);
    }
    fputs("</div></header>\n", f);
    for (int i = 0; i < r->nlayers; i++) layer_html(f, &r->layers[i], i);
    fprintf(f, "<div id=\"full\"><img alt=\"full size\"></div><script>%s</script></body></html>\n", JS);
    if (ferror(f)) rc = fb_fail(FB_ERR_IO, "%s: cannot write the HTML report", path);
    if (fclose(f) != 0 && !rc) rc = fb_fail(FB_ERR_IO, "%s: cannot write the HTML report", path);
    return fb_output_done(path, rc);
}

/* ---- stored scenes: the keys whose values differ ------------------------------------------- */

static void add_line(char ***lines, int *n, const char *key, const char *va, const char *vb)
{
    char **l = realloc(*lines, sizeof **lines * (size_t)(*n + 1));
    if (!l) return;
    *lines = l;
    size_t len = strlen(key) + strlen(va) + strlen(vb) + 32;
    if ((l[*n] = malloc(len))) snprintf(l[*n], len, "%s: %s in A, %s in B", key, va, vb), (*n)++;
}

static void walk(const json_t *a, const json_t *b, const char *key, char ***lines, int *n);

static void walk_object(const json_t *a, const json_t *b, const char *key, char ***lines, int *n)
{
    const char *k;
    json_t *v;
    char sub[512];
    json_object_foreach((json_t *)a, k, v)
    {
        snprintf(sub, sizeof sub, "%s%s%s", key, key[0] ? "." : "", k);
        walk(v, json_object_get(b, k), sub, lines, n);
    }
    json_object_foreach((json_t *)b, k, v) if (!json_object_get(a, k))
    {
        snprintf(sub, sizeof sub, "%s%s%s", key, key[0] ? "." : "", k);
        walk(NULL, v, sub, lines, n);
    }
}

/* layers by name where they have one ("layers.sky.octaves"), else by index */
static void walk_array(const json_t *a, const json_t *b, const char *key, char ***lines, int *n)
{
    size_t na = json_array_size(a), nb = json_array_size(b), m = na > nb ? na : nb;
    char sub[512];
    for (size_t i = 0; i < m; i++) {
        const json_t *x = json_array_get(a, i), *y = json_array_get(b, i);
        const char *nx = json_string_value(json_object_get(x, "name")),
                   *ny = json_string_value(json_object_get(y, "name"));
        if (nx && ny && !strcmp(nx, ny))
            snprintf(sub, sizeof sub, "%s.%s", key, nx);
        else
            snprintf(sub, sizeof sub, "%s[%zu]", key, i);
        walk(x, y, sub, lines, n);
    }
}

static void walk(const json_t *a, const json_t *b, const char *key, char ***lines, int *n)
{
    if (a && b && json_is_object(a) && json_is_object(b)) return walk_object(a, b, key, lines, n);
    if (a && b && json_is_array(a) && json_is_array(b)) return walk_array(a, b, key, lines, n);
    if (a && b && json_equal((json_t *)a, (json_t *)b)) return;
    char *ta = a ? json_dumps(a, JSON_ENCODE_ANY | JSON_COMPACT) : NULL;
    char *tb = b ? json_dumps(b, JSON_ENCODE_ANY | JSON_COMPACT) : NULL;
    add_line(lines, n, key, ta ? ta : "absent", tb ? tb : "absent");
    free(ta);
    free(tb);
}

fb_result fb_report_scene_diff(const char *a, const char *b, char ***lines, int *n)
{
    *lines = NULL, *n = 0;
    json_t *ja = a ? json_loads(a, 0, NULL) : NULL, *jb = b ? json_loads(b, 0, NULL) : NULL;
    if (ja || jb) walk(ja, jb, "", lines, n);
    json_decref(ja);
    json_decref(jb);
    return FB_OK;
}

/* ---- JUnit ---------------------------------------------------------------------------------- */

fb_result fb_report_junit(const char *path, const char *suite, const fb_junit_case *cases, int n, double seconds)
{
    FILE *f = NULL;
    fb_result rc = fb_output_fopen(path, "JUnit report", (void **)&f);
    if (rc) return rc;
    int failures = 0;
    for (int i = 0; i < n; i++) failures += cases[i].failed;
    fputs("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<testsuites><testsuite name=\"", f);
    esc(f, suite);
    fprintf(f, "\" tests=\"%d\" failures=\"%d\" errors=\"0\" skipped=\"0\" time=\"%.3f\">\n", n, failures, seconds);
    for (int i = 0; i < n; i++) {
        fputs("  <testcase classname=\"", f);
        esc(f, cases[i].classname);
        fputs("\" name=\"", f);
        esc(f, cases[i].name);
        fputs("\" time=\"0\">", f);
        if (cases[i].failed) fputs("<failure message=\"", f), esc(f, cases[i].message), fputs("\"/>", f);
        if (cases[i].warned) fputs("<system-out>warning: ", f), esc(f, cases[i].message), fputs("</system-out>", f);
        fputs("</testcase>\n", f);
    }
    fputs("</testsuite></testsuites>\n", f);
    if (ferror(f)) rc = fb_fail(FB_ERR_IO, "%s: cannot write the JUnit report", path);
    if (fclose(f) != 0 && !rc) rc = fb_fail(FB_ERR_IO, "%s: cannot write the JUnit report", path);
    return fb_output_done(path, rc);
}
