#include "pool.h"

#include <pthread.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>

struct fb_pool {
    pthread_mutex_t mu;
    pthread_cond_t work_cv, done_cv;
    pthread_t *threads;
    int nworkers; /* threads besides the caller */
    /* the current job */
    fb_task_fn fn;
    void *ctx;
    fb_scope scope; /* the starting thread's (fb.h): the workers work in it */
    int ntasks, next, finished;
    unsigned generation;
    bool quit;
};

/* Takes and runs tasks of the current job until none is left. Called with mu held; returns with it held. */
static void drain(fb_pool *p)
{
    while (p->next < p->ntasks) {
        int t = p->next++;
        fb_task_fn fn = p->fn;
        void *ctx = p->ctx;
        pthread_mutex_unlock(&p->mu);
        fn(ctx, t);
        pthread_mutex_lock(&p->mu);
        if (++p->finished == p->ntasks) pthread_cond_broadcast(&p->done_cv);
    }
}

static void *worker(void *arg)
{
    fb_pool *p = arg;
    unsigned seen = 0;
    pthread_mutex_lock(&p->mu);
    for (;;) {
        while (!p->quit && p->generation == seen) pthread_cond_wait(&p->work_cv, &p->mu);
        if (p->quit) break;
        seen = p->generation;
        fb_scope_set(p->scope);
        drain(p);
        fb_scope_set((fb_scope){0});
    }
    pthread_mutex_unlock(&p->mu);
    return NULL;
}

fb_result fb_pool_create(int nthreads, fb_pool **out)
{
    fb_pool *p = calloc(1, sizeof *p);
    if (!p) return fb_fail(FB_ERR_NOMEM, "out of memory");
    if (nthreads < 1) nthreads = 1;
    pthread_mutex_init(&p->mu, NULL);
    pthread_cond_init(&p->work_cv, NULL);
    pthread_cond_init(&p->done_cv, NULL);
    p->threads = calloc((size_t)nthreads, sizeof *p->threads);
    if (!p->threads) {
        fb_pool_destroy(&p);
        return fb_fail(FB_ERR_NOMEM, "out of memory");
    }
    for (int i = 0; i < nthreads - 1; i++) {
        if (pthread_create(&p->threads[i], NULL, worker, p) != 0) {
            fb_pool_destroy(&p);
            return fb_fail(FB_ERR_INTERNAL, "cannot start worker threads");
        }
        p->nworkers++;
    }
    *out = p;
    return FB_OK;
}

void fb_pool_destroy(fb_pool **pp)
{
    if (!pp || !*pp) return;
    fb_pool *p = *pp;
    pthread_mutex_lock(&p->mu);
    p->quit = true;
    pthread_cond_broadcast(&p->work_cv);
    pthread_mutex_unlock(&p->mu);
    for (int i = 0; i < p->nworkers; i++) pthread_join(p->threads[i], NULL);
    free(p->threads);
    pthread_mutex_destroy(&p->mu);
    pthread_cond_destroy(&p->work_cv);
    pthread_cond_destroy(&p->done_cv);
    memset(p, 0, sizeof *p);
    free(p);
    *pp = NULL;
}

int fb_pool_threads(const fb_pool *p)
{
    return p->nworkers + 1;
}

void fb_pool_start(fb_pool *p, int ntasks, fb_task_fn fn, void *ctx)
{
    if (ntasks <= 0) return;
    pthread_mutex_lock(&p->mu);
    if (NEVER(p->finished < p->ntasks)) { /* a job still running: finish it first */
        drain(p);
        while (p->finished < p->ntasks) pthread_cond_wait(&p->done_cv, &p->mu);
    }
    p->fn = fn;
    p->ctx = ctx;
    p->scope = fb_scope_capture();
    p->ntasks = ntasks;
    p->next = 0;
    p->finished = 0;
    p->generation++;
    pthread_cond_broadcast(&p->work_cv);
    pthread_mutex_unlock(&p->mu);
}

void fb_pool_wait(fb_pool *p)
{
    pthread_mutex_lock(&p->mu);
    drain(p);
    while (p->finished < p->ntasks) pthread_cond_wait(&p->done_cv, &p->mu);
    pthread_mutex_unlock(&p->mu);
}

void fb_pool_run(fb_pool *p, int ntasks, fb_task_fn fn, void *ctx)
{
    fb_pool_start(p, ntasks, fn, ctx);
    fb_pool_wait(p);
}
