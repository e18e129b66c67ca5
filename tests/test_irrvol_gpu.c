/* irrvol.h on the GPU: the flat arrays of irrvol_gpu_export and the GLSL
   evaluator of irrvol_glsl_source. The evaluator is written in the subset
   of GLSL that C shares; the header keeps it as macros, stringified for
   irrvol_glsl_source and expanded here as C, so this test runs the very
   text a shader compiles on the exported arrays and compares it with
   irrvol_query_sh. When glslangValidator (Debian: glslang-tools, installed
   by tests/deps.sh) is on the PATH the GLSL is also compiled, in a compute
   shader. The header's portable (IRRVOL_NO_SIMD) code runs here; the SSE2
   code computes the same bits (tests/test_irrvol_levels.c). Run from the
   repository root (it writes build/tests/). */
#define IRRVOL_NO_SIMD   /* the portable code here; the other tests run the SSE2 code where there is one */
#define IRRVOL_IMPLEMENTATION
#include "irrvol.h"
#include "tests/test.h"
#include "tests/test_irrvol_scenes.h"
#include "examples/common/pool.h"

#define PI SC_PI

/* ---- the GLSL text as C ----------------------------------------------------- */

typedef uint32_t glsl_uint;
static const uint32_t *gpu_index;   /* the two arrays the shader reads */
static const float *gpu_data;
#define IRRVOL_INDEX(i) gpu_index[i]
#define IRRVOL_DATA(i) gpu_data[i]
#define IRRVOL_U(x) ((glsl_uint)(x))
#define IRRVOL_I(x) ((int)(x))
#define IRRVOL_F(x) ((float)(x))
#define IRRVOL_ABS(x) fabsf(x)
#define IRRVOL_SQRT(x) sqrtf(x)
#define IRRVOL_MIN(a, b) ((a) < (b) ? (a) : (b))   /* as the GLSL prelude defines them */
#define IRRVOL_MAX(a, b) ((a) > (b) ? (a) : (b))
typedef struct IrrvolRGB IrrvolRGB;
#define GLSL_AS_C(...) __VA_ARGS__
#define uint glsl_uint
IRRVOL__GLSL_PART1(GLSL_AS_C)
IRRVOL__GLSL_PART2(GLSL_AS_C)
IRRVOL__GLSL_PART3(GLSL_AS_C)
#undef uint

/* ---- a scene with everything the evaluator must handle ------------------------- */

static uint32_t rng_state = 777u;
static float frand(void) { return sc_frand(&rng_state); }

/* Two rooms behind a 2 cm wall, samples in the wall (relocated), a closed
   box around a sample (invalid), a lamp (refinement by geometry and by
   light, hanging samples). */
static irrvol *level_volume(ex_pool *pool)
{
    static sc_scene s;
    static irrvol_material m[3];
    float lo[3], hi[3];
    irrvol_desc d;
    irrvol *v = NULL;
    memset(&s, 0, sizeof s);
    sc_set3(lo, -4.0f, 0.0f, 0.0f); sc_set3(hi, -0.01f, 3.0f, 4.0f);
    sc_box(&s, lo, hi, 0, 1);
    sc_set3(lo, 0.01f, 0.0f, 0.0f); sc_set3(hi, 4.0f, 3.0f, 4.0f);
    sc_box(&s, lo, hi, 1, 1);
    sc_set3(lo, -2.25f, 0.7f, 1.75f); sc_set3(hi, -1.75f, 1.3f, 2.25f);   /* around the sample (-2, 1, 2) */
    sc_box(&s, lo, hi, 1, 0);
    sc_set3(lo, 2.2f, 2.2f, 1.0f); sc_set3(hi, 2.5f, 2.4f, 1.3f);
    sc_box(&s, lo, hi, 2, 0);
    memset(m, 0, sizeof m);
    sc_set3(m[0].radiance, 0.5f, 0.45f, 0.4f);
    sc_set3(m[1].radiance, 0.1f, 0.12f, 0.15f);
    sc_set3(m[2].radiance, 30.0f, 25.0f, 20.0f);
    m[2].flags = IRRVOL_MATERIAL_IMPORTANT;
    sc_scene_desc(&d, &s, m, 3);
    d.resolution = 9;
    d.grid_samples[0] = 7; d.grid_samples[1] = 5; d.grid_samples[2] = 3;
    sc_set3(d.bounds_min, -3.0f, 0.5f, 1.0f);
    sc_set3(d.bounds_max, 3.0f, 2.5f, 3.0f);   /* samples at x = 0 (in the wall) and at (-2, 1, 2) */
    d.refine_threshold = 0.02f;
    d.parallel_for = ex_pool_parallel_for;
    d.parallel_user = pool;
    if (irrvol_build(&d, &v) != IRRVOL_OK) return NULL;
    return v;
}

static void export_volume(const irrvol *v, uint32_t order, irrvol_gpu_layout *l, uint32_t **index, float **data)
{
    *index = NULL;
    *data = NULL;
    if (irrvol_gpu_export(v, order, l, NULL, 0, NULL, 0) != IRRVOL_OK) return;
    *index = (uint32_t *)malloc(l->index_count * sizeof(uint32_t));
    *data = (float *)malloc(l->data_count * sizeof(float));
    if (irrvol_gpu_export(v, order, l, *index, l->index_count, *data, l->data_count) != IRRVOL_OK) {
        free(*index);
        free(*data);
        *index = NULL;
        *data = NULL;
    }
}

static void test_glsl_equals_c_query(void)
{
    ex_pool *pool = ex_pool_create(0);
    irrvol *v = level_volume(pool);
    irrvol_volume_info info;
    uint32_t order;
    if (!CHECK(v != NULL)) { ex_pool_destroy(pool); return; }
    irrvol_info(v, &info);
    test_note("level for the GPU: %u samples (%u hanging, %u relocated, %u invalid), %u cells refined (%u for light)",
              info.sample_count, info.hanging_samples, info.relocated_samples, info.invalid_samples,
              info.refined_cells, info.light_refined_cells);
    CHECK(info.hanging_samples > 0 && info.relocated_samples > 0 && info.invalid_samples > 0);
    for (order = 1; order <= 2; order++) {
        irrvol_gpu_layout l;
        uint32_t *index;
        float *data;
        double worst = 0.0, lit = 0.0;
        int i, k, exact = 0;
        export_volume(v, order, &l, &index, &data);
        if (!CHECK(index && data)) break;
        gpu_index = index;
        gpu_data = data;
        rng_state = 5u + order;
        for (i = 0; i < 1000; i++) {
            float p[3], n[3], c[3], len;
            IrrvolRGB e;
            /* anywhere in the grid and a little past it, any direction */
            sc_set3(p, 6.4f * frand() - 3.2f, 2.4f * frand() + 0.3f, 2.4f * frand() + 0.8f);
            sc_set3(n, frand() - 0.5f, frand() - 0.5f, frand() - 0.5f);
            len = sqrtf(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
            for (k = 0; k < 3; k++) n[k] /= len;
            irrvol_query_sh(v, order, IRRVOL_WEIGHTING_VISIBILITY, p, n, c);
            e = irrvol_irradiance_sh(p[0], p[1], p[2], n[0], n[1], n[2]);
            exact += c[0] == e.r && c[1] == e.g && c[2] == e.b;
            lit += c[0];
            {
                double g[3] = {e.r, e.g, e.b};
                for (k = 0; k < 3; k++) {
                    double scale = fabs(c[k]) > 1e-3 ? fabs(c[k]) : 1e-3;
                    if (fabs(g[k] - c[k]) / scale > worst) worst = fabs(g[k] - c[k]) / scale;
                }
            }
        }
        test_note("GLSL evaluator (compiled as C) vs irrvol_query_sh, L%u, 1000 random points: largest relative "
                  "difference %.2g, %d bit for bit (index %zu + data %zu floats)", order, worst, exact,
                  l.index_count, l.data_count);
        CHECK(worst <= 1e-4);   /* the acceptance bound */
        CHECK(lit > 10.0);      /* the points see light: the comparison is not of zeros */
        free(index);
        free(data);
    }
    irrvol_destroy(v);
    ex_pool_destroy(pool);
}

static void test_export_layout_and_bad_arguments(void)
{
    ex_pool *pool = ex_pool_create(0);
    irrvol *v = level_volume(pool);
    irrvol_volume_info info;
    irrvol_gpu_layout l;
    uint32_t *index;
    float *data;
    if (!CHECK(v != NULL)) { ex_pool_destroy(pool); return; }
    irrvol_info(v, &info);
    CHECK_EQ_INT(irrvol_gpu_export(NULL, 2, &l, NULL, 0, NULL, 0), IRRVOL_ERROR_INVALID_ARGUMENT);
    CHECK_EQ_INT(irrvol_gpu_export(v, 2, NULL, NULL, 0, NULL, 0), IRRVOL_ERROR_INVALID_ARGUMENT);
    CHECK_EQ_INT(irrvol_gpu_export(v, 0, &l, NULL, 0, NULL, 0), IRRVOL_ERROR_INVALID_ARGUMENT);
    CHECK_EQ_INT(irrvol_gpu_export(v, 3, &l, NULL, 0, NULL, 0), IRRVOL_ERROR_INVALID_ARGUMENT);
    CHECK_EQ_INT(irrvol_gpu_export(v, 2, &l, NULL, 0, NULL, 0), IRRVOL_OK);   /* sizes only */
    CHECK_EQ_INT(l.coefficients, 9);
    CHECK_EQ_INT(l.cells_at, 16);
    CHECK_EQ_INT(l.ids_at, 16 + 2 * info.cell_count);
    CHECK_EQ_INT(l.index_count, l.parents_at + 4 * info.hanging_samples);
    CHECK_EQ_INT(l.visibility_at, 16 + 4 * info.sample_count);
    CHECK_EQ_INT(l.sh_at, l.visibility_at + 4 * (info.sample_count - info.hanging_samples) *
                          (info.visibility_resolution + 2) * (info.visibility_resolution + 2));   /* bordered maps */
    CHECK_EQ_INT(l.data_count, l.parent_weights_at + 4 * info.hanging_samples);
    index = (uint32_t *)malloc(l.index_count * sizeof(uint32_t));
    data = (float *)malloc(l.data_count * sizeof(float));
    CHECK_EQ_INT(irrvol_gpu_export(v, 2, &l, index, l.index_count - 1, data, l.data_count), IRRVOL_ERROR_INVALID_ARGUMENT);
    CHECK_EQ_INT(irrvol_gpu_export(v, 2, &l, index, l.index_count, data, l.data_count - 1), IRRVOL_ERROR_INVALID_ARGUMENT);
    CHECK_EQ_INT(irrvol_gpu_export(v, 2, &l, index, l.index_count, NULL, 0), IRRVOL_ERROR_INVALID_ARGUMENT);
    CHECK_EQ_INT(irrvol_gpu_export(v, 2, &l, NULL, 0, data, l.data_count), IRRVOL_ERROR_INVALID_ARGUMENT);
    CHECK_EQ_INT(irrvol_gpu_export(v, 2, &l, index, l.index_count, data, l.data_count), IRRVOL_OK);
    CHECK_EQ_INT(index[0], 1);                       /* the layout's version */
    CHECK_EQ_INT(index[4], info.sample_count);
    CHECK_EQ_INT(index[5], info.sample_count - info.hanging_samples);
    {   /* the first-level samples' harmonics come first, a dense x-fastest 3D array */
        uint32_t s = 1 + 7 * (1 + 5 * 1);   /* (1, 1, 1): the sample at (-2, 1, 2), in the box */
        irrvol_sample_info si;
        irrvol_sample(v, s, &si);
        CHECK(si.position[0] == -2.0f && si.position[1] == 1.0f && si.position[2] == 2.0f);
        CHECK_EQ_INT(si.state, IRRVOL_SAMPLE_INVALID);
        CHECK(data[l.origins_at + 4 * s + 3] == 0.0f);   /* flagged invalid for the shader */
        CHECK(data[l.origins_at + 4 * (s + 1) + 3] == 1.0f);
    }
    free(index);
    free(data);
    irrvol_destroy(v);
    ex_pool_destroy(pool);
}

/* The GLSL source: length, truncation, and (with glslangValidator) a compile. */
static void test_glsl_source_compiles(void)
{
    size_t n = irrvol_glsl_source(NULL, 0), m;
    char *text = (char *)malloc(n + 1), small[16], comp[512], log[512], cmd[1200];
    FILE *f;
    if (!CHECK(n > 1000 && text)) { free(text); return; }
    CHECK_EQ_INT(irrvol_glsl_source(text, n + 1), n);
    CHECK(text[n] == '\0' && strlen(text) == n);
    CHECK(strstr(text, "irrvol_irradiance_sh") != NULL && strstr(text, "vec3 irrvol_irradiance(") != NULL);
    {   /* one statement a line, indented: a shader compiler's messages point somewhere */
        size_t lines = 0, k;
        for (k = 0; k < n; k++) lines += text[k] == '\n';
        CHECK(lines > 150 && strstr(text, "\n        float den = ") != NULL);
    }
    m = irrvol_glsl_source(small, sizeof small);
    CHECK(m == n && small[15] == '\0' && memcmp(small, text, 15) == 0);   /* truncated, terminated */
    CHECK_EQ_INT(irrvol_glsl_source(small, 0), n);
    if (system("glslangValidator --version > /dev/null 2>&1") != 0) {
        test_note("glslangValidator not found (Debian: glslang-tools): the GLSL is checked as C only");
        free(text);
        return;
    }
    f = fopen(test_scratch_path(comp, sizeof comp, "eval.comp"), "w");
    if (!CHECK(f != NULL)) { free(text); return; }
    fprintf(f, "#version 430\n%s\n", text);
    fprintf(f, "layout(local_size_x = 64) in;\n"
               "layout(std430, binding = 2) readonly buffer Queries { vec4 queries[]; };\n"
               "layout(std430, binding = 3) writeonly buffer Results { vec4 results[]; };\n"
               "void main()\n{\n    uint i = gl_GlobalInvocationID.x;\n"
               "    results[i] = vec4(irrvol_irradiance(queries[2u * i].xyz, queries[2u * i + 1u].xyz), 1.0);\n}\n");
    fclose(f);
    {
        int status;
        snprintf(cmd, sizeof cmd, "glslangValidator -S comp '%s' > '%s' 2>&1", comp,
                 test_scratch_path(log, sizeof log, "eval.log"));
        status = system(cmd);
        test_note("glslangValidator -S comp %s: %s%s%s", comp, status == 0 ? "compiled" : "FAILED (see ",
                  status == 0 ? "" : log, status == 0 ? "" : ")");
        CHECK_EQ_INT(status, 0);
    }
    free(text);
}

int main(int argc, char **argv)
{
    TEST_INIT(argc, argv);
    RUN(test_glsl_equals_c_query);
    RUN(test_export_layout_and_bad_arguments);
    RUN(test_glsl_source_compiles);
    return test_finish();
}
