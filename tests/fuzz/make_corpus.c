/* make_corpus.c - writes the fuzz targets' seed corpora (tests/fuzz/corpus/)
   from the headers' own save functions, so that they follow the file formats:
   run `make fuzz-corpus` after a format changes, and commit the result.

       make_corpus [directory]     (default tests/fuzz/corpus; run from the
                                    repository root: it reads examples/data)

   For every loader, a few small real files (the Cornell box of
   examples/data and small scenes of the unit tests, saved by the library)
   and, from each, the files a loader must refuse: truncations (at the ends of
   the header's fields, inside the payload, just before and inside the
   checksum), a wrong checksum, a wrong payload size and the next format
   version. The names say what loading must give (see fuzz.h): ok-,
   corrupt-, version-. For the OBJ parser: the examples' scenes with their
   material libraries, truncations (part-: no promise, a cut at a line end
   parses) and malformed files with a known answer.

   Output is deterministic: running it twice writes the same bytes. Files the
   generator writes (ok-, corrupt-, version-, part-) are removed first, so
   seeds of a format that changed do not linger; a fuzzer's reproducers
   (crash-..., other names) are kept. */
#if !defined(_POSIX_C_SOURCE) || _POSIX_C_SOURCE < 200809L
#  undef _POSIX_C_SOURCE
#  define _POSIX_C_SOURCE 200809L   /* opendir, mkdir */
#endif
#define IRRVOL_IMPLEMENTATION
#define RADINTERP_IMPLEMENTATION
#define LIGHTVEC_IMPLEMENTATION
#define RENDERCACHE_IMPLEMENTATION
#include "irrvol.h"
#include "radinterp.h"
#include "lightvec.h"
#include "rendercache.h"
#include <dirent.h>
#include <errno.h>
#include <sys/stat.h>
#include <unistd.h>
#include "examples/common/obj.h"
#define FUZZ_NO_TARGET   /* only the checksum helpers */
#include "tests/fuzz/fuzz.h"

static const char *root = "tests/fuzz/corpus";
static int failures;

static void fail(const char *what, const char *detail)
{
    fprintf(stderr, "make_corpus: %s: %s\n", what, detail);
    failures++;
}

/* ---- files ------------------------------------------------------------------ */

static void write_file(const char *target, const char *name, const void *data, size_t size)
{
    char path[512];
    FILE *f;
    snprintf(path, sizeof path, "%s/%s/%s", root, target, name);
    f = fopen(path, "wb");
    if (!f || (size && fwrite(data, 1, size, f) != size) || fclose(f) != 0) {
        fail(path, strerror(errno));
        return;
    }
    printf("  %-12s %-40s %7lu bytes\n", target, name, (unsigned long)size);
}

static int generated_name(const char *name)
{
    return strncmp(name, "ok-", 3) == 0 || strncmp(name, "corrupt-", 8) == 0 ||
           strncmp(name, "version-", 8) == 0 || strncmp(name, "part-", 5) == 0;
}

/* Makes root/target and removes the seeds an earlier run wrote there. */
static void prepare_directory(const char *target)
{
    char path[512];
    DIR *d;
    struct dirent *e;
    mkdir(root, 0755);
    snprintf(path, sizeof path, "%s/%s", root, target);
    if (mkdir(path, 0755) != 0 && errno != EEXIST) fail(path, strerror(errno));
    d = opendir(path);
    if (!d) return;
    while ((e = readdir(d)) != NULL) {
        char file[1024];
        if (!generated_name(e->d_name)) continue;
        snprintf(file, sizeof file, "%s/%s", path, e->d_name);
        if (unlink(file) != 0) fail(file, strerror(errno));
    }
    closedir(d);
}

static uint8_t *read_whole(const char *path, size_t *size)
{
    FILE *f = fopen(path, "rb");
    uint8_t *data = NULL;
    long n;
    if (f && fseek(f, 0, SEEK_END) == 0 && (n = ftell(f)) >= 0 && fseek(f, 0, SEEK_SET) == 0) {
        data = (uint8_t *)malloc((size_t)n + 1);
        if (data && fread(data, 1, (size_t)n, f) != (size_t)n) {
            free(data);
            data = NULL;
        }
        *size = (size_t)n;
    }
    if (f) fclose(f);
    if (!data) fail(path, "cannot read");
    return data;
}

/* ---- a saved file and the files a loader must refuse ------------------------- */

static void put_le32(uint8_t *p, uint32_t v)
{
    p[0] = (uint8_t)v; p[1] = (uint8_t)(v >> 8); p[2] = (uint8_t)(v >> 16); p[3] = (uint8_t)(v >> 24);
}
static uint32_t get_le32(const uint8_t *p)
{
    return (uint32_t)p[0] | ((uint32_t)p[1] << 8) | ((uint32_t)p[2] << 16) | ((uint32_t)p[3] << 24);
}

/* Every project file starts with magic (8 bytes), format version (u32) and
   payload size (u64), and ends in a CRC-32 of everything before it. */
enum { OFFSET_VERSION = 8, OFFSET_PAYLOAD_SIZE = 12, HEADER_BYTES = 20 };

static void write_variant(const char *target, const char *prefix, const char *scene, const char *what,
                          const uint8_t *data, size_t size)
{
    char name[128];
    snprintf(name, sizeof name, "%s%s%s%s", prefix, scene, what[0] ? "-" : "", what);
    write_file(target, name, data, size);
}

static int compare_sizes(const void *a, const void *b)
{
    size_t x = *(const size_t *)a, y = *(const size_t *)b;
    return x < y ? -1 : x > y;
}

/* Truncation lengths: the ends of the header's fields, the first payload
   fields, quarters of the file, and the checksum's neighbourhood. */
static size_t truncations(size_t size, size_t *cut)
{
    size_t wanted[14], n = 0, i, k = 0;
    wanted[n++] = 0;
    wanted[n++] = 7;
    wanted[n++] = OFFSET_VERSION;
    wanted[n++] = OFFSET_PAYLOAD_SIZE;
    wanted[n++] = HEADER_BYTES - 1;
    wanted[n++] = HEADER_BYTES;
    wanted[n++] = HEADER_BYTES + 4;
    wanted[n++] = HEADER_BYTES + 16;
    wanted[n++] = size / 4;
    wanted[n++] = size / 2;
    wanted[n++] = size - size / 4;
    wanted[n++] = size - 5;
    wanted[n++] = size - 4;
    wanted[n++] = size - 1;
    qsort(wanted, n, sizeof wanted[0], compare_sizes);
    for (i = 0; i < n; i++)
        if (wanted[i] < size && (k == 0 || wanted[i] != cut[k - 1])) cut[k++] = wanted[i];
    return k;
}

static void write_seeds(const char *target, const char *scene, const void *saved, size_t size)
{
    const uint8_t *data = (const uint8_t *)saved;
    uint8_t *copy;
    size_t cut[14], n, i;
    char what[32];
    if (size < FUZZ_MIN_CHECKSUMMED) {
        fail(scene, "saved file shorter than a header and a checksum");
        return;
    }
    copy = (uint8_t *)malloc(size);
    if (!copy) {
        fail(scene, "out of memory");
        return;
    }
    write_variant(target, "ok-", scene, "", data, size);
    n = truncations(size, cut);
    for (i = 0; i < n; i++) {
        snprintf(what, sizeof what, "truncated-%lu", (unsigned long)cut[i]);
        write_variant(target, "corrupt-", scene, what, data, cut[i]);
    }
    memcpy(copy, data, size);
    copy[size - 1] ^= 0x01;
    write_variant(target, "corrupt-", scene, "checksum", copy, size);
    memcpy(copy, data, size);
    put_le32(copy + OFFSET_PAYLOAD_SIZE, get_le32(copy + OFFSET_PAYLOAD_SIZE) + 1);
    fuzz_fix_checksum(copy, size);
    write_variant(target, "corrupt-", scene, "payload-size", copy, size);
    memcpy(copy, data, size);
    put_le32(copy + OFFSET_VERSION, get_le32(copy + OFFSET_VERSION) + 1);
    fuzz_fix_checksum(copy, size);
    write_variant(target, "version-", scene, "next", copy, size);
    free(copy);
}

/* ---- the Cornell box of examples/data ----------------------------------------- */

static obj_scene cornell;

static int load_cornell(void)
{
    char err[256];
    if (obj_load("examples/data/cornell_box.obj", &cornell, err, sizeof err) != 0) {
        fail("examples/data/cornell_box.obj", err);
        return 0;
    }
    return 1;
}

static void set3(float *v, float x, float y, float z) { v[0] = x; v[1] = y; v[2] = z; }

/* ---- irrvol ------------------------------------------------------------------ */

static void save_volume(const char *scene, const irrvol_desc *d)
{
    irrvol *v = NULL;
    void *bytes = NULL;
    size_t size = 0;
    irrvol_result r = irrvol_build(d, &v);
    if (r == IRRVOL_OK) r = irrvol_save_to_memory(v, NULL, &bytes, &size);
    if (r != IRRVOL_OK) fail(scene, irrvol_result_string(r));
    else write_seeds("irrvol", scene, bytes, size);
    irrvol_free_memory(NULL, bytes);
    irrvol_destroy(v);
}

static void radiance_field(void *user, const float org[3], const float dir[3], float rgb[3])
{
    (void)user;
    rgb[0] = 1.0f + org[0];
    rgb[1] = 2.0f + org[1];
    rgb[2] = 0.5f + org[2] * dir[2];
}

static void irrvol_seeds(void)
{
    irrvol_material mats[8];
    irrvol_desc d;
    uint32_t i;
    prepare_directory("irrvol");
    /* the Cornell box lit by its own emission (radiance = Ke): 2 x 2 x 2
       samples with second-level grids where the blocks are, k = 2 */
    memset(mats, 0, sizeof mats);
    for (i = 0; i < cornell.material_count && i < 8; i++) memcpy(mats[i].radiance, cornell.materials[i].ke, 12);
    memset(&d, 0, sizeof d);
    d.positions = cornell.positions;
    d.vertex_count = cornell.vertex_count;
    d.indices = cornell.tri_indices;
    d.triangle_count = cornell.tri_count;
    d.triangle_materials = cornell.tri_material;
    d.materials = mats;
    d.material_count = cornell.material_count < 8 ? cornell.material_count : 8;
    d.grid_samples[0] = d.grid_samples[1] = d.grid_samples[2] = 2;
    d.resolution = 2;
    d.seed = 1;
    save_volume("cornell", &d);
    /* a radiance field given by a callback, kept radiance, moment 3,
       bilinear, explicit bounds: a volume of every optional part */
    memset(&d, 0, sizeof d);
    d.radiance = radiance_field;
    d.resolution = 2;
    d.moment = 3;
    d.filter = IRRVOL_FILTER_BILINEAR;
    d.keep_radiance = 1;
    d.subgrid_samples = 2;
    d.grid_samples[0] = 2; d.grid_samples[1] = 3; d.grid_samples[2] = 2;
    set3(d.bounds_min, 0, 0, 0);
    set3(d.bounds_max, 1, 1, 1);
    save_volume("field-moment", &d);
}

/* ---- radinterp ----------------------------------------------------------------- */

typedef struct patch_scene {
    float pos[3 * 64];
    uint32_t patch[4 * 16], mat[16];
    uint32_t nv, np;
    radinterp_material m[4];
} patch_scene;

/* Axis-aligned rectangle at height z, facing up (+z) or down. */
static void add_rect(patch_scene *s, float x0, float y0, float x1, float y1, float z, int up, uint32_t mat)
{
    float c[4][3];
    uint32_t k, p = s->np++;
    set3(c[0], x0, y0, z); set3(c[1], x1, y0, z); set3(c[2], x1, y1, z); set3(c[3], x0, y1, z);
    for (k = 0; k < 4; k++) {
        uint32_t corner = up ? k : (4 - k) % 4;
        memcpy(s->pos + 3 * s->nv, c[corner], 12);
        s->patch[4 * p + k] = s->nv++;
    }
    s->mat[p] = mat;
}

static void save_mesh(const char *scene, const radinterp_desc *d, const radinterp_mesh_desc *md)
{
    radinterp_solution *sol = NULL;
    radinterp_mesh *m = NULL;
    void *bytes = NULL;
    size_t size = 0;
    radinterp_result r = radinterp_solve(d, &sol);
    if (r == RADINTERP_OK) r = radinterp_build_mesh(sol, md, &m);
    if (r == RADINTERP_OK) r = radinterp_mesh_save_to_memory(m, NULL, &bytes, &size);
    if (r != RADINTERP_OK) fail(scene, radinterp_result_string(r));
    else write_seeds("radinterp", scene, bytes, size);
    radinterp_free_memory(NULL, bytes);
    radinterp_mesh_destroy(m);
    radinterp_solution_destroy(sol);
}

static void radinterp_seeds(void)
{
    patch_scene s;
    radinterp_desc d;
    radinterp_mesh_desc md;
    int k;
    prepare_directory("radinterp");
    /* a floor under a small light with a blocker between them (the unit
       tests' save/load scene): EV and VE discontinuities, active ones */
    memset(&s, 0, sizeof s);
    for (k = 0; k < 3; k++) {
        s.m[0].reflectance[k] = 0.5f;
        s.m[1].emission[k] = 100.0f;
    }
    add_rect(&s, 0, 0, 1, 1, 0, 1, 0);
    add_rect(&s, 0.4f, 0.4f, 0.6f, 0.6f, 1.0f, 0, 1);
    add_rect(&s, 0.3f, 0.45f, 0.5f, 0.65f, 0.4f, 1, 0);
    memset(&d, 0, sizeof d);
    d.positions = s.pos;
    d.vertex_count = s.nv;
    d.patches = s.patch;
    d.patch_count = s.np;
    d.patch_materials = s.mat;
    d.materials = s.m;
    d.material_count = 2;
    d.eps = 5.0f;
    memset(&md, 0, sizeof md);
    md.min_discont_weight = 1.0f;
    save_mesh("floor-blocker", &d, &md);
    /* the same scene meshed without discontinuities */
    md.no_discontinuities = 1;
    save_mesh("floor-plain", &d, &md);
}

/* ---- lightvec --------------------------------------------------------------------- */

/* A cache of one record whose view direction was given as a vector of
   length 1.25e-20 (components of 1e-20 and 3e-40, whose squares are
   subnormal floats): what insert makes of it must save, load and save to
   the same bytes (the first fuzz finding of fuzz_lightvec). */
static void save_tiny_view(lightvec_cache *gathered)
{
    lightvec_cache_desc cd;
    lightvec_cache *cache = NULL;
    lightvec_record rec;
    void *bytes = NULL;
    size_t size = 0;
    lightvec_result r = lightvec_cache_record(gathered, 0, &rec);
    memset(&cd, 0, sizeof cd);
    if (r == LIGHTVEC_OK) r = lightvec_cache_create(&cd, &cache);
    rec.flags = 0;
    set3(rec.outgoing, 1.2510025e-20f, 3.0376367e-40f, 0.0f);
    if (r == LIGHTVEC_OK) r = lightvec_insert(cache, &rec, NULL);
    if (r == LIGHTVEC_OK) r = lightvec_save_to_memory(cache, NULL, &bytes, &size);
    if (r != LIGHTVEC_OK) fail("tiny-view", lightvec_result_string(r));
    else write_file("lightvec", "ok-tiny-view", bytes, size);
    lightvec_free_memory(NULL, bytes);
    lightvec_cache_destroy(cache);
}

static void lightvec_seeds(void)
{
    lightvec_material mats[8];
    lightvec_scene_desc sd;
    lightvec_scene *scene = NULL;
    lightvec_gather_desc gd;
    lightvec_cache_desc cd;
    lightvec_result r;
    static const float points[6][6] = {   /* position, normal: floor, back wall, ceiling, side walls */
        { 0.20f, 0.0001f, 0.05f, 0, 1, 0 }, { 0.45f, 0.0001f, 0.50f, 0, 1, 0 }, { 0.30f, 0.30f, 0.5590f, 0, 0, -1 },
        { 0.10f, 0.5487f, 0.10f, 0, -1, 0 }, { 0.5500f, 0.25f, 0.30f, -1, 0, 0 }, { 0.0001f, 0.25f, 0.30f, 1, 0, 0 }
    };
    static const float tilt[3] = { 0.3f, 0.2f, -0.4f };   /* view = normalize(normal + tilt): in front */
    static const char *names[2] = { "cornell-indirect", "cornell-direct" };
    uint32_t i, kind;
    prepare_directory("lightvec");
    memset(mats, 0, sizeof mats);
    for (i = 0; i < cornell.material_count && i < 8; i++) {
        memcpy(mats[i].diffuse, cornell.materials[i].kd, 12);
        memcpy(mats[i].emission, cornell.materials[i].ke, 12);
    }
    memset(&sd, 0, sizeof sd);
    sd.positions = cornell.positions;
    sd.vertex_count = cornell.vertex_count;
    sd.indices = cornell.tri_indices;
    sd.triangle_count = cornell.tri_count;
    sd.material_ids = cornell.tri_material;
    sd.materials = mats;
    sd.material_count = cornell.material_count < 8 ? cornell.material_count : 8;
    r = lightvec_scene_create(&sd, &scene);
    if (r != LIGHTVEC_OK) {
        fail("lightvec scene", lightvec_result_string(r));
        return;
    }
    memset(&gd, 0, sizeof gd);
    gd.strata_theta = 4;   /* 4 x 12 rays: records of a real gather, cheaply */
    gd.strata_phi = 12;
    gd.seed = 3;
    /* kind 0: indirect light vectors, half of them view independent, the
       default interpolation; kind 1: direct ones, the paper's plain
       interpolation, a split threshold the records exceed */
    for (kind = 0; kind < 2; kind++) {
        lightvec_cache *cache = NULL;
        void *bytes = NULL;
        size_t size = 0;
        memset(&cd, 0, sizeof cd);
        cd.kind = kind ? LIGHTVEC_KIND_DIRECT : LIGHTVEC_KIND_INDIRECT;
        cd.interpolation = kind ? LIGHTVEC_INTERPOLATION_PLAIN : LIGHTVEC_INTERPOLATION_DEFAULT;
        cd.face_split_threshold = kind ? 2 : 0;
        r = lightvec_cache_create(&cd, &cache);
        for (i = 0; i < 6 && r == LIGHTVEC_OK; i++) {
            lightvec_surface sf;
            lightvec_record rec;
            memset(&sf, 0, sizeof sf);
            memcpy(sf.position, points[i], 12);
            memcpy(sf.normal, points[i] + 3, 12);
            {
                float l;
                int k;
                for (k = 0; k < 3; k++) sf.outgoing[k] = sf.normal[k] + tilt[k];
                l = sqrtf(sf.outgoing[0] * sf.outgoing[0] + sf.outgoing[1] * sf.outgoing[1] +
                          sf.outgoing[2] * sf.outgoing[2]);
                for (k = 0; k < 3; k++) sf.outgoing[k] /= l;
            }
            sf.flags = (kind == 0 && (i & 1)) ? LIGHTVEC_RECORD_VIEW_INDEPENDENT : 0;
            memcpy(sf.material.diffuse, mats[0].diffuse, 12);
            r = kind ? lightvec_gather_direct(scene, &gd, &sf, i, &rec) : lightvec_gather(scene, &gd, &sf, i, &rec);
            if (r == LIGHTVEC_OK) r = lightvec_insert(cache, &rec, NULL);
        }
        if (r == LIGHTVEC_OK) r = lightvec_save_to_memory(cache, NULL, &bytes, &size);
        if (r != LIGHTVEC_OK) fail(names[kind], lightvec_result_string(r));
        else write_seeds("lightvec", names[kind], bytes, size);
        lightvec_free_memory(NULL, bytes);
        if (kind == 0) save_tiny_view(cache);
        lightvec_cache_destroy(cache);
    }
    lightvec_scene_destroy(scene);
}

/* ---- rendercache ------------------------------------------------------------------ */

/* The nearest Cornell box triangle along a ray (Moller-Trumbore), or -1. */
static int cornell_hit(const float o[3], const float d[3], float *t_hit)
{
    uint32_t t;
    int best = -1;
    float best_t = 1e30f;
    for (t = 0; t < cornell.tri_count; t++) {
        const float *a = cornell.positions + 3 * cornell.tri_indices[3 * t];
        const float *b = cornell.positions + 3 * cornell.tri_indices[3 * t + 1];
        const float *c = cornell.positions + 3 * cornell.tri_indices[3 * t + 2];
        float e1[3], e2[3], p[3], q[3], s[3], det, u, v, dist;
        int k;
        for (k = 0; k < 3; k++) { e1[k] = b[k] - a[k]; e2[k] = c[k] - a[k]; s[k] = o[k] - a[k]; }
        p[0] = d[1] * e2[2] - d[2] * e2[1]; p[1] = d[2] * e2[0] - d[0] * e2[2]; p[2] = d[0] * e2[1] - d[1] * e2[0];
        det = e1[0] * p[0] + e1[1] * p[1] + e1[2] * p[2];
        if (fabsf(det) < 1e-12f) continue;
        u = (s[0] * p[0] + s[1] * p[1] + s[2] * p[2]) / det;
        q[0] = s[1] * e1[2] - s[2] * e1[1]; q[1] = s[2] * e1[0] - s[0] * e1[2]; q[2] = s[0] * e1[1] - s[1] * e1[0];
        v = (d[0] * q[0] + d[1] * q[1] + d[2] * q[2]) / det;
        dist = (e2[0] * q[0] + e2[1] * q[1] + e2[2] * q[2]) / det;
        if (u < 0 || v < 0 || u + v > 1 || dist <= 1e-6f || dist >= best_t) continue;
        best_t = dist;
        best = (int)t;
    }
    *t_hit = best_t;
    return best;
}

/* Ray casts the Cornell box from camera: colour = the material's Kd + Ke,
   object = the OBJ face, pixels without a ray stay RENDERCACHE_NO_SAMPLE. */
static void save_range_image(const char *scene, const rendercache_camera *cam)
{
    rendercache_range_image *img = NULL;
    void *bytes = NULL;
    size_t size = 0;
    uint32_t x, y;
    rendercache_result r = rendercache_range_image_create(cam, NULL, &img);
    for (y = 0; r == RENDERCACHE_OK && y < cam->height; y++)
        for (x = 0; x < cam->width; x++) {
            size_t p = (size_t)y * cam->width + x;
            float o[3], d[3], t;
            int hit, k;
            if (rendercache_camera_ray(cam, (float)x + 0.5f, (float)y + 0.5f, o, d) != RENDERCACHE_OK) continue;
            hit = cornell_hit(o, d, &t);
            if (hit < 0) {
                img->object[p] = RENDERCACHE_MISS;
                continue;
            }
            for (k = 0; k < 3; k++) {
                const obj_material *m = &cornell.materials[cornell.tri_material[hit]];
                img->rgb[3 * p + (size_t)k] = m->kd[k] + m->ke[k];
            }
            img->depth[p] = t;
            img->object[p] = cornell.tri_face[hit];
        }
    if (r == RENDERCACHE_OK) r = rendercache_range_image_save_to_memory(img, NULL, &bytes, &size);
    if (r != RENDERCACHE_OK) fail(scene, rendercache_result_string(r));
    else write_seeds("rendercache", scene, bytes, size);
    rendercache_free_memory(NULL, bytes);
    rendercache_range_image_destroy(img);
}

static void rendercache_seeds(void)
{
    rendercache_camera cam;
    prepare_directory("rendercache");
    /* the data's camera, 8 x 6 pixels; the eye is outside the box, so the
       border pixels miss */
    memset(&cam, 0, sizeof cam);
    cam.kind = RENDERCACHE_CAMERA_PERSPECTIVE;
    set3(cam.eye, 0.278f, 0.273f, -0.800f);
    set3(cam.look_at, 0.278f, 0.273f, 0.0f);
    set3(cam.up, 0, 1, 0);
    cam.vfov_degrees = 45.0f;
    cam.width = 8;
    cam.height = 6;
    save_range_image("cornell-perspective", &cam);
    /* a fish-eye and a sphere inside the box: no-sample pixels outside the
       fish-eye's circle, every pixel of the sphere hits a wall */
    set3(cam.eye, 0.278f, 0.4f, 0.3f);
    set3(cam.look_at, 0.278f, 0.4f, 0.5f);
    cam.kind = RENDERCACHE_CAMERA_FISHEYE;
    cam.width = cam.height = 8;
    save_range_image("cornell-fisheye", &cam);
    cam.kind = RENDERCACHE_CAMERA_SPHERE;
    cam.width = 8;
    cam.height = 4;
    save_range_image("cornell-sphere", &cam);
}

/* ---- OBJ + MTL ---------------------------------------------------------------- */

/* The fuzz input of an OBJ file and its material library (see fuzz_obj.c):
   the OBJ text with its mtllib line naming m.mtl, a zero byte, the MTL text. */
static uint8_t *obj_input(const char *obj_path, const char *mtl_path, size_t *size)
{
    size_t obj_size = 0, mtl_size = 0, n = 0, i;
    uint8_t *obj = read_whole(obj_path, &obj_size), *mtl = read_whole(mtl_path, &mtl_size), *out = NULL;
    static const char mtllib[] = "mtllib m.mtl";
    if (obj && mtl) out = (uint8_t *)malloc(obj_size + mtl_size + sizeof mtllib + 1);
    if (out) {
        for (i = 0; i < obj_size;) {   /* line by line, the mtllib line replaced */
            const uint8_t *eol = (const uint8_t *)memchr(obj + i, '\n', obj_size - i);
            size_t len = eol ? (size_t)(eol - (obj + i)) + 1 : obj_size - i;
            if (len >= 7 && memcmp(obj + i, "mtllib ", 7) == 0) {
                memcpy(out + n, mtllib, sizeof mtllib - 1);
                n += sizeof mtllib - 1;
                out[n++] = '\n';
            } else {
                memcpy(out + n, obj + i, len);
                n += len;
            }
            i += len;
        }
        out[n++] = 0;
        memcpy(out + n, mtl, mtl_size);
        n += mtl_size;
    }
    free(obj);
    free(mtl);
    *size = n;
    return out;
}

static void write_text(const char *name, const char *text, int with_mtl)
{
    static const char mtl[] = "newmtl grey\nKd 0.5 0.5 0.5\nnewmtl lamp\nKe 10 10 10\n";
    size_t n = strlen(text);
    uint8_t *buf = (uint8_t *)malloc(n + sizeof mtl + 1);
    if (!buf) return;
    memcpy(buf, text, n);
    if (with_mtl) {
        buf[n++] = 0;
        memcpy(buf + n, mtl, sizeof mtl - 1);
        n += sizeof mtl - 1;
    }
    write_file("obj", name, buf, n);
    free(buf);
}

static void obj_seeds(void)
{
    static const char *scenes[2] = { "cornell_box", "office" };
    static const char quad[] = "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nusemtl grey\n";
    char path[2][128], name[128], text[512];
    int s;
    prepare_directory("obj");
    for (s = 0; s < 2; s++) {
        size_t size = 0, cut;
        uint8_t *input;
        snprintf(path[0], sizeof path[0], "examples/data/%s.obj", scenes[s]);
        snprintf(path[1], sizeof path[1], "examples/data/%s.mtl", scenes[s]);
        input = obj_input(path[0], path[1], &size);
        if (!input) continue;
        snprintf(name, sizeof name, "ok-%s", scenes[s]);
        write_file("obj", name, input, size);
        for (cut = 1; cut < 4; cut++) {   /* cut texts: no promise, a cut at a line end parses */
            snprintf(name, sizeof name, "part-%s-%lu", scenes[s], (unsigned long)(cut * size / 4));
            write_file("obj", name, input, cut * size / 4);
        }
        free(input);
    }
    /* small files with a known answer (obj.h's contract: every problem is an
       error, no input crashes it) */
    snprintf(text, sizeof text, "%sf 1 2 3 4\no second\nusemtl lamp\nf -4 -3 -2\n", quad);
    write_text("ok-groups-relative-indices", text, 1);
    snprintf(text, sizeof text, "%sf 1 2 5\n", quad);
    write_text("corrupt-index-past-last-vertex", text, 1);
    snprintf(text, sizeof text, "%sf 1 2 -5\n", quad);
    write_text("corrupt-relative-index-before-first", text, 1);
    snprintf(text, sizeof text, "%sf 1 2\n", quad);
    write_text("corrupt-face-of-two-corners", text, 1);
    snprintf(text, sizeof text, "%susemtl chalk\nf 1 2 3\n", quad);
    write_text("corrupt-unknown-material", text, 1);
    write_text("corrupt-nan-coordinate", "v nan 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", 0);
    write_text("corrupt-huge-coordinate", "v 1e39 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", 0);
    write_text("corrupt-missing-library", quad, 0);
    write_text("corrupt-unknown-statement", "v 0 0 0\nbogus 1 2\n", 0);
}

int main(int argc, char **argv)
{
    if (argc > 1) root = argv[1];
    if (!load_cornell()) return 1;
    irrvol_seeds();
    radinterp_seeds();
    lightvec_seeds();
    rendercache_seeds();
    obj_seeds();
    obj_free(&cornell);
    if (failures) fprintf(stderr, "make_corpus: %d failures\n", failures);
    return failures ? 1 : 0;
}
