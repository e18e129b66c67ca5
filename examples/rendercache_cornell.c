/* rendercache_cornell.c - the render cache (Walter, Drettakis and Parker
   1999/2002) on a camera path through the Cornell box, with a bunny walking
   across the floor. The first frame is traced in full; after that each frame
   reprojects the cache, traces only the pixels the cache asks for (about 8%
   of the image, the budget of Crespin and Peroche 2004) with direct light
   and one diffuse bounce, and writes the cache's image as a PNG. It prints,
   per frame, the cache's own time (reprojection, cull, fill, priorities,
   requests, insertion), the tracing time and the number of samples. At the
   end it traces the last view in full for comparison.

       cc -O2 -I. examples/rendercache_cornell.c -o rendercache_cornell -lm -lpthread
       ./rendercache_cornell --out build/out

   Options: --out DIR, --frames N, --size WxH, --budget FRACTION, --spp N
   (paths per requested pixel), --no-bunny, --no-predict, --late (an
   asynchronous renderer one frame behind: the samples of a frame's requests
   are inserted after the next begin_frame, each stored where its own ray
   hit). */
#define _POSIX_C_SOURCE 200809L /* clock_gettime, mkdir */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>

#include "examples/common/image.h"
#include "examples/common/pool.h"
#include "examples/common/trace.h"
#define RENDERCACHE_IMPLEMENTATION
#include "rendercache.h"

#define PI_F 3.14159265f

typedef struct options {
    const char *out;
    int frames, width, height, spp, bunny, predict, late;
    float budget;
} options;

static double seconds(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

/* ---------------------------------------------------------------------
   The animation: a slow orbit and dolly from the published viewpoint, and
   the bunny walking to and fro in front of the tall block.
   --------------------------------------------------------------------- */
static rendercache_camera camera_at(const options *o, int frame)
{
    rendercache_camera c;
    float t = o->frames > 1 ? (float)frame / (float)(o->frames - 1) : 0.0f;
    memset(&c, 0, sizeof c);
    c.kind = RENDERCACHE_CAMERA_PERSPECTIVE;
    c.eye[0] = 0.278f + 0.16f * sinf(PI_F * t);
    c.eye[1] = 0.273f + 0.06f * sinf(2.0f * PI_F * t);
    c.eye[2] = -0.8f + 0.35f * t;
    c.look_at[0] = 0.278f - 0.04f * sinf(PI_F * t);
    c.look_at[1] = 0.24f;
    c.look_at[2] = 0.28f;
    c.up[1] = 1.0f;
    c.vfov_degrees = 39.3f;
    c.width = (uint32_t)o->width;
    c.height = (uint32_t)o->height;
    return c;
}

/* Bunny to world: scaled to ~0.12 m, feet on the floor, turning as it
   walks along x at z = 0.12 (free floor between the blocks and the
   opening). lo/hi: the bunny mesh's bounds. */
static void bunny_at(const options *o, int frame, const float lo[3], const float hi[3], float m[12])
{
    float t = o->frames > 1 ? (float)frame / (float)(o->frames - 1) : 0.0f;
    float s = 0.12f / (hi[1] - lo[1]), a = 2.0f * PI_F * t, ca = cosf(a), sa = sinf(a);
    float cx = 0.5f * (lo[0] + hi[0]), cz = 0.5f * (lo[2] + hi[2]);
    float tx = 0.40f + 0.07f * sinf(2.0f * PI_F * t), tz = 0.12f;
    /* world = R_y(a) * s * (p - (cx, lo.y, cz)) + (tx, 0, tz) */
    m[0] = s * ca;  m[1] = 0.0f; m[2] = s * sa;  m[3] = tx - s * (ca * cx + sa * cz);
    m[4] = 0.0f;    m[5] = s;    m[6] = 0.0f;    m[7] = -s * lo[1];
    m[8] = -s * sa; m[9] = 0.0f; m[10] = s * ca; m[11] = tz - s * (-sa * cx + ca * cz);
}

/* ---------------------------------------------------------------------
   The sample source: the examples' ray tracer, in parallel.
   --------------------------------------------------------------------- */
typedef struct shade_job {
    const ex_tracer *tracer;
    const rendercache_pixel_request *req;
    rendercache_sample *out;
    uint32_t count, frame, width;
    int spp;
} shade_job;

/* Shades requests [64 i, 64 i + 64): spp paths along the pixel's primary
   ray (direct light and one diffuse bounce each), averaged. The cache keeps
   the primary hit as the point, with the object it belongs to. */
static void shade_batch(void *ctx, uint32_t index)
{
    const shade_job *j = (const shade_job *)ctx;
    uint32_t i, end = index * 64 + 64;
    if (end > j->count) end = j->count;
    for (i = index * 64; i < end; i++) {
        const rendercache_pixel_request *r = &j->req[i];
        rendercache_sample *s = &j->out[i];
        ex_rng rng = ex_rng_stream(j->frame, (uint64_t)r->y * j->width + r->x);
        ex_trace_hit hit;
        int k, n;
        memset(s, 0, sizeof *s);
        s->x = r->x;
        s->y = r->y;
        s->flags = r->flags;
        s->frame = r->frame;
        s->object = RENDERCACHE_MISS;
        for (n = 0; n < j->spp; n++) {
            float rgb[3];
            if (!ex_tracer_shade(j->tracer, r->org, r->dir, 1, &rng, rgb, &hit)) break;   /* a miss: black */
            for (k = 0; k < 3; k++) s->rgb[k] += rgb[k] / (float)j->spp;
            if (n == 0) {
                s->object = hit.instance == EX_TRACE_STATIC ? 0u : hit.instance + 1u;
                memcpy(s->position, hit.pos, sizeof s->position);
            }
        }
    }
}

static void shade(ex_pool *pool, const ex_tracer *t, const rendercache_pixel_request *req, rendercache_sample *out,
                  uint32_t n, uint32_t frame, const options *o)
{
    shade_job j;
    j.tracer = t;
    j.req = req;
    j.out = out;
    j.count = n;
    j.frame = frame;
    j.width = (uint32_t)o->width;
    j.spp = o->spp;
    ex_pool_parallel_for(pool, shade_batch, &j, (n + 63) / 64);
}

/* ---------------------------------------------------------------------
   main
   --------------------------------------------------------------------- */
static void usage(void)
{
    puts("usage: rendercache_cornell [--out DIR] [--frames N] [--size WxH] [--budget FRACTION] [--spp N]\n"
         "                           [--no-bunny] [--no-predict] [--late]\n"
         "Renders a camera path through the Cornell box with the render cache and writes\n"
         "DIR/rendercache_cornell_NNN.png for every frame and DIR/rendercache_cornell_full.png,\n"
         "the last view traced in full. Defaults: build/out, 48 frames, 320x320, budget 0.08, 4 spp.");
}

static int parse(int argc, char **argv, options *o)
{
    int i;
    o->out = "build/out";
    o->frames = 48;
    o->width = o->height = 320;
    o->budget = 0.08f;
    o->spp = 4;
    o->bunny = o->predict = 1;
    o->late = 0;
    for (i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--help") || !strcmp(argv[i], "-h")) { usage(); exit(0); }
        if (!strcmp(argv[i], "--no-bunny")) { o->bunny = 0; continue; }
        if (!strcmp(argv[i], "--no-predict")) { o->predict = 0; continue; }
        if (!strcmp(argv[i], "--late")) { o->late = 1; continue; }
        if (i + 1 >= argc) { fprintf(stderr, "rendercache_cornell: %s needs a value (see --help)\n", argv[i]); return 0; }
        if (!strcmp(argv[i], "--out")) o->out = argv[++i];
        else if (!strcmp(argv[i], "--frames")) o->frames = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--spp")) o->spp = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--budget")) o->budget = (float)atof(argv[++i]);
        else if (!strcmp(argv[i], "--size")) {
            if (sscanf(argv[++i], "%dx%d", &o->width, &o->height) != 2) o->width = 0;
        } else { fprintf(stderr, "rendercache_cornell: unknown option '%s' (see --help)\n", argv[i]); return 0; }
    }
    if (o->frames < 1 || o->frames > 100000 || o->spp < 1 || o->spp > 4096 || !(o->budget > 0.0f && o->budget <= 1.0f) ||
        o->width < 1 || o->height < 1 || o->width > 8192 || o->height > 8192) {
        fprintf(stderr, "rendercache_cornell: need 1..100000 frames, 1..4096 spp, a budget in (0, 1], a size up to 8192x8192\n");
        return 0;
    }
    return 1;
}

static int write_frame(const options *o, const char *name, const float *rgb, float exposure, unsigned char *rgb8)
{
    char path[1024];
    snprintf(path, sizeof path, "%s/%s.png", o->out, name);
    ex_tonemap(rgb, o->width, o->height, exposure, rgb8);
    if (ex_write_png(path, o->width, o->height, rgb8) != 0) {
        fprintf(stderr, "rendercache_cornell: cannot write %s\n", path);
        return 0;
    }
    return 1;
}

/* Every pixel of a camera traced the way the cache's samples are. */
static double full_render(ex_pool *pool, const ex_tracer *tracer, const rendercache_camera *cam, const options *o,
                          rendercache_pixel_request *req, rendercache_sample *samples, uint32_t frame, float *rgb)
{
    uint32_t p, n = (uint32_t)o->width * (uint32_t)o->height;
    double t0 = seconds();
    for (p = 0; p < n; p++) {
        req[p].x = p % (uint32_t)o->width;
        req[p].y = p / (uint32_t)o->width;
        req[p].flags = 0;
        rendercache_camera_ray(cam, (float)req[p].x + 0.5f, (float)req[p].y + 0.5f, req[p].org, req[p].dir);
    }
    shade(pool, tracer, req, samples, n, frame, o);
    for (p = 0; p < n; p++) memcpy(rgb + 3 * (size_t)p, samples[p].rgb, 3 * sizeof(float));
    return seconds() - t0;
}

int main(int argc, char **argv)
{
    options o;
    obj_scene scene, bunny;
    ex_tracer *tracer;
    ex_pool *pool;
    rendercache_desc desc;
    rendercache *rc;
    rendercache_pixel_request *req;
    rendercache_sample *samples, *pending;
    unsigned char *rgb8;
    float *full, exposure = 1.0f, lo[3], hi[3], m[12];
    char err[512], name[64];
    uint32_t pixels, budget;
    double cache_total = 0.0, trace_total = 0.0, full_time;
    uint64_t sample_total = 0;
    uint32_t waiting = 0;   /* --late: samples of the last frame, not yet inserted */
    int frame, bunny_instance = -1;
    if (!parse(argc, argv, &o)) return 2;
    mkdir(o.out, 0777);   /* may exist already; writing the first PNG tells */
    if (obj_load("examples/data/cornell_box.obj", &scene, err, sizeof err) != 0) {
        fprintf(stderr, "rendercache_cornell: %s (run from the repository root)\n", err);
        return 1;
    }
    tracer = ex_tracer_create(&scene);
    pool = ex_pool_create(0);
    if (!tracer || !pool) { fprintf(stderr, "rendercache_cornell: out of memory\n"); return 1; }
    memset(&bunny, 0, sizeof bunny);
    if (o.bunny) {
        static const float grey[3] = { 0.6f, 0.6f, 0.6f };
        if (obj_load("examples/data/bunny.obj", &bunny, err, sizeof err) != 0 || !obj_bounds(&bunny, lo, hi) ||
            (bunny_instance = ex_tracer_add_instance(tracer, &bunny, grey)) < 0) {
            fprintf(stderr, "rendercache_cornell: no bunny (%s); continuing without\n", err);
            o.bunny = 0;
        }
    }

    pixels = (uint32_t)o.width * (uint32_t)o.height;
    budget = (uint32_t)(o.budget * (float)pixels + 0.5f);
    if (budget < 1) budget = 1;
    memset(&desc, 0, sizeof desc);
    desc.width = (uint32_t)o.width;
    desc.height = (uint32_t)o.height;
    desc.object_count = 2;   /* 0: the box, 1: the bunny */
    desc.parallel_for = ex_pool_parallel_for;
    desc.parallel_user = pool;
    req = (rendercache_pixel_request *)malloc(sizeof *req * pixels);
    samples = (rendercache_sample *)malloc(sizeof *samples * pixels);
    pending = (rendercache_sample *)malloc(sizeof *pending * pixels);
    rgb8 = (unsigned char *)malloc(3 * (size_t)pixels);
    full = (float *)malloc(3 * sizeof(float) * pixels);
    if (!req || !samples || !pending || !rgb8 || !full || rendercache_create(&desc, &rc) != RENDERCACHE_OK) {
        fprintf(stderr, "rendercache_cornell: out of memory\n");
        return 1;
    }
    printf("rendercache_cornell: %dx%d, %d frames, budget %u samples per frame (%.1f%%), %d spp, %d threads%s%s\n",
           o.width, o.height, o.frames, budget, 100.0 * budget / pixels, o.spp, ex_pool_threads(pool),
           o.bunny ? ", moving bunny" : "", o.predict ? ", predictive sampling" : "");
    if (o.late) printf("samples arrive one frame late (inserted after the next begin_frame)\n");
    printf("frame  cache ms  trace ms  samples  (predicted)  filled holes  empty\n");
    for (frame = 0; frame < o.frames; frame++) {
        rendercache_camera cam = camera_at(&o, frame), next = camera_at(&o, frame + 1);
        rendercache_stats st;
        uint32_t n = 0;
        double t0, t1, t2, t3;
        int fused;
        if (o.bunny) {
            bunny_at(&o, frame, lo, hi, m);
            ex_tracer_set_transform(tracer, bunny_instance, m);
            rendercache_set_object_transform(rc, 1, m);
        }
        /* the prediction in the projection's pass over the points, unless late samples are inserted
           first (predict then counts them too) */
        fused = o.predict && frame > 0 && frame + 1 < o.frames && !(o.late && waiting);
        t0 = seconds();
        if (fused) rendercache_begin_frame_predicted(rc, &cam, &next);
        else rendercache_begin_frame(rc, &cam);
        if (o.late && waiting) {   /* last frame's samples, back from the renderer now */
            rendercache_insert(rc, pending, waiting, NULL);
            waiting = 0;
        }
        if (!fused && o.predict && frame > 0 && frame + 1 < o.frames) rendercache_predict(rc, &next);
        /* the first frame is traced in full, as in the paper */
        rendercache_request(rc, req, frame == 0 ? pixels : budget, &n);
        t1 = seconds();
        shade(pool, tracer, req, samples, n, (uint32_t)frame + 1, &o);
        t2 = seconds();
        if (o.late && frame > 0) {   /* they come back in the next frame */
            rendercache_sample *t = pending;
            pending = samples;
            samples = t;
            waiting = n;
        } else {
            rendercache_insert(rc, samples, n, NULL);
        }
        t3 = seconds();
        rendercache_get_stats(rc, &st);
        if (frame == 0) exposure = ex_auto_exposure(rendercache_image(rc), o.width, o.height, 0.97f);
        snprintf(name, sizeof name, "rendercache_cornell_%03d", frame);
        if (!write_frame(&o, name, rendercache_image(rc), exposure, rgb8)) return 1;
        printf("%5d  %8.2f  %8.2f  %7u  (%9u)  %12u  %5u\n", frame, 1e3 * (t1 - t0 + t3 - t2), 1e3 * (t2 - t1), n,
               st.predicted, st.interpolated + st.sparse, st.empty);
        if (frame > 0) {
            cache_total += t1 - t0 + t3 - t2;
            trace_total += t2 - t1;
            sample_total += n;
        }
    }
    /* the last view traced in full, for comparison */
    {
        rendercache_camera cam = camera_at(&o, o.frames - 1);
        full_time = full_render(pool, tracer, &cam, &o, req, samples, (uint32_t)o.frames + 1, full);
        if (!write_frame(&o, "rendercache_cornell_full", full, exposure, rgb8)) return 1;
    }
    if (o.frames > 1) {
        double frames = (double)(o.frames - 1);
        printf("mean per frame after the first: cache %.2f ms, tracing %.2f ms for %.0f samples; "
               "a full trace of the last view took %.1f ms (%.1fx the cache frame)\n",
               1e3 * cache_total / frames, 1e3 * trace_total / frames, (double)sample_total / frames, 1e3 * full_time,
               full_time / ((cache_total + trace_total) / frames));
    }
    printf("wrote %s/rendercache_cornell_000.png ... _%03d.png and rendercache_cornell_full.png\n", o.out, o.frames - 1);
    rendercache_destroy(rc);
    ex_tracer_destroy(tracer);
    ex_pool_destroy(pool);
    obj_free(&scene);
    if (o.bunny) obj_free(&bunny);
    free(req);
    free(samples);
    free(pending);
    free(rgb8);
    free(full);
    return 0;
}
