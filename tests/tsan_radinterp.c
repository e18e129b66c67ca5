/* Concurrency test of radinterp.h under ThreadSanitizer.
   1. Three threads query one shared solution at once:
      radinterp_irradiance_at_point and radinterp_radiosity_at_point at points
      all over the room (full and partial visibility, backprojection through
      the block), radinterp_patch_radiosity, radinterp_get_leaf and
      radinterp_solution_info. Every answer must equal, bit for bit, the same
      call made serially beforehand.
   2. radinterp_solve, radinterp_build_mesh and radinterp_shade (and
      radinterp_shade_gouraud) through desc.parallel_for driven by a real
      thread pool (examples/common/pool.h) give the results of the serial
      calls, bit for bit, and their jobs ran on more than one thread.
   ThreadSanitizer makes the process exit non-zero (66) after any report, so
   a race in the library fails the run even when every comparison passes.
   3. To show that this holds, the program runs itself again with --racy:
      the concurrent queries, but every thread also adds its results into one
      unsynchronised sum, a caller's race. That run must print a data race
      report and exit non-zero. */
#if !defined(_POSIX_C_SOURCE) || _POSIX_C_SOURCE < 200809L
#  undef _POSIX_C_SOURCE
#  define _POSIX_C_SOURCE 200809L   /* fork, execv, pipe, pthread_barrier */
#endif
#define RADINTERP_IMPLEMENTATION
#include "radinterp.h"
#include <time.h>
#include "tests/test.h"
#include "examples/common/pool.h"
#include "tests/tsan.h"

/* 3 threads on the 2 cores of the test machine: more threads than cores,
   so the scheduler interleaves them mid-call as well as running two at once. */
#define THREADS 3
/* 240 points, each queried three ways, 3 rounds per thread: a few seconds of
   the three threads inside the point query under ThreadSanitizer, so that
   the queries of one thread overlap those of another many times over, in
   every phase of the query (link walk, shadow unions, backprojection); more
   only costs time. */
#define POINTS 240u
#define ROUNDS 3
/* Pixels shaded per call: 16 jobs of 16384 and a partial 17th, a few
   milliseconds each under ThreadSanitizer, ample time for the workers to
   wake and take some. */
#define PIXELS (16u * 16384u + 1000u)

static double seconds(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

/* ---- the scene: a room (floor and four walls, z up) with a block on the
   floor under a light on the open top, so that the floor sees the light
   partly blocked: partial visibility, EV and VE discontinuities, a contact -- */
typedef struct scene {
    float pos[3 * 64];
    uint32_t patch[4 * 16], mat[16];
    uint32_t nv, np;
    radinterp_material m[2];
} scene;

static uint32_t add_vertex(scene *s, const float *p)
{
    memcpy(s->pos + 3 * s->nv, p, 12);
    return s->nv++;
}

static void add_quad(scene *s, const float *a, const float *b, const float *c, const float *d, uint32_t mat)
{
    uint32_t i = s->np++;
    s->patch[4 * i] = add_vertex(s, a);
    s->patch[4 * i + 1] = add_vertex(s, b);
    s->patch[4 * i + 2] = add_vertex(s, c);
    s->patch[4 * i + 3] = add_vertex(s, d);
    s->mat[i] = mat;
}

/* Corner i of the box [lo, hi]: bit 0 = x, bit 1 = y, bit 2 = z at hi. */
static void corner(const float *lo, const float *hi, int i, float *c)
{
    c[0] = i & 1 ? hi[0] : lo[0];
    c[1] = i & 2 ? hi[1] : lo[1];
    c[2] = i & 4 ? hi[2] : lo[2];
}

/* A box's faces facing in (room: floor and walls) or out (block: top and sides). */
static void add_box(scene *s, const float *lo, const float *hi, int inward, uint32_t mat)
{
    static const int in[5][4] = { { 0, 1, 3, 2 }, { 0, 4, 5, 1 }, { 2, 3, 7, 6 }, { 0, 2, 6, 4 }, { 1, 5, 7, 3 } };
    static const int out[5][4] = { { 4, 5, 7, 6 }, { 0, 1, 5, 4 }, { 2, 6, 7, 3 }, { 0, 4, 6, 2 }, { 1, 3, 7, 5 } };
    float c[4][3];
    int f, k;
    for (f = 0; f < 5; f++) {
        for (k = 0; k < 4; k++) corner(lo, hi, inward ? in[f][k] : out[f][k], c[k]);
        add_quad(s, c[0], c[1], c[2], c[3], mat);
    }
}

static void make_scene(scene *s, radinterp_desc *d)
{
    static const float room_lo[3] = { 0, 0, 0 }, room_hi[3] = { 2, 1.5f, 1.2f };
    static const float block_lo[3] = { 0.6f, 0.4f, 0 }, block_hi[3] = { 1.1f, 0.9f, 0.45f };
    static const float light[4][3] = { { 0.8f, 0.5f, 1.2f }, { 0.8f, 1.0f, 1.2f }, { 1.4f, 1.0f, 1.2f },
                                       { 1.4f, 0.5f, 1.2f } };   /* facing down */
    int c;
    memset(s, 0, sizeof *s);
    for (c = 0; c < 3; c++) {
        s->m[0].reflectance[c] = 0.6f;
        s->m[1].emission[c] = 30.0f;
    }
    add_box(s, room_lo, room_hi, 1, 0);
    add_box(s, block_lo, block_hi, 0, 0);
    add_quad(s, light[0], light[1], light[2], light[3], 1);
    memset(d, 0, sizeof *d);
    d->positions = s->pos;
    d->vertex_count = s->nv;
    d->patches = s->patch;
    d->patch_count = s->np;
    d->patch_materials = s->mat;
    d->materials = s->m;
    d->material_count = 2;
    d->eps = 0.1f;   /* about 3,300 leaves with links through the block: a solve of about a second under ThreadSanitizer */
}

/* ---- point queries -------------------------------------------------------- */
/* Points on POINTS leaves spread over the solution: the leaf's centre, or a
   point near one of its corners approached from the centre (the corners of
   floor leaves lie on penumbra boundaries and at the block's foot). */
typedef struct query_set {
    uint32_t patch[POINTS];
    float p[POINTS][3], toward[POINTS][3];
} query_set;

static void make_queries(const radinterp_solution *s, query_set *q)
{
    uint32_t leaves = radinterp_leaf_count(s), i, k, v;
    for (i = 0; i < POINTS; i++) {
        radinterp_leaf leaf;
        float centre[3] = { 0, 0, 0 };
        radinterp_get_leaf(s, (uint32_t)((uint64_t)i * leaves / POINTS), &leaf);
        for (v = 0; v < leaf.vertex_count; v++)
            for (k = 0; k < 3; k++) centre[k] += leaf.vertices[v][k] / (float)leaf.vertex_count;
        q->patch[i] = leaf.patch;
        memcpy(q->toward[i], centre, sizeof centre);
        for (k = 0; k < 3; k++)
            q->p[i][k] = (i & 1) ? 0.999f * leaf.vertices[i / 2 % leaf.vertex_count][k] + 0.001f * centre[k]
                                 : centre[k];
    }
}

/* Every answer a thread computes from the shared solution. */
typedef struct answers {
    float irradiance[POINTS][3], radiosity[POINTS][3], patch_radiosity[POINTS][3];
    radinterp_leaf leaf[POINTS];
    radinterp_info info;
    radinterp_result results;   /* OR of every result code: RADINTERP_OK when all were */
} answers;

typedef struct shared {
    const radinterp_solution *s;
    const query_set *q;
    pthread_barrier_t start;
    double racy_sum;            /* --racy only: added to without synchronisation */
    int racy;
} shared;

/* Every read-only call, once; a thread starts at its own offset, so that at
   any moment the threads query different points as well as the same ones. */
static void compute_answers(const shared *sh, answers *a, uint32_t offset)
{
    uint32_t n, leaves = radinterp_leaf_count(sh->s);
    for (n = 0; n < POINTS; n++) {
        uint32_t i = (n + offset) % POINTS;
        const query_set *q = sh->q;
        a->results |= radinterp_irradiance_at_point(sh->s, q->patch[i], q->p[i], q->toward[i], a->irradiance[i]);
        a->results |= radinterp_radiosity_at_point(sh->s, q->patch[i], q->p[i], NULL, a->radiosity[i]);
        a->results |= radinterp_patch_radiosity(sh->s, q->patch[i], a->patch_radiosity[i]);
        a->results |= radinterp_get_leaf(sh->s, (uint32_t)((uint64_t)i * leaves / POINTS), &a->leaf[i]);
    }
    radinterp_solution_info(sh->s, &a->info);
}

static int answers_equal(const answers *x, const answers *y)
{
    return x->results == RADINTERP_OK && y->results == RADINTERP_OK &&
           memcmp(x->irradiance, y->irradiance, sizeof x->irradiance) == 0 &&
           memcmp(x->radiosity, y->radiosity, sizeof x->radiosity) == 0 &&
           memcmp(x->patch_radiosity, y->patch_radiosity, sizeof x->patch_radiosity) == 0 &&
           memcmp(x->leaf, y->leaf, sizeof x->leaf) == 0 && memcmp(&x->info, &y->info, sizeof x->info) == 0;
}

typedef struct worker_arg {
    shared *sh;
    const answers *serial;
    answers mine;
    uint32_t index;
    int mismatched_rounds;
} worker_arg;

static void *worker(void *arg)
{
    worker_arg *w = (worker_arg *)arg;
    int round;
    uint32_t i;
    pthread_barrier_wait(&w->sh->start);
    for (round = 0; round < ROUNDS; round++) {
        memset(&w->mine, 0, sizeof w->mine);
        compute_answers(w->sh, &w->mine, (w->index * POINTS) / THREADS + (uint32_t)round * 37u);
        if (!answers_equal(&w->mine, w->serial)) w->mismatched_rounds++;
        if (w->sh->racy)   /* the deliberate race: a plain read-modify-write from every thread */
            for (i = 0; i < POINTS; i++) w->sh->racy_sum += w->mine.irradiance[i][0];
    }
    return NULL;
}

/* Runs THREADS workers on the shared solution; returns the rounds whose
   answers differed from the serial ones. */
static int run_workers(shared *sh, const answers *serial)
{
    pthread_t t[THREADS];
    static worker_arg w[THREADS];
    int i, started, mismatched = 0;
    if (pthread_barrier_init(&sh->start, NULL, THREADS) != 0) {
        fprintf(stderr, "pthread_barrier_init failed\n");
        exit(1);
    }
    for (i = 0; i < THREADS; i++) {
        w[i].sh = sh;
        w[i].serial = serial;
        w[i].index = (uint32_t)i;
        w[i].mismatched_rounds = 0;
    }
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
    return mismatched;
}

static radinterp_solution *serial_solution;   /* solved once, shared by the tests */
static scene the_scene;

static void query_setup(shared *sh, query_set *q, answers *serial)
{
    make_queries(serial_solution, q);
    memset(sh, 0, sizeof *sh);
    sh->s = serial_solution;
    sh->q = q;
    memset(serial, 0, sizeof *serial);
    compute_answers(sh, serial, 0);
}

static void test_concurrent_point_queries(void)
{
    static query_set q;
    static answers serial;
    shared sh;
    double t0;
    int mismatched;
    if (!CHECK(serial_solution != NULL)) return;
    query_setup(&sh, &q, &serial);
    CHECK_EQ_INT(serial.results, RADINTERP_OK);
    t0 = seconds();
    mismatched = run_workers(&sh, &serial);
    test_note("%d threads x %d rounds x %u points (irradiance, radiosity, patch radiosity, leaf) on %u leaves: "
              "%.2f s, %d rounds differed from the serial answers",
              THREADS, ROUNDS, POINTS, radinterp_leaf_count(serial_solution), seconds() - t0, mismatched);
    CHECK_EQ_INT(mismatched, 0);
}

/* ---- solve, mesh and shade through the pool ------------------------------ */
static int same_solution(const radinterp_solution *a, const radinterp_solution *b)
{
    radinterp_info ia, ib;
    uint32_t i, n = radinterp_leaf_count(a);
    radinterp_solution_info(a, &ia);
    radinterp_solution_info(b, &ib);
    if (memcmp(&ia, &ib, sizeof ia) != 0 || radinterp_leaf_count(b) != n) return 0;
    for (i = 0; i < n; i++) {
        radinterp_leaf la, lb;
        if (radinterp_get_leaf(a, i, &la) != RADINTERP_OK || radinterp_get_leaf(b, i, &lb) != RADINTERP_OK ||
            memcmp(&la, &lb, sizeof la) != 0)
            return 0;
    }
    return 1;
}

static void test_pool_solve_matches_serial(tsan_pool *tp)
{
    radinterp_desc d;
    radinterp_solution *pooled = NULL;
    uint32_t jobs;
    int busy;
    double t0;
    if (!CHECK(serial_solution != NULL)) return;
    make_scene(&the_scene, &d);
    d.parallel_for = tsan_parallel_for;
    d.parallel_user = tp;
    t0 = seconds();
    if (!CHECK_EQ_INT(radinterp_solve(&d, &pooled), RADINTERP_OK)) return;
    busy = tsan_busy_threads(tp, &jobs);
    test_note("pooled solve: %.2f s, %u jobs on %d of %d threads", seconds() - t0, jobs, busy, ex_pool_threads(tp->pool));
    /* the solve runs hundreds of jobs under ThreadSanitizer, ample time for a
       worker to wake: one thread alone would mean nothing ran concurrently */
    CHECK(busy >= 2);
    CHECK(same_solution(serial_solution, pooled));   /* bit-identical for any thread count */
    radinterp_solution_destroy(pooled);
}

static int saved_equal(const radinterp_mesh *a, const radinterp_mesh *b)
{
    void *x = NULL, *y = NULL;
    size_t nx = 0, ny = 0;
    int same = radinterp_mesh_save_to_memory(a, NULL, &x, &nx) == RADINTERP_OK &&
               radinterp_mesh_save_to_memory(b, NULL, &y, &ny) == RADINTERP_OK && nx == ny && memcmp(x, y, nx) == 0;
    radinterp_free_memory(NULL, x);
    radinterp_free_memory(NULL, y);
    return same;
}

/* Pixels over every triangle of the mesh, at barycentric points that cover
   the triangle, with a few ids of no triangle among them. */
static void make_pixels(uint32_t triangles, uint32_t *ids, float *st)
{
    uint32_t i;
    for (i = 0; i < PIXELS; i++) {
        float s = (float)(i % 7) / 7.0f, t = (float)(i % 5) / 5.0f;
        ids[i] = i % 97 == 0 ? RADINTERP_NO_TRIANGLE : (uint32_t)((i * 2654435761u) % triangles);
        if (s + t > 1.0f) { s = 1.0f - s; t = 1.0f - t; }
        st[2 * i] = s;
        st[2 * i + 1] = t;
    }
}

/* radinterp_shade and radinterp_shade_gouraud of one mesh through its
   parallel_for (set_parallel_for or the build's): rgb holds 6 per pixel. */
static void shade_both(const radinterp_mesh *m, const uint32_t *ids, const float *st, float *rgb, radinterp_result *r)
{
    memset(rgb, 0, 6 * sizeof(float) * PIXELS);
    *r = radinterp_shade(m, ids, st, PIXELS, rgb);
    *r = (radinterp_result)(*r | radinterp_shade_gouraud(m, ids, st, PIXELS, rgb + 3 * (size_t)PIXELS));
}

static void test_pool_mesh_and_shade_match_serial(tsan_pool *tp)
{
    radinterp_mesh_desc md;
    radinterp_mesh *serial = NULL, *pooled = NULL;
    radinterp_mesh_data data;
    radinterp_result rs, rp;
    uint32_t *ids = (uint32_t *)malloc(PIXELS * sizeof(uint32_t)), jobs;
    float *st = (float *)malloc(2 * sizeof(float) * PIXELS);
    float *a = (float *)malloc(6 * sizeof(float) * PIXELS), *b = (float *)malloc(6 * sizeof(float) * PIXELS);
    int busy;
    double t0;
    if (!CHECK(serial_solution && ids && st && a && b)) goto done;
    memset(&md, 0, sizeof md);
    md.min_leaf_area = 0.05f;   /* the unit tests' room mesh: a few thousand triangles */
    if (!CHECK_EQ_INT(radinterp_build_mesh(serial_solution, &md, &serial), RADINTERP_OK)) goto done;
    md.parallel_for = tsan_parallel_for;
    md.parallel_user = tp;
    t0 = seconds();
    if (!CHECK_EQ_INT(radinterp_build_mesh(serial_solution, &md, &pooled), RADINTERP_OK)) goto done;
    busy = tsan_busy_threads(tp, &jobs);
    test_note("pooled mesh: %.2f s, %u jobs on %d of %d threads", seconds() - t0, jobs, busy,
              ex_pool_threads(tp->pool));
    CHECK(busy >= 2);
    CHECK(saved_equal(serial, pooled));   /* bit-identical for any thread count */

    /* shading: the serial mesh without a job system, the pooled one through
       the pool (its build's, set again as a caller of a loaded mesh would) */
    radinterp_mesh_get_data(serial, &data);
    if (!CHECK(data.triangle_count > 0)) goto done;
    make_pixels(data.triangle_count, ids, st);
    shade_both(serial, ids, st, a, &rs);
    radinterp_mesh_set_parallel_for(pooled, tsan_parallel_for, tp);
    t0 = seconds();
    shade_both(pooled, ids, st, b, &rp);
    busy = tsan_busy_threads(tp, &jobs);
    test_note("pooled shade of %u pixels (B and Gouraud) over %u triangles: %.3f s, %u jobs on %d threads",
              PIXELS, data.triangle_count, seconds() - t0, jobs, busy);
    CHECK_EQ_INT(rs, RADINTERP_OK);
    CHECK_EQ_INT(rp, RADINTERP_OK);
    CHECK(memcmp(a, b, 6 * sizeof(float) * PIXELS) == 0);
    CHECK(busy >= 2);
done:
    radinterp_mesh_destroy(serial);
    radinterp_mesh_destroy(pooled);
    free(ids);
    free(st);
    free(a);
    free(b);
}

static tsan_pool the_pool;
static void test_pool_solve(void) { test_pool_solve_matches_serial(&the_pool); }
static void test_pool_mesh_and_shade(void) { test_pool_mesh_and_shade_match_serial(&the_pool); }

/* ---- ThreadSanitizer is on and catches a race here ---------------------- */
/* The --racy run: the concurrent queries plus the unsynchronised sum. The
   threads meet only at the start barrier, so their writes to the sum are
   unordered whatever the timing: a certain report. */
static int racy_main(void)
{
    static query_set q;
    static answers serial;
    shared sh;
    if (!serial_solution) return 2;
    query_setup(&sh, &q, &serial);
    sh.racy = 1;
    run_workers(&sh, &serial);
    printf("racy sum %g\n", sh.racy_sum);
    return 0;
}

static void test_racy_run_is_reported(void) { tsan_check_racy_run("tsan_radinterp"); }

int main(int argc, char **argv)
{
    radinterp_desc d;
    int racy = argc > 1 && strcmp(argv[1], "--racy") == 0, status;
    make_scene(&the_scene, &d);
    if (radinterp_solve(&d, &serial_solution) != RADINTERP_OK) serial_solution = NULL;
    if (racy) {
        status = racy_main();
        radinterp_solution_destroy(serial_solution);
        return status;
    }
    TEST_INIT(argc, argv);
    the_pool.pool = ex_pool_create(THREADS);
    if (!the_pool.pool) {
        fprintf(stderr, "ex_pool_create failed\n");
        return 1;
    }
    RUN(test_racy_run_is_reported);
    RUN(test_concurrent_point_queries);
    RUN(test_pool_solve);
    RUN(test_pool_mesh_and_shade);
    ex_pool_destroy(the_pool.pool);
    radinterp_solution_destroy(serial_solution);
    return test_finish();
}
