/*
 * Reading .flame files without trusting them (see scan.h).
 */
#include "scan.h"
#include "genome.h"
#include "textin.h"

#include <libxml/SAX2.h>
#include <libxml/parser.h>
#include <libxml/xmlerror.h>

#include <errno.h>
#include <stdarg.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* libxml2's first error of a parse, caught instead of printed. */
typedef struct xml_errors {
    bool set, nomem;
    int line;
    char msg[160];
    xmlGenericErrorFunc old_generic;
    void *old_generic_ctx;
    xmlStructuredErrorFunc old_structured;
    void *old_structured_ctx;
} xml_errors;

static void on_structured(void *user, xmlErrorPtr e)
{
    xml_errors *x = user;
    if (x->set || !e || e->level < XML_ERR_ERROR) return;
    x->set = true;
    x->nomem = e->code == XML_ERR_NO_MEMORY || e->domain == XML_FROM_MEMORY;
    x->line = e->line;
    snprintf(x->msg, sizeof x->msg, "%s", e->message ? e->message : "parse error");
    x->msg[strcspn(x->msg, "\n")] = 0;
}

/* What libxml2 prints without a context (some of its out-of-memory paths): nothing. */
static void on_generic(void *user, const char *fmt, ...)
{
    (void)user, (void)fmt;
}

/* libxml2 keeps its handlers per thread: ours for the parse, then the previous ones back. */
static void errors_begin(xml_errors *x)
{
    *x = (xml_errors){.old_generic = xmlGenericError,
                      .old_generic_ctx = xmlGenericErrorContext,
                      .old_structured = xmlStructuredError,
                      .old_structured_ctx = xmlStructuredErrorContext};
    xmlSetGenericErrorFunc(NULL, on_generic);
    xmlSetStructuredErrorFunc(x, on_structured);
}

static void errors_end(xml_errors *x)
{
    xmlSetGenericErrorFunc(x->old_generic_ctx, x->old_generic);
    xmlSetStructuredErrorFunc(x->old_structured_ctx, x->old_structured);
}

/* The one line for libxml2's error. */
static fb_result xml_error(const char *what, const xml_errors *x)
{
    if (x->nomem) return fb_fail(FB_ERR_NOMEM, "%s:%d: out of memory reading the XML", what, x->line);
    return fb_fail(FB_ERR_INPUT, "%s:%d: not well-formed XML: %s", what, x->line, x->msg);
}

/* ---- the counting pass ------------------------------------------------------------------------- */

typedef struct level {
    bool flame;                 /* a <flame> element */
    int xforms, finals, colors; /* a flame's children so far */
} level;

typedef struct scan {
    const char *what;
    xmlParserCtxtPtr ctxt;
    fb_result rc; /* the first refusal (logged) */
    int depth;    /* elements open */
    int in_flame; /* of them, <flame> elements */
    int flames;
    long elements;
    size_t text; /* of the innermost open element */
    level lv[FB_FLAME_SCAN_MAX_DEPTH + 1];
} scan;

static void refuse(scan *s, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static void refuse(scan *s, const char *fmt, ...)
{
    if (s->rc) return;
    char msg[256];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    s->rc = fb_fail(FB_ERR_INPUT, "%s:%d: %s", s->what, xmlSAX2GetLineNumber(s->ctxt), msg);
    xmlStopParser(s->ctxt);
}

static void on_start(void *user, const xmlChar *name, const xmlChar *prefix, const xmlChar *uri, int nns,
                     const xmlChar **ns, int nattrs, int ndefaulted, const xmlChar **attrs)
{
    (void)prefix, (void)uri, (void)nns, (void)ns, (void)ndefaulted;
    scan *s = user;
    const char *en = (const char *)name;
    if (s->rc) return;
    s->text = 0;
    if (++s->elements > FB_FLAME_SCAN_MAX_ELEMENTS)
        return refuse(s, "more than %d elements (a .flame file holds at most %d flames)", FB_FLAME_SCAN_MAX_ELEMENTS,
                      FB_FLAME_SCAN_MAX_FLAMES);
    if (s->depth == FB_FLAME_SCAN_MAX_DEPTH)
        return refuse(s, "<%s>: elements nested more than %d deep", en, FB_FLAME_SCAN_MAX_DEPTH);
    if (nattrs > FB_FLAME_SCAN_MAX_ATTRS)
        return refuse(s, "<%s>: %d attributes, more than %d (flam3 has 99 variations and about 70 other attributes)",
                      en, nattrs, FB_FLAME_SCAN_MAX_ATTRS);
    for (int i = 0; i < nattrs; i++) { /* localname, prefix, URI, value, end */
        size_t n = (size_t)(attrs[5 * i + 4] - attrs[5 * i + 3]);
        if (n > FB_FLAME_SCAN_MAX_ATTR_BYTES)
            return refuse(s, "<%s %s>: a value of %zu bytes, more than %u KiB", en, (const char *)attrs[5 * i], n,
                          FB_FLAME_SCAN_MAX_ATTR_BYTES >> 10);
    }
    level *parent = &s->lv[s->depth];
    if (s->depth > 0 && parent->flame) {
        if (!strcmp(en, "xform") && ++parent->xforms > FB_FLAME_MAX_XFORMS)
            return refuse(s, "more than %d xforms in one <flame>", FB_FLAME_MAX_XFORMS);
        if (!strcmp(en, "finalxform") && ++parent->finals > 1) return refuse(s, "more than one <finalxform>");
        if ((!strcmp(en, "color") || !strcmp(en, "colors") || !strcmp(en, "palette")) &&
            ++parent->colors > FB_FLAME_SCAN_MAX_PALETTE)
            return refuse(s, "more than %d palette elements (<color>, <colors>, <palette>) in one <flame>",
                          FB_FLAME_SCAN_MAX_PALETTE);
    }
    bool flame = !strcmp(en, "flame");
    if (flame && !s->in_flame && ++s->flames > FB_FLAME_SCAN_MAX_FLAMES)
        return refuse(s, "more than %d <flame> elements", FB_FLAME_SCAN_MAX_FLAMES);
    s->in_flame += flame;
    s->lv[++s->depth] = (level){.flame = flame};
}

static void on_end(void *user, const xmlChar *name, const xmlChar *prefix, const xmlChar *uri)
{
    (void)name, (void)prefix, (void)uri;
    scan *s = user;
    if (s->rc || s->depth == 0) return;
    s->in_flame -= s->lv[s->depth--].flame;
    s->text = 0;
}

static void on_text(void *user, const xmlChar *ch, int len)
{
    (void)ch;
    scan *s = user;
    if (!s->rc && (s->text += (size_t)len) > FB_FLAME_SCAN_MAX_TEXT)
        refuse(s, "more than %u KiB of text in one element", FB_FLAME_SCAN_MAX_TEXT >> 10);
}

static void on_entity(void *user, const xmlChar *name, int type, const xmlChar *id, const xmlChar *sys,
                      xmlChar *content)
{
    (void)type, (void)id, (void)sys, (void)content;
    refuse(user, "declares the entity %s: entities are not expanded in a .flame file", (const char *)name);
}

/* Only these: no tree is built, no entity stored, no external subset loaded. */
static xmlSAXHandler sax(void)
{
    xmlSAXHandler h;
    memset(&h, 0, sizeof h);
    h.initialized = XML_SAX2_MAGIC;
    h.startElementNs = on_start;
    h.endElementNs = on_end;
    h.characters = on_text;
    h.cdataBlock = on_text;
    h.entityDecl = on_entity;
    return h;
}

static xmlParserCtxtPtr scan_begin(scan *s, const char *what)
{
    xmlSAXHandler h = sax();
    *s = (scan){.what = what};
    s->ctxt = xmlCreatePushParserCtxt(&h, s, NULL, 0, what);
    if (s->ctxt) xmlCtxtUseOptions(s->ctxt, XML_PARSE_NONET | XML_PARSE_NOERROR | XML_PARSE_NOWARNING);
    return s->ctxt;
}

/* Feeds n bytes (last: the end of the file); false once the file is refused or not well-formed. */
static bool scan_feed(scan *s, const char *bytes, size_t n, bool last, const xml_errors *x)
{
    xmlParseChunk(s->ctxt, bytes, (int)n, last);
    return !s->rc && !x->set;
}

/* The scan's verdict, once fed: its refusal, libxml2's error, or none. */
static fb_result scan_end(scan *s, const xml_errors *x)
{
    fb_result rc = s->rc ? s->rc : x->set ? xml_error(s->what, x) : FB_OK;
    /* libxml2 makes a document to hold a DOCTYPE's entities even for SAX, and leaves it to us */
    if (s->ctxt->myDoc) xmlFreeDoc(s->ctxt->myDoc);
    xmlFreeParserCtxt(s->ctxt);
    return rc;
}

fb_result fb_flame_load(const char *path, char **text, size_t *len)
{
    *text = NULL;
    *len = 0;
    FILE *f = NULL;
    fb_result rc = fb_input_open(path, "flame", &f);
    if (rc) return rc;
    xml_errors x;
    scan s;
    errors_begin(&x);
    if (!scan_begin(&s, path)) {
        errors_end(&x);
        fclose(f);
        return fb_fail(FB_ERR_NOMEM, "%s: out of memory for the XML reader", path);
    }
    char *buf = NULL, chunk[1 << 16];
    size_t n = 0, cap = 0, got;
    bool going = true;
    while (going && !rc && (got = fread(chunk, 1, sizeof chunk, f)) > 0) {
        if (n + got > FB_FLAME_SCAN_MAX_BYTES) {
            rc = fb_fail(FB_ERR_INPUT, "%s: larger than %u MiB (expected the flame file)", path,
                         FB_FLAME_SCAN_MAX_BYTES >> 20);
            break;
        }
        if (n + got + 1 > cap) {
            size_t grown = cap ? 2 * cap : sizeof chunk + 1;
            while (grown < n + got + 1) grown *= 2;
            char *t = realloc(buf, grown);
            if (!t) {
                rc = fb_fail(FB_ERR_NOMEM, "%s: out of memory reading the flame file", path);
                break;
            }
            buf = t, cap = grown;
        }
        memcpy(buf + n, chunk, got);
        n += got;
        going = scan_feed(&s, chunk, got, false, &x);
    }
    if (!rc && ferror(f)) rc = fb_fail(FB_ERR_INPUT, "%s: cannot read the flame file: %s", path, strerror(errno));
    if (!rc && n == 0 && fb_input_is_fifo(path, f)) rc = fb_input_fifo_empty(path, "flame");
    if (!rc && going) scan_feed(&s, NULL, 0, true, &x);
    fb_result src = scan_end(&s, &x);
    errors_end(&x);
    fclose(f);
    if (!rc) rc = src;
    if (rc) {
        free(buf);
        return rc;
    }
    if (!buf && !(buf = malloc(1))) return fb_fail(FB_ERR_NOMEM, "out of memory");
    buf[n] = 0;
    *text = buf;
    *len = n;
    return FB_OK;
}

fb_result fb_flame_parse(const char *xml, size_t len, const char *what, xmlDocPtr *doc)
{
    *doc = NULL;
    if (len > FB_FLAME_SCAN_MAX_BYTES)
        return fb_fail(FB_ERR_INPUT, "%s: larger than %u MiB", what, FB_FLAME_SCAN_MAX_BYTES >> 20);
    xml_errors x;
    scan s;
    errors_begin(&x);
    fb_result rc = FB_OK;
    if (!scan_begin(&s, what)) {
        rc = fb_fail(FB_ERR_NOMEM, "%s: out of memory for the XML reader", what);
    } else {
        bool going = true;
        for (size_t at = 0; going && at < len; at += 1 << 16)
            going = scan_feed(&s, xml + at, len - at < (1u << 16) ? len - at : 1u << 16, false, &x);
        if (going) scan_feed(&s, NULL, 0, true, &x);
        rc = scan_end(&s, &x);
    }
    if (!rc) {
        x.set = false;
        *doc = xmlReadMemory(xml, (int)len, what, NULL, XML_PARSE_NONET | XML_PARSE_NOERROR | XML_PARSE_NOWARNING);
        if (!*doc) rc = x.set ? xml_error(what, &x) : fb_fail(FB_ERR_NOMEM, "%s: out of memory reading the XML", what);
    }
    errors_end(&x);
    return rc;
}
