/* obj.h - OBJ + MTL loader for the project's examples and tests.

   Loads positions, polygonal faces (kept as polygons, because the radiosity
   solver wants quadrilaterals, and also fan-triangulated for everything that
   wants triangles), materials and group names. Texture coordinates and normals
   are validated and ignored.

       obj_scene s;
       char err[256];
       if (obj_load("examples/data/office.obj", &s, err, sizeof err) != 0) {
           fprintf(stderr, "%s\n", err);
           return 1;
       }
       ... s.positions, s.tri_indices, s.tri_material, s.materials ...
       obj_free(&s);

   Material fields (MTL): Kd = diffuse reflectance, Ks = specular (glossy)
   reflectance, Ns = Phong exponent, Ke = emitted radiance in W/(m^2 sr) (a
   diffuse emitter's radiosity is pi * Ke). Faces before any `usemtl` use
   material 0, "default" (Kd 0.8). Faces before any `o`/`g` belong to group 0,
   "default".

   Every problem (missing file, malformed number, index out of range, face with
   fewer than three vertices, unknown material) returns non-zero with a message
   naming the file and line, and leaves *out empty. No input crashes it. */
#ifndef EXAMPLES_COMMON_OBJ_H
#define EXAMPLES_COMMON_OBJ_H

#include <errno.h>
#include <float.h>
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "base.h"

#define OBJ_NAME_MAX 64
#define OBJ_MAX_FILE_BYTES ((size_t)1 << 30) /* refuse inputs over 1 GiB */

typedef struct obj_material {
    char name[OBJ_NAME_MAX];
    float kd[3];   /* diffuse reflectance */
    float ks[3];   /* glossy reflectance */
    float ke[3];   /* emitted radiance */
    float ns;      /* Phong exponent */
} obj_material;

typedef struct obj_scene {
    float *positions;          /* xyz per vertex */
    uint32_t vertex_count;

    uint32_t *face_start;      /* face f: face_vertices[face_start[f] .. face_start[f+1]) */
    uint32_t *face_vertices;
    uint32_t *face_material;
    uint32_t *face_group;
    uint32_t face_count;

    uint32_t *tri_indices;     /* 3 per triangle, fan-triangulated faces */
    uint32_t *tri_material;
    uint32_t *tri_face;        /* the face each triangle came from */
    uint32_t tri_count;

    obj_material *materials;
    uint32_t material_count;
    char (*groups)[OBJ_NAME_MAX];
    uint32_t group_count;
} obj_scene;

/* ---- growable arrays ---------------------------------------------------- */

typedef struct obj__array { void *data; size_t count, capacity, item; } obj__array;

static int obj__push(obj__array *a, const void *item)
{
    if (a->count == a->capacity) {
        size_t cap = a->capacity ? a->capacity * 2 : 64;
        void *p;
        if (cap > (SIZE_MAX / a->item)) return 0;
        p = realloc(a->data, cap * a->item);
        if (!p) return 0;
        a->data = p;
        a->capacity = cap;
    }
    memcpy((char *)a->data + a->count * a->item, item, a->item);
    a->count++;
    return 1;
}

/* ---- parsing helpers ---------------------------------------------------- */

typedef struct obj__parser {
    const char *file;       /* for messages */
    int line;
    char *err;
    size_t err_size;
} obj__parser;

static int obj__fail(obj__parser *p, const char *fmt, ...)
{
    va_list ap;
    int n = 0;
    if (p->err && p->err_size) {
        n = snprintf(p->err, p->err_size, "%s:%d: ", p->file, p->line);
        if (n < 0 || (size_t)n >= p->err_size) n = 0;
        va_start(ap, fmt);
        vsnprintf(p->err + n, p->err_size - (size_t)n, fmt, ap);
        va_end(ap);
    }
    return -1;
}

static const char *obj__skip_space(const char *s, const char *end)
{
    while (s < end && (*s == ' ' || *s == '\t' || *s == '\r')) s++;
    return s;
}

/* The next whitespace-separated token of [s, end) into tok; returns its end. */
static const char *obj__token(const char *s, const char *end, char *tok, size_t tok_size)
{
    size_t n = 0;
    s = obj__skip_space(s, end);
    while (s < end && *s != ' ' && *s != '\t' && *s != '\r') {
        if (n + 1 < tok_size) tok[n++] = *s;
        s++;
    }
    tok[n] = 0;
    return s;
}

/* The next line of [*s, end) without its newline, advancing *s past it and
   counting it in p->line; returns 0 at the end of the text. */
static int obj__next_line(obj__parser *p, const char **s, const char *end, const char **line,
                          const char **eol)
{
    if (*s >= end) return 0;
    *line = *s;
    *eol = (const char *)memchr(*s, '\n', (size_t)(end - *s));
    if (!*eol) *eol = end;
    *s = *eol + (*eol < end);
    p->line++;
    return 1;
}

static int obj__parse_float(const char *tok, float *out)
{
    char *stop;
    double v;
    if (!tok[0]) return 0;
    errno = 0;
    v = strtod(tok, &stop);
    if (*stop || errno == ERANGE || !(v == v) || fabs(v) > FLT_MAX) return 0;
    *out = (float)v;
    return 1;
}

/* Reads n floats; a line with fewer or extra values is an error. */
static int obj__floats(obj__parser *p, const char *s, const char *end, float *out, int n,
                       const char *what)
{
    char tok[128];
    int i;
    for (i = 0; i < n; i++) {
        s = obj__token(s, end, tok, sizeof tok);
        if (!obj__parse_float(tok, &out[i]))
            return obj__fail(p, "%s needs %d numbers, got '%s'", what, n, tok);
    }
    s = obj__token(s, end, tok, sizeof tok);
    if (tok[0] && strcmp(what, "v") != 0) /* v may carry a w or colour; others may not */
        return obj__fail(p, "%s: unexpected '%s'", what, tok);
    return 0;
}

/* OBJ vertex reference "v", "v/t", "v//n", "v/t/n"; negative is relative. */
static int obj__vertex_ref(obj__parser *p, const char *tok, size_t vertex_count, uint32_t *out)
{
    char *stop;
    long v;
    errno = 0;
    v = strtol(tok, &stop, 10);
    if (stop == tok || errno == ERANGE || (*stop && *stop != '/'))
        return obj__fail(p, "bad vertex reference '%s'", tok);
    if (v < 0) v = (long)vertex_count + v + 1;
    if (v < 1 || (unsigned long)v > vertex_count)
        return obj__fail(p, "vertex index '%s' out of range (1..%lu)", tok, (unsigned long)vertex_count);
    *out = (uint32_t)(v - 1);
    return 0;
}

static int obj__read_file(const char *path, char **text, size_t *len)
{
    FILE *f = fopen(path, "rb");
    long size;
    if (!f) return -1;
    if (fseek(f, 0, SEEK_END) != 0 || (size = ftell(f)) < 0 || (size_t)size > OBJ_MAX_FILE_BYTES ||
        fseek(f, 0, SEEK_SET) != 0) {
        fclose(f);
        return -1;
    }
    *text = (char *)malloc((size_t)size + 1);
    if (!*text) { fclose(f); return -1; }
    if (fread(*text, 1, (size_t)size, f) != (size_t)size) {
        free(*text);
        fclose(f);
        return -1;
    }
    (*text)[size] = 0;
    *len = (size_t)size;
    fclose(f);
    return 0;
}

/* ---- MTL ---------------------------------------------------------------- */

static void obj__default_material(obj_material *m, const char *name)
{
    size_t n = strlen(name);
    memset(m, 0, sizeof *m);
    memcpy(m->name, name, n < OBJ_NAME_MAX ? n : OBJ_NAME_MAX - 1);
    m->kd[0] = m->kd[1] = m->kd[2] = 0.8f;
    m->ns = 1.0f;
}

/* Parses MTL text and appends its materials. */
static int obj__parse_mtl(obj__parser *p, const char *text, size_t len, obj__array *materials)
{
    const char *s = text, *end = text + len, *line, *eol;
    obj_material *cur = NULL;
    char tok[OBJ_NAME_MAX + 8];
    p->line = 0;
    while (obj__next_line(p, &s, end, &line, &eol)) {
        const char *rest = obj__token(line, eol, tok, sizeof tok);
        if (!tok[0] || tok[0] == '#') {
            /* blank or comment */
        } else if (strcmp(tok, "newmtl") == 0) {
            obj_material m;
            obj__token(rest, eol, tok, sizeof tok);
            if (!tok[0]) return obj__fail(p, "newmtl without a name");
            if (strlen(tok) >= OBJ_NAME_MAX) return obj__fail(p, "material name too long");
            obj__default_material(&m, tok);
            if (!obj__push(materials, &m)) return obj__fail(p, "out of memory");
            cur = (obj_material *)materials->data + materials->count - 1;
        } else if (!cur) {
            return obj__fail(p, "'%s' before any newmtl", tok);
        } else if (strcmp(tok, "Kd") == 0) {
            if (obj__floats(p, rest, eol, cur->kd, 3, "Kd")) return -1;
        } else if (strcmp(tok, "Ks") == 0) {
            if (obj__floats(p, rest, eol, cur->ks, 3, "Ks")) return -1;
        } else if (strcmp(tok, "Ke") == 0) {
            if (obj__floats(p, rest, eol, cur->ke, 3, "Ke")) return -1;
        } else if (strcmp(tok, "Ns") == 0) {
            if (obj__floats(p, rest, eol, &cur->ns, 1, "Ns")) return -1;
        } /* other statements (Ka, illum, map_*, ...) are ignored */
    }
    return 0;
}

/* ---- OBJ ---------------------------------------------------------------- */

typedef struct obj__build {
    obj__array positions, face_start, face_vertices, face_material, face_group;
    obj__array materials, groups;
} obj__build;

static void obj__build_free(obj__build *b)
{
    free(b->positions.data);
    free(b->face_start.data);
    free(b->face_vertices.data);
    free(b->face_material.data);
    free(b->face_group.data);
    free(b->materials.data);
    free(b->groups.data);
}

static int obj__find_material(const obj__build *b, const char *name, uint32_t *out)
{
    const obj_material *m = (const obj_material *)b->materials.data;
    size_t i;
    for (i = 0; i < b->materials.count; i++)
        if (strcmp(m[i].name, name) == 0) { *out = (uint32_t)i; return 1; }
    return 0;
}

static int obj__load_mtllib(obj__parser *p, const char *base_dir, const char *name, obj__build *b)
{
    char path[1024];
    char *text;
    size_t len;
    obj__parser mp;
    int n = snprintf(path, sizeof path, "%s%s", base_dir ? base_dir : "", name);
    if (n < 0 || (size_t)n >= sizeof path) return obj__fail(p, "mtllib path too long");
    if (obj__read_file(path, &text, &len) != 0)
        return obj__fail(p, "cannot read material library '%s'", path);
    mp.file = path;
    mp.line = 0;
    mp.err = p->err;
    mp.err_size = p->err_size;
    n = obj__parse_mtl(&mp, text, len, &b->materials);
    free(text);
    return n;
}

static int obj__parse_face(obj__parser *p, const char *s, const char *end, obj__build *b,
                           uint32_t material, uint32_t group)
{
    char tok[128];
    uint32_t start = (uint32_t)b->face_vertices.count, n = 0;
    for (;;) {
        uint32_t v = 0;
        s = obj__token(s, end, tok, sizeof tok);
        if (!tok[0]) break;
        if (obj__vertex_ref(p, tok, b->positions.count / 3, &v)) return -1;
        if (!obj__push(&b->face_vertices, &v)) return obj__fail(p, "out of memory");
        n++;
    }
    if (n < 3) return obj__fail(p, "face with %u vertices (needs at least 3)", n);
    if (b->face_vertices.count > UINT32_MAX / 2) return obj__fail(p, "too many face vertices");
    if (!obj__push(&b->face_start, &start) || !obj__push(&b->face_material, &material) ||
        !obj__push(&b->face_group, &group))
        return obj__fail(p, "out of memory");
    return 0;
}

static int obj__parse_obj(obj__parser *p, const char *text, size_t len, const char *base_dir,
                          obj__build *b)
{
    const char *s = text, *end = text + len, *line, *eol;
    char tok[OBJ_NAME_MAX + 8];
    uint32_t material = 0, group = 0;
    obj_material def;
    char def_group[OBJ_NAME_MAX] = "default";
    obj__default_material(&def, "default");
    if (!obj__push(&b->materials, &def) || !obj__push(&b->groups, def_group))
        return obj__fail(p, "out of memory");
    p->line = 0;
    while (obj__next_line(p, &s, end, &line, &eol)) {
        const char *rest = obj__token(line, eol, tok, sizeof tok);
        if (!tok[0] || tok[0] == '#') {
            /* blank or comment */
        } else if (strcmp(tok, "v") == 0) {
            float v[3];
            if (obj__floats(p, rest, eol, v, 3, "v")) return -1;
            if (b->positions.count / 3 >= UINT32_MAX - 1) return obj__fail(p, "too many vertices");
            if (!obj__push(&b->positions, &v[0]) || !obj__push(&b->positions, &v[1]) ||
                !obj__push(&b->positions, &v[2]))
                return obj__fail(p, "out of memory");
        } else if (strcmp(tok, "f") == 0) {
            if (obj__parse_face(p, rest, eol, b, material, group)) return -1;
        } else if (strcmp(tok, "usemtl") == 0) {
            obj__token(rest, eol, tok, sizeof tok);
            if (!obj__find_material(b, tok, &material))
                return obj__fail(p, "unknown material '%s'", tok);
        } else if (strcmp(tok, "mtllib") == 0) {
            obj__token(rest, eol, tok, sizeof tok);
            if (!tok[0]) return obj__fail(p, "mtllib without a file name");
            if (obj__load_mtllib(p, base_dir, tok, b)) return -1;
        } else if (strcmp(tok, "o") == 0 || strcmp(tok, "g") == 0) {
            char name[OBJ_NAME_MAX];
            memset(name, 0, sizeof name);
            obj__token(rest, eol, tok, sizeof tok);
            if (strlen(tok) >= OBJ_NAME_MAX) return obj__fail(p, "group name too long");
            memcpy(name, tok[0] ? tok : "default", tok[0] ? strlen(tok) : 7);
            if (b->groups.count >= UINT32_MAX) return obj__fail(p, "too many groups");
            group = (uint32_t)b->groups.count;
            if (!obj__push(&b->groups, name)) return obj__fail(p, "out of memory");
        } else if (strcmp(tok, "vt") == 0 || strcmp(tok, "vn") == 0 || strcmp(tok, "s") == 0 ||
                   strcmp(tok, "l") == 0 || strcmp(tok, "p") == 0) {
            /* not needed by the project */
        } else {
            return obj__fail(p, "unknown statement '%s'", tok);
        }
    }
    return 0;
}

/* Fan-triangulates the faces and moves the arrays into out. */
static int obj__finish(obj__parser *p, obj__build *b, obj_scene *out)
{
    uint32_t f, tri = 0, face_count = (uint32_t)b->face_start.count;
    uint32_t end = (uint32_t)b->face_vertices.count;
    size_t tri_count = b->face_vertices.count - 2 * (size_t)face_count;
    const uint32_t *start = (const uint32_t *)b->face_start.data;
    const uint32_t *fv = (const uint32_t *)b->face_vertices.data;
    if (!obj__push(&b->face_start, &end)) return obj__fail(p, "out of memory");
    start = (const uint32_t *)b->face_start.data;
    memset(out, 0, sizeof *out);
    out->tri_indices = (uint32_t *)malloc(sizeof(uint32_t) * 3 * (tri_count ? tri_count : 1));
    out->tri_material = (uint32_t *)malloc(sizeof(uint32_t) * (tri_count ? tri_count : 1));
    out->tri_face = (uint32_t *)malloc(sizeof(uint32_t) * (tri_count ? tri_count : 1));
    if (!out->tri_indices || !out->tri_material || !out->tri_face) {
        free(out->tri_indices); free(out->tri_material); free(out->tri_face);
        memset(out, 0, sizeof *out);
        return obj__fail(p, "out of memory");
    }
    for (f = 0; f < face_count; f++) {
        uint32_t k;
        for (k = start[f] + 1; k + 1 < start[f + 1]; k++, tri++) {
            out->tri_indices[3 * tri + 0] = fv[start[f]];
            out->tri_indices[3 * tri + 1] = fv[k];
            out->tri_indices[3 * tri + 2] = fv[k + 1];
            out->tri_material[tri] = ((const uint32_t *)b->face_material.data)[f];
            out->tri_face[tri] = f;
        }
    }
    out->tri_count = tri;
    out->positions = (float *)b->positions.data;
    out->vertex_count = (uint32_t)(b->positions.count / 3);
    out->face_start = (uint32_t *)b->face_start.data;
    out->face_vertices = (uint32_t *)b->face_vertices.data;
    out->face_material = (uint32_t *)b->face_material.data;
    out->face_group = (uint32_t *)b->face_group.data;
    out->face_count = face_count;
    out->materials = (obj_material *)b->materials.data;
    out->material_count = (uint32_t)b->materials.count;
    out->groups = (char (*)[OBJ_NAME_MAX])b->groups.data;
    out->group_count = (uint32_t)b->groups.count;
    memset(b, 0, sizeof *b);
    return 0;
}

EX_FN void obj_free(obj_scene *s)
{
    if (!s) return;
    free(s->positions);
    free(s->face_start);
    free(s->face_vertices);
    free(s->face_material);
    free(s->face_group);
    free(s->tri_indices);
    free(s->tri_material);
    free(s->tri_face);
    free(s->materials);
    free(s->groups);
    memset(s, 0, sizeof *s);
}

/* Parses OBJ text held in memory. base_dir (ending in '/', or NULL) locates
   mtllib files. name is used in messages. */
EX_FN int obj_parse(const char *text, size_t len, const char *name, const char *base_dir,
                    obj_scene *out, char *err, size_t err_size)
{
    obj__build b;
    obj__parser p;
    int r;
    memset(&b, 0, sizeof b);
    b.positions.item = sizeof(float);
    b.face_start.item = b.face_vertices.item = b.face_material.item = b.face_group.item =
        sizeof(uint32_t);
    b.materials.item = sizeof(obj_material);
    b.groups.item = OBJ_NAME_MAX;
    p.file = name ? name : "<memory>";
    p.line = 0;
    p.err = err;
    p.err_size = err_size;
    if (out) memset(out, 0, sizeof *out);
    if (!text || !out) return obj__fail(&p, "no input");
    r = obj__parse_obj(&p, text, len, base_dir, &b);
    if (r == 0) r = obj__finish(&p, &b, out);
    obj__build_free(&b);
    return r;
}

/* Loads an OBJ file and the material libraries it names (relative to it). */
EX_FN int obj_load(const char *path, obj_scene *out, char *err, size_t err_size)
{
    char dir[1024];
    const char *slash;
    char *text;
    size_t len, n;
    int r;
    if (out) memset(out, 0, sizeof *out);
    if (!path || !out) {
        if (err && err_size) snprintf(err, err_size, "obj_load: no path");
        return -1;
    }
    slash = strrchr(path, '/');
    n = slash ? (size_t)(slash - path) + 1 : 0;
    if (n >= sizeof dir) {
        if (err && err_size) snprintf(err, err_size, "%s: path too long", path);
        return -1;
    }
    memcpy(dir, path, n);
    dir[n] = 0;
    if (obj__read_file(path, &text, &len) != 0) {
        if (err && err_size) snprintf(err, err_size, "%s: cannot read file", path);
        return -1;
    }
    r = obj_parse(text, len, path, dir, out, err, err_size);
    free(text);
    return r;
}

/* Index of the group with this name, or -1. */
EX_FN int obj_find_group(const obj_scene *s, const char *name)
{
    uint32_t g;
    for (g = 0; g < s->group_count; g++)
        if (strcmp(s->groups[g], name) == 0) return (int)g;
    return -1;
}

/* Index of the material with this name, or -1. */
EX_FN int obj_find_material(const obj_scene *s, const char *name)
{
    uint32_t m;
    for (m = 0; m < s->material_count; m++)
        if (strcmp(s->materials[m].name, name) == 0) return (int)m;
    return -1;
}

/* Axis-aligned bounds of all vertices; false when the scene has none. */
EX_FN int obj_bounds(const obj_scene *s, float lo[3], float hi[3])
{
    uint32_t v;
    int k;
    if (!s->vertex_count) return 0;
    for (k = 0; k < 3; k++) lo[k] = hi[k] = s->positions[k];
    for (v = 1; v < s->vertex_count; v++)
        for (k = 0; k < 3; k++) {
            float x = s->positions[3 * v + k];
            if (x < lo[k]) lo[k] = x;
            if (x > hi[k]) hi[k] = x;
        }
    return 1;
}

/* Smooth vertex normals: the area-weighted sum of the normals of the
   triangles around each vertex (by winding), normalised. normals holds 3
   floats per vertex; a vertex used by no non-degenerate triangle gets 0,1,0. */
EX_FN void obj_vertex_normals(const obj_scene *s, float *normals)
{
    uint32_t i, v;
    memset(normals, 0, sizeof(float) * 3 * (size_t)s->vertex_count);
    for (i = 0; i < s->tri_count; i++) {
        const uint32_t *t = s->tri_indices + 3 * (size_t)i;
        const float *a = s->positions + 3 * (size_t)t[0], *b = s->positions + 3 * (size_t)t[1],
                    *c = s->positions + 3 * (size_t)t[2];
        float e1[3], e2[3], n[3];
        int k, j;
        for (k = 0; k < 3; k++) { e1[k] = b[k] - a[k]; e2[k] = c[k] - a[k]; }
        n[0] = e1[1] * e2[2] - e1[2] * e2[1];   /* |n| = twice the area: area weighting */
        n[1] = e1[2] * e2[0] - e1[0] * e2[2];
        n[2] = e1[0] * e2[1] - e1[1] * e2[0];
        for (j = 0; j < 3; j++)
            for (k = 0; k < 3; k++) normals[3 * (size_t)t[j] + (size_t)k] += n[k];
    }
    for (v = 0; v < s->vertex_count; v++) {
        float *n = normals + 3 * (size_t)v;
        float l = sqrtf(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        if (l > 0.0f) { n[0] /= l; n[1] /= l; n[2] /= l; }
        else { n[0] = 0.0f; n[1] = 1.0f; n[2] = 0.0f; }
    }
}

#endif /* EXAMPLES_COMMON_OBJ_H */
