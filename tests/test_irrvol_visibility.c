/* irrvol_visibility_ratio (thesis 6.1.3): the cosine-weighted open fraction
   of each vertex's hemisphere against its own mesh. Known answers: the form
   factor from the floor centre of an open box to its opening, a flat sheet
   (fully open), a closed cube seen from inside (fully closed). */
#define IRRVOL_IMPLEMENTATION
#include "irrvol.h"
#include "tests/test.h"
#include "tests/test_irrvol_scenes.h"
#include "examples/common/pool.h"


/* Open box: floor [-1, 1]^2 at y = 0 as four quads meeting at the centre
   vertex (vertex 2 of the first quad), walls up to y = 2, no top. */
static void open_box(sc_scene *s)
{
    float a[3], b[3], c[3], d[3];
    int qx, qz;
    memset(s, 0, sizeof *s);
    for (qz = 0; qz < 2; qz++)
        for (qx = 0; qx < 2; qx++) {
            float x0 = qx ? 0.0f : -1.0f, z0 = qz ? 0.0f : -1.0f;
            /* first quad's third vertex is the centre (0, 0, 0) */
            sc_set3(a, x0, 0, z0); sc_set3(b, x0 + 1, 0, z0); sc_set3(c, x0 + 1, 0, z0 + 1); sc_set3(d, x0, 0, z0 + 1);
            sc_quad(s, a, b, c, d, 0);
        }
    sc_square(s, 0, -1.0f, 1.0f, 0.0f, 1.0f, 0);   /* x = -1: y in [0, 2], z in [-1, 1] */
    sc_square(s, 0, 1.0f, 1.0f, 0.0f, 1.0f, 0);
    sc_square(s, 2, -1.0f, 0.0f, 1.0f, 1.0f, 0);   /* z = -1: x in [-1, 1], y in [0, 2] */
    sc_square(s, 2, 1.0f, 0.0f, 1.0f, 1.0f, 0);
}

static void test_open_box_floor_centre(void)
{
    sc_scene s;
    irrvol_visibility_desc d;
    float normals[4 * 3 * SC_MAX_QUADS], ratio[4 * SC_MAX_QUADS];
    /* form factor from the centre to the 2 x 2 opening at height 2: four
       corner rectangles with X = Y = 1/2 */
    double x = 0.5, f = 4.0 * (2.0 * x / sqrt(1 + x * x) * atan(x / sqrt(1 + x * x))) / (2.0 * SC_PI);
    uint32_t i;
    open_box(&s);
    for (i = 0; i < s.nv; i++) sc_set3(normals + 3 * i, 0, 1, 0);
    memset(&d, 0, sizeof d);
    d.positions = s.pos;
    d.vertex_count = s.nv;
    d.indices = s.idx;
    d.triangle_count = s.nt;
    d.normals = normals;
    d.rays = 4096;
    if (!CHECK_EQ_INT(irrvol_visibility_ratio(&d, ratio), IRRVOL_OK)) return;
    test_note("open box, floor centre: visibility ratio %.4f, form factor to the opening %.4f", ratio[2], f);
    CHECK_CLOSE(ratio[2], f, 0.0, 0.02);   /* 4096 stratified rays: binomial sigma 0.0067, 3 sigma */
    CHECK(f > 0.239 && f < 0.24);
    for (i = 0; i < s.nv; i++) CHECK(ratio[i] >= 0.0f && ratio[i] <= 1.0f);
    {   /* the same with 1 and 2 threads, bit for bit; and the limited distance */
        float again[4 * SC_MAX_QUADS];
        ex_pool *pool = ex_pool_create(2);
        d.parallel_for = ex_pool_parallel_for;
        d.parallel_user = pool;
        CHECK_EQ_INT(irrvol_visibility_ratio(&d, again), IRRVOL_OK);
        CHECK(memcmp(ratio, again, s.nv * sizeof(float)) == 0);
        d.max_distance = 1e-3f;   /* nothing that close above the floor */
        CHECK_EQ_INT(irrvol_visibility_ratio(&d, again), IRRVOL_OK);
        CHECK(again[2] == 1.0f);
        ex_pool_destroy(pool);
    }
}

static void test_sheet_and_closed_cube(void)
{
    sc_scene s;
    irrvol_visibility_desc d;
    float ratio[4 * SC_MAX_QUADS], inward[4 * 3 * SC_MAX_QUADS];
    uint32_t i, open = 0, closed = 0;
    memset(&s, 0, sizeof s);
    sc_square(&s, 1, 0.0f, 0.0f, 0.0f, 1.0f, 0);
    sc_square(&s, 1, 0.0f, 2.0f, 0.0f, 1.0f, 0);   /* two coplanar quads */
    memset(&d, 0, sizeof d);
    d.positions = s.pos;
    d.vertex_count = s.nv;
    d.indices = s.idx;
    d.triangle_count = s.nt;
    if (!CHECK_EQ_INT(irrvol_visibility_ratio(&d, ratio), IRRVOL_OK)) return;   /* computed normals */
    for (i = 0; i < s.nv; i++) open += ratio[i] == 1.0f;
    CHECK_EQ_INT(open, s.nv);
    sc_cube(&s);   /* closed: every hemisphere facing the inside is blocked */
    for (i = 0; i < s.nv; i++) {
        const float *p = s.pos + 3 * i;
        sc_set3(inward + 3 * i, -p[0], -p[1], -p[2]);   /* corner vertices: the inward diagonal */
    }
    d.positions = s.pos;
    d.vertex_count = s.nv;
    d.indices = s.idx;
    d.triangle_count = s.nt;
    d.normals = inward;
    if (!CHECK_EQ_INT(irrvol_visibility_ratio(&d, ratio), IRRVOL_OK)) return;
    for (i = 0; i < s.nv; i++) closed += ratio[i] == 0.0f;
    CHECK_EQ_INT(closed, s.nv);
}

static int cancel_now(void *user, uint64_t done, uint64_t total) { (void)user; (void)done; (void)total; return 1; }

static void test_visibility_bad_inputs(void)
{
    sc_scene s;
    irrvol_visibility_desc d, good;
    float ratio[4 * SC_MAX_QUADS];
    uint32_t bad[3] = {0, 1, 500};
    sc_cube(&s);
    memset(&good, 0, sizeof good);
    good.positions = s.pos;
    good.vertex_count = s.nv;
    good.indices = s.idx;
    good.triangle_count = s.nt;
    CHECK_EQ_INT(irrvol_visibility_ratio(NULL, ratio), IRRVOL_ERROR_INVALID_ARGUMENT);
    CHECK_EQ_INT(irrvol_visibility_ratio(&good, NULL), IRRVOL_ERROR_INVALID_ARGUMENT);
#define BAD(stmt) do { d = good; stmt; CHECK_EQ_INT(irrvol_visibility_ratio(&d, ratio), IRRVOL_ERROR_INVALID_ARGUMENT); } while (0)
    BAD(d.positions = NULL);
    BAD(d.triangle_count = 0);
    BAD(d.vertex_count = 0);
    BAD(d.indices = bad; d.triangle_count = 1);
    BAD(d.position_stride = 4);
    BAD(d.rays = 1u << 20);
    BAD(d.ray_offset = -1.0f);
    BAD(d.max_distance = NAN);
    BAD(d.normals = s.pos; d.normal_stride = 2);
    {   /* issue 17: 3 * 0x55555556 triangles wraps to 2 indices in 32 bits */
        uint32_t few[9] = {0, 1, 2, 0, 2, 3, 0, 1, 99};
        BAD(d.indices = few; d.triangle_count = 0x55555556u);
    }
#undef BAD
    s.pos[5] = NAN;
    d = good;
    CHECK_EQ_INT(irrvol_visibility_ratio(&d, ratio), IRRVOL_ERROR_INVALID_ARGUMENT);
    s.pos[5] = -1.0f;
    d.progress = cancel_now;
    CHECK_EQ_INT(irrvol_visibility_ratio(&d, ratio), IRRVOL_ERROR_CANCELLED);
}

int main(int argc, char **argv)
{
    TEST_INIT(argc, argv);
    RUN(test_open_box_floor_centre);
    RUN(test_sheet_and_closed_cube);
    RUN(test_visibility_bad_inputs);
    return test_finish();
}
