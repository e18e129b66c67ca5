/* Concurrency test of rendercache.h under ThreadSanitizer: every parallel
   part of the library runs on a pool of two workers and the calling thread
   (the render cache's frame with prediction, apart or counted in the
   projection's pass, requests, insertion and rendercache_invalidate_where;
   warps of fish-eye and
   perspective range images, prepared or not, with every fill mode and a fill
   callback; pixelwise and motion-compensated time blends), and its result
   must equal, bit for bit, the same calls made serially. ThreadSanitizer
   reports any two jobs that touch the same memory without order (the
   hole filling of one tile against the reads of the next, a shared dummy
   slot written by every tile). */
#include "examples/common/pool.h"
#define RENDERCACHE_IMPLEMENTATION
#include "rendercache.h"
#include "tests/test.h"

#include <float.h>

#define W 256               /* 24 tiles of 8 rows, each long enough to overlap in time with others */
#define H 192
#define FRAMES 8

/* The analytic scene: a wall at z = 10 (object 0, red) and a square at
   z = 6 that moves along x (object 1, green), sky elsewhere. */
static uint32_t trace(float shift, const float o[3], const float d[3], float pos[3], float rgb[3])
{
    float t;
    rgb[0] = rgb[1] = rgb[2] = 0.0f;
    if (d[2] > 0.0f) {
        t = (6.0f - o[2]) / d[2];
        pos[0] = o[0] + t * d[0]; pos[1] = o[1] + t * d[1]; pos[2] = 6.0f;
        if (fabsf(pos[0] - shift) <= 1.0f && fabsf(pos[1]) <= 1.0f) {
            rgb[1] = 0.5f + 0.1f * (pos[0] - shift);
            return 1;
        }
        t = (10.0f - o[2]) / d[2];
        pos[0] = o[0] + t * d[0]; pos[1] = o[1] + t * d[1]; pos[2] = 10.0f;
        if (fabsf(pos[0]) <= 9.0f && fabsf(pos[1]) <= 9.0f) {
            rgb[0] = 0.5f + 0.04f * pos[0] + 0.01f * pos[1];
            return 0;
        }
    }
    rgb[2] = 0.3f + 0.2f * d[1];
    return RENDERCACHE_MISS;
}

static rendercache_camera camera(rendercache_camera_kind kind, float x, float turn, uint32_t w, uint32_t h)
{
    rendercache_camera c;
    memset(&c, 0, sizeof c);
    c.kind = kind;
    c.eye[0] = x;
    c.eye[1] = 0.2f;
    c.look_at[0] = x + turn;
    c.look_at[1] = 0.1f;
    c.look_at[2] = 10.0f;
    c.up[1] = 1.0f;
    c.vfov_degrees = 60.0f;
    c.width = w;
    c.height = h;
    return c;
}

static uint64_t hash_bytes(uint64_t h, const void *p, size_t n)
{
    const unsigned char *b = (const unsigned char *)p;
    while (n--) h = (h ^ *b++) * 1099511628211ull;
    return h;
}

/* ---- the render cache ---------------------------------------------- */
/* The frame with a half-resolution grey ramp in its holes
   (rendercache_compose_fallback, after the frame's parallel passes). */
static const float *composed_with_fallback(const rendercache *rc)
{
    static float rgb[3 * (W / 2) * (H / 2)], conf[(W / 2) * (H / 2)], out[3 * W * H];
    rendercache_fallback fb;
    uint32_t p;
    for (p = 0; p < (W / 2) * (H / 2); p++) {
        rgb[3 * p] = rgb[3 * p + 1] = rgb[3 * p + 2] = (float)(p % (W / 2)) / (float)W;
        conf[p] = p % 3 ? 1.0f : 0.5f;
    }
    memset(&fb, 0, sizeof fb);
    fb.rgb = rgb;
    fb.confidence = conf;
    fb.width = W / 2;
    fb.height = H / 2;
    CHECK_EQ_INT(rendercache_compose_fallback(rc, &fb, out), RENDERCACHE_OK);
    return out;
}

/* rendercache_invalidate_where's predicate, called from several threads
   at once: only reads. The wall's points in the square's shadow from a
   light up and to the left (the square's x is *user). */
static int in_shadow(void *user, const float p[3], uint32_t object)
{
    const float *shift = (const float *)user;
    return object == 0 && fabsf(p[0] - *shift - 2.0f) <= 2.0f && fabsf(p[1] + 2.0f) <= 2.0f;
}

/* The frame sequence with points_per_pixel ppp (0: the default). */
/* The most rounds a projection of run_cache took (the projection's jobs
   hand the points that land in another job's pixels over in rounds). */
static uint32_t g_rounds;

static uint64_t run_cache(ex_pool *pool, float ppp)
{
    static rendercache_pixel_request req[W * H];
    static rendercache_sample late[W * H], now[W * H];
    rendercache_desc d;
    rendercache *rc = NULL;
    uint64_t h = 1469598103934665603ull;
    uint32_t pending = 0, f, i, n;
    memset(&d, 0, sizeof d);
    d.width = W;
    d.height = H;
    d.points_per_pixel = ppp;
    d.parallel_for = pool ? ex_pool_parallel_for : NULL;
    d.parallel_user = pool;
    d.refill_samples = 1;   /* the refill's bands run after every insert */
    if (!CHECK_EQ_INT(rendercache_create(&d, &rc), RENDERCACHE_OK)) return 0;
    for (f = 0; f < FRAMES; f++) {
        float shift = 0.1f * (float)f, m[12] = { 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0 };
        rendercache_camera c = camera(RENDERCACHE_CAMERA_PERSPECTIVE, 0.05f * (float)f, 0.3f * (float)f, W, H);
        rendercache_camera next = camera(RENDERCACHE_CAMERA_PERSPECTIVE, 0.05f * (float)(f + 1), 0.3f * (float)(f + 1), W, H);
        m[3] = shift;
        CHECK_EQ_INT(rendercache_set_object_transform(rc, 1, m), RENDERCACHE_OK);
        if (f % 2) {   /* the prediction counted in the projection's jobs */
            CHECK_EQ_INT(rendercache_begin_frame_predicted(rc, &c, &next), RENDERCACHE_OK);
            /* last frame's samples come back one frame late */
            CHECK_EQ_INT(rendercache_insert(rc, late, pending, NULL), RENDERCACHE_OK);
        } else {
            CHECK_EQ_INT(rendercache_begin_frame(rc, &c), RENDERCACHE_OK);
            if (rc->splat.rounds > g_rounds) g_rounds = rc->splat.rounds;
            CHECK_EQ_INT(rendercache_insert(rc, late, pending, NULL), RENDERCACHE_OK);
            CHECK_EQ_INT(rendercache_predict(rc, &next), RENDERCACHE_OK);
        }
        /* a quarter of the pixels first: holes everywhere, next to every tile border */
        CHECK_EQ_INT(rendercache_request(rc, req, f == 0 ? W * H / 4 : W * H / 8, &n), RENDERCACHE_OK);
        for (i = 0; i < n; i++) {   /* half of them now, half a frame later */
            rendercache_sample *s = i % 2 ? &late[i / 2] : &now[i / 2];
            memset(s, 0, sizeof *s);
            s->x = req[i].x;
            s->y = req[i].y;
            s->flags = req[i].flags;
            s->frame = req[i].frame;
            s->object = trace(shift, req[i].org, req[i].dir, s->position, s->rgb);
        }
        pending = n / 2;
        CHECK_EQ_INT(rendercache_insert(rc, now, n - n / 2, NULL), RENDERCACHE_OK);
        if (f == 5) CHECK_EQ_INT(rendercache_invalidate(rc, 1), RENDERCACHE_OK);
        if (f % 3 == 1) {   /* the square's shadow moved: its points asked in the jobs */
            uint32_t aged = 0;
            CHECK_EQ_INT(rendercache_invalidate_where(rc, in_shadow, &shift, &aged), RENDERCACHE_OK);
            CHECK(aged > 0);
            h = hash_bytes(h, &aged, sizeof aged);
        }
        h = hash_bytes(h, req, n * sizeof *req);
        h = hash_bytes(h, rendercache_image(rc), sizeof(float) * 3 * W * H);
        h = hash_bytes(h, rendercache_priority_image(rc), sizeof(float) * W * H);
        h = hash_bytes(h, composed_with_fallback(rc), sizeof(float) * 3 * W * H);
    }
    rendercache_destroy(rc);
    return h;
}

/* ---- warps and blends ---------------------------------------------- */
static rendercache_range_image *render(const rendercache_camera *c, float shift, double time)
{
    rendercache_range_image *img = NULL;
    uint32_t x, y;
    if (rendercache_range_image_create(c, NULL, &img) != RENDERCACHE_OK) return NULL;
    img->time = time;
    for (y = 0; y < c->height; y++)
        for (x = 0; x < c->width; x++) {
            size_t p = (size_t)y * c->width + x;
            float o[3], d[3], pos[3];
            if (rendercache_camera_ray(c, (float)x + 0.5f, (float)y + 0.5f, o, d) != RENDERCACHE_OK) continue;
            img->object[p] = trace(shift, o, d, pos, img->rgb + 3 * p);
            img->depth[p] = img->object[p] == RENDERCACHE_MISS
                                ? RENDERCACHE_FAR_DEPTH
                                : sqrtf((pos[0] - o[0]) * (pos[0] - o[0]) + (pos[1] - o[1]) * (pos[1] - o[1]) +
                                        (pos[2] - o[2]) * (pos[2] - o[2]));
        }
    return img;
}

/* Fills every third empty pixel with a flat grey at distance 8. */
static int fill_some(void *user, uint32_t x, uint32_t y, const float org[3], const float dir[3], float rgb[3],
                     float *depth, uint32_t *object)
{
    (void)user; (void)org; (void)dir;
    if ((x + y) % 3) return 0;
    rgb[0] = rgb[1] = rgb[2] = 0.25f;
    *depth = 8.0f;
    *object = 0;
    return 1;
}

static uint64_t run_warps(ex_pool *pool)
{
    static const rendercache_fill fills[4] = { RENDERCACHE_FILL_NONE, RENDERCACHE_FILL_FOREGROUND,
                                               RENDERCACHE_FILL_BACKGROUND, RENDERCACHE_FILL_BOTH };
    rendercache_camera fish[3], target = camera(RENDERCACHE_CAMERA_PERSPECTIVE, 0.4f, 0.5f, W, H);
    rendercache_range_image *in[3], *a, *b, *out = NULL, *blend = NULL;
    rendercache_warp_desc d;
    rendercache_warper *w = NULL;
    rendercache_motion motion;
    float world[3][24];
    uint64_t h = 1469598103934665603ull;
    int i, f;
    memset(&d, 0, sizeof d);
    d.parallel_for = pool ? ex_pool_parallel_for : NULL;
    d.parallel_user = pool;
    d.fill_pixel = fill_some;
    fish[0] = camera(RENDERCACHE_CAMERA_FISHEYE, -0.5f, 0.0f, 80, 80);
    fish[1] = camera(RENDERCACHE_CAMERA_FISHEYE, 0.9f, 0.2f, 80, 80);
    fish[2] = camera(RENDERCACHE_CAMERA_PERSPECTIVE, 0.2f, -0.2f, 64, 48);
    for (i = 0; i < 3; i++) in[i] = render(&fish[i], 0.0f, 0.0);
    a = render(&fish[0], 0.0f, 0.0);
    b = render(&fish[0], 0.6f, 1.0);
    if (!CHECK(in[0] && in[1] && in[2] && a && b)) return 0;
    CHECK_EQ_INT(rendercache_warper_create(&d, &w), RENDERCACHE_OK);
    CHECK_EQ_INT(rendercache_range_image_create(&target, NULL, &out), RENDERCACHE_OK);
    CHECK_EQ_INT(rendercache_range_image_create(&fish[0], NULL, &blend), RENDERCACHE_OK);
    for (f = 0; f < 12; f++) {   /* every fill, every fill averaging the inputs, every fill from prepared inputs */
        if (f == 4 || f == 8) {
            rendercache_warper_destroy(w);
            d.average = f == 4;
            CHECK_EQ_INT(rendercache_warper_create(&d, &w), RENDERCACHE_OK);
        }
        if (f == 8)
            for (i = 0; i < 3; i++) CHECK_EQ_INT(rendercache_range_image_prepare(in[i]), RENDERCACHE_OK);
        CHECK_EQ_INT(rendercache_warp(w, (const rendercache_range_image *const *)in, 3, &target, fills[f % 4], out),
                     RENDERCACHE_OK);
        h = hash_bytes(h, out->rgb, sizeof(float) * 3 * W * H);
        h = hash_bytes(h, out->depth, sizeof(float) * W * H);
        h = hash_bytes(h, out->object, sizeof(uint32_t) * W * H);
    }
    /* time blends: pixelwise, then with the square moved by its transforms */
    for (i = 0; i < 3; i++) {
        memset(world[i], 0, sizeof world[i]);
        world[i][0] = world[i][5] = world[i][10] = 1.0f;
        memcpy(world[i] + 12, world[i], 12 * sizeof(float));
    }
    world[1][12 + 3] = 0.6f;   /* the square at b's time */
    world[2][12 + 3] = 0.3f;   /* and at the blend's */
    motion.object_count = 2;
    motion.world_a = world[0];
    motion.world_b = world[1];
    motion.world_t = world[2];
    CHECK_EQ_INT(rendercache_blend(a, b, 0.5f, blend), RENDERCACHE_OK);
    h = hash_bytes(h, blend->rgb, sizeof(float) * 3 * 80 * 80);
    for (f = 0; f < 4; f++) {
        CHECK_EQ_INT(rendercache_blend_motion(w, a, b, 0.5f, &motion, fills[f], blend), RENDERCACHE_OK);
        h = hash_bytes(h, blend->rgb, sizeof(float) * 3 * 80 * 80);
        h = hash_bytes(h, blend->depth, sizeof(float) * 80 * 80);
    }
    for (i = 0; i < 3; i++) rendercache_range_image_destroy(in[i]);
    rendercache_range_image_destroy(a);
    rendercache_range_image_destroy(b);
    rendercache_range_image_destroy(out);
    rendercache_range_image_destroy(blend);
    rendercache_warper_destroy(w);
    return h;
}

static void test_parallel_frame_matches_serial(void)
{
    ex_pool *pool = ex_pool_create(3);
    uint64_t serial = run_cache(NULL, 0.0f);
    if (!CHECK(pool != NULL)) return;
    CHECK(serial != 0);
    g_rounds = 0;
    CHECK(run_cache(pool, 0.0f) == serial);
    CHECK(g_rounds >= 2);   /* the jobs handed points over, in more than one round */
    ex_pool_destroy(pool);
}

/* With 3 points per pixel the cache has 9 ranges of the re-sort into image
   order, so each frame re-sorts 2 of them in 2 jobs (one range, as with the
   default, runs as a single job). */
static void test_parallel_resort_matches_serial(void)
{
    ex_pool *pool = ex_pool_create(3);
    uint64_t serial = run_cache(NULL, 3.0f);
    if (!CHECK(pool != NULL)) return;
    CHECK(serial != 0);
    CHECK(run_cache(pool, 3.0f) == serial);
    ex_pool_destroy(pool);
}

static void test_parallel_warps_match_serial(void)
{
    ex_pool *pool = ex_pool_create(3);
    uint64_t serial = run_warps(NULL);
    if (!CHECK(pool != NULL)) return;
    CHECK(serial != 0);
    CHECK(run_warps(pool) == serial);
    ex_pool_destroy(pool);
}

int main(int argc, char **argv)
{
    TEST_INIT(argc, argv);
    RUN(test_parallel_frame_matches_serial);
    RUN(test_parallel_resort_matches_serial);
    RUN(test_parallel_warps_match_serial);
    return test_finish();
}
