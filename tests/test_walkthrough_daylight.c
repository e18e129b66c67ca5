/* Tests of the walkthrough by day (examples/data/building_1k_daylight.*,
   `--scene daylight`: glass in every window facing out, lamps off, a
   ground, a constant overcast sky named by the layout's sky line): the
   layout reader's sky lines, camera rays through the panes, daylight
   reaching the rooms only through the glass (nothing with the panes made
   opaque), the raytrace mode's frames against converged renders, mode
   radiosity lighting a room through a glass pane in its ceiling, and the
   bunny's contact shadow on the floor (by day, its only shadow). */
#define _POSIX_C_SOURCE 200809L
#include "examples/common/walkthrough.h"
#include "tests/test.h"
#include "tests/walkthrough_test.h"

#define DAY_W 48
#define DAY_H 36

static wt_options day_options(wt_mode mode, const char *scene)
{
    return quiet_options(mode, scene, DAY_W, DAY_H, 12);
}

/* ---- the sky line ------------------------------------------------------------ */

#define ROOM_LINE "room 0 0 0 0 1 0 2.8 0 1 panel 0\n"

/* Loads a layout of one room and the given sky line(s); 0 or -1. */
static int load_sky(const char *dir, const char *sky, wt_layout *l, char *err, size_t err_size)
{
    char path[512], text[512];
    snprintf(path, sizeof path, "%s/s.layout", dir);
    snprintf(text, sizeof text, "%s%s", ROOM_LINE, sky);
    if (!write_file(path, text)) return -2;
    err[0] = 0;
    return wt_layout_load(path, l, err, err_size);
}

static void test_sky_lines(void)
{
    static const float map[4 * 2 * 3] = {   /* 4 x 2 texels, rows from the zenith down */
        1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 0.5f, 0.25f, 0, 0, 0, 0, 1, 1, 1, 2, 2, 2
    };
    float negative[4 * 2 * 3];
    static const char *bad[] = {
        "sky 1 2\n",                          /* a channel short */
        "sky -1 1 1\n",                       /* negative */
        "sky nan 1 1\n",                      /* not finite */
        "sky 1 inf 1\n",
        "sky 1 1 1 missing.pfm\n",            /* no such map */
        "sky 1 1 1 s.pfm extra\n",            /* a field too many */
        "sky 1 1 1\nsky 2 2 2\n",             /* two skies */
        "sky 1 1 1 neg.pfm\n",                /* a negative texel */
        "sky 1 1 1 short.pfm\n",              /* truncated */
        "sky 1 1 1 s.layout\n"                /* not a PFM */
    };
    wt_layout l;
    char dir[256], path[512], err[512];
    size_t i;
    int k;
    if (!CHECK(make_temp_dir(dir, sizeof dir))) return;
    snprintf(path, sizeof path, "%s/s.pfm", dir);
    CHECK(ex_write_pfm(path, 4, 2, map) == 0);
    memcpy(negative, map, sizeof map);
    negative[7] = -1.0f;
    snprintf(path, sizeof path, "%s/neg.pfm", dir);
    CHECK(ex_write_pfm(path, 4, 2, negative) == 0);
    snprintf(path, sizeof path, "%s/short.pfm", dir);
    CHECK(write_file(path, "PF\n4 2\n-1.0\n0123456789"));

    /* the daylight building's own line */
    if (CHECK(wt_layout_load("examples/data/building_1k_daylight.layout", &l, err, sizeof err) == 0)) {
        CHECK(l.has_sky && l.sky.map == NULL && l.sky.radiance[0] == 4.0f && l.sky.radiance[1] == 4.3f &&
              l.sky.radiance[2] == 5.0f && l.window_count > 0);
        wt_layout_free(&l);
    }
    /* no sky line: no sky */
    if (CHECK(load_sky(dir, "", &l, err, sizeof err) == 0)) {
        CHECK(!l.has_sky && l.sky_map == NULL);
        wt_layout_free(&l);
    }
    /* a black sky is a sky (of nothing) */
    if (CHECK(load_sky(dir, "sky 0 0 0\n", &l, err, sizeof err) == 0)) {
        CHECK(l.has_sky && l.sky.radiance[0] == 0.0f);
        wt_layout_free(&l);
    }
    /* a map beside the layout, times R G B */
    if (CHECK_MSG(load_sky(dir, "sky 2 1 0.5 s.pfm\n", &l, err, sizeof err) == 0, "%s", err)) {
        CHECK(l.has_sky && l.sky.map == l.sky_map && l.sky.width == 4 && l.sky.height == 2);
        for (k = 0; k < 24; k++)
            CHECK_MSG(l.sky_map[k] == map[k] * (k % 3 == 0 ? 2.0f : k % 3 == 1 ? 1.0f : 0.5f), "texel value %d", k);
        CHECK(strstr(l.sky_map_path, dir) == l.sky_map_path);
        wt_layout_free(&l);
    }
    for (i = 0; i < sizeof bad / sizeof *bad; i++) {
        int r = load_sky(dir, bad[i], &l, err, sizeof err);
        CHECK_MSG(r == -1 && strstr(err, "s.layout:") != NULL && l.rooms == NULL && l.sky_map == NULL && !l.has_sky,
                  "'%s' gave %d, '%s'", bad[i], r, err);
        test_note("%-28.*s -> %s", (int)strcspn(bad[i], "\n"), bad[i], err + strlen(dir) + 1);
    }
    remove_dir(dir);
}

/* ---- glass -------------------------------------------------------------------- */

/* Appends to the OBJ at path a door leaf in the middle of every entrance
   of the layout (a door with no room on one side), both faces (surfaces
   are one-sided): the building closed but for its windows. Returns the
   number of entrances closed, or -1. */
static int close_entrances(const char *obj, const wt_layout *l)
{
    FILE *f = fopen(obj, "a");
    uint32_t i;
    int closed = 0, k;
    if (!f) return -1;
    for (i = 0; i < l->door_count; i++) {
        const wt_box *b = &l->doors[i];
        int thin = b->hi[0] - b->lo[0] < b->hi[2] - b->lo[2] ? 0 : 2, across = 2 - thin;
        float c[3], p[3], q[3], mid;
        for (k = 0; k < 3; k++) c[k] = 0.5f * (b->lo[k] + b->hi[k]);
        c[1] = b->lo[1] + 0.5f;
        memcpy(p, c, sizeof p);
        memcpy(q, c, sizeof q);
        p[thin] = b->lo[thin] - 0.3f;
        q[thin] = b->hi[thin] + 0.3f;
        if (wt_layout_room_at(l, p) >= 0 && wt_layout_room_at(l, q) >= 0) continue;   /* between two rooms */
        mid = 0.5f * (b->lo[thin] + b->hi[thin]);
        for (k = 0; k < 4; k++) {   /* the leaf's corners, in the door's plane */
            float v[3];
            v[thin] = mid;
            v[1] = k < 2 ? b->lo[1] : b->hi[1];
            v[across] = k == 0 || k == 3 ? b->lo[across] : b->hi[across];
            fprintf(f, "v %.6f %.6f %.6f\n", v[0], v[1], v[2]);
        }
        fprintf(f, "o entrance_leaf\nusemtl facade\nf -4 -3 -2\nf -4 -2 -1\nf -4 -1 -2\nf -4 -2 -3\n");
        closed++;
    }
    return fclose(f) == 0 ? closed : -1;
}

/* A copy of the daylight building in dir with the panes' transmittance
   replaced by tf ("0 0 0": opaque) and its entrances closed when asked;
   its OBJ path in obj. Returns the number of entrances closed, or -1. */
static int daylight_copy(const char *dir, const char *tf, int close, char *obj, size_t size)
{
    char cmd[1400], err[512];
    wt_layout l;
    int closed = 0;
    snprintf(cmd, sizeof cmd,
             "cp examples/data/building_1k_daylight.obj examples/data/building_1k_daylight.layout '%s'/ && "
             "sed 's/^Tf .*/Tf %s/' examples/data/building_1k_daylight.mtl > '%s'/building_1k_daylight.mtl",
             dir, tf, dir);
    snprintf(obj, size, "%s/building_1k_daylight.obj", dir);
    if (system(cmd) != 0) return -1;
    if (!close) return 0;
    if (wt_layout_load("examples/data/building_1k_daylight.layout", &l, err, sizeof err) != 0) return -1;
    closed = close_entrances(obj, &l);
    wt_layout_free(&l);
    return closed;
}

/* A ray from inside the building through the middle of the layout's
   first window ("window 0 6.36 7.6 0.9 2.2 -0.1 0.1": a pane at z = 0 in
   the wall facing -z), 17 degrees upward: past the pane it leaves the
   building and sees the sky. */
static void window_ray(float org[3], float dir[3])
{
    float l = sqrtf(0.3f * 0.3f + 1.0f);
    org[0] = 0.5f * (6.36f + 7.6f);
    org[1] = 0.5f * (0.9f + 2.2f) - 0.3f;
    org[2] = 1.0f;
    dir[0] = 0.0f;
    dir[1] = 0.3f / l;
    dir[2] = -1.0f / l;
}

/* A camera ray through a pane sees the sky dimmed by the pane's
   transmittance, exactly; with the pane opaque it sees black. */
static void test_camera_through_glass(void)
{
    wt_options o = day_options(WT_MODE_RAYTRACE, "daylight");
    wt_world *w = NULL;
    wt_point p;
    wt_light_stats st = { 0, 0, 0, 0 };
    char err[512], dir[256], obj[512];
    static const float tf[3] = { 0.85f, 0.87f, 0.86f }, sky[3] = { 4.0f, 4.3f, 5.0f };
    int k;
    if (!CHECK_MSG(wt_world_create(&o, &w, err, sizeof err) == 0, "%s", err)) return;
    memset(&p, 0, sizeof p);
    window_ray(p.org, p.dir);
    CHECK(wt_shade_points(w, &p, 1, WT_SHADE_DIRECT, &st, NULL, NULL) == 0);
    test_note("through the window: object %u, rgb %.4f %.4f %.4f", p.object, p.rgb[0], p.rgb[1], p.rgb[2]);
    CHECK(p.object == RENDERCACHE_MISS);
    for (k = 0; k < 3; k++) CHECK_MSG(p.rgb[k] == tf[k] * sky[k], "channel %d: %.6f", k, p.rgb[k]);
    wt_world_destroy(w);
    w = NULL;
    if (!CHECK(make_temp_dir(dir, sizeof dir))) return;
    o.scene = obj;
    if (CHECK(daylight_copy(dir, "0 0 0", 0, obj, sizeof obj) == 0) &&
        CHECK_MSG(wt_world_create(&o, &w, err, sizeof err) == 0, "%s", err)) {
        memset(&p, 0, sizeof p);
        window_ray(p.org, p.dir);
        CHECK(wt_shade_points(w, &p, 1, WT_SHADE_DIRECT, &st, NULL, NULL) == 0);
        CHECK(p.object == WT_OBJECT_OFFICE && fabsf(p.pos[2]) < 1e-3f);   /* the pane, at z = 0 */
        CHECK(p.rgb[0] == 0.0f && p.rgb[1] == 0.0f && p.rgb[2] == 0.0f);
        wt_world_destroy(w);
    }
    remove_dir(dir);
}

/* Statistics of an image: mean luminance, largest luminance. */
static void image_stats(const float *rgb, int n, double *mean, double *max)
{
    int i;
    *mean = *max = 0.0;
    for (i = 0; i < n; i++) {
        double y = luminance(rgb + 3 * i);
        *mean += y / n;
        if (y > *max) *max = y;
    }
}

/* LRMS of what is displayed (clamped at the white point 1 / exposure, as
   wt_display_lrms does) over BLOCK x BLOCK pixel blocks: the light's
   distribution over the frame (which walls and rooms are lit, how much)
   without the per-pixel noise of the converged render. -1 on failure. */
#define BLOCK 6
static double block_lrms(const float *reference, const float *image, float exposure)
{
    enum { BW = DAY_W / BLOCK, BH = DAY_H / BLOCK };
    float a[3 * BW * BH], b[3 * BW * BH], white = 1.0f / exposure;
    double lrms = -1.0;
    int x, y, k;
    memset(a, 0, sizeof a);
    memset(b, 0, sizeof b);
    for (y = 0; y < BH * BLOCK; y++)
        for (x = 0; x < BW * BLOCK; x++)
            for (k = 0; k < 3; k++) {
                size_t p = 3 * ((size_t)y * DAY_W + (size_t)x) + (size_t)k, q = 3 * (size_t)(y / BLOCK * BW + x / BLOCK) + (size_t)k;
                a[q] += fminf(reference[p], white) / (BLOCK * BLOCK);
                b[q] += fminf(image[p], white) / (BLOCK * BLOCK);
            }
    return rendercache_lrms(a, b, BW, BH, &lrms) == RENDERCACHE_OK ? lrms : -1.0;
}

/* Daylight comes in: the walkthrough's shading (light vectors looked up
   and gathered, their gathers seeing the sky through the panes and the
   entrance: lightvec.h's GLASS AND SKY; lamps off, so all of it is
   indirect light) against converged renders (a gather at every pixel, no
   interpolation, no reuse), at the first frame (traced in full) and at the
   last (wt_render_full: the frames' shading without the render cache,
   whose lag behind a camera walking the whole building in 48 frames is
   not what this test is about; its frame's mean luminance is checked).
   The converged render is noisy per pixel (two of them, at 10 and 16
   strata, differ by 0.14-0.37 LRMS: daylight through small windows is
   seen by few gather rays), so the pictures are compared over 6 x 6 pixel
   blocks: the two converged renders differ by 0.02-0.07 there, the
   frames measured 0.041 and 0.035 when this test was written; the bound is
   twice the converged renders' own largest difference. The mean luminance
   within 10%: the converged render's noise is about 1% of the mean and
   interpolation errors average out over a frame; a sky that did not reach
   the gathers through the glass, or passed it without the panes'
   transmittance (0.86), would be 14% or more off. */
#define CONVERGED_STRATA 10
#define CONVERGED_LIGHT_SAMPLES 4      /* no lamps: direct light is zero */
#define DAYLIGHT_FRAMES 48
#define DAYLIGHT_MAX_BLOCK_LRMS 0.14
#define DAYLIGHT_MAX_MEAN_ERROR 0.10
static void test_daylight_frames(void)
{
    wt_options o = day_options(WT_MODE_RAYTRACE, "daylight");
    wt_world *w = NULL;
    wt_renderer *r = NULL;
    wt_frame_stats st;
    char err[512];
    const int n = DAY_W * DAY_H;
    float *rgb = (float *)malloc(sizeof(float) * 3 * n), *ref = (float *)malloc(sizeof(float) * 3 * n);
    float *full = (float *)malloc(sizeof(float) * 3 * n), e0 = 0.0f;
    int f;
    o.frames = DAYLIGHT_FRAMES;
    if (!CHECK(rgb && ref && full) ||
        !CHECK_MSG(wt_world_create(&o, &w, err, sizeof err) == 0 && wt_renderer_create(w, &r, err, sizeof err) == 0, "%s",
                   err))
        goto done;
    for (f = 0; f < o.frames; f++) {
        double t = wt_frame_time(&o, f), lrms, mean, max, full_mean, ref_mean, ref_max;
        rendercache_camera c;
        float e;
        if (!CHECK(wt_render_frame(r, f, rgb, &st) == 0)) break;
        e = wt_exposure(&o, rgb, e0);
        if (f == 0) e0 = e;
        if (f != 0 && f != o.frames - 1) continue;
        c = wt_camera(&w->opt, t, DAY_W, DAY_H);
        if (f == 0) memcpy(full, rgb, sizeof(float) * 3 * n);
        if (!CHECK(f == 0 || wt_render_full(w, &c, t, (uint32_t)f, full, NULL) == 0) ||
            !CHECK(wt_render_converged(w, &c, t, CONVERGED_STRATA, CONVERGED_LIGHT_SAMPLES, ref) == 0))
            break;
        image_stats(rgb, n, &mean, &max);
        image_stats(full, n, &full_mean, &max);
        image_stats(ref, n, &ref_mean, &ref_max);
        lrms = block_lrms(ref, full, e);
        test_note("daylight frame %d: mean luminance %.4f (full render %.4f), converged %.4f; LRMS over %dx%d blocks "
                  "%.4f (bound %.2f)", f, mean, full_mean, ref_mean, BLOCK, BLOCK, lrms, DAYLIGHT_MAX_BLOCK_LRMS);
        CHECK(ref_mean > 0.05);   /* lit: the sky is 4.3 W/(m^2 sr), the rooms get a few percent of it */
        CHECK_MSG(lrms >= 0.0 && lrms <= DAYLIGHT_MAX_BLOCK_LRMS, "frame %d: LRMS %.4f", f, lrms);
        CHECK_MSG(fabs(mean - ref_mean) <= DAYLIGHT_MAX_MEAN_ERROR * ref_mean, "frame %d: mean %.4f, converged %.4f", f,
                  mean, ref_mean);
        CHECK_MSG(fabs(full_mean - ref_mean) <= DAYLIGHT_MAX_MEAN_ERROR * ref_mean, "frame %d: full render's mean %.4f",
                  f, full_mean);
    }
done:
    wt_renderer_destroy(r);
    wt_world_destroy(w);
    free(rgb);
    free(ref);
    free(full);
}

/* With the entrance closed, daylight reaches the rooms through the glass
   only: the frames and their converged renders are lit with the panes as
   they are, and exactly black with the panes made opaque (a leak through
   a wall, a door leaf or a pane would light a pixel). */
static void test_light_only_through_glass(void)
{
    static const char *tf[2] = { "0.85 0.87 0.86", "0 0 0" };
    wt_options o = day_options(WT_MODE_RAYTRACE, NULL);
    wt_world *w = NULL;
    wt_renderer *r = NULL;
    wt_frame_stats st;
    char err[512], dir[256], obj[512];
    const int n = DAY_W * DAY_H;
    float *rgb = (float *)malloc(sizeof(float) * 3 * n), *ref = (float *)malloc(sizeof(float) * 3 * n);
    int f, pass, closed;
    if (!CHECK(rgb && ref) || !CHECK(make_temp_dir(dir, sizeof dir))) {
        free(rgb);
        free(ref);
        return;
    }
    o.scene = obj;
    for (pass = 0; pass < 2; pass++) {
        closed = daylight_copy(dir, tf[pass], 1, obj, sizeof obj);
        CHECK_MSG(closed == 1, "%d entrances closed", closed);   /* make_building.py: one entrance, on the ground floor */
        if (!CHECK_MSG(wt_world_create(&o, &w, err, sizeof err) == 0 && wt_renderer_create(w, &r, err, sizeof err) == 0,
                       "%s", err))
            break;
        for (f = 0; f < 2; f++) {
            double t = wt_frame_time(&o, f), mean, max, ref_mean, ref_max;
            rendercache_camera c = wt_camera(&w->opt, t, DAY_W, DAY_H);
            if (!CHECK(wt_render_frame(r, f, rgb, &st) == 0) ||
                !CHECK(wt_render_converged(w, &c, t, CONVERGED_STRATA, CONVERGED_LIGHT_SAMPLES, ref) == 0))
                break;
            image_stats(rgb, n, &mean, &max);
            image_stats(ref, n, &ref_mean, &ref_max);
            test_note("entrance closed, panes Tf %s, frame %d: mean luminance %.4f (largest %.3g), converged %.4f "
                      "(largest %.3g)", tf[pass], f, mean, max, ref_mean, ref_max);
            if (pass == 0) CHECK(mean > 0.01 && ref_mean > 0.01);
            else CHECK(max == 0.0 && ref_max == 0.0);
        }
        wt_renderer_destroy(r);
        wt_world_destroy(w);
        r = NULL;
        w = NULL;
    }
    remove_dir(dir);
    free(rgb);
    free(ref);
}

/* Mode radiosity by day (radinterp.h's glass and sky): a room 4 x 2.8 x 4 m
   (two rooms in the layout, for the bunny's walk) with a 1.2 m square glass pane (Tf 0.85) in the middle of its ceiling
   under the daylight building's sky (4, 4.3, 5), written here. The floor
   under the window has at least rho tf pi L F of the sky straight through
   the pane, F the closed-form factor of the window from the floor's centre
   (the rest is light from the walls, which the sky lit), and less in the
   room's corner; with the pane opaque (Tf 0, no other light) every floor
   triangle is black. The frames render. */
#define DAY_ROOM_LAYOUT                                                                                  \
    "room 0 0 0 0 2 0 2.8 0 4 panel 0\nroom 0 0 1 2 4 0 2.8 0 4 none 0\ndoor 0 1.95 2.05 0 2.1 1.5 2.5\nsky 4 4.3 5\n"

static void write_day_room(const char *dir, float tf)
{
    static const char *obj =
        "mtllib room.mtl\n"
        "v 0 0 0\nv 4 0 0\nv 4 0 4\nv 0 0 4\nv 0 2.8 0\nv 4 2.8 0\nv 4 2.8 4\nv 0 2.8 4\n"
        "v 1.4 2.8 1.4\nv 2.6 2.8 1.4\nv 2.6 2.8 2.6\nv 1.4 2.8 2.6\n"
        "usemtl floor\nf 1 4 3 2\n"
        "usemtl wall\nf 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\n"
        "f 5 6 10 9\nf 6 7 11 10\nf 7 8 12 11\nf 8 5 9 12\n"
        "usemtl glass\nf 9 10 11 12\n";
    char path[512], mtl[256];
    snprintf(path, sizeof path, "%s/room.obj", dir);
    CHECK(write_file(path, obj));
    snprintf(mtl, sizeof mtl, "newmtl floor\nKd 0.5 0.5 0.5\nnewmtl wall\nKd 0.6 0.6 0.6\n"
             "newmtl glass\nKd 0 0 0\nTf %g %g %g\nillum 4\n", tf, tf, tf);
    snprintf(path, sizeof path, "%s/room.mtl", dir);
    CHECK(write_file(path, mtl));
    snprintf(path, sizeof path, "%s/room.layout", dir);
    CHECK(write_file(path, DAY_ROOM_LAYOUT));
}

/* The radiosity B (green) of the floor's mesh at (x, 0, z): the
   interpolant of the floor triangle containing it, at its barycentrics. */
static float floor_radiosity(const wt_renderer *r, float x, float z)
{
    const radinterp_mesh_data *d = &r->statics.data;
    uint32_t t;
    float rgb[3] = { -1.0f, -1.0f, -1.0f };
    for (t = 0; t < d->triangle_count; t++) {
        const float *a = d->positions + 3 * (size_t)d->indices[3 * t], *b = d->positions + 3 * (size_t)d->indices[3 * t + 1];
        const float *c = d->positions + 3 * (size_t)d->indices[3 * t + 2];
        float e1x = b[0] - a[0], e1z = b[2] - a[2], e2x = c[0] - a[0], e2z = c[2] - a[2], px = x - a[0], pz = z - a[2];
        float det = e1x * e2z - e1z * e2x, u, v;
        if (d->triangle_patch[t] != 0 || det == 0.0f) continue;   /* the floor is the OBJ's first face */
        u = (px * e2z - pz * e2x) / det;
        v = (e1x * pz - e1z * px) / det;
        if (u < -1e-6f || v < -1e-6f || u + v > 1.0f + 1e-6f) continue;
        radinterp_eval(r->statics.mesh, t, u, v, rgb);
        break;
    }
    return rgb[1];
}

static void test_radiosity_by_day(void)
{
    static const float sky_green = 4.3f, tf = 0.85f, rho = 0.5f;
    char dir[256], obj[512], err[512];
    float *rgb = (float *)malloc(3 * sizeof(float) * DAY_W * DAY_H);
    int opaque;
    /* F of a 1.2 m square at 2.8 m from the point under its centre (eq. 6.1 in closed form) */
    double x = 0.6 / 2.8, f = 4.0 / 3.14159265358979 * (x / sqrt(1 + x * x) * atan(x / sqrt(1 + x * x)));
    if (!CHECK(rgb && make_temp_dir(dir, sizeof dir))) { free(rgb); return; }
    snprintf(obj, sizeof obj, "%s/room.obj", dir);
    for (opaque = 0; opaque < 2; opaque++) {
        wt_options o = day_options(WT_MODE_RADIOSITY, obj);
        wt_world *w = NULL;
        wt_renderer *r = NULL;
        wt_frame_stats st;
        write_day_room(dir, opaque ? 0.0f : tf);
        if (!CHECK_MSG(wt_world_create(&o, &w, err, sizeof err) == 0, "%s", err)) continue;
        if (CHECK_MSG(wt_renderer_create(w, &r, err, sizeof err) == 0, "%s", err)) {
            float centre = floor_radiosity(r, 2.0f, 2.0f), corner = floor_radiosity(r, 0.2f, 0.2f);
            double direct = rho * tf * 3.14159265358979 * sky_green * f;
            if (!opaque) {
                /* the direct sky alone is a floor: 3% under it for the sky's sampling (1024 rays) */
                CHECK_MSG(centre >= 0.97 * direct, "under the window B = %.4f, direct sky alone %.4f", centre, direct);
                CHECK_MSG(corner > 0.0f && corner < centre, "corner %.4f, centre %.4f", corner, centre);
                test_note("radiosity by day: floor B %.4f under the window (direct sky through the pane %.4f), %.4f in "
                          "the corner", centre, direct, corner);
            } else {
                CHECK_MSG(centre == 0.0f && corner == 0.0f, "opaque pane: %.4g, %.4g", centre, corner);
            }
            CHECK(wt_render_frame(r, 0, rgb, &st) == 0);
            wt_renderer_destroy(r);
        }
        wt_world_destroy(w);
    }
    remove_dir(dir);
    free(rgb);
}

/* ---- contact shadows ------------------------------------------------------ */

/* The bunny's contact shadow (issue 19) by day, when all light is
   indirect and the light vectors of the floor are gathered without the
   bunny: floor points around it, shaded through the frames' pipeline
   (wt_shade_points: trace, direct light, a light vector) with the contact
   shadows on and off. By day a floor point's radiance is its indirect
   light times the share the bunny leaves, so the ratio is that share.
   Along each of CONTACT_AZIMUTHS directions from the feet: the first floor
   point seen from above (the edge of the bunny's silhouette on the floor,
   found in 1 cm steps), the point 15 cm farther out, and a point beyond
   the reach (WT_CONTACT_REACH bounding radii past the bounding sphere).
   Bounds: at the edge at most 0.8 of the light is left (measured 0.63: a
   contact shadow that shows; 1 without it), 15 cm out more than at the
   edge and under 1 (measured 0.94: it fades, soft), beyond the reach all
   of it, bit for bit (the points there that land on the floor; a few land
   on furniture). */
#define CONTACT_AZIMUTHS 16
#define CONTACT_OUT 0.15f
static void test_contact_shadow(void)
{
    wt_options o = day_options(WT_MODE_RAYTRACE, "daylight");
    wt_world *w = NULL;
    wt_point pts[2][3 * CONTACT_AZIMUTHS];
    wt_light_stats st = { 0, 0, 0, 0 };
    char err[512];
    float feet[3], edge[CONTACT_AZIMUTHS], far_radius;
    double sum[2][3] = { { 0, 0, 0 }, { 0, 0, 0 } }, left[3];
    int run, ring, a, count[3] = { 0, 0, 0 }, same = 0;
    o.strata = 8;
    if (!CHECK_MSG(wt_world_create(&o, &w, err, sizeof err) == 0, "%s", err)) return;
    wt_set_time(w, 0.0);
    wt_bunny_position(&w->opt, 0.0, feet, NULL);
    far_radius = (1.0f + WT_CONTACT_REACH) * 2.0f * w->bunny_bound_radius + 0.05f;   /* past the reach from all of it */
    for (a = 0; a < CONTACT_AZIMUTHS; a++) {   /* the silhouette's edge on the floor */
        float phi = 2.0f * 3.14159265f * ((float)a + 0.5f) / CONTACT_AZIMUTHS, down[3] = { 0.0f, -1.0f, 0.0f };
        for (edge[a] = 0.0f; edge[a] < 0.5f; edge[a] += 0.01f) {
            float org[3] = { feet[0] + edge[a] * cosf(phi), feet[1] + 1.0f, feet[2] + edge[a] * sinf(phi) };
            ex_trace_hit h;
            if (ex_tracer_intersect(w->tracer, org, down, FLT_MAX, &h) && h.instance == EX_TRACE_STATIC) break;
        }
    }
    for (run = 0; run < 2; run++) {   /* 0: contact shadows on, 1: off */
        memset(pts[run], 0, sizeof pts[run]);
        for (ring = 0; ring < 3; ring++)
            for (a = 0; a < CONTACT_AZIMUTHS; a++) {
                wt_point *p = &pts[run][ring * CONTACT_AZIMUTHS + a];
                float r = ring == 0 ? edge[a] : ring == 1 ? edge[a] + CONTACT_OUT : far_radius + 0.02f * (float)a;
                float phi = 2.0f * 3.14159265f * ((float)a + 0.5f) / CONTACT_AZIMUTHS;
                p->org[0] = feet[0] + r * cosf(phi);
                p->org[1] = feet[1] + 1.0f;   /* 1 m above the floor, looking down */
                p->org[2] = feet[2] + r * sinf(phi);
                p->dir[1] = -1.0f;
                p->stream = (uint64_t)(ring * CONTACT_AZIMUTHS + a);
            }
        w->opt.bunny_shadow = run == 0;
        CHECK(wt_shade_points(w, pts[run], 3 * CONTACT_AZIMUTHS, WT_SHADE_DIRECT, &st, NULL, NULL) == 0);
    }
    for (ring = 0; ring < 3; ring++) {
        for (a = 0; a < CONTACT_AZIMUTHS; a++) {
            const wt_point *on = &pts[0][ring * CONTACT_AZIMUTHS + a], *off = &pts[1][ring * CONTACT_AZIMUTHS + a];
            if (off->object != WT_OBJECT_OFFICE || fabsf(off->pos[1] - feet[1]) > 0.01f) continue;   /* the floor only */
            sum[0][ring] += luminance(on->rgb);
            sum[1][ring] += luminance(off->rgb);
            count[ring]++;
            if (ring == 2) same += memcmp(on->rgb, off->rgb, sizeof on->rgb) == 0;
        }
        left[ring] = sum[1][ring] > 0.0 ? sum[0][ring] / sum[1][ring] : -1.0;
    }
    test_note("share of the floor's light left with the contact shadow: %.3f at the bunny's edge (%d points), %.3f "
              "%.0f cm farther out (%d), %.3f beyond %.2f m (%d, %d untouched)", left[0], count[0], left[1],
              100.0 * CONTACT_OUT, count[1], left[2], (double)far_radius, count[2], same);
    CHECK(count[0] == CONTACT_AZIMUTHS && count[1] == CONTACT_AZIMUTHS && count[2] >= CONTACT_AZIMUTHS / 2);
    CHECK_MSG(left[0] > 0.0 && left[0] <= 0.8, "at the edge: %.3f", left[0]);
    CHECK_MSG(left[1] > left[0] && left[1] < 1.0, "%.0f cm out: %.3f", 100.0 * CONTACT_OUT, left[1]);
    CHECK_EQ_INT(same, count[2]);   /* out of reach: untouched */
    wt_world_destroy(w);
}

int main(int argc, char **argv)
{
    test_init(argc, argv);
    RUN(test_sky_lines);
    RUN(test_camera_through_glass);
    RUN(test_radiosity_by_day);
    RUN(test_light_only_through_glass);
    RUN(test_daylight_frames);
    RUN(test_contact_shadow);
    return test_finish();
}
