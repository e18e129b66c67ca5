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

   The caller owns the rendering (ray tracer, shading) and the base images'
   storage policy (all precomputed, or traced when first needed); this file
   owns the decomposition and the per-frame reconstruction. */
#ifndef EXAMPLES_COMMON_BASEVIEWS_H
#define EXAMPLES_COMMON_BASEVIEWS_H

#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "base.h"
#include "rendercache.h"

typedef struct ex_baseviews_desc {
    rendercache_camera fisheye;      /* every base view's kind, look direction (look_at - eye) and up;
                                        width x height = the id images of the coherence tests */
    float lo[3], hi[3];              /* the view space: a box of eyes (an axis with lo == hi is not split) */
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
    rendercache_view_space *vs;
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
    rendercache_free_memory(NULL, bv->times);
    rendercache_view_space_destroy(bv->vs);
    memset(bv, 0, sizeof *bv);
}

/* The decomposition: base views (section 4.1) and key times (section 4.2,
   with the base views and the extra cameras). Returns 0, or -1 when a call
   failed or render_ids cancelled. */
EX_FN int ex_baseviews_build(const ex_baseviews_desc *d, ex_baseviews *bv)
{
    rendercache_view_space_desc vd;
    rendercache_time_desc td;
    rendercache_camera *cams;
    double t0 = ex__baseviews_seconds();
    uint32_t v;
    memset(bv, 0, sizeof *bv);
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
    bv->seconds_views = ex__baseviews_seconds() - t0;
    t0 = ex__baseviews_seconds();
    cams = (rendercache_camera *)malloc(sizeof *cams * (bv->view_count + d->extra_count));
    if (!cams) { ex_baseviews_free(bv); return -1; }
    for (v = 0; v < d->extra_count; v++) cams[v] = d->extra_cameras[v];
    for (v = 0; v < bv->view_count; v++) rendercache_view_space_camera(bv->vs, v, &cams[d->extra_count + v]);
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
    rendercache_view_space_camera(bv->vs, view, &c);
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
   of the view-space cell around the eye (*count of them) at keys k and k+1. */
EX_FN int ex_baseviews_needs(const ex_baseviews *bv, const float eye[3], double t, uint32_t views[8],
                             uint32_t *count, uint32_t *key)
{
    if (rendercache_view_space_locate(bv->vs, eye, views, count) != RENDERCACHE_OK) return -1;
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

#endif /* EXAMPLES_COMMON_BASEVIEWS_H */
