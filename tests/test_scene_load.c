/* Unit tests of examples/common/scene_load.h as every build has it (the
   unit tests are built without Assimp; tests/assimp_load.c covers the rest):
   the scene options parse and refuse bad values, OBJ files load turned and
   scaled as asked, coincident faces are dropped on request, and a format
   other than OBJ fails with a message that says how to read it. */
#include "examples/common/scene_load.h"
#include "tests/test.h"

static int parse_args(int argc, const char **args, ex_scene_options *o, char *err, size_t n, int *rest)
{
    int i, r;
    *rest = 0;
    for (i = 1; i < argc; i++) {
        r = ex_scene_option(argc, (char **)args, &i, o, err, n);
        if (r < 0) return -1;
        *rest += r == 0;
    }
    return 0;
}

static void test_options(void)
{
    const char *good[] = { "prog", "--scene", "a.glb", "--frames", "--up", "z", "--scale", "0.01", "--drop-coincident" };
    const char *bad[][3] = {
        { "prog", "--up", "x" }, { "prog", "--scale", "0" }, { "prog", "--scale", "-1" }, { "prog", "--scale", "1e99" },
        { "prog", "--scale", "3m" }, { "prog", "--scale", "nan" },
    };
    ex_scene_options o;
    char err[256];
    int rest, i;
    ex_scene_options_default(&o, "default.obj");
    CHECK(parse_args(9, good, &o, err, sizeof err, &rest) == 0);
    CHECK(strcmp(o.path, "a.glb") == 0 && o.up == 'z' && o.drop_coincident == 1);
    CHECK_CLOSE(o.scale, 0.01, 1e-7, 0);
    CHECK_EQ_INT(rest, 1);   /* --frames is not a scene option */
    for (i = 0; i < (int)(sizeof bad / sizeof bad[0]); i++) {
        ex_scene_options_default(&o, "x.obj");
        err[0] = 0;
        CHECK_MSG(parse_args(3, bad[i], &o, err, sizeof err, &rest) < 0, "%s %s accepted", bad[i][1], bad[i][2]);
        CHECK(strstr(err, bad[i][1]) != NULL);
    }
    {
        const char *missing[] = { "prog", "--scene" };
        ex_scene_options_default(&o, "x.obj");
        CHECK(parse_args(2, missing, &o, err, sizeof err, &rest) < 0 && strstr(err, "needs a value"));
    }
}

/* The office loaded z-up and in centimetres: its y (height) becomes -z,
   its z becomes y, everything a hundredth. */
static void test_obj_turned_and_scaled(void)
{
    ex_scene_options o;
    obj_scene a, b;
    char err[256];
    uint32_t v;
    ex_scene_options_default(&o, "examples/data/office.obj");
    if (!CHECK_MSG(ex_scene_load(&o, &a, err, sizeof err) == 0, "%s", err)) return;
    o.up = 'z';
    o.scale = 0.01f;
    if (!CHECK_MSG(ex_scene_load(&o, &b, err, sizeof err) == 0, "%s", err)) { obj_free(&a); return; }
    for (v = 0; v < a.vertex_count; v++) {   /* one float product each */
        CHECK_CLOSE(b.positions[3 * v], 0.01 * a.positions[3 * v], 1e-6, 1e-9);
        CHECK_CLOSE(b.positions[3 * v + 1], 0.01 * a.positions[3 * v + 2], 1e-6, 1e-9);
        CHECK_CLOSE(b.positions[3 * v + 2], -0.01 * a.positions[3 * v + 1], 1e-6, 1e-9);
    }
    CHECK(memcmp(a.tri_indices, b.tri_indices, sizeof(uint32_t) * 3 * a.tri_count) == 0);   /* a turn keeps the winding */
    obj_free(&a);
    obj_free(&b);
}

static void test_drop_on_request(void)
{
    const char *text = "v 0 0 0\nv 1 0 0\nv 1 0 1\nv 0 0 1\nf 1 4 3 2\nf 1 4 3 2\n";
    char path[512];
    FILE *f = fopen(test_scratch_path(path, sizeof path, "twice.obj"), "w");
    ex_scene_options o;
    obj_scene s;
    char err[256];
    if (!CHECK(f != NULL)) return;
    fputs(text, f);
    fclose(f);
    ex_scene_options_default(&o, path);
    if (!CHECK(ex_scene_load(&o, &s, err, sizeof err) == 0)) return;
    CHECK_EQ_INT(s.face_count, 2);
    CHECK_EQ_INT(s.coincident_pairs, 1);
    obj_free(&s);
    o.drop_coincident = 1;
    if (!CHECK(ex_scene_load(&o, &s, err, sizeof err) == 0)) return;
    CHECK_EQ_INT(s.face_count, 1);
    CHECK_EQ_INT(s.coincident_pairs, 0);
    obj_free(&s);
}

static void test_other_formats(void)
{
    ex_scene_options o;
    obj_scene s;
    char err[512] = "";
    CHECK(ex_scene_is_obj("a/b/House.OBJ") && !ex_scene_is_obj("house.glb") && !ex_scene_is_obj("obj"));
    ex_scene_options_default(&o, "build/tests/no_such_house.glb");
    CHECK(ex_scene_load(&o, &s, err, sizeof err) != 0);
    CHECK(strstr(err, "no_such_house.glb") != NULL);
#ifndef EX_HAVE_ASSIMP
    CHECK_MSG(strstr(err, "libassimp-dev") != NULL, "'%s' does not say how to read it", err);
#endif
    CHECK(s.tri_count == 0 && s.positions == NULL);
    CHECK(ex_scene_load(NULL, &s, err, sizeof err) != 0);
}

int main(int argc, char **argv)
{
    TEST_INIT(argc, argv);
    RUN(test_options);
    RUN(test_obj_turned_and_scaled);
    RUN(test_drop_on_request);
    RUN(test_other_formats);
    return test_finish();
}
