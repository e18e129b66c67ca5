/* Fuzz target of lightvec_load (see tests/fuzz/fuzz.h): loads the bytes as a
   light-vector cache; a cache that loads must hold the records it counts
   (and refuse the next id), answer lookups and finds at its records and
   between them, describe every icosahedron face it counts, and save to bytes
   that load again and save to the same bytes. (The loader renormalises unit
   vectors, so the first save may differ from the input; from then on the
   encoding is fixed.) */
#define LIGHTVEC_IMPLEMENTATION
#include "lightvec.h"
#include "tests/fuzz/fuzz.h"

/* Lookups are capped so that one input stays fast. */
#define MAX_LOOKUPS 32u

static fuzz_outcome outcome_of(lightvec_result r)
{
    switch (r) {
    case LIGHTVEC_OK: return FUZZ_LOADED;
    case LIGHTVEC_ERROR_CORRUPT_DATA: return FUZZ_CORRUPT;
    case LIGHTVEC_ERROR_VERSION: return FUZZ_VERSION;
    default: return FUZZ_OTHER;
    }
}

/* A lookup and a find at point p with the normal and view of record r. */
static void query_like(lightvec_cache *c, const float p[3], const lightvec_record *r)
{
    const float *view = (r->flags & LIGHTVEC_RECORD_VIEW_INDEPENDENT) ? NULL : r->outgoing;
    lightvec_lookup_result res;
    uint32_t ids[8], count = 0, i;
    float weights[8];
    lightvec_record found;
    fuzz_require(lightvec_lookup(c, p, r->normal, view, &res) == LIGHTVEC_OK, "a lookup at a record was refused");
    fuzz_require(lightvec_find(c, p, r->normal, view, ids, weights, 8, &count) == LIGHTVEC_OK,
                 "a find at a record was refused");
    for (i = 0; i < count && i < 8; i++)
        fuzz_require(lightvec_cache_record(c, ids[i], &found) == LIGHTVEC_OK, "a find gave an id of no record");
}

static void use_cache(lightvec_cache *c, const lightvec_cache_stats *stats)
{
    uint32_t n = (uint32_t)stats->record_count, i, face;
    lightvec_record r, next;
    lightvec_face_info f;
    for (i = 0; i < n && i < MAX_LOOKUPS; i++) {
        float mid[3];
        int k;
        fuzz_require(lightvec_cache_record(c, i, &r) == LIGHTVEC_OK, "a counted record was refused");
        query_like(c, r.position, &r);
        if (lightvec_cache_record(c, (i + 1) % n, &next) != LIGHTVEC_OK) fuzz_fail("a counted record was refused");
        for (k = 0; k < 3; k++) mid[k] = 0.5f * r.position[k] + 0.5f * next.position[k];
        query_like(c, mid, &r);
        fuzz_require(lightvec_cache_locate(c, r.outgoing, &face) == LIGHTVEC_OK && face < stats->face_count,
                     "a record's view direction is in no face");
    }
    fuzz_require(lightvec_cache_record(c, n, &r) == LIGHTVEC_ERROR_INVALID_ARGUMENT, "a record past the last was given");
    for (i = 0; i < stats->face_count; i++)
        fuzz_require(lightvec_cache_face(c, i, &f) == LIGHTVEC_OK, "a counted face was refused");
}

/* save, load, save: the two saves are the same bytes. */
static void check_save_is_stable(const lightvec_cache *c)
{
    void *first = NULL, *second = NULL;
    size_t first_size = 0, second_size = 0;
    lightvec_cache *back = NULL;
    fuzz_require(lightvec_save_to_memory(c, NULL, &first, &first_size) == LIGHTVEC_OK, "a loaded cache did not save");
    fuzz_require(lightvec_load_from_memory(first, first_size, NULL, &back) == LIGHTVEC_OK,
                 "a saved cache did not load");
    fuzz_require(lightvec_save_to_memory(back, NULL, &second, &second_size) == LIGHTVEC_OK,
                 "a reloaded cache did not save");
    fuzz_require(fuzz_same_bytes(first, first_size, second, second_size), "saving a reloaded cache changed its bytes");
    lightvec_free_memory(NULL, first);
    lightvec_free_memory(NULL, second);
    lightvec_cache_destroy(back);
}

static fuzz_outcome load_cache(const uint8_t *data, size_t size)
{
    lightvec_cache *c = NULL;
    lightvec_cache_stats stats;
    lightvec_result r = lightvec_load_from_memory(data, size, NULL, &c);
    if (r != LIGHTVEC_OK) {
        fuzz_require(c == NULL, "a refused cache was returned");
        return outcome_of(r);
    }
    fuzz_require(lightvec_cache_info(c, &stats) == LIGHTVEC_OK && stats.face_count >= 20,
                 "lightvec_cache_info of a loaded cache");
    use_cache(c, &stats);
    check_save_is_stable(c);
    lightvec_cache_destroy(c);
    return FUZZ_LOADED;
}

/* Whether loading the bytes and saving gives them back: true of every file
   lightvec_save wrote, since unit vectors load as they are (the header:
   "normalising twice (insert, save, load) changes nothing"). */
static int resaves_same(const uint8_t *data, size_t size)
{
    lightvec_cache *c = NULL;
    void *saved = NULL;
    size_t saved_size = 0;
    int same = lightvec_load_from_memory(data, size, NULL, &c) == LIGHTVEC_OK &&
               lightvec_save_to_memory(c, NULL, &saved, &saved_size) == LIGHTVEC_OK &&
               fuzz_same_bytes(saved, saved_size, data, size);
    lightvec_free_memory(NULL, saved);
    lightvec_cache_destroy(c);
    return same;
}

const fuzz_target fuzz_this_target = { "lightvec", load_cache, 1, resaves_same };
