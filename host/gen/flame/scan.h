/*
 * Reading a .flame file (flam3's XML genomes, or its palette library) without trusting it. Flame files
 * come from the internet: the bytes stream through libxml2's SAX parser, which counts as they come
 * and refuses the file at the first count beyond its limit, before anything large is built; only a
 * file within every limit is then parsed into a tree (genome.c). Entities are never expanded (an
 * entity declaration is refused), no DTD is loaded, nothing is fetched from the network, and
 * libxml2's own messages become one logged line naming the file and the line.
 */
#ifndef FB_FLAME_SCAN_H
#define FB_FLAME_SCAN_H

#include "fb.h"

#include <libxml/tree.h>

#include <stddef.h>

/* The limits. A genome has at most 24 xforms and a final one (genome.h); each variation is an
 * attribute of its xform, so the attributes of an element bound its variations too (flam3 3.1.1 has
 * 99 variations and about 70 other attributes an xform may carry). A palette has 256 entries. */
#define FB_FLAME_SCAN_MAX_BYTES      (16u << 20) /* the file */
#define FB_FLAME_SCAN_MAX_FLAMES     4096        /* <flame> elements not inside another */
#define FB_FLAME_SCAN_MAX_ELEMENTS   (1 << 20)   /* in the file */
#define FB_FLAME_SCAN_MAX_DEPTH      64          /* elements inside one another (<edit> histories nest) */
#define FB_FLAME_SCAN_MAX_ATTRS      256         /* attributes of one element */
#define FB_FLAME_SCAN_MAX_ATTR_BYTES (64u << 10) /* one attribute's value */
#define FB_FLAME_SCAN_MAX_TEXT       (64u << 10) /* the text of one element (a <palette>'s hex digits) */
#define FB_FLAME_SCAN_MAX_PALETTE    256         /* <color>, <colors> and <palette> elements of one flame */

/* The whole of path (fb_input_open's rule: a regular file or a pipe), NUL-terminated and malloc'ed
 * into *text, checked against the limits as it streams in: FB_ERR_INPUT with one line naming the
 * file, the line and the count at the first one beyond its limit (or the first XML error). */
fb_result fb_flame_load(const char *path, char **text, size_t *len);

/* The tree of the XML text (len bytes; what names it in messages), after the same checks; entities
 * not expanded, no DTD, no network. Errors: one line naming `what` and the line (FB_ERR_INPUT, or
 * FB_ERR_NOMEM when libxml2 ran out of memory). The caller frees *doc with xmlFreeDoc. */
fb_result fb_flame_parse(const char *xml, size_t len, const char *what, xmlDocPtr *doc);

#endif
