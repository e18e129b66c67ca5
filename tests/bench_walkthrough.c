/* Benchmark of the walkthrough (examples/common/walkthrough.h): frames per
   second at 640x480 along the 48-frame path, per mode, on 1 and 2 threads,
   with the published figures beside them:

     Greger 1996, figure 5.8: 5.3 frames/s with a 1162-polygon rabbit (601
       volume queries per frame) in a 43946-polygon radiosity office, on a
       1996 graphics workstation;
     Hardt 1996, section 7: 2.3 updates/s at 640x480 for per-pixel
       quadratic radiosity interpolants;
     the project's target for mode radiosity: 60 frames/s at 640x480 on this
       2-core machine.

   Mode radiosity (the default) reports its phases as in Greger's figure:
   raster (the office's interpolant mesh and the bunny into the ID +
   barycentric buffers), shade (radinterp_shade per pixel, the occlusion
   blob, the bunny's Gouraud blend), volume (the bunny's 1839 vertex queries
   of the irradiance volume) and other. Mode raytrace reports the displayed
   rate (frames after the first, which is traced in full) and the sampled
   rate (samples per second at the 8% budget); mode baseviews the rate of
   reconstructed frames.

   Precomputed data comes from (or goes to) build/cache, as in the example.
   Medians over the frames. The machine is shared: on 1 thread the frame
   time is the calling thread's CPU time (all the work runs on it, and
   moments another process held the core do not count); on 2 threads it is
   wall time, and noisy. Phases are wall time. */
#define _POSIX_C_SOURCE 200809L
#include "examples/common/walkthrough.h"

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

static wt_options bench_options(wt_mode mode, int threads)
{
    wt_options o;
    wt_options_default(&o);
    o.mode = mode;
    o.frames = FRAMES;
    o.threads = threads;
    o.progress = 0;
    o.verbose = 0;
    return o;
}

/* Renders the path; *median_ms over the frames from `first` on. */
static int run_mode(wt_mode mode, int threads, double *median_ms, double *first_ms, uint32_t *samples,
                    double *median_phase)
{
    wt_options o = bench_options(mode, threads);
    wt_world *w = NULL;
    wt_renderer *r = NULL;
    wt_frame_stats st;
    char err[512];
    double ms[FRAMES], phase[WT_PHASES][FRAMES];
    float *rgb = (float *)malloc(sizeof(float) * 3 * (size_t)o.width * (size_t)o.height);
    int f, k, first = mode == WT_MODE_RAYTRACE ? 1 : 0;
    if (!rgb || wt_world_create(&o, &w, err, sizeof err) != 0 || wt_renderer_create(w, &r, err, sizeof err) != 0) {
        printf("  %s: %s\n", wt_mode_name(mode), rgb ? err : "out of memory");
        wt_world_destroy(w);
        free(rgb);
        return 0;
    }
    for (f = 0; f < FRAMES; f++) {
        double c0 = cpu_seconds(), total;
        if (wt_render_frame(r, f, rgb, &st) != 0) break;
        total = threads == 1 ? cpu_seconds() - c0 : st.total;
        if (f == 0) *first_ms = 1e3 * total;
        if (f >= first) {
            ms[f - first] = 1e3 * total;
            for (k = 0; k < WT_PHASES; k++) phase[k][f - first] = 1e3 * st.phase[k];
        }
        *samples = st.samples;
    }
    *median_ms = median(ms, FRAMES - first);
    for (k = 0; k < WT_PHASES; k++) median_phase[k] = median(phase[k], FRAMES - first);
    wt_renderer_destroy(r);
    wt_world_destroy(w);
    free(rgb);
    return f == FRAMES;
}

int main(void)
{
    static const wt_mode modes[3] = { WT_MODE_RADIOSITY, WT_MODE_RAYTRACE, WT_MODE_BASEVIEWS };
    int threads, m, k;
    printf("walkthrough at 640x480, %d frames along the path (medians per frame)\n", FRAMES);
    printf("  paper: Greger 1996 fig. 5.8: 5.3 frames/s (1162-polygon rabbit, 601 queries/frame, 1996 hardware);\n"
           "         Hardt 1996: 2.3 updates/s at 640x480; target for mode radiosity: 60 frames/s on 2 cores\n");
    for (m = 0; m < 3; m++)
        for (threads = 1; threads <= 2; threads++) {
            double med = 0.0, first = 0.0, phase[WT_PHASES];
            uint32_t samples = 0;
            if (!run_mode(modes[m], threads, &med, &first, &samples, phase)) continue;
            printf("  %-9s  %d thread%s: %6.1f ms/frame = %5.1f frames/s", wt_mode_name(modes[m]), threads,
                   threads > 1 ? "s" : " ", med, 1e3 / med);
            printf(" (%s)", threads > 1 ? "wall" : "CPU");
            if (modes[m] == WT_MODE_RAYTRACE)
                printf(" displayed, %6.0f samples/s sampled (%u per frame; the first frame, all pixels: %.0f ms)",
                       samples / (med * 1e-3), samples, first);
            if (modes[m] == WT_MODE_RADIOSITY) printf(", %u volume queries per frame", samples);
            printf("\n             phases:");
            for (k = 0; k < WT_PHASES && wt_phase_name(modes[m], k); k++)
                printf(" %s %.2f ms", wt_phase_name(modes[m], k), phase[k]);
            printf("\n");
        }
    return 0;
}
