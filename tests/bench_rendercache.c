/* Benchmark of rendercache.h: the per-frame overhead of the render cache
   (ageing + projection + binning, z-buffer, depth cull, interpolation,
   priority image, request selection, insertion) on a camera path through the
   Cornell box, at 512x512 and 1024x768, on 1 and 2 threads, with the
   8%-of-the-pixels sample budget of Crespin and Peroche. Samples come from
   the examples' ray tracer; their shading time is not part of the cache
   overhead but is measured once to compare a cache frame with a full
   re-render. Medians over the frames of the path. */
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

enum { P_PROJECT, P_CULL, P_INTERP, P_REQUEST, P_INSERT, P_TOTAL, P_COUNT };

static void run(const ex_tracer *tracer, ex_pool *shade_pool, uint32_t w, uint32_t h, int threads,
                double *frame_ms, double *sample_us)
{
    /* priority is computed inside cull (pixels with a point) and interp (holes) */
    static const char *names[P_COUNT] = { "project+z-buffer", "cull+priority", "interp+priority", "request",
                                          "insert", "total" };
    double times[P_COUNT][FRAMES];
    rendercache_desc d;
    rendercache *rc;
    rendercache_pixel_request *req = (rendercache_pixel_request *)malloc(sizeof *req * w * h);
    rendercache_sample *samples = (rendercache_sample *)malloc(sizeof *samples * w * h);
    ex_pool *pool = threads > 1 ? ex_pool_create(threads) : NULL;
    uint32_t n = 0, budget = (uint32_t)(BUDGET * w * h + 0.5);
    double shade_time = 0.0;
    uint64_t shaded = 0;
    int f, k;
    memset(&d, 0, sizeof d);
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
        shade_all(shade_pool, tracer, req, samples, n, 0, 0);
        rendercache_insert(rc, samples, n);
    }
    for (f = 0; f < FRAMES; f++) {
        rendercache_camera c = path_camera(f + 1, w, h);
        rendercache_stats st;
        double t0;
        rendercache_begin_frame(rc, &c);
        rendercache_request(rc, req, budget, &n);
        t0 = now_seconds(NULL);
        shade_all(shade_pool, tracer, req, samples, n, (uint32_t)f + 1, 1);   /* direct + one bounce */
        shade_time += now_seconds(NULL) - t0;
        shaded += n;
        rendercache_insert(rc, samples, n);
        rendercache_get_stats(rc, &st);
        times[P_PROJECT][f] = st.time_project;
        times[P_CULL][f] = st.time_cull;
        times[P_INTERP][f] = st.time_interpolate;
        times[P_REQUEST][f] = st.time_request;
        times[P_INSERT][f] = st.time_insert;
        times[P_TOTAL][f] = st.time_project + st.time_cull + st.time_interpolate +
                            st.time_request + st.time_insert;
    }
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

int main(int argc, char **argv)
{
    static const uint32_t sizes[2][2] = { { 512, 512 }, { 1024, 768 } };
    obj_scene scene;
    ex_tracer *tracer;
    ex_pool *shade_pool;
    char err[256];
    int s, threads;
    double frame_ms[2][2] = { { 0, 0 }, { 0, 0 } }, sample_us = 0.0;
    (void)argv;
    if (obj_load("examples/data/cornell_box.obj", &scene, err, sizeof err) != 0) {
        printf("cannot load the Cornell box: %s\n", err);
        return 1;
    }
    tracer = ex_tracer_create(&scene);
    shade_pool = ex_pool_create(0);
    if (!tracer || !shade_pool) return 1;
    printf("render cache per-frame overhead, Cornell box camera path, %d frames, budget %.0f%% of the pixels\n",
           FRAMES, BUDGET * 100);
    for (s = 0; s < (argc > 1 ? 1 : 2); s++)
        for (threads = 1; threads <= (argc > 1 ? 1 : 2); threads++)
            run(tracer, shade_pool, sizes[s][0], sizes[s][1], threads, &frame_ms[s][threads - 1], &sample_us);
    printf("paper (Walter et al. 2002): 62 ms per 512x512 frame on a Pentium 4 (16 fps potential, 12-14 observed)\n");
    printf("ours 512x512: %.2f ms on 1 thread (target < 8 ms), %.2f ms on 2; ratio to the paper %.1fx\n",
           frame_ms[0][0], frame_ms[0][1], 62.0 / frame_ms[0][0]);
    {
        double pixels = 512.0 * 512.0, full_ms = pixels * sample_us * 1e-3;
        double cache_ms = frame_ms[0][0] + BUDGET * pixels * sample_us * 1e-3;
        printf("512x512 with direct light + one bounce (%.2f us per sample, %d shading threads): full re-render "
               "%.0f ms, cache frame (overhead + 8%% samples) %.0f ms, %.1fx faster\n",
               sample_us, ex_pool_threads(shade_pool), full_ms, cache_ms, full_ms / cache_ms);
    }
    ex_tracer_destroy(tracer);
    ex_pool_destroy(shade_pool);
    obj_free(&scene);
    return 0;
}
