/* tsan.h - what the ThreadSanitizer tests (tests/tsan_*.c) share, after
   test.h and examples/common/pool.h:

   - a pool that counts the threads its jobs ran on, so that a test can show
     that a header's parallel_for really ran jobs at once:
         tsan_pool tp = { ex_pool_create(3) };
         desc.parallel_for = tsan_parallel_for;   (any header's hook type)
         desc.parallel_user = &tp;
         ... build ...
         CHECK(tsan_busy_threads(&tp, &jobs) >= 2);
   - tsan_check_racy_run(name): runs this program again with --racy (the
     program then makes a deliberate race of its own) and checks that
     ThreadSanitizer reported it and failed the run, which proves that the
     sanitizer is on and that a race in the library would fail the test. */
#ifndef TESTS_TSAN_H
#define TESTS_TSAN_H

#include <pthread.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <unistd.h>

/* ---- a pool that counts the threads its jobs ran on ----------------------- */
/* The counters are relaxed atomics: they order nothing, so they hide no race
   of the library's jobs from ThreadSanitizer (a mutex here would). The job
   and its context travel in a per-call struct, so a parallel_for issued from
   inside a job (the pool runs it serially) cannot overwrite another's. */
typedef struct tsan_pool {
    ex_pool *pool;
    uint32_t jobs[EX_POOL_MAX_THREADS + 1];   /* [0]: the calling thread, [1 + i]: worker i */
} tsan_pool;

typedef struct tsan__call {
    tsan_pool *tp;
    void (*job)(void *ctx, uint32_t index);
    void *ctx;
} tsan__call;

static void tsan__counted_job(void *ctx, uint32_t index)
{
    tsan__call *call = (tsan__call *)ctx;
    pthread_t self = pthread_self();
    int i, slot = 0;
    for (i = 0; i < call->tp->pool->thread_count; i++)
        if (pthread_equal(self, call->tp->pool->threads[i])) slot = 1 + i;
    __atomic_fetch_add(&call->tp->jobs[slot], 1u, __ATOMIC_RELAXED);
    call->job(call->ctx, index);
}

/* The parallel_for hook of every header's desc; user is a tsan_pool. */
TEST__FN void tsan_parallel_for(void *user, void (*job)(void *ctx, uint32_t index), void *ctx, uint32_t count)
{
    tsan__call call;
    call.tp = (tsan_pool *)user;
    call.job = job;
    call.ctx = ctx;
    ex_pool_parallel_for(call.tp->pool, tsan__counted_job, &call, count);
}

/* Threads that ran at least one job since the last call, and the jobs in
   *jobs; clears the counts. Call it when no parallel_for is running. */
TEST__FN int tsan_busy_threads(tsan_pool *tp, uint32_t *jobs)
{
    int i, busy = 0;
    *jobs = 0;
    for (i = 0; i <= tp->pool->thread_count; i++) {
        *jobs += tp->jobs[i];
        busy += tp->jobs[i] > 0;
        tp->jobs[i] = 0;
    }
    return busy;
}

/* ---- ThreadSanitizer is on and catches a race ----------------------------- */
/* Runs this program again as `name --racy`, its output into a pipe, and
   checks the report. The racy run must race in a function named worker (the
   report's summary names it). */
TEST__FN void tsan_check_racy_run(const char *name)
{
    int fds[2], status = 0;
    pid_t pid;
    char buf[4096];
    size_t have = 0;
    static char out[1 << 16];
    ssize_t got;
    if (!CHECK(pipe(fds) == 0)) return;
    fflush(NULL);
    pid = fork();
    if (pid == 0) {   /* the child runs this program again, stdout and stderr into the pipe */
        char *args[3];
        args[0] = (char *)name;
        args[1] = (char *)"--racy";
        args[2] = NULL;
        close(fds[0]);
        dup2(fds[1], 1);
        dup2(fds[1], 2);
        close(fds[1]);
        execv("/proc/self/exe", args);
        _exit(127);
    }
    close(fds[1]);
    if (!CHECK(pid > 0)) { close(fds[0]); return; }
    while ((got = read(fds[0], buf, sizeof buf)) > 0) {   /* keep the first 64 KiB: the report comes first */
        size_t n = (size_t)got < sizeof out - 1 - have ? (size_t)got : sizeof out - 1 - have;
        memcpy(out + have, buf, n);
        have += n;
    }
    out[have] = '\0';
    close(fds[0]);
    waitpid(pid, &status, 0);
    test_note("--racy run: exit status %d, %zu bytes of output, %s", WIFEXITED(status) ? WEXITSTATUS(status) : -1,
              have, strstr(out, "WARNING: ThreadSanitizer: data race") ? "data race reported" : "NO report");
    CHECK(strstr(out, "WARNING: ThreadSanitizer: data race") != NULL);
    CHECK(strstr(out, "SUMMARY: ThreadSanitizer: data race") != NULL && strstr(out, " in worker") != NULL);
    CHECK(WIFEXITED(status) && WEXITSTATUS(status) != 0 && WEXITSTATUS(status) != 127);
}

#endif /* TESTS_TSAN_H */
