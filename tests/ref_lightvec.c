/* Reference tests of lightvec.h against Embree (tests/reference):
   - the built-in BVH agrees with Embree on random rays, and a gather through
     an Embree trace callback equals the built-in one;
   - the built-in renderer's direct + indirect irradiance (many bounces)
     equals the reference path tracer's global illumination;
   - the cache on the Cornell box walls: interpolated indirect radiance
     against gathering at every point, mean relative error below 5% with the
     default parameters, hit rate reported; a second, moved camera reuses the
     cache through the directional criterion;
   - a glossy Cornell floor (0.3 Lambert + 0.4 normalized Phong, exponent 20)
     seen by a camera that moves 15 cm, then turns 10 degrees: mean error at
     most 5% against a converged gather at a hit rate of at least 85%; a
     purely glossy floor (specular 0.7): median error at most 10% after the
     move, every value finite. */
#define LIGHTVEC_IMPLEMENTATION
#include "lightvec.h"
#include "tests/reference/ref.h"
#include "examples/common/camera.h"
#include "tests/test.h"

#define PI 3.14159265358979323846

static obj_scene g_obj;
static lightvec_material *g_mats;
static lightvec_scene *g_scene;      /* built-in BVH */
static lightvec_scene *g_scene_rtc;  /* Embree through the trace callback */
static ref_scene *g_ref;

static int embree_trace(void *user, const float org[3], const float dir[3], float tmax, lightvec_hit *hit)
{
    ref_hit h;
    if (!ref_intersect((const ref_scene *)user, org, dir, 0.0f, tmax, &h)) return 0;
    hit->t = h.t;
    hit->u = h.u;
    hit->v = h.v;
    hit->triangle = h.tri;
    return 1;
}

static int setup(void)
{
    char err[256];
    lightvec_scene_desc d;
    uint32_t i;
    if (g_scene) return 1;
    if (!CHECK_MSG(obj_load("examples/data/cornell_box.obj", &g_obj, err, sizeof err) == 0, "%s", err)) return 0;
    g_mats = (lightvec_material *)calloc(g_obj.material_count, sizeof *g_mats);
    for (i = 0; i < g_obj.material_count; i++) {
        memcpy(g_mats[i].diffuse, g_obj.materials[i].kd, sizeof g_mats[i].diffuse);
        memcpy(g_mats[i].specular, g_obj.materials[i].ks, sizeof g_mats[i].specular);
        memcpy(g_mats[i].emission, g_obj.materials[i].ke, sizeof g_mats[i].emission);
        g_mats[i].exponent = g_obj.materials[i].ns;
    }
    memset(&d, 0, sizeof d);
    d.positions = g_obj.positions;
    d.vertex_count = g_obj.vertex_count;
    d.indices = g_obj.tri_indices;
    d.triangle_count = g_obj.tri_count;
    d.material_ids = g_obj.tri_material;
    d.materials = g_mats;
    d.material_count = g_obj.material_count;
    g_ref = ref_scene_from_obj(&g_obj);
    if (!CHECK(g_ref != NULL) || !CHECK(lightvec_scene_create(&d, &g_scene) == LIGHTVEC_OK)) return 0;
    d.trace = embree_trace;
    d.trace_user = g_ref;
    return CHECK(lightvec_scene_create(&d, &g_scene_rtc) == LIGHTVEC_OK);
}

static double rnd(uint64_t *s)
{
    *s = *s * 6364136223846793005ull + 1442695040888963407ull;
    return (double)(*s >> 11) * (1.0 / 9007199254740992.0);
}

static float lum(const float *c) { return 0.2126f * c[0] + 0.7152f * c[1] + 0.0722f * c[2]; }

/* ---- the built-in BVH and Embree ---------------------------------------------------- */

static void test_bvh_matches_embree(void)
{
    uint64_t s = 1;
    int i, disagree = 0, hits = 0;
    if (!setup()) return;
    for (i = 0; i < 20000; i++) {
        float org[3], dir[3];
        lightvec_hit a;
        ref_hit b;
        int k, ha, hb;
        for (k = 0; k < 3; k++) {
            org[k] = (float)(-0.2 + 1.0 * rnd(&s));
            dir[k] = (float)(rnd(&s) - 0.5);
        }
        ha = lightvec_scene_intersect(g_scene, org, dir, 1e30f, &a);
        hb = ref_intersect(g_ref, org, dir, 0.0f, 1e30f, &b);
        hits += ha;
        /* rays through a shared edge may report either triangle: compare t;
           1e-4 relative plus 1e-6 absolute covers float error in t */
        if (ha != hb || (ha && fabsf(a.t - b.t) > 1e-4f * b.t + 1e-6f)) disagree++;
    }
    test_note("BVH vs Embree: %d of 20000 rays disagree (%d hits)", disagree, hits);
    CHECK(hits > 5000);
    CHECK(disagree <= 2); /* grazing rays along a face may differ */
}

/* The same gather through the built-in BVH and through Embree. */
static void test_gather_through_embree(void)
{
    lightvec_gather_desc gd;
    lightvec_surface sf;
    float pts[3][3] = { { 0.3f, 0.0f, 0.3f }, { 0.0f, 0.3f, 0.3f }, { 0.28f, 0.3f, 0.559f } };
    float nrm[3][3] = { { 0, 1, 0 }, { 1, 0, 0 }, { 0, 0, -1 } };
    int i, c;
    if (!setup()) return;
    memset(&gd, 0, sizeof gd);
    memset(&sf, 0, sizeof sf);
    sf.material = g_mats[1];
    sf.flags = LIGHTVEC_RECORD_VIEW_INDEPENDENT;
    for (i = 0; i < 3; i++) {
        lightvec_record a, b;
        memcpy(sf.position, pts[i], sizeof sf.position);
        memcpy(sf.normal, nrm[i], sizeof sf.normal);
        CHECK(lightvec_gather(g_scene, &gd, &sf, (uint64_t)i, &a) == LIGHTVEC_OK);
        CHECK(lightvec_gather(g_scene_rtc, &gd, &sf, (uint64_t)i, &b) == LIGHTVEC_OK);
        /* same random numbers, same rays: only float differences in hit
           distances can move a sample */
        for (c = 0; c < 3; c++) CHECK_CLOSE(a.irradiance[c], b.irradiance[c], 1e-3, 1e-6);
        CHECK_CLOSE(a.distance, b.distance, 1e-3, 0);
    }
}

/* ---- the built-in renderer against the reference path tracer -------------------------- */

static void test_renderer_matches_reference_gi(void)
{
    lightvec_gather_desc gd, dd;
    lightvec_surface sf;
    float pts[4][3] = { { 0.45f, 0.0f, 0.12f }, { 0.0f, 0.35f, 0.2f }, { 0.2f, 0.45f, 0.559f }, { 0.4f, 0.5488f, 0.45f } };
    float nrm[4][3] = { { 0, 1, 0 }, { 1, 0, 0 }, { 0, 0, -1 }, { 0, -1, 0 } };
    int i, c;
    if (!setup()) return;
    memset(&gd, 0, sizeof gd);
    gd.strata_theta = 48;   /* 6912 rays */
    gd.bounces = 12;        /* what is left after 12 bounces is below 0.1% here */
    gd.light_samples = 2;
    dd = gd;
    dd.strata_theta = dd.strata_phi = 64;
    memset(&sf, 0, sizeof sf);
    sf.material = g_mats[1];
    sf.flags = LIGHTVEC_RECORD_VIEW_INDEPENDENT;
    for (i = 0; i < 4; i++) {
        lightvec_record ind, dir;
        ref_estimate e;
        memcpy(sf.position, pts[i], sizeof sf.position);
        memcpy(sf.normal, nrm[i], sizeof sf.normal);
        CHECK(lightvec_gather(g_scene, &gd, &sf, (uint64_t)i, &ind) == LIGHTVEC_OK);
        CHECK(lightvec_gather_direct(g_scene, &dd, &sf, (uint64_t)i, &dir) == LIGHTVEC_OK);
        e = ref_irradiance_gi(g_ref, sf.position, sf.normal, 200000, 100 + (uint64_t)i);
        test_note("point %d: direct %.3f + indirect %.3f = %.3f, reference GI %.3f +- %.3f", i, dir.irradiance[0],
                  ind.irradiance[0], dir.irradiance[0] + ind.irradiance[0], e.mean[0], e.std_error[0]);
        for (c = 0; c < 3; c++)
            /* 4 standard errors of the reference plus 3% for the noise of
               the stratified gathers (a few thousand rays each) */
            CHECK_CLOSE(dir.irradiance[c] + ind.irradiance[c], e.mean[c], 0.03, 4 * e.std_error[c]);
    }
}

/* ---- the cache on the Cornell box ---------------------------------------------------------- */

#define RES 128    /* the walls' test */
#define GRES 256   /* the glossy floors' */

typedef struct pixel { int valid, wall, floor; lightvec_surface s; } pixel;

/* A scene to render: the Cornell box as loaded, or with another floor. */
typedef struct box_view {
    const lightvec_scene *scene;
    const lightvec_material *mats;
    const uint32_t *tri_mat;
} box_view;

static box_view plain_box(void)
{
    box_view v;
    v.scene = g_scene;
    v.mats = g_mats;
    v.tri_mat = g_obj.tri_material;
    return v;
}

/* Primary hits of a res x res camera (front faces, emitters skipped); walls
   are floor, ceiling and the three walls. */
static void trace_pixels(const box_view *v, const float eye[3], const float target[3], int res, pixel *px)
{
    float up[3] = { 0, 1, 0 };
    ex_camera cam = ex_camera_look_at(eye, target, up, 39.3f, res, res);
    const char *walls[5] = { "floor", "ceiling", "back_wall", "left_wall", "right_wall" };
    int wall_group[5], x, y, k;
    for (k = 0; k < 5; k++) wall_group[k] = obj_find_group(&g_obj, walls[k]);
    for (y = 0; y < res; y++)
        for (x = 0; x < res; x++) {
            pixel *p = &px[y * res + x];
            lightvec_hit h;
            float d[3], e1[3], e2[3], n[3], l;
            const float *a, *b, *c;
            uint32_t t, m, g;
            memset(p, 0, sizeof *p);
            ex_camera_ray(&cam, (float)x + 0.5f, (float)y + 0.5f, d);
            if (!lightvec_scene_intersect(v->scene, cam.eye, d, 1e30f, &h)) continue;
            t = h.triangle;
            a = g_obj.positions + 3 * g_obj.tri_indices[3 * t];
            b = g_obj.positions + 3 * g_obj.tri_indices[3 * t + 1];
            c = g_obj.positions + 3 * g_obj.tri_indices[3 * t + 2];
            for (k = 0; k < 3; k++) { e1[k] = b[k] - a[k]; e2[k] = c[k] - a[k]; }
            n[0] = e1[1] * e2[2] - e1[2] * e2[1];
            n[1] = e1[2] * e2[0] - e1[0] * e2[2];
            n[2] = e1[0] * e2[1] - e1[1] * e2[0];
            l = sqrtf(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
            m = v->tri_mat[t];
            if (n[0] * d[0] + n[1] * d[1] + n[2] * d[2] >= 0 || lum(v->mats[m].emission) > 0) continue;
            for (k = 0; k < 3; k++) {
                p->s.position[k] = cam.eye[k] + h.t * d[k];
                p->s.normal[k] = n[k] / l;
                p->s.outgoing[k] = -d[k];
            }
            p->s.material = v->mats[m];
            g = g_obj.face_group[g_obj.tri_face[t]];
            for (k = 0; k < 5; k++) p->wall |= (int)g == wall_group[k];
            p->floor = (int)g == wall_group[0];
            p->valid = 1;
        }
}

typedef struct pass_stats { uint32_t visible, hits, floor, floor_hits, nonfinite; } pass_stats;

/* Figure 2 over the image in a random order (the paper's remedy against
   scan-line bias): lookup, else gather (default parameters) and insert.
   Fills rgb. */
static pass_stats cache_pass(const box_view *v, lightvec_cache *cache, const pixel *px, int res, float *rgb,
                             uint64_t seed)
{
    static uint32_t order[GRES * GRES];
    uint32_t i, n = (uint32_t)(res * res);
    lightvec_gather_desc gd;
    pass_stats st;
    uint64_t s = seed;
    memset(&st, 0, sizeof st);
    memset(&gd, 0, sizeof gd);
    for (i = 0; i < n; i++) order[i] = i;
    for (i = n - 1; i > 0; i--) {
        uint32_t j = (uint32_t)(rnd(&s) * (i + 1)), t = order[i];
        order[i] = order[j];
        order[j] = t;
    }
    for (i = 0; i < n; i++) {
        uint32_t k = order[i];
        const pixel *p = &px[k];
        lightvec_lookup_result lr;
        if (!p->valid) continue;
        st.visible++;
        CHECK(lightvec_lookup(cache, p->s.position, p->s.normal, p->s.outgoing, &lr) == LIGHTVEC_OK);
        if (!lr.hit) {
            lightvec_record rec;
            CHECK(lightvec_gather(v->scene, &gd, &p->s, seed * 1000003u + k, &rec) == LIGHTVEC_OK);
            CHECK(lightvec_insert(cache, &rec, NULL) == LIGHTVEC_OK);
            lr.vector = rec.vector;
        }
        st.hits += (uint32_t)lr.hit;
        st.floor += (uint32_t)p->floor;
        st.floor_hits += (uint32_t)(p->floor && lr.hit);
        lightvec_radiance(&p->s.material, p->s.normal, p->s.outgoing, &lr.vector, rgb + 3 * k);
        st.nonfinite += !(isfinite(rgb[3 * k]) && isfinite(rgb[3 * k + 1]) && isfinite(rgb[3 * k + 2]));
    }
    return st;
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

/* Relative luminance errors of rgb over `count` random pixels (the floor's
   when floor_only, else the walls') against gathers of gd. Returns the mean;
   *median gets the median. */
static double pixel_error(const box_view *v, const pixel *px, int res, const float *rgb, int floor_only,
                          const lightvec_gather_desc *gd, uint32_t count, uint64_t seed, double *median)
{
    static double err[1000];
    uint64_t s = seed;
    uint32_t n = 0, tries = 0, all = (uint32_t)(res * res);
    double sum = 0;
    while (n < count && n < 1000 && tries++ < 100 * count) {
        uint32_t k = (uint32_t)(rnd(&s) * all) % all;
        lightvec_record rec;
        float ref[3];
        if (!px[k].valid || !(floor_only ? px[k].floor : px[k].wall)) continue;
        CHECK(lightvec_gather(v->scene, gd, &px[k].s, k, &rec) == LIGHTVEC_OK);
        lightvec_radiance(&px[k].s.material, px[k].s.normal, px[k].s.outgoing, &rec.vector, ref);
        err[n] = fabs(lum(rgb + 3 * k) - lum(ref)) / lum(ref);
        sum += err[n++];
    }
    qsort(err, n, sizeof *err, cmp_double);
    if (median) *median = n ? err[n / 2] : 1.0;
    return n ? sum / n : 1.0;
}

/* Mean relative luminance error on wall pixels against gathering at every
   point (strata: 0 = the defaults), over `count` random wall pixels. */
static double wall_error(const pixel *px, const float *rgb, uint32_t strata, uint32_t count, uint64_t seed)
{
    box_view v = plain_box();
    lightvec_gather_desc gd;
    memset(&gd, 0, sizeof gd);
    gd.strata_theta = strata;
    gd.seed = seed;
    return pixel_error(&v, px, RES, rgb, 0, &gd, count, seed, NULL);
}

static pixel g_px[GRES * GRES];
static float g_rgb[GRES * GRES * 3];

static void test_cornell_walls_cache_error(void)
{
    float eye[3] = { 0.278f, 0.273f, -0.8f }, target[3] = { 0.278f, 0.273f, 0.0f };
    lightvec_cache *cache = NULL;
    lightvec_cache_stats st;
    box_view v;
    pass_stats ps;
    double err_gather, err_converged;
    if (!setup()) return;
    v = plain_box();
    if (!CHECK(lightvec_cache_create(NULL, &cache) == LIGHTVEC_OK)) return;
    trace_pixels(&v, eye, target, RES, g_px);
    ps = cache_pass(&v, cache, g_px, RES, g_rgb, 1);
    lightvec_cache_info(cache, &st);
    err_gather = wall_error(g_px, g_rgb, 0, 600, 77);
    err_converged = wall_error(g_px, g_rgb, 60, 150, 78); /* 60 x 180 strata: about 1% noise */
    test_note("Cornell %dx%d, defaults: hit rate %.1f%% (%llu records for %u pixels)", RES, RES,
              100.0 * ps.hits / ps.visible, (unsigned long long)st.record_count, ps.visible);
    test_note("walls: mean relative error %.2f%% vs. gathering at every point (defaults), %.2f%% vs. a converged "
              "gather", 100 * err_gather, 100 * err_converged);
    CHECK(err_gather < 0.05);
    CHECK(err_converged < 0.05);
    CHECK(ps.hits > ps.visible * 8 / 10);

    /* a moved camera (4 cm right, 2 degrees turned): the cache keeps serving
       the parts seen from nearly the same direction */
    {
        float eye2[3] = { 0.318f, 0.273f, -0.8f }, target2[3] = { 0.29f, 0.273f, 0.0f };
        trace_pixels(&v, eye2, target2, RES, g_px);
        ps = cache_pass(&v, cache, g_px, RES, g_rgb, 2);
        err_gather = wall_error(g_px, g_rgb, 0, 300, 79);
        test_note("moved camera: hit rate %.1f%%, wall error %.2f%% vs. gathering", 100.0 * ps.hits / ps.visible,
                  100 * err_gather);
        CHECK(ps.hits > ps.visible * 9 / 10); /* the first frame's records are reused */
        CHECK(err_gather < 0.05);
    }
    lightvec_cache_destroy(cache);
}

/* ---- a glossy floor ---------------------------------------------------------------------- */

typedef struct glossy_frame { float eye[3], target[3]; } glossy_frame;

static lightvec_scene *g_glossy_scene;
static lightvec_material g_glossy_mats[16];
static uint32_t *g_glossy_tri_mat;

/* The Cornell box with its floor made of material `floor` (an extra material). */
static int glossy_setup(const lightvec_material *floor, box_view *v)
{
    lightvec_scene_desc d;
    uint32_t i, fm = g_obj.material_count;
    int fg = obj_find_group(&g_obj, "floor");
    lightvec_scene_destroy(g_glossy_scene);
    g_glossy_scene = NULL;
    if (!CHECK(fm < 16)) return 0;
    memcpy(g_glossy_mats, g_mats, fm * sizeof *g_mats);
    g_glossy_mats[fm] = *floor;
    if (!g_glossy_tri_mat) g_glossy_tri_mat = (uint32_t *)malloc(g_obj.tri_count * sizeof(uint32_t));
    if (!CHECK(g_glossy_tri_mat != NULL)) return 0;
    for (i = 0; i < g_obj.tri_count; i++)
        g_glossy_tri_mat[i] = (int)g_obj.face_group[g_obj.tri_face[i]] == fg ? fm : g_obj.tri_material[i];
    memset(&d, 0, sizeof d);
    d.positions = g_obj.positions;
    d.vertex_count = g_obj.vertex_count;
    d.indices = g_obj.tri_indices;
    d.triangle_count = g_obj.tri_count;
    d.material_ids = g_glossy_tri_mat;
    d.materials = g_glossy_mats;
    d.material_count = fm + 1;
    if (!CHECK(lightvec_scene_create(&d, &g_glossy_scene) == LIGHTVEC_OK)) return 0;
    v->scene = g_glossy_scene;
    v->mats = g_glossy_mats;
    v->tri_mat = g_glossy_tri_mat;
    return 1;
}

/* Relative errors of the floor against a converged gather: 60 x 180 strata
   and 8,192 lobe rays. Two such gathers differ by 1.8% (mean, 0.3 Lambert +
   0.4 gloss) and 3.2% (pure gloss): each is within about 1.3% and 2.3%. */
static double floor_error(const box_view *v, uint32_t count, uint64_t seed, double *median)
{
    lightvec_gather_desc gd;
    memset(&gd, 0, sizeof gd);
    gd.strata_theta = 60;
    gd.glossy_samples = 8192;
    gd.seed = seed;
    return pixel_error(v, g_px, GRES, g_rgb, 1, &gd, count, seed, median);
}

/* The three frames: the Cornell camera, moved 15 cm to the right, then
   turned 10 degrees to the left about the vertical. */
static void glossy_frames(glossy_frame fr[3])
{
    double a = 10.0 * PI / 180.0;
    int k;
    for (k = 0; k < 3; k++) {
        fr[k].eye[0] = k ? 0.428f : 0.278f;
        fr[k].eye[1] = 0.273f;
        fr[k].eye[2] = -0.8f;
        fr[k].target[0] = fr[k].eye[0];
        fr[k].target[1] = 0.273f;
        fr[k].target[2] = 0.0f;
    }
    fr[2].target[0] = fr[2].eye[0] - 0.8f * (float)sin(a);
    fr[2].target[2] = fr[2].eye[2] + 0.8f * (float)cos(a);
}

static void test_glossy_floor(void)
{
    lightvec_material floor;
    lightvec_cache *cache = NULL;
    glossy_frame fr[3];
    box_view v;
    int f;
    if (!setup()) return;
    memset(&floor, 0, sizeof floor);
    floor.diffuse[0] = floor.diffuse[1] = floor.diffuse[2] = 0.3f;
    floor.specular[0] = floor.specular[1] = floor.specular[2] = 0.4f;
    floor.exponent = 20.0f;
    if (!glossy_setup(&floor, &v) || !CHECK(lightvec_cache_create(NULL, &cache) == LIGHTVEC_OK)) return;
    glossy_frames(fr);
    for (f = 0; f < 3; f++) {
        pass_stats st;
        double mean, median;
        trace_pixels(&v, fr[f].eye, fr[f].target, GRES, g_px);
        st = cache_pass(&v, cache, g_px, GRES, g_rgb, 1 + (uint64_t)f);
        mean = floor_error(&v, 300, 100 + (uint64_t)f, &median);
        test_note("glossy floor, frame %d (%s): hit rate %.1f%% (floor %.1f%%), floor error mean %.2f%% median %.2f%%",
                  f + 1, f == 0 ? "first" : f == 1 ? "moved 15 cm" : "turned 10 degrees", 100.0 * st.hits / st.visible,
                  100.0 * st.floor_hits / st.floor, 100 * mean, 100 * median);
        CHECK_EQ_INT(st.nonfinite, 0);
        if (f == 0) continue; /* the acceptance is on the frames that reuse the cache */
        CHECK(mean <= 0.05);
        CHECK(st.hits >= st.visible * 85 / 100);
    }
    lightvec_cache_destroy(cache);
}

static void test_pure_glossy_floor(void)
{
    lightvec_material floor;
    lightvec_cache *cache = NULL;
    glossy_frame fr[3];
    pass_stats st;
    box_view v;
    double mean, median;
    if (!setup()) return;
    memset(&floor, 0, sizeof floor);
    floor.specular[0] = floor.specular[1] = floor.specular[2] = 0.7f;
    floor.exponent = 20.0f;
    if (!glossy_setup(&floor, &v) || !CHECK(lightvec_cache_create(NULL, &cache) == LIGHTVEC_OK)) return;
    glossy_frames(fr);
    trace_pixels(&v, fr[0].eye, fr[0].target, GRES, g_px);
    st = cache_pass(&v, cache, g_px, GRES, g_rgb, 1);
    CHECK_EQ_INT(st.nonfinite, 0);
    trace_pixels(&v, fr[1].eye, fr[1].target, GRES, g_px);
    st = cache_pass(&v, cache, g_px, GRES, g_rgb, 2);
    mean = floor_error(&v, 300, 101, &median);
    test_note("purely glossy floor, moved 15 cm: hit rate %.1f%% (floor %.1f%%), floor error median %.2f%% (mean %.2f%%)",
              100.0 * st.hits / st.visible, 100.0 * st.floor_hits / st.floor, 100 * median, 100 * mean);
    CHECK_EQ_INT(st.nonfinite, 0);
    CHECK(median <= 0.10);
    lightvec_cache_destroy(cache);
}

int main(int argc, char **argv)
{
    TEST_INIT(argc, argv);
    RUN(test_bvh_matches_embree);
    RUN(test_gather_through_embree);
    RUN(test_renderer_matches_reference_gi);
    RUN(test_cornell_walls_cache_error);
    RUN(test_glossy_floor);
    RUN(test_pure_glossy_floor);
    lightvec_scene_destroy(g_scene);
    lightvec_scene_destroy(g_glossy_scene);
    free(g_glossy_tri_mat);
    lightvec_scene_destroy(g_scene_rtc);
    ref_scene_destroy(g_ref);
    free(g_mats);
    obj_free(&g_obj);
    return test_finish();
}
