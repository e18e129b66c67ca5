/* Unit tests of the examples' tracer with glass and a sky
   (examples/common/trace.h, scene_sky.h): known answers for light through
   a thin glass window from a constant sky, from an environment map and from
   an area light, shadow rays through several panes (with and without an
   instance in the way), the sky seen through
   glass, and bad skies refused. */
#include "examples/common/trace.h"
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
    char err[256], text[4096], name[256], path[512];
    snprintf(text, sizeof text, "mtllib %s\n%s", test_scratch_name(name, sizeof name, "glass.mtl"), obj);
    if (!CHECK(write_file(test_scratch_path(path, sizeof path, "glass.mtl"), mtl))) return 0;
    return CHECK_MSG(obj_parse(text, strlen(text), "glass.obj", TEST_SCRATCH_DIR, s, err, sizeof err) == 0, "%s", err);
}

/* Form factor from a point to a rectangle a x b parallel to its surface, at
   height c, the point below one corner (Howell's catalogue, C-11). */
static double form_factor_corner(double a, double b, double c)
{
    double A = a / c, B = b / c, sa = sqrt(1 + A * A), sb = sqrt(1 + B * B);
    return (A / sa * atan(B / sa) + B / sb * atan(A / sb)) / (2 * PI);
}

/* A closed black room [-1,1] x [0,2] x [-1,1] (walls facing in), a grey
   floor (kd 0.5), and in the ceiling a glass window [-0.5,0.5]^2 of
   transmittance (0.8, 0.6, 0.4) facing down (into the room) or up. */
static int glass_room(obj_scene *s, int window_faces_up)
{
    static const char *mtl =
        "newmtl black\nKd 0 0 0\n"
        "newmtl floor\nKd 0.5 0.5 0.5\n"
        "newmtl glass\nKd 0 0 0\nTf 0.8 0.6 0.4\nillum 4\n";
    char obj[3000];
    snprintf(obj, sizeof obj,
             "v -1 0 -1\nv 1 0 -1\nv 1 0 1\nv -1 0 1\n"          /* 1-4 floor corners */
             "v -1 2 -1\nv 1 2 -1\nv 1 2 1\nv -1 2 1\n"          /* 5-8 ceiling corners */
             "v -0.5 2 -0.5\nv 0.5 2 -0.5\nv 0.5 2 0.5\nv -0.5 2 0.5\n"  /* 9-12 window */
             "usemtl floor\nf 1 4 3 2\n"
             "usemtl black\n"
             "f 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\n"      /* walls, facing in */
             "f 5 6 10 9\nf 6 7 11 10\nf 7 8 12 11\nf 8 5 9 12\n" /* the ceiling round the window, facing down */
             "usemtl glass\n%s\n",
             window_faces_up ? "f 9 12 11 10" : "f 9 10 11 12");
    return load(obj, mtl, s);
}

/* Mean and standard error of n samples of the red channel of a shaded ray. */
static void shade_mean(const ex_tracer *t, const float org[3], const float dir[3], int bounces, int n, uint64_t seed,
                       double mean[3], double se[3])
{
    double sum[3] = { 0, 0, 0 }, sum2[3] = { 0, 0, 0 };
    ex_rng r = ex_rng_stream(seed, 0);
    int i, k;
    for (i = 0; i < n; i++) {
        float rgb[3];
        ex_tracer_shade(t, org, dir, bounces, &r, rgb, NULL);
        for (k = 0; k < 3; k++) { sum[k] += rgb[k]; sum2[k] += (double)rgb[k] * rgb[k]; }
    }
    for (k = 0; k < 3; k++) {
        mean[k] = sum[k] / n;
        se[k] = sqrt(fmax(0.0, sum2[k] / n - mean[k] * mean[k]) / (n - 1));
    }
}

/* The floor's centre under the window and a constant sky L: it reflects
   L_out = kd tf L F, F the form factor to the window. Every bounce count
   gives the same (the room is black). */
static void test_sky_through_window(void)
{
    const float L[3] = { 1.0f, 2.0f, 3.0f }, tf[3] = { 0.8f, 0.6f, 0.4f };
    const float org[3] = { 0, 1, 0 }, down[3] = { 0, -1, 0 };
    double F = 4 * form_factor_corner(0.5, 0.5, 2.0), mean[3], se[3];
    int up, bounces, k;
    ex_sky sky;
    memset(&sky, 0, sizeof sky);
    memcpy(sky.radiance, L, sizeof L);
    for (up = 0; up < 2; up++)
        for (bounces = 0; bounces <= 2; bounces += 2) {
            obj_scene s;
            ex_tracer *t;
            if (!glass_room(&s, up)) return;
            t = ex_tracer_create(&s);
            if (!CHECK(t && ex_tracer_set_sky(t, &sky) == 0)) { obj_free(&s); return; }
            shade_mean(t, org, down, bounces, 200000, 3 + (uint64_t)bounces, mean, se);
            for (k = 0; k < 3; k++)   /* a Bernoulli estimate: 4 standard errors */
                CHECK_CLOSE(mean[k], 0.5 * tf[k] * L[k] * F, 0, 4 * se[k]);
            test_note("window facing %s, %d bounces: floor radiance %.5f (expected %.5f, standard error %.5f)",
                      up ? "out" : "in", bounces, mean[0], 0.5 * tf[0] * L[0] * F, se[0]);
            ex_tracer_destroy(t);
            obj_free(&s);
        }
}

/* Looking up through the window from the floor: the sky times tf, exactly;
   beside it, the black ceiling. */
static void test_sky_seen_through_glass(void)
{
    const float org[3] = { 0, 0.5f, 0 }, up[3] = { 0.1f, 1, 0.05f }, beside[3] = { 1.5f, 1, 0 };
    ex_sky sky;
    int facing, k;
    memset(&sky, 0, sizeof sky);
    sky.radiance[0] = 1.0f; sky.radiance[1] = 2.0f; sky.radiance[2] = 4.0f;
    for (facing = 0; facing < 2; facing++) {
        obj_scene s;
        ex_tracer *t;
        ex_rng r = ex_rng_stream(1, 1);
        float rgb[3];
        if (!glass_room(&s, facing)) return;
        t = ex_tracer_create(&s);
        ex_tracer_set_sky(t, &sky);
        CHECK(ex_tracer_shade(t, org, up, 0, &r, rgb, NULL));
        for (k = 0; k < 3; k++) CHECK_CLOSE(rgb[k], s.materials[obj_find_material(&s, "glass")].tf[k] * sky.radiance[k], 1e-6, 0);
        ex_tracer_shade(t, org, beside, 0, &r, rgb, NULL);
        CHECK(rgb[0] == 0.0f && rgb[1] == 0.0f && rgb[2] == 0.0f);
        ex_tracer_destroy(t);
        obj_free(&s);
    }
}

/* A 2 x 2 lamp at height 1 over an endless grey floor (test_trace's known
   answer, L_out = kd Ke F with F = 0.554126) with glass panes between them:
   one of tf 0.5 at 0.8 (facing down), one of tf 0.8 at 0.6 (facing up). */
static void test_area_light_through_panes(void)
{
    static const char *mtl =
        "newmtl lamp\nKd 0 0 0\nKe 2 2 2\n"
        "newmtl floor\nKd 0.5 0.5 0.5\n"
        "newmtl half\nKd 0 0 0\nTf 0.5\nillum 4\n"
        "newmtl most\nKd 0 0 0\nTf 0.8\nillum 6\n";
    static const char *obj =
        "v -1 1 -1\nv 1 1 -1\nv 1 1 1\nv -1 1 1\n"
        "v -50 0 -50\nv 50 0 -50\nv 50 0 50\nv -50 0 50\n"
        "v -9 0.8 -9\nv 9 0.8 -9\nv 9 0.8 9\nv -9 0.8 9\n"
        "v -9 0.6 -9\nv 9 0.6 -9\nv 9 0.6 9\nv -9 0.6 9\n"
        "usemtl lamp\nf 1 2 3 4\nusemtl floor\nf 5 8 7 6\n"
        "usemtl half\nf 9 10 11 12\nusemtl most\nf 13 16 15 14\n";
    const float org[3] = { 0, 0.5f, 0 }, down[3] = { 0, -1, 0 }, up[3] = { 0, 1, 0 };
    obj_scene s, blocker;
    ex_tracer *t;
    double mean[3], se[3];
    float through[3];
    if (!load(obj, mtl, &s)) return;
    t = ex_tracer_create(&s);
    shade_mean(t, org, down, 0, 200000, 9, mean, se);
    /* the light sample's weight varies by a factor ~3 over the lamp: 0.1%
       standard error; 0.5% is 5 of them (as in test_trace) */
    CHECK_CLOSE(mean[0], 0.4 * 0.5 * 2.0 * 0.554126, 5e-3, 0);
    /* a shadow ray up from the floor crosses both panes */
    CHECK(ex_tracer_transmittance(t, org, up, 0.45f, through));
    CHECK_CLOSE(through[1], 0.4, 1e-6, 0);
    CHECK(ex_tracer_transmittance(t, org, up, 0.2f, through));   /* ends before the second pane */
    CHECK_CLOSE(through[1], 0.8, 1e-6, 0);
    CHECK(!ex_tracer_transmittance(t, org, up, 10.0f, through));   /* the lamp's back is opaque */
    CHECK(through[0] == 0.0f);
    /* an instance between the panes blocks the ray; the static scene's
       transmittance lets it through (what a moving object's shadow-free
       pass sees) */
    if (load("v -1 0.7 -1\nv 1 0.7 -1\nv 1 0.7 1\nv -1 0.7 1\nusemtl grey\nf 1 2 3 4\n", "newmtl grey\nKd 0.5 0.5 0.5\n",
             &blocker)) {
        static const float grey[3] = { 0.5f, 0.5f, 0.5f };
        CHECK(ex_tracer_add_instance(t, &blocker, grey) == 0);
        CHECK(!ex_tracer_transmittance(t, org, up, 0.45f, through));
        CHECK(through[1] == 0.0f);
        CHECK(ex_tracer_transmittance_static(t, org, up, 0.45f, through));
        CHECK_CLOSE(through[1], 0.4, 1e-6, 0);
        CHECK(!ex_tracer_transmittance_static(t, org, up, 10.0f, through));   /* the lamp still is opaque */
        obj_free(&blocker);
    }
    ex_tracer_destroy(t);
    obj_free(&s);
}

/* A camera ray meets a pane that reflects (kd 0.3) and passes (tf 0.6) in
   front of a wide lamp: with a bounce left the path goes through with
   probability tf / (tf + kd) and is weighted back, so the mean is tf Ke
   (the bounce side finds nothing: no sky, the lamp behind the pane); with
   none left it always goes through: exactly tf Ke. */
static void test_pass_or_bounce_is_unbiased(void)
{
    static const char *mtl = "newmtl lamp\nKd 0 0 0\nKe 5 5 5\nnewmtl pane\nKd 0.75 0.75 0.75\nTf 0.6\nillum 4\n";
    static const char *obj =
        "v -50 -50 -1\nv 50 -50 -1\nv 50 50 -1\nv -50 50 -1\nusemtl lamp\nf 1 2 3 4\n"
        "v -50 -50 0\nv 50 -50 0\nv 50 50 0\nv -50 50 0\nusemtl pane\nf 5 6 7 8\n";
    const float org[3] = { 0.1f, 0.2f, 1 }, dir[3] = { 0, 0, -1 };
    obj_scene s;
    ex_tracer *t;
    double mean[3], se[3];
    if (!load(obj, mtl, &s)) return;
    CHECK_CLOSE(s.materials[obj_find_material(&s, "pane")].kd[0], 0.3, 1e-6, 0);
    t = ex_tracer_create(&s);
    shade_mean(t, org, dir, 0, 1000, 5, mean, se);
    CHECK_CLOSE(mean[0], 0.6 * 5, 1e-6, 0);
    CHECK_CLOSE(se[0], 0, 0, 1e-6);
    shade_mean(t, org, dir, 1, 100000, 6, mean, se);
    CHECK_CLOSE(mean[0], 0.6 * 5, 0, 4 * se[0]);   /* Bernoulli, p = 0.6 / 0.9 */
    test_note("pass or bounce: %.4f (expected 3, standard error %.4f)", mean[0], se[0]);
    ex_tracer_destroy(t);
    obj_free(&s);
}

/* More panes than EX_TRACE_MAX_PASSES block the light. */
static void test_too_many_panes(void)
{
    char obj[8192], *p = obj;
    const float org[3] = { 0, -0.5f, 0 }, up[3] = { 0, 1, 0 };
    obj_scene s;
    ex_tracer *t;
    float through[3];
    int i;
    p += sprintf(p, "usemtl clear\n");
    for (i = 0; i < EX_TRACE_MAX_PASSES + 1; i++)   /* panes at y = 0, 1, ..., facing down */
        p += sprintf(p, "v -1 %d -1\nv 1 %d -1\nv 1 %d 1\nv -1 %d 1\nf -4 -3 -2 -1\n", i, i, i, i);
    if (!load(obj, "newmtl clear\nTf 1\nillum 4\n", &s)) return;
    t = ex_tracer_create(&s);
    CHECK(ex_tracer_transmittance(t, org, up, (float)EX_TRACE_MAX_PASSES, through));   /* the first 16 */
    CHECK_CLOSE(through[0], 1.0, 0, 0);
    CHECK(!ex_tracer_transmittance(t, org, up, 100.0f, through));   /* 17 */
    ex_tracer_destroy(t);
    obj_free(&s);
}

/* An environment map of 8 x 6 texels with radiance changing by row and
   column: a grey floor facing up reflects kd/pi E, E in closed form
   (ex_sky_irradiance_up); a camera ray sees the texel it points at. */
static void test_environment_map(void)
{
    static const char *obj = "v -50 0 -50\nv 50 0 -50\nv 50 0 50\nv -50 0 50\nusemtl floor\nf 1 4 3 2\n";
    float map[8 * 6 * 3];
    const float org[3] = { 0, 1, 0 }, down[3] = { 0, -1, 0 };
    obj_scene s;
    ex_tracer *t;
    ex_sky sky;
    double e[3], mean[3], se[3];
    int i, k;
    for (i = 0; i < 8 * 6; i++) {
        map[3 * i] = (float)(1 + i / 8);           /* by row */
        map[3 * i + 1] = (float)(1 + i % 8);       /* by column */
        map[3 * i + 2] = i / 8 < 3 ? 2.0f : 50.0f; /* bright below the horizon: must not count */
    }
    memset(&sky, 0, sizeof sky);
    sky.map = map;
    sky.width = 8;
    sky.height = 6;
    ex_sky_irradiance_up(&sky, e);
    CHECK_CLOSE(e[2], 2.0 * PI, 1e-12, 0);   /* the upper half at 2: pi * 2 */
    if (!load(obj, "newmtl floor\nKd 0.5 0.5 0.5\n", &s)) return;
    t = ex_tracer_create(&s);
    if (!CHECK(ex_tracer_set_sky(t, &sky) == 0)) return;
    shade_mean(t, org, down, 0, 200000, 21, mean, se);
    for (k = 0; k < 3; k++) CHECK_CLOSE(mean[k], 0.5 / PI * e[k], 0, 4 * se[k] + 1e-9);
    test_note("environment map: floor radiance (%.4f %.4f %.4f), expected (%.4f %.4f %.4f)", mean[0], mean[1], mean[2],
              0.5 / PI * e[0], 0.5 / PI * e[1], 0.5 / PI * e[2]);
    for (i = 0; i < 100; i++) {   /* directions to texel centres, upwards (the floor hides the rest) */
        int row = i % 3, col = (i / 3) % 8;
        double theta = PI * (row + 0.5) / 6, phi = 2 * PI * (col + 0.5) / 8 - PI;
        float dir[3] = { (float)(sin(theta) * cos(phi)), (float)cos(theta), (float)(sin(theta) * sin(phi)) }, rgb[3];
        ex_rng r = ex_rng_stream(2, (uint64_t)i);
        ex_tracer_shade(t, org, dir, 0, &r, rgb, NULL);
        CHECK(rgb[0] == map[3 * (row * 8 + col)] && rgb[1] == map[3 * (row * 8 + col) + 1]);
    }
    ex_tracer_destroy(t);
    obj_free(&s);
}

/* Negative, NaN or infinite radiance and bad map sizes are refused; the
   tracer keeps its sky. */
static void test_bad_skies(void)
{
    static const char *obj = "v 0 0 0\nv 1 0 0\nv 0 0 1\nf 1 3 2\n";
    float map[12] = { 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1 };
    obj_scene s;
    ex_tracer *t;
    ex_sky sky;
    if (!load(obj, "newmtl x\n", &s)) return;
    t = ex_tracer_create(&s);
    memset(&sky, 0, sizeof sky);
    sky.radiance[1] = -1.0f;
    CHECK(ex_tracer_set_sky(t, &sky) == -1);
    sky.radiance[1] = NAN;
    CHECK(ex_tracer_set_sky(t, &sky) == -1);
    sky.radiance[1] = INFINITY;
    CHECK(ex_tracer_set_sky(t, &sky) == -1);
    sky.radiance[1] = 1.0f;
    sky.map = map;
    sky.width = 0; sky.height = 4;
    CHECK(ex_tracer_set_sky(t, &sky) == -1);
    sky.width = 2; sky.height = 2;
    map[5] = NAN;
    CHECK(ex_tracer_set_sky(t, &sky) == -1);
    map[5] = 1.0f;
    CHECK(ex_tracer_set_sky(t, &sky) == 0);
    CHECK(ex_tracer_set_sky(t, NULL) == 0);
    CHECK(ex_tracer_set_sky(NULL, &sky) == -1);
    ex_tracer_destroy(t);
    obj_free(&s);
}

int main(int argc, char **argv)
{
    TEST_INIT(argc, argv);
    RUN(test_sky_through_window);
    RUN(test_sky_seen_through_glass);
    RUN(test_area_light_through_panes);
    RUN(test_pass_or_bounce_is_unbiased);
    RUN(test_too_many_panes);
    RUN(test_environment_map);
    RUN(test_bad_skies);
    return test_finish();
}
