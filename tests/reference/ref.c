/* ref.c - Embree-based Monte Carlo reference renderer (see ref.h). */
#include "tests/reference/ref.h"

#include <embree3/rtcore.h>
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "examples/common/pool.h"

#define REF_PI 3.14159265358979323846
#define REF_CHUNKS 64         /* fixed split of the samples: results do not depend on threads */
#define REF_MIN_BOUNCES 3     /* Russian roulette starts after this many bounces */
#define REF_MAX_BOUNCES 256   /* a safety net; roulette ends paths long before */
#define REF_MAX_PASSES 64     /* panes a next-event ray crosses before it counts as blocked */

typedef struct ref_vec { double x, y, z; } ref_vec;

struct ref_scene {
    RTCDevice device;
    RTCScene rtc;
    float *positions;
    uint32_t *indices;
    uint32_t tri_count;
    ref_vec *normal;          /* unit geometric normal per triangle (from the winding) */
    double *area;
    uint32_t *tri_material;
    ref_material *materials;
    uint32_t material_count;
    uint32_t *emitters;       /* triangles with emission */
    double *emitter_cdf;      /* by power: area * luminance(ke) */
    uint32_t emitter_count;
    double emitter_power;
    double epsilon;           /* ray offset, relative to the scene size */
    int has_glass;            /* some material has tf > 0 */
    int has_sky;
    ex_sky sky;
    ex_pool *pool;
};

/* ---- small math and random numbers ------------------------------------- */

static ref_vec rv(double x, double y, double z) { ref_vec r; r.x = x; r.y = y; r.z = z; return r; }
static ref_vec rv_load(const float *p) { return rv(p[0], p[1], p[2]); }
static ref_vec rv_add(ref_vec a, ref_vec b) { return rv(a.x + b.x, a.y + b.y, a.z + b.z); }
static ref_vec rv_sub(ref_vec a, ref_vec b) { return rv(a.x - b.x, a.y - b.y, a.z - b.z); }
static ref_vec rv_scale(ref_vec a, double s) { return rv(a.x * s, a.y * s, a.z * s); }
static double rv_dot(ref_vec a, ref_vec b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
static ref_vec rv_cross(ref_vec a, ref_vec b)
{
    return rv(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}
static ref_vec rv_normalize(ref_vec a)
{
    double l = sqrt(rv_dot(a, a));
    return l > 0 ? rv_scale(a, 1.0 / l) : a;
}

/* An orthonormal basis around unit n (Duff et al. 2017). */
static void rv_basis(ref_vec n, ref_vec *t, ref_vec *b)
{
    double s = n.z >= 0 ? 1.0 : -1.0, a = -1.0 / (s + n.z), c = n.x * n.y * a;
    *t = rv(1.0 + s * n.x * n.x * a, s * c, -s * n.x);
    *b = rv(c, s + n.y * n.y * a, -n.y);
}

typedef struct ref_rng { uint64_t state; } ref_rng;

static uint64_t ref_mix64(uint64_t z)
{
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}
static ref_rng ref_rng_stream(uint64_t seed, uint64_t stream)
{
    ref_rng r;
    r.state = ref_mix64(seed + 0x9E3779B97F4A7C15ull) ^ ref_mix64(stream * 0xD1B54A32D192ED03ull + 1u);
    return r;
}
static double ref_rand(ref_rng *r)
{
    r->state += 0x9E3779B97F4A7C15ull;
    return (double)(ref_mix64(r->state) >> 11) * (1.0 / 9007199254740992.0);
}

/* Cosine-weighted direction around n: pdf = cos / pi. */
static ref_vec ref_sample_cosine(ref_vec n, ref_rng *r)
{
    double u = ref_rand(r), v = ref_rand(r), rad = sqrt(u), phi = 2 * REF_PI * v;
    ref_vec t, b;
    rv_basis(n, &t, &b);
    return rv_add(rv_add(rv_scale(t, rad * cos(phi)), rv_scale(b, rad * sin(phi))),
                  rv_scale(n, sqrt(1.0 > u ? 1.0 - u : 0.0)));
}

/* Phong lobe cos^ns around axis: pdf = (ns+1)/(2 pi) cos^ns. */
static ref_vec ref_sample_phong(ref_vec axis, double ns, ref_rng *r)
{
    double u = ref_rand(r), v = ref_rand(r);
    double c = pow(u, 1.0 / (ns + 1.0)), s = sqrt(1.0 > c * c ? 1.0 - c * c : 0.0), phi = 2 * REF_PI * v;
    ref_vec t, b;
    rv_basis(axis, &t, &b);
    return rv_add(rv_add(rv_scale(t, s * cos(phi)), rv_scale(b, s * sin(phi))), rv_scale(axis, c));
}

double ref_luminance(const float rgb[3])
{
    return 0.2126 * rgb[0] + 0.7152 * rgb[1] + 0.0722 * rgb[2];
}

/* ---- scene ---------------------------------------------------------------- */

static int ref_finite(float x) { return x == x && x <= FLT_MAX && x >= -FLT_MAX; }

static int ref_build_emitters(ref_scene *s)
{
    uint32_t i, n = 0;
    double sum = 0;
    s->emitters = (uint32_t *)malloc(sizeof(uint32_t) * (s->tri_count ? s->tri_count : 1));
    s->emitter_cdf = (double *)malloc(sizeof(double) * (s->tri_count ? s->tri_count : 1));
    if (!s->emitters || !s->emitter_cdf) return -1;
    for (i = 0; i < s->tri_count; i++) {
        double power = s->area[i] * ref_luminance(s->materials[s->tri_material[i]].ke);
        if (power <= 0) continue;
        sum += power;
        s->emitters[n] = i;
        s->emitter_cdf[n] = sum;
        n++;
    }
    s->emitter_count = n;
    s->emitter_power = sum;
    return 0;
}

static int ref_build_geometry(ref_scene *s, uint32_t vertex_count)
{
    RTCGeometry g;
    float *vb;
    uint32_t *ib;
    s->device = rtcNewDevice(NULL);
    if (!s->device) return -1;
    s->rtc = rtcNewScene(s->device);
    rtcSetSceneFlags(s->rtc, RTC_SCENE_FLAG_ROBUST);
    rtcSetSceneBuildQuality(s->rtc, RTC_BUILD_QUALITY_HIGH);
    g = rtcNewGeometry(s->device, RTC_GEOMETRY_TYPE_TRIANGLE);
    vb = (float *)rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                          3 * sizeof(float), vertex_count ? vertex_count : 1);
    ib = (uint32_t *)rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                             3 * sizeof(uint32_t), s->tri_count ? s->tri_count : 1);
    if (!vb || !ib) { rtcReleaseGeometry(g); return -1; }
    memcpy(vb, s->positions, sizeof(float) * 3 * vertex_count);
    memcpy(ib, s->indices, sizeof(uint32_t) * 3 * s->tri_count);
    rtcCommitGeometry(g);
    rtcAttachGeometry(s->rtc, g);
    rtcReleaseGeometry(g);
    rtcCommitScene(s->rtc);
    return 0;
}

ref_scene *ref_scene_create(const float *positions, uint32_t vertex_count, const uint32_t *indices,
                            uint32_t tri_count, const uint32_t *tri_material,
                            const ref_material *materials, uint32_t material_count)
{
    static const ref_material grey = { { 0.5f, 0.5f, 0.5f }, { 0, 0, 0 }, 1.0f, { 0, 0, 0 }, { 0, 0, 0 } };
    ref_scene *s;
    uint32_t i;
    double lo[3] = { DBL_MAX, DBL_MAX, DBL_MAX }, hi[3] = { -DBL_MAX, -DBL_MAX, -DBL_MAX }, diag;
    if (!positions || !indices || tri_count == 0 || vertex_count == 0) {
        fprintf(stderr, "ref_scene_create: empty scene\n");
        return NULL;
    }
    for (i = 0; i < 3 * vertex_count; i++)
        if (!ref_finite(positions[i])) { fprintf(stderr, "ref_scene_create: non-finite vertex\n"); return NULL; }
    for (i = 0; i < 3 * tri_count; i++)
        if (indices[i] >= vertex_count) { fprintf(stderr, "ref_scene_create: index out of range\n"); return NULL; }
    if (tri_material && materials)
        for (i = 0; i < tri_count; i++)
            if (tri_material[i] >= material_count) { fprintf(stderr, "ref_scene_create: material out of range\n"); return NULL; }
    for (i = 0; materials && i < 3 * material_count; i++)
        if (!(materials[i / 3].tf[i % 3] >= 0.0f && materials[i / 3].tf[i % 3] <= 1.0f)) {
            fprintf(stderr, "ref_scene_create: transmittance outside [0, 1]\n");
            return NULL;
        }
    s = (ref_scene *)calloc(1, sizeof *s);
    if (!s) return NULL;
    s->tri_count = tri_count;
    s->positions = (float *)malloc(sizeof(float) * 3 * vertex_count);
    s->indices = (uint32_t *)malloc(sizeof(uint32_t) * 3 * tri_count);
    s->normal = (ref_vec *)malloc(sizeof(ref_vec) * tri_count);
    s->area = (double *)malloc(sizeof(double) * tri_count);
    s->tri_material = (uint32_t *)calloc(tri_count, sizeof(uint32_t));
    s->material_count = materials ? material_count : 1;
    s->materials = (ref_material *)malloc(sizeof(ref_material) * s->material_count);
    if (!s->positions || !s->indices || !s->normal || !s->area || !s->tri_material || !s->materials) {
        ref_scene_destroy(s);
        return NULL;
    }
    memcpy(s->positions, positions, sizeof(float) * 3 * vertex_count);
    memcpy(s->indices, indices, sizeof(uint32_t) * 3 * tri_count);
    if (materials) memcpy(s->materials, materials, sizeof(ref_material) * material_count);
    else s->materials[0] = grey;
    if (tri_material && materials) memcpy(s->tri_material, tri_material, sizeof(uint32_t) * tri_count);
    for (i = 0; i < 3 * s->material_count; i++) s->has_glass |= s->materials[i / 3].tf[i % 3] > 0.0f;
    for (i = 0; i < vertex_count; i++) {
        int k;
        for (k = 0; k < 3; k++) {
            if (positions[3 * i + k] < lo[k]) lo[k] = positions[3 * i + k];
            if (positions[3 * i + k] > hi[k]) hi[k] = positions[3 * i + k];
        }
    }
    diag = sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
                (hi[2] - lo[2]) * (hi[2] - lo[2]));
    s->epsilon = 1e-5 * (diag > 0 ? diag : 1.0);
    for (i = 0; i < tri_count; i++) {
        ref_vec a = rv_load(positions + 3 * indices[3 * i]);
        ref_vec b = rv_load(positions + 3 * indices[3 * i + 1]);
        ref_vec c = rv_load(positions + 3 * indices[3 * i + 2]);
        ref_vec n = rv_cross(rv_sub(b, a), rv_sub(c, a));
        s->area[i] = 0.5 * sqrt(rv_dot(n, n));
        s->normal[i] = rv_normalize(n);
    }
    if (ref_build_emitters(s) != 0 || ref_build_geometry(s, vertex_count) != 0) {
        ref_scene_destroy(s);
        return NULL;
    }
    s->pool = ex_pool_create(0);
    return s;
}

ref_scene *ref_scene_from_obj(const obj_scene *o)
{
    ref_material *m;
    ref_scene *s;
    uint32_t i;
    if (!o || !o->material_count) return NULL;
    m = (ref_material *)malloc(sizeof(ref_material) * o->material_count);
    if (!m) return NULL;
    for (i = 0; i < o->material_count; i++) {
        memcpy(m[i].kd, o->materials[i].kd, sizeof m[i].kd);
        memcpy(m[i].ks, o->materials[i].ks, sizeof m[i].ks);
        memcpy(m[i].ke, o->materials[i].ke, sizeof m[i].ke);
        memcpy(m[i].tf, o->materials[i].tf, sizeof m[i].tf);
        m[i].ns = o->materials[i].ns;
    }
    s = ref_scene_create(o->positions, o->vertex_count, o->tri_indices, o->tri_count,
                         o->tri_material, m, o->material_count);
    free(m);
    return s;
}

void ref_scene_destroy(ref_scene *s)
{
    if (!s) return;
    if (s->rtc) rtcReleaseScene(s->rtc);
    if (s->device) rtcReleaseDevice(s->device);
    ex_pool_destroy(s->pool);
    free(s->positions);
    free(s->indices);
    free(s->normal);
    free(s->area);
    free(s->tri_material);
    free(s->materials);
    free(s->emitters);
    free(s->emitter_cdf);
    free(s);
}

uint32_t ref_scene_triangle_count(const ref_scene *s) { return s ? s->tri_count : 0; }

int ref_scene_set_sky(ref_scene *s, const ex_sky *sky)
{
    if (!s || (sky && !ex_sky_valid(sky))) return -1;
    s->has_sky = sky && (sky->map || sky->radiance[0] > 0 || sky->radiance[1] > 0 || sky->radiance[2] > 0);
    if (sky) s->sky = *sky;
    return 0;
}

/* ---- rays ----------------------------------------------------------------- */

int ref_intersect(const ref_scene *s, const float org[3], const float dir[3], float tnear,
                  float tfar, ref_hit *hit)
{
    struct RTCRayHit rh;
    struct RTCIntersectContext ctx;
    memset(&rh, 0, sizeof rh);
    rh.ray.org_x = org[0]; rh.ray.org_y = org[1]; rh.ray.org_z = org[2];
    rh.ray.dir_x = dir[0]; rh.ray.dir_y = dir[1]; rh.ray.dir_z = dir[2];
    rh.ray.tnear = tnear;
    rh.ray.tfar = tfar;
    rh.ray.mask = 0xFFFFFFFFu;
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rtcInitIntersectContext(&ctx);
    rtcIntersect1(s->rtc, &ctx, &rh);
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) {
        hit->tri = REF_NO_HIT;
        hit->t = tfar;
        hit->u = hit->v = 0;
        hit->front = 0;
        return 0;
    }
    hit->tri = rh.hit.primID;
    hit->t = rh.ray.tfar;
    hit->u = rh.hit.u;
    hit->v = rh.hit.v;
    hit->front = rv_dot(s->normal[hit->tri], rv(dir[0], dir[1], dir[2])) < 0;
    return 1;
}

int ref_occluded(const ref_scene *s, const float org[3], const float dir[3], float tnear, float tfar)
{
    struct RTCRay ray;
    struct RTCIntersectContext ctx;
    memset(&ray, 0, sizeof ray);
    ray.org_x = org[0]; ray.org_y = org[1]; ray.org_z = org[2];
    ray.dir_x = dir[0]; ray.dir_y = dir[1]; ray.dir_z = dir[2];
    ray.tnear = tnear;
    ray.tfar = tfar;
    ray.mask = 0xFFFFFFFFu;
    rtcInitIntersectContext(&ctx);
    rtcOccluded1(s->rtc, &ctx, &ray);
    return ray.tfar < 0; /* Embree sets tfar to -inf on a hit */
}

static int ref_trace(const ref_scene *s, ref_vec org, ref_vec dir, ref_hit *hit)
{
    float o[3], d[3];
    o[0] = (float)org.x; o[1] = (float)org.y; o[2] = (float)org.z;
    d[0] = (float)dir.x; d[1] = (float)dir.y; d[2] = (float)dir.z;
    return ref_intersect(s, o, d, 0.0f, FLT_MAX, hit);
}

static int ref_passes(const float tf[3]) { return tf[0] > 0 || tf[1] > 0 || tf[2] > 0; }

/* The distance a ray steps past a surface it crosses, along itself: to
   epsilon behind the surface (capped at 100 epsilon for grazing rays). */
static double ref_step_past(const ref_scene *s, uint32_t tri, ref_vec unit_dir)
{
    double c = fabs(rv_dot(s->normal[tri], unit_dir));
    return s->epsilon / (c > 0.01 ? c : 0.01);
}

/* What of the light leaving b reaches a (both pushed off their surfaces):
   the product of the transmittances of the panes between them, or 0 when
   something opaque is in the way (or more than REF_MAX_PASSES panes). */
static int ref_transmittance(const ref_scene *s, ref_vec a, ref_vec b, double through[3])
{
    ref_vec d = rv_sub(b, a), unit;
    float o[3], dir[3], tnear = 0.0f, tfar = 1.0f - 1e-4f;
    double len = sqrt(rv_dot(d, d));
    int pass, k;
    through[0] = through[1] = through[2] = 1.0;
    o[0] = (float)a.x; o[1] = (float)a.y; o[2] = (float)a.z;
    dir[0] = (float)d.x; dir[1] = (float)d.y; dir[2] = (float)d.z;
    if (!s->has_glass) {
        if (!ref_occluded(s, o, dir, tnear, tfar)) return 1;
        through[0] = through[1] = through[2] = 0.0;
        return 0;
    }
    unit = rv_scale(d, len > 0 ? 1.0 / len : 0.0);
    for (pass = 0; pass <= REF_MAX_PASSES; pass++) {
        ref_hit h;
        const float *tf;
        if (!ref_intersect(s, o, dir, tnear, tfar, &h)) return 1;
        tf = s->materials[s->tri_material[h.tri]].tf;
        if (!ref_passes(tf) || pass == REF_MAX_PASSES) break;
        for (k = 0; k < 3; k++) through[k] *= tf[k];
        tnear = (float)(h.t + ref_step_past(s, h.tri, unit) / len);
        if (!(tnear < tfar)) return 1;
    }
    through[0] = through[1] = through[2] = 0.0;
    return 0;
}

static ref_vec ref_hit_point(const ref_scene *s, const ref_hit *h)
{
    const uint32_t *t = s->indices + 3 * h->tri;
    ref_vec a = rv_load(s->positions + 3 * t[0]);
    ref_vec b = rv_load(s->positions + 3 * t[1]);
    ref_vec c = rv_load(s->positions + 3 * t[2]);
    return rv_add(rv_add(rv_scale(a, 1.0 - h->u - h->v), rv_scale(b, h->u)), rv_scale(c, h->v));
}

static ref_vec ref_sample_triangle(const ref_scene *s, uint32_t tri, ref_rng *r)
{
    const uint32_t *t = s->indices + 3 * tri;
    double u = sqrt(ref_rand(r)), v = ref_rand(r);
    ref_vec a = rv_load(s->positions + 3 * t[0]);
    ref_vec b = rv_load(s->positions + 3 * t[1]);
    ref_vec c = rv_load(s->positions + 3 * t[2]);
    return rv_add(rv_add(rv_scale(a, 1.0 - u), rv_scale(b, u * (1.0 - v))), rv_scale(c, u * v));
}

/* ---- light transport -------------------------------------------------------- */

/* The scattering at a path vertex: a material (Lambert + normalized Phong
   around the mirror of wo), or, at a point where irradiance is estimated, the
   bare cosine weight (f = 1, cosine-sampled). */
typedef struct ref_surface {
    ref_vec n, wo;           /* normal, direction towards the viewer */
    const ref_material *m;   /* NULL: the irradiance weight */
    int diffuse_only;        /* ignore the glossy lobe */
    double reflect;          /* probability that a path reflects here rather than passing: 1 when opaque */
} ref_surface;

static ref_vec ref_mirror(const ref_surface *sf)
{
    return rv_sub(rv_scale(sf->n, 2 * rv_dot(sf->n, sf->wo)), sf->wo);
}

static double ref_glossy_weight(const ref_surface *sf)
{
    double kd, ks;
    if (!sf->m || sf->diffuse_only) return 0;
    kd = ref_luminance(sf->m->kd);
    ks = ref_luminance(sf->m->ks);
    return kd + ks > 0 ? ks / (kd + ks) : 0;
}

static void ref_brdf_eval(const ref_surface *sf, ref_vec wi, double f[3])
{
    double glossy = 0, c;
    int k;
    if (!sf->m) { f[0] = f[1] = f[2] = 1.0; return; }
    if (!sf->diffuse_only && (c = rv_dot(ref_mirror(sf), wi)) > 0)
        glossy = (sf->m->ns + 2) / (2 * REF_PI) * pow(c, sf->m->ns);
    for (k = 0; k < 3; k++) f[k] = sf->m->kd[k] / REF_PI + sf->m->ks[k] * glossy;
}

/* Solid-angle density with which ref_brdf_sample picks wi (given that the
   path reflects). */
static double ref_brdf_pdf(const ref_surface *sf, ref_vec wi)
{
    double cos_i = rv_dot(sf->n, wi), pg = ref_glossy_weight(sf), pdf, c;
    if (cos_i <= 0) return 0;
    pdf = (1 - pg) * cos_i / REF_PI;
    if (pg > 0 && (c = rv_dot(ref_mirror(sf), wi)) > 0)
        pdf += pg * (sf->m->ns + 1) / (2 * REF_PI) * pow(c, sf->m->ns);
    return pdf;
}

/* The share of the paths at a surface that reflect: luminance of kd (+ ks)
   against tf; 1 on an opaque surface or the irradiance weight. */
static double ref_reflect_share(const ref_material *m, int diffuse_only)
{
    double lt, lr;
    if (!m || !ref_passes(m->tf)) return 1.0;
    lt = ref_luminance(m->tf);
    lr = ref_luminance(m->kd) + (diffuse_only ? 0.0 : ref_luminance(m->ks));
    return lr / (lr + lt);
}

/* Picks the next direction from the mix of the diffuse and glossy lobes.
   Returns its pdf and the weight f * cos / pdf, or 0 to end the path. */
static double ref_brdf_sample(const ref_surface *sf, ref_rng *r, ref_vec *wi, double weight[3])
{
    double pg = ref_glossy_weight(sf), pdf, f[3], cos_i;
    int k;
    if (sf->m && ref_luminance(sf->m->kd) + (sf->diffuse_only ? 0 : ref_luminance(sf->m->ks)) <= 0) return 0;
    *wi = ref_rand(r) < pg ? ref_sample_phong(ref_mirror(sf), sf->m->ns, r) : ref_sample_cosine(sf->n, r);
    cos_i = rv_dot(sf->n, *wi);
    pdf = ref_brdf_pdf(sf, *wi);
    if (cos_i <= 0 || pdf <= 0) return 0;
    ref_brdf_eval(sf, *wi, f);
    for (k = 0; k < 3; k++) weight[k] = f[k] * cos_i / pdf;
    return pdf;
}

/* Solid-angle density with which ref_direct picks a point of emitter tri
   seen at distance^2 d2 under cosine cos_y. */
static double ref_light_pdf(const ref_scene *s, uint32_t tri, double d2, double cos_y)
{
    double p_area = ref_luminance(s->materials[s->tri_material[tri]].ke) / s->emitter_power;
    return cos_y > 0 ? p_area * d2 / cos_y : 0;
}

/* Balance heuristic (Veach 1997): the weight of a sample from the strategy
   with density a when the other strategy has density b. */
static double ref_mis(double a, double b) { return a + b > 0 ? a / (a + b) : 0; }

/* Next-event estimate at x: one point on an emitter, chosen by power, and its
   contribution ke * f * cos_x * cos_y / (d^2 pdf_area), weighted against
   finding the same light by sampling the BRDF. */
static void ref_direct(const ref_scene *s, ref_vec x, const ref_surface *sf, ref_rng *r, double out[3])
{
    double pick = ref_rand(r) * s->emitter_power, d2, cos_x, cos_y, g, w, f[3], through[3];
    uint32_t lo = 0, hi = s->emitter_count - 1, tri;
    ref_vec y, wi;
    const float *ke;
    out[0] = out[1] = out[2] = 0;
    if (s->emitter_count == 0) return;
    while (lo < hi) { /* first cdf entry above pick */
        uint32_t mid = (lo + hi) / 2;
        if (s->emitter_cdf[mid] <= pick) lo = mid + 1;
        else hi = mid;
    }
    tri = s->emitters[lo];
    y = ref_sample_triangle(s, tri, r);
    wi = rv_sub(y, x);
    d2 = rv_dot(wi, wi);
    if (d2 <= 0) return;
    wi = rv_scale(wi, 1.0 / sqrt(d2));
    cos_x = rv_dot(sf->n, wi);
    cos_y = -rv_dot(s->normal[tri], wi);
    if (cos_x <= 0 || cos_y <= 0) return; /* behind x, or the emitter's back face */
    if (!ref_transmittance(s, rv_add(x, rv_scale(sf->n, s->epsilon)), rv_add(y, rv_scale(s->normal[tri], s->epsilon)), through))
        return;
    ke = s->materials[s->tri_material[tri]].ke;
    /* the path's own strategy finds this light with the density of
       reflecting and then picking wi */
    w = ref_mis(ref_light_pdf(s, tri, d2, cos_y), sf->reflect * ref_brdf_pdf(sf, wi));
    g = cos_x * cos_y / (d2 * (ref_luminance(ke) / s->emitter_power)) * w;
    ref_brdf_eval(sf, wi, f);
    out[0] = ke[0] * f[0] * g * through[0];
    out[1] = ke[1] * f[1] * g * through[1];
    out[2] = ke[2] * f[2] * g * through[2];
}

/* Radiance arriving at org along unit dir. pdf is the solid-angle density with
   which dir was sampled at org by a vertex that also did next-event
   estimation (its emission hit is then MIS-weighted), or 0 for a camera ray
   (emission seen in full). Rays that leave the scene see the sky; back faces
   are black. Through glass the path goes on in the same direction: the
   last scattering vertex's pdf and distance still weigh the emitter it
   finds, as its next-event ray crossed the same panes. */
static void ref_radiance(const ref_scene *s, ref_vec org, ref_vec dir, int diffuse_only, double pdf,
                         ref_rng *r, double out[3])
{
    double throughput[3] = { 1, 1, 1 }, travelled = 0;
    int depth, k;
    out[0] = out[1] = out[2] = 0;
    for (depth = 0; depth < REF_MAX_BOUNCES; depth++) {
        ref_hit h;
        ref_surface sf;
        ref_vec x;
        double direct[3], w[3], em, dist;
        if (!ref_trace(s, org, dir, &h)) {
            if (s->has_sky) {
                float d[3], sky[3];
                d[0] = (float)dir.x; d[1] = (float)dir.y; d[2] = (float)dir.z;
                ex_sky_radiance(&s->sky, d, sky);
                for (k = 0; k < 3; k++) out[k] += throughput[k] * sky[k];
            }
            return;
        }
        x = ref_hit_point(s, &h);
        sf.n = s->normal[h.tri];
        sf.wo = rv_scale(dir, -1);
        sf.m = &s->materials[s->tri_material[h.tri]];
        sf.diffuse_only = diffuse_only;
        sf.reflect = h.front ? ref_reflect_share(sf.m, diffuse_only) : 0.0;
        if (!h.front && !ref_passes(sf.m->tf)) return;
        dist = travelled + h.t;
        if (h.front && ref_luminance(sf.m->ke) > 0) {
            em = pdf > 0 ? ref_mis(pdf, ref_light_pdf(s, h.tri, dist * dist, rv_dot(sf.wo, sf.n))) : 1;
            for (k = 0; k < 3; k++) out[k] += throughput[k] * sf.m->ke[k] * em;
        }
        if (h.front) {
            ref_direct(s, x, &sf, r, direct);
            for (k = 0; k < 3; k++) out[k] += throughput[k] * direct[k];
        }
        if (sf.reflect < 1.0 && ref_rand(r) >= sf.reflect) {   /* straight through */
            double step = ref_step_past(s, h.tri, dir);
            for (k = 0; k < 3; k++) throughput[k] *= sf.m->tf[k] / (1.0 - sf.reflect);
            org = rv_add(x, rv_scale(dir, step));
            travelled = dist + step;
            continue;
        }
        pdf = ref_brdf_sample(&sf, r, &dir, w);
        if (pdf <= 0) return;
        pdf *= sf.reflect;
        travelled = 0;
        for (k = 0; k < 3; k++) throughput[k] *= w[k] / sf.reflect;
        if (depth + 1 >= REF_MIN_BOUNCES) { /* Russian roulette keeps the estimate unbiased */
            double q = throughput[0] > throughput[1] ? throughput[0] : throughput[1];
            if (throughput[2] > q) q = throughput[2];
            if (q > 0.95) q = 0.95;
            if (ref_rand(r) >= q) return;
            for (k = 0; k < 3; k++) throughput[k] /= q;
        }
        org = rv_add(x, rv_scale(sf.n, s->epsilon));
    }
}

/* ---- estimates in chunks ------------------------------------------------- */

/* One sample of an estimator: 3 channels. */
typedef void (*ref_sample_fn)(const void *ctx, ref_rng *r, double x[3]);

typedef struct ref_chunk_job {
    const ref_scene *scene;
    ref_sample_fn sample;
    const void *ctx;
    uint64_t samples, seed;
    double sum[REF_CHUNKS][3], sum2[REF_CHUNKS][3];
} ref_chunk_job;

static void ref_chunk_run(void *ctx, uint32_t chunk)
{
    ref_chunk_job *job = (ref_chunk_job *)ctx;
    uint64_t n = job->samples / REF_CHUNKS + (chunk < job->samples % REF_CHUNKS), i;
    ref_rng r = ref_rng_stream(job->seed, chunk);
    int k;
    for (k = 0; k < 3; k++) job->sum[chunk][k] = job->sum2[chunk][k] = 0;
    for (i = 0; i < n; i++) {
        double x[3];
        job->sample(job->ctx, &r, x);
        for (k = 0; k < 3; k++) {
            job->sum[chunk][k] += x[k];
            job->sum2[chunk][k] += x[k] * x[k];
        }
    }
}

static ref_estimate ref_estimate_run(const ref_scene *s, ref_sample_fn fn, const void *ctx,
                                     uint64_t samples, uint64_t seed)
{
    ref_chunk_job *job = (ref_chunk_job *)calloc(1, sizeof *job);
    ref_estimate e;
    int c, k;
    memset(&e, 0, sizeof e);
    if (!job || samples == 0) { free(job); return e; }
    job->scene = s;
    job->sample = fn;
    job->ctx = ctx;
    job->samples = samples;
    job->seed = seed;
    ex_pool_parallel_for(s->pool, ref_chunk_run, job, REF_CHUNKS);
    for (k = 0; k < 3; k++) {
        double sum = 0, sum2 = 0, mean, var;
        for (c = 0; c < REF_CHUNKS; c++) { sum += job->sum[c][k]; sum2 += job->sum2[c][k]; }
        mean = sum / (double)samples;
        var = samples > 1 ? (sum2 - sum * mean) / (double)(samples - 1) : 0;
        e.mean[k] = mean;
        e.std_error[k] = sqrt((var > 0 ? var : 0) / (double)samples);
    }
    e.samples = samples;
    free(job);
    return e;
}

/* (a) field irradiance: cosine-weighted directions, E = pi * L. */
typedef struct ref_field_ctx {
    const ref_scene *s;
    ref_vec p, n;
    const float *tri_radiance;
    const float *background;
    ref_radiance_fn fn;
    void *user;
} ref_field_ctx;

static void ref_field_sample(const void *ctx, ref_rng *r, double x[3])
{
    const ref_field_ctx *c = (const ref_field_ctx *)ctx;
    ref_vec d = ref_sample_cosine(c->n, r);
    float o[3], dir[3], rgb[3] = { 0, 0, 0 };
    ref_hit h;
    int hit, k;
    o[0] = (float)c->p.x; o[1] = (float)c->p.y; o[2] = (float)c->p.z;
    dir[0] = (float)d.x; dir[1] = (float)d.y; dir[2] = (float)d.z;
    hit = ref_intersect(c->s, o, dir, 0.0f, FLT_MAX, &h);
    if (c->fn) c->fn(c->user, o, dir, hit ? &h : NULL, rgb);
    else if (hit) memcpy(rgb, c->tri_radiance + 3 * h.tri, sizeof rgb);
    else if (c->background) memcpy(rgb, c->background, sizeof rgb);
    for (k = 0; k < 3; k++) x[k] = REF_PI * rgb[k];
}

static int ref_check_point(const float p[3], const float n[3])
{
    return p && n && ref_finite(p[0]) && ref_finite(p[1]) && ref_finite(p[2]) && ref_finite(n[0]) &&
           ref_finite(n[1]) && ref_finite(n[2]) && (n[0] != 0 || n[1] != 0 || n[2] != 0);
}

static ref_estimate ref_field_run(const ref_scene *s, const float p[3], const float n[3],
                                  const float *tri_radiance, const float *background,
                                  ref_radiance_fn fn, void *user, uint64_t samples, uint64_t seed)
{
    ref_field_ctx c;
    ref_estimate none;
    memset(&none, 0, sizeof none);
    if (!s || (!tri_radiance && !fn) || !ref_check_point(p, n)) return none;
    memset(&c, 0, sizeof c);
    c.s = s;
    c.n = rv_normalize(rv_load(n));
    /* a point on a surface must not see its own triangle: push it off along n,
       as the global-illumination estimator does */
    c.p = rv_add(rv_load(p), rv_scale(c.n, s->epsilon));
    c.tri_radiance = tri_radiance;
    c.background = background;
    c.fn = fn;
    c.user = user;
    return ref_estimate_run(s, ref_field_sample, &c, samples, seed);
}

ref_estimate ref_irradiance_field(const ref_scene *s, const float p[3], const float n[3],
                                  const float *tri_radiance, const float background[3],
                                  uint64_t samples, uint64_t seed)
{
    if (!tri_radiance) { ref_estimate none; memset(&none, 0, sizeof none); return none; }
    return ref_field_run(s, p, n, tri_radiance, background, NULL, NULL, samples, seed);
}

ref_estimate ref_irradiance_callback(const ref_scene *s, const float p[3], const float n[3],
                                     ref_radiance_fn radiance, void *user, uint64_t samples,
                                     uint64_t seed)
{
    if (!radiance) { ref_estimate none; memset(&none, 0, sizeof none); return none; }
    return ref_field_run(s, p, n, NULL, NULL, radiance, user, samples, seed);
}

/* (b) global-illumination irradiance: direct light by emitter sampling plus
   pi * reflected radiance along a cosine-weighted direction. */
typedef struct ref_gi_ctx {
    const ref_scene *s;
    ref_vec p, n;
    const uint32_t *tris;   /* radiosity average: the patch */
    uint32_t count;
    double patch_area;
} ref_gi_ctx;

/* E = integral of L cos: next-event estimation plus one cosine-sampled ray
   (weight f cos / pdf = pi), both MIS-weighted for the emitters they find. */
static void ref_gi_irradiance(const ref_scene *s, ref_vec p, ref_vec n, ref_rng *r, double x[3])
{
    double direct[3], incoming[3], w[3], pdf;
    ref_surface sf;
    ref_vec dir;
    int k;
    sf.n = n;
    sf.wo = n;
    sf.m = NULL;
    sf.diffuse_only = 1;
    sf.reflect = 1.0;
    ref_direct(s, p, &sf, r, direct);
    pdf = ref_brdf_sample(&sf, r, &dir, w);
    if (pdf > 0) ref_radiance(s, rv_add(p, rv_scale(n, s->epsilon)), dir, 1, pdf, r, incoming);
    else incoming[0] = incoming[1] = incoming[2] = 0;
    for (k = 0; k < 3; k++) x[k] = direct[k] + w[k] * incoming[k];
}

static void ref_gi_sample(const void *ctx, ref_rng *r, double x[3])
{
    const ref_gi_ctx *c = (const ref_gi_ctx *)ctx;
    ref_gi_irradiance(c->s, c->p, c->n, r, x);
}

ref_estimate ref_irradiance_gi(const ref_scene *s, const float p[3], const float n[3],
                               uint64_t samples, uint64_t seed)
{
    ref_gi_ctx c;
    ref_estimate none;
    memset(&none, 0, sizeof none);
    if (!s || !ref_check_point(p, n)) return none;
    memset(&c, 0, sizeof c);
    c.s = s;
    c.p = rv_load(p);
    c.n = rv_normalize(rv_load(n));
    return ref_estimate_run(s, ref_gi_sample, &c, samples, seed);
}

/* A uniformly distributed point of the patch, then B = pi*ke + kd*H there. */
static void ref_radiosity_sample(const void *ctx, ref_rng *r, double x[3])
{
    const ref_gi_ctx *c = (const ref_gi_ctx *)ctx;
    double pick = ref_rand(r) * c->patch_area, h[3];
    uint32_t i = 0, tri;
    const ref_material *m;
    ref_vec p;
    int k;
    while (i + 1 < c->count && pick >= c->s->area[c->tris[i]]) pick -= c->s->area[c->tris[i++]];
    tri = c->tris[i];
    p = ref_sample_triangle(c->s, tri, r);
    ref_gi_irradiance(c->s, p, c->s->normal[tri], r, h);
    m = &c->s->materials[c->s->tri_material[tri]];
    for (k = 0; k < 3; k++) x[k] = REF_PI * m->ke[k] + m->kd[k] * h[k];
}

ref_estimate ref_radiosity_average(const ref_scene *s, const uint32_t *tris, uint32_t count,
                                   uint64_t samples, uint64_t seed)
{
    ref_gi_ctx c;
    ref_estimate none;
    uint32_t i;
    memset(&none, 0, sizeof none);
    if (!s || !tris || count == 0) return none;
    memset(&c, 0, sizeof c);
    c.s = s;
    c.tris = tris;
    c.count = count;
    for (i = 0; i < count; i++) {
        if (tris[i] >= s->tri_count) return none;
        c.patch_area += s->area[tris[i]];
    }
    if (!(c.patch_area > 0)) return none;
    return ref_estimate_run(s, ref_radiosity_sample, &c, samples, seed);
}

/* ---- images --------------------------------------------------------------- */

typedef struct ref_render_job {
    const ref_scene *s;
    ref_vec eye, forward, right, up;
    double tan_half;
    int width, height, diffuse_only;
    uint32_t spp;
    uint64_t seed;
    float *rgb, *variance;
} ref_render_job;

static void ref_render_row(void *ctx, uint32_t y)
{
    ref_render_job *j = (ref_render_job *)ctx;
    ref_rng r = ref_rng_stream(j->seed, y);
    double aspect = (double)j->width / (double)j->height;
    int x;
    for (x = 0; x < j->width; x++) {
        double sum[3] = { 0, 0, 0 }, sum2[3] = { 0, 0, 0 };
        uint32_t i;
        int k;
        for (i = 0; i < j->spp; i++) {
            double sx = (2 * ((x + ref_rand(&r)) / j->width) - 1) * j->tan_half * aspect;
            double sy = (1 - 2 * ((y + ref_rand(&r)) / j->height)) * j->tan_half;
            ref_vec dir = rv_normalize(rv_add(j->forward, rv_add(rv_scale(j->right, sx), rv_scale(j->up, sy))));
            double l[3];
            ref_radiance(j->s, j->eye, dir, j->diffuse_only, 0, &r, l);
            for (k = 0; k < 3; k++) { sum[k] += l[k]; sum2[k] += l[k] * l[k]; }
        }
        for (k = 0; k < 3; k++) {
            double mean = sum[k] / j->spp;
            size_t at = 3 * ((size_t)y * (size_t)j->width + (size_t)x) + (size_t)k;
            j->rgb[at] = (float)mean;
            if (j->variance) {
                double var = j->spp > 1 ? (sum2[k] - sum[k] * mean) / (j->spp - 1) : 0;
                j->variance[at] = (float)((var > 0 ? var : 0) / j->spp);
            }
        }
    }
}

static int ref_render_any(const ref_scene *s, const ref_camera *c, uint32_t spp, uint64_t seed,
                          float *rgb, float *variance, int diffuse_only)
{
    ref_render_job j;
    if (!s || !c || !rgb || spp == 0 || c->width <= 0 || c->height <= 0 ||
        !(c->vfov_degrees > 0 && c->vfov_degrees < 180))
        return -1;
    memset(&j, 0, sizeof j);
    j.s = s;
    j.eye = rv_load(c->eye);
    j.forward = rv_normalize(rv_sub(rv_load(c->target), j.eye));
    j.right = rv_normalize(rv_cross(j.forward, rv_load(c->up)));
    j.up = rv_cross(j.right, j.forward);
    j.tan_half = tan(0.5 * c->vfov_degrees * REF_PI / 180.0);
    j.width = c->width;
    j.height = c->height;
    j.spp = spp;
    j.seed = seed;
    j.rgb = rgb;
    j.variance = variance;
    j.diffuse_only = diffuse_only;
    ex_pool_parallel_for(s->pool, ref_render_row, &j, (uint32_t)c->height);
    return 0;
}

int ref_render(const ref_scene *s, const ref_camera *c, uint32_t spp, uint64_t seed, float *rgb,
               float *variance)
{
    return ref_render_any(s, c, spp, seed, rgb, variance, 0);
}

int ref_render_diffuse(const ref_scene *s, const ref_camera *c, uint32_t spp, uint64_t seed,
                       float *rgb, float *variance)
{
    return ref_render_any(s, c, spp, seed, rgb, variance, 1);
}

double ref_lrms(const float *reference, const float *image, int width, int height)
{
    size_t i, n = (size_t)width * (size_t)height;
    double sum_ref = 0, sum_d2 = 0, mean;
    if (!reference || !image || n == 0) return -1;
    for (i = 0; i < n; i++) {
        double d = ref_luminance(image + 3 * i) - ref_luminance(reference + 3 * i);
        sum_ref += ref_luminance(reference + 3 * i);
        sum_d2 += d * d;
    }
    mean = sum_ref / (double)n;
    return mean > 0 ? sqrt(sum_d2 / (double)n) / mean : -1;
}
