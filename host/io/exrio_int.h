/* What exrio's writer and reader share: OpenEXRCore's context set-up and its last message. */
#ifndef FB_EXRIO_INT_H
#define FB_EXRIO_INT_H

#include <openexr.h>

/* A context initializer whose error handler keeps the message for exrio_exr_msg. */
exr_context_initializer_t exrio_initializer(void);
/* The last message OpenEXRCore gave this thread (the library itself never prints). */
const char *exrio_exr_msg(void);

#endif
