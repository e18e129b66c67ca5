/* Unit tests of irrvol.h's glass and sky: nested glass boxes under a
   constant sky (a furnace through panes: pi L times the product of the
   transmittances in every bin), the layer limit, a latitude-longitude map
   of one radiance equal to the constant sky bit for bit, and bad
   transmittances and skies refused. */
#define IRRVOL_IMPLEMENTATION
#include "irrvol.h"
#include "tests/test.h"
#include "tests/test_irrvol_scenes.h"

#define PI SC_PI

static const float sky[3] = { 1.0f, 0.5f, 2.0f };

/* `boxes` nested closed boxes around the origin, half sizes 1, 2, ...,
   facing out (panes seen from behind by the samples inside), material i
   for box i; a 2 x 2 x 2 grid within the smallest box. */
static void nested_boxes(sc_scene *s, irrvol_desc *d, irrvol_material *m, uint32_t boxes)
{
    uint32_t i;
    memset(s, 0, sizeof *s);
    for (i = 0; i < boxes; i++) {
        float h = (float)(i + 1), lo[3], hi[3];
        sc_set3(lo, -h, -h, -h);
        sc_set3(hi, h, h, h);
        sc_box(s, lo, hi, i, 0);
    }
    memset(d, 0, sizeof *d);
    d->positions = s->pos;
    d->vertex_count = s->nv;
    d->indices = s->idx;
    d->triangle_count = s->nt;
    d->triangle_materials = s->mat;
    d->materials = m;
    d->material_count = boxes;
    d->grid_samples[0] = d->grid_samples[1] = d->grid_samples[2] = 2;
    d->subgrid_samples = 2;
    sc_set3(d->bounds_min, -0.5f, -0.5f, -0.5f);
    sc_set3(d->bounds_max, 0.5f, 0.5f, 0.5f);
    memcpy(d->background, sky, sizeof sky);
}

/* Largest |H - expected| / expected over every bin of every sample. */
static double worst_bin_error(const irrvol *vol, const double expected[3])
{
    irrvol_volume_info info;
    uint32_t s, i;
    double worst = 0.0;
    float *h;
    if (!CHECK(irrvol_info(vol, &info) == IRRVOL_OK)) return 1e9;
    CHECK_EQ_INT(info.invalid_samples, 0);   /* the panes' backs do not make samples "inside" */
    h = (float *)malloc(3 * (size_t)info.bins * sizeof(float));
    if (!CHECK(h != NULL)) return 1e9;
    for (s = 0; s < info.sample_count; s++) {
        if (!CHECK(irrvol_sample_values(vol, s, h, NULL) == IRRVOL_OK)) break;
        for (i = 0; i < 3 * info.bins; i++) {
            double e = expected[i % 3], err = e > 0.0 ? fabs(h[i] - e) / e : fabs(h[i]);
            if (err > worst) worst = err;
        }
    }
    free(h);
    return worst;
}

/* Three nested glass boxes of different transmittances: every direction
   crosses each pane once, so every bin holds pi L t1 t2 t3 (within the
   weights' 0.05 % integration error). */
static void test_nested_glass_furnace(void)
{
    static const float tf[3][3] = { { 0.5f, 0.8f, 1.0f }, { 0.9f, 0.25f, 0.6f }, { 1.0f, 1.0f, 0.3f } };
    irrvol_material m[3];
    sc_scene s;
    irrvol_desc d;
    irrvol *vol = NULL;
    double expected[3];
    uint32_t i;
    int k;
    memset(m, 0, sizeof m);
    for (i = 0; i < 3; i++) memcpy(m[i].transmittance, tf[i], sizeof tf[i]);
    nested_boxes(&s, &d, m, 3);
    d.full_precision = 1;   /* the gather's 0.05 %: the compact store rounds each channel to 2^-9 of the largest */
    if (!CHECK(irrvol_build(&d, &vol) == IRRVOL_OK)) return;
    for (k = 0; k < 3; k++) expected[k] = PI * sky[k] * tf[0][k] * tf[1][k] * tf[2][k];
    {
        double worst = worst_bin_error(vol, expected);
        test_note("three nested glass boxes: largest |H - pi L t1 t2 t3| / (pi L t1 t2 t3) = %.3g %%", 100.0 * worst);
        CHECK(worst < 5e-4);   /* the weights' integration error at k = 17 */
    }
    irrvol_destroy(vol);
}

/* IRRVOL_MAX_GLASS_LAYERS clear panes pass the sky; one more blocks it:
   panes 1000 wide at heights 1, 2, ... above the samples, and the kept
   radiance of the bins looking up (y > 0.3, every ray of them crosses every
   pane). */
static void test_glass_layer_limit(void)
{
    irrvol_material m[1];
    sc_scene s;
    irrvol_desc d;
    uint32_t panes;
    memset(m, 0, sizeof m);
    sc_set3(m[0].transmittance, 1.0f, 1.0f, 1.0f);
    for (panes = IRRVOL_MAX_GLASS_LAYERS; panes <= IRRVOL_MAX_GLASS_LAYERS + 1; panes++) {
        irrvol_volume_info info;
        irrvol *vol = NULL;
        float *l;
        uint32_t i, bin, looked = 0;
        memset(&s, 0, sizeof s);
        for (i = 0; i < panes; i++) sc_square_facing(&s, 1, (float)(i + 1), 0.0f, 0.0f, 500.0f, 0, i % 2 ? 1 : -1);
        sc_scene_desc(&d, &s, m, 1);
        d.grid_samples[0] = d.grid_samples[1] = d.grid_samples[2] = 2;
        d.subgrid_samples = 2;
        sc_set3(d.bounds_min, -0.5f, -0.5f, -0.5f);
        sc_set3(d.bounds_max, 0.5f, 0.5f, 0.5f);
        memcpy(d.background, sky, sizeof sky);
        d.resolution = 8;
        d.keep_radiance = 1;
        if (!CHECK(irrvol_build(&d, &vol) == IRRVOL_OK && irrvol_info(vol, &info) == IRRVOL_OK)) return;
        l = (float *)malloc(3 * (size_t)info.bins * sizeof(float));
        if (CHECK(l && irrvol_sample_values(vol, 0, NULL, l) == IRRVOL_OK))
            for (bin = 0; bin < info.bins; bin++) {
                float dir[3];
                int k;
                irrvol_bin_direction(vol, bin, dir);
                if (dir[1] <= 0.3f) continue;
                looked++;
                for (k = 0; k < 3; k++) CHECK(l[3 * bin + k] == (panes > IRRVOL_MAX_GLASS_LAYERS ? 0.0f : sky[k]));
            }
        CHECK(looked > 10);
        free(l);
        irrvol_destroy(vol);
    }
}

static void save(const irrvol *vol, void **data, size_t *size)
{
    *data = NULL;
    *size = 0;
    CHECK(irrvol_save_to_memory(vol, NULL, data, size) == IRRVOL_OK);
}

/* A map of one radiance is that constant sky: the same volume byte for
   byte, seen through a pane (the room of the cube with a glass face). */
static void test_constant_map_is_constant_sky(void)
{
    irrvol_material m[6];
    float map[5 * 3 * 3];
    sc_scene s;
    irrvol_desc d;
    irrvol *a = NULL, *b = NULL;
    void *da = NULL, *db = NULL;
    size_t na = 0, nb = 0;
    int i;
    memset(m, 0, sizeof m);
    for (i = 0; i < 6; i++) sc_set3(m[i].radiance, 0.1f * (float)i, 0.05f, 0.02f);
    sc_set3(m[3].transmittance, 0.7f, 0.5f, 0.9f);   /* the ceiling (+y) is glass */
    for (i = 0; i < 5 * 3; i++) memcpy(map + 3 * i, sky, sizeof sky);
    sc_cube(&s);
    sc_scene_desc(&d, &s, m, 6);
    d.grid_samples[0] = d.grid_samples[1] = d.grid_samples[2] = 3;
    memcpy(d.background, sky, sizeof sky);
    if (!CHECK(irrvol_build(&d, &a) == IRRVOL_OK)) return;
    memset(d.background, 0, sizeof d.background);   /* the map replaces it */
    d.environment = map;
    d.environment_width = 5;
    d.environment_height = 3;
    if (CHECK(irrvol_build(&d, &b) == IRRVOL_OK)) {
        save(a, &da, &na);
        save(b, &db, &nb);
        CHECK(na == nb && na > 0 && memcmp(da, db, na) == 0);
    }
    irrvol_free_memory(NULL, da);
    irrvol_free_memory(NULL, db);
    irrvol_destroy(a);
    irrvol_destroy(b);
}

/* Negative, NaN, infinite and above-one transmittances, NaN or negative
   skies and bad maps: INVALID_ARGUMENT, nothing built. */
static void test_bad_glass_and_sky(void)
{
    irrvol_material m[6];
    float map[4 * 2 * 3];
    sc_scene s;
    irrvol_desc d;
    irrvol *vol;
    int i, c;
    const float bad[4] = { -0.1f, NAN, INFINITY, 1.5f };
    memset(m, 0, sizeof m);
    for (i = 0; i < 4 * 2 * 3; i++) map[i] = 1.0f;
    sc_cube(&s);
    sc_scene_desc(&d, &s, m, 6);
    d.grid_samples[0] = d.grid_samples[1] = d.grid_samples[2] = 2;
    for (i = 0; i < 4; i++)
        for (c = 0; c < 3; c++) {
            memset(m[2].transmittance, 0, sizeof m[2].transmittance);
            m[2].transmittance[c] = bad[i];
            vol = (irrvol *)&s;
            CHECK_EQ_INT(irrvol_build(&d, &vol), IRRVOL_ERROR_INVALID_ARGUMENT);
            CHECK(vol == NULL);
        }
    memset(m[2].transmittance, 0, sizeof m[2].transmittance);
    d.background[1] = NAN;
    CHECK_EQ_INT(irrvol_build(&d, &vol), IRRVOL_ERROR_INVALID_ARGUMENT);
    d.background[1] = -1.0f;
    CHECK_EQ_INT(irrvol_build(&d, &vol), IRRVOL_ERROR_INVALID_ARGUMENT);
    d.background[1] = 0.0f;
    d.environment = map;
    d.environment_width = 4;
    d.environment_height = 0;
    CHECK_EQ_INT(irrvol_build(&d, &vol), IRRVOL_ERROR_INVALID_ARGUMENT);
    d.environment_height = IRRVOL_MAX_ENVIRONMENT_SIZE + 1;
    CHECK_EQ_INT(irrvol_build(&d, &vol), IRRVOL_ERROR_INVALID_ARGUMENT);
    d.environment_height = 2;
    map[7] = NAN;
    CHECK_EQ_INT(irrvol_build(&d, &vol), IRRVOL_ERROR_INVALID_ARGUMENT);
    map[7] = -2.0f;
    CHECK_EQ_INT(irrvol_build(&d, &vol), IRRVOL_ERROR_INVALID_ARGUMENT);
    map[7] = 1.0f;
    CHECK_EQ_INT(irrvol_build(&d, &vol), IRRVOL_OK);   /* and the same desc, repaired, builds */
    irrvol_destroy(vol);
}

int main(int argc, char **argv)
{
    TEST_INIT(argc, argv);
    RUN(test_nested_glass_furnace);
    RUN(test_glass_layer_limit);
    RUN(test_constant_map_is_constant_sky);
    RUN(test_bad_glass_and_sky);
    return test_finish();
}
