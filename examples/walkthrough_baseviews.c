/* walkthrough_baseviews.c - a range-image walkthrough of an animated scene
   (Nimeroff, Dorsey and Rushmeier 1996): the office with a cabinet sliding
   across the room under a ceiling light.

   For each quality q (default 0.3, 0.6, 0.9):
     1. base views: a 2D view space (eyes in a 1.5 m x 0.5 m rectangle at eye
        height, looking at the desk) is subdivided until the fish-eye id
        images at the corners of every cell agree on a fraction q of their
        pixels (section 4.1);
     2. time steps: [0, 1] is halved until the id images of a fish-eye at
        the light and of every base view agree on a fraction q between
        successive times (section 4.2);
     3. base images: a 180-degree fish-eye range image per base view and
        time step, traced by the examples' ray tracer;
     4. a 30-frame camera path is reconstructed: for each frame, the base
        views at the corners of the view-space cell around the eye are
        blended to the frame's time (the cabinet moved by its transforms, so
        that it does not ghost; the paper's pixelwise blend is measured too)
        and warped into the frame's camera with foreground and background
        fill.
   Every frame is compared with a full render by the relative luminance RMS
   error (LRMS), and the example prints the shape of the paper's tables 3-5:
   more base views and time steps, and lower error, as q rises; the time to
   build the base images against the time to reconstruct a frame.

   Shading: a point light at the ceiling with shadow rays, Lambert plus the
   materials' Phong lobe (view-dependent, as in the paper's studio),
   emitters, and indirect light sampled in space and time (section 4.3):
   one bounce of irradiance at the nodes of a 0.3 m grid on every face
   (the cabinet's move with it), gathered at key times that
   rendercache_keytimes_create chooses for each q and interpolated in time
   for the base images; the full renders gather it at their own time. 3 x 3
   rays per pixel against aliasing; the gathers use one random stream per
   node at every time, so that the images hold no noise that changes with
   time and LRMS measures the reconstruction.

       cc -O2 -I. examples/walkthrough_baseviews.c -o walkthrough_baseviews -lm -lpthread
       ./walkthrough_baseviews --out build/out

   Options: --out DIR, --frames N, --size WxH (frames), --base N (base
   images N x N), --quality LIST (e.g. 0.3,0.9). Writes
   DIR/walkthrough_q<q>_NN.png (reconstructed frames),
   DIR/walkthrough_ref_NN.png (full renders), DIR/walkthrough_sheet.png
   (frame 10 of every q beside the full render) and
   DIR/walkthrough_frame10_q<q>.pfm. */
#define _POSIX_C_SOURCE 200809L /* clock_gettime, mkdir */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>

#include "examples/common/baseviews.h"
#include "examples/common/image.h"
#include "examples/common/pool.h"
#include "examples/common/trace.h"
#define RENDERCACHE_IMPLEMENTATION
#include "rendercache.h"

#define PI_F 3.14159265f
#define ID_SIZE 64            /* id images for the coherence tests */
#define MAX_Q 8

typedef struct options {
    const char *out;
    int frames, width, height, base, quality_count;
    float quality[MAX_Q];
} options;

static double seconds(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

/* ---------------------------------------------------------------------
   The scene: the office and a cabinet (0.9 x 1.4 x 0.5 m) sliding along x
   between the viewer and the desk. Range-image object ids: the office's OBJ
   groups, then the cabinet. Id images for the coherence tests are finer,
   one id per polygon, as the paper's ("a unique 32-bit color to each
   polygon").
   --------------------------------------------------------------------- */
typedef struct world {
    obj_scene office, box;
    ex_tracer *tracer;
    ex_pool *pool;
    uint32_t box_object;     /* range-image id of the cabinet = office group count */
    ex_indirect indirect;    /* the grids of the indirect light */
    float *irradiance;       /* its nodes' irradiance at the time being rendered (3 per node) */
    rendercache_keytimes *keys;   /* the indirect light at the key times of the current quality */
    const obj_scene *meshes[1];   /* the instances' meshes: the cabinet */
} world;

static const char box_obj[] =
    "v -0.5 0 -0.25\nv 0.5 0 -0.25\nv 0.5 0 0.25\nv -0.5 0 0.25\n"
    "v -0.5 1.6 -0.25\nv 0.5 1.6 -0.25\nv 0.5 1.6 0.25\nv -0.5 1.6 0.25\n"
    "f 1 2 3 4\nf 5 8 7 6\nf 1 5 6 2\nf 2 6 7 3\nf 3 7 8 4\nf 4 8 5 1\n";
static const float box_kd[3] = { 0.15f, 0.3f, 0.75f };
static const float light_pos[3] = { 2.5f, 2.7f, 2.0f };
static const float light_intensity[3] = { 16.0f, 15.0f, 13.0f };   /* W/sr */
static const float emitter_scale = 0.05f;
#define GRID_SPACING 0.3f     /* metres between the nodes of the indirect light's grids */
#define GATHER_RAYS 192       /* rays per node and gather */

/* The cabinet's object-to-world transform at time t in [0, 1]. */
static void box_at(double t, float m[12])
{
    memset(m, 0, 12 * sizeof(float));
    m[0] = m[5] = m[10] = 1.0f;
    m[3] = (float)(0.3 + 2.8 * t);
    m[11] = 2.3f;
}

static void set_time(world *w, double t)
{
    float m[12];
    box_at(t, m);
    ex_tracer_set_transform(w->tracer, 0, m);
}

/* rendercache_solve_fn: the nodes' irradiance with the cabinet where it is at t. */
static int solve_indirect(void *user, double t, float *values)
{
    world *w = (world *)user;
    set_time(w, t);
    ex_indirect_gather(&w->indirect, values);
    return 0;
}

/* Radiance towards -d from a hit: emission, the point light (Lambert and
   normalised Phong, with a shadow ray) and the indirect light of the grids
   (w->irradiance, Lambertian). */
static void shade(const world *w, const ex_trace_hit *h, const float d[3], float rgb[3])
{
    static const float none[3] = { 0, 0, 0 };
    const float *kd = box_kd, *ks = none, *ke = none;
    float ns = 1.0f, l[3], org[3], dist, cosl, vn, c = 0.0f, phong;
    int k;
    if (h->instance == EX_TRACE_STATIC) {
        const obj_material *m = &w->office.materials[w->office.tri_material[h->tri]];
        kd = m->kd; ks = m->ks; ke = m->ke; ns = m->ns;
    }
    if (!h->front) {
        rgb[0] = rgb[1] = rgb[2] = 0.0f;
        return;
    }
    ex_indirect_at(&w->indirect, w->irradiance, h, rgb);
    for (k = 0; k < 3; k++)   /* emitters shown at 5% of their radiance: bright, not 100 times the room */
        rgb[k] = emitter_scale * ke[k] + kd[k] / PI_F * rgb[k];
    for (k = 0; k < 3; k++) l[k] = light_pos[k] - h->pos[k];
    dist = sqrtf(l[0] * l[0] + l[1] * l[1] + l[2] * l[2]);
    for (k = 0; k < 3; k++) l[k] /= dist;
    cosl = l[0] * h->normal[0] + l[1] * h->normal[1] + l[2] * h->normal[2];
    if (cosl <= 0.0f) return;
    for (k = 0; k < 3; k++) org[k] = h->pos[k] + 1e-4f * h->normal[k];
    if (ex_tracer_occluded(w->tracer, org, l, dist - 2e-4f)) return;
    vn = -(d[0] * h->normal[0] + d[1] * h->normal[1] + d[2] * h->normal[2]);
    for (k = 0; k < 3; k++) c += (d[k] + 2.0f * vn * h->normal[k]) * l[k];   /* mirror of the view . light */
    phong = c > 0.0f ? (ns + 2.0f) / (2.0f * PI_F) * powf(c, ns) : 0.0f;
    for (k = 0; k < 3; k++) rgb[k] += light_intensity[k] * cosl / (dist * dist) * (kd[k] / PI_F + ks[k] * phong);
}

/* The colour of pixel (x, y): the mean over a regular grid of SUPERSAMPLE^2
   rays (the pixel's depth and object are its centre's). */
#define SUPERSAMPLE 3
static void antialiased(const world *w, const rendercache_camera *c, uint32_t x, uint32_t y, float rgb[3])
{
    int i, j, k, n = 0;
    rgb[0] = rgb[1] = rgb[2] = 0.0f;
    for (j = 0; j < SUPERSAMPLE; j++)
        for (i = 0; i < SUPERSAMPLE; i++) {
            float o[3], d[3], sample[3];
            ex_trace_hit hit;
            float px = (float)x + ((float)i + 0.5f) / SUPERSAMPLE, py = (float)y + ((float)j + 0.5f) / SUPERSAMPLE;
            if (rendercache_camera_ray(c, px, py, o, d) != RENDERCACHE_OK) continue;
            n++;
            if (!ex_tracer_intersect(w->tracer, o, d, FLT_MAX, &hit)) continue;
            shade(w, &hit, d, sample);
            for (k = 0; k < 3; k++) rgb[k] += sample[k];
        }
    for (k = 0; k < 3; k++) rgb[k] /= (float)(n ? n : 1);
}

/* ---- rendering, in parallel over rows ------------------------------ */
typedef struct render_job {
    world *w;
    const rendercache_camera *camera;
    rendercache_range_image *image;   /* range image, or */
    uint32_t *ids;                    /* id image */
} render_job;

static void render_rows(void *ctx, uint32_t row)
{
    const render_job *j = (const render_job *)ctx;
    const world *w = j->w;
    const rendercache_camera *c = j->camera;
    uint32_t x;
    for (x = 0; x < c->width; x++) {
        size_t p = (size_t)row * c->width + x;
        float o[3], d[3];
        ex_trace_hit hit;
        if (rendercache_camera_ray(c, (float)x + 0.5f, (float)row + 0.5f, o, d) != RENDERCACHE_OK) {
            if (j->ids) j->ids[p] = RENDERCACHE_NO_SAMPLE;
            else j->image->object[p] = RENDERCACHE_NO_SAMPLE;
            continue;
        }
        if (!ex_tracer_intersect(w->tracer, o, d, FLT_MAX, &hit)) {
            if (j->ids) j->ids[p] = RENDERCACHE_MISS;
            else { j->image->object[p] = RENDERCACHE_MISS; memset(j->image->rgb + 3 * p, 0, 3 * sizeof(float)); }
            continue;
        }
        if (j->ids) {   /* one id per polygon */
            j->ids[p] = hit.instance == EX_TRACE_STATIC ? w->office.tri_face[hit.tri] : w->office.face_count + hit.tri / 2;
            continue;
        }
        j->image->object[p] = hit.instance == EX_TRACE_STATIC ? w->office.face_group[w->office.tri_face[hit.tri]]
                                                              : w->box_object;
        j->image->depth[p] = hit.t;
        antialiased(w, c, x, row, j->image->rgb + 3 * p);
    }
}

static void render_range(world *w, const rendercache_camera *camera, double t, rendercache_range_image *image)
{
    render_job j;
    set_time(w, t);
    j.w = w;
    j.camera = camera;
    j.image = image;
    j.ids = NULL;
    image->time = t;
    ex_pool_parallel_for(w->pool, render_rows, &j, camera->height);
}

/* The coherence tests' callback: an id image of camera at time. */
static int render_ids(void *user, const rendercache_camera *camera, double time, uint32_t *ids)
{
    render_job j;
    world *w = (world *)user;
    set_time(w, time);
    j.w = w;
    j.camera = camera;
    j.image = NULL;
    j.ids = ids;
    ex_pool_parallel_for(w->pool, render_rows, &j, camera->height);
    return 0;
}

/* ---------------------------------------------------------------------
   Cameras: base views are fish-eyes looking at the desk (+z); the path
   crosses the view space diagonally, turning from 20 degrees left to 20
   degrees right.
   --------------------------------------------------------------------- */
static const float space_lo[3] = { 1.5f, 1.4f, 0.8f }, space_hi[3] = { 3.0f, 1.4f, 1.3f };

static rendercache_camera fisheye_template(uint32_t size)
{
    rendercache_camera c;
    memset(&c, 0, sizeof c);
    c.kind = RENDERCACHE_CAMERA_FISHEYE;
    c.eye[0] = 2.2f; c.eye[1] = 1.4f; c.eye[2] = 1.0f;
    c.look_at[0] = 2.2f; c.look_at[1] = 1.4f; c.look_at[2] = 2.0f;
    c.up[1] = 1.0f;
    c.width = c.height = size;
    return c;
}

static rendercache_camera path_camera(const options *o, int frame)
{
    rendercache_camera c;
    float s = o->frames > 1 ? (float)frame / (float)(o->frames - 1) : 0.0f, yaw = (-20.0f + 40.0f * s) * PI_F / 180.0f;
    memset(&c, 0, sizeof c);
    c.kind = RENDERCACHE_CAMERA_PERSPECTIVE;
    c.eye[0] = 1.55f + 1.4f * s;
    c.eye[1] = 1.4f;
    c.eye[2] = 0.85f + 0.4f * s;
    c.look_at[0] = c.eye[0] - sinf(yaw);   /* image right is world -x when looking at +z */
    c.look_at[1] = 1.25f;
    c.look_at[2] = c.eye[2] + cosf(yaw);
    c.up[1] = 1.0f;
    c.vfov_degrees = 55.0f;
    c.width = (uint32_t)o->width;
    c.height = (uint32_t)o->height;
    return c;
}

static double frame_time(const options *o, int frame) { return o->frames > 1 ? (double)frame / (o->frames - 1) : 0.0; }

/* ---------------------------------------------------------------------
   One quality level: decomposition, base images, reconstruction.
   --------------------------------------------------------------------- */
typedef struct level_result {
    uint32_t keys;                 /* key times of the indirect light */
    double t_keys, indirect10;     /* their gathers (s); LRMS of frame 10 with it interpolated (table 2) */
    double t_interpolate;          /* of the interpolation for frame 10 (s) */
    float q;
    uint32_t views, cells, times, rendered;
    double time_list[64];
    double t_views, t_times, t_bases, t_frames, lrms_sum, lrms_pixelwise_sum, lrms[512], frame10, frame10_pixelwise;
} level_result;

/* A decomposition (examples/common/baseviews.h) and its base images. Base
   images are traced when a frame first needs them (the views around the
   path, at the key times around the frames' times) and dropped once the
   path's time has passed them: a real system would precompute them all, for
   any path in the view space; the tables report both counts. */
static int build_level(world *w, const options *o, float q, ex_baseviews *L, level_result *r)
{
    ex_baseviews_desc d;
    rendercache_camera light;
    double start[2] = { 0.0, 1.0 };
    uint32_t k;
    memset(&d, 0, sizeof d);
    d.fisheye = fisheye_template(ID_SIZE);
    memcpy(d.lo, space_lo, sizeof d.lo);
    memcpy(d.hi, space_hi, sizeof d.hi);
    d.quality = q;
    d.view_depth = 3;   /* every axis halved at most 3 times: at most 9 x 9 views */
    d.time_depth = 5;
    d.times = start;
    d.time_count = 2;
    /* time steps: a fish-eye at the light looking down (direct light coherence) and the base views */
    light = fisheye_template(ID_SIZE);
    memcpy(light.eye, light_pos, sizeof light_pos);
    light.look_at[0] = light_pos[0]; light.look_at[1] = 0.0f; light.look_at[2] = light_pos[2];
    light.up[1] = 0.0f; light.up[2] = 1.0f;
    d.extra_cameras = &light;
    d.extra_count = 1;
    d.render_ids = render_ids;
    d.user = w;
    (void)o;
    if (ex_baseviews_build(&d, L) != 0) return 0;
    {   /* the indirect light's key times (section 4.3): apart from the base images' */
        rendercache_keytime_desc kd;
        double seconds = w->indirect.seconds;
        memset(&kd, 0, sizeof kd);
        kd.element_count = w->indirect.node_count;
        kd.components = 3;
        kd.t0 = 0.0;
        kd.t1 = 1.0;
        kd.quality = q;
        kd.max_depth = 5;
        kd.solve = solve_indirect;
        kd.user = w;
        rendercache_keytimes_destroy(w->keys);
        w->keys = NULL;
        if (rendercache_keytimes_create(&kd, &w->keys) != RENDERCACHE_OK) return 0;
        r->keys = rendercache_keytimes_count(w->keys);
        r->t_keys = w->indirect.seconds - seconds;
    }
    r->t_views = L->seconds_views;
    r->t_times = L->seconds_times;
    r->q = q;
    r->views = L->view_count;
    r->cells = rendercache_view_space_cell_count(L->vs);
    r->times = L->time_count;
    for (k = 0; k < L->time_count && k < 64; k++) r->time_list[k] = L->times[k];
    return 1;
}

/* The base image of view v at key time k, traced the first time. */
static rendercache_range_image *base_image(world *w, const options *o, ex_baseviews *L, uint32_t v, uint32_t k,
                                           level_result *r)
{
    rendercache_range_image **slot = &L->base[v * L->time_count + k];
    rendercache_camera c;
    double t0;
    if (*slot) return *slot;
    t0 = seconds();
    c = ex_baseviews_base_camera(L, v, (uint32_t)o->base);
    if (rendercache_range_image_create(&c, NULL, slot) != RENDERCACHE_OK) return NULL;
    if (rendercache_keytimes_eval(w->keys, L->times[k], w->irradiance, 3 * (size_t)w->indirect.node_count) != RENDERCACHE_OK)
        return NULL;
    render_range(w, &c, L->times[k], *slot);
    r->t_bases += seconds() - t0;
    r->rendered++;
    return *slot;
}

/* Drops the base images of the key times before key k. */
static void drop_before(ex_baseviews *L, uint32_t k)
{
    uint32_t v, i;
    for (v = 0; v < L->view_count; v++)
        for (i = 0; i < k; i++) {
            rendercache_range_image_destroy(L->base[v * L->time_count + i]);
            L->base[v * L->time_count + i] = NULL;
        }
}

/* The transforms of every range-image object at time t: the office's
   groups stay, the box moves. */
static void object_transforms(void *user, double t, float *m)
{
    const world *w = (const world *)user;
    uint32_t o;
    for (o = 0; o < w->box_object; o++) {
        memset(m + 12 * (size_t)o, 0, 12 * sizeof(float));
        m[12 * o + 0] = m[12 * o + 5] = m[12 * o + 10] = 1.0f;
    }
    box_at(t, m + 12 * (size_t)w->box_object);
}

/* Reconstructs the frame of camera at time t: the corners of the view
   space cell around the eye, each blended to t between the key times
   around it (motion-compensated, or pixelwise as the paper's pcomb), then
   all warped into the camera. *seconds_spent: the time of the blends and
   the warp. */
static int reconstruct(world *w, const options *o, ex_baseviews *L, level_result *r, ex_baseviews_reconstructor *rec,
                       const rendercache_camera *camera, double t, int motion_compensated, rendercache_range_image **blend,
                       rendercache_range_image *out, double *seconds_spent)
{
    uint32_t corners[8], n, i, k;
    if (ex_baseviews_needs(L, camera->eye, t, corners, &n, &k) != 0) return 0;
    drop_before(L, k);
    for (i = 0; i < n; i++)   /* the base images this frame needs (traced now if new; not timed as synthesis) */
        if (!base_image(w, o, L, corners[i], k, r) || !base_image(w, o, L, corners[i], k + 1, r)) return 0;
    rec->object_count = motion_compensated ? w->box_object + 1 : 0;
    if (ex_baseviews_reconstruct(L, rec, camera, t, blend, out) != 0) return 0;
    *seconds_spent = rec->seconds_blend + rec->seconds_warp;
    return 1;
}

/* ---------------------------------------------------------------------
   main
   --------------------------------------------------------------------- */
static void usage(void)
{
    puts("usage: walkthrough_baseviews [--out DIR] [--frames N] [--size WxH] [--base N] [--quality q1,q2,...]\n"
         "Reconstructs a walkthrough of the office with a moving cabinet from fish-eye base views chosen\n"
         "by coherence tests at each quality q, and compares every frame with a full render.\n"
         "Defaults: build/out, 30 frames, 320x240, base images 384x384, q = 0.3,0.6,0.9.");
}

static int parse(int argc, char **argv, options *o)
{
    int i;
    o->out = "build/out";
    o->frames = 30;
    o->width = 320;
    o->height = 240;
    o->base = 384;
    o->quality_count = 3;
    o->quality[0] = 0.3f; o->quality[1] = 0.6f; o->quality[2] = 0.9f;
    for (i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--help") || !strcmp(argv[i], "-h")) { usage(); exit(0); }
        if (i + 1 >= argc) { fprintf(stderr, "walkthrough_baseviews: %s needs a value (see --help)\n", argv[i]); return 0; }
        if (!strcmp(argv[i], "--out")) o->out = argv[++i];
        else if (!strcmp(argv[i], "--frames")) o->frames = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--base")) o->base = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--size")) {
            if (sscanf(argv[++i], "%dx%d", &o->width, &o->height) != 2) o->width = 0;
        } else if (!strcmp(argv[i], "--quality")) {
            char *s = argv[++i], *end;
            o->quality_count = 0;
            while (*s && o->quality_count < MAX_Q) {
                o->quality[o->quality_count++] = strtof(s, &end);
                if (end == s) { o->quality_count = 0; break; }
                s = *end == ',' ? end + 1 : end;
            }
        } else { fprintf(stderr, "walkthrough_baseviews: unknown option '%s' (see --help)\n", argv[i]); return 0; }
    }
    for (i = 0; i < o->quality_count; i++)
        if (!(o->quality[i] >= 0.0f && o->quality[i] <= 1.0f)) o->quality_count = 0;
    if (o->frames < 2 || o->frames > 512 || o->base < 16 || o->base > 4096 ||
        o->width < 8 || o->height < 8 || o->width > 4096 || o->height > 4096 || o->quality_count < 1) {
        fprintf(stderr, "walkthrough_baseviews: need 2..512 frames, a base size of 16..4096, a frame size "
                        "of 8..4096, qualities in [0, 1]\n");
        return 0;
    }
    return 1;
}

static int write_png(const options *o, const char *name, const float *rgb, int w, int h, float exposure, unsigned char *rgb8)
{
    char path[1024];
    snprintf(path, sizeof path, "%s/%s.png", o->out, name);
    ex_tonemap(rgb, w, h, exposure, rgb8);
    if (ex_write_png(path, w, h, rgb8) != 0) {
        fprintf(stderr, "walkthrough_baseviews: cannot write %s\n", path);
        return 0;
    }
    return 1;
}

int main(int argc, char **argv)
{
    options o;
    world w;
    char err[512], name[128];
    rendercache_range_image **refs, *out = NULL, *blend[8];
    ex_baseviews_reconstructor rec;
    rendercache_warp_desc wd;
    level_result results[MAX_Q];
    unsigned char *rgb8, *sheet_cells[MAX_Q + 1] = { 0 }, *sheet;
    float exposure;
    double t_full = 0.0;
    int f, qi, i;
    uint32_t pixels;
    if (!parse(argc, argv, &o)) return 2;
    mkdir(o.out, 0777);   /* may exist already; writing the first PNG tells */
    memset(&w, 0, sizeof w);
    if (obj_load("examples/data/office.obj", &w.office, err, sizeof err) != 0) {
        fprintf(stderr, "walkthrough_baseviews: %s (run from the repository root)\n", err);
        return 1;
    }
    if (obj_parse(box_obj, sizeof box_obj - 1, "box", NULL, &w.box, err, sizeof err) != 0) {
        fprintf(stderr, "walkthrough_baseviews: %s\n", err);
        return 1;
    }
    w.box_object = w.office.group_count;
    w.tracer = ex_tracer_create(&w.office);
    w.pool = ex_pool_create(0);
    if (!w.tracer || !w.pool || ex_tracer_add_instance(w.tracer, &w.box, box_kd) != 0) {
        fprintf(stderr, "walkthrough_baseviews: out of memory\n");
        return 1;
    }
    {   /* the grids of the indirect light: the office's faces, and the cabinet's in its own frame */
        ex_indirect_desc id;
        w.meshes[0] = &w.box;
        memset(&id, 0, sizeof id);
        id.tracer = w.tracer;
        id.scene = &w.office;
        id.meshes = w.meshes;
        id.mesh_count = 1;
        id.spacing = GRID_SPACING;
        id.rays = GATHER_RAYS;
        id.seed = 7;
        id.pool = w.pool;
        if (ex_indirect_init(&id, &w.indirect) != 0 ||
            !(w.irradiance = (float *)malloc(3 * sizeof(float) * w.indirect.node_count))) {
            fprintf(stderr, "walkthrough_baseviews: out of memory\n");
            return 1;
        }
    }
    pixels = (uint32_t)o.width * (uint32_t)o.height;
    rgb8 = (unsigned char *)malloc(3 * (size_t)pixels);
    refs = (rendercache_range_image **)calloc((size_t)o.frames, sizeof *refs);
    memset(&wd, 0, sizeof wd);
    wd.parallel_for = ex_pool_parallel_for;
    wd.parallel_user = w.pool;
    memset(&rec, 0, sizeof rec);
    rec.motion = object_transforms;
    rec.motion_user = &w;
    rec.fill = RENDERCACHE_FILL_BOTH;
    rec.blend_fill = RENDERCACHE_FILL_FOREGROUND;   /* holes stay open: the warp fills them from the other views first */
    if (!rgb8 || !refs || rendercache_warper_create(&wd, &rec.blender) != RENDERCACHE_OK ||
        rendercache_warper_create(&wd, &rec.warper) != RENDERCACHE_OK) {
        fprintf(stderr, "walkthrough_baseviews: out of memory\n");
        return 1;
    }
    printf("office, cabinet sliding from x = 0.3 to 3.1 m over t in [0, 1]; %d frames of %dx%d; fish-eye bases "
           "%dx%d; %dx%d rays per pixel; %d threads\n", o.frames, o.width, o.height, o.base, o.base, SUPERSAMPLE,
           SUPERSAMPLE, ex_pool_threads(w.pool));

    /* the full renders the reconstructions are measured against: indirect light gathered at their time */
    for (f = 0; f < o.frames; f++) {
        rendercache_camera c = path_camera(&o, f);
        double t0 = seconds();
        if (rendercache_range_image_create(&c, NULL, &refs[f]) != RENDERCACHE_OK) return 1;
        solve_indirect(&w, frame_time(&o, f), w.irradiance);
        render_range(&w, &c, frame_time(&o, f), refs[f]);
        t_full += seconds() - t0;
    }
    exposure = ex_auto_exposure(refs[0]->rgb, o.width, o.height, 0.97f);
    for (f = 0; f < o.frames; f++) {
        snprintf(name, sizeof name, "walkthrough_ref_%02d", f);
        if (!write_png(&o, name, refs[f]->rgb, o.width, o.height, exposure, rgb8)) return 1;
    }

    for (qi = 0; qi < o.quality_count; qi++) {
        ex_baseviews L;
        level_result *r = &results[qi];
        rendercache_camera bc = fisheye_template((uint32_t)o.base);
        memset(&L, 0, sizeof L);
        memset(r, 0, sizeof *r);
        if (!build_level(&w, &o, o.quality[qi], &L, r)) {
            fprintf(stderr, "walkthrough_baseviews: decomposition failed (out of memory)\n");
            return 1;
        }
        {   /* table 2: frame 10 rendered in full with the indirect light interpolated between its keys */
            int f10 = 10 % o.frames;
            rendercache_camera c = path_camera(&o, f10);
            rendercache_range_image *img = NULL;
            double t0 = seconds();
            if (rendercache_range_image_create(&c, NULL, &img) != RENDERCACHE_OK ||
                rendercache_keytimes_eval(w.keys, frame_time(&o, f10), w.irradiance, 3 * (size_t)w.indirect.node_count) !=
                    RENDERCACHE_OK)
                return 1;
            r->t_interpolate = seconds() - t0;
            render_range(&w, &c, frame_time(&o, f10), img);
            rendercache_lrms(refs[f10]->rgb, img->rgb, c.width, c.height, &r->indirect10);
            rendercache_range_image_destroy(img);
        }
        for (i = 0; i < 8; i++)
            if (rendercache_range_image_create(&bc, NULL, &blend[i]) != RENDERCACHE_OK) return 1;
        for (f = 0; f < o.frames; f++) {
            rendercache_camera c = path_camera(&o, f);
            double t = frame_time(&o, f), spent;
            if (!out && rendercache_range_image_create(&c, NULL, &out) != RENDERCACHE_OK) return 1;
            /* the paper's pixelwise time blend, for comparison */
            if (!reconstruct(&w, &o, &L, r, &rec, &c, t, 0, blend, out, &spent)) return 1;
            rendercache_lrms(refs[f]->rgb, out->rgb, c.width, c.height, &r->lrms[f]);
            r->lrms_pixelwise_sum += r->lrms[f];
            if (f == 10 % o.frames) r->frame10_pixelwise = r->lrms[f];
            if (!reconstruct(&w, &o, &L, r, &rec, &c, t, 1, blend, out, &spent)) return 1;
            r->t_frames += spent;
            rendercache_lrms(refs[f]->rgb, out->rgb, c.width, c.height, &r->lrms[f]);
            r->lrms_sum += r->lrms[f];
            snprintf(name, sizeof name, "walkthrough_q%.1f_%02d", (double)r->q, f);
            if (!write_png(&o, name, out->rgb, o.width, o.height, exposure, rgb8)) return 1;
            if (f == 10 % o.frames) {
                r->frame10 = r->lrms[f];
                snprintf(name, sizeof name, "%s/walkthrough_frame10_q%.1f.pfm", o.out, (double)r->q);
                ex_write_pfm(name, o.width, o.height, out->rgb);
                sheet_cells[qi] = (unsigned char *)malloc(3 * (size_t)pixels);
                if (sheet_cells[qi]) ex_tonemap(out->rgb, o.width, o.height, exposure, sheet_cells[qi]);
            }
        }
        for (i = 0; i < 8; i++) rendercache_range_image_destroy(blend[i]);
        ex_baseviews_free(&L);
        printf("q = %.1f: %u base views (%u cells), %u time steps: %u base images, %u traced for this path; "
               "mean LRMS %.3f (pixelwise time blend %.3f)\n", (double)r->q, r->views, r->cells, r->times,
               r->views * r->times, r->rendered, r->lrms_sum / o.frames, r->lrms_pixelwise_sum / o.frames);
    }

    /* the paper's tables, our numbers */
    printf("\nIndirect light in time (cf. table 2: LRMS .147 / .138 / .119 at q = .3 / .6 / .9)\n");
    printf("  %-8s %6s %8s %16s %18s %24s\n", "quality", "nodes", "keys", "gathers (s)", "interpolate (ms)",
           "LRMS fr 10 (full render)");
    for (qi = 0; qi < o.quality_count; qi++) {
        const level_result *r = &results[qi];
        printf("  %-8.1f %6u %8u %16.2f %18.2f %24.4f\n", (double)r->q, w.indirect.node_count, r->keys, r->t_keys,
               1e3 * r->t_interpolate, r->indirect10);
    }
    printf("\nView reconstruction (cf. table 3)\n");
    printf("  %-8s %6s %6s %14s %18s %18s %10s\n", "quality", "views", "cells", "decompose (s)", "s per base image",
           "synthesis (ms/fr)", "LRMS");
    for (qi = 0; qi < o.quality_count; qi++) {
        const level_result *r = &results[qi];
        printf("  %-8.1f %6u %6u %14.2f %18.3f %18.1f %10.3f\n", (double)r->q, r->views, r->cells, r->t_views,
               r->rendered ? r->t_bases / r->rendered : 0.0, 1e3 * r->t_frames / o.frames, r->lrms_sum / o.frames);
    }
    printf("  %-8s %6s %6s %14s %18s %18.1f %10.3f\n", "full", "-", "-", "-", "-", 1e3 * t_full / o.frames, 0.0);
    printf("\nMotion interpolation (cf. table 4)\n");
    printf("  %-8s %6s %14s %20s %20s  %s\n", "quality", "steps", "decompose (s)", "LRMS fr 10 (motion)",
           "LRMS fr 10 (pcomb)", "time list");
    for (qi = 0; qi < o.quality_count; qi++) {
        const level_result *r = &results[qi];
        char list[256];
        size_t len = 0;
        uint32_t k;
        list[0] = 0;
        for (k = 0; k < r->times && k < 64 && len + 8 < sizeof list; k++)
            len += (size_t)snprintf(list + len, sizeof list - len, "%s%.3g", k ? ", " : "", r->time_list[k]);
        printf("  %-8.1f %6u %14.2f %20.3f %20.3f  %s\n", (double)r->q, r->times, r->t_times, r->frame10,
               r->frame10_pixelwise, list);
    }
    printf("\nWalkthrough (cf. table 5; all base images: their number times the time of one)\n");
    printf("  %-8s %14s %24s %26s\n", "quality", "decompose (s)", "all base images (s)", "walkthrough, frames (s)");
    printf("  %-8s %14s %24s %26.2f\n", "full", "-", "-", t_full);
    for (qi = 0; qi < o.quality_count; qi++) {
        const level_result *r = &results[qi];
        double per_base = r->rendered ? r->t_bases / r->rendered : 0.0;
        printf("  %-8.1f %14.2f %24.2f %26.2f\n", (double)r->q, r->t_views + r->t_times,
               per_base * r->views * r->times, r->t_frames);
    }
    printf("\nLRMS per frame (cf. fig. 19)\n  frame");
    for (qi = 0; qi < o.quality_count; qi++) printf("   q=%.1f", (double)results[qi].q);
    printf("\n");
    for (f = 0; f < o.frames; f++) {
        printf("  %5d", f);
        for (qi = 0; qi < o.quality_count; qi++) printf(" %7.3f", results[qi].lrms[f]);
        printf("\n");
    }

    /* frame 10 of every quality beside the full render */
    sheet_cells[o.quality_count] = (unsigned char *)malloc(3 * (size_t)pixels);
    sheet = (unsigned char *)malloc(3 * (size_t)pixels * (size_t)(o.quality_count + 1));
    if (sheet && sheet_cells[o.quality_count]) {
        int ok = 1;
        ex_tonemap(refs[10 % o.frames]->rgb, o.width, o.height, exposure, sheet_cells[o.quality_count]);
        for (qi = 0; qi < o.quality_count; qi++) ok &= sheet_cells[qi] != NULL;
        if (ok) {
            ex_contact_sheet((const unsigned char *const *)sheet_cells, o.quality_count + 1, o.width, o.height,
                             o.quality_count + 1, sheet);
            snprintf(name, sizeof name, "%s/walkthrough_sheet.png", o.out);
            ex_write_png(name, o.width * (o.quality_count + 1), o.height, sheet);
        }
    }
    printf("\nwrote %s/walkthrough_*.png (frames, full renders, sheet of frame 10: q = ", o.out);
    for (qi = 0; qi < o.quality_count; qi++) printf("%.1f, ", (double)o.quality[qi]);
    printf("full render)\n");
    for (qi = 0; qi <= o.quality_count; qi++) free(sheet_cells[qi]);
    free(sheet);
    for (f = 0; f < o.frames; f++) rendercache_range_image_destroy(refs[f]);
    free(refs);
    free(rgb8);
    rendercache_range_image_destroy(out);
    rendercache_warper_destroy(rec.blender);
    rendercache_warper_destroy(rec.warper);
    rendercache_keytimes_destroy(w.keys);
    ex_indirect_free(&w.indirect);
    free(w.irradiance);
    ex_tracer_destroy(w.tracer);
    ex_pool_destroy(w.pool);
    obj_free(&w.office);
    obj_free(&w.box);
    return 0;
}
