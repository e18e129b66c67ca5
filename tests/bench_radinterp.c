/* Benchmark of radinterp.h part 1 on the office scene, beside Hardt's
   figures (1996, four 250 MHz R4400, one used for the offline phase):
   hierarchical radiosity solve, IrradianceAtPoint throughput for points
   whose sources are all fully visible and for points that need the
   backprojection triangulation, and the constrained Delaunay triangulation.
   Times are medians of several runs. */
#define _POSIX_C_SOURCE 200809L
#define RADINTERP_IMPLEMENTATION
#include "radinterp.h"
#include "examples/common/obj.h"
#include "examples/common/pool.h"

#include <time.h>

#define PI 3.14159265358979323846

static double now(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

/* CPU time of the calling thread: the machine is shared, so query rates
   are measured in it rather than in wall time. */
static double thread_cpu(void)
{
    struct timespec t;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : (x > y ? 1 : 0);
}

static double median(double *v, int n)
{
    qsort(v, (size_t)n, sizeof *v, cmp_double);
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

static obj_scene office;
static uint32_t *patches;
static radinterp_material *mats;

static radinterp_desc office_desc(void)
{
    radinterp_desc d;
    memset(&d, 0, sizeof d);
    d.positions = office.positions;
    d.vertex_count = office.vertex_count;
    d.patches = patches;
    d.patch_count = office.face_count;
    d.patch_materials = office.face_material;
    d.materials = mats;
    d.material_count = office.material_count;
    return d;
}

/* Solve time (median of 3) and the solution of the last run. */
static radinterp_solution *bench_solve(radinterp_desc *d, const char *label)
{
    double t[3];
    radinterp_solution *s = NULL;
    radinterp_info info;
    int r;
    for (r = 0; r < 3; r++) {
        double t0 = now();
        if (s) radinterp_solution_destroy(s);
        if (radinterp_solve(d, &s) != RADINTERP_OK) {
            printf("solve failed\n");
            return NULL;
        }
        t[r] = now() - t0;
    }
    radinterp_solution_info(s, &info);
    printf("  %-30s eps %.3f W/m^2: %.3f s, %u leaves, %u links, %llu blocker entries, %u iterations%s\n", label,
           s->eps, median(t, 3), info.leaf_count, info.link_count, (unsigned long long)info.blocker_entries,
           info.iterations, info.converged ? "" : " (not converged)");
    return s;
}

typedef struct sample_point { uint32_t patch; float p[3]; } sample_point;

/* Random points, uniform over the total patch area. */
static uint32_t random_points(const radinterp_solution *s, sample_point *out, uint32_t n, uint64_t seed)
{
    double total = 0.0, *cdf = (double *)malloc(sizeof(double) * s->patch_count);
    uint32_t i, k;
    radinterp__rng rng = radinterp__rng_stream(seed, 1);
    for (i = 0; i < s->patch_count; i++) { total += s->patches[i].area; cdf[i] = total; }
    for (k = 0; k < n; k++) {
        double x = radinterp__rng_float(&rng) * total, tri[4], v[4][3], q[3];
        int c;
        for (i = 0; i + 1 < s->patch_count && cdf[i] < x; i++) {}
        c = radinterp__patch_poly(&s->patches[i], v);
        radinterp__poly_point((const double (*)[3])v, c, tri, radinterp__fan_areas((const double (*)[3])v, c, tri),
                              radinterp__rng_float(&rng), radinterp__rng_float(&rng), q);
        out[k].patch = i;
        out[k].p[0] = (float)q[0]; out[k].p[1] = (float)q[1]; out[k].p[2] = (float)q[2];
    }
    free(cdf);
    return n;
}

/* Calls per second of thread CPU time over a set of points (median of 5
   passes). */
static double bench_queries(const radinterp_solution *s, const sample_point *pts, uint32_t n)
{
    double t[5], sink = 0.0;
    int r;
    uint32_t i;
    if (n == 0) return 0.0;
    for (r = 0; r < 5; r++) {
        double t0 = thread_cpu();
        for (i = 0; i < n; i++) {
            float h[3];
            radinterp_irradiance_at_point(s, pts[i].patch, pts[i].p, NULL, h);
            sink += h[0];
        }
        t[r] = thread_cpu() - t0;
    }
    if (sink < 0) printf("?");
    return n / median(t, 5);
}

/* Query rates of one visibility method: all points, points whose sources
   are all fully visible, points with a partly visible source. */
static void bench_method(const radinterp_solution *s, const char *name, const sample_point *pts, uint32_t n,
                         const sample_point *full, uint32_t nfull, const sample_point *part, uint32_t npart)
{
    printf("  %s:\n", name);
    printf("    all points (uniform over the area)   : %9.0f calls/s\n", bench_queries(s, pts, n));
    printf("    every source fully visible (%4.1f%%)   : %9.0f calls/s\n", 100.0 * nfull / n, bench_queries(s, full, nfull));
    printf("    some source partly visible (%4.1f%%)   : %9.0f calls/s\n", 100.0 * npart / n, bench_queries(s, part, npart));
}

static void bench_cdt(void)
{
    const uint32_t n = 100000, nseg = 2000;
    double *xy = (double *)malloc(sizeof(double) * 2 * (n + 2 * nseg)), t[3];
    uint32_t *ids = (uint32_t *)malloc(sizeof(uint32_t) * (n + 2 * nseg)), i, r;
    radinterp_allocator a;
    radinterp__rng rng = radinterp__rng_stream(5, 5);
    uint32_t verts = 0, tris = 0;
    memset(&a, 0, sizeof a);
    for (i = 0; i < 2 * n; i++) xy[i] = radinterp__rng_float(&rng);
    for (r = 0; r < 3; r++) {
        radinterp__cdt c;
        double t0 = now();
        radinterp__cdt_init(&c, &a, NULL, 0);
        radinterp__cdt_add_points(&c, xy, n, ids);
        t[r] = now() - t0;
        verts = c.vertex_count;
        tris = c.tri_count;
        radinterp__cdt_free(&c);
    }
    printf("  %u random points (Hilbert order): %.3f s, %.0f points/s (%u vertices, %u triangles incl. ghosts)\n", n,
           median(t, 3), n / median(t, 3), verts, tris);
    /* segments of length about 0.02 in random directions, which cross each
       other and pass near many points */
    for (i = 0; i < nseg; i++) {
        double x = 0.05 + 0.9 * radinterp__rng_float(&rng), y = 0.05 + 0.9 * radinterp__rng_float(&rng);
        double ang = 6.283185307179586 * radinterp__rng_float(&rng);
        xy[2 * (n + 2 * i)] = x;
        xy[2 * (n + 2 * i) + 1] = y;
        xy[2 * (n + 2 * i + 1)] = x + 0.02 * cos(ang);
        xy[2 * (n + 2 * i + 1) + 1] = y + 0.02 * sin(ang);
    }
    for (r = 0; r < 3; r++) {
        radinterp__cdt c;
        double t0;
        radinterp__cdt_init(&c, &a, NULL, 0);
        radinterp__cdt_add_points(&c, xy, n + 2 * nseg, ids);
        t0 = now();
        for (i = 0; i < nseg; i++) radinterp__cdt_add_segment(&c, ids[n + 2 * i], ids[n + 2 * i + 1]);
        t[r] = now() - t0;
        verts = c.vertex_count;
        radinterp__cdt_free(&c);
    }
    printf("  + %u constraints among them: %.3f s, %.0f segments/s (%u vertices after crossings)\n", nseg,
           median(t, 3), nseg / median(t, 3), verts);
    free(xy);
    free(ids);
}

int main(void)
{
    char err[256];
    radinterp_desc d;
    radinterp_solution *s;
    sample_point *pts, *full, *part;
    uint32_t f, n = 4000, nfull = 0, npart = 0, i;
    ex_pool *pool;
    if (obj_load("examples/data/office.obj", &office, err, sizeof err) != 0) {
        printf("%s\n", err);
        return 1;
    }
    patches = (uint32_t *)malloc(4 * sizeof(uint32_t) * office.face_count);
    mats = (radinterp_material *)malloc(sizeof(radinterp_material) * office.material_count);
    for (f = 0; f < office.face_count; f++) {
        uint32_t c = office.face_start[f + 1] - office.face_start[f], k;
        for (k = 0; k < 4; k++) patches[4 * f + k] = k < c ? office.face_vertices[office.face_start[f] + k] : RADINTERP_NO_VERTEX;
    }
    for (f = 0; f < office.material_count; f++) {
        int k;
        for (k = 0; k < 3; k++) {
            mats[f].reflectance[k] = office.materials[f].kd[k];
            mats[f].emission[k] = (float)PI * office.materials[f].ke[k];
        }
    }
    printf("radinterp.h part 1: office scene, %u patches (Hardt: about 60 quadrilaterals)\n", office.face_count);
    printf("hierarchical radiosity solve (Hardt: eps 0.1 W/m^2, 1622 leaves, under 2 minutes):\n");
    d = office_desc();
    s = bench_solve(&d, "default parameters, 1 thread");
    radinterp_solution_destroy(s);
    pool = ex_pool_create(0);
    d.parallel_for = ex_pool_parallel_for;
    d.parallel_user = pool;
    s = bench_solve(&d, "default parameters, pool");
    radinterp_solution_destroy(s);
    d = office_desc();
    d.eps = 0.1f;
    s = bench_solve(&d, "Hardt's eps, 1 thread");
    radinterp_solution_destroy(s);
    d = office_desc();
    s = bench_solve(&d, "default (queried below)");
    if (!s) return 1;

    printf("IrradianceAtPoint, one core, thread CPU time (Hardt: about 39,000 evaluations in 2.5 CPU hours = 4.3/s;\n"
           "target 100,000/s):\n");
    pts = (sample_point *)malloc(sizeof *pts * n);
    full = (sample_point *)malloc(sizeof *pts * n);
    part = (sample_point *)malloc(sizeof *pts * n);
    random_points(s, pts, n, 11);
    for (i = 0; i < n; i++) {
        double h[3];
        uint32_t tri = 0;
        radinterp__irradiance(s, pts[i].patch, pts[i].p, NULL, h, &tri);
        if (tri) part[npart++] = pts[i];
        else full[nfull++] = pts[i];
    }
    bench_method(s, "shadow union (default; F(source) - F(union of the shadows))", pts, n, full, nfull, part, npart);
    {
        radinterp_solution *t = NULL;
        d.visibility = RADINTERP_VISIBILITY_TRIANGULATION;
        if (radinterp_solve(&d, &t) == RADINTERP_OK)
            bench_method(t, "triangulation (Hardt 6.2.3: CDT of the projected edges, a ray per region; before)", pts, n,
                         full, nfull, part, npart);
        radinterp_solution_destroy(t);
    }
    {
        double links = 0.0;
        for (i = 0; i < 200; i++) {
            uint32_t node = radinterp__locate_leaf(s, pts[i].patch, (const double[3]){pts[i].p[0], pts[i].p[1], pts[i].p[2]});
            for (; node != RADINTERP__NONE; node = s->nodes[node].parent) links += s->nodes[node].link_count;
        }
        printf("  links per query: %.1f on average\n", links / 200);
    }
    printf("constrained Delaunay triangulation:\n");
    bench_cdt();
    radinterp_solution_destroy(s);
    ex_pool_destroy(pool);
    free(pts);
    free(full);
    free(part);
    free(patches);
    free(mats);
    obj_free(&office);
    return 0;
}
