/* The headers' built-in BVH against Embree 3: rtcIntersect1 on one thread,
   default build quality, and again with RTC_SCENE_FLAG_ROBUST (Embree's
   watertight mode, the one that compares with our watertight test).
   Incoherent closest-hit rays (random origins in the scene's box, uniformly
   random directions), the same rays for all, rounds interleaved (ours,
   Embree, Embree robust, ours scalar path, ...), each timed in this thread's
   CPU time: the medians, and the medians of the rounds' ratios. Build times
   in process CPU time (Embree builds on a one-thread device). Scenes: the
   office with the bunny on its floor (the reference tests' scene), the bunny
   subdivided three times (235,136 triangles), and four copies of the 64k
   building preset side by side (264,320 triangles; origins in their box,
   mostly inside rooms). */
#define IRRVOL_IMPLEMENTATION
#include "irrvol.h"
#include "tests/ref_irrvol_scene.h"
#include <embree3/rtcore.h>
#include <time.h>

#ifndef ROUNDS
#define ROUNDS 7
#endif
#ifndef RAYS
#define RAYS 1000000u
#endif

static double thread_cpu(void)
{
    struct timespec t;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

static double process_cpu(void)
{
    struct timespec t;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

static double median(double *x, int n)
{
    int i, j;
    for (i = 1; i < n; i++)
        for (j = i; j > 0 && x[j - 1] > x[j]; j--) { double t = x[j]; x[j] = x[j - 1]; x[j - 1] = t; }
    return n % 2 ? x[n / 2] : 0.5 * (x[n / 2 - 1] + x[n / 2]);
}

static uint64_t rng_state;
static double frand(void)
{
    rng_state = rng_state * 6364136223846793005ull + 1442695040888963407ull;
    return (double)(rng_state >> 11) * (1.0 / 9007199254740992.0);
}

typedef struct mesh {
    float *positions;
    uint32_t *indices;
    uint32_t vertex_count, tri_count;
} mesh;

/* Each triangle split in four at its edge midpoints, `levels` times
   (vertices not shared: the BVHs see triangles only). */
static int mesh_subdivide(const float *positions, const uint32_t *indices, uint32_t tri_count,
                          int levels, mesh *out)
{
    uint32_t n = tri_count, i;
    int l;
    float *tri = (float *)malloc((size_t)tri_count * 9 * sizeof(float));
    if (!tri) return -1;
    for (i = 0; i < tri_count; i++) {
        int k;
        for (k = 0; k < 3; k++) memcpy(tri + 9 * i + 3 * k, positions + 3 * indices[3 * i + (uint32_t)k], 3 * sizeof(float));
    }
    for (l = 0; l < levels; l++) {
        float *next = (float *)malloc((size_t)n * 4 * 9 * sizeof(float));
        if (!next) { free(tri); return -1; }
        for (i = 0; i < n; i++) {
            const float *a = tri + 9 * i, *b = a + 3, *c = a + 6;
            float ab[3], bc[3], ca[3], *o = next + 36 * (size_t)i;
            int k;
            for (k = 0; k < 3; k++) {
                ab[k] = 0.5f * (a[k] + b[k]);
                bc[k] = 0.5f * (b[k] + c[k]);
                ca[k] = 0.5f * (c[k] + a[k]);
            }
            memcpy(o + 0, a, 12); memcpy(o + 3, ab, 12); memcpy(o + 6, ca, 12);
            memcpy(o + 9, ab, 12); memcpy(o + 12, b, 12); memcpy(o + 15, bc, 12);
            memcpy(o + 18, ca, 12); memcpy(o + 21, bc, 12); memcpy(o + 24, c, 12);
            memcpy(o + 27, ab, 12); memcpy(o + 30, bc, 12); memcpy(o + 33, ca, 12);
        }
        free(tri);
        tri = next;
        n *= 4;
    }
    out->positions = tri;
    out->vertex_count = 3 * n;
    out->tri_count = n;
    out->indices = (uint32_t *)malloc((size_t)n * 3 * sizeof(uint32_t));
    if (!out->indices) { free(tri); return -1; }
    for (i = 0; i < 3 * n; i++) out->indices[i] = i;
    return 0;
}

typedef struct bench_scene {
    const char *name;
    const float *positions;
    const uint32_t *indices;
    uint32_t vertex_count, tri_count;
    float lo[3], hi[3];   /* ray origins are uniform in this box */
} bench_scene;

/* Copies of a scene side by side on an nx x nz grid (x and z), a gap of 2 m
   between them. */
static int mesh_replicate(const float *positions, uint32_t vertex_count, const uint32_t *indices, uint32_t tri_count,
                          uint32_t nx, uint32_t nz, mesh *out)
{
    float lo[3] = {FLT_MAX, FLT_MAX, FLT_MAX}, hi[3] = {-FLT_MAX, -FLT_MAX, -FLT_MAX};
    uint32_t c, i;
    int k;
    for (i = 0; i < vertex_count; i++)
        for (k = 0; k < 3; k++) {
            lo[k] = fminf(lo[k], positions[3 * i + (uint32_t)k]);
            hi[k] = fmaxf(hi[k], positions[3 * i + (uint32_t)k]);
        }
    out->vertex_count = vertex_count * nx * nz;
    out->tri_count = tri_count * nx * nz;
    out->positions = (float *)malloc((size_t)out->vertex_count * 3 * sizeof(float));
    out->indices = (uint32_t *)malloc((size_t)out->tri_count * 3 * sizeof(uint32_t));
    if (!out->positions || !out->indices) return -1;
    for (c = 0; c < nx * nz; c++) {
        float dx = (float)(c % nx) * (hi[0] - lo[0] + 2.0f), dz = (float)(c / nx) * (hi[2] - lo[2] + 2.0f);
        for (i = 0; i < vertex_count; i++) {
            float *q = out->positions + 3 * ((size_t)c * vertex_count + i);
            q[0] = positions[3 * i] + dx;
            q[1] = positions[3 * i + 1];
            q[2] = positions[3 * i + 2] + dz;
        }
        for (i = 0; i < 3 * tri_count; i++) out->indices[(size_t)c * 3 * tri_count + i] = indices[i] + c * vertex_count;
    }
    return 0;
}

static void mesh_bounds(const mesh *m, float lo[3], float hi[3])
{
    uint32_t i;
    int k;
    for (k = 0; k < 3; k++) { lo[k] = FLT_MAX; hi[k] = -FLT_MAX; }
    for (i = 0; i < m->vertex_count; i++)
        for (k = 0; k < 3; k++) {
            lo[k] = fminf(lo[k], m->positions[3 * i + (uint32_t)k]);
            hi[k] = fmaxf(hi[k], m->positions[3 * i + (uint32_t)k]);
        }
}

static float *make_rays(const bench_scene *s, uint32_t n)
{
    float *r = (float *)malloc((size_t)n * 6 * sizeof(float));
    uint32_t i;
    if (!r) return NULL;
    rng_state = 12345;
    for (i = 0; i < n; i++) {
        float *o = r + 6 * (size_t)i, *d = o + 3;
        double z = 2.0 * frand() - 1.0, phi = 6.283185307179586 * frand(), q = sqrt(1.0 - z * z);
        int k;
        for (k = 0; k < 3; k++) o[k] = s->lo[k] + (float)frand() * (s->hi[k] - s->lo[k]);
        d[0] = (float)(q * cos(phi)); d[1] = (float)(q * sin(phi)); d[2] = (float)z;
    }
    return r;
}

static RTCScene embree_build(RTCDevice dev, const bench_scene *s, int robust)
{
    RTCScene sc = rtcNewScene(dev);
    if (robust) rtcSetSceneFlags(sc, RTC_SCENE_FLAG_ROBUST);
    RTCGeometry g = rtcNewGeometry(dev, RTC_GEOMETRY_TYPE_TRIANGLE);
    float *vb = (float *)rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                 3 * sizeof(float), s->vertex_count);
    uint32_t *ib = (uint32_t *)rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                       3 * sizeof(uint32_t), s->tri_count);
    memcpy(vb, s->positions, (size_t)s->vertex_count * 3 * sizeof(float));
    memcpy(ib, s->indices, (size_t)s->tri_count * 3 * sizeof(uint32_t));
    rtcCommitGeometry(g);
    rtcAttachGeometry(sc, g);
    rtcReleaseGeometry(g);
    rtcCommitScene(sc);
    return sc;
}

static double embree_trace(RTCScene sc, const float *rays, uint32_t n, double *checksum)
{
    struct RTCIntersectContext ctx;
    double t0 = thread_cpu(), sum = 0.0;
    uint32_t i;
    rtcInitIntersectContext(&ctx);
    for (i = 0; i < n; i++) {
        struct RTCRayHit rh;
        const float *r = rays + 6 * (size_t)i;
        rh.ray.org_x = r[0]; rh.ray.org_y = r[1]; rh.ray.org_z = r[2];
        rh.ray.dir_x = r[3]; rh.ray.dir_y = r[4]; rh.ray.dir_z = r[5];
        rh.ray.tnear = 0.0f;
        rh.ray.tfar = FLT_MAX;
        rh.ray.mask = 0xFFFFFFFFu;
        rh.ray.time = 0.0f;
        rh.ray.flags = 0;
        rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
        rtcIntersect1(sc, &ctx, &rh);
        if (rh.hit.geomID != RTC_INVALID_GEOMETRY_ID) sum += rh.ray.tfar;
    }
    *checksum = sum;
    return thread_cpu() - t0;
}

static double ours_trace(const irrvol__bvh *bvh, const float *rays, uint32_t n, double *checksum)
{
    double t0 = thread_cpu(), sum = 0.0;
    uint32_t i;
    for (i = 0; i < n; i++) {
        const float *r = rays + 6 * (size_t)i;
        irrvol__hit h;
        if (irrvol__bvh_intersect(bvh, r, r + 3, 0.0f, FLT_MAX, &h)) sum += h.t;
    }
    *checksum = sum;
    return thread_cpu() - t0;
}

static const char *filter;   /* argv[1]: run only the scenes whose name contains it */

static void bench(RTCDevice dev, const bench_scene *s)
{
    double ours[ROUNDS], theirs[ROUNDS], robust[ROUNDS], scalar[ROUNDS], ratio[ROUNDS], ratio_robust[ROUNDS];
    double b_ours[ROUNDS], b_theirs[ROUNDS], sum_ours = 0, sum_theirs = 0, sum_robust = 0, sum_scalar = 0;
    float *rays;
    irrvol__mesh_view m;
    irrvol_allocator a;
    irrvol__bvh bvh;
    RTCScene sc = NULL, sc_robust;
    int r;
    if (filter && !strstr(s->name, filter)) return;
    rays = make_rays(s, RAYS);
    if (!rays) { fprintf(stderr, "out of memory\n"); exit(1); }
    memset(&a, 0, sizeof a);
    m.positions = s->positions;
    m.stride = 0;
    m.indices = s->indices;
    m.tri_count = s->tri_count;
    for (r = 0; r < ROUNDS; r++) {
        double t0 = process_cpu();
        if (r) irrvol__bvh_free(&bvh, &a);
        if (irrvol__bvh_build(&bvh, &m, &a) != 0) { fprintf(stderr, "build failed\n"); exit(1); }
        b_ours[r] = process_cpu() - t0;
        t0 = process_cpu();
        if (sc) rtcReleaseScene(sc);
        sc = embree_build(dev, s, 0);
        b_theirs[r] = process_cpu() - t0;
    }
    sc_robust = embree_build(dev, s, 1);
    for (r = 0; r < ROUNDS; r++) {
        ours[r] = ours_trace(&bvh, rays, RAYS, &sum_ours);
        theirs[r] = embree_trace(sc, rays, RAYS, &sum_theirs);
        robust[r] = embree_trace(sc_robust, rays, RAYS, &sum_robust);
        ratio[r] = theirs[r] / ours[r];
        ratio_robust[r] = robust[r] / ours[r];
        bvh.simd = 0;
        scalar[r] = ours_trace(&bvh, rays, RAYS / 4, &sum_scalar) * 4.0;
        bvh.simd = 1;
    }
    printf("%-18s %7u tris  Mrays/s: ours %5.2f (scalar path %5.2f)  Embree %5.2f  robust %5.2f  "
           "ours/Embree %.2f  ours/robust %.2f   build ms: ours %6.1f  Embree %6.1f\n",
           s->name, s->tri_count, RAYS / median(ours, ROUNDS) / 1e6, RAYS / median(scalar, ROUNDS) / 1e6,
           RAYS / median(theirs, ROUNDS) / 1e6, RAYS / median(robust, ROUNDS) / 1e6, median(ratio, ROUNDS),
           median(ratio_robust, ROUNDS), 1e3 * median(b_ours, ROUNDS), 1e3 * median(b_theirs, ROUNDS));
    if (fabs(sum_ours - sum_theirs) > 1e-5 * sum_theirs || fabs(sum_ours - sum_robust) > 1e-5 * sum_robust)
        printf("  hit distances differ: sums %.9g / %.9g / %.9g\n", sum_ours, sum_theirs, sum_robust);
    rtcReleaseScene(sc);
    rtcReleaseScene(sc_robust);
    irrvol__bvh_free(&bvh, &a);
    free(rays);
}

int main(int argc, char **argv)
{
    office_scene office;
    obj_scene building;
    char err[256];
    mesh big;
    bench_scene s;
    RTCDevice dev = rtcNewDevice("threads=1");
    double load[3] = {0, 0, 0};
    FILE *f = fopen("/proc/loadavg", "r");
    (void)office_scene_desc;
    filter = argc > 1 ? argv[1] : NULL;
    if (f) { if (fscanf(f, "%lf %lf %lf", &load[0], &load[1], &load[2]) != 3) load[0] = -1; fclose(f); }
    printf("BVH vs Embree %d.%d.%d rtcIntersect1 (default quality; robust: RTC_SCENE_FLAG_ROBUST, watertight as ours), "
           "one thread, %u incoherent rays, medians of %d interleaved rounds (ratios: median of the rounds'), thread CPU "
           "time; builds in process CPU time (Embree on a one-thread device); load average %.2f\n",
           RTC_VERSION_MAJOR, RTC_VERSION_MINOR, RTC_VERSION_PATCH, RAYS, ROUNDS, load[0]);
    if (!dev || office_scene_load(&office, "examples/data", 2.5f, 2.0f) != 0) return 1;
    memset(&s, 0, sizeof s);
    s.name = "office + bunny";
    s.positions = office.positions;
    s.indices = office.indices;
    s.vertex_count = office.vertex_count;
    s.tri_count = office.tri_count;
    s.lo[0] = 0.0f; s.lo[1] = 0.0f; s.lo[2] = 0.0f;
    s.hi[0] = 5.0f; s.hi[1] = 2.8f; s.hi[2] = 4.0f;
    bench(dev, &s);
    if (mesh_subdivide(office.bunny.positions, office.bunny.tri_indices, office.bunny.tri_count, 3, &big) != 0) return 1;
    s.name = "bunny subdivided x64";
    s.positions = big.positions;
    s.indices = big.indices;
    s.vertex_count = big.vertex_count;
    s.tri_count = big.tri_count;
    obj_bounds(&office.bunny, s.lo, s.hi);
    bench(dev, &s);
    free(big.positions);
    free(big.indices);
    if (obj_load("build/data/building_64k.obj", &building, err, sizeof err) != 0) {
        printf("building 64k x 4: %s (make bench writes it)\n", err);
    } else {
        if (mesh_replicate(building.positions, building.vertex_count, building.tri_indices, building.tri_count, 2, 2, &big) != 0) return 1;
        s.name = "building 64k x 4";
        s.positions = big.positions;
        s.indices = big.indices;
        s.vertex_count = big.vertex_count;
        s.tri_count = big.tri_count;
        mesh_bounds(&big, s.lo, s.hi);
        bench(dev, &s);
        free(big.positions);
        free(big.indices);
        obj_free(&building);
    }
    office_scene_free(&office);
    rtcReleaseDevice(dev);
    return 0;
}
