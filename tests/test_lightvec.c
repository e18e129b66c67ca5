/* Unit tests of lightvec.h: the light vector reproduces the gathered radiance
   exactly (eq. 2, 3, 5), the furnace, Ward & Heckbert's gradient against the
   closed-form gradient of a strip light, the BRDF, direct light against the
   closed-form polygon factor, the DLV visibility rule, bad input. The cache
   structure (kd-trees, icosahedron, brute force, save/load) is in
   test_lightvec_cache.c. */
#define LIGHTVEC_IMPLEMENTATION
#include "lightvec.h"
#include "tests/test.h"

#define PI 3.14159265358979323846

/* ---- helpers ------------------------------------------------------------------ */

static void set3(float *d, float x, float y, float z) { d[0] = x; d[1] = y; d[2] = z; }
static double dot3d(const float *a, const float *b) { return (double)a[0] * b[0] + (double)a[1] * b[1] + (double)a[2] * b[2]; }

static void normalize3(float *v)
{
    double l = sqrt(dot3d(v, v));
    v[0] = (float)(v[0] / l); v[1] = (float)(v[1] / l); v[2] = (float)(v[2] / l);
}

static lightvec_material material(float kd, float ks, float ns)
{
    lightvec_material m;
    memset(&m, 0, sizeof m);
    set3(m.diffuse, kd, 0.8f * kd, 0.5f * kd);
    set3(m.specular, ks, ks, 0.9f * ks);
    m.exponent = ns;
    return m;
}

/* An incoming radiance field that records every ray it answers. */
#define LOG_MAX 20000
typedef struct ray_log {
    int count;
    float dir[LOG_MAX][3];
    float rad[LOG_MAX][3];
} ray_log;

static void field_logged(void *user, const float org[3], const float dir[3], float radiance[3], float *distance)
{
    ray_log *log = (ray_log *)user;
    /* a bright lobe toward (0.6, 0.2, 0.77), a dimmer coloured one elsewhere */
    double a = 0.6 * dir[0] + 0.2 * dir[1] + 0.77 * dir[2], b = -0.7 * dir[0] + 0.1 * dir[1] + 0.7 * dir[2];
    double l1 = a > 0 ? pow(a, 6.0) : 0.0, l2 = b > 0 ? b * b : 0.0;
    (void)org;
    radiance[0] = (float)(0.1 + 3.0 * l1 + 0.5 * l2);
    radiance[1] = (float)(0.2 + 2.0 * l1 + 0.1 * l2);
    radiance[2] = (float)(0.05 + 1.0 * l1 + 0.9 * l2);
    *distance = (float)(1.0 + 0.5 * dir[0] * dir[0]);
    if (log->count < LOG_MAX) {
        memcpy(log->dir[log->count], dir, 3 * sizeof(float));
        memcpy(log->rad[log->count], radiance, 3 * sizeof(float));
        log->count++;
    }
}

static ray_log g_log;

/* ---- light vector: exact at its computing point ---------------------------------- */

/* The normalized Phong lobe alone, in double. */
static double lobe_ref(double e, const float *n, const float *wi, const float *wo)
{
    double c = dot3d(n, wi), ca = 0.0;
    int k;
    for (k = 0; k < 3; k++) ca += (2.0 * c * n[k] - wi[k]) * wo[k];
    return ca > 0.0 ? (e + 2.0) / (2.0 * PI) * pow(ca, e) : 0.0;
}

/* The gathered radiance written out from the logged rays: the first M N are
   the strata, the rest were drawn from the lobe around the mirror direction
   m (glossy surfaces), all weighted by the balance heuristic:
     L = rho_d / pi * 2 pi / (MN) sum_strata L cos
       + rho_s * sum_all lobe L cos / (MN / (2 pi) + K (e + 1) / (2 pi) (w . m)^e). */
static void check_exact(const lightvec_material *m, const float n[3], const float wo[3], uint32_t flags)
{
    lightvec_gather_desc gd;
    lightvec_surface sf;
    lightvec_record rec;
    double expect[3] = { 0, 0, 0 }, mirror[3], e = m->exponent;
    const int strata = 300, lobe = 64;
    int glossy = !flags && (m->specular[0] > 0 || m->specular[1] > 0 || m->specular[2] > 0), i, k;
    float got[3];
    memset(&gd, 0, sizeof gd);
    gd.strata_theta = 10;
    gd.strata_phi = 30;
    gd.glossy_samples = (uint32_t)lobe;
    gd.seed = 7;
    gd.incoming_radiance = field_logged;
    gd.incoming_user = &g_log;
    memset(&sf, 0, sizeof sf);
    set3(sf.position, 0.1f, 0.2f, 0.3f);
    memcpy(sf.normal, n, sizeof sf.normal);
    memcpy(sf.outgoing, wo, sizeof sf.outgoing);
    sf.flags = flags;
    sf.material = *m;
    g_log.count = 0;
    if (!CHECK(lightvec_gather(NULL, &gd, &sf, 42, &rec) == LIGHTVEC_OK)) return;
    if (glossy) CHECK(g_log.count > strata && g_log.count <= strata + lobe); /* lobe rays below the horizon are not cast */
    else CHECK_EQ_INT(g_log.count, strata);
    for (k = 0; k < 3; k++) mirror[k] = 2.0 * dot3d(rec.normal, rec.outgoing) * rec.normal[k] - rec.outgoing[k];
    for (i = 0; i < g_log.count; i++) {
        double c = dot3d(rec.normal, g_log.dir[i]), cm = 0.0, q, f;
        CHECK(c > 0.0);
        for (k = 0; k < 3; k++) cm += mirror[k] * g_log.dir[i][k];
        if (i < strata)
            for (k = 0; k < 3; k++) expect[k] += 2.0 * PI / strata * m->diffuse[k] / PI * g_log.rad[i][k] * c;
        if (!glossy) continue;
        q = strata / (2.0 * PI) + (cm > 0 ? lobe * (e + 1.0) / (2.0 * PI) * pow(cm, e) : 0.0);
        f = lobe_ref(e, rec.normal, g_log.dir[i], rec.outgoing);
        for (k = 0; k < 3; k++) expect[k] += m->specular[k] * f * g_log.rad[i][k] * c / q;
    }
    lightvec_radiance(m, rec.normal, flags ? NULL : rec.outgoing, &rec.vector, got);
    /* float precision: M and M_g are stored as float, the BRDF and cosines
       are recomputed from the stored D and D_g; a few ulps of each plus the
       cos theta of a stratum (computed before the direction is normalised) */
    for (k = 0; k < 3; k++) CHECK_CLOSE(got[k], expect[k], 1e-5, 1e-9);
    for (k = 0; k < 3; k++) CHECK(isfinite(rec.vector.magnitude[k]) && isfinite(rec.vector.glossy_magnitude[k]));
}

static void test_vector_reproduces_gathered_radiance(void)
{
    float n[3], wo[4][3];
    lightvec_material mats[4];
    int i, j;
    set3(n, 0.1f, 0.2f, 0.97f);
    normalize3(n);
    set3(wo[0], 0.0f, 0.0f, 1.0f);
    set3(wo[1], 0.7f, 0.1f, 0.7f);
    set3(wo[2], -0.5f, 0.6f, 0.62f);
    set3(wo[3], 0.3f, -0.9f, 0.3f);
    for (i = 0; i < 4; i++) normalize3(wo[i]);
    mats[0] = material(0.7f, 0.0f, 0.0f);    /* Lambert */
    mats[1] = material(0.4f, 0.4f, 10.0f);   /* broad gloss */
    mats[2] = material(0.2f, 0.6f, 80.0f);   /* sharp gloss */
    mats[3] = material(0.05f, 0.9f, 300.0f); /* nearly a mirror */
    for (i = 0; i < 4; i++)
        for (j = 0; j < 4; j++) check_exact(&mats[i], n, wo[j], 0);
    check_exact(&mats[0], n, wo[0], LIGHTVEC_RECORD_VIEW_INDEPENDENT);
}

/* The glossy vector depends on the viewer: the same point seen from two
   directions gets different magnitudes (the 5D extension is not trivial). */
static void test_glossy_vector_depends_on_view(void)
{
    lightvec_gather_desc gd;
    lightvec_surface sf;
    lightvec_record a, b;
    int k;
    memset(&gd, 0, sizeof gd);
    gd.incoming_radiance = field_logged;
    gd.incoming_user = &g_log;
    memset(&sf, 0, sizeof sf);
    set3(sf.normal, 0, 0, 1);
    set3(sf.outgoing, 0, 0, 1);
    sf.material = material(0.2f, 0.6f, 40.0f);
    CHECK(lightvec_gather(NULL, &gd, &sf, 1, &a) == LIGHTVEC_OK);
    /* the viewer whose mirror direction is the field's bright lobe */
    set3(sf.outgoing, -0.6f, -0.2f, 0.77f);
    normalize3(sf.outgoing);
    CHECK(lightvec_gather(NULL, &gd, &sf, 1, &b) == LIGHTVEC_OK);
    CHECK(b.glossy[0] > 2.0 * a.glossy[0]);
    /* the diffuse vector (eq. 2, eq. 3 with the Lambert term) does not
       involve the viewer: same strata, same rays, same vector */
    for (k = 0; k < 3; k++) {
        CHECK(a.vector.direction[k] == b.vector.direction[k]);
        CHECK(a.vector.magnitude[k] == b.vector.magnitude[k]);
    }
}

/* ---- furnace: uniform radiance ---------------------------------------------------------- */

static void furnace(void *user, const float org[3], const float dir[3], float radiance[3], float *distance)
{
    (void)user; (void)org; (void)dir;
    set3(radiance, 1.0f, 0.5f, 0.25f);
    *distance = 2.0f;
}

static void test_furnace(void)
{
    lightvec_gather_desc gd;
    lightvec_surface sf;
    lightvec_record rec;
    int c, k;
    memset(&gd, 0, sizeof gd);
    gd.incoming_radiance = furnace;
    memset(&sf, 0, sizeof sf);
    set3(sf.normal, 0.3f, -0.4f, 0.866f);
    normalize3(sf.normal);
    memcpy(sf.outgoing, sf.normal, sizeof sf.outgoing);
    sf.material = material(0.5f, 0.3f, 20.0f);
    if (!CHECK(lightvec_gather(NULL, &gd, &sf, 3, &rec) == LIGHTVEC_OK)) return;
    /* E = pi L; the jittered strata (12 x 36, default) estimate the cosine
       integral with a standard deviation of 2 pi / (M sqrt(12 M N)) = 0.7% */
    CHECK_CLOSE(rec.irradiance[0], PI, 0.02, 0);
    CHECK_CLOSE(rec.irradiance[1], 0.5 * PI, 0.02, 0);
    /* every stratum sees the same radiance: the gradient is exactly zero */
    for (c = 0; c < 3; c++)
        for (k = 0; k < 3; k++) CHECK(rec.gradient[c][k] == 0.0f);
    /* harmonic mean of equal distances */
    CHECK_CLOSE(rec.distance, 2.0, 1e-6, 0);
    /* D = integral of w over the hemisphere = pi n: along the normal (within 1 degree) */
    CHECK(dot3d(rec.vector.direction, sf.normal) > cos(PI / 180.0));
    CHECK_CLOSE(rec.visibility, 1.0, 0, 0);
}

/* Uniform radiance 1 and a lobe well above the horizon: the lobe reflects
   G = integral of (e + 2) / (2 pi) cos^e alpha cos theta_i = cos theta_r
   (cos theta_i averages cos alpha cos theta_r over the lobe, and
   (e + 2) / (2 pi) integral cos^(e + 1) alpha = 1), so the view gradient is
   the derivative of n . w_r on the sphere, n - (n . w_r) w_r. Exponent 60,
   30 degrees off the normal: the lobe's tail past the horizon (70 degrees
   away, cos^60 = 1e-28) is nothing. */
static void test_glossy_furnace(void)
{
    lightvec_gather_desc gd;
    lightvec_surface sf;
    lightvec_record rec;
    double c = cos(PI / 6), s = sin(PI / 6), expect[3], grad[3] = { 0, 0, 0 };
    int k, seed;
    memset(&gd, 0, sizeof gd);
    gd.incoming_radiance = furnace;
    memset(&sf, 0, sizeof sf);
    set3(sf.normal, 0, 0, 1);
    set3(sf.outgoing, (float)s, 0, (float)c);
    sf.material = material(0.0f, 1.0f, 60.0f);
    for (seed = 0; seed < 4; seed++) {
        gd.seed = (uint64_t)seed;
        if (!CHECK(lightvec_gather(NULL, &gd, &sf, 5, &rec) == LIGHTVEC_OK)) return;
        /* 1,200 strata and 256 lobe rays under the balance heuristic: the
           estimate of this smooth integrand is within 1% */
        CHECK_CLOSE(rec.glossy[0], c, 0.01, 0);
        CHECK_CLOSE(rec.glossy[1], 0.5 * c, 0.01, 0);
        for (k = 0; k < 3; k++) grad[k] += rec.glossy_gradient[0][k] / 4;
    }
    /* n - cos theta w_r = (-s c, 0, s^2), of length 0.5; one gather's
       estimate scatters by about 8% of it (measured over seeds, unbiased:
       0.1% with 40 x 120 strata and 4,096 lobe rays), the mean of 4 by 4%:
       5% of the length */
    expect[0] = -s * c; expect[1] = 0; expect[2] = s * s;
    for (k = 0; k < 3; k++) CHECK_CLOSE(grad[k], expect[k], 0, 0.025);
    CHECK_CLOSE(rec.glossy_distance, 2.0, 1e-6, 0);  /* every ray sees distance 2 */
    CHECK(rec.exponent == 60.0f);
    /* the glossy light vector points at the mirror direction */
    CHECK_CLOSE(rec.vector.glossy_direction[0], -s, 1e-6, 1e-6);
    CHECK_CLOSE(rec.vector.glossy_direction[2], c, 1e-6, 1e-6);
}

/* ---- gradient: a strip light of height H at distance h ----------------------------------- */

/* A wall x = 1 (facing -x), 0 < z < H, infinite in y, radiance 1; nothing else. */
static void strip(void *user, const float org[3], const float dir[3], float radiance[3], float *distance)
{
    double H = *(const double *)user, t, z;
    set3(radiance, 0, 0, 0);
    *distance = INFINITY;
    if (dir[0] <= 0.0f) return;
    t = (1.0 - org[0]) / dir[0];
    z = org[2] + t * dir[2];
    if (z > 0.0 && z < H) {
        set3(radiance, 1, 1, 1);
        *distance = (float)t;
    }
}

static void test_gradient_strip_light(void)
{
    /* E(h) = pi/2 (1 - h / sqrt(h^2 + H^2)) and dE/dx = pi/2 H^2 / (h^2 + H^2)^1.5
       toward the wall (integrate z h / r^4 over the wall) */
    double H = 1.0, h = 1.0, e_exact = PI / 2 * (1 - h / sqrt(h * h + H * H));
    double g_exact = PI / 2 * H * H / pow(h * h + H * H, 1.5), gx = 0, gy = 0, gz = 0, e = 0;
    lightvec_gather_desc gd;
    lightvec_surface sf;
    lightvec_record rec;
    int s;
    memset(&gd, 0, sizeof gd);
    gd.strata_theta = 48;
    gd.strata_phi = 144;
    gd.incoming_radiance = strip;
    gd.incoming_user = &H;
    memset(&sf, 0, sizeof sf);
    set3(sf.normal, 0, 0, 1);
    sf.flags = LIGHTVEC_RECORD_VIEW_INDEPENDENT;
    sf.material = material(0.5f, 0, 0);
    for (s = 0; s < 4; s++) { /* average of 4 seeds: the estimate's noise is not under test */
        gd.seed = (uint64_t)s;
        if (!CHECK(lightvec_gather(NULL, &gd, &sf, 0, &rec) == LIGHTVEC_OK)) return;
        e += rec.irradiance[0] / 4;
        gx += rec.gradient[0][0] / 4;
        gy += rec.gradient[0][1] / 4;
        gz += rec.gradient[0][2] / 4;
    }
    test_note("strip light: E = %.4f (exact %.4f), dE/dx = %.4f (exact %.4f), dE/dy = %.4f", e, e_exact, gx,
              g_exact, gy);
    CHECK_CLOSE(e, e_exact, 0.01, 0); /* 6912 strata: noise well under 1% */
    /* Ward & Heckbert's estimate: boundaries between strata with one ray
       each, the min of two distances; 10% covers its discretisation */
    CHECK_CLOSE(gx, g_exact, 0.10, 0);
    CHECK(fabs(gy) < 0.05 * g_exact); /* symmetric in y */
    CHECK(gz == 0.0);                 /* in the tangent plane */
    /* the gradient predicts E one step closer */
    {
        double h2 = 0.9, e2 = PI / 2 * (1 - h2 / sqrt(h2 * h2 + H * H));
        CHECK_CLOSE(e + 0.1 * gx, e2, 0.02, 0);
    }
}

/* ---- BRDF ----------------------------------------------------------------------------------- */

static void test_brdf(void)
{
    lightvec_material m = material(0.6f, 0.3f, 20.0f);
    float n[3] = { 0, 0, 1 }, wi[3] = { 0.6f, 0, 0.8f }, wo[3] = { -0.6f, 0, 0.8f }, f[3];
    double albedo = 0;
    int i, j;
    lightvec_brdf(&m, n, wi, wo, f);
    /* at the mirror direction: rho_d / pi + rho_s (n + 2) / (2 pi) */
    CHECK_CLOSE(f[0], 0.6 / PI + 0.3 * 22.0 / (2 * PI), 1e-6, 0);
    /* normal incidence: albedo = rho_d + rho_s exactly (the lobe is normalised) */
    set3(wi, 0, 0, 1);
    for (i = 0; i < 400; i++)
        for (j = 0; j < 400; j++) {
            double ct = (i + 0.5) / 400, st = sqrt(1 - ct * ct), phi = 2 * PI * (j + 0.5) / 400;
            set3(wo, (float)(st * cos(phi)), (float)(st * sin(phi)), (float)ct);
            lightvec_brdf(&m, n, wi, wo, f);
            albedo += f[0] * ct * 2 * PI / (400.0 * 400.0);
        }
    CHECK_CLOSE(albedo, 0.9, 2e-3, 0); /* midpoint rule on 160000 cells */
}

/* ---- direct light against the closed-form polygon factor ------------------------------------- */

/* Irradiance at p (normal n) from a Lambertian polygon of radiance L:
   E = L * 1/2 sum_i angle_i (n . unit(v_i x v_i+1)) (Lambert's formula). */
static double polygon_irradiance(const float p[3], const float n[3], const float *v, int count, double L)
{
    double s = 0;
    int i;
    for (i = 0; i < count; i++) {
        double a[3], b[3], c[3], la, lb, lc, ang;
        int k;
        for (k = 0; k < 3; k++) { a[k] = v[3 * i + k] - p[k]; b[k] = v[3 * ((i + 1) % count) + k] - p[k]; }
        la = sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
        lb = sqrt(b[0] * b[0] + b[1] * b[1] + b[2] * b[2]);
        ang = acos((a[0] * b[0] + a[1] * b[1] + a[2] * b[2]) / (la * lb));
        c[0] = a[1] * b[2] - a[2] * b[1]; c[1] = a[2] * b[0] - a[0] * b[2]; c[2] = a[0] * b[1] - a[1] * b[0];
        lc = sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
        s += ang * (c[0] * n[0] + c[1] * n[1] + c[2] * n[2]) / lc;
    }
    return fabs(0.5 * L * s);
}

/* A floor (y = 0, 4 x 4) under a square light (y = 1, 0.5 x 0.5, facing down);
   optionally a small occluder plate at y = 0.5. */
typedef struct light_scene {
    float pos[16 * 3];
    uint32_t idx[8 * 3];
    uint32_t mat[8];
    lightvec_material mats[2];
    uint32_t tris;
} light_scene;

static void light_scene_init(light_scene *s, int occluder)
{
    static const float p[12][3] = {
        { -2, 0, -2 }, { 2, 0, -2 }, { 2, 0, 2 }, { -2, 0, 2 },              /* floor, up */
        { -0.25f, 1, -0.25f }, { 0.25f, 1, -0.25f }, { 0.25f, 1, 0.25f }, { -0.25f, 1, 0.25f }, /* light */
        { 0.6f, 0.5f, -0.3f }, { 1.0f, 0.5f, -0.3f }, { 1.0f, 0.5f, 0.3f }, { 0.6f, 0.5f, 0.3f } /* plate */
    };
    static const uint32_t t[6][3] = { { 0, 2, 1 }, { 0, 3, 2 }, { 4, 5, 6 }, { 4, 6, 7 }, { 8, 9, 10 }, { 8, 10, 11 } };
    int i;
    memset(s, 0, sizeof *s);
    memcpy(s->pos, p, sizeof p);
    s->tris = occluder ? 6 : 4;
    for (i = 0; i < (int)s->tris; i++) {
        memcpy(s->idx + 3 * i, t[i], sizeof t[i]);
        s->mat[i] = (i == 2 || i == 3) ? 1u : 0u;
    }
    s->mats[0] = material(0.5f, 0, 0);
    s->mats[1] = material(0.0f, 0, 0);
    set3(s->mats[1].emission, 10.0f, 10.0f, 10.0f);
}

static lightvec_scene *light_scene_create(light_scene *s)
{
    lightvec_scene_desc d;
    lightvec_scene *scene = NULL;
    memset(&d, 0, sizeof d);
    d.positions = s->pos;
    d.vertex_count = 12;
    d.indices = s->idx;
    d.triangle_count = s->tris;
    d.material_ids = s->mat;
    d.materials = s->mats;
    d.material_count = 2;
    CHECK(lightvec_scene_create(&d, &scene) == LIGHTVEC_OK);
    return scene;
}

static void test_direct_light_closed_form(void)
{
    light_scene ls;
    lightvec_scene *scene;
    lightvec_scene_stats st;
    lightvec_gather_desc gd;
    lightvec_surface sf;
    lightvec_record rec;
    static const float light[12] = { -0.25f, 1, -0.25f, 0.25f, 1, -0.25f, 0.25f, 1, 0.25f, -0.25f, 1, 0.25f };
    float pts[3][3] = { { 0, 0, 0 }, { 0.7f, 0, 0.2f }, { -1.5f, 0, 1.2f } };
    int i;
    light_scene_init(&ls, 0);
    scene = light_scene_create(&ls);
    if (!scene) return;
    CHECK(lightvec_scene_info(scene, &st) == LIGHTVEC_OK);
    CHECK_EQ_INT(st.emitter_count, 2);
    CHECK_EQ_INT(st.degenerate_count, 0);
    memset(&gd, 0, sizeof gd);
    gd.strata_theta = 32;
    gd.strata_phi = 32;
    memset(&sf, 0, sizeof sf);
    set3(sf.normal, 0, 1, 0);
    set3(sf.outgoing, 0, 1, 0);
    sf.material = ls.mats[0];
    for (i = 0; i < 3; i++) {
        double e;
        memcpy(sf.position, pts[i], sizeof sf.position);
        if (!CHECK(lightvec_gather_direct(scene, &gd, &sf, (uint64_t)i, &rec) == LIGHTVEC_OK)) break;
        e = polygon_irradiance(pts[i], sf.normal, light, 4, 10.0);
        /* 1024 stratified area samples of a light 0.5 wide at distance >= 1 */
        CHECK_CLOSE(rec.irradiance[0], e, 0.01, 0);
        CHECK_CLOSE(rec.visibility, 1.0, 0, 0);
        /* Lambert: M f cos = rho/pi E exactly */
        {
            float rgb[3];
            lightvec_radiance(&sf.material, rec.normal, rec.outgoing, &rec.vector, rgb);
            CHECK_CLOSE(rgb[0], 0.5 / PI * rec.irradiance[0], 1e-5, 0);
        }
    }
    /* exact derivative of the estimate vs. a finite difference of the closed form */
    {
        float p1[3] = { 0.7f, 0, 0.2f }, p2[3] = { 0.701f, 0, 0.2f }, p0[3] = { 0.699f, 0, 0.2f };
        double fd = (polygon_irradiance(p2, sf.normal, light, 4, 10.0) - polygon_irradiance(p0, sf.normal, light, 4, 10.0)) / 0.002;
        memcpy(sf.position, p1, sizeof sf.position);
        CHECK(lightvec_gather_direct(scene, &gd, &sf, 9, &rec) == LIGHTVEC_OK);
        CHECK_CLOSE(rec.gradient[0][0], fd, 0.02, 0);
        CHECK(fabs(rec.gradient[0][1]) < 1e-4 * fabs(fd)); /* tangent plane y = 0 */
    }
    lightvec_scene_destroy(scene);
}

/* ---- the DLV cache: penumbra records and mixed classes make misses ------------------------------ */

/* A Lambertian surface facing +y, seen from above (its position is set by the caller). */
static lightvec_surface upward_surface(lightvec_material m)
{
    lightvec_surface sf;
    memset(&sf, 0, sizeof sf);
    set3(sf.normal, 0, 1, 0);
    set3(sf.outgoing, 0, 1, 0);
    sf.flags = LIGHTVEC_RECORD_VIEW_INDEPENDENT;
    sf.material = m;
    return sf;
}

static void test_direct_cache_visibility_rule(void)
{
    light_scene ls;
    lightvec_scene *scene;
    lightvec_cache *cache = NULL;
    lightvec_cache_desc cd;
    lightvec_gather_desc gd;
    lightvec_surface sf;
    lightvec_record rec;
    lightvec_lookup_result lr;
    float x;
    int lit_hits = 0, lit_tries = 0, lit_bad = 0, misses_in_penumbra = 0, penumbra_tries = 0;
    double worst_penumbra = 0, lit_level = 1;
    uint32_t i;
    light_scene_init(&ls, 1);
    scene = light_scene_create(&ls);
    if (!scene) return;
    memset(&cd, 0, sizeof cd);
    cd.kind = LIGHTVEC_KIND_DIRECT;
    CHECK(lightvec_cache_create(&cd, &cache) == LIGHTVEC_OK);
    memset(&gd, 0, sizeof gd);
    gd.strata_theta = 8;
    gd.strata_phi = 8;
    sf = upward_surface(ls.mats[0]);
    /* a line of points along x through the plate's shadow (plate x 0.6..1 at
       half the light's height, light x -0.25..0.25): umbra x 1.45..1.75,
       penumbrae 0.95..1.45 and 1.75..2.25 */
    for (i = 0; i < 400 && cache; i++) {
        x = -1.0f + 3.0f * (float)i / 400.0f;
        set3(sf.position, x, 0, 0);
        CHECK(lightvec_lookup(cache, sf.position, sf.normal, NULL, &lr) == LIGHTVEC_OK);
        if (!lr.hit) {
            CHECK(lightvec_gather_direct(scene, &gd, &sf, i, &rec) == LIGHTVEC_OK);
            CHECK(lightvec_insert(cache, &rec, NULL) == LIGHTVEC_OK);
        }
    }
    /* the unshadowed irradiance near the shadow, as the scale of penumbra errors */
    set3(sf.position, 1.5f, 0, 0);
    {
        light_scene open_ls;
        lightvec_scene *open_scene;
        light_scene_init(&open_ls, 0);
        open_scene = light_scene_create(&open_ls);
        if (open_scene) {
            CHECK(lightvec_gather_direct(open_scene, &gd, &sf, 0, &rec) == LIGHTVEC_OK);
            lit_level = rec.irradiance[0];
            lightvec_scene_destroy(open_scene);
        }
    }
    /* second pass: hits only where the records agree on visibility */
    for (i = 0; i < 200 && cache; i++) {
        float rgb[3];
        uint32_t ids[64], k, count, partial = 0;
        float w[64];
        double exact, err;
        x = -1.0f + 3.0f * ((float)i + 0.37f) / 200.0f;
        set3(sf.position, x, 0, 0);
        CHECK(lightvec_gather_direct(scene, &gd, &sf, 1000 + i, &rec) == LIGHTVEC_OK);
        CHECK(lightvec_lookup(cache, sf.position, sf.normal, NULL, &lr) == LIGHTVEC_OK);
        CHECK(lightvec_find(cache, sf.position, sf.normal, NULL, ids, w, 64, &count) == LIGHTVEC_OK);
        for (k = 0; k < count && k < 64; k++) {
            lightvec_record other;
            lightvec_cache_record(cache, ids[k], &other);
            partial += other.visibility > 0.0f && other.visibility < 1.0f;
        }
        if (partial) CHECK(!lr.hit); /* a valid penumbra record always makes a miss */
        exact = 0.5 / PI * rec.irradiance[0];
        lightvec_radiance(&sf.material, sf.normal, NULL, &lr.vector, rgb);
        err = lr.hit ? fabs(rgb[0] - exact) / exact : 0.0;
        if (rec.visibility > 0.0f && rec.visibility < 1.0f) {
            /* in a penumbra, relative to the radiance the point would get unshadowed */
            err = lr.hit ? fabs(rgb[0] - exact) / (0.5 / PI * lit_level) : 0.0;
            penumbra_tries++;
            misses_in_penumbra += !lr.hit;
            if (err > worst_penumbra) worst_penumbra = err;
        }
        if (x < 0.3f) { /* far from the shadow: fully lit */
            lit_tries++;
            lit_hits += lr.hit;
            lit_bad += err > 0.05;
        }
    }
    test_note("DLV line: %d/%d lit hits (%d off by > 5%%), %d/%d penumbra points missed, worst penumbra hit "
              "off by %.1f%% of the unshadowed light", lit_hits, lit_tries, lit_bad, misses_in_penumbra, penumbra_tries, 100 * worst_penumbra);
    CHECK(penumbra_tries > 10);
    /* a penumbra point is interpolated only where the shadow starts inside the
       radius of fully lit (or umbra) records, before any penumbra record is
       near (documented); there the light is nearly all (or nothing) */
    CHECK(misses_in_penumbra > penumbra_tries / 2);
    CHECK(worst_penumbra < 0.35);
    CHECK(lit_hits > lit_tries / 2);
    CHECK_EQ_INT(lit_bad, 0);
    lightvec_cache_destroy(cache);
    lightvec_scene_destroy(scene);
}

/* ---- built-in renderer ------------------------------------------------------------------------ */

/* The point (0.8, 0, 0) on the floor sits under the plate, whose front (lit
   side) faces down: with bounces = 1 the only light it can gather is direct
   light reflected once at what it sees, and the plate's underside gets none,
   so the indirect light is zero; bounces = 2 adds floor -> plate -> point. */
static void test_bounces(void)
{
    light_scene ls;
    lightvec_scene *scene;
    lightvec_gather_desc gd;
    lightvec_surface sf;
    lightvec_record rec;
    light_scene_init(&ls, 1);
    scene = light_scene_create(&ls);
    if (!scene) return;
    memset(&gd, 0, sizeof gd);
    memset(&sf, 0, sizeof sf);
    set3(sf.position, 0.8f, 0, 0);
    set3(sf.normal, 0, 1, 0);
    sf.flags = LIGHTVEC_RECORD_VIEW_INDEPENDENT;
    sf.material = ls.mats[0];
    gd.bounces = 1;
    CHECK(lightvec_gather(scene, &gd, &sf, 0, &rec) == LIGHTVEC_OK);
    CHECK(rec.irradiance[0] == 0.0f); /* the plate's underside is not lit directly */
    CHECK(rec.distance > 0.4f && rec.distance < 100.0f);
    gd.bounces = 2;
    CHECK(lightvec_gather(scene, &gd, &sf, 0, &rec) == LIGHTVEC_OK);
    CHECK(rec.irradiance[0] > 0.0f);
    /* deterministic: same (seed, index), same record */
    {
        lightvec_record again;
        CHECK(lightvec_gather(scene, &gd, &sf, 0, &again) == LIGHTVEC_OK);
        CHECK(memcmp(&again, &rec, sizeof rec) == 0);
    }
    lightvec_scene_destroy(scene);
}

/* ---- the gather's light samples at its hits go to emitters that can light them -------------- */

/* A point under a ceiling lit by a small lamp that faces it; below the
   point, out of every gather ray's reach, 8 decoy emitters 1000 times
   brighter face down, away from everything. They light nothing the gather
   sees, so the gathered light must not change when they are added. Picking
   emitters by power alone (lightvec.h before v0.4.8), they took 99.9% of
   the samples at each hit and the estimate became 1000 times noisier;
   picked by importance (power, distance and both cosines bounded, zero
   behind an emitter's plane), they take none, and the same random numbers
   choose the same lamp points (the decoys add exact zeros to the
   importance sum). */
static void test_hit_light_sampling_skips_dark_emitters(void)
{
    enum { DECOYS = 8 };
    float pos[3 * (8 + 4 * DECOYS)];
    uint32_t idx[3 * (4 + 2 * DECOYS)], mat[4 + 2 * DECOYS];
    lightvec_material mats[3];
    lightvec_scene_desc d;
    lightvec_scene *with = NULL, *without = NULL;
    lightvec_gather_desc gd;
    lightvec_surface sf;
    lightvec_record a, b;
    static const float quad[2][12] = {
        { -20, 1, -20, -20, 1, 20, 20, 1, 20, 20, 1, -20 },                          /* ceiling, facing down */
        { 0.5f, 0.2f, -0.1f, 0.7f, 0.2f, -0.1f, 0.7f, 0.2f, 0.1f, 0.5f, 0.2f, 0.1f } /* lamp, facing up */
    };
    int q, k, i;
    memcpy(pos, quad, sizeof quad);
    for (q = 0; q < DECOYS; q++) {   /* y = -1, facing down */
        float x = -4.0f + (float)q, v[12] = { 0, -1, -0.5f, 0, -1, 0.5f, 0.5f, -1, 0.5f, 0.5f, -1, -0.5f };
        for (k = 0; k < 4; k++) v[3 * k] += x;
        memcpy(pos + 24 + 12 * q, v, sizeof v);
    }
    for (q = 0; q < 2 + DECOYS; q++) {
        static const uint32_t t[6] = { 0, 2, 1, 0, 3, 2 };
        for (k = 0; k < 6; k++) idx[6 * q + k] = 4u * (uint32_t)q + t[k];
        mat[2 * q] = mat[2 * q + 1] = q == 0 ? 0u : q == 1 ? 1u : 2u;
    }
    mats[0] = material(0.5f, 0, 0);
    mats[1] = material(0.0f, 0, 0);
    set3(mats[1].emission, 10.0f, 10.0f, 10.0f);
    mats[2] = material(0.0f, 0, 0);
    set3(mats[2].emission, 10000.0f, 10000.0f, 10000.0f);
    memset(&d, 0, sizeof d);
    d.positions = pos;
    d.indices = idx;
    d.material_ids = mat;
    d.materials = mats;
    d.material_count = 3;
    d.vertex_count = 8;
    d.triangle_count = 4;
    CHECK(lightvec_scene_create(&d, &without) == LIGHTVEC_OK);
    d.vertex_count = 8 + 4 * DECOYS;
    d.triangle_count = 4 + 2 * DECOYS;
    CHECK(lightvec_scene_create(&d, &with) == LIGHTVEC_OK);
    if (!with || !without) goto done;
    memset(&gd, 0, sizeof gd);
    gd.strata_theta = 8;
    gd.bounces = 1;
    gd.light_samples = 4;
    sf = upward_surface(mats[0]);
    for (i = 0; i < 3; i++) {
        set3(sf.position, -0.3f * (float)i, 0, 0.1f * (float)i);
        if (!CHECK(lightvec_gather(without, &gd, &sf, (uint64_t)i, &a) == LIGHTVEC_OK &&
                   lightvec_gather(with, &gd, &sf, (uint64_t)i, &b) == LIGHTVEC_OK))
            break;
        CHECK(a.irradiance[0] > 0.0f);   /* the ceiling is lit by the lamp */
        /* the same samples: the decoys only widen the scene's bounds, and so its ray offset (1e-4 of
           the diagonal) by 0.05%, moving the hits by microns; one decoy sample would add ~1000x */
        CHECK_CLOSE(b.irradiance[0], a.irradiance[0], 1e-4, 0);
    }
done:
    lightvec_scene_destroy(with);
    lightvec_scene_destroy(without);
}

/* ---- priority (4.3) ----------------------------------------------------------------------------- */

static void test_priority(void)
{
    CHECK_CLOSE(lightvec_priority(2.0f, 0.5f), 4.0, 0, 0);
    CHECK_CLOSE(lightvec_priority(1.0f, 1.0f), 1.0, 0, 0);
    CHECK(lightvec_priority(1.0f, 0.0f) == LIGHTVEC_PRIORITY_MAX);
    CHECK(lightvec_priority(1.0f, NAN) == LIGHTVEC_PRIORITY_MAX);
    CHECK(lightvec_priority(1e30f, 1e-10f) == LIGHTVEC_PRIORITY_MAX);
}

static void free_only(void *p, void *user) { (void)user; free(p); }

/* ---- bad input ---------------------------------------------------------------------------------- */

static void test_bad_input(void)
{
    lightvec_cache_desc cd;
    lightvec_cache *cache = NULL;
    lightvec_gather_desc gd;
    lightvec_surface sf;
    lightvec_record rec;
    lightvec_lookup_result lr;
    lightvec_scene_desc sd;
    lightvec_scene *scene = NULL;
    float p[3] = { 0, 0, 0 }, n[3] = { 0, 0, 1 }, zero[3] = { 0, 0, 0 }, nan3[3] = { NAN, 0, 1 };
    light_scene ls;

    memset(&cd, 0, sizeof cd);
    cd.max_normal_angle = -5.0f;
    CHECK(lightvec_cache_create(&cd, &cache) == LIGHTVEC_ERROR_INVALID_ARGUMENT);
    cd.max_normal_angle = 0;
    cd.max_direction_angle = 200.0f;
    CHECK(lightvec_cache_create(&cd, &cache) == LIGHTVEC_ERROR_INVALID_ARGUMENT);
    cd.max_direction_angle = 0;
    cd.radius_scale = -1.0f;
    CHECK(lightvec_cache_create(&cd, &cache) == LIGHTVEC_ERROR_INVALID_ARGUMENT);
    cd.radius_scale = NAN;
    CHECK(lightvec_cache_create(&cd, &cache) == LIGHTVEC_ERROR_INVALID_ARGUMENT);
    cd.radius_scale = 0;
    cd.max_irradiance_change = -0.1f;
    CHECK(lightvec_cache_create(&cd, &cache) == LIGHTVEC_ERROR_INVALID_ARGUMENT);
    cd.max_irradiance_change = 0;
    cd.kind = (lightvec_kind)7;
    CHECK(lightvec_cache_create(&cd, &cache) == LIGHTVEC_ERROR_INVALID_ARGUMENT);
    cd.kind = LIGHTVEC_KIND_DEFAULT;
    cd.max_face_depth = 99;
    CHECK(lightvec_cache_create(&cd, &cache) == LIGHTVEC_ERROR_INVALID_ARGUMENT);
    cd.max_face_depth = 0;
    cd.allocator.free = free_only;  /* free without alloc */
    CHECK(lightvec_cache_create(&cd, &cache) == LIGHTVEC_ERROR_INVALID_ARGUMENT);
    CHECK(cache == NULL);
    CHECK(lightvec_cache_create(NULL, NULL) == LIGHTVEC_ERROR_INVALID_ARGUMENT);
    if (!CHECK(lightvec_cache_create(NULL, &cache) == LIGHTVEC_OK)) return;

    /* records */
    memset(&rec, 0, sizeof rec);
    set3(rec.normal, 0, 0, 1);
    set3(rec.outgoing, 0, 0, 1);
    set3(rec.vector.direction, 0, 0, 1);
    rec.distance = 1.0f;
    rec.visibility = 1.0f;
    CHECK(lightvec_insert(cache, &rec, NULL) == LIGHTVEC_OK);
    rec.normal[2] = 0.0f; /* zero normal */
    CHECK(lightvec_insert(cache, &rec, NULL) == LIGHTVEC_ERROR_INVALID_ARGUMENT);
    rec.normal[2] = 1.0f;
    rec.position[1] = NAN;
    CHECK(lightvec_insert(cache, &rec, NULL) == LIGHTVEC_ERROR_INVALID_ARGUMENT);
    rec.position[1] = 0;
    rec.distance = -1.0f;
    CHECK(lightvec_insert(cache, &rec, NULL) == LIGHTVEC_ERROR_INVALID_ARGUMENT);
    rec.distance = 1.0f;
    rec.vector.magnitude[0] = -1.0f;
    CHECK(lightvec_insert(cache, &rec, NULL) == LIGHTVEC_ERROR_INVALID_ARGUMENT);
    rec.vector.magnitude[0] = 0;
    rec.gradient[1][2] = INFINITY;
    CHECK(lightvec_insert(cache, &rec, NULL) == LIGHTVEC_ERROR_INVALID_ARGUMENT);
    rec.gradient[1][2] = 0;
    rec.visibility = 1.5f;
    CHECK(lightvec_insert(cache, &rec, NULL) == LIGHTVEC_ERROR_INVALID_ARGUMENT);
    rec.visibility = 1;
    rec.flags = 0x80;
    CHECK(lightvec_insert(cache, &rec, NULL) == LIGHTVEC_ERROR_INVALID_ARGUMENT);
    rec.flags = 0;
    set3(rec.outgoing, 0, 0, 0);
    CHECK(lightvec_insert(cache, &rec, NULL) == LIGHTVEC_ERROR_INVALID_ARGUMENT);
    CHECK(lightvec_insert(cache, NULL, NULL) == LIGHTVEC_ERROR_INVALID_ARGUMENT);

    /* lookups */
    CHECK(lightvec_lookup(cache, p, n, n, &lr) == LIGHTVEC_OK);
    CHECK_EQ_INT(lr.valid_count, 1);
    CHECK(lightvec_lookup(cache, nan3, n, n, &lr) == LIGHTVEC_ERROR_INVALID_ARGUMENT);
    CHECK(lightvec_lookup(cache, p, zero, n, &lr) == LIGHTVEC_ERROR_INVALID_ARGUMENT);
    CHECK(lightvec_lookup(cache, p, n, zero, &lr) == LIGHTVEC_ERROR_INVALID_ARGUMENT);
    CHECK(lightvec_lookup(cache, p, n, nan3, &lr) == LIGHTVEC_ERROR_INVALID_ARGUMENT);
    CHECK(lightvec_lookup(cache, p, n, n, NULL) == LIGHTVEC_ERROR_INVALID_ARGUMENT);
    CHECK(lightvec_lookup(NULL, p, n, n, &lr) == LIGHTVEC_ERROR_INVALID_ARGUMENT);
    CHECK(lightvec_cache_record(cache, 1, &rec) == LIGHTVEC_ERROR_INVALID_ARGUMENT);

    /* gathers */
    memset(&gd, 0, sizeof gd);
    gd.incoming_radiance = furnace;
    memset(&sf, 0, sizeof sf);
    set3(sf.normal, 0, 0, 1);
    set3(sf.outgoing, 0, 0, 1);
    sf.material = material(0.5f, 0, 0);
    CHECK(lightvec_gather(NULL, &gd, &sf, 0, &rec) == LIGHTVEC_OK);
    set3(sf.normal, 0, 0, 0);
    CHECK(lightvec_gather(NULL, &gd, &sf, 0, &rec) == LIGHTVEC_ERROR_INVALID_ARGUMENT);
    set3(sf.normal, 0, 0, 1);
    sf.position[0] = INFINITY;
    CHECK(lightvec_gather(NULL, &gd, &sf, 0, &rec) == LIGHTVEC_ERROR_INVALID_ARGUMENT);
    sf.position[0] = 0;
    sf.material.diffuse[1] = -0.5f;
    CHECK(lightvec_gather(NULL, &gd, &sf, 0, &rec) == LIGHTVEC_ERROR_INVALID_ARGUMENT);
    sf.material.diffuse[1] = 0.5f;
    sf.flags = LIGHTVEC_RECORD_VIEW_INDEPENDENT;
    sf.material.specular[2] = 0.1f; /* a glossy surface cannot be view-independent */
    CHECK(lightvec_gather(NULL, &gd, &sf, 0, &rec) == LIGHTVEC_ERROR_INVALID_ARGUMENT);
    sf.material.specular[2] = 0.0f;
    CHECK(lightvec_gather(NULL, &gd, &sf, 0, &rec) == LIGHTVEC_OK);
    sf.flags = 0;
    gd.strata_theta = 100000;
    CHECK(lightvec_gather(NULL, &gd, &sf, 0, &rec) == LIGHTVEC_ERROR_INVALID_ARGUMENT);
    gd.strata_theta = 0;
    gd.min_distance = -1.0f;
    CHECK(lightvec_gather(NULL, &gd, &sf, 0, &rec) == LIGHTVEC_ERROR_INVALID_ARGUMENT);
    gd.min_distance = 2.0f;
    gd.max_distance = 1.0f;
    CHECK(lightvec_gather(NULL, &gd, &sf, 0, &rec) == LIGHTVEC_ERROR_INVALID_ARGUMENT);
    gd.min_distance = gd.max_distance = 0;
    gd.incoming_radiance = NULL; /* no renderer at all */
    CHECK(lightvec_gather(NULL, &gd, &sf, 0, &rec) == LIGHTVEC_ERROR_INVALID_ARGUMENT);
    CHECK(lightvec_gather_direct(NULL, &gd, &sf, 0, &rec) == LIGHTVEC_ERROR_INVALID_ARGUMENT);

    /* scenes */
    light_scene_init(&ls, 0);
    memset(&sd, 0, sizeof sd);
    sd.positions = ls.pos;
    sd.vertex_count = 12;
    sd.indices = ls.idx;
    sd.triangle_count = ls.tris;
    sd.materials = ls.mats;
    sd.material_count = 2;
    ls.idx[5] = 12; /* out of range */
    CHECK(lightvec_scene_create(&sd, &scene) == LIGHTVEC_ERROR_INVALID_ARGUMENT);
    ls.idx[5] = 1;
    ls.pos[4] = NAN;
    CHECK(lightvec_scene_create(&sd, &scene) == LIGHTVEC_ERROR_INVALID_ARGUMENT);
    ls.pos[4] = 0;
    sd.material_ids = ls.mat;
    ls.mat[0] = 5;
    CHECK(lightvec_scene_create(&sd, &scene) == LIGHTVEC_ERROR_INVALID_ARGUMENT);
    ls.mat[0] = 0;
    ls.mats[0].exponent = -1.0f;
    CHECK(lightvec_scene_create(&sd, &scene) == LIGHTVEC_ERROR_INVALID_ARGUMENT);
    ls.mats[0].exponent = 0;
    sd.triangle_count = 0;
    CHECK(lightvec_scene_create(&sd, &scene) == LIGHTVEC_ERROR_INVALID_ARGUMENT);
    sd.triangle_count = ls.tris;
    sd.stride = 5;
    CHECK(lightvec_scene_create(&sd, &scene) == LIGHTVEC_ERROR_INVALID_ARGUMENT);
    sd.stride = 0;
    /* degenerate triangles are skipped and counted */
    ls.idx[3] = ls.idx[4] = ls.idx[5] = 0;
    if (CHECK(lightvec_scene_create(&sd, &scene) == LIGHTVEC_OK)) {
        lightvec_scene_stats st;
        lightvec_scene_info(scene, &st);
        CHECK_EQ_INT(st.degenerate_count, 1);
        lightvec_scene_destroy(scene);
    }
    CHECK(strcmp(lightvec_result_string(LIGHTVEC_ERROR_CORRUPT_DATA), "corrupt data") == 0);
    lightvec_cache_destroy(cache);
}

int main(int argc, char **argv)
{
    TEST_INIT(argc, argv);
    RUN(test_vector_reproduces_gathered_radiance);
    RUN(test_glossy_vector_depends_on_view);
    RUN(test_furnace);
    RUN(test_glossy_furnace);
    RUN(test_gradient_strip_light);
    RUN(test_brdf);
    RUN(test_direct_light_closed_form);
    RUN(test_direct_cache_visibility_rule);
    RUN(test_bounces);
    RUN(test_hit_light_sampling_skips_dark_emitters);
    RUN(test_priority);
    RUN(test_bad_input);
    return test_finish();
}
