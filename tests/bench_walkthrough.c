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

   Mode raytrace reports the displayed rate (frames after the first, which is
   traced in full) and the sampled rate (samples per second at the 8% budget);
   mode baseviews the rate of reconstructed frames. Mode radiosity needs
   radinterp.h's online phase; until it exists, the parts of its frame that
   do not need radinterp are timed: rasterizing the office and the bunny
   into the ID + barycentric buffers, and the bunny's volume queries
   (1839 vertices) with Gouraud shading, on a volume of the lamp's emission.

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

/* The parts of a radiosity-mode frame that exist without radinterp.h's
   online phase: raster (office + bunny) and the bunny's volume queries. */
static void radiosity_parts(int threads)
{
    wt_options o = bench_options(WT_MODE_RADIOSITY, threads);
    wt_world *w = NULL;
    irrvol *vol = NULL;
    irrvol_desc src;
    irrvol_material *mats;
    ex_raster ra;
    char err[512];
    float *vis, *pos, *nrm, *vrgb, *img, m[12];
    double raster[FRAMES], query[FRAMES], shade[FRAMES];
    uint32_t i, nv;
    int f, reused;
    double (*now)(void) = threads == 1 ? cpu_seconds : wt_seconds;
    if (wt_world_create(&o, &w, err, sizeof err) != 0) { printf("  %s\n", err); return; }
    nv = w->bunny.vertex_count;
    mats = (irrvol_material *)calloc(w->office.material_count, sizeof *mats);
    vis = (float *)malloc(sizeof(float) * nv);
    pos = (float *)malloc(3 * sizeof(float) * nv);
    nrm = (float *)malloc(3 * sizeof(float) * nv);
    vrgb = (float *)malloc(3 * sizeof(float) * nv);
    img = (float *)malloc(3 * sizeof(float) * (size_t)o.width * (size_t)o.height);
    if (!mats || !vis || !pos || !nrm || !vrgb || !img || ex_raster_init(&ra, o.width, o.height) != 0) {
        printf("  out of memory\n");
        return;
    }
    ra.pool = w->pool;
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
    if (wt_bunny_visibility(w, vis, &reused, err, sizeof err) != 0 ||
        wt_volume_build(w, &src, wt_hash_str(w->scene_hash, "lamp emission"), &vol, &reused, err, sizeof err) != 0) {
        printf("  %s\n", err);
        return;
    }
    for (f = 0; f < FRAMES; f++) {
        double t = wt_frame_time(&o, f), t0;
        rendercache_camera c = wt_camera(&o, t, (uint32_t)o.width, (uint32_t)o.height);
        wt_bunny_transform(w, t, m);
        t0 = now();
        wt_bunny_light(w, vol, vis, m, pos, nrm, vrgb);
        query[f] = 1e3 * (now() - t0);
        t0 = now();
        wt_raster_scene(w, &ra, &c, w->office.positions, w->office.tri_indices, w->office.tri_count, pos);
        raster[f] = 1e3 * (now() - t0);
        t0 = now();
        ex_raster_resolve_gouraud(&ra, w->bunny.tri_indices, w->bunny.tri_count, w->office.tri_count, vrgb, img);
        shade[f] = 1e3 * (now() - t0);
    }
    printf("  radiosity  %d thread%s: needs radinterp.h's online phase; without it, per frame: raster (office %u + "
           "bunny %u triangles) %.2f ms, bunny volume queries (%u vertices) %.3f ms, bunny Gouraud %.2f ms\n",
           threads, threads > 1 ? "s" : " ", w->office.tri_count, w->bunny.tri_count, median(raster, FRAMES), nv,
           median(query, FRAMES), median(shade, FRAMES));
    irrvol_destroy(vol);
    ex_raster_free(&ra);
    free(mats); free(vis); free(pos); free(nrm); free(vrgb); free(img);
    wt_world_destroy(w);
}

int main(void)
{
    int threads, m, k;
    printf("walkthrough at 640x480, %d frames along the path (medians per frame)\n", FRAMES);
    printf("  paper: Greger 1996 fig. 5.8: 5.3 frames/s (1162-polygon rabbit, 601 queries/frame, 1996 hardware);\n"
           "         Hardt 1996: 2.3 updates/s at 640x480; target for mode radiosity: 60 frames/s on 2 cores\n");
    for (m = 0; m < 2; m++)
        for (threads = 1; threads <= 2; threads++) {
            double med = 0.0, first = 0.0, phase[WT_PHASES];
            uint32_t samples = 0;
            if (!run_mode((wt_mode)m, threads, &med, &first, &samples, phase)) continue;
            printf("  %-9s  %d thread%s: %6.1f ms/frame = %5.1f frames/s", wt_mode_name((wt_mode)m), threads,
                   threads > 1 ? "s" : " ", med, 1e3 / med);
            printf(" (%s)", threads > 1 ? "wall" : "CPU");
            if (m == WT_MODE_RAYTRACE)
                printf(" displayed, %6.0f samples/s sampled (%u per frame; the first frame, all pixels: %.0f ms)",
                       samples / (med * 1e-3), samples, first);
            printf("\n             phases:");
            for (k = 0; k < WT_PHASES && wt_phase_name((wt_mode)m, k); k++)
                printf(" %s %.1f ms", wt_phase_name((wt_mode)m, k), phase[k]);
            printf("\n");
        }
    for (threads = 1; threads <= 2; threads++) radiosity_parts(threads);
    return 0;
}
