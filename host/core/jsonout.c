#include "jsonout.h"

#include "fb.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

void fb_json_number(double v, char *out)
{
    if (!isfinite(v)) {
        strcpy(out, "null");
        return;
    }
    fb_format_shortest(v, out, 32);
    if (!strpbrk(out, ".eEn")) strcat(out, ".0"); /* a real stays a real: 1.0, not 1 */
}

typedef struct sbuf {
    char *s;
    size_t n, cap;
    int oom;
} sbuf;

static void put(sbuf *b, const char *t, size_t n)
{
    if (b->oom) return;
    if (b->n + n + 1 > b->cap) {
        size_t cap = b->cap ? b->cap : 256;
        while (cap < b->n + n + 1) cap *= 2;
        char *s = realloc(b->s, cap);
        if (!s) {
            b->oom = 1;
            return;
        }
        b->s = s, b->cap = cap;
    }
    memcpy(b->s + b->n, t, n);
    b->n += n;
    b->s[b->n] = 0;
}

static void puts_(sbuf *b, const char *t)
{
    put(b, t, strlen(t));
}

static void put_string(sbuf *b, const char *s, size_t len)
{
    put(b, "\"", 1);
    for (size_t i = 0; i < len; i++) {
        unsigned char c = (unsigned char)s[i];
        char esc[8];
        if (c == '"' || c == '\\') {
            esc[0] = '\\', esc[1] = (char)c;
            put(b, esc, 2);
        } else if (c < 0x20) {
            snprintf(esc, sizeof esc, "\\u%04x", c);
            puts_(b, esc);
        } else {
            put(b, (const char *)&s[i], 1);
        }
    }
    put(b, "\"", 1);
}

static void newline(sbuf *b, int indent, int level)
{
    if (!indent) return;
    put(b, "\n", 1);
    for (int i = 0; i < indent * level; i++) put(b, " ", 1);
}

static int cmp_keys(const void *a, const void *b)
{
    return strcmp(*(const char *const *)a, *(const char *const *)b);
}

static void dump(sbuf *b, const json_t *j, int indent, int level)
{
    char num[40];
    switch (json_typeof(j)) {
    case JSON_OBJECT: {
        size_t n = json_object_size(j), k = 0;
        const char **keys = malloc((n ? n : 1) * sizeof *keys);
        if (!keys) {
            b->oom = 1;
            return;
        }
        const char *key;
        json_t *v;
        json_object_foreach((json_t *)j, key, v) keys[k++] = key;
        qsort(keys, n, sizeof *keys, cmp_keys);
        put(b, "{", 1);
        for (k = 0; k < n; k++) {
            if (k) put(b, ",", 1);
            newline(b, indent, level + 1);
            put_string(b, keys[k], strlen(keys[k]));
            puts_(b, indent ? ": " : ":");
            dump(b, json_object_get(j, keys[k]), indent, level + 1);
        }
        if (n) newline(b, indent, level);
        put(b, "}", 1);
        free(keys);
        break;
    }
    case JSON_ARRAY: {
        size_t n = json_array_size(j);
        /* short lists of numbers (a size, a colour, a point) stay on one line */
        int flat = n <= 8;
        for (size_t k = 0; k < n && flat; k++) flat = json_is_number(json_array_get(j, k));
        put(b, "[", 1);
        for (size_t k = 0; k < n; k++) {
            if (k) puts_(b, flat && indent ? ", " : ",");
            if (!flat) newline(b, indent, level + 1);
            dump(b, json_array_get(j, k), indent, level + 1);
        }
        if (n && !flat) newline(b, indent, level);
        put(b, "]", 1);
        break;
    }
    case JSON_STRING:
        put_string(b, json_string_value(j), json_string_length(j));
        break;
    case JSON_INTEGER:
        snprintf(num, sizeof num, "%" JSON_INTEGER_FORMAT, json_integer_value(j));
        puts_(b, num);
        break;
    case JSON_REAL:
        fb_json_number(json_real_value(j), num);
        puts_(b, num);
        break;
    case JSON_TRUE:
        puts_(b, "true");
        break;
    case JSON_FALSE:
        puts_(b, "false");
        break;
    case JSON_NULL:
        puts_(b, "null");
        break;
    }
}

char *fb_json_dumps(const json_t *j, int indent)
{
    sbuf b = {0};
    dump(&b, j, indent, 0);
    if (b.oom) {
        free(b.s);
        return NULL;
    }
    return b.s ? b.s : strdup("");
}
