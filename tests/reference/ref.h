/* ref.h - the project's reference renderer: Embree ray casting and Monte Carlo
   estimates with standard errors, EXR images, and the LRMS metric. Used only
   by tests and benchmarks (the headers never need Embree or OpenEXR).

   What it answers:
   (a) ref_irradiance_field: irradiance at a point and normal for a scene whose
       surfaces have a known outgoing diffuse radiance (per triangle, or from a
       callback), cosine-weighted hemisphere sampling.
   (b) ref_irradiance_gi / ref_radiosity_average: irradiance (and patch-average
       radiosity) from emitters and diffuse interreflection, path traced with
       next-event estimation and Russian roulette (unbiased, all bounces).
   (c) ref_render: a path-traced image (Lambert + normalized Phong glossy, area
       lights from emissive triangles) for a pinhole camera.
   (b) and (c) see thin glass and a sky: a material's tf passes that share
   of the light straight through, from either side (a thin dielectric, no
   refraction: next-event rays are attenuated by every pane they cross,
   paths go through or reflect in proportion to tf against kd + ks), and
   ref_scene_set_sky gives the radiance of rays that leave the scene
   (examples/common/scene_sky.h: constant, or an environment map), found by
   the paths' own directions.

   Conventions, shared with the headers:
   - Surfaces are one-sided as in radiosity: a triangle's front is the side its
     counter-clockwise winding faces. Hits on a back face see black in (b) and
     (c) (no emission, no reflection). In (a) the per-triangle field applies
     to both sides; the callback receives the side and may do otherwise.
   - Material ke is emitted radiance in W/(m^2 sr) (a diffuse emitter's
     radiosity is pi * ke), kd the diffuse reflectance, ks and ns the
     normalized Phong lobe: f = kd/pi + ks (ns+2)/(2 pi) max(0, r.wi)^ns with r
     the mirror direction of the outgoing direction.
   - Radiosity B = pi * ke + kd * H; radiance of a diffuse surface = B / pi.
   - Every estimate carries its standard error (standard deviation of the
     mean, per channel), so tests set tolerances as k standard errors plus a
     stated bias allowance.

   Estimates are deterministic for a given seed: the samples are split into a
   fixed number of chunks, each with its own random stream, and run on a pool
   of threads (EX_THREADS, default: all cores). */
#ifndef TESTS_REFERENCE_REF_H
#define TESTS_REFERENCE_REF_H

#include <stdint.h>

#include "examples/common/obj.h"
#include "examples/common/scene_sky.h"

typedef struct ref_material {
    float kd[3];   /* diffuse reflectance */
    float ks[3];   /* glossy reflectance */
    float ns;      /* Phong exponent */
    float ke[3];   /* emitted radiance */
    float tf[3];   /* straight-through transmittance in [0, 1] (thin glass); 0 = opaque */
} ref_material;

typedef struct ref_scene ref_scene;

typedef struct ref_hit {
    float t;        /* distance in units of |dir| */
    float u, v;     /* barycentric weights of the 2nd and 3rd vertex (Embree's) */
    uint32_t tri;   /* triangle index; REF_NO_HIT when missed */
    int front;      /* 1 when the ray hit the triangle's front face */
} ref_hit;
#define REF_NO_HIT 0xFFFFFFFFu

typedef struct ref_estimate {
    double mean[3];
    double std_error[3];   /* standard error of the mean, per channel */
    uint64_t samples;
} ref_estimate;

typedef struct ref_camera {
    float eye[3], target[3], up[3];
    float vfov_degrees;
    int width, height;
} ref_camera;

/* Scene: triangles with per-triangle material indices (NULL: all material 0)
   and a material table (NULL: one grey diffuse material). Copies what it
   needs. Returns NULL on bad input (message on stderr). */
ref_scene *ref_scene_create(const float *positions, uint32_t vertex_count, const uint32_t *indices,
                            uint32_t tri_count, const uint32_t *tri_material,
                            const ref_material *materials, uint32_t material_count);
/* All triangles and materials of a loaded OBJ scene. */
ref_scene *ref_scene_from_obj(const obj_scene *s);
/* The radiance of rays that leave the scene in (b) and (c); NULL = black.
   The sky is copied; its map must outlive the scene. Returns 0, or -1 when
   the sky is invalid (ex_sky_valid). */
int ref_scene_set_sky(ref_scene *scene, const ex_sky *sky);
void ref_scene_destroy(ref_scene *scene);
uint32_t ref_scene_triangle_count(const ref_scene *scene);

/* Closest hit in (tnear, tfar) / any hit, through Embree. */
int ref_intersect(const ref_scene *scene, const float org[3], const float dir[3], float tnear,
                  float tfar, ref_hit *hit);
int ref_occluded(const ref_scene *scene, const float org[3], const float dir[3], float tnear,
                 float tfar);

/* (a) Irradiance at p for a surface with unit normal n, from outgoing radiance
   tri_radiance[3*tri] (rgb per triangle) on every surface and background
   radiance for rays that leave the scene (NULL = black). */
ref_estimate ref_irradiance_field(const ref_scene *scene, const float p[3], const float n[3],
                                  const float *tri_radiance, const float background[3],
                                  uint64_t samples, uint64_t seed);

/* (a) with radiance from a callback: hit is NULL for rays that leave the
   scene. Called concurrently from several threads. */
typedef void (*ref_radiance_fn)(void *user, const float org[3], const float dir[3],
                                const ref_hit *hit, float rgb[3]);
ref_estimate ref_irradiance_callback(const ref_scene *scene, const float p[3], const float n[3],
                                     ref_radiance_fn radiance, void *user, uint64_t samples,
                                     uint64_t seed);

/* (b) Irradiance at p (normal n) from emitters and diffuse interreflection:
   the emitted radiance seen directly plus all bounces of diffuse light. */
ref_estimate ref_irradiance_gi(const ref_scene *scene, const float p[3], const float n[3],
                               uint64_t samples, uint64_t seed);

/* (b) Area-average radiosity B = pi*ke + kd*H over a patch made of the given
   triangles (e.g. the two triangles of a quadrilateral). */
ref_estimate ref_radiosity_average(const ref_scene *scene, const uint32_t *tris, uint32_t count,
                                   uint64_t samples, uint64_t seed);

/* (c) Path-traced image, rows top to bottom, rgb floats. variance (optional,
   3 floats per pixel) receives the variance of each pixel's mean. spp samples
   per pixel. Returns 0, or -1 on bad arguments. */
int ref_render(const ref_scene *scene, const ref_camera *camera, uint32_t spp, uint64_t seed,
               float *rgb, float *variance);

/* (c) for diffuse transport only (ks ignored): the radiosity image, pixel =
   radiance B/pi of the first visible surface. */
int ref_render_diffuse(const ref_scene *scene, const ref_camera *camera, uint32_t spp,
                       uint64_t seed, float *rgb, float *variance);

/* EXR images (RGB float, scanline, ZIP): 0 on success. ref_exr_read returns a
   malloc'ed image (free() it) or NULL. */
int ref_exr_write(const char *path, int width, int height, const float *rgb);
float *ref_exr_read(const char *path, int *width, int *height);

/* Relative luminance RMS (Nimeroff, Dorsey and Rushmeier 1996): RMS of the
   per-pixel luminance difference divided by the mean luminance of reference. */
double ref_lrms(const float *reference, const float *image, int width, int height);
double ref_luminance(const float rgb[3]);

#endif /* TESTS_REFERENCE_REF_H */
