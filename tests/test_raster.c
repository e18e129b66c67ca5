/* Unit tests of examples/common/camera.h and raster.h: exact coverage (each
   pixel centre inside a mesh covered by exactly one triangle, also where
   triangles are clipped by the near plane), depth order, perspective-correct
   barycentrics, parallel = serial, and meshes drawn in one pass = drawn
   one by one. */
#include "examples/common/raster.h"
#include "tests/test.h"

/* A w x h grid of quads in the plane y = height, from (x0,z0) to (x1,z1),
   each quad split along a diagonal that alternates, with optional jitter of
   interior vertices. */
typedef struct grid { float *pos; uint32_t *idx; uint32_t tris, verts; } grid;

static grid make_grid(int w, int h, float x0, float z0, float x1, float z1, float height, float jitter)
{
    grid g;
    int i, j;
    uint64_t state = 99;
    g.verts = (uint32_t)((w + 1) * (h + 1));
    g.tris = (uint32_t)(2 * w * h);
    g.pos = (float *)malloc(sizeof(float) * 3 * g.verts);
    g.idx = (uint32_t *)malloc(sizeof(uint32_t) * 3 * g.tris);
    for (j = 0; j <= h; j++)
        for (i = 0; i <= w; i++) {
            float *p = g.pos + 3 * (j * (w + 1) + i);
            float jx = 0, jz = 0;
            if (i > 0 && i < w && j > 0 && j < h) {
                state = state * 6364136223846793005ull + 1442695040888963407ull;
                jx = jitter * ((float)((state >> 40) & 1023) / 1023.0f - 0.5f);
                jz = jitter * ((float)((state >> 20) & 1023) / 1023.0f - 0.5f);
            }
            p[0] = x0 + (x1 - x0) * ((float)i + jx) / (float)w;
            p[1] = height;
            p[2] = z0 + (z1 - z0) * ((float)j + jz) / (float)h;
        }
    for (j = 0; j < h; j++)
        for (i = 0; i < w; i++) {
            uint32_t a = (uint32_t)(j * (w + 1) + i), b = a + 1, c = a + (uint32_t)(w + 1), d = c + 1;
            uint32_t *t = g.idx + 6 * (j * w + i);
            if ((i + j) & 1) { t[0] = a; t[1] = b; t[2] = d; t[3] = a; t[4] = d; t[5] = c; }
            else { t[0] = a; t[1] = b; t[2] = c; t[3] = b; t[4] = d; t[5] = c; }
        }
    return g;
}

static void free_grid(grid *g) { free(g->pos); free(g->idx); }

/* Counts pixels by coverage: how many have 0, 1 and more than 1. */
static void coverage_histogram(const ex_raster *r, int *zero, int *one, int *more)
{
    int p;
    *zero = *one = *more = 0;
    for (p = 0; p < r->width * r->height; p++) {
        if (r->coverage[p] == 0) (*zero)++;
        else if (r->coverage[p] == 1) (*one)++;
        else (*more)++;
    }
}

/* A jittered grid filling the whole view: every pixel exactly once. */
static void test_mesh_covers_every_pixel_once(void)
{
    float eye[3] = { 0, 5, 0 }, target[3] = { 0, 0, 0.001f }, up[3] = { 0, 0, 1 };
    ex_camera c = ex_camera_look_at(eye, target, up, 70.0f, 97, 61);
    ex_raster r;
    grid g = make_grid(37, 23, -20, -20, 20, 20, 0, 0.8f);
    int zero, one, more;
    if (!CHECK(ex_raster_init(&r, 97, 61) == 0)) return;
    ex_raster_clear(&r);
    CHECK(ex_raster_count(&r, &c, g.pos, g.idx, g.tris) == 0);
    coverage_histogram(&r, &zero, &one, &more);
    CHECK_EQ_INT(zero, 0);
    CHECK_EQ_INT(more, 0);
    CHECK_EQ_INT(one, 97 * 61);
    ex_raster_free(&r);
    free_grid(&g);
}

/* Vertices exactly on pixel centres and pixel edges (an unjittered grid seen
   straight on with one grid step per pixel): the tie rule decides alone. */
static void test_ties_on_pixel_centres(void)
{
    /* a 64x64 image of a plane at distance 1 with vfov 90: the visible square
       spans [-1,1], so 0.5/32 per half pixel */
    float eye[3] = { 0, 1, 0 }, target[3] = { 0, 0, 0 }, up[3] = { 0, 0, -1 };
    ex_camera c = ex_camera_look_at(eye, target, up, 90.0f, 64, 64);
    ex_raster r;
    grid g = make_grid(128, 128, -2, -2, 2, 2, 0, 0.0f); /* steps of 1/32: corners on centres and edges */
    int zero, one, more;
    if (!CHECK(ex_raster_init(&r, 64, 64) == 0)) return;
    ex_raster_clear(&r);
    CHECK(ex_raster_count(&r, &c, g.pos, g.idx, g.tris) == 0);
    coverage_histogram(&r, &zero, &one, &more);
    CHECK_EQ_INT(zero, 0);
    CHECK_EQ_INT(more, 0);
    ex_raster_free(&r);
    free_grid(&g);
}

/* A floor that extends behind the camera: triangles cut by the near plane
   and the guard band still cover each pixel below the horizon once. */
static void test_clipped_floor_covers_once(void)
{
    float eye[3] = { 0.3f, 1.0f, 0.2f }, target[3] = { 0.5f, 0.6f, 3.0f }, up[3] = { 0, 1, 0 };
    ex_camera c = ex_camera_look_at(eye, target, up, 75.0f, 80, 60);
    ex_raster r;
    grid g = make_grid(31, 29, -50, -50, 50, 50, 0, 0.7f);
    int zero, one, more, x, y, mismatches = 0;
    if (!CHECK(ex_raster_init(&r, 80, 60) == 0)) return;
    ex_raster_clear(&r);
    CHECK(ex_raster_count(&r, &c, g.pos, g.idx, g.tris) == 0);
    coverage_histogram(&r, &zero, &one, &more);
    CHECK_EQ_INT(more, 0);
    CHECK(one > 0 && zero > 0);
    /* covered exactly where the pixel ray goes down and meets the floor inside the grid */
    for (y = 0; y < 60; y++)
        for (x = 0; x < 80; x++) {
            float d[3];
            int hits_floor;
            ex_camera_ray(&c, (float)x + 0.5f, (float)y + 0.5f, d);
            hits_floor = d[1] < 0 && fabsf(eye[0] - eye[1] / d[1] * d[0]) < 49.0f &&
                         fabsf(eye[2] - eye[1] / d[1] * d[2]) < 49.0f;
            if (d[1] < 0 && !hits_floor) continue; /* near the grid border: jitter decides */
            mismatches += hits_floor != (r.coverage[y * 80 + x] == 1);
        }
    CHECK_EQ_INT(mismatches, 0);
    ex_raster_free(&r);
    free_grid(&g);
}

/* The reference for one input triangle: transformed, clipped with nothing
   counted off screen, snapped as the raster snaps (ex__raster_emit), and
   each pixel centre in the image tested against the three edge functions
   in 64-bit integers with the tie rule: the coverage a per-pixel
   rasterizer gives, to compare with the span walk and the early rejection. */
static void reference_count(ex_raster *r, const ex_camera *c, const float *pos, const uint32_t *idx, uint32_t tri,
                            uint32_t *coverage)
{
    float aspect = (float)r->width / (float)r->height;
    ex__clip_vertex poly[16];
    ex__raster_batch batch;
    uint32_t i;
    int k, n, x, y;
    memset(&batch, 0, sizeof batch);
    if (ex__raster_reserve(&batch, 6) != 0) return;
    for (k = 0; k < 3; k++) {
        const float *p = pos + 3 * (size_t)idx[3 * tri + (uint32_t)k];
        float d[3] = { p[0] - c->eye[0], p[1] - c->eye[1], p[2] - c->eye[2] };
        poly[k].p[0] = ex__dot(d, c->right);
        poly[k].p[1] = ex__dot(d, c->up);
        poly[k].p[2] = ex__dot(d, c->forward);
        poly[k].u = poly[k].v = 0.0f;
    }
    r->camera = c;
    n = ex__clip_polygon(poly, 3, r->near_plane, c->tan_half * aspect, c->tan_half);
    for (k = 1; k + 1 < n; k++) ex__raster_emit(r, &batch, &poly[0], &poly[k], &poly[k + 1], tri);
    for (i = 0; i < batch.count; i++) {
        const ex_raster_tri *t = &batch.tris[i];
        for (y = 0; y < r->height; y++)
            for (x = 0; x < r->width; x++) {
                int64_t px = (int64_t)x * EX_RASTER_SUBPIXEL + EX_RASTER_SUBPIXEL / 2;
                int64_t py = (int64_t)y * EX_RASTER_SUBPIXEL + EX_RASTER_SUBPIXEL / 2;
                int inside = 1;
                for (k = 0; k < 3; k++) {
                    int a = (k + 1) % 3, b = (k + 2) % 3;
                    int64_t dx = t->x[b] - t->x[a], dy = t->y[b] - t->y[a];
                    inside &= dx * (py - t->y[a]) - dy * (px - t->x[a]) + ex__edge_owns_ties(dx, dy) > 0;
                }
                coverage[y * r->width + x] += (uint32_t)inside;
            }
    }
    free(batch.tris);
}

/* Random triangles of every kind (slivers, large ones crossing the guard
   band and the near plane, ones just beside the screen within and beyond
   its two-pixel margin, ones behind the eye) cover exactly the pixels the
   per-pixel reference covers: the rows' spans, stepped from row to row,
   and the rejection of triangles beside the screen drop no pixel and add
   none. */
static void test_spans_equal_pixel_tests(void)
{
    const int W = 61, H = 47;
    float eye[3] = { 0.5f, 1.0f, -2.0f }, target[3] = { 0.2f, 0.8f, 3.0f }, up[3] = { 0, 1, 0 };
    ex_camera c = ex_camera_look_at(eye, target, up, 65.0f, W, H);
    ex_raster r;
    float *pos = (float *)malloc(sizeof(float) * 9 * 4000);
    uint32_t *idx = (uint32_t *)malloc(sizeof(uint32_t) * 3 * 4000), *ref = (uint32_t *)calloc((size_t)(W * H), sizeof(uint32_t));
    uint64_t state = 12345;
    uint32_t t, tris = 4000;
    int p, mismatches = 0, covered = 0;
    if (!CHECK(pos && idx && ref && ex_raster_init(&r, W, H) == 0)) return;
    for (t = 0; t < tris; t++) {
        int kind = (int)(t % 5), k;
        float cx = 0, cy = 0;
        for (k = 0; k < 3; k++) {
            float px, py, depth, d[3], u[4];
            int j;
            for (j = 0; j < 4; j++) {
                state = state * 6364136223846793005ull + 1442695040888963407ull;
                u[j] = (float)(state >> 40) / (float)(1ull << 24);
            }
            if (k == 0) { cx = (u[0] * 1.6f - 0.3f) * (float)W; cy = (u[1] * 1.6f - 0.3f) * (float)H; }
            if (kind == 0) { px = cx + 6.0f * u[2]; py = cy + 6.0f * u[3]; depth = 2.0f + u[0]; }              /* small */
            else if (kind == 1) { px = cx + 0.3f * u[2]; py = cy + 40.0f * u[3]; depth = 1.0f + 9.0f * u[1]; } /* sliver */
            else if (kind == 2) { px = (u[2] * 40.0f - 20.0f) * (float)W; py = (u[3] * 40.0f - 20.0f) * (float)H; depth = 50.0f * u[0] - 5.0f; }
            else if (kind == 3) { px = (float)W + 0.05f + 3.5f * u[2]; py = cy + 8.0f * u[3]; depth = 1.0f + u[1]; } /* beside, right */
            else { px = cx + 8.0f * u[2]; py = -0.05f - 3.5f * u[3]; depth = 1.0f + u[1]; }                       /* above */
            ex_camera_ray(&c, px, py, d);
            for (j = 0; j < 3; j++) pos[9 * t + 3 * (uint32_t)k + (uint32_t)j] = eye[j] + depth * d[j];
            idx[3 * t + (uint32_t)k] = 3 * t + (uint32_t)k;
        }
        reference_count(&r, &c, pos, idx, t, ref);
    }
    ex_raster_clear(&r);
    CHECK(ex_raster_count(&r, &c, pos, idx, tris) == 0);
    for (p = 0; p < W * H; p++) {
        mismatches += r.coverage[p] != ref[p];
        covered += ref[p] > 0;
    }
    CHECK_EQ_INT(mismatches, 0);
    CHECK(covered > W * H / 2);
    ex_raster_free(&r);
    free(pos);
    free(idx);
    free(ref);
}

/* Barycentrics reconstruct a point that projects back onto the pixel centre,
   and the depth buffer holds its view depth. */
static void test_perspective_correct_barycentrics(void)
{
    static const float pos[] = { -1, 0, 1, 3, 0.5f, 6, -2, 2, 9 };
    static const uint32_t idx[] = { 0, 1, 2 };
    float eye[3] = { 0, 0.5f, -1 }, target[3] = { 0, 0.7f, 5 }, up[3] = { 0, 1, 0 };
    ex_camera c = ex_camera_look_at(eye, target, up, 60.0f, 50, 40);
    ex_raster r;
    int p, covered = 0;
    float worst = 0, worst_depth = 0;
    if (!CHECK(ex_raster_init(&r, 50, 40) == 0)) return;
    ex_raster_clear(&r);
    CHECK(ex_raster_draw(&r, &c, pos, idx, 1, 7) == 0);
    for (p = 0; p < 50 * 40; p++) {
        float u, v, q[3], px, py, depth;
        int k;
        if (r.id[p] == EX_RASTER_EMPTY) continue;
        CHECK_EQ_INT(r.id[p], 7);
        covered++;
        u = r.bary[2 * p];
        v = r.bary[2 * p + 1];
        for (k = 0; k < 3; k++) q[k] = (1 - u - v) * pos[k] + u * pos[3 + k] + v * pos[6 + k];
        CHECK(ex_camera_project(&c, q, &px, &py, &depth));
        worst = fmaxf(worst, fmaxf(fabsf(px - (float)(p % 50) - 0.5f), fabsf(py - (float)(p / 50) - 0.5f)));
        worst_depth = fmaxf(worst_depth, fabsf(depth - r.depth[p]) / depth);
    }
    CHECK(covered > 100);
    /* vertices snap to 1/256 pixel, moving them up to 0.00195 pixels; float
       interpolation adds a little: 0.003 pixels */
    CHECK_MSG(worst < 3e-3f, "reprojection error %g pixels", worst);
    CHECK_MSG(worst_depth < 1e-5f, "relative depth error %g", worst_depth);
    ex_raster_free(&r);
}

static void test_depth_order(void)
{
    /* two full-screen quads; the nearer one wins whatever the draw order */
    static const float near_quad[] = { -9, -9, 2, 9, -9, 2, 9, 9, 2, -9, 9, 2 };
    static const float far_quad[] = { -9, -9, 4, 9, -9, 4, 9, 9, 4, -9, 9, 4 };
    static const uint32_t idx[] = { 0, 1, 2, 0, 2, 3 };
    float eye[3] = { 0, 0, 0 }, target[3] = { 0, 0, 1 }, up[3] = { 0, 1, 0 };
    ex_camera c = ex_camera_look_at(eye, target, up, 60.0f, 32, 32);
    ex_raster r;
    int p, wrong = 0, pass;
    if (!CHECK(ex_raster_init(&r, 32, 32) == 0)) return;
    for (pass = 0; pass < 2; pass++) {
        ex_raster_clear(&r);
        if (pass == 0) {
            ex_raster_draw(&r, &c, far_quad, idx, 2, 100);
            ex_raster_draw(&r, &c, near_quad, idx, 2, 200);
        } else {
            ex_raster_draw(&r, &c, near_quad, idx, 2, 200);
            ex_raster_draw(&r, &c, far_quad, idx, 2, 100);
        }
        for (p = 0; p < 32 * 32; p++) wrong += r.id[p] < 200 || r.id[p] > 201 || fabsf(r.depth[p] - 2) > 1e-5f;
    }
    CHECK_EQ_INT(wrong, 0);
    ex_raster_free(&r);
}

static void test_parallel_equals_serial(void)
{
    float eye[3] = { 0.3f, 1.0f, 0.2f }, target[3] = { 0.5f, 0.6f, 3.0f }, up[3] = { 0, 1, 0 };
    ex_camera c = ex_camera_look_at(eye, target, up, 75.0f, 200, 150);
    ex_raster a, b;
    grid g = make_grid(40, 40, -10, -10, 10, 10, 0, 0.9f);
    ex_pool *pool = ex_pool_create(2);
    size_t n = 200 * 150;
    if (!CHECK(ex_raster_init(&a, 200, 150) == 0 && ex_raster_init(&b, 200, 150) == 0)) return;
    ex_raster_clear(&a);
    ex_raster_clear(&b);
    b.pool = pool;
    ex_raster_draw(&a, &c, g.pos, g.idx, g.tris, 0);
    ex_raster_draw(&b, &c, g.pos, g.idx, g.tris, 0);
    CHECK(memcmp(a.id, b.id, n * sizeof(uint32_t)) == 0);
    CHECK(memcmp(a.bary, b.bary, 2 * n * sizeof(float)) == 0);
    CHECK(memcmp(a.depth, b.depth, n * sizeof(float)) == 0);
    ex_raster_free(&a);
    ex_raster_free(&b);
    ex_pool_destroy(pool);
    free_grid(&g);
}

/* What tile_done saw, gathered into whole frames. */
typedef struct tiles_seen { int width; float *depth, *bary; uint32_t *id; int tiles; } tiles_seen;

static void gather_tile(void *user, const ex_raster_tile *t)
{
    tiles_seen *seen = (tiles_seen *)user;
    int x, y;
    for (y = t->y0; y < t->y1; y++)
        for (x = t->x0; x < t->x1; x++) {
            size_t p = (size_t)y * (size_t)seen->width + (size_t)x;
            int q = (y - t->y0) * EX_RASTER_TILE + (x - t->x0);
            seen->depth[p] = t->depth[q];
            seen->id[p] = t->id[q];
            seen->bary[2 * p] = t->bary[2 * q];
            seen->bary[2 * p + 1] = t->bary[2 * q + 1];
        }
    seen->tiles++;   /* serial: the raster below has no pool */
}

/* Drawing meshes in one pass gives the frames of drawing them one after the
   other, bit for bit: a floor, a raised patch over part of it (overdraw in
   both orders) and the floor again, whose exact depth ties the first copy
   keeps (ids below 100000 everywhere). The tiles tile_done sees are those
   frames, also when the raster leaves its depth and barycentric buffers
   unwritten. */
static void test_draw_meshes_equals_draws(void)
{
    float eye[3] = { 0.2f, 3.0f, -4.0f }, target[3] = { 0.0f, 0.0f, 1.0f }, up[3] = { 0, 1, 0 };
    const int W = 150, H = 110;
    ex_camera c = ex_camera_look_at(eye, target, up, 70.0f, W, H);
    grid floor = make_grid(30, 30, -6, -3, 6, 9, 0, 0.8f), patch = make_grid(9, 7, -2, 0, 2, 4, 0.7f, 0.6f);
    ex_raster_mesh m[3];
    ex_raster a, b;
    tiles_seen seen;
    size_t n = (size_t)W * (size_t)H, p, far = 0, patch_pixels = 0;
    int k;
    seen.width = W;
    seen.tiles = 0;
    seen.depth = (float *)malloc(n * sizeof(float));
    seen.bary = (float *)malloc(2 * n * sizeof(float));
    seen.id = (uint32_t *)malloc(n * sizeof(uint32_t));
    if (!CHECK(seen.depth && seen.bary && seen.id && ex_raster_init(&a, W, H) == 0 && ex_raster_init(&b, W, H) == 0))
        return;
    m[0].positions = floor.pos; m[0].indices = floor.idx; m[0].tri_count = floor.tris; m[0].id_base = 0;
    m[0].vertex_count = floor.verts;
    m[1].positions = patch.pos; m[1].indices = patch.idx; m[1].tri_count = patch.tris; m[1].id_base = 50000;
    m[1].vertex_count = 0;   /* found from the indices */
    m[2] = m[0];
    m[2].id_base = 100000;
    ex_raster_clear(&a);
    for (k = 0; k < 3; k++) CHECK(ex_raster_draw(&a, &c, m[k].positions, m[k].indices, m[k].tri_count, m[k].id_base) == 0);
    for (k = 0; k < 2; k++) {
        memset(seen.id, 0xAB, n * sizeof(uint32_t));
        ex_raster_clear_deferred(&b);
        b.skip = k ? EX_RASTER_SKIP_DEPTH | EX_RASTER_SKIP_BARY : 0;
        b.tile_done = gather_tile;
        b.tile_user = &seen;
        seen.tiles = 0;
        CHECK(ex_raster_draw_meshes(&b, &c, m, 3) == 0);
        CHECK(seen.tiles == b.tiles_x * b.tiles_y);
        CHECK(memcmp(a.id, b.id, n * sizeof(uint32_t)) == 0);
        if (!k) CHECK(memcmp(a.bary, b.bary, 2 * n * sizeof(float)) == 0 && memcmp(a.depth, b.depth, n * sizeof(float)) == 0);
        CHECK(memcmp(a.id, seen.id, n * sizeof(uint32_t)) == 0);
        CHECK(memcmp(a.bary, seen.bary, 2 * n * sizeof(float)) == 0);
        CHECK(memcmp(a.depth, seen.depth, n * sizeof(float)) == 0);
    }
    for (p = 0; p < n; p++) {
        far += a.id[p] != EX_RASTER_EMPTY && a.id[p] >= 100000;
        patch_pixels += a.id[p] >= 50000 && a.id[p] < 100000;
    }
    CHECK(far == 0);
    CHECK(patch_pixels > n / 20);   /* the patch is in view, over the floor */
    ex_raster_free(&a);
    ex_raster_free(&b);
    free(seen.depth);
    free(seen.bary);
    free(seen.id);
    free_grid(&floor);
    free_grid(&patch);
}

static void test_camera_round_trip(void)
{
    float eye[3] = { 1, 2, 3 }, target[3] = { -2, 0.5f, 7 }, up[3] = { 0, 1, 0 };
    ex_camera cams[2];
    int k, i;
    cams[0] = ex_camera_look_at(eye, target, up, 50.0f, 120, 80);
    cams[1] = ex_camera_fisheye(eye, target, up, 100, 100);
    for (k = 0; k < 2; k++)
        for (i = 0; i < 200; i++) {
            float px = 5.0f + (float)((i * 37) % 90), py = 5.0f + (float)((i * 53) % 70), d[3], q[3], x, y, depth;
            if (!ex_camera_ray(&cams[k], px, py, d)) continue;
            q[0] = eye[0] + 3 * d[0]; q[1] = eye[1] + 3 * d[1]; q[2] = eye[2] + 3 * d[2];
            CHECK(ex_camera_project(&cams[k], q, &x, &y, &depth));
            CHECK_CLOSE(x, px, 0, 1e-3);
            CHECK_CLOSE(y, py, 0, 1e-3);
        }
    /* a perspective camera does not project points behind it */
    {
        float behind[3] = { 4, 3.5f, -1 }, x, y, depth;
        CHECK(!ex_camera_project(&cams[0], behind, &x, &y, &depth));
    }
}

static void test_bad_arguments(void)
{
    ex_raster r;
    float eye[3] = { 0, 0, 0 }, target[3] = { 0, 0, 1 }, up[3] = { 0, 1, 0 };
    ex_camera c = ex_camera_look_at(eye, target, up, 60.0f, 16, 16), wrong = c;
    CHECK(ex_raster_init(&r, 0, 10) != 0);
    CHECK(ex_raster_init(&r, 16, 16) == 0);
    wrong.width = 17;
    CHECK(ex_raster_draw(&r, &wrong, NULL, NULL, 1, 0) != 0);
    wrong = ex_camera_fisheye(eye, target, up, 16, 16);
    CHECK(ex_raster_draw(&r, &wrong, NULL, NULL, 1, 0) != 0);
    CHECK(ex_raster_draw(&r, &c, NULL, NULL, 1, 0) != 0);
    CHECK(ex_raster_draw(&r, &c, NULL, NULL, 0, 0) == 0);
    {   /* an index past the vertex count given */
        static const float pos[] = { -1, -1, 2, 1, -1, 2, 0, 1, 2 };
        static const uint32_t idx[] = { 0, 1, 2 };
        ex_raster_mesh m;
        m.positions = pos; m.indices = idx; m.tri_count = 1; m.id_base = 0; m.vertex_count = 2;
        CHECK(ex_raster_draw_meshes(&r, &c, &m, 1) != 0);
        m.vertex_count = 3;
        CHECK(ex_raster_draw_meshes(&r, &c, &m, 1) == 0);
    }
    ex_raster_free(&r);
}

int main(int argc, char **argv)
{
    TEST_INIT(argc, argv);
    RUN(test_mesh_covers_every_pixel_once);
    RUN(test_ties_on_pixel_centres);
    RUN(test_clipped_floor_covers_once);
    RUN(test_spans_equal_pixel_tests);
    RUN(test_perspective_correct_barycentrics);
    RUN(test_depth_order);
    RUN(test_parallel_equals_serial);
    RUN(test_draw_meshes_equals_draws);
    RUN(test_camera_round_trip);
    RUN(test_bad_arguments);
    return test_finish();
}
