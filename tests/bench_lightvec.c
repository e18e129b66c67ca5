/* Benchmarks of lightvec.h, with the paper's figures beside ours:
   - lookup time with 10^4, 10^5, 10^6 cached vectors, sparse (~6 valid per
     query) and dense (~45 valid), queries in a random and in a sorted order
     (paper, 3.3: 10-15 ms per query on a 1.2 GHz Athlon, nearly independent
     of the size; issue 15's target: under 2 us at 10^5);
   - gather time (one light vector, default parameters);
   - one 512 x 512 Cornell box frame of indirect light with the cache against
     gathering at every pixel (target: 10x faster, at < 5% error);
   - hit rate over a 30-frame camera path in the Cornell box and the frame-time
     saving against gathering everywhere (paper, table 1: 66% saved against the
     render cache alone on Cornell box 1; we have no render cache here);
   - the same path over issue 15's glossy floor: frame time against gathering
     every pixel, hit rates, the floor's error against a converged gather.
   Timings are medians over repetitions, single-threaded, in CPU time of the
   benchmark thread (the machine may be shared: wall time would count the
   time other processes run). */
#define _POSIX_C_SOURCE 200809L
#define LIGHTVEC_IMPLEMENTATION
#include "lightvec.h"
#include "examples/common/obj.h"
#include "examples/common/camera.h"
#include <stdio.h>
#include <time.h>

#define PI 3.14159265358979323846

static double now(void)
{
    struct timespec t;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

static double median(double *v, int n)
{
    qsort(v, (size_t)n, sizeof *v, cmp_double);
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

typedef struct rng { uint64_t s; } rng;
static double rnd(rng *r)
{
    r->s = r->s * 6364136223846793005ull + 1442695040888963407ull;
    return (double)(r->s >> 11) * (1.0 / 9007199254740992.0);
}

static void random_unit(rng *r, float *v)
{
    double z = 2 * rnd(r) - 1, phi = 2 * PI * rnd(r), s = sqrt(1 - z * z);
    v[0] = (float)(s * cos(phi)); v[1] = (float)(s * sin(phi)); v[2] = (float)z;
}

/* A cache as a walkthrough would build it: records on the six walls of a
   unit room (normal = the wall's), computed for a viewer somewhere on a
   circle of radius 0.15 around the room's centre (sigma = toward that eye),
   validity radii set so that a point of a wall lies in about 12 validity
   disks, whatever the count (a cache places records where none is valid). */
static void wall_point(rng *r, float *p, float *n)
{
    int wall = (int)(rnd(r) * 6) % 6, axis = wall / 2, k;
    for (k = 0; k < 3; k++) {
        p[k] = (float)rnd(r);
        n[k] = 0.0f;
    }
    p[axis] = wall % 2 ? 1.0f : 0.0f;
    n[axis] = wall % 2 ? -1.0f : 1.0f;
}

static void toward_eye(rng *r, const float *p, float *w)
{
    double a = 2 * PI * rnd(r), l;
    float eye[3];
    int k;
    eye[0] = (float)(0.5 + 0.15 * cos(a));
    eye[1] = 0.5f;
    eye[2] = (float)(0.5 + 0.15 * sin(a));
    for (k = 0; k < 3; k++) w[k] = eye[k] - p[k];
    l = sqrt((double)w[0] * w[0] + (double)w[1] * w[1] + (double)w[2] * w[2]);
    for (k = 0; k < 3; k++) w[k] = (float)(w[k] / l);
}

static void random_record(rng *r, lightvec_record *rec, double radius)
{
    int c;
    memset(rec, 0, sizeof *rec);
    wall_point(r, rec->position, rec->normal);
    toward_eye(r, rec->position, rec->outgoing);
    random_unit(r, rec->vector.direction);
    if (rec->vector.direction[0] * rec->normal[0] + rec->vector.direction[1] * rec->normal[1] +
        rec->vector.direction[2] * rec->normal[2] < 0)
        for (c = 0; c < 3; c++) rec->vector.direction[c] = -rec->vector.direction[c];
    for (c = 0; c < 3; c++) {
        rec->vector.magnitude[c] = (float)(0.5 + rnd(r));
        rec->irradiance[c] = (float)(0.5 + rnd(r));
    }
    /* radius_scale 0.3 (default) times d_avg gives the validity radius */
    rec->distance = (float)(radius * (0.5 + rnd(r)) / 0.3);
    rec->visibility = 1.0f;
}

static int cmp_cell(const void *a, const void *b)
{
    const float *x = (const float *)a, *y = (const float *)b;
    int k;
    for (k = 0; k < 3; k++) {
        int cx = (int)(x[k] * 64.0f), cy = (int)(y[k] * 64.0f);
        if (cx != cy) return cx < cy ? -1 : 1;
    }
    return 0;
}

/* Median time per lookup over 5 passes of the queries qp[0, nq). */
static double lookup_time(const lightvec_cache *cache, float (*qp)[9], uint32_t nq, uint32_t *valid, uint32_t *hits)
{
    double times[5];
    int rep;
    *valid = *hits = 0;
    for (rep = 0; rep < 5; rep++) {
        double t0 = now();
        uint32_t q;
        for (q = 0; q < nq; q++) {
            lightvec_lookup_result lr;
            lightvec_lookup(cache, qp[q], qp[q] + 3, qp[q] + 6, &lr);
            if (rep == 0) { *valid += lr.valid_count; *hits += (uint32_t)lr.hit; }
        }
        times[rep] = (now() - t0) / nq;
    }
    return median(times, 5);
}

/* Sparse caches (a wall point inside about 12 validity disks before the
   criteria: ~6 valid records per query) at 1e4 .. 1e6 records, dense ones
   (~150 disks: ~45 valid) at 1e5. Queries in a random order (every
   one a cache miss at 1e5 records and more) and sorted by position (as the
   pixels of a frame come), before and after optimize. */
static void bench_lookups(void)
{
    static const uint32_t sizes[4] = { 10000, 100000, 1000000, 100000 };
    static const double cover[4] = { 12, 12, 12, 150 };
    double at_1e5[2][2] = { { 0, 0 }, { 0, 0 } }, valid_1e5[2] = { 0, 0 }; /* [sparse, dense][random, sorted] */
    int s;
    printf("lookup time, us, thread CPU time, median of 5 passes (paper, 3.3: 10-15 ms per query on a 1.2 GHz\n"
           "Athlon, nearly independent of the size; issue 15's target: < 2 us at 1e5 records, sparse and dense);\n"
           "opt[ms]: lightvec_cache_optimize, CPU time; B/rec: memory the cache holds per record as inserted\n");
    printf("  %9s %7s %11s %9s %9s %9s %9s %8s %8s %8s %8s\n", "records", "cover", "insert[us]", "random", "sorted",
           "opt rand", "opt sort", "valid", "hits", "opt[ms]", "B/rec");
    for (s = 0; s < 4; s++) {
        lightvec_cache *cache = NULL;
        lightvec_record rec;
        rng r;
        lightvec_cache_stats st;
        uint32_t i, q, nq = 100000, valid = 0, hits = 0, v2, h2;
        /* disks of radius r cover a wall point about `cover` times: n/6 pi r^2 = cover */
        double radius = sqrt(cover[s] * 6.0 / (PI * sizes[s])), t0, t_insert, t_optimize, t[4];
        float (*qp)[9] = (float (*)[9])malloc(sizeof(float[9]) * nq), (*sorted)[9] = (float (*)[9])malloc(sizeof(float[9]) * nq);
        if (!qp || !sorted || lightvec_cache_create(NULL, &cache) != LIGHTVEC_OK) return;
        r.s = 1234;
        t0 = now();
        for (i = 0; i < sizes[s]; i++) {
            random_record(&r, &rec, radius);
            lightvec_insert(cache, &rec, NULL);
        }
        t_insert = (now() - t0) / sizes[s];
        for (q = 0; q < nq; q++) { /* points on the walls seen from the path */
            wall_point(&r, qp[q], qp[q] + 3);
            toward_eye(&r, qp[q], qp[q] + 6);
        }
        memcpy(sorted, qp, sizeof(float[9]) * nq);
        qsort(sorted, nq, sizeof(float[9]), cmp_cell);
        t[0] = lookup_time(cache, qp, nq, &valid, &hits);
        t[1] = lookup_time(cache, sorted, nq, &v2, &h2);
        lightvec_cache_info(cache, &st); /* memory held as inserted: records, trees, faces */
        t0 = now();
        lightvec_cache_optimize(cache);
        t_optimize = now() - t0;
        t[2] = lookup_time(cache, qp, nq, &v2, &h2);
        t[3] = lookup_time(cache, sorted, nq, &v2, &h2);
        printf("  %9u %7.0f %11.2f %9.3f %9.3f %9.3f %9.3f %8.1f %7.1f%% %8.1f %8.0f\n", sizes[s], cover[s],
               1e6 * t_insert, 1e6 * t[0], 1e6 * t[1], 1e6 * t[2], 1e6 * t[3], (double)valid / nq, 100.0 * hits / nq,
               1e3 * t_optimize, (double)st.bytes / sizes[s]);
        if (sizes[s] == 100000) {
            at_1e5[s == 3][0] = t[0];
            at_1e5[s == 3][1] = t[1];
            valid_1e5[s == 3] = (double)valid / nq;
        }
        free(qp);
        free(sorted);
        lightvec_cache_destroy(cache);
    }
    for (s = 0; s < 2; s++)
        printf("  1e5 records, %s (%.0f valid): %.2f us random, %.2f us sorted (issue 15's target: < 2 us)\n",
               s ? "dense " : "sparse", valid_1e5[s], 1e6 * at_1e5[s][0], 1e6 * at_1e5[s][1]);
}

/* ---- Cornell box ------------------------------------------------------------------ */

static obj_scene g_obj;
static lightvec_material *g_mats;      /* the scene's materials, the glossy floor's last */
static uint32_t *g_tri_mat;            /* per triangle */
static lightvec_scene *g_scene;

typedef struct pixel { int valid, wall, floor; lightvec_surface s; } pixel;

/* g_scene over the box's triangles with g_tri_mat and g_mats[0, materials). */
static int make_scene(uint32_t materials)
{
    lightvec_scene_desc d;
    lightvec_scene_destroy(g_scene);
    g_scene = NULL;
    memset(&d, 0, sizeof d);
    d.positions = g_obj.positions;
    d.vertex_count = g_obj.vertex_count;
    d.indices = g_obj.tri_indices;
    d.triangle_count = g_obj.tri_count;
    d.material_ids = g_tri_mat;
    d.materials = g_mats;
    d.material_count = materials;
    return lightvec_scene_create(&d, &g_scene) == LIGHTVEC_OK ? 0 : -1;
}

static int load_cornell(void)
{
    char err[256];
    uint32_t i;
    if (obj_load("examples/data/cornell_box.obj", &g_obj, err, sizeof err) != 0) {
        fprintf(stderr, "%s\n", err);
        return -1;
    }
    g_mats = (lightvec_material *)calloc(g_obj.material_count + 1, sizeof *g_mats);
    g_tri_mat = (uint32_t *)malloc(g_obj.tri_count * sizeof *g_tri_mat);
    if (!g_mats || !g_tri_mat) return -1;
    memcpy(g_tri_mat, g_obj.tri_material, g_obj.tri_count * sizeof *g_tri_mat);
    for (i = 0; i < g_obj.material_count; i++) {
        memcpy(g_mats[i].diffuse, g_obj.materials[i].kd, sizeof g_mats[i].diffuse);
        memcpy(g_mats[i].specular, g_obj.materials[i].ks, sizeof g_mats[i].specular);
        memcpy(g_mats[i].emission, g_obj.materials[i].ke, sizeof g_mats[i].emission);
        g_mats[i].exponent = g_obj.materials[i].ns;
    }
    return make_scene(g_obj.material_count);
}

/* The box again with its floor made of `floor`. */
static int glossy_floor(const lightvec_material *floor)
{
    uint32_t i, fm = g_obj.material_count;
    int fg = obj_find_group(&g_obj, "floor");
    g_mats[fm] = *floor;
    for (i = 0; i < g_obj.tri_count; i++)
        if ((int)g_obj.face_group[g_obj.tri_face[i]] == fg) g_tri_mat[i] = fm;
    return make_scene(fm + 1);
}

static float lum(const float *c) { return 0.2126f * c[0] + 0.7152f * c[1] + 0.0722f * c[2]; }

static void trace_pixels(const ex_camera *cam, pixel *px, uint32_t flags)
{
    const char *walls[5] = { "floor", "ceiling", "back_wall", "left_wall", "right_wall" };
    int x, y, k, wall_group[5];
    for (k = 0; k < 5; k++) wall_group[k] = obj_find_group(&g_obj, walls[k]);
    for (y = 0; y < cam->height; y++)
        for (x = 0; x < cam->width; x++) {
            pixel *p = &px[y * cam->width + x];
            lightvec_hit h;
            float d[3], e1[3], e2[3], n[3], l;
            const float *a, *b, *c;
            uint32_t t, m, g;
            memset(p, 0, sizeof *p);
            ex_camera_ray(cam, (float)x + 0.5f, (float)y + 0.5f, d);
            if (!lightvec_scene_intersect(g_scene, cam->eye, d, 1e30f, &h)) continue;
            t = h.triangle;
            a = g_obj.positions + 3 * g_obj.tri_indices[3 * t];
            b = g_obj.positions + 3 * g_obj.tri_indices[3 * t + 1];
            c = g_obj.positions + 3 * g_obj.tri_indices[3 * t + 2];
            for (k = 0; k < 3; k++) { e1[k] = b[k] - a[k]; e2[k] = c[k] - a[k]; }
            n[0] = e1[1] * e2[2] - e1[2] * e2[1];
            n[1] = e1[2] * e2[0] - e1[0] * e2[2];
            n[2] = e1[0] * e2[1] - e1[1] * e2[0];
            l = sqrtf(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
            m = g_tri_mat[t];
            if (n[0] * d[0] + n[1] * d[1] + n[2] * d[2] >= 0 || lum(g_mats[m].emission) > 0) continue;
            for (k = 0; k < 3; k++) {
                p->s.position[k] = cam->eye[k] + h.t * d[k];
                p->s.normal[k] = n[k] / l;
                p->s.outgoing[k] = -d[k];
            }
            p->s.material = g_mats[m];
            p->s.flags = flags;
            g = g_obj.face_group[g_obj.tri_face[t]];
            for (k = 0; k < 5; k++) p->wall |= (int)g == wall_group[k];
            p->floor = (int)g == wall_group[0];
            p->valid = 1;
        }
}

/* Figure 2 over one frame in a random pixel order; returns the time. */
static double cache_frame(lightvec_cache *cache, const pixel *px, uint32_t n, float *rgb, uint32_t *hits,
                          uint32_t *visible, uint32_t *gathers, uint64_t seed)
{
    uint32_t *order = (uint32_t *)malloc(n * sizeof *order), i;
    rng r;
    lightvec_gather_desc gd;
    double t0;
    memset(&gd, 0, sizeof gd);
    r.s = seed;
    for (i = 0; i < n; i++) order[i] = i;
    for (i = n - 1; i > 0; i--) {
        uint32_t j = (uint32_t)(rnd(&r) * (i + 1)), t = order[i];
        order[i] = order[j];
        order[j] = t;
    }
    *hits = *visible = *gathers = 0;
    t0 = now();
    for (i = 0; i < n; i++) {
        const pixel *p = &px[order[i]];
        const float *wo = (p->s.flags & LIGHTVEC_RECORD_VIEW_INDEPENDENT) ? NULL : p->s.outgoing;
        lightvec_lookup_result lr;
        if (!p->valid) continue;
        (*visible)++;
        lightvec_lookup(cache, p->s.position, p->s.normal, wo, &lr);
        if (lr.hit) (*hits)++;
        else {
            lightvec_record rec;
            lightvec_gather(g_scene, &gd, &p->s, seed * 1000003u + order[i], &rec);
            lightvec_insert(cache, &rec, NULL);
            lr.vector = rec.vector;
            (*gathers)++;
        }
        lightvec_radiance(&p->s.material, p->s.normal, wo, &lr.vector, rgb + 3 * order[i]);
    }
    free(order);
    return now() - t0;
}

/* Median time of one gather over pixels spread across the frame, and the
   mean relative wall error of rgb against these gathers. */
static double gather_time(const pixel *px, uint32_t n, const float *rgb, double *wall_error)
{
    double t[2000], err = 0;
    uint32_t i, k, count = 0, walls = 0;
    lightvec_gather_desc gd;
    memset(&gd, 0, sizeof gd);
    gd.seed = 99;
    for (i = 0, k = 0; count < 2000 && i < 4 * n; i++, k = (k + 2654435761u) % n) {
        lightvec_record rec;
        const float *wo;
        float g[3];
        double t0;
        if (!px[k].valid) continue;
        wo = (px[k].s.flags & LIGHTVEC_RECORD_VIEW_INDEPENDENT) ? NULL : px[k].s.outgoing;
        t0 = now();
        lightvec_gather(g_scene, &gd, &px[k].s, k, &rec);
        t[count++] = now() - t0;
        lightvec_radiance(&px[k].s.material, px[k].s.normal, wo, &rec.vector, g);
        if (px[k].wall && lum(g) > 0) {
            err += fabs(lum(rgb + 3 * k) - lum(g)) / lum(g);
            walls++;
        }
    }
    *wall_error = walls ? err / walls : 0;
    return median(t, (int)count);
}

static uint64_t cache_records(lightvec_cache *cache)
{
    lightvec_cache_stats st;
    lightvec_cache_info(cache, &st);
    return st.record_count;
}

static void bench_frame_512(void)
{
    const int size = 512;
    uint32_t n = (uint32_t)(size * size), hits, visible, gathers;
    pixel *px = (pixel *)malloc(n * sizeof *px);
    float *rgb = (float *)calloc(3 * (size_t)n, sizeof(float));
    float eye[3] = { 0.278f, 0.273f, -0.8f }, target[3] = { 0.278f, 0.273f, 0.0f }, up[3] = { 0, 1, 0 };
    ex_camera cam = ex_camera_look_at(eye, target, up, 39.3f, size, size);
    lightvec_cache *cache = NULL;
    double t_cache, t_gather, err;
    if (!px || !rgb || lightvec_cache_create(NULL, &cache) != LIGHTVEC_OK) return;
    trace_pixels(&cam, px, 0);
    t_cache = cache_frame(cache, px, n, rgb, &hits, &visible, &gathers, 1);
    t_gather = gather_time(px, n, rgb, &err);
    {   /* lookups alone, in scan-line order: coherent queries, as in rendering */
        double t[5];
        uint32_t k, rep;
        for (rep = 0; rep < 5; rep++) {
            double t0 = now();
            for (k = 0; k < n; k++) {
                lightvec_lookup_result lr;
                if (px[k].valid) lightvec_lookup(cache, px[k].s.position, px[k].s.normal, px[k].s.outgoing, &lr);
            }
            t[rep] = (now() - t0) / visible;
        }
        printf("\nlookups over the finished 512x512 Cornell frame (%llu records, scan-line order): %.3f us each\n",
               (unsigned long long)cache_records(cache), 1e6 * median(t, 5));
    }
    printf("one 512x512 Cornell frame of indirect light, cold cache, one thread (target: 10x faster, error < 5%%)\n");
    printf("  gather: %.3f ms per light vector (default 20 x 60 strata, 2 bounces)\n", 1e3 * t_gather);
    printf("  cache: %.2f s, hit rate %.2f%% (%u gathers)\n", t_cache, 100.0 * hits / visible, gathers);
    printf("  gathering at every pixel: %.1f s (%u x median gather); cache %.1fx faster\n", t_gather * visible,
           visible, t_gather * visible / t_cache);
    printf("  wall error vs. gathering: %.2f%%\n", 100 * err);
    lightvec_cache_destroy(cache);
    free(px);
    free(rgb);
}

/* Mean relative error of the floor pixels of rgb against a converged
   gather (60 x 180 strata, 8,192 lobe rays; within about 1.3% itself), over
   `count` pixels spread across the frame. */
static double floor_error(const pixel *px, uint32_t n, const float *rgb, uint32_t count)
{
    lightvec_gather_desc gd;
    uint32_t i, k, m = 0;
    double err = 0;
    memset(&gd, 0, sizeof gd);
    gd.strata_theta = 60;
    gd.glossy_samples = 8192;
    gd.seed = 77;
    for (i = 0, k = 0; m < count && i < 8 * n; i++, k = (k + 2654435761u) % n) {
        lightvec_record rec;
        float g[3];
        if (!px[k].valid || !px[k].floor) continue;
        lightvec_gather(g_scene, &gd, &px[k].s, k, &rec);
        lightvec_radiance(&px[k].s.material, px[k].s.normal, px[k].s.outgoing, &rec.vector, g);
        err += fabs(lum(rgb + 3 * k) - lum(g)) / lum(g);
        m++;
    }
    return m ? err / m : 0;
}

/* 30 frames: the eye slides across the whole opening of the box (55 cm, at
   70 cm from it) while looking at its centre, so that a wall point is seen
   from directions up to 30 degrees apart over the path. With floor_report
   (the box's floor made glossy first): how much of the floor the cache
   covers after each frame, and the floor's error in the last frame. */
static void bench_path(uint32_t flags, int size, int floor_report)
{
    uint32_t n = (uint32_t)(size * size), hits, visible, gathers, total_hits = 0, total_visible = 0, k;
    pixel *px = (pixel *)malloc(n * sizeof *px);
    float *rgb = (float *)calloc(3 * (size_t)n, sizeof(float));
    float up[3] = { 0, 1, 0 }, target[3] = { 0.278f, 0.25f, 0.28f };
    lightvec_cache *cache = NULL;
    double t_gather = 0, err, t_frames = 0, t_later = 0, t_first = 0, rates[30], floor_rates[30];
    int f;
    if (!px || !rgb || lightvec_cache_create(NULL, &cache) != LIGHTVEC_OK) return;
    printf("\n30-frame camera path, %dx%d, %s light vectors%s\n", size, size, flags ? "3D (view-independent)" : "5D",
           floor_report ? ", a glossy floor (0.3 Lambert + 0.4 Phong, exponent 20)" : "");
    for (f = 0; f < 30; f++) {
        float eye[3];
        ex_camera cam;
        double t;
        uint32_t floor_hits = 0, floor_px = 0;
        eye[0] = 0.0f + 0.556f * (float)f / 29.0f;
        eye[1] = 0.273f;
        eye[2] = -0.7f;
        cam = ex_camera_look_at(eye, target, up, 39.3f, size, size);
        trace_pixels(&cam, px, flags);
        t = cache_frame(cache, px, n, rgb, &hits, &visible, &gathers, 10 + (uint64_t)f);
        if (f == 0) t_gather = gather_time(px, n, rgb, &err) * visible;
        rates[f] = 100.0 * hits / visible;
        total_hits += hits;
        total_visible += visible;
        t_frames += t;
        if (f == 0) t_first = t;
        else t_later += t;
        for (k = 0; floor_report && k < n; k++) /* how much of the floor the cache covers once the frame is done */
            if (px[k].valid && px[k].floor) {
                lightvec_lookup_result lr;
                floor_px++;
                lightvec_lookup(cache, px[k].s.position, px[k].s.normal, px[k].s.outgoing, &lr);
                floor_hits += (uint32_t)lr.hit;
            }
        floor_rates[f] = floor_px ? 100.0 * floor_hits / floor_px : 0.0;
        if (f == 0 || f == 1 || f == 29) printf("  frame %2d: hit rate %6.2f%%, %5u gathers, %.2f s\n", f, rates[f], gathers, t);
    }
    printf("  mean hit rate %.2f%% (frames 1-29: median %.2f%%)\n", 100.0 * total_hits / total_visible,
           median(rates + 1, 29));
    printf("  frame time: first %.2f s, later ones %.2f s on average; gathering everywhere %.1f s per frame (%.1fx)\n",
           t_first, t_later / 29, t_gather, t_gather / (t_later / 29));
    printf("  time saved vs. gathering everywhere: %.1f%% over the path, %.1f%% on frames 1-29 "
           "(paper: 66%% vs. the render cache alone)\n",
           100.0 * (1.0 - t_frames / (30 * t_gather)), 100.0 * (1.0 - t_later / (29 * t_gather)));
    if (floor_report) {
        printf("  floor pixels the cache covers after each frame: median %.2f%%\n", median(floor_rates + 1, 29));
        printf("  floor error in the last frame: %.2f%% mean against a converged gather (issue 15: <= 5%%)\n",
               100 * floor_error(px, n, rgb, 200));
        printf("  (paper, table 1, Cornell box 1: next pictures 46 s ray traced, 13 s with the render cache, 4.4 s\n"
               "   with 5D light vectors and the render cache; Lambertian boxes, 512x512, 1.2 GHz Athlon)\n");
    }
    lightvec_cache_destroy(cache);
    free(px);
    free(rgb);
}

int main(int argc, char **argv)
{
    if (argc < 2 || strcmp(argv[1], "--glossy")) bench_lookups();
    if (argc > 1 && !strcmp(argv[1], "--lookups")) return 0;
    if (load_cornell() != 0) return 1;
    if (argc > 1 && !strcmp(argv[1], "--glossy")) goto glossy;
    bench_frame_512();
    bench_path(0, 256, 0);
    bench_path(LIGHTVEC_RECORD_VIEW_INDEPENDENT, 256, 0);
glossy:
    {
        lightvec_material floor;
        memset(&floor, 0, sizeof floor);
        floor.diffuse[0] = floor.diffuse[1] = floor.diffuse[2] = 0.3f;
        floor.specular[0] = floor.specular[1] = floor.specular[2] = 0.4f;
        floor.exponent = 20.0f;
        if (glossy_floor(&floor) != 0) return 1;
        bench_path(0, 256, 1);
    }
    lightvec_scene_destroy(g_scene);
    free(g_mats);
    free(g_tri_mat);
    obj_free(&g_obj);
    return 0;
}
