/* Benchmark of radinterp.h on the office scene, beside Hardt's figures
   (1996, four 250 MHz R4400, one used for the offline phase):
   part 1: hierarchical radiosity solve, IrradianceAtPoint throughput for
   points whose sources are all fully visible and for points that need the
   backprojection triangulation, and the constrained Delaunay triangulation;
   part 2: the discontinuity mesh (discontinuities found and activated,
   leaves, triangles, build time on 1 and 2 threads) and the online phase
   (radinterp_shade on a 640x480 ID + barycentric buffer, 1 and 2 threads).
   Times are medians of several runs. */
#define _POSIX_C_SOURCE 200809L
#define RADINTERP_IMPLEMENTATION
#include "radinterp.h"
#include "examples/common/obj.h"
#include "examples/common/pool.h"
#include "examples/common/raster.h"

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

/* Mesh build time (median of 3) and the mesh of the last run. */
static radinterp_mesh *bench_mesh(const radinterp_solution *s, ex_pool *pool, const char *label)
{
    radinterp_mesh_desc md;
    radinterp_mesh *m = NULL;
    radinterp_mesh_info info;
    double t[3];
    int r;
    memset(&md, 0, sizeof md);
    md.parallel_for = pool ? ex_pool_parallel_for : NULL;
    md.parallel_user = pool;
    for (r = 0; r < 3; r++) {
        double t0 = now();
        radinterp_mesh_destroy(m);
        if (radinterp_build_mesh(s, &md, &m) != RADINTERP_OK) {
            printf("mesh build failed\n");
            return NULL;
        }
        t[r] = now() - t0;
    }
    radinterp_mesh_get_info(m, &info);
    printf("  %-12s %.2f s for %u triangles (%llu IrradianceAtPoint samples, %.0f samples/s)\n", label, median(t, 3),
           info.triangle_count, (unsigned long long)info.samples, (double)info.samples / median(t, 3));
    return m;
}

typedef struct shade_frame { const radinterp_mesh *m; const uint32_t *ids; const float *st; float *rgb; size_t n; } shade_frame;

/* Frames per second of radinterp_shade (or the Gouraud variant) over a
   fixed ID + barycentric buffer, median of 5 runs of 100 frames. */
static double bench_shade(const shade_frame *f, int gouraud)
{
    double t[5];
    int r, k;
    for (r = 0; r < 5; r++) {
        double t0 = now();
        for (k = 0; k < 100; k++) {
            if (gouraud) radinterp_shade_gouraud(f->m, f->ids, f->st, f->n, f->rgb);
            else radinterp_shade(f->m, f->ids, f->st, f->n, f->rgb);
        }
        t[r] = (now() - t0) / 100;
    }
    return 1.0 / median(t, 5);
}

static void bench_part2(const radinterp_solution *s)
{
    ex_pool *pool2 = ex_pool_create(2);
    radinterp_mesh *m;
    radinterp_mesh_info info;
    radinterp_mesh_data data;
    ex_raster r;
    ex_camera cam;
    shade_frame f;
    float eye[3] = {4.6f, 1.6f, 0.3f}, target[3] = {1.6f, 0.7f, 3.2f}, up[3] = {0, 1, 0};
    size_t i, covered = 0;
    void *bytes = NULL;
    size_t size = 0;
    printf("discontinuity mesh with quadratic interpolants (Hardt: 1622 leaves, 6576 triangles, interpolants in "
           "2.5 CPU hours; target: under 10 s):\n");
    m = bench_mesh(s, NULL, "1 thread:");
    radinterp_mesh_destroy(m);
    m = bench_mesh(s, pool2, "2 threads:");
    if (!m) return;
    radinterp_mesh_get_info(m, &info);
    radinterp_mesh_get_data(m, &data);
    radinterp_mesh_save_to_memory(m, NULL, &bytes, &size);
    radinterp_free_memory(NULL, bytes);
    printf("  discontinuities found: %u (%u EV, %u VE, %u horizon, %u contact) on %u lines (DSets); %u above "
           "min_discont_weight, %u activated\n", info.discontinuities, info.ev, info.ve, info.horizon, info.contact,
           info.dsets, info.candidates, info.active_discontinuities);
    printf("  %u leaves (%u split to restrict the quadtrees), %u triangles, %u vertices; %u T-vertices closed inside "
           "patches, %u seam vertices; %.1f MB in memory, %.1f MB saved\n", info.leaf_count, info.balance_splits,
           info.triangle_count, info.vertex_count, info.hanging_vertices, info.seam_vertices, info.bytes / 1e6,
           size / 1e6);
    /* the online phase on the example's view */
    cam = ex_camera_look_at(eye, target, up, 60.0f, 640, 480);
    if (ex_raster_init(&r, 640, 480) != 0) return;
    ex_raster_clear(&r);
    ex_raster_draw(&r, &cam, data.positions, data.indices, data.triangle_count, 0);
    for (i = 0; i < (size_t)640 * 480; i++) covered += r.id[i] != EX_RASTER_EMPTY;
    f.m = m;
    f.ids = r.id;
    f.st = r.bary;
    f.n = (size_t)640 * 480;
    f.rgb = (float *)malloc(3 * f.n * sizeof(float));
    printf("per-pixel shading of a 640x480 ID + barycentric buffer (%.0f%% covered; Hardt: 2.3 frames/s on four "
           "250 MHz CPUs; target: 500 frames/s on one core):\n", 100.0 * covered / f.n);
    printf("  interpolants, 1 thread : %7.0f frames/s\n", bench_shade(&f, 0));
    printf("  Gouraud,      1 thread : %7.0f frames/s\n", bench_shade(&f, 1));
    radinterp_mesh_set_parallel_for(m, ex_pool_parallel_for, pool2);
    printf("  interpolants, 2 threads: %7.0f frames/s\n", bench_shade(&f, 0));
    free(f.rgb);
    ex_raster_free(&r);
    radinterp_mesh_destroy(m);
    ex_pool_destroy(pool2);
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
    mats = (radinterp_material *)calloc(office.material_count, sizeof(radinterp_material));
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
    printf("radinterp.h: office scene, %u patches (Hardt: about 60 quadrilaterals)\n", office.face_count);
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
    bench_part2(s);
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
