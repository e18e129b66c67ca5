/* The built-in BVH of irrvol.h, lightvec.h and radinterp.h (one code, three
   copies, each tested): on every scene the SIMD and the scalar kernels find the
   same hits bit for bit on 100,000 rays, any-hit answers agree with the
   closest hit, and the closest hit equals a brute-force search over every
   triangle. Scenes: the office with the bunny, a lattice of cubes (shared
   edges, rays along the axes and through vertices), a soup of random
   triangles with coincident copies, the cubes at scale 2^-40, a chain of
   triangles that drives the build past its depth cap, a flat pile of equal
   triangles, and the degenerate ones: no triangle, only zero-area triangles
   (an empty tree), a few triangles (a root leaf). Then the empty tree
   through each header's public functions (issue 17: the empty tree was
   walked as an inner node).
   The program of tests/test_bvh.c; tests/test_bvh_scalar.c compiles it with
   the SIMD kernels off. */
#define IRRVOL_IMPLEMENTATION
#include "irrvol.h"
#define LIGHTVEC_IMPLEMENTATION
#include "lightvec.h"
#define RADINTERP_IMPLEMENTATION
#include "radinterp.h"
#include "tests/test.h"
#include "examples/common/obj.h"

/* ---- scenes -------------------------------------------------------------- */

typedef struct bvh_scene {
    const char *name;
    float *positions;
    uint32_t *indices;
    uint32_t vertex_count, tri_count, degenerate_count;
    float lo[3], hi[3];   /* ray origins are drawn from this box */
    int expect_hits;
} bvh_scene;

static uint64_t rng_state;
static float frand(void)   /* uniform [0, 1) */
{
    rng_state = rng_state * 6364136223846793005ull + 1442695040888963407ull;
    return (float)(rng_state >> 40) * (1.0f / 16777216.0f);
}
static uint32_t irand(uint32_t n) { return (uint32_t)(frand() * (float)n) % n; }

static void scene_alloc(bvh_scene *s, const char *name, uint32_t vertices, uint32_t tris)
{
    memset(s, 0, sizeof *s);
    s->name = name;
    s->vertex_count = vertices;
    s->tri_count = tris;
    s->positions = (float *)malloc(3 * sizeof(float) * (vertices ? vertices : 1));
    s->indices = (uint32_t *)malloc(3 * sizeof(uint32_t) * (tris ? tris : 1));
    s->expect_hits = 1;
}

static void scene_free(bvh_scene *s)
{
    free(s->positions);
    free(s->indices);
}

static void scene_bounds(bvh_scene *s)
{
    uint32_t i;
    int k;
    for (k = 0; k < 3; k++) { s->lo[k] = FLT_MAX; s->hi[k] = -FLT_MAX; }
    for (i = 0; i < s->vertex_count; i++)
        for (k = 0; k < 3; k++) {
            if (s->positions[3 * i + (uint32_t)k] < s->lo[k]) s->lo[k] = s->positions[3 * i + (uint32_t)k];
            if (s->positions[3 * i + (uint32_t)k] > s->hi[k]) s->hi[k] = s->positions[3 * i + (uint32_t)k];
        }
    if (!s->vertex_count) for (k = 0; k < 3; k++) { s->lo[k] = -1.0f; s->hi[k] = 1.0f; }
}

static void set_tri(bvh_scene *s, uint32_t t, uint32_t a, uint32_t b, uint32_t c)
{
    s->indices[3 * t] = a;
    s->indices[3 * t + 1] = b;
    s->indices[3 * t + 2] = c;
}

static int scene_office(bvh_scene *s)
{
    obj_scene office, bunny;
    char err[256];
    float lo[3], hi[3], scale;
    uint32_t i;
    if (obj_load("examples/data/office.obj", &office, err, sizeof err) != 0) { fprintf(stderr, "%s\n", err); return -1; }
    if (obj_load("examples/data/bunny.obj", &bunny, err, sizeof err) != 0) { fprintf(stderr, "%s\n", err); obj_free(&office); return -1; }
    scene_alloc(s, "office + bunny", office.vertex_count + bunny.vertex_count, office.tri_count + bunny.tri_count);
    memcpy(s->positions, office.positions, 3 * sizeof(float) * office.vertex_count);
    memcpy(s->indices, office.tri_indices, 3 * sizeof(uint32_t) * office.tri_count);
    obj_bounds(&bunny, lo, hi);
    scale = 0.3f / (hi[1] - lo[1]);
    for (i = 0; i < bunny.vertex_count; i++) {
        const float *p = bunny.positions + 3 * i;
        float *q = s->positions + 3 * (office.vertex_count + i);
        q[0] = 2.5f + scale * (p[0] - 0.5f * (lo[0] + hi[0]));
        q[1] = scale * (p[1] - lo[1]);
        q[2] = 2.0f + scale * (p[2] - 0.5f * (lo[2] + hi[2]));
    }
    for (i = 0; i < 3 * bunny.tri_count; i++) s->indices[3 * office.tri_count + i] = bunny.tri_indices[i] + office.vertex_count;
    obj_free(&office);
    obj_free(&bunny);
    scene_bounds(s);
    return 0;
}

/* n^3 unit cubes on a lattice of pitch 2, 12 triangles each, scaled. */
static void scene_cubes(bvh_scene *s, const char *name, uint32_t n, float scale)
{
    static const float corner[8][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
    static const uint32_t face[12][3] = {{0, 2, 1}, {0, 3, 2}, {4, 5, 6}, {4, 6, 7}, {0, 1, 5}, {0, 5, 4},
                                         {3, 6, 2}, {3, 7, 6}, {0, 4, 7}, {0, 7, 3}, {1, 2, 6}, {1, 6, 5}};
    uint32_t c, v, f;
    scene_alloc(s, name, 8 * n * n * n, 12 * n * n * n);
    for (c = 0; c < n * n * n; c++) {
        float base[3];
        base[0] = 2.0f * (float)(c % n);
        base[1] = 2.0f * (float)(c / n % n);
        base[2] = 2.0f * (float)(c / n / n);
        for (v = 0; v < 8; v++) {
            int k;
            for (k = 0; k < 3; k++) s->positions[3 * (8 * c + v) + (uint32_t)k] = scale * (base[k] + corner[v][k]);
        }
        for (f = 0; f < 12; f++) set_tri(s, 12 * c + f, 8 * c + face[f][0], 8 * c + face[f][1], 8 * c + face[f][2]);
    }
    scene_bounds(s);
}

/* Random triangles of sizes from 1 mm to 3 m in a 10 m box; every tenth is
   repeated with the opposite winding (two triangles at every distance). */
static void scene_soup(bvh_scene *s)
{
    uint32_t t, n = 3000;
    scene_alloc(s, "random soup", 3 * n, n);
    rng_state = 7;
    for (t = 0; t < n; t++) {
        float *p = s->positions + 9 * t;
        if (t % 10 == 9) {
            memcpy(p, p - 9, 3 * sizeof(float));
            memcpy(p + 3, p - 3, 3 * sizeof(float));
            memcpy(p + 6, p - 6, 3 * sizeof(float));
        } else {
            float size = 0.001f * powf(3000.0f, frand());
            int k, v;
            for (k = 0; k < 3; k++) p[k] = 10.0f * frand();
            for (v = 1; v < 3; v++)
                for (k = 0; k < 3; k++) p[3 * v + k] = p[k] + size * (2.0f * frand() - 1.0f);
        }
        set_tri(s, t, 3 * t, 3 * t + 1, 3 * t + 2);
    }
    scene_bounds(s);
}

/* 400 triangles at x = 1.1^-i, each smaller than the last: every split
   cuts a few of the largest off (one block: the SAH), so the binary tree
   grows about 100 levels deep, past the build's depth cap (60), where it
   halves by count. */
static void scene_chain(bvh_scene *s)
{
    uint32_t t, n = 400;
    scene_alloc(s, "chain past the depth cap", 3 * n, n);
    for (t = 0; t < n; t++) {
        float x = powf(1.1f, -(float)t), h = 0.5f * x;
        float *p = s->positions + 9 * t;
        p[0] = x; p[1] = 0.0f; p[2] = 0.0f;
        p[3] = x; p[4] = h; p[5] = 0.0f;
        p[6] = x; p[7] = 0.0f; p[8] = h;
        set_tri(s, t, 3 * t, 3 * t + 1, 3 * t + 2);
    }
    scene_bounds(s);
}

/* 200 copies of one triangle in the plane z = 0: no axis can split the
   centroids, the build halves by count; every hit is a tie. */
static void scene_pile(bvh_scene *s)
{
    uint32_t t, n = 200;
    scene_alloc(s, "pile of equal triangles", 3, n);
    s->positions[0] = 0.0f; s->positions[1] = 0.0f; s->positions[2] = 0.0f;
    s->positions[3] = 1.0f; s->positions[4] = 0.0f; s->positions[5] = 0.0f;
    s->positions[6] = 0.0f; s->positions[7] = 1.0f; s->positions[8] = 0.0f;
    for (t = 0; t < n; t++) set_tri(s, t, 0, 1, 2);
    scene_bounds(s);
    s->lo[2] = -1.0f;
    s->hi[2] = 1.0f;
}

/* Zero-area triangles only (repeated vertices, collinear points, the same
   index thrice), plus `valid` real ones. */
static void scene_degenerate(bvh_scene *s, const char *name, uint32_t valid)
{
    uint32_t t, n = 500;
    scene_alloc(s, name, 3 * n, n);
    for (t = 0; t < n; t++) {
        float *p = s->positions + 9 * t;
        float a = (float)t;   /* integers: the collinear points are exact */
        p[0] = a; p[1] = 1.0f; p[2] = 2.0f;
        p[3] = a + 1.0f; p[4] = 2.0f; p[5] = 3.0f;
        p[6] = a + 2.0f; p[7] = 3.0f; p[8] = 4.0f;   /* collinear */
        if (t % 3 == 1) memcpy(p + 3, p, 3 * sizeof(float));
        if (t % 3 == 2) set_tri(s, t, 3 * t, 3 * t, 3 * t);
        else set_tri(s, t, 3 * t, 3 * t + 1, 3 * t + 2);
        if (t < valid) {
            p[3] = a + 1.0f; p[4] = 2.0f; p[5] = 3.0f;
            p[6] = a; p[7] = 3.0f; p[8] = 2.0f;
            set_tri(s, t, 3 * t, 3 * t + 1, 3 * t + 2);
        }
    }
    s->degenerate_count = n - valid;
    s->expect_hits = valid > 0;
    scene_bounds(s);
}

/* Ray i of a scene: five kinds in turn. Random directions; through a random
   vertex (edge functions exactly zero); along an axis or with zero
   components; from a point on a triangle (self hits at t ~ 0); toward a
   vertex inside the coordinate plane through it (a zero component, and the
   ray runs in the face plane of every box the vertex bounds). */
static void make_ray(const bvh_scene *s, uint32_t i, float o[3], float d[3])
{
    int k;
    if (i == 0) rng_state = 0x2545F4914F6CDD1Dull;
    for (k = 0; k < 3; k++) {
        float pad = 0.1f * (s->hi[k] - s->lo[k]);
        o[k] = s->lo[k] - pad + frand() * (s->hi[k] - s->lo[k] + 2.0f * pad);
    }
    switch (i % 5) {
    case 0: default: {
        float z = 2.0f * frand() - 1.0f, phi = 6.2831853f * frand(), q = sqrtf(1.0f - z * z);
        d[0] = q * cosf(phi); d[1] = q * sinf(phi); d[2] = z;
        break;
    }
    case 1:
        if (s->vertex_count) {
            const float *v = s->positions + 3 * irand(s->vertex_count);
            for (k = 0; k < 3; k++) d[k] = v[k] - o[k];
        } else {
            d[0] = 1.0f; d[1] = d[2] = 0.0f;
        }
        break;
    case 2: {
        uint32_t axis = irand(3), other = (axis + 1 + irand(2)) % 3;
        d[0] = d[1] = d[2] = 0.0f;
        d[axis] = frand() < 0.5f ? -1.0f : 1.0f;
        if (frand() < 0.5f) d[other] = 2.0f * frand() - 1.0f;   /* one zero component */
        break;
    }
    case 3:
        if (s->tri_count) {
            const uint32_t *t = s->indices + 3 * irand(s->tri_count);
            float a = frand(), b = frand() * (1.0f - a);
            for (k = 0; k < 3; k++)
                o[k] = (1.0f - a - b) * s->positions[3 * t[0] + (uint32_t)k] + a * s->positions[3 * t[1] + (uint32_t)k] +
                       b * s->positions[3 * t[2] + (uint32_t)k];
        }
        d[0] = 2.0f * frand() - 1.0f; d[1] = 2.0f * frand() - 1.0f; d[2] = 2.0f * frand() - 1.0f;
        break;
    case 4:
        d[0] = 1.0f; d[1] = d[2] = 0.0f;
        if (s->vertex_count) {
            const float *v = s->positions + 3 * irand(s->vertex_count);
            uint32_t axis = irand(3);
            o[axis] = v[axis];
            for (k = 0; k < 3; k++) d[k] = v[k] - o[k];   /* d[axis] = 0 exactly */
            if (d[0] == 0.0f && d[1] == 0.0f && d[2] == 0.0f) d[(axis + 1) % 3] = 1.0f;
        }
        break;
    }
}

/* Allocator that fails its fail_at-th call and counts live blocks. */
typedef struct failing { int count, fail_at; long live; } failing;
static void *failing_alloc(size_t size, void *user)
{
    failing *f = (failing *)user;
    if (f->count++ == f->fail_at) return NULL;
    f->live++;
    return malloc(size);
}
static void failing_free(void *p, void *user)
{
    ((failing *)user)->live--;
    free(p);
}

/* ---- the cases, once per header ------------------------------------------- */

#define BVH(x) irrvol__##x
#define BVH_NO_HIT IRRVOL__NO_HIT
#define BVH_LEAF IRRVOL__BVH_LEAF
#define BVH_ALLOCATOR irrvol_allocator
#define T(x) irrvol_test_##x
#include "tests/test_bvh_cases.h"
#undef BVH
#undef BVH_NO_HIT
#undef BVH_LEAF
#undef BVH_ALLOCATOR
#undef T

#define BVH(x) lightvec__##x
#define BVH_NO_HIT LIGHTVEC__NO_HIT
#define BVH_LEAF LIGHTVEC__BVH_LEAF
#define BVH_ALLOCATOR lightvec_allocator
#define T(x) lightvec_test_##x
#include "tests/test_bvh_cases.h"
#undef BVH
#undef BVH_NO_HIT
#undef BVH_LEAF
#undef BVH_ALLOCATOR
#undef T

#define BVH(x) radinterp__##x
#define BVH_NO_HIT RADINTERP__NO_HIT
#define BVH_LEAF RADINTERP__BVH_LEAF
#define BVH_ALLOCATOR radinterp_allocator
#define T(x) radinterp_test_##x
#include "tests/test_bvh_cases.h"
#undef BVH
#undef BVH_NO_HIT
#undef BVH_LEAF
#undef BVH_ALLOCATOR
#undef T

#define RAYS 100000u
#define CHECKED 2000u   /* brute force: every triangle per ray */

static void compare_all(const bvh_scene *s)
{
    irrvol_test_compare("irrvol", s, RAYS, CHECKED);
    lightvec_test_compare("lightvec", s, RAYS, CHECKED);
    radinterp_test_compare("radinterp", s, RAYS, CHECKED);
}

static void test_office(void)
{
    bvh_scene s;
    if (!CHECK(scene_office(&s) == 0)) return;
    compare_all(&s);
    scene_free(&s);
}

static void test_cubes(void)
{
    bvh_scene s;
    scene_cubes(&s, "6^3 cubes", 6, 1.0f);
    compare_all(&s);
    scene_free(&s);
}

/* Issue 17: at scale 1e-12 the float cross product of a triangle underflows;
   the area test runs in double, the triangles stay and are hit. */
static void test_tiny_scale(void)
{
    bvh_scene s;
    scene_cubes(&s, "6^3 cubes at scale 2^-40", 6, 1.0f / 1099511627776.0f);
    compare_all(&s);
    scene_free(&s);
}

static void test_soup(void)
{
    bvh_scene s;
    scene_soup(&s);
    compare_all(&s);
    scene_free(&s);
}

static void test_depth_cap(void)
{
    bvh_scene s;
    scene_chain(&s);
    compare_all(&s);
    scene_free(&s);
}

static void test_pile(void)
{
    bvh_scene s;
    scene_pile(&s);
    compare_all(&s);
    scene_free(&s);
}

/* Issue 17: a scene whose triangles all have zero area built a one-node
   empty tree that the traversal walked as an inner node. */
static void test_empty_trees(void)
{
    bvh_scene s;
    scene_degenerate(&s, "zero-area triangles only", 0);
    compare_all(&s);
    scene_free(&s);
    scene_alloc(&s, "no triangles", 0, 0);
    scene_bounds(&s);
    s.expect_hits = 0;
    compare_all(&s);
    scene_free(&s);
    scene_degenerate(&s, "3 triangles and 497 of zero area", 3);
    compare_all(&s);
    scene_free(&s);
}

static void test_allocation_failures(void)
{
    bvh_scene s;
    scene_cubes(&s, "2^3 cubes", 2, 1.0f);
    irrvol_test_allocation_failures(&s);
    lightvec_test_allocation_failures(&s);
    radinterp_test_allocation_failures(&s);
    scene_free(&s);
}

/* ---- the empty tree through the public functions -------------------------- */

/* irrvol_build over zero-area triangles only: every ray of the gather sees
   the background. */
static void test_irrvol_zero_area_scene(void)
{
    bvh_scene s;
    irrvol_desc d;
    irrvol_material m;
    irrvol *vol = NULL;
    float h[3], n[3] = {0.0f, 1.0f, 0.0f}, p[3] = {1.0f, 2.0f, 3.0f};
    scene_degenerate(&s, "zero-area triangles only", 0);
    memset(&d, 0, sizeof d);
    memset(&m, 0, sizeof m);
    m.radiance[0] = m.radiance[1] = m.radiance[2] = 1.0f;
    d.positions = s.positions;
    d.vertex_count = s.vertex_count;
    d.indices = s.indices;
    d.triangle_count = s.tri_count;
    d.materials = &m;
    d.material_count = 1;
    d.background[0] = d.background[1] = d.background[2] = 0.5f;
    d.bounds_min[0] = d.bounds_min[1] = d.bounds_min[2] = -1.0f;
    d.bounds_max[0] = d.bounds_max[1] = d.bounds_max[2] = 8.0f;
    d.grid_samples[0] = d.grid_samples[1] = d.grid_samples[2] = 2;
    d.resolution = 4;
    if (CHECK_EQ_INT(irrvol_build(&d, &vol), IRRVOL_OK)) {
        irrvol_query(vol, p, n, h);
        CHECK_CLOSE(h[0], 3.14159265 * 0.5, 1e-3, 0.0);   /* a furnace: pi * L */
    }
    irrvol_destroy(vol);
    scene_free(&s);
}

/* lightvec_scene_create over zero-area triangles only: rays miss, the
   gather sees nothing (no light, no hits). */
static void test_lightvec_zero_area_scene(void)
{
    bvh_scene s;
    lightvec_scene_desc d;
    lightvec_material m;
    lightvec_scene *scene = NULL;
    lightvec_gather_desc g;
    lightvec_surface surface;
    lightvec_record rec;
    lightvec_hit hit;
    float o[3] = {1.0f, 2.0f, 3.0f}, dir[3] = {0.0f, 0.0f, 1.0f};
    scene_degenerate(&s, "zero-area triangles only", 0);
    memset(&d, 0, sizeof d);
    memset(&m, 0, sizeof m);
    m.diffuse[0] = m.diffuse[1] = m.diffuse[2] = 0.5f;
    m.emission[0] = m.emission[1] = m.emission[2] = 1.0f;
    d.positions = s.positions;
    d.vertex_count = s.vertex_count;
    d.indices = s.indices;
    d.triangle_count = s.tri_count;
    d.materials = &m;
    d.material_count = 1;
    if (CHECK_EQ_INT(lightvec_scene_create(&d, &scene), LIGHTVEC_OK)) {
        CHECK_EQ_INT(lightvec_scene_intersect(scene, o, dir, FLT_MAX, &hit), 0);
        memset(&g, 0, sizeof g);
        memset(&surface, 0, sizeof surface);
        memcpy(surface.position, o, sizeof o);
        surface.normal[1] = 1.0f;
        surface.outgoing[1] = 1.0f;
        surface.material = m;
        if (CHECK_EQ_INT(lightvec_gather(scene, &g, &surface, 0, &rec), LIGHTVEC_OK))
            CHECK(rec.vector.magnitude[0] == 0.0f && rec.vector.magnitude[1] == 0.0f && rec.vector.magnitude[2] == 0.0f);
    }
    lightvec_scene_destroy(scene);
    scene_free(&s);
}

/* A closed cube room with an emitting ceiling: the radiosity of its floor at
   scale 2^-40 (about 1e-12 m, where the float area test of the BVH used to
   call every patch degenerate) equals the floor's at scale 1 (form factors
   do not depend on scale). */
static double cube_floor_radiosity(float scale)
{
    static const float corner[8][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
    /* faces wound to face the inside: floor (y = 0) first, ceiling (y = 1) second */
    static const uint32_t face[6][4] = {{0, 4, 5, 1}, {3, 2, 6, 7}, {0, 1, 2, 3}, {4, 7, 6, 5}, {0, 3, 7, 4}, {1, 5, 6, 2}};
    static const uint32_t material[6] = {0, 1, 0, 0, 0, 0};
    radinterp_material mats[2];
    radinterp_desc d;
    radinterp_solution *sol = NULL;
    float positions[24], rgb[3] = {-1.0f, -1.0f, -1.0f};
    uint32_t i;
    for (i = 0; i < 24; i++) positions[i] = scale * corner[i / 3][i % 3];
    memset(mats, 0, sizeof mats);
    mats[0].reflectance[0] = mats[0].reflectance[1] = mats[0].reflectance[2] = 0.5f;
    mats[1].emission[0] = mats[1].emission[1] = mats[1].emission[2] = 1.0f;
    memset(&d, 0, sizeof d);
    d.positions = positions;
    d.vertex_count = 8;
    d.patches = &face[0][0];
    d.patch_count = 6;
    d.patch_materials = material;
    d.materials = mats;
    d.material_count = 2;
    if (!CHECK_EQ_INT(radinterp_solve(&d, &sol), RADINTERP_OK)) return -1.0;
    CHECK_EQ_INT(radinterp_patch_radiosity(sol, 0, rgb), RADINTERP_OK);
    radinterp_solution_destroy(sol);
    return rgb[0];
}

static void test_radinterp_tiny_scene(void)
{
    double unit = cube_floor_radiosity(1.0f), tiny = cube_floor_radiosity(1.0f / 1099511627776.0f);
    CHECK(unit > 0.1);   /* the ceiling lights the floor: F ~ 0.2 */
    CHECK_CLOSE(tiny, unit, 1e-3, 0.0);   /* float rounding of the scaled corners */
}

int main(int argc, char **argv)
{
    TEST_INIT(argc, argv);
    RUN(test_office);
    RUN(test_cubes);
    RUN(test_tiny_scale);
    RUN(test_soup);
    RUN(test_depth_cap);
    RUN(test_pile);
    RUN(test_empty_trees);
    RUN(test_allocation_failures);
    RUN(test_irrvol_zero_area_scene);
    RUN(test_lightvec_zero_area_scene);
    RUN(test_radinterp_tiny_scene);
    return test_finish();
}
