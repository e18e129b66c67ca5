/* pool.h - a small pthreads thread pool whose parallel_for matches the hook of
   every header's desc:

       void parallel_for(void *user, void (*job)(void *ctx, uint32_t index),
                         void *ctx, uint32_t count);

       ex_pool *pool = ex_pool_create(0);          // 0: one thread per core
       desc.parallel_for = ex_pool_parallel_for;
       desc.parallel_user = pool;
       ...
       ex_pool_destroy(pool);

   The calling thread works too. Jobs are handed out one index at a time from
   a shared counter, so uneven jobs balance. A parallel_for issued from inside
   a job (or while another is running) runs serially in its caller instead of
   deadlocking. The thread count can be forced with the environment variable
   EX_THREADS. */
#ifndef EXAMPLES_COMMON_POOL_H
#define EXAMPLES_COMMON_POOL_H

#if !defined(_POSIX_C_SOURCE) || _POSIX_C_SOURCE < 200809L
#  undef _POSIX_C_SOURCE
#  define _POSIX_C_SOURCE 200809L
#endif
#include <pthread.h>
#include <stdint.h>
#include <stdlib.h>
#include <unistd.h>

#include "base.h"

#define EX_POOL_MAX_THREADS 64

typedef void (*ex_job_fn)(void *ctx, uint32_t index);

typedef struct ex_pool {
    pthread_t threads[EX_POOL_MAX_THREADS];
    int thread_count;          /* workers, not counting the caller */
    pthread_mutex_t lock;
    pthread_cond_t wake, done;
    /* the batch being run, guarded by lock */
    ex_job_fn job;
    void *ctx;
    uint32_t count, next;      /* next index to hand out */
    uint32_t finished;         /* indices completed */
    uint64_t generation;       /* bumps once per batch */
    int busy, quit;
} ex_pool;

/* Takes the next index of the current batch, or returns 0 when none is left. */
static int ex__pool_take(ex_pool *p, uint32_t *index)
{
    int ok;
    pthread_mutex_lock(&p->lock);
    ok = p->next < p->count;
    if (ok) *index = p->next++;
    pthread_mutex_unlock(&p->lock);
    return ok;
}

static void ex__pool_work(ex_pool *p)
{
    uint32_t index;
    while (ex__pool_take(p, &index)) {
        p->job(p->ctx, index);
        pthread_mutex_lock(&p->lock);
        if (++p->finished == p->count) pthread_cond_broadcast(&p->done);
        pthread_mutex_unlock(&p->lock);
    }
}

static void *ex__pool_worker(void *arg)
{
    ex_pool *p = (ex_pool *)arg;
    uint64_t seen = 0;
    for (;;) {
        pthread_mutex_lock(&p->lock);
        while (!p->quit && p->generation == seen) pthread_cond_wait(&p->wake, &p->lock);
        if (p->quit) { pthread_mutex_unlock(&p->lock); return NULL; }
        seen = p->generation;
        pthread_mutex_unlock(&p->lock);
        ex__pool_work(p);
    }
}

/* threads: total threads including the caller; 0 = EX_THREADS or the core count. */
EX_FN ex_pool *ex_pool_create(int threads)
{
    ex_pool *p = (ex_pool *)calloc(1, sizeof *p);
    int i;
    if (!p) return NULL;
    if (threads <= 0) {
        const char *env = getenv("EX_THREADS");
        threads = env ? atoi(env) : (int)sysconf(_SC_NPROCESSORS_ONLN);
    }
    if (threads < 1) threads = 1;
    if (threads > EX_POOL_MAX_THREADS) threads = EX_POOL_MAX_THREADS;
    pthread_mutex_init(&p->lock, NULL);
    pthread_cond_init(&p->wake, NULL);
    pthread_cond_init(&p->done, NULL);
    for (i = 0; i < threads - 1; i++) {
        if (pthread_create(&p->threads[i], NULL, ex__pool_worker, p) != 0) break;
        p->thread_count++;
    }
    return p;
}

EX_FN void ex_pool_destroy(ex_pool *p)
{
    int i;
    if (!p) return;
    pthread_mutex_lock(&p->lock);
    p->quit = 1;
    pthread_cond_broadcast(&p->wake);
    pthread_mutex_unlock(&p->lock);
    for (i = 0; i < p->thread_count; i++) pthread_join(p->threads[i], NULL);
    pthread_mutex_destroy(&p->lock);
    pthread_cond_destroy(&p->wake);
    pthread_cond_destroy(&p->done);
    free(p);
}

/* Total threads that run jobs (workers plus the caller). */
EX_FN int ex_pool_threads(const ex_pool *p) { return p ? p->thread_count + 1 : 1; }

/* Runs job(ctx, i) for every i in [0, count) and returns when all are done. */
EX_FN void ex_pool_parallel_for(void *user, ex_job_fn job, void *ctx, uint32_t count)
{
    ex_pool *p = (ex_pool *)user;
    uint32_t i;
    int nested;
    if (count == 0) return;
    if (p) {
        pthread_mutex_lock(&p->lock);
        nested = p->busy;
        if (!nested) {
            p->busy = 1;
            p->job = job;
            p->ctx = ctx;
            p->count = count;
            p->next = 0;
            p->finished = 0;
            p->generation++;
            pthread_cond_broadcast(&p->wake);
        }
        pthread_mutex_unlock(&p->lock);
        if (!nested) {
            ex__pool_work(p);
            pthread_mutex_lock(&p->lock);
            while (p->finished < p->count) pthread_cond_wait(&p->done, &p->lock);
            p->busy = 0;
            pthread_mutex_unlock(&p->lock);
            return;
        }
    }
    for (i = 0; i < count; i++) job(ctx, i);
}

#endif /* EXAMPLES_COMMON_POOL_H */
