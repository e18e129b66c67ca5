/* rendercache.h - v0.2.0 - render cache and range-image walkthroughs - public domain or MIT, see end of file

   RENDERCACHE.H: an image-space point cache that reprojects and resamples, and range-image walkthroughs of animated scenes.

   The render cache (Walter, Drettakis and Parker 1999; Walter, Drettakis and
   Greenberg 2002) keeps the shaded points of earlier frames. Every frame it
   reprojects them into the new camera, keeps the nearest one per pixel,
   drops points that show through nearer surfaces (depth cull), fills small
   holes from neighbouring points without blending across depth edges, and
   builds a priority image (old points, sparse and empty regions). Error
   diffusion of the thresholded priority image picks the pixels that deserve
   a new ray within the caller's budget; the caller shades them with any
   renderer and inserts the results. Objects may move: each point belongs to
   an object whose transform the caller updates, and the point moves with it.

   DO THIS

       #define RENDERCACHE_IMPLEMENTATION
       #include "rendercache.h"

   in exactly one C or C++ file; include "rendercache.h" without the define
   everywhere else.

   EXAMPLE

       rendercache_desc d;
       rendercache *rc;
       memset(&d, 0, sizeof d);
       d.width = 512; d.height = 512;                 // everything else: defaults
       if (rendercache_create(&d, &rc) != RENDERCACHE_OK) return 1;
       while (running) {
           uint32_t i, n;
           rendercache_begin_frame(rc, &camera);      // reproject, cull, fill, prioritise
           rendercache_request(rc, req, budget, &n);  // the pixels that deserve a ray
           for (i = 0; i < n; i++) {
               s[i].x = req[i].x; s[i].y = req[i].y; s[i].flags = req[i].flags;
               shade(req[i].org, req[i].dir, s[i].position, s[i].rgb, &s[i].object);
           }
           rendercache_insert(rc, s, n);
           show(rendercache_image(rc));               // width * height RGB floats, top row first
       }
       rendercache_destroy(rc);

   CONFIGURATION MACROS

       RENDERCACHE_STATIC          make every function static (private to one file)
       RENDERCACHE_API             linkage of public functions (default: extern)
       RENDERCACHE_MALLOC, RENDERCACHE_FREE  replace malloc/free (define both or neither)

   FUNCTION REFERENCE

       const char *rendercache_result_string(rendercache_result r);   name of an error code
       rendercache_create(desc, &rc) / rendercache_destroy(rc)        the cache, sized from the image
       rendercache_set_object_transform(rc, object, m)                object-to-world 3x4 matrix
       rendercache_begin_frame(rc, camera)                            reproject into a new camera
       rendercache_predict(rc, next_camera)                           optional: sample what it will uncover
       rendercache_request(rc, out, max, &count)                      pixels to shade this frame
       rendercache_insert(rc, samples, n)                             shaded samples become points
       rendercache_image(rc)                                          the current RGB float image
       rendercache_priority_image(rc), rendercache_pixel_kinds(rc),
       rendercache_depth_image(rc)                                    per-pixel internals (inspection)
       rendercache_get_stats(rc, &stats)                              counts and phase times of the frame
       rendercache_clear(rc)                                          forget every point
       rendercache_camera_ray(camera, px, py, org, dir)               primary ray through an image point
       rendercache_camera_project(camera, p, &px, &py, &depth)        world point to image point

   CONVENTIONS

       Pixel (x, y) covers [x, x+1) x [y, y+1) of the image plane, y = 0 is the
       top row; its primary ray passes through (x + 0.5, y + 0.5). Images are
       row-major, top row first, linear RGB floats. Depth is the distance from
       the eye along the ray. One rendercache object is used by one thread at
       a time; the per-frame work runs in parallel through desc.parallel_for
       and gives bit-identical results for any thread count.

   HOW A FRAME WORKS (and which published step each part is)

       begin_frame: every point is projected into the camera and z-buffered,
       one point per pixel (WDP99 reprojection); a point much farther than
       the average depth of its 3x3 neighbourhood, with nearer points on
       opposite sides, is dropped (WDP99 depth cull); holes are filled by a
       3x3 tent filter, or a 7x7 one where points are sparse (WDG02), from
       the nearest or the farthest depth layer only, never a blend; the
       priority image ranks old points (age, faster for moving objects,
       times the sample's priority_scale) below holes (the fewer points
       around, the higher), and pixels with nothing near at 1 (WDP99).
       request: the levels of the priority image above a threshold are all
       requested, the level at the threshold gets the rest of the budget,
       spread by Floyd-Steinberg error diffusion (WDP99); with predict, up to
       desc.predict_fraction of the budget goes to the holes of the next
       camera (WDG02 predictive sampling). insert: a sample replaces the
       point its pixel showed, or the oldest point not visible (clock).

   LIMITS

       Image up to 2^28 pixels, cache up to 2^31 points, up to 2^24 objects.
       Memory: 40 bytes per cache point (2 per pixel by default) and about 71
       bytes per pixel, 95 with parallel_for: 40 MB for 512x512. Point
       colours are fixed when they are inserted (the cache ages them so that
       they get refreshed); view-dependent shading changes only as points are
       resampled, as in the paper. Error diffusion is sequential by nature and
       runs on the calling thread; the rest of a frame runs in parallel.

   PAPER

       Bruce Walter, George Drettakis and Steven Parker, Interactive Rendering using the Render Cache, EGWR 1999; Bruce Walter, George Drettakis and Donald P. Greenberg, Enhancing and Optimizing the Render Cache, EGWR 2002; Nimeroff, Dorsey and Rushmeier, Implementation and Analysis of an Image-Based Global Illumination Framework for Animated Environments, IEEE TVCG 2(4), 1996. The render cache as used by Rodolphe Crespin and Bernard Peroche, Light Vectors for a Moving Observer, WSCG 2004 (sections 2.2 and 4.1).
*/
#ifndef RENDERCACHE_H
#define RENDERCACHE_H

#include <stddef.h>
#include <stdint.h>

#define RENDERCACHE_VERSION_MAJOR 0
#define RENDERCACHE_VERSION_MINOR 2
#define RENDERCACHE_VERSION_PATCH 0

#ifndef RENDERCACHE_API
#  ifdef RENDERCACHE_STATIC
#    define RENDERCACHE_API static
#  else
#    define RENDERCACHE_API extern
#  endif
#endif

#ifdef __cplusplus
extern "C" {
#endif

/* Every fallible function returns one of these; zero is success. */
typedef enum rendercache_result {
    RENDERCACHE_OK = 0,
    RENDERCACHE_ERROR_INVALID_ARGUMENT,  /* NULL pointer, zero count, NaN, index out of range, ... */
    RENDERCACHE_ERROR_OUT_OF_MEMORY,     /* the allocator returned NULL, or a size overflowed */
    RENDERCACHE_ERROR_CORRUPT_DATA,      /* serialized data is truncated or fails its checks */
    RENDERCACHE_ERROR_VERSION,           /* serialized data has an unsupported format version */
    RENDERCACHE_ERROR_CANCELLED,         /* the progress callback asked to stop */
    RENDERCACHE_ERROR_IO                 /* a read or write callback failed */
} rendercache_result;

/* Object id of a sample whose ray left the scene: it becomes a background
   point at infinity along the ray. */
#define RENDERCACHE_MISS 0xFFFFFFFFu

/* rendercache_pixel_request.flags: the ray belongs to the predicted camera
   given to rendercache_predict, not to the current one. */
#define RENDERCACHE_REQUEST_PREDICTED 1u

typedef struct rendercache rendercache;

typedef struct rendercache_allocator {
    void *(*alloc)(size_t size, void *user);  /* NULL: RENDERCACHE_MALLOC */
    void (*free)(void *ptr, void *user);      /* NULL: RENDERCACHE_FREE */
    void *user;
} rendercache_allocator;

typedef void (*rendercache_job_fn)(void *ctx, uint32_t index);

/* 0 is the pinhole camera; the range-image walkthroughs add wide-angle kinds. */
typedef enum rendercache_camera_kind {
    RENDERCACHE_CAMERA_PERSPECTIVE = 0
} rendercache_camera_kind;

/* A look-at camera: the image's vertical axis spans vfov_degrees, pixels are
   square, "up" need not be orthogonal to the view direction (it is
   orthogonalised), right = forward x up. */
typedef struct rendercache_camera {
    rendercache_camera_kind kind;
    float eye[3];
    float look_at[3];        /* a point on the view axis, not the eye */
    float up[3];             /* not parallel to look_at - eye */
    float vfov_degrees;      /* perspective: in (0, 180) */
    uint32_t width, height;  /* pixels; must equal the cache's image size */
} rendercache_camera;

typedef struct rendercache_desc {
    uint32_t width, height;      /* image size in pixels (required) */
    float points_per_pixel;      /* cache capacity = points_per_pixel * width * height; default 2 */
    uint32_t object_count;       /* object ids 0 .. object_count-1, each with a transform; default 256 */
    float depth_tolerance;       /* relative depth step that counts as a discontinuity (depth cull,
                                    interpolation layers); default 0.1 */
    uint32_t age_ramp_frames;    /* a point's priority grows with age for this many frames; default 32 */
    uint32_t moving_age_step;    /* age a point gains per frame while its object moves; default 4 */
    uint32_t sparse_neighbours;  /* a hole with fewer points in its 3x3 neighbourhood uses the wide
                                    filter; default 2 (1..8) */
    uint32_t wide_radius;        /* half width of the wide filter: default 3 (7x7), at most 7 */
    float predict_fraction;      /* share of the budget for predicted samples when
                                    rendercache_predict was called; default 0.25, at most 1 */
    float background[3];         /* colour of pixels nothing covers; default black */
    rendercache_allocator allocator;
    void (*parallel_for)(void *user, rendercache_job_fn job, void *ctx, uint32_t count);
    void *parallel_user;
    double (*clock)(void *user); /* optional: seconds, to time the phases in rendercache_stats */
    void *clock_user;
    void (*log)(void *user, const char *message); /* optional details on errors */
    void *log_user;
} rendercache_desc;

/* A pixel that deserves a new sample, with its primary ray (unit dir). */
typedef struct rendercache_pixel_request {
    uint32_t x, y;
    uint32_t flags;          /* RENDERCACHE_REQUEST_PREDICTED or 0 */
    float org[3], dir[3];
} rendercache_pixel_request;

/* A shaded sample: copy x, y and flags from its request. */
typedef struct rendercache_sample {
    uint32_t x, y;           /* the requested pixel */
    uint32_t flags;          /* the request's flags */
    uint32_t object;         /* id of the object hit (< desc.object_count), or RENDERCACHE_MISS */
    float position[3];       /* world-space hit point; ignored for a miss */
    float rgb[3];            /* radiance towards the eye, linear RGB */
    float priority_scale;    /* multiplies the point's priority, e.g. lightvec_priority(1, W);
                                0 means 1 */
} rendercache_sample;

/* What a pixel of the current image shows (rendercache_pixel_kinds). */
typedef enum rendercache_pixel_kind {
    RENDERCACHE_PIXEL_POINT = 0,     /* a cached point */
    RENDERCACHE_PIXEL_INTERPOLATED,  /* a hole filled by the 3x3 filter */
    RENDERCACHE_PIXEL_SPARSE,        /* a hole filled by the wide filter */
    RENDERCACHE_PIXEL_EMPTY          /* nothing near: background colour */
} rendercache_pixel_kind;

typedef struct rendercache_stats {
    uint64_t frame;              /* begin_frame calls so far */
    uint32_t capacity;           /* cache slots */
    uint32_t live_points;        /* slots holding a point */
    uint32_t projected;          /* points that landed inside the image this frame */
    uint32_t visible;            /* pixels showing a point after z-buffer and depth cull */
    uint32_t culled;             /* z-buffer winners dropped by the depth cull */
    uint32_t interpolated;       /* holes filled by the 3x3 filter */
    uint32_t sparse;             /* holes filled by the wide filter */
    uint32_t empty;              /* pixels nothing covers */
    uint32_t requested;          /* requests handed out since begin_frame (all kinds) */
    uint32_t predicted;          /* of which for the predicted camera */
    uint32_t inserted;           /* samples accepted since begin_frame */
    uint32_t replaced;           /* of which replaced the point their pixel showed */
    uint32_t evicted;            /* of which overwrote a point not visible in this frame */
    uint32_t rejected;           /* samples ignored since begin_frame (bad values or pixel) */
    /* seconds spent in each phase of the last frame (0 without desc.clock) */
    double time_project;         /* projection and z-buffer of every point */
    double time_cull;            /* depth cull, with the colour and priority of the pixels showing points */
    double time_interpolate;     /* hole filling, with the priority of the holes */
    double time_predict;         /* rendercache_predict */
    double time_request;         /* threshold and error diffusion (all request calls) */
    double time_insert;
} rendercache_stats;

RENDERCACHE_API const char *rendercache_result_string(rendercache_result r);

/* Creates a cache for images of desc->width x desc->height pixels. Every
   buffer the per-frame work needs is allocated here, none later. */
RENDERCACHE_API rendercache_result rendercache_create(const rendercache_desc *desc, rendercache **out);
RENDERCACHE_API void rendercache_destroy(rendercache *rc);

/* Sets the object-to-world transform of an object: m is 3x4 row-major
   (world = m[0..2] . p + m[3], ...). Its points move with it from the next
   begin_frame on, and age faster while the transform keeps changing. Every
   object starts at the identity. Singular or non-finite matrices are
   rejected. */
RENDERCACHE_API rendercache_result rendercache_set_object_transform(rendercache *rc, uint32_t object,
                                                                    const float m[12]);

/* Starts a frame: ages the points, projects them into the camera, z-buffers,
   depth-culls, fills holes and builds the priority image. */
RENDERCACHE_API rendercache_result rendercache_begin_frame(rendercache *rc, const rendercache_camera *camera);

/* Predictive sampling (2002): projects the cache into the camera the caller
   expects next; rendercache_request then spends up to desc.predict_fraction
   of its budget on the holes that camera would see (requests flagged
   RENDERCACHE_REQUEST_PREDICTED, rays of the predicted camera). Valid until
   the next begin_frame. */
RENDERCACHE_API rendercache_result rendercache_predict(rendercache *rc, const rendercache_camera *next);

/* Chooses up to max pixels to sample by error diffusion of the thresholded
   priority image and writes them to out (*count of them). A second call in
   the same frame returns the next most important pixels. */
RENDERCACHE_API rendercache_result rendercache_request(rendercache *rc, rendercache_pixel_request *out,
                                                       uint32_t max, uint32_t *count);

/* Adds shaded samples as points. A sample for a current-frame pixel
   replaces the point that pixel shows (and updates the image at once);
   other samples take the slot of the oldest point not visible in this
   frame. Samples with non-finite values, unknown objects or pixels outside
   the image are ignored and counted in stats.rejected. n = 0 does nothing. */
RENDERCACHE_API rendercache_result rendercache_insert(rendercache *rc, const rendercache_sample *samples,
                                                      uint32_t n);

/* The current image: width * height * 3 floats, valid until the next call
   that changes the cache. */
RENDERCACHE_API const float *rendercache_image(const rendercache *rc);
/* Per-pixel priority in [0, 1] (1: nothing to show), after requests zeroed the chosen pixels. */
RENDERCACHE_API const float *rendercache_priority_image(const rendercache *rc);
/* Per-pixel rendercache_pixel_kind values. */
RENDERCACHE_API const unsigned char *rendercache_pixel_kinds(const rendercache *rc);
/* Per-pixel depth of the point shown (distance from the eye; 1e18 for a
   background point), FLT_MAX where the pixel shows no point. Computed on
   each call. */
RENDERCACHE_API const float *rendercache_depth_image(rendercache *rc);

RENDERCACHE_API void rendercache_get_stats(const rendercache *rc, rendercache_stats *out);

/* Forgets every point (e.g. after lights changed); transforms are kept. */
RENDERCACHE_API void rendercache_clear(rendercache *rc);

/* The primary ray through image point (px, py) (pixel centres at +0.5):
   org = eye, dir = unit direction. */
RENDERCACHE_API rendercache_result rendercache_camera_ray(const rendercache_camera *camera, float px, float py,
                                                          float org[3], float dir[3]);
/* Projects world point p: returns 1 and the image point and the distance
   from the eye when p lands inside the image, else 0. */
RENDERCACHE_API int rendercache_camera_project(const rendercache_camera *camera, const float p[3],
                                               float *px, float *py, float *depth);

#ifdef __cplusplus
}
#endif
#endif /* RENDERCACHE_H */

/* ------------------------------------------------------------------------ */
#if defined(RENDERCACHE_IMPLEMENTATION) && !defined(RENDERCACHE_IMPLEMENTATION_INCLUDED)
#define RENDERCACHE_IMPLEMENTATION_INCLUDED

#if defined(RENDERCACHE_MALLOC) != defined(RENDERCACHE_FREE)
#  error "rendercache.h: define both RENDERCACHE_MALLOC and RENDERCACHE_FREE, or neither"
#endif
#ifndef RENDERCACHE_MALLOC
#  include <stdlib.h>
#  define RENDERCACHE_MALLOC(size) malloc(size)
#  define RENDERCACHE_FREE(ptr) free(ptr)
#endif

#include <string.h>
#include <math.h>
#include <float.h>

/* ======================================================================
   1. allocation
   ---------------------------------------------------------------------- */
/* Both callbacks or neither: a lone alloc would leak through RENDERCACHE_FREE. */
static int rendercache__allocator_valid(const rendercache_allocator *a)
{
    return (a->alloc == NULL) == (a->free == NULL);
}

static void *rendercache__alloc(const rendercache_allocator *a, size_t size)
{
    if (size == 0) size = 1;
    return a->alloc ? a->alloc(size, a->user) : RENDERCACHE_MALLOC(size);
}

/* count * item bytes, or NULL when the product overflows. */
static void *rendercache__alloc_array(const rendercache_allocator *a, size_t count, size_t item)
{
    if (item && count > SIZE_MAX / item) return NULL;
    return rendercache__alloc(a, count * item);
}

static void rendercache__free(const rendercache_allocator *a, void *p)
{
    if (!p) return;
    if (a->free) a->free(p, a->user);
    else RENDERCACHE_FREE(p);
}

/* Zero means default: the documented default replaces a zero field. */
#define rendercache__def(v, d) ((v) ? (v) : (d))

/* ======================================================================
   2. small math
   ---------------------------------------------------------------------- */
static int rendercache__iabs(int v) { return v < 0 ? -v : v; }
static int rendercache__finite3(const float *p) { return isfinite(p[0]) && isfinite(p[1]) && isfinite(p[2]); }

static double rendercache__dot3d(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static void rendercache__cross3d(const double a[3], const double b[3], double out[3])
{
    out[0] = a[1] * b[2] - a[2] * b[1];
    out[1] = a[2] * b[0] - a[0] * b[2];
    out[2] = a[0] * b[1] - a[1] * b[0];
}

/* Normalises v in place; returns 0 when v is zero or not finite. */
static int rendercache__normalize3d(double v[3])
{
    double l = sqrt(rendercache__dot3d(v, v));
    if (!(l > 0.0) || !isfinite(l)) return 0;
    v[0] /= l; v[1] /= l; v[2] /= l;
    return 1;
}

/* y = m x for a 3x4 row-major affine matrix (w = 1). */
static void rendercache__affine(const float m[12], const float x[3], float y[3])
{
    y[0] = m[0] * x[0] + m[1] * x[1] + m[2] * x[2] + m[3];
    y[1] = m[4] * x[0] + m[5] * x[1] + m[6] * x[2] + m[7];
    y[2] = m[8] * x[0] + m[9] * x[1] + m[10] * x[2] + m[11];
}

/* ======================================================================
   7. jobs: the caller's parallel_for, or a serial loop
   ---------------------------------------------------------------------- */
static void rendercache__run_jobs(void (*parallel_for)(void *, rendercache_job_fn, void *, uint32_t), void *user,
                                  rendercache_job_fn job, void *ctx, uint32_t count)
{
    uint32_t i;
    if (count == 0) return;
    if (parallel_for) { parallel_for(user, job, ctx, count); return; }
    for (i = 0; i < count; i++) job(ctx, i);
}

/* ======================================================================
   8. cameras: world <-> image mapping shared by the render cache and the
   range-image warps. A view is a validated camera with its orthonormal
   basis; every mapping goes through camera space (right, up, forward
   components), so a new camera kind only adds a case to view_to_pixel and
   view_from_pixel.
   ---------------------------------------------------------------------- */
#define RENDERCACHE__NONE 0xFFFFFFFFu        /* no point / no element */
#define RENDERCACHE__FAR 1e18f               /* distance of background points, "at infinity" */
#define RENDERCACHE__FAR2 1e36f              /* its square: depths are compared squared */
#define RENDERCACHE__MAX_PIXELS (1u << 28)
#define RENDERCACHE__MAX_CAPACITY (1u << 31)
#define RENDERCACHE__MAX_OBJECTS (1u << 24)

typedef struct rendercache__view {
    rendercache_camera_kind kind;
    float eye[3];
    float axis[3][3];        /* rows: right, up, forward; orthonormal */
    float focal;             /* perspective: pixels per unit of tangent */
    float cx, cy;            /* image centre in pixels */
    uint32_t width, height;
} rendercache__view;

/* Validates a camera and builds its view; returns 0 on bad input. */
static int rendercache__view_init(rendercache__view *v, const rendercache_camera *c)
{
    double f[3], u[3], r[3], half;
    int k;
    if (!c || c->kind != RENDERCACHE_CAMERA_PERSPECTIVE) return 0;
    if (!rendercache__finite3(c->eye) || !rendercache__finite3(c->look_at) || !rendercache__finite3(c->up)) return 0;
    if (c->width == 0 || c->height == 0 || (uint64_t)c->width * c->height > RENDERCACHE__MAX_PIXELS) return 0;
    if (!(c->vfov_degrees > 0.0f && c->vfov_degrees < 180.0f)) return 0;
    for (k = 0; k < 3; k++) {
        f[k] = (double)c->look_at[k] - (double)c->eye[k];
        u[k] = c->up[k];
    }
    if (!rendercache__normalize3d(f)) return 0;
    rendercache__cross3d(f, u, r);
    if (!rendercache__normalize3d(r)) return 0;     /* up parallel to the view direction */
    rendercache__cross3d(r, f, u);
    half = 0.5 * (double)c->vfov_degrees * 3.14159265358979323846 / 180.0;
    v->kind = c->kind;
    for (k = 0; k < 3; k++) {
        v->eye[k] = c->eye[k];
        v->axis[0][k] = (float)r[k];
        v->axis[1][k] = (float)u[k];
        v->axis[2][k] = (float)f[k];
    }
    v->width = c->width;
    v->height = c->height;
    v->cx = 0.5f * (float)c->width;
    v->cy = 0.5f * (float)c->height;
    v->focal = (float)(0.5 * (double)c->height / tan(half));
    return 1;
}

/* Camera-space vector c (a point, or a direction for points at infinity) to
   continuous image coordinates. Returns 0 when it does not land inside the
   image (behind the camera, outside the frame, NaN). */
static int rendercache__view_to_pixel(const rendercache__view *v, const float c[3], float *px, float *py)
{
    float x, y;
    switch (v->kind) {
    case RENDERCACHE_CAMERA_PERSPECTIVE:
    default:
        if (!(c[2] > 0.0f)) return 0;
        x = v->cx + v->focal * c[0] / c[2];
        y = v->cy - v->focal * c[1] / c[2];
        break;
    }
    if (!(x >= 0.0f && x < (float)v->width && y >= 0.0f && y < (float)v->height)) return 0;
    *px = x;
    *py = y;
    return 1;
}

/* Image point to a unit camera-space direction. */
static void rendercache__view_from_pixel(const rendercache__view *v, float px, float py, float c[3])
{
    float l;
    switch (v->kind) {
    case RENDERCACHE_CAMERA_PERSPECTIVE:
    default:
        c[0] = (px - v->cx) / v->focal;
        c[1] = (v->cy - py) / v->focal;
        c[2] = 1.0f;
        break;
    }
    l = sqrtf(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
    c[0] /= l; c[1] /= l; c[2] /= l;
}

/* World vector to camera space (rotation only). */
static void rendercache__view_rotate(const rendercache__view *v, const float w[3], float c[3])
{
    int k;
    for (k = 0; k < 3; k++) c[k] = v->axis[k][0] * w[0] + v->axis[k][1] * w[1] + v->axis[k][2] * w[2];
}

/* The primary ray direction (world, unit) through image point (px, py). */
static void rendercache__view_ray(const rendercache__view *v, float px, float py, float dir[3])
{
    float c[3], l;
    int k;
    rendercache__view_from_pixel(v, px, py, c);
    for (k = 0; k < 3; k++) dir[k] = c[0] * v->axis[0][k] + c[1] * v->axis[1][k] + c[2] * v->axis[2][k];
    l = sqrtf(dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]);
    dir[0] /= l; dir[1] /= l; dir[2] /= l;
}

/* Object-to-camera matrix: the view's [R | -R eye] times the object's
   object-to-world matrix m, composed in double. */
static void rendercache__view_compose(const rendercache__view *v, const float m[12], float out[12])
{
    int i, j;
    for (i = 0; i < 3; i++) {
        const float *r = v->axis[i];
        for (j = 0; j < 3; j++)
            out[4 * i + j] = (float)((double)r[0] * m[j] + (double)r[1] * m[4 + j] + (double)r[2] * m[8 + j]);
        out[4 * i + 3] = (float)((double)r[0] * ((double)m[3] - v->eye[0]) +
                                 (double)r[1] * ((double)m[7] - v->eye[1]) +
                                 (double)r[2] * ((double)m[11] - v->eye[2]));
    }
}

/* ======================================================================
   9. splat: many elements (cache points, range-image pixels) into one
   z-buffer (the reprojection and z-buffer step of Walter et al. 1999),
   keeping per pixel the nearest element, its depth and a payload of four
   floats (colour and one more value) copied as it wins, so that nothing has
   to be gathered from the elements afterwards.
   Parallel and deterministic: when the caller gives parallel_for, the
   elements are split into RENDERCACHE__SPLAT_JOBS ranges, each z-buffered
   into its own raster, and the rasters are merged tile by tile. The winner
   of a pixel is the least (depth, element index) in every case, so the
   result does not depend on the split or on the thread count. (Sorting the
   elements into image bands first, as the tiled cache of Walter et al. 2002
   does, let any number of threads share the z-buffer but cost three times
   as much memory traffic here.)
   ---------------------------------------------------------------------- */
#define RENDERCACHE__SPLAT_JOBS 2u   /* partial z-buffers when running in parallel */
#define RENDERCACHE__BATCH 256u      /* elements per source call */
#define RENDERCACHE__TILE_ROWS 8u    /* image rows per tile job */

/* Projects elements [begin, end): pix[i - begin] = y * width + x of the
   pixel it lands in, or RENDERCACHE__NONE; depth[...] its distance. */
typedef void (*rendercache__source_fn)(const void *src, uint32_t begin, uint32_t end, uint32_t *pix, float *depth);
/* Payload of elements [begin, end): 4 floats each, for those whose pix is
   not RENDERCACHE__NONE. */
typedef void (*rendercache__payload_fn)(const void *src, uint32_t begin, uint32_t end, const uint32_t *pix,
                                        float *payload);

/* The result of a splat: per pixel the nearest depth (FLT_MAX when empty),
   the element (RENDERCACHE__NONE when empty) and its payload. */
typedef struct rendercache__raster {
    float *depth;
    uint32_t *index;
    float *payload;          /* 4 per pixel */
} rendercache__raster;

/* One job's z-buffer: per pixel the key (depth bits << 32 | element; depths
   are non-negative, so their bits order as the values do, and one compare
   settles depth and then index) and the payload. One random access per test. */
typedef struct rendercache__zbuffer {
    uint64_t *key;
    float *payload;
} rendercache__zbuffer;
#define RENDERCACHE__EMPTY_KEY 0xFFFFFFFFFFFFFFFFull

typedef struct rendercache__splat {
    uint32_t width, height, pixel_count, tile_count;
    uint32_t jobs;           /* z-buffers allocated: 1, or SPLAT_JOBS with parallel_for */
    rendercache__raster final;                        /* payload is job 0's */
    rendercache__zbuffer zb[RENDERCACHE__SPLAT_JOBS];
    uint32_t projected;      /* elements that landed in the image in the last run */
    uint32_t job_projected[RENDERCACHE__SPLAT_JOBS];
} rendercache__splat;

static void rendercache__splat_free(rendercache__splat *s, const rendercache_allocator *a)
{
    uint32_t j;
    rendercache__free(a, s->final.depth);
    rendercache__free(a, s->final.index);
    for (j = 0; j < RENDERCACHE__SPLAT_JOBS; j++) {
        rendercache__free(a, s->zb[j].key);
        rendercache__free(a, s->zb[j].payload);
    }
    memset(s, 0, sizeof *s);
}

/* Allocates a splat for a width x height raster, run by jobs (1 or
   RENDERCACHE__SPLAT_JOBS) z-buffers. Returns 0, or -1 when out of memory. */
static int rendercache__splat_alloc(rendercache__splat *s, uint32_t width, uint32_t height, uint32_t jobs,
                                    const rendercache_allocator *a)
{
    uint32_t j;
    int failed;
    memset(s, 0, sizeof *s);
    s->jobs = jobs;
    s->width = width;
    s->height = height;
    s->pixel_count = width * height;
    s->tile_count = (height + RENDERCACHE__TILE_ROWS - 1) / RENDERCACHE__TILE_ROWS;
    s->final.depth = (float *)rendercache__alloc_array(a, s->pixel_count, sizeof(float));
    s->final.index = (uint32_t *)rendercache__alloc_array(a, s->pixel_count, sizeof(uint32_t));
    failed = !s->final.depth || !s->final.index;
    for (j = 0; j < jobs; j++) {
        s->zb[j].key = (uint64_t *)rendercache__alloc_array(a, s->pixel_count, sizeof(uint64_t));
        s->zb[j].payload = (float *)rendercache__alloc_array(a, s->pixel_count, 4 * sizeof(float));
        failed |= !s->zb[j].key || !s->zb[j].payload;
    }
    s->final.payload = s->zb[0].payload;
    if (failed) rendercache__splat_free(s, a);
    return failed ? -1 : 0;
}

typedef struct rendercache__splat_job {
    rendercache__splat *s;
    rendercache__source_fn source;
    rendercache__payload_fn payload;   /* NULL: no payload */
    const void *src;
    uint32_t element_count, jobs;
} rendercache__splat_job;

static uint64_t rendercache__key(float depth, uint32_t element)
{
    uint32_t bits;
    memcpy(&bits, &depth, sizeof bits);
    return (uint64_t)bits << 32 | element;
}

/* Job j: z-buffers its range of elements into its own z-buffer. */
static void rendercache__splat_range(void *ctx, uint32_t j)
{
    const rendercache__splat_job *job = (const rendercache__splat_job *)ctx;
    rendercache__splat *s = job->s;
    uint64_t *key = s->zb[j].key;
    float *payload = s->zb[j].payload;
    uint32_t pix[RENDERCACHE__BATCH], begin, end, b, i, projected = 0;
    float d[RENDERCACHE__BATCH], pay[4 * RENDERCACHE__BATCH];
    begin = (uint32_t)((uint64_t)job->element_count * j / job->jobs);
    end = (uint32_t)((uint64_t)job->element_count * (j + 1) / job->jobs);
    for (i = 0; i < s->pixel_count; i++) key[i] = RENDERCACHE__EMPTY_KEY;
    for (b = begin; b < end; b += RENDERCACHE__BATCH) {
        uint32_t n = end - b < RENDERCACHE__BATCH ? end - b : RENDERCACHE__BATCH;
        job->source(job->src, b, b + n, pix, d);
        if (job->payload) job->payload(job->src, b, b + n, pix, pay);
        for (i = 0; i < n; i++) {
            uint32_t p = pix[i];
            uint64_t k;
            if (p == RENDERCACHE__NONE) continue;
            projected++;
            k = rendercache__key(d[i], b + i);
            if (k < key[p]) {
                key[p] = k;
                if (job->payload) memcpy(payload + 4 * (size_t)p, pay + 4 * i, 4 * sizeof(float));
            }
        }
    }
    s->job_projected[j] = projected;
}

/* Job per tile: the least key over the jobs' z-buffers becomes the final
   depth and element (with its payload). */
static void rendercache__splat_merge(void *ctx, uint32_t tile)
{
    const rendercache__splat_job *job = (const rendercache__splat_job *)ctx;
    rendercache__splat *s = job->s;
    uint32_t p0 = tile * RENDERCACHE__TILE_ROWS * s->width, p1 = p0 + RENDERCACHE__TILE_ROWS * s->width, j, p;
    if (p1 > s->pixel_count) p1 = s->pixel_count;
    for (p = p0; p < p1; p++) {
        uint64_t k = s->zb[0].key[p];
        uint32_t bits;
        for (j = 1; j < job->jobs; j++) {
            if (!(s->zb[j].key[p] < k)) continue;
            k = s->zb[j].key[p];
            if (job->payload) memcpy(s->final.payload + 4 * (size_t)p, s->zb[j].payload + 4 * (size_t)p, 4 * sizeof(float));
        }
        if (k == RENDERCACHE__EMPTY_KEY) {
            s->final.depth[p] = FLT_MAX;
            s->final.index[p] = RENDERCACHE__NONE;
            continue;
        }
        bits = (uint32_t)(k >> 32);
        memcpy(&s->final.depth[p], &bits, sizeof bits);
        s->final.index[p] = (uint32_t)k;
    }
}

/* Runs the splat over elements [0, count) into s->final; parallel_for only
   when the splat was allocated for several jobs. */
static void rendercache__splat_run(rendercache__splat *s, void (*parallel_for)(void *, rendercache_job_fn, void *, uint32_t),
                                   void *user, rendercache__source_fn source, rendercache__payload_fn payload,
                                   const void *src, uint32_t count)
{
    rendercache__splat_job job;
    uint32_t j;
    job.s = s;
    job.source = source;
    job.payload = payload;
    job.src = src;
    job.element_count = count;
    job.jobs = parallel_for ? s->jobs : 1u;
    rendercache__run_jobs(parallel_for, user, rendercache__splat_range, &job, job.jobs);
    rendercache__run_jobs(parallel_for, user, rendercache__splat_merge, &job, s->tile_count);
    s->projected = 0;
    for (j = 0; j < job.jobs; j++) s->projected += s->job_projected[j];
}

/* ======================================================================
   10. the cache object
   ---------------------------------------------------------------------- */
#define RENDERCACHE__FREE_SLOT 0xFFFFFFFEu   /* object id of an unused cache slot */
#define RENDERCACHE__LEVELS 1024u            /* priority levels of the threshold histogram */
#define RENDERCACHE__TILE_STATS 6u           /* visible, culled, interpolated, sparse, empty, scratch */

/* Priority image values (WDP99 priority image, extended to [0, 1]): a point
   rises with age to POINT_MAX; holes rank above every point, the sparser the
   higher; a pixel with nothing near is at 1. */
#define RENDERCACHE__PRIORITY_POINT_MAX 0.5f
#define RENDERCACHE__PRIORITY_INTERP 0.5f    /* + up to 0.25 as the 3x3 neighbourhood empties */
#define RENDERCACHE__PRIORITY_SPARSE 0.75f   /* + up to 0.2 as the wide window empties */

/* A cache slot as the projection reads it: 16 bytes. */
typedef struct rendercache__geo {
    float pos[3];            /* object-space position, or the world unit direction of a background point */
    uint32_t object;         /* object id, RENDERCACHE_MISS, or RENDERCACHE__FREE_SLOT */
} rendercache__geo;

/* The rest of a slot, read for the points that land in the image: 24
   bytes, streamed with geo. A point's age is not stored but derived, so nothing is written
   per point and frame: age = frame - birth + (motion of its object since
   birth), the last term making points of moving objects age faster. */
typedef struct rendercache__point {
    float rgb[3];
    float scale;             /* priority scale */
    uint32_t birth;          /* frame of insertion */
    uint32_t motion_birth;   /* the object's obj_motion at insertion */
} rendercache__point;

struct rendercache {
    rendercache_allocator alloc;
    void (*parallel_for)(void *, rendercache_job_fn, void *, uint32_t);
    void *parallel_user;
    double (*clock)(void *);
    void *clock_user;
    void (*log)(void *, const char *);
    void *log_user;

    uint32_t width, height, pixel_count, tile_count;
    uint32_t capacity, object_count;
    float depth_tolerance, predict_fraction, background[3];
    uint32_t age_ramp, moving_age_step, sparse_neighbours, wide_radius;
    float inv_age_ramp;

    /* point cache: slot order is insertion order; the projection streams
       through both arrays */
    rendercache__geo *geo;
    rendercache__point *data;
    uint32_t hand;           /* clock hand of the eviction */
    uint32_t live;
    int hand_exhausted;      /* a full turn found no invisible slot in this frame */

    /* objects */
    float *obj_world;        /* 12 per object: object to world */
    float *obj_local;        /* 12 per object: world to object */
    float *obj_camera;       /* 12 per object: object to camera space of the current view */
    float *obj_predicted;    /* 12 per object: object to camera space of the predicted view */
    uint32_t *obj_motion;    /* extra age the object's points gathered while it moved */
    unsigned char *obj_moved;

    /* current frame */
    uint32_t frame;
    int has_frame, has_prediction;
    rendercache__view view, predicted;
    rendercache__splat splat;
    uint32_t *px_index;      /* per pixel: the slot shown, after the depth cull */
    float *px_depth;         /* per pixel: its squared distance, FLT_MAX without a point */
    float *depth_out;        /* rendercache_depth_image: distances, filled on request */
    float *image, *priority, *pred_priority;
    unsigned char *kind, *count;
    uint32_t *tile_stats;    /* RENDERCACHE__TILE_STATS per tile */

    /* request scratch */
    uint32_t *hist;          /* RENDERCACHE__LEVELS per tile, then the merged histogram */
    float *select_v;         /* per pixel: value plus diffused error of the fractional pixels */
    unsigned char *chosen;   /* per pixel: 1 chosen, 2 fractional (error-diffused) */
    float *err_rows;         /* two rows of diffused error */
    uint32_t pred_holes;
    uint32_t touched;        /* rendercache__touch_slots' results, kept so its reads stay */

    rendercache_stats stats;
};

static double rendercache__now(const rendercache *rc)
{
    return rc->clock ? rc->clock(rc->clock_user) : 0.0;
}

static void rendercache__log(const rendercache_desc *d, const char *message)
{
    if (d && d->log) d->log(d->log_user, message);
}

static void rendercache__identity(float m[12])
{
    memset(m, 0, 12 * sizeof(float));
    m[0] = m[5] = m[10] = 1.0f;
}

/* Image and per-pixel state as if nothing were cached. */
static void rendercache__reset_image(rendercache *rc)
{
    uint32_t p;
    for (p = 0; p < rc->pixel_count; p++) {
        rc->image[3 * p + 0] = rc->background[0];
        rc->image[3 * p + 1] = rc->background[1];
        rc->image[3 * p + 2] = rc->background[2];
        rc->priority[p] = 1.0f;
        rc->pred_priority[p] = 0.0f;
        rc->kind[p] = RENDERCACHE_PIXEL_EMPTY;
        rc->count[p] = 0;
        rc->px_index[p] = RENDERCACHE__NONE;
        rc->px_depth[p] = FLT_MAX;
    }
}

static void rendercache__reset_points(rendercache *rc)
{
    uint32_t i;
    for (i = 0; i < rc->capacity; i++) rc->geo[i].object = RENDERCACHE__FREE_SLOT;
    rc->hand = 0;
    rc->live = 0;
}

static void rendercache__release(rendercache *rc)
{
    const rendercache_allocator a = rc->alloc;
    void *blocks[21];
    size_t i;
    blocks[0] = rc->geo; blocks[1] = rc->data; blocks[2] = rc->obj_predicted; blocks[3] = rc->obj_motion;
    blocks[4] = rc->depth_out; blocks[5] = rc->obj_world; blocks[6] = rc->obj_local;
    blocks[7] = rc->obj_camera; blocks[8] = rc->obj_moved; blocks[9] = rc->px_index;
    blocks[10] = rc->px_depth; blocks[11] = rc->image; blocks[12] = rc->priority;
    blocks[13] = rc->pred_priority; blocks[14] = rc->kind; blocks[15] = rc->count;
    blocks[16] = rc->tile_stats; blocks[17] = rc->hist; blocks[18] = rc->select_v;
    blocks[19] = rc->chosen; blocks[20] = rc->err_rows;
    for (i = 0; i < sizeof blocks / sizeof blocks[0]; i++) rendercache__free(&a, blocks[i]);
    rendercache__splat_free(&rc->splat, &a);
    rendercache__free(&a, rc);
}

static int rendercache__alloc_buffers(rendercache *rc)
{
    const rendercache_allocator *a = &rc->alloc;
    size_t n = rc->capacity, px = rc->pixel_count, no = rc->object_count;
    rc->geo = (rendercache__geo *)rendercache__alloc_array(a, n, sizeof(rendercache__geo));
    rc->data = (rendercache__point *)rendercache__alloc_array(a, n, sizeof(rendercache__point));
    rc->obj_predicted = (float *)rendercache__alloc_array(a, no, 12 * sizeof(float));
    rc->obj_motion = (uint32_t *)rendercache__alloc_array(a, no, sizeof(uint32_t));
    rc->obj_world = (float *)rendercache__alloc_array(a, no, 12 * sizeof(float));
    rc->obj_local = (float *)rendercache__alloc_array(a, no, 12 * sizeof(float));
    rc->obj_camera = (float *)rendercache__alloc_array(a, no, 12 * sizeof(float));
    rc->obj_moved = (unsigned char *)rendercache__alloc_array(a, no, 1);
    rc->px_index = (uint32_t *)rendercache__alloc_array(a, px, sizeof(uint32_t));
    rc->px_depth = (float *)rendercache__alloc_array(a, px, sizeof(float));
    rc->depth_out = (float *)rendercache__alloc_array(a, px, sizeof(float));
    rc->image = (float *)rendercache__alloc_array(a, px, 3 * sizeof(float));
    rc->priority = (float *)rendercache__alloc_array(a, px, sizeof(float));
    rc->pred_priority = (float *)rendercache__alloc_array(a, px, sizeof(float));
    rc->kind = (unsigned char *)rendercache__alloc_array(a, px, 1);
    rc->count = (unsigned char *)rendercache__alloc_array(a, px, 1);
    rc->tile_stats = (uint32_t *)rendercache__alloc_array(a, rc->tile_count, RENDERCACHE__TILE_STATS * sizeof(uint32_t));
    rc->hist = (uint32_t *)rendercache__alloc_array(a, (size_t)rc->tile_count + 1, RENDERCACHE__LEVELS * sizeof(uint32_t));
    rc->select_v = (float *)rendercache__alloc_array(a, px, sizeof(float));
    rc->chosen = (unsigned char *)rendercache__alloc_array(a, px, 1);
    rc->err_rows = (float *)rendercache__alloc_array(a, 2 * ((size_t)rc->width + 2), sizeof(float));
    if (!rc->geo || !rc->data || !rc->obj_predicted || !rc->obj_motion || !rc->obj_world ||
        !rc->obj_local || !rc->obj_camera || !rc->obj_moved || !rc->px_index || !rc->px_depth || !rc->depth_out || !rc->image ||
        !rc->priority || !rc->pred_priority || !rc->kind || !rc->count || !rc->tile_stats || !rc->hist ||
        !rc->select_v || !rc->chosen || !rc->err_rows)
        return -1;
    return rendercache__splat_alloc(&rc->splat, rc->width, rc->height,
                                    rc->parallel_for ? RENDERCACHE__SPLAT_JOBS : 1u, a);
}

/* Applies the defaults and checks the ranges of a desc; 0 on bad input. */
static int rendercache__configure(rendercache *rc, const rendercache_desc *d)
{
    double capacity;
    float ppp = rendercache__def(d->points_per_pixel, 2.0f);
    if (d->width == 0 || d->height == 0 || (uint64_t)d->width * d->height > RENDERCACHE__MAX_PIXELS) return 0;
    if (!rendercache__allocator_valid(&d->allocator)) return 0;
    if (!(ppp > 0.0f) || !isfinite(ppp)) return 0;
    if (!(d->depth_tolerance >= 0.0f) || !isfinite(d->depth_tolerance)) return 0;
    if (!(d->predict_fraction >= 0.0f && d->predict_fraction <= 1.0f)) return 0;
    if (!rendercache__finite3(d->background)) return 0;
    if (d->object_count > RENDERCACHE__MAX_OBJECTS || d->sparse_neighbours > 8 || d->wide_radius > 7) return 0;
    capacity = ceil((double)ppp * d->width * d->height);
    if (capacity < 1.0 || capacity > (double)RENDERCACHE__MAX_CAPACITY) return 0;
    rc->alloc = d->allocator;
    rc->parallel_for = d->parallel_for;
    rc->parallel_user = d->parallel_user;
    rc->clock = d->clock;
    rc->clock_user = d->clock_user;
    rc->log = d->log;
    rc->log_user = d->log_user;
    rc->width = d->width;
    rc->height = d->height;
    rc->pixel_count = d->width * d->height;
    rc->tile_count = (d->height + RENDERCACHE__TILE_ROWS - 1) / RENDERCACHE__TILE_ROWS;
    rc->capacity = (uint32_t)capacity;
    rc->object_count = rendercache__def(d->object_count, 256u);
    rc->depth_tolerance = rendercache__def(d->depth_tolerance, 0.1f);
    rc->predict_fraction = rendercache__def(d->predict_fraction, 0.25f);
    rc->age_ramp = rendercache__def(d->age_ramp_frames, 32u);
    rc->inv_age_ramp = 1.0f / (float)rc->age_ramp;
    rc->moving_age_step = rendercache__def(d->moving_age_step, 4u);
    if (rc->moving_age_step > 65536u) rc->moving_age_step = 65536u;
    rc->sparse_neighbours = rendercache__def(d->sparse_neighbours, 2u);
    rc->wide_radius = rendercache__def(d->wide_radius, 3u);
    memcpy(rc->background, d->background, sizeof rc->background);
    return 1;
}

RENDERCACHE_API rendercache_result rendercache_create(const rendercache_desc *desc, rendercache **out)
{
    rendercache *rc;
    rendercache_allocator a;
    uint32_t o;
    if (!out) return RENDERCACHE_ERROR_INVALID_ARGUMENT;
    *out = NULL;
    if (!desc) return RENDERCACHE_ERROR_INVALID_ARGUMENT;
    if (!rendercache__allocator_valid(&desc->allocator)) {
        rendercache__log(desc, "rendercache_create: allocator needs both alloc and free, or neither");
        return RENDERCACHE_ERROR_INVALID_ARGUMENT;
    }
    a = desc->allocator;
    rc = (rendercache *)rendercache__alloc(&a, sizeof *rc);
    if (!rc) return RENDERCACHE_ERROR_OUT_OF_MEMORY;
    memset(rc, 0, sizeof *rc);
    rc->alloc = a;
    if (!rendercache__configure(rc, desc)) {
        rendercache__log(desc, "rendercache_create: bad size, tolerance, fraction or radius in the desc");
        rendercache__release(rc);
        return RENDERCACHE_ERROR_INVALID_ARGUMENT;
    }
    if (rendercache__alloc_buffers(rc) != 0) {
        rendercache__log(desc, "rendercache_create: out of memory");
        rendercache__release(rc);
        return RENDERCACHE_ERROR_OUT_OF_MEMORY;
    }
    for (o = 0; o < rc->object_count; o++) {
        rendercache__identity(rc->obj_world + 12 * (size_t)o);
        rendercache__identity(rc->obj_local + 12 * (size_t)o);
        rc->obj_moved[o] = 0;
        rc->obj_motion[o] = 0;
    }
    rendercache__reset_points(rc);
    rendercache__reset_image(rc);
    rc->stats.capacity = rc->capacity;
    *out = rc;
    return RENDERCACHE_OK;
}

RENDERCACHE_API void rendercache_destroy(rendercache *rc)
{
    if (rc) rendercache__release(rc);
}

RENDERCACHE_API void rendercache_clear(rendercache *rc)
{
    if (!rc) return;
    rendercache__reset_points(rc);
    rendercache__reset_image(rc);
    rc->has_prediction = 0;
    rc->stats.live_points = 0;
}

/* ======================================================================
   11. object transforms
   ---------------------------------------------------------------------- */
/* Inverse of an affine 3x4 matrix in double; 0 when singular. */
static int rendercache__invert_affine(const float m[12], float out[12])
{
    double a = m[0], b = m[1], c = m[2], d = m[4], e = m[5], f = m[6], g = m[8], h = m[9], k = m[10];
    double det = a * (e * k - f * h) - b * (d * k - f * g) + c * (d * h - e * g), inv[9];
    double scale = fabs(a) + fabs(b) + fabs(c) + fabs(d) + fabs(e) + fabs(f) + fabs(g) + fabs(h) + fabs(k);
    int i;
    if (!(fabs(det) > 1e-12 * scale * scale * scale) || !isfinite(det)) return 0;
    inv[0] = (e * k - f * h) / det; inv[1] = (c * h - b * k) / det; inv[2] = (b * f - c * e) / det;
    inv[3] = (f * g - d * k) / det; inv[4] = (a * k - c * g) / det; inv[5] = (c * d - a * f) / det;
    inv[6] = (d * h - e * g) / det; inv[7] = (b * g - a * h) / det; inv[8] = (a * e - b * d) / det;
    for (i = 0; i < 3; i++) {
        out[4 * i + 0] = (float)inv[3 * i + 0];
        out[4 * i + 1] = (float)inv[3 * i + 1];
        out[4 * i + 2] = (float)inv[3 * i + 2];
        out[4 * i + 3] = (float)-(inv[3 * i + 0] * m[3] + inv[3 * i + 1] * m[7] + inv[3 * i + 2] * m[11]);
    }
    return 1;
}

RENDERCACHE_API rendercache_result rendercache_set_object_transform(rendercache *rc, uint32_t object,
                                                                    const float m[12])
{
    float inv[12];
    int k;
    if (!rc || !m || object >= rc->object_count) return RENDERCACHE_ERROR_INVALID_ARGUMENT;
    for (k = 0; k < 12; k++)
        if (!isfinite(m[k])) return RENDERCACHE_ERROR_INVALID_ARGUMENT;
    if (!rendercache__invert_affine(m, inv)) return RENDERCACHE_ERROR_INVALID_ARGUMENT;
    if (memcmp(m, rc->obj_world + 12 * (size_t)object, 12 * sizeof(float)) != 0) rc->obj_moved[object] = 1;
    memcpy(rc->obj_world + 12 * (size_t)object, m, 12 * sizeof(float));
    memcpy(rc->obj_local + 12 * (size_t)object, inv, 12 * sizeof(float));
    return RENDERCACHE_OK;
}

/* ======================================================================
   12. per-frame pipeline (Walter et al. 1999): project every point into
   the new camera and z-buffer it (section 9) -> depth cull -> interpolate
   the holes; the priority image is written by the last two (points: age;
   holes: how few points surround them). Then requests by thresholding and
   error diffusion (section 14), and insertion (section 15).
   ---------------------------------------------------------------------- */
/* Where a projection goes: a view and its object-to-camera matrices. */
typedef struct rendercache__projector {
    const rendercache *rc;
    const rendercache__view *view;
    const float *obj_camera;
} rendercache__projector;

/* Reprojection of one cache point (WDP99): object space -> camera space
   through the object's composed matrix, then to a pixel; background points
   are directions, rotated only, at distance RENDERCACHE__FAR. Depths are
   squared distances (the z-buffer only compares them). Returns the pixel
   index or RENDERCACHE__NONE. */
static uint32_t rendercache__project_point(const rendercache__projector *pr, const rendercache__geo *g, float *depth2)
{
    const rendercache__view *v = pr->view;
    float c[3], px, py;
    if (g->object == RENDERCACHE__FREE_SLOT) return RENDERCACHE__NONE;
    if (g->object == RENDERCACHE_MISS) {
        rendercache__view_rotate(v, g->pos, c);
        *depth2 = RENDERCACHE__FAR2;
    } else {
        rendercache__affine(pr->obj_camera + 12 * (size_t)g->object, g->pos, c);
        *depth2 = c[0] * c[0] + c[1] * c[1] + c[2] * c[2];
    }
    if (!rendercache__view_to_pixel(v, c, &px, &py)) return RENDERCACHE__NONE;
    return (uint32_t)py * v->width + (uint32_t)px;
}

/* Priority of a pixel showing a point (WDP99: age is the main measure of
   how likely a colour is stale; points of moving objects age faster),
   times its priority scale (the light-vector weight of Crespin and Peroche
   2004, section 4.2.4), in [0, 1]. motion: the object's obj_motion. */
static float rendercache__point_priority(const rendercache *rc, const rendercache__point *pt, uint32_t motion)
{
    uint32_t age = rc->frame - pt->birth + (motion - pt->motion_birth);
    float pr = (float)age * rc->inv_age_ramp;
    pr = (pr < 1.0f ? pr : 1.0f) * (RENDERCACHE__PRIORITY_POINT_MAX * pt->scale);
    return pr < 1.0f ? pr : 1.0f;
}

/* Perspective projection of n points of one object (matrix m): written
   without branches or library calls so that compilers vectorise it; this
   loop is the hottest of the frame. */
static void rendercache__project_perspective(const rendercache__geo *g, uint32_t n, const float *m,
                                             const rendercache__view *v, uint32_t *pix, float *depth2)
{
    const float fx = v->focal, cx = v->cx, cy = v->cy, w = (float)v->width, h = (float)v->height;
    const uint32_t width = v->width;
    uint32_t i;
    for (i = 0; i < n; i++) {
        float x0 = g[i].pos[0], x1 = g[i].pos[1], x2 = g[i].pos[2];
        float c0 = m[0] * x0 + m[1] * x1 + m[2] * x2 + m[3];
        float c1 = m[4] * x0 + m[5] * x1 + m[6] * x2 + m[7];
        float c2 = m[8] * x0 + m[9] * x1 + m[10] * x2 + m[11];
        float inv = 1.0f / c2, x = cx + fx * c0 * inv, y = cy - fx * c1 * inv;
        int inside = (c2 > 0.0f) & (x >= 0.0f) & (x < w) & (y >= 0.0f) & (y < h);
        float xs = inside ? x : 0.0f, ys = inside ? y : 0.0f;
        depth2[i] = c0 * c0 + c1 * c1 + c2 * c2;
        pix[i] = inside ? (uint32_t)ys * width + (uint32_t)xs : RENDERCACHE__NONE;
    }
}

/* The object all points [begin, end) belong to, or RENDERCACHE__NONE when
   they are mixed (or background, or free). */
static uint32_t rendercache__batch_object(const rendercache__geo *geo, uint32_t begin, uint32_t end)
{
    uint32_t o = geo[begin].object, differ = 0, i;
    for (i = begin + 1; i < end; i++) differ |= geo[i].object ^ o;
    return differ || o >= RENDERCACHE__FREE_SLOT ? RENDERCACHE__NONE : o;
}

/* The one object of the points [begin, end) other than background points,
   RENDERCACHE__NONE when there are several or free slots; *background
   tells whether background points are among them. */
static uint32_t rendercache__batch_object_or_background(const rendercache__geo *geo, uint32_t begin, uint32_t end,
                                                        int *background)
{
    uint32_t o = RENDERCACHE__NONE, i;
    *background = 0;
    for (i = begin; i < end; i++) {
        uint32_t g = geo[i].object;
        if (g == RENDERCACHE_MISS) { *background = 1; continue; }
        if (g == RENDERCACHE__FREE_SLOT || (o != RENDERCACHE__NONE && g != o)) return RENDERCACHE__NONE;
        o = g;
    }
    return o;
}

/* The splat source of the render cache: cache slots [begin, end). Batches
   of one object (with or without background points) under a perspective
   view take the vectorised path; the rest goes point by point. */
static void rendercache__project_points(const void *src, uint32_t begin, uint32_t end, uint32_t *pix, float *depth2)
{
    const rendercache__projector *pr = (const rendercache__projector *)src;
    const rendercache__geo *geo = pr->rc->geo;
    int background;
    uint32_t i, o = rendercache__batch_object_or_background(geo, begin, end, &background);
    if (pr->view->kind == RENDERCACHE_CAMERA_PERSPECTIVE && o != RENDERCACHE__NONE) {
        rendercache__project_perspective(geo + begin, end - begin, pr->obj_camera + 12 * (size_t)o, pr->view, pix,
                                         depth2);
        if (background)   /* the few background points, again, as directions */
            for (i = begin; i < end; i++)
                if (geo[i].object == RENDERCACHE_MISS) pix[i - begin] = rendercache__project_point(pr, &geo[i], &depth2[i - begin]);
        return;
    }
    for (i = begin; i < end; i++) pix[i - begin] = rendercache__project_point(pr, &geo[i], &depth2[i - begin]);
}

/* The payload of a cache point: its colour and priority. */
static void rendercache__point_payload(const void *src, uint32_t begin, uint32_t end, const uint32_t *pix,
                                       float *payload)
{
    const rendercache *rc = ((const rendercache__projector *)src)->rc;
    const rendercache__point *data = rc->data;
    const rendercache__geo *geo = rc->geo;
    uint32_t i, o = rendercache__batch_object(geo, begin, end);
    if (o != RENDERCACHE__NONE) {   /* one object: no branch, vectorisable */
        uint32_t motion = rc->obj_motion[o];
        for (i = begin; i < end; i++) {
            float *out = payload + 4 * (size_t)(i - begin);
            out[0] = data[i].rgb[0];
            out[1] = data[i].rgb[1];
            out[2] = data[i].rgb[2];
            out[3] = rendercache__point_priority(rc, &data[i], motion);
        }
        return;
    }
    for (i = begin; i < end; i++) {
        float *out = payload + 4 * (size_t)(i - begin);
        uint32_t obj = geo[i].object;
        if (pix[i - begin] == RENDERCACHE__NONE) continue;
        out[0] = data[i].rgb[0];
        out[1] = data[i].rgb[1];
        out[2] = data[i].rgb[2];
        out[3] = rendercache__point_priority(rc, &data[i], obj == RENDERCACHE_MISS ? 0u : rc->obj_motion[obj]);
    }
}

/* Object-to-camera matrices of every object for view v. */
static void rendercache__compose_objects(const rendercache *rc, const rendercache__view *v, float *out)
{
    uint32_t o;
    for (o = 0; o < rc->object_count; o++)
        rendercache__view_compose(v, rc->obj_world + 12 * (size_t)o, out + 12 * (size_t)o);
}

/* Projects every point into view v (matrices obj_camera) and z-buffers
   them into rc->splat, with colour and priority when with_payload. */
static void rendercache__splat_points(rendercache *rc, const rendercache__view *v, const float *obj_camera,
                                      int with_payload, double *t_project)
{
    rendercache__projector pr;
    pr.rc = rc;
    pr.view = v;
    pr.obj_camera = obj_camera;
    double t0 = rendercache__now(rc);
    rendercache__splat_run(&rc->splat, rc->parallel_for, rc->parallel_user, rendercache__project_points,
                           with_payload ? rendercache__point_payload : NULL, &pr, rc->capacity);
    if (t_project) *t_project += rendercache__now(rc) - t0;
}

/* Priority of a hole (WDP99, Crespin-Peroche 4.1): the fewer points around
   it, the higher; nothing near gives the maximum. */
static float rendercache__hole_priority(const rendercache *rc, unsigned char kind, uint32_t count)
{
    float window;
    switch (kind) {
    case RENDERCACHE_PIXEL_INTERPOLATED:
        return RENDERCACHE__PRIORITY_INTERP + 0.25f * (float)(8u - count) / 8.0f;
    case RENDERCACHE_PIXEL_SPARSE:
        window = (float)((2 * rc->wide_radius + 1) * (2 * rc->wide_radius + 1) - 1);
        return RENDERCACHE__PRIORITY_SPARSE + 0.2f * (1.0f - (float)count / window);
    default:
        return 1.0f;
    }
}

/* The 8 neighbours in the order W E N S NW NE SW SE, so that bits (0,1),
   (2,3), (4,7) and (5,6) are opposite pairs. */
static const int rendercache__nx[8] = { -1, 1, 0, 0, -1, 1, -1, 1 };
static const int rendercache__ny[8] = { 0, 0, -1, 1, -1, -1, 1, 1 };

/* Depth cull (WDP99): a point much farther than the average depth of the
   points in its 3x3 neighbourhood shows through a nearer surface and is
   dropped. Depths are squared distances here (FLT_MAX where empty), so the
   average is a root mean square and tol2 the squared tolerance factor.
   Refinement: the nearer points must also lie on opposite sides (left and
   right, above and below, or both diagonals), as they do when a far point
   falls into a gap of a nearer surface; a point beside a silhouette has its
   nearer neighbours on one side only and is kept, so a static view keeps
   every sampled point. nd: the 8 neighbours' depths. */
static int rendercache__occluded(const float nd[8], float d, float tol2)
{
    uint32_t nearer = 0, n = 0, k;
    float sum = 0.0f;
    for (k = 0; k < 8; k++) {
        int filled = nd[k] < FLT_MAX;
        sum += filled ? nd[k] : 0.0f;
        n += (uint32_t)filled;
        nearer |= (uint32_t)(d > nd[k] * tol2) << k;
    }
    if (!(((nearer & 3u) == 3u) || ((nearer & 12u) == 12u) || ((nearer & 0xF0u) == 0xF0u))) return 0;
    return d * (float)n > sum * tol2;   /* d > mean * tol2, as rendercache__cull_row computes it */
}

/* The depths of the 8 neighbours of (x, y), FLT_MAX outside the image. */
static void rendercache__neighbour_depths(const float *depth, uint32_t w, uint32_t h, uint32_t x, uint32_t y,
                                          float nd[8])
{
    int k;
    if (x > 0 && y > 0 && x + 1 < w && y + 1 < h) {
        const float *c = depth + (size_t)y * w + x;
        nd[0] = c[-1]; nd[1] = c[1]; nd[2] = c[-(ptrdiff_t)w]; nd[3] = c[w];
        nd[4] = c[-(ptrdiff_t)w - 1]; nd[5] = c[-(ptrdiff_t)w + 1]; nd[6] = c[w - 1]; nd[7] = c[w + 1];
        return;
    }
    for (k = 0; k < 8; k++) {
        int qx = (int)x + rendercache__nx[k], qy = (int)y + rendercache__ny[k];
        nd[k] = (qx < 0 || qy < 0 || qx >= (int)w || qy >= (int)h) ? FLT_MAX : depth[(size_t)qy * w + (uint32_t)qx];
    }
}

/* The depth cull of the interior pixels x in [1, w-1) of row y, written
   without branches so that compilers vectorise it: occ[x] = 1 where the
   pixel's point is culled. Same test as rendercache__occluded. */
static void rendercache__cull_row(const float *depth, uint32_t w, uint32_t y, float tol2, unsigned char *occ)
{
    const float *c = depth + (size_t)y * w, *u = c - w, *l = c + w;
    uint32_t x;
    for (x = 1; x + 1 < w; x++) {
        float d = c[x], sum = 0.0f, n = 0.0f;
        float nd0 = c[x - 1], nd1 = c[x + 1], nd2 = u[x], nd3 = l[x];
        float nd4 = u[x - 1], nd5 = u[x + 1], nd6 = l[x - 1], nd7 = l[x + 1];
        int e01, e23, ediag, enclosed;
        sum += nd0 < FLT_MAX ? nd0 : 0.0f; n += nd0 < FLT_MAX ? 1.0f : 0.0f;
        sum += nd1 < FLT_MAX ? nd1 : 0.0f; n += nd1 < FLT_MAX ? 1.0f : 0.0f;
        sum += nd2 < FLT_MAX ? nd2 : 0.0f; n += nd2 < FLT_MAX ? 1.0f : 0.0f;
        sum += nd3 < FLT_MAX ? nd3 : 0.0f; n += nd3 < FLT_MAX ? 1.0f : 0.0f;
        sum += nd4 < FLT_MAX ? nd4 : 0.0f; n += nd4 < FLT_MAX ? 1.0f : 0.0f;
        sum += nd5 < FLT_MAX ? nd5 : 0.0f; n += nd5 < FLT_MAX ? 1.0f : 0.0f;
        sum += nd6 < FLT_MAX ? nd6 : 0.0f; n += nd6 < FLT_MAX ? 1.0f : 0.0f;
        sum += nd7 < FLT_MAX ? nd7 : 0.0f; n += nd7 < FLT_MAX ? 1.0f : 0.0f;
        e01 = (d > nd0 * tol2) & (d > nd1 * tol2);
        e23 = (d > nd2 * tol2) & (d > nd3 * tol2);
        ediag = (d > nd4 * tol2) & (d > nd5 * tol2) & (d > nd6 * tol2) & (d > nd7 * tol2);
        enclosed = e01 | e23 | ediag;
        /* enclosed implies n >= 2, so the mean is defined where it matters */
        occ[x] = (unsigned char)(enclosed & (d < FLT_MAX) & (d * (n > 0.0f ? n : 1.0f) > sum * tol2));
    }
}

/* Job per tile: depth cull; surviving points give their colour and
   priority to the pixel. The kind array holds the cull decisions of a row
   until the row is written. */
static void rendercache__cull_job(void *ctx, uint32_t tile)
{
    rendercache *rc = (rendercache *)ctx;
    const rendercache__raster *s = &rc->splat.final;
    const float *depth = s->depth, *payload = s->payload;
    const uint32_t *index = s->index, w = rc->width, h = rc->height;
    uint32_t *px_index = rc->px_index;
    float *px_depth = rc->px_depth, *image = rc->image, *priority = rc->priority;
    unsigned char *kind = rc->kind, *count = rc->count;
    uint32_t y0 = tile * RENDERCACHE__TILE_ROWS, y1 = y0 + RENDERCACHE__TILE_ROWS, x, y;
    uint32_t visible = 0, culled = 0, *stats = rc->tile_stats + RENDERCACHE__TILE_STATS * (size_t)tile;
    float tol2 = (1.0f + rc->depth_tolerance) * (1.0f + rc->depth_tolerance);
    if (y1 > h) y1 = h;
    for (y = y0; y < y1; y++) {
        unsigned char *occ = kind + (size_t)y * w;
        int interior_row = y > 0 && y + 1 < h;
        if (interior_row) rendercache__cull_row(depth, w, y, tol2, occ);
        for (x = 0; x < w; x++) {
            uint32_t p = y * w + x, k = index[p];
            if (!interior_row || x == 0 || x + 1 == w) {   /* border: the general test */
                float nd[8];
                occ[x] = 0;
                if (k != RENDERCACHE__NONE) {
                    rendercache__neighbour_depths(depth, w, h, x, y, nd);
                    occ[x] = (unsigned char)rendercache__occluded(nd, depth[p], tol2);
                }
            }
            if (k != RENDERCACHE__NONE && occ[x]) {
                k = RENDERCACHE__NONE;
                culled++;
            }
            px_index[p] = k;
            if (k == RENDERCACHE__NONE) {
                px_depth[p] = FLT_MAX;
                continue;
            }
            px_depth[p] = depth[p];
            memcpy(image + 3 * (size_t)p, payload + 4 * (size_t)p, 3 * sizeof(float));
            priority[p] = payload[4 * (size_t)p + 3];
            kind[p] = RENDERCACHE_PIXEL_POINT;
            count[p] = 0;
            visible++;
        }
    }
    stats[0] = visible;
    stats[1] = culled;
}

/* Interpolation of a hole (WDP99 3x3 weighted filter; WDG02 wider filter
   for sparse regions) from the points within radius r, tent weights
   (r+1-|dx|)(r+1-|dy|). Never blends across a depth discontinuity: when the
   neighbours' depths span more than the tolerance, only the nearest layer
   (within tolerance of the minimum) or the farthest layer (within tolerance
   of the maximum) is used, whichever carries more weight (the far one on a
   tie: a hole beside an edge is more often uncovered background). Returns
   the number of points in the window; rgb is set when it is not zero.
   Depths are squared distances, compared with the squared tolerance. */
static uint32_t rendercache__interpolate(const rendercache *rc, uint32_t x, uint32_t y, int r, float rgb[3])
{
    const float *depth = rc->px_depth, *image = rc->image;
    const uint32_t w = rc->width;
    int x0 = (int)x - r, x1 = (int)x + r, y0 = (int)y - r, y1 = (int)y + r, qx, qy;
    float dmin = FLT_MAX, dmax = 0.0f, tol2 = (1.0f + rc->depth_tolerance) * (1.0f + rc->depth_tolerance);
    float near_sum[4] = { 0, 0, 0, 0 }, far_sum[4] = { 0, 0, 0, 0 };
    const float *chosen;
    uint32_t n = 0;
    if (x0 < 0) x0 = 0;
    if (y0 < 0) y0 = 0;
    if (x1 >= (int)w) x1 = (int)w - 1;
    if (y1 >= (int)rc->height) y1 = (int)rc->height - 1;
    for (qy = y0; qy <= y1; qy++) {
        const float *row = depth + (size_t)qy * w;
        for (qx = x0; qx <= x1; qx++) {
            float d = row[qx];
            if (d == FLT_MAX) continue;   /* no point there */
            dmin = d < dmin ? d : dmin;
            dmax = d > dmax ? d : dmax;
            n++;
        }
    }
    if (n == 0) return 0;
    for (qy = y0; qy <= y1; qy++) {
        const float *row = depth + (size_t)qy * w;
        float wy = (float)(r + 1 - rendercache__iabs(qy - (int)y));
        for (qx = x0; qx <= x1; qx++) {
            float d = row[qx], wgt, *acc;
            const float *c;
            if (d == FLT_MAX) continue;
            if (d <= dmin * tol2) acc = near_sum;
            else if (d * tol2 >= dmax) acc = far_sum;
            else continue;   /* a middle layer: neither side of the choice */
            wgt = wy * (float)(r + 1 - rendercache__iabs(qx - (int)x));
            c = image + 3 * ((size_t)qy * w + (size_t)qx);
            acc[0] += wgt * c[0];
            acc[1] += wgt * c[1];
            acc[2] += wgt * c[2];
            acc[3] += wgt;
        }
    }
    chosen = (far_sum[3] >= near_sum[3]) ? far_sum : near_sum;
    if (dmax <= dmin * tol2) chosen = near_sum;   /* one layer: every point was counted as near */
    rgb[0] = chosen[0] / chosen[3];
    rgb[1] = chosen[1] / chosen[3];
    rgb[2] = chosen[2] / chosen[3];
    return n;
}

/* Job per tile: fill the holes left by projection and cull, and rank them. */
static void rendercache__interpolate_job(void *ctx, uint32_t tile)
{
    rendercache *rc = (rendercache *)ctx;
    uint32_t y0 = tile * RENDERCACHE__TILE_ROWS, y1 = y0 + RENDERCACHE__TILE_ROWS, x, y;
    uint32_t counts[3] = { 0, 0, 0 }, *stats = rc->tile_stats + RENDERCACHE__TILE_STATS * (size_t)tile;
    if (y1 > rc->height) y1 = rc->height;
    for (y = y0; y < y1; y++) {
        for (x = 0; x < rc->width; x++) {
            uint32_t p = y * rc->width + x, n;
            float rgb[3];
            if (rc->px_index[p] != RENDERCACHE__NONE) continue;
            n = rendercache__interpolate(rc, x, y, 1, rgb);
            if (n >= rc->sparse_neighbours) {
                rc->kind[p] = RENDERCACHE_PIXEL_INTERPOLATED;
                counts[0]++;
            } else {
                n = rendercache__interpolate(rc, x, y, (int)rc->wide_radius, rgb);
                if (n) {
                    rc->kind[p] = RENDERCACHE_PIXEL_SPARSE;
                    counts[1]++;
                } else {
                    memcpy(rgb, rc->background, sizeof rgb);
                    rc->kind[p] = RENDERCACHE_PIXEL_EMPTY;
                    counts[2]++;
                }
            }
            rc->count[p] = (unsigned char)(n > 255 ? 255 : n);
            rc->priority[p] = rendercache__hole_priority(rc, rc->kind[p], rc->count[p]);
            memcpy(rc->image + 3 * (size_t)p, rgb, sizeof rgb);
        }
    }
    stats[2] = counts[0];
    stats[3] = counts[1];
    stats[4] = counts[2];
}

/* Sums one column of the per-tile statistics. */
static uint32_t rendercache__tile_sum(const rendercache *rc, uint32_t column)
{
    uint32_t t, sum = 0;
    for (t = 0; t < rc->tile_count; t++) sum += rc->tile_stats[RENDERCACHE__TILE_STATS * (size_t)t + column];
    return sum;
}

static void rendercache__start_stats(rendercache *rc)
{
    rendercache_stats *s = &rc->stats;
    s->frame = rc->frame;
    s->requested = s->predicted = s->inserted = s->replaced = s->evicted = s->rejected = 0;
    s->time_project = s->time_cull = s->time_interpolate = 0.0;
    s->time_predict = s->time_request = s->time_insert = 0.0;
}

RENDERCACHE_API rendercache_result rendercache_begin_frame(rendercache *rc, const rendercache_camera *camera)
{
    rendercache__view v;
    double t1, t2;
    uint32_t o;
    if (!rc || !rendercache__view_init(&v, camera) || camera->width != rc->width || camera->height != rc->height) {
        if (rc && rc->log) rc->log(rc->log_user, "rendercache_begin_frame: invalid camera or image size");
        return RENDERCACHE_ERROR_INVALID_ARGUMENT;
    }
    rc->frame++;
    rc->view = v;
    rc->has_prediction = 0;
    rc->hand_exhausted = 0;
    rendercache__start_stats(rc);
    for (o = 0; o < rc->object_count; o++) {   /* points of moving objects age faster */
        if (rc->obj_moved[o]) rc->obj_motion[o] += rc->moving_age_step - 1u;
        rc->obj_moved[o] = 0;
    }
    rendercache__compose_objects(rc, &rc->view, rc->obj_camera);
    rendercache__splat_points(rc, &rc->view, rc->obj_camera, 1, &rc->stats.time_project);
    t1 = rendercache__now(rc);
    rendercache__run_jobs(rc->parallel_for, rc->parallel_user, rendercache__cull_job, rc, rc->tile_count);
    t2 = rendercache__now(rc);
    rendercache__run_jobs(rc->parallel_for, rc->parallel_user, rendercache__interpolate_job, rc, rc->tile_count);
    rc->stats.time_cull = t2 - t1;
    rc->stats.time_interpolate = rendercache__now(rc) - t2;
    rc->stats.projected = rc->splat.projected;
    rc->stats.visible = rendercache__tile_sum(rc, 0);
    rc->stats.culled = rendercache__tile_sum(rc, 1);
    rc->stats.interpolated = rendercache__tile_sum(rc, 2);
    rc->stats.sparse = rendercache__tile_sum(rc, 3);
    rc->stats.empty = rendercache__tile_sum(rc, 4);
    rc->stats.live_points = rc->live;
    rc->has_frame = 1;
    return RENDERCACHE_OK;
}

/* ======================================================================
   13. predictive sampling (Walter et al. 2002): the cache projected into
   the camera expected next; pixels with no point in their 3x3
   neighbourhood there are regions the motion will uncover.
   ---------------------------------------------------------------------- */
static void rendercache__predict_job(void *ctx, uint32_t tile)
{
    rendercache *rc = (rendercache *)ctx;
    const rendercache__raster *s = &rc->splat.final;
    uint32_t y0 = tile * RENDERCACHE__TILE_ROWS, y1 = y0 + RENDERCACHE__TILE_ROWS, x, y, holes = 0;
    if (y1 > rc->height) y1 = rc->height;
    for (y = y0; y < y1; y++) {
        uint32_t ya = y > 0 ? y - 1 : 0, yb = y + 1 < rc->height ? y + 1 : y;
        for (x = 0; x < rc->width; x++) {
            uint32_t xa = x > 0 ? x - 1 : 0, xb = x + 1 < rc->width ? x + 1 : x, qx, qy;
            int covered = 0;
            for (qy = ya; qy <= yb && !covered; qy++)
                for (qx = xa; qx <= xb; qx++)
                    if (s->index[qy * rc->width + qx] != RENDERCACHE__NONE) { covered = 1; break; }
            rc->pred_priority[y * rc->width + x] = covered ? 0.0f : 1.0f;
            holes += !covered;
        }
    }
    rc->tile_stats[RENDERCACHE__TILE_STATS * (size_t)tile + 5] = holes;
}

RENDERCACHE_API rendercache_result rendercache_predict(rendercache *rc, const rendercache_camera *next)
{
    rendercache__view v;
    double t0;
    if (!rc || !rc->has_frame || !rendercache__view_init(&v, next) || next->width != rc->width ||
        next->height != rc->height)
        return RENDERCACHE_ERROR_INVALID_ARGUMENT;
    t0 = rendercache__now(rc);
    rc->predicted = v;
    rendercache__compose_objects(rc, &rc->predicted, rc->obj_predicted);
    rendercache__splat_points(rc, &rc->predicted, rc->obj_predicted, 0, NULL);
    rendercache__run_jobs(rc->parallel_for, rc->parallel_user, rendercache__predict_job, rc, rc->tile_count);
    rc->pred_holes = rendercache__tile_sum(rc, 5);
    rc->has_prediction = 1;
    rc->stats.time_predict += rendercache__now(rc) - t0;
    return RENDERCACHE_OK;
}

/* ======================================================================
   14. sample selection: thresholding and error diffusion of the priority
   image (WDP99, after Floyd and Steinberg 1976).
   Thresholding: priorities are binned into RENDERCACHE__LEVELS levels; the
   levels above a cut level, all of whose pixels fit the budget, are taken
   whole (value 1); the cut level gets the fraction of the budget left
   (value in (0, 1)); lower levels get 0. So holes are served before old
   points, and old points before young ones.
   Error diffusion: Floyd-Steinberg on these values in serpentine order
   spreads the fractional level's requests evenly (with a modulated
   threshold for sparse levels, see below). Pixels of value 0 or 1 are
   decided outright and pass incoming error on unchanged; error that would
   leave the image goes to the next pixel in scan order instead, so the
   count equals the budget up to the last pixel's residual, which a final
   pass corrects with the pixels closest to the threshold. Each decision
   depends on the previous ones, so this step is serial; everything around
   it runs in tiles.
   ---------------------------------------------------------------------- */
typedef struct rendercache__select_job {
    rendercache *rc;
    const float *priority;
    uint32_t cut;
    float fraction;
} rendercache__select_job;

/* The histogram level of a priority in [0, 1] (anything else: level 0). */
static uint32_t rendercache__level(float priority)
{
    float l = priority * (float)RENDERCACHE__LEVELS;
    l = l > 0.0f ? l : 0.0f;
    l = l < (float)(RENDERCACHE__LEVELS - 1) ? l : (float)(RENDERCACHE__LEVELS - 1);
    return (uint32_t)l;
}

static void rendercache__histogram_job(void *ctx, uint32_t tile)
{
    const rendercache__select_job *j = (const rendercache__select_job *)ctx;
    const rendercache *rc = j->rc;
    const float *priority = j->priority;
    uint32_t *h = rc->hist + (size_t)tile * RENDERCACHE__LEVELS;
    uint32_t p0 = tile * RENDERCACHE__TILE_ROWS * rc->width, p1 = p0 + RENDERCACHE__TILE_ROWS * rc->width, p;
    if (p1 > rc->pixel_count) p1 = rc->pixel_count;
    memset(h, 0, RENDERCACHE__LEVELS * sizeof *h);
    for (p = p0; p < p1; p++)
        if (priority[p] > 0.0f) h[rendercache__level(priority[p])]++;
}

/* Job per tile: the pixels decided outright, and those left to the error
   diffusion (all of value fraction). */
static void rendercache__threshold_job(void *ctx, uint32_t tile)
{
    const rendercache__select_job *j = (const rendercache__select_job *)ctx;
    rendercache *rc = j->rc;
    const float *priority = j->priority;
    const uint32_t cut = j->cut;
    const unsigned char at_cut = j->fraction >= 1.0f ? 1u : 2u;   /* a whole level fits: chosen outright */
    unsigned char *chosen = rc->chosen;
    uint32_t p0 = tile * RENDERCACHE__TILE_ROWS * rc->width, p1 = p0 + RENDERCACHE__TILE_ROWS * rc->width, p, ones = 0;
    if (p1 > rc->pixel_count) p1 = rc->pixel_count;
    for (p = p0; p < p1; p++) {
        float pr = priority[p];
        uint32_t l = rendercache__level(pr);
        /* 1: chosen outright; 2: fractional (value: the cut's fraction), for the error diffusion */
        unsigned char c = !(pr > 0.0f) ? 0u : (l > cut ? 1u : (l == cut ? at_cut : 0u));
        chosen[p] = c;
        ones += c == 1u;
    }
    rc->tile_stats[RENDERCACHE__TILE_STATS * (size_t)tile + 5] = ones;
}

/* Finds the cut level and its fraction so that the values sum to budget
   (or to the number of positive pixels when fewer). */
static void rendercache__find_cut(rendercache *rc, uint32_t budget, uint32_t *cut, float *fraction)
{
    uint32_t *total = rc->hist + (size_t)rc->tile_count * RENDERCACHE__LEVELS, t, l;
    uint64_t above = 0;
    memset(total, 0, RENDERCACHE__LEVELS * sizeof *total);
    for (t = 0; t < rc->tile_count; t++) {
        const uint32_t *h = rc->hist + (size_t)t * RENDERCACHE__LEVELS;
        for (l = 0; l < RENDERCACHE__LEVELS; l++) total[l] += h[l];
    }
    *cut = 0;
    *fraction = 1.0f;
    for (l = RENDERCACHE__LEVELS; l-- > 0;) {
        if (above + total[l] >= budget) {
            *cut = l;
            *fraction = (float)((double)(budget - above) / (double)total[l]);
            return;
        }
        above += total[l];
    }
}

/* Whether pixel q takes part in the diffusion (its value is fractional). */
static int rendercache__fractional(const rendercache *rc, uint32_t q)
{
    return (rc->chosen[q] & 2u) != 0;
}

/* Hands the error e of pixel (x, y) to its unvisited neighbours with the
   Floyd-Steinberg weights 7/16 ahead, 3/16 behind-below, 5/16 below, 1/16
   ahead-below. A weight whose neighbour lies outside the image goes to the
   pixel below instead (ahead on the last row); then only fractional
   neighbours keep their weight, renormalised, so error never lands on a
   pixel whose choice is already made (it would be lost there). Returns the
   part that found no taker, for the next fractional pixel in scan order. */
static float rendercache__spread_error(const rendercache *rc, float *cur, float *next, uint32_t y, int x, int dir,
                                       float e)
{
    int w = (int)rc->width, ax = x + dir, bx = x - dir, below = y + 1 < rc->height;
    float wt[4] = { 7.0f, 3.0f, 5.0f, 1.0f }, sum, s;   /* ahead, behind-below, below, ahead-below */
    uint32_t row = y * rc->width, row_below = row + rc->width;
    if (!below) {   /* last row: everything ahead, if there is an ahead */
        if (ax < 0 || ax >= w || !rendercache__fractional(rc, row + (uint32_t)ax)) return e;
        cur[ax + 1] += e;
        return 0.0f;
    }
    if (ax < 0 || ax >= w) { wt[2] += wt[0] + wt[3]; wt[0] = wt[3] = 0.0f; }
    if (bx < 0 || bx >= w) { wt[2] += wt[1]; wt[1] = 0.0f; }
    if (wt[0] > 0.0f && !rendercache__fractional(rc, row + (uint32_t)ax)) wt[0] = 0.0f;
    if (wt[1] > 0.0f && !rendercache__fractional(rc, row_below + (uint32_t)bx)) wt[1] = 0.0f;
    if (wt[2] > 0.0f && !rendercache__fractional(rc, row_below + (uint32_t)x)) wt[2] = 0.0f;
    if (wt[3] > 0.0f && !rendercache__fractional(rc, row_below + (uint32_t)ax)) wt[3] = 0.0f;
    sum = wt[0] + wt[1] + wt[2] + wt[3];
    if (sum == 0.0f) return e;
    s = e / sum;
    if (wt[0] > 0.0f) cur[ax + 1] += wt[0] * s;
    if (wt[1] > 0.0f) next[bx + 1] += wt[1] * s;
    if (wt[2] > 0.0f) next[x + 1] += wt[2] * s;
    if (wt[3] > 0.0f) next[ax + 1] += wt[3] * s;
    return 0.0f;
}

/* Threshold modulation (Knuth 1987; Eschbach and Knox 1991): a sparse
   level under plain Floyd-Steinberg chooses nothing until the error has
   piled up to 0.5, and it spreads sideways while it does, so the first rows
   of the image starve and choices come in bursts. A threshold varied per
   pixel by up to +-amp breaks that up; it fades out as the level gets
   denser (no transient there, and it would let choices touch). The
   variation is a hash of (pixel, frame): deterministic, and different from
   frame to frame. */
#define RENDERCACHE__MODULATION 0.4f          /* amplitude at density 0 */
#define RENDERCACHE__MODULATION_FADE 0.1f     /* density where it reaches 0 */

static float rendercache__threshold(uint32_t p, uint32_t frame, float amp)
{
    /* a 32-bit integer hash (lowbias32, Wellons): the serial loop is this one */
    uint32_t z = p * 0x9E3779B9u ^ frame * 0x85EBCA6Bu;
    z ^= z >> 16;
    z *= 0x7FEB352Du;
    z ^= z >> 15;
    z *= 0x846CA68Bu;
    z ^= z >> 16;
    return 0.5f + amp * ((float)(z >> 8) * (1.0f / 8388608.0f) - 1.0f);
}

/* Serial serpentine Floyd-Steinberg pass over the fractional pixels (of
   value fraction, the cut level's share); marks rc->chosen and returns the
   count. Pixels of value 0 or 1 are decided outright; the error moves
   among the fractional pixels only, so their count is their total value up
   to the last carry. Fractional pixels keep value + incoming error in select_v
   for the count correction. The threshold pass marked them (chosen & 2)
   and counted the pixels chosen outright (tile statistics column 5). */
static uint32_t rendercache__diffuse(rendercache *rc, float fraction, uint32_t *best_add, uint32_t *best_drop)
{
    uint32_t w = rc->width, h = rc->height, y, count = rendercache__tile_sum(rc, 5);
    unsigned char *chosen = rc->chosen;
    float *select_v = rc->select_v;
    float add_v = -FLT_MAX, drop_v = FLT_MAX;
    float *cur = rc->err_rows, *next = rc->err_rows + (w + 2), carry = 0.0f;
    float amp = RENDERCACHE__MODULATION * (1.0f - fraction / RENDERCACHE__MODULATION_FADE);
    if (amp < 0.0f) amp = 0.0f;
    memset(cur, 0, (w + 2) * sizeof *cur);
    for (y = 0; y < h; y++) {
        int dir = (y & 1u) ? -1 : 1, x = dir > 0 ? 0 : (int)w - 1, k;
        float *t;
        memset(next, 0, (w + 2) * sizeof *next);
        for (k = 0; k < (int)w; k++, x += dir) {
            uint32_t p = y * w + (uint32_t)x;
            float total, e;
            unsigned char pick;
            if (!(chosen[p] & 2u)) continue;   /* decided by the threshold */
            total = fraction + cur[x + 1] + carry;
            pick = total >= rendercache__threshold(p, rc->frame, amp) ? 1u : 0u;
            e = total - (float)pick;
            select_v[p] = total;
            chosen[p] = (unsigned char)(2u | pick);
            count += pick;
            if (pick ? total < drop_v : total > add_v) {   /* the marginal choices, for the correction */
                if (pick) { drop_v = total; *best_drop = p; }
                else { add_v = total; *best_add = p; }
            }
            carry = rendercache__spread_error(rc, cur, next, y, x, dir, e);
        }
        t = cur; cur = next; next = t;
    }
    return count;
}

/* Brings the count to the target with the fractional pixels nearest the
   threshold: adds the unchosen with the largest value + error, or drops the
   chosen with the smallest. The residual (the error left over at the end of
   the diffusion) is mostly one pixel, which the diffusion pass already
   found (best_add, best_drop); a larger one takes one scan per 64 pixels,
   keeping the best 64 candidates in a sorted list. */
#define RENDERCACHE__CORRECT_BATCH 64u
static uint32_t rendercache__correct_count(rendercache *rc, uint32_t count, uint32_t target, uint32_t best_add,
                                           uint32_t best_drop)
{
    if (count + 1 == target && best_add != RENDERCACHE__NONE) { rc->chosen[best_add] ^= 1u; return target; }
    if (count == target + 1 && best_drop != RENDERCACHE__NONE) { rc->chosen[best_drop] ^= 1u; return target; }
    while (count != target) {
        uint32_t list[RENDERCACHE__CORRECT_BATCH], n = 0, want, p, i;
        float key[RENDERCACHE__CORRECT_BATCH];
        int add = count < target;
        want = add ? target - count : count - target;
        if (want > RENDERCACHE__CORRECT_BATCH) want = RENDERCACHE__CORRECT_BATCH;
        for (p = 0; p < rc->pixel_count; p++) {
            unsigned char c = rc->chosen[p];
            float k;
            if (!(c & 2u) || (int)(c & 1u) == add) continue;
            k = add ? -rc->select_v[p] : rc->select_v[p];   /* smaller key: better candidate */
            if (n == want && !(k < key[n - 1])) continue;
            i = n < want ? n++ : n - 1;
            while (i > 0 && k < key[i - 1]) { key[i] = key[i - 1]; list[i] = list[i - 1]; i--; }
            key[i] = k;
            list[i] = p;
        }
        if (n == 0) break;
        for (i = 0; i < n; i++) rc->chosen[list[i]] ^= 1u;
        count = add ? count + n : count - n;
    }
    return count;
}

/* Selects up to budget pixels of a priority image into rc->chosen. */
static uint32_t rendercache__select(rendercache *rc, const float *priority, uint32_t budget)
{
    rendercache__select_job job;
    uint64_t positive = 0;
    uint32_t l, count, target, best_add = RENDERCACHE__NONE, best_drop = RENDERCACHE__NONE;
    if (budget == 0) return 0;
    job.rc = rc;
    job.priority = priority;
    rendercache__run_jobs(rc->parallel_for, rc->parallel_user, rendercache__histogram_job, &job, rc->tile_count);
    rendercache__find_cut(rc, budget, &job.cut, &job.fraction);
    for (l = 0; l < RENDERCACHE__LEVELS; l++) positive += rc->hist[(size_t)rc->tile_count * RENDERCACHE__LEVELS + l];
    target = positive < budget ? (uint32_t)positive : budget;
    rendercache__run_jobs(rc->parallel_for, rc->parallel_user, rendercache__threshold_job, &job, rc->tile_count);
    count = rendercache__diffuse(rc, job.fraction, &best_add, &best_drop);
    return rendercache__correct_count(rc, count, target, best_add, best_drop);
}

/* Writes the chosen pixels as requests in scan order and zeroes their
   priority, so a further request call moves on to the next pixels. */
static uint32_t rendercache__emit(rendercache *rc, const rendercache__view *v, float *priority, uint32_t flags,
                                  rendercache_pixel_request *out, uint32_t max)
{
    uint32_t p, n = 0;
    for (p = 0; p < rc->pixel_count && n < max; p++) {
        rendercache_pixel_request *r;
        if (!(rc->chosen[p] & 1u)) continue;
        r = &out[n++];
        r->x = p % rc->width;
        r->y = p / rc->width;
        r->flags = flags;
        memcpy(r->org, v->eye, sizeof r->org);
        rendercache__view_ray(v, (float)r->x + 0.5f, (float)r->y + 0.5f, r->dir);
        priority[p] = 0.0f;
    }
    return n;
}

RENDERCACHE_API rendercache_result rendercache_request(rendercache *rc, rendercache_pixel_request *out,
                                                       uint32_t max, uint32_t *count)
{
    uint32_t n = 0, pred_budget = 0;
    double t0;
    if (count) *count = 0;
    if (!rc || !count || (!out && max) || !rc->has_frame) return RENDERCACHE_ERROR_INVALID_ARGUMENT;
    if (max == 0) return RENDERCACHE_OK;
    t0 = rendercache__now(rc);
    if (rc->has_prediction) {
        pred_budget = (uint32_t)((double)max * rc->predict_fraction);
        if (pred_budget > rc->pred_holes) pred_budget = rc->pred_holes;
    }
    if (rendercache__select(rc, rc->priority, max - pred_budget))
        n = rendercache__emit(rc, &rc->view, rc->priority, 0u, out, max - pred_budget);
    if (rc->has_prediction && n < max && rendercache__select(rc, rc->pred_priority, max - n)) {
        uint32_t m = rendercache__emit(rc, &rc->predicted, rc->pred_priority, RENDERCACHE_REQUEST_PREDICTED,
                                       out + n, max - n);
        rc->pred_holes -= m;
        rc->stats.predicted += m;
        n += m;
    }
    rc->stats.requested += n;
    rc->stats.time_request += rendercache__now(rc) - t0;
    *count = n;
    return RENDERCACHE_OK;
}

/* ======================================================================
   15. insertion and eviction
   ---------------------------------------------------------------------- */
/* Whether slot shows in the current frame: inserted in it, or its point
   projects to a pixel that shows it. Checked only for the slots the clock
   hand passes, so nothing is written per point and frame. */
static int rendercache__slot_in_use(const rendercache *rc, uint32_t slot)
{
    rendercache__projector pr;
    float depth;
    uint32_t p;
    if (rc->data[slot].birth == rc->frame) return 1;
    pr.rc = rc;
    pr.view = &rc->view;
    pr.obj_camera = rc->obj_camera;
    p = rendercache__project_point(&pr, &rc->geo[slot], &depth);
    return p != RENDERCACHE__NONE && rc->px_index[p] == slot;
}

/* Eviction (clock, second chance): the hand walks the slots in the order
   they were filled, so the slot under it holds the oldest insertion; a
   point shown in this frame is skipped (still useful), a free slot or a
   point not visible (off screen, hidden, culled) is taken. When a whole
   turn finds nothing, the cache is smaller than what is visible and the
   oldest slot is taken anyway. */
static uint32_t rendercache__victim(rendercache *rc)
{
    uint32_t scanned, slot;
    for (scanned = 0; !rc->hand_exhausted && scanned < rc->capacity; scanned++) {
        slot = rc->hand;
        rc->hand = slot + 1 == rc->capacity ? 0 : slot + 1;
        if (rc->geo[slot].object == RENDERCACHE__FREE_SLOT || !rendercache__slot_in_use(rc, slot)) return slot;
    }
    rc->hand_exhausted = 1;
    slot = rc->hand;
    rc->hand = slot + 1 == rc->capacity ? 0 : slot + 1;
    return slot;
}

static int rendercache__sample_valid(const rendercache *rc, const rendercache_sample *s)
{
    if (s->x >= rc->width || s->y >= rc->height) return 0;
    if (s->flags & ~RENDERCACHE_REQUEST_PREDICTED) return 0;
    if ((s->flags & RENDERCACHE_REQUEST_PREDICTED) && !rc->has_prediction) return 0;
    if (s->object != RENDERCACHE_MISS && s->object >= rc->object_count) return 0;
    if (s->object != RENDERCACHE_MISS && !rendercache__finite3(s->position)) return 0;
    if (!rendercache__finite3(s->rgb) || !(s->priority_scale >= 0.0f) || !isfinite(s->priority_scale)) return 0;
    return 1;
}

/* Stores sample s in slot; returns its squared distance from the eye of view v. */
static float rendercache__store(rendercache *rc, uint32_t slot, const rendercache_sample *s, const rendercache__view *v)
{
    rendercache__geo *g = &rc->geo[slot];
    rendercache__point *pt = &rc->data[slot];
    float *pos = g->pos, d;
    if (g->object == RENDERCACHE__FREE_SLOT) rc->live++;
    if (s->object == RENDERCACHE_MISS) {
        rendercache__view_ray(v, (float)s->x + 0.5f, (float)s->y + 0.5f, pos);
        d = RENDERCACHE__FAR2;
    } else {
        float dx = s->position[0] - v->eye[0], dy = s->position[1] - v->eye[1], dz = s->position[2] - v->eye[2];
        rendercache__affine(rc->obj_local + 12 * (size_t)s->object, s->position, pos);
        d = dx * dx + dy * dy + dz * dz;
    }
    g->object = s->object;
    memcpy(pt->rgb, s->rgb, sizeof pt->rgb);
    pt->scale = s->priority_scale > 0.0f ? s->priority_scale : 1.0f;
    pt->birth = rc->frame;   /* age 0; new points are not evicted in their own frame */
    pt->motion_birth = s->object == RENDERCACHE_MISS ? 0u : rc->obj_motion[s->object];
    return d;
}

/* A current-frame sample also becomes its pixel's point at once. */
static void rendercache__show(rendercache *rc, uint32_t p, uint32_t slot, float depth, const float rgb[3])
{
    rc->px_index[p] = slot;
    rc->px_depth[p] = depth;
    memcpy(rc->image + 3 * (size_t)p, rgb, 3 * sizeof(float));
    rc->kind[p] = RENDERCACHE_PIXEL_POINT;
    rc->count[p] = 0;
    rc->priority[p] = 0.0f;
}

/* Reads the slots that the next samples will replace in place, all at
   once, so that their cache misses overlap instead of coming one by one.
   Returns a value that depends on the reads (for the caller to keep). */
static uint32_t rendercache__touch_slots(const rendercache *rc, const rendercache_sample *samples, uint32_t n)
{
    uint32_t i, sum = 0;
    for (i = 0; i < n; i++) {
        const rendercache_sample *s = &samples[i];
        uint32_t slot;
        if (s->x >= rc->width || s->y >= rc->height || (s->flags & RENDERCACHE_REQUEST_PREDICTED)) continue;
        slot = rc->px_index[s->y * rc->width + s->x];
        if (slot != RENDERCACHE__NONE) sum += rc->geo[slot].object + rc->data[slot].birth;
    }
    return sum;
}

RENDERCACHE_API rendercache_result rendercache_insert(rendercache *rc, const rendercache_sample *samples, uint32_t n)
{
    uint32_t i;
    double t0;
    if (!rc || (!samples && n)) return RENDERCACHE_ERROR_INVALID_ARGUMENT;
    t0 = rendercache__now(rc);
    for (i = 0; i < n; i++) {
        const rendercache_sample *s = &samples[i];
        int predicted = (s->flags & RENDERCACHE_REQUEST_PREDICTED) != 0;
        const rendercache__view *v = predicted ? &rc->predicted : &rc->view;
        uint32_t p, slot;
        float d;
        if (i % 32 == 0) rc->touched += rendercache__touch_slots(rc, s, n - i < 32 ? n - i : 32);
        if (!rendercache__sample_valid(rc, s) || (!predicted && !rc->has_frame)) { rc->stats.rejected++; continue; }
        p = s->y * rc->width + s->x;
        slot = predicted ? RENDERCACHE__NONE : rc->px_index[p];
        if (slot != RENDERCACHE__NONE) {
            rc->stats.replaced++;
        } else {
            slot = rendercache__victim(rc);
            if (rc->geo[slot].object != RENDERCACHE__FREE_SLOT) rc->stats.evicted++;
        }
        d = rendercache__store(rc, slot, s, v);
        if (!predicted) rendercache__show(rc, p, slot, d, s->rgb);
        rc->stats.inserted++;
    }
    rc->stats.live_points = rc->live;
    rc->stats.time_insert += rendercache__now(rc) - t0;
    return RENDERCACHE_OK;
}

/* ======================================================================
   16. accessors and camera helpers
   ---------------------------------------------------------------------- */
RENDERCACHE_API const float *rendercache_image(const rendercache *rc) { return rc ? rc->image : NULL; }
RENDERCACHE_API const float *rendercache_priority_image(const rendercache *rc) { return rc ? rc->priority : NULL; }
RENDERCACHE_API const unsigned char *rendercache_pixel_kinds(const rendercache *rc) { return rc ? rc->kind : NULL; }
RENDERCACHE_API const float *rendercache_depth_image(rendercache *rc)
{
    uint32_t p;
    if (!rc) return NULL;
    for (p = 0; p < rc->pixel_count; p++)
        rc->depth_out[p] = rc->px_depth[p] == FLT_MAX ? FLT_MAX : sqrtf(rc->px_depth[p]);
    return rc->depth_out;
}

RENDERCACHE_API void rendercache_get_stats(const rendercache *rc, rendercache_stats *out)
{
    if (!out) return;
    if (!rc) { memset(out, 0, sizeof *out); return; }
    *out = rc->stats;
}

RENDERCACHE_API rendercache_result rendercache_camera_ray(const rendercache_camera *camera, float px, float py,
                                                          float org[3], float dir[3])
{
    rendercache__view v;
    if (!org || !dir || !rendercache__view_init(&v, camera) || !isfinite(px) || !isfinite(py))
        return RENDERCACHE_ERROR_INVALID_ARGUMENT;
    memcpy(org, v.eye, 3 * sizeof(float));
    rendercache__view_ray(&v, px, py, dir);
    return RENDERCACHE_OK;
}

RENDERCACHE_API int rendercache_camera_project(const rendercache_camera *camera, const float p[3], float *px,
                                               float *py, float *depth)
{
    rendercache__view v;
    float w[3], c[3], x, y;
    if (!p || !rendercache__view_init(&v, camera) || !rendercache__finite3(p)) return 0;
    w[0] = p[0] - v.eye[0];
    w[1] = p[1] - v.eye[1];
    w[2] = p[2] - v.eye[2];
    rendercache__view_rotate(&v, w, c);
    if (!rendercache__view_to_pixel(&v, c, &x, &y)) return 0;
    if (px) *px = x;
    if (py) *py = y;
    if (depth) *depth = sqrtf(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
    return 1;
}

RENDERCACHE_API const char *rendercache_result_string(rendercache_result r)
{
    switch (r) {
    case RENDERCACHE_OK: return "ok";
    case RENDERCACHE_ERROR_INVALID_ARGUMENT: return "invalid argument";
    case RENDERCACHE_ERROR_OUT_OF_MEMORY: return "out of memory";
    case RENDERCACHE_ERROR_CORRUPT_DATA: return "corrupt data";
    case RENDERCACHE_ERROR_VERSION: return "unsupported format version";
    case RENDERCACHE_ERROR_CANCELLED: return "cancelled";
    case RENDERCACHE_ERROR_IO: return "read or write callback failed";
    }
    return "unknown result";
}

#endif /* RENDERCACHE_IMPLEMENTATION */

/*
------------------------------------------------------------------------------
This software is available under 2 licenses -- choose whichever you prefer.
------------------------------------------------------------------------------
ALTERNATIVE A - MIT License
Copyright (c) 2026 The irrvol/radinterp/lightvec/rendercache authors
Permission is hereby granted, free of charge, to any person obtaining a copy of
this software and associated documentation files (the "Software"), to deal in
the Software without restriction, including without limitation the rights to
use, copy, modify, merge, publish, distribute, sublicense, and/or sell copies
of the Software, and to permit persons to whom the Software is furnished to do
so, subject to the following conditions:
The above copyright notice and this permission notice shall be included in all
copies or substantial portions of the Software.
THE SOFTWARE IS PROVIDED "AS IS", WITHOUT WARRANTY OF ANY KIND, EXPRESS OR
IMPLIED, INCLUDING BUT NOT LIMITED TO THE WARRANTIES OF MERCHANTABILITY,
FITNESS FOR A PARTICULAR PURPOSE AND NONINFRINGEMENT. IN NO EVENT SHALL THE
AUTHORS OR COPYRIGHT HOLDERS BE LIABLE FOR ANY CLAIM, DAMAGES OR OTHER
LIABILITY, WHETHER IN AN ACTION OF CONTRACT, TORT OR OTHERWISE, ARISING FROM,
OUT OF OR IN CONNECTION WITH THE SOFTWARE OR THE USE OR OTHER DEALINGS IN THE
SOFTWARE.
------------------------------------------------------------------------------
ALTERNATIVE B - Public Domain (www.unlicense.org)
This is free and unencumbered software released into the public domain.
Anyone is free to copy, modify, publish, use, compile, sell, or distribute this
software, either in source code form or as a compiled binary, for any purpose,
commercial or non-commercial, and by any means.
In jurisdictions that recognize copyright laws, the author or authors of this
software dedicate any and all copyright interest in the software to the public
domain. We make this dedication for the benefit of the public at large and to
the detriment of our heirs and successors. We intend this dedication to be an
overt act of relinquishment in perpetuity of all present and future rights to
this software under copyright law.
THE SOFTWARE IS PROVIDED "AS IS", WITHOUT WARRANTY OF ANY KIND, EXPRESS OR
IMPLIED, INCLUDING BUT NOT LIMITED TO THE WARRANTIES OF MERCHANTABILITY,
FITNESS FOR A PARTICULAR PURPOSE AND NONINFRINGEMENT. IN NO EVENT SHALL THE
AUTHORS BE LIABLE FOR ANY CLAIM, DAMAGES OR OTHER LIABILITY, WHETHER IN AN
ACTION OF CONTRACT, TORT OR OTHERWISE, ARISING FROM, OUT OF OR IN CONNECTION
WITH THE SOFTWARE OR THE USE OR OTHER DEALINGS IN THE SOFTWARE.
------------------------------------------------------------------------------
*/
