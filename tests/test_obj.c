/* Unit tests of examples/common/obj.h: the project's scenes load with their
   known counts; malformed input gives an error naming the line, never a crash
   (random mutations of a real file run under ASan+UBSan); concave, collinear,
   self-touching and 100-corner faces triangulate to their exact area without
   a flipped triangle, and a house with door frames keeps its doorways open
   for the examples' tracer. */
#include "examples/common/trace.h"
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

/* ---- triangulation ------------------------------------------------------ */

/* A polygon in the plane z = 0 (2D corners), placed in 3D by a rotation and
   an offset so that no projection axis is special, written as one face. */
typedef struct poly_text { char *text; size_t len, cap; } poly_text;

static void poly_append(poly_text *t, const char *fmt, ...)
{
    va_list ap;
    int n;
    for (;;) {
        va_start(ap, fmt);
        n = vsnprintf(t->text + t->len, t->cap - t->len, fmt, ap);
        va_end(ap);
        if (n >= 0 && t->len + (size_t)n < t->cap) { t->len += (size_t)n; return; }
        t->cap = t->cap ? 2 * t->cap : 4096;
        t->text = (char *)realloc(t->text, t->cap);
    }
}

/* Rotation about the unit axis (1, 2, 3)/sqrt(14) by 0.7 radians
   (Rodrigues), and then an offset: no projection axis is special. */
static void tilt_point(const double p[3], double q[3])
{
    double k[3] = { 1 / sqrt(14.0), 2 / sqrt(14.0), 3 / sqrt(14.0) }, c = cos(0.7), s = sin(0.7);
    double kp = k[0] * p[0] + k[1] * p[1] + k[2] * p[2];
    double x[3] = { k[1] * p[2] - k[2] * p[1], k[2] * p[0] - k[0] * p[2], k[0] * p[1] - k[1] * p[0] };
    int i;
    for (i = 0; i < 3; i++) q[i] = p[i] * c + x[i] * s + k[i] * kp * (1 - c) + 0.25 * i;
}

static void write_polygon(poly_text *t, const double *xy, int n, int rotate)
{
    int i;
    for (i = 0; i < n; i++) {
        double p[3] = { xy[2 * i], xy[2 * i + 1], 0.0 }, q[3];
        if (rotate) tilt_point(p, q);
        else memcpy(q, p, sizeof q);
        poly_append(t, "v %.9g %.9g %.9g\n", q[0], q[1], q[2]);
    }
    poly_append(t, "f");
    for (i = 0; i < n; i++) poly_append(t, " %d", i - n);
    poly_append(t, "\n");
}

/* Shoelace area of a 2D polygon (positive counter-clockwise). */
static double shoelace(const double *xy, int n)
{
    double a = 0.0;
    int i;
    for (i = 0; i < n; i++) {
        int j = (i + 1) % n;
        a += xy[2 * i] * xy[2 * j + 1] - xy[2 * j] * xy[2 * i + 1];
    }
    return 0.5 * a;
}

typedef struct tri_stats { double area, signed_area, face_area, face_size; int flipped, degenerate; } tri_stats;

/* The face's triangles: their total area and their vector area along the
   face's Newell normal. Triangles that cover a face's boundary add up to its
   vector area whatever they are (the diagonals cancel), so signed_area must
   equal face_area to double rounding; a flipped triangle makes area larger
   than signed_area. A triangle counts as flipped when it turns against the
   face and is larger than 1e-6 of the face: below that its orientation is
   the rounding of float corners (a sliver along collinear corners). */
static tri_stats face_triangles(const obj_scene *s, uint32_t face)
{
    tri_stats st;
    double n[3] = { 0, 0, 0 }, len;
    uint32_t i;
    memset(&st, 0, sizeof st);
    obj__newell(s->positions, s->face_vertices + s->face_start[face], s->face_start[face + 1] - s->face_start[face], n);
    len = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    st.face_area = 0.5 * len;
    for (i = 0; i < s->tri_count; i++) {
        const float *a, *b, *c;
        double e[3], f[3], x[3], area, along;
        int k;
        if (s->tri_face[i] != face) continue;
        a = s->positions + 3 * s->tri_indices[3 * i];
        b = s->positions + 3 * s->tri_indices[3 * i + 1];
        c = s->positions + 3 * s->tri_indices[3 * i + 2];
        for (k = 0; k < 3; k++) { e[k] = (double)b[k] - a[k]; f[k] = (double)c[k] - a[k]; }
        x[0] = e[1] * f[2] - e[2] * f[1];
        x[1] = e[2] * f[0] - e[0] * f[2];
        x[2] = e[0] * f[1] - e[1] * f[0];
        area = 0.5 * sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]);
        along = 0.5 * (x[0] * n[0] + x[1] * n[1] + x[2] * n[2]) / len;
        st.area += area;
        st.signed_area += along;
        st.flipped += along < 0.0 && area > 1e-6 * st.face_area;
        st.degenerate += area <= 1e-9 * st.face_area;
    }
    return st;
}

/* Loads one polygon (in the plane, or tilted) and checks its triangulation:
   n - 2 triangles, its area exactly the face's, none flipped. */
static int check_polygon(const char *name, const double *xy, int n, int rotate, int allow_degenerate)
{
    poly_text t;
    obj_scene s;
    char err[256];
    tri_stats st;
    double area = fabs(shoelace(xy, n));
    int ok;
    memset(&t, 0, sizeof t);
    write_polygon(&t, xy, n, rotate);
    ok = CHECK_MSG(obj_parse(t.text, t.len, name, NULL, &s, err, sizeof err) == 0, "%s", err);
    free(t.text);
    if (!ok) return 0;
    st = face_triangles(&s, 0);
    ok = CHECK_EQ_INT(s.tri_count, n - 2);
    /* exact: sums of at most 100 double terms */
    ok &= CHECK_CLOSE(st.signed_area, st.face_area, 1e-12, 0);
    /* flat polygons: every triangle lies in the face's plane, so the total
       equals the vector area to double rounding; tilted ones are stored as
       floats, slightly off their plane (6e-8 relative), and each triangle's
       normal leans by its corners' rounding over its width: 1e-7 of the
       area for these shapes, except the 1e-4 wide sliver (1e-3 rad) */
    ok &= CHECK_CLOSE(st.area, st.signed_area, rotate ? (strcmp(name, "sliver") == 0 ? 1e-5 : 1e-7) : 1e-12, 0);
    /* the loaded face is the intended one up to the 9 printed digits and the
       floats' 6e-8, relative to the polygon's size: a 1e-6 change of area,
       or of the sliver's 1e-4 width, 1e-2 */
    ok &= CHECK_CLOSE(st.face_area, area, strcmp(name, "sliver") == 0 ? 1e-2 : 1e-6, 0);
    ok &= CHECK_MSG(st.flipped == 0, "%s: %d flipped triangles", name, st.flipped);
    if (!allow_degenerate) ok &= CHECK_MSG(st.degenerate == 0, "%s: %d zero-area triangles", name, st.degenerate);
    obj_free(&s);
    return ok;
}

/* Shapes a fan gets wrong: an L, a U (a door frame), a comb, an arrowhead,
   each flat and tilted, counter-clockwise and clockwise. */
static void test_concave_faces(void)
{
    static const double l_shape[] = { 0,0, 2,0, 2,1, 1,1, 1,3, 0,3 };
    static const double door_frame[] = { 0,0, 4,0, 4,2.1, 5,2.1, 5,0, 10,0, 10,3, 0,3 };
    static const double comb[] = { 0,0, 7,0, 7,3, 6,3, 6,1, 5,1, 5,3, 4,3, 4,1, 3,1, 3,3, 2,3, 2,1, 1,1, 1,3, 0,3 };
    static const double arrow[] = { 0,0, 2,1, 4,0, 2,4 };
    static const struct { const char *name; const double *xy; int n; } shapes[] = {
        { "L", l_shape, 6 }, { "door frame", door_frame, 8 }, { "comb", comb, 16 }, { "arrowhead", arrow, 4 },
    };
    size_t i;
    int rotate, reverse, k;
    for (i = 0; i < sizeof shapes / sizeof shapes[0]; i++)
        for (rotate = 0; rotate < 2; rotate++)
            for (reverse = 0; reverse < 2; reverse++) {
                double xy[64];
                for (k = 0; k < shapes[i].n; k++) {
                    int j = reverse ? shapes[i].n - 1 - k : k;
                    xy[2 * k] = shapes[i].xy[2 * j];
                    xy[2 * k + 1] = shapes[i].xy[2 * j + 1];
                }
                CHECK_MSG(check_polygon(shapes[i].name, xy, shapes[i].n, rotate, 0), "%s (tilted %d, reversed %d)",
                          shapes[i].name, rotate, reverse);
            }
}

/* 100 corners: a star of 50 spikes (50 reflex corners), a convex circle
   (fanned), and a spiral band whose ears are all at its two ends. */
static void test_hundred_corner_faces(void)
{
    double star[200], circle[200], spiral[200];
    int i, rotate;
    for (i = 0; i < 100; i++) {
        double a = 2.0 * 3.14159265358979 * i / 100.0, r = i % 2 ? 0.4 : 1.0;
        star[2 * i] = r * cos(a);
        star[2 * i + 1] = r * sin(a);
        circle[2 * i] = 3.0 * cos(a);
        circle[2 * i + 1] = 3.0 * sin(a);
    }
    for (i = 0; i < 50; i++) { /* out along the outer arm, back along the inner one */
        double a = 3.0 * 3.14159265358979 * i / 49.0, ro = 1.0 + 0.35 * a, ri = 0.8 + 0.35 * a;
        spiral[2 * i] = ro * cos(a);
        spiral[2 * i + 1] = ro * sin(a);
        spiral[2 * (99 - i)] = ri * cos(a);
        spiral[2 * (99 - i) + 1] = ri * sin(a);
    }
    for (rotate = 0; rotate < 2; rotate++) {
        CHECK(check_polygon("star", star, 100, rotate, 0));
        CHECK(check_polygon("circle", circle, 100, rotate, 0));
        CHECK(check_polygon("spiral", spiral, 100, rotate, 0));
    }
}

/* Collinear corners on every side of a rectangle (CAD exports split edges
   where a neighbour's corner meets them): every corner must be a corner of
   some triangle, or the neighbours see a T-junction crack; a window cut as a
   keyhole (the outline runs in along a slit, round the hole and back out,
   touching itself); corners repeated; a sliver 1e-4 wide. */
static void test_collinear_and_degenerate_faces(void)
{
    static const double collinear[] = { 0,0, 1,0, 2,0, 3,0, 3,1, 3,2, 2,2, 1,2, 0,2, 0,1 };
    static const double concave_collinear[] = { 0,0, 1,0, 2,0, 2,1, 1,1, 1,2, 1,3, 0,3, 0,2, 0,1 };
    static const double keyhole[] = { 0,0, 4,0, 4,3, 2,3, 2,2, 3,2, 3,1, 1,1, 1,2, 2,2, 2,3, 0,3 };
    static const double repeated[] = { 0,0, 2,0, 2,0, 2,2, 1,1, 0,2, 0,2 };
    static const double sliver[] = { 0,0, 5,1e-4, 10,0, 10,2e-4, 5,1.5e-4, 0,2e-4 };
    int rotate, i, seen[10];
    obj_scene s;
    char err[256];
    for (rotate = 0; rotate < 2; rotate++) {
        CHECK(check_polygon("collinear", collinear, 10, rotate, 0));
        CHECK(check_polygon("concave collinear", concave_collinear, 10, rotate, 0));
        CHECK(check_polygon("keyhole", keyhole, 12, rotate, 1));
        CHECK(check_polygon("repeated corners", repeated, 7, rotate, 1));
        CHECK(check_polygon("sliver", sliver, 6, rotate, 0));
    }
    /* the keyhole's area is the frame's: 12 - 2 */
    CHECK_CLOSE(fabs(shoelace(keyhole, 12)), 10.0, 1e-12, 0);
    {
        poly_text t;
        memset(&t, 0, sizeof t);
        write_polygon(&t, collinear, 10, 0);
        if (CHECK(obj_parse(t.text, t.len, "collinear", NULL, &s, err, sizeof err) == 0)) {
            memset(seen, 0, sizeof seen);
            for (i = 0; i < 3 * (int)s.tri_count; i++) seen[s.tri_indices[i]] = 1;
            for (i = 0; i < 10; i++) CHECK_MSG(seen[i], "corner %d is in no triangle", i);
            obj_free(&s);
        }
        free(t.text);
    }
}

/* An outline that crosses itself (a bow tie) has no triangulation without a
   flipped triangle; it must still give n - 2 triangles and no crash, as must
   a face whose corners are all on one line or one point. */
static void test_impossible_faces(void)
{
    const char *text =
        "v 0 0 0\nv 2 2 0\nv 2 0 0\nv 0 2 0\nv 1 1 1\nv 2 2 2\nv 3 3 3\nv 4 4 4\n"
        "f 1 2 3 4\nf 5 6 7 8\nf 5 5 5 5 5\nf 1 2 3 4 1 2 3 4\n";
    obj_scene s;
    char err[256];
    if (!CHECK_MSG(obj_parse(text, strlen(text), NULL, NULL, &s, err, sizeof err) == 0, "%s", err)) return;
    CHECK_EQ_INT(s.tri_count, 2 + 2 + 3 + 6);
    obj_free(&s);
}

/* A house written as a CAD exporter writes it: each wall one face, the door
   openings cut into its outline (a U-shaped notch), a window as a keyhole.
   Rays through every doorway and the window reach the far side; rays beside
   them hit the wall. A fan triangulation closes all of them. */
static void test_house_doorways_open(void)
{
    /* three rooms along x (0-4, 4-8, 8-12), depth 5 along z, height 3; the
       front wall (z = 0) has a door at x 1-2, the two inner walls (x = 4 and
       x = 8) doors at z 2-3, the back wall (z = 5) a window x 5-7, y 1-2;
       doors are 2.1 high */
    static const double front[] = { 0,0, 1,0, 1,2.1, 2,2.1, 2,0, 12,0, 12,3, 0,3 };            /* (x, y) */
    static const double inner[] = { 0,0, 2,0, 2,2.1, 3,2.1, 3,0, 5,0, 5,3, 0,3 };               /* (z, y) */
    static const double back[] = { 0,0, 12,0, 12,3, 6,3, 6,2, 7,2, 7,1, 5,1, 5,2, 6,2, 6,3, 0,3 }; /* (x, y) */
    poly_text t;
    obj_scene s;
    char err[256];
    ex_tracer *tr;
    int i, k, j, wall = 0, open = 0, rays = 0;
    memset(&t, 0, sizeof t);
    for (i = 0; i < 8; i++) poly_append(&t, "v %g %g 0\n", front[2 * i], front[2 * i + 1]);
    poly_append(&t, "f -8 -7 -6 -5 -4 -3 -2 -1\n");
    for (j = 0; j < 2; j++) {
        for (i = 0; i < 8; i++) poly_append(&t, "v %d %g %g\n", 4 + 4 * j, inner[2 * i + 1], inner[2 * i]);
        poly_append(&t, "f -1 -2 -3 -4 -5 -6 -7 -8\n");   /* facing +x */
    }
    for (i = 0; i < 12; i++) poly_append(&t, "v %g %g 5\n", back[2 * i], back[2 * i + 1]);
    poly_append(&t, "f -1 -2 -3 -4 -5 -6 -7 -8 -9 -10 -11 -12\n");   /* facing -z */
    poly_append(&t, "v 0 0 0\nv 12 0 0\nv 12 0 5\nv 0 0 5\nf -4 -1 -2 -3\n");  /* floor, facing up */
    poly_append(&t, "v -20 -1 20\nv 30 -1 20\nv 30 10 20\nv -20 10 20\nf -4 -3 -2 -1\n");  /* far side behind the back wall */
    if (!CHECK_MSG(obj_parse(t.text, t.len, "house.obj", NULL, &s, err, sizeof err) == 0, "%s", err)) { free(t.text); return; }
    free(t.text);
    tr = ex_tracer_create(&s);
    if (!CHECK(tr != NULL)) { obj_free(&s); return; }
    for (k = 0; k < 5; k++)
        for (j = 0; j < 5; j++) {
            float u = 0.1f + 0.2f * (float)k, v = 0.1f + 0.2f * (float)j;
            struct { float org[3], dir[3]; float through; } ray[4] = {
                /* the front door, along +z into the first room, to its back wall */
                { { 1 + u, 2.1f * v, -1 }, { 0, 0, 1 }, 6.0f },
                /* both inner doors, along +x from the first room to past the third */
                { { 0.5f, 2.1f * v, 2 + u }, { 1, 0, 0 }, 100.0f },
                /* the window, along +z from inside to the far plane */
                { { 5 + 2 * u, 1 + v, 4 }, { 0, 0, 1 }, 16.0f },
                /* beside the front door: the wall */
                { { 3 + u, 2.1f * v, -1 }, { 0, 0, 1 }, 1.0f },
            };
            for (i = 0; i < 4; i++) {
                ex_trace_hit h;
                int hit = ex_tracer_intersect(tr, ray[i].org, ray[i].dir, FLT_MAX, &h);
                rays++;
                if (ray[i].through == 1.0f) {
                    wall += hit && fabsf(h.t - 1.0f) < 1e-5f;
                    continue;
                }
                /* through: the first hit is the far side (the house's back
                   wall, nothing for the inner doors, the far plane) */
                if (ray[i].through == 100.0f) open += !hit;
                else open += hit && fabsf(h.t - ray[i].through) < 1e-4f * ray[i].through;
            }
        }
    CHECK_EQ_INT(open, 3 * 25);
    CHECK_EQ_INT(wall, 25);
    test_note("house: %u faces, %u triangles; %d of %d rays through the openings reached the far side", s.face_count,
              s.tri_count, open, 3 * 25);
    (void)rays;
    ex_tracer_destroy(tr);
    obj_free(&s);
}

/* ---- materials that pass light ------------------------------------------ */

static int write_file(const char *path, const char *text)
{
    FILE *f = fopen(path, "w");
    if (!f) return 0;
    fputs(text, f);
    return fclose(f) == 0;
}

/* MTL transmission (obj.h's "Transmission"): glass by Tf under a
   transparent illumination model, coverage by d or Tr, both together, and
   Tf on an opaque model (as 3ds Max writes it) is no glass. */
static void test_mtl_transmission(void)
{
    const char *mtl =
        "newmtl glass\nKd 0.5 0.5 0.5\nKs 0.08 0.08 0.08\nTf 0.8 0.9 0.7\nillum 4\n"
        "newmtl veil\nKd 0.4 0.6 0.8\nKs 0.2 0.2 0.2\nd 0.25\n"
        "newmtl tr\nKd 1 1 1\nTr 0.6\n"
        "newmtl halo\nd -halo 0.5\n"
        "newmtl both\nKd 0.5 0.5 0.5\nd 0.5\nTf 0.8\nillum 7\n"
        "newmtl max_opaque\nKd 0.3 0.3 0.3\nTf 1 1 1\nd 1\nillum 2\n";
    char obj[512], name[256], path[512];
    obj_scene s;
    char err[256];
    const obj_material *m;
    snprintf(obj, sizeof obj, "mtllib %s\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl glass\nf 1 2 3\n",
             test_scratch_name(name, sizeof name, "glass.mtl"));
    if (!CHECK(write_file(test_scratch_path(path, sizeof path, "glass.mtl"), mtl))) return;
    if (!CHECK_MSG(obj_parse(obj, strlen(obj), "glass.obj", TEST_SCRATCH_DIR, &s, err, sizeof err) == 0, "%s", err)) return;
    /* float products of short decimals: 1e-6 */
    m = &s.materials[obj_find_material(&s, "glass")];
    CHECK_CLOSE(m->tf[0], 0.8, 1e-6, 0); CHECK_CLOSE(m->tf[1], 0.9, 1e-6, 0); CHECK_CLOSE(m->tf[2], 0.7, 1e-6, 0);
    CHECK_CLOSE(m->kd[0], 0.5 * 0.2, 1e-6, 0); CHECK_CLOSE(m->kd[2], 0.5 * 0.3, 1e-6, 0);
    CHECK_CLOSE(m->ks[1], 0.08, 1e-6, 0);
    m = &s.materials[obj_find_material(&s, "veil")];
    CHECK_CLOSE(m->tf[0], 0.75, 1e-6, 0); CHECK_CLOSE(m->tf[2], 0.75, 1e-6, 0);
    CHECK_CLOSE(m->kd[1], 0.6 * 0.25, 1e-6, 0); CHECK_CLOSE(m->ks[0], 0.2 * 0.25, 1e-6, 0);
    m = &s.materials[obj_find_material(&s, "tr")];
    CHECK_CLOSE(m->tf[1], 0.6, 1e-6, 0); CHECK_CLOSE(m->kd[1], 0.4, 1e-6, 0);
    m = &s.materials[obj_find_material(&s, "halo")];
    CHECK_CLOSE(m->tf[0], 0.5, 1e-6, 0);
    m = &s.materials[obj_find_material(&s, "both")];
    CHECK_CLOSE(m->tf[0], 0.5 + 0.5 * 0.8, 1e-6, 0); CHECK_CLOSE(m->kd[0], 0.5 * 0.5 * 0.2, 1e-6, 0);
    m = &s.materials[obj_find_material(&s, "max_opaque")];
    CHECK(m->tf[0] == 0.0f && m->tf[1] == 0.0f && m->tf[2] == 0.0f);
    CHECK_CLOSE(m->kd[0], 0.3, 1e-6, 0);
    m = &s.materials[0];   /* the default material is opaque */
    CHECK(m->tf[0] == 0.0f);
    obj_free(&s);
}

/* Bad transmission statements fail with the MTL file's line. */
static void test_mtl_transmission_errors(void)
{
    static const struct { const char *mtl, *msg; } bad[] = {
        { "newmtl a\nd 1.5\n", ":2:" },
        { "newmtl a\nTr -0.1\n", ":2:" },
        { "newmtl a\nTf spectral glass.rfl\n", "spectral" },
        { "newmtl a\nTf xyz 0.5 0.5 0.5\n", "xyz" },
        { "newmtl a\nTf 0.5 0.5\n", ":2:" },
        { "newmtl a\nillum 2.5\n", ":2:" },
        { "newmtl a\nd nan\n", ":2:" },
        { "d 0.5\n", ":1:" },
    };
    char obj[512], name[256], path[512];
    size_t i;
    snprintf(obj, sizeof obj, "mtllib %s\n", test_scratch_name(name, sizeof name, "bad.mtl"));
    test_scratch_path(path, sizeof path, "bad.mtl");
    for (i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        obj_scene s;
        char err[256] = "";
        if (!CHECK(write_file(path, bad[i].mtl))) return;
        CHECK_MSG(obj_parse(obj, strlen(obj), "bad.obj", TEST_SCRATCH_DIR, &s, err, sizeof err) != 0, "input %u accepted", (unsigned)i);
        CHECK_MSG(strstr(err, bad[i].msg) != NULL, "input %u: '%s' lacks '%s'", (unsigned)i, err, bad[i].msg);
        CHECK(s.tri_count == 0 && s.materials == NULL);
    }
}

/* ---- coincident faces --------------------------------------------------- */

/* A 10 x 10 floor (faces up) with: paint over all of it written after it
   (the same corners from another one: a different diagonal), a wall
   painted on half its area, a wall back to back with its twin, floor
   tiles that only share edges, a face 1e-7 of the scene above the floor
   (coincident) and one 1e-3 above it (not). */
static const char *coincident_text =
    "v 0 0 0\nv 10 0 0\nv 10 0 10\nv 0 0 10\n"                    /* 1-4 floor */
    "f 1 4 3 2\n"                                               /* face 0: floor */
    "v 0 0 0\nv 0 3 0\nv 10 3 0\nv 10 0 0\nv 5 0 0\nv 5 3 0\n"  /* 5-10 wall z = 0, facing +z */
    "f 5 8 7 6\n"                                               /* face 1: wall */
    "f 5 9 10 6\n"                                              /* face 2: paint on half the wall */
    "f 5 6 7 8\n"                                               /* face 3: the wall's back */
    "v 20 0 0\nv 21 0 0\nv 22 0 0\nv 20 0 1\nv 21 0 1\nv 22 0 1\n" /* 11-16 tiles */
    "f 11 14 15 12\nf 12 15 16 13\n"                            /* faces 4, 5: tiles */
    "f 2 1 4 3\n"                                               /* face 6: paint over the floor */
    "v 2 0.0000015 2\nv 2 0.0000015 3\nv 3 0.0000015 3\nv 3 0.0000015 2\n"
    "f 17 18 19 20\n"                                           /* face 7: 1e-7 of the scene above */
    "v 2 0.02 2\nv 2 0.02 3\nv 3 0.02 3\nv 3 0.02 2\n"
    "f 21 22 23 24\n";                                          /* face 8: 1e-3 above */

static void test_coincident_faces_reported(void)
{
    obj_scene s;
    char err[256];
    if (!CHECK_MSG(obj_parse(coincident_text, strlen(coincident_text), NULL, NULL, &s, err, sizeof err) == 0, "%s", err))
        return;
    /* floor + paint, floor + raised square, paint + raised square, wall + half paint */
    CHECK_EQ_INT(s.coincident_pairs, 4);
    CHECK_EQ_INT(s.coincident_faces, 5);   /* 0, 6, 7, 1, 2 */
    /* overlaps: 100 + 1 + 1 + 15 m^2 (clipping is exact to rounding) */
    CHECK_CLOSE(s.coincident_area, 117.0, 1e-9, 0);
    obj_free(&s);
}

static void test_drop_coincident(void)
{
    obj_scene s;
    char err[256];
    int d;
    uint32_t t;
    if (!CHECK(obj_parse(coincident_text, strlen(coincident_text), NULL, NULL, &s, err, sizeof err) == 0)) return;
    /* only the floor goes: the later paint covers it; the raised square
       (face 7) comes after everything it overlaps, the half-painted wall is
       covered in part */
    d = obj_drop_coincident(&s);
    CHECK_EQ_INT(d, 1);
    CHECK_EQ_INT(s.face_count, 8);
    CHECK_EQ_INT(s.tri_count, 16);
    /* the first face is now the wall, and every triangle names its face */
    CHECK_EQ_INT(s.face_vertices[s.face_start[0]], 4);
    for (t = 0; t < s.tri_count; t++) {
        uint32_t f = s.tri_face[t], k, in = 0;
        for (k = 0; k < 3; k++) {
            uint32_t c;
            for (c = s.face_start[f]; c < s.face_start[f + 1]; c++) in += s.face_vertices[c] == s.tri_indices[3 * t + k];
        }
        CHECK_MSG(in == 3, "triangle %u is not made of face %u's corners", t, f);
    }
    /* left: paint + raised square, wall + half paint (kept: the paint covers half) */
    CHECK_EQ_INT(s.coincident_pairs, 2);
    CHECK_EQ_INT(obj_drop_coincident(&s), 0);
    obj_free(&s);
}

/* A face covered by the union of two later ones (each covering part) goes;
   a face covered by an earlier one stays. */
static void test_drop_coincident_union(void)
{
    const char *text =
        "v 0 0 0\nv 4 0 0\nv 4 0 4\nv 0 0 4\nv 2 0 0\nv 2 0 4\n"
        "f 1 4 3 2\n"        /* 0: the whole square */
        "f 1 4 6 5\n"        /* 1: its left half */
        "f 5 6 3 2\n"        /* 2: its right half */
        "v 10 0 0\nv 14 0 0\nv 14 0 4\nv 10 0 4\n"
        "f 7 10 9 8\n"       /* 3: a square */
        "f 7 10 9 8\n";      /* 4: its exact copy */
    obj_scene s;
    char err[256];
    if (!CHECK(obj_parse(text, strlen(text), NULL, NULL, &s, err, sizeof err) == 0)) return;
    CHECK_EQ_INT(s.coincident_pairs, 3);
    CHECK_EQ_INT(obj_drop_coincident(&s), 2);   /* faces 0 and 3 */
    CHECK_EQ_INT(s.face_count, 3);
    CHECK_EQ_INT(s.coincident_pairs, 0);
    CHECK_CLOSE(s.coincident_area, 0.0, 0, 0);
    obj_free(&s);
}

/* ---- writing and moving ------------------------------------------------- */

/* A scene with a concave face, a convex quad, a concave quad, a triangle,
   glass, an emitter and names that are no OBJ tokens, written and read
   back: the same positions, the same triangles in the same order, the same
   material values; concave faces come back as their triangles. */
static void test_write_round_trip(void)
{
    const char *mtl = "newmtl glass\nKd 0.5 0.4 0.3\nKs 0.05 0.05 0.05\nNs 200\nTf 0.8 0.7 0.6\nillum 4\n"
                      "newmtl lamp\nKd 0.1 0.1 0.1\nKe 5 4 3\nnewmtl default\nKd 0.2 0.3 0.4\n";
    const char *body =
        "v 0 0 0\nv 4 0 0\nv 4 2.1 0\nv 5 2.1 0\nv 5 0 0\nv 10 0 0\nv 10 3 0\nv 0 3 0\n"
        "v 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\nv 0.5 0.25 1\n"
        "g front\nusemtl glass\nf 1 2 3 4 5 6 7 8\n"
        "g quads\nusemtl lamp\nf 9 10 11 12\nusemtl default\nf 9 10 11 13\nf 9 10 11\n";
    obj_scene a, b;
    char err[256], obj[1024], name[256], path[512];
    uint32_t i;
    int k;
    snprintf(obj, sizeof obj, "mtllib %s\n%s", test_scratch_name(name, sizeof name, "rt.mtl"), body);
    if (!CHECK(write_file(test_scratch_path(path, sizeof path, "rt.mtl"), mtl))) return;
    if (!CHECK_MSG(obj_parse(obj, strlen(obj), "rt.obj", TEST_SCRATCH_DIR, &a, err, sizeof err) == 0, "%s", err)) return;
    strcpy(a.groups[1], "front wall");   /* not a token: written as front_wall */
    test_scratch_path(path, sizeof path, "written.obj");
    if (!CHECK_MSG(obj_write(&a, path, err, sizeof err) == 0, "%s", err)) return;
    if (!CHECK_MSG(obj_load(path, &b, err, sizeof err) == 0, "%s", err)) return;
    CHECK_EQ_INT(b.vertex_count, a.vertex_count);
    CHECK(memcmp(a.positions, b.positions, sizeof(float) * 3 * a.vertex_count) == 0);
    CHECK_EQ_INT(b.tri_count, a.tri_count);
    CHECK(memcmp(a.tri_indices, b.tri_indices, sizeof(uint32_t) * 3 * a.tri_count) == 0);
    CHECK_EQ_INT(b.face_count, 6 + 1 + 2 + 1);   /* the door frame and the concave quad as triangles */
    CHECK(obj_find_group(&b, "front_wall") >= 0 && obj_find_group(&b, "quads") >= 0);
    for (i = 0; i < a.tri_count; i++) {
        const obj_material *ma = &a.materials[a.tri_material[i]], *mb = &b.materials[b.tri_material[i]];
        for (k = 0; k < 3; k++) {   /* Kd goes through a division by 1 - tf and back: float rounding */
            CHECK_CLOSE(mb->kd[k], ma->kd[k], 1e-6, 0);
            CHECK_CLOSE(mb->ks[k], ma->ks[k], 0, 0);
            CHECK_CLOSE(mb->ke[k], ma->ke[k], 0, 0);
            CHECK_CLOSE(mb->tf[k], ma->tf[k], 0, 0);
        }
        CHECK_CLOSE(mb->ns, ma->ns, 0, 0);
    }
    CHECK(obj_write(&a, "build/tests/no_extension", err, sizeof err) != 0);
    CHECK(obj_write(&a, "build/no_such_dir/x.obj", err, sizeof err) != 0 && strstr(err, "no_such_dir") != NULL);
    obj_free(&a);
    obj_free(&b);
}

/* z-up to y-up with a scale: positions turned, fronts kept; a mirror
   reverses the faces and triangles so the fronts stay fronts. */
static void test_transform(void)
{
    const char *text = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n";   /* faces +z */
    const float z_up_cm[9] = { 0.01f, 0, 0, 0, 0, 0.01f, 0, -0.01f, 0 }, mirror[9] = { -1, 0, 0, 0, 1, 0, 0, 0, 1 };
    obj_scene s;
    char err[256];
    float n[12];
    if (!CHECK(obj_parse(text, strlen(text), NULL, NULL, &s, err, sizeof err) == 0)) return;
    CHECK(obj_transform(&s, z_up_cm) == 0);
    CHECK_CLOSE(s.positions[3 * 2 + 0], 0.01, 1e-7, 0);   /* (1, 1, 0) -> (0.01, 0, -0.01) */
    CHECK_CLOSE(s.positions[3 * 2 + 1], 0.0, 0, 0);
    CHECK_CLOSE(s.positions[3 * 2 + 2], -0.01, 1e-7, 0);
    obj_vertex_normals(&s, n);
    CHECK_CLOSE(n[1], 1.0, 1e-6, 0);   /* +z became +y */
    CHECK(obj_transform(&s, mirror) == 0);
    obj_vertex_normals(&s, n);
    CHECK_CLOSE(n[1], 1.0, 1e-6, 0);   /* still +y: the winding was reversed with the mirror */
    CHECK_EQ_INT(s.face_vertices[0], 3);
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
    RUN(test_concave_faces);
    RUN(test_hundred_corner_faces);
    RUN(test_collinear_and_degenerate_faces);
    RUN(test_impossible_faces);
    RUN(test_house_doorways_open);
    RUN(test_mtl_transmission);
    RUN(test_mtl_transmission_errors);
    RUN(test_coincident_faces_reported);
    RUN(test_drop_coincident);
    RUN(test_drop_coincident_union);
    RUN(test_write_round_trip);
    RUN(test_transform);
    return test_finish();
}
