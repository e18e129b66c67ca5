/* irrvol_bunny.c - a bunny walking through the office, lit by an irradiance
   volume (Greger 1996, figures 5.3 and 5.4): it darkens as it goes under the
   desk and takes on a yellow tinge beside the divider.

       cc -O2 -I. examples/irrvol_bunny.c -o irrvol_bunny -lm -lpthread
       ./irrvol_bunny --out build/out

   Options: --out DIR, --data DIR (default examples/data), --size WxH
   (default 480x360), --frames N per walk (default 6).

   1. The office is cut into patches of at most 0.2 m and each patch vertex
      gets a radiance: its emission plus Kd/pi times the irradiance there,
      direct light from the lamp (area samples with shadow rays) plus one
      bounce (cosine rays), through the examples' ray tracer.
   2. irrvol builds the volume from that per-vertex radiance with its
      defaults (Greger's 7^3 first level and 3^3 second level, k = 17, the
      second level also where the light changes), the lamp IMPORTANT.
   3. Every frame the bunny's vertices query the volume (eq. 4.7: radiance =
      Kd H / pi) with the leak-safe default weighting, scaled by each
      vertex's self-occlusion ratio (thesis 6.1.3, computed once: it does not
      change as the bunny moves rigidly), and the software rasterizer draws
      the office and the bunny Gouraud-shaded. The walk past the divider is
      drawn a second time with the thesis's plain trilinear query: samples
      behind the 5 cm panel light the bunny through it.
   4. Light transfer (5.4): the same field split into its emitted (direct)
      and reflected (indirect) parts gives two more volumes whose sum is the
      full one (all on one grid: refined where geometry is), and a volume
      that IGNOREs the divider loses its colour bleeding.

   Writes irrvol_desk_NN.png, irrvol_divider_NN.png, irrvol_divider_plain_NN.png,
   contact sheets irrvol_desk.png, irrvol_divider.png, irrvol_divider_plain.png
   and irrvol_transfer.png. */
#define _POSIX_C_SOURCE 200809L /* clock_gettime */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>

#define IRRVOL_IMPLEMENTATION
#include "irrvol.h"

#include "examples/common/camera.h"
#include "examples/common/image.h"
#include "examples/common/obj.h"
#include "examples/common/pool.h"
#include "examples/common/raster.h"
#include "examples/common/trace.h"

#define PATCH_SIZE 0.2f       /* metres: the office's shading resolution */
#define DIRECT_SIDE 4         /* 4 x 4 area samples per emitting triangle */
#define INDIRECT_RAYS 1024    /* cosine rays per vertex for the bounce */
#define BUNNY_HEIGHT 0.3f     /* metres */
#define BUNNY_KD 0.6f

static double now(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

/* ---- the office cut into patches ----------------------------------------- */

typedef struct mesh {
    float *pos, *normal;      /* per vertex */
    uint32_t *vertex_material;
    uint32_t *idx, *tri_material, vertex_count, tri_count;
} mesh;

static void mesh_free(mesh *m)
{
    free(m->pos); free(m->normal); free(m->vertex_material); free(m->idx); free(m->tri_material);
    memset(m, 0, sizeof *m);
}

static float dist3(const float *a, const float *b)
{
    float d[3] = {a[0] - b[0], a[1] - b[1], a[2] - b[2]};
    return sqrtf(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
}

/* Quadrilateral faces become grids of patches (bilinear), other faces stay
   fans. Every face keeps its own vertices and its winding's normal. */
static int subdivide(const obj_scene *s, mesh *m)
{
    uint32_t f, nv = 0, nt = 0, pass;
    for (pass = 0; pass < 2; pass++) {
        if (pass == 1) {
            m->pos = (float *)malloc(3 * sizeof(float) * nv);
            m->normal = (float *)malloc(3 * sizeof(float) * nv);
            m->vertex_material = (uint32_t *)malloc(sizeof(uint32_t) * nv);
            m->idx = (uint32_t *)malloc(3 * sizeof(uint32_t) * nt);
            m->tri_material = (uint32_t *)malloc(sizeof(uint32_t) * nt);
            if (!m->pos || !m->normal || !m->vertex_material || !m->idx || !m->tri_material) return -1;
            m->vertex_count = m->tri_count = 0;
        }
        nv = nt = 0;
        for (f = 0; f < s->face_count; f++) {
            const uint32_t *fv = s->face_vertices + s->face_start[f];
            uint32_t count = s->face_start[f + 1] - s->face_start[f], i, j, nu = 1, nw = 1;
            const float *p[4];
            float e1[3], e2[3], n[3], l;
            int k;
            for (i = 0; i < 3; i++) p[i] = s->positions + 3 * (size_t)fv[i];
            for (k = 0; k < 3; k++) { e1[k] = p[1][k] - p[0][k]; e2[k] = p[2][k] - p[0][k]; }
            n[0] = e1[1] * e2[2] - e1[2] * e2[1];
            n[1] = e1[2] * e2[0] - e1[0] * e2[2];
            n[2] = e1[0] * e2[1] - e1[1] * e2[0];
            l = sqrtf(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
            if (l > 0.0f) { n[0] /= l; n[1] /= l; n[2] /= l; }
            if (count == 4) {
                p[3] = s->positions + 3 * (size_t)fv[3];
                nu = (uint32_t)ceilf(dist3(p[0], p[1]) / PATCH_SIZE);
                nw = (uint32_t)ceilf(dist3(p[1], p[2]) / PATCH_SIZE);
                nu = nu < 1 ? 1 : nu;
                nw = nw < 1 ? 1 : nw;
                if (pass == 1) {
                    uint32_t base = m->vertex_count;
                    for (j = 0; j <= nw; j++)
                        for (i = 0; i <= nu; i++) {
                            float a = (float)i / (float)nu, b = (float)j / (float)nw;
                            float *q = m->pos + 3 * (size_t)m->vertex_count;
                            for (k = 0; k < 3; k++)
                                q[k] = (1 - a) * (1 - b) * p[0][k] + a * (1 - b) * p[1][k] + a * b * p[2][k] +
                                       (1 - a) * b * p[3][k];
                            memcpy(m->normal + 3 * (size_t)m->vertex_count, n, sizeof n);
                            m->vertex_material[m->vertex_count++] = s->face_material[f];
                        }
                    for (j = 0; j < nw; j++)
                        for (i = 0; i < nu; i++) {
                            uint32_t v00 = base + j * (nu + 1) + i, v10 = v00 + 1, v01 = v00 + nu + 1, v11 = v01 + 1;
                            uint32_t *t = m->idx + 3 * (size_t)m->tri_count;
                            t[0] = v00; t[1] = v10; t[2] = v11; t[3] = v00; t[4] = v11; t[5] = v01;
                            m->tri_material[m->tri_count] = m->tri_material[m->tri_count + 1] = s->face_material[f];
                            m->tri_count += 2;
                        }
                }
                nv += (nu + 1) * (nw + 1);
                nt += 2 * nu * nw;
            } else {
                if (pass == 1) {
                    uint32_t base = m->vertex_count;
                    for (i = 0; i < count; i++) {
                        memcpy(m->pos + 3 * (size_t)m->vertex_count, s->positions + 3 * (size_t)fv[i], 3 * sizeof(float));
                        memcpy(m->normal + 3 * (size_t)m->vertex_count, n, sizeof n);
                        m->vertex_material[m->vertex_count++] = s->face_material[f];
                    }
                    for (i = 1; i + 1 < count; i++) {
                        uint32_t *t = m->idx + 3 * (size_t)m->tri_count;
                        t[0] = base; t[1] = base + i; t[2] = base + i + 1;
                        m->tri_material[m->tri_count++] = s->face_material[f];
                    }
                }
                nv += count;
                nt += count - 2;
            }
        }
    }
    return 0;
}

/* ---- the office's radiance: emission + Kd/pi (direct + one bounce) ------ */

typedef struct radiance_job {
    const obj_scene *office;
    const ex_tracer *tracer;
    const mesh *m;
    float *emitted, *reflected;   /* rgb per vertex */
} radiance_job;

static int is_emitter(const obj_material *mt) { return mt->ke[0] > 0.0f || mt->ke[1] > 0.0f || mt->ke[2] > 0.0f; }

/* Irradiance from the emitting triangles: stratified points on each, shadow
   rays, emitters one-sided (they light the side their winding faces). */
static void direct_irradiance(const radiance_job *j, const float p[3], const float n[3], ex_rng *r, float e[3])
{
    const obj_scene *s = j->office;
    uint32_t t;
    e[0] = e[1] = e[2] = 0.0f;
    for (t = 0; t < s->tri_count; t++) {
        const obj_material *mt = &s->materials[s->tri_material[t]];
        const float *a, *b, *c;
        float e1[3], e2[3], ln[3], area2;
        int x, y, k;
        if (!is_emitter(mt)) continue;
        a = s->positions + 3 * (size_t)s->tri_indices[3 * t];
        b = s->positions + 3 * (size_t)s->tri_indices[3 * t + 1];
        c = s->positions + 3 * (size_t)s->tri_indices[3 * t + 2];
        for (k = 0; k < 3; k++) { e1[k] = b[k] - a[k]; e2[k] = c[k] - a[k]; }
        ln[0] = e1[1] * e2[2] - e1[2] * e2[1];
        ln[1] = e1[2] * e2[0] - e1[0] * e2[2];
        ln[2] = e1[0] * e2[1] - e1[1] * e2[0];
        area2 = sqrtf(ln[0] * ln[0] + ln[1] * ln[1] + ln[2] * ln[2]);
        if (!(area2 > 0.0f)) continue;
        for (k = 0; k < 3; k++) ln[k] /= area2;
        for (y = 0; y < DIRECT_SIDE; y++)
            for (x = 0; x < DIRECT_SIDE; x++) {
                float u1 = ((float)x + ex_rng_float(r)) / DIRECT_SIDE, u2 = ((float)y + ex_rng_float(r)) / DIRECT_SIDE;
                float sq = sqrtf(u1), q[3], w[3], d2, d, cx, cy, g;
                for (k = 0; k < 3; k++) q[k] = (1 - sq) * a[k] + sq * (1 - u2) * b[k] + sq * u2 * c[k];
                for (k = 0; k < 3; k++) w[k] = q[k] - p[k];
                d2 = w[0] * w[0] + w[1] * w[1] + w[2] * w[2];
                d = sqrtf(d2);
                for (k = 0; k < 3; k++) w[k] /= d;
                cx = w[0] * n[0] + w[1] * n[1] + w[2] * n[2];
                cy = -(w[0] * ln[0] + w[1] * ln[1] + w[2] * ln[2]);
                if (cx <= 0.0f || cy <= 0.0f || ex_tracer_occluded(j->tracer, p, w, d * 0.999f)) continue;
                g = cx * cy / d2 * 0.5f * area2 / (DIRECT_SIDE * DIRECT_SIDE);
                for (k = 0; k < 3; k++) e[k] += mt->ke[k] * g;
            }
    }
}

static void radiance_vertex(void *ctx, uint32_t v)
{
    const radiance_job *j = (const radiance_job *)ctx;
    const float *n = j->m->normal + 3 * (size_t)v;
    float p[3], e[3], ind[3] = {0, 0, 0}, t[3], b[3];
    uint32_t i, mat = j->m->vertex_material[v];
    ex_rng r = ex_rng_stream(2024, v);
    int k;
    for (k = 0; k < 3; k++) p[k] = j->m->pos[3 * (size_t)v + k] + 1e-3f * n[k];
    direct_irradiance(j, p, n, &r, e);
    /* one bounce: the radiance of what cosine rays see, without its emission */
    if (fabsf(n[0]) > 0.5f) { t[0] = 0; t[1] = 1; t[2] = 0; } else { t[0] = 1; t[1] = 0; t[2] = 0; }
    b[0] = n[1] * t[2] - n[2] * t[1]; b[1] = n[2] * t[0] - n[0] * t[2]; b[2] = n[0] * t[1] - n[1] * t[0];
    {
        float l = sqrtf(b[0] * b[0] + b[1] * b[1] + b[2] * b[2]);
        for (k = 0; k < 3; k++) b[k] /= l;
        t[0] = b[1] * n[2] - b[2] * n[1]; t[1] = b[2] * n[0] - b[0] * n[2]; t[2] = b[0] * n[1] - b[1] * n[0];
    }
    for (i = 0; i < INDIRECT_RAYS; i++) {
        float u1 = ex_rng_float(&r), u2 = ex_rng_float(&r), rad = sqrtf(u1), phi = 6.2831853f * u2, z = sqrtf(1 - u1);
        float dir[3], rgb[3];
        ex_trace_hit hit;
        for (k = 0; k < 3; k++) dir[k] = rad * cosf(phi) * t[k] + rad * sinf(phi) * b[k] + z * n[k];
        if (!ex_tracer_shade(j->tracer, p, dir, 0, &r, rgb, &hit) || hit.tri == 0xFFFFFFFFu) continue;
        if (hit.front) {
            const float *ke = j->office->materials[j->office->tri_material[hit.tri]].ke;
            for (k = 0; k < 3; k++) rgb[k] -= ke[k];
        }
        for (k = 0; k < 3; k++) ind[k] += rgb[k];
    }
    for (k = 0; k < 3; k++) {
        const obj_material *mt = &j->office->materials[mat];
        float h = e[k] + 3.14159265f * ind[k] / INDIRECT_RAYS;
        j->emitted[3 * (size_t)v + k] = mt->ke[k];
        j->reflected[3 * (size_t)v + k] = mt->kd[k] * h / 3.14159265f;
    }
}

/* ---- the bunny -------------------------------------------------------------- */

typedef struct bunny {
    float *pos, *normal;      /* object space: feet at y = 0, centred, BUNNY_HEIGHT tall */
    float *visibility;        /* self-occlusion ratio per vertex */
    float *world_pos, *world_normal, *rgb;
    uint32_t *idx, vertex_count, tri_count;
} bunny;

static int bunny_load(const char *path, bunny *b, ex_pool *pool)
{
    obj_scene s;
    char err[256];
    float lo[3], hi[3], scale;
    irrvol_visibility_desc vd;
    uint32_t v;
    if (obj_load(path, &s, err, sizeof err) != 0) { fprintf(stderr, "%s\n", err); return -1; }
    obj_bounds(&s, lo, hi);
    scale = BUNNY_HEIGHT / (hi[1] - lo[1]);
    b->vertex_count = s.vertex_count;
    b->tri_count = s.tri_count;
    b->pos = (float *)malloc(3 * sizeof(float) * s.vertex_count);
    b->normal = (float *)malloc(3 * sizeof(float) * s.vertex_count);
    b->visibility = (float *)malloc(sizeof(float) * s.vertex_count);
    b->world_pos = (float *)malloc(3 * sizeof(float) * s.vertex_count);
    b->world_normal = (float *)malloc(3 * sizeof(float) * s.vertex_count);
    b->rgb = (float *)malloc(3 * sizeof(float) * s.vertex_count);
    b->idx = (uint32_t *)malloc(3 * sizeof(uint32_t) * s.tri_count);
    if (!b->pos || !b->normal || !b->visibility || !b->world_pos || !b->world_normal || !b->rgb || !b->idx) return -1;
    for (v = 0; v < s.vertex_count; v++) {
        b->pos[3 * v] = scale * (s.positions[3 * v] - 0.5f * (lo[0] + hi[0]));
        b->pos[3 * v + 1] = scale * (s.positions[3 * v + 1] - lo[1]);
        b->pos[3 * v + 2] = scale * (s.positions[3 * v + 2] - 0.5f * (lo[2] + hi[2]));
    }
    obj_vertex_normals(&s, b->normal);
    memcpy(b->idx, s.tri_indices, 3 * sizeof(uint32_t) * s.tri_count);
    obj_free(&s);
    memset(&vd, 0, sizeof vd);   /* 6.1.3: the open part of each vertex's hemisphere */
    vd.positions = b->pos;
    vd.vertex_count = b->vertex_count;
    vd.indices = b->idx;
    vd.triangle_count = b->tri_count;
    vd.normals = b->normal;
    vd.rays = 256;
    vd.parallel_for = ex_pool_parallel_for;
    vd.parallel_user = pool;
    return irrvol_visibility_ratio(&vd, b->visibility) == IRRVOL_OK ? 0 : -1;
}

static void bunny_free(bunny *b)
{
    free(b->pos); free(b->normal); free(b->visibility); free(b->world_pos); free(b->world_normal); free(b->rgb); free(b->idx);
}

/* Places the bunny at (x, 0, z) turned by yaw and lights its vertices from
   the volume: Kd H / pi (eq. 4.7) times the self-occlusion ratio. */
static double bunny_light(bunny *b, const irrvol *vol, irrvol_weighting weighting, float x, float z, float yaw)
{
    float c = cosf(yaw), s = sinf(yaw);
    double t0;
    uint32_t v;
    for (v = 0; v < b->vertex_count; v++) {
        const float *p = b->pos + 3 * v, *n = b->normal + 3 * v;
        float *wp = b->world_pos + 3 * v, *wn = b->world_normal + 3 * v;
        wp[0] = x + c * p[0] + s * p[2]; wp[1] = p[1]; wp[2] = z - s * p[0] + c * p[2];
        wn[0] = c * n[0] + s * n[2];     wn[1] = n[1]; wn[2] = -s * n[0] + c * n[2];
    }
    t0 = now();
    irrvol_query_many(vol, IRRVOL_FILTER_DEFAULT, weighting, b->vertex_count, b->world_pos, 0, b->world_normal, 0, b->rgb);
    t0 = now() - t0;
    for (v = 0; v < 3 * b->vertex_count; v++) b->rgb[v] *= BUNNY_KD / 3.14159265f * b->visibility[v / 3];
    return t0;
}

/* ---- frames ----------------------------------------------------------------- */

typedef struct scene {
    mesh office;
    float *office_rgb;        /* displayed radiance per office vertex */
    bunny rabbit;
    ex_raster raster;
    float *image;
    unsigned char *bytes;
    int width, height;
    float exposure;
} scene;

/* Draws the office and the bunny Gouraud-shaded into s->bytes. */
static int draw(scene *s, const ex_camera *cam)
{
    size_t n = (size_t)s->width * (size_t)s->height, p;
    ex_raster_clear(&s->raster);
    if (ex_raster_draw(&s->raster, cam, s->office.pos, s->office.idx, s->office.tri_count, 0) != 0 ||
        ex_raster_draw(&s->raster, cam, s->rabbit.world_pos, s->rabbit.idx, s->rabbit.tri_count, s->office.tri_count) != 0)
        return -1;
    for (p = 0; p < 3 * n; p++) s->image[p] = 0.0f;
    ex_raster_resolve_gouraud(&s->raster, s->office.idx, s->office.tri_count, 0, s->office_rgb, s->image);
    ex_raster_resolve_gouraud(&s->raster, s->rabbit.idx, s->rabbit.tri_count, s->office.tri_count, s->rabbit.rgb, s->image);
    if (s->exposure <= 0.0f) s->exposure = ex_auto_exposure(s->image, s->width, s->height, 0.97f);
    ex_tonemap(s->image, s->width, s->height, s->exposure, s->bytes);
    return 0;
}

typedef struct walk {
    const char *name;          /* the images' name */
    float eye[3], target[3];
    float from[2], to[2];      /* bunny path on the floor (x, z) */
    float yaw;
} walk;

static int run_walk(scene *s, const irrvol *vol, irrvol_weighting weighting, const walk *w, int frames, const char *out)
{
    ex_camera cam;
    static const float up[3] = {0, 1, 0};
    unsigned char **shots = (unsigned char **)calloc((size_t)frames, sizeof *shots), *sheet;
    size_t bytes = 3 * (size_t)s->width * (size_t)s->height;
    char path[1024];
    double query_time = 0.0;
    printf("%s walk, mean bunny radiance per frame:", w->name);
    int f, columns = frames < 3 ? frames : 3, rows = (frames + columns - 1) / columns, rc = 0;
    cam = ex_camera_look_at(w->eye, w->target, up, 55.0f, s->width, s->height);
    for (f = 0; f < frames && rc == 0; f++) {
        float a = frames > 1 ? (float)f / (float)(frames - 1) : 0.0f;
        query_time += bunny_light(&s->rabbit, vol, weighting, w->from[0] + a * (w->to[0] - w->from[0]),
                                  w->from[1] + a * (w->to[1] - w->from[1]), w->yaw);
        {
            double sum[3] = {0, 0, 0};
            uint32_t v;
            for (v = 0; v < s->rabbit.vertex_count; v++) {
                sum[0] += s->rabbit.rgb[3 * v]; sum[1] += s->rabbit.rgb[3 * v + 1]; sum[2] += s->rabbit.rgb[3 * v + 2];
            }
            printf(" (%.3f %.3f %.3f)", sum[0] / s->rabbit.vertex_count, sum[1] / s->rabbit.vertex_count,
                   sum[2] / s->rabbit.vertex_count);
        }
        if (draw(s, &cam) != 0) { rc = -1; break; }
        snprintf(path, sizeof path, "%s/irrvol_%s_%02d.png", out, w->name, f);
        if (ex_write_png(path, s->width, s->height, s->bytes) != 0) { fprintf(stderr, "cannot write %s\n", path); rc = -1; }
        shots[f] = (unsigned char *)malloc(bytes);
        if (shots[f]) memcpy(shots[f], s->bytes, bytes);
    }
    if (rc == 0) {
        sheet = (unsigned char *)malloc(bytes * (size_t)(columns * rows));
        ex_contact_sheet((const unsigned char *const *)shots, frames, s->width, s->height, columns, sheet);
        snprintf(path, sizeof path, "%s/irrvol_%s.png", out, w->name);
        if (ex_write_png(path, columns * s->width, rows * s->height, sheet) != 0) rc = -1;
        printf("\n%s walk: %d frames, %u queries each, %.1f us of queries per frame -> %s\n", w->name, frames,
               s->rabbit.vertex_count, 1e6 * query_time / frames, path);
        free(sheet);
    }
    for (f = 0; f < frames; f++) free(shots[f]);
    free(shots);
    return rc;
}

/* ---- volumes ---------------------------------------------------------------- */

static irrvol *build_volume(const mesh *m, const float *vertex_radiance, irrvol_material *mats, uint32_t nmat,
                            float refine_threshold, ex_pool *pool, const char *label)
{
    irrvol_desc d;
    irrvol *vol = NULL;
    irrvol_volume_info info;
    irrvol_result r;
    double t0 = now();
    memset(&d, 0, sizeof d);
    d.positions = m->pos;
    d.vertex_count = m->vertex_count;
    d.indices = m->idx;
    d.triangle_count = m->tri_count;
    d.triangle_materials = m->tri_material;
    d.materials = mats;
    d.material_count = nmat;
    d.vertex_radiance = vertex_radiance;
    d.refine_threshold = refine_threshold;   /* 0: the default; negative: where geometry is only */
    d.parallel_for = ex_pool_parallel_for;
    d.parallel_user = pool;
    r = irrvol_build(&d, &vol);
    if (r != IRRVOL_OK) { fprintf(stderr, "irrvol_build: %s\n", irrvol_result_string(r)); return NULL; }
    irrvol_info(vol, &info);
    printf("volume %-22s %u samples (%u second level, %u refined cells, %u for light; %u moved out of geometry, %u "
           "invalid), %u bins, %.1f Mrays, %.2f s, %.1f MB\n", label, info.sample_count, info.second_level_samples,
           info.refined_cells, info.light_refined_cells, info.relocated_samples, info.invalid_samples, info.bins,
           info.rays / 1e6, now() - t0, info.bytes / 1e6);
    return vol;
}

int main(int argc, char **argv)
{
    const char *out = "build/out", *data = "examples/data";
    char path[1024], err[256];
    int frames = 6, i, rc = 1;
    obj_scene office;
    ex_tracer *tracer = NULL;
    ex_pool *pool = ex_pool_create(0);
    scene s;
    radiance_job job;
    irrvol_material *mats = NULL;
    irrvol *full = NULL, *same_grid = NULL, *direct = NULL, *indirect = NULL, *no_divider = NULL;
    float *total = NULL;
    uint32_t v, m;
    double t0;
    static const walk desk = {"desk", {1.8f, 1.0f, 0.7f}, {1.8f, 0.3f, 3.0f}, {1.8f, 1.7f}, {1.8f, 3.35f}, 1.5708f};
    /* along the divider's lit face, seen from ahead so that its divider side shows */
    static const walk divider = {"divider", {3.1f, 0.6f, 3.25f}, {3.5f, 0.12f, 1.6f}, {3.42f, 0.8f}, {3.42f, 2.4f}, -0.6f};
    walk divider_plain = divider;
    memset(&s, 0, sizeof s);
    memset(&job, 0, sizeof job);
    s.width = 480;
    s.height = 360;
    for (i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--out") && i + 1 < argc) out = argv[++i];
        else if (!strcmp(argv[i], "--data") && i + 1 < argc) data = argv[++i];
        else if (!strcmp(argv[i], "--frames") && i + 1 < argc) frames = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--size") && i + 1 < argc) {
            if (sscanf(argv[++i], "%dx%d", &s.width, &s.height) != 2) s.width = 0;
        } else {
            fprintf(stderr, "usage: %s [--out DIR] [--data DIR] [--size WxH] [--frames N]\n", argv[0]);
            return 2;
        }
    }
    if (frames < 1 || frames > 64 || s.width < 16 || s.height < 16 || s.width > 8192 || s.height > 8192) {
        fprintf(stderr, "bad --frames or --size\n");
        return 2;
    }
    mkdir(out, 0755);   /* may exist already; writing a frame reports a real problem */
    snprintf(path, sizeof path, "%s/office.obj", data);
    if (obj_load(path, &office, err, sizeof err) != 0) { fprintf(stderr, "%s\n", err); return 1; }
    tracer = ex_tracer_create(&office);
    snprintf(path, sizeof path, "%s/bunny.obj", data);
    if (!tracer || subdivide(&office, &s.office) != 0 || bunny_load(path, &s.rabbit, pool) != 0) goto done;

    /* 1. the office's radiance at every patch vertex */
    t0 = now();
    job.office = &office;
    job.tracer = tracer;
    job.m = &s.office;
    job.emitted = (float *)calloc(3 * (size_t)s.office.vertex_count, sizeof(float));
    job.reflected = (float *)calloc(3 * (size_t)s.office.vertex_count, sizeof(float));
    total = (float *)malloc(3 * sizeof(float) * s.office.vertex_count);
    if (!job.emitted || !job.reflected || !total) goto done;
    ex_pool_parallel_for(pool, radiance_vertex, &job, s.office.vertex_count);
    for (v = 0; v < 3 * s.office.vertex_count; v++) total[v] = job.emitted[v] + job.reflected[v];
    s.office_rgb = total;
    printf("office: %u patch vertices, %u triangles; radiance (direct + one bounce) in %.2f s\n", s.office.vertex_count,
           s.office.tri_count, now() - t0);

    /* 2. the volumes: full, and for light transfer (5.4) full, direct, indirect
          and no divider on one grid, refined where geometry is */
    mats = (irrvol_material *)calloc(office.material_count, sizeof *mats);
    if (!mats) goto done;
    for (m = 0; m < office.material_count; m++)
        if (is_emitter(&office.materials[m])) mats[m].flags = IRRVOL_MATERIAL_IMPORTANT;   /* the lamp: never missed */
    full = build_volume(&s.office, total, mats, office.material_count, 0.0f, pool, "(full, defaults)");
    same_grid = build_volume(&s.office, total, mats, office.material_count, -1.0f, pool, "(full)");
    direct = build_volume(&s.office, job.emitted, mats, office.material_count, -1.0f, pool, "(emitted: direct)");
    indirect = build_volume(&s.office, job.reflected, mats, office.material_count, -1.0f, pool, "(reflected: indirect)");
    i = obj_find_material(&office, "yellow");
    if (i >= 0) mats[i].flags |= IRRVOL_MATERIAL_IGNORE;
    no_divider = build_volume(&s.office, total, mats, office.material_count, -1.0f, pool, "(divider ignored)");
    if (!full || !same_grid || !direct || !indirect || !no_divider) goto done;

    /* 3. the walks of figures 5.3 and 5.4 */
    if (ex_raster_init(&s.raster, s.width, s.height) != 0) goto done;
    s.raster.pool = pool;
    s.image = (float *)malloc(3 * sizeof(float) * (size_t)s.width * (size_t)s.height);
    s.bytes = (unsigned char *)malloc(3 * (size_t)s.width * (size_t)s.height);
    if (!s.image || !s.bytes) goto done;
    if (run_walk(&s, full, IRRVOL_WEIGHTING_DEFAULT, &desk, frames, out) != 0) goto done;
    if (run_walk(&s, full, IRRVOL_WEIGHTING_DEFAULT, &divider, frames, out) != 0) goto done;
    divider_plain.name = "divider_plain";
    if (run_walk(&s, full, IRRVOL_WEIGHTING_TRILINEAR, &divider_plain, frames, out) != 0) goto done;

    /* 4. light transfer: the bunny beside the divider under four volumes */
    {
        double facing[4][3];
        const irrvol *vols[4];
        const char *names[4] = {"full", "direct only", "indirect only", "divider ignored"};
        unsigned char *shots[4] = {NULL, NULL, NULL, NULL}, *sheet;
        int failed = 0;
        size_t bytes = 3 * (size_t)s.width * (size_t)s.height;
        ex_camera cam;
        static const float up[3] = {0, 1, 0};
        double worst = 0.0;
        float *h = (float *)malloc(3 * 3 * sizeof(float) * s.rabbit.vertex_count);
        vols[0] = same_grid; vols[1] = direct; vols[2] = indirect; vols[3] = no_divider;
        cam = ex_camera_look_at(divider.eye, divider.target, up, 55.0f, s.width, s.height);
        for (i = 0; i < 4; i++) {
            bunny_light(&s.rabbit, vols[i], IRRVOL_WEIGHTING_DEFAULT, 3.42f, 2.1f, divider.yaw);
            if (h && i < 3) memcpy(h + 3 * (size_t)i * s.rabbit.vertex_count, s.rabbit.rgb, 3 * sizeof(float) * s.rabbit.vertex_count);
            {   /* the mean colour of the vertices that face the divider (+x) */
                uint32_t count = 0;
                facing[i][0] = facing[i][1] = facing[i][2] = 0.0;
                for (v = 0; v < s.rabbit.vertex_count; v++)
                    if (s.rabbit.world_normal[3 * v] > 0.5f) {
                        int k;
                        for (k = 0; k < 3; k++) facing[i][k] += s.rabbit.rgb[3 * v + (uint32_t)k];
                        count++;
                    }
                for (v = 0; v < 3 && count; v++) facing[i][v] /= count;
            }
            shots[i] = (unsigned char *)malloc(bytes);
            if (draw(&s, &cam) != 0 || !shots[i]) { failed = 1; break; }
            memcpy(shots[i], s.bytes, bytes);
            printf("transfer %d: bunny lit by the %s volume\n", i, names[i]);
        }
        for (v = 0; h && v < 3 * s.rabbit.vertex_count; v++) {   /* full = direct + indirect */
            double d = fabs(h[v] - h[3 * s.rabbit.vertex_count + v] - h[6 * s.rabbit.vertex_count + v]);
            if (h[v] > 0.0f && d / h[v] > worst) worst = d / h[v];
        }
        printf("direct + indirect = full at every bunny vertex within %.2g (relative)\n", worst);
        printf("bunny vertices facing the divider, mean radiance: full (%.4f %.4f %.4f), divider ignored "
               "(%.4f %.4f %.4f): blue/red %.2f vs %.2f\n", facing[0][0], facing[0][1], facing[0][2], facing[3][0],
               facing[3][1], facing[3][2], facing[0][2] / facing[0][0], facing[3][2] / facing[3][0]);
        sheet = failed ? NULL : (unsigned char *)malloc(4 * bytes);
        if (sheet) {
            ex_contact_sheet((const unsigned char *const *)shots, 4, s.width, s.height, 2, sheet);
            snprintf(path, sizeof path, "%s/irrvol_transfer.png", out);
            if (ex_write_png(path, 2 * s.width, 2 * s.height, sheet) == 0) printf("transfer sheet -> %s\n", path);
            else failed = 1;
        }
        for (i = 0; i < 4; i++) free(shots[i]);
        free(sheet);
        free(h);
        if (failed || !sheet) goto done;
    }
    rc = 0;
done:
    if (rc) fprintf(stderr, "irrvol_bunny failed (is %s writable? run from the repository root)\n", out);
    irrvol_destroy(full); irrvol_destroy(same_grid); irrvol_destroy(direct); irrvol_destroy(indirect);
    irrvol_destroy(no_divider);
    free(mats); free(total); free(job.emitted); free(job.reflected);
    free(s.image); free(s.bytes);
    ex_raster_free(&s.raster);
    bunny_free(&s.rabbit);
    mesh_free(&s.office);
    ex_tracer_destroy(tracer);
    obj_free(&office);
    ex_pool_destroy(pool);
    return rc;
}
