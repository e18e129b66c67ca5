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
    radinterp_material m[2] = {{{0.5f, 0.5f, 0.5f}, {0, 0, 0}, {0, 0, 0}}, {{0, 0, 0}, {1, 1, 1}, {0, 0, 0}}};
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
    {
        radinterp_mesh_desc md;
        radinterp_mesh *mesh = NULL;
        radinterp_mesh_data data;
        uint32_t id = 0;
        float st[2] = {0.25f, 0.25f}, b[3] = {-1, -1, -1}, e[3];
        memset(&md, 0, sizeof md);
        CHECK(radinterp_build_mesh(s, &md, &mesh) == RADINTERP_OK);
        radinterp_mesh_get_data(mesh, &data);
        CHECK(data.triangle_count > 0);
        CHECK(radinterp_shade(mesh, &id, st, 1, b) == RADINTERP_OK);
        CHECK(radinterp_eval(mesh, 0, st[0], st[1], e) == RADINTERP_OK && fabs(b[0] - e[0]) < 1e-5);
        radinterp_mesh_destroy(mesh);
    }
    radinterp_solution_destroy(s);
}

static void irrvol_link_radiance(void *user, const float org[3], const float dir[3], float rgb[3])
{
    (void)user; (void)org; (void)dir;
    rgb[0] = rgb[1] = rgb[2] = 1.0f;
}

static void test_irrvol_link(void)
{
    irrvol_desc d;
    irrvol *vol = NULL;
    float p[3] = {0.5f, 0.5f, 0.5f}, n[3] = {0.0f, 1.0f, 0.0f}, h[3];
    memset(&d, 0, sizeof d);
    d.radiance = irrvol_link_radiance;
    d.resolution = 3;
    d.bounds_max[0] = d.bounds_max[1] = d.bounds_max[2] = 1.0f;
    CHECK(irrvol_build(&d, &vol) == IRRVOL_OK);
    if (!vol) return;
    irrvol_query(vol, p, n, h);
    CHECK(h[0] > 3.0f && h[0] < 3.3f);   /* pi, within the k = 3 quadrature */
    irrvol_destroy(vol);
}

static void test_rendercache_links(void)
{
    rendercache_desc d;
    rendercache_camera cam;
    rendercache_pixel_request req[4];
    rendercache_sample s[4];
    rendercache *rc = NULL;
    uint32_t n = 0, i;
    memset(&d, 0, sizeof d);
    memset(&cam, 0, sizeof cam);
    d.width = cam.width = 8;
    d.height = cam.height = 6;
    cam.look_at[2] = 1.0f;
    cam.up[1] = 1.0f;
    cam.vfov_degrees = 60.0f;
    CHECK(rendercache_create(&d, &rc) == RENDERCACHE_OK);
    CHECK(rendercache_begin_frame(rc, &cam) == RENDERCACHE_OK);
    CHECK(rendercache_request(rc, req, 4, &n) == RENDERCACHE_OK && n == 4);
    memset(s, 0, sizeof s);
    for (i = 0; i < n; i++) {
        s[i].x = req[i].x;
        s[i].y = req[i].y;
        s[i].object = RENDERCACHE_MISS;
        s[i].rgb[0] = 1.0f;
    }
    CHECK(rendercache_insert(rc, s, n, NULL) == RENDERCACHE_OK);
    CHECK(rendercache_image(rc)[3 * (req[0].y * 8 + req[0].x)] == 1.0f);
    rendercache_destroy(rc);
}

static void test_rendercache_walkthrough_links(void)
{
    rendercache_camera cam;
    rendercache_range_image *img = NULL, *out = NULL;
    const rendercache_range_image *in[1];
    rendercache_warp_desc d;
    rendercache_warper *w = NULL;
    const uint32_t *ids[2];
    float f = 0.0f;
    memset(&cam, 0, sizeof cam);
    cam.kind = RENDERCACHE_CAMERA_FISHEYE;
    cam.look_at[2] = 1.0f;
    cam.up[1] = 1.0f;
    cam.width = cam.height = 8;
    memset(&d, 0, sizeof d);
    CHECK(rendercache_range_image_create(&cam, NULL, &img) == RENDERCACHE_OK);
    CHECK(rendercache_range_image_create(&cam, NULL, &out) == RENDERCACHE_OK);
    CHECK(rendercache_warper_create(&d, &w) == RENDERCACHE_OK);
    in[0] = img;
    CHECK(rendercache_warp(w, in, 1, NULL, RENDERCACHE_FILL_BOTH, out) == RENDERCACHE_OK);
    ids[0] = ids[1] = out->object;
    CHECK(rendercache_fitness(ids, 2, 8, 8, &f) == RENDERCACHE_OK && f == 1.0f);
    rendercache_warper_destroy(w);
    rendercache_range_image_destroy(img);
    rendercache_range_image_destroy(out);
}

static void test_lightvec_link(void)
{
    lightvec_cache *cache = NULL;
    lightvec_record rec;
    lightvec_lookup_result lr;
    memset(&rec, 0, sizeof rec);
    rec.normal[2] = rec.outgoing[2] = rec.vector.direction[2] = 1.0f;
    rec.distance = rec.visibility = 1.0f;
    CHECK(lightvec_cache_create(NULL, &cache) == LIGHTVEC_OK);
    CHECK(lightvec_insert(cache, &rec, NULL) == LIGHTVEC_OK);
    CHECK(lightvec_lookup(cache, rec.position, rec.normal, rec.outgoing, &lr) == LIGHTVEC_OK && lr.valid_count == 1);
    lightvec_cache_destroy(cache);
}

int main(int argc, char **argv)
{
    TEST_INIT(argc, argv);
    RUN(test_result_strings_link);
    RUN(test_radinterp_link);
    RUN(test_irrvol_link);
    RUN(test_rendercache_links);
    RUN(test_rendercache_walkthrough_links);
    RUN(test_lightvec_link);
    return test_finish();
}
