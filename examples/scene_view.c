/* scene_view.c - renders a scene with the examples' ray tracer (direct
   light from emitters and the sky, diffuse bounces, thin glass) and writes
   a PNG: the project's scenes, or any scene a user has (OBJ always; glTF,
   FBX, Collada, IFC, PLY... when built with Assimp, as make does when
   libassimp-dev is present).

       cc -O2 -I. examples/scene_view.c -o scene_view -lm -lpthread
       ./scene_view --scene examples/data/office.obj --out build/out
       ./scene_view --scene house.ifc --sky 1,1,1 --out build/out

   Options: --scene FILE, --up y|z, --scale S, --drop-coincident, --sky R,G,B,
   --out DIR, --size WxH, --spp N, --bounces N (see --help). */
#define _POSIX_C_SOURCE 200809L /* clock_gettime */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "examples/common/camera.h"
#include "examples/common/image.h"
#include "examples/common/pool.h"
#include "examples/common/scene_load.h"
#include "examples/common/trace.h"

typedef struct view_job {
    const ex_tracer *tracer;
    ex_camera camera;
    int spp, bounces;
    float *rgb;
} view_job;

static void render_row(void *ctx, uint32_t y)
{
    view_job *j = (view_job *)ctx;
    int x, s, k;
    for (x = 0; x < j->camera.width; x++) {
        ex_rng r = ex_rng_stream(1, (uint64_t)y * (uint64_t)j->camera.width + (uint64_t)x);
        float sum[3] = { 0, 0, 0 };
        for (s = 0; s < j->spp; s++) {
            float dir[3], rgb[3];
            ex_camera_ray(&j->camera, (float)x + ex_rng_float(&r), (float)y + ex_rng_float(&r), dir);
            ex_tracer_shade(j->tracer, j->camera.eye, dir, j->bounces, &r, rgb, NULL);
            for (k = 0; k < 3; k++) sum[k] += rgb[k];
        }
        for (k = 0; k < 3; k++) j->rgb[3 * ((size_t)y * (size_t)j->camera.width + (size_t)x) + (size_t)k] = sum[k] / (float)j->spp;
    }
}

static void usage(void)
{
    printf("usage: scene_view [options]\n"
           "Renders the scene with direct light and diffuse bounces and writes DIR/<scene>.png.\n"
           "The office and the Cornell box have built-in viewpoints; other scenes are\n"
           "viewed from outside their bounding box.\n\n"
           "%s"
           "  --sky R,G,B          a constant sky of this radiance, W/(m^2 sr) (default: none)\n"
           "  --out DIR            where the PNG goes (default build/out)\n"
           "  --size WxH           image size (default 480x360)\n"
           "  --spp N              samples per pixel (default 16)\n"
           "  --bounces N          diffuse bounces after direct light (default 1)\n",
           ex_scene_options_help());
}

int main(int argc, char **argv)
{
    const char *scene_path, *out = "build/out";
    int width = 480, height = 360, spp = 16, bounces = 1, i, r;
    ex_scene_options so;
    ex_sky sky;
    obj_scene scene;
    char err[512], path[1024];
    float lo[3], hi[3], eye[3], target[3], up[3] = { 0, 1, 0 }, vfov = 60.0f;
    ex_tracer *tracer;
    ex_pool *pool;
    view_job job;
    unsigned char *rgb8;
    const char *name;
    struct timespec t0, t1;
    ex_scene_options_default(&so, "examples/data/office.obj");
    memset(&sky, 0, sizeof sky);
    for (i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--help") || !strcmp(argv[i], "-h")) { usage(); return 0; }
        if ((r = ex_scene_option(argc, argv, &i, &so, err, sizeof err)) != 0) {
            if (r < 0) { fprintf(stderr, "scene_view: %s (see --help)\n", err); return 2; }
            continue;
        }
        if (i + 1 >= argc) { fprintf(stderr, "scene_view: %s needs a value (see --help)\n", argv[i]); return 2; }
        if (!strcmp(argv[i], "--out")) out = argv[++i];
        else if (!strcmp(argv[i], "--sky")) {
            i++;
            if (sscanf(argv[i], "%f,%f,%f", &sky.radiance[0], &sky.radiance[1], &sky.radiance[2]) != 3 || !ex_sky_valid(&sky)) {
                fprintf(stderr, "scene_view: bad --sky '%s' (use R,G,B, each >= 0)\n", argv[i]);
                return 2;
            }
        }
        else if (!strcmp(argv[i], "--size")) {
            if (sscanf(argv[++i], "%dx%d", &width, &height) != 2 || width < 1 || height < 1 || width > 8192 || height > 8192) {
                fprintf(stderr, "scene_view: bad --size '%s' (use WxH)\n", argv[i]);
                return 2;
            }
        } else if (!strcmp(argv[i], "--spp")) spp = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--bounces")) bounces = atoi(argv[++i]);
        else { fprintf(stderr, "scene_view: unknown option '%s' (see --help)\n", argv[i]); return 2; }
    }
    if (spp < 1 || spp > 65536 || bounces < 0 || bounces > 64) {
        fprintf(stderr, "scene_view: --spp must be 1..65536 and --bounces 0..64\n");
        return 2;
    }
    scene_path = so.path;
    if (ex_scene_load(&so, &scene, err, sizeof err) != 0) { fprintf(stderr, "scene_view: %s\n", err); return 1; }
    if (scene.coincident_pairs)
        printf("scene_view: %s: %u pairs of coincident faces (%u faces, %.3g m^2) will speckle%s\n", scene_path,
               scene.coincident_pairs, scene.coincident_faces, scene.coincident_area,
               so.drop_coincident ? " (those not covered entirely)" : "; --drop-coincident drops the covered ones");
    if (!obj_bounds(&scene, lo, hi)) { fprintf(stderr, "scene_view: %s has no vertices\n", scene_path); return 1; }
    name = strrchr(scene_path, '/') ? strrchr(scene_path, '/') + 1 : scene_path;
    if (strstr(name, "office")) {
        eye[0] = 4.6f; eye[1] = 1.6f; eye[2] = 0.3f;
        target[0] = 1.6f; target[1] = 0.7f; target[2] = 3.2f;
    } else if (strstr(name, "cornell")) {
        eye[0] = 0.278f; eye[1] = 0.273f; eye[2] = -0.8f;
        target[0] = 0.278f; target[1] = 0.273f; target[2] = 0.0f;
        vfov = 39.3f;
    } else {
        for (i = 0; i < 3; i++) target[i] = 0.5f * (lo[i] + hi[i]);
        eye[0] = target[0] + 1.2f * (hi[0] - lo[0]);
        eye[1] = target[1] + 0.6f * (hi[1] - lo[1]);
        eye[2] = target[2] + 1.2f * (hi[2] - lo[2]);
    }
    tracer = ex_tracer_create(&scene);
    if (tracer) ex_tracer_set_sky(tracer, &sky);
    pool = ex_pool_create(0);
    job.tracer = tracer;
    job.camera = ex_camera_look_at(eye, target, up, vfov, width, height);
    job.spp = spp;
    job.bounces = bounces;
    job.rgb = (float *)calloc(3 * (size_t)width * (size_t)height, sizeof(float));
    rgb8 = (unsigned char *)malloc(3 * (size_t)width * (size_t)height);
    if (!tracer || !pool || !job.rgb || !rgb8) { fprintf(stderr, "scene_view: out of memory\n"); return 1; }
    clock_gettime(CLOCK_MONOTONIC, &t0);
    ex_pool_parallel_for(pool, render_row, &job, (uint32_t)height);
    clock_gettime(CLOCK_MONOTONIC, &t1);
    ex_tonemap(job.rgb, width, height, ex_auto_exposure(job.rgb, width, height, 0.97f), rgb8);
    snprintf(path, sizeof path, "%s/%.*s.png", out, (int)(strcspn(name, ".")), name);
    if (ex_write_png(path, width, height, rgb8) != 0) {
        fprintf(stderr, "scene_view: cannot write %s (does the directory exist?)\n", path);
        return 1;
    }
    printf("scene_view: %s: %u triangles, %u materials; %dx%d, %d samples per pixel, %d bounce(s), "
           "%d threads, %.2f s; wrote %s\n",
           scene_path, scene.tri_count, scene.material_count, width, height, spp, bounces,
           ex_pool_threads(pool), (double)(t1.tv_sec - t0.tv_sec) + 1e-9 * (double)(t1.tv_nsec - t0.tv_nsec), path);
    ex_pool_destroy(pool);
    ex_tracer_destroy(tracer);
    free(job.rgb);
    free(rgb8);
    obj_free(&scene);
    return 0;
}
