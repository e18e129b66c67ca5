/* Fuzz target of the examples' OBJ + MTL parser, examples/common/obj.h (see
   tests/fuzz/fuzz.h). An input is OBJ text, optionally followed by a zero
   byte and the text of a material library: that part is written to the file
   m.mtl in a directory of this process, which the OBJ text's `mtllib m.mtl`
   finds (the seeds say so; a mutated name reaches the parser's "cannot read"
   path). A scene that parses must be consistent: every triangle's corners
   are vertices, every face's material and group exist, faces and triangles
   agree, and its bounds and vertex normals compute without a sanitizer
   report. */
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
    uint32_t f, t, i, corners = 0;
    float lo[3], hi[3], *normals;
    for (f = 0; f < s->face_count; f++) {
        uint32_t n = s->face_start[f + 1] - s->face_start[f];
        fuzz_require(s->face_start[f] < s->face_start[f + 1] && n >= 3, "a face with fewer than 3 corners");
        fuzz_require(s->face_material[f] < s->material_count && s->face_group[f] < s->group_count,
                     "a face's material or group does not exist");
        for (i = s->face_start[f]; i < s->face_start[f + 1]; i++)
            fuzz_require(s->face_vertices[i] < s->vertex_count, "a face's corner is not a vertex");
        corners += n - 2;
    }
    fuzz_require(corners == s->tri_count, "the triangles are not the faces' fans");
    for (t = 0; t < s->tri_count; t++) {
        fuzz_require(s->tri_indices[3 * t] < s->vertex_count && s->tri_indices[3 * t + 1] < s->vertex_count &&
                         s->tri_indices[3 * t + 2] < s->vertex_count,
                     "a triangle's corner is not a vertex");
        fuzz_require(s->tri_face[t] < s->face_count && s->tri_material[t] == s->face_material[s->tri_face[t]],
                     "a triangle's face or material");
    }
    for (i = 0; i < s->material_count; i++)
        fuzz_require(memchr(s->materials[i].name, 0, OBJ_NAME_MAX) != NULL, "a material name without its end");
    for (i = 0; i < s->group_count; i++)
        fuzz_require(memchr(s->groups[i], 0, OBJ_NAME_MAX) != NULL, "a group name without its end");
    fuzz_require(obj_bounds(s, lo, hi) == (s->vertex_count > 0), "obj_bounds");
    normals = (float *)malloc(3 * sizeof(float) * ((size_t)s->vertex_count + 1));
    if (normals) {
        obj_vertex_normals(s, normals);
        free(normals);
    }
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
    obj_free(&s);
    return FUZZ_LOADED;
}

const fuzz_target fuzz_this_target = { "obj", parse_scene, 0 };
