/* `fractalbake info`: what an EXR file holds. */
#ifndef FB_INFO_H
#define FB_INFO_H

#include "fb.h"

#include <stdbool.h>

/* Prints size, compression, layers (parts) and channels with types, attributes with their values
 * and the stored scene; or, with json, one JSON object of the same. */
fb_result fb_info(const char *path, bool json, void (*print)(const char *line, void *user), void *user);

#endif
