/* Tests of the examples' Assimp loader (examples/common/scene_assimp.h via
   scene_load.h), built and run only when Assimp is present (the Makefile
   builds tests/assimp_*.c with EX_HAVE_ASSIMP then). A glTF 2.0 file the
   test writes (nodes with transforms, metallic-roughness materials, glass
   through KHR_materials_transmission, an emitter with
   KHR_materials_emissive_strength, a blended veil) loads to the same
   triangles and material values as its OBJ twin; --up and --scale apply;
   bad files fail with a message; models of Debian's assimp-testmodels
   package load when it is installed (a CAD house in IFC with concave
   faces of up to 113 corners, FBX units, glTF binary), skipped otherwise. */
#include "examples/common/scene_load.h"
#include "tests/test.h"

#define TESTMODELS "/usr/share/assimp/models"

static int write_file(const char *path, const char *text)
{
    FILE *f = fopen(path, "w");
    if (!f) return 0;
    fputs(text, f);
    return fclose(f) == 0;
}

static void base64(const unsigned char *in, size_t n, char *out)
{
    static const char alphabet[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    size_t i;
    for (i = 0; i < n; i += 3) {
        uint32_t v = (uint32_t)in[i] << 16 | (i + 1 < n ? (uint32_t)in[i + 1] << 8 : 0) | (i + 2 < n ? in[i + 2] : 0);
        *out++ = alphabet[v >> 18 & 63];
        *out++ = alphabet[v >> 12 & 63];
        *out++ = i + 1 < n ? alphabet[v >> 6 & 63] : '=';
        *out++ = i + 2 < n ? alphabet[v & 63] : '=';
    }
    *out = 0;
}

/* ---- the glTF scene and its twin ------------------------------------------ */

#define MESHES 5
#define QUAD_VERTICES 4

/* Each mesh is one quad (two triangles) in its node's space. */
static const float quad[MESHES][QUAD_VERTICES][3] = {
    { { 0, 0, 0 }, { 0, 0, 4 }, { 4, 0, 4 }, { 4, 0, 0 } },          /* floor, facing up */
    { { 0, 0, 0 }, { 4, 0, 0 }, { 4, 3, 0 }, { 0, 3, 0 } },          /* wall, facing +z */
    { { -1, 1, 0 }, { 1, 1, 0 }, { 1, 2, 0 }, { -1, 2, 0 } },        /* glass pane */
    { { 1, 2.9f, 1 }, { 2, 2.9f, 1 }, { 2, 2.9f, 2 }, { 1, 2.9f, 2 } }, /* lamp, facing down */
    { { 0, 0.5f, 3 }, { 1, 0.5f, 3 }, { 1, 1.5f, 3 }, { 0, 1.5f, 3 } }, /* veil */
};
static const uint32_t quad_indices[6] = { 0, 1, 2, 0, 2, 3 };

/* Node transforms: translation, rotation (a quaternion x y z w), scale. */
static const double node_t[MESHES][3] = { { 0, 0, 0 }, { 0, 0, 0 }, { 2, 0, 1 }, { 0, 0, 0 }, { 0.5, 0, 0 } };
static const double node_r[MESHES][4] = { { 0, 0, 0, 1 }, { 0, 0, 0, 1 }, { 0, 0.70710678118654752, 0, 0.70710678118654752 },
                                          { 0, 0, 0, 1 }, { 0, 0, 0, 1 } };
static const double node_s[MESHES] = { 1, 1, 0.5, 1, 2 };

/* glTF's materials, one per mesh. */
static const char *gltf_materials =
    "{\"name\":\"plaster\",\"pbrMetallicRoughness\":{\"baseColorFactor\":[0.6,0.5,0.4,1],\"metallicFactor\":0,\"roughnessFactor\":0.5}},"
    "{\"name\":\"brass\",\"pbrMetallicRoughness\":{\"baseColorFactor\":[0.9,0.8,0.3,1],\"metallicFactor\":1,\"roughnessFactor\":0.2}},"
    "{\"name\":\"glass\",\"pbrMetallicRoughness\":{\"baseColorFactor\":[1,1,1,1],\"metallicFactor\":0,\"roughnessFactor\":0},"
    "\"extensions\":{\"KHR_materials_transmission\":{\"transmissionFactor\":0.9}}},"
    "{\"name\":\"lamp\",\"pbrMetallicRoughness\":{\"baseColorFactor\":[0,0,0,1],\"metallicFactor\":0},"
    "\"emissiveFactor\":[1,0.5,0.25],\"extensions\":{\"KHR_materials_emissive_strength\":{\"emissiveStrength\":8}}},"
    "{\"name\":\"veil\",\"alphaMode\":\"BLEND\",\"pbrMetallicRoughness\":{\"baseColorFactor\":[0.5,0.5,0.5,0.25],"
    "\"metallicFactor\":0,\"roughnessFactor\":0.5}}";

/* What those materials mean by the glTF 2.0 BRDF (F0 = 0.04), written as MTL
   by obj.h's rules: Kd (1 - F0) base for dielectrics; glass passes
   0.96 * 0.9 = 0.864 and keeps 0.096 of diffuse, written as Kd 0.096 /
   (1 - 0.864) under Tf; the veil is d 0.25. Ns = (2 / roughness^4 - 2) / 4. */
static const char *twin_mtl =
    "newmtl plaster\nKd 0.576 0.48 0.384\nKs 0.04 0.04 0.04\nNs 7.5\n"
    "newmtl brass\nKd 0 0 0\nKs 0.9 0.8 0.3\nNs 312\n"
    "newmtl glass\nKd 0.70588235 0.70588235 0.70588235\nKs 0.04 0.04 0.04\nNs 10000\nTf 0.864 0.864 0.864\nillum 4\n"
    "newmtl lamp\nKd 0 0 0\nKs 0.04 0.04 0.04\nNs 0\nKe 8 4 2\n"
    "newmtl veil\nKd 0.48 0.48 0.48\nKs 0.04 0.04 0.04\nNs 7.5\nd 0.25\n";
static const char *material_names[MESHES] = { "plaster", "brass", "glass", "lamp", "veil" };

/* p rotated by unit quaternion q, scaled by s, moved by t. */
static void node_point(int mesh, const float *p, double out[3])
{
    const double *q = node_r[mesh];
    double v[3] = { p[0] * node_s[mesh], p[1] * node_s[mesh], p[2] * node_s[mesh] }, u[3], t[3];
    int k;
    /* v + 2 q.xyz x (q.xyz x v + w v) */
    u[0] = q[1] * v[2] - q[2] * v[1] + q[3] * v[0];
    u[1] = q[2] * v[0] - q[0] * v[2] + q[3] * v[1];
    u[2] = q[0] * v[1] - q[1] * v[0] + q[3] * v[2];
    t[0] = q[1] * u[2] - q[2] * u[1];
    t[1] = q[2] * u[0] - q[0] * u[2];
    t[2] = q[0] * u[1] - q[1] * u[0];
    for (k = 0; k < 3; k++) out[k] = v[k] + 2 * t[k] + node_t[mesh][k];
}

/* Writes the glTF (positions and indices in one base64 buffer) and the OBJ
   twin. bad_vertex puts an infinite coordinate into the buffer. */
static int write_scene(const char *gltf_path, const char *obj_path, int bad_vertex)
{
    unsigned char bin[MESHES * (QUAD_VERTICES * 12 + 24)];
    char *b64 = (char *)malloc(4 * sizeof bin / 3 + 8), *json = (char *)malloc(64 * 1024), *p;
    size_t at = 0;
    int m, i, ok;
    if (!b64 || !json) { free(b64); free(json); return 0; }
    for (m = 0; m < MESHES; m++) {
        memcpy(bin + at, quad[m], sizeof quad[m]);
        if (bad_vertex && m == 1) { float inf = INFINITY; memcpy(bin + at + 4, &inf, 4); }
        at += sizeof quad[m];
        memcpy(bin + at, quad_indices, sizeof quad_indices);
        at += sizeof quad_indices;
    }
    base64(bin, at, b64);
    p = json;
    p += sprintf(p, "{\"asset\":{\"version\":\"2.0\"},\"extensionsUsed\":[\"KHR_materials_transmission\","
                    "\"KHR_materials_emissive_strength\"],\"buffers\":[{\"byteLength\":%u,\"uri\":"
                    "\"data:application/octet-stream;base64,%s\"}],\"bufferViews\":[", (unsigned)at, b64);
    for (m = 0; m < MESHES; m++) {
        size_t base = (size_t)m * (QUAD_VERTICES * 12 + 24);
        p += sprintf(p, "%s{\"buffer\":0,\"byteOffset\":%u,\"byteLength\":48},{\"buffer\":0,\"byteOffset\":%u,\"byteLength\":24}",
                     m ? "," : "", (unsigned)base, (unsigned)(base + 48));
    }
    p += sprintf(p, "],\"accessors\":[");
    for (m = 0; m < MESHES; m++) {
        float lo[3], hi[3];
        int k;
        for (k = 0; k < 3; k++) {
            lo[k] = hi[k] = quad[m][0][k];
            for (i = 1; i < QUAD_VERTICES; i++) {
                if (quad[m][i][k] < lo[k]) lo[k] = quad[m][i][k];
                if (quad[m][i][k] > hi[k]) hi[k] = quad[m][i][k];
            }
        }
        p += sprintf(p, "%s{\"bufferView\":%d,\"componentType\":5126,\"count\":4,\"type\":\"VEC3\",\"min\":[%g,%g,%g],"
                        "\"max\":[%g,%g,%g]},{\"bufferView\":%d,\"componentType\":5125,\"count\":6,\"type\":\"SCALAR\"}",
                     m ? "," : "", 2 * m, lo[0], lo[1], lo[2], hi[0], hi[1], hi[2], 2 * m + 1);
    }
    p += sprintf(p, "],\"materials\":[%s],\"meshes\":[", gltf_materials);
    for (m = 0; m < MESHES; m++)
        p += sprintf(p, "%s{\"name\":\"%s_mesh\",\"primitives\":[{\"attributes\":{\"POSITION\":%d},\"indices\":%d,\"material\":%d}]}",
                     m ? "," : "", material_names[m], 2 * m, 2 * m + 1, m);
    p += sprintf(p, "],\"nodes\":[");
    for (m = 0; m < MESHES; m++)
        p += sprintf(p, "%s{\"mesh\":%d,\"translation\":[%.17g,%.17g,%.17g],\"rotation\":[%.17g,%.17g,%.17g,%.17g],\"scale\":[%.17g,%.17g,%.17g]}",
                     m ? "," : "", m, node_t[m][0], node_t[m][1], node_t[m][2], node_r[m][0], node_r[m][1], node_r[m][2],
                     node_r[m][3], node_s[m], node_s[m], node_s[m]);
    p += sprintf(p, "],\"scenes\":[{\"nodes\":[0,1,2,3,4]}],\"scene\":0}\n");
    ok = write_file(gltf_path, json);
    if (obj_path) {   /* the twin: the same triangles, already placed */
        p = json;
        p += sprintf(p, "mtllib assimp_twin.mtl\n");
        for (m = 0; m < MESHES; m++) {
            p += sprintf(p, "g %s_mesh\nusemtl %s\n", material_names[m], material_names[m]);
            for (i = 0; i < QUAD_VERTICES; i++) {
                double w[3];
                node_point(m, quad[m][i], w);
                p += sprintf(p, "v %.9g %.9g %.9g\n", w[0], w[1], w[2]);
            }
            for (i = 0; i < 6; i += 3)
                p += sprintf(p, "f %d %d %d\n", (int)quad_indices[i] - 4, (int)quad_indices[i + 1] - 4, (int)quad_indices[i + 2] - 4);
        }
        ok = ok && write_file(obj_path, json) && write_file("build/tests/assimp_twin.mtl", twin_mtl);
    }
    free(b64);
    free(json);
    return ok;
}

static int same_point(const float *a, const float *b)
{
    /* the node transforms run in float in Assimp, in double for the twin,
       which is then printed with 9 digits: 1e-6 of the scene's size (4 m) */
    return fabsf(a[0] - b[0]) < 4e-6f && fabsf(a[1] - b[1]) < 4e-6f && fabsf(a[2] - b[2]) < 4e-6f;
}

/* The twin triangle with the same corners in the same turn, or -1. */
static int find_twin(const obj_scene *a, uint32_t t, const obj_scene *b)
{
    uint32_t u;
    int r, k;
    for (u = 0; u < b->tri_count; u++)
        for (r = 0; r < 3; r++) {
            int all = 1;
            for (k = 0; k < 3 && all; k++)
                all = same_point(a->positions + 3 * a->tri_indices[3 * t + k], b->positions + 3 * b->tri_indices[3 * u + (k + r) % 3]);
            if (all) return (int)u;
        }
    return -1;
}

static void test_gltf_equals_obj_twin(void)
{
    ex_scene_options o;
    obj_scene g, w;
    char err[512];
    uint32_t t;
    int k;
    if (!CHECK(write_scene("build/tests/assimp_scene.gltf", "build/tests/assimp_twin.obj", 0))) return;
    ex_scene_options_default(&o, "build/tests/assimp_scene.gltf");
    if (!CHECK_MSG(ex_scene_load(&o, &g, err, sizeof err) == 0, "%s", err)) return;
    ex_scene_options_default(&o, "build/tests/assimp_twin.obj");
    if (!CHECK_MSG(ex_scene_load(&o, &w, err, sizeof err) == 0, "%s", err)) { obj_free(&g); return; }
    CHECK_EQ_INT(g.tri_count, 2 * MESHES);
    CHECK_EQ_INT(w.tri_count, g.tri_count);
    CHECK_EQ_INT(g.vertex_count, 4 * MESHES - 2);   /* welded: the floor and the wall share two corners */
    for (t = 0; t < g.tri_count; t++) {
        int u = find_twin(&g, t, &w);
        const obj_material *a, *b;
        if (!CHECK_MSG(u >= 0, "glTF triangle %u has no twin", t)) continue;
        a = &g.materials[g.tri_material[t]];
        b = &w.materials[w.tri_material[u]];
        CHECK_MSG(strcmp(a->name, b->name) == 0, "triangle %u: material %s, twin %s", t, a->name, b->name);
        for (k = 0; k < 3; k++) {   /* decimal MTL values against float products: 1e-6 */
            CHECK_CLOSE(a->kd[k], b->kd[k], 1e-6, 1e-7);
            CHECK_CLOSE(a->ks[k], b->ks[k], 1e-6, 1e-7);
            CHECK_CLOSE(a->ke[k], b->ke[k], 1e-6, 1e-7);
            CHECK_CLOSE(a->tf[k], b->tf[k], 1e-6, 1e-7);
        }
        CHECK_CLOSE(a->ns, b->ns, 1e-5, 1e-6);
        CHECK_MSG(strstr(g.groups[g.face_group[g.tri_face[t]]], a->name) != NULL, "triangle %u: group %s", t,
                  g.groups[g.face_group[g.tri_face[t]]]);
    }
    obj_free(&g);
    obj_free(&w);
}

/* --up z turns the file (its +z becomes +y), --scale scales it; the glTF's
   own orientation is y-up. */
static void test_up_and_scale(void)
{
    ex_scene_options o;
    obj_scene a, b;
    char err[512];
    uint32_t v;
    if (!CHECK(write_scene("build/tests/assimp_scene.gltf", NULL, 0))) return;
    ex_scene_options_default(&o, "build/tests/assimp_scene.gltf");
    if (!CHECK_MSG(ex_scene_load(&o, &a, err, sizeof err) == 0, "%s", err)) return;
    o.up = 'z';
    o.scale = 0.01f;
    if (!CHECK_MSG(ex_scene_load(&o, &b, err, sizeof err) == 0, "%s", err)) { obj_free(&a); return; }
    CHECK_EQ_INT(b.vertex_count, a.vertex_count);
    for (v = 0; v < a.vertex_count; v++) {   /* (x, y, z) -> 0.01 (x, z, -y), float products */
        CHECK_CLOSE(b.positions[3 * v], 0.01 * a.positions[3 * v], 1e-6, 1e-9);
        CHECK_CLOSE(b.positions[3 * v + 1], 0.01 * a.positions[3 * v + 2], 1e-6, 1e-9);
        CHECK_CLOSE(b.positions[3 * v + 2], -0.01 * a.positions[3 * v + 1], 1e-6, 1e-9);
    }
    obj_free(&a);
    obj_free(&b);
}

/* A missing file, a file no reader takes, a glTF with an infinite vertex:
   each fails with a message naming the file, the scene left empty. */
static void test_bad_files(void)
{
    const char *paths[3] = { "build/tests/no_such_scene.glb", "build/tests/assimp_garbage.fbx", "build/tests/assimp_bad.gltf" };
    ex_scene_options o;
    obj_scene s;
    int i;
    CHECK(write_file(paths[1], "this is not a scene \x01\x02\x03\n"));
    CHECK(write_scene(paths[2], NULL, 1));
    for (i = 0; i < 3; i++) {
        char err[512] = "";
        ex_scene_options_default(&o, paths[i]);
        CHECK_MSG(ex_scene_load(&o, &s, err, sizeof err) != 0, "%s loaded", paths[i]);
        CHECK_MSG(strstr(err, paths[i]) != NULL, "message '%s' does not name %s", err, paths[i]);
        CHECK(s.tri_count == 0 && s.positions == NULL);
    }
}

/* The JSON reader behind KHR_materials_emissive_strength: the written
   glTF gives the lamp's 8 and 1 elsewhere; byte flips and truncations of it
   never crash it (ASan) and give finite, non-negative strengths. */
static void test_emissive_strength_reader(void)
{
    char *text, *copy;
    size_t len, i;
    float strength[MESHES + 1];
    uint64_t state = 99;
    static const char alphabet[] = "{}[]\",:0123456789.eE-+ \\tnul";
    int round, k;
    if (!CHECK(write_scene("build/tests/assimp_scene.gltf", NULL, 0))) return;
    if (!CHECK(obj__read_file("build/tests/assimp_scene.gltf", &text, &len) == 0)) return;
    for (k = 0; k <= MESHES; k++) strength[k] = 1.0f;
    ex__json_strengths(text, len, strength, MESHES);
    for (k = 0; k < MESHES; k++) CHECK_CLOSE(strength[k], k == 3 ? 8.0 : 1.0, 0, 0);
    copy = (char *)malloc(len + 1);
    for (round = 0; round < 3000 && copy; round++) {
        size_t n = len;
        memcpy(copy, text, len);
        for (i = 0; i < 1 + (size_t)round % 4; i++) {
            state = state * 6364136223846793005ull + 1442695040888963407ull;
            copy[(state >> 33) % len] = alphabet[(state >> 20) % (sizeof alphabet - 1)];
        }
        if (round % 5 == 0) n = (size_t)((state >> 40) % len);
        for (k = 0; k <= MESHES; k++) strength[k] = 1.0f;
        ex__json_strengths(copy, n, strength, MESHES);
        for (k = 0; k <= MESHES; k++) CHECK_MSG(strength[k] >= 0.0f && isfinite(strength[k]), "round %d: %g", round, strength[k]);
    }
    free(copy);
    free(text);
}

/* ---- models of Debian's assimp-testmodels ---------------------------------- */

static int have_model(const char *path)
{
    FILE *f = fopen(path, "rb");
    if (!f) {
        test_note("%s not found: skipped (apt-get install assimp-testmodels to run it)", path);
        return 0;
    }
    fclose(f);
    return 1;
}

/* The FZK house (Karlsruhe Institute of Technology, IFC 2x3 from ArchiCAD):
   walls with door and window openings cut into concave faces of up to 113
   corners, paint layers over walls. It loads y-up in metres (Assimp turns
   IFC), every face gives n - 2 triangles with none flipped, and the paint
   is found coincident. */
static void test_ifc_house(void)
{
    const char *path = TESTMODELS "/IFC/AC14-FZK-Haus.ifc";
    ex_scene_options o;
    obj_scene s;
    char err[512];
    float lo[3], hi[3];
    uint32_t f, t = 0, most = 0, concave = 0, flipped = 0;
    if (!have_model(path)) return;
    ex_scene_options_default(&o, path);
    if (!CHECK_MSG(ex_scene_load(&o, &s, err, sizeof err) == 0, "%s", err)) return;
    CHECK(obj_bounds(&s, lo, hi));
    CHECK_MSG(hi[1] - lo[1] > 5.0f && hi[1] - lo[1] < 10.0f, "height %g m", hi[1] - lo[1]);   /* two storeys and a roof */
    CHECK_MSG(hi[0] - lo[0] > 10.0f && hi[0] - lo[0] < 30.0f, "width %g m", hi[0] - lo[0]);
    for (f = 0; f < s.face_count; f++) {
        uint32_t n = s.face_start[f + 1] - s.face_start[f], k;
        double nrm[3], len;
        obj__newell(s.positions, s.face_vertices + s.face_start[f], n, nrm);
        len = sqrt(nrm[0] * nrm[0] + nrm[1] * nrm[1] + nrm[2] * nrm[2]);
        if (n > most) most = n;
        for (k = 0; k + 2 < n; k++, t++) {
            const float *a = s.positions + 3 * s.tri_indices[3 * t], *b = s.positions + 3 * s.tri_indices[3 * t + 1],
                        *c = s.positions + 3 * s.tri_indices[3 * t + 2];
            double e[3] = { b[0] - a[0], b[1] - a[1], b[2] - a[2] }, g[3] = { c[0] - a[0], c[1] - a[1], c[2] - a[2] };
            double x[3] = { e[1] * g[2] - e[2] * g[1], e[2] * g[0] - e[0] * g[2], e[0] * g[1] - e[1] * g[0] };
            double area = 0.5 * sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]);
            double along = 0.5 * (x[0] * nrm[0] + x[1] * nrm[1] + x[2] * nrm[2]) / (len > 0 ? len : 1);
            /* as in test_obj: flipped when turned against the face and above
               1e-6 of its area (smaller is the rounding of float corners) */
            flipped += along < 0 && area > 1e-6 * 0.5 * len;
        }
        concave += n > 4;
    }
    CHECK_EQ_INT(t, s.tri_count);
    CHECK_EQ_INT(flipped, 0);
    CHECK_EQ_INT(most, 113);
    CHECK(s.coincident_pairs > 0);
    test_note("FZK house: %u faces (%u of more than 4 corners, up to %u), %u triangles, none flipped; %.1f x %.1f x %.1f m; "
              "%u coincident pairs of faces over %.1f m^2", s.face_count, concave, most, s.tri_count, hi[0] - lo[0],
              hi[1] - lo[1], hi[2] - lo[2], s.coincident_pairs, s.coincident_area);
    obj_free(&s);
}

/* Two FBX files of the same cubes, one in centimetres (UnitScaleFactor 1),
   one in metres (100; it also mirrors a cube across y, which changes its y
   extent): the loader applies the unit, so both come out the same size in
   metres along x and z; --scale overrides it. */
static void test_fbx_units(void)
{
    const char *cm = TESTMODELS "/FBX/cubes_nonames.fbx", *m = TESTMODELS "/FBX/cubes_with_mirroring_and_pivot.fbx";
    ex_scene_options o;
    obj_scene a, b;
    char err[512];
    float alo[3], ahi[3], blo[3], bhi[3];
    int k;
    if (!have_model(cm) || !have_model(m)) return;
    ex_scene_options_default(&o, cm);
    if (!CHECK_MSG(ex_scene_load(&o, &a, err, sizeof err) == 0, "%s", err)) return;
    o.path = m;
    if (!CHECK_MSG(ex_scene_load(&o, &b, err, sizeof err) == 0, "%s", err)) { obj_free(&a); return; }
    obj_bounds(&a, alo, ahi);
    obj_bounds(&b, blo, bhi);
    for (k = 0; k < 3; k += 2) CHECK_CLOSE(ahi[k] - alo[k], bhi[k] - blo[k], 1e-4, 0);   /* the files store 6 digits */
    CHECK(ahi[0] - alo[0] < 1.0f);   /* 0.2 m, not 20 */
    obj_free(&a);
    o.path = cm;
    o.scale = 1.0f;   /* one unit is one metre, whatever the file says */
    if (CHECK_MSG(ex_scene_load(&o, &a, err, sizeof err) == 0, "%s", err)) {
        obj_bounds(&a, alo, ahi);
        CHECK_CLOSE(ahi[0] - alo[0], 100.0 * (bhi[0] - blo[0]), 1e-4, 0);
        obj_free(&a);
    }
    obj_free(&b);
}

/* A glTF binary of the sample models: a textured box, 12 triangles. */
static void test_glb_box(void)
{
    const char *path = TESTMODELS "/glTF2/BoxTextured-glTF-Binary/BoxTextured.glb";
    ex_scene_options o;
    obj_scene s;
    char err[512];
    if (!have_model(path)) return;
    ex_scene_options_default(&o, path);
    if (!CHECK_MSG(ex_scene_load(&o, &s, err, sizeof err) == 0, "%s", err)) return;
    CHECK_EQ_INT(s.tri_count, 12);
    CHECK_EQ_INT(s.vertex_count, 8);   /* 24 vertices with normals and uvs, 8 places */
    obj_free(&s);
}

int main(int argc, char **argv)
{
    TEST_INIT(argc, argv);
    RUN(test_gltf_equals_obj_twin);
    RUN(test_up_and_scale);
    RUN(test_bad_files);
    RUN(test_emissive_strength_reader);
    RUN(test_ifc_house);
    RUN(test_fbx_units);
    RUN(test_glb_box);
    return test_finish();
}
