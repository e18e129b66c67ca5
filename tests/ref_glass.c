/* Reference tests of thin glass and the sky in the reference renderer
   (tests/reference: next-event rays through panes, paths through or off
   them, rays that leave the scene see the sky) and in the examples' tracer
   (examples/common/trace.h): closed-form irradiance through a window from a
   constant sky, from an environment map and from an area light; a point
   inside nested glass boxes; and, with interreflection, the tracer against
   the reference in a glass-roofed room. These are the references the
   headers' glass tests will stand on. */
#include "examples/common/trace.h"
#include "tests/reference/ref.h"
#include "tests/test.h"

#define PI 3.14159265358979323846

static int write_file(const char *path, const char *text)
{
    FILE *f = fopen(path, "w");
    if (!f) return 0;
    fputs(text, f);
    return fclose(f) == 0;
}

static int load(const char *obj, const char *mtl, obj_scene *s)
{
    char err[256], text[8192], name[256], path[512];
    snprintf(text, sizeof text, "mtllib %s\n%s", test_scratch_name(name, sizeof name, "glass.mtl"), obj);
    if (!CHECK(write_file(test_scratch_path(path, sizeof path, "glass.mtl"), mtl))) return 0;
    return CHECK_MSG(obj_parse(text, strlen(text), "glass.obj", TEST_SCRATCH_DIR, s, err, sizeof err) == 0, "%s", err);
}

/* Form factor from a point to a parallel rectangle a x b at height c, the
   point below one corner (Howell's catalogue, C-11). */
static double form_factor_corner(double a, double b, double c)
{
    double A = a / c, B = b / c, sa = sqrt(1 + A * A), sb = sqrt(1 + B * B);
    return (A / sa * atan(B / sa) + B / sb * atan(A / sb)) / (2 * PI);
}

/* A closed room [-1,1] x [0,2] x [-1,1] (walls facing in, reflectance wall
   for walls and ceiling, floor for the floor) with a glass window
   [-0.5,0.5]^2 in the ceiling: transmittance (0.8, 0.6, 0.4), reflectance
   pane (its diffuse part), facing down or up. */
static int glass_room(obj_scene *s, float wall, float floor_kd, float pane, int window_faces_up)
{
    char mtl[512], obj[3000];
    /* Kd of glass keeps 1 - Tf of itself: write pane / (1 - Tf) per channel */
    snprintf(mtl, sizeof mtl,
             "newmtl wall\nKd %g %g %g\nnewmtl floor\nKd %g %g %g\n"
             "newmtl glass\nKd %.9g %.9g %.9g\nTf 0.8 0.6 0.4\nillum 4\n",
             wall, wall, wall, floor_kd, floor_kd, floor_kd, pane / 0.2, pane / 0.4, pane / 0.6);
    snprintf(obj, sizeof obj,
             "v -1 0 -1\nv 1 0 -1\nv 1 0 1\nv -1 0 1\n"
             "v -1 2 -1\nv 1 2 -1\nv 1 2 1\nv -1 2 1\n"
             "v -0.5 2 -0.5\nv 0.5 2 -0.5\nv 0.5 2 0.5\nv -0.5 2 0.5\n"
             "usemtl floor\nf 1 4 3 2\n"
             "usemtl wall\n"
             "f 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\n"
             "f 5 6 10 9\nf 6 7 11 10\nf 7 8 12 11\nf 8 5 9 12\n"
             "usemtl glass\n%s\n",
             window_faces_up ? "f 9 12 11 10" : "f 9 10 11 12");
    return load(obj, mtl, s);
}

static const float up_normal[3] = { 0, 1, 0 };

/* A black room under a constant sky L: the floor's centre receives
   E = pi tf L F through the window, whichever way the pane faces and
   whatever diffuse reflectance it has (a black room sends it nothing). */
static void test_sky_through_window(void)
{
    const float L[3] = { 1.0f, 2.0f, 3.0f }, tf[3] = { 0.8f, 0.6f, 0.4f }, p[3] = { 0, 0, 0 };
    double F = 4 * form_factor_corner(0.5, 0.5, 2.0);
    ex_sky sky;
    int up, reflecting, k;
    memset(&sky, 0, sizeof sky);
    memcpy(sky.radiance, L, sizeof L);
    for (up = 0; up < 2; up++)
        for (reflecting = 0; reflecting < 2; reflecting++) {
            obj_scene o;
            ref_scene *s;
            ref_estimate e;
            if (!glass_room(&o, 0.0f, 0.0f, reflecting ? 0.1f : 0.0f, up)) return;
            s = ref_scene_from_obj(&o);
            if (!CHECK(s && ref_scene_set_sky(s, &sky) == 0)) { obj_free(&o); return; }
            e = ref_irradiance_gi(s, p, up_normal, 400000, 7);
            for (k = 0; k < 3; k++)   /* Bernoulli-like samples: 4 standard errors */
                CHECK_CLOSE(e.mean[k], PI * tf[k] * L[k] * F, 0, 4 * e.std_error[k]);
            test_note("window facing %s, pane kd %s: E = %.5f (expected %.5f, standard error %.5f)", up ? "out" : "in",
                      reflecting ? "0.1" : "0", e.mean[0], PI * tf[0] * L[0] * F, e.std_error[0]);
            ref_scene_destroy(s);
            obj_free(&o);
        }
}

/* A point inside two nested closed glass boxes (tf 0.5 and 0.8, both with
   the faces out) under a constant sky: every direction crosses each box
   once, E = pi 0.4 L. */
static void test_nested_glass_boxes(void)
{
    static const char *mtl = "newmtl outer\nKd 0 0 0\nTf 0.5\nillum 4\nnewmtl inner\nKd 0 0 0\nTf 0.8\nillum 6\n";
    char obj[4000], *q = obj;
    const float p[3] = { 0.1f, -0.2f, 0.3f }, n[3] = { 0.3f, 0.8f, -0.5f };
    obj_scene o;
    ref_scene *s;
    ref_estimate e;
    ex_sky sky;
    int box, k;
    for (box = 0; box < 2; box++) {
        double h = box ? 1.0 : 3.0;
        q += sprintf(q, "usemtl %s\n", box ? "inner" : "outer");
        q += sprintf(q, "v %g %g %g\nv %g %g %g\nv %g %g %g\nv %g %g %g\n", -h, -h, -h, h, -h, -h, h, h, -h, -h, h, -h);
        q += sprintf(q, "v %g %g %g\nv %g %g %g\nv %g %g %g\nv %g %g %g\n", -h, -h, h, h, -h, h, h, h, h, -h, h, h);
        q += sprintf(q, "f -8 -5 -6 -7\nf -4 -3 -2 -1\nf -8 -7 -3 -4\nf -5 -1 -2 -6\nf -8 -4 -1 -5\nf -7 -6 -2 -3\n");
    }
    if (!load(obj, mtl, &o)) return;
    s = ref_scene_from_obj(&o);
    memset(&sky, 0, sizeof sky);
    sky.radiance[0] = 1.0f; sky.radiance[1] = 0.5f; sky.radiance[2] = 2.0f;
    if (!CHECK(s && ref_scene_set_sky(s, &sky) == 0)) { obj_free(&o); return; }
    e = ref_irradiance_gi(s, p, n, 20000, 3);
    for (k = 0; k < 3; k++)   /* every sample is the same up to float rounding */
        CHECK_CLOSE(e.mean[k], PI * 0.4 * sky.radiance[k], 1e-5, 0);
    ref_scene_destroy(s);
    obj_free(&o);
}

/* An endless floor under an environment map of 8 x 6 texels (radiance by
   row and column, bright below the horizon, which the floor hides): E in
   closed form (ex_sky_irradiance_up). */
static void test_environment_map(void)
{
    static const char *obj = "v -1000 0 -1000\nv 1000 0 -1000\nv 1000 0 1000\nv -1000 0 1000\nusemtl floor\nf 1 4 3 2\n";
    float map[8 * 6 * 3];
    const float p[3] = { 0, 0, 0 };
    obj_scene o;
    ref_scene *s;
    ref_estimate e;
    ex_sky sky;
    double exact[3];
    int i, k;
    for (i = 0; i < 8 * 6; i++) {
        map[3 * i] = (float)(1 + i / 8);
        map[3 * i + 1] = (float)(1 + i % 8);
        map[3 * i + 2] = i / 8 < 3 ? 2.0f : 50.0f;
    }
    memset(&sky, 0, sizeof sky);
    sky.map = map;
    sky.width = 8;
    sky.height = 6;
    ex_sky_irradiance_up(&sky, exact);
    if (!load(obj, "newmtl floor\nKd 0 0 0\n", &o)) return;
    s = ref_scene_from_obj(&o);
    if (!CHECK(s && ref_scene_set_sky(s, &sky) == 0)) { obj_free(&o); return; }
    e = ref_irradiance_gi(s, p, up_normal, 200000, 5);
    for (k = 0; k < 3; k++) CHECK_CLOSE(e.mean[k], exact[k], 0, 4 * e.std_error[k] + 1e-9);
    test_note("environment map: E = (%.4f %.4f %.4f), expected (%.4f %.4f %.4f)", e.mean[0], e.mean[1], e.mean[2], exact[0],
              exact[1], exact[2]);
    ref_scene_destroy(s);
    obj_free(&o);
}

/* A 2 x 2 lamp of radiance 2 at height 1 over a black floor, a pane of tf
   0.5 at height 0.8 between them: E = tf pi Ke F, F = 0.554126. The pane
   reflects (kd 0.2, so paths choose between passing and reflecting) but
   only sees the black floor and, from behind, nothing: the answer stays. */
static void test_area_light_through_pane(void)
{
    static const char *mtl =
        "newmtl lamp\nKd 0 0 0\nKe 2 2 2\nnewmtl floor\nKd 0 0 0\nnewmtl pane\nKd 0.4 0.4 0.4\nTf 0.5\nillum 4\n";
    static const char *obj =
        "v -1 1 -1\nv 1 1 -1\nv 1 1 1\nv -1 1 1\n"
        "v -50 0 -50\nv 50 0 -50\nv 50 0 50\nv -50 0 50\n"
        "v -9 0.8 -9\nv 9 0.8 -9\nv 9 0.8 9\nv -9 0.8 9\n"
        "usemtl lamp\nf 1 2 3 4\nusemtl floor\nf 5 8 7 6\nusemtl pane\nf 9 10 11 12\n";
    const float p[3] = { 0, 0, 0 };
    obj_scene o;
    ref_scene *s;
    ref_estimate e;
    if (!load(obj, mtl, &o)) return;
    s = ref_scene_from_obj(&o);
    if (!CHECK(s != NULL)) { obj_free(&o); return; }
    e = ref_irradiance_gi(s, p, up_normal, 100000, 11);
    CHECK_CLOSE(e.mean[0], 0.5 * PI * 2.0 * 0.554126, 0, 4 * e.std_error[0] + 1e-5);
    test_note("area light through a pane: E = %.5f (expected %.5f, standard error %.5f)", e.mean[0],
              0.5 * PI * 2.0 * 0.554126, e.std_error[0]);
    ref_scene_destroy(s);
    obj_free(&o);
}

/* With interreflection (grey walls 0.5, floor 0.6, a pane reflecting 0.1):
   the examples' tracer with 16 bounces (what it leaves out, 0.6^16 of the
   light, is 3e-4) against the reference, at the floor's centre and off it:
   floor radiance = kd / pi E. */
static void test_tracer_agrees_with_reference(void)
{
    const float points[2][3] = { { 0, 0, 0 }, { 0.6f, 0, -0.4f } };
    ex_sky sky;
    int i, k;
    memset(&sky, 0, sizeof sky);
    sky.radiance[0] = 1.0f; sky.radiance[1] = 1.5f; sky.radiance[2] = 2.0f;
    for (i = 0; i < 2; i++) {
        obj_scene o;
        ref_scene *s;
        ex_tracer *t;
        ref_estimate e;
        double sum[3] = { 0, 0, 0 }, sum2[3] = { 0, 0, 0 };
        float org[3] = { points[i][0], 1.0f, points[i][2] }, down[3] = { 0, -1, 0 };
        ex_rng r = ex_rng_stream(17, (uint64_t)i);
        int n = 100000, j;
        if (!glass_room(&o, 0.5f, 0.6f, 0.1f, i)) return;
        s = ref_scene_from_obj(&o);
        t = ex_tracer_create(&o);
        if (!CHECK(s && t && ref_scene_set_sky(s, &sky) == 0 && ex_tracer_set_sky(t, &sky) == 0)) return;
        e = ref_irradiance_gi(s, points[i], up_normal, 200000, 13 + (uint64_t)i);
        for (j = 0; j < n; j++) {
            float rgb[3];
            ex_tracer_shade(t, org, down, 16, &r, rgb, NULL);
            for (k = 0; k < 3; k++) { sum[k] += rgb[k]; sum2[k] += (double)rgb[k] * rgb[k]; }
        }
        for (k = 0; k < 3; k++) {
            double mean = sum[k] / n, se = sqrt(fmax(0.0, sum2[k] / n - mean * mean) / (n - 1));
            double expected = 0.6 / PI * e.mean[k], se_ref = 0.6 / PI * e.std_error[k];
            /* 4 combined standard errors, plus the tracer's truncation
               (0.6^16 relative) */
            CHECK_CLOSE(mean, expected, 3e-4, 4 * sqrt(se * se + se_ref * se_ref));
            if (k == 0)
                test_note("glass room point %d: tracer %.5f +- %.5f, reference %.5f +- %.5f", i, mean, se, expected, se_ref);
        }
        ex_tracer_destroy(t);
        ref_scene_destroy(s);
        obj_free(&o);
    }
}

/* Bad transmittance and skies are refused. */
static void test_bad_input(void)
{
    static const float pos[9] = { 0, 0, 0, 1, 0, 0, 0, 0, 1 };
    static const uint32_t idx[3] = { 0, 2, 1 };
    ref_material m;
    ref_scene *s;
    ex_sky sky;
    memset(&m, 0, sizeof m);
    m.tf[1] = 1.5f;
    CHECK(ref_scene_create(pos, 3, idx, 1, NULL, &m, 1) == NULL);
    m.tf[1] = NAN;
    CHECK(ref_scene_create(pos, 3, idx, 1, NULL, &m, 1) == NULL);
    m.tf[1] = 0.5f;
    s = ref_scene_create(pos, 3, idx, 1, NULL, &m, 1);
    if (!CHECK(s != NULL)) return;
    memset(&sky, 0, sizeof sky);
    sky.radiance[2] = -1.0f;
    CHECK(ref_scene_set_sky(s, &sky) == -1);
    CHECK(ref_scene_set_sky(s, NULL) == 0);
    ref_scene_destroy(s);
}

int main(int argc, char **argv)
{
    TEST_INIT(argc, argv);
    RUN(test_sky_through_window);
    RUN(test_nested_glass_boxes);
    RUN(test_environment_map);
    RUN(test_area_light_through_pane);
    RUN(test_tracer_agrees_with_reference);
    RUN(test_bad_input);
    return test_finish();
}
