/* Benchmark of the walkthrough (examples/common/walkthrough.h) in the
   office (the scene whose figures the README has followed across
   versions; WT_BENCH_SCENE=house, building or an OBJ path benches
   another): frames per second along the 48-frame path, mode radiosity at
   640x480, 1280x720 and 1920x1080, modes raytrace and baseviews at
   640x480, each on 1 and 2 threads; then the house (what `make demo`
   shows: wt_options_default's scene): the first run's precompute of mode
   radiosity on 2 threads from an empty cache (wall time: the radiosity
   solve and interpolant mesh, the irradiance volume, the bunny's
   self-occlusion; target under 60 s), and its frames at 640x480 on 1 and 2
   threads; with the published figures beside them:

     Greger 1996, figure 5.8: 5.3 frames/s with a 1162-polygon rabbit (601
       volume queries per frame) in a 43946-polygon radiosity office, on a
       1996 graphics workstation;
     Hardt 1996, section 7: 2.3 updates/s at 640x480 for per-pixel
       quadratic radiosity interpolants;
     the project's target for mode radiosity: 60 frames/s at 1920x1080 on
       this 2-core machine (issue 18).

   Honest figures on a shared machine: a 1-thread line runs with no thread
   pool at all (every job runs on the calling thread) and reports that
   thread's CPU time (CLOCK_THREAD_CPUTIME_ID: moments another process held
   the core do not count); a 2-thread line reports wall time and says so
   (it counts whatever else the machine ran). Medians over the frames. Each
   line ends with the machine's load average (1, 5, 15 minutes) when it was
   measured: a 2-thread figure taken at a load over 2 shares its cores.

   Mode radiosity reports its phases as in Greger's figure, as CPU time
   summed over the threads that ran them: raster (the interpolant mesh and
   the bunny into the ID + barycentric buffers: setup, binning, depth tests,
   barycentrics), shade (radinterp_shade_span per run of pixels of one
   triangle, the occlusion blob, the bunny's Gouraud blend, fused with the
   raster tile by tile), volume (the bunny's vertex queries of the
   irradiance volume) and other (wall time outside those). Mode raytrace
   reports the displayed rate (frames after the first, which is traced in
   full) and the sampled rate; mode baseviews the rate of reconstructed frames; their phases are wall time. Precomputed data comes from
   (or goes to) build/cache, as in the example. Arguments select lines: a
   mode, a size and a thread count, e.g. `radiosity 1920x1080 1t`. */
#define _POSIX_C_SOURCE 200809L
#include "examples/common/walkthrough.h"
#include "tests/test.h"
#include "tests/walkthrough_test.h"   /* make_temp_dir, remove_dir */

#define FRAMES 48

static double cpu_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static int compare_doubles(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

static double median(double *v, int n)
{
    qsort(v, (size_t)n, sizeof *v, compare_doubles);
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

/* "load 1.23 0.98 0.77" from /proc/loadavg, or "load ?". */
static const char *load_average(void)
{
    static char text[64];
    double a = 0, b = 0, c = 0;
    FILE *f = fopen("/proc/loadavg", "r");
    if (f && fscanf(f, "%lf %lf %lf", &a, &b, &c) == 3) snprintf(text, sizeof text, "load %.2f %.2f %.2f", a, b, c);
    else snprintf(text, sizeof text, "load ?");
    if (f) fclose(f);
    return text;
}

static const char *bench_scene = "office";   /* unless WT_BENCH_SCENE names one */

static wt_options bench_options(wt_mode mode, int threads, int width, int height)
{
    wt_options o;
    const char *scene = getenv("WT_BENCH_SCENE");
    wt_options_default(&o);
    o.scene = scene && scene[0] ? scene : bench_scene;
    o.mode = mode;
    o.frames = FRAMES;
    o.threads = threads;
    o.width = width;
    o.height = height;
    o.progress = 0;
    o.verbose = 0;
    return o;
}

typedef struct result { double ms, first_ms, phase[WT_PHASES]; uint32_t samples; } result;

/* Renders the path; medians over the frames from `first` on. */
static int run_mode(wt_mode mode, int threads, int width, int height, result *res)
{
    wt_options o = bench_options(mode, threads, width, height);
    wt_world *w = NULL;
    wt_renderer *r = NULL;
    wt_frame_stats st;
    char err[512];
    double ms[FRAMES], phase[WT_PHASES][FRAMES];
    float *rgb = (float *)malloc(sizeof(float) * 3 * (size_t)o.width * (size_t)o.height);
    int f, k, first = mode == WT_MODE_RAYTRACE ? 1 : 0;
    if (!rgb || wt_world_create(&o, &w, err, sizeof err) != 0 || wt_renderer_create(w, &r, err, sizeof err) != 0) {
        printf("  %-9s %4dx%-4d %d thread%s: not run: %s\n", wt_mode_name(mode), width, height, threads,
               threads > 1 ? "s" : " ", rgb ? err : "out of memory");
        wt_world_destroy(w);
        free(rgb);
        return 0;
    }
    for (f = 0; f < FRAMES; f++) {
        double c0 = cpu_seconds(), total;
        if (wt_render_frame(r, f, rgb, &st) != 0) break;
        total = threads == 1 ? cpu_seconds() - c0 : st.total;
        if (f == 0) res->first_ms = 1e3 * total;
        if (f >= first) {
            ms[f - first] = 1e3 * total;
            for (k = 0; k < WT_PHASES; k++) phase[k][f - first] = 1e3 * st.phase[k];
        }
        res->samples = st.samples;
    }
    res->ms = median(ms, FRAMES - first);
    for (k = 0; k < WT_PHASES; k++) res->phase[k] = median(phase[k], FRAMES - first);
    wt_renderer_destroy(r);
    wt_world_destroy(w);
    free(rgb);
    return f == FRAMES;
}

static void report(wt_mode mode, int threads, int width, int height)
{
    result res;
    int k;
    memset(&res, 0, sizeof res);
    if (!run_mode(mode, threads, width, height, &res)) return;
    printf("  %-9s %4dx%-4d %d thread%s: %6.1f ms/frame = %5.1f frames/s (%s)", wt_mode_name(mode), width, height,
           threads, threads > 1 ? "s" : " ", res.ms, 1e3 / res.ms, threads > 1 ? "wall" : "thread CPU, no pool");
    if (mode == WT_MODE_RADIOSITY && width == 1920 && height == 1080)
        printf(" {target: 60 frames/s = 16.7 ms wall on 2 threads%s}",
               threads == 1 ? "" : res.ms <= 1e3 / 60.0 ? ": met" : ": not met");
    if (mode == WT_MODE_RAYTRACE)
        printf(" displayed, %.0f samples/s (%u per frame; first frame, all pixels: %.0f ms)", res.samples / (res.ms * 1e-3),
               res.samples, res.first_ms);
    printf("  [%s]\n             phases (%s):", load_average(), mode == WT_MODE_RADIOSITY ? "CPU, all threads" : "wall");
    for (k = 0; k < WT_PHASES && wt_phase_name(mode, k); k++) printf(" %s %.2f ms", wt_phase_name(mode, k), res.phase[k]);
    if (mode == WT_MODE_RADIOSITY) printf("; %u volume queries per frame", res.samples);
    printf("\n");
    fflush(stdout);
}

/* The first run's precompute of mode radiosity in the demo's scene on 2
   threads, from an empty temporary cache (wall time). */
static void report_precompute(void)
{
    wt_options o = bench_options(WT_MODE_RADIOSITY, 2, 640, 480);
    wt_world *w = NULL;
    wt_renderer *r = NULL;
    char err[512], dir[256];
    double t0 = wt_seconds(), total;
    if (!make_temp_dir(dir, sizeof dir)) {
        printf("  precompute: not run: no temporary directory\n");
        return;
    }
    o.cache_dir = dir;
    if (wt_world_create(&o, &w, err, sizeof err) != 0 || wt_renderer_create(w, &r, err, sizeof err) != 0) {
        printf("  precompute: not run: %s\n", err);
    } else {
        radinterp_mesh_info mi;
        total = wt_seconds() - t0;
        radinterp_mesh_get_info(r->statics.mesh, &mi);
        printf("  precompute of mode radiosity, 2 threads, first run: %.1f s wall (solve %.1f s, mesh %.1f s: %u triangles, "
               "%llu IrradianceAtPoint samples; the volume, the bunny's self-occlusion and loading the rest) "
               "{target: under 60 s%s}  [%s]\n", total, r->statics.seconds_solve, r->statics.seconds_mesh, mi.triangle_count,
               (unsigned long long)mi.samples, total < 60.0 ? ": met" : ": not met", load_average());
    }
    wt_renderer_destroy(r);
    wt_world_destroy(w);
    remove_dir(dir);
    fflush(stdout);
}

/* Whether the command line selects this line: no arguments select every
   line; else a mode name, a size WxH or a thread count "1t" / "2t" given
   restricts the lines to those (e.g. `bench_walkthrough radiosity 1920x1080 1t`); "precompute" selects the
   house's precompute alone. */
static int selected(int argc, char **argv, wt_mode mode, int threads, int width, int height)
{
    int i, want_mode = 0, want_size = 0, want_threads = 0, mode_ok = 0, size_ok = 0, threads_ok = 0;
    for (i = 1; i < argc; i++) {
        int w = 0, h = 0, t = 0;
        char c = 0;
        if (sscanf(argv[i], "%dx%d%c", &w, &h, &c) == 2) {
            want_size = 1;
            size_ok |= w == width && h == height;
        } else if (sscanf(argv[i], "%dt%c", &t, &c) == 1) {
            want_threads = 1;
            threads_ok |= t == threads;
        } else {
            want_mode = 1;
            mode_ok |= !strcmp(argv[i], wt_mode_name(mode));
        }
    }
    return (!want_mode || mode_ok) && (!want_size || size_ok) && (!want_threads || threads_ok);
}

int main(int argc, char **argv)
{
    static const int sizes[3][2] = { { 640, 480 }, { 1280, 720 }, { 1920, 1080 } };
    const char *scene = getenv("WT_BENCH_SCENE");
    int threads, s, m;
    printf("walkthrough in %s, %d frames along the path (medians per frame)\n",
           scene && scene[0] ? scene : "the office", FRAMES);
    printf("  paper: Greger 1996 fig. 5.8: 5.3 frames/s (1162-polygon rabbit, 601 queries/frame, 1996 hardware);\n"
           "         Hardt 1996: 2.3 updates/s at 640x480; target for mode radiosity: 60 frames/s at 1920x1080 on 2 cores\n");
    for (s = 0; s < 3; s++)
        for (threads = 1; threads <= 2; threads++)
            if (selected(argc, argv, WT_MODE_RADIOSITY, threads, sizes[s][0], sizes[s][1]))
                report(WT_MODE_RADIOSITY, threads, sizes[s][0], sizes[s][1]);
    for (m = 0; m < 2; m++)
        for (threads = 1; threads <= 2; threads++) {
            wt_mode mode = m ? WT_MODE_BASEVIEWS : WT_MODE_RAYTRACE;
            if (selected(argc, argv, mode, threads, 640, 480)) report(mode, threads, 640, 480);
        }
    if (scene && scene[0]) return 0;
    {
        wt_options d;
        wt_options_default(&d);
        bench_scene = d.scene;
    }
    printf("walkthrough in %s (what make demo shows), %d frames along the path (medians per frame)\n", bench_scene, FRAMES);
    for (m = 1; m < argc && strcmp(argv[m], "precompute"); m++) {}
    if (argc < 2 || m < argc) report_precompute();
    for (threads = 1; threads <= 2; threads++)
        if (selected(argc, argv, WT_MODE_RADIOSITY, threads, 640, 480)) report(WT_MODE_RADIOSITY, threads, 640, 480);
    return 0;
}
