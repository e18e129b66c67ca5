/* radinterp_office.c - Hardt's radiosity rendering of the office: the
   hierarchical radiosity solution, the discontinuity mesh with one quadratic
   irradiance interpolant per triangle, and the online phase in software (a
   triangle-ID buffer and a perspective-correct barycentric buffer from the
   rasterizer, then radinterp_shade per pixel, as in section 3.4 of the thesis).

       cc -O2 -I. examples/radinterp_office.c -o radinterp_office -lm -lpthread
       ./radinterp_office --out build/out

   Writes DIR/radinterp_office_interpolant.png (per-pixel quadratic
   interpolants), DIR/radinterp_office_gouraud.png (the same mesh, radiosity
   at the triangle corners blended linearly) and DIR/radinterp_office_mesh.png
   (the interpolant image with leaf edges in grey and discontinuity edges in
   red). Options: --scene FILE (the office or the Cornell box have built-in
   views), --out DIR, --size WxH, --eps W/m^2 (solver error bound),
   --min-leaf-area M2 (coarsest mesh leaves taken from the solution),
   --min-weight W/m^2 (weakest discontinuity meshed), --max-dsets N,
   --refine (representation-based refinement), --save FILE (the mesh). */
#define _POSIX_C_SOURCE 200809L /* clock_gettime */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#define RADINTERP_IMPLEMENTATION
#include "radinterp.h"
#include "examples/common/camera.h"
#include "examples/common/image.h"
#include "examples/common/obj.h"
#include "examples/common/pool.h"
#include "examples/common/raster.h"

static double seconds(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

static void print_log(void *user, const char *message)
{
    (void)user;
    fprintf(stderr, "%s\n", message);
}

static int file_write(void *user, const void *bytes, size_t n)
{
    return fwrite(bytes, 1, n, (FILE *)user) == n ? 0 : -1;
}

/* Draws the mesh's flagged edges over an image, hidden where the depth
   buffer holds something nearer: leaf edges grey, discontinuities red. */
static void draw_edges(const radinterp_mesh_data *d, const ex_camera *cam, const ex_raster *r, float *rgb)
{
    uint32_t t;
    int e;
    for (t = 0; t < d->triangle_count; t++) {
        for (e = 0; e < 3; e++) {
            const float *a = d->positions + 3 * (size_t)d->indices[3 * (size_t)t + (size_t)(e + 1) % 3];
            const float *b = d->positions + 3 * (size_t)d->indices[3 * (size_t)t + (size_t)(e + 2) % 3];
            int disc = (d->edge_flags[t] >> (3 + e)) & 1, leaf = (d->edge_flags[t] >> e) & 1, steps, i;
            float pa[2], pb[2], depth;
            if (!leaf && !disc) continue;
            if (!ex_camera_project(cam, a, &pa[0], &pa[1], &depth) || !ex_camera_project(cam, b, &pb[0], &pb[1], &depth))
                continue;
            steps = 2 * (int)(fabsf(pb[0] - pa[0]) + fabsf(pb[1] - pa[1])) + 2;
            if (steps > 8192) steps = 8192;
            for (i = 0; i <= steps; i++) {
                float s = (float)i / (float)steps, p[3], px, py;
                int k, x, y;
                size_t pix;
                for (k = 0; k < 3; k++) p[k] = a[k] + s * (b[k] - a[k]);
                if (!ex_camera_project(cam, p, &px, &py, &depth)) continue;
                x = (int)px;
                y = (int)py;
                if (x < 0 || y < 0 || x >= r->width || y >= r->height) continue;
                pix = (size_t)y * (size_t)r->width + (size_t)x;
                if (depth > r->depth[pix] * 1.002f + 1e-3f) continue;
                if (disc) {
                    rgb[3 * pix] = 1e3f; rgb[3 * pix + 1] = 0.0f; rgb[3 * pix + 2] = 0.0f;
                } else if (rgb[3 * pix + 1] < 1e3f) {
                    for (k = 0; k < 3; k++) rgb[3 * pix + (size_t)k] = 0.5f * rgb[3 * pix + (size_t)k] + 0.02f;
                }
            }
        }
    }
}

static int write_image(const char *dir, const char *name, const float *rgb, int w, int h, float exposure,
                       unsigned char *rgb8)
{
    char path[1024];
    ex_tonemap(rgb, w, h, exposure, rgb8);
    snprintf(path, sizeof path, "%s/%s", dir, name);
    if (ex_write_png(path, w, h, rgb8) != 0) {
        fprintf(stderr, "radinterp_office: cannot write %s (does the directory exist?)\n", path);
        return -1;
    }
    printf("  wrote %s\n", path);
    return 0;
}

static void usage(void)
{
    puts("usage: radinterp_office [--scene FILE.obj] [--out DIR] [--size WxH] [--eps E] [--min-leaf-area A]\n"
         "                        [--min-weight W] [--max-dsets N] [--refine] [--save FILE]\n"
         "Solves the scene by hierarchical radiosity, builds the discontinuity mesh with\n"
         "quadratic irradiance interpolants and writes the interpolant, Gouraud and mesh\n"
         "images to DIR (default build/out).");
}

int main(int argc, char **argv)
{
    const char *scene_path = "examples/data/office.obj", *out = "build/out", *save = NULL, *name;
    int width = 640, height = 480, i, refine = 0, max_dsets = 0;
    float eps = 0.0f, min_weight = 0.0f, min_leaf_area = 0.0f, eye[3], target[3], up[3] = {0, 1, 0}, vfov = 60.0f, exposure;
    obj_scene scene;
    char err[512];
    uint32_t *patches, f, k;
    radinterp_material *mats;
    radinterp_desc d;
    radinterp_mesh_desc md;
    radinterp_solution *sol;
    radinterp_mesh *mesh;
    radinterp_mesh_info info;
    radinterp_mesh_data data;
    radinterp_result res;
    ex_pool *pool;
    ex_raster raster;
    ex_camera cam;
    float *interp, *gouraud;
    unsigned char *rgb8;
    size_t n;
    double t0, t_solve, t_mesh, t_shade;
    for (i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--help") || !strcmp(argv[i], "-h")) { usage(); return 0; }
        if (!strcmp(argv[i], "--refine")) { refine = 1; continue; }
        if (i + 1 >= argc) { fprintf(stderr, "radinterp_office: %s needs a value (see --help)\n", argv[i]); return 2; }
        if (!strcmp(argv[i], "--scene")) scene_path = argv[++i];
        else if (!strcmp(argv[i], "--out")) out = argv[++i];
        else if (!strcmp(argv[i], "--save")) save = argv[++i];
        else if (!strcmp(argv[i], "--eps")) eps = (float)atof(argv[++i]);
        else if (!strcmp(argv[i], "--min-weight")) min_weight = (float)atof(argv[++i]);
        else if (!strcmp(argv[i], "--min-leaf-area")) min_leaf_area = (float)atof(argv[++i]);
        else if (!strcmp(argv[i], "--max-dsets")) max_dsets = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--size")) {
            if (sscanf(argv[++i], "%dx%d", &width, &height) != 2 || width < 16 || height < 16 || width > 8192 ||
                height > 8192) {
                fprintf(stderr, "radinterp_office: bad --size '%s' (use WxH)\n", argv[i]);
                return 2;
            }
        } else { fprintf(stderr, "radinterp_office: unknown option '%s' (see --help)\n", argv[i]); return 2; }
    }
    if (eps < 0.0f || min_weight < 0.0f || min_leaf_area < 0.0f || max_dsets < 0) {
        fprintf(stderr, "radinterp_office: --eps, --min-leaf-area, --min-weight and --max-dsets must not be negative\n");
        return 2;
    }
    if (obj_load(scene_path, &scene, err, sizeof err) != 0) { fprintf(stderr, "radinterp_office: %s\n", err); return 1; }
    name = strrchr(scene_path, '/') ? strrchr(scene_path, '/') + 1 : scene_path;
    if (strstr(name, "cornell")) {
        eye[0] = 0.278f; eye[1] = 0.273f; eye[2] = -0.8f;
        target[0] = 0.278f; target[1] = 0.273f; target[2] = 0.0f;
        vfov = 39.3f;
    } else {
        eye[0] = 4.6f; eye[1] = 1.6f; eye[2] = 0.3f;
        target[0] = 1.6f; target[1] = 0.7f; target[2] = 3.2f;
    }

    /* the scene as patches: one per polygon face, E = pi * Ke */
    patches = (uint32_t *)malloc(4 * sizeof(uint32_t) * scene.face_count);
    mats = (radinterp_material *)calloc(scene.material_count ? scene.material_count : 1, sizeof(radinterp_material));
    pool = ex_pool_create(0);
    if (!patches || !mats || !pool) { fprintf(stderr, "radinterp_office: out of memory\n"); return 1; }
    for (f = 0; f < scene.face_count; f++) {
        uint32_t c = scene.face_start[f + 1] - scene.face_start[f];
        if (c > 4) { fprintf(stderr, "radinterp_office: face %u has %u corners (3 or 4 only)\n", f, c); return 1; }
        for (k = 0; k < 4; k++) patches[4 * f + k] = k < c ? scene.face_vertices[scene.face_start[f] + k] : RADINTERP_NO_VERTEX;
    }
    for (f = 0; f < scene.material_count; f++)
        for (k = 0; k < 3; k++) {
            mats[f].reflectance[k] = scene.materials[f].kd[k];
            mats[f].emission[k] = 3.14159265f * scene.materials[f].ke[k];
        }
    memset(&d, 0, sizeof d);
    d.positions = scene.positions;
    d.vertex_count = scene.vertex_count;
    d.patches = patches;
    d.patch_count = scene.face_count;
    d.patch_materials = scene.face_material;
    d.materials = mats;
    d.material_count = scene.material_count;
    d.eps = eps;
    d.parallel_for = ex_pool_parallel_for;
    d.parallel_user = pool;
    d.log = print_log;
    t0 = seconds();
    res = radinterp_solve(&d, &sol);
    if (res != RADINTERP_OK) { fprintf(stderr, "radinterp_office: solve: %s\n", radinterp_result_string(res)); return 1; }
    t_solve = seconds() - t0;

    memset(&md, 0, sizeof md);
    md.min_discont_weight = min_weight;
    md.min_leaf_area = min_leaf_area;
    md.max_leaf_dsets = (uint32_t)max_dsets;
    md.refine = refine;
    md.parallel_for = ex_pool_parallel_for;
    md.parallel_user = pool;
    md.log = print_log;
    t0 = seconds();
    res = radinterp_build_mesh(sol, &md, &mesh);
    if (res != RADINTERP_OK) { fprintf(stderr, "radinterp_office: mesh: %s\n", radinterp_result_string(res)); return 1; }
    t_mesh = seconds() - t0;
    radinterp_mesh_get_info(mesh, &info);
    radinterp_mesh_get_data(mesh, &data);
    printf("radinterp_office: %s, %u patches, %d threads\n", scene_path, scene.face_count, ex_pool_threads(pool));
    printf("  solve %.2f s: %u leaves\n", t_solve, radinterp_leaf_count(sol));
    printf("  mesh %.2f s: %u discontinuities (%u EV, %u VE, %u horizon, %u contact), %u active; %u leaves, "
           "%u triangles, %u vertices; %llu IrradianceAtPoint samples\n",
           t_mesh, info.discontinuities, info.ev, info.ve, info.horizon, info.contact, info.active_discontinuities,
           info.leaf_count, info.triangle_count, info.vertex_count, (unsigned long long)info.samples);
    if (save) {
        FILE *fp = fopen(save, "wb");
        if (!fp || radinterp_mesh_save(mesh, file_write, fp) != RADINTERP_OK) fprintf(stderr, "radinterp_office: cannot write %s\n", save);
        else printf("  wrote %s\n", save);
        if (fp) fclose(fp);
    }

    /* the online phase: ID + barycentric buffers, then one interpolant per pixel */
    cam = ex_camera_look_at(eye, target, up, vfov, width, height);
    n = (size_t)width * (size_t)height;
    interp = (float *)calloc(3 * n, sizeof(float));
    gouraud = (float *)calloc(3 * n, sizeof(float));
    rgb8 = (unsigned char *)malloc(3 * n);
    if (!interp || !gouraud || !rgb8 || ex_raster_init(&raster, width, height) != 0) {
        fprintf(stderr, "radinterp_office: out of memory\n");
        return 1;
    }
    raster.pool = pool;
    ex_raster_clear(&raster);
    ex_raster_draw(&raster, &cam, data.positions, data.indices, data.triangle_count, 0);
    t0 = seconds();
    radinterp_shade(mesh, raster.id, raster.bary, n, interp);
    t_shade = seconds() - t0;
    radinterp_shade_gouraud(mesh, raster.id, raster.bary, n, gouraud);
    for (i = 0; i < (int)(3 * n); i++) { interp[i] *= (float)(1.0 / EX_PI); gouraud[i] *= (float)(1.0 / EX_PI); } /* radiance B / pi */
    printf("  shading %dx%d: %.2f ms (%.0f frames/s)\n", width, height, 1e3 * t_shade, 1.0 / t_shade);
    exposure = ex_auto_exposure(interp, width, height, 0.97f);
    if (write_image(out, "radinterp_office_interpolant.png", interp, width, height, exposure, rgb8) != 0 ||
        write_image(out, "radinterp_office_gouraud.png", gouraud, width, height, exposure, rgb8) != 0)
        return 1;
    draw_edges(&data, &cam, &raster, interp);
    if (write_image(out, "radinterp_office_mesh.png", interp, width, height, exposure, rgb8) != 0) return 1;

    ex_raster_free(&raster);
    free(interp);
    free(gouraud);
    free(rgb8);
    radinterp_mesh_destroy(mesh);
    radinterp_solution_destroy(sol);
    ex_pool_destroy(pool);
    free(patches);
    free(mats);
    obj_free(&scene);
    return 0;
}
