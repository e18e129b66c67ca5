/* scene_assimp.h - any scene Assimp reads (glTF 2.0, FBX, Collada, IFC, PLY,
   3DS, STL, ...), loaded into the examples' obj_scene (obj.h). Compiled only
   when Assimp is present: the Makefile defines EX_HAVE_ASSIMP and links
   -lassimp when it finds libassimp-dev; scene_load.h includes this file then.
   Programs call ex_scene_load (scene_load.h), not this file.

       obj_scene s;
       char err[256];
       if (ex_assimp_load("house.glb", 0, 0.0f, &s, err, sizeof err) != 0) ...

   What is kept: the polygons of every mesh, placed by the node hierarchy
   (aiProcess_PreTransformVertices), positions welded where exactly equal,
   triangulated by obj.h (ear clipping, n - 2 triangles per polygon), one
   group per mesh, one material per Assimp material. Points and lines are
   skipped. Normals, texture coordinates and textures are not read.

   Materials (obj_material fields):
   - glTF's metallic-roughness model (when the material has a metallic
     factor), following the glTF 2.0 BRDF with its dielectric Fresnel term at
     normal incidence F0 = 0.04 (index of refraction 1.5):
       kd = (1 - metallic) (1 - transmission) (1 - F0) base
       tf = (1 - metallic) transmission (1 - F0) base  (KHR_materials_transmission)
       ks = (1 - metallic) F0 + metallic base          (the glossy lobe)
       ns = (2 / alpha^2 - 2) / 4, alpha = roughness^2 (the Blinn-Phong
            exponent of a GGX width alpha, Walter et al. 2007, made a Phong
            exponent about the mirror direction: the half vector turns half
            as far), clamped to [0, EX_ASSIMP_MAX_EXPONENT];
   - other models: kd = diffuse colour, ks = specular colour times shininess
     strength, ns = shininess (a Phong exponent);
   - ke = emissive colour times emissive strength, read as radiance in
     W/(m^2 sr): the strength is Assimp's emissive intensity when it has one,
     else, for glTF files, KHR_materials_emissive_strength read here from the
     file's JSON (Assimp 5.2 does not pass it on);
   - opacity (glTF: alpha of BLEND materials; MASK materials are 0 or 1 by
     their cutoff; OPAQUE ignores alpha) is coverage as MTL's d: tf gains
     1 - opacity, kd and ks keep opacity of themselves.

   Axes and units: the examples are y-up, in metres. Assimp already converts
   Collada (up_axis, unit) and IFC to that, and glTF is y-up metres by
   definition. FBX declares its axes and unit (UpAxis, FrontAxis, CoordAxis
   with their signs, UnitScaleFactor in centimetres) without Assimp applying
   them: they are applied here. Other formats are taken as y-up metres.
   up ('y' or 'z', 0 = the file's) and scale (metres per file unit, 0 = the
   file's) override what the file says; an override of Collada's up axis
   makes Assimp ignore the file's. */
#ifndef EXAMPLES_COMMON_SCENE_ASSIMP_H
#define EXAMPLES_COMMON_SCENE_ASSIMP_H

#include <assimp/cimport.h>
#include <assimp/material.h>
#include <assimp/metadata.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <assimp/version.h>

#include "obj.h"

#include "base.h"

#define EX_ASSIMP_MAX_EXPONENT 10000.0f   /* a mirror for the headers' Phong lobe */
#define EX_ASSIMP_F0 0.04f                /* dielectric reflectance at normal incidence (IOR 1.5) */

/* ---- materials ---------------------------------------------------------- */

static int ex__ai_float(const C_STRUCT aiMaterial *m, const char *key, unsigned type, unsigned index, float *out)
{
    ai_real v;
    unsigned n = 1;
    if (aiGetMaterialFloatArray(m, key, type, index, &v, &n) != aiReturn_SUCCESS || n != 1 || !isfinite(v)) return 0;
    *out = (float)v;
    return 1;
}

static int ex__ai_color(const C_STRUCT aiMaterial *m, const char *key, unsigned type, unsigned index, float rgb[3])
{
    C_STRUCT aiColor4D c;
    if (aiGetMaterialColor(m, key, type, index, &c) != aiReturn_SUCCESS) return 0;
    if (!isfinite(c.r) || !isfinite(c.g) || !isfinite(c.b)) return 0;
    rgb[0] = c.r; rgb[1] = c.g; rgb[2] = c.b;
    return 1;
}

static float ex__ai_clamp(float x, float lo, float hi) { return x < lo ? lo : x > hi ? hi : x; }

/* An Assimp name, cut to OBJ_NAME_MAX - 1 bytes. */
static void ex__ai_name(char *dst, const C_STRUCT aiString *src)
{
    size_t n = strlen(src->data);
    if (n >= OBJ_NAME_MAX) n = OBJ_NAME_MAX - 1;
    memcpy(dst, src->data, n);
    dst[n] = 0;
}

/* glTF's opacity rule: OPAQUE ignores alpha, MASK cuts it at the cutoff. */
static float ex__ai_opacity(const C_STRUCT aiMaterial *m)
{
    float opacity = 1.0f, cutoff = 0.5f;
    C_STRUCT aiString mode;
    ex__ai_float(m, AI_MATKEY_OPACITY, &opacity);
    if (aiGetMaterialString(m, "$mat.gltf.alphaMode", 0, 0, &mode) == aiReturn_SUCCESS) {
        if (strcmp(mode.data, "OPAQUE") == 0) return 1.0f;
        if (strcmp(mode.data, "MASK") == 0) {
            ex__ai_float(m, "$mat.gltf.alphaCutoff", 0, 0, &cutoff);
            return opacity >= cutoff ? 1.0f : 0.0f;
        }
    }
    return ex__ai_clamp(opacity, 0.0f, 1.0f);
}

/* One Assimp material as the headers' (see the doc block). gltf_strength:
   the material's KHR_materials_emissive_strength, 1 when none. */
static void ex__ai_material(const C_STRUCT aiMaterial *m, float gltf_strength, obj_material *out)
{
    float base[3] = { 0.8f, 0.8f, 0.8f }, metallic, roughness = 1.0f, transmission = 0.0f, strength = 1.0f, opacity;
    C_STRUCT aiString name;
    int k;
    memset(out, 0, sizeof *out);
    if (aiGetMaterialString(m, AI_MATKEY_NAME, &name) == aiReturn_SUCCESS)
        ex__ai_name(out->name, &name);
    if (!ex__ai_color(m, AI_MATKEY_BASE_COLOR, base)) ex__ai_color(m, AI_MATKEY_COLOR_DIFFUSE, base);
    for (k = 0; k < 3; k++) base[k] = ex__ai_clamp(base[k], 0.0f, 1.0f);
    if (ex__ai_float(m, AI_MATKEY_METALLIC_FACTOR, &metallic)) {   /* glTF's metallic-roughness */
        float alpha, dielectric;
        metallic = ex__ai_clamp(metallic, 0.0f, 1.0f);
        ex__ai_float(m, AI_MATKEY_ROUGHNESS_FACTOR, &roughness);
        ex__ai_float(m, AI_MATKEY_TRANSMISSION_FACTOR, &transmission);
        roughness = ex__ai_clamp(roughness, 0.0f, 1.0f);
        transmission = ex__ai_clamp(transmission, 0.0f, 1.0f);
        dielectric = (1.0f - metallic) * (1.0f - EX_ASSIMP_F0);
        for (k = 0; k < 3; k++) {
            out->kd[k] = dielectric * (1.0f - transmission) * base[k];
            out->tf[k] = dielectric * transmission * base[k];
            out->ks[k] = (1.0f - metallic) * EX_ASSIMP_F0 + metallic * base[k];
        }
        alpha = roughness * roughness;
        out->ns = alpha * alpha > 2.0f / (4.0f * EX_ASSIMP_MAX_EXPONENT + 2.0f)
                      ? (2.0f / (alpha * alpha) - 2.0f) / 4.0f : EX_ASSIMP_MAX_EXPONENT;
    } else {
        float spec[3] = { 0, 0, 0 }, spec_strength = 1.0f, shininess = 0.0f;
        ex__ai_color(m, AI_MATKEY_COLOR_SPECULAR, spec);
        ex__ai_float(m, AI_MATKEY_SHININESS_STRENGTH, &spec_strength);
        ex__ai_float(m, AI_MATKEY_SHININESS, &shininess);
        for (k = 0; k < 3; k++) {   /* ks gives way where kd + ks > 1 (e.g. Assimp's white defaults for PLY) */
            out->kd[k] = base[k];
            out->ks[k] = ex__ai_clamp(spec[k] * spec_strength, 0.0f, 1.0f - base[k]);
        }
        out->ns = ex__ai_clamp(shininess, 0.0f, EX_ASSIMP_MAX_EXPONENT);
    }
    if (ex__ai_color(m, AI_MATKEY_COLOR_EMISSIVE, out->ke)) {
        if (!ex__ai_float(m, AI_MATKEY_EMISSIVE_INTENSITY, &strength)) strength = gltf_strength;
        for (k = 0; k < 3; k++) out->ke[k] = ex__ai_clamp(out->ke[k] * strength, 0.0f, 3.4e38f);
    }
    opacity = ex__ai_opacity(m);
    for (k = 0; k < 3; k++) {
        out->tf[k] = (1.0f - opacity) + opacity * out->tf[k];
        out->kd[k] *= opacity;
        out->ks[k] *= opacity;
    }
}

/* ---- glTF's emissive strength ----------------------------------------------
   A small JSON reader, enough to find materials[i].extensions.
   KHR_materials_emissive_strength.emissiveStrength in a .gltf file or a
   .glb's JSON chunk. Hostile input is bounded: nesting depth, lengths. */
#define EX__JSON_MAX_DEPTH 64

typedef struct ex__json { const char *s, *end; } ex__json;

static void ex__json_ws(ex__json *j)
{
    while (j->s < j->end && (*j->s == ' ' || *j->s == '\t' || *j->s == '\n' || *j->s == '\r')) j->s++;
}

/* A string token; *str and *len cover it without the quotes (escapes kept). */
static int ex__json_string(ex__json *j, const char **str, size_t *len)
{
    ex__json_ws(j);
    if (j->s >= j->end || *j->s != '"') return 0;
    *str = ++j->s;
    while (j->s < j->end && *j->s != '"') j->s += *j->s == '\\' && j->s + 1 < j->end ? 2 : 1;
    if (j->s >= j->end) return 0;
    *len = (size_t)(j->s - *str);
    j->s++;
    return 1;
}

static int ex__json_expect(ex__json *j, char c)
{
    ex__json_ws(j);
    if (j->s >= j->end || *j->s != c) return 0;
    j->s++;
    return 1;
}

/* Whether the next character (after blanks) is c; does not consume it. */
static int ex__json_peek(ex__json *j, char c)
{
    ex__json_ws(j);
    return j->s < j->end && *j->s == c;
}

static int ex__json_number(ex__json *j, double *out)
{
    char buf[64], *stop;
    size_t n = 0;
    ex__json_ws(j);
    while (j->s + n < j->end && n + 1 < sizeof buf && strchr("+-0123456789.eE", j->s[n])) { buf[n] = j->s[n]; n++; }
    buf[n] = 0;
    if (!n) return 0;
    *out = strtod(buf, &stop);
    if (*stop) return 0;
    j->s += n;
    return 1;
}

/* Skips one value of any kind. */
static int ex__json_skip(ex__json *j, int depth)
{
    const char *str;
    size_t len;
    double x;
    if (depth > EX__JSON_MAX_DEPTH) return 0;
    ex__json_ws(j);
    if (j->s >= j->end) return 0;
    if (*j->s == '"') return ex__json_string(j, &str, &len);
    if (*j->s == '{' || *j->s == '[') {
        char close = *j->s == '{' ? '}' : ']';
        int object = *j->s == '{';
        j->s++;
        if (ex__json_expect(j, close)) return 1;
        do {
            if (object && (!ex__json_string(j, &str, &len) || !ex__json_expect(j, ':'))) return 0;
            if (!ex__json_skip(j, depth + 1)) return 0;
        } while (ex__json_expect(j, ','));
        return ex__json_expect(j, close);
    }
    if (j->end - j->s >= 4 && (!strncmp(j->s, "true", 4) || !strncmp(j->s, "null", 4))) { j->s += 4; return 1; }
    if (j->end - j->s >= 5 && !strncmp(j->s, "false", 5)) { j->s += 5; return 1; }
    return ex__json_number(j, &x);
}

/* In the object at j, moves j to the value of key; false when absent. */
static int ex__json_find(ex__json *j, const char *key, int depth)
{
    const char *str;
    size_t len, n = strlen(key);
    if (!ex__json_expect(j, '{')) return 0;
    if (ex__json_peek(j, '}')) return 0;
    do {
        if (!ex__json_string(j, &str, &len) || !ex__json_expect(j, ':')) return 0;
        if (len == n && !memcmp(str, key, n)) return 1;
        if (!ex__json_skip(j, depth + 1)) return 0;
    } while (ex__json_expect(j, ','));
    return 0;
}

/* The emissive strength of the material object at j (1 when none). */
static float ex__json_strength(ex__json j)
{
    double x;
    if (ex__json_find(&j, "extensions", 1) && ex__json_find(&j, "KHR_materials_emissive_strength", 2) &&
        ex__json_find(&j, "emissiveStrength", 3) && ex__json_number(&j, &x) && x >= 0.0 && x < 3.4e38)
        return (float)x;
    return 1.0f;
}

/* strength[i] for the first count materials of glTF JSON text. */
static void ex__json_strengths(const char *text, size_t len, float *strength, unsigned count)
{
    ex__json j;
    unsigned i = 0;
    j.s = text;
    j.end = text + len;
    if (!ex__json_find(&j, "materials", 0) || !ex__json_expect(&j, '[') || ex__json_peek(&j, ']')) return;
    do {
        if (i < count) strength[i++] = ex__json_strength(j);
        if (!ex__json_skip(&j, 1)) return;
    } while (ex__json_expect(&j, ','));
}

/* Reads the emissive strengths of a .gltf or .glb file; leaves 1s when the
   file is neither or cannot be read. */
static void ex__gltf_strengths(const char *path, float *strength, unsigned count)
{
    char *text;
    size_t len;
    if (obj__read_file(path, &text, &len) != 0) return;
    if (len >= 20 && !memcmp(text, "glTF", 4)) {   /* .glb: header, then the JSON chunk */
        uint32_t chunk = (uint32_t)(unsigned char)text[12] | (uint32_t)(unsigned char)text[13] << 8 |
                         (uint32_t)(unsigned char)text[14] << 16 | (uint32_t)(unsigned char)text[15] << 24;
        if (!memcmp(text + 16, "JSON", 4) && chunk <= len - 20) ex__json_strengths(text + 20, chunk, strength, count);
    } else {
        ex__json_strengths(text, len, strength, count);
    }
    free(text);
}

/* ---- axes and units ----------------------------------------------------- */

static int ex__ai_meta_int(const C_STRUCT aiMetadata *md, const char *key, int *out)
{
    unsigned i;
    for (i = 0; md && i < md->mNumProperties; i++) {
        if (strcmp(md->mKeys[i].data, key) != 0) continue;
        if (md->mValues[i].mType == AI_INT32) { *out = *(const int32_t *)md->mValues[i].mData; return 1; }
        if (md->mValues[i].mType == AI_UINT64) { *out = (int)*(const uint64_t *)md->mValues[i].mData; return 1; }
        return 0;
    }
    return 0;
}

static int ex__ai_meta_double(const C_STRUCT aiMetadata *md, const char *key, double *out)
{
    unsigned i;
    for (i = 0; md && i < md->mNumProperties; i++) {
        if (strcmp(md->mKeys[i].data, key) != 0) continue;
        if (md->mValues[i].mType == AI_FLOAT) { *out = *(const float *)md->mValues[i].mData; return 1; }
        if (md->mValues[i].mType == AI_DOUBLE) { *out = *(const double *)md->mValues[i].mData; return 1; }
        if (md->mValues[i].mType == AI_INT32) { *out = *(const int32_t *)md->mValues[i].mData; return 1; }
        return 0;
    }
    return 0;
}

/* FBX's axis system as a map to x right, y up, z front: row r of m is the
   file axis (with its sign) that becomes world axis r. False when the file
   declares none, or a degenerate one. */
static int ex__ai_fbx_axes(const C_STRUCT aiMetadata *md, float m[9])
{
    int up, up_sign, front, front_sign, coord, coord_sign;
    if (!ex__ai_meta_int(md, "UpAxis", &up) || !ex__ai_meta_int(md, "UpAxisSign", &up_sign) ||
        !ex__ai_meta_int(md, "FrontAxis", &front) || !ex__ai_meta_int(md, "FrontAxisSign", &front_sign) ||
        !ex__ai_meta_int(md, "CoordAxis", &coord) || !ex__ai_meta_int(md, "CoordAxisSign", &coord_sign))
        return 0;
    if (up < 0 || up > 2 || front < 0 || front > 2 || coord < 0 || coord > 2 || up == front || up == coord || front == coord)
        return 0;
    memset(m, 0, 9 * sizeof(float));
    m[0 + coord] = coord_sign < 0 ? -1.0f : 1.0f;
    m[3 + up] = up_sign < 0 ? -1.0f : 1.0f;
    m[6 + front] = front_sign < 0 ? -1.0f : 1.0f;
    return 1;
}

/* The map from file coordinates to y-up metres (see the doc block). */
static void ex__ai_world_map(const C_STRUCT aiScene *sc, char up, float scale, float m[9])
{
    static const float identity[9] = { 1, 0, 0, 0, 1, 0, 0, 0, 1 };
    static const float z_up[9] = { 1, 0, 0, 0, 0, 1, 0, -1, 0 };   /* (x, y, z) -> (x, z, -y) */
    double unit = 1.0;
    int up_axis, fbx = ex__ai_meta_int(sc->mMetaData, "UpAxis", &up_axis), k;
    if (up == 'z') memcpy(m, z_up, sizeof z_up);
    else if (up == 'y' || !fbx || !ex__ai_fbx_axes(sc->mMetaData, m)) memcpy(m, identity, sizeof identity);
    if (scale <= 0.0f) {
        if (fbx && ex__ai_meta_double(sc->mMetaData, "UnitScaleFactor", &unit) && unit > 0.0 && isfinite(unit)) unit /= 100.0;
        else unit = 1.0;
        scale = (float)unit;
    }
    for (k = 0; k < 9; k++) m[k] *= scale;
}

/* ---- geometry ----------------------------------------------------------- */

/* Exact-position welding: an open-addressing table of vertex indices. */
typedef struct ex__ai_weld { uint32_t *slot; size_t mask; } ex__ai_weld;

static uint32_t ex__ai_hash(const float p[3])
{
    uint32_t h = 2166136261u, bits;
    int k;
    for (k = 0; k < 3; k++) {
        float x = p[k] == 0.0f ? 0.0f : p[k];   /* -0 and +0 are one place */
        memcpy(&bits, &x, sizeof bits);
        h = (h ^ bits) * 16777619u;
        h ^= h >> 15;
    }
    return h;
}

/* Index of position p in b, added when new; -1 when out of memory. */
static int64_t ex__ai_vertex(ex__ai_weld *w, obj__build *b, const float p[3])
{
    size_t i = ex__ai_hash(p) & w->mask;
    const float *pos = (const float *)b->positions.data;
    float q[3];
    uint32_t v;
    int k;
    for (k = 0; k < 3; k++) q[k] = p[k] == 0.0f ? 0.0f : p[k];
    while (w->slot[i] != UINT32_MAX) {
        const float *c = pos + 3 * (size_t)w->slot[i];
        if (c[0] == q[0] && c[1] == q[1] && c[2] == q[2]) return w->slot[i];
        i = (i + 1) & w->mask;
    }
    v = (uint32_t)(b->positions.count / 3);
    if (!obj__push(&b->positions, &q[0]) || !obj__push(&b->positions, &q[1]) || !obj__push(&b->positions, &q[2])) return -1;
    w->slot[i] = v;
    return v;
}

/* Appends mesh me (material and group given) to b, its positions mapped by
   m; a mirroring m reverses the polygons so that fronts stay fronts. */
static int ex__ai_mesh(obj__parser *p, const C_STRUCT aiMesh *me, const float m[9], uint32_t material, uint32_t group,
                       ex__ai_weld *w, obj__build *b, uint32_t *map)
{
    double det = obj__det3(m);
    unsigned v, f, k;
    for (v = 0; v < me->mNumVertices; v++) {
        const C_STRUCT aiVector3D *a = &me->mVertices[v];
        float q[3];
        int64_t at;
        int r;
        if (!isfinite(a->x) || !isfinite(a->y) || !isfinite(a->z))
            return obj__fail(p, "mesh '%s': vertex %u is not finite", me->mName.data, v);
        for (r = 0; r < 3; r++) q[r] = m[3 * r] * a->x + m[3 * r + 1] * a->y + m[3 * r + 2] * a->z;
        if ((at = ex__ai_vertex(w, b, q)) < 0) return obj__fail(p, "out of memory");
        map[v] = (uint32_t)at;
    }
    for (f = 0; f < me->mNumFaces; f++) {
        const C_STRUCT aiFace *face = &me->mFaces[f];
        uint32_t start = (uint32_t)b->face_vertices.count;
        if (face->mNumIndices < 3) continue;   /* a point or a line */
        if (b->face_vertices.count + face->mNumIndices > UINT32_MAX / 2) return obj__fail(p, "too many face vertices");
        for (k = 0; k < face->mNumIndices; k++) {
            unsigned corner = face->mIndices[det < 0.0 ? face->mNumIndices - 1 - k : k];
            if (corner >= me->mNumVertices)
                return obj__fail(p, "mesh '%s': face %u refers to vertex %u of %u", me->mName.data, f, corner, me->mNumVertices);
            if (!obj__push(&b->face_vertices, &map[corner])) return obj__fail(p, "out of memory");
        }
        if (!obj__push(&b->face_start, &start) || !obj__push(&b->face_material, &material) ||
            !obj__push(&b->face_group, &group))
            return obj__fail(p, "out of memory");
    }
    return 0;
}

static int ex__ai_build(obj__parser *p, const C_STRUCT aiScene *sc, const float m[9], obj__build *b)
{
    ex__ai_weld w;
    uint32_t *map = NULL, max_vertices = 0;
    size_t total = 0, cap = 64;
    float *strength = (float *)malloc(sizeof(float) * (sc->mNumMaterials + 1));
    unsigned i;
    int r = 0;
    if (!strength) return obj__fail(p, "out of memory");
    for (i = 0; i < sc->mNumMaterials; i++) strength[i] = 1.0f;
    ex__gltf_strengths(p->file, strength, sc->mNumMaterials);
    for (i = 0; i < sc->mNumMaterials; i++) {
        obj_material mat;
        ex__ai_material(sc->mMaterials[i], strength[i], &mat);
        if (!mat.name[0]) snprintf(mat.name, sizeof mat.name, "material_%u", i);
        if (!obj__push(&b->materials, &mat)) { free(strength); return obj__fail(p, "out of memory"); }
    }
    free(strength);
    for (i = 0; i < sc->mNumMeshes; i++) {
        total += sc->mMeshes[i]->mNumVertices;
        if (sc->mMeshes[i]->mNumVertices > max_vertices) max_vertices = sc->mMeshes[i]->mNumVertices;
        if (sc->mMeshes[i]->mMaterialIndex >= sc->mNumMaterials) return obj__fail(p, "mesh %u has no material", i);
    }
    if (total >= UINT32_MAX / 4) return obj__fail(p, "too many vertices");
    while (cap < 2 * total) cap *= 2;
    w.mask = cap - 1;
    w.slot = (uint32_t *)malloc(cap * sizeof(uint32_t));
    map = (uint32_t *)malloc(sizeof(uint32_t) * (max_vertices + 1));
    if (!w.slot || !map) { free(w.slot); free(map); return obj__fail(p, "out of memory"); }
    memset(w.slot, 0xFF, cap * sizeof(uint32_t));
    for (i = 0; i < sc->mNumMeshes && r == 0; i++) {
        const C_STRUCT aiMesh *me = sc->mMeshes[i];
        char group[OBJ_NAME_MAX];
        uint32_t g = (uint32_t)b->groups.count;
        memset(group, 0, sizeof group);
        if (me->mName.length) ex__ai_name(group, &me->mName);
        else snprintf(group, sizeof group, "mesh_%u", i);
        if (!obj__push(&b->groups, group)) r = obj__fail(p, "out of memory");
        else r = ex__ai_mesh(p, me, m, me->mMaterialIndex, g, &w, b, map);
    }
    free(w.slot);
    free(map);
    return r;
}

/* Loads path through Assimp into out (see the doc block for up and scale).
   Returns 0, or -1 with a message naming the file. */
EX_FN int ex_assimp_load(const char *path, char up, float scale, obj_scene *out, char *err, size_t err_size)
{
    C_STRUCT aiPropertyStore *props;
    const C_STRUCT aiScene *sc;
    obj__build b;
    obj__parser p;
    float m[9];
    int r;
    obj__parser_init(&p, path, err, err_size);
    if (out) memset(out, 0, sizeof *out);
    if (!path || !out) return obj__fail(&p, "no input");
    if (up != 0 && up != 'y' && up != 'z') return obj__fail(&p, "up axis must be y or z");
    if (!(scale >= 0.0f && scale <= 1e9f)) return obj__fail(&p, "bad scale");
    props = aiCreatePropertyStore();
    if (!props) return obj__fail(&p, "out of memory");
    if (up) aiSetImportPropertyInteger(props, AI_CONFIG_IMPORT_COLLADA_IGNORE_UP_DIRECTION, 1);
    aiSetImportPropertyInteger(props, AI_CONFIG_PP_SBP_REMOVE, aiPrimitiveType_POINT | aiPrimitiveType_LINE);
    sc = aiImportFileExWithProperties(path, aiProcess_PreTransformVertices | aiProcess_SortByPType | aiProcess_ValidateDataStructure,
                                      NULL, props);
    aiReleasePropertyStore(props);
    if (!sc) return obj__fail(&p, "%s", aiGetErrorString());
    if (sc->mFlags & AI_SCENE_FLAGS_INCOMPLETE) {
        aiReleaseImport(sc);
        return obj__fail(&p, "the file holds no complete scene");
    }
    ex__ai_world_map(sc, up, scale, m);
    obj__build_init(&b);
    r = ex__ai_build(&p, sc, m, &b);
    aiReleaseImport(sc);
    if (r == 0) r = obj__finish(&p, &b, out);
    obj__build_free(&b);
    return r;
}

/* "Assimp X.Y.Z". */
EX_FN void ex_assimp_version(char *out, size_t size)
{
    snprintf(out, size, "Assimp %u.%u.%u", aiGetVersionMajor(), aiGetVersionMinor(), aiGetVersionPatch());
}

#endif /* EXAMPLES_COMMON_SCENE_ASSIMP_H */
