/* irrvol.h serialization: bit-exact round trips, every truncation length,
   every single-byte corruption, hostile headers with valid checksums, write
   failures. */
#define IRRVOL_IMPLEMENTATION
#include "irrvol.h"
#include "tests/test.h"
#include "tests/test_irrvol_scenes.h"


/* CRC-32 (IEEE, reflected), written here independently of the header. */
static uint32_t crc32_of(const unsigned char *p, size_t n)
{
    uint32_t c = 0xFFFFFFFFu;
    size_t i;
    int k;
    for (i = 0; i < n; i++) {
        c ^= p[i];
        for (k = 0; k < 8; k++) c = (c & 1u) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
    }
    return c ^ 0xFFFFFFFFu;
}
static void put_le32(unsigned char *p, uint32_t v)
{
    p[0] = (unsigned char)v; p[1] = (unsigned char)(v >> 8);
    p[2] = (unsigned char)(v >> 16); p[3] = (unsigned char)(v >> 24);
}
static void fix_crc(unsigned char *data, size_t size) { put_le32(data + size - 4, crc32_of(data, size - 4)); }

/* Payload offsets (after magic 8, version 4, size 8). */
enum { OFF_VERSION = 8, OFF_PAYLOAD = 20, OFF_K = 20, OFF_WEIGHTING = 32, OFF_SAMPLES_X = 40, OFF_SUBGRID = 52,
       OFF_VIS_RES = 56, OFF_LO_X = 60, OFF_BIAS = 84, OFF_COUNT = 88, OFF_INVALID = 104, OFF_FLAGS = 112 };

/* Largest single allocation, to prove hostile sizes are refused first. */
typedef struct tracking { size_t largest; long live; } tracking;
static void *tracking_alloc(size_t size, void *user)
{
    tracking *t = (tracking *)user;
    if (size > t->largest) t->largest = size;
    t->live++;
    return malloc(size);
}
static void tracking_free(void *p, void *user) { ((tracking *)user)->live--; free(p); }

static void constant_radiance(void *user, const float org[3], const float dir[3], float rgb[3])
{
    (void)user; (void)dir;
    rgb[0] = 1.0f + org[0]; rgb[1] = 2.0f + org[1]; rgb[2] = 0.5f + org[2] * dir[2];
}

/* A small volume with a second level, kept radiance and a moment. */
static irrvol *small_volume_stored(int keep_radiance, int full_precision)
{
    sc_scene s;
    irrvol_desc d;
    irrvol *v = NULL;
    memset(&s, 0, sizeof s);
    sc_square(&s, 1, 0.3f, 0.3f, 0.3f, 0.05f, 0);
    sc_geometry_desc(&d, &s);
    d.radiance = constant_radiance;
    d.resolution = 2;
    d.visibility_resolution = 3;   /* small maps: every byte of the file is loaded twice per length */
    d.moment = 3;
    d.filter = IRRVOL_FILTER_BILINEAR;
    d.keep_radiance = keep_radiance;
    d.full_precision = full_precision;
    d.grid_samples[0] = 2; d.grid_samples[1] = 3; d.grid_samples[2] = 2;
    sc_set3(d.bounds_min, 0, 0, 0);
    sc_set3(d.bounds_max, 1, 1, 1);
    if (irrvol_build(&d, &v) != IRRVOL_OK) return NULL;
    return v;
}

/* keep_radiance also keeps the irradiance at full precision: the files of
   both irradiance stores are tested. */
static irrvol *small_volume(int keep_radiance)
{
    return small_volume_stored(keep_radiance, keep_radiance);
}

/* Streams that move a few bytes at a time, as a file or socket might. */
typedef struct stream { unsigned char *data; size_t size, pos, cap, fail_after; } stream;
static int stream_write(void *user, const void *bytes, size_t n)
{
    stream *s = (stream *)user;
    if (s->pos + n > s->fail_after) return -1;
    if (s->pos + n > s->cap) {
        s->cap = 2 * (s->pos + n);
        s->data = (unsigned char *)realloc(s->data, s->cap);
    }
    memcpy(s->data + s->pos, bytes, n);
    s->pos += n;
    s->size = s->pos;
    return 0;
}
static int stream_read(void *user, void *bytes, size_t n)
{
    stream *s = (stream *)user;
    if (n > s->size - s->pos) return -1;
    memcpy(bytes, s->data + s->pos, n);
    s->pos += n;
    return 0;
}

static int same_queries(const irrvol *a, const irrvol *b)
{
    uint32_t s = 99u;
    int i, k, f;
    for (i = 0; i < 500; i++) {
        float p[3], d[3], ha[3], hb[3];
        for (k = 0; k < 3; k++) {
            s = s * 1664525u + 1013904223u;
            p[k] = (float)(s >> 8) / 16777216.0f * 1.4f - 0.2f;
            s = s * 1664525u + 1013904223u;
            d[k] = (float)(s >> 8) / 16777216.0f - 0.5f;
        }
        for (f = 0; f < 9; f++) {   /* every filter with every weighting, and the harmonics */
            irrvol_query_filter(a, (irrvol_filter)(f % 3), (irrvol_weighting)(f / 3), p, d, ha);
            irrvol_query_filter(b, (irrvol_filter)(f % 3), (irrvol_weighting)(f / 3), p, d, hb);
            if (memcmp(ha, hb, sizeof ha) != 0) return 0;
            irrvol_query_sh(a, (uint32_t)(1 + f % 2), (irrvol_weighting)(f / 3), p, d, ha);
            irrvol_query_sh(b, (uint32_t)(1 + f % 2), (irrvol_weighting)(f / 3), p, d, hb);
            if (memcmp(ha, hb, sizeof ha) != 0) return 0;
        }
    }
    return 1;
}

static void test_round_trip(void)
{
    int keep;
    for (keep = 0; keep <= 1; keep++) {
        irrvol *v = small_volume(keep), *w = NULL;
        irrvol_volume_info iv, iw;
        void *data, *again;
        size_t size, again_size;
        stream st;
        float rv[8 * 3], rw[8 * 3];
        uint32_t i;
        if (!CHECK(v != NULL)) return;
        CHECK_EQ_INT(irrvol_save_to_memory(v, NULL, &data, &size), IRRVOL_OK);
        CHECK_EQ_INT(irrvol_load_from_memory(data, size, NULL, &w), IRRVOL_OK);
        if (!CHECK(w != NULL)) { irrvol_destroy(v); irrvol_free_memory(NULL, data); return; }
        CHECK(same_queries(v, w));
        irrvol_info(v, &iv);
        irrvol_info(w, &iw);
        CHECK(memcmp(&iv, &iw, sizeof iv) == 0);   /* counts, bounds, rays, bytes: all kept */
        CHECK(iv.refined_cells > 0 && iv.second_level_samples > 0 && iv.has_radiance == keep);
        for (i = 0; i < iv.sample_count && keep; i++) {
            irrvol_sample_values(v, i, NULL, rv);
            irrvol_sample_values(w, i, NULL, rw);
            CHECK(memcmp(rv, rw, sizeof rv) == 0);
        }
        CHECK_EQ_INT(irrvol_save_to_memory(w, NULL, &again, &again_size), IRRVOL_OK);
        CHECK(again_size == size && memcmp(again, data, size) == 0);   /* bit-exact */
        /* the same bytes through callbacks */
        memset(&st, 0, sizeof st);
        st.fail_after = (size_t)-1;
        CHECK_EQ_INT(irrvol_save(v, stream_write, &st), IRRVOL_OK);
        CHECK(st.size == size && memcmp(st.data, data, size) == 0);
        st.pos = 0;
        irrvol_destroy(w);
        CHECK_EQ_INT(irrvol_load(NULL, stream_read, &st, &w), IRRVOL_OK);
        CHECK(w && same_queries(v, w));
        free(st.data);
        irrvol_destroy(w);
        irrvol_destroy(v);
        irrvol_free_memory(NULL, data);
        irrvol_free_memory(NULL, again);
    }
}

/* The default bins (k = 17, 578 of them) in the compact store: the bins
   are most of the file, a word each, so a size check that counted three
   floats a bin would refuse the file as too short. */
static void test_round_trip_default_resolution(void)
{
    sc_scene s;
    irrvol_desc d;
    irrvol *v = NULL, *w = NULL;
    irrvol_volume_info info;
    void *data;
    size_t size;
    memset(&s, 0, sizeof s);
    sc_square(&s, 1, 0.3f, 0.3f, 0.3f, 0.05f, 0);
    sc_geometry_desc(&d, &s);
    d.radiance = constant_radiance;
    d.grid_samples[0] = 2; d.grid_samples[1] = 2; d.grid_samples[2] = 2;
    sc_set3(d.bounds_min, 0, 0, 0);
    sc_set3(d.bounds_max, 1, 1, 1);
    if (!CHECK_EQ_INT(irrvol_build(&d, &v), IRRVOL_OK)) return;
    irrvol_info(v, &info);
    CHECK(info.bins == 578 && info.bin_bytes == 4);
    CHECK_EQ_INT(irrvol_save_to_memory(v, NULL, &data, &size), IRRVOL_OK);
    CHECK(size < (size_t)info.sample_count * info.bins * 12);   /* shorter than three floats a bin */
    CHECK_EQ_INT(irrvol_load_from_memory(data, size, NULL, &w), IRRVOL_OK);
    CHECK(w && same_queries(v, w));
    irrvol_destroy(w);
    irrvol_destroy(v);
    irrvol_free_memory(NULL, data);
}

static void test_truncation_and_corruption(void)
{
    irrvol *v = small_volume(1), *w;
    void *data;
    unsigned char *copy;
    size_t size, n, wrong = 0;
    if (!CHECK(v != NULL)) return;
    CHECK_EQ_INT(irrvol_save_to_memory(v, NULL, &data, &size), IRRVOL_OK);
    test_note("saved volume: %zu bytes; loading every truncation and every byte flip", size);
    copy = (unsigned char *)malloc(size);
    for (n = 0; n < size; n++) {   /* every truncation length */
        irrvol_result r = irrvol_load_from_memory(data, n, NULL, &w);
        if (r != IRRVOL_ERROR_CORRUPT_DATA || w != NULL) wrong++;
    }
    CHECK_EQ_INT(wrong, 0);
    for (n = 0; n < size; n++) {   /* every single-byte corruption */
        irrvol_result r;
        memcpy(copy, data, size);
        copy[n] ^= 0x5Au;
        r = irrvol_load_from_memory(copy, size, NULL, &w);
        if (w != NULL) { irrvol_destroy(w); wrong++; }
        else if (r != IRRVOL_ERROR_CORRUPT_DATA && !(r == IRRVOL_ERROR_VERSION && n >= OFF_VERSION && n < OFF_VERSION + 4))
            wrong++;
    }
    CHECK_EQ_INT(wrong, 0);
    {   /* bytes after the checksum are not the loader's business */
        unsigned char *longer = (unsigned char *)malloc(size + 7);
        memcpy(longer, data, size);
        memset(longer + size, 0xEE, 7);
        CHECK_EQ_INT(irrvol_load_from_memory(longer, size + 7, NULL, &w), IRRVOL_OK);
        irrvol_destroy(w);
        free(longer);
    }
    free(copy);
    irrvol_free_memory(NULL, data);
    irrvol_destroy(v);
}

/* Headers that lie, with a valid checksum: refused before any large
   allocation. Destroys v. */
static void hostile_headers(irrvol *v)
{
    irrvol *w;
    void *data;
    unsigned char *c;
    size_t size, irradiance_at;
    tracking t;
    irrvol_allocator a;
    irrvol_volume_info info;
    if (!CHECK(v != NULL)) return;
    CHECK_EQ_INT(irrvol_save_to_memory(v, NULL, &data, &size), IRRVOL_OK);
    c = (unsigned char *)malloc(size);
    a.alloc = tracking_alloc;
    a.free = tracking_free;
    a.user = &t;
    irrvol_info(v, &info);   /* the irradiance follows the cell flags and the gathered samples' origins */
    irradiance_at = OFF_FLAGS + info.cell_count + 16 * (info.sample_count - info.hanging_samples);
#define CORRUPTED(stmt, expected, limit) do { memcpy(c, data, size); stmt; fix_crc(c, size); \
        t.largest = 0; t.live = 0; w = (irrvol *)c; \
        CHECK_EQ_INT(irrvol_load_from_memory(c, size, &a, &w), expected); \
        CHECK(w == NULL && t.live == 0 && t.largest < (limit)); } while (0)
    /* sizes that lie: refused before anything large is allocated */
#define HOSTILE(stmt, expected) CORRUPTED(stmt, expected, 4096)
    /* values out of range, found while reading: allocations in proportion to the input (the
       visibility maps gain their borders: (n + 2)^2 / n^2 of what was read) */
#define BAD_VALUE(stmt) CORRUPTED(stmt, IRRVOL_ERROR_CORRUPT_DATA, 2 * size)
    HOSTILE(put_le32(c + OFF_SAMPLES_X, 1024); put_le32(c + OFF_SAMPLES_X + 4, 1024);
            put_le32(c + OFF_SAMPLES_X + 8, 1024), IRRVOL_ERROR_CORRUPT_DATA);   /* a billion cells */
    HOSTILE(put_le32(c + OFF_K, 64), IRRVOL_ERROR_CORRUPT_DATA);                 /* 8192 bins per sample */
    HOSTILE(put_le32(c + OFF_K, 0), IRRVOL_ERROR_CORRUPT_DATA);
    HOSTILE(put_le32(c + OFF_SAMPLES_X, 1), IRRVOL_ERROR_CORRUPT_DATA);
    HOSTILE(put_le32(c + OFF_SUBGRID, 99), IRRVOL_ERROR_CORRUPT_DATA);
    HOSTILE(put_le32(c + OFF_COUNT, 0xFFFFFFF0u), IRRVOL_ERROR_CORRUPT_DATA);     /* sample count vs payload */
    HOSTILE(put_le32(c + OFF_COUNT, 12), IRRVOL_ERROR_CORRUPT_DATA);              /* fewer than the grid has */
    HOSTILE(put_le32(c + OFF_LO_X, 0x7FC00000u), IRRVOL_ERROR_CORRUPT_DATA);      /* NaN bound */
    HOSTILE(put_le32(c + OFF_LO_X, 0x3F800000u), IRRVOL_ERROR_CORRUPT_DATA);      /* min = max = 1 */
    HOSTILE(c[OFF_FLAGS] = 3, IRRVOL_ERROR_CORRUPT_DATA);                        /* a cell flag not 0, 1 or 2 */
    HOSTILE(put_le32(c + OFF_WEIGHTING, 7), IRRVOL_ERROR_CORRUPT_DATA);          /* no such weighting */
    HOSTILE(put_le32(c + OFF_VIS_RES, 0), IRRVOL_ERROR_CORRUPT_DATA);
    HOSTILE(put_le32(c + OFF_VIS_RES, IRRVOL_MAX_VISIBILITY_RESOLUTION + 1), IRRVOL_ERROR_CORRUPT_DATA);
    HOSTILE(put_le32(c + OFF_VIS_RES, 4096), IRRVOL_ERROR_CORRUPT_DATA);         /* 16 M texels per sample */
    HOSTILE(put_le32(c + OFF_BIAS, 0x7FC00000u), IRRVOL_ERROR_CORRUPT_DATA);     /* NaN bias */
    HOSTILE(put_le32(c + OFF_BIAS, 0xBF800000u), IRRVOL_ERROR_CORRUPT_DATA);     /* negative bias */
    BAD_VALUE(put_le32(c + OFF_INVALID, 1));                                     /* counts disagree with the origins */
    BAD_VALUE(put_le32(c + OFF_FLAGS + 2 + 12, 0x3F000000u));                    /* a validity of 0.5 */
    BAD_VALUE(put_le32(c + OFF_FLAGS + 2, 0x3F000000u));                         /* moved, against the count */
    BAD_VALUE(put_le32(c + size - 8, 0xBF800000u));                              /* a negative fit variance */
    HOSTILE(put_le32(c + 12, (uint32_t)size), IRRVOL_ERROR_CORRUPT_DATA);         /* payload size too large */
    HOSTILE(put_le32(c + 12, 30), IRRVOL_ERROR_CORRUPT_DATA);                     /* too small */
    BAD_VALUE(put_le32(c + size - 8, 0x7F800000u));                              /* an infinite fit variance */
    BAD_VALUE(put_le32(c + irradiance_at, 0x7F800000u));   /* infinite irradiance, or a compact store's shift
                                                              past any finite float's */
    BAD_VALUE(put_le32(c + irradiance_at - 4, 0x40000000u));                     /* a validity of 2 */
    HOSTILE(put_le32(c + OFF_VERSION, IRRVOL_FILE_FORMAT_VERSION + 1), IRRVOL_ERROR_VERSION);
#undef HOSTILE
#undef BAD_VALUE
#undef CORRUPTED
    free(c);
    irrvol_free_memory(NULL, data);
    irrvol_destroy(v);
}

static void test_hostile_headers(void)
{
    irrvol_volume_info info;
    irrvol *v = small_volume(0);
    if (CHECK(v != NULL)) {
        irrvol_info(v, &info);
        CHECK_EQ_INT(info.bin_bytes, 4);   /* the compact store */
        hostile_headers(v);
    }
    v = small_volume_stored(0, 1);   /* no radiance: the file ends with the visibility fits */
    if (CHECK(v != NULL)) {
        irrvol_info(v, &info);
        CHECK_EQ_INT(info.bin_bytes, 12);   /* full precision */
        hostile_headers(v);
    }
}

static void test_write_failures(void)
{
    irrvol *v = small_volume(1);
    void *data;
    size_t size, n;
    if (!CHECK(v != NULL)) return;
    CHECK_EQ_INT(irrvol_save_to_memory(v, NULL, &data, &size), IRRVOL_OK);
    for (n = 0; n < size; n += 13) {
        stream st;
        memset(&st, 0, sizeof st);
        st.fail_after = n;
        CHECK_EQ_INT(irrvol_save(v, stream_write, &st), IRRVOL_ERROR_IO);
        free(st.data);
    }
    irrvol_free_memory(NULL, data);
    irrvol_destroy(v);
    CHECK_EQ_INT(irrvol_save_to_memory(NULL, NULL, &data, &size), IRRVOL_ERROR_INVALID_ARGUMENT);
    CHECK(data == NULL && size == 0);
    CHECK_EQ_INT(irrvol_load_from_memory(NULL, 10, NULL, &v), IRRVOL_ERROR_INVALID_ARGUMENT);
    CHECK(v == NULL);
}

int main(int argc, char **argv)
{
    TEST_INIT(argc, argv);
    RUN(test_round_trip);
    RUN(test_round_trip_default_resolution);
    RUN(test_truncation_and_corruption);
    RUN(test_hostile_headers);
    RUN(test_write_failures);
    return test_finish();
}
