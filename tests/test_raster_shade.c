/* Unit tests of shading a raster's runs of pixels with radinterp_shade_span
   (Hardt's online phase, section 3.4, one run of one triangle at a time, as
   the walkthrough's tile pass does): the runs of a rasterized room shade to
   the bits radinterp_shade gives the whole frame; the SIMD kernel and the
   scalar kernel give the same bits on every run length and on barycentrics
   inside and outside the triangle (where the clamp at 0 acts); exactly
   3 * count floats are written; bad arguments give INVALID_ARGUMENT and
   leave the output as it was. */
#define RADINTERP_IMPLEMENTATION
#include "../radinterp.h"
#include "examples/common/camera.h"
#include "examples/common/raster.h"
#include "tests/test.h"
#include "tests/test_radinterp_scenes.h"

#define W 160
#define H 120

static radinterp_mesh *room;   /* every test's mesh, built once */

/* One lit room of the test building (walls, floor, ceiling, desk, cabinet
   and a lamp whose underside emits), solved and meshed coarsely: the tests
   are about evaluating the mesh's interpolants, not their accuracy. */
static radinterp_mesh *room_mesh(void)
{
    rb_scene b;
    radinterp_desc d;
    radinterp_mesh_desc md;
    radinterp_solution *sol = NULL;
    radinterp_mesh *m = NULL;
    rb_building(&b, 1, 1, 1, RB_ALL_LIT);
    d = rb_desc(&b);
    if (CHECK_EQ_INT(radinterp_solve(&d, &sol), RADINTERP_OK)) {
        memset(&md, 0, sizeof md);
        md.min_leaf_area = 0.25f;
        CHECK_EQ_INT(radinterp_build_mesh(sol, &md, &m), RADINTERP_OK);
    }
    radinterp_solution_destroy(sol);
    rb_free(&b);
    return m;
}

/* rgb of count pixels of one triangle through the public function, the
   scalar kernel and radinterp_shade; 1 when all three agree bit for bit. */
static int span_agrees(const radinterp_mesh *m, uint32_t tri, const float *st, size_t count)
{
    float span[3 * 64], scalar[3 * 64], ref[3 * 64];
    uint32_t ids[64];
    size_t i;
    if (count > 64) return 0;
    for (i = 0; i < count; i++) ids[i] = tri;
    if (radinterp_shade_span(m, tri, st, count, span) != RADINTERP_OK ||
        radinterp_shade(m, ids, st, count, ref) != RADINTERP_OK)
        return 0;
    radinterp__shade_span_scalar(m->shade + 24 * (size_t)tri, st, count, scalar);
    return memcmp(span, ref, 3 * count * sizeof(float)) == 0 && memcmp(scalar, ref, 3 * count * sizeof(float)) == 0;
}

/* Two views of the room rasterized into an ID and a barycentric buffer;
   each row's runs of one triangle shaded with radinterp_shade_span give
   the frame radinterp_shade gives, bit for bit (the lamp, an emitter, in
   view). */
static void test_runs_equal_shade(void)
{
    static const float eyes[2][3] = { { 0.6f, 0.5f, 1.2f }, { 3.6f, 3.4f, 2.4f } };
    static const float targets[2][3] = { { 2.2f, 2.2f, 2.9f }, { 1.0f, 1.2f, 0.5f } };
    const float up[3] = { 0, 0, 1 };
    radinterp_mesh *m = room;
    radinterp_mesh_data data;
    ex_raster r;
    float *span = (float *)malloc(3 * W * H * sizeof(float)), *ref = (float *)malloc(3 * W * H * sizeof(float));
    long runs = 0, pixels = 0, emitting = 0;
    int v, bad = 0;
    if (!m || !span || !ref || !CHECK(ex_raster_init(&r, W, H) == 0)) {
        free(span);
        free(ref);
        return;
    }
    radinterp_mesh_get_data(m, &data);
    for (v = 0; v < 2; v++) {
        ex_camera c = ex_camera_look_at(eyes[v], targets[v], up, 75.0f, W, H);
        int x, y, end;
        ex_raster_clear(&r);
        CHECK(ex_raster_draw(&r, &c, data.positions, data.indices, data.triangle_count, 0) == 0);
        memset(span, 0, 3 * W * H * sizeof(float));
        memset(ref, 0, 3 * W * H * sizeof(float));
        CHECK_EQ_INT(radinterp_shade(m, r.id, r.bary, (size_t)W * H, ref), RADINTERP_OK);
        for (y = 0; y < H; y++)
            for (x = 0; x < W; x = end) {
                size_t p = (size_t)y * W + (size_t)x;
                uint32_t id = r.id[p];
                for (end = x + 1; end < W && r.id[p + (size_t)(end - x)] == id;) end++;
                if (id == EX_RASTER_EMPTY) continue;
                bad += radinterp_shade_span(m, id, r.bary + 2 * p, (size_t)(end - x), span + 3 * p) != RADINTERP_OK;
                bad += !span_agrees(m, id, r.bary + 2 * p, (size_t)(end - x));
                emitting += data.emission[3 * (size_t)id] > 0.0f;
                runs++;
                pixels += end - x;
            }
        CHECK(memcmp(span, ref, 3 * W * H * sizeof(float)) == 0);
    }
    CHECK_EQ_INT(bad, 0);
    CHECK(emitting > 0);
    test_note("%u triangles; %ld runs of one triangle over 2 views, %.1f pixels a run, %ld of the lamp", data.triangle_count,
              runs, runs ? (double)pixels / (double)runs : 0.0, emitting);
    ex_raster_free(&r);
    free(span);
    free(ref);
}

/* Every run length from 1 to 64 on barycentrics inside and outside the
   triangle (to -2 and 3: the quadratic extends past it and goes negative,
   where the clamp gives 0): the SIMD kernel, the scalar one and
   radinterp_shade agree bit for bit, and nothing after the run's
   3 * count floats is written. */
static void test_span_lengths_and_clamp(void)
{
    radinterp_mesh *m = room;
    radinterp_mesh_info info;
    float st[2 * 64], out[3 * 64 + 4];
    uint64_t state = 12345;
    size_t count, i;
    int bad = 0, untouched = 1;
    long zeros = 0;
    if (!m) return;
    radinterp_mesh_get_info(m, &info);
    for (count = 1; count <= 64; count++) {
        uint32_t tri = (uint32_t)((count * 2654435761u) % info.triangle_count);
        for (i = 0; i < 2 * count; i++) {
            state = state * 6364136223846793005ull + 1442695040888963407ull;
            st[i] = -2.0f + 5.0f * (float)(state >> 40) / (float)(1u << 24);
        }
        bad += !span_agrees(m, tri, st, count);
        for (i = 0; i < 3 * 64 + 4; i++) out[i] = -7.0f;
        CHECK_EQ_INT(radinterp_shade_span(m, tri, st, count, out), RADINTERP_OK);
        for (i = 0; i < 3 * count; i++) zeros += out[i] == 0.0f;
        for (i = 3 * count; i < 3 * 64 + 4; i++) untouched &= out[i] == -7.0f;
    }
    CHECK_EQ_INT(bad, 0);
    CHECK(untouched);
    CHECK(zeros > 0);   /* the clamp was exercised */
    test_note("64 runs of 1 to 64 pixels: %ld channels clamped to 0", zeros);
}

/* A NULL mesh, a triangle not in the mesh (RADINTERP_NO_TRIANGLE among
   them) and NULL arrays give INVALID_ARGUMENT and leave the output alone;
   an empty run is fine with NULL arrays. */
static void test_span_bad_arguments(void)
{
    radinterp_mesh *m = room;
    radinterp_mesh_info info;
    float st[4] = { 0.25f, 0.25f, 0.5f, 0.1f }, out[6] = { -7, -7, -7, -7, -7, -7 };
    int i, untouched = 1;
    if (!m) return;
    radinterp_mesh_get_info(m, &info);
    CHECK_EQ_INT(radinterp_shade_span(NULL, 0, st, 2, out), RADINTERP_ERROR_INVALID_ARGUMENT);
    CHECK_EQ_INT(radinterp_shade_span(m, info.triangle_count, st, 2, out), RADINTERP_ERROR_INVALID_ARGUMENT);
    CHECK_EQ_INT(radinterp_shade_span(m, RADINTERP_NO_TRIANGLE, st, 2, out), RADINTERP_ERROR_INVALID_ARGUMENT);
    CHECK_EQ_INT(radinterp_shade_span(m, 0, NULL, 2, out), RADINTERP_ERROR_INVALID_ARGUMENT);
    CHECK_EQ_INT(radinterp_shade_span(m, 0, st, 2, NULL), RADINTERP_ERROR_INVALID_ARGUMENT);
    for (i = 0; i < 6; i++) untouched &= out[i] == -7.0f;
    CHECK(untouched);
    CHECK_EQ_INT(radinterp_shade_span(m, 0, NULL, 0, NULL), RADINTERP_OK);
    CHECK_EQ_INT(radinterp_shade_span(m, info.triangle_count - 1, st, 2, out), RADINTERP_OK);
}

int main(int argc, char **argv)
{
    int result;
    TEST_INIT(argc, argv);
    room = room_mesh();
    RUN(test_runs_equal_shade);
    RUN(test_span_lengths_and_clamp);
    RUN(test_span_bad_arguments);
    result = test_finish();
    radinterp_mesh_destroy(room);
    return result;
}
