/* Unit tests of examples/common/trace.h: hits equal a brute-force loop over
   all triangles (static scene and a transformed instance), and the direct
   light estimate converges to the closed form under a square light. */
#include "examples/common/trace.h"
#include "tests/test.h"

/* Closest hit by testing every triangle with the same watertight test. */
static float brute_force(const float *pos, const uint32_t *idx, uint32_t n, const float m[12],
                         const float org[3], const float dir[3], uint32_t *tri)
{
    float best = FLT_MAX;
    uint32_t i;
    tr__ray ray;
    tr__ray_setup(&ray, org, dir);
    *tri = TR__NO_HIT;
    for (i = 0; i < n; i++) {
        tr__bvh_tri t;
        tr__hit h;
        int k;
        for (k = 0; k < 3; k++) {
            const float *p = pos + 3 * idx[3 * i + (uint32_t)k];
            float *dst = k == 0 ? t.v0 : k == 1 ? t.v1 : t.v2;
            if (m) ex__affine_point(m, p, dst);
            else memcpy(dst, p, 3 * sizeof(float));
        }
        t.id = i;
        h.t = best;
        h.tri = TR__NO_HIT;
        if (tr__ray_tri(&ray, &t, 0.0f, &h)) { best = h.t; *tri = i; }
    }
    return best;
}

static void test_hits_equal_brute_force(void)
{
    obj_scene office, bunny;
    char err[256];
    ex_tracer *t;
    float grey[3] = { 0.5f, 0.5f, 0.5f };
    float m[12] = { 0, 0, 0.03f, 2.0f, 0, 0.03f, 0, 0.0f, -0.03f, 0, 0, 2.5f }; /* turned 90 degrees */
    ex_rng r = ex_rng_stream(5, 0);
    int i, wrong = 0, bunny_hits = 0;
    if (!CHECK(obj_load("examples/data/office.obj", &office, err, sizeof err) == 0)) return;
    if (!CHECK(obj_load("examples/data/bunny.obj", &bunny, err, sizeof err) == 0)) return;
    t = ex_tracer_create(&office);
    CHECK(ex_tracer_add_instance(t, &bunny, grey) == 0);
    CHECK(ex_tracer_set_transform(t, 0, m) == 0);
    for (i = 0; i < 3000; i++) {
        float org[3] = { 1.5f + ex_rng_float(&r), 0.05f + 0.5f * ex_rng_float(&r), 2.0f + ex_rng_float(&r) };
        float dir[3] = { ex_rng_float(&r) - 0.5f, ex_rng_float(&r) - 0.5f, ex_rng_float(&r) - 0.5f };
        ex_trace_hit h;
        uint32_t so, bo;
        float ts = brute_force(office.positions, office.tri_indices, office.tri_count, NULL, org, dir, &so);
        float tb = brute_force(bunny.positions, bunny.tri_indices, bunny.tri_count, m, org, dir, &bo);
        int hit = ex_tracer_intersect(t, org, dir, FLT_MAX, &h);
        if (!hit) { wrong += so != TR__NO_HIT || bo != TR__NO_HIT; continue; }
        if (tb < ts) {
            bunny_hits++;
            /* object-space and world-space tests round differently: t to 1e-4 */
            wrong += h.instance != 0 || fabsf(h.t - tb) > 1e-4f * tb + 1e-6f;
        } else {
            wrong += h.instance != EX_TRACE_STATIC || h.tri != so || h.t != ts;
        }
        CHECK_EQ_INT(ex_tracer_occluded(t, org, dir, h.t * 1.001f), 1);
        CHECK_EQ_INT(ex_tracer_occluded(t, org, dir, h.t * 0.999f), 0);
    }
    test_note("%d of 3000 rays hit the instanced bunny", bunny_hits);
    CHECK(bunny_hits > 100);
    CHECK_EQ_INT(wrong, 0);
    ex_tracer_destroy(t);
    obj_free(&office);
    obj_free(&bunny);
}

/* A diffuse floor point under a square emitter of side 2 at height 1 reflects
   L_out = kd/pi * E = kd * L * F with F = 0.554126 (Howell's catalogue). */
static void test_direct_light_known_answer(void)
{
    const char *body =
        "v -1 1 -1\nv 1 1 -1\nv 1 1 1\nv -1 1 1\n"
        "v -50 0 -50\nv 50 0 -50\nv 50 0 50\nv -50 0 50\n"
        "usemtl lamp\nf 1 2 3 4\nusemtl floor\nf 5 8 7 6\n";
    char text[512], name[256], path[512], err[256];
    FILE *f = fopen(test_scratch_path(path, sizeof path, "light.mtl"), "w");
    obj_scene s;
    ex_tracer *t;
    float org[3] = { 0, 0.5f, 0 }, dir[3] = { 0, -1, 0 };
    double sum = 0;
    ex_rng r = ex_rng_stream(9, 1);
    int i, n = 200000;
    if (!CHECK(f != NULL)) return;
    fputs("newmtl lamp\nKd 0 0 0\nKe 2 2 2\nnewmtl floor\nKd 0.5 0.5 0.5\n", f);
    fclose(f);
    snprintf(text, sizeof text, "mtllib %s\n%s", test_scratch_name(name, sizeof name, "light.mtl"), body);
    if (!CHECK_MSG(obj_parse(text, strlen(text), "light.obj", TEST_SCRATCH_DIR, &s, err, sizeof err) == 0, "%s", err)) return;
    t = ex_tracer_create(&s);
    for (i = 0; i < n; i++) {
        float rgb[3];
        ex_trace_hit h;
        ex_tracer_shade(t, org, dir, 0, &r, rgb, &h);
        sum += rgb[0];
    }
    /* the light sample's weight cos^2/d^2 varies by a factor ~3 over the lamp:
       standard error about 0.1% at 2e5 samples; 0.5% is 5 standard errors */
    CHECK_CLOSE(sum / n, 0.5 * 2.0 * 0.554126, 5e-3, 0);
    ex_tracer_destroy(t);
    obj_free(&s);
}

int main(int argc, char **argv)
{
    TEST_INIT(argc, argv);
    RUN(test_hits_equal_brute_force);
    RUN(test_direct_light_known_answer);
    return test_finish();
}
