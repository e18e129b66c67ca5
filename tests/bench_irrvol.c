/* irrvol.h benchmark: Greger's office settings (7^3 first level, 3^3 second
   level, k = 17, 578 bins) on the office with a static bunny. Build time and
   rays/s on 1 and 2 threads, memory, queries/s, next to the thesis's figures
   (5.1.1: 2287 samples, 24 minutes, 18 MB, 27,600 queries/s on a 100 MHz
   PA-RISC 7100LC). Medians of several runs. The machine is shared with other
   work: single-thread figures are measured in the thread's CPU time, which
   time slicing does not inflate; two-thread builds in wall-clock time. */
#define IRRVOL_IMPLEMENTATION
#include "irrvol.h"
#include "tests/ref_irrvol_scene.h"
#include "examples/common/pool.h"
#include <time.h>

static double now(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

static double cpu_now(void)   /* this thread's CPU time */
{
    struct timespec t;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

static double median(double *x, int n)
{
    int i, j;
    for (i = 1; i < n; i++)
        for (j = i; j > 0 && x[j - 1] > x[j]; j--) { double t = x[j]; x[j] = x[j - 1]; x[j - 1] = t; }
    return n % 2 ? x[n / 2] : 0.5 * (x[n / 2 - 1] + x[n / 2]);
}

#define RUNS 5

/* Median build time (CPU time without a pool, else wall clock); *vol keeps
   the last volume. */
static double time_build(irrvol_desc *d, ex_pool *pool, irrvol **vol)
{
    double t[RUNS];
    double (*clock_fn)(void) = pool ? now : cpu_now;
    int r;
    d->parallel_for = pool ? ex_pool_parallel_for : NULL;
    d->parallel_user = pool;
    *vol = NULL;
    for (r = 0; r < RUNS; r++) {
        double t0;
        irrvol_destroy(*vol);
        t0 = clock_fn();
        if (irrvol_build(d, vol) != IRRVOL_OK) { fprintf(stderr, "build failed\n"); exit(1); }
        t[r] = clock_fn() - t0;
    }
    return median(t, RUNS);
}

static float *queries;   /* position xyz, direction xyz */
#define QUERIES 4000000u

static double time_batched(const irrvol *v, irrvol_filter filter, const float *q, uint32_t n, float *out)
{
    double t[RUNS];
    int r;
    for (r = 0; r < RUNS; r++) {
        double t0 = cpu_now();
        irrvol_query_many(v, filter, n, q, 6 * sizeof(float), q + 3, 6 * sizeof(float), out);
        t[r] = cpu_now() - t0;
    }
    return (double)n / median(t, RUNS);
}

static double time_queries(const irrvol *v, irrvol_filter filter, const float *q, uint32_t n, uint32_t repeat,
                           float *checksum)
{
    double t[RUNS];
    int r;
    float sum = 0.0f;
    for (r = 0; r < RUNS; r++) {
        double t0 = cpu_now();
        uint32_t i, k;
        for (k = 0; k < repeat; k++)
            for (i = 0; i < n; i++) {
                float h[3];
                irrvol_query_filter(v, filter, q + 6 * (size_t)i, q + 6 * (size_t)i + 3, h);
                sum += h[1];
            }
        t[r] = cpu_now() - t0;
    }
    *checksum = sum;
    return (double)n * repeat / median(t, RUNS);
}

int main(void)
{
    office_scene s;
    irrvol_desc d;
    irrvol *vol;
    irrvol_volume_info info;
    ex_pool *two = ex_pool_create(2);
    uint32_t i, m, bunny_n;
    uint64_t state = 7;
    double t1, t2, nearest, bilinear, coherent, per_sample, many_nearest, many_bilinear;
    float *many_out;
    float checksum, *bunny_q;
    uint32_t flags[64];
    memset(&info, 0, sizeof info);
    if (office_scene_load(&s, "examples/data", 2.0f, 1.5f) != 0 || s.material_count > 64) return 1;
    office_scene_desc(&s, &d);
    printf("office + bunny: %u triangles; Greger's settings: 7^3 first level, 3^3 second level, k = 17 (578 bins)\n",
           s.tri_count);
    printf("%-44s %14s %14s %14s %10s\n", "", "samples", "build 1 thr", "build 2 thr", "memory");
    printf("%-44s %14s %14s %14s\n", "", "", "(CPU time)", "(wall clock)");

    /* thesis sampling: one ray per bin, no informed sampling */
    for (m = 0; m < s.material_count; m++) {
        flags[m] = s.materials[m].flags;
        s.materials[m].flags = 0;
    }
    t1 = time_build(&d, NULL, &vol);
    irrvol_destroy(vol);
    t2 = time_build(&d, two, &vol);
    irrvol_info(vol, &info);
    printf("%-44s %14u %12.3f s %12.3f s %7.1f MB\n", "this header, 1 ray per bin (thesis sampling)", info.sample_count,
           t1, t2, info.bytes / 1e6);
    printf("%-44s %14s %12.2f M %12.2f M   rays/s (whole build)\n", "", "", info.rays / t1 / 1e6, info.rays / t2 / 1e6);
    per_sample = t1 / info.sample_count;
    printf("%-44s %14s %10.3f ms %14s   per sample, 1 thread (Greger: 630 ms)\n", "", "", 1e3 * per_sample, "");
    irrvol_destroy(vol);

    /* with the lamp IMPORTANT (informed sampling) */
    for (m = 0; m < s.material_count; m++) s.materials[m].flags = flags[m];
    t1 = time_build(&d, NULL, &vol);
    irrvol_destroy(vol);
    t2 = time_build(&d, two, &vol);
    irrvol_info(vol, &info);
    printf("%-44s %14u %12.3f s %12.3f s %7.1f MB\n", "this header, lamp IMPORTANT (informed)", info.sample_count, t1,
           t2, info.bytes / 1e6);
    printf("%-44s %14s %12.2f M %12.2f M   rays/s (whole build)\n", "", "", info.rays / t1 / 1e6, info.rays / t2 / 1e6);
    printf("%-44s %14u %14s %14s %7.1f MB\n", "Greger 1996 (PA-RISC 7100LC, 100 MHz)", 2287u, "24 min", "", 18.0);
    printf("target: build under 3 s  [%s]\n\n", t2 < 3.0 ? "met" : "NOT MET");

    /* queries: random positions in the room and random directions */
    queries = (float *)malloc(6 * sizeof(float) * QUERIES);
    for (i = 0; i < 6 * QUERIES; i++) {
        state = state * 6364136223846793005ull + 1442695040888963407ull;
        queries[i] = (float)(state >> 40) / 16777216.0f;
    }
    for (i = 0; i < QUERIES; i++) {
        float *q = queries + 6 * (size_t)i;
        q[0] *= 5.0f; q[1] *= 2.8f; q[2] *= 4.0f;
        q[3] -= 0.5f; q[4] -= 0.5f; q[5] -= 0.5f;
    }
    nearest = time_queries(vol, IRRVOL_FILTER_NEAREST, queries, QUERIES, 1, &checksum);
    bilinear = time_queries(vol, IRRVOL_FILTER_BILINEAR, queries, QUERIES, 1, &checksum);
    many_out = (float *)malloc(3 * sizeof(float) * QUERIES);
    many_nearest = time_batched(vol, IRRVOL_FILTER_NEAREST, queries, QUERIES, many_out);
    many_bilinear = time_batched(vol, IRRVOL_FILTER_BILINEAR, queries, QUERIES, many_out);
    free(many_out);
    /* a bunny's vertices with their normals, 0.3 m tall, under the desk */
    bunny_n = s.bunny.vertex_count;
    bunny_q = (float *)malloc(6 * sizeof(float) * bunny_n);
    {
        float *normals = (float *)malloc(3 * sizeof(float) * bunny_n);
        obj_vertex_normals(&s.bunny, normals);
        for (i = 0; i < bunny_n; i++) {
            const float *p = s.positions + 3 * (size_t)(s.office.vertex_count + i);
            bunny_q[6 * i] = p[0]; bunny_q[6 * i + 1] = p[1]; bunny_q[6 * i + 2] = p[2] + 1.8f;
            memcpy(bunny_q + 6 * i + 3, normals + 3 * i, 3 * sizeof(float));
        }
        free(normals);
    }
    coherent = time_queries(vol, IRRVOL_FILTER_NEAREST, bunny_q, bunny_n, 1000, &checksum);
    printf("%-44s %16s %16s\n", "queries per CPU second, one thread", "nearest", "bilinear");
    printf("%-44s %14.1f M %14.1f M\n", "random positions and directions", nearest / 1e6, bilinear / 1e6);
    printf("%-44s %14.1f M %14.1f M\n", "  the same through irrvol_query_many", many_nearest / 1e6, many_bilinear / 1e6);
    printf("%-44s %14.1f M %16s   (%u queries: %.1f us per frame)\n", "the bunny's vertices (coherent)", coherent / 1e6,
           "", bunny_n, 1e6 * bunny_n / coherent);
    printf("%-44s %14.4f M %16s\n", "Greger 1996 (random)", 0.0276, "");
    printf("speed-up over the thesis: %.0fx; one query vs one sample's gather (578 rays + eq. 4.3, %.0f us): %.0fx\n",
           nearest / 27600.0, 1e6 * per_sample, per_sample * nearest);
    printf("target: at least 20 M nearest queries/s on one core  [single queries: %s, batched: %s]\n",
           nearest >= 20e6 ? "met" : "NOT MET", many_nearest >= 20e6 ? "met" : "NOT MET");
    (void)checksum;
    free(bunny_q);
    free(queries);
    irrvol_destroy(vol);
    ex_pool_destroy(two);
    office_scene_free(&s);
    return 0;
}
