/* Unit tests of rendercache.h, range-image walkthroughs (Nimeroff, Dorsey
   and Rushmeier 1996): the wide-angle cameras, view interpolation with its
   fill modes, and time interpolation. Known answers come from an analytic
   scene of axis-aligned boxes in front of a wall: every surface has its own
   colour channel with a colour linear in (object-space) position, so a
   reprojected pixel can be checked against the exact colour of the surface
   it shows, and a colour blended across a depth edge shows as two non-zero
   channels. */
#include "examples/common/pool.h"
#define RENDERCACHE_IMPLEMENTATION
#include "rendercache.h"
#include "test.h"

#include <float.h>

#define PI_F 3.14159265f

/* ---------------------------------------------------------------------
   The scene: object 0 is a wall at z = wall_z (|x|, |y| <= wall_half,
   red), then up to four boxes (objects 1.., green or blue), each with a
   translation (for moving objects: the texture moves with the box). Rays
   that miss everything see the sky (RENDERCACHE_MISS), colour (0, 0, 0)
   plus a little of every channel, so that it never looks like a surface.
   --------------------------------------------------------------------- */
typedef struct box {
    float lo[3], hi[3];      /* object space */
    float shift[3];          /* object to world translation */
    int channel;
} box;

typedef struct scene {
    float wall_z, wall_half;
    box boxes[4];
    int box_count;
} scene;

static float texture(const float p[3]) { return 0.5f + 0.04f * p[0] + 0.03f * p[1] + 0.02f * p[2]; }

/* Ray / box slab test: entry distance or -1. */
static float hit_box(const box *b, const float o[3], const float d[3])
{
    float t0 = 0.0f, t1 = FLT_MAX;
    int k;
    for (k = 0; k < 3; k++) {
        float lo = b->lo[k] + b->shift[k], hi = b->hi[k] + b->shift[k];
        if (d[k] == 0.0f) {
            if (o[k] < lo || o[k] > hi) return -1.0f;
            continue;
        }
        {
            float a = (lo - o[k]) / d[k], c = (hi - o[k]) / d[k];
            if (a > c) { float s = a; a = c; c = s; }
            t0 = a > t0 ? a : t0;
            t1 = c < t1 ? c : t1;
        }
    }
    return t0 <= t1 && t0 > 0.0f ? t0 : -1.0f;
}

/* Closest hit: object id (or RENDERCACHE_MISS), distance and colour. */
static uint32_t trace(const scene *s, const float o[3], const float d[3], float *dist, float rgb[3])
{
    uint32_t id = RENDERCACHE_MISS;
    float best = FLT_MAX, p[3];
    int i, k;
    rgb[0] = rgb[1] = rgb[2] = 0.05f;
    *dist = FLT_MAX;
    if (d[2] != 0.0f) {
        float t = (s->wall_z - o[2]) / d[2];
        if (t > 0.0f && fabsf(o[0] + t * d[0]) <= s->wall_half && fabsf(o[1] + t * d[1]) <= s->wall_half) {
            best = t;
            id = 0;
        }
    }
    for (i = 0; i < s->box_count; i++) {
        float t = hit_box(&s->boxes[i], o, d);
        if (t > 0.0f && t < best) { best = t; id = (uint32_t)i + 1u; }
    }
    if (id == RENDERCACHE_MISS) return id;
    for (k = 0; k < 3; k++) p[k] = o[k] + best * d[k];
    rgb[0] = rgb[1] = rgb[2] = 0.0f;
    if (id == 0) {
        rgb[0] = texture(p);
    } else {
        const box *b = &s->boxes[id - 1];
        float q[3];
        for (k = 0; k < 3; k++) q[k] = p[k] - b->shift[k];
        rgb[b->channel] = texture(q);
    }
    *dist = best;
    return id;
}

static rendercache_camera make_camera(rendercache_camera_kind kind, float ex, float ey, float ez, float lx, float ly,
                                      float lz, float vfov, uint32_t w, uint32_t h)
{
    rendercache_camera c;
    memset(&c, 0, sizeof c);
    c.kind = kind;
    c.eye[0] = ex; c.eye[1] = ey; c.eye[2] = ez;
    c.look_at[0] = lx; c.look_at[1] = ly; c.look_at[2] = lz;
    c.up[1] = 1.0f;
    c.vfov_degrees = vfov;
    c.width = w;
    c.height = h;
    return c;
}

/* A range image of the scene for camera (the test owns it). */
static rendercache_range_image *render(const scene *s, const rendercache_camera *cam, double time)
{
    rendercache_range_image *img = NULL;
    uint32_t x, y;
    if (rendercache_range_image_create(cam, NULL, &img) != RENDERCACHE_OK) return NULL;
    img->time = time;
    for (y = 0; y < cam->height; y++)
        for (x = 0; x < cam->width; x++) {
            size_t p = (size_t)y * cam->width + x;
            float o[3], d[3], dist;
            if (rendercache_camera_ray(cam, (float)x + 0.5f, (float)y + 0.5f, o, d) != RENDERCACHE_OK) continue;
            img->object[p] = trace(s, o, d, &dist, img->rgb + 3 * p);
            img->depth[p] = img->object[p] == RENDERCACHE_MISS ? RENDERCACHE_FAR_DEPTH : dist;
        }
    return img;
}

static rendercache_warper *make_warper(void (*pf)(void *, rendercache_job_fn, void *, uint32_t), void *user)
{
    rendercache_warp_desc d;
    rendercache_warper *w = NULL;
    memset(&d, 0, sizeof d);
    d.parallel_for = pf;
    d.parallel_user = user;
    CHECK_EQ_INT(rendercache_warper_create(&d, &w), RENDERCACHE_OK);
    return w;
}

/* The analytic ids at the centre and the four corners of pixel (x, y) of
   cam: returns 1 when they are all the same (the pixel lies inside one
   surface), with that id. */
static int pixel_interior(const scene *s, const rendercache_camera *cam, uint32_t x, uint32_t y, uint32_t *id)
{
    static const float cx[5] = { 0.5f, 0.0f, 1.0f, 0.0f, 1.0f }, cy[5] = { 0.5f, 0.0f, 0.0f, 1.0f, 1.0f };
    int k;
    for (k = 0; k < 5; k++) {
        float o[3], d[3], rgb[3], dist;
        uint32_t i;
        rendercache_camera_ray(cam, (float)x + cx[k], (float)y + cy[k], o, d);
        i = trace(s, o, d, &dist, rgb);
        if (k == 0) *id = i;
        else if (i != *id) return 0;
    }
    return 1;
}

/* Whether every pixel in the 3x3 neighbourhood of (x, y) is interior to the same surface. */
static int far_from_edges(const scene *s, const rendercache_camera *cam, uint32_t x, uint32_t y, uint32_t *id)
{
    int dx, dy;
    uint32_t first = 0, i;
    for (dy = -1; dy <= 1; dy++)
        for (dx = -1; dx <= 1; dx++) {
            int qx = (int)x + dx, qy = (int)y + dy;
            if (qx < 0 || qy < 0 || qx >= (int)cam->width || qy >= (int)cam->height) return 0;
            if (!pixel_interior(s, cam, (uint32_t)qx, (uint32_t)qy, &i)) return 0;
            if (dx == -1 && dy == -1) first = i;
            else if (i != first) return 0;
        }
    *id = first;
    return 1;
}

static scene boxes_scene(void)
{
    scene s;
    memset(&s, 0, sizeof s);
    s.wall_z = 10.0f;
    s.wall_half = 40.0f;
    s.box_count = 2;
    s.boxes[0].lo[0] = -1.6f; s.boxes[0].lo[1] = -1.0f; s.boxes[0].lo[2] = 5.0f;
    s.boxes[0].hi[0] = -0.4f; s.boxes[0].hi[1] = 0.8f; s.boxes[0].hi[2] = 6.0f;
    s.boxes[0].channel = 1;
    s.boxes[1].lo[0] = 0.5f; s.boxes[1].lo[1] = -0.4f; s.boxes[1].lo[2] = 7.0f;
    s.boxes[1].hi[0] = 1.7f; s.boxes[1].hi[1] = 1.2f; s.boxes[1].hi[2] = 7.8f;
    s.boxes[1].channel = 2;
    return s;
}

/* ---------------------------------------------------------------------
   Cameras
   --------------------------------------------------------------------- */
static void test_fisheye_camera(void)
{
    rendercache_camera cam = make_camera(RENDERCACHE_CAMERA_FISHEYE, 1, 2, 3, 1, 2, 13, 0, 64, 48);
    float o[3], d[3], p[3], px, py, depth;
    uint32_t x, y, rays = 0;
    int k;
    /* every pixel centre inside the circle has a unit ray that projects back onto it */
    for (y = 0; y < 48; y++)
        for (x = 0; x < 64; x++) {
            float fx = (float)x + 0.5f, fy = (float)y + 0.5f, r2 = (fx - 32) * (fx - 32) + (fy - 24) * (fy - 24);
            rendercache_result r = rendercache_camera_ray(&cam, fx, fy, o, d);
            CHECK_EQ_INT(r, r2 <= 24.0f * 24.0f ? RENDERCACHE_OK : RENDERCACHE_ERROR_INVALID_ARGUMENT);
            if (r != RENDERCACHE_OK) continue;
            rays++;
            /* the direction polynomials are accurate to 1e-8; float rounding 1e-6 */
            CHECK_CLOSE(d[0] * d[0] + d[1] * d[1] + d[2] * d[2], 1.0, 0.0, 2e-6);
            for (k = 0; k < 3; k++) p[k] = o[k] + 7.0f * d[k];
            CHECK(rendercache_camera_project(&cam, p, &px, &py, &depth));
            CHECK_CLOSE(px, fx, 0.0, 2e-3);   /* float round trip through atan2: a thousandth of a pixel */
            CHECK_CLOSE(py, fy, 0.0, 2e-3);
            CHECK_CLOSE(depth, 7.0, 1e-5, 0.0);
        }
    /* the inscribed circle holds pi/4 of the 48x48 square (quantised to pixel centres) */
    CHECK_CLOSE(rays, PI_F * 24.0f * 24.0f, 0.02, 0.0);
    /* equidistant: 60 degrees off axis lands at 2/3 of the radius; right is image right */
    p[0] = 1.0f - 7.0f * sinf(PI_F / 3); p[1] = 2.0f; p[2] = 3.0f + 7.0f * cosf(PI_F / 3);
    CHECK(rendercache_camera_project(&cam, p, &px, &py, &depth));
    CHECK_CLOSE(px, 32.0 + 16.0, 0.0, 1e-3);   /* world -x is camera right (forward +z, up +y) */
    CHECK_CLOSE(py, 24.0, 0.0, 1e-3);
    /* straight up: the top of the circle; behind the eye: no image */
    p[0] = 1.0f; p[1] = 9.0f; p[2] = 3.0f;
    CHECK(rendercache_camera_project(&cam, p, &px, &py, &depth));
    CHECK_CLOSE(px, 32.0, 0.0, 1e-3);
    CHECK_CLOSE(py, 0.0, 0.0, 1e-3);
    p[1] = 2.0f; p[2] = 2.0f;
    CHECK(!rendercache_camera_project(&cam, p, &px, &py, &depth));
}

static void test_sphere_camera(void)
{
    rendercache_camera cam = make_camera(RENDERCACHE_CAMERA_SPHERE, 0, 0, 0, 0, 0, 1, 0, 128, 64);
    float o[3], d[3], p[3], px, py, depth;
    uint32_t x, y, cap = 0, front = 0;
    double mean[3] = { 0, 0, 0 };
    int k;
    for (y = 0; y < 64; y++)
        for (x = 0; x < 128; x++) {
            float fx = (float)x + 0.5f, fy = (float)y + 0.5f;
            CHECK_EQ_INT(rendercache_camera_ray(&cam, fx, fy, o, d), RENDERCACHE_OK);   /* every pixel has a ray */
            CHECK_CLOSE(d[0] * d[0] + d[1] * d[1] + d[2] * d[2], 1.0, 0.0, 2e-6);
            for (k = 0; k < 3; k++) { p[k] = 3.0f * d[k]; mean[k] += d[k]; }
            CHECK(rendercache_camera_project(&cam, p, &px, &py, &depth));
            CHECK_CLOSE(px, fx, 0.0, 2e-3);
            CHECK_CLOSE(py, fy, 0.0, 2e-3);
            front += (x < 64) == (d[2] >= 0.0f);   /* left half looks forward */
            cap += d[1] > 0.5f;                    /* the cap above 30 degrees of elevation */
        }
    CHECK_EQ_INT(front, 128 * 64);
    /* equal area: the cap y > 1/2 is a quarter of the sphere's solid angle;
       pixel quantisation along its boundary: 2% */
    CHECK_CLOSE(cap, 0.25 * 128 * 64, 0.02, 0.0);
    for (k = 0; k < 3; k++) CHECK_CLOSE(mean[k] / (128.0 * 64.0), 0.0, 0.0, 0.01);
    /* straight up and straight back */
    p[0] = 0; p[1] = 5; p[2] = 0;
    CHECK(rendercache_camera_project(&cam, p, &px, &py, &depth));
    CHECK(py < 1.0f);
    p[1] = 0; p[2] = -5;
    CHECK(rendercache_camera_project(&cam, p, &px, &py, &depth));
    CHECK_CLOSE(px, 96.0, 0.0, 1e-3);
    CHECK_CLOSE(py, 32.0, 0.0, 1e-3);
}

/* ---------------------------------------------------------------------
   Warps
   --------------------------------------------------------------------- */
static void test_warp_into_own_camera_is_identity(void)
{
    static const rendercache_fill fills[4] = { RENDERCACHE_FILL_NONE, RENDERCACHE_FILL_FOREGROUND,
                                               RENDERCACHE_FILL_BACKGROUND, RENDERCACHE_FILL_BOTH };
    scene s = boxes_scene();
    rendercache_camera cams[3];
    rendercache_warper *w = make_warper(NULL, NULL);
    int c, f;
    cams[0] = make_camera(RENDERCACHE_CAMERA_PERSPECTIVE, 0.3f, 0.2f, 0, 0, 0, 10, 60, 48, 36);
    cams[1] = make_camera(RENDERCACHE_CAMERA_FISHEYE, 0.3f, 0.2f, 0, 0, 0, 10, 0, 40, 40);
    cams[2] = make_camera(RENDERCACHE_CAMERA_SPHERE, 0.3f, 0.2f, 0, 0, 0, 10, 0, 64, 32);
    for (c = 0; c < 3 && w; c++) {
        rendercache_range_image *src = render(&s, &cams[c], 2.5), *out = NULL;
        const rendercache_range_image *in[1];
        size_t n = (size_t)cams[c].width * cams[c].height, p;
        rendercache_warp_stats st;
        in[0] = src;
        if (!CHECK(src) || !CHECK_EQ_INT(rendercache_range_image_create(&cams[c], NULL, &out), RENDERCACHE_OK)) break;
        for (f = 0; f < 4; f++) {
            uint32_t bad_rgb = 0, bad_id = 0, bad_depth = 0;
            CHECK_EQ_INT(rendercache_warp(w, in, 1, NULL, fills[f], out), RENDERCACHE_OK);
            for (p = 0; p < n; p++) {
                int k;
                bad_id += out->object[p] != src->object[p];
                for (k = 0; k < 3; k++)
                    /* without quads, bit for bit; a quad touching the pixel centre interpolates with
                       weights (1, 0, 0) up to rounding: 1e-6 */
                    bad_rgb += fabsf(out->rgb[3 * p + k] - src->rgb[3 * p + k]) > (fills[f] == RENDERCACHE_FILL_NONE ||
                                                                                   fills[f] == RENDERCACHE_FILL_BACKGROUND ? 0.0f : 1e-6f);
                if (src->object[p] < RENDERCACHE_NO_SAMPLE)   /* squared and back: 1e-6 relative */
                    bad_depth += fabsf(out->depth[p] - src->depth[p]) > 1e-6f * src->depth[p];
            }
            CHECK_MSG(bad_id == 0 && bad_rgb == 0 && bad_depth == 0, "camera %d fill %d: %u ids, %u colours, %u depths differ",
                      c, (int)fills[f], bad_id, bad_rgb, bad_depth);
            CHECK_CLOSE(out->time, 2.5, 0.0, 0.0);
            rendercache_warp_get_stats(w, &st);
            CHECK_EQ_INT(st.background + st.computed + st.empty, 0);
        }
        rendercache_range_image_destroy(src);
        rendercache_range_image_destroy(out);
    }
    rendercache_warper_destroy(w);
}

/* A textured rectangle |x|, |y| <= 2 at z = 10 in front of nothing (sky),
   seen from z = 0 and warped into a camera moved to z = 3 along its
   normal: magnified by 10/7. */
static void test_warp_along_plane_normal_matches_analytic_image(void)
{
    scene s;
    rendercache_camera from = make_camera(RENDERCACHE_CAMERA_PERSPECTIVE, 0, 0, 0, 0, 0, 10, 50, 64, 48);
    rendercache_camera to = make_camera(RENDERCACHE_CAMERA_PERSPECTIVE, 0, 0, 3, 0, 0, 10, 50, 64, 48);
    rendercache_range_image *src, *out = NULL;
    const rendercache_range_image *in[1];
    rendercache_warper *w = make_warper(NULL, NULL);
    rendercache_warp_stats st;
    uint32_t x, y, inside = 0, bad_inside = 0, bad_outside = 0, holes = 0, middle = 0, bad_none = 0;
    memset(&s, 0, sizeof s);
    s.wall_z = 10.0f;
    s.wall_half = 2.0f;
    src = render(&s, &from, 0.0);
    in[0] = src;
    if (!CHECK(src && w) || !CHECK_EQ_INT(rendercache_range_image_create(&to, NULL, &out), RENDERCACHE_OK)) return;
    CHECK_EQ_INT(rendercache_warp(w, in, 1, &to, RENDERCACHE_FILL_FOREGROUND, out), RENDERCACHE_OK);
    for (y = 0; y < 48; y++)
        for (x = 0; x < 64; x++) {
            size_t p = (size_t)y * 64 + x;
            float o[3], d[3], rgb[3], dist;
            uint32_t id;
            /* the source samples the rectangle every 1.43 target pixels: its last sample before
               the edge may lie that far inside, so pixels next to the edge are left out */
            if (!far_from_edges(&s, &to, x, y, &id)) continue;
            rendercache_camera_ray(&to, (float)x + 0.5f, (float)y + 0.5f, o, d);
            trace(&s, o, d, &dist, rgb);
            if (id == 0) {
                inside++;
                /* a linear texture on a plane parallel to the image, interpolated at the pixel
                   centre: exact up to float rounding. Squared distances are interpolated
                   linearly; on this plane they are quadratic in the image: 2e-4 relative at a
                   focal length of 51 pixels */
                bad_inside += out->object[p] != 0 || fabsf(out->rgb[3 * p] - rgb[0]) > 1e-4f ||
                              fabsf(out->depth[p] - dist) > 5e-4f * dist;
            } else {
                bad_outside += out->object[p] != RENDERCACHE_MISS;
            }
        }
    CHECK(inside > 500);
    CHECK_MSG(bad_inside == 0 && bad_outside == 0, "%u of %u rectangle pixels and %u sky pixels wrong", bad_inside,
              inside, bad_outside);
    rendercache_warp_get_stats(w, &st);
    CHECK_EQ_INT(st.empty, 0);
    /* no fill: a source pixel lands in one target pixel, whose footprint holds its colour.
       Magnified 1.43 times in both axes, about half of the pixels that see the middle of
       the rectangle (|x|, |y| < 1.3, where no sky direction of the source lands) stay empty */
    CHECK_EQ_INT(rendercache_warp(w, in, 1, &to, RENDERCACHE_FILL_NONE, out), RENDERCACHE_OK);
    for (y = 0; y < 48; y++)
        for (x = 0; x < 64; x++) {
            size_t p = (size_t)y * 64 + x;
            float lo = FLT_MAX, hi = -FLT_MAX, o[3], d[3], rgb[3], dist;
            int k;
            uint32_t id;
            rendercache_camera_ray(&to, (float)x + 0.5f, (float)y + 0.5f, o, d);
            trace(&s, o, d, &dist, rgb);
            if (fabsf(o[0] + dist * d[0]) < 1.3f && fabsf(o[1] + dist * d[1]) < 1.3f) {
                middle++;
                holes += out->object[p] == RENDERCACHE_NO_SAMPLE;
            }
            if (out->object[p] != 0) continue;
            if (!pixel_interior(&s, &to, x, y, &id) || id != 0) { bad_none++; continue; }
            for (k = 0; k < 4; k++) {
                rendercache_camera_ray(&to, (float)x + (float)(k & 1), (float)y + (float)(k >> 1), o, d);
                trace(&s, o, d, &dist, rgb);
                lo = rgb[0] < lo ? rgb[0] : lo;
                hi = rgb[0] > hi ? rgb[0] : hi;
            }
            bad_none += out->rgb[3 * p] < lo - 1e-5f || out->rgb[3 * p] > hi + 1e-5f;
        }
    CHECK_EQ_INT(bad_none, 0);
    test_note("no fill: %u of %u pixels in the middle empty (1 - 0.7^2 = 51%% expected)", holes, middle);
    CHECK_CLOSE(holes, 0.51 * middle, 0.1, 0.0);
    rendercache_range_image_destroy(src);
    rendercache_range_image_destroy(out);
    rendercache_warper_destroy(w);
}

/* Two wide base views at x = -1 and x = +1 flank the new view at x = 0:
   with both fills, every pixel whose surface either base view sees gets the
   right object, and no colour crosses a depth edge. */
static int visible_from(const scene *s, const rendercache_camera *base, const float point[3], uint32_t id)
{
    float d[3], rgb[3], dist, len, px, py, depth;
    int k;
    if (!rendercache_camera_project(base, point, &px, &py, &depth)) return 0;
    for (k = 0; k < 3; k++) d[k] = point[k] - base->eye[k];
    len = sqrtf(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    for (k = 0; k < 3; k++) d[k] /= len;
    return trace(s, base->eye, d, &dist, rgb) == id && fabsf(dist - len) < 1e-3f * len;
}

static void test_flanking_views_fill_every_visible_pixel(void)
{
    scene s = boxes_scene();
    rendercache_camera left = make_camera(RENDERCACHE_CAMERA_PERSPECTIVE, -1, 0.1f, 0, -1, 0.1f, 10, 80, 96, 72);
    rendercache_camera right = make_camera(RENDERCACHE_CAMERA_PERSPECTIVE, 1, 0.1f, 0, 1, 0.1f, 10, 80, 96, 72);
    rendercache_camera mid = make_camera(RENDERCACHE_CAMERA_PERSPECTIVE, 0, 0, 0, 0, 0, 10, 60, 64, 48);
    rendercache_range_image *a = render(&s, &left, 0), *b = render(&s, &right, 0), *out = NULL;
    const rendercache_range_image *in[2];
    rendercache_warper *w = make_warper(NULL, NULL);
    uint32_t x, y, checked = 0, wrong_id = 0, crossed = 0, unseen = 0;
    in[0] = a;
    in[1] = b;
    if (!CHECK(a && b && w) || !CHECK_EQ_INT(rendercache_range_image_create(&mid, NULL, &out), RENDERCACHE_OK)) return;
    CHECK_EQ_INT(rendercache_warp(w, in, 2, NULL, RENDERCACHE_FILL_BOTH, out), RENDERCACHE_OK);
    for (y = 0; y < 48; y++)
        for (x = 0; x < 64; x++) {
            size_t p = (size_t)y * 64 + x;
            float o[3], d[3], rgb[3], dist, point[3];
            uint32_t id, k, nonzero = 0;
            for (k = 0; k < 3; k++) nonzero += out->rgb[3 * p + k] != 0.0f;
            /* a blend across a depth edge mixes two surfaces' channels */
            crossed += nonzero != 1 || (out->object[p] < 3 && out->rgb[3 * p + (out->object[p] == 0 ? 0 :
                                                               s.boxes[out->object[p] - 1].channel)] == 0.0f);
            if (!far_from_edges(&s, &mid, x, y, &id)) continue;
            rendercache_camera_ray(&mid, (float)x + 0.5f, (float)y + 0.5f, o, d);
            trace(&s, o, d, &dist, rgb);
            for (k = 0; k < 3; k++) point[k] = o[k] + dist * d[k];
            if (!visible_from(&s, &left, point, id) && !visible_from(&s, &right, point, id)) { unseen++; continue; }
            checked++;
            wrong_id += out->object[p] != id;
        }
    test_note("flanking views: %u pixels checked, %u seen by neither base view", checked, unseen);
    CHECK(checked > 2000);
    CHECK_EQ_INT(wrong_id, 0);
    CHECK_EQ_INT(crossed, 0);
    rendercache_range_image_destroy(a);
    rendercache_range_image_destroy(b);
    rendercache_range_image_destroy(out);
    rendercache_warper_destroy(w);
}

/* ---------------------------------------------------------------------
   Tile culling: tiles of an input whose points all fall outside the
   target's frustum are skipped, with their ring of pixels, so that no
   quad reaching the image loses a corner.
   --------------------------------------------------------------------- */
/* Where the pixel (x, y) of base lands in target, as rendercache_camera_project
   says (a background pixel: a point far along its ray). Returns 0 when it has
   no sample or lands nowhere. */
static int landing(const rendercache_range_image *base, const rendercache_camera *target, uint32_t x, uint32_t y,
                   float *px, float *py)
{
    size_t p = (size_t)y * base->camera.width + x;
    float o[3], d[3], q[3], depth;
    uint32_t id = base->object[p];
    int k;
    if (id == RENDERCACHE_NO_SAMPLE) return 0;
    if (rendercache_camera_ray(&base->camera, (float)x + 0.5f, (float)y + 0.5f, o, d) != RENDERCACHE_OK) return 0;
    for (k = 0; k < 3; k++) q[k] = o[k] + (id == RENDERCACHE_MISS ? 1e5f : base->depth[p]) * d[k];
    return rendercache_camera_project(target, q, px, py, &depth);
}

/* Fish-eye and perspective inputs, most of whose pixels miss a turned
   target, warped without fill: every target pixel that some input pixel
   lands in (clear of pixel edges by more than rounding) is filled, and
   every pixel that none comes near stays empty. */
static void test_culled_tiles_lose_no_landing_pixel(void)
{
    scene s = boxes_scene();
    rendercache_camera cams[3], target;
    rendercache_range_image *bases[3], *out = NULL;
    const rendercache_range_image *in[3];
    static unsigned char sure[64 * 48], near[64 * 48];
    rendercache_warper *w = make_warper(NULL, NULL);
    uint32_t i, x, y, missing = 0, extra = 0, landed = 0;
    const float margin = 0.01f;   /* pixels: rounding of two different projections of one point */
    cams[0] = make_camera(RENDERCACHE_CAMERA_FISHEYE, -0.8f, 0.2f, 0, -0.8f, 0.2f, 10, 0, 160, 160);
    cams[1] = make_camera(RENDERCACHE_CAMERA_FISHEYE, 0.9f, -0.1f, 0.5f, 3, 0, 10, 0, 128, 128);
    cams[2] = make_camera(RENDERCACHE_CAMERA_PERSPECTIVE, 0.2f, 0, -1, -2, 0, 10, 80, 96, 72);
    target = make_camera(RENDERCACHE_CAMERA_PERSPECTIVE, 0.1f, 0, 0.3f, 3.5f, 1.0f, 10, 40, 64, 48);
    memset(sure, 0, sizeof sure);
    memset(near, 0, sizeof near);
    for (i = 0; i < 3; i++) {
        bases[i] = render(&s, &cams[i], 0);
        in[i] = bases[i];
        if (!CHECK(bases[i])) return;
        for (y = 0; y < cams[i].height; y++)
            for (x = 0; x < cams[i].width; x++) {
                float px, py;
                int dx, dy;
                if (!landing(bases[i], &target, x, y, &px, &py)) continue;
                for (dy = -1; dy <= 1; dy++)
                    for (dx = -1; dx <= 1; dx++) {
                        float qx = px + (float)dx * margin, qy = py + (float)dy * margin;
                        if (qx >= 0.0f && qy >= 0.0f && qx < 64.0f && qy < 48.0f) near[(int)qy * 64 + (int)qx] = 1;
                    }
                if (px - floorf(px) > margin && px - floorf(px) < 1.0f - margin && py - floorf(py) > margin &&
                    py - floorf(py) < 1.0f - margin)
                    sure[(int)py * 64 + (int)px] = 1;
            }
    }
    if (!CHECK(w) || !CHECK_EQ_INT(rendercache_range_image_create(&target, NULL, &out), RENDERCACHE_OK)) return;
    CHECK_EQ_INT(rendercache_warp(w, in, 3, NULL, RENDERCACHE_FILL_NONE, out), RENDERCACHE_OK);
    for (i = 0; i < 64 * 48; i++) {
        int filled = out->object[i] != RENDERCACHE_NO_SAMPLE;
        landed += sure[i];
        missing += sure[i] && !filled;
        extra += filled && !near[i];
    }
    test_note("tile culling: %u target pixels surely landed in, %u of them empty, %u filled from nowhere", landed, missing,
              extra);
    CHECK(landed > 1000);
    CHECK_EQ_INT(missing, 0);
    CHECK_EQ_INT(extra, 0);
    for (i = 0; i < 3; i++) rendercache_range_image_destroy(bases[i]);
    rendercache_range_image_destroy(out);
    rendercache_warper_destroy(w);
}

/* A fish-eye coarser than the target (0.70 against 0.42 degrees per
   pixel), of a wall that fills its view: without quads the target would
   have holes. With foreground fill every target pixel shows the wall, the
   image border included, where the tiles of the input are cut by the
   culling; and so for any number of jobs. (The input's eye lies inside the
   target's frustum, a little in front of its eye, so that only the tiles
   cull: the older culling of single rows by the planes whose outside holds
   the input's eye drops some quads at the border, see warp_culled.) The
   same from the input prepared (its tiles' bounds with their rings kept). */
static void test_culled_tiles_keep_quads_at_the_border(void)
{
    scene s;
    rendercache_camera base = make_camera(RENDERCACHE_CAMERA_FISHEYE, 0, 0, 0, 0.5f, 0.3f, 10, 0, 256, 256);
    rendercache_camera target = make_camera(RENDERCACHE_CAMERA_PERSPECTIVE, 0.1f, -0.05f, -0.6f, 1.5f, 0.4f, 10, 40, 128, 96);
    rendercache_range_image *src, *out = NULL;
    const rendercache_range_image *in[1];
    ex_pool *pool = ex_pool_create(2);
    int run;
    memset(&s, 0, sizeof s);
    s.wall_z = 10.0f;
    s.wall_half = 60.0f;
    src = render(&s, &base, 0);
    in[0] = src;
    if (!CHECK(src) || !CHECK_EQ_INT(rendercache_range_image_create(&target, NULL, &out), RENDERCACHE_OK)) return;
    for (run = 0; run < 3; run++) {
        rendercache_warper *w = run ? make_warper(pool ? ex_pool_parallel_for : NULL, pool) : make_warper(NULL, NULL);
        uint32_t p, holes = 0, border_holes = 0, none_filled = 0;
        if (!w) break;
        if (run == 2) CHECK_EQ_INT(rendercache_range_image_prepare(src), RENDERCACHE_OK);
        CHECK_EQ_INT(rendercache_warp(w, in, 1, NULL, RENDERCACHE_FILL_NONE, out), RENDERCACHE_OK);
        for (p = 0; p < 128 * 96; p++) none_filled += out->object[p] == 0;
        CHECK_EQ_INT(rendercache_warp(w, in, 1, NULL, RENDERCACHE_FILL_FOREGROUND, out), RENDERCACHE_OK);
        for (p = 0; p < 128 * 96; p++) {
            uint32_t x = p % 128, y = p / 128;
            holes += out->object[p] != 0;
            border_holes += out->object[p] != 0 && (x == 0 || y == 0 || x == 127 || y == 95);
        }
        if (run == 0) test_note("coarse fish-eye: %u of %u pixels filled by points alone, %u holes with quads",
                                none_filled, 128 * 96, holes);
        CHECK(none_filled < 128 * 96 * 3 / 4);   /* the quads are needed */
        CHECK_EQ_INT(holes, 0);
        CHECK_EQ_INT(border_holes, 0);
        rendercache_warper_destroy(w);
    }
    rendercache_range_image_destroy(src);
    rendercache_range_image_destroy(out);
    ex_pool_destroy(pool);
}

/* A sideways move uncovers the wall beside a box. Foreground quads never
   bridge the uncovered strip (depth edge), background fill gives it the
   wall, the farther surface. */
static void test_fill_modes_at_a_disocclusion(void)
{
    scene s;
    rendercache_camera from = make_camera(RENDERCACHE_CAMERA_PERSPECTIVE, 0, 0, 0, 0, 0, 10, 50, 64, 48);
    rendercache_camera to = make_camera(RENDERCACHE_CAMERA_PERSPECTIVE, 0.6f, 0, 0.5f, 0.6f, 0, 10, 50, 64, 48);
    rendercache_range_image *src, *out = NULL;
    const rendercache_range_image *in[1];
    rendercache_warper *w = make_warper(NULL, NULL);
    uint32_t x, y, hidden = 0, counts[4][3];
    int f;
    memset(&s, 0, sizeof s);
    memset(counts, 0, sizeof counts);
    s.wall_z = 10.0f;
    s.wall_half = 40.0f;
    s.box_count = 1;
    s.boxes[0].lo[0] = -1.0f; s.boxes[0].lo[1] = -1.0f; s.boxes[0].lo[2] = 4.0f;
    s.boxes[0].hi[0] = 1.0f; s.boxes[0].hi[1] = 1.0f; s.boxes[0].hi[2] = 4.5f;
    s.boxes[0].channel = 1;
    src = render(&s, &from, 0.0);
    in[0] = src;
    if (!CHECK(src && w) || !CHECK_EQ_INT(rendercache_range_image_create(&to, NULL, &out), RENDERCACHE_OK)) return;
    for (f = 0; f < 4; f++) {
        CHECK_EQ_INT(rendercache_warp(w, in, 1, NULL, (rendercache_fill)(RENDERCACHE_FILL_NONE + f), out), RENDERCACHE_OK);
        for (y = 0; y < 48; y++)
            for (x = 0; x < 64; x++) {
                size_t p = (size_t)y * 64 + x;
                float o[3], d[3], rgb[3], dist, point[3];
                uint32_t id, k;
                if (!far_from_edges(&s, &to, x, y, &id) || id != 0) continue;
                rendercache_camera_ray(&to, (float)x + 0.5f, (float)y + 0.5f, o, d);
                trace(&s, o, d, &dist, rgb);
                for (k = 0; k < 3; k++) point[k] = o[k] + dist * d[k];
                if (visible_from(&s, &from, point, 0)) continue;
                /* wall the source never saw: counts of empty / wall / box */
                hidden += f == 0;
                counts[f][out->object[p] == RENDERCACHE_NO_SAMPLE ? 0 : out->object[p] == 0 ? 1 : 2]++;
            }
    }
    test_note("uncovered wall: %u pixels; none %u/%u/%u, foreground %u/%u/%u, background %u/%u/%u, both %u/%u/%u "
              "(empty/wall/box)", hidden, counts[0][0], counts[0][1], counts[0][2], counts[1][0], counts[1][1],
              counts[1][2], counts[2][0], counts[2][1], counts[2][2], counts[3][0], counts[3][1], counts[3][2]);
    CHECK(hidden > 50);
    CHECK_EQ_INT(counts[0][0], hidden);   /* nothing lands there */
    CHECK_EQ_INT(counts[1][0], hidden);   /* no quad spans the depth edge */
    /* background: the farther neighbour, the wall, except where a box pixel is the next
       pixel (pinterp's rule: a neighbour right next to the hole wins) */
    CHECK(counts[2][1] >= hidden - hidden / 20);
    CHECK_EQ_INT(counts[3][1], hidden);
    rendercache_range_image_destroy(src);
    rendercache_range_image_destroy(out);
    rendercache_warper_destroy(w);
}

/* The fill callback computes the pixels still empty. */
static const scene *g_fill_scene;
static unsigned char g_computed[64 * 48], g_far[64 * 48];
static int fill_by_tracing(void *user, uint32_t x, uint32_t y, const float org[3], const float dir[3], float rgb[3],
                           float *depth, uint32_t *object)
{
    (*(uint32_t *)user)++;
    g_computed[y * 64 + x] = 1;
    *object = trace(g_fill_scene, org, dir, depth, rgb);
    return 1;
}

static void test_fill_callback_computes_the_rest(void)
{
    scene s = boxes_scene();
    rendercache_camera from = make_camera(RENDERCACHE_CAMERA_PERSPECTIVE, 0, 0, 0, 0, 0, 10, 50, 64, 48);
    rendercache_camera to = make_camera(RENDERCACHE_CAMERA_PERSPECTIVE, 0.8f, 0.3f, 1.0f, 0.5f, 0, 10, 55, 64, 48);
    rendercache_range_image *src = render(&s, &from, 0), *out = NULL, *ref = render(&s, &to, 0);
    const rendercache_range_image *in[1];
    rendercache_warp_desc d;
    rendercache_warper *w = NULL;
    rendercache_warp_stats st;
    uint32_t calls = 0, p, wrong = 0;
    in[0] = src;
    g_fill_scene = &s;
    memset(&d, 0, sizeof d);
    d.fill_pixel = fill_by_tracing;
    d.fill_user = &calls;
    if (!CHECK(src && ref) || !CHECK_EQ_INT(rendercache_warper_create(&d, &w), RENDERCACHE_OK) ||
        !CHECK_EQ_INT(rendercache_range_image_create(&to, NULL, &out), RENDERCACHE_OK))
        return;
    memset(g_computed, 0, sizeof g_computed);
    CHECK_EQ_INT(rendercache_warp(w, in, 1, NULL, RENDERCACHE_FILL_NONE, out), RENDERCACHE_OK);
    rendercache_warp_get_stats(w, &st);
    CHECK_EQ_INT(st.computed, calls);
    CHECK(calls > 100);
    CHECK_EQ_INT(st.empty, 0);
    CHECK_EQ_INT(st.warped + st.computed, 64 * 48);
    for (p = 0; p < 64 * 48; p++) {   /* a computed pixel is the reference's, exactly (same ray) */
        int same = out->object[p] == ref->object[p] && out->rgb[3 * p] == ref->rgb[3 * p] &&
                   out->rgb[3 * p + 1] == ref->rgb[3 * p + 1] && out->rgb[3 * p + 2] == ref->rgb[3 * p + 2] &&
                   (ref->object[p] == RENDERCACHE_MISS || out->depth[p] == ref->depth[p]);
        wrong += g_computed[p] && !same;
        calls -= g_computed[p];
    }
    CHECK_EQ_INT(wrong, 0);
    CHECK_EQ_INT(calls, 0);   /* one call per computed pixel */
    /* background fill at most 2 pixels from its source (pinterp's -fs 2): the pixels farther
       from every filled pixel of their row and column go to the callback */
    {
        rendercache_warp_stats full, near2;
        rendercache_warper *w2 = NULL;
        uint32_t x, y, far = 0, far_computed = 0;
        CHECK_EQ_INT(rendercache_warp(w, in, 1, NULL, RENDERCACHE_FILL_BACKGROUND, out), RENDERCACHE_OK);
        rendercache_warp_get_stats(w, &full);
        d.max_fill_distance = 2;
        CHECK_EQ_INT(rendercache_warper_create(&d, &w2), RENDERCACHE_OK);
        memset(g_computed, 0, sizeof g_computed);
        CHECK_EQ_INT(rendercache_warp(w2, in, 1, NULL, RENDERCACHE_FILL_NONE, out), RENDERCACHE_OK);
        memcpy(g_far, g_computed, sizeof g_far);   /* what no-fill leaves empty */
        memset(g_computed, 0, sizeof g_computed);
        CHECK_EQ_INT(rendercache_warp(w2, in, 1, NULL, RENDERCACHE_FILL_BACKGROUND, out), RENDERCACHE_OK);
        rendercache_warp_get_stats(w2, &near2);
        CHECK(near2.computed > 0 && near2.background < full.background);
        CHECK_EQ_INT(near2.background + near2.computed, full.background + full.computed);
        for (y = 0; y < 48; y++)
            for (x = 0; x < 64; x++) {   /* an empty pixel 3 or more pixels from filled ones in all four directions */
                int dx, reach = 1;
                if (!g_far[y * 64 + x]) continue;
                for (dx = -2; dx <= 2; dx++) {
                    int qx = (int)x + dx, qy = (int)y + dx;
                    if (qx >= 0 && qx < 64 && !g_far[y * 64 + (uint32_t)qx]) reach = 0;
                    if (qy >= 0 && qy < 48 && !g_far[(uint32_t)qy * 64 + x]) reach = 0;
                }
                far += (uint32_t)reach;
                far_computed += (uint32_t)(reach && g_computed[y * 64 + x]);
            }
        CHECK(far > 0);
        CHECK_EQ_INT(far_computed, far);
        rendercache_warper_destroy(w2);
    }
    rendercache_range_image_destroy(src);
    rendercache_range_image_destroy(ref);
    rendercache_range_image_destroy(out);
    rendercache_warper_destroy(w);
}

/* Inputs are taken nearest first; a later one wins only when nearer by
   more than the tolerance. */
static void test_input_order_and_depth_tolerance(void)
{
    scene s;
    rendercache_camera near_cam = make_camera(RENDERCACHE_CAMERA_PERSPECTIVE, 0.2f, 0, 0, 0, 0, 10, 60, 32, 24);
    rendercache_camera far_cam = make_camera(RENDERCACHE_CAMERA_PERSPECTIVE, -0.6f, 0, 0, 0, 0, 10, 60, 32, 24);
    rendercache_camera to = make_camera(RENDERCACHE_CAMERA_PERSPECTIVE, 0, 0, 0, 0, 0, 10, 30, 32, 24);
    rendercache_range_image *a, *b, *out = NULL;
    const rendercache_range_image *in[2];
    rendercache_warper *w = make_warper(NULL, NULL);
    uint32_t p, from_a = 0, from_b = 0;
    memset(&s, 0, sizeof s);
    s.wall_z = 10.0f;
    s.wall_half = 40.0f;
    a = render(&s, &near_cam, 1.0);
    b = render(&s, &far_cam, 2.0);
    if (!CHECK(a && b && w) || !CHECK_EQ_INT(rendercache_range_image_create(&to, NULL, &out), RENDERCACHE_OK)) return;
    for (p = 0; p < 32 * 24; p++) {   /* same wall, told apart by colour */
        a->rgb[3 * p + 1] = 1.0f;
        b->rgb[3 * p + 2] = 1.0f;
    }
    in[0] = b;   /* the farther first in the list: the order is by distance, not by position */
    in[1] = a;
    CHECK_EQ_INT(rendercache_warp(w, in, 2, NULL, RENDERCACHE_FILL_FOREGROUND, out), RENDERCACHE_OK);
    for (p = 0; p < 32 * 24; p++) {
        from_a += out->rgb[3 * p + 1] > 0.999f;   /* interpolated ones: rounding */
        from_b += out->rgb[3 * p + 2] > 0.999f;
    }
    CHECK_EQ_INT(from_a, 32 * 24);   /* the nearer input covers the view; the other is the same surface */
    CHECK_EQ_INT(from_b, 0);
    CHECK_CLOSE(out->time, 1.0, 0.0, 0.0);
    /* the far view's wall 5% nearer (beyond the 2% tolerance) wins everywhere */
    for (p = 0; p < 32 * 24; p++) b->depth[p] *= 0.95f;
    CHECK_EQ_INT(rendercache_warp(w, in, 2, NULL, RENDERCACHE_FILL_FOREGROUND, out), RENDERCACHE_OK);
    for (p = 0, from_b = 0; p < 32 * 24; p++) from_b += out->rgb[3 * p + 2] > 0.999f;
    CHECK_EQ_INT(from_b, 32 * 24);
    /* 1% nearer is within the tolerance: the nearer input still wins */
    for (p = 0; p < 32 * 24; p++) b->depth[p] *= 0.99f / 0.95f;
    CHECK_EQ_INT(rendercache_warp(w, in, 2, NULL, RENDERCACHE_FILL_FOREGROUND, out), RENDERCACHE_OK);
    for (p = 0, from_b = 0; p < 32 * 24; p++) from_b += out->rgb[3 * p + 2] > 0.999f;
    CHECK_EQ_INT(from_b, 0);
    rendercache_range_image_destroy(a);
    rendercache_range_image_destroy(b);
    rendercache_range_image_destroy(out);
    rendercache_warper_destroy(w);
}

/* ---------------------------------------------------------------------
   Time interpolation
   --------------------------------------------------------------------- */
static void test_blend_is_pixelwise(void)
{
    scene s = boxes_scene();
    rendercache_camera cam = make_camera(RENDERCACHE_CAMERA_PERSPECTIVE, 0, 0, 0, 0, 0, 10, 60, 32, 24);
    rendercache_range_image *a, *b, *out = NULL;
    uint32_t p;
    a = render(&s, &cam, 1.0);
    s.boxes[0].shift[0] = 0.7f;
    b = render(&s, &cam, 3.0);
    if (!CHECK(a && b) || !CHECK_EQ_INT(rendercache_range_image_create(&cam, NULL, &out), RENDERCACHE_OK)) return;
    CHECK_EQ_INT(rendercache_blend(a, b, 0.25f, out), RENDERCACHE_OK);
    CHECK_CLOSE(out->time, 1.5, 0.0, 1e-12);
    for (p = 0; p < 32 * 24; p++) {
        int k;
        for (k = 0; k < 3; k++)   /* (1 - t) a + t b in float */
            CHECK_CLOSE(out->rgb[3 * p + k], 0.75f * a->rgb[3 * p + k] + 0.25f * b->rgb[3 * p + k], 0.0, 1e-6);
        CHECK_EQ_INT(out->object[p], a->object[p]);   /* geometry of the image nearer in time */
        CHECK(out->depth[p] == a->depth[p]);
    }
    CHECK_EQ_INT(rendercache_blend(a, b, 0.75f, a), RENDERCACHE_OK);   /* in place */
    for (p = 0; p < 32 * 24; p++) CHECK_EQ_INT(a->object[p], b->object[p]);
    CHECK_EQ_INT(rendercache_blend(a, b, 1.5f, out), RENDERCACHE_ERROR_INVALID_ARGUMENT);
    CHECK_EQ_INT(rendercache_blend(a, b, NAN, out), RENDERCACHE_ERROR_INVALID_ARGUMENT);
    rendercache_range_image_destroy(a);
    rendercache_range_image_destroy(b);
    rendercache_range_image_destroy(out);
}

/* A box moving across the wall between two images: the motion-compensated
   blend shows it once, where it is at the blend time, with its texture; the
   pixelwise blend shows two half-bright ghosts. */
static void translation(float x, float m[12])
{
    memset(m, 0, 12 * sizeof(float));
    m[0] = m[5] = m[10] = 1.0f;
    m[3] = x;
}

/* A box of the channel-1 texture in front of the wall, between depths z0
   and z1, moving in x from -1.2 at time 0 (image a) to 1.2 at time 1 (image
   b); ref is the render at 0.5 and motion the objects' transforms: the wall
   (object 0) static, the box (object 1) translated. */
typedef struct sliding_box {
    scene s;
    rendercache_camera cam;
    rendercache_range_image *a, *b, *ref;
    float world[3][2 * 12];
    rendercache_motion motion;
} sliding_box;

static void sliding_box_free(sliding_box *sb)
{
    rendercache_range_image_destroy(sb->a);
    rendercache_range_image_destroy(sb->b);
    rendercache_range_image_destroy(sb->ref);
}

static int sliding_box_init(sliding_box *sb, float z0, float z1)
{
    scene *s = &sb->s;
    memset(sb, 0, sizeof *sb);
    sb->cam = make_camera(RENDERCACHE_CAMERA_PERSPECTIVE, 0, 0, 0, 0, 0, 10, 50, 64, 48);
    s->wall_z = 10.0f;
    s->wall_half = 40.0f;
    s->box_count = 1;
    s->boxes[0].lo[0] = -1.0f; s->boxes[0].lo[1] = -1.0f; s->boxes[0].lo[2] = z0;
    s->boxes[0].hi[0] = 1.0f; s->boxes[0].hi[1] = 1.0f; s->boxes[0].hi[2] = z1;
    s->boxes[0].channel = 1;
    s->boxes[0].shift[0] = -1.2f;
    sb->a = render(s, &sb->cam, 0.0);
    s->boxes[0].shift[0] = 1.2f;
    sb->b = render(s, &sb->cam, 1.0);
    s->boxes[0].shift[0] = 0.0f;
    sb->ref = render(s, &sb->cam, 0.5);
    translation(0.0f, sb->world[0]); translation(0.0f, sb->world[1]); translation(0.0f, sb->world[2]);
    translation(-1.2f, sb->world[0] + 12); translation(1.2f, sb->world[1] + 12); translation(0.0f, sb->world[2] + 12);
    sb->motion.object_count = 2;
    sb->motion.world_a = sb->world[0];
    sb->motion.world_b = sb->world[1];
    sb->motion.world_t = sb->world[2];
    return sb->a && sb->b && sb->ref;
}

static void test_motion_blend_does_not_ghost(void)
{
    sliding_box sb;
    rendercache_range_image *out = NULL;
    rendercache_warper *w = make_warper(NULL, NULL);
    uint32_t x, y, checked = 0, wrong_motion = 0, wrong_plain = 0;
    if (!CHECK(sliding_box_init(&sb, 6.0f, 6.5f) && w) ||
        !CHECK_EQ_INT(rendercache_range_image_create(&sb.cam, NULL, &out), RENDERCACHE_OK)) {
        sliding_box_free(&sb);
        rendercache_warper_destroy(w);
        return;
    }
    CHECK_EQ_INT(rendercache_blend_motion(w, sb.a, sb.b, 0.5f, &sb.motion, RENDERCACHE_FILL_BOTH, out), RENDERCACHE_OK);
    CHECK_CLOSE(out->time, 0.5, 0.0, 1e-12);
    for (y = 0; y < 48; y++)
        for (x = 0; x < 64; x++) {
            size_t p = (size_t)y * 64 + x;
            uint32_t id;
            int k, off = 0;
            if (!far_from_edges(&sb.s, &sb.cam, x, y, &id)) continue;
            checked++;
            /* both images show each surface point with the same colour, so a blend of the same
               point is exact up to the interpolation inside a quad: 1e-3 */
            for (k = 0; k < 3; k++) off |= fabsf(out->rgb[3 * p + k] - sb.ref->rgb[3 * p + k]) > 1e-3f;
            wrong_motion += out->object[p] != id || off;
        }
    test_note("motion blend: %u of %u interior pixels differ from the render at t = 0.5", wrong_motion, checked);
    CHECK_EQ_INT(wrong_motion, 0);
    CHECK_EQ_INT(rendercache_blend(sb.a, sb.b, 0.5f, out), RENDERCACHE_OK);
    for (y = 0; y < 48; y++)
        for (x = 0; x < 64; x++) {
            size_t p = (size_t)y * 64 + x;
            uint32_t id;
            int k, off = 0;
            if (!far_from_edges(&sb.s, &sb.cam, x, y, &id)) continue;
            for (k = 0; k < 3; k++) off |= fabsf(out->rgb[3 * p + k] - sb.ref->rgb[3 * p + k]) > 1e-3f;
            wrong_plain += off;
        }
    test_note("pixelwise blend: %u of %u interior pixels differ (ghosts)", wrong_plain, checked);
    CHECK(wrong_plain > 200);
    /* a singular transform at an image's time is refused */
    memset(sb.world[0] + 12, 0, 12 * sizeof(float));
    CHECK_EQ_INT(rendercache_blend_motion(w, sb.a, sb.b, 0.5f, &sb.motion, RENDERCACHE_FILL_BOTH, out),
                 RENDERCACHE_ERROR_INVALID_ARGUMENT);
    sliding_box_free(&sb);
    rendercache_range_image_destroy(out);
    rendercache_warper_destroy(w);
}

/* A moving box flat against a static wall (their depths agree within the
   foreground fill's tolerance): the fill's triangles must not join the box's
   pixels to the wall's, or they stretch across the wall as the box moves. */
static void test_motion_blend_keeps_objects_apart(void)
{
    sliding_box sb;
    rendercache_range_image *out = NULL;
    rendercache_warper *w = make_warper(NULL, NULL);
    uint32_t x, y, checked = 0, wrong = 0;
    if (!CHECK(sliding_box_init(&sb, 9.9f, 10.0f) && w) ||
        !CHECK_EQ_INT(rendercache_range_image_create(&sb.cam, NULL, &out), RENDERCACHE_OK)) {
        sliding_box_free(&sb);
        rendercache_warper_destroy(w);
        return;
    }
    CHECK_EQ_INT(rendercache_blend_motion(w, sb.a, sb.b, 0.5f, &sb.motion, RENDERCACHE_FILL_FOREGROUND, out),
                 RENDERCACHE_OK);
    for (y = 0; y < 48; y++)
        for (x = 0; x < 64; x++) {
            size_t p = (size_t)y * 64 + x;
            uint32_t id;
            int k, off = 0;
            if (!far_from_edges(&sb.s, &sb.cam, x, y, &id)) continue;
            checked++;
            /* same tolerance as the ghost test: interpolation inside a quad */
            for (k = 0; k < 3; k++) off |= out->object[p] != RENDERCACHE_NO_SAMPLE &&
                                           fabsf(out->rgb[3 * p + k] - sb.ref->rgb[3 * p + k]) > 1e-3f;
            wrong += off || (out->object[p] != RENDERCACHE_NO_SAMPLE && out->object[p] != id);
        }
    test_note("box against a wall, motion blend with foreground fill: %u of %u interior pixels wrong",
              wrong, checked);
    CHECK(checked > 1000);
    CHECK_EQ_INT(wrong, 0);
    sliding_box_free(&sb);
    rendercache_range_image_destroy(out);
    rendercache_warper_destroy(w);
}

/* ---------------------------------------------------------------------
   Determinism, bad input
   --------------------------------------------------------------------- */
static void reversed_parallel_for(void *user, rendercache_job_fn job, void *ctx, uint32_t count)
{
    (void)user;
    while (count--) job(ctx, count);
}

static uint64_t hash_image(const rendercache_range_image *img)
{
    uint64_t h = 1469598103934665603ull;
    size_t n = (size_t)img->camera.width * img->camera.height, i;
    const unsigned char *bytes[3];
    size_t sizes[3];
    int k;
    bytes[0] = (const unsigned char *)img->rgb; sizes[0] = 12 * n;
    bytes[1] = (const unsigned char *)img->depth; sizes[1] = 4 * n;
    bytes[2] = (const unsigned char *)img->object; sizes[2] = 4 * n;
    for (k = 0; k < 3; k++)
        for (i = 0; i < sizes[k]; i++) h = (h ^ bytes[k][i]) * 1099511628211ull;
    return h;
}

static uint64_t warp_sequence(void (*pf)(void *, rendercache_job_fn, void *, uint32_t), void *user)
{
    scene s = boxes_scene();
    rendercache_camera c1 = make_camera(RENDERCACHE_CAMERA_FISHEYE, -1, 0, 0, -1, 0, 10, 0, 96, 96);
    rendercache_camera c2 = make_camera(RENDERCACHE_CAMERA_SPHERE, 1, 0.2f, 0, 1, 0, 10, 0, 128, 64);
    rendercache_camera to = make_camera(RENDERCACHE_CAMERA_PERSPECTIVE, 0.1f, 0, 0.5f, -0.3f, 0, 10, 60, 61, 37);
    rendercache_range_image *a = render(&s, &c1, 0), *b = render(&s, &c2, 1), *out = NULL;
    const rendercache_range_image *in[2];
    rendercache_warper *w = make_warper(pf, user);
    uint64_t h = 0;
    int f;
    in[0] = a;
    in[1] = b;
    if (a && b && w && rendercache_range_image_create(&to, NULL, &out) == RENDERCACHE_OK)
        for (f = 1; f <= 4; f++) {
            CHECK_EQ_INT(rendercache_warp(w, in, 2, NULL, (rendercache_fill)f, out), RENDERCACHE_OK);
            h = h * 31u + hash_image(out);
        }
    rendercache_range_image_destroy(a);
    rendercache_range_image_destroy(b);
    rendercache_range_image_destroy(out);
    rendercache_warper_destroy(w);
    return h;
}

static void test_warp_deterministic_for_any_thread_count(void)
{
    ex_pool *pool = ex_pool_create(3);
    uint64_t serial = warp_sequence(NULL, NULL);
    CHECK(serial != 0);
    CHECK(warp_sequence(reversed_parallel_for, NULL) == serial);
    if (pool) {
        CHECK(warp_sequence(ex_pool_parallel_for, pool) == serial);
        ex_pool_destroy(pool);
    }
}

static void lone_free(void *ptr, void *user)
{
    (void)user;
    free(ptr);
}

/* pinterp's weight of a view with eye e for the target ray (o, dir) to a
   point at distance dist: 1 / sin of the angle between the two rays. */
static float average_weight(const float e[3], const float o[3], const float dir[3], float dist)
{
    float q[3], l2 = 0.0f, c = 0.0f;
    int k;
    for (k = 0; k < 3; k++) {
        q[k] = o[k] + dir[k] * dist - e[k];
        l2 += q[k] * q[k];
        c += q[k] * dir[k];
    }
    return 1.0f / sqrtf(1.0f - c * c / l2);
}

/* Averaging (pinterp's -a): two views of the scene from eyes at x = -1
   and x = +1, the second with every colour doubled, warped to x = 0.
   Where both see the wall, the weighted mean (1 wa + 2 wb) / (wa + wb) of
   the colour; without averaging the nearer (first) input's colour stays;
   where one alone sees it (the disocclusions of the boxes), its colour. */
static void test_averaging_weighs_inputs_by_ray_angle(void)
{
    scene s = boxes_scene();
    rendercache_camera a = make_camera(RENDERCACHE_CAMERA_PERSPECTIVE, -1.0f, 0, 0, -1.0f, 0, 10, 80, 96, 72);
    rendercache_camera b = make_camera(RENDERCACHE_CAMERA_PERSPECTIVE, 1.0f, 0, 0, 1.0f, 0, 10, 80, 96, 72);
    rendercache_camera t = make_camera(RENDERCACHE_CAMERA_PERSPECTIVE, -0.01f, 0, 0, -0.01f, 0, 10, 50, 64, 48);
    rendercache_range_image *in[2], *out = NULL, *avg = NULL;
    rendercache_warp_desc d;
    rendercache_warper *plain = make_warper(NULL, NULL), *mean = NULL, *mean2 = NULL;
    ex_pool *pool = ex_pool_create(3);
    uint32_t x, y, both = 0, mixed = 0, only = 0, kept = 0, p;
    in[0] = render(&s, &a, 0.0);
    in[1] = render(&s, &b, 0.0);
    memset(&d, 0, sizeof d);
    d.average = 1;
    if (!CHECK(in[0] && in[1] && plain) || !CHECK_EQ_INT(rendercache_warper_create(&d, &mean), RENDERCACHE_OK)) return;
    d.parallel_for = pool ? ex_pool_parallel_for : NULL;
    d.parallel_user = pool;
    CHECK_EQ_INT(rendercache_warper_create(&d, &mean2), RENDERCACHE_OK);
    for (p = 0; p < 96 * 72 * 3; p++) in[1]->rgb[p] *= 2.0f;
    CHECK_EQ_INT(rendercache_range_image_create(&t, NULL, &out), RENDERCACHE_OK);
    CHECK_EQ_INT(rendercache_range_image_create(&t, NULL, &avg), RENDERCACHE_OK);
    CHECK_EQ_INT(rendercache_warp(plain, (const rendercache_range_image *const *)in, 2, &t, RENDERCACHE_FILL_FOREGROUND, out),
                 RENDERCACHE_OK);
    CHECK_EQ_INT(rendercache_warp(mean, (const rendercache_range_image *const *)in, 2, &t, RENDERCACHE_FILL_FOREGROUND, avg),
                 RENDERCACHE_OK);
    for (y = 0; y < 48; y++)
        for (x = 0; x < 64; x++) {
            float o[3], dir[3], rgb[3], dist, point[3];
            uint32_t id, k;
            p = y * 64 + x;
            if (!far_from_edges(&s, &t, x, y, &id) || id != 0) continue;
            rendercache_camera_ray(&t, (float)x + 0.5f, (float)y + 0.5f, o, dir);
            trace(&s, o, dir, &dist, rgb);
            for (k = 0; k < 3; k++) point[k] = o[k] + dist * dir[k];
            if (visible_from(&s, &a, point, 0) && visible_from(&s, &b, point, 0)) {
                float wa = average_weight(a.eye, o, dir, dist), wb = average_weight(b.eye, o, dir, dist);
                both++;
                /* the quads interpolate the colour linearly, exact on the plane but for rounding: 1e-4 */
                mixed += fabsf(avg->rgb[3 * p] / rgb[0] - (wa + 2.0f * wb) / (wa + wb)) < 1e-4f;
                kept += fabsf(out->rgb[3 * p] / rgb[0] - 1.0f) < 0.01f || fabsf(out->rgb[3 * p] / rgb[0] - 2.0f) < 0.02f;
            } else if (visible_from(&s, &a, point, 0) != visible_from(&s, &b, point, 0)) {
                float expect = visible_from(&s, &a, point, 0) ? 1.0f : 2.0f;
                only += fabsf(avg->rgb[3 * p] / rgb[0] - expect) < 1e-4f * expect;
            }
        }
    test_note("averaging: %u wall pixels seen by both views, %u of them the weighted mean (plain warp: %u kept one view); "
              "%u seen by one view keep its colour", both, mixed, kept, only);
    CHECK(both > 500);
    /* a few wall pixels next to a disocclusion of one view get that view's edge points instead of quads */
    CHECK(mixed >= both - both / 30);
    CHECK(kept >= both - both / 100);
    CHECK(only > 0);
    /* any number of threads: the same image, bit for bit */
    CHECK_EQ_INT(rendercache_warp(mean2, (const rendercache_range_image *const *)in, 2, &t, RENDERCACHE_FILL_BOTH, out),
                 RENDERCACHE_OK);
    CHECK_EQ_INT(rendercache_warp(mean, (const rendercache_range_image *const *)in, 2, &t, RENDERCACHE_FILL_BOTH, avg),
                 RENDERCACHE_OK);
    CHECK(memcmp(out->rgb, avg->rgb, sizeof(float) * 3 * 64 * 48) == 0);
    CHECK(memcmp(out->depth, avg->depth, sizeof(float) * 64 * 48) == 0);
    rendercache_range_image_destroy(in[0]);
    rendercache_range_image_destroy(in[1]);
    rendercache_range_image_destroy(out);
    rendercache_range_image_destroy(avg);
    rendercache_warper_destroy(plain);
    rendercache_warper_destroy(mean);
    rendercache_warper_destroy(mean2);
    ex_pool_destroy(pool);
}

/* ---------------------------------------------------------------------
   A render cache seeded from base views (rendercache_seed): the first
   frame of an interactive session shows the precomputed views at once,
   and sampling then replaces them.
   --------------------------------------------------------------------- */
/* Pixels of an image of cam whose colour lies outside the range of the
   exact colours at the centres of the 3x3 pixels around it (+- 0.01). */
static uint32_t wrong_against_scene(const scene *s, const rendercache_camera *cam, const float *img)
{
    uint32_t x, y, wrong = 0;
    for (y = 0; y < cam->height; y++)
        for (x = 0; x < cam->width; x++) {
            float lo[3] = { FLT_MAX, FLT_MAX, FLT_MAX }, hi[3] = { -FLT_MAX, -FLT_MAX, -FLT_MAX };
            const float *c = img + 3 * ((size_t)y * cam->width + x);
            int dx, dy, k, bad = 0;
            for (dy = -1; dy <= 1; dy++)
                for (dx = -1; dx <= 1; dx++) {
                    float o[3], d[3], rgb[3], dist;
                    rendercache_camera_ray(cam, (float)x + 0.5f + (float)dx, (float)y + 0.5f + (float)dy, o, d);
                    trace(s, o, d, &dist, rgb);
                    for (k = 0; k < 3; k++) {
                        lo[k] = rgb[k] < lo[k] ? rgb[k] : lo[k];
                        hi[k] = rgb[k] > hi[k] ? rgb[k] : hi[k];
                    }
                }
            for (k = 0; k < 3; k++) bad |= c[k] < lo[k] - 0.01f || c[k] > hi[k] + 0.01f;
            wrong += (uint32_t)bad;
        }
    return wrong;
}

static void test_seed_render_cache_from_base_views(void)
{
    const uint32_t w = 64, h = 48, n = w * h;
    scene s = boxes_scene();
    rendercache_camera cam = make_camera(RENDERCACHE_CAMERA_PERSPECTIVE, 0.3f, 0.1f, 0.5f, 0.5f, 0.0f, 10.0f, 60.0f, w, h);
    rendercache_camera fish[2];
    rendercache_range_image *base[2] = { NULL, NULL }, *bad = NULL;
    rendercache_desc d;
    rendercache *rc = NULL;
    rendercache_stats st;
    static rendercache_pixel_request req[64 * 48];
    static rendercache_sample smp[64 * 48];
    uint32_t taken = 0, wrong_seeded, empty = 0, p, got, i, f, wrong_after;
    fish[0] = make_camera(RENDERCACHE_CAMERA_FISHEYE, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 10.0f, 0, 160, 160);
    fish[1] = make_camera(RENDERCACHE_CAMERA_FISHEYE, 0.8f, 0.2f, 0.8f, 0.8f, 0.2f, 10.8f, 0, 160, 160);
    base[0] = render(&s, &fish[0], 0.0);
    base[1] = render(&s, &fish[1], 0.0);
    memset(&d, 0, sizeof d);
    d.width = w;
    d.height = h;
    d.object_count = 4;
    if (!CHECK(base[0] && base[1]) || !CHECK_EQ_INT(rendercache_create(&d, &rc), RENDERCACHE_OK)) return;
    CHECK_EQ_INT(rendercache_seed(rc, (const rendercache_range_image *const *)base, 2, &taken),
                 RENDERCACHE_ERROR_INVALID_ARGUMENT);   /* no frame yet */
    CHECK_EQ_INT(rendercache_begin_frame(rc, &cam), RENDERCACHE_OK);
    for (p = 0; p < n; p++) empty += rendercache_pixel_kinds(rc)[p] == RENDERCACHE_PIXEL_EMPTY;
    CHECK_EQ_INT(empty, n);   /* an empty cache */
    CHECK_EQ_INT(rendercache_seed(rc, (const rendercache_range_image *const *)base, 2, &taken), RENDERCACHE_OK);
    CHECK(taken > n / 2);   /* (seeds of one surface that land in one pixel replace each other) */
    empty = 0;
    for (p = 0; p < n; p++) empty += rendercache_pixel_kinds(rc)[p] == RENDERCACHE_PIXEL_EMPTY;
    wrong_seeded = wrong_against_scene(&s, &cam, rendercache_image(rc));
    /* the seeded frame is nearly right (disocclusions of both base views, and edges of their
       coarser pixels, stay wrong) and nothing is empty */
    CHECK_EQ_INT(empty, 0);
    CHECK_MSG(wrong_seeded < n / 25, "%u of %u pixels wrong after seeding", wrong_seeded, n);
    /* the seeds are old: the first requests of the next frames go to them, and they make way */
    for (f = 0; f < 14; f++) {
        CHECK_EQ_INT(rendercache_begin_frame(rc, &cam), RENDERCACHE_OK);
        CHECK_EQ_INT(rendercache_request(rc, req, n / 12, &got), RENDERCACHE_OK);
        for (i = 0; i < got; i++) {
            float dist;
            memset(&smp[i], 0, sizeof smp[i]);
            smp[i].x = req[i].x; smp[i].y = req[i].y; smp[i].frame = req[i].frame;
            smp[i].object = trace(&s, req[i].org, req[i].dir, &dist, smp[i].rgb);
            for (p = 0; p < 3; p++) smp[i].position[p] = req[i].org[p] + dist * req[i].dir[p];
        }
        CHECK_EQ_INT(rendercache_insert(rc, smp, got, NULL), RENDERCACHE_OK);
    }
    CHECK_EQ_INT(rendercache_begin_frame(rc, &cam), RENDERCACHE_OK);
    wrong_after = wrong_against_scene(&s, &cam, rendercache_image(rc));
    rendercache_get_stats(rc, &st);
    test_note("seeding a %ux%u cache from 2 fish-eyes: %u points, %u pixels wrong, %u after 14 frames at 8%%",
              w, h, taken, wrong_seeded, wrong_after);
    CHECK(wrong_after < wrong_seeded || wrong_after == 0);
    CHECK(st.live_points <= st.capacity);
    /* bad input */
    CHECK_EQ_INT(rendercache_seed(NULL, (const rendercache_range_image *const *)base, 2, &taken), RENDERCACHE_ERROR_INVALID_ARGUMENT);
    CHECK_EQ_INT(rendercache_seed(rc, NULL, 2, &taken), RENDERCACHE_ERROR_INVALID_ARGUMENT);
    CHECK_EQ_INT(rendercache_seed(rc, NULL, 0, &taken), RENDERCACHE_OK);
    CHECK_EQ_INT(taken, 0);
    CHECK_EQ_INT(rendercache_range_image_create(&fish[0], NULL, &bad), RENDERCACHE_OK);
    bad->camera.vfov_degrees = 0.0f;
    bad->camera.kind = (rendercache_camera_kind)9;
    CHECK_EQ_INT(rendercache_seed(rc, (const rendercache_range_image *const *)&bad, 1, &taken), RENDERCACHE_ERROR_INVALID_ARGUMENT);
    rendercache_range_image_destroy(bad);
    rendercache_range_image_destroy(base[0]);
    rendercache_range_image_destroy(base[1]);
    rendercache_destroy(rc);
}

/* Whether a range image is one the library accepts: what save validates
   (finite colours, depths finite and positive where there is a surface). */
static int image_valid(const rendercache_range_image *img)
{
    void *data = NULL;
    size_t size = 0;
    int ok = rendercache_range_image_save_to_memory(img, NULL, &data, &size) == RENDERCACHE_OK;
    rendercache_free_memory(NULL, data);
    return ok;
}

/* Depths at the ends of the float range (a denormal 2e-41 next to 2.7e23 in
   one 2x2 block) and colours near FLT_MAX: the projected positions leave
   every integer range and the squared distances overflow, and the warp must
   still give a valid image (no float-to-int overflow: compile with clang
   -fsanitize=float-cast-overflow to see the conversions themselves). */
static void test_extreme_depths_and_colours(void)
{
    static const rendercache_fill fills[4] = { RENDERCACHE_FILL_NONE, RENDERCACHE_FILL_FOREGROUND,
                                               RENDERCACHE_FILL_BACKGROUND, RENDERCACHE_FILL_BOTH };
    rendercache_camera src = make_camera(RENDERCACHE_CAMERA_PERSPECTIVE, 0, 0, 0, 0, 0, 10, 60.0f, 4, 4);
    /* the source's eye lies 1e-20 in front of the target's eye plane: its nearest pixels project to x ~ -1e21 */
    rendercache_camera dst = make_camera(RENDERCACHE_CAMERA_PERSPECTIVE, -1.0f, 0.0f, -1e-20f, -1.0f, 0.0f, 10.0f, 60.0f, 16, 12);
    rendercache_range_image *in = NULL, *out = NULL, *other = NULL, *blend = NULL;
    rendercache_warper *w = make_warper(NULL, NULL);
    const rendercache_range_image *list[2];
    uint64_t seed = 12345;
    uint32_t p, f, trial, invalid = 0;
    if (!w || !CHECK_EQ_INT(rendercache_range_image_create(&src, NULL, &in), RENDERCACHE_OK) ||
        !CHECK_EQ_INT(rendercache_range_image_create(&dst, NULL, &out), RENDERCACHE_OK))
        return;
    for (p = 0; p < 16; p++) {
        in->object[p] = 0;
        in->depth[p] = 5.0f;
        in->rgb[3 * p] = in->rgb[3 * p + 1] = in->rgb[3 * p + 2] = 0.5f;
    }
    in->depth[5] = in->depth[6] = in->depth[9] = 2e-41f;   /* the 2x2 block of pixels (1..2, 1..2) */
    in->depth[10] = 2.7e23f;
    for (f = 0; f < 4; f++) {
        CHECK_EQ_INT(rendercache_warp(w, (const rendercache_range_image *const *)&in, 1, &dst, fills[f], out), RENDERCACHE_OK);
        CHECK_MSG(image_valid(out), "fill %u: an invalid output image", f);
    }
    /* random images: depths log-uniform over the floats (denormals included), colours up to 3e38 */
    src = make_camera(RENDERCACHE_CAMERA_FISHEYE, 0, 0, 0, 0, 0, 10, 60.0f, 24, 24);
    rendercache_range_image_destroy(in);
    in = NULL;
    CHECK_EQ_INT(rendercache_range_image_create(&src, NULL, &in), RENDERCACHE_OK);
    CHECK_EQ_INT(rendercache_range_image_create(&src, NULL, &other), RENDERCACHE_OK);
    CHECK_EQ_INT(rendercache_range_image_create(&src, NULL, &blend), RENDERCACHE_OK);
    for (trial = 0; trial < 24; trial++) {
        rendercache_range_image *imgs[2];
        imgs[0] = in;
        imgs[1] = other;
        for (f = 0; f < 2; f++)
            for (p = 0; p < 24 * 24; p++) {
                rendercache_range_image *img = imgs[f];
                float u;
                int k;
                seed = seed * 6364136223846793005ull + 1442695040888963407ull;
                u = (float)(seed >> 40) / 16777216.0f;
                if (img->object[p] == RENDERCACHE_NO_SAMPLE && f == 0 && trial == 0) continue;   /* outside the circle */
                img->object[p] = (seed >> 20) % 5 == 0 ? RENDERCACHE_MISS : (uint32_t)((seed >> 24) % 2);
                img->depth[p] = img->object[p] == RENDERCACHE_MISS ? RENDERCACHE_FAR_DEPTH : powf(10.0f, -41.0f + 79.5f * u);
                if (!(img->depth[p] > 0.0f && img->depth[p] <= FLT_MAX)) img->depth[p] = 1.0f;
                for (k = 0; k < 3; k++) img->rgb[3 * p + k] = (seed >> (30 + k)) & 1 ? 3e38f : -3e38f * u;
            }
        other->camera.eye[0] = 0.3f * (float)(trial % 5);
        other->camera.look_at[0] = other->camera.eye[0];
        dst = make_camera(RENDERCACHE_CAMERA_PERSPECTIVE, -1.0f + 0.1f * (float)trial, 0.2f, trial % 3 ? -1e-20f : 0.5f,
                          0.3f * (float)trial, 0.0f, 10.0f, 60.0f, 16, 12);
        list[0] = in;
        list[1] = other;
        CHECK_EQ_INT(rendercache_warp(w, list, 2, &dst, fills[trial % 4], out), RENDERCACHE_OK);
        invalid += !image_valid(out);
        {
            float world[36];
            rendercache_motion m;
            int k;
            memset(world, 0, sizeof world);
            for (k = 0; k < 3; k++) world[12 * k] = world[12 * k + 5] = world[12 * k + 10] = 1.0f;
            world[12 + 3] = 2.0f;   /* object 0 moves */
            m.object_count = 1;
            m.world_a = world;
            m.world_b = world + 12;
            m.world_t = world + 24;
            CHECK_EQ_INT(rendercache_blend_motion(w, in, in, 0.5f, &m, fills[trial % 4], blend), RENDERCACHE_OK);
            invalid += !image_valid(blend);
            CHECK_EQ_INT(rendercache_blend(in, in, 0.3f, blend), RENDERCACHE_OK);
            invalid += !image_valid(blend);
        }
    }
    CHECK_EQ_INT(invalid, 0);
    rendercache_range_image_destroy(in);
    rendercache_range_image_destroy(other);
    rendercache_range_image_destroy(blend);
    rendercache_range_image_destroy(out);
    rendercache_warper_destroy(w);
}

/* ---------------------------------------------------------------------
   Prepared inputs (rendercache_range_image_prepare)
   --------------------------------------------------------------------- */

/* The warps of n inputs into four perspective targets with every fill, as
   one hash of the images and the warp statistics. */
static uint64_t warp_configurations(rendercache_range_image *const *in, uint32_t n, int average,
                                    void (*pf)(void *, rendercache_job_fn, void *, uint32_t), void *user)
{
    rendercache_camera to[4];
    rendercache_warp_desc d;
    rendercache_warper *w = NULL;
    rendercache_range_image *out = NULL;
    uint64_t h = 0;
    int f, t;
    to[0] = make_camera(RENDERCACHE_CAMERA_PERSPECTIVE, 0.1f, 0, 0.5f, -0.3f, 0, 10, 60, 64, 48);
    to[1] = make_camera(RENDERCACHE_CAMERA_PERSPECTIVE, -0.2f, 0.1f, 0.2f, -5.0f, 0, 6, 50, 64, 48);   /* half the inputs' tiles outside */
    to[2] = make_camera(RENDERCACHE_CAMERA_PERSPECTIVE, 0.1f, 0, 0.3f, 3.5f, 1.0f, 10, 40, 64, 48);   /* narrow: tiles */
    to[3] = make_camera(RENDERCACHE_CAMERA_PERSPECTIVE, 0.1f, -0.05f, -0.6f, 1.5f, 0.4f, 10, 40, 64, 48);   /* cut at the border */
    memset(&d, 0, sizeof d);
    d.parallel_for = pf;
    d.parallel_user = user;
    d.average = average;
    if (!CHECK_EQ_INT(rendercache_warper_create(&d, &w), RENDERCACHE_OK) ||
        !CHECK_EQ_INT(rendercache_range_image_create(&to[0], NULL, &out), RENDERCACHE_OK))
        return 0;
    for (t = 0; t < 4; t++)
        for (f = 1; f <= 4; f++) {
            rendercache_warp_stats st;
            CHECK_EQ_INT(rendercache_warp(w, (const rendercache_range_image *const *)in, n, &to[t], (rendercache_fill)f, out),
                         RENDERCACHE_OK);
            rendercache_warp_get_stats(w, &st);
            h = h * 31u + hash_image(out);
            h = h * 31u + st.projected + 7u * st.warped + 13u * st.background + 17u * st.empty;
        }
    rendercache_range_image_destroy(out);
    rendercache_warper_destroy(w);
    return h;
}

/* Prepared inputs warp bit for bit as unprepared ones (the prepared tile
   bounds are the same numbers, and the lazily computed quad flags the same
   flags): two fish-eyes and a perspective view, 1 to 3 inputs, every fill,
   with and without averaging, serial and on 3 threads. */
static void test_prepared_inputs_warp_bit_identically(void)
{
    scene s = boxes_scene();
    rendercache_camera c[3];
    rendercache_range_image *in[3];
    ex_pool *pool = ex_pool_create(3);
    uint32_t n, i, differ = 0;
    int average, threads;
    c[0] = make_camera(RENDERCACHE_CAMERA_FISHEYE, -1, 0, 0, -1, 0, 10, 0, 128, 128);
    c[1] = make_camera(RENDERCACHE_CAMERA_FISHEYE, 1, 0.3f, 0.5f, 1, 0.3f, 10, 0, 112, 112);
    c[2] = make_camera(RENDERCACHE_CAMERA_PERSPECTIVE, 0, 0.5f, -0.5f, 0, 0, 10, 70, 96, 72);
    for (i = 0; i < 3; i++) in[i] = render(&s, &c[i], 0);
    if (!CHECK(in[0] && in[1] && in[2])) return;
    for (threads = 0; threads < (pool ? 2 : 1); threads++)
        for (average = 0; average < 2; average++)
            for (n = 1; n <= 3; n++) {
                uint64_t plain = warp_configurations(in, n, average, threads ? ex_pool_parallel_for : NULL, pool), prepared;
                for (i = 0; i < n; i++) CHECK_EQ_INT(rendercache_range_image_prepare(in[i]), RENDERCACHE_OK);
                prepared = warp_configurations(in, n, average, threads ? ex_pool_parallel_for : NULL, pool);
                for (i = 0; i < n; i++) rendercache_range_image_unprepare(in[i]);
                CHECK(plain != 0);
                differ += plain != prepared;
            }
    CHECK_EQ_INT(differ, 0);
    for (i = 0; i < 3; i++) rendercache_range_image_destroy(in[i]);
    ex_pool_destroy(pool);
}

/* The contract of prepare: depths changed in place afterwards give the
   image the stale bounds let through (here another image than an
   unprepared warp of the same arrays: so the warp does read the prepared
   bounds), a valid image and no read outside the arrays (ASan). */
static void test_prepared_input_changed_in_place(void)
{
    scene s = boxes_scene();
    rendercache_camera c = make_camera(RENDERCACHE_CAMERA_FISHEYE, -1, 0, 0, -1, 0, 10, 0, 128, 128);
    rendercache_camera to = make_camera(RENDERCACHE_CAMERA_PERSPECTIVE, -0.2f, 0.1f, 0.2f, -5.0f, 0, 6, 50, 64, 48);
    rendercache_range_image *a = render(&s, &c, 0), *out = NULL, copy;
    const rendercache_range_image *in[1];
    rendercache_warper *w = make_warper(NULL, NULL);
    uint64_t stale, fresh;
    size_t p;
    if (!CHECK(a && w) || !CHECK_EQ_INT(rendercache_range_image_create(&to, NULL, &out), RENDERCACHE_OK)) return;
    CHECK_EQ_INT(rendercache_range_image_prepare(a), RENDERCACHE_OK);
    for (p = 0; p < (size_t)128 * 128; p++)   /* everything 20 times nearer: tiles culled by the far wall now land */
        if (a->object[p] < RENDERCACHE_NO_SAMPLE) a->depth[p] *= 0.05f;
    in[0] = a;
    CHECK_EQ_INT(rendercache_warp(w, in, 1, &to, RENDERCACHE_FILL_BOTH, out), RENDERCACHE_OK);
    CHECK(image_valid(out));
    stale = hash_image(out);
    copy = *a;   /* the same arrays, unprepared */
    copy.prepared = NULL;
    in[0] = &copy;
    CHECK_EQ_INT(rendercache_warp(w, in, 1, &to, RENDERCACHE_FILL_BOTH, out), RENDERCACHE_OK);
    fresh = hash_image(out);
    CHECK(stale != fresh);
    CHECK_EQ_INT(rendercache_range_image_prepare(a), RENDERCACHE_OK);   /* prepared again: the fresh image */
    in[0] = a;
    CHECK_EQ_INT(rendercache_warp(w, in, 1, &to, RENDERCACHE_FILL_BOTH, out), RENDERCACHE_OK);
    CHECK(hash_image(out) == fresh);
    rendercache_range_image_destroy(a);
    rendercache_range_image_destroy(out);
    rendercache_warper_destroy(w);
}

/* An allocator that fails once `left` allocations have succeeded. */
typedef struct failing_allocator { int left; } failing_allocator;
static void *failing_alloc(size_t size, void *user)
{
    failing_allocator *f = (failing_allocator *)user;
    if (f->left <= 0) return NULL;
    f->left--;
    return malloc(size);
}

static void test_prepare_rejects_bad_input(void)
{
    scene s = boxes_scene();
    rendercache_camera cam = make_camera(RENDERCACHE_CAMERA_FISHEYE, 0, 0, 0, 0, 0, 10, 0, 48, 48);
    rendercache_camera to = make_camera(RENDERCACHE_CAMERA_PERSPECTIVE, 0.3f, 0, 0, 0.3f, 0, 10, 60, 16, 12);
    rendercache_range_image *a = render(&s, &cam, 0), *out = NULL, *img = NULL, copy;
    const rendercache_range_image *in[1];
    rendercache_warper *w = make_warper(NULL, NULL);
    rendercache_allocator fa;
    failing_allocator budget;
    float *depth2;
    if (!CHECK(a && w) || !CHECK_EQ_INT(rendercache_range_image_create(&to, NULL, &out), RENDERCACHE_OK)) return;
    in[0] = a;
    /* NULL, an invalid camera, a missing array, a lone alloc callback: INVALID_ARGUMENT, left unprepared */
    CHECK_EQ_INT(rendercache_range_image_prepare(NULL), RENDERCACHE_ERROR_INVALID_ARGUMENT);
    copy = *a;
    copy.camera.vfov_degrees = NAN;
    copy.camera.kind = (rendercache_camera_kind)7;
    CHECK_EQ_INT(rendercache_range_image_prepare(&copy), RENDERCACHE_ERROR_INVALID_ARGUMENT);
    CHECK(copy.prepared == NULL);
    copy = *a;
    copy.object = NULL;
    CHECK_EQ_INT(rendercache_range_image_prepare(&copy), RENDERCACHE_ERROR_INVALID_ARGUMENT);
    copy = *a;
    copy.allocator.free = lone_free;
    CHECK_EQ_INT(rendercache_range_image_prepare(&copy), RENDERCACHE_ERROR_INVALID_ARGUMENT);
    CHECK(copy.prepared == NULL);
    /* the size changed since prepare: warp and blend_motion refuse it (its bounds are for other tiles) */
    CHECK_EQ_INT(rendercache_range_image_prepare(a), RENDERCACHE_OK);
    CHECK(a->prepared != NULL);
    CHECK_EQ_INT(rendercache_range_image_prepare(a), RENDERCACHE_OK);   /* again: recomputed, the first freed (ASan) */
    a->camera.width = 32;
    CHECK_EQ_INT(rendercache_warp(w, in, 1, &to, RENDERCACHE_FILL_BOTH, out), RENDERCACHE_ERROR_INVALID_ARGUMENT);
    CHECK_EQ_INT(rendercache_blend_motion(w, a, a, 0.5f, NULL, RENDERCACHE_FILL_BOTH, out), RENDERCACHE_ERROR_INVALID_ARGUMENT);
    a->camera.width = 48;
    CHECK_EQ_INT(rendercache_warp(w, in, 1, &to, RENDERCACHE_FILL_BOTH, out), RENDERCACHE_OK);
    /* other arrays under the prepared data (a struct copy given new depths) */
    copy = *a;
    depth2 = (float *)malloc(48 * 48 * sizeof(float));
    if (CHECK(depth2 != NULL)) {
        memcpy(depth2, a->depth, 48 * 48 * sizeof(float));
        copy.depth = depth2;
        in[0] = &copy;
        CHECK_EQ_INT(rendercache_warp(w, in, 1, &to, RENDERCACHE_FILL_BOTH, out), RENDERCACHE_ERROR_INVALID_ARGUMENT);
        copy.prepared = NULL;
        CHECK_EQ_INT(rendercache_warp(w, in, 1, &to, RENDERCACHE_FILL_BOTH, out), RENDERCACHE_OK);
        free(depth2);
    }
    /* an image the library writes loses its prepared data */
    CHECK_EQ_INT(rendercache_range_image_prepare(out), RENDERCACHE_OK);
    in[0] = a;
    CHECK_EQ_INT(rendercache_warp(w, in, 1, &to, RENDERCACHE_FILL_BOTH, out), RENDERCACHE_OK);
    CHECK(out->prepared == NULL);
    CHECK_EQ_INT(rendercache_range_image_prepare(out), RENDERCACHE_OK);
    CHECK_EQ_INT(rendercache_blend(out, out, 0.5f, out), RENDERCACHE_OK);
    CHECK(out->prepared == NULL);
    /* allocation failure: OUT_OF_MEMORY, the image left unprepared and still warped */
    memset(&fa, 0, sizeof fa);
    fa.alloc = failing_alloc;
    fa.free = lone_free;
    fa.user = &budget;
    budget.left = 4;   /* the image and its three arrays */
    if (CHECK_EQ_INT(rendercache_range_image_create(&cam, &fa, &img), RENDERCACHE_OK)) {
        memcpy(img->rgb, a->rgb, 3 * 48 * 48 * sizeof(float));
        memcpy(img->depth, a->depth, 48 * 48 * sizeof(float));
        memcpy(img->object, a->object, 48 * 48 * sizeof(uint32_t));
        CHECK_EQ_INT(rendercache_range_image_prepare(img), RENDERCACHE_ERROR_OUT_OF_MEMORY);
        CHECK(img->prepared == NULL);
        in[0] = img;
        CHECK_EQ_INT(rendercache_warp(w, in, 1, &to, RENDERCACHE_FILL_BOTH, out), RENDERCACHE_OK);
        budget.left = 1;
        CHECK_EQ_INT(rendercache_range_image_prepare(img), RENDERCACHE_OK);
        CHECK(img->prepared != NULL);
        rendercache_range_image_destroy(img);   /* frees the prepared data too (ASan: no leak) */
    }
    rendercache_range_image_unprepare(NULL);
    rendercache_range_image_unprepare(out);   /* not prepared: nothing */
    rendercache_range_image_destroy(a);
    rendercache_range_image_destroy(out);
    rendercache_warper_destroy(w);
}

static void test_warp_rejects_bad_input(void)
{
    scene s = boxes_scene();
    rendercache_camera cam = make_camera(RENDERCACHE_CAMERA_PERSPECTIVE, 0, 0, 0, 0, 0, 10, 60, 16, 12), bad;
    rendercache_range_image *a = render(&s, &cam, 0), *out = NULL, *tmp = NULL, copy;
    const rendercache_range_image *in[2];
    rendercache_warp_desc d;
    rendercache_warper *w = make_warper(NULL, NULL), *w2 = (rendercache_warper *)&d;
    in[0] = a;
    in[1] = NULL;
    if (!CHECK(a && w) || !CHECK_EQ_INT(rendercache_range_image_create(&cam, NULL, &out), RENDERCACHE_OK)) return;
    CHECK_EQ_INT(rendercache_warp(NULL, in, 1, NULL, RENDERCACHE_FILL_BOTH, out), RENDERCACHE_ERROR_INVALID_ARGUMENT);
    CHECK_EQ_INT(rendercache_warp(w, NULL, 1, NULL, RENDERCACHE_FILL_BOTH, out), RENDERCACHE_ERROR_INVALID_ARGUMENT);
    CHECK_EQ_INT(rendercache_warp(w, in, 0, NULL, RENDERCACHE_FILL_BOTH, out), RENDERCACHE_ERROR_INVALID_ARGUMENT);
    CHECK_EQ_INT(rendercache_warp(w, in, 2, NULL, RENDERCACHE_FILL_BOTH, out), RENDERCACHE_ERROR_INVALID_ARGUMENT);
    CHECK_EQ_INT(rendercache_warp(w, in, 1, NULL, RENDERCACHE_FILL_BOTH, NULL), RENDERCACHE_ERROR_INVALID_ARGUMENT);
    CHECK_EQ_INT(rendercache_warp(w, in, 1, NULL, (rendercache_fill)9, out), RENDERCACHE_ERROR_INVALID_ARGUMENT);
    in[1] = out;   /* the output among the inputs */
    CHECK_EQ_INT(rendercache_warp(w, in, 2, NULL, RENDERCACHE_FILL_BOTH, out), RENDERCACHE_ERROR_INVALID_ARGUMENT);
    bad = cam; bad.eye[2] = NAN;
    CHECK_EQ_INT(rendercache_warp(w, in, 1, &bad, RENDERCACHE_FILL_BOTH, out), RENDERCACHE_ERROR_INVALID_ARGUMENT);
    bad = cam; bad.width = 17;   /* not the output's size */
    CHECK_EQ_INT(rendercache_warp(w, in, 1, &bad, RENDERCACHE_FILL_BOTH, out), RENDERCACHE_ERROR_INVALID_ARGUMENT);
    bad = cam; bad.kind = RENDERCACHE_CAMERA_SPHERE; bad.width = 1;
    CHECK_EQ_INT(rendercache_range_image_create(&bad, NULL, &tmp), RENDERCACHE_ERROR_INVALID_ARGUMENT);
    bad = cam; bad.up[1] = NAN;
    CHECK_EQ_INT(rendercache_range_image_create(&bad, NULL, &tmp), RENDERCACHE_ERROR_INVALID_ARGUMENT);
    CHECK(tmp == NULL);
    copy = *a;   /* an input with an invalid camera or a missing array */
    copy.camera.vfov_degrees = NAN;
    in[1] = &copy;
    CHECK_EQ_INT(rendercache_warp(w, in, 2, NULL, RENDERCACHE_FILL_BOTH, out), RENDERCACHE_ERROR_INVALID_ARGUMENT);
    copy = *a;
    copy.depth = NULL;
    CHECK_EQ_INT(rendercache_warp(w, in, 2, NULL, RENDERCACHE_FILL_BOTH, out), RENDERCACHE_ERROR_INVALID_ARGUMENT);
    /* NaN, negative and infinite depths are skipped, not fatal */
    a->depth[0] = NAN; a->depth[1] = -1.0f; a->depth[2] = INFINITY;
    CHECK_EQ_INT(rendercache_warp(w, in, 1, NULL, RENDERCACHE_FILL_NONE, out), RENDERCACHE_OK);
    /* mismatched blend sizes */
    bad = cam; bad.width = 8;
    CHECK_EQ_INT(rendercache_range_image_create(&bad, NULL, &tmp), RENDERCACHE_OK);
    CHECK_EQ_INT(rendercache_blend(a, tmp, 0.5f, out), RENDERCACHE_ERROR_INVALID_ARGUMENT);
    CHECK_EQ_INT(rendercache_blend_motion(w, a, a, 0.5f, NULL, RENDERCACHE_FILL_BOTH, tmp), RENDERCACHE_OK);
    CHECK_EQ_INT(rendercache_blend_motion(w, a, out, 0.5f, NULL, RENDERCACHE_FILL_BOTH, out), RENDERCACHE_ERROR_INVALID_ARGUMENT);
    /* warper desc */
    memset(&d, 0, sizeof d);
    d.depth_tolerance = -1.0f;
    CHECK_EQ_INT(rendercache_warper_create(&d, &w2), RENDERCACHE_ERROR_INVALID_ARGUMENT);
    CHECK(w2 == NULL);
    d.depth_tolerance = 0.0f;
    d.background[1] = NAN;
    CHECK_EQ_INT(rendercache_warper_create(&d, &w2), RENDERCACHE_ERROR_INVALID_ARGUMENT);
    d.background[1] = 0.0f;
    d.allocator.free = lone_free;
    CHECK_EQ_INT(rendercache_warper_create(&d, &w2), RENDERCACHE_ERROR_INVALID_ARGUMENT);
    rendercache_range_image_destroy(tmp);
    rendercache_range_image_destroy(a);
    rendercache_range_image_destroy(out);
    rendercache_warper_destroy(w);
    rendercache_warper_destroy(NULL);
    rendercache_range_image_destroy(NULL);
}

int main(int argc, char **argv)
{
    TEST_INIT(argc, argv);
    RUN(test_fisheye_camera);
    RUN(test_sphere_camera);
    RUN(test_warp_into_own_camera_is_identity);
    RUN(test_warp_along_plane_normal_matches_analytic_image);
    RUN(test_flanking_views_fill_every_visible_pixel);
    RUN(test_culled_tiles_lose_no_landing_pixel);
    RUN(test_culled_tiles_keep_quads_at_the_border);
    RUN(test_fill_modes_at_a_disocclusion);
    RUN(test_fill_callback_computes_the_rest);
    RUN(test_input_order_and_depth_tolerance);
    RUN(test_blend_is_pixelwise);
    RUN(test_motion_blend_does_not_ghost);
    RUN(test_motion_blend_keeps_objects_apart);
    RUN(test_warp_deterministic_for_any_thread_count);
    RUN(test_averaging_weighs_inputs_by_ray_angle);
    RUN(test_seed_render_cache_from_base_views);
    RUN(test_extreme_depths_and_colours);
    RUN(test_prepared_inputs_warp_bit_identically);
    RUN(test_prepared_input_changed_in_place);
    RUN(test_prepare_rejects_bad_input);
    RUN(test_warp_rejects_bad_input);
    return test_finish();
}
