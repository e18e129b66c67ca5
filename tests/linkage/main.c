/* Linkage test, translation unit 2: uses every header through its
   declarations only, so the program links only if the implementation in
   impl.c has external linkage and matching signatures. */
#include "irrvol.h"
#include "radinterp.h"
#include "lightvec.h"
#include "rendercache.h"
#include "tests/test.h"

static void test_result_strings_link(void)
{
    CHECK(strcmp(irrvol_result_string(IRRVOL_OK), "ok") == 0);
    CHECK(strcmp(radinterp_result_string(RADINTERP_ERROR_CORRUPT_DATA), "corrupt data") == 0);
    CHECK(strcmp(lightvec_result_string(LIGHTVEC_ERROR_OUT_OF_MEMORY), "out of memory") == 0);
    CHECK(strcmp(rendercache_result_string(RENDERCACHE_ERROR_INVALID_ARGUMENT), "invalid argument") == 0);
}

static void test_lightvec_link(void)
{
    lightvec_cache *cache = NULL;
    lightvec_record rec;
    lightvec_lookup_result lr;
    memset(&rec, 0, sizeof rec);
    rec.normal[2] = rec.outgoing[2] = rec.vector.direction[2] = 1.0f;
    rec.distance = rec.visibility = 1.0f;
    CHECK(lightvec_cache_create(NULL, &cache) == LIGHTVEC_OK);
    CHECK(lightvec_insert(cache, &rec, NULL) == LIGHTVEC_OK);
    CHECK(lightvec_lookup(cache, rec.position, rec.normal, rec.outgoing, &lr) == LIGHTVEC_OK && lr.valid_count == 1);
    lightvec_cache_destroy(cache);
}

int main(int argc, char **argv)
{
    TEST_INIT(argc, argv);
    RUN(test_result_strings_link);
    RUN(test_lightvec_link);
    return test_finish();
}
