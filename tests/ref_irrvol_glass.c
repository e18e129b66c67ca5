/* irrvol.h's glass and sky against the Embree reference (tests/reference,
   which passes light through thin glass and sees the sky): a closed room
   with a window in the ceiling under a sky of radiance L, walls of a known
   radiance (in the reference: emitters with no reflectance, so the field is
   the same), single and double glazing, the panes facing in or out. The
   volume's own samples on the floor under the window are compared bin by
   bin (the irradiance of a surface facing the bin's direction) with the
   reference's irradiance at the sample, so that what is measured is the
   gather, not the interpolation between samples. */
#define IRRVOL_IMPLEMENTATION
#include "irrvol.h"
#include "tests/glass_room.h"
#include "tests/reference/ref.h"
#include "tests/test.h"

static const float sky_radiance[3] = { 1.0f, 2.0f, 3.0f };
static const float wall_radiance[3] = { 0.05f, 0.1f, 0.15f };
static const float pane_tf[3] = { 0.8f, 0.6f, 0.4f };
static const float inner_tf[3] = { 0.9f, 0.9f, 0.5f };

static ref_scene *reference_room(const glass_room *room, const ex_sky *sky)
{
    ref_material m[GLASS_ROOM_MATERIALS];
    ref_scene *s;
    memset(m, 0, sizeof m);
    memcpy(m[GLASS_ROOM_WALL].ke, wall_radiance, sizeof wall_radiance);
    memcpy(m[GLASS_ROOM_PANE].tf, pane_tf, sizeof pane_tf);
    memcpy(m[GLASS_ROOM_INNER_PANE].tf, inner_tf, sizeof inner_tf);
    s = ref_scene_create(room->positions, room->vertex_count, room->indices, room->triangle_count, room->materials,
                         m, GLASS_ROOM_MATERIALS);
    if (s && ref_scene_set_sky(s, sky) != 0) {
        ref_scene_destroy(s);
        return NULL;
    }
    return s;
}

/* The volume: a 3 x 3 x 3 grid over [-0.8,0.8] x [0.1,1.7] x [-0.8,0.8], so
   that samples stand 0.1 above the floor under the window's centre
   (sample 4) and off it; no second level (the samples measured are the
   first level's). */
static irrvol *build_volume(const glass_room *room, const float *environment, uint32_t width, uint32_t height)
{
    irrvol_material m[GLASS_ROOM_MATERIALS];
    irrvol_desc d;
    irrvol *vol = NULL;
    memset(m, 0, sizeof m);
    memset(&d, 0, sizeof d);
    memcpy(m[GLASS_ROOM_WALL].radiance, wall_radiance, sizeof wall_radiance);
    memcpy(m[GLASS_ROOM_PANE].transmittance, pane_tf, sizeof pane_tf);
    memcpy(m[GLASS_ROOM_INNER_PANE].transmittance, inner_tf, sizeof inner_tf);
    d.positions = room->positions;
    d.vertex_count = room->vertex_count;
    d.indices = room->indices;
    d.triangle_count = room->triangle_count;
    d.triangle_materials = room->materials;
    d.materials = m;
    d.material_count = GLASS_ROOM_MATERIALS;
    d.grid_samples[0] = d.grid_samples[1] = d.grid_samples[2] = 3;
    d.subgrid_samples = 2;
    d.bounds_min[0] = -0.8f; d.bounds_min[1] = 0.1f; d.bounds_min[2] = -0.8f;
    d.bounds_max[0] = 0.8f; d.bounds_max[1] = 1.7f; d.bounds_max[2] = 0.8f;
    d.supersamples = 8;   /* 64 rays a bin: the window's edges cut bins */
    memcpy(d.background, sky_radiance, sizeof sky_radiance);
    d.environment = environment;
    d.environment_width = width;
    d.environment_height = height;
    d.seed = 5;
    if (irrvol_build(&d, &vol) != IRRVOL_OK) return NULL;
    return vol;
}

/* Every bin of sample s facing up (y > 0.7) against the reference at the
   sample's origin; returns the largest error in units of the tolerance. */
static double compare_sample(const irrvol *vol, uint32_t s, const ref_scene *ref, const char *label)
{
    irrvol_volume_info info;
    irrvol_sample_info si;
    float *values;
    uint32_t bin, compared = 0;
    double worst = 0.0, worst_rel = 0.0, worst_se = 0.0;
    if (!CHECK(irrvol_info(vol, &info) == IRRVOL_OK && irrvol_sample(vol, s, &si) == IRRVOL_OK)) return 1e9;
    CHECK_EQ_INT(si.state, IRRVOL_SAMPLE_VALID);   /* a pane's back is not the inside of a solid */
    values = (float *)malloc(3 * (size_t)info.bins * sizeof(float));
    if (!CHECK(values && irrvol_sample_values(vol, s, values, NULL) == IRRVOL_OK)) { free(values); return 1e9; }
    for (bin = 0; bin < info.bins; bin++) {
        float dir[3], queried[3];
        ref_estimate e;
        int k;
        irrvol_bin_direction(vol, bin, dir);
        if (dir[1] <= 0.7f) continue;
        /* at the sample itself, the query returns the sample's bin */
        irrvol_query_filter(vol, IRRVOL_FILTER_NEAREST, IRRVOL_WEIGHTING_DEFAULT, si.position, dir, queried);
        e = ref_irradiance_gi(ref, si.origin, dir, 100000, 1000 + bin);
        for (k = 0; k < 3; k++) {
            double got = values[3 * bin + k], want = e.mean[k];
            /* 2 % for the bins' discretisation (radiance constant across a
               bin that a window edge cuts), 3 standard errors for the
               reference's noise */
            double tol = 0.02 * want + 3.0 * e.std_error[k], err = fabs(got - want) / tol;
            CHECK_CLOSE(queried[k], got, 1e-5, 0);
            CHECK_CLOSE(got, want, 0.02, 3.0 * e.std_error[k]);
            if (err > worst) {
                worst = err;
                worst_rel = (got - want) / want;
                worst_se = e.std_error[k] / want;
            }
        }
        compared++;
    }
    test_note("%s, sample %u: %u bins, worst %+.2f%% (reference standard error %.2f%%), %.2f of the tolerance", label,
              s, compared, 100.0 * worst_rel, 100.0 * worst_se, worst);
    free(values);
    return worst;
}

/* Single and double glazing, the panes facing in and out, a constant sky. */
static void test_window_under_constant_sky(void)
{
    int up, glazing;
    ex_sky sky;
    memset(&sky, 0, sizeof sky);
    memcpy(sky.radiance, sky_radiance, sizeof sky_radiance);
    for (glazing = 0; glazing < 2; glazing++)
        for (up = 0; up < 2; up++) {
            glass_room room;
            ref_scene *ref;
            irrvol *vol;
            char label[64];
            glass_room_make(&room, up, glazing);
            ref = reference_room(&room, &sky);
            vol = build_volume(&room, NULL, 0, 0);
            if (CHECK(ref && vol)) {
                snprintf(label, sizeof label, "%s glazing, panes facing %s", glazing ? "double" : "single",
                         up ? "out" : "in");
                compare_sample(vol, 4, ref, label);          /* under the window's centre */
                if (!glazing && !up) compare_sample(vol, 8, ref, label);   /* (0.8, 0.1, 0.8): off it */
            }
            irrvol_destroy(vol);
            ref_scene_destroy(ref);
        }
}

/* An environment map (8 x 4 texels, a brighter zenith row and a blue
   column) seen through the window: the map's parameterisation agrees with
   the reference's (examples/common/scene_sky.h). */
static void test_window_under_environment_map(void)
{
    float map[8 * 4 * 3];
    glass_room room;
    ref_scene *ref;
    irrvol *vol;
    ex_sky sky;
    glass_room_map(map);
    memset(&sky, 0, sizeof sky);
    sky.map = map;
    sky.width = 8;
    sky.height = 4;
    glass_room_make(&room, 0, 0);
    ref = reference_room(&room, &sky);
    vol = build_volume(&room, map, 8, 4);
    if (CHECK(ref && vol)) compare_sample(vol, 4, ref, "environment map");
    irrvol_destroy(vol);
    ref_scene_destroy(ref);
}

int main(int argc, char **argv)
{
    TEST_INIT(argc, argv);
    RUN(test_window_under_constant_sky);
    RUN(test_window_under_environment_map);
    return test_finish();
}
