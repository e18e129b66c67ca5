/* What the walkthrough's test files share (tests/test_walkthrough*.c,
   tests/test_viewer.c): luminance, the stored reference frames' paths, the
   moment the bunny is deepest under the desk, the tests' common settings, the bunny's luminance in a
   full render, the moment it is deepest inside a building's lit or dark room, temporary cache
   directories and small files. Include after examples/common/walkthrough.h. */
#ifndef TESTS_WALKTHROUGH_TEST_H
#define TESTS_WALKTHROUGH_TEST_H

#include <stdio.h>
#include <stdlib.h>

/* The settings every walkthrough test starts from: the scene, mode and frame
   size it names, 2 threads (the frames are the same on any count), 4 shadow
   rays per point over all the lights, and no disk cache, progress or log. */
TEST__FN wt_options quiet_options(wt_mode mode, const char *scene, int width, int height, int frames)
{
    wt_options o;
    wt_options_default(&o);
    o.mode = mode;
    o.scene = scene;
    o.width = width;
    o.height = height;
    o.frames = frames;
    o.threads = 2;
    o.light_samples = 4;
    o.use_cache = 0;
    o.progress = 0;
    o.verbose = 0;
    return o;
}

/* Rec. 709 luminance of a linear RGB triple. */
TEST__FN float luminance(const float *c) { return 0.2126f * c[0] + 0.7152f * c[1] + 0.0722f * c[2]; }

/* tests/data/walkthrough_<mode>_f<frame>.pfm */
TEST__FN void reference_path(char *path, size_t size, wt_mode mode, int frame)
{
    snprintf(path, size, "tests/data/walkthrough_%s_f%d.pfm", wt_mode_name(mode), frame);
}

/* One sample of light L at org for direct light (wt__light_view_sample, the bunny casting),
   with the light's view made for this sample alone. */
TEST__FN void light_sample(const wt_world *w, const wt_light *L, const float org[3], const float n[3],
                           const float mirror[3], const lightvec_material *m, float u1, float u2, float scale,
                           float rgb[3], float gloss[3], int *bunny_shadow)
{
    wt__light_view v;
    wt__light_view_make(w, L, org, &v);
    wt__light_view_sample(w, &v, org, n, mirror, m, u1, u2, scale, 1, rgb, gloss, bunny_shadow);
}

/* The time at which the bunny is deepest under the office's desk (x 1.0-2.6, z 2.9-3.7). */
TEST__FN double time_under_desk(void)
{
    double best = 0.0;
    float depth = -1e9f, p[3];
    int i;
    for (i = 0; i <= 200; i++) {
        float d;
        wt_bunny_position(NULL, i / 200.0, p, NULL);
        d = fminf(fminf(p[0] - 1.0f, 2.6f - p[0]), fminf(p[2] - 2.9f, 3.7f - p[2]));
        if (d > depth) { depth = d; best = i / 200.0; }
    }
    return best;
}

/* Mean luminance of the bunny's pixels in a full render at time t (the
   raytrace mode's shading: direct light with shadow rays, light vectors),
   96 x 72 pixels; *count = how many pixels show the bunny. */
TEST__FN double bunny_pixels(wt_world *w, double t, int *count)
{
    const int W = 96, H = 72;
    rendercache_camera c = wt_camera(&w->opt, t, W, H);
    float *rgb = (float *)malloc(sizeof(float) * 3 * W * H);
    uint32_t *obj = (uint32_t *)malloc(sizeof(uint32_t) * W * H);
    double sum = 0.0;
    int i;
    *count = 0;
    if (rgb && obj && wt_render_full(w, &c, t, 0, rgb, obj) == 0)
        for (i = 0; i < W * H; i++)
            if (obj[i] == WT_OBJECT_BUNNY) {
                sum += luminance(rgb + 3 * i);
                ++*count;
            }
    free(rgb);
    free(obj);
    return *count ? sum / *count : 0.0;
}

/* The time when the bunny is deepest inside a room of the given kind (lit
   or dark); its depth (metres from the room's walls) into *depth. */
TEST__FN double deepest_in_room(const wt_world *w, int lit, float *depth)
{
    double best = -1.0;
    int i;
    *depth = -1.0f;
    for (i = 0; i <= 400; i++) {
        float p[3], d;
        int room;
        const wt_room *r;
        wt_bunny_position(&w->opt, i / 400.0, p, NULL);
        room = wt_layout_room_at(&w->layout, p);
        if (room < 0) continue;
        r = &w->layout.rooms[room];
        if (r->lamp != lit) continue;
        d = fminf(fminf(p[0] - r->lo[0], r->hi[0] - p[0]), fminf(p[2] - r->lo[2], r->hi[2] - p[2]));
        if (d > *depth) {
            *depth = d;
            best = i / 400.0;
        }
    }
    return best;
}

/* Writes text to a new file at path; 0 when it cannot. */
TEST__FN int write_file(const char *path, const char *text)
{
    FILE *f = fopen(path, "w");
    if (!f) return 0;
    fputs(text, f);
    return fclose(f) == 0;
}

/* A new empty directory under /tmp, its path into dir; 0 when none could be made. */
TEST__FN int make_temp_dir(char *dir, size_t size)
{
    snprintf(dir, size, "/tmp/walkthrough-test-XXXXXX");
    return mkdtemp(dir) != NULL;
}

TEST__FN void remove_dir(const char *dir)
{
    char cmd[1200];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
    if (system(cmd) != 0) fprintf(stderr, "  could not remove %s\n", dir);
}

/* How many names in dir match the grep pattern; -1 when that cannot be told. */
TEST__FN int count_files(const char *dir, const char *pattern)
{
    char cmd[1200];
    FILE *p;
    int n = -1;
    snprintf(cmd, sizeof cmd, "ls -1 '%s' | grep -c -- '%s'", dir, pattern);
    p = popen(cmd, "r");
    if (p) {
        if (fscanf(p, "%d", &n) != 1) n = -1;
        pclose(p);
    }
    return n;
}

/* The many-light sampler (wt__direct: n shadow rays per point, lights chosen
   by importance, divided by the choice's probability) is unbiased: at the
   primary hits of a cols x rows image of the path's camera at time t, its
   mean over `streams` random streams agrees with the sum over every light
   of `per_light` stratified samples each (the estimator that samples every
   light: light_sample with probability 1, no importance involved),
   summed over the hits, within 4 standard errors of the difference (both
   estimates' spreads measured from their own repeats: 4 sigma leaves a
   false alarm 1 time in 16000, and a missing 1 / p or a light never chosen
   moves the sum by far more). Returns the relative difference (-1 on
   failure) and, in noise[], the relative RMS noise of one estimate over the
   hits (sqrt(sum of variances / sum of squared means), the LRMS a frame of
   such estimates has against the converged one) of the sampler at n rays
   and of the every-light estimator at per_light rays per light (*rays: the
   lights it traces per hit times per_light), for the notes. */
#define DIRECT_REPEATS 4   /* repeats of the every-light sum: its spread */
TEST__FN double direct_light_bias(wt_world *w, double t, int cols, int rows, int streams, int per_light, double *sigmas,
                                  double noise[2], double *rays)
{
    rendercache_camera c = wt_camera(&w->opt, t, (uint32_t)cols, (uint32_t)rows);
    double sum = 0.0, var = 0.0, all = 0.0, all_var = 0.0, var_new = 0.0, var_old = 0.0, squares = 0.0;
    int x, y, i, k, hits = 0;
    wt_set_time(w, t);
    *rays = 0.0;
    for (y = 0; y < rows; y++)
        for (x = 0; x < cols; x++) {
            float org[3], dir[3], mirror[3], o[3], vn;
            double m1 = 0.0, m2 = 0.0, a1 = 0.0, a2 = 0.0, one_old = 0.0;
            ex_trace_hit h;
            const lightvec_material *mat;
            if (rendercache_camera_ray(&c, (float)x + 0.5f, (float)y + 0.5f, org, dir) != RENDERCACHE_OK ||
                !ex_tracer_intersect(w->tracer, org, dir, FLT_MAX, &h) || !h.front)
                continue;
            mat = &w->materials[h.instance == EX_TRACE_STATIC ? w->office.tri_material[h.tri] : w->bunny_material];
            for (i = 0; i < streams; i++) {
                ex_rng r = ex_rng_stream(w->opt.seed + 1000u, (uint64_t)(y * cols + x) * 4096u + (uint64_t)i);
                float rgb[3], gloss[3];
                int shadow = 0;
                double l;
                wt__direct(w, &h, dir, mat, &r, 1, WT__LEARN_USE, rgb, gloss, &shadow);
                l = luminance(rgb);
                m1 += l;
                m2 += l * l;
            }
            vn = -(dir[0] * h.normal[0] + dir[1] * h.normal[1] + dir[2] * h.normal[2]);
            for (k = 0; k < 3; k++) {
                o[k] = h.pos[k] + w->tracer->epsilon * h.normal[k];
                mirror[k] = dir[k] + 2.0f * vn * h.normal[k];
            }
            for (i = 0; i < DIRECT_REPEATS; i++) {
                ex_rng r = ex_rng_stream(w->opt.seed + 2000u, (uint64_t)(y * cols + x) * 4096u + (uint64_t)i);
                float rgb[3] = { 0, 0, 0 }, one[3] = { 0, 0, 0 }, gloss[3] = { 0, 0, 0 };
                uint32_t e;
                int s, shadow = 0;
                for (e = 0; e < w->light_count; e++)
                    for (s = 0; s < per_light; s++)
                        light_sample(w, &w->lights[e], o, h.normal, mirror, mat,
                                         ((float)s + ex_rng_float(&r)) / (float)per_light, ex_rng_float(&r),
                                         1.0f / (float)per_light, rgb, gloss, &shadow);
                a1 += luminance(rgb);
                a2 += (double)luminance(rgb) * luminance(rgb);
                for (e = 0; e < w->light_count; e++) {   /* one sample per light: the old default's spread */
                    light_sample(w, &w->lights[e], o, h.normal, mirror, mat, ex_rng_float(&r), ex_rng_float(&r),
                                     1.0f, one, gloss, &shadow);
                    if (i == 0) *rays += wt__light_importance(&w->lights[e], o, h.normal) > 0.0f;
                }
                one_old += (double)luminance(one) * luminance(one);
            }
            m1 /= streams;
            m2 = m2 / streams - m1 * m1;
            a1 /= DIRECT_REPEATS;
            a2 = a2 / DIRECT_REPEATS - a1 * a1;
            sum += m1;
            var += (m2 > 0.0 ? m2 : 0.0) / (streams - 1);
            all += a1;
            all_var += (a2 > 0.0 ? a2 : 0.0) / (DIRECT_REPEATS - 1);
            {   /* the every-light variance at per_light rays per light, from one-sample draws */
                double v1 = one_old / DIRECT_REPEATS - a1 * a1;
                var_new += m2 > 0.0 ? m2 : 0.0;
                var_old += v1 > 0.0 ? v1 / per_light : 0.0;
                squares += a1 * a1;
            }
            hits++;
        }
    if (!hits || !(all > 0.0)) return -1.0;
    *rays = *rays * per_light / hits;
    *sigmas = fabs(sum - all) / sqrt(var + all_var + 1e-300);
    noise[0] = sqrt(var_new / squares);
    noise[1] = sqrt(var_old / squares);
    return fabs(sum - all) / all;
}

#endif
