/* obj.h - OBJ + MTL loader for the project's examples and tests.

   Loads positions, polygonal faces (kept as polygons, because the radiosity
   solver wants quadrilaterals, and also triangulated for everything that
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

   Transmission: tf is the share of the light arriving on either side that
   goes straight through, per channel (a thin dielectric: no refraction, no
   change of direction). Two MTL statements make a surface pass light:
   - `d` (dissolve, or `Tr` = 1 - d) is coverage: a share 1 - d of the surface
     is not there, so 1 - d of the light passes untinted and Kd, Ks reflect
     d of what they would;
   - `Tf` (transmission filter) is glass when the illumination model is one
     of the transparent ones (`illum` 4, 6, 7 or 9): Tf passes through, the
     diffuse part keeps 1 - Tf of its reflectance (as glTF's transmission
     mixes the diffuse lobe) and Ks stays (the glass's reflection). Exporters
     write `Tf 1 1 1` on opaque materials with other models, so Tf alone is
     not glass.
   Together: tf = (1 - d) + d Tf, Kd d (1 - Tf), Ks d. Every value must lie in
   [0, 1].

   Triangulation: a face is a planar polygon without holes, of any number of
   corners, concave or not (CAD exports cut door openings into a wall's
   outline and windows as keyholes). Strictly convex faces are fanned from
   their first corner; every other face is ear-clipped in the plane of its
   dominant axis, robust to collinear and repeated corners and to slivers.
   A face of n corners always gives n - 2 triangles (tri_face names the face),
   none turned against the face, their areas adding up to the face's. A face
   whose outline crosses itself has no such triangulation: it still gives
   n - 2 triangles, cut where the outline turns most.

   Coincident faces: two faces that overlap in one plane (within 1e-5 of the
   scene's size, OBJ_COINCIDENT_TOLERANCE) facing the same way, such as paint
   exported over the concrete it covers, make every renderer pick either one
   per pixel or per ray: speckled bands. The loader finds them and reports
   them in coincident_pairs, coincident_faces and coincident_area; it keeps
   them. obj_drop_coincident removes each face that faces of higher index
   cover entirely (the later face is the one meant: paint is written after
   the wall); a face covered only in part stays, as cutting it would leave
   T-junctions. Faces back to back (a wall's two sides in one plane) face
   opposite ways and are not coincident.

   Functions:
       obj_load, obj_parse       read a file / text in memory
       obj_free
       obj_write                 write OBJ + MTL that read back the same
       obj_transform             change axes or units (mirrors keep fronts)
       obj_drop_coincident       drop faces covered by later coincident ones
       obj_find_group, obj_find_material, obj_bounds, obj_vertex_normals
   Other formats: scene_load.h (ex_scene_load) reads them through Assimp
   into the same obj_scene.

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
    float tf[3];   /* straight-through transmittance (thin glass, no refraction); 0 = opaque */
} obj_material;

typedef struct obj_scene {
    float *positions;          /* xyz per vertex */
    uint32_t vertex_count;

    uint32_t *face_start;      /* face f: face_vertices[face_start[f] .. face_start[f+1]) */
    uint32_t *face_vertices;
    uint32_t *face_material;
    uint32_t *face_group;
    uint32_t face_count;

    uint32_t *tri_indices;     /* 3 per triangle: the faces' n - 2 triangles each, in face order */
    uint32_t *tri_material;
    uint32_t *tri_face;        /* the face each triangle came from */
    uint32_t tri_count;

    obj_material *materials;
    uint32_t material_count;
    char (*groups)[OBJ_NAME_MAX];
    uint32_t group_count;

    /* coincident faces (see "Coincident faces" above), found at load */
    uint32_t coincident_pairs;     /* pairs of faces overlapping in one plane, facing the same way */
    uint32_t coincident_faces;     /* faces in at least one such pair */
    double coincident_area;        /* area of the overlaps, summed over the pairs */
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
        n = p->line > 0 ? snprintf(p->err, p->err_size, "%s:%d: ", p->file, p->line)
                        : snprintf(p->err, p->err_size, "%s: ", p->file);
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

/* What an MTL material says about light through it, kept until the
   material's last line has been read. */
typedef struct obj__mtl_pass {
    float d;             /* dissolve: the share of the surface that is there (1 = opaque) */
    float filter[3];     /* Tf */
    int has_filter, illum;
} obj__mtl_pass;

static void obj__mtl_pass_reset(obj__mtl_pass *t)
{
    memset(t, 0, sizeof *t);
    t->d = 1.0f;
    t->illum = -1;
}

/* The straight-through transmittance of a finished material, and the
   reflectances scaled to what is left (see "Transmission" above). */
static void obj__material_transmission(obj_material *m, const obj__mtl_pass *t)
{
    int glass = t->has_filter && (t->illum == 4 || t->illum == 6 || t->illum == 7 || t->illum == 9), k;
    for (k = 0; k < 3; k++) {
        float through_glass = glass ? t->filter[k] : 0.0f;
        m->tf[k] = (1.0f - t->d) + t->d * through_glass;
        m->kd[k] *= t->d * (1.0f - through_glass);
        m->ks[k] *= t->d;
    }
}

/* A fraction in [0, 1] (d, Tr, Tf): anything else is an error. */
static int obj__fractions(obj__parser *p, const char *s, const char *end, float *out, int n, const char *what)
{
    int k;
    if (obj__floats(p, s, end, out, n, what)) return -1;
    for (k = 0; k < n; k++)
        if (!(out[k] >= 0.0f && out[k] <= 1.0f)) return obj__fail(p, "%s must be in [0, 1], got %g", what, (double)out[k]);
    return 0;
}

/* "d factor" or "d -halo factor" (the halo form is read as the plain one). */
static int obj__dissolve(obj__parser *p, const char *s, const char *end, float *d)
{
    char tok[16];
    const char *after = obj__token(s, end, tok, sizeof tok);
    return obj__fractions(p, strcmp(tok, "-halo") == 0 ? after : s, end, d, 1, "d");
}

/* "Tf r g b" or "Tf r" (grey). The spectral and CIE XYZ forms are refused. */
static int obj__filter(obj__parser *p, const char *s, const char *end, float f[3])
{
    char tok[32];
    const char *after = obj__token(s, end, tok, sizeof tok);
    obj__token(after, end, tok, sizeof tok);
    if (!tok[0]) {
        if (obj__fractions(p, s, end, f, 1, "Tf")) return -1;
        f[1] = f[2] = f[0];
        return 0;
    }
    obj__token(s, end, tok, sizeof tok);
    if (strcmp(tok, "spectral") == 0 || strcmp(tok, "xyz") == 0)
        return obj__fail(p, "Tf %s is not supported (give Tf r g b)", tok);
    return obj__fractions(p, s, end, f, 3, "Tf");
}

/* Parses MTL text and appends its materials. */
static int obj__parse_mtl(obj__parser *p, const char *text, size_t len, obj__array *materials)
{
    const char *s = text, *end = text + len, *line, *eol;
    obj_material *cur = NULL;
    obj__mtl_pass pass;
    char tok[OBJ_NAME_MAX + 8];
    p->line = 0;
    obj__mtl_pass_reset(&pass);
    while (obj__next_line(p, &s, end, &line, &eol)) {
        const char *rest = obj__token(line, eol, tok, sizeof tok);
        if (!tok[0] || tok[0] == '#') {
            /* blank or comment */
        } else if (strcmp(tok, "newmtl") == 0) {
            obj_material m;
            obj__token(rest, eol, tok, sizeof tok);
            if (!tok[0]) return obj__fail(p, "newmtl without a name");
            if (strlen(tok) >= OBJ_NAME_MAX) return obj__fail(p, "material name too long");
            if (cur) obj__material_transmission(cur, &pass);
            obj__mtl_pass_reset(&pass);
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
        } else if (strcmp(tok, "d") == 0) {
            if (obj__dissolve(p, rest, eol, &pass.d)) return -1;
        } else if (strcmp(tok, "Tr") == 0) {
            float tr;
            if (obj__fractions(p, rest, eol, &tr, 1, "Tr")) return -1;
            pass.d = 1.0f - tr;
        } else if (strcmp(tok, "Tf") == 0) {
            if (obj__filter(p, rest, eol, pass.filter)) return -1;
            pass.has_filter = 1;
        } else if (strcmp(tok, "illum") == 0) {
            float illum;
            if (obj__floats(p, rest, eol, &illum, 1, "illum")) return -1;
            if (!(illum >= 0.0f && illum <= 10.0f) || illum != (float)(int)illum)
                return obj__fail(p, "illum must be an integer 0..10");
            pass.illum = (int)illum;
        } /* other statements (Ka, Ni, map_*, ...) are ignored */
    }
    if (cur) obj__material_transmission(cur, &pass);
    return 0;
}

/* ---- OBJ ---------------------------------------------------------------- */

typedef struct obj__build {
    obj__array positions, face_start, face_vertices, face_material, face_group;
    obj__array materials, groups;
} obj__build;

static void obj__build_init(obj__build *b)
{
    memset(b, 0, sizeof *b);
    b->positions.item = sizeof(float);
    b->face_start.item = b->face_vertices.item = b->face_material.item = b->face_group.item = sizeof(uint32_t);
    b->materials.item = sizeof(obj_material);
    b->groups.item = OBJ_NAME_MAX;
}

static void obj__parser_init(obj__parser *p, const char *name, char *err, size_t err_size)
{
    p->file = name ? name : "<memory>";
    p->line = 0;
    p->err = err;
    p->err_size = err_size;
}

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

/* ---- triangulation -------------------------------------------------------
   A face is a planar polygon without holes. Its corners are projected on the
   plane of the dominant axis of its Newell normal (the axis where the
   projected area is largest, so the projection cannot fold), oriented
   counter-clockwise there. A strictly convex face is fanned from its first
   corner; any other face (a concave outline, collinear corners, repeated
   corners, a nearly degenerate sliver) is ear-clipped: a corner is cut off
   when it turns left and no other corner lies in or on the triangle it cuts.
   Every face of n corners gives n - 2 triangles, each turning the face's way
   (or of zero area), and their areas add up to the face's area. Orientation
   tests run in double precision on the float coordinates, where a difference
   of two floats is exact. */

/* Relative size of a turn below which a corner counts as collinear: sin of
   the angle between the two edges. Float coordinates carry a relative error
   of 6e-8, so turns a thousand times finer than 1e-6 are noise. */
#define OBJ__COLLINEAR 1e-6
typedef struct obj__ring {
    double *x, *y;          /* projected corners */
    uint32_t *prev, *next;  /* the corners still in the outline */
    uint32_t capacity;
} obj__ring;

/* Newell's normal of a polygon (twice its vector area), in double. */
static void obj__newell(const float *pos, const uint32_t *v, uint32_t n, double nrm[3])
{
    uint32_t i;
    nrm[0] = nrm[1] = nrm[2] = 0.0;
    for (i = 0; i < n; i++) {
        const float *a = pos + 3 * (size_t)v[i], *b = pos + 3 * (size_t)v[(i + 1) % n];
        nrm[0] += ((double)a[1] - b[1]) * ((double)a[2] + b[2]);
        nrm[1] += ((double)a[2] - b[2]) * ((double)a[0] + b[0]);
        nrm[2] += ((double)a[0] - b[0]) * ((double)a[1] + b[1]);
    }
}

/* Twice the signed area of the triangle (a, b, c) of the ring. */
static double obj__orient(const obj__ring *r, uint32_t a, uint32_t b, uint32_t c)
{
    return (r->x[b] - r->x[a]) * (r->y[c] - r->y[a]) - (r->y[b] - r->y[a]) * (r->x[c] - r->x[a]);
}

/* The turn at corner b of the path a -> b -> c: positive when it turns left
   by more than OBJ__COLLINEAR, negative when right, zero when collinear. */
static int obj__turn(const obj__ring *r, uint32_t a, uint32_t b, uint32_t c)
{
    double ex = r->x[b] - r->x[a], ey = r->y[b] - r->y[a], fx = r->x[c] - r->x[b], fy = r->y[c] - r->y[b];
    double cross = ex * fy - ey * fx, scale = sqrt((ex * ex + ey * ey) * (fx * fx + fy * fy));
    if (cross > OBJ__COLLINEAR * scale) return 1;
    if (cross < -OBJ__COLLINEAR * scale) return -1;
    return 0;
}

/* Projects face v[0..n) on its dominant plane, counter-clockwise. */
static void obj__project(obj__ring *r, const float *pos, const uint32_t *v, uint32_t n)
{
    double nrm[3];
    int axis, u, w;
    uint32_t i;
    obj__newell(pos, v, n, nrm);
    axis = fabs(nrm[0]) > fabs(nrm[1]) ? (fabs(nrm[0]) > fabs(nrm[2]) ? 0 : 2) : (fabs(nrm[1]) > fabs(nrm[2]) ? 1 : 2);
    u = (axis + 1) % 3;
    w = (axis + 2) % 3;
    if (nrm[axis] < 0.0) { int t = u; u = w; w = t; }   /* seen from the side the normal points to */
    for (i = 0; i < n; i++) {
        r->x[i] = pos[3 * (size_t)v[i] + u];
        r->y[i] = pos[3 * (size_t)v[i] + w];
        r->prev[i] = (i + n - 1) % n;
        r->next[i] = (i + 1) % n;
    }
}

/* Strictly convex: every corner turns left and the outline goes round once
   (its turning angles add up to 2 pi, not 4 pi as in a pentagram). */
static int obj__convex(const obj__ring *r, uint32_t n)
{
    double total = 0.0;
    uint32_t i;
    for (i = 0; i < n; i++) {
        uint32_t a = (i + n - 1) % n, c = (i + 1) % n;
        double ex = r->x[i] - r->x[a], ey = r->y[i] - r->y[a], fx = r->x[c] - r->x[i], fy = r->y[c] - r->y[i];
        if (obj__turn(r, a, i, c) <= 0) return 0;
        total += atan2(ex * fy - ey * fx, ex * fx + ey * fy);
    }
    return total < 3.0 * 3.14159265358979323846;   /* 2 pi, far from 4 pi */
}

/* Whether p is left of, on or within OBJ__COLLINEAR of the line a -> b. */
static int obj__left_or_on(const obj__ring *r, uint32_t a, uint32_t b, uint32_t p)
{
    double ex = r->x[b] - r->x[a], ey = r->y[b] - r->y[a], fx = r->x[p] - r->x[a], fy = r->y[p] - r->y[a];
    return ex * fy - ey * fx >= -OBJ__COLLINEAR * sqrt((ex * ex + ey * ey) * (fx * fx + fy * fy));
}

/* Whether corner p lies inside or on triangle (a, b, c), counter-clockwise,
   counting a corner within rounding of an edge as on it (a diagonal through
   a corner would leave a crack or a flipped sliver). A corner at the same
   place as a, b or c does not count (outlines that touch themselves repeat
   a point). */
static int obj__blocks(const obj__ring *r, uint32_t a, uint32_t b, uint32_t c, uint32_t p)
{
    if ((r->x[p] == r->x[a] && r->y[p] == r->y[a]) || (r->x[p] == r->x[b] && r->y[p] == r->y[b]) ||
        (r->x[p] == r->x[c] && r->y[p] == r->y[c]))
        return 0;
    return obj__left_or_on(r, a, b, p) && obj__left_or_on(r, b, c, p) && obj__left_or_on(r, c, a, p);
}

/* Corner b is an ear: it turns left and no other remaining corner that does
   not turn left lies in or on the triangle it cuts (a corner that turns left
   cannot be the first one inside a convex ear). */
static int obj__is_ear(const obj__ring *r, uint32_t b)
{
    uint32_t a = r->prev[b], c = r->next[b], p;
    if (obj__turn(r, a, b, c) <= 0) return 0;
    for (p = r->next[c]; p != a; p = r->next[p])
        if (obj__turn(r, r->prev[p], p, r->next[p]) <= 0 && obj__blocks(r, a, b, c, p)) return 0;
    return 1;
}

/* The corner to cut when no corner is an ear (an outline that crosses itself,
   or all corners collinear): the one that turns left the most, else the one
   closest to straight. A simple outline always has an ear (Meisters 1975). */
static uint32_t obj__fallback_ear(const obj__ring *r, uint32_t start)
{
    uint32_t b = start, best = start;
    double best_area = -DBL_MAX;
    do {
        double area = obj__orient(r, r->prev[b], b, r->next[b]);
        if (area > best_area) { best_area = area; best = b; }
        b = r->next[b];
    } while (b != start);
    return best;
}

/* Writes the n - 2 triangles of face v[0..n) to tri (3 corner indices each). */
static void obj__triangulate(obj__ring *r, const float *pos, const uint32_t *v, uint32_t n, uint32_t *tri)
{
    uint32_t b = 0, left = n, tested = 0, k;
    obj__project(r, pos, v, n);
    if (n == 3 || obj__convex(r, n)) {
        for (k = 1; k + 1 < n; k++) { tri[0] = v[0]; tri[1] = v[k]; tri[2] = v[k + 1]; tri += 3; }
        return;
    }
    while (left > 3) {
        uint32_t a, c;
        if (!obj__is_ear(r, b)) {
            if (++tested < left) { b = r->next[b]; continue; }
            b = obj__fallback_ear(r, b);   /* a whole round without an ear */
        }
        tested = 0;
        a = r->prev[b];
        c = r->next[b];
        tri[0] = v[a]; tri[1] = v[b]; tri[2] = v[c];
        tri += 3;
        r->next[a] = c;
        r->prev[c] = a;
        left--;
        b = c;   /* the next ear is likely next door */
    }
    tri[0] = v[r->prev[b]]; tri[1] = v[b]; tri[2] = v[r->next[b]];
}

static void obj__ring_free(obj__ring *r)
{
    free(r->x); free(r->y); free(r->prev); free(r->next);
    memset(r, 0, sizeof *r);
}

static int obj__ring_reserve(obj__ring *r, uint32_t n)
{
    if (n <= r->capacity) return 1;
    obj__ring_free(r);
    r->x = (double *)malloc(sizeof(double) * n);
    r->y = (double *)malloc(sizeof(double) * n);
    r->prev = (uint32_t *)malloc(sizeof(uint32_t) * n);
    r->next = (uint32_t *)malloc(sizeof(uint32_t) * n);
    if (!r->x || !r->y || !r->prev || !r->next) { obj__ring_free(r); return 0; }
    r->capacity = n;
    return 1;
}

/* Triangulates every face into out's triangle arrays; -1 when out of memory. */
static int obj__triangulate_faces(const obj__build *b, obj_scene *out)
{
    const uint32_t *start = (const uint32_t *)b->face_start.data, *fv = (const uint32_t *)b->face_vertices.data;
    const uint32_t *material = (const uint32_t *)b->face_material.data;
    const float *pos = (const float *)b->positions.data;
    uint32_t f, tri = 0, face_count = (uint32_t)b->face_start.count - 1;
    obj__ring ring;
    memset(&ring, 0, sizeof ring);
    for (f = 0; f < face_count; f++) {
        uint32_t n = start[f + 1] - start[f], k;
        if (!obj__ring_reserve(&ring, n)) return -1;
        obj__triangulate(&ring, pos, fv + start[f], n, out->tri_indices + 3 * (size_t)tri);
        for (k = 0; k + 2 < n; k++, tri++) {
            out->tri_material[tri] = material[f];
            out->tri_face[tri] = f;
        }
    }
    out->tri_count = tri;
    obj__ring_free(&ring);
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

/* ---- coincident faces -------------------------------------------------
   Two triangles of different faces coincide when each one's corners lie
   within OBJ_COINCIDENT_TOLERANCE of the other's plane, they face the same
   way and their overlap in that plane has an area. Candidates come from a
   sort by plane offset (from the scene's centre) and, within a run of equal
   offsets, a sweep along the scene's longest axis; the overlap is the
   convex clip of one triangle by the other, in 2D on the dominant plane.
   Back-to-back faces (a wall's two sides in one plane) face opposite ways
   and are no coincidence. */

/* Relative to the scene's bounding-box diagonal: the examples' tracers
   offset their rays by 1e-5 of it, so surfaces closer than that are told
   apart by chance. */
#define OBJ_COINCIDENT_TOLERANCE 1e-5
/* An overlap counts when larger than this share of the smaller triangle:
   neighbours that share an edge overlap by rounding, 1e-7 of their area. */
#define OBJ__OVERLAP_MIN 1e-5
#define OBJ__CLIP_MAX 16       /* corners of a clipped piece: 3 + one per cut */
#define OBJ__PIECES_MAX 64     /* pieces of a triangle left uncovered, before giving up */

typedef struct obj__plane_tri {
    double n[3], d, area;      /* unit normal, offset from the centre, area */
    float lo[3], hi[3];
    float key;                 /* lo along the sweep axis */
    uint32_t tri;
} obj__plane_tri;

typedef struct obj__pair { uint32_t lower, upper; double area; } obj__pair;  /* triangles, lower's face < upper's; first */

typedef struct obj__poly2 { double x[OBJ__CLIP_MAX], y[OBJ__CLIP_MAX]; int n; } obj__poly2;

static int obj__cmp_plane(const void *a, const void *b)
{
    double x = ((const obj__plane_tri *)a)->d, y = ((const obj__plane_tri *)b)->d;
    return x < y ? -1 : x > y;
}

static int obj__cmp_sweep(const void *a, const void *b)
{
    float x = ((const obj__plane_tri *)a)->key, y = ((const obj__plane_tri *)b)->key;
    return x < y ? -1 : x > y;
}

/* Pairs of uint32_t: by first, then second. */
static int obj__cmp_pair(const void *a, const void *b)
{
    const uint32_t *p = (const uint32_t *)a, *q = (const uint32_t *)b;
    if (p[0] != q[0]) return p[0] < q[0] ? -1 : 1;
    return p[1] < q[1] ? -1 : p[1] > q[1];
}

static double obj__poly2_area(const obj__poly2 *p)
{
    double a = 0.0;
    int i;
    for (i = 0; i < p->n; i++) {
        int j = (i + 1) % p->n;
        a += p->x[i] * p->y[j] - p->x[j] * p->y[i];
    }
    return 0.5 * a;
}

/* The part of convex p on the left of a -> b (keep = 1) or on its right
   (keep = 0): one Sutherland-Hodgman step. */
static void obj__clip(const obj__poly2 *p, double ax, double ay, double bx, double by, int keep, obj__poly2 *out)
{
    int i;
    out->n = 0;
    for (i = 0; i < p->n; i++) {
        int j = (i + 1) % p->n;
        double si = (bx - ax) * (p->y[i] - ay) - (by - ay) * (p->x[i] - ax);
        double sj = (bx - ax) * (p->y[j] - ay) - (by - ay) * (p->x[j] - ax);
        if (!keep) { si = -si; sj = -sj; }
        if (si >= 0.0 && out->n < OBJ__CLIP_MAX) { out->x[out->n] = p->x[i]; out->y[out->n] = p->y[i]; out->n++; }
        if (((si >= 0.0) != (sj >= 0.0)) && out->n < OBJ__CLIP_MAX) {
            double t = si / (si - sj);
            out->x[out->n] = p->x[i] + t * (p->x[j] - p->x[i]);
            out->y[out->n] = p->y[i] + t * (p->y[j] - p->y[i]);
            out->n++;
        }
    }
}

/* Triangle tri projected along the axis of normal n, counter-clockwise
   seen from n's side. Returns the factor from projected to true area. */
static double obj__project_tri(const obj_scene *s, uint32_t tri, const double n[3], obj__poly2 *out)
{
    int axis = fabs(n[0]) > fabs(n[1]) ? (fabs(n[0]) > fabs(n[2]) ? 0 : 2) : (fabs(n[1]) > fabs(n[2]) ? 1 : 2);
    int u = (axis + 1) % 3, w = (axis + 2) % 3, k;
    if (n[axis] < 0.0) { int t = u; u = w; w = t; }
    for (k = 0; k < 3; k++) {
        const float *p = s->positions + 3 * (size_t)s->tri_indices[3 * (size_t)tri + (size_t)k];
        out->x[k] = p[u];
        out->y[k] = p[w];
    }
    out->n = 3;
    return 1.0 / fabs(n[axis]);
}

/* Area of the overlap of triangles a and b (coplanar, same facing). */
static double obj__overlap(const obj_scene *s, const obj__plane_tri *a, const obj__plane_tri *b)
{
    obj__poly2 pa, pb, t;
    double scale = obj__project_tri(s, a->tri, a->n, &pa);
    int k;
    obj__project_tri(s, b->tri, a->n, &pb);
    for (k = 0; k < 3 && pb.n >= 3; k++) {
        obj__clip(&pb, pa.x[k], pa.y[k], pa.x[(k + 1) % 3], pa.y[(k + 1) % 3], 1, &t);
        pb = t;
    }
    return pb.n >= 3 ? scale * obj__poly2_area(&pb) : 0.0;
}

static double obj__plane_distance(const obj__plane_tri *a, const float *p, const double centre[3])
{
    return a->n[0] * (p[0] - centre[0]) + a->n[1] * (p[1] - centre[1]) + a->n[2] * (p[2] - centre[2]) - a->d;
}

/* Whether b's corners lie within tol of a's plane. */
static int obj__near_plane(const obj_scene *s, const obj__plane_tri *a, const obj__plane_tri *b, const double centre[3],
                           double tol)
{
    int k;
    for (k = 0; k < 3; k++)
        if (fabs(obj__plane_distance(a, s->positions + 3 * (size_t)s->tri_indices[3 * (size_t)b->tri + (size_t)k], centre)) > tol)
            return 0;
    return 1;
}

/* The plane (offset from centre), area and bounds of triangle tri; false
   when it has no area. */
static int obj__plane_tri_at(const obj_scene *s, uint32_t tri, const double centre[3], obj__plane_tri *out)
{
    const float *a = s->positions + 3 * (size_t)s->tri_indices[3 * (size_t)tri];
    const float *b = s->positions + 3 * (size_t)s->tri_indices[3 * (size_t)tri + 1];
    const float *c = s->positions + 3 * (size_t)s->tri_indices[3 * (size_t)tri + 2];
    double e[3], f[3], x[3], len;
    int k;
    for (k = 0; k < 3; k++) { e[k] = (double)b[k] - a[k]; f[k] = (double)c[k] - a[k]; }
    x[0] = e[1] * f[2] - e[2] * f[1];
    x[1] = e[2] * f[0] - e[0] * f[2];
    x[2] = e[0] * f[1] - e[1] * f[0];
    len = sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]);
    if (!(len > 0.0)) return 0;
    for (k = 0; k < 3; k++) {
        out->n[k] = x[k] / len;
        out->lo[k] = a[k] < b[k] ? (a[k] < c[k] ? a[k] : c[k]) : (b[k] < c[k] ? b[k] : c[k]);
        out->hi[k] = a[k] > b[k] ? (a[k] > c[k] ? a[k] : c[k]) : (b[k] > c[k] ? b[k] : c[k]);
    }
    out->area = 0.5 * len;
    out->d = 0.0;
    out->d = obj__plane_distance(out, a, centre);   /* with d = 0: n . (a - centre) */
    out->key = 0.0f;
    out->tri = tri;
    return 1;
}

/* Every triangle with an area; returns how many. */
static uint32_t obj__plane_tris(const obj_scene *s, const double centre[3], obj__plane_tri *out)
{
    uint32_t i, n = 0;
    for (i = 0; i < s->tri_count; i++) n += obj__plane_tri_at(s, i, centre, &out[n]);
    return n;
}

/* Tests a and b (of different faces) and records a coincidence. */
static int obj__test_pair(const obj_scene *s, const obj__plane_tri *a, const obj__plane_tri *b, const double centre[3],
                          double tol, obj__array *pairs)
{
    obj__pair pair;
    uint32_t fa = s->tri_face[a->tri], fb = s->tri_face[b->tri];
    int k;
    if (fa == fb || a->n[0] * b->n[0] + a->n[1] * b->n[1] + a->n[2] * b->n[2] <= 0.0) return 0;
    for (k = 0; k < 3; k++)
        if (a->lo[k] > b->hi[k] + tol || b->lo[k] > a->hi[k] + tol) return 0;
    if (!obj__near_plane(s, a, b, centre, tol) || !obj__near_plane(s, b, a, centre, tol)) return 0;
    pair.area = obj__overlap(s, a, b);
    if (!(pair.area > OBJ__OVERLAP_MIN * (a->area < b->area ? a->area : b->area))) return 0;
    pair.lower = fa < fb ? a->tri : b->tri;
    pair.upper = fa < fb ? b->tri : a->tri;
    return obj__push(pairs, &pair) ? 0 : -1;
}

/* Bounds of the vertices of triangles; false when there are none. */
static int obj__tri_bounds(const obj_scene *s, double lo[3], double hi[3])
{
    uint32_t i;
    int k;
    if (!s->tri_count) return 0;
    for (k = 0; k < 3; k++) { lo[k] = DBL_MAX; hi[k] = -DBL_MAX; }
    for (i = 0; i < 3 * s->tri_count; i++)
        for (k = 0; k < 3; k++) {
            double x = s->positions[3 * (size_t)s->tri_indices[i] + (size_t)k];
            if (x < lo[k]) lo[k] = x;
            if (x > hi[k]) hi[k] = x;
        }
    return 1;
}

/* Every coincident pair of triangles, sorted by lower triangle. Returns 0,
   or -1 when out of memory. */
static int obj__coincident_pairs(const obj_scene *s, obj__array *pairs)
{
    double lo[3], hi[3], centre[3], diag = 0.0, tol;
    obj__plane_tri *pt;
    uint32_t n, i, j, run_end;
    int k, axis = 0;
    memset(pairs, 0, sizeof *pairs);
    pairs->item = sizeof(obj__pair);
    if (s->tri_count < 2 || !obj__tri_bounds(s, lo, hi)) return 0;
    for (k = 0; k < 3; k++) {
        centre[k] = 0.5 * (lo[k] + hi[k]);
        diag += (hi[k] - lo[k]) * (hi[k] - lo[k]);
        if (hi[k] - lo[k] > hi[axis] - lo[axis]) axis = k;
    }
    tol = OBJ_COINCIDENT_TOLERANCE * sqrt(diag);
    pt = (obj__plane_tri *)malloc(sizeof *pt * s->tri_count);
    if (!pt) return -1;
    n = obj__plane_tris(s, centre, pt);
    qsort(pt, n, sizeof *pt, obj__cmp_plane);
    for (i = 0; i < n; i = run_end) {
        /* a run of offsets each within 2 tol of the previous one, swept
           along the longest axis */
        for (run_end = i + 1; run_end < n && pt[run_end].d - pt[run_end - 1].d <= 2.0 * tol; run_end++) {}
        for (j = i; j < run_end; j++) pt[j].key = pt[j].lo[axis];
        qsort(pt + i, run_end - i, sizeof *pt, obj__cmp_sweep);
        for (j = i; j < run_end; j++) {
            uint32_t m;
            for (m = j + 1; m < run_end && pt[m].lo[axis] <= pt[j].hi[axis] + tol; m++)
                if (obj__test_pair(s, &pt[j], &pt[m], centre, tol, pairs) != 0) { free(pt); free(pairs->data); return -1; }
        }
    }
    free(pt);
    if (pairs->count > 1) qsort(pairs->data, pairs->count, sizeof(obj__pair), obj__cmp_pair);
    return 0;
}

/* Counts the coincident pairs of faces and their overlap into the scene. */
static int obj__report_coincident(obj_scene *s)
{
    obj__array pairs;
    unsigned char *in_pair;
    uint32_t *faces;
    size_t i;
    if (obj__coincident_pairs(s, &pairs) != 0) return -1;
    s->coincident_pairs = s->coincident_faces = 0;
    s->coincident_area = 0.0;
    in_pair = (unsigned char *)calloc(s->face_count + 1, 1);
    faces = (uint32_t *)malloc(sizeof(uint32_t) * 2 * (pairs.count + 1));
    if (!in_pair || !faces) { free(in_pair); free(faces); free(pairs.data); return -1; }
    for (i = 0; i < pairs.count; i++) {
        const obj__pair *p = (const obj__pair *)pairs.data + i;
        faces[2 * i] = s->tri_face[p->lower];
        faces[2 * i + 1] = s->tri_face[p->upper];
        in_pair[faces[2 * i]] = in_pair[faces[2 * i + 1]] = 1;
        s->coincident_area += p->area;
    }
    qsort(faces, pairs.count, 2 * sizeof(uint32_t), obj__cmp_pair);
    for (i = 0; i < pairs.count; i++)
        s->coincident_pairs += i == 0 || faces[2 * i] != faces[2 * i - 2] || faces[2 * i + 1] != faces[2 * i - 1];
    for (i = 0; i < s->face_count; i++) s->coincident_faces += in_pair[i];
    free(in_pair);
    free(faces);
    free(pairs.data);
    return 0;
}

/* Whether triangle lower is covered by the union of the upper triangles of
   pairs[0..count): what is left of it after cutting each one away (convex
   pieces: outside each edge of an upper triangle in turn) is under
   OBJ__OVERLAP_MIN of its area. */
static int obj__covered(const obj_scene *s, uint32_t lower, const obj__pair *pairs, size_t count)
{
    obj__poly2 pieces[OBJ__PIECES_MAX], next[OBJ__PIECES_MAX], b, rest, out;
    obj__plane_tri pl;
    double scale, left = 0.0;
    int np = 1, nn, i, k;
    size_t c;
    static const double origin[3] = { 0.0, 0.0, 0.0 };
    if (!obj__plane_tri_at(s, lower, origin, &pl)) return 1;   /* no area: nothing to see */
    scale = obj__project_tri(s, lower, pl.n, &pieces[0]);
    for (c = 0; c < count; c++) {
        obj__project_tri(s, pairs[c].upper, pl.n, &b);
        for (i = 0, nn = 0; i < np; i++) {
            rest = pieces[i];
            for (k = 0; k < 3 && rest.n >= 3; k++) {
                obj__clip(&rest, b.x[k], b.y[k], b.x[(k + 1) % 3], b.y[(k + 1) % 3], 0, &out);
                if (out.n >= 3 && scale * obj__poly2_area(&out) > 1e-9 * pl.area) {
                    if (nn == OBJ__PIECES_MAX) return 0;   /* too finely cut to tell: keep the face */
                    next[nn++] = out;
                }
                obj__clip(&rest, b.x[k], b.y[k], b.x[(k + 1) % 3], b.y[(k + 1) % 3], 1, &out);
                rest = out;
            }
        }
        memcpy(pieces, next, sizeof(obj__poly2) * (size_t)nn);
        np = nn;
        if (np == 0) break;
    }
    for (i = 0; i < np; i++) left += scale * obj__poly2_area(&pieces[i]);
    return left <= OBJ__OVERLAP_MIN * pl.area;
}

/* Removes the faces flagged in drop, keeping the order of the others. */
static void obj__remove_faces(obj_scene *s, const unsigned char *drop)
{
    uint32_t f, nf = 0, nv = 0, t = 0, nt = 0;
    for (f = 0; f < s->face_count; f++) {
        uint32_t a = s->face_start[f], b = s->face_start[f + 1], k, tris = b - a - 2;
        if (drop[f]) { t += tris; continue; }
        s->face_start[nf] = nv;
        for (k = a; k < b; k++) s->face_vertices[nv++] = s->face_vertices[k];
        s->face_material[nf] = s->face_material[f];
        s->face_group[nf] = s->face_group[f];
        for (k = 0; k < tris; k++, t++, nt++) {
            memmove(s->tri_indices + 3 * (size_t)nt, s->tri_indices + 3 * (size_t)t, 3 * sizeof(uint32_t));
            s->tri_material[nt] = s->tri_material[t];
            s->tri_face[nt] = nf;
        }
        nf++;
    }
    s->face_start[nf] = nv;
    s->face_count = nf;
    s->tri_count = nt;
}
/* Triangulates the faces and moves the arrays into out. */
static int obj__finish(obj__parser *p, obj__build *b, obj_scene *out)
{
    uint32_t face_count = (uint32_t)b->face_start.count;
    uint32_t end = (uint32_t)b->face_vertices.count;
    size_t tri_count = b->face_vertices.count - 2 * (size_t)face_count;
    if (!obj__push(&b->face_start, &end)) return obj__fail(p, "out of memory");
    memset(out, 0, sizeof *out);
    out->tri_indices = (uint32_t *)malloc(sizeof(uint32_t) * 3 * (tri_count ? tri_count : 1));
    out->tri_material = (uint32_t *)malloc(sizeof(uint32_t) * (tri_count ? tri_count : 1));
    out->tri_face = (uint32_t *)malloc(sizeof(uint32_t) * (tri_count ? tri_count : 1));
    if (!out->tri_indices || !out->tri_material || !out->tri_face || obj__triangulate_faces(b, out) != 0) {
        free(out->tri_indices); free(out->tri_material); free(out->tri_face);
        memset(out, 0, sizeof *out);
        return obj__fail(p, "out of memory");
    }
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
    if (obj__report_coincident(out) != 0) {
        obj_free(out);
        return obj__fail(p, "out of memory");
    }
    return 0;
}

/* Parses OBJ text held in memory. base_dir (ending in '/', or NULL) locates
   mtllib files. name is used in messages. */
EX_FN int obj_parse(const char *text, size_t len, const char *name, const char *base_dir,
                    obj_scene *out, char *err, size_t err_size)
{
    obj__build b;
    obj__parser p;
    int r;
    obj__build_init(&b);
    obj__parser_init(&p, name, err, err_size);
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

/* Drops every face whose triangles are all covered by coincident
   triangles of faces with a higher index (see "Coincident faces"), keeping
   the others in order, and counts again what is left. Returns the number of
   faces dropped, or -1 when out of memory (the scene unchanged). */
EX_FN int obj_drop_coincident(obj_scene *s)
{
    obj__array pairs;
    unsigned char *drop, *covered;
    const obj__pair *pr;
    uint32_t f, t, dropped = 0;
    size_t i = 0;
    if (!s || obj__coincident_pairs(s, &pairs) != 0) return -1;
    pr = (const obj__pair *)pairs.data;
    drop = (unsigned char *)malloc(s->face_count + 1);
    covered = (unsigned char *)malloc(s->tri_count + 1);
    if (!drop || !covered) { free(drop); free(covered); free(pairs.data); return -1; }
    for (t = 0; t < s->tri_count; t++) {
        size_t first = i;
        while (i < pairs.count && pr[i].lower == t) i++;
        /* no pairs: pr may be NULL, and NULL + 0 is undefined */
        covered[t] = (unsigned char)obj__covered(s, t, i > first ? pr + first : NULL, i - first);
    }
    for (f = 0, t = 0; f < s->face_count; f++) {
        uint32_t end = t + (s->face_start[f + 1] - s->face_start[f] - 2);
        drop[f] = 1;
        for (; t < end; t++) drop[f] &= covered[t];
        dropped += drop[f];
    }
    if (dropped) obj__remove_faces(s, drop);
    free(drop);
    free(covered);
    free(pairs.data);
    if (dropped && obj__report_coincident(s) != 0) return -1;
    return (int)dropped;
}

/* ---- writing ------------------------------------------------------------ */

/* The names given so far (names[0..count), and names[count] = the parser's
   "default", which no written name may take), hashed, each with the last
   suffix given to a name made from it: naming n equal names costs O(n)
   hash probes, where comparing each with all before it, suffix by suffix,
   cost O(n^3) (a file of 5,000 unnamed groups took minutes). */
typedef struct {
    char (*names)[OBJ_NAME_MAX];
    uint32_t *slot;          /* 1 + index into names, 0 when empty */
    uint32_t *last_suffix;   /* per name */
    uint32_t mask;
} obj__name_set;

static uint32_t obj__name_hash(const char *s)
{
    uint32_t h = 2166136261u;   /* FNV-1a */
    while (*s) h = (h ^ (unsigned char)*s++) * 16777619u;
    return h;
}

/* The index of name in t, or UINT32_MAX; *at is its slot or where it goes. */
static uint32_t obj__name_find(const obj__name_set *t, const char *name, uint32_t *at)
{
    uint32_t i = obj__name_hash(name) & t->mask;
    while (t->slot[i] && strcmp(t->names[t->slot[i] - 1], name) != 0) i = (i + 1) & t->mask;
    *at = i;
    return t->slot[i] ? t->slot[i] - 1 : UINT32_MAX;
}

/* Room for count names (names has count + 1 entries); 0, or -1 out of memory. */
static int obj__name_set_init(obj__name_set *t, char (*names)[OBJ_NAME_MAX], uint32_t count)
{
    uint32_t size = 4, at;
    while (size < 2 * ((uint64_t)count + 1)) size *= 2;
    t->names = names;
    t->mask = size - 1;
    t->slot = (uint32_t *)calloc(size, sizeof *t->slot);
    t->last_suffix = (uint32_t *)calloc((size_t)count + 1, sizeof *t->last_suffix);
    if (!t->slot || !t->last_suffix) return -1;
    snprintf(names[count], OBJ_NAME_MAX, "default");
    obj__name_find(t, names[count], &at);
    t->slot[at] = count + 1;
    return 0;
}

static void obj__name_set_free(obj__name_set *t)
{
    free(t->slot);
    free(t->last_suffix);
}

/* names[i] = name as an OBJ/MTL token (whitespace and controls become '_'),
   different from the names given before it and from "default". */
static void obj__unique_name(obj__name_set *t, const char *name, uint32_t i)
{
    char base[OBJ_NAME_MAX];
    uint32_t at, owner, suffix;
    size_t k;
    snprintf(base, sizeof base, "%.50s", name[0] ? name : "unnamed");
    for (k = 0; base[k]; k++)
        if ((unsigned char)base[k] <= ' ' || base[k] == 127) base[k] = '_';
    owner = obj__name_find(t, base, &at);
    if (owner == UINT32_MAX) {
        memcpy(t->names[i], base, sizeof base);
    } else {
        suffix = t->last_suffix[owner];
        do snprintf(t->names[i], OBJ_NAME_MAX, "%.50s_%u", base, ++suffix);
        while (obj__name_find(t, t->names[i], &at) != UINT32_MAX);
        t->last_suffix[owner] = suffix;
    }
    t->slot[at] = i + 1;
}

/* Writes the materials as MTL that obj__parse_mtl reads back to the same
   values: a material that passes light as glass (Tf under illum 4, its Kd
   divided by what glass keeps of it). */
static int obj__write_mtl(FILE *f, const obj_scene *s, char (*names)[OBJ_NAME_MAX])
{
    uint32_t m;
    int k;
    fprintf(f, "# written by examples/common/obj.h\n");
    for (m = 0; m < s->material_count; m++) {
        const obj_material *mt = &s->materials[m];
        float kd[3];
        int glass = mt->tf[0] > 0 || mt->tf[1] > 0 || mt->tf[2] > 0;
        for (k = 0; k < 3; k++) kd[k] = glass ? (mt->tf[k] < 1.0f ? mt->kd[k] / (1.0f - mt->tf[k]) : 0.0f) : mt->kd[k];
        fprintf(f, "newmtl %s\nKd %.9g %.9g %.9g\nKs %.9g %.9g %.9g\nNs %.9g\nKe %.9g %.9g %.9g\n", names[m], kd[0], kd[1],
                kd[2], mt->ks[0], mt->ks[1], mt->ks[2], mt->ns, mt->ke[0], mt->ke[1], mt->ke[2]);
        if (glass) fprintf(f, "Tf %.9g %.9g %.9g\nillum 4\n", mt->tf[0], mt->tf[1], mt->tf[2]);
    }
    return ferror(f) ? -1 : 0;
}

/* Whether face f is written as it is: 3 corners, or 4 strictly convex. */
static int obj__face_as_is(const obj_scene *s, uint32_t f, obj__ring *ring)
{
    uint32_t n = s->face_start[f + 1] - s->face_start[f];
    if (n == 3) return 1;
    if (n != 4) return 0;
    obj__project(ring, s->positions, s->face_vertices + s->face_start[f], 4);
    return obj__convex(ring, 4);
}

static int obj__write_obj(FILE *f, const obj_scene *s, const char *mtl_name, char (*mat_names)[OBJ_NAME_MAX],
                          char (*group_names)[OBJ_NAME_MAX])
{
    obj__ring ring;
    uint32_t v, fc, t = 0, material = UINT32_MAX, group = UINT32_MAX, k;
    memset(&ring, 0, sizeof ring);
    if (!obj__ring_reserve(&ring, 4)) return -1;
    fprintf(f, "# written by examples/common/obj.h: faces of 3 corners or convex 4, the others as triangles\n");
    fprintf(f, "mtllib %s\n", mtl_name);
    for (v = 0; v < s->vertex_count; v++)
        fprintf(f, "v %.9g %.9g %.9g\n", s->positions[3 * (size_t)v], s->positions[3 * (size_t)v + 1], s->positions[3 * (size_t)v + 2]);
    for (fc = 0; fc < s->face_count; fc++) {
        uint32_t a = s->face_start[fc], n = s->face_start[fc + 1] - a;
        if (s->face_group[fc] != group) fprintf(f, "g %s\n", group_names[group = s->face_group[fc]]);
        if (s->face_material[fc] != material) fprintf(f, "usemtl %s\n", mat_names[material = s->face_material[fc]]);
        if (obj__face_as_is(s, fc, &ring)) {
            fputc('f', f);
            for (k = 0; k < n; k++) fprintf(f, " %u", s->face_vertices[a + k] + 1);
            fputc('\n', f);
        } else {
            for (k = 0; k + 2 < n; k++, t++)   /* the face's triangles: they come in face order */
                fprintf(f, "f %u %u %u\n", s->tri_indices[3 * (size_t)t] + 1, s->tri_indices[3 * (size_t)t + 1] + 1,
                        s->tri_indices[3 * (size_t)t + 2] + 1);
            continue;
        }
        t += n - 2;
    }
    obj__ring_free(&ring);
    return ferror(f) ? -1 : 0;
}

/* Writes s as an OBJ file at obj_path (ending in ".obj") and its materials
   beside it (the same name ending in ".mtl"), so that obj_load reads back
   the same positions, triangles, groups' and materials' values (names made
   unique OBJ tokens). Faces of 3 corners and strictly convex faces of 4 are
   written as they are; every other face as its triangles, so every face of
   the file is a convex patch of 3 or 4 corners (what radinterp takes).
   Returns 0, or -1 with a message. */
EX_FN int obj_write(const obj_scene *s, const char *obj_path, char *err, size_t err_size)
{
    char mtl_path[1024], (*mat_names)[OBJ_NAME_MAX], (*group_names)[OBJ_NAME_MAX];
    const char *base;
    size_t n = obj_path ? strlen(obj_path) : 0;
    FILE *fo = NULL, *fm = NULL;
    obj__name_set mat_set = {NULL, NULL, NULL, 0}, group_set = {NULL, NULL, NULL, 0};
    uint32_t i;
    int r = -1, named;
    if (!s || n < 5 || strcmp(obj_path + n - 4, ".obj") != 0 || n >= sizeof mtl_path) {
        if (err && err_size) snprintf(err, err_size, "obj_write: the path must end in .obj");
        return -1;
    }
    memcpy(mtl_path, obj_path, n - 3);
    memcpy(mtl_path + n - 3, "mtl", 4);
    base = strrchr(mtl_path, '/') ? strrchr(mtl_path, '/') + 1 : mtl_path;
    mat_names = (char (*)[OBJ_NAME_MAX])malloc(OBJ_NAME_MAX * ((size_t)s->material_count + 1));
    group_names = (char (*)[OBJ_NAME_MAX])malloc(OBJ_NAME_MAX * ((size_t)s->group_count + 1));
    named = mat_names && group_names && obj__name_set_init(&mat_set, mat_names, s->material_count) == 0 &&
            obj__name_set_init(&group_set, group_names, s->group_count) == 0;
    if (named) {
        for (i = 0; i < s->material_count; i++) obj__unique_name(&mat_set, s->materials[i].name, i);
        for (i = 0; i < s->group_count; i++) obj__unique_name(&group_set, s->groups[i], i);
        fo = fopen(obj_path, "w");
        fm = fopen(mtl_path, "w");
        if (fo && fm) r = obj__write_mtl(fm, s, mat_names) | obj__write_obj(fo, s, base, mat_names, group_names);
    }
    if (fo && fclose(fo) != 0) r = -1;
    if (fm && fclose(fm) != 0) r = -1;
    if (r != 0 && err && err_size) snprintf(err, err_size, "%s: cannot write (%s)", obj_path, named ? strerror(errno) : "out of memory");
    obj__name_set_free(&mat_set);
    obj__name_set_free(&group_set);
    free(mat_names);
    free(group_names);
    return r;
}

/* Determinant of a 3x3 row-major matrix: negative for a mirror. */
static double obj__det3(const float m[9])
{
    return (double)m[0] * ((double)m[4] * m[8] - (double)m[5] * m[7]) -
           (double)m[1] * ((double)m[3] * m[8] - (double)m[5] * m[6]) +
           (double)m[2] * ((double)m[3] * m[7] - (double)m[4] * m[6]);
}

/* Maps every position p to m p (m 3x3, row-major): a change of axes or of
   units. A mirroring map (negative determinant) also reverses every face
   and triangle, so that fronts stay fronts. The coincidence report is
   counted again. Returns 0, or -1 when out of memory (positions already
   mapped, report left as it was). */
EX_FN int obj_transform(obj_scene *s, const float m[9])
{
    double det = obj__det3(m);
    uint32_t i, f;
    for (i = 0; i < s->vertex_count; i++) {
        float *p = s->positions + 3 * (size_t)i, q[3];
        int r;
        for (r = 0; r < 3; r++) q[r] = m[3 * r] * p[0] + m[3 * r + 1] * p[1] + m[3 * r + 2] * p[2];
        memcpy(p, q, sizeof q);
    }
    if (det < 0.0) {
        for (f = 0; f < s->face_count; f++) {
            uint32_t a = s->face_start[f], b = s->face_start[f + 1] - 1;
            for (; a < b; a++, b--) { uint32_t t = s->face_vertices[a]; s->face_vertices[a] = s->face_vertices[b]; s->face_vertices[b] = t; }
        }
        for (i = 0; i < s->tri_count; i++) {
            uint32_t t = s->tri_indices[3 * (size_t)i + 1];
            s->tri_indices[3 * (size_t)i + 1] = s->tri_indices[3 * (size_t)i + 2];
            s->tri_indices[3 * (size_t)i + 2] = t;
        }
    }
    return obj__report_coincident(s);
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
