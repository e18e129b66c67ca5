/* lightvec_cornell - ray traces the Cornell box with indirect light from the
   light-vector cache of lightvec.h (figure 2 of Crespin & Peroche 2004), then
   again gathering indirect light at every pixel, and compares the two.

       cc -O2 -I. examples/lightvec_cornell.c -o lightvec_cornell -lm -lpthread
       ./lightvec_cornell [--size 512] [--out build/out] [--no-reference] [--3d] [--glossy]

   Direct light comes from lightvec_gather_direct at every pixel (area
   sampling of the light with shadow rays), indirect light from the cache: a
   lookup per pixel, and on a miss a hemisphere gather that is inserted for
   the next pixels. Pixels are visited in a random order (the paper's remedy
   for scan-line bias) by all cores; inserts are serialized by a mutex while
   lookups run concurrently (the cache's one-writer, many-readers model).
   --3d treats the (Lambertian) surfaces as view independent. --glossy makes
   the floor glossy (0.3 Lambert + 0.4 normalized Phong, exponent 20): its
   light vectors carry a glossy part that follows the viewer.
   Writes lightvec_cache.png, lightvec_gather.png and the indirect components
   lightvec_indirect_cache.png, lightvec_indirect_gather.png under --out. */
#define _POSIX_C_SOURCE 200809L
#define LIGHTVEC_IMPLEMENTATION
#include "lightvec.h"
#include "examples/common/pool.h"
#include "examples/common/obj.h"
#include "examples/common/camera.h"
#include "examples/common/image.h"
#include <errno.h>
#include <stdio.h>
#include <sys/stat.h>
#include <time.h>

typedef struct pixel {
    int valid, wall;
    lightvec_surface s;
    float emitted[3];          /* the light itself, seen directly */
} pixel;

typedef struct app {
    obj_scene obj;
    lightvec_material *mats;       /* the file's, and the glossy floor's last */
    uint32_t *tri_material;
    lightvec_scene *scene;
    lightvec_cache *cache;
    pthread_mutex_t insert_lock;
    lightvec_gather_desc gather;
    ex_camera cam;
    int size, view_independent, glossy;
    pixel *px;
    uint32_t *order;
    float *direct, *ind_cache, *ind_gather;
    int *hit;
} app;

static double now(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

static float lum(const float *c) { return 0.2126f * c[0] + 0.7152f * c[1] + 0.0722f * c[2]; }

static int load_scene(app *a)
{
    char err[256];
    lightvec_scene_desc d;
    uint32_t i;
    lightvec_result r;
    if (obj_load("examples/data/cornell_box.obj", &a->obj, err, sizeof err) != 0) {
        fprintf(stderr, "%s\n", err);
        return -1;
    }
    a->mats = (lightvec_material *)calloc(a->obj.material_count + 1, sizeof *a->mats);
    a->tri_material = (uint32_t *)malloc(a->obj.tri_count * sizeof *a->tri_material);
    if (!a->mats || !a->tri_material) return -1;
    memcpy(a->tri_material, a->obj.tri_material, a->obj.tri_count * sizeof *a->tri_material);
    if (a->glossy) {
        lightvec_material *f = &a->mats[a->obj.material_count];
        int floor = obj_find_group(&a->obj, "floor");
        f->diffuse[0] = f->diffuse[1] = f->diffuse[2] = 0.3f;
        f->specular[0] = f->specular[1] = f->specular[2] = 0.4f;
        f->exponent = 20.0f;
        for (i = 0; i < a->obj.tri_count; i++)
            if ((int)a->obj.face_group[a->obj.tri_face[i]] == floor) a->tri_material[i] = a->obj.material_count;
    }
    for (i = 0; i < a->obj.material_count; i++) {
        memcpy(a->mats[i].diffuse, a->obj.materials[i].kd, sizeof a->mats[i].diffuse);
        memcpy(a->mats[i].specular, a->obj.materials[i].ks, sizeof a->mats[i].specular);
        memcpy(a->mats[i].emission, a->obj.materials[i].ke, sizeof a->mats[i].emission);
        memcpy(a->mats[i].transmittance, a->obj.materials[i].tf, sizeof a->mats[i].transmittance);
        a->mats[i].exponent = a->obj.materials[i].ns;
    }
    memset(&d, 0, sizeof d);
    d.positions = a->obj.positions;
    d.vertex_count = a->obj.vertex_count;
    d.indices = a->obj.tri_indices;
    d.triangle_count = a->obj.tri_count;
    d.material_ids = a->tri_material;
    d.materials = a->mats;
    d.material_count = a->obj.material_count + (a->glossy ? 1u : 0u);
    r = lightvec_scene_create(&d, &a->scene);
    if (r != LIGHTVEC_OK) {
        fprintf(stderr, "lightvec_scene_create: %s\n", lightvec_result_string(r));
        return -1;
    }
    return 0;
}

/* Primary ray of pixel i: the surface it sees (front faces only). */
static void primary_job(void *ctx, uint32_t i)
{
    app *a = (app *)ctx;
    pixel *p = &a->px[i];
    int x = (int)(i % (uint32_t)a->size), y = (int)(i / (uint32_t)a->size), k;
    const char *walls[5] = { "floor", "ceiling", "back_wall", "left_wall", "right_wall" };
    float d[3], e1[3], e2[3], n[3], l;
    const float *v0, *v1, *v2;
    lightvec_hit h;
    uint32_t t, m, g;
    memset(p, 0, sizeof *p);
    ex_camera_ray(&a->cam, (float)x + 0.5f, (float)y + 0.5f, d);
    if (!lightvec_scene_intersect(a->scene, a->cam.eye, d, 1e30f, &h)) return;
    t = h.triangle;
    v0 = a->obj.positions + 3 * a->obj.tri_indices[3 * t];
    v1 = a->obj.positions + 3 * a->obj.tri_indices[3 * t + 1];
    v2 = a->obj.positions + 3 * a->obj.tri_indices[3 * t + 2];
    for (k = 0; k < 3; k++) { e1[k] = v1[k] - v0[k]; e2[k] = v2[k] - v0[k]; }
    n[0] = e1[1] * e2[2] - e1[2] * e2[1];
    n[1] = e1[2] * e2[0] - e1[0] * e2[2];
    n[2] = e1[0] * e2[1] - e1[1] * e2[0];
    l = sqrtf(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    if (!(l > 0.0f) || n[0] * d[0] + n[1] * d[1] + n[2] * d[2] >= 0.0f) return; /* back faces are black */
    m = a->tri_material[t];
    for (k = 0; k < 3; k++) {
        p->s.position[k] = a->cam.eye[k] + h.t * d[k];
        p->s.normal[k] = n[k] / l;
        p->s.outgoing[k] = -d[k];
        p->emitted[k] = a->mats[m].emission[k];
    }
    p->s.material = a->mats[m];
    p->s.flags = a->view_independent ? LIGHTVEC_RECORD_VIEW_INDEPENDENT : 0u;
    g = a->obj.face_group[a->obj.tri_face[t]];
    for (k = 0; k < 5; k++) p->wall |= (int)g == obj_find_group(&a->obj, walls[k]);
    p->valid = 1;
}

static const float *outgoing_of(const app *a, const pixel *p)
{
    return a->view_independent ? NULL : p->s.outgoing;
}

/* Direct light at pixel i: a DLV computed on the spot (64 light samples). */
static void direct_job(void *ctx, uint32_t i)
{
    app *a = (app *)ctx;
    pixel *p = &a->px[i];
    lightvec_gather_desc gd;
    lightvec_record rec;
    float *out = a->direct + 3 * i;
    int k;
    out[0] = out[1] = out[2] = 0.0f;
    if (!p->valid) return;
    memset(&gd, 0, sizeof gd);
    gd.strata_theta = gd.strata_phi = 8;
    gd.seed = 5;
    if (lightvec_gather_direct(a->scene, &gd, &p->s, i, &rec) != LIGHTVEC_OK) return;
    lightvec_radiance(&p->s.material, p->s.normal, outgoing_of(a, p), &rec.vector, out);
    for (k = 0; k < 3; k++) out[k] += p->emitted[k];
}

/* Figure 2: lookup; on a miss gather, insert, and use the new vector. */
static void cache_job(void *ctx, uint32_t j)
{
    app *a = (app *)ctx;
    uint32_t i = a->order[j];
    pixel *p = &a->px[i];
    lightvec_lookup_result lr;
    if (!p->valid) return;
    if (lightvec_lookup(a->cache, p->s.position, p->s.normal, outgoing_of(a, p), &lr) != LIGHTVEC_OK) return;
    a->hit[i] = lr.hit;
    if (!lr.hit) {
        lightvec_record rec;
        if (lightvec_gather(a->scene, &a->gather, &p->s, i, &rec) != LIGHTVEC_OK) return;
        pthread_mutex_lock(&a->insert_lock);
        lightvec_insert(a->cache, &rec, NULL);
        pthread_mutex_unlock(&a->insert_lock);
        lr.vector = rec.vector;
    }
    lightvec_radiance(&p->s.material, p->s.normal, outgoing_of(a, p), &lr.vector, a->ind_cache + 3 * i);
}

/* Gathering at every pixel, for comparison. */
static void gather_job(void *ctx, uint32_t i)
{
    app *a = (app *)ctx;
    pixel *p = &a->px[i];
    lightvec_gather_desc gd = a->gather;
    lightvec_record rec;
    if (!p->valid) return;
    gd.seed = 99; /* other random numbers than the cache's records */
    if (lightvec_gather(a->scene, &gd, &p->s, i, &rec) != LIGHTVEC_OK) return;
    lightvec_radiance(&p->s.material, p->s.normal, outgoing_of(a, p), &rec.vector, a->ind_gather + 3 * i);
}

static int write_image(const char *dir, const char *name, const float *rgb, int size, float exposure)
{
    char path[1024];
    unsigned char *bytes = (unsigned char *)malloc(3 * (size_t)size * (size_t)size);
    int r;
    if (!bytes) return -1;
    snprintf(path, sizeof path, "%s/%s", dir, name);
    ex_tonemap(rgb, size, size, exposure, bytes);
    r = ex_write_png(path, size, size, bytes);
    free(bytes);
    if (r != 0) fprintf(stderr, "cannot write %s\n", path);
    else printf("wrote %s\n", path);
    return r;
}

static void sum_images(const float *a, const float *b, float *out, size_t n)
{
    size_t i;
    for (i = 0; i < n; i++) out[i] = a[i] + b[i];
}

static int make_dirs(const char *path)
{
    char buf[1024];
    size_t i, n = strlen(path);
    if (n == 0 || n >= sizeof buf) return -1;
    memcpy(buf, path, n + 1);
    for (i = 1; i <= n; i++)
        if (buf[i] == '/' || buf[i] == '\0') {
            char c = buf[i];
            buf[i] = '\0';
            if (mkdir(buf, 0755) != 0 && errno != EEXIST) return -1;
            buf[i] = c;
        }
    return 0;
}

int main(int argc, char **argv)
{
    static app a;
    const char *out = "build/out";
    float eye[3] = { 0.278f, 0.273f, -0.8f }, target[3] = { 0.278f, 0.273f, 0.0f }, up[3] = { 0, 1, 0 };
    int reference = 1, i;
    uint32_t n, visible = 0, hits = 0, k;
    uint64_t s = 1;
    double t0, t_cache, t_gather = 0, err = 0, exposure;
    size_t wall_pixels = 0;
    lightvec_cache_stats st;
    ex_pool *pool;
    float *full;
    a.size = 512;
    for (i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--out") && i + 1 < argc) out = argv[++i];
        else if (!strcmp(argv[i], "--size") && i + 1 < argc) a.size = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--no-reference")) reference = 0;
        else if (!strcmp(argv[i], "--3d")) a.view_independent = 1;
        else if (!strcmp(argv[i], "--glossy")) a.glossy = 1;
        else {
            fprintf(stderr, "usage: %s [--size N] [--out DIR] [--no-reference] [--3d] [--glossy]\n", argv[0]);
            return 2;
        }
    }
    if (a.glossy && a.view_independent) {
        fprintf(stderr, "--glossy and --3d exclude each other: a glossy surface depends on the viewer\n");
        return 2;
    }
    if (a.size < 8 || a.size > 8192) {
        fprintf(stderr, "--size must be in 8..8192\n");
        return 2;
    }
    if (load_scene(&a) != 0) return 1;
    n = (uint32_t)(a.size * a.size);
    a.px = (pixel *)calloc(n, sizeof *a.px);
    a.order = (uint32_t *)malloc(n * sizeof *a.order);
    a.direct = (float *)calloc(3 * (size_t)n, sizeof(float));
    a.ind_cache = (float *)calloc(3 * (size_t)n, sizeof(float));
    a.ind_gather = (float *)calloc(3 * (size_t)n, sizeof(float));
    a.hit = (int *)calloc(n, sizeof(int));
    full = (float *)calloc(3 * (size_t)n, sizeof(float));
    if (!a.px || !a.order || !a.direct || !a.ind_cache || !a.ind_gather || !a.hit || !full) return 1;
    if (lightvec_cache_create(NULL, &a.cache) != LIGHTVEC_OK) return 1;
    pthread_mutex_init(&a.insert_lock, NULL);
    a.cam = ex_camera_look_at(eye, target, up, 39.3f, a.size, a.size);
    pool = ex_pool_create(0);

    ex_pool_parallel_for(pool, primary_job, &a, n);
    ex_pool_parallel_for(pool, direct_job, &a, n);
    for (k = 0; k < n; k++) a.order[k] = k;
    for (k = n - 1; k > 0; k--) { /* random pixel order */
        uint32_t j, t;
        s = s * 6364136223846793005ull + 1442695040888963407ull;
        j = (uint32_t)((s >> 33) % (k + 1));
        t = a.order[k]; a.order[k] = a.order[j]; a.order[j] = t;
    }

    t0 = now();
    ex_pool_parallel_for(pool, cache_job, &a, n);
    t_cache = now() - t0;
    for (k = 0; k < n; k++) {
        visible += (uint32_t)a.px[k].valid;
        hits += (uint32_t)a.hit[k];
    }
    lightvec_cache_info(a.cache, &st);
    printf("%dx%d Cornell box%s, %s light vectors: indirect light from the cache in %.2f s\n", a.size, a.size,
           a.glossy ? " with a glossy floor" : "", a.view_independent ? "3D" : "5D", t_cache);
    printf("  hit rate %.2f%% (%u of %u pixels), %llu records, %u faces, %.1f MB\n", 100.0 * hits / visible, hits,
           visible, (unsigned long long)st.record_count, st.face_count, st.bytes / 1048576.0);

    if (reference) {
        printf("gathering at every pixel (%u gathers)...\n", visible);
        fflush(stdout);
        t0 = now();
        ex_pool_parallel_for(pool, gather_job, &a, n);
        t_gather = now() - t0;
        for (k = 0; k < n; k++) {
            float g, c;
            if (!a.px[k].valid || !a.px[k].wall) continue;
            g = lum(a.ind_gather + 3 * k);
            c = lum(a.ind_cache + 3 * k);
            if (g > 0.0f) {
                err += fabs(c - g) / g;
                wall_pixels++;
            }
        }
        printf("  gathering everywhere: %.2f s; the cache is %.1fx faster (%.0f%% of the time saved)\n", t_gather,
               t_gather / t_cache, 100.0 * (1.0 - t_cache / t_gather));
        printf("  indirect light on the walls: mean relative difference %.2f%% (%zu pixels)\n",
               100.0 * err / (double)(wall_pixels ? wall_pixels : 1), wall_pixels);
    }

    if (make_dirs(out) != 0) {
        fprintf(stderr, "cannot create %s\n", out);
        return 1;
    }
    sum_images(a.direct, a.ind_cache, full, 3 * (size_t)n);
    exposure = ex_auto_exposure(full, a.size, a.size, 0.97f);
    write_image(out, "lightvec_cache.png", full, a.size, (float)exposure);
    write_image(out, "lightvec_indirect_cache.png", a.ind_cache, a.size, (float)exposure * 2.0f);
    if (reference) {
        sum_images(a.direct, a.ind_gather, full, 3 * (size_t)n);
        write_image(out, "lightvec_gather.png", full, a.size, (float)exposure);
        write_image(out, "lightvec_indirect_gather.png", a.ind_gather, a.size, (float)exposure * 2.0f);
    }

    ex_pool_destroy(pool);
    pthread_mutex_destroy(&a.insert_lock);
    lightvec_cache_destroy(a.cache);
    lightvec_scene_destroy(a.scene);
    obj_free(&a.obj);
    free(a.mats); free(a.tri_material); free(a.px); free(a.order); free(a.direct); free(a.ind_cache); free(a.ind_gather); free(a.hit);
    free(full);
    return 0;
}
