/* Benchmark of rendercache.h.

   1. The per-frame overhead of the render cache (ageing + projection +
   binning, z-buffer, depth cull, interpolation, priority image, request
   selection, insertion) on a camera path through the Cornell box, at
   512x512 and 1920x1080, on 1 and 2 threads, with the 8%-of-the-pixels sample
   budget of Crespin and Peroche, and the memory it holds per pixel.
   Samples come from the examples' ray tracer; their shading time is not
   part of the cache overhead but is measured once to compare a cache frame
   with a full re-render.

   2. Range-image walkthroughs (Nimeroff et al. 1996): a 640x480 frame warped
   from 2 and 4 fish-eye base images of the office (1024x1024, 180 degrees),
   without fill and with both fills, on 1 and 2 threads, along a camera path
   between the base views; a time blend of two base images (pixelwise and
   motion-compensated); the fitness of id images.

   3. Tables 1-4 of Nimeroff et al. beside ours: indirect light on grids
   of the office simplified at three qualities against a fine solution
   (table 1); the indirect light of the Cornell box with a sliding cube at
   key times for q = 0.3, 0.6, 0.9, interpolated (table 2); base views of
   the office and the frame warped from them (table 3); key times of the
   sliding cube and frame 10 of 12 blended from them, pixelwise and
   motion-compensated (table 4).

   Medians over the frames of the paths. */
#if defined(__linux__) && !defined(_DEFAULT_SOURCE)
#  define _DEFAULT_SOURCE 1   /* madvise(MADV_HUGEPAGE) for the huge-page allocator */
#endif
#include "examples/common/baseviews.h"
#include "examples/common/pool.h"
#include "examples/common/trace.h"
#define RENDERCACHE_IMPLEMENTATION
#include "rendercache.h"

#include <stdio.h>
#include <time.h>
#if defined(__linux__)
#  include <sys/mman.h>
#endif

#define FRAMES 48
#define BUDGET 0.08

/* Wall time, or with a non-NULL user the calling thread's CPU time: the
   machine is shared, and a single-threaded run measured in CPU time does
   not count the moments another process held the core. */
static double now_seconds(void *user)
{
    struct timespec ts;
    clock_gettime(user ? CLOCK_THREAD_CPUTIME_ID : CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static int g_cpu_clock = 1;

/* CPU time of the whole process, every thread's. */
static double process_cpu_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* "load 1.23 0.98 0.77" from /proc/loadavg, or "load ?": the machine is
   shared, and wall times (2 threads) mean little without it. */
static const char *load_average(void)
{
    static char text[64];
    double a = 0, b = 0, c = 0;
    FILE *f = fopen("/proc/loadavg", "r");
    if (f && fscanf(f, "%lf %lf %lf", &a, &b, &c) == 3) snprintf(text, sizeof text, "load %.2f %.2f %.2f", a, b, c);
    else snprintf(text, sizeof text, "load ?");
    if (f) fclose(f);
    return text;
}

/* An allocator that counts the bytes live (for the memory per pixel).
   With huge set, blocks of 2 MB or more are aligned to 2 MB and asked to
   be backed by huge pages (Linux transparent huge pages, madvise mode):
   the cache's reads and writes at random over tens of megabytes then miss
   the TLB far less. */
typedef struct counted { size_t live, peak; int huge; } counted;
#define HUGE_PAGE ((size_t)2 << 20)
static void *counted_alloc(size_t size, void *user)
{
    counted *c = (counted *)user;
    size_t *p = NULL;
#if defined(__linux__) && defined(MADV_HUGEPAGE)
    if (c->huge && size >= HUGE_PAGE) {
        void *block = NULL;
        size_t total = (size + HUGE_PAGE + HUGE_PAGE - 1) / HUGE_PAGE * HUGE_PAGE;
        if (posix_memalign(&block, HUGE_PAGE, total) != 0) return NULL;
        madvise(block, total, MADV_HUGEPAGE);
        p = (size_t *)((char *)block + HUGE_PAGE - sizeof(size_t) * 2);   /* the data starts on a huge page */
        p[0] = size;
        p[1] = HUGE_PAGE;   /* offset back to the block */
        c->live += size;
        if (c->live > c->peak) c->peak = c->live;
        return p + 2;
    }
#endif
    p = (size_t *)malloc(size + sizeof(size_t) * 2);
    if (!p) return NULL;
    p[1] = 0;
    p[0] = size;
    c->live += size;
    if (c->live > c->peak) c->peak = c->live;
    return p + 2;
}
static void counted_free(void *ptr, void *user)
{
    counted *c = (counted *)user;
    size_t *p = (size_t *)ptr;
    if (!p) return;
    c->live -= p[-2];
    if (p[-1]) free((char *)(p - 2) - (p[-1] - sizeof(size_t) * 2));
    else free(p - 2);
}

static int compare_doubles(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

static double median(double *v, int n)
{
    qsort(v, (size_t)n, sizeof *v, compare_doubles);
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

/* A slow orbit and dolly inside the box, looking at its middle. */
static rendercache_camera path_camera(int frame, uint32_t w, uint32_t h)
{
    rendercache_camera c;
    float t = (float)frame / (float)FRAMES;
    memset(&c, 0, sizeof c);
    c.eye[0] = 0.278f + 0.12f * sinf(2.0f * t);
    c.eye[1] = 0.273f + 0.05f * sinf(3.0f * t);
    c.eye[2] = -0.8f + 0.35f * t;
    c.look_at[0] = 0.278f - 0.05f * t;
    c.look_at[1] = 0.25f;
    c.look_at[2] = 0.28f;
    c.up[1] = 1.0f;
    c.vfov_degrees = 39.3f;
    c.width = w;
    c.height = h;
    return c;
}

typedef struct shade_job {
    const ex_tracer *tracer;
    const rendercache_pixel_request *req;
    rendercache_sample *out;
    uint32_t count, frame;
    int bounces;
} shade_job;

static void shade_one(void *ctx, uint32_t index)
{
    const shade_job *j = (const shade_job *)ctx;
    uint32_t i, begin = index * 256, end = begin + 256;
    if (end > j->count) end = j->count;
    for (i = begin; i < end; i++) {
        const rendercache_pixel_request *r = &j->req[i];
        rendercache_sample *s = &j->out[i];
        ex_rng rng = ex_rng_stream(j->frame, (uint64_t)r->y * 65536u + r->x);
        ex_trace_hit hit;
        memset(s, 0, sizeof *s);
        s->x = r->x;
        s->y = r->y;
        s->flags = r->flags;
        s->frame = r->frame;
        if (!ex_tracer_shade(j->tracer, r->org, r->dir, j->bounces, &rng, s->rgb, &hit)) {
            s->object = RENDERCACHE_MISS;
        } else {
            s->object = 0;
            memcpy(s->position, hit.pos, sizeof s->position);
        }
    }
}

static void shade_all(ex_pool *pool, const ex_tracer *t, const rendercache_pixel_request *req,
                      rendercache_sample *out, uint32_t n, uint32_t frame, int bounces)
{
    shade_job j;
    j.tracer = t;
    j.req = req;
    j.out = out;
    j.count = n;
    j.frame = frame;
    j.bounces = bounces;
    ex_pool_parallel_for(pool, shade_one, &j, (n + 255) / 256);
}

/* FNV-1a hash of n bytes. */
static uint64_t fnv1a(const void *bytes, size_t n)
{
    const unsigned char *b = (const unsigned char *)bytes;
    uint64_t h = 0xcbf29ce484222325ull;
    size_t i;
    for (i = 0; i < n; i++) h = (h ^ b[i]) * 0x100000001b3ull;
    return h;
}

/* Hash of the requests' fields (the struct has padding). */
static uint64_t requests_hash(const rendercache_pixel_request *req, uint32_t n)
{
    uint64_t h = 0;
    uint32_t i;
    for (i = 0; i < n; i++) {
        const rendercache_pixel_request *r = &req[i];
        uint64_t f[2];
        f[0] = r->frame;
        f[1] = (uint64_t)r->x << 32 | r->y;
        h = h * 31 + fnv1a(f, sizeof f) + fnv1a(&r->flags, sizeof r->flags) + fnv1a(r->org, sizeof r->org) +
            fnv1a(r->dir, sizeof r->dir);
    }
    return h;
}

/* Hash of n 32-bit words, a word at a time (the cache holds hundreds of megabytes). */
static uint64_t words_hash(const void *words, size_t n)
{
    const uint32_t *w = (const uint32_t *)words;
    uint64_t h = 0xcbf29ce484222325ull;
    size_t i;
    for (i = 0; i < n; i++) h = (h ^ w[i]) * 0x100000001b3ull;
    return h;
}

/* Hash of the cache's contents (its slots' positions, objects and records, the clock's hand, the live
   count): the frames of two versions may match while their caches differ, which later frames would show. */
static uint64_t cache_hash(const rendercache *rc)
{
    uint64_t h = words_hash(rc->geo.x, rc->capacity);
    h = h * 31 + words_hash(rc->geo.y, rc->capacity);
    h = h * 31 + words_hash(rc->geo.z, rc->capacity);
    h = h * 31 + words_hash(rc->geo.object, rc->capacity);
    h = h * 31 + words_hash(rc->data, (size_t)rc->capacity * sizeof rc->data[0] / sizeof(uint32_t));
    return h * 31 + ((uint64_t)rc->hand << 32 | rc->live);
}

enum { P_PROJECT, P_CULL, P_SORT, P_PREDICT, P_REQUEST, P_INSERT, P_TOTAL, P_COUNT };

static void run(const ex_tracer *tracer, ex_pool *shade_pool, uint32_t w, uint32_t h, int threads,
                double *frame_ms, double *sample_us, double *bytes_per_pixel, int huge)
{
    /* priority is computed inside the cull (pixels with a point) and the hole filling, which run
       interleaved, timed together (stats.time_cull) */
    static const char *names[P_COUNT] = { "project+z-buffer(+predict)", "cull+interp", "sort", "predict", "request",
                                          "insert", "total" };
    double times[P_COUNT][FRAMES], cpu[FRAMES], wall[FRAMES];
    rendercache_desc d;
    rendercache *rc;
    rendercache_pixel_request *req = (rendercache_pixel_request *)malloc(sizeof *req * w * h);
    rendercache_sample *samples = (rendercache_sample *)malloc(sizeof *samples * w * h);
    ex_pool *pool = threads > 1 ? ex_pool_create(threads) : NULL;
    uint32_t n = 0, budget = (uint32_t)(BUDGET * w * h + 0.5);
    double shade_time = 0.0;
    uint64_t shaded = 0;
    counted memory = { 0, 0, 0 };
    int f, k;
    memset(&d, 0, sizeof d);
    d.allocator.alloc = counted_alloc;
    d.allocator.free = counted_free;
    d.allocator.user = &memory;
    if (getenv("BENCH_NOCHANGE")) d.change_threshold = FLT_MAX;
    memory.huge = huge;
    d.width = w;
    d.height = h;
    d.clock = now_seconds;
    d.clock_user = threads == 1 ? (void *)&g_cpu_clock : NULL;
    d.parallel_for = pool ? ex_pool_parallel_for : NULL;
    d.parallel_user = pool;
    if (!req || !samples || rendercache_create(&d, &rc) != RENDERCACHE_OK) {
        printf("out of memory\n");
        exit(1);
    }
    /* the first frame is rendered in full, as in the paper */
    {
        rendercache_camera c = path_camera(0, w, h);
        rendercache_begin_frame(rc, &c);
        rendercache_request(rc, req, w * h, &n);
        shade_all(shade_pool, tracer, req, samples, n, 0, 1);   /* the shading of every later sample */
        rendercache_insert(rc, samples, n, NULL);
    }
    for (f = 0; f < FRAMES; f++) {
        rendercache_camera c = path_camera(f + 1, w, h), next = path_camera(f + 2, w, h);
        rendercache_stats st;
        double t0, c0;
        c0 = process_cpu_seconds();
        t0 = now_seconds(NULL);
        /* WDG02: the holes of the next camera, from a quarter of the budget; counted in the projection's
           pass over the points (its time is part of project+z-buffer) */
        rendercache_begin_frame_predicted(rc, &c, &next);
        rendercache_request(rc, req, budget, &n);
        cpu[f] = process_cpu_seconds() - c0;
        wall[f] = now_seconds(NULL) - t0;
        t0 = now_seconds(NULL);
        shade_all(shade_pool, tracer, req, samples, n, (uint32_t)f + 1, 1);   /* direct + one bounce */
        shade_time += now_seconds(NULL) - t0;
        shaded += n;
        c0 = process_cpu_seconds();
        t0 = now_seconds(NULL);
        rendercache_insert(rc, samples, n, NULL);
        cpu[f] += process_cpu_seconds() - c0;
        wall[f] += now_seconds(NULL) - t0;
        rendercache_get_stats(rc, &st);
        times[P_PROJECT][f] = st.time_project;
        times[P_CULL][f] = st.time_cull;
        times[P_PREDICT][f] = st.time_predict;
        times[P_REQUEST][f] = st.time_request;
        times[P_INSERT][f] = st.time_insert;
        times[P_SORT][f] = st.time_sort;
        if (getenv("BENCH_DEBUG")) printf("frame %d: inserted %u replaced %u changed %u\n", f, st.inserted, st.replaced, st.changed);
        if (getenv("BENCH_HASH"))   /* to compare two versions' frames, requests and caches bit for bit */
            printf("frame %d: image %016llx requests %016llx cache %016llx\n", f,
                   (unsigned long long)fnv1a(rendercache_image(rc), sizeof(float) * 3 * w * h),
                   (unsigned long long)requests_hash(req, n), (unsigned long long)cache_hash(rc));
        times[P_TOTAL][f] = st.time_project + st.time_cull + st.time_sort + st.time_predict +
                            st.time_request + st.time_insert;
    }
    *bytes_per_pixel = (double)memory.peak / ((double)w * h);
    printf("%4ux%-4u %d thread%s (%s%s):", w, h, threads, threads > 1 ? "s" : " ", threads > 1 ? "wall" : "cpu ",
           huge ? ", huge pages" : "");
    for (k = 0; k < P_COUNT; k++) {
        double m = median(times[k], FRAMES) * 1e3;
        printf(" %s %.2f%s", names[k], m, k + 1 < P_COUNT ? "," : " ms (medians)\n");
        if (k == P_TOTAL) *frame_ms = m;
    }
    /* the same frames in wall time (which counts the moments other processes held the cores) and in cpu time
       summed over the threads (the work done, whoever waited) */
    printf("%9s %d thread%s: the same frames %.2f ms wall, %.2f ms cpu summed over the threads (medians; %s)\n", "",
           threads, threads > 1 ? "s" : " ", median(wall, FRAMES) * 1e3, median(cpu, FRAMES) * 1e3, load_average());
    *sample_us = shaded ? shade_time / (double)shaded * 1e6 : 0.0;
    rendercache_destroy(rc);
    ex_pool_destroy(pool);
    free(req);
    free(samples);
}

/* ---------------------------------------------------------------------
   Range-image walkthroughs
   --------------------------------------------------------------------- */
#define BASE_SIZE 1024
#define WARP_FRAMES 16

typedef struct base_job {
    const ex_tracer *tracer;
    const obj_scene *scene;
    rendercache_range_image *img;
} base_job;

/* Rows [8 i, 8 i + 8) of a base image: first hit, object = OBJ group (or
   instance), colour = diffuse reflectance lit by the view direction. */
static void base_rows(void *ctx, uint32_t index)
{
    const base_job *j = (const base_job *)ctx;
    rendercache_range_image *img = j->img;
    uint32_t w = img->camera.width, y, x;
    for (y = index * 8; y < index * 8 + 8 && y < img->camera.height; y++)
        for (x = 0; x < w; x++) {
            size_t p = (size_t)y * w + x;
            float o[3], d[3];
            ex_trace_hit hit;
            img->object[p] = RENDERCACHE_NO_SAMPLE;
            if (rendercache_camera_ray(&img->camera, (float)x + 0.5f, (float)y + 0.5f, o, d) != RENDERCACHE_OK) continue;
            if (!ex_tracer_intersect(j->tracer, o, d, FLT_MAX, &hit)) {
                img->object[p] = RENDERCACHE_MISS;
                continue;
            } else {
                const float *kd = j->scene->materials[j->scene->tri_material[hit.tri]].kd;
                float c = 0.3f + 0.7f * fabsf(hit.normal[0] * d[0] + hit.normal[1] * d[1] + hit.normal[2] * d[2]);
                int k;
                for (k = 0; k < 3; k++) img->rgb[3 * p + k] = kd[k] * c;
                img->depth[p] = hit.t;
                img->object[p] = j->scene->face_group[j->scene->tri_face[hit.tri]];
            }
        }
}

static rendercache_camera office_camera(rendercache_camera_kind kind, float x, float z, float yaw, uint32_t w,
                                        uint32_t h)
{
    rendercache_camera c;
    memset(&c, 0, sizeof c);
    c.kind = kind;
    c.eye[0] = x; c.eye[1] = 1.4f; c.eye[2] = z;
    c.look_at[0] = x + sinf(yaw); c.look_at[1] = 1.3f; c.look_at[2] = z + cosf(yaw);
    c.up[1] = 1.0f;
    c.vfov_degrees = 60.0f;
    c.width = w;
    c.height = h;
    return c;
}

/* The two-thread column of a warp line; a quick run (one part of the bench
   asked for by name) times one thread only. */
static const char *two_thread_column(double ms, int quick)
{
    static char text[48];
    if (quick) return ", 2 threads not run (quick run)";
    snprintf(text, sizeof text, ", %6.2f ms on 2 (wall)", ms);
    return text;
}

static void warp_run(rendercache_range_image *const *bases, uint32_t n, rendercache_fill fill, int threads, int average,
                     double *median_ms)
{
    double times[WARP_FRAMES];
    rendercache_warp_desc d;
    rendercache_warper *w = NULL;
    rendercache_range_image *out = NULL;
    rendercache_camera cam = office_camera(RENDERCACHE_CAMERA_PERSPECTIVE, 2.0f, 1.0f, 0.0f, 640, 480);
    ex_pool *pool = threads > 1 ? ex_pool_create(threads) : NULL;
    int f;
    memset(&d, 0, sizeof d);
    d.parallel_for = pool ? ex_pool_parallel_for : NULL;
    d.parallel_user = pool;
    d.clock = now_seconds;
    d.clock_user = threads == 1 ? (void *)&g_cpu_clock : NULL;
    d.average = average;
    if (rendercache_warper_create(&d, &w) != RENDERCACHE_OK || rendercache_range_image_create(&cam, NULL, &out) != RENDERCACHE_OK) {
        printf("out of memory\n");
        exit(1);
    }
    for (f = 0; f < WARP_FRAMES; f++) {   /* between the base views, turning */
        rendercache_warp_stats st;
        float t = (float)f / (WARP_FRAMES - 1);
        cam = office_camera(RENDERCACHE_CAMERA_PERSPECTIVE, 1.6f + 0.8f * t, 0.8f + 0.4f * t, -0.4f + 0.8f * t, 640, 480);
        rendercache_warp(w, (const rendercache_range_image *const *)bases, n, &cam, fill, out);
        rendercache_warp_get_stats(w, &st);
        times[f] = st.time_total;
    }
    *median_ms = median(times, WARP_FRAMES) * 1e3;
    rendercache_range_image_destroy(out);
    rendercache_warper_destroy(w);
    ex_pool_destroy(pool);
}

/* Bytes allocated through the base images' allocator (what prepare takes). */
static size_t g_base_bytes;
static void *counting_alloc(size_t size, void *user)
{
    (void)user;
    g_base_bytes += size;
    return malloc(size);
}
static void counting_free(void *p, void *user)
{
    (void)user;
    free(p);
}

/* The prepared warp beside the unprepared one, the same warps alternating
   in this process (pairs of 16-frame runs; the medians of the runs' medians
   and of the pairwise ratios). */
static double warp_prepared_line(rendercache_range_image *const *bases, uint32_t n, int average, const char *what)
{
    double plain[5], prepared[5], ratio[5];
    int r, i;
    for (r = 0; r < 5; r++) {
        for (i = 0; i < (int)n; i++) rendercache_range_image_unprepare(bases[i]);
        warp_run(bases, n, RENDERCACHE_FILL_BOTH, 1, average, &plain[r]);
        for (i = 0; i < (int)n; i++) rendercache_range_image_prepare(bases[i]);
        warp_run(bases, n, RENDERCACHE_FILL_BOTH, 1, average, &prepared[r]);
        ratio[r] = prepared[r] / plain[r];
    }
    printf("  warp from %u bases, both fills%s, prepared: %6.2f ms on 1 thread (cpu), unprepared %6.2f ms "
           "(alternating, ratio %.3f)\n", n, what, median(prepared, 5), median(plain, 5), median(ratio, 5));
    return median(prepared, 5);
}

static void bench_walkthrough(ex_pool *shade_pool, int quick)
{
    static const float corners[4][2] = { { 1.5f, 0.5f }, { 2.5f, 0.5f }, { 1.5f, 1.5f }, { 2.5f, 1.5f } };
    obj_scene scene;
    ex_tracer *tracer;
    rendercache_range_image *bases[4];
    const uint32_t *ids[4];
    char err[256];
    double ms[2][4][2], blend_times[8], motion_times[8], fit_times[8], prepared_ms;
    uint32_t i, k;
    int counts[2] = { 2, 4 }, c, fi, threads;
    rendercache_allocator counting;
    static const rendercache_fill fills[4] = { RENDERCACHE_FILL_NONE, RENDERCACHE_FILL_FOREGROUND,
                                               RENDERCACHE_FILL_BACKGROUND, RENDERCACHE_FILL_BOTH };
    static const char *fill_names[4] = { "no fill", "foreground", "background", "both fills" };
    if (obj_load("examples/data/office.obj", &scene, err, sizeof err) != 0) {
        printf("cannot load the office: %s\n", err);
        return;
    }
    tracer = ex_tracer_create(&scene);
    if (!tracer) return;
    memset(&counting, 0, sizeof counting);
    counting.alloc = counting_alloc;
    counting.free = counting_free;
    for (i = 0; i < 4; i++) {   /* fish-eyes at the corners of a 1 m square, looking at the desk */
        rendercache_camera cam = office_camera(RENDERCACHE_CAMERA_FISHEYE, corners[i][0], corners[i][1], 0.0f, BASE_SIZE, BASE_SIZE);
        base_job j;
        bases[i] = NULL;
        if (rendercache_range_image_create(&cam, &counting, &bases[i]) != RENDERCACHE_OK) exit(1);
        j.tracer = tracer;
        j.scene = &scene;
        j.img = bases[i];
        ex_pool_parallel_for(shade_pool, base_rows, &j, (BASE_SIZE + 7) / 8);
        bases[i]->time = 0.0;
    }
    printf("\nrange-image walkthrough, office, %d fish-eye base images of %dx%d, 640x480 frames (medians of %d):\n",
           4, BASE_SIZE, BASE_SIZE, WARP_FRAMES);
    for (c = 0; c < 2; c++)
        for (fi = 0; fi < 4; fi++)
            for (threads = 1; threads <= 2; threads++) {
                ms[c][fi][threads - 1] = 0.0;
                if (quick && threads > 1) continue;
                warp_run(bases, (uint32_t)counts[c], fills[fi], threads, 0, &ms[c][fi][threads - 1]);
            }
    for (c = 0; c < 2; c++)
        for (fi = 0; fi < 4; fi++)
            printf("  warp from %d bases, %-10s: %6.2f ms on 1 thread (cpu)%s\n", counts[c], fill_names[fi], ms[c][fi][0],
                   two_thread_column(ms[c][fi][1], quick));
    {   /* averaging the inputs (pinterp -a), as the walkthrough's baseviews mode does */
        double avg[2] = { 0.0, 0.0 };
        for (threads = 1; threads <= (quick ? 1 : 2); threads++) warp_run(bases, 4, RENDERCACHE_FILL_BOTH, threads, 1, &avg[threads - 1]);
        printf("  warp from 4 bases, both fills, averaged: %6.2f ms on 1 thread (cpu)%s\n", avg[0], two_thread_column(avg[1], quick));
    }
    {   /* prepared bases (rendercache_range_image_prepare): their cost once, then the warps */
        double prep[8], t0;
        size_t bytes0 = g_base_bytes;
        for (k = 0; k < 8; k++) {
            t0 = now_seconds(&g_cpu_clock);
            if (rendercache_range_image_prepare(bases[k % 4]) != RENDERCACHE_OK) exit(1);
            prep[k] = now_seconds(&g_cpu_clock) - t0;
        }
        printf("  prepare a base (tile depth bounds): %.2f ms on 1 thread (cpu), %.1f KB per %dx%d base\n",
               median(prep, 8) * 1e3, (double)(g_base_bytes - bytes0) / 8.0 / 1024.0, BASE_SIZE, BASE_SIZE);
        prepared_ms = warp_prepared_line(bases, 4, 0, "");
        warp_prepared_line(bases, 2, 0, "");
        warp_prepared_line(bases, 4, 1, ", averaged");
        for (i = 0; i < 4; i++) rendercache_range_image_unprepare(bases[i]);
    }
    {   /* time interpolation of two images of one base view (the second a copy: a static scene), and fitness */
        rendercache_range_image *out = NULL, *later = NULL;
        rendercache_warp_desc d;
        rendercache_warper *w = NULL;
        size_t n = (size_t)BASE_SIZE * BASE_SIZE;
        memset(&d, 0, sizeof d);
        if (rendercache_range_image_create(&bases[0]->camera, NULL, &out) != RENDERCACHE_OK ||
            rendercache_range_image_create(&bases[0]->camera, NULL, &later) != RENDERCACHE_OK ||
            rendercache_warper_create(&d, &w) != RENDERCACHE_OK)
            exit(1);
        memcpy(later->rgb, bases[0]->rgb, 3 * n * sizeof(float));
        memcpy(later->depth, bases[0]->depth, n * sizeof(float));
        memcpy(later->object, bases[0]->object, n * sizeof(uint32_t));
        later->time = 1.0;
        for (k = 0; k < 8; k++) {
            double t0 = now_seconds(&g_cpu_clock);
            float f;
            rendercache_blend(bases[0], later, 0.3f, out);
            blend_times[k] = now_seconds(&g_cpu_clock) - t0;
            t0 = now_seconds(&g_cpu_clock);
            rendercache_blend_motion(w, bases[0], later, 0.3f, NULL, RENDERCACHE_FILL_BOTH, out);
            motion_times[k] = now_seconds(&g_cpu_clock) - t0;
            for (i = 0; i < 4; i++) ids[i] = bases[i]->object;
            t0 = now_seconds(&g_cpu_clock);
            rendercache_fitness(ids, 4, BASE_SIZE, BASE_SIZE, &f);
            fit_times[k] = (now_seconds(&g_cpu_clock) - t0) / 4.0;
            if (k == 0) printf("  fitness of the 4 base views' id images: %.3f\n", f);
        }
        printf("  time blend of two %dx%d images of one view: pixelwise %.2f ms, motion-compensated (2 warps) %.2f ms; "
               "fitness %.3f ms per %dx%d id image (1 thread, cpu)\n", BASE_SIZE, BASE_SIZE,
               median(blend_times, 8) * 1e3, median(motion_times, 8) * 1e3, median(fit_times, 8) * 1e3, BASE_SIZE,
               BASE_SIZE);
        rendercache_range_image_destroy(out);
        rendercache_range_image_destroy(later);
        rendercache_warper_destroy(w);
    }
    printf("paper (Nimeroff et al. 1996, table 3): pinterp synthesis 0.046-0.061 min = 2.8-3.7 s per frame\n");
    printf("ours, 640x480 from 4 bases on 1 thread (target < 20 ms): %.2f ms with background fill, %.2f ms with "
           "both fills (%.0fx faster than pinterp's 3 s), %.2f ms with both fills from prepared bases\n", ms[1][2][0],
           ms[1][3][0], 3000.0 / ms[1][3][0], prepared_ms);
    for (i = 0; i < 4; i++) rendercache_range_image_destroy(bases[i]);
    ex_tracer_destroy(tracer);
    obj_free(&scene);
}


/* ---------------------------------------------------------------------
   Tables 1-4 of Nimeroff, Dorsey and Rushmeier 1996
   --------------------------------------------------------------------- */
#define NIM_SAMPLES 8            /* direct light samples per pixel, the same streams in every image compared */

typedef struct nim_view {
    const ex_tracer *tracer;
    const ex_indirect *ind;      /* NULL: no indirect light */
    const float *irradiance;
    const rendercache_camera *camera;
    float *rgb;
    uint32_t *ids;               /* when set: the id image instead (one id per face) */
    uint32_t instance_faces;     /* ids of instance 0's faces start here */
    uint32_t gather_rays;        /* > 0: the indirect light gathered at every pixel instead (reference) */
} nim_view;

/* One bounce of irradiance at a hit, gathered with rays cosine rays (the
   estimator of ex_indirect's nodes, at the pixel itself). */
static void nim_gather(const ex_tracer *t, const ex_trace_hit *h, uint32_t rays, ex_rng *rng, float e[3])
{
    float org[3];
    tr__vec3 tn = tr__v3_load(h->normal), tb, bb;
    uint32_t r;
    int k;
    tr__basis(tn, &tb, &bb);
    for (k = 0; k < 3; k++) { org[k] = h->pos[k] + 1e-3f * h->normal[k]; e[k] = 0.0f; }
    for (r = 0; r < rays; r++) {
        tr__vec3 s = ex__sample_cosine(rng);
        float d[3], l[3];
        ex_trace_hit g;
        s = tr__add(tr__add(tr__scale(tb, s.x), tr__scale(bb, s.y)), tr__scale(tn, s.z));
        d[0] = s.x; d[1] = s.y; d[2] = s.z;
        if (!ex_tracer_intersect(t, org, d, FLT_MAX, &g) || !g.front) continue;
        ex__tracer_direct(t, &g, d, rng, l);
        for (k = 0; k < 3; k++) e[k] += l[k];
    }
    for (k = 0; k < 3; k++) e[k] *= 3.14159265f / (float)rays;
}

/* Rows of an image: emission, direct light (NIM_SAMPLES point samples, the
   pixel's own stream) and the grid's indirect light through a Lambertian BRDF. */
static void nim_rows(void *ctx, uint32_t y)
{
    const nim_view *v = (const nim_view *)ctx;
    const rendercache_camera *c = v->camera;
    uint32_t x, i;
    for (x = 0; x < c->width; x++) {
        size_t p = (size_t)y * c->width + x;
        float o[3], d[3], *rgb = v->rgb ? v->rgb + 3 * p : NULL;
        ex_trace_hit h;
        int k;
        if (rgb) rgb[0] = rgb[1] = rgb[2] = 0.0f;
        if (rendercache_camera_ray(c, (float)x + 0.5f, (float)y + 0.5f, o, d) != RENDERCACHE_OK) {
            if (v->ids) v->ids[p] = RENDERCACHE_NO_SAMPLE;
            continue;
        }
        if (!ex_tracer_intersect(v->tracer, o, d, FLT_MAX, &h)) {
            if (v->ids) v->ids[p] = RENDERCACHE_MISS;
            continue;
        }
        if (v->ids) {
            v->ids[p] = h.instance == EX_TRACE_STATIC ? v->tracer->scene->tri_face[h.tri] : v->instance_faces + h.tri / 2;
            continue;
        }
        if (!h.front) continue;
        {
            const float *kd, *ks, *ke;
            float ns, e[3] = { 0, 0, 0 }, l[3];
            ex_rng rng = ex_rng_stream(17, p);
            ex__tracer_material(v->tracer, &h, &kd, &ks, &ns, &ke);
            for (i = 0; i < NIM_SAMPLES; i++) {
                ex__tracer_direct(v->tracer, &h, d, &rng, l);
                for (k = 0; k < 3; k++) rgb[k] += l[k] / NIM_SAMPLES;
            }
            if (v->gather_rays) {
                ex_rng g = ex_rng_stream(29, p);
                nim_gather(v->tracer, &h, v->gather_rays, &g, e);
            } else if (v->ind) {
                ex_indirect_at(v->ind, v->irradiance, &h, e);
            }
            for (k = 0; k < 3; k++) rgb[k] += ke[k] + kd[k] / 3.14159265f * e[k];
        }
    }
}

static void nim_render(ex_pool *pool, nim_view *v)
{
    ex_pool_parallel_for(pool, nim_rows, v, v->camera->height);
}

/* An image of camera with the grid's indirect light (ind NULL: none). */
static void nim_image(ex_pool *pool, const ex_tracer *t, const ex_indirect *ind, const float *irradiance,
                      const rendercache_camera *camera, float *rgb)
{
    nim_view v;
    memset(&v, 0, sizeof v);
    v.tracer = t;
    v.ind = ind;
    v.irradiance = irradiance;
    v.camera = camera;
    v.rgb = rgb;
    nim_render(pool, &v);
}

static rendercache_camera nim_camera(rendercache_camera_kind kind, const float eye[3], const float at[3], uint32_t w,
                                     uint32_t h)
{
    rendercache_camera c;
    memset(&c, 0, sizeof c);
    c.kind = kind;
    memcpy(c.eye, eye, sizeof c.eye);
    memcpy(c.look_at, at, sizeof c.look_at);
    c.up[1] = 1.0f;
    if (at[0] == eye[0] && at[2] == eye[2]) { c.up[1] = 0.0f; c.up[2] = 1.0f; }
    c.vfov_degrees = 50.0f;
    c.width = w;
    c.height = h;
    return c;
}

/* Table 1: the indirect light of the office on grids simplified at three
   qualities (coarser grids, small faces reduced to one node) against the
   indirect light gathered at every pixel (1,024 rays: the reference); the
   images differ in their indirect light only. */
#define NIM_NODE_RAYS 512
static void nim_table1(ex_pool *pool)
{
    static const float spacing[3] = { 0.6f, 0.3f, 0.15f }, min_area[3] = { 0.5f, 0.1f, 0.0f };
    static const char *names[4] = { "low", "medium", "high", "per pixel" };
    static const float eye[3] = { 1.2f, 1.4f, 0.6f }, at[3] = { 2.6f, 1.0f, 3.4f };
    rendercache_camera cam = nim_camera(RENDERCACHE_CAMERA_PERSPECTIVE, eye, at, 160, 120);
    obj_scene office;
    ex_tracer *tracer;
    char err[256];
    float *img[4];
    uint32_t faces[4], reduced[4], nodes[4], f;
    double seconds[4], lrms[3];
    int q;
    if (obj_load("examples/data/office.obj", &office, err, sizeof err) != 0 || !(tracer = ex_tracer_create(&office))) return;
    {   /* the reference */
        nim_view v;
        double t0 = now_seconds(NULL);
        img[3] = (float *)malloc(sizeof(float) * 3 * cam.width * cam.height);
        if (!img[3]) exit(1);
        memset(&v, 0, sizeof v);
        v.tracer = tracer;
        v.camera = &cam;
        v.rgb = img[3];
        v.gather_rays = 1024;
        nim_render(pool, &v);
        seconds[3] = now_seconds(NULL) - t0;
        faces[3] = office.face_count;
        reduced[3] = 0;
        nodes[3] = cam.width * cam.height;
    }
    for (q = 2; q >= 0; q--) {
        ex_indirect ind;
        ex_indirect_desc d;
        float *values;
        memset(&d, 0, sizeof d);
        d.tracer = tracer;
        d.scene = &office;
        d.spacing = spacing[q];
        d.min_area = min_area[q];
        d.rays = NIM_NODE_RAYS;
        d.seed = 3;
        d.pool = pool;
        img[q] = (float *)malloc(sizeof(float) * 3 * cam.width * cam.height);
        if (!img[q] || ex_indirect_init(&d, &ind) != 0) exit(1);
        values = (float *)malloc(3 * sizeof(float) * ind.node_count);
        if (!values) exit(1);
        ex_indirect_gather(&ind, values);
        faces[q] = ind.face_count;
        nodes[q] = ind.node_count;
        seconds[q] = ind.seconds;
        for (f = reduced[q] = 0; f < ind.face_count; f++) reduced[q] += ind.faces[f].nu * ind.faces[f].nv == 1;
        nim_image(pool, tracer, &ind, values, &cam, img[q]);
        rendercache_lrms(img[3], img[q], cam.width, cam.height, &lrms[q]);
        free(values);
        ex_indirect_free(&ind);
    }
    printf("\ntable 1, geometric simplification for the indirect light (office, 160x120, one bounce, %d rays per node)\n",
           NIM_NODE_RAYS);
    printf("  %-12s %6s %14s %8s %12s %10s\n", "quality", "faces", "one-node faces", "nodes", "gathers (s)", "LRMS");
    for (q = 0; q < 4; q++)
        printf("  %-12s %6u %14u %8u %12.2f %10.4f\n", names[q], faces[q], reduced[q], nodes[q], seconds[q], q < 3 ? lrms[q] : 0.0);
    printf("  paper (studio, 68,718 surfaces): low 14,008 surfaces LRMS 0.381, medium 31,598 0.340, high 66,102 0.339 "
           "(Radiance typical 0.360); 18-36 h of rendering\n");
    for (q = 0; q < 4; q++) free(img[q]);
    ex_tracer_destroy(tracer);
    obj_free(&office);
}

/* The Cornell box with a block of 0.16 x 0.33 x 0.16 m (the size of the
   box's tall block) sliding 0.3 m along x over [0, 1] (tables 2 and 4). */
static const char nim_cube_obj[] =
    "v -0.08 0 -0.08\nv 0.08 0 -0.08\nv 0.08 0 0.08\nv -0.08 0 0.08\n"
    "v -0.08 0.33 -0.08\nv 0.08 0.33 -0.08\nv 0.08 0.33 0.08\nv -0.08 0.33 0.08\n"
    "f 1 2 3 4\nf 5 8 7 6\nf 1 5 6 2\nf 2 6 7 3\nf 3 7 8 4\nf 4 8 5 1\n";
static const float nim_cube_kd[3] = { 0.2f, 0.6f, 0.25f };

typedef struct nim_box {
    obj_scene box, cube;
    ex_tracer *tracer;
    const obj_scene *meshes[1];
    ex_indirect ind;
    ex_pool *pool;
} nim_box;

static void nim_cube_at(double t, float m[12])
{
    memset(m, 0, 12 * sizeof(float));
    m[0] = m[5] = m[10] = 1.0f;
    m[3] = (float)(0.12 + 0.3 * t);
    m[11] = 0.1f;
}

static void nim_box_time(nim_box *b, double t)
{
    float m[12];
    nim_cube_at(t, m);
    ex_tracer_set_transform(b->tracer, 0, m);
}

static int nim_solve(void *user, double t, float *values)
{
    nim_box *b = (nim_box *)user;
    nim_box_time(b, t);
    ex_indirect_gather(&b->ind, values);
    return 0;
}

static int nim_box_ids(void *user, const rendercache_camera *camera, double t, uint32_t *ids)
{
    nim_box *b = (nim_box *)user;
    nim_view v;
    nim_box_time(b, t);
    memset(&v, 0, sizeof v);
    v.tracer = b->tracer;
    v.camera = camera;
    v.ids = ids;
    v.instance_faces = b->box.face_count;
    nim_render(b->pool, &v);
    return 0;
}

/* Table 2 (the indirect light at key times, interpolated) and table 4 (key
   times of the motion; frame 10 of 12 blended from the images at its keys). */
static void nim_tables24(ex_pool *pool, int table)
{
    static const float qs[3] = { 0.3f, 0.6f, 0.9f };
    static const float eye[3] = { 0.278f, 0.273f, -0.8f }, at[3] = { 0.278f, 0.2f, 0.28f };
    static const float light_eye[3] = { 0.278f, 0.54f, 0.28f }, light_at[3] = { 0.278f, 0.0f, 0.28f };
    rendercache_camera cam = nim_camera(RENDERCACHE_CAMERA_PERSPECTIVE, eye, at, 160, 160), cams[2];
    nim_box b;
    ex_indirect_desc d;
    char err[256];
    float *exact, *values, *img, *ref;
    double t_test = 10.0 / 11.0, render_s;
    int q;
    memset(&b, 0, sizeof b);
    b.pool = pool;
    if (obj_load("examples/data/cornell_box.obj", &b.box, err, sizeof err) != 0 ||
        obj_parse(nim_cube_obj, sizeof nim_cube_obj - 1, "cube", NULL, &b.cube, err, sizeof err) != 0 ||
        !(b.tracer = ex_tracer_create(&b.box)) || ex_tracer_add_instance(b.tracer, &b.cube, nim_cube_kd) != 0)
        return;
    b.meshes[0] = &b.cube;
    memset(&d, 0, sizeof d);
    d.tracer = b.tracer;
    d.scene = &b.box;
    d.meshes = b.meshes;
    d.mesh_count = 1;
    d.spacing = 0.04f;
    d.rays = 128;
    d.seed = 5;
    d.pool = pool;
    if (ex_indirect_init(&d, &b.ind) != 0) exit(1);
    exact = (float *)malloc(3 * sizeof(float) * b.ind.node_count);
    values = (float *)malloc(3 * sizeof(float) * b.ind.node_count);
    img = (float *)malloc(sizeof(float) * 3 * 160 * 160);
    ref = (float *)malloc(sizeof(float) * 3 * 160 * 160);
    if (!exact || !values || !img || !ref) exit(1);
    {   /* the reference of table 2: the indirect light gathered at the frame's own time */
        double t0;
        nim_solve(&b, t_test, exact);
        t0 = now_seconds(NULL);
        nim_image(pool, b.tracer, &b.ind, exact, &cam, ref);
        render_s = now_seconds(NULL) - t0;
    }
    if (table == 2) {
        printf("\ntable 2, indirect light in time (Cornell box, a block sliding 0.3 m; %u nodes, 128 rays; frame at t = %.3f, "
               "160x160)\n", b.ind.node_count, t_test);
        printf("  %-8s %6s %16s %18s %14s %10s\n", "quality", "keys", "decompose (s)", "interpolate (ms)", "render (ms)", "LRMS");
    }
    for (q = 0; q < 3 && table == 2; q++) {
        rendercache_keytime_desc kd;
        rendercache_keytimes *kt = NULL;
        double seconds = b.ind.seconds, t0, lrms;
        memset(&kd, 0, sizeof kd);
        kd.element_count = b.ind.node_count;
        kd.components = 3;
        kd.t0 = 0.0;
        kd.t1 = 1.0;
        kd.quality = qs[q];
        kd.max_depth = 5;
        kd.solve = nim_solve;
        kd.user = &b;
        if (rendercache_keytimes_create(&kd, &kt) != RENDERCACHE_OK) exit(1);
        t0 = now_seconds(NULL);
        rendercache_keytimes_eval(kt, t_test, values, 3 * (size_t)b.ind.node_count);
        t0 = now_seconds(NULL) - t0;
        nim_box_time(&b, t_test);
        nim_image(pool, b.tracer, &b.ind, values, &cam, img);
        rendercache_lrms(ref, img, 160, 160, &lrms);
        printf("  %-8.1f %6u %16.2f %18.3f %14.1f %10.4f\n", (double)qs[q], rendercache_keytimes_count(kt),
               b.ind.seconds - seconds, 1e3 * t0, 1e3 * render_s, lrms);
        rendercache_keytimes_destroy(kt);
    }
    if (table == 2)
        printf("  paper (Cornell box, WR): LRMS 0.147 / 0.138 / 0.119 at q = 0.3 / 0.6 / 0.9 (Radiance typical 0.183); "
               "decomposition 0.04-0.31 min, indirect generation 0.73-1.69 min, rendering 88-112 min for 30 frames\n");

    /* table 4: key times of the motion (the view and a fish-eye at the light), frame 10 of 12 blended */
    cams[0] = cam;
    cams[0].width = cams[0].height = 48;
    cams[1] = nim_camera(RENDERCACHE_CAMERA_FISHEYE, light_eye, light_at, 48, 48);
    if (table == 4) {
        printf("\ntable 4, motion interpolation (Cornell box, the sliding block; frame 10 of 12 from the images at its key "
               "times, direct light only)\n");
        printf("  %-8s %6s %16s %22s %22s  %s\n", "quality", "keys", "decompose (s)", "LRMS pixelwise (pcomb)",
               "LRMS motion-compensated", "time list");
    }
    nim_box_time(&b, t_test);
    if (table == 4) nim_image(pool, b.tracer, NULL, NULL, &cam, ref);   /* frame 10 rendered at its time */
    for (q = 0; q < 3 && table == 4; q++) {
        rendercache_time_desc td;
        double ends[2] = { 0.0, 1.0 }, *times = NULL, t0 = now_seconds(NULL), lrms[2];
        uint32_t count = 0, k = 0, i, m;
        rendercache_range_image *key[2], *out = NULL;
        rendercache_warp_desc wd;
        rendercache_warper *w = NULL;
        char list[256];
        size_t len = 0;
        memset(&td, 0, sizeof td);
        td.cameras = cams;
        td.camera_count = 2;
        td.times = ends;
        td.time_count = 2;
        td.quality = qs[q];
        td.max_depth = 5;
        td.render_ids = nim_box_ids;
        td.user = &b;
        if (rendercache_subdivide_time(&td, &times, &count) != RENDERCACHE_OK) exit(1);
        t0 = now_seconds(NULL) - t0;
        while (k + 2 < count && times[k + 1] <= t_test) k++;
        memset(&wd, 0, sizeof wd);
        if (rendercache_warper_create(&wd, &w) != RENDERCACHE_OK || rendercache_range_image_create(&cam, NULL, &out) != RENDERCACHE_OK)
            exit(1);
        for (i = 0; i < 2; i++) {   /* the images at the keys around frame 10: colour, distance, object */
            nim_view v;
            uint32_t p, *ids = (uint32_t *)malloc(sizeof(uint32_t) * 160 * 160);
            if (!ids || rendercache_range_image_create(&cam, NULL, &key[i]) != RENDERCACHE_OK) exit(1);
            key[i]->time = times[k + i];
            nim_box_time(&b, times[k + i]);
            nim_image(pool, b.tracer, NULL, NULL, &cam, key[i]->rgb);
            memset(&v, 0, sizeof v);
            v.tracer = b.tracer;
            v.camera = &cam;
            v.ids = ids;
            v.instance_faces = b.box.face_count;
            nim_render(pool, &v);
            for (p = 0; p < 160 * 160; p++) {
                float o[3], dd[3];
                ex_trace_hit h;
                rendercache_camera_ray(&cam, (float)(p % 160) + 0.5f, (float)(p / 160) + 0.5f, o, dd);
                if (!ex_tracer_intersect(b.tracer, o, dd, FLT_MAX, &h)) {
                    key[i]->object[p] = RENDERCACHE_MISS;
                    continue;
                }
                key[i]->object[p] = ids[p] >= b.box.face_count ? 1u : 0u;   /* the box, or the cube */
                key[i]->depth[p] = h.t;
            }
            free(ids);
        }
        {   /* objects: 0 the box (still), 1 the cube */
            double s = (t_test - times[k]) / (times[k + 1] - times[k]);
            float wa[24], wb[24], wt[24];
            rendercache_motion motion;
            memset(wa, 0, sizeof wa);
            wa[0] = wa[5] = wa[10] = 1.0f;
            memcpy(wb, wa, sizeof wb);
            memcpy(wt, wa, sizeof wt);
            nim_cube_at(times[k], wa + 12);
            nim_cube_at(times[k + 1], wb + 12);
            nim_cube_at(t_test, wt + 12);
            motion.object_count = 2;
            motion.world_a = wa;
            motion.world_b = wb;
            motion.world_t = wt;
            rendercache_blend(key[0], key[1], (float)s, out);
            rendercache_lrms(ref, out->rgb, 160, 160, &lrms[0]);
            rendercache_blend_motion(w, key[0], key[1], (float)s, &motion, RENDERCACHE_FILL_BOTH, out);
            rendercache_lrms(ref, out->rgb, 160, 160, &lrms[1]);
        }
        list[0] = 0;
        for (m = 0; m < count && len + 8 < sizeof list; m++)
            len += (size_t)snprintf(list + len, sizeof list - len, "%s%.3g", m ? ", " : "", times[m]);
        printf("  %-8.1f %6u %16.2f %22.3f %22.3f  %s\n", (double)qs[q], count, t0, lrms[0], lrms[1], list);
        rendercache_range_image_destroy(key[0]);
        rendercache_range_image_destroy(key[1]);
        rendercache_range_image_destroy(out);
        rendercache_warper_destroy(w);
        rendercache_free_memory(NULL, times);
    }
    if (table == 4)
        printf("  paper (Cornell box): 2 / 3 / 5 solutions (0, 48 / 0, 24, 48 / 0, 12, 24, 36, 48), frame 10 LRMS 0.849 / "
               "0.748 / 0.576\n");
    free(exact);
    free(values);
    free(img);
    free(ref);
    ex_indirect_free(&b.ind);
    ex_tracer_destroy(b.tracer);
    obj_free(&b.box);
    obj_free(&b.cube);
}


/* Table 3: base views of a 1D view space across the office (fish-eye id
   images of 48x48, one id per face) for q = 0.3, 0.6, 0.9, and a 320x240
   frame in the middle of the cell around its eye, warped with both fills
   and averaging from the corner views' 512x512 base images. Shading as the
   walkthrough bench's base images (flat, so that LRMS measures the
   reconstruction). */
typedef struct nim_office {
    obj_scene scene;
    ex_tracer *tracer;
    ex_pool *pool;
} nim_office;

static int nim_office_ids(void *user, const rendercache_camera *camera, double t, uint32_t *ids)
{
    nim_office *o = (nim_office *)user;
    nim_view v;
    (void)t;
    memset(&v, 0, sizeof v);
    v.tracer = o->tracer;
    v.camera = camera;
    v.ids = ids;
    nim_render(o->pool, &v);
    return 0;
}

static void nim_table3(ex_pool *pool)
{
    static const float qs[3] = { 0.3f, 0.6f, 0.9f };
    nim_office o;
    char err[256];
    int q;
    memset(&o, 0, sizeof o);
    o.pool = pool;
    if (obj_load("examples/data/office.obj", &o.scene, err, sizeof err) != 0 || !(o.tracer = ex_tracer_create(&o.scene))) return;
    printf("\ntable 3, view reconstruction (office, view space 1.5 m along x, fish-eye bases of 512x512, a 320x240 frame "
           "between its two nearest views; 1 thread for the synthesis)\n");
    printf("  %-8s %6s %16s %14s %18s %10s\n", "quality", "views", "decompose (s)", "base (s each)", "synthesis (ms)", "LRMS");
    for (q = 0; q < 3; q++) {
        rendercache_view_space_desc vd;
        rendercache_view_space *vs = NULL;
        rendercache_camera frame = office_camera(RENDERCACHE_CAMERA_PERSPECTIVE, 2.21f, 1.0f, 0.0f, 320, 240);
        rendercache_range_image *bases[2], *out = NULL, *ref = NULL;
        rendercache_warp_desc wd;
        rendercache_warper *w = NULL;
        uint32_t corners[8], n = 0, i;
        double t0 = now_seconds(NULL), decompose, base_s, synth, lrms;
        memset(&vd, 0, sizeof vd);
        vd.camera = office_camera(RENDERCACHE_CAMERA_FISHEYE, 1.5f, 1.0f, 0.0f, 48, 48);
        vd.lo[0] = 1.5f; vd.lo[1] = 1.4f; vd.lo[2] = 1.0f;
        vd.hi[0] = 3.0f; vd.hi[1] = 1.4f; vd.hi[2] = 1.0f;
        vd.quality = qs[q];
        vd.max_depth = 6;
        vd.render_ids = nim_office_ids;
        vd.user = &o;
        if (rendercache_view_space_create(&vd, &vs) != RENDERCACHE_OK) exit(1);
        decompose = now_seconds(NULL) - t0;
        rendercache_view_space_locate(vs, frame.eye, corners, &n);
        t0 = now_seconds(NULL);
        for (i = 0; i < n && i < 2; i++) {
            rendercache_camera c;
            base_job j;
            rendercache_view_space_camera(vs, corners[i], &c);
            c.width = c.height = 512;
            bases[i] = NULL;
            if (rendercache_range_image_create(&c, NULL, &bases[i]) != RENDERCACHE_OK) exit(1);
            j.tracer = o.tracer;
            j.scene = &o.scene;
            j.img = bases[i];
            ex_pool_parallel_for(pool, base_rows, &j, (512 + 7) / 8);
        }
        base_s = (now_seconds(NULL) - t0) / 2.0;
        memset(&wd, 0, sizeof wd);
        wd.average = 1;
        if (rendercache_warper_create(&wd, &w) != RENDERCACHE_OK || rendercache_range_image_create(&frame, NULL, &out) != RENDERCACHE_OK ||
            rendercache_range_image_create(&frame, NULL, &ref) != RENDERCACHE_OK)
            exit(1);
        t0 = now_seconds(&g_cpu_clock);
        rendercache_warp(w, (const rendercache_range_image *const *)bases, 2, &frame, RENDERCACHE_FILL_BOTH, out);
        synth = now_seconds(&g_cpu_clock) - t0;
        {
            base_job j;
            j.tracer = o.tracer;
            j.scene = &o.scene;
            j.img = ref;
            ex_pool_parallel_for(pool, base_rows, &j, (240 + 7) / 8);
        }
        rendercache_lrms(ref->rgb, out->rgb, 320, 240, &lrms);
        printf("  %-8.1f %6u %16.2f %14.2f %18.1f %10.4f\n", (double)qs[q], rendercache_view_space_count(vs), decompose, base_s,
               1e3 * synth, lrms);
        for (i = 0; i < 2; i++) rendercache_range_image_destroy(bases[i]);
        rendercache_range_image_destroy(out);
        rendercache_range_image_destroy(ref);
        rendercache_warper_destroy(w);
        rendercache_view_space_destroy(vs);
    }
    printf("  paper (studio): 2 / 3 / 5 views, decomposition 10.8 / 34.1 / 116 s, base views 570-728 min each, synthesis "
           "0.046-0.061 min, LRMS 0.638 / 0.625 / 0.117 (resampled Radiance 0.120)\n");
    ex_tracer_destroy(o.tracer);
    obj_free(&o.scene);
}

/* The render cache figures next to the paper's and the target. */
static void cache_summary(double frame_ms[2][2], double sample_us, int shade_threads, const double bytes[2])
{
    double pixels = 512.0 * 512.0, full_ms = pixels * sample_us * 1e-3;
    double cache_ms = frame_ms[0][0] + BUDGET * pixels * sample_us * 1e-3;
    printf("paper (Walter et al. 2002): 62 ms per 512x512 frame on a Pentium 4 (16 fps potential, 12-14 observed)\n");
    if (frame_ms[0][0] > 0.0)   /* (the lines a selection left out are not summed up) */
        printf("ours 512x512: %.2f ms on 1 thread (target <= 8 ms), %.2f ms on 2; ratio to the paper %.1fx\n",
               frame_ms[0][0], frame_ms[0][1], 62.0 / frame_ms[0][0]);
    if (frame_ms[1][0] > 0.0 || frame_ms[1][1] > 0.0)
        printf("ours 1920x1080: %.2f ms on 1 thread, %.2f ms on 2 (wall; target <= 40 ms)\n", frame_ms[1][0], frame_ms[1][1]);
    printf("memory: %.1f bytes per pixel at 512x512, %.1f at 1920x1080 (2 points per pixel, with parallel_for)\n",
           bytes[0], bytes[1]);
    if (frame_ms[0][0] > 0.0)
        printf("512x512 with direct light + one bounce (%.2f us per sample, %d shading threads): full re-render "
               "%.0f ms, cache frame (overhead + 8%% samples) %.0f ms, %.1fx faster\n",
               sample_us, shade_threads, full_ms, cache_ms, full_ms / cache_ms);
}

/* Whether the cache line of size w x h on that many threads runs: with
   "cache" followed by sizes WxH and thread counts "1t" / "2t", only those
   (e.g. `bench_rendercache cache 1920x1080 2t`); "cache" alone or "quick":
   512x512 on one thread; no argument: every line. */
static int cache_selected(int argc, char **argv, uint32_t w, uint32_t h, int threads)
{
    int i, size_given = 0, size_ok = 0, threads_given = 0, threads_ok = 0;
    for (i = 2; i < argc; i++) {
        unsigned sw, sh;
        int t;
        char c;
        if (sscanf(argv[i], "%ux%u%c", &sw, &sh, &c) == 2) {
            size_given = 1;
            size_ok |= sw == w && sh == h;
        } else if (sscanf(argv[i], "%dt%c", &t, &c) == 1) {
            threads_given = 1;
            threads_ok |= t == threads;
        }
    }
    if (argc < 2) return 1;
    if (!size_given && !threads_given) return w == 512 && threads == 1;
    return (!size_given || size_ok) && (!threads_given || threads_ok);
}

/* Whether the cache line of size w x h on that many threads runs again
   with the huge-page allocator: with no argument 512x512 on one thread and
   1920x1080 on two; with "cache ... huge", the lines cache_selected runs. */
static int huge_selected(int argc, char **argv, uint32_t w, uint32_t h, int threads)
{
    int i;
    if (argc < 2) return (w == 512 && threads == 1) || (w == 1920 && threads == 2);
    for (i = 2; i < argc; i++)
        if (strcmp(argv[i], "huge") == 0) return cache_selected(argc, argv, w, h, threads);
    return 0;
}

/* Arguments: "quick" (any argument but the three below) runs 512x512 and
   the warps on one thread only; "cache", "warp" or "tables" runs that part
   only, quick (e.g. under valgrind --tool=callgrind); "cache" takes sizes
   and thread counts (cache_selected), and "huge" (huge_selected). */
int main(int argc, char **argv)
{
    static const uint32_t sizes[2][2] = { { 512, 512 }, { 1920, 1080 } };
    obj_scene scene;
    ex_tracer *tracer;
    ex_pool *shade_pool;
    char err[256];
    int s, threads, quick = argc > 1, cache = 1, warp = 1, tables = 1;
    double frame_ms[2][2] = { { 0, 0 }, { 0, 0 } }, sample_us = 0.0, bytes[2] = { 0, 0 }, b;
    if (quick && strcmp(argv[1], "cache") == 0) warp = tables = 0;
    if (quick && strcmp(argv[1], "warp") == 0) cache = tables = 0;
    if (quick && strcmp(argv[1], "tables") == 0) cache = warp = 0;
    printf("%s at the start\n", load_average());
    if (obj_load("examples/data/cornell_box.obj", &scene, err, sizeof err) != 0) {
        printf("cannot load the Cornell box: %s\n", err);
        return 1;
    }
    tracer = ex_tracer_create(&scene);
    shade_pool = ex_pool_create(0);
    if (!tracer || !shade_pool) return 1;
    if (cache) printf("render cache per-frame overhead, Cornell box camera path, %d frames, budget %.0f%% of the pixels\n",
                      FRAMES, BUDGET * 100);
    for (s = 0; cache && s < 2; s++)
        for (threads = 1; threads <= 2; threads++) {
            if (!cache_selected(argc, argv, sizes[s][0], sizes[s][1], threads)) continue;
            run(tracer, shade_pool, sizes[s][0], sizes[s][1], threads, &frame_ms[s][threads - 1], &sample_us, &b, 0);
            if (b > bytes[s]) bytes[s] = b;
        }
    /* the same with an allocator that backs large blocks with huge pages (an engine's allocator may;
       the library takes whatever its desc's allocator gives) */
    for (s = 0; cache && s < 2; s++)
        for (threads = 1; threads <= 2; threads++) {
            double ms, us;
            if (huge_selected(argc, argv, sizes[s][0], sizes[s][1], threads))
                run(tracer, shade_pool, sizes[s][0], sizes[s][1], threads, &ms, &us, &b, 1);
        }
    if (cache) cache_summary(frame_ms, sample_us, ex_pool_threads(shade_pool), bytes);
    printf("%s at the end\n", load_average());
    if (warp) bench_walkthrough(shade_pool, quick);
    if (tables) {
        printf("\nNimeroff, Dorsey and Rushmeier 1996, tables 1-4, beside ours\n");
        nim_table1(shade_pool);
        nim_tables24(shade_pool, 2);
        nim_table3(shade_pool);
        nim_tables24(shade_pool, 4);
    }
    ex_tracer_destroy(tracer);
    ex_pool_destroy(shade_pool);
    obj_free(&scene);
    return 0;
}
