/* Tests of examples/common/image.h's PFM reader and writer, which carry the
   tests' stored reference frames: a round trip is bit-exact (values of
   every magnitude, signed zeros, infinities), and the reader refuses a
   missing file, another size, another format and every truncation. */
#define _POSIX_C_SOURCE 200809L
#include "examples/common/image.h"
#include "tests/test.h"

#include <unistd.h>

#define W 7
#define H 5

static void temp_path(char *path, size_t size)
{
    snprintf(path, size, "/tmp/test_image_%ld.pfm", (long)getpid());
}

static void fill(float *rgb)
{
    int i;
    for (i = 0; i < 3 * W * H; i++) rgb[i] = (float)((i * 7919) % 1000) * 0.37f - 100.0f;
    rgb[0] = -0.0f;
    rgb[1] = 1e-40f;          /* subnormal */
    rgb[2] = 3.0e38f;
    rgb[3] = (float)HUGE_VAL; /* infinity */
}

static void test_pfm_round_trip(void)
{
    float a[3 * W * H], b[3 * W * H];
    char path[128];
    temp_path(path, sizeof path);
    fill(a);
    memset(b, 0, sizeof b);
    CHECK(ex_write_pfm(path, W, H, a) == 0);
    CHECK(ex_read_pfm(path, W, H, b) == 0);
    CHECK_MSG(memcmp(a, b, sizeof a) == 0, "the round trip changed a value");
    remove(path);
}

static void test_pfm_rejects(void)
{
    float a[3 * W * H], b[3 * W * H];
    char path[128];
    FILE *f;
    long size, cut;
    unsigned char *bytes;
    int rejected = 0;
    temp_path(path, sizeof path);
    fill(a);
    CHECK(ex_read_pfm("/nonexistent/frame.pfm", W, H, b) == -1);
    CHECK(ex_write_pfm(path, W, H, a) == 0);
    CHECK(ex_read_pfm(path, W + 1, H, b) == -1);   /* another size */
    CHECK(ex_read_pfm(path, W, H - 1, b) == -1);
    CHECK(ex_read_pfm(path, 0, H, b) == -1);
    CHECK(ex_read_pfm(path, W, H, NULL) == -1);
    f = fopen(path, "rb");
    if (!CHECK(f != NULL)) return;
    fseek(f, 0, SEEK_END);
    size = ftell(f);
    rewind(f);
    bytes = (unsigned char *)malloc((size_t)size);
    if (!CHECK(bytes && fread(bytes, 1, (size_t)size, f) == (size_t)size)) {
        fclose(f);
        free(bytes);
        return;
    }
    fclose(f);
    for (cut = 0; cut < size; cut++) {   /* every truncation */
        f = fopen(path, "wb");
        if (!f) break;
        fwrite(bytes, 1, (size_t)cut, f);
        fclose(f);
        rejected += ex_read_pfm(path, W, H, b) == -1;
    }
    CHECK_EQ_INT(rejected, (int)size);
    bytes[1] = 'f';                       /* "Pf": one channel, another format */
    f = fopen(path, "wb");
    if (CHECK(f != NULL)) {
        fwrite(bytes, 1, (size_t)size, f);
        fclose(f);
        CHECK(ex_read_pfm(path, W, H, b) == -1);
    }
    free(bytes);
    remove(path);
}

/* The filmic pipeline: Narkowicz's ACES fit at known points (its
   rational function evaluated by hand), monotonic, saturating at white;
   the key exposure of a uniform image maps it to middle grey. */
static void test_filmic(void)
{
    float x, prev = -1.0f, img[3 * 16], black[3 * 16];
    unsigned char out[3 * 16];
    int i, monotonic = 1;
    CHECK(ex_filmic(0.0f) == 0.0f && ex_filmic(-1.0f) == 0.0f && ex_filmic(NAN) == 0.0f);
    /* 0.18 (2.51 0.18 + 0.03) / (0.18 (2.43 0.18 + 0.59) + 0.14) = 0.08672 / 0.32493 */
    CHECK_CLOSE(ex_filmic(0.18f), 0.086724 / 0.324929, 1e-5, 0.0);
    CHECK_CLOSE(ex_filmic(1.0f), 2.54 / 3.16, 1e-5, 0.0);
    CHECK(ex_filmic(1e6f) == 1.0f);
    for (x = 0.0f; x < 64.0f; x += 0.01f) {
        monotonic &= ex_filmic(x) >= prev;
        prev = ex_filmic(x);
    }
    CHECK(monotonic);
    for (i = 0; i < 3 * 16; i++) {
        img[i] = 2.5f;
        black[i] = 0.0f;
    }
    CHECK_CLOSE(ex_exposure_key(img, 4, 4), 0.18 / 2.5, 2e-4, 0.0);   /* delta = 1e-4 of the peak */
    CHECK(ex_exposure_key(black, 4, 4) == 1.0f);
    ex_tonemap_filmic(img, 4, 4, ex_exposure_key(img, 4, 4), out);
    CHECK(out[0] >= 139 && out[0] <= 141);   /* middle grey: filmic 0.267, sRGB 0.553 */
}

int main(int argc, char **argv)
{
    TEST_INIT(argc, argv);
    RUN(test_pfm_round_trip);
    RUN(test_pfm_rejects);
    RUN(test_filmic);
    return test_finish();
}
