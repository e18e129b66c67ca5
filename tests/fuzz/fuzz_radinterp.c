/* Fuzz target of radinterp_mesh_load (see tests/fuzz/fuzz.h): loads the
   bytes as a radiosity mesh with its interpolants; a mesh that loads must
   evaluate and shade every triangle, give every leaf and discontinuity it
   counts (and refuse the next index), hold arrays as long as it says (read
   whole under ASan), and save to exactly the bytes it was loaded from (every
   field is stored as read). */
#define RADINTERP_IMPLEMENTATION
#include "radinterp.h"
#include "tests/fuzz/fuzz.h"

/* Per-triangle work is capped so that one input stays fast. */
#define MAX_TRIANGLES 256u

static fuzz_outcome outcome_of(radinterp_result r)
{
    switch (r) {
    case RADINTERP_OK: return FUZZ_LOADED;
    case RADINTERP_ERROR_CORRUPT_DATA: return FUZZ_CORRUPT;
    case RADINTERP_ERROR_VERSION: return FUZZ_VERSION;
    default: return FUZZ_OTHER;
    }
}

/* Sums every float of an array: ASan reports an array shorter than n. */
static float touch(const float *a, size_t n)
{
    float sum = 0.0f;
    size_t i;
    for (i = 0; i < n; i++) sum += a[i];
    return sum;
}

static void check_data(const radinterp_mesh *m, const radinterp_mesh_data *d)
{
    uint32_t i;
    for (i = 0; i < 3 * d->triangle_count; i++)
        fuzz_require(d->indices[i] < d->vertex_count, "a triangle's corner is not a vertex");
    for (i = 0; i < d->triangle_count; i++)
        fuzz_require(d->triangle_leaf[i] < radinterp_mesh_leaf_count(m) && d->edge_flags[i] < 64,
                     "a triangle's leaf or edge flags out of range");
    (void)touch(d->positions, 3 * (size_t)d->vertex_count);
    (void)touch(d->vertex_radiosity, 3 * (size_t)d->vertex_count);
    (void)touch(d->coefficients, 18 * (size_t)d->triangle_count);
    (void)touch(d->irradiance_coefficients, 18 * (size_t)d->triangle_count);
    (void)touch(d->corner_radiosity, 9 * (size_t)d->triangle_count);
    (void)touch(d->reflectance, 3 * (size_t)d->triangle_count);
    (void)touch(d->emission, 3 * (size_t)d->triangle_count);
}

static void shade_triangles(const radinterp_mesh *m, uint32_t triangles)
{
    static const float st[4][2] = { { 0, 0 }, { 1, 0 }, { 0, 1 }, { 1.0f / 3, 1.0f / 3 } };
    uint32_t ids[MAX_TRIANGLES + 2], t;
    float uv[2 * (MAX_TRIANGLES + 2)], rgb[3 * (MAX_TRIANGLES + 2)];
    uint32_t n = triangles < MAX_TRIANGLES ? triangles : MAX_TRIANGLES, k;
    for (t = 0; t < n; t++)
        for (k = 0; k < 4; k++) {
            fuzz_require(radinterp_eval(m, t, st[k][0], st[k][1], rgb) == RADINTERP_OK &&
                             radinterp_eval_irradiance(m, t, st[k][0], st[k][1], rgb) == RADINTERP_OK,
                         "radinterp_eval refused a triangle of the mesh");
        }
    fuzz_require(radinterp_eval(m, triangles, 0.25f, 0.25f, rgb) == RADINTERP_ERROR_INVALID_ARGUMENT,
                 "radinterp_eval accepted a triangle past the last");
    for (t = 0; t < n; t++) {
        ids[t] = t;
        uv[2 * t] = st[t % 4][0];
        uv[2 * t + 1] = st[t % 4][1];
    }
    ids[n] = RADINTERP_NO_TRIANGLE;   /* pixels of no triangle are left as they are */
    ids[n + 1] = triangles;
    uv[2 * n] = uv[2 * n + 1] = uv[2 * n + 2] = uv[2 * n + 3] = 0.5f;
    memset(rgb, 0, sizeof rgb);
    radinterp_shade(m, ids, uv, n + 2, rgb);
    radinterp_shade_gouraud(m, ids, uv, n + 2, rgb);
}

static void check_leaves_and_discontinuities(const radinterp_mesh *m)
{
    uint32_t leaves = radinterp_mesh_leaf_count(m), discs = radinterp_mesh_discontinuity_count(m), i;
    radinterp_mesh_leaf leaf;
    radinterp_discontinuity disc;
    for (i = 0; i < leaves; i++)
        fuzz_require(radinterp_mesh_get_leaf(m, i, &leaf) == RADINTERP_OK, "a counted leaf was refused");
    fuzz_require(radinterp_mesh_get_leaf(m, leaves, &leaf) != RADINTERP_OK, "a leaf past the last was given");
    for (i = 0; i < discs; i++)
        fuzz_require(radinterp_mesh_get_discontinuity(m, i, &disc) == RADINTERP_OK,
                     "a counted discontinuity was refused");
    fuzz_require(radinterp_mesh_get_discontinuity(m, discs, &disc) != RADINTERP_OK,
                 "a discontinuity past the last was given");
}

static void check_saves_what_it_loaded(const radinterp_mesh *m, const uint8_t *data, size_t size)
{
    void *saved = NULL;
    size_t saved_size = 0;
    fuzz_require(radinterp_mesh_save_to_memory(m, NULL, &saved, &saved_size) == RADINTERP_OK,
                 "a loaded mesh did not save");
    /* the loader leaves bytes after the CRC alone: the mesh is what precedes them */
    fuzz_require(saved_size <= size && fuzz_same_bytes(saved, saved_size, data, saved_size),
                 "a loaded mesh saved to other bytes");
    radinterp_free_memory(NULL, saved);
}

static fuzz_outcome load_mesh(const uint8_t *data, size_t size)
{
    radinterp_mesh *m = NULL;
    radinterp_mesh_info info;
    radinterp_mesh_data d;
    radinterp_result r = radinterp_mesh_load_from_memory(data, size, NULL, &m);
    if (r != RADINTERP_OK) {
        fuzz_require(m == NULL, "a refused mesh was returned");
        return outcome_of(r);
    }
    radinterp_mesh_get_info(m, &info);
    radinterp_mesh_get_data(m, &d);
    fuzz_require(info.triangle_count == d.triangle_count && info.vertex_count == d.vertex_count &&
                     info.leaf_count == radinterp_mesh_leaf_count(m) &&
                     info.kept_discontinuities == radinterp_mesh_discontinuity_count(m) &&
                     info.discontinuities >= info.kept_discontinuities,
                 "the info of a loaded mesh disagrees with its data");
    check_data(m, &d);
    shade_triangles(m, d.triangle_count);
    check_leaves_and_discontinuities(m);
    check_saves_what_it_loaded(m, data, size);
    radinterp_mesh_destroy(m);
    return FUZZ_LOADED;
}

const fuzz_target fuzz_this_target = { "radinterp", load_mesh, 1, NULL };   /* load checks that it saves the same bytes */
