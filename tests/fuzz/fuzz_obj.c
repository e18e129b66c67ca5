/* Fuzz target of the examples' OBJ + MTL parser, examples/common/obj.h (see
   tests/fuzz/fuzz.h). An input is OBJ text, optionally followed by a zero
   byte and the text of a material library: that part is written to the file
   m.mtl in a directory of this process, which the OBJ text's `mtllib m.mtl`
   finds (the seeds say so; a mutated name reaches the parser's "cannot read"
   path). A scene that parses must be consistent (every triangle's corners
   are vertices, every face's material and group exist, a face of n corners
   gives its n - 2 triangles in face order, transmittances lie in [0, 1]);
   its bounds and vertex normals compute without a sanitizer report; obj_write
   writes files that parse back to the same positions, triangles and
   material values; and the scene stays consistent through a mirroring
   obj_transform and obj_drop_coincident. */
#if !defined(_POSIX_C_SOURCE) || _POSIX_C_SOURCE < 200809L
#  undef _POSIX_C_SOURCE
#  define _POSIX_C_SOURCE 200809L   /* mkdtemp */
#endif
#include <unistd.h>
#include "examples/common/obj.h"
#include "tests/fuzz/fuzz.h"

/* The directory holding m.mtl, made once per process and removed at exit. */
static char mtl_dir[64];
static char mtl_path[96];
static uint8_t *mtl_written;   /* what m.mtl holds, so that an unchanged library is not written again */
static size_t mtl_written_size;

static void remove_mtl_dir(void)
{
    unlink(mtl_path);
    rmdir(mtl_dir);
    free(mtl_written);
}

static int make_mtl_dir(void)
{
    const char *tmp = getenv("TMPDIR");
    if (mtl_dir[0]) return 1;
    snprintf(mtl_dir, sizeof mtl_dir, "%s/fuzz_obj.XXXXXX", tmp && strlen(tmp) < 40 ? tmp : "/tmp");
    if (!mkdtemp(mtl_dir)) {
        mtl_dir[0] = 0;
        return 0;
    }
    snprintf(mtl_path, sizeof mtl_path, "%s/m.mtl", mtl_dir);
    atexit(remove_mtl_dir);
    return 1;
}

/* Writes the library unless m.mtl already holds these bytes. */
static int write_mtl(const uint8_t *text, size_t size)
{
    FILE *f;
    uint8_t *copy;
    if (mtl_written && fuzz_same_bytes(mtl_written, mtl_written_size, text, size)) return 1;
    f = fopen(mtl_path, "wb");
    if (!f) return 0;
    if (size && fwrite(text, 1, size, f) != size) {
        fclose(f);
        return 0;
    }
    if (fclose(f) != 0) return 0;
    copy = (uint8_t *)malloc(size + 1);
    free(mtl_written);
    mtl_written = copy;
    mtl_written_size = copy ? size : 0;
    if (copy && size) memcpy(copy, text, size);
    return 1;
}

static void check_scene(const obj_scene *s)
{
    uint32_t f, t = 0, i;
    float lo[3], hi[3], *normals;
    for (f = 0; f < s->face_count; f++) {
        uint32_t n = s->face_start[f + 1] - s->face_start[f], end;
        fuzz_require(s->face_start[f] < s->face_start[f + 1] && n >= 3, "a face with fewer than 3 corners");
        fuzz_require(s->face_material[f] < s->material_count && s->face_group[f] < s->group_count,
                     "a face's material or group does not exist");
        for (i = s->face_start[f]; i < s->face_start[f + 1]; i++)
            fuzz_require(s->face_vertices[i] < s->vertex_count, "a face's corner is not a vertex");
        for (end = t + n - 2; t < end; t++)
            fuzz_require(t < s->tri_count && s->tri_face[t] == f && s->tri_material[t] == s->face_material[f],
                         "a face's n - 2 triangles are not next in face order");
    }
    fuzz_require(t == s->tri_count, "triangles of no face");
    for (t = 0; t < 3 * s->tri_count; t++)
        fuzz_require(s->tri_indices[t] < s->vertex_count, "a triangle's corner is not a vertex");
    for (i = 0; i < s->material_count; i++) {
        const obj_material *m = &s->materials[i];
        fuzz_require(memchr(m->name, 0, OBJ_NAME_MAX) != NULL, "a material name without its end");
        fuzz_require(m->tf[0] >= 0 && m->tf[0] <= 1 && m->tf[1] >= 0 && m->tf[1] <= 1 && m->tf[2] >= 0 && m->tf[2] <= 1,
                     "a transmittance outside [0, 1]");
    }
    for (i = 0; i < s->group_count; i++)
        fuzz_require(memchr(s->groups[i], 0, OBJ_NAME_MAX) != NULL, "a group name without its end");
    fuzz_require(obj_bounds(s, lo, hi) == (s->vertex_count > 0), "obj_bounds");
    normals = (float *)malloc(3 * sizeof(float) * ((size_t)s->vertex_count + 1));
    if (normals) {
        obj_vertex_normals(s, normals);
        free(normals);
    }
}

/* Whether two materials have the same values: exactly, except the diffuse
   reflectance of glass, which the file holds divided by 1 - tf (a rounding
   each way, so within 4 float steps). */
static int same_material(const obj_material *a, const obj_material *b)
{
    int k, same = a->ns == b->ns;
    for (k = 0; k < 3; k++) {
        float tol = a->tf[k] > 0.0f ? 4.0f * FLT_EPSILON * a->kd[k] : 0.0f;
        same &= a->ks[k] == b->ks[k] && a->ke[k] == b->ke[k] && a->tf[k] == b->tf[k] && fabsf(a->kd[k] - b->kd[k]) <= tol;
    }
    return same;
}

/* obj_write, then obj_load of what it wrote: the same positions, triangles
   and materials' values (names are made unique tokens, faces may come back
   as their triangles). */
static void check_written_scene(const obj_scene *s)
{
    char path[128], err[256];
    obj_scene back;
    uint32_t t;
    snprintf(path, sizeof path, "%s/written.obj", mtl_dir);
    fuzz_require(obj_write(s, path, err, sizeof err) == 0, "obj_write failed");
    fuzz_require(obj_load(path, &back, err, sizeof err) == 0, "what obj_write wrote does not load");
    fuzz_require(back.vertex_count == s->vertex_count && back.tri_count == s->tri_count,
                 "what obj_write wrote loads with other counts");
    fuzz_require(fuzz_same_bytes(back.positions, 12 * (size_t)back.vertex_count, s->positions, 12 * (size_t)s->vertex_count) &&
                     fuzz_same_bytes(back.tri_indices, 12 * (size_t)back.tri_count, s->tri_indices, 12 * (size_t)s->tri_count),
                 "what obj_write wrote loads with other positions or triangles");
    for (t = 0; t < s->tri_count; t++)
        fuzz_require(same_material(&s->materials[s->tri_material[t]], &back.materials[back.tri_material[t]]),
                     "what obj_write wrote loads with other material values");
    obj_free(&back);
    snprintf(path, sizeof path, "%s/written.obj", mtl_dir);
    unlink(path);
    snprintf(path, sizeof path, "%s/written.mtl", mtl_dir);
    unlink(path);
}

/* A mirror (x and z swapped, so faces turn) and the removal of covered
   coincident faces keep the scene consistent. */
static void check_transform_and_drop(obj_scene *s)
{
    static const float mirror[9] = { 0, 0, 1, 0, 1, 0, 1, 0, 0 };
    if (obj_transform(s, mirror) != 0) return;   /* out of memory */
    check_scene(s);
    if (obj_drop_coincident(s) < 0) return;      /* out of memory */
    check_scene(s);
}

static fuzz_outcome parse_scene(const uint8_t *data, size_t size)
{
    const uint8_t *zero = (const uint8_t *)memchr(data, 0, size);
    size_t obj_size = zero ? (size_t)(zero - data) : size;
    char base_dir[80], err[256];
    obj_scene s;
    int r;
    if (!make_mtl_dir()) return FUZZ_OTHER;
    if (zero && !write_mtl(zero + 1, size - obj_size - 1)) return FUZZ_OTHER;
    if (!zero && mtl_written) {   /* no library: mtllib fails */
        unlink(mtl_path);
        free(mtl_written);
        mtl_written = NULL;
    }
    snprintf(base_dir, sizeof base_dir, "%s/", mtl_dir);
    r = obj_parse((const char *)data, obj_size, "fuzz.obj", base_dir, &s, err, sizeof err);
    if (r != 0) {
        fuzz_require(s.positions == NULL && s.tri_indices == NULL && s.tri_count == 0, "a failed parse left a scene");
        fuzz_require(memchr(err, 0, sizeof err) != NULL && err[0] != 0, "a failed parse gave no message");
        return FUZZ_CORRUPT;
    }
    check_scene(&s);
    check_written_scene(&s);
    check_transform_and_drop(&s);
    obj_free(&s);
    return FUZZ_LOADED;
}

const fuzz_target fuzz_this_target = { "obj", parse_scene, 0, NULL };
