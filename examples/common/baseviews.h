/* baseviews.h - range-image walkthroughs for the examples (Nimeroff, Dorsey
   and Rushmeier 1996) on top of rendercache.h part 2: base views chosen by
   the fitness of id images over a box of eye positions, key times refined
   by the same test, and frames reconstructed by blending the base images
   around a frame's time and warping them into its camera.

       ex_baseviews bv;
       ex_baseviews_desc d = {0};
       d.fisheye = template;              // kind, look direction, up; size = id images
       d.lo = ..., d.hi = ...;            // the view space
       d.quality = 0.6f; d.times = keys; d.time_count = n;
       d.render_ids = ids_callback; d.user = scene;
       ex_baseviews_build(&d, &bv);       // views and key times
       for each view v and key k: bv.base[v * bv.time_count + k] = a range image of
           ex_baseviews_base_camera(&bv, v, size) at time bv.times[k]
       for each frame:
           ex_baseviews_reconstruct(&bv, &r, camera, t, blend, out);
       ex_baseviews_free(&bv);

   A walk through a building is a path through rooms, not a box: a box of
   eyes around it holds walls, storeys and rooms the camera never enters,
   and its subdivision plans hundreds of views. Instead, the view space can
   be the route itself (d.route: the fish-eye the walk has at time t), a
   chain of one-dimensional stretches of time, each halved by the same
   fitness test where the id images at its ends differ (turns, doors); the
   views of a frame at time t are the two ends of the stretch around t, and
   neighbouring stretches share their end. Base views then grow with the
   route's length and its occlusion changes, not with its bounding box.

   The caller owns the rendering (ray tracer, shading) and the base images'
   storage policy (all precomputed, or traced when first needed); this file
   owns the decomposition and the per-frame reconstruction.

   Indirect light sampled in space and time (section 4.3), for the shading
   of base images: irradiance at the nodes of a grid on every face of the
   tracer's scene and of its moving instances, gathered by ex_indirect_gather
   at key times that rendercache_keytimes_create chooses; ex_indirect_at
   gives a hit its face's bilinear interpolation.

       ex_indirect ind;
       ex_indirect_desc id = {0};
       id.tracer = tracer; id.scene = &office; id.spacing = 0.3f; id.rays = 256;
       ex_indirect_init(&id, &ind);
       keytime desc: element_count = ind.node_count, components = 3, solve = a
           callback that poses the scene at t and calls ex_indirect_gather
       per image: rendercache_keytimes_eval(kt, t, E, 3 * ind.node_count);
           indirect radiance of a Lambertian hit = kd / pi * ex_indirect_at(&ind, E, &hit)
       ex_indirect_free(&ind); */
#ifndef EXAMPLES_COMMON_BASEVIEWS_H
#define EXAMPLES_COMMON_BASEVIEWS_H

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "base.h"
#include "obj.h"
#include "pool.h"
#include "trace.h"
#include "rendercache.h"

/* Sets the view at time t of a route: its eye, look direction and up, in
   camera, which holds ex_baseviews_desc.fisheye (its kind and size are
   kept: those of the id images). */
typedef void (*ex_baseviews_route_fn)(void *user, double t, rendercache_camera *camera);

typedef struct ex_baseviews_desc {
    rendercache_camera fisheye;      /* every base view's kind, look direction (look_at - eye) and up;
                                        width x height = the id images of the coherence tests */
    float lo[3], hi[3];              /* the view space: a box of eyes (an axis with lo == hi is not split) */
    ex_baseviews_route_fn route;     /* instead of the box (when set): the route's views, times[0] .. times[last] */
    void *route_user;
    uint32_t stretches;              /* route: equal stretches of time before the fitness test halves them (0 = 1) */
    float quality;                   /* q: id images at the ends of every cell and interval agree on this
                                        fraction of their pixels */
    uint32_t view_depth;             /* halvings of each view-space axis at most (0 = 3) */
    uint32_t time_depth;             /* halvings of each key interval at most (0 = 5) */
    const double *times;             /* the key times to refine (sorted, at least 2), e.g. {0, 1} */
    uint32_t time_count;
    const rendercache_camera *extra_cameras;   /* more cameras for the time test, e.g. at the lights */
    uint32_t extra_count;
    rendercache_render_ids_fn render_ids;
    void *user;
} ex_baseviews_desc;

typedef struct ex_baseviews {
    rendercache_view_space *vs;      /* the box (NULL for a route) */
    double *view_times;              /* a route: the views' times, increasing (NULL for the box) */
    rendercache_camera *view_cameras;   /* a route: the views' fish-eyes (id image size) */
    double *times;                   /* key times (rendercache_subdivide_time's list) */
    uint32_t time_count, view_count;
    rendercache_range_image **base;  /* view * time_count + key: set by the caller, NULL until then */
    double seconds_views, seconds_times;   /* time of the two decompositions */
} ex_baseviews;

/* The transforms (3x4 row-major, 12 floats each) of objects
   0 .. object_count-1 at time t, for the motion-compensated blend. */
typedef void (*ex_baseviews_motion_fn)(void *user, double t, float *m);

/* Everything a reconstruction uses besides the base images. */
typedef struct ex_baseviews_reconstructor {
    rendercache_warper *blender;     /* time blends (the base image size) */
    rendercache_warper *warper;      /* the warp into the frame (the frame size) */
    uint32_t object_count;           /* objects with transforms (motion compensation); 0 = pixelwise blend */
    ex_baseviews_motion_fn motion;
    void *motion_user;
    rendercache_fill fill;           /* of the final warp; 0 = BOTH */
    rendercache_fill blend_fill;     /* of the motion-compensated blends; 0 = FOREGROUND */
    double seconds_blend, seconds_warp;   /* of the last reconstruction */
} ex_baseviews_reconstructor;

static double ex__baseviews_seconds(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

EX_FN void ex_baseviews_free(ex_baseviews *bv)
{
    uint32_t i;
    if (!bv) return;
    if (bv->base)
        for (i = 0; i < bv->view_count * bv->time_count; i++) rendercache_range_image_destroy(bv->base[i]);
    free(bv->base);
    free(bv->view_times);
    free(bv->view_cameras);
    rendercache_free_memory(NULL, bv->times);
    rendercache_view_space_destroy(bv->vs);
    memset(bv, 0, sizeof *bv);
}

/* The route's view at time t, with the id images' kind and size. */
static rendercache_camera ex__baseviews_route_camera(const ex_baseviews_desc *d, double t)
{
    rendercache_camera c = d->fisheye;
    d->route(d->route_user, t, &c);
    c.kind = d->fisheye.kind;
    c.width = d->fisheye.width;
    c.height = d->fisheye.height;
    return c;
}

typedef struct ex__baseviews_route {
    const ex_baseviews_desc *d;
    ex_baseviews *bv;
    uint32_t capacity, max_depth;
    uint32_t **ids;                  /* one id image per depth: the middle of the stretch halved there */
} ex__baseviews_route;

/* Appends the view at time t. */
static int ex__baseviews_route_add(ex__baseviews_route *r, double t)
{
    ex_baseviews *bv = r->bv;
    if (bv->view_count == r->capacity) {
        uint32_t n = r->capacity ? 2 * r->capacity : 16;
        double *times = (double *)realloc(bv->view_times, sizeof *times * n);
        rendercache_camera *cams;
        if (!times) return -1;
        bv->view_times = times;
        cams = (rendercache_camera *)realloc(bv->view_cameras, sizeof *cams * n);
        if (!cams) return -1;
        bv->view_cameras = cams;
        r->capacity = n;
    }
    bv->view_times[bv->view_count] = t;
    bv->view_cameras[bv->view_count++] = ex__baseviews_route_camera(r->d, t);
    return 0;
}

/* The stretch (a, b], whose end views have id images ia and ib: halved
   while their fitness is below quality (depth halvings at most), its views
   after a appended in time order. */
static int ex__baseviews_route_split(ex__baseviews_route *r, double a, double b, const uint32_t *ia, const uint32_t *ib,
                                     uint32_t depth)
{
    const rendercache_camera *c = &r->d->fisheye;
    const uint32_t *pair[2];
    float fitness = 1.0f;
    double m = 0.5 * (a + b);
    rendercache_camera cm;
    pair[0] = ia;
    pair[1] = ib;
    if (depth < r->max_depth && rendercache_fitness(pair, 2, c->width, c->height, &fitness) != RENDERCACHE_OK) return -1;
    if (depth >= r->max_depth || fitness >= r->d->quality) return ex__baseviews_route_add(r, b);
    cm = ex__baseviews_route_camera(r->d, m);
    if (r->d->render_ids(r->d->user, &cm, r->d->times[0], r->ids[depth]) != 0) return -1;
    if (ex__baseviews_route_split(r, a, m, ia, r->ids[depth], depth + 1) != 0) return -1;
    return ex__baseviews_route_split(r, m, b, r->ids[depth], ib, depth + 1);
}

/* The views of a route: the ends of d->stretches equal stretches of
   [times[0], times[last]], each split by ex__baseviews_route_split, with
   the id images at time times[0] (as the box's). */
static int ex__baseviews_route_views(const ex_baseviews_desc *d, ex_baseviews *bv)
{
    ex__baseviews_route r;
    const double t0 = d->times[0], t1 = d->times[d->time_count - 1];
    const size_t pixels = (size_t)d->fisheye.width * d->fisheye.height;
    const uint32_t stretches = d->stretches ? d->stretches : 1;
    uint32_t *ends[2], s, i;
    rendercache_camera c;
    int result = 0;
    memset(&r, 0, sizeof r);
    r.d = d;
    r.bv = bv;
    r.max_depth = d->view_depth ? d->view_depth : 3;
    r.ids = (uint32_t **)calloc(r.max_depth + 2, sizeof *r.ids);
    if (!r.ids) return -1;
    for (i = 0; i < r.max_depth + 2; i++)
        if (!(r.ids[i] = (uint32_t *)malloc(sizeof(uint32_t) * (pixels ? pixels : 1)))) result = -1;
    ends[0] = r.ids[r.max_depth];
    ends[1] = r.ids[r.max_depth + 1];
    if (result == 0) result = ex__baseviews_route_add(&r, t0);
    c = ex__baseviews_route_camera(d, t0);
    if (result == 0 && d->render_ids(d->user, &c, t0, ends[0]) != 0) result = -1;
    for (s = 1; s <= stretches && result == 0; s++) {   /* (t(s-1), t(s)] */
        double a = t0 + (t1 - t0) * (double)(s - 1) / stretches, b = s == stretches ? t1 : t0 + (t1 - t0) * (double)s / stretches;
        uint32_t *swap;
        c = ex__baseviews_route_camera(d, b);
        if (d->render_ids(d->user, &c, t0, ends[1]) != 0 || ex__baseviews_route_split(&r, a, b, ends[0], ends[1], 0) != 0)
            result = -1;
        swap = ends[0];   /* this stretch's end begins the next */
        ends[0] = ends[1];
        ends[1] = swap;
    }
    for (i = 0; i < r.max_depth + 2; i++) free(r.ids[i]);
    free(r.ids);
    return result;
}

/* The decomposition: base views (section 4.1: the box, or the route) and
   key times (section 4.2, with the base views and the extra cameras).
   Returns 0, or -1 when a call failed or render_ids cancelled. */
EX_FN int ex_baseviews_build(const ex_baseviews_desc *d, ex_baseviews *bv)
{
    rendercache_view_space_desc vd;
    rendercache_time_desc td;
    rendercache_camera *cams;
    double t0 = ex__baseviews_seconds();
    uint32_t v;
    memset(bv, 0, sizeof *bv);
    if (d->route) {
        if (ex__baseviews_route_views(d, bv) != 0) {
            ex_baseviews_free(bv);
            return -1;
        }
    } else {
        memset(&vd, 0, sizeof vd);
        vd.camera = d->fisheye;
        memcpy(vd.lo, d->lo, sizeof vd.lo);
        memcpy(vd.hi, d->hi, sizeof vd.hi);
        vd.time = d->times[0];
        vd.quality = d->quality;
        vd.max_depth = d->view_depth ? d->view_depth : 3;
        vd.render_ids = d->render_ids;
        vd.user = d->user;
        if (rendercache_view_space_create(&vd, &bv->vs) != RENDERCACHE_OK) return -1;
        bv->view_count = rendercache_view_space_count(bv->vs);
    }
    bv->seconds_views = ex__baseviews_seconds() - t0;
    t0 = ex__baseviews_seconds();
    cams = (rendercache_camera *)malloc(sizeof *cams * (bv->view_count + d->extra_count));
    if (!cams) { ex_baseviews_free(bv); return -1; }
    for (v = 0; v < d->extra_count; v++) cams[v] = d->extra_cameras[v];
    for (v = 0; v < bv->view_count; v++) {
        if (bv->vs) rendercache_view_space_camera(bv->vs, v, &cams[d->extra_count + v]);
        else cams[d->extra_count + v] = bv->view_cameras[v];
    }
    memset(&td, 0, sizeof td);
    td.cameras = cams;
    td.camera_count = bv->view_count + d->extra_count;
    td.times = d->times;
    td.time_count = d->time_count;
    td.quality = d->quality;
    td.max_depth = d->time_depth ? d->time_depth : 5;
    td.render_ids = d->render_ids;
    td.user = d->user;
    if (rendercache_subdivide_time(&td, &bv->times, &bv->time_count) != RENDERCACHE_OK) {
        free(cams);
        ex_baseviews_free(bv);
        return -1;
    }
    free(cams);
    bv->seconds_times = ex__baseviews_seconds() - t0;
    bv->base = (rendercache_range_image **)calloc((size_t)bv->view_count * bv->time_count, sizeof *bv->base);
    if (!bv->base) { ex_baseviews_free(bv); return -1; }
    return 0;
}

/* The camera of base view `view`, size x size pixels. */
EX_FN rendercache_camera ex_baseviews_base_camera(const ex_baseviews *bv, uint32_t view, uint32_t size)
{
    rendercache_camera c;
    if (bv->vs) rendercache_view_space_camera(bv->vs, view, &c);
    else c = bv->view_cameras[view];
    c.width = c.height = size;
    return c;
}

/* The key interval [times[k], times[k+1]] that holds t (clamped). */
EX_FN uint32_t ex_baseviews_interval(const ex_baseviews *bv, double t)
{
    uint32_t k = 0;
    while (k + 2 < bv->time_count && bv->times[k + 1] <= t) k++;
    return k;
}

/* The base images a frame at eye and time t needs: the views at the corners
   of the view-space cell around the eye (*count of them; on a route the two
   ends of the stretch around t) at keys k and k+1. */
EX_FN int ex_baseviews_needs(const ex_baseviews *bv, const float eye[3], double t, uint32_t views[8],
                             uint32_t *count, uint32_t *key)
{
    if (bv->vs) {
        if (rendercache_view_space_locate(bv->vs, eye, views, count) != RENDERCACHE_OK) return -1;
    } else {
        uint32_t lo = 0, hi = bv->view_count - 1;   /* view_times[lo] <= t < view_times[hi], clamped */
        if (bv->view_count < 2) return -1;
        while (hi - lo > 1) {
            uint32_t mid = lo + (hi - lo) / 2;
            if (bv->view_times[mid] <= t) lo = mid;
            else hi = mid;
        }
        views[0] = lo;
        views[1] = hi;
        *count = 2;
    }
    *key = ex_baseviews_interval(bv, t);
    return 0;
}

/* Reconstructs the frame of camera at time t: each corner view's base
   images at the keys around t are blended to t (moving objects moved by
   their transforms when r->object_count > 0, else pixelwise as the paper's
   pcomb; holes stay open for the warp to fill from the other views), then
   all are warped into the camera. blend: 8 range images of the base size.
   The needed base images must be present. Returns 0 or -1. */
EX_FN int ex_baseviews_reconstruct(const ex_baseviews *bv, ex_baseviews_reconstructor *r,
                                   const rendercache_camera *camera, double t, rendercache_range_image **blend,
                                   rendercache_range_image *out)
{
    uint32_t corners[8], n, i, k;
    const rendercache_range_image *in[8];
    float *m = NULL;
    rendercache_motion motion;
    double s, t0 = ex__baseviews_seconds();
    int ok = 1;
    if (ex_baseviews_needs(bv, camera->eye, t, corners, &n, &k) != 0) return -1;
    for (i = 0; i < n; i++)
        if (!bv->base[corners[i] * bv->time_count + k] || !bv->base[corners[i] * bv->time_count + k + 1]) return -1;
    s = (t - bv->times[k]) / (bv->times[k + 1] - bv->times[k]);
    if (s < 0.0) s = 0.0;
    if (s > 1.0) s = 1.0;
    if (r->object_count) {
        m = (float *)malloc(3 * 12 * sizeof(float) * r->object_count);
        if (!m) return -1;
        r->motion(r->motion_user, bv->times[k], m);
        r->motion(r->motion_user, bv->times[k + 1], m + 12 * (size_t)r->object_count);
        r->motion(r->motion_user, t, m + 24 * (size_t)r->object_count);
        motion.object_count = r->object_count;
        motion.world_a = m;
        motion.world_b = m + 12 * (size_t)r->object_count;
        motion.world_t = m + 24 * (size_t)r->object_count;
    }
    for (i = 0; i < n && ok; i++) {
        const rendercache_range_image *a = bv->base[corners[i] * bv->time_count + k];
        const rendercache_range_image *b = bv->base[corners[i] * bv->time_count + k + 1];
        blend[i]->camera = a->camera;   /* the blend stays in the corner view's camera */
        if (r->object_count)
            ok = rendercache_blend_motion(r->blender, a, b, (float)s, &motion,
                                          r->blend_fill ? r->blend_fill : RENDERCACHE_FILL_FOREGROUND,
                                          blend[i]) == RENDERCACHE_OK;
        else
            ok = rendercache_blend(a, b, (float)s, blend[i]) == RENDERCACHE_OK;
        in[i] = blend[i];
    }
    free(m);
    r->seconds_blend = ex__baseviews_seconds() - t0;
    if (!ok) return -1;
    t0 = ex__baseviews_seconds();
    ok = rendercache_warp(r->warper, in, n, camera, r->fill ? r->fill : RENDERCACHE_FILL_BOTH, out) == RENDERCACHE_OK;
    r->seconds_warp = ex__baseviews_seconds() - t0;
    return ok ? 0 : -1;
}


/* ---- indirect light sampled in space and time ------------------------- */

typedef struct ex_indirect_desc {
    const ex_tracer *tracer;
    const obj_scene *scene;          /* the tracer's static scene */
    const obj_scene *const *meshes;  /* instance i's mesh, i < mesh_count: its grids move with it */
    uint32_t mesh_count;
    float spacing;                   /* grid spacing in scene units (0 = 0.25) */
    float min_area;                  /* faces smaller than this get one node at their centre (0: none) */
    uint32_t rays;                   /* gather rays per node (0 = 128) */
    uint64_t seed;
    ex_pool *pool;
} ex_indirect_desc;

typedef struct ex_indirect_face {
    float origin[3], u[3], v[3], n[3];   /* the face's plane: origin + a u + b v, normal n (object space) */
    float du, dv;                        /* node spacing along u and v */
    uint32_t nu, nv, first;              /* nodes along u and v (1 x 1: one at the centre), first node */
    uint32_t instance;                   /* EX_TRACE_STATIC or its instance */
} ex_indirect_face;

typedef struct ex_indirect {
    ex_indirect_desc desc;
    ex_indirect_face *faces;             /* the static scene's, then each mesh's */
    uint32_t face_count, *mesh_first;    /* mesh_first[i]: instance i's first face */
    uint32_t node_count;
    double seconds;                      /* time of the gathers so far */
} ex_indirect;

EX_FN void ex_indirect_free(ex_indirect *ind)
{
    free(ind->faces);
    free(ind->mesh_first);
    memset(ind, 0, sizeof *ind);
}

/* The plane frame and grid of face f of mesh m. */
static void ex__indirect_face(const obj_scene *m, uint32_t f, const ex_indirect_desc *d, ex_indirect_face *out)
{
    const uint32_t *fv = m->face_vertices + m->face_start[f], count = m->face_start[f + 1] - m->face_start[f];
    const float *p0 = m->positions + 3 * (size_t)fv[0];
    float lo[2] = { FLT_MAX, FLT_MAX }, hi[2] = { -FLT_MAX, -FLT_MAX }, area = 0.0f, l, spacing = d->spacing > 0.0f ? d->spacing : 0.25f;
    uint32_t i;
    int k;
    memset(out->n, 0, sizeof out->n);
    for (i = 1; i + 1 < count; i++) {   /* the fan's normal, area weighted */
        const float *a = m->positions + 3 * (size_t)fv[i], *b = m->positions + 3 * (size_t)fv[i + 1];
        float e0[3], e1[3];
        for (k = 0; k < 3; k++) { e0[k] = a[k] - p0[k]; e1[k] = b[k] - p0[k]; }
        out->n[0] += e0[1] * e1[2] - e0[2] * e1[1];
        out->n[1] += e0[2] * e1[0] - e0[0] * e1[2];
        out->n[2] += e0[0] * e1[1] - e0[1] * e1[0];
    }
    l = sqrtf(out->n[0] * out->n[0] + out->n[1] * out->n[1] + out->n[2] * out->n[2]);
    area = 0.5f * l;
    for (k = 0; k < 3; k++) out->n[k] = l > 0.0f ? out->n[k] / l : (k == 1 ? 1.0f : 0.0f);
    for (k = 0; k < 3; k++) out->u[k] = m->positions[3 * (size_t)fv[1] + k] - p0[k];
    l = sqrtf(out->u[0] * out->u[0] + out->u[1] * out->u[1] + out->u[2] * out->u[2]);
    for (k = 0; k < 3; k++) out->u[k] = l > 0.0f ? out->u[k] / l : (k == 0 ? 1.0f : 0.0f);
    out->v[0] = out->n[1] * out->u[2] - out->n[2] * out->u[1];
    out->v[1] = out->n[2] * out->u[0] - out->n[0] * out->u[2];
    out->v[2] = out->n[0] * out->u[1] - out->n[1] * out->u[0];
    for (i = 0; i < count; i++) {   /* the face's extent in its frame */
        const float *q = m->positions + 3 * (size_t)fv[i];
        float a = 0.0f, b = 0.0f;
        for (k = 0; k < 3; k++) { a += (q[k] - p0[k]) * out->u[k]; b += (q[k] - p0[k]) * out->v[k]; }
        lo[0] = a < lo[0] ? a : lo[0]; hi[0] = a > hi[0] ? a : hi[0];
        lo[1] = b < lo[1] ? b : lo[1]; hi[1] = b > hi[1] ? b : hi[1];
    }
    for (k = 0; k < 3; k++) out->origin[k] = p0[k] + lo[0] * out->u[k] + lo[1] * out->v[k];
    if (area < d->min_area) {   /* simplified to one node at the centre of its box */
        for (k = 0; k < 3; k++) out->origin[k] += 0.5f * (hi[0] - lo[0]) * out->u[k] + 0.5f * (hi[1] - lo[1]) * out->v[k];
        out->nu = out->nv = 1;
        out->du = out->dv = 1.0f;
        return;
    }
    out->nu = (uint32_t)ceilf((hi[0] - lo[0]) / spacing) + 1;
    out->nv = (uint32_t)ceilf((hi[1] - lo[1]) / spacing) + 1;
    out->du = out->nu > 1 ? (hi[0] - lo[0]) / (float)(out->nu - 1) : 1.0f;
    out->dv = out->nv > 1 ? (hi[1] - lo[1]) / (float)(out->nv - 1) : 1.0f;
}

/* Lays the grids. Returns 0, or -1 when out of memory. */
EX_FN int ex_indirect_init(const ex_indirect_desc *d, ex_indirect *ind)
{
    uint32_t f, m, faces = d->scene->face_count, at = 0;
    memset(ind, 0, sizeof *ind);
    ind->desc = *d;
    for (m = 0; m < d->mesh_count; m++) faces += d->meshes[m]->face_count;
    ind->faces = (ex_indirect_face *)calloc(faces ? faces : 1, sizeof *ind->faces);
    ind->mesh_first = (uint32_t *)calloc(d->mesh_count + 1, sizeof *ind->mesh_first);
    if (!ind->faces || !ind->mesh_first) { ex_indirect_free(ind); return -1; }
    for (m = 0; m <= d->mesh_count; m++) {
        const obj_scene *mesh = m == 0 ? d->scene : d->meshes[m - 1];
        if (m > 0) ind->mesh_first[m - 1] = at;
        for (f = 0; f < mesh->face_count; f++, at++) {
            ex__indirect_face(mesh, f, d, &ind->faces[at]);
            ind->faces[at].instance = m == 0 ? EX_TRACE_STATIC : m - 1;
            ind->faces[at].first = ind->node_count;
            ind->node_count += ind->faces[at].nu * ind->faces[at].nv;
        }
    }
    ind->face_count = faces;
    return 0;
}

typedef struct ex__indirect_job {
    const ex_indirect *ind;
    float *values;
    uint32_t faces_per_job;
} ex__indirect_job;

/* Irradiance at node (a, b) of face f: cosine-sampled rays, each bringing
   the direct light its hit reflects (one bounce of indirect light). */
static void ex__indirect_node(const ex_indirect *ind, const ex_indirect_face *f, uint32_t a, uint32_t b, float out[3])
{
    const ex_tracer *t = ind->desc.tracer;
    const uint32_t rays = ind->desc.rays ? ind->desc.rays : 128, node = f->first + b * f->nu + a;
    float p[3], n[3], org[3], sum[3] = { 0, 0, 0 };
    tr__vec3 tn, tb, bb;
    ex_rng rng = ex_rng_stream(ind->desc.seed, node);   /* one stream per node, at every time */
    uint32_t r;
    int k;
    for (k = 0; k < 3; k++) p[k] = f->origin[k] + (float)a * f->du * f->u[k] + (float)b * f->dv * f->v[k];
    memcpy(n, f->n, sizeof n);
    if (f->instance != EX_TRACE_STATIC) {
        const float *m = t->instances[f->instance].to_world;
        float q[3], l;
        memcpy(q, p, sizeof q);
        ex__affine_point(m, q, p);
        memcpy(q, n, sizeof q);
        ex__affine_vector(m, q, n);
        l = sqrtf(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        for (k = 0; k < 3; k++) n[k] /= l > 0.0f ? l : 1.0f;
    }
    for (k = 0; k < 3; k++) org[k] = p[k] + 1e-3f * n[k];
    tn = tr__v3_load(n);
    tr__basis(tn, &tb, &bb);
    for (r = 0; r < rays; r++) {
        tr__vec3 s = ex__sample_cosine(&rng);
        float d[3], l[3];
        ex_trace_hit h;
        s = tr__add(tr__add(tr__scale(tb, s.x), tr__scale(bb, s.y)), tr__scale(tn, s.z));
        d[0] = s.x; d[1] = s.y; d[2] = s.z;
        if (!ex_tracer_intersect(t, org, d, FLT_MAX, &h) || !h.front) continue;
        ex__tracer_direct(t, &h, d, &rng, l);
        for (k = 0; k < 3; k++) sum[k] += l[k];
    }
    for (k = 0; k < 3; k++) out[k] = (float)TR__PI * sum[k] / (float)rays;   /* E = pi mean(L) for cosine sampling */
}

static void ex__indirect_run(void *ctx, uint32_t job)
{
    const ex__indirect_job *j = (const ex__indirect_job *)ctx;
    uint32_t f, end = (job + 1) * j->faces_per_job, a, b;
    if (end > j->ind->face_count) end = j->ind->face_count;
    for (f = job * j->faces_per_job; f < end; f++) {
        const ex_indirect_face *face = &j->ind->faces[f];
        for (b = 0; b < face->nv; b++)
            for (a = 0; a < face->nu; a++) ex__indirect_node(j->ind, face, a, b, j->values + 3 * (size_t)(face->first + b * face->nu + a));
    }
}

/* Gathers the irradiance of every node (3 floats each) with the tracer as
   it is posed now. */
EX_FN void ex_indirect_gather(ex_indirect *ind, float *values)
{
    ex__indirect_job j;
    double t0 = ex__baseviews_seconds();
    j.ind = ind;
    j.values = values;
    j.faces_per_job = 1;
    ex_pool_parallel_for(ind->desc.pool, ex__indirect_run, &j, ind->face_count);
    ind->seconds += ex__baseviews_seconds() - t0;
}

/* The irradiance at a hit: its face's nodes, interpolated bilinearly at the
   hit point (clamped to the grid). */
EX_FN void ex_indirect_at(const ex_indirect *ind, const float *values, const ex_trace_hit *h, float rgb[3])
{
    const ex_tracer *t = ind->desc.tracer;
    const ex_indirect_face *f;
    float p[3], a = 0.0f, b = 0.0f, fa, fb;
    uint32_t ia, ib, i0, i1, i2, i3;
    int k;
    if (h->instance == EX_TRACE_STATIC) {
        f = &ind->faces[ind->desc.scene->tri_face[h->tri]];
        memcpy(p, h->pos, sizeof p);
    } else {
        f = &ind->faces[ind->mesh_first[h->instance] + ind->desc.meshes[h->instance]->tri_face[h->tri]];
        ex__affine_point(t->instances[h->instance].to_object, h->pos, p);
    }
    for (k = 0; k < 3; k++) {
        a += (p[k] - f->origin[k]) * f->u[k];
        b += (p[k] - f->origin[k]) * f->v[k];
    }
    a /= f->du;
    b /= f->dv;
    a = a < 0.0f ? 0.0f : a > (float)(f->nu - 1) ? (float)(f->nu - 1) : a;
    b = b < 0.0f ? 0.0f : b > (float)(f->nv - 1) ? (float)(f->nv - 1) : b;
    ia = (uint32_t)a < f->nu - 1 ? (uint32_t)a : (f->nu > 1 ? f->nu - 2 : 0);
    ib = (uint32_t)b < f->nv - 1 ? (uint32_t)b : (f->nv > 1 ? f->nv - 2 : 0);
    fa = f->nu > 1 ? a - (float)ia : 0.0f;
    fb = f->nv > 1 ? b - (float)ib : 0.0f;
    i0 = f->first + ib * f->nu + ia;
    i1 = f->nu > 1 ? i0 + 1 : i0;
    i2 = f->nv > 1 ? i0 + f->nu : i0;
    i3 = f->nv > 1 ? i1 + f->nu : i1;
    for (k = 0; k < 3; k++)
        rgb[k] = (1.0f - fb) * ((1.0f - fa) * values[3 * i0 + k] + fa * values[3 * i1 + k]) +
                 fb * ((1.0f - fa) * values[3 * i2 + k] + fa * values[3 * i3 + k]);
}

#endif /* EXAMPLES_COMMON_BASEVIEWS_H */
