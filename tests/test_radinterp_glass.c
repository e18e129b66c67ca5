/* Unit tests of radinterp.h's glass and sky (GLASS AND SKY) with known
   answers: a box open at the top under a constant sky (the floor's
   irradiance is pi L times the view factor of the opening, in closed form),
   the same box under a glass roof (tf times that, per channel, the pane
   facing in or out), a pane between an emitter and a receiver (the received
   light scales by tf), an environment map that is constant over the upper
   hemisphere (the same answer bit for bit), determinism for any thread
   count, scenes without glass or sky left as they were, and the bad inputs
   (a transmittance outside [0, 1] or NaN, a negative, NaN or infinite sky,
   environment maps of bad dimensions or texels, too many sky rays). */
#define RADINTERP_IMPLEMENTATION
#include "../radinterp.h"
#include "examples/common/pool.h"
#include "test.h"

#define PI 3.14159265358979323846

typedef struct scene {
    float pos[3 * 128];
    uint32_t patch[4 * 32], mat[32];
    uint32_t nv, np;
    radinterp_material m[4];
} scene;

/* A rectangle of the plane `axis` = c (x 0, y 1, z 2) over [a0,a1] x [b0,b1]
   of the next two axes in cyclic order (y z, z x, x y), facing +axis (up)
   or -axis: counter-clockwise in those two axes is a front along +axis. */
static uint32_t add_rect(scene *s, int axis, float c, float a0, float a1, float b0, float b1, int up, uint32_t mat)
{
    int ia = (axis + 1) % 3, ib = (axis + 2) % 3, k;
    float uv[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
    uint32_t p = s->np++;
    for (k = 0; k < 4; k++) {
        int corner = up ? k : (4 - k) % 4;
        float *x = s->pos + 3 * s->nv;
        x[axis] = c;
        x[ia] = uv[corner][0] ? a1 : a0;
        x[ib] = uv[corner][1] ? b1 : b0;
        s->patch[4 * p + k] = s->nv++;
    }
    s->mat[p] = mat;
    return p;
}

static radinterp_desc scene_desc(const scene *s, uint32_t materials)
{
    radinterp_desc d;
    memset(&d, 0, sizeof d);
    d.positions = s->pos;
    d.vertex_count = s->nv;
    d.patches = s->patch;
    d.patch_count = s->np;
    d.patch_materials = s->mat;
    d.materials = s->m;
    d.material_count = materials;
    d.seed = 3;
    /* elements no smaller than (diagonal / 50)^2: the sky refines the floor
       everywhere (its irradiance varies all over it), and the answers checked
       here are a point query, which sums the sky at the point itself, and
       area means, which coarser elements keep; 16 times fewer elements keep
       the test to seconds under the sanitizers */
    {
        float lo[3] = {1e30f, 1e30f, 1e30f}, hi[3] = {-1e30f, -1e30f, -1e30f};
        uint32_t v, k;
        for (v = 0; v < s->nv; v++)
            for (k = 0; k < 3; k++) {
                lo[k] = s->pos[3 * v + k] < lo[k] ? s->pos[3 * v + k] : lo[k];
                hi[k] = s->pos[3 * v + k] > hi[k] ? s->pos[3 * v + k] : hi[k];
            }
        d.min_area = ((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
                      (hi[2] - lo[2]) * (hi[2] - lo[2])) / 2500.0f;
    }
    return d;
}

enum { FLOOR, WALL, PANE };

/* The box [-1,1] x [0,1] x [-1,1] (y up), every surface facing in, walls
   black; open at the top, or closed by a pane (facing in or out) of
   material PANE with transmittance tf and no reflectance. */
static void open_box(scene *s, float floor_rho, const float *tf, int pane_up)
{
    memset(s, 0, sizeof *s);
    s->m[FLOOR].reflectance[0] = s->m[FLOOR].reflectance[1] = s->m[FLOOR].reflectance[2] = floor_rho;
    add_rect(s, 1, 0.0f, -1, 1, -1, 1, 1, FLOOR);   /* y = 0, facing +y */
    add_rect(s, 0, -1.0f, 0, 1, -1, 1, 1, WALL);    /* x = -1, facing +x */
    add_rect(s, 0, 1.0f, 0, 1, -1, 1, 0, WALL);     /* x = 1, facing -x */
    add_rect(s, 2, -1.0f, -1, 1, 0, 1, 1, WALL);    /* z = -1, facing +z */
    add_rect(s, 2, 1.0f, -1, 1, 0, 1, 0, WALL);     /* z = 1, facing -z */
    if (tf) {
        memcpy(s->m[PANE].transmittance, tf, 3 * sizeof(float));
        add_rect(s, 1, 1.0f, -1, 1, -1, 1, pane_up, PANE);
    }
}

/* Eq. 6.1's closed form for a point under the centre of a parallel a x b
   rectangle at height c: 4 corner rectangles of (a/2) x (b/2). */
static double ff_centre(double a, double b, double c)
{
    double x = a / (2.0 * c), y = b / (2.0 * c);
    return 2.0 / PI * (x / sqrt(1 + x * x) * atan(y / sqrt(1 + x * x)) + y / sqrt(1 + y * y) * atan(x / sqrt(1 + y * y)));
}

/* Patch-to-patch form factor between directly opposed parallel a x b
   rectangles at distance c (Howell's catalogue, C-11). */
static double ff_parallel(double a, double b, double c)
{
    double x = a / c, y = b / c, x1 = 1 + x * x, y1 = 1 + y * y;
    return 2.0 / (PI * x * y) *
           (0.5 * log(x1 * y1 / (x1 + y * y)) + x * sqrt(y1) * atan(x / sqrt(y1)) + y * sqrt(x1) * atan(y / sqrt(x1)) -
            x * atan(x) - y * atan(y));
}

static const float sky_l[3] = {1.0f, 2.0f, 3.0f};
static const float pane_tf[3] = {0.8f, 0.6f, 0.4f};

/* The floor faces up: a check of the scene builder itself. */
static int floor_faces_up(const scene *s)
{
    const float *a = s->pos + 3 * s->patch[0], *b = s->pos + 3 * s->patch[1], *c = s->pos + 3 * s->patch[2];
    float e1[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, e2[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    return e1[2] * e2[0] - e1[0] * e2[2] > 0.0f;
}

/* Floor centre irradiance (point query) and floor radiosity (solution)
   under the sky, open or under the pane; tf NULL = open. */
static void box_answers(const float *tf, int pane_up, uint32_t sky_rays, float centre[3], float floor_b[3])
{
    scene s;
    radinterp_desc d;
    radinterp_solution *sol = NULL;
    float p[3] = {0.0f, 0.0f, 0.0f};
    open_box(&s, 0.5f, tf, pane_up);
    CHECK(floor_faces_up(&s));
    d = scene_desc(&s, tf ? 3 : 2);
    memcpy(d.sky, sky_l, sizeof sky_l);
    d.sky_rays = sky_rays;
    centre[0] = centre[1] = centre[2] = floor_b[0] = floor_b[1] = floor_b[2] = -1.0f;
    if (!CHECK_EQ_INT(radinterp_solve(&d, &sol), RADINTERP_OK)) return;
    {
        radinterp_info info;
        radinterp_solution_info(sol, &info);
        CHECK_EQ_INT(info.glass_patches, tf && (tf[0] > 0.0f || tf[1] > 0.0f || tf[2] > 0.0f) ? 1 : 0);
    }
    CHECK_EQ_INT(radinterp_irradiance_at_point(sol, 0, p, NULL, centre), RADINTERP_OK);
    CHECK_EQ_INT(radinterp_patch_radiosity(sol, 0, floor_b), RADINTERP_OK);
    radinterp_solution_destroy(sol);
}

/* The open box: E(centre) = pi L F(centre -> opening) with the walls black
   and the floor's own light leaving through the opening or into black
   walls; the floor's mean radiosity = rho pi L F(floor -> opening). */
static void test_open_box_under_sky(void)
{
    float centre[3], floor_b[3];
    double f_point = ff_centre(2, 2, 1), f_floor = ff_parallel(2, 2, 1);
    int k;
    box_answers(NULL, 0, 4096, centre, floor_b);
    for (k = 0; k < 3; k++) {
        /* 4096 rays in a 64 x 64 jittered grid: only the strata the
           opening's outline crosses (a few hundred) vary, each by at most
           1/4096 of the hemisphere: a few tenths of a percent (0.4%
           measured), 1% allowed */
        CHECK_CLOSE(centre[k], PI * sky_l[k] * f_point, 0.01, 0);
        /* the floor's leaves each average sky_rays rays over their own
           area; the mean over the floor is within 1% as well */
        CHECK_CLOSE(floor_b[k], 0.5 * PI * sky_l[k] * f_floor, 0.01, 0);
    }
    test_note("open box: E(centre) %.5f (pi L F = %.5f), floor B %.5f (rho pi L F = %.5f), green channel", centre[1],
              PI * sky_l[1] * f_point, floor_b[1], 0.5 * PI * sky_l[1] * f_floor);
}

/* The box under a glass roof: tf times the open box's answers, per
   channel, the pane facing in or out (light crosses a pane from either
   side). The rays are the same as the open box's (the pane is crossed, not
   sampled), so the ratio is exact up to float rounding. */
static void test_glass_roof_scales_by_tf(void)
{
    float open_c[3], open_b[3];
    int up, k;
    box_answers(NULL, 0, 1024, open_c, open_b);
    for (up = 0; up < 2; up++) {
        float c[3], b[3];
        box_answers(pane_tf, up, 1024, c, b);
        for (k = 0; k < 3; k++) {
            CHECK_CLOSE(c[k], pane_tf[k] * open_c[k], 1e-5, 0);   /* float rounding of the sums */
            /* the leaves' sky estimates use random streams keyed by node
               index, which the pane's own quadtree shifts: 1% covers their
               noise (0.1% measured) */
            CHECK_CLOSE(b[k], pane_tf[k] * open_b[k], 0.01, 0);
        }
        test_note("glass roof facing %s: E(centre) %.5f %.5f %.5f = tf x open %.5f %.5f %.5f", up ? "out" : "in", c[0],
                  c[1], c[2], pane_tf[0] * open_c[0], pane_tf[1] * open_c[1], pane_tf[2] * open_c[2]);
    }
}

/* An emitter (1 x 1 at y = 1, facing down) over a receiver (1 x 1 at y = 0,
   facing up), with or without a pane at y = 0.5 wider than both (every ray
   between them crosses it): the receiver's irradiance, at its centre and
   as its radiosity, scales by tf. With two panes, by the product. */
static void pane_between(int panes, float centre[3], float b[3])
{
    scene s;
    radinterp_desc d;
    radinterp_solution *sol = NULL;
    float p[3] = {0.0f, 0.0f, 0.0f};
    memset(&s, 0, sizeof s);
    s.m[0].reflectance[0] = s.m[0].reflectance[1] = s.m[0].reflectance[2] = 0.5f;
    s.m[1].emission[0] = s.m[1].emission[1] = s.m[1].emission[2] = 10.0f;
    memcpy(s.m[2].transmittance, pane_tf, sizeof pane_tf);
    s.m[3].transmittance[0] = s.m[3].transmittance[1] = s.m[3].transmittance[2] = 0.5f;
    add_rect(&s, 1, 0.0f, -0.5f, 0.5f, -0.5f, 0.5f, 1, 0);   /* receiver, facing +y */
    add_rect(&s, 1, 1.0f, -0.5f, 0.5f, -0.5f, 0.5f, 0, 1);   /* emitter, facing -y */
    if (panes > 0) add_rect(&s, 1, 0.5f, -2, 2, -2, 2, 1, 2);
    if (panes > 1) add_rect(&s, 1, 0.6f, -2, 2, -2, 2, 0, 3);
    d = scene_desc(&s, 4);
    d.clustering = RADINTERP_CLUSTERING_OFF;   /* patch-to-patch links: no cluster transfer estimate in the way */
    centre[0] = centre[1] = centre[2] = b[0] = b[1] = b[2] = -1.0f;
    if (!CHECK_EQ_INT(radinterp_solve(&d, &sol), RADINTERP_OK)) return;
    CHECK_EQ_INT(radinterp_irradiance_at_point(sol, 0, p, NULL, centre), RADINTERP_OK);
    CHECK_EQ_INT(radinterp_patch_radiosity(sol, 0, b), RADINTERP_OK);
    radinterp_solution_destroy(sol);
}

static void test_pane_between_emitter_and_receiver(void)
{
    float c0[3], b0[3], c1[3], b1[3], c2[3], b2[3];
    int k;
    pane_between(0, c0, b0);
    pane_between(1, c1, b1);
    pane_between(2, c2, b2);
    /* eq. 6.1 is exact without blockers; the source is moved push_off =
       1e-5 diag behind its plane (6.4), which lowers F by 3e-5 here */
    CHECK_CLOSE(c0[0], 10.0 * ff_centre(1, 1, 1), 1e-4, 0);
    for (k = 0; k < 3; k++) {
        /* the point factor through the panes is the clear factor: only the
           push-off differs, the panes make the scene's diagonal (and so
           push_off) 3.3 times larger, 6e-5 of F */
        CHECK_CLOSE(c1[k], pane_tf[k] * c0[k], 2e-4, 0);
        CHECK_CLOSE(c2[k], 0.5 * pane_tf[k] * c0[k], 2e-4, 0);
        /* the solver refines each scene by its own error estimate (the link
           through a pane carries less, so it is refined less): the
           receiver's mean differs by the discretisation, 0.3% at most here */
        CHECK_CLOSE(b1[k], pane_tf[k] * b0[k], 0.005, 0);
        CHECK_CLOSE(b2[k], 0.5 * pane_tf[k] * b0[k], 0.005, 0);
    }
    test_note("pane between: E(centre) %.5f clear, %.5f through tf 0.8, %.5f through 0.8 and 0.5", c0[0], c1[0], c2[0]);
}

/* A latitude-longitude map whose upper rows hold L and lower rows 0 gives
   every surface under an opening above it the constant sky's answer bit
   for bit (every ray that reaches the sky goes up); a map of one texel L is
   the constant sky everywhere. */
static void test_environment_map(void)
{
    scene s;
    radinterp_desc d;
    float map[4 * 2 * 3], one[3], ref[3], got[3], p[3] = {0.2f, 0.0f, -0.3f};
    int i, which;
    for (i = 0; i < 8; i++) memcpy(map + 3 * i, i < 4 ? sky_l : (const float[3]){0.0f, 0.0f, 0.0f}, sizeof sky_l);
    memcpy(one, sky_l, sizeof one);
    open_box(&s, 0.5f, NULL, 0);
    for (which = 0; which < 3; which++) {
        radinterp_solution *sol = NULL;
        d = scene_desc(&s, 2);
        memcpy(d.sky, sky_l, sizeof sky_l);
        if (which == 1) { d.environment = map; d.environment_width = 4; d.environment_height = 2; }
        if (which == 2) { memset(d.sky, 0, sizeof d.sky); d.environment = one; d.environment_width = d.environment_height = 1; }
        if (!CHECK_EQ_INT(radinterp_solve(&d, &sol), RADINTERP_OK)) return;
        CHECK_EQ_INT(radinterp_irradiance_at_point(sol, 0, p, NULL, which ? got : ref), RADINTERP_OK);
        if (which) CHECK(memcmp(got, ref, sizeof got) == 0);
        radinterp_solution_destroy(sol);
    }
}

/* A window room (the box closed by a roof with a pane in its middle, an
   emitter on a wall) solved serially and with 3 threads: bit-identical. */
static void test_deterministic_with_glass_and_sky(void)
{
    scene s;
    radinterp_desc d;
    radinterp_solution *a = NULL, *b = NULL;
    ex_pool *pool = ex_pool_create(3);
    uint32_t i, n;
    open_box(&s, 0.5f, NULL, 0);
    add_rect(&s, 1, 1.0f, -1, -0.3f, -1, 1, 0, WALL);
    add_rect(&s, 1, 1.0f, 0.3f, 1, -1, 1, 0, WALL);
    add_rect(&s, 1, 1.0f, -0.3f, 0.3f, -1, -0.3f, 0, WALL);
    add_rect(&s, 1, 1.0f, -0.3f, 0.3f, 0.3f, 1, 0, WALL);
    add_rect(&s, 1, 1.0f, -0.3f, 0.3f, -0.3f, 0.3f, 0, PANE);
    memcpy(s.m[PANE].transmittance, pane_tf, sizeof pane_tf);
    s.m[WALL].reflectance[0] = s.m[WALL].reflectance[1] = s.m[WALL].reflectance[2] = 0.6f;
    d = scene_desc(&s, 3);
    memcpy(d.sky, sky_l, sizeof sky_l);
    if (!CHECK(radinterp_solve(&d, &a) == RADINTERP_OK)) return;
    d.parallel_for = ex_pool_parallel_for;
    d.parallel_user = pool;
    if (CHECK(radinterp_solve(&d, &b) == RADINTERP_OK)) {
        n = radinterp_leaf_count(a);
        CHECK_EQ_INT(radinterp_leaf_count(b), n);
        for (i = 0; i < n && i < radinterp_leaf_count(b); i++) {
            radinterp_leaf la, lb;
            radinterp_get_leaf(a, i, &la);
            radinterp_get_leaf(b, i, &lb);
            if (!CHECK(memcmp(la.radiosity, lb.radiosity, sizeof la.radiosity) == 0)) break;
        }
    }
    radinterp_solution_destroy(a);
    radinterp_solution_destroy(b);
    ex_pool_destroy(pool);
}

/* Bad inputs: INVALID_ARGUMENT, nothing allocated (ASan checks leaks). */
static void test_bad_inputs(void)
{
    static const float bad[] = {-0.1f, 1.5f, NAN, INFINITY};
    scene s;
    radinterp_desc d;
    radinterp_solution *sol;
    float map[3 * 4] = {1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1};
    uint32_t i;
    int k;
    open_box(&s, 0.5f, pane_tf, 0);
    for (i = 0; i < sizeof bad / sizeof bad[0]; i++)
        for (k = 0; k < 3; k++) {
            memcpy(s.m[PANE].transmittance, pane_tf, sizeof pane_tf);
            s.m[PANE].transmittance[k] = bad[i];
            d = scene_desc(&s, 3);
            sol = (radinterp_solution *)&s;
            CHECK_EQ_INT(radinterp_solve(&d, &sol), RADINTERP_ERROR_INVALID_ARGUMENT);
            CHECK(sol == NULL);
        }
    memcpy(s.m[PANE].transmittance, pane_tf, sizeof pane_tf);
    for (i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        if (bad[i] == 1.5f) continue;   /* a sky may be brighter than 1 */
        for (k = 0; k < 3; k++) {
            d = scene_desc(&s, 3);
            memcpy(d.sky, sky_l, sizeof sky_l);
            d.sky[k] = bad[i];
            CHECK_EQ_INT(radinterp_solve(&d, &sol), RADINTERP_ERROR_INVALID_ARGUMENT);
            d = scene_desc(&s, 3);
            d.environment = map;
            d.environment_width = 2;
            d.environment_height = 2;
            map[3 * 3 + k] = bad[i];   /* the last texel */
            CHECK_EQ_INT(radinterp_solve(&d, &sol), RADINTERP_ERROR_INVALID_ARGUMENT);
            map[3 * 3 + k] = 1.0f;
        }
    }
    d = scene_desc(&s, 3);
    d.environment = map;
    d.environment_width = 0;
    d.environment_height = 2;
    CHECK_EQ_INT(radinterp_solve(&d, &sol), RADINTERP_ERROR_INVALID_ARGUMENT);
    d.environment_width = 2;
    d.environment_height = 0;
    CHECK_EQ_INT(radinterp_solve(&d, &sol), RADINTERP_ERROR_INVALID_ARGUMENT);
    d.environment_width = RADINTERP_MAX_ENVIRONMENT_SIZE + 1;
    d.environment_height = 1;
    CHECK_EQ_INT(radinterp_solve(&d, &sol), RADINTERP_ERROR_INVALID_ARGUMENT);
    d.environment_width = 1;
    d.environment_height = RADINTERP_MAX_ENVIRONMENT_SIZE + 1;
    CHECK_EQ_INT(radinterp_solve(&d, &sol), RADINTERP_ERROR_INVALID_ARGUMENT);
    d = scene_desc(&s, 3);
    d.sky_rays = RADINTERP_MAX_SKY_RAYS + 1;
    CHECK_EQ_INT(radinterp_solve(&d, &sol), RADINTERP_ERROR_INVALID_ARGUMENT);
    d.sky_rays = RADINTERP_MAX_SKY_RAYS;   /* the limit itself is accepted */
    d.sky[0] = 1.0f;
    if (CHECK_EQ_INT(radinterp_solve(&d, &sol), RADINTERP_OK)) radinterp_solution_destroy(sol);
}

/* A pane of transmittance 0 is an opaque patch: the box closed by it is
   dark under the sky. */
static void test_zero_transmittance_is_opaque(void)
{
    float c0[3], b0[3];
    float zero[3] = {0.0f, 0.0f, 0.0f};
    box_answers(zero, 0, 256, c0, b0);
    CHECK(c0[0] == 0.0f && c0[1] == 0.0f && c0[2] == 0.0f);   /* the closed box: no sky reaches the floor */
    CHECK(b0[0] == 0.0f && b0[1] == 0.0f && b0[2] == 0.0f);
}

int main(int argc, char **argv)
{
    TEST_INIT(argc, argv);
    RUN(test_open_box_under_sky);
    RUN(test_glass_roof_scales_by_tf);
    RUN(test_pane_between_emitter_and_receiver);
    RUN(test_environment_map);
    RUN(test_deterministic_with_glass_and_sky);
    RUN(test_bad_inputs);
    RUN(test_zero_transmittance_is_opaque);
    return test_finish();
}
