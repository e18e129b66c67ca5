/* Unit tests of lightvec.h's glass and sky: a point inside nested glass
   boxes under a constant sky (every ray crosses each pane once: E = pi L
   t1 t2), the layer limit, a latitude-longitude map of one radiance equal
   to the constant sky bit for bit, and bad transmittances and skies
   refused. */
#define LIGHTVEC_IMPLEMENTATION
#include "lightvec.h"
#include "tests/test.h"

#define PI 3.14159265358979323846
#define MAX_BOXES (LIGHTVEC_MAX_GLASS_LAYERS + 1)

static const float sky[3] = { 1.0f, 0.5f, 2.0f };
static const float up[3] = { 0, 1, 0 };

typedef struct boxes {
    float pos[MAX_BOXES * 8 * 3];
    uint32_t idx[MAX_BOXES * 36], mat[MAX_BOXES * 12];
    uint32_t nv, nt;
} boxes;

/* Closed cubes of half size 1, 2, ... around the origin, faces out,
   material i for cube i. */
static void nested_boxes(boxes *b, uint32_t count)
{
    static const uint32_t faces[12][3] = { { 0, 2, 1 }, { 0, 3, 2 }, { 4, 5, 6 }, { 4, 6, 7 }, { 0, 1, 5 }, { 0, 5, 4 },
                                           { 3, 7, 6 }, { 3, 6, 2 }, { 0, 4, 7 }, { 0, 7, 3 }, { 1, 2, 6 }, { 1, 6, 5 } };
    uint32_t i, v, f;
    memset(b, 0, sizeof *b);
    for (i = 0; i < count; i++) {
        float h = (float)(i + 1);
        for (v = 0; v < 8; v++) {
            b->pos[3 * (b->nv + v)] = (v == 1 || v == 2 || v == 5 || v == 6) ? h : -h;
            b->pos[3 * (b->nv + v) + 1] = (v == 2 || v == 3 || v == 6 || v == 7) ? h : -h;
            b->pos[3 * (b->nv + v) + 2] = v >= 4 ? h : -h;
        }
        for (f = 0; f < 12; f++) {
            for (v = 0; v < 3; v++) b->idx[3 * b->nt + v] = b->nv + faces[f][v];
            b->mat[b->nt++] = i;
        }
        b->nv += 8;
    }
}

static lightvec_result make_scene(const boxes *b, const lightvec_material *m, uint32_t count, const float *map,
                                  uint32_t w, uint32_t h, lightvec_scene **s)
{
    lightvec_scene_desc d;
    memset(&d, 0, sizeof d);
    d.positions = b->pos;
    d.vertex_count = b->nv;
    d.indices = b->idx;
    d.triangle_count = b->nt;
    d.material_ids = b->mat;
    d.materials = m;
    d.material_count = count;
    memcpy(d.sky, sky, sizeof sky);
    d.environment = map;
    d.environment_width = w;
    d.environment_height = h;
    return lightvec_scene_create(&d, s);
}

static int gather(const lightvec_scene *s, lightvec_record *r)
{
    lightvec_gather_desc g;
    lightvec_surface sf;
    memset(&g, 0, sizeof g);
    memset(&sf, 0, sizeof sf);
    sf.position[1] = -0.5f;
    memcpy(sf.normal, up, sizeof up);
    sf.flags = LIGHTVEC_RECORD_VIEW_INDEPENDENT;
    sf.material.diffuse[0] = 0.5f;
    return lightvec_gather(s, &g, &sf, 3, r) == LIGHTVEC_OK;
}

/* Two nested glass cubes seen from behind: E = pi L t1 t2 (within the
   strata's estimate of the cosine's integral, 0.5 %), the distance that of
   the first pane. */
static void test_nested_glass_boxes(void)
{
    lightvec_material m[2];
    boxes b;
    lightvec_scene *s = NULL;
    lightvec_record r;
    int k;
    memset(m, 0, sizeof m);
    m[0].transmittance[0] = 0.5f; m[0].transmittance[1] = 0.8f; m[0].transmittance[2] = 1.0f;
    m[1].transmittance[0] = 0.9f; m[1].transmittance[1] = 0.25f; m[1].transmittance[2] = 0.6f;
    m[1].diffuse[0] = 0.3f;   /* the outer box reflects, but only the black inside ever sees it */
    nested_boxes(&b, 2);
    if (!CHECK(make_scene(&b, m, 2, NULL, 0, 0, &s) == LIGHTVEC_OK)) return;
    if (CHECK(gather(s, &r)))
        for (k = 0; k < 3; k++) {
            double expected = PI * sky[k] * m[0].transmittance[k] * m[1].transmittance[k];
            CHECK_CLOSE(r.irradiance[k], expected, 5e-3, 0);
        }
    CHECK(r.distance < 1.6f);   /* harmonic mean distance to the inner cube (0.5 to 1.7 away), not to the sky */
    lightvec_scene_destroy(s);
}

/* LIGHTVEC_MAX_GLASS_LAYERS clear panes pass the sky; one more blocks it. */
static void test_glass_layer_limit(void)
{
    static lightvec_material m[MAX_BOXES];
    static boxes b;
    uint32_t count, i;
    for (count = LIGHTVEC_MAX_GLASS_LAYERS; count <= MAX_BOXES; count++) {
        lightvec_scene *s = NULL;
        lightvec_record r;
        memset(m, 0, sizeof m);
        for (i = 0; i < count; i++) m[i].transmittance[0] = m[i].transmittance[1] = m[i].transmittance[2] = 1.0f;
        nested_boxes(&b, count);
        if (!CHECK(make_scene(&b, m, count, NULL, 0, 0, &s) == LIGHTVEC_OK)) return;
        if (CHECK(gather(s, &r))) {
            if (count > LIGHTVEC_MAX_GLASS_LAYERS) CHECK(r.irradiance[0] == 0.0f);
            else CHECK_CLOSE(r.irradiance[0], PI * sky[0], 5e-3, 0);
        }
        lightvec_scene_destroy(s);
    }
}

/* A map of one radiance gives the records of the constant sky, bit for bit. */
static void test_constant_map_is_constant_sky(void)
{
    lightvec_material m[1];
    float map[6 * 3 * 3];
    boxes b;
    lightvec_scene *a = NULL, *c = NULL;
    lightvec_record ra, rc;
    int i;
    memset(m, 0, sizeof m);
    m[0].transmittance[0] = 0.7f; m[0].transmittance[1] = 0.4f; m[0].transmittance[2] = 0.9f;
    m[0].diffuse[1] = 0.2f;
    for (i = 0; i < 6 * 3; i++) memcpy(map + 3 * i, sky, sizeof sky);
    nested_boxes(&b, 1);
    if (CHECK(make_scene(&b, m, 1, NULL, 0, 0, &a) == LIGHTVEC_OK && make_scene(&b, m, 1, map, 6, 3, &c) == LIGHTVEC_OK &&
              gather(a, &ra) && gather(c, &rc)))
        CHECK(memcmp(&ra, &rc, sizeof ra) == 0);
    lightvec_scene_destroy(a);
    lightvec_scene_destroy(c);
}

/* Negative, NaN, infinite and above-one transmittances, NaN or negative
   skies, bad maps: INVALID_ARGUMENT and no scene. */
static void test_bad_glass_and_sky(void)
{
    const float bad[4] = { -0.1f, NAN, INFINITY, 1.5f };
    lightvec_material m[1];
    lightvec_scene_desc d;
    float map[4 * 2 * 3];
    boxes b;
    lightvec_scene *s;
    int i, c;
    memset(m, 0, sizeof m);
    for (i = 0; i < 4 * 2 * 3; i++) map[i] = 1.0f;
    nested_boxes(&b, 1);
    for (i = 0; i < 4; i++)
        for (c = 0; c < 3; c++) {
            memset(m[0].transmittance, 0, sizeof m[0].transmittance);
            m[0].transmittance[c] = bad[i];
            s = (lightvec_scene *)&b;
            CHECK_EQ_INT(make_scene(&b, m, 1, NULL, 0, 0, &s), LIGHTVEC_ERROR_INVALID_ARGUMENT);
            CHECK(s == NULL);
        }
    memset(m[0].transmittance, 0, sizeof m[0].transmittance);
    memset(&d, 0, sizeof d);
    d.positions = b.pos;
    d.vertex_count = b.nv;
    d.indices = b.idx;
    d.triangle_count = b.nt;
    d.materials = m;
    d.material_count = 1;
    d.sky[2] = NAN;
    CHECK_EQ_INT(lightvec_scene_create(&d, &s), LIGHTVEC_ERROR_INVALID_ARGUMENT);
    d.sky[2] = -1.0f;
    CHECK_EQ_INT(lightvec_scene_create(&d, &s), LIGHTVEC_ERROR_INVALID_ARGUMENT);
    d.sky[2] = 0.0f;
    d.environment = map;
    d.environment_width = 0;
    d.environment_height = 2;
    CHECK_EQ_INT(lightvec_scene_create(&d, &s), LIGHTVEC_ERROR_INVALID_ARGUMENT);
    d.environment_width = LIGHTVEC_MAX_ENVIRONMENT_SIZE + 1;
    CHECK_EQ_INT(lightvec_scene_create(&d, &s), LIGHTVEC_ERROR_INVALID_ARGUMENT);
    d.environment_width = 4;
    map[5] = NAN;
    CHECK_EQ_INT(lightvec_scene_create(&d, &s), LIGHTVEC_ERROR_INVALID_ARGUMENT);
    map[5] = -3.0f;
    CHECK_EQ_INT(lightvec_scene_create(&d, &s), LIGHTVEC_ERROR_INVALID_ARGUMENT);
    map[5] = 1.0f;
    CHECK_EQ_INT(lightvec_scene_create(&d, &s), LIGHTVEC_OK);   /* repaired, it builds */
    lightvec_scene_destroy(s);
}

int main(int argc, char **argv)
{
    TEST_INIT(argc, argv);
    RUN(test_nested_glass_boxes);
    RUN(test_glass_layer_limit);
    RUN(test_constant_map_is_constant_sky);
    RUN(test_bad_glass_and_sky);
    return test_finish();
}
