/* irrvol.h on real levels: light leaks through a thin wall, samples inside
   geometry (invalid, relocated, dilated), continuity across every
   first-level face on a non-linear field (hanging samples), refinement by
   light (6.1.1), the spherical-harmonic encoding, and the seams and leaks
   of the thesis's plain query for comparison. Default settings unless a
   test says otherwise. */
#define IRRVOL_IMPLEMENTATION
#include "irrvol.h"
#include "tests/test.h"
#include "tests/test_irrvol_scenes.h"
#include "examples/common/pool.h"

#define PI SC_PI

static uint32_t rng_state = 4242u;
static float frand(void) { return sc_frand(&rng_state); }
static void random_dir(float d[3]) { sc_random_dir(&rng_state, d); }
static float luminance(const float *rgb) { return 0.2126f * rgb[0] + 0.7152f * rgb[1] + 0.0722f * rgb[2]; }

/* The scene's volume, default settings, built on a pool of all cores. */
static irrvol_result build_defaults(const sc_scene *s, const irrvol_material *m, uint32_t nm, irrvol **v)
{
    irrvol_desc d;
    ex_pool *pool = ex_pool_create(0);
    irrvol_result r;
    sc_scene_desc(&d, s, m, nm);
    d.parallel_for = ex_pool_parallel_for;
    d.parallel_user = pool;
    r = irrvol_build(&d, v);
    ex_pool_destroy(pool);
    return r;
}

/* ---- two rooms and a 2 cm wall ------------------------------------------------ */

/* Two closed 4 x 3 x 4 m rooms side by side, x < -0.01 lit (every surface
   radiance 1: H = pi everywhere inside) and x > 0.01 dark (radiance 0);
   the wall between them is 2 cm thick, both its faces geometry. */
static void two_rooms(sc_scene *s, irrvol_material m[2])
{
    float lo[3], hi[3];
    memset(s, 0, sizeof *s);
    sc_set3(lo, -4.0f, 0.0f, 0.0f); sc_set3(hi, -0.01f, 3.0f, 4.0f);
    sc_box(s, lo, hi, 0, 1);
    sc_set3(lo, 0.01f, 0.0f, 0.0f); sc_set3(hi, 4.0f, 3.0f, 4.0f);
    sc_box(s, lo, hi, 1, 1);
    memset(m, 0, 2 * sizeof *m);
    sc_set3(m[0].radiance, 1, 1, 1);
}

/* Mean over a 24 x 24 grid of points on the plane x = at (y, z across the
   wall, 10 cm from the floor, ceiling and side walls), each with a random
   direction, of the luminance of H / pi: the fraction of the lit room's
   irradiance; *worst the largest. */
static double plane_leak(const irrvol *v, irrvol_weighting weighting, float at, double *worst)
{
    double sum = 0.0;
    int i, j;
    *worst = 0.0;
    for (j = 0; j < 24; j++)
        for (i = 0; i < 24; i++) {
            float p[3], dir[3], h[3];
            double leak;
            sc_set3(p, at, 0.1f + 2.8f * ((float)i + 0.5f) / 24.0f, 0.1f + 3.8f * ((float)j + 0.5f) / 24.0f);
            random_dir(dir);
            irrvol_query_filter(v, IRRVOL_FILTER_DEFAULT, weighting, p, dir, h);
            leak = luminance(h) / PI;
            sum += leak;
            if (leak > *worst) *worst = leak;
        }
    return sum / (24.0 * 24.0);
}

static void test_leak_through_thin_wall(void)
{
    sc_scene s;
    irrvol_material m[2];
    irrvol *v;
    irrvol_volume_info info;
    double leak1, leak10, worst1, worst10, plain1, plain10, lit, worst_lit, w;
    two_rooms(&s, m);
    if (!CHECK_EQ_INT(build_defaults(&s, m, 2, &v), IRRVOL_OK)) return;
    irrvol_info(v, &info);
    leak1 = plane_leak(v, IRRVOL_WEIGHTING_DEFAULT, 0.02f, &worst1);
    leak10 = plane_leak(v, IRRVOL_WEIGHTING_DEFAULT, 0.11f, &worst10);
    plain1 = plane_leak(v, IRRVOL_WEIGHTING_TRILINEAR, 0.02f, &w);
    plain10 = plane_leak(v, IRRVOL_WEIGHTING_TRILINEAR, 0.11f, &w);
    lit = plane_leak(v, IRRVOL_WEIGHTING_DEFAULT, -0.02f, &worst_lit);
    test_note("two rooms, 2 cm wall, defaults (%u samples, %u relocated, %u invalid): leak into the dark room at "
              "1 cm %.2f %% (worst %.1f %%), at 10 cm %.2f %% (worst %.1f %%); plain trilinear %.1f %% and %.1f %%; "
              "lit side 1 cm from the wall %.1f %% of pi", info.sample_count, info.relocated_samples,
              info.invalid_samples, 100.0 * leak1, 100.0 * worst1, 100.0 * leak10, 100.0 * worst10, 100.0 * plain1,
              100.0 * plain10, 100.0 * lit);
    CHECK(leak1 <= 0.03);    /* the acceptance bounds */
    CHECK(leak10 <= 0.01);
    CHECK(plain1 > 0.2);     /* the thesis's query leaks: the test can fail */
    CHECK(lit > 0.97);       /* and the lit side keeps its light */
    irrvol_destroy(v);
}

/* A sample exactly in the middle of the wall (x = 0) sees back faces all
   around: it moves out of the wall, into one room, and gathers that room. */
static void test_relocation_out_of_wall(void)
{
    sc_scene s;
    irrvol_material m[2];
    irrvol_desc d;
    irrvol *v;
    irrvol_volume_info info;
    uint32_t i, moved = 0;
    two_rooms(&s, m);
    sc_scene_desc(&d, &s, m, 2);
    d.resolution = 9;
    d.grid_samples[0] = 5; d.grid_samples[1] = d.grid_samples[2] = 3;
    sc_set3(d.bounds_min, -3.0f, 0.5f, 0.5f);
    sc_set3(d.bounds_max, 3.0f, 2.5f, 3.5f);   /* samples at x = 0: in the wall */
    if (!CHECK_EQ_INT(irrvol_build(&d, &v), IRRVOL_OK)) return;
    irrvol_info(v, &info);
    for (i = 0; i < info.sample_count; i++) {
        irrvol_sample_info si;
        float h[9 * 9 * 2 * 3], expect;
        uint32_t b;
        double worst = 0.0;
        irrvol_sample(v, i, &si);
        if (si.position[0] != 0.0f || si.state == IRRVOL_SAMPLE_HANGING) continue;
        CHECK_EQ_INT(si.state, IRRVOL_SAMPLE_RELOCATED);
        CHECK(fabsf(si.origin[0]) > 0.01f && fabsf(si.origin[0]) < 0.2f);   /* out of the wall, near it */
        /* through the nearest back face: along the bin ray closest to the wall's normal */
        CHECK(fabsf(si.origin[1] - si.position[1]) < 0.5f * fabsf(si.origin[0]) &&
              fabsf(si.origin[2] - si.position[2]) < 0.5f * fabsf(si.origin[0]));
        expect = si.origin[0] < 0.0f ? (float)PI : 0.0f;   /* the room it moved into */
        irrvol_sample_values(v, i, h, NULL);
        for (b = 0; b < info.bins; b++)
            if (fabs(h[3 * b] - expect) > worst) worst = fabs(h[3 * b] - expect);
        CHECK(worst < 0.005 * PI);   /* the furnace bound */
        moved++;
    }
    test_note("samples in the middle of the 2 cm wall: %u of them moved out, into one room", moved);
    CHECK(moved >= 9);
    CHECK_EQ_INT(info.relocated_samples, moved);
    irrvol_destroy(v);
}

/* ---- a closed box around a sample ------------------------------------------- */

static const float box_half = 0.45f;

/* Rays from inside the box see the user's radiance, the others 0.5. */
static void inside_box_radiance(void *user, const float org[3], const float dir[3], float rgb[3])
{
    float l = fabsf(org[0]) < box_half && fabsf(org[1]) < box_half && fabsf(org[2]) < box_half ? *(const float *)user : 0.5f;
    (void)dir;
    rgb[0] = rgb[1] = rgb[2] = l;
}

/* A room [-2, 2]^3 with a closed 0.9 m box (faces out) around its centre,
   samples every 1.5 m (fine spacing 0.75 m around the box): the centre
   sample is 0.45 m deep inside, farther than it may move (0.45 x 0.75), so
   it is invalid. Two volumes that differ only in what the rays from inside
   the box see answer every query identically. */
static void test_sample_in_closed_box(void)
{
    static const float dark = 0.0f, bright = 1000.0f;
    sc_scene s;
    irrvol_desc d;
    irrvol *a, *b;
    irrvol_volume_info info;
    irrvol_sample_info si;
    float lo[3], hi[3], h[8 * 8 * 2 * 3];
    uint32_t i, centre = 13, different = 0;
    int k;
    memset(&s, 0, sizeof s);
    sc_set3(lo, -2, -2, -2); sc_set3(hi, 2, 2, 2);
    sc_box(&s, lo, hi, 0, 1);
    sc_set3(lo, -box_half, -box_half, -box_half); sc_set3(hi, box_half, box_half, box_half);
    sc_box(&s, lo, hi, 0, 0);
    sc_geometry_desc(&d, &s);
    d.radiance = inside_box_radiance;
    d.radiance_user = (void *)(uintptr_t)&dark;
    d.resolution = 8;
    d.grid_samples[0] = d.grid_samples[1] = d.grid_samples[2] = 3;
    sc_set3(d.bounds_min, -1.5f, -1.5f, -1.5f);
    sc_set3(d.bounds_max, 1.5f, 1.5f, 1.5f);
    if (!CHECK_EQ_INT(irrvol_build(&d, &a), IRRVOL_OK)) return;
    d.radiance_user = (void *)(uintptr_t)&bright;
    if (!CHECK_EQ_INT(irrvol_build(&d, &b), IRRVOL_OK)) { irrvol_destroy(a); return; }
    irrvol_info(a, &info);
    irrvol_sample(a, centre, &si);
    CHECK(si.position[0] == 0.0f && si.position[1] == 0.0f && si.position[2] == 0.0f);
    CHECK_EQ_INT(si.state, IRRVOL_SAMPLE_INVALID);
    CHECK_EQ_INT(info.invalid_samples, 1);
    /* its values are its neighbours' mean (the room's furnace), not what it saw */
    irrvol_sample_values(b, centre, h, NULL);
    for (i = 0; i < info.bins; i++) CHECK_CLOSE(h[3 * i], PI * 0.5, 0.005, 0.0);
    for (i = 0; i < 3000; i++) {   /* inside the box, around it, everywhere: the same answers */
        float p[3], dir[3], ha[3], hb[3];
        int w;
        for (k = 0; k < 3; k++) p[k] = (i < 1000 ? 1.0f : 3.2f) * (frand() - 0.5f);
        random_dir(dir);
        for (w = 0; w < 3; w++) {
            irrvol_query_filter(a, (irrvol_filter)w, (irrvol_weighting)w, p, dir, ha);
            irrvol_query_filter(b, (irrvol_filter)w, (irrvol_weighting)w, p, dir, hb);
            different += memcmp(ha, hb, sizeof ha) != 0;
            irrvol_query_sh(a, 2, (irrvol_weighting)w, p, dir, ha);
            irrvol_query_sh(b, 2, (irrvol_weighting)w, p, dir, hb);
            different += memcmp(ha, hb, sizeof ha) != 0;
        }
    }
    test_note("sample in a closed box: invalid; 18,000 queries of two volumes that differ only inside the box: "
              "%u differ", different);
    CHECK_EQ_INT(different, 0);
    irrvol_destroy(a);
    irrvol_destroy(b);
}

/* ---- continuity across every first-level face -------------------------------- */

/* A 4 x 3 x 4 m room (surfaces radiance 0.2) with a lamp, a 0.4 m box of
   radiance 20 hanging from the ceiling on a cord: a strongly non-linear
   field, refined around the lamp, unrefined elsewhere. */
static void lamp_room(sc_scene *s, irrvol_material m[3])
{
    float lo[3], hi[3];
    memset(s, 0, sizeof *s);
    sc_set3(lo, 0, 0, 0); sc_set3(hi, 4, 3, 4);
    sc_box(s, lo, hi, 0, 1);
    sc_set3(lo, 1.45f, 2.0f, 1.75f); sc_set3(hi, 1.85f, 2.3f, 2.15f);
    sc_box(s, lo, hi, 1, 0);
    sc_set3(lo, 1.63f, 2.3f, 1.93f); sc_set3(hi, 1.67f, 3.0f, 1.97f);
    sc_box(s, lo, hi, 2, 0);
    memset(m, 0, 3 * sizeof *m);
    sc_set3(m[0].radiance, 0.2f, 0.2f, 0.2f);
    sc_set3(m[1].radiance, 20.0f, 18.0f, 14.0f);
    m[1].flags = IRRVOL_MATERIAL_IMPORTANT;
    sc_set3(m[2].radiance, 0.05f, 0.05f, 0.05f);
}

/* The query in a given cell at the given offsets: what either side of a
   face computes. mode 0..1: NEAREST, BILINEAR with the plain weights;
   2..3 the same leak-safe; 4: harmonics, leak-safe. */
static void query_in_cell(const irrvol *v, int mode, const uint32_t c[3], const float o[3], const float dir[3],
                          float rgb[3])
{
    irrvol__prepared q;
    float p[3];
    int d;
    for (d = 0; d < 3; d++) p[d] = v->lo[d] + ((float)c[d] + o[d]) / v->scale[d];
    irrvol__prepare_in_cell(v, mode < 2 || mode == 4 ? (mode == 4 ? IRRVOL_WEIGHTING_VISIBILITY : IRRVOL_WEIGHTING_TRILINEAR)
                                                     : IRRVOL_WEIGHTING_VISIBILITY, c, o, p, dir, &q);
    if (mode == 4) {
        float ylm[9], e[3] = {0, 0, 0};
        uint32_t i, j;
        irrvol__sh_basis(dir[0], dir[1], dir[2], ylm);
        for (i = 0; i < q.count; i++)
            for (j = 0; j < 27; j++) e[j % 3] += q.w[i] * v->sh[27 * (size_t)q.id[i] + j] * ylm[j / 3];
        for (d = 0; d < 3; d++) rgb[d] = e[d] * q.scale;
        return;
    }
    irrvol__direction_bins(v, mode % 2 ? IRRVOL_FILTER_BILINEAR : IRRVOL_FILTER_NEAREST, dir, &q);
    irrvol__finish(v, &q, rgb);
}

static void test_continuity_across_faces(void)
{
    sc_scene s;
    irrvol_material m[3];
    irrvol *v;
    irrvol_volume_info info;
    uint32_t c[3], axis, faces = 0, mixed = 0, points = 0, beyond = 0;
    double worst = 0.0;
    lamp_room(&s, m);
    if (!CHECK_EQ_INT(build_defaults(&s, m, 3, &v), IRRVOL_OK)) return;
    irrvol_info(v, &info);
    for (axis = 0; axis < 3; axis++)
        for (c[2] = 0; c[2] < v->cells[2] - (axis == 2); c[2]++)
            for (c[1] = 0; c[1] < v->cells[1] - (axis == 1); c[1]++)
                for (c[0] = 0; c[0] < v->cells[0] - (axis == 0); c[0]++) {
                    uint32_t n[3], i;
                    int mode;
                    memcpy(n, c, sizeof n);
                    n[axis]++;
                    faces++;
                    mixed += (v->refined[c[0] + v->cells[0] * (c[1] + v->cells[1] * c[2])] != 0) !=
                             (v->refined[n[0] + v->cells[0] * (n[1] + v->cells[1] * n[2])] != 0);
                    for (i = 0; i < 6; i++) {   /* points on the face, seen from both cells */
                        float o[3], on[3], dir[3];
                        o[0] = frand(); o[1] = frand(); o[2] = frand();
                        if (i == 0) { o[(axis + 1) % 3] = 0.5f; o[(axis + 2) % 3] = 0.5f; }   /* a hanging spot */
                        o[axis] = 1.0f;
                        memcpy(on, o, sizeof on);
                        on[axis] = 0.0f;
                        random_dir(dir);
                        for (mode = 0; mode < 5; mode++) {
                            float a[3], b[3];
                            int k;
                            query_in_cell(v, mode, c, o, dir, a);
                            query_in_cell(v, mode, n, on, dir, b);
                            for (k = 0; k < 3; k++) {
                                double scale = fabs(a[k]) > fabs(b[k]) ? fabs(a[k]) : fabs(b[k]);
                                double e = fabs(a[k] - b[k]) / (scale > 1e-3 ? scale : 1e-3);
                                if (e > worst) worst = e;
                                if (e > 1e-4) beyond++;
                            }
                            points++;
                        }
                    }
                }
    test_note("lamp room, defaults (%u samples, %u cells refined, %u of them for light, %u hanging samples): %u "
              "first-level faces, %u between a refined and an unrefined cell; %u points x 5 queries (nearest and "
              "bilinear, plain and leak-safe; harmonics), largest relative jump %.2g", info.sample_count,
              info.refined_cells, info.light_refined_cells, info.hanging_samples, faces, mixed, points / 5, worst);
    CHECK(mixed > 20 && info.hanging_samples > 0);   /* the test meets the seams it is about */
    CHECK_EQ_INT(beyond, 0);   /* float rounding: relative 1e-4 */
    irrvol_destroy(v);
}

/* A leak-safe query in a sub-cell with hanging corners weighs its eight
   distinct samples, each with the sum of its terms' weights: the same
   weights, up to float rounding, as weighing every term (each parent of a
   hanging corner on its own) and adding them per sample in double. */
static void test_merged_terms_weigh_like_every_term(void)
{
    sc_scene s;
    irrvol_material m[3];
    irrvol *v;
    uint32_t i, merged = 0, compared = 0;
    double worst = 0.0;
    lamp_room(&s, m);
    if (!CHECK_EQ_INT(build_defaults(&s, m, 3, &v), IRRVOL_OK)) return;
    for (i = 0; i < 20000; i++) {
        float p[3], n[3], x[3], vis[IRRVOL__MAX_TERMS];
        double per_sample[8] = {0, 0, 0, 0, 0, 0, 0, 0}, total = 0.0;
        irrvol__prepared q, terms;
        const irrvol__corners *rec;
        uint32_t k, j;
        int d;
        sc_set3(p, 8.4f * frand() - 4.2f, 3.2f * frand() - 0.1f, 4.2f * frand() - 0.1f);
        random_dir(n);
        irrvol__prepare_at(v, IRRVOL_WEIGHTING_VISIBILITY, p, n, &q);
        rec = irrvol__locate(v, p, terms.id, terms.w);
        if (!rec->hanging) continue;
        CHECK(rec->merged);   /* every record of this grid names at most eight samples */
        if (!rec->merged) break;
        merged++;
        terms.count = 8;
        irrvol__expand_hanging(v, rec, &terms);
        for (d = 0; d < 3; d++) x[d] = p[d] + v->bias * n[d];   /* random_dir: unit length */
        irrvol__visibility_weights(v, terms.id, terms.count, x, n, vis);
        for (k = 0; k < terms.count; k++) {
            double w = (double)terms.w[k] * vis[k];
            for (j = 0; j < 8 && rec->id[j] != terms.id[k]; j++) continue;
            if (!CHECK(j < 8)) break;   /* every term's sample is among the record's eight */
            per_sample[j] += w;
            total += w;
        }
        /* no sample visible (the weights sum below FLT_MIN): the plain weights stand; far above it, both sides
           renormalise */
        if (!(total > 1e-30)) continue;
        for (j = 0; j < 8; j++) {
            double e = fabs((double)q.w[j] * q.scale - per_sample[j] / total);
            if (e > worst) worst = e;
        }
        compared++;
    }
    test_note("lamp room: %u of 20,000 random leak-safe queries in sub-cells with hanging corners, %u compared; "
              "largest difference of a normalised weight %.2g", merged, compared, worst);
    CHECK(merged > 1000 && compared > 1000);
    /* float rounding: up to 4 products per sample and 8 sums in float, each off by 2^-24 at most */
    CHECK(worst < 1e-5);
    irrvol_destroy(v);
}

/* ---- refinement by light (6.1.1) ---------------------------------------------- */

/* A dark 6 x 3 x 6 m room lit by a 0.3 m square panel of radiance 50 facing
   down from 2.5 m (both sides emit, as the header's emitters do), nothing
   else: the exact irradiance at any point is the panel's integral. */
static void panel_room(sc_scene *s, irrvol_material m[2])
{
    float lo[3], hi[3];
    memset(s, 0, sizeof *s);
    sc_set3(lo, 0, 0, 0); sc_set3(hi, 6, 3, 6);
    sc_box(s, lo, hi, 0, 1);
    sc_square_facing(s, 1, 2.5f, 2.2f, 2.2f, 0.15f, 1, -1);
    memset(m, 0, 2 * sizeof *m);
    sc_set3(m[1].radiance, 50, 50, 50);
    m[1].flags = IRRVOL_MATERIAL_IMPORTANT;
}

/* Mean relative error of plain trilinear queries against the panel's
   integral at random points of the room's inner part, random directions. */
static double panel_error(const irrvol *v)
{
    double err = 0.0, total = 0.0;
    int i;
    rng_state = 99u;
    for (i = 0; i < 1500; i++) {
        float p[3], dir[3], h[3];
        double pd[3], nd[3], exact;
        sc_set3(p, 0.3f + 5.4f * frand(), 0.3f + 1.9f * frand(), 0.3f + 5.4f * frand());
        random_dir(dir);
        irrvol_query_filter(v, IRRVOL_FILTER_BILINEAR, IRRVOL_WEIGHTING_TRILINEAR, p, dir, h);
        pd[0] = p[0]; pd[1] = p[1]; pd[2] = p[2];
        nd[0] = dir[0]; nd[1] = dir[1]; nd[2] = dir[2];
        exact = sc_square_irradiance(pd, nd, 1, 2.5, 2.2, 2.2, 0.15, 50.0, 0.0, 24);
        err += fabs(h[0] - exact);
        total += exact;
    }
    return err / total;
}

static void test_refinement_by_light(void)
{
    sc_scene s;
    irrvol_material m[2];
    irrvol_desc d;
    irrvol *geometry, *light;
    irrvol_volume_info ig, il;
    ex_pool *pool = ex_pool_create(0);
    double eg, el;
    panel_room(&s, m);
    sc_scene_desc(&d, &s, m, 2);
    d.resolution = 9;
    d.parallel_for = ex_pool_parallel_for;
    d.parallel_user = pool;
    d.refine_threshold = -1.0f;   /* the thesis: only where geometry is */
    if (!CHECK_EQ_INT(irrvol_build(&d, &geometry), IRRVOL_OK)) { ex_pool_destroy(pool); return; }
    d.refine_threshold = 0.0f;    /* the default */
    if (!CHECK_EQ_INT(irrvol_build(&d, &light), IRRVOL_OK)) { irrvol_destroy(geometry); ex_pool_destroy(pool); return; }
    irrvol_info(geometry, &ig);
    irrvol_info(light, &il);
    eg = panel_error(geometry);
    el = panel_error(light);
    test_note("panel room, k = 9: refined by geometry %u cells, %u samples, %.2f MB, mean error %.1f %%; by light too "
              "%u cells (%u for light), %u samples, %.2f MB, mean error %.1f %%", ig.refined_cells, ig.sample_count,
              ig.bytes / 1e6, 100.0 * eg, il.refined_cells, il.light_refined_cells, il.sample_count, il.bytes / 1e6,
              100.0 * el);
    CHECK_EQ_INT(ig.light_refined_cells, 0);
    CHECK(il.light_refined_cells > 0 && il.refined_cells == ig.refined_cells + il.light_refined_cells);
    CHECK(il.bytes > ig.bytes);
    CHECK(el < 0.8 * eg);   /* the second level where the light changes pays */
    irrvol_destroy(geometry);
    irrvol_destroy(light);
    ex_pool_destroy(pool);
}

/* A furnace has nothing to refine; neither has a dark room. */
static void test_refinement_by_light_furnace(void)
{
    sc_scene s;
    irrvol_material m[2];
    irrvol_desc d;
    irrvol *v;
    irrvol_volume_info info;
    int lit;
    for (lit = 0; lit < 2; lit++) {
        panel_room(&s, m);
        sc_set3(m[0].radiance, (float)lit, (float)lit, (float)lit);
        sc_set3(m[1].radiance, (float)lit, (float)lit, (float)lit);
        sc_scene_desc(&d, &s, m, 2);
        d.resolution = 5;
        if (!CHECK_EQ_INT(irrvol_build(&d, &v), IRRVOL_OK)) return;
        irrvol_info(v, &info);
        CHECK_EQ_INT(info.light_refined_cells, 0);
        irrvol_destroy(v);
    }
}

/* ---- spherical harmonics ------------------------------------------------------ */

static void constant_radiance(void *user, const float org[3], const float dir[3], float rgb[3])
{
    const float *l = (const float *)user;
    (void)org; (void)dir;
    rgb[0] = l[0]; rgb[1] = l[1]; rgb[2] = l[2];
}

static void test_sh_furnace(void)
{
    static const float l[3] = {1.0f, 2.0f, 0.5f};
    irrvol_desc d;
    irrvol *v;
    uint32_t order;
    memset(&d, 0, sizeof d);
    d.radiance = constant_radiance;
    d.radiance_user = (void *)(uintptr_t)l;
    d.grid_samples[0] = d.grid_samples[1] = d.grid_samples[2] = 2;
    sc_set3(d.bounds_min, 0, 0, 0);
    sc_set3(d.bounds_max, 1, 1, 1);
    if (!CHECK_EQ_INT(irrvol_build(&d, &v), IRRVOL_OK)) return;
    for (order = 1; order <= 2; order++) {
        double worst = 0.0;
        int i, c;
        for (i = 0; i < 2000; i++) {
            float p[3], dir[3], h[3];
            sc_set3(p, frand(), frand(), frand());
            random_dir(dir);
            irrvol_query_sh(v, order, IRRVOL_WEIGHTING_DEFAULT, p, dir, h);
            for (c = 0; c < 3; c++)
                if (fabs(h[c] / (PI * l[c]) - 1.0) > worst) worst = fabs(h[c] / (PI * l[c]) - 1.0);
        }
        test_note("furnace through the harmonics, L%u: largest |E - pi L| / pi L = %.3g %%", order, 100.0 * worst);
        CHECK(worst < 0.005);   /* the acceptance bound */
    }
    irrvol_destroy(v);
}

/* A single small light: the harmonics of E hold its cosine lobe to l = 2
   (Ramamoorthi and Hanrahan: E_lm = A_l L_lm), so facing it they give
   (1/4 + 1/2 + 5/16) / 1 = 1.0625 times the exact value... and the bins the
   exact value; L1 gives (1/4 + 1/2) = 0.75 of it. Seen from the centre of a
   dark cube, a 0.02 m lamp at 0.95 m is a near-point source. */
static void test_sh_point_light(void)
{
    sc_scene s;
    irrvol_material m[2];
    irrvol_desc d;
    irrvol *v;
    float c[3] = {0, 0, 0}, up[3] = {0, 1, 0}, side[3] = {1, 0, 0}, hb[3], h1[3], h2[3], hs[3];
    sc_cube(&s);
    memset(s.mat, 0, sizeof s.mat);
    sc_square_facing(&s, 1, 0.95f, 0.0f, 0.0f, 0.01f, 1, -1);
    memset(m, 0, sizeof m);
    sc_set3(m[1].radiance, 1000, 1000, 1000);
    m[1].flags = IRRVOL_MATERIAL_IMPORTANT;
    sc_scene_desc(&d, &s, m, 2);
    d.grid_samples[0] = d.grid_samples[1] = d.grid_samples[2] = 3;
    sc_set3(d.bounds_min, -0.5f, -0.5f, -0.5f);
    sc_set3(d.bounds_max, 0.5f, 0.5f, 0.5f);
    if (!CHECK_EQ_INT(irrvol_build(&d, &v), IRRVOL_OK)) return;
    irrvol_query(v, c, up, hb);
    irrvol_query_sh(v, 1, IRRVOL_WEIGHTING_DEFAULT, c, up, h1);
    irrvol_query_sh(v, 2, IRRVOL_WEIGHTING_DEFAULT, c, up, h2);
    irrvol_query_sh(v, 2, IRRVOL_WEIGHTING_DEFAULT, c, side, hs);
    test_note("near-point light overhead: bins %.4f, L1 %.4f (%.4f of it), L2 %.4f (%.4f); sideways L2 %.4f of the "
              "overhead value", hb[0], h1[0], h1[0] / hb[0], h2[0], h2[0] / hb[0], hs[0] / hb[0]);
    CHECK_CLOSE(h1[0] / hb[0], 0.75, 0.01, 0.0);     /* the lamp's 0.6 degrees blur the lobe by 1e-4 */
    CHECK_CLOSE(h2[0] / hb[0], 1.0625, 0.01, 0.0);
    /* sideways: cos 90 = 0, the L2 lobe there: 1/4 - 5/32 = 0.09375 */
    CHECK_CLOSE(hs[0] / hb[0], 0.09375, 0.02, 0.002);
    irrvol_destroy(v);
}

/* The SSE2 weights of four samples at once equal the scalar definition's,
   bit for bit, on the two rooms' relocated samples and everywhere else. */
static void test_simd_visibility_is_scalar(void)
{
#ifdef IRRVOL__SSE2
    sc_scene s;
    irrvol_material m[2];
    irrvol_desc d;
    irrvol *v;
    uint32_t i, differ = 0, visible = 0, near = 0, records = 0, merged = 0, clear = 0;
    two_rooms(&s, m);
    sc_scene_desc(&d, &s, m, 2);
    d.resolution = 5;
    d.visibility_resolution = 6;
    if (!CHECK_EQ_INT(irrvol_build(&d, &v), IRRVOL_OK)) return;
    for (i = 0; i < 20000; i++) {
        float x[3], n[3], four[4];
        uint32_t id[4], k;
        sc_set3(x, 8.4f * frand() - 4.2f, 3.2f * frand() - 0.1f, 4.2f * frand() - 0.1f);
        random_dir(n);
        for (k = 0; k < 4; k++) id[k] = (uint32_t)(frand() * (float)v->hanging_begin) % v->hanging_begin;
        if (i % 100 == 0) memcpy(x, v->origins + 4 * (size_t)id[1], 3 * sizeof(float));   /* at a sample: r = 0 */
        {   /* the SSE2 steps */
            irrvol__point4 p = irrvol__point4_set(x, n);
            irrvol__lanes4 l;
            irrvol__lanes4_locate_samples(v, id, &p, &l);
            irrvol__lanes4_fetch(v, &l);
            irrvol__lanes4_weigh(&l, four);
            for (k = 0; k < 4; k++) near += l.near >> k & 1;
        }
        for (k = 0; k < 4; k++) {
            float one = irrvol__visibility_weight(v, id[k], x, n);
            differ += memcmp(&one, &four[k], sizeof one) != 0;
            visible += one > 0.5f;
        }
        {   /* a sub-cell's record read by irrvol__corner_weights: its corners' weights, as scalar */
            const irrvol__cell *cell = &v->cell[(uint32_t)(frand() * (float)v->cell_count) % v->cell_count];
            uint32_t f = cell->side - 1, sub = (uint32_t)(frand() * (float)(f * f * f)) % (f * f * f);
            const irrvol__corners *r = v->corners + cell->corners + sub;
            float eight[8], in[3];
            uint32_t corner[8];
            int d;
            if (r->hanging && !r->merged) continue;   /* merged: its eight distinct samples, probes in the record */
            records++;
            merged += r->merged != 0;
            irrvol__corner_weights(v, r, 0u, x, n, NULL, 0u, eight);
            for (k = 0; k < 8; k++) {
                float one = irrvol__visibility_weight(v, r->id[k], x, n);
                differ += memcmp(&one, &eight[k], sizeof one) != 0;
            }
            /* a test point in the sub-cell, which may skip the maps of the samples its clear mask names */
            irrvol__table_corners(v, cell, sub % f, sub / f % f, sub / (f * f), corner);
            for (d = 0; d < 3; d++) {
                float lo = v->positions[3 * (size_t)corner[0] + d], hi = v->positions[3 * (size_t)corner[7] + d];
                in[d] = lo + frand() * (hi - lo) + v->bias * n[d];
            }
            irrvol__corner_weights(v, r, r->clear, in, n, NULL, 0u, eight);
            for (k = 0; k < 8; k++) {
                float one = irrvol__visibility_weight(v, r->id[k], in, n);
                differ += memcmp(&one, &eight[k], sizeof one) != 0;
                clear += r->clear >> k & 1;
            }
        }
    }
    test_note("SSE2 visibility weights vs the scalar code: %u of %u differ (%u of the 80,000 random ones above 0.5, "
              "%u within their sample's reach; %u records with hanging corners; %u weights in their sub-cell, %u "
              "of them with the map skipped)", differ, 80000 + 16 * records, visible, near, merged, 8 * records, clear);
    CHECK_EQ_INT(differ, 0);
    CHECK(visible > 1000 && visible < 79000);   /* both visible and hidden samples were compared */
    CHECK(near > 200 && near < 79000);          /* and both sides of the reach (806 measured) */
    CHECK(records > 1000);
    CHECK(merged > 100);   /* sub-cells with hanging corners among them (their eight samples) */
    CHECK(clear > 1000 && clear < 8 * records);   /* maps skipped and read in sub-cells */
    irrvol_destroy(v);
#else
    test_note("no SSE2 here: the scalar code is the only one");
#endif
}

int main(int argc, char **argv)
{
    TEST_INIT(argc, argv);
    RUN(test_leak_through_thin_wall);
    RUN(test_relocation_out_of_wall);
    RUN(test_sample_in_closed_box);
    RUN(test_continuity_across_faces);
    RUN(test_merged_terms_weigh_like_every_term);
    RUN(test_refinement_by_light);
    RUN(test_refinement_by_light_furnace);
    RUN(test_sh_furnace);
    RUN(test_sh_point_light);
    RUN(test_simd_visibility_is_scalar);
    return test_finish();
}
