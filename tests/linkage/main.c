/* Linkage test, translation unit 2: uses every header through its
   declarations only, so the program links only if the implementation in
   impl.c has external linkage and matching signatures. */
#include "irrvol.h"
#include "radinterp.h"
#include "lightvec.h"
#include "rendercache.h"
#include "tests/test.h"

static void test_result_strings_link(void)
{
    CHECK(strcmp(irrvol_result_string(IRRVOL_OK), "ok") == 0);
    CHECK(strcmp(radinterp_result_string(RADINTERP_ERROR_CORRUPT_DATA), "corrupt data") == 0);
    CHECK(strcmp(lightvec_result_string(LIGHTVEC_ERROR_OUT_OF_MEMORY), "out of memory") == 0);
    CHECK(strcmp(rendercache_result_string(RENDERCACHE_ERROR_INVALID_ARGUMENT), "invalid argument") == 0);
}

static void test_radinterp_link(void)
{
    float p[3] = {0, 0, 0}, n[3] = {0, 0, 1}, h[3];
    float pos[24] = {-1, -1, 0, 1, -1, 0, 1, 1, 0, -1, 1, 0, -1, -1, 1, -1, 1, 1, 1, 1, 1, 1, -1, 1};
    uint32_t quads[8] = {0, 1, 2, 3, 4, 5, 6, 7};
    uint32_t mat[2] = {0, 1};
    radinterp_material m[2] = {{{0.5f, 0.5f, 0.5f}, {0, 0, 0}}, {{0, 0, 0}, {1, 1, 1}}};
    radinterp_desc d;
    radinterp_solution *s = NULL;
    /* a 2 x 2 square at height 1 above the element: Howell's 0.554126 */
    CHECK(fabs(radinterp_form_factor_point_polygon(p, n, pos + 12, 4) - 0.554126) < 1e-5);
    memset(&d, 0, sizeof d);
    d.positions = pos;
    d.vertex_count = 8;
    d.patches = quads;
    d.patch_count = 2;
    d.patch_materials = mat;
    d.materials = m;
    d.material_count = 2;
    CHECK(radinterp_solve(&d, &s) == RADINTERP_OK);
    CHECK(radinterp_irradiance_at_point(s, 0, p, NULL, h) == RADINTERP_OK);
    CHECK(fabs(h[0] - 0.554126) < 1e-3); /* the emitter is moved 1e-5 of the scene size behind its plane */
    radinterp_solution_destroy(s);
}

int main(int argc, char **argv)
{
    TEST_INIT(argc, argv);
    RUN(test_result_strings_link);
    RUN(test_radinterp_link);
    return test_finish();
}
