/* irrvol.h benchmark, with the build flags a user would use (-O2; the
   Makefile builds this one benchmark so): Greger's office settings (7^3
   first level, 3^3 second level, k = 17, 578 bins, the defaults) on the
   office with a static bunny, and the generated building when its OBJ is
   there. Build time and rays/s on 1 and 2 threads and memory, with and
   without refinement by light; queries/s for every filter and weighting and
   for the harmonics; next to the thesis's figures (5.1.1: 2287 samples, 24
   minutes, 18 MB, 27,600 queries/s on a 100 MHz PA-RISC 7100LC).
   The machine is shared with other work: single-thread figures are the
   thread's CPU time (time slicing does not inflate it), medians of several
   runs; two-thread builds are wall-clock time and say so. The load average
   is printed with the figures. */
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

static void print_load(void)
{
    char line[128] = "unknown";
    FILE *f = fopen("/proc/loadavg", "r");
    if (f) {
        if (!fgets(line, sizeof line, f)) strcpy(line, "unknown\n");
        fclose(f);
    }
    printf("load average: %s", line);
}

/* Median build time (CPU time without a pool, else wall clock) of runs
   builds; *vol keeps the last volume. */
static double time_build(irrvol_desc *d, ex_pool *pool, int runs, irrvol **vol)
{
    double t[5];
    double (*clock_fn)(void) = pool ? now : cpu_now;
    int r;
    d->parallel_for = pool ? ex_pool_parallel_for : NULL;
    d->parallel_user = pool;
    *vol = NULL;
    for (r = 0; r < runs; r++) {
        double t0;
        irrvol_destroy(*vol);
        t0 = clock_fn();
        if (irrvol_build(d, vol) != IRRVOL_OK) { fprintf(stderr, "build failed\n"); exit(1); }
        t[r] = clock_fn() - t0;
    }
    return median(t, runs);
}

/* One line of the build table: 1 and 2 threads, samples, memory. */
static irrvol *build_row(const char *name, irrvol_desc *d, ex_pool *two, int runs)
{
    irrvol *vol;
    irrvol_volume_info info;
    double t1 = time_build(d, NULL, runs, &vol), t2;
    irrvol_destroy(vol);
    t2 = time_build(d, two, runs, &vol);
    irrvol_info(vol, &info);
    printf("%-40s %7u %6u %6u %10.2f s %10.2f s %8.1f MB %7.2f M %5u %5u\n", name, info.sample_count,
           info.refined_cells, info.light_refined_cells, t1, t2, info.bytes / 1e6, info.rays / t1 / 1e6,
           info.relocated_samples, info.invalid_samples);
    return vol;
}

static void build_header(void)
{
    printf("%-40s %7s %6s %6s %12s %12s %11s %9s %5s %5s\n", "", "samples", "refin.", "light", "build 1 thr",
           "build 2 thr", "memory", "rays/s", "moved", "inval");
    printf("%-40s %7s %6s %6s %12s %12s %11s %9s %5s %5s\n", "", "", "cells", "cells", "(CPU time)", "(wall clock)", "",
           "1 thread", "", "id");
}

#define QUERIES 2000000u
#define RUNS 5

typedef enum query_kind { BINS, SH, MANY } query_kind;

/* Queries per CPU second of one thread, median of RUNS passes. */
static double time_queries(const irrvol *v, query_kind kind, irrvol_filter filter, irrvol_weighting weighting,
                           uint32_t order, const float *q, uint32_t n, uint32_t repeat, float *out)
{
    double t[RUNS];
    int r;
    for (r = 0; r < RUNS; r++) {
        double t0 = cpu_now();
        uint32_t i, k;
        for (k = 0; k < repeat; k++) {
            if (kind == MANY) {
                irrvol_query_many(v, filter, weighting, n, q, 6 * sizeof(float), q + 3, 6 * sizeof(float), out);
                continue;
            }
            for (i = 0; i < n; i++) {
                const float *p = q + 6 * (size_t)i;
                if (kind == SH) irrvol_query_sh(v, order, weighting, p, p + 3, out + 3 * (size_t)i);
                else irrvol_query_filter(v, filter, weighting, p, p + 3, out + 3 * (size_t)i);
            }
        }
        t[r] = cpu_now() - t0;
    }
    return (double)n * repeat / median(t, RUNS);
}

/* Query rates on the default volume (random points in the office and the
   bunny's vertices, coherent), on the same volume with its bins at full
   precision (desc.full_precision: three floats a bin instead of an RGB9E5
   word) and, random, on the volume refined where geometry is only, the
   size the thesis's settings give (the rate of random queries falls as the
   volume outgrows the caches). The last column repeats eight random
   queries in turn: everything they read stays in the first-level cache and
   their branches are learnt, so it is the rate of the query's arithmetic
   alone, the ceiling of any data layout. The targets are issue 14's, for single
   random queries. */
#define SAME_QUERIES 100000u   /* copies of eight queries, run 20 times */

static void query_table(const irrvol *vol, const irrvol *full, const irrvol *thesis_grid, const float *random_q,
                        const float *bunny_q, uint32_t bunny_n)
{
    static const struct {
        const char *name; query_kind kind; irrvol_filter f; irrvol_weighting w; uint32_t order; double target;
    } rows[] = {
        {"nearest, plain trilinear (thesis)", BINS, IRRVOL_FILTER_NEAREST, IRRVOL_WEIGHTING_TRILINEAR, 0, 20e6},
        {"bilinear, plain trilinear", BINS, IRRVOL_FILTER_BILINEAR, IRRVOL_WEIGHTING_TRILINEAR, 0, 0.0},
        {"nearest, leak-safe", BINS, IRRVOL_FILTER_NEAREST, IRRVOL_WEIGHTING_VISIBILITY, 0, 0.0},
        {"bilinear, leak-safe (the default)", BINS, IRRVOL_FILTER_BILINEAR, IRRVOL_WEIGHTING_VISIBILITY, 0, 10e6},
        {"harmonics L2, leak-safe", SH, IRRVOL_FILTER_DEFAULT, IRRVOL_WEIGHTING_VISIBILITY, 2, 0.0},
        {"harmonics L2, plain trilinear", SH, IRRVOL_FILTER_DEFAULT, IRRVOL_WEIGHTING_TRILINEAR, 2, 0.0},
        {"harmonics L1, leak-safe", SH, IRRVOL_FILTER_DEFAULT, IRRVOL_WEIGHTING_VISIBILITY, 1, 0.0},
        {"batched nearest, plain (query_many)", MANY, IRRVOL_FILTER_NEAREST, IRRVOL_WEIGHTING_TRILINEAR, 0, 0.0},
        {"batched bilinear, leak-safe (query_many)", MANY, IRRVOL_FILTER_BILINEAR, IRRVOL_WEIGHTING_VISIBILITY, 0, 0.0},
    };
    float *out = (float *)malloc(3 * sizeof(float) * QUERIES), *same_q = (float *)malloc(6 * sizeof(float) * SAME_QUERIES);
    size_t i;
    irrvol_volume_info a_info, f_info, b_info;
    irrvol_info(vol, &a_info);
    irrvol_info(full, &f_info);
    irrvol_info(thesis_grid, &b_info);
    for (i = 0; i < SAME_QUERIES; i++) memcpy(same_q + 6 * i, random_q + 6 * (i % 8), 6 * sizeof(float));
    printf("%-42s %13s %13s %13s %13s %13s %s\n", "queries per CPU second, one thread", "random", "bunny verts",
           "random", "random", "8 queries", "  target (random)");
    printf("%-42s %13s %13s %13s %13s %13s\n", "", "(defaults)", "(defaults)", "(full prec.)", "(geom. grid)",
           "(repeated)");
    printf("%-42s %10.1f MB %13s %10.1f MB %10.1f MB\n", "", a_info.bytes / 1e6, "", f_info.bytes / 1e6,
           b_info.bytes / 1e6);
    for (i = 0; i < sizeof rows / sizeof rows[0]; i++) {
        double a = time_queries(vol, rows[i].kind, rows[i].f, rows[i].w, rows[i].order, random_q, QUERIES, 1, out);
        double b = time_queries(vol, rows[i].kind, rows[i].f, rows[i].w, rows[i].order, bunny_q, bunny_n, 500, out);
        double f = time_queries(full, rows[i].kind, rows[i].f, rows[i].w, rows[i].order, random_q, QUERIES, 1, out);
        double c = time_queries(thesis_grid, rows[i].kind, rows[i].f, rows[i].w, rows[i].order, random_q, QUERIES, 1, out);
        double o = time_queries(vol, rows[i].kind, rows[i].f, rows[i].w, rows[i].order, same_q, SAME_QUERIES, 20, out);
        printf("%-42s %11.1f M %11.1f M %11.1f M %11.1f M %11.1f M", rows[i].name, a / 1e6, b / 1e6, f / 1e6, c / 1e6,
               o / 1e6);
        if (rows[i].target > 0.0)
            printf("   >= %.0f M [%s]", rows[i].target / 1e6, a >= rows[i].target ? "met" : "NOT MET");
        printf("\n");
    }
    printf("%-42s %11.4f M\n", "Greger 1996 (random)", 0.0276);
    free(same_q);
    free(out);
}

/* The generated building, when examples/data has it: its triangles with a
   grey Kd and the emitting materials IMPORTANT, like the office. */
static void building_rows(ex_pool *two)
{
    static const char *names[] = {"building_4k", "building"};
    char path[256], err[256];
    obj_scene b;
    size_t i;
    int loaded = 0;
    for (i = 0; i < sizeof names / sizeof names[0] && !loaded; i++) {
        snprintf(path, sizeof path, "examples/data/%s.obj", names[i]);
        loaded = obj_load(path, &b, err, sizeof err) == 0;
    }
    if (!loaded) {
        printf("generated building: examples/data/building_4k.obj not found (python3 examples/data/make_building.py "
               "writes it)\n");
        return;
    }
    {
        irrvol_material *m = (irrvol_material *)calloc(b.material_count ? b.material_count : 1, sizeof *m);
        irrvol_desc d;
        irrvol *vol;
        uint32_t k;
        char name[64];
        for (k = 0; k < b.material_count; k++) {
            int c;
            for (c = 0; c < 3; c++) m[k].radiance[c] = b.materials[k].ke[c] + 0.1f * b.materials[k].kd[c];
            if (b.materials[k].ke[0] > 0.0f || b.materials[k].ke[1] > 0.0f || b.materials[k].ke[2] > 0.0f)
                m[k].flags = IRRVOL_MATERIAL_IMPORTANT;
        }
        memset(&d, 0, sizeof d);
        d.positions = b.positions;
        d.vertex_count = b.vertex_count;
        d.indices = b.tri_indices;
        d.triangle_count = b.tri_count;
        d.triangle_materials = b.tri_material;
        d.materials = m;
        d.material_count = b.material_count ? b.material_count : 1;
        printf("%s: %u triangles, defaults\n", path, b.tri_count);
        snprintf(name, sizeof name, "refined by geometry only");
        d.refine_threshold = -1.0f;
        irrvol_destroy(build_row(name, &d, two, 1));
        snprintf(name, sizeof name, "and by light (the default)");
        d.refine_threshold = 0.0f;
        vol = build_row(name, &d, two, 1);
        irrvol_destroy(vol);
        free(m);
        obj_free(&b);
    }
}

int main(void)
{
    office_scene s;
    irrvol_desc d;
    irrvol *vol, *thesis_grid, *full;
    irrvol_volume_info info;
    ex_pool *two = ex_pool_create(2);
    uint32_t i, m, bunny_n;
    uint64_t state = 7;
    float *queries, *bunny_q;
    uint32_t flags[64];
    print_load();
    if (office_scene_load(&s, "examples/data", 2.0f, 1.5f) != 0 || s.material_count > 64) return 1;
    office_scene_desc(&s, &d);
    printf("office + bunny: %u triangles; Greger's settings (the defaults): 7^3 first level, 3^3 second level, "
           "k = 17 (578 bins)\n", s.tri_count);
    build_header();
    for (m = 0; m < s.material_count; m++) {   /* thesis sampling: one ray per bin, no informed sampling */
        flags[m] = s.materials[m].flags;
        s.materials[m].flags = 0;
    }
    d.refine_threshold = -1.0f;
    irrvol_destroy(build_row("1 ray per bin, geometry refinement", &d, two, RUNS));
    for (m = 0; m < s.material_count; m++) s.materials[m].flags = flags[m];
    thesis_grid = build_row("lamp IMPORTANT, geometry refinement", &d, two, RUNS);
    d.refine_threshold = 0.0f;
    vol = build_row("lamp IMPORTANT, and light (the default)", &d, two, RUNS);
    printf("%-40s %7u %6s %6s %12s %12s %8.1f MB\n", "Greger 1996 (PA-RISC 7100LC, 100 MHz)", 2287u, "", "", "24 min",
           "", 18.0);
    d.full_precision = 1;   /* the same volume, its bins as floats: queries compared below */
    full = build_row("and light, full precision", &d, two, 1);
    d.full_precision = 0;
    irrvol_info(vol, &info);
    printf("the default volume: %u samples (%u hanging: no gather), %u relocated, %u invalid; %.1f KB per sample of "
           "which bins %.1f, visibility %.1f, harmonics %.2f\n\n", info.sample_count, info.hanging_samples,
           info.relocated_samples, info.invalid_samples, info.bytes / 1e3 / info.sample_count,
           info.bins * info.bin_bytes / 1e3,
           (info.visibility_resolution + 2) * (info.visibility_resolution + 2) * 16 / 1e3, 27 * 4 / 1e3);

    /* queries: random positions in the room and random directions; the bunny's vertices */
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
    bunny_n = s.bunny.vertex_count;   /* a bunny's vertices and normals, 0.3 m tall, under the desk */
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
    query_table(vol, full, thesis_grid, queries, bunny_q, bunny_n);
    irrvol_destroy(vol);
    irrvol_destroy(full);
    irrvol_destroy(thesis_grid);
    free(bunny_q);
    free(queries);
    printf("\n");
    building_rows(two);
    print_load();
    ex_pool_destroy(two);
    office_scene_free(&s);
    return 0;
}
