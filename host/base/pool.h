/*
 * A fixed pool of worker threads for the native backend. fb_pool_run hands out task indices
 * 0..n-1 to the workers and the calling thread, and returns when all are done; fb_pool_start and
 * fb_pool_wait split it in two, so that the caller can do other work while the workers start. Which thread runs
 * which task never affects a result: tasks write disjoint outputs computed from their index alone. The
 * workers run a job's tasks in the scope (fb.h: log, outputs, progress) of the thread that started it.
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

/* Hands tasks 0..ntasks-1 to the workers and returns at once. One job at a time: every start is
 * followed by fb_pool_wait before the next start or run. ctx must live until the wait returns. */
void fb_pool_start(fb_pool *pool, int ntasks, fb_task_fn fn, void *ctx);

/* The caller runs what the workers have not taken yet, then waits until every task of the job
 * started last is done. Does nothing when no job is running. */
void fb_pool_wait(fb_pool *pool);

#endif
