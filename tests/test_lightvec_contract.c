/* Contract tests of lightvec.h: what each public function validates, sizes
   whose arithmetic would wrap in 32 bits, and allocation failures during
   face splits and optimize reported as errors (nothing half done). */
#define LIGHTVEC_IMPLEMENTATION
#include "lightvec.h"
#include "tests/test.h"

/* ---- an allocator that counts, remembers the largest request, and fails on demand ---- */

typedef struct tally {
    long allocs, frees, fail_at;   /* fail_at: index of the allocation to refuse, -1 none */
    size_t largest;
} tally;

static void *tally_alloc(size_t size, void *user)
{
    tally *t = (tally *)user;
    if (size > t->largest) t->largest = size;
    if (t->fail_at >= 0 && t->allocs == t->fail_at) {
        t->fail_at = -1;
        return NULL;
    }
    t->allocs++;
    return malloc(size);
}

static void tally_free(void *p, void *user)
{
    ((tally *)user)->frees++;
    free(p);
}

static lightvec_allocator tally_allocator(tally *t)
{
    lightvec_allocator a;
    memset(t, 0, sizeof *t);
    t->fail_at = -1;
    a.alloc = tally_alloc;
    a.free = tally_free;
    a.user = t;
    return a;
}

/* ---- issue 17, defect 2: 3 * triangle_count in 32 bits ----------------------------------- */

/* triangle_count = 0x55555556 made 3 * count wrap to 2 in the index check, so
   only two indices were checked and the scene asked the allocator for 51.5 GB
   before reading indices far past the caller's buffer. The third index here is
   out of range: a check that reaches it answers INVALID_ARGUMENT at once, and
   nothing is allocated. The caller's buffer holds two triangles; only the
   first three indices may be read. */
static void test_triangle_count_wraps_32_bits(void)
{
    static const float pos[9] = { 0, 0, 0, 1, 0, 0, 0, 1, 0 };
    static const uint32_t idx[6] = { 0, 1, 99, 0, 1, 2 };
    static const uint32_t counts[3] = { 0x55555556u, 0x55555555u, 0xFFFFFFFFu };
    lightvec_material mat;
    lightvec_scene_desc d;
    lightvec_scene *scene = NULL;
    tally t;
    int i;
    memset(&mat, 0, sizeof mat);
    memset(&d, 0, sizeof d);
    d.positions = pos;
    d.vertex_count = 3;
    d.indices = idx;
    d.materials = &mat;
    d.material_count = 1;
    d.allocator = tally_allocator(&t);
    for (i = 0; i < 3; i++) {
        d.triangle_count = counts[i];
        CHECK(lightvec_scene_create(&d, &scene) == LIGHTVEC_ERROR_INVALID_ARGUMENT);
        CHECK(scene == NULL);
        CHECK_EQ_INT(t.allocs, 0);
        CHECK_MSG(t.largest == 0, "count 0x%x: the allocator was asked for %zu bytes", counts[i], t.largest);
    }
    /* the two triangles themselves are fine once the bad index is gone */
    {
        uint32_t good[6] = { 0, 1, 2, 0, 2, 1 };
        d.indices = good;
        d.triangle_count = 2;
        if (CHECK(lightvec_scene_create(&d, &scene) == LIGHTVEC_OK)) lightvec_scene_destroy(scene);
        CHECK_EQ_INT(t.allocs, t.frees);
    }
}

/* ---- issue 17, defect 9: a face split or an optimize without memory -------------------------- */

typedef struct lcg { uint64_t s; } lcg;
static float lcg_float(lcg *r)
{
    r->s = r->s * 6364136223846793005ull + 1442695040888963407ull;
    return (float)(r->s >> 40) * (1.0f / 16777216.0f);
}

/* Records in the unit cube viewed from a few directions: faces split often
   with threshold 24. */
static void split_record(lcg *r, lightvec_record *rec)
{
    int k;
    memset(rec, 0, sizeof *rec);
    for (k = 0; k < 3; k++) rec->position[k] = lcg_float(r);
    rec->normal[2] = 1.0f;
    rec->outgoing[0] = 0.3f * lcg_float(r);
    rec->outgoing[1] = 0.3f * lcg_float(r) - 0.15f;
    rec->outgoing[2] = 1.0f;
    rec->vector.direction[2] = 1.0f;
    for (k = 0; k < 3; k++) rec->vector.magnitude[k] = rec->irradiance[k] = 1.0f;
    rec->distance = 0.3f;
    rec->visibility = 1.0f;
}

typedef struct shape { uint64_t faces, leaves, trees, records; } shape;

static int same_shape(const shape *a, const shape *b)
{
    return a->faces == b->faces && a->leaves == b->leaves && a->trees == b->trees && a->records == b->records;
}

static shape shape_of(const lightvec_cache *c)
{
    lightvec_cache_stats st;
    shape s;
    lightvec_cache_info(c, &st);
    s.faces = st.face_count;
    s.leaves = st.leaf_count;
    s.trees = st.tree_count;
    s.records = st.record_count;
    return s;
}

#define SPLIT_RECORDS 400

/* Inserts SPLIT_RECORDS records then optimizes, with allocation fail_at
   (counted after create) refused. A call that refuses is repeated once
   (the refusal is one-shot). Every call that answers OK leaves the cache
   shaped exactly as the run without failures at the same step (a refused
   allocation it absorbed, such as the list of memory awaiting readers, must
   not change the result); every call that answers OUT_OF_MEMORY leaves it as
   before the call. Returns the number of calls that answered an error. */
static int split_scenario(long fail_at, shape *reference, int *mismatches)
{
    lightvec_cache_desc d;
    lightvec_cache *c = NULL;
    tally t;
    lcg r;
    int errors = 0, i;
    memset(&d, 0, sizeof d);
    d.allocator = tally_allocator(&t);
    d.face_split_threshold = 24;
    d.max_direction_angle = 1.0f;
    if (!CHECK(lightvec_cache_create(&d, &c) == LIGHTVEC_OK)) return 0;
    if (fail_at >= 0) t.fail_at = t.allocs + fail_at;
    r.s = 3;
    for (i = 0; i <= SPLIT_RECORDS; i++) {
        shape before = shape_of(c), after;
        lightvec_record rec;
        lightvec_result res;
        if (i < SPLIT_RECORDS) {
            split_record(&r, &rec);
            res = lightvec_insert(c, &rec, NULL);
        } else {
            res = lightvec_cache_optimize(c);
        }
        after = shape_of(c);
        if (res == LIGHTVEC_ERROR_OUT_OF_MEMORY) {
            errors++;
            if (i < SPLIT_RECORDS && !same_shape(&before, &after)) (*mismatches)++;
            res = i < SPLIT_RECORDS ? lightvec_insert(c, &rec, NULL) : lightvec_cache_optimize(c);
            after = shape_of(c);
        }
        if (!CHECK_MSG(res == LIGHTVEC_OK, "fail at %ld, step %d: %s", fail_at, i, lightvec_result_string(res))) break;
        if (fail_at < 0) reference[i] = after;
        else if (!same_shape(&reference[i], &after)) {
            if (*mismatches < 3)
                test_note("fail at %ld, step %d: %llu faces, %llu trees (without failures %llu, %llu)", fail_at, i,
                          (unsigned long long)after.faces, (unsigned long long)after.trees,
                          (unsigned long long)reference[i].faces, (unsigned long long)reference[i].trees);
            (*mismatches)++;
        }
    }
    lightvec_cache_destroy(c);
    CHECK_EQ_INT(t.allocs, t.frees);
    return errors;
}

static void test_split_and_optimize_out_of_memory(void)
{
    static shape reference[SPLIT_RECORDS + 1];
    tally t;
    long k, total;
    int errors = 0, mismatches = 0;
    lightvec_cache_desc d;
    lightvec_cache *c = NULL;
    split_scenario(-1, reference, &mismatches);
    CHECK(reference[SPLIT_RECORDS - 1].faces > 40); /* splits happened */
    /* the number of allocations after create */
    memset(&d, 0, sizeof d);
    d.allocator = tally_allocator(&t);
    d.face_split_threshold = 24;
    d.max_direction_angle = 1.0f;
    {
        lcg r;
        int i;
        long base;
        lightvec_cache_create(&d, &c);
        base = t.allocs;
        r.s = 3;
        for (i = 0; i < SPLIT_RECORDS; i++) {
            lightvec_record rec;
            split_record(&r, &rec);
            lightvec_insert(c, &rec, NULL);
        }
        lightvec_cache_optimize(c);
        total = t.allocs - base;
        lightvec_cache_destroy(c);
    }
    for (k = 0; k < total; k++) errors += split_scenario(k, reference, &mismatches);
    test_note("%ld allocations refused one at a time: %d calls answered out of memory", total, errors);
    CHECK_EQ_INT(mismatches, 0);
    CHECK(errors > total / 2); /* most refusals surface; the rest are absorbed without a change */
}

/* ---- issue 15: every OK result finite ------------------------------------------------------ */

/* A bright source 40 degrees off the normal toward +x and a dim sky. */
static void source_and_sky(void *user, const float org[3], const float dir[3], float radiance[3], float *distance)
{
    double c = dir[0] * 0.6427876 + dir[2] * 0.7660444;
    float l = c > 0.995 ? 50.0f : 1e-3f;
    (void)user;
    (void)org;
    radiance[0] = radiance[1] = radiance[2] = l;
    *distance = 1.0f;
}

/* A purely glossy surface (exponents 20 .. 260) seen from 4,000 directions:
   where the lobe misses the source by the right angle, f_r(D -> w_r) is a
   float denormal, and eq. 3 computed with a float denominator overflowed:
   v0.2 returned OK with M = inf for 43 of these views (the inf of issue 15,
   one floor pixel in 1,513). Every magnitude, and the radiance they give
   back, must be finite. */
static void test_magnitudes_finite(void)
{
    int i, bad = 0, gathered = 0;
    for (i = 0; i < 4000; i++) {
        lightvec_gather_desc gd;
        lightvec_surface sf;
        lightvec_record rec;
        float rgb[3];
        double a = -1.5 + 3.0 * i / 4000.0, b = 0.9 * ((i * 37) % 100) / 100.0 - 0.45;
        int k;
        memset(&gd, 0, sizeof gd);
        gd.incoming_radiance = source_and_sky;
        gd.strata_theta = 8;
        memset(&sf, 0, sizeof sf);
        sf.normal[2] = 1.0f;
        sf.outgoing[0] = (float)(sin(a) * cos(b));
        sf.outgoing[1] = (float)sin(b);
        sf.outgoing[2] = (float)(cos(a) * cos(b));
        if (!(sf.outgoing[2] > 0.01f)) continue;
        sf.material.specular[0] = sf.material.specular[1] = sf.material.specular[2] = 0.7f;
        sf.material.exponent = (float)(20 + (i % 7) * 40);
        if (!CHECK(lightvec_gather(NULL, &gd, &sf, (uint64_t)i, &rec) == LIGHTVEC_OK)) break;
        gathered++;
        lightvec_radiance(&sf.material, sf.normal, sf.outgoing, &rec.vector, rgb);
        for (k = 0; k < 3; k++)
            bad += !isfinite(rec.vector.magnitude[k]) || !isfinite(rec.vector.glossy_magnitude[k]) || !isfinite(rgb[k]) ||
                   !isfinite(rec.glossy[k]);
    }
    CHECK(gathered > 3000);
    CHECK_EQ_INT(bad, 0);
}

/* ---- what each function checks (the FUNCTION REFERENCE) ------------------------------------ */

static lightvec_record good_record(void)
{
    lightvec_record r;
    memset(&r, 0, sizeof r);
    r.normal[2] = 1.0f;
    r.outgoing[2] = 1.0f;
    r.vector.direction[2] = 1.0f;
    r.vector.magnitude[0] = r.irradiance[0] = 1.0f;
    r.glossy[0] = 0.5f;
    r.glossy_distance = 1.0f;
    r.exponent = 20.0f;
    r.distance = 1.0f;
    r.visibility = 1.0f;
    return r;
}

static void test_contract_cache_settings(void)
{
    lightvec_cache_desc d;
    lightvec_cache *c = NULL;
    memset(&d, 0, sizeof d);
    d.max_neighbors = 257;
    CHECK(lightvec_cache_create(&d, &c) == LIGHTVEC_ERROR_INVALID_ARGUMENT && c == NULL);
    d.max_neighbors = 256;
    CHECK(lightvec_cache_create(&d, &c) == LIGHTVEC_OK);
    lightvec_cache_destroy(c);
    d.max_neighbors = 0;
    d.front_tolerance = -1.0f;
    CHECK(lightvec_cache_create(&d, &c) == LIGHTVEC_ERROR_INVALID_ARGUMENT);
    d.front_tolerance = NAN;
    CHECK(lightvec_cache_create(&d, &c) == LIGHTVEC_ERROR_INVALID_ARGUMENT);
    d.front_tolerance = 0.0f;
    d.flags = 0x8u;
    CHECK(lightvec_cache_create(&d, &c) == LIGHTVEC_ERROR_INVALID_ARGUMENT);
    d.flags = 0;
    d.max_direction_angle = 0.05f;
    CHECK(lightvec_cache_create(&d, &c) == LIGHTVEC_ERROR_INVALID_ARGUMENT);
    CHECK(c == NULL);
}

/* Every bad field of a record is refused, and a refused insert leaves the
   cache as it was; the radius a caller sets is ignored. */
static void test_contract_insert(void)
{
    lightvec_cache *c = NULL;
    const lightvec_cache *cc;
    lightvec_record r, got;
    lightvec_cache_stats st;
    lightvec_lookup_result lr;
    float p[3] = { 0, 0, 0 }, n[3] = { 0, 0, 1 };
    int i;
    if (!CHECK(lightvec_cache_create(NULL, &c) == LIGHTVEC_OK)) return;
    for (i = 0; i < 14; i++) {
        r = good_record();
        switch (i) {
        case 0: r.glossy_share = 1.5f; break;
        case 1: r.glossy_share = -0.1f; break;
        case 2: r.exponent = -1.0f; break;
        case 3: r.exponent = 2e6f; break;
        case 4: r.glossy_distance = -1.0f; break;
        case 5: r.glossy_distance = INFINITY; break;
        case 6: r.vector.glossy_direction[1] = NAN; break;
        case 7: r.vector.glossy_magnitude[2] = -1.0f; break;
        case 8: r.glossy[1] = -0.5f; break;
        case 9: r.glossy_gradient[2][0] = INFINITY; break;
        case 10: r.vector.magnitude[0] = INFINITY; break;
        case 11: r.distance = 0.0f; break;
        case 12: r.outgoing[2] = 0.0f; break;
        default: r.flags = 0x4u; break;
        }
        CHECK_MSG(lightvec_insert(c, &r, NULL) == LIGHTVEC_ERROR_INVALID_ARGUMENT, "bad record %d accepted", i);
    }
    lightvec_cache_info(c, &st);
    CHECK_EQ_INT(st.record_count, 0);
    r = good_record();
    r.radius = NAN; /* set by the cache */
    CHECK(lightvec_insert(c, &r, NULL) == LIGHTVEC_OK);
    cc = c; /* the readers take a const cache */
    CHECK(lightvec_cache_record(cc, 0, &got) == LIGHTVEC_OK);
    CHECK(got.radius == st.radius_scale * r.distance);
    CHECK(lightvec_lookup(cc, p, n, n, &lr) == LIGHTVEC_OK);
    CHECK_EQ_INT(lr.valid_count, 1);
    CHECK(lightvec_cache_record(cc, 1, &got) == LIGHTVEC_ERROR_INVALID_ARGUMENT);
    lightvec_cache_destroy(c);
}

static void test_contract_gather_and_angles(void)
{
    lightvec_gather_desc gd;
    lightvec_surface sf;
    lightvec_record rec;
    memset(&gd, 0, sizeof gd);
    gd.incoming_radiance = source_and_sky;
    gd.strata_theta = 4;
    memset(&sf, 0, sizeof sf);
    sf.normal[2] = sf.outgoing[2] = 1.0f;
    sf.material.specular[0] = 0.5f;
    sf.material.exponent = 10.0f;
    gd.glossy_samples = 65537;
    CHECK(lightvec_gather(NULL, &gd, &sf, 0, &rec) == LIGHTVEC_ERROR_INVALID_ARGUMENT);
    gd.glossy_samples = 64;
    CHECK(lightvec_gather(NULL, &gd, &sf, 0, &rec) == LIGHTVEC_OK);
    CHECK(rec.glossy_distance == 1.0f && rec.exponent == 10.0f && rec.glossy_share == 1.0f);
    /* the derivation's numbers: 0.909 acos(exp(-1 / 2n)) */
    CHECK_CLOSE(lightvec_direction_angle(20.0f), 0.90915 * acos(exp(-1.0 / 40.0)) * 180.0 / 3.14159265358979, 1e-5, 0);
    CHECK_CLOSE(lightvec_direction_angle(20.0f), 11.6, 0.01, 0);
    CHECK(lightvec_direction_angle(0.0f) == 180.0f && lightvec_direction_angle(NAN) == 180.0f);
    CHECK(lightvec_direction_angle(1e6f) >= 0.1f);
    CHECK(lightvec_direction_angle(100.0f) < lightvec_direction_angle(20.0f)); /* narrower lobe, tighter bound */
}

int main(int argc, char **argv)
{
    TEST_INIT(argc, argv);
    RUN(test_triangle_count_wraps_32_bits);
    RUN(test_split_and_optimize_out_of_memory);
    RUN(test_magnitudes_finite);
    RUN(test_contract_cache_settings);
    RUN(test_contract_insert);
    RUN(test_contract_gather_and_angles);
    return test_finish();
}
