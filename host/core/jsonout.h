/*
 * JSON text as people read it and programs parse it: keys sorted, numbers in their shortest form
 * that reads back as the same double (-0.3, not -0.29999999999999999), integers as integers.
 */
#ifndef FB_JSONOUT_H
#define FB_JSONOUT_H

#include <jansson.h>

/* The JSON text of j (any value): compact on one line when indent is 0, else one member or element
 * a line, indented by `indent` spaces a level. Returns malloc'd text, or NULL when out of memory. */
char *fb_json_dumps(const json_t *j, int indent);

/* The shortest decimal text of a finite double that strtod reads back as the same double, with a
 * ".0" when it would otherwise read as an integer; "null" for NaN and infinities (JSON has no
 * spelling for them). out holds at least 32 bytes. */
void fb_json_number(double v, char *out);

#endif
