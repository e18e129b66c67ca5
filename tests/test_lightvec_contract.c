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

int main(int argc, char **argv)
{
    TEST_INIT(argc, argv);
    RUN(test_triangle_count_wraps_32_bits);
    return test_finish();
}
