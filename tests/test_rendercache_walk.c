/* Unit tests of rendercache.h, the coherence tests and bookkeeping of
   range-image walkthroughs (Nimeroff, Dorsey and Rushmeier 1996): fitness
   of id images, adaptive subdivision of view spaces and of time against an
   independent reference recursion on synthetic id images, key times of an
   object-space solution on a synthetic irradiance signal, the LRMS metric
   on known answers, and hostile loading of saved range images. */
#define RENDERCACHE_IMPLEMENTATION
#include "rendercache.h"
#include "test.h"

#include <float.h>

/* ---------------------------------------------------------------------
   Fitness
   --------------------------------------------------------------------- */
static void test_fitness_known_answers(void)
{
    static const uint32_t a[6] = { 1, 2, 3, 4, 5, 6 }, b[6] = { 7, 8, 9, 10, 11, 12 }, c[6] = { 1, 2, 3, 0, 0, 0 };
    static const uint32_t d[4] = { RENDERCACHE_NO_SAMPLE, 1, 2, RENDERCACHE_NO_SAMPLE };
    static const uint32_t e[4] = { RENDERCACHE_NO_SAMPLE, 1, 5, 4 };
    const uint32_t *set[3];
    float f = -1.0f;
    set[0] = a; set[1] = a; set[2] = a;
    CHECK_EQ_INT(rendercache_fitness(set, 3, 3, 2, &f), RENDERCACHE_OK);
    CHECK(f == 1.0f);   /* identical */
    set[1] = b;
    CHECK_EQ_INT(rendercache_fitness(set, 2, 3, 2, &f), RENDERCACHE_OK);
    CHECK(f == 0.0f);   /* disjoint */
    set[1] = c;
    CHECK_EQ_INT(rendercache_fitness(set, 2, 6, 1, &f), RENDERCACHE_OK);
    CHECK(f == 0.5f);
    set[2] = b;
    CHECK_EQ_INT(rendercache_fitness(set, 3, 6, 1, &f), RENDERCACHE_OK);
    CHECK(f == 0.0f);
    CHECK_EQ_INT(rendercache_fitness(set, 1, 6, 1, &f), RENDERCACHE_OK);
    CHECK(f == 1.0f);   /* one image agrees with itself */
    /* pixels without a ray in every image are not counted; in one image only, they differ */
    set[0] = d; set[1] = e;
    CHECK_EQ_INT(rendercache_fitness(set, 2, 4, 1, &f), RENDERCACHE_OK);
    CHECK_CLOSE(f, 1.0 / 3.0, 1e-6, 0.0);
    CHECK_EQ_INT(rendercache_fitness(NULL, 2, 4, 1, &f), RENDERCACHE_ERROR_INVALID_ARGUMENT);
    CHECK_EQ_INT(rendercache_fitness(set, 0, 4, 1, &f), RENDERCACHE_ERROR_INVALID_ARGUMENT);
    CHECK_EQ_INT(rendercache_fitness(set, 2, 0, 1, &f), RENDERCACHE_ERROR_INVALID_ARGUMENT);
    CHECK_EQ_INT(rendercache_fitness(set, 2, 4, 1, NULL), RENDERCACHE_ERROR_INVALID_ARGUMENT);
    set[1] = NULL;
    CHECK_EQ_INT(rendercache_fitness(set, 2, 4, 1, &f), RENDERCACHE_ERROR_INVALID_ARGUMENT);
}

/* ---------------------------------------------------------------------
   View space subdivision. Synthetic id images of P pixels per row: row r
   of the image of eye e has id 1 on its first floor(P g_r(e)) pixels and id
   2 on the rest, so the fitness of a set of eyes is known in closed form.
   --------------------------------------------------------------------- */
#define P 1000

typedef struct synth {
    int rows;                 /* 1: g0(x); 2: g0(x) and g1(y) */
    uint32_t renders;
    int cancel_after;         /* 0: never */
} synth;

static double g0(double x) { return (x / 2.0) * (x / 2.0); }   /* x in [0, 2] */
static double g1(double y) { return y; }                       /* y in [0, 1] */

static uint32_t threshold(int row, const float eye[3])
{
    double g = row == 0 ? g0(eye[0]) : g1(eye[1]);
    return (uint32_t)floor((double)P * g);
}

static int render_synthetic(void *user, const rendercache_camera *camera, double time, uint32_t *ids)
{
    synth *s = (synth *)user;
    int r;
    uint32_t p;
    (void)time;
    if (s->cancel_after && (int)s->renders >= s->cancel_after) return 1;
    s->renders++;
    for (r = 0; r < s->rows; r++) {
        uint32_t t = threshold(r, camera->eye);
        for (p = 0; p < P; p++) ids[(size_t)r * P + p] = p < t ? 1u : 2u;
    }
    return 0;
}

/* The reference: the fitness of the corners in closed form, and the same
   rule (below q: halve the longest axis that can be halved). Records the
   leaves' lattice bounds. */
typedef struct ref_cells {
    uint32_t lo[64][2], hi[64][2];
    int count;
} ref_cells;

static float ref_fitness(int rows, const float lo[3], const float hi[3])
{
    uint32_t spread = 0;
    int r;
    for (r = 0; r < rows; r++) {
        uint32_t a = threshold(r, lo), b = threshold(r, hi);
        spread += a > b ? a - b : b - a;   /* g is monotone: the extreme corners bound the others */
    }
    return (float)(1.0 - (double)spread / (double)(P * rows));
}

static void lattice_eye(const float lo[3], const float hi[3], const uint32_t k[2], uint32_t steps, float eye[3])
{
    int i;
    for (i = 0; i < 2; i++) eye[i] = (float)((double)lo[i] + ((double)hi[i] - lo[i]) * ((double)k[i] / (double)steps));
    eye[2] = lo[2];
}

static void ref_subdivide(int rows, const float lo[3], const float hi[3], uint32_t steps, float q, const uint32_t klo[2],
                          const uint32_t khi[2], ref_cells *out)
{
    float elo[3], ehi[3];
    int axis = -1, i;
    double best = -1.0;
    lattice_eye(lo, hi, klo, steps, elo);
    lattice_eye(lo, hi, khi, steps, ehi);
    for (i = 0; i < rows; i++) {
        double len = ((double)hi[i] - lo[i]) * (double)(khi[i] - klo[i]);
        if (khi[i] - klo[i] >= 2 && len > best) { best = len; axis = i; }
    }
    if (ref_fitness(rows, elo, ehi) >= q || axis < 0) {
        if (out->count < 64) {
            memcpy(out->lo[out->count], klo, sizeof out->lo[0]);
            memcpy(out->hi[out->count], khi, sizeof out->hi[0]);
        }
        out->count++;
        return;
    }
    {
        uint32_t mid = (klo[axis] + khi[axis]) / 2, a[2], b[2];
        memcpy(a, khi, sizeof a);
        memcpy(b, klo, sizeof b);
        a[axis] = mid;
        b[axis] = mid;
        ref_subdivide(rows, lo, hi, steps, q, klo, a, out);
        ref_subdivide(rows, lo, hi, steps, q, b, khi, out);
    }
}

static rendercache_view_space_desc view_desc(synth *s, float q, uint32_t depth)
{
    rendercache_view_space_desc d;
    memset(&d, 0, sizeof d);
    d.camera.kind = RENDERCACHE_CAMERA_PERSPECTIVE;
    d.camera.look_at[2] = 1.0f;
    d.camera.up[1] = 1.0f;
    d.camera.vfov_degrees = 60.0f;
    d.camera.width = P;
    d.camera.height = (uint32_t)s->rows;
    d.hi[0] = 2.0f;
    d.hi[1] = s->rows > 1 ? 1.0f : 0.0f;
    d.lo[2] = d.hi[2] = 5.0f;
    d.quality = q;
    d.max_depth = depth;
    d.render_ids = render_synthetic;
    d.user = s;
    return d;
}

static void check_against_reference(int rows, float q)
{
    synth s;
    rendercache_view_space_desc d;
    rendercache_view_space *vs = NULL;
    ref_cells ref;
    uint32_t klo[2] = { 0, 0 }, khi[2], steps = 1u << 6, i, c, n;
    memset(&s, 0, sizeof s);
    s.rows = rows;
    d = view_desc(&s, q, 6);
    khi[0] = steps;
    khi[1] = rows > 1 ? steps : 0;
    memset(&ref, 0, sizeof ref);
    ref_subdivide(rows, d.lo, d.hi, steps, q, klo, khi, &ref);
    if (!CHECK_EQ_INT(rendercache_view_space_create(&d, &vs), RENDERCACHE_OK)) return;
    n = rendercache_view_space_cell_count(vs);
    test_note("%dD view space, q = %.2f: %u views, %u cells (reference %d cells), %u id images rendered", rows, q,
              rendercache_view_space_count(vs), n, ref.count, s.renders);
    CHECK_EQ_INT(n, ref.count);
    CHECK_EQ_INT(s.renders, rendercache_view_space_count(vs));   /* each view rendered once */
    for (c = 0; c < n && (int)c < ref.count && c < 64; c++) {   /* same leaves, in the same order */
        float lo[3], hi[3], f, elo[3], ehi[3];
        CHECK_EQ_INT(rendercache_view_space_cell(vs, c, lo, hi, &f), RENDERCACHE_OK);
        lattice_eye(d.lo, d.hi, ref.lo[c], steps, elo);
        lattice_eye(d.lo, d.hi, ref.hi[c], steps, ehi);
        for (i = 0; i < 2; i++) {
            CHECK(lo[i] == elo[i]);
            CHECK(hi[i] == ehi[i]);
        }
        /* a leaf passes q, or it cannot be halved any more */
        CHECK_CLOSE(f, ref_fitness(rows, elo, ehi), 0.0, 1e-6);
        CHECK(f >= q || (hi[0] - lo[0]) * (float)steps <= 2.0f * 1.0001f);
    }
    /* locate: the corners of the cell holding an eye enclose it */
    for (i = 0; i < 50; i++) {
        float eye[3], lo[3] = { FLT_MAX, FLT_MAX, 0 }, hi[3] = { -FLT_MAX, -FLT_MAX, 0 };
        uint32_t views[8], count, k;
        const float *eyes = rendercache_view_space_eyes(vs);
        eye[0] = 2.0f * (float)i / 49.0f;
        eye[1] = rows > 1 ? (float)((i * 7) % 50) / 49.0f : 0.0f;
        eye[2] = 5.0f;
        CHECK_EQ_INT(rendercache_view_space_locate(vs, eye, views, &count), RENDERCACHE_OK);
        CHECK_EQ_INT(count, rows > 1 ? 4 : 2);
        for (k = 0; k < count; k++) {
            int a;
            CHECK(views[k] < rendercache_view_space_count(vs));
            for (a = 0; a < 2; a++) {
                lo[a] = eyes[3 * views[k] + a] < lo[a] ? eyes[3 * views[k] + a] : lo[a];
                hi[a] = eyes[3 * views[k] + a] > hi[a] ? eyes[3 * views[k] + a] : hi[a];
            }
        }
        CHECK(lo[0] <= eye[0] && eye[0] <= hi[0]);
        if (rows > 1) CHECK(lo[1] <= eye[1] && eye[1] <= hi[1]);
    }
    rendercache_view_space_destroy(vs);
}

static void test_view_space_subdivision_matches_reference(void)
{
    static const float qs[4] = { 0.3f, 0.6f, 0.9f, 0.99f };
    int i;
    for (i = 0; i < 4; i++) {
        check_against_reference(1, qs[i]);
        check_against_reference(2, qs[i]);
    }
}

static void test_view_space_edge_cases(void)
{
    synth s;
    rendercache_view_space_desc d;
    rendercache_view_space *vs = NULL;
    rendercache_camera cam;
    const float *eyes;
    memset(&s, 0, sizeof s);
    s.rows = 2;
    /* q = 0: the corners of the box only */
    d = view_desc(&s, 0.0f, 6);
    if (CHECK_EQ_INT(rendercache_view_space_create(&d, &vs), RENDERCACHE_OK)) {
        CHECK_EQ_INT(rendercache_view_space_count(vs), 4);
        CHECK_EQ_INT(rendercache_view_space_cell_count(vs), 1);
        eyes = rendercache_view_space_eyes(vs);
        CHECK(eyes[0] == 0.0f && eyes[1] == 0.0f && eyes[2] == 5.0f);
        CHECK_EQ_INT(rendercache_view_space_camera(vs, 3, &cam), RENDERCACHE_OK);
        CHECK(cam.eye[0] == 2.0f && cam.eye[1] == 1.0f && cam.look_at[2] == 6.0f);   /* the look direction is kept */
        CHECK_EQ_INT(rendercache_view_space_camera(vs, 4, &cam), RENDERCACHE_ERROR_INVALID_ARGUMENT);
        rendercache_view_space_destroy(vs);
    }
    /* q = 1 with depth 2: subdivision stops at the depth limit */
    d = view_desc(&s, 1.0f, 2);
    if (CHECK_EQ_INT(rendercache_view_space_create(&d, &vs), RENDERCACHE_OK)) {
        CHECK_EQ_INT(rendercache_view_space_count(vs), 25);   /* a 5 x 5 lattice */
        rendercache_view_space_destroy(vs);
    }
    /* 3D: the eight corners, and every eye inside the box located in the one cell */
    d = view_desc(&s, 0.0f, 4);
    d.hi[2] = 6.0f;
    if (CHECK_EQ_INT(rendercache_view_space_create(&d, &vs), RENDERCACHE_OK)) {
        uint32_t views[8], count = 0, k, seen = 0;
        float eye[3] = { 0.5f, 0.5f, 5.5f };
        CHECK_EQ_INT(rendercache_view_space_count(vs), 8);
        CHECK_EQ_INT(rendercache_view_space_locate(vs, eye, views, &count), RENDERCACHE_OK);
        CHECK_EQ_INT(count, 8);
        for (k = 0; k < count; k++) seen |= 1u << views[k];
        CHECK_EQ_INT(seen, 0xFF);
        rendercache_view_space_destroy(vs);
    }
    /* a point: one view */
    d = view_desc(&s, 0.9f, 4);
    d.hi[0] = d.lo[0];
    d.hi[1] = d.lo[1];
    if (CHECK_EQ_INT(rendercache_view_space_create(&d, &vs), RENDERCACHE_OK)) {
        CHECK_EQ_INT(rendercache_view_space_count(vs), 1);
        rendercache_view_space_destroy(vs);
    }
    /* the callback cancels: nothing leaks (ASan) */
    s.renders = 0;
    s.cancel_after = 5;
    d = view_desc(&s, 0.9f, 6);
    CHECK_EQ_INT(rendercache_view_space_create(&d, &vs), RENDERCACHE_ERROR_CANCELLED);
    CHECK(vs == NULL);
    s.cancel_after = 0;
    /* bad input */
    d = view_desc(&s, 1.5f, 6);
    CHECK_EQ_INT(rendercache_view_space_create(&d, &vs), RENDERCACHE_ERROR_INVALID_ARGUMENT);
    d = view_desc(&s, 0.5f, 21);
    CHECK_EQ_INT(rendercache_view_space_create(&d, &vs), RENDERCACHE_ERROR_INVALID_ARGUMENT);
    d = view_desc(&s, 0.5f, 6);
    d.lo[0] = 3.0f;   /* lo > hi */
    CHECK_EQ_INT(rendercache_view_space_create(&d, &vs), RENDERCACHE_ERROR_INVALID_ARGUMENT);
    d = view_desc(&s, 0.5f, 6);
    d.camera.eye[1] = NAN;
    CHECK_EQ_INT(rendercache_view_space_create(&d, &vs), RENDERCACHE_ERROR_INVALID_ARGUMENT);
    d = view_desc(&s, 0.5f, 6);
    d.render_ids = NULL;
    CHECK_EQ_INT(rendercache_view_space_create(&d, &vs), RENDERCACHE_ERROR_INVALID_ARGUMENT);
    CHECK_EQ_INT(rendercache_view_space_create(NULL, &vs), RENDERCACHE_ERROR_INVALID_ARGUMENT);
    CHECK_EQ_INT(rendercache_view_space_locate(NULL, d.lo, NULL, NULL), RENDERCACHE_ERROR_INVALID_ARGUMENT);
    rendercache_view_space_destroy(NULL);
}

/* ---------------------------------------------------------------------
   Time subdivision: camera c's id image at time t splits at floor(P h_c(t)).
   --------------------------------------------------------------------- */
static double h_time(int camera, double t) { return camera == 0 ? t * t : 0.5 + 0.5 * sin(3.0 * t); }

static int render_in_time(void *user, const rendercache_camera *camera, double time, uint32_t *ids)
{
    uint32_t p, t = (uint32_t)floor((double)P * h_time(camera->eye[0] > 0.5f, time));
    (*(uint32_t *)user)++;
    for (p = 0; p < P; p++) ids[p] = p < t ? 1u : 2u;
    return 0;
}

/* Reference: halve while some camera's pair has fitness below q. */
static void ref_times(int cameras, double ta, double tb, float q, uint32_t depth, uint32_t max_depth, double *out,
                      uint32_t *n)
{
    int c, coherent = 1;
    for (c = 0; c < cameras; c++) {
        double a = floor((double)P * h_time(c, ta)), b = floor((double)P * h_time(c, tb));
        coherent &= (float)(1.0 - fabs(a - b) / (double)P) >= q;
    }
    if (coherent || depth >= max_depth) {
        out[(*n)++] = tb;
        return;
    }
    ref_times(cameras, ta, 0.5 * (ta + tb), q, depth + 1, max_depth, out, n);
    ref_times(cameras, 0.5 * (ta + tb), tb, q, depth + 1, max_depth, out, n);
}

static void test_time_subdivision_matches_reference(void)
{
    static const float qs[3] = { 0.3f, 0.6f, 0.9f };
    static const double start[3] = { 0.0, 0.3, 1.0 };
    rendercache_camera cams[2];
    rendercache_time_desc d;
    uint32_t renders = 0, count = 0, n, i, k, last = 0;
    double *times = NULL, expect[1100];
    int c, qi;
    memset(cams, 0, sizeof cams);
    for (c = 0; c < 2; c++) {
        cams[c].kind = RENDERCACHE_CAMERA_FISHEYE;   /* as if placed at a light */
        cams[c].eye[0] = (float)c;
        cams[c].look_at[0] = (float)c;
        cams[c].look_at[1] = -1.0f;
        cams[c].up[2] = 1.0f;
        cams[c].width = P;
        cams[c].height = 1;
    }
    memset(&d, 0, sizeof d);
    d.cameras = cams;
    d.times = start;
    d.render_ids = render_in_time;
    d.user = &renders;
    for (qi = 0; qi < 3; qi++)
        for (c = 1; c <= 2; c++) {
            d.camera_count = (uint32_t)c;
            d.quality = qs[qi];
            d.time_count = 3;
            d.max_depth = 8;
            n = 1;
            expect[0] = 0.0;
            for (k = 1; k < 3; k++) ref_times(c, start[k - 1], start[k], qs[qi], 0, 8, expect, &n);
            if (!CHECK_EQ_INT(rendercache_subdivide_time(&d, &times, &count), RENDERCACHE_OK)) continue;
            CHECK_EQ_INT(count, n);
            for (i = 0; i < count && i < n; i++) CHECK(times[i] == expect[i]);
            if (c == 2) {
                test_note("time list for q = %.1f, 2 cameras: %u key times", qs[qi], count);
                CHECK(count >= last);   /* more keys as q rises */
                last = count;
            }
            rendercache_free_memory(NULL, times);
        }
    /* bad input */
    d.camera_count = 2;
    d.time_count = 1;
    CHECK_EQ_INT(rendercache_subdivide_time(&d, &times, &count), RENDERCACHE_ERROR_INVALID_ARGUMENT);
    d.time_count = 3;
    d.times = expect;
    expect[0] = 0.0; expect[1] = 0.0; expect[2] = 1.0;   /* not increasing */
    CHECK_EQ_INT(rendercache_subdivide_time(&d, &times, &count), RENDERCACHE_ERROR_INVALID_ARGUMENT);
    expect[1] = NAN;
    CHECK_EQ_INT(rendercache_subdivide_time(&d, &times, &count), RENDERCACHE_ERROR_INVALID_ARGUMENT);
    d.times = start;
    cams[1].width = 0;
    CHECK_EQ_INT(rendercache_subdivide_time(&d, &times, &count), RENDERCACHE_ERROR_INVALID_ARGUMENT);
    CHECK(times == NULL && count == 0);
}

/* ---------------------------------------------------------------------
   Key times of a synthetic indirect irradiance: a light moving away along
   x (from x = -1 at t = 0 to x = -2 at t = 1, 1 m above the floor) lights 40
   floor vertices in [0, 10]: E = h / r^3, decreasing in time at every vertex,
   fast near the light and slowly far from it.
   --------------------------------------------------------------------- */
#define VERTS 40

static double irradiance(int vertex, double t)
{
    double x = 10.0 * (double)vertex / (VERTS - 1), lx = -1.0 - t, r2 = (x - lx) * (x - lx) + 1.0;
    return 1.0 / (r2 * sqrt(r2));
}

typedef struct solver { uint32_t calls, components; int fail_at; } solver;

static int solve_irradiance(void *user, double t, float *values)
{
    solver *s = (solver *)user;
    uint32_t v, k;
    if (s->fail_at && (int)s->calls >= s->fail_at) return 1;
    s->calls++;
    for (v = 0; v < VERTS; v++)
        for (k = 0; k < s->components; k++) values[v * s->components + k] = (float)(irradiance((int)v, t) / (1.0 + k));
    return 0;
}

/* ---------------------------------------------------------------------
   The trends of Nimeroff et al.'s tables 3 and 4 in a ray-cast scene: a
   room of 6 x 3 x 8 m with three pieces of furniture (every face its own
   id, as the paper's id images). Table 3: a 1D view space 4 m long across
   the room, 48x48 fish-eyes; table 4: a cabinet sliding 2 m across a fixed
   48x48 view of 60 degrees (the paper's Cornell box sequence), with a
   fish-eye at the ceiling light. As q rises, more base views and more key
   times.
   --------------------------------------------------------------------- */
typedef struct room_box { float lo[3], hi[3]; } room_box;

typedef struct room {
    room_box furniture[3];
    room_box slider;         /* at time 0; moves along +x by 2 m over [0, 1] */
    int with_slider;
} room;

/* Entry (outside: the nearest face) or exit (inside) of a ray and a box:
   distance and face id (2 per axis, + base), or 0 when missed. */
static uint32_t room_hit(const room_box *b, float shift, const float o[3], const float d[3], int inside, float *t,
                         uint32_t base)
{
    float t0 = -FLT_MAX, t1 = FLT_MAX;
    uint32_t f0 = 0, f1 = 0;
    int k;
    for (k = 0; k < 3; k++) {
        float lo = b->lo[k] + (k == 0 ? shift : 0.0f), hi = b->hi[k] + (k == 0 ? shift : 0.0f), a, c;
        uint32_t fa = base + 2u * (uint32_t)k, fc = fa + 1u;
        if (d[k] == 0.0f) {
            if (o[k] < lo || o[k] > hi) return 0;
            continue;
        }
        a = (lo - o[k]) / d[k];
        c = (hi - o[k]) / d[k];
        if (a > c) { float x = a; a = c; c = x; fa = fc; fc = base + 2u * (uint32_t)k; }
        if (a > t0) { t0 = a; f0 = fa; }
        if (c < t1) { t1 = c; f1 = fc; }
    }
    if (t0 > t1) return 0;
    if (inside) { *t = t1; return f1; }
    if (t0 <= 0.0f) return 0;
    *t = t0;
    return f0;
}

static int render_room(void *user, const rendercache_camera *camera, double time, uint32_t *ids)
{
    static const room_box walls = { { 0, 0, 0 }, { 6, 3, 8 } };
    const room *r = (const room *)user;
    uint32_t x, y;
    for (y = 0; y < camera->height; y++)
        for (x = 0; x < camera->width; x++) {
            float o[3], d[3], best = FLT_MAX, t;
            uint32_t id = 0, f, i;
            if (rendercache_camera_ray(camera, (float)x + 0.5f, (float)y + 0.5f, o, d) != RENDERCACHE_OK) {
                ids[y * camera->width + x] = RENDERCACHE_NO_SAMPLE;
                continue;
            }
            if ((f = room_hit(&walls, 0.0f, o, d, 1, &t, 10)) != 0) { best = t; id = f; }
            for (i = 0; i < 3; i++)
                if ((f = room_hit(&r->furniture[i], 0.0f, o, d, 0, &t, 20 + 10 * i)) != 0 && t < best) { best = t; id = f; }
            if (r->with_slider && (f = room_hit(&r->slider, 2.0f * (float)time, o, d, 0, &t, 60)) != 0 && t < best) id = f;
            ids[y * camera->width + x] = id;
        }
    return 0;
}

static room make_room(void)
{
    static const room_box pieces[3] = { { { 0.5f, 0, 5.0f }, { 2.5f, 0.8f, 6.0f } },     /* a desk */
                                        { { 4.0f, 0, 3.0f }, { 4.3f, 1.8f, 6.5f } },     /* a divider */
                                        { { 0.0f, 0, 7.4f }, { 3.0f, 2.2f, 8.0f } } };   /* shelves */
    room r;
    memset(&r, 0, sizeof r);
    memcpy(r.furniture, pieces, sizeof pieces);
    r.slider.lo[0] = 1.2f; r.slider.lo[1] = 0.0f; r.slider.lo[2] = 1.6f;
    r.slider.hi[0] = 2.6f; r.slider.hi[1] = 2.0f; r.slider.hi[2] = 2.2f;
    return r;
}

static rendercache_camera room_fisheye(float x, float y, float z, float lx, float ly, float lz)
{
    rendercache_camera c;
    memset(&c, 0, sizeof c);
    c.kind = RENDERCACHE_CAMERA_FISHEYE;
    c.eye[0] = x; c.eye[1] = y; c.eye[2] = z;
    c.look_at[0] = lx; c.look_at[1] = ly; c.look_at[2] = lz;
    c.up[1] = 1.0f;
    if (lx == x && lz == z) { c.up[1] = 0.0f; c.up[2] = 1.0f; }
    c.width = c.height = 48;
    return c;
}

static void test_more_views_and_key_times_as_quality_rises(void)
{
    static const float qs[3] = { 0.3f, 0.6f, 0.9f };
    room r = make_room();
    uint32_t views[3], keys[3];
    int i;
    for (i = 0; i < 3; i++) {   /* table 3: base views of a 1D view space */
        rendercache_view_space_desc d;
        rendercache_view_space *vs = NULL;
        memset(&d, 0, sizeof d);
        d.camera = room_fisheye(1.0f, 1.5f, 1.0f, 1.0f, 1.3f, 2.0f);
        d.lo[0] = 1.0f; d.lo[1] = 1.5f; d.lo[2] = 1.0f;
        d.hi[0] = 5.0f; d.hi[1] = 1.5f; d.hi[2] = 1.0f;
        d.quality = qs[i];
        d.max_depth = 6;
        d.render_ids = render_room;
        d.user = &r;
        views[i] = 0;
        if (CHECK_EQ_INT(rendercache_view_space_create(&d, &vs), RENDERCACHE_OK)) views[i] = rendercache_view_space_count(vs);
        rendercache_view_space_destroy(vs);
    }
    r.with_slider = 1;
    for (i = 0; i < 3; i++) {   /* table 4: key times of a motion before a fixed view and the light */
        rendercache_camera cams[2];
        rendercache_time_desc d;
        double ends[2] = { 0.0, 1.0 }, *times = NULL;
        cams[0] = room_fisheye(3.0f, 1.2f, 0.0f, 3.0f, 1.2f, 1.0f);
        cams[0].kind = RENDERCACHE_CAMERA_PERSPECTIVE;
        cams[0].vfov_degrees = 60.0f;
        cams[1] = room_fisheye(3.0f, 2.9f, 4.0f, 3.0f, 0.0f, 4.0f);   /* the light, looking down */
        memset(&d, 0, sizeof d);
        d.cameras = cams;
        d.camera_count = 2;
        d.times = ends;
        d.time_count = 2;
        d.quality = qs[i];
        d.max_depth = 6;
        d.render_ids = render_room;
        d.user = &r;
        keys[i] = 0;
        CHECK_EQ_INT(rendercache_subdivide_time(&d, &times, &keys[i]), RENDERCACHE_OK);
        rendercache_free_memory(NULL, times);
    }
    test_note("tables 3-4 in a ray-cast room, q = 0.3 / 0.6 / 0.9: %u / %u / %u base views (paper: 2 / 3 / 5), "
              "%u / %u / %u key times (paper: 2 / 3 / 5)", views[0], views[1], views[2], keys[0], keys[1], keys[2]);
    CHECK(views[0] >= 2 && views[0] < views[1] && views[1] < views[2]);
    CHECK(keys[0] >= 2 && keys[0] < keys[1] && keys[1] < keys[2]);
}

static void test_key_times_reproduce_the_signal(void)
{
    static const float qs[4] = { 0.3f, 0.6f, 0.9f, 1.0f };
    rendercache_keytime_desc d;
    rendercache_keytimes *kt = NULL;
    solver s;
    float values[3 * VERTS];
    uint32_t last = 0;
    int qi, i, v;
    memset(&d, 0, sizeof d);
    memset(&s, 0, sizeof s);
    d.element_count = VERTS;
    d.t0 = 0.0;
    d.t1 = 1.0;
    d.epsilon = 0.05f;
    d.max_depth = 12;
    d.solve = solve_irradiance;
    d.user = &s;
    for (qi = 0; qi < 4; qi++) {
        uint32_t keys, worst_changed = 0;
        const double *times;
        s.calls = 0;
        s.components = qi == 3 ? 3u : 1u;
        d.components = s.components;
        d.quality = qs[qi];
        if (!CHECK_EQ_INT(rendercache_keytimes_create(&d, &kt), RENDERCACHE_OK)) continue;
        keys = rendercache_keytimes_count(kt);
        times = rendercache_keytimes_times(kt);
        CHECK_EQ_INT(keys, s.calls);   /* every solution computed is a key */
        CHECK(times[0] == 0.0 && times[keys - 1] == 1.0);
        CHECK(keys >= last);
        last = keys;
        /* at every time, the elements off by more than epsilon (relative to the larger of the
           bracketing keys' values) are at most the fraction 1 - q: the signal is monotone in
           time, so the error is at most the change over the interval */
        for (i = 0; i <= 200; i++) {
            double t = (double)i / 200.0;
            uint32_t lo = 0, off = 0;
            CHECK_EQ_INT(rendercache_keytimes_eval(kt, t, values, sizeof values / sizeof values[0]), RENDERCACHE_OK);
            while (lo + 2 < keys && times[lo + 1] <= t) lo++;
            for (v = 0; v < VERTS; v++) {
                double a = irradiance(v, times[lo]), b = irradiance(v, times[lo + 1]);
                double scale = a > b ? a : b, err = fabs(values[v * s.components] - irradiance(v, t));
                /* float storage of the values: 1e-6 relative */
                off += err > d.epsilon * scale + 1e-6 * scale;
            }
            worst_changed = off > worst_changed ? off : worst_changed;
        }
        test_note("key times for q = %.1f: %u keys, worst fraction off by more than epsilon %.3f (allowed %.3f)",
                  qs[qi], keys, (double)worst_changed / VERTS, 1.0 - qs[qi]);
        CHECK((double)worst_changed <= (1.0 - qs[qi]) * VERTS + 1e-9);
        /* at the key times themselves, the stored solution */
        for (i = 0; i < (int)keys; i++) {
            const float *kv = rendercache_keytimes_values(kt, (uint32_t)i);
            CHECK_EQ_INT(rendercache_keytimes_eval(kt, times[i], values, sizeof values / sizeof values[0]), RENDERCACHE_OK);
            CHECK(memcmp(values, kv, VERTS * s.components * sizeof(float)) == 0);
        }
        /* clamped outside [t0, t1] */
        CHECK_EQ_INT(rendercache_keytimes_eval(kt, -5.0, values, sizeof values / sizeof values[0]), RENDERCACHE_OK);
        /* a buffer shorter than the solution */
        CHECK_EQ_INT(rendercache_keytimes_eval(kt, 0.5, values, (size_t)VERTS * s.components - 1),
                     RENDERCACHE_ERROR_INVALID_ARGUMENT);
        CHECK(values[0] == rendercache_keytimes_values(kt, 0)[0]);
        rendercache_keytimes_destroy(kt);
        kt = NULL;
    }
    CHECK(last > 2);
    /* cancel, NaN solutions, bad desc */
    s.components = 1;
    d.components = 1;
    s.calls = 0;
    s.fail_at = 3;
    CHECK_EQ_INT(rendercache_keytimes_create(&d, &kt), RENDERCACHE_ERROR_CANCELLED);
    CHECK(kt == NULL);
    s.fail_at = 0;
    d.t1 = 0.0;
    CHECK_EQ_INT(rendercache_keytimes_create(&d, &kt), RENDERCACHE_ERROR_INVALID_ARGUMENT);
    d.t1 = 1.0;
    d.element_count = 0;
    CHECK_EQ_INT(rendercache_keytimes_create(&d, &kt), RENDERCACHE_ERROR_INVALID_ARGUMENT);
    d.element_count = VERTS;
    d.epsilon = NAN;
    CHECK_EQ_INT(rendercache_keytimes_create(&d, &kt), RENDERCACHE_ERROR_INVALID_ARGUMENT);
    CHECK_EQ_INT(rendercache_keytimes_eval(NULL, 0.0, values, sizeof values / sizeof values[0]), RENDERCACHE_ERROR_INVALID_ARGUMENT);
    rendercache_keytimes_destroy(NULL);
}

static int solve_nan(void *user, double t, float *values)
{
    (void)user;
    values[0] = t > 0.5 ? NAN : 1.0f;
    return 0;
}

static void test_key_times_reject_non_finite_solutions(void)
{
    rendercache_keytime_desc d;
    rendercache_keytimes *kt = NULL;
    memset(&d, 0, sizeof d);
    d.element_count = 1;
    d.t1 = 1.0;
    d.quality = 0.5f;
    d.solve = solve_nan;
    CHECK_EQ_INT(rendercache_keytimes_create(&d, &kt), RENDERCACHE_ERROR_INVALID_ARGUMENT);
    CHECK(kt == NULL);
}

/* ---------------------------------------------------------------------
   LRMS
   --------------------------------------------------------------------- */
static void test_lrms_known_answers(void)
{
    float ref[3 * 8], img[3 * 8];
    double e = -1.0;
    int i;
    for (i = 0; i < 24; i++) { ref[i] = 1.0f; img[i] = 1.1f; }
    CHECK_EQ_INT(rendercache_lrms(ref, img, 4, 2, &e), RENDERCACHE_OK);
    CHECK_CLOSE(e, 0.1, 1e-6, 0.0);   /* float inputs: 1e-6 */
    for (i = 0; i < 24; i++) img[i] = 1.0f;
    for (i = 0; i < 4; i++) img[3 * i] = 1.5f;   /* half the pixels: red + 0.5, luminance + 0.1063 */
    CHECK_EQ_INT(rendercache_lrms(ref, img, 4, 2, &e), RENDERCACHE_OK);
    CHECK_CLOSE(e, 0.2126 * 0.5 * sqrt(0.5), 1e-6, 0.0);
    CHECK_EQ_INT(rendercache_lrms(ref, ref, 4, 2, &e), RENDERCACHE_OK);
    CHECK(e == 0.0);
    for (i = 0; i < 24; i++) ref[i] = 0.0f;
    CHECK_EQ_INT(rendercache_lrms(ref, img, 4, 2, &e), RENDERCACHE_ERROR_INVALID_ARGUMENT);   /* no mean to divide by */
    CHECK_EQ_INT(rendercache_lrms(NULL, img, 4, 2, &e), RENDERCACHE_ERROR_INVALID_ARGUMENT);
    CHECK_EQ_INT(rendercache_lrms(img, img, 0, 2, &e), RENDERCACHE_ERROR_INVALID_ARGUMENT);
    img[5] = NAN;
    CHECK_EQ_INT(rendercache_lrms(img, img, 4, 2, &e), RENDERCACHE_ERROR_INVALID_ARGUMENT);
}

/* ---------------------------------------------------------------------
   Save and load
   --------------------------------------------------------------------- */
typedef struct counting { int allocs, frees, fail_after; } counting;

static void *counting_alloc(size_t size, void *user)
{
    counting *c = (counting *)user;
    if (c->fail_after >= 0 && c->allocs >= c->fail_after) return NULL;
    c->allocs++;
    return malloc(size);
}

static void counting_free(void *p, void *user)
{
    ((counting *)user)->frees++;
    free(p);
}

static rendercache_range_image *sample_image(const rendercache_allocator *a)
{
    rendercache_camera cam;
    rendercache_range_image *img = NULL;
    uint32_t p;
    memset(&cam, 0, sizeof cam);
    cam.kind = RENDERCACHE_CAMERA_FISHEYE;
    cam.eye[0] = 1.5f;
    cam.look_at[2] = 4.0f;
    cam.up[1] = 1.0f;
    cam.width = 5;
    cam.height = 4;
    if (rendercache_range_image_create(&cam, a, &img) != RENDERCACHE_OK) return NULL;
    img->time = 12.25;
    for (p = 0; p < 20; p++) {
        img->rgb[3 * p] = 0.1f * (float)p;
        img->rgb[3 * p + 1] = -0.5f;
        img->rgb[3 * p + 2] = 1e3f;
        img->depth[p] = 1.0f + (float)p;
        img->object[p] = p % 5 == 0 ? RENDERCACHE_MISS : p % 7 == 0 ? RENDERCACHE_NO_SAMPLE : p;
    }
    return img;
}

static int failing_write(void *user, const void *bytes, size_t n)
{
    (void)bytes;
    (void)n;
    return --*(int *)user < 0;
}

static void test_save_load_round_trip(void)
{
    rendercache_range_image *img = sample_image(NULL), *back = NULL;
    void *data = NULL;
    size_t size = 0;
    uint32_t p;
    int budget = 5;
    if (!CHECK(img)) return;
    CHECK_EQ_INT(rendercache_range_image_save_to_memory(img, NULL, &data, &size), RENDERCACHE_OK);
    CHECK_EQ_INT(size, 20 + 60 + 20 * 20 + 4);
    CHECK_EQ_INT(rendercache_range_image_load_from_memory(data, size, NULL, &back), RENDERCACHE_OK);
    if (back) {
        CHECK(memcmp(&back->camera, &img->camera, sizeof img->camera) == 0);
        CHECK(back->time == 12.25);
        CHECK(memcmp(back->rgb, img->rgb, 60 * sizeof(float)) == 0);
        CHECK(memcmp(back->object, img->object, 20 * sizeof(uint32_t)) == 0);
        for (p = 0; p < 20; p++)
            CHECK(back->depth[p] == (img->object[p] >= RENDERCACHE_NO_SAMPLE ? RENDERCACHE_FAR_DEPTH : img->depth[p]));
    }
    rendercache_range_image_destroy(back);
    rendercache_free_memory(NULL, data);
    /* a failing write callback */
    CHECK_EQ_INT(rendercache_range_image_save(img, failing_write, &budget), RENDERCACHE_ERROR_IO);
    /* only loadable images are saved */
    img->rgb[7] = NAN;
    CHECK_EQ_INT(rendercache_range_image_save_to_memory(img, NULL, &data, &size), RENDERCACHE_ERROR_INVALID_ARGUMENT);
    img->rgb[7] = 0.0f;
    img->depth[1] = -1.0f;
    CHECK_EQ_INT(rendercache_range_image_save_to_memory(img, NULL, &data, &size), RENDERCACHE_ERROR_INVALID_ARGUMENT);
    CHECK(data == NULL && size == 0);
    rendercache_range_image_destroy(img);
}

static void test_load_is_hostile_proof(void)
{
    rendercache_range_image *img = sample_image(NULL), *back = NULL;
    unsigned char *data = NULL, *copy;
    size_t size = 0, n, i;
    uint64_t state = 12345;
    int r;
    if (!CHECK(img) ||
        !CHECK_EQ_INT(rendercache_range_image_save_to_memory(img, NULL, (void **)&data, &size), RENDERCACHE_OK))
        return;
    copy = (unsigned char *)malloc(size);
    /* every truncation */
    for (n = 0; n < size; n++) {
        r = rendercache_range_image_load_from_memory(data, n, NULL, &back);
        CHECK_MSG(r == RENDERCACHE_ERROR_CORRUPT_DATA, "truncated to %zu bytes: %d", n, r);
        CHECK(back == NULL);
    }
    {   /* a byte after the CRC is left alone: the same object loads */
        unsigned char *longer = test_with_byte_after(data, size);
        void *again = NULL;
        size_t again_size = 0;
        if (CHECK(longer != NULL) && CHECK_EQ_INT(rendercache_range_image_load_from_memory(longer, size + 1, NULL, &back), RENDERCACHE_OK) &&
            CHECK_EQ_INT(rendercache_range_image_save_to_memory(back, NULL, &again, &again_size), RENDERCACHE_OK))
            CHECK(again_size == size && memcmp(again, data, size) == 0);
        rendercache_free_memory(NULL, again);
        rendercache_range_image_destroy(back);
        free(longer);
    }
    /* every byte changed: never accepted (the CRC covers everything; the version field
       reports a version error) */
    for (i = 0; i < size; i++) {
        memcpy(copy, data, size);
        copy[i] ^= 0x5A;
        r = rendercache_range_image_load_from_memory(copy, size, NULL, &back);
        CHECK_MSG(r == RENDERCACHE_ERROR_CORRUPT_DATA || (r == RENDERCACHE_ERROR_VERSION && i >= 8 && i < 12),
                  "byte %zu changed: %d", i, r);
        rendercache_range_image_destroy(back);
        back = NULL;
    }
    /* random multi-byte corruption */
    for (i = 0; i < 2000; i++) {
        int k;
        memcpy(copy, data, size);
        for (k = 0; k < 4; k++) {
            state = state * 6364136223846793005ull + 1442695040888963407ull;
            copy[(state >> 33) % size] = (unsigned char)(state >> 20);
        }
        r = rendercache_range_image_load_from_memory(copy, size, NULL, &back);
        CHECK(r != RENDERCACHE_OK || memcmp(copy, data, size) == 0);
        rendercache_range_image_destroy(back);
        back = NULL;
    }
    /* a header promising a 16384 x 16384 image in a short payload: refused before allocating */
    memcpy(copy, data, size);
    copy[20 + 44] = 0; copy[20 + 45] = 0x40; copy[20 + 46] = 0; copy[20 + 47] = 0;   /* width 16384 */
    copy[20 + 48] = 0; copy[20 + 49] = 0x40; copy[20 + 50] = 0; copy[20 + 51] = 0;   /* height */
    CHECK_EQ_INT(rendercache_range_image_load_from_memory(copy, size, NULL, &back), RENDERCACHE_ERROR_CORRUPT_DATA);
    CHECK_EQ_INT(rendercache_range_image_load_from_memory(NULL, size, NULL, &back), RENDERCACHE_ERROR_INVALID_ARGUMENT);
    free(copy);
    rendercache_free_memory(NULL, data);
    rendercache_range_image_destroy(img);
}

static void test_allocators_balance_and_fail_cleanly(void)
{
    counting c;
    rendercache_allocator a;
    rendercache_range_image *img, *back = NULL;
    void *data = NULL;
    size_t size = 0;
    int k;
    memset(&c, 0, sizeof c);
    c.fail_after = -1;
    a.alloc = counting_alloc;
    a.free = counting_free;
    a.user = &c;
    img = sample_image(&a);
    if (!CHECK(img)) return;
    CHECK_EQ_INT(rendercache_range_image_save_to_memory(img, &a, &data, &size), RENDERCACHE_OK);
    CHECK_EQ_INT(rendercache_range_image_load_from_memory(data, size, &a, &back), RENDERCACHE_OK);
    rendercache_range_image_destroy(back);
    /* every allocation of a load failing in turn: out of memory, nothing leaked */
    for (k = 0; k < 4; k++) {
        int before = c.allocs - c.frees;
        c.fail_after = c.allocs + k;
        back = NULL;
        CHECK_EQ_INT(rendercache_range_image_load_from_memory(data, size, &a, &back), RENDERCACHE_ERROR_OUT_OF_MEMORY);
        CHECK(back == NULL);
        CHECK_EQ_INT(c.allocs - c.frees, before);
    }
    c.fail_after = -1;
    rendercache_free_memory(&a, data);
    rendercache_range_image_destroy(img);
    CHECK_EQ_INT(c.allocs, c.frees);
    a.free = NULL;   /* alloc without free */
    CHECK_EQ_INT(rendercache_range_image_create(NULL, &a, &img), RENDERCACHE_ERROR_INVALID_ARGUMENT);
}

int main(int argc, char **argv)
{
    TEST_INIT(argc, argv);
    RUN(test_fitness_known_answers);
    RUN(test_view_space_subdivision_matches_reference);
    RUN(test_view_space_edge_cases);
    RUN(test_time_subdivision_matches_reference);
    RUN(test_more_views_and_key_times_as_quality_rises);
    RUN(test_key_times_reproduce_the_signal);
    RUN(test_key_times_reject_non_finite_solutions);
    RUN(test_lrms_known_answers);
    RUN(test_save_load_round_trip);
    RUN(test_load_is_hostile_proof);
    RUN(test_allocators_balance_and_fail_cleanly);
    return test_finish();
}
