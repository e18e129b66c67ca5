/* Unit tests of the light-vector cache of lightvec.h: lookups against a brute
   force scan of every record with the criteria of section 4.2 written out
   here (10^5 random records, insertions, optimize, save/load), the recursive
   icosahedron (threshold, point location, solid angles), interpolation and
   the weight W, hostile loading (every truncation, corrupted bytes), and
   allocation failures at every allocation. */
#define LIGHTVEC_IMPLEMENTATION
#include "lightvec.h"
#include "examples/common/pool.h"
#include "tests/test.h"

#define PI 3.14159265358979323846

/* ---- random records ------------------------------------------------------------ */

typedef struct rng { uint64_t s; } rng;
static double rnd(rng *r)
{
    r->s = r->s * 6364136223846793005ull + 1442695040888963407ull;
    return (double)(r->s >> 11) * (1.0 / 9007199254740992.0);
}

static void random_unit(rng *r, float *v)
{
    double z = 2 * rnd(r) - 1, phi = 2 * PI * rnd(r), s = sqrt(1 - z * z);
    v[0] = (float)(s * cos(phi)); v[1] = (float)(s * sin(phi)); v[2] = (float)z;
}

/* base tilted by up to max_deg degrees */
static void jitter(rng *r, const float *base, double max_deg, float *out)
{
    float d[3];
    double a = max_deg * PI / 180.0 * rnd(r), l;
    int k;
    random_unit(r, d);
    for (k = 0; k < 3; k++) out[k] = (float)(base[k] * cos(a) + d[k] * sin(a));
    l = sqrt((double)out[0] * out[0] + (double)out[1] * out[1] + (double)out[2] * out[2]);
    for (k = 0; k < 3; k++) out[k] = (float)(out[k] / l);
}

static double dot3(const float *a, const float *b) { return (double)a[0] * b[0] + (double)a[1] * b[1] + (double)a[2] * b[2]; }

static const float axes[6][3] = { { 1, 0, 0 }, { -1, 0, 0 }, { 0, 1, 0 }, { 0, -1, 0 }, { 0, 0, 1 }, { 0, 0, -1 } };

/* Records in the unit cube, normals near the six axes, viewer directions half
   near eight cluster directions and half uniform, radii scaled so that a
   point is inside ~dozens of validity spheres, gradients that make the
   irradiance-change criterion matter; half of the 5D records have a glossy
   part (a lobe, its view gradient, a lobe distance for the parallax). */
static void random_record(rng *r, lightvec_record *rec, double radius_scale)
{
    static const float clusters[8][3] = { { 0.577f, 0.577f, 0.577f }, { -0.577f, 0.577f, 0.577f },
                                          { 0.577f, -0.577f, 0.577f }, { 0.577f, 0.577f, -0.577f },
                                          { 0, 0.8f, 0.6f },          { 0.6f, 0, -0.8f },
                                          { -0.8f, -0.6f, 0 },        { 0, 0, -1 } };
    int k, c;
    memset(rec, 0, sizeof *rec);
    for (k = 0; k < 3; k++) rec->position[k] = (float)rnd(r);
    jitter(r, axes[(int)(rnd(r) * 6) % 6], 12.0, rec->normal);
    if (rnd(r) < 0.5) jitter(r, clusters[(int)(rnd(r) * 8) % 8], 8.0, rec->outgoing);
    else random_unit(r, rec->outgoing);
    random_unit(r, rec->vector.direction);
    for (c = 0; c < 3; c++) {
        rec->vector.magnitude[c] = (float)(0.1 + 2 * rnd(r));
        rec->irradiance[c] = (float)(0.2 + rnd(r));
        for (k = 0; k < 3; k++) rec->gradient[c][k] = (float)((rnd(r) - 0.5) * 8.0 * rnd(r));
    }
    if (rnd(r) < 0.02) rec->irradiance[0] = rec->irradiance[1] = rec->irradiance[2] = 0.0f; /* dark */
    rec->distance = (float)(radius_scale * (0.5 + rnd(r)));
    rec->visibility = 1.0f;
    rec->flags = rnd(r) < 0.1 ? LIGHTVEC_RECORD_VIEW_INDEPENDENT : 0u;
    if (!rec->flags && rnd(r) < 0.5) {
        /* lobes from broad to narrow (direction angles 35 .. 3 degrees),
           changes and parallax that pass or fail the glossy criteria */
        rec->exponent = (float)(2.0 + 400.0 * rnd(r) * rnd(r));
        rec->glossy_distance = (float)(0.2 + 2.0 * rnd(r));
        rec->glossy_share = rnd(r) < 0.3 ? 0.0f : (float)(0.05 + 0.95 * rnd(r)); /* 0 reads as 1 */
        for (c = 0; c < 3; c++) {
            rec->glossy[c] = (float)(0.5 + rnd(r));
            for (k = 0; k < 3; k++) rec->glossy_gradient[c][k] = (float)((rnd(r) - 0.5) * 4.0 * rnd(r));
        }
    }
}

/* ---- section 4.2 written out: the brute-force reference --------------------------- */

typedef struct criteria {
    float cos_normal, cos_dir, inv_normal, inv_dir, front, dir_angle, max_change;
    uint32_t min_valid, max_neighbors;
    lightvec_interpolation interpolation;
} criteria;

static criteria criteria_of(const lightvec_cache *cache, float max_direction_angle)
{
    lightvec_cache_stats st;
    criteria c;
    lightvec_cache_info(cache, &st);
    c.max_change = st.max_irradiance_change;
    c.cos_normal = st.cos_normal;
    c.cos_dir = st.cos_direction;
    c.inv_normal = 1.0f / (1.0f - c.cos_normal);
    c.inv_dir = 1.0f / (1.0f - c.cos_dir);
    c.front = st.front_tolerance;
    c.dir_angle = (float)(max_direction_angle * (PI / 180.0));
    c.min_valid = st.min_valid;
    c.max_neighbors = st.max_neighbors;
    c.interpolation = st.interpolation;
    return c;
}

typedef struct query { float a[3], n[3], w[3], m[3]; int directional; } query;

/* The angle a record's glossy part is carried over: |w - sigma| plus the
   parallax |(A - B) off A's mirror direction| / d_g (the header's
   lightvec__glossy_angle, same float operations). */
static float glossy_angle(const query *q, const lightvec_record *b, float dx, float dy, float dz)
{
    float inv = 1.0f / b->glossy_distance;
    float vx = q->w[0] - b->outgoing[0], vy = q->w[1] - b->outgoing[1], vz = q->w[2] - b->outgoing[2];
    float along = dx * q->m[0] + dy * q->m[1] + dz * q->m[2];
    float px = dx - along * q->m[0], py = dy - along * q->m[1], pz = dz - along * q->m[2];
    return sqrtf(vx * vx + vy * vy + vz * vz) + sqrtf(px * px + py * py + pz * pz) * inv;
}

static float share_of(const lightvec_record *b) { return b->glossy_share > 0.0f ? b->glossy_share : 1.0f; }

/* |grad Y(G)| / Y(G) of a record times its glossy share, as the header
   computes it. */
static float rel_glossy_gradient(const lightvec_record *b)
{
    float gx = 0, gy = 0, gz = 0, y, gl;
    gx = gx + b->glossy_gradient[0][0] * 0.2126f; gy = gy + b->glossy_gradient[0][1] * 0.2126f; gz = gz + b->glossy_gradient[0][2] * 0.2126f;
    gx = gx + b->glossy_gradient[1][0] * 0.7152f; gy = gy + b->glossy_gradient[1][1] * 0.7152f; gz = gz + b->glossy_gradient[1][2] * 0.7152f;
    gx = gx + b->glossy_gradient[2][0] * 0.0722f; gy = gy + b->glossy_gradient[2][1] * 0.0722f; gz = gz + b->glossy_gradient[2][2] * 0.0722f;
    y = 0.2126f * b->glossy[0] + 0.7152f * b->glossy[1] + 0.0722f * b->glossy[2];
    gl = sqrtf(gx * gx + gy * gy + gz * gz);
    return y > 0.0f ? (gl / y * share_of(b) < FLT_MAX ? gl / y * share_of(b) : FLT_MAX) : (gl > 0.0f ? FLT_MAX : 0.0f);
}

/* S_dir of record b's glossy part: its lobe's angle over sqrt(share), never
   wider than the cache's bound. */
static float record_cos_dir(const criteria *c, const lightvec_record *b)
{
    double a;
    if (!(b->glossy_distance > 0.0f)) return c->cos_dir;
    a = lightvec_direction_angle(b->exponent) * (PI / 180.0) / sqrt((double)share_of(b));
    return a < (double)c->dir_angle ? (float)cos(a) : c->cos_dir;
}

/* Weights of record b (b->radius: its radius as the cache has it) at query
   q: w for the diffuse vector (0 when a criterion fails: not valid), wg for
   its glossy part (0 when that is not valid). Same float operations as the
   header, so both agree to the last bit. */
static int brute_weight(const criteria *c, const lightvec_record *b, const query *q, float *weight, float *wg)
{
    float R = b->radius;
    float dx = q->a[0] - b->position[0], dy = q->a[1] - b->position[1], dz = q->a[2] - b->position[2];
    float d2 = dx * dx + dy * dy + dz * dz, d, cn, change, ws = 1.0f, front, wb;
    float gx = 0, gy = 0, gz = 0, y, gl, rel;
    const float *n = q->n;
    *wg = 0.0f;
    if (q->directional ? (b->flags & LIGHTVEC_RECORD_VIEW_INDEPENDENT) != 0
                       : (b->flags & LIGHTVEC_RECORD_VIEW_INDEPENDENT) == 0)
        return 0; /* 3D records answer 3D queries only, 5D records 5D queries */
    if (!(d2 < R * R)) return 0;
    if (q->directional) {
        /* w_sigma = (cos(w, sigma) - S_dir) / (1 - S_dir) */
        float cs = q->w[0] * b->outgoing[0] + q->w[1] * b->outgoing[1] + q->w[2] * b->outgoing[2];
        if (!(cs > c->cos_dir)) return 0;
        ws = (cs - c->cos_dir) * c->inv_dir;
    }
    cn = n[0] * b->normal[0] + n[1] * b->normal[1] + n[2] * b->normal[2];
    if (!(cn > c->cos_normal)) return 0;
    /* Ward's in-front test: (A - B) . (n_A + n_B) / 2 >= -front R_B */
    front = 0.5f * (dx * (n[0] + b->normal[0]) + dy * (n[1] + b->normal[1]) + dz * (n[2] + b->normal[2]));
    if (!(front >= -c->front * R)) return 0;
    gx = gx + b->gradient[0][0] * 0.2126f; gy = gy + b->gradient[0][1] * 0.2126f; gz = gz + b->gradient[0][2] * 0.2126f;
    gx = gx + b->gradient[1][0] * 0.7152f; gy = gy + b->gradient[1][1] * 0.7152f; gz = gz + b->gradient[1][2] * 0.7152f;
    gx = gx + b->gradient[2][0] * 0.0722f; gy = gy + b->gradient[2][1] * 0.0722f; gz = gz + b->gradient[2][2] * 0.0722f;
    y = 0.2126f * b->irradiance[0] + 0.7152f * b->irradiance[1] + 0.0722f * b->irradiance[2];
    gl = sqrtf(gx * gx + gy * gy + gz * gz);
    rel = y > 0.0f ? (gl / y < FLT_MAX ? gl / y : FLT_MAX) : (gl > 0.0f ? FLT_MAX : 0.0f);
    d = sqrtf(d2);
    change = d * rel;
    if (!(change < c->max_change)) return 0;
    /* w_B = (1 - |AB|/R) / (1 + |AB| dE / E) (cos - S_curv) / (1 - S_curv) */
    wb = (1.0f - d / R) * (1.0f / (1.0f + change)) * ((cn - c->cos_normal) * c->inv_normal);
    if (q->directional && b->glossy_distance > 0.0f) {
        /* the glossy part: the record's own S_dir over psi, and the change of G along psi */
        float psi = glossy_angle(q, b, dx, dy, dz), cos_psi = 1.0f - 0.5f * psi * psi, s = record_cos_dir(c, b);
        float gchange = psi * rel_glossy_gradient(b);
        if (cos_psi > s && gchange < c->max_change) *wg = wb * ((cos_psi - s) / (1.0f - s)) * (1.0f / (1.0f + gchange));
    }
    *weight = wb * ws;
    return 1;
}

/* One record's term in the interpolated M (red channel), per 4.2.3 and the
   header's interpolation modes. */
static double interpolated_term(lightvec_interpolation mode, const lightvec_record *b, const float *a)
{
    double cos_nd = dot3(b->normal, b->vector.direction), m = b->vector.magnitude[0], f = 1.0;
    if (mode == LIGHTVEC_INTERPOLATION_PLAIN) return m;
    if (cos_nd < 0) cos_nd = 0;
    if (mode == LIGHTVEC_INTERPOLATION_GRADIENT && b->irradiance[0] > 0) {
        int k;
        for (k = 0; k < 3; k++) f += (double)b->gradient[0][k] / b->irradiance[0] * (a[k] - b->position[k]);
        if (f < 0) f = 0;
    }
    return m * cos_nd * f;
}

static void set_query(query *q, const float *a, const float *n, const float *w)
{
    int k;
    double c;
    memcpy(q->a, a, sizeof q->a);
    memcpy(q->n, n, sizeof q->n);
    q->directional = w != NULL;
    if (!w) return;
    memcpy(q->w, w, sizeof q->w);
    c = 2.0f * (n[0] * w[0] + n[1] * w[1] + n[2] * w[2]);
    for (k = 0; k < 3; k++) q->m[k] = (float)c * n[k] - w[k];
}

static void random_query(rng *r, const lightvec_record *recs, uint32_t count, query *q)
{
    const lightvec_record *b = &recs[(uint32_t)(rnd(r) * count) % count];
    float a[3], n[3], w[3];
    int k;
    for (k = 0; k < 3; k++) a[k] = b->position[k] + (float)((rnd(r) - 0.5) * 0.08);
    jitter(r, b->normal, 10.0, n);
    jitter(r, b->outgoing, 6.0, w);
    set_query(q, a, n, (b->flags & LIGHTVEC_RECORD_VIEW_INDEPENDENT) ? NULL : w);
}

#define MAX_FOUND 4096
static uint32_t g_ids[MAX_FOUND], g_bf_ids[MAX_FOUND], g_order[MAX_FOUND];
static float g_w[MAX_FOUND], g_bf_w[MAX_FOUND], g_bf_wg[MAX_FOUND];

static void sort_pairs(uint32_t *ids, float *w, uint32_t n)
{
    uint32_t i, j;
    for (i = 1; i < n; i++) { /* insertion sort by id: n is small */
        uint32_t id = ids[i];
        float x = w[i];
        for (j = i; j > 0 && ids[j - 1] > id; j--) { ids[j] = ids[j - 1]; w[j] = w[j - 1]; }
        ids[j] = id;
        w[j] = x;
    }
}

/* The brute force's interpolation of the records kept by the k-nearest
   cap (largest weights, ties to the smaller id): W, the red M, D and the
   glossy G with its mean exponent, written out independently in double. */
typedef struct expected { double wsum, m, d[3], g, gw, e; uint32_t used, glossy, glossy_valid; } expected;

static expected brute_interpolation(const criteria *c, const lightvec_record *stored, const query *q, uint32_t found)
{
    expected x;
    uint32_t i, j;
    memset(&x, 0, sizeof x);
    for (i = 0; i < found; i++) g_order[i] = i;
    for (i = 1; i < found; i++) /* by weight descending, then id ascending */
        for (j = i; j > 0; j--) {
            uint32_t a = g_order[j - 1], b = g_order[j], t;
            if (g_bf_w[a] > g_bf_w[b] || (g_bf_w[a] == g_bf_w[b] && g_bf_ids[a] < g_bf_ids[b])) break;
            t = g_order[j - 1]; g_order[j - 1] = g_order[j]; g_order[j] = t;
        }
    x.used = found < c->max_neighbors ? found : c->max_neighbors;
    for (i = 0; i < x.used; i++) {
        const lightvec_record *b = &stored[g_bf_ids[g_order[i]]];
        double w = g_bf_w[g_order[i]];
        x.wsum += w;
        x.m += w * interpolated_term(c->interpolation, b, q->a);
        for (j = 0; j < 3; j++) x.d[j] += w * b->vector.direction[j];
        x.glossy += q->directional && b->glossy_distance > 0.0f;
        if (g_bf_wg[g_order[i]] > 0.0f) {
            /* G_B extrapolated to w with the view gradient */
            double wg = g_bf_wg[g_order[i]], g = b->glossy[0];
            for (j = 0; j < 3; j++) g += (double)b->glossy_gradient[0][j] * (q->w[j] - b->outgoing[j]);
            x.g += wg * (g > 0 ? g : 0);
            x.gw += wg;
            x.e += wg * b->exponent;
            x.glossy_valid++;
        }
    }
    return x;
}

/* Compares lightvec_find and lightvec_lookup with the brute force for nq
   queries. Returns the mean number of valid records per query. */
static double compare_with_brute_force(const lightvec_cache *cache, const lightvec_record *stored, uint32_t count,
                                       uint32_t nq, uint64_t seed, float max_direction_angle, int *mismatches)
{
    criteria c = criteria_of(cache, max_direction_angle);
    rng r;
    uint32_t q, i, found, bf, total = 0, hits = 0, glossy_hits = 0;
    r.s = seed;
    for (q = 0; q < nq; q++) {
        query qu;
        lightvec_lookup_result lr;
        expected x;
        int same = 1;
        random_query(&r, stored, count, &qu);
        if (!CHECK(lightvec_find(cache, qu.a, qu.n, qu.directional ? qu.w : NULL, g_ids, g_w, MAX_FOUND, &found) ==
                   LIGHTVEC_OK))
            return 0;
        bf = 0;
        for (i = 0; i < count; i++) {
            float w, wg;
            if (brute_weight(&c, &stored[i], &qu, &w, &wg) && bf < MAX_FOUND) {
                g_bf_ids[bf] = i;
                g_bf_w[bf] = w;
                g_bf_wg[bf] = wg;
                bf++;
            }
        }
        total += bf;
        if (found != bf) same = 0;
        if (same) {
            sort_pairs(g_ids, g_w, found);
            for (i = 0; i < found; i++)
                if (g_ids[i] != g_bf_ids[i] || g_w[i] != g_bf_w[i]) same = 0;
        }
        if (!same) {
            (*mismatches)++;
            if (*mismatches < 4) {
                test_note("query %u: cache found %u records, brute force %u", q, found, bf);
                for (i = 0; i < found || i < bf; i++)
                    test_note("   %u %.9g | %u %.9g", i < found ? g_ids[i] : 0, i < found ? g_w[i] : 0.0f, i < bf ? g_bf_ids[i] : 0, i < bf ? g_bf_w[i] : 0.0f);
            }
        }
        x = brute_interpolation(&c, stored, &qu, bf);
        CHECK(lightvec_lookup(cache, qu.a, qu.n, qu.directional ? qu.w : NULL, &lr) == LIGHTVEC_OK);
        CHECK_EQ_INT(lr.valid_count, bf);
        CHECK_EQ_INT(lr.used_count, x.used);
        CHECK_EQ_INT(lr.hit, x.used >= c.min_valid && x.wsum > 0 && (!x.glossy || x.glossy_valid >= c.min_valid));
        if (x.used) CHECK_CLOSE(lr.weight, x.wsum / x.used, 1e-5, 0); /* W = mean weight (4.3) */
        if (lr.hit) {
            double dl = sqrt(x.d[0] * x.d[0] + x.d[1] * x.d[1] + x.d[2] * x.d[2]), m = x.m;
            double cos_a = dl > 0 ? (qu.n[0] * x.d[0] + qu.n[1] * x.d[1] + qu.n[2] * x.d[2]) / dl : 1.0;
            hits++;
            if (c.interpolation != LIGHTVEC_INTERPOLATION_PLAIN) m /= cos_a > 1e-3 ? cos_a : 1.0;
            /* normalised weighted sums; the order of summation differs */
            if (cos_a > 1e-2) CHECK_CLOSE(lr.vector.magnitude[0], m / x.wsum, 1e-4, 1e-6);
            if (dl > 1e-3 * x.wsum) {
                if (c.interpolation == LIGHTVEC_INTERPOLATION_PLAIN || cos_a > 2e-3)
                    CHECK_CLOSE(lr.vector.direction[2], x.d[2] / dl, 1e-4, 1e-4);
                else if (cos_a < 5e-4) /* light from behind A: the header falls back to n_A */
                    CHECK_CLOSE(lr.vector.direction[2], qu.n[2], 1e-6, 1e-6);
            }
            if (x.gw > 0 && qu.n[0] * qu.w[0] + qu.n[1] * qu.w[1] + qu.n[2] * qu.w[2] > 0.05f && x.g > 0) {
                /* the glossy light vector, lit by a white lobe of the records' mean exponent, gives back G */
                lightvec_material mat;
                float rgb[3];
                memset(&mat, 0, sizeof mat);
                mat.specular[0] = 1.0f;
                mat.exponent = (float)(x.e / x.gw);
                lightvec_radiance(&mat, qu.n, qu.w, &lr.vector, rgb);
                CHECK_CLOSE(rgb[0], x.g / x.gw, 1e-4, 1e-6);
                glossy_hits++;
            }
        }
    }
    test_note("%u queries: %.1f valid records per query, %u hits (%u with a glossy part)", nq, (double)total / nq,
              hits, glossy_hits);
    return (double)total / nq;
}

static lightvec_record *g_stored;

/* Records a cache clamps against each other (see test_neighbor_clamping). */
static int clamp_compatible(const lightvec_record *a, const lightvec_record *b, float cos_dir)
{
    int ai = (a->flags & LIGHTVEC_RECORD_VIEW_INDEPENDENT) != 0, bi = (b->flags & LIGHTVEC_RECORD_VIEW_INDEPENDENT) != 0;
    if (ai != bi) return 0;
    return ai || a->outgoing[0] * b->outgoing[0] + a->outgoing[1] * b->outgoing[1] + a->outgoing[2] * b->outgoing[2] > cos_dir;
}

static void fill_cache(lightvec_cache *cache, uint32_t count, uint64_t seed, double radius)
{
    rng r;
    uint32_t i, id;
    r.s = seed;
    for (i = 0; i < count; i++) {
        lightvec_record rec;
        random_record(&r, &rec, radius);
        if (!CHECK(lightvec_insert(cache, &rec, &id) == LIGHTVEC_OK)) return;
        CHECK_EQ_INT(id, i);
    }
    /* as stored: normalised, with the radii neighbour clamping left */
    for (i = 0; i < count; i++) lightvec_cache_record(cache, i, &g_stored[i]);
}

static void test_brute_force_100k(void)
{
    const uint32_t n = 100000;
    lightvec_cache *cache = NULL, *loaded = NULL;
    lightvec_cache_stats st;
    void *data = NULL;
    size_t size = 0;
    int mismatches = 0;
    double per_query;
    lightvec_cache_desc d;
    memset(&d, 0, sizeof d);
    d.face_split_threshold = 1024; /* splits during the insertions (default 8192) */
    g_stored = (lightvec_record *)malloc(n * sizeof *g_stored);
    if (!CHECK(g_stored != NULL) || !CHECK(lightvec_cache_create(&d, &cache) == LIGHTVEC_OK)) return;
    fill_cache(cache, n, 11, 1.0); /* radius_scale 0.3: validity radii 0.15 .. 0.45 before clamping */
    lightvec_cache_info(cache, &st);
    test_note("100k records: %u faces (%u leaves, depth %u), %u kd-trees, %.1f MB", st.face_count, st.leaf_count,
              st.max_depth, st.tree_count, st.bytes / 1048576.0);
    CHECK(st.face_count > 20);    /* the 20 roots split past 1024 records */
    per_query = compare_with_brute_force(cache, g_stored, n, 400, 99, 15.0f, &mismatches);
    CHECK(per_query > 3.0);       /* the comparison is not vacuous */
    CHECK_EQ_INT(mismatches, 0);
    /* one kd-tree per leaf */
    CHECK(lightvec_cache_optimize(cache) == LIGHTVEC_OK);
    lightvec_cache_info(cache, &st);
    CHECK_EQ_INT(st.tree_count, st.leaf_count + 1); /* + the view-independent leaf */
    compare_with_brute_force(cache, g_stored, n, 100, 7, 15.0f, &mismatches);
    CHECK_EQ_INT(mismatches, 0);
    /* save, load through a thread pool, same answers */
    if (CHECK(lightvec_save_to_memory(cache, NULL, &data, &size) == LIGHTVEC_OK)) {
        lightvec_cache_desc d;
        ex_pool *pool = ex_pool_create(2);
        memset(&d, 0, sizeof d);
        d.parallel_for = ex_pool_parallel_for;
        d.parallel_user = pool;
        CHECK(size == 20u + 56u + (size_t)n * 208u + 4u);
        if (CHECK(lightvec_load_from_memory(data, size, &d, &loaded) == LIGHTVEC_OK)) {
            lightvec_record a, b;
            CHECK(lightvec_cache_record(loaded, 12345, &a) == LIGHTVEC_OK);
            CHECK(lightvec_cache_record(cache, 12345, &b) == LIGHTVEC_OK);
            CHECK(memcmp(&a, &b, sizeof a) == 0);
            compare_with_brute_force(loaded, g_stored, n, 100, 5, 15.0f, &mismatches);
            CHECK_EQ_INT(mismatches, 0);
            lightvec_cache_destroy(loaded);
        }
        ex_pool_destroy(pool);
        lightvec_free_memory(NULL, data);
    }
    lightvec_cache_destroy(cache);
    free(g_stored);
}

/* ---- the recursive icosahedron ------------------------------------------------------ */

static double det3(const float *a, const float *b, const float *c)
{
    return (double)a[0] * ((double)b[1] * c[2] - (double)b[2] * c[1]) -
           (double)a[1] * ((double)b[0] * c[2] - (double)b[2] * c[0]) +
           (double)a[2] * ((double)b[0] * c[1] - (double)b[1] * c[0]);
}

/* Smallest signed distance of d to the three great circles of a
   counter-clockwise spherical triangle: >= 0 inside. */
static double inside_margin(const lightvec_face_info *f, const float *d)
{
    double m = 1e9;
    int i;
    for (i = 0; i < 3; i++) {
        const float *a = f->vertices[i], *b = f->vertices[(i + 1) % 3];
        double cx = (double)a[1] * b[2] - (double)a[2] * b[1], cy = (double)a[2] * b[0] - (double)a[0] * b[2];
        double cz = (double)a[0] * b[1] - (double)a[1] * b[0], l = sqrt(cx * cx + cy * cy + cz * cz);
        double s = (cx * d[0] + cy * d[1] + cz * d[2]) / l;
        if (s < m) m = s;
    }
    return m;
}

/* Solid angle of a spherical triangle (Van Oosterom and Strackee 1983). */
static double solid_angle(const lightvec_face_info *f)
{
    const float *a = f->vertices[0], *b = f->vertices[1], *c = f->vertices[2];
    double num = det3(a, b, c);
    double ab = (double)a[0] * b[0] + (double)a[1] * b[1] + (double)a[2] * b[2];
    double bc = (double)b[0] * c[0] + (double)b[1] * c[1] + (double)b[2] * c[2];
    double ca = (double)c[0] * a[0] + (double)c[1] * a[1] + (double)c[2] * a[2];
    return 2.0 * atan2(fabs(num), 1.0 + ab + bc + ca);
}

static void test_icosahedron(void)
{
    lightvec_cache_desc d;
    lightvec_cache *cache = NULL;
    lightvec_cache_stats st;
    lightvec_face_info fi;
    rng r;
    uint32_t i, j, threshold = 16, n = 20000, leaves = 0, bad_split = 0, bad_locate = 0, ambiguous = 0;
    uint64_t leaf_records = 0;
    double area_sum = 0, amin[8], amax[8];
    lightvec_face_info *all;
    memset(&d, 0, sizeof d);
    d.face_split_threshold = threshold;
    d.max_direction_angle = 0.5f; /* faces may split until max_face_depth */
    d.max_face_depth = 5;
    if (!CHECK(lightvec_cache_create(&d, &cache) == LIGHTVEC_OK)) return;
    lightvec_cache_info(cache, &st);
    CHECK_EQ_INT(st.face_count, 20);
    r.s = 3;
    for (i = 0; i < n; i++) {
        lightvec_record rec;
        random_record(&r, &rec, 0.05);
        rec.flags = 0;
        if (i % 2) jitter(&r, axes[4], 3.0, rec.outgoing); /* a dense spot near +z reaches max depth */
        CHECK(lightvec_insert(cache, &rec, NULL) == LIGHTVEC_OK);
    }
    lightvec_cache_info(cache, &st);
    test_note("icosahedron: %u faces, %u leaves, max depth %u", st.face_count, st.leaf_count, st.max_depth);
    CHECK_EQ_INT(st.max_depth, 5);
    all = (lightvec_face_info *)malloc(st.face_count * sizeof *all);
    if (!CHECK(all != NULL)) return;
    for (i = 0; i < 8; i++) { amin[i] = 1e9; amax[i] = 0; }
    for (i = 0; i < st.face_count; i++) {
        double a;
        if (!CHECK(lightvec_cache_face(cache, i, &all[i]) == LIGHTVEC_OK)) break;
        CHECK(det3(all[i].vertices[0], all[i].vertices[1], all[i].vertices[2]) > 0); /* counter-clockwise */
        a = solid_angle(&all[i]);
        if (a < amin[all[i].depth]) amin[all[i].depth] = a;
        if (a > amax[all[i].depth]) amax[all[i].depth] = a;
        if (all[i].leaf) {
            leaves++;
            leaf_records += all[i].record_count;
            area_sum += a;
            /* a leaf holds at most the threshold unless it may not split */
            if (all[i].record_count > threshold && all[i].depth < 5) bad_split++;
        } else if (all[i].record_count <= threshold) {
            bad_split++; /* split without passing the threshold */
        }
    }
    CHECK(lightvec_cache_face(cache, st.face_count, &fi) == LIGHTVEC_ERROR_INVALID_ARGUMENT);
    CHECK_EQ_INT(leaves, st.leaf_count);
    CHECK_EQ_INT(leaf_records, n);
    CHECK_EQ_INT(bad_split, 0);
    CHECK_CLOSE(area_sum, 4 * PI, 1e-5, 0); /* the leaves tile the sphere */
    for (i = 0; i <= 5; i++) {
        test_note("depth %u: solid angles %.5f .. %.5f sr (ratio %.3f)", i, amin[i], amax[i], amax[i] / amin[i]);
        CHECK(amax[i] / amin[i] <= 2.0); /* subdivision keeps faces within 2x */
    }
    /* point location against a brute-force scan of all leaves */
    for (i = 0; i < 20000; i++) {
        float dir[3];
        uint32_t loc, containing = 0, last = 0;
        if (i % 4) random_unit(&r, dir);
        else jitter(&r, axes[4], 4.0, dir); /* many near the deep spot */
        if (!CHECK(lightvec_cache_locate(cache, dir, &loc) == LIGHTVEC_OK)) break;
        if (!all[loc].leaf || inside_margin(&all[loc], dir) < -1e-6) bad_locate++;
        for (j = 0; j < st.face_count; j++)
            if (all[j].leaf && inside_margin(&all[j], dir) >= -1e-6) { containing++; last = j; }
        if (containing == 1 && last != loc) bad_locate++;
        ambiguous += containing > 1; /* on an edge, within 1e-6 */
    }
    test_note("point location: %u of 20000 directions within 1e-6 of an edge", ambiguous);
    CHECK_EQ_INT(bad_locate, 0);
    free(all);
    lightvec_cache_destroy(cache);
}

/* A face splits exactly when it holds more than the threshold. */
static void test_split_threshold(void)
{
    lightvec_cache_desc d;
    lightvec_cache *cache = NULL;
    lightvec_cache_stats st;
    lightvec_record rec;
    lightvec_face_info fi;
    float centre[3], l;
    rng r;
    int i;
    memset(&d, 0, sizeof d);
    d.face_split_threshold = 10;
    d.max_direction_angle = 1.0f;
    if (!CHECK(lightvec_cache_create(&d, &cache) == LIGHTVEC_OK)) return;
    lightvec_cache_face(cache, 0, &fi); /* aim at the centre of root face 0 */
    for (i = 0; i < 3; i++) centre[i] = fi.vertices[0][i] + fi.vertices[1][i] + fi.vertices[2][i];
    l = sqrtf(centre[0] * centre[0] + centre[1] * centre[1] + centre[2] * centre[2]);
    for (i = 0; i < 3; i++) centre[i] /= l;
    r.s = 5;
    for (i = 0; i < 11; i++) {
        random_record(&r, &rec, 0.1);
        rec.flags = 0;
        jitter(&r, centre, 2.0, rec.outgoing);
        CHECK(lightvec_insert(cache, &rec, NULL) == LIGHTVEC_OK);
        lightvec_cache_info(cache, &st);
        if (i < 10) CHECK_EQ_INT(st.face_count, 20);
    }
    /* the 11th record splits the face, and the child holding the tight
       bundle again, recursively, until no leaf holds more than 10 */
    CHECK(st.face_count > 20 && (st.face_count - 20) % 4 == 0);
    for (i = 0; i < (int)st.face_count; i++) {
        lightvec_cache_face(cache, (uint32_t)i, &fi);
        if (fi.leaf) CHECK(fi.record_count <= 10);
    }
    lightvec_cache_destroy(cache);
}

/* ---- interpolation, W, view independence --------------------------------------------- */

/* The same two records under PROJECTED and GRADIENT: b's vector lies in the
   tangent plane (cos(n_b, D_b) = 0), so only a contributes M cos; b's
   gradient moves a's term. */
static void interpolation_modes(lightvec_record *a, lightvec_record *b, const float *p, const float *n,
                                const float *w, double wa, double wb)
{
    lightvec_cache_desc d;
    lightvec_cache *cache = NULL;
    lightvec_lookup_result lr;
    double cos_d = wa / sqrt(wa * wa + wb * wb); /* cos(n_A, normalize(wa z + wb x)) */
    memset(&d, 0, sizeof d);
    d.min_valid = 2;
    d.radius_scale = 1.0f;
    d.interpolation = LIGHTVEC_INTERPOLATION_PROJECTED;
    if (!CHECK(lightvec_cache_create(&d, &cache) == LIGHTVEC_OK)) return;
    CHECK(lightvec_insert(cache, a, NULL) == LIGHTVEC_OK && lightvec_insert(cache, b, NULL) == LIGHTVEC_OK);
    CHECK(lightvec_lookup(cache, p, n, w, &lr) == LIGHTVEC_OK);
    CHECK_CLOSE(lr.vector.magnitude[0], wa * 1.0 / (wa + wb) / cos_d, 1e-6, 0);
    lightvec_cache_destroy(cache);
    /* GRADIENT: a's red irradiance grows by 50% per unit x; A is 0.1 from a */
    a->gradient[0][0] = 0.5f;
    d.interpolation = LIGHTVEC_INTERPOLATION_GRADIENT;
    if (!CHECK(lightvec_cache_create(&d, &cache) == LIGHTVEC_OK)) return;
    CHECK(lightvec_insert(cache, a, NULL) == LIGHTVEC_OK && lightvec_insert(cache, b, NULL) == LIGHTVEC_OK);
    CHECK(lightvec_lookup(cache, p, n, w, &lr) == LIGHTVEC_OK);
    /* the irradiance-change criterion shrinks a's weight: |AB| |grad Y| / Y */
    {
        double change = 0.1 * 0.5 * 0.2126 / 1.0, wa2 = 0.9 / (1 + change);
        cos_d = wa2 / sqrt(wa2 * wa2 + wb * wb);
        CHECK_CLOSE(lr.vector.magnitude[0], wa2 * 1.05 / (wa2 + wb) / cos_d, 1e-5, 0);
        CHECK_CLOSE(lr.vector.magnitude[1], wa2 * 1.0 / (wa2 + wb) / cos_d, 1e-5, 0);
    }
    a->gradient[0][0] = 0.0f;
    lightvec_cache_destroy(cache);
}

static void test_interpolation(void)
{
    lightvec_cache *cache = NULL;
    lightvec_cache_desc d;
    lightvec_record a, b;
    lightvec_lookup_result lr;
    float p[3] = { 0.1f, 0, 0 }, n[3] = { 0, 0, 1 }, w[3] = { 0, 0, 1 };
    double wa, wb;
    memset(&d, 0, sizeof d);
    d.min_valid = 2;
    d.radius_scale = 1.0f; /* the paper's |AB| < d_avg */
    d.interpolation = LIGHTVEC_INTERPOLATION_PLAIN;
    if (!CHECK(lightvec_cache_create(&d, &cache) == LIGHTVEC_OK)) return;
    memset(&a, 0, sizeof a);
    a.normal[2] = 1; a.outgoing[2] = 1; a.vector.direction[2] = 1;
    a.vector.magnitude[0] = 1; a.vector.magnitude[1] = 1; a.distance = 1; a.visibility = 1;
    a.irradiance[0] = a.irradiance[1] = a.irradiance[2] = 1;
    b = a;
    b.position[0] = 0.4f;
    b.vector.direction[0] = 1; b.vector.direction[2] = 0;
    b.vector.magnitude[0] = 3;
    CHECK(lightvec_insert(cache, &a, NULL) == LIGHTVEC_OK);
    CHECK(lightvec_lookup(cache, p, n, w, &lr) == LIGHTVEC_OK);
    CHECK_EQ_INT(lr.valid_count, 1);
    CHECK(!lr.hit); /* fewer than min_valid */
    CHECK_CLOSE(lr.weight, 0.9, 1e-6, 0); /* 1 - |AB| / d_avg, all else 1 */
    CHECK(lightvec_insert(cache, &b, NULL) == LIGHTVEC_OK);
    CHECK(lightvec_lookup(cache, p, n, w, &lr) == LIGHTVEC_OK);
    wa = 0.9; wb = 0.7;
    CHECK(lr.hit);
    CHECK_CLOSE(lr.weight, (wa + wb) / 2, 1e-6, 0);
    CHECK_CLOSE(lr.vector.magnitude[0], (wa * 1 + wb * 3) / (wa + wb), 1e-6, 0);
    CHECK_CLOSE(lr.vector.direction[0], wb / sqrt(wa * wa + wb * wb), 1e-6, 0);
    interpolation_modes(&a, &b, p, n, w, wa, wb);
    /* a viewer 10 degrees away: w_sigma = (cos 10 - cos 15) / (1 - cos 15) */
    w[0] = (float)sin(PI / 18); w[2] = (float)cos(PI / 18);
    CHECK(lightvec_lookup(cache, p, n, w, &lr) == LIGHTVEC_OK);
    CHECK_CLOSE(lr.weight, (wa + wb) / 2 * (cos(PI / 18) - cos(PI / 12)) / (1 - cos(PI / 12)), 1e-5, 0);
    /* 20 degrees: outside S_dir */
    w[0] = (float)sin(PI / 9); w[2] = (float)cos(PI / 9);
    CHECK(lightvec_lookup(cache, p, n, w, &lr) == LIGHTVEC_OK);
    CHECK_EQ_INT(lr.valid_count, 0);
    CHECK(lr.weight == 0.0f);
    CHECK(lightvec_priority(1.0f, lr.weight) == LIGHTVEC_PRIORITY_MAX);
    /* view-independent lookups see only view-independent records */
    CHECK(lightvec_lookup(cache, p, n, NULL, &lr) == LIGHTVEC_OK);
    CHECK_EQ_INT(lr.valid_count, 0);
    a.flags = LIGHTVEC_RECORD_VIEW_INDEPENDENT;
    a.outgoing[0] = 0; a.outgoing[1] = 0; a.outgoing[2] = 0; /* ignored for 3D records */
    CHECK(lightvec_insert(cache, &a, NULL) == LIGHTVEC_OK);
    CHECK(lightvec_lookup(cache, p, n, NULL, &lr) == LIGHTVEC_OK);
    CHECK_EQ_INT(lr.valid_count, 1);
    CHECK_CLOSE(lr.weight, 0.9, 1e-6, 0);
    lightvec_cache_destroy(cache);
}

/* ---- neighbour clamping, the k-nearest cap, Ward's in-front test ------------------------ */

/* The radii neighbour clamping leaves, written out: in insertion order,
   R_i = min(R_i, R_j + |B_i - B_j|) over the earlier compatible records j
   (view independent with view independent, 5D with 5D when their sigmas are
   within the cache's max_direction_angle), then R_j = min(R_j, R_i + |B_i -
   B_j|) for each of them. Same float operations as the header. */
static void brute_clamp(const lightvec_record *recs, uint32_t n, float scale, float cos_dir, float *radius)
{
    uint32_t i, j;
    for (i = 0; i < n; i++) {
        radius[i] = scale * recs[i].distance;
        for (j = 0; j < i; j++) {
            float dx = recs[i].position[0] - recs[j].position[0], dy = recs[i].position[1] - recs[j].position[1];
            float dz = recs[i].position[2] - recs[j].position[2], d = sqrtf(dx * dx + dy * dy + dz * dz);
            if (!clamp_compatible(&recs[i], &recs[j], cos_dir)) continue;
            if (radius[j] + d < radius[i]) radius[i] = radius[j] + d;
        }
        for (j = 0; j < i; j++) {
            float dx = recs[i].position[0] - recs[j].position[0], dy = recs[i].position[1] - recs[j].position[1];
            float dz = recs[i].position[2] - recs[j].position[2], d = sqrtf(dx * dx + dy * dy + dz * dz);
            if (!clamp_compatible(&recs[i], &recs[j], cos_dir)) continue;
            if (radius[i] + d < radius[j]) radius[j] = radius[i] + d;
        }
    }
}

static void test_neighbor_clamping(void)
{
    const uint32_t n = 3000;
    lightvec_record *recs = (lightvec_record *)malloc(n * sizeof *recs);
    float *expect = (float *)malloc(n * sizeof(float));
    lightvec_cache_desc d;
    lightvec_cache *cache = NULL;
    lightvec_cache_stats st;
    uint32_t i, clamped = 0, wrong = 0;
    rng r;
    if (!CHECK(recs && expect)) return;
    r.s = 21;
    for (i = 0; i < n; i++) {
        random_record(&r, &recs[i], 0.3);
        /* d_avg over two orders of magnitude: most records get clamped */
        recs[i].distance *= (float)(0.05 + 3.0 * rnd(&r) * rnd(&r));
    }
    memset(&d, 0, sizeof d);
    d.face_split_threshold = 256; /* splits and merges during the insertions */
    if (!CHECK(lightvec_cache_create(&d, &cache) == LIGHTVEC_OK)) return;
    lightvec_cache_info(cache, &st);
    for (i = 0; i < n; i++) CHECK(lightvec_insert(cache, &recs[i], NULL) == LIGHTVEC_OK);
    for (i = 0; i < n; i++) lightvec_cache_record(cache, i, &recs[i]); /* normalised as the cache compares them */
    brute_clamp(recs, n, st.radius_scale, st.cos_direction, expect);
    for (i = 0; i < n; i++) {
        clamped += expect[i] < st.radius_scale * recs[i].distance;
        wrong += recs[i].radius != expect[i];
    }
    test_note("neighbour clamping: %u of %u radii clamped, %u differ from the brute force", clamped, n, wrong);
    CHECK(clamped > n / 10);
    CHECK_EQ_INT(wrong, 0);
    /* the same radii after a save and a load, and after optimize */
    {
        void *data = NULL;
        size_t size = 0;
        lightvec_cache *loaded = NULL;
        lightvec_record a;
        CHECK(lightvec_cache_optimize(cache) == LIGHTVEC_OK);
        if (CHECK(lightvec_save_to_memory(cache, NULL, &data, &size) == LIGHTVEC_OK) &&
            CHECK(lightvec_load_from_memory(data, size, NULL, &loaded) == LIGHTVEC_OK)) {
            for (i = 0, wrong = 0; i < n; i++) {
                lightvec_cache_record(loaded, i, &a);
                wrong += a.radius != expect[i];
            }
            CHECK_EQ_INT(wrong, 0);
            lightvec_cache_destroy(loaded);
        }
        lightvec_free_memory(NULL, data);
    }
    lightvec_cache_destroy(cache);
    /* LIGHTVEC_CACHE_NO_NEIGHBOR_CLAMP keeps radius_scale * d_avg */
    d.flags = LIGHTVEC_CACHE_NO_NEIGHBOR_CLAMP;
    if (CHECK(lightvec_cache_create(&d, &cache) == LIGHTVEC_OK)) {
        lightvec_record a;
        for (i = 0; i < 500; i++) CHECK(lightvec_insert(cache, &recs[i], NULL) == LIGHTVEC_OK);
        for (i = 0, wrong = 0; i < 500; i++) {
            lightvec_cache_record(cache, i, &a);
            wrong += a.radius != st.radius_scale * recs[i].distance;
        }
        CHECK_EQ_INT(wrong, 0);
        lightvec_cache_destroy(cache);
    }
    free(recs);
    free(expect);
}

/* A lookup interpolates the max_neighbors valid records of largest weight;
   the brute force keeps the same ones. A cap of 3 binds on most queries of
   a sparse cache; a cap of 24 with wide direction cones (90 degrees) makes
   a lookup gather more than 24 + 48 candidates, where it selects by
   quickselect (up to 64 it counts). */
static void test_neighbor_cap(void)
{
    static const uint32_t caps[2] = { 3, 24 };
    static const double least[2] = { 6.0, 60.0 };
    static const uint32_t queries[2] = { 300, 100 };
    static const float angle[2] = { 15.0f, 90.0f };
    const uint32_t n = 40000;
    int k;
    g_stored = (lightvec_record *)malloc(n * sizeof *g_stored);
    if (!CHECK(g_stored != NULL)) return;
    for (k = 0; k < 2; k++) {
        lightvec_cache_desc d;
        lightvec_cache *cache = NULL;
        int mismatches = 0;
        double per_query;
        memset(&d, 0, sizeof d);
        d.max_neighbors = caps[k];
        d.min_valid = 2;
        d.max_direction_angle = angle[k];
        /* The cap is the subject here: with radii this large, clamping each
           insertion against its neighbours was 60 % of the case's time under
           ASan (test_brute_force_100k compares the clamped radii). */
        d.flags = LIGHTVEC_CACHE_NO_NEIGHBOR_CLAMP;
        if (!CHECK(lightvec_cache_create(&d, &cache) == LIGHTVEC_OK)) break;
        fill_cache(cache, n, 31, 2.0);
        per_query = compare_with_brute_force(cache, g_stored, n, queries[k], 17, angle[k], &mismatches);
        CHECK(per_query > least[k]); /* the cap binds on most queries */
        CHECK_EQ_INT(mismatches, 0);
        lightvec_cache_destroy(cache);
    }
    free(g_stored);
}

/* Ward's "in front" test: a record 2 cm above A's plane (a step, same
   normal) is skipped, 4 mm above is kept (tolerance 0.05 R_B = 5 mm), and
   one below A (A in front of it) is kept. */
static void test_in_front(void)
{
    lightvec_cache *cache = NULL;
    lightvec_record b;
    lightvec_lookup_result lr;
    float a[3] = { 0, 0, 0 }, n[3] = { 0, 0, 1 };
    float heights[3] = { 0.02f, 0.004f, -0.02f };
    int expect[3] = { 0, 1, 1 }, i;
    for (i = 0; i < 3; i++) {
        if (!CHECK(lightvec_cache_create(NULL, &cache) == LIGHTVEC_OK)) return;
        memset(&b, 0, sizeof b);
        b.position[0] = 0.01f;
        b.position[2] = heights[i];
        b.normal[2] = 1.0f;
        b.vector.direction[2] = 1.0f;
        b.vector.magnitude[0] = b.irradiance[0] = 1.0f;
        b.distance = 0.1f / 0.3f; /* R_B = 0.1 */
        b.visibility = 1.0f;
        b.flags = LIGHTVEC_RECORD_VIEW_INDEPENDENT;
        CHECK(lightvec_insert(cache, &b, NULL) == LIGHTVEC_OK);
        CHECK(lightvec_lookup(cache, a, n, NULL, &lr) == LIGHTVEC_OK);
        CHECK_EQ_INT(lr.valid_count, expect[i]);
        lightvec_cache_destroy(cache);
    }
}

/* The glossy part carried to a new view by its view gradient: two records
   at A for views 2 degrees apart (the lobe tolerates 11.6 degrees), G linear
   in the view: the lookup between them gives the line's value, whatever
   the weights. */
static void test_glossy_extrapolation(void)
{
    lightvec_cache_desc d;
    lightvec_cache *cache = NULL;
    lightvec_record b;
    lightvec_lookup_result lr;
    lightvec_material m;
    float a[3] = { 0, 0, 0 }, n[3] = { 0, 0, 1 }, w[3], rgb[3];
    double g0 = 0.5, slope = 2.0; /* G = g0 + slope * (w_x - 0.5) */
    int i, k;
    memset(&d, 0, sizeof d);
    d.min_valid = 2;
    if (!CHECK(lightvec_cache_create(&d, &cache) == LIGHTVEC_OK)) return;
    for (i = 0; i < 2; i++) {
        double t = (30.0 + (i ? 2.0 : 0.0)) * PI / 180.0;
        memset(&b, 0, sizeof b);
        b.position[1] = i ? 0.01f : -0.01f;
        b.normal[2] = 1.0f;
        b.outgoing[0] = (float)sin(t);
        b.outgoing[2] = (float)cos(t);
        b.vector.direction[2] = 1.0f;
        b.irradiance[0] = b.irradiance[1] = b.irradiance[2] = 1.0f;
        for (k = 0; k < 3; k++) {
            b.glossy[k] = (float)(g0 + slope * (b.outgoing[0] - 0.5));
            /* d/dw of slope * w_x, taken off sigma */
            b.glossy_gradient[k][0] = (float)(slope * (1.0 - b.outgoing[0] * b.outgoing[0]));
            b.glossy_gradient[k][2] = (float)(slope * (-b.outgoing[0] * b.outgoing[2]));
        }
        b.distance = 1.0f;
        b.glossy_distance = 1e6f; /* no parallax to speak of */
        b.exponent = 20.0f;
        b.visibility = 1.0f;
        CHECK(lightvec_insert(cache, &b, NULL) == LIGHTVEC_OK);
    }
    w[0] = (float)sin(31.0 * PI / 180.0); w[1] = 0; w[2] = (float)cos(31.0 * PI / 180.0);
    if (CHECK(lightvec_lookup(cache, a, n, w, &lr) == LIGHTVEC_OK) && CHECK(lr.hit)) {
        memset(&m, 0, sizeof m);
        m.specular[0] = m.specular[1] = m.specular[2] = 1.0f;
        m.exponent = 20.0f;
        lightvec_radiance(&m, n, w, &lr.vector, rgb);
        /* first order in the chord w - sigma, whose part along sigma is
           cos(1 degree) - 1: slope sigma_x (1 - cos 1 degree) = 1.5e-4 off;
           twice that */
        CHECK_CLOSE(rgb[0], g0 + slope * (w[0] - 0.5), 0, 3e-4);
    }
    lightvec_cache_destroy(cache);
}

/* ---- save / load: hostile input ---------------------------------------------------------- */

typedef struct fail_writer { size_t left; } fail_writer;
static int write_until(void *user, const void *bytes, size_t n)
{
    fail_writer *f = (fail_writer *)user;
    (void)bytes;
    if (n > f->left) return -1;
    f->left -= n;
    return 0;
}

static void test_load_hostile(void)
{
    lightvec_cache *cache = NULL, *loaded = NULL;
    lightvec_cache_desc d;
    unsigned char *data = NULL, *copy;
    size_t size = 0, i;
    rng r;
    uint32_t k, corrupt_ok = 0, trials = 0;
    memset(&d, 0, sizeof d);
    d.kind = LIGHTVEC_KIND_DIRECT;
    d.min_valid = 3;
    if (!CHECK(lightvec_cache_create(&d, &cache) == LIGHTVEC_OK)) return;
    r.s = 77;
    for (k = 0; k < 30; k++) {
        lightvec_record rec;
        random_record(&r, &rec, 0.2);
        rec.visibility = (float)(k % 3) * 0.5f;
        CHECK(lightvec_insert(cache, &rec, NULL) == LIGHTVEC_OK);
    }
    if (!CHECK(lightvec_save_to_memory(cache, NULL, (void **)&data, &size) == LIGHTVEC_OK)) return;
    /* round trip keeps settings and records */
    if (CHECK(lightvec_load_from_memory(data, size, NULL, &loaded) == LIGHTVEC_OK)) {
        lightvec_cache_stats a, b;
        lightvec_record ra, rb;
        lightvec_cache_info(cache, &a);
        lightvec_cache_info(loaded, &b);
        CHECK_EQ_INT(b.kind, LIGHTVEC_KIND_DIRECT);
        CHECK_EQ_INT(b.min_valid, 3);
        CHECK_EQ_INT(b.record_count, 30);
        CHECK(a.cos_normal == b.cos_normal && a.radius_scale == b.radius_scale);
        for (k = 0; k < 30; k++) {
            lightvec_cache_record(cache, k, &ra);
            lightvec_cache_record(loaded, k, &rb);
            CHECK(memcmp(&ra, &rb, sizeof ra) == 0);
        }
        lightvec_cache_destroy(loaded);
    }
    /* every truncation */
    for (i = 0; i < size; i++) {
        lightvec_result res = lightvec_load_from_memory(data, i, NULL, &loaded);
        if (res != LIGHTVEC_ERROR_CORRUPT_DATA) {
            CHECK_MSG(0, "truncated to %zu bytes: %s", i, lightvec_result_string(res));
            break;
        }
        CHECK(loaded == NULL);
    }
    {   /* a byte after the CRC is left alone: the same object loads */
        unsigned char *longer = test_with_byte_after(data, size);
        void *again = NULL;
        size_t again_size = 0;
        if (CHECK(longer != NULL) && CHECK_EQ_INT(lightvec_load_from_memory(longer, size + 1, NULL, &loaded), LIGHTVEC_OK) &&
            CHECK_EQ_INT(lightvec_save_to_memory(loaded, NULL, &again, &again_size), LIGHTVEC_OK))
            CHECK(again_size == size && memcmp(again, data, size) == 0);
        lightvec_free_memory(NULL, again);
        lightvec_cache_destroy(loaded);
        free(longer);
    }
    /* every byte flipped, then random multi-byte damage */
    copy = (unsigned char *)malloc(size);
    if (!CHECK(copy != NULL)) return;
    for (i = 0; i < size + 3000; i++) {
        lightvec_result res;
        memcpy(copy, data, size);
        if (i < size) copy[i] ^= 0x5A;
        else
            for (k = 0; k < 1 + (uint32_t)(rnd(&r) * 6); k++) copy[(size_t)(rnd(&r) * size) % size] ^= (unsigned char)(1 + rnd(&r) * 255);
        res = lightvec_load_from_memory(copy, size, NULL, &loaded);
        trials++;
        if (res == LIGHTVEC_OK) { /* only if the damage cancelled out */
            corrupt_ok += memcmp(copy, data, size) != 0;
            lightvec_cache_destroy(loaded);
        } else {
            CHECK(res == LIGHTVEC_ERROR_CORRUPT_DATA || (res == LIGHTVEC_ERROR_VERSION && i >= 8));
        }
    }
    CHECK_EQ_INT(corrupt_ok, 0);
    /* a future version, and the previous one (records without glossy parts) */
    memcpy(copy, data, size);
    copy[8] = LIGHTVEC_FILE_FORMAT_VERSION + 1;
    CHECK(lightvec_load_from_memory(copy, size, NULL, &loaded) == LIGHTVEC_ERROR_VERSION);
    copy[8] = 1;
    CHECK(lightvec_load_from_memory(copy, size, NULL, &loaded) == LIGHTVEC_ERROR_VERSION);
    /* a write callback that fails at every point */
    for (i = 0; i < size; i += 37) {
        fail_writer fw;
        fw.left = i;
        CHECK(lightvec_save(cache, write_until, &fw) == LIGHTVEC_ERROR_IO);
    }
    CHECK(lightvec_load(NULL, NULL, NULL, &loaded) == LIGHTVEC_ERROR_INVALID_ARGUMENT);
    free(copy);
    lightvec_free_memory(NULL, data);
    lightvec_cache_destroy(cache);
}

/* ---- allocation failures at every allocation ------------------------------------------------ */

typedef struct counting { long allocs, frees, fail_at; } counting;
static void *count_alloc(size_t size, void *user)
{
    counting *c = (counting *)user;
    if (c->fail_at >= 0 && c->allocs >= c->fail_at) return NULL;
    c->allocs++;
    return malloc(size);
}
static void count_free(void *p, void *user)
{
    ((counting *)user)->frees++;
    free(p);
}

/* create, 600 inserts (merges, splits), optimize, save, load: returns the
   first failure, or OK */
static lightvec_result scenario(counting *cnt)
{
    lightvec_cache_desc d;
    lightvec_cache *cache = NULL, *loaded = NULL;
    lightvec_result res;
    rng r;
    uint32_t i;
    void *data = NULL;
    size_t size;
    memset(&d, 0, sizeof d);
    d.allocator.alloc = count_alloc;
    d.allocator.free = count_free;
    d.allocator.user = cnt;
    d.face_split_threshold = 64;
    d.max_direction_angle = 5.0f;
    res = lightvec_cache_create(&d, &cache);
    if (res != LIGHTVEC_OK) return res;
    r.s = 9;
    for (i = 0; i < 600 && res == LIGHTVEC_OK; i++) {
        lightvec_record rec;
        random_record(&r, &rec, 0.2);
        res = lightvec_insert(cache, &rec, NULL);
    }
    if (res == LIGHTVEC_OK) res = lightvec_cache_optimize(cache);
    if (res == LIGHTVEC_OK) res = lightvec_save_to_memory(cache, &d.allocator, &data, &size);
    if (res == LIGHTVEC_OK) {
        res = lightvec_load_from_memory(data, size, &d, &loaded);
        lightvec_free_memory(&d.allocator, data);
    }
    if (res == LIGHTVEC_OK) {
        lightvec_lookup_result lr;
        float p[3] = { 0.5f, 0.5f, 0.5f }, n[3] = { 0, 0, 1 };
        res = lightvec_lookup(loaded, p, n, n, &lr);
    }
    lightvec_cache_destroy(loaded);
    lightvec_cache_destroy(cache);
    return res;
}

static void test_allocation_failures(void)
{
    counting cnt;
    long total, k, failures = 0;
    memset(&cnt, 0, sizeof cnt);
    cnt.fail_at = -1;
    CHECK(scenario(&cnt) == LIGHTVEC_OK);
    CHECK_EQ_INT(cnt.allocs, cnt.frees);
    total = cnt.allocs;
    test_note("allocation failures: %ld allocations in the scenario, each made to fail once", total);
    for (k = 0; k < total; k++) {
        lightvec_result res;
        memset(&cnt, 0, sizeof cnt);
        cnt.fail_at = k;
        res = scenario(&cnt);
        if (res != LIGHTVEC_OK && res != LIGHTVEC_ERROR_OUT_OF_MEMORY) CHECK_MSG(0, "fail at %ld: %s", k, lightvec_result_string(res));
        failures += res != LIGHTVEC_OK;
        if (cnt.allocs != cnt.frees) { CHECK_MSG(0, "fail at %ld: %ld allocs, %ld frees", k, cnt.allocs, cnt.frees); break; }
    }
    CHECK(failures > total / 2); /* most failures surface; a full list of memory awaiting readers is absorbed */
}

/* ---- progress and cancel ------------------------------------------------------------------ */

static int cancel_now(void *user, uint64_t done, uint64_t total)
{
    (void)done; (void)total;
    ++*(int *)user;
    return 1;
}

static void test_optimize_cancel(void)
{
    lightvec_cache_desc d;
    lightvec_cache *cache = NULL;
    lightvec_lookup_result lr;
    float p[3] = { 0.5f, 0.5f, 0.5f }, n[3] = { 0, 0, 1 };
    rng r;
    int calls = 0;
    uint32_t i;
    memset(&d, 0, sizeof d);
    d.face_split_threshold = 40;
    d.max_direction_angle = 2.0f;
    d.progress = cancel_now;
    d.progress_user = &calls;
    if (!CHECK(lightvec_cache_create(&d, &cache) == LIGHTVEC_OK)) return;
    r.s = 4;
    for (i = 0; i < 20000; i++) {
        lightvec_record rec;
        random_record(&r, &rec, 0.1);
        CHECK(lightvec_insert(cache, &rec, NULL) == LIGHTVEC_OK);
    }
    CHECK(lightvec_cache_optimize(cache) == LIGHTVEC_ERROR_CANCELLED);
    CHECK_EQ_INT(calls, 1);
    CHECK(lightvec_lookup(cache, p, n, n, &lr) == LIGHTVEC_OK); /* still a valid cache */
    lightvec_cache_destroy(cache);
}

int main(int argc, char **argv)
{
    TEST_INIT(argc, argv);
    RUN(test_brute_force_100k);
    RUN(test_icosahedron);
    RUN(test_split_threshold);
    RUN(test_interpolation);
    RUN(test_neighbor_clamping);
    RUN(test_neighbor_cap);
    RUN(test_in_front);
    RUN(test_glossy_extrapolation);
    RUN(test_load_hostile);
    RUN(test_allocation_failures);
    RUN(test_optimize_cancel);
    return test_finish();
}
