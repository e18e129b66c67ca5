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

   Medians over the frames of the paths. */
#include "examples/common/pool.h"
#include "examples/common/trace.h"
#define RENDERCACHE_IMPLEMENTATION
#include "rendercache.h"

#include <stdio.h>
#include <time.h>

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

/* An allocator that counts the bytes live (for the memory per pixel). */
typedef struct counted { size_t live, peak; } counted;
static void *counted_alloc(size_t size, void *user)
{
    counted *c = (counted *)user;
    size_t *p = (size_t *)malloc(size + sizeof(size_t) * 2);
    if (!p) return NULL;
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
    free(p - 2);
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

enum { P_PROJECT, P_CULL, P_INTERP, P_PREDICT, P_REQUEST, P_INSERT, P_TOTAL, P_COUNT };

static void run(const ex_tracer *tracer, ex_pool *shade_pool, uint32_t w, uint32_t h, int threads,
                double *frame_ms, double *sample_us, double *bytes_per_pixel)
{
    /* priority is computed inside cull (pixels with a point) and interp (holes); on one thread the
       two run interleaved, timed together under cull */
    static const char *names[P_COUNT] = { "project+z-buffer", "cull(+interp on 1 thread)", "interp+priority",
                                          "predict", "request", "insert", "total" };
    double times[P_COUNT][FRAMES];
    rendercache_desc d;
    rendercache *rc;
    rendercache_pixel_request *req = (rendercache_pixel_request *)malloc(sizeof *req * w * h);
    rendercache_sample *samples = (rendercache_sample *)malloc(sizeof *samples * w * h);
    ex_pool *pool = threads > 1 ? ex_pool_create(threads) : NULL;
    uint32_t n = 0, budget = (uint32_t)(BUDGET * w * h + 0.5);
    double shade_time = 0.0;
    uint64_t shaded = 0;
    counted memory = { 0, 0 };
    int f, k;
    memset(&d, 0, sizeof d);
    d.allocator.alloc = counted_alloc;
    d.allocator.free = counted_free;
    d.allocator.user = &memory;
    if (getenv("BENCH_NOCHANGE")) d.change_threshold = FLT_MAX;
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
        double t0;
        rendercache_begin_frame(rc, &c);
        rendercache_predict(rc, &next);   /* WDG02: the holes of the next camera, from a quarter of the budget */
        rendercache_request(rc, req, budget, &n);
        t0 = now_seconds(NULL);
        shade_all(shade_pool, tracer, req, samples, n, (uint32_t)f + 1, 1);   /* direct + one bounce */
        shade_time += now_seconds(NULL) - t0;
        shaded += n;
        rendercache_insert(rc, samples, n, NULL);
        rendercache_get_stats(rc, &st);
        times[P_PROJECT][f] = st.time_project;
        times[P_CULL][f] = st.time_cull;
        times[P_INTERP][f] = st.time_interpolate;
        times[P_PREDICT][f] = st.time_predict;
        times[P_REQUEST][f] = st.time_request;
        times[P_INSERT][f] = st.time_insert;
        if (getenv("BENCH_DEBUG")) printf("frame %d: inserted %u replaced %u changed %u\n", f, st.inserted, st.replaced, st.changed);
        times[P_TOTAL][f] = st.time_project + st.time_cull + st.time_interpolate + st.time_predict +
                            st.time_request + st.time_insert;
    }
    *bytes_per_pixel = (double)memory.peak / ((double)w * h);
    printf("%4ux%-4u %d thread%s (%s):", w, h, threads, threads > 1 ? "s" : " ", threads > 1 ? "wall" : "cpu ");
    for (k = 0; k < P_COUNT; k++) {
        double m = median(times[k], FRAMES) * 1e3;
        printf(" %s %.2f%s", names[k], m, k + 1 < P_COUNT ? "," : " ms (medians)\n");
        if (k == P_TOTAL) *frame_ms = m;
    }
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

static void warp_run(rendercache_range_image *const *bases, uint32_t n, rendercache_fill fill, int threads,
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

static void bench_walkthrough(ex_pool *shade_pool, int quick)
{
    static const float corners[4][2] = { { 1.5f, 0.5f }, { 2.5f, 0.5f }, { 1.5f, 1.5f }, { 2.5f, 1.5f } };
    obj_scene scene;
    ex_tracer *tracer;
    rendercache_range_image *bases[4];
    const uint32_t *ids[4];
    char err[256];
    double ms[2][4][2], blend_times[8], motion_times[8], fit_times[8];
    uint32_t i, k;
    int counts[2] = { 2, 4 }, c, fi, threads;
    static const rendercache_fill fills[4] = { RENDERCACHE_FILL_NONE, RENDERCACHE_FILL_FOREGROUND,
                                               RENDERCACHE_FILL_BACKGROUND, RENDERCACHE_FILL_BOTH };
    static const char *fill_names[4] = { "no fill", "foreground", "background", "both fills" };
    if (obj_load("examples/data/office.obj", &scene, err, sizeof err) != 0) {
        printf("cannot load the office: %s\n", err);
        return;
    }
    tracer = ex_tracer_create(&scene);
    if (!tracer) return;
    for (i = 0; i < 4; i++) {   /* fish-eyes at the corners of a 1 m square, looking at the desk */
        rendercache_camera cam = office_camera(RENDERCACHE_CAMERA_FISHEYE, corners[i][0], corners[i][1], 0.0f, BASE_SIZE, BASE_SIZE);
        base_job j;
        bases[i] = NULL;
        if (rendercache_range_image_create(&cam, NULL, &bases[i]) != RENDERCACHE_OK) exit(1);
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
                warp_run(bases, (uint32_t)counts[c], fills[fi], threads, &ms[c][fi][threads - 1]);
            }
    for (c = 0; c < 2; c++)
        for (fi = 0; fi < 4; fi++)
            printf("  warp from %d bases, %-10s: %6.2f ms on 1 thread (cpu), %6.2f ms on 2 (wall)\n", counts[c],
                   fill_names[fi], ms[c][fi][0], ms[c][fi][1]);
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
           "both fills (%.0fx faster than pinterp's 3 s)\n", ms[1][2][0], ms[1][3][0], 3000.0 / ms[1][3][0]);
    for (i = 0; i < 4; i++) rendercache_range_image_destroy(bases[i]);
    ex_tracer_destroy(tracer);
    obj_free(&scene);
}

/* The render cache figures next to the paper's and the target. */
static void cache_summary(double frame_ms[2][2], double sample_us, int shade_threads, const double bytes[2])
{
    double pixels = 512.0 * 512.0, full_ms = pixels * sample_us * 1e-3;
    double cache_ms = frame_ms[0][0] + BUDGET * pixels * sample_us * 1e-3;
    printf("paper (Walter et al. 2002): 62 ms per 512x512 frame on a Pentium 4 (16 fps potential, 12-14 observed)\n");
    printf("ours 512x512: %.2f ms on 1 thread (target <= 8 ms), %.2f ms on 2; ratio to the paper %.1fx\n",
           frame_ms[0][0], frame_ms[0][1], 62.0 / frame_ms[0][0]);
    if (frame_ms[1][1] > 0.0)
        printf("ours 1920x1080: %.2f ms on 1 thread, %.2f ms on 2 (wall; target <= 40 ms)\n", frame_ms[1][0], frame_ms[1][1]);
    printf("memory: %.1f bytes per pixel at 512x512, %.1f at 1920x1080 (2 points per pixel, with parallel_for)\n",
           bytes[0], bytes[1]);
    printf("512x512 with direct light + one bounce (%.2f us per sample, %d shading threads): full re-render "
           "%.0f ms, cache frame (overhead + 8%% samples) %.0f ms, %.1fx faster\n",
           sample_us, shade_threads, full_ms, cache_ms, full_ms / cache_ms);
}

/* Arguments: "quick" (any argument but the two below) runs 512x512 and
   the warps on one thread only; "cache" or "warp" runs that part only,
   quick (e.g. under valgrind --tool=callgrind). */
int main(int argc, char **argv)
{
    static const uint32_t sizes[2][2] = { { 512, 512 }, { 1920, 1080 } };
    obj_scene scene;
    ex_tracer *tracer;
    ex_pool *shade_pool;
    char err[256];
    int s, threads, quick = argc > 1, cache = 1, warp = 1;
    double frame_ms[2][2] = { { 0, 0 }, { 0, 0 } }, sample_us = 0.0, bytes[2] = { 0, 0 }, b;
    if (quick && strcmp(argv[1], "cache") == 0) warp = 0;
    if (quick && strcmp(argv[1], "warp") == 0) cache = 0;
    if (obj_load("examples/data/cornell_box.obj", &scene, err, sizeof err) != 0) {
        printf("cannot load the Cornell box: %s\n", err);
        return 1;
    }
    tracer = ex_tracer_create(&scene);
    shade_pool = ex_pool_create(0);
    if (!tracer || !shade_pool) return 1;
    if (cache) printf("render cache per-frame overhead, Cornell box camera path, %d frames, budget %.0f%% of the pixels\n",
                      FRAMES, BUDGET * 100);
    for (s = 0; cache && s < (quick ? 1 : 2); s++)
        for (threads = 1; threads <= (quick ? 1 : 2); threads++) {
            run(tracer, shade_pool, sizes[s][0], sizes[s][1], threads, &frame_ms[s][threads - 1], &sample_us, &b);
            if (b > bytes[s]) bytes[s] = b;
        }
    if (cache) cache_summary(frame_ms, sample_us, ex_pool_threads(shade_pool), bytes);
    if (warp) bench_walkthrough(shade_pool, quick);
    ex_tracer_destroy(tracer);
    ex_pool_destroy(shade_pool);
    obj_free(&scene);
    return 0;
}
