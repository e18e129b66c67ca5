/* Unit tests of irrvol.h: known answers (furnace, cube with an emitting
   face, mirrors, linear fields), the grid structure, informed sampling,
   moments, filters, threads, progress, allocation failures, bad inputs. */
#define IRRVOL_IMPLEMENTATION
#include "irrvol.h"
#include "tests/test.h"
#include "tests/test_irrvol_scenes.h"
#include "examples/common/pool.h"

#define PI SC_PI

/* ---- helpers ------------------------------------------------------------ */

static uint32_t rng_state = 12345u;
static float frand(void) { return sc_frand(&rng_state); }
static void random_dir(float d[3]) { sc_random_dir(&rng_state, d); }

static void cube_bounds(irrvol_desc *d, float h)
{
    sc_set3(d->bounds_min, -h, -h, -h);
    sc_set3(d->bounds_max, h, h, h);
}

static void scene_desc(irrvol_desc *d, const sc_scene *s, const irrvol_material *m, uint32_t nm)
{
    sc_scene_desc(d, s, m, nm);
    d->grid_samples[0] = d->grid_samples[1] = d->grid_samples[2] = 3;
}

/* Counting allocator that can fail its n-th allocation. */
typedef struct counting { long live, count, fail_at; } counting;
static void *counting_alloc(size_t size, void *user)
{
    counting *c = (counting *)user;
    if (c->fail_at >= 0 && c->count == c->fail_at) { c->count++; return NULL; }
    c->count++;
    c->live++;
    return malloc(size);
}
static void counting_free(void *p, void *user)
{
    counting *c = (counting *)user;
    c->live--;
    free(p);
}
static irrvol_allocator counting_allocator(counting *c, long fail_at)
{
    irrvol_allocator a;
    c->live = c->count = 0;
    c->fail_at = fail_at;
    a.alloc = counting_alloc;
    a.free = counting_free;
    a.user = c;
    return a;
}

static void constant_radiance(void *user, const float org[3], const float dir[3], float rgb[3])
{
    const float *l = (const float *)user;
    (void)org; (void)dir;
    rgb[0] = l[0]; rgb[1] = l[1]; rgb[2] = l[2];
}

/* L = 1 + 0.5 x + 0.25 y - 0.3 z, the same in every direction. */
static void linear_radiance(void *user, const float org[3], const float dir[3], float rgb[3])
{
    float l = 1.0f + 0.5f * org[0] + 0.25f * org[1] - 0.3f * org[2];
    (void)user; (void)dir;
    rgb[0] = l; rgb[1] = 2.0f * l; rgb[2] = 0.5f * l;
}

/* A volume lit by a constant callback, no geometry: cheap, for API tests. */
static irrvol *callback_volume(uint32_t k, const float l[3])
{
    irrvol_desc d;
    irrvol *v = NULL;
    memset(&d, 0, sizeof d);
    d.radiance = constant_radiance;
    d.radiance_user = (void *)(uintptr_t)l;
    d.resolution = k;
    d.grid_samples[0] = d.grid_samples[1] = d.grid_samples[2] = 2;
    sc_set3(d.bounds_min, 0, 0, 0);
    sc_set3(d.bounds_max, 1, 1, 1);
    if (irrvol_build(&d, &v) != IRRVOL_OK) return NULL;
    return v;
}

/* ---- directions ----------------------------------------------------------- */

static void test_inverse_concentric_map(void)
{
    static const float one[3] = {1, 1, 1};
    irrvol *v = callback_volume(17, one);
    uint32_t b, i, wrong = 0, hemisphere;
    float worst = 0.0f;
    if (!CHECK(v != NULL)) return;
    for (b = 0; b < 578; b++) {   /* every bin centre maps back to its bin, at any length */
        float d[3], big[3], tiny[3];
        irrvol_bin_direction(v, b, d);
        sc_set3(big, 3.7f * d[0], 3.7f * d[1], 3.7f * d[2]);
        sc_set3(tiny, 1e-3f * d[0], 1e-3f * d[1], 1e-3f * d[2]);
        if (irrvol_direction_bin(v, d) != b || irrvol_direction_bin(v, big) != b || irrvol_direction_bin(v, tiny) != b)
            wrong++;
    }
    CHECK_EQ_INT(wrong, 0);
    for (i = 0; i < 100000; i++) {   /* forward then inverse: identity on the square */
        float u = frand(), w = frand(), u2, w2, d[3];
        uint32_t h = frand() < 0.5f;
        irrvol__vec3 p = irrvol__square_to_hemisphere(u, w);
        sc_set3(d, p.x, p.y, h ? -p.z : p.z);
        irrvol__direction_to_square(d, &u2, &w2, &hemisphere);
        if (fabsf(u2 - u) > worst) worst = fabsf(u2 - u);
        if (fabsf(w2 - w) > worst) worst = fabsf(w2 - w);
        if (hemisphere != h && p.z != 0.0f) wrong++;
    }
    test_note("inverse concentric map: largest error on the square %.2g", worst);
    CHECK(worst < 5e-6f);   /* float rounding of sqrt/division plus the 1.6e-7 atan polynomial */
    CHECK_EQ_INT(wrong, 0);
    {   /* zero, NaN and infinite directions still give a bin in range */
        float z[3] = {0, 0, 0}, n[3], inf[3];
        sc_set3(n, NAN, 0.0f, 1.0f);
        sc_set3(inf, INFINITY, -INFINITY, 1.0f);
        CHECK(irrvol_direction_bin(v, z) < 578);
        CHECK(irrvol_direction_bin(v, n) < 578);
        CHECK(irrvol_direction_bin(v, inf) < 578);
    }
    irrvol_destroy(v);
}

/* ---- furnace --------------------------------------------------------------- */

static void test_furnace(void)
{
    sc_scene s;
    irrvol_material m[6];
    irrvol_desc d;
    irrvol *v;
    int f, filter;
    sc_cube(&s);
    memset(m, 0, sizeof m);
    for (f = 0; f < 6; f++) sc_set3(m[f].radiance, 1.0f, 2.0f, 0.5f);
    scene_desc(&d, &s, m, 6);
    if (!CHECK_EQ_INT(irrvol_build(&d, &v), IRRVOL_OK)) return;
    for (filter = 0; filter < 6; filter++) {   /* every filter (default too) with either weighting */
        irrvol_filter f = (irrvol_filter)(filter % 3);
        irrvol_weighting g = filter < 3 ? IRRVOL_WEIGHTING_VISIBILITY : IRRVOL_WEIGHTING_TRILINEAR;
        double worst = 0.0;
        int i, c;
        for (i = 0; i < 2000; i++) {
            float p[3], dir[3], h[3];
            /* inside the room and past its walls: outside points clamp */
            sc_set3(p, 2.4f * frand() - 1.2f, 2.4f * frand() - 1.2f, 2.4f * frand() - 1.2f);
            random_dir(dir);
            irrvol_query_filter(v, f, g, p, dir, h);
            for (c = 0; c < 3; c++) {
                double e = fabs(h[c] - PI * m[0].radiance[c]) / (PI * m[0].radiance[c]);
                if (e > worst) worst = e;
            }
        }
        test_note("furnace k=17 %s, %s: largest |H - pi L| / pi L = %.3g %%",
                  f == IRRVOL_FILTER_NEAREST ? "nearest" : f == IRRVOL_FILTER_BILINEAR ? "bilinear" : "default",
                  g == IRRVOL_WEIGHTING_VISIBILITY ? "leak-safe" : "trilinear", 100.0 * worst);
        CHECK(worst < 0.005);   /* the acceptance bound; the bin weights integrate cos to 0.05 % */
    }
    irrvol_destroy(v);
}

/* Furnace of moment volumes and of the literal eq. 4.3 (weights at the bin
   centres only), through the radiance callback. */
static void test_furnace_moments_and_weights(void)
{
    static const float l[3] = {1.5f, 1.5f, 1.5f};
    static const uint32_t moments[4] = {1, 2, 10, 40};
    int i, j;
    for (i = 0; i < 5; i++) {
        irrvol_desc d;
        irrvol *v;
        double worst = 0.0;
        memset(&d, 0, sizeof d);
        d.radiance = constant_radiance;
        d.radiance_user = (void *)(uintptr_t)l;
        d.grid_samples[0] = d.grid_samples[1] = d.grid_samples[2] = 2;
        sc_set3(d.bounds_min, 0, 0, 0);
        sc_set3(d.bounds_max, 1, 1, 1);
        if (i < 4) d.moment = moments[i];
        else d.weight_subdivisions = 1;   /* eq. 4.3 evaluated literally at bin centres */
        if (!CHECK_EQ_INT(irrvol_build(&d, &v), IRRVOL_OK)) return;
        for (j = 0; j < 1000; j++) {
            float p[3], dir[3], h[3];
            sc_set3(p, frand(), frand(), frand());
            random_dir(dir);
            /* the bin a direction falls in, as the thesis stores it (bilinear would average the bins' errors) */
            irrvol_query_filter(v, IRRVOL_FILTER_NEAREST, IRRVOL_WEIGHTING_DEFAULT, p, dir, h);
            if (fabs(h[0] / (PI * l[0]) - 1.0) > worst) worst = fabs(h[0] / (PI * l[0]) - 1.0);
        }
        if (i < 4) {
            test_note("furnace, moment n=%u: largest error %.3g %%", moments[i], 100.0 * worst);
            CHECK(worst < 0.005);   /* (n+1)/2 normalizes eq. 4.8 to pi L */
        } else {
            test_note("furnace, eq. 4.3 at bin centres (weight_subdivisions 1): largest error %.3g %%", 100.0 * worst);
            CHECK(worst < 0.008);   /* the midpoint rule of eq. 4.3 is 0.69 % off at k = 17 */
            CHECK(worst > 0.005);   /* and measurably worse than the integrated weights */
        }
        irrvol_destroy(v);
    }
}

/* ---- cube with one emitting face ------------------------------------------- */

static void emitting_cube(sc_scene *s, irrvol_material m[6], irrvol_desc *d, float l)
{
    sc_cube(s);
    memset(m, 0, 6 * sizeof *m);
    sc_set3(m[5].radiance, l, l, l);   /* +z */
    scene_desc(d, s, m, 6);
    cube_bounds(d, 0.5f);           /* samples at -0.5, 0, 0.5: the centre is one */
    d->supersamples = 4;            /* 4 x 4 jittered rays: partly covered bins average */
}

static void test_cube_emitting_face(void)
{
    sc_scene s;
    irrvol_material m[6];
    irrvol_desc d;
    irrvol *v;
    const float l = 2.0f;
    float c[3] = {0, 0, 0}, up[3] = {0, 0, 1}, side[3] = {1, 0, 0}, bin_dir[3], h[3];
    double p[3] = {0, 0, 0}, n[3], expect;
    emitting_cube(&s, m, &d, l);
    if (!CHECK_EQ_INT(irrvol_build(&d, &v), IRRVOL_OK)) return;
    irrvol_query(v, c, up, h);
    test_note("cube centre facing the emitter: H / (pi L) = %.5f (closed form 0.554126)", h[0] / (PI * l));
    CHECK_CLOSE(h[0], PI * l * 0.554126, 0.02, 0.0);   /* acceptance: 2 % */
    /* facing a side wall: bilinear along +x, against the brute-force integral.
       +x lies on the equator, halfway between the centres of two bins 13
       degrees apart where H is strongly curved (0.91 and 0.52): linear
       interpolation between them is 2.2 % high, hence 3 % */
    n[0] = 1; n[1] = 0; n[2] = 0;
    expect = sc_square_irradiance(p, n, 2, 1.0, 0.0, 0.0, 1.0, l, 0.0, 600);
    irrvol_query_filter(v, IRRVOL_FILTER_BILINEAR, IRRVOL_WEIGHTING_DEFAULT, c, side, h);
    test_note("cube centre facing a side wall, bilinear: H = %.4f, brute force %.4f (%.2f %%)", h[0], expect,
              100.0 * (h[0] - expect) / expect);
    CHECK_CLOSE(h[0], expect, 0.03, 0.0);
    /* nearest returns the irradiance of the bin centre next to +x: compare
       with the integral in that direction */
    irrvol_bin_direction(v, irrvol_direction_bin(v, side), bin_dir);
    n[0] = bin_dir[0]; n[1] = bin_dir[1]; n[2] = bin_dir[2];
    expect = sc_square_irradiance(p, n, 2, 1.0, 0.0, 0.0, 1.0, l, 0.0, 600);
    irrvol_query_filter(v, IRRVOL_FILTER_NEAREST, IRRVOL_WEIGHTING_DEFAULT, c, side, h);
    test_note("cube centre facing a side wall, nearest: H = %.4f, brute force at the bin centre %.4f (%.2f %%)", h[0],
              expect, 100.0 * (h[0] - expect) / expect);
    CHECK_CLOSE(h[0], expect, 0.02, 0.0);
    irrvol_destroy(v);
}

/* ---- trilinear interpolation reproduces a linear field exactly ------------- */

static void test_linear_field_both_levels(void)
{
    sc_scene s;
    irrvol_desc d;
    irrvol *v;
    irrvol_volume_info info;
    double worst = 0.0;
    int i, c;
    memset(&s, 0, sizeof s);
    sc_square(&s, 1, 0.3f, 0.3f, 0.3f, 0.05f, 0);   /* geometry in one cell: refines it */
    sc_geometry_desc(&d, &s);
    d.radiance = linear_radiance;
    d.grid_samples[0] = d.grid_samples[1] = d.grid_samples[2] = 4;
    sc_set3(d.bounds_min, 0, 0, 0);
    sc_set3(d.bounds_max, 1, 1, 1);
    d.full_precision = 1;   /* the gather's own accuracy, below the compact store's rounding (test_compact_store) */
    if (!CHECK_EQ_INT(irrvol_build(&d, &v), IRRVOL_OK)) return;
    irrvol_info(v, &info);
    CHECK(info.refined_cells >= 1);
    CHECK(info.second_level_samples > 0);
    for (i = 0; i < 3000; i++) {
        float p[3], dir[3], h[3], l;
        if (i % 2) sc_set3(p, 0.25f + 0.1f * frand(), 0.25f + 0.1f * frand(), 0.25f + 0.1f * frand()); /* refined */
        else sc_set3(p, frand(), frand(), frand());
        random_dir(dir);
        irrvol_query_filter(v, IRRVOL_FILTER_DEFAULT, IRRVOL_WEIGHTING_TRILINEAR, p, dir, h);
        l = 1.0f + 0.5f * p[0] + 0.25f * p[1] - 0.3f * p[2];
        for (c = 0; c < 3; c++) {
            double e = fabs(h[c] / (PI * l * (c == 0 ? 1.0 : c == 1 ? 2.0 : 0.5)) - 1.0);
            if (e > worst) worst = e;
        }
    }
    test_note("linear radiance field, both levels, plain trilinear: largest relative error %.3g", worst);
    CHECK(worst < 1e-3);   /* trilinear is exact for linear data; 0.05 % weight quadrature + float rounding */
    CHECK(info.hanging_samples > 0);   /* the hanging samples' blends are exact for it too */
    irrvol_destroy(v);
}

/* ---- grid: refinement, shared samples, the overlap test --------------------- */

static void test_triangle_box_overlap(void)
{
    double c[3] = {0, 0, 0}, h[3] = {1, 1, 1};
    double inside[3][3] = {{-0.5, -0.5, 0}, {0.5, -0.5, 0}, {0, 0.5, 0}};
    double crossing[3][3] = {{-3, 0, 0}, {3, 0.1, 0}, {0, 0.2, 3}};       /* no vertex inside */
    double corner_miss[3][3] = {{1.5, 2.0, 0}, {2.0, 1.5, 0}, {2.0, 2.0, 0}}; /* bounds overlap, triangle not */
    double diagonal_miss[3][3] = {{3.2, 0, 0}, {0, 3.2, 0}, {0, 0, 3.2}}; /* plane x+y+z = 3.2 > 3 */
    double diagonal_hit[3][3] = {{2.8, 0, 0}, {0, 2.8, 0}, {0, 0, 2.8}};
    double touching[3][3] = {{1, -2, -2}, {1, 2, -2}, {1, 0, 2}};         /* in the face x = 1 */
    /* only the axis z x (edge AB) separates it: x + y >= 2.2 on the triangle, <= 2 in the box */
    double edge_axis_miss[3][3] = {{4.2, -2, 0}, {-2, 4.2, 0}, {3, 3, 5}};
    CHECK(irrvol__tri_box_overlap(c, h, inside));
    CHECK(irrvol__tri_box_overlap(c, h, crossing));
    CHECK(!irrvol__tri_box_overlap(c, h, corner_miss));
    CHECK(!irrvol__tri_box_overlap(c, h, diagonal_miss));
    CHECK(irrvol__tri_box_overlap(c, h, diagonal_hit));
    CHECK(irrvol__tri_box_overlap(c, h, touching));
    CHECK(!irrvol__tri_box_overlap(c, h, edge_axis_miss));
}

static irrvol_result structure_volume(const sc_scene *s, irrvol **v)
{
    static const float one[3] = {1, 1, 1};
    irrvol_desc d;
    sc_geometry_desc(&d, s);
    d.radiance = constant_radiance;
    d.radiance_user = (void *)(uintptr_t)one;
    d.resolution = 2;
    d.grid_samples[0] = d.grid_samples[1] = d.grid_samples[2] = 3;   /* 2 x 2 x 2 cells of size 1 */
    sc_set3(d.bounds_min, 0, 0, 0);
    sc_set3(d.bounds_max, 2, 2, 2);
    return irrvol_build(&d, v);
}

static void test_shared_second_level_samples(void)
{
    sc_scene s;
    irrvol *v;
    irrvol_volume_info info;
    uint32_t i;
    /* one small triangle pair inside cell (0,0,0): 27 + (27 - 8) samples */
    memset(&s, 0, sizeof s);
    sc_square(&s, 2, 0.5f, 0.5f, 0.5f, 0.1f, 0);
    if (!CHECK_EQ_INT(structure_volume(&s, &v), IRRVOL_OK)) return;
    irrvol_info(v, &info);
    CHECK_EQ_INT(info.refined_cells, 1);
    CHECK_EQ_INT(info.sample_count, 27 + 19);
    irrvol_destroy(v);
    /* a quad across cells (0,0,0) and (1,0,0): the 5 new samples of their
       common face are shared: 27 + 2 * 19 - 5 */
    memset(&s, 0, sizeof s);
    sc_square(&s, 2, 0.5f, 1.0f, 0.5f, 0.3f, 0);
    if (!CHECK_EQ_INT(structure_volume(&s, &v), IRRVOL_OK)) return;
    irrvol_info(v, &info);
    CHECK_EQ_INT(info.refined_cells, 2);
    CHECK_EQ_INT(info.first_level_samples, 27);
    CHECK_EQ_INT(info.second_level_samples, 33);
    for (i = 0; i < info.sample_count; i++) {   /* every sample on the half-cell lattice, no duplicates */
        irrvol_sample_info si, sj;
        uint32_t j, k, dup = 0;
        irrvol_sample(v, i, &si);
        for (k = 0; k < 3; k++) CHECK(fabsf(si.position[k] * 2.0f - roundf(si.position[k] * 2.0f)) < 1e-6f);
        CHECK_EQ_INT(si.level, i < 27 ? 1 : 2);
        for (j = 0; j < i; j++) {
            irrvol_sample(v, j, &sj);
            if (memcmp(si.position, sj.position, sizeof si.position) == 0) dup++;
        }
        CHECK_EQ_INT(dup, 0);
    }
    irrvol_destroy(v);
    /* a huge plane through the lower layer of cells refines exactly those four */
    memset(&s, 0, sizeof s);
    sc_square(&s, 1, 0.5f, 0.0f, 0.0f, 1e30f, 0);
    if (!CHECK_EQ_INT(structure_volume(&s, &v), IRRVOL_OK)) return;
    irrvol_info(v, &info);
    CHECK_EQ_INT(info.refined_cells, 4);
    irrvol_destroy(v);
    /* geometry on the outer walls of the scene stays outside the inset grid */
    {
        sc_scene c;
        irrvol_material m[6];
        irrvol_desc d;
        sc_cube(&c);
        memset(m, 0, sizeof m);
        scene_desc(&d, &c, m, 6);
        d.resolution = 2;
        if (!CHECK_EQ_INT(irrvol_build(&d, &v), IRRVOL_OK)) return;
        irrvol_info(v, &info);
        CHECK_EQ_INT(info.refined_cells, 0);
        CHECK_CLOSE(info.bounds_min[0], -0.98, 1e-6, 0.0);   /* default inset: 1 % of the extent */
        irrvol_destroy(v);
    }
}

/* ---- moments ------------------------------------------------------------------ */

static void test_moment_one_is_irradiance(void)
{
    sc_scene s;
    irrvol_material m[6];
    irrvol_desc d;
    irrvol *a, *b;
    irrvol_volume_info info;
    float *ha, *hb, *la, dirs[578][3];
    uint32_t i, j, bin;
    double worst = 0.0;
    emitting_cube(&s, m, &d, 3.0f);
    d.supersamples = 1;
    d.keep_radiance = 1;
    d.weight_subdivisions = 1;   /* the literal eq. 4.3 / 4.8 at bin centres */
    d.full_precision = 1;   /* the gather's own accuracy, below the compact store's rounding (test_compact_store) */
    if (!CHECK_EQ_INT(irrvol_build(&d, &a), IRRVOL_OK)) return;
    d.moment = 1;
    if (!CHECK_EQ_INT(irrvol_build(&d, &b), IRRVOL_OK)) { irrvol_destroy(a); return; }
    irrvol_info(a, &info);
    ha = (float *)malloc(578 * 3 * sizeof(float));
    hb = (float *)malloc(578 * 3 * sizeof(float));
    la = (float *)malloc(578 * 3 * sizeof(float));
    for (bin = 0; bin < 578; bin++) irrvol_bin_direction(a, bin, dirs[bin]);
    for (i = 0; i < info.sample_count; i++) {
        irrvol_sample_values(a, i, ha, la);
        irrvol_sample_values(b, i, hb, NULL);
        CHECK(memcmp(ha, hb, 578 * 3 * sizeof(float)) == 0);   /* n = 1 is the irradiance volume, bit for bit */
        for (j = 0; j < 578; j++) {   /* eq. 4.3 summed here in double from the kept radiance */
            double sum = 0.0;
            for (bin = 0; bin < 578; bin++) {
                double c = (double)dirs[bin][0] * dirs[j][0] + (double)dirs[bin][1] * dirs[j][1] +
                           (double)dirs[bin][2] * dirs[j][2];
                if (c > 0.0) sum += la[3 * bin] * c;
            }
            sum *= 4.0 * PI / 578.0;
            if (fabs(ha[3 * j] - sum) > worst) worst = fabs(ha[3 * j] - sum);
        }
    }
    test_note("matrix-product irradiance vs eq. 4.3 summed in double: largest difference %.3g (H up to %.3g)", worst,
              PI * 3.0);
    CHECK(worst < 2e-5);   /* float weights and float sums of 578 terms */
    free(ha); free(hb); free(la);
    irrvol_destroy(a);
    irrvol_destroy(b);
}

/* (n+1)/2 times the integral of L max(0, n . w)^n over the 0.2 x 0.2 patch
   of radiance 50 at z = 0.99, seen from the origin. */
static double patch_moment(uint32_t moment, const float n[3])
{
    double sum = 0.0;
    int gi, gj, g = 200;
    for (gj = 0; gj < g; gj++)
        for (gi = 0; gi < g; gi++) {
            double x = -0.1 + (gi + 0.5) * 0.2 / g, y = -0.1 + (gj + 0.5) * 0.2 / g, z = 0.99;
            double r2 = x * x + y * y + z * z, r = sqrt(r2), c = (n[0] * x + n[1] * y + n[2] * z) / r;
            if (c > 0.0) sum += 0.5 * (moment + 1.0) * 50.0 * pow(c, moment) * (z / r) / r2 * (0.2 / g) * (0.2 / g);
        }
    return sum;
}

/* A small bright patch at the centre of the +z wall, seen from the cube's
   centre: moments of higher order weight the patch more when the query
   looks at it and less when it looks 45 degrees away (fig. 4.14). */
static void test_moments_weight_towards_direction(void)
{
    static const uint32_t moments[5] = {1, 2, 4, 10, 20};
    sc_scene s;
    irrvol_material m[2];
    irrvol_desc d;
    float c[3] = {0, 0, 0}, at[3] = {0, 0, 1}, off[3] = {0.70710678f, 0, 0.70710678f};
    double prev_at = 0.0, prev_off = 1e30;
    int i;
    sc_cube(&s);
    for (i = 0; i < (int)s.nt; i++) s.mat[i] = 0;
    sc_square_facing(&s, 2, 0.99f, 0.0f, 0.0f, 0.1f, 1, -1);
    memset(m, 0, sizeof m);
    sc_set3(m[1].radiance, 50, 50, 50);
    m[1].flags = IRRVOL_MATERIAL_IMPORTANT;   /* integrated exactly over its solid angle */
    for (i = 0; i < 5; i++) {
        irrvol *v;
        float h_at[3], h_off[3], bin_off[3];
        double expect_at, expect_off;
        scene_desc(&d, &s, m, 2);
        cube_bounds(&d, 0.5f);
        d.moment = moments[i];
        if (!CHECK_EQ_INT(irrvol_build(&d, &v), IRRVOL_OK)) return;
        /* +z and the bin centre next to 45 degrees: every filter gives the bin there */
        irrvol_bin_direction(v, irrvol_direction_bin(v, off), bin_off);
        irrvol_query(v, c, at, h_at);
        irrvol_query(v, c, bin_off, h_off);
        expect_at = patch_moment(moments[i], at);
        expect_off = patch_moment(moments[i], bin_off);
        test_note("moment n=%2u: H^n at the patch %.4f (integral %.4f), 45 degrees off %.4f (integral %.4f)", moments[i],
                  h_at[0], expect_at, h_off[0], expect_off);
        CHECK(h_at[0] > prev_at);              /* sharper lobe: more of the patch */
        if (i >= 2) CHECK(h_off[0] < prev_off); /* and, past n = 2 where (n+1)/2 cos^n 45 deg peaks, less 45 deg away */
        /* the IMPORTANT patch enters eq. 4.8 with each area sample's own
           direction: only the stratified sampling error remains (0.05 %) */
        CHECK_CLOSE(h_at[0], expect_at, 0.01, 0.0);
        CHECK_CLOSE(h_off[0], expect_off, 0.01, 1e-4);
        prev_at = h_at[0];
        prev_off = h_off[0];
        irrvol_destroy(v);
    }
}

/* ---- informed sampling ---------------------------------------------------------- */

/* Mean relative error of every bin of every sample against the integral of
   a 0.1 x 0.1 lamp of radiance 100 in a dark room. */
static double small_lamp_error(uint32_t k, int important)
{
    sc_scene s;
    irrvol_material m[2];
    irrvol_desc d;
    irrvol *v;
    irrvol_volume_info info;
    double err = 0.0, total = 0.0;
    float *h;
    uint32_t i, b;
    sc_cube(&s);
    for (i = 0; i < s.nt; i++) s.mat[i] = 0;
    sc_square(&s, 1, 0.9f, 0.0f, 0.0f, 0.05f, 1);
    memset(m, 0, sizeof m);
    sc_set3(m[1].radiance, 100, 100, 100);
    if (important) m[1].flags = IRRVOL_MATERIAL_IMPORTANT;
    scene_desc(&d, &s, m, 2);
    d.subgrid_samples = 2;
    d.resolution = k;
    cube_bounds(&d, 0.6f);
    if (irrvol_build(&d, &v) != IRRVOL_OK) return -1.0;
    irrvol_info(v, &info);
    h = (float *)malloc((size_t)info.bins * 3 * sizeof(float));
    for (i = 0; i < info.sample_count; i++) {
        irrvol_sample_info si;
        irrvol_sample(v, i, &si);
        irrvol_sample_values(v, i, h, NULL);
        for (b = 0; b < info.bins; b++) {
            float dir[3];
            double p[3], n[3], exact;
            irrvol_bin_direction(v, b, dir);
            p[0] = si.position[0]; p[1] = si.position[1]; p[2] = si.position[2];
            n[0] = dir[0]; n[1] = dir[1]; n[2] = dir[2];
            exact = sc_square_irradiance(p, n, 1, 0.9, 0.0, 0.0, 0.05, 100.0, 0.0, 20);
            err += fabs(h[3 * b] - exact);
            total += exact;
        }
    }
    free(h);
    irrvol_destroy(v);
    return err / total;
}

static void test_informed_sampling(void)
{
    static const uint32_t ks[3] = {5, 9, 17};
    /* informed: the lamp enters eq. 4.3 through points sampled on it, each
       with its exact direction: only the area sampling error remains (0.1 %) */
    static const double bound[3] = {0.01, 0.01, 0.01};
    int i;
    for (i = 0; i < 3; i++) {
        double plain = small_lamp_error(ks[i], 0), informed = small_lamp_error(ks[i], 1);
        test_note("small lamp, k=%2u: mean |H - exact| / H: plain %.1f %%, IMPORTANT %.1f %%", ks[i], 100.0 * plain,
                  100.0 * informed);
        CHECK(plain > 0.5);           /* the lamp falls between bin centres, or one centre ray overweights it */
        CHECK(informed >= 0.0 && informed < bound[i]);
    }
}

/* ---- IGNORE, linearity, mirrors, per-vertex radiance, background ------------ */

static void test_ignore_and_linearity(void)
{
    sc_scene s;
    irrvol_material m[6];
    irrvol_desc d;
    irrvol *all, *low, *high;
    irrvol_volume_info info;
    float ha[578 * 3], hl[578 * 3], hh[578 * 3];
    double worst = 0.0;
    uint32_t i, j;
    int f;
    sc_cube(&s);
    memset(m, 0, sizeof m);
    for (f = 0; f < 6; f++) sc_set3(m[f].radiance, 1.0f + f, 0.5f * f, 2.0f);
    scene_desc(&d, &s, m, 6);
    d.refine_threshold = -1.0f;   /* the same grid whatever the light: samples compare one to one */
    d.full_precision = 1;         /* the sums are linear; each volume's own rounding in the compact store is not */
    if (!CHECK_EQ_INT(irrvol_build(&d, &all), IRRVOL_OK)) return;
    for (f = 0; f < 3; f++) m[f].flags = IRRVOL_MATERIAL_IGNORE;
    if (!CHECK_EQ_INT(irrvol_build(&d, &high), IRRVOL_OK)) return;
    for (f = 0; f < 6; f++) m[f].flags = f < 3 ? 0u : IRRVOL_MATERIAL_IGNORE;
    if (!CHECK_EQ_INT(irrvol_build(&d, &low), IRRVOL_OK)) return;
    irrvol_info(all, &info);
    for (i = 0; i < info.sample_count; i++) {   /* light transfer adds up: H(all) = H(some) + H(the rest) */
        irrvol_sample_values(all, i, ha, NULL);
        irrvol_sample_values(low, i, hl, NULL);
        irrvol_sample_values(high, i, hh, NULL);
        for (j = 0; j < 578 * 3; j++)
            if (fabs(ha[j] - hl[j] - hh[j]) > worst) worst = fabs(ha[j] - hl[j] - hh[j]);
    }
    CHECK(worst < 1e-4);   /* float sums of up to 578 terms of size ~ 20 */
    irrvol_destroy(all); irrvol_destroy(low); irrvol_destroy(high);
    for (f = 0; f < 6; f++) m[f].flags = IRRVOL_MATERIAL_IGNORE;   /* all ignored: darkness */
    if (!CHECK_EQ_INT(irrvol_build(&d, &all), IRRVOL_OK)) return;
    {
        float p[3] = {0.1f, 0.2f, 0.3f}, dir[3] = {0, 1, 0}, h[3];
        irrvol_query(all, p, dir, h);
        CHECK(h[0] == 0.0f && h[1] == 0.0f && h[2] == 0.0f);
    }
    irrvol_destroy(all);
}

/* The compact store (the default) against full precision on a cube of
   coloured faces, sky and a box inside (both levels, hanging samples,
   light from 0.5 to 30 W/m^2 between channels): every bin of every sample
   within 2^-9 of its largest channel (RGB9E5 rounds each mantissa to the
   nearest of 9 bits under an exponent shared with the largest channel,
   whose mantissa is >= 256); queries, linear in the bins with the same
   weights in both volumes, within 2^-9 of their channels' sum (each bin's
   largest channel is at most its sum), plus float rounding (1e-6). The
   memory: a third of the bins'. */
static void test_compact_store(void)
{
    sc_scene s;
    irrvol_material m[7];
    irrvol_desc d;
    irrvol *full, *compact;
    irrvol_volume_info fi, ci;
    float hf[578 * 3], hc[578 * 3];
    double worst = 0.0, worst_query = 0.0;
    uint32_t i, j;
    int f;
    sc_cube(&s);
    sc_square(&s, 1, 0.3f, 0.2f, 0.1f, 0.3f, 6);   /* a shelf: a second level around it */
    memset(m, 0, sizeof m);
    for (f = 0; f < 7; f++) sc_set3(m[f].radiance, 0.2f + f, 0.05f + 0.5f * f, 9.0f - f);
    scene_desc(&d, &s, m, 7);
    d.refine_threshold = -1.0f;   /* the shelf's cells alone refined: hanging samples beside them */
    d.full_precision = 1;
    if (!CHECK_EQ_INT(irrvol_build(&d, &full), IRRVOL_OK)) return;
    d.full_precision = 0;
    if (!CHECK_EQ_INT(irrvol_build(&d, &compact), IRRVOL_OK)) { irrvol_destroy(full); return; }
    irrvol_info(full, &fi);
    irrvol_info(compact, &ci);
    CHECK(fi.bin_bytes == 12 && ci.bin_bytes == 4 && ci.sample_count == fi.sample_count);
    CHECK(fi.hanging_samples > 0 && fi.refined_cells > 0);
    CHECK(fi.bytes - ci.bytes == (size_t)fi.sample_count * fi.bins * 8);
    for (i = 0; i < fi.sample_count; i++) {
        irrvol_sample_values(full, i, hf, NULL);
        irrvol_sample_values(compact, i, hc, NULL);
        for (j = 0; j < fi.bins; j++) {
            float *a = hf + 3 * j, *b = hc + 3 * j;
            double big = fmax(a[0], fmax(a[1], a[2]));
            int c;
            for (c = 0; c < 3; c++) worst = fmax(worst, fabs((double)a[c] - b[c]) / big);
        }
    }
    test_note("compact store: largest bin error %.6g of its largest channel (bound 2^-9 = %.3g)", worst, 1.0 / 512);
    CHECK(worst <= 1.0 / 512);
    for (i = 0; i < 4000; i++) {
        float p[3], dir[3], a[3], b[3];
        int c;
        for (c = 0; c < 3; c++) {
            p[c] = (float)((i * 7919u + 104729u * (uint32_t)c) % 1000u) / 500.0f - 1.0f;
            dir[c] = (float)((i * 15485863u + 32452843u * (uint32_t)c) % 997u) / 498.0f - 1.0f;
        }
        irrvol_query_filter(full, (irrvol_filter)(1 + i % 2), (irrvol_weighting)(1 + i / 2 % 2), p, dir, a);
        irrvol_query_filter(compact, (irrvol_filter)(1 + i % 2), (irrvol_weighting)(1 + i / 2 % 2), p, dir, b);
        for (c = 0; c < 3; c++)
            worst_query = fmax(worst_query, fabs((double)a[c] - b[c]) / ((double)a[0] + a[1] + a[2]));
    }
    test_note("compact store: largest query error %.3g of the query's channel sum", worst_query);
    CHECK(worst_query <= 1.0 / 512 + 1e-6);
    /* a query is its terms' weighted sum of the decoded words, summed here in double: the
       order of the float sums (BILINEAR by lanes, the exponents from their bits, the scale
       2^pack_shift applied at the end) changes only rounding, at most 64 roundings of
       non-negative terms: 64 x 2^-24 = 3.8e-6 of the channel sum */
    worst_query = 0.0;
    for (i = 0; i < 4000; i++) {
        float p[3], dir[3], b[3], value[3];
        double ref[3] = {0.0, 0.0, 0.0};
        irrvol__prepared q;
        uint32_t t, k;
        int c;
        for (c = 0; c < 3; c++) {
            p[c] = (float)((i * 7919u + 104729u * (uint32_t)c) % 1000u) / 500.0f - 1.0f;
            dir[c] = (float)((i * 15485863u + 32452843u * (uint32_t)c) % 997u) / 498.0f - 1.0f;
        }
        irrvol_query_filter(compact, (irrvol_filter)(1 + i % 2), (irrvol_weighting)(1 + i / 2 % 2), p, dir, b);
        irrvol__prepare(compact, (irrvol_filter)(1 + i % 2), (irrvol_weighting)(1 + i / 2 % 2), p, dir, dir, &q);
        for (t = 0; t < q.count; t++)
            for (k = 0; k < q.bins; k++) {
                irrvol__bin_value(compact, (size_t)q.bin[k] * ci.sample_count + q.id[t], value);
                for (c = 0; c < 3; c++) ref[c] += (double)q.w[t] * q.bw[k] * value[c] * q.scale;
            }
        for (c = 0; c < 3; c++) worst_query = fmax(worst_query, fabs(ref[c] - b[c]) / (ref[0] + ref[1] + ref[2]));
    }
    test_note("compact store: largest difference of a query from its terms summed in double %.3g of the channel sum",
              worst_query);
    CHECK(worst_query <= 3.8e-6);
    irrvol_destroy(full);
    irrvol_destroy(compact);
}

static void test_mirror_chain(void)
{
    sc_scene s;
    irrvol_material m[6];
    irrvol_desc d;
    irrvol *v;
    float c[3] = {0, 0, 0}, down[3] = {0, 0, -1}, h[3];
    double p[3] = {0, 0, 0}, n[3] = {0, 0, 1}, expect;
    int f;
    /* the -z face mirrors the emitting +z face: facing -z, the centre sees
       the emitter's image, a square of half-size 1 at distance 3, times 0.5 */
    emitting_cube(&s, m, &d, 2.0f);
    sc_set3(m[4].specular, 0.5f, 0.5f, 0.5f);
    if (!CHECK_EQ_INT(irrvol_build(&d, &v), IRRVOL_OK)) return;
    irrvol_query(v, c, down, h);
    expect = 0.5 * sc_square_irradiance(p, n, 2, 3.0, 0.0, 0.0, 1.0, 2.0, 0.0, 600);
    test_note("mirror: H = %.4f, image integral %.4f", h[0], expect);
    CHECK_CLOSE(h[0], expect, 0.03, 0.0);   /* small image: 3 % for the partly covered bins */
    irrvol_destroy(v);
    /* every face a 0.5 mirror, no emitter, background 1: the weight floor
       cuts every chain at 0.5^4 = 0.0625 < 0.1 */
    sc_cube(&s);
    memset(m, 0, sizeof m);
    for (f = 0; f < 6; f++) sc_set3(m[f].specular, 0.5f, 0.5f, 0.5f);
    scene_desc(&d, &s, m, 6);
    d.resolution = 9;   /* bin centres of the exact corners and edges of the cube included */
    sc_set3(d.background, 1, 1, 1);
    d.min_weight = 0.1f;
    d.max_depth = 100;
    if (!CHECK_EQ_INT(irrvol_build(&d, &v), IRRVOL_OK)) return;
    irrvol_query(v, c, down, h);
    CHECK_CLOSE(h[0], PI * 0.0625, 0.005, 0.0);
    irrvol_destroy(v);
    /* the depth limit: two reflections followed, the third surface's
       reflection replaced by the background: 0.5^3 */
    d.min_weight = 1e-9f;
    d.max_depth = 2;
    if (!CHECK_EQ_INT(irrvol_build(&d, &v), IRRVOL_OK)) return;
    irrvol_query(v, c, down, h);
    CHECK_CLOSE(h[0], PI * 0.125, 0.005, 0.0);
    irrvol_destroy(v);
}

static void test_background_and_open_scene(void)
{
    sc_scene s;
    irrvol_material m[1];
    irrvol_desc d;
    irrvol *v;
    float c[3] = {0, 0.5f, 0}, up[3] = {0, 1, 0}, h[3];
    memset(&s, 0, sizeof s);
    sc_square(&s, 1, 0.0f, 0.0f, 0.0f, 1000.0f, 0);   /* a floor, nothing else */
    memset(m, 0, sizeof m);
    scene_desc(&d, &s, m, 1);
    sc_set3(d.background, 0.25f, 0.5f, 1.0f);           /* the sky */
    sc_set3(d.bounds_min, -1, 0.25f, -1);
    sc_set3(d.bounds_max, 1, 0.75f, 1);
    d.full_precision = 1;   /* red is 1/4 of blue: the compact store may round it by 4 x 2^-9 = 0.8 % */
    if (!CHECK_EQ_INT(irrvol_build(&d, &v), IRRVOL_OK)) return;
    irrvol_query(v, c, up, h);
    CHECK_CLOSE(h[2], PI, 0.005, 0.0);   /* facing the sky: pi B */
    CHECK_CLOSE(h[0], PI * 0.25, 0.005, 0.0);
    irrvol_destroy(v);
    d.full_precision = 0;   /* the compact store: within 2^-9 of blue in every channel, beyond the 0.5 % */
    if (!CHECK_EQ_INT(irrvol_build(&d, &v), IRRVOL_OK)) return;
    irrvol_query(v, c, up, h);
    CHECK_CLOSE(h[2], PI, 0.005 + 1.0 / 512, 0.0);
    CHECK_CLOSE(h[0], PI * 0.25, 0.0, PI * (0.25 * 0.005 + 1.0 / 512));
    irrvol_destroy(v);
}

static void test_vertex_radiance(void)
{
    sc_scene s;
    irrvol_material m[6];
    irrvol_desc d;
    irrvol *v;
    float *lv, c[3] = {0, 0, 0}, up[3] = {0, 0, 1}, h[3];
    double p[3] = {0, 0, 0}, n[3] = {0, 0, 1}, expect;
    uint32_t i;
    emitting_cube(&s, m, &d, 0.0f);
    lv = (float *)calloc(s.nv, 3 * sizeof(float));
    for (i = 20; i < 24; i++) {   /* the +z face's vertices: L = 2 + x */
        float l = 2.0f + s.pos[3 * i];
        sc_set3(lv + 3 * i, l, l, l);
    }
    d.vertex_radiance = lv;
    if (!CHECK_EQ_INT(irrvol_build(&d, &v), IRRVOL_OK)) { free(lv); return; }
    irrvol_query(v, c, up, h);
    expect = sc_square_irradiance(p, n, 2, 1.0, 0.0, 0.0, 1.0, 2.0, 0.0, 600);   /* the x term integrates to 0 */
    CHECK_CLOSE(h[0], expect, 0.02, 0.0);
    {   /* facing +x the brighter half counts more: against the linear integral */
        float side[3] = {1, 0, 0};
        n[0] = 1; n[2] = 0;
        /* axis 2's coordinate axis+1 is x: l0 + l1 * x */
        expect = sc_square_irradiance(p, n, 2, 1.0, 0.0, 0.0, 1.0, 2.0, 1.0, 600);
        irrvol_query_filter(v, IRRVOL_FILTER_BILINEAR, IRRVOL_WEIGHTING_DEFAULT, c, side, h);
        test_note("per-vertex radiance L = 2 + x, facing +x: H = %.4f, integral %.4f", h[0], expect);
        CHECK_CLOSE(h[0], expect, 0.02, 0.0);
    }
    irrvol_destroy(v);
    free(lv);
}

/* ---- filters and query variants ---------------------------------------------- */

static void test_filters_and_queries(void)
{
    sc_scene s;
    irrvol_material m[6];
    irrvol_desc d;
    irrvol *v;
    float c[3] = {0.1f, -0.2f, 0.05f}, h[3], g[3], prev_n[3], prev_b[3];
    double jump_n = 0.0, jump_b = 0.0;
    uint32_t b;
    int i;
    emitting_cube(&s, m, &d, 2.0f);
    d.supersamples = 1;
    if (!CHECK_EQ_INT(irrvol_build(&d, &v), IRRVOL_OK)) return;
    /* a sweep across the equator (z = 0) from +x toward +z and -z: nearest
       jumps bin to bin, bilinear varies continuously */
    for (i = 0; i <= 360; i++) {
        float a = (float)(i - 180) * (float)PI / 720.0f, dir[3];   /* -45 to +45 degrees, 1/4 degree steps */
        sc_set3(dir, cosf(a), 0.3f, sinf(a));
        irrvol_query_filter(v, IRRVOL_FILTER_NEAREST, IRRVOL_WEIGHTING_TRILINEAR, c, dir, h);
        irrvol_query_filter(v, IRRVOL_FILTER_BILINEAR, IRRVOL_WEIGHTING_TRILINEAR, c, dir, g);
        if (i) {
            if (fabs(h[0] - prev_n[0]) > jump_n) jump_n = fabs(h[0] - prev_n[0]);
            if (fabs(g[0] - prev_b[0]) > jump_b) jump_b = fabs(g[0] - prev_b[0]);
        }
        memcpy(prev_n, h, sizeof h);
        memcpy(prev_b, g, sizeof g);
    }
    test_note("largest step between queries 1/4 degree apart: nearest %.4f, bilinear %.4f", jump_n, jump_b);
    CHECK(jump_b < 0.25 * jump_n);
    for (b = 0; b < 578; b += 7) {   /* at a bin centre both filters agree */
        float dir[3];
        irrvol_bin_direction(v, b, dir);
        irrvol_query_filter(v, IRRVOL_FILTER_NEAREST, IRRVOL_WEIGHTING_TRILINEAR, c, dir, h);
        irrvol_query_filter(v, IRRVOL_FILTER_BILINEAR, IRRVOL_WEIGHTING_TRILINEAR, c, dir, g);
        CHECK_CLOSE(g[0], h[0], 1e-3, 1e-5);   /* the centre maps back within float rounding */
    }
    for (i = 0; i < 200; i++) {
        float p[3], out[3], eye[3], n[3] = {0, 1, 0}, mirrored[3];
        irrvol__prepared q;
        sc_set3(p, 2.0f * frand() - 1.0f, 2.0f * frand() - 1.0f, 2.0f * frand() - 1.0f);
        random_dir(eye);
        /* glossy: the bins of the view vector mirrored about the normal, here
           exactly (-x, y, -z), the visibility weights of the normal */
        irrvol_query_glossy(v, p, n, eye, h);
        sc_set3(mirrored, -eye[0], eye[1], -eye[2]);
        irrvol__prepare(v, IRRVOL_FILTER_DEFAULT, IRRVOL_WEIGHTING_DEFAULT, p, n, mirrored, &q);
        irrvol__finish(v, &q, g);
        CHECK(memcmp(h, g, sizeof h) == 0);
        /* outside the bounds, plain trilinear: the same as the nearest boundary point */
        sc_set3(out, p[0] * 3.0f, p[1], p[2]);
        irrvol_query_filter(v, IRRVOL_FILTER_DEFAULT, IRRVOL_WEIGHTING_TRILINEAR, out, eye, h);
        out[0] = out[0] < -0.5f ? -0.5f : (out[0] > 0.5f ? 0.5f : out[0]);
        out[1] = out[1] < -0.5f ? -0.5f : (out[1] > 0.5f ? 0.5f : out[1]);
        out[2] = out[2] < -0.5f ? -0.5f : (out[2] > 0.5f ? 0.5f : out[2]);
        irrvol_query_filter(v, IRRVOL_FILTER_DEFAULT, IRRVOL_WEIGHTING_TRILINEAR, out, eye, g);
        CHECK(memcmp(h, g, sizeof h) == 0);
    }
    {   /* batches through the pipeline, with strides, equal single queries bit for bit,
           for every filter and weighting */
        static float pos[1000][3], dir[1000][4], out[1000][3];
        int f, w, k;
        for (i = 0; i < 1000; i++) {
            for (k = 0; k < 3; k++) pos[i][k] = 2.4f * frand() - 1.2f;
            random_dir(dir[i]);
        }
        for (f = IRRVOL_FILTER_DEFAULT; f <= IRRVOL_FILTER_BILINEAR; f++)
            for (w = IRRVOL_WEIGHTING_DEFAULT; w <= IRRVOL_WEIGHTING_TRILINEAR; w++) {
                int same = 1;
                irrvol_query_many(v, (irrvol_filter)f, (irrvol_weighting)w, 1000, &pos[0][0], 0, &dir[0][0],
                                  4 * sizeof(float), &out[0][0]);
                for (i = 0; i < 1000; i++) {
                    irrvol_query_filter(v, (irrvol_filter)f, (irrvol_weighting)w, pos[i], dir[i], h);
                    same &= memcmp(h, out[i], sizeof h) == 0;
                }
                CHECK(same);
            }
        irrvol_query_many(v, IRRVOL_FILTER_NEAREST, IRRVOL_WEIGHTING_DEFAULT, 0, NULL, 0, NULL, 0, NULL);   /* nothing to do */
        /* the defaults are the volume's: BILINEAR and leak-safe */
        irrvol_query(v, pos[7], dir[7], h);
        irrvol_query_filter(v, IRRVOL_FILTER_BILINEAR, IRRVOL_WEIGHTING_VISIBILITY, pos[7], dir[7], g);
        CHECK(memcmp(h, g, sizeof h) == 0);
    }
    {   /* NaN and infinite positions and directions: finite results */
        float nan3[3] = {NAN, NAN, NAN}, inf3[3] = {INFINITY, -INFINITY, 1.0f}, dir[3] = {0, 0, 1};
        int w;
        for (w = IRRVOL_WEIGHTING_DEFAULT; w <= IRRVOL_WEIGHTING_TRILINEAR; w++) {
            irrvol_query_filter(v, IRRVOL_FILTER_DEFAULT, (irrvol_weighting)w, nan3, dir, h);
            CHECK(isfinite(h[0]) && isfinite(h[1]) && isfinite(h[2]));
            irrvol_query_filter(v, IRRVOL_FILTER_DEFAULT, (irrvol_weighting)w, c, nan3, h);
            CHECK(isfinite(h[0]) && isfinite(h[1]) && isfinite(h[2]));
            irrvol_query_filter(v, IRRVOL_FILTER_DEFAULT, (irrvol_weighting)w, inf3, inf3, h);
            CHECK(isfinite(h[0]) && isfinite(h[1]) && isfinite(h[2]));
            irrvol_query_sh(v, 2, (irrvol_weighting)w, nan3, nan3, h);
            CHECK(isfinite(h[0]) && isfinite(h[1]) && isfinite(h[2]));
            irrvol_query_sh(v, 1, (irrvol_weighting)w, inf3, inf3, h);
            CHECK(isfinite(h[0]) && isfinite(h[1]) && isfinite(h[2]));
        }
    }
    irrvol_destroy(v);
}

/* ---- threads, progress, allocation ------------------------------------------- */

typedef struct progress_log { uint64_t calls, last_done, total, cancel_at; int monotonic; } progress_log;
static int progress_cb(void *user, uint64_t done, uint64_t total)
{
    progress_log *p = (progress_log *)user;
    p->calls++;
    if (done < p->last_done || done > total) p->monotonic = 0;
    p->last_done = done;
    p->total = total;
    return p->cancel_at && p->calls >= p->cancel_at;
}

/* A scene that exercises every build path: second level, an important lamp,
   a mirror, jitter. */
static void busy_scene(sc_scene *s, irrvol_material m[8], irrvol_desc *d)
{
    sc_cube(s);
    sc_square(s, 1, -0.3f, 0.2f, 0.1f, 0.25f, 6);   /* a table */
    sc_square(s, 1, 0.8f, -0.5f, 0.5f, 0.1f, 7);    /* a lamp */
    memset(m, 0, 8 * sizeof *m);
    sc_set3(m[0].radiance, 0.3f, 0.2f, 0.1f);
    sc_set3(m[3].radiance, 0.5f, 0.5f, 0.5f);
    sc_set3(m[2].specular, 0.4f, 0.4f, 0.4f);
    sc_set3(m[6].radiance, 0.2f, 0.4f, 0.1f);
    sc_set3(m[7].radiance, 30, 28, 20);
    m[7].flags = IRRVOL_MATERIAL_IMPORTANT;
    scene_desc(d, s, m, 8);
    d->grid_samples[0] = 5;
    d->supersamples = 2;
    d->resolution = 9;
    d->seed = 77;
}

static int volumes_equal(const irrvol *a, const irrvol *b)
{
    irrvol_volume_info ia, ib;
    uint32_t i;
    float *x, *y;
    int same = 1;
    irrvol_info(a, &ia);
    irrvol_info(b, &ib);
    if (ia.sample_count != ib.sample_count || ia.bins != ib.bins || ia.rays != ib.rays) return 0;
    x = (float *)malloc((size_t)ia.bins * 3 * sizeof(float));
    y = (float *)malloc((size_t)ia.bins * 3 * sizeof(float));
    for (i = 0; i < ia.sample_count && same; i++) {
        irrvol_sample_values(a, i, x, NULL);
        irrvol_sample_values(b, i, y, NULL);
        same = memcmp(x, y, (size_t)ia.bins * 3 * sizeof(float)) == 0;
    }
    free(x);
    free(y);
    return same;
}

static void test_threads_bit_identical(void)
{
    sc_scene s;
    irrvol_material m[8];
    irrvol_desc d;
    irrvol *one, *two;
    ex_pool *pool = ex_pool_create(2);
    busy_scene(&s, m, &d);
    if (!CHECK_EQ_INT(irrvol_build(&d, &one), IRRVOL_OK)) { ex_pool_destroy(pool); return; }
    d.parallel_for = ex_pool_parallel_for;
    d.parallel_user = pool;
    if (!CHECK_EQ_INT(irrvol_build(&d, &two), IRRVOL_OK)) { irrvol_destroy(one); ex_pool_destroy(pool); return; }
    CHECK(volumes_equal(one, two));
    irrvol_destroy(two);
    d.seed = 78;   /* the seed matters (jitter): a different volume */
    if (CHECK_EQ_INT(irrvol_build(&d, &two), IRRVOL_OK)) {
        CHECK(!volumes_equal(one, two));
        irrvol_destroy(two);
    }
    irrvol_destroy(one);
    ex_pool_destroy(pool);
}

static void test_progress_and_cancel(void)
{
    sc_scene s;
    irrvol_material m[8];
    irrvol_desc d;
    irrvol *v = NULL;
    progress_log log;
    counting c;
    irrvol_volume_info info;
    busy_scene(&s, m, &d);
    memset(&log, 0, sizeof log);
    log.monotonic = 1;
    d.progress = progress_cb;
    d.progress_user = &log;
    if (!CHECK_EQ_INT(irrvol_build(&d, &v), IRRVOL_OK)) return;
    irrvol_info(v, &info);
    CHECK(log.calls >= 1 && log.monotonic);
    /* every sample but the hanging ones gathers */
    CHECK_EQ_INT(log.last_done, info.sample_count - info.hanging_samples);
    CHECK_EQ_INT(log.total, info.sample_count - info.hanging_samples);
    irrvol_destroy(v);
    memset(&log, 0, sizeof log);
    log.cancel_at = 1;
    d.allocator = counting_allocator(&c, -1);
    CHECK_EQ_INT(irrvol_build(&d, &v), IRRVOL_ERROR_CANCELLED);
    CHECK(v == NULL);
    CHECK_EQ_INT(c.live, 0);
}

static void test_allocation_failures(void)
{
    sc_scene s;
    irrvol_material m[8];
    irrvol_desc d;
    irrvol *v;
    counting c;
    long n, failures = 0;
    void *data;
    size_t size;
    busy_scene(&s, m, &d);
    d.keep_radiance = 1;
    for (n = 0;; n++) {   /* fail the n-th allocation: out of memory, nothing leaked */
        irrvol_result r;
        d.allocator = counting_allocator(&c, n);
        r = irrvol_build(&d, &v);
        if (r == IRRVOL_OK) break;
        failures++;
        CHECK_EQ_INT(r, IRRVOL_ERROR_OUT_OF_MEMORY);
        CHECK_EQ_INT(c.live, 0);
    }
    CHECK(failures > 5);
    if (!CHECK_EQ_INT(irrvol_save_to_memory(v, NULL, &data, &size), IRRVOL_OK)) { irrvol_destroy(v); return; }
    irrvol_destroy(v);
    CHECK_EQ_INT(c.live, 0);
    for (n = 0;; n++) {
        irrvol_allocator a = counting_allocator(&c, n);
        irrvol_result r = irrvol_load_from_memory(data, size, &a, &v);
        if (r == IRRVOL_OK) { irrvol_destroy(v); break; }
        CHECK_EQ_INT(r, IRRVOL_ERROR_OUT_OF_MEMORY);
        CHECK_EQ_INT(c.live, 0);
    }
    CHECK_EQ_INT(c.live, 0);
    for (n = 0; n < 3; n++) {   /* saving into memory that cannot grow */
        irrvol_allocator a = counting_allocator(&c, n);
        void *out;
        size_t out_size;
        irrvol_load_from_memory(data, size, NULL, &v);
        CHECK_EQ_INT(irrvol_save_to_memory(v, &a, &out, &out_size), IRRVOL_ERROR_OUT_OF_MEMORY);
        CHECK(out == NULL && out_size == 0);
        CHECK_EQ_INT(c.live, 0);
        irrvol_destroy(v);
    }
    irrvol_free_memory(NULL, data);
}

/* ---- bad inputs --------------------------------------------------------------- */

static int log_calls;
static void log_cb(void *user, const char *message) { (void)user; if (message && *message) log_calls++; }

static int bad_trace(void *user, const float org[3], const float dir[3], float tmax, irrvol_hit *hit)
{
    (void)user; (void)org; (void)dir; (void)tmax;
    hit->t = 1.0f; hit->u = hit->v = 0.0f;
    hit->triangle = 0xFFFFFF00u;   /* a hostile caster: out of range, treated as a miss */
    return 1;
}

static void test_bad_inputs(void)
{
    sc_scene s;
    irrvol_material m[6];
    irrvol_desc d, good;
    irrvol *v = (irrvol *)&d;
    uint32_t bad_idx[3] = {0, 1, 99};
    float flat[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    uint32_t flat_idx[3] = {0, 1, 2};
    counting c;
    sc_cube(&s);
    memset(m, 0, sizeof m);
    scene_desc(&good, &s, m, 6);
    good.resolution = 3;
    good.log = log_cb;
    log_calls = 0;
    CHECK_EQ_INT(irrvol_build(NULL, &v), IRRVOL_ERROR_INVALID_ARGUMENT);
    CHECK_EQ_INT(irrvol_build(&good, NULL), IRRVOL_ERROR_INVALID_ARGUMENT);
#define BAD(stmt) do { d = good; stmt; v = (irrvol *)&d; \
        CHECK_EQ_INT(irrvol_build(&d, &v), IRRVOL_ERROR_INVALID_ARGUMENT); CHECK(v == NULL); } while (0)
    {
        float keep = s.pos[4];
        BAD(s.pos[4] = NAN);
        BAD(s.pos[4] = INFINITY);
        s.pos[4] = keep;
    }
    BAD(d.indices = bad_idx; d.triangle_count = 1);
    BAD(s.mat[3] = 6);
    s.mat[3] = 1;
    BAD(d.positions = NULL);
    BAD(d.vertex_count = 0);
    BAD(d.position_stride = 8);
    BAD(d.materials = NULL);
    BAD(d.material_count = 0);
    BAD(m[2].radiance[1] = -1.0f);
    m[2].radiance[1] = 0.0f;
    BAD(m[2].specular[0] = NAN);
    m[2].specular[0] = 0.0f;
    BAD(d.triangle_count = 0);                          /* no geometry and no radiance callback */
    BAD(d.positions = flat; d.indices = flat_idx; d.triangle_count = 1; d.vertex_count = 3; d.triangle_materials = NULL);
    BAD(d.grid_samples[1] = 1);
    BAD(d.grid_samples[2] = IRRVOL_MAX_GRID_SAMPLES + 1);
    BAD(d.subgrid_samples = 1);
    BAD(d.subgrid_samples = IRRVOL_MAX_SUBGRID_SAMPLES + 1);
    BAD(d.resolution = IRRVOL_MAX_RESOLUTION + 1);
    BAD(d.supersamples = 17);
    BAD(d.moment = IRRVOL_MAX_MOMENT + 1);
    BAD(d.inset = 0.5f);
    BAD(d.inset = -0.1f);
    BAD(d.inset = NAN);
    BAD(sc_set3(d.bounds_min, 0, 0, 0); sc_set3(d.bounds_max, 1, 0, 1));   /* zero size */
    BAD(sc_set3(d.bounds_min, 0, 0, 0); sc_set3(d.bounds_max, 1, NAN, 1));
    BAD(d.filter = (irrvol_filter)7);
    BAD(d.background[0] = -1.0f);
    BAD(d.min_weight = NAN);
    BAD(d.ray_offset = -1.0f);
    BAD(d.vertex_radiance = flat; d.vertex_radiance_stride = 4);
    BAD(d.allocator = counting_allocator(&c, -1); d.allocator.free = NULL);
    BAD(d.weighting = (irrvol_weighting)7);
    BAD(d.visibility_resolution = IRRVOL_MAX_VISIBILITY_RESOLUTION + 1);
    BAD(d.important_rays = IRRVOL_MAX_IMPORTANT_RAYS + 1);
    BAD(d.weight_subdivisions = IRRVOL_MAX_WEIGHT_SUBDIVISIONS + 1);
    BAD(d.normal_bias = NAN);
    BAD(d.normal_bias = 2.0f);
    BAD(d.refine_threshold = INFINITY);
    {   /* issue 17: 3 * 0x55555556 wraps to 2 in 32 bits; the check must see
           the index past the first triangle (and the count past UINT32_MAX / 3)
           before the build reads 1.4 billion triangles from a 9-entry buffer */
        uint32_t few[9] = {0, 1, 2, 0, 2, 3, 0, 1, 99};
        BAD(d.indices = few; d.triangle_count = 0x55555556u; d.triangle_materials = NULL);
        BAD(d.indices = few; d.triangle_count = 3; d.triangle_materials = NULL);   /* index 99 */
    }
#undef BAD
    CHECK(log_calls > 20);
    {   /* degenerate triangles are skipped and counted, not fatal */
        irrvol_volume_info info;
        uint32_t idx[3 * (2 * SC_MAX_QUADS + 2)];
        uint32_t mat[2 * SC_MAX_QUADS + 2];
        memcpy(idx, s.idx, 3 * s.nt * sizeof(uint32_t));
        memcpy(mat, s.mat, s.nt * sizeof(uint32_t));
        idx[3 * s.nt] = 0; idx[3 * s.nt + 1] = 0; idx[3 * s.nt + 2] = 1;       /* a repeated vertex */
        idx[3 * s.nt + 3] = 0; idx[3 * s.nt + 4] = 1; idx[3 * s.nt + 5] = 0;
        mat[s.nt] = mat[s.nt + 1] = 0;
        d = good;
        d.indices = idx;
        d.triangle_materials = mat;
        d.triangle_count = s.nt + 2;
        if (CHECK_EQ_INT(irrvol_build(&d, &v), IRRVOL_OK)) {
            irrvol_info(v, &info);
            CHECK_EQ_INT(info.degenerate_triangles, 2);
            irrvol_destroy(v);
        }
    }
    {   /* a ray caster that reports nonsense triangles: every ray misses */
        float p[3] = {0, 0, 0}, dir[3] = {0, 0, 1}, h[3];
        d = good;
        d.trace = bad_trace;
        d.resolution = 17;
        sc_set3(d.background, 1, 1, 1);
        if (CHECK_EQ_INT(irrvol_build(&d, &v), IRRVOL_OK)) {
            irrvol_query(v, p, dir, h);
            CHECK_CLOSE(h[0], PI, 0.005, 0.0);
            irrvol_destroy(v);
        }
    }
    {   /* the other entry points */
        irrvol_sample_info si;
        float buf[3 * 18];
        static const float one[3] = {1, 1, 1};
        irrvol *w = callback_volume(3, one);
        v = w;
        CHECK_EQ_INT(irrvol_info(NULL, NULL), IRRVOL_ERROR_INVALID_ARGUMENT);
        CHECK_EQ_INT(irrvol_sample(v, 8, &si), IRRVOL_ERROR_INVALID_ARGUMENT);
        CHECK_EQ_INT(irrvol_sample(v, 7, &si), IRRVOL_OK);
        CHECK_EQ_INT(irrvol_sample_values(v, 0, buf, buf), IRRVOL_ERROR_INVALID_ARGUMENT);   /* no radiance kept */
        CHECK_EQ_INT(irrvol_save(v, NULL, NULL), IRRVOL_ERROR_INVALID_ARGUMENT);
        CHECK_EQ_INT(irrvol_load(NULL, NULL, NULL, &v), IRRVOL_ERROR_INVALID_ARGUMENT);
        CHECK(v == NULL);
        irrvol_destroy(w);
        irrvol_destroy(NULL);
        CHECK(strcmp(irrvol_result_string(IRRVOL_ERROR_CORRUPT_DATA), "corrupt data") == 0);
        CHECK(strcmp(irrvol_result_string((irrvol_result)99), "unknown result") == 0);
    }
}

int main(int argc, char **argv)
{
    TEST_INIT(argc, argv);
    RUN(test_inverse_concentric_map);
    RUN(test_furnace);
    RUN(test_furnace_moments_and_weights);
    RUN(test_cube_emitting_face);
    RUN(test_linear_field_both_levels);
    RUN(test_triangle_box_overlap);
    RUN(test_shared_second_level_samples);
    RUN(test_moment_one_is_irradiance);
    RUN(test_moments_weight_towards_direction);
    RUN(test_informed_sampling);
    RUN(test_ignore_and_linearity);
    RUN(test_compact_store);
    RUN(test_mirror_chain);
    RUN(test_background_and_open_scene);
    RUN(test_vertex_radiance);
    RUN(test_filters_and_queries);
    RUN(test_threads_bit_identical);
    RUN(test_progress_and_cancel);
    RUN(test_allocation_failures);
    RUN(test_bad_inputs);
    return test_finish();
}
