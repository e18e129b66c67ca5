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

int main(int argc, char **argv)
{
    TEST_INIT(argc, argv);
    RUN(test_result_strings_link);
    return test_finish();
}
