/* Contract tests of irrvol.h: what the doc block's VALIDATION AND CONTRACT
   says of each public function, checked as a caller sees it: refused
   arguments give the named code before anything is allocated and leave
   every output as it was; the queries never fail and answer out-of-range
   arguments as documented; the size-writing functions never write past a
   capacity. */
#define IRRVOL_IMPLEMENTATION
#include "irrvol.h"
#include "tests/test.h"
#include "tests/test_irrvol_scenes.h"

/* ---- an allocator that counts and remembers the largest request ---------------------------- */

typedef struct tally {
    long allocs, frees;
    size_t largest;
} tally;

static void *tally_alloc(size_t size, void *user)
{
    tally *t = (tally *)user;
    if (size > t->largest) t->largest = size;
    t->allocs++;
    return malloc(size);
}

static void tally_free(void *p, void *user)
{
    ((tally *)user)->frees++;
    free(p);
}

static irrvol_allocator tally_allocator(tally *t)
{
    irrvol_allocator a;
    memset(t, 0, sizeof *t);
    a.alloc = tally_alloc;
    a.free = tally_free;
    a.user = t;
    return a;
}

/* The closed cube room with one emitting face, a 3^3 grid and k = 3: a
   volume built in milliseconds. */
static irrvol_material cube_materials[6];

static void cube_desc(irrvol_desc *d, sc_scene *s)
{
    sc_cube(s);
    memset(cube_materials, 0, sizeof cube_materials);
    cube_materials[5].radiance[0] = cube_materials[5].radiance[1] = cube_materials[5].radiance[2] = 1.0f;
    sc_scene_desc(d, s, cube_materials, 6);
    d->grid_samples[0] = d->grid_samples[1] = d->grid_samples[2] = 3;
    d->resolution = 3;
}

static irrvol *cube_volume(sc_scene *s)
{
    irrvol_desc d;
    irrvol *v = NULL;
    cube_desc(&d, s);
    if (!CHECK(irrvol_build(&d, &v) == IRRVOL_OK)) return NULL;
    return v;
}

/* ---- irrvol_build ----------------------------------------------------------------------------- */

/* Every refused desc: INVALID_ARGUMENT, *out NULL, and the allocator never
   called (the checks run before the first allocation). triangle_count =
   0x55555556 made 3 * count wrap to 2 in 32 bits: the check must reach the
   bad third index of a buffer that holds one triangle. The one check that
   needs the grid, a scene flat along an axis (zero-size bounds), runs once
   the volume's header exists: it frees what it allocated. */
static void test_build_checks_before_allocating(void)
{
    static const uint32_t counts[3] = { 0x55555556u, 0x55555555u, 0xFFFFFFFFu };
    static const uint32_t bad_third[3] = { 0, 1, 99 };
    sc_scene s;
    irrvol_desc good, d;
    irrvol *v;
    tally t;
    float env[3] = { 1.0f, 1.0f, 1.0f };
    uint32_t mats[2 * SC_MAX_QUADS];
    int c;
    cube_desc(&good, &s);
    good.allocator = tally_allocator(&t);
    memcpy(mats, s.mat, s.nt * sizeof *mats);
    mats[s.nt - 1] = 6;   /* one past the materials */
    for (c = 0; c < 17; c++) {
        d = good;
        switch (c) {
        case 0: d.indices = bad_third; d.triangle_count = counts[0]; break;
        case 1: d.indices = bad_third; d.triangle_count = counts[1]; break;
        case 2: d.indices = bad_third; d.triangle_count = counts[2]; break;
        case 3: d.position_stride = 11; break;
        case 4: d.vertex_radiance = s.pos; d.vertex_radiance_stride = 8; break;
        case 5: d.environment = env; d.environment_width = 0; d.environment_height = 1; break;
        case 6: d.environment = env; d.environment_width = IRRVOL_MAX_ENVIRONMENT_SIZE + 1; d.environment_height = 1; break;
        case 7: d.allocator.alloc = NULL; break;
        case 8: d.supersamples = IRRVOL_MAX_SUPERSAMPLES + 1; break;
        case 9: d.materials = NULL; break;
        case 10: d.triangle_materials = mats; break;
        case 11: d.background[1] = NAN; break;
        case 12: d.ray_offset = INFINITY; break;
        case 13: d.visibility_resolution = IRRVOL_MAX_VISIBILITY_RESOLUTION + 1; break;
        case 14: d.bounds_min[0] = 1.0f; d.bounds_max[0] = 1.0f; d.bounds_max[1] = d.bounds_max[2] = 1.0f; break;
        case 15: d.grid_samples[0] = 1; break;
        default: d.triangle_count = 1; break;   /* one triangle: flat bounds */
        }
        v = (irrvol *)&d;   /* anything: a refused build sets it to NULL */
        t.allocs = t.frees = 0;
        t.largest = 0;
        CHECK_MSG(irrvol_build(&d, &v) == IRRVOL_ERROR_INVALID_ARGUMENT, "case %d accepted", c);
        CHECK_MSG(v == NULL, "case %d left *out set", c);
        CHECK_MSG(t.frees == t.allocs, "case %d: %ld allocations, %ld frees", c, t.allocs, t.frees);
        CHECK_MSG(t.allocs == 0 || c == 16, "case %d: %ld allocations (largest %zu bytes) before the check", c,
                  t.allocs, t.largest);
    }
    t.allocs = t.frees = 0;
    v = (irrvol *)&d;
    CHECK(irrvol_build(NULL, &v) == IRRVOL_ERROR_INVALID_ARGUMENT && v == NULL);
    CHECK(irrvol_build(&good, NULL) == IRRVOL_ERROR_INVALID_ARGUMENT);
    CHECK_EQ_INT(t.allocs, 0);
    /* the good desc builds, and everything it allocated is freed by destroy */
    if (CHECK(irrvol_build(&good, &v) == IRRVOL_OK)) {
        CHECK(t.allocs > 0);
        irrvol_destroy(v);
        CHECK_EQ_INT(t.frees, t.allocs);
    }
    irrvol_destroy(NULL);   /* accepted */
}

/* ---- the readers: info, sample, sample_values --------------------------------------------------- */

/* A refused call returns INVALID_ARGUMENT and leaves its outputs byte for
   byte as they were. */
static void test_readers_change_nothing_when_refused(void)
{
    sc_scene s;
    irrvol *v = cube_volume(&s);
    irrvol_volume_info info;
    irrvol_sample_info si, before;
    float values[2 * 3 * 3 * 3 + 1], keep[2 * 3 * 3 * 3 + 1];
    if (!v) return;
    CHECK(irrvol_info(NULL, &info) == IRRVOL_ERROR_INVALID_ARGUMENT);
    CHECK(irrvol_info(v, NULL) == IRRVOL_ERROR_INVALID_ARGUMENT);
    CHECK(irrvol_info(v, &info) == IRRVOL_OK);
    CHECK_EQ_INT(info.bins, 18);
    memset(&si, 0xAB, sizeof si);
    before = si;
    CHECK(irrvol_sample(v, info.sample_count, &si) == IRRVOL_ERROR_INVALID_ARGUMENT);
    CHECK(irrvol_sample(NULL, 0, &si) == IRRVOL_ERROR_INVALID_ARGUMENT);
    CHECK(irrvol_sample(v, 0, NULL) == IRRVOL_ERROR_INVALID_ARGUMENT);
    CHECK(memcmp(&si, &before, sizeof si) == 0);
    memset(values, 0xAB, sizeof values);
    memcpy(keep, values, sizeof keep);
    CHECK(irrvol_sample_values(v, info.sample_count, values, NULL) == IRRVOL_ERROR_INVALID_ARGUMENT);
    CHECK(irrvol_sample_values(v, 0, NULL, values) == IRRVOL_ERROR_INVALID_ARGUMENT);   /* radiance not kept */
    CHECK(irrvol_sample_values(NULL, 0, values, NULL) == IRRVOL_ERROR_INVALID_ARGUMENT);
    CHECK(memcmp(values, keep, sizeof values) == 0);
    /* accepted: bins x 3 floats written, the float after them untouched */
    CHECK(irrvol_sample_values(v, 0, values, NULL) == IRRVOL_OK);
    CHECK(memcmp(values + 3 * info.bins, keep + 3 * info.bins, sizeof(float)) == 0);
    CHECK(irrvol_sample_values(v, 0, NULL, NULL) == IRRVOL_OK);   /* neither wanted: nothing to do */
    irrvol_destroy(v);
}

/* ---- the queries ------------------------------------------------------------------------------ */

static int same3(const float *a, const float *b) { return memcmp(a, b, 3 * sizeof(float)) == 0; }
static int finite3(const float *a) { return isfinite(a[0]) && isfinite(a[1]) && isfinite(a[2]); }

/* Queries check nothing and never fail: non-finite positions clamp to the
   boundary, NaN and zero directions give a bin in range, unknown filters
   act as NEAREST and unknown weightings as TRILINEAR, order 0 or 1 reads
   L1 and any other L2, and the batch equals the single queries. */
static void test_queries_answer_everything(void)
{
    sc_scene s;
    irrvol *v = cube_volume(&s);
    irrvol_volume_info info;
    const float inside[3] = { 0.3f, -0.2f, 0.1f }, dir[3] = { 0.2f, 0.5f, -0.8f };
    float a[3], b[3], p[3], big[3], d[3];
    const irrvol_filter unknown_filter = (irrvol_filter)99;
    const irrvol_weighting unknown_weighting = (irrvol_weighting)99;
    if (!v) return;
    irrvol_info(v, &info);
    /* positions: +inf and a finite point past the bounds find the same cell and weights; NaN clamps to
       the low side. The leak-safe weights test the point itself (finite), or stand plain (not finite) */
    p[0] = INFINITY; p[1] = inside[1]; p[2] = inside[2];
    big[0] = 1e30f; big[1] = inside[1]; big[2] = inside[2];
    irrvol_query_filter(v, IRRVOL_FILTER_BILINEAR, IRRVOL_WEIGHTING_TRILINEAR, p, dir, a);
    irrvol_query_filter(v, IRRVOL_FILTER_BILINEAR, IRRVOL_WEIGHTING_TRILINEAR, big, dir, b);
    CHECK(finite3(a) && same3(a, b));
    irrvol_query(v, p, dir, b);
    CHECK(same3(a, b));
    irrvol_query(v, big, dir, a);
    CHECK(finite3(a));
    p[0] = NAN;
    big[0] = -1e30f;
    irrvol_query_filter(v, IRRVOL_FILTER_NEAREST, IRRVOL_WEIGHTING_TRILINEAR, p, dir, a);
    irrvol_query_filter(v, IRRVOL_FILTER_NEAREST, IRRVOL_WEIGHTING_TRILINEAR, big, dir, b);
    CHECK(finite3(a) && same3(a, b));
    /* directions: zero, NaN and infinite look up some bin: a finite answer */
    d[0] = d[1] = d[2] = 0.0f;
    irrvol_query(v, inside, d, a);
    CHECK(finite3(a));
    d[1] = NAN;
    irrvol_query(v, inside, d, a);
    CHECK(finite3(a));
    CHECK(irrvol_direction_bin(v, d) < info.bins);
    d[1] = INFINITY;
    irrvol_query_glossy(v, inside, d, dir, a);
    CHECK(finite3(a));
    irrvol_query_sh(v, 2, IRRVOL_WEIGHTING_DEFAULT, inside, d, a);
    CHECK(finite3(a));
    /* unknown enumerators */
    irrvol_query_filter(v, unknown_filter, IRRVOL_WEIGHTING_VISIBILITY, inside, dir, a);
    irrvol_query_filter(v, IRRVOL_FILTER_NEAREST, IRRVOL_WEIGHTING_VISIBILITY, inside, dir, b);
    CHECK(same3(a, b));
    irrvol_query_filter(v, IRRVOL_FILTER_BILINEAR, unknown_weighting, inside, dir, a);
    irrvol_query_filter(v, IRRVOL_FILTER_BILINEAR, IRRVOL_WEIGHTING_TRILINEAR, inside, dir, b);
    CHECK(same3(a, b));
    /* the defaults are the volume's: BILINEAR and VISIBILITY */
    irrvol_query(v, inside, dir, a);
    irrvol_query_filter(v, IRRVOL_FILTER_BILINEAR, IRRVOL_WEIGHTING_VISIBILITY, inside, dir, b);
    CHECK(same3(a, b));
    /* harmonic orders */
    irrvol_query_sh(v, 0, IRRVOL_WEIGHTING_TRILINEAR, inside, dir, a);
    irrvol_query_sh(v, 1, IRRVOL_WEIGHTING_TRILINEAR, inside, dir, b);
    CHECK(same3(a, b));
    irrvol_query_sh(v, 7, IRRVOL_WEIGHTING_TRILINEAR, inside, dir, a);
    irrvol_query_sh(v, 2, IRRVOL_WEIGHTING_TRILINEAR, inside, dir, b);
    CHECK(same3(a, b));
    {   /* the batch at strides (positions and directions interleaved, 7 floats apart) equals single queries */
        float in[7 * 5], out[3 * 5], one[3];
        uint32_t i, seed = 99u;
        int k;
        for (i = 0; i < 5; i++)
            for (k = 0; k < 7; k++) in[7 * i + (uint32_t)k] = 2.4f * sc_frand(&seed) - 1.2f;   /* some outside */
        in[7 * 4 + 1] = NAN;
        irrvol_query_many(v, IRRVOL_FILTER_DEFAULT, IRRVOL_WEIGHTING_DEFAULT, 5, in, 7 * sizeof(float), in + 3,
                          7 * sizeof(float), out);
        for (i = 0; i < 5; i++) {
            irrvol_query(v, in + 7 * i, in + 7 * i + 3, one);
            CHECK_MSG(same3(one, out + 3 * i), "batch query %u differs", i);
        }
        irrvol_query_many(v, IRRVOL_FILTER_DEFAULT, IRRVOL_WEIGHTING_DEFAULT, 0, NULL, 0, NULL, 0, NULL);
    }
    /* bins past the last, and no volume at all, give +z */
    irrvol_bin_direction(v, info.bins, a);
    CHECK(a[0] == 0.0f && a[1] == 0.0f && a[2] == 1.0f);
    irrvol_bin_direction(NULL, 0, a);
    CHECK(a[0] == 0.0f && a[1] == 0.0f && a[2] == 1.0f);
    irrvol_destroy(v);
}

/* ---- the GPU export and the GLSL text ---------------------------------------------------------- */

/* Sizes first; then every refused call (wrong order, one array without the
   other, a capacity one short) leaves both arrays untouched. */
static void test_gpu_export_checks(void)
{
    sc_scene s;
    irrvol *v = cube_volume(&s);
    irrvol_gpu_layout l;
    uint32_t *index;
    float *data;
    unsigned char *keep_index, *keep_data;
    size_t ib, db;
    if (!v) return;
    CHECK(irrvol_gpu_export(NULL, 2, &l, NULL, 0, NULL, 0) == IRRVOL_ERROR_INVALID_ARGUMENT);
    CHECK(irrvol_gpu_export(v, 2, NULL, NULL, 0, NULL, 0) == IRRVOL_ERROR_INVALID_ARGUMENT);
    CHECK(irrvol_gpu_export(v, 0, &l, NULL, 0, NULL, 0) == IRRVOL_ERROR_INVALID_ARGUMENT);
    CHECK(irrvol_gpu_export(v, 3, &l, NULL, 0, NULL, 0) == IRRVOL_ERROR_INVALID_ARGUMENT);
    if (!CHECK(irrvol_gpu_export(v, 2, &l, NULL, 0, NULL, 0) == IRRVOL_OK)) { irrvol_destroy(v); return; }
    ib = l.index_count * sizeof *index;
    db = l.data_count * sizeof *data;
    index = (uint32_t *)malloc(ib);
    data = (float *)malloc(db);
    keep_index = (unsigned char *)malloc(ib);
    keep_data = (unsigned char *)malloc(db);
    memset(index, 0xAB, ib);
    memset(data, 0xAB, db);
    memcpy(keep_index, index, ib);
    memcpy(keep_data, data, db);
    CHECK(irrvol_gpu_export(v, 2, &l, index, l.index_count, NULL, 0) == IRRVOL_ERROR_INVALID_ARGUMENT);
    CHECK(irrvol_gpu_export(v, 2, &l, NULL, 0, data, l.data_count) == IRRVOL_ERROR_INVALID_ARGUMENT);
    CHECK(irrvol_gpu_export(v, 2, &l, index, l.index_count - 1, data, l.data_count) == IRRVOL_ERROR_INVALID_ARGUMENT);
    CHECK(irrvol_gpu_export(v, 2, &l, index, l.index_count, data, l.data_count - 1) == IRRVOL_ERROR_INVALID_ARGUMENT);
    CHECK(memcmp(index, keep_index, ib) == 0 && memcmp(data, keep_data, db) == 0);
    CHECK(irrvol_gpu_export(v, 2, &l, index, l.index_count, data, l.data_count) == IRRVOL_OK);
    CHECK_EQ_INT(l.sh_order, 2);
    CHECK_EQ_INT(l.coefficients, 9);
    free(index);
    free(data);
    free(keep_index);
    free(keep_data);
    irrvol_destroy(v);
}

/* irrvol_glsl_source writes at most capacity bytes, zero-terminated when
   capacity > 0, and returns the full length whatever the capacity. */
static void test_glsl_source_capacity(void)
{
    size_t n = irrvol_glsl_source(NULL, 0), caps[4] = { 0, 1, 10, 0 }, i;
    char *full, *cut;
    caps[3] = n + 1;
    if (!CHECK(n > 100)) return;
    full = (char *)malloc(n + 1);
    cut = (char *)malloc(n + 9);
    CHECK(irrvol_glsl_source(full, n + 1) == n);
    CHECK(full[n] == '\0' && strlen(full) == n);
    for (i = 0; i < 4; i++) {
        memset(cut, '#', n + 9);
        CHECK(irrvol_glsl_source(cut, caps[i]) == n);
        if (caps[i] == 0) {
            CHECK(cut[0] == '#');
        } else {
            CHECK_MSG(cut[caps[i] - 1] == '\0', "capacity %zu: not terminated", caps[i]);
            CHECK(memcmp(cut, full, caps[i] - 1) == 0);
        }
        CHECK_MSG(cut[caps[i]] == '#', "capacity %zu: wrote past it", caps[i]);
    }
    free(full);
    free(cut);
}

/* ---- serialization ------------------------------------------------------------------------------ */

static int refuse_write(void *user, const void *bytes, size_t n)
{
    (void)user; (void)bytes; (void)n;
    return 1;
}

/* NULL arguments are refused with *out NULL; a failing write is IO; a
   load's allocator must have both callbacks or neither; the loaded volume
   allocates only through the caller's allocator and frees everything. */
static void test_save_and_load_contract(void)
{
    sc_scene s;
    irrvol *v = cube_volume(&s), *w;
    irrvol_allocator half;
    void *data = NULL;
    size_t size = 0;
    tally t;
    irrvol_allocator a = tally_allocator(&t);
    float p[3] = { 0.1f, 0.2f, 0.3f }, dir[3] = { 0.0f, 1.0f, 0.0f }, x[3], y[3];
    if (!v) return;
    CHECK(irrvol_save(NULL, refuse_write, NULL) == IRRVOL_ERROR_INVALID_ARGUMENT);
    CHECK(irrvol_save(v, NULL, NULL) == IRRVOL_ERROR_INVALID_ARGUMENT);
    CHECK(irrvol_save(v, refuse_write, NULL) == IRRVOL_ERROR_IO);
    CHECK(irrvol_save_to_memory(NULL, NULL, &data, &size) == IRRVOL_ERROR_INVALID_ARGUMENT);
    CHECK(irrvol_save_to_memory(v, NULL, NULL, &size) == IRRVOL_ERROR_INVALID_ARGUMENT);
    CHECK(irrvol_save_to_memory(v, NULL, &data, NULL) == IRRVOL_ERROR_INVALID_ARGUMENT);
    w = v;
    CHECK(irrvol_load(NULL, NULL, NULL, &w) == IRRVOL_ERROR_INVALID_ARGUMENT && w == NULL);
    CHECK(irrvol_load(NULL, NULL, NULL, NULL) == IRRVOL_ERROR_INVALID_ARGUMENT);
    if (!CHECK(irrvol_save_to_memory(v, &a, &data, &size) == IRRVOL_OK)) { irrvol_destroy(v); return; }
    CHECK_EQ_INT(t.frees + 1, t.allocs);   /* the buffer is the one allocation left */
    half = a;
    half.free = NULL;
    w = v;
    CHECK(irrvol_load_from_memory(data, size, &half, &w) == IRRVOL_ERROR_INVALID_ARGUMENT && w == NULL);
    w = v;
    CHECK(irrvol_load_from_memory(NULL, size, NULL, &w) == IRRVOL_ERROR_INVALID_ARGUMENT && w == NULL);
    CHECK(irrvol_load_from_memory(data, size, NULL, NULL) == IRRVOL_ERROR_INVALID_ARGUMENT);
    CHECK_EQ_INT(t.frees + 1, t.allocs);   /* refused loads allocate nothing */
    if (CHECK(irrvol_load_from_memory(data, size, &a, &w) == IRRVOL_OK)) {
        irrvol_query(v, p, dir, x);
        irrvol_query(w, p, dir, y);
        CHECK(same3(x, y));
        irrvol_destroy(w);
    }
    irrvol_free_memory(&a, data);
    CHECK_EQ_INT(t.frees, t.allocs);
    irrvol_free_memory(&a, NULL);   /* accepted */
    irrvol_free_memory(NULL, NULL);
    CHECK_EQ_INT(t.frees, t.allocs);
    irrvol_destroy(v);
}

int main(int argc, char **argv)
{
    TEST_INIT(argc, argv);
    RUN(test_build_checks_before_allocating);
    RUN(test_readers_change_nothing_when_refused);
    RUN(test_queries_answer_everything);
    RUN(test_gpu_export_checks);
    RUN(test_glsl_source_capacity);
    RUN(test_save_and_load_contract);
    return test_finish();
}
