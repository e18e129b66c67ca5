/* Concurrency test of irrvol.h under ThreadSanitizer.
   1. Three threads use one shared volume at once: single queries (nearest,
      bilinear, the volume's filter, glossy, plain trilinear, harmonics),
      irrvol_query_many batches, irrvol_info, irrvol_sample /
      irrvol_sample_values, the bin functions, irrvol_gpu_export and
      irrvol_save_to_memory, while irrvol_visibility_ratio runs on one
      shared const desc. Every answer must equal, bit for bit, the same call
      made serially beforehand.
   2. A volume built through desc.parallel_for driven by a real thread pool
      (examples/common/pool.h) saves to the same bytes as one built serially,
      and its jobs ran on more than one thread.
   ThreadSanitizer makes the process exit non-zero (66) after any report, so
   a race in the library fails the run even when every comparison passes.
   3. To show that this holds, the program runs itself again with --racy:
      the same concurrent queries, but every thread also adds its results
      into one unsynchronised sum, a caller's race. That run must print a
      data race report and exit non-zero. */
#if !defined(_POSIX_C_SOURCE) || _POSIX_C_SOURCE < 200809L
#  undef _POSIX_C_SOURCE
#  define _POSIX_C_SOURCE 200809L   /* fork, execv, pipe, pthread_barrier */
#endif
#define IRRVOL_IMPLEMENTATION
#include "irrvol.h"
#include <pthread.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>
#include "tests/test.h"
#include "tests/test_irrvol_scenes.h"
#include "examples/common/pool.h"

/* 3 threads on the 2 cores of the test machine: more threads than cores,
   so the scheduler interleaves them mid-call as well as running two at once. */
#define THREADS 3
/* 1500 queries of each kind per round (a few million float loads from all
   over the volume), 8 rounds per thread: about a second of the three threads
   in the library under ThreadSanitizer, so that every kind of call of one
   thread overlaps every kind of another many times; more only costs time. */
#define QUERIES 1500u
#define ROUNDS 8


static uint64_t mix(uint64_t z)
{
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}
static float unitf(uint64_t *s) { *s = mix(*s + 0x9E3779B97F4A7C15ull); return (float)(*s >> 40) / 16777216.0f; }

static double seconds(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

/* ---- the scene: the cube [-1, 1]^3 with a table, a small IMPORTANT lamp
   and a mirror wall, so that the build runs every kind of job (mirror
   chains, informed sampling, supersample jitter, second-level grids) --- */
typedef struct scene {
    sc_scene mesh;
    irrvol_material mats[8];
} scene;

static void make_scene(scene *s, irrvol_desc *d)
{
    sc_cube(&s->mesh);
    sc_square(&s->mesh, 1, -0.3f, 0.2f, 0.1f, 0.25f, 6);   /* a table */
    sc_square(&s->mesh, 1, 0.8f, -0.5f, 0.5f, 0.1f, 7);    /* a lamp */
    memset(s->mats, 0, sizeof s->mats);
    sc_set3(s->mats[0].radiance, 0.3f, 0.2f, 0.1f);
    sc_set3(s->mats[3].radiance, 0.5f, 0.5f, 0.5f);
    sc_set3(s->mats[2].specular, 0.4f, 0.4f, 0.4f);
    sc_set3(s->mats[6].radiance, 0.2f, 0.4f, 0.1f);
    sc_set3(s->mats[7].radiance, 30, 28, 20);
    s->mats[7].flags = IRRVOL_MATERIAL_IMPORTANT;
    memset(d, 0, sizeof *d);
    d->positions = s->mesh.pos;
    d->vertex_count = s->mesh.nv;
    d->indices = s->mesh.idx;
    d->triangle_count = s->mesh.nt;
    d->triangle_materials = s->mesh.mat;
    d->materials = s->mats;
    d->material_count = 8;
    /* 4 x 3 x 3 first-level samples, k = 5 (50 bins), 2 x 2 rays per bin:
       107 samples, a build of about 0.3 s under ThreadSanitizer; the sizes
       only need to give the jobs real work, not accuracy */
    d->grid_samples[0] = 4;
    d->grid_samples[1] = d->grid_samples[2] = 3;
    d->resolution = 5;
    d->supersamples = 2;
    d->moment = 4;            /* a moment volume: irrvol_query_glossy is meant for it */
    d->keep_radiance = 1;     /* the saved bytes hold the gathered radiance too */
    d->seed = 2024;
}

/* ---- queries --------------------------------------------------------- */
/* Positions in [-1.1, 1.1]^3, a little outside the grid too (they clamp),
   unit directions, normals and view vectors. */
typedef struct query_set {
    float pos[3 * QUERIES], dir[3 * QUERIES], normal[3 * QUERIES], eye[3 * QUERIES];
} query_set;

static void random_unit(uint64_t *s, float d[3])
{
    float z = 2.0f * unitf(s) - 1.0f, phi = 6.2831853f * unitf(s), r = sqrtf(1.0f - z * z);
    sc_set3(d, r * cosf(phi), r * sinf(phi), z);
}

static void make_queries(query_set *q)
{
    uint64_t s = 99;
    uint32_t i, k;
    for (i = 0; i < QUERIES; i++) {
        for (k = 0; k < 3; k++) q->pos[3 * i + k] = 2.2f * unitf(&s) - 1.1f;
        random_unit(&s, q->dir + 3 * i);
        random_unit(&s, q->normal + 3 * i);
        random_unit(&s, q->eye + 3 * i);
    }
}

/* Every answer a thread computes from the shared volume. */
typedef struct answers {
    float nearest[3 * QUERIES], bilinear[3 * QUERIES], plain[3 * QUERIES], glossy[3 * QUERIES];
    float trilinear[3 * QUERIES], sh[3 * QUERIES];
    float many_nearest[3 * QUERIES], many_bilinear[3 * QUERIES];
    irrvol_volume_info info;
    float *values;            /* irrvol_sample_values of every sample: irradiance, radiance */
    uint32_t *bin_of_dir;     /* irrvol_direction_bin of every query direction */
    float *bin_dirs;          /* irrvol_bin_direction of every bin */
    void *saved;              /* irrvol_save_to_memory */
    uint32_t *gpu_index;      /* irrvol_gpu_export */
    float *gpu_data;
    irrvol_gpu_layout gpu;
    size_t saved_size;
    float *ratio;             /* irrvol_visibility_ratio of the scene mesh */
    irrvol_result results;    /* OR of every result code: IRRVOL_OK when all were */
} answers;

typedef struct shared {
    const irrvol *vol;
    const query_set *q;
    const irrvol_visibility_desc *vis;
    pthread_barrier_t start;
    double racy_sum;          /* --racy only: added to without synchronisation */
    int racy;
} shared;

static int answers_alloc(answers *a, const irrvol *vol, const irrvol_volume_info *info, uint32_t vertices)
{
    memset(a, 0, sizeof *a);
    a->values = (float *)malloc((size_t)info->sample_count * info->bins * 6 * sizeof(float));
    a->bin_of_dir = (uint32_t *)malloc(QUERIES * sizeof(uint32_t));
    a->bin_dirs = (float *)malloc((size_t)info->bins * 3 * sizeof(float));
    a->ratio = (float *)malloc((size_t)vertices * sizeof(float));
    if (irrvol_gpu_export(vol, 2, &a->gpu, NULL, 0, NULL, 0) != IRRVOL_OK) return 0;
    a->gpu_index = (uint32_t *)calloc(a->gpu.index_count, sizeof(uint32_t));
    a->gpu_data = (float *)calloc(a->gpu.data_count, sizeof(float));
    return a->values && a->bin_of_dir && a->bin_dirs && a->ratio && a->gpu_index && a->gpu_data;
}

static void answers_free(answers *a)
{
    free(a->values);
    free(a->bin_of_dir);
    free(a->bin_dirs);
    free(a->ratio);
    free(a->gpu_index);
    free(a->gpu_data);
    irrvol_free_memory(NULL, a->saved);
    memset(a, 0, sizeof *a);
}

/* Every read-only call, once; a thread starts its single queries at its own
   offset, so that at any moment the threads read different parts of the
   volume as well as the same ones. */
static void compute_answers(const shared *sh, answers *a, uint32_t offset)
{
    const irrvol *v = sh->vol;
    const query_set *q = sh->q;
    uint32_t n, i, b;
    for (n = 0; n < QUERIES; n++) {
        uint32_t j = (n + offset) % QUERIES;
        const float *p = q->pos + 3 * j, *d = q->dir + 3 * j;
        irrvol_query_filter(v, IRRVOL_FILTER_NEAREST, IRRVOL_WEIGHTING_DEFAULT, p, d, a->nearest + 3 * j);
        irrvol_query_filter(v, IRRVOL_FILTER_BILINEAR, IRRVOL_WEIGHTING_DEFAULT, p, d, a->bilinear + 3 * j);
        irrvol_query(v, p, d, a->plain + 3 * j);
        irrvol_query_glossy(v, p, q->normal + 3 * j, q->eye + 3 * j, a->glossy + 3 * j);
        irrvol_query_filter(v, IRRVOL_FILTER_DEFAULT, IRRVOL_WEIGHTING_TRILINEAR, p, d, a->trilinear + 3 * j);
        irrvol_query_sh(v, 2, IRRVOL_WEIGHTING_DEFAULT, p, d, a->sh + 3 * j);
        a->bin_of_dir[j] = irrvol_direction_bin(v, d);
    }
    irrvol_query_many(v, IRRVOL_FILTER_NEAREST, IRRVOL_WEIGHTING_DEFAULT, QUERIES, q->pos, 0, q->dir, 0, a->many_nearest);
    irrvol_query_many(v, IRRVOL_FILTER_BILINEAR, IRRVOL_WEIGHTING_DEFAULT, QUERIES, q->pos, 0, q->dir, 0, a->many_bilinear);
    a->results |= irrvol_info(v, &a->info);
    for (i = 0; i < a->info.sample_count; i++) {
        float *at = a->values + (size_t)i * a->info.bins * 6;
        irrvol_sample_info si;
        a->results |= irrvol_sample(v, i, &si);
        a->results |= irrvol_sample_values(v, i, at, at + (size_t)a->info.bins * 3);
    }
    for (b = 0; b < a->info.bins; b++) irrvol_bin_direction(v, b, a->bin_dirs + 3 * b);
    irrvol_free_memory(NULL, a->saved);
    a->results |= irrvol_save_to_memory(v, NULL, &a->saved, &a->saved_size);
    a->results |= irrvol_gpu_export(v, 2, &a->gpu, a->gpu_index, a->gpu.index_count, a->gpu_data, a->gpu.data_count);
    a->results |= irrvol_visibility_ratio(sh->vis, a->ratio);
}

static int same_floats(const float *x, const float *y, size_t n) { return memcmp(x, y, n * sizeof(float)) == 0; }

/* Bit-identical answers (the byte images of the saves included). */
static int answers_equal(const answers *x, const answers *y, uint32_t vertices)
{
    size_t n = 3 * (size_t)QUERIES;
    return x->results == IRRVOL_OK && y->results == IRRVOL_OK &&
           same_floats(x->nearest, y->nearest, n) && same_floats(x->bilinear, y->bilinear, n) &&
           same_floats(x->plain, y->plain, n) && same_floats(x->glossy, y->glossy, n) &&
           same_floats(x->trilinear, y->trilinear, n) && same_floats(x->sh, y->sh, n) &&
           memcmp(x->gpu_index, y->gpu_index, x->gpu.index_count * sizeof(uint32_t)) == 0 &&
           same_floats(x->gpu_data, y->gpu_data, x->gpu.data_count) &&
           same_floats(x->many_nearest, y->many_nearest, n) && same_floats(x->many_bilinear, y->many_bilinear, n) &&
           memcmp(&x->info, &y->info, sizeof x->info) == 0 &&
           same_floats(x->values, y->values, (size_t)x->info.sample_count * x->info.bins * 6) &&
           memcmp(x->bin_of_dir, y->bin_of_dir, QUERIES * sizeof(uint32_t)) == 0 &&
           same_floats(x->bin_dirs, y->bin_dirs, (size_t)x->info.bins * 3) &&
           x->saved_size == y->saved_size && memcmp(x->saved, y->saved, x->saved_size) == 0 &&
           same_floats(x->ratio, y->ratio, vertices);
}

typedef struct worker_arg {
    shared *sh;
    const answers *serial;
    answers mine;
    uint32_t index, vertices;
    int mismatched_rounds;
} worker_arg;

static void *worker(void *arg)
{
    worker_arg *w = (worker_arg *)arg;
    int round;
    uint32_t i;
    pthread_barrier_wait(&w->sh->start);
    for (round = 0; round < ROUNDS; round++) {
        compute_answers(w->sh, &w->mine, (w->index * QUERIES) / THREADS + (uint32_t)round * 37u);
        if (!answers_equal(&w->mine, w->serial, w->vertices)) w->mismatched_rounds++;
        if (w->sh->racy)   /* the deliberate race: a plain read-modify-write from every thread */
            for (i = 0; i < 3 * QUERIES; i++) w->sh->racy_sum += w->mine.nearest[i];
    }
    return NULL;
}

/* Runs THREADS workers on the shared volume; returns the rounds whose
   answers differed from the serial ones, or -1 when setting up failed. */
static int run_workers(shared *sh, const answers *serial, const irrvol_volume_info *info, uint32_t vertices)
{
    pthread_t t[THREADS];
    worker_arg w[THREADS];
    int i, started = 0, mismatched = 0, ok = 1;
    for (i = 0; i < THREADS; i++) {
        w[i].sh = sh;
        w[i].serial = serial;
        w[i].index = (uint32_t)i;
        w[i].vertices = vertices;
        w[i].mismatched_rounds = 0;
        ok &= answers_alloc(&w[i].mine, sh->vol, info, vertices);
    }
    if (ok && pthread_barrier_init(&sh->start, NULL, THREADS) == 0) {
        for (started = 0; started < THREADS; started++)
            if (pthread_create(&t[started], NULL, worker, &w[started]) != 0) break;
        if (started < THREADS) {   /* the barrier would never open: no threads, no test */
            fprintf(stderr, "pthread_create failed\n");
            exit(1);
        }
        for (i = 0; i < THREADS; i++) {
            pthread_join(t[i], NULL);
            mismatched += w[i].mismatched_rounds;
        }
        pthread_barrier_destroy(&sh->start);
    }
    for (i = 0; i < THREADS; i++) answers_free(&w[i].mine);
    return ok && started == THREADS ? mismatched : -1;
}

static void visibility_desc(const scene *s, irrvol_visibility_desc *vd)
{
    memset(vd, 0, sizeof *vd);
    vd->positions = s->mesh.pos;
    vd->vertex_count = s->mesh.nv;
    vd->indices = s->mesh.idx;
    vd->triangle_count = s->mesh.nt;
    vd->rays = 64;   /* the default; 32 vertices x 64 rays: cheap, still a BVH build and traversal per call */
    vd->seed = 5;
}

/* Serial answers first, then the same calls from THREADS threads at once. */
static void test_concurrent_reads(void)
{
    static query_set q;
    scene s;
    irrvol_desc d;
    irrvol_visibility_desc vd;
    irrvol *vol;
    irrvol_volume_info info;
    answers serial;
    shared sh;
    double t0;
    int mismatched;
    make_scene(&s, &d);
    make_queries(&q);
    visibility_desc(&s, &vd);
    if (!CHECK_EQ_INT(irrvol_build(&d, &vol), IRRVOL_OK)) return;
    irrvol_info(vol, &info);
    memset(&sh, 0, sizeof sh);
    sh.vol = vol;
    sh.q = &q;
    sh.vis = &vd;
    if (CHECK(answers_alloc(&serial, vol, &info, s.mesh.nv))) {
        compute_answers(&sh, &serial, 0);
        CHECK_EQ_INT(serial.results, IRRVOL_OK);
        t0 = seconds();
        mismatched = run_workers(&sh, &serial, &info, s.mesh.nv);
        test_note("%d threads x %d rounds x (%u single queries of 4 kinds + 2 batches + %u samples read + save of "
                  "%zu bytes + visibility ratio): %.2f s, %d rounds differed from the serial answers",
                  THREADS, ROUNDS, QUERIES, info.sample_count, serial.saved_size, seconds() - t0, mismatched);
        CHECK_EQ_INT(mismatched, 0);
    }
    answers_free(&serial);
    irrvol_destroy(vol);
}

/* ---- the build through a thread pool ----------------------------------- */
/* Forwards to ex_pool_parallel_for and counts, per pool thread, the jobs it
   ran. The counters are relaxed atomics: they order nothing, so they hide no
   race of the library's jobs from ThreadSanitizer (a mutex here would). */
typedef struct counted_pool {
    ex_pool *pool;
    uint32_t jobs[EX_POOL_MAX_THREADS + 1];   /* [0]: the calling thread, [1 + i]: worker i */
    irrvol_job_fn job;
    void *ctx;
} counted_pool;

static void counted_job(void *ctx, uint32_t index)
{
    counted_pool *c = (counted_pool *)ctx;
    pthread_t self = pthread_self();
    int i, slot = 0;
    for (i = 0; i < c->pool->thread_count; i++)
        if (pthread_equal(self, c->pool->threads[i])) slot = 1 + i;
    __atomic_fetch_add(&c->jobs[slot], 1u, __ATOMIC_RELAXED);
    c->job(c->ctx, index);
}

static void counted_parallel_for(void *user, irrvol_job_fn job, void *ctx, uint32_t count)
{
    counted_pool *c = (counted_pool *)user;
    c->job = job;   /* builds call parallel_for from one thread, one batch at a time */
    c->ctx = ctx;
    ex_pool_parallel_for(c->pool, counted_job, c, count);
}

static void test_pool_build_matches_serial(void)
{
    scene s;
    irrvol_desc d;
    irrvol *serial, *pooled;
    void *a = NULL, *b = NULL;
    size_t na = 0, nb = 0;
    counted_pool cp;
    uint32_t total = 0;
    int i, busy_threads = 0;
    double t0;
    make_scene(&s, &d);
    if (!CHECK_EQ_INT(irrvol_build(&d, &serial), IRRVOL_OK)) return;
    memset(&cp, 0, sizeof cp);
    cp.pool = ex_pool_create(THREADS);
    if (!CHECK(cp.pool != NULL)) { irrvol_destroy(serial); return; }
    d.parallel_for = counted_parallel_for;
    d.parallel_user = &cp;
    t0 = seconds();
    if (CHECK_EQ_INT(irrvol_build(&d, &pooled), IRRVOL_OK)) {
        double t = seconds() - t0;
        for (i = 0; i <= cp.pool->thread_count; i++) {
            total += cp.jobs[i];
            busy_threads += cp.jobs[i] > 0;
        }
        test_note("pooled build: %.2f s, %u jobs on %d of %d threads", t, total, busy_threads,
                  ex_pool_threads(cp.pool));
        /* the build runs over a hundred jobs of milliseconds each under
           ThreadSanitizer, ample time for a worker to wake: one thread alone
           would mean the pool never ran anything concurrently */
        CHECK(busy_threads >= 2);
        CHECK_EQ_INT(irrvol_save_to_memory(serial, NULL, &a, &na), IRRVOL_OK);
        CHECK_EQ_INT(irrvol_save_to_memory(pooled, NULL, &b, &nb), IRRVOL_OK);
        CHECK(na > 0 && na == nb && memcmp(a, b, na) == 0);   /* bit-identical for any thread count */
        irrvol_free_memory(NULL, a);
        irrvol_free_memory(NULL, b);
        irrvol_destroy(pooled);
    }
    ex_pool_destroy(cp.pool);
    irrvol_destroy(serial);
}

/* ---- ThreadSanitizer is on and catches a race here ---------------------- */
/* The --racy run: the concurrent reads of test_concurrent_reads plus the
   unsynchronised sum. The threads meet only at the start barrier, so their
   writes to the sum are unordered whatever the timing: a certain report. */
static int racy_main(void)
{
    static query_set q;
    scene s;
    irrvol_desc d;
    irrvol_visibility_desc vd;
    irrvol *vol;
    irrvol_volume_info info;
    answers serial;
    shared sh;
    make_scene(&s, &d);
    d.resolution = 3;   /* the race needs no detail: the smallest quick volume */
    d.supersamples = 1;
    make_queries(&q);
    visibility_desc(&s, &vd);
    if (irrvol_build(&d, &vol) != IRRVOL_OK) return 2;
    irrvol_info(vol, &info);
    memset(&sh, 0, sizeof sh);
    sh.vol = vol;
    sh.q = &q;
    sh.vis = &vd;
    sh.racy = 1;
    if (!answers_alloc(&serial, vol, &info, s.mesh.nv)) return 2;
    compute_answers(&sh, &serial, 0);
    run_workers(&sh, &serial, &info, s.mesh.nv);
    printf("racy sum %g\n", sh.racy_sum);
    answers_free(&serial);
    irrvol_destroy(vol);
    return 0;
}

static void test_racy_run_is_reported(void)
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
        args[0] = (char *)"tsan_irrvol";
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
    CHECK(strstr(out, "SUMMARY: ThreadSanitizer: data race") != NULL && strstr(out, " in worker") != NULL);   /* at the racy sum */
    CHECK(WIFEXITED(status) && WEXITSTATUS(status) != 0 && WEXITSTATUS(status) != 127);
}

int main(int argc, char **argv)
{
    if (argc > 1 && strcmp(argv[1], "--racy") == 0) return racy_main();
    TEST_INIT(argc, argv);
    RUN(test_racy_run_is_reported);
    RUN(test_concurrent_reads);
    RUN(test_pool_build_matches_serial);
    return test_finish();
}
