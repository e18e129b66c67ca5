/* Tests of the walkthrough's frame pipeline (examples/common/walkthrough.h):
   options, paths, the precompute cache on disk, modes raytrace and
   baseviews against stored reference frames, determinism across thread
   counts, the bunny darkening under the desk (in the ray-traced frames and
   through an irradiance volume of the lamp), and the rasterizer against the
   ray tracer. Mode radiosity: tests/test_walkthrough_radiosity.c.

   Reference frames (tests/data/walkthrough_<mode>_f<frame>.pfm, 64x48) were
   written by this program with WT_WRITE_REFERENCE=1 from the repository
   root:

       WT_WRITE_REFERENCE=1 build/tests/test_walkthrough reference

   at the settings of small_options() below, and are compared by the
   relative luminance RMS error (LRMS). Rendering is deterministic (counter
   based random streams, light vectors looked up and inserted in a fixed
   order, the same on any thread count), so on the machine that wrote them
   the error is 0. Another compiler or libm may round differently and flip
   a decision (a light-vector lookup, a render cache request), which redraws
   pixels with other random numbers. At these settings one pixel's noise is
   about 0.6 of the mean luminance (the seed-to-seed LRMS, printed by
   test_reference_frames), and a flip in frame 0 can at worst move all the
   requests of frame 1 (8% of its pixels, 16% counting both frames):
   LRMS <= 0.6 sqrt(0.16) = 0.24. The tolerance is half the seed-to-seed
   LRMS (about 0.3): such flips pass, other random numbers everywhere fail,
   and so does a change of the shading (the light vectors' indirect light is
   63% of frame 0's luminance: without it the LRMS is 0.74). */
#define _POSIX_C_SOURCE 200809L
#include "examples/common/walkthrough.h"
#include "tests/test.h"
#include "tests/walkthrough_test.h"

#define REF_W 64
#define REF_H 48
#define REF_TOLERANCE_SHARE 0.5   /* of the seed-to-seed LRMS, see above */

/* Small, fast settings: 64x48 frames of a 24-frame path, thin gathers, no
   disk cache. */
static wt_options small_options(wt_mode mode)
{
    wt_options o = quiet_options(mode, "office", REF_W, REF_H, 24);
    o.strata = 6;
    o.bunny_strata = 4;
    o.warmup_divisor = 4;
    o.base_size = 64;
    o.id_size = 24;
    o.keys = 3;
    o.quality = 0.6f;
    return o;
}

/* Renders frames 0 .. count-1 of o's path; frames: count * w * h * 3 floats. */
static int render_frames(const wt_options *o, int count, float *frames)
{
    wt_world *w = NULL;
    wt_renderer *r = NULL;
    wt_frame_stats st;
    char err[512];
    int f, ok = 1;
    if (wt_world_create(o, &w, err, sizeof err) != 0 || wt_renderer_create(w, &r, err, sizeof err) != 0) {
        fprintf(stderr, "  %s\n", err);
        wt_world_destroy(w);
        return 0;
    }
    for (f = 0; f < count && ok; f++)
        ok = wt_render_frame(r, f, frames + (size_t)f * 3 * (size_t)o->width * (size_t)o->height, &st) == 0;
    wt_renderer_destroy(r);
    wt_world_destroy(w);
    return ok;
}

/* ---- options -------------------------------------------------------------- */

static int parse(const char *line, wt_options *o, char *err, size_t err_size)
{
    char buf[512], *argv[32];
    int argc = 0;
    strcpy(buf, line);
    argv[argc++] = (char *)"walkthrough";
    for (argv[argc] = strtok(buf, " "); argv[argc] && argc < 31; argv[++argc] = strtok(NULL, " ")) {}
    wt_options_default(o);
    return wt_parse_options(argc, argv, o, err, err_size);
}

static void test_options(void)
{
    wt_options o;
    char err[256];
    static const char *bad[] = {
        "--mode fast", "--frames 0", "--frames ten", "--size 640", "--size 640x", "--size x480", "--size 4x4",
        "--budget 0", "--budget 2", "--quality 1.5", "--threads -1", "--light-samples 0", "--wobble", "--frames",
        "frames", "--out"
    };
    size_t i;
    CHECK_EQ_INT(parse("--mode baseviews --frames 12 --size 320x200 --threads 1 --seed 7 --no-cache --quiet", &o, err,
                       sizeof err), 1);
    CHECK(o.mode == WT_MODE_BASEVIEWS && o.frames == 12 && o.width == 320 && o.height == 200 && o.threads == 1);
    CHECK(o.seed == 7 && !o.use_cache && !o.progress && !o.verbose);
    CHECK_EQ_INT(parse("--mode radiosity --budget 0.25 --quality 0.5 --out x --cache y --data z", &o, err, sizeof err), 1);
    CHECK(o.mode == WT_MODE_RADIOSITY && o.budget == 0.25f && o.quality == 0.5f && !strcmp(o.out, "x"));
    for (i = 0; i < sizeof bad / sizeof *bad; i++) {
        err[0] = 0;
        CHECK_MSG(parse(bad[i], &o, err, sizeof err) == -1 && err[0], "'%s' was accepted", bad[i]);
    }
    CHECK_EQ_INT(parse("--eps 0.5 --min-leaf-area 0.25 --volume-k 9 --no-bunny-shadow", &o, err, sizeof err), 1);
    CHECK(o.radiosity_eps == 0.5f && o.min_leaf_area == 0.25f && o.volume_resolution == 9 && !o.bunny_shadow);
    for (i = 0; i < 3; i++) {
        static const char *more[] = { "--eps 0", "--min-leaf-area -1", "--volume-k 33" };
        CHECK_MSG(parse(more[i], &o, err, sizeof err) == -1 && err[0], "'%s' was accepted", more[i]);
    }
    wt_options_default(&o);
    CHECK(o.mode == WT_MODE_RADIOSITY);   /* the default: what make demo shows */
}

/* A missing scene file is an error that names it. */
static void test_missing_files(void)
{
    wt_options o = small_options(WT_MODE_RAYTRACE);
    wt_world *w = NULL;
    char err[512];
    o.data_dir = "tests/no-such-directory";
    CHECK(wt_world_create(&o, &w, err, sizeof err) == -1 && w == NULL);
    CHECK_MSG(strstr(err, "tests/no-such-directory/office.obj") != NULL, "message: %s", err);
}

/* ---- paths ---------------------------------------------------------------- */

/* Distance from (x, z) to an axis-aligned rectangle of the floor plan. */
static float box_distance(float x, float z, float x0, float x1, float z0, float z1)
{
    float dx = x < x0 ? x0 - x : x > x1 ? x - x1 : 0.0f, dz = z < z0 ? z0 - z : z > z1 ? z - z1 : 0.0f;
    return sqrtf(dx * dx + dz * dz);
}

static void test_bunny_path(void)
{
    /* obstacles on the floor: desk panels, divider, lamp pole, shelves; and the walls */
    static const float boxes[][4] = {
        { 1.0f, 1.03f, 2.9f, 3.7f }, { 2.57f, 2.6f, 2.9f, 3.7f }, { 3.6f, 3.65f, 1.3f, 2.6f },
        { 3.28f, 3.32f, 3.38f, 3.42f }, { 0.0f, 0.35f, 1.0f, 1.9f }
    };
    float clearance = 1e9f, under = -1e9f, divider = 1e9f, p[3], heading;
    int i, b, open_start;
    wt_bunny_position(NULL, 0.0, p, &heading);
    open_start = box_distance(p[0], p[2], 1.0f, 2.6f, 2.9f, 3.7f) > 0.5f;
    CHECK_MSG(open_start, "the bunny starts at (%.2f, %.2f), not on the open floor", (double)p[0], (double)p[2]);
    for (i = 0; i <= 1000; i++) {
        wt_bunny_position(NULL, i / 1000.0, p, &heading);
        CHECK(isfinite(heading));
        for (b = 0; b < 5; b++) {
            float d = box_distance(p[0], p[2], boxes[b][0], boxes[b][1], boxes[b][2], boxes[b][3]);
            clearance = d < clearance ? d : clearance;
        }
        clearance = fminf(clearance, fminf(fminf(p[0], 5.0f - p[0]), fminf(p[2], 4.0f - p[2])));
        /* depth under the desk top (x 1.0-2.6, z 2.9-3.7): how far inside its footprint */
        under = fmaxf(under, fminf(fminf(p[0] - 1.0f, 2.6f - p[0]), fminf(p[2] - 2.9f, 3.7f - p[2])));
        divider = fminf(divider, box_distance(p[0], p[2], 3.6f, 3.65f, 1.3f, 2.6f));
    }
    test_note("bunny path: clearance %.3f m (footprint radius %.2f), %.2f m inside the desk, %.2f m from the divider",
              (double)clearance, (double)WT_BUNNY_RADIUS, (double)under, (double)divider);
    CHECK(clearance > WT_BUNNY_RADIUS);        /* never walks through anything */
    CHECK(under > 0.3f);                       /* well under the desk top */
    CHECK(divider < 0.35f);                    /* right past the divider */
}

/* The camera sees the bunny in every frame, from inside the room. */
static void test_camera_path(void)
{
    wt_options o = small_options(WT_MODE_RAYTRACE);
    int f;
    for (f = 0; f < o.frames; f++) {
        double t = wt_frame_time(&o, f);
        rendercache_camera c = wt_camera(&o, t, 640, 480);
        float p[3], px, py, depth;
        wt_bunny_position(&o, t, p, NULL);
        p[1] = 0.15f;   /* the bunny's middle */
        CHECK(c.eye[0] > 0.2f && c.eye[0] < 4.8f && c.eye[1] > 0.2f && c.eye[1] < 2.6f && c.eye[2] > 0.2f && c.eye[2] < 3.8f);
        CHECK_MSG(rendercache_camera_project(&c, p, &px, &py, &depth) && px > 32 && px < 608 && py > 32 && py < 448,
                  "frame %d: the bunny projects to (%.0f, %.0f)", f, (double)px, (double)py);
    }
}

/* The default frame count follows the route (wt_route_frames): the
   office's walk (1.3 m of eye movement, 51 degrees of turn) is shorter than
   48 frames of 0.1 m and 1.5 degrees, so it keeps 48; wt_world_create
   resolves the count before the precompute keys hash it, so a key of the
   default count is the key of the same count given explicitly, and another
   count gives another key. */
static void test_route_frames(void)
{
    wt_options o = small_options(WT_MODE_RAYTRACE);
    wt_world *w[3] = { NULL, NULL, NULL };
    wt_route route = wt_route_measure(&o);
    char err[512];
    int i, ok = 1;
    test_note("office route: %.3f m, %.1f degrees: %d frames", route.length, route.turn, wt_route_frames(&o));
    CHECK(route.length > 1.0 && route.length < 1.6 && route.turn > 40.0 && route.turn < 60.0);   /* the walk as it is */
    CHECK_EQ_INT(wt_route_frames(&o), WT_MIN_FRAMES);
    for (i = 0; i < 3; i++) {
        o.frames = i == 0 ? 0 : i == 1 ? WT_MIN_FRAMES : WT_MIN_FRAMES + 1;
        ok = ok && CHECK(wt_world_create(&o, &w[i], err, sizeof err) == 0);
    }
    if (ok) {
        CHECK_EQ_INT(w[0]->opt.frames, WT_MIN_FRAMES);
        CHECK(wt__lightvec_key(w[0]) == wt__lightvec_key(w[1]));
        CHECK(wt__lightvec_key(w[0]) != wt__lightvec_key(w[2]));
    }
    for (i = 0; i < 3; i++) wt_world_destroy(w[i]);
}

/* ---- the precompute cache on disk -------------------------------------------- */

static void test_cache_files(void)
{
    char dir[256], path[1024], err[256];
    unsigned char payload[1000];
    void *data;
    size_t size, i;
    FILE *f;
    if (!CHECK(make_temp_dir(dir, sizeof dir))) return;
    for (i = 0; i < sizeof payload; i++) payload[i] = (unsigned char)(i * 7);
    CHECK_EQ_INT(wt_cache_load(dir, "thing", 42, &data, &size), 0);          /* absent */
    CHECK_EQ_INT(wt_cache_store(dir, "thing", 42, payload, sizeof payload, err, sizeof err), 0);
    CHECK_EQ_INT(count_files(dir, "\\.bin$"), 1);
    CHECK_EQ_INT(count_files(dir, "tmp[0-9]*$"), 0);                          /* renamed, nothing left */
    CHECK_EQ_INT(wt_cache_load(dir, "thing", 42, &data, &size), 1);
    CHECK(size == sizeof payload && memcmp(data, payload, size) == 0);
    free(data);
    CHECK_EQ_INT(wt_cache_load(dir, "thing", 43, &data, &size), 0);          /* another key: another file */
    /* a flipped byte, then a truncation: damaged, never trusted */
    wt_cache_path(dir, "thing", 42, path, sizeof path);
    f = fopen(path, "r+b");
    if (CHECK(f != NULL)) {
        fseek(f, 100, SEEK_SET);
        fputc(0x55, f);
        fclose(f);
    }
    CHECK_EQ_INT(wt_cache_load(dir, "thing", 42, &data, &size), -1);
    CHECK(data == NULL);
    CHECK(truncate(path, 20) == 0);
    CHECK_EQ_INT(wt_cache_load(dir, "thing", 42, &data, &size), -1);
    remove_dir(dir);
}

/* A second renderer reuses the precomputed light vectors and base images,
   and renders the same frames; other parameters make other files. */
static void test_precompute_reuse(void)
{
    int m;
    for (m = 0; m < 2; m++) {
        char dir[256], err[512];
        wt_options o = small_options((wt_mode)m);
        wt_world *w1 = NULL, *w2 = NULL;
        wt_renderer *r1 = NULL, *r2 = NULL;
        size_t n = 3 * (size_t)REF_W * REF_H;
        float *a = (float *)malloc(sizeof(float) * 2 * n), *b = (float *)malloc(sizeof(float) * 2 * n);
        wt_frame_stats st;
        uint64_t key = 0;
        int f;
        if (!CHECK(a && b && make_temp_dir(dir, sizeof dir))) { free(a); free(b); return; }
        o.cache_dir = dir;
        o.use_cache = 1;
        if (CHECK(wt_world_create(&o, &w1, err, sizeof err) == 0 && wt_renderer_create(w1, &r1, err, sizeof err) == 0)) {
            CHECK(!r1->reused_lightvec && !r1->reused_baseviews);
            for (f = 0; f < 2; f++) CHECK(wt_render_frame(r1, f, a + f * n, &st) == 0);
            key = r1->lightvec_key;
        }
        if (CHECK(wt_world_create(&o, &w2, err, sizeof err) == 0 && wt_renderer_create(w2, &r2, err, sizeof err) == 0)) {
            CHECK(r2->reused_lightvec);
            CHECK(m != WT_MODE_BASEVIEWS || r2->reused_baseviews);
            CHECK(r1 && r2->static_vectors == r1->static_vectors);
            for (f = 0; f < 2; f++) CHECK(wt_render_frame(r2, f, b + f * n, &st) == 0);
            /* the same vectors and base images, the same kd-trees: the same frames */
            CHECK_MSG(memcmp(a, b, sizeof(float) * 2 * n) == 0, "%s: frames differ after loading the precompute",
                      wt_mode_name((wt_mode)m));
        }
        wt_renderer_destroy(r2);
        wt_world_destroy(w2);
        w2 = NULL;
        r2 = NULL;
        o.strata = 7;   /* another parameter: another key, nothing reused */
        if (CHECK(wt_world_create(&o, &w2, err, sizeof err) == 0 && wt_renderer_create(w2, &r2, err, sizeof err) == 0))
            CHECK(!r2->reused_lightvec && r2->lightvec_key != key);
        CHECK_EQ_INT(count_files(dir, "tmp[0-9]*$"), 0);
        wt_renderer_destroy(r1);
        wt_renderer_destroy(r2);
        wt_world_destroy(w1);
        wt_world_destroy(w2);
        remove_dir(dir);
        free(a);
        free(b);
    }
}

/* ---- frames ------------------------------------------------------------------ */

/* Frames 0 and 1 of both modes against the stored references. */
static double frames_vs_reference(wt_mode mode, uint64_t seed, int write)
{
    wt_options o = small_options(mode);
    float *frames = (float *)malloc(sizeof(float) * 6 * REF_W * REF_H), *ref = (float *)malloc(sizeof(float) * 3 * REF_W * REF_H);
    double worst = -1.0;
    int f;
    o.seed = seed;
    if (frames && ref && render_frames(&o, 2, frames)) {
        worst = 0.0;
        for (f = 0; f < 2; f++) {
            char path[256];
            double lrms;
            reference_path(path, sizeof path, mode, f);
            if (write) {
                if (ex_write_pfm(path, REF_W, REF_H, frames + (size_t)f * 3 * REF_W * REF_H) != 0) worst = -1.0;
                continue;
            }
            if (ex_read_pfm(path, REF_W, REF_H, ref) != 0 ||
                rendercache_lrms(ref, frames + (size_t)f * 3 * REF_W * REF_H, REF_W, REF_H, &lrms) != RENDERCACHE_OK)
                return -1.0;
            worst = lrms > worst ? lrms : worst;
        }
    }
    free(frames);
    free(ref);
    return worst;
}

static void test_reference_frames(void)
{
    int m;
    for (m = 0; m < 2; m++) {
        double other = frames_vs_reference((wt_mode)m, 2, 0), lrms = frames_vs_reference((wt_mode)m, 1, 0);
        double tol = REF_TOLERANCE_SHARE * other;
        test_note("%s: frames 0 and 1 against the references: LRMS %.4f; with another seed %.4f (tolerance %.4f)",
                  wt_mode_name((wt_mode)m), lrms, other, tol);
        CHECK(other > 0.0);   /* the comparison sees a change of random numbers */
        CHECK_MSG(lrms >= 0.0 && lrms <= tol, "%s: LRMS %.4f", wt_mode_name((wt_mode)m), lrms);
    }
}

/* Direct light by many-light sampling has the mean of sampling every light
   (tests/walkthrough_test.h): the office's lamp, at the hits of a 16 x 12
   view of frame 0 and of the bunny under the desk; first with the grid's
   flags alone, then with the counts that the 24 raytrace frames of the
   walk learned (wt__light_learn_merge: the picks then depend on earlier
   frames' shadow rays, never on the point's own). */
static void test_direct_light_unbiased(void)
{
    wt_options o = small_options(WT_MODE_RAYTRACE);
    wt_world *w = NULL;
    wt_renderer *r = NULL;
    wt_frame_stats st;
    float *rgb = (float *)malloc(sizeof(float) * 3 * REF_W * REF_H);
    char err[512];
    int i, f;
    size_t counted = 0, j;
    o.light_samples = 8;
    if (!CHECK(rgb && wt_world_create(&o, &w, err, sizeof err) == 0)) goto done;
    for (i = 0; i < 4; i++) {
        double sigmas = 0.0, noise[2], rays = 0.0, t = i % 2 ? time_under_desk() : 0.0, bias;
        if (i == 2) {   /* the walk's frames: their shadow rays are counted */
            if (!CHECK(w->learn_sides > 0 && wt_renderer_create(w, &r, err, sizeof err) == 0)) break;
            for (f = 0; f < o.frames; f++)
                if (!CHECK(wt_render_frame(r, f, rgb, &st) == 0)) goto done;
            for (j = 0; j < (size_t)w->grid_dims[0] * w->grid_dims[1] * w->grid_dims[2] * w->learn_sides * w->light_count; j++)
                counted += w->light_learned[2 * j] > 0;
            CHECK(counted > 0);
        }
        bias = direct_light_bias(w, t, 16, 12, 64, 4, &sigmas, noise, &rays);
        test_note("office, t %.2f%s: many-light mean %.4f from every light's (%.1f sigma); relative RMS noise "
                  "%.3f at 8 rays against %.3f at 4 rays per light (%.1f rays)", t,
                  i < 2 ? "" : ", learned counts", bias, sigmas, noise[0], noise[1], rays);
        CHECK_MSG(bias >= 0.0 && sigmas < 4.0, "office t %.2f: relative difference %.4f, %.1f sigma", t, bias, sigmas);
    }
    test_note("%zu (key, light) pairs counted after the walk", counted);
done:
    wt_renderer_destroy(r);
    wt_world_destroy(w);
    free(rgb);
}

/* The irradiance a convex planar polygon of unit radiance sends to x
   (normal n, every corner above x's horizon): Lambert's formula, half the
   sum over the edges of the angle each edge subtends times the cosine
   between n and the normal of the plane through x and the edge (Arvo 1995,
   "Applications of Irradiance Tensors", eq. 10 for a constant emitter). */
static double polygon_irradiance(const float x[3], const float n[3], const float *const *corners, int count)
{
    double sum = 0.0;
    int i, k;
    for (i = 0; i < count; i++) {
        double a[3], b[3], c[3], la, lb, lc;
        for (k = 0; k < 3; k++) {
            a[k] = (double)corners[i][k] - x[k];
            b[k] = (double)corners[(i + 1) % count][k] - x[k];
        }
        la = sqrt(wt__dot3(a, a));
        lb = sqrt(wt__dot3(b, b));
        for (k = 0; k < 3; k++) {
            a[k] /= la;
            b[k] /= lb;
        }
        c[0] = a[1] * b[2] - a[2] * b[1];
        c[1] = a[2] * b[0] - a[0] * b[2];
        c[2] = a[0] * b[1] - a[1] * b[0];
        lc = sqrt(wt__dot3(c, c));
        sum += atan2(lc, wt__dot3(a, b)) * (c[0] * n[0] + c[1] * n[1] + c[2] * n[2]) / lc;
    }
    return fabs(sum) / 2.0;
}

/* Mean and variance of one sample of the irradiance at x (normal n) from
   light L: sampler 0 wt__light_area_direction, 1 by solid angle
   (wt__light_view_solid_angle), 2 light_sample (the sampler it
   picks, shadow rays, a white Lambert surface); count stratified samples
   as wt__direct draws them for one light. */
static void light_irradiance(const wt_world *w, const wt_light *L, const float x[3], const float n[3], int sampler,
                             int count, double *mean, double *var)
{
    static const lightvec_material white = { { 1, 1, 1 }, { 0, 0, 0 }, 0, { 0, 0, 0 }, { 0, 0, 0 } };
    double m1 = 0.0, m2 = 0.0;
    int i;
    for (i = 0; i < count; i++) {
        float u1 = ((float)i + 0.5f) / (float)count, u2 = wt__radical_inverse((uint32_t)i), wi[3], d, weight;
        float rgb[3] = { 0, 0, 0 }, gloss[3] = { 0, 0, 0 }, mirror[3] = { 0, 1, 0 };
        double e = 0.0;
        int shadow = 0, got;
        if (sampler == 2) {
            light_sample(w, L, x, n, mirror, &white, u1, u2, 1.0f, rgb, gloss, &shadow);
            e = rgb[1] * WT_PI / L->ke[1];
        } else {
            wt__light_view v;
            if (sampler) wt__light_view_solid_angle(w, L, x, &v);
            got = sampler ? wt__light_view_direction(w, &v, x, u1, u2, wi, &d, &weight)
                          : wt__light_area_direction(w, L, x, u1, u2, wi, &d, &weight);
            if (got > 0) e = fmax(wi[0] * n[0] + wi[1] * n[1] + wi[2] * n[2], 0.0) * weight;
        }
        m1 += e;
        m2 += e * e;
    }
    *mean = m1 / count;
    *var = m2 / count - *mean * *mean;
}

/* Direct light from one emitting polygon against Lambert's closed form:
   the office's lamp shade (a box of 6 emitting quads, 2 triangles each),
   at points 2 cm and 10 cm in front of a face (over its middle, and beside
   it, past its edge, facing it or tilted: the walls and the desk near the
   lamp) and 2.2 m away where the room has space (about 10 of the face's
   radii: sampled by area).
   Each sampler's mean over N stratified samples matches the closed form
   within 4 of its standard errors (the plain Monte Carlo error, sqrt(var /
   N): stratification only lowers it) plus 1e-4 of the value (float
   directions and weights); the light path light_sample takes (shadow
   rays included: nothing stands in front of the shade's top and x sides
   with the bunny on the floor) does too. Near the
   face, one sample's variance by solid angle is below half of area's
   (measured 0.004-0.048 of it: by solid angle only cos_x varies, nothing
   near 2 cm in front of the face's middle); far away the two agree. */
static void test_light_solid_angle(void)
{
    enum { N = 4096 };
    wt_options o = small_options(WT_MODE_RAYTRACE);
    wt_world *w = NULL;
    char err[512];
    uint32_t e;
    float lo[3], hi[3];
    int tested = 0;
    if (!CHECK(wt_world_create(&o, &w, err, sizeof err) == 0)) return;
    if (!CHECK(obj_bounds(&w->office, lo, hi))) {
        wt_world_destroy(w);
        return;
    }
    wt_set_time(w, 0.0);   /* the bunny on the floor, out of the way */
    for (e = 0; e < w->light_count; e++) {
        const wt_light *L = &w->lights[e];
        const float *corners[4];
        const float *tri[3];
        float tangent[3], nl[3];
        int c, k;
        if (L->tri_count != 2 || !(fabsf(L->normal[0]) > 0.9f || L->normal[1] > 0.9f))
            continue;   /* the top and the x sides: the pole stands under the bottom; z as x */
        /* the quad's corners in order: the fan's first triangle and the second's last corner */
        wt__light_corners(w, L, 0, tri);
        corners[0] = tri[0];
        corners[1] = tri[1];
        corners[2] = tri[2];
        wt__light_corners(w, L, 1, tri);
        corners[3] = tri[2];
        for (k = 0; k < 3; k++) {
            nl[k] = L->normal[k];
            tangent[k] = corners[1][k] - corners[0][k];
        }
        for (c = 0; c < 6; c++) {
            static const float ahead[6] = { 0.02f, 0.10f, 0.02f, 0.10f, 0.02f, 2.2f };
            static const float aside[6] = { 0.0f, 0.0f, 0.7f, 0.7f, 0.7f, 0.0f };
            float x[3], n[3], len = 0.0f;
            double area_mean, area_var, solid_mean, solid_var, mean, var, exact;
            int ok = 1;
            for (k = 0; k < 3; k++) {
                x[k] = L->centre[k] + ahead[c] * nl[k] + aside[c] * tangent[k];
                n[k] = -nl[k] - (c == 4 ? 0.8f * tangent[k] / L->radius : 0.0f);   /* case 4: tilted towards the face */
                len += n[k] * n[k];
            }
            for (k = 0; k < 3; k++) n[k] /= sqrtf(len);
            if (!(x[0] > lo[0] && x[0] < hi[0] && x[1] > lo[1] && x[1] < hi[1] && x[2] > lo[2] && x[2] < hi[2]))
                continue;   /* 2.2 m away is outside the room: only the -x and -z faces have room for it */
            for (k = 0; k < 4; k++)   /* the formula holds with every corner above the horizon */
                ok &= (corners[k][0] - x[0]) * n[0] + (corners[k][1] - x[1]) * n[1] + (corners[k][2] - x[2]) * n[2] > 0.0f;
            if (!CHECK_MSG(ok, "light %u case %d: a corner below the horizon", e, c)) continue;
            exact = polygon_irradiance(x, n, corners, 4);
            light_irradiance(w, L, x, n, 0, N, &area_mean, &area_var);
            light_irradiance(w, L, x, n, 1, N, &solid_mean, &solid_var);
            light_irradiance(w, L, x, n, 2, N, &mean, &var);
            test_note("light %u, %.2f m ahead, %.2f aside%s: irradiance %.5f; by area %.5f (sd %.4f), by solid angle "
                      "%.5f (sd %.4f), shaded %.5f: variance ratio %.3f", e, ahead[c], aside[c], c == 4 ? ", tilted" : "",
                      exact, area_mean, sqrt(area_var), solid_mean, sqrt(solid_var), mean, solid_var / area_var);
            CHECK_CLOSE(area_mean, exact, 1e-4, 4.0 * sqrt(area_var / N));
            CHECK_CLOSE(mean, exact, 1e-4, 4.0 * sqrt(var / N));
            if (ahead[c] < 1.0f) {
                CHECK_CLOSE(solid_mean, exact, 1e-4, 4.0 * sqrt(solid_var / N));
                CHECK_MSG(solid_var < 0.5 * area_var, "light %u case %d: variance %.3g by solid angle, %.3g by area", e,
                          c, solid_var, area_var);
            }
        }
        tested++;
    }
    CHECK_MSG(tested == 3, "%d of the lamp's faces tested", tested);
    wt_world_destroy(w);
}

/* Frames are bit-identical on 1 and 2 threads. */
static void test_threads(void)
{
    int m;
    for (m = 0; m < 2; m++) {
        wt_options o = small_options((wt_mode)m);
        size_t n = 6 * (size_t)REF_W * REF_H;
        float *a = (float *)malloc(sizeof(float) * n), *b = (float *)malloc(sizeof(float) * n);
        if (CHECK(a && b)) {
            o.threads = 1;
            CHECK(render_frames(&o, 2, a));
            o.threads = 2;
            CHECK(render_frames(&o, 2, b));
            CHECK_MSG(memcmp(a, b, sizeof(float) * n) == 0, "%s differs between 1 and 2 threads", wt_mode_name((wt_mode)m));
        }
        free(a);
        free(b);
    }
}

/* ---- the bunny under the desk ------------------------------------------------- */


/* Issue 19's measure of the raytrace mode: the LRMS of its frames against
   converged renders (wt_render_converged: a gather at every pixel, 32
   shadow rays, no interpolation, no render-cache reuse), at the demo's
   shading settings (default strata and light samples) on a small image,
   pooled over CONVERGED_FRAMES frames of the walk (the root of their mean
   squared LRMS). The converged render is itself noisy at CONVERGED_STRATA
   (its LRMS against one of 48 x 144 rays is 0.048 at 80x60; two converged
   renders of frames 7, 23, 39 at 160x120 with other random numbers differ
   by 0.047-0.054), so the error printed includes that noise in quadrature.
   One frame alone moves by up to 0.04 whenever the render cache's requests
   are drawn anew (frame 23 of this walk: 0.176 with glossy points' priority
   fixed at insertion, 0.219 with them aged by the view's turn since they
   were shaded, rendercache's view_lobe, while the pooled LRMS of the odd
   frames went from 0.1749 to 0.1744), so the test pools frames 7, 15 and
   23: 0.1772 before view_lobe (frames 0.130, 0.215, 0.176), 0.1778 with it
   (0.127, 0.175, 0.219), 0.1550 once a colour change no longer aged the
   points shaded in its own frame and aged the others only to where they
   rank with the holes (0.123, 0.156, 0.181; in the building walkthrough a
   third of each frame's requests had gone to the previous frame's
   samples; 0.1708 with the first change alone). The bound is that plus
   10% for a compiler flipping a light-vector decision (a flip redraws at
   most the 8% of a frame's pixels requested after it); a frame without
   its indirect light (63% of the luminance) is at 0.7. Requests at the
   reprojected image's steps brought the pooled LRMS from 0.1550 to 0.1439
   here when the walkthrough made them itself (half the budget), and to
   0.1278 from the render cache (rendercache_desc.edge_fraction 0.75,
   spread over the steps; 0.1862 with 1, which starves the holes of this
   fast walk). The frames are deterministic, so the bound 0.140 sits
   between 0.1278 and the two before, and fails when the steps' requests
   are lost or take the whole budget (0.1311 once the light picks learned
   from the frames' shadow rays, frames 0.099, 0.162, 0.124: their
   requests are drawn anew). The target (0.07) is not met:
   the bound guards against regressions. */
#define CONVERGED_STRATA 12
#define CONVERGED_LIGHT_SAMPLES 32
#define CONVERGED_FRAMES 3
#define CONVERGED_MAX_LRMS 0.140
static void test_raytrace_against_converged(void)
{
    static const int frames[CONVERGED_FRAMES] = { 7, 15, 23 };
    wt_options o = small_options(WT_MODE_RAYTRACE), d;
    wt_world *w = NULL;
    wt_renderer *r = NULL;
    wt_frame_stats st;
    char err[512];
    float *rgb = (float *)malloc(sizeof(float) * 3 * REF_W * REF_H), *ref = (float *)malloc(sizeof(float) * 3 * REF_W * REF_H);
    float e0 = 0.0f;
    double squares = 0.0, pooled;
    int f, checked = 0;
    wt_options_default(&d);
    o.strata = d.strata;
    o.bunny_strata = d.bunny_strata;
    o.light_samples = d.light_samples;
    if (!CHECK(rgb && ref) || !CHECK(o.frames == frames[CONVERGED_FRAMES - 1] + 1) ||
        !CHECK(wt_world_create(&o, &w, err, sizeof err) == 0 && wt_renderer_create(w, &r, err, sizeof err) == 0))
        goto done;
    for (f = 0; f < o.frames; f++) {
        float e;
        if (!CHECK(wt_render_frame(r, f, rgb, &st) == 0)) break;
        e = wt_exposure(&o, rgb, e0);
        if (f == 0) e0 = e;
        if (checked < CONVERGED_FRAMES && f == frames[checked]) {
            double t = wt_frame_time(&o, f), lrms = -1.0;
            rendercache_camera c = wt_camera(&w->opt, t, REF_W, REF_H);
            if (!CHECK(wt_render_converged(w, &c, t, CONVERGED_STRATA, CONVERGED_LIGHT_SAMPLES, ref) == 0 &&
                       wt_display_lrms(ref, rgb, REF_W, REF_H, e, &lrms) == 0 && lrms >= 0.0))
                break;
            test_note("raytrace frame %d against a converged render: LRMS %.4f", f, lrms);
            squares += lrms * lrms;
            checked++;
        }
    }
    if (CHECK(checked == CONVERGED_FRAMES)) {
        pooled = sqrt(squares / CONVERGED_FRAMES);
        test_note("raytrace frames pooled: LRMS %.4f (bound %.3f, issue target 0.07)", pooled, CONVERGED_MAX_LRMS);
        CHECK(pooled <= CONVERGED_MAX_LRMS);
    }
done:
    wt_renderer_destroy(r);
    wt_world_destroy(w);
    free(rgb);
    free(ref);
}

/* wt_converged_lrms takes a converged render's own noise out of the
   LRMS: a frame that is a third converged render (other random numbers)
   must read as one render's noise, s = LRMS(C1, C2) / sqrt 2, and a frame
   that is the first of its two renders as none (here s 0.0353: the third
   reads 0.0351, the first 0.0010). Without the correction they would read
   0.0431 (1.22 s: sqrt 1.5, the mean of two renders keeps half of one's
   noise in squares) and 0.0250 (0.71 s); taking out half of LRMS(C1, C2)^2
   instead of a quarter, 0.0247 and 0. The 15 % allowed is for a 64x48
   image's sampling of these means (3,072 pixels) and the display's white
   clamp, which makes the noises a little less than independent. */
static void test_converged_lrms_takes_out_the_noise(void)
{
    wt_options o = small_options(WT_MODE_RAYTRACE);
    wt_world *w = NULL;
    char err[512];
    const size_t n = 3 * (size_t)REF_W * REF_H;
    float *c1 = (float *)malloc(sizeof(float) * n), *c2 = (float *)malloc(sizeof(float) * n);
    float *c3 = (float *)malloc(sizeof(float) * n), e;
    double t, apart = -1.0, third = -1.0, first = -1.0, s;
    rendercache_camera c;
    if (!CHECK(c1 && c2 && c3) || !CHECK(wt_world_create(&o, &w, err, sizeof err) == 0)) goto done;
    t = wt_frame_time(&o, 7);
    c = wt_camera(&w->opt, t, REF_W, REF_H);
    if (!CHECK(wt__render_converged(w, &c, t, WT_CONVERGED_STRATA, WT_CONVERGED_LIGHT_SAMPLES, WT__CONVERGED_STREAM, c1) == 0 &&
               wt__render_converged(w, &c, t, WT_CONVERGED_STRATA, WT_CONVERGED_LIGHT_SAMPLES, WT__CONVERGED_STREAM - 1u, c2) == 0 &&
               wt__render_converged(w, &c, t, WT_CONVERGED_STRATA, WT_CONVERGED_LIGHT_SAMPLES, 0xABCDEu, c3) == 0))
        goto done;
    e = wt_exposure(&o, c1, 0.0f);
    if (!CHECK(wt_display_lrms(c1, c2, REF_W, REF_H, e, &apart) == 0 && apart > 0.0) ||
        !CHECK(wt_converged_lrms(w, &c, t, c3, e, &third) == 0) || !CHECK(wt_converged_lrms(w, &c, t, c1, e, &first) == 0))
        goto done;
    s = apart / sqrt(2.0);
    test_note("one converged render's noise %.4f; a third render reads %.4f, the first %.4f", s, third, first);
    CHECK(fabs(third - s) <= 0.15 * s);
    CHECK(first <= 0.15 * s);
done:
    wt_world_destroy(w);
    free(c1);
    free(c2);
    free(c3);
}

/* With the precompute cache on, wt_converged_lrms keeps its two converged
   renders there (one file per camera and time) and reads them back: a
   pair stored under the frame's key that are both the frame itself must
   make the frame read 0, which a render made again (one render's noise,
   about 0.035 here) would not; another time makes another file. */
static void test_converged_renders_cached(void)
{
    wt_options o = small_options(WT_MODE_RAYTRACE);
    wt_world *w = NULL;
    char dir[256], err[512];
    const size_t n = 3 * (size_t)REF_W * REF_H;
    float *frame = (float *)malloc(sizeof(float) * n), *pair = (float *)malloc(sizeof(float) * 2 * n), e;
    double t, first = -1.0, again = -1.0, stored = -1.0;
    rendercache_camera c;
    int made = 0;
    if (!CHECK(frame && pair && (made = make_temp_dir(dir, sizeof dir)) != 0)) goto done;
    o.cache_dir = dir;
    o.use_cache = 1;
    if (!CHECK(wt_world_create(&o, &w, err, sizeof err) == 0)) goto done;
    t = wt_frame_time(&o, 7);
    c = wt_camera(&w->opt, t, REF_W, REF_H);
    if (!CHECK(wt__render_converged(w, &c, t, 2, 1, 0xABCDEu, frame) == 0)) goto done;   /* a noisy frame */
    e = wt_exposure(&o, frame, 0.0f);
    CHECK(wt_converged_lrms(w, &c, t, frame, e, &first) == 0 && first > 0.0);
    CHECK_EQ_INT(count_files(dir, "^walkthrough-converged-.*bin$"), 1);
    CHECK(wt_converged_lrms(w, &c, t, frame, e, &again) == 0 && again == first);   /* read back: the same figure */
    memcpy(pair, frame, sizeof(float) * n);
    memcpy(pair + n, frame, sizeof(float) * n);
    CHECK(wt_cache_store(dir, "converged", wt__converged_key(w, &c, t), pair, sizeof(float) * 2 * n, err, sizeof err) == 0);
    CHECK(wt_converged_lrms(w, &c, t, frame, e, &stored) == 0);
    test_note("against converged renders %.4f, read back %.4f, against the frame stored as both %.4f", first, again, stored);
    CHECK(stored == 0.0);
    t = wt_frame_time(&o, 8);
    c = wt_camera(&w->opt, t, REF_W, REF_H);
    CHECK(wt_converged_lrms(w, &c, t, frame, e, &again) == 0);
    CHECK_EQ_INT(count_files(dir, "^walkthrough-converged-.*bin$"), 2);
    CHECK_EQ_INT(count_files(dir, "tmp[0-9]*$"), 0);
done:
    wt_world_destroy(w);
    if (made) remove_dir(dir);
    free(frame);
    free(pair);
}

/* A route's view space (ex_baseviews_desc.route, the house's walk) on a
   synthetic scene with known answers: the view at time t stands at
   (t, 0, 0), and its id image shows object 1 on a share
   clamp(4 t - 3, 0, 1) of its pixels, object 2
   elsewhere, so the fitness of the views at t and u is 1 - |share(t) -
   share(u)| and the images change only in the last quarter of the walk.
   Two stretches, q 0.9, 3 halvings: the first stretch and [0.5, 0.75]
   (halved once) keep their ends; [0.75, 1] is halved down to eighths of
   the stretch (the third halving is the last, whatever the fitness of
   its halves). A frame at t warps from the two views around t.
   Splitting everywhere (17 views) or nowhere (3) fails, and so does a
   frame located by its eye in a box (its eyes lie on a line). */
static void route_view_on_line(void *user, double t, rendercache_camera *c)
{
    (void)user;
    memset(c->eye, 0, sizeof c->eye);
    c->eye[0] = (float)t;
    c->look_at[0] = (float)t;
    c->look_at[1] = 0.0f;
    c->look_at[2] = 1.0f;
}

static int route_ids_on_line(void *user, const rendercache_camera *c, double time, uint32_t *ids)
{
    uint32_t i, n = c->width * c->height;
    float share = 4.0f * c->eye[0] - 3.0f;
    (void)user;
    (void)time;
    share = share < 0.0f ? 0.0f : share > 1.0f ? 1.0f : share;
    for (i = 0; i < n; i++) ids[i] = (float)i < share * (float)n ? 1u : 2u;
    return 0;
}

static void test_baseviews_route(void)
{
    static const double expect[] = { 0.0, 0.5, 0.75, 0.8125, 0.875, 0.9375, 1.0 };
    const double times[2] = { 0.0, 1.0 };
    const uint32_t n = (uint32_t)(sizeof expect / sizeof expect[0]);
    ex_baseviews_desc d;
    ex_baseviews bv;
    uint32_t views[8], count = 0, key = 9, i;
    memset(&d, 0, sizeof d);
    d.fisheye.kind = RENDERCACHE_CAMERA_FISHEYE;
    d.fisheye.look_at[2] = 1.0f;
    d.fisheye.up[1] = 1.0f;
    d.fisheye.width = d.fisheye.height = 16;
    d.route = route_view_on_line;
    d.stretches = 2;
    d.quality = 0.9f;
    d.times = times;
    d.time_count = 2;
    d.render_ids = route_ids_on_line;
    if (!CHECK(ex_baseviews_build(&d, &bv) == 0)) return;
    CHECK(bv.vs == NULL && bv.time_count == 2);
    if (CHECK_MSG(bv.view_count == n, "%u views", bv.view_count))
        for (i = 0; i < n; i++) {
            rendercache_camera c = ex_baseviews_base_camera(&bv, i, 32);
            CHECK_MSG(bv.view_times[i] == expect[i] && c.eye[0] == (float)expect[i] && c.width == 32 &&
                      c.kind == RENDERCACHE_CAMERA_FISHEYE, "view %u at %g", i, bv.view_times[i]);
        }
    CHECK(ex_baseviews_needs(&bv, bv.view_cameras[0].eye, 0.3, views, &count, &key) == 0 && count == 2 &&
          views[0] == 0 && views[1] == 1 && key == 0);
    CHECK(ex_baseviews_needs(&bv, bv.view_cameras[0].eye, 0.8, views, &count, &key) == 0 && count == 2 &&
          views[0] == 2 && views[1] == 3);
    CHECK(ex_baseviews_needs(&bv, bv.view_cameras[0].eye, 1.0, views, &count, &key) == 0 && count == 2 &&
          views[0] == n - 2 && views[1] == n - 1);
    ex_baseviews_free(&bv);
}

/* Shadow trails in the raytrace frames (issues 16 and 19): the render
   cache learns that the light changed only where a sample lands, so the
   floor the bunny shadowed kept its dark colour until its age came up and
   a dark trail followed the bunny. The raytrace mode now ages, after each
   step, the points whose light the step may change (wt__age_trail,
   rendercache_invalidate_where). The predicate: on the office's path, a
   point on the far side of the bunny from the lamp (its shadow) at its old
   place and one at its new place are both aged, and so is the floor under
   it; a point between the bunny and the lamp, beyond the contact reach,
   and one off to the side are not. Then the frames: after a step, the
   pixels of the next frame that show points the predicate flags are at
   the aged priority or above (but for 5% whose point lies off the pixel
   centre's hit); without the ageing 20 of 141 were below (1 with it). */
#define TRAIL_STEP_FRAME 12
#define TRAIL_AGED_PRIORITY 0.49   /* an aged point ranks at RENDERCACHE__PRIORITY_POINT_MAX, 0.5, or above */

static void trail_point(const float lamp[3], const float c[3], float s, float p[3])
{
    int k;
    for (k = 0; k < 3; k++) p[k] = c[k] + s * (c[k] - lamp[k]);   /* s > 0: beyond the bunny from the lamp */
}

static void test_raytrace_trail_ageing(void)
{
    wt_options o = small_options(WT_MODE_RAYTRACE);
    wt_world *w = NULL;
    wt_renderer *r = NULL;
    wt_frame_stats st;
    char err[512];
    float *rgb = (float *)malloc(sizeof(float) * 3 * REF_W * REF_H), c[2][3], p[3], q[3];
    wt__trail tr;
    int f, i;
    if (!CHECK(rgb) || !CHECK(wt_world_create(&o, &w, err, sizeof err) == 0 && wt_renderer_create(w, &r, err, sizeof err) == 0))
        goto done;
    if (!CHECK(w->light_count >= 1) || !CHECK(wt__trail_lamps(r) == 0)) goto done;
    CHECK(r->trail_lamp_count == 1);   /* the office's lamp: 6 lights, one sphere */
    for (i = 0; i < 2; i++) {
        wt_set_time(w, wt_frame_time(&o, TRAIL_STEP_FRAME - 8 + 8 * i));   /* a step long enough to tell them apart */
        ex__affine_point(w->pose, w->bunny_bound_centre, c[i]);
    }
    wt__trail_make(r, c[0], c[1], &tr);
    for (i = 0; i < 2; i++) {
        trail_point(w->lights[0].centre, c[i], 0.5f, p);   /* in the shadow at either place */
        CHECK(wt__trail_changed(&tr, p, WT_OBJECT_OFFICE));
        trail_point(w->lights[0].centre, c[i], -0.6f, p);   /* towards the lamp, out of reach */
        CHECK(!wt__trail_changed(&tr, p, WT_OBJECT_OFFICE));
        memcpy(q, c[i], sizeof q);
        q[1] -= 1.5f * w->bunny_bound_radius;   /* under it: the contact shadow */
        CHECK(wt__trail_changed(&tr, q, WT_OBJECT_OFFICE));
    }
    memcpy(p, c[1], sizeof p);
    p[0] += 2.0f;
    p[2] += 2.0f;   /* two metres off, level with it: nowhere near a cone of the lamp above */
    CHECK(!wt__trail_changed(&tr, p, WT_OBJECT_OFFICE));
    /* the same, only the new place: its old shadow is then missed */
    wt__trail_make(r, c[1], c[1], &tr);
    trail_point(w->lights[0].centre, c[0], 0.5f, p);
    CHECK(!wt__trail_changed(&tr, p, WT_OBJECT_OFFICE));
    for (f = 0; f <= TRAIL_STEP_FRAME; f++)
        if (!CHECK(wt_render_frame(r, f, rgb, &st) == 0)) goto done;
    {   /* the frame's last step ranks its trail high: in the next frame's priority image before its requests */
        double t = wt_frame_time(&o, TRAIL_STEP_FRAME + 1), sum[2] = { 0, 0 }, low[2] = { 0, 0 };
        rendercache_camera cam = wt_camera(&w->opt, t, REF_W, REF_H);
        const float *prio;
        uint32_t x, y;
        int count[2] = { 0, 0 };
        wt_set_time(w, t);
        CHECK(wt__age_trail(r, 0) == 0);
        CHECK(rendercache_set_object_transform(r->rc, WT_OBJECT_BUNNY, w->pose) == RENDERCACHE_OK &&
              rendercache_begin_frame(r->rc, &cam) == RENDERCACHE_OK);
        prio = rendercache_priority_image(r->rc);
        wt__trail_make(r, c[0], c[0], &tr);
        memcpy(tr.centre[0], r->trail_centre, sizeof tr.centre[0]);
        memcpy(tr.centre[1], r->trail_centre, sizeof tr.centre[1]);
        for (y = 0; y < REF_H; y++)
            for (x = 0; x < REF_W; x++) {
                float org[3], dir[3], through[3];
                ex_trace_hit h;
                int in;
                rendercache_camera_ray(&cam, (float)x + 0.5f, (float)y + 0.5f, org, dir);
                if (!ex_tracer_intersect_through(w->tracer, org, dir, FLT_MAX, &h, through) || h.instance != EX_TRACE_STATIC ||
                    rendercache_pixel_kinds(r->rc)[y * REF_W + x] != RENDERCACHE_PIXEL_POINT)
                    continue;
                in = wt__trail_changed(&tr, h.pos, WT_OBJECT_OFFICE);
                sum[in] += prio[y * REF_W + x];
                low[in] += prio[y * REF_W + x] < TRAIL_AGED_PRIORITY;
                count[in]++;
            }
        test_note("frame %d: the office pixels showing points in the bunny's shadow and reach (%d) at mean priority "
                  "%.3f, %.0f below %.2f; the others (%d) at %.3f, %.0f below", TRAIL_STEP_FRAME + 1, count[1],
                  count[1] ? sum[1] / count[1] : 0.0, low[1], TRAIL_AGED_PRIORITY, count[0], count[0] ? sum[0] / count[0] : 0.0, low[0]);
        CHECK(count[1] > 20 && count[0] > 200);
        CHECK(low[1] <= 0.05 * count[1]);   /* aged, but for the odd pixel whose point lies off the centre's hit */
    }
done:
    wt_renderer_destroy(r);
    wt_world_destroy(w);
    free(rgb);
}

/* The view lobe of a glossy point that shows no highlight (wt__view_lobe,
   wt__highlight_lobe): a wood-floor point 1.5 m beside a ceiling lamp's
   panel, shaded from 8 m away at a grazing angle (its mirror direction
   0.8 rad below the lamp), then seen from where the lamp's mirror image
   falls on it. The render cache ages it by the turn between the two eyes
   over its lobe (rendercache__view_age); at one lobe it ranks with the
   holes. By the glossy share it showed (0) alone it had no lobe and never
   aged for the view: a dark blotch in the house's frame 29. It must be
   stale there, and still fresh after a small turn (0.1 rad); the same
   point in the lamp's shadow, and a matte one, have no lobe. */
static void test_view_lobe_of_highlights(void)
{
    static const lightvec_material wood = { { 0.45f, 0.33f, 0.22f }, { 0.06f, 0.06f, 0.06f }, 40.0f, { 0, 0, 0 }, { 0, 0, 0 } };
    static const lightvec_material plaster = { { 0.72f, 0.71f, 0.68f }, { 0, 0, 0 }, 0.0f, { 0, 0, 0 }, { 0, 0, 0 } };
    const float far_eye[3] = { 9.5f, 1.6f, 0.0f }, omega_lamp = 0.25f * (2.5f / sqrtf(8.5f)) / 8.5f;
    float near_eye[3], to_far[3], to_near[3], lamp_dir[3], turn, lobe, len;
    wt_world w;
    wt_light lamp;
    wt_point p;
    int k;
    memset(&w, 0, sizeof w);
    memset(&lamp, 0, sizeof lamp);
    lamp.area = 0.25f;   /* a 0.5 m square panel 2.5 m up, facing down */
    lamp.normal[1] = -1.0f;
    lamp.point[1] = lamp.centre[1] = 2.5f;
    lamp.radius = 0.3536f;
    lamp.ke[0] = 20.0f;
    lamp.ke[1] = 19.0f;
    lamp.ke[2] = 17.0f;
    w.lights = &lamp;
    w.light_count = 1;   /* no grid: every light counts */
    memset(&p, 0, sizeof p);
    p.object = WT_OBJECT_OFFICE;
    p.pos[0] = 1.5f;
    p.normal[1] = 1.0f;
    for (k = 0; k < 3; k++) {
        p.org[k] = far_eye[k];
        p.dir[k] = p.pos[k] - far_eye[k];
        lamp_dir[k] = lamp.centre[k] - p.pos[k];
    }
    len = sqrtf(ex__dot(p.dir, p.dir));
    for (k = 0; k < 3; k++) {
        p.dir[k] /= len;
        /* its diffuse light from the lamp, Kd / pi L Omega cos_x, and some indirect light; no highlight */
        p.direct[k] = wood.diffuse[k] / WT_PI * lamp.ke[k] * omega_lamp * (2.5f / sqrtf(8.5f));
        p.indirect[k] = 0.3f * p.direct[k];
        p.through[k] = 1.0f;
    }
    p.contact = 1.0f;
    wt__point_radiance(&p);
    CHECK(p.view_share == 0.0f);
    /* the eye whose mirror direction points at the lamp: the lamp's direction mirrored in the floor */
    for (k = 0; k < 3; k++) near_eye[k] = p.pos[k] + (k == 1 ? 0.6f : -0.6f) * lamp_dir[k];
    for (k = 0; k < 3; k++) {
        to_far[k] = far_eye[k] - p.pos[k];
        to_near[k] = near_eye[k] - p.pos[k];
    }
    turn = acosf(ex__dot(to_far, to_near) / sqrtf(ex__dot(to_far, to_far) * ex__dot(to_near, to_near)));
    lobe = wt__view_lobe(&w, &p, &wood);
    test_note("a wood-floor point shaded at a grazing angle: lobe %.3f rad; the turn to the lamp's mirror image %.3f rad, "
              "%.2f lobes", lobe, turn, lobe > 0.0f ? turn / lobe : 0.0f);
    CHECK_MSG(lobe > 0.0f && isfinite(lobe), "lobe %g", lobe);
    CHECK_MSG(turn >= lobe, "turn %g, lobe %g: not stale under the highlight", turn, lobe);
    CHECK_MSG(0.1f <= 0.5f * lobe, "lobe %g: stale after a small turn", lobe);
    CHECK(wt__view_lobe(&w, &p, &plaster) == 0.0f);   /* matte: view-independent */
    for (k = 0; k < 3; k++) p.direct[k] = 0.0f;        /* in the lamp's shadow: no highlight can come */
    wt__point_radiance(&p);
    CHECK(wt__view_lobe(&w, &p, &wood) == 0.0f);
    p.object = RENDERCACHE_MISS;
    CHECK(wt__view_lobe(&w, &p, &wood) == 0.0f);      /* the sky is still */
}

/* Ghost shadows in the baseviews frames (issue 19): the floor the bunny
   shadowed at key time 0 must not stay dark once it has left. Pixels: the
   office pixels of frame GHOST_FRAME that a converged render of the
   frame's camera with the bunny at its t = 0 place shows darker than one
   with the bunny at the frame's place by more than GHOST_SHADOW (its old
   shadows, direct and contact). There, the baseviews frame's mean
   luminance against the converged render at the frame's time, over the
   same ratio on the rest of the office's pixels (the reconstruction's own
   bias cancels). A shadow baked into the key-time-0 base images and
   blended into this frame darkens these pixels by its blend weight times
   its depth (> GHOST_SHADOW). Frame 1 (t 0.04): the bunny has moved off
   its shadow of t = 0 while the key-time-0 images still weigh most in the
   blend. Measured: 0.79 with the shadows baked into the base images, 0.92
   with them traced at the frame's time (below 1: the bunny is still close
   by and the 20-odd pixels carry the converged renders' noise, a few
   percent); the bound 0.85 lies half-way. */
#define GHOST_FRAME 1
#define GHOST_SHADOW 0.7f
#define GHOST_MIN_RATIO 0.85

static void test_baseviews_no_ghost_shadows(void)
{
    wt_options o = small_options(WT_MODE_BASEVIEWS);
    wt_world *w = NULL;
    wt_renderer *r = NULL;
    wt_frame_stats st;
    char err[512];
    size_t n = (size_t)REF_W * REF_H, i;
    float *rgb = (float *)malloc(sizeof(float) * 3 * n), *ref = (float *)malloc(sizeof(float) * 3 * n);
    float *before = (float *)malloc(sizeof(float) * 3 * n);
    uint32_t *object = (uint32_t *)malloc(sizeof(uint32_t) * n);
    double t = 0.0, sum[2][2] = { { 0, 0 }, { 0, 0 } };
    int count[2] = { 0, 0 };
    if (!CHECK(rgb && ref && before && object) ||
        !CHECK(wt_world_create(&o, &w, err, sizeof err) == 0 && wt_renderer_create(w, &r, err, sizeof err) == 0))
        goto done;
    t = wt_frame_time(&o, GHOST_FRAME);
    if (!CHECK(wt_render_frame(r, GHOST_FRAME, rgb, &st) == 0)) goto done;
    memcpy(object, r->out->object, sizeof(uint32_t) * n);
    {
        rendercache_camera c = wt_camera(&w->opt, t, REF_W, REF_H);
        if (!CHECK(wt_render_converged(w, &c, 0.0, CONVERGED_STRATA, CONVERGED_LIGHT_SAMPLES, before) == 0 &&
                   wt_render_converged(w, &c, t, CONVERGED_STRATA, CONVERGED_LIGHT_SAMPLES, ref) == 0))
            goto done;
    }
    for (i = 0; i < n; i++) {
        int old_shadow = luminance(before + 3 * i) < GHOST_SHADOW * luminance(ref + 3 * i);
        if (object[i] != WT_OBJECT_OFFICE) continue;
        sum[old_shadow][0] += luminance(rgb + 3 * i);
        sum[old_shadow][1] += luminance(ref + 3 * i);
        count[old_shadow]++;
    }
    test_note("baseviews frame %d (t %.2f): where the bunny's shadow was at t = 0, %d pixels at %.3f of the converged "
              "luminance; the rest of the office (%d pixels) at %.3f (bound %.2f on their ratio)", GHOST_FRAME, t,
              count[1], sum[1][0] / sum[1][1], count[0], sum[0][0] / sum[0][1], GHOST_MIN_RATIO);
    CHECK(count[1] > 10 && count[0] > 200);   /* the old shadow is in view */
    CHECK((sum[1][0] / sum[1][1]) / (sum[0][0] / sum[0][1]) >= GHOST_MIN_RATIO);
done:
    wt_renderer_destroy(r);
    wt_world_destroy(w);
    free(rgb);
    free(ref);
    free(before);
    free(object);
}

/* Greger's figure 5.3: the rabbit darkens as it enters the desk's shadow.
   In the ray-traced frames: direct light and light vectors on its pixels. */
static void test_bunny_darkens_in_frames(void)
{
    wt_options o = small_options(WT_MODE_RAYTRACE);
    wt_world *w = NULL;
    char err[512];
    double open, under;
    int n_open, n_under;
    wt_renderer *r = NULL;
    if (!CHECK(wt_world_create(&o, &w, err, sizeof err) == 0 && wt_renderer_create(w, &r, err, sizeof err) == 0)) {
        wt_world_destroy(w);
        return;
    }
    open = bunny_pixels(w, 0.0, &n_open);
    under = bunny_pixels(w, time_under_desk(), &n_under);
    test_note("bunny pixels: mean luminance %.4f in the open (%d pixels), %.4f under the desk (%d): ratio %.2f", open,
              n_open, under, n_under, under / open);
    CHECK(n_open > 20 && n_under > 10);   /* seen in both */
    CHECK(under < 0.6 * open);            /* the desk takes the ceiling's and the lamp's light */
    wt_renderer_destroy(r);
    wt_world_destroy(w);
}

/* The same through the pipeline that lights the bunny in mode radiosity,
   with a volume of the lamp's emission alone (the direct
   component, lamp IMPORTANT), queried at the bunny's vertices with their
   self-occlusion ratios, and the bunny rasterized and Gouraud-shaded. */
static void test_bunny_darkens_in_volume(void)
{
    wt_options o = small_options(WT_MODE_RADIOSITY);
    wt_world *w = NULL;
    irrvol *vol = NULL;
    irrvol_desc src;
    irrvol_material *mats;
    char err[512];
    float *vis, *pos, *nrm, *rgb, m[12];
    double mean[2] = { 0, 0 };
    int reused, k;
    uint32_t i, v, nv;
    o.volume_resolution = 6;
    o.visibility_rays = 16;
    if (!CHECK(wt_world_create(&o, &w, err, sizeof err) == 0)) return;
    nv = w->bunny.vertex_count;
    mats = (irrvol_material *)calloc(w->office.material_count, sizeof *mats);
    vis = (float *)malloc(sizeof(float) * nv);
    pos = (float *)malloc(3 * sizeof(float) * nv);
    nrm = (float *)malloc(3 * sizeof(float) * nv);
    rgb = (float *)malloc(3 * sizeof(float) * nv);
    if (CHECK(mats && vis && pos && nrm && rgb)) {
        for (i = 0; i < w->office.material_count; i++) {
            memcpy(mats[i].radiance, w->office.materials[i].ke, sizeof mats[i].radiance);
            if (mats[i].radiance[0] > 0.0f) mats[i].flags = IRRVOL_MATERIAL_IMPORTANT;
        }
        memset(&src, 0, sizeof src);
        src.positions = w->office.positions;
        src.vertex_count = w->office.vertex_count;
        src.indices = w->office.tri_indices;
        src.triangle_count = w->office.tri_count;
        src.triangle_materials = w->office.tri_material;
        src.materials = mats;
        src.material_count = w->office.material_count;
        /* Greger's grid (7^3, second level 3^3): samples every 0.23 m in
           height near geometry, so some lie under the desk top */
        CHECK(wt_bunny_visibility(w, vis, &reused, err, sizeof err) == 0);
        for (v = 0, mean[0] = 0.0; v < nv; v++) mean[0] += vis[v] / nv;
        test_note("bunny self-occlusion: mean open fraction %.3f", mean[0]);
        CHECK(mean[0] > 0.5 && mean[0] < 0.98);   /* ears and legs shade the body, most of it is open */
        if (CHECK(wt_volume_build(w, &src, 1, &vol, &reused, err, sizeof err) == 0)) {
            double t[2];
            t[0] = 0.0;
            t[1] = time_under_desk();
            for (k = 0; k < 2; k++) {
                mean[k] = 0.0;
                wt_bunny_transform(w, t[k], m);
                wt_bunny_light(w, vol, vis, m, pos, nrm, rgb);
                for (v = 0; v < nv; v++) mean[k] += luminance(rgb + 3 * v) / nv;
            }
            test_note("bunny vertices lit by the lamp's volume: %.4f in the open, %.4f under the desk", mean[0], mean[1]);
            CHECK(mean[1] < 0.3 * mean[0]);   /* the desk top blocks the lamp */
            /* rasterized, Gouraud-shaded: the bunny's pixels darken too */
            {
                ex_raster ra;
                const int W = 96, H = 72;
                float *img = (float *)calloc(3 * W * H, sizeof(float));
                double pix[2] = { 0, 0 };
                int cnt[2] = { 0, 0 }, p;
                if (CHECK(img && ex_raster_init(&ra, W, H) == 0)) {
                    for (k = 0; k < 2; k++) {
                        rendercache_camera c = wt_camera(&o, t[k], W, H);
                        wt_bunny_transform(w, t[k], m);
                        wt_bunny_light(w, vol, vis, m, pos, nrm, rgb);
                        CHECK(wt_raster_scene(w, &ra, &c, w->office.positions, w->office.tri_indices,
                                              w->office.tri_count, w->office.vertex_count, pos) == 0);
                        ex_raster_resolve_gouraud(&ra, w->bunny.tri_indices, w->bunny.tri_count, w->office.tri_count,
                                                  rgb, img);
                        for (p = 0; p < W * H; p++)
                            if (ra.id[p] != EX_RASTER_EMPTY && ra.id[p] >= w->office.tri_count) {
                                pix[k] += luminance(img + 3 * p);
                                cnt[k]++;
                            }
                    }
                    CHECK(cnt[0] > 20 && cnt[1] > 10);
                    CHECK(cnt[0] && cnt[1] && pix[1] / cnt[1] < 0.3 * pix[0] / cnt[0]);
                    ex_raster_free(&ra);
                }
                free(img);
            }
            irrvol_destroy(vol);
        }
    }
    free(mats);
    free(vis);
    free(pos);
    free(nrm);
    free(rgb);
    wt_world_destroy(w);
}

/* The rasterizer's camera is the ray tracer's: the ID buffer of the office
   and the bunny agrees with primary rays pixel by pixel, but for pixels on
   edges. */
static void test_raster_matches_tracer(void)
{
    wt_options o = small_options(WT_MODE_RADIOSITY);
    wt_world *w = NULL;
    ex_raster ra;
    char err[512];
    const int W = 96, H = 72;
    float *pos;
    uint32_t v, agree = 0, bunny = 0;
    int x, y;
    double t = 0.3;
    if (!CHECK(wt_world_create(&o, &w, err, sizeof err) == 0)) return;
    pos = (float *)malloc(3 * sizeof(float) * w->bunny.vertex_count);
    if (CHECK(pos && ex_raster_init(&ra, W, H) == 0)) {
        rendercache_camera c = wt_camera(&o, t, W, H);
        wt_set_time(w, t);
        for (v = 0; v < w->bunny.vertex_count; v++) ex__affine_point(w->pose, w->bunny.positions + 3 * (size_t)v, pos + 3 * (size_t)v);
        CHECK(wt_raster_scene(w, &ra, &c, w->office.positions, w->office.tri_indices, w->office.tri_count,
                              w->office.vertex_count, pos) == 0);
        for (y = 0; y < H; y++)
            for (x = 0; x < W; x++) {
                float org[3], dir[3];
                ex_trace_hit h;
                uint32_t id = ra.id[y * W + x], expect;
                rendercache_camera_ray(&c, (float)x + 0.5f, (float)y + 0.5f, org, dir);
                if (!ex_tracer_intersect(w->tracer, org, dir, FLT_MAX, &h)) continue;
                expect = h.instance == EX_TRACE_STATIC ? w->office.tri_face[h.tri] : 0xFFFFu;
                if (id != EX_RASTER_EMPTY)
                    id = id < w->office.tri_count ? w->office.tri_face[id] : 0xFFFFu;
                agree += id == expect;
                bunny += expect == 0xFFFFu;
            }
        test_note("raster vs tracer: %u of %d pixels show the same polygon (%u bunny pixels)", agree, W * H, bunny);
        CHECK(bunny > 10);
        CHECK(agree >= (uint32_t)(0.97 * W * H));   /* polygon edges may fall either way by rounding */
        ex_raster_free(&ra);
    }
    free(pos);
    wt_world_destroy(w);
}

static void write_references(void)
{
    int m;
    for (m = 0; m < 2; m++) {
        CHECK(frames_vs_reference((wt_mode)m, 1, 1) == 0.0);
        printf("  wrote tests/data/walkthrough_%s_f0.pfm, _f1.pfm\n", wt_mode_name((wt_mode)m));
    }
}

int main(int argc, char **argv)
{
    TEST_INIT(argc, argv);
    if (getenv("WT_WRITE_REFERENCE")) {
        RUN(write_references);
        return test_finish();
    }
    RUN(test_options);
    RUN(test_missing_files);
    RUN(test_bunny_path);
    RUN(test_camera_path);
    RUN(test_route_frames);
    RUN(test_cache_files);
    RUN(test_precompute_reuse);
    RUN(test_reference_frames);
    RUN(test_direct_light_unbiased);
    RUN(test_light_solid_angle);
    RUN(test_threads);
    RUN(test_raytrace_against_converged);
    RUN(test_converged_lrms_takes_out_the_noise);
    RUN(test_converged_renders_cached);
    RUN(test_baseviews_route);
    RUN(test_raytrace_trail_ageing);
    RUN(test_view_lobe_of_highlights);
    RUN(test_baseviews_no_ghost_shadows);
    RUN(test_bunny_darkens_in_frames);
    RUN(test_bunny_darkens_in_volume);
    RUN(test_raster_matches_tracer);
    return test_finish();
}
