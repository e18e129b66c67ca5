/* Unit tests of examples/common/obj.h: the project's scenes load with their
   known counts; malformed input gives an error naming the line, never a crash
   (random mutations of a real file run under ASan+UBSan). */
#include "examples/common/obj.h"
#include "tests/test.h"

static int parse(const char *text, obj_scene *s, char *err, size_t n)
{
    return obj_parse(text, strlen(text), "test.obj", NULL, s, err, n);
}

static void test_cornell_box_counts(void)
{
    obj_scene s;
    char err[256];
    if (!CHECK_MSG(obj_load("examples/data/cornell_box.obj", &s, err, sizeof err) == 0, "%s", err)) return;
    /* floor, 4 ceiling pieces, back, right, 2 left triangles, light, 5 + 5 block faces */
    CHECK_EQ_INT(s.face_count, 20);
    CHECK_EQ_INT(s.tri_count, 18 * 2 + 2);
    CHECK_EQ_INT(s.material_count, 5); /* default + white, red, green, light */
    CHECK(obj_find_group(&s, "light") >= 0);
    CHECK_CLOSE(s.materials[obj_find_material(&s, "light")].ke[0], 17.0, 0, 0);
    CHECK_CLOSE(s.materials[obj_find_material(&s, "red")].kd[0], 0.63, 1e-6, 0);
    obj_free(&s);
}

static void test_office_counts(void)
{
    obj_scene s;
    char err[256];
    uint32_t f, quads = 0;
    float lo[3], hi[3];
    if (!CHECK_MSG(obj_load("examples/data/office.obj", &s, err, sizeof err) == 0, "%s", err)) return;
    for (f = 0; f < s.face_count; f++) quads += s.face_start[f + 1] - s.face_start[f] == 4;
    CHECK_EQ_INT(s.face_count, 55);
    CHECK_EQ_INT(quads, 55);
    CHECK_EQ_INT(s.tri_count, 110);
    CHECK(obj_find_group(&s, "desk") >= 0 && obj_find_group(&s, "divider") >= 0);
    CHECK(obj_find_group(&s, "lamp_shade_top") >= 0);
    CHECK(obj_bounds(&s, lo, hi));
    CHECK_CLOSE(hi[0] - lo[0], 5.0, 1e-6, 0);
    CHECK_CLOSE(hi[1] - lo[1], 2.8, 1e-6, 0);
    CHECK_CLOSE(hi[2] - lo[2], 4.0, 1e-6, 0);
    obj_free(&s);
}

static void test_bunny_counts(void)
{
    obj_scene s;
    char err[256];
    if (!CHECK_MSG(obj_load("examples/data/bunny.obj", &s, err, sizeof err) == 0, "%s", err)) return;
    CHECK_EQ_INT(s.vertex_count, 1839);
    CHECK_EQ_INT(s.tri_count, 3674);
    CHECK_EQ_INT(s.face_count, 3674);
    obj_free(&s);
}

static void test_polygon_fan_and_relative_indices(void)
{
    obj_scene s;
    char err[256];
    const char *text = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv -1 0.5 0\nf -5 -4 -3 -2 -1\nf 1/1/1 2//2 3\n";
    if (!CHECK_MSG(parse(text, &s, err, sizeof err) == 0, "%s", err)) return;
    CHECK_EQ_INT(s.face_count, 2);
    CHECK_EQ_INT(s.tri_count, 3 + 1);
    CHECK_EQ_INT(s.tri_indices[0], 0);
    CHECK_EQ_INT(s.tri_indices[7], 3); /* third fan triangle: 0 3 4 */
    CHECK_EQ_INT(s.tri_face[3], 1);
    CHECK_EQ_INT(s.face_material[0], 0);
    obj_free(&s);
}

/* Each malformed input must fail, name its line, and leave the scene empty. */
static void test_malformed_inputs(void)
{
    static const struct { const char *text; const char *line; } bad[] = {
        { "v 0 0\n", ":1:" },                          /* too few coordinates */
        { "v 0 0 x\n", ":1:" },                        /* not a number */
        { "v 0 0 nan\n", ":1:" },                      /* NaN */
        { "v 0 0 1e999\n", ":1:" },                    /* overflow */
        { "v 0 0 0\nv 1 0 0\nf 1 2\n", ":3:" },        /* two-vertex face */
        { "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n", ":4:" },   /* index past the end */
        { "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n", ":4:" },   /* index 0 */
        { "v 0 0 0\nv 1 0 0\nv 0 1 0\nf -4 1 2\n", ":4:" },  /* relative index before the start */
        { "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3x\n", ":4:" },  /* junk after an index */
        { "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 99999999999999999999\n", ":4:" },
        { "usemtl nothing\n", ":1:" },                 /* unknown material */
        { "mtllib does_not_exist.mtl\n", "does_not_exist" },
        { "frobnicate 1 2 3\n", ":1:" },               /* unknown statement */
        { "\n\no aaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaa\n", ":3:" },
    };
    size_t i;
    for (i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        obj_scene s;
        char err[256] = "";
        int r = parse(bad[i].text, &s, err, sizeof err);
        CHECK_MSG(r != 0, "input %u was accepted", (unsigned)i);
        CHECK_MSG(strstr(err, bad[i].line) != NULL, "input %u: message '%s' lacks '%s'", (unsigned)i, err, bad[i].line);
        CHECK(s.tri_count == 0 && s.positions == NULL);
    }
}

static void test_missing_file_and_null(void)
{
    obj_scene s;
    char err[256] = "";
    CHECK(obj_load("examples/data/no_such_scene.obj", &s, err, sizeof err) != 0);
    CHECK(strstr(err, "no_such_scene") != NULL);
    CHECK(obj_load(NULL, &s, err, sizeof err) != 0);
    CHECK(obj_parse(NULL, 0, NULL, NULL, &s, err, sizeof err) != 0);
    CHECK(obj_parse("v 1 2 3\n", 8, NULL, NULL, NULL, NULL, 0) != 0);
    obj_free(NULL);
}

static void test_empty_input_is_an_empty_scene(void)
{
    obj_scene s;
    char err[256];
    CHECK(obj_parse("", 0, NULL, NULL, &s, err, sizeof err) == 0);
    CHECK_EQ_INT(s.face_count, 0);
    CHECK_EQ_INT(s.tri_count, 0);
    obj_free(&s);
}

/* Random byte flips, insertions and truncations of the office file: each
   either loads or fails with a message, under the sanitizers. */
static void test_mutations_never_crash(void)
{
    FILE *f = fopen("examples/data/office.obj", "rb");
    char *text, *copy;
    long len;
    int round, loaded = 0, rejected = 0;
    uint64_t state = 12345;
    static const char alphabet[] = "0123456789 -./\n\tfvo#xe+";
    if (!CHECK(f != NULL)) return;
    fseek(f, 0, SEEK_END);
    len = ftell(f);
    fseek(f, 0, SEEK_SET);
    text = (char *)malloc((size_t)len + 1);
    copy = (char *)malloc((size_t)len + 16);
    CHECK(fread(text, 1, (size_t)len, f) == (size_t)len);
    fclose(f);
    for (round = 0; round < 400; round++) {
        obj_scene s;
        char err[256];
        long n = len, k;
        memcpy(copy, text, (size_t)len);
        for (k = 0; k < 1 + round % 5; k++) {
            state = state * 6364136223846793005ull + 1442695040888963407ull;
            copy[(state >> 33) % (uint64_t)len] = alphabet[(state >> 20) % (sizeof alphabet - 1)];
        }
        if (round % 7 == 0) n = (long)((state >> 40) % (uint64_t)len); /* truncation */
        if (obj_parse(copy, (size_t)n, "mutated.obj", "examples/data/", &s, err, sizeof err) == 0) {
            loaded++;
            obj_free(&s);
        } else {
            rejected++;
        }
    }
    test_note("mutated office files: %d loaded, %d rejected with a message", loaded, rejected);
    CHECK(rejected > 0);
    free(text);
    free(copy);
}

/* A unit cube's corner normal points along the diagonal; a bunny's normals
   are unit length. */
static void test_vertex_normals(void)
{
    const char *cube =
        "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n"
        "f 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 4 8 7 3\nf 1 5 8 4\nf 2 3 7 6\n";
    obj_scene s;
    char err[256];
    float n[3 * 8];
    if (!CHECK(obj_parse(cube, strlen(cube), NULL, NULL, &s, err, sizeof err) == 0)) return;
    obj_vertex_normals(&s, n);
    /* vertex 7 = (1,1,1): its three faces are outward +x, +y, +z; the fan
       split gives two of them unequal weight, so only the octant is exact */
    CHECK(n[3 * 6] > 0.3f && n[3 * 6 + 1] > 0.3f && n[3 * 6 + 2] > 0.3f);
    CHECK(n[0] < -0.3f && n[1] < -0.3f && n[2] < -0.3f);
    CHECK_CLOSE(n[3 * 6] * n[3 * 6] + n[3 * 6 + 1] * n[3 * 6 + 1] + n[3 * 6 + 2] * n[3 * 6 + 2], 1.0, 1e-6, 0);
    obj_free(&s);
}

int main(int argc, char **argv)
{
    TEST_INIT(argc, argv);
    RUN(test_cornell_box_counts);
    RUN(test_office_counts);
    RUN(test_bunny_counts);
    RUN(test_polygon_fan_and_relative_indices);
    RUN(test_malformed_inputs);
    RUN(test_missing_file_and_null);
    RUN(test_empty_input_is_an_empty_scene);
    RUN(test_mutations_never_crash);
    RUN(test_vertex_normals);
    return test_finish();
}
