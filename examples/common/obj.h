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

   Triangulation: a face is a planar polygon without holes, of any number of
   corners, concave or not (CAD exports cut door openings into a wall's
   outline and windows as keyholes). Strictly convex faces are fanned from
   their first corner; every other face is ear-clipped in the plane of its
   dominant axis, robust to collinear and repeated corners and to slivers.
   A face of n corners always gives n - 2 triangles (tri_face names the face),
   none turned against the face, their areas adding up to the face's. A face
   whose outline crosses itself has no such triangulation: it still gives
   n - 2 triangles, cut where the outline turns most.

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

    uint32_t *tri_indices;     /* 3 per triangle: the faces' n - 2 triangles each, in face order */
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
