/* irrvol.h against the Embree reference (tests/reference): the built-in BVH
   hits the same triangles at the same distances; irradiance at the samples
   equals a Monte Carlo estimate of the same radiance field; the error of
   interpolated queries between samples on the office scene (a table). */
#define IRRVOL_IMPLEMENTATION
#include "irrvol.h"
#include "tests/test.h"
#include "tests/reference/ref.h"
#include "tests/ref_irrvol_scene.h"
#include "examples/common/pool.h"

static office_scene scene;
static ref_scene *reference;
static ex_pool *pool;

static uint64_t rng_state = 0x9E3779B97F4A7C15ull;
static double frand(void)
{
    rng_state = rng_state * 6364136223846793005ull + 1442695040888963407ull;
    return (double)(rng_state >> 11) * (1.0 / 9007199254740992.0);
}
static void random_dir(float d[3])
{
    double z = 2.0 * frand() - 1.0, phi = 2.0 * 3.14159265358979323846 * frand(), s = sqrt(1.0 - z * z);
    d[0] = (float)(s * cos(phi)); d[1] = (float)(s * sin(phi)); d[2] = (float)z;
}

static void test_bvh_matches_embree(void)
{
    irrvol__bvh bvh;
    irrvol__mesh_view m;
    irrvol_allocator a;
    uint32_t i, n = 100000, hits = 0, same = 0, tie = 0, wrong = 0;
    rng_state = 1;
    memset(&a, 0, sizeof a);
    m.positions = scene.positions;
    m.stride = 0;
    m.indices = scene.indices;
    m.tri_count = scene.tri_count;
    if (!CHECK(irrvol__bvh_build(&bvh, &m, &a) == 0)) return;
    for (i = 0; i < n; i++) {
        float o[3], d[3];
        irrvol__hit h;
        ref_hit r;
        int mine, theirs;
        o[0] = (float)(5.0 * frand()); o[1] = (float)(2.8 * frand()); o[2] = (float)(4.0 * frand());
        random_dir(d);
        mine = irrvol__bvh_intersect(&bvh, o, d, 0.0f, FLT_MAX, &h);
        theirs = ref_intersect(reference, o, d, 0.0f, FLT_MAX, &r);
        if (mine != theirs) { wrong++; continue; }
        if (!mine) { same++; continue; }
        hits++;
        /* rays from within 0.1 mm of a 5 m triangle carry that much float error in t */
        if (fabsf(h.t - r.t) > 1e-4f * r.t + 1e-6f) { wrong++; continue; }
        if (h.tri == r.tri) same++;
        else tie++;   /* same distance, another triangle: an edge shared by both */
    }
    test_note("BVH vs Embree, %u random rays over office + bunny (%u triangles): %u hit, %u identical, "
              "%u edge ties, %u different", n, scene.tri_count, hits, same, tie, wrong);
    CHECK_EQ_INT(wrong, 0);
    CHECK(tie < n / 10000);   /* ties need a ray through an edge: rare */
    irrvol__bvh_free(&bvh, &a);
}

/* An engine's ray caster in the two callbacks: Embree finds the hits. */
static int embree_trace(void *user, const float org[3], const float dir[3], float tmax, irrvol_hit *hit)
{
    ref_hit h;
    (void)user;
    if (!ref_intersect(reference, org, dir, 0.0f, tmax, &h)) return 0;
    hit->t = h.t; hit->u = h.u; hit->v = h.v; hit->triangle = h.tri;
    return 1;
}
static void embree_radiance(void *user, const float org[3], const float dir[3], float rgb[3])
{
    ref_hit h;
    (void)user;
    rgb[0] = rgb[1] = rgb[2] = 0.0f;
    if (ref_intersect(reference, org, dir, 0.0f, FLT_MAX, &h)) memcpy(rgb, scene.tri_radiance + 3 * h.tri, 3 * sizeof(float));
}

/* The same volume from the built-in BVH, from desc.trace and from
   desc.radiance, both through Embree: the hits agree, so do the volumes.
   (With informed sampling the rays aimed at points of the lamp near its
   edges meet Embree's and the watertight test's different edge rules; the
   volumes then differ by up to 1 %.) */
static void test_callbacks_match_builtin(void)
{
    irrvol_desc d;
    irrvol *builtin = NULL, *traced = NULL, *radiance = NULL;
    irrvol_volume_info info;
    float *a, *b, *c;
    double worst_trace = 0.0, worst_radiance = 0.0;
    uint32_t s, i;
    uint32_t flags[64], m;
    for (m = 0; m < scene.material_count && m < 64; m++) {   /* plain sampling: rays at bin centres */
        flags[m] = scene.materials[m].flags;
        scene.materials[m].flags = 0;
    }
    office_scene_desc(&scene, &d);
    d.resolution = 9;
    d.parallel_for = ex_pool_parallel_for;
    d.parallel_user = pool;
    CHECK_EQ_INT(irrvol_build(&d, &builtin), IRRVOL_OK);
    d.trace = embree_trace;
    CHECK_EQ_INT(irrvol_build(&d, &traced), IRRVOL_OK);
    d.trace = NULL;
    d.radiance = embree_radiance;
    CHECK_EQ_INT(irrvol_build(&d, &radiance), IRRVOL_OK);
    for (m = 0; m < scene.material_count && m < 64; m++) scene.materials[m].flags = flags[m];
    if (!builtin || !traced || !radiance) return;
    irrvol_info(builtin, &info);
    a = (float *)malloc(3 * sizeof(float) * info.bins);
    b = (float *)malloc(3 * sizeof(float) * info.bins);
    c = (float *)malloc(3 * sizeof(float) * info.bins);
    for (s = 0; s < info.sample_count; s++) {
        irrvol_sample_values(builtin, s, a, NULL);
        irrvol_sample_values(traced, s, b, NULL);
        irrvol_sample_values(radiance, s, c, NULL);
        for (i = 0; i < 3 * info.bins; i++) {
            double scale = fabs(a[i]) > 1e-3 ? fabs(a[i]) : 1e-3;
            if (fabs(a[i] - b[i]) / scale > worst_trace) worst_trace = fabs(a[i] - b[i]) / scale;
            if (fabs(a[i] - c[i]) / scale > worst_radiance) worst_radiance = fabs(a[i] - c[i]) / scale;
        }
    }
    test_note("office volume through Embree callbacks vs the built-in BVH: largest relative difference %.2g (trace), "
              "%.2g (radiance)", worst_trace, worst_radiance);
    CHECK(worst_trace == 0.0);      /* the same hits, the same sums: the same bits */
    CHECK(worst_radiance == 0.0);
    free(a); free(b); free(c);
    irrvol_destroy(builtin);
    irrvol_destroy(traced);
    irrvol_destroy(radiance);
}

static irrvol *office_volume(uint32_t subgrid, uint32_t k, float refine_threshold)
{
    irrvol_desc d;
    irrvol *v = NULL;
    office_scene_desc(&scene, &d);
    d.subgrid_samples = subgrid;
    d.resolution = k;
    d.refine_threshold = refine_threshold;
    d.supersamples = 2;   /* 2 x 2 jittered rays per bin: partly covered bins average */
    d.parallel_for = ex_pool_parallel_for;
    d.parallel_user = pool;
    if (irrvol_build(&d, &v) != IRRVOL_OK) return NULL;
    return v;
}

/* At the samples the volume holds eq. 4.3 of the gathered radiance: it must
   agree with the reference estimate of the same field in the bin centre
   direction. */
static void test_irradiance_at_samples(void)
{
    irrvol *v = office_volume(3, 17, 0.0f);
    irrvol_volume_info info;
    float *h;
    uint32_t s, j, checked = 0, outside = 0, skipped = 0;
    double worst = 0.0, sum_rel = 0.0;
    if (!CHECK(v != NULL)) return;
    irrvol_info(v, &info);
    h = (float *)malloc((size_t)info.bins * 3 * sizeof(float));
    for (s = 0; s < info.sample_count; s += 31) {
        irrvol_sample_info si;
        irrvol_sample(v, s, &si);
        /* invalid samples hold their neighbours' mean and hanging ones a
           blend of first-level samples: neither is a gather to compare */
        if (si.state == IRRVOL_SAMPLE_INVALID || si.state == IRRVOL_SAMPLE_HANGING) { skipped++; continue; }
        memcpy(si.position, si.origin, sizeof si.position);   /* a relocated sample gathered there */
        irrvol_sample_values(v, s, h, NULL);
        for (j = 0; j < 4; j++) {
            uint32_t bin = (s * 37u + j * 151u) % info.bins;
            float n[3];
            ref_estimate e;
            int c;
            irrvol_bin_direction(v, bin, n);
            /* 2^17 cosine rays: a partly hidden lamp is a rare, heavy tail that a
               much smaller estimate misses, along with its standard error */
            e = ref_irradiance_field(reference, si.position, n, scene.tri_radiance, NULL, 1u << 17, s * 4u + j);
            for (c = 0; c < 3; c++) {
                double diff = fabs(h[3 * bin + (uint32_t)c] - e.mean[c]);
                double allowed = 3.0 * e.std_error[c] + 0.02 * e.mean[c];
                if (diff > allowed) {
                    outside++;
                    test_note("  sample %u (%.3f %.3f %.3f) level %d bin %u channel %d: H %.4f, reference %.4f +- %.4f", s,
                              si.position[0], si.position[1], si.position[2], si.level, bin, c, h[3 * bin + (uint32_t)c],
                              e.mean[c], e.std_error[c]);
                }
                if (e.mean[c] > 0.0) {
                    sum_rel += diff / e.mean[c];
                    if (diff / e.mean[c] > worst) worst = diff / e.mean[c];
                }
            }
            checked++;
        }
    }
    test_note("irradiance at %u (sample, bin) pairs vs Embree (2^17 cosine rays each): mean relative difference "
              "%.2f %%, largest %.2f %%, %u channels outside 3 SE + 2 %% (%u invalid or hanging samples skipped)",
              checked, 100.0 * sum_rel / (3.0 * checked), 100.0 * worst, outside, skipped);
    CHECK_EQ_INT(outside, 0);
    free(h);
    irrvol_destroy(v);
}

/* Between samples: random points and directions, interpolated queries
   against the reference. Printed as a table; sanity and the orderings the
   method promises are asserted. */
#define TABLE_POINTS 200
typedef struct table_row {
    const char *grid;
    uint32_t subgrid, k;
    float refine;             /* desc.refine_threshold */
    irrvol_filter filter;
    irrvol_weighting weighting;
    uint32_t sh_order;        /* 0: the bins */
} table_row;

static void test_interpolation_error_table(void)
{
    static float pos[TABLE_POINTS][3], dir[TABLE_POINTS][3];
    static double expect[TABLE_POINTS], se[TABLE_POINTS];
    static int near_geometry[TABLE_POINTS];
    static const table_row rows[] = {
        {"7^3              ", 2, 9, -1.0f, IRRVOL_FILTER_NEAREST, IRRVOL_WEIGHTING_TRILINEAR, 0},
        {"7^3              ", 2, 17, -1.0f, IRRVOL_FILTER_NEAREST, IRRVOL_WEIGHTING_TRILINEAR, 0},
        {"7^3              ", 2, 17, -1.0f, IRRVOL_FILTER_BILINEAR, IRRVOL_WEIGHTING_TRILINEAR, 0},
        {"+ 3^3 geometry   ", 3, 9, -1.0f, IRRVOL_FILTER_NEAREST, IRRVOL_WEIGHTING_TRILINEAR, 0},
        {"+ 3^3 geometry   ", 3, 17, -1.0f, IRRVOL_FILTER_NEAREST, IRRVOL_WEIGHTING_TRILINEAR, 0},
        {"+ 3^3 geometry   ", 3, 17, -1.0f, IRRVOL_FILTER_BILINEAR, IRRVOL_WEIGHTING_TRILINEAR, 0},
        {"+ 3^3 geometry   ", 3, 17, -1.0f, IRRVOL_FILTER_BILINEAR, IRRVOL_WEIGHTING_VISIBILITY, 0},
        {"+ 3^3 geom+light ", 3, 17, 0.0f, IRRVOL_FILTER_NEAREST, IRRVOL_WEIGHTING_TRILINEAR, 0},
        {"+ 3^3 geom+light ", 3, 17, 0.0f, IRRVOL_FILTER_BILINEAR, IRRVOL_WEIGHTING_TRILINEAR, 0},
        {"+ 3^3 geom+light ", 3, 17, 0.0f, IRRVOL_FILTER_NEAREST, IRRVOL_WEIGHTING_VISIBILITY, 0},
        {"+ 3^3 geom+light ", 3, 17, 0.0f, IRRVOL_FILTER_BILINEAR, IRRVOL_WEIGHTING_VISIBILITY, 0},   /* defaults */
        {"+ 3^3 geom+light ", 3, 17, 0.0f, IRRVOL_FILTER_DEFAULT, IRRVOL_WEIGHTING_VISIBILITY, 2},
        {"+ 3^3 geom+light ", 3, 17, 0.0f, IRRVOL_FILTER_DEFAULT, IRRVOL_WEIGHTING_VISIBILITY, 1},
    };
    enum { ROWS = sizeof rows / sizeof rows[0] };
    double l1[ROWS], median[ROWS];
    irrvol *v = NULL;
    uint32_t i, r;
    double mean_se = 0.0;
    rng_state = 2;
    for (i = 0; i < TABLE_POINTS; i++) {
        ref_estimate e;
        /* inside the grid (1 % inset) */
        pos[i][0] = (float)(0.05 + 4.9 * frand());
        pos[i][1] = (float)(0.028 + 2.744 * frand());
        pos[i][2] = (float)(0.04 + 3.92 * frand());
        random_dir(dir[i]);
        e = ref_irradiance_field(reference, pos[i], dir[i], scene.tri_radiance, NULL, 1u << 16, 1000u + i);
        expect[i] = ref_luminance((const float[3]){(float)e.mean[0], (float)e.mean[1], (float)e.mean[2]});
        se[i] = 0.2126 * e.std_error[0] + 0.7152 * e.std_error[1] + 0.0722 * e.std_error[2];
        mean_se += se[i] / expect[i] / TABLE_POINTS;
    }
    v = office_volume(3, 2, -1.0f);   /* which points lie in cells with geometry (refined by it) */
    if (!CHECK(v != NULL)) return;
    for (i = 0; i < TABLE_POINTS; i++) {
        uint32_t c[3];
        float o[3];
        irrvol__cell_coords(v, pos[i], c, o);
        near_geometry[i] = v->refined[c[0] + v->cells[0] * (c[1] + v->cells[1] * c[2])] == IRRVOL__REFINED_GEOMETRY;
    }
    irrvol_destroy(v);
    v = NULL;
    test_note("interpolation error on the office, %d random points and directions, luminance of H "
              "(reference relative standard error %.2f %%):", TABLE_POINTS, 100.0 * mean_se);
    test_note("  relative L1 = sum |H - H_ref| / sum H_ref; median, 90th percentile, max of |H - H_ref| / H_ref");
    test_note("  grid               k  filter    weighting  samples    MB  rel. L1  median  90th pct     max  "
              "(points in cells with geometry: rel. L1)");
    for (r = 0; r < ROWS; r++) {
        const table_row *t = &rows[r];
        static double err[TABLE_POINTS];
        double sum = 0.0, sum_refined = 0.0, total = 0.0, total_refined = 0.0, tmp;
        uint32_t refined = 0, x, y;
        irrvol_volume_info info;
        if (r == 0 || t->subgrid != rows[r - 1].subgrid || t->k != rows[r - 1].k || t->refine != rows[r - 1].refine) {
            irrvol_destroy(v);
            v = office_volume(t->subgrid, t->k, t->refine);
            if (!CHECK(v != NULL)) return;
        }
        irrvol_info(v, &info);
        for (i = 0; i < TABLE_POINTS; i++) {
            float h[3];
            if (t->sh_order) irrvol_query_sh(v, t->sh_order, t->weighting, pos[i], dir[i], h);
            else irrvol_query_filter(v, t->filter, t->weighting, pos[i], dir[i], h);
            err[i] = fabs(ref_luminance(h) - expect[i]) / expect[i];
            sum += fabs(ref_luminance(h) - expect[i]);
            total += expect[i];
            if (near_geometry[i]) {
                refined++;
                sum_refined += fabs(ref_luminance(h) - expect[i]);
                total_refined += expect[i];
            }
        }
        for (x = 1; x < TABLE_POINTS; x++)   /* insertion sort for the percentiles */
            for (y = x; y > 0 && err[y - 1] > err[y]; y--) { tmp = err[y]; err[y] = err[y - 1]; err[y - 1] = tmp; }
        test_note("  %s %2u  %-8s  %-9s %7u %5.1f  %5.1f %%  %5.1f %%  %6.1f %%  %6.0f %%  (%u: %.1f %%)", t->grid, t->k,
                  t->sh_order ? (t->sh_order == 1 ? "SH L1" : "SH L2") : t->filter == IRRVOL_FILTER_NEAREST ? "nearest" : "bilinear",
                  t->weighting == IRRVOL_WEIGHTING_VISIBILITY ? "leak-safe" : "plain", info.sample_count, info.bytes / 1e6,
                  100.0 * sum / total, 100.0 * err[TABLE_POINTS / 2], 100.0 * err[TABLE_POINTS * 9 / 10],
                  100.0 * err[TABLE_POINTS - 1], refined, refined ? 100.0 * sum_refined / total_refined : 0.0);
        l1[r] = sum / total;
        median[r] = err[TABLE_POINTS / 2];
    }
    irrvol_destroy(v);
    CHECK(l1[10] < 0.3);                  /* sanity: the default volume follows the field */
    CHECK(l1[5] < l1[2] && l1[4] < l1[1]);   /* the second level helps (4.1) */
    CHECK(l1[8] < l1[7] && l1[10] < l1[9]);   /* bilinear helps (6.1.2) */
    CHECK(median[10] < median[4] && l1[10] < l1[4]);   /* the defaults beat the thesis (nearest, plain, geometry) */
    CHECK(l1[10] < l1[8]);                /* and so does leak prevention, here chiefly at the divider */
}

/* The harmonics against the bins they come from, on the office's default
   volume: diffuse irradiance (moment 1) at random points and directions. */
static void test_sh_against_bins(void)
{
    irrvol *v = office_volume(3, 17, 0.0f);
    static double err[2][2000];
    uint32_t i, order;
    if (!CHECK(v != NULL)) return;
    rng_state = 3;
    for (i = 0; i < 2000; i++) {
        float p[3], d[3], hb[3], hs[3];
        p[0] = (float)(0.05 + 4.9 * frand());
        p[1] = (float)(0.028 + 2.744 * frand());
        p[2] = (float)(0.04 + 3.92 * frand());
        random_dir(d);
        irrvol_query(v, p, d, hb);
        for (order = 1; order <= 2; order++) {
            irrvol_query_sh(v, order, IRRVOL_WEIGHTING_DEFAULT, p, d, hs);
            err[order - 1][i] = fabs(ref_luminance(hs) - ref_luminance(hb)) / ref_luminance(hb);
        }
    }
    for (order = 0; order < 2; order++) {
        double tmp;
        uint32_t x, y;
        for (x = 1; x < 2000; x++)
            for (y = x; y > 0 && err[order][y - 1] > err[order][y]; y--) {
                tmp = err[order][y]; err[order][y] = err[order][y - 1]; err[order][y - 1] = tmp;
            }
        test_note("office, harmonics L%u against the bins (both leak-safe), 2000 random points and directions: "
                  "median %.2f %%, 90th percentile %.1f %%, max %.0f %%", order + 1, 100.0 * err[order][1000],
                  100.0 * err[order][1800], 100.0 * err[order][1999]);
    }
    CHECK(err[1][1000] <= 0.03);   /* the acceptance bound for L2 */
    irrvol_destroy(v);
}

int main(int argc, char **argv)
{
    TEST_INIT(argc, argv);
    if (office_scene_load(&scene, "examples/data", 2.0f, 1.5f) != 0) {
        CHECK(0);
        return test_finish();
    }
    reference = ref_scene_create(scene.positions, scene.vertex_count, scene.indices, scene.tri_count, NULL, NULL, 0);
    pool = ex_pool_create(0);
    if (reference) {
        RUN(test_bvh_matches_embree);
        RUN(test_callbacks_match_builtin);
        RUN(test_irradiance_at_samples);
        RUN(test_interpolation_error_table);
        RUN(test_sh_against_bins);
    } else {
        CHECK(0);
    }
    ex_pool_destroy(pool);
    ref_scene_destroy(reference);
    office_scene_free(&scene);
    return test_finish();
}
