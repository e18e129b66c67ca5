/* Fuzz target of irrvol_load (see tests/fuzz/fuzz.h): loads the bytes as an
   irradiance volume; a volume that loads must answer every query without a
   sanitizer report, map each bin's centre direction back to that bin, and
   save to exactly the bytes it was loaded from (the format has one encoding
   of a volume: every field is stored as read). */
#define IRRVOL_IMPLEMENTATION
#include "irrvol.h"
#include "tests/fuzz/fuzz.h"

static fuzz_outcome outcome_of(irrvol_result r)
{
    switch (r) {
    case IRRVOL_OK: return FUZZ_LOADED;
    case IRRVOL_ERROR_CORRUPT_DATA: return FUZZ_CORRUPT;
    case IRRVOL_ERROR_VERSION: return FUZZ_VERSION;
    default: return FUZZ_OTHER;
    }
}

/* Positions at the corners, the centre and the middles of the faces of the
   bounds, and as far again outside them (queries clamp to the bounds). */
static void query_point(const irrvol_volume_info *info, int i, float p[3])
{
    static const float at[4] = { -1.0f, 0.0f, 0.5f, 1.0f };   /* fraction of the extent: -1 is outside */
    int k, digit = i;
    for (k = 0; k < 3; k++, digit /= 4) {
        float lo = info->bounds_min[k], ext = info->bounds_max[k] - lo;
        p[k] = lo + at[digit % 4] * ext;
        if (!isfinite(p[k])) p[k] = lo;   /* bounds near FLT_MAX: stay finite */
    }
}

/* The GPU arrays of a loaded volume: the sizes first, then the arrays,
   which must fill exactly the sizes it gave; one entry too few is refused. */
static void export_to_gpu(const irrvol *v)
{
    irrvol_gpu_layout l;
    uint32_t *index;
    float *data;
    if (irrvol_gpu_export(v, 2, &l, NULL, 0, NULL, 0) != IRRVOL_OK) return;
    index = (uint32_t *)malloc((l.index_count ? l.index_count : 1) * sizeof *index);
    data = (float *)malloc((l.data_count ? l.data_count : 1) * sizeof *data);
    if (index && data) {
        fuzz_require(irrvol_gpu_export(v, 2, &l, index, l.index_count, data, l.data_count) == IRRVOL_OK,
                     "irrvol_gpu_export refused the sizes it gave");
        if (l.data_count)
            fuzz_require(irrvol_gpu_export(v, 2, &l, index, l.index_count, data, l.data_count - 1) != IRRVOL_OK,
                         "irrvol_gpu_export accepted a data array one float short");
    }
    free(index);
    free(data);
}

static void use_volume(const irrvol *v, const irrvol_volume_info *info)
{
    static const float dirs[8][3] = { { 1, 0, 0 }, { -1, 0, 0 }, { 0, 1, 0 }, { 0, -1, 0 },
                                      { 0, 0, 1 }, { 0, 0, -1 }, { 0.6f, 0.0f, 0.8f }, { 0, 0, 0 } };
    float pos[64][3], dir[64][3], many[64][3], rgb[3], d[3];
    uint32_t last = info->sample_count - 1, b;
    irrvol_sample_info si;
    float *values;
    int i;
    for (i = 0; i < 64; i++) {
        query_point(info, i, pos[i]);
        memcpy(dir[i], dirs[i % 8], sizeof dir[i]);
        irrvol_query(v, pos[i], dir[i], rgb);
        irrvol_query_filter(v, IRRVOL_FILTER_NEAREST, IRRVOL_WEIGHTING_TRILINEAR, pos[i], dir[i], rgb);
        irrvol_query_filter(v, IRRVOL_FILTER_BILINEAR, IRRVOL_WEIGHTING_VISIBILITY, pos[i], dir[i], rgb);
        irrvol_query_glossy(v, pos[i], dir[i], dirs[(i + 3) % 8], rgb);
        irrvol_query_sh(v, 1 + (uint32_t)(i & 1), IRRVOL_WEIGHTING_DEFAULT, pos[i], dir[i], rgb);
    }
    irrvol_query_many(v, IRRVOL_FILTER_BILINEAR, IRRVOL_WEIGHTING_DEFAULT, 64, &pos[0][0], 0, &dir[0][0], 0,
                      &many[0][0]);
    export_to_gpu(v);
    fuzz_require(irrvol_sample(v, 0, &si) == IRRVOL_OK && irrvol_sample(v, last, &si) == IRRVOL_OK,
                 "irrvol_sample refused a sample the volume has");
    fuzz_require(irrvol_sample(v, info->sample_count, &si) == IRRVOL_ERROR_INVALID_ARGUMENT,
                 "irrvol_sample accepted an index past the last sample");
    values = (float *)malloc((size_t)info->bins * 6 * sizeof(float));
    if (values) {
        fuzz_require(irrvol_sample_values(v, last, values, info->has_radiance ? values + 3 * (size_t)info->bins : NULL) ==
                         IRRVOL_OK,
                     "irrvol_sample_values refused the last sample");
        free(values);
    }
    for (b = 0; b < info->bins; b++) {
        irrvol_bin_direction(v, b, d);
        fuzz_require(irrvol_direction_bin(v, d) == b, "a bin's centre direction maps to another bin");
    }
}

static void check_saves_what_it_loaded(const irrvol *v, const uint8_t *data, size_t size)
{
    void *saved = NULL;
    size_t saved_size = 0;
    fuzz_require(irrvol_save_to_memory(v, NULL, &saved, &saved_size) == IRRVOL_OK, "a loaded volume did not save");
    /* the loader leaves bytes after the CRC alone: the volume is what precedes them */
    fuzz_require(saved_size <= size && fuzz_same_bytes(saved, saved_size, data, saved_size),
                 "a loaded volume saved to other bytes");
    irrvol_free_memory(NULL, saved);
}

static fuzz_outcome load_volume(const uint8_t *data, size_t size)
{
    irrvol *v = NULL;
    irrvol_volume_info info;
    irrvol_result r = irrvol_load_from_memory(data, size, NULL, &v);
    if (r != IRRVOL_OK) {
        fuzz_require(v == NULL, "a refused volume was returned");
        return outcome_of(r);
    }
    fuzz_require(irrvol_info(v, &info) == IRRVOL_OK && info.sample_count > 0 &&
                     info.bins == 2 * info.resolution * info.resolution,
                 "irrvol_info of a loaded volume");
    use_volume(v, &info);
    check_saves_what_it_loaded(v, data, size);
    irrvol_destroy(v);
    return FUZZ_LOADED;
}

const fuzz_target fuzz_this_target = { "irrvol", load_volume, 1, NULL };   /* load checks that it saves the same bytes */
