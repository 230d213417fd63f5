/*
 * A fixed pool of worker threads for the native backend. fb_pool_run hands out task indices
 * 0..n-1 to the workers and the calling thread, and returns when all are done. Which thread runs
 * which task never affects a result: tasks write disjoint outputs computed from their index alone.
 */
#ifndef FB_POOL_H
#define FB_POOL_H

#include "fb.h"

typedef struct fb_pool fb_pool;
typedef void (*fb_task_fn)(void *ctx, int task);

/* nthreads counts the caller: nthreads == 1 runs everything on the calling thread. */
fb_result fb_pool_create(int nthreads, fb_pool **out);
void fb_pool_destroy(fb_pool **pool);
int fb_pool_threads(const fb_pool *pool);
void fb_pool_run(fb_pool *pool, int ntasks, fb_task_fn fn, void *ctx);

#endif
